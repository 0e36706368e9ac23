// What the shells around the task components (the study's own page, session.js; the jsPsych
// plugin, packages/jspsych-plugin-emogen) show around every task's screens (each task's own
// markup: tasks/<task>.js, gathered by tasks/index.js).

/** The load indicator and the message line the shells share (drawFaces, say). */
export const STATUS_LINES = `
  <p id="load-status" class="load-status" role="status" aria-live="polite" hidden><span id="load-text">Loading faces…</span><progress id="load-bar" max="1"></progress></p>
  <p id="message" class="message" role="alert" aria-live="assertive"></p>`;
