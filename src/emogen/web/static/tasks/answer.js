// The categorise task's rules, free of the DOM (unit-tested with `node --test`): the labels
// offered and their keys, when an answer is complete, and the body of the answer step. The
// screen is tasks/categorise.js. Types come from the server's OpenAPI schema (../api-types.d.ts,
// generated).

/** @typedef {import("../api-types").components["schemas"]["SessionState"]} SessionState */
/** @typedef {import("../api-types").components["schemas"]["CategoriseView"]} CategoriseView */
/** @typedef {import("../api-types").components["schemas"]["Answer"]} AnswerBody */

/** The answer of "none of these" (where the block offers it). */
export const NONE = "none";

/**
 * An answer in progress: the label chosen and the ratings given (null: not yet).
 * @typedef {{ label: string | null, intensity: number | null, confidence: number | null }} Answer
 */

/** @returns {Answer} */
export function emptyAnswer() {
  return { label: null, intensity: null, confidence: null };
}

/**
 * A label as the participant reads it ("fearful" → "Fearful"; "none" → "None of these").
 * @param {string} label
 */
export function labelText(label) {
  if (label === NONE) return "None of these";
  const words = label.replace(/[_-]+/g, " ").trim();
  return words.charAt(0).toUpperCase() + words.slice(1);
}

/**
 * The buttons of a categorise trial, in the order the server drew: each label, then "none of
 * these" where offered; the first nine answer to the number keys 1-9.
 * @param {CategoriseView} view
 * @returns {{ label: string, text: string, key: string | null }[]}
 */
export function options(view) {
  const labels = view.none_option ? [...view.labels, NONE] : [...view.labels];
  return labels.map((label, i) => ({
    label,
    text: labelText(label),
    key: i < 9 ? String(i + 1) : null,
  }));
}

/**
 * The label a key press chooses ("1" → the first label shown), or null.
 * @param {CategoriseView} view
 * @param {string} key
 */
export function labelForKey(view, key) {
  const found = options(view).find((o) => o.key === key);
  return found ? found.label : null;
}

/**
 * Whether the intensity is asked for this answer ("none of these" names no expression whose
 * intensity could be rated).
 * @param {CategoriseView} view
 * @param {Answer} answer
 */
export function asksIntensity(view, answer) {
  return view.intensity !== null && answer.label !== NONE;
}

/**
 * Whether a label press sends the answer at once (no rating asked).
 * @param {CategoriseView} view
 */
export function answersAtOnce(view) {
  return view.intensity === null && view.confidence === null;
}

/**
 * Whether the answer can be sent: a label, and every rating the block asks.
 * @param {CategoriseView} view
 * @param {Answer} answer
 */
export function complete(view, answer) {
  if (answer.label === null) return false;
  if (asksIntensity(view, answer) && answer.intensity === null) return false;
  return view.confidence === null || answer.confidence !== null;
}

/**
 * What is still missing, in words for the participant ("" when complete).
 * @param {CategoriseView} view
 * @param {Answer} answer
 */
export function missing(view, answer) {
  if (answer.label === null) {
    return answersAtOnce(view) ? "Choose the emotion the face shows." : "First choose the emotion the face shows.";
  }
  const left = [];
  if (asksIntensity(view, answer) && answer.intensity === null) left.push("how intense it is");
  if (view.confidence !== null && answer.confidence === null) left.push("how sure you are");
  return left.length ? `Now say ${left.join(" and ")}, then press Continue.` : "";
}

/**
 * The categorise view of a state in a categorise trial.
 * @param {SessionState} state
 * @returns {CategoriseView}
 */
export function categoriseView(state) {
  const view = state.view;
  if (!state.trial || !view || view.task !== "categorise") throw new Error("not a categorise trial's state");
  return view;
}

/**
 * The body of the answer step for the trial shown in ``state``.
 * @param {SessionState} state
 * @param {Answer} answer
 * @param {string} key
 * @param {number} responseMs faces drawn → answer sent
 * @param {number} [loadMs] the page's time from receiving the face to drawing it
 * @returns {AnswerBody}
 */
export function answerBody(state, answer, key, responseMs, loadMs) {
  const view = categoriseView(state);
  if (!complete(view, answer) || answer.label === null) {
    throw new Error("an answer needs a categorise trial and a complete answer");
  }
  return {
    command: "answer",
    key,
    trial: state.progress.trial,
    label: answer.label,
    intensity: asksIntensity(view, answer) ? answer.intensity : null,
    confidence: view.confidence === null ? null : answer.confidence,
    response_ms: responseMs,
    ...(loadMs === undefined ? {} : { load_ms: loadMs }),
  };
}
