// `vismask scene-dump`: the JSON holds the scene LoadScene loads (the
// polygons as mended, their materials, Kd and Ke after --emit, glTF's
// two-sided materials), the camera `render` uses with the same options (as
// run.json records it), and --sky and --sun; it refuses what render refuses,
// with the same message and nothing written. The tools that read scenes
// through it (tools/silhouette-mask, tools/renderpark-run, tools/reference)
// refuse what vismask refuses, with vismask's message, and accept what it
// accepts.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/scene/scene.h"

namespace vismask {
namespace {

using test::FileExists;
using test::HaveNumpy;
using test::ReadFile;
using test::RunMain;
using test::RunShell;
using test::Shell;
using test::TempDir;
using test::WriteFile;

nlohmann::json Dump(const std::vector<std::string>& args, const std::string& out) {
  std::vector<std::string> a{"scene-dump"};
  a.insert(a.end(), args.begin(), args.end());
  a.insert(a.end(), {"--out", out});
  test::RunResult r = RunMain(a);
  EXPECT_EQ(r.code, 0) << r.err;
  if (r.code != 0) return nlohmann::json();
  return nlohmann::json::parse(ReadFile(out));
}

glm::vec3 Vec(const nlohmann::json& j) {
  return glm::vec3(j.at(0).get<float>(), j.at(1).get<float>(), j.at(2).get<float>());
}

// Every polygon, material and bound of `d` is the loaded scene's, float for
// float; but material `missing`, whose texture file is not there, which
// render shows (and scene-dump writes) untextured with half its Kd factor.
void ExpectScene(const nlohmann::json& d, const Scene& s, const std::string& missing = "") {
  ASSERT_EQ(d["faces"].size(), s.polygons.size());
  for (size_t i = 0; i < s.polygons.size(); ++i) {
    const nlohmann::json& f = d["faces"][i];
    const Polygon& p = s.polygons[i];
    EXPECT_EQ(f["material"].get<uint32_t>(), p.material) << i;
    EXPECT_EQ(f["line"].get<int>(), p.line) << i;
    ASSERT_EQ(f["corners"].size(), p.corners.size()) << i;
    for (size_t c = 0; c < p.corners.size(); ++c)
      EXPECT_EQ(Vec(f["corners"][c]), p.corners[c]) << "face " << i << " corner " << c;
  }
  ASSERT_EQ(d["materials"].size(), s.materials.size());
  for (size_t k = 0; k < s.materials.size(); ++k) {
    const nlohmann::json& m = d["materials"][k];
    EXPECT_EQ(m["name"].get<std::string>(), s.materials[k].name);
    if (s.materials[k].name == missing) {
      EXPECT_FALSE(s.materials[k].mapKd.empty());
      EXPECT_TRUE(m["texture"].is_null());
      EXPECT_EQ(Vec(m["kd"]), 0.5f * s.materials[k].kd);
      continue;
    }
    EXPECT_EQ(Vec(m["kd"]), s.materials[k].kd) << s.materials[k].name;
    EXPECT_EQ(Vec(m["ke"]), s.materials[k].ke) << s.materials[k].name;
    EXPECT_EQ(m["two_sided"].get<bool>(), s.materials[k].twoSided) << s.materials[k].name;
    EXPECT_EQ(m["texture"].is_null(), s.materials[k].mapKd.empty()) << s.materials[k].name;
    if (!s.materials[k].mapKd.empty()) {
      EXPECT_EQ(m["texture"].get<std::string>(), s.materials[k].mapKd);
    }
  }
  EXPECT_EQ(Vec(d["bounds"]["lo"]), s.bounds.lo);
  EXPECT_EQ(Vec(d["bounds"]["hi"]), s.bounds.hi);
}

// run.json's camera (ten numbers), view and view_auto, as scene-dump writes them.
void ExpectRenderCamera(const nlohmann::json& d, const std::string& runJson) {
  const nlohmann::json o = nlohmann::json::parse(runJson)["options"];
  const nlohmann::json& c = d["camera"];
  std::vector<float> want;
  for (const auto& v : o["camera"]) want.push_back(v.get<float>());
  ASSERT_EQ(want.size(), 10u);
  const glm::vec3 eye = Vec(c["eye"]), target = Vec(c["target"]), up = Vec(c["up"]);
  const std::vector<float> got{eye.x,    eye.y, eye.z, target.x, target.y,
                               target.z, up.x,  up.y,  up.z,     c["fovy"].get<float>()};
  EXPECT_EQ(got, want);
  const std::string view = o["view"].is_null() ? "" : o["view"].get<std::string>();
  if (view == "inside") {
    EXPECT_EQ(c["from"], "inside");
    EXPECT_TRUE(c["view"].is_null());
  } else if (!view.empty()) {
    EXPECT_EQ(c["from"], "side");
    EXPECT_EQ(c["view"], view);
    EXPECT_EQ(c["view_auto"].get<bool>(), o["view_auto"].get<bool>());
  }
}

std::string TinyRunJson(const TempDir& dir, std::vector<std::string> args) {
  args.insert(args.begin(), "render");
  args.insert(args.end(), {"--out", dir.File("run"), "--max-shots", "2", "--rays", "16", "--width",
                           "16", "--height", "16", "--quiet"});
  test::RunResult r = RunMain(args);
  EXPECT_EQ(r.code, 0) << r.err;
  return ReadFile(dir.File("run/run.json"));
}

TEST(SceneDumpTest, CornellIsTheLoadedSceneWithEmitAndRendersCamera) {
  TempDir dir;
  const std::vector<std::string> args{"scenes/cornell.obj", "--emit", "yellow=1,2,3"};
  nlohmann::json d = Dump(args, dir.File("d.json"));
  ASSERT_FALSE(d.is_null());
  EXPECT_EQ(d["format"], "vismask-scene 1");
  EXPECT_EQ(d["files"], nlohmann::json({"scenes/cornell.obj", "scenes/cornell.mtl"}));
  Scene s;
  LoadOptions lo;
  lo.emit.push_back({"yellow", false, glm::vec3(1, 2, 3)});
  ASSERT_TRUE(LoadScene("scenes/cornell.obj", &s, lo).ok());
  ExpectScene(d, s);
  bool yellow = false;
  for (const auto& m : d["materials"])
    if (m["name"] == "yellow") {
      yellow = true;
      EXPECT_EQ(Vec(m["ke"]), glm::vec3(1, 2, 3));  // --emit replaced the MTL's Ke
    }
  EXPECT_TRUE(yellow);
  EXPECT_TRUE(d["sky"].is_null());
  EXPECT_TRUE(d["sun"].is_null());
  ExpectRenderCamera(d, TinyRunJson(dir, args));
  EXPECT_EQ(d["camera"]["view"], "front");
  EXPECT_EQ(d["front_camera"]["eye"], d["camera"]["eye"]);  // the Cornell box's view is front

  // --view and --camera: render's camera for them too.
  d = Dump({"scenes/cornell.obj", "--view", "top"}, dir.File("top.json"));
  ExpectRenderCamera(d, TinyRunJson(dir, {"scenes/cornell.obj", "--view", "top"}));
  EXPECT_FALSE(d["camera"]["view_auto"].get<bool>());
  const std::string cam = "1,2,-500,3,4,5,0,1,0,50";
  d = Dump({"scenes/cornell.obj", "--camera", cam}, dir.File("cam.json"));
  EXPECT_EQ(d["camera"]["from"], "--camera");
  ExpectRenderCamera(d, TinyRunJson(dir, {"scenes/cornell.obj", "--camera", cam}));
}

TEST(SceneDumpTest, SkylightIsSeenFromInsideWithSkyAndSun) {
  TempDir dir;
  const std::vector<std::string> args{"scenes/skylight.obj", "--sky", "0.5,0.25,1", "--sun",
                                      "0,2,0,3,4,5,1.5"};
  nlohmann::json d = Dump(args, dir.File("d.json"));
  ASSERT_FALSE(d.is_null());
  Scene s;
  LoadOptions lo;
  lo.outsideLight = true;
  ASSERT_TRUE(LoadScene("scenes/skylight.obj", &s, lo).ok());
  ExpectScene(d, s);
  EXPECT_EQ(Vec(d["sky"]), glm::vec3(0.5f, 0.25f, 1.0f));
  EXPECT_EQ(Vec(d["sun"]["toward"]), glm::vec3(0, 1, 0));  // normalised
  EXPECT_EQ(Vec(d["sun"]["irradiance"]), glm::vec3(3, 4, 5));
  EXPECT_EQ(d["sun"]["degrees"].get<float>(), 1.5f);
  ExpectRenderCamera(d, TinyRunJson(dir, args));
  EXPECT_EQ(d["camera"]["from"], "inside");
  EXPECT_NE(d["front_camera"]["eye"], d["camera"]["eye"]);
}

TEST(SceneDumpTest, GltfIsTheLoadedSceneWithTwoSidedMaterials) {
  TempDir dir;
  const std::string path = "scenes/gltf-cornell/cornell_box.gltf";
  nlohmann::json d = Dump({path}, dir.File("d.json"));
  ASSERT_FALSE(d.is_null());
  EXPECT_EQ(d["files"], nlohmann::json({path}));
  Scene s;
  ASSERT_TRUE(LoadScene(path, &s).ok());
  // Its texture, textures/testwaifu.png, is not in the download (README).
  ExpectScene(d, s, "tall_box_mat");
  int twoSided = 0;
  for (const auto& m : d["materials"]) twoSided += m["two_sided"].get<bool>();
  EXPECT_GT(twoSided, 0);  // the published box's materials are double-sided
  ExpectRenderCamera(d, TinyRunJson(dir, {path}));
}

TEST(SceneDumpTest, RefusesWhatRenderRefusesAndWritesNothing) {
  TempDir dir;
  WriteFile(dir.File("s.mtl"), "newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\nKa -1 0 0\n");
  WriteFile(dir.File("s.obj"), "mtllib s.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  WriteFile(dir.File("dark.mtl"), "newmtl a\nKd 0.5 0.5 0.5\n");
  WriteFile(dir.File("dark.obj"),
            "mtllib dark.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{dir.File("s.obj")}, dir.File("s.mtl") + ":4:"},
      {{dir.File("dark.obj")}, "no emitter"},
      {{dir.File("nothere.obj")}, "nothere.obj"},
      {{"scenes/cornell.obj", "--emit", "nosuch=1,1,1"}, "nosuch"},
      {{"scenes/cornell.obj", "--camera", "0,0,0,0,0,0,0,1,0,40"}, "--camera"},
      {{"scenes/cornell.obj", "--sky", "-1,0,0"}, "--sky"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> dump{"scene-dump"}, render{"render"};
    dump.insert(dump.end(), c.args.begin(), c.args.end());
    render.insert(render.end(), c.args.begin(), c.args.end());
    dump.insert(dump.end(), {"--out", dir.File("d.json")});
    render.insert(render.end(), {"--out", dir.File("r"), "--quiet"});
    test::RunResult rd = RunMain(dump), rr = RunMain(render);
    EXPECT_EQ(rd.code, 2) << c.message;
    EXPECT_EQ(rr.code, 2) << c.message;
    EXPECT_NE(rd.err.find(c.message), std::string::npos) << rd.err;
    EXPECT_EQ(rd.err, rr.err);  // render's words exactly
    EXPECT_FALSE(FileExists(dir.File("d.json"))) << c.message;
  }
  // --out must be a .json file (the default "out" is render's directory).
  test::RunResult r = RunMain({"scene-dump", "scenes/cornell.obj"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--out FILE.json"), std::string::npos) << r.err;
  Shell h = RunShell(test::VismaskBin() + " scene-dump --help");
  EXPECT_EQ(h.code, 0) << h.out;
  EXPECT_EQ(h.out.rfind("usage: vismask scene-dump SCENE", 0), 0u) << h.out;
}

// What the tools refuse is vismask's refusal, word for word (a negative Ka,
// which only vismask's loader checks), and what vismask mends they accept
// (a face before any 'usemtl', which the loader gives a made-up material).
TEST(SceneDumpTest, ToolsRefuseWhatVismaskRefuses) {
  if (!HaveNumpy()) GTEST_SKIP() << "numpy missing (tools/install-deps --reference)";
  TempDir dir;
  WriteFile(dir.File("bad.mtl"), "newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\nKa -1 0 0\n");
  WriteFile(dir.File("bad.obj"),
            "mtllib bad.mtl\nusemtl a\nv -1 -1 5\nv 1 -1 5\nv 1 1 5\nv -1 1 5\nf 1 2 3 4\n");
  WriteFile(dir.File("ok.mtl"), "newmtl a\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
  WriteFile(dir.File("ok.obj"),
            "mtllib ok.mtl\nv -9 -9 9\nv 9 -9 9\nv 9 9 9\nv -9 9 9\nf 1 2 3 4\n"
            "usemtl a\nv -1 -1 5\nv 1 -1 5\nv 1 1 5\nv -1 1 5\nf 5 6 7 8\n");
  test::RunResult v = RunMain({"render", dir.File("bad.obj"), "--out", dir.File("r")});
  ASSERT_EQ(v.code, 2) << v.err;
  const std::string refusal = v.err.substr(0, v.err.find('\n'));
  ASSERT_NE(refusal.find(dir.File("bad.mtl") + ":4:"), std::string::npos) << refusal;
  const std::string env = "VISMASK_BIN=" + test::VismaskBin() + " ";
  const std::string camera = " --camera 0,0,0,0,0,1,0,1,0,90 --size 16 16 ";
  for (const std::string& tool :
       {env + "tools/silhouette-mask SCENE" + camera + "--out " + dir.File("m.pgm"),
        env + "tools/renderpark-run mgf SCENE --out " + dir.File("s.mgf"),
        env + "tools/reference SCENE --size 16 16 --spp 2 --no-cache --quiet --out " +
            dir.File("ref.pfm")}) {
    auto at = [&](const std::string& scene) {
      std::string cmd = tool;
      cmd.replace(cmd.find("SCENE"), 5, scene);
      return cmd;
    };
    Shell r = RunShell(at(dir.File("bad.obj")));
    EXPECT_EQ(r.code, 2) << tool << "\n" << r.out;
    EXPECT_NE(r.out.find(refusal), std::string::npos) << tool << "\n" << r.out;
    if (tool.find("tools/reference") != std::string::npos) continue;  // Blender: not here
    r = RunShell(at(dir.File("ok.obj")));
    EXPECT_EQ(r.code, 0) << tool << "\n" << r.out;
  }
  // The mesh the tools build: ok.obj's two faces, the made-up material first.
  std::string mgf = ReadFile(dir.File("s.mgf"));
  EXPECT_NE(mgf.find("m m0\nf v0 v1 v2 v3\nm m1\nf v4 v5 v6 v7\n"), std::string::npos) << mgf;
  EXPECT_NE(mgf.find("\ted "), std::string::npos) << mgf;  // material a emits
  // A camera vismask refuses (eye at the target) is refused as vismask words it.
  Shell r = RunShell(env + "tools/silhouette-mask " + dir.File("ok.obj") +
                     " --camera 0,0,5,0,0,5,0,1,0,90 --size 16 16 --out " + dir.File("m2.pgm"));
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--camera"), std::string::npos) << r.out;
  EXPECT_FALSE(FileExists(dir.File("m2.pgm")));
}

}  // namespace
}  // namespace vismask
