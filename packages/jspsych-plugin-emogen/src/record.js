// The trial's data, as jsPsych stores it: what the page showed and the participant chose, step
// by step (only steps the server accepted), and the trial's record from the server (the
// researcher's session id, the seeds, the final face) — the same rows `emogen study export`
// writes, so the two can be joined on session_id and trial.

/**
 * The data of a trial before it starts (a failed trial keeps what it had).
 * @param {string} task
 * @param {string} server
 */
export function emptyData(task, server) {
  return {
    task,
    success: true,
    reason: /** @type {string | null} */ (null),
    failure: /** @type {string | null} */ (null),
    simulated: false,
    server,
    study: /** @type {string | null} */ (null),
    session_id: /** @type {number | null} */ (null),
    participant_id: /** @type {string | null} */ (null),
    token: /** @type {string | undefined} */ (undefined),
    trial: /** @type {number | null} */ (null),
    block: /** @type {number | null} */ (null),
    block_name: /** @type {string | null} */ (null),
    emotion: /** @type {string | null} */ (null),
    identity: /** @type {string | null} */ (null),
    display: /** @type {string | null} */ (null),
    seed: /** @type {string | null} */ (null),
    session_seed: /** @type {string | null} */ (null),
    attempt: /** @type {number | null} */ (null),
    /** evolve: one entry per generation answered: {attempt, generation, shown, elite, others, rt, load_ms} */
    generations: /** @type {any[]} */ ([]),
    /** evolve: "Start again" presses: {attempt, generation, rt} */
    restarts: /** @type {any[]} */ ([]),
    rating: /** @type {number | null} */ (null),
    rating_rt: /** @type {number | null} */ (null),
    /** categorise: the labels offered, in the order shown */
    labels: /** @type {string[] | null} */ (null),
    label: /** @type {string | null} */ (null),
    intensity: /** @type {number | null} */ (null),
    confidence: /** @type {number | null} */ (null),
    /** categorise: face drawn → answer sent (ms), and the face's drawing time */
    response_rt: /** @type {number | null} */ (null),
    load_ms: /** @type {number | null} */ (null),
    final_face_id: /** @type {number | null} */ (null),
    final_weights: /** @type {number[] | null} */ (null),
    first_faces_ms: /** @type {number | null} */ (null),
    rt: /** @type {number | null} */ (null),
  };
}

/**
 * A step the server accepted, recorded from its body and the state it answered.
 * @param {ReturnType<typeof emptyData>} data
 * @param {string} kind select | restart | rating | categorise
 * @param {any} body
 * @param {any} state the state the step answered (what the page showed)
 */
export function recordStep(data, kind, body, state) {
  if (kind === "select") {
    data.generations.push({
      attempt: body.attempt,
      generation: body.generation,
      shown: state.population.faces.map((/** @type {any} */ f) => f.id),
      elite: body.elite,
      others: [...body.others],
      rt: body.response_ms ?? null,
      load_ms: body.load_ms ?? null,
    });
  } else if (kind === "restart") {
    data.restarts.push({ attempt: body.attempt, generation: body.generation, rt: body.response_ms ?? null });
  } else if (kind === "rating") {
    data.rating = body.value;
    data.rating_rt = body.response_ms ?? null;
  } else if (kind === "categorise") {
    const view = state.categorise;
    data.labels = view.none_option ? [...view.labels, "none"] : [...view.labels];
    data.label = body.label;
    data.intensity = body.intensity ?? null;
    data.confidence = body.confidence ?? null;
    data.response_rt = body.response_ms ?? null;
    data.load_ms = body.load_ms ?? null;
  }
}

/**
 * The server's record of the finished trial, added to its data.
 * @param {ReturnType<typeof emptyData>} data
 * @param {any} record GET /api/s/{token}/trials/{n}
 */
export function withRecord(data, record) {
  Object.assign(data, {
    session_id: record.session_id,
    participant_id: record.participant_id,
    study: record.study,
    trial: record.trial,
    block: record.block,
    block_name: record.block_name,
    emotion: record.emotion || null,
    identity: record.identity,
    seed: record.seed,
    session_seed: record.session_seed,
    attempt: record.attempt,
    final_face_id: record.final_face ? record.final_face.id : null,
    final_weights: record.final_face ? record.final_face.weights : null,
  });
  return data;
}
