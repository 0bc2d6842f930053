// Direct light gathered per pixel (direct.h): the exact unoccluded
// irradiance and its shadow-ray samples against the closed form under a
// square emitter, and the samples' spread over two emitters by their
// shares of it; whole renders: a floor under a square emitter matches the
// closed form, lamps behind a wall bring nothing while those in view bring
// their closed form (exactly where all are in view), a hard shadow edge is
// as sharp as its geometry, the indirect part has no step at patch edges,
// a quarter of the rays gives the converged image's mean.
#include "vismask/display/direct.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "direct_test_util.h"
#include "grid_test_util.h"
#include "test_util.h"
#include "vismask/output/image_io.h"

namespace vismask {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The form factor from a point to a parallel rectangle [0, a] x [0, b] at
// height h, the point below its corner (0, 0).
double CornerFormFactor(double a, double b, double h) {
  double x = a / h, y = b / h;
  double sx = std::sqrt(1.0 + x * x), sy = std::sqrt(1.0 + y * y);
  return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0 * kPi);
}

// The same for the rectangle [x0, x1] x [z0, z1] and the point (px, pz),
// by adding and taking away rectangles with a corner above the point.
double FormFactor(double x0, double x1, double z0, double z1, double h, double px, double pz) {
  auto f = [&](double u, double v) {
    double s = (u < 0 ? -1.0 : 1.0) * (v < 0 ? -1.0 : 1.0);
    return u == 0.0 || v == 0.0 ? 0.0 : s * CornerFormFactor(std::fabs(u), std::fabs(v), h);
  };
  return f(x1 - px, z1 - pz) - f(x0 - px, z1 - pz) - f(x1 - px, z0 - pz) + f(x0 - px, z0 - pz);
}

// An emitter [-0.5, 0.5]^2 at y = 1 facing down, cut into 2 x 2 patches
// (so that the shared inner edges must cancel), Ke = (2, 1, 0.5).
gridtest::TestScene EmitterScene() {
  gridtest::TestScene s;
  gridtest::AddSubdividedQuad(1, 1.0f, -0.5f, 0.5f, -0.5f, 0.5f, -1, 2, &s);
  for (Patch& p : s.patches) p.ke = glm::vec3(2.0f, 1.0f, 0.5f);
  return s;
}

TEST(DirectTest, UnoccludedIrradianceUnderASquareEmitterIsTheClosedForm) {
  gridtest::TestScene s = EmitterScene();
  ASSERT_EQ(s.patches.size(), 4u);
  DirectLight light;
  Span<const Patch> patches(s.patches.data(), s.patches.size());
  DirectLight::Counts counts = DirectLight::Count(patches);
  EXPECT_EQ(counts.groups, 1u);
  EXPECT_EQ(counts.edges, 8u) << "the outline of 2 x 2 patches: 8 edges, the inner 8 cancel";
  EXPECT_EQ(counts.corners, 4u);
  Arena arena(64 * 1024);
  light.Layout(arena, counts);
  light.Build(patches);
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  for (float px : {0.0f, 0.3f, 0.5f, 1.2f, -2.0f})
    for (float pz : {0.0f, -0.4f, 0.9f}) {
      double f = FormFactor(-0.5, 0.5, -0.5, 0.5, 1.0, px, pz);
      glm::vec3 e = light.Unoccluded(glm::vec3(px, 0.0f, pz), up);
      EXPECT_NEAR(e.x, 2.0 * f, 1e-5 + 1e-4 * 2.0 * f) << px << "," << pz;
      EXPECT_NEAR(e.z, 0.5 * f, 1e-5 + 1e-4 * 0.5 * f) << px << "," << pz;
    }
  // Behind the emitter (above it): nothing.
  EXPECT_EQ(light.Unoccluded(glm::vec3(0.0f, 2.0f, 0.0f), -up).x, 0.0f);
}

