// Textures (map_Kd): decoding, the patch mean the solve uses, uv maps, the
// loader's warnings and errors, and the image, which shows the texture
// modulating the solved irradiance.
#include "vismask/scene/texture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <glm/geometric.hpp>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/display/camera.h"
#include "vismask/output/image_io.h"
#include "vismask/solve/partition.h"

// stb_image_write for this test's own images (static: image_io.cpp has its own).
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;

// A w x h RGB texture over `texels` (held by the caller).
Texture TexView(std::vector<uint8_t>& texels, uint32_t w, uint32_t h) {
  Texture t;
  t.width = w;
  t.height = h;
  t.texels = texels.data();
  return t;
}

// A 2 x 2 checker: white (255) top left and bottom right, black elsewhere.
std::vector<uint8_t> Checker2() {
  std::vector<uint8_t> c(12, 0);
  for (int k = 0; k < 3; ++k) c[0 + k] = c[9 + k] = 255;
  return c;
}

// The unit square in z = 0 (normal +z) as a quad patch.
Patch Square() {
  Patch p{};
  p.corner[0] = {0, 0, 0};
  p.corner[1] = {1, 0, 0};
  p.corner[2] = {1, 1, 0};
  p.corner[3] = {0, 1, 0};
  p.normal = {0, 0, 1};
  p.numCorners = 4;
  p.area = 1.0f;
  return p;
}

TEST(TextureTest, SrgbCodesDecodeToLinear) {
  EXPECT_EQ(SrgbToLinear(0), 0.0f);
  EXPECT_EQ(SrgbToLinear(255), 1.0f);
  EXPECT_NEAR(SrgbToLinear(10), 10.0 / 255.0 / 12.92, 1e-7);  // the linear toe
  EXPECT_NEAR(SrgbToLinear(128), 0.21586050011389926, 1e-7);  // ((128/255 + .055)/1.055)^2.4
  EXPECT_NEAR(SrgbToLinear(188), 0.5028864580325687, 1e-7);   // about half
  // A texture of code 128 reflects 0.216 on average, not 128/255 = 0.502.
  std::vector<uint8_t> grey(4 * 4 * 3, 128);
  Texture t = TexView(grey, 4, 4);
  EXPECT_NEAR(t.Sample({0.3f, 0.7f}).x, 0.2158605, 1e-6);
}

TEST(TextureTest, ReadsPngAndJpegFiles) {
  TempDir dir;
  std::vector<uint8_t> img(8 * 4 * 3);
  for (size_t i = 0; i < img.size(); i += 3) img[i] = 200, img[i + 1] = 100, img[i + 2] = 50;
  ASSERT_NE(stbi_write_png(dir.File("a.png").c_str(), 8, 4, 3, img.data(), 8 * 3), 0);
  // The same image as a JPEG, committed: stb's JPEG writer (quality 100)
  // made it; under UBSan that writer shifts negative values, its reader not.
  for (std::string name : {dir.File("a.png"), std::string("tests/data/flat-8x4.jpg")}) {
    TextureImage t;
    Status s = ReadTexture(name, "m.mtl:3", &t);
    ASSERT_TRUE(s.ok()) << s.ToString();
    EXPECT_EQ(t.width, 8u);
    EXPECT_EQ(t.height, 4u);
    ASSERT_EQ(t.rgb.size(), 8u * 4u * 3u);
    // PNG exactly; JPEG to within its quantisation of a flat image.
    double tol = name == dir.File("a.png") ? 1e-9 : 0.02;
    EXPECT_NEAR(t.mean.x, SrgbToLinear(200), tol) << name;
    EXPECT_NEAR(t.mean.y, SrgbToLinear(100), tol) << name;
    EXPECT_NEAR(t.mean.z, SrgbToLinear(50), tol) << name;
  }
  // Not an image, and no file at all: errors at the map's line.
  test::WriteFile(dir.File("b.png"), "not an image");
  TextureImage t;
  Status s = ReadTexture(dir.File("b.png"), "m.mtl:3", &t);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.ToString(), "m.mtl:3: cannot read texture '" + dir.File("b.png") +
                              "': not a PNG, JPEG, BMP or TGA image");
  s = ReadTexture(dir.File("c.png"), "m.mtl:3", &t);
  EXPECT_EQ(s.ToString(), "m.mtl:3: cannot read texture '" + dir.File("c.png") + "': cannot open");
}

