#include "vismask/scene/texture.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/geometric.hpp>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "vismask/core/os.h"

// stb_image, compiled here only, for init: it allocates with malloc, which
// is allowed before the solve starts. Memory in, so the file is read (and a
// missing one reported) by us.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
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

namespace vismask {

namespace {

// sRGB decoding (IEC 61966-2-1): the files hold encoded values, reflectance
// is linear. Computed in double once, rounded to float.
std::array<float, 256> MakeSrgbTable() {
  std::array<float, 256> t{};
  for (int i = 0; i < 256; ++i) {
    double c = i / 255.0;
    t[i] = static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
  }
  return t;
}
const std::array<float, 256> kSrgbTable = MakeSrgbTable();

// "file:line" into a Status at that place.
Status ErrorAt(const std::string& where, const std::string& message) {
  size_t colon = where.rfind(':');
  if (colon == std::string::npos) return Status::Error(where + ": " + message);
  return Status::At(where.substr(0, colon), std::atoi(where.c_str() + colon + 1), message);
}

// The points and weights PatchTextureMean integrates with, passed to `f`.
template <class F>
void ForSamples(const Patch& p, int n, F f) {
  const double inv = 1.0 / n;
  if (p.numCorners == 3) {
    // The centroids of the n x n similar sub-triangles: equal areas.
    for (int j = 0; j < n; ++j)
      for (int i = 0; i + j < n; ++i) {
        f(glm::vec2(static_cast<float>((i + 1.0 / 3.0) * inv),
                    static_cast<float>((j + 1.0 / 3.0) * inv)),
          1.0);
        if (i + j + 1 < n)
          f(glm::vec2(static_cast<float>((i + 2.0 / 3.0) * inv),
                      static_cast<float>((j + 2.0 / 3.0) * inv)),
            1.0);
      }
    return;
  }
  // Cell midpoints of an n x n grid in (s, t), weighted by the bilinear
  // map's area element there.
  const glm::dvec3 c0(p.corner[0]), c1(p.corner[1]), c2(p.corner[2]), c3(p.corner[3]),
      nrm(p.normal);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double s = (i + 0.5) * inv, t = (j + 0.5) * inv;
      glm::dvec3 ds = (1 - t) * (c1 - c0) + t * (c2 - c3), dt = (1 - s) * (c3 - c0) + s * (c2 - c1);
      double w = std::max(0.0, glm::dot(nrm, glm::cross(ds, dt)));
      f(glm::vec2(static_cast<float>(s), static_cast<float>(t)), w);
    }
}

}  // namespace

float SrgbToLinear(uint8_t code) {
  return kSrgbTable[code];
}

glm::vec3 Texture::Sample(glm::vec2 uv) const {
  float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
  if (!(u >= 0.0f && u <= 1.0f)) u = 0.0f;  // NaN or infinite
  if (!(v >= 0.0f && v <= 1.0f)) v = 0.0f;
  // Texel centres at (i + 1/2) / width; row 0 is the image's top, v = 1.
  float x = u * static_cast<float>(width) - 0.5f,
        y = (1.0f - v) * static_cast<float>(height) - 0.5f;
  float fx = std::floor(x), fy = std::floor(y);
  float ax = x - fx, ay = y - fy;
  int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);  // -1 .. size - 1
  const int w = static_cast<int>(width), h = static_cast<int>(height);
  uint32_t i0 = static_cast<uint32_t>(x0 < 0 ? w - 1 : x0),
           i1 = static_cast<uint32_t>(x0 + 1 >= w ? 0 : x0 + 1);
  uint32_t j0 = static_cast<uint32_t>(y0 < 0 ? h - 1 : y0),
           j1 = static_cast<uint32_t>(y0 + 1 >= h ? 0 : y0 + 1);
  const uint8_t* r0 = texels + size_t(j0) * width * 3;
  const uint8_t* r1 = texels + size_t(j1) * width * 3;
  glm::vec3 out;
  for (int c = 0; c < 3; ++c) {
    float t00 = kSrgbTable[r0[i0 * 3 + c]], t10 = kSrgbTable[r0[i1 * 3 + c]];
    float t01 = kSrgbTable[r1[i0 * 3 + c]], t11 = kSrgbTable[r1[i1 * 3 + c]];
    out[c] = (1.0f - ay) * ((1.0f - ax) * t00 + ax * t10) + ay * ((1.0f - ax) * t01 + ax * t11);
  }
  return out;
}

