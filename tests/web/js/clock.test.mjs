// Unit tests of the response-time clock both shells share (src/emogen/web/static/tasks/shell.js,
// responseClock): a response is timed to its input event's own time: `node --test tests/web/js/`.
import assert from "node:assert/strict";
import { test } from "node:test";

import { responseClock } from "../../../src/emogen/web/static/tasks/shell.js";

const busy = (ms) => {
  const start = performance.now();
  while (performance.now() - start < ms) {
    // the page is busy
  }
};
/** ``event`` (made now, or given) handled after ``ms`` busy; the response time its handler took. */
function handledLate(root, elapsed, shownAt, ms, event) {
  busy(ms);
  let rt = -1;
  const handler = () => (rt = elapsed(shownAt));
  root.addEventListener(event.type, handler);
  root.dispatchEvent(event);
  root.removeEventListener(event.type, handler);
  return rt;
}
const tick = () => new Promise((resolve) => setTimeout(resolve, 0));

test("a click handled late is timed when it was made", () => {
  const root = new EventTarget();
  const elapsed = responseClock(root);
  const shownAt = performance.now();
  busy(30);
  const click = new Event("click"); // stamped now: the participant clicks
  const rt = handledLate(root, elapsed, shownAt, 200, click);
  assert.equal(rt, Math.round(click.timeStamp - shownAt));
  assert.ok(rt >= 30 && rt < 150, `${rt}`);
});

test("a key press is heard too; a step sent by code is timed to now", async () => {
  const root = new EventTarget();
  const elapsed = responseClock(root);
  const shownAt = performance.now();
  const key = new Event("keydown");
  const rt = handledLate(root, elapsed, shownAt, 100, key);
  assert.equal(rt, Math.round(key.timeStamp - shownAt));
  await tick(); // that input's handlers have run: no input is being handled
  busy(50);
  const now = elapsed(shownAt);
  assert.ok(now >= 150, `${now}`);
});

test("an input stamped before the faces were drawn, or off the page's clock, is timed to now", () => {
  const root = new EventTarget();
  const elapsed = responseClock(root);
  const early = new Event("click");
  busy(20);
  const shownAt = performance.now();
  const rt = handledLate(root, elapsed, shownAt, 40, early);
  assert.ok(rt >= 40, `${rt}`); // not negative, not clamped to 0
  const epoch = new Event("click");
  Object.defineProperty(epoch, "timeStamp", { value: Date.now() }); // older browsers' epoch ms
  const later = handledLate(root, elapsed, shownAt, 0, epoch);
  assert.ok(later >= 40 && later < 10_000, `${later}`);
});

test("other events are not responses; the clock stops listening when its signal aborts", () => {
  const root = new EventTarget();
  const stop = new AbortController();
  const elapsed = responseClock(root, stop.signal);
  const shownAt = performance.now();
  const moved = handledLate(root, elapsed, shownAt, 60, new Event("input"));
  assert.ok(moved >= 60, `${moved}`);
  stop.abort();
  const rt = handledLate(root, elapsed, shownAt, 60, new Event("click"));
  assert.ok(rt >= 120, `${rt}`);
});
