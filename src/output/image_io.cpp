#include "vismask/output/image_io.h"

#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <istream>
#include <limits>
#include <streambuf>
#include <system_error>
#include <utility>

#include "vismask/core/check.h"
#include "vismask/core/os.h"

namespace vismask {

namespace {

// A bump heap over a fixed region for the PNG encoder: malloc bumps,
// realloc and free of the most recent block work in place, other frees are
// no-ops. Out of room returns null (the encoder then fails cleanly).
class BumpHeap {
 public:
  explicit BumpHeap(Span<uint8_t> region) : region_(region) {}
  void* Malloc(size_t n) {
    size_t start = Align(used_) + kHeader;
    if (start + n > region_.size()) return nullptr;
    std::memcpy(region_.data() + start - kHeader, &n, sizeof n);
    last_ = start;
    used_ = start + n;
    return region_.data() + start;
  }
  void Free(void* p) {
    if (p && Offset(p) == last_) used_ = last_ - kHeader;
  }
  void* Realloc(void* p, size_t n) {
    if (!p) return Malloc(n);
    size_t off = Offset(p);
    size_t old;
    std::memcpy(&old, region_.data() + off - kHeader, sizeof old);
    if (off == last_ && off + n <= region_.size()) {
      std::memcpy(region_.data() + off - kHeader, &n, sizeof n);
      used_ = off + n;
      return p;
    }
    void* q = Malloc(n);
    if (q) std::memcpy(q, p, old < n ? old : n);
    return q;
  }
  static constexpr size_t kHeader = 16;

 private:
  static size_t Align(size_t x) { return (x + 15) & ~size_t(15); }
  size_t Offset(void* p) const {
    return static_cast<size_t>(static_cast<uint8_t*>(p) - region_.data());
  }
  Span<uint8_t> region_;
  size_t used_ = 0;
  size_t last_ = 0;
};

BumpHeap* gHeap = nullptr;  // the heap of the WritePng call in progress

// zlib's memory for deflateInit2(windowBits 15, memLevel 8), from zconf.h:
// (1 << (windowBits + 2)) + (1 << (memLevel + 9)), plus its state structure,
// which is a few KiB; 32 KiB covers it and the allocation headers.
constexpr int kWindowBits = 15;
constexpr int kMemLevel = 8;
constexpr size_t kZlibBytes =
    (size_t(1) << (kWindowBits + 2)) + (size_t(1) << (kMemLevel + 9)) + 32768;

voidpf ZAlloc(voidpf, uInt items, uInt size) {
  return gHeap->Malloc(size_t(items) * size);
}
void ZFree(voidpf, voidpf p) {
  gHeap->Free(p);
}

unsigned char* Compress(unsigned char* data, int len, int* outLen, int quality) {
  z_stream zs;
  std::memset(&zs, 0, sizeof zs);
  zs.zalloc = ZAlloc;
  zs.zfree = ZFree;
  int level = quality < 1 ? 1 : (quality > 9 ? 9 : quality);
  if (deflateInit2(&zs, level, Z_DEFLATED, kWindowBits, kMemLevel, Z_DEFAULT_STRATEGY) != Z_OK)
    return nullptr;
  uLong bound = deflateBound(&zs, static_cast<uLong>(len));
  CHECK(bound <= compressBound(static_cast<uLong>(len)));
  unsigned char* out = static_cast<unsigned char*>(gHeap->Malloc(bound));
  if (!out) {
    deflateEnd(&zs);
    return nullptr;
  }
  zs.next_in = data;
  zs.avail_in = static_cast<uInt>(len);
  zs.next_out = out;
  zs.avail_out = static_cast<uInt>(bound);
  int rc = deflate(&zs, Z_FINISH);
  *outLen = static_cast<int>(zs.total_out);
  deflateEnd(&zs);
  return rc == Z_STREAM_END ? out : nullptr;
}

void StbWrite(void* context, void* data, int size) {
  auto* file = static_cast<os::OutFile*>(context);
  file->Write(data, static_cast<size_t>(size));
}

}  // namespace

}  // namespace vismask

