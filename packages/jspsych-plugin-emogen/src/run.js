// One emogen trial inside a jsPsych page: the study page's own task component (found by the
// task registry, static/tasks/index.js) over the same face display, given the context the study
// page's shell gives it (static/session.js: `page`), against the study server's one step route.
// The trial runs the session's current trial, whatever the timeline expected (the server's
// order wins: after a failure, a reload or a reopened link the next emogen trial carries on
// where the session is; a mismatch is reported to the researcher once, in the console and the
// data). It ends when the server's session moves past it; what was shown and chosen, and the
// trial's record (session id, seeds, its task's result), are its data. A failure ends it with
// success false and the researcher's reason in the data and console, the participant's words
// in the page — never a trial that waits for ever: every request has a deadline
// (``patience_ms``), and the faces must be drawn within ``load_timeout_ms`` of the start.
import { newKey } from "../../../src/emogen/web/static/api.js";
import { statusText } from "../../../src/emogen/web/static/connection.js";
import { createFaceDisplay } from "../../../src/emogen/web/static/faces.js";
import { screenPrompt } from "../../../src/emogen/web/static/progress.js";
import { SCREENS, TASK_VIEWS, taskOf } from "../../../src/emogen/web/static/tasks/index.js";
import { STATUS_LINES } from "../../../src/emogen/web/static/tasks/markup.js";
import { createDrawFaces, fillScale, responseClock } from "../../../src/emogen/web/static/tasks/shell.js";
import { createViewerDisplay } from "../../../src/emogen/web/static/viewer-adapter.js";
import { TrialFailure, participantFromUrl, request, serverBase, session, studyInfo } from "./connect.js";
import { carryOver, emptyData, recordStep, withRecord } from "./record.js";

const SHELL = `
<div class="emogen-trial" data-emogen-stage="loading">
  <header class="bar">
    <div class="progress" aria-live="polite"><span id="gen-progress">&nbsp;</span></div>
    <h1 id="prompt" class="prompt">&nbsp;</h1>
  </header>
  <div class="emogen-main">
    <section id="view-loading" class="view text-page"><p class="muted">Connecting to the study…</p></section>
    ${TASK_VIEWS}
    <section id="view-failed" class="view text-page" hidden>
      <h2 id="failed-heading">This part of the experiment could not go on</h2>
      <p id="failed-reason"></p>
      <p id="failed-next" class="muted">Press Continue to go on with the experiment.</p>
      <div class="actions-row">
        <button id="failed-retry" class="secondary" type="button" hidden>Try again</button>
        <button id="failed-continue" class="primary" type="button">Continue</button>
      </div>
    </section>
    ${STATUS_LINES}
  </div>
</div>`;
const VIEWS = ["loading", ...SCREENS, "failed"];

/** What the participant reads when a trial fails, by the failure's kind (the researcher's
 * reason is in the data and the console). */
const LOST = "The connection to the study was lost, so this part could not go on. What you did so far is saved; this is not your fault.";
const PARTICIPANT_WORDS = {
  unreachable: LOST,
  timeout: LOST,
  "other-tab": "You opened this experiment again in another tab or window, and it goes on there. Please close this tab.",
  other: "This part of the experiment could not be shown. This is not your fault: the researcher will see what happened.",
};

/** The failures a participant may try again (the connection back): the server keeps the
 * session, and the next run carries on where it is. */
const RETRIABLE = new Set(["unreachable", "timeout"]);

/** Said once per page in the browser's console (a study whose blocks differ from the timeline). */
const reported = new Set();
function reportOnce(text) {
  if (reported.has(text)) return;
  reported.add(text);
  console.warn(`emogen: ${text}`);
}

/** "a categorise", "an evolve". @param {string} word */
const article = (word) => (/^[aeiou]/i.test(word) ? `an ${word}` : `a ${word}`);

/**
 * Where the study's trial (``data.task``, ``data.trial``) is of another task than the timeline's
 * (``timelineTask``), the trial runs the study's: its data and the console say so (once).
 * @param {Record<string, any>} data @param {string} timelineTask @param {number} trials the study's
 */
export function followStudy(data, timelineTask, trials) {
  if (data.task === timelineTask) return;
  data.timeline_task = timelineTask;
  data.warning = `the study's current trial (trial ${data.trial + 1} of ${trials}) is ${article(data.task)} trial, where the timeline has ${article(timelineTask)} trial: it runs the study's trial (the study's order wins; order the timeline's emogen trials as the study's blocks)`;
  reportOnce(data.warning);
}

