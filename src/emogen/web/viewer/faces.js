// Ten (or n) faces in one WebGL context: one renderer and canvas over the grid, per-face meshes
// sharing each GLB primitive's index and shading attributes and holding their own morphed
// positions, normals and strain (morph.js), each face drawn into its slot's rectangle with
// viewport + scissor.
import {
  ClampToEdgeWrapping,
  ColorManagement,
  Color,
  Group,
  LinearFilter,
  LinearMipmapLinearFilter,
  LinearSRGBColorSpace,
  Matrix4,
  NoColorSpace,
  PerspectiveCamera,
  RepeatWrapping,
  Scene,
  Vector2,
  Vector3,
  Vector4,
  WebGLRenderer,
} from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { hairLayer, look } from './look.js';
import { faceMaterial, gazeMatrix } from './material.js';
import { addShadingAttributes } from './mesh.js';
import { MorphSource } from './morph.js';
import { Clip, FRAME_RATE } from './motion.js';
import { CLIP_BYTES, KeptFrames, Overlay, coarseToFine } from './kept.js';
import { StrainField } from './strain.js';

ColorManagement.enabled = false; // shade.glsl writes sRGB itself: no conversions anywhere

const CM_PER_M = 100;

// One probe context: is WebGL 2 there, and is it Chrome's software SwiftShader?
let probed = null;
export function probeWebGL() {
  if (probed) return probed;
  probed = { webgl2: false, swiftshader: false };
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    if (gl) {
      const info = gl.getExtension('WEBGL_debug_renderer_info');
      const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
      probed = { webgl2: true, swiftshader: /swiftshader/i.test(name) };
      gl.getExtension('WEBGL_lose_context')?.loseContext();
    }
  } catch {
    // no WebGL: the PNG fallback takes over
  }
  return probed;
}

// The camera: the GLB's own (asset.extras.emogen.camera, fitted to its identity's face, as the
// offscreen renderer fits it) or else the look's default framing.
function makeCamera(c = look.framings[look.framing]) {
  const camera = new PerspectiveCamera(c.fov_y_deg, 1, c.near_cm, c.far_cm);
  camera.up.set(...c.up);
  camera.position.set(...c.position_cm);
  camera.lookAt(new Vector3(...c.target_cm));
  camera.updateMatrixWorld();
  return camera;
}

// The identity's skin atlas and detail tile from the GLB (asset.extras.emogen.textures), set up
// as emogen.render.gl.GLRenderer.set_textures: trilinear mipmaps, the atlas clamped, the tile
// repeated, texels passed as they are (shade.glsl linearises; no colour-space conversion, no
// flip: row 0 is glTF v = 0). Null when the GLB has none. wrinkleStrength: the identity's
// (asset.extras.emogen.appearance.wrinkle_strength; 1 in GLBs written before it existed).
async function skinTextures(gltf, indices, appearance) {
  if (!indices) return null;
  const [skin, detail] = await Promise.all(
    [indices.skin, indices.detail].map((i) => gltf.parser.getDependency('texture', i)),
  );
  for (const [t, wrap] of [[skin, ClampToEdgeWrapping], [detail, RepeatWrapping]]) {
    t.colorSpace = NoColorSpace;
    t.flipY = false;
    t.wrapS = t.wrapT = wrap;
    t.minFilter = LinearMipmapLinearFilter;
    t.magFilter = LinearFilter;
    t.generateMipmaps = true;
    t.anisotropy = 1;
    t.needsUpdate = true;
  }
  return { skin, detail, wrinkleStrength: appearance?.wrinkle_strength ?? 1 };
}

// An object URL of the GLB's long-hair layer image (asset.extras.emogen.hair_layer), decoded
// before it is shown, so the first faces on screen have it; null when the GLB has none.
async function hairLayerUrl(gltf, index) {
  if (index === undefined) return null;
  const image = gltf.parser.json.images[index];
  const bytes = await gltf.parser.getDependency('bufferView', image.bufferView);
  const url = URL.createObjectURL(new Blob([bytes], { type: image.mimeType }));
  const img = new Image();
  img.src = url;
  await img.decode();
  return url;
}