// stb_image_write, compiled here with every allocation routed to gHeap.
#define STBIW_MALLOC(sz) ::vismask::gHeap->Malloc(sz)
#define STBIW_REALLOC(p, newsz) ::vismask::gHeap->Realloc(p, newsz)
#define STBIW_FREE(p) ::vismask::gHeap->Free(p)
#define STBIW_ZLIB_COMPRESS ::vismask::Compress
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace vismask {

size_t PngScratchBytes(int width, int height) {
  size_t raw = (3 * size_t(width) + 1) * size_t(height);  // filtered scanlines
  size_t z = compressBound(static_cast<uLong>(raw));
  // filt + line buffer + zlib + deflate output + PNG file, each with a header.
  return raw + 3 * size_t(width) + kZlibBytes + z + (z + 64) + 16 * BumpHeap::kHeader + 64;
}

bool WritePng(os::OutFile* file, int width, int height, Span<const uint8_t> rgb,
              Span<uint8_t> scratch, char* why) {
  CHECK(rgb.size() == size_t(width) * size_t(height) * 3);
  BumpHeap heap(scratch);
  gHeap = &heap;
  int ok = stbi_write_png_to_func(StbWrite, file, width, height, 3, rgb.data(), width * 3);
  gHeap = nullptr;
  if (!ok)
    std::snprintf(why, os::kWhyBytes, "PNG encoder failed (scratch %zu bytes)", scratch.size());
  return ok != 0;
}

bool WritePfm(os::OutFile* file, int width, int height, Span<const glm::vec3> color) {
  static_assert(sizeof(glm::vec3) == 12, "PFM rows are written straight from memory");
  CHECK(color.size() == size_t(width) * size_t(height));
  char header[64];
  int n = std::snprintf(header, sizeof header, "PF\n%d %d\n-1.0\n", width, height);
  bool ok = file->Write(header, static_cast<size_t>(n));
  for (int y = height - 1; y >= 0 && ok; --y)
    ok = file->Write(color.data() + size_t(y) * size_t(width), size_t(width) * sizeof(glm::vec3));
  return ok;
}

ImageError CompareImages(Span<const float> a, Span<const float> b, Span<const uint8_t> exclude) {
  CHECK(a.size() == b.size());
  CHECK(exclude.empty() || a.size() == 3 * exclude.size());
  double num = 0.0, den = 0.0;
  ImageError e;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!exclude.empty() && exclude[i / 3] != 0) {
      if (i % 3 == 0) ++e.excludedPixels;
      continue;
    }
    double d = static_cast<double>(a[i]) - b[i];
    num += d * d;
    den += static_cast<double>(b[i]) * b[i];
    e.maxAbs = std::fmax(e.maxAbs, std::fabs(d));
  }
  e.relativeRmse = den > 0.0 ? std::sqrt(num / den) : (num > 0.0 ? INFINITY : 0.0);
  return e;
}

