// Per-vertex shading attributes for the GLB's primitives, by the rules of emogen/render/scene.py:
// part codes from the regions, eye frames from the outer shell, lash opacity from the distance
// to the face. Each primitive's extras map its vertices to the source model's vertex numbers.
import { BufferAttribute, Matrix4, Vector3 } from 'three';
import { look, srgbToLinear } from './look.js';

const CM_PER_M = 100;

function sourceIndices(runs) {
  let n = 0;
  for (const [, count] of runs) n += count;
  const out = new Int32Array(n);
  let k = 0;
  for (const [first, count] of runs) for (let i = 0; i < count; i++) out[k++] = first + i;
  return out;
}

// Least-squares sphere centre: solve 2 p·c + (r² − |c|²) = |p|² by the normal equations.
function sphereCentre(points) {
  const m = Array.from({ length: 4 }, () => new Float64Array(5));
  for (const p of points) {
    const a = [2 * p[0], 2 * p[1], 2 * p[2], 1];
    const b = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    for (let i = 0; i < 4; i++) {
      for (let j = 0; j < 4; j++) m[i][j] += a[i] * a[j];
      m[i][4] += a[i] * b;
    }
  }
  for (let c = 0; c < 4; c++) {
    let pivot = c;
    for (let r = c + 1; r < 4; r++) if (Math.abs(m[r][c]) > Math.abs(m[pivot][c])) pivot = r;
    [m[c], m[pivot]] = [m[pivot], m[c]];
    for (let r = 0; r < 4; r++) {
      if (r === c) continue;
      const f = m[r][c] / m[c][c];
      for (let k = c; k < 5; k++) m[r][k] -= f * m[c][k];
    }
  }
  return [m[0][4] / m[0][0], m[1][4] / m[1][1], m[2][4] / m[2][2]];
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => {
  const n = Math.hypot(a[0], a[1], a[2]);
  return [a[0] / n, a[1] / n, a[2] / n];
};

// Rest frame of an eye from its shell's points (source order): centre and rows x, y, z = axis.
function eyeFrame(points, nAxis) {
  const centre = sphereCentre(points);
  const ranked = points.map((p, i) => {
    const d = sub(p, centre);
    return { i, d, r: d[2] > 0 ? Math.hypot(d[0], d[1], d[2]) : -1 };
  });
  ranked.sort((a, b) => b.r - a.r); // stable, like numpy's argsort(kind="stable")
  const z = [0, 0, 0];
  for (const { d, r } of ranked.slice(0, nAxis)) for (let k = 0; k < 3; k++) z[k] += d[k] / r;
  const axis = unit(z);
  const x = unit(cross([0, 1, 0], axis));
  return { centre, rows: [x, cross(axis, x), axis] };
}

const smoothstep = (e0, e1, x) => {
  const t = Math.min(Math.max((x - e0) / (e1 - e0), 0), 1);
  return t * t * (3 - 2 * t);
};

/**
 * The eye attribute of skin vertices that lie on an eyeball (look.json lid_margin, as
 * emogen.render.scene._lid_margin): [lower lid's wet margin, inner corner] by source vertex.
 */
function lidMargins(frames, regionPoints, restBySource, codeBySource) {
  const lm = look.lid_margin;
  const out = new Map();
  if (!lm) return out;
  const skin = look.shader.PART_SKIN;
  for (const f of frames) {
    const shell = regionPoints(f.shell);
    for (const [s, p] of restBySource) {
      if (codeBySource[s] !== skin) continue;
      const d = [p[0] - f.centre[0], p[1] - f.centre[1], p[2] - f.centre[2]];
      if (Math.hypot(d[0], d[1], d[2]) >= 2.5) continue;
      let best = Infinity;
      for (const q of shell) {
        best = Math.min(best, (q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2 + (q[2] - p[2]) ** 2);
      }
      const on = 1 - smoothstep(lm.near_cm, lm.far_cm, Math.sqrt(best));
      const u = unit([dot(f.rows[0], d), dot(f.rows[1], d), dot(f.rows[2], d)]);
      const nasal = f.side === 1 ? -u[0] : u[0];
      out.set(s, [
        on * Math.min(Math.max(-u[1] / lm.lower_fade, 0), 1),
        on * smoothstep(lm.caruncle_from, lm.caruncle_full, nasal),
      ]);
    }
  }
  return out;
}

/**
 * Add aPart, aAlbedo, aSurface and aEye attributes to every primitive of a loaded GLB.
 * meshes: the primitives' three.js Meshes (world matrices up to date); regions: the GLB's
 * asset.extras.emogen.regions. Returns {meshes: [{mesh, part, flags}]}.
 */
export function addShadingAttributes(meshes, regions) {
  const prims = meshes.map((mesh) => {
    const runs = mesh.geometry.userData?.emogen?.source_vertices;
    if (!runs) throw new Error('GLB primitive lacks extras.emogen.source_vertices');
    const src = sourceIndices(runs);
    const pos = mesh.geometry.attributes.position;
    if (src.length !== pos.count) throw new Error('source_vertices does not match the vertex count');
    const world = new Float64Array(pos.count * 3);
    const v = new Vector3();
    const toCm = new Matrix4().makeScale(CM_PER_M, CM_PER_M, CM_PER_M).multiply(mesh.matrixWorld);
    for (let i = 0; i < pos.count; i++) {
      v.fromBufferAttribute(pos, i).applyMatrix4(toCm);
      world[3 * i] = v.x;
      world[3 * i + 1] = v.y;
      world[3 * i + 2] = v.z;
    }
    return { mesh, src, world };
  });

  // Compacted region ranges → source ranges (the exported vertices, sorted, are the compaction).
  const all = new Int32Array(prims.reduce((n, p) => n + p.src.length, 0));
  let k = 0;
  for (const p of prims) {
    all.set(p.src, k);
    k += p.src.length;
  }
  all.sort();
  const used = all.filter((x, i) => i === 0 || x !== all[i - 1]);
  const ranges = {};
  for (const [name, r] of Object.entries(regions || {})) {
    if (r[1] > r[0]) ranges[name] = [used[r[0]], used[r[1] - 1] + 1];
  }

  // Unique rest positions (cm) by source vertex, in source order.
  const restBySource = new Map();
  for (const p of prims) {
    for (let i = 0; i < p.src.length; i++) {
      if (!restBySource.has(p.src[i])) {
        restBySource.set(p.src[i], [p.world[3 * i], p.world[3 * i + 1], p.world[3 * i + 2]]);
      }
    }
  }
  const regionPoints = (name) => {
    if (!ranges[name]) return [];
    const out = [];
    for (let s = ranges[name][0]; s < ranges[name][1]; s++) {
      if (restBySource.has(s)) out.push(restBySource.get(s));
    }
    return out;
  };

  const frames = [];
  for (const eye of look.eyes) {
    if (!ranges[eye.shell] || !ranges[eye.ball]) continue;
    frames.push({ ...eye, ...eyeFrame(regionPoints(eye.shell), look.eye_axis_vertices) });
  }
  const root = regionPoints(look.fringe_root);
  const rootXYZ = new Float64Array(root.flat());
  const parts = look.parts;
  const albedo = parts.map((p) => p.albedo_srgb.map(srgbToLinear));

  // Part code and eye frame of every source vertex (the last part listing a region wins).
  const nSource = used.length ? used[used.length - 1] + 1 : 0;
  const codeBySource = new Uint8Array(nSource);
  parts.forEach((part, c) => {
    for (const r of part.regions) if (ranges[r]) codeBySource.fill(c, ranges[r][0], ranges[r][1]);
  });
  const frameBySource = new Int8Array(nSource).fill(-1);
  frames.forEach((f, k) => {
    for (const r of [f.shell, f.ball]) frameBySource.fill(k, ranges[r][0], ranges[r][1]);
  });
  const nearestRoot = (x, y, z) => {
    let best = Infinity;
    for (let j = 0; j < rootXYZ.length; j += 3) {
      const dx = rootXYZ[j] - x, dy = rootXYZ[j + 1] - y, dz = rootXYZ[j + 2] - z;
      const d2 = dx * dx + dy * dy + dz * dz;
      if (d2 < best) best = d2;
    }
    return Math.sqrt(best);
  };

  const lids = lidMargins(frames, regionPoints, restBySource, codeBySource);
  const out = [];
  for (const p of prims) {
    const n = p.src.length;
    const aPart = new Float32Array(n);
    const aAlbedo = new Float32Array(n * 3);
    const aSurface = new Float32Array(n * 4);
    const aEye = new Float32Array(n * 4);
    for (let i = 0; i < n; i++) {
      const s = p.src[i];
      const code = codeBySource[s];
      const part = parts[code];
      const x = p.world[3 * i], y = p.world[3 * i + 1], z = p.world[3 * i + 2];
      let alpha = part.opacity;
      if (part.fringe_cm > 0 && root.length) {
        alpha = part.opacity * (1 - smoothstep(0, part.fringe_cm, nearestRoot(x, y, z)));
      }
      aPart[i] = code;
      aAlbedo.set(albedo[code], 3 * i);
      aSurface[4 * i] = part.specular;
      aSurface[4 * i + 1] = part.shininess;
      aSurface[4 * i + 2] = part.cavity;
      aSurface[4 * i + 3] = alpha;
      const k = frameBySource[s];
      if (k >= 0) {
        const f = frames[k];
        const d = [x - f.centre[0], y - f.centre[1], z - f.centre[2]];
        const e = unit([dot(f.rows[0], d), dot(f.rows[1], d), dot(f.rows[2], d)]);
        aEye.set([e[0], e[1], e[2], f.side], 4 * i);
      } else if (lids.has(s)) {
        aEye.set([...lids.get(s), 0, 0], 4 * i);
      }
    }
    const g = p.mesh.geometry;
    g.setAttribute('aPart', new BufferAttribute(aPart, 1));
    g.setAttribute('aAlbedo', new BufferAttribute(aAlbedo, 3));
    g.setAttribute('aSurface', new BufferAttribute(aSurface, 4));
    g.setAttribute('aEye', new BufferAttribute(aEye, 4));
    const first = g.index ? g.index.getX(0) : 0;
    let lo = Infinity, hi = -Infinity; // the part codes a fragment can interpolate between
    for (const c of aPart) (lo = Math.min(lo, c)), (hi = Math.max(hi, c));
    out.push({ mesh: p.mesh, part: parts[aPart[first] | 0], codes: [lo, hi] });
  }
  return out;
}
