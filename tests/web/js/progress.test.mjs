// Unit tests of what the participant reads about where they are
// (src/emogen/web/static/progress.js): `node --test tests/web/js/`.
import assert from "node:assert/strict";
import { test } from "node:test";

import {
  progressOf,
  screenPrompt,
  startsTrial,
  transitionText,
} from "../../../src/emogen/web/static/progress.js";
import { taskOfState } from "../../../src/emogen/web/static/tasks/index.js";
import { categoriseState, sessionState } from "./states.mjs";

const rating = { question: "How sad does this face look?", low_label: "not", high_label: "very", points: 7 };

const state = sessionState;

const prompt = (s) => screenPrompt(s, "Study", taskOfState(s));
const next = (s) => transitionText(s, /** @type {any} */ (taskOfState(s)));

test("the progress line: the trial, the task's step (else the part of the study), the share done", () => {
  assert.deepEqual(progressOf(state(), taskOfState(state())), { trial: "Trial 1 of 8", detail: "· Round 1 of 11", done: 1 / 12 / 8 });
  const rated = state({}, { status: "rating" }, { generation: 10 });
  assert.equal(progressOf(rated, taskOfState(rated)).detail, "· Rating");
  const parts = { progress: { trial: 5, trials: 8, block: 1, blocks: 3 } };
  const cat = categoriseState({}, parts);
  assert.deepEqual(progressOf(cat, taskOfState(cat)), { trial: "Trial 6 of 8", detail: "· Part 2 of 3", done: 5 / 8 });
  const single = categoriseState({}, { progress: { ...parts.progress, blocks: 1 } });
  assert.equal(progressOf(single, taskOfState(single)).detail, "");
  const done = state({ stage: "done", trial: null, view: null, progress: { trial: 7, trials: 8, block: 0, blocks: 1 } });
  assert.deepEqual(progressOf(done, null), { trial: "Trial 8 of 8", detail: "", done: 1 });
});

test("the rating screen keeps the trial's prompt as its heading (its question is the scale's legend)", () => {
  const rated = state({}, { status: "rating" }, { rating });
  assert.equal(prompt(rated), "Make the face look SAD");
  assert.equal(prompt(state()), "Make the face look SAD");
  assert.equal(prompt(state({ stage: "done", trial: null, view: null })), "Study");
  const cat = categoriseState({}, {}, { prompt: "Which emotion does this face show?" });
  assert.equal(prompt(cat), "Which emotion does this face show?");
});

test("a pause comes before each new trial, not between rounds, nor after a reload", () => {
  const first = state();
  const second = state({ progress: { ...first.progress, trial: 1 } }, { position: 1 }, { emotion: "happy" });
  const instructions = state({ stage: "instructions", trial: null, view: null });
  assert.equal(startsTrial(instructions, first), true);
  assert.equal(startsTrial(state({}, { status: "rating" }, { rating }), second), true);
  assert.equal(startsTrial(first, state({}, {}, { generation: 1 })), false);
  assert.equal(startsTrial(null, first), false); // a reload resumes at once
  assert.equal(startsTrial(second, state({ stage: "done", trial: null, view: null })), false);
  assert.equal(next(second), "Trial 2 of 8 — next: HAPPY");
  const cat = categoriseState();
  assert.equal(next(cat), "Trial 1 of 8 — next: name the emotion"); // no answer given away
  assert.ok(!("emotion" in cat.view) && !("emotion" in cat.trial)); // nor does the state carry it
});
