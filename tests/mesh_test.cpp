#include "vismask/scene/mesh.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>
#include <limits>
#include <map>
#include <numeric>
#include <vector>

namespace vismask {
namespace {

// Places xy-plane test shapes in a tilted plane away from the origin.
glm::vec3 Tilt(float x, float y) {
  static const glm::mat4 m =
      glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(30, -20, 5)), 0.7f, glm::vec3(1, 2, 3));
  return glm::vec3(m * glm::vec4(x, y, 0.0f, 1.0f));
}

// A scene of one polygon per xy-plane shape (tilted unless `flat`), with the
// normal and area the loader would give.
Scene MakeScene(const std::vector<std::vector<glm::vec2>>& shapes, bool flat = false) {
  Scene scene;
  scene.objPath = "test.obj";
  scene.materials.push_back(
      {"m", glm::vec3(0.5f), glm::vec3(1.0f, 2.0f, 3.0f), glm::vec3(0.0f), "", ""});
  for (const auto& shape : shapes) {
    Polygon p;
    for (glm::vec2 v : shape) p.corners.push_back(flat ? glm::vec3(v, 0.0f) : Tilt(v.x, v.y));
    glm::dvec3 sum(0.0);
    for (size_t i = 1; i + 1 < p.corners.size(); ++i)
      sum += glm::cross(glm::dvec3(p.corners[i] - p.corners[0]),
                        glm::dvec3(p.corners[i + 1] - p.corners[0]));
    p.normal = glm::vec3(glm::normalize(sum));
    p.area = glm::length(sum) / 2;
    scene.polygons.push_back(p);
  }
  return scene;
}

std::vector<uint32_t> All(const Scene& scene) {
  std::vector<uint32_t> all(scene.polygons.size());
  std::iota(all.begin(), all.end(), 0u);
  return all;
}

// Checks every patch of `mesh` against its polygon, and that the patches of
// each of `polygons` cover its area.
void CheckMesh(const Scene& scene, const std::vector<uint32_t>& polygons, const Mesh& mesh,
               float patchSize, double areaTolerance = 1e-5) {
  std::vector<double> area(scene.polygons.size(), 0.0);
  for (size_t i = 0; i < mesh.patches.size(); ++i) {
    const Patch& p = mesh.patches[i];
    SCOPED_TRACE(testing::Message() << "patch " << i << " of polygon " << p.surface);
    ASSERT_EQ(p.globalId, i);
    ASSERT_LT(p.surface, scene.polygons.size());
    ASSERT_TRUE(p.numCorners == 3 || p.numCorners == 4);
    const Polygon& poly = scene.polygons[p.surface];
    EXPECT_EQ(p.normal, poly.normal);
    EXPECT_EQ(p.kd, scene.materials[poly.material].kd);
    EXPECT_EQ(p.ke, scene.materials[poly.material].ke);
    if (p.numCorners == 3) {
      EXPECT_EQ(p.corner[3], p.corner[2]);
    }
    float extent = 0.0f;
    for (uint32_t k = 0; k < 4; ++k) {
      ASSERT_LT(p.vertex[k], mesh.vertices.size());
      EXPECT_EQ(mesh.vertices[p.vertex[k]], p.corner[k]);
      extent = std::fmax(extent, glm::length(p.corner[k]));
    }
    // Edges no longer than the patch size and corners on the polygon's plane,
    // up to float rounding of the coordinates; counter-clockwise and convex.
    const uint32_t n = p.numCorners;
    const float rounding = 8.0f * FLT_EPSILON * extent;
    for (uint32_t k = 0; k < n; ++k) {
      glm::vec3 a = p.corner[k], b = p.corner[(k + 1) % n], c = p.corner[(k + 2) % n];
      EXPECT_LE(glm::length(b - a), patchSize * (1.0f + 1e-6f) + rounding);
      EXPECT_LE(std::fabs(glm::dot(poly.normal, a - poly.corners[0])), rounding);
      EXPECT_GT(glm::dot(poly.normal, glm::cross(b - a, c - b)), 0.0f);
    }
    EXPECT_GT(p.area, 0.0f);
    area[p.surface] += p.area;
  }
  for (uint32_t i : polygons)
    EXPECT_NEAR(area[i], scene.polygons[i].area, areaTolerance * scene.polygons[i].area)
        << "polygon " << i;
}

// How many patches use each lattice vertex.
std::map<uint32_t, int> VertexUses(const Mesh& mesh) {
  std::map<uint32_t, int> uses;
  for (const Patch& p : mesh.patches)
    for (uint32_t k = 0; k < p.numCorners; ++k) ++uses[p.vertex[k]];
  return uses;
}

