// Unit tests of the page's requests (src/emogen/web/static/api.js) against a stand-in `fetch`:
// a session request that meets the per-address limit (429) waits as Retry-After asks and gets
// in; other requests still fail on a 429. `node --test tests/web/js/`.
import assert from "node:assert/strict";
import { afterEach, test } from "node:test";

import { api } from "../../../src/emogen/web/static/api.js";

const realFetch = globalThis.fetch;
const realRandom = Math.random;
afterEach(() => {
  globalThis.fetch = realFetch;
  Math.random = realRandom;
});

/**
 * A server answering `answers` in turn; records when each request came.
 * @param {Array<{ status: number, headers?: Record<string, string>, json?: unknown }>} answers
 */
function server(answers) {
  /** @type {number[]} */
  const times = [];
  globalThis.fetch = /** @type {any} */ (
    async () => {
      times.push(Date.now());
      const a = answers[Math.min(times.length - 1, answers.length - 1)];
      return new Response(JSON.stringify(a.json ?? { detail: "too many new sessions" }), {
        status: a.status,
        headers: a.headers ?? {},
      });
    }
  );
  return times;
}

test("a 429 is waited out as Retry-After asks, the page told how long, then the session starts", async () => {
  Math.random = () => 0; // no spread: the wait is exactly Retry-After
  const times = server([
    { status: 429, headers: { "Retry-After": "1" } },
    { status: 429, headers: { "Retry-After": "1" } },
    { status: 201, json: { token: "t", url: "/s/t" } },
  ]);
  /** @type {string[]} */
  const heard = [];
  const created = await api("/api/sessions", {
    method: "POST",
    body: {},
    waitIfCrowded: true,
    onLink: (link) => heard.push(link.kind === "online" ? "online" : `${link.kind} ${link.attempt}`),
  });
  assert.deepEqual(created, { token: "t", url: "/s/t" });
  assert.equal(times.length, 3);
  for (const gap of [times[1] - times[0], times[2] - times[1]]) {
    assert.ok(gap >= 995 && gap < 1500, `waited ${gap} ms for Retry-After: 1`);
  }
  assert.deepEqual(heard, ["crowded 0", "crowded 1", "online"]);
});

test("a 429 where waiting is not asked for is an error with the server's sentence", async () => {
  const times = server([{ status: 429, headers: { "Retry-After": "20" } }]);
  await assert.rejects(api("/api/researcher/status"), (err) => {
    assert.equal(/** @type {any} */ (err).status, 429);
    assert.equal(/** @type {Error} */ (err).message, "too many new sessions");
    return true;
  });
  assert.equal(times.length, 1);
});

/** A server that takes every request and never answers (only the request's abort ends it). */
function silent() {
  /** @type {number[]} */
  const times = [];
  globalThis.fetch = /** @type {any} */ (
    (/** @type {string} */ _path, /** @type {RequestInit} */ init) =>
      new Promise((_resolve, reject) => {
        times.push(Date.now());
        init.signal?.addEventListener("abort", () => reject(new DOMException("aborted", "AbortError")));
      })
  );
  return times;
}

test("a server that never answers: each try gives up after timeoutMs, the request at its deadline", async () => {
  const times = silent();
  const t0 = Date.now();
  await assert.rejects(
    api("/api/study", { retries: Infinity, timeoutMs: 300, patienceMs: 2500 }),
    (err) => {
      assert.equal(/** @type {any} */ (err).status, 0);
      assert.equal(/** @type {any} */ (err).timedOut, true);
      assert.match(/** @type {Error} */ (err).message, /has not answered for 2 s/);
      return true;
    },
  );
  const took = Date.now() - t0;
  // tries at 0, 0.3+1, 1.6+2 would start after the deadline: two tries, ended by the deadline
  assert.equal(times.length, 2);
  assert.ok(took >= 1500 && took <= 2600, `the request took ${took} ms; its deadline is 2500 ms`);
});

test("a slow answer within the deadline is retried with the same request and succeeds", async () => {
  let n = 0;
  /** @type {string[]} */
  const bodies = [];
  globalThis.fetch = /** @type {any} */ (
    (/** @type {string} */ _path, /** @type {RequestInit} */ init) => {
      bodies.push(String(init.body));
      if (n++ === 0) {
        return new Promise((_r, reject) => init.signal?.addEventListener("abort", () => reject(new Error("aborted"))));
      }
      return Promise.resolve(new Response(JSON.stringify({ ok: 1 }), { status: 200 }));
    }
  );
  const got = await api("/api/s/t/step", { method: "POST", body: { key: "k1" }, timeoutMs: 200, patienceMs: 5000 });
  assert.deepEqual(got, { ok: 1 });
  assert.deepEqual(bodies, ['{"key":"k1"}', '{"key":"k1"}']); // the same idempotency key
});
