// Two-sided scenes (--two-sided, --two-sided-emitters: mesh.h's twins) and
// the emitter check (emitter_check.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <glm/geometric.hpp>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/camera.h"
#include "vismask/display.h"
#include "vismask/emitter_check.h"
#include "vismask/environment.h"
#include "vismask/grid.h"
#include "vismask/image_io.h"
#include "vismask/mesh.h"
#include "vismask/rng.h"
#include "vismask/scene.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;

const char kMtl[] =
    "newmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\n"
    "newmtl white\nKd 0.7 0.7 0.7\n";

Scene LoadText(const std::string& obj, const std::string& name = "test.obj") {
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadSceneFromText(
      name, "mtllib test.mtl\n" + obj,
      [](const std::string&, std::string* text) {
        *text = kMtl;
        return std::string();
      },
      &scene, &warnings);
  EXPECT_TRUE(s.ok()) << s.ToString();
  return scene;
}

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
  Scene scene;
  Mesh mesh = TwinnedTriangle(&scene, false);
  const uint32_t count = static_cast<uint32_t>(mesh.patches.size()), n = count / 2;
  std::vector<PatchGeom> geom = GeomOf(mesh);
  Span<const Patch> patches(mesh.patches.data(), count);
  Span<const PatchGeom> g(geom.data(), count);
  Grid::Plan plan = Grid::MakePlan(patches, g, 4.0f);
  Grid grid;
  Arena measure = Arena::Measure();
  grid.Layout(measure, plan);
  Arena arena(ArenaRoundUp(measure.used()));
  grid.Layout(arena, plan);
  grid.Build(patches, g);

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
  Scene scene;
  Mesh mesh = TwinnedTriangle(&scene, false);
  const uint32_t count = static_cast<uint32_t>(mesh.patches.size()), n = count / 2;
  std::vector<PatchGeom> geom = GeomOf(mesh);
  Span<const Patch> patches(mesh.patches.data(), count);
  Span<const PatchGeom> g(geom.data(), count);
  Grid::Plan plan = Grid::MakePlan(patches, g, 4.0f);
  Grid grid;
  Arena measure = Arena::Measure();
  grid.Layout(measure, plan);
  Arena arena(ArenaRoundUp(measure.used()));
  grid.Layout(arena, plan);
  grid.Build(patches, g);
  const uint32_t i = n / 2;
  const Patch& p = mesh.patches[i];
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

// Mean radiance (channels summed) of image rows [y0, y1) x columns [x0, x1).
double Region(const PfmImage& im, int y0, int y1, int x0, int x1) {
  double sum = 0.0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c) sum += im.pixels[(size_t(y) * im.width + x) * 3 + c];
  return sum / ((y1 - y0) * (x1 - x0));
}

// scenes/miswound.obj: the Cornell box with the floor, the back wall and the
// green wall wound the wrong way. One-sided they are black; two-sided they
// look as in the correctly wound box.
TEST(TwoSidedTest, MiswoundWallsAreBlackOneSidedAndLitTwoSided) {
  TempDir dir;
  auto render = [&](const std::string& scene, const std::string& name, bool twoSided) {
    std::vector<std::string> args = {"render",         scene,    "--out",         dir.File(name),
                                     "--width",        "64",     "--height",      "64",
                                     "--emitted-rays", "300000", "--stop-unshot", "1e-2",
                                     "--quiet",        "--view", "front"};
    // (--view front: by default the camera would look at the mis-wound box
    // from the side its wrong-way faces front, below.)
    if (twoSided) args.push_back("--two-sided");
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err, "") << "no warning for these scenes";
    PfmImage im;
    EXPECT_TRUE(ReadPfm(dir.File(name + "/image.pfm"), &im).ok());
    return im;
  };
  PfmImage good = render("scenes/cornell.obj", "cornell", false);
  PfmImage one = render("scenes/miswound.obj", "one", false);
  PfmImage two = render("scenes/miswound.obj", "two", true);
  struct Wall {
    const char* name;
    int y0, y1, x0, x1;
  };
  for (const Wall& w : {Wall{"floor", 58, 62, 26, 34}, Wall{"back wall", 14, 22, 28, 36},
                        Wall{"green wall", 20, 40, 58, 62}}) {
    double ref = Region(good, w.y0, w.y1, w.x0, w.x1);
    ASSERT_GT(ref, 0.01) << w.name;
    EXPECT_LT(Region(one, w.y0, w.y1, w.x0, w.x1), 1e-3 * ref) << w.name << " is lit one-sided";
    EXPECT_NEAR(Region(two, w.y0, w.y1, w.x0, w.x1), ref, 0.1 * ref) << w.name;
  }
  std::string json = ReadFile(dir.File("two/run.json"));
  EXPECT_NE(json.find("\"two_sided\": true"), std::string::npos);
  EXPECT_NE(json.find("\"twin_patches\": "), std::string::npos);
  // A one-sided run.json is as before: no two-sided keys.
  EXPECT_EQ(ReadFile(dir.File("one/run.json")).find("two_sided"), std::string::npos);
}

