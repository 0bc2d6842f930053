#include "vismask/scene/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <limits>
#include <string>
#include <vector>

#include "geometry_util.h"
#include "mesh_internal.h"
#include "vismask/core/check.h"

namespace vismask {
namespace {

using meshing::Piece;
using meshing::StripPieces;

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), x < 1e18 && x == std::floor(x) ? "%.0f" : "%.3g", x);
  return buf;
}

bool IsConvexQuad(const std::vector<glm::dvec3>& c, glm::dvec3 normal) {
  return c.size() == 4 && IsConvex(c, normal);
}

// Appends the patch over lattice vertices v[0..k) of one polygon.
void AddPatch(const Scene& scene, uint32_t polygon, const uint32_t* v, uint32_t k, Mesh* mesh) {
  const Polygon& poly = scene.polygons[polygon];
  const Material& mat = scene.materials[poly.material];
  Patch p{};
  for (uint32_t q = 0; q < 4; ++q) {
    p.vertex[q] = v[std::min(q, k - 1)];
    p.corner[q] = mesh->vertices[p.vertex[q]];
  }
  p.numCorners = k;
  p.normal = poly.normal;
  p.kd = mat.kd;
  p.ke = mat.ke;
  // Area projected on the normal: two triangles (the second is empty for k == 3).
  glm::dvec3 n(poly.normal), a(p.corner[0]), b(p.corner[1]), c(p.corner[2]), d(p.corner[3]);
  p.area = static_cast<float>(
      0.5 * (glm::dot(n, glm::cross(b - a, c - a)) + glm::dot(n, glm::cross(c - a, d - a))));
  p.surface = polygon;
  p.globalId = static_cast<uint32_t>(mesh->patches.size());
  mesh->patches.push_back(p);
}

