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