TexturePyramid BuildPyramid(const Texture& t) {
  TexturePyramid py;
  const uint32_t w = t.width, h = t.height;
  size_t total = 0;
  for (uint32_t lw = w, lh = h; lw > 1 || lh > 1;) {
    lw = (lw + 1) / 2;
    lh = (lh + 1) / 2;
    TexturePyramid::Level l;
    l.width = lw;
    l.height = lh;
    l.offset = total;
    total += size_t(lw) * lh * 3;
    py.levels.push_back(l);
  }
  py.texels.assign(total, 0.0f);
  // Level k's linear texel (x, y), level 0 being the 8-bit texture.
  auto at = [&](size_t k, uint32_t x, uint32_t y, int c) -> float {
    if (k == 0) return kSrgbTable[t.texels[(size_t(y) * w + x) * 3 + c]];
    const TexturePyramid::Level& l = py.levels[k - 1];
    return py.texels[l.offset + (size_t(y) * l.width + x) * 3 + c];
  };
  for (size_t k = 0; k < py.levels.size(); ++k) {
    const TexturePyramid::Level& l = py.levels[k];
    const uint32_t bw = k == 0 ? w : py.levels[k - 1].width;
    const uint32_t bh = k == 0 ? h : py.levels[k - 1].height;
    for (uint32_t y = 0; y < l.height; ++y)
      for (uint32_t x = 0; x < l.width; ++x) {
        const uint32_t x1 = std::min(2 * x + 1, bw - 1), y1 = std::min(2 * y + 1, bh - 1);
        const float n = static_cast<float>((x1 - 2 * x + 1) * (y1 - 2 * y + 1));
        for (int c = 0; c < 3; ++c) {
          float s = at(k, 2 * x, 2 * y, c);
          if (x1 != 2 * x) s += at(k, x1, 2 * y, c);
          if (y1 != 2 * y) s += at(k, 2 * x, y1, c);
          if (x1 != 2 * x && y1 != 2 * y) s += at(k, x1, y1, c);
          py.texels[l.offset + (size_t(y) * l.width + x) * 3 + c] = s / n;
        }
      }
  }
  return py;
}

glm::vec3 TexturePyramid::Sample(size_t k, glm::vec2 uv) const {
  const Level& l = levels[k - 1];
  float u = uv.x - std::floor(uv.x), v = uv.y - std::floor(uv.y);
  if (!(u >= 0.0f && u <= 1.0f)) u = 0.0f;
  if (!(v >= 0.0f && v <= 1.0f)) v = 0.0f;
  const float x = u * static_cast<float>(l.width) - 0.5f,
              y = (1.0f - v) * static_cast<float>(l.height) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  const int w = static_cast<int>(l.width), h = static_cast<int>(l.height);
  const size_t i0 = static_cast<size_t>(x0 < 0 ? w - 1 : x0),
               i1 = static_cast<size_t>(x0 + 1 >= w ? 0 : x0 + 1);
  const size_t j0 = static_cast<size_t>(y0 < 0 ? h - 1 : y0),
               j1 = static_cast<size_t>(y0 + 1 >= h ? 0 : y0 + 1);
  const float* r0 = texels.data() + l.offset + j0 * l.width * 3;
  const float* r1 = texels.data() + l.offset + j1 * l.width * 3;
  glm::vec3 out;
  for (int c = 0; c < 3; ++c)
    out[c] = (1.0f - ay) * ((1.0f - ax) * r0[i0 * 3 + c] + ax * r0[i1 * 3 + c]) +
             ay * ((1.0f - ax) * r1[i0 * 3 + c] + ax * r1[i1 * 3 + c]);
  return out;
}

