// Face display: the 3D viewer (three.js, WebGL) when available, else PNGs rendered by the server.
//
//   const display = await createFaceDisplay({ token });
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
  constructor(token) {
    this.token = token;
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
        img.src = `/api/s/${this.token}/faces/${face.id}.png${query}`;
      }).then(loaded);
    });
    return Promise.all(loads);
  }
}

async function loadViewer() {
  if (document.body.dataset.viewer !== "yes" || !webglAvailable()) return null;
  try {
    const mod = await import("/static/viewer-adapter.js");
    return await mod.createViewerDisplay();
  } catch (err) {
    console.warn("3D viewer unavailable, using server images:", err);
    return null;
  }
}

export async function createFaceDisplay({ token }) {
  const forced = new URLSearchParams(location.search).get("render");
  if (forced !== "png") {
    const viewer = await loadViewer();
    if (viewer) return viewer;
  }
  return new PngDisplay(token);
}