TEST(DirectTest, ShadowSamplesAverageToTheClosedForm) {
  gridtest::TestScene s = EmitterScene();
  LitTestScene lit(s);
  const gridtest::BuiltGrid& b = lit.b;
  DirectLight& light = lit.light;
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  for (float px : {0.0f, 0.45f, 1.5f}) {
    glm::vec3 x(px, 0.0f, 0.2f);
    const uint32_t n = 4096;
    glm::dvec3 sum(0.0);
    uint32_t visible = 0;
    light.Unoccluded(x, up, light.tallies());
    for (uint32_t k = 0; k < n; ++k) {
      glm::vec3 w;
      visible += light.Sample(b.grid, kNoPatch, kNoPatch, x, up, DirectLightSample(7, k),
                              light.tallies(), 1e-4f, nullptr, &w)
                     ? 1u
                     : 0u;
      sum += glm::dvec3(w);
    }
    double f = FormFactor(-0.5, 0.5, -0.5, 0.5, 1.0, px, 0.2);
    EXPECT_EQ(visible, n) << "nothing lies between";
    EXPECT_NEAR(sum.x / n, 2.0 * f, 0.01 * 2.0 * f) << px;
    EXPECT_NEAR(sum.y / n, 1.0 * f, 0.01 * 1.0 * f) << px;
  }
}

TEST(DirectTest, SamplesGoToEachGroupByItsShareOfTheIrradianceThere) {
  // The square emitter, and a larger, brighter one higher up and aside:
  // the second has most of the power, the first about half the
  // irradiance at x.
  gridtest::TestScene s = EmitterScene();
  gridtest::AddSubdividedQuad(1, 2.0f, 1.0f, 3.0f, -1.0f, 1.0f, -1, 1, &s);
  for (size_t i = 4; i < s.patches.size(); ++i) s.patches[i].ke = glm::vec3(8.0f);
  LitTestScene lit(s);
  const gridtest::BuiltGrid& b = lit.b;
  DirectLight& light = lit.light;
  ASSERT_EQ(light.numGroups(), 2u);
  const glm::vec3 up(0.0f, 1.0f, 0.0f), x(0.2f, 0.0f, -0.3f);
  const Span<DirectLight::Tally> tally = light.tallies();
  const glm::vec3 e0 = light.Unoccluded(x, up, tally);
  // The groups' parts add up to the whole, and the first's share of it
  // (channels summed) is where the cumulative shares split.
  const glm::vec3 parts = tally[0].e0 + tally[1].e0;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(parts[c], e0[c], 1e-5 * e0[c]);
  const float first = (tally[0].e0.x + tally[0].e0.y + tally[0].e0.z) / (e0.x + e0.y + e0.z);
  EXPECT_NEAR(tally[0].cdf, first, 1e-6);
  EXPECT_EQ(tally[1].cdf, 1.0f);
  ASSERT_GT(first, 0.2f);
  ASSERT_LT(first, 0.8f);
  const uint32_t n = 4096;
  uint32_t drawn[2] = {0, 0};
  glm::dvec3 sum(0.0);
  for (uint32_t k = 0; k < n; ++k) {
    glm::vec3 w;
    uint32_t source = 2;
    light.Sample(b.grid, kNoPatch, kNoPatch, x, up, DirectLightSample(5, k), tally, 1e-4f, nullptr,
                 &w, 0.0f, &source);
    ASSERT_LT(source, 2u);
    ++drawn[source];
    sum += glm::dvec3(w);
  }
  // Halton points: the counts are the shares to within a couple of samples.
  EXPECT_NEAR(drawn[0], n * first, 2.0);
  // The weights average to the unoccluded irradiance.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / n, e0[c], 0.01 * e0[c]) << c;
}

// --- whole renders --------------------------------------------------------------

