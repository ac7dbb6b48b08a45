#pragma once
// GLSL 4.50 sources of the renderer's passes. Every program starts with kCommon (the per-view uniform
// block, the sky and the colour map; their C++ twins are render::SkyColor in renderer.cpp: keep the two
// identical). A pass that shares a source with another names itself with a #define (kDefine...), never
// an integer uniform. Programs() lists every program the renderer links; a test compiles each one
// offline with glslangValidator.
#include <vector>

namespace sphxr::render::shaders {

inline constexpr const char* kCommon = R"(#version 450 core
layout(std140, binding = 0) uniform ViewBlock {
  mat4 uView;
  mat4 uProj;
  mat4 uViewProj;
  mat4 uInvViewProj;
  mat4 uShadowViewProj; // world -> the sun's clip space (orthographic)
  vec4 uEye;            // xyz: camera position in the world
  vec4 uSun;            // xyz: unit vector towards the sun
  vec4 uViewport;       // x, y, width, height in pixels
  vec4 uAbsorption;     // rgb: Beer-Lambert coefficients, 1/m (scene scale included)
  vec4 uWaterColor;     // rgb: inscattered colour
  vec4 uParticle;       // x: radius (m), y: pixels per (m / eye depth) for point sizes, z: diffuse radius (m)
  vec4 uOptics;         // x: Fresnel F0 of water, y: index of refraction, w: shadow depth range (m)
  vec4 uTarget;         // xy: size in texels of the frame targets (the views use their lower-left corner)
  vec4 uTankMin;        // xyz: the tank's lower corner, w: the absorption's scene scale
  vec4 uTankMax;        // xyz: the tank's upper corner
  vec4 uPlace;          // x: ground height, y: tile size (m), z: fade distance (m), w: table top height
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

// World position of a pixel of this view at window depth z (0..1).
vec3 WorldAt(vec2 viewPixel, float z) {
  vec2 ndc = viewPixel / uViewport.zw * 2.0 - 1.0;
  vec4 w = uInvViewProj * vec4(ndc, z * 2.0 - 1.0, 1.0);
  return w.xyz / w.w;
}
)";

// Pixel of a fragment inside its view (the frame targets hold the view at their lower-left corner).
inline constexpr const char* kViewPixel = R"(
ivec2 ViewPixel() { return ivec2(gl_FragCoord.xy - uViewport.xy); }
)";

// The sun's light on a receiver. With SUN_SHADOWS (the programs' shadowed variants, used when the
// render quality has a shadow map): the shadow of the opaque casters (one hardware PCF tap: the 2x2
// texels around the point, compared and blended) and, for receivers inside the tank, Beer-Lambert over
// the water between them and the sun. Without it, full sunlight: a software rasteriser runs a branch's
// texture fetches even where no pixel takes it, so "shadows off" must not be a uniform.
inline constexpr const char* kDefineShadows = "#define SUN_SHADOWS 1\n";
inline constexpr const char* kSunLight = R"(
#if defined(SUN_SHADOWS)
layout(binding = 4) uniform sampler2DShadow uShadowMap;
layout(binding = 5) uniform sampler2D uWaterShadowMap;
vec3 SunVisibility(vec3 world, vec3 n) {
  vec4 c = uShadowViewProj * vec4(world + n * 0.002 * uOptics.w, 1.0);
  vec3 p = c.xyz / c.w * 0.5 + 0.5;
  if (any(lessThan(p, vec3(0.0))) || any(greaterThan(p, vec3(1.0)))) return vec3(1.0);
  const float bias = 0.0015;
  vec3 light = vec3(texture(uShadowMap, vec3(p.xy, p.z - bias)));
  // Light that crossed water to reach a receiver in the tank: real water's absorption (the scene scale
  // is for the colour seen along the eye's path); light leaving through the glass walls is refocused
  // into caustics, which are not drawn, so receivers outside the tank see no water shadow.
  bool inTank = all(greaterThanEqual(world, uTankMin.xyz - 1e-4)) && all(lessThanEqual(world, uTankMax.xyz + 1e-4));
  if (inTank) {
    float waterTop = texture(uWaterShadowMap, p.xy).r;
    float below = max(p.z - waterTop, 0.0) * uOptics.w;
    light *= exp(-uAbsorption.rgb / uTankMin.w * below);
  }
  return light;
}
#else
vec3 SunVisibility(vec3 world, vec3 n) { return vec3(1.0); }
#endif
)";

// ---- sky: one full-screen triangle at the far plane (drawn where nothing else is) ---------------
inline constexpr const char* kFullScreenVs = R"(
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  gl_Position = vec4(p * 2.0 - 1.0, 1.0, 1.0);
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

