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

class PngDisplay {
  constructor(token, base = "") {
    this.token = token;
    this.base = base;
    this.kind = "png";
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
      }).then(loaded);
    });
    return Promise.all(loads);
  }

  // Server images stand still: nothing to replay or step through.
  replay() {}

  scrub() {}

  clipTime() {
    return null;
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
