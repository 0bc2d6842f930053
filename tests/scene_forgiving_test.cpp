// Scenes as published (issue 40): faces before any 'usemtl', a missing MTL
// file, an undefined material, a texture not found or named in another
// letter case, map_Kd names with spaces. Each is repaired with exactly one
// warning line naming file:line, and --strict still refuses it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "scene_test_util.h"
#include "test_util.h"
#include "vismask/scene/texture.h"

namespace vismask {
namespace {

using test::ExpectError;
using test::kStrict;
using test::RunMain;
using test::SceneTest;

// The lines of `warnings` that contain `word`.
std::vector<std::string> With(const std::vector<std::string>& warnings, const std::string& word) {
  std::vector<std::string> out;
  for (const std::string& w : warnings)
    if (w.find(word) != std::string::npos) out.push_back(w);
  return out;
}

// The lines of a run's stderr that contain `word`.
size_t CountLines(const std::string& err, const std::string& word) {
  size_t n = 0, at = 0;
  while ((at = err.find(word, at)) != std::string::npos) {
    ++n;
    at += word.size();
  }
  return n;
}

const char kTwoTriangles[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";

TEST_F(SceneTest, FacesBeforeAnyUsemtlGetTheDefaultGrey) {
  // The 2005 Sponza's shape: no mtllib, no usemtl; then a light.
  Write("m.mtl", test::kMtl);
  const std::string text = std::string(kTwoTriangles) + "mtllib m.mtl\nusemtl light\nf 1 2 4\n";
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadObjWarnings(Write("s.obj", text), &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 3u);
  const Material& m = scene.materials[scene.polygons[0].material];
  EXPECT_EQ(m.kd, glm::vec3(0.5f));
  EXPECT_EQ(m.ke, glm::vec3(0.0f));
  EXPECT_EQ(scene.polygons[1].material, scene.polygons[0].material);
  auto lines = With(warnings, "usemtl");
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], obj() +
                          ":5: warning: faces before any 'usemtl': they get the default grey "
                          "material 'default' (Kd 0.5)");
  ExpectError(LoadScene(obj(), &scene, kStrict), obj(), 5, "face before any 'usemtl'");
}

TEST_F(SceneTest, AMissingMtlAndUndefinedMaterialsGetTheDefaultGrey) {
  // Sibenik's shape: the MTL it names is not there.
  const std::string text = "mtllib gone.mtl\nusemtl glass\n" + std::string(kTwoTriangles) +
                           "usemtl stone\nf 1 2 4\nusemtl glass\nf 1 4 3\n";
  Scene scene;
  std::vector<std::string> warnings;
  LoadOptions emit;
  emit.emit.push_back({"glass", false, glm::vec3(2.0f)});
  Status s = LoadObjWarnings(Write("s.obj", text), &scene, &warnings, emit);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.materials.size(), 2u);
  EXPECT_EQ(scene.materials[0].name, "glass");
  EXPECT_EQ(scene.materials[0].kd, glm::vec3(0.5f));
  EXPECT_EQ(scene.materials[0].ke, glm::vec3(2.0f));  // --emit names a material only the OBJ uses
  EXPECT_EQ(scene.materials[1].kd, glm::vec3(0.5f));
  EXPECT_EQ(scene.polygons[3].material, 0u);
  auto mtl = With(warnings, "gone.mtl");
  ASSERT_EQ(mtl.size(), 1u);
  EXPECT_EQ(mtl[0], obj() + ":1: warning: MTL file '" + dir_ +
                        "gone.mtl' not found: the materials it defines get the default grey "
                        "(Kd 0.5)");
  auto undefined = With(warnings, "no MTL defines");
  ASSERT_EQ(undefined.size(), 1u);
  EXPECT_EQ(undefined[0].rfind(obj() + ":2: warning: 2 materials that no MTL defines", 0), 0u)
      << undefined[0];
  EXPECT_NE(undefined[0].find("'glass', 'stone'"), std::string::npos) << undefined[0];
  // Without --emit: no emitter, and the error names the made-up materials.
  s = LoadScene(obj(), &scene);
  ExpectError(s, obj(), 0, "no emitter");
  EXPECT_NE(s.message().find("materials no MTL defines: 'glass', 'stone'"), std::string::npos)
      << s.ToString();
  ExpectError(LoadScene(obj(), &scene, kStrict), obj(), 1, "gone.mtl");
}

