// Direct light gathered per pixel (direct.h): the emitter lists, the exact
// unoccluded irradiance, and the shadow samples of its visible share.
#include "vismask/display/direct.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <tuple>
#include <vector>

#include "vismask/core/check.h"
#include "vismask/display/foreign_light.h"
#include "vismask/solve/rng.h"

namespace vismask {

namespace {

float TriangleArea(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  return 0.5f * glm::length(glm::cross(b - a, c - a));
}

// The emitting patches grouped by polygon (surface, normal, Ke), each
// group's patches in index order, and the edges of each that no other
// patch of the group has the other way round.
struct Plan {
  std::vector<std::vector<uint32_t>> groups;
  std::vector<std::vector<std::pair<glm::vec3, glm::vec3>>> edges;
  std::vector<glm::vec3> corners;  // where the outline turns (every group's)
  std::vector<uint32_t> cornerGroup;
};

Plan MakePlan(Span<const Patch> patches) {
  using Key = std::tuple<uint32_t, float, float, float, float, float, float>;
  std::map<Key, size_t> index;
  Plan plan;
  for (uint32_t i = 0; i < patches.size(); ++i) {
    const Patch& p = patches[i];
    if (!Emits(p)) continue;
    Key key{p.surface, p.normal.x, p.normal.y, p.normal.z, p.ke.r, p.ke.g, p.ke.b};
    auto it = index.find(key);
    if (it == index.end()) {
      it = index.emplace(key, plan.groups.size()).first;
      plan.groups.emplace_back();
    }
    plan.groups[it->second].push_back(i);
  }
  using Point = std::tuple<float, float, float>;
  auto pt = [](const glm::vec3& v) { return Point{v.x, v.y, v.z}; };
  for (const std::vector<uint32_t>& g : plan.groups) {
    std::map<std::pair<Point, Point>, int> count;
    for (uint32_t i : g) {
      const Patch& p = patches[i];
      for (uint32_t k = 0; k < p.numCorners; ++k) {
        const glm::vec3& a = p.corner[k];
        const glm::vec3& b = p.corner[(k + 1) % p.numCorners];
        if (a == b) continue;
        auto back = count.find({pt(b), pt(a)});
        if (back != count.end() && back->second > 0)
          --back->second;
        else
          ++count[{pt(a), pt(b)}];
      }
    }
    plan.edges.emplace_back();
    for (const auto& e : count)
      for (int k = 0; k < e.second; ++k) {
        const Point& a = e.first.first;
        const Point& b = e.first.second;
        plan.edges.back().push_back({glm::vec3(std::get<0>(a), std::get<1>(a), std::get<2>(a)),
                                     glm::vec3(std::get<0>(b), std::get<1>(b), std::get<2>(b))});
      }
  }
  // The outline's corners: the ends of edges where the next edge turns.
  for (size_t g = 0; g < plan.edges.size(); ++g) {
    const auto& edges = plan.edges[g];
    for (const auto& e : edges) {
      glm::vec3 d = e.second - e.first;
      for (const auto& f : edges) {
        if (f.first != e.second) continue;
        glm::vec3 d2 = f.second - f.first;
        float c = glm::length(glm::cross(d, d2));
        if (c > 1e-4f * glm::length(d) * glm::length(d2)) {
          plan.corners.push_back(e.second);
          plan.cornerGroup.push_back(static_cast<uint32_t>(g));
        }
        break;
      }
    }
  }
  return plan;
}

// The signed sum over edges a -> b (relative to the receiving point) of
// the angle they subtend times the cosine of their plane with n.
double EdgeTerm(const glm::vec3& a, const glm::vec3& b, const glm::vec3& n) {
  glm::dvec3 da(a), db(b);
  double la = glm::length(da), lb = glm::length(db);
  if (!(la > 0.0) || !(lb > 0.0)) return 0.0;
  da /= la;
  db /= lb;
  glm::dvec3 c = glm::cross(da, db);
  double s = glm::length(c);
  if (!(s > 0.0)) return 0.0;
  double theta = std::atan2(s, glm::dot(da, db));
  return theta * glm::dot(glm::dvec3(n), c) / s;
}

// Whether `ray` reaches its end past everything but the receiver and its
// twin (*hint: Grid::Occluded's, or null): every shadow ray's last step.
bool Unblocked(const Grid& grid, const Ray& ray, uint32_t receiver, uint32_t twin, uint32_t* hint) {
  const Skip skip(receiver, twin);
  return !(hint ? grid.Occluded(ray, skip, hint) : grid.Occluded(ray, skip));
}

}  // namespace

DirectLight::Counts DirectLight::Count(Span<const Patch> patches) {
  Counts c;
  Plan plan = MakePlan(patches);
  c.groups = static_cast<uint32_t>(plan.groups.size());
  for (size_t g = 0; g < plan.groups.size(); ++g) {
    c.emitters += static_cast<uint32_t>(plan.groups[g].size());
    c.edges += static_cast<uint32_t>(plan.edges[g].size());
  }
  c.corners = static_cast<uint32_t>(plan.corners.size());
  return c;
}

void DirectLight::Layout(Arena& arena, const Counts& counts) {
  emitters_ = arena.Alloc<Emitter>(counts.emitters);
  groups_ = arena.Alloc<Group>(counts.groups);
  tallies_ = arena.Alloc<Tally>(counts.groups);
  edges_ = arena.Alloc<Edge>(counts.edges);
  corners_ = arena.Alloc<Corner>(counts.corners);
}

void DirectLight::Build(Span<const Patch> patches) {
  patches_ = patches;
  Plan plan = MakePlan(patches);
  CHECK(plan.groups.size() == groups_.size());
  constexpr double kInvPi = 0.318309886183790672;
  uint32_t np = 0, ne = 0;
  for (size_t g = 0; g < plan.groups.size(); ++g) {
    Group& gr = groups_[g];
    const Patch& first = patches[plan.groups[g][0]];
    gr.normal = first.normal;
    gr.point = first.corner[0];
    gr.ke = first.ke;
    gr.firstPatch = np;
    gr.numPatches = static_cast<uint32_t>(plan.groups[g].size());
    // The group's sampling list in patch index order: a patch in
    // proportion to its power (area times Ke, channels summed) within it.
    double total = 0.0;
    for (uint32_t i : plan.groups[g]) {
      CHECK(np < emitters_.size());
      const Patch& p = patches[i];
      Emitter& e = emitters_[np++];
      e = Emitter{};
      e.patch = i;
      float a0 = TriangleArea(p.corner[0], p.corner[1], p.corner[2]);
      float a1 = p.numCorners == 4 ? TriangleArea(p.corner[0], p.corner[2], p.corner[3]) : 0.0f;
      e.split = a0 + a1 > 0.0f ? a0 / (a0 + a1) : 1.0f;
      total += static_cast<double>(p.area) * (p.ke.r + p.ke.g + p.ke.b);
      e.cdfHi = static_cast<float>(total);
    }
    for (uint32_t j = gr.firstPatch; j < np; ++j) {
      Emitter& e = emitters_[j];
      const Patch& p = patches[e.patch];
      double w = static_cast<double>(p.area) * (p.ke.r + p.ke.g + p.ke.b);
      // pdf per unit area of a point on e, the group given: (w / total) / area.
      double k = w > 0.0 ? total / w * p.area * kInvPi : 0.0;
      e.scale = glm::vec3(static_cast<float>(p.ke.r * k), static_cast<float>(p.ke.g * k),
                          static_cast<float>(p.ke.b * k));
      e.cdfHi = total > 0.0 ? static_cast<float>(e.cdfHi / total) : 1.0f;
    }
    emitters_[np - 1].cdfHi = 1.0f;
    gr.firstEdge = ne;
    gr.numEdges = static_cast<uint32_t>(plan.edges[g].size());
    for (const auto& e : plan.edges[g]) {
      CHECK(ne < edges_.size());
      edges_[ne++] = Edge{e.first, e.second};
    }
  }
  CHECK(np == emitters_.size() && ne == edges_.size());
  CHECK(plan.corners.size() == corners_.size());
  for (size_t k = 0; k < corners_.size(); ++k) {
    // The group's patch with this corner (the first; the nearest centre
    // if none has it exactly).
    const Group& g = groups_[plan.cornerGroup[k]];
    uint32_t best = emitters_[g.firstPatch].patch;
    float bestD = std::numeric_limits<float>::infinity();
    for (uint32_t j = g.firstPatch; j < g.firstPatch + g.numPatches && bestD > 0.0f; ++j) {
      const Patch& p = patches[emitters_[j].patch];
      for (uint32_t m = 0; m < p.numCorners; ++m)
        if (p.corner[m] == plan.corners[k]) {
          best = emitters_[j].patch;
          bestD = 0.0f;
        }
      const float d = glm::length(CentreOf(p) - plan.corners[k]);
      if (d < bestD) {
        bestD = d;
        best = emitters_[j].patch;
      }
    }
    corners_[k] = Corner{plan.corners[k], plan.cornerGroup[k], best};
  }
}

glm::vec3 DirectLight::PointOn(const Patch& p, float split, glm::vec2 u) {
  // Which triangle, then u.x stretched back to [0, 1) within it.
  glm::vec3 a = p.corner[0], b = p.corner[1], c = p.corner[2];
  float x = u.x;
  if (x >= split) {
    b = p.corner[2];
    c = p.corner[3];
    x = split < 1.0f ? (x - split) / (1.0f - split) : 0.0f;
  } else {
    x = split > 0.0f ? x / split : 0.0f;
  }
  // Uniform in the triangle.
  float s = std::sqrt(std::fmin(x, 1.0f));
  float b1 = 1.0f - s, b2 = s * u.y;
  return (1.0f - b1 - b2) * c + b1 * a + b2 * b;
}

glm::vec3 DirectLight::Unoccluded(const glm::vec3& x, const glm::vec3& n, Span<Tally> tally) const {
  CHECK(tally.empty() || tally.size() == groups_.size());
  constexpr double kInv2Pi = 0.159154943091895336;
  glm::dvec3 sum(0.0);
  double cumulative = 0.0;  // the groups' E0 so far, channels summed
  uint32_t lastLit = 0;     // one past the last group that brings any
  for (uint32_t gi = 0; gi < groups_.size(); ++gi) {
    const Group& g = groups_[gi];
    if (!tally.empty()) tally[gi] = Tally{static_cast<float>(cumulative), {}, {}, {}};
    // Only the front of an emitter emits.
    if (!(glm::dot(g.normal, x - g.point) > 0.0f)) continue;
    // Wholly above x's horizon: its outline edges.
    bool above = true;
    for (uint32_t k = g.firstEdge; k < g.firstEdge + g.numEdges && above; ++k)
      above = glm::dot(n, edges_[k].a - x) > 0.0f;
    double s = 0.0;
    if (above) {
      for (uint32_t k = g.firstEdge; k < g.firstEdge + g.numEdges; ++k)
        s += EdgeTerm(edges_[k].a - x, edges_[k].b - x, n);
    } else {
      // Across the horizon: each patch clipped to the part above it.
      for (uint32_t j = g.firstPatch; j < g.firstPatch + g.numPatches; ++j) {
        const Patch& p = patches_[emitters_[j].patch];
        glm::vec3 in[4], out[8];
        int m = 0;
        for (uint32_t k = 0; k < p.numCorners; ++k) in[k] = p.corner[k] - x;
        for (uint32_t k = 0; k < p.numCorners; ++k) {
          const glm::vec3& a = in[k];
          const glm::vec3& b = in[(k + 1) % p.numCorners];
          float fa = glm::dot(n, a), fb = glm::dot(n, b);
          if (fa > 0.0f) out[m++] = a;
          if ((fa > 0.0f) != (fb > 0.0f)) out[m++] = a + (fa / (fa - fb)) * (b - a);
        }
        for (int k = 0; k < m; ++k) s += EdgeTerm(out[k], out[(k + 1) % m], n);
      }
    }
    const glm::dvec3 e = std::fabs(s) * kInv2Pi * glm::dvec3(g.ke);
    sum += e;
    if (tally.empty() || !(e.x + e.y + e.z > 0.0)) continue;
    cumulative += e.x + e.y + e.z;
    tally[gi].cdf = static_cast<float>(cumulative);
    tally[gi].e0 = glm::vec3(e);
    lastLit = gi + 1;
  }
  // Each group's cumulative share; the last that brings any ends at 1
  // exactly, so rounding never picks a group that brings nothing.
  for (uint32_t gi = 0; gi < tally.size(); ++gi)
    tally[gi].cdf = lastLit == 0        ? 0.0f
                    : gi + 1 >= lastLit ? 1.0f
                                        : static_cast<float>(tally[gi].cdf / cumulative);
  if (hasSun_) sum += glm::dvec3(UnoccludedSun(n));
  return glm::vec3(sum);
}

void DirectLight::SetSun(const OutsideLight& light) {
  hasSun_ = light.HasSun();
  sun_ = light.sun;
  sunToward_ = light.sunToward;
  sunDegrees_ = light.sunDegrees;
}

glm::vec3 DirectLight::UnoccludedSun(const glm::vec3& n) const {
  if (!hasSun_) return glm::vec3(0.0f);
  return sun_ * std::fmax(0.0f, glm::dot(n, sunToward_));
}

bool DirectLight::Sample(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                         const glm::vec3& n, glm::vec2 u, Span<const Tally> tally, float epsilon,
                         uint32_t* hint, glm::vec3* weight, float sunShare, uint32_t* source,
                         uint32_t viewer) const {
  uint32_t unused;
  source = source ? source : &unused;
  if (!(sunShare > 0.0f))
    return SampleArea(grid, receiver, twin, x, n, u, tally, epsilon, hint, weight, source, viewer);
  // The kind from u.x (the sun below sunShare), u.x stretched back to
  // [0, 1) within it; the weight over the kind's share.
  if (u.x < sunShare || emitters_.empty()) {
    *source = numGroups();
    const float s = std::fmin(u.x / sunShare, 0.99999994f);
    const bool vis =
        SampleSun(grid, receiver, twin, x, n, glm::vec2(s, u.y), epsilon, hint, weight, viewer);
    *weight /= std::fmin(sunShare, 1.0f);
    return vis;
  }
  const float s = std::fmin((u.x - sunShare) / (1.0f - sunShare), 0.99999994f);
  const bool vis = SampleArea(grid, receiver, twin, x, n, glm::vec2(s, u.y), tally, epsilon, hint,
                              weight, source, viewer);
  *weight /= 1.0f - sunShare;
  return vis;
}

bool DirectLight::SampleSun(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                            const glm::vec3& n, glm::vec2 u, float epsilon, uint32_t* hint,
                            glm::vec3* weight, uint32_t viewer) const {
  *weight = glm::vec3(0.0f);
  // A direction uniform in solid angle within the sun's disc: the radiance
  // E / (the disc's solid angle) times the cosine over the pdf 1 / (the
  // disc's solid angle) is E times the cosine.
  const glm::vec3 d = -SunConeDirection(sunToward_, sunDegrees_, u.x, u.y);
  const float cosX = glm::dot(n, d);
  if (!(cosX > 0.0f)) return false;
  *weight = sun_ * cosX;
  // The ray must leave the scene: nothing in the way, however far (and
  // through the other environments, their maps).
  return Unblocked(grid, Ray{x, d, epsilon, std::numeric_limits<float>::infinity()}, receiver, twin,
                   hint) &&
         PassesSun(viewer, x, n, d);
}

bool DirectLight::PassesSun(uint32_t viewer, const glm::vec3& x, const glm::vec3& n,
                            const glm::vec3& d) const {
  return viewer == kNoViewer || !transit_ || transit_->PassesSun(x, n, d);
}

bool DirectLight::SunRimVisible(const Grid& grid, uint32_t receiver, uint32_t twin,
                                const glm::vec3& x, const glm::vec3& n, uint32_t k, float epsilon,
                                uint32_t* hint, bool* usable, uint32_t viewer) const {
  // u1 = 1: the cone's edge; u2: the azimuth.
  const glm::vec3 d =
      -SunConeDirection(sunToward_, sunDegrees_, 1.0f, static_cast<float>(k) / kSunRimRays);
  *usable = glm::dot(n, d) > 0.0f;
  if (!*usable) return false;
  return Unblocked(grid, Ray{x, d, epsilon, std::numeric_limits<float>::infinity()}, receiver, twin,
                   hint) &&
         PassesSun(viewer, x, n, d);
}

namespace {

// The first of `size` ascending cumulative shares (cdf(i)) above x (the
// last if none is) and x stretched back to [0, 1) within its interval;
// *share: the interval's width.
template <class Cdf>
uint32_t Pick(Cdf cdf, uint32_t size, float x, float* stretched, float* share) {
  uint32_t lo = 0, hi = size - 1;
  while (lo < hi) {
    uint32_t mid = (lo + hi) / 2;
    if (x < cdf(mid))
      hi = mid;
    else
      lo = mid + 1;
  }
  const float below = lo > 0 ? cdf(lo - 1) : 0.0f;
  *share = cdf(lo) - below;
  const float s = *share > 0.0f ? (x - below) / *share : 0.0f;
  *stretched = std::fmin(std::fmax(s, 0.0f), 0.99999994f);
  return lo;
}

}  // namespace

bool DirectLight::SampleArea(const Grid& grid, uint32_t receiver, uint32_t twin, const glm::vec3& x,
                             const glm::vec3& n, glm::vec2 u, Span<const Tally> tally,
                             float epsilon, uint32_t* hint, glm::vec3* weight, uint32_t* source,
                             uint32_t viewer) const {
  *weight = glm::vec3(0.0f);
  if (emitters_.empty()) return false;
  CHECK(tally.size() == groups_.size());
  // The group, in proportion to its unoccluded irradiance at x; then a
  // patch of it in proportion to its power (the group's cumulative shares
  // in its emitters' cdfHi).
  float sx, groupShare, patchShare;
  *source = Pick([&](uint32_t i) { return tally[i].cdf; }, static_cast<uint32_t>(tally.size()), u.x,
                 &sx, &groupShare);
  const Group& g = groups_[*source];
  if (!(groupShare > 0.0f)) return false;
  const Emitter* list = &emitters_[g.firstPatch];
  const Emitter& e =
      list[Pick([&](uint32_t i) { return list[i].cdfHi; }, g.numPatches, sx, &sx, &patchShare)];
  const Patch& p = patches_[e.patch];
  glm::vec3 y = PointOn(p, e.split, glm::vec2(sx, u.y));
  glm::vec3 d = y - x;
  float r2 = glm::dot(d, d);
  if (!(r2 > 0.0f)) return false;
  float cosX = glm::dot(n, d), cosY = -glm::dot(p.normal, d);
  if (!(cosX > 0.0f) || !(cosY > 0.0f)) return false;
  *weight = e.scale * (cosX * cosY / (r2 * r2)) / groupShare;
  float t = epsilon / std::sqrt(r2);
  if (!(t < 0.5f)) return true;
  return Unblocked(grid, Ray{x, d, t, 1.0f - t}, receiver, twin, hint) &&
         Passes(e.patch, viewer, x, n);
}

bool DirectLight::Passes(uint32_t patch, uint32_t viewer, const glm::vec3& x,
                         const glm::vec3& n) const {
  return viewer == kNoViewer || !transit_ || transit_->Passes(patch, viewer, x, n);
}

bool DirectLight::CornerVisible(const Grid& grid, uint32_t receiver, uint32_t twin,
                                const glm::vec3& x, const glm::vec3& n, uint32_t k, float epsilon,
                                uint32_t* hint, bool* usable, uint32_t viewer) const {
  *usable = false;
  const glm::vec3 y = corners_[k].point;
  glm::vec3 d = y - x;
  float r2 = glm::dot(d, d);
  if (!(glm::dot(n, d) > 0.0f) || !(r2 > 0.0f)) return false;
  // x in front of the corner's polygon.
  const Group& g = groups_[corners_[k].group];
  if (!(glm::dot(g.normal, x - g.point) > 0.0f)) return false;
  *usable = true;
  float t = epsilon / std::sqrt(r2);
  if (!(t < 0.5f)) return true;
  return Unblocked(grid, Ray{x, d, t, 1.0f - t}, receiver, twin, hint) &&
         Passes(corners_[k].patch, viewer, x, n);
}

}  // namespace vismask
