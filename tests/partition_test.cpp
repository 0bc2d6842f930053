// Partitioning a scene into environments: parsing grids, planes and boxes,
// polygons cut at the planes, and the invariants on random polygons.
#include "vismask/solve/partition.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <map>
#include <string>
#include <vector>

#include "partition_test_util.h"

namespace vismask {
namespace {

using namespace parttest;

TEST(PartitionTest, ParseEnvGrid) {
  struct Case {
    const char* text;
    int n[3];
  };
  for (const Case& c :
       {Case{"2", {2, 1, 1}}, Case{"2x1", {2, 1, 1}}, Case{"4x1x2", {4, 1, 2}},
        Case{"1", {1, 1, 1}}, Case{"64x3", {64, 3, 1}}, Case{"1x1x64", {1, 1, 64}}}) {
    int n[3] = {7, 7, 7};
    ASSERT_TRUE(ParseEnvGrid(c.text, n)) << c.text;
    for (int a = 0; a < 3; ++a) EXPECT_EQ(n[a], c.n[a]) << c.text << " axis " << a;
  }
  for (const char* text : {"0", "2x", "x2", "2x2x2x2", "65", " 2", "2.5", "-1", "", "2 ", "2x0",
                           "+2", "02", "2X2", "2xx2", "99999999999", "2x65"}) {
    int n[3] = {7, 7, 7};
    EXPECT_FALSE(ParseEnvGrid(text, n)) << "'" << text << "'";
    EXPECT_EQ(n[0], 7) << "'" << text << "'";  // untouched on failure
  }
  int n[3];
  EXPECT_FALSE(ParseEnvGrid(nullptr, n));
}

TEST(PartitionTest, PlanesAndBoxes) {
  EnvGrid grid;
  grid.n[0] = 3;
  grid.n[1] = 7;
  grid.n[2] = 1;
  grid.box.lo = glm::vec3(0.1f, -3.3f, 2.0f);
  grid.box.hi = glm::vec3(0.7f, 5.9f, 2.5f);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(grid.Plane(a, 0), grid.box.lo[a]);
    EXPECT_EQ(grid.Plane(a, grid.n[a]), grid.box.hi[a]);
    for (int k = 0; k < grid.n[a]; ++k) EXPECT_LT(grid.Plane(a, k), grid.Plane(a, k + 1));
  }
  EXPECT_EQ(grid.Plane(1, 3), -3.3f + (5.9f - -3.3f) * 3.0f / 7.0f);
  // Neighbouring boxes share their planes exactly.
  for (int i = 0; i < grid.count(); ++i) {
    int c[3];
    grid.Cell(i, c);
    Bounds b = grid.EnvBox(i);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(b.lo[a], grid.Plane(a, c[a]));
      EXPECT_EQ(b.hi[a], grid.Plane(a, c[a] + 1));
    }
  }
}

TEST(PartitionTest, CornellAtSeveralGrids) {
  const Scene scene = LoadCornell();
  ASSERT_FALSE(scene.polygons.empty());
  for (const char* text : {"1", "2", "2x1", "4x1x2", "2x2x2", "3x3x3", "5x7x3", "64x1x1"}) {
    SCOPED_TRACE(text);
    const EnvGrid grid = MakeGrid(text, scene.bounds);
    Partition part;
    Status s = PartitionScene(scene, grid, &part);
    ASSERT_TRUE(s.ok()) << s.ToString();
    CheckPartition(scene, grid, part);
    if (grid.count() > 1) {
      EXPECT_GT(part.scene.polygons.size(), scene.polygons.size());
    }
  }
}

