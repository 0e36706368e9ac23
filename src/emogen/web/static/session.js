// The participant's session: instructions, trials (ten faces, choose the best and any others),
// ratings, completion. Every step is sent with an idempotency key and the page state always
// comes from the server, so a reload or a server restart resumes exactly.
import { api, ApiError, newKey } from "./api.js";
import { statusText } from "./connection.js";
import { createFaceDisplay } from "./faces.js";
import * as selection from "./selection.js";

const token = document.body.dataset.token;
const $ = (id) => document.getElementById(id);
const views = ["loading", "instructions", "trial", "rating", "done"];
// The grid also holds the 3D viewer's canvas: always go through the cells.
const cellsOf = () => Array.from($("grid").querySelectorAll(":scope > .cell"));

const ui = {
  state: null,
  display: null,
  shownAt: 0, // performance.now() when the current faces finished drawing
  // performance.now() when the answer holding the current faces arrived; the first faces this
  // page shows count from the page's start (0), so their load_ms includes page, model, textures
  receivedAt: /** @type {number | null} */ (null),
  loadMs: 0, // receivedAt → shownAt, reported with the select / restart step
  key: null, // idempotency key of the pending step
  elite: null, // face id
  others: [], // face ids, in the order chosen
  busy: false,
  loading: false, // faces being fetched or drawn
  focus: 0,
  link: /** @type {import("./connection.js").Link} */ ({ kind: "online" }),
  linkTimer: 0,
  said: "", // the last message that was not about the connection
};
// Tests and the researcher's tools read this.
window.emogenStudy = { ready: false, stage: null, display: null };

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
function megabytes(bytes) {
  return (bytes / 1e6).toFixed(1);
}

function onLoadProgress(done, total, unit) {
  const text =
    unit === "faces"
      ? `Loading faces: ${done} of ${total}…`
      : total > 0
        ? `Loading the 3D faces: ${megabytes(done)} of ${megabytes(total)} MB…`
        : `Loading the 3D faces: ${megabytes(done)} MB…`;
  $("load-text").textContent = text;
  const bar = $("load-bar");
  if (total > 0) bar.value = Math.min(1, done / total);
  else bar.removeAttribute("value"); // indeterminate
  $("load-status").hidden = false;
  document.body.dataset.loaded = `${done}/${total} ${unit}`;
}

async function drawFaces(slots, faces, identity) {
  ui.loading = true;
  $("load-text").textContent = "Loading faces…";
  $("load-bar").removeAttribute("value");
  const timer = setTimeout(() => ($("load-status").hidden = false), 150);
  try {
    await ui.display.show(slots, faces, identity, onLoadProgress);
  } finally {
    clearTimeout(timer);
    ui.loading = false;
    $("load-status").hidden = true;
  }
}

// ---- progress -------------------------------------------------------------------------------
function renderProgress(state) {
  const p = state.progress;
  const G = p.generations + 1;
  $("trial-progress").textContent = `Trial ${p.trial + 1} of ${p.trials}`;
  $("gen-progress").textContent =
    state.stage === "trial" && state.trial && state.trial.status === "active"
      ? `· Generation ${p.generation + 1} of ${G}`
      : state.stage === "trial"
        ? "· Rating"
        : "";
  const done = state.stage === "done" ? 1 : (p.trial + (p.generation + 1) / (G + 1)) / p.trials;
  $("meter-fill").style.width = `${Math.round(100 * Math.min(1, done))}%`;
  $("prompt").textContent = state.trial ? state.trial.prompt : document.title;
}

// ---- selection (kept in sessionStorage until submitted, so a reload keeps the clicks) ---------
function selectionKey() {
  const s = ui.state;
  return `emogen-sel:${token}:${s.progress.trial}:${s.trial.attempt}:${s.progress.generation}`;
}

function saveSelection() {
  try {
    sessionStorage.setItem(
      selectionKey(),
      JSON.stringify({ elite: ui.elite, others: ui.others, key: ui.key }),
    );
  } catch {
    /* storage unavailable: fine */
  }
}

function restoreSelection(ids) {
  ui.key = newKey();
  let saved = null;
  try {
    saved = JSON.parse(sessionStorage.getItem(selectionKey()) || "null");
  } catch {
    /* storage unavailable or garbled: start afresh */
  }
  ({ elite: ui.elite, others: ui.others } = selection.restoreChoice(saved, ids));
  if (saved && typeof saved.key === "string") ui.key = saved.key;
}

function count() {
  return selection.count(ui);
}

// A click (toggle) or the star (makeBest): the pure rule decides, the page shows the result.
function choose(rule, id) {
  const { choice, refused } = rule({ elite: ui.elite, others: ui.others }, id, ui.state.limits);
  if (refused) {
    say(refused);
    return;
  }
  ({ elite: ui.elite, others: ui.others } = choice);
  say("");
  saveSelection();
  paintSelection();
}

