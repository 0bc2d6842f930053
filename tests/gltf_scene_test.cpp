// glTF 2.0 input (issue 40): a scene written both as OBJ + MTL and as glTF
// (.gltf with its buffer in a data: URI, and .glb) renders the same bytes;
// node transforms, doubleSided, emissive strength, an embedded texture and
// the file's camera are read; what vismask cannot use is named in one
// warning; malformed files are refused with exit 2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/scene/scene.h"
#include "vismask/scene/texture.h"

namespace vismask {
namespace {

using test::ReadFile;
using test::RunMain;
using test::TempDir;

std::string Base64(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8) | uint8_t(in[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += k[(v >> s) & 63];
  }
  if (i + 1 == in.size()) {
    uint32_t v = uint8_t(in[i]) << 16;
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == in.size()) {
    uint32_t v = (uint8_t(in[i]) << 16) | (uint8_t(in[i + 1]) << 8);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += k[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

std::string G17(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}
std::string G9(float x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.9g", x);
  return b;
}

// A scene as both files see it: triangles with a material each (and uv),
// materials with Kd, Ke, an optional texture (encoded image bytes).
struct TestMaterial {
  std::string name;
  glm::vec3 kd{0.5f}, ke{0.0f};
  bool doubleSided = false;
  std::string image;  // encoded (BMP); with it, the material's map
};
struct TestTriangle {
  glm::vec3 p[3];
  glm::vec2 uv[3];
  uint32_t material;
};
struct TestScene {
  std::vector<TestMaterial> materials;
  std::vector<TestTriangle> triangles;
  bool camera = false;  // at `eye` looking +z (glTF: rotated half a turn about y)
  glm::vec3 eye{0.0f};
  double fovyDeg = 39.3;
};

// The OBJ and MTL (textures written beside them as tN.bmp).
void WriteObj(const TempDir& dir, const TestScene& s, const std::string& name) {
  std::string mtl, obj = "mtllib " + name + ".mtl\n";
  for (size_t m = 0; m < s.materials.size(); ++m) {
    const TestMaterial& t = s.materials[m];
    mtl += "newmtl " + t.name + "\nKd " + G9(t.kd.x) + " " + G9(t.kd.y) + " " + G9(t.kd.z) +
           "\nKe " + G9(t.ke.x) + " " + G9(t.ke.y) + " " + G9(t.ke.z) + "\n";
    if (!t.image.empty()) {
      test::WriteFile(dir.File("t" + std::to_string(m) + ".bmp"), t.image);
      mtl += "map_Kd t" + std::to_string(m) + ".bmp\n";
    }
  }
  int v = 0;
  for (const TestTriangle& t : s.triangles) {
    obj += "usemtl " + s.materials[t.material].name + "\n";
    for (int c = 0; c < 3; ++c)
      obj += "v " + G9(t.p[c].x) + " " + G9(t.p[c].y) + " " + G9(t.p[c].z) + "\nvt " +
             G9(t.uv[c].x) + " " + G9(t.uv[c].y) + "\n";
    obj += "f " + std::to_string(v + 1) + "/" + std::to_string(v + 1) + " " +
           std::to_string(v + 2) + "/" + std::to_string(v + 2) + " " + std::to_string(v + 3) + "/" +
           std::to_string(v + 3) + "\n";
    v += 3;
  }
  test::WriteFile(dir.File(name + ".mtl"), mtl);
  test::WriteFile(dir.File(name + ".obj"), obj);
}

// The glTF: one node, one mesh, a primitive per run of triangles of one
// material, non-indexed; Ke as emissiveFactor Ke / S with strength S / pi
// (S the largest channel), so that pi * factor * strength is Ke again.
// `glb`: binary, the buffer in its BIN chunk; else a .gltf with a data: URI.
void WriteGltf(const std::string& path, const TestScene& s, bool glb) {
  std::string bin, views, accessors, prims, images, textures;
  auto addView = [&](const std::string& bytes) {
    while (bin.size() % 4) bin += '\0';
    if (!views.empty()) views += ",";
    views += "{\"buffer\":0,\"byteOffset\":" + std::to_string(bin.size()) +
             ",\"byteLength\":" + std::to_string(bytes.size()) + "}";
    bin += bytes;
    return std::count(views.begin(), views.end(), '{') - 1;
  };
  auto addFloats = [&](const std::vector<float>& f, const char* type, size_t count) {
    std::string bytes(f.size() * 4, '\0');
    std::memcpy(bytes.data(), f.data(), bytes.size());
    const long view = addView(bytes);
    if (!accessors.empty()) accessors += ",";
    accessors += "{\"bufferView\":" + std::to_string(view) +
                 ",\"componentType\":5126,\"count\":" + std::to_string(count) + ",\"type\":\"" +
                 type + "\"}";
    return std::count(accessors.begin(), accessors.end(), '{') - 1;
  };
  for (size_t i = 0; i < s.triangles.size();) {
    size_t j = i;
    std::vector<float> pos, uv;
    while (j < s.triangles.size() && s.triangles[j].material == s.triangles[i].material) {
      for (int c = 0; c < 3; ++c) {
        for (int a = 0; a < 3; ++a) pos.push_back(s.triangles[j].p[c][a]);
        uv.push_back(s.triangles[j].uv[c].x);
        uv.push_back(1.0f - s.triangles[j].uv[c].y);
      }
      ++j;
    }
    const long p = addFloats(pos, "VEC3", 3 * (j - i));
    const long t = addFloats(uv, "VEC2", 3 * (j - i));
    if (!prims.empty()) prims += ",";
    prims += "{\"attributes\":{\"POSITION\":" + std::to_string(p) +
             ",\"TEXCOORD_0\":" + std::to_string(t) +
             "},\"material\":" + std::to_string(s.triangles[i].material) + "}";
    i = j;
  }
  std::string materials;
  for (const TestMaterial& m : s.materials) {
    if (!materials.empty()) materials += ",";
    const double strength = std::max({m.ke.x, m.ke.y, m.ke.z});
    materials += "{\"name\":\"" + m.name +
                 "\",\"doubleSided\":" + (m.doubleSided ? "true" : "false") +
                 ",\"pbrMetallicRoughness\":{\"metallicFactor\":0,\"baseColorFactor\":[" +
                 G17(m.kd.x) + "," + G17(m.kd.y) + "," + G17(m.kd.z) + ",1]";
    if (!m.image.empty()) {
      const long view = addView(m.image);
      if (!images.empty()) images += ",", textures += ",";
      const long image = std::count(images.begin(), images.end(), '{');
      images += "{\"bufferView\":" + std::to_string(view) + ",\"mimeType\":\"image/bmp\"}";
      textures += "{\"source\":" + std::to_string(image) + "}";
      materials += ",\"baseColorTexture\":{\"index\":" + std::to_string(image) + "}";
    }
    materials += "}";
    if (strength > 0.0)
      materials += ",\"emissiveFactor\":[" + G17(m.ke.x / strength) + "," + G17(m.ke.y / strength) +
                   "," + G17(m.ke.z / strength) +
                   "],\"extensions\":{\"KHR_materials_emissive_strength\":{"
                   "\"emissiveStrength\":" +
                   G17(strength / M_PI) + "}}";
    materials += "}";
  }
  while (bin.size() % 4) bin += '\0';
  std::string json =
      "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":"
      "[\"KHR_materials_emissive_strength\"],\"scene\":0,\"scenes\":[{\"nodes\":[0";
  if (s.camera) json += ",1";
  json += "]}],\"nodes\":[{\"mesh\":0}";
  if (s.camera)
    json += ",{\"camera\":0,\"translation\":[" + G17(s.eye.x) + "," + G17(s.eye.y) + "," +
            G17(s.eye.z) + "],\"rotation\":[0,1,0,0]}";
  json += "],\"meshes\":[{\"primitives\":[" + prims + "]}],\"materials\":[" + materials + "]";
  if (s.camera)
    json += ",\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":" +
            G17(s.fovyDeg * M_PI / 180.0) + ",\"znear\":0.01}}]";
  if (!images.empty()) json += ",\"images\":[" + images + "],\"textures\":[" + textures + "]";
  json += ",\"bufferViews\":[" + views + "],\"accessors\":[" + accessors + "]";
  json += ",\"buffers\":[{\"byteLength\":" + std::to_string(bin.size());
  if (!glb) json += ",\"uri\":\"data:application/octet-stream;base64," + Base64(bin) + "\"";
  json += "}]}";
  if (!glb) {
    test::WriteFile(path, json);
    return;
  }
  while (json.size() % 4) json += ' ';
  auto u32 = [](uint32_t v) {
    std::string b(4, '\0');
    for (int i = 0; i < 4; ++i) b[i] = static_cast<char>((v >> (8 * i)) & 255);
    return b;
  };
  std::string file = "glTF" + u32(2) +
                     u32(static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size())) +
                     u32(static_cast<uint32_t>(json.size())) + "JSON" + json +
                     u32(static_cast<uint32_t>(bin.size())) + std::string("BIN\0", 4) + bin;
  test::WriteFile(path, file);
}

// A 2 x 2 BMP, two colours in a checker.
std::string Bmp(uint8_t a, uint8_t b) {
  std::string f = "BM";
  auto u32 = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) f += static_cast<char>((v >> (8 * i)) & 255);
  };
  auto u16 = [&](uint16_t v) {
    f += static_cast<char>(v & 255);
    f += static_cast<char>(v >> 8);
  };
  u32(70), u32(0), u32(54), u32(40), u32(2), u32(2), u16(1), u16(24), u32(0), u32(16);
  u32(2835), u32(2835), u32(0), u32(0);
  for (int row = 0; row < 2; ++row) {
    for (int x = 0; x < 2; ++x) f += std::string(3, static_cast<char>((x + row) % 2 ? b : a));
    f += std::string(2, '\0');
  }
  return f;
}

// The Cornell box of scenes/cornell.obj, its faces fanned into triangles,
// and a textured floor material in place of the floor's white.
TestScene CornellTriangles(bool doubleSided) {
  Scene scene;
  EXPECT_TRUE(LoadScene("scenes/cornell.obj", &scene).ok());
  TestScene s;
  for (const Material& m : scene.materials) {
    TestMaterial t;
    t.name = m.name;
    t.kd = m.kd;
    t.ke = m.ke;
    t.doubleSided = doubleSided;
    s.materials.push_back(t);
  }
  TestMaterial floor;
  floor.name = "floor_tex";
  floor.kd = glm::vec3(0.75f);
  floor.image = Bmp(230, 40);
  floor.doubleSided = doubleSided;
  s.materials.push_back(floor);
  for (size_t i = 0; i < scene.polygons.size(); ++i) {
    const Polygon& p = scene.polygons[i];
    for (size_t k = 1; k + 1 < p.corners.size(); ++k) {
      TestTriangle t;
      const size_t c[3] = {0, k, k + 1};
      for (int j = 0; j < 3; ++j) {
        t.p[j] = p.corners[c[j]];
        t.uv[j] = glm::vec2(c[j] == 1 || c[j] == 2 ? 1.0f : 0.0f, c[j] >= 2 ? 1.0f : 0.0f);
      }
      // The first polygon is the floor (y = 0 everywhere): textured.
      const bool isFloor = p.normal.y > 0.99f && p.corners[0].y == 0.0f && i == 0;
      t.material = isFloor ? static_cast<uint32_t>(s.materials.size() - 1) : p.material;
      s.triangles.push_back(t);
    }
  }
  return s;
}

const std::vector<std::string> kRun = {"--width",        "48",    "--height", "48",
                                       "--emitted-rays", "20000", "--quiet"};

test::RunResult Render(const std::string& scene, const std::string& out,
                       std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"render", scene, "--out", out};
  args.insert(args.end(), kRun.begin(), kRun.end());
  args.insert(args.end(), extra.begin(), extra.end());
  return RunMain(args);
}

void ExpectSameOutputs(const std::string& a, const std::string& b) {
  for (const char* f : {"image.pfm", "patches.csv"}) {
    const std::string x = ReadFile(a + "/" + f), y = ReadFile(b + "/" + f);
    EXPECT_FALSE(x.empty()) << a << "/" << f;
    EXPECT_TRUE(x == y) << a << "/" << f << " differs from " << b << "/" << f;
  }
}

TEST(GltfTest, TheBoxAsGltfAndGlbRendersTheObjBoxByteForByte) {
  TempDir dir;
  TestScene s = CornellTriangles(false);
  s.camera = true;
  s.eye = glm::vec3(278.0f, 273.0f, -800.0f);
  WriteObj(dir, s, "box");
  WriteGltf(dir.File("box.gltf"), s, false);
  WriteGltf(dir.File("box.glb"), s, true);
  const std::string camera = "278,273,-800,278,273,-799,0,1,0,39.3";
  auto r = Render(dir.File("box.obj"), dir.File("obj"), {"--camera", camera});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"box.gltf", "box.glb"}) {
    const std::string out = dir.File(std::string("out_") + f);
    r = Render(dir.File(f), out);
    ASSERT_EQ(r.code, 0) << f << "\n" << r.err;
    EXPECT_EQ(r.err, "") << f;  // nothing it cannot use
    ExpectSameOutputs(dir.File("obj"), out);
    // The file's camera, recorded as such.
    const std::string json = ReadFile(out + "/run.json");
    EXPECT_NE(json.find("\"camera_from_scene\": true"), std::string::npos) << json;
    EXPECT_NE(json.find("\"view\": null"), std::string::npos);
  }
  // --view wins over the file's camera.
  r = Render(dir.File("box.glb"), dir.File("side"), {"--view", "front"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(ReadFile(dir.File("side/run.json")).find("\"camera_from_scene\": false"),
            std::string::npos);
}

// doubleSided: every face two-sided, an emitter's back emitting too, as
// --two-sided --two-sided-emitters make an OBJ.
TEST(GltfTest, DoubleSidedIsTwoSidedWithEmittingTwins) {
  TempDir dir;
  TestScene s = CornellTriangles(true);
  WriteObj(dir, s, "box");
  WriteGltf(dir.File("box.glb"), s, true);
  auto r = Render(dir.File("box.obj"), dir.File("obj"),
                  {"--two-sided", "--two-sided-emitters", "--view", "front"});
  ASSERT_EQ(r.code, 0) << r.err;
  r = Render(dir.File("box.glb"), dir.File("glb"), {"--view", "front"});
  ASSERT_EQ(r.code, 0) << r.err;
  ExpectSameOutputs(dir.File("obj"), dir.File("glb"));
  // One-sided it is not.
  r = Render(dir.File("box.obj"), dir.File("one"), {"--view", "front"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(ReadFile(dir.File("one/patches.csv")), ReadFile(dir.File("glb/patches.csv")));
}

// Node transforms, fields vismask cannot use, the default material.
TEST(GltfTest, NodeTransformsAndOneWarningForWhatIsNotUsed) {
  TempDir dir;
  // A unit triangle, its node scaled by 2, rotated a quarter turn about z
  // and moved by (10, 0, 0); a second node mirrors it (negative scale),
  // which must keep the triangle facing the same way in the world.
  const std::string json = R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0,1]}],
    "nodes":[{"mesh":0,"translation":[10,0,0],"rotation":[0,0,0.70710678118654757,0.70710678118654757],"scale":[2,2,2]},
             {"mesh":1,"matrix":[-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}],
    "meshes":[{"primitives":[{"attributes":{"POSITION":0},"material":0}]},
              {"primitives":[{"attributes":{"POSITION":0}},{"attributes":{"POSITION":0},"mode":1}]}],
    "materials":[{"name":"lamp","emissiveFactor":[1,0.5,0.25],"normalTexture":{"index":0},
                  "pbrMetallicRoughness":{"roughnessFactor":0.5},
                  "extensions":{"KHR_materials_transmission":{"transmissionFactor":1}}}],
    "textures":[{"source":0}],"images":[{"uri":"normal.png"}],
    "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,)" +
                           Base64(std::string("\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x80\x3f\0\0\0\0\0\0\0\0"
                                              "\0\0\0\0\0\0\x80\x3f\0\0\0\0",
                                              36)) +
                           R"("}],
    "bufferViews":[{"buffer":0,"byteLength":36}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}]})";
  test::WriteFile(dir.File("t.gltf"), json);
  Scene scene;
  std::vector<std::string> warnings;
  Status st = LoadGltf(dir.File("t.gltf"), LoadOptions(), &scene, &warnings);
  ASSERT_TRUE(st.ok()) << st.ToString();
  ASSERT_EQ(scene.polygons.size(), 2u);
  // (0,0,0) (1,0,0) (0,1,0) scaled by 2, turned: (0,0,0) (0,2,0) (-2,0,0), moved.
  const Polygon& a = scene.polygons[0];
  EXPECT_NEAR(a.corners[0].x, 10.0f, 1e-5f);
  EXPECT_NEAR(a.corners[1].x, 10.0f, 1e-5f);
  EXPECT_NEAR(a.corners[1].y, 2.0f, 1e-5f);
  EXPECT_NEAR(a.corners[2].x, 8.0f, 1e-5f);
  EXPECT_NEAR(a.normal.z, 1.0f, 1e-6f);
  // Mirrored in x: still facing +z (its winding reversed with the mirror).
  EXPECT_NEAR(scene.polygons[1].normal.z, 1.0f, 1e-6f);
  EXPECT_NEAR(scene.polygons[1].corners[2].x, -1.0f, 1e-6f);
  // Ke = pi x emissiveFactor (no strength given: 1).
  EXPECT_FLOAT_EQ(scene.materials[0].ke.x, static_cast<float>(M_PI));
  EXPECT_FLOAT_EQ(scene.materials[0].ke.z, static_cast<float>(M_PI * 0.25));
  EXPECT_EQ(scene.materials[0].kd, glm::vec3(1.0f));  // baseColorFactor's default
  EXPECT_EQ(scene.materials[1].name, "default");
  EXPECT_EQ(scene.materials[1].kd, glm::vec3(0.5f));
  EXPECT_EQ(scene.polygons[1].material, 1u);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0], dir.File("t.gltf") +
                             ": warning: 1 triangle with no material: the default grey "
                             "material 'default' (Kd 0.5)");
  EXPECT_EQ(warnings[1], dir.File("t.gltf") +
                             ": warning: glTF fields vismask cannot use (it renders diffuse "
                             "light only), ignored: KHR_materials_transmission (1 material), "
                             "metallicFactor (1 material), roughnessFactor (1 material), "
                             "normalTexture (1 material), points and lines (1 primitive)");
}

