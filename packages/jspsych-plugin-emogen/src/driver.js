// simulate()'s visual mode: a simulated observer at the real trial's screens, against the
// study server. It reads the faces the screen shows (their weights, from the server's state),
// clicks the nearest to its target as the best face and the next ones as also acceptable, and
// presses the buttons a participant would (the same clicks, so the server records the same).
import { choose } from "./observer.js";

/**
 * The target as a weight vector in the study's weight order: an array as given, or an object
 * naming weights (``{ mouthSmile_L: 0.8 }``, names as GET /api/study lists them; others 0).
 * @param {number[] | Record<string, number>} target
 * @param {string[]} names
 */
export function targetVector(target, names) {
  if (Array.isArray(target)) return target;
  const unknown = Object.keys(target).filter((k) => !names.includes(k));
  if (unknown.length) throw new Error(`simulation target names weights the study does not have: ${unknown.join(", ")}`);
  return names.map((n) => target[n] ?? 0);
}

const later = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

/**
 * The driver runTrial calls whenever a screen is ready.
 * @param {{ target: number[], chosen?: number, noise?: number, rating?: number, label?: string,
 *   delay_ms?: number }} options
 */
export function observerDriver({ target, chosen = 3, noise = 0, rating, label, delay_ms = 200 }) {
  const click = (/** @type {Element | null} */ el) => {
    if (el) /** @type {HTMLElement} */ (el).click();
  };
  const check = (/** @type {HTMLElement} */ root, /** @type {string} */ scale, /** @type {number} */ value) => {
    const inputs = root.querySelectorAll(`#${scale} input`);
    const input = /** @type {HTMLInputElement | undefined} */ (inputs[Math.min(inputs.length, value) - 1]);
    if (!input) return;
    input.checked = true;
    input.dispatchEvent(new Event("change", { bubbles: true }));
  };
  return async (/** @type {string} */ view, /** @type {any} */ state, /** @type {HTMLElement} */ root) => {
    await later(delay_ms);
    if (view === "trial") {
      const { min_selections: min, max_selections: max } = state.limits;
      const n = Math.min(max, Math.max(min, chosen));
      const pick = choose(state.population.faces, target, n, { noise });
      for (const id of [pick.elite, ...pick.others]) click(root.querySelector(`#grid > .cell[data-face="${id}"] .face`));
      click(root.querySelector("#next"));
    } else if (view === "rating") {
      check(root, "rating-scale", rating ?? Math.ceil(0.7 * state.rating.points));
      click(root.querySelector("#rate"));
    } else if (view === "categorise") {
      const buttons = Array.from(root.querySelectorAll("#label-buttons button"));
      const wanted = buttons.find((b) => /** @type {HTMLElement} */ (b).dataset.label === label) ?? buttons[0];
      click(wanted);
      const middle = (/** @type {any} */ s) => Math.ceil(s.points / 2);
      if (state.categorise.intensity && !root.querySelector("#intensity-set")?.hasAttribute("hidden")) {
        check(root, "intensity-scale", middle(state.categorise.intensity));
      }
      if (state.categorise.confidence) check(root, "confidence-scale", middle(state.categorise.confidence));
      const answer = /** @type {HTMLButtonElement | null} */ (root.querySelector("#answer"));
      if (answer && !answer.hidden && !answer.disabled) answer.click();
    } else if (view === "failed") {
      click(root.querySelector("#failed-continue"));
    }
  };
}
