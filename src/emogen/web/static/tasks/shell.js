// What the shells around the task components share (session.js, the study's own page; the
// jsPsych plugin's trial in packages/jspsych-plugin-emogen): a rating scale's buttons and the
// words of the loading indicator.

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