export class FaceGrid {
  constructor(container, slots, { antialias } = {}) {
    this.container = container;
    this.slots = slots;
    this.canvas = document.createElement('canvas');
    this.canvas.className = 'faces-canvas';
    container.appendChild(this.canvas);
    const aa = antialias ?? !probeWebGL().swiftshader; // SwiftShader speckles with antialias
    this.renderer = new WebGLRenderer({ canvas: this.canvas, antialias: aa, alpha: true });
    this.renderer.outputColorSpace = LinearSRGBColorSpace;
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setScissorTest(true);
    this.renderer.autoClear = false;
    this.camera = makeCamera();
    this.background = new Color(...look.background_srgb);
    this.faces = [];
    this.hairUrl = null;
    this.shapeNames = [];
    this.drawnSize = null;
    this.kept = new Map(); // face → its KeptFrames (kept.js)
    this.overlay = null; // the 2D canvas playing kept frames, made by the first keep()
    new ResizeObserver(() => {
      const box = container.getBoundingClientRect();
      const key = `${Math.round(box.width)}x${Math.round(box.height)}`;
      if (this.faces.length && key !== this.drawnSize) this.render();
    }).observe(container);
  }

  /** Load the GLB (URL) and build one face per slot sharing its geometries. */
  async load(url) {
    const t0 = performance.now();
    const gltf = await new GLTFLoader().loadAsync(url);
    this.timings = { gltf_ms: performance.now() - t0 };
    const extras = gltf.asset?.extras?.emogen ?? {};
    this.asset = gltf.asset;
    if (extras.camera) this.camera = makeCamera(extras.camera);
    const textures = await skinTextures(gltf, extras.textures, extras.appearance);
    this.textured = textures !== null;
    this.hairUrl = await hairLayerUrl(gltf, extras.hair_layer);
    gltf.scene.updateMatrixWorld(true);
    const meshes = [];
    gltf.scene.traverse((o) => o.isMesh && meshes.push(o));
    if (!meshes.length) throw new Error(`${url} holds no mesh`);
    const t1 = performance.now();
    const prims = addShadingAttributes(meshes, extras.regions);
    this.timings.attributes_ms = performance.now() - t1;
    // The skin's strain per target (wrinkles), on the textured parts only, as shade.glsl uses it.
    const t3 = performance.now();
    const skinCodes = [look.shader.PART_SKIN, look.shader.PART_EYE_SOCKET];
    const strains = prims.map((p) =>
      textures && skinCodes.includes(look.parts.indexOf(p.part)) ? StrainField.of(p.mesh.geometry) : null,
    );
    this.timings.strain_ms = performance.now() - t3;
    const sources = prims.map((p, k) => new MorphSource(p.mesh.geometry, strains[k]));
    this.shapeNames = meshes[0].geometry.morphAttributes.position
      ? Object.keys(meshes[0].morphTargetDictionary ?? {}).sort(
          (a, b) => meshes[0].morphTargetDictionary[a] - meshes[0].morphTargetDictionary[b],
        )
      : [];
    this.gaze = extras.gaze ?? null;
    const shapeIndex = new Map(this.shapeNames.map((n, i) => [n, i]));
    if (this.gaze) {
      this.gazeIndex = {};
      for (const k of ['look_left', 'look_right', 'look_up', 'look_down']) {
        this.gazeIndex[k] = this.gaze[k].map((n) => shapeIndex.get(n)).filter((i) => i !== undefined);
      }
    }
    // Eye centres (metres in the GLB's scene) in each primitive's local coordinates.
    const centres = (mesh) => {
      if (!this.gaze) return null;
      const inv = new Matrix4().copy(mesh.matrixWorld).invert();
      return {
        left: new Vector3(...this.gaze.left_centre).applyMatrix4(inv),
        right: new Vector3(...this.gaze.right_centre).applyMatrix4(inv),
      };
    };
    const order = (p) => (p.opacity < 1 || p.fringe_cm > 0 ? 4 : 0) + (p.cutout ? 2 : 0) + (p.double_sided ? 1 : 0);
    for (let i = 0; i < this.slots.length; i++) {
      const scene = new Scene();
      const root = new Group();
      root.scale.setScalar(CM_PER_M);
      const copy = gltf.scene.clone(true); // shares geometries; own morph influences
      const copies = [];
      copy.traverse((o) => o.isMesh && copies.push(o));
      copies.forEach((mesh, k) => {
        mesh.geometry = sources[k].faceGeometry(meshes[k].geometry);
        mesh.morphTargetInfluences = undefined;
        mesh.morphTargetDictionary = undefined;
        mesh.material = faceMaterial(prims[k].part, centres(meshes[k]), textures, prims[k].codes);
        mesh.renderOrder = order(prims[k].part);
        mesh.frustumCulled = false;
      });
      root.add(copy);
      scene.add(root);
      this.faces.push({ scene, meshes: copies, sources, weights: null, shown: null });
    }
    // The shaders compiled without holding up the page (KHR_parallel_shader_compile where the
    // browser has it): a face model made ahead while the participant answers (see the study
    // page's viewer-adapter.js) must not delay their clicks. Every face shares the programs.
    const t4 = performance.now();
    await this.renderer.compileAsync(this.faces[0].scene, this.camera);
    this.timings.compile_ms = performance.now() - t4;
    const t2 = performance.now();
    this.render();
    this.timings.first_render_ms = performance.now() - t2; // commands issued, not yet drawn
  }

