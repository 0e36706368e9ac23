// jsPsych 8 plugin: an EmoGen trial — one trial of a study block, of the task the block runs
// (the registry's tasks: static/tasks/index.js; an evolve trial is one GA trial — the ten faces,
// the selections, "Start again", generation after generation, the rating; a categorise trial
// one face, one label) — run by the study server, shown by the study page's own components.
// See README.md and docs/jspsych.md.
import { ParameterType } from "jspsych";
import { TASK_NAMES } from "../../../src/emogen/web/static/tasks/index.js";
import { serverBase, studyInfo } from "./connect.js";
import { observerDriver, targetVector } from "./driver.js";
import { DATA_FIELDS, fieldName, namespaced } from "./record.js";
import { runTrial } from "./run.js";
import { SMILE, simulatedData } from "./simulate.js";

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
    /** The task the timeline expects (a task of the registry, static/tasks/index.js). The trial
     * runs the study's current trial (the server's order wins); where that is of another task,
     * the data and the console say so once. */
    task: { type: ParameterType.SELECT, options: TASK_NAMES, default: TASK_NAMES[0] },
    /** The participant id; null: from the URL (the study's participant_param, e.g.
     * PROLIFIC_PID, else ``participant``; JATOS: the study link's query), else one is made. */
    participant_id: { type: ParameterType.STRING, default: null },
    /** The URL parameter with the participant id; null: the study config's. */
    participant_param: { type: ParameterType.STRING, default: null },
    /** ``auto`` (3D viewer where WebGL 2 works, else the server's images) or ``png``. */
    render: { type: ParameterType.SELECT, options: ["auto", "png"], default: "auto" },
    /** One request's wait for an answer (ms) before it is tried again (a server or proxy that
     * takes the connection and never answers). */
    timeout_ms: { type: ParameterType.INT, default: 10_000 },
    /** A request's deadline (ms): a lost connection, a silent or busy server is retried (1, 2,
     * 4, 8 … s apart, with the same idempotency key) for this long, then the trial ends as
     * failed. Survives a server restart or a short outage. */
    patience_ms: { type: ParameterType.INT, default: 30_000 },
    /** Trial start → its faces drawn (ms, the 3D model's download included): past it, the trial
     * ends as failed (kind ``timeout``). */
    load_timeout_ms: { type: ParameterType.INT, default: 90_000 },
    /** After a failure the page says why until Continue is pressed, or this many ms (null: until
     * Continue). */
    failure_wait_ms: { type: ParameterType.INT, default: null },
  },
  /** Every trial's fields and each task's own (record.js; tasks/<task>.js: ``data``), named
   * ``emogen_<name>`` (``rt`` is jsPsych's own). */
  data: Object.fromEntries(Object.entries(DATA_FIELDS).map(([name, field]) => [fieldName(name), declared(field)])),
  // Inlined when the bundle is built; the paper EmoGen implements (README).
  citations: {
    apa: "Roubtsova, N., Parsons, M., Binetti, N., Mareschal, I., Viding, E., & Cosker, D. EmoGen: Quantifiable emotion generation and analysis for experimental psychology.",
    bibtex: "@article{roubtsova_emogen, title={EmoGen: Quantifiable Emotion Generation and Analysis for Experimental Psychology}, author={Roubtsova, Nadejda and Parsons, Martin and Binetti, Nicola and Mareschal, Isabelle and Viding, Essi and Cosker, Darren}}",
  },
});

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

  /**
   * The trial, run again while the participant presses "Try again" after a lost connection (it
   * then carries on where the server's session is; jsPsych gets one row: the runs' records of
   * the trial together, ``emogen_tries`` counting the runs).
   * @param {HTMLElement} element @param {any} trial @param {() => void} onLoad @param {any} [driver]
   */
  async run(element, trial, onLoad, driver) {
    let loaded = false;
    const loadOnce = () => {
      if (!loaded) onLoad();
      loaded = true;
    };
    let earlier = null;
    for (let tries = 1; ; tries++) {
      const run = await runTrial({ element, params: trial, onLoad: loadOnce, driver, simulated: driver !== undefined, tries, earlier });
      run.data.duration_ms += earlier ? earlier.duration_ms : 0; // the whole trial, every run
      if (!run.again) return namespaced(run.data);
      earlier = run.data;
    }
  }

  /**
   * ``data-only``: a simulated participant without a session (simulate.js): the study's trial at
   * this place in the timeline, from GET /api/study (or options ``study``: that answer, saved),
   * its data as the trial's task simulates it (tasks/<task>.js: ``simulate``; evolve: a stand-in
   * GA — options target, an array or weights by name, chosen, noise, rating; categorise: label,
   * prototypes, face), the session's ``seed`` (none: from jsPsych's seeded Math.random).
   * ``visual``: the observer at the real trial, against the server.
   * @param {any} trial
   * @param {"data-only" | "visual"} mode
   * @param {any} options
   * @param {() => void} load
   */
  async simulate(trial, mode, options = {}, load = () => {}) {
    if (mode === "visual") {
      const base = serverBase(trial.server);
      const timing = { timeoutMs: trial.timeout_ms, patienceMs: trial.patience_ms };
      const names = (await studyInfo(base, timing)).weight_names;
      const driver = observerDriver({ ...options, target: targetVector(options.target ?? SMILE, names) });
      return this.run(this.jsPsych.getDisplayElement(), trial, load, driver);
    }
    load();
    const data = await simulatedData(this.jsPsych, trial, options);
    return this.jsPsych.pluginAPI.mergeSimulationData(namespaced(data), options);
  }
}

export default EmogenPlugin;
export { VERSION };
