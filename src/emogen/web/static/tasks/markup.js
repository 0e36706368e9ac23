// The task components' screens (evolve: the ten-face grid and the rating; categorise: one face
// and its labels), as markup the page inserts before its components start: the study's own page
// (session.js) and the jsPsych plugin (packages/jspsych-plugin-emogen) show the same screens.
// Ids are the components' handles (tasks/evolve.js, tasks/categorise.js).

export const TASK_VIEWS = `
  <section id="view-trial" class="view" hidden aria-labelledby="prompt">
    <p id="grid-help" class="sr-only">Faces. Tab or the arrow keys move between faces; Enter or Space selects a face or removes it; B makes the focused face the best one.</p>
    <div id="grid" class="grid" data-viewer-container role="group" aria-describedby="grid-help"></div>
    <div class="actions">
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
        <legend id="rating-question" class="sr-only">&nbsp;</legend>
        <div class="scale" id="rating-scale"></div>
        <div class="scale-labels"><span id="rating-low"></span><span id="rating-high"></span></div>
      </fieldset>
      <div class="actions-row"><button id="rate" class="primary" type="submit" disabled>Continue</button></div>
    </form>
  </section>

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

/** The load indicator and the message line the shells share (drawFaces, say). */
export const STATUS_LINES = `
  <p id="load-status" class="load-status" role="status" aria-live="polite" hidden><span id="load-text">Loading faces…</span><progress id="load-bar" max="1"></progress></p>
  <p id="message" class="message" role="alert" aria-live="assertive"></p>`;
