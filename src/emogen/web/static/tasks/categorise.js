// The categorise task's screen: one face (the same display, identity and framing as the GA's
// tiles, larger) and the study's emotion labels in the order the server drew; optionally an
// intensity and a confidence rating. Number keys 1-9 choose a label. Without ratings a label
// press sends the answer; with them, Continue does once every rating is given. The rules are
// in ../answer.js; the page's shell (session.js) gives this component its context.
import { newKey } from "../api.js";
import * as answers from "../answer.js";

/** @param {any} page the shell's context (session.js: `page`) */
export function createCategorise(page) {
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
    if (!(state && state.stage === "trial" && state.trial.task === "categorise")) return;
    const view = state.categorise;
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
    const view = ui.state.categorise;
    if (ui.busy || !page.ready() || !answers.complete(view, answer)) return;
    page.step("categorise", answers.answerBody(ui.state, answer, ui.key, page.elapsed(), ui.loadMs));
  }

  function chooseLabel(label) {
    if (ui.busy || !page.ready() || label === null) return;
    const view = ui.state.categorise;
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
    const view = state.categorise;
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
    const label = answers.labelForKey(ui.state.categorise, event.key);
    if (label === null) return;
    event.preventDefault();
    chooseLabel(label);
  }, { signal: page.signal });

  return { views: ["categorise"], render, paint };
}
