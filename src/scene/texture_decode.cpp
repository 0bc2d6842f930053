#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "scene_parse.h"
#include "vismask/core/os.h"
#include "vismask/scene/jpeg.h"
#include "vismask/scene/texture.h"

// stb_image, compiled here only, for init: it allocates with malloc, which
// is allowed before the solve starts. Memory in, so the file is read (and a
// missing one reported) by us.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO
#define STBI_ONLY_PNG
#define STBI_ONLY_BMP
#define STBI_ONLY_TGA
#define STBI_ONLY_HDR  // --sky FILE.hdr (ReadSkyMap); DecodeTexture refuses it
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
// stb_image 2.27 copies 0 bytes into a null buffer (a PNG whose first IDAT
// chunk is empty): harmless, but undefined for memcpy (UBSan stops the
// fuzzer there). Its copies go through StbMemcpy, which copies nothing then.
// (<cstring> first: stb_image's own #include <string.h> is then a no-op.)
#include <cstring>
namespace {
inline void* StbMemcpy(void* to, const void* from, size_t n) {
  return n == 0 ? to : std::memcpy(to, from, n);
}
}  // namespace
#define memcpy StbMemcpy
// Its buffers zeroed when made: for a corrupt JPEG that lacks some scans it
// outputs blocks it never wrote, which were then whatever the heap held
// (two decodes of one file differed).
#define STBI_MALLOC(size) std::calloc(1, size)
#define STBI_REALLOC(p, size) std::realloc(p, size)
#define STBI_FREE(p) std::free(p)
#include <stb_image.h>
#undef memcpy
#pragma GCC diagnostic pop

