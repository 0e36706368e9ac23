// The participant's session: consent was given on the landing page; here the instructions,
// the trials of every block — each drawn by its task's component, found by the trial's view in
// the task registry (tasks/index.js) — and the completion. Every step goes to the one step
// route with an idempotency key and the page state always comes from the server, so a reload or
// a server restart resumes exactly.
import { api, ApiError, newKey } from "./api.js";
import { statusText } from "./connection.js";
import { createFaceDisplay } from "./faces.js";
import { progressOf, screenOf, screenPrompt, startsTrial, TRANSITION_MS, transitionText } from "./progress.js";
import { SCREENS, TASK_VIEWS, TASKS, taskOfState } from "./tasks/index.js";
import { STATUS_LINES } from "./tasks/markup.js";
import { createDrawFaces, fillScale, responseClock } from "./tasks/shell.js";

const token = document.body.dataset.token;
const $ = (id) => document.getElementById(id);
// the task components' screens (shared with the jsPsych plugin), before the components start
$("view-instructions").insertAdjacentHTML("afterend", TASK_VIEWS);
$("main").insertAdjacentHTML("beforeend", STATUS_LINES);
const views = ["loading", "instructions", "transition", ...SCREENS, "done"];

const ui = {
  state: null,
  display: null,
  shownAt: 0, // performance.now() when the current faces finished drawing
  // performance.now() when the answer holding the current faces arrived; the first faces this
  // page shows count from the page's start (0), so their load_ms includes page, model, textures
  receivedAt: /** @type {number | null} */ (null),
  loadMs: 0, // receivedAt → shownAt, reported with the step that answers these faces
  key: null, // idempotency key of the pending step
  busy: false,
  loading: false, // faces being fetched or drawn
  link: /** @type {import("./connection.js").Link} */ ({ kind: "online" }),
  linkTimer: 0,
  said: "", // the last message that was not about the connection
};
// Tests and the researcher's tools read this (loads: the face models the 3D display built, each
// with its timings; loadMs: the current screen's from its answer to its faces drawn; clipTimes:
// the clip time each face shown plays now; keptFrames: each face's frames kept ahead).
window.emogenStudy = {
  ready: false, stage: null, display: null, loads: [], loadMs: 0, shownAt: 0, clipTimes: () => [], keptFrames: () => [],
};

function setReady(ready) {
  window.emogenStudy.ready = ready;
  document.body.dataset.ready = ready ? "true" : "false";
}

function show(view) {
  for (const v of views) $(`view-${v}`).hidden = v !== view;
  window.emogenStudy.stage = view;
}

function say(text) {
  ui.said = text || "";
  if (ui.link.kind === "online") $("message").textContent = ui.said;
}

// ---- the connection: said at once, with a countdown to the next try ----------------------------
function paintLink() {
  const text = statusText(ui.link, Date.now());
  $("message").textContent = text || ui.said;
  document.body.dataset.link = ui.link.kind;
}

function onLink(link) {
  const wasOnline = ui.link.kind === "online";
  ui.link = link;
  clearInterval(ui.linkTimer);
  if (link.kind !== "online") {
    ui.linkTimer = setInterval(paintLink, 250);
  } else if (!wasOnline) {
    ui.said = "Connected again.";
    setTimeout(() => {
      if (ui.said === "Connected again.") say("");
    }, 4000);
  }
  paintLink();
}

/** Requests of the session: retried until the server answers. */
const call = (path, options = {}) => api(path, { retries: Infinity, onLink, ...options });

// ---- loading progress ------------------------------------------------------------------------
const draw = createDrawFaces($, ui, (done, total, unit) => {
  document.body.dataset.loaded = `${done}/${total} ${unit}`;
});

/**
 * The faces drawn; then, when the browser is idle, the next trial's face model made ahead
 * (display.prefetch: the 3D viewer's; it fails soft), so a new identity's first trial does not
 * wait for it.
 * @param {HTMLElement[]} slots @param {any[]} faces @param {string} identity
 */
async function drawFaces(slots, faces, identity) {
  await draw(slots, faces, identity);
  const next = ui.state?.trial?.next_identity;
  if (!next || !ui.display.prefetch) return;
  const later = window.requestIdleCallback ?? ((f) => setTimeout(f, 50));
  later(() => ui.display.prefetch(next), { timeout: 1000 });
}

// ---- progress -------------------------------------------------------------------------------
function renderProgress(state) {
  const task = taskOfState(state);
  const { trial, detail, done } = progressOf(state, task);
  $("trial-progress").textContent = trial;
  $("gen-progress").textContent = detail;
  $("meter-fill").style.width = `${Math.round(100 * done)}%`;
  $("prompt").textContent = screenPrompt(state, document.title, task);
}

// ---- what the task components share ---------------------------------------------------------
/** The faces of the current screen are drawn: the response-time clock starts now. */
function facesShown() {
  ui.shownAt = performance.now();
  ui.loadMs = Math.max(0, Math.round(ui.shownAt - (ui.receivedAt ?? 0)));
  window.emogenStudy.loadMs = ui.loadMs;
  window.emogenStudy.shownAt = ui.shownAt;
}

const responseMs = responseClock(document);
/** The response time of the input being handled: from the faces drawn to the click or key. */
function elapsed() {
  return responseMs(ui.shownAt);
}

