// A scripted stand-in for the study server's participant API (the real one is driven by
// tests/web/test_jspsych_browser.py): sessions of an evolve trial (two generations, then a
// rating) and a categorise trial; it records every request, and can go down (fetch rejects) or
// refuse this page's origin (CORS: only a no-cors probe gets through).
const SERVER = "https://study.example.org";

function face(id, k) {
  return { id, weights: [k / 10, 1 - k / 10, 0.5] };
}

export function fakeServer({ blocks = ["evolve", "categorise"], generations = 1 } = {}) {
  const log = [];
  const fake = { log, down: false, refuseOrigin: false, sessions: 0 };
  const s = { stage: "instructions", position: 0, generation: 0, status: "active" };
  const tasks = blocks;

  function state() {
    const task = tasks[s.position];
    const base = {
      stage: s.stage, participant_id: fake.participant,
      progress: { trial: s.position, trials: tasks.length, block: s.position, blocks: tasks.length,
        generation: s.generation, generations },
      limits: { min_selections: 2, max_selections: 3 }, allow_restart: true,
      trial: null, population: null, rating: null, categorise: null, completion: null,
    };
    if (s.stage !== "trial") return base;
    base.trial = { position: s.position, block: s.position, task, emotion: task === "evolve" ? "happy" : "",
      prompt: task === "evolve" ? "Make the face look HAPPY" : "Which emotion does this face show?",
      identity: "generic", attempt: 0, status: s.status };
    if (task === "evolve" && s.status === "active") {
      base.population = { attempt: 0, generation: s.generation,
        faces: Array.from({ length: 10 }, (_, k) => face(10 * s.generation + k, k)) };
    } else if (task === "evolve") {
      base.rating = { question: "How well?", low_label: "not", high_label: "perfectly", points: 7, face: face(99, 3) };
    } else {
      base.categorise = { face: face(0, 4), labels: ["sad", "happy"], none_option: false, question: "Which emotion does this face show?",
        intensity: null, confidence: null };
    }
    return base;
  }

  function next() {
    s.position += 1;
    s.generation = 0;
    s.status = "active";
    if (s.position >= tasks.length) s.stage = "done";
  }

  function answer(method, path, body) {
    if (path === "/api/study") {
      return { name: "fake", title: "Fake", participant_param: "PROLIFIC_PID", weight_names: ["a", "b", "c"],
        blocks: tasks.map((task, k) => ({ block: k, name: `block${k + 1}`, task, trials: 1 })) };
    }
    if (path === "/api/sessions") {
      fake.sessions += 1;
      fake.participant = body.participant_id ?? "generated";
      return { token: "t".repeat(20), url: "/s/tttt", state: state() };
    }
    const [, , , , what, n] = path.split("/");
    if (what === "state") return state();
    if (what === "begin") s.stage = "trial";
    else if (what === "select") {
      if (s.generation < generations) s.generation += 1;
      else s.status = "rating";
    } else if (what === "rating" || what === "categorise") next();
    else if (what === "trials") {
      const k = Number(n);
      return { session_id: 7, participant_id: fake.participant, study: "fake", trial: k, block: k, block_name: `block${k + 1}`,
        task: tasks[k], status: "done", emotion: tasks[k] === "evolve" ? "happy" : "", identity: "generic", attempt: 0,
        seed: "12345678901234567890", session_seed: "98765432109876543210",
        final_face: tasks[k] === "evolve" ? face(99, 3) : face(0, 4) };
    }
    return state();
  }

  fake.fetch = async (url, options = {}) => {
    const path = String(url).replace(SERVER, "");
    if (fake.down) throw new TypeError("Failed to fetch");
    if (fake.refuseOrigin && options.mode !== "no-cors") throw new TypeError("Failed to fetch");
    if (options.mode === "no-cors") return new Response(null, { status: 200 });
    const body = options.body ? JSON.parse(options.body) : undefined;
    log.push({ method: options.method ?? "GET", path, body });
    return new Response(JSON.stringify(answer(options.method ?? "GET", path, body)), {
      status: path === "/api/sessions" ? 201 : 200, headers: { "Content-Type": "application/json" },
    });
  };
  return fake;
}

export { SERVER };