  /**
   * Weights per face: arrays in the GLB's morph-target order (the shapes, then any corrective
   * targets; a shorter array leaves the remaining targets at 0), or {target: value} objects.
   */
  setFaces(weights) {
    const n = Math.min(weights.length, this.faces.length);
    for (let i = 0; i < n; i++) this.setFace(i, weights[i]);
    this.render();
  }

  /** Weights ``w`` (an array in the GLB's order, or a {target: value} object) as the full
   * vector of the GLB's targets, for face ``i`` (named in the error). */
  vectorOf(w, i) {
    const vector = Array.isArray(w) || ArrayBuffer.isView(w)
      ? Array.from(w, Number)
      : this.shapeNames.map((name) => Number(w?.[name] ?? 0));
    if (vector.length > this.shapeNames.length) {
      throw new Error(`face ${i}: expected at most ${this.shapeNames.length} weights, got ${vector.length}`);
    }
    while (vector.length < this.shapeNames.length) vector.push(0);
    return vector;
  }

  /** Face ``i`` set to show weights ``w``: morphed to them now, or, a face with kept frames,
   * when it is drawn live. */
  setFace(i, w) {
    this.faces[i].shown = this.vectorOf(w, i);
    if (!this.kept.has(i)) this.morph(i, this.faces[i].shown);
  }

  /** Face ``i``'s meshes morphed to ``vector`` (unless they hold it already). */
  morph(i, vector) {
    const face = this.faces[i];
    if (!vector || (face.weights && vector.every((x, k) => x === face.weights[k]))) return;
    face.weights = vector;
    const active = [];
    vector.forEach((x, k) => x !== 0 && active.push(k));
    face.meshes.forEach((mesh, k) => face.sources[k].morph(mesh.geometry, vector, active));
    const [yaw, pitch] = this.gazeAngles(vector);
    for (const mesh of face.meshes) {
      gazeMatrix(yaw, pitch, mesh.material.uniforms.uEyeRotLeft.value);
      gazeMatrix(yaw, pitch, mesh.material.uniforms.uEyeRotRight.value);
    }
  }

  /**
   * Face ``i``'s faces known ahead (weight vectors, e.g. a slider's positions; null or
   * none: forget them): each is shown as the frame the live draw made for it, kept (kept.js);
   * idle animation frames draw the rest, nearest the one shown first.
   */
  keep(i, faces, options) {
    this.kept.get(i)?.clear();
    this.kept.delete(i);
    if (faces?.length) {
      this.kept.set(i, new KeptFrames(faces.map((w) => this.vectorOf(w, i)), options));
      this.overlay ??= new Overlay(this.canvas);
      this.ahead();
    } else if (this.faces[i].shown) {
      this.overlay?.uncover(i);
      this.render(); // drawn live again: the WebGL canvas under the kept frames may hold another
    }
  }

  /** Face ``i``'s kept frames: {shown: the position it shows (−1: none of them), showing: the
   * kept frame on screen (null: drawn live; another than ``shown`` while a clip's frames are
   * drawn ahead), kept, of, complete: none left to draw}; null when none are kept. */
  keptState(i) {
    const kept = this.kept.get(i);
    if (!kept) return null;
    const shown = this.faces[i].shown ? kept.find(this.faces[i].shown) : -1;
    const showing = this.overlay?.shows.get(i)?.[0] ?? null; // the kept frame on screen
    return { shown, showing, kept: kept.frames.size, of: kept.faces.length, complete: shown >= 0 && kept.complete(shown) };
  }

