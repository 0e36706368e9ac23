// The plugin under jsPsych's own test utilities (@jspsych/test-utils) in a jsdom page, against
// a scripted study server (test/fake-server.mjs): an evolve and a categorise trial end to end
// with their data, one session for both; each wrong use (a study without the block, the server
// gone mid-trial, an origin the server does not allow) ends the trial as data with its reason,
// said in the page; simulate() in data-only mode.
import { window } from "./dom.mjs";
import assert from "node:assert/strict";
import { beforeEach, test } from "node:test";
import { clickTarget, simulateTimeline, startTimeline } from "@jspsych/test-utils";
import { ParameterType } from "jspsych";
import EmogenPlugin from "../src/index.js";
import { forgetSessions } from "../src/connect.js";
import { distance, uniform } from "../../../src/emogen/web/static/observer.js";
import { TASK_NAMES } from "../../../src/emogen/web/static/tasks/index.js";
import { SERVER, fakeServer } from "./fake-server.mjs";

/** Waits (up to 5 s) until ``check()`` is true. */
async function until(check, what) {
  for (let i = 0; i < 500; i++) {
    if (check()) return;
    await new Promise((r) => setTimeout(r, 10));
  }
  assert.fail(`waited 5 s for ${what}`);
}

const root = () => document.querySelector(".emogen-trial");

/** A row of jsPsych's data with the plugin's names unprefixed (``emogen_label`` → ``label``). */
const plain = (row) => Object.fromEntries(Object.entries(row).map(([k, v]) => [k.replace(/^emogen_/, ""), v]));
/** Every row of a timeline's data, unprefixed. */
const rows = (data) => data.values().map(plain);
const ready = (stage) => () =>
  root() && root().dataset.emogenStage === stage && root().dataset.emogenReady === "true";

let fake;
beforeEach(() => {
  document.body.innerHTML = ""; // an earlier test's page gone
  forgetSessions();
  sessionStorage.clear();
  fake = fakeServer();
  globalThis.fetch = fake.fetch;
});

async function chooseAndNext(first, second) {
  await until(ready("trial"), "the faces");
  const cells = [...document.querySelectorAll("#grid > .cell")];
  await clickTarget(cells[first].querySelector(".face"));
  await clickTarget(cells[second].querySelector(".face"));
  await clickTarget(document.querySelector("#next"));
}

/** The fake's evolve trial: faces 2 (best) and 5, then 0 and 9, then rating 5. */
async function evolveTrial() {
  await chooseAndNext(2, 5);
  await until(() => document.querySelector("#gen-progress").textContent === "Round 2 of 2", "generation 2");
  await chooseAndNext(0, 9);
  await until(ready("rating"), "the rating");
  const five = document.querySelector('#rating-scale input[value="5"]');
  five.checked = true;
  five.dispatchEvent(new Event("change", { bubbles: true }));
  await clickTarget(document.querySelector("#rate"));
}

test("info declares every parameter and data field with a jsPsych type", () => {
  const { parameters, data, name } = EmogenPlugin.info;
  assert.equal(name, "emogen");
  assert.equal(parameters.server.default, undefined); // required
  assert.deepEqual(parameters.task.options, TASK_NAMES); // every registered task's
  assert.deepEqual(TASK_NAMES.slice(0, 2), ["evolve", "categorise"]);
  const types = new Set(Object.values(ParameterType));
  for (const field of [...Object.values(parameters), ...Object.values(data)]) assert.ok(types.has(field.type));
});

