// The categorise task's page component: one face (the same display, identity and framing as the
// GA's tiles, larger) and the study's emotion labels in the order the server drew; optionally an
// intensity and a confidence rating. Number keys 1-9 choose a label. Without ratings a label
// press sends the answer; with them, Continue does once every rating is given. What the shells
// ask of a task: see ./evolve.js's header; the rules of an answer: ./answer.js.
import { newKey } from "../api.js";
import { distance, randomFace, responseTime, uniform } from "../observer.js";
import * as answers from "./answer.js";

const markup = `
  <section id="view-categorise" class="view categorise" hidden aria-labelledby="prompt">
    <div class="categorise-face" data-viewer-container><div class="slot big" id="categorise-slot"></div></div>
    <form id="categorise-form" class="categorise-form">
      <fieldset>
        <legend class="sr-only">Emotions (number keys choose one)</legend>
        <div class="labels" id="label-buttons"></div>
      </fieldset>
      <fieldset id="intensity-set" hidden>
        <legend id="intensity-question">&nbsp;</legend>
        <div class="scale" id="intensity-scale"></div>
        <div class="scale-labels"><span id="intensity-low"></span><span id="intensity-high"></span></div>
      </fieldset>
      <fieldset id="confidence-set" hidden>
        <legend id="confidence-question">&nbsp;</legend>
        <div class="scale" id="confidence-scale"></div>
        <div class="scale-labels"><span id="confidence-low"></span><span id="confidence-high"></span></div>
      </fieldset>
      <p id="categorise-status" class="status" aria-live="polite">&nbsp;</p>
      <div class="actions-row"><button id="answer" class="primary" type="submit" disabled>Continue</button></div>
    </form>
  </section>
`;

