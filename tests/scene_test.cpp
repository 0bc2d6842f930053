// Loading OBJ and MTL files: the Cornell box, the statements and corner
// forms read, materials, and warnings.
#include "vismask/scene/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <glm/geometric.hpp>
#include <string>
#include <vector>

#include "scene_test_util.h"

namespace vismask {
namespace {

using namespace test;

TEST_F(SceneTest, LoadsCornellBox) {
  Scene scene;
  Status s = LoadScene("scenes/cornell.obj", &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(scene.objPath, "scenes/cornell.obj");
  // 16 surfaces; the non-planar left wall is two triangles.
  ASSERT_EQ(scene.polygons.size(), 17u);
  ASSERT_EQ(scene.materials.size(), 5u);
  // In file order; only the light emits.
  const char* names[] = {"white", "red", "green", "yellow", "light"};
  const glm::vec3 kd[] = {{0.725f, 0.71f, 0.68f},
                          {0.63f, 0.065f, 0.05f},
                          {0.14f, 0.45f, 0.091f},
                          {0.75f, 0.65f, 0.15f},
                          {0.78f, 0.78f, 0.78f}};
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(scene.materials[i].name, names[i]);
    EXPECT_EQ(scene.materials[i].kd, kd[i]);
    EXPECT_EQ(scene.materials[i].ke, i == 4 ? glm::vec3(17.0f, 12.0f, 4.0f) : glm::vec3(0.0f));
  }
  EXPECT_EQ(scene.materials[scene.polygons[6].material].name, "light");
  EXPECT_EQ(scene.materials[scene.polygons[16].material].name, "yellow");
  EXPECT_EQ(scene.bounds.lo, glm::vec3(0.0f));
  EXPECT_EQ(scene.bounds.hi, glm::vec3(556.0f, 548.8f, 559.2f));
  EXPECT_NEAR(scene.polygons[0].area, 308231.04, 0.1);       // floor
  EXPECT_NEAR(scene.polygons[6].area, 130.0 * 105.0, 1e-3);  // light
}

TEST_F(SceneTest, CornellNormalsFaceTheInterior) {
  Scene scene;
  ASSERT_TRUE(LoadScene("scenes/cornell.obj", &scene).ok());
  auto normal = [&](size_t i) { return scene.polygons[i].normal; };
  auto centroid = [&](size_t i) {
    glm::vec3 c(0.0f);
    for (const glm::vec3& v : scene.polygons[i].corners) c += v;
    return c / static_cast<float>(scene.polygons[i].corners.size());
  };
  const float eps = 1e-6f;
  EXPECT_LT(glm::length(normal(0) - glm::vec3(0, 1, 0)), eps);   // floor
  EXPECT_LT(glm::length(normal(1) - glm::vec3(0, -1, 0)), eps);  // ceiling
  EXPECT_LT(glm::length(normal(2) - glm::vec3(0, 0, -1)), eps);  // back wall
  EXPECT_LT(glm::length(normal(3) - glm::vec3(1, 0, 0)), eps);   // right wall (x = 0)
  EXPECT_LT(normal(4).x, -0.99f);                                // left wall, 2 triangles
  EXPECT_LT(normal(5).x, -0.99f);
  EXPECT_LT(glm::length(normal(6) - glm::vec3(0, -1, 0)), eps);  // light
  EXPECT_LT(glm::length(normal(7) - glm::vec3(0, 1, 0)), eps);   // short block top
  EXPECT_LT(glm::length(normal(12) - glm::vec3(0, 1, 0)), eps);  // tall block top
  // Room surfaces face the box's centre; block sides face away from the block.
  const glm::vec3 room(278.0f, 274.0f, 280.0f);
  for (size_t i = 0; i <= 6; ++i) EXPECT_GT(glm::dot(normal(i), room - centroid(i)), 0.0f) << i;
  for (size_t top : {7u, 12u}) {
    for (size_t i = top + 1; i <= top + 4; ++i) {
      glm::vec3 out = centroid(i) - centroid(top);
      out.y = 0.0f;
      EXPECT_NEAR(normal(i).y, 0.0f, eps) << i;
      EXPECT_GT(glm::dot(normal(i), out), 0.0f) << i;
    }
  }
  for (const Polygon& p : scene.polygons) EXPECT_NEAR(glm::length(p.normal), 1.0f, 1e-6f);
}

TEST_F(SceneTest, NegativeIndicesAndCornerForms) {
  Scene scene;
  Status s = LoadBody("vt 0 0\nvn 0 0 1\nf -4/1/1 -3//1 -2/1 -1\n", &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 1u);
  const Polygon& p = scene.polygons[0];
  ASSERT_EQ(p.corners.size(), 4u);
  EXPECT_EQ(p.corners[0], glm::vec3(0, 0, 0));
  EXPECT_EQ(p.corners[3], glm::vec3(0, 1, 0));
  EXPECT_EQ(p.normal, glm::vec3(0, 0, 1));
  EXPECT_DOUBLE_EQ(p.area, 1.0);
  EXPECT_EQ(p.line, 9);
}

TEST_F(SceneTest, TextureCoordinatesNormalsAndSmoothingGroups) {
  Scene scene;
  Status s = LoadBody(
      "vt 0 0\nvt 1 0\nvt 1 1 0\nvn 0 0 1\ns 3\nf 1/1/1 2/2/1 3/3/1\ns off\nf 1//1 3//1 4//1\n"
      "f 1/-3 3/-1 4/-1\n",
      &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 3u);
  const Polygon& a = scene.polygons[0];
  ASSERT_EQ(a.uv.size(), 3u);
  EXPECT_EQ(a.uv[1], glm::vec2(1.0f, 0.0f));
  EXPECT_EQ(a.uv[2], glm::vec2(1.0f, 1.0f));
  ASSERT_EQ(a.vn.size(), 3u);
  EXPECT_EQ(a.vn[0], glm::vec3(0.0f, 0.0f, 1.0f));
  EXPECT_EQ(a.smoothing, 3u);
  EXPECT_TRUE(scene.polygons[1].uv.empty());
  EXPECT_EQ(scene.polygons[1].vn.size(), 3u);
  EXPECT_EQ(scene.polygons[1].smoothing, 0u);
  EXPECT_EQ(scene.polygons[2].uv[0], glm::vec2(0.0f, 0.0f));
  EXPECT_TRUE(scene.polygons[2].vn.empty());
}

TEST_F(SceneTest, PerCornerDataIsAllOrNothingAndInRange) {
  Scene scene;
  std::vector<std::string> warnings;
  ASSERT_TRUE(LoadBodyWarnings("vt 0 0\nf 1/1 2 3\nf 1/1 3 4\n", &scene, &warnings).ok());
  EXPECT_TRUE(scene.polygons[0].uv.empty());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0],
            obj() + ":8: warning: texture coordinates on some corners of a face only: ignored");
  ExpectError(LoadBody("vt 0 0\nf 1/2 2/1 3/1\n", &scene), obj(), 8,
              "texture coordinate index 2 out of range (1 texture coordinates so far)");
  ExpectError(LoadBody("f 1//1 2//1 3//1\n", &scene), obj(), 7, "normal index 1 out of range");
  ExpectError(LoadBody("vn 0 0\n", &scene), obj(), 7, "'vn' needs 3 numbers");
  ExpectError(LoadBody("s -1\n", &scene), obj(), 7, "bad smoothing group");
}

