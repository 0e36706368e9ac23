// The evolve task's page component (the GA): ten faces, choose the best and any others, round
// after round, then rate the final face. What the shells (the study's page, static/session.js;
// the jsPsych plugin's trial) ask of a task: its screens' markup, `create(page)` (render and
// paint them in the shell's context: the shared state, the step sender, the face display), the
// screen a state shows, the progress line, the heading, the pause's announcement; and for the
// plugin, the trial's data (`data`, `record`, `result`), the simulated observer at the screens
// (`drive`) and without a server (`simulate`). The rules of a selection: ./selection.js.
import { newKey } from "../api.js";
import { choose, normal, randomFace, responseTime, uniform } from "../observer.js";
import * as selection from "./selection.js";

const markup = `
  <section id="view-trial" class="view" hidden aria-labelledby="prompt">
    <p id="grid-help" class="sr-only">Faces. Tab or the arrow keys move between faces; Enter or Space selects a face or removes it; B makes the focused face the best one.</p>
    <div id="grid" class="grid" data-viewer-container role="group" aria-describedby="grid-help"></div>
    <div class="actions">
      <div id="motion" class="motion" hidden>
        <button id="replay" type="button" class="secondary">↻ Play all again</button>
        <label for="scrub" class="scrub">Step through face <span id="scrub-face">1</span>:</label>
        <input id="scrub" type="range" min="0" max="1" step="0.01" value="0">
      </div>
      <p id="star-help" class="legend"><span class="legend-best">★ best</span> · <span class="legend-ok">✓ also acceptable</span> · the ★ on a face makes it the best</p>
      <p id="selection-status" class="status" aria-live="polite">&nbsp;</p>
      <div class="buttons">
        <button id="restart" type="button" class="secondary">Start again</button>
        <button id="next" type="button" class="primary" disabled>Next round</button>
      </div>
    </div>
  </section>

  <section id="view-rating" class="view rating" hidden>
    <div class="rating-face" data-viewer-container><div class="slot big" id="rating-slot"></div></div>
    <form id="rating-form" class="rating-form">
      <fieldset>
        <legend id="rating-question">&nbsp;</legend>
        <div class="scale" id="rating-scale"></div>
        <div class="scale-labels"><span id="rating-low"></span><span id="rating-high"></span></div>
      </fieldset>
      <div class="actions-row"><button id="rate" class="primary" type="submit" disabled>Continue</button></div>
    </form>
  </section>
`;

