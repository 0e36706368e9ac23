// The gsp task's page component (Gibbs sampling with people): one face, large, and one slider
// under it. The view carries the face at every slider position (``frames``), so moving the
// slider shows the face of that position on every input event, without asking the server: the
// 3D viewer keeps each position's frame once drawn and draws the others ahead while the page is
// idle (display.keep, viewer/kept.js: on software GL a live draw of this face runs at 7.6–10.5
// frames/s, its kept frames at ≥ 30; benchmarks/bench_gsp_slider.py). The frames are given
// back when the answer is sent. The
// slider starts where the server drew it (recorded); arrow keys move it, Home/End jump to its
// ends, Enter or "Next" sends it. Without WebGL (the server's images) a strip of nine pictures
// at evenly spaced positions stands in for the slider, and the answer says so (``fallback``).
// While every chain of the concept is held by someone else the view says ``waiting``: the page
// says so and asks again every few seconds. What the shells ask of a task: ./evolve.js's header.
import { newKey } from "../api.js";
import { responseTime, uniform } from "../observer.js";

/** Seconds between two requests for a chain while waiting. */
const POLL_MS = 3000;

/** Whether the page shows the strip of pictures (no WebGL): the heading then asks for a picture
 * (the block's prompt speaks of the slider). One display per page: set whenever the component asks which it is. */
let pictures = false;

const markup = `
  <section id="view-gsp" class="view gsp" hidden aria-labelledby="prompt">
    <p id="gsp-wait" class="gsp-wait status" aria-live="polite" hidden>Someone else is working on this face right now. It will be ready for you in a moment…</p>
    <div id="gsp-face" class="gsp-face" data-viewer-container><div class="slot big" id="gsp-slot"></div></div>
    <label for="gsp-slider" class="sr-only">Slider: move it until the face fits the word best</label>
    <input id="gsp-slider" class="gsp-slider" type="range" min="0" max="40" step="1" value="20">
    <div id="gsp-strip" class="gsp-strip" role="group" aria-label="Pictures: choose the one that fits the word best" data-viewer-container hidden></div>
    <p id="gsp-status" class="status" aria-live="polite">&nbsp;</p>
    <div class="actions-row"><button id="gsp-next" class="primary" type="button" disabled>Next</button></div>
  </section>
`;

// Its layout, adopted by the document when the component starts (a constructed style sheet: the
// study's Content-Security-Policy allows no inline <style>, and the task keeps its own rules).
const CSS = `
.gsp { display: flex; flex-direction: column; align-items: center; gap: 0.75rem; padding-top: 0.75rem; }
.gsp-face { width: min(58vh, 92vw, 560px); aspect-ratio: 1; position: relative; }
.gsp-slider { width: min(58vh, 92vw, 560px); height: 2.75rem; margin: 0; touch-action: none; }
.gsp-slider::-webkit-slider-thumb { width: 2.25rem; height: 2.25rem; }
.gsp-strip { display: grid; grid-template-columns: repeat(3, minmax(0, 1fr)); gap: 0.4rem; width: min(92vw, 60vh, 620px); }
.gsp-strip button { position: relative; aspect-ratio: 1; padding: 0; border: 3px solid transparent; border-radius: 6px; background: none; cursor: pointer; overflow: hidden; }
.gsp-strip button[aria-pressed="true"] { border-color: var(--accent, #1a5fb4); }
.gsp-wait { max-width: 32rem; text-align: center; }
`;

function adoptStyle() {
  if (typeof CSSStyleSheet === "undefined" || !("adoptedStyleSheets" in document)) return;
  const sheet = new CSSStyleSheet();
  sheet.replaceSync(CSS);
  document.adoptedStyleSheets = [...document.adoptedStyleSheets, sheet];
}

