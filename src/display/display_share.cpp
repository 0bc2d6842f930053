// The display's shared vertices (display.h): collected from each
// environment's lattice, and the values the environments on either side of
// a cut, and smoothed polygons meeting at a point, agree on.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

#include "vismask/core/check.h"
#include "vismask/display/display.h"
#include "vismask/display/smoothing.h"

namespace vismask {

namespace {

// What of vertex v's solved direct light a record carries: all of it, or
// nothing where every environment's pixels gather every emitter.
glm::vec3 SharedDirect(const Environment& env, uint32_t v) {
  return env.direct().gathersForeign() ? glm::vec3(0.0f) : env.lattice().SolvedDirect(v);
}

// The record of lattice vertex v of `env` (its cut normal, if a cut vertex).
VertexRecord MakeRecord(const Environment& env, uint32_t v, const glm::vec3& normal, uint32_t flags,
                        const SmoothVertex* s) {
  VertexRecord r{};
  const DisplayLattice& lattice = env.lattice();
  float w = lattice.weights()[v];
  // The solve's whole (the environments across a cut may gather different
  // emitters per pixel: what one leaves to its pixels the other shows
  // solved); where every environment gathers every emitter, the shown
  // (indirect) part.
  glm::vec3 x = lattice.vertices()[v], b = lattice.radiosity()[v] + SharedDirect(env, v);
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

// The records ShareVertices reads: sorted, the first `used` real, and the
// smooth ones' indices (`smooth`, numSmooth of them) by cell, then in that
// order; scratch for candidates follows them.
struct SharedRecords {
  Span<VertexRecord> all;
  size_t used = 0;
  uint32_t* smooth = nullptr;
  size_t numSmooth = 0;
  const ShareRule* rule = nullptr;
  float tolerance = 0.0f;
  float cell = 0.0f;
  uint64_t KeyOf(const VertexRecord& r) const {
    return CellKey(CellOf(r.pos[0], rule->origin.x, cell), CellOf(r.pos[1], rule->origin.y, cell),
                   CellOf(r.pos[2], rule->origin.z, cell));
  }
};

// What one vertex takes in: the weighted sum and weight, whether anything
// was shared and whether a smooth record of another polygon was, and the
// other side's records along a cut that stood for it.
struct SharedSum {
  glm::vec3 sum;
  float weight;
  bool shared = false, matched = false;
  const VertexRecord* below = nullptr;
  const VertexRecord* above = nullptr;
};

// Cut vertex x of `env` (its surface's normal n): the other side's display
// function along the cut line.
void AddCutSide(const SharedRecords& rec, const Environment& env, const glm::vec3& x,
                const glm::vec3& n, SharedSum* out) {
  Span<VertexRecord> all = rec.all;
  const size_t used = rec.used;
  const float tolerance = rec.tolerance;
  glm::vec3& sum = out->sum;
  float& weight = out->weight;
  bool& shared = out->shared;
  const VertexRecord*& below = out->below;
  const VertexRecord*& above = out->above;
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
  if (len > 0.5f) {  // else the surface lies in the cut plane
    d /= len;
    // The other side's display function along the cut line: its records
    // on this line with this normal, the nearest at or below x and above.
    float tBelow = 0.0f, tAbove = 0.0f;
    for (size_t i = 0; i < used; ++i) {
      const VertexRecord& r = all[i];
      if (!(r.flags & kRecordCut) || r.env == env.index()) continue;
      if (r.normal[0] * n.x + r.normal[1] * n.y + r.normal[2] * n.z < 0.999f) continue;
      glm::vec3 q(r.pos[0], r.pos[1], r.pos[2]);
      glm::vec3 off = q - x;
      if (std::fabs(off[axis]) > tolerance || std::fabs(glm::dot(off, n)) > tolerance) continue;
      float t = glm::dot(off, d);
      if (t <= tolerance && (!below || t > tBelow)) {
        below = &r;
        tBelow = t;
      }
      if (t >= -tolerance && (!above || t < tAbove)) {
        above = &r;
        tAbove = t;
      }
    }
    if (below && above) {
      float f = tAbove - tBelow > tolerance ? -tBelow / (tAbove - tBelow) : 0.0f;
      for (int c = 0; c < 3; ++c) sum[c] += (1.0f - f) * below->sum[c] + f * above->sum[c];
      weight += (1.0f - f) * below->weight + f * above->weight;
      shared = true;
    } else {
      below = above = nullptr;  // x is beyond the other side's cut edge
    }
  }
}

// Smooth vertex v of `env` at x (s): the smooth records of the polygons
// that smooth with its own there.
void AddSmoothGroup(const SharedRecords& rec, const Environment& env, uint32_t v,
                    const glm::vec3& x, const SmoothVertex* s, SharedSum* out) {
  Span<VertexRecord> all = rec.all;
  uint32_t* smooth = rec.smooth;
  const size_t numSmooth = rec.numSmooth;
  const float tolerance = rec.tolerance, cell = rec.cell;
  const ShareRule& rule = *rec.rule;
  auto keyOf = [&](const VertexRecord& r) { return rec.KeyOf(r); };
  glm::vec3& sum = out->sum;
  float& weight = out->weight;
  bool &shared = out->shared, &matched = out->matched;
  const VertexRecord* below = out->below;
  const VertexRecord* above = out->above;
  // The smooth records at x (other than this one), in a fixed order.
  uint32_t* cand = smooth + all.size();
  size_t numCand = 0;
  uint32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = CellOf(x[a] - tolerance, rule.origin[a], cell);
    hi[a] = CellOf(x[a] + tolerance, rule.origin[a], cell);
  }
  for (uint32_t kx = lo[0]; kx <= hi[0]; ++kx)
    for (uint32_t ky = lo[1]; ky <= hi[1]; ++ky)
      for (uint32_t kz = lo[2]; kz <= hi[2]; ++kz) {
        const uint64_t key = CellKey(kx, ky, kz);
        const uint32_t* first =
            std::lower_bound(smooth, smooth + numSmooth, key,
                             [&](uint32_t i, uint64_t k) { return keyOf(all[i]) < k; });
        for (const uint32_t* it = first; it < smooth + numSmooth && keyOf(all[*it]) == key; ++it) {
          const VertexRecord& r = all[*it];
          if (r.env == env.index() && r.vertex == v) continue;
          if (glm::length(glm::vec3(r.pos[0], r.pos[1], r.pos[2]) - x) > tolerance) continue;
          cand[numCand++] = *it;
        }
      }
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
                          glm::vec3(b.vn[0], b.vn[1], b.vn[2]), b.group, rule.cosCrease);
  };
  for (bool grew = true; grew;) {
    grew = false;
    for (size_t c = 0; c < numCand; ++c) {
      if (cand[c] & kMember) continue;
      const VertexRecord& r = all[cand[c]];
      bool join = r.polygon == s->polygon ||
                  SmoothTogether(s->normal, s->vn, s->group,
                                 glm::vec3(r.normal[0], r.normal[1], r.normal[2]),
                                 glm::vec3(r.vn[0], r.vn[1], r.vn[2]), r.group, rule.cosCrease);
      for (size_t d = 0; d < numCand && !join; ++d)
        join = (cand[d] & kMember) && together(all[cand[d] & ~kMember], r);
      if (join) {
        cand[c] |= kMember;
        grew = true;
      }
    }
  }
  // Their values, each record once (not again if it stood for the other
  // side of the cut; this polygon's own pieces only through the cut).
  for (size_t c = 0; c < numCand; ++c) {
    if (!(cand[c] & kMember)) continue;
    const VertexRecord& r = all[cand[c] & ~kMember];
    if (r.polygon == s->polygon || &r == below || &r == above) continue;
    for (int k = 0; k < 3; ++k) sum[k] += r.sum[k];
    weight += r.weight;
    shared = matched = true;
  }
}

