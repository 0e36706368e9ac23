// JSON requests to the study server, retried on network errors and 503 (same idempotency key).

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
 * @typedef {{ method?: string, body?: unknown, retries?: number, headers?: Record<string, string> }} ApiOptions
 */

/**
 * A JSON request; errors (status >= 400) throw an {@link ApiError} with the server's message.
 * @param {string} path
 * @param {ApiOptions} [options]
 * @returns {Promise<any>}
 */
export async function api(path, { method = "GET", body, retries = 4, headers = {} } = {}) {
  /** @type {ApiError | undefined} */
  let lastError;
  for (let attempt = 0; attempt <= retries; attempt++) {
    let response;
    try {
      response = await fetch(path, {
        method,
        headers: body === undefined ? headers : { "Content-Type": "application/json", ...headers },
        body: body === undefined ? undefined : JSON.stringify(body),
        cache: "no-store",
      });
    } catch {
      lastError = new ApiError(0, "The connection to the study server was lost; retrying…");
      await sleep(400 * 2 ** attempt);
      continue;
    }
    if (response.status === 503 && attempt < retries) {
      lastError = new ApiError(503, "The server is busy; retrying…");
      await sleep(400 * 2 ** attempt);
      continue;
    }
    let data;
    try {
      data = await response.json();
    } catch {
      data = null;
    }
    if (!response.ok) {
      const detail = data && typeof data.detail === "string" ? data.detail : response.statusText;
      throw new ApiError(response.status, detail);
    }
    return data;
  }
  throw lastError;
}

export function newKey() {
  if (globalThis.crypto && crypto.randomUUID) return crypto.randomUUID();
  const bytes = new Uint8Array(16);
  crypto.getRandomValues(bytes);
  return Array.from(bytes, (b) => b.toString(16).padStart(2, "0")).join("");
}
