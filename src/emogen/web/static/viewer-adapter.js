// The 3D face display of the study pages: the viewer's FaceGrid (one WebGL canvas drawing every
// face into its slot). Slots live in containers marked data-viewer-container (the grid, the
// rating view); each container gets a FaceGrid over the GLB of the trial's identity. Under the
// study's ``oval`` framing each slot is seen through look.json's oval (a layer over the canvas,
// as the viewer page's ?framing=oval, under the face's number and marks, which come after the
// slot; the server's PNGs are rendered through the oval themselves).
import { FaceGrid, ovalLayer } from "./build/study-viewer.js";

function webgl2Available() {
  try {
    return Boolean(document.createElement("canvas").getContext("webgl2"));
  } catch {
    return false;
  }
}

// The GLB read with a running count of bytes (GLTFLoader reports none we can use), handed to the
// loader as an object URL (the GLB is self-contained).
async function fetchGlb(url, onProgress) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  const declared = Number(response.headers.get("Content-Length")) || 0;
  const encoded = Boolean(response.headers.get("Content-Encoding"));
  const total = encoded ? 0 : declared; // a compressed length does not count the bytes read
  if (!response.body) return response.blob();
  const reader = response.body.getReader();
  const chunks = [];
  let loaded = 0;
  onProgress(0, total, "bytes");
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    chunks.push(value);
    loaded += value.length;
    // more bytes than declared: the length was a compressed one after all (unknown total)
    onProgress(loaded, loaded <= total ? total : 0, "bytes");
  }
  return new Blob(chunks, { type: "model/gltf-binary" });
}

// Each identity's GLB is read once per page: every container (the grid, the rating view; each
// trial of the jsPsych plugin) builds its FaceGrid from the same bytes. A failed read is
// forgotten, so the next show tries again.
/** @type {Map<string, Promise<Blob>>} */
const glbs = new Map();

function glbOnce(url, onProgress) {
  let got = glbs.get(url);
  if (!got) {
    got = fetchGlb(url, onProgress);
    glbs.set(url, got);
    got.catch(() => glbs.delete(url));
  }
  return got;
}

function release(grid) {
  grid.remove();
  grid.renderer.dispose();
  grid.renderer.forceContextLoss(); // the browser's WebGL contexts are few: give this one back
}

const nextFrame = () => new Promise((resolve) => requestAnimationFrame(() => resolve()));

/** The face models a container keeps built: the one shown and the next trial's (made ahead). */
const KEEP = 2;

class ViewerDisplay {
  /**
   * @param {string} base the study server's origin ("" on its own pages)
   * @param {string} framing the study's framing (``face``, ``oval``)
   */
  constructor(base, framing) {
    this.kind = "webgl";
    this.base = base;
    this.framing = framing;
    // container -> Map(url -> {count, ahead, grid, ready: Promise<FaceGrid>}), least recently
    // shown first; the container's other grids' canvases are hidden
    this.grids = new Map();
    /** Each face model built: its URL, whether ahead of its trial, its timings (benchmarks). */
    this.loads = [];
    this.playing = new Map(); // container -> {grid, slots} last shown
  }

  urlOf(identity) {
    return `${this.base}/api/model/${encodeURIComponent(identity)}.glb`;
  }

  heldBy(container) {
    let held = this.grids.get(container);
    if (!held) this.grids.set(container, (held = new Map()));
    return held;
  }

  build(container, slots, url, onProgress, ahead) {
    const grid = new FaceGrid(container, slots);
    grid.setVisible(false); // until its show
    const began = performance.now();
    const ready = glbOnce(url, onProgress).then(async (blob) => {
      const fetched = performance.now() - began;
      const local = URL.createObjectURL(blob);
      try {
        await grid.load(local);
      } finally {
        URL.revokeObjectURL(local);
      }
      this.loads.push({ url, ahead, fetch_ms: fetched, ...grid.timings, total_ms: performance.now() - began });
      return grid;
    });
    const entry = { count: slots.length, ahead, grid, ready };
    const held = this.heldBy(container);
    held.set(url, entry);
    // a failed load (a lost connection) is tried afresh next time
    ready.catch(() => {
      if (held.get(url) === entry) held.delete(url);
      release(grid);
    });
    return entry;
  }

  /** The container's grids beyond KEEP given back, least recently shown first, never ``keep``. */
  trim(container, keep) {
    const held = this.heldBy(container);
    for (const [url, entry] of held) {
      if (held.size <= KEEP) break;
      if (url === keep) continue;
      held.delete(url);
      entry.ready.then(release, () => {});
    }
  }

  gridFor(container, slots, url, onProgress) {
    const held = this.heldBy(container);
    let entry = held.get(url);
    if (entry && entry.count !== slots.length) {
      held.delete(url);
      entry.ready.then(release, () => {});
      entry = undefined;
    }
    if (!entry) entry = this.build(container, slots, url, onProgress, false);
    held.delete(url); // the most recently shown last
    held.set(url, entry);
    this.trim(container, url);
    return entry.ready;
  }

