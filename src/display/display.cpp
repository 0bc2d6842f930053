#include "vismask/display/display.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/core/check.h"
#include "vismask/display/direct.h"
#include "vismask/display/smoothing.h"

namespace vismask {

namespace {

bool Inside(bool triangle, glm::vec2 st) {
  if (st.x < 0.0f || st.y < 0.0f) return false;
  return triangle ? st.x + st.y <= 1.0f : st.x <= 1.0f && st.y <= 1.0f;
}

// The display radiosity at parameters `st` of patch `i`.
glm::vec3 CornerValue(const Environment& env, uint32_t i, glm::vec2 st, const double ambient[3]) {
  const Patch& p = env.patches()[i];
  const bool triangle = p.numCorners == 3;
  glm::vec2 roots[4];
  int n = RootCorners(triangle, roots);
  for (int k = 0; k < n; ++k)
    if (st == roots[k]) return env.vertexRadiosity()[p.vertex[k]];
  // On an edge of the patch along a cut: the line between the edge's two
  // lattice vertices, whose values are shared with the other side (ShareVertices).
  // Likewise along an outline edge whose ends are shared with other
  // polygons (smoothing).
  for (int k = 0; k < n; ++k) {
    uint32_t a = p.vertex[k], b = p.vertex[(k + 1) % n];
    bool cut = env.IsCutVertex(a) && env.IsCutVertex(b);
    if (!cut && !env.IsSmoothEdge(i, static_cast<uint32_t>(k))) continue;
    glm::vec2 e = roots[(k + 1) % n] - roots[k], q = st - roots[k];
    if (std::fabs(e.x * q.y - e.y * q.x) > 1e-6f) continue;  // not on this edge
    float f = glm::dot(q, e) / glm::dot(e, e);
    return (1.0f - f) * env.vertexRadiosity()[a] + f * env.vertexRadiosity()[b];
  }
  // The leaves touching `st`: probes a hair away in eight directions.
  constexpr float e = 1e-5f;
  const glm::vec2 dirs[8] = {{e, 0}, {-e, 0}, {0, e}, {0, -e}, {e, e}, {-e, e}, {e, -e}, {-e, -e}};
  uint32_t seen[8];
  int count = 0;
  glm::vec3 sum(0.0f);
  float weight = 0.0f;
  for (const glm::vec2& d : dirs) {
    glm::vec2 q = st + d;
    if (!Inside(triangle, q)) continue;
    uint32_t leaf = env.LeafAt(i, q);
    bool dup = false;
    for (int k = 0; k < count; ++k) dup |= seen[k] == leaf;
    if (dup) continue;
    seen[count++] = leaf;
    float w = env.elements()[leaf].area;
    sum += w * env.LeafRadiosity(i, leaf, ambient);
    weight += w;
  }
  return weight > 0.0f ? sum / weight : glm::vec3(0.0f);
}

}  // namespace

void DrawEnvironment(const View& view, const Environment& env, const double ambient[3],
                     Framebuffer* fb, Span<const Texture> textures) {
  Span<const Element> elements = env.elements();
  uint32_t hint = kNoPatch;  // the last occluder of a shadow ray
  for (uint32_t i = 0; i < env.patches().size(); ++i) {
    const Patch& p = env.patches()[i];
    const bool triangle = p.numCorners == 3;
    // The back of a one-sided patch reflects nothing: it is drawn black.
    const bool facing = glm::dot(p.normal, view.eye - p.corner[0]) > 0.0f;
    // Of two twins (two-sided meshes) only the one facing the eye is drawn:
    // they share corner[0] and their normals are exact negatives, so just
    // one of them faces it, and no coplanar back face takes a fragment.
    if (!facing && env.twinOf(i) != kNoPatch) continue;
    const PatchTexture* tex = facing ? env.patchTexture(i) : nullptr;
    CHECK(!tex || (tex->texture < textures.size() && textures[tex->texture].texels));
    // Per-pixel direct light: the leaves show their indirect radiosity
    // (LeafRadiosity), interpolated as the whole was; the direct part is
    // gathered at each shaded point.
    DirectHook hook;
    const bool direct = facing && env.ShowsIndirect(i) && !env.directLight().empty();
    if (direct) {
      constexpr float kInvPi = 0.318309886183790672f;
      hook.light = &env.directLight();
      hook.grid = &env.grid();
      hook.patch = i;
      hook.twin = env.twinOf(i);
      hook.normal = p.normal;
      hook.planePoint = p.corner[0];
      hook.scale = kInvPi * p.kd * (tex ? tex->scale : glm::vec3(1.0f));
      hook.samples = env.directSamples();
      hook.epsilon = env.rayEpsilon();
      hook.hint = &hint;
    }
    // Depth-first over the tree, with a fixed stack (4 entries per level).
    struct Node {
      uint32_t e;
      glm::vec2 c[4];
    };
    Node stack[4 * 32 + 1];
    int top = 0;
    stack[top].e = i;
    int n = RootCorners(triangle, stack[top].c);
    ++top;
    while (top > 0) {
      Node node = stack[--top];
      const Element& el = elements[node.e];
      if (el.child != kNoElement) {
        for (uint32_t k = 0; k < 4; ++k) {
          Node& ch = stack[top++];
          ch.e = el.child + k;
          ChildCorners(triangle, node.c, k, ch.c);
        }
        continue;
      }
      DisplayPiece piece;
      piece.numCorners = static_cast<uint32_t>(n);
      // The polygon's id, not the patch's: the pieces of one polygon tile its
      // plane, so the raster may merge them into one fragment per pixel,
      // which leaves room at a silhouette where two faces of a block, each
      // cut into patches, meet a wall behind (with patch ids that pixel held
      // five or more fragments and lost the wall: dark dots along the edges).
      piece.id = p.surface;
      for (int k = 0; k < n; ++k) {
        piece.p[k] = PatchPoint(p, node.c[k]);
        piece.c[k] =
            facing ? DisplayRadiance(CornerValue(env, i, node.c[k], ambient)) : glm::vec3(0.0f);
      }
      if (n == 3) {
        piece.p[3] = piece.p[2];
        piece.c[3] = piece.c[2];
      }
      if (tex) {
        piece.texture = &textures[tex->texture];
        piece.ke = DisplayRadiance(p.ke);
        for (int k = 0; k < n; ++k) piece.uv[k] = PatchUv(*tex, triangle, node.c[k]);
        piece.uv[3] = piece.uv[n - 1];
      }
      if (direct) piece.direct = &hook;
      DrawPiece(view, piece, fb);
    }
  }
}

namespace {

// The record of lattice vertex v of `env` (its cut normal, if a cut vertex).
VertexRecord MakeRecord(const Environment& env, uint32_t v, const glm::vec3& normal, uint32_t flags,
                        const SmoothVertex* s) {
  VertexRecord r{};
  float w = env.vertexWeights()[v];
  glm::vec3 x = env.vertices()[v], b = env.vertexRadiosity()[v];
  for (int a = 0; a < 3; ++a) {
    r.pos[a] = x[a];
    r.normal[a] = normal[a];
    r.sum[a] = b[a] * w;
  }
  r.weight = w;
  r.env = env.index();
  r.vertex = v;
  r.polygon = kNoPatch;
  if (s) {
    for (int a = 0; a < 3; ++a) r.vn[a] = s->vn[a];
    r.group = s->group;
    r.polygon = s->polygon;
    flags |= kRecordSmooth;
  }
  r.flags = flags;
  return r;
}

constexpr int kCellBits = 21;

// The cell of point x on one axis: cells 4 tolerances wide from the origin.
uint32_t CellOf(float x, float origin, float cell) {
  float k = std::floor((x - origin) / cell);
  if (!(k > 0.0f)) return 0;
  return k >= float((1u << kCellBits) - 1) ? (1u << kCellBits) - 1 : static_cast<uint32_t>(k);
}

uint64_t CellKey(uint32_t kx, uint32_t ky, uint32_t kz) {
  return (uint64_t(kx) << (2 * kCellBits)) | (uint64_t(ky) << kCellBits) | kz;
}

}  // namespace

void CollectShared(Span<Environment* const> envs, Span<VertexRecord> out) {
  size_t n = 0;
  for (const Environment* env : envs) {
    Span<const uint32_t> cut = env->cutVertices();
    for (size_t k = 0; k < cut.size(); ++k) {
      CHECK(n < out.size());
      int64_t s = env->FindSmooth(cut[k]);
      out[n++] = MakeRecord(*env, cut[k], env->cutNormals()[k], kRecordCut,
                            s < 0 ? nullptr : &env->smoothVertices()[size_t(s)]);
    }
    for (const SmoothVertex& s : env->smoothVertices()) {
      if (env->IsCutVertex(s.vertex)) continue;
      CHECK(n < out.size());
      out[n++] = MakeRecord(*env, s.vertex, s.normal, 0, &s);
    }
  }
  for (; n < out.size(); ++n) out[n] = VertexRecord{};
}

namespace {

// ShareVertices' records, sorted, with the smooth ones indexed by cell.
class VertexSharer {
 public:
  VertexSharer(Span<VertexRecord> all, Span<uint32_t> scratch, const ShareRule& rule)
      : all_(all), rule_(rule), tolerance_(rule.tolerance) {
    // Padding last; the rest in a fixed order (ties below break on it too).
    auto less = [](const VertexRecord& a, const VertexRecord& b) {
      if ((a.weight > 0.0f) != (b.weight > 0.0f)) return a.weight > 0.0f;
      if (a.env != b.env) return a.env < b.env;
      return a.vertex < b.vertex;
    };
    std::sort(all.begin(), all.end(), less);
    while (used_ < all.size() && all[used_].weight > 0.0f) ++used_;
    // The smooth records by cell, then in that fixed order.
    cell_ = std::fmax(4.0f * tolerance_, std::numeric_limits<float>::min());
    for (size_t i = 0; i < used_; ++i) {
      if (!(all[i].flags & kRecordSmooth)) continue;
      CHECK(2 * all.size() <= scratch.size());
      scratch[numSmooth_++] = static_cast<uint32_t>(i);
    }
    smooth_ = scratch.data();
    std::sort(smooth_, smooth_ + numSmooth_, [&](uint32_t a, uint32_t b) {
      uint64_t ka = KeyOf(all_[a]), kb = KeyOf(all_[b]);
      return ka != kb ? ka < kb : a < b;
    });
  }

