// Frames rendered ahead and kept (issues #43, #44): a slot whose faces are known in advance (a
// one-face slider page's positions, known when its trial opens) shows each of them as a frame the viewer
// drew live with WebGL for that face and kept as an ImageBitmap, played by a 2D canvas laid over
// the WebGL one. A face not yet kept is drawn live when shown (then kept); while the page is idle
// the viewer draws the others, nearest (in the list) the one shown first. There is no second
// drawing code: a kept frame is a copy of the pixels the live draw made.
//
// Why (benchmarks/bench_viewer_cost.py, docs/render.md): on software GL (SwiftShader) the slider
// page's face costs 87 ms of GPU-process CPU a frame drawn live (7.6 frames/s, target 30) and 11 ms
// played from kept frames (59.7 frames/s); benchmarks/bench_gsp_slider.py measures the slider.
//
// Memory: frames × width × height × 4 bytes (device pixels): the slider's face at 1366×768, 41
// positions of 445×445, is 32 MB. At most KEEP_BYTES a slot: beyond it the frames farthest from
// the one shown are dropped (a phone (390×844) at 3 device pixels a CSS pixel keeps 28 of 41).
//
// Faces that move (motion.js) keep the frames of their clip's grid, when all of them fit in
// CLIP_BYTES over the screen's tiles (else they are drawn live, as before): drawn ahead coarse
// to fine (the first and last frames, then the middle, then the quarters …, one tile after
// another), and while a tile's frame is not kept yet the nearest kept one is shown.

/** The most bytes of kept frames one slot holds. */
export const KEEP_BYTES = 128 * 2 ** 20;

/** The most bytes of kept clip frames one screen of tiles holds. */
export const CLIP_BYTES = 256 * 2 ** 20;

/** Positions 0 … last in the order a clip's frames are drawn ahead: 0 and last, then each
 * halving of the grid's step (the frames of a coarser grid first). @param {number} last */
export function coarseToFine(last) {
  const order = [0, last];
  const seen = new Set(order);
  for (let step = 2 ** Math.ceil(Math.log2(Math.max(1, last))); step >= 1; step /= 2) {
    for (let k = step; k < last; k += step) if (!seen.has(k)) (seen.add(k), order.push(k));
  }
  return order;
}

/** The key of a weight vector (the full vector the grid draws). @param {number[]} vector */
export const keyOf = (vector) => vector.join(',');

/** The frames of one slot: ``faces`` (full weight vectors) and the ones drawn so far. */
export class KeptFrames {
  /**
   * @param {number[][]} faces
   * @param {{bytes?: number, order?: number[]}} [options] ``bytes``: the most the slot keeps
   * (KEEP_BYTES); ``order``: the positions in the order they are drawn ahead (a clip's; none:
   * the nearest the one shown first, a slider's)
   */
  constructor(faces, { bytes = KEEP_BYTES, order = null } = {}) {
    this.faces = faces;
    this.index = new Map(faces.map((w, k) => [keyOf(w), k]));
    /** k → {bitmap: ImageBitmap | null (its copy under way), rect: [x, y, w, h] (device px)} */
    this.frames = new Map();
    this.limit = faces.length;
    this.bytes = bytes;
    this.order = order;
  }

  /** The position of weights ``vector`` among the faces (−1: none of them). */
  find(vector) {
    const k = this.index.get(keyOf(vector));
    return k === undefined ? -1 : k;
  }

  /** Frame ``k`` (drawn live just now at ``rect``, device pixels) copied from ``canvas`` and
   * kept; the frame farthest from ``shown`` dropped when the slot holds more than KEEP_BYTES. */
  keep(k, canvas, rect, shown) {
    const frame = { bitmap: null, rect };
    this.frames.set(k, frame);
    createImageBitmap(canvas, ...rect).then(
      (bitmap) => {
        if (this.frames.get(k) === frame) frame.bitmap = bitmap;
        else bitmap.close(); // dropped meanwhile
      },
      () => this.frames.get(k) === frame && this.frames.delete(k), // not copied: drawn again when shown
    );
    this.limit = Math.max(1, Math.floor(this.bytes / (rect[2] * rect[3] * 4)));
    while (this.frames.size > this.limit) this.drop(this.farthest(shown));
  }