// run.json's energy triple `key`.
std::vector<double> Triple(const std::string& json, const std::string& key) {
  size_t at = json.find("\"" + key + "\": [");
  std::vector<double> v;
  if (at == std::string::npos) return v;
  const char* p = json.c_str() + json.find('[', at) + 1;
  for (int c = 0; c < 3; ++c) {
    char* end = nullptr;
    v.push_back(std::strtod(p, &end));
    p = end + 1;
  }
  return v;
}

// The ledger closes with both sides receiving and both sides of the light
// emitting, in one environment and across two with Method R (whose ledger
// books its power in flight exactly).
TEST(TwoSidedTest, LedgerClosesTwoSided) {
  TempDir dir;
  for (std::vector<std::string> extra :
       // --round-shots 1: draining to exactly 0 with rounds by work runs for
       // minutes (over a million shots; open issue, see the issue 20 report).
       {std::vector<std::string>{},
        std::vector<std::string>{"--envs", "2", "--mask-method", "R", "--stop-unshot", "0",
                                 "--round-shots", "1"}}) {
    std::vector<std::string> args = {"render",
                                     "scenes/miswound.obj",
                                     "--out",
                                     dir.File("out"),
                                     "--width",
                                     "32",
                                     "--height",
                                     "32",
                                     "--emitted-rays",
                                     "200000",
                                     "--stop-unshot",
                                     "1e-2",
                                     "--quiet",
                                     "--two-sided",
                                     "--two-sided-emitters",
                                     "--max-rays",
                                     "1024"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    std::string json = ReadFile(dir.File("out/run.json"));
    std::vector<double> emitted = Triple(json, "emitted"), residual = Triple(json, "residual");
    ASSERT_EQ(residual.size(), 3u);
    for (int c = 0; c < 3; ++c)
      EXPECT_LT(std::fabs(residual[c]), 1e-9 * emitted[c])
          << "channel " << c << ", " << extra.size() << " extra options";
  }
}

// --two-sided-emitters: each side emits Ke, twice the one-sided power; with
// --two-sided alone an emitter's back reflects but does not emit.
TEST(TwoSidedTest, TwoSidedEmittersDoubleTheEmittedPower) {
  TempDir dir;
  auto emitted = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "render", "scenes/cornell.obj", "--out", dir.File(name), "--width", "16", "--height",
        "16",     "--max-shots",        "10",    "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    return Triple(ReadFile(dir.File(name + "/run.json")), "emitted");
  };
  std::vector<double> one = emitted("one", {});
  std::vector<double> both = emitted("both", {"--two-sided-emitters"});
  std::vector<double> all = emitted("all", {"--two-sided", "--two-sided-emitters"});
  std::vector<double> backs = emitted("backs", {"--two-sided"});
  ASSERT_EQ(one.size(), 3u);
  ASSERT_EQ(both.size(), 3u);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(one[c], 0.0);
    EXPECT_DOUBLE_EQ(both[c], 2.0 * one[c]);
    EXPECT_DOUBLE_EQ(all[c], 2.0 * one[c]);
    EXPECT_DOUBLE_EQ(backs[c], one[c]);
  }
}