// A floor [-10, 10]^2 at y = 0 (Kd 0.5, facing up), a square emitter of side
// `side` centred above the origin at height `height` facing down (Kd 0,
// Ke 10), and optionally a black occluder over x < 0 at height `occluder`
// facing up (so the floor sees its back, which absorbs). The emitter may be
// moved to x = `emitterX`.
void WriteFloorScene(const std::string& dir, double side, double height, double occluder,
                     double emitterX = 0.0) {
  std::ostringstream obj;
  double h = side / 2, x0 = emitterX - h, x1 = emitterX + h;
  obj << "mtllib s.mtl\n"
      << "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n"
      << "v " << x0 << " " << height << " " << -h << "\nv " << x1 << " " << height << " " << -h
      << "\nv " << x1 << " " << height << " " << h << "\nv " << x0 << " " << height << " " << h
      << "\n"
      << "v -10 " << occluder << " -10\nv 0 " << occluder << " -10\nv 0 " << occluder
      << " 10\nv -10 " << occluder << " 10\n"
      << "usemtl floor\nf 1 4 3 2\n"
      << "usemtl light\nf 5 6 7 8\n";
  if (occluder > 0) obj << "usemtl black\nf 9 12 11 10\n";
  test::WriteFile(dir + "/s.obj", obj.str());
  test::WriteFile(dir + "/s.mtl",
                  "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n"
                  "newmtl black\nKd 0 0 0\n");
}

TEST(DirectTest, FloorUnderASquareEmitterMatchesTheClosedForm) {
  test::TempDir dir;
  WriteFloorScene(dir.path(), 1.0, 1.0, 0.0);
  const int n = 32;
  PfmImage img = RenderDown(dir, n, "--aa off --direct-samples 8 --patch-size 2");
  ASSERT_EQ(img.width, n);
  // Pixel (i, j) sees the floor point 0.5 * ((i + 0.5) / n * 2 - 1) along
  // each axis (the signs do not matter: the emitter is symmetric).
  double worst = 0.0;
  for (int j = 0; j < n; j += 5)
    for (int i = 0; i < n; i += 3) {
      double u = 0.5 * ((i + 0.5) / n * 2.0 - 1.0), v = 0.5 * ((j + 0.5) / n * 2.0 - 1.0);
      double expect = 0.5 * 10.0 * FormFactor(-0.5, 0.5, -0.5, 0.5, 1.0, u, v) / kPi;
      worst = std::max(worst, std::fabs(Pixel(img, i, j) / expect - 1.0));
    }
  EXPECT_LT(worst, 0.01) << "the floor's radiance: kd E / pi, E the closed form";
}

// Four small lamps over the floor seen (symmetric about both axes, so the
// image's orientation does not matter) and six larger, brighter ones
// behind the wall at x = 1: those bring most of the power and a good part
// of the unoccluded irradiance at the floor seen, and none of its light.
std::vector<Lamp> HiddenLamps() {
  std::vector<Lamp> lamps;
  for (double x : {-0.4, 0.4})
    for (double z : {-0.4, 0.4}) lamps.push_back({x, 0.8, z, 0.3, 10.0});
  for (double x : {1.8, 2.4})
    for (double z : {-1.2, 0.0, 1.2}) lamps.push_back({x, 1.2, z, 0.5, 20.0});
  return lamps;
}

TEST(DirectTest, LampsBehindAWallBringNothingAndTheOthersTheirClosedForm) {
  test::TempDir dir;
  const std::vector<Lamp> lamps = HiddenLamps();
  WriteLampsScene(dir.path(), lamps);
  const int n = 32;
  PfmImage img = RenderDown(dir, n, "--aa off --direct-samples 32 --patch-size 2");
  ASSERT_EQ(img.width, n);
  // Pixel (i, j) sees the floor point 0.5 * ((i + 0.5) / n * 2 - 1) along
  // each axis (up to the signs, which the near lamps' symmetry makes moot):
  // its radiance is kd / pi times the near lamps' irradiance. A lamp in
  // full view or hidden counts exactly once it draws samples; one that
  // draws less than one in expectation counts by what its samples bring
  // (the worst pixels), so the bound on one pixel is looser than on all.
  double worst = 0.0, sum2 = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double u = 0.5 * ((i + 0.5) / n * 2.0 - 1.0), v = 0.5 * ((j + 0.5) / n * 2.0 - 1.0);
      double e = 0.0;
      for (const Lamp& l : lamps) {
        if (l.x > 1.0) continue;
        const double h = l.side / 2;
        e += l.ke * FormFactor(l.x - h, l.x + h, l.z - h, l.z + h, l.y, u, v);
      }
      const double error = Pixel(img, i, j) / (0.5 * e / kPi) - 1.0;
      worst = std::max(worst, std::fabs(error));
      sum2 += error * error;
    }
  EXPECT_LT(std::sqrt(sum2 / (n * n)), 0.01) << "the relative RMS error, 32 shadow rays a pixel";
  EXPECT_LT(worst, 0.05) << "the worst pixel's relative error";
}

