// The parser's text helpers and line sources (scene_parse.h).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>

#include "scene_parse.h"

namespace vismask::objload {

std::string CoordinateError(double x) {
  return "coordinate " + Num(x) + " is beyond +-" + Num(kMaxCoordinate) +
         " (float ray tests would overflow); scale the scene down";
}

namespace {
bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

const char* KindOf(std::filesystem::file_type t) {
  switch (t) {
    case std::filesystem::file_type::directory:
      return "a directory";
    case std::filesystem::file_type::character:
      return "a character device";
    case std::filesystem::file_type::block:
      return "a block device";
    case std::filesystem::file_type::fifo:
      return "a FIFO";
    case std::filesystem::file_type::socket:
      return "a socket";
    default:
      return "not a file";
  }
}

}  // namespace

Tokens Tokenize(const std::string& line) {
  Tokens tokens;
  size_t i = 0;
  while (i < line.size() && line[i] != '#') {
    if (IsSpace(line[i])) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < line.size() && !IsSpace(line[j]) && line[j] != '#') ++j;
    tokens.push_back(line.substr(i, j - i));
    i = j;
  }
  return tokens;
}

std::string MapName(const std::string& line, const Tokens& t, bool* hadOptions) {
  // The options of a texture map statement and how many values each takes
  // at most (numbers; -blendu and the like take one word).
  struct Option {
    const char* name;
    size_t values;
    bool numbers;
  };
  static const Option kOptions[] = {
      {"-blendu", 1, false}, {"-blendv", 1, false}, {"-bm", 1, true},       {"-boost", 1, true},
      {"-cc", 1, false},     {"-clamp", 1, false},  {"-imfchan", 1, false}, {"-mm", 2, true},
      {"-o", 3, true},       {"-s", 3, true},       {"-t", 3, true},        {"-texres", 1, true},
      {"-type", 1, false}};
  *hadOptions = false;
  size_t k = 1;
  while (k < t.size() && t[k].size() > 1 && t[k][0] == '-') {
    const Option* o = nullptr;
    for (const Option& c : kOptions)
      if (t[k] == c.name) o = &c;
    if (!o) break;  // not an option: a name that starts with '-'
    *hadOptions = true;
    ++k;
    for (size_t v = 0; v < o->values && k + 1 < t.size(); ++v, ++k) {
      if (!o->numbers) continue;
      char* end = nullptr;
      std::strtod(t[k].c_str(), &end);
      if (end == t[k].c_str() || *end != '\0') break;
    }
  }
  if (k >= t.size()) return "";
  // The tokens are the line's own bytes in order: the name runs from the
  // k-th to the end of the last, with the spaces between kept as written.
  size_t at = 0, begin = 0, end = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    at = line.find(t[i], at);
    if (i == k) begin = at;
    at += t[i].size();
  }
  end = at;
  return line.substr(begin, end - begin);
}

std::string Str(size_t n) {
  return std::to_string(n);
}

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g", x);
  return buf;
}

// A piece of the input quoted in a message: at most 32 bytes, anything but
// printable ASCII escaped (\xNN), so that binary garbage, terminal escapes
// or a megabyte line never reach the terminal whole.
std::string Quote(const std::string& s) {
  constexpr size_t kMax = 32;
  std::string q = "'";
  for (size_t i = 0; i < s.size() && i < kMax; ++i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    if (c >= 0x20 && c < 0x7f && c != '\\') {
      q += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      q += hex;
    }
  }
  return q + (s.size() > kMax ? "'..." : "'");
}

