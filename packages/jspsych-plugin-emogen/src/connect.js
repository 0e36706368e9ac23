// The plugin's link to the study server: the study's blocks, the participant's session (made
// once per page and participant, resumed after a reload or, where the study resumes by
// participant id, in another tab), and failures said in words a researcher understands (the
// participant's words are run.js's). The requests are the study page's own (static/api.js:
// retries with backoff, 429s waited out, each try's timeout and the request's deadline).
import { api, ApiError } from "../../../src/emogen/web/static/api.js";

/**
 * How long requests may take: ``timeoutMs`` one try, ``patienceMs`` the request with its retries.
 * @typedef {{ timeoutMs: number, patienceMs: number }} Timing
 */

/** A failure the trial records as data (success false) and says in the page. */
export class TrialFailure extends Error {
  /**
   * @param {string} reason a sentence for the researcher's data (and the browser's console)
   * @param {string} kind "unreachable" | "timeout" | "origin" | "block" | "server" | "resume" |
   *   "other-tab" | "finished"
   * @param {number} [status] the server's HTTP status, where it answered
   */
  constructor(reason, kind, status = 0) {
    super(reason);
    this.kind = kind;
    this.status = status;
  }
}

/** The server's origin without a trailing slash ("https://study.example.org"). */
export function serverBase(server) {
  if (typeof server !== "string" || !/^https?:\/\/[^/]+/.test(server)) {
    throw new TrialFailure(
      `the emogen trial's 'server' must be the study server's address (http(s)://host[:port]); got ${JSON.stringify(server)}`,
      "server",
    );
  }
  return server.replace(/\/+$/, "");
}

/**
 * Whether the server answers at all, asked without CORS (an opaque answer): a server that
 * answers this but not the API does not allow this page's origin.
 * @param {string} base
 */
async function answersAtAll(base) {
  try {
    await fetch(`${base}/healthz`, { mode: "no-cors", cache: "no-store", signal: AbortSignal.timeout(5000) });
    return true;
  } catch {
    return false;
  }
}

/**
 * A request to the study server; a failure becomes a {@link TrialFailure} naming what went wrong.
 * @param {string} base
 * @param {string} path
 * @param {import("../../../src/emogen/web/static/api.js").ApiOptions} options
 */
export async function request(base, path, options = {}) {
  const started = Date.now();
  try {
    return await api(`${base}${path}`, options);
  } catch (err) {
    if (!(err instanceof ApiError)) throw err;
    if (err.status === 0 && err.timedOut) {
      const seconds = Math.round((Date.now() - started) / 1000);
      const route = path.replace(/^\/api\/s\/[^/]+/, "/api/s/…"); // the session's secret stays out
      throw new TrialFailure(
        `the study server ${base} did not answer ${route} within ${seconds} s (the connection was taken, no answer came)`,
        "timeout",
      );
    }
    if (err.status === 0) {
      const origin = globalThis.location ? location.origin : "this page";
      if (await answersAtAll(base)) {
        throw new TrialFailure(
          `the study server ${base} does not allow pages of ${origin} to use it: add "${origin}" to embed_origins in its study config`,
          "origin",
        );
      }
      throw new TrialFailure(`the study server ${base} cannot be reached`, "unreachable");
    }
    throw new TrialFailure(`the study server ${base} answered ${err.status}: ${err.message}`, "server", err.status);
  }
}

/**
 * The participant id from the page's URL, as the study's own consent page takes it: the
 * study's parameter (e.g. Prolific's PROLIFIC_PID), else ``participant``; under JATOS, the
 * study link's query (``jatos.urlQueryParameters``) too. null: none (the server makes one).
 * @param {string} param
 */
export function participantFromUrl(param) {
  const params = new URLSearchParams(globalThis.location ? location.search : "");
  const jatos = /** @type {any} */ (globalThis).jatos;
  const fromJatos = (name) =>
    jatos && jatos.urlQueryParameters && typeof jatos.urlQueryParameters[name] === "string"
      ? jatos.urlQueryParameters[name]
      : null;
  for (const name of [param, "participant"]) {
    const value = params.get(name) || fromJatos(name);
    if (value) return value;
  }
  return null;
}

/**
 * A participant's session as this page holds it: ``used`` once a trial has shown its first
 * state; ``sessionId`` the researcher's id (export: ``session_id``), for every row, failed ones
 * too; ``takenOver`` once another tab of this browser opened the same participant's session
 * (its trials then end, saying so; ``listeners`` hear of it).
 * @typedef {{ token: string, state: any, used: boolean, sessionId: number | null,
 *   takenOver: boolean, listeners: Set<() => void>, channel: BroadcastChannel | null }} Held
 */

/** @type {Map<string, Promise<any>>} */
const studies = new Map();
/** @type {Map<string, Promise<Held>>} */
const sessions = new Map();
/** @type {Set<BroadcastChannel>} */
const channels = new Set();

