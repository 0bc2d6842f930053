#include "vismask/core/status.h"

namespace vismask {

Status Status::At(std::string file, int line, std::string message) {
  Status s;
  s.failed_ = true;
  s.file_ = std::move(file);
  s.line_ = line;
  s.message_ = std::move(message);
  return s;
}

Status Status::Error(std::string message) {
  return At("", 0, std::move(message));
}

std::string Status::ToString() const {
  if (file_.empty()) return message_;
  if (line_ <= 0) return file_ + ": " + message_;
  return file_ + ":" + std::to_string(line_) + ": " + message_;
}

}  // namespace vismask
