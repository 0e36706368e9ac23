// Unit tests of the page's connection policy (src/emogen/web/static/connection.js):
// `node --test tests/web/js/` (run by `make test`).
import assert from "node:assert/strict";
import { test } from "node:test";

import {
  BACKOFF,
  ONLINE,
  crowded,
  failed,
  retryAfterMs,
  retryDelay,
  retryable,
  statusText,
} from "../../../src/emogen/web/static/connection.js";

test("the backoff doubles from 1 s and stops at 30 s", () => {
  const waits = Array.from({ length: 8 }, (_, n) => retryDelay(n));
  assert.deepEqual(waits, [1000, 2000, 4000, 8000, 16000, 30000, 30000, 30000]);
  assert.equal(retryDelay(1000), BACKOFF.capMs); // no overflow to Infinity or NaN
  assert.equal(retryDelay(2, { baseMs: 100, capMs: 250 }), 250);
  assert.throws(() => retryDelay(-1), /non-negative integer; got -1/);
});

test("lost connections and busy answers are retried; other answers are not", () => {
  for (const s of [0, 502, 503, 504]) assert.equal(retryable(s), true, String(s));
  for (const s of [200, 400, 404, 409, 413, 422, 500]) assert.equal(retryable(s), false, String(s));
});

test("failures in a row count up and schedule the next try; any answer ends them", () => {
  let link = failed(ONLINE, 0, 10_000);
  assert.deepEqual(link, { kind: "offline", attempt: 0, retryAt: 11_000 });
  link = failed(link, 0, 11_000);
  assert.deepEqual(link, { kind: "offline", attempt: 1, retryAt: 13_000 });
  link = failed(link, 503, 13_000);
  assert.deepEqual(link, { kind: "busy", attempt: 2, retryAt: 17_000 });
  // the retries never stop: after many failures the wait stays at the cap
  for (let i = 0; i < 50; i++) link = failed(link, 0, 0);
  assert.equal(link.kind === "online" ? -1 : link.retryAt, 30_000);
});

test("the message says at once that the connection is lost and when the next try is", () => {
  const link = failed(ONLINE, 0, 0);
  assert.equal(statusText(ONLINE, 0), "");
  const t = (/** @type {number} */ now, over = {}) => statusText({ ...link, ...over }, now);
  assert.match(t(0), /^Connection lost — retrying in 1 s…/);
  assert.match(t(0, { retryAt: 8000 }), /retrying in 8 s…/);
  assert.match(t(7200, { retryAt: 8000 }), /retrying in 1 s…/); // rounded up, never "0 s"
  assert.match(t(8000, { retryAt: 8000 }), /retrying now…/);
  assert.match(statusText(failed(ONLINE, 503, 0), 0), /^The study server is busy — retrying in 1 s…/);
});

test("Retry-After is read as seconds or as an HTTP date; anything else is no answer", () => {
  assert.equal(retryAfterMs("12", 0), 12_000);
  assert.equal(retryAfterMs(" 3 ", 0), 3000);
  const now = Date.parse("Thu, 26 Nov 2026 12:00:00 GMT");
  assert.equal(retryAfterMs("Thu, 26 Nov 2026 12:00:07 GMT", now), 7000);
  assert.equal(retryAfterMs("Thu, 26 Nov 2026 11:59:00 GMT", now), 0); // already past: now
  for (const h of [null, undefined, "", "soon", "-5", "1.5"]) assert.equal(retryAfterMs(h, 0), null);
});

test("a 429 waits what Retry-After asks, never less, spread so a room does not return at once", () => {
  assert.deepEqual(crowded(ONLINE, 4000, 10_000, () => 0), {
    kind: "crowded",
    attempt: 0,
    retryAt: 14_000,
  });
  // the spread adds at most the wait itself (and never more than the backoff's cap)
  assert.equal(crowded(ONLINE, 4000, 10_000, () => 0.5).retryAt, 16_000);
  assert.equal(crowded(ONLINE, 120_000, 0, () => 0.999_999).retryAt, 150_000);
  const waits = Array.from({ length: 60 }, (_, i) => crowded(ONLINE, 2000, 0, () => i / 60).retryAt);
  assert.ok(waits.every((w) => w >= 2000 && w < 4000));
  assert.equal(new Set(waits).size, 60); // 60 pages told "2 s" come back at 60 different times
  // without Retry-After: the backoff, counting up
  let link = crowded(ONLINE, null, 0, () => 0);
  assert.equal(link.retryAt, 1000);
  link = crowded(link, null, 0, () => 0);
  assert.deepEqual(link, { kind: "crowded", attempt: 1, retryAt: 2000 });
});

test("while crowded the page says many people are starting and counts down to getting in", () => {
  const link = crowded(ONLINE, 9000, 0, () => 0);
  assert.equal(statusText(link, 0), "Many people are starting at once — you will be in in 9 s.");
  assert.equal(statusText(link, 8100), "Many people are starting at once — you will be in in 1 s.");
  assert.equal(statusText(link, 9000), "Many people are starting at once — getting you in now…");
});