// Vertex v of `env`: on a cut (normal n) and/or smooth (s). Returns
// whether a smooth record of another polygon was taken in.
bool ShareVertex(const SharedRecords& rec, Environment* env, uint32_t v, bool isCut, glm::vec3 n,
                 const SmoothVertex* s) {
  DisplayLattice& lattice = env->lattice();
  glm::vec3 x = lattice.vertices()[v];
  float w = lattice.weights()[v];
  // Shared as the solve's whole (MakeRecord); this environment's pixels
  // add the direct light they gather to the rest.
  const glm::vec3 gathered = SharedDirect(*env, v), whole = lattice.radiosity()[v] + gathered;
  SharedSum sh;
  sh.sum = whole * w;
  sh.weight = w;
  // Where this side's pixels gather a part of the light (more than 1e-4 of
  // the whole, above rounding), it keeps its own indirect part on the cut:
  // the other side's whole holds the same emitters' light as solved, which
  // no record separates, and the indirect part varies slowly across the
  // cut. Its record still gives the other side the whole.
  const bool gathers = gathered.x + gathered.y + gathered.z > 1e-4f * (whole.x + whole.y + whole.z);
  if (isCut && !gathers) AddCutSide(rec, *env, x, n, &sh);
  if (s) AddSmoothGroup(rec, *env, v, x, s, &sh);
  if (sh.shared && sh.weight > 0.0f) lattice.SetRadiosity(v, sh.sum / sh.weight - gathered);
  return sh.matched;
}

