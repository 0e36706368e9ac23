// A scripted stand-in for the study server's participant API v2 (the real one is driven by
// tests/web/test_jspsych_browser.py): one step route whose body names its command (its fields
// exactly: others are refused, 422; a command the trial's task does not take, 409), the view
// keyed by task, the trial record's result keyed by task; sessions of an evolve trial (two
// generations, then a rating) and a categorise trial. It records every request, and can go
// down (fetch rejects) or refuse this page's origin (CORS: only a no-cors probe gets through).
const SERVER = "https://study.example.org";

const TIMES = ["response_ms", "load_ms"];
const POSITION = ["key", "trial", "attempt", "generation"];
/** Each command's fields (besides "command"), as the API's command union has them. */
const COMMANDS = {
  begin: ["key"],
  select: [...POSITION, "elite", "others", ...TIMES, "fallback"],
  restart: [...POSITION, ...TIMES, "fallback"],
  rate: ["key", "trial", "value", "response_ms", "fallback"],
  answer: ["key", "trial", "label", "intensity", "confidence", ...TIMES],
};
const ACCEPTS = { evolve: ["select", "restart", "rate"], categorise: ["answer"] };

function face(id, k) {
  return { id, weights: [k / 10, 1 - k / 10, 0.5] };
}

export function fakeServer({ blocks = ["evolve", "categorise"], generations = 1 } = {}) {
  const log = [];
  const fake = { log, down: false, refuseOrigin: false, sessions: 0 };
  const s = { stage: "instructions", position: 0, generation: 0, status: "active", labels: {} };
  const tasks = blocks;

  /** What GET /api/study says each block shows (as the views below show it). */
  const shows = {
    evolve: { emotions: ["happy"], identities: ["generic"], generations, faces: 10, min_selections: 2, max_selections: 3, rating_points: 7 },
    categorise: { labels: ["sad", "happy"], identities: ["generic"], none_option: false, intensity_points: null, confidence_points: null },
  };

  function view(task) {
    if (task === "evolve") {
      return {
        task, emotion: "happy", generation: s.generation, generations,
        limits: { min_selections: 2, max_selections: 3 }, allow_restart: true,
        population: s.status === "active"
          ? { attempt: 0, generation: s.generation, faces: Array.from({ length: 10 }, (_, k) => face(10 * s.generation + k, k)) }
          : null,
        rating: s.status === "rating"
          ? { question: "How well?", low_label: "not", high_label: "perfectly", points: 7, face: face(99, 3) }
          : null,
      };
    }
    return { task, face: face(0, 4), labels: ["sad", "happy"], none_option: false, question: "Which emotion does this face show?",
      intensity: null, confidence: null };
  }

  function state() {
    const task = tasks[s.position];
    const done = s.stage === "done";
    const base = {
      stage: s.stage, participant_id: fake.participant,
      progress: { trial: done ? tasks.length - 1 : s.position, trials: tasks.length,
        block: done ? tasks.length - 1 : s.position, blocks: tasks.length },
      trial: null, view: null, completion: done ? { message: "Thanks", code: null, redirect_url: null } : null,
    };
    if (s.stage !== "trial") return base;
    base.trial = { position: s.position, block: s.position, task,
      prompt: task === "evolve" ? "Make the face look HAPPY" : "Which emotion does this face show?",
      identity: "generic", attempt: 0, status: s.status };
    base.view = view(task);
    return base;
  }

  function next() {
    s.position += 1;
    s.generation = 0;
    s.status = "active";
    if (s.position >= tasks.length) s.stage = "done";
  }

  /** The step route: the command's fields exactly (others refused, 422), accepted by the trial's task (else 409). */
  function step(body) {
    const fields = COMMANDS[body.command];
    if (!fields) return [422, { detail: `unknown command ${body.command}` }];
    const extra = Object.keys(body).filter((k) => k !== "command" && !fields.includes(k));
    if (extra.length) return [422, { detail: `extra fields: ${extra.join(", ")}` }];
    const task = tasks[s.position];
    if (body.command === "begin") {
      if (s.stage !== "instructions") return [409, { detail: "already begun" }];
      s.stage = "trial";
    } else if (s.stage !== "trial" || !ACCEPTS[task].includes(body.command) || body.trial !== s.position) {
      return [409, { detail: "stale page" }];
    } else if ((body.command === "rate") !== (s.status === "rating")) {
      return [409, { detail: `not now: the trial is ${s.status}` }];
    } else if (body.command === "select") {
      if (body.generation !== s.generation) return [409, { detail: "stale generation" }];
      if (s.generation < generations) s.generation += 1;
      else s.status = "rating";
    } else if (body.command === "restart") {
      s.generation = 0;
    } else {
      if (body.command === "answer") s.labels[s.position] = body.label;
      next();
    }
    return [200, state()];
  }

  function answer(method, path, body) {
    if (path === "/api/study") {
      return [200, { name: "fake", title: "Fake", participant_param: "PROLIFIC_PID", weight_names: ["a", "b", "c"],
        blocks: tasks.map((task, k) => ({ block: k, name: `block${k + 1}`, task, trials: 1, shows: shows[task] })) }];
    }
    if (path === "/api/sessions") {
      fake.sessions += 1;
      fake.participant = body.participant_id ?? "generated";
      return [201, { token: "t".repeat(20), url: "/s/tttt", state: state() }];
    }
    const [, , , , what, n] = path.split("/");
    if (what === "state" && method === "GET") return [200, state()];
    if (what === "step" && method === "POST") return step(body);
    if (what === "trials" && method === "GET") {
      const k = Number(n);
      const done = k < s.position || s.stage === "done";
      const result = !done ? null : tasks[k] === "evolve"
        ? { task: "evolve", emotion: "happy", final_face: face(99, 3) }
        : { task: "categorise", label: s.labels[k], weights: face(0, 4).weights };
      return [200, { session_id: 7, participant_id: fake.participant, study: "fake", trial: k, block: k,
        block_name: `block${k + 1}`, task: tasks[k], status: done ? "done" : "active", identity: "generic", attempt: 0,
        seed: "12345678901234567890", session_seed: "98765432109876543210", result }];
    }
    return [404, { detail: "not found" }];
  }

  fake.fetch = async (url, options = {}) => {
    const path = String(url).replace(SERVER, "");
    if (fake.down) throw new TypeError("Failed to fetch");
    if (fake.refuseOrigin && options.mode !== "no-cors") throw new TypeError("Failed to fetch");
    if (options.mode === "no-cors") return new Response(null, { status: 200 });
    const body = options.body ? JSON.parse(options.body) : undefined;
    log.push({ method: options.method ?? "GET", path, body });
    const [status, json] = answer(options.method ?? "GET", path, body);
    return new Response(JSON.stringify(json), { status, headers: { "Content-Type": "application/json" } });
  };
  return fake;
}

export { SERVER };