TEST(TextureTest, SamplingIsBilinearBetweenTexelCentresAndRepeats) {
  std::vector<uint8_t> c = Checker2();
  Texture t = TexView(c, 2, 2);
  // Texel centres: (0.25, 0.75) is the top-left texel (v = 1 is the top row).
  EXPECT_EQ(t.Sample({0.25f, 0.75f}).x, 1.0f);
  EXPECT_EQ(t.Sample({0.75f, 0.75f}).x, 0.0f);
  EXPECT_EQ(t.Sample({0.75f, 0.25f}).x, 1.0f);
  // Halfway between two texels, and across the wrap (u = 0 is between
  // texel columns 1 and 0).
  EXPECT_NEAR(t.Sample({0.5f, 0.75f}).x, 0.5f, 1e-6);
  EXPECT_NEAR(t.Sample({0.0f, 0.75f}).x, 0.5f, 1e-6);
  // Repeat: whole periods away, negative too.
  EXPECT_EQ(t.Sample({3.25f, -1.25f}).x, 1.0f);
  EXPECT_EQ(t.Sample({-0.25f, 0.75f}).x, 0.0f);
  EXPECT_EQ(t.Sample({NAN, INFINITY}).x, t.Sample({0.0f, 0.0f}).x);
}

TEST(TextureTest, PatchMeanOfACheckerItCoversIsHalf) {
  std::vector<uint8_t> c = Checker2();
  Texture t = TexView(c, 2, 2);
  Patch quad = Square();
  glm::vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  glm::dvec3 m = PatchTextureMean(t, quad, uv);
  EXPECT_NEAR(m.x, 0.5, 1e-9);
  EXPECT_NEAR(m.y, 0.5, 1e-9);
  // Three periods each way (repeat), and a triangle over half the square.
  glm::vec2 uv3[4] = {{0, 0}, {3, 0}, {3, 3}, {0, 3}};
  EXPECT_NEAR(PatchTextureMean(t, quad, uv3).x, 0.5, 1e-6);
  Patch tri = quad;
  tri.numCorners = 3;
  tri.corner[2] = tri.corner[3] = {0, 1, 0};
  glm::vec2 uvt[4] = {{0, 0}, {1, 0}, {0, 1}, {0, 1}};
  EXPECT_NEAR(PatchTextureMean(t, tri, uvt).x, 0.5, 1e-3);
  // A patch over the top-left texel's inner quarter only: white.
  glm::vec2 uvw[4] = {{0.15f, 0.65f}, {0.35f, 0.65f}, {0.35f, 0.85f}, {0.15f, 0.85f}};
  EXPECT_GT(PatchTextureMean(t, quad, uvw).x, 0.6);
  glm::vec2 uvb[4] = {{0.65f, 0.65f}, {0.85f, 0.65f}, {0.85f, 0.85f}, {0.65f, 0.85f}};
  EXPECT_LT(PatchTextureMean(t, quad, uvb).x, 0.4);
}