// ---- present: the opaque scene (colour and depth) into the view's framebuffer --------------------
inline constexpr const char* kPresentFs = R"(
layout(binding = 1) uniform sampler2D uSceneColor;
layout(binding = 2) uniform sampler2D uSceneDepth;
layout(location = 0) out vec4 outColor;
void main() {
  ivec2 px = ViewPixel();
  outColor = vec4(texelFetch(uSceneColor, px, 0).rgb, 1.0);
  gl_FragDepth = texelFetch(uSceneDepth, px, 0).r;
}
)";

// ---- lit solids: ground, table, obstacles, paddles, controllers -----------------------------------
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
// Materials: 0 plain (a colour), 1 ground (stone tiles fading into the horizon), 2 wood (the table).
inline constexpr const char* kSolidFs = R"(
in vec3 vWorld;
in vec3 vNormal;
layout(location = 1) uniform vec4 uColor;    // rgb, a = 1
layout(location = 2) uniform int uMaterial;
layout(location = 0) out vec4 outColor;
float Hash(vec2 p) { return fract(sin(dot(p, vec2(127.1, 311.7))) * 43758.5453); }
void main() {
  vec3 n = normalize(vNormal);
  vec3 base = uColor.rgb;
  if (uMaterial == 1) {  // stone tiles; the grout fades with distance before it can alias
    vec2 cell = floor(vWorld.xz / uPlace.y);
    vec2 f = fract(vWorld.xz / uPlace.y);
    vec2 width = fwidth(vWorld.xz / uPlace.y);
    float lineWidth = 0.02;
    vec2 edge = smoothstep(vec2(lineWidth) - width, vec2(lineWidth) + width, min(f, 1.0 - f));
    float grout = mix(1.0, edge.x * edge.y, clamp(1.0 - 4.0 * max(width.x, width.y), 0.0, 1.0));
    base *= mix(0.7, 0.92 + 0.12 * Hash(cell), grout);
  } else if (uMaterial == 2) {  // wood: fine grain along the table's length
    float along = abs(n.y) > 0.5 ? vWorld.z : vWorld.y;
    float warp = 0.004 * sin(23.0 * vWorld.x + 3.0 * vWorld.z) + 0.002 * sin(71.0 * vWorld.x);
    float grain = 0.5 + 0.5 * sin(900.0 * (along + warp));
    base *= 0.9 + 0.1 * grain * (1.0 - clamp(200.0 * fwidth(along), 0.0, 1.0));
  }
  float diffuse = max(dot(n, uSun.xyz), 0.0);
  vec3 ambient = 0.45 * SkyColor(n);
  vec3 c = base * (ambient + 0.65 * diffuse * SunVisibility(vWorld, n));
  if (uMaterial == 1) {  // the ground fades into the horizon
    vec3 toFrag = vWorld - uEye.xyz;
    float fade = smoothstep(0.3 * uPlace.z, uPlace.z, length(toFrag.xz));
    c = mix(c, SkyColor(normalize(toFrag)), fade);  // seamless into the sky behind
  }
  outColor = vec4(c, 1.0);
}
)";

// ---- shadow casters: depth only, from the sun ----------------------------------------------------
inline constexpr const char* kShadowVs = R"(
layout(location = 0) in vec3 aPosition;
layout(location = 0) uniform mat4 uModel;
void main() { gl_Position = uShadowViewProj * uModel * vec4(aPosition, 1.0); }
)";
inline constexpr const char* kShadowFs = R"(
void main() {}
)";

// ---- glass: the tank's panes and edges -----------------------------------------------------------
// dst = reflection + dst * (1 - alpha) (premultiplied): Schlick with glass's F0 = 0.04, a faint tint,
// and the edges, seen through the pane's width, a denser green.
inline constexpr const char* kGlassFs = R"(
in vec3 vWorld;
in vec3 vNormal;
layout(location = 1) uniform vec4 uColor;  // rgb: tint, a: base opacity (panes low, edges high)
layout(location = 0) out vec4 outColor;
void main() {
  vec3 n = normalize(vNormal);
  vec3 v = normalize(uEye.xyz - vWorld);
  if (dot(n, v) < 0.0) n = -n;
  float cosT = clamp(dot(n, v), 0.0, 1.0);
  float fresnel = 0.04 + 0.96 * pow(1.0 - cosT, 5.0);
  vec3 r = reflect(-v, n);
  float alpha = clamp(fresnel + uColor.a, 0.0, 1.0);
  vec3 lit = uColor.rgb * (0.45 * SkyColor(n) + 0.65 * max(dot(n, uSun.xyz), 0.0));
  vec3 c = fresnel * SkyColor(r) + uColor.a * lit + 2.0 * fresnel * pow(max(dot(r, uSun.xyz), 0.0), 400.0);
  outColor = vec4(c, alpha);
}
)";