/** @param {any} page the shell's context (session.js: `page`) */
function create(page) {
  adoptStyle();
  const { $, ui } = page;
  /** @type {ReturnType<typeof setTimeout> | null} */
  let poll = null;
  /** The position chosen (the slider's, or the strip's picture); null until one is. */
  let chosen = /** @type {number | null} */ (null);
  const slider = /** @type {HTMLInputElement} */ ($("gsp-slider"));
  const fallback = () => {
    pictures = Boolean(ui.display && ui.display.kind === "png");
    return pictures;
  };

  function stopPolling() {
    if (poll !== null) clearTimeout(poll);
    poll = null;
  }

  function paint() {
    const state = ui.state;
    if (!(state && state.stage === "trial" && state.view.task === "gsp")) return;
    const waiting = state.view.waiting;
    const next = /** @type {HTMLButtonElement} */ ($("gsp-next"));
    next.disabled = waiting || ui.busy || ui.loading || chosen === null;
    next.textContent = ui.busy && !waiting ? "Saving…" : "Next";
    slider.disabled = ui.busy || ui.loading;
    $("gsp-status").textContent = ui.busy && !waiting
      ? "Saving your answer…"
      : ui.loading
        ? "Loading the face: please wait until it appears."
        : fallback() && chosen === null && !waiting
          ? "Choose the picture that fits the word best."
          : "\u00a0";
  }

  /** The face at slider position ``p`` drawn now (one morph update). @param {number} p */
  function morph(p) {
    const view = ui.state.view;
    const face = { id: p, weights: view.frames[p] };
    ui.display.show([$("gsp-slot")], [face], ui.state.trial.identity);
  }

  function send() {
    const state = ui.state;
    if (ui.busy || !page.ready() || state.view.waiting || chosen === null) return;
    if (!fallback()) ui.display.keep?.($("gsp-slot"), null); // the trial's frames given back
    page.step({
      command: "slide",
      key: ui.key,
      trial: state.progress.trial,
      position: chosen,
      fallback: fallback(),
      response_ms: page.elapsed(),
      load_ms: ui.loadMs,
    });
  }

  function waitForChain(state) {
    for (const id of ["gsp-face", "gsp-strip"]) $(id).hidden = true;
    slider.hidden = true;
    $("gsp-wait").hidden = false;
    page.show("gsp");
    page.setReady(true);
    paint();
    stopPolling();
    poll = setTimeout(() => {
      poll = null;
      if (ui.state === state && !ui.busy) {
        page.step({ command: "await_chain", key: newKey(), trial: state.progress.trial });
      }
    }, POLL_MS);
  }

  async function showStrip(state) {
    const view = state.view;
    const box = $("gsp-strip");
    box.replaceChildren();
    const slots = view.strip.map((/** @type {number} */ p, /** @type {number} */ i) => {
      const button = document.createElement("button");
      button.type = "button";
      button.dataset.position = String(p);
      button.setAttribute("aria-pressed", "false");
      button.setAttribute("aria-label", `picture ${i + 1} of ${view.strip.length}`);
      const slot = document.createElement("div");
      slot.className = "slot";
      button.appendChild(slot);
      box.appendChild(button);
      return slot;
    });
    box.hidden = false;
    page.show("gsp");
    const faces = view.strip.map((/** @type {number} */ p) => ({ id: p, weights: view.frames[p] }));
    await page.drawFaces(slots, faces, state.trial.identity);
  }

  async function render(state) {
    const view = state.view;
    if (view.waiting) return waitForChain(state);
    stopPolling();
    $("gsp-wait").hidden = true;
    ui.key = newKey();
    chosen = fallback() ? null : view.slider.start;
    if (pictures) $("prompt").textContent = prompt(state); // the shell wrote it before we knew
    page.setReady(false);
    ui.loading = true;
    paint();
    if (fallback()) {
      $("gsp-face").hidden = true;
      slider.hidden = true;
      await showStrip(state);
    } else {
      $("gsp-strip").hidden = true;
      $("gsp-face").hidden = false;
      slider.hidden = false;
      slider.max = String(view.slider.steps - 1);
      slider.value = String(view.slider.start);
      page.show("gsp");
      await page.drawFaces([$("gsp-slot")], [view.face], state.trial.identity);
      const positions = view.frames.map((/** @type {number[]} */ w, /** @type {number} */ p) => ({ id: p, weights: w }));
      ui.display.keep?.($("gsp-slot"), positions);
    }
    page.facesShown();
    page.setReady(true);
    paint();
    if (!fallback()) slider.focus({ preventScroll: true });
  }

  slider.addEventListener("input", () => {
    if (ui.loading || ui.state.view.waiting) return;
    chosen = Number(slider.value);
    morph(chosen);
    paint();
  });

  slider.addEventListener("keydown", (event) => {
    if (event.key === "Enter") {
      event.preventDefault();
      send();
    }
  }, { signal: page.signal });

  $("gsp-strip").addEventListener("click", (event) => {
    const button = event.target.closest("button");
    if (!button || ui.busy || !page.ready()) return;
    chosen = Number(button.dataset.position);
    for (const b of $("gsp-strip").querySelectorAll("button")) {
      b.setAttribute("aria-pressed", b === button ? "true" : "false");
    }
    paint();
  });

  $("gsp-next").addEventListener("click", send);

  return { render, paint };
}

