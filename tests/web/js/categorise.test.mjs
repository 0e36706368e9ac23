// Unit tests of the categorise task's rules (src/emogen/web/static/tasks/answer.js) and of what
// its component tells the shared page and the plugin (tasks/categorise.js): `node --test tests/web/js/`.
import assert from "node:assert/strict";
import { test } from "node:test";

import {
  answerBody,
  answersAtOnce,
  complete,
  emptyAnswer,
  labelForKey,
  labelText,
  missing,
  options,
} from "../../../src/emogen/web/static/tasks/answer.js";
import { screenOf } from "../../../src/emogen/web/static/progress.js";
import categorise from "../../../src/emogen/web/static/tasks/categorise.js";
import { taskOf } from "../../../src/emogen/web/static/tasks/index.js";
import { categoriseState } from "./states.mjs";

const scale = { question: "How intense?", points: 7, low_label: "weak", high_label: "strong" };

function view(over = {}) {
  return categoriseState(over).view;
}

function state(v) {
  return categoriseState(v, { progress: { trial: 6, trials: 9, block: 2, blocks: 3 } },
    { position: 6, block: 2, identity: "female-medium" });
}

test("labels are offered in the server's order, 'none of these' last, keyed 1-9", () => {
  const o = options(view({ none_option: true }));
  assert.deepEqual(o.map((x) => [x.label, x.text, x.key]), [
    ["sad", "Sad", "1"], ["happy", "Happy", "2"], ["fearful", "Fearful", "3"],
    ["none", "None of these", "4"],
  ]);
  assert.equal(labelForKey(view(), "2"), "happy");
  assert.equal(labelForKey(view(), "4"), null); // no "none" offered
  assert.equal(labelForKey(view(), "0"), null);
  assert.equal(labelForKey(view(), "a"), null);
  assert.equal(labelText("very_surprised"), "Very surprised");
});

test("past nine labels, the rest have no key", () => {
  const labels = Array.from({ length: 11 }, (_, i) => `e${i}`);
  const o = options(view({ labels }));
  assert.equal(o[8].key, "9");
  assert.equal(o[9].key, null);
  assert.equal(labelForKey(view({ labels }), "10"), null);
});

test("an answer is complete with a label and every rating asked", () => {
  const v = view({ intensity: scale, confidence: scale, none_option: true });
  const a = emptyAnswer();
  assert.equal(complete(v, a), false);
  assert.match(missing(v, a), /First choose/);
  a.label = "happy";
  assert.equal(complete(v, a), false);
  assert.match(missing(v, a), /how intense it is and how sure you are/);
  a.intensity = 3;
  assert.match(missing(v, a), /how sure you are/);
  a.confidence = 7;
  assert.equal(complete(v, a), true);
  assert.equal(missing(v, a), "");
  // "none of these" names no expression: its intensity is not asked
  assert.equal(complete(v, { label: "none", intensity: null, confidence: 2 }), true);
  assert.equal(answersAtOnce(v), false);
  assert.equal(answersAtOnce(view()), true);
  assert.equal(complete(view(), { label: "sad", intensity: null, confidence: null }), true);
});

test("the body sends the ratings asked, and no intensity with 'none of these'", () => {
  const v = view({ intensity: scale, confidence: scale, none_option: true });
  const body = answerBody(state(v), { label: "none", intensity: 5, confidence: 2 }, "k1", 812, 40);
  assert.deepEqual(body, {
    command: "answer", key: "k1", trial: 6, label: "none", intensity: null, confidence: 2, response_ms: 812,
    load_ms: 40,
  });
  const plain = answerBody(state(view()), { label: "sad", intensity: 4, confidence: 4 }, "k2", 300);
  assert.deepEqual(plain, {
    command: "answer", key: "k2", trial: 6, label: "sad", intensity: null, confidence: null, response_ms: 300,
  });
  assert.throws(() => answerBody(state(v), emptyAnswer(), "k3", 1), /complete answer/);
});

test("a categorise trial's state shows the categorise screen, found by the registry", () => {
  const s = state(view());
  assert.equal(taskOf(s.view.task), categorise);
  assert.equal(screenOf(s, categorise), "categorise");
  assert.throws(() => screenOf({ ...s, view: null }, categorise), /must carry its trial and its view/);
  assert.throws(() => answerBody(categoriseState({}, { view: null }), { label: "sad", intensity: null, confidence: null }, "k", 1),
    /not a categorise trial/);
});

test("the plugin's data: the answer and the labels offered; the result's face has no id", () => {
  const v = view({ none_option: true, intensity: scale });
  const data = {};
  categorise.record(data, { command: "answer", key: "k", trial: 6, label: "happy", intensity: 3, confidence: null,
    response_ms: 812, load_ms: 40 }, v);
  assert.deepEqual(data, { labels: ["sad", "happy", "fearful", "none"], label: "happy", intensity: 3, confidence: null,
    response_rt: 812, load_ms: 40 });
  assert.deepEqual(categorise.result({ task: "categorise", label: "happy", weights: [0.1, 0.2] }),
    { label: "happy", final_face_id: null, final_weights: [0.1, 0.2] });
});
