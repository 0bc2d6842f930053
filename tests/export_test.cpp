// --export FILE.glb (gltf.h, src/output/export.cpp): the file's structure, its
// colours against image.pfm, its options, and Khronos' glTF-Validator on
// real exports (when node is installed: tools/install-deps).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/app/options.h"
#include "vismask/core/arena.h"
#include "vismask/output/gltf.h"

namespace vismask {
namespace {

using test::FileExists;
using test::ReadFile;
using test::RunMain;
using test::TempDir;

uint32_t U32(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<uint8_t>(s[at + k]);
  return v;
}

float F32(const std::string& s, size_t at) {
  uint32_t bits = U32(s, at);
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

// The unsigned number after the n-th (0-based) occurrence of `key` in `json`.
uint64_t JsonNumber(const std::string& json, const std::string& key, int n = 0) {
  size_t at = 0;
  for (int k = 0; k <= n; ++k) {
    at = json.find(key, k == 0 ? 0 : at + 1);
    if (at == std::string::npos) return ~0ull;
  }
  return std::strtoull(json.c_str() + at + key.size(), nullptr, 10);
}

// A .glb as vismask writes it (one interleaved vertex view, then indices),
// read back with every length checked against the bytes.
struct Glb {
  std::string json;
  double scale = 0.0;           // extras.radianceScale: radiance = COLOR_0 * scale
  std::vector<float> pos, col;  // 3 per vertex
  std::vector<uint32_t> idx;
};

::testing::AssertionResult ReadGlb(const std::string& bytes, Glb* g) {
  if (bytes.size() < 28)
    return ::testing::AssertionFailure() << "only " << bytes.size() << " bytes";
  if (bytes.compare(0, 4, "glTF") != 0 || U32(bytes, 4) != 2)
    return ::testing::AssertionFailure() << "not a GLB version 2";
  if (U32(bytes, 8) != bytes.size())
    return ::testing::AssertionFailure()
           << "header length " << U32(bytes, 8) << ", file " << bytes.size();
  uint32_t jsonBytes = U32(bytes, 12);
  if (jsonBytes % 4 != 0 || bytes.compare(16, 4, "JSON") != 0 || 20 + jsonBytes + 8 > bytes.size())
    return ::testing::AssertionFailure() << "bad JSON chunk";
  g->json = bytes.substr(20, jsonBytes);
  size_t sc = g->json.find("\"radianceScale\":");
  if (sc == std::string::npos) return ::testing::AssertionFailure() << "no radianceScale";
  g->scale = std::strtod(g->json.c_str() + sc + 16, nullptr);
  size_t bin = 20 + jsonBytes;
  uint32_t binBytes = U32(bytes, bin);
  if (bytes.compare(bin + 4, 4, std::string("BIN\0", 4)) != 0 || bin + 8 + binBytes != bytes.size())
    return ::testing::AssertionFailure() << "bad BIN chunk";
  uint64_t vertices = JsonNumber(g->json, "\"count\":", 0);
  uint64_t indices = JsonNumber(g->json, "\"count\":", 2);
  if (vertices * 24 + indices * 4 != binBytes)
    return ::testing::AssertionFailure() << vertices << " vertices and " << indices
                                         << " indices do not fill " << binBytes << " bytes";
  size_t at = bin + 8;
  for (uint64_t v = 0; v < vertices; ++v, at += 24)
    for (int a = 0; a < 3; ++a) {
      g->pos.push_back(F32(bytes, at + 4 * a));
      g->col.push_back(F32(bytes, at + 12 + 4 * a));
    }
  for (uint64_t i = 0; i < indices; ++i, at += 4) g->idx.push_back(U32(bytes, at));
  return ::testing::AssertionSuccess();
}

// The three numbers after `key` in `json` (comma-separated) are `want`,
// parsed as doubles.
void ExpectVector(const std::string& json, const std::string& key, const float want[3]) {
  const char* p = json.c_str() + json.find(key) + key.size();
  for (int a = 0; a < 3; ++a) {
    char* end = nullptr;
    EXPECT_EQ(std::strtod(p, &end), static_cast<double>(want[a])) << key << a;
    p = end + 1;
  }
}

TEST(ExportTest, HeadDescribesTheDataThatFollows) {
  GlbMesh m;
  m.vertices = 5;
  m.triangles = 3;
  const float lo[3] = {-1.5f, 0.1f, 2.0f}, hi[3] = {3.0f, 0.7f, 1e6f};
  for (int a = 0; a < 3; ++a) {
    m.lo[a] = lo[a];
    m.hi[a] = hi[a];
  }
  std::vector<uint8_t> head(kGlbHeadBytes, 0xee);
  size_t n = WriteGlbHead(m, Span<uint8_t>(head.data(), head.size()));
  ASSERT_GT(n, 28u);
  ASSERT_LE(n, kGlbHeadBytes);
  std::string bytes(reinterpret_cast<const char*>(head.data()), n);
  bytes.append(GlbBinBytes(m), '\0');
  Glb g;
  ASSERT_TRUE(ReadGlb(bytes, &g));
  EXPECT_EQ(g.pos.size(), 15u);
  EXPECT_EQ(g.idx.size(), 9u);
  EXPECT_EQ(g.json.back(), g.json.find_last_not_of(' ') + 1 == g.json.size() ? '}' : ' ');
  // The agreed shape: one scene, node and mesh; unlit, in extensionsUsed only.
  for (const char* s : {"\"generator\":\"vismask\"", "\"extensionsUsed\":[\"KHR_materials_unlit\"]",
                        "\"KHR_materials_unlit\":{}", "\"baseColorFactor\":[1,1,1,1]", "\"mode\":4",
                        "\"POSITION\":0", "\"COLOR_0\":1", "\"indices\":2",
                        "\"componentType\":5125", "\"byteStride\":24"})
    EXPECT_NE(g.json.find(s), std::string::npos) << s << " in " << g.json;
  EXPECT_EQ(g.json.find("extensionsRequired"), std::string::npos);
  // The bounds are the floats themselves: parsed as doubles, they are equal.
  ASSERT_NE(g.json.find("\"min\":["), std::string::npos);
  ExpectVector(g.json, "\"min\":[", lo);
  ExpectVector(g.json, "\"max\":[", hi);
  // Vertices and triangles are little-endian floats and 32-bit indices.
  uint8_t v[kGlbVertexBytes], t[kGlbTriangleBytes];
  PutGlbVertex(glm::vec3(1.0f, -2.0f, 0.5f), glm::vec3(3.25f, 0.0f, 7.0f), 1.0f, v);
  PutGlbTriangle(1, 0x01020304u, 7, t);
  std::string vs(reinterpret_cast<const char*>(v), sizeof v),
      ts(reinterpret_cast<const char*>(t), sizeof t);
  EXPECT_EQ(F32(vs, 4), -2.0f);
  EXPECT_EQ(F32(vs, 12), 3.25f);
  EXPECT_EQ(F32(vs, 20), 7.0f);
  EXPECT_EQ(U32(ts, 4), 0x01020304u);
  EXPECT_EQ(static_cast<uint8_t>(ts[4]), 0x04);
  // Scaled by a power of two: exact.
  PutGlbVertex(glm::vec3(0.0f), glm::vec3(3.25f, 0.1f, 7.0f), 8.0f, v);
  vs.assign(reinterpret_cast<const char*>(v), sizeof v);
  EXPECT_EQ(F32(vs, 12) * 8.0f, 3.25f);
  EXPECT_EQ(F32(vs, 16) * 8.0f, 0.1f);
  EXPECT_EQ(F32(vs, 20), 0.875f);
}

// COLOR_0 in [0, 1] (glTF-Validator: ACCESSOR_NON_CLAMPED is an error):
// the least power of two at least as large as the brightest component.
TEST(ExportTest, RadianceScaleIsTheLeastPowerOfTwoAboveTheBrightest) {
  GlbMesh m;
  EXPECT_EQ(GlbRadianceScale(m), 1.0f);
  const float brightestAndScale[][2] = {{0.3f, 1.0f},  {1.0f, 1.0f},       {1.0001f, 2.0f},
                                        {5.45f, 8.0f}, {4096.0f, 4096.0f}, {1e38f, 0x1p127f}};
  for (const auto& c : brightestAndScale) {
    m.maxRadiance = c[0];
    EXPECT_EQ(GlbRadianceScale(m), c[1]) << c[0];
  }
  m.vertices = m.triangles = 1;
  std::vector<uint8_t> head(kGlbHeadBytes);
  size_t n = WriteGlbHead(m, Span<uint8_t>(head.data(), head.size()));
  std::string json(reinterpret_cast<const char*>(head.data()) + 20, n - 28);
  EXPECT_NE(json.find("\"extras\":{\"radianceScale\":1.7014118346046923e+38}"), std::string::npos)
      << json;
}

TEST(ExportTest, MergedBoundsAndCounts) {
  GlbMesh a, b, none, all;
  a.vertices = 2;
  a.triangles = 1;
  b.vertices = 3;
  b.triangles = 2;
  for (int k = 0; k < 3; ++k) {
    a.lo[k] = -1.0f;
    a.hi[k] = 1.0f;
    b.lo[k] = 0.5f;
    b.hi[k] = 4.0f;
    none.lo[k] = -100.0f;  // no vertices: its bounds mean nothing
  }
  MergeGlbMesh(b, &all);
  MergeGlbMesh(none, &all);
  MergeGlbMesh(a, &all);
  EXPECT_EQ(all.vertices, 5u);
  EXPECT_EQ(all.triangles, 3u);
  EXPECT_EQ(all.lo[1], -1.0f);
  EXPECT_EQ(all.hi[2], 4.0f);
}

const std::vector<std::string> kCornell = {
    "render", "scenes/cornell.obj", "--rays", "256",    "--max-shots", "300", "--width",
    "33",     "--height",           "33",     "--quiet"};

// The mesh of a Cornell render: the patches' lattice, every index in range,
// the bounds those of the data, and the counts run.json gives.
TEST(ExportTest, CornellExportIsTheSolvedMesh) {
  TempDir dir;
  auto args = kCornell;
  args.insert(args.end(), {"--out", dir.File("out"), "--export", dir.File("cornell.glb")});
  auto r = RunMain(args);
  ASSERT_EQ(r.code, 0) << r.err;
  Glb g;
  ASSERT_TRUE(ReadGlb(ReadFile(dir.File("cornell.glb")), &g));
  const size_t n = g.pos.size() / 3;
  std::string json = ReadFile(dir.File("out/run.json"));
  EXPECT_EQ(JsonNumber(json, "\"vertices\": "), n);
  EXPECT_EQ(JsonNumber(json, "\"export\": {\"vertices\": "), n);
  EXPECT_EQ(JsonNumber(json, "\"triangles\": "), g.idx.size() / 3);
  EXPECT_EQ(JsonNumber(json, "\"bytes\": "), ReadFile(dir.File("cornell.glb")).size());
  // The patches give at least one triangle each, at most two.
  uint64_t patches = JsonNumber(json, "\"patches\": ");
  EXPECT_GE(g.idx.size() / 3, patches);
  EXPECT_LE(g.idx.size() / 3, 2 * patches);
  for (uint32_t i : g.idx) ASSERT_LT(i, n);
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = g.pos[a];
  for (size_t v = 0; v < n; ++v)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::fmin(lo[a], g.pos[3 * v + a]);
      hi[a] = std::fmax(hi[a], g.pos[3 * v + a]);
    }
  const char* p = g.json.c_str() + g.json.find("\"min\":[") + 7;
  for (int a = 0; a < 3; ++a) {
    char* end = nullptr;
    EXPECT_EQ(std::strtod(p, &end), lo[a]);
    p = end + 1;
  }
  EXPECT_EQ(lo[0], 0.0f);
  EXPECT_NEAR(hi[1], 548.8f, 1.0f);
  // Colours are radiance over radianceScale, in [0, 1], never clamped: the
  // brightest (the light's: Ke / pi is 5.4 in red) is scaled to (0.5, 1].
  float brightest = 0.0f;
  for (float c : g.col) {
    ASSERT_GE(c, 0.0f);
    ASSERT_LE(c, 1.0f);
    brightest = std::fmax(brightest, c);
  }
  EXPECT_EQ(g.scale, 8.0);
  EXPECT_GT(brightest, 0.5f);
  EXPECT_GT(brightest * g.scale, 17.0 / 3.14159265);
}

// The PFM's pixel (x, y), RGB.
void PfmPixel(const std::string& pfm, int width, int x, int y, float out[3]) {
  // Three header lines.
  size_t at = 0;
  for (int k = 0; k < 3; ++k) at = pfm.find('\n', at) + 1;
  size_t px = at + (static_cast<size_t>(y) * width + x) * 12;
  for (int c = 0; c < 3; ++c) std::memcpy(&out[c], pfm.data() + px + 4 * c, 4);
}

// COLOR_0 at a lattice vertex is what image.pfm shows there: a camera
// aimed straight at the vertex, an odd image size so that the centre
// pixel's centre is the vertex, point sampling (--aa off). One vertex
// inside the back wall and one inside the light (emission included). A
// short solve, so the ambient term is a large part of what is shown.
TEST(ExportTest, ColourIsWhatTheImageShowsAtTheVertex) {
  TempDir dir;
  auto args = kCornell;
  // The image as the solve has it: per-pixel direct light is the view's,
  // not the export's (DirectTest.ExportIsTheSolvedWhole).
  args.insert(args.end(),
              {"--out", dir.File("out"), "--export", dir.File("c.glb"), "--direct-samples", "0"});
  ASSERT_EQ(RunMain(args).code, 0);
  Glb g;
  ASSERT_TRUE(ReadGlb(ReadFile(dir.File("c.glb")), &g));
  const size_t n = g.pos.size() / 3;
  // A back-wall vertex near the wall's middle, and a light vertex (the
  // brightest red) nearest the light's centre.
  float maxZ = 0.0f, maxRed = 0.0f;
  for (size_t v = 0; v < n; ++v) {
    maxZ = std::fmax(maxZ, g.pos[3 * v + 2]);
    maxRed = std::fmax(maxRed, g.col[3 * v]);
  }
  auto nearest = [&](auto accept, float x, float y, float z) {
    size_t best = n;
    float bestD = 1e30f;
    for (size_t v = 0; v < n; ++v) {
      if (!accept(v)) continue;
      float d = std::hypot(g.pos[3 * v] - x, g.pos[3 * v + 1] - y, g.pos[3 * v + 2] - z);
      if (d < bestD) {
        bestD = d;
        best = v;
      }
    }
    return best;
  };
  size_t wall = nearest([&](size_t v) { return g.pos[3 * v + 2] == maxZ; }, 250.0f, 300.0f, maxZ);
  size_t light =
      nearest([&](size_t v) { return g.col[3 * v] > 0.5f * maxRed; }, 278.0f, 548.0f, 280.0f);
  ASSERT_LT(wall, n);
  ASSERT_LT(light, n);
  struct Aim {
    size_t v;
    float dx, dy, dz;  // eye = vertex - d
    const char* up;
  };
  for (const Aim& aim :
       {Aim{wall, 0.0f, 0.0f, 60.0f, "0,1,0"}, Aim{light, 0.0f, 60.0f, 0.0f, "0,0,1"}}) {
    const float* x = &g.pos[3 * aim.v];
    char camera[300];
    std::snprintf(camera, sizeof camera, "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%s,4", x[0] - aim.dx,
                  x[1] - aim.dy, x[2] - aim.dz, x[0], x[1], x[2], aim.up);
    auto view = kCornell;
    view.insert(view.end(), {"--out", dir.File("view"), "--aa", "off", "--camera", camera,
                             "--direct-samples", "0"});
    auto r = RunMain(view);
    ASSERT_EQ(r.code, 0) << r.err;
    float px[3];
    PfmPixel(ReadFile(dir.File("view/image.pfm")), 33, 16, 16, px);
    for (int c = 0; c < 3; ++c) {
      const double radiance = g.col[3 * aim.v + c] * g.scale;
      EXPECT_NEAR(px[c], radiance, 1e-4 * radiance + 1e-7)
          << "vertex " << aim.v << " (" << x[0] << ", " << x[1] << ", " << x[2] << ") channel "
          << c;
    }
  }
  EXPECT_GT(g.col[3 * light] * g.scale, 17.0 / 3.14159265);  // the emission is in it
}

TEST(ExportTest, OptionIsAGlbPath) {
  TempDir dir;
  for (const char* bad : {"scene.gltf", "scene", ".glb", "dir/.glb", "glb"}) {
    auto args = kCornell;
    args.insert(args.end(), {"--out", dir.File("out"), "--export", bad});
    auto r = RunMain(args);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_NE(r.err.find("--export: expected a file name ending in .glb"), std::string::npos)
        << r.err;
  }
  auto args = kCornell;
  args.insert(args.end(), {"--out", dir.File("out"), "--export", "--quiet"});
  auto r = RunMain(args);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--export: missing value"), std::string::npos) << r.err;
  EXPECT_FALSE(FileExists(dir.File("out")));
  // Where the file cannot be made: exit 1 at init, no output at all.
  args = kCornell;
  args.insert(args.end(), {"--out", dir.File("out"), "--export", dir.File("missing/x.glb")});
  r = RunMain(args);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("--export"), std::string::npos) << r.err;
  EXPECT_FALSE(FileExists(dir.File("out/run.json")));
  EXPECT_FALSE(FileExists(dir.File("out/image.pfm")));
  // A directory of that name is refused at init too (it could not be replaced).
  ASSERT_EQ(std::system(("mkdir " + dir.File("d.glb")).c_str()), 0);
  args = kCornell;
  args.insert(args.end(), {"--out", dir.File("out"), "--export", dir.File("d.glb")});
  r = RunMain(args);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("exists and is not a regular file"), std::string::npos) << r.err;
  EXPECT_FALSE(FileExists(dir.File("out/run.json")));
  // Upper case is a .glb too; --help names the option.
  args = kCornell;
  args.insert(args.end(), {"--out", dir.File("out"), "--export", dir.File("X.GLB")});
  EXPECT_EQ(RunMain(args).code, 0);
  EXPECT_TRUE(FileExists(dir.File("X.GLB")));
  EXPECT_FALSE(FileExists(dir.File("X.GLB.tmp")));
  EXPECT_NE(std::string(HelpText()).find("--export FILE.glb"), std::string::npos);
}

