// Faces, reflectance and lights as users bring them (issue 16): non-planar,
// degenerate and self-intersecting faces, perfect reflectors, --emit.
#include <gtest/gtest.h>

#include <algorithm>
#include <glm/geometric.hpp>
#include <string>
#include <vector>

#include "scene_test_util.h"
#include "vismask/scene/scene.h"

namespace vismask {
namespace {

using namespace test;

// --- Faces as they come (issue 16) -------------------------------------------

// A quad with corner 3 (1, 1, 0.1) raised: split along 2-4 (1-based), whose
// triangles are the flatter pair (cos 1/sqrt(1 + 2h^2) against 1/(1 + h^2));
// the triangles carry their corners' uv and vn and the face's group,
// material and line; one warning counts the faces.
TEST_F(SceneTest, NonPlanarQuadIsTriangulatedWithAWarning) {
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadBodyWarnings(
      "v 1 1 0.1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ns 4\n"
      "f 1/1/1 2/2/1 5/3/1 4/4/1\nf 1 2 5 4\n",
      &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 4u);
  const Polygon& a = scene.polygons[0];
  const Polygon& b = scene.polygons[1];
  EXPECT_EQ(a.corners, (std::vector<glm::vec3>{{1, 0, 0}, {1, 1, 0.1f}, {0, 1, 0}}));
  EXPECT_EQ(b.corners, (std::vector<glm::vec3>{{1, 0, 0}, {0, 1, 0}, {0, 0, 0}}));
  EXPECT_EQ(a.uv, (std::vector<glm::vec2>{{1, 0}, {1, 1}, {0, 1}}));
  EXPECT_EQ(b.uv, (std::vector<glm::vec2>{{1, 0}, {0, 1}, {0, 0}}));
  EXPECT_EQ(b.vn.size(), 3u);
  for (const Polygon& p : scene.polygons) {
    EXPECT_EQ(p.material, 1u);  // light
    EXPECT_GT(p.normal.z, 0.9f);
  }
  EXPECT_EQ(a.line, 14);
  EXPECT_EQ(b.line, 14);
  EXPECT_EQ(a.smoothing, 4u);
  EXPECT_EQ(b.smoothing, 4u);
  EXPECT_EQ(scene.polygons[2].line, 15);
  EXPECT_TRUE(scene.polygons[2].uv.empty());
  EXPECT_NEAR(a.area + b.area, 1.0, 0.01);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0],
            obj() +
                ":14: warning: 2 non-planar faces triangulated (first here; up to 0.0249 "
                "off their plane)");
}

// A concave non-planar quad keeps its side: only the diagonal from its
// reflex corner splits it (here the other pair would be flatter).
TEST_F(SceneTest, ConcaveNonPlanarQuadSplitsAtItsReflexCorner) {
  Scene scene;
  Status s = LoadBody("v 2 0 0\nv 0.5 0.5 0.3\nv 0 2 0\nf 1 5 6 7\n", &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 2u);
  for (const Polygon& p : scene.polygons) {
    EXPECT_GT(p.normal.z, 0.5f);
    EXPECT_NE(std::find(p.corners.begin(), p.corners.end(), glm::vec3(0.5f, 0.5f, 0.3f)),
              p.corners.end());
  }
}

// Larger non-planar faces are ear-clipped: n - 2 triangles covering it.
TEST_F(SceneTest, NonPlanarPentagonIsEarClipped) {
  Scene scene;
  Status s = LoadBody("v 0 0 0\nv 2 0 0\nv 2 2 0.2\nv 1 3 0\nv 0 2 0\nf -5 -4 -3 -2 -1\n", &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 3u);
  double area = 0.0;
  for (const Polygon& p : scene.polygons) {
    area += p.area;
    EXPECT_EQ(p.corners.size(), 3u);
    EXPECT_GT(p.normal.z, 0.9f);
  }
  EXPECT_NEAR(area, 5.0, 0.05);
}

// Zero-area faces (collinear corners, a repeated vertex leaving two) are
// dropped and counted in one line at the first.
TEST_F(SceneTest, DegenerateFacesAreDroppedWithACount) {
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadBodyWarnings("v 2 0 0\nf 1 2 5\nf 1 2 1\nf 1 2 3\nf 1 3 2 4\n", &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 1u);
  EXPECT_EQ(scene.polygons[0].line, 10);
  ASSERT_EQ(warnings.size(), 1u) << warnings[0];
  EXPECT_EQ(warnings[0], obj() +
                             ":8: warning: 3 degenerate faces dropped (zero area: repeated or "
                             "collinear vertices; first here)");
}

