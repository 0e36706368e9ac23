// Unit tests of what the participant reads about where they are
// (src/emogen/web/static/progress.js): `node --test tests/web/js/`.
import assert from "node:assert/strict";
import { test } from "node:test";

import {
  roundText,
  screenPrompt,
  startsTrial,
  transitionText,
} from "../../../src/emogen/web/static/progress.js";
import { sessionState } from "./states.mjs";

const rating = { question: "How sad does this face look?", low_label: "not", high_label: "very", points: 7 };

const state = sessionState;

test("ga.generations = 10 reads as rounds 1 … 11, the count the study's G + 1 screens make", () => {
  const p = state().progress;
  assert.equal(roundText(p), "Round 1 of 11");
  assert.equal(roundText({ ...p, generation: 10 }), "Round 11 of 11");
  assert.doesNotMatch(roundText(p), /Generation/); // not "Generation 1 of 11" for generations = 10
});

test("the rating screen asks its own question, not the trial's prompt", () => {
  const rated = state({ rating }, { status: "rating" });
  assert.equal(screenPrompt(rated, "Study"), "How sad does this face look?");
  assert.equal(screenPrompt(state(), "Study"), "Make the face look SAD");
  assert.equal(screenPrompt(state({ stage: "done", trial: null }), "Study"), "Study");
  const cat = state({}, { task: "categorise", prompt: "Which emotion does this face show?" });
  assert.equal(screenPrompt(cat, "Study"), "Which emotion does this face show?");
});

test("a pause comes before each new trial, not between rounds, nor after a reload", () => {
  const first = state();
  const second = state({ progress: { ...first.progress, trial: 1 } }, { position: 1, emotion: "happy" });
  const instructions = state({ stage: "instructions", trial: null });
  assert.equal(startsTrial(instructions, first), true);
  assert.equal(startsTrial(state({ rating }, { status: "rating" }), second), true);
  assert.equal(startsTrial(first, state({ progress: { ...first.progress, generation: 1 } })), false);
  assert.equal(startsTrial(null, first), false); // a reload resumes at once
  assert.equal(startsTrial(second, state({ stage: "done", trial: null })), false);
  assert.equal(transitionText(second), "Trial 2 of 8 — next: HAPPY");
  const cat = state({}, { task: "categorise", emotion: "fear" });
  assert.equal(transitionText(cat), "Trial 1 of 8 — next: name the emotion"); // no answer given away
});