  /** The kept frame farthest from position ``shown``. */
  farthest(shown) {
    let worst = -1;
    for (const k of this.frames.keys()) if (worst < 0 || Math.abs(k - shown) > Math.abs(worst - shown)) worst = k;
    return worst;
  }

  drop(k) {
    this.frames.get(k)?.bitmap?.close();
    this.frames.delete(k);
  }

  /** Every frame given back (the trial is over, or the slot's size changed). */
  clear() {
    for (const k of [...this.frames.keys()]) this.drop(k);
  }

  /** The kept frame (copied) nearest position ``k``; null when none is. */
  nearest(k) {
    let best = null;
    for (const [j, frame] of this.frames) {
      if (frame.bitmap && (!best || Math.abs(j - k) < Math.abs(best[0] - k))) best = [j, frame];
    }
    return best;
  }

  /** The position to draw ahead next: the first of ``order`` not kept, or else the nearest to
   * ``shown`` not kept (ties: the lower one), while it is nearer than the farthest kept or
   * there is room; −1 when none. */
  next(shown) {
    if (this.order) {
      if (this.frames.size >= this.limit) return -1;
      return this.order.find((k) => !this.frames.has(k)) ?? -1;
    }
    for (let d = 0; d < this.faces.length; d++) {
      for (const k of [shown - d, shown + d]) {
        if (k < 0 || k >= this.faces.length || this.frames.has(k)) continue;
        if (this.frames.size < this.limit) return k;
        const far = this.farthest(shown);
        return Math.abs(far - shown) > d ? k : -1;
      }
    }
    return -1;
  }

  /** Whether every frame to be drawn ahead has been copied (the benchmark's "all kept"). */
  complete(shown) {
    return this.next(shown) < 0 && [...this.frames.values()].every((f) => f.bitmap);
  }
}

/** The 2D canvas over a FaceGrid's WebGL canvas (the same place, size and pixels) on which the
 * kept frames are played; transparent over the faces drawn live. */
export class Overlay {
  /** @param {HTMLCanvasElement} gl the grid's WebGL canvas */
  constructor(gl) {
    this.gl = gl;
    this.canvas = document.createElement('canvas');
    const style = getComputedStyle(gl);
    Object.assign(this.canvas.style, {
      position: 'absolute', left: '0', top: '0', pointerEvents: 'none', zIndex: style.zIndex,
      visibility: gl.style.visibility,
    });
    gl.after(this.canvas);
    this.context = this.canvas.getContext('2d', { alpha: true });
    this.shows = new Map(); // face → [position, rect] it shows
    this.fit();
  }

  /** The WebGL canvas's size again (what was shown is cleared). */
  fit() {
    this.canvas.width = this.gl.width;
    this.canvas.height = this.gl.height;
    this.canvas.style.width = this.gl.style.width;
    this.canvas.style.height = this.gl.style.height;
    this.shows.clear();
  }

  /** Face ``i``'s position ``k`` played from its kept ``frame``; false when it cannot be (not
   * kept, or its copy under way and another position shown). */
  play(i, k, frame) {
    if (frame?.bitmap) {
      this.context.clearRect(...frame.rect);
      this.context.drawImage(frame.bitmap, frame.rect[0], frame.rect[1]);
      this.shows.set(i, [k, frame.rect]);
      return true;
    }
    return Boolean(frame) && this.shows.get(i)?.[0] === k;
  }

  /** Face ``i``'s position ``k`` as the WebGL canvas holds it now (just drawn) at ``rect``. */
  copy(i, k, rect) {
    this.context.clearRect(...rect);
    this.context.drawImage(this.gl, ...rect, ...rect);
    this.shows.set(i, [k, rect]);
  }

  /** Face ``i`` drawn live: nothing kept over it. */
  uncover(i) {
    const shown = this.shows.get(i);
    if (shown) this.context.clearRect(...shown[1]);
    this.shows.delete(i);
  }
}
