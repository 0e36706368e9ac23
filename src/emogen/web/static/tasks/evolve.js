// The evolve task's screens (the GA): ten faces, choose the best and any others, then rate the
// final face. The rules of a selection are in ../selection.js; the page's shell (session.js)
// gives this component its context: the shared state, the step sender and the face display.
import { newKey } from "../api.js";
import * as selection from "../selection.js";

/** @param {any} page the shell's context (session.js: `page`) */
export function createEvolve(page) {
  const { $, ui } = page;
  // The grid also holds the 3D viewer's canvas: always go through the cells.
  const cellsOf = () => Array.from($("grid").querySelectorAll(":scope > .cell"));
  /** @type {{ elite: number | null, others: number[], focus: number }} */
  const sel = { elite: null, others: [], focus: 0 };

  // ---- selection (kept in sessionStorage until submitted, so a reload keeps the clicks) -----
  function selectionKey() {
    const s = ui.state;
    return `emogen-sel:${page.token}:${s.progress.trial}:${s.trial.attempt}:${s.progress.generation}`;
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
  function choose(rule, id) {
    const { choice, refused } = rule({ elite: sel.elite, others: sel.others }, id, ui.state.limits);
    if (refused) {
      page.say(refused);
      return;
    }
    ({ elite: sel.elite, others: sel.others } = choice);
    page.say("");
    saveSelection();
    paint();
  }

  const toggle = (id) => choose(selection.toggle, id);
  const makeBest = (id) => choose(selection.makeBest, id);

  function paint() {
    if (!(ui.state && ui.state.stage === "trial" && ui.state.trial.status === "active")) return;
    if (ui.state.trial.task !== "evolve") return;
    const { min_selections: min, max_selections: max } = ui.state.limits;
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
    else if (sel.elite === null) status = "Tap the face most like the emotion: it becomes ★ best.";
    else if (n < min) status = `Choose at least ${min} faces (${n} chosen).`;
    else status = `${n} chosen (up to ${max}): ★ best + ${sel.others.length} also acceptable. Then press Next round.`;
    $("selection-status").textContent = status;
    $("next").disabled = ui.busy || ui.loading || !selection.complete(sel, ui.state.limits);
    $("next").textContent = ui.busy ? "Saving…" : "Next round";
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
    const pop = state.population;
    const ids = pop.faces.map((f) => f.id);
    buildGrid(ids.length);
    const cells = cellsOf();
    cells.forEach((cell, i) => {
      cell.dataset.face = String(ids[i]);
    });
    restoreSelection(ids);
    page.show("trial");
    $("restart").hidden = !state.allow_restart;
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
    page.facesShown();
    page.setReady(true);
    paint();
  }

  // ---- rating --------------------------------------------------------------------------------
  async function showRating(state) {
    const r = state.rating;
    $("rating-question").textContent = r.question;
    $("rating-low").textContent = `1 = ${r.low_label}`;
    $("rating-high").textContent = `${r.points} = ${r.high_label}`;
    page.fillScale($("rating-scale"), "rating", r.points);
    ui.key = newKey();
    $("rate").disabled = true;
    page.show("rating");
    page.setReady(false);
    if (r.face) await page.drawFaces([$("rating-slot")], [r.face], state.trial.identity);
    page.facesShown();
    page.setReady(true);
  }

  function position() {
    const s = ui.state;
    return { trial: s.progress.trial, attempt: s.trial.attempt, generation: s.progress.generation };
  }

  $("grid").addEventListener("click", onGridClick);
  $("grid").addEventListener("keydown", onGridKey);

  $("next").addEventListener("click", () => {
    if (sel.elite === null || ui.busy) return;
    page.step("select", selection.selectionBody(ui.state, sel, ui.key, page.elapsed(), ui.loadMs));
  });

  $("restart").addEventListener("click", () => {
    if (ui.busy) return;
    if (!confirm("Start this face again from a new set of faces?")) return;
    page.step("restart", { key: ui.key, ...position(), response_ms: page.elapsed(), load_ms: ui.loadMs });
  });

  $("rating-scale").addEventListener("change", () => {
    $("rate").disabled = false;
  });

  $("rating-form").addEventListener("submit", (event) => {
    event.preventDefault();
    const checked = $("rating-scale").querySelector('input[name="rating"]:checked');
    if (!checked || ui.busy) return;
    page.step("rating", {
      key: ui.key,
      trial: ui.state.progress.trial,
      value: Number(checked.value),
      response_ms: page.elapsed(),
    });
  });

  return {
    views: ["trial", "rating"],
    /** @param {any} state */
    render: (state) => (state.trial.status === "rating" ? showRating(state) : showTrial(state)),
    paint,
  };
}