const toggle = (id) => choose(selection.toggle, id);
const makeBest = (id) => choose(selection.makeBest, id);

function paintSelection() {
  const { min_selections: min, max_selections: max } = ui.state.limits;
  for (const cell of cellsOf()) {
    const id = Number(cell.dataset.face);
    const face = cell.querySelector(".face");
    const role = ui.elite === id ? "best" : ui.others.includes(id) ? "ok" : "none";
    cell.dataset.role = role;
    face.setAttribute("aria-pressed", role === "none" ? "false" : "true");
    const n = Number(cell.dataset.pos) + 1;
    face.setAttribute(
      "aria-label",
      `Face ${n}` + (role === "best" ? ": best" : role === "ok" ? ": also acceptable" : ""),
    );
    cell.querySelector(".badge").textContent = role === "best" ? "★ Best" : role === "ok" ? "✓" : "";
  }
  const n = count();
  let status;
  if (ui.busy) status = "Saving your choice…";
  else if (ui.loading) status = "Loading the faces: please wait until they appear.";
  else if (ui.elite === null) status = "Click the face that looks most like the emotion: it becomes ★ best.";
  else if (n < min) status = `Choose at least ${min} faces (${n} chosen).`;
  else status = `${n} chosen (up to ${max}): ★ best + ${ui.others.length} also acceptable. Then press Next generation.`;
  $("selection-status").textContent = status;
  $("next").disabled = ui.busy || ui.loading || !selection.complete(ui, ui.state.limits);
  $("next").textContent = ui.busy ? "Saving…" : "Next generation";
}

// ---- the grid --------------------------------------------------------------------------------
function buildGrid(n) {
  const grid = $("grid");
  if (cellsOf().length === n) return;
  for (const old of cellsOf()) old.remove();
  const first = grid.firstChild;
  for (let i = 0; i < n; i++) {
    const cell = document.createElement("div");
    cell.className = "cell";
    cell.dataset.pos = String(i);
    cell.innerHTML =
      `<button type="button" class="face" aria-pressed="false">` +
      `<span class="slot"></span><span class="num" aria-hidden="true">${i + 1}</span>` +
      `<span class="badge" aria-hidden="true"></span></button>` +
      `<button type="button" class="star" tabindex="-1" title="Make this the best face" aria-label="Make face ${i + 1} the best">★</button>`;
    grid.insertBefore(cell, first);
  }
}

function cellOf(target) {
  const cell = target.closest(".cell");
  return cell && $("grid").contains(cell) ? cell : null;
}

function onGridClick(event) {
  const cell = cellOf(event.target);
  if (!cell || ui.busy || !window.emogenStudy.ready) return;
  const id = Number(cell.dataset.face);
  focusCell(Number(cell.dataset.pos));
  if (event.target.closest(".star")) makeBest(id);
  else toggle(id);
}

function columns() {
  const grid = $("grid");
  return getComputedStyle(grid).gridTemplateColumns.split(" ").length || 5;
}

function focusCell(pos) {
  const cells = cellsOf();
  pos = Math.max(0, Math.min(cells.length - 1, pos));
  // Every face is in the Tab order (as the instructions say); the arrows move by rows too.
  cells[pos].querySelector(".face").focus({ preventScroll: false });
  ui.focus = pos;
}

function onGridKey(event) {
  const cell = cellOf(event.target);
  if (!cell) return;
  const pos = Number(cell.dataset.pos);
  const cols = columns();
  const moves = { ArrowRight: 1, ArrowLeft: -1, ArrowDown: cols, ArrowUp: -cols };
  if (event.key in moves) {
    event.preventDefault();
    focusCell(pos + moves[event.key]);
  } else if (event.key === "Home") {
    event.preventDefault();
    focusCell(0);
  } else if (event.key === "End") {
    event.preventDefault();
    focusCell(cellsOf().length - 1);
  } else if ((event.key === "b" || event.key === "B") && window.emogenStudy.ready && !ui.busy) {
    event.preventDefault();
    makeBest(Number(cell.dataset.face));
  }
}

async function showTrial(state) {
  const pop = state.population;
  const ids = pop.faces.map((f) => f.id);
  buildGrid(ids.length);
  const cells = cellsOf();
  cells.forEach((cell, i) => {
    cell.dataset.face = String(ids[i]);
  });
  restoreSelection(ids);
  show("trial");
  $("restart").hidden = !state.allow_restart;
  setReady(false);
  ui.loading = true;
  paintSelection();
  $("grid").setAttribute("aria-busy", "true");
  await drawFaces(
    cells.map((c) => c.querySelector(".slot")),
    pop.faces,
    state.trial.identity,
  );
  $("grid").setAttribute("aria-busy", "false");
  ui.shownAt = performance.now();
  ui.loadMs = Math.max(0, Math.round(ui.shownAt - (ui.receivedAt ?? 0)));
  setReady(true);
  paintSelection();
}