  // Vertex v of `env`: on a cut (normal n) and/or smooth (s).
  // Returns whether a smooth record of another polygon was taken in.
  bool Share(Environment* env, uint32_t v, bool isCut, glm::vec3 n, const SmoothVertex* s) const {
    glm::vec3 x = env->vertices()[v];
    float w = env->vertexWeights()[v];
    glm::vec3 sum = env->vertexRadiosity()[v] * w;
    float weight = w;
    bool shared = false, matched = false;
    const VertexRecord* below = nullptr;
    const VertexRecord* above = nullptr;
    if (isCut) shared = AcrossCut(*env, x, n, &below, &above, &sum, &weight);
    if (s && SmoothGroup(*env, v, x, *s, below, above, &sum, &weight)) shared = matched = true;
    if (shared && weight > 0.0f) env->SetVertexRadiosity(v, sum / weight);
    return matched;
  }

 private:
  uint64_t KeyOf(const VertexRecord& r) const {
    return CellKey(CellOf(r.pos[0], rule_.origin.x, cell_), CellOf(r.pos[1], rule_.origin.y, cell_),
                   CellOf(r.pos[2], rule_.origin.z, cell_));
  }

  // The other side's display function along the cut line through x: its
  // records on this line with this normal, the nearest at or below x and
  // above, interpolated into *sum and *weight. Whether there were both.
  bool AcrossCut(const Environment& env, glm::vec3 x, glm::vec3 n, const VertexRecord** below,
                 const VertexRecord** above, glm::vec3* sum, float* weight) const {
    const float tolerance = tolerance_;
    const Bounds& box = env.box();
    // The cut plane it lies on (the first, at a corner of the box).
    int axis = 0;
    for (int a = 2; a >= 0; --a)
      if (std::fabs(x[a] - box.lo[a]) <= tolerance || std::fabs(x[a] - box.hi[a]) <= tolerance)
        axis = a;
    glm::vec3 e(0.0f);
    e[axis] = 1.0f;
    glm::vec3 d = glm::cross(e, n);
    float len = glm::length(d);
    if (!(len > 0.5f)) return false;  // the surface lies in the cut plane
    d /= len;
    float tBelow = 0.0f, tAbove = 0.0f;
    for (size_t i = 0; i < used_; ++i) {
      const VertexRecord& r = all_[i];
      if (!(r.flags & kRecordCut) || r.env == env.index()) continue;
      if (r.normal[0] * n.x + r.normal[1] * n.y + r.normal[2] * n.z < 0.999f) continue;
      glm::vec3 q(r.pos[0], r.pos[1], r.pos[2]);
      glm::vec3 off = q - x;
      if (std::fabs(off[axis]) > tolerance || std::fabs(glm::dot(off, n)) > tolerance) continue;
      float t = glm::dot(off, d);
      if (t <= tolerance && (!*below || t > tBelow)) {
        *below = &r;
        tBelow = t;
      }
      if (t >= -tolerance && (!*above || t < tAbove)) {
        *above = &r;
        tAbove = t;
      }
    }
    if (!*below || !*above) {
      *below = *above = nullptr;  // x is beyond the other side's cut edge
      return false;
    }
    float f = tAbove - tBelow > tolerance ? -tBelow / (tAbove - tBelow) : 0.0f;
    for (int c = 0; c < 3; ++c) (*sum)[c] += (1.0f - f) * (*below)->sum[c] + f * (*above)->sum[c];
    *weight += (1.0f - f) * (*below)->weight + f * (*above)->weight;
    return true;
  }

