// EmoGen shading, compiled as-is by both the offscreen renderer (moderngl, GLSL 3.30) and the
// browser viewer (three.js ShaderMaterial, GLSL ES 3.00), so a face looks the same in both.
// The constants (KEY_DIR, PUPIL_DEG, …) are #defines generated from render/look.json.
//
// Inputs per fragment:
//   part    : part code (index into look.json "parts"; exact on the eyes, which are separate meshes)
//   albedo  : linear RGB base colour (per vertex, interpolated: stitched skin parts blend smoothly)
//   surface : (specular, shininess, cavity) per vertex
//   pos     : world position in cm; n: unit normal; v: unit direction to the camera
//   eye     : xyz = unit direction from the eyeball centre in the eye's rest frame (z = eye axis),
//             w = side (1 left, 2 right, 0 not an eye); on skin (w = 0): x the lower lid's wet
//             margin, y the inner eye corner, in [0, 1] (look.json lid_margin)
//   uv      : glTF texture coordinates (u counts UDIM tiles: face 0-1, head 1-2; v down)
//   strain  : rotation-free (Biot) strain of the skin in UV axes (εuu, εvv, εuv; −0.2:
//             compressed by 20 %), the face's morph targets' strains blended by its weights
//             (emogen/render/wrinkles.py, viewer/strain.js)
//
// Textures (skin and eye-socket parts, when emogenTextured > 0.5): emogenSkin, the identity's skin atlas
// (SKIN_TILES tiles side by side, sRGB); emogenDetail, a tileable micro-relief (R height,
// G roughness) repeated DETAIL_TILES times per tile. Both are sampled unconditionally (mipmap
// derivatives need uniform control flow) and used only on skin. emogenWrinkleStrength: the
// identity's wrinkle_strength (emogen.appearance.Appearance; 1 the look of every earlier
// version), scaling the depth and shade of the strain wrinkles and folds.

// Which kinds of part a draw holds: the offscreen renderer compiles one program per draw group
// with the kinds its triangles have (gl.py); the browser's one material keeps both. A software
// rasteriser (llvmpipe) runs both sides of every branch, so the code that no fragment of a group
// needs is compiled out rather than branched around (the result is the same).
#ifndef EMOGEN_SKIN
#define EMOGEN_SKIN 1 // skin and eye-socket parts: skin texture, micro-relief, wrinkles
#endif
#ifndef EMOGEN_EYES
#define EMOGEN_EYES 1 // eyeballs (sclera, iris): iris, eyeball shade, catchlights
#endif

uniform sampler2D emogenSkin;
uniform sampler2D emogenDetail;
uniform float emogenTextured;
uniform float emogenWrinkleStrength;

vec3 emogenToLinear(vec3 c) {
    vec3 lo = c / 12.92;
    vec3 hi = pow((c + 0.055) / 1.055, vec3(2.4));
    return mix(hi, lo, vec3(lessThanEqual(c, vec3(0.04045))));
}

vec3 emogenToSrgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    vec3 lo = c * 12.92;
    vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(hi, lo, vec3(lessThanEqual(c, vec3(0.0031308))));
}

bool emogenIsEye(float part) {
    return abs(part - PART_SCLERA) < 0.5 || abs(part - PART_IRIS) < 0.5;
}

// Angle (degrees) of an eye direction from the eye axis.
float emogenEyeAngle(vec4 eye) {
    vec3 e = normalize(eye.xyz);
    return degrees(acos(clamp(e.z, -1.0, 1.0)));
}

// The ICT sclera mesh is an outer shell whose front is a transparent cornea bulge: drop it so
// the iris on the inner ball shows through.
bool emogenHidden(float part, vec4 eye) {
    return abs(part - PART_SCLERA) < 0.5 && eye.w > 0.5 && emogenEyeAngle(eye) < CORNEA_DEG;
}

// Iris and pupil painted on the inner eyeball by angle from the eye axis (linear RGB).
vec3 emogenIris(vec4 eye, vec3 scleraLinear) {
    float th = emogenEyeAngle(eye);
    vec3 e = normalize(eye.xyz);
    float ph = atan(e.y, e.x);
    if (th < PUPIL_DEG) {
        return emogenToLinear(PUPIL_SRGB);
    }
    float t = (th - PUPIL_DEG) / (IRIS_DEG - PUPIL_DEG);
    if (t > 1.0) {
        return scleraLinear;
    }
    float fibres = 0.5 + 0.3 * sin(ph * 41.0 + 1.7 * sin(ph * 7.0)) + 0.2 * sin(ph * 23.0 + 5.0 * t);
    vec3 inner = emogenToLinear(IRIS_INNER_SRGB);
    vec3 outer = emogenToLinear(IRIS_OUTER_SRGB);
    vec3 c = mix(inner, outer, smoothstep(0.25, 0.6, t));
    c *= 0.7 + 0.6 * fibres;
    c *= 1.0 + 0.35 * exp(-pow((t - 0.3) / 0.08, 2.0));
    c = mix(emogenToLinear(PUPIL_SRGB), c, smoothstep(0.0, 0.08, t));
    c = mix(c, emogenToLinear(LIMBUS_SRGB), smoothstep(0.78, 1.0, t));
    return c;
}

