// Emitter check: whether an emitter sends most of its power where it lights
// nothing, which is what a face wound the wrong way does in a real scene (a
// ceiling light facing the ceiling it hangs under). Estimated at init with a
// fixed, deterministic set of cosine-weighted rays per emitting polygon
// (EmitterCheckRays: kEmitterCheckRays, fewer when the scene has so many
// emitting polygons that the total would pass kEmitterCheckRayBudget; a
// fixed seed) traced against the whole scene, one patch per polygon.
// Init-time only; uses the heap.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vismask/scene.h"

namespace vismask {

constexpr uint32_t kEmitterCheckRays = 512;  // per emitting polygon, per side
// The whole check's rays a side: a scene of 300 000 emitting faces would
// otherwise trace 3e8 rays before init could refuse it for memory. A
// polygon gets no fewer than kEmitterCheckMinRays (a share's standard error
// of at most 0.09 against the 0.5 threshold: still a clear verdict on a face
// wound the wrong way).
constexpr uint64_t kEmitterCheckRayBudget = 1u << 20;
constexpr uint32_t kEmitterCheckMinRays = 32;

// Rays per emitting polygon and side for a scene of `emitters` of them.
uint32_t EmitterCheckRays(uint64_t emitters);
constexpr double kEmitterNearShare = 0.02;   // "nearby": within 2% of the scene's largest extent
constexpr double kEmitterMostShare = 0.5;    // warn above half of the polygon's power

// One emitting polygon's estimate, each a share of its power (rays).
struct EmitterEstimate {
  uint32_t polygon = 0;
  double nearShare = 0.0;      // hits a surface within the near distance of its front
  double nearDistance = 0.0;   // the mean distance of those hits (scene units)
  double escapeShare = 0.0;    // hits nothing: leaves the scene
  double backEscapeShare = 0.0;  // the same for rays from its back side
  // The reason to warn: most of the power into a surface just in front, or
  // most of it out of the scene while most from the back side would hit it.
  bool nearWarning() const { return nearShare > kEmitterMostShare; }
  bool escapeWarning() const {
    return !nearWarning() && escapeShare > kEmitterMostShare && backEscapeShare < kEmitterMostShare;
  }
};

// The estimate for every emitting polygon of `scene`, in polygon order.
std::vector<EmitterEstimate> EstimateEmitters(const Scene& scene);

// One line per emitting material with at least one polygon that warns,
// "FILE:LINE: warning: emitter 'NAME' ...", naming the first such face
// (in file order) and how many of the material's faces warn. No newline.
std::vector<std::string> EmitterWarnings(const Scene& scene);

}  // namespace vismask
