// The morph on the CPU: a face's positions, normals and skin strain are the rest values plus its
// targets' deltas times their weights, summed in one typed-array pass over the vertices each
// target moves (the targets are sparse: a shape moves a sixth of the vertices, most correctives
// fewer). The faces are then drawn as plain meshes: the vertex shader reads the morphed values as
// attributes. Software GL (SwiftShader) ran the blend for every vertex in every draw, three
// texture fetches per non-zero target. CPU of Chromium's GPU process a frame, vertex-shader
// morph → this (docs/render.md): the one-face slider page 185 → 80 ms (benchmarks/bench_gsp_slider.py),
// ten moving tiles 1057 → 493 ms (bench_dynamic_page.py), shared 2-core VM, load average 11–16.
import { BufferAttribute, BufferGeometry, DynamicDrawUsage } from 'three';

// A vec3 attribute's stored values and the divisor that makes them floats as the GPU reads them
// (1: floats already; 32767 or 127: normalised int16 or int8, read as max(c / divisor, −1)),
// without a copy where they are a plain array.
function stored(attr) {
  const a = attr.array;
  if (!attr.isInterleavedBufferAttribute && attr.itemSize === 3 && a.length === attr.count * 3) {
    if (!attr.normalized) return [a, 1];
    if (a instanceof Int16Array) return [a, 32767];
    if (a instanceof Int8Array) return [a, 127];
  }
  const out = new Float32Array(attr.count * 3);
  for (let i = 0; i < attr.count; i++) {
    out[3 * i] = attr.getX(i);
    out[3 * i + 1] = attr.getY(i);
    out[3 * i + 2] = attr.getZ(i);
  }
  return [out, 1];
}

/** (count · 3) float values of a vec3 attribute (plain, normalised integer or interleaved). */
export function floats(attr) {
  const [a, scale] = stored(attr);
  if (scale === 1) return a;
  const out = new Float32Array(a.length);
  for (let i = 0; i < a.length; i++) out[i] = Math.max(a[i] / scale, -1);
  return out;
}

/**
 * One primitive's rest positions and normals and its morph targets (relative POSITION and
 * NORMAL deltas, three's morphAttributes), each target kept as the vertices it moves and their
 * six deltas, made the first time a face uses it. strain: the primitive's StrainField
 * (strain.js) or null.
 */
export class MorphSource {
  constructor(geometry, strain = null) {
    this.positions = geometry.morphAttributes.position ?? [];
    this.normals = geometry.morphAttributes.normal ?? [];
    this.rest = floats(geometry.attributes.position);
    this.restNormal = geometry.attributes.normal
      ? floats(geometry.attributes.normal)
      : new Float32Array(this.rest.length);
    this.vertices = geometry.attributes.position.count;
    this.strain = strain;
    this.sparse = new Array(this.positions.length).fill(null);
  }

  /** Target ``t`` as {index: the vertices it moves, delta: their (dx dy dz dnx dny dnz)}. */
  target(t) {
    if (this.sparse[t]) return this.sparse[t];
    const [p, ps] = stored(this.positions[t]);
    const [n, ns] = this.normals[t] ? stored(this.normals[t]) : [new Float32Array(p.length), 1];
    const end = 3 * this.vertices;
    let count = 0;
    for (let i = 0; i < end; i += 3) {
      if (p[i] || p[i + 1] || p[i + 2] || n[i] || n[i + 1] || n[i + 2]) count++;
    }
    const index = new Int32Array(count);
    const delta = new Float32Array(6 * count);
    for (let i = 0, j = 0; i < end; i += 3) {
      if (!(p[i] || p[i + 1] || p[i + 2] || n[i] || n[i + 1] || n[i + 2])) continue;
      index[j] = i / 3;
      for (let k = 0; k < 3; k++) {
        delta[6 * j + k] = ps === 1 ? p[i + k] : Math.max(p[i + k] / ps, -1);
        delta[6 * j + 3 + k] = ns === 1 ? n[i + k] : Math.max(n[i + k] / ns, -1);
      }
      j++;
    }
    this.sparse[t] = { index, delta };
    return this.sparse[t];
  }

  /**
   * A geometry of its own for one face: the primitive's index and per-vertex attributes shared
   * (uploaded once), its own position, normal and aStrain (the skin's strain, strain.js).
   */
  faceGeometry(geometry) {
    const g = new BufferGeometry();
    g.setIndex(geometry.index);
    for (const [name, attr] of Object.entries(geometry.attributes)) {
      if (name !== 'position' && name !== 'normal') g.setAttribute(name, attr);
    }
    const own = (values) => new BufferAttribute(values, 3).setUsage(DynamicDrawUsage);
    g.setAttribute('position', own(Float32Array.from(this.rest)));
    g.setAttribute('normal', own(Float32Array.from(this.restNormal)));
    g.setAttribute('aStrain', own(new Float32Array(3 * this.vertices)));
    g.userData = geometry.userData;
    return g;
  }

  /**
   * Morph ``geometry`` (from faceGeometry) to ``weights`` (every target's weight; ``active``:
   * the targets whose weight is not 0, in order): rest + Σ weight · delta for positions and
   * normals, Σ weight · strain for the strain, then their upload.
   */
  morph(geometry, weights, active) {
    const pos = geometry.attributes.position.array;
    const nor = geometry.attributes.normal.array;
    const str = geometry.attributes.aStrain.array;
    pos.set(this.rest);
    nor.set(this.restNormal);
    str.fill(0);
    for (const t of active) {
      if (t >= this.positions.length) continue;
      const w = weights[t];
      const { index, delta } = this.target(t);
      for (let j = 0; j < index.length; j++) {
        const v = 3 * index[j], d = 6 * j;
        pos[v] += w * delta[d];
        pos[v + 1] += w * delta[d + 1];
        pos[v + 2] += w * delta[d + 2];
        nor[v] += w * delta[d + 3];
        nor[v + 1] += w * delta[d + 4];
        nor[v + 2] += w * delta[d + 5];
      }
    }
    if (this.strain) this.strain.blend(weights, active, str);
    for (const name of ['position', 'normal', 'aStrain']) geometry.attributes[name].needsUpdate = true;
  }
}
