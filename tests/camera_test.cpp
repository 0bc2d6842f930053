// The default camera's side (occlusion included), the --view presets, and
// the warning for an image that shows nothing.
#include "vismask/display/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <sstream>

#include "test_util.h"
#include "vismask/app/options.h"
#include "vismask/scene/scene.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;
using test::WriteFile;

// A polygon from its corners, counter-clockwise seen from its front.
Polygon Quad(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d) {
  Polygon p;
  p.corners = {a, b, c, d};
  glm::vec3 n = glm::cross(b - a, c - a);
  p.area = glm::length(n);
  p.normal = n / static_cast<float>(p.area);
  return p;
}

void AddBounds(Scene* s) {
  s->bounds.lo = s->bounds.hi = s->polygons[0].corners[0];
  for (const Polygon& p : s->polygons)
    for (const glm::vec3& c : p.corners) {
      s->bounds.lo = glm::min(s->bounds.lo, c);
      s->bounds.hi = glm::max(s->bounds.hi, c);
    }
}

// The unit cube's six faces facing inward, less the one on `open`'s side
// (kFront: the -z face missing, ...); open < 0 keeps all six.
Scene OpenBox(int open) {
  const glm::vec3 v[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                          {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  struct Face {
    ViewSide side;
    int a, b, c, d;
  };
  // Counter-clockwise seen from inside.
  const Face faces[6] = {{ViewSide::kFront, 0, 1, 2, 3},  {ViewSide::kBack, 4, 7, 6, 5},
                         {ViewSide::kBottom, 0, 4, 5, 1}, {ViewSide::kTop, 3, 2, 6, 7},
                         {ViewSide::kRight, 0, 3, 7, 4},  {ViewSide::kLeft, 1, 5, 6, 2}};
  Scene s;
  for (const Face& f : faces)
    if (static_cast<int>(f.side) != open)
      s.polygons.push_back(Quad(v[f.a], v[f.b], v[f.c], v[f.d]));
  AddBounds(&s);
  return s;
}

// The same box as an OBJ, with a small emitter under the ceiling facing
// down; `missing` names the face left out ("" for none, "+z" for the
// CornellBox-Sphere shape: closed on -z, open on +z).
void WriteOpenBox(const std::string& dir, const std::string& missing) {
  std::ostringstream obj;
  obj << "mtllib box.mtl\n";
  const double c[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                          {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (auto& v : c) obj << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
  obj << "v 0.4 0.99 0.4\nv 0.6 0.99 0.4\nv 0.6 0.99 0.6\nv 0.4 0.99 0.6\n";
  obj << "usemtl wall\n";
  if (missing != "-z") obj << "f 1 2 3 4\n";
  if (missing != "+z") obj << "f 5 8 7 6\n";
  if (missing != "-y") obj << "f 1 5 6 2\n";
  if (missing != "+y") obj << "f 4 3 7 8\n";
  if (missing != "-x") obj << "f 1 4 8 5\n";
  if (missing != "+x") obj << "f 2 6 7 3\n";
  obj << "usemtl light\nf 9 10 11 12\n";  // normal -y
  WriteFile(dir + "/box.obj", obj.str());
  WriteFile(dir + "/box.mtl", "newmtl wall\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 5 5 5\n");
}

std::vector<std::string> TinyRender(const TempDir& dir, const std::string& scene) {
  return {"render", scene,     "--out", dir.File("out"), "--max-shots", "20",     "--rays",
          "64",     "--width", "24",    "--height",      "24",          "--quiet"};
}

// run.json's "camera" array: eye, target, up, fovy.
std::vector<double> JsonCamera(const std::string& json) {
  std::vector<double> c;
  size_t at = json.find("\"camera\": [");
  if (at == std::string::npos) return c;
  std::istringstream in(json.substr(at + 11));
  double x;
  char sep;
  while (c.size() < 10 && in >> x) {
    c.push_back(x);
    in >> sep;
  }
  return c;
}

TEST(CameraTest, FrontIsTheCameraBeforeViewBitForBit) {
  // The formula DefaultCamera had before --view existed, on the Cornell
  // box's bounds and on a flat one.
  for (Bounds b : {Bounds{{0.0f, 0.0f, 0.0f}, {556.0f, 548.8f, 559.2f}},
                   Bounds{{-1.5f, 2.0f, 3.0f}, {0.25f, 2.0f, 7.0f}}}) {
    glm::vec3 centre = 0.5f * (b.lo + b.hi);
    glm::vec3 half = 0.5f * (b.hi - b.lo);
    float tanHalf = std::tan(0.5f * 39.3f * 3.14159265358979f / 180.0f);
    float reach = std::fmax(half.x, half.y);
    if (reach <= 0.0f) reach = std::fmax(half.z, 1.0f);
    float distance = 1.04f * reach / tanHalf;
    for (Camera c : {SideCamera(b, ViewSide::kFront), DefaultCamera(b)}) {
      EXPECT_EQ(c.eye, glm::vec3(centre.x, centre.y, b.lo.z - distance));
      EXPECT_EQ(c.target, glm::vec3(centre.x, centre.y, b.lo.z));
      EXPECT_EQ(c.up, glm::vec3(0.0f, 1.0f, 0.0f));
      EXPECT_EQ(c.fovyDeg, 39.3f);
    }
  }
}

TEST(CameraTest, EachSideLooksAtItsFaceFromOutside) {
  const Bounds b{{0.0f, 0.0f, 0.0f}, {4.0f, 2.0f, 1.0f}};
  struct Expect {
    ViewSide side;
    const char* name;
    int axis;
    float sign;  // the eye's side of the box along axis
    glm::vec3 up;
    float reach;  // the face's larger half extent
  };
  const Expect cases[] = {
      {ViewSide::kFront, "front", 2, -1.0f, {0, 1, 0}, 2.0f},
      {ViewSide::kBack, "back", 2, 1.0f, {0, 1, 0}, 2.0f},
      {ViewSide::kLeft, "left", 0, 1.0f, {0, 1, 0}, 1.0f},
      {ViewSide::kRight, "right", 0, -1.0f, {0, 1, 0}, 1.0f},
      {ViewSide::kTop, "top", 1, 1.0f, {0, 0, 1}, 2.0f},
      {ViewSide::kBottom, "bottom", 1, -1.0f, {0, 0, -1}, 2.0f},
  };
  const float tanHalf = std::tan(0.5f * 39.3f * 3.14159265358979f / 180.0f);
  for (const Expect& e : cases) {
    SCOPED_TRACE(e.name);
    EXPECT_STREQ(ViewSideName(e.side), e.name);
    ViewSide parsed = ViewSide::kFront;
    ASSERT_TRUE(ParseViewSide(e.name, &parsed));
    EXPECT_EQ(parsed, e.side);
    Camera c = SideCamera(b, e.side);
    glm::vec3 face = 0.5f * (b.lo + b.hi);
    face[e.axis] = e.sign > 0.0f ? b.hi[e.axis] : b.lo[e.axis];
    EXPECT_EQ(c.target, face);
    glm::vec3 back = c.eye - c.target;
    for (int a = 0; a < 3; ++a)
      if (a != e.axis) {
        EXPECT_EQ(back[a], 0.0f);
      }
    EXPECT_NEAR(back[e.axis], e.sign * 1.04f * e.reach / tanHalf, 1e-4f);
    EXPECT_EQ(c.up, e.up);
    View v;
    ASSERT_TRUE(MakeView(c, 64, 48, &v));
    // top and bottom keep the front view's +x on the image's left.
    if (e.axis == 1) {
      EXPECT_LT(v.right.x, -0.99f);
    }
  }
  ViewSide s;
  EXPECT_FALSE(ParseViewSide("side", &s));
  EXPECT_FALSE(ParseViewSide("Front", &s));
}

TEST(CameraTest, OpenBoxIsSeenThroughItsOpenSide) {
  for (int open = 0; open < kNumViewSides; ++open) {
    SCOPED_TRACE(ViewSideName(static_cast<ViewSide>(open)));
    Scene s = OpenBox(open);
    uint32_t rays[kNumViewSides];
    VisibleFrontRays(s, rays);
    for (int side = 0; side < kNumViewSides; ++side) {
      if (side == open) {
        EXPECT_GT(rays[side], 3000u);  // the inside fills most of the view
      } else {
        EXPECT_EQ(rays[side], 0u) << ViewSideName(static_cast<ViewSide>(side));
      }
    }
    EXPECT_EQ(ChooseViewSide(s), static_cast<ViewSide>(open));
  }
}

TEST(CameraTest, ClosedBoxKeepsFront) {
  Scene s = OpenBox(-1);
  uint32_t rays[kNumViewSides];
  VisibleFrontRays(s, rays);
  for (uint32_t r : rays) EXPECT_EQ(r, 0u);
  EXPECT_EQ(ChooseViewSide(s), ViewSide::kFront);
}

// Issue 40: from outside, a closed room shows only the backs of its walls;
// the default camera goes inside, where every candidate sees walls' fronts.
// An open box is still seen from outside through its open side.
ViewChoice Choice(const Scene& s) {
  ViewProbe probe(s.bounds);
  for (uint32_t k = 0; k < s.polygons.size(); ++k) probe.Add(k, s.polygons[k]);
  return probe.Choose();
}

TEST(CameraTest, ClosedRoomIsSeenFromInside) {
  ViewChoice closed = Choice(OpenBox(-1));
  EXPECT_TRUE(closed.inside);
  EXPECT_EQ(closed.sideFront, 0.0);
  EXPECT_GT(closed.sideBack, 0.5);
  EXPECT_GE(closed.candidate, 0);
  EXPECT_GT(closed.candidateFront, 0.99);  // walls all round
  for (int open = 0; open < kNumViewSides; ++open) {
    ViewChoice c = Choice(OpenBox(open));
    EXPECT_FALSE(c.inside) << ViewSideName(static_cast<ViewSide>(open));
    EXPECT_EQ(c.side, static_cast<ViewSide>(open));
  }
  // A box facing out (a building seen from outside): its fronts are seen
  // from outside, five walls of them, no view from inside.
  Scene out = OpenBox(-1);
  for (Polygon& p : out.polygons) {
    std::reverse(p.corners.begin(), p.corners.end());
    p.normal = -p.normal;
  }
  ViewChoice c = Choice(out);
  EXPECT_FALSE(c.inside);
  EXPECT_GT(c.sideFront, 0.3);
  // Seen from inside, it is all backs: no candidate reaches half.
  EXPECT_LT(c.candidateFront, 0.5);
}

// A long room (12 x 3 x 4, walls facing in) with four pillars in its far
// half and a small lamp under the ceiling near its x = 0 end: the pillars
// make the far half the most varied view (the geometric score), while the
// light is at the other end. As an OBJ (the lamp's material emits), and as
// polygons with the lamp as the lit score's light.
struct LongRoom {
  std::vector<Polygon> polygons;
  ViewLight lamp;
  std::string obj;
};

LongRoom MakeLongRoom() {
  LongRoom room;
  std::ostringstream obj, faces;
  obj << "mtllib room.mtl\n";
  int vertices = 0;
  // The quad o, o + a, o + a + b, o + b: its normal is a x b.
  auto quad = [&](glm::vec3 o, glm::vec3 a, glm::vec3 b, const char* mat) {
    const glm::vec3 c[4] = {o, o + a, o + a + b, o + b};
    room.polygons.push_back(Quad(c[0], c[1], c[2], c[3]));
    for (const glm::vec3& v : c) obj << "v " << v.x << " " << v.y << " " << v.z << "\n";
    faces << "usemtl " << mat << "\nf " << vertices + 1 << " " << vertices + 2 << " "
          << vertices + 3 << " " << vertices + 4 << "\n";
    vertices += 4;
  };
  auto box = [&](glm::vec3 lo, glm::vec3 hi, bool inward) {
    const glm::vec3 d = hi - lo;
    const glm::vec3 x(d.x, 0, 0), y(0, d.y, 0), z(0, 0, d.z);
    const glm::vec3 o[6] = {lo, lo + y, lo, lo + z, lo, lo + x};
    const glm::vec3 a[6] = {z, x, x, y, y, z}, b[6] = {x, z, y, x, z, y};
    for (int f = 0; f < 6; ++f)
      inward ? quad(o[f], a[f], b[f], "wall") : quad(o[f], b[f], a[f], "wall");
  };
  box({0, 0, 0}, {12, 3, 4}, true);
  for (float x : {7.5f, 10.0f})
    for (float z : {1.2f, 2.8f}) box({x - 0.3f, 0, z - 0.3f}, {x + 0.3f, 3, z + 0.3f}, false);
  quad({0.7f, 2.99f, 1.7f}, {0.6f, 0, 0}, {0, 0, 0.6f}, "lamp");
  room.lamp.centre = glm::vec3(1.0f, 2.99f, 2.0f);
  room.lamp.normal = room.polygons.back().normal;
  room.lamp.power = 20.0 * 0.36;
  room.obj = obj.str() + faces.str();
  return room;
}

// Issue 40: the inside view scored by how lit it is. In the long room the
// geometric score picks a view of the dark far half (the pillars); the lit
// score one looking towards the lamp's end, and it wins.
TEST(CameraTest, InsideViewGoesWhereTheLightIs) {
  const LongRoom room = MakeLongRoom();
  ASSERT_LT(room.lamp.normal.y, -0.99f);  // facing down
  Bounds bounds{{0, 0, 0}, {12, 3, 4}};
  auto choose = [&](bool lit) {
    ViewProbe probe(bounds);
    if (lit) probe.SetLights({room.lamp});
    for (uint32_t k = 0; k < room.polygons.size(); ++k) probe.Add(k, room.polygons[k]);
    return probe.Choose();
  };
  const ViewChoice geometric = choose(false), lit = choose(true);
  ASSERT_TRUE(geometric.inside);
  ASSERT_TRUE(lit.inside);
  EXPECT_FALSE(geometric.byLight);
  EXPECT_TRUE(lit.byLight);
  // The geometric choice looks away from the lamp (towards +x), the lit
  // one towards it, and they differ.
  const Camera g = InsideCamera(bounds, geometric.candidate);
  const Camera l = InsideCamera(bounds, lit.candidate);
  EXPECT_GT(g.target.x, g.eye.x);
  EXPECT_LT(l.target.x, l.eye.x);
  EXPECT_NE(geometric.candidate, lit.candidate);
  // The scores say so: the geometric winner has the higher geometric score,
  // the lit winner the higher lit score; without lights every lit score is 0.
  EXPECT_GT(lit.geometric[geometric.candidate], lit.geometric[lit.candidate]);
  EXPECT_GT(lit.lit[lit.candidate], 2.0 * lit.lit[geometric.candidate]);
  for (int k = 0; k < kInsideCandidates; ++k) {
    EXPECT_EQ(geometric.geometric[k], lit.geometric[k]) << k;
    EXPECT_EQ(geometric.lit[k], 0.0) << k;
  }
  // A lamp behind a wall lights nothing: the far end's wall (x = 12) seen
  // from a lamp outside it, facing in, is in its shadow map's way.
  ViewLight behind = room.lamp;
  behind.centre = glm::vec3(12.5f, 1.5f, 2.0f);
  behind.normal = glm::vec3(-1, 0, 0);
  ViewProbe probe(bounds);
  probe.SetLights({behind});
  for (uint32_t k = 0; k < room.polygons.size(); ++k) probe.Add(k, room.polygons[k]);
  const ViewChoice shut = probe.Choose();
  for (int k = 0; k < kInsideCandidates; ++k) EXPECT_EQ(shut.lit[k], 0.0) << k;
  EXPECT_FALSE(shut.byLight);
  EXPECT_EQ(shut.candidate, geometric.candidate);
}

// The same through `vismask render`: the scene's lamp is the light, and
// run.json records every candidate's geometric and lit score.
TEST(CameraTest, RunJsonRecordsTheInsideScores) {
  TempDir dir;
  const LongRoom room = MakeLongRoom();
  WriteFile(dir.File("room.obj"), room.obj);
  WriteFile(dir.File("room.mtl"), "newmtl wall\nKd 0.6 0.6 0.6\nnewmtl lamp\nKe 20 20 20\n");
  auto r = RunMain({"render", dir.File("room.obj"), "--out", dir.File("out"), "--max-shots", "5",
                    "--width", "32", "--height", "32", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = ReadFile(dir.File("out/run.json"));
  ViewProbe probe(Bounds{{0, 0, 0}, {12, 3, 4}});
  probe.SetLights({room.lamp});
  for (uint32_t k = 0; k < room.polygons.size(); ++k) probe.Add(k, room.polygons[k]);
  const ViewChoice want = probe.Choose();
  EXPECT_NE(json.find("\"inside\": true, \"inside_by_light\": true"), std::string::npos) << json;
  EXPECT_NE(json.find("\"inside_candidate\": " + std::to_string(want.candidate) + ","),
            std::string::npos)
      << json;
  for (const char* key : {"\"inside_scores\": [", "\"inside_lit_scores\": ["}) {
    const size_t at = json.find(key);
    ASSERT_NE(at, std::string::npos) << key;
    const double* scores = key[8] == 's' ? want.geometric : want.lit;
    const char* p = json.c_str() + at + std::strlen(key);
    for (int k = 0; k < kInsideCandidates; ++k) {
      char* end = nullptr;
      const double v = std::strtod(p, &end);
      ASSERT_NE(end, p) << key << k;
      EXPECT_NEAR(v, scores[k], 1e-5 * std::fabs(scores[k]) + 1e-12) << key << k;
      p = end + (*end == ',' ? 1 : 0);
    }
  }
}

TEST(CameraTest, OccludedFrontFacesAreNotCounted) {
  // A quad facing -z (towards the front camera) behind a larger one facing
  // +z: facing the eye is not enough, the front camera sees only a back.
  Polygon facing =
      Quad({0.65f, 0.35f, 1.0f}, {0.35f, 0.35f, 1.0f}, {0.35f, 0.65f, 1.0f}, {0.65f, 0.65f, 1.0f});
  Polygon wall =
      Quad({0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 0.0f});
  ASSERT_LT(facing.normal.z, 0.0f);
  ASSERT_GT(wall.normal.z, 0.0f);
  Scene alone;
  alone.polygons = {facing};
  alone.bounds = Bounds{{0, 0, 0}, {1, 1, 1}};
  Scene hidden = alone;
  hidden.polygons.push_back(wall);
  uint32_t a[kNumViewSides], h[kNumViewSides];
  VisibleFrontRays(alone, a);
  VisibleFrontRays(hidden, h);
  const int front = static_cast<int>(ViewSide::kFront), back = static_cast<int>(ViewSide::kBack);
  EXPECT_GT(a[front], 50u);
  EXPECT_EQ(h[front], 0u);
  // From +z the wall is seen through the hole around the quad's back.
  EXPECT_GT(h[back], 0u);
  EXPECT_EQ(ChooseViewSide(hidden), ViewSide::kBack);
}

TEST(CameraTest, NearTiesGoToFront) {
  // Two squares facing out of the unit cube's z faces, -z and +z: the front
  // and back cameras each see one, alike; front wins the tie.
  Scene s;
  s.polygons = {Quad({1, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 1, 0}),
                Quad({0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1})};
  s.bounds = Bounds{{0, 0, 0}, {1, 1, 1}};
  ASSERT_LT(s.polygons[0].normal.z, 0.0f);
  ASSERT_GT(s.polygons[1].normal.z, 0.0f);
  uint32_t rays[kNumViewSides];
  VisibleFrontRays(s, rays);
  EXPECT_GT(rays[0], 2000u);
  EXPECT_NEAR(rays[0], rays[1], rays[0] / 100);
  for (int side = 2; side < kNumViewSides; ++side) EXPECT_EQ(rays[side], 0u);
  EXPECT_EQ(ChooseViewSide(s), ViewSide::kFront);
  // Without the front's square, back.
  s.polygons.erase(s.polygons.begin());
  EXPECT_EQ(ChooseViewSide(s), ViewSide::kBack);
}

TEST(CameraTest, CornellBoxKeepsFront) {
  Scene s;
  Status st = LoadScene("scenes/cornell.obj", &s);
  ASSERT_TRUE(st.ok()) << st.ToString();
  EXPECT_EQ(ChooseViewSide(s), ViewSide::kFront);
}

TEST(CameraTest, McGuireSphereBoxIsSeenFromBack) {
  // The project's copy of McGuire's scene, as published (scenes/real/).
  const char* path = "scenes/real/CornellBox-Sphere.obj";
  ASSERT_TRUE(test::FileExists(path)) << path;
  Scene s;
  std::vector<std::string> warnings;
  Status st = LoadSceneFromText(
      path, ReadFile(path),
      [](const std::string& p, std::string* text) {
        if (!test::FileExists(p)) return std::string("cannot open");
        *text = ReadFile(p);
        return std::string();
      },
      &s, &warnings);
  ASSERT_TRUE(st.ok()) << st.ToString();
  EXPECT_EQ(ChooseViewSide(s), ViewSide::kBack);
}

// Through the command line.

TEST(CameraTest, DefaultRenderOfABoxOpenOnPlusZLooksFromPlusZ) {
  TempDir dir;
  WriteOpenBox(dir.path(), "+z");
  auto r = RunMain(TinyRender(dir, dir.File("box.obj")));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  std::string json = ReadFile(dir.File("out/run.json"));
  EXPECT_NE(json.find("\"view\": \"back\",\n    \"view_auto\": true,"), std::string::npos) << json;
  std::vector<double> c = JsonCamera(json);
  ASSERT_EQ(c.size(), 10u) << json;
  EXPECT_GT(c[2], 1.0);  // eye beyond the box's +z face
  EXPECT_EQ(c[5], 1.0);  // looking at that face
}

TEST(CameraTest, DefaultRenderOfAClosedRoomLooksFromInside) {
  TempDir dir;
  WriteOpenBox(dir.path(), "");
  auto r = RunMain(TinyRender(dir, dir.File("box.obj")));
  ASSERT_EQ(r.code, 0) << r.err;
  std::string json = ReadFile(dir.File("out/run.json"));
  EXPECT_NE(json.find("\"view\": \"inside\",\n    \"view_auto\": true,"), std::string::npos)
      << json;
  EXPECT_NE(json.find("\"inside\": true,"), std::string::npos) << json;
  std::vector<double> c = JsonCamera(json);
  ASSERT_EQ(c.size(), 10u) << json;
  for (int a = 0; a < 3; ++a) {  // the eye and the target in the unit box
    EXPECT_GT(c[a], 0.0);
    EXPECT_LT(c[a], 1.0);
    EXPECT_GT(c[3 + a], 0.0);
    EXPECT_LT(c[3 + a], 1.0);
  }
  // --view keeps its side.
  auto args = TinyRender(dir, dir.File("box.obj"));
  args.insert(args.end(), {"--view", "front"});
  r = RunMain(args);
  ASSERT_EQ(r.code, 0) << r.err;
  json = ReadFile(dir.File("out/run.json"));
  EXPECT_NE(json.find("\"view\": \"front\",\n    \"view_auto\": false,"), std::string::npos);
  EXPECT_NE(json.find("\"view_choice\": null"), std::string::npos);
}

TEST(CameraTest, CornellDefaultCameraIsUnchanged) {
  TempDir dir;
  auto r = RunMain({"render", "scenes/cornell.obj", "--out", dir.File("out"), "--max-shots", "5",
                    "--rays", "64", "--width", "16", "--height", "16"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::string json = ReadFile(dir.File("out/run.json"));
  // The numbers run.json held before --view existed.
  EXPECT_NE(json.find("\"camera\": [278, 274.399994, -809.706604, 278, 274.399994, 0, 0, 1, 0, "
                      "39.2999992],\n    \"view\": \"front\",\n    \"view_auto\": true,"),
            std::string::npos)
      << json;
  EXPECT_NE(r.err.find(", view front (chosen); wrote "), std::string::npos) << r.err;
}

TEST(CameraTest, ViewPresetsPutTheEyeOnTheirSide) {
  TempDir dir;
  WriteOpenBox(dir.path(), "");
  struct Case {
    const char* view;
    int axis;
    double sign;
  };
  for (const Case& k : {Case{"front", 2, -1}, Case{"back", 2, 1}, Case{"left", 0, 1},
                        Case{"right", 0, -1}, Case{"top", 1, 1}, Case{"bottom", 1, -1}}) {
    SCOPED_TRACE(k.view);
    auto args = TinyRender(dir, dir.File("box.obj"));
    args.insert(args.end(), {"--view", k.view});
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    std::string json = ReadFile(dir.File("out/run.json"));
    EXPECT_NE(json.find(std::string("\"view\": \"") + k.view + "\",\n    \"view_auto\": false,"),
              std::string::npos)
        << json;
    std::vector<double> c = JsonCamera(json);
    ASSERT_EQ(c.size(), 10u) << json;
    for (int a = 0; a < 3; ++a) {
      if (a == k.axis) {
        EXPECT_GT(k.sign * (c[a] - 0.5), 0.5);  // outside the unit box
      } else {
        EXPECT_EQ(c[a], 0.5);
      }
    }
  }
}

TEST(CameraTest, ViewWithCameraIsAUsageError) {
  TempDir dir;
  WriteOpenBox(dir.path(), "+z");
  auto args = TinyRender(dir, dir.File("box.obj"));
  args.insert(args.end(), {"--view", "back", "--camera", "0.5,0.5,3,0.5,0.5,0,0,1,0,40"});
  auto r = RunMain(args);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--view and --camera"), std::string::npos) << r.err;
  EXPECT_FALSE(test::FileExists(dir.File("out/run.json")));
  args = TinyRender(dir, dir.File("box.obj"));
  args.insert(args.end(), {"--view", "sideways"});
  r = RunMain(args);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--view: expected front, back, left, right, top or bottom, got 'sideways'"),
            std::string::npos)
      << r.err;
  EXPECT_NE(std::string(HelpText()).find("--view SIDE"), std::string::npos);
}

TEST(CameraTest, BlackImagesWarnAndExitZero) {
  TempDir dir;
  WriteOpenBox(dir.path(), "+z");
  // The box's closed side: the backs of its walls, drawn black.
  auto args = TinyRender(dir, dir.File("box.obj"));
  args.insert(args.end(), {"--view", "front"});
  auto r = RunMain(args);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("vismask: warning: the image is black: the camera sees no lit "
                       "front-facing surface"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("(try --view "), std::string::npos) << r.err;
  EXPECT_TRUE(test::FileExists(dir.File("out/image.png")));
  // Looking away from the scene: nothing at all.
  args = TinyRender(dir, dir.File("box.obj"));
  args.insert(args.end(), {"--camera", "0.5,0.5,3,0.5,0.5,4,0,1,0,40"});
  r = RunMain(args);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("vismask: warning: the image is all background: the camera sees no surface "
                       "(try another --camera"),
            std::string::npos)
      << r.err;
  // One line.
  size_t at = r.err.find("warning");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(r.err.find('\n', at), r.err.size() - 1) << r.err;
}

}  // namespace
}  // namespace vismask
