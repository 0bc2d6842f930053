#include "vismask/display/smoothing.h"

#include <algorithm>
#include <glm/geometric.hpp>
#include <vector>

#include "vismask/core/check.h"

namespace vismask {

// Marks a twin's polygon id in SmoothVertex::polygon (source polygon ids are
// far below 2^31).
constexpr uint32_t kTwinPolygon = 0x80000000u;

void MarkSmoothVertices(const Scene& source, const Partition& part, float tolerance, Mesh* mesh,
                        const std::vector<uint32_t>* sourceIds) {
  const double tol = tolerance;
  std::vector<char> seen(mesh->vertices.size(), 0);
  std::vector<SmoothVertex> found;
  for (const Patch& p : mesh->patches) {
    CHECK(p.surface < part.source.size());
    const uint32_t src = part.source[p.surface];
    const Polygon& poly = source.polygons[src];
    if (poly.smoothing == 0 && poly.vn.empty()) continue;
    // A two-sided twin (--two-sided) is its polygon seen from the back: its
    // normals are the polygon's negated, so it never smooths with its
    // original, only with the twins of its neighbours.
    const float side = glm::dot(p.normal, poly.normal) < 0.0f ? -1.0f : 1.0f;
    // ... and it is another polygon: the same id would join the two sides.
    const uint32_t global = sourceIds ? (*sourceIds)[src] : src;
    const uint32_t id = side < 0.0f ? global | kTwinPolygon : global;
    const size_t m = poly.corners.size();
    for (uint32_t k = 0; k < p.numCorners; ++k) {
      const uint32_t v = p.vertex[k];
      if (seen[v]) continue;
      seen[v] = 1;
      const glm::dvec3 x(mesh->vertices[v]);
      SmoothVertex s{v,
                     id,
                     poly.smoothing,
                     {kNoPatch, kNoPatch},
                     side * poly.normal,
                     glm::vec3(0.0f),
                     glm::vec3(0.0f)};
      // The outline edges within `tolerance` of x; the vertex normal is
      // interpolated along the first.
      for (size_t e = 0; e < m; ++e) {
        const glm::dvec3 a(poly.corners[e]), b(poly.corners[(e + 1) % m]);
        const glm::dvec3 ab = b - a;
        double t = glm::dot(x - a, ab) / glm::dot(ab, ab);
        t = std::min(1.0, std::max(0.0, t));
        if (glm::length(a + t * ab - x) > tol) continue;
        if (s.edge[0] == kNoPatch) {
          s.edge[0] = static_cast<uint32_t>(e);
          s.dir = glm::vec3(glm::normalize(ab));
          if (!poly.vn.empty()) {
            glm::dvec3 n =
                (1.0 - t) * glm::dvec3(poly.vn[e]) + t * glm::dvec3(poly.vn[(e + 1) % m]);
            double len = glm::length(n);
            if (len > 0.0) s.vn = side * glm::vec3(n / len);
          }
        } else if (s.edge[1] == kNoPatch) {
          s.edge[1] = static_cast<uint32_t>(e);
        }
      }
      if (s.edge[0] == kNoPatch) continue;  // inside the polygon
      if (s.edge[1] == kNoPatch) s.edge[1] = s.edge[0];
      found.push_back(s);
    }
  }
  std::sort(found.begin(), found.end(),
            [](const SmoothVertex& a, const SmoothVertex& b) { return a.vertex < b.vertex; });
  mesh->smooth.insert(mesh->smooth.end(), found.begin(), found.end());
}

bool SmoothTogether(const glm::vec3& na, const glm::vec3& vna, uint32_t ga, const glm::vec3& nb,
                    const glm::vec3& vnb, uint32_t gb, float cosCrease) {
  const glm::vec3 zero(0.0f);
  if (vna != zero && vnb != zero)
    return glm::dot(vna, vnb) >= cosCrease && glm::dot(vna, nb) > 0.0f && glm::dot(vnb, na) > 0.0f;
  return ga != 0 && ga == gb && glm::dot(na, nb) >= cosCrease;
}

}  // namespace vismask
