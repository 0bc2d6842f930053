// libFuzzer target for the texture reader (`make fuzz`): stb_image through
// vismask's checks (DecodeTexture: the dimensions read first and judged
// against a budget, then the decoding), as ReadTexture runs it on a file's
// bytes. It must return a Status for anything: no crash, no sanitizer
// report, no hang, no decoding beyond the budget (a small file that claims
// 20000 x 20000 texels is refused by its header); what it accepts is a whole
// image, the same each time; and no message quotes a byte of the input that
// is not printable ASCII (a PNG chunk named ESC [ 2 J once cleared the
// terminal).
// tests/fuzz/texture-corpus/ holds the seeds: small PNG (8-bit, 16-bit,
// grey with alpha), JPEG, BMP and TGA images, and jpeg-dc-overflow, whose
// DC terms overflow stb_image 2.27's int (UBSan stops there unless
// texture_decode.cpp is compiled with -fwrapv, as the Makefile does).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "vismask/scene/texture.h"

namespace {
// What the fuzzer's inputs may decode into (some 58,000 texels): the
// budget check is exercised, and no input takes seconds to decode.
constexpr uint64_t kBudget = uint64_t{1} << 20;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  vismask::TextureImage image;
  vismask::Status s = vismask::DecodeTexture(bytes, "fuzz.png", "fuzz.mtl:1", &image, kBudget);
  const std::string message = s.ToString();
  for (char c : message) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u < 0x20 || u >= 0x7f) __builtin_trap();  // a raw byte reached the message
  }
  if (s.ok()) {
    const uint64_t texels = uint64_t{image.width} * image.height;
    if (image.width == 0 || image.height == 0 || image.rgb.size() != texels * 3 ||
        size + vismask::kTextureDecodeBytesPerTexel * texels > kBudget)
      __builtin_trap();
    for (int c = 0; c < 3; ++c)
      if (!(image.mean[c] >= 0.0 && image.mean[c] <= 1.0)) __builtin_trap();
    // The same bytes decode to the same texels (stb_image once output
    // blocks of a corrupt JPEG it never wrote: whatever the heap held).
    vismask::TextureImage again;
    if (!vismask::DecodeTexture(bytes, "fuzz.png", "fuzz.mtl:1", &again, kBudget).ok() ||
        again.rgb != image.rgb)
      __builtin_trap();
  }
  return 0;
}
