// The viewer's CPU morph (src/emogen/web/viewer/morph.js) against a plain loop over every vertex
// and every target: position = rest + Σ w·Δp, normal = rest normal + Σ w·Δn, with the targets
// stored as glTF stores them (normalised int16 positions, int8 normals, mostly zeros), each
// value read as the GPU reads it (max(c / 32767, −1)).
import assert from "node:assert/strict";
import { test } from "node:test";

import { BufferAttribute, BufferGeometry } from "three";
import { MorphSource } from "../../../src/emogen/web/viewer/morph.js";

const N = 50;
const TARGETS = 6;

// A seeded stream (xorshift32) in [0, 1): the test's data are the same on every run.
function stream(seed) {
  let x = seed >>> 0 || 1;
  return () => {
    x ^= x << 13;
    x ^= x >>> 17;
    x ^= x << 5;
    return (x >>> 0) / 4294967296;
  };
}

function geometry() {
  const rnd = stream(7);
  const ints = (Kind, n, max, density) =>
    Kind.from({ length: 3 * n }, () => (rnd() < density ? Math.round((2 * rnd() - 1) * max) : 0));
  const g = new BufferGeometry();
  g.setAttribute("position", new BufferAttribute(ints(Int16Array, N, 32767, 1), 3, true));
  g.setAttribute("normal", new BufferAttribute(ints(Int8Array, N, 127, 1), 3, true));
  g.setAttribute("uv", new BufferAttribute(new Float32Array(2 * N), 2));
  g.setIndex([0, 1, 2, 2, 3, 4]);
  // target 3 moves nothing; target 4 turns normals only; the others move a third of the vertices
  // (-32768 included: it reads as -1, like -32767)
  const position = [], normal = [];
  for (let t = 0; t < TARGETS; t++) {
    const p = t === 3 || t === 4 ? new Int16Array(3 * N) : ints(Int16Array, N, 32767, 0.33);
    if (t === 0) p[5] = -32768;
    position.push(new BufferAttribute(p, 3, true));
    normal.push(new BufferAttribute(t === 3 ? new Int8Array(3 * N) : ints(Int8Array, N, 127, 0.4), 3, true));
  }
  g.morphAttributes = { position, normal };
  return g;
}

const read = (attr, j) => Math.max(attr.array[j] / (attr.array instanceof Int16Array ? 32767 : 127), -1);

test("a face's positions and normals are the rest plus its weighted target deltas, as a plain loop", () => {
  const g = geometry();
  const source = new MorphSource(g);
  const face = source.faceGeometry(g);
  assert.equal(face.index, g.index); // shared with every face, uploaded once
  assert.equal(face.attributes.uv, g.attributes.uv);
  assert.equal(face.morphAttributes.position, undefined); // a plain mesh: three blends nothing
  for (const weights of [[0, 0, 0, 0, 0, 0], [1, 0, 0.5, 0.2, 1, 0], [-0.3, 0.7, 0, 1, 0.25, 1.5]]) {
    const active = weights.flatMap((w, t) => (w !== 0 ? [t] : []));
    source.morph(face, weights, active);
    for (const [name, key] of [["position", "position"], ["normal", "normal"]]) {
      const got = face.attributes[name].array;
      const rest = g.attributes[name];
      for (let j = 0; j < 3 * N; j++) {
        let want = read(rest, j);
        for (let t = 0; t < TARGETS; t++) want += weights[t] * read(g.morphAttributes[key][t], j);
        assert.ok(Math.abs(got[j] - want) < 1e-6, `${name} ${j} with weights ${weights}: ${got[j]} vs ${want}`);
      }
      assert.equal(face.attributes[name].version > 0, true); // marked for upload
    }
    assert.deepEqual(Array.from(face.attributes.aStrain.array), new Array(3 * N).fill(0)); // no strain field
  }
  // the sparse targets hold exactly the vertices a target moves (positions or normals)
  assert.equal(source.target(3).index.length, 0);
  const moved4 = source.target(4).index;
  assert.ok(moved4.length > 0 && moved4.length < N);
});

test("two faces of one primitive morph independently", () => {
  const g = geometry();
  const source = new MorphSource(g);
  const [a, b] = [source.faceGeometry(g), source.faceGeometry(g)];
  source.morph(a, [1, 0, 0, 0, 0, 0], [0]);
  source.morph(b, [0, 1, 0, 0, 0, 0], [1]);
  const pa = a.attributes.position.array, pb = b.attributes.position.array;
  assert.notDeepEqual(Array.from(pa), Array.from(pb));
  source.morph(b, [1, 0, 0, 0, 0, 0], [0]); // back from target 1: nothing of it is left
  assert.deepEqual(Array.from(pb), Array.from(pa));
});