// Texture files into texels: the file read, its bytes checked for the
// stb_image 2.27 faults a corrupt file could reach, decoded, and the
// texture's mean and pyramid made (ReadTexture, DecodeTexture).
namespace vismask {

namespace {

// "file:line" into a Status at that place.
Status ErrorAt(const std::string& where, const std::string& message) {
  size_t colon = where.rfind(':');
  if (colon == std::string::npos) return Status::Error(where + ": " + message);
  return Status::At(where.substr(0, colon), std::atoi(where.c_str() + colon + 1), message);
}

}  // namespace

namespace {

// A decoder's message with every byte that is not printable ASCII escaped
// (\xNN): stb_image names an unknown PNG chunk by its four bytes, which
// come from the file (a terminal escape, say).
std::string EscapedReason(const char* reason) {
  std::string out;
  for (const char* c = reason; *c != '\0' && out.size() < 200; ++c)
    objload::AppendEscaped(&out, static_cast<unsigned char>(*c));
  return out;
}

// stb_image 2.27 (Debian 12's) writes past its Huffman arrays when a JPEG
// DHT table declares more than 256 codes (their sum over the 16 lengths):
// such a file is refused here, before the decoder sees it. Walks the
// segments as stb_image does (bytes between segments skipped up to the next
// 0xff, fill bytes, the entropy-coded data after each SOS up to the next
// marker, a byte past the end read as 0); "" if every DHT table it finds is
// well-formed or `b` is no JPEG.
std::string BadJpegHuffman(const unsigned char* b, size_t n) {
  // SOI, after any fill bytes (0xff 0xff 0xd8 is one to stb_image).
  size_t at = 0;
  while (at < n && b[at] == 0xff) ++at;
  if (at == 0 || at >= n || b[at] != 0xd8) return "";
  ++at;
  auto byte = [&](size_t i) -> size_t { return i < n ? b[i] : 0; };
  for (;;) {
    while (at < n && b[at] != 0xff) ++at;
    while (at < n && b[at] == 0xff) ++at;
    if (at >= n) return "";
    const unsigned char m = b[at++];
    if (m == 0xd9) return "";                                          // EOI
    if (m == 0x00 || m == 0x01 || (m >= 0xd0 && m <= 0xd8)) continue;  // no length
    const size_t len = (byte(at) << 8) | byte(at + 1);
    if (m == 0xc4) {
      for (size_t t = at + 2; t < at + len && t < n;) {
        size_t codes = 0;
        for (size_t k = 1; k <= 16; ++k) codes += byte(t + k);
        if (codes > 256)
          return "a Huffman table (DHT) of " + std::to_string(codes) +
                 " codes, more than the 256 JPEG allows";
        t += 17 + codes;
      }
    }
    if (len < 2 || at + len > n) return "";  // stb_image stops there
    at += len;
    if (m == 0xda) {
      // Entropy-coded data: up to the next marker that is not a stuffed
      // 0xff00 or a restart marker.
      while (at + 1 < n &&
             !(b[at] == 0xff && b[at + 1] != 0x00 && !(b[at + 1] >= 0xd0 && b[at + 1] <= 0xd7)))
        ++at;
    }
  }
}

// A PNG chunk that claims more bytes than the file has left: stb_image
// 2.27 grows its buffer for the chunk (doubling, up to 2 GiB) before it
// finds the bytes missing, so a file of a hundred bytes could take
// gigabytes. "" if every chunk fits or `b` is no PNG.
std::string BadPngChunks(const unsigned char* b, size_t n) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n < 8 || std::memcmp(b, kSignature, 8) != 0) return "";
  for (size_t at = 8; at + 8 <= n;) {
    const size_t len =
        (size_t{b[at]} << 24) | (size_t{b[at + 1]} << 16) | (size_t{b[at + 2]} << 8) | b[at + 3];
    const size_t left = n - at - 8;  // after the chunk's length and type
    if (len + 4 > left) {
      char type[4 * 4 + 1] = "";
      for (int k = 0; k < 4; ++k) {
        const unsigned char c = b[at + 4 + k];
        char one[5];
        std::snprintf(one, sizeof one, c >= 0x20 && c < 0x7f && c != '\\' ? "%c" : "\\x%02x", c);
        std::strcat(type, one);
      }
      return std::string("a chunk (") + type + ") of " + std::to_string(len) +
             " bytes and its CRC, where the file has " + std::to_string(left) + " left";
    }
    if (std::memcmp(b + at + 4, "IEND", 4) == 0) return "";
    at += 12 + len;
  }
  return "";
}

// A palette BMP (1, 4 or 8 bits a pixel) whose palette has fewer than
// 2^bits colours: stb_image 2.27 reads the colours past it from a stack
// array it never filled, so the texels would be whatever the stack held
// (and two decodes differ). Read as stb_image reads the header (a byte past
// the end as 0); "" if the palette is whole or `b` is no such BMP.
std::string BadBmpPalette(const unsigned char* b, size_t n) {
  if (n < 2 || b[0] != 'B' || b[1] != 'M') return "";
  auto le = [&](size_t at, int bytes) {
    long long v = 0;
    for (int k = bytes - 1; k >= 0; --k) v = (v << 8) | (at + k < n ? b[at + k] : 0);
    return v;
  };
  const long long offset = le(10, 4), hsz = le(14, 4);
  const long long bpp = hsz == 12 ? le(24, 2) : le(28, 2);
  if (bpp != 1 && bpp != 4 && bpp != 8) return "";
  // As stb_image counts them: / 3 (toward 0) for the old header, >> 2
  // (toward minus infinity) for the others.
  const long long d = offset - 14 - hsz;
  const long long colours = hsz == 12 ? (offset - 14 - 24) / 3 : (d >= 0 ? d / 4 : -((3 - d) / 4));
  // stb_image refuses 0 or more than 256, but takes a negative count (an
  // offset inside the header) as an empty palette.
  if (colours == 0 || colours > 256 || colours >= (1LL << bpp)) return "";
  return (colours < 0 ? std::string("no palette (its pixels start inside the header)")
                      : "a palette of " + std::to_string(colours) + " colours") +
         " for " + std::to_string(bpp) + "-bit pixels (" + std::to_string(1LL << bpp) +
         " colours needed)";
}