Texture TextureImage::View() const {
  Texture t;
  t.width = width;
  t.height = height;
  t.texels = rgb.data();
  for (int c = 0; c < 3; ++c)
    t.invMean[c] = mean[c] > 0.0 ? static_cast<float>(1.0 / mean[c]) : 0.0f;
  return t;
}

namespace {

// A decoder's message with every byte that is not printable ASCII escaped
// (\xNN): stb_image names an unknown PNG chunk by its four bytes, which
// come from the file (a terminal escape, say).
std::string EscapedReason(const char* reason) {
  std::string out;
  for (const char* c = reason; *c != '\0' && out.size() < 200; ++c) {
    const unsigned char b = static_cast<unsigned char>(*c);
    if (b >= 0x20 && b < 0x7f && b != '\\') {
      out += static_cast<char>(b);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", b);
      out += hex;
    }
  }
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
  // The size first, from the header alone: the decoded bytes are judged
  // against the budget before any is made.
  if (!stbi_info_from_memory(encoded, static_cast<int>(bytes.size()), &w, &h, &comp))
    return decodeError();
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
  stbi_uc* data = stbi_load_from_memory(encoded, static_cast<int>(bytes.size()), &w, &h, &comp, 3);
  if (!data) return decodeError();
  if (w <= 0 || h <= 0) {
    stbi_image_free(data);
    return noTexels();
  }
  TextureImage img;
  img.path = path;
  img.width = static_cast<uint32_t>(w);
  img.height = static_cast<uint32_t>(h);
  img.rgb.assign(data, data + size_t(w) * size_t(h) * 3);
  stbi_image_free(data);
  glm::dvec3 sum(0.0);
  for (size_t i = 0; i < img.rgb.size(); i += 3)
    for (int c = 0; c < 3; ++c) {
      sum[c] += kSrgbTable[img.rgb[i + c]];
      img.maxCode = std::max(img.maxCode, img.rgb[i + c]);
    }
  img.mean = sum / (static_cast<double>(w) * static_cast<double>(h));
  img.pyramid = BuildPyramid(img.View());
  *image = std::move(img);
  return Status::Ok();
}

glm::vec2 UvMap::At(const glm::vec3& x) const {
  glm::dvec3 p(x);
  return glm::vec2(static_cast<float>(u.x * p.x + u.y * p.y + u.z * p.z + u.w),
                   static_cast<float>(v.x * p.x + v.y * p.y + v.z * p.z + v.w));
}

UvMap FitUvMap(const Polygon& polygon) {
  UvMap m;
  const size_t n = polygon.corners.size();
  if (polygon.uv.size() != n || n < 3) return m;
  // Least squares in a frame of the plane, about the corners' centroid:
  // u = mean_u + c1 a + c2 b (the same for v).
  glm::dvec3 centroid(0.0);
  glm::dvec2 meanUv(0.0);
  for (size_t k = 0; k < n; ++k) {
    centroid += glm::dvec3(polygon.corners[k]);
    meanUv += glm::dvec2(polygon.uv[k]);
  }
  centroid /= static_cast<double>(n);
  meanUv /= static_cast<double>(n);
  const glm::dvec3 normal(polygon.normal);
  glm::dvec3 e1 = glm::dvec3(polygon.corners[1]) - glm::dvec3(polygon.corners[0]);
  e1 = glm::normalize(e1 - glm::dot(e1, normal) * normal);
  const glm::dvec3 e2 = glm::cross(normal, e1);
  double saa = 0, sab = 0, sbb = 0;
  glm::dvec2 sau(0.0), sbu(0.0);
  for (size_t k = 0; k < n; ++k) {
    glm::dvec3 d = glm::dvec3(polygon.corners[k]) - centroid;
    double a = glm::dot(d, e1), b = glm::dot(d, e2);
    glm::dvec2 w = glm::dvec2(polygon.uv[k]) - meanUv;
    saa += a * a;
    sab += a * b;
    sbb += b * b;
    sau += a * w;
    sbu += b * w;
  }
  double det = saa * sbb - sab * sab;
  if (!(det > 0.0)) return m;  // cannot happen for a loaded (non-degenerate) face
  glm::dvec2 c1 = (sbb * sau - sab * sbu) / det, c2 = (saa * sbu - sab * sau) / det;
  glm::dvec3 gu = c1.x * e1 + c2.x * e2, gv = c1.y * e1 + c2.y * e2;
  m.u = glm::dvec4(gu, meanUv.x - glm::dot(gu, centroid));
  m.v = glm::dvec4(gv, meanUv.y - glm::dot(gv, centroid));
  return m;
}

glm::vec2 PatchUv(const PatchTexture& t, bool triangle, glm::vec2 st) {
  if (triangle) return t.uv[0] + st.x * (t.uv[1] - t.uv[0]) + st.y * (t.uv[2] - t.uv[0]);
  return (1.0f - st.x) * (1.0f - st.y) * t.uv[0] + st.x * (1.0f - st.y) * t.uv[1] +
         st.x * st.y * t.uv[2] + (1.0f - st.x) * st.y * t.uv[3];
}

glm::dvec3 PatchTextureMean(const Texture& texture, const Patch& p, const glm::vec2 uv[4],
                            const TexturePyramid* pyramid, uint64_t* samples) {
  // Two samples a texel along the patch's longest extent in texel units.
  double extent = 0.0;
  for (uint32_t a = 0; a < p.numCorners; ++a)
    for (uint32_t b = a + 1; b < p.numCorners; ++b) {
      glm::vec2 d = uv[a] - uv[b];
      extent = std::max({extent, std::fabs(double(d.x)) * texture.width,
                         std::fabs(double(d.y)) * texture.height});
    }
  int n = 2;
  if (extent > 1.0) n = static_cast<int>(std::min(64.0, std::ceil(2.0 * extent)));
  // With the pyramid: the level where two samples a texel take at most
  // kDirectSamples a side (a patch of fewer keeps the texels themselves).
  size_t level = 0;
  if (pyramid && 2.0 * extent > kDirectSamples) {
    double e = extent;
    while (2.0 * e > kDirectSamples && level < pyramid->levels.size()) {
      e *= 0.5;
      ++level;
    }
    n = std::max(2, static_cast<int>(std::ceil(2.0 * e)));
  }
  PatchTexture t;
  for (int k = 0; k < 4; ++k) t.uv[k] = uv[k];
  const bool triangle = p.numCorners == 3;
  glm::dvec3 sum(0.0);
  double weight = 0.0;
  uint64_t taken = 0;
  ForSamples(p, n, [&](glm::vec2 st, double w) {
    const glm::vec2 at = PatchUv(t, triangle, st);
    sum += w * glm::dvec3(level > 0 ? pyramid->Sample(level, at) : texture.Sample(at));
    weight += w;
    ++taken;
  });
  if (samples) *samples += taken;
  return weight > 0.0 ? sum / weight : glm::dvec3(texture.Sample(uv[0]));
}

std::string FindTexture(const std::string& path) {
  if (os::Exists(path.c_str())) return path;
  const size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  std::vector<std::string> names;
  std::string why;
  if (name.empty() || !os::ListDirectory(dir.c_str(), &names, &why)) return "";
  auto lower = [](std::string s) {
    for (char& c : s)
      if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return s;
  };
  const std::string want = lower(name);
  // Sorted bytewise: of several names that differ only in case, the first.
  for (const std::string& n : names)
    if (lower(n) == want) return slash == std::string::npos ? n : dir + n;
  return "";
}

void ResolveTextures(std::vector<Material>* materials, const std::vector<uint8_t>& used,
                     bool strict, std::vector<std::string>* warnings) {
  std::string otherCase, otherCaseWhere, missing, missingWhere;
  size_t numOtherCase = 0, numMissing = 0;
  for (size_t m = 0; m < materials->size(); ++m) {
    Material& mat = (*materials)[m];
    if (!used[m] || mat.mapKd.empty() || mat.mapKdBytes) continue;  // held in a glTF file
    const std::string found = FindTexture(mat.mapKd);
    // --strict: the name as written, and the reader says why it cannot.
    if (found == mat.mapKd || strict) continue;
    const size_t slash = found.rfind('/');
    if (!found.empty()) {
      if (numOtherCase++ == 0) otherCaseWhere = mat.mapKdWhere;
      otherCase += (otherCase.empty() ? "'" : ", '") + mat.mapKd + "' as '" +
                   (slash == std::string::npos ? found : found.substr(slash + 1)) + "'";
      mat.mapKd = found;
      continue;
    }
    if (numMissing++ == 0) missingWhere = mat.mapKdWhere;
    missing += (missing.empty() ? "'" : ", '") + mat.mapKd + "' (" + mat.name + ")";
    mat.mapKd.clear();
    mat.mapKdWhere.clear();
    if (mat.mapIsColour)
      mat.kd *= 0.5f;
    else if (mat.kd == glm::vec3(0.0f))
      mat.kd = glm::vec3(0.5f);
  }
  if (numOtherCase > 0)
    warnings->push_back(otherCaseWhere + ": warning: " + std::to_string(numOtherCase) +
                        (numOtherCase == 1 ? " texture" : " textures") +
                        " found in another letter case (first here): " + otherCase);
  if (numMissing > 0)
    warnings->push_back(missingWhere + ": warning: " + std::to_string(numMissing) +
                        (numMissing == 1 ? " texture" : " textures") +
                        " not found, their materials untextured with their Kd (0.5 grey where "
                        "Kd is 0, a glTF base colour factor times 0.5; first here): " +
                        missing);
}

Status LoadSceneTextures(Scene* scene, SceneTextures* out, bool strict) {
  const size_t nm = scene->materials.size();
  std::vector<uint8_t> used(nm, 0);
  std::vector<int> noUv(nm, 0);
  for (const Polygon& p : scene->polygons) {
    used[p.material] = 1;
    if (p.uv.empty() && noUv[p.material] == 0) noUv[p.material] = p.line;
  }
  return LoadMaterialTextures(scene->objPath, &scene->materials, used, noUv, out, strict);
}

Status LoadMaterialTextures(const std::string& objPath, std::vector<Material>* materialsIo,
                            const std::vector<uint8_t>& used, const std::vector<int>& noUvLineOf,
                            SceneTextures* out, uint64_t budget, bool strict) {
  SceneTextures r;
  ResolveTextures(materialsIo, used, strict, &r.warnings);
  const std::vector<Material>& materials = *materialsIo;
  const size_t nm = materials.size();
  r.ofMaterial.assign(nm, kNoTexture);
  r.kdOfMaterial.resize(nm);
  int noUvLine = 0;  // the first face of a textured material without uv
  for (size_t m = 0; m < nm; ++m) r.kdOfMaterial[m] = materials[m].kd;
  std::map<std::string, uint32_t> byPath;
  std::string zeroKd;  // materials whose map stands alone
  std::string zeroKdWhere;
  for (size_t m = 0; m < nm; ++m) {
    const Material& mat = materials[m];
    if (!used[m] || mat.mapKd.empty()) continue;
    auto it = byPath.find(mat.mapKd);
    if (it == byPath.end()) {
      TextureImage img;
      // A file, or an image the scene file holds (glTF): the same checks
      // and decoder, within the budget (DecodeTexture).
      Status s = mat.mapKdBytes
                     ? DecodeTexture(*mat.mapKdBytes, mat.mapKd, mat.mapKdWhere, &img, budget)
                     : ReadTexture(mat.mapKd, mat.mapKdWhere, &img, budget);
      if (!s.ok()) return s;
      if (budget > 0) budget -= std::min(budget - 1, static_cast<uint64_t>(img.rgb.size()));
      it = byPath.emplace(mat.mapKd, static_cast<uint32_t>(r.images.size())).first;
      r.images.push_back(std::move(img));
    }
    r.ofMaterial[m] = it->second;
    if (mat.kd == glm::vec3(0.0f)) {
      // The map alone is the reflectance: white texels reflect everything,
      // as Kd 1 does (issue 16 accepts it; a scene that then cannot lose
      // power is the loader's to refuse).
      r.kdOfMaterial[m] = glm::vec3(1.0f);
      zeroKd += (zeroKd.empty() ? "'" : ", '") + mat.name + "'";
      if (zeroKdWhere.empty()) zeroKdWhere = mat.mapKdWhere;
    }
  }
  for (size_t m = 0; m < nm; ++m)
    if (r.ofMaterial[m] != kNoTexture && noUvLineOf[m] != 0 &&
        (noUvLine == 0 || noUvLineOf[m] < noUvLine))
      noUvLine = noUvLineOf[m];
  if (!zeroKd.empty())
    r.warnings.push_back(zeroKdWhere +
                         ": warning: Kd 0 0 0 with map_Kd: the map alone is the "
                         "reflectance (Kd taken as 1) for material" +
                         (zeroKd.find(',') == std::string::npos ? " " : "s ") + zeroKd);
  if (noUvLine != 0)
    r.warnings.push_back(objPath + ":" + std::to_string(noUvLine) +
                         ": warning: faces with a map_Kd material but no texture coordinates "
                         "('vt'): they take the texture's mean reflectance, untextured");
  *out = std::move(r);
  return Status::Ok();
}

void TextureMesh(const Scene& scene, const SceneTextures& textures, Mesh* mesh) {
  mesh->textures.clear();
  if (!textures.any()) return;
  std::vector<PatchTexture> out(mesh->patches.size());
  bool any = false;
  uint32_t fitted = kNoPatch;
  UvMap map;
  for (size_t i = 0; i < mesh->patches.size(); ++i) {
    Patch& p = mesh->patches[i];
    const Polygon& poly = scene.polygons[p.surface];
    const uint32_t t = textures.ofMaterial[poly.material];
    if (t == kNoTexture) continue;
    const TextureImage& img = textures.images[t];
    const glm::vec3 kd = textures.kdOfMaterial[poly.material];
    if (poly.uv.empty()) {  // no coordinates: the texture's mean, untextured
      for (int c = 0; c < 3; ++c) p.kd[c] = static_cast<float>(kd[c] * img.mean[c]);
      continue;
    }
    if (fitted != p.surface) {
      map = FitUvMap(poly);
      fitted = p.surface;
    }
    PatchTexture& pt = out[i];
    pt.texture = t;
    for (int k = 0; k < 4; ++k) pt.uv[k] = map.At(p.corner[k]);
    glm::dvec3 mean = PatchTextureMean(img.View(), p, pt.uv, &img.pyramid);
    for (int c = 0; c < 3; ++c) {
      p.kd[c] = static_cast<float>(kd[c] * mean[c]);
      double kdMaterial = kd[c] * img.mean[c];
      pt.scale[c] = p.kd[c] > 0.0f ? static_cast<float>(kdMaterial / p.kd[c]) : 0.0f;
    }
    any = true;
  }
  if (any) mesh->textures = std::move(out);
}

void TextureSet::Layout(Arena& arena, const SceneTextures& scene,
                        const std::vector<uint8_t>& used) {
  const size_t mark = arena.used();
  textures = arena.Alloc<Texture>(scene.images.size());
  for (size_t i = 0; i < scene.images.size(); ++i) {
    const TextureImage& img = scene.images[i];
    Span<uint8_t> texels = used[i] ? arena.Alloc<uint8_t>(img.rgb.size()) : Span<uint8_t>();
    if (arena.measuring()) continue;
    Texture t = img.View();
    t.texels = nullptr;
    if (used[i]) {
      std::copy(img.rgb.begin(), img.rgb.end(), texels.begin());
      t.texels = texels.data();
    }
    textures[i] = t;
  }
  bytes = arena.used() - mark;
}

}  // namespace vismask
