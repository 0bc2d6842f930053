#include "partition_test_util.h"

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

#include "vismask/solve/partition.h"

namespace vismask::parttest {

glm::dvec3 AreaVector(const std::vector<glm::vec3>& corners) {
  glm::dvec3 sum(0.0), c0(corners[0]);
  for (size_t i = 1; i + 1 < corners.size(); ++i)
    sum += glm::cross(glm::dvec3(corners[i]) - c0, glm::dvec3(corners[i + 1]) - c0);
  return sum / 2.0;
}

Polygon MakePolygon(const std::vector<glm::vec3>& corners, int line) {
  Polygon p;
  p.corners = corners;
  glm::dvec3 a = AreaVector(corners);
  p.area = glm::length(a);
  p.normal = glm::vec3(a / p.area);
  p.line = line;
  return p;
}

Scene MakeScene(const std::vector<Polygon>& polygons) {
  Scene scene;
  scene.objPath = "test.obj";
  scene.materials.push_back({"m", glm::vec3(0.5f), glm::vec3(1.0f), glm::vec3(0.0f), "", ""});
  scene.polygons = polygons;
  scene.bounds.lo = scene.bounds.hi = polygons[0].corners[0];
  for (const Polygon& p : polygons) {
    for (const glm::vec3& v : p.corners) {
      scene.bounds.lo = glm::min(scene.bounds.lo, v);
      scene.bounds.hi = glm::max(scene.bounds.hi, v);
    }
  }
  return scene;
}

EnvGrid MakeGrid(const char* text, const Bounds& box) {
  EnvGrid grid;
  EXPECT_TRUE(ParseEnvGrid(text, grid.n)) << text;
  grid.box = box;
  return grid;
}

Scene LoadCornell() {
  Scene scene;
  Status s = LoadScene("scenes/cornell.obj", &scene);
  EXPECT_TRUE(s.ok()) << s.ToString();
  return scene;
}

void CheckPartition(const Scene& scene, const EnvGrid& grid, const Partition& part) {
  const size_t n = part.scene.polygons.size();
  ASSERT_EQ(part.env.size(), n);
  ASSERT_EQ(part.source.size(), n);
  EXPECT_EQ(part.scene.objPath, scene.objPath);
  EXPECT_EQ(part.scene.materials.size(), scene.materials.size());
  EXPECT_EQ(part.scene.bounds.lo, scene.bounds.lo);
  EXPECT_EQ(part.scene.bounds.hi, scene.bounds.hi);
  for (int a = 0; a < 3; ++a) EXPECT_EQ(part.grid.n[a], grid.n[a]);
  const double size = glm::length(glm::dvec3(scene.bounds.hi) - glm::dvec3(scene.bounds.lo));
  const double tol = 1e-4 * size;
  std::vector<double> area(scene.polygons.size(), 0.0);
  std::vector<int> count(scene.polygons.size(), 0);
  double total = 0.0, sourceTotal = 0.0;
  for (size_t i = 0; i < n; ++i) {
    SCOPED_TRACE(testing::Message() << "piece " << i << " of polygon " << part.source[i]);
    ASSERT_LT(part.env[i], static_cast<uint32_t>(grid.count()));
    ASSERT_LT(part.source[i], scene.polygons.size());
    if (i > 0) {
      ASSERT_LE(part.env[i - 1], part.env[i]);
      if (part.env[i - 1] == part.env[i]) {
        ASSERT_LE(part.source[i - 1], part.source[i]);
      }
    }
    const Polygon& p = part.scene.polygons[i];
    const Polygon& src = scene.polygons[part.source[i]];
    EXPECT_EQ(p.normal, src.normal);
    EXPECT_EQ(p.material, src.material);
    EXPECT_EQ(p.line, src.line);
    ASSERT_GE(p.corners.size(), 3u);
    EXPECT_NEAR(p.area, glm::length(AreaVector(p.corners)), 1e-9 * src.area);
    EXPECT_GT(p.area, 0.0);
    const Bounds box = grid.EnvBox(static_cast<int>(part.env[i]));
    const size_t k = p.corners.size();
    for (size_t j = 0; j < k; ++j) {
      const glm::vec3 v = p.corners[j];
      for (int a = 0; a < 3; ++a) {
        EXPECT_GE(v[a], box.lo[a] - tol) << "corner " << j << " axis " << a;
        EXPECT_LE(v[a], box.hi[a] + tol) << "corner " << j << " axis " << a;
      }
      EXPECT_LE(std::fabs(glm::dot(glm::dvec3(src.normal), glm::dvec3(v - src.corners[0]))), tol);
      // A corner made by a cut lies exactly on a face of the box.
      if (std::find(src.corners.begin(), src.corners.end(), v) == src.corners.end()) {
        bool onFace = false;
        for (int a = 0; a < 3; ++a) onFace = onFace || v[a] == box.lo[a] || v[a] == box.hi[a];
        EXPECT_TRUE(onFace) << "corner " << j;
      }
      if (p.corners != src.corners) {  // a cut piece is convex
        glm::dvec3 u(p.corners[(j + 1) % k] - v),
            w(p.corners[(j + 2) % k] - p.corners[(j + 1) % k]);
        EXPECT_GT(glm::dot(glm::cross(u, w), glm::dvec3(src.normal)), 0.0) << "corner " << j + 1;
      }
    }
    area[part.source[i]] += p.area;
    ++count[part.source[i]];
    total += p.area;
  }
  for (size_t s = 0; s < scene.polygons.size(); ++s) {
    EXPECT_GE(count[s], 1) << "polygon " << s;
    EXPECT_NEAR(area[s], scene.polygons[s].area, 1e-6 * scene.polygons[s].area) << "polygon " << s;
    sourceTotal += scene.polygons[s].area;
  }
  EXPECT_NEAR(total, sourceTotal, 1e-6 * sourceTotal);
}

}  // namespace vismask::parttest
