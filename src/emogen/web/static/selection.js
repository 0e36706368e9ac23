// The participant page's state handling, free of the DOM (unit-tested with `node --test`):
// which view a session state shows, and the selection a participant builds in a generation.
// Types come from the server's OpenAPI schema (api-types.d.ts, generated; see tests/web/test_js.py).

/** @typedef {import("./api-types").components["schemas"]["SessionState"]} SessionState */
/** @typedef {import("./api-types").components["schemas"]["Limits"]} Limits */
/** @typedef {import("./api-types").components["schemas"]["Selection"]} SelectionBody */
/** @typedef {"instructions" | "trial" | "rating" | "categorise" | "done"} View */

/**
 * A selection in progress: the best face (elite) and the others, in the order chosen.
 * @typedef {{ elite: number | null, others: number[] }} Choice
 */

/**
 * The view a state shows: an evolve trial shows its faces ("trial"), or its rating once it waits
 * for one; a categorise trial shows its face and labels.
 * @param {SessionState} state
 * @returns {View}
 */
export function viewOf(state) {
  if (state.stage === "trial") {
    if (!state.trial) throw new Error("a state in stage 'trial' must carry its trial");
    if (state.trial.task === "categorise") {
      if (!state.categorise) throw new Error("a categorise trial's state must carry its face");
      return "categorise";
    }
    return state.trial.status === "rating" ? "rating" : "trial";
  }
  return state.stage;
}

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
 * The body of the select step for the generation shown in ``state``.
 * @param {SessionState} state
 * @param {Choice} choice
 * @param {string} key
 * @param {number} responseMs
 * @param {number} [loadMs] the page's time from receiving this population to its faces drawn
 * @returns {SelectionBody}
 */
export function selectionBody(state, choice, key, responseMs, loadMs) {
  if (!state.trial || choice.elite === null) {
    throw new Error("a selection needs a trial and a best face");
  }
  return {
    key,
    trial: state.progress.trial,
    attempt: state.trial.attempt,
    generation: state.progress.generation,
    elite: choice.elite,
    others: [...choice.others],
    response_ms: responseMs,
    ...(loadMs === undefined ? {} : { load_ms: loadMs }),
  };
}
