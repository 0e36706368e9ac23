// A face that moves, as the page plays it: the server's emogen.ga.motion.frames in one typed-array
// pass a frame (docs/ga.md, "Dynamic faces"). The view gives a face its peak weights (shapes, then
// correctives) and its motion: a clip of clip_s seconds, then hold_s at rest, looped; per shape a
// row [t_on, t_peak, t_off, rise_slope, fall_slope]; the corrective weights at keyframes evenly
// over the clip. At time t a shape's weight is its peak weight times
//   c(t) = H((t − t_on) / (t_peak − t_on); rise_slope)    t ≤ t_peak   (0 before t_on)
//        = H((t_off − t) / (t_off − t_peak); fall_slope)  t > t_peak   (0 from t_off)
//   H(x; m) = 3x² − 2x³ + m (x³ − 2x² + x),  x clipped to [0, 1]
// and the correctives are the keyframes interpolated linearly around t.
//
// Played, a clip shows the frames of a fixed grid over it, as a video does: FRAME_RATE frames a
// second or a little more (n = ceil(clip_s × FRAME_RATE) steps, frames at clip_s × k / n,
// k = 0 … n; the last is the face at rest the hold shows), the same frames on every machine;
// a face scrubbed to a time shows that time exactly. The viewer keeps each grid frame once drawn
// (kept.js), so a machine that draws ten faces slowly plays them at the grid's rate.

/** Frames a second of the grid a clip plays on (issue #44: ≥ 30 on a laptop GPU). */
export const FRAME_RATE = 30;

const hermite = (x, m) => 3 * x * x - 2 * x * x * x + m * (x * x * x - 2 * x * x + x);
const unit = (x) => (x < 0 ? 0 : x > 1 ? 1 : x);

export class Clip {
  /**
   * @param {number[]} weights the face's peak weights (shapes, then any correctives)
   * @param {{clip_s: number, hold_s: number, curves: number[][], keyframes: number[][]}} motion
   * @param {number} targets the GLB's morph targets (shapes, then correctives)
   */
  constructor(weights, motion, targets) {
    this.clip = motion.clip_s;
    this.loop = motion.clip_s + motion.hold_s;
    this.targets = targets;
    const shapes = Math.min(motion.curves.length, targets);
    const moving = [];
    for (let k = 0; k < shapes; k++) if (weights[k] > 0) moving.push(k);
    // per moving shape: index, peak weight, t_on, t_peak, t_off, rise slope, fall slope
    this.rows = new Float64Array(moving.length * 7);
    moving.forEach((k, j) => this.rows.set([k, weights[k], ...motion.curves[k]], 7 * j));
    this.shapes = shapes;
    const keys = motion.keyframes;
    this.frames = keys.length;
    this.correctives = keys.length ? Math.min(keys[0].length, targets - shapes) : 0;
    this.keys = new Float64Array(this.frames * this.correctives);
    keys.forEach((row, f) => this.keys.set(row.slice(0, this.correctives), f * this.correctives));
  }

  /** The clip's time (s) at ``tau`` seconds into the loop: the hold is the clip's end. */
  time(tau) {
    const t = tau % this.loop;
    return t < this.clip ? t : this.clip;
  }

  /** The grid's steps over the clip: its frames are ``gridTime(0 … steps)``. */
  get steps() {
    return Math.max(1, Math.ceil(this.clip * FRAME_RATE - 1e-9));
  }

  /** The clip time (s) of grid frame ``k``. */
  gridTime(k) {
    return (k / this.steps) * this.clip;
  }

  /** The grid frame played at clip time ``t`` (s): the nearest. */
  gridFrame(t) {
    return Math.min(this.steps, Math.max(0, Math.round((t / this.clip) * this.steps)));
  }

  /** The morph weights at clip time ``t`` (s) into ``out`` (Float32Array of the targets). */
  at(t, out) {
    out.fill(0);
    const r = this.rows;
    for (let j = 0; j < r.length; j += 7) {
      const [on, peak, off] = [r[j + 2], r[j + 3], r[j + 4]];
      const c = t <= peak
        ? hermite(unit((t - on) / (peak - on)), r[j + 5])
        : hermite(unit((off - t) / (off - peak)), r[j + 6]);
      out[r[j]] = r[j + 1] * c;
    }
    const n = this.correctives;
    if (!n) return out;
    const x = (Math.min(Math.max(t, 0), this.clip) / this.clip) * (this.frames - 1);
    const left = Math.min(Math.floor(x), this.frames - 2);
    const s = x - left;
    const a = left * n, b = a + n;
    for (let c = 0; c < n; c++) {
      out[this.shapes + c] = this.keys[a + c] + (this.keys[b + c] - this.keys[a + c]) * s;
    }
    return out;
  }
}