// A Radiance HDR file whose run-length data ends inside a scanline:
// stb_image 2.27 reads bytes past the end as 0, a run count of 0 that
// never advances, and loops for ever. Read as stb_image reads it (the
// header's lines, then each scanline's four channels); "" if the data
// lasts, or stb_image takes the scanlines as flat (finite) or refuses them.
std::string CutHdrRuns(const unsigned char* b, size_t n, int w, int h) {
  if (w < 8 || w >= 32768) return "";  // flat data: stb_image reads every texel once
  size_t at = 0;
  auto get8 = [&]() -> int { return at < n ? b[at++] : 0; };
  // stbi__hdr_gettoken: up to a '\n' or the end; whether the line is empty
  // as a C string (none, or a NUL first).
  auto line = [&]() {
    int len = 0;
    bool empty = true;
    for (int c = get8(); at < n && c != '\n'; c = get8()) {
      if (len == 0) empty = c == 0;
      if (++len == 1023) {
        while (at < n && get8() != '\n') {
        }
        break;
      }
    }
    return empty;
  };
  line();            // #?RADIANCE
  while (!line()) {  // the header, to an empty line
  }
  line();  // -Y h +X w
  for (int j = 0; j < h; ++j) {
    const int c1 = get8(), c2 = get8(), hi = get8();
    if (c1 != 2 || c2 != 2 || (hi & 0x80)) return "";  // flat from here
    if (((hi << 8) | get8()) != w) return "";          // refused by stb_image
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < w;) {
        if (at >= n)
          return "its run-length data ends inside scanline " + std::to_string(j) + " of " +
                 std::to_string(h);
        int count = get8();
        if (count > 128) {
          get8();
          count -= 128;
        } else {
          at = std::min(n, at + static_cast<size_t>(count));
        }
        if (count > w - i) return "";  // refused by stb_image
        i += count;
      }
  }
  return "";
}

}  // namespace

namespace {

// An image file's bytes, read whole: ReadTexture's and ReadSkyMap's checks.
// `fail` makes the error from a reason.
template <class Fail>
Status ReadImageBytes(const std::string& path, uint64_t budget, const Fail& fail,
                      std::string* out) {
  // Only a regular file (not /dev/zero, not a FIFO), of a size stb_image
  // takes, read whole only once its size is known.
  os::InFile in;
  std::string why;
  if (!in.Open(path.c_str(), &why)) {
    if (in.kind()) return fail(std::string("not a regular file (") + in.kind() + ")");
    return fail("cannot open");
  }
  const int64_t size = in.Size();
  if (size < 0) return fail("cannot read its size");
  if (size > std::numeric_limits<int>::max())
    return fail(std::to_string(size) + " bytes, more than the " +
                std::to_string(std::numeric_limits<int>::max()) + " a texture file may have");
  auto overBudget = [&](uint64_t need, const std::string& what) {
    return fail(what + " needs " + std::to_string(need) + " bytes, more than the " +
                std::to_string(budget) + " --mem-budget leaves it at init");
  };
  if (budget > 0 && static_cast<uint64_t>(size) > budget)
    return overBudget(static_cast<uint64_t>(size), "reading it");
  std::string bytes(static_cast<size_t>(size), '\0');
  const int64_t got = size > 0 ? in.Read(&bytes[0], bytes.size(), &why) : 0;
  if (got < 0) return fail("read error (" + why + ")");
  if (got != size) return fail("the file changed while it was read");
  *out = std::move(bytes);
  return Status::Ok();
}

}  // namespace

