// libFuzzer target for the sky-map reader (`make fuzz`): stb_image's
// Radiance HDR decoder through vismask's checks (DecodeSkyMap: the
// dimensions read first and judged against a budget and kMaxSkyTexels,
// then the decoding, every texel finite and >= 0, then the faces'
// integrals), as ReadSkyMap runs it on --sky FILE.hdr's bytes. It must
// return a Status for anything: no crash, no sanitizer report, no hang, no
// decoding beyond the budget; what it accepts is a whole map whose texels
// and integrals are finite and >= 0, the same each time; and no message
// quotes a byte of the input that is not printable ASCII.
// tests/fuzz/sky-corpus/ holds the seeds: small flat and run-length
// encoded RGBE maps, one with the +Y/-X orientation line stb_image refuses,
// and one whose header claims more texels than its bytes hold.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "vismask/scene/texture.h"
#include "vismask/solve/outside.h"

namespace {
// What the fuzzer's inputs may decode into (some 43,000 texels): the budget
// check is exercised, and no input takes seconds to decode.
constexpr uint64_t kBudget = uint64_t{1} << 20;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  vismask::SkyMap map;
  vismask::Status s = vismask::DecodeSkyMap(bytes, "fuzz.hdr", &map, kBudget);
  const std::string message = s.ToString();
  for (char c : message) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7f) __builtin_trap();  // a raw byte reached the message
  }
  if (s.ok()) {
    const uint64_t texels = uint64_t{map.width} * map.height;
    if (map.width == 0 || map.height == 0 || map.staged.size() != texels * 3 ||
        map.texels.size() != map.staged.size() ||
        size + vismask::kSkyDecodeBytesPerTexel * texels > kBudget)
      __builtin_trap();
    for (float v : map.staged)
      if (!(v >= 0.0f && std::isfinite(v))) __builtin_trap();
    for (const auto& face : map.crossing)
      for (double c : face)
        if (!(c >= 0.0 && std::isfinite(c))) __builtin_trap();
    // Every direction's radiance is a texel's: finite and >= 0.
    const glm::vec3 up = map.Radiance(glm::vec3(0.0f, 1.0f, 0.0f));
    const glm::vec3 side = map.Radiance(glm::vec3(-1.0f, -0.3f, 0.2f));
    for (int c = 0; c < 3; ++c)
      if (!(up[c] >= 0.0f && std::isfinite(up[c]) && side[c] >= 0.0f && std::isfinite(side[c])))
        __builtin_trap();
    // The same bytes decode to the same texels.
    vismask::SkyMap again;
    if (!vismask::DecodeSkyMap(bytes, "fuzz.hdr", &again, kBudget).ok() ||
        again.staged != map.staged)
      __builtin_trap();
  }
  return 0;
}
