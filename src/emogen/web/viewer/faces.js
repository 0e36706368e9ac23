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
  WebGLRenderer,
} from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { hairLayer, look } from './look.js';
import { faceMaterial, gazeMatrix } from './material.js';
import { addShadingAttributes } from './mesh.js';
import { MorphSource } from './morph.js';
import { Clip } from './motion.js';
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
      this.faces.push({ scene, meshes: copies, sources, weights: null });
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

  /** Face ``i`` set to weights ``w`` (morphed to them unless it shows them already). */
  setFace(i, w) {
    const vector = Array.isArray(w) || ArrayBuffer.isView(w)
      ? Array.from(w, Number)
      : this.shapeNames.map((name) => Number(w?.[name] ?? 0));
    if (vector.length > this.shapeNames.length) {
      throw new Error(`face ${i}: expected at most ${this.shapeNames.length} weights, got ${vector.length}`);
    }
    while (vector.length < this.shapeNames.length) vector.push(0);
    const face = this.faces[i];
    if (face.weights && vector.every((x, k) => x === face.weights[k])) return;
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
   * Faces that move (motion.js): per face {weights, motion} (a face without motion stays as
   * setFaces left it). The clips play in sync from now, looped (clip, then the hold at rest),
   * one requestAnimationFrame a frame; null stops the playing.
   */
  play(faces) {
    cancelAnimationFrame(this.raf ?? 0);
    this.raf = null;
    const n = this.shapeNames.length;
    this.clips = (faces ?? []).map((f) => (f?.motion ? new Clip(f.weights, f.motion, n) : null));
    if (!this.clips.some(Boolean)) return;
    this.frame = new Float32Array(n);
    this.held = new Map(); // face → clip time it is scrubbed to
    this.frames = 0; // frames drawn since play (the benchmark's count)
    this.start = performance.now();
    const tick = (now) => {
      this.draw(now);
      this.raf = requestAnimationFrame(tick);
    };
    this.raf = requestAnimationFrame(tick);
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

  /** The clip time (s) face ``i`` shows now (null: it does not move). */
  clipTime(i, now = performance.now()) {
    const clip = this.clips?.[i];
    if (!clip) return null;
    return this.held.has(i) ? this.held.get(i) : clip.time((now - this.start) / 1000);
  }

  draw(now) {
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
    this.drawnSize = `${width}x${height}`;
    r.setScissor(0, 0, width, height);
    r.setClearColor(0x000000, 0);
    r.clear();
    r.setClearColor(this.background, 1);
    this.faces.forEach((face, i) => {
      const rect = this.slots[i].getBoundingClientRect();
      const x = rect.left - box.left;
      const y = box.bottom - rect.bottom;
      r.setViewport(x, y, rect.width, rect.height);
      r.setScissor(x, y, rect.width, rect.height);
      this.camera.aspect = rect.width / rect.height;
      this.camera.updateProjectionMatrix();
      r.clear();
      r.render(face.scene, this.camera);
    });
  }
}