  /**
   * The face model of ``identity`` built ahead, unseen, in every container that shows faces,
   * so that the first trial of that identity does not wait for it (its download, parsing and
   * upload to the GPU: seconds in a software-rendered browser). It fails soft: a failed build
   * is forgotten (show loads it as ever) and nothing is said to the participant.
   * @param {string} identity
   */
  prefetch(identity) {
    const url = this.urlOf(identity);
    for (const [container, held] of this.grids) {
      if (held.has(url) || held.size === 0) continue;
      const shown = [...held.values()].at(-1);
      const entry = this.build(container, shown.grid.slots, url, () => {}, true);
      entry.ready.catch((err) => console.info(`face model ${url} not made ahead (${err}); it loads when shown`));
      this.trim(container, [...held.keys()].at(-2));
    }
  }

  /** Every grid's WebGL context given back (the page's screens are gone: a plugin trial ended). */
  dispose() {
    for (const held of this.grids.values()) for (const entry of held.values()) entry.ready.then(release, () => {});
    this.grids.clear();
    this.playing.clear();
  }

  /**
   * slots: elements of one container; faces: [{id, weights}] in the GLB's morph-target order
   * (shapes, then correctives when the study corrects faces); longer vectors are cut to the
   * GLB's targets, shorter ones padded with 0 by the grid. onProgress(done, total, "bytes")
   * follows the GLB's download (the first time a container shows an identity).
   */
  async show(slots, faces, identity = "generic", onProgress = () => {}) {
    for (const slot of slots) ovalLayer(slot, this.framing);
    const container = slots[0].closest("[data-viewer-container]");
    const url = this.urlOf(identity);
    const ahead = this.heldBy(container).get(url)?.ahead;
    let grid;
    try {
      grid = await this.gridFor(container, slots, url, onProgress);
    } catch (err) {
      if (!ahead) throw err;
      grid = await this.gridFor(container, slots, url, onProgress); // made ahead and failed: load it now
    }
    for (const entry of this.heldBy(container).values()) {
      entry.grid.setVisible(entry.grid === grid);
    }
    const n = grid.shapeNames.length;
    grid.setFaces(faces.map((f) => f.weights.slice(0, n)));
    // a screen shows one grid's faces: the others (hidden now, or another identity's) stop playing
    for (const shown of this.playing.values()) if (shown.grid !== grid) shown.grid.play(null);
    this.playing.clear();
    grid.play(faces); // faces that move play their clips (the others stay as set)
    this.playing.set(container, { grid, slots });
    await nextFrame();
    return faces.map(() => true);
  }

  /**
   * The faces ``slot`` (shown last) may show next, known ahead (a slider's positions:
   * [{id, weights}]; null: forget them): each is shown as a frame drawn once and kept, and the
   * browser's idle frames draw the rest, nearest the one shown first (viewer/kept.js).
   */
  keep(slot, faces) {
    const tile = this.tileOf(slot);
    if (!tile) return;
    const n = tile.grid.shapeNames.length;
    tile.grid.keep(tile.i, faces ? faces.map((f) => f.weights.slice(0, n)) : null);
  }

  /** ``slot``'s kept frames: {shown: the position shown (−1: none of them), showing: the kept
   * frame on screen (null: drawn live), kept, of, complete}
   * (null: none kept; benchmarks and tests). */
  keptOf(slot) {
    const tile = this.tileOf(slot);
    return tile ? tile.grid.keptState(tile.i) : null;
  }

  /** The grid drawing ``slot`` and the slot's place in it (null: none shown there). */
  tileOf(slot) {
    const shown = this.playing.get(slot.closest("[data-viewer-container]"));
    const i = shown ? shown.slots.indexOf(slot) : -1;
    return i < 0 ? null : { grid: shown.grid, i };
  }

  /** Faces that move in ``slot``'s container play from their start again. */
  replay(slot) {
    this.tileOf(slot)?.grid.replay();
  }

  /** ``slot``'s face held at clip time ``t`` seconds (null: it plays along again). */
  scrub(slot, t) {
    const tile = this.tileOf(slot);
    tile?.grid.scrub(tile.i, t);
  }

  /** The clip time (s) ``slot`` shows now (null: a face that does not move). */
  clipTime(slot) {
    const tile = this.tileOf(slot);
    return tile ? tile.grid.clipTime(tile.i) : null;
  }
}

/**
 * @param {{ base?: string, framing?: string }} [options] ``base``: the study server's origin on
 * another site's page; ``framing``: the study's (``face``, ``oval``: GET /api/study)
 */
export async function createViewerDisplay({ base = "", framing = "face" } = {}) {
  return webgl2Available() ? new ViewerDisplay(base, framing) : null;
}
