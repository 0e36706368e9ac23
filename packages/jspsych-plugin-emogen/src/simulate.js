// simulate()'s data-only mode: a simulated participant's trial without a session. The study's
// blocks come from its server (GET /api/study) or are given (simulation option ``study``: that
// answer, saved), so a row is a real trial's: the study's trial at this place in the timeline
// (the server's order wins, as in a real trial), its block, and its task's data as the task
// simulates it from what the block shows (tasks/<task>.js: ``simulate``) — the same fields, types
// and lengths as a real row, ``emogen_simulated`` true.
import { taskOf } from "../../../src/emogen/web/static/tasks/index.js";
import { uniform } from "../../../src/emogen/web/static/observer.js";
import { TrialFailure, serverBase, studyInfo } from "./connect.js";
import { targetVector } from "./driver.js";
import { emptyData } from "./record.js";
import { followStudy } from "./run.js";

/** The default target: a smile (ICT-FaceKit's shape names). */
export const SMILE = { mouthSmile_L: 0.8, mouthSmile_R: 0.8, cheekSquint_L: 0.4, cheekSquint_R: 0.4 };

/** Each simulated session's seed, by jsPsych instance: one session per timeline. */
const sessionSeeds = new WeakMap();

/**
 * The study's trials in order: each one's block and place in it.
 * @param {any} study GET /api/study
 */
const trialsOf = (study) =>
  study.blocks.flatMap((/** @type {any} */ block) => Array.from({ length: block.trials }, (_, index) => ({ block, index })));

/**
 * One simulated trial's data (plain names; never rejects: a study that cannot be read is a
 * failed row, as in a real trial).
 * @param {any} jsPsych
 * @param {any} trial the trial's parameters
 * @param {any} options the simulation options (``seed``: the session's; none: drawn from
 *   Math.random, which jsPsych.randomization.setSeed seeds)
 * @returns {Promise<Record<string, any>>}
 */
export async function simulatedData(jsPsych, trial, options) {
  const data = { ...emptyData(trial.task, String(trial.server)), simulated: true };
  delete data.token;
  try {
    const timing = { timeoutMs: trial.timeout_ms, patienceMs: trial.patience_ms };
    const study = options.study ?? (await studyInfo(serverBase(trial.server), timing));
    // this trial's place: the emogen rows before it in this timeline's data
    const position = jsPsych.data.get().filter({ trial_type: "emogen" }).count();
    const trials = trialsOf(study);
    if (position >= trials.length) {
      throw new TrialFailure(`this participant's session of the study is complete: it has no trial left (the study has ${trials.length})`, "finished");
    }
    if (!sessionSeeds.has(jsPsych)) sessionSeeds.set(jsPsych, options.seed ?? Math.floor(Math.random() * 2 ** 31));
    const sessionSeed = sessionSeeds.get(jsPsych);
    const seed = Math.floor(uniform(sessionSeed + position)() * 2 ** 31);
    const { block, index } = trials[position];
    Object.assign(data, {
      study: study.name, session_id: 0, participant_id: trial.participant_id ?? "simulated",
      trial: position, block: block.block, block_name: block.name, task: block.task,
      display: "none", seed: String(seed), session_seed: String(sessionSeed), attempt: 0, first_faces_ms: 0,
    });
    followStudy(data, trial.task, trials.length);
    const names = study.weight_names;
    // the default smile: its weights the study's faces have (a face model without them: 0)
    const smile = Object.fromEntries(Object.entries(SMILE).filter(([name]) => names.includes(name)));
    const target = targetVector(options.target ?? smile, names);
    Object.assign(data, taskOf(block.task).simulate({ ...options, target, weight_names: names, shows: block.shows, index, seed }));
    data.duration_ms = data.rt;
  } catch (err) {
    data.success = false;
    data.failure = err instanceof TrialFailure ? err.kind : "error";
    data.reason = err instanceof Error ? err.message : String(err);
    console.error(`emogen: the simulated trial could not go on: ${data.reason}`);
  }
  return data;
}