TEST_F(SceneTest, AnUndefinedMaterialIsGreyAndEmitMayNameIt) {
  // CornellBox-Glossy's shape: the MTL is there, 'light' is not in it.
  Write("m.mtl", "newmtl white\nKd 0.7 0.7 0.7\n");
  const std::string text =
      "mtllib m.mtl\nusemtl white\n" + std::string(kTwoTriangles) + "usemtl light\nf 1 2 4\n";
  Scene scene;
  std::vector<std::string> warnings;
  LoadOptions emit;
  emit.emit.push_back({"light", false, glm::vec3(5.0f)});
  Status s = LoadObjWarnings(Write("s.obj", text), &scene, &warnings, emit);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], obj() +
                             ":9: warning: 1 material that no MTL defines, given the default grey "
                             "(Kd 0.5; --emit NAME=R,G,B makes one an emitter; first here): "
                             "'light'");
  EXPECT_EQ(scene.materials[1].ke, glm::vec3(5.0f));
  ExpectError(LoadScene(obj(), &scene, kStrict), obj(), 9, "undefined material 'light'");
}

TEST_F(SceneTest, MapKdNamesMayHoldSpaces) {
  Write("m.mtl", std::string(test::kMtl) +
                     "newmtl a\nmap_Kd my tex.png\n"
                     "newmtl b\nmap_Kd -s 1 1 1 -bm 0.5 -clamp on  two  spaces.png \n"
                     "newmtl c\nmap_Kd -o 1 plain.png # a comment\n");
  Scene scene;
  std::vector<std::string> warnings;
  Status s =
      LoadObjWarnings(Write("s.obj", test::kHead + std::string("f 1 2 3\n")), &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(scene.materials[2].mapKd, dir_ + "my tex.png");
  EXPECT_EQ(scene.materials[3].mapKd, dir_ + "two  spaces.png");
  EXPECT_EQ(scene.materials[4].mapKd, dir_ + "plain.png");
  EXPECT_EQ(With(warnings, "ignoring map_Kd options").size(), 1u);
}

// A floor with texture coordinates under a light, its material's map_Kd
// `map` and Kd `kd`.
void WriteTexturedScene(const test::TempDir& dir, const std::string& map, const std::string& kd) {
  test::WriteFile(dir.File("s.mtl"), "newmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\nnewmtl tex\nKd " +
                                         kd + "\nmap_Kd " + map + "\n");
  test::WriteFile(dir.File("s.obj"),
                  "mtllib s.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\n"
                  "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 1/1 2/2 3/3 4/4\n"
                  "usemtl light\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nf 5 6 7 8\n");
}

// A 2 x 2 BMP of one colour (enough for stb_image; no writer needed).
std::string Bmp(uint8_t r, uint8_t g, uint8_t b) {
  std::string f = "BM";
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) f += static_cast<char>((v >> (8 * i)) & 255);
  };
  auto u16 = [&](uint16_t v) {
    f += static_cast<char>(v & 255);
    f += static_cast<char>(v >> 8);
  };
  u32(54 + 16);
  u32(0);
  u32(54);
  u32(40);
  u32(2);
  u32(2);
  u16(1);
  u16(24);
  u32(0);
  u32(16);
  u32(2835);
  u32(2835);
  u32(0);
  u32(0);
  for (int row = 0; row < 2; ++row) {
    for (int x = 0; x < 2; ++x) {
      f += static_cast<char>(b);
      f += static_cast<char>(g);
      f += static_cast<char>(r);
    }
    f += std::string(2, '\0');  // rows padded to 4 bytes
  }
  return f;
}

// The floor's kd (patches.csv column 9) of a render of dir/s.obj.
double FloorKd(const test::TempDir& dir) {
  auto rows = test::ReadCsv(dir.File("out/patches.csv"));
  return std::stod(rows[1][9]);
}