// Issue 40: texture means at init in time proportional to texels + patches.
// Counted: the pyramid's texels (built once a texture) and the samples a
// patch takes. A patch over the whole texture takes the same samples at
// 128^2 and at 1024^2 texels, where without the pyramid the samples grew
// with the texels it covers up to 4 096: the work is the texels' plus the
// patches', not their product. The means stay within 2% of the texels'
// exact mean, as the direct samples' do.
TEST(TextureTest, PatchMeansTakeWorkInProportionToTexelsPlusPatches) {
  auto make = [](uint32_t n) {
    std::vector<uint8_t> texels(size_t(n) * n * 3);
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x)
        for (int c = 0; c < 3; ++c)
          texels[(size_t(y) * n + x) * 3 + c] = static_cast<uint8_t>(
              60 + (x * 7 + y * 3) % 100 + ((x / 4 + y / 4) % 2) * 60 + c * 10);
    return texels;
  };
  // The exact mean of the linear texels over [0, f]^2 of the texture (f
  // a whole number of texels).
  auto exact = [](const std::vector<uint8_t>& texels, uint32_t n, uint32_t cols, int c) {
    double s = 0.0;
    for (uint32_t y = n - cols; y < n; ++y)  // v in [0, f]: the bottom rows
      for (uint32_t x = 0; x < cols; ++x) s += SrgbToLinear(texels[(size_t(y) * n + x) * 3 + c]);
    return s / (double(cols) * cols);
  };
  Patch quad = Square();
  uint64_t perPatch[2] = {0, 0}, pyramidTexels[2] = {0, 0};
  const uint32_t sizes[2] = {128, 1024};
  for (int k = 0; k < 2; ++k) {
    const uint32_t n = sizes[k];
    std::vector<uint8_t> texels = make(n);
    Texture t = TexView(texels, n, n);
    TexturePyramid py = BuildPyramid(t);
    pyramidTexels[k] = py.texels.size() / 3;
    for (float f : {1.0f, 0.25f}) {
      glm::vec2 uv[4] = {{0, 0}, {f, 0}, {f, f}, {0, f}};
      uint64_t direct = 0, levelled = 0;
      glm::dvec3 a = PatchTextureMean(t, quad, uv, nullptr, &direct);
      glm::dvec3 b = PatchTextureMean(t, quad, uv, &py, &levelled);
      EXPECT_EQ(direct, 4096u) << n;  // the direct cap (n = 64)
      EXPECT_LE(levelled, uint64_t(kDirectSamples) * kDirectSamples) << n;
      const uint32_t cols = static_cast<uint32_t>(f * n);
      for (int c = 0; c < 3; ++c) {
        const double e = exact(texels, n, cols, c);
        EXPECT_NEAR(a[c], e, 0.02 * e) << n << " " << f << " direct " << c;
        EXPECT_NEAR(b[c], e, 0.02 * e) << n << " " << f << " levelled " << c;
      }
      if (f == 1.0f) perPatch[k] = levelled;
    }
  }
  EXPECT_EQ(perPatch[0], perPatch[1]);  // independent of the texture's size
  // The pyramid: a third of the texels, in proportion to them.
  EXPECT_NEAR(static_cast<double>(pyramidTexels[0]), 128.0 * 128 / 3, 128.0);
  EXPECT_NEAR(static_cast<double>(pyramidTexels[1]) / pyramidTexels[0], 64.0, 0.5);
  // A patch of few texels keeps the texels themselves: the bytes of old.
  std::vector<uint8_t> texels = make(128);
  Texture t = TexView(texels, 128, 128);
  TexturePyramid py = BuildPyramid(t);
  glm::vec2 small[4] = {{0, 0}, {0.1f, 0}, {0.1f, 0.1f}, {0, 0.1f}};
  glm::dvec3 a = PatchTextureMean(t, quad, small), b = PatchTextureMean(t, quad, small, &py);
  EXPECT_EQ(a.x, b.x);
}

TEST(TextureTest, UvMapIsExactForTrianglesAndAffineCornersAndFitsTheRest) {
  Polygon tri;
  tri.corners = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
  tri.uv = {{0.5f, 0.5f}, {1.5f, 0.5f}, {0.2f, 2.0f}};
  tri.normal = {0, 0, 1};
  UvMap m = FitUvMap(tri);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(m.At(tri.corners[k]).x, tri.uv[k].x, 1e-6);
    EXPECT_NEAR(m.At(tri.corners[k]).y, tri.uv[k].y, 1e-6);
  }
  // A quad with a non-affine uv (one corner moved): least squares, so no
  // corner is exact but the centre is their mean.
  Polygon quad;
  quad.corners = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.uv = {{0, 0}, {1, 0}, {1.4f, 1.4f}, {0, 1}};
  quad.normal = {0, 0, 1};
  UvMap q = FitUvMap(quad);
  EXPECT_NEAR(q.At({0.5f, 0.5f, 0}).x, 0.6f, 1e-6);
  EXPECT_GT(std::fabs(q.At(quad.corners[2]).x - 1.4f), 0.1f);
  // No uv: the zero map.
  Polygon none = quad;
  none.uv.clear();
  EXPECT_EQ(FitUvMap(none).At({1, 1, 0}), glm::vec2(0.0f));
}

