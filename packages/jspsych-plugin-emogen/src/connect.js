// The plugin's link to the study server: the study's blocks, the participant's session (made
// once per page and participant, resumed after a reload), and failures said in words a
// participant and a researcher both understand. The requests are the study page's own
// (static/api.js: retries with backoff, 429s waited out).
import { api, ApiError } from "../../../src/emogen/web/static/api.js";

/** A failure the trial records as data (success false) and says in the page. */
export class TrialFailure extends Error {
  /**
   * @param {string} reason a sentence for the researcher's data and the participant's screen
   * @param {string} kind "unreachable" | "origin" | "block" | "server" | "finished"
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
    await fetch(`${base}/healthz`, { mode: "no-cors", cache: "no-store" });
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
  try {
    return await api(`${base}${path}`, options);
  } catch (err) {
    if (!(err instanceof ApiError)) throw err;
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

/** @type {Map<string, Promise<any>>} */
const studies = new Map();
/** @type {Map<string, Promise<{ token: string, state: any, used: boolean }>>} */
const sessions = new Map();

/** @param {string} base */
export function studyInfo(base, retries) {
  if (!studies.has(base)) {
    const got = request(base, "/api/study", { retries });
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
 * The participant's session on this server: made by the first emogen trial of the page (the
 * instructions step taken: the experiment's own timeline instructs), the same for the
 * following trials, resumed after a reload of the page.
 * @param {string} base
 * @param {string | null} participant
 * @param {{ retries: number, onLink?: (link: any) => void }} options
 */
export function session(base, participant, { retries, onLink }) {
  const key = storageKey(base, participant);
  if (!sessions.has(key)) {
    const made = (async () => {
      const created = await request(base, "/api/sessions", {
        method: "POST",
        body: { participant_id: participant, resume_token: remembered(key), create_key: createKey(key) },
        waitIfCrowded: true,
        retries,
        onLink,
      });
      try {
        sessionStorage.setItem(key, created.token);
      } catch {
        /* storage unavailable: this page still holds the session */
      }
      return { token: created.token, state: created.state, used: false };
    })();
    sessions.set(key, made);
    made.catch(() => sessions.delete(key));
  }
  return /** @type {Promise<{ token: string, state: any, used: boolean }>} */ (sessions.get(key));
}

/** Forget the sessions and studies this page knows (tests; a new participant on a kiosk). */
export function forgetSessions() {
  sessions.clear();
  studies.clear();
}