const std::vector<std::string> kQuick = {"--rays",   "64", "--max-shots",  "10", "--width", "16",
                                         "--height", "16", "--patch-size", "2",  "--quiet"};

test::RunResult Render(const test::TempDir& dir, std::vector<std::string> extra = {},
                       const std::string& out = "out") {
  std::vector<std::string> args = {"render", dir.File("s.obj"), "--out", dir.File(out)};
  args.insert(args.end(), kQuick.begin(), kQuick.end());
  args.insert(args.end(), extra.begin(), extra.end());
  return RunMain(args);
}

TEST(SceneForgivingTest, ATextureInAnotherLetterCaseIsFoundWithOneWarning) {
  test::TempDir dir;
  test::WriteFile(dir.File("sp_luk.JPG"), Bmp(200, 200, 200));  // a BMP under any name
  WriteTexturedScene(dir, "SP_LUK.JPG", "0.5 0.5 0.5");
  EXPECT_EQ(FindTexture(dir.File("SP_LUK.JPG")), dir.File("sp_luk.JPG"));
  EXPECT_EQ(FindTexture(dir.File("sp_luk.JPG")), dir.File("sp_luk.JPG"));
  EXPECT_EQ(FindTexture(dir.File("nothere.png")), "");
  auto r = Render(dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(CountLines(r.err, "warning:"), 1u) << r.err;
  EXPECT_NE(r.err.find(dir.File("s.mtl") +
                       ":6: warning: 1 texture found in another letter case (first here): '" +
                       dir.File("SP_LUK.JPG") + "' as 'sp_luk.JPG'"),
            std::string::npos)
      << r.err;
  EXPECT_NEAR(FloorKd(dir), 0.5 * SrgbToLinear(200), 1e-4);
  r = Render(dir, {"--strict"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("s.mtl") + ":6: cannot read texture"), std::string::npos) << r.err;
}

TEST(SceneForgivingTest, ATextureNotFoundLeavesKdOrGreyWithOneWarning) {
  test::TempDir dir;
  WriteTexturedScene(dir, "missing.png", "0.25 0.5 0.75");
  auto r = Render(dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(CountLines(r.err, "warning:"), 1u) << r.err;
  EXPECT_NE(r.err.find(dir.File("s.mtl") + ":6: warning: 1 texture not found"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("'" + dir.File("missing.png") + "' (tex)"), std::string::npos) << r.err;
  EXPECT_NEAR(FloorKd(dir), 0.25, 1e-6);  // Kd as written (red, column 9)
  // Kd 0 0 0: the map was all the reflectance; without it, grey 0.5.
  WriteTexturedScene(dir, "missing.png", "0 0 0");
  r = Render(dir);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(CountLines(r.err, "warning:"), 1u) << r.err;
  EXPECT_NEAR(FloorKd(dir), 0.5, 1e-6);
  r = Render(dir, {"--strict"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("s.mtl") + ":6: cannot read texture '" + dir.File("missing.png") +
                       "': cannot open"),
            std::string::npos)
      << r.err;
}

// The command line: each repair one warning line on stderr, --strict exit 2
// with the refusal, nothing written.
TEST(SceneForgivingTest, TheCommandLineWarnsOnceAndStrictRefuses) {
  test::TempDir dir;
  test::WriteFile(dir.File("s.obj"),
                  "mtllib gone.mtl\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nf 1 2 3 4\n"
                  "usemtl lamp\nv 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nf 5 6 7 8\n");
  auto r = Render(dir, {"--emit", "lamp=1,1,1"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(CountLines(r.err, "warning:"), 3u) << r.err;
  EXPECT_EQ(CountLines(r.err, "gone.mtl' not found"), 1u) << r.err;
  EXPECT_EQ(CountLines(r.err, "faces before any 'usemtl'"), 1u) << r.err;
  EXPECT_EQ(CountLines(r.err, "no MTL defines"), 1u) << r.err;
  r = Render(dir, {"--emit", "lamp=1,1,1", "--strict"}, "strict");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(dir.File("s.obj") + ":1: "), std::string::npos) << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("strict")));
}

}  // namespace
}  // namespace vismask