test("an evolve and a categorise trial run on one session; their data are what was chosen", async () => {
  const { getData, expectFinished, displayElement } = await startTimeline([
    { type: EmogenPlugin, server: `${SERVER}/`, task: "evolve" },
    { type: EmogenPlugin, server: SERVER, task: "categorise" },
  ]);
  await evolveTrial();
  await until(ready("categorise"), "the categorise face");
  assert.deepEqual([...displayElement.querySelectorAll("#label-buttons button")].map((b) => b.dataset.label), ["sad", "happy"]);
  await clickTarget(displayElement.querySelector('#label-buttons button[data-label="happy"]'));
  await until(() => getData().count() === 2, "both trials' data");
  await expectFinishedOk(expectFinished);

  const raw = getData().values();
  const [evolve, categorise] = rows(getData());
  assert.equal(fake.sessions, 1); // one session for both trials
  const steps = fake.log.filter((r) => r.method === "POST" && r.path.startsWith("/api/s/"));
  assert.ok(steps.every((r) => r.path === `/api/s/${"t".repeat(20)}/step`)); // the one step route
  assert.deepEqual(steps.map((r) => r.body.command), ["begin", "select", "select", "rate", "answer"]);
  assert.equal(fake.participant, "node-participant"); // PROLIFIC_PID from the page's URL
  // the creation key: the server's pattern, kept for the session (a lost answer's retry gets it)
  const create = fake.log.find((r) => r.path === "/api/sessions").body;
  assert.match(create.create_key, /^[A-Za-z0-9_-]{16,64}$/);
  assert.equal(sessionStorage.getItem(`emogen-plugin:${SERVER}:node-participant:create-key`), create.create_key);
  assert.equal(evolve.success, true);
  assert.equal(evolve.reason, null);
  assert.equal(evolve.session_id, 7);
  assert.equal(evolve.participant_id, "node-participant");
  assert.equal(evolve.seed, "12345678901234567890"); // exact: a string
  assert.deepEqual(evolve.generations.map((g) => [g.generation, g.elite, g.others]), [[0, 2, [5]], [1, 10, [19]]]);
  assert.deepEqual(evolve.generations[1].shown, [10, 11, 12, 13, 14, 15, 16, 17, 18, 19]);
  const sent = steps.filter((r) => r.body.command === "select").map((r) => r.body);
  assert.deepEqual(evolve.generations.map((g) => g.rt), sent.map((b) => b.response_ms));
  assert.equal(evolve.rating, 5);
  assert.deepEqual(evolve.final_weights, [0.3, 0.7, 0.5]);
  assert.equal(evolve.final_face_id, 99);
  assert.equal(evolve.emotion, "happy"); // from the trial record's evolve result
  assert.equal(evolve.display, "png");
  // every evolve step says the server's images showed its faces (recorded with the step)
  assert.deepEqual(evolveBodies(steps).map((b) => b.fallback), [true, true, true]);
  assert.ok(evolve.first_faces_ms >= 0 && evolve.duration_ms >= evolve.first_faces_ms);
  // rt: jsPsych's response time — the trial's responses' times summed (loading excluded)
  const evolveSteps = steps.filter((r) => ["select", "rate"].includes(r.body.command));
  assert.equal(evolve.rt, evolveSteps.reduce((t, r) => t + r.body.response_ms, 0));
  assert.equal(categorise.rt, categorise.response_rt);
  assert.equal(categorise.success, true);
  assert.equal(categorise.label, "happy");
  assert.deepEqual(categorise.labels, ["sad", "happy"]);
  assert.equal(categorise.trial, 1);
  assert.equal(categorise.final_face_id, null); // the face shown is no GA face: no id
  assert.deepEqual(categorise.final_weights, [0.4, 0.6, 0.5]);
  assert.equal(categorise.emotion, null); // never the emotion the face was made for
  assert.deepEqual(steps.at(-1).body, {
    command: "answer", key: steps.at(-1).body.key, trial: 1, label: "happy", intensity: null, confidence: null,
    response_ms: categorise.response_rt, load_ms: categorise.load_ms,
  });
  assert.ok(!("token" in evolve) || evolve.token === undefined); // the session's secret stays out
  const jspsychOwn = ["trial_type", "trial_index", "plugin_version", "time_elapsed"];
  for (const key of Object.keys(raw[0]).filter((k) => !jspsychOwn.includes(k))) {
    assert.ok(key in EmogenPlugin.info.data, `data field '${key}' is declared in info.data`);
    assert.ok(key === "rt" || key.startsWith("emogen_"), `data field '${key}' is namespaced`);
  }
});

async function expectFinishedOk(expectFinished) {
  const { expect } = await import("./expect.mjs");
  globalThis.expect = expect;
  await expectFinished();
}

async function failedTrial(params, what) {
  const { getData } = await startTimeline([{ type: EmogenPlugin, server: SERVER, patience_ms: 500, ...params }]);
  await until(() => root() && root().dataset.emogenStage === "failed", what);
  const shown = document.querySelector("#failed-reason").textContent;
  await clickTarget(document.querySelector("#failed-continue"));
  await until(() => getData().count() === 1, "the failed trial's data");
  return { data: rows(getData())[0], shown };
}