  // The smooth records at x (other than vertex v's own) into cand, in a
  // fixed order; how many.
  size_t Candidates(const Environment& env, uint32_t v, glm::vec3 x, uint32_t* cand) const {
    size_t numCand = 0;
    uint32_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = CellOf(x[a] - tolerance_, rule_.origin[a], cell_);
      hi[a] = CellOf(x[a] + tolerance_, rule_.origin[a], cell_);
    }
    for (uint32_t kx = lo[0]; kx <= hi[0]; ++kx)
      for (uint32_t ky = lo[1]; ky <= hi[1]; ++ky)
        for (uint32_t kz = lo[2]; kz <= hi[2]; ++kz) {
          const uint64_t key = CellKey(kx, ky, kz);
          const uint32_t* first =
              std::lower_bound(smooth_, smooth_ + numSmooth_, key,
                               [&](uint32_t i, uint64_t k) { return KeyOf(all_[i]) < k; });
          for (const uint32_t* it = first; it < smooth_ + numSmooth_ && KeyOf(all_[*it]) == key;
               ++it) {
            const VertexRecord& r = all_[*it];
            if (r.env == env.index() && r.vertex == v) continue;
            if (glm::length(glm::vec3(r.pos[0], r.pos[1], r.pos[2]) - x) > tolerance_) continue;
            cand[numCand++] = *it;
          }
        }
    return numCand;
  }

