// EmoGen face viewer: n faces (default 10) of the model GLB, driven by weight vectors.
//
// Query parameters: model (GLB URL, default face.glb), faces (default 10), size (pixels per
// face, default 256), columns (default 5), fallback=1 (force the PNG fallback), png (fallback
// URL template, default render.png?size={size}&weights={weights}), aa=0|1 (antialiasing),
// framing=oval (each face seen through look.json's oval on the background, as offscreen).
//
// API: window.emogen.setFaces(weights) with weights[i] a vector in the GLB's shape order
// (window.emogen.shapeNames) or a {shape: value} object; returns a Promise resolved once drawn.
// window.emogenReady becomes true when the first faces are on screen; window.emogen.error holds
// a message if loading failed.
import { FaceGrid, probeWebGL } from './faces.js';
import { ImageGrid } from './fallback.js';
import { ovalLayer } from './look.js';

const params = new URLSearchParams(window.location.search);
const count = Math.max(1, Math.min(40, Number(params.get('faces') ?? 10) || 10));
const size = Math.max(32, Math.min(2048, Number(params.get('size') ?? 256) || 256));
const columns = Math.max(1, Number(params.get('columns') ?? Math.min(5, count)) || 5);
const modelUrl = params.get('model') ?? 'face.glb';
const template = params.get('png') ?? 'render.png?size={size}&weights={weights}';
const forceFallback = params.get('fallback') === '1';
const aaParam = params.get('aa');
const framing = params.get('framing');

const grid = document.getElementById('faces');
grid.style.setProperty('--face-size', `${size}px`);
grid.style.setProperty('--columns', String(columns));
const slots = Array.from({ length: count }, (_, i) => {
  const slot = document.createElement('div');
  slot.className = 'face';
  slot.dataset.index = String(i);
  ovalLayer(slot, framing);
  grid.appendChild(slot);
  return slot;
});

const nextFrame = () => new Promise((resolve) => requestAnimationFrame(() => resolve()));

const api = {
  mode: null,
  shapeNames: [],
  slots,
  error: null,
  timings: {},
  setFaces: async () => {
    throw new Error('viewer not ready');
  },
};
window.emogen = api;
window.emogenReady = false;

async function startWebGL() {
  const t0 = performance.now();
  const view = new FaceGrid(grid, slots, aaParam === null ? {} : { antialias: aaParam === '1' });
  await view.load(modelUrl);
  api.mode = 'webgl';
  api.shapeNames = view.shapeNames;
  api.view = view;
  api.setFaces = async (weights) => {
    view.setFaces(weights);
    await nextFrame();
  };
  await nextFrame();
  api.timings.load_ms = performance.now() - t0;
  Object.assign(api.timings, view.timings);
}

async function startFallback() {
  const view = new ImageGrid(slots, { template, size });
  api.mode = 'fallback';
  api.view = view;
  api.setFaces = (weights) => view.setFaces(weights);
  await view.setFaces(slots.map(() => []));
}

async function start() {
  try {
    if (!forceFallback && probeWebGL().webgl2) {
      await startWebGL();
    } else {
      await startFallback();
    }
  } catch (err) {
    api.error = String(err?.message ?? err);
    console.error('EmoGen viewer:', err);
    if (api.mode !== 'fallback') {
      await startFallback();
    }
  }
  api.timings.ready_ms = performance.now();
  document.body.dataset.mode = api.mode;
  window.emogenReady = true;
  requestAnimationFrame(() => { api.timings.next_frame_ms = performance.now(); });
  window.dispatchEvent(new Event('emogen-ready'));
}

start();