/** @param {any} page the shell's context (session.js: `page`) */
function create(page) {
  const { $, ui } = page;
  const view = () => ui.state.view;
  // The grid also holds the 3D viewer's canvas: always go through the cells.
  const cellsOf = () => Array.from($("grid").querySelectorAll(":scope > .cell"));
  /** @type {{ elite: number | null, others: number[], focus: number }} */
  const sel = { elite: null, others: [], focus: 0 };

  // ---- selection (kept in sessionStorage until submitted, so a reload keeps the clicks) -----
  function selectionKey() {
    const s = ui.state;
    return `emogen-sel:${page.token}:${s.progress.trial}:${s.trial.attempt}:${s.view.generation}`;
  }

  function saveSelection() {
    try {
      sessionStorage.setItem(
        selectionKey(),
        JSON.stringify({ elite: sel.elite, others: sel.others, key: ui.key }),
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
    ({ elite: sel.elite, others: sel.others } = selection.restoreChoice(saved, ids));
    if (saved && typeof saved.key === "string") ui.key = saved.key;
  }

  // A click (toggle) or the star (makeBest): the pure rule decides, the page shows the result.
  function decide(rule, id) {
    const { choice, refused } = rule({ elite: sel.elite, others: sel.others }, id, view().limits);
    if (refused) {
      page.say(refused);
      return;
    }
    ({ elite: sel.elite, others: sel.others } = choice);
    page.say("");
    saveSelection();
    paint();
  }

  const toggle = (id) => decide(selection.toggle, id);
  const makeBest = (id) => decide(selection.makeBest, id);

  function paint() {
    if (!(ui.state && ui.state.stage === "trial" && ui.state.view.task === "evolve")) return;
    if (ui.state.trial.status === "rating") {
      paintRate();
      return;
    }
    if (ui.state.trial.status !== "active") return;
    const { min_selections: min, max_selections: max } = view().limits;
    for (const cell of cellsOf()) {
      const id = Number(cell.dataset.face);
      const face = cell.querySelector(".face");
      const role = sel.elite === id ? "best" : sel.others.includes(id) ? "ok" : "none";
      cell.dataset.role = role;
      face.setAttribute("aria-pressed", role === "none" ? "false" : "true");
      const n = Number(cell.dataset.pos) + 1;
      face.setAttribute(
        "aria-label",
        `Face ${n}` + (role === "best" ? ": best" : role === "ok" ? ": also acceptable" : ""),
      );
      cell.querySelector(".badge").textContent = role === "best" ? "★ Best" : role === "ok" ? "✓" : "";
    }
    const n = selection.count(sel);
    let status;
    if (ui.busy) status = "Saving your choice…";
    else if (ui.loading) status = "Loading the faces: please wait until they appear.";
    else if (sel.elite === null) status = `${pointerVerb()} the face most like the emotion: it becomes ★ best.`;
    else if (n < min) status = `Choose at least ${min} faces (${n} chosen).`;
    else status = `${n} chosen (up to ${max}): ★ best + ${sel.others.length} also acceptable. Then press Next round.`;
    $("selection-status").textContent = status;
    $("next").disabled = ui.busy || ui.loading || !selection.complete(sel, view().limits);
    $("next").textContent = ui.busy ? "Saving…" : "Next round";
  }

  /** "Tap" where the main pointer is a finger (a phone, a tablet), "Click" with a mouse (and
   * where the page cannot ask: a document without media queries). */
  function pointerVerb() {
    return window.matchMedia?.("(pointer: coarse)").matches ? "Tap" : "Click";
  }

  // ---- the grid ------------------------------------------------------------------------------
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
    if (!cell || ui.busy || !page.ready()) return;
    const id = Number(cell.dataset.face);
    focusCell(Number(cell.dataset.pos));
    if (event.target.closest(".star")) makeBest(id);
    else toggle(id);
  }

  function columns() {
    return getComputedStyle($("grid")).gridTemplateColumns.split(" ").length || 5;
  }

  function focusCell(pos) {
    const cells = cellsOf();
    pos = Math.max(0, Math.min(cells.length - 1, pos));
    // Every face is in the Tab order (as the instructions say); the arrows move by rows too.
    cells[pos].querySelector(".face").focus({ preventScroll: false });
    sel.focus = pos;
    $("scrub-face").textContent = String(pos + 1);
  }

  // ---- faces that move: every tile plays its clip in sync; one tile can be stepped through ----
  function showMotion(faces) {
    const moving = faces.find((f) => f.motion);
    $("motion").hidden = !moving;
    if (!moving) return;
    const scrub = $("scrub");
    scrub.max = String(moving.motion.clip_s);
    scrub.value = "0";
    $("scrub-face").textContent = String(sel.focus + 1);
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
    } else if ((event.key === "b" || event.key === "B") && page.ready() && !ui.busy) {
      event.preventDefault();
      makeBest(Number(cell.dataset.face));
    }
  }

  async function showTrial(state) {
    const pop = state.view.population;
    const ids = pop.faces.map((f) => f.id);
    buildGrid(ids.length);
    const cells = cellsOf();
    cells.forEach((cell, i) => {
      cell.dataset.face = String(ids[i]);
    });
    restoreSelection(ids);
    page.show("trial");
    $("restart").hidden = !state.view.allow_restart;
    page.setReady(false);
    ui.loading = true;
    paint();
    $("grid").setAttribute("aria-busy", "true");
    await page.drawFaces(
      cells.map((c) => c.querySelector(".slot")),
      pop.faces,
      state.trial.identity,
    );
    $("grid").setAttribute("aria-busy", "false");
    showMotion(pop.faces);
    page.facesShown();
    page.setReady(true);
    paint();
  }

  // ---- rating --------------------------------------------------------------------------------
  // the Continue button says when the rating is being saved; it is pressed once a point is chosen
  function paintRate() {
    const rate = $("rate");
    rate.textContent = ui.busy ? "Saving…" : "Continue";
    rate.disabled = ui.busy || !$("rating-scale").querySelector('input[name="rating"]:checked');
  }

  async function showRating(state) {
    const r = state.view.rating;
    $("rating-question").textContent = r.question;
    $("rating-low").textContent = `1 = ${r.low_label}`;
    $("rating-high").textContent = `${r.points} = ${r.high_label}`;
    page.fillScale($("rating-scale"), "rating", r.points);
    ui.key = newKey();
    paintRate();
    page.show("rating");
    page.setReady(false);
    if (r.face) await page.drawFaces([$("rating-slot")], [r.face], state.trial.identity);
    page.facesShown();
    page.setReady(true);
  }

  function position() {
    const s = ui.state;
    return { trial: s.progress.trial, attempt: s.trial.attempt, generation: s.view.generation };
  }

  // which display showed the faces (recorded with the step): the server's images (no WebGL:
  // pictures, strips of frames for faces that move) or the 3D viewer
  const shownBy = () => (ui.display ? { fallback: ui.display.kind === "png" } : {});

  $("grid").addEventListener("click", onGridClick);
  $("grid").addEventListener("keydown", onGridKey);

  $("next").addEventListener("click", () => {
    if (sel.elite === null || ui.busy) return;
    page.step({ ...selection.selectionBody(ui.state, sel, ui.key, page.elapsed(), ui.loadMs), ...shownBy() });
  });

  const slotAt = (pos) => cellsOf()[pos]?.querySelector(".slot");

  $("replay").addEventListener("click", () => {
    const slot = slotAt(0);
    if (slot) ui.display.replay(slot);
    $("scrub").value = "0";
  });

  $("scrub").addEventListener("input", () => {
    const slot = slotAt(sel.focus);
    if (slot) ui.display.scrub(slot, Number($("scrub").value));
  });

  $("restart").addEventListener("click", () => {
    if (ui.busy) return;
    if (!confirm("Start this face again from a new set of faces?")) return;
    page.step({
      command: "restart", key: ui.key, ...position(), response_ms: page.elapsed(), load_ms: ui.loadMs, ...shownBy(),
    });
  });

  $("rating-scale").addEventListener("change", () => {
    $("rate").disabled = false;
  });

  $("rating-form").addEventListener("submit", (event) => {
    event.preventDefault();
    const checked = $("rating-scale").querySelector('input[name="rating"]:checked');
    if (!checked || ui.busy) return;
    page.step({
      command: "rate",
      key: ui.key,
      trial: ui.state.progress.trial,
      value: Number(checked.value),
      response_ms: page.elapsed(),
      ...shownBy(),
    });
  });

  return {
    /** @param {any} state */
    render: (state) => (state.trial.status === "rating" ? showRating(state) : showTrial(state)),
    paint,
  };
}

