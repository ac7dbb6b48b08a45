// Spray, foam and bubbles as the renderer draws them (DiffusePass): a frame with them differs from the
// same frame without them only where they are: spray and foam within their sprites' projected
// footprints (a sprite is a disc of the diffuse radius, stretched along its velocity by the distance
// it moves in 1/90 s), bubbles only inside the water (they are drawn behind its surface and seen through
// its refraction); and at render quality low none are drawn.
#include <cmath>
#include <vector>

#include "render_support.h"

namespace sphxr::test {
namespace {

using DiffuseSpritesTest = RenderFixture;

TEST_F(DiffuseSpritesTest, AFrameWithThemDiffersOnlyWhereTheyAre) {
  const glm::vec3 lo(-0.4f, 0.0f, -0.3f), hi(0.4f, 0.3f, 0.3f);
  const BoxMesh water(lo, hi);
  render::FrameScene scene;
  scene.drawFloor = false;
  scene.drawTank = false;
  scene.tank = sim::Aabb{{lo.x, lo.y, lo.z}, {hi.x, 0.6f, hi.z}};
  scene.surface = water.View();
  scene.absorptionScale = 4.0f;
  // Spray above the water, foam on its surface (both moving), bubbles inside it.
  std::vector<sim::Vec4> position, velocity;
  const float radius = 0.025f;
  for (int i = 0; i < 6; ++i) {
    position.push_back({-0.3f + 0.1f * i, 0.45f, 0.0f, 2.0f});  // spray, 2 s left
    velocity.push_back({0.6f, 0.3f, 0.0f, 0.0f});
    position.push_back({-0.25f + 0.1f * i, 0.3f + 0.5f * radius, 0.1f, 2.0f});  // foam
    velocity.push_back({0.0f, 0.0f, 0.2f, 1.0f});
    position.push_back({-0.3f + 0.1f * i, 0.15f, 0.0f, 2.0f});  // bubbles
    velocity.push_back({0.0f, 0.1f, 0.0f, 2.0f});
  }
  const glm::vec3 eye(0.0f, 0.9f, 1.6f);
  const render::View v = FullView(glm::lookAt(eye, glm::vec3(0.0f, 0.2f, 0.0f), glm::vec3(0, 1, 0)),
                                  glm::perspective(0.8f, float(kW) / kH, 0.05f, 50.0f));
  const render::Image without = DrawAndRead(scene, std::span(&v, 1));
  scene.diffuse = {position.data(), velocity.data(), static_cast<int>(position.size()), radius};
  const render::Image with = DrawAndRead(scene, std::span(&v, 1));

  // Truth: each sprite's footprint on the screen, from its projected centre: the disc's radius in
  // pixels, grown by half the stretch it gets from its velocity in 1/60 s, plus 1.5 px for rasterisation.
  const glm::mat4 vp = v.projection * v.view;
  const float pixelsPerMetre = 0.5f * v.projection[1][1] * kH;
  auto footprint = [&](int i, int x, int y) {
    const glm::vec3 p(position[i].x, position[i].y, position[i].z), vel(velocity[i].x, velocity[i].y, velocity[i].z);
    const glm::vec4 eyeP = v.view * glm::vec4(p, 1.0f);
    const float depth = -eyeP.z;
    const glm::vec2 c = Project(vp, p, v);
    const float stretch = glm::length(glm::vec2(glm::mat3(v.view) * vel)) / 90.0f;
    const float reach = (radius + 0.5f * stretch) * pixelsPerMetre / std::max(depth - radius, 1e-3f) + 1.5f;
    return glm::length(glm::vec2(x + 0.5f, y + 0.5f) - c) <= reach;
  };
  auto inWater = [&](int x, int y) {
    return RayHitsBox(eye, PixelRay(vp, eye, x + 0.5f, y + 0.5f, v), lo - glm::vec3(0.01f), hi + glm::vec3(0.01f));
  };
  int changed = 0, strayOutside = 0, bubbleOutsideWater = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      if (glm::length(Rgb(with, x, y) - Rgb(without, x, y)) <= 2.5f / 255.0f) continue;
      ++changed;
      bool near = false;
      for (int i = 0; i < static_cast<int>(position.size()) && !near; ++i) {
        if (velocity[i].w < 1.5f) near = footprint(i, x, y);
      }
      if (!near) {
        // Not spray or foam: it must be a bubble, seen through the water.
        if (!inWater(x, y)) ++bubbleOutsideWater;
        ++strayOutside;
      }
    }
  }
  std::printf("%d pixels changed; %d outside the spray and foam footprints (bubbles), %d of those outside the water\n",
              changed, strayOutside, bubbleOutsideWater);
  EXPECT_GT(changed, 30);
  EXPECT_GT(strayOutside, 0) << "the bubbles were not seen through the water";
  EXPECT_EQ(bubbleOutsideWater, 0) << "changed pixels that are neither a sprite's footprint nor in the water";

  // At render quality low the diffuse particles are not drawn: the frame is the one without them.
  m_renderer->SetQuality(render::RenderQuality::kLow);
  const render::Image lowWith = DrawAndRead(scene, std::span(&v, 1));
  scene.diffuse = {};
  const render::Image lowWithout = DrawAndRead(scene, std::span(&v, 1));
  int lowChanged = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) lowChanged += glm::length(Rgb(lowWith, x, y) - Rgb(lowWithout, x, y)) > 0.0f;
  }
  EXPECT_EQ(lowChanged, 0);
}

}  // namespace
}  // namespace sphxr::test