TEST(GltfTest, MalformedFilesAreRefusedNamingTheFile) {
  TempDir dir;
  struct Case {
    std::string text;
    std::string word;
  };
  const std::string head =
      R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)";
  const Case cases[] = {
      {"{ not json", "cannot read glTF"},
      {"glTF\x02\0\0\0\x10\0\0\0garbage!", "cannot read glTF"},
      // An accessor running past its buffer.
      {head + R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
        "buffers":[{"byteLength":12,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAA"}],
        "bufferViews":[{"buffer":0,"byteLength":12}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}]})",
       "run past the end"},
      // An index out of range.
      {head + R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
        "buffers":[{"byteLength":42,"uri":"data:application/octet-stream;base64,)" +
           Base64(std::string(36, '\0') + std::string("\0\0\x01\0\x07\0", 6)) + R"("}],
        "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"},
                     {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}]})",
       "out of range"},
      // baseColorFactor above 1.
      {head + R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"material":0}]}],
        "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[2,1,1,1]}}]})",
       "baseColorFactor 2 is not in [0, 1]"},
  };
  for (const Case& c : cases) {
    test::WriteFile(dir.File("bad.gltf"), c.text);
    auto r = Render(dir.File("bad.gltf"), dir.File("out"));
    EXPECT_EQ(r.code, 2) << c.text;
    EXPECT_EQ(r.err.rfind(dir.File("bad.gltf") + ": ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.word), std::string::npos) << r.err;
    EXPECT_FALSE(test::FileExists(dir.File("out")));
  }
}

// The published Blender boxes (scenes/gltf-cornell, CC0), read as
// published. The .gltf: the light's emissive strength and double-sidedness
// kept, its texture not shipped (one warning). The .glb is another export,
// with two textures inside and no light: --emit makes one.
TEST(GltfTest, ThePublishedBlenderBoxesRender) {
  TempDir dir;
  const std::string gltf = "scenes/gltf-cornell/cornell_box.gltf";
  Scene scene;
  std::vector<std::string> warnings;
  Status st = LoadGltf(gltf, LoadOptions(), &scene, &warnings);
  ASSERT_TRUE(st.ok()) << st.ToString();
  ASSERT_EQ(scene.materials.size(), 6u);
  const Material& light = scene.materials[3];
  EXPECT_EQ(light.name, "light_mat");
  EXPECT_FLOAT_EQ(light.ke.x, static_cast<float>(5.0 * M_PI));  // strength 5
  for (const Material& m : scene.materials) EXPECT_TRUE(m.twoSided) << m.name;
  EXPECT_EQ(scene.polygons.size(), 36u);
  // The tall box's base colour is its missing texture (factor 1): without
  // it, a mid grey (Kd 1 would close a lossless cavity inside the box).
  SceneTextures textures;
  ASSERT_TRUE(LoadSceneTextures(&scene, &textures).ok());
  EXPECT_EQ(scene.materials[2].name, "tall_box_mat");
  EXPECT_EQ(scene.materials[2].kd, glm::vec3(0.5f));
  EXPECT_EQ(scene.materials[2].mapKd, "");
  auto r = Render(gltf, dir.File("gltf"), {"--view", "left"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("1 texture not found"), std::string::npos) << r.err;
  EXPECT_NE(ReadFile(dir.File("gltf/run.json")).find("\"stop_reason\": \"converged\""),
            std::string::npos);
  // The light faces the ceiling 6 mm away, but it is double-sided: no
  // warning that it is wound the wrong way.
  EXPECT_EQ(r.err.find("wound the wrong way"), std::string::npos) << r.err;
  EXPECT_NE(ReadFile(dir.File("gltf/run.json")).find("\"textures\": []"), std::string::npos);

  const std::string glb = "scenes/gltf-cornell/cornell_box.glb";
  r = Render(glb, dir.File("glb"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no emitter"), std::string::npos) << r.err;
  r = Render(glb, dir.File("glb"), {"--max-shots", "300", "--emit", "box_mat=3,3,3"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = ReadFile(dir.File("glb/run.json"));
  EXPECT_NE(json.find("cornell_box.glb#images[0]\", \"width\": 1024"), std::string::npos)
      << json.substr(json.find("\"textures\""), 300);
  EXPECT_NE(json.find("cornell_box.glb#images[1]"), std::string::npos);
}

}  // namespace
}  // namespace vismask
