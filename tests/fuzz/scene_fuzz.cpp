// libFuzzer target for the scene loader (`make fuzz FUZZ_SECONDS=N`).
// An input is the OBJ text, then optionally a NUL byte and the text every
// MTL file it names reads as (no NUL: no MTL file can be opened). The
// loader must return a Status for anything: no crash, no sanitizer report,
// no hang. tests/fuzz/corpus/ holds the seeds: the scenes and edge cases.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vismask/scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string all(reinterpret_cast<const char*>(data), size);
  size_t nul = all.find('\0');
  std::string obj = all.substr(0, nul);
  bool haveMtl = nul != std::string::npos;
  std::string mtl = haveMtl ? all.substr(nul + 1) : std::string();
  vismask::Scene scene;
  std::vector<std::string> warnings;
  vismask::Status s = vismask::LoadSceneFromText(
      "fuzz.obj", obj,
      [&](const std::string&, std::string* text) -> std::string {
        if (!haveMtl) return "cannot open";
        *text = mtl;
        return "";
      },
      &scene, &warnings);
  (void)s.ToString();
  return 0;
}
