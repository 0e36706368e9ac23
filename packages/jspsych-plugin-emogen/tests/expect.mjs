// The one piece of jest's `expect` that @jspsych/test-utils' expectFinished() uses.
import assert from "node:assert/strict";

export function expect(actual) {
  return { toBe: (expected) => assert.equal(actual, expected) };
}