// ---- where the participant is: one screen, one answer ------------------------------------------
const screen = () => "gsp";
const progress = () => ({ step: null, within: 0 });
/** The heading: the block's prompt, or without WebGL a request for a picture. @param {any} state */
const prompt = (state) =>
  pictures && !state.view.waiting
    ? `Choose the picture where the face looks most ${String(state.view.emotion).toUpperCase()}`
    : null;
/** The word the slider is for: "next: HAPPY". @param {any} state */
const upcoming = (state) => String(state.view.emotion).toUpperCase();

// ---- the jsPsych plugin's data -----------------------------------------------------------------
/** The trial's data fields (jsPsych types by name) and their values before the trial. */
const data = {
  /** The slider's start and the position chosen (0 … steps − 1), its gene value, and whether
   * it was chosen from the strip of pictures (no WebGL). */
  slider_start: { type: "INT", value: null },
  position: { type: "INT", value: null },
  value: { type: "FLOAT", value: null },
  fallback: { type: "BOOL", value: null },
  /** Face drawn → answer sent (ms), and the face's drawing time. */
  response_rt: { type: "INT", value: null },
  load_ms: { type: "INT", value: null },
};

/**
 * The answer the server accepted, added to the trial's data.
 * @param {any} data
 * @param {any} body
 * @param {any} view
 */
function record(data, body, view) {
  if (body.command !== "slide") return;
  data.slider_start = view.slider ? view.slider.start : null;
  data.position = body.position;
  data.fallback = Boolean(body.fallback);
  data.response_rt = body.response_ms ?? null;
  data.load_ms = body.load_ms ?? null;
}

/** The trial record's result: the concept, the value chosen and the chosen face's weights. @param {any} result */
const result = (result) => ({
  emotion: result.emotion,
  value: result.value,
  final_face_id: null,
  final_weights: result.weights,
});

/**
 * The simulated observer at the screen: the slider moved to ``position`` (default: the middle)
 * with input events, or that picture of the strip, then Next.
 * @param {string} _shown the screen
 * @param {any} state
 * @param {{ root: HTMLElement, click: (selector: string | Element | null | undefined) => void }} act
 * @param {{ position?: number }} options
 */
function drive(_shown, state, act, { position }) {
  const view = state.view;
  if (view.waiting) return; // the page asks again by itself
  const want = position ?? Math.floor(view.slider.steps / 2);
  const slider = /** @type {HTMLInputElement | null} */ (act.root.querySelector("#gsp-slider"));
  if (slider && !slider.hidden) {
    slider.value = String(want);
    slider.dispatchEvent(new Event("input", { bubbles: true }));
  } else {
    const nearest = [...view.strip].sort((a, b) => Math.abs(a - want) - Math.abs(b - want))[0];
    act.click(act.root.querySelector(`#gsp-strip button[data-position="${nearest}"]`));
  }
  act.click("#gsp-next");
}

/**
 * A trial's data without a server (the plugin's data-only simulate): a slider of ``steps``
 * positions (the block's, from ``shows``) starting at random; the observer picks the position
 * nearest ``target`` (a number 0 … 1 along the slider; weights given for the other tasks are
 * no slider position: the middle then); ``value`` on the block's slider range. No face: the
 * chain's face is the server's.
 * @param {{ shows?: any, steps?: number, target?: unknown, seed?: number, median_rt?: number }} options
 */
export function simulate({ shows, steps = shows?.steps ?? 41, target, seed = 1, median_rt = 3000 }) {
  const random = uniform(seed);
  const start = Math.floor(random() * steps);
  const along = typeof target === "number" ? Math.min(1, Math.max(0, target)) : 0.5;
  const position = Math.round(along * (steps - 1));
  const [low, high] = shows?.slider ?? [0, 1];
  const rt = responseTime(random, median_rt);
  return {
    slider_start: start, position, value: low + (position / (steps - 1)) * (high - low), fallback: false,
    final_face_id: null, final_weights: null, response_rt: rt, rt,
  };
}

export default {
  name: "gsp",
  markup,
  screens: ["gsp"],
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
