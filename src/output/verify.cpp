// `vismask verify OUT_DIR`: whether the outputs in OUT_DIR are the set one
// run committed, by the commit record in its run.json (run.h). A commit an
// interrupted run left half done is finished first (os::CommitAll's
// journal), as the next render into OUT_DIR would.
#include <zlib.h>

#include "../app/run.h"

namespace vismask::run {

namespace {

// A file's whole text, if it is a regular file of at most `limit` bytes.
std::string ReadSmall(const std::string& path, size_t limit, std::string* why) {
  os::InFile in;
  if (!in.Open(path.c_str(), why)) return "";
  const int64_t size = in.Size();
  if (size < 0 || static_cast<uint64_t>(size) > limit) {
    *why = "larger than " + std::to_string(limit) + " bytes";
    return "";
  }
  std::string text(static_cast<size_t>(size), '\0');
  if (size > 0 && in.Read(&text[0], text.size(), why) != size) {
    if (why->empty()) *why = "it changed while it was read";
    return "";
  }
  why->clear();
  return text;
}

// Reads a JSON string starting at text[*at] == '"' (run.json's escapes:
// \" \\ and \u00XX, which stands for the byte XX); false if malformed.
bool JsonStringAt(const std::string& text, size_t* at, std::string* out) {
  size_t i = *at;
  if (i >= text.size() || text[i] != '"') return false;
  out->clear();
  for (++i; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '"') {
      *at = i + 1;
      return true;
    }
    if (c != '\\') {
      *out += c;
      continue;
    }
    if (++i >= text.size()) return false;
    const char e = text[i];
    if (e == '"' || e == '\\' || e == '/') {
      *out += e;
    } else if (e == 'u' && i + 4 < text.size() && text.compare(i + 1, 2, "00") == 0) {
      const unsigned long v = std::strtoul(text.substr(i + 3, 2).c_str(), nullptr, 16);
      *out += static_cast<char>(v);
      i += 4;
    } else {
      return false;
    }
  }
  return false;
}

struct Listed {
  std::string file;
  uint64_t bytes = 0;
  uint32_t crc = 0;
};

// The "outputs" array of run.json, as WriteRunJson writes it.
bool ParseOutputs(const std::string& json, std::vector<Listed>* out) {
  size_t at = json.find("\n  \"outputs\": [");
  if (at == std::string::npos) return false;
  at = json.find('[', at) + 1;
  for (;;) {
    const size_t open = json.find_first_not_of(" \n,", at);
    if (open == std::string::npos) return false;
    if (json[open] == ']') return true;
    const std::string key = "{\"file\": ";
    if (json.compare(open, key.size(), key) != 0) return false;
    at = open + key.size();
    Listed l;
    if (!JsonStringAt(json, &at, &l.file)) return false;
    unsigned long long bytes = 0;
    unsigned crc = 0;
    int used = 0;
    if (std::sscanf(json.c_str() + at, ", \"bytes\": %llu, \"crc32\": \"%8x\"}%n", &bytes, &crc,
                    &used) != 2 ||
        used == 0)
      return false;
    at += static_cast<size_t>(used);
    l.bytes = bytes;
    l.crc = crc;
    out->push_back(l);
  }
}

}  // namespace

bool SizeAndCrc(const std::string& path, uint64_t* bytes, uint32_t* crc, std::string* why) {
  os::InFile in;
  if (!in.Open(path.c_str(), why)) return false;
  *bytes = 0;
  uLong c = ::crc32(0L, Z_NULL, 0);
  static char buf[1 << 16];
  for (;;) {
    const int64_t n = in.Read(buf, sizeof buf, why);
    if (n < 0) return false;
    if (n == 0) break;
    c = ::crc32(c, reinterpret_cast<const Bytef*>(buf), static_cast<uInt>(n));
    *bytes += static_cast<uint64_t>(n);
  }
  *crc = static_cast<uint32_t>(c);
  return true;
}

int Verify(const Options& o) {
  const std::string& dir = o.verifyDir;
  char why[os::kWhyBytes] = "";
  // A commit left half done by a killed run: finished, under the lock.
  if (os::Exists((dir + "/.vismask.commit").c_str())) {
    os::DirLock lock;
    if (!lock.Acquire(dir.c_str(), why)) {
      os::PrintErr("vismask: verify: %s\n", why);
      return lock.inUse() ? kExitUsage : kExitOutput;
    }
    int renamed = 0;
    if (os::FinishInterruptedCommit(dir.c_str(), &renamed, why) < 0) {
      os::PrintErr("vismask: verify: %s\n", why);
      return kExitOutput;
    }
    os::PrintErr(
        "vismask: verify: finished the commit an interrupted run left in '%s' (%d file%s "
        "renamed)\n",
        dir.c_str(), renamed, renamed == 1 ? "" : "s");
  }
  std::string err;
  const std::string runJson = dir + "/run.json";
  const std::string json = ReadSmall(runJson, size_t{64} << 20, &err);
  if (!err.empty()) {
    os::PrintErr("vismask: verify: cannot read '%s' (%s): no complete run in '%s'\n",
                 runJson.c_str(), err.c_str(), dir.c_str());
    return kExitOutput;
  }
  std::vector<Listed> listed;
  if (!ParseOutputs(json, &listed) || listed.empty()) {
    os::PrintErr(
        "vismask: verify: '%s' has no commit record (\"outputs\"; an older vismask "
        "wrote it, or it is damaged)\n",
        runJson.c_str());
    return kExitOutput;
  }
  int bad = 0;
  for (const Listed& l : listed) {
    // Names without a '/' are in OUT_DIR; --export's path is as given.
    const std::string path = l.file.find('/') == std::string::npos ? dir + "/" + l.file : l.file;
    uint64_t bytes = 0;
    uint32_t crc = 0;
    if (!SizeAndCrc(path, &bytes, &crc, &err)) {
      os::PrintErr("vismask: verify: '%s': cannot read (%s)\n", path.c_str(), err.c_str());
      ++bad;
    } else if (bytes != l.bytes || crc != l.crc) {
      os::PrintErr(
          "vismask: verify: '%s' has %llu bytes, CRC-32 %08x; run.json lists %llu bytes, "
          "CRC-32 %08x: not the file of the run that wrote run.json\n",
          path.c_str(), static_cast<unsigned long long>(bytes), static_cast<unsigned>(crc),
          static_cast<unsigned long long>(l.bytes), static_cast<unsigned>(l.crc));
      ++bad;
    }
  }
  if (bad > 0) {
    os::PrintErr("vismask: verify: '%s' is not one run's complete set (%d of %zu outputs)\n",
                 dir.c_str(), bad, listed.size());
    return kExitOutput;
  }
  char line[2048];
  const int n = std::snprintf(line, sizeof line, "%s: complete: %zu outputs and run.json\n",
                              dir.c_str(), listed.size());
  if (!WriteStdout(line,
                   static_cast<size_t>(n) < sizeof line ? static_cast<size_t>(n) : sizeof line - 1))
    return kExitOutput;
  return kExitOk;
}

}  // namespace vismask::run
