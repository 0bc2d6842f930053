// The streaming loader (scene_stream.h) against the whole-file one
// (LoadScene + PartitionScene): the same polygons, pieces, warnings and
// errors on every scene of scenes/; the streamed emitter check and camera
// probe against their whole-scene forms.
#include "vismask/scene/scene_stream.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/display/camera.h"
#include "vismask/scene/emitter_check.h"
#include "vismask/scene/scene.h"
#include "vismask/solve/partition.h"

namespace vismask {
namespace {

using test::TempDir;

std::vector<std::string> EveryScene() {
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::recursive_directory_iterator("scenes"))
    if (entry.path().extension() == ".obj") paths.push_back(entry.path().string());
  std::sort(paths.begin(), paths.end());
  return paths;
}

// Bit for bit: corners, uv, vn, normal, area, material, line, smoothing.
void ExpectSamePolygon(const Polygon& a, const Polygon& b, const std::string& where) {
  ASSERT_EQ(a.corners.size(), b.corners.size()) << where;
  EXPECT_EQ(0,
            std::memcmp(a.corners.data(), b.corners.data(), a.corners.size() * sizeof(glm::vec3)))
      << where;
  ASSERT_EQ(a.uv.size(), b.uv.size()) << where;
  // (memcmp of an empty vector's null data() is undefined: UBSan says so.)
  if (!a.uv.empty()) {
    EXPECT_EQ(0, std::memcmp(a.uv.data(), b.uv.data(), a.uv.size() * sizeof(glm::vec2))) << where;
  }
  ASSERT_EQ(a.vn.size(), b.vn.size()) << where;
  if (!a.vn.empty()) {
    EXPECT_EQ(0, std::memcmp(a.vn.data(), b.vn.data(), a.vn.size() * sizeof(glm::vec3))) << where;
  }
  EXPECT_EQ(0, std::memcmp(&a.normal, &b.normal, sizeof a.normal)) << where;
  EXPECT_EQ(0, std::memcmp(&a.area, &b.area, sizeof a.area)) << where;
  EXPECT_EQ(a.material, b.material) << where;
  EXPECT_EQ(a.line, b.line) << where;
  EXPECT_EQ(a.smoothing, b.smoothing) << where;
}

// The options a scene needs to load (its light is Ka only).
LoadOptions OptionsFor(const std::string& path) {
  LoadOptions o;
  if (path.find("cornell_box.obj") != std::string::npos) o.emit.push_back({"light", true, {}});
  if (path.find("lamp-room.obj") != std::string::npos) o.emit.push_back({"lamp", true, {}});
  return o;
}

TEST(SceneStreamTest, SamePolygonsPiecesAndWarningsOnEveryScene) {
  const std::vector<std::string> scenes = EveryScene();
  ASSERT_GE(scenes.size(), 20u);
  size_t loaded = 0;
  for (const std::string& path : scenes) {
    const LoadOptions options = OptionsFor(path);
    Scene whole;
    std::vector<std::string> warnings;
    Status ws = LoadSceneFromText(
        path, test::ReadFile(path),
        [](const std::string& p, std::string* text) {
          if (!test::FileExists(p)) return std::string("cannot open");
          *text = test::ReadFile(p);
          return std::string();
        },
        &whole, &warnings, options);
    SceneInfo info;
    ASSERT_TRUE(CountObj(path, &info).ok()) << path;
    std::vector<Polygon> scanned, streamed;
    Status ss = ScanObj(
        path, options,
        [&](uint32_t i, const Polygon& p) {
          EXPECT_EQ(i, scanned.size());
          scanned.push_back(p);
        },
        &info);
    EXPECT_EQ(ws.ToString(), ss.ToString()) << path;
    if (!ws.ok() || !ss.ok()) continue;
    ++loaded;
    EXPECT_EQ(warnings, info.warnings) << path;
    EXPECT_EQ(0, std::memcmp(&whole.bounds, &info.bounds, sizeof whole.bounds)) << path;
    ASSERT_EQ(whole.materials.size(), info.materials.size()) << path;
    for (size_t m = 0; m < whole.materials.size(); ++m) {
      EXPECT_EQ(whole.materials[m].name, info.materials[m].name);
      EXPECT_EQ(whole.materials[m].ke, info.materials[m].ke) << path;
    }
    ASSERT_TRUE(
        StreamObj(info, options, [&](uint32_t, const Polygon& p) { streamed.push_back(p); }).ok());
    ASSERT_EQ(whole.polygons.size(), scanned.size()) << path;
    ASSERT_EQ(whole.polygons.size(), streamed.size()) << path;
    EXPECT_EQ(whole.polygons.size(), info.numPolygons);
    for (size_t i = 0; i < whole.polygons.size(); ++i) {
      ExpectSamePolygon(whole.polygons[i], scanned[i], path + " pass 1");
      ExpectSamePolygon(whole.polygons[i], streamed[i], path + " pass 2");
    }
    // Clipped one polygon at a time, as the streaming init does, then put
    // in environment order: the whole partition's pieces.
    EnvGrid grid;
    grid.n[0] = 3, grid.n[1] = 2, grid.n[2] = 2;
    grid.box = whole.bounds;
    Partition all;
    ASSERT_TRUE(PartitionScene(whole, grid, &all).ok()) << path;
    struct Piece {
      uint32_t env, source;
      Polygon p;
    };
    std::vector<Piece> pieces;
    Scene one;
    one.objPath = path;
    one.bounds = whole.bounds;
    for (uint32_t i = 0; i < streamed.size(); ++i) {
      one.polygons.assign(1, streamed[i]);
      Partition cut;
      ASSERT_TRUE(PartitionScene(one, grid, &cut).ok()) << path;
      for (size_t k = 0; k < cut.scene.polygons.size(); ++k)
        pieces.push_back({cut.env[k], i, cut.scene.polygons[k]});
    }
    std::stable_sort(pieces.begin(), pieces.end(),
                     [](const Piece& a, const Piece& b) { return a.env < b.env; });
    ASSERT_EQ(pieces.size(), all.scene.polygons.size()) << path;
    for (size_t k = 0; k < pieces.size(); ++k) {
      EXPECT_EQ(pieces[k].env, all.env[k]) << path;
      EXPECT_EQ(pieces[k].source, all.source[k]) << path;
      ExpectSamePolygon(pieces[k].p, all.scene.polygons[k], path + " piece");
    }
  }
  EXPECT_GE(loaded, 18u);
}

// Pass 1 gives every error LoadScene gives, at the same file:line.
TEST(SceneStreamTest, SameErrors) {
  TempDir dir;
  test::WriteFile(dir.File("m.mtl"),
                  "newmtl light\nKe 1 1 1\nKd 0.5 0.5 0.5\nnewmtl dark\nKd 0.5 0.5 0.5\n"
                  "newmtl white\nKd 1 1 1\nKe 0 0 0\n");
  const std::string head = "mtllib m.mtl\nusemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n";
  const std::vector<std::string> bodies = {
      "f 1 2 9\n",                            // out of range
      "f 1 2\n",                              // too few
      "v 1 abc 0\nf 1 2 3\n",                 // bad number
      "usemtl dark\nf 1 2 3\n",               // no emitter
      "f 1 2 3\nl 1 2\n",                     // lines
      "usemtl nothing\n",                     // unknown material
      "v 0 0 2e15\nf 1 2 5\n",                // beyond float's range
      "v 1e-16 0 0\nv 0 1e-16 0\nf 1 5 6\n",  // a face too small
      "f 1 2 3\nf 3 2 1\n",                   // fine
  };
  for (const std::string& body : bodies) {
    const std::string path = dir.File("s.obj");
    test::WriteFile(path, head + body);
    for (bool strict : {false, true}) {
      LoadOptions options;
      options.strict = strict;
      Scene whole;
      std::vector<std::string> w;
      Status a = LoadSceneFromText(
          path, head + body,
          [](const std::string& p, std::string* text) {
            *text = test::ReadFile(p);
            return std::string();
          },
          &whole, &w, options);
      SceneInfo info;
      ASSERT_TRUE(CountObj(path, &info).ok());
      Status b = ScanObj(
          path, options, [](uint32_t, const Polygon&) {}, &info);
      EXPECT_EQ(a.ToString(), b.ToString()) << body;
    }
  }
  SceneInfo info;
  Status missing = CountObj(dir.File("none.obj"), &info);
  Scene whole;
  EXPECT_EQ(missing.ToString(), LoadScene(dir.File("none.obj"), &whole).ToString());
}

// The emitter check traced a few polygons at a time gives what one grid over
// the whole scene gives, estimate for estimate (and the same warnings).
TEST(SceneStreamTest, ChunkedEmitterCheckIsTheWholeOne) {
  size_t compared = 0;
  for (const std::string& path : EveryScene()) {
    Scene scene;
    if (!LoadScene(path, &scene, OptionsFor(path)).ok()) continue;
    std::vector<EmitterEstimate> whole = EstimateEmitters(scene);
    for (size_t chunk : {size_t{1}, size_t{7}, size_t{64}}) {
      std::vector<EmitterEstimate> part = EstimateEmitters(scene, chunk);
      ASSERT_EQ(whole.size(), part.size()) << path;
      for (size_t i = 0; i < whole.size(); ++i) {
        EXPECT_EQ(whole[i].polygon, part[i].polygon);
        EXPECT_EQ(whole[i].nearShare, part[i].nearShare) << path << " chunk " << chunk;
        EXPECT_EQ(whole[i].nearDistance, part[i].nearDistance) << path << " chunk " << chunk;
        EXPECT_EQ(whole[i].escapeShare, part[i].escapeShare) << path << " chunk " << chunk;
        EXPECT_EQ(whole[i].backEscapeShare, part[i].backEscapeShare) << path << " chunk " << chunk;
      }
      compared += whole.size();
    }
  }
  EXPECT_GT(compared, 20u);
}

// The camera's probe keeps the nearest hit per ray with a fixed tie rule,
// so the order polygons come in does not matter.
TEST(SceneStreamTest, ViewProbeIsOrderFree) {
  for (const std::string& path : EveryScene()) {
    Scene scene;
    if (!LoadScene(path, &scene, OptionsFor(path)).ok()) continue;
    ViewProbe forward(scene.bounds), backward(scene.bounds);
    for (uint32_t k = 0; k < scene.polygons.size(); ++k) forward.Add(k, scene.polygons[k]);
    for (uint32_t k = static_cast<uint32_t>(scene.polygons.size()); k-- > 0;)
      backward.Add(k, scene.polygons[k]);
    uint32_t a[kNumViewSides], b[kNumViewSides];
    forward.Rays(a);
    backward.Rays(b);
    for (int s = 0; s < kNumViewSides; ++s) EXPECT_EQ(a[s], b[s]) << path << " side " << s;
  }
}

}  // namespace
}  // namespace vismask
