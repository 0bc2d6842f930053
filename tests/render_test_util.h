// Shared by the render tests: bad command lines, and the closed box whose
// radiosity has a closed form.
#pragma once
#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace vismask::test {

// A command line that must fail.
struct BadCase {
  std::vector<std::string> args;
  const char* message;  // a substring of the expected stderr
};

// A closed cube of side `s`, six faces facing inward, one material.
inline void WriteClosedBox(const std::string& dir, double s, double rho, double e) {
  std::ostringstream obj;
  obj << "mtllib box.mtl\nusemtl wall\n";
  const double c[8][3] = {{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0},
                          {0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}};
  for (auto& v : c) obj << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
  // Counter-clockwise seen from inside the cube.
  obj << "f 1 2 3 4\n"   // z = 0, normal +z
      << "f 5 8 7 6\n"   // z = s, normal -z
      << "f 1 5 6 2\n"   // y = 0, normal +y
      << "f 4 3 7 8\n"   // y = s, normal -y
      << "f 1 4 8 5\n"   // x = 0, normal +x
      << "f 2 6 7 3\n";  // x = s, normal -x
  WriteFile(dir + "/box.obj", obj.str());
  std::ostringstream mtl;
  mtl << "newmtl wall\nKd " << rho << " " << rho << " " << rho << "\nKe " << e << " " << e << " "
      << e << "\n";
  WriteFile(dir + "/box.mtl", mtl.str());
}

}  // namespace vismask::test