// Whether an unknown MTL key may be named in a warning: a short identifier,
// as MTL keys are. Anything else (a line of a file that is not MTL at all)
// is counted, never echoed.
bool LooksLikeKey(const std::string& s) {
  if (s.empty() || s.size() > 24) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

std::string CheckReadable(const std::string& path) {
  // Only regular files, of a size the loader can hold: a device (/dev/zero)
  // or a FIFO would be read until memory runs out.
  std::error_code ec;
  std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (ec) return "cannot open (" + ec.message() + ")";
  if (!std::filesystem::is_regular_file(st))
    return std::string("cannot read: not a regular file (") + KindOf(st.type()) + ")";
  uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return "cannot read (" + ec.message() + ")";
  if (size > kMaxFileBytes)
    return "cannot read: it has " + std::to_string(size) + " bytes, more than the " +
           std::to_string(kMaxFileBytes) + " a scene file may have";
  return "";
}

std::string NotText(const char* bytes, size_t n) {
  const size_t look = std::min(n, kTextProbeBytes);
  const void* nul = std::memchr(bytes, '\0', look);
  if (nul == nullptr) return "";
  return "not a text file (a NUL byte at byte " +
         std::to_string(static_cast<const char*>(nul) - bytes + 1) + ")";
}

namespace {

std::string ReadWhole(const std::string& path, bool text, std::string* out) {
  std::string err = CheckReadable(path);
  if (!err.empty()) return err;
  os::InFile in;
  std::string why;
  if (!in.Open(path.c_str(), &why)) return "cannot open (" + why + ")";
  std::string all;
  char buf[1 << 16];
  for (;;) {
    const int64_t n = in.Read(buf, sizeof buf, &why);
    if (n < 0) return "cannot read (" + why + ")";
    if (n == 0) break;
    // A binary file is refused by its first kilobyte, not read whole.
    if (text && all.empty()) {
      err = NotText(buf, static_cast<size_t>(n));
      if (!err.empty()) return err;
    }
    all.append(buf, static_cast<size_t>(n));
  }
  *out = std::move(all);
  return "";
}

}  // namespace

std::string ReadText(const std::string& path, std::string* text) {
  return ReadWhole(path, true, text);
}

std::string ReadBytes(const std::string& path, std::string* bytes) {
  return ReadWhole(path, false, bytes);
}

// A file named inside another (mtllib in an OBJ, map_Kd in an MTL): relative
// to the naming file's directory, or as it is when absolute.
std::string Beside(const std::string& namingFile, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  size_t slash = namingFile.rfind('/');
  return (slash == std::string::npos ? "" : namingFile.substr(0, slash + 1)) + name;
}

// Parses tokens[first..first+count) as finite floats into out[].
std::string ParseFloats(const Tokens& tokens, size_t first, size_t count, float* out) {
  for (size_t i = 0; i < count; ++i) {
    const std::string& s = tokens[first + i];
    char* end = nullptr;
    double d = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || *end != '\0') return "bad number " + Quote(s);
    if (!std::isfinite(d)) return "number " + Quote(s) + " is not finite";
    if (std::fabs(d) > std::numeric_limits<float>::max())
      return "number " + Quote(s) + " is too large";
    if (d != 0.0 && std::fabs(d) < std::numeric_limits<float>::min())
      return "number " + Quote(s) +
             " is too small for float (it would be 0 or denormal; least 1.2e-38)";
    out[i] = static_cast<float>(d);
  }
  return "";
}

