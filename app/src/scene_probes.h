#pragma once
// The scene's "probes" section (docs/user/scenes.md#probes) -> app::ProbeConfig. Used by the scene
// loader (scene_file.cpp); its own file because the section is one thing.
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sphxr/app/probe_config.h"
#include "sphxr/common/status.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/params.h"

namespace sphxr::app {

/// `path` names the file in messages ("path: probes.pressure[0].at: why"); `unknown` is called with the
/// full key of every key it does not know. The tank and the paddles must be read already: a point
/// outside the tank, a force probe naming no paddle, `every` not above 0 are errors naming the key.
/// A force probe's body is its paddle's index (the paddles' bodies are the scene's bodies, in order).
Status ParseProbes(const nlohmann::json& j, const std::string& path, const sim::SceneSetup& setup,
                   const std::vector<interaction::PaddleDesc>& paddles,
                   const std::function<void(const std::string&)>& unknown, ProbeConfig* out);

}  // namespace sphxr::app