/** @param {string} base @param {Timing} timing */
export function studyInfo(base, timing) {
  if (!studies.has(base)) {
    const got = request(base, "/api/study", { retries: Infinity, ...timing });
    studies.set(base, got);
    got.catch(() => studies.delete(base)); // asked afresh by the next trial
  }
  return /** @type {Promise<any>} */ (studies.get(base));
}

function storageKey(base, participant) {
  return `emogen-plugin:${base}:${participant ?? "anonymous"}`;
}

function remembered(key) {
  try {
    return sessionStorage.getItem(key);
  } catch {
    return null;
  }
}

/**
 * The page's creation key for this participant's session: made once, kept with the session,
 * sent with every try, so that a create whose answer was lost (a dropped connection, a proxy
 * timeout) is answered with the same session instead of "already has a session".
 * @param {string} key
 */
function createKey(key) {
  const name = `${key}:create-key`;
  let made = remembered(name);
  if (!made) {
    const bytes = crypto.getRandomValues(new Uint8Array(18));
    made = btoa(String.fromCharCode(...bytes)).replace(/\+/g, "-").replace(/\//g, "_");
    try {
      sessionStorage.setItem(name, made);
    } catch {
      /* storage unavailable: the key lives as long as the page */
    }
  }
  return made;
}

/**
 * Tells this browser's other tabs that this one now holds the participant's session, and
 * listens for a later tab saying the same (the older tab gives way: two tabs never step
 * the same session at once). Without BroadcastChannel: nothing (the server still refuses a
 * stale step, 409, and the trial shows the server's state).
 * @param {string} key
 * @param {Held} held
 */
function holdAgainstOtherTabs(key, held) {
  if (typeof BroadcastChannel === "undefined") return;
  const channel = new BroadcastChannel(key);
  /** @type {any} */ (channel).unref?.(); // Node (the plugin's tests): keeps no process alive
  channels.add(channel);
  channel.onmessage = (event) => {
    if (!event.data || !event.data.opened) return;
    held.takenOver = true;
    for (const listener of held.listeners) listener();
  };
  channel.postMessage({ opened: Date.now() });
  held.channel = channel;
}

/**
 * The participant's session on this server: made by the first emogen trial of the page (the
 * instructions step taken: the experiment's own timeline instructs), the same for the
 * following trials, resumed after a reload of the page — or, in a study that resumes by
 * participant id (``resume = "participant_id"``), when the link is opened again.
 * @param {string} base
 * @param {string | null} participant
 * @param {Timing & { onLink?: (link: any) => void, simulated?: boolean }} options
 *   ``simulated``: simulate()'s visual mode (the export marks the session simulated)
 * @returns {Promise<Held>}
 */
export function session(base, participant, { onLink, simulated = false, ...timing }) {
  const key = storageKey(base, participant);
  if (!sessions.has(key)) {
    const made = (async () => {
      const created = await request(base, "/api/sessions", {
        method: "POST",
        body: { participant_id: participant, resume_token: remembered(key), create_key: createKey(key), simulated },
        waitIfCrowded: true,
        retries: Infinity,
        ...timing,
        onLink,
      }).catch((err) => {
        throw err instanceof TrialFailure && err.status === 409 ? heldElsewhere(err) : err;
      });
      try {
        sessionStorage.setItem(key, created.token);
      } catch {
        /* storage unavailable: this page still holds the session */
      }
      /** @type {Held} */
      const held = {
        token: created.token, state: created.state, used: false, sessionId: null,
        takenOver: false, listeners: new Set(), channel: null,
      };
      // the researcher's session id, for every row of the page (a failed one too)
      const record = await request(base, `/api/s/${created.token}/trials/0`, { retries: Infinity, ...timing }).catch(() => null);
      held.sessionId = record ? record.session_id : null;
      if (participant !== null) holdAgainstOtherTabs(key, held);
      return held;
    })();
    sessions.set(key, made);
    made.catch(() => sessions.delete(key));
  }
  return /** @type {Promise<Held>} */ (sessions.get(key));
}

/**
 * A 409 on making the session: the participant's session is held by another browser (or a
 * tab whose storage this one lacks) and the study resumes only by the session's link.
 * @param {TrialFailure} err
 */
function heldElsewhere(err) {
  return new TrialFailure(
    `${err.message.replace(/^the study server [^ ]+ answered 409: /, "")} — the study resumes a session only in the browser tab that began it; set resume = "participant_id" in the study config to let a reopened link continue it (docs/jspsych.md)`,
    "resume",
    409,
  );
}

/** Forget the sessions and studies this page knows (tests; a new participant on a kiosk). */
export function forgetSessions() {
  sessions.clear();
  studies.clear();
  for (const channel of channels) channel.close();
  channels.clear();
}
