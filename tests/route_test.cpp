// Method R's routing (the default mask method): a shot's packets go only
// where its rays go, each ray to the neighbour across the face it leaves by,
// and a receiver traces only the rays that entered it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace vismask {
namespace {

using test::RunMain;
using test::TempDir;

// The number after "key": in run.json (the first from `from`; of a list,
// its first element).
double JsonValue(const std::string& json, const std::string& key, size_t from = 0) {
  size_t at = json.find("\"" + key + "\":", from);
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return -1.0;
  at += key.size() + 3;
  while (at < json.size() && (json[at] == ' ' || json[at] == '[')) ++at;
  return std::strtod(json.c_str() + at, nullptr);
}

// Two closed rooms side by side, each with its own light, x in [0, 1] and
// [2, 3]; `window` opens a hole in the facing walls joined by a tunnel, so
// light passes from one room to the other.
void WriteTwoRooms(const std::string& dir, bool window, double kd) {
  std::ostringstream obj;
  obj << "mtllib rooms.mtl\n";
  int n = 0;
  auto quad = [&](const char* mtl, const double(&q)[4][3]) {
    obj << "usemtl " << mtl << "\n";
    for (auto& v : q) obj << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
    obj << "f " << n + 1 << " " << n + 2 << " " << n + 3 << " " << n + 4 << "\n";
    n += 4;
  };
  for (double x0 : {0.0, 2.0}) {
    const double x1 = x0 + 1.0;
    // Counter-clockwise seen from inside.
    double floor_[4][3] = {{x0, 0, 0}, {x0, 0, 1}, {x1, 0, 1}, {x1, 0, 0}};
    double ceil_[4][3] = {{x0, 1, 0}, {x1, 1, 0}, {x1, 1, 1}, {x0, 1, 1}};
    double back[4][3] = {{x0, 0, 1}, {x0, 1, 1}, {x1, 1, 1}, {x1, 0, 1}};
    double front[4][3] = {{x0, 0, 0}, {x1, 0, 0}, {x1, 1, 0}, {x0, 1, 0}};
    quad("wall", floor_);
    quad("wall", ceil_);
    quad("wall", back);
    quad("wall", front);
    // The side walls: x = x0 facing +x, x = x1 facing -x.
    double left[4][3] = {{x0, 0, 0}, {x0, 1, 0}, {x0, 1, 1}, {x0, 0, 1}};
    double right[4][3] = {{x1, 0, 0}, {x1, 0, 1}, {x1, 1, 1}, {x1, 1, 0}};
    const bool inner = x0 == 0.0 ? false : true;  // the wall facing the other room
    const double(&facing)[4][3] = inner ? left : right;
    const double(&outer)[4][3] = inner ? right : left;
    quad("wall", outer);
    if (!window) {
      quad("wall", facing);
    } else {
      // The facing wall with a square hole (y, z in [0.4, 0.6]) as four strips.
      const double x = facing[0][0];
      const bool plusX = inner;  // x = x0 of the right room faces +x
      auto strip = [&](double y0, double y1, double z0, double z1) {
        double q[4][3] = {{x, y0, z0}, {x, y1, z0}, {x, y1, z1}, {x, y0, z1}};
        if (!plusX) {
          double r[4][3] = {{x, y0, z0}, {x, y0, z1}, {x, y1, z1}, {x, y1, z0}};
          quad("wall", r);
        } else {
          quad("wall", q);
        }
      };
      strip(0.0, 0.4, 0.0, 1.0);
      strip(0.6, 1.0, 0.0, 1.0);
      strip(0.4, 0.6, 0.0, 0.4);
      strip(0.4, 0.6, 0.6, 1.0);
    }
    // The light under the ceiling, facing down.
    double light[4][3] = {
        {x0 + 0.4, 0.99, 0.4}, {x0 + 0.6, 0.99, 0.4}, {x0 + 0.6, 0.99, 0.6}, {x0 + 0.4, 0.99, 0.6}};
    quad("light", light);
  }
  test::WriteFile(dir + "/rooms.obj", obj.str());
  std::ostringstream mtl;
  mtl << "newmtl wall\nKd " << kd << " " << kd << " " << kd
      << "\nnewmtl light\nKd 0 0 0\nKe 5 5 5\n";
  test::WriteFile(dir + "/rooms.mtl", mtl.str());
}

std::string Render(const TempDir& dir, const std::string& name, bool window, double kd,
                   const std::vector<std::string>& extra) {
  WriteTwoRooms(dir.path(), window, kd);
  std::vector<std::string> args = {"render",         dir.File("rooms.obj"),
                                   "--envs",         "2x1x1",
                                   "--emitted-rays", "200000",
                                   "--width",        "16",
                                   "--height",       "16",
                                   "--quiet",        "--out",
                                   dir.File(name)};
  args.insert(args.end(), extra.begin(), extra.end());
  auto r = RunMain(args);
  EXPECT_EQ(r.code, 0) << r.err;
  return test::ReadFile(dir.File(name) + "/run.json");
}

// Sealed rooms in two environments: no ray leaves its room, so no packet
// is ever sent and no environment shoots a foreign shooter, where the
// hemisphere methods send every shot on (their neighbours wait for it).
TEST(RouteTest, SealedRoomsExchangeNoPackets) {
  TempDir dir;
  std::string r = Render(dir, "sealed", false, 0.6, {});
  EXPECT_EQ(JsonValue(r, "packets"), 0.0);
  EXPECT_EQ(JsonValue(r, "foreign_shots"), 0.0);
  EXPECT_GT(JsonValue(r, "local_shots"), 100.0);
  std::string b = Render(dir, "sealed-B", false, 0.6, {"--mask-method", "B"});
  EXPECT_GT(JsonValue(b, "packets"), 100.0);
}

// With a window between the rooms, rays cross: packets flow and foreign
// shots are made. With black walls there is direct light only, so once the
// lights have shot and every queue is drained (--stop-unshot 0), every ray
// has been absorbed in exactly one environment: nothing is left in flight,
// the ledger closes, and the result does not depend on the ranks.
TEST(RouteTest, RaysThroughAWindowAreDeliveredOnce) {
  TempDir dir;
  // --stop-unshot 0 needs a limit beside it; this one is never reached.
  const std::vector<std::string> drain = {"--stop-unshot", "0", "--max-shots", "10000000"};
  std::string r = Render(dir, "window", true, 0.0, drain);
  EXPECT_NE(r.find("\"stop_reason\": \"converged\""), std::string::npos);
  EXPECT_GT(JsonValue(r, "packets"), 0.0);
  EXPECT_GT(JsonValue(r, "foreign_shots"), 0.0);
  const size_t energy = r.find("\"energy\"");
  ASSERT_NE(energy, std::string::npos);
  const double emitted = JsonValue(r, "emitted", energy);
  EXPECT_GT(emitted, 0.0);
  EXPECT_LT(std::abs(JsonValue(r, "in_flight", energy)), 1e-9 * emitted);
  EXPECT_LT(std::abs(JsonValue(r, "unshot", energy)), 1e-9 * emitted);
  EXPECT_LT(std::abs(JsonValue(r, "residual", energy)), 1e-9 * emitted);
  std::vector<std::string> drain2 = drain;
  drain2.insert(drain2.end(), {"--ranks", "2"});
  std::string two = Render(dir, "window2", true, 0.0, drain2);
  EXPECT_EQ(test::ReadFile(dir.File("window") + "/patches.csv"),
            test::ReadFile(dir.File("window2") + "/patches.csv"));
}

}  // namespace
}  // namespace vismask
