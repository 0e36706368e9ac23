// The viewer's per-target strain (src/emogen/web/viewer/strain.js) against the textbook polar
// decomposition: an affine map x → (I + M) x of a flat sheet, I + M = R U, has the Biot strain
// U − I at every vertex, in UV axes (here the x and y axes, at any UV scale), U from the
// eigenvectors of (I + M)ᵀ(I + M); a rigid rotation of the sheet in space has none — as
// emogen/render/wrinkles.py computes it (tests/render/test_wrinkles.py checks the Python side).
import assert from "node:assert/strict";
import { test } from "node:test";

import { BufferAttribute, BufferGeometry } from "three";
import { StrainField } from "../../../src/emogen/web/viewer/strain.js";

// Target t's strain at every vertex (n · 3): the field's blend of t alone at weight 1.
function strainOf(field, t) {
  const weights = new Array(field.targets.length).fill(0);
  weights[t] = 1;
  const out = new Float32Array(3 * field.vertices);
  field.blend(weights, [t], out);
  return out;
}

// U − I of I + M = [[1 + a, b], [c, 1 + d]] by eigen-decomposition of C = (I + M)ᵀ(I + M).
function biotByEigen([a, b, c, d]) {
  const f = [[1 + a, b], [c, 1 + d]];
  const c00 = f[0][0] ** 2 + f[1][0] ** 2, c11 = f[0][1] ** 2 + f[1][1] ** 2;
  const c01 = f[0][0] * f[0][1] + f[1][0] * f[1][1];
  const mean = 0.5 * (c00 + c11), r = Math.hypot(0.5 * (c00 - c11), c01);
  const u = [[0, 0], [0, 0]];
  for (const lam of [mean + r, mean - r]) {
    // eigenvector of C for lam: (c01, lam − c00) or (lam − c11, c01)
    let v = [c01, lam - c00];
    if (Math.hypot(...v) < 1e-9) v = [lam - c11, c01];
    if (Math.hypot(...v) < 1e-9) v = lam === mean + r ? [1, 0] : [0, 1];
    const norm = Math.hypot(...v);
    v = [v[0] / norm, v[1] / norm];
    for (let i = 0; i < 2; i++) for (let j = 0; j < 2; j++) u[i][j] += Math.sqrt(lam) * v[i] * v[j];
  }
  return [u[0][0] - 1, u[1][1] - 1, u[0][1]];
}

function sheet(n, uvScale, grads) {
  const pos = [], uv = [], index = [];
  for (let j = 0; j <= n; j++) {
    for (let i = 0; i <= n; i++) {
      const x = (10 * i) / n + 0.3 * Math.sin(7 * j), y = (10 * j) / n + 0.3 * Math.cos(5 * i);
      pos.push(x, y, 0);
      uv.push(x / uvScale, y / uvScale);
    }
  }
  for (let j = 0; j < n; j++) {
    for (let i = 0; i < n; i++) {
      const a = j * (n + 1) + i;
      index.push(a, a + 1, a + n + 2, a, a + n + 2, a + n + 1);
    }
  }
  const g = new BufferGeometry();
  g.setAttribute("position", new BufferAttribute(new Float32Array(pos), 3));
  g.setAttribute("uv", new BufferAttribute(new Float32Array(uv), 2));
  g.setIndex(index);
  g.morphAttributes.position = grads.map(([a, b, c, d]) => {
    const delta = new Float32Array(pos.length);
    for (let k = 0; k < pos.length; k += 3) {
      delta[k] = a * pos[k] + b * pos[k + 1];
      delta[k + 1] = c * pos[k] + d * pos[k + 1];
    }
    return new BufferAttribute(delta, 3);
  });
  return g;
}

test("an affine map I + M = R U has the Biot strain U − I at every vertex, per target", () => {
  const grads = [[0.1, -0.05, 0.2, -0.15], [0, 0, 0, 0], [-0.2, 0.1, 0.1, 0.05]];
  const g = sheet(6, 20, grads);
  const field = StrainField.of(g);
  const n = field.vertices;
  grads.forEach(([a, b, c, d], t) => {
    const want = t === 1 ? [0, 0, 0] : biotByEigen([a, b, c, d]);  // target 1 moves nothing: none
    const strain = strainOf(field, t);
    for (let i = 0; i < n; i++) {
      for (let k = 0; k < 3; k++) {
        assert.ok(Math.abs(strain[3 * i + k] - want[k]) < 1e-5, `target ${t} vertex ${i}`);
      }
    }
  });
  // a face's strain: the targets' strains blended with its weights
  const out = new Float32Array(3 * n);
  field.blend([0.5, 0.9, -0.25], [0, 1, 2], out);
  const [s0, s2] = [strainOf(field, 0), strainOf(field, 2)];
  for (let j = 0; j < 3 * n; j++) assert.ok(Math.abs(out[j] - (0.5 * s0[j] - 0.25 * s2[j])) < 1e-6);
});

test("a rigid rotation of the sheet in space, by any angle, has no strain", () => {
  const g = sheet(5, 10, []);
  const pos = g.attributes.position.array;
  const angles = [0.3, 1.2, 2.5];
  g.morphAttributes.position = angles.map((th) => {
    // about the axis (1, 1, 1)/√3 by th (Rodrigues), then shifted
    const k = [1, 1, 1].map((x) => x / Math.sqrt(3));
    const delta = new Float32Array(pos.length);
    for (let i = 0; i < pos.length; i += 3) {
      const p = [pos[i], pos[i + 1], pos[i + 2]];
      const kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
      const cross = [k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]];
      for (let j = 0; j < 3; j++) {
        const r = p[j] * Math.cos(th) + cross[j] * Math.sin(th) + k[j] * kp * (1 - Math.cos(th));
        delta[i + j] = r - p[j] + 0.7 * (j + 1);
      }
    }
    return new BufferAttribute(delta, 3);
  });
  const field = StrainField.of(g);
  const n = field.vertices;
  for (let t = 0; t < angles.length; t++) {
    const strain = strainOf(field, t);
    for (let i = 0; i < n; i++) {
      for (let k = 0; k < 3; k++) {
        assert.ok(Math.abs(strain[3 * i + k]) < 1e-5, `rotation ${angles[t]} vertex ${i}`);
      }
    }
  }
});

test("no UVs or no morph targets: no strain field", () => {
  const g = sheet(2, 10, []);
  assert.equal(StrainField.of(g), null);
});