/**
 * Runs one trial; resolves with its data (plain names) and ``again``: the participant pressed
 * "Try again" after a lost connection (the caller runs it once more, ``tries`` + 1, ``earlier``
 * this run's data); never rejects.
 * @param {{ element: HTMLElement, params: any, onLoad?: () => void, tries?: number, earlier?: any,
 *   driver?: (view: string, state: any, root: HTMLElement) => void, simulated?: boolean }} options
 * @returns {Promise<{ data: Record<string, any>, again: boolean }>}
 */
export async function runTrial({ element, params, onLoad = () => {}, driver, simulated = false, tries = 1, earlier = null }) {
  element.innerHTML = SHELL;
  const root = /** @type {HTMLElement} */ (element.querySelector(".emogen-trial"));
  const $ = (id) => /** @type {any} */ (root.querySelector(`#${id}`));
  const abort = new AbortController();
  const started = performance.now();
  const timing = { timeoutMs: params.timeout_ms, patienceMs: params.patience_ms };
  const data = emptyData(params.task, String(params.server));
  data.simulated = simulated;
  data.tries = tries;
  let base = "";
  const ui = {
    state: /** @type {any} */ (null), display: /** @type {any} */ (null), shownAt: 0,
    receivedAt: started, loadMs: 0, key: null, busy: false, loading: false,
    link: /** @type {any} */ ({ kind: "online" }), linkTimer: 0, said: "", ready: false, stage: "loading",
  };
  let ended = false;
  let again = false;
  let finish = (/** @type {any} */ _outcome) => {};
  const finished = new Promise((resolve) => (finish = (outcome) => {
    ended = true;
    resolve(outcome);
  }));
  let loaded = false;

  const show = (view) => {
    for (const v of VIEWS) $(`view-${v}`).hidden = v !== view;
    ui.stage = view;
    root.dataset.emogenStage = view;
  };
  let answerable = false; // a screen has been ready for an answer (faces drawn or not)
  const setReady = (ready) => {
    ui.ready = ready;
    answerable ||= ready;
    root.dataset.emogenReady = ready ? "true" : "false";
    if (ready && driver && VIEWS.includes(ui.stage) && ui.state) driver(ui.stage, ui.state, root);
  };
  const paintLink = () => {
    $("message").textContent = statusText(ui.link, Date.now()) || ui.said;
  };
  const onLink = (link) => {
    ui.link = link;
    clearInterval(ui.linkTimer);
    if (link.kind !== "online") ui.linkTimer = setInterval(paintLink, 250);
    paintLink();
  };
  const say = (text) => {
    ui.said = text || "";
    if (ui.link.kind === "online") $("message").textContent = ui.said;
  };
  const call = (path, options = {}) =>
    request(base, `/api/s/${data.token}${path}`, { retries: Infinity, ...timing, onLink, ...options });

  const responseMs = responseClock(document, abort.signal);
  const page = {
    $, ui, token: "", show, say, setReady, signal: abort.signal,
    ready: () => ui.ready,
    stage: () => ui.stage,
    fillScale,
    drawFaces: createDrawFaces($, ui),
    facesShown() {
      ui.shownAt = performance.now();
      ui.loadMs = Math.max(0, Math.round(ui.shownAt - ui.receivedAt));
      if (data.first_faces_ms === null) data.first_faces_ms = Math.round(ui.shownAt - started);
      if (!loaded) {
        loaded = true;
        onLoad();
      }
    },
    elapsed: () => responseMs(ui.shownAt),
    step: (body) => step(body),
  };

  /** Shows ``state`` if it is still this trial; else the trial is over. */
  async function render(state) {
    if (ended) return;
    ui.receivedAt = performance.now();
    ui.state = state;
    if (state.stage !== "trial" || state.trial.position !== data.trial) {
      finish({ ok: true });
      return;
    }
    const task = taskOf(state.view.task);
    // the task's step within the trial ("Round 2 of 11"); the experiment says the rest
    $("gen-progress").textContent = task.progress(state).step ?? "";
    $("prompt").textContent = screenPrompt(state, state.trial.prompt, task);
    await component.render(state);
  }

  /** One step (its body names the command), sent to the one step route: retried with the
   * same body (its idempotency key) until the server answers or the deadline passes. */
  async function step(body) {
    if (ui.busy || ended) return;
    ui.busy = true;
    setReady(false);
    component.paint();
    try {
      const state = await call("/step", { method: "POST", body });
      recordStep(data, body, ui.state);
      ui.busy = false;
      say("");
      await render(state);
    } catch (err) {
      ui.busy = false;
      if (!(err instanceof TrialFailure && err.status === 409)) {
        finish({ ok: false, error: err });
        return;
      }
      // the page was out of date (a double submission, another device): the server's state
      try {
        await render(await call("/state"));
      } catch (again) {
        finish({ ok: false, error: again });
      }
    }
  }

  let component = /** @type {any} */ (null);
  let held = /** @type {any} */ (null);
  const takenOver = () =>
    finish({ ok: false, error: new TrialFailure("the participant's session was opened in another tab or window of this browser, which carries it on; this tab gave way", "other-tab") });
  const loadDeadline = setTimeout(() => {
    if (loaded || answerable) return;
    const seconds = params.load_timeout_ms / 1000;
    finish({ ok: false, error: new TrialFailure(`the trial's faces were not drawn within ${seconds} s of its start (load_timeout_ms)`, "timeout") });
  }, params.load_timeout_ms);
  const outcome = await (async () => {
    try {
      await Promise.race([start(), finished]);
      return await finished;
    } catch (err) {
      return { ok: false, error: err };
    }
  })();
  ended = true;
  clearTimeout(loadDeadline);
  if (held) held.listeners.delete(takenOver);

  async function start() {
    show("loading");
    base = serverBase(params.server);
    data.server = base;
    const info = await studyInfo(base, timing);
    data.study = info.name;
    if (!info.blocks.some((b) => b.task === params.task)) {
      const have = info.blocks.map((b) => `${b.name} (${b.task})`).join(", ");
      throw new TrialFailure(`the study '${info.name}' has no ${params.task} block (its blocks: ${have})`, "block");
    }
    const participant = params.participant_id ?? participantFromUrl(params.participant_param ?? info.participant_param);
    held = await session(base, participant, { ...timing, onLink, simulated });
    data.token = page.token = held.token;
    data.session_id = held.sessionId;
    if (held.takenOver) return takenOver();
    held.listeners.add(takenOver);
    // the state the session was made with, for its first trial; the server's now, after that
    let state = held.used ? await call("/state") : held.state;
    held.used = true;
    if (state.stage === "instructions") {
      state = await call("/step", { method: "POST", body: { command: "begin", key: newKey() } });
    }
    data.participant_id = state.participant_id;
    if (state.stage === "done") {
      throw new TrialFailure("this participant's session of the study is complete: it has no trial left", "finished");
    }
    data.trial = state.trial.position;
    data.task = state.trial.task;
    followStudy(data, params.task, state.progress.trials);
    carryOver(data, earlier);
    const png = params.render === "png";
    const display = await createFaceDisplay({
      token: held.token,
      base,
      loadViewer: async () => (png ? null : createViewerDisplay({ base, framing: info.framing })),
    });
    if (ended) return display.dispose();
    ui.display = display;
    data.display = display.kind;
    component = taskOf(state.trial.task).create(page);
    await render(state);
  }

  if (outcome.ok) {
    await call(`/trials/${data.trial}`).then(
      (record) => withRecord(data, record),
      (err) => (data.reason = `the trial is done, but its record could not be read: ${err.message}`),
    );
  } else {
    const err = outcome.error;
    data.success = false;
    data.failure = err instanceof TrialFailure ? err.kind : "error";
    data.reason = err instanceof Error ? err.message : String(err);
    console.error(`emogen: the trial could not go on: ${data.reason}`);
    // a session with no trial left ends the trial quietly: nothing went wrong for the participant
    if (data.failure !== "finished") again = (await showFailure(data.failure)) === "retry";
    else if (!loaded) onLoad();
  }
  abort.abort();
  clearInterval(ui.linkTimer);
  if (ui.display) ui.display.dispose();
  data.duration_ms = Math.round(performance.now() - started);
  delete data.token; // the session's secret stays out of the experiment's data
  return { data, again };

  /** The participant's words for a failure of ``kind``, until Continue (or ``failure_wait_ms``),
   * or "Try again" where the connection was lost: resolves with "retry" or "continue". */
  function showFailure(kind) {
    $("failed-reason").textContent = PARTICIPANT_WORDS[kind] ?? PARTICIPANT_WORDS.other;
    if (kind === "other-tab") {
      // nothing to continue here: the other tab has the session (and the experiment)
      $("failed-heading").textContent = "This experiment is open in another tab";
      $("failed-next").hidden = true;
      $("failed-continue").closest(".actions-row").hidden = true;
    }
    $("prompt").textContent = "";
    $("gen-progress").textContent = "";
    $("message").textContent = "";
    $("load-status").hidden = true;
    show("failed");
    ui.state = null;
    if (!loaded) onLoad();
    return new Promise((resolve) => {
      $("failed-continue").addEventListener("click", () => resolve("continue"), { once: true });
      if (RETRIABLE.has(kind)) {
        $("failed-retry").hidden = false;
        $("failed-next").textContent = "Press Try again once you are back online, or Continue to go on with the experiment.";
        $("failed-retry").addEventListener("click", () => resolve("retry"), { once: true });
      }
      if (params.failure_wait_ms !== null) setTimeout(() => resolve("continue"), params.failure_wait_ms);
      if (driver) driver("failed", null, root);
    });
  }
}
