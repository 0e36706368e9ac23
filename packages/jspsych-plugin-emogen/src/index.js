// jsPsych 8 plugin: an EmoGen trial — one trial of a study block, of the task the block runs
// (the registry's tasks: static/tasks/index.js; an evolve trial is one GA trial — the ten faces,
// the selections, "Start again", generation after generation, the rating; a categorise trial
// one face, one label) — run by the study server, shown by the study page's own components.
// See README.md and docs/jspsych.md.
import { ParameterType } from "jspsych";
import { TASK_NAMES, taskOf } from "../../../src/emogen/web/static/tasks/index.js";
import { serverBase, studyInfo } from "./connect.js";
import { observerDriver, targetVector } from "./driver.js";
import { DATA_FIELDS, emptyData } from "./record.js";
import { runTrial } from "./run.js";

const VERSION = "0.1.0";

/**
 * A data field in jsPsych's terms (its type from ParameterType by name, nested fields too).
 * @param {import("./record.js").Field} field
 * @returns {any}
 */
function declared({ type, array, nested }) {
  const out = /** @type {any} */ ({ type: /** @type {any} */ (ParameterType)[type] });
  if (array) out.array = true;
  if (nested) out.nested = Object.fromEntries(Object.entries(nested).map(([k, f]) => [k, declared(f)]));
  return out;
}

const info = /** @type {const} */ ({
  name: "emogen",
  version: VERSION,
  parameters: {
    /** The study server's address (``https://study.example.org``); its study config must list
     * this page's origin in ``embed_origins``. */
    server: { type: ParameterType.STRING, default: undefined },
    /** The task of the trial (a task of the registry, static/tasks/index.js): the study's next
     * trial must be of this task. */
    task: { type: ParameterType.SELECT, options: TASK_NAMES, default: TASK_NAMES[0] },
    /** The participant id; null: from the URL (the study's participant_param, e.g.
     * PROLIFIC_PID, else ``participant``; JATOS: the study link's query), else one is made. */
    participant_id: { type: ParameterType.STRING, default: null },
    /** The URL parameter with the participant id; null: the study config's. */
    participant_param: { type: ParameterType.STRING, default: null },
    /** ``auto`` (3D viewer where WebGL 2 works, else the server's images) or ``png``. */
    render: { type: ParameterType.SELECT, options: ["auto", "png"], default: "auto" },
    /** How often a lost connection or busy answer is retried (1, 2, 4 … s apart) before the
     * trial ends as failed. */
    retries: { type: ParameterType.INT, default: 3 },
    /** After a failure the page says why until Continue is pressed, or this many ms (null: until
     * Continue). */
    failure_wait_ms: { type: ParameterType.INT, default: null },
  },
  /** Every trial's fields and each task's own (record.js; tasks/<task>.js: ``data``). */
  data: Object.fromEntries(Object.entries(DATA_FIELDS).map(([name, field]) => [name, declared(field)])),
});

/** The default target of simulate(): a smile (ICT-FaceKit's shape names). */
const SMILE = { mouthSmile_L: 0.8, mouthSmile_R: 0.8, cheekSquint_L: 0.4, cheekSquint_R: 0.4 };

class EmogenPlugin {
  static info = info;

  /** @param {any} jsPsych */
  constructor(jsPsych) {
    this.jsPsych = jsPsych;
  }

  /**
   * @param {HTMLElement} display_element
   * @param {any} trial
   * @param {() => void} on_load
   */
  trial(display_element, trial, on_load) {
    return this.run(display_element, trial, on_load);
  }

  /** @param {HTMLElement} element @param {any} trial @param {() => void} onLoad @param {any} [driver] */
  async run(element, trial, onLoad, driver) {
    let base;
    try {
      base = serverBase(trial.server);
    } catch (err) {
      onLoad();
      return { ...emptyData(trial.task, String(trial.server)), success: false, failure: "server", reason: /** @type {Error} */ (err).message, token: undefined };
    }
    return runTrial({ element, params: trial, base, onLoad, driver });
  }

  /**
   * ``data-only``: the simulated observer without a server, as the trial's task simulates it
   * (tasks/<task>.js: ``simulate``; evolve: a stand-in GA — options target, an array or weights
   * by name, generations, chosen, noise, seed; categorise: labels, prototypes, face). ``visual``:
   * the observer at the real trial, against the server.
   * @param {any} trial
   * @param {"data-only" | "visual"} mode
   * @param {any} options
   * @param {() => void} load
   */
  async simulate(trial, mode, options = {}, load = () => {}) {
    if (mode === "visual") {
      const base = serverBase(trial.server);
      const names = (await studyInfo(base, trial.retries)).weight_names;
      const driver = observerDriver({ ...options, target: targetVector(options.target ?? SMILE, names) });
      return this.run(this.jsPsych.getDisplayElement(), trial, load, driver);
    }
    load();
    const data = { ...emptyData(trial.task, String(trial.server)), simulated: true, token: undefined };
    delete data.token;
    Object.assign(data, taskOf(trial.task).simulate({ ...options, target: options.target ?? SMILE, seed: options.seed ?? 1 }));
    return this.jsPsych.pluginAPI.mergeSimulationData(data, options);
  }
}

export default EmogenPlugin;
export { VERSION };
