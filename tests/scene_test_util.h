// The scene tests' fixture: a directory of its own for each test, a good
// MTL and OBJ header, and loading helpers.
#pragma once
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "vismask/scene/scene.h"

namespace vismask::test {

// A good MTL (one emitter) and an OBJ header using it: 6 lines, so the first
// statement of a test's body is line 7.
inline constexpr char kMtl[] =
    "newmtl white\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
inline constexpr char kHead[] = "mtllib m.mtl\nusemtl light\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

inline const LoadOptions kStrict{true, {}};  // --strict

inline void ExpectError(const Status& s, const std::string& file, int line,
                        const std::string& word) {
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.file(), file);
  EXPECT_EQ(s.line(), line);
  EXPECT_NE(s.message().find(word), std::string::npos) << s.ToString();
}

// Each test gets its own directory for the files it writes.
class SceneTest : public testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (std::filesystem::temp_directory_path() / "vismask_scene_XXXXXX").string();
    ASSERT_NE(mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl + "/";
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ + name, std::ios::binary) << text;
    return dir_ + name;
  }
  // Loads kHead + `body` with kMtl as m.mtl.
  Status LoadBody(const std::string& body, Scene* scene,
                  const LoadOptions& options = LoadOptions()) {
    Write("m.mtl", kMtl);
    return LoadScene(Write("s.obj", kHead + body), scene, options);
  }
  // The same, its warnings in *warnings.
  Status LoadBodyWarnings(const std::string& body, Scene* scene, std::vector<std::string>* warnings,
                          const LoadOptions& options = LoadOptions()) {
    Write("m.mtl", kMtl);
    return LoadObjWarnings(Write("s.obj", kHead + body), scene, warnings, options);
  }
  // Loads the OBJ at `path` (MTL files from disk), its warnings in *warnings.
  Status LoadObjWarnings(const std::string& path, Scene* scene, std::vector<std::string>* warnings,
                         const LoadOptions& options = LoadOptions()) {
    std::ifstream in(path, std::ios::binary);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto read = [](const std::string& file, std::string* t) {
      std::ifstream m(file, std::ios::binary);
      t->assign(std::istreambuf_iterator<char>(m), std::istreambuf_iterator<char>());
      return std::string(m ? "" : "cannot open");
    };
    return LoadSceneFromText(path, text, read, scene, warnings, options);
  }
  // Loads kHead with `mtlText` as m.mtl: an error at `line` of m.mtl, with
  // `word` in its message.
  void ExpectMtlError(const std::string& mtlText, int line, const std::string& word) {
    Write("m.mtl", mtlText);
    Scene scene;
    ExpectError(LoadScene(Write("s.obj", kHead), &scene), mtl(), line, word);
  }
  std::string obj() const { return dir_ + "s.obj"; }
  std::string mtl() const { return dir_ + "m.mtl"; }

  std::string dir_;
};

}  // namespace vismask::test
