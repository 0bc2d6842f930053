#include "vismask/output/text_writer.h"

#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace vismask {

TextWriter::TextWriter(os::OutFile* file, Span<char> buffer) : file_(file), buffer_(buffer) {
  CHECK(buffer.size() >= 2 * kMaxLine);
}

void TextWriter::Printf(const char* fmt, ...) {
  if (buffer_.size() - used_ < kMaxLine) Flush();
  va_list ap;
  va_start(ap, fmt);
  int n = std::vsnprintf(buffer_.data() + used_, kMaxLine, fmt, ap);
  va_end(ap);
  CHECK_MSG(n >= 0 && static_cast<size_t>(n) < kMaxLine, "TextWriter line too long");
  used_ += static_cast<size_t>(n);
}

void TextWriter::Write(const char* s, size_t n) {
  while (n > 0) {
    if (used_ == buffer_.size()) Flush();
    size_t k = buffer_.size() - used_ < n ? buffer_.size() - used_ : n;
    std::memcpy(buffer_.data() + used_, s, k);
    used_ += k;
    s += k;
    n -= k;
  }
}

bool TextWriter::Flush() {
  if (used_ > 0 && file_) ok_ = file_->Write(buffer_.data(), used_) && ok_;
  used_ = 0;
  return ok_;
}

}  // namespace vismask
