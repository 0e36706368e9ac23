// Unit tests of the evolve task's rules (src/emogen/web/static/tasks/selection.js) and of what
// its component tells the shared page (tasks/evolve.js): `node --test tests/web/js/` (run by
// `make test`).
import assert from "node:assert/strict";
import { test } from "node:test";

import { screenOf } from "../../../src/emogen/web/static/progress.js";
import evolve from "../../../src/emogen/web/static/tasks/evolve.js";
import { TASKS, taskOf } from "../../../src/emogen/web/static/tasks/index.js";
import {
  complete,
  makeBest,
  restoreChoice,
  roundText,
  selectionBody,
  toggle,
} from "../../../src/emogen/web/static/tasks/selection.js";
import { sessionState } from "./states.mjs";

const limits = { min_selections: 2, max_selections: 3 };
const none = { elite: null, others: [] };

/** A GA trial's state: trial 1 of 4, its attempt 1, generation 2 of 9. */
function state(over = {}, trial = {}) {
  return sessionState(
    { progress: { trial: 1, trials: 4, block: 0, blocks: 1 }, ...over },
    { position: 1, prompt: "Joy", attempt: 1, ...trial },
    { emotion: "joy", generation: 2, generations: 9, limits, allow_restart: true },
  );
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

test("the screen follows the stage and the trial's status; the registry finds the component", () => {
  assert.equal(taskOf("evolve"), evolve);
  assert.equal(TASKS.evolve.name, "evolve");
  assert.throws(() => taskOf("gibbs"), /cannot show a 'gibbs' trial/);
  assert.equal(screenOf(state({ stage: "instructions", trial: null, view: null }), null), "instructions");
  assert.equal(screenOf(state(), evolve), "trial");
  assert.equal(screenOf(state({}, { status: "rating" }), evolve), "rating");
  assert.equal(screenOf(state({ stage: "done", trial: null, view: null }), null), "done");
  assert.throws(() => screenOf(state({ trial: null }), evolve), /must carry its trial/);
  assert.throws(() => screenOf(state(), null), /cannot show a 'evolve' trial/);
});

test("the round is the view's generation: ga.generations = 10 reads as rounds 1 … 11", () => {
  assert.equal(roundText({ generation: 0, generations: 10 }), "Round 1 of 11");
  assert.equal(roundText({ generation: 10, generations: 10 }), "Round 11 of 11");
  assert.doesNotMatch(roundText({ generation: 0, generations: 10 }), /Generation/);
  assert.deepEqual(evolve.progress(state()), { step: "Round 3 of 10", within: 3 / 11 });
  assert.equal(evolve.progress(state({}, { status: "rating" })).step, "Rating");
});

test("the select body names the generation shown", () => {
  const body = selectionBody(state(), { elite: 4, others: [2] }, "key-12345678", 850);
  assert.deepEqual(body, {
    command: "select", key: "key-12345678", trial: 1, attempt: 1, generation: 2, elite: 4, others: [2],
    response_ms: 850,
  });
  assert.throws(() => selectionBody(state(), none, "k", 0), /best face/);
  assert.throws(() => selectionBody(state({ view: null }), { elite: 4, others: [] }, "k", 0), /not an evolve/);
});

test("the select body carries the page's load time only when measured", () => {
  const body = selectionBody(state(), { elite: 4, others: [] }, "key-12345678", 850, 1234);
  assert.equal(body.load_ms, 1234);
  assert.equal(body.response_ms, 850);
  const without = selectionBody(state(), { elite: 4, others: [] }, "key-12345678", 850);
  assert.equal("load_ms" in without, false);
});

test("the plugin's data: a step recorded from its body and the view it answered; the result's face", () => {
  const data = { generations: [], restarts: [], rating: null, rating_rt: null };
  const faces = [{ id: 5, weights: [] }, { id: 6, weights: [] }];
  const view = { ...state().view, population: { attempt: 1, generation: 2, faces } };
  evolve.record(data, { command: "select", key: "k", trial: 1, attempt: 1, generation: 2, elite: 6, others: [5],
    response_ms: 700 }, view);
  evolve.record(data, { command: "restart", key: "k", trial: 1, attempt: 1, generation: 3, response_ms: 90 }, view);
  evolve.record(data, { command: "rate", key: "k", trial: 1, value: 6, response_ms: 400 }, view);
  assert.deepEqual(data, {
    generations: [{ attempt: 1, generation: 2, shown: [5, 6], elite: 6, others: [5], rt: 700, load_ms: null }],
    restarts: [{ attempt: 1, generation: 3, rt: 90 }], rating: 6, rating_rt: 400,
  });
  const final = { id: 12, weights: [0.5] };
  assert.deepEqual(evolve.result({ task: "evolve", emotion: "joy", final_face: final }),
    { emotion: "joy", final_face_id: 12, final_weights: [0.5] });
  assert.deepEqual(evolve.result({ task: "evolve", emotion: "joy", final_face: null }),
    { emotion: "joy", final_face_id: null, final_weights: null });
});
