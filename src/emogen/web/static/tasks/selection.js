// The evolve task's rules, free of the DOM (unit-tested with `node --test`): the selection a
// participant builds in a generation, the body of its select step and the round it is in. The
// screens are tasks/evolve.js. Types come from the server's OpenAPI schema (../api-types.d.ts,
// generated; see tests/web/test_js.py).

/** @typedef {import("../api-types").components["schemas"]["SessionState"]} SessionState */
/** @typedef {import("../api-types").components["schemas"]["EvolveView"]} EvolveView */
/** @typedef {import("../api-types").components["schemas"]["Limits"]} Limits */
/** @typedef {import("../api-types").components["schemas"]["Select"]} SelectBody */

/**
 * A selection in progress: the best face (elite) and the others, in the order chosen.
 * @typedef {{ elite: number | null, others: number[] }} Choice
 */

/**
 * How many faces are chosen.
 * @param {Choice} choice
 */
export function count(choice) {
  return (choice.elite === null ? 0 : 1) + choice.others.length;
}

/**
 * Click on a face: unselect it, or add it (as the elite when there is none yet).
 * @param {Choice} choice
 * @param {number} id
 * @param {Limits} limits
 * @returns {{ choice: Choice, refused?: string }}
 */
export function toggle(choice, id, limits) {
  const max = limits.max_selections;
  if (choice.elite === id) return { choice: { elite: null, others: choice.others } };
  if (choice.others.includes(id)) {
    return { choice: { elite: choice.elite, others: choice.others.filter((o) => o !== id) } };
  }
  if (count(choice) >= max) {
    return { choice, refused: `You can choose at most ${max} faces. Remove one first.` };
  }
  if (choice.elite === null) return { choice: { elite: id, others: choice.others } };
  return { choice: { elite: choice.elite, others: [...choice.others, id] } };
}

/**
 * Make a face the elite; the former elite becomes the first of the others while there is room.
 * @param {Choice} choice
 * @param {number} id
 * @param {Limits} limits
 * @returns {{ choice: Choice, refused?: string }}
 */
export function makeBest(choice, id, limits) {
  const max = limits.max_selections;
  if (choice.elite === id) return { choice };
  const wasSelected = choice.others.includes(id);
  if (!wasSelected && count(choice) >= max && choice.elite === null) {
    return { choice, refused: `You can choose at most ${max} faces. Remove one first.` };
  }
  const others = choice.others.filter((o) => o !== id);
  if (choice.elite !== null && count({ elite: id, others }) + 1 <= max) others.unshift(choice.elite);
  return { choice: { elite: id, others } };
}

/**
 * Whether the choice can be sent: an elite and between min and max faces in all.
 * @param {Choice} choice
 * @param {Limits} limits
 */
export function complete(choice, limits) {
  const n = count(choice);
  return choice.elite !== null && n >= limits.min_selections && n <= limits.max_selections;
}

/**
 * A saved choice restored against the faces shown now (unknown or repeated ids dropped).
 * @param {unknown} saved
 * @param {number[]} ids
 * @returns {Choice}
 */
export function restoreChoice(saved, ids) {
  if (!saved || typeof saved !== "object") return { elite: null, others: [] };
  const s = /** @type {{ elite?: unknown, others?: unknown }} */ (saved);
  const elite = typeof s.elite === "number" && ids.includes(s.elite) ? s.elite : null;
  const given = Array.isArray(s.others) ? s.others : [];
  /** @type {number[]} */
  const others = [];
  for (const id of given) {
    if (typeof id === "number" && ids.includes(id) && id !== elite && !others.includes(id)) {
      others.push(id);
    }
  }
  return { elite, others };
}

/**
 * The evolve view of a state in an evolve trial.
 * @param {SessionState} state
 * @returns {EvolveView}
 */
export function evolveView(state) {
  const view = state.view;
  if (!state.trial || !view || view.task !== "evolve") throw new Error("not an evolve trial's state");
  return view;
}

/**
 * The round of a GA trial: ``ga.generations = G`` breeds G generations after the first set
 * of faces, so the participant chooses in G + 1 rounds, generation g being round g + 1.
 * @param {{ generation: number, generations: number }} view
 */
export function roundText(view) {
  return `Round ${view.generation + 1} of ${view.generations + 1}`;
}

/**
 * The body of the select step for the generation shown in ``state``.
 * @param {SessionState} state
 * @param {Choice} choice
 * @param {string} key
 * @param {number} responseMs
 * @param {number} [loadMs] the page's time from receiving this population to its faces drawn
 * @returns {SelectBody}
 */
export function selectionBody(state, choice, key, responseMs, loadMs) {
  const view = evolveView(state);
  if (!state.trial || choice.elite === null) {
    throw new Error("a selection needs a trial and a best face");
  }
  return {
    command: "select",
    key,
    trial: state.progress.trial,
    attempt: state.trial.attempt,
    generation: view.generation,
    elite: choice.elite,
    others: [...choice.others],
    response_ms: responseMs,
    ...(loadMs === undefined ? {} : { load_ms: loadMs }),
  };
}