/** What a participant reads where the reason is the researcher's. */
const NOT_YOUR_FAULT = /could not be shown\. This is not your fault/;
const CONNECTION_LOST = /The connection to the study was lost.*What you did so far is saved/;

test("a study without that block: the trial fails with its reason, in the page and the data", async () => {
  fake = fakeServer({ blocks: ["evolve"] });
  globalThis.fetch = fake.fetch;
  const { data, shown } = await failedTrial({ task: "categorise" }, "the failure");
  assert.equal(data.success, false);
  assert.equal(data.failure, "block");
  assert.match(data.reason, /study 'fake' has no categorise block \(its blocks: block1 \(evolve\)\)/);
  assert.match(shown, NOT_YOUR_FAULT); // the participant's words; the reason is the researcher's
  assert.ok(!shown.includes("block"));
  assert.equal(fake.sessions, 0); // nothing made for nothing
});

test("the study's current trial of another task: it runs, the mismatch said once to the researcher", async () => {
  const warned = [];
  const warn = console.warn;
  console.warn = (text) => warned.push(text);
  try {
    const { getData } = await startTimeline([
      { type: EmogenPlugin, server: SERVER, task: "categorise" },
      { type: EmogenPlugin, server: SERVER, task: "evolve" },
    ]);
    await evolveTrial(); // the study's trial 1 is the evolve trial: the first one runs it
    await until(ready("categorise"), "the categorise face, in the timeline's evolve trial");
    await clickTarget(document.querySelector('#label-buttons button[data-label="sad"]'));
    await until(() => getData().count() === 2, "both trials' data");
    const [first, second] = rows(getData());
    assert.deepEqual([first.task, first.timeline_task, first.trial, first.success], ["evolve", "categorise", 0, true]);
    assert.deepEqual([second.task, second.timeline_task, second.trial, second.label], ["categorise", "evolve", 1, "sad"]);
    assert.match(first.warning, /current trial \(trial 1 of 2\) is an evolve trial, where the timeline has a categorise trial/);
    assert.equal(warned.filter((w) => w.includes("where the timeline has")).length, 2); // one per mismatch
  } finally {
    console.warn = warn;
  }
});

/** The fake's evolve trial: faces 1 and 2 chosen, then the server gone as 3 and 4 are sent
 * (past patience_ms: the failure screen). */
async function lostAtGeneration2() {
  await chooseAndNext(1, 2);
  await until(() => document.querySelector("#gen-progress").textContent === "Round 2 of 2", "generation 2");
  await until(ready("trial"), "the faces");
  fake.down = true;
  await chooseAndNext(3, 4);
  await until(() => root().dataset.emogenStage === "failed", "the failure");
}

test("the server gone mid-trial: the trial ends as failed, what was done kept", async () => {
  const { getData } = await startTimeline([{ type: EmogenPlugin, server: SERVER, patience_ms: 500 }]);
  await lostAtGeneration2();
  assert.match(document.querySelector("#failed-reason").textContent, CONNECTION_LOST);
  await clickTarget(document.querySelector("#failed-continue"));
  await until(() => getData().count() === 1, "the data");
  const data = rows(getData())[0];
  assert.equal(data.success, false);
  assert.equal(data.failure, "unreachable");
  assert.match(data.reason, /the study server https:\/\/study\.example\.org cannot be reached/);
  assert.equal(data.generations.length, 1); // the first generation was recorded by the server
  assert.equal(data.generations[0].elite, 1);
  assert.equal(data.session_id, 7); // a failed row carries its session
});