// ---- particle mode: sphere sprites coloured by a scalar -------------------------------------------
// aParticle: xyz position, w the colour scalar in [0, 1].
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
// The sphere under a point sprite's pixel: its eye-space normal and position; writes its depth.
inline constexpr const char* kSphere = R"(
in vec3 vCenterEye;
in float vScalar;
bool SpherePixel(out vec3 nEye, out vec3 pEye, out vec2 d) {
  d = gl_PointCoord * 2.0 - 1.0;
  d.y = -d.y;
  float r2 = dot(d, d);
  if (r2 > 1.0) return false;
  nEye = vec3(d, sqrt(1.0 - r2));
  pEye = vCenterEye + nEye * uParticle.x;
  vec4 clip = uProj * vec4(pEye, 1.0);
  gl_FragDepth = clamp(0.5 * clip.z / clip.w + 0.5, 0.0, 1.0);
  return true;
}
)";
inline constexpr const char* kParticleFs = R"(
layout(location = 0) out vec4 outColor;
void main() {
  vec3 nEye, pEye;
  vec2 d;
  if (!SpherePixel(nEye, pEye, d)) discard;
  vec3 base = ColorMap(vScalar);
  vec3 nWorld = transpose(mat3(uView)) * nEye;
  float diffuse = max(dot(nWorld, uSun.xyz), 0.0);
  vec3 c = base * (0.35 + 0.65 * diffuse) + 0.25 * pow(max(dot(reflect(-normalize(-pEye), nEye),
                                                             mat3(uView) * uSun.xyz), 0.0), 40.0);
  outColor = vec4(c, 1.0);
}
)";

// ---- water ---------------------------------------------------------------------------------------
// Three passes share the water's geometry (the surface mesh, or sphere sprites without one):
//   WATER_THICKNESS  additive into an R32F target: mesh: +distance on faces turned away from the eye,
//                    -distance on faces towards it (a closed surface sums to the water's length on the
//                    ray); sprites: the chord through the sphere
//   WATER_DEPTH      depth only: the nearest water surface (the mesh; sprites shade with the depth test)
//   WATER_SHADE      the nearest surface, shaded over the opaque scene kept as textures (ShadeWater)
inline constexpr const char* kDefineThickness = "#define WATER_THICKNESS 1\n";
inline constexpr const char* kDefineDepth = "#define WATER_DEPTH 1\n";
inline constexpr const char* kDefineShade = "#define WATER_SHADE 1\n";

// The water's optics at a surface point (normal n out of the water):
//   F = F0 + (1 - F0)(1 - n.v)^5                         Schlick, F0 = ((n_w - 1)/(n_w + 1))^2 = 0.020
//   path = min(thickness, distance to the opaque scene behind)
//   t = refract(-v, n, 1/n_w); the scene behind is sampled where the refracted ray is after crossing
//       the water's length along the view ray (the lateral shift of a slab), rejected where that pixel's
//       opaque depth is in front of the water
//   colour = F env(reflect) + (1 - F) (body + behind exp(-sigma path)) + sun specular
inline constexpr const char* kWaterShade = R"(
layout(binding = 0) uniform sampler2D uThickness;
layout(binding = 1) uniform sampler2D uSceneColor;
layout(binding = 2) uniform sampler2D uSceneDepth;
layout(location = 0) out vec4 outColor;

vec3 SceneBehind(vec3 world, vec3 v, vec3 n, float path, float sceneDistance) {
  ivec2 px = ViewPixel();
  vec3 straight = texelFetch(uSceneColor, px, 0).rgb;
  vec3 t = refract(-v, n, 1.0 / uOptics.y);
  if (dot(t, t) == 0.0 || uOptics.y == 1.0) return straight;
  float along = max(dot(t, -v), 1e-3);
  vec3 shift = (t / along + v) * path;          // lateral shift after crossing `path` of water
  vec3 behind = world - v * min(sceneDistance, 1e4) + shift;
  vec4 clip = uViewProj * vec4(behind, 1.0);
  if (clip.w <= 0.0) return straight;
  vec2 pixel = (clip.xy / clip.w * 0.5 + 0.5) * uViewport.zw;
  if (any(lessThan(pixel, vec2(0.5))) || any(greaterThan(pixel, uViewport.zw - 0.5))) return straight;
  // Rejected where the scene at the shifted pixel lies in front of the water (it is not behind it).
  if (texelFetch(uSceneDepth, ivec2(pixel), 0).r < gl_FragCoord.z) return straight;
  return texture(uSceneColor, pixel / uTarget.xy).rgb;
}

