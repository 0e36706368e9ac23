// The trial's data, as jsPsych stores it: what the page showed and the participant chose, step
// by step (only steps the server accepted), and the trial's record from the server (the
// researcher's session id, the seeds, its task's result) — the same rows `emogen study export`
// writes, so the two can be joined on emogen_session_id and emogen_trial. The fields every
// trial has are here; each task adds its own (tasks/<task>.js: `data`, `record`, `result`).
// In jsPsych's data every field is namespaced, ``emogen_<name>`` (jsPsych's own ``rt`` aside):
// a lab's ``jsPsych.data.addProperties({ subject_id, study_id, session_id })`` (jsPsych's
// Prolific recipe) or a trial's ``data`` parameter cannot overwrite them.
import { TASKS, taskOf } from "../../../src/emogen/web/static/tasks/index.js";

/**
 * A data field: its jsPsych type by name (ParameterType's: STRING, INT …) and its value before
 * the trial; a task's fields have the same form.
 * @typedef {{ type: string, array?: boolean, nested?: Record<string, any>, value?: any }} Field
 */

/** @type {Record<string, Field>} the fields before the tasks' own */
const HEAD = {
  task: { type: "STRING", value: null },
  /** The timeline's task where the study's current trial, which the trial ran, is of another
   * (``warning`` then says so; null: they agree). */
  timeline_task: { type: "STRING", value: null },
  warning: { type: "STRING", value: null },
  /** false: the trial could not run; ``reason`` says why (for the researcher), ``failure``
   * names the kind (unreachable, timeout, origin, block, server, resume, other-tab, finished). */
  success: { type: "BOOL", value: true },
  reason: { type: "STRING", value: null },
  failure: { type: "STRING", value: null },
  simulated: { type: "BOOL", value: false },
  /** The trial's runs: more than 1 where the participant pressed "Try again" after a lost
   * connection (the row has every run's steps of the trial; its outcome is the last run's). */
  tries: { type: "INT", value: 1 },
  server: { type: "STRING", value: null },
  study: { type: "STRING", value: null },
  /** The researcher's session id: ``session_id`` in every table of ``emogen study export``. */
  session_id: { type: "INT", value: null },
  participant_id: { type: "STRING", value: null },
  /** The trial's position in the session (``trial`` in the export), its block and name. */
  trial: { type: "INT", value: null },
  block: { type: "INT", value: null },
  block_name: { type: "STRING", value: null },
  identity: { type: "STRING", value: null },
  display: { type: "STRING", value: null },
  /** The trial's and the session's seeds (decimal strings: 64-bit integers). */
  seed: { type: "STRING", value: null },
  session_seed: { type: "STRING", value: null },
  attempt: { type: "INT", value: null },
};

/** @type {Record<string, Field>} the fields after the tasks' own */
const TAIL = {
  /** The trial's final face (its task's: the last best face; the face shown, whose id is null)
   * and its weights in the study's weight order (GET /api/study: weight_names). */
  final_face_id: { type: "INT", value: null },
  final_weights: { type: "FLOAT", array: true, value: null },
  /** Trial start → first faces drawn (ms), and the whole trial's duration. */
  first_faces_ms: { type: "INT", value: null },
  duration_ms: { type: "INT", value: null },
  /** jsPsych's meaning: the response time (ms) — the sum of the trial's responses' times, each
   * from its screen shown to the response (the loading of faces excluded); null: none. */
  rt: { type: "INT", value: null },
};

/** The field's name in jsPsych's data: ``emogen_<name>``; ``rt`` is jsPsych's own. @param {string} name */
export const fieldName = (name) => (name === "rt" ? name : `emogen_${name}`);

/**
 * The trial's data with jsPsych's names (see {@link fieldName}).
 * @param {Record<string, any>} data
 */
export function namespaced(data) {
  return Object.fromEntries(Object.entries(data).map(([name, value]) => [fieldName(name), value]));
}

/** Every data field of the plugin's trials: the shared ones and each task's, in that order. */
export const DATA_FIELDS = /** @type {Record<string, Field>} */ (
  Object.assign({}, HEAD, ...Object.values(TASKS).map((task) => task.data), TAIL)
);

/** A field's value before the trial (a fresh array where it is a list). @param {Field} field */
const initial = (field) => (Array.isArray(field.value) ? [...field.value] : (field.value ?? null));

/**
 * The data of a trial before it starts (a failed trial keeps what it had).
 * @param {string} task
 * @param {string} server
 * @returns {Record<string, any>}
 */
export function emptyData(task, server) {
  /** @type {Record<string, any>} */
  const data = Object.fromEntries(Object.entries(DATA_FIELDS).map(([name, field]) => [name, initial(field)]));
  data.task = task;
  data.server = server;
  data.token = undefined;
  return data;
}

/**
 * A step the server accepted, recorded by its task from its body and the state it answered.
 * @param {Record<string, any>} data
 * @param {any} body the step's body (its ``command`` names it)
 * @param {any} state the state the step answered (what the page showed)
 */
export function recordStep(data, body, state) {
  if (state && state.view) taskOf(state.view.task).record(data, body, state.view);
  if (typeof body.response_ms === "number") data.rt = (data.rt ?? 0) + body.response_ms;
}

/**
 * The server's record of the finished trial, added to its data (its task's result by its task).
 * @param {Record<string, any>} data
 * @param {any} record GET /api/s/{token}/trials/{n}
 */
export function withRecord(data, record) {
  Object.assign(data, {
    session_id: record.session_id,
    participant_id: record.participant_id,
    study: record.study,
    trial: record.trial,
    block: record.block,
    block_name: record.block_name,
    identity: record.identity,
    seed: record.seed,
    session_seed: record.session_seed,
    attempt: record.attempt,
  });
  if (record.result) Object.assign(data, taskOf(record.result.task).result(record.result));
  return data;
}

/**
 * A run after "Try again" of the same trial keeps what the earlier runs recorded (its task's
 * fields, the response time so far); a run that finds the session at another trial starts afresh.
 * @param {Record<string, any>} data the run's, its trial and task known
 * @param {Record<string, any> | null} earlier the earlier run's data (plain names)
 */
export function carryOver(data, earlier) {
  if (!earlier || earlier.trial !== data.trial || earlier.task !== data.task) return;
  for (const name of Object.keys(taskOf(data.task).data)) data[name] = earlier[name];
  data.rt = earlier.rt;
}
