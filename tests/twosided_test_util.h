// A scene loaded from OBJ text against an MTL of a light and a white
// material: for the two-sided and emitter-check tests.
#pragma once
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "vismask/scene/scene.h"

namespace vismask::twosided {

inline constexpr char kMtl[] =
    "newmtl light\nKd 0.5 0.5 0.5\nKe 10 10 10\n"
    "newmtl white\nKd 0.7 0.7 0.7\n";

// `obj` after "mtllib test.mtl", loaded as the file `name` with kMtl.
inline Scene LoadText(const std::string& obj, const std::string& name = "test.obj") {
  Scene scene;
  std::vector<std::string> warnings;
  Status s = LoadSceneFromText(
      name, "mtllib test.mtl\n" + obj,
      [](const std::string&, std::string* text) {
        *text = kMtl;
        return std::string();
      },
      &scene, &warnings);
  EXPECT_TRUE(s.ok()) << s.ToString();
  return scene;
}

}  // namespace vismask::twosided
