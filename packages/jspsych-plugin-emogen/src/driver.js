// simulate()'s visual mode: a simulated observer at the real trial's screens, against the
// study server. Each task's component drives its own screens (tasks/<task>.js: `drive`): it
// reads what the screen shows (the faces' weights, from the server's state), chooses as the
// observer would and presses the buttons a participant would (the same clicks, so the server
// records the same).
import { taskOf } from "../../../src/emogen/web/static/tasks/index.js";

/**
 * The target as a weight vector in the study's weight order: an array as given, or an object
 * naming weights (``{ mouthSmile_L: 0.8 }``, names as GET /api/study lists them; others 0).
 * @param {number[] | Record<string, number>} target
 * @param {string[]} names
 */
export function targetVector(target, names) {
  if (Array.isArray(target)) {
    if (target.length === names.length) return target;
    throw new Error(`simulation target has ${target.length} weights; the study's faces have ${names.length} (GET /api/study: weight_names)`);
  }
  const unknown = Object.keys(target).filter((k) => !names.includes(k));
  if (unknown.length) throw new Error(`simulation target names weights the study does not have: ${unknown.join(", ")}`);
  return names.map((n) => target[n] ?? 0);
}

const later = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/**
 * What a task's driver may do at its screens: click an element (or the first a selector
 * finds), choose a point of a rating scale.
 * @param {HTMLElement} root
 */
function actions(root) {
  return {
    root,
    /** @param {string | Element | null | undefined} target */
    click(target) {
      const el = typeof target === "string" ? root.querySelector(target) : target;
      if (el) /** @type {HTMLElement} */ (el).click();
    },
    /** @param {string} scale the scale's id @param {number} value 1 … points */
    check(scale, value) {
      const inputs = root.querySelectorAll(`#${scale} input`);
      const input = /** @type {HTMLInputElement | undefined} */ (inputs[Math.min(inputs.length, value) - 1]);
      if (!input) return;
      input.checked = true;
      input.dispatchEvent(new Event("change", { bubbles: true }));
    },
  };
}

/**
 * The driver runTrial calls whenever a screen is ready (options: the target, and what each
 * task's driver reads: chosen, noise, rating, label …).
 * @param {{ target: number[], delay_ms?: number } & Record<string, any>} options
 */
export function observerDriver({ delay_ms = 200, ...options }) {
  return async (/** @type {string} */ screen, /** @type {any} */ state, /** @type {HTMLElement} */ root) => {
    await later(delay_ms);
    const act = actions(root);
    if (screen === "failed") act.click("#failed-continue");
    else taskOf(state.view.task).drive(screen, state, act, options);
  };
}
