// Face display: the 3D viewer (three.js, WebGL) when available, else PNGs rendered by the server.
//
//   const display = await createFaceDisplay({ token });   // the study's own page
//   const display = await createFaceDisplay({ token, base, loadViewer });  // another site's page
//   await display.show(slots, faces, identity, onProgress, where);
//   // slots: elements; faces: [{id, weights}]; where: {trial, attempt} the faces belong to
//
// `show` resolves when every face is drawn (or has failed to load), so the caller can start
// the response-time clock and set the page's ready flag. `onProgress(done, total, unit)` hears
// how far the loading is: unit "faces" (images loaded) or "bytes" (the 3D model; total 0 when
// the server did not say the size).

function webglAvailable() {
  try {
    const canvas = document.createElement("canvas");
    return !!canvas.getContext("webgl2");
  } catch {
    return false;
  }
}

// A face that moves comes from the server as a strip of its frames (the clip at evenly spaced
// times, left to right, each frame as tall as wide): shown a frame at a time, every strip of a
// screen in sync, looped with the clip's hold at rest, as the 3D viewer plays its clips.
class Strips {
  constructor() {
    /** @type {Map<HTMLElement, {img: HTMLImageElement, motion: any}>} */
    this.shown = new Map();
    /** @type {Map<HTMLElement, number>} */
    this.held = new Map();
    this.start = performance.now();
    this.raf = 0;
  }

  play(slot, img, motion) {
    if (!motion) {
      this.shown.delete(slot);
      slot.classList.remove("strip");
      img.removeAttribute("style");
      return;
    }
    slot.classList.add("strip");
    this.shown.set(slot, { img, motion });
    this.held.delete(slot);
    this.start = performance.now();
    if (!this.raf) this.raf = requestAnimationFrame((now) => this.tick(now));
  }

  time(slot, now = performance.now()) {
    const entry = this.shown.get(slot);
    if (!entry) return null;
    if (this.held.has(slot)) return this.held.get(slot) ?? null;
    const { clip_s: clip, hold_s: hold } = entry.motion;
    return Math.min(((now - this.start) / 1000) % (clip + hold), clip);
  }

  tick(now) {
    for (const [slot, { img, motion }] of this.shown) {
      const frames = img.naturalHeight ? Math.round(img.naturalWidth / img.naturalHeight) : 1;
      const k = Math.round(((this.time(slot, now) ?? 0) / motion.clip_s) * (frames - 1));
      img.style.width = `${frames * 100}%`;
      img.style.transform = `translateX(${(-100 * k) / frames}%)`;
    }
    this.raf = this.shown.size ? requestAnimationFrame((t) => this.tick(t)) : 0;
  }
}

class PngDisplay {
  constructor(token, base = "") {
    this.token = token;
    this.base = base;
    this.kind = "png";
    this.strips = new Strips();
  }

  show(slots, faces, _identity, onProgress = () => {}, where = { trial: 0, attempt: 0 }) {
    // Face ids count from 0 in every trial and attempt: the URL names both, so a cached image
    // of an earlier trial's face with the same id is never shown.
    const query = `?trial=${where.trial}&attempt=${where.attempt}`;
    let done = 0;
    onProgress(0, faces.length, "faces");
    const loaded = (ok) => {
      onProgress(++done, faces.length, "faces");
      return ok;
    };
    const loads = faces.map((face, i) => {
      const slot = slots[i];
      let img = slot.querySelector("img");
      if (!img) {
        img = document.createElement("img");
        img.alt = "";
        img.decoding = "async";
        slot.replaceChildren(img);
      }
      return new Promise((resolve) => {
        img.onload = () => {
          slot.classList.remove("failed");
          resolve(true);
        };
        img.onerror = () => {
          slot.classList.add("failed");
          resolve(false);
        };
        img.src = `${this.base}/api/s/${this.token}/faces/${face.id}.png${query}`;
        this.strips.play(slot, img, face.motion);
      }).then(loaded);
    });
    return Promise.all(loads);
  }

  /** Every strip from its first frame again (a held one plays along again). */
  replay() {
    this.strips.held.clear();
    this.strips.start = performance.now();
  }

  /** ``slot``'s strip held at the frame nearest clip time ``t`` (s); null: it plays again. */
  scrub(slot, t) {
    if (t === null) this.strips.held.delete(slot);
    else if (this.strips.shown.has(slot)) this.strips.held.set(slot, t);
  }

  /** The clip time (s) ``slot`` shows now (null: a still face). */
  clipTime(slot) {
    return this.strips.time(slot);
  }

  dispose() {}
}

async function loadOwnViewer() {
  if (document.body.dataset.viewer !== "yes") return null;
  const mod = await import("/static/viewer-adapter.js");
  return mod.createViewerDisplay({ framing: document.body.dataset.framing || "face" });
}

/**
 * The face display of session ``token``: the 3D viewer unless ``?render=png`` or WebGL 2 is
 * missing. ``base``: the study server's origin when the page is another site's (the jsPsych
 * plugin), "" on the server's own pages; ``loadViewer``: how that page gets the 3D viewer (the
 * study's page imports it from /static when the server has it built).
 * @param {{ token: string, base?: string, loadViewer?: () => Promise<any> }} options
 */
export async function createFaceDisplay({ token, base = "", loadViewer = loadOwnViewer }) {
  const forced = new URLSearchParams(location.search).get("render");
  if (forced !== "png" && webglAvailable()) {
    try {
      const viewer = await loadViewer();
      if (viewer) return viewer;
    } catch (err) {
      console.warn("3D viewer unavailable, using server images:", err);
    }
  }
  return new PngDisplay(token, base);
}
