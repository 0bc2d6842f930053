// Two-sided scenes (--two-sided, --two-sided-emitters: mesh.h's twins): the
// twins' corners, the rays that meet them, the shot that skips its twin, and
// the one twin drawn.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <glm/geometric.hpp>
#include <string>
#include <vector>

#include "twosided_test_util.h"
#include "vismask/accel/grid.h"
#include "vismask/display/camera.h"
#include "vismask/display/display.h"
#include "vismask/output/image_io.h"
#include "vismask/scene/mesh.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/environment.h"
#include "vismask/solve/rng.h"

namespace vismask {
namespace {

using twosided::LoadText;

// A tilted triangle with awkward coordinates, emitting, meshed into many
// patches and twinned.
Mesh TwinnedTriangle(Scene* scene, bool emitters) {
  *scene =
      LoadText("usemtl light\nv 0.13 0.21 0.37\nv 1.31 0.27 0.11\nv 0.71 1.19 0.93\nf 1 2 3\n");
  Mesh mesh;
  EXPECT_TRUE(MeshScene(*scene, {0}, 0.2f, 100000, &mesh).ok());
  TwinOptions t;
  t.all = true;
  t.emitters = emitters;
  AddTwins(t, &mesh);
  return mesh;
}

std::vector<PatchGeom> GeomOf(const Mesh& mesh) {
  std::vector<PatchGeom> geom(mesh.patches.size());
  for (size_t i = 0; i < geom.size(); ++i) {
    bool copy = mesh.twin[i] < i;
    geom[i] =
        copy ? TwinGeom(MakePatchGeom(mesh.patches[mesh.twin[i]])) : MakePatchGeom(mesh.patches[i]);
  }
  return geom;
}

// The twinned triangle (not emitting), its ray-test data and a grid built
// over them in an arena of its own.
struct TwinGrid {
  Scene scene;
  Mesh mesh;
  uint32_t n = 0;  // patches a side: patch i's twin is n + i
  std::vector<PatchGeom> geom;
  Arena arena{1};
  Grid grid;
};

void BuildTwinGrid(TwinGrid* t) {
  t->mesh = TwinnedTriangle(&t->scene, false);
  const uint32_t count = static_cast<uint32_t>(t->mesh.patches.size());
  t->n = count / 2;
  t->geom = GeomOf(t->mesh);
  Span<const Patch> patches(t->mesh.patches.data(), count);
  Span<const PatchGeom> g(t->geom.data(), count);
  Grid::Plan plan = Grid::MakePlan(patches, g, 4.0f);
  Arena measure = Arena::Measure();
  t->grid.Layout(measure, plan);
  t->arena = Arena(ArenaRoundUp(measure.used()));
  t->grid.Layout(t->arena, plan);
  t->grid.Build(patches, g);
}

TEST(TwoSidedTest, TwinsAreTheSameCornersReversedWithTheirOwnVertices) {
  Scene scene;
  Mesh mesh = TwinnedTriangle(&scene, false);
  const size_t n = mesh.patches.size() / 2;
  ASSERT_GT(n, 10u);
  for (size_t i = 0; i < n; ++i) {
    const Patch& p = mesh.patches[i];
    const Patch& t = mesh.patches[mesh.twin[i]];
    ASSERT_EQ(mesh.twin[i], n + i);
    ASSERT_EQ(mesh.twin[n + i], i);
    EXPECT_EQ(t.globalId, n + i);
    EXPECT_EQ(t.normal, -p.normal);
    EXPECT_EQ(t.area, p.area);
    EXPECT_EQ(t.surface, p.surface);
    EXPECT_EQ(t.ke, glm::vec3(0.0f)) << "an emitter's twin emits only with --two-sided-emitters";
    // Bit-identical corners, reversed from corner[0].
    EXPECT_EQ(t.corner[0], p.corner[0]);
    EXPECT_EQ(t.corner[1], p.corner[2]);
    EXPECT_EQ(t.corner[2], p.corner[1]);
    for (int k = 0; k < 4; ++k)
      EXPECT_GE(t.vertex[k], mesh.vertices.size() / 2) << "shares a vertex";
  }
  Scene s2;
  Mesh emitting = TwinnedTriangle(&s2, true);
  EXPECT_EQ(emitting.patches.back().ke, emitting.patches.front().ke);
}

// The geometry the tie rule relies on: a ray meets a patch and its twin at
// the same t, bit for bit, from opposite sides; and the grid lands every ray
// on the twin it faces, from either side.
TEST(TwoSidedTest, TwinsMeetARayAtTheSameTAndTheFacingOneIsHit) {
  TwinGrid t;
  BuildTwinGrid(&t);
  const Scene& scene = t.scene;
  const Mesh& mesh = t.mesh;
  const std::vector<PatchGeom>& geom = t.geom;
  const Grid& grid = t.grid;
  const uint32_t n = t.n;

  const glm::vec3 normal = mesh.patches[0].normal;
  Rng rng(7, 3);
  int hits[2] = {0, 0};
  for (int r = 0; r < 20000; ++r) {
    // A point on the triangle, seen from a random point on either side.
    float a = rng.NextFloat(), b = rng.NextFloat();
    if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
    const Polygon& poly = scene.polygons[0];
    glm::vec3 target = poly.corners[0] + a * (poly.corners[1] - poly.corners[0]) +
                       b * (poly.corners[2] - poly.corners[0]);
    const int side = r & 1;
    glm::vec3 off(rng.NextFloat() - 0.5f, rng.NextFloat() - 0.5f, rng.NextFloat() - 0.5f);
    off -= glm::dot(off, normal) * normal;  // sideways only: the side stays the side
    glm::vec3 o = target + (side ? -1.0f : 1.0f) * (0.2f + rng.NextFloat()) * normal + off;
    Ray ray{o, target - o, 0.0f, 10.0f};
    for (uint32_t i = 0; i < n; ++i) {
      float t0 = 0, t1 = 0;
      bool f0 = false, f1 = false;
      bool h0 = IntersectPatch(geom[i], ray, &t0, &f0);
      bool h1 = IntersectPatch(geom[n + i], ray, &t1, &f1);
      ASSERT_EQ(h0, h1) << "patch " << i << " ray " << r;
      if (!h0) continue;
      ASSERT_EQ(0, std::memcmp(&t0, &t1, sizeof t0)) << t0 << " " << t1;
      ASSERT_NE(f0, f1);
    }
    Hit hit;
    if (!grid.Intersect(ray, Skip(), &hit)) continue;
    ++hits[side];
    ASSERT_TRUE(hit.front) << "ray " << r << " from the " << (side ? "back" : "front")
                           << " landed on a back side (patch " << hit.patch << ")";
    ASSERT_EQ(hit.patch < n, side == 0);
  }
  EXPECT_GT(hits[0], 9000);
  EXPECT_GT(hits[1], 9000);
}

// A ray from a shooter whose lifted origin rounded behind its plane would hit
// its twin from the front: the shooter's twin is skipped with it.
TEST(TwoSidedTest, AShotSkipsItsTwin) {
  TwinGrid t;
  BuildTwinGrid(&t);
  const Grid& grid = t.grid;
  const uint32_t n = t.n, i = n / 2;
  const Patch& p = t.mesh.patches[i];
  glm::vec3 centre = (p.corner[0] + p.corner[1] + p.corner[2]) / 3.0f;
  // Just behind the plane, leaving along the normal (a tilt keeps it general).
  Ray ray{centre - 1e-4f * p.normal, p.normal + 0.1f * glm::normalize(p.corner[1] - p.corner[0]),
          0.0f, 10.0f};
  Hit hit;
  ASSERT_TRUE(grid.Intersect(ray, Skip(i), &hit));
  EXPECT_EQ(hit.patch, n + i);
  EXPECT_TRUE(hit.front);
  EXPECT_FALSE(grid.Intersect(ray, Skip(i, n + i), &hit));
  EXPECT_FALSE(grid.Occluded(ray, Skip(i, n + i)));
}

// Of two twins only the one facing the eye is drawn: one fragment a pixel,
// and the polygon is bright from both sides with --two-sided-emitters.
TEST(TwoSidedTest, OnlyTheTwinFacingTheEyeIsDrawn) {
  Scene scene;
  Mesh mesh = TwinnedTriangle(&scene, true);
  std::vector<uint32_t> ids(mesh.patches.size());
  for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
  EnvGrid grid;
  grid.box = scene.bounds;
  EnvOptions o;
  o.rayEpsilon = 1e-6f;
  Environment env;
  env.Init(grid, 0, mesh, ids, o);
  ASSERT_EQ(env.numTwins(), ids.size() / 2);
  const double ambient[3] = {0, 0, 0};
  env.ComputeVertexRadiosity(ambient);
  const glm::vec3 centre =
      (scene.polygons[0].corners[0] + scene.polygons[0].corners[1] + scene.polygons[0].corners[2]) /
      3.0f;
  for (float side : {1.0f, -1.0f}) {
    Camera cam;
    cam.eye = centre + side * 3.0f * scene.polygons[0].normal;
    cam.target = centre;
    cam.up = glm::normalize(glm::cross(scene.polygons[0].normal, glm::vec3(1, 0, 0)));
    cam.fovyDeg = 40.0f;
    View view;
    ASSERT_TRUE(MakeView(cam, 48, 48, &view));
    Arena measure = Arena::Measure();
    Framebuffer probe;
    probe.Layout(measure, 48, 48, true);
    Arena arena(ArenaRoundUp(measure.used()));
    Framebuffer fb;
    fb.Layout(arena, 48, 48, true);
    fb.Clear();
    DrawEnvironment(view, env, ambient, &fb);
    size_t covered = 0;
    for (size_t px = 0; px < fb.color.size(); ++px) {
      const Fragment* f = &fb.frags[px * kFragments];
      if (f[0].id == kNoPatch) continue;
      ++covered;
      EXPECT_EQ(f[1].id, kNoPatch) << "a second fragment (the back twin) at pixel " << px;
      EXPECT_GT(f[0].coverage, 0.0f) << "a back face drawn at pixel " << px;
    }
    Resolve(&fb);
    EXPECT_GT(covered, 100u) << "side " << side;
    size_t centrePx = 24 * 48 + 24;
    EXPECT_GT(fb.color[centrePx].x, 1.0f) << "side " << side << ": the emitter is dark";
  }
}

}  // namespace
}  // namespace vismask
