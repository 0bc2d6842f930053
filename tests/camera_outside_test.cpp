// Issue 40: the inside views' lit score counts light from outside (--sky,
// --sun): a closed room lit through a skylight alone is seen where that
// light lands, not where its geometry is most varied.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <glm/geometric.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/display/camera.h"
#include "vismask/solve/outside.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;
using test::WriteFile;

// A long room (20 x 3 x 4, walls facing in) with two pillars at its far
// end (+x), which make a view towards that end the most varied (the
// geometric score), and nothing that emits: its ceiling has a 1.25 x 1.5
// opening at the x = 0 end. As polygons and as an OBJ.
struct SkylightRoom {
  std::vector<Polygon> polygons;
  std::string obj;
};

SkylightRoom MakeSkylightRoom() {
  SkylightRoom room;
  std::ostringstream obj, faces;
  obj << "mtllib room.mtl\n";
  int vertices = 0;
  // The quad o, o + a, o + a + b, o + b: its normal is a x b.
  auto quad = [&](glm::vec3 o, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 c[4] = {o, o + a, o + a + b, o + b};
    Polygon p;
    p.corners.assign(c, c + 4);
    const glm::vec3 n = glm::cross(a, b);
    p.area = glm::length(n);
    p.normal = n / static_cast<float>(p.area);
    room.polygons.push_back(p);
    for (const glm::vec3& v : c) obj << "v " << v.x << " " << v.y << " " << v.z << "\n";
    faces << "f " << vertices + 1 << " " << vertices + 2 << " " << vertices + 3 << " "
          << vertices + 4 << "\n";
    vertices += 4;
  };
  // A box's faces but its top (the ceiling, made below), facing in or out.
  auto box = [&](glm::vec3 lo, glm::vec3 hi, bool inward, bool top) {
    const glm::vec3 d = hi - lo;
    const glm::vec3 x(d.x, 0, 0), y(0, d.y, 0), z(0, 0, d.z);
    const glm::vec3 o[6] = {lo, lo + y, lo, lo + z, lo, lo + x};
    const glm::vec3 a[6] = {z, x, x, y, y, z}, b[6] = {x, z, y, x, z, y};
    for (int f = 0; f < 6; ++f)
      if (f != 1 || top) inward ? quad(o[f], a[f], b[f]) : quad(o[f], b[f], a[f]);
  };
  box({0, 0, 0}, {20, 3, 4}, true, false);
  // The ceiling (facing down) around the opening x 0.25-1.5, z 1.25-2.75.
  auto ceiling = [&](float x0, float x1, float z0, float z1) {
    quad({x0, 3, z0}, {x1 - x0, 0, 0}, {0, 0, z1 - z0});
  };
  ceiling(0, 20, 0, 1.25f);
  ceiling(0, 20, 2.75f, 4);
  ceiling(0, 0.25f, 1.25f, 2.75f);
  ceiling(1.5f, 20, 1.25f, 2.75f);
  for (float z : {1.2f, 2.8f}) box({18.3f, 0, z - 0.3f}, {18.9f, 3, z + 0.3f}, false, true);
  room.obj = obj.str() + "usemtl wall\n" + faces.str();
  return room;
}

const Bounds kRoomBounds{{0, 0, 0}, {20, 3, 4}};

OutsideLight Sky() {
  OutsideLight light;
  light.sky = glm::vec3(1.0f);
  return light;
}

OutsideLight Sun() {
  OutsideLight light;
  light.sunToward = glm::normalize(glm::vec3(0.1f, 1.0f, 0.05f));
  light.sun = glm::vec3(3.0f);
  return light;
}

ViewChoice Choose(const SkylightRoom& room, const OutsideLight* light) {
  ViewProbe probe(kRoomBounds);
  if (light) probe.SetOutside(*light);
  for (uint32_t k = 0; k < room.polygons.size(); ++k) probe.Add(k, room.polygons[k]);
  return probe.Choose();
}

