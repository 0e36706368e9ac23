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

// The CSS background that shows a face's square tile through a framing's oval (look.json's
// mask) on the look's background, as emogen.render.images.apply_oval does offscreen: the oval's
// edge ramps over about one pixel. null: the framing has no oval (face, head).
export function ovalMask(framing) {
  const oval = look.framings[framing]?.mask;
  if (!oval) return null;
  const [cx, cy] = oval.centre, [rx, ry] = oval.radii;
  const bg = look.background_srgb.map((c) => Math.round(255 * c)).join(', ');
  return (
    `radial-gradient(ellipse ${100 * rx}% ${100 * ry}% at ${100 * cx}% ${100 * cy}%, ` +
    `rgba(${bg}, 0) calc(100% - 0.5px), rgb(${bg}) calc(100% + 0.5px))`
  );
}