  /** The next frame to keep drawn at the next animation frame (one a frame, the faces in
   * turn), until none is left. */
  ahead() {
    if (this.aheadRaf) return;
    this.aheadRaf = requestAnimationFrame(() => {
      this.aheadRaf = null;
      if (this.drewLive) { // a face shown was drawn live in this frame: the next one draws ahead
        this.drewLive = false;
        return this.ahead();
      }
      const order = [...this.kept.keys()];
      const from = order.indexOf(this.aheadFrom) + 1;
      for (const i of [...order.slice(from), ...order.slice(0, from)]) {
        const kept = this.kept.get(i);
        const slot = this.slots[i].getBoundingClientRect();
        if (!slot.width || !slot.height) continue; // not on screen: nothing to draw
        const shown = this.faces[i].shown ? kept.find(this.faces[i].shown) : -1;
        const k = shown < 0 ? -1 : kept.next(shown);
        if (k < 0) continue;
        this.aheadFrom = i;
        if (!this.sameSize() || (k === shown && !kept.order)) this.render(); // drawn live, kept
        else this.drawAhead(i, kept, k, shown);
        this.ahead();
        return;
      }
    });
  }

  /** Frame ``k`` of face ``i`` drawn into its slot and kept, under the kept frame shown. */
  drawAhead(i, kept, k, shown) {
    const rect = this.viewport(i, this.container.getBoundingClientRect());
    this.morph(i, kept.faces[k]);
    this.renderer.clear();
    this.renderer.render(this.faces[i].scene, this.camera);
    kept.keep(k, this.canvas, rect, shown);
  }

  /**
   * Faces that move (motion.js): per face {weights, motion} (a face without motion stays as
   * setFaces left it). The clips play in sync from now, looped (clip, then the hold at rest),
   * one requestAnimationFrame a frame; null stops the playing.
   */
  play(faces) {
    cancelAnimationFrame(this.raf ?? 0);
    this.raf = null;
    this.forgetClips();
    const n = this.shapeNames.length;
    this.clips = (faces ?? []).map((f) => (f?.motion ? new Clip(f.weights, f.motion, n) : null));
    if (!this.clips.some(Boolean)) return;
    this.frame = new Float32Array(n);
    this.keepClips();
    this.held = new Map(); // face → clip time it is scrubbed to
    this.frames = 0; // frames drawn since play (the benchmark's count)
    this.slowDraws = 0; // draws in a row slower than two grid steps
    this.behind = false; // two of them seen: frames not kept yet show the nearest kept one
    this.last = null;
    this.start = performance.now();
    const tick = (now) => {
      this.draw(now);
      this.raf = requestAnimationFrame(tick);
    };
    this.raf = requestAnimationFrame(tick);
  }

  /** Every clip's grid frames kept (kept.js), when all of them fit in CLIP_BYTES at the tiles'
   * size now (else they are drawn live); the frames kept before given back. */
  keepClips() {
    this.forgetClips();
    const dpr = window.devicePixelRatio || 1;
    let bytes = 0;
    this.clips.forEach((clip, i) => {
      const r = this.slots[i].getBoundingClientRect();
      if (clip) bytes += (clip.steps + 1) * Math.ceil(r.width * dpr) * Math.ceil(r.height * dpr) * 4;
    });
    if (bytes > CLIP_BYTES) return; // drawn live
    const share = CLIP_BYTES / this.clips.filter(Boolean).length;
    this.clips.forEach((clip, i) => {
      if (!clip) return;
      const faces = Array.from({ length: clip.steps + 1 }, (_, k) => Array.from(clip.at(clip.gridTime(k), this.frame)));
      this.keep(i, faces, { bytes: share, order: coarseToFine(clip.steps) });
      this.clipKept.push(i);
    });
  }

  /** The clips' kept frames given back (a new screen, or the tiles' size changed). */
  forgetClips() {
    for (const i of this.clipKept ?? []) {
      this.kept.get(i)?.clear();
      this.kept.delete(i);
      this.overlay.uncover(i);
    }
    this.clipKept = [];
  }

  /** Every clip from its start again (scrubbed faces play along again). */
  replay() {
    this.held?.clear();
    this.start = performance.now();
  }

  /** Face ``i`` held at clip time ``t`` (s) while the others play; null lets it play again. */
  scrub(i, t) {
    if (t === null) this.held?.delete(i);
    else this.held?.set(i, t);
  }

  /** The clip time (s) face ``i`` shows now: its grid frame's, or the time it is scrubbed to
   * (null: it does not move). */
  clipTime(i, now = performance.now()) {
    const clip = this.clips?.[i];
    if (!clip) return null;
    if (this.held.has(i)) return this.held.get(i);
    return clip.gridTime(clip.gridFrame(clip.time((now - this.start) / 1000)));
  }