TEST(TextureTest, PartitionGivesCutPiecesTheSourcesUv) {
  Scene scene;
  Polygon p;
  p.corners = {{0, 0, 0}, {4, 0, 0}, {4, 2, 0}, {0, 2, 0}};
  p.uv = {{0, 0}, {2, 0}, {2, 1}, {0, 1}};
  p.normal = {0, 0, 1};
  p.area = 8.0;
  scene.polygons.push_back(p);
  scene.materials.resize(1);
  scene.bounds.lo = {0, 0, 0};
  scene.bounds.hi = {4, 2, 0};
  EnvGrid grid;
  grid.n[0] = 4;
  grid.box = scene.bounds;
  Partition part;
  ASSERT_TRUE(PartitionScene(scene, grid, &part).ok());
  ASSERT_EQ(part.scene.polygons.size(), 4u);
  for (const Polygon& piece : part.scene.polygons) {
    ASSERT_EQ(piece.uv.size(), piece.corners.size());
    for (size_t k = 0; k < piece.corners.size(); ++k) {
      EXPECT_NEAR(piece.uv[k].x, piece.corners[k].x / 2, 1e-6);
      EXPECT_NEAR(piece.uv[k].y, piece.corners[k].y / 2, 1e-6);
    }
  }
}

// A scene in `dir`: a floor with material `floorMtl` and a light; `mtl` is
// the MTL's text (materials "light" and the floor's).
void WriteScene(const TempDir& dir, const std::string& mtl, const std::string& floorMtl = "tex") {
  test::WriteFile(dir.File("s.mtl"), mtl);
  test::WriteFile(dir.File("s.obj"),
                  "mtllib s.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                  "usemtl " +
                      floorMtl +
                      "\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 1/1 2/2 3/3 4/4\n"
                      "usemtl light\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nf 5 6 7 8\n");
}

void WritePng(const std::string& path, int w, int h, uint8_t a, uint8_t b) {
  std::vector<uint8_t> img(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) img[(size_t(y) * w + x) * 3 + c] = (x + y) % 2 ? b : a;
  ASSERT_NE(stbi_write_png(path.c_str(), w, h, 3, img.data(), w * 3), 0);
}

const char kLight[] = "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n";

