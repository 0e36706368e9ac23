// The skin's strain per morph target, by the rules of emogen/render/wrinkles.py: per triangle
// the linear strain sym(Fᵀ Fd) / s² of the target's displacement in the UV chart, averaged over
// a vertex's triangles by rest area. Linear in the displacement, so the vertex shader blends the
// targets' strains with the face's morph weights (material.js) and gets the strain of the face
// itself, as the offscreen renderer computes it. Output: a float RGBA texture, texel
// target · nVertices + vertex at (index mod STRAIN_WIDTH, index div STRAIN_WIDTH).
import { DataTexture, FloatType, NearestFilter, RGBAFormat } from 'three';

export const STRAIN_WIDTH = 4096;

// (count · 3) float values of a vec3 attribute (plain, normalised integer or interleaved).
function floats(attr) {
  const a = attr.array;
  if (!attr.isInterleavedBufferAttribute && attr.itemSize === 3 && a.length === attr.count * 3) {
    if (!attr.normalized) return a;
    const scale = a instanceof Int16Array ? 32767 : a instanceof Int8Array ? 127 : 0;
    if (scale) {
      const out = new Float32Array(a.length);
      for (let i = 0; i < a.length; i++) out[i] = Math.max(a[i] / scale, -1);
      return out;
    }
  }
  const out = new Float32Array(attr.count * 3);
  for (let i = 0; i < attr.count; i++) {
    out[3 * i] = attr.getX(i);
    out[3 * i + 1] = attr.getY(i);
    out[3 * i + 2] = attr.getZ(i);
  }
  return out;
}

// Per triangle (typed arrays): corners, A⁻¹ (row-major 2×2), F / s² (3×2 row-major), rest area;
// and the triangles of each vertex (CSR).
function charts(pos, uv, index, n) {
  const nAll = index.length / 3;
  const corner = new Int32Array(nAll * 3);
  const inv = new Float64Array(nAll * 4);
  const f = new Float64Array(nAll * 6);
  const area = new Float64Array(nAll);
  let m = 0;
  for (let t = 0; t < nAll; t++) {
    const i0 = index[3 * t], i1 = index[3 * t + 1], i2 = index[3 * t + 2];
    const a00 = uv[2 * i1] - uv[2 * i0], a10 = uv[2 * i1 + 1] - uv[2 * i0 + 1];
    const a01 = uv[2 * i2] - uv[2 * i0], a11 = uv[2 * i2 + 1] - uv[2 * i0 + 1];
    const det = a00 * a11 - a01 * a10;
    if (Math.abs(det) <= 1e-12) continue;
    const q = [a11 / det, -a01 / det, -a10 / det, a00 / det];
    const e1 = [0, 0, 0], e2 = [0, 0, 0];
    let s2 = 0;
    for (let k = 0; k < 3; k++) {
      e1[k] = pos[3 * i1 + k] - pos[3 * i0 + k];
      e2[k] = pos[3 * i2 + k] - pos[3 * i0 + k];
      const c0 = e1[k] * q[0] + e2[k] * q[2];
      const c1 = e1[k] * q[1] + e2[k] * q[3];
      f[6 * m + 2 * k] = c0;
      f[6 * m + 2 * k + 1] = c1;
      s2 += c0 * c0 + c1 * c1;
    }
    for (let k = 0; k < 6; k++) f[6 * m + k] /= 0.5 * s2;
    inv.set(q, 4 * m);
    corner[3 * m] = i0;
    corner[3 * m + 1] = i1;
    corner[3 * m + 2] = i2;
    const cx = e1[1] * e2[2] - e1[2] * e2[1];
    const cy = e1[2] * e2[0] - e1[0] * e2[2];
    const cz = e1[0] * e2[1] - e1[1] * e2[0];
    area[m++] = 0.5 * Math.hypot(cx, cy, cz);
  }
  const start = new Int32Array(n + 1);
  for (let c = 0; c < 3 * m; c++) start[corner[c] + 1]++;
  for (let i = 0; i < n; i++) start[i + 1] += start[i];
  const fill = start.slice(0, n);
  const tris = new Int32Array(3 * m);
  for (let c = 0; c < 3 * m; c++) tris[fill[corner[c]]++] = (c / 3) | 0;
  return { m, corner, inv, f, area, start, tris };
}

