// POSIX implementation of os.h's init-time services for `vismask view`:
// listing a directory, the executable's directory, exec.
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "vismask/core/os.h"

namespace vismask::os {

bool IsDirectory(const char* path) {
  struct stat st;
  return ::stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

bool ListDirectory(const char* dir, std::vector<std::string>* names, std::string* why) {
  names->clear();
  DIR* d = ::opendir(dir);
  if (!d) {
    *why = std::string("cannot read directory ") + dir + ": " + ::strerror(errno);
    return false;
  }
  while (const dirent* e = ::readdir(d)) {
    if (std::strcmp(e->d_name, ".") == 0 || std::strcmp(e->d_name, "..") == 0) continue;
    names->push_back(e->d_name);
  }
  ::closedir(d);
  std::sort(names->begin(), names->end());
  return true;
}

std::string ExecutableDir() {
  char* real = ::realpath("/proc/self/exe", nullptr);
  if (!real) return std::string();
  std::string path(real);
  ::free(real);
  size_t slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash == 0 ? 1 : slash);
}

void Exec(const std::vector<std::string>& argv, std::string* why) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  ::execvp(args[0], args.data());
  *why = "cannot run " + argv[0] + ": " + ::strerror(errno);
}

}  // namespace vismask::os