  draw(now) {
    // two draws in a row slower than two of the grid's steps: from then on the faces' frames
    // not kept yet show the nearest kept one while the rest are drawn ahead
    const slow = this.last !== null && now - this.last > 2000 / FRAME_RATE;
    this.slowDraws = slow ? this.slowDraws + 1 : 0;
    this.behind ||= this.slowDraws >= 2;
    this.last = now;
    this.clips.forEach((clip, i) => {
      if (clip) this.setFace(i, clip.at(this.clipTime(i, now), this.frame));
    });
    this.render();
    this.frames++;
  }

  gazeAngles(vector) {
    if (!this.gaze) return [0, 0];
    const mean = (idx) => (idx.length ? idx.reduce((a, k) => a + vector[k], 0) / idx.length : 0);
    const g = this.gaze, ix = this.gazeIndex, rad = Math.PI / 180;
    const yaw = g.yaw_deg * rad * (mean(ix.look_left) - mean(ix.look_right));
    const pitch = g.pitch_up_deg * rad * mean(ix.look_up) - g.pitch_down_deg * rad * mean(ix.look_down);
    return [yaw, pitch];
  }

  /** Whether the container still has the size last drawn. */
  sameSize() {
    const box = this.container.getBoundingClientRect();
    return `${Math.max(1, Math.round(box.width))}x${Math.max(1, Math.round(box.height))}` === this.drawnSize;
  }

  /** Viewport, scissor and camera set to face ``i``'s slot; its rectangle in the canvas's
   * device pixels from the top left, [x, y, width, height]. */
  viewport(i, box) {
    const r = this.renderer;
    const rect = this.slots[i].getBoundingClientRect();
    const x = rect.left - box.left;
    const y = box.bottom - rect.bottom;
    r.setViewport(x, y, rect.width, rect.height);
    r.setScissor(x, y, rect.width, rect.height);
    this.camera.aspect = rect.width / rect.height;
    this.camera.updateProjectionMatrix();
    const v = r.getCurrentViewport(new Vector4());
    return [v.x, this.canvas.height - v.y - v.w, v.z, v.w];
  }

  render() {
    // The slots show the long-hair layer of the grid drawn in them (grids of other identities
    // may share the slots: a page keeps one per identity, hidden until shown), or none.
    if (this.canvas.style.visibility !== 'hidden') {
      for (const slot of this.slots) hairLayer(slot, this.hairUrl);
    }
    const r = this.renderer;
    const box = this.container.getBoundingClientRect();
    const width = Math.max(1, Math.round(box.width));
    const height = Math.max(1, Math.round(box.height));
    const size = r.getSize(new Vector2());
    if (size.x !== width || size.y !== height) r.setSize(width, height, true);
    const resized = this.drawnSize !== `${width}x${height}`;
    if (resized) {
      for (const kept of this.kept.values()) kept.clear(); // frames of another size
      this.overlay?.fit();
    }
    this.drawnSize = `${width}x${height}`;
    if (resized && this.clips?.some(Boolean)) this.keepClips(); // if they fit at the new size
    r.setScissor(0, 0, width, height);
    r.setClearColor(0x000000, 0);
    r.clear();
    r.setClearColor(this.background, 1);
    this.faces.forEach((face, i) => {
      const rect = this.viewport(i, box);
      const kept = this.kept.get(i);
      const k = kept && face.shown ? kept.find(face.shown) : -1;
      if (k >= 0 && this.overlay.play(i, k, kept.frames.get(k))) return;
      const near = k >= 0 && kept.order && this.behind ? kept.nearest(k) : null;
      if (near && this.overlay.play(i, ...near)) return this.ahead(); // a clip's frame: not yet
      this.morph(i, face.shown);
      r.clear();
      r.render(face.scene, this.camera);
      if (k >= 0) {
        if (!kept.frames.has(k)) kept.keep(k, this.canvas, rect, k);
        this.overlay.copy(i, k, rect);
        this.drewLive = true;
        this.ahead();
      } else {
        this.overlay?.uncover(i);
      }
    });
  }

  /** Shown (true) or hidden, the kept frames' canvas with it. */
  setVisible(visible) {
    this.canvas.style.visibility = visible ? '' : 'hidden';
    if (this.overlay) this.overlay.canvas.style.visibility = this.canvas.style.visibility;
  }

  /** Playing stopped, kept frames given back, the canvases taken off the page. */
  remove() {
    this.play(null);
    cancelAnimationFrame(this.aheadRaf ?? 0);
    for (const kept of this.kept.values()) kept.clear();
    this.kept.clear();
    this.canvas.remove();
    this.overlay?.canvas.remove();
  }
}
