// The water's optics against truth computed here: refraction of a checkerboard behind a curved water
// surface (the image inside the water is the background displaced; an index of 1 changes nothing
// outside the water), Fresnel's growth at grazing incidence (Schlick with F0 = 0.02), Beer-Lambert
// absorption through a wedge (ln I linear in the thickness, red first), and the depth the water leaves
// in the view's depth buffer (the ray/box hit through the same matrices).
#include <epoxy/gl.h>

#include <array>
#include <cmath>
#include <vector>

#include "render_support.h"

namespace sphxr::test {
namespace {

constexpr float kFov = 0.8f;
glm::mat4 Perspective() { return glm::perspective(kFov, float(RenderFixture::kW) / RenderFixture::kH, 0.05f, 50.0f); }

float Luminance(glm::vec3 c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

/// A closed water body over x in [-w, w], y in [y0, y1]: back face z = zBack, front face z = Front(x)
/// (a bent surface), triangulated in strips along x with outward normals.
struct Lens {
  float w = 0.5f, y0 = 0.1f, y1 = 0.9f, zBack = -0.7f;
  float a = 0.8f, b = 0.25f, z0 = 0.1f;  // front: z0 + a x + b x^2
  std::vector<float> positions, normals;
  float Front(float x) const { return z0 + a * x + b * x * x; }
  glm::vec3 FrontNormal(float x) const { return glm::normalize(glm::vec3(-(a + 2.0f * b * x), 0.0f, 1.0f)); }
  void Tri(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 n0, glm::vec3 n1, glm::vec3 n2) {
    for (glm::vec3 p : {p0, p1, p2}) positions.insert(positions.end(), {p.x, p.y, p.z});
    for (glm::vec3 n : {n0, n1, n2}) normals.insert(normals.end(), {n.x, n.y, n.z});
  }
  void Quad(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 p3, glm::vec3 n) {  // counter-clockwise seen from n
    Tri(p0, p1, p2, n, n, n);
    Tri(p0, p2, p3, n, n, n);
  }
  Lens() {
    const int strips = 48;
    for (int i = 0; i < strips; ++i) {
      const float xa = -w + 2.0f * w * i / strips, xb = -w + 2.0f * w * (i + 1) / strips;
      const glm::vec3 na = FrontNormal(xa), nb = FrontNormal(xb);
      // front (normal mostly +z)
      Tri({xa, y0, Front(xa)}, {xb, y0, Front(xb)}, {xb, y1, Front(xb)}, na, nb, nb);
      Tri({xa, y0, Front(xa)}, {xb, y1, Front(xb)}, {xa, y1, Front(xa)}, na, nb, na);
      // back (-z), bottom (-y), top (+y)
      Quad({xb, y0, zBack}, {xa, y0, zBack}, {xa, y1, zBack}, {xb, y1, zBack}, {0, 0, -1});
      Quad({xa, y0, zBack}, {xb, y0, zBack}, {xb, y0, Front(xb)}, {xa, y0, Front(xa)}, {0, -1, 0});
      Quad({xa, y1, Front(xa)}, {xb, y1, Front(xb)}, {xb, y1, zBack}, {xa, y1, zBack}, {0, 1, 0});
    }
    Quad({-w, y0, zBack}, {-w, y0, Front(-w)}, {-w, y1, Front(-w)}, {-w, y1, zBack}, {-1, 0, 0});
    Quad({w, y0, Front(w)}, {w, y0, zBack}, {w, y1, zBack}, {w, y1, Front(w)}, {1, 0, 0});
  }
  render::MeshView View() const {
    render::MeshView v;
    v.positions = positions.data();
    v.normals = normals.data();
    v.vertexCount = static_cast<int>(positions.size() / 3);
    return v;
  }
};

/// A vertical board of tiles behind the water, each a solid of its own, alternating dark and bright with
/// a grey level that differs from tile to tile (so that a shift by whole tiles does not align it).
void AddCheckerboard(render::FrameScene* scene, float z, float tile) {
  uint32_t state = 12345u;
  for (int i = -5; i < 5; ++i) {
    for (int j = -2; j < 7; ++j) {
      state = state * 1664525u + 1013904223u;
      const float jitter = float(state >> 8) / float(1u << 24);
      render::SolidMesh s;
      s.model = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3((i + 0.5f) * tile, (j + 0.5f) * tile, z)),
                           glm::vec3(tile, tile, 0.01f));
      s.color = glm::vec3(((i + j) & 1) ? 0.65f + 0.35f * jitter : 0.05f + 0.3f * jitter);
      scene->solids.push_back(s);
    }
  }
}

render::FrameScene Bare() {
  render::FrameScene s;
  s.drawFloor = false;
  s.drawTank = false;
  s.tank = sim::Aabb{{-5, -5, -5}, {-4, -4, -4}};  // far away: no receiver here is "in the tank"
  return s;
}

using WaterOpticsTest = RenderFixture;

TEST_F(WaterOpticsTest, RefractionShowsTheBackgroundDisplacedInsideTheWaterOnly) {
  const Lens lens;
  render::FrameScene background = Bare();
  AddCheckerboard(&background, -1.2f, 0.2f);
  render::FrameScene water = background;
  water.surface = lens.View();
  water.absorptionScale = 1.0f;  // nearly clear: the pattern stays readable through it
  const glm::vec3 eye(0.0f, 0.5f, 2.5f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0)), Perspective());
  const render::Image back = DrawAndRead(background, std::span(&v, 1));
  const render::Image bent = DrawAndRead(water, std::span(&v, 1));

  // The same water with an index of 1: no refraction and no reflection (F0 = 0).
  render::RendererConfig flatConfig = m_renderer->Config();
  flatConfig.waterIor = 1.0f;
  std::unique_ptr<render::Renderer> flat;
  ASSERT_TRUE(render::Renderer::Create(flatConfig, &flat).ok());
  flat->Draw(water, std::span(&v, 1));
  const render::Image straight = m_target->Read();

  // Truth: the water's silhouette from the ray through each pixel, marched through the body.
  const glm::mat4 vp = v.projection * v.view;
  auto inside = [&](glm::vec3 p) {
    return p.x >= -lens.w && p.x <= lens.w && p.y >= lens.y0 && p.y <= lens.y1 && p.z >= lens.zBack &&
           p.z <= lens.Front(p.x);
  };
  std::vector<int> mask(kW * kH, 0);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const glm::vec3 ray = PixelRay(vp, eye, x + 0.5f, y + 0.5f, v);
      for (float t = 1.0f; t < 4.0f && !mask[y * kW + x]; t += 0.002f) mask[y * kW + x] = inside(eye + t * ray);
    }
  }
  auto near = [&](int x, int y, int r) {  // within r pixels of the mask
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx >= 0 && yy >= 0 && xx < kW && yy < kH && mask[yy * kW + xx]) return true;
      }
    }
    return false;
  };
  int changedOutside = 0, changedInside = 0, insideCount = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const bool differs = glm::length(Rgb(bent, x, y) - Rgb(straight, x, y)) > 2.5f / 255.0f;
      if (!near(x, y, 1)) changedOutside += differs;
      if (mask[y * kW + x]) {
        ++insideCount;
        changedInside += differs;
      }
    }
  }
  EXPECT_GT(insideCount, 2000);
  EXPECT_EQ(changedOutside, 0) << "pixels outside the water changed with its index of refraction";
  EXPECT_GT(changedInside, insideCount / 4) << "the index of refraction changed too little inside the water";

  // Inside the water (a patch away from its silhouette, where the front is tilted by about 35 degrees):
  // the best-aligning shift of the background-only image.
  auto patchError = [&](const render::Image& img, int sx, int sy, int x0, int y0, int x1, int y1) {
    double e = 0.0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) e += Luminance(glm::abs(Rgb(img, x, y) - Rgb(back, x + sx, y + sy)));
    }
    return e;
  };
  const glm::vec2 c0 = Project(vp, glm::vec3(-0.25f, 0.5f, lens.Front(-0.25f)), v);
  const int x0 = int(c0.x) - 12, x1 = int(c0.x) + 12, y0 = int(c0.y) - 12, y1 = int(c0.y) + 12;
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) ASSERT_TRUE(mask[y * kW + x]) << "the patch must lie inside the water";
  }
  auto bestShift = [&](const render::Image& img) {
    glm::ivec2 best(0);
    double bestError = 1e30;
    for (int sy = -12; sy <= 12; ++sy) {
      for (int sx = -12; sx <= 12; ++sx) {
        const double e = patchError(img, sx, sy, x0, y0, x1, y1);
        if (e < bestError) bestError = e, best = {sx, sy};
      }
    }
    return best;
  };
  const glm::ivec2 shiftBent = bestShift(bent), shiftStraight = bestShift(straight);
  std::printf("best-aligning shift: n = 1.333: (%d, %d) px; n = 1: (%d, %d) px\n", shiftBent.x, shiftBent.y,
              shiftStraight.x, shiftStraight.y);
  EXPECT_GE(std::abs(shiftBent.x) + std::abs(shiftBent.y), 2) << "the water does not displace what is behind it";
  EXPECT_LT(std::max(std::abs(shiftBent.x), std::abs(shiftBent.y)), 12) << "the best shift lies at the search's edge";
  EXPECT_EQ(shiftStraight, glm::ivec2(0)) << "with an index of 1 the background must be seen where it is";
}

