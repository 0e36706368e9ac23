// What the participant reads about where they are (DOM-free, unit-tested with `node --test`):
// the screen a state shows, its heading, the progress line and the short pause between trials —
// the parts a trial's task decides asked of its component (tasks/index.js finds it by the
// view's task). Types come from the server's OpenAPI schema (api-types.d.ts, generated).

/** @typedef {import("./api-types").components["schemas"]["SessionState"]} SessionState */

/**
 * What the shared page asks of a trial's task component (tasks/<task>.js): the screen its state
 * shows, where the participant is within the trial (``step``: words for the progress line, or
 * null; ``within``: the share of the trial done, 0 … 1), the screen's own heading (null: the
 * trial's prompt) and what the pause before the trial announces.
 * @typedef {{
 *   screen: (state: SessionState) => string,
 *   progress: (state: SessionState) => { step: string | null, within: number },
 *   prompt: (state: SessionState) => string | null,
 *   upcoming: (state: SessionState) => string,
 * }} TaskPart
 */

/** How long the pause between trials shows before the next trial starts by itself (ms). */
export const TRANSITION_MS = 1200;

/**
 * The screen a state shows: the instructions, the trial's (its task says which), the end.
 * @param {SessionState} state
 * @param {TaskPart | null} task the trial's task component (null outside a trial)
 */
export function screenOf(state, task) {
  if (state.stage !== "trial") return state.stage;
  if (!state.trial || !state.view) throw new Error("a state in stage 'trial' must carry its trial and its view");
  if (!task) throw new Error(`this page cannot show a '${state.view.task}' trial`);
  return task.screen(state);
}

/**
 * The heading of the screen: the task's own (a GA trial's rating asks its question), else the
 * trial's prompt; outside a trial, ``fallback``.
 * @param {SessionState} state
 * @param {string} fallback the heading outside a trial (the study's title)
 * @param {TaskPart | null} task
 */
export function screenPrompt(state, fallback, task) {
  const trial = state.stage === "trial" ? state.trial : null;
  if (!trial) return fallback;
  return (task && task.prompt(state)) || trial.prompt;
}

/**
 * The progress line and bar: "Trial 2 of 8", the task's step within it (else the part of the
 * study, where it has several), and the share of the study done.
 * @param {SessionState} state
 * @param {TaskPart | null} task
 * @returns {{ trial: string, detail: string, done: number }}
 */
export function progressOf(state, task) {
  const p = state.progress;
  const where = state.stage === "trial" && task ? task.progress(state) : null;
  let detail = "";
  if (where && where.step) detail = `· ${where.step}`;
  else if (where && p.blocks > 1) detail = `· Part ${p.block + 1} of ${p.blocks}`;
  const done = state.stage === "done" ? 1 : (p.trial + (where ? where.within : 0)) / p.trials;
  return { trial: `Trial ${p.trial + 1} of ${p.trials}`, detail, done: Math.min(1, done) };
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
 * What the pause before a trial says: "Trial 2 of 8 — next: SAD" (the task says what comes;
 * one that must not give its answer away says what to do: "next: name the emotion").
 * @param {SessionState} state
 * @param {TaskPart} task
 */
export function transitionText(state, task) {
  const p = state.progress;
  return `Trial ${p.trial + 1} of ${p.trials} — next: ${task.upcoming(state)}`;
}