TEST(DirectTest, LampsAllInViewGiveTheirClosedFormExactly) {
  // The four near lamps and six far ones, all on the near side of the
  // wall: every shadow ray reaches its lamp, so every pixel is the closed
  // form (to float rounding), the far lamps' few samples notwithstanding.
  test::TempDir dir;
  std::vector<Lamp> lamps = HiddenLamps();
  for (Lamp& l : lamps)
    if (l.x > 1.0) l.x = -l.x - 1.0;
  WriteLampsScene(dir.path(), lamps);
  const int n = 16;
  PfmImage img = RenderDown(dir, n, "--aa off --direct-samples 32 --patch-size 2");
  ASSERT_EQ(img.width, n);
  // Pixel (i, j) sees the floor point (-u, 0, -v), u and v as in the other
  // floor tests (the image's right is -x, its top +z).
  double worst = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = 0.5 * ((i + 0.5) / n * 2.0 - 1.0), v = 0.5 * ((j + 0.5) / n * 2.0 - 1.0);
      double e = 0.0;
      for (const Lamp& l : lamps) {
        const double h = l.side / 2;
        e += l.ke * FormFactor(l.x - h, l.x + h, l.z - h, l.z + h, l.y, -u, -v);
      }
      worst = std::max(worst, std::fabs(Pixel(img, i, j) / (0.5 * e / kPi) - 1.0));
    }
  EXPECT_LT(worst, 1e-3);
}

TEST(DirectTest, HardShadowEdgeIsAsSharpAsItsGeometry) {
  test::TempDir dir;
  // A 0.1 emitter at height 3, the occluder's edge (x = 0) at 1.5: the
  // penumbra on the floor is 0.1 wide (a linear ramp across the square
  // emitter), its 10%-90% part 0.08: 10.2 pixels of 128 over the 1.0 seen.
  WriteFloorScene(dir.path(), 0.1, 3.0, 1.5);
  const int n = 128;
  const double geometric = 0.08 * n;
  PfmImage direct = RenderDown(dir, n, "--direct-samples 32");
  PfmImage solved = RenderDown(dir, n, "--direct-samples 0");
  double wDirect = 0.0, wSolved = 0.0;
  for (int y : {20, 64, 100}) {
    wDirect = std::max(wDirect, std::fabs(EdgeWidth(direct, y) - geometric));
    wSolved = std::max(wSolved, std::fabs(EdgeWidth(solved, y) - geometric));
  }
  EXPECT_LT(wDirect, 1.5) << "the 10-90% width, off its geometric " << geometric << " px";
  // The solved radiosity alone cannot draw it (the test tells them apart).
  EXPECT_GT(wSolved, 2.0);
}

TEST(DirectTest, AShadowEdgeIsBoxFilteredWherePiecesSplitThePixel) {
  test::TempDir dir;
  // A 0.002 emitter at height 3 above x = -0.05, the occluder's edge
  // (x = 0) at 1.5: a step on the floor at x = 0.05 (clear of the patches'
  // and elements' edges, at multiples of 20/53/16 from x = 0), an eighth of
  // a pixel wide, placed 0.45 of the way into pixel column 32 (the floor
  // beyond it, left of it, lit; not 0.5, where a piece's centroid would sit
  // on the step, nor under 0.4, where the adaptive gather's first four
  // samples may all miss the lit part). The patches and elements cut the
  // floor along rows that cross some pixels: there the pixel is covered by
  // two pieces, each over part of it. Box-filtered, every row's pixel 32 is
  // 0.45 of the way from dark to lit, to the samples' noise.
  WriteFloorScene(dir.path(), 0.002, 3.0, 1.5, -0.05);
  const int n = 64;
  PfmImage img = RenderDown(dir, n, "--patch-size 0.377358 --emitted-rays 200000", 0.05 + 0.45 / n);
  double worst = 0.0;
  int worstRow = -1;
  for (int y = 2; y < n - 2; ++y) {
    const double lit = Pixel(img, 28, y), dark = Pixel(img, 36, y);
    ASSERT_GT(lit - dark, 0.0) << "row " << y;
    const double v = (Pixel(img, 32, y) - dark) / (lit - dark);
    if (std::fabs(v - 0.45) > worst) worst = std::fabs(v - 0.45), worstRow = y;
  }
  EXPECT_LT(worst, 0.15) << "row " << worstRow;
}

