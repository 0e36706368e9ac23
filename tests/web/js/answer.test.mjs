// Unit tests of the categorise screen's rules (src/emogen/web/static/answer.js) and of the
// view a categorise state shows (selection.js viewOf): `node --test tests/web/js/`.
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
} from "../../../src/emogen/web/static/answer.js";
import { viewOf } from "../../../src/emogen/web/static/selection.js";
import { sessionState } from "./states.mjs";

const scale = { question: "How intense?", points: 7, low_label: "weak", high_label: "strong" };

function view(over = {}) {
  return {
    question: "Which emotion?",
    face: { id: 0, weights: [0.1, 0.2] },
    labels: ["sad", "happy", "fearful"],
    none_option: false,
    intensity: null,
    confidence: null,
    ...over,
  };
}

function state(v) {
  return sessionState(
    {
      progress: { trial: 6, trials: 9, block: 2, blocks: 3, generation: 0, generations: 9 },
      allow_restart: true,
      categorise: v,
    },
    { position: 6, block: 2, task: "categorise", emotion: "", prompt: "Which emotion?", identity: "female-medium" },
  );
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
    key: "k1", trial: 6, label: "none", intensity: null, confidence: 2, response_ms: 812, load_ms: 40,
  });
  const plain = answerBody(state(view()), { label: "sad", intensity: 4, confidence: 4 }, "k2", 300);
  assert.deepEqual(plain, { key: "k2", trial: 6, label: "sad", intensity: null, confidence: null, response_ms: 300 });
  assert.throws(() => answerBody(state(v), emptyAnswer(), "k3", 1), /complete answer/);
});

test("a categorise trial's state shows the categorise view", () => {
  assert.equal(viewOf(state(view())), "categorise");
  assert.throws(() => viewOf(state(null)), /must carry its face/);
});