TEST(MeshTest, CornellBoxAtSeveralSizes) {
  Scene scene;
  Status s = LoadScene("scenes/cornell.obj", &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  for (float size : {7.0f, 25.0f, 100.0f, 1000.0f}) {
    SCOPED_TRACE(testing::Message() << "patch size " << size);
    Mesh mesh;
    s = MeshScene(scene, All(scene), size, 1u << 20, &mesh);
    ASSERT_TRUE(s.ok()) << s.ToString();
    CheckMesh(scene, All(scene), mesh, size);
    if (size == 1000.0f) {
      EXPECT_EQ(mesh.patches.size(), scene.polygons.size());
    }
  }
}

TEST(MeshTest, TriangleIntoSimilarTriangles) {
  Scene scene = MakeScene({{{0, 0}, {10, 0}, {0, 5}}});
  Mesh mesh;
  ASSERT_TRUE(MeshScene(scene, {0}, 3.0f, 100, &mesh).ok());  // longest edge 11.2: n = 4
  EXPECT_EQ(mesh.patches.size(), 16u);
  EXPECT_EQ(mesh.vertices.size(), 15u);
  CheckMesh(scene, {0}, mesh, 3.0f);
  for (const Patch& p : mesh.patches) EXPECT_NEAR(p.area, 25.0f / 16, 1e-4f);
  // The 3 interior lattice points are each shared by 6 triangles.
  int interior = 0;
  for (auto [vertex, uses] : VertexUses(mesh)) interior += uses == 6;
  EXPECT_EQ(interior, 3);
}

TEST(MeshTest, TrapezoidIntoQuadGrid) {
  Scene scene = MakeScene({{{0, 0}, {10, 0}, {7, 5}, {3, 5}}});
  Mesh mesh;
  ASSERT_TRUE(MeshScene(scene, {0}, 2.0f, 100, &mesh).ok());
  // u edges 10 and 4: m = 5; v edges 5.83: n = 3.
  EXPECT_EQ(mesh.patches.size(), 15u);
  EXPECT_EQ(mesh.vertices.size(), 24u);
  CheckMesh(scene, {0}, mesh, 2.0f);
  for (const Patch& p : mesh.patches) EXPECT_EQ(p.numCorners, 4u);
  // Interior lattice points, (m-1)(n-1) of them, are each shared by 4 quads.
  int interior = 0;
  for (auto [vertex, uses] : VertexUses(mesh)) interior += uses == 4;
  EXPECT_EQ(interior, 8);
}

TEST(MeshTest, ExactDivision) {
  // Exact in float when axis-aligned (tilted, the rounded edges may need 5).
  Scene scene = MakeScene({{{0, 0}, {100, 0}, {100, 100}, {0, 100}}}, true);
  Mesh mesh;
  ASSERT_TRUE(MeshScene(scene, {0}, 25.0f, 100, &mesh).ok());
  EXPECT_EQ(mesh.patches.size(), 16u);
  CheckMesh(scene, {0}, mesh, 25.0f);
}

TEST(MeshTest, NonConvexQuadAndPentagon) {
  // A dart (reflex at (2, 1)), a notched pentagon, and both clockwise.
  std::vector<std::vector<glm::vec2>> shapes = {{{0, 0}, {2, 1}, {4, 0}, {2, 4}},
                                                {{0, 0}, {4, 0}, {4, 4}, {2, 1}, {0, 4}}};
  for (size_t i = 0; i < 2; ++i) shapes.emplace_back(shapes[i].rbegin(), shapes[i].rend());
  Scene scene = MakeScene(shapes);
  EXPECT_NEAR(scene.polygons[0].area, 6.0, 1e-5);
  EXPECT_NEAR(scene.polygons[1].area, 10.0, 1e-5);
  for (float size : {0.3f, 1.0f, 10.0f}) {
    SCOPED_TRACE(testing::Message() << "patch size " << size);
    Mesh mesh;
    ASSERT_TRUE(MeshScene(scene, All(scene), size, 100000, &mesh).ok());
    CheckMesh(scene, All(scene), mesh, size);
    for (const Patch& p : mesh.patches) EXPECT_EQ(p.numCorners, 3u);
  }
}

TEST(MeshTest, AppendsAfterEarlierPolygons) {
  Scene scene;
  ASSERT_TRUE(LoadScene("scenes/cornell.obj", &scene).ok());
  Mesh mesh;
  ASSERT_TRUE(MeshScene(scene, {0, 1, 2}, 100.0f, 10000, &mesh).ok());
  const size_t firstVertices = mesh.vertices.size();
  ASSERT_TRUE(MeshScene(scene, {6, 16}, 100.0f, 10000, &mesh).ok());
  CheckMesh(scene, {0, 1, 2, 6, 16}, mesh, 100.0f);  // globalId == index across calls
  std::map<uint32_t, int> surfaces;
  for (const Patch& p : mesh.patches) {
    ++surfaces[p.surface];
    if (p.surface == 6 || p.surface == 16) {
      for (uint32_t v : p.vertex) EXPECT_GE(v, firstVertices);  // no sharing across polygons
    }
  }
  EXPECT_EQ(surfaces.size(), 5u);
}

TEST(MeshTest, BadPatchSize) {
  Scene scene = MakeScene({{{0, 0}, {1, 0}, {0, 1}}});
  for (float size : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                     std::numeric_limits<float>::infinity()}) {
    Mesh mesh;
    mesh.vertices.push_back(glm::vec3(0.0f));
    Status s = MeshScene(scene, {0}, size, 100, &mesh);
    EXPECT_FALSE(s.ok()) << size;
    EXPECT_NE(s.message().find("patch size"), std::string::npos) << s.ToString();
    EXPECT_EQ(mesh.vertices.size(), 1u);
    EXPECT_TRUE(mesh.patches.empty());
  }
}