// footprint counts the export's buffers, exactly what the render reserves.
TEST(ExportTest, FootprintCountsTheExportBuffers) {
  TempDir dir;
  std::vector<std::string> base = {
      "scenes/cornell.obj", "--envs", "2", "--ranks", "2", "--width", "33", "--height", "33"};
  auto fp = [&](bool exporting) {
    std::vector<std::string> args = {"footprint"};
    args.insert(args.end(), base.begin(), base.end());
    args.push_back("--json");
    if (exporting) args.insert(args.end(), {"--export", dir.File("x.glb")});
    testing::internal::CaptureStdout();
    auto r = RunMain(args);
    std::string out = testing::internal::GetCapturedStdout();
    EXPECT_EQ(r.code, 0) << r.err;
    return out;
  };
  std::string without = fp(false), with = fp(true);
  EXPECT_EQ(JsonNumber(without, "\"export_bytes\": "), 0u);
  uint64_t rank0 = JsonNumber(with, "\"export_bytes\": ");
  EXPECT_GE(rank0, kGlbHeadBytes + 2048 * kGlbVertexBytes);
  // Each rank's total grows by its export buffers, up to the arena's
  // alignment either way (the buffers may fill what rounding left before
  // them, or leave some after); rank 0 also holds the file's head.
  auto rankField = [](const std::string& j, int rank, const char* key) {
    return JsonNumber(j.substr(j.find("{\"rank\": " + std::to_string(rank))), key);
  };
  for (int k = 0; k < 2; ++k) {
    uint64_t bytes = rankField(with, k, "\"export_bytes\": ");
    uint64_t grown =
        rankField(with, k, "\"total_bytes\": ") - rankField(without, k, "\"total_bytes\": ");
    EXPECT_GT(grown + Arena::kAlign, bytes) << "rank " << k;
    EXPECT_LT(grown, bytes + Arena::kAlign) << "rank " << k;
  }
  EXPECT_EQ(rank0 - rankField(with, 1, "\"export_bytes\": "), kGlbHeadBytes);
  std::vector<std::string> args = {"render"};
  args.insert(args.end(), base.begin(), base.end());
  args.insert(args.end(), {"--rays", "256", "--max-shots", "100", "--quiet", "--out",
                           dir.File("out"), "--export", dir.File("x.glb")});
  auto r = RunMain(args);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(JsonNumber(ReadFile(dir.File("out/run.json")), "\"rank0_export_bytes\": "), rank0);
}

