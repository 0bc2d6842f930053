// Environment, what it receives: the radiosity a ray brings to a patch
// (Receive) and the element tree that refines where it lands (MaybeSplit,
// Descend, LeafAt, LeafRadiosity), then the display radiosity at mesh
// vertices (ComputeVertexRadiosity). The rest of Environment is in
// environment.cpp (layout and init), trace.cpp (rays) and env_queue.cpp
// (shots and the queue).
#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "vismask/solve/environment.h"

namespace vismask {

// Patch j receives `share` (W per channel) at point `x`.
void Environment::Receive(uint32_t j, const double share[3], const glm::vec3& x) {
  const Patch& p = patches_[j];
  PatchEnergy& e = energy_[j];
  double invArea = 1.0 / p.area;
  // The leaf element the ray landed in, and the quarter of it.
  glm::vec2 st = PatchParam(p, x);
  uint32_t depth = 0;
  uint8_t path[32];
  uint32_t leaf = Descend(j, &st, path, &depth);
  Element& el = elements_[leaf];
  uint32_t quarter = ChildOf(p.numCorners == 3, &st);
  double hitPower = 0.0;
  for (int c = 0; c < 3; ++c) {
    double reflected = share[c] * p.kd[c];
    hitPower += reflected;
    el.received[c] += reflected;
    el.quarter[quarter][c] += reflected;
    e.b[c] += reflected * invArea;
    e.var[c] += (reflected * invArea) * (reflected * invArea);  // one ray's term
    e.unshot[c] += reflected;
    if (!indirect_.empty()) indirect_[3 * size_t(leaf) + c] += reflected * (1.0 - shotDirect_[c]);
    ledger_.unshot[c] += reflected;
    ledger_.radiosity[c] += reflected;
    ledger_.absorbed[c] += share[c] - reflected;
  }
  el.squares += hitPower * hitPower;
  tree_.Increase(j, UnshotKey(e));
  // Whether to split is asked at 64, 128, 256, ... hits.
  uint32_t hits = ++el.hits;
  if (hits >= options_.elements.minHits && (hits & (hits - 1)) == 0 &&
      el.depth < options_.elements.maxDepth && options_.elements.perPatch > 0)
    MaybeSplit(j, leaf, path, depth);
}

// Splits leaf `e` of patch `j` (reached from the root by the children
// `path[0..depth)`) if its quarters differ beyond noise.
void Environment::MaybeSplit(uint32_t j, uint32_t e, const uint8_t* path, uint32_t depth) {
  const Patch& p = patches_[j];
  const bool triangle = p.numCorners == 3;
  Element& el = elements_[e];
  // The element's corners in the patch's parameters, down its path.
  glm::vec2 corners[4], next[4];
  int n = RootCorners(triangle, corners);
  for (uint32_t d = 0; d < depth; ++d) {
    ChildCorners(triangle, corners, path[d], next);
    for (int k = 0; k < n; ++k) corners[k] = next[k];
  }
  // Each quarter's area, from its corners on the patch.
  double quarterArea[4];
  for (uint32_t q = 0; q < 4; ++q) {
    ChildCorners(triangle, corners, q, next);
    glm::vec3 w[4];
    for (int k = 0; k < n; ++k) w[k] = PatchPoint(p, next[k]);
    glm::vec3 cr =
        n == 3 ? glm::cross(w[1] - w[0], w[2] - w[0]) : glm::cross(w[2] - w[0], w[3] - w[1]);
    quarterArea[q] = 0.5 * glm::length(glm::dvec3(cr));
  }
  double areaSum = quarterArea[0] + quarterArea[1] + quarterArea[2] + quarterArea[3];
  double power[4], total = 0.0;
  for (uint32_t q = 0; q < 4; ++q) {
    power[q] = el.quarter[q][0] + el.quarter[q][1] + el.quarter[q][2];
    total += power[q];
  }
  if (!(total > 0.0) || !(el.squares > 0.0)) return;
  // Against an even spread, quarter q expects f_q = area_q / area of the
  // power, with variance f_q * (sum of the hits' squared powers).
  double chi2 = 0.0, spread = 0.0;
  for (uint32_t q = 0; q < 4; ++q) {
    double f = quarterArea[q] / areaSum, expect = f * total;
    chi2 += (power[q] - expect) * (power[q] - expect) / (f * el.squares);
    double rel = power[q] / expect - 1.0;
    spread += f * rel * rel;
  }
  if (chi2 <= options_.elements.chi2 || std::sqrt(spread) <= options_.elements.threshold) return;
  if (nextElement_ + 4 > elements_.size()) {
    ++stats_.refusedSplits;
    return;
  }
  uint32_t first = nextElement_;
  nextElement_ += 4;
  ++stats_.splits;
  for (uint32_t q = 0; q < 4; ++q) {
    Element& ch = elements_[first + q];
    ch = Element{};
    ch.area = static_cast<float>(quarterArea[q] * (el.area / areaSum));
    ch.child = kNoElement;
    ch.depth = el.depth + 1;
    for (int c = 0; c < 3; ++c) {
      double older = el.received[c] -
                     (el.quarter[0][c] + el.quarter[1][c] + el.quarter[2][c] + el.quarter[3][c]);
      ch.received[c] = older * (quarterArea[q] / areaSum) + el.quarter[q][c];
      // The indirect part in the same proportion as the whole.
      if (!indirect_.empty())
        indirect_[3 * size_t(first + q) + c] =
            el.received[c] > 0.0 ? indirect_[3 * size_t(e) + c] * (ch.received[c] / el.received[c])
                                 : 0.0;
    }
  }
  el.child = first;
}

// The leaf of patch `patch` holding `st`, which is left in the leaf's own
// parameters; with `path`, the children taken are appended there (*depth
// of them, at most the element depth).
uint32_t Environment::Descend(uint32_t patch, glm::vec2* st, uint8_t* path, uint32_t* depth) const {
  const bool triangle = patches_[patch].numCorners == 3;
  uint32_t e = patch;
  while (elements_[e].child != kNoElement) {
    uint32_t k = ChildOf(triangle, st);
    if (path) path[(*depth)++] = static_cast<uint8_t>(k);
    e = elements_[e].child + k;
  }
  return e;
}

uint32_t Environment::LeafAt(uint32_t patch, glm::vec2 st) const {
  return Descend(patch, &st, nullptr, nullptr);
}

glm::vec3 Environment::LeafRadiosity(uint32_t patch, uint32_t e, const double ambient[3]) const {
  const Patch& p = patches_[patch];
  const Element& el = elements_[e];
  glm::vec3 b;
  const PatchTexture* t = patchTexture(patch);
  // Per-pixel direct light: the patch's indirect radiosity, every leaf alike
  // (the direct part, which has the detail, is gathered per pixel).
  if (ShowsIndirect(patch)) {
    glm::dvec3 ind = Indirect(e);
    for (int c = 0; c < 3; ++c)
      b[c] = static_cast<float>(static_cast<double>(p.ke[c]) +
                                (ind[c] + p.kd[c] * ambient[c]) * (t ? t->scale[c] : 1.0f));
    return b;
  }
  if (t) {
    // Reflected light as the material's mean reflectance would give it
    // (scale = kd_mat / kd): the display multiplies the texture back in.
    for (int c = 0; c < 3; ++c)
      b[c] = static_cast<float>(static_cast<double>(p.ke[c]) +
                                (el.received[c] / el.area + p.kd[c] * ambient[c]) * t->scale[c]);
    return b;
  }
  for (int c = 0; c < 3; ++c)
    b[c] = static_cast<float>(static_cast<double>(p.ke[c]) + el.received[c] / el.area +
                              p.kd[c] * ambient[c]);
  return b;
}

void Environment::EmissionUnshot(double out[3]) const {
  for (int c = 0; c < 3; ++c) out[c] = 0.0;
  for (size_t i = 0; i < emitLeft_.size(); i += 3)
    for (int c = 0; c < 3; ++c) out[c] += emitLeft_[i + c];
}

void Environment::ComputeVertexRadiosity(const double ambient[3]) {
  lattice_.Clear();
  for (uint32_t i = 0; i < patches_.size(); ++i) {
    const Patch& p = patches_[i];
    glm::vec2 corners[4];
    RootCorners(p.numCorners == 3, corners);
    // Each distinct corner once (triangles repeat their last vertex), with
    // the leaf element that holds it.
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      // A point just inside the corner, so the leaf is the corner's own.
      glm::vec2 centre = p.numCorners == 3 ? glm::vec2(1.0f / 3.0f) : glm::vec2(0.5f);
      uint32_t leaf = LeafAt(i, corners[k] + 1e-4f * (centre - corners[k]));
      float w = elements_[leaf].area;
      lattice_.Add(p.vertex[k], w, LeafRadiosity(i, leaf, ambient), std::sqrt(w / p.area));
    }
  }
  lattice_.Finish(patches_);
}

}  // namespace vismask