const page = {
  $,
  ui,
  token,
  show,
  say,
  setReady,
  ready: () => window.emogenStudy.ready,
  stage: () => window.emogenStudy.stage,
  drawFaces,
  fillScale,
  facesShown,
  elapsed,
  step: (body) => step(body),
};
/** Each task's component, started in this page: view.task → {render, paint}. */
const components = Object.fromEntries(Object.entries(TASKS).map(([name, task]) => [name, task.create(page)]));
const componentOf = (state) => {
  const task = taskOfState(state);
  return task ? components[task.name] : null;
};

// ---- completion ------------------------------------------------------------------------------
function showDone(state) {
  const c = state.completion;
  $("done-message").textContent = c.message;
  if (c.code) {
    $("done-code").textContent = c.code;
    $("done-code-line").hidden = false;
  }
  if (c.redirect_url) {
    $("done-redirect").href = c.redirect_url;
    $("done-redirect-line").hidden = false;
    setTimeout(() => location.assign(c.redirect_url), 4000);
  }
  show("done");
  setReady(true);
}

// ---- the pause between trials: "Trial 2 of 8 — next: SAD", a tap or a key skips it -----------
function pause(state) {
  $("transition-text").textContent = transitionText(state, /** @type {any} */ (taskOfState(state)));
  show("transition");
  return new Promise((resolve) => {
    const done = () => {
      clearTimeout(timer);
      $("view-transition").removeEventListener("click", done);
      document.removeEventListener("keydown", done);
      resolve(undefined);
    };
    const timer = setTimeout(done, TRANSITION_MS);
    $("view-transition").addEventListener("click", done);
    document.addEventListener("keydown", done);
  });
}

// ---- state machine ---------------------------------------------------------------------------
async function render(state) {
  const before = ui.state;
  ui.state = state;
  renderProgress(state);
  if (startsTrial(before, state)) {
    await pause(state);
    ui.receivedAt = performance.now(); // the faces' load time starts after the pause
  } else {
    // the first faces this page draws count from the page's start (receivedAt stays 0)
    ui.receivedAt = ui.receivedAt === null ? 0 : performance.now();
  }
  const view = screenOf(state, taskOfState(state));
  if (view === "instructions") {
    $("resume-link").value = `${location.origin}/s/${token}`;
    show("instructions");
    setReady(true);
    $("begin").focus();
  } else if (view === "done") {
    showDone(state);
  } else {
    await componentOf(state).render(state);
  }
}

function paintTask() {
  const component = componentOf(ui.state);
  if (component) component.paint();
}

/** The Begin button says it is starting while its step is sent. */
function paintBusy(command) {
  if (command !== "begin") return;
  const button = $("begin");
  button.dataset.label = button.dataset.label || button.textContent;
  button.textContent = ui.busy ? "Starting…" : button.dataset.label;
  button.disabled = ui.busy;
}

/** One step of the session (its body names the command), sent to the one step route. */
async function step(body) {
  if (ui.busy) return; // one step at a time (and the key makes a repeat harmless)
  ui.busy = true;
  setReady(false);
  paintTask();
  paintBusy(body.command);
  try {
    const state = await call(`/api/s/${token}/step`, { method: "POST", body });
    say("");
    ui.busy = false;
    paintBusy(body.command);
    guardHistory();
    await render(state);
  } catch (err) {
    ui.busy = false;
    paintBusy(body.command);
    if (err instanceof ApiError && err.status === 409) {
      // The page was out of date (another tab, a double submission): show the server's state.
      say("");
      await render(await call(`/api/s/${token}/state`));
    } else {
      say(err.message);
      setReady(true);
      paintTask();
    }
  }
}

// ---- the Back button stays in the study ------------------------------------------------------
// The page keeps one entry of its own above the session's entry; Back lands on the session's
// entry (same URL: nothing reloads), and the page puts its entry back and says why.
function guardHistory() {
  if (history.state && history.state.emogen === "guard") return;
  history.replaceState({ emogen: "session" }, "", location.href);
  history.pushState({ emogen: "guard" }, "", location.href);
}

window.addEventListener("popstate", () => {
  guardHistory();
  say("Your answers are saved as you go, so Back does not undo them: carry on here.");
});

// ---- the personal link -----------------------------------------------------------------------
async function copyLink() {
  const input = $("resume-link");
  let copied;
  try {
    await navigator.clipboard.writeText(input.value);
    copied = true;
  } catch {
    input.select();
    copied = document.queryCommandSupported("copy") && document.execCommand("copy");
  }
  $("copy-status").textContent = copied
    ? "Copied. Keep it somewhere safe (an e-mail to yourself, a note)."
    : "Your browser would not copy it: select the link and copy it yourself.";
}
$("copy-link").addEventListener("click", copyLink);
$("resume-link").addEventListener("focus", (event) => event.target.select());

$("begin").addEventListener("click", () => step({ command: "begin", key: newKey() }));

async function main() {
  try {
    guardHistory();
    ui.display = await createFaceDisplay({ token });
    window.emogenStudy.display = ui.display.kind;
    window.emogenStudy.loads = ui.display.loads ?? []; // face models built (benchmarks)
    // the clip time (s) each face shown plays now (null: a face that does not move)
    window.emogenStudy.clipTimes = () =>
      Array.from(document.querySelectorAll("[data-viewer-container] .slot"), (s) => ui.display.clipTime(s));
    // each face's frames kept ahead (viewer/kept.js; null: none)
    window.emogenStudy.keptFrames = () =>
      Array.from(document.querySelectorAll("[data-viewer-container] .slot"), (s) => ui.display.keptOf?.(s) ?? null);
    await render(await call(`/api/s/${token}/state`));
  } catch (err) {
    say(err.message);
  }
}

main();
