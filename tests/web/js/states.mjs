// A participant's session state as the server sends it (SessionState), for the page's unit
// tests: a GA trial in its first round unless ``over`` (top-level fields) and ``trial`` (the
// trial's fields) say otherwise.
export function sessionState(over = {}, trial = {}) {
  return {
    stage: "trial",
    participant_id: "p",
    progress: { trial: 0, trials: 8, generation: 0, generations: 10, block: 0, blocks: 1 },
    limits: { min_selections: 1, max_selections: 4 },
    allow_restart: false,
    trial: { position: 0, block: 0, task: "evolve", emotion: "sad", prompt: "Make the face look SAD",
             identity: "generic", attempt: 0, status: "active", ...trial },
    population: null,
    rating: null,
    completion: null,
    ...over,
  };
}
