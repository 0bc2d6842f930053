// The parser's files (scene_parse.h): checked and read whole, or a line at
// a time through a fixed buffer (FileLines), and the statements counted.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "scene_parse.h"

namespace vismask::objload {

namespace {

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