namespace {

// Reads the whole file at `path` into *bytes; an error message, empty on
// success. Only regular files (InFile::Open): a device (/dev/zero) or a FIFO
// would be read until memory runs out, or never answer.
std::string ReadBytes(const std::string& path, std::string* bytes) {
  os::InFile in;
  std::string why;
  if (!in.Open(path.c_str(), &why)) {
    if (in.kind()) return std::string("cannot read: not a regular file (") + in.kind() + ")";
    return "cannot open";
  }
  const int64_t size = in.Size();
  if (size < 0) return "cannot read";
  if (static_cast<uint64_t>(size) > std::numeric_limits<size_t>::max() / 2)
    return "cannot read: " + std::to_string(size) + " bytes";
  std::string all(static_cast<size_t>(size), '\0');
  const int64_t got = size > 0 ? in.Read(&all[0], static_cast<size_t>(size), &why) : 0;
  if (got < 0) return "cannot read (" + why + ")";
  if (got != size) return "cannot read (the file changed while read)";
  *bytes = std::move(all);
  return "";
}

// A read-only stream buffer over bytes in memory (no copy), so that a header
// is parsed with the same istream >> as a file would be.
class MemoryBuf : public std::streambuf {
 public:
  MemoryBuf(const char* data, size_t size) {
    char* p = const_cast<char*>(data);  // never written: no put area, no putback of a new char
    setg(p, p, p + size);
  }
  size_t Offset() const { return static_cast<size_t>(gptr() - eback()); }
};

// Checks a w x h image of `bytesPerPixel` against the `left` bytes after its
// header, before anything is allocated: a header may claim any size.
std::string CheckPixelBytes(size_t left, int w, int h, int bytesPerPixel, const char* kind) {
  // w * h * bytesPerPixel without overflow: w, h < 2^31, so compare by division.
  unsigned long long perRow = static_cast<unsigned long long>(w) * bytesPerPixel;
  if (left / perRow < static_cast<unsigned long long>(h))
    return std::string("truncated ") + kind + ": the header says " + std::to_string(w) + " x " +
           std::to_string(h) + " pixels (" +
           std::to_string(static_cast<unsigned long long>(w) * static_cast<unsigned long long>(h)) +
           " x " + std::to_string(bytesPerPixel) + " bytes), the file holds " +
           std::to_string(left) + " bytes after it";
  return "";
}

// The header of a PFM or PGM: "MAGIC W H LAST", then the single whitespace
// byte before the pixels.
template <typename Last>
struct ImageHeader {
  std::string magic;
  int w = 0, h = 0;
  Last last = 0;     // PFM: the scale; PGM: maxval
  size_t start = 0;  // the pixels' offset in `bytes`
};
// The header at the start of `bytes`, as a stream reads it. False unless
// all four fields are there, the magic is `magic` and W and H are positive
// (LAST is the caller's to check).
template <typename Last>
bool ReadHeader(const std::string& bytes, const char* magic, ImageHeader<Last>* hd) {
  MemoryBuf buf(bytes.data(), bytes.size());
  std::istream in(&buf);
  in >> hd->magic >> hd->w >> hd->h >> hd->last;
  if (!in || hd->magic != magic || hd->w <= 0 || hd->h <= 0) return false;
  in.get();
  hd->start = buf.Offset();
  return true;
}

// Reads the file at `path` whole and decodes it with `fromBytes`.
template <typename Image>
Status ReadImageFile(const std::string& path, Image* image,
                     Status (*fromBytes)(const std::string&, const std::string&, Image*)) {
  std::string bytes;
  std::string err = ReadBytes(path, &bytes);
  if (!err.empty()) return Status::At(path, 0, err);
  return fromBytes(path, bytes, image);
}

}  // namespace

Status ReadPfm(const std::string& path, PfmImage* image) {
  return ReadImageFile(path, image, ReadPfmFromBytes);
}

