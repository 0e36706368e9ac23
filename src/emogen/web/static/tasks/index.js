// The registry of the page's tasks: a trial's view names its task (``view.task``, as the server's
// task registry does), and the shells — the study's page (static/session.js) and the jsPsych
// plugin (packages/jspsych-plugin-emogen) — find its component here and nowhere else. A new task
// adds its module (tasks/<task>.js: see ./evolve.js's header for what a component gives) and
// its line below.
import categorise from "./categorise.js";
import evolve from "./evolve.js";
import gsp from "./gsp.js";

/** view.task → the task's component. */
export const TASKS = Object.freeze(Object.fromEntries([evolve, categorise, gsp].map((task) => [task.name, task])));

/** The tasks' names, in the registry's order. */
export const TASK_NAMES = Object.keys(TASKS);

/**
 * The component of the task named ``name``.
 * @param {string} name
 */
export function taskOf(name) {
  if (!Object.prototype.hasOwnProperty.call(TASKS, name)) throw new Error(`this page cannot show a '${name}' trial`);
  return TASKS[name];
}

/**
 * The component of the trial a state shows (null outside a trial).
 * @param {any} state
 */
export function taskOfState(state) {
  return state && state.stage === "trial" && state.view ? taskOf(state.view.task) : null;
}

/** Every task's screens (their ids: view-<screen>), and their markup, inserted by the shells. */
export const SCREENS = Object.values(TASKS).flatMap((task) => task.screens);
export const TASK_VIEWS = Object.values(TASKS).map((task) => task.markup).join("\n");