  // The values of the polygons that smooth with s's at x into *sum and
  // *weight (each record once: not again if it stood for the other side of
  // the cut, below or above; s's own polygon's pieces only through the
  // cut). Whether any was taken in.
  bool SmoothGroup(const Environment& env, uint32_t v, glm::vec3 x, const SmoothVertex& s,
                   const VertexRecord* below, const VertexRecord* above, glm::vec3* sum,
                   float* weight) const {
    uint32_t* cand = smooth_ + all_.size();
    const size_t numCand = Candidates(env, v, x, cand);
    // The polygons that smooth with this one, directly or through others
    // at x (so that every polygon of the group sees the same set, as with
    // faces joined by smooth edges around a vertex): grown from this one
    // until no record joins. Bit 31 marks a member.
    constexpr uint32_t kMember = 1u << 31;
    auto together = [&](const VertexRecord& a, const VertexRecord& b) {
      if (a.polygon == b.polygon) return true;
      return SmoothTogether(glm::vec3(a.normal[0], a.normal[1], a.normal[2]),
                            glm::vec3(a.vn[0], a.vn[1], a.vn[2]), a.group,
                            glm::vec3(b.normal[0], b.normal[1], b.normal[2]),
                            glm::vec3(b.vn[0], b.vn[1], b.vn[2]), b.group, rule_.cosCrease);
    };
    for (bool grew = true; grew;) {
      grew = false;
      for (size_t c = 0; c < numCand; ++c) {
        if (cand[c] & kMember) continue;
        const VertexRecord& r = all_[cand[c]];
        bool join = r.polygon == s.polygon ||
                    SmoothTogether(s.normal, s.vn, s.group,
                                   glm::vec3(r.normal[0], r.normal[1], r.normal[2]),
                                   glm::vec3(r.vn[0], r.vn[1], r.vn[2]), r.group, rule_.cosCrease);
        for (size_t d = 0; d < numCand && !join; ++d)
          join = (cand[d] & kMember) && together(all_[cand[d] & ~kMember], r);
        if (join) {
          cand[c] |= kMember;
          grew = true;
        }
      }
    }
    bool matched = false;
    for (size_t c = 0; c < numCand; ++c) {
      if (!(cand[c] & kMember)) continue;
      const VertexRecord& r = all_[cand[c] & ~kMember];
      if (r.polygon == s.polygon || &r == below || &r == above) continue;
      for (int k = 0; k < 3; ++k) (*sum)[k] += r.sum[k];
      *weight += r.weight;
      matched = true;
    }
    return matched;
  }

