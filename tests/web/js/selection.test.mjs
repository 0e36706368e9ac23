// Unit tests of the participant page's state handling (src/emogen/web/static/selection.js):
// `node --test tests/web/js/` (run by `make test`).
import assert from "node:assert/strict";
import { test } from "node:test";

import {
  complete,
  makeBest,
  restoreChoice,
  selectionBody,
  toggle,
  viewOf,
} from "../../../src/emogen/web/static/selection.js";

const limits = { min_selections: 2, max_selections: 3 };
const none = { elite: null, others: [] };

/** @param {Partial<import("../../../src/emogen/web/static/selection.js").SessionState>} over */
function state(over) {
  return {
    stage: "trial",
    participant_id: "p",
    progress: { trial: 1, trials: 4, generation: 2, generations: 9 },
    limits,
    allow_restart: true,
    trial: { position: 1, emotion: "joy", prompt: "Joy", identity: "generic", attempt: 1, status: "active" },
    population: null,
    rating: null,
    completion: null,
    ...over,
  };
}

test("the first click picks the best face, later clicks add others, a second click removes", () => {
  let c = toggle(none, 7, limits).choice;
  assert.deepEqual(c, { elite: 7, others: [] });
  c = toggle(c, 3, limits).choice;
  c = toggle(c, 5, limits).choice;
  assert.deepEqual(c, { elite: 7, others: [3, 5] });
  assert.deepEqual(toggle(c, 3, limits).choice, { elite: 7, others: [5] });
  assert.deepEqual(toggle(c, 7, limits).choice, { elite: null, others: [3, 5] });
});

test("a click beyond the maximum is refused and changes nothing", () => {
  const full = { elite: 1, others: [2, 3] };
  const { choice, refused } = toggle(full, 4, limits);
  assert.equal(choice, full);
  assert.match(refused ?? "", /at most 3 faces/);
});

test("making a face the best keeps the former best among the others while there is room", () => {
  assert.deepEqual(makeBest({ elite: 1, others: [2] }, 3, limits).choice, { elite: 3, others: [1, 2] });
  assert.deepEqual(makeBest({ elite: 1, others: [2, 3] }, 3, limits).choice, { elite: 3, others: [1, 2] });
  assert.deepEqual(makeBest({ elite: 1, others: [2, 4] }, 3, limits).choice, { elite: 3, others: [2, 4] });
  assert.deepEqual(makeBest(none, 4, limits).choice, { elite: 4, others: [] });
});

test("a choice is complete with a best face and min..max faces", () => {
  assert.equal(complete({ elite: 1, others: [] }, limits), false);
  assert.equal(complete({ elite: 1, others: [2] }, limits), true);
  assert.equal(complete({ elite: null, others: [2, 3] }, limits), false);
});

test("a saved choice keeps only the faces shown now", () => {
  const ids = [10, 11, 12];
  assert.deepEqual(restoreChoice({ elite: 11, others: [10, 99, 11, 10] }, ids), { elite: 11, others: [10] });
  assert.deepEqual(restoreChoice({ elite: 99, others: "x" }, ids), { elite: null, others: [] });
  assert.deepEqual(restoreChoice(null, ids), { elite: null, others: [] });
});

test("the view follows the stage and the trial's status", () => {
  assert.equal(viewOf(state({ stage: "instructions", trial: null })), "instructions");
  assert.equal(viewOf(state({})), "trial");
  const rating = state({});
  if (rating.trial) rating.trial.status = "rating";
  assert.equal(viewOf(rating), "rating");
  assert.equal(viewOf(state({ stage: "done", trial: null })), "done");
  assert.throws(() => viewOf(state({ trial: null })), /must carry its trial/);
});

test("the select body names the generation shown", () => {
  const body = selectionBody(state({}), { elite: 4, others: [2] }, "key-12345678", 850);
  assert.deepEqual(body, {
    key: "key-12345678", trial: 1, attempt: 1, generation: 2, elite: 4, others: [2], response_ms: 850,
  });
  assert.throws(() => selectionBody(state({}), none, "k", 0), /best face/);
});

test("the select body carries the page's load time only when measured", () => {
  const body = selectionBody(state({}), { elite: 4, others: [] }, "key-12345678", 850, 1234);
  assert.equal(body.load_ms, 1234);
  assert.equal(body.response_ms, 850);
  const without = selectionBody(state({}), { elite: 4, others: [] }, "key-12345678", 850);
  assert.equal("load_ms" in without, false);
});