// A corner in the middle of an edge, or repeating its neighbour, is removed
// from an otherwise good face, which is kept (with its other corners' uv).
TEST_F(SceneTest, CollinearOrRepeatedCornersAreRemoved) {
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadBodyWarnings(
      "v 0.5 0 0\nvt 0 0\nvt 0.5 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 5/2 2/3 3/4 4/5\nf 1 2 2 3 4\n",
      &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 2u);
  const Polygon& p = scene.polygons[0];
  EXPECT_EQ(p.corners, (std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  EXPECT_EQ(p.uv, (std::vector<glm::vec2>{{0, 0}, {1, 0}, {1, 1}, {0, 1}}));
  EXPECT_DOUBLE_EQ(p.area, 1.0);
  EXPECT_EQ(scene.polygons[1].corners.size(), 4u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], obj() +
                             ":13: warning: 2 repeated or collinear corners removed from 2 faces "
                             "(first here)");
}

// A bow tie has no one reading: dropped, counted.
TEST_F(SceneTest, SelfIntersectingFacesAreDropped) {
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadBodyWarnings("v 2 2 0\nf 1 2 4 5\nf 1 2 3\n", &scene, &warnings);
  ASSERT_TRUE(s.ok()) << s.ToString();
  ASSERT_EQ(scene.polygons.size(), 1u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], obj() + ":8: warning: 1 self-intersecting face dropped (first here)");
}

// Mended or not, a good scene loads the same: Cornell's faces are untouched.
TEST_F(SceneTest, StrictAndMendedAgreeOnGoodScenes) {
  Scene a, b;
  ASSERT_TRUE(LoadScene("scenes/cornell.obj", &a).ok());
  ASSERT_TRUE(LoadScene("scenes/cornell.obj", &b, kStrict).ok());
  ASSERT_EQ(a.polygons.size(), b.polygons.size());
  for (size_t i = 0; i < a.polygons.size(); ++i) {
    EXPECT_EQ(a.polygons[i].corners, b.polygons[i].corners);
    EXPECT_EQ(a.polygons[i].normal, b.polygons[i].normal);
    EXPECT_EQ(a.polygons[i].area, b.polygons[i].area);
  }
}

// --- Reflectance and lights as they come (issue 16) -------------------------

// The box [lo, hi]^3's six faces (five if `open`: none at z = lo),
// counter-clockwise seen from inside (or, with `out`, from outside), after
// `head`, with indices relative to its 8 vertices.
std::string Box(const std::string& head, double lo, double hi, bool out = false,
                bool open = false) {
  std::string s = head;
  for (int k = 0; k < 8; ++k) {
    const int x[8] = {0, 1, 1, 0, 0, 1, 1, 0}, y[8] = {0, 0, 1, 1, 0, 0, 1, 1};
    s += "v " + std::to_string(x[k] ? hi : lo) + " " + std::to_string(y[k] ? hi : lo) + " " +
         std::to_string(k >= 4 ? hi : lo) + "\n";
  }
  const char* in[6] = {"1 2 3 4", "5 8 7 6", "1 5 6 2", "4 3 7 8", "1 4 8 5", "2 6 7 3"};
  const char* outward[6] = {"4 3 2 1", "6 7 8 5", "2 6 5 1", "8 7 3 4", "5 8 4 1", "3 7 6 2"};
  for (int f = open ? 1 : 0; f < 6; ++f) {
    std::string face = out ? outward[f] : in[f], rel;
    for (char ch : face) rel += ch == ' ' ? std::string(" ") : "-" + std::to_string(9 - (ch - '0'));
    s += "f " + rel + "\n";
  }
  return s;
}
std::string Cube(const std::string& head, bool out = false, bool open = false) {
  return Box(head, 0.0, 1.0, out, open);
}

