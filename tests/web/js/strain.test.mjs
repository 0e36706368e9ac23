// The viewer's per-target strain (src/emogen/web/viewer/strain.js) against the textbook linear
// strain: an affine displacement u(x) = M x of a flat sheet has strain sym(M) at every vertex,
// in UV axes (here the x and y axes, at any UV scale), as emogen/render/wrinkles.py computes
// it (tests/render/test_wrinkles.py checks the Python side the same way).
import assert from "node:assert/strict";
import { test } from "node:test";

import { BufferAttribute, BufferGeometry } from "three";
import { StrainField, STRAIN_WIDTH } from "../../../src/emogen/web/viewer/strain.js";

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

test("an affine displacement has strain sym(M) at every vertex, per target", () => {
  const grads = [[0.1, -0.05, 0.2, -0.15], [0, 0, 0, 0], [-0.2, 0.1, 0.1, 0.05]];
  const g = sheet(6, 20, grads);
  const field = StrainField.of(g);
  assert.equal(field.texture.image.width, STRAIN_WIDTH);
  field.ensure([0, 2]);
  const n = field.vertices;
  grads.forEach(([a, b, c, d], t) => {
    const want = t === 1 ? [0, 0, 0] : [a, d, 0.5 * (b + c)];  // target 1 not computed: zeros
    for (let i = 0; i < n; i++) {
      for (let k = 0; k < 3; k++) {
        assert.ok(Math.abs(field.data[(t * n + i) * 4 + k] - want[k]) < 1e-5, `target ${t} vertex ${i}`);
      }
    }
  });
});

test("no UVs or no morph targets: no strain field", () => {
  const g = sheet(2, 10, []);
  assert.equal(StrainField.of(g), null);
});