test("a connection lost longer than patience_ms: Try again carries on the same trial, nothing lost", async () => {
  const { getData, expectFinished } = await startTimeline([
    { type: EmogenPlugin, server: SERVER, patience_ms: 500 },
    { type: EmogenPlugin, server: SERVER, task: "categorise" },
  ]);
  await lostAtGeneration2();
  const retry = document.querySelector("#failed-retry");
  assert.equal(retry.hidden, false);
  assert.match(document.querySelector("#failed-next").textContent, /Try again once you are back online/);
  fake.down = false; // the connection is back
  const retried = performance.now();
  await clickTarget(retry);
  await until(ready("trial"), "the same trial again, where the session is");
  assert.equal(document.querySelector("#gen-progress").textContent, "Round 2 of 2");
  // the choice made before the outage (faces 3 and 4) is still chosen: Next sends it
  await clickTarget(document.querySelector("#next"));
  await until(ready("rating"), "the rating");
  const five = document.querySelector('#rating-scale input[value="5"]');
  five.checked = true;
  five.dispatchEvent(new Event("change", { bubbles: true }));
  await clickTarget(document.querySelector("#rate"));
  await until(() => getData().count() === 1, "the evolve trial's row");
  const retriedFor = performance.now() - retried; // the second run's length, at most
  await until(ready("categorise"), "the next trial: the timeline is not one trial short");
  await clickTarget(document.querySelector('#label-buttons button[data-label="happy"]'));
  await until(() => getData().count() === 2, "both trials' data");
  await expectFinishedOk(expectFinished);
  const [evolve, categorise] = rows(getData());
  assert.deepEqual([evolve.success, evolve.tries, evolve.failure], [true, 2, null]);
  // the whole trial's duration, both runs: more than the time since Try again
  assert.ok(evolve.duration_ms > retriedFor, `${evolve.duration_ms} ms, ${retriedFor} ms since Try again`);
  // both runs' steps: generation 0 (first run) and generation 1 (after Try again)
  assert.deepEqual(evolve.generations.map((g) => [g.generation, g.elite, g.others]), [[0, 1, [2]], [1, 13, [14]]]);
  assert.equal(evolve.rating, 5);
  assert.deepEqual([categorise.success, categorise.tries, categorise.label], [true, 1, "happy"]);
});

test("a failure that is not the connection's offers no Try again", async () => {
  fake.refuseOrigin = true;
  const { getData } = await startTimeline([{ type: EmogenPlugin, server: SERVER, patience_ms: 500 }]);
  await until(() => root() && root().dataset.emogenStage === "failed", "the failure");
  assert.equal(document.querySelector("#failed-retry").hidden, true);
  await clickTarget(document.querySelector("#failed-continue"));
  await until(() => getData().count() === 1, "the failed trial's data");
  assert.deepEqual([rows(getData())[0].failure, rows(getData())[0].tries], ["origin", 1]);
});

test("an origin the server does not allow: the reason names the origin and the setting", async () => {
  fake.refuseOrigin = true;
  const { data, shown } = await failedTrial({}, "the failure");
  assert.equal(data.failure, "origin");
  assert.match(data.reason, /does not allow pages of https:\/\/experiments\.example\.org .*embed_origins/);
  assert.match(shown, NOT_YOUR_FAULT);
  assert.ok(!shown.includes("embed_origins")); // researcher's words stay in the data
});

test("faces never drawn: the trial ends at load_timeout_ms, not for ever", async () => {
  const proto = window.HTMLImageElement.prototype;
  const loads = Object.getOwnPropertyDescriptor(proto, "src");
  Object.defineProperty(proto, "src", { set(v) { this.setAttribute("src", v); }, get() { return this.getAttribute("src"); }, configurable: true });
  try {
    const started = Date.now();
    const { data, shown } = await failedTrial({ load_timeout_ms: 300 }, "the failure");
    assert.equal(data.failure, "timeout");
    assert.match(data.reason, /faces were not drawn within 0\.3 s of its start \(load_timeout_ms\)/);
    assert.match(shown, CONNECTION_LOST);
    assert.ok(Date.now() - started < 3000);
    assert.equal(data.session_id, 7);
  } finally {
    Object.defineProperty(proto, "src", loads);
  }
});

test("failure_wait_ms ends a failed trial by itself", async () => {
  fake.down = true;
  const { getData } = await startTimeline([{ type: EmogenPlugin, server: SERVER, patience_ms: 500, failure_wait_ms: 20 }]);
  await until(() => getData().count() === 1, "the data");
  assert.equal(rows(getData())[0].failure, "unreachable");
});

