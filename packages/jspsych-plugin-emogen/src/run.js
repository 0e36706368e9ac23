// One emogen trial inside a jsPsych page: the study page's own task component (found by the
// task registry, static/tasks/index.js) over the same face display, given the context the study
// page's shell gives it (static/session.js: `page`), against the study server's one step route.
// The trial ends when the server's session moves past it; what was shown and chosen, and the
// trial's record (session id, seeds, its task's result), are its data. A failure ends it with
// success false and the reason, said in the page — never a trial that waits for ever.
import { newKey } from "../../../src/emogen/web/static/api.js";
import { statusText } from "../../../src/emogen/web/static/connection.js";
import { createFaceDisplay } from "../../../src/emogen/web/static/faces.js";
import { screenPrompt } from "../../../src/emogen/web/static/progress.js";
import { SCREENS, TASK_VIEWS, taskOf } from "../../../src/emogen/web/static/tasks/index.js";
import { STATUS_LINES } from "../../../src/emogen/web/static/tasks/markup.js";
import { createDrawFaces, fillScale } from "../../../src/emogen/web/static/tasks/shell.js";
import { createViewerDisplay } from "../../../src/emogen/web/static/viewer-adapter.js";
import { TrialFailure, participantFromUrl, request, session, studyInfo } from "./connect.js";
import { emptyData, recordStep, withRecord } from "./record.js";

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
      <h2>This part of the experiment could not run</h2>
      <p id="failed-reason"></p>
      <p class="muted">The researcher's data say what happened. Press Continue to go on with the experiment.</p>
      <div class="actions-row"><button id="failed-continue" class="primary" type="button">Continue</button></div>
    </section>
    ${STATUS_LINES}
  </div>
</div>`;
const VIEWS = ["loading", ...SCREENS, "failed"];

/**
 * Runs one trial; resolves with its data (never rejects).
 * @param {{ element: HTMLElement, params: any, base: string, onLoad?: () => void,
 *   driver?: (view: string, state: any, root: HTMLElement) => void }} options
 */
export async function runTrial({ element, params, base, onLoad = () => {}, driver }) {
  element.innerHTML = SHELL;
  const root = /** @type {HTMLElement} */ (element.querySelector(".emogen-trial"));
  const $ = (id) => /** @type {any} */ (root.querySelector(`#${id}`));
  const abort = new AbortController();
  const started = performance.now();
  const data = emptyData(params.task, base);
  const ui = {
    state: /** @type {any} */ (null), display: /** @type {any} */ (null), shownAt: 0,
    receivedAt: started, loadMs: 0, key: null, busy: false, loading: false,
    link: /** @type {any} */ ({ kind: "online" }), linkTimer: 0, said: "", ready: false, stage: "loading",
  };
  let finish = (/** @type {any} */ _outcome) => {};
  const finished = new Promise((resolve) => (finish = resolve));
  let loaded = false;

  const show = (view) => {
    for (const v of VIEWS) $(`view-${v}`).hidden = v !== view;
    ui.stage = view;
    root.dataset.emogenStage = view;
  };
  const setReady = (ready) => {
    ui.ready = ready;
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
    request(base, `/api/s/${data.token}${path}`, { retries: params.retries, onLink, ...options });

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
    elapsed: () => Math.max(0, Math.round(performance.now() - ui.shownAt)),
    step: (body) => step(body),
  };

  /** Shows ``state`` if it is still this trial; else the trial is over. */
  async function render(state) {
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

  /** One step (its body names the command), sent to the one step route. */
  async function step(body) {
    if (ui.busy) return;
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
      // the page was out of date (a double submission): show the server's state
      try {
        await render(await call("/state"));
      } catch (again) {
        finish({ ok: false, error: again });
      }
    }
  }

  let component = /** @type {any} */ (null);
  const outcome = await (async () => {
    try {
      await start();
      return await finished;
    } catch (err) {
      return { ok: false, error: err };
    }
  })();

  async function start() {
    show("loading");
    const info = await studyInfo(base, params.retries);
    data.study = info.name;
    const blocks = info.blocks.filter((b) => b.task === params.task);
    if (!blocks.length) {
      const have = info.blocks.map((b) => `${b.name} (${b.task})`).join(", ");
      throw new TrialFailure(
        `the study '${info.name}' has no ${params.task} block (its blocks: ${have})`,
        "block",
      );
    }
    const participant = params.participant_id ?? participantFromUrl(params.participant_param ?? info.participant_param);
    const made = await session(base, participant, { retries: params.retries, onLink });
    data.token = page.token = made.token;
    // the state the session was made with, for its first trial; the server's now, after that
    let state = made.used ? await call("/state") : made.state;
    made.used = true;
    if (state.stage === "instructions") {
      state = await call("/step", { method: "POST", body: { command: "begin", key: newKey() } });
    }
    data.participant_id = state.participant_id;
    if (state.stage === "done") {
      throw new TrialFailure("this participant's session of the study is complete: it has no trial left", "finished");
    }
    if (state.trial.task !== params.task) {
      throw new TrialFailure(
        `the study's next trial (trial ${state.progress.trial + 1} of ${state.progress.trials}) is a ${state.trial.task} trial, not ${params.task}: order the experiment's emogen trials as the study's blocks`,
        "block",
      );
    }
    data.trial = state.trial.position;
    const png = params.render === "png";
    ui.display = await createFaceDisplay({
      token: made.token,
      base,
      loadViewer: async () => (png ? null : createViewerDisplay({ base, framing: info.framing })),
    });
    data.display = ui.display.kind;
    component = taskOf(params.task).create(page);
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
    await showFailure(data.reason);
  }
  abort.abort();
  clearInterval(ui.linkTimer);
  if (ui.display) ui.display.dispose();
  data.rt = Math.round(performance.now() - started);
  delete data.token; // the session's secret stays out of the experiment's data
  return data;

  /** The reason said in the page until Continue (or ``failure_wait_ms``, if set). */
  function showFailure(reason) {
    $("failed-reason").textContent = `${reason.charAt(0).toUpperCase()}${reason.slice(1)}.`;
    $("prompt").textContent = "";
    $("gen-progress").textContent = "";
    show("failed");
    ui.state = null;
    if (!loaded) onLoad();
    return new Promise((resolve) => {
      $("failed-continue").addEventListener("click", () => resolve(undefined), { once: true });
      if (params.failure_wait_ms !== null) setTimeout(resolve, params.failure_wait_ms);
      if (driver) driver("failed", null, root);
    });
  }
}