TEST_F(WaterOpticsTest, FresnelReflectsTheSkyAtGrazingIncidenceAndLittleHeadOn) {
  // Deep flat water (1 m) over a black floor under the sky; the sun behind the camera (no glint).
  const BoxMesh box(glm::vec3(-20.0f, -1.0f, -20.0f), glm::vec3(20.0f, 0.0f, 20.0f));
  render::FrameScene scene = Bare();
  scene.surface = box.View();
  render::SolidMesh floor;
  floor.model = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0, -1.05f, 0)), glm::vec3(60.0f, 0.1f, 60.0f));
  floor.color = glm::vec3(0.0f);
  scene.solids.push_back(floor);
  auto centreLuminance = [&](float incidenceRadians) {
    const glm::vec3 target(0.0f);
    const glm::vec3 eye = target + 3.0f * glm::vec3(0.0f, std::cos(incidenceRadians), std::sin(incidenceRadians));
    const glm::vec3 up = incidenceRadians < 0.1f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
    const render::View v = FullView(glm::lookAt(eye, target, up), Perspective());
    const render::Image img = DrawAndRead(scene, std::span(&v, 1));
    float sum = 0.0f;
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) sum += Luminance(Rgb(img, kW / 2 + dx, kH / 2 + dy));
    }
    return sum / 25.0f;
  };
  const float headOn = centreLuminance(0.0f), grazing = centreLuminance(80.0f * 3.14159265f / 180.0f);
  std::printf("luminance head-on %.4f, at 80 degrees %.4f (ratio %.1f)\n", headOn, grazing, grazing / headOn);
  EXPECT_GE(grazing, 5.0f * headOn);
}

