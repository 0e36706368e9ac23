// What the shells around the task components share (session.js, the study's own page; the
// jsPsych plugin's trial in packages/jspsych-plugin-emogen): a rating scale's buttons, the
// drawing of faces with its loading indicator, and the response-time clock.

/**
 * A rating scale's radio buttons 1 … points, named ``name``.
 * @param {HTMLElement} scale
 * @param {string} name
 * @param {number} points
 */
export function fillScale(scale, name, points) {
  scale.replaceChildren();
  for (let v = 1; v <= points; v++) {
    const label = document.createElement("label");
    const input = document.createElement("input");
    input.type = "radio";
    input.name = name;
    input.value = String(v);
    const text = document.createElement("span");
    text.textContent = String(v);
    label.append(input, text);
    scale.appendChild(label);
  }
}

/** @param {number} bytes */
function megabytes(bytes) {
  return (bytes / 1e6).toFixed(1);
}

/**
 * What the loading indicator says: images loaded ("faces") or the 3D model's bytes (total 0:
 * the server did not say the size).
 * @param {number} done
 * @param {number} total
 * @param {string} unit
 */
export function loadProgressText(done, total, unit) {
  if (unit === "faces") return `Loading faces: ${done} of ${total}…`;
  return total > 0
    ? `Loading the 3D faces: ${megabytes(done)} of ${megabytes(total)} MB…`
    : `Loading the 3D faces: ${megabytes(done)} MB…`;
}

/**
 * The shell's ``drawFaces(slots, faces, identity)``: the faces drawn by ``ui.display`` while the
 * loading indicator (#load-status, #load-text, #load-bar) says how far it is (shown only when
 * drawing takes over 150 ms); ``ui.loading`` is true meanwhile. ``onProgress`` hears it too.
 * @param {(id: string) => any} $
 * @param {any} ui the shell's state: its display, its session state, its loading flag
 * @param {(done: number, total: number, unit: string) => void} [onProgress]
 */
export function createDrawFaces($, ui, onProgress = () => {}) {
  /** @type {(done: number, total: number, unit: string) => void} */
  const progress = (done, total, unit) => {
    $("load-text").textContent = loadProgressText(done, total, unit);
    const bar = $("load-bar");
    if (total > 0) bar.value = Math.min(1, done / total);
    else bar.removeAttribute("value"); // indeterminate
    $("load-status").hidden = false;
    onProgress(done, total, unit);
  };
  /** @param {HTMLElement[]} slots @param {any[]} faces @param {string} identity */
  return async (slots, faces, identity) => {
    ui.loading = true;
    $("load-text").textContent = "Loading faces…";
    $("load-bar").removeAttribute("value");
    const timer = setTimeout(() => ($("load-status").hidden = false), 150);
    try {
      const where = { trial: ui.state.progress.trial, attempt: ui.state.trial.attempt };
      await ui.display.show(slots, faces, identity, progress, where);
    } finally {
      clearTimeout(timer);
      ui.loading = false;
      $("load-status").hidden = true;
    }
  };
}

/**
 * The shell's response-time clock: ``elapsed(shownAt)`` is the time in ms from ``shownAt`` (the
 * ``performance.now()`` at which the faces were drawn) to the participant's click, tap or key
 * press whose handler is running now, read from that input event's own ``timeStamp`` (when the
 * browser received it), or to now when no input is being handled (a step sent by code). A page
 * busy with other work (building the next identity's model ahead, a slow draw) can hold a click
 * for a second or more before its handler runs; timing from the event keeps that wait out of the
 * response time. Where the browser's event time is not on the page's clock (older browsers gave
 * epoch milliseconds) or falls before ``shownAt``, the handler's time is used, as before.
 * @param {EventTarget} root where the inputs are heard (the document)
 * @param {AbortSignal} [signal] stops listening (a jsPsych trial's end)
 * @returns {(shownAt: number) => number}
 */
export function responseClock(root, signal) {
  /** @type {number | null} */
  let inputAt = null;
  /** @param {Event} event */
  const heard = (event) => {
    const at = event.timeStamp;
    inputAt = at;
    setTimeout(() => {
      if (inputAt === at) inputAt = null; // that input's handlers have all run
    }, 0);
  };
  for (const type of ["click", "keydown"]) root.addEventListener(type, heard, { capture: true, signal });
  return (shownAt) => {
    const now = performance.now();
    const at = inputAt !== null && inputAt >= shownAt && inputAt <= now ? inputAt : now;
    return Math.max(0, Math.round(at - shownAt));
  };
}
