// JSON requests to the study server, retried with the same request (and so the same idempotency
// key) on lost connections and busy answers, with capped exponential backoff (connection.js);
// a request that may meet the server's per-address limit (429) waits as Retry-After asks.
import { ONLINE, crowded, failed, retryAfterMs, retryable } from "./connection.js";

/** An answer other than 2xx: its HTTP status (0: no connection) and the server's ``detail``. */
export class ApiError extends Error {
  /**
   * @param {number} status
   * @param {string} message
   */
  constructor(status, message) {
    super(message);
    this.status = status;
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
 * changed nothing when refused (creating a session).
 * @typedef {{
 *   method?: string,
 *   body?: unknown,
 *   retries?: number,
 *   waitIfCrowded?: boolean,
 *   headers?: Record<string, string>,
 *   onLink?: (link: import("./connection.js").Link) => void,
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
  { method = "GET", body, retries = 4, waitIfCrowded = false, headers = {}, onLink } = {},
) {
  /** @type {import("./connection.js").Link} */
  let link = ONLINE;
  let failures = 0; // lost connections and busy answers (a crowded wait is not one)
  for (;;) {
    let response;
    try {
      response = await fetch(path, {
        method,
        headers: body === undefined ? headers : { "Content-Type": "application/json", ...headers },
        body: body === undefined ? undefined : JSON.stringify(body),
        cache: "no-store",
      });
    } catch {
      response = null;
    }
    const status = response ? response.status : 0;
    if (status === 429 && waitIfCrowded && response) {
      const now = Date.now();
      link = crowded(link, retryAfterMs(response.headers.get("Retry-After"), now), now);
      if (onLink) onLink(link);
      await sleep(Math.max(0, link.retryAt - Date.now()));
      continue;
    }
    if (retryable(status)) {
      if (failures++ >= retries) {
        if (onLink) onLink(ONLINE);
        throw new ApiError(
          status,
          status === 0
            ? "The study server cannot be reached. Check your connection and try again."
            : "The study server is busy. Please try again in a minute.",
        );
      }
      link = failed(link, status, Date.now());
      if (onLink) onLink(link);
      await sleep(Math.max(0, link.retryAt - Date.now()));
      continue;
    }
    if (link.kind !== "online" && onLink) onLink(ONLINE);
    const answer = /** @type {Response} */ (response);
    let data;
    try {
      data = await answer.json();
    } catch {
      data = null;
    }
    if (!answer.ok) {
      const detail = data && typeof data.detail === "string" ? data.detail : answer.statusText;
      throw new ApiError(answer.status, detail);
    }
    return data;
  }
}

export function newKey() {
  if (globalThis.crypto && crypto.randomUUID) return crypto.randomUUID();
  const bytes = new Uint8Array(16);
  crypto.getRandomValues(bytes);
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}
