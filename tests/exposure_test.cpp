// The exposed share of a leaf (Environment::MeasureExposure): a floor that
// runs on under a block standing on it is dark beneath, and its patches
// straddling the block's foot show their power over the exposed part only,
// so the floor beside the block is as bright as where the floor stops at
// the block.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "env_test_util.h"
#include "grid_test_util.h"
#include "test_util.h"
#include "vismask/output/image_io.h"
#include "vismask/solve/element_tree.h"

namespace vismask {
namespace {

// An OBJ file's text in material white (s.mtl), one quad face a call
// (its corners in order).
struct ObjQuads {
  std::string text = "mtllib s.mtl\nusemtl white\n";
  int next = 1;
  void Quad(const std::vector<std::vector<double>>& c) {
    for (const auto& p : c)
      text += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " +
              std::to_string(p[2]) + "\n";
    text += "f " + std::to_string(next) + " " + std::to_string(next + 1) + " " +
            std::to_string(next + 2) + " " + std::to_string(next + 3) + "\n";
    next += 4;
  }
};

// The floor [0, 4]^2 at y = 0, facing up, whole or (holed) cut around the
// block's footprint [1, 2.5] x [1, 2]; the block (height h, five faces, no
// bottom) and a lamp [0, 4]^2 facing down at y = 6.
void WriteBlockScene(const std::string& dir, bool holed, double h = 1.0) {
  ObjQuads obj;
  auto quad = [&](const std::vector<std::vector<double>>& c) { obj.Quad(c); };
  // Counter-clockwise seen from above: facing up.
  auto floor = [&](double x0, double z0, double x1, double z1) {
    quad({{x0, 0, z0}, {x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}});
  };
  if (holed) {
    floor(0, 0, 4, 1);
    floor(0, 2, 4, 4);
    floor(0, 1, 1, 2);
    floor(2.5, 1, 4, 2);
  } else {
    floor(0, 0, 4, 4);
  }
  const double x0 = 1, x1 = 2.5, z0 = 1, z1 = 2;
  quad({{x0, h, z0}, {x0, h, z1}, {x1, h, z1}, {x1, h, z0}});  // top, up
  quad({{x0, h, z0}, {x1, h, z0}, {x1, 0, z0}, {x0, 0, z0}});  // -z
  quad({{x1, h, z1}, {x0, h, z1}, {x0, 0, z1}, {x1, 0, z1}});  // +z
  quad({{x0, h, z1}, {x0, h, z0}, {x0, 0, z0}, {x0, 0, z1}});  // -x
  quad({{x1, h, z0}, {x1, h, z1}, {x1, 0, z1}, {x1, 0, z0}});  // +x
  obj.text += "usemtl lamp\n";
  quad({{0, 6, 0}, {4, 6, 0}, {4, 6, 4}, {0, 6, 4}});  // facing down
  test::WriteFile(dir + "/s.obj", obj.text);
  test::WriteFile(dir + "/s.mtl",
                  "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 4 4 4\n");
}

// Sum of b * area (channels summed) over patches.csv's patches.
double PatchPowerTotal(const std::string& path) {
  double total = 0.0;
  const auto rows = test::ReadCsv(path);
  for (size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    total += std::stod(r[8]) * (std::stod(r[15]) + std::stod(r[16]) + std::stod(r[17]));
  }
  return total;
}

// The block scene with the whole floor, in one environment (built, so
// its roots measured).
void MakeBlockEnv(const test::TempDir& dir, test::TestEnvs* envs) {
  WriteBlockScene(dir.path(), false);
  EnvOptions eo;
  eo.rayEpsilon = 1e-4f;
  test::MakeTestEnvs(dir.File("s.obj").c_str(), EnvGrid{}, 1.0f, eo, envs);
}

TEST(ExposureTest, PatchesUnderABlockAreBuriedInProportion) {
  test::TempDir dir;
  test::TestEnvs envs;
  MakeBlockEnv(dir, &envs);
  if (HasFatalFailure()) return;
  Environment& env = *envs.ptrs[0];
  env.MeasureExposure();
  int seen = 0;
  for (uint32_t i = 0; i < env.patches().size(); ++i) {
    const Patch& p = env.patches()[i];
    glm::vec3 c(0.0f);
    for (uint32_t k = 0; k < p.numCorners; ++k) c += p.corner[k];
    c /= static_cast<float>(p.numCorners);
    const float share = env.ExposedArea(i) / p.area;
    const bool floor = p.normal.y > 0.5f && std::fabs(c.y) < 1e-4f;
    if (floor && std::fabs(c.z - 1.5f) < 1e-3f && std::fabs(c.x - 1.5f) < 1e-3f) {
      EXPECT_EQ(share, 0.0f) << "under the block";
      ++seen;
    } else if (floor && std::fabs(c.z - 1.5f) < 1e-3f && std::fabs(c.x - 2.5f) < 1e-3f) {
      EXPECT_EQ(share, 0.5f) << "half under the block";
      ++seen;
    } else {
      EXPECT_EQ(share, 1.0f) << "patch " << i << " at " << c.x << "," << c.y << "," << c.z;
    }
  }
  EXPECT_EQ(seen, 2);
}

// The floor just beside the block's +x face, seen from above with the
// solve's radiosity (no per-pixel direct light): the same brightness whether
// the floor runs on under the block or stops at it.
TEST(ExposureTest, TheFloorBesideABlockIsNotDarkenedByThePartBeneath) {
  double mean[2] = {0.0, 0.0};
  for (int holed = 0; holed < 2; ++holed) {
    test::TempDir dir;
    WriteBlockScene(dir.path(), holed == 1);
    test::RunResult r = test::RunMain(
        {"render", dir.File("s.obj"), "--out", dir.File("out"), "--camera",
         "2.75,2,1.5,2.75,0,1.5,0,0,1,11", "--width", "16", "--height", "16", "--patch-size", "1",
         "--direct-samples", "0", "--emitted-rays", "400000", "--indirect-filter", "0", "--quiet"});
    ASSERT_EQ(r.code, 0) << r.err;
    PfmImage img;
    ASSERT_TRUE(ReadPfm(dir.File("out/image.pfm"), &img).ok());
    for (size_t k = 0; k < img.pixels.size(); k += 3) mean[holed] += img.pixels[k];
    mean[holed] /= static_cast<double>(img.pixels.size() / 3);
  }
  ASSERT_GT(mean[1], 0.0);
  EXPECT_NEAR(mean[0] / mean[1], 1.0, 0.05) << mean[0] << " whole, " << mean[1] << " holed";
}

// A quad leaf measured part buried draws its rays' origins from its open
// cells only (and alike over them), a whole or unmeasured one anywhere:
// a ray from under a block would only meet the block's inside.
TEST(ExposureTest, OriginsLeaveFromTheOpenCellsOnly) {
  test::UnitQuadTree quad(false);
  ASSERT_EQ(quad.patches.size(), 1u);
  ElementTree& tree = quad.tree;
  glm::vec2 st;
  const float mid[3] = {0.5f, 0.5f, 0.5f};
  EXPECT_FALSE(tree.SampleByPower(false, 0, mid, &st)) << "unmeasured: the caller's uniform point";
  tree.SetExposed(0, 1.0f, 0xffff);
  EXPECT_FALSE(tree.SampleByPower(false, 0, mid, &st)) << "all open: the same";
  // Open: the cells with b (the last edge's index) 2 or 3, and cell (0, 1).
  const uint16_t open = 0xcccc | (1u << 1);
  tree.SetExposed(0, 9.0f / 16.0f, open);
  int perCell[16] = {0};
  const int n = 36, m = 32;  // n a multiple of the 9 open cells
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const float u[3] = {0.5f, (i + 0.5f) / n, (j + 0.5f) / m};
      ASSERT_TRUE(tree.SampleByPower(false, 0, u, &st));
      const int a = static_cast<int>(st.x * 4.0f), b = static_cast<int>(st.y * 4.0f);
      ASSERT_TRUE(a >= 0 && a < 4 && b >= 0 && b < 4) << st.x << "," << st.y;
      ASSERT_TRUE((open >> (a * 4 + b)) & 1u) << "a buried cell: " << a << "," << b;
      ++perCell[a * 4 + b];
    }
  for (int c = 0; c < 16; ++c) {
    if ((open >> c) & 1u) {
      EXPECT_EQ(perCell[c], n * m / 9) << c;
    }
  }
}

// A lamp hung 0.0015 below a ceiling of two unit patches (the Cornell
// lamp's 0.8 mm in its 556 mm room), from x = edge on: the second patch is
// wholly above it, the first from x = edge. The first is measured again on
// 8 x 8 points since it shares a corner with a buried patch: the strip
// above the lamp is buried, and so is the slit within a 60-degree probe's
// reach of the lamp's edge (one probe gets out there, the normal does not).
TEST(ExposureTest, TheCeilingAboveALampHungJustBelowItIsBuried) {
  for (const float edge : {0.9f, 0.9365f}) {
    test::TempDir dir;
    char obj[512];
    const float h = 1.0f, gap = 0.0015f;
    std::snprintf(obj, sizeof obj,
                  "mtllib s.mtl\nusemtl white\n"
                  "v 0 %g 0\nv 2 %g 0\nv 2 %g 1\nv 0 %g 1\nf 1 2 3 4\n"
                  "usemtl lamp\n"
                  "v %g %g -0.5\nv 2.5 %g -0.5\nv 2.5 %g 1.5\nv %g %g 1.5\nf 5 6 7 8\n",
                  h, h, h, h, edge, h - gap, h - gap, h - gap, edge, h - gap);
    test::WriteFile(dir.File("s.obj"), obj);
    test::WriteFile(dir.File("s.mtl"),
                    "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 4 4 4\n");
    EnvOptions eo;
    eo.rayEpsilon = 1e-5f;
    test::TestEnvs envs;
    test::MakeTestEnvs(dir.File("s.obj").c_str(), EnvGrid{}, 1.0f, eo, &envs);
    if (HasFatalFailure()) return;
    const Environment& env = *envs.ptrs[0];
    int ceilings = 0;
    for (uint32_t i = 0; i < env.patches().size(); ++i) {
      const Patch& p = env.patches()[i];
      if (p.normal.y > -0.5f || std::fabs(p.corner[0].y - h) > 1e-6f) continue;
      ++ceilings;
      float x = 0.0f;
      for (uint32_t k = 0; k < p.numCorners; ++k) x += p.corner[k].x / p.numCorners;
      if (x > 1.0f) {
        EXPECT_EQ(env.elementTree().exposed(i), 0.0f) << "lamp edge at x = " << edge;
        continue;
      }
      // Of the points at x = (a + 1/2) / 8, only a = 7 (x = 0.9375) lies over the lamp.
      EXPECT_EQ(env.elementTree().exposed(i), 7.0f / 8.0f) << "lamp edge at x = " << edge;
      // The cells along x hold two points each: the last is half buried, so closed.
      EXPECT_EQ(__builtin_popcount(env.elementTree().open(i)), 12) << "lamp edge at x = " << edge;
    }
    EXPECT_EQ(ceilings, 2);
  }
}

// The roots are measured when the solve is reset, before any shot, and a
// split's children when it splits: the origins know the buried parts from
// the first shot on.
TEST(ExposureTest, RootsAreMeasuredBeforeTheFirstShot) {
  test::TempDir dir;
  test::TestEnvs envs;
  MakeBlockEnv(dir, &envs);
  if (HasFatalFailure()) return;
  const Environment& env = *envs.ptrs[0];
  int partBuried = 0;
  for (uint32_t i = 0; i < env.patches().size(); ++i) {
    const float share = env.elementTree().exposed(i);
    ASSERT_NE(share, ElementTree::kUnmeasured) << i;
    const int cells = __builtin_popcount(env.elementTree().open(i));
    EXPECT_EQ(share, static_cast<float>(cells) / 16.0f) << i;
    partBuried += share > 0.0f && share < 1.0f;
  }
  EXPECT_EQ(partBuried, 1) << "the floor patch half under the block";
}

// Cut into two environments by the plane y = 3 through a block 4 high,
// the lower one holds the floor and the block's walls, the upper one its
// top. From under the block the normal probe leaves for the upper
// environment, and the floor there is still measured buried: the slanted
// probes meet the walls from inside. The patch half under the block keeps
// its open cells in Patch::openCells, which its rays leave from wherever
// they are traced; one environment draws by power instead and keeps 0.
TEST(ExposureTest, AFloorUnderABlockCutAboveItIsStillBuried) {
  for (const int envs : {1, 2}) {
    test::TempDir dir;
    WriteBlockScene(dir.path(), false, 4.0);
    EnvOptions eo;
    eo.rayEpsilon = 1e-4f;
    EnvGrid grid;
    grid.n[1] = envs;
    test::TestEnvs made;
    test::MakeTestEnvs(dir.File("s.obj").c_str(), grid, 1.0f, eo, &made);
    if (HasFatalFailure()) return;
    const Environment& env = *made.ptrs[0];
    int seen = 0;
    for (uint32_t i = 0; i < env.patches().size(); ++i) {
      const Patch& p = env.patches()[i];
      const glm::vec3 c = CentreOf(p);
      if (p.normal.y < 0.5f || std::fabs(c.y) > 1e-4f || std::fabs(c.z - 1.5f) > 1e-3f) continue;
      const float share = env.elementTree().exposed(i);
      if (std::fabs(c.x - 1.5f) < 1e-3f) {
        EXPECT_EQ(share, 0.0f) << envs << " environments: under the block";
        EXPECT_EQ(p.openCells, 0) << "wholly buried: it never shoots";
        ++seen;
      } else if (std::fabs(c.x - 2.5f) < 1e-3f) {
        EXPECT_EQ(share, 0.5f) << envs << " environments: half under the block";
        EXPECT_EQ(p.openCells, envs == 1 ? 0 : env.elementTree().open(i));
        EXPECT_EQ(__builtin_popcount(p.openCells), envs == 1 ? 0 : 8);
        ++seen;
      }
    }
    EXPECT_EQ(seen, 2) << envs;
  }
}

// A closed box 4 on a side, all Kd 0.5, its ceiling the lamp (Ke 1), a
// block 2 x 2 x 2 in the middle of the floor; at patch size 2 each floor
// patch is a quarter under the block. Cut by the plane x = 2 through the
// block, the patches' radiosity accounts for all the light one
// environment's does (closed: every watt emitted is absorbed by a patch, so
// the total is the same however it is spread); with the floor's rays left
// uniformly from under the block (--origins uniform), the block's inside
// absorbs a share of them on its back faces.
TEST(ExposureTest, ASplitThroughABlockLosesNoLightUnderIt) {
  test::TempDir dir;
  ObjQuads obj;
  auto quad = [&](const std::vector<std::vector<double>>& c) { obj.Quad(c); };
  const double L = 4, x0 = 1, x1 = 3, h = 2;
  quad({{0, 0, 0}, {0, 0, L}, {L, 0, L}, {L, 0, 0}});  // floor, up
  quad({{0, 0, 0}, {L, 0, 0}, {L, L, 0}, {0, L, 0}});  // the walls, inward
  quad({{0, 0, L}, {0, L, L}, {L, L, L}, {L, 0, L}});
  quad({{0, 0, 0}, {0, L, 0}, {0, L, L}, {0, 0, L}});
  quad({{L, 0, 0}, {L, 0, L}, {L, L, L}, {L, L, 0}});
  quad({{x0, h, x0}, {x0, h, x1}, {x1, h, x1}, {x1, h, x0}});  // the block: top
  quad({{x0, h, x0}, {x1, h, x0}, {x1, 0, x0}, {x0, 0, x0}});  // and walls
  quad({{x1, h, x1}, {x0, h, x1}, {x0, 0, x1}, {x1, 0, x1}});
  quad({{x0, h, x1}, {x0, h, x0}, {x0, 0, x0}, {x0, 0, x1}});
  quad({{x1, h, x0}, {x1, h, x1}, {x1, 0, x1}, {x1, 0, x0}});
  obj.text += "usemtl lamp\n";
  quad({{0, L, 0}, {L, L, 0}, {L, L, L}, {0, L, L}});  // ceiling, down
  test::WriteFile(dir.File("s.obj"), obj.text);
  test::WriteFile(dir.File("s.mtl"),
                  "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  auto total = [&](const std::string& extra) {
    std::vector<std::string> args = {"render",
                                     dir.File("s.obj"),
                                     "--out",
                                     dir.File("out"),
                                     "--width",
                                     "8",
                                     "--height",
                                     "8",
                                     "--patch-size",
                                     "2",
                                     "--direct-samples",
                                     "0",
                                     "--emitted-rays",
                                     "200000",
                                     "--quiet"};
    for (const std::string& w : test::Words(extra)) args.push_back(w);
    test::RunResult r = test::RunMain(args);
    EXPECT_EQ(r.code, 0) << r.err;
    return PatchPowerTotal(dir.File("out/patches.csv"));
  };
  const double one = total("");
  ASSERT_GT(one, 0.0);
  const double split = total("--envs 2"), uniform = total("--envs 2 --origins uniform");
  EXPECT_NEAR(split / one, 1.0, 0.002) << "split " << split << ", one " << one;
  EXPECT_LT(uniform / one, 0.995) << "uniform origins lose light under the block";
}

// A shooter's masks are cast from its centre, or with open cells from the
// centre of the open cell nearest their mean: from a patch whose centre
// lies under a block every centre ray would start inside it.
TEST(ExposureTest, MasksAreCastFromAnOpenCell) {
  gridtest::TestScene s;
  gridtest::AddSubdividedQuad(1, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1, 1, &s);
  ASSERT_EQ(s.patches.size(), 1u);
  Patch p = s.patches[0];
  const glm::vec3 centre = CentreOf(p);
  EXPECT_EQ(MaskCentre(p), centre) << "no open cells: the centre";
  // Open: the cells with a (along the first edge) 0 or 1, and (2, 0).
  p.openCells = 0x00ff | (1u << 8);
  const glm::vec2 st = PatchParam(p, MaskCentre(p));
  const int a = static_cast<int>(st.x * 4.0f), b = static_cast<int>(st.y * 4.0f);
  EXPECT_TRUE((p.openCells >> (a * 4 + b)) & 1u) << st.x << "," << st.y;
  EXPECT_NEAR(st.x, 0.375f, 1e-6f) << "the open cell nearest the mean (0.29, 0.46)";
  EXPECT_NEAR(st.y, 0.375f, 1e-6f);
}

// A patch that is still one leaf sends its rays by the power its quarters
// received once it has ElementTree::kQuarterHits hits (each quarter also
// counting kQuarterPrior hits' worth spread evenly), over its open cells
// when part buried; a triangle's by its child triangles.
TEST(ExposureTest, OneLeafPatchesLeaveByTheirQuartersPower) {
  test::UnitQuadTree quad(false);
  ElementTree& tree = quad.tree;
  tree.SetExposed(0, 1.0f, 0xffff);
  ElementTree::QuarterOrigins o;
  Element& el = tree[0];
  const double q[4] = {1.0, 3.0, 0.0, 0.0};  // k = [s >= 1/2] + 2 [t >= 1/2]
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) el.quarter[k][c] = q[k] / 3.0;
  el.hits = ElementTree::kQuarterHits - 1;
  EXPECT_FALSE(tree.MakeQuarterOrigins(false, 0, &o)) << "too few hits: as before";
  el.hits = 100;
  // The shares a stratified u[0] must find, and where the points fall.
  auto shares = [&](const ElementTree::QuarterOrigins& origins, int perQuarter[4], int* buried,
                    uint16_t open) {
    const int n = 4000;
    for (int i = 0; i < n; ++i) {
      const float u[3] = {(i + 0.5f) / n, 0.37f, 0.61f};
      const glm::vec2 st = origins.Point(u);
      ASSERT_TRUE(st.x > 0.0f && st.x < 1.0f && st.y > 0.0f && st.y < 1.0f);
      ++perQuarter[(st.x >= 0.5f) + 2 * (st.y >= 0.5f)];
      const int a = static_cast<int>(st.x * 4.0f), b = static_cast<int>(st.y * 4.0f);
      *buried += !((open >> (a * 4 + b)) & 1u);
    }
  };
  const double prior = ElementTree::kQuarterPrior * 4.0 / (4.0 * el.hits), all = 4.0 + 4.0 * prior;
  ASSERT_TRUE(tree.MakeQuarterOrigins(false, 0, &o));
  int per[4] = {0, 0, 0, 0}, buried = 0;
  shares(o, per, &buried, 0xffff);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(per[k] / 4000.0, (q[k] + prior) / all, 1e-3) << k;
  // Part buried: cell (a, b) open for b >= 2 (the cells of quarters 2 and 3)
  // and for (1, 0) and (3, 1); each quarter's power over its open cells.
  const uint16_t open = 0xcccc | (1u << 4) | (1u << 13);
  tree.SetExposed(0, 10.0f / 16.0f, open);
  ASSERT_TRUE(tree.MakeQuarterOrigins(false, 0, &o));
  int perB[4] = {0, 0, 0, 0};
  buried = 0;
  shares(o, perB, &buried, open);
  EXPECT_EQ(buried, 0);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(perB[k] / 4000.0, (q[k] + prior) / all, 1e-3) << k;
  // A triangle: the child triangle ChildOf names.
  ASSERT_TRUE(tree.MakeQuarterOrigins(true, 0, &o));
  int perT[4] = {0, 0, 0, 0};
  for (int i = 0; i < 4000; ++i) {
    const float u[3] = {(i + 0.5f) / 4000.0f, 0.37f, 0.61f};
    glm::vec2 st = o.Point(u);
    ASSERT_LT(st.x + st.y, 1.0f);
    ++perT[ChildOf(true, &st)];
  }
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(perT[k] / 4000.0, (q[k] + prior) / all, 1e-3) << k;
}

}  // namespace
}  // namespace vismask