TEST_F(SceneTest, PerfectReflectorIsAccepted) {
  Write("m.mtl", "newmtl light\nKd 1 1 1\nKe 1 1 1\n");
  Scene scene;
  ASSERT_TRUE(
      LoadScene(Write("s.obj", Cube("mtllib m.mtl\nusemtl light\n", false, true)), &scene).ok());
  EXPECT_EQ(scene.materials[0].kd, glm::vec3(1.0f));
  EXPECT_EQ(scene.polygons.size(), 5u);
  // Facing out, closed: light escapes.
  ASSERT_TRUE(LoadScene(Write("s.obj", Cube("mtllib m.mtl\nusemtl light\n", true)), &scene).ok());
  // Closed, facing in, but one face absorbs a little.
  Write("m.mtl", "newmtl light\nKd 1 1 1\nKe 1 1 1\nnewmtl grey\nKd 0.99 0.99 0.99\n");
  std::string box = Cube("mtllib m.mtl\nusemtl light\n");
  size_t last = box.rfind("f ");
  box.insert(last, "usemtl grey\n");
  Status s = LoadScene(Write("s.obj", box), &scene);
  EXPECT_TRUE(s.ok()) << s.ToString() << "\n" << box;
}

// A closed box facing in with Kd 1 in a channel cannot lose power there.
TEST_F(SceneTest, ClosedPerfectReflectorIsRefused) {
  Write("m.mtl", "newmtl light\nKd 0.5 1 1\nKe 1 1 1\n");
  Scene scene;
  ExpectError(LoadScene(Write("s.obj", Cube("mtllib m.mtl\nusemtl light\n")), &scene), obj(), 0,
              "the scene cannot lose power in the green channel: every face has Kd 1 there");
  // Blocks standing in the room, facing out, close nothing more.
  std::string room = Cube("mtllib m.mtl\nusemtl light\n");
  ExpectError(LoadScene(Write("s.obj", room + Box("", 0.2, 0.4, true)), &scene), obj(), 0,
              "cannot lose power");
  // A box facing in inside the room shows its back faces: accepted.
  EXPECT_TRUE(LoadScene(Write("s.obj", room + Box("", 0.2, 0.4)), &scene).ok());
}

TEST_F(SceneTest, EmitMakesAMaterialAnEmitter) {
  Write("m.mtl",
        "newmtl white\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0.8 0.8 0.8\nKa 20 10 5\n"
        "newmtl old\nKe 3 3 3\n");
  std::string path = Write("s.obj",
                           "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl white\nf 1 2 3\n"
                           "usemtl lamp\nf 1 2 3\nusemtl old\nf 1 2 3\n");
  Scene scene;
  std::vector<std::string> warnings;
  LoadOptions ka;
  ka.emit.push_back({"lamp", true, glm::vec3(0.0f)});
  ASSERT_TRUE(LoadObjWarnings(path, &scene, &warnings, ka).ok());
  EXPECT_EQ(scene.materials[1].ke, glm::vec3(20.0f, 10.0f, 5.0f));
  EXPECT_EQ(scene.materials[2].ke, glm::vec3(3.0f));
  EXPECT_TRUE(warnings.empty());
  LoadOptions rgb;
  rgb.emit.push_back({"white", false, glm::vec3(1.0f, 2.0f, 3.0f)});
  rgb.emit.push_back({"old", false, glm::vec3(0.0f)});
  ASSERT_TRUE(LoadObjWarnings(path, &scene, &warnings, rgb).ok());
  EXPECT_EQ(scene.materials[0].ke, glm::vec3(1.0f, 2.0f, 3.0f));
  EXPECT_EQ(scene.materials[2].ke, glm::vec3(0.0f));
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], mtl() + ":6: warning: --emit replaces the MTL's Ke of old (Ke 3 3 3)");
  // Turning the only light off leaves no emitter; a name no MTL defines is an error.
  LoadOptions off;
  off.emit.push_back({"old", false, glm::vec3(0.0f)});
  ExpectError(LoadScene(path, &scene, off), path, 0, "--emit");
  LoadOptions unknown;
  unknown.emit.push_back({"lmap", true, glm::vec3(0.0f)});
  Status s = LoadScene(path, &scene, unknown);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.ToString(), "vismask: --emit: no material 'lmap' in " + path +
                              " (its materials: white, lamp, old)");
}

// Malformed input: each names its file and line.

}  // namespace
}  // namespace vismask