Status ReadPfmFromBytes(const std::string& name, const std::string& bytes, PfmImage* image) {
  ImageHeader<double> hd;
  if (!ReadHeader(bytes, "PF", &hd) || hd.last == 0.0 || !std::isfinite(hd.last))
    return Status::At(name, 0, "not a colour PFM (expected 'PF', width, height, scale)");
  const int w = hd.w, h = hd.h;
  const double scale = hd.last;
  // The scale's sign is the byte order; its magnitude would scale every
  // pixel, which vismask does not do: only 1 and -1 are read.
  if (scale != 1.0 && scale != -1.0)
    return Status::At(name, 0,
                      "PFM scale " + std::to_string(scale) +
                          ": only 1 (big-endian) and -1 (little-endian) are read (any other "
                          "would scale the pixels)");
  const size_t start = hd.start;
  std::string err = CheckPixelBytes(bytes.size() - start, w, h, 12, "PFM");
  if (!err.empty()) return Status::At(name, 0, err);
  const size_t extra = bytes.size() - start - size_t(w) * size_t(h) * 12;
  if (extra > 0)
    return Status::At(name, 0,
                      std::to_string(extra) + " bytes after the pixels (the header says " +
                          std::to_string(w) + " x " + std::to_string(h) + "): not one PFM image");
  const bool bigEndian = scale > 0.0;
  const size_t rowFloats = size_t(w) * 3;
  std::vector<float> pixels(rowFloats * size_t(h));
  for (size_t y = 0; y < size_t(h); ++y) {  // PFM rows run bottom to top
    float* row = &pixels[(size_t(h) - 1 - y) * rowFloats];
    std::memcpy(row, bytes.data() + start + y * rowFloats * 4, rowFloats * 4);
    for (size_t i = 0; i < rowFloats; ++i) {
      if (bigEndian) {
        uint32_t u;
        std::memcpy(&u, &row[i], 4);
        u = __builtin_bswap32(u);
        std::memcpy(&row[i], &u, 4);
      }
      // A NaN would compare as a perfect match and an Inf write -nan into JSON.
      if (!std::isfinite(row[i]))
        return Status::At(name, 0,
                          "pixel (" + std::to_string(i / 3) + ", " +
                              std::to_string(size_t(h) - 1 - y) +
                              ") (x, y from the top left) is not finite: " +
                              (std::isnan(row[i]) ? "NaN" : "Inf"));
    }
  }
  image->width = w;
  image->height = h;
  image->pixels = std::move(pixels);
  return Status::Ok();
}

Status ReadPgm(const std::string& path, PgmImage* image) {
  return ReadImageFile(path, image, ReadPgmFromBytes);
}

Status ReadPgmFromBytes(const std::string& name, const std::string& bytes, PgmImage* image) {
  ImageHeader<int> hd;
  if (!ReadHeader(bytes, "P5", &hd) || hd.last <= 0 || hd.last > 255)
    return Status::At(name, 0,
                      "not an 8-bit binary PGM (expected 'P5', width, height, maxval <= 255)");
  const int w = hd.w, h = hd.h;
  const size_t start = hd.start;
  std::string err = CheckPixelBytes(bytes.size() - start, w, h, 1, "PGM");
  if (!err.empty()) return Status::At(name, 0, err);
  const uint8_t* p = reinterpret_cast<const uint8_t*>(bytes.data()) + start;
  image->width = w;
  image->height = h;
  image->pixels.assign(p, p + size_t(w) * size_t(h));
  return Status::Ok();
}

namespace {
float Luminance(const glm::vec3& c) {
  return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
}  // namespace

float AutoExposure(Span<const glm::vec3> color, Span<const uint32_t> coverage, uint32_t emptyId) {
  double sumLog = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < color.size(); ++i) {
    if (coverage[i] == emptyId) continue;
    sumLog += std::log(1e-12 + static_cast<double>(Luminance(color[i])));
    ++count;
  }
  if (count == 0) return 1.0f;
  double logAverage = std::exp(sumLog / static_cast<double>(count));
  if (!(logAverage > 1e-11)) return 1.0f;
  return static_cast<float>(0.18 / logAverage);
}

void ToneMap(Span<const glm::vec3> color, float exposure, Span<uint8_t> rgb) {
  CHECK(rgb.size() == 3 * color.size());
  for (size_t i = 0; i < color.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      float v = color[i][c] * exposure;
      v = !(v > 0.0f) ? 0.0f : (v >= 1.0f ? 1.0f : v);  // NaN -> 0
      float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
      rgb[3 * i + c] = static_cast<uint8_t>(std::lround(255.0f * s));
    }
  }
}

}  // namespace vismask