void ShadeWater(vec3 world, vec3 n, float specWeight) {
  vec3 v = normalize(uEye.xyz - world);
  if (dot(n, v) < 0.0) n = -n;
  float cosT = clamp(dot(n, v), 0.0, 1.0);
  float fresnel = uOptics.x + (1.0 - uOptics.x) * pow(1.0 - cosT, 5.0);
  vec3 r = reflect(-v, n);
  vec3 reflection = SkyColor(r);
  float spec = specWeight * 3.0 * pow(max(dot(r, uSun.xyz), 0.0), 300.0) * SunVisibility(world, n).g;
  ivec2 px = ViewPixel();
  float thickness = max(texelFetch(uThickness, px, 0).r, 0.0);
  float sceneZ = texelFetch(uSceneDepth, px, 0).r;
  float sceneDistance = sceneZ >= 1.0 ? 1e9 : distance(world, WorldAt(vec2(px) + 0.5, sceneZ));
  float path = min(thickness, sceneDistance);
  vec3 transmission = exp(-uAbsorption.rgb * path);
  // Light scattered back by the water body grows as the light behind it is absorbed.
  vec3 body = uWaterColor.rgb * (vec3(1.0) - transmission) * (0.55 + 0.45 * max(uSun.y, 0.0));
  vec3 behind = SceneBehind(world, v, n, path, sceneDistance);
  outColor = vec4(fresnel * reflection + (1.0 - fresnel) * (body + behind * transmission) + spec, 1.0);
}
)";

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
inline constexpr const char* kMeshFs = R"(
in vec3 vWorld;
in vec3 vNormal;
#if defined(WATER_THICKNESS)
layout(location = 0) out vec4 outColor;
void main() {
  vec3 toFrag = vWorld - uEye.xyz;
  float facing = dot(normalize(vNormal), toFrag) > 0.0 ? 1.0 : -1.0;  // normal away from the eye: back face
  outColor = vec4(facing * length(toFrag), 0.0, 0.0, 0.0);
}
#elif defined(WATER_DEPTH)
void main() {}
#else
void main() { ShadeWater(vWorld, normalize(vNormal), 1.0); }
#endif
)";

inline constexpr const char* kWaterSpriteFs = R"(
#if defined(WATER_THICKNESS)
layout(location = 0) out vec4 outColor;
#endif
void main() {
  vec3 nEye, pEye;
  vec2 d;
  if (!SpherePixel(nEye, pEye, d)) discard;
#if defined(WATER_THICKNESS)
  outColor = vec4(2.0 * nEye.z * uParticle.x, 0.0, 0.0, 0.0);  // chord length through the sphere
#elif defined(WATER_SHADE)
  // Each sphere's normal is flattened towards the eye, so that the body of overlapping spheres shades
  // like one surface rather than a heap of glittering beads; no sun glint for the same reason.
  vec3 world = (inverse(uView) * vec4(pEye, 1.0)).xyz;
  vec3 flattened = transpose(mat3(uView)) * normalize(vec3(0.35 * d, 1.0));
  ShadeWater(world, normalize(flattened), 0.0);
#endif
}
)";