// ---- where the participant is ------------------------------------------------------------------
/** @param {any} state */
const screen = (state) => (state.trial.status === "rating" ? "rating" : "trial");

/**
 * The round (or the rating), and the share of the trial done: G + 1 rounds and the rating.
 * @param {any} state
 */
function progress(state) {
  const view = state.view;
  const step = state.trial.status === "active" ? selection.roundText(view) : "Rating";
  return { step, within: (view.generation + 1) / (view.generations + 2) };
}

/** The heading stays the trial's prompt ("Make the face look SAD") through the rating: the
 * rating's own question is the scale's legend below the face. @param {any} state */
const prompt = () => null;

/** The emotion to make: "next: SAD". @param {any} state */
const upcoming = (state) => state.view.emotion.toUpperCase();

// ---- the jsPsych plugin's data -----------------------------------------------------------------
/** The trial's data fields (jsPsych types by name) and their values before the trial. */
const data = {
  /** The emotion the trial asked for (from the trial's record). */
  emotion: { type: "STRING", value: null },
  /** One entry per generation answered: {attempt, generation, shown, elite, others, rt, load_ms}. */
  generations: {
    type: "COMPLEX",
    array: true,
    nested: {
      attempt: { type: "INT" }, generation: { type: "INT" }, shown: { type: "INT", array: true },
      elite: { type: "INT" }, others: { type: "INT", array: true }, rt: { type: "INT" }, load_ms: { type: "INT" },
    },
    value: [],
  },
  /** "Start again" presses: {attempt, generation, rt}. */
  restarts: { type: "COMPLEX", array: true, value: [] },
  rating: { type: "INT", value: null },
  rating_rt: { type: "INT", value: null },
};

/**
 * A step the server accepted, added to the trial's data from its body and the view it answered.
 * @param {any} data
 * @param {any} body
 * @param {any} view
 */
function record(data, body, view) {
  if (body.command === "select") {
    data.generations.push({
      attempt: body.attempt,
      generation: body.generation,
      shown: view.population.faces.map((/** @type {any} */ f) => f.id),
      elite: body.elite,
      others: [...body.others],
      rt: body.response_ms ?? null,
      load_ms: body.load_ms ?? null,
    });
  } else if (body.command === "restart") {
    data.restarts.push({ attempt: body.attempt, generation: body.generation, rt: body.response_ms ?? null });
  } else if (body.command === "rate") {
    data.rating = body.value;
    data.rating_rt = body.response_ms ?? null;
  }
}