TEST_F(SceneTest, AmbientColourAndDiffuseMapAreRead) {
  Write("m.mtl", std::string(kMtl) + "newmtl tex\nKa 20 20 20\nmap_Kd -bm 1 tex/wood.png\n");
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadObjWarnings(Write("s.obj", std::string(kHead) + "f 1 2 3\n"), &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.materials.size(), 3u);
  EXPECT_EQ(scene.materials[2].ka, glm::vec3(20.0f));
  EXPECT_EQ(scene.materials[2].mapKd, dir_ + "tex/wood.png");
  EXPECT_EQ(scene.materials[2].where, mtl() + ":6");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("ignoring map_Kd options"), std::string::npos) << warnings[0];
}

TEST_F(SceneTest, CrlfCommentsAndTrailingWhitespace) {
  Write("m.mtl", "# materials\r\nnewmtl light \r\nKd 0.5 0.5 0.5\t\r\nKe 1 1 1\r\n");
  std::string path = Write("s.obj",
                           "# a square\r\n\r\nmtllib m.mtl\r\no square  \r\ng sq\r\ns off\r\n"
                           "usemtl light\r\nv 0 0 0 1\r\nv 2 0 0\r\nv 2 2 0  # corner\r\n"
                           "  v 0 2 0\t\r\nf 1 2 3 4 \r\n");
  Scene scene;
  Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 1u);
  EXPECT_EQ(scene.materials[0].name, "light");
  EXPECT_EQ(scene.polygons[0].line, 12);
  EXPECT_DOUBLE_EQ(scene.polygons[0].area, 4.0);
  EXPECT_EQ(scene.bounds.hi, glm::vec3(2, 2, 0));
}