TEST(PartitionTest, OneEnvironmentKeepsThePolygons) {
  const Scene scene = LoadCornell();
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, MakeGrid("1", scene.bounds), &part).ok());
  ASSERT_EQ(part.scene.polygons.size(), scene.polygons.size());
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    const Polygon& p = part.scene.polygons[i];
    const Polygon& src = scene.polygons[i];
    EXPECT_EQ(part.env[i], 0u);
    EXPECT_EQ(part.source[i], i);
    EXPECT_EQ(p.corners, src.corners) << i;
    EXPECT_EQ(p.normal, src.normal) << i;
    EXPECT_EQ(p.area, src.area) << i;
    EXPECT_EQ(p.material, src.material) << i;
    EXPECT_EQ(p.line, src.line) << i;
  }
}

TEST(PartitionTest, QuadCrossingAPlaneSplitsAtIt) {
  const Scene scene = LoadCornell();
  const EnvGrid grid = MakeGrid("2", scene.bounds);
  ASSERT_EQ(grid.Plane(0, 1), 278.0f);
  // The floor, (552.8, 0, 0) (0, 0, 0) (0, 0, 559.2) (549.6, 0, 559.2), crosses x = 278.
  ASSERT_EQ(scene.polygons[0].corners.size(), 4u);
  ASSERT_EQ(scene.polygons[0].corners[1], glm::vec3(0.0f));
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
  std::vector<size_t> pieces;
  for (size_t i = 0; i < part.source.size(); ++i)
    if (part.source[i] == 0) pieces.push_back(i);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(part.env[pieces[0]], 0u);
  EXPECT_EQ(part.env[pieces[1]], 1u);
  std::vector<std::vector<glm::vec3>> cuts(2);
  for (int k = 0; k < 2; ++k) {
    const Polygon& p = part.scene.polygons[pieces[k]];
    EXPECT_EQ(p.corners.size(), 4u);
    for (const glm::vec3& v : p.corners) {
      if (v.x == 278.0f) cuts[k].push_back(v);
      EXPECT_TRUE(k == 0 ? v.x <= 278.0f : v.x >= 278.0f) << v.x;
    }
    ASSERT_EQ(cuts[k].size(), 2u) << "piece " << k;
    std::sort(cuts[k].begin(), cuts[k].end(), [](glm::vec3 a, glm::vec3 b) { return a.z < b.z; });
  }
  // Both pieces share the cut, which lies on the floor's edges.
  EXPECT_EQ(cuts[0], cuts[1]);
  EXPECT_EQ(cuts[0][0], glm::vec3(278.0f, 0.0f, 0.0f));
  EXPECT_EQ(cuts[0][1], glm::vec3(278.0f, 0.0f, 559.2f));
}