// A smooth vertex inside an outline edge that met no other polygon's there
// (the polygons along the edge are subdivided differently): the line
// between the nearest vertices of its edge on either side that did, so
// that both sides show one function along the edge. A polygon's vertices
// are consecutive in the lattice's smooth vertices.
void InterpolateUnmatched(DisplayLattice& lattice, float tolerance) {
  Span<const SmoothVertex> sv = lattice.smoothVertices();
  for (size_t k = 0; k < sv.size(); ++k) {
    const SmoothVertex& s = sv[k];
    if (lattice.smoothMatched(k) || s.edge[0] != s.edge[1]) continue;
    const glm::vec3 x = lattice.vertices()[s.vertex];
    int64_t below = -1, above = -1;
    float tBelow = 0.0f, tAbove = 0.0f;
    auto consider = [&](size_t j) {
      const SmoothVertex& o = sv[j];
      if (!lattice.smoothMatched(j) || (o.edge[0] != s.edge[0] && o.edge[1] != s.edge[0])) return;
      float t = glm::dot(lattice.vertices()[o.vertex] - x, s.dir);
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
    lattice.SetRadiosity(s.vertex, (1.0f - f) * lattice.radiosity()[sv[size_t(below)].vertex] +
                                       f * lattice.radiosity()[sv[size_t(above)].vertex]);
  }
}

}  // namespace

void CollectShared(Span<Environment* const> envs, Span<VertexRecord> out) {
  size_t n = 0;
  for (const Environment* env : envs) {
    const DisplayLattice& lattice = env->lattice();
    Span<const uint32_t> cut = lattice.cutVertices();
    for (size_t k = 0; k < cut.size(); ++k) {
      CHECK(n < out.size());
      int64_t s = lattice.FindSmooth(cut[k]);
      out[n++] = MakeRecord(*env, cut[k], lattice.cutNormals()[k], kRecordCut,
                            s < 0 ? nullptr : &lattice.smoothVertices()[size_t(s)]);
    }
    for (const SmoothVertex& s : lattice.smoothVertices()) {
      if (lattice.IsCutVertex(s.vertex)) continue;
      CHECK(n < out.size());
      out[n++] = MakeRecord(*env, s.vertex, s.normal, 0, &s);
    }
  }
  for (; n < out.size(); ++n) out[n] = VertexRecord{};
}

void ShareVertices(Span<Environment* const> envs, Span<VertexRecord> all, Span<uint32_t> scratch,
                   const ShareRule& rule) {
  const float tolerance = rule.tolerance;
  // Padding last; the rest in a fixed order (ties below break on it too).
  auto less = [](const VertexRecord& a, const VertexRecord& b) {
    if ((a.weight > 0.0f) != (b.weight > 0.0f)) return a.weight > 0.0f;
    if (a.env != b.env) return a.env < b.env;
    return a.vertex < b.vertex;
  };
  std::sort(all.begin(), all.end(), less);
  size_t used = 0;
  while (used < all.size() && all[used].weight > 0.0f) ++used;
  // The smooth records by cell, then in that fixed order.
  const float cell = std::fmax(4.0f * tolerance, std::numeric_limits<float>::min());
  auto keyOf = [&](const VertexRecord& r) {
    return CellKey(CellOf(r.pos[0], rule.origin.x, cell), CellOf(r.pos[1], rule.origin.y, cell),
                   CellOf(r.pos[2], rule.origin.z, cell));
  };
  size_t numSmooth = 0;
  for (size_t i = 0; i < used; ++i) {
    if (!(all[i].flags & kRecordSmooth)) continue;
    CHECK(2 * all.size() <= scratch.size());
    scratch[numSmooth++] = static_cast<uint32_t>(i);
  }
  uint32_t* smooth = scratch.data();
  std::sort(smooth, smooth + numSmooth, [&](uint32_t a, uint32_t b) {
    uint64_t ka = keyOf(all[a]), kb = keyOf(all[b]);
    return ka != kb ? ka < kb : a < b;
  });

  SharedRecords rec;
  rec.all = all;
  rec.used = used;
  rec.smooth = smooth;
  rec.numSmooth = numSmooth;
  rec.rule = &rule;
  rec.tolerance = tolerance;
  rec.cell = cell;
  for (Environment* env : envs) {
    DisplayLattice& lattice = env->lattice();
    Span<const uint32_t> cut = lattice.cutVertices();
    Span<const SmoothVertex> sv = lattice.smoothVertices();
    for (size_t k = 0; k < cut.size(); ++k) {
      int64_t s = lattice.FindSmooth(cut[k]);
      bool matched = ShareVertex(rec, env, cut[k], true, lattice.cutNormals()[k],
                                 s < 0 ? nullptr : &sv[size_t(s)]);
      if (s >= 0) lattice.SetSmoothMatched(size_t(s), matched);
    }
    for (size_t k = 0; k < sv.size(); ++k)
      if (!lattice.IsCutVertex(sv[k].vertex))
        lattice.SetSmoothMatched(k,
                                 ShareVertex(rec, env, sv[k].vertex, false, sv[k].normal, &sv[k]));
    InterpolateUnmatched(lattice, tolerance);
  }
}

}  // namespace vismask