// The eyeball's own shading (no shadows are cast): darker toward the corners, away from the
// eye axis, and under the upper lid, which shades the top of the visible ball.
float emogenEyeShade(vec4 eye) {
    vec3 e = normalize(eye.xyz);
    float corner = 1.0 - EYE_CORNER_SHADE * smoothstep(IRIS_DEG, 55.0, emogenEyeAngle(eye));
    float lid = 1.0 - EYE_LID_SHADE * smoothstep(0.10, 0.45, e.y);
    return corner * lid;
}

// Two lights and a sky/ground ambient. wrap (per channel) lets light reach past the terminator:
// skin's soft light bleed, wider in red than in blue (wrap lighting as a cheap stand-in for
// subsurface scattering; Green 2004, GPU Gems ch. 16). Eyes take no wrap.
vec3 emogenLight(vec3 n, vec3 v, vec3 albedo, float spec, float shin, vec3 wrap) {
    vec3 l1 = normalize(KEY_DIR);
    vec3 l2 = normalize(FILL_DIR);
    float n1 = dot(n, l1);
    float n2 = dot(n, l2);
    vec3 d1 = max((vec3(n1) + wrap) / (1.0 + wrap), 0.0);
    vec3 d2 = max((vec3(n2) + wrap) / (1.0 + wrap), 0.0);
    float s1 = n1 > 0.0 ? spec * pow(max(dot(n, normalize(l1 + v)), 0.0), shin) : 0.0;
    float s2 = n2 > 0.0 ? spec * pow(max(dot(n, normalize(l2 + v)), 0.0), shin) : 0.0;
    vec3 hemi = mix(GROUND_RGB, SKY_RGB, 0.5 + 0.5 * n.y);
    return albedo * (hemi + KEY_RGB * d1 + FILL_RGB * d2) + KEY_RGB * s1 + FILL_RGB * s2;
}

// The catchlights: the key and fill lights mirrored by the cornea, whose normal (in the eye's
// frame, z the axis) turns CORNEA_CURVE times faster than the direction from the eye's centre.
// Approximates the eye frame by the camera's (gaze turns the eyes by at most ~25°).
vec3 emogenCatchlight(vec4 eye, vec3 v) {
    vec3 e = normalize(eye.xyz);
    vec3 c = normalize(vec3(e.xy * CORNEA_CURVE, e.z));
    float k = pow(max(dot(c, normalize(normalize(KEY_DIR) + v)), 0.0), CATCH_SHININESS);
    float f = pow(max(dot(c, normalize(normalize(FILL_DIR) + v)), 0.0), CATCH_SHININESS);
    float onCornea = 1.0 - smoothstep(IRIS_DEG - 2.0, IRIS_DEG + 1.0, emogenEyeAngle(eye));
    return CATCH_STRENGTH * onCornea * (KEY_RGB * k + 0.5 * FILL_RGB * f);
}

// Normal perturbed by a height field h (cm) from screen-space derivatives (no tangents needed).
vec3 emogenBump(vec3 pos, vec3 n, float h) {
    vec3 dpdx = dFdx(pos);
    vec3 dpdy = dFdy(pos);
    float dhdx = dFdx(h);
    float dhdy = dFdy(h);
    vec3 r1 = cross(dpdy, n);
    vec3 r2 = cross(n, dpdx);
    float det = dot(dpdx, r1);
    vec3 grad = sign(det) * (dhdx * r1 + dhdy * r2);
    vec3 bumped = abs(det) * n - grad;
    float len = length(bumped);
    return len > 1e-12 ? bumped / len : n;
}

// A smooth periodic wave in [0, 1], 1 at the integers (the shape of 0.5 + 0.5 cos 2πx, at a
// few operations instead of a sine's polynomial: the rasteriser may be software).
float emogenWave(float x) {
    float t = abs(fract(x) - 0.5) * 2.0;
    return t * t * (3.0 - 2.0 * t);
}

// Furrows across lines of constant x (UV units): 1 in a furrow, 0 between. The lines wander
// and fade along y so that they do not look ruled.
float emogenFurrows(float x, float y) {
    float k = 1.0 / WRINKLE_PERIOD_UV;
    float ph = x * k + 0.35 * sin(y * k * 0.45 + 1.3) + 0.24 * emogenWave(y * k * 0.207);
    float s = emogenWave(ph);
    float along = 0.55 + 0.45 * emogenWave(y * k * 0.127 + 0.43 * floor(ph + 0.5));
    return s * s * along;
}

