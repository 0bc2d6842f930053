// TextWriter: formatted text into an output file through a fixed buffer
// carved at init, so that writing CSV and JSON allocates nothing. Lines are
// formatted with vsnprintf (each at most 1 KiB) and flushed when the buffer
// is nearly full.
#pragma once
#include "vismask/core/os.h"
#include "vismask/core/span.h"

namespace vismask {

class TextWriter {
 public:
  static constexpr size_t kMaxLine = 1024;

  TextWriter() = default;
  // `buffer` must hold at least 2 * kMaxLine bytes.
  TextWriter(os::OutFile* file, Span<char> buffer);

  void Printf(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  void Write(const char* s, size_t n);
  // Writes the buffered text. False if any write has failed.
  bool Flush();
  bool ok() const { return ok_; }

 private:
  os::OutFile* file_ = nullptr;
  Span<char> buffer_;
  size_t used_ = 0;
  bool ok_ = true;
};

}  // namespace vismask