// ---- rating ----------------------------------------------------------------------------------
async function showRating(state) {
  const r = state.rating;
  $("rating-question").textContent = r.question;
  $("rating-low").textContent = `1 = ${r.low_label}`;
  $("rating-high").textContent = `${r.points} = ${r.high_label}`;
  const scale = $("rating-scale");
  scale.replaceChildren();
  for (let v = 1; v <= r.points; v++) {
    const label = document.createElement("label");
    label.innerHTML = `<input type="radio" name="rating" value="${v}"><span>${v}</span>`;
    scale.appendChild(label);
  }
  ui.key = newKey();
  $("rate").disabled = true;
  show("rating");
  setReady(false);
  if (r.face) await drawFaces([$("rating-slot")], [r.face], state.trial.identity);
  ui.shownAt = performance.now();
  setReady(true);
}

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

// ---- state machine ---------------------------------------------------------------------------
async function render(state) {
  // the first population this page draws counts from the page's start (receivedAt stays 0)
  ui.receivedAt = ui.receivedAt === null ? 0 : performance.now();
  ui.state = state;
  renderProgress(state);
  const view = selection.viewOf(state);
  if (view === "instructions") {
    $("resume-link").value = `${location.origin}/s/${token}`;
    show("instructions");
    setReady(true);
    $("begin").focus();
  } else if (view === "trial") {
    await showTrial(state);
  } else if (view === "rating") {
    await showRating(state);
  } else {
    showDone(state);
  }
}

const savingLabels = { begin: ["begin", "Starting…"], rating: ["rate", "Saving…"] };

function paintBusy(path) {
  const [id, label] = savingLabels[path] || [];
  if (!id) return;
  const button = $(id);
  button.dataset.label = button.dataset.label || button.textContent;
  button.textContent = ui.busy ? label : button.dataset.label;
  button.disabled = ui.busy;
}

async function step(path, body) {
  if (ui.busy) return; // one step at a time (and the key makes a repeat harmless)
  ui.busy = true;
  setReady(false);
  paintIfTrial();
  paintBusy(path);
  try {
    const state = await call(`/api/s/${token}/${path}`, { method: "POST", body });
    say("");
    ui.busy = false;
    paintBusy(path);
    guardHistory();
    await render(state);
  } catch (err) {
    ui.busy = false;
    paintBusy(path);
    if (err instanceof ApiError && err.status === 409) {
      // The page was out of date (another tab, a double submission): show the server's state.
      say("");
      await render(await call(`/api/s/${token}/state`));
    } else {
      say(err.message);
      setReady(true);
      paintIfTrial();
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

function paintIfTrial() {
  if (ui.state && ui.state.stage === "trial" && ui.state.trial.status === "active") paintSelection();
}

function elapsed() {
  return Math.max(0, Math.round(performance.now() - ui.shownAt));
}

function position() {
  const s = ui.state;
  return { trial: s.progress.trial, attempt: s.trial.attempt, generation: s.progress.generation };
}

$("grid").addEventListener("click", onGridClick);
$("grid").addEventListener("keydown", onGridKey);

$("begin").addEventListener("click", () => step("begin", { key: newKey() }));

$("next").addEventListener("click", () => {
  if (ui.elite === null || ui.busy) return;
  step("select", selection.selectionBody(ui.state, ui, ui.key, elapsed(), ui.loadMs));
});

$("restart").addEventListener("click", () => {
  if (ui.busy) return;
  if (!confirm("Start this face again from a new set of faces?")) return;
  step("restart", { key: ui.key, ...position(), response_ms: elapsed(), load_ms: ui.loadMs });
});

$("rating-scale").addEventListener("change", () => {
  $("rate").disabled = false;
});

$("rating-form").addEventListener("submit", (event) => {
  event.preventDefault();
  const checked = document.querySelector('input[name="rating"]:checked');
  if (!checked || ui.busy) return;
  step("rating", {
    key: ui.key,
    trial: ui.state.progress.trial,
    value: Number(checked.value),
    response_ms: elapsed(),
  });
});

async function main() {
  try {
    guardHistory();
    ui.display = await createFaceDisplay({ token });
    window.emogenStudy.display = ui.display.kind;
    await render(await call(`/api/s/${token}/state`));
  } catch (err) {
    say(err.message);
  }
}

main();