/** @param {any} page the shell's context (session.js: `page`) */
function create(page) {
  const { $, ui } = page;
  /** @type {import("../answer.js").Answer} */
  let answer = answers.emptyAnswer();

  function storageKey() {
    return `emogen-cat:${page.token}:${ui.state.progress.trial}`;
  }

  // The answer in progress is kept in sessionStorage (with its step key) until sent, so a
  // reload keeps it and a resend after a lost answer is recognised by the server.
  function save() {
    try {
      sessionStorage.setItem(storageKey(), JSON.stringify({ ...answer, key: ui.key }));
    } catch {
      /* storage unavailable: fine */
    }
  }

  function restore(view) {
    ui.key = newKey();
    answer = answers.emptyAnswer();
    let saved = null;
    try {
      saved = JSON.parse(sessionStorage.getItem(storageKey()) || "null");
    } catch {
      /* storage unavailable or garbled: start afresh */
    }
    if (!saved || typeof saved !== "object") return;
    const labels = answers.options(view).map((o) => o.label);
    const points = (view.intensity || view.confidence || { points: 0 }).points;
    const rating = (v) => (Number.isInteger(v) && v >= 1 && v <= points ? v : null);
    if (labels.includes(saved.label)) answer.label = saved.label;
    answer.intensity = view.intensity ? rating(saved.intensity) : null;
    answer.confidence = view.confidence ? rating(saved.confidence) : null;
    if (typeof saved.key === "string") ui.key = saved.key;
  }

  function buildLabels(view) {
    const box = $("label-buttons");
    box.replaceChildren();
    for (const o of answers.options(view)) {
      const button = document.createElement("button");
      button.type = "button";
      button.className = o.label === answers.NONE ? "label-option none" : "label-option";
      button.dataset.label = o.label;
      button.setAttribute("aria-pressed", "false");
      if (o.key) {
        const key = document.createElement("span");
        key.className = "key";
        key.setAttribute("aria-hidden", "true");
        key.textContent = o.key;
        button.appendChild(key);
        button.setAttribute("aria-keyshortcuts", o.key);
      }
      const text = document.createElement("span");
      text.textContent = o.text;
      button.appendChild(text);
      box.appendChild(button);
    }
  }

  function buildScale(name, scale) {
    $(`${name}-set`).hidden = !scale;
    if (!scale) return;
    $(`${name}-question`).textContent = scale.question;
    $(`${name}-low`).textContent = `1 = ${scale.low_label}`;
    $(`${name}-high`).textContent = `${scale.points} = ${scale.high_label}`;
    page.fillScale($(`${name}-scale`), name, scale.points);
  }

  function paint() {
    const state = ui.state;
    if (!(state && state.stage === "trial" && state.view.task === "categorise")) return;
    const view = state.view;
    for (const button of $("label-buttons").querySelectorAll("button")) {
      const chosen = button.dataset.label === answer.label;
      button.setAttribute("aria-pressed", chosen ? "true" : "false");
      button.disabled = ui.busy || ui.loading;
    }
    const intensity = answers.asksIntensity(view, answer);
    $("intensity-set").hidden = !view.intensity || answer.label === null || !intensity;
    $("confidence-set").hidden = !view.confidence || answer.label === null;
    for (const [name, value] of [["intensity", answer.intensity], ["confidence", answer.confidence]]) {
      for (const input of $(`${name}-scale`).querySelectorAll("input")) {
        input.checked = Number(input.value) === value;
        input.disabled = ui.busy;
      }
    }
    const once = answers.answersAtOnce(view);
    $("answer").hidden = once;
    $("answer").disabled = ui.busy || ui.loading || !answers.complete(view, answer);
    $("answer").textContent = ui.busy ? "Saving…" : "Continue";
    $("categorise-status").textContent = ui.busy
      ? "Saving your answer…"
      : ui.loading
        ? "Loading the face: please wait until it appears."
        : answers.missing(view, answer);
  }

  function send() {
    const view = ui.state.view;
    if (ui.busy || !page.ready() || !answers.complete(view, answer)) return;
    page.step(answers.answerBody(ui.state, answer, ui.key, page.elapsed(), ui.loadMs));
  }

  function chooseLabel(label) {
    if (ui.busy || !page.ready() || label === null) return;
    const view = ui.state.view;
    const first = answer.label === null;
    answer.label = label;
    if (!answers.asksIntensity(view, answer)) answer.intensity = null;
    page.say("");
    save();
    paint();
    if (answers.answersAtOnce(view)) send();
    // the ratings appear with the first label chosen: bring them into view (a phone)
    else if (first) $("answer").scrollIntoView({ block: "nearest", behavior: "smooth" });
  }

  async function render(state) {
    const view = state.view;
    buildLabels(view);
    buildScale("intensity", view.intensity);
    buildScale("confidence", view.confidence);
    restore(view);
    page.show("categorise");
    page.setReady(false);
    ui.loading = true;
    paint();
    await page.drawFaces([$("categorise-slot")], [view.face], state.trial.identity);
    page.facesShown();
    page.setReady(true);
    paint();
    const first = $("label-buttons").querySelector("button");
    if (first && !answer.label) first.focus({ preventScroll: true });
  }

  $("label-buttons").addEventListener("click", (event) => {
    const button = event.target.closest("button");
    if (button) chooseLabel(button.dataset.label);
  });

  for (const name of ["intensity", "confidence"]) {
    $(`${name}-scale`).addEventListener("change", (event) => {
      answer[name] = Number(event.target.value);
      save();
      paint();
    });
  }

  $("categorise-form").addEventListener("submit", (event) => {
    event.preventDefault();
    send();
  });

  // Number keys choose a label; in a rating scale, they give that rating (not while typing
  // in a field, nor with a modifier held). ``page.signal`` (the plugin's trial) removes it.
  document.addEventListener("keydown", (event) => {
    if (page.stage() !== "categorise" || event.ctrlKey || event.metaKey || event.altKey) return;
    const target = event.target;
    if (target instanceof HTMLInputElement && target.type === "radio") {
      const input = target.closest(".scale")?.querySelector(`input[value="${event.key}"]`);
      if (input instanceof HTMLInputElement && !ui.busy) {
        event.preventDefault();
        input.checked = true;
        input.focus();
        input.dispatchEvent(new Event("change", { bubbles: true }));
      }
      return;
    }
    if (target instanceof HTMLInputElement || target instanceof HTMLTextAreaElement) return;
    const label = answers.labelForKey(ui.state.view, event.key);
    if (label === null) return;
    event.preventDefault();
    chooseLabel(label);
  }, { signal: page.signal });

  return { render, paint };
}

// ---- where the participant is: one screen, no step within the trial ---------------------------
const screen = () => "categorise";
const progress = () => ({ step: null, within: 0 });
const prompt = () => null;
/** The pause does not give the answer away: it says what to do. */
const upcoming = () => "name the emotion";