// The sky alone and the sun alone: the geometric score picks a view
// towards the pillars' end; the lit score another, which sees more of the
// light that comes in through the skylight, and it wins.
TEST(CameraOutsideTest, InsideViewGoesWhereTheSkyAndTheSunLight) {
  const SkylightRoom room = MakeSkylightRoom();
  const ViewChoice geometric = Choose(room, nullptr);
  ASSERT_TRUE(geometric.inside);
  EXPECT_FALSE(geometric.byLight);
  EXPECT_FALSE(geometric.sun || geometric.sky);
  const Camera g = InsideCamera(kRoomBounds, geometric.candidate);
  EXPECT_GT(g.target.x, g.eye.x);
  for (const OutsideLight& light : {Sky(), Sun()}) {
    const bool sky = light.HasSky();
    const ViewChoice lit = Choose(room, &light);
    ASSERT_TRUE(lit.inside) << sky;
    EXPECT_TRUE(lit.byLight) << sky;
    EXPECT_EQ(lit.sky, sky);
    EXPECT_EQ(lit.sun, !sky);
    EXPECT_EQ(lit.lamps, 0);
    EXPECT_NE(lit.candidate, geometric.candidate) << sky;
    // The geometric scores are the same; the lit winner's lit score is
    // above the geometric winner's, and every lit score is >= 0.
    for (int k = 0; k < kInsideCandidates; ++k) {
      EXPECT_EQ(lit.geometric[k], geometric.geometric[k]);
      EXPECT_GE(lit.lit[k], 0.0);
    }
    EXPECT_GT(lit.lit[lit.candidate], lit.lit[geometric.candidate]) << sky;
  }
}

// Without the skylight the room is shut: the sun, straight down, reaches
// nothing inside, and the geometry decides.
TEST(CameraOutsideTest, ASunOverAShutRoomLightsNothing) {
  SkylightRoom room = MakeSkylightRoom();
  Polygon lid;
  lid.corners = {{0.25f, 3, 1.25f}, {1.5f, 3, 1.25f}, {1.5f, 3, 2.75f}, {0.25f, 3, 2.75f}};
  lid.normal = glm::vec3(0, -1, 0);
  lid.area = 1.25 * 1.5;
  room.polygons.push_back(lid);
  const ViewChoice geometric = Choose(room, nullptr);
  OutsideLight sun;
  sun.sunToward = glm::vec3(0, 1, 0);
  sun.sun = glm::vec3(3.0f);
  const ViewChoice shut = Choose(room, &sun);
  for (int k = 0; k < kInsideCandidates; ++k) EXPECT_EQ(shut.lit[k], 0.0) << k;
  EXPECT_FALSE(shut.byLight);
  EXPECT_EQ(shut.candidate, geometric.candidate);
}

// Through `vismask render`: the room lit by --sky alone (and --sun alone)
// is seen from the inside candidate the probe's lit score picks, and
// run.json's view_choice says what lit it.
TEST(CameraOutsideTest, RunJsonRecordsTheOutsideLight) {
  TempDir dir;
  const SkylightRoom room = MakeSkylightRoom();
  WriteFile(dir.File("room.obj"), room.obj);
  WriteFile(dir.File("room.mtl"), "newmtl wall\nKd 0.6 0.6 0.6\n");
  const ViewChoice geometric = Choose(room, nullptr);
  for (int sun = 0; sun < 2; ++sun) {
    const OutsideLight light = sun ? Sun() : Sky();
    std::vector<std::string> args = {"render",      dir.File("room.obj"),
                                     "--out",       dir.File("out"),
                                     "--rays",      "64",
                                     "--max-shots", "5",
                                     "--width",     "16",
                                     "--height",    "16",
                                     "--quiet"};
    if (sun) {
      args.insert(args.end(), {"--sun", "0.1,1,0.05,3,3,3"});
    } else {
      args.insert(args.end(), {"--sky", "1,1,1"});
    }
    auto r = RunMain(args);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string json = ReadFile(dir.File("out/run.json"));
    const ViewChoice want = Choose(room, &light);
    ASSERT_NE(want.candidate, geometric.candidate);
    EXPECT_NE(json.find("\"inside\": true, \"inside_by_light\": true"), std::string::npos) << json;
    EXPECT_NE(json.find("\"inside_candidate\": " + std::to_string(want.candidate) + ","),
              std::string::npos)
        << json;
    const std::string by = std::string("\"inside_lit_by\": {\"lamps\": 0, \"sun\": ") +
                           (sun ? "true" : "false") + ", \"sky\": " + (sun ? "false" : "true") +
                           "}";
    EXPECT_NE(json.find(by), std::string::npos) << json;
  }
}

}  // namespace
}  // namespace vismask
