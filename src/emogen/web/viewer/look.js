// The look shared with the offscreen renderer: look.json and shade.glsl, bundled at build time.
import look from '../../render/look.json';
import shadeGlsl from '../../render/shaders/shade.glsl';

export { look, shadeGlsl };

function glslFloat(x) {
  return Number(x).toFixed(6);
}

// `#define` lines for shade.glsl, written exactly as emogen.render.look.Look.glsl_defines does.
export function glslDefines(shader = look.shader) {
  let out = '';
  for (const [key, value] of Object.entries(shader)) {
    const text = Array.isArray(value)
      ? `vec${value.length}(${value.map(glslFloat).join(', ')})`
      : glslFloat(value);
    out += `#define ${key} ${text}\n`;
  }
  return out;
}

export function srgbToLinear(c) {
  return c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4;
}

// A layer over a face's square slot that shows it through a framing's oval (look.json's mask)
// on the look's background, as emogen.render.images.apply_oval does offscreen: the oval's edge
// ramps over about one pixel. Styled here (inline, no stylesheet rule), above the faces' canvas
// (z-index 1) and below what the page draws after the slot. Nothing when the framing has no oval
// (face, head); an earlier layer is kept (or taken away).
export function ovalLayer(slot, framing) {
  const oval = look.framings[framing]?.mask;
  let layer = slot.querySelector(':scope > .oval-layer');
  if (!oval) {
    layer?.remove();
    return null;
  }
  const [cx, cy] = oval.centre, [rx, ry] = oval.radii;
  const bg = look.background_srgb.map((c) => Math.round(255 * c)).join(', ');
  if (!layer) {
    layer = document.createElement('div');
    layer.className = 'oval-layer';
    Object.assign(layer.style, { position: 'absolute', inset: '0', zIndex: '2', pointerEvents: 'none' });
    slot.appendChild(layer);
  }
  layer.style.background =
    `radial-gradient(ellipse ${100 * rx}% ${100 * ry}% at ${100 * cx}% ${100 * cy}%, ` +
    `rgba(${bg}, 0) calc(100% - 0.5px), rgb(${bg}) calc(100% + 0.5px))`;
  return layer;
}

// The identity's long-hair layer (hair = "long": emogen.appearance.long_hair) over a face's
// slot, as emogen.render.renderer composites it offscreen: one RGBA image (the GLB's image
// asset.extras.emogen.hair_layer, WebP) stretched over the slot, above the canvas and below the
// oval layer (which hides it outside the oval, as offscreen). url null: an earlier layer is
// taken away. Called by each draw of the grid shown in the slot (cheap when nothing changed).
export function hairLayer(slot, url) {
  let layer = slot.querySelector(':scope > .hair-layer');
  if (!url) {
    layer?.remove();
    return null;
  }
  if (!layer) {
    layer = document.createElement('div');
    layer.className = 'hair-layer';
    Object.assign(layer.style, {
      position: 'absolute', inset: '0', zIndex: '2', pointerEvents: 'none',
      backgroundSize: '100% 100%', backgroundRepeat: 'no-repeat',
    });
    slot.insertBefore(layer, slot.querySelector(':scope > .oval-layer'));
  }
  if (layer.dataset.url !== url) {
    layer.dataset.url = url;
    layer.style.backgroundImage = `url(${url})`;
  }
  return layer;
}
