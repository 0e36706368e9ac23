// The 3D face display of the study pages: the viewer's FaceGrid (one WebGL canvas drawing every
// face into its slot). Slots live in containers marked data-viewer-container (the grid, the
// rating view); each container gets a FaceGrid over the GLB of the trial's identity.
import { FaceGrid } from "./build/study-viewer.js";

function webgl2Available() {
  try {
    return Boolean(document.createElement("canvas").getContext("webgl2"));
  } catch {
    return false;
  }
}

const nextFrame = () => new Promise((resolve) => requestAnimationFrame(() => resolve()));

class ViewerDisplay {
  constructor() {
    this.kind = "webgl";
    this.grids = new Map(); // container -> {url, count, ready: Promise<FaceGrid>}
  }

  gridFor(container, slots, url) {
    const entry = this.grids.get(container);
    if (entry && entry.url === url && entry.count === slots.length) return entry.ready;
    if (entry) {
      entry.ready.then((old) => {
        old.renderer.dispose();
        old.canvas.remove();
      }, () => {});
    }
    const grid = new FaceGrid(container, slots);
    const ready = grid.load(url).then(() => grid);
    this.grids.set(container, { url, count: slots.length, ready });
    return ready;
  }

  /**
   * slots: elements of one container; faces: [{id, weights}] in the GLB's morph-target order
   * (shapes, then correctives when the study corrects faces); longer vectors are cut to the
   * GLB's targets, shorter ones padded with 0 by the grid.
   */
  async show(slots, faces, identity = "generic") {
    const container = slots[0].closest("[data-viewer-container]");
    const url = `/api/model/${encodeURIComponent(identity)}.glb`;
    const grid = await this.gridFor(container, slots, url);
    const n = grid.shapeNames.length;
    grid.setFaces(faces.map((f) => f.weights.slice(0, n)));
    await nextFrame();
    return faces.map(() => true);
  }
}

export async function createViewerDisplay() {
  return webgl2Available() ? new ViewerDisplay() : null;
}