test("a server address that is not one: the failure screen, no request", async () => {
  const { data, shown } = await failedTrial({ server: "study.example.org" }, "the failure screen");
  assert.equal(data.failure, "server");
  assert.match(data.reason, /'server' must be the study server's address \(http\(s\):\/\/host\[:port\]\); got "study\.example\.org"/);
  assert.match(shown, NOT_YOUR_FAULT);
  assert.equal(fake.log.length, 0);
});

/** A study as GET /api/study answers (given to simulate(): no server asked). */
function studyOf({ weights = 5, generations = 8, evolve = 1, categorise = 0, labels = ["happy", "sad"] } = {}) {
  const blocks = [];
  if (evolve) {
    blocks.push({ task: "evolve", trials: evolve, shows: { emotions: ["happy", "sad"], identities: ["a", "b"],
      generations, faces: 6, min_selections: 1, max_selections: 2, rating_points: 9 } });
  }
  if (categorise) {
    blocks.push({ task: "categorise", trials: categorise, shows: { labels, identities: ["a"], none_option: true,
      intensity_points: 5, confidence_points: null } });
  }
  return { name: "given", weight_names: Array.from({ length: weights }, (_, k) => `w${k}`),
    blocks: blocks.map((b, k) => ({ ...b, block: k, name: `block${k + 1}` })) };
}

/** The data-only simulation of ``timeline`` (its rows, jsPsych's clock aside). */
async function simulated(timeline) {
  const { getData } = await simulateTimeline(timeline, "data-only");
  await until(() => getData().count() === timeline.length, "the simulated data");
  return rows(getData()).map(({ time_elapsed: _clock, ...row }) => row);
}

test("simulate data-only: the study's trial, an observer near its target, repeatable", async () => {
  const target = [0.9, 0.1, 0.6, 0.0, 0.3];
  const study = studyOf();
  const run = async (seed) => (await simulated([{ type: EmogenPlugin, server: SERVER, simulation_options: { study, target, seed, chosen: 3 } }]))[0];
  const data = await run(3);
  assert.equal(fake.log.length, 0); // the study given: no server asked
  assert.equal(data.simulated, true);
  assert.equal(data.success, true);
  assert.deepEqual([data.study, data.trial, data.block, data.block_name, data.emotion, data.identity], ["given", 0, 0, "block1", "happy", "a"]);
  assert.equal(data.generations.length, 9); // generations 8 after the first
  for (const g of data.generations) {
    assert.equal(g.shown.length, 6); // the study's faces a generation
    assert.equal(g.others.length, 1); // 3 chosen asked, the study's limit 2
    assert.ok(g.shown.includes(g.elite) && g.others.every((o) => g.shown.includes(o)));
  }
  assert.equal(data.rating, 7); // 70% of the study's 9 points, rounded up
  assert.equal(data.final_weights.length, 5);
  // independent reference: faces drawn as the stand-in GA draws its first ones, 2000 of them
  const random = uniform(99);
  const typical = Array.from({ length: 2000 }, () =>
    distance(target.map(() => (random() < 0.3 ? random() : 0)), target),
  ).sort((a, b) => a - b);
  assert.ok(distance(data.final_weights, target) < typical[100], "the final face is nearer than 95% of random faces");
  assert.deepEqual(await run(3), data);
  assert.notDeepEqual((await run(4)).final_weights, data.final_weights);
});

test("simulate data-only reads GET /api/study: its blocks in order, a warning where the timeline differs", async () => {
  const options = { simulation_options: { target: [0.9, 0.1, 0.6], seed: 5 } };
  const trial = { type: EmogenPlugin, server: SERVER, ...options };
  const [evolve, categorise, past] = await simulated([trial, trial, trial]); // the fake: evolve, categorise
  assert.deepEqual(fake.log.map((r) => r.path), ["/api/study"]); // read once
  assert.equal(evolve.task, "evolve");
  assert.equal(evolve.generations.length, 2); // the fake's generations: 1
  assert.equal(categorise.task, "categorise");
  assert.equal(categorise.timeline_task, "evolve");
  assert.match(categorise.warning, /the study's current trial \(trial 2 of 2\) is a categorise trial, where the timeline has an evolve trial/);
  assert.deepEqual([...categorise.labels].sort(), ["happy", "sad"]);
  assert.equal(categorise.final_weights.length, 3);
  assert.equal(categorise.session_seed, evolve.session_seed); // one session
  assert.notEqual(categorise.seed, evolve.seed);
  assert.deepEqual([past.success, past.failure], [false, "finished"]);
  assert.match(past.reason, /no trial left \(the study has 2\)/);
});

test("simulate data-only: a target or face of the wrong length, a server that is not one: failed rows that say so", async () => {
  const [wrong] = await simulated([{ type: EmogenPlugin, server: SERVER, simulation_options: { study: studyOf(), target: [1, 0] } }]);
  assert.equal(wrong.success, false);
  assert.match(wrong.reason, /simulation target has 2 weights; the study's faces have 5/);
  const [bad] = await simulated([{ type: EmogenPlugin, server: "study.example.org", simulation_options: {} }]);
  assert.deepEqual([bad.success, bad.failure], [false, "server"]);
  const face = [0.2, 0.9];
  const [categorise] = await simulated([{ type: EmogenPlugin, server: SERVER, task: "categorise",
    simulation_options: { study: studyOf({ evolve: 0, categorise: 1 }), face } }]);
  assert.match(categorise.reason, /simulation face has 2 weights; the study's faces have 5/);
});

test("simulate data-only without a seed: trials differ, and jsPsych's seed repeats them", async () => {
  const run = async () => {
    const trial = { type: EmogenPlugin, server: SERVER, simulation_options: { study: studyOf({ weights: 3, generations: 2, evolve: 2 }), target: [0.9, 0.1, 0.6] } };
    return (await simulated([trial, trial])).map((r) => r.final_weights);
  };
  const { initJsPsych } = await import("jspsych");
  const seeded = async (seed) => {
    initJsPsych().randomization.setSeed(seed);
    return run();
  };
  const [first, second] = await seeded("forty");
  assert.notDeepEqual(first, second); // each trial its own data
  assert.deepEqual(await seeded("forty"), [first, second]);
  assert.notDeepEqual(await seeded("other"), [first, second]);
});

test("simulate data-only categorise: the study's labels, none of these, the label of the nearest prototype", async () => {
  const study = studyOf({ weights: 2, evolve: 0, categorise: 1, labels: ["happy", "sad", "angry"] });
  const [data] = await simulated([{ type: EmogenPlugin, server: SERVER, task: "categorise",
    simulation_options: { study, prototypes: { happy: [1, 0], sad: [0, 1] }, face: [0.2, 0.9] } }]);
  assert.equal(data.label, "sad");
  assert.deepEqual(data.final_weights, [0.2, 0.9]);
  assert.equal(data.final_face_id, null);
  assert.equal(data.labels.at(-1), "none"); // "none of these" last, as on the screen
  assert.deepEqual(data.labels.slice(0, 3).sort(), ["angry", "happy", "sad"]);
  assert.equal(data.intensity, 3); // the middle of the study's 5 points
  assert.equal(data.confidence, null); // not asked
});

test("simulate visual: the tasks' observers drive the real screens through the step route", async () => {
  const simulation_options = { target: [0.9, 0.1, 0.5], chosen: 2, rating: 6, label: "sad", delay_ms: 0 };
  const { getData } = await simulateTimeline([
    { type: EmogenPlugin, server: SERVER, task: "evolve", simulation_options },
    { type: EmogenPlugin, server: SERVER, task: "categorise", simulation_options },
  ], "visual");
  await until(() => getData().count() === 2, "both simulated trials' data");
  const [evolve, categorise] = rows(getData());
  assert.equal(evolve.success, true);
  assert.equal(evolve.simulated, true);
  assert.equal(fake.log.find((r) => r.path === "/api/sessions").body.simulated, true); // marked in the export
  // the faces nearest the target (face k has weights [k/10, 1 - k/10, 0.5]): 9 then 8
  assert.deepEqual(evolve.generations.map((g) => [g.elite, g.others]), [[9, [8]], [19, [18]]]);
  assert.equal(evolve.rating, 6);
  assert.equal(categorise.success, true);
  assert.equal(categorise.label, "sad");
  const commands = fake.log.filter((r) => r.path.endsWith("/step")).map((r) => r.body.command);
  assert.deepEqual(commands, ["begin", "select", "select", "rate", "answer"]);
});

/** The bodies of the evolve steps sent (select, restart, rate), in order. @param {any[]} steps */
function evolveBodies(steps) {
  return steps.map((r) => r.body).filter((b) => ["select", "restart", "rate"].includes(b.command));
}