/** The trial record's result: the emotion and the final face (the last best face). @param {any} result */
const result = (result) => ({
  emotion: result.emotion,
  final_face_id: result.final_face ? result.final_face.id : null,
  final_weights: result.final_face ? result.final_face.weights : null,
});

/**
 * The simulated observer at the screens: the faces nearest its target as the best and the
 * others (``chosen`` faces within the study's limits), then its rating (default 70% of the scale).
 * @param {string} shown the screen
 * @param {any} state
 * @param {{ click: (selector: string) => void, check: (scale: string, value: number) => void }} act
 * @param {{ target: number[], chosen?: number, noise?: number, rating?: number }} options
 */
function drive(shown, state, act, { target, chosen = 3, noise = 0, rating }) {
  const view = state.view;
  if (shown === "trial") {
    const { min_selections: min, max_selections: max } = view.limits;
    const pick = choose(view.population.faces, target, Math.min(max, Math.max(min, chosen)), { noise });
    for (const id of [pick.elite, ...pick.others]) act.click(`#grid > .cell[data-face="${id}"] .face`);
    act.click("#next");
  } else if (shown === "rating") {
    act.check("rating-scale", rating ?? Math.ceil(0.7 * view.rating.points));
    act.click("#rate");
  }
}

/** A child of two chosen faces: each weight from either, mutated (p 0.2, sd 0.15), in [0, 1]. */
function child(random, a, b) {
  return a.map((w, i) => {
    const gene = random() < 0.5 ? w : b[i];
    const mutated = random() < 0.2 ? gene + 0.15 * normal(random) : gene;
    return Math.min(1, Math.max(0, mutated));
  });
}

/**
 * A trial's data without a server (the plugin's data-only simulate): the observer meets a
 * stand-in for the server's GA — random faces, then children of the chosen faces (uniform
 * crossover, Gaussian mutation) — made only so a lab can dry-run its timeline and its analysis
 * code; the faces it writes are not emogen's GA's. ``shows``: what the study's block shows (GET
 * /api/study: its emotions and identities, in config order, ``generations`` + 1 generations of
 * ``faces``, the selection's limits, the rating's points); ``index``: the trial's place in it.
 * @param {{ target: number[], shows: any, index?: number, chosen?: number, noise?: number,
 *   seed?: number, median_rt?: number, rating?: number }} options
 */
export function simulate({ target, shows, index = 0, chosen = 3, noise = 0, seed = 1, median_rt = 4000, rating }) {
  const { generations, faces, min_selections: min, max_selections: max } = shows;
  const n = Math.min(max, Math.max(min, chosen));
  const random = uniform(seed);
  let nextId = 0;
  let population = Array.from({ length: faces }, () => ({ id: nextId++, weights: randomFace(random, target.length) }));
  const rows = [];
  let best = population[0];
  for (let g = 0; g <= generations; g++) {
    const { elite, others } = choose(population, target, n, { noise, random });
    rows.push({
      attempt: 0, generation: g, shown: population.map((f) => f.id), elite, others: [...others],
      rt: responseTime(random, median_rt), load_ms: 0,
    });
    const picked = [elite, ...others].map((id) => population.find((f) => f.id === id));
    best = /** @type {any} */ (picked[0]);
    const children = Array.from({ length: faces - 1 }, () => {
      const a = picked[Math.floor(random() * picked.length)];
      const b = picked[Math.floor(random() * picked.length)];
      return { id: nextId++, weights: child(random, /** @type {any} */ (a).weights, /** @type {any} */ (b).weights) };
    });
    population = [best, ...children];
  }
  const ratingRt = responseTime(random, median_rt / 2);
  return {
    emotion: shows.emotions[index % shows.emotions.length],
    identity: shows.identities[index % shows.identities.length],
    generations: rows, final_face_id: best.id, final_weights: best.weights,
    rating: rating ?? Math.ceil(0.7 * shows.rating_points), rating_rt: ratingRt,
    rt: rows.reduce((t, row) => t + row.rt, ratingRt),
  };
}

export default {
  name: "evolve",
  markup,
  screens: ["trial", "rating"],
  create,
  screen,
  progress,
  prompt,
  upcoming,
  data,
  record,
  result,
  drive,
  simulate,
};