// footprint shows what the twins cost: patches doubled, and the bytes.
TEST(TwoSidedTest, FootprintShowsTheCost) {
  auto fp = [](std::vector<std::string> extra) {
    std::vector<std::string> args = {"footprint", "scenes/cornell.obj", "--json", "--envs", "2"};
    args.insert(args.end(), extra.begin(), extra.end());
    testing::internal::CaptureStdout();
    auto r = RunMain(args);
    std::string out = testing::internal::GetCapturedStdout();
    EXPECT_EQ(r.code, 0) << r.err;
    return out;
  };
  auto number = [](const std::string& json, const std::string& key) {
    size_t at = json.find("\"" + key + "\": ");
    EXPECT_NE(at, std::string::npos) << key;
    return std::strtoll(json.c_str() + at + key.size() + 4, nullptr, 10);
  };
  std::string one = fp({}), two = fp({"--two-sided"});
  EXPECT_EQ(number(one, "twin_patches"), 0);
  EXPECT_EQ(number(one, "extra_bytes"), 0);
  EXPECT_EQ(number(two, "patches"), 2 * number(two, "one_sided_patches"));
  EXPECT_EQ(number(two, "twin_patches"), number(two, "one_sided_patches"));
  EXPECT_EQ(number(two, "one_sided_total_bytes"), number(one, "total_bytes"));
  EXPECT_GT(number(two, "extra_bytes"), 0);
  EXPECT_EQ(number(two, "total_bytes") - number(two, "one_sided_total_bytes"),
            number(two, "extra_bytes"));
}

// The furnished-room case: a ceiling light wound to face the ceiling it
// hangs under sends nearly all its power into it.
const char kLightUnderCeiling[] =
    "usemtl white\n"
    "v 0 0 0\nv 100 0 0\nv 100 0 100\nv 0 0 100\nf 1 4 3 2\n"  // floor, facing up
    "v 0 5 0\nv 0 5 100\nv 100 5 100\nv 100 5 0\nf 5 8 7 6\n"  // ceiling, facing down
    "usemtl light\n"
    "v 49 4.95 49\nv 51 4.95 49\nv 51 4.95 51\nv 49 4.95 51\n"
    "f 9 12 11 10\n";  // line 18 (after mtllib): facing up

TEST(EmitterCheckTest, WarnsForALightFacingTheCeilingAbove) {
  Scene scene = LoadText(kLightUnderCeiling, "room.obj");
  std::vector<std::string> w = EmitterWarnings(scene);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].rfind("room.obj:18: warning: emitter 'light' sends ", 0), 0u) << w[0];
  EXPECT_NE(w[0].find("into a surface"), std::string::npos) << w[0];
  std::vector<EmitterEstimate> e = EstimateEmitters(scene);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_GT(e[0].nearShare, 0.95);
  EXPECT_GE(e[0].nearDistance, 0.05);  // the gap, along cosine-weighted rays
  EXPECT_LE(e[0].nearDistance, 0.2);
  // Wound the right way (facing down at the floor), it is silent.
  std::string fixed = kLightUnderCeiling;
  fixed.replace(fixed.find("f 9 12 11 10"), 12, "f 9 10 11 12");
  EXPECT_TRUE(EmitterWarnings(LoadText(fixed, "room.obj")).empty());
  // Without the ceiling, facing up, it lights nothing while its back faces
  // the floor.
  std::string open = kLightUnderCeiling;
  open.replace(open.find("f 5 8 7 6\n"), 10, "");
  std::vector<std::string> w2 = EmitterWarnings(LoadText(open, "room.obj"));
  ASSERT_EQ(w2.size(), 1u);
  EXPECT_NE(w2[0].find("straight out of the scene"), std::string::npos) << w2[0];
}