// Appends an m x n grid over a convex quad: (m+1)(n+1) shared lattice points.
void MeshQuad(const Scene& scene, const Piece& q, Mesh* mesh) {
  const uint64_t m = static_cast<uint64_t>(q.m), n = static_cast<uint64_t>(q.n);
  const uint64_t base = mesh->vertices.size();
  for (uint64_t j = 0; j <= n; ++j) {
    for (uint64_t i = 0; i <= m; ++i) {
      double u = static_cast<double>(i) / q.m, v = static_cast<double>(j) / q.n;
      glm::dvec3 x =
          (1 - u) * (1 - v) * q.c[0] + u * (1 - v) * q.c[1] + u * v * q.c[2] + (1 - u) * v * q.c[3];
      mesh->vertices.emplace_back(x);
    }
  }
  auto at = [&](uint64_t i, uint64_t j) { return static_cast<uint32_t>(base + j * (m + 1) + i); };
  for (uint64_t j = 0; j < n; ++j) {
    for (uint64_t i = 0; i < m; ++i) {
      uint32_t v[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      AddPatch(scene, q.polygon, v, 4, mesh);
    }
  }
}

// Appends n x n triangles similar to the piece over a triangular lattice of
// (n+1)(n+2)/2 points; point (i, j) is c0 + (i(c1-c0) + j(c2-c0)) / n.
void MeshTriangle(const Scene& scene, const Piece& t, Mesh* mesh) {
  const uint64_t n = static_cast<uint64_t>(t.n);
  const uint64_t base = mesh->vertices.size();
  for (uint64_t j = 0; j <= n; ++j) {
    for (uint64_t i = 0; i + j <= n; ++i) {
      glm::dvec3 x = (static_cast<double>(n - i - j) * t.c[0] + static_cast<double>(i) * t.c[1] +
                      static_cast<double>(j) * t.c[2]) /
                     t.n;
      mesh->vertices.emplace_back(x);
    }
  }
  auto at = [&](uint64_t i, uint64_t j) {
    return static_cast<uint32_t>(base + j * (n + 1) - j * (j - 1) / 2 + i);
  };
  for (uint64_t j = 0; j < n; ++j) {
    for (uint64_t i = 0; i + j < n; ++i) {
      uint32_t up[3] = {at(i, j), at(i + 1, j), at(i, j + 1)};
      AddPatch(scene, t.polygon, up, 3, mesh);
      if (i + j + 1 < n) {
        uint32_t down[3] = {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
        AddPatch(scene, t.polygon, down, 3, mesh);
      }
    }
  }
}

// Appends the fan of t.n triangles from t.c[0] over t.c[1] .. t.c[2]: n + 2
// lattice points.
void MeshFan(const Scene& scene, const Piece& t, Mesh* mesh) {
  const uint64_t n = static_cast<uint64_t>(t.n);
  const uint32_t apex = static_cast<uint32_t>(mesh->vertices.size());
  mesh->vertices.emplace_back(t.c[0]);
  for (uint64_t j = 0; j <= n; ++j) {
    const double f = static_cast<double>(j) / t.n;
    mesh->vertices.emplace_back((1.0 - f) * t.c[1] + f * t.c[2]);
  }
  for (uint64_t j = 0; j < n; ++j) {
    uint32_t v[3] = {apex, static_cast<uint32_t>(apex + 1 + j),
                     static_cast<uint32_t>(apex + 2 + j)};
    AddPatch(scene, t.polygon, v, 3, mesh);
  }
}

// Plans the pieces of one polygon (appended to *pieces unless null) and
// counts their patches and lattice vertices.
Status PlanPolygon(const std::string& objPath, const Polygon& poly, uint32_t index, double s,
                   std::vector<Piece>* pieces, double* numPatches, double* numVertices,
                   bool* inStrips = nullptr) {
  if (inStrips) *inStrips = false;
  std::vector<glm::dvec3> c;
  for (const glm::vec3& v : poly.corners) c.emplace_back(v);
  if (IsConvexQuad(c, glm::dvec3(poly.normal))) {
    Piece q{index, 4, {c[0], c[1], c[2], c[3]}, 0.0, 0.0};
    QuadDivisions(c.data(), s, &q.m, &q.n);
    *numPatches += q.m * q.n;
    *numVertices += (q.m + 1) * (q.n + 1);
    if (pieces) pieces->push_back(q);
    return Status::Ok();
  }
  // A convex polygon of many corners whose ear-clipped slivers would make
  // more than twice its area and outline in patches: as strips, when they
  // make fewer (a disc's slivers each take patches of their own, far more
  // than its area needs).
  // Any triangulation has n - 2 patches at least: past the bound by that
  // alone, the strips are taken without triangulating.
  const glm::dvec3 normal(poly.normal);
  double perimeter = 0.0;
  for (size_t k = 0; k < c.size(); ++k) perimeter += glm::length(c[(k + 1) % c.size()] - c[k]);
  const double bound = 2.0 * (0.5 * glm::length(NewellSum(c)) / (s * s) + perimeter / s);
  std::vector<Piece> strips;
  double stripPatches = 0.0, stripVertices = 0.0;
  const bool haveStrips = StripPieces(c, normal, index, s, &strips, &stripPatches, &stripVertices);
  auto useStrips = [&]() {
    *numPatches += stripPatches;
    *numVertices += stripVertices;
    if (pieces) pieces->insert(pieces->end(), strips.begin(), strips.end());
    if (inStrips) *inStrips = true;
    return Status::Ok();
  };
  const double fewest = static_cast<double>(c.size()) - 2.0;
  if (haveStrips && fewest > bound && stripPatches < fewest) return useStrips();
  std::vector<std::array<size_t, 3>> tris;
  if (!Triangulate(c, normal, &tris))
    return Status::At(objPath, poly.line, "cannot triangulate face");
  std::vector<Piece> triangles;
  double triPatches = 0.0, triVertices = 0.0;
  for (const auto& tri : tris) {
    Piece t{index, 3, {c[tri[0]], c[tri[1]], c[tri[2]], c[tri[2]]}, 0.0, 0.0};
    double longest = std::max(
        {glm::length(t.c[1] - t.c[0]), glm::length(t.c[2] - t.c[1]), glm::length(t.c[0] - t.c[2])});
    t.n = t.m = EdgeDivisions(longest, s);
    triPatches += t.n * t.n;
    triVertices += (t.n + 1) * (t.n + 2) / 2;
    triangles.push_back(t);
  }
  if (haveStrips && triPatches > bound && stripPatches < triPatches) return useStrips();
  *numPatches += triPatches;
  *numVertices += triVertices;
  if (pieces) pieces->insert(pieces->end(), triangles.begin(), triangles.end());
  return Status::Ok();
}

}  // namespace

Status CountPolygonPatches(const std::string& objPath, const Polygon& polygon, float patchSize,
                           double* patches, double* vertices, bool* strips) {
  return PlanPolygon(objPath, polygon, 0, patchSize, nullptr, patches, vertices, strips);
}

Status MeshesInStrips(const std::string& objPath, const Polygon& polygon, float patchSize,
                      bool* strips, double* areaChange) {
  std::vector<Piece> pieces;
  double patches = 0.0, vertices = 0.0;
  *areaChange = 0.0;
  Status st = PlanPolygon(objPath, polygon, 0, patchSize, &pieces, &patches, &vertices, strips);
  if (!st.ok() || !*strips) return st;
  double area = 0.0;
  for (const Piece& p : pieces) {
    area += 0.5 * glm::length(glm::cross(p.c[1] - p.c[0], p.c[2] - p.c[0]));
    if (!p.fan) area += 0.5 * glm::length(glm::cross(p.c[2] - p.c[0], p.c[3] - p.c[0]));
  }
  if (polygon.area > 0.0) *areaChange = area / polygon.area - 1.0;
  return Status::Ok();
}

double EdgeDivisions(double len, double patchSize) {
  return std::max(1.0, std::ceil(len / patchSize));
}

void QuadDivisions(const glm::dvec3* c, double patchSize, double* m, double* n) {
  *m = EdgeDivisions(std::max(glm::length(c[1] - c[0]), glm::length(c[2] - c[3])), patchSize);
  *n = EdgeDivisions(std::max(glm::length(c[3] - c[0]), glm::length(c[2] - c[1])), patchSize);
}

Status MeshSizeError(double numPatches, float patchSize, uint64_t maxPatches) {
  return Status::Error("the mesh needs " + Num(numPatches) + " patches at patch size " +
                       Num(patchSize) + ", more than the limit of " +
                       Num(static_cast<double>(maxPatches)));
}

Status MeshScene(const Scene& scene, const std::vector<uint32_t>& polygons, float patchSize,
                 uint64_t maxPatches, Mesh* mesh) {
  if (!(std::isfinite(patchSize) && patchSize > 0.0f))
    return Status::Error("patch size must be a positive finite number, got " + Num(patchSize));
  const double s = patchSize;

  // Plan every piece and count, so that nothing is appended on failure.
  std::vector<Piece> pieces;
  double numPatches = 0.0, numVertices = 0.0;
  for (uint32_t index : polygons) {
    CHECK(index < scene.polygons.size());
    Status st = PlanPolygon(scene.objPath, scene.polygons[index], index, s, &pieces, &numPatches,
                            &numVertices);
    if (!st.ok()) return st;
  }
  if (numPatches > static_cast<double>(maxPatches))
    return MeshSizeError(numPatches, patchSize, maxPatches);
  // Patch and vertex ids are 32-bit (kNoPatch is reserved).
  const double kMaxId = static_cast<double>(kNoPatch);
  if (static_cast<double>(mesh->patches.size()) + numPatches >= kMaxId ||
      static_cast<double>(mesh->vertices.size()) + numVertices >= kMaxId)
    return Status::Error("the mesh needs " + Num(numPatches) + " patches and " + Num(numVertices) +
                         " vertices at patch size " + Num(s) + ", more than 32-bit ids allow");

  CHECK_MSG(mesh->twin.empty(), "twins come after every patch: AddTwins after the last MeshScene");
  mesh->patches.reserve(mesh->patches.size() + static_cast<size_t>(numPatches));
  mesh->vertices.reserve(mesh->vertices.size() + static_cast<size_t>(numVertices));
  for (const Piece& piece : pieces) {
    if (piece.fan) {
      MeshFan(scene, piece, mesh);
    } else if (piece.numCorners == 4) {
      MeshQuad(scene, piece, mesh);
    } else {
      MeshTriangle(scene, piece, mesh);
    }
  }
  return Status::Ok();
}

void AddTwins(const TwinOptions& options, Mesh* mesh, const Scene* scene) {
  if (!options.any()) return;
  const uint32_t n = static_cast<uint32_t>(mesh->patches.size());
  CHECK_MSG(mesh->twin.empty(), "AddTwins runs once, on a mesh without twins");
  mesh->twin.assign(n, kNoPatch);
  // Each original vertex a twin uses gets one copy, shared by the twins of
  // the patches around it: the reversed side has a lattice of its own.
  std::vector<uint32_t> copy(mesh->vertices.size(), kNoPatch);
  for (uint32_t i = 0; i < n; ++i) {
    const Patch p = mesh->patches[i];  // a copy: patches grows below
    const bool emits = p.ke.x > 0.0f || p.ke.y > 0.0f || p.ke.z > 0.0f;
    const uint32_t material = options.materials.empty() ? 0 : scene->polygons[p.surface].material;
    if (!options.Twins(material, emits)) continue;
    // corner[0] stays, the rest run backwards; a triangle repeats its last.
    static const uint32_t kQuad[4] = {0, 3, 2, 1}, kTriangle[4] = {0, 2, 1, 1};
    const uint32_t* from = p.numCorners == 4 ? kQuad : kTriangle;
    Patch t = p;
    for (uint32_t q = 0; q < 4; ++q) {
      uint32_t v = p.vertex[from[q]];
      if (copy[v] == kNoPatch) {
        copy[v] = static_cast<uint32_t>(mesh->vertices.size());
        glm::vec3 x = mesh->vertices[v];
        mesh->vertices.push_back(x);
      }
      t.vertex[q] = copy[v];
      t.corner[q] = p.corner[from[q]];
    }
    t.normal = -p.normal;
    if (!options.TwinEmits(material, emits)) t.ke = glm::vec3(0.0f);
    t.globalId = static_cast<uint32_t>(mesh->patches.size());
    mesh->twin[i] = t.globalId;
    mesh->twin.push_back(i);
    mesh->patches.push_back(t);
  }
}

}  // namespace vismask