// A unit quad in the plane x = 1 (or y, z: `axis`) of the box [0, 2]^3,
// counter-clockwise seen from the + side when `facingUp`.
Scene QuadOnPlane(int axis, bool facingUp) {
  std::vector<glm::vec3> corners;
  const float uv[4][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  for (const auto& c : uv) {
    glm::vec3 v;
    v[axis] = 1.0f;
    v[(axis + 1) % 3] = c[0];
    v[(axis + 2) % 3] = c[1];
    corners.push_back(v);
  }
  if (!facingUp) std::reverse(corners.begin(), corners.end());
  Scene scene = MakeScene({MakePolygon(corners, 3)});
  scene.bounds.lo = glm::vec3(0.0f);
  scene.bounds.hi = glm::vec3(2.0f);
  return scene;
}

TEST(PartitionTest, PolygonOnASplitPlaneGoesToItsFrontSide) {
  for (int axis = 0; axis < 3; ++axis) {
    for (bool up : {true, false}) {
      SCOPED_TRACE(testing::Message() << "axis " << axis << (up ? " facing +" : " facing -"));
      const Scene scene = QuadOnPlane(axis, up);
      ASSERT_EQ(scene.polygons[0].normal[axis], up ? 1.0f : -1.0f);
      // Two environments along the axis: whole, in the one it faces.
      EnvGrid grid;
      grid.n[axis] = 2;
      grid.box = scene.bounds;
      Partition part;
      ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
      ASSERT_EQ(part.scene.polygons.size(), 1u);
      EXPECT_EQ(part.env[0], up ? 1u : 0u);
      EXPECT_EQ(part.scene.polygons[0].corners, scene.polygons[0].corners);
      // 2x2x2: cut in four along the other axes, all on the side it faces.
      grid = MakeGrid("2x2x2", scene.bounds);
      ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
      CheckPartition(scene, grid, part);
      ASSERT_EQ(part.scene.polygons.size(), 4u);
      for (size_t i = 0; i < 4; ++i) {
        int c[3];
        grid.Cell(static_cast<int>(part.env[i]), c);
        EXPECT_EQ(c[axis], up ? 1 : 0);
        EXPECT_NEAR(part.scene.polygons[i].area, 1.0, 1e-12);
        for (const glm::vec3& v : part.scene.polygons[i].corners) EXPECT_EQ(v[axis], 1.0f);
      }
    }
  }
}

TEST(PartitionTest, PolygonTouchingAPlaneIsNotCut) {
  // A square in z = 0.5 whose edge lies on the plane x = 1 of the box [0, 2]^3.
  Scene scene = MakeScene({MakePolygon(
      {{0.0f, 0.0f, 0.5f}, {1.0f, 0.0f, 0.5f}, {1.0f, 1.0f, 0.5f}, {0.0f, 1.0f, 0.5f}}, 1)});
  scene.bounds.lo = glm::vec3(0.0f);
  scene.bounds.hi = glm::vec3(2.0f);
  const EnvGrid grid = MakeGrid("2x2x2", scene.bounds);
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
  ASSERT_EQ(part.scene.polygons.size(), 1u);
  EXPECT_EQ(part.env[0], 0u);
  EXPECT_EQ(part.scene.polygons[0].corners, scene.polygons[0].corners);
}

TEST(PartitionTest, NonConvexPolygonConservesArea) {
  // An L in z = 0 of area 5: [0, 1] x [0, 3] and [1, 3] x [0, 1].
  const Scene scene = MakeScene({MakePolygon({{0.0f, 0.0f, 0.0f},
                                              {3.0f, 0.0f, 0.0f},
                                              {3.0f, 1.0f, 0.0f},
                                              {1.0f, 1.0f, 0.0f},
                                              {1.0f, 3.0f, 0.0f},
                                              {0.0f, 3.0f, 0.0f}},
                                             9)});
  ASSERT_DOUBLE_EQ(scene.polygons[0].area, 5.0);
  struct Case {
    const char* grid;
    std::map<uint32_t, double> area;  // by environment
  };
  // Planes at x = 1.5 (and y = 1.5).
  for (const Case& c :
       {Case{"2", {{0, 3.5}, {1, 1.5}}}, Case{"2x2", {{0, 2.0}, {1, 1.5}, {2, 1.5}}},
        Case{"3x3", {{0, 1.0}, {1, 1.0}, {2, 1.0}, {3, 1.0}, {6, 1.0}}}}) {
    SCOPED_TRACE(c.grid);
    const EnvGrid grid = MakeGrid(c.grid, scene.bounds);
    Partition part;
    ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
    CheckPartition(scene, grid, part);
    std::map<uint32_t, double> area;
    for (size_t i = 0; i < part.env.size(); ++i) area[part.env[i]] += part.scene.polygons[i].area;
    ASSERT_EQ(area.size(), c.area.size());
    for (const auto& [env, expected] : c.area) EXPECT_NEAR(area[env], expected, 1e-6) << env;
  }
}

TEST(PartitionTest, SliverPastAPlaneIsDropped) {
  // A triangle whose tip is 1e-5 past the plane x = 1: the piece there has
  // area ~5e-11, below 1e-7 of the triangle's.
  const float tip = 1.0f + 1e-5f;
  const Scene scene =
      MakeScene({MakePolygon({{0.0f, 0.0f, 0.0f}, {tip, 0.5f, 0.0f}, {0.0f, 1.0f, 0.0f}}, 1)});
  Bounds box = scene.bounds;
  box.hi.x = 2.0f;
  const EnvGrid grid = MakeGrid("2", box);
  ASSERT_EQ(grid.Plane(0, 1), 1.0f);
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
  CheckPartition(scene, grid, part);
  ASSERT_EQ(part.scene.polygons.size(), 1u);
  EXPECT_EQ(part.env[0], 0u);
  for (const glm::vec3& v : part.scene.polygons[0].corners) EXPECT_LE(v.x, 1.0f);
}

TEST(PartitionTest, RandomPolygonsOnALattice) {
  // Corners on an integer lattice and planes at integers, so that many
  // corners, edges and whole polygons lie exactly on planes. Fixed seed.
  uint32_t state = 12345;
  auto next = [&](int n) {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>((state >> 16) % static_cast<uint32_t>(n));
  };
  std::vector<Polygon> polygons;
  while (polygons.size() < 300) {
    const int kind = static_cast<int>(next(3));
    std::vector<glm::vec3> c;
    if (kind == 0) {  // any triangle
      for (int k = 0; k < 3; ++k) c.push_back({next(9), next(9), next(9)});
    } else {  // an axis-aligned rectangle (1) or L (2) across an axis
      const int axis = static_cast<int>(next(3));
      const float at = next(9), u0 = next(8), v0 = next(8);
      const float u1 = u0 + 1 + next(8 - static_cast<int>(u0)),
                  v1 = v0 + 1 + next(8 - static_cast<int>(v0));
      std::vector<glm::vec2> uv = {{u0, v0}, {u1, v0}, {u1, v1}, {u0, v1}};
      if (kind == 2) {
        if (u1 - u0 < 2 || v1 - v0 < 2) continue;
        uv = {{u0, v0}, {u1, v0}, {u1, v0 + 1}, {u0 + 1, v0 + 1}, {u0 + 1, v1}, {u0, v1}};
      }
      if (next(2) == 1) std::reverse(uv.begin(), uv.end());
      for (glm::vec2 p : uv) {
        glm::vec3 v;
        v[axis] = at;
        v[(axis + 1) % 3] = p.x;
        v[(axis + 2) % 3] = p.y;
        c.push_back(v);
      }
    }
    glm::dvec3 a = AreaVector(c);
    if (glm::length(a) < 0.1) continue;
    polygons.push_back(MakePolygon(c, static_cast<int>(polygons.size()) + 1));
  }
  Scene scene = MakeScene(polygons);
  Bounds box;
  box.hi = glm::vec3(8.0f);
  for (const char* text : {"1", "2x4x8", "8x8x8", "4x2", "1x1x8"}) {
    SCOPED_TRACE(text);
    const EnvGrid grid = MakeGrid(text, box);
    Partition part;
    ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
    CheckPartition(scene, grid, part);
    // An axis-aligned polygon on a plane stays on the side it faces.
    for (size_t i = 0; i < part.env.size(); ++i) {
      const Polygon& src = scene.polygons[part.source[i]];
      const Bounds b = grid.EnvBox(static_cast<int>(part.env[i]));
      for (int a = 0; a < 3; ++a) {
        const float at = src.corners[0][a];
        bool onSplit = false;
        for (int k = 1; k < grid.n[a]; ++k) onSplit = onSplit || at == grid.Plane(a, k);
        if (std::fabs(src.normal[a]) != 1.0f || !onSplit) continue;
        EXPECT_EQ(src.normal[a] > 0.0f ? b.lo[a] : b.hi[a], at) << "piece " << i << " axis " << a;
      }
    }
  }
}

TEST(PartitionTest, BoxNotHoldingTheSceneFails) {
  const Scene scene = LoadCornell();
  Bounds box = scene.bounds;
  box.hi.x = 500.0f;
  Partition part;
  part.env.push_back(42);
  Status s = PartitionScene(scene, MakeGrid("2", box), &part);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("outside"), std::string::npos) << s.ToString();
  ASSERT_EQ(part.env.size(), 1u);  // untouched
}

}  // namespace
}  // namespace vismask
