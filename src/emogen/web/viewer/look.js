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
