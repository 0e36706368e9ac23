// The simulated participant's means, shared by the tasks' simulations (tasks/<task>.js:
// `simulate` for the jsPsych plugin's data-only mode, `drive` for its visual mode): a seeded
// random stream, an observer who chooses the faces nearest a target face (Euclidean distance
// between weight vectors, optionally with Gaussian noise on each distance), as emogen's
// simulated observers do (emogen.simulate), response times and random faces.

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

/**
 * A standard normal draw (Box–Muller).
 * @param {() => number} random
 */
export function normal(random) {
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

/**
 * A response time (ms): log-normal around ``median``, as choice RTs are.
 * @param {() => number} random
 * @param {number} median
 */
export function responseTime(random, median) {
  return Math.round(median * Math.exp(0.4 * normal(random)));
}

/**
 * A random face: each weight active with probability 0.3, its value uniform in [0, 1].
 * @param {() => number} random
 * @param {number} n
 */
export function randomFace(random, n) {
  return Array.from({ length: n }, () => (random() < 0.3 ? random() : 0));
}