Status ReadTexture(const std::string& path, const std::string& where, TextureImage* image,
                   uint64_t budget) {
  auto fail = [&](const std::string& why) {
    return ErrorAt(where, "cannot read texture '" + path + "': " + why);
  };
  std::string bytes;
  Status s = ReadImageBytes(path, budget, fail, &bytes);
  if (!s.ok()) return s;
  return DecodeTexture(bytes, path, where, image, budget);
}

Status ReadSkyMap(const std::string& path, SkyMap* map, uint64_t budget) {
  auto fail = [&](const std::string& why) {
    return Status::Error("vismask: --sky: cannot read sky map '" + path + "': " + why);
  };
  std::string bytes;
  Status s = ReadImageBytes(path, budget, fail, &bytes);
  if (!s.ok()) return s;
  return DecodeSkyMap(bytes, path, map, budget);
}

Status DecodeSkyMap(const std::string& bytes, const std::string& path, SkyMap* map,
                    uint64_t budget) {
  auto fail = [&](const std::string& why) {
    return Status::Error("vismask: --sky: cannot read sky map '" + path + "': " + why);
  };
  if (bytes.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
    return fail(std::to_string(bytes.size()) + " bytes, more than the " +
                std::to_string(std::numeric_limits<int>::max()) + " a sky map file may have");
  const stbi_uc* encoded = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int n = static_cast<int>(bytes.size());
  if (!stbi_is_hdr_from_memory(encoded, n)) return fail("not a Radiance HDR image");
  int w = 0, h = 0, comp = 0;
  if (!stbi_info_from_memory(encoded, n, &w, &h, &comp))
    return fail(stbi_failure_reason() ? EscapedReason(stbi_failure_reason()) : "decoder failed");
  if (w <= 0 || h <= 0)
    return fail("the image is " + std::to_string(w) + "x" + std::to_string(h) +
                " texels: it has none");
  const uint64_t texels = static_cast<uint64_t>(w) * static_cast<uint64_t>(h);
  if (texels > kMaxSkyTexels)
    return fail(std::to_string(w) + "x" + std::to_string(h) + " texels, more than the " +
                std::to_string(kMaxSkyTexels) + " a sky map may have");
  const uint64_t need = bytes.size() + kSkyDecodeBytesPerTexel * texels;
  if (budget > 0 && need > budget)
    return fail("decoding its " + std::to_string(w) + "x" + std::to_string(h) + " texels needs " +
                std::to_string(need) + " bytes, more than the " + std::to_string(budget) +
                " --mem-budget leaves it at init");
  const std::string cut = CutHdrRuns(encoded, bytes.size(), w, h);
  if (!cut.empty()) return fail("corrupt HDR: " + cut);
  float* data = stbi_loadf_from_memory(encoded, n, &w, &h, &comp, 3);
  if (!data)
    return fail(stbi_failure_reason() ? EscapedReason(stbi_failure_reason()) : "decoder failed");
  if (static_cast<uint64_t>(w) * static_cast<uint64_t>(h) != texels) {
    stbi_image_free(data);
    return fail("the image's size changed while it was decoded");
  }
  SkyMap m;
  m.path = path;
  m.width = static_cast<uint32_t>(w);
  m.height = static_cast<uint32_t>(h);
  m.staged.assign(data, data + texels * 3);
  stbi_image_free(data);
  for (float v : m.staged)
    if (!(v >= 0.0f && v <= 1e20f))  // NaN, infinite, negative or beyond outside.cpp's bound
      return fail("a texel's radiance is negative or not finite");
  m.Integrate();
  *map = std::move(m);
  map->texels = Span<const float>(map->staged.data(), map->staged.size());
  return Status::Ok();
}

Status DecodeTexture(const std::string& bytes, const std::string& path, const std::string& where,
                     TextureImage* image, uint64_t budget) {
  auto fail = [&](const std::string& why) {
    return ErrorAt(where, "cannot read texture '" + path + "': " + why);
  };
  auto overBudget = [&](uint64_t need, const std::string& what) {
    return fail(what + " needs " + std::to_string(need) + " bytes, more than the " +
                std::to_string(budget) + " --mem-budget leaves it at init");
  };
  if (bytes.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
    return fail(std::to_string(bytes.size()) + " bytes, more than the " +
                std::to_string(std::numeric_limits<int>::max()) + " a texture file may have");
  const uint64_t size = bytes.size();
  int w = 0, h = 0, comp = 0;
  auto decodeError = [&]() {
    std::string reason =
        stbi_failure_reason() ? EscapedReason(stbi_failure_reason()) : "decoder failed";
    if (reason == "unknown image type") reason = "not a PNG, JPEG, BMP or TGA image";
    return fail(reason);
  };
  const stbi_uc* encoded = reinterpret_cast<const stbi_uc*>(bytes.data());
  std::string corrupt = BadJpegHuffman(encoded, bytes.size());
  if (!corrupt.empty()) return fail("corrupt JPEG: " + corrupt);
  corrupt = BadPngChunks(encoded, bytes.size());
  if (!corrupt.empty()) return fail("corrupt PNG: " + corrupt);
  corrupt = BadBmpPalette(encoded, bytes.size());
  if (!corrupt.empty()) return fail("unsupported BMP: " + corrupt);
  // A Radiance HDR file is a sky (--sky), not a texture.
  if (stbi_is_hdr_from_memory(encoded, static_cast<int>(bytes.size())))
    return fail("not a PNG, JPEG, BMP or TGA image");
  // JPEG through libjpeg-turbo (jpeg.h says why), the rest through stb_image.
  const bool jpeg = IsJpeg(encoded, bytes.size());
  // The size first, from the header alone: the decoded bytes are judged
  // against the budget before any is made.
  if (jpeg) {
    const std::string why = JpegSize(encoded, bytes.size(), &w, &h);
    if (!why.empty()) return fail("corrupt JPEG: " + why);
  } else if (!stbi_info_from_memory(encoded, static_cast<int>(bytes.size()), &w, &h, &comp)) {
    return decodeError();
  }
  // stb_image 2.27 takes a BMP of width 0: no texels, a mean of NaN.
  auto noTexels = [&]() {
    return fail("the image is " + std::to_string(w) + "x" + std::to_string(h) +
                " texels: it has none");
  };
  if (w <= 0 || h <= 0) return noTexels();
  const uint64_t need =
      size + kTextureDecodeBytesPerTexel * static_cast<uint64_t>(w) * static_cast<uint64_t>(h);
  if (budget > 0 && need > budget)
    return overBudget(need,
                      "decoding its " + std::to_string(w) + "x" + std::to_string(h) + " texels");
  TextureImage img;
  if (jpeg) {
    const std::string why = DecodeJpeg(encoded, bytes.size(), &w, &h, &img.rgb);
    if (!why.empty()) return fail("corrupt JPEG: " + why);
  } else {
    stbi_uc* data =
        stbi_load_from_memory(encoded, static_cast<int>(bytes.size()), &w, &h, &comp, 3);
    if (!data) return decodeError();
    if (w <= 0 || h <= 0) {
      stbi_image_free(data);
      return noTexels();
    }
    img.rgb.assign(data, data + size_t(w) * size_t(h) * 3);
    stbi_image_free(data);
  }
  img.path = path;
  img.width = static_cast<uint32_t>(w);
  img.height = static_cast<uint32_t>(h);
  glm::dvec3 sum(0.0);
  for (size_t i = 0; i < img.rgb.size(); i += 3)
    for (int c = 0; c < 3; ++c) {
      sum[c] += SrgbToLinear(img.rgb[i + c]);
      img.maxCode = std::max(img.maxCode, img.rgb[i + c]);
    }
  img.mean = sum / (static_cast<double>(w) * static_cast<double>(h));
  img.pyramid = BuildPyramid(img.View());
  *image = std::move(img);
  return Status::Ok();
}

}  // namespace vismask