bool IsInteger(const std::string& s) {
  size_t i = (!s.empty() && (s[0] == '-' || s[0] == '+')) ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

// Resolves a 1-based OBJ index (negative: counts back from the last element
// defined so far) against `count` elements of `what` ("vertex", ...).
namespace {
std::string ResolveIndex(const std::string& s, const std::string& corner, size_t count,
                         const char* what, const char* plural, size_t* index) {
  long long i = std::strtoll(s.c_str(), nullptr, 10);  // saturates: then out of range
  if (i == 0)
    return std::string(what) + " index 0 in " + Quote(corner) + " (OBJ indices start at 1)";
  long long resolved = i > 0 ? i - 1 : static_cast<long long>(count) + i;
  if (resolved < 0 || resolved >= static_cast<long long>(count))
    return std::string(what) + " index " + (s.size() > 20 ? s.substr(0, 20) + "..." : s) +
           " out of range (" + Str(count) + " " + plural + " so far)";
  *index = static_cast<size_t>(resolved);
  return "";
}

}  // namespace

std::string ParseCorner(const std::string& s, size_t numVertices, size_t numUvs, size_t numNormals,
                        CornerIndex* out) {
  const std::string bad = "bad face vertex " + Quote(s);
  size_t slash = s.find('/');
  std::string pos = s.substr(0, slash), uv, normal;
  if (slash != std::string::npos) {
    std::string rest = s.substr(slash + 1);
    size_t slash2 = rest.find('/');
    uv = rest.substr(0, slash2);
    if (slash2 != std::string::npos) {
      normal = rest.substr(slash2 + 1);
      if (!IsInteger(normal)) return bad;
    }
    if (!(IsInteger(uv) || (uv.empty() && slash2 != std::string::npos))) return bad;
  }
  if (!IsInteger(pos)) return bad;
  CornerIndex c;
  std::string err = ResolveIndex(pos, s, numVertices, "vertex", "vertices", &c.v);
  if (err.empty() && !uv.empty())
    err = ResolveIndex(uv, s, numUvs, "texture coordinate", "texture coordinates", &c.vt);
  if (err.empty() && !normal.empty())
    err = ResolveIndex(normal, s, numNormals, "normal", "normals", &c.vn);
  *out = c;
  return err;
}

// "1 face", "3 faces".
std::string Count(size_t n, const char* one, const char* many) {
  return Str(n) + " " + (n == 1 ? one : many);
}

// Parses "a b c" (or one number) leniently, for keys only read to warn.
bool LenientFloats(const Tokens& t, size_t count, double* out) {
  if (t.size() < count + 1) return false;
  for (size_t i = 0; i < count; ++i) {
    char* end = nullptr;
    out[i] = std::strtod(t[i + 1].c_str(), &end);
    if (end == t[i + 1].c_str() || *end != '\0' || !std::isfinite(out[i])) return false;
  }
  return true;
}

// MTL keys that do not matter to diffuse radiosity, read silently (those
// that describe a specular or transparent material are looked at for the
// warning that names such materials).
bool IsSilentMtlKey(const std::string& key) {
  static const char* const kKeys[] = {
      "Ns",     "Ni",     "d",        "Tr",       "Tf",   "illum", "Ks",    "sharpness", "map_Ka",
      "map_Ks", "map_Ns", "map_bump", "map_Bump", "bump", "disp",  "decal", "refl",      "Km"};
  for (const char* k : kKeys)
    if (key == k) return true;
  return false;
}

// Why a material is not purely diffuse, or "" if it is.
std::string NotDiffuse(const Finish& f) {
  if (f.illum >= 3 && f.illum <= 9) return "illum " + std::to_string(f.illum);
  if (f.ks && f.illum != 0 && f.illum != 1) return "Ks";
  if (f.d < 1.0) return "d " + Num(f.d);
  if (f.tf) return "Tf";
  return "";
}

TextLines::TextLines(const std::string& text) : text_(text) {
  // A UTF-8 byte-order mark (some Windows editors write one) is not text.
  pos_ = text.compare(0, 3, "\xef\xbb\xbf") == 0 ? 3 : 0;
}

bool TextLines::Next(std::string* line) {
  if (pos_ >= text_.size()) return false;
  size_t end = text_.find_first_of("\r\n", pos_);
  if (end == std::string::npos) end = text_.size();
  line->assign(text_, pos_, end - pos_);
  // A line ends at LF, CR LF or a lone CR (old Mac files).
  pos_ = end + (end + 1 < text_.size() && text_[end] == '\r' && text_[end + 1] == '\n' ? 2 : 1);
  return true;
}

namespace {
// The first CR or LF in [p, p + n), or null.
const char* FindLineEnd(const char* p, size_t n) {
  for (const char* e = p + n; p < e; ++p)
    if (*p == '\n' || *p == '\r') return p;
  return nullptr;
}
}  // namespace

namespace {
constexpr size_t kLineBuffer = size_t{1} << 16;
}  // namespace

std::string FileLines::Open(const std::string& path) {
  std::string err = CheckReadable(path);
  if (!err.empty()) return err;
  std::string why;
  if (!in_.Open(path.c_str(), &why)) return "cannot open (" + why + ")";
  buf_.reset(new char[kLineBuffer]);
  begin_ = end_ = 0;
  first_ = true;
  eof_ = false;
  lines_ = 0;
  pendingCr_ = false;
  errorLine_ = 0;
  error_.clear();
  return "";
}

bool FileLines::Fail(std::string error, int line) {
  error_ = std::move(error);
  errorLine_ = line;
  eof_ = true;
  begin_ = end_ = 0;
  return false;
}

bool FileLines::Next(std::string* line) {
  line->clear();
  if (!error_.empty()) return false;
  bool any = false;  // a line has begun (bytes, or a '\n' ends an empty one)
  for (;;) {
    if (begin_ == end_) {
      if (eof_ || !in_.isOpen()) {
        if (any) ++lines_;
        return any;
      }
      std::string why;
      const int64_t n = in_.Read(buf_.get(), kLineBuffer, &why);
      end_ = n > 0 ? static_cast<size_t>(n) : 0;
      begin_ = 0;
      if (n < 0) return Fail("cannot read (" + why + ")", 0);
      if (end_ < kLineBuffer) eof_ = true;
      // The LF of a CR LF whose CR ended the last buffer.
      if (pendingCr_ && end_ > 0 && buf_[0] == '\n') begin_ = 1;
      pendingCr_ = false;
      if (first_ && end_ > 0) {
        first_ = false;
        // A binary file (1 GB of NUL bytes) is refused by its first
        // kilobyte, at the line the NUL is on.
        std::string err = NotText(buf_.get(), end_);
        if (!err.empty()) {
          const char* nul = static_cast<const char*>(std::memchr(buf_.get(), '\0', end_));
          int at = 1;
          for (const char* c = buf_.get(); c < nul; ++c)
            at += *c == '\n' || (*c == '\r' && c[1] != '\n');
          return Fail(err, at);
        }
        // A UTF-8 byte-order mark at the start is not text (split reads of
        // it are not worth handling: the buffer holds far more than 3 bytes).
        if (end_ >= 3 && std::memcmp(buf_.get(), "\xef\xbb\xbf", 3) == 0) begin_ = 3;
      }
      if (begin_ == end_) {
        if (any) ++lines_;
        return any;
      }
    }
    const char* start = buf_.get() + begin_;
    // A line ends at LF, CR LF or a lone CR (old Mac files).
    const char* nl = FindLineEnd(start, end_ - begin_);
    const size_t n = nl != nullptr ? static_cast<size_t>(nl - start) : end_ - begin_;
    // The line's bytes are bounded: a longer line (a 300 MB comment) is
    // refused with its number instead of being held.
    if (line->size() + n > kMaxLineBytes) {
      line->clear();
      return Fail("line longer than " + std::to_string(kMaxLineBytes) +
                      " bytes (the most a scene file's line may have)",
                  lines_ + 1);
    }
    line->append(start, n);
    if (nl != nullptr) {
      begin_ += n + 1;
      if (*nl == '\r') {
        if (begin_ < end_ && buf_[begin_] == '\n')
          ++begin_;
        else if (begin_ == end_)
          pendingCr_ = true;  // its LF, if any, comes with the next read
      }
      ++lines_;
      return true;
    }
    begin_ = end_;
    any = true;
  }
}

ObjCounts CountStatements(LineSource& lines) {
  ObjCounts c;
  std::string line;
  while (lines.Next(&line)) {
    ++c.lines;
    size_t i = 0;
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i + 1 >= line.size() || line[i] == '#') continue;
    const char a = line[i], b = line[i + 1];
    const char after = i + 2 < line.size() ? line[i + 2] : ' ';
    const bool sep1 = b == ' ' || b == '\t', sep2 = after == ' ' || after == '\t';
    if (a == 'v' && sep1) {
      ++c.vertices;
    } else if (a == 'v' && b == 't' && sep2) {
      ++c.uvs;
    } else if (a == 'v' && b == 'n' && sep2) {
      ++c.normals;
    } else if (a == 'f' && sep1) {
      ++c.faces;
      // Corners: words after the 'f'.
      bool inWord = false;
      for (size_t k = i + 1; k < line.size() && line[k] != '#'; ++k) {
        bool space = line[k] == ' ' || line[k] == '\t' || line[k] == '\r';
        if (!space && !inWord) ++c.faceCorners;
        inWord = !space;
      }
    }
  }
  return c;
}

}  // namespace vismask::objload
