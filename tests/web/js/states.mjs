// A participant's session state as the server sends it (SessionState, API v2: the view keyed by
// task), for the page's unit tests: a GA trial in its first round unless ``over`` (top-level
// fields), ``trial`` (the trial's fields) and ``view`` (the view's fields) say otherwise.
export function sessionState(over = {}, trial = {}, view = {}) {
  return {
    stage: "trial",
    participant_id: "p",
    progress: { trial: 0, trials: 8, block: 0, blocks: 1 },
    trial: { position: 0, block: 0, task: "evolve", prompt: "Make the face look SAD",
             identity: "generic", attempt: 0, status: "active", ...trial },
    view: { task: "evolve", emotion: "sad", generation: 0, generations: 10,
            limits: { min_selections: 1, max_selections: 4 }, allow_restart: false,
            population: null, rating: null, ...view },
    completion: null,
    ...over,
  };
}

/** A categorise trial's state: its view (``view``'s fields over a plain one) and ``over``. */
export function categoriseState(view = {}, over = {}, trial = {}) {
  return sessionState(
    {
      view: { task: "categorise", question: "Which emotion?", face: { id: 0, weights: [0.1, 0.2] },
              labels: ["sad", "happy", "fearful"], none_option: false, intensity: null, confidence: null, ...view },
      ...over,
    },
    { task: "categorise", prompt: "Which emotion?", ...trial },
  );
}