// Wrinkles of skin under strain: (furrow depth in cm, furrow shade in [0, 1]). Compression c
// along four directions of the UV plane (c = −eᵀ ε e; ε the rotation-free strain) makes furrows
// across each, from WRINKLE_START to full depth at WRINKLE_FULL; the sharpening keeps the
// dominant direction. Skin held taut across that direction (stretched from TAUT_START, flat
// from TAUT_FULL: the jaw's sides under jawOpen) stays smooth: only slack skin buckles.
vec2 emogenWrinkles(vec2 uv, vec3 strain) {
    float mean = 0.5 * (strain.x + strain.y);
    vec4 c = -vec4(strain.x, strain.y, mean + strain.z, mean - strain.z);
    float cmax = max(max(c.x, c.y), max(c.z, c.w));
    vec2 out_ = vec2(0.0);
    // Most skin is not compressed: skip the furrows there (the caller's derivatives of the
    // result are taken outside this branch, in uniform control flow).
    if (cmax > WRINKLE_START) {
        vec4 share = clamp(c / cmax, 0.0, 1.0);
        share *= share;
        vec4 slack = vec4(1.0) - smoothstep(vec4(TAUT_START), vec4(TAUT_FULL), -c.yxwz);
        vec4 a = smoothstep(vec4(WRINKLE_START), vec4(WRINKLE_FULL), c) * share * share * slack;
        float r = 0.70710678;
        float f = a.x * emogenFurrows(uv.x, uv.y) + a.y * emogenFurrows(uv.y, uv.x)
            + a.z * emogenFurrows((uv.x + uv.y) * r, (uv.x - uv.y) * r)
            + a.w * emogenFurrows((uv.x - uv.y) * r, (uv.x + uv.y) * r);
        float fold = max(max(a.x, a.y), max(a.z, a.w));
        out_ = vec2(WRINKLE_DEPTH_CM * f, WRINKLE_SHADE * f + FOLD_SHADE * fold);
    }
    return out_;
}

// Final sRGB colour of a fragment.
vec3 emogenShade(float part, vec3 albedo, vec3 surface, vec3 pos, vec3 n, vec3 v, vec4 eye,
                 bool front, vec2 uv, vec3 strain) {
#if EMOGEN_SKIN
    vec3 skin = texture(emogenSkin, vec2(uv.x / SKIN_TILES, uv.y)).rgb;
    vec3 detail = texture(emogenDetail, uv * DETAIL_TILES).rgb;
    vec2 wrinkle = emogenWrinkleStrength * emogenWrinkles(uv, strain);
    vec3 bumped = emogenBump(pos, n, (detail.r - 0.5) * DETAIL_BUMP_CM - wrinkle.x);
    bool textured = emogenTextured > 0.5
        && (abs(part - PART_SKIN) < 0.5 || abs(part - PART_EYE_SOCKET) < 0.5);
    if (textured) {
        albedo = emogenToLinear(skin) * max(1.0 - wrinkle.y, 0.0);
        surface.x *= 1.0 + DETAIL_SPECULAR * (2.0 * detail.g - 1.0);
        n = bumped;
    }
    // The lower lid's wet margin (the tear line, with its highlight) and the inner corner (the
    // caruncle): weights on the skin vertices that touch the eyeball, in eye.xy (eye.w = 0;
    // scene.py and mesh.js from look.json's lid_margin). Branch-free: most fragments have 0.
    vec2 lid = eye.xy * (1.0 - step(0.5, eye.w));
    albedo *= mix(vec3(1.0), TEAR_TINT_RGB, lid.x) * mix(vec3(1.0), CARUNCLE_TINT_RGB, lid.y);
    surface.xy = mix(surface.xy, vec2(WET_SPECULAR, WET_SHININESS), max(lid.x, lid.y));
#endif
    bool isEye = EMOGEN_EYES != 0 && emogenIsEye(part);
    bool isIris = isEye && abs(part - PART_IRIS) < 0.5 && eye.w > 0.5;
    if (!front) {
        if (isEye) {
            return EYE_INTERIOR_SRGB;
        }
        n = -n;
    }
    vec3 base = albedo;
    if (isIris) {
        // The back of the inner ball is only ever seen through the pupil: the eye's interior.
        if (emogenEyeAngle(eye) > 90.0) {
            return EYE_INTERIOR_SRGB;
        }
        base = emogenIris(eye, albedo);
    }
    if (isEye && eye.w > 0.5) {
        // The caruncle's pink flesh in the eye's inner corner (nasal: −x on the left eye).
        float nasal = (eye.w < 1.5 ? -eye.x : eye.x) / length(eye.xyz);
        base = mix(base, emogenToLinear(CARUNCLE_SRGB), smoothstep(CARUNCLE_FROM, CARUNCLE_FULL, nasal));
        base *= emogenEyeShade(eye);
    }
    // No shadows: deep in the mouth gets darker with depth behind the lips instead.
    float depth = smoothstep(CAVITY_Z_BACK, CAVITY_Z_FRONT, pos.z);
    float cavity = mix(1.0, mix(CAVITY_MIN, 1.0, depth), clamp(surface.z, 0.0, 1.0));
    vec3 wrap = isEye ? vec3(0.0) : SKIN_WRAP_RGB;
    vec3 lit = emogenLight(n, v, base * cavity, surface.x * cavity, surface.y, wrap);
    if (isIris) {
        lit += emogenCatchlight(eye, v);
    }
    return emogenToSrgb(lit);
}