// The render prints it (one line, at init) and carries on.
TEST(EmitterCheckTest, RenderWarnsOnceOnStderr) {
  TempDir dir;
  test::WriteFile(dir.File("room.obj"), std::string("mtllib room.mtl\n") + kLightUnderCeiling);
  test::WriteFile(dir.File("room.mtl"), kMtl);
  auto r = RunMain({"render", dir.File("room.obj"), "--out", dir.File("out"), "--width", "16",
                    "--height", "16", "--max-shots", "5", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.rfind(dir.File("room.obj") + ":18: warning: emitter 'light'", 0), 0u) << r.err;
  // One line for the emitter; the image it leaves unlit gets the black-image
  // warning (the camera's, issue 16 item 8) as the only other line.
  size_t eol = r.err.find('\n');
  ASSERT_NE(eol, std::string::npos);
  EXPECT_EQ(r.err.find("emitter"), r.err.rfind("emitter 'light'")) << r.err;
  EXPECT_EQ(r.err.substr(eol + 1).rfind("vismask: warning: the image is black", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find('\n', eol + 1), r.err.size() - 1) << "two lines: " << r.err;
}

// The scenes that ship stay silent: the Cornell box's light hangs just below
// the ceiling facing down; the stiff boxes are closed; the extreme scenes
// are open on purpose (their lights' backs face nothing either).
TEST(EmitterCheckTest, ShippedScenesAreSilent) {
  std::vector<std::string> scenes = {"scenes/cornell.obj", "scenes/miswound.obj"};
  for (const char* rho : {"0.5", "0.9", "0.99", "0.999"})
    scenes.push_back(std::string("scenes/stiff/box-rho") + rho + ".obj");
  for (const char* name :
       {"grazing", "one-patch", "sliver", "cornell-on-plane", "cornell-ke1e-6", "cornell-ke1e30",
        "cornell-moved1e6", "cornell-scale1e-3", "cornell-scale1e6"})
    scenes.push_back(std::string("scenes/extreme/") + name + ".obj");
  for (const std::string& path : scenes) {
    Scene scene;
    Status s = LoadScene(path, &scene);
    ASSERT_TRUE(s.ok()) << s.ToString();
    std::vector<std::string> w = EmitterWarnings(scene);
    EXPECT_TRUE(w.empty()) << path << ": " << (w.empty() ? "" : w[0]);
    EXPECT_FALSE(EstimateEmitters(scene).empty()) << path;
  }
}

}  // namespace
}  // namespace vismask

// The emitter check's rays a polygon: all of them up to the budget's share,
// then fewer, never below the floor, so that a scene of very many emitting
// faces is checked in bounded time before init can refuse it.
TEST(EmitterCheckTest, RaysPerPolygonShrinkWithinTheBudget) {
  EXPECT_EQ(vismask::EmitterCheckRays(0), vismask::kEmitterCheckRays);
  EXPECT_EQ(vismask::EmitterCheckRays(1), vismask::kEmitterCheckRays);
  EXPECT_EQ(vismask::EmitterCheckRays(vismask::kEmitterCheckRayBudget / vismask::kEmitterCheckRays),
            vismask::kEmitterCheckRays);
  EXPECT_EQ(
      vismask::EmitterCheckRays(2 * vismask::kEmitterCheckRayBudget / vismask::kEmitterCheckRays),
      vismask::kEmitterCheckRays / 2);
  EXPECT_EQ(vismask::EmitterCheckRays(300000), vismask::kEmitterCheckMinRays);
  for (uint64_t n : {1ull, 100ull, 5000ull, 40000ull, 300000ull})
    EXPECT_LE(
        uint64_t(vismask::EmitterCheckRays(n)) * n,
        std::max<uint64_t>(vismask::kEmitterCheckRayBudget, vismask::kEmitterCheckMinRays * n));
}
