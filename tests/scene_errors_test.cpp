// Scene errors: each names its file and line.
#include <gtest/gtest.h>

#include <string>

#include "scene_test_util.h"
#include "vismask/scene/scene.h"

namespace vismask {
namespace {

using namespace test;

TEST_F(SceneTest, MissingObj) {
  Scene scene;
  ExpectError(LoadScene(dir_ + "none.obj", &scene), dir_ + "none.obj", 0, "cannot open");
}

TEST_F(SceneTest, UnreadableObj) {
  Scene scene;
  ExpectError(LoadScene(dir_, &scene), dir_, 0, "cannot read");  // a directory
}

// Issue 17 item 11: mtllib may name any file. Only regular files are read;
// absolute names are used as they are; what is quoted back is a short,
// escaped excerpt, and lines that are no MTL statement are counted, never
// echoed (an /etc/shadow-like file printed its first fields).
TEST_F(SceneTest, MtllibReadsOnlyRegularFilesAndEchoesNothingOfThem) {
  Scene scene;
  ExpectError(LoadScene(Write("s.obj", "mtllib /dev/zero\n"), &scene), obj(), 1,
              "not a regular file");
  ExpectError(
      LoadScene(
          Write("s.obj", "mtllib ../" + dir_.substr(dir_.rfind('/', dir_.size() - 2) + 1) + "\n"),
          &scene),
      obj(), 1, "not a regular file");  // a directory
  // Absolute: used as it is (it was joined to the OBJ's directory: DIR//abs).
  Write("abs.mtl", kMtl);
  ASSERT_TRUE(LoadScene(Write("s.obj", "mtllib " + dir_ +
                                           "abs.mtl\nusemtl light\nv 0 0 0\nv 1 0 0\n"
                                           "v 0 1 0\nf 1 2 3\n"),
                        &scene)
                  .ok());
  // A file that is not MTL: its lines are counted, not quoted.
  Write("secret", std::string(kMtl) +
                      "root:$6$secrethash:19000:0:99999:7:::\n"
                      "daemon:*:19000:0:99999:7:::\n\x1b[31mred\n");
  std::vector<std::string> warnings;
  Status st =
      LoadObjWarnings(Write("s.obj", std::string("mtllib secret\n") + (kHead + 12) + "f 1 2 3\n"),
                      &scene, &warnings);
  ASSERT_TRUE(st.ok()) << st.ToString();
  std::string all;
  for (const std::string& w : warnings) all += w + "\n";
  EXPECT_EQ(all.find("secrethash"), std::string::npos) << all;
  EXPECT_EQ(all.find("root"), std::string::npos) << all;
  EXPECT_EQ(all.find('\x1b'), std::string::npos) << all;
  EXPECT_NE(all.find("3 lines are not MTL statements"), std::string::npos) << all;
  // A garbage statement in the OBJ is quoted short and escaped.
  Status bad = LoadBody(std::string("\x1b[2J") + std::string(5000, 'x') + "\n", &scene);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.message().find('\x1b'), std::string::npos);
  EXPECT_LT(bad.message().size(), 100u) << bad.message();
  EXPECT_NE(bad.message().find("unknown statement '\\x1b[2Jxxx"), std::string::npos)
      << bad.message();
}

// Issue 17 item 15: a UTF-8 byte-order mark gave "unknown statement 'mtllib'".
TEST_F(SceneTest, ByteOrderMarkIsSkipped) {
  Scene scene;
  Write("m.mtl", std::string("\xef\xbb\xbf") + kMtl);
  Status s = LoadScene(Write("s.obj", std::string("\xef\xbb\xbf") + kHead + "f 1 2 3\n"), &scene);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(scene.polygons.size(), 1u);
}

// --strict keeps the refusals the loader now repairs (scene_forgiving_test.cpp).
TEST_F(SceneTest, MissingMtl) {
  Scene scene;
  ExpectError(LoadScene(Write("s.obj", "v 0 0 0\nmtllib none.mtl\n"), &scene, kStrict), obj(), 2,
              "none.mtl");
}

TEST_F(SceneTest, BadNumber) {
  Scene scene;
  ExpectError(LoadBody("v 1 abc 0\n", &scene), obj(), 7, "bad number 'abc'");
}

TEST_F(SceneTest, PartlyParsedNumber) {
  Scene scene;
  ExpectError(LoadBody("v 1 2 3.5x\n", &scene), obj(), 7, "bad number '3.5x'");
}

TEST_F(SceneTest, NanNumber) {
  Scene scene;
  ExpectError(LoadBody("v nan 0 0\n", &scene), obj(), 7, "not finite");
}

TEST_F(SceneTest, InfiniteNumber) {
  Scene scene;
  ExpectError(LoadBody("v 0 0 -inf\n", &scene), obj(), 7, "not finite");
}

TEST_F(SceneTest, NumberBeyondFloat) {
  Scene scene;
  ExpectError(LoadBody("v 0 1e39 0\n", &scene), obj(), 7, "too large");
}

TEST_F(SceneTest, VertexArgumentCount) {
  Scene scene;
  ExpectError(LoadBody("v 1 2\n", &scene), obj(), 7, "needs 3 or 4");
}

TEST_F(SceneTest, IndexZero) {
  Scene scene;
  ExpectError(LoadBody("f 0 1 2\n", &scene), obj(), 7, "index 0");
}

TEST_F(SceneTest, IndexOutOfRange) {
  Scene scene;
  ExpectError(LoadBody("f 1 2 5\n", &scene), obj(), 7, "out of range");
}

TEST_F(SceneTest, NegativeIndexOutOfRange) {
  Scene scene;
  ExpectError(LoadBody("f -1 -2 -5\n", &scene), obj(), 7, "out of range");
}

TEST_F(SceneTest, BadFaceVertex) {
  Scene scene;
  ExpectError(LoadBody("f 1 2 3/1/1/1\n", &scene), obj(), 7, "bad face vertex");
  ExpectError(LoadBody("f 1.5 2 3\n", &scene), obj(), 7, "bad face vertex");
}

TEST_F(SceneTest, FaceWithTwoVertices) {
  Scene scene;
  ExpectError(LoadBody("f 1 2\n", &scene), obj(), 7, "3 or more");
}

TEST_F(SceneTest, RepeatedVertex) {
  Scene scene;
  ExpectError(LoadBody("f 1 2 2 3\n", &scene, kStrict), obj(), 7,
              "degenerate face: vertices 2 and 3 coincide");
}

TEST_F(SceneTest, CollinearVertices) {
  Scene scene;
  ExpectError(LoadBody("v 2 0 0\nf 1 2 5\n", &scene, kStrict), obj(), 8,
              "degenerate face: vertex 1 is collinear with its neighbours");
}

TEST_F(SceneTest, ZeroArea) {
  Scene scene;
  ExpectError(LoadBody("f 1 3 2 4\n", &scene, kStrict), obj(), 7,
              "degenerate face: zero area");  // a symmetric bow tie
}

TEST_F(SceneTest, SelfIntersecting) {
  Scene scene;
  ExpectError(LoadBody("v 2 2 0\nf 1 2 4 5\n", &scene, kStrict), obj(), 8,
              "self-intersecting face: edges 2 and 4 meet");
}

TEST_F(SceneTest, NonPlanar) {
  Scene scene;
  ExpectError(LoadBody("v 0 1 0.01\nf 1 2 3 5\n", &scene, kStrict), obj(), 8,
              "non-planar face: vertex 1 is 0.0025 off the face's plane (tolerance 0.000141)");
}

TEST_F(SceneTest, UndefinedMaterial) {
  Scene scene;
  ExpectError(LoadBody("usemtl nope\n", &scene, kStrict), obj(), 7, "undefined material 'nope'");
}

TEST_F(SceneTest, FaceBeforeUsemtl) {
  Write("m.mtl", kMtl);
  Scene scene;
  ExpectError(LoadScene(Write("s.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
                        &scene, kStrict),
              obj(), 5, "usemtl");
}

TEST_F(SceneTest, UnknownStatement) {
  Scene scene;
  ExpectError(LoadBody("vp 0.5 0.5\n", &scene), obj(), 7, "unknown statement 'vp'");
}

TEST_F(SceneTest, LinesNotSupported) {
  Scene scene;
  ExpectError(LoadBody("l 1 2\n", &scene), obj(), 7, "not supported");
}

TEST_F(SceneTest, KdOutOfRange) {
  ExpectMtlError("newmtl light\nKd 0.5 1.001 0.5\nKe 1 1 1\n", 2, "Kd must be in [0, 1], got 1");
}

TEST_F(SceneTest, KdNegative) {
  ExpectMtlError("newmtl light\nKe 1 1 1\nKd 0.5 -0.1 0.5\n", 3, "Kd must be in [0, 1]");
}

TEST_F(SceneTest, KdArgumentCount) {
  ExpectMtlError("newmtl light\nKd 0.5\n", 2, "needs 3");
}

TEST_F(SceneTest, KdBeforeNewmtl) {
  ExpectMtlError("Kd 0.5 0.5 0.5\nnewmtl light\n", 1, "newmtl");
}

TEST_F(SceneTest, KeNegative) {
  ExpectMtlError("newmtl light\n\nKe 1 -1 1\n", 3, "Ke must be >= 0");
}

TEST_F(SceneTest, KeNotFinite) {
  ExpectMtlError("newmtl light\nKe 1 inf 1\n", 2, "not finite");
}

TEST_F(SceneTest, DuplicateMaterial) {
  ExpectMtlError("newmtl light\nKe 1 1 1\nnewmtl light\n", 3, "duplicate material 'light'");
}

TEST_F(SceneTest, NoEmitter) {
  Scene scene;
  ExpectError(LoadBody("usemtl white\nf 1 2 3\n", &scene), obj(), 0, "no emitter");
  ExpectError(LoadBody("usemtl white\nf 1 2 3\n", &scene), obj(), 0,
              "--emit NAME=R,G,B or NAME=ka");
}

}  // namespace
}  // namespace vismask
