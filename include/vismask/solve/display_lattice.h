// DisplayLattice: an environment's display vertices (its patches' corners,
// local ids) and the radiosity the image interpolates between them. The
// vertices on a face shared with a neighbour (cut vertices) and those that
// may share their value with other polygons' (smooth vertices) are the ones
// the display exchanges (display.h: CollectShared, ShareVertices). Carved
// from the environment's arena (Layout), filled once at Build.
#pragma once
#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

#include "vismask/core/arena.h"
#include "vismask/core/span.h"
#include "vismask/scene/mesh.h"
#include "vismask/solve/patch.h"

namespace vismask {

class DisplayLattice {
 public:
  // What Build copies in, staged by Environment::Prepare.
  struct Staged {
    std::vector<glm::vec3> vertices;
    std::vector<uint32_t> cut;         // cut vertices
    std::vector<glm::vec3> cutNormal;  // their surface's normal
    std::vector<SmoothVertex> smooth;  // by vertex
    std::vector<uint8_t> smoothEdges;  // per patch (IsSmoothEdge); empty without smooth vertices
    uint32_t numShared = 0;            // cut or smooth, each once
  };

  // Room for the staged lattice, with `smoothing` (per-pixel direct light)
  // its scratch and, with cut vertices, SolvedDirect (also from a measuring
  // arena).
  void Layout(Arena& arena, const Staged& staged, bool smoothing);
  // Copies the staged lattice in and marks the outline vertices to
  // extrapolate (from `patches`, in local vertex ids).
  void Build(const Staged& staged, Span<const Patch> patches);

  // The radiosity at every vertex: Clear, Add each patch corner's leaf
  // value with its weight (the leaf's area) and its edge's share of the
  // patch's edge, then Finish: the weighted mean, extrapolated to the
  // polygon's outline along quads' diagonals. With `smoothSteps` > 0 (laid
  // out for smoothing) the vertices two edges or more inside the outline
  // are smoothed first, that many steps: each takes half its value and half
  // the mean of its edge neighbours that hold a value (weight > 0; a vertex
  // no exposed leaf touches holds none and keeps its 0) (a linear field
  // stays as it was), and the outline is extrapolated from them.
  void Clear();
  void Add(uint32_t v, float weight, const glm::vec3& b, float edgeShare) {
    radiosity_[v] += weight * b;
    weight_[v] += weight;
    frac_[v] += edgeShare;
  }
  // Whether SolvedDirect is kept: per-pixel direct light (laid out with
  // smoothing) on a lattice with cut vertices.
  bool keepsSolvedDirect() const { return !solvedDirect_.empty(); }
  // Where keepsSolvedDirect: the part of leaf value b that the pixels gather
  // instead (the solve's direct light), added at vertex v with the same
  // weight, so that a cut vertex can share the whole with a neighbour that
  // shows it (SolvedDirect).
  void AddSolvedDirect(uint32_t v, float weight, const glm::vec3& d) {
    solvedDirect_[v] += weight * d;
  }
  void Finish(Span<const Patch> patches, int smoothSteps = 0);
  // A mark per vertex for the environment's passes over its patches
  // (Environment::MeasureExposure: the vertices of patches with a buried part).
  void ClearMarks() {
    for (uint8_t& m : mark_) m = 0;
  }
  void Mark(uint32_t v) { mark_[v] = 1; }
  bool Marked(uint32_t v) const { return mark_[v] != 0; }
  // Whether the last Finish smoothed, and vertex v's value without it.
  bool smoothed() const { return smoothed_; }
  glm::vec3 Unsmoothed(uint32_t v) const { return smoothed_ ? raw_[v] : radiosity_[v]; }

  Span<const glm::vec3> vertices() const { return vertices_; }
  Span<const glm::vec3> radiosity() const { return radiosity_; }
  Span<const float> weights() const { return weight_; }
  // The display's shared value of vertex v (ShareVertices).
  void SetRadiosity(uint32_t v, const glm::vec3& b) { radiosity_[v] = b; }
  // The solve's direct light at vertex v that radiosity() leaves to the
  // pixels (the weighted mean of AddSolvedDirect's; 0 where none is kept).
  // radiosity() + SolvedDirect(v) is the solve's whole: what a cut vertex
  // shares, since the environment across the cut may gather other emitters
  // or none and show their light as solved.
  glm::vec3 SolvedDirect(uint32_t v) const {
    return solvedDirect_.empty() ? glm::vec3(0.0f) : solvedDirect_[v];
  }

  // Cut vertices and their surface's normal (known from Layout on).
  Span<const uint32_t> cutVertices() const { return cut_; }
  uint32_t numCut() const { return numCut_; }
  Span<const glm::vec3> cutNormals() const { return cutNormal_; }
  bool IsCutVertex(uint32_t v) const { return isCut_[v] != 0; }
  // Smooth vertices (Mesh::smooth, local vertex ids, by vertex), and how
  // many vertices the display exchanges: cut or smooth, each once.
  Span<const SmoothVertex> smoothVertices() const { return smooth_; }
  uint32_t numShared() const { return numShared_; }
  // The index in smoothVertices() of vertex v, or -1.
  int64_t FindSmooth(uint32_t v) const;
  // Whether smooth vertex k shared its value with another polygon's at the
  // same point in the last ShareVertices (display scratch).
  bool smoothMatched(size_t k) const { return smoothMatched_[k] != 0; }
  void SetSmoothMatched(size_t k, bool matched) { smoothMatched_[k] = matched ? 1 : 0; }
  // Whether edge k (corner k to k+1) of patch i lies on an outline edge of
  // its polygon whose ends are both smooth vertices: the display
  // interpolates their shared values along it.
  bool IsSmoothEdge(uint32_t i, uint32_t k) const {
    return !smoothEdges_.empty() && ((smoothEdges_[i] >> k) & 1u);
  }

 private:
  void MarkInterior(const Staged& staged, Span<const Patch> patches);
  void Extrapolate(Span<const Patch> patches);

  Span<glm::vec3> vertices_;
  Span<glm::vec3> radiosity_;
  Span<float> weight_;
  Span<uint32_t> cut_;
  Span<uint8_t> isCut_;  // 1 for a cut vertex
  // Outline vertices of quad lattices that Finish extrapolates: how many
  // quads touch them (1 or 2; 0: not extrapolated), fixed at Build. Its
  // scratch: the corner leaves' edge shares, the inward value.
  Span<uint8_t> outline_;
  Span<float> frac_;
  Span<uint8_t> mark_;
  Span<glm::vec3> inward_;
  // Smoothing (laid out with it): at a vertex it smooths (its corners'
  // angles close around it and around each neighbour; not cut or smooth)
  // the edge ends there, else 0; the values before smoothing, then a
  // step's sums.
  Span<uint8_t> interior_;
  Span<glm::vec3> raw_;
  Span<glm::vec3> cutNormal_;
  Span<glm::vec3> solvedDirect_;  // per vertex, with smoothing and cut vertices; else empty
  uint32_t numCut_ = 0;
  Span<SmoothVertex> smooth_;
  Span<uint8_t> smoothMatched_;
  Span<uint8_t> smoothEdges_;  // bit k: edge k is smooth; empty without smooth vertices
  uint32_t numShared_ = 0;
  bool smoothed_ = false;
};

}  // namespace vismask
