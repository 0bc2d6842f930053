// `vismask view OUT_DIR`: the viewer page (viewer/; docs/DESIGN.md, The
// viewer) and one run's outputs served on localhost by Python's http.server
// (the page's serve.py, which prints the URL). Init-time code: it allocates,
// and on success it does not return (the process becomes python3).
#pragma once
#include <string>
#include <vector>

#include "vismask/app/options.h"
#include "vismask/core/status.h"

namespace vismask {

// Where the viewer's directory may be for a binary in `exeDir`, in the order
// tried: installed (exeDir/../share/vismask/viewer, for PREFIX/bin), then
// the source tree beside the build directory (exeDir/../viewer for build/,
// exeDir/../../viewer for build/san, build/debug and the like).
std::vector<std::string> ViewerCandidates(const std::string& exeDir);

// The first of `candidates` holding index.html and serve.py. An error names
// the places tried, or, when the first such directory lacks the three.js
// files (vendor/three.module.js), says to make them (make viewer).
Status FindViewerDir(const std::vector<std::string>& candidates, std::string* dir);

// The mesh to show: `glb` (a file name in `outDir`) when not empty, else the
// one *.glb in `outDir`. An error when `outDir` is not a readable directory,
// when it holds no .glb or several (naming them; --glb picks one), or when
// the file is not binary glTF 2.0 (its 12-byte header: magic, version,
// length equal to the file's size).
Status ChooseMesh(const std::string& outDir, const std::string& glb, std::string* name);

// The command: checks OUT_DIR and the mesh (exit 2 with a message), finds
// the viewer (exit 1 if missing) and execs python3 serve.py; returns only
// on failure, with the exit status.
int View(const Options& options);

// `vismask view --help`.
const char* ViewHelpText();

}  // namespace vismask