// Khronos' glTF-Validator (tools/gltf, installed by tools/install-deps with
// npm ci) finds no error and no warning in the Cornell box, a render on
// 2x2 environments and 2 ranks, and a scene from scenes/real/.
TEST(ExportTest, KhronosValidatorAcceptsTheExports) {
  if (std::system("command -v node >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "node is not installed (tools/install-deps installs nodejs and npm): the "
                    "glTF-Validator check of --export was skipped";
  ASSERT_TRUE(FileExists("tools/gltf/node_modules/gltf-validator/package.json"))
      << "node is installed but the validator is not: tools/install-deps runs npm ci in tools/gltf";
  TempDir dir;
  std::vector<std::vector<std::string>> runs = {
      {"render", "scenes/cornell.obj", "--export", dir.File("cornell.glb")},
      {"render", "scenes/cornell.obj", "--envs", "2x2", "--ranks", "2", "--mask-method", "R",
       "--export", dir.File("cornell-2x2.glb")},
      {"render", "scenes/real/CornellBox-Sphere.obj", "--export", dir.File("sphere.glb")}};
  for (size_t k = 0; k < runs.size(); ++k) {
    auto args = runs[k];
    args.insert(args.end(),
                {"--emitted-rays", "100000", "--stop-unshot", "5e-2", "--width", "32", "--height",
                 "32", "--quiet", "--out", dir.File("out" + std::to_string(k))});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  std::string files = " " + dir.File("cornell.glb") + " " + dir.File("cornell-2x2.glb") + " " +
                      dir.File("sphere.glb");
  std::string cmd =
      "node tools/gltf/validate.mjs" + files + " >" + dir.File("validator.txt") + " 2>&1";
  int status = std::system(cmd.c_str());
  std::string report = ReadFile(dir.File("validator.txt"));
  std::printf("%s", report.c_str());
  EXPECT_EQ(status, 0) << report;
  // One line of counts per file, each with no error and no warning.
  size_t clean = 0;
  for (size_t at = report.find(": 0 errors, 0 warnings"); at != std::string::npos;
       at = report.find(": 0 errors, 0 warnings", at + 1))
    ++clean;
  EXPECT_EQ(clean, 3u) << report;
}

}  // namespace
}  // namespace vismask