TEST(TextureTest, KdZeroWithAMapWarnsOnceNamingTheMaterials) {
  TempDir dir;
  WritePng(dir.File("t.png"), 4, 4, 200, 20);
  WriteScene(dir, std::string(kLight) +
                      "newmtl tex\nKd 0 0 0\nmap_Kd t.png\n"
                      "newmtl tex2\nmap_Kd t.png\n"
                      "newmtl tex3\nKd 0.5 0.5 0.5\nmap_Kd t.png\n");
  // Two floors (tex and tex2), one with Kd: one warning naming both others.
  test::WriteFile(dir.File("s.obj"),
                  ReadFile(dir.File("s.obj")) +
                      "usemtl tex2\nv 0 0 2\nv 0 0 3\nv 1 0 3\nv 1 0 2\nf 9/1 10/2 11/3 12/4\n"
                      "usemtl tex3\nv 0 0 4\nv 0 0 5\nv 1 0 5\nv 1 0 4\nf 13/1 14/2 15/3 16/4\n");
  Scene scene;
  ASSERT_TRUE(LoadScene(dir.File("s.obj"), &scene).ok());
  SceneTextures t;
  ASSERT_TRUE(LoadSceneTextures(&scene, &t).ok());
  ASSERT_EQ(t.warnings.size(), 1u);
  EXPECT_EQ(t.warnings[0], dir.File("s.mtl") +
                               ":6: warning: Kd 0 0 0 with map_Kd: the map alone "
                               "is the reflectance (Kd taken as 1) for materials 'tex', 'tex2'");
  ASSERT_EQ(t.images.size(), 1u);  // one file, read once
  EXPECT_EQ(t.kdOfMaterial[1], glm::vec3(1.0f));
  EXPECT_EQ(t.kdOfMaterial[3], glm::vec3(0.5f));
  // The command line prints it once.
  auto r =
      RunMain({"render", dir.File("s.obj"), "--out", dir.File("out"), "--rays", "64", "--max-shots",
               "20", "--width", "16", "--height", "16", "--patch-size", "2", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  size_t at = r.err.find("Kd 0 0 0 with map_Kd");
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("Kd 0 0 0 with map_Kd", at + 1), std::string::npos) << r.err;
  // The map alone: the floor's kd (one patch) is the texture's mean, not 0.
  auto rows = test::ReadCsv(dir.File("out/patches.csv"));
  double kd = std::stod(rows[1][9]);
  EXPECT_NEAR(kd, (SrgbToLinear(200) + SrgbToLinear(20)) / 2, 0.02);
}

// Kd 1 is a perfect reflector (issue 16): so is a white texel of a map used
// alone (Kd 0 0 0), where it was refused while Kd had to stay below 1.
TEST(TextureTest, KdZeroWithWhiteTexelsIsAPerfectReflector) {
  TempDir dir;
  WritePng(dir.File("t.png"), 4, 4, 255, 20);
  WriteScene(dir, std::string(kLight) + "newmtl tex\nKd 0 0 0\nmap_Kd t.png\n");
  auto r = RunMain({"render", dir.File("s.obj"), "--out", dir.File("out"), "--quiet"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("Kd 0 0 0 with map_Kd"), std::string::npos) << r.err;
  auto rows = test::ReadCsv(dir.File("out/patches.csv"));
  double kd = std::stod(rows[1][9]);
  EXPECT_NEAR(kd, (SrgbToLinear(255) + SrgbToLinear(20)) / 2, 0.02);
}

// A texture not found is an error with --strict (without, a warning:
// scene_forgiving_test.cpp); one that cannot be decoded always.
TEST(TextureTest, MissingOrUnreadableTextureIsAnErrorAtItsLine) {
  TempDir dir;
  WriteScene(dir, std::string(kLight) + "newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd -bm 1 missing.png\n");
  auto r = RunMain({"render", dir.File("s.obj"), "--out", dir.File("out"), "--quiet", "--strict"});
  EXPECT_EQ(r.code, 2);
  std::string expect = dir.File("s.mtl") + ":6: cannot read texture '" + dir.File("missing.png") +
                       "': cannot open\n";
  EXPECT_NE(r.err.find(expect), std::string::npos) << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
  // footprint reads the textures too (their bytes count).
  r = RunMain({"footprint", dir.File("s.obj"), "--strict"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(expect), std::string::npos) << r.err;
  // A truncated PNG.
  WritePng(dir.File("t.png"), 4, 4, 200, 20);
  std::string png = ReadFile(dir.File("t.png"));
  test::WriteFile(dir.File("cut.png"), png.substr(0, png.size() / 2));
  WriteScene(dir, std::string(kLight) + "newmtl tex\nKd 0.5 0.5 0.5\nmap_Kd cut.png\n");
  r = RunMain({"render", dir.File("s.obj"), "--out", dir.File("out"), "--quiet"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(
      r.err.find(dir.File("s.mtl") + ":6: cannot read texture '" + dir.File("cut.png") + "': "),
      std::string::npos)
      << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("out")));
  // A material no face uses is not read.
  WriteScene(
      dir, std::string(kLight) + "newmtl tex\nKd 0.5 0.5 0.5\nnewmtl unused\nmap_Kd missing.png\n");
  r = RunMain({"render", dir.File("s.obj"), "--out", dir.File("out"), "--rays", "64", "--max-shots",
               "10", "--width", "16", "--height", "16", "--quiet"});
  EXPECT_EQ(r.code, 0) << r.err;
}

// scenes/textured/room.obj seen from above: a patch of floor away from the
// block, lit from the ceiling light, where squares of the checker are 1.25
// units wide (uv = (z, x) / 5, 4 squares per period). Patches of 2.5 units
// each cover 2 x 2 squares, so every floor patch reflects the same mean:
// the checker in the image is the per-pixel texture alone.
TEST(TextureTest, TheImageShowsTheCheckerWhileTheSolveUsesItsMean) {
  TempDir dir;
  for (const char* aa : {"on", "off"}) {
    const std::string out = dir.File(std::string("aa") + aa);
    auto r =
        RunMain({"render", "scenes/textured/room.obj", "--out", out, "--emitted-rays", "300000",
                 "--width", "96", "--height", "96", "--camera", "7.5,8,2.5,7.5,0,2.5,0,0,1,30",
                 "--aa", aa, "--patch-size", "2.5", "--quiet"});
    ASSERT_EQ(r.code, 0) << r.err;
    PfmImage img;
    ASSERT_TRUE(ReadPfm(out + "/image.pfm", &img).ok());
    Camera cam;
    cam.eye = {7.5f, 8.0f, 2.5f};
    cam.target = {7.5f, 0.0f, 2.5f};
    cam.up = {0.0f, 0.0f, 1.0f};
    cam.fovyDeg = 30.0f;
    View view;
    ASSERT_TRUE(MakeView(cam, 96, 96, &view));
    // The checker's texture, to tell bright squares from dark.
    TextureImage tex;
    ASSERT_TRUE(ReadTexture("scenes/textured/checker.png", "room.mtl:4", &tex).ok());
    Texture t = tex.View();
    int bright = 0, dark = 0, checked = 0;
    // Square centres in view: x and z at 1.25 (k + 1/2).
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) {
        glm::vec3 x(1.25f * (i + 0.5f), 0.0f, 1.25f * (j + 0.5f));
        glm::vec3 d = x - view.eye;
        float depth = glm::dot(d, view.forward);
        float px = 48.0f + view.focal * glm::dot(d, view.right) / depth;
        float py = 48.0f - view.focal * glm::dot(d, view.up) / depth;
        if (px < 4 || px > 92 || py < 4 || py > 92) continue;
        int row = static_cast<int>(py), col = static_cast<int>(px);
        float value = img.pixels[(size_t(row) * 96 + col) * 3 + 1];
        // The same point one square over along x: the other colour.
        glm::vec3 x2 = x + glm::vec3(1.25f, 0.0f, 0.0f);
        glm::vec3 d2 = x2 - view.eye;
        float depth2 = glm::dot(d2, view.forward);
        float qx = 48.0f + view.focal * glm::dot(d2, view.right) / depth2;
        float qy = 48.0f - view.focal * glm::dot(d2, view.up) / depth2;
        if (qx < 4 || qx > 92 || qy < 4 || qy > 92) continue;
        float other =
            img.pixels[(size_t(static_cast<int>(qy)) * 96 + static_cast<int>(qx)) * 3 + 1];
        bool isBright = t.Sample(glm::vec2(x.z / 5.0f, x.x / 5.0f)).y > 0.5f;
        ASSERT_NE(isBright, t.Sample(glm::vec2(x2.z / 5.0f, x2.x / 5.0f)).y > 0.5f);
        // linear 0.83 against 0.021 under nearly the same light
        if (isBright)
          EXPECT_GT(value, 10.0f * other) << aa << " square " << i << "," << j;
        else
          EXPECT_LT(10.0f * value, other) << aa << " square " << i << "," << j;
        (isBright ? bright : dark)++;
        ++checked;
      }
    EXPECT_GE(checked, 6) << aa;
    EXPECT_GT(bright, 0);
    EXPECT_GT(dark, 0);
    // The solve: each floor patch's kd is 0.8 times the texture's mean over
    // it, here the whole texture's.
    auto rows = test::ReadCsv(out + "/patches.csv");
    double area = 0.0;
    for (size_t k = 1; k < rows.size(); ++k) {
      if (std::stod(rows[k][3]) != 0.0 || std::stod(rows[k][6]) != 1.0) continue;  // floor: y 0, up
      area += std::stod(rows[k][8]);
      EXPECT_NEAR(std::stod(rows[k][9]), 0.8 * tex.mean.y, 1e-4) << k;
    }
    EXPECT_NEAR(area, 100.0, 1e-3);
  }
}

// The texture fuzz target's seeds (tests/fuzz/texture-corpus, make fuzz):
// each decodes, from its bytes as from its file, to the same image; except
// jpeg-dc-overflow, a corrupt JPEG kept as a seed, which is refused.
TEST(TextureTest, TextureFuzzSeedsDecode) {
  int seen = 0;
  for (const auto& entry : std::filesystem::directory_iterator("tests/fuzz/texture-corpus")) {
    const std::string path = entry.path().string();
    TextureImage fromFile, fromBytes;
    Status a = ReadTexture(path, "m.mtl:1", &fromFile);
    Status b = DecodeTexture(test::ReadFile(path), path, "m.mtl:1", &fromBytes, uint64_t{64} << 20);
    if (entry.path().filename() == "jpeg-dc-overflow") {
      EXPECT_NE(a.ToString().find("': corrupt JPEG: Corrupt JPEG data"), std::string::npos)
          << a.ToString();
      EXPECT_EQ(a.ToString(), b.ToString());
      ++seen;
      continue;
    }
    ASSERT_TRUE(a.ok()) << a.ToString();
    ASSERT_TRUE(b.ok()) << b.ToString();
    EXPECT_EQ(fromFile.rgb, fromBytes.rgb) << path;
    EXPECT_GT(fromFile.width, 0u);
    ++seen;
  }
  EXPECT_GE(seen, 7);
}

}  // namespace
}  // namespace vismask