  Span<VertexRecord> all_;
  const ShareRule& rule_;
  const float tolerance_;
  float cell_ = 0.0f;
  size_t used_ = 0;
  uint32_t* smooth_ = nullptr;  // the smooth records' indices, by cell
  size_t numSmooth_ = 0;
};

// A smooth vertex inside an outline edge that met no other polygon's
// there (the polygons along the edge are subdivided differently): the
// line between the nearest vertices of its edge on either side that
// did, so that both sides show one function along the edge. A polygon's
// vertices are consecutive in sv.
void JoinUnmatched(Environment* env, float tolerance) {
  Span<const SmoothVertex> sv = env->smoothVertices();
  for (size_t k = 0; k < sv.size(); ++k) {
    const SmoothVertex& s = sv[k];
    if (env->smoothMatched(k) || s.edge[0] != s.edge[1]) continue;
    const glm::vec3 x = env->vertices()[s.vertex];
    int64_t below = -1, above = -1;
    float tBelow = 0.0f, tAbove = 0.0f;
    auto consider = [&](size_t j) {
      const SmoothVertex& o = sv[j];
      if (!env->smoothMatched(j) || (o.edge[0] != s.edge[0] && o.edge[1] != s.edge[0])) return;
      float t = glm::dot(env->vertices()[o.vertex] - x, s.dir);
      if (t < -tolerance && (below < 0 || t > tBelow)) {
        below = static_cast<int64_t>(j);
        tBelow = t;
      }
      if (t > tolerance && (above < 0 || t < tAbove)) {
        above = static_cast<int64_t>(j);
        tAbove = t;
      }
    };
    for (size_t j = k; j-- > 0 && sv[j].polygon == s.polygon;) consider(j);
    for (size_t j = k + 1; j < sv.size() && sv[j].polygon == s.polygon; ++j) consider(j);
    if (below < 0 || above < 0) continue;
    float f = -tBelow / (tAbove - tBelow);
    env->SetVertexRadiosity(s.vertex,
                            (1.0f - f) * env->vertexRadiosity()[sv[size_t(below)].vertex] +
                                f * env->vertexRadiosity()[sv[size_t(above)].vertex]);
  }
}

}  // namespace

void ShareVertices(Span<Environment* const> envs, Span<VertexRecord> all, Span<uint32_t> scratch,
                   const ShareRule& rule) {
  const VertexSharer sharer(all, scratch, rule);
  for (Environment* env : envs) {
    Span<const uint32_t> cut = env->cutVertices();
    Span<const SmoothVertex> sv = env->smoothVertices();
    for (size_t k = 0; k < cut.size(); ++k) {
      int64_t s = env->FindSmooth(cut[k]);
      bool matched =
          sharer.Share(env, cut[k], true, env->cutNormals()[k], s < 0 ? nullptr : &sv[size_t(s)]);
      if (s >= 0) env->SetSmoothMatched(size_t(s), matched);
    }
    for (size_t k = 0; k < sv.size(); ++k)
      if (!env->IsCutVertex(sv[k].vertex))
        env->SetSmoothMatched(k, sharer.Share(env, sv[k].vertex, false, sv[k].normal, &sv[k]));
    JoinUnmatched(env, rule.tolerance);
  }
}

}  // namespace vismask