TEST(DirectTest, IndirectPartHasNoStepAtPatchEdges) {
  // The Cornell box's ceiling gets no direct light (the light faces down):
  // what the image shows there is the indirect part alone, interpolated
  // across patches; along a row no step between neighbouring pixels is
  // more than a few percent of the row's mean, while the patches (20
  // units, about 6 pixels here) differ by their Monte Carlo noise.
  test::TempDir dir;
  std::vector<std::string> args = {"render",         "scenes/cornell.obj",
                                   "--out",          dir.path(),
                                   "--camera",       "278,273,-800,278,273,0,0,1,0,39.3076",
                                   "--width",        "128",
                                   "--height",       "128",
                                   "--emitted-rays", "1000000",
                                   "--quiet"};
  test::RunResult r = test::RunMain(args);
  ASSERT_EQ(r.code, 0) << r.err;
  PfmImage img;
  ASSERT_TRUE(ReadPfm(dir.File("image.pfm"), &img).ok());
  for (int y : {6, 10}) {
    double sum = 0.0, worst = 0.0;
    for (int x = 30; x < 98; ++x) sum += Pixel(img, x, y);
    double mean = sum / 68.0;
    ASSERT_GT(mean, 0.0);
    for (int x = 31; x < 98; ++x)
      worst = std::max(worst, std::fabs(Pixel(img, x, y) - Pixel(img, x - 1, y)) / mean);
    EXPECT_LT(worst, 0.03) << "row " << y;
  }
}

TEST(DirectTest, ExportIsTheSolvedWhole) {
  // The export keeps the view-independent solution: the same bytes with
  // per-pixel direct light as without, while the images differ (with
  // --emission-rays 1, the same rays; below 1 the light traces fewer).
  test::TempDir dir;
  std::string glb[2], image[2];
  for (int k = 0; k < 2; ++k) {
    std::vector<std::string> args = {"render",
                                     "scenes/cornell.obj",
                                     "--out",
                                     dir.File("out" + std::to_string(k)),
                                     "--width",
                                     "48",
                                     "--height",
                                     "48",
                                     "--quiet",
                                     "--emitted-rays",
                                     "200000",
                                     "--export",
                                     dir.File("c" + std::to_string(k) + ".glb"),
                                     "--emission-rays",
                                     "1",
                                     "--direct-samples",
                                     k == 0 ? "0" : "32"};
    test::RunResult r = test::RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    glb[k] = test::ReadFile(dir.File("c" + std::to_string(k) + ".glb"));
    image[k] = test::ReadFile(dir.File("out" + std::to_string(k) + "/image.pfm"));
  }
  EXPECT_FALSE(glb[0].empty());
  EXPECT_EQ(glb[0], glb[1]);
  EXPECT_NE(image[0], image[1]);
}

double Mean(const PfmImage& img) {
  double s = 0.0;
  for (float v : img.pixels) s += v;
  return s / static_cast<double>(img.pixels.size());
}

