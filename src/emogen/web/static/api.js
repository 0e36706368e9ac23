// JSON requests to the study server, retried with the same request (and so the same idempotency
// key) on lost connections and busy answers, with capped exponential backoff (connection.js);
// a request that may meet the server's per-address limit (429) waits as Retry-After asks.
import { ONLINE, crowded, failed, retryAfterMs, retryable } from "./connection.js";

/** An answer other than 2xx: its HTTP status (0: no connection) and the server's ``detail``;
 * ``timedOut``: the last try had no answer within its time (the server or a proxy was silent). */
export class ApiError extends Error {
  /**
   * @param {number} status
   * @param {string} message
   * @param {boolean} [timedOut]
   */
  constructor(status, message, timedOut = false) {
    super(message);
    this.status = status;
    this.timedOut = timedOut;
  }
}

/** @param {number} ms */
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

/**
 * `retries`: how many times a lost connection or a busy answer is retried (Infinity: until the
 * server answers); `onLink` hears of each failure (with the time of the next try) and of the
 * answer that ends them, so the page can say what is happening. `waitIfCrowded`: a 429 (too
 * many new sessions from this address, as in a computer room behind one address) is waited out
 * too — as long as the server's `Retry-After` asks, however many times — for a request that
 * changed nothing when refused (creating a session). `timeoutMs`: one try's wait for an answer
 * (a server that accepts the connection and never answers, a frozen proxy) before it counts as
 * a lost connection; `patienceMs`: the request's whole deadline — no try starts or waits past
 * it, so a request never takes longer (Infinity: no deadline).
 * @typedef {{
 *   method?: string,
 *   body?: unknown,
 *   retries?: number,
 *   waitIfCrowded?: boolean,
 *   headers?: Record<string, string>,
 *   onLink?: (link: import("./connection.js").Link) => void,
 *   timeoutMs?: number,
 *   patienceMs?: number,
 * }} ApiOptions
 */

/**
 * A JSON request; errors (status >= 400) throw an {@link ApiError} with the server's message.
 * @param {string} path
 * @param {ApiOptions} [options]
 * @returns {Promise<any>}
 */
export async function api(
  path,
  {
    method = "GET",
    body,
    retries = 4,
    waitIfCrowded = false,
    headers = {},
    onLink,
    timeoutMs = 20_000,
    patienceMs = Infinity,
  } = {},
) {
  /** @type {import("./connection.js").Link} */
  let link = ONLINE;
  let failures = 0; // lost connections and busy answers (a crowded wait is not one)
  const started = Date.now();
  const init = {
    method,
    headers: body === undefined ? headers : { "Content-Type": "application/json", ...headers },
    body: body === undefined ? undefined : JSON.stringify(body),
    cache: /** @type {RequestCache} */ ("no-store"),
  };
  for (;;) {
    const wait = Math.max(0, Math.min(timeoutMs, started + patienceMs - Date.now()));
    const { response, data, timedOut } = await oneTry(path, init, wait);
    const status = response ? response.status : 0;
    if (status === 429 && waitIfCrowded && response) {
      const now = Date.now();
      link = crowded(link, retryAfterMs(response.headers.get("Retry-After"), now), now);
      if (onLink) onLink(link);
      await sleep(Math.max(0, link.retryAt - Date.now()));
      continue;
    }
    if (retryable(status)) {
      const next = failed(link, status, Date.now());
      if (failures++ >= retries || next.retryAt >= started + patienceMs) {
        if (onLink) onLink(ONLINE);
        throw new ApiError(status, unanswered(status, timedOut, Date.now() - started), timedOut);
      }
      link = next;
      if (onLink) onLink(link);
      await sleep(Math.max(0, link.retryAt - Date.now()));
      continue;
    }
    if (link.kind !== "online" && onLink) onLink(ONLINE);
    const answer = /** @type {Response} */ (response);
    if (!answer.ok) {
      const detail = data && typeof data.detail === "string" ? data.detail : answer.statusText;
      throw new ApiError(answer.status, detail);
    }
    return data;
  }
}

/**
 * One try: the answer and its JSON body (null where it has none), both within ``ms`` — a try
 * whose headers or body do not come in time is given up (``timedOut``) like a lost connection.
 * @param {string} path
 * @param {RequestInit} init
 * @param {number} ms
 * @returns {Promise<{ response: Response | null, data: any, timedOut: boolean }>}
 */
async function oneTry(path, init, ms) {
  const timer = new AbortController();
  let timedOut = false;
  const alarm = setTimeout(() => {
    timedOut = true;
    timer.abort();
  }, ms);
  try {
    const response = await fetch(path, { ...init, signal: timer.signal });
    let data = null;
    try {
      data = await response.json();
    } catch {
      if (timedOut) return { response: null, data: null, timedOut };
    }
    return { response, data, timedOut: false };
  } catch {
    return { response: null, data: null, timedOut };
  } finally {
    clearTimeout(alarm);
  }
}

/**
 * Why a request ended without an answer, in words for people.
 * @param {number} status
 * @param {boolean} timedOut
 * @param {number} elapsedMs
 */
function unanswered(status, timedOut, elapsedMs) {
  if (timedOut) return `The study server has not answered for ${Math.round(elapsedMs / 1000)} s.`;
  return status === 0
    ? "The study server cannot be reached. Check your connection and try again."
    : "The study server is busy. Please try again in a minute.";
}

export function newKey() {
  if (globalThis.crypto && crypto.randomUUID) return crypto.randomUUID();
  const bytes = new Uint8Array(16);
  crypto.getRandomValues(bytes);
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}