TEST(MeshTest, TooManyPatches) {
  Scene scene = MakeScene({{{0, 0}, {10, 0}, {0, 5}}});  // 16 patches at size 3
  Mesh mesh;
  Status s = MeshScene(scene, {0}, 3.0f, 15, &mesh);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message(), "the mesh needs 16 patches at patch size 3, more than the limit of 15");
  EXPECT_TRUE(mesh.patches.empty());
  EXPECT_TRUE(mesh.vertices.empty());
  EXPECT_FALSE(MeshScene(scene, {0}, 1e-30f, 1000, &mesh).ok());  // count overflows nothing
  EXPECT_TRUE(MeshScene(scene, {0}, 3.0f, 16, &mesh).ok());
}

// Issue 42 item 3: a convex disc of 10,000 corners was ear-clipped into
// 9,998 slivers of up to (diameter / s)^2 patches each: over a million
// where its area needs a few hundred. Such a polygon is cut in strips: its
// patches number at most 2 (A / s^2 + P / s) whatever its corners, each
// still at most s a side, counter-clockwise and in its plane, covering its
// area less the slivers the chords cut off (below 0.5% here).
TEST(MeshTest, ConvexPolygonsOfManyCornersFollowTheirArea) {
  const float s = 0.1f;
  auto arc = [](int n, double rx, double ry, double from, double to, bool closed) {
    std::vector<glm::vec2> v;
    const int count = closed ? n : n + 1;
    for (int k = 0; k < count; ++k) {
      const double a = from + (to - from) * k / n;
      v.emplace_back(static_cast<float>(rx * std::cos(a)), static_cast<float>(ry * std::sin(a)));
    }
    return v;
  };
  const double pi = 3.14159265358979;
  const std::vector<std::vector<glm::vec2>> shapes = {
      arc(10000, 1.0, 1.0, 0.0, 2 * pi, true), arc(1000, 1.0, 1.0, 0.0, 2 * pi, true),
      arc(100, 1.0, 1.0, 0.0, 2 * pi, true),   arc(2000, 2.0, 0.5, 0.0, 2 * pi, true),
      arc(500, 1.0, 1.0, 0.0, pi, false),  // a half disc: two sharp corners
  };
  for (bool flat : {true, false}) {
    const Scene scene = MakeScene(shapes, flat);
    for (uint32_t i = 0; i < scene.polygons.size(); ++i) {
      const Polygon& poly = scene.polygons[i];
      SCOPED_TRACE(testing::Message()
                   << "shape " << i << ", " << poly.corners.size() << " corners, flat " << flat);
      double perimeter = 0.0;
      for (size_t k = 0; k < poly.corners.size(); ++k)
        perimeter +=
            glm::length(glm::dvec3(poly.corners[(k + 1) % poly.corners.size()] - poly.corners[k]));
      const double bound = 2.0 * (poly.area / (s * s) + perimeter / s);
      Mesh mesh;
      ASSERT_TRUE(MeshScene(scene, {i}, s, 1u << 24, &mesh).ok());
      EXPECT_LE(static_cast<double>(mesh.patches.size()), bound);
      CheckMesh(scene, {i}, mesh, s, 5e-3);
      double area = 0.0;
      for (const Patch& p : mesh.patches) area += p.area;
      EXPECT_LE(area, poly.area * (1.0 + 1e-6));  // inside the outline
      bool strips = false;
      double change = 0.0;
      ASSERT_TRUE(MeshesInStrips("test.obj", poly, s, &strips, &change).ok());
      EXPECT_TRUE(strips);
      EXPECT_NEAR(change, area / poly.area - 1.0, 1e-5);
      double counted = 0.0, vertices = 0.0;
      ASSERT_TRUE(CountPolygonPatches("test.obj", poly, s, &counted, &vertices).ok());
      EXPECT_EQ(counted, static_cast<double>(mesh.patches.size()));
      EXPECT_EQ(vertices, static_cast<double>(mesh.vertices.size()));
    }
  }
  // A polygon whose slivers stay within the bound keeps them: a small
  // hexagon is its 4 ear-clipped triangles, as before.
  const Scene hexagon = MakeScene({arc(6, 0.04, 0.04, 0.0, 2 * pi, true)});
  Mesh mesh;
  ASSERT_TRUE(MeshScene(hexagon, {0}, s, 1u << 20, &mesh).ok());
  EXPECT_EQ(mesh.patches.size(), 4u);
  CheckMesh(hexagon, {0}, mesh, s);
}

}  // namespace
}  // namespace vismask