TEST(DirectTest, AQuarterOfTheRaysGivesTheConvergedMean) {
  // The image at any moment carries the best estimate of what is not yet
  // shown: the direct part whole, the rest as the ambient term. A quarter
  // of the rays (the solve's time is its rays: a quarter of its time,
  // without depending on the machine) gives the converged image's mean
  // within 5%. (Without per-pixel direct light, 22% too bright here.)
  test::TempDir dir;
  auto render = [&](const std::string& extra, PfmImage* img, std::string* json) {
    std::vector<std::string> args = {
        "render", "scenes/cornell.obj", "--out",  dir.path(), "--width", "64", "--height",
        "64",     "--emitted-rays",     "400000", "--quiet"};
    for (const std::string& w : test::Words(extra)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_TRUE(ReadPfm(dir.File("image.pfm"), img).ok());
    *json = test::ReadFile(dir.File("run.json"));
  };
  PfmImage done, quarter;
  std::string json;
  render("", &done, &json);
  const long rays = static_cast<long>(test::JsonNumber(json, "rays"));
  ASSERT_GT(rays, 100000);
  render("--ray-budget " + std::to_string(rays / 4), &quarter, &json);
  EXPECT_NEAR(Mean(quarter) / Mean(done), 1.0, 0.05);
}

TEST(DirectTest, EmissionTracesItsShareOfTheRays) {
  // --emission-rays F: the light's own emission traces F of the rays its
  // power is worth, the reflected power all of them; without per-pixel
  // direct light (whose image would show that noise) all of them, the
  // same solve as F = 1. Defaults: 0.125 with direct light (in several
  // environments where their pixels gather every emitter), else 1.
  test::TempDir dir;
  auto run = [&](const std::string& extra, std::string* json) {
    std::vector<std::string> args = {
        "render",  "scenes/cornell.obj", "--out", dir.path(), "--width", "16", "--height", "16",
        "--quiet", "--emitted-rays",     "200000"};
    for (const std::string& w : test::Words(extra)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    *json = test::ReadFile(dir.File("run.json"));
    return test::JsonNumber(*json, "rays");
  };
  std::string json;
  const double all = run("--emission-rays 1", &json);
  const double quarter = run("--emission-rays 0.25", &json);
  EXPECT_NE(json.find("\"emission_rays\": 0.25"), std::string::npos);
  EXPECT_NEAR((all - quarter) / (0.75 * 200000.0), 1.0, 0.05) << all << " " << quarter;
  EXPECT_EQ(run("--emission-rays 0.25 --direct-samples 0", &json),
            run("--direct-samples 0", &json));
  EXPECT_EQ(run("--direct-samples 0", &json), all);
  EXPECT_NE(json.find("\"emission_rays\": 1,"), std::string::npos);
  // The default, an eighth.
  std::string given;
  const double eighth = run("--emission-rays 0.125", &given);
  EXPECT_LT(eighth, quarter);
  EXPECT_EQ(run("", &json), eighth);
  EXPECT_NE(json.find("\"emission_rays\": 0.125"), std::string::npos);
  // Several environments: an eighth too where their pixels gather every
  // environment's emitters (--foreign-mask-res, the default), else 1.
  run("--envs 2", &json);
  EXPECT_NE(json.find("\"emission_rays\": 0.125"), std::string::npos);
  run("--envs 2 --foreign-mask-res 0", &json);
  EXPECT_NE(json.find("\"emission_rays\": 1,"), std::string::npos);
}

TEST(DirectTest, MaxSecondsPlansTheEmittedRays) {
  // --max-seconds without --emitted-rays: fewer than the default, from the
  // rate timed at init, and run.json says so; given, they are kept.
  test::TempDir dir;
  auto json = [&](const std::string& extra) {
    std::vector<std::string> args = {
        "render",  "scenes/cornell.obj", "--out", dir.path(), "--width", "16", "--height", "16",
        "--quiet", "--max-seconds",      "0.5"};
    for (const std::string& w : test::Words(extra)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    return test::ReadFile(dir.File("run.json"));
  };
  std::string planned = json("");
  EXPECT_NE(planned.find("\"emitted_rays_planned\": true"), std::string::npos);
  const double rays = test::JsonNumber(planned, "emitted_rays", "options");
  EXPECT_GE(rays, 10000);
  EXPECT_LT(rays, 4000000);
  std::string given = json("--emitted-rays 300000");
  EXPECT_EQ(given.find("emitted_rays_planned"), std::string::npos);
  EXPECT_NE(given.find("\"emitted_rays\": 300000,"), std::string::npos);
}

TEST(DirectTest, MaxSecondsPlansThePatchSize) {
  // A budget far too short for the automatic mesh's tail of small shots
  // (some 7 500 patches; 10 ms is a few hundred patches' tail on any
  // machine): init meshes again with larger patches, run.json says so, and
  // the loader's warnings are said once. Given, the patch size is kept.
  test::TempDir dir;
  // The Cornell box with one face of a material no MTL defines (a warning).
  std::string obj = test::ReadFile("scenes/cornell.obj");
  const size_t at = obj.find("usemtl white");
  ASSERT_NE(at, std::string::npos);
  test::WriteFile(dir.File("box.obj"), obj.replace(at, 12, "usemtl nosuch"));
  test::WriteFile(dir.File("cornell.mtl"), test::ReadFile("scenes/cornell.mtl"));
  auto run = [&](const std::string& extra, std::string* err) {
    std::vector<std::string> args = {
        "render",  dir.File("box.obj"), "--out", dir.File("out"), "--width", "16", "--height", "16",
        "--quiet", "--max-seconds",     "0.01"};
    for (const std::string& w : test::Words(extra)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    *err = r.err;
    return test::ReadFile(dir.File("out/run.json"));
  };
  std::string err, auto_json = run("", &err), plain;
  auto patchSize = [](const std::string& json) {
    size_t at = json.find("\"patch_size\": ");
    return at == std::string::npos ? 0.0 : std::atof(json.c_str() + at + 14);
  };
  EXPECT_NE(auto_json.find("\"patch_size_planned\": true"), std::string::npos);
  const std::string auto_given = run("--patch-size 19.9714298", &plain);
  EXPECT_EQ(auto_given.find("patch_size_planned"), std::string::npos);
  EXPECT_GT(patchSize(auto_json), 1.5 * patchSize(auto_given));
  // The undefined material's warning: once, as without the plan.
  auto count = [](const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_GE(count(plain, "warning"), 1u) << plain;
  EXPECT_EQ(count(err, "warning"), count(plain, "warning")) << err;
}

// The per-pixel sequences read from tables give DirectLightSample's and
// DirectPixelOffset's floats, bit for bit, in the tables and past them.
TEST(DirectTest, PixelSequencesAreThePerSampleOnes) {
  for (uint32_t pixel : {0u, 1u, 511u, 262143u, 4000000000u}) {
    const DirectPixelSequence light(pixel, DirectPixelSequence::Kind::kLight);
    const DirectPixelSequence offset(pixel, DirectPixelSequence::Kind::kOffset);
    for (uint32_t k = 0; k < DirectPixelSequence::kTabled + 200; ++k) {
      const glm::vec2 a = light(k), b = DirectLightSample(pixel, k);
      const glm::vec2 c = offset(k), d = DirectPixelOffset(pixel, k);
      ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0) << pixel << " " << k;
      ASSERT_EQ(std::memcmp(&c, &d, sizeof c), 0) << pixel << " " << k;
    }
  }
}

// A piece covering part of a pixel gathers N x its coverage, rounded up,
// at least kMinPartSamples (N itself when N is fewer); a whole pixel N.
TEST(DirectTest, APieceCoveringPartOfAPixelGathersItsShare) {
  EXPECT_EQ(PartSamples(128, 1.0f), 128u);
  EXPECT_EQ(PartSamples(128, 0.5f), 64u);
  EXPECT_EQ(PartSamples(128, 0.26f), 34u);  // 33.28 up
  EXPECT_EQ(PartSamples(128, 0.01f), kMinPartSamples);
  EXPECT_EQ(PartSamples(4, 0.01f), 4u);
  EXPECT_EQ(PartSamples(128, 0.0f), kMinPartSamples);
  EXPECT_EQ(PartSamples(128, 1.5f), 128u);  // never more than N
  uint32_t last = 0;
  for (int i = 1; i <= 100; ++i) {
    const uint32_t s = PartSamples(200, 0.01f * static_cast<float>(i));
    EXPECT_GE(s, last);
    EXPECT_GE(static_cast<float>(s), 200.0f * 0.01f * static_cast<float>(i) - 1e-3f);
    last = s;
  }
}

}  // namespace
}  // namespace vismask
