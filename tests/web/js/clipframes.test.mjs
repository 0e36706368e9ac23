// A clip's frame grid (src/emogen/web/viewer/motion.js) and the order its frames are drawn
// ahead (src/emogen/web/viewer/kept.js), against plain definitions: n = ceil(clip × 30) steps,
// frame k at clip × k / n, a time played as its nearest frame; every position drawn ahead once,
// the first and last first, each coarser grid's frames before a finer one's.
import assert from "node:assert/strict";
import { test } from "node:test";

import { Clip, FRAME_RATE } from "../../../src/emogen/web/viewer/motion.js";
import { coarseToFine } from "../../../src/emogen/web/viewer/kept.js";

const clipOf = (clip_s) =>
  new Clip([0.5], { clip_s, hold_s: 0.75, curves: [[0.1, 0.4, 0.9, 0, 0]], keyframes: [] }, 1);

test("the grid has ceil(clip × 30) steps, its last frame the clip's end", () => {
  assert.equal(FRAME_RATE, 30);
  for (const [clip_s, steps] of [[1.25, 38], [1, 30], [2, 60], [0.1, 3], [0.02, 1]]) {
    const c = clipOf(clip_s);
    assert.equal(c.steps, steps, `clip ${clip_s}`);
    assert.equal(c.gridTime(0), 0);
    assert.equal(c.gridTime(steps), clip_s);
    assert.ok(c.gridTime(1) <= 1 / 30 + 1e-12);
  }
});

test("a time plays as its nearest grid frame; the hold as the last", () => {
  const c = clipOf(1.25);
  for (let t = 0; t <= 1.25; t += 0.0071) {
    const k = c.gridFrame(t);
    for (let j = 0; j <= c.steps; j++) {
      assert.ok(Math.abs(c.gridTime(k) - t) <= Math.abs(c.gridTime(j) - t) + 1e-12, `${t}: ${k} vs ${j}`);
    }
  }
  assert.equal(c.gridFrame(c.time(1.9)), c.steps); // in the hold
  assert.equal(c.gridFrame(c.time(2.0 + 0.001)), 0); // looped
});

test("frames are drawn ahead coarse to fine, each once", () => {
  for (const last of [1, 2, 3, 7, 8, 38, 60]) {
    const order = coarseToFine(last);
    assert.deepEqual([...order].sort((a, b) => a - b), Array.from({ length: last + 1 }, (_, k) => k), `${last}`);
    assert.deepEqual(order.slice(0, 2), [0, last]);
    // a frame on a grid of step 2^j comes before every frame on no grid coarser than 2^(j−1)
    const level = (k) => (k === 0 || k === last ? 99 : Math.log2(k & -k));
    for (let a = 2; a < order.length; a++) {
      for (let b = a + 1; b < order.length; b++) assert.ok(level(order[a]) >= level(order[b]), `${last}: ${order}`);
    }
  }
});
