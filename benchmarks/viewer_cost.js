// The page side of bench_viewer_cost.py: loaded into the viewer page (viewer/index.html) once its
// faces are drawn; each function redraws for ms milliseconds, one draw per animation frame, and
// returns {frames, seconds, note}.
/* global window, document, performance, requestAnimationFrame, createImageBitmap */
(() => {
  const view = () => window.emogen.view;
  const nextFrame = () => new Promise((resolve) => requestAnimationFrame(resolve));

  // Weights of frame k: 30 shapes swept between rest and a fixed mix, back and forth over 40 frames.
  function sweepWeights(n, k) {
    const w = new Float32Array(n);
    const s = (k % 40 < 20 ? k % 40 : 40 - (k % 40)) / 20;
    for (let j = 0; j < Math.min(30, n); j++) w[j] = (s * ((j * 7) % 10)) / 10;
    return w;
  }

  async function loop(ms, drawFrame) {
    let frames = 0;
    const t0 = performance.now();
    while (performance.now() - t0 < ms) {
      drawFrame(frames);
      frames += 1;
      await nextFrame();
    }
    return { frames, seconds: (performance.now() - t0) / 1000 };
  }

  const morphAll = (v, w) => v.faces.forEach((_, i) => v.setFace(i, w));

  /** The faces as drawn; only: that primitive alone; plain: its skin section compiled out. */
  async function sweep({ ms, only = null, plain = 0 }) {
    const v = view();
    const n = v.shapeNames.length;
    const saved = v.faces.map((f) => f.meshes.map((m) => [m.visible, m.material]));
    for (const f of v.faces) {
      f.meshes.forEach((m, k) => {
        if (only !== null) m.visible = k === only;
        if (plain && k === only) {
          const c = m.material.clone();
          c.fragmentShader = c.fragmentShader.replace('#define EMOGEN_SKIN 1', '#define EMOGEN_SKIN 0');
          if (c.fragmentShader === m.material.fragmentShader) throw new Error('no skin section');
          m.material = c;
        }
      });
    }
    const r = await loop(ms, (k) => {
      morphAll(v, sweepWeights(n, k));
      v.render();
    });
    v.faces.forEach((f, i) => f.meshes.forEach((m, k) => ([m.visible, m.material] = saved[i][k])));
    return r;
  }

  // A seeded uniform [0, 1) (the same samples at every run).
  function random(seed) {
    let s = seed >>> 0;
    return () => {
      s = (Math.imul(s, 1664525) + 1013904223) >>> 0;
      return s / 4294967296;
    };
  }

  // Face k of the samples: every target alone at 1, then random sparse faces.
  function sampleWeights(n, k, rand) {
    const w = new Float32Array(n);
    if (k < n) w[k] = 1;
    else for (let j = 0; j < n; j++) if (rand() < 0.15) w[j] = rand();
    return w;
  }

  // A material drawing each triangle's number + 1 as RGB: the face's vertex shader and uniforms
  // (gaze) and its cut-outs, no blending.
  function idMaterial(material) {
    const m = material.clone();
    m.uniforms = material.uniforms;
    const tri = 'attribute float aTri;\nflat varying float vTri;\nvoid main() {\n    vTri = aTri;';
    m.vertexShader = material.vertexShader.replace('void main() {', tri);
    const at = material.fragmentShader.lastIndexOf('void main() {');
    const rgb = 'float(id & 255), float((id >> 8) & 255), float((id >> 16) & 255)';
    m.fragmentShader =
      material.fragmentShader.slice(0, at) +
      'flat varying float vTri;\n' +
      material.fragmentShader
        .slice(at)
        .replace(
          'gl_FragColor = vec4(c, vSurface.w);',
          `int id = int(vTri + 0.5) + 1;\n    gl_FragColor = vec4(${rgb}, 255.0) / 255.0;`,
        );
    m.transparent = false;
    m.depthWrite = true;
    m.blending = 0; // NoBlending
    return m;
  }

  function readFace(v, i) {
    const gl = v.renderer.getContext();
    const box = v.container.getBoundingClientRect();
    const rect = v.slots[i].getBoundingClientRect();
    const [x, y] = [Math.round(rect.left - box.left), Math.round(box.bottom - rect.bottom)];
    const [w, h] = [Math.round(rect.width), Math.round(rect.height)];
    const out = new Uint8Array(w * h * 4);
    gl.readPixels(x, y, w, h, gl.RGBA, gl.UNSIGNED_BYTE, out);
    return out;
  }

  // Which triangles of face 0 (numbered across its primitives) showed in its ID buffer over
  // ``samples`` faces. Blended primitives hide nothing behind them: left out of the ID buffer.
  function seenTriangles(v, samples, blended, offsets, total) {
    const n = v.shapeNames.length;
    const meshes = v.faces[0].meshes;
    const seen = new Uint8Array(total);
    const saved = meshes.map((m) => [m.geometry, m.material, m.visible]);
    const ids = meshes.map((m) => idMaterial(m.material));
    const rand = random(1);
    for (let s = 0; s < samples; s++) {
      v.setFace(0, sampleWeights(n, s, rand));
      meshes.forEach((m, k) => {
        if (blended[k]) return void (m.visible = false);
        const flat = saved[k][0].toNonIndexed();
        const tri = new Float32Array(flat.attributes.position.count);
        for (let j = 0; j < tri.length; j++) tri[j] = offsets[k] + Math.floor(j / 3);
        flat.setAttribute('aTri', new flat.attributes.position.constructor(tri, 1));
        m.geometry = flat;
        m.material = ids[k];
      });
      v.render();
      const px = readFace(v, 0);
      for (let p = 0; p < px.length; p += 4) {
        const id = px[p] + 256 * px[p + 1] + 65536 * px[p + 2] - 1;
        if (id >= 0 && id < total) seen[id] = 1;
      }
      meshes.forEach((m, k) => {
        if (!blended[k]) m.geometry.dispose();
        [m.geometry, m.material, m.visible] = saved[k];
      });
    }
    return seen;
  }

  // An index of the triangles seen (seen: one flag a triangle of this primitive) and ``rings``
  // rings of neighbours (triangles sharing a vertex with a kept one).
  function keptIndex(index, vertices, seen, rings) {
    const idx = index.array;
    const count = idx.length / 3;
    const kept = Uint8Array.from(seen);
    for (let ring = 0; ring < rings; ring++) {
      const near = new Uint8Array(vertices);
      for (let t = 0; t < count; t++) {
        if (kept[t]) for (let c = 0; c < 3; c++) near[idx[3 * t + c]] = 1;
      }
      for (let t = 0; t < count; t++) {
        if (near[idx[3 * t]] || near[idx[3 * t + 1]] || near[idx[3 * t + 2]]) kept[t] = 1;
      }
    }
    const keep = [];
    for (let t = 0; t < count; t++) if (kept[t]) keep.push(...idx.subarray(3 * t, 3 * t + 3));
    return new index.constructor(new idx.constructor(keep), 1);
  }

  // Face 0 drawn with each index set (use(set)) over eight faces not among the samples:
  // [pixels differing, their largest channel difference, pixels compared].
  function comparePixels(v, use, full, culled) {
    const other = random(2);
    const n = v.shapeNames.length;
    let differ = 0, worst = 0, pixels = 0;
    for (let s = 0; s < 8; s++) {
      v.setFace(0, sampleWeights(n, n, other));
      const [a, b] = [full, culled].map((which) => {
        use(which);
        v.render();
        return readFace(v, 0);
      });
      pixels += a.length / 4;
      for (let p = 0; p < a.length; p += 4) {
        const d = Math.max(...[0, 1, 2].map((c) => Math.abs(a[p + c] - b[p + c])));
        if (d > 0) differ += 1;
        worst = Math.max(worst, d);
      }
    }
    return [differ, worst, pixels];
  }

  let uncull = () => {};

  /**
   * Option 1: the faces drawn with only the triangles a triangle-ID buffer ever showed (and
   * their neighbours) until uncull(); returns what it kept and how its pixels compare.
   */
  function cull({ samples, rings }) {
    const v = view();
    const faces = v.faces;
    v.faces = [faces[0]]; // one face drawn while measuring
    const meshes = faces[0].meshes;
    const blended = meshes.map((m) => m.material.transparent);
    const counts = meshes.map((m) => m.geometry.index.count / 3);
    const offsets = counts.map((_, k) => counts.slice(0, k).reduce((a, b) => a + b, 0));
    const total = counts.reduce((a, b) => a + b, 0);
    const t0 = performance.now();
    const seen = seenTriangles(v, samples, blended, offsets, total);
    const idMs = performance.now() - t0;
    const full = meshes.map((m) => m.geometry.index);
    const culled = meshes.map((m, k) => {
      if (blended[k]) return full[k]; // kept whole
      const own = seen.subarray(offsets[k], offsets[k] + counts[k]);
      return keptIndex(full[k], m.geometry.attributes.position.count, own, rings);
    });
    const kept = culled.reduce((a, c) => a + c.count / 3, 0);
    const use = (which) => faces.forEach((f) => f.meshes.forEach((m, k) => m.geometry.setIndex(which[k])));
    const [differ, worst, pixels] = comparePixels(v, use, full, culled);
    v.faces = faces;
    use(culled);
    uncull = () => use(full);
    const share = ((100 * kept) / total).toFixed(0);
    return (
      `${kept} of ${total} triangles (${share} %) from ${samples} faces' ID buffers and ${rings} ` +
      `ring(s) of neighbours (${(idMs / 1000).toFixed(1)} s); 8 other faces: ${differ} of ` +
      `${pixels} pixels differ (at most ${worst}/255)`
    );
  }

  /** Option 3: 20 frames per face rendered ahead, played by a 2D canvas's drawImage. */
  async function prerendered({ ms }) {
    const v = view();
    const n = v.shapeNames.length;
    const box = v.container.getBoundingClientRect();
    const rects = v.slots.map((s) => s.getBoundingClientRect());
    const count = 20;
    const t0 = performance.now();
    const frames = [];
    for (let k = 0; k < count; k++) {
      morphAll(v, sweepWeights(n, 2 * k));
      v.render();
      const [x, y] = [(r) => r.left - box.left, (r) => r.top - box.top];
      frames.push(rects.map((r) => createImageBitmap(v.canvas, x(r), y(r), r.width, r.height)));
    }
    const bitmaps = await Promise.all(frames.map((f) => Promise.all(f)));
    const aheadMs = performance.now() - t0;
    const canvas = document.createElement('canvas');
    canvas.width = Math.round(box.width);
    canvas.height = Math.round(box.height);
    Object.assign(canvas.style, { position: 'fixed', left: `${box.left}px`, top: `${box.top}px` });
    document.body.appendChild(canvas);
    const ctx = canvas.getContext('2d');
    const r = await loop(ms, (k) => {
      rects.forEach((r, i) => ctx.drawImage(bitmaps[k % count][i], r.left - box.left, r.top - box.top));
    });
    canvas.remove();
    const ahead = (aheadMs / 1000).toFixed(1);
    r.note = `${count} frames of ${v.faces.length} face(s) rendered ahead in ${ahead} s`;
    return r;
  }

  window.viewerCost = { sweep, cull, uncull: () => uncull(), prerendered };
})();
