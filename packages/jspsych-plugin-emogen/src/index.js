// jsPsych 8 plugin: an EmoGen trial — an evolve trial (one GA trial of a study block: the ten
// faces, the selections, "Start again", generation after generation, the rating) or a
// categorise trial (one face, one label) — run by the study server, shown by the study page's
// own components. See README.md and docs/jspsych.md.
import { ParameterType } from "jspsych";
import { serverBase, studyInfo } from "./connect.js";
import { observerDriver, targetVector } from "./driver.js";
import { simulateCategorise, simulateEvolve } from "./observer.js";
import { emptyData } from "./record.js";
import { runTrial } from "./run.js";

const VERSION = "0.1.0";
const generation = {
  attempt: { type: ParameterType.INT },
  generation: { type: ParameterType.INT },
  shown: { type: ParameterType.INT, array: true },
  elite: { type: ParameterType.INT },
  others: { type: ParameterType.INT, array: true },
  rt: { type: ParameterType.INT },
  load_ms: { type: ParameterType.INT },
};

const info = /** @type {const} */ ({
  name: "emogen",
  version: VERSION,
  parameters: {
    /** The study server's address (``https://study.example.org``); its study config must list
     * this page's origin in ``embed_origins``. */
    server: { type: ParameterType.STRING, default: undefined },
    /** ``evolve`` or ``categorise``: the study's next trial must be of this task. */
    task: { type: ParameterType.SELECT, options: ["evolve", "categorise"], default: "evolve" },
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
  data: {
    task: { type: ParameterType.STRING },
    /** false: the trial could not run; ``reason`` says why, ``failure`` names the kind
     * (unreachable, origin, block, server, finished). */
    success: { type: ParameterType.BOOL },
    reason: { type: ParameterType.STRING },
    failure: { type: ParameterType.STRING },
    simulated: { type: ParameterType.BOOL },
    server: { type: ParameterType.STRING },
    study: { type: ParameterType.STRING },
    /** The researcher's session id: ``session_id`` in every table of ``emogen study export``. */
    session_id: { type: ParameterType.INT },
    participant_id: { type: ParameterType.STRING },
    /** The trial's position in the session (``trial`` in the export), its block and name. */
    trial: { type: ParameterType.INT },
    block: { type: ParameterType.INT },
    block_name: { type: ParameterType.STRING },
    emotion: { type: ParameterType.STRING },
    identity: { type: ParameterType.STRING },
    display: { type: ParameterType.STRING },
    /** The trial's and the session's seeds (decimal strings: 64-bit integers). */
    seed: { type: ParameterType.STRING },
    session_seed: { type: ParameterType.STRING },
    attempt: { type: ParameterType.INT },
    generations: { type: ParameterType.COMPLEX, array: true, nested: generation },
    restarts: { type: ParameterType.COMPLEX, array: true },
    rating: { type: ParameterType.INT },
    rating_rt: { type: ParameterType.INT },
    labels: { type: ParameterType.STRING, array: true },
    label: { type: ParameterType.STRING },
    intensity: { type: ParameterType.INT },
    confidence: { type: ParameterType.INT },
    response_rt: { type: ParameterType.INT },
    load_ms: { type: ParameterType.INT },
    /** The final face (evolve: the last best face; categorise: the face shown): its id and its
     * weights in the study's weight order (GET /api/study: weight_names). */
    final_face_id: { type: ParameterType.INT },
    final_weights: { type: ParameterType.FLOAT, array: true },
    /** Trial start → first faces drawn (ms), and the whole trial's duration. */
    first_faces_ms: { type: ParameterType.INT },
    rt: { type: ParameterType.INT },
  },
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
   * ``data-only``: the simulated observer against a stand-in GA, no server (options: target —
   * an array, or weights by name —, generations, chosen, noise, seed; categorise: labels,
   * prototypes, label). ``visual``: the observer at the real trial, against the server.
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
    const seed = options.seed ?? 1;
    if (trial.task === "categorise") {
      Object.assign(data, simulateCategorise({ ...options, seed }));
    } else {
      const target = Array.isArray(options.target) ? options.target : Object.values(options.target ?? SMILE);
      Object.assign(data, simulateEvolve({ ...options, target, seed }));
      data.rating = options.rating ?? null;
    }
    data.rt = data.task === "categorise" ? data.response_rt : data.generations.reduce((t, g) => t + g.rt, 0);
    return this.jsPsych.pluginAPI.mergeSimulationData(data, options);
  }
}

export default EmogenPlugin;
export { VERSION };