TEST_F(SceneTest, PentagonNormalAndArea) {
  Scene scene;
  // A notched pentagon in the plane x = 1, counter-clockwise about -x.
  Status s = LoadBody("v 1 0 0\nv 1 0 4\nv 1 1 2\nv 1 4 4\nv 1 4 0\nf -5 -4 -3 -2 -1\n", &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(scene.polygons[0].normal, glm::vec3(-1, 0, 0));
  EXPECT_DOUBLE_EQ(scene.polygons[0].area, 12.0);
}

TEST_F(SceneTest, SeveralMtlFilesRelativeToTheObj) {
  std::filesystem::create_directory(dir_ + "sub");
  Write("sub/a.mtl", "newmtl a\nKd 0.1 0.2 0.3\n");
  Write("sub/b.mtl", "newmtl b\nKe 1 0 0\n");
  std::string path = Write("sub/s.obj",
                           "mtllib a.mtl b.mtl\nmtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                           "usemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n");
  Scene scene;
  Status s = LoadScene(path, &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.materials.size(), 2u);
  EXPECT_EQ(scene.materials[scene.polygons[0].material].name, "a");
  EXPECT_EQ(scene.materials[scene.polygons[1].material].name, "b");
  EXPECT_EQ(scene.materials[0].kd, glm::vec3(0.1f, 0.2f, 0.3f));
}

// Keys that do not matter to diffuse radiosity are read silently; the rest
// are named in one line at the first.
TEST_F(SceneTest, UnknownMtlKeysWarnInOneLine) {
  Write("m.mtl",
        "newmtl light\nNs 10\nKd 0.5 0.5 0.5\nNs 20\nillum 2\nKe 1 1 1\nNi 1.5\nd 1\nTr 0\n"
        "Tf 1 1 1\nKs 0 0 0\nKa 0.5 0.5 0.5\nmap_d a.png\nmap_Ke b.png\nmap_d c.png\nrefl d.png\n");
  Scene scene;
  testing::internal::CaptureStderr();
  Status s = LoadScene(Write("s.obj", kHead + std::string("f 1 2 3\n")), &scene);
  std::string err = testing::internal::GetCapturedStderr();
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(err, mtl() + ":13: warning: ignoring MTL keys 'map_d', 'map_Ke' (first here)\n");
  // A typical McGuire MTL (Ns, Ni, illum 2, Ka, Ks 0, Ke 0 ...) says nothing.
  testing::internal::CaptureStderr();
  s = LoadScene("scenes/real/CornellBox-Original.obj", &scene, LoadOptions{true, {}});
  err = testing::internal::GetCapturedStderr();
  ExpectError(s, "scenes/real/CornellBox-Original.obj", 62, "non-planar");
  EXPECT_EQ(err, "");
}

// illum 3-9, Ks with a highlight, transparency: diffuse with their Kd, named
// in one line (only materials that faces use).
TEST_F(SceneTest, SpecularMaterialsAreNamedInOneWarning) {
  Write("m.mtl",
        std::string(kMtl) +
            "newmtl mirror\nKd 0.1 0.1 0.1\nillum 5\nnewmtl glass\nKd 0.2 0.2 0.2\nTf 0.1 0.1 0.1\n"
            "Ni 1.5\nillum 7\nnewmtl shiny\nKd 0.3 0.3 0.3\nKs 0.5 0.5 0.5\nillum 2\n"
            "newmtl matte\nKd 0.3 0.3 0.3\nKs 0.5 0.5 0.5\nillum 1\n"
            "newmtl unused\nillum 5\nnewmtl veil\nKd 0.5 0.5 0.5\nd 0.25\n");
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadObjWarnings(
      Write("s.obj",
            kHead + std::string(
                        "f 1 2 3\nusemtl mirror\nf 1 2 3\nusemtl glass\nf 1 2 3\n"
                        "usemtl shiny\nf 1 2 3\nusemtl matte\nf 1 2 3\nusemtl veil\nf 1 2 3\n")),
      &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], mtl() +
                             ":6: warning: specular materials rendered as diffuse with their Kd: "
                             "mirror (illum 5), glass (illum 7), shiny (Ks), veil (d 0.25)");
  EXPECT_EQ(scene.materials[3].kd, glm::vec3(0.2f));  // glass: its Kd, as diffuse
}

TEST_F(SceneTest, ErrorLeavesSceneUntouched) {
  Scene scene;
  scene.objPath = "before";
  EXPECT_FALSE(LoadBody("f 1 2 9\n", &scene).ok());
  EXPECT_EQ(scene.objPath, "before");
  EXPECT_TRUE(scene.polygons.empty());
}

}  // namespace
}  // namespace vismask
