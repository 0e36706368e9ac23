// The face material: the face as morph.js morphed it (positions, normals and the skin's strain
// as attributes) + rigid eye rotation in the vertex shader, and the fragment shading of
// shade.glsl (the same text the offscreen renderer compiles). Skin is textured by the identity's
// atlas and detail tile from the GLB (see faces.js), sampled with glTF's TEXCOORD_0 (three's
// built-in `uv` attribute).
import { DoubleSide, FrontSide, Matrix3, NormalBlending, ShaderMaterial, Vector3 } from 'three';
import { glslDefines, look, shadeGlsl } from './look.js';

const vertexShader = /* glsl */ `
#include <common>
attribute vec3 aStrain;
attribute float aPart;
attribute vec3 aAlbedo;
attribute vec4 aSurface;
attribute vec4 aEye;
uniform mat3 uEyeRotLeft;
uniform mat3 uEyeRotRight;
uniform vec3 uEyeCentreLeft;
uniform vec3 uEyeCentreRight;
varying vec3 vStrain;
varying vec3 vWorld;
varying vec3 vNormal;
varying float vPart;
varying vec3 vAlbedo;
varying vec4 vSurface;
varying vec4 vEye;
varying vec2 vUv;
void main() {
    vec3 objectNormal = vec3(normal);
    vec3 transformed = vec3(position);
    vStrain = aStrain;
    if (aEye.w > 0.5) {
        bool left = aEye.w < 1.5;
        mat3 r = left ? uEyeRotLeft : uEyeRotRight;
        vec3 c = left ? uEyeCentreLeft : uEyeCentreRight;
        transformed = r * (transformed - c) + c;
        objectNormal = r * objectNormal;
    }
    vec4 world = modelMatrix * vec4(transformed, 1.0);
    vWorld = world.xyz;
    vNormal = mat3(modelMatrix) * objectNormal;
    vPart = aPart;
    vAlbedo = aAlbedo;
    vSurface = aSurface;
    vEye = aEye;
    vUv = uv;
    gl_Position = projectionMatrix * viewMatrix * world;
}
`;

const fragmentMain = /* glsl */ `
varying vec3 vWorld;
varying vec3 vNormal;
varying float vPart;
varying vec3 vAlbedo;
varying vec4 vSurface;
varying vec4 vEye;
varying vec2 vUv;
varying vec3 vStrain;
void main() {
#ifdef EMOGEN_DISCARD
    if (emogenHidden(vPart, vEye)) discard;
#endif
    vec3 n = normalize(vNormal);
    vec3 v = normalize(cameraPosition - vWorld);
    vec3 c = emogenShade(vPart, vAlbedo, vSurface.xyz, vWorld, n, v, vEye, gl_FrontFacing, vUv, vStrain);
    gl_FragColor = vec4(c, vSurface.w);
}
`;

/**
 * A material for one primitive whose vertices belong to `part` (a look.json part).
 * textures: {skin, detail} three.js Textures of the identity and its wrinkleStrength (see
 * skinTextures in faces.js), or null: every part in its flat look.json colour. codes: [lowest,
 * highest] part code of the primitive's vertices (null: any).
 */
export function faceMaterial(part, eyeCentres, textures = null, codes = null) {
  const blended = part.opacity < 1 || part.fringe_cm > 0;
  // Compile out what no fragment of the primitive runs (as gl.py per draw group): SwiftShader,
  // like llvmpipe, runs both sides of a branch. codes: [lowest, highest] part code it holds.
  const holds = (...names) =>
    !codes || names.some((n) => codes[0] - 0.5 < look.shader[n] && look.shader[n] < codes[1] + 0.5);
  const kinds =
    `#define EMOGEN_SKIN ${holds('PART_SKIN', 'PART_EYE_SOCKET') ? 1 : 0}\n` +
    `#define EMOGEN_EYES ${holds('PART_SCLERA', 'PART_IRIS') ? 1 : 0}\n`;
  return new ShaderMaterial({
    vertexShader,
    fragmentShader:
      (part.cutout ? '#define EMOGEN_DISCARD\n' : '') + kinds + glslDefines() + shadeGlsl + fragmentMain,
    uniforms: {
      uEyeRotLeft: { value: new Matrix3() },
      uEyeRotRight: { value: new Matrix3() },
      uEyeCentreLeft: { value: eyeCentres?.left?.clone() ?? new Vector3() },
      uEyeCentreRight: { value: eyeCentres?.right?.clone() ?? new Vector3() },
      emogenSkin: { value: textures?.skin ?? null },
      emogenDetail: { value: textures?.detail ?? null },
      emogenTextured: { value: textures ? 1 : 0 },
      emogenWrinkleStrength: { value: textures?.wrinkleStrength ?? 1 },
    },
    side: part.double_sided ? DoubleSide : FrontSide,
    transparent: blended,
    depthWrite: !blended,
    blending: NormalBlending,
  });
}

/** Gaze rotation as emogen.model.face.gaze_rotations: R = Ry(yaw) · Rx(pitch), row-major. */
export function gazeMatrix(yaw, pitch, target = new Matrix3()) {
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  // ry = [[cy,0,sy],[0,1,0],[-sy,0,cy]]; rx = [[1,0,0],[0,cp,sp],[0,-sp,cp]]
  return target.set(
    cy, -sy * sp, sy * cp,
    0, cp, sp,
    -sy, -cy * sp, cy * cp,
  );
}
