#pragma once
// GLSL 4.50 sources of the renderer. Every program starts with kCommon: the per-view uniform block and
// the sky function (its C++ twin is render::SkyColor in renderer.cpp; keep the two identical).

namespace sphxr::render::shaders {

inline constexpr const char* kCommon = R"(#version 450 core
layout(std140, binding = 0) uniform ViewBlock {
  mat4 uView;
  mat4 uProj;
  mat4 uViewProj;
  mat4 uInvViewProj;
  vec4 uEye;          // xyz: camera position in the world
  vec4 uSun;          // xyz: unit vector towards the sun
  vec4 uViewport;     // x, y, width, height in pixels
  vec4 uAbsorption;   // rgb: Beer-Lambert coefficients, 1/m
  vec4 uWaterColor;   // rgb: inscattered colour
  vec4 uParticle;     // x: radius (m), y: pixels per (m / eye depth) for point sizes
};

vec3 SkyColor(vec3 d) {
  vec3 horizon = vec3(0.80, 0.87, 0.95);
  vec3 zenith = vec3(0.22, 0.45, 0.85);
  vec3 ground = vec3(0.62, 0.63, 0.64);
  float t = clamp(d.y, -1.0, 1.0);
  vec3 c = t >= 0.0 ? mix(horizon, zenith, sqrt(t)) : mix(horizon, ground, sqrt(-t));
  float s = max(dot(d, uSun.xyz), 0.0);
  c += vec3(1.0, 0.9, 0.7) * (4.0 * pow(s, 800.0) + 0.15 * pow(s, 8.0));
  return clamp(c, 0.0, 1.0);
}

// Blue -> cyan -> green -> yellow -> red for s in [0, 1].
vec3 ColorMap(float s) {
  s = clamp(s, 0.0, 1.0);
  vec3 c0 = vec3(0.10, 0.20, 0.85), c1 = vec3(0.05, 0.75, 0.90), c2 = vec3(0.20, 0.80, 0.25);
  vec3 c3 = vec3(0.95, 0.85, 0.15), c4 = vec3(0.90, 0.15, 0.10);
  float x = s * 4.0;
  if (x < 1.0) return mix(c0, c1, x);
  if (x < 2.0) return mix(c1, c2, x - 1.0);
  if (x < 3.0) return mix(c2, c3, x - 2.0);
  return mix(c3, c4, x - 3.0);
}
)";

// ---- sky: one full-screen triangle ---------------------------------------------------------------
inline constexpr const char* kSkyVs = R"(
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";
inline constexpr const char* kSkyFs = R"(
layout(location = 0) out vec4 outColor;
void main() {
  vec2 ndc = (gl_FragCoord.xy - uViewport.xy) / uViewport.zw * 2.0 - 1.0;
  vec4 far = uInvViewProj * vec4(ndc, 1.0, 1.0);
  vec3 dir = normalize(far.xyz / far.w - uEye.xyz);
  outColor = vec4(SkyColor(dir), 1.0);
}
)";

// ---- lit solids: floor, obstacles, paddles --------------------------------------------------------
inline constexpr const char* kSolidVs = R"(
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 0) uniform mat4 uModel;
out vec3 vWorld;
out vec3 vNormal;
void main() {
  vec4 w = uModel * vec4(aPosition, 1.0);
  vWorld = w.xyz;
  vNormal = mat3(transpose(inverse(uModel))) * aNormal;
  gl_Position = uViewProj * w;
}
)";
inline constexpr const char* kSolidFs = R"(
in vec3 vWorld;
in vec3 vNormal;
layout(location = 1) uniform vec4 uColor;    // rgb, a = 1
layout(location = 2) uniform vec4 uChecker;  // x: square size in m (0: plain), y: fade distance
layout(location = 0) out vec4 outColor;
void main() {
  vec3 n = normalize(vNormal);
  vec3 base = uColor.rgb;
  if (uChecker.x > 0.0) {
    ivec2 cell = ivec2(floor(vWorld.xz / uChecker.x));
    base *= ((cell.x + cell.y) & 1) == 0 ? 1.0 : 0.82;
  }
  float diffuse = max(dot(n, uSun.xyz), 0.0);
  vec3 ambient = 0.45 * SkyColor(n);
  vec3 c = base * (ambient + 0.65 * diffuse);
  if (uChecker.y > 0.0) {  // the floor fades into the horizon
    vec3 toFrag = vWorld - uEye.xyz;
    float fade = smoothstep(0.3 * uChecker.y, uChecker.y, length(toFrag.xz));
    c = mix(c, SkyColor(normalize(toFrag)), fade);  // seamless into the sky behind
  }
  outColor = vec4(c, 1.0);
}
)";

// ---- lines: tank edges ----------------------------------------------------------------------------
inline constexpr const char* kLineVs = R"(
layout(location = 0) in vec3 aPosition;
layout(location = 0) uniform mat4 uModel;
void main() { gl_Position = uViewProj * uModel * vec4(aPosition, 1.0); }
)";
inline constexpr const char* kLineFs = R"(
layout(location = 1) uniform vec4 uColor;
layout(location = 0) out vec4 outColor;
void main() { outColor = uColor; }
)";