// ---- the jsPsych plugin's data -----------------------------------------------------------------
/** The trial's data fields (jsPsych types by name) and their values before the trial. */
const data = {
  /** The labels offered, in the order shown ("none": "none of these"). */
  labels: { type: "STRING", array: true, value: null },
  label: { type: "STRING", value: null },
  intensity: { type: "INT", value: null },
  confidence: { type: "INT", value: null },
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
  if (body.command !== "answer") return;
  data.labels = answers.options(view).map((o) => o.label);
  data.label = body.label;
  data.intensity = body.intensity ?? null;
  data.confidence = body.confidence ?? null;
  data.response_rt = body.response_ms ?? null;
  data.load_ms = body.load_ms ?? null;
}

/** The trial record's result: the face shown (its weights; no face id: it is no GA face). @param {any} result */
const result = (result) => ({ label: result.label, final_face_id: null, final_weights: result.weights });

/**
 * The simulated observer at the screen: the label asked for (else the first), the middle of
 * each rating scale shown, then Continue where there is one.
 * @param {string} _shown the screen
 * @param {any} state
 * @param {{ root: HTMLElement, click: (selector: string | Element | null | undefined) => void,
 *   check: (scale: string, value: number) => void }} act
 * @param {{ label?: string }} options
 */
function drive(_shown, state, act, { label }) {
  const view = state.view;
  const buttons = Array.from(act.root.querySelectorAll("#label-buttons button"));
  act.click(buttons.find((b) => /** @type {HTMLElement} */ (b).dataset.label === label) ?? buttons[0]);
  const middle = (/** @type {any} */ s) => Math.ceil(s.points / 2);
  if (view.intensity && !act.root.querySelector("#intensity-set")?.hasAttribute("hidden")) {
    act.check("intensity-scale", middle(view.intensity));
  }
  if (view.confidence) act.check("confidence-scale", middle(view.confidence));
  const button = /** @type {HTMLButtonElement | null} */ (act.root.querySelector("#answer"));
  if (button && !button.hidden && !button.disabled) button.click();
}

/**
 * A trial's data without a server (the plugin's data-only simulate): ``shows``' labels (GET
 * /api/study: the block's) offered in an order drawn for the trial, the face (``face`` as given,
 * else a random one of the study's ``weight_names``), its label — the nearest of ``prototypes``
 * (label → weights) where given, else ``label`` where offered, else one drawn at random — and
 * the middle of each rating scale the block asks.
 * @param {{ shows: any, weight_names: string[], index?: number, prototypes?: Record<string, number[]>,
 *   face?: number[], label?: string, seed?: number, median_rt?: number }} options
 */
export function simulate({ shows, weight_names, index = 0, prototypes, face, label, seed = 1, median_rt = 2500 }) {
  const random = uniform(seed);
  const offered = [...shows.labels];
  for (let i = offered.length - 1; i > 0; i--) {
    const k = Math.floor(random() * (i + 1));
    [offered[i], offered[k]] = [offered[k], offered[i]];
  }
  const labels = answers.options({ labels: offered, none_option: shows.none_option }).map((o) => o.label);
  if (face && face.length !== weight_names.length) {
    throw new Error(`simulation face has ${face.length} weights; the study's faces have ${weight_names.length} (GET /api/study: weight_names)`);
  }
  const weights = face ?? randomFace(random, weight_names.length);
  let chosen = label !== undefined && labels.includes(label) ? label : labels[Math.floor(random() * labels.length)];
  if (prototypes) {
    const known = labels.filter((l) => l in prototypes);
    known.sort((x, y) => distance(weights, prototypes[x]) - distance(weights, prototypes[y]));
    chosen = known[0] ?? chosen;
  }
  const middle = (/** @type {number | null} */ points) => (points ? Math.ceil(points / 2) : null);
  const rt = responseTime(random, median_rt);
  return {
    identity: shows.identities[index % shows.identities.length],
    labels, label: chosen,
    intensity: chosen === answers.NONE ? null : middle(shows.intensity_points),
    confidence: middle(shows.confidence_points),
    final_face_id: null, final_weights: weights, response_rt: rt, load_ms: 0, rt,
  };
}

export default {
  name: "categorise",
  markup,
  screens: ["categorise"],
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