// One target's vertex strains (area-weighted means) into data at base, visiting only the
// triangles next to a vertex it moves.
function targetStrain(ch, d, n, areaSum, work, target, data, base) {
  const { corner, inv, f, area, start, tris } = ch;
  const { acc, stamp, mark, touched, seen } = work;
  let nTouched = 0;
  for (let i = 0; i < n; i++) {
    if (d[3 * i] === 0 && d[3 * i + 1] === 0 && d[3 * i + 2] === 0) continue;
    for (let j = start[i]; j < start[i + 1]; j++) {
      const t = tris[j];
      if (stamp[t] !== target) {
        stamp[t] = target;
        touched[nTouched++] = t;
      }
    }
  }
  let nSeen = 0;
  const add = (i, a00, a11, a01) => {
    if (mark[i] !== target) {
      mark[i] = target;
      acc[3 * i] = acc[3 * i + 1] = acc[3 * i + 2] = 0;
      seen[nSeen++] = i;
    }
    acc[3 * i] += a00;
    acc[3 * i + 1] += a11;
    acc[3 * i + 2] += a01;
  };
  for (let k = 0; k < nTouched; k++) {
    const t = touched[k];
    const i0 = 3 * corner[3 * t], i1 = 3 * corner[3 * t + 1], i2 = 3 * corner[3 * t + 2];
    const q0 = inv[4 * t], q1 = inv[4 * t + 1], q2 = inv[4 * t + 2], q3 = inv[4 * t + 3];
    let e00 = 0, e01 = 0, e10 = 0, e11 = 0;
    for (let c = 0; c < 3; c++) {
      const x1 = d[i1 + c] - d[i0 + c];
      const x2 = d[i2 + c] - d[i0 + c];
      const g0 = x1 * q0 + x2 * q2;
      const g1 = x1 * q1 + x2 * q3;
      const fu = f[6 * t + 2 * c], fv = f[6 * t + 2 * c + 1];
      e00 += fu * g0;
      e01 += fu * g1;
      e10 += fv * g0;
      e11 += fv * g1;
    }
    const a = area[t];
    const s00 = a * e00, s11 = a * e11, s01 = 0.5 * a * (e01 + e10);
    add(i0 / 3, s00, s11, s01);
    add(i1 / 3, s00, s11, s01);
    add(i2 / 3, s00, s11, s01);
  }
  for (let k = 0; k < nSeen; k++) {
    const i = seen[k];
    const o = base + 4 * i;
    data[o] = acc[3 * i] / areaSum[i];
    data[o + 1] = acc[3 * i + 1] / areaSum[i];
    data[o + 2] = acc[3 * i + 2] / areaSum[i];
  }
}

/**
 * The strain texture of a primitive's geometry (rest positions, TEXCOORD_0 as `uv`, index,
 * relative morph positions). A target's strains are computed the first time a face uses it
 * (`ensure`), so loading costs only the charts. Null without UVs or morph targets.
 */
export class StrainField {
  static of(geometry) {
    const morphs = geometry.morphAttributes?.position;
    if (!morphs?.length || !geometry.attributes.uv || !geometry.index) return null;
    return new StrainField(geometry);
  }

  constructor(geometry) {
    this.morphs = geometry.morphAttributes.position;
    const n = geometry.attributes.position.count;
    const uvAttr = geometry.attributes.uv;
    const uv = new Float32Array(n * 2);
    for (let i = 0; i < n; i++) {
      uv[2 * i] = uvAttr.getX(i);
      uv[2 * i + 1] = uvAttr.getY(i);
    }
    this.charts = charts(floats(geometry.attributes.position), uv, geometry.index.array, n);
    const ch = this.charts;
    this.areaSum = new Float64Array(n);
    for (let c = 0; c < 3 * ch.m; c++) this.areaSum[ch.corner[c]] += ch.area[(c / 3) | 0];
    const rows = Math.max(1, Math.ceil((this.morphs.length * n) / STRAIN_WIDTH));
    this.data = new Float32Array(STRAIN_WIDTH * rows * 4);
    this.work = {
      acc: new Float64Array(n * 3),
      stamp: new Int32Array(ch.m).fill(-1),
      mark: new Int32Array(n).fill(-1),
      touched: new Int32Array(ch.m),
      seen: new Int32Array(n),
    };
    this.done = new Uint8Array(this.morphs.length);
    this.vertices = n;
    this.texture = new DataTexture(this.data, STRAIN_WIDTH, rows, RGBAFormat, FloatType);
    this.texture.minFilter = this.texture.magFilter = NearestFilter;
    this.texture.generateMipmaps = false;
    this.texture.needsUpdate = true;
  }

  /** Compute the strains of these target indices if not yet done (then re-upload). */
  ensure(targets) {
    let changed = false;
    for (const t of targets) {
      if (this.done[t]) continue;
      const base = t * this.vertices * 4;
      targetStrain(this.charts, floats(this.morphs[t]), this.vertices, this.areaSum, this.work, t,
        this.data, base);
      this.done[t] = 1;
      changed = true;
    }
    if (changed) this.texture.needsUpdate = true;
  }
}