TEST_F(WaterOpticsTest, AbsorptionThroughAWedgeIsBeerLambertAndTakesRedFirst) {
  // A wedge of water over a white floor, seen from straight above: thickness d(x) from 2 cm to 40 cm.
  const float w = 0.6f, dMin = 0.02f, dMax = 0.4f;
  auto thickness = [&](float x) { return dMin + (dMax - dMin) * (x + w) / (2.0f * w); };
  std::vector<float> positions, normals;
  auto tri = [&](glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 n) {
    for (glm::vec3 p : {p0, p1, p2}) positions.insert(positions.end(), {p.x, p.y, p.z});
    for (int k = 0; k < 3; ++k) normals.insert(normals.end(), {n.x, n.y, n.z});
  };
  auto quad = [&](glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 p3, glm::vec3 n) {
    tri(p0, p1, p2, n);
    tri(p0, p2, p3, n);
  };
  const float z0 = -0.5f, z1 = 0.5f;
  const glm::vec3 topN = glm::normalize(glm::vec3(-(dMax - dMin) / (2.0f * w), 1.0f, 0.0f));
  quad({-w, thickness(-w), z1}, {w, thickness(w), z1}, {w, thickness(w), z0}, {-w, thickness(-w), z0}, topN);
  quad({-w, 0, z0}, {w, 0, z0}, {w, 0, z1}, {-w, 0, z1}, {0, -1, 0});
  quad({-w, 0, z1}, {w, 0, z1}, {w, thickness(w), z1}, {-w, thickness(-w), z1}, {0, 0, 1});
  quad({w, 0, z0}, {-w, 0, z0}, {-w, thickness(-w), z0}, {w, thickness(w), z0}, {0, 0, -1});
  quad({w, 0, z1}, {w, 0, z0}, {w, thickness(w), z0}, {w, thickness(w), z1}, {1, 0, 0});
  quad({-w, 0, z0}, {-w, 0, z1}, {-w, thickness(-w), z1}, {-w, thickness(-w), z0}, {-1, 0, 0});
  render::FrameScene scene = Bare();
  scene.surface.positions = positions.data();
  scene.surface.normals = normals.data();
  scene.surface.vertexCount = static_cast<int>(positions.size() / 3);
  scene.absorptionScale = 15.0f;
  render::SolidMesh floor;
  floor.model = glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0, -0.05f, 0)), glm::vec3(4.0f, 0.1f, 4.0f));
  floor.color = glm::vec3(1.0f);
  scene.solids.push_back(floor);
  const glm::vec3 eye(0.0f, 3.0f, 0.0f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0.0f), glm::vec3(0, 0, -1)), Perspective());
  const render::Image img = DrawAndRead(scene, std::span(&v, 1));
  const glm::mat4 vp = v.projection * v.view;

  std::vector<double> d, lnR, lnB, lnL;
  float previous = 1e9f;
  int rises = 0;
  for (int k = 0; k <= 10; ++k) {
    const float x = -0.85f * w + 1.7f * w * k / 10.0f;
    const glm::vec2 p = Project(vp, glm::vec3(x, thickness(x), 0.0f), v);
    const glm::vec3 c = Rgb(img, int(p.x), int(p.y));
    const float l = Luminance(c);
    rises += l > previous;
    previous = l;
    d.push_back(thickness(x));
    lnR.push_back(std::log(std::max(c.r, 1e-3f)));
    lnB.push_back(std::log(std::max(c.b, 1e-3f)));
    lnL.push_back(std::log(std::max(l, 1e-3f)));
  }
  EXPECT_EQ(rises, 0) << "the luminance must fall as the water deepens";
  auto fit = [&](const std::vector<double>& y, double* slope) {  // least squares; returns R^2
    const double n = double(d.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    for (size_t i = 0; i < d.size(); ++i) sx += d[i], sy += y[i], sxx += d[i] * d[i], sxy += d[i] * y[i], syy += y[i] * y[i];
    *slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    const double r = (n * sxy - sx * sy) / std::sqrt((n * sxx - sx * sx) * (n * syy - sy * sy));
    return r * r;
  };
  double slopeL = 0, slopeR = 0, slopeB = 0;
  const double r2 = fit(lnL, &slopeL);
  fit(lnR, &slopeR);
  fit(lnB, &slopeB);
  std::printf("ln I against thickness: R^2 %.4f, slopes (1/m): luminance %.2f, red %.2f, blue %.2f\n", r2, slopeL,
              slopeR, slopeB);
  EXPECT_GE(r2, 0.95);
  EXPECT_LT(slopeR, slopeB) << "red must be absorbed faster than blue";
  EXPECT_LT(slopeL, 0.0);
  // The red channel's slope is the coefficient itself (the floor's light is the same at every depth):
  // within 10 % (the Fresnel term and the light scattered back add a little at the deep end).
  const double sigmaRed = m_renderer->Config().waterAbsorption.r * scene.absorptionScale;
  EXPECT_NEAR(-slopeR, sigmaRed, 0.1 * sigmaRed);
}

