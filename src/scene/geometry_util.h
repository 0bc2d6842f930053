// Polygon geometry shared by the loader, the partition and the mesher:
// Newell's area vector, convexity, ear-clipping triangulation. Internal to src/.
#pragma once
#include <array>
#include <cstddef>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <numeric>
#include <vector>

namespace vismask {

// Newell's method about corner 0 (for precision): twice the area times the
// unit normal of a planar polygon whose corners run counter-clockwise about it.
inline glm::dvec3 NewellSum(const std::vector<glm::dvec3>& c) {
  glm::dvec3 sum(0.0);
  for (size_t i = 1; i + 1 < c.size(); ++i) sum += glm::cross(c[i] - c[0], c[i + 1] - c[0]);
  return sum;
}

inline double Cross2(glm::dvec2 a, glm::dvec2 b) {
  return a.x * b.y - a.y * b.x;
}

// Whether every corner turns strictly left about `normal` (no flat corners).
inline bool IsConvex(const std::vector<glm::dvec3>& c, glm::dvec3 normal) {
  const size_t n = c.size();
  for (size_t i = 0; i < n; ++i) {
    glm::dvec3 a = c[i] - c[(i + n - 1) % n], b = c[(i + 1) % n] - c[i];
    if (glm::dot(glm::cross(a, b), normal) <= 0.0) return false;
  }
  return true;
}

// Ear-clipping triangulation of a simple polygon whose corners run counter-
// clockwise about `normal`. False if it finds no ear (input the loader rejects).
inline bool Triangulate(const std::vector<glm::dvec3>& c, glm::dvec3 normal,
                        std::vector<std::array<size_t, 3>>* tris) {
  // Project along the normal's dominant axis, keeping the winding CCW.
  glm::dvec3 an = glm::abs(normal);
  int axis = an.x > an.y ? (an.x > an.z ? 0 : 2) : (an.y > an.z ? 1 : 2);
  double flip = normal[axis] < 0.0 ? -1.0 : 1.0;
  std::vector<glm::dvec2> p;
  for (const glm::dvec3& v : c) p.emplace_back(v[(axis + 1) % 3], flip * v[(axis + 2) % 3]);

  std::vector<size_t> left(c.size());
  std::iota(left.begin(), left.end(), size_t{0});
  while (left.size() > 3) {
    const size_t size = left.size();
    size_t k = 0;
    for (; k < size; ++k) {
      size_t ia = left[(k + size - 1) % size], ib = left[k], ic = left[(k + 1) % size];
      glm::dvec2 a = p[ia], b = p[ib], d = p[ic];
      if (Cross2(b - a, d - b) <= 0.0) continue;  // reflex or flat corner
      // An ear holds no other corner, not even on its border.
      bool empty = true;
      for (size_t q : left) {
        if (q == ia || q == ib || q == ic) continue;
        if (Cross2(b - a, p[q] - a) >= 0.0 && Cross2(d - b, p[q] - b) >= 0.0 &&
            Cross2(a - d, p[q] - d) >= 0.0) {
          empty = false;
          break;
        }
      }
      if (empty) break;
    }
    if (k == size) return false;
    tris->push_back({left[(k + size - 1) % size], left[k], left[(k + 1) % size]});
    left.erase(left.begin() + static_cast<std::ptrdiff_t>(k));
  }
  tris->push_back({left[0], left[1], left[2]});
  return true;
}

}  // namespace vismask
