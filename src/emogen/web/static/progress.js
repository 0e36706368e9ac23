// What the participant reads about where they are (DOM-free, unit-tested with `node --test`):
// the round of a GA trial, the prompt of the screen, and the short pause between trials.
// Types come from the server's OpenAPI schema (api-types.d.ts, generated).

/** @typedef {import("./api-types").components["schemas"]["SessionState"]} SessionState */
/** @typedef {import("./api-types").components["schemas"]["Progress"]} Progress */

/** How long the pause between trials shows before the next trial starts by itself (ms). */
export const TRANSITION_MS = 1200;

/**
 * The round of a GA trial: ``ga.generations = G`` breeds G generations after the first set
 * of faces, so the participant chooses in G + 1 rounds, generation g being round g + 1.
 * @param {Progress} p
 */
export function roundText(p) {
  return `Round ${p.generation + 1} of ${p.generations + 1}`;
}

/**
 * The heading of the screen: a GA trial's rating asks its own question (the study's
 * ``[rating] question``), every other screen shows the trial's prompt.
 * @param {SessionState} state
 * @param {string} fallback the heading outside a trial (the study's title)
 */
export function screenPrompt(state, fallback) {
  const trial = state.stage === "trial" ? state.trial : null;
  if (!trial) return fallback;
  if (trial.task === "evolve" && trial.status === "rating" && state.rating) return state.rating.question;
  return trial.prompt;
}

/**
 * Whether a new trial starts between the state shown (``before``; null: nothing shown yet, as
 * after a reload, which resumes without a pause) and the state arriving.
 * @param {SessionState | null} before
 * @param {SessionState} after
 */
export function startsTrial(before, after) {
  if (!before || after.stage !== "trial" || !after.trial) return false;
  return before.stage !== "trial" || before.progress.trial !== after.progress.trial;
}

/**
 * What the pause before a trial says: "Trial 2 of 8 — next: SAD" (a categorise trial does not
 * give its answer away: "next: name the emotion").
 * @param {SessionState} state
 */
export function transitionText(state) {
  const p = state.progress;
  const trial = state.trial;
  const next = trial && trial.task === "evolve" ? trial.emotion.toUpperCase() : "name the emotion";
  return `Trial ${p.trial + 1} of ${p.trials} — next: ${next}`;
}
