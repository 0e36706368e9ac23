// The link to the study server, free of the DOM (unit-tested with `node --test`): which answers
// are worth retrying, how long to wait before the next try (exponential backoff, capped; after a
// 429, what the server's Retry-After asks), and what the page says meanwhile. api.js drives
// these; session.js and landing.js show `statusText`.

/**
 * The backoff: the n-th retry (0-based) waits `baseMs * 2**n`, never more than `capMs`.
 * @typedef {{ baseMs: number, capMs: number }} Backoff
 */

/**
 * The link as the page knows it. `attempt` counts the failures in a row; `retryAt` is when the
 * next try starts (ms, the same clock as `now` in the functions below).
 * `crowded`: the server limits new sessions per address and many people behind this one (a
 * computer room) are starting at once (429).
 * @typedef {{ kind: "offline" | "busy" | "crowded", attempt: number, retryAt: number }} Trouble
 * @typedef {{ kind: "online" } | Trouble} Link
 */

/** @type {Backoff} */
export const BACKOFF = Object.freeze({ baseMs: 1000, capMs: 30_000 });

/** @type {Link} */
export const ONLINE = Object.freeze({ kind: "online" });

/**
 * The wait before retry number `attempt` (0-based): 1 s, 2 s, 4 s, … up to the cap.
 * @param {number} attempt
 * @param {Backoff} [policy]
 */
export function retryDelay(attempt, policy = BACKOFF) {
  if (!Number.isInteger(attempt) || attempt < 0) {
    throw new Error(`attempt must be a non-negative integer; got ${attempt}`);
  }
  return Math.min(policy.capMs, policy.baseMs * 2 ** Math.min(attempt, 30));
}

/**
 * Whether an answer (HTTP status; 0: no answer at all) is worth the same request again:
 * no connection, a proxy that could not reach the server, or a busy server.
 * @param {number} status
 */
export function retryable(status) {
  return status === 0 || status === 502 || status === 503 || status === 504;
}

/**
 * The link after a failed try with `status` at time `now`: one more failure in a row, and the
 * time of the next try.
 * @param {Link} link
 * @param {number} status
 * @param {number} now
 * @param {Backoff} [policy]
 * @returns {Trouble}
 */
export function failed(link, status, now, policy = BACKOFF) {
  const attempt = link.kind === "online" ? 0 : link.attempt + 1;
  const kind = status === 0 || status === 502 || status === 504 ? "offline" : "busy";
  return { kind, attempt, retryAt: now + retryDelay(attempt, policy) };
}

/**
 * The wait a 429's `Retry-After` header asks for, in ms: delta-seconds ("12") or an HTTP date
 * (IMF-fixdate, counted from `now`); null when the header is absent or unreadable.
 * @param {string | null | undefined} header
 * @param {number} now
 */
export function retryAfterMs(header, now) {
  const text = (header ?? "").trim();
  if (text === "") return null;
  if (/^\d+$/.test(text)) return Number(text) * 1000;
  if (!/^[A-Za-z]{3}, /.test(text)) return null; // an HTTP date: "Thu, 26 Nov 2026 12:00:07 GMT"
  const at = Date.parse(text);
  return Number.isNaN(at) ? null : Math.max(0, at - now);
}

/**
 * The link after a 429 at time `now`: wait what the server asked (`waitMs`, from Retry-After;
 * else the backoff), plus a share of it drawn by `random` (at most `capMs` more), so that a
 * room's pages, all told the same wait, do not come back in the same instant.
 * @param {Link} link
 * @param {number | null} waitMs
 * @param {number} now
 * @param {() => number} [random]
 * @param {Backoff} [policy]
 * @returns {Trouble}
 */
export function crowded(link, waitMs, now, random = Math.random, policy = BACKOFF) {
  const attempt = link.kind === "online" ? 0 : link.attempt + 1;
  const wait = waitMs ?? retryDelay(attempt, policy);
  const spread = Math.min(wait, policy.capMs) * random();
  return { kind: "crowded", attempt, retryAt: now + wait + Math.round(spread) };
}

/**
 * What the page says about the link at time `now` ("" when there is nothing to say).
 * @param {Link} link
 * @param {number} now
 */
export function statusText(link, now) {
  if (link.kind === "online") return "";
  const seconds = Math.ceil((link.retryAt - now) / 1000);
  if (link.kind === "crowded") {
    const when = seconds > 0 ? `you will be in in ${seconds} s.` : "getting you in now…";
    return `Many people are starting at once — ${when}`;
  }
  const what = link.kind === "offline" ? "Connection lost" : "The study server is busy";
  const when = seconds > 0 ? `retrying in ${seconds} s…` : "retrying now…";
  return `${what} — ${when} Your choices are kept.`;
}
