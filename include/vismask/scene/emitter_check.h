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
#include <glm/vec3.hpp>
#include <string>
#include <utility>
#include <vector>

#include "vismask/scene/scene.h"

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
constexpr double kEmitterNearShare = 0.02;  // "nearby": within 2% of the scene's largest extent
constexpr double kEmitterMostShare = 0.5;   // warn above half of the polygon's power

// One emitting polygon's estimate, each a share of its power (rays).
struct EmitterEstimate {
  uint32_t polygon = 0;  // its index in file order
  uint32_t material = 0;
  int line = 0;                  // of its 'f' statement
  double nearShare = 0.0;        // hits a surface within the near distance of its front
  double nearDistance = 0.0;     // the mean distance of those hits (scene units)
  double escapeShare = 0.0;      // hits nothing: leaves the scene
  double backEscapeShare = 0.0;  // the same for rays from its back side
  // The reason to warn: most of the power into a surface just in front, or
  // most of it out of the scene while most from the back side would hit it.
  bool nearWarning() const { return nearShare > kEmitterMostShare; }
  bool escapeWarning() const {
    return !nearWarning() && escapeShare > kEmitterMostShare && backEscapeShare < kEmitterMostShare;
  }
};

// The estimate streamed: built from the emitting polygons (with their
// indices in file order, the scene's bounds and materials known), then fed
// every polygon in file order (Add); the polygons are traced `chunk` at a
// time against a grid of their own, each ray keeping its nearest hit, so
// that the check holds its rays and one chunk, never the scene, and gives
// what one grid over every polygon gives. Finish: the estimates, in polygon
// order (none when a polygon cannot be meshed or the scene has no extent).
class EmitterCheck {
 public:
  EmitterCheck(const Bounds& bounds, const std::vector<Material>& materials,
               const std::vector<std::pair<uint32_t, Polygon>>& emitters, size_t chunk);
  void Add(uint32_t index, const Polygon& polygon);
  std::vector<EmitterEstimate> Finish();
  // A bound on the heap the check holds for `emitters` emitting polygons
  // and chunks of `chunk` polygons.
  static uint64_t HeapBytes(size_t emitters, size_t chunk);

 private:
  struct RayState {
    glm::vec3 o{0.0f}, d{0.0f};
    float t = kNoHit;    // the nearest hit's parameter so far (kNoHit: none yet)
    uint32_t patch = 0;  // its patch in the emitter's own one-patch mesh
  };
  static constexpr float kNoHit = 3.0e38f;  // beyond any hit's t (float max is 3.4e38)
  struct Source {
    uint32_t polygon, material, firstRay;
    int line;
  };
  void Flush();
  size_t chunk_;
  uint32_t raysPer_;  // EmitterCheckRays(emitting polygons), a side
  bool failed_ = false;
  float patchSize_ = 0.0f;
  double nearDistance_ = 0.0;
  std::vector<Source> sources_;
  std::vector<RayState> rays_;  // per source: 2 * raysPer_, (front, back) per ray
  Scene chunkScene_;
  uint32_t chunkFirst_ = 0;
};

// Polygons the streaming check traces at a time (render_init.cpp).
constexpr size_t kEmitterCheckChunk = 65536;

// The estimate for every emitting polygon of `scene`, in polygon order
// (chunk: polygons traced at a time; 0, all at once).
std::vector<EmitterEstimate> EstimateEmitters(const Scene& scene, size_t chunk = 0);

// One line per emitting material with at least one polygon that warns,
// "FILE:LINE: warning: emitter 'NAME' ...", naming the first such face
// (in file order) and how many of the material's faces warn. No newline.
std::vector<std::string> EmitterWarnings(const Scene& scene);
// The same lines from estimates already made (EmitterCheck).
std::vector<std::string> EmitterWarnings(const std::vector<EmitterEstimate>& estimates,
                                         const std::string& objPath,
                                         const std::vector<Material>& materials,
                                         const Bounds& bounds);

}  // namespace vismask
