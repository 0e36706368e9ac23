// The skin's strain per morph target, by the rules of emogen/render/wrinkles.py: per triangle
// the rotation-free (Biot) strain U − I of the target at full weight, F = R U the polar
// decomposition of the deformation gradient in the rest triangle's frame (first axis along u),
// averaged over a vertex's triangles by rest area, twice (two rings). A target that only turns
// or moves skin has none. A face's strain is its targets' strains blended with its morph weights
// (``blend``, in morph.js's pass), as the offscreen renderer does with its weights; each target's
// strain is kept for the vertices it reaches (two rings around those it moves).
import { floats } from './morph.js';

// Per triangle (typed arrays): corners, A⁻¹ (row-major 2×2), the rest Jacobian F₀ (3×2
// row-major, cm per UV unit), L⁻¹ of F₀ = Q L (a, b, c of [[a, b], [0, c]]), rest area; and the
// triangles of each vertex (CSR).
function charts(pos, uv, index, n) {
  const nAll = index.length / 3;
  const corner = new Int32Array(nAll * 3);
  const inv = new Float64Array(nAll * 4);
  const f = new Float64Array(nAll * 6);
  const frame = new Float64Array(nAll * 3);
  const area = new Float64Array(nAll);
  let m = 0;
  for (let t = 0; t < nAll; t++) {
    const i0 = index[3 * t], i1 = index[3 * t + 1], i2 = index[3 * t + 2];
    const a00 = uv[2 * i1] - uv[2 * i0], a10 = uv[2 * i1 + 1] - uv[2 * i0 + 1];
    const a01 = uv[2 * i2] - uv[2 * i0], a11 = uv[2 * i2 + 1] - uv[2 * i0 + 1];
    const det = a00 * a11 - a01 * a10;
    if (Math.abs(det) <= 1e-12) continue;
    const q = [a11 / det, -a01 / det, -a10 / det, a00 / det];
    const e1 = [0, 0, 0], e2 = [0, 0, 0], fu = [0, 0, 0], fv = [0, 0, 0];
    for (let k = 0; k < 3; k++) {
      e1[k] = pos[3 * i1 + k] - pos[3 * i0 + k];
      e2[k] = pos[3 * i2 + k] - pos[3 * i0 + k];
      fu[k] = e1[k] * q[0] + e2[k] * q[2];
      fv[k] = e1[k] * q[1] + e2[k] * q[3];
    }
    const l11 = Math.hypot(fu[0], fu[1], fu[2]);
    if (!(l11 > 1e-9)) continue;
    const l12 = (fu[0] * fv[0] + fu[1] * fv[1] + fu[2] * fv[2]) / l11;
    const l22 = Math.hypot(fv[0] - (l12 * fu[0]) / l11, fv[1] - (l12 * fu[1]) / l11,
      fv[2] - (l12 * fu[2]) / l11);
    if (!(l22 > 1e-9 * Math.max(l11, 1))) continue;
    for (let k = 0; k < 3; k++) {
      f[6 * m + 2 * k] = fu[k];
      f[6 * m + 2 * k + 1] = fv[k];
    }
    frame[3 * m] = 1 / l11;
    frame[3 * m + 1] = -l12 / (l11 * l22);
    frame[3 * m + 2] = 1 / l22;
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
  return { m, corner, inv, f, frame, area, start, tris };
}

// Triangle t's Biot strain (uu, vv, uv) under displacements d, into out[0..2].
function biot(ch, d, t, out) {
  const { corner, inv, f, frame } = ch;
  const i0 = 3 * corner[3 * t], i1 = 3 * corner[3 * t + 1], i2 = 3 * corner[3 * t + 2];
  const q0 = inv[4 * t], q1 = inv[4 * t + 1], q2 = inv[4 * t + 2], q3 = inv[4 * t + 3];
  const a = frame[3 * t], b = frame[3 * t + 1], c = frame[3 * t + 2];
  let c00 = 0, c01 = 0, c11 = 0;
  for (let k = 0; k < 3; k++) {
    const x1 = d[i1 + k] - d[i0 + k];
    const x2 = d[i2 + k] - d[i0 + k];
    const u = f[6 * t + 2 * k] + x1 * q0 + x2 * q2;  // F₁ = F₀ + [d1 − d0, d2 − d0] A⁻¹
    const v = f[6 * t + 2 * k + 1] + x1 * q1 + x2 * q3;
    const g0 = a * u, g1 = b * u + c * v;  // F = F₁ L⁻¹
    c00 += g0 * g0;
    c01 += g0 * g1;
    c11 += g1 * g1;
  }
  const s = Math.sqrt(Math.max(c00 * c11 - c01 * c01, 0));
  const tr = Math.sqrt(Math.max(c00 + c11 + 2 * s, 0));
  const k = tr > 1e-12 ? 1 / tr : 0;
  out[0] = (c00 + s) * k - 1;
  out[1] = (c11 + s) * k - 1;
  out[2] = c01 * k;
}

// The triangles next to the listed vertices (stamped with id), appended to list; their count.
function around(ch, verts, nVerts, stamp, id, list) {
  let count = 0;
  for (let j = 0; j < nVerts; j++) {
    const i = verts[j];
    for (let k = ch.start[i]; k < ch.start[i + 1]; k++) {
      const t = ch.tris[k];
      if (stamp[t] !== id) {
        stamp[t] = id;
        list[count++] = t;
      }
    }
  }
  return count;
}

// Area-weighted sums of per-triangle values (val, 3 a triangle) into the vertices (acc, zeroed
// on first touch, listed in seen); the count of seen vertices.
function spread(ch, tris, nTris, val, acc, mark, id, seen) {
  let nSeen = 0;
  for (let j = 0; j < nTris; j++) {
    const t = tris[j], a = ch.area[t];
    for (let c = 0; c < 3; c++) {
      const i = ch.corner[3 * t + c];
      if (mark[i] !== id) {
        mark[i] = id;
        acc[3 * i] = acc[3 * i + 1] = acc[3 * i + 2] = 0;
        seen[nSeen++] = i;
      }
      for (let k = 0; k < 3; k++) acc[3 * i + k] += a * val[3 * j + k];
    }
  }
  return nSeen;
}

// One target's vertex strains (two rings of area-weighted means), visiting only the triangles
// near a vertex it moves: {index: the vertices reached, value: their (uu, vv, uv) strains}.
function targetStrain(ch, d, n, areaSum, work, target) {
  const { acc, mark, mark2, stamp, stamp2, tris1, tris2, val, seen, seen2 } = work;
  const moved = [];
  for (let i = 0; i < n; i++) {
    if (d[3 * i] !== 0 || d[3 * i + 1] !== 0 || d[3 * i + 2] !== 0) moved.push(i);
  }
  const n1 = around(ch, moved, moved.length, stamp, target, tris1);
  const e = [0, 0, 0];
  for (let j = 0; j < n1; j++) {
    biot(ch, d, tris1[j], e);
    val[3 * j] = e[0];
    val[3 * j + 1] = e[1];
    val[3 * j + 2] = e[2];
  }
  const s1 = spread(ch, tris1, n1, val, acc, mark, target, seen);
  for (let j = 0; j < s1; j++) {
    const i = seen[j];
    for (let k = 0; k < 3; k++) acc[3 * i + k] /= areaSum[i];
  }
  // second ring: each triangle the mean of its corners, spread to the vertices again
  const n2 = around(ch, seen, s1, stamp2, target, tris2);
  for (let j = 0; j < n2; j++) {
    const t = tris2[j];
    for (let k = 0; k < 3; k++) {
      let sum = 0;
      for (let c = 0; c < 3; c++) {
        const i = ch.corner[3 * t + c];
        if (mark[i] === target) sum += acc[3 * i + k];
      }
      val[3 * j + k] = sum / 3;
    }
  }
  const acc2 = work.acc2;
  const s2 = spread(ch, tris2, n2, val, acc2, mark2, target, seen2);
  const index = seen2.slice(0, s2).sort();
  const value = new Float32Array(3 * s2);
  for (let j = 0; j < s2; j++) {
    const i = index[j];
    for (let k = 0; k < 3; k++) value[3 * j + k] = acc2[3 * i + k] / areaSum[i];
  }
  return { index, value };
}

/**
 * The per-target strains of a primitive's geometry (rest positions, TEXCOORD_0 as `uv`, index,
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
    this.work = {
      acc: new Float64Array(n * 3),
      acc2: new Float64Array(n * 3),
      val: new Float64Array(ch.m * 3),
      stamp: new Int32Array(ch.m).fill(-1),
      stamp2: new Int32Array(ch.m).fill(-1),
      mark: new Int32Array(n).fill(-1),
      mark2: new Int32Array(n).fill(-1),
      tris1: new Int32Array(ch.m),
      tris2: new Int32Array(ch.m),
      seen: new Int32Array(n),
      seen2: new Int32Array(n),
    };
    /** Per target, once computed: {index: vertices, value: (uu, vv, uv) per vertex}. */
    this.targets = new Array(this.morphs.length).fill(null);
    this.vertices = n;
  }

  /** Compute the strains of these target indices if not yet done. */
  ensure(targets) {
    for (const t of targets) {
      if (this.targets[t]) continue;
      this.targets[t] = targetStrain(this.charts, floats(this.morphs[t]), this.vertices,
        this.areaSum, this.work, t);
    }
  }

  /** Σ weights[t] · strain of t over the ``active`` targets, added into ``out`` (n · 3). */
  blend(weights, active, out) {
    for (const t of active) {
      if (t >= this.targets.length) continue;
      this.ensure([t]);
      const w = weights[t];
      const { index, value } = this.targets[t];
      for (let j = 0; j < index.length; j++) {
        const v = 3 * index[j];
        out[v] += w * value[3 * j];
        out[v + 1] += w * value[3 * j + 1];
        out[v + 2] += w * value[3 * j + 2];
      }
    }
  }
}
