#include "vismask/app/viewer.h"

#include <cstdint>
#include <cstring>

#include "vismask/core/os.h"

namespace vismask {

namespace {

constexpr int kExitNoViewer = 1, kExitUsage = 2;

bool EndsWith(const std::string& s, const char* suffix) {
  size_t n = std::strlen(suffix);
  return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

uint32_t Le32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// A binary glTF 2.0 header: "glTF", version 2, the file's length.
Status CheckGlbHeader(const std::string& path) {
  os::InFile in;
  std::string why;
  if (!in.Open(path.c_str(), &why)) return Status::Error("vismask: view: cannot read " + path);
  const int64_t size = in.Size();
  unsigned char h[12] = {};
  if (size < 12 || in.Read(h, sizeof h, &why) != 12 || std::memcmp(h, "glTF", 4) != 0 ||
      Le32(h + 4) != 2)
    return Status::Error("vismask: view: " + path +
                         ": not binary glTF 2.0 (vismask render --export FILE.glb writes it)");
  if (Le32(h + 8) != static_cast<uint64_t>(size))
    return Status::Error("vismask: view: " + path + ": its header says " +
                         std::to_string(Le32(h + 8)) + " bytes, the file has " +
                         std::to_string(size) + " (cut short?)");
  return Status::Ok();
}

}  // namespace

std::vector<std::string> ViewerCandidates(const std::string& exeDir) {
  return {exeDir + "/../share/vismask/viewer", exeDir + "/../viewer", exeDir + "/../../viewer"};
}

Status FindViewerDir(const std::vector<std::string>& candidates, std::string* dir) {
  std::string tried;
  for (const std::string& c : candidates) {
    tried += (tried.empty() ? "" : ", ") + c;
    if (!os::Exists((c + "/index.html").c_str()) || !os::Exists((c + "/serve.py").c_str()))
      continue;
    if (!os::Exists((c + "/vendor/three.module.js").c_str()))
      return Status::Error(
          "vismask: view: the viewer in " + c +
          " has no three.js files (vendor/three.module.js): run 'make viewer' in the "
          "source tree (it needs npm; tools/install-deps)");
    *dir = c;
    return Status::Ok();
  }
  return Status::Error(
      "vismask: view: cannot find the viewer page (index.html and serve.py); looked in " + tried);
}

Status ChooseMesh(const std::string& outDir, const std::string& glb, std::string* name) {
  if (!os::Exists(outDir.c_str()))
    return Status::Error("vismask: view: " + outDir + ": no such directory");
  if (!os::IsDirectory(outDir.c_str()))
    return Status::Error("vismask: view: " + outDir +
                         ": not a directory (give a render's --out directory)");
  std::vector<std::string> names;
  std::string why;
  if (!os::ListDirectory(outDir.c_str(), &names, &why))
    return Status::Error("vismask: view: " + why);
  if (!glb.empty()) {
    if (glb.find('/') != std::string::npos || glb == "." || glb == "..")
      return Status::Error("vismask: view: --glb: expected a file name in " + outDir + ", got '" +
                           glb + "'");
    if (!os::Exists((outDir + "/" + glb).c_str()))
      return Status::Error("vismask: view: " + outDir + "/" + glb + ": no such file");
    *name = glb;
  } else {
    std::vector<std::string> meshes;
    for (const std::string& n : names)
      if (EndsWith(n, ".glb")) meshes.push_back(n);
    if (meshes.empty())
      return Status::Error("vismask: view: " + outDir + " holds no .glb (render with --export " +
                           outDir + "/NAME.glb)");
    if (meshes.size() > 1) {
      std::string list;
      for (const std::string& m : meshes) list += (list.empty() ? "" : ", ") + m;
      return Status::Error("vismask: view: " + outDir + " holds several meshes (" + list +
                           "): choose one with --glb NAME.glb");
    }
    *name = meshes[0];
  }
  return CheckGlbHeader(outDir + "/" + *name);
}

int View(const Options& o) {
  std::string glb, viewer;
  Status s = ChooseMesh(o.viewDir, o.viewGlb, &glb);
  if (!s.ok()) {
    os::PrintErr("%s\n", s.message().c_str());
    return kExitUsage;
  }
  const std::string exeDir = os::ExecutableDir();
  s = exeDir.empty()
          ? Status::Error("vismask: view: cannot tell where this program is (/proc/self/exe)")
          : FindViewerDir(ViewerCandidates(exeDir), &viewer);
  if (!s.ok()) {
    os::PrintErr("%s\n", s.message().c_str());
    return kExitNoViewer;
  }
  std::vector<std::string> argv = {
      "python3", viewer + "/serve.py",      "--viewer", viewer, "--out", o.viewDir, "--glb", glb,
      "--port",  std::to_string(o.viewPort)};
  // The camera and exposure come from run.json when the directory has one.
  if (os::Exists((o.viewDir + "/run.json").c_str()))
    argv.push_back("--run");
  else
    os::PrintErr("vismask: view: %s has no run.json: the page frames the mesh from the front\n",
                 o.viewDir.c_str());
  std::string why;
  os::Exec(argv, &why);
  os::PrintErr("vismask: view: %s (python3 serves the page; tools/install-deps installs it)\n",
               why.c_str());
  return kExitNoViewer;
}

const char* ViewHelpText() {
  return R"(usage: vismask view OUT_DIR [--glb NAME.glb] [--port P]

Serves the viewer page and OUT_DIR's files on 127.0.0.1 (Python's
http.server) and prints the URL to open: the solved mesh that
'vismask render SCENE.obj --out OUT_DIR --export OUT_DIR/NAME.glb' wrote,
lit as image.png shows it, to orbit and fly through, starting from the
run's camera (OUT_DIR/run.json). Ctrl-C stops it.

  --glb NAME.glb   the mesh, a file in OUT_DIR (default: the one .glb there)
  --port P         the port, 1-65535 (default: any free port)

exit status: 2 OUT_DIR is not a directory, holds no .glb or several, or the
file is not binary glTF 2.0; 1 the viewer page or python3 is missing.
)";
}

}  // namespace vismask
