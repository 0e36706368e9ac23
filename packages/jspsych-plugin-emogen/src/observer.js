// The simulated participant of the plugin's simulate(): an observer who chooses the faces
// nearest a target face (Euclidean distance between weight vectors, optionally with Gaussian
// noise on each distance), as emogen's simulated observers do (emogen.simulate). In data-only
// mode it meets a stand-in for the server's GA — random faces, then children of the chosen
// faces (uniform crossover, Gaussian mutation) — made only so a lab can dry-run its timeline
// and its analysis code; the faces it writes are not emogen's GA's.

/**
 * A seeded uniform [0, 1) generator (mulberry32), so a simulated timeline repeats exactly.
 * @param {number} seed
 */
export function uniform(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/** @param {() => number} random */
function normal(random) {
  const u = Math.max(random(), 1e-12);
  return Math.sqrt(-2 * Math.log(u)) * Math.cos(2 * Math.PI * random());
}

/**
 * Euclidean distance between two weight vectors (the shorter one padded with zeros).
 * @param {number[]} a
 * @param {number[]} b
 */
export function distance(a, b) {
  let sum = 0;
  for (let i = 0; i < Math.max(a.length, b.length); i++) sum += ((a[i] ?? 0) - (b[i] ?? 0)) ** 2;
  return Math.sqrt(sum);
}

/**
 * The observer's choice among ``faces``: ids ordered by (noisy) distance to ``target``, the
 * nearest first (the best face), ``n`` of them.
 * @param {{ id: number, weights: number[] }[]} faces
 * @param {number[]} target
 * @param {number} n
 * @param {{ noise?: number, random?: () => number }} [options]
 */
export function choose(faces, target, n, { noise = 0, random = Math.random } = {}) {
  const scored = faces.map((f) => ({ id: f.id, d: distance(f.weights, target) + noise * normal(random) }));
  scored.sort((x, y) => x.d - y.d);
  const ids = scored.slice(0, n).map((s) => s.id);
  return { elite: ids[0], others: ids.slice(1) };
}

/** A response time (ms): log-normal around ``median``, as choice RTs are. */
function responseTime(random, median) {
  return Math.round(median * Math.exp(0.4 * normal(random)));
}

/** A random face: each weight active with probability 0.3, its value uniform in [0, 1]. */
function randomFace(random, n) {
  return Array.from({ length: n }, () => (random() < 0.3 ? random() : 0));
}

/** A child of two chosen faces: each weight from either, mutated (p 0.2, sd 0.15), in [0, 1]. */
function child(random, a, b) {
  return a.map((w, i) => {
    const gene = random() < 0.5 ? w : b[i];
    const mutated = random() < 0.2 ? gene + 0.15 * normal(random) : gene;
    return Math.min(1, Math.max(0, mutated));
  });
}

/**
 * An evolve trial's data without a server: ``generations`` + 1 generations of ``faces`` faces.
 * @param {{ target: number[], generations?: number, faces?: number, chosen?: number,
 *   noise?: number, seed?: number, median_rt?: number }} options
 */
export function simulateEvolve({ target, generations = 10, faces = 10, chosen = 3, noise = 0, seed = 1, median_rt = 4000 }) {
  const random = uniform(seed);
  let nextId = 0;
  let population = Array.from({ length: faces }, () => ({ id: nextId++, weights: randomFace(random, target.length) }));
  const rows = [];
  let best = population[0];
  for (let g = 0; g <= generations; g++) {
    const { elite, others } = choose(population, target, chosen, { noise, random });
    rows.push({
      attempt: 0, generation: g, shown: population.map((f) => f.id), elite, others: [...others],
      rt: responseTime(random, median_rt), load_ms: 0,
    });
    const picked = [elite, ...others].map((id) => population.find((f) => f.id === id));
    best = /** @type {any} */ (picked[0]);
    const children = Array.from({ length: faces - 1 }, () => {
      const a = picked[Math.floor(random() * picked.length)];
      const b = picked[Math.floor(random() * picked.length)];
      return { id: nextId++, weights: child(random, /** @type {any} */ (a).weights, /** @type {any} */ (b).weights) };
    });
    population = [best, ...children];
  }
  return { generations: rows, final_face_id: best.id, final_weights: best.weights };
}

/**
 * A categorise trial's data without a server: the label nearest the face by ``prototypes``
 * (label → weights) where given, else a label drawn at random.
 * @param {{ labels?: string[], prototypes?: Record<string, number[]>, face?: number[], seed?: number, median_rt?: number }} options
 */
export function simulateCategorise({ labels = ["happy", "sad", "angry", "fearful"], prototypes, face, seed = 1, median_rt = 2500 }) {
  const random = uniform(seed);
  const weights = face ?? randomFace(random, prototypes ? Object.values(prototypes)[0].length : 20);
  let label = labels[Math.floor(random() * labels.length)];
  if (prototypes) {
    const known = labels.filter((l) => l in prototypes);
    known.sort((x, y) => distance(weights, prototypes[x]) - distance(weights, prototypes[y]));
    label = known[0] ?? label;
  }
  return { labels: [...labels], label, final_face_id: 0, final_weights: weights, response_rt: responseTime(random, median_rt) };
}