// ---- water surface mesh ---------------------------------------------------------------------------
// Pass 0 (uPass 0): thickness, additive into an R32F target: +distance for surfaces facing away from
// the eye, -distance for surfaces facing it, so a closed surface sums to the length of water on the ray.
// Pass 1: depth only. Pass 2: shading of the nearest surface (depth test LEQUAL), dual-source blend
// dst = colour + dst * transmission.
inline constexpr const char* kMeshVs = R"(
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
out vec3 vWorld;
out vec3 vNormal;
invariant gl_Position;
void main() {
  vWorld = aPosition;
  vNormal = aNormal;
  gl_Position = uViewProj * vec4(aPosition, 1.0);
}
)";

inline constexpr const char* kWaterShade = R"(
layout(binding = 0) uniform sampler2D uThickness;
layout(location = 0, index = 0) out vec4 outColor;
layout(location = 0, index = 1) out vec4 outTransmission;
void ShadeWater(vec3 world, vec3 n, float specWeight) {
  vec3 v = normalize(uEye.xyz - world);
  if (dot(n, v) < 0.0) n = -n;
  float cosT = clamp(dot(n, v), 0.0, 1.0);
  float fresnel = 0.02 + 0.98 * pow(1.0 - cosT, 5.0);  // Schlick, water n = 1.33
  vec3 r = reflect(-v, n);
  vec3 reflection = SkyColor(r);
  float spec = specWeight * 3.0 * pow(max(dot(r, uSun.xyz), 0.0), 300.0);
  float thickness = max(texelFetch(uThickness, ivec2(gl_FragCoord.xy - uViewport.xy), 0).r, 0.0);
  vec3 transmission = exp(-uAbsorption.rgb * thickness);
  // Light scattered back by the water body grows as the light behind it is absorbed.
  vec3 body = uWaterColor.rgb * (vec3(1.0) - transmission) * (0.55 + 0.45 * max(uSun.y, 0.0));
  outColor = vec4(fresnel * reflection + (1.0 - fresnel) * body + spec, 1.0);
  outTransmission = vec4((1.0 - fresnel) * transmission, 1.0);
}
)";

inline constexpr const char* kMeshFs = R"(
in vec3 vWorld;
in vec3 vNormal;
layout(location = 3) uniform int uPass;
void main() {
  vec3 n = normalize(vNormal);
  if (uPass == 0) {
    vec3 toFrag = vWorld - uEye.xyz;
    float facing = dot(n, toFrag) > 0.0 ? 1.0 : -1.0;  // outward normal away from the eye: back face
    outColor = vec4(facing * length(toFrag), 0.0, 0.0, 0.0);
    outTransmission = vec4(0.0);
    return;
  }
  if (uPass == 1) {
    outColor = vec4(0.0);
    outTransmission = vec4(1.0);
    return;
  }
  ShadeWater(vWorld, n, 1.0);
}
)";

// ---- particles as point sprites (spheres) ---------------------------------------------------------
// aParticle: xyz position, w the colour scalar in [0, 1]. uPass as for the mesh; uPass 3: opaque
// particle mode (colour map).
inline constexpr const char* kSpriteVs = R"(
layout(location = 0) in vec4 aParticle;
out vec3 vCenterEye;
out float vScalar;
void main() {
  vec4 eye = uView * vec4(aParticle.xyz, 1.0);
  vCenterEye = eye.xyz;
  vScalar = aParticle.w;
  gl_Position = uProj * eye;
  gl_PointSize = max(2.0 * uParticle.x * uParticle.y / max(-eye.z, 1e-4), 1.0);
}
)";
inline constexpr const char* kSpriteFs = R"(
in vec3 vCenterEye;
in float vScalar;
layout(location = 3) uniform int uPass;
void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  d.y = -d.y;
  float r2 = dot(d, d);
  if (r2 > 1.0) discard;
  float z = sqrt(1.0 - r2);
  vec3 nEye = vec3(d, z);
  if (uPass == 0) {  // chord length through the sphere
    outColor = vec4(2.0 * z * uParticle.x, 0.0, 0.0, 0.0);
    outTransmission = vec4(0.0);
    return;
  }
  vec3 pEye = vCenterEye + nEye * uParticle.x;
  vec4 clip = uProj * vec4(pEye, 1.0);
  gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
  vec3 nWorld = transpose(mat3(uView)) * nEye;
  if (uPass == 1) {
    outColor = vec4(0.0);
    outTransmission = vec4(1.0);
    return;
  }
  if (uPass == 3) {
    vec3 base = ColorMap(vScalar);
    float diffuse = max(dot(nWorld, uSun.xyz), 0.0);
    vec3 c = base * (0.35 + 0.65 * diffuse) + 0.25 * pow(max(dot(reflect(-normalize(-pEye), nEye),
                                                               mat3(uView) * uSun.xyz), 0.0), 40.0);
    outColor = vec4(c, 1.0);
    outTransmission = vec4(0.0);
    return;
  }
  // Water from particles: each sphere's normal is flattened towards the eye, so that the body of
  // overlapping spheres shades like one surface rather than a heap of glittering beads.
  vec3 world = (inverse(uView) * vec4(pEye, 1.0)).xyz;
  vec3 flattened = transpose(mat3(uView)) * normalize(vec3(0.35 * d, 1.0));
  // No sun glint: the beads' tilted normals would sparkle where a real surface would not.
  ShadeWater(world, normalize(flattened), 0.0);
}
)";

}  // namespace sphxr::render::shaders