// ---- diffuse particles: spray, foam and bubbles as soft sprites stretched along their velocity ----
// Read from a storage buffer (two vec4 per particle: position with w = remaining lifetime, velocity
// with w = the kind: 0 spray, 1 foam, 2 bubble), six vertices per particle. DIFFUSE_BUBBLES draws the
// bubbles (into the opaque scene, so that the water refracts them); otherwise spray and foam (on top).
inline constexpr const char* kDefineBubbles = "#define DIFFUSE_BUBBLES 1\n";
inline constexpr const char* kDiffuseVs = R"(
layout(std430, binding = 0) readonly buffer Diffuse { vec4 uDiffuse[]; };
out vec2 vCorner;
out float vFade;
flat out int vKind;
void main() {
  int i = gl_VertexID / 6, k = gl_VertexID % 6;
  vec4 p = uDiffuse[2 * i], vel = uDiffuse[2 * i + 1];
  vKind = int(vel.w + 0.5);
#if defined(DIFFUSE_BUBBLES)
  bool keep = vKind == 2;
#else
  bool keep = vKind != 2;
#endif
  const vec2 corners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
  vec2 c = corners[k];
  vCorner = c;
  vFade = clamp(p.w / 0.5, 0.0, 1.0);  // fades out over its last half second
  vec4 eye = uView * vec4(p.xyz, 1.0);
  vec3 velEye = mat3(uView) * vel.xyz;
  float r = uParticle.z * (vKind == 0 ? 0.6 : (vKind == 2 ? 0.7 : 1.0));
  // Stretched along the velocity seen on the screen by the distance it moves in 1/90 s (a frame).
  vec2 dir = length(velEye.xy) > 1e-5 ? normalize(velEye.xy) : vec2(1.0, 0.0);
  float stretch = length(velEye.xy) / 90.0;
  vec2 along = dir * (r + 0.5 * stretch), across = vec2(-dir.y, dir.x) * r;
  eye.xy += c.x * along + c.y * across;
#if !defined(DIFFUSE_BUBBLES)
  eye.z += r;  // foam rides on the surface: half of each sprite would otherwise sink under the water's depth
#endif
  gl_Position = keep ? uProj * eye : vec4(2.0, 2.0, 2.0, 1.0);  // dropped kinds land outside the clip volume
}
)";
inline constexpr const char* kDiffuseFs = R"(
in vec2 vCorner;
in float vFade;
flat in int vKind;
layout(location = 0) out vec4 outColor;
void main() {
  float r2 = dot(vCorner, vCorner);
  if (r2 > 1.0) discard;
  float soft = (1.0 - r2) * (1.0 - r2);
#if defined(DIFFUSE_BUBBLES)
  // A bubble: a bright rim and a clear centre.
  float alpha = 0.55 * vFade * smoothstep(0.2, 0.9, r2) * (1.0 - smoothstep(0.9, 1.0, r2));
#else
  float alpha = (vKind == 1 ? 0.85 : 0.45) * soft * vFade;  // foam dense, spray a mist of drops
#endif
  vec3 light = vec3(0.92, 0.95, 1.0) * (0.55 + 0.45 * max(uSun.y, 0.0));
  outColor = vec4(light * alpha, alpha);  // premultiplied
}
)";

/// One program: its vertex and fragment sources in the order they are concatenated.
struct ProgramSource {
  const char* name;
  std::vector<const char*> vertex;
  std::vector<const char*> fragment;
};

/// Every program the renderer links (also compiled offline by tests/render/shaders_test.cpp).
inline const std::vector<ProgramSource>& Programs() {
  static const std::vector<ProgramSource> programs = {
      {"sky", {kCommon, kFullScreenVs}, {kCommon, kSkyFs}},
      {"present", {kCommon, kFullScreenVs}, {kCommon, kViewPixel, kPresentFs}},
      {"solid", {kCommon, kSolidVs}, {kCommon, kSunLight, kSolidFs}},
      {"solid (shadowed)", {kCommon, kSolidVs}, {kCommon, kDefineShadows, kSunLight, kSolidFs}},
      {"shadow", {kCommon, kShadowVs}, {kCommon, kShadowFs}},
      {"glass", {kCommon, kSolidVs}, {kCommon, kGlassFs}},
      {"particles", {kCommon, kSpriteVs}, {kCommon, kSphere, kParticleFs}},
      {"water thickness (mesh)", {kCommon, kMeshVs}, {kCommon, kDefineThickness, kMeshFs}},
      {"water thickness (sprites)", {kCommon, kSpriteVs}, {kCommon, kDefineThickness, kSphere, kWaterSpriteFs}},
      {"water depth (mesh)", {kCommon, kMeshVs}, {kCommon, kDefineDepth, kMeshFs}},
      {"water shade (mesh)", {kCommon, kMeshVs}, {kCommon, kDefineShade, kViewPixel, kSunLight, kWaterShade, kMeshFs}},
      {"water shade (mesh, shadowed)",
       {kCommon, kMeshVs},
       {kCommon, kDefineShade, kDefineShadows, kViewPixel, kSunLight, kWaterShade, kMeshFs}},
      {"water shade (sprites)",
       {kCommon, kSpriteVs},
       {kCommon, kDefineShade, kViewPixel, kSunLight, kWaterShade, kSphere, kWaterSpriteFs}},
      {"water shade (sprites, shadowed)",
       {kCommon, kSpriteVs},
       {kCommon, kDefineShade, kDefineShadows, kViewPixel, kSunLight, kWaterShade, kSphere, kWaterSpriteFs}},
      {"diffuse (bubbles)", {kCommon, kDefineBubbles, kDiffuseVs}, {kCommon, kDefineBubbles, kDiffuseFs}},
      {"diffuse (spray and foam)", {kCommon, kDiffuseVs}, {kCommon, kDiffuseFs}},
  };
  return programs;
}

}  // namespace sphxr::render::shaders