TEST_F(WaterOpticsTest, TheWaterLeavesItsSurfaceDepthInTheViewsDepthBuffer) {
  const glm::vec3 lo(-0.3f, 0.2f, -0.2f), hi(0.3f, 0.7f, 0.1f);
  const BoxMesh box(lo, hi);
  render::FrameScene scene = Bare();
  scene.surface = box.View();
  const glm::vec3 eye(0.6f, 1.1f, 1.8f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0.0f, 0.45f, 0.0f), glm::vec3(0, 1, 0)), Perspective());
  DrawAndRead(scene, std::span(&v, 1));
  const std::vector<float> depth = m_target->ReadDepth();
  const glm::mat4 vp = v.projection * v.view;
  int water = 0, wrong = 0, background = 0;
  for (int y = 2; y < kH - 2; y += 2) {
    for (int x = 2; x < kW - 2; x += 2) {
      const glm::vec3 ray = PixelRay(vp, eye, x + 0.5f, y + 0.5f, v);
      float t = 0.0f;
      if (RayHitsBox(eye, ray, lo, hi, &t)) {
        const glm::vec4 clip = vp * glm::vec4(eye + t * ray, 1.0f);
        const float expected = 0.5f * clip.z / clip.w + 0.5f;
        ++water;
        // Rasterised depth against the exact hit: the plane's depth varies across a pixel by at most
        // its slope; half a pixel either way bounds it, and 1e-4 covers the pixel-centre sampling.
        wrong += std::abs(depth[size_t(y) * kW + x] - expected) > 1e-4f;
      } else {
        background += depth[size_t(y) * kW + x] != 1.0f;
      }
    }
  }
  EXPECT_GT(water, 300);
  EXPECT_LE(wrong, water / 50) << "water pixels whose depth is not the surface's (silhouette pixels allowed)";
  EXPECT_EQ(background, 0) << "pixels without water or solids must keep the far depth";
}

}  // namespace
}  // namespace sphxr::test
