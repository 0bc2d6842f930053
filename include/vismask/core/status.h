// The result of an init-time operation that can fail on user input: ok, or an
// error that names where in the input it happened ("file:line: message").
// Only for init and argument parsing: it holds std::strings.
#pragma once
#include <string>

namespace vismask {

class Status {
 public:
  static Status Ok() { return Status(); }
  // An error at `line` of `file` (line 0: the file as a whole).
  static Status At(std::string file, int line, std::string message);
  // An error that is not tied to a file (a bad option, say).
  static Status Error(std::string message);

  bool ok() const { return !failed_; }
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& message() const { return message_; }
  // "file:line: message", "file: message" or "message".
  std::string ToString() const;

 private:
  bool failed_ = false;
  std::string file_;
  int line_ = 0;
  std::string message_;
};

}  // namespace vismask
