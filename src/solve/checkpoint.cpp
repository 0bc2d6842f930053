#include "vismask/solve/checkpoint.h"

#include <zlib.h>

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <type_traits>

namespace vismask {

namespace {

constexpr char kMagic[8] = {'v', 'i', 's', 'm', 'c', 'k', 'p', 't'};
// 2: RoundTotals' fields reordered (EnvSums); 3: EnvSums::emission;
// 4: EnvSums::foreignShots and shotWork.
constexpr uint32_t kVersion = 4;
constexpr char kManifestHead[] = "vismask checkpoint 1\n";
constexpr size_t kManifestExtra = 1024;  // the manifest's lines beside the identity

// An environment's file: this head, EnvState, SolveState, the arena's bytes.
struct FileHead {
  char magic[8];
  uint32_t version;
  uint32_t env;
  uint64_t generation;
  uint64_t stateBytes;
  uint64_t solveBytes;
  uint64_t arenaBytes;
  uint32_t crc;  // of everything after the head
  uint32_t numEnvs;
};
static_assert(std::is_trivially_copyable<FileHead>::value, "written as it is");
static_assert(std::is_trivially_copyable<EnvState>::value, "written as it is");
static_assert(std::is_trivially_copyable<SolveState>::value, "written as it is");

uint32_t Crc(uint32_t crc, const void* data, size_t n) {
  const Bytef* p = static_cast<const Bytef*>(data);
  uLong c = crc;
  while (n > 0) {
    const size_t part = n < (size_t{1} << 30) ? n : (size_t{1} << 30);
    c = ::crc32(c, p, static_cast<uInt>(part));
    p += part;
    n -= part;
  }
  return static_cast<uint32_t>(c);
}

// Reads exactly n bytes; false (with *why) on an error or a short file.
bool ReadAll(os::InFile* f, void* data, size_t n, const std::string& path, std::string* why) {
  uint8_t* p = static_cast<uint8_t*>(data);
  while (n > 0) {
    const int64_t got = f->Read(p, n, why);
    if (got < 0) {
      *why = "cannot read " + path + ": " + *why;
      return false;
    }
    if (got == 0) {
      *why = path + " is cut short (a damaged checkpoint)";
      return false;
    }
    p += got;
    n -= static_cast<size_t>(got);
  }
  return true;
}

// The manifest's "key value" lines (value: the rest of the line).
bool ReadManifest(const std::string& dir, std::vector<std::pair<std::string, std::string>>* lines,
                  std::string* why) {
  const std::string path = dir + "/manifest";
  os::InFile f;
  if (!f.Open(path.c_str(), why)) {
    *why = "no complete checkpoint in " + dir + " (" + path + ": " + *why + ")";
    return false;
  }
  std::string text;
  char buf[4096];
  for (;;) {
    const int64_t got = f.Read(buf, sizeof buf, why);
    if (got < 0) {
      *why = "cannot read " + path + ": " + *why;
      return false;
    }
    if (got == 0) break;
    text.append(buf, static_cast<size_t>(got));
  }
  if (text.compare(0, sizeof kManifestHead - 1, kManifestHead) != 0) {
    *why = path + ":1: not a vismask checkpoint manifest";
    return false;
  }
  size_t at = sizeof kManifestHead - 1;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(at, end - at);
    const size_t space = line.find(' ');
    lines->emplace_back(line.substr(0, space),
                        space == std::string::npos ? "" : line.substr(space + 1));
    at = end + 1;
  }
  return true;
}

const std::string* Find(const std::vector<std::pair<std::string, std::string>>& lines,
                        const std::string& key) {
  for (const auto& kv : lines)
    if (kv.first == key) return &kv.second;
  return nullptr;
}

}  // namespace

uint64_t CheckpointFileBytes(uint64_t arenaBytes) {
  return sizeof(FileHead) + sizeof(EnvState) + sizeof(SolveState) + arenaBytes;
}

std::string CheckpointIdentity(uint64_t sceneBytes, uint32_t sceneCrc, const std::string& envSpec,
                               const std::vector<std::string>& resultArgs) {
  char scene[64];
  std::snprintf(scene, sizeof scene, "scene %llu %08x\n",
                static_cast<unsigned long long>(sceneBytes), sceneCrc);
  std::string options = "options";
  for (const std::string& a : resultArgs) options += " " + a;
  return std::string(scene) + "environments " + envSpec + "\n" + options + "\n";
}

std::string ManifestValue(const std::string& dir, const char* key) {
  std::vector<std::pair<std::string, std::string>> lines;
  std::string why;
  if (!ReadManifest(dir, &lines, &why)) return "";
  const std::string* v = Find(lines, key);
  return v ? *v : "";
}

Status Checkpoints::Setup(const std::string& dir, double every, Span<Environment* const> envs,
                          uint32_t numEnvs, Transport* transport, const std::string& identity) {
  dir_ = dir;
  every_ = every;
  envs_ = envs;
  numEnvs_ = numEnvs;
  transport_ = transport;
  identity_ = identity;
  paths_.clear();
  rankBytes_ = 0;
  for (Environment* e : envs) {
    char name[32];
    for (char slot : {'a', 'b'}) {
      std::snprintf(name, sizeof name, "/env-%05u.%c", e->index(), slot);
      paths_.push_back(dir + name);
    }
    rankBytes_ += CheckpointFileBytes(e->arenaBytes().size());
  }
  manifestPath_ = dir + "/manifest";
  // What killed runs left: temporary files of their checkpoints.
  for (const std::string& path : paths_) os::RemoveStaleTemporaries(path.c_str(), nullptr, 0);
  if (transport->rank() == 0) os::RemoveStaleTemporaries(manifestPath_.c_str(), nullptr, 0);
  if (transport->rank() == 0) manifest_.assign(identity.size() + kManifestExtra, '\0');
  char why[os::kWhyBytes] = "";
  int32_t mine = os::MakeDirs(dir.c_str(), why) ? 0 : 1, all[kMaxRanks] = {};
  if (mine == 0 && dir.size() + 32 >= os::kMaxPath) {
    std::snprintf(why, sizeof why, "path too long");
    mine = 1;
  }
  transport->AllGather(&mine, sizeof mine, all);
  if (mine != 0)
    return Status::Error("vismask: rank " + std::to_string(transport->rank()) + ": --checkpoint " +
                         dir + ": " + why);
  for (int k = 0; k < transport->size(); ++k)
    if (all[k] != 0) return Status::Error("");
  return Status::Ok();
}

Status Checkpoints::Resume(SolveState* state) {
  // Rank 0: the manifest, and whether this run agrees with it.
  struct Verdict {
    int32_t ok;
    uint32_t pad;
    uint64_t generation;
  } mine = {0, 0, 0}, all[kMaxRanks] = {};
  std::string message;
  if (transport_->rank() == 0) {
    std::vector<std::pair<std::string, std::string>> lines;
    std::string why;
    if (!ReadManifest(dir_, &lines, &why)) {
      message = "vismask: --resume: " + why;
    } else {
      // The identity's lines, each compared.
      std::string diff;
      size_t at = 0;
      while (at < identity_.size()) {
        size_t end = identity_.find('\n', at);
        const std::string line = identity_.substr(at, end - at);
        at = end + 1;
        const size_t space = line.find(' ');
        const std::string key = line.substr(0, space), value = line.substr(space + 1);
        const std::string* theirs = Find(lines, key);
        if (theirs == nullptr || *theirs != value)
          diff += (diff.empty() ? "" : "; ") + key + ": the checkpoint's '" +
                  (theirs ? *theirs : std::string("(none)")) + "', this run's '" + value + "'";
      }
      const std::string* g = Find(lines, "generation");
      const std::string* n = Find(lines, "environment_files");
      unsigned long long gen = 0;
      if (!diff.empty()) {
        message = "vismask: --resume " + dir_ +
                  ": the checkpoint is of another run (the scene, the environments and the "
                  "options that change the result must be the same): " +
                  diff;
      } else if (!g || std::sscanf(g->c_str(), "%llu", &gen) != 1 || gen == 0 || !n ||
                 *n != std::to_string(numEnvs_)) {
        message = "vismask: --resume: " + manifestPath_ + ": damaged (no generation or count)";
      } else {
        mine.ok = 1;
        mine.generation = gen;
      }
    }
  }
  transport_->AllGather(&mine, sizeof mine, all);
  if (!all[0].ok) return Status::Error(message);
  const uint64_t generation = all[0].generation;
  const char slot = generation % 2 == 0 ? 'b' : 'a';
  // Every rank: its environments' files of that generation.
  mine.ok = 1;
  for (size_t i = 0; i < envs_.size() && mine.ok; ++i) {
    Environment* e = envs_[i];
    const std::string& path = paths_[2 * i + (slot == 'a' ? 0 : 1)];
    std::string why;
    os::InFile f;
    FileHead head;
    EnvState es;
    SolveState ss;
    auto fail = [&](const std::string& what) {
      message = "vismask: rank " + std::to_string(transport_->rank()) + ": --resume: " + what;
      mine.ok = 0;
    };
    if (!f.Open(path.c_str(), &why)) {
      fail("cannot open " + path + ": " + why +
           " (every environment's file must be in the checkpoint directory of the rank that "
           "now holds it)");
      break;
    }
    if (!ReadAll(&f, &head, sizeof head, path, &why)) {
      fail(why);
      break;
    }
    if (std::memcmp(head.magic, kMagic, sizeof kMagic) != 0 || head.version != kVersion) {
      fail(path + ": not a vismask checkpoint file of this version");
      break;
    }
    if (head.env != e->index() || head.generation != generation || head.numEnvs != numEnvs_ ||
        head.stateBytes != sizeof es || head.solveBytes != sizeof ss ||
        head.arenaBytes != e->arenaBytes().size()) {
      fail(path + ": of another checkpoint or layout (environment " + std::to_string(head.env) +
           ", generation " + std::to_string(head.generation) + ", " +
           std::to_string(head.arenaBytes) + " arena bytes; expected environment " +
           std::to_string(e->index()) + ", generation " + std::to_string(generation) + ", " +
           std::to_string(e->arenaBytes().size()) + ")");
      break;
    }
    Span<uint8_t> arena = e->mutableArenaBytes();
    if (!ReadAll(&f, &es, sizeof es, path, &why) || !ReadAll(&f, &ss, sizeof ss, path, &why) ||
        !ReadAll(&f, arena.data(), arena.size(), path, &why)) {
      fail(why);
      break;
    }
    uint32_t crc = Crc(0, nullptr, 0);
    crc = Crc(crc, &es, sizeof es);
    crc = Crc(crc, &ss, sizeof ss);
    crc = Crc(crc, arena.data(), arena.size());
    char extra;
    if (crc != head.crc || f.Read(&extra, 1, &why) != 0) {
      fail(path + ": damaged (its CRC-32 or size does not match)");
      break;
    }
    if (!e->RestoreState(es)) {
      fail(path + ": its state does not fit environment " + std::to_string(e->index()));
      break;
    }
    if (i == 0) *state = ss;
  }
  transport_->AllGather(&mine, sizeof mine, all);
  for (int k = 0; k < transport_->size(); ++k)
    if (!all[k].ok) return Status::Error(mine.ok ? "" : message);
  generation_ = generation;
  lastRounds_ = triedRounds_ = resumedRounds_ = state->result.rounds;
  lastElapsed_ = triedElapsed_ = state->totals.elapsed;
  resumed_ = true;
  return Status::Ok();
}

bool Checkpoints::AtRoundEnd(const SolveState& state) {
  const bool interrupt = state.totals.interrupt != 0;
  const bool due = state.result.rounds > triedRounds_ &&
                   (every_ <= 0.0 || state.totals.elapsed - triedElapsed_ >= every_);
  if (!interrupt && !due) return false;
  const bool ok = Write(state);
  if (!interrupt) return false;
  interrupt_ = static_cast<int>(state.totals.interrupt);
  (void)ok;
  return true;
}

bool Checkpoints::Write(const SolveState& state) {
  const double t0 = os::Seconds();
  triedRounds_ = state.result.rounds;  // a failed one is tried again an interval later
  triedElapsed_ = state.totals.elapsed;
  const uint64_t generation = generation_ + 1;
  const int slot = generation % 2 == 0 ? 1 : 0;
  char why[os::kWhyBytes] = "";
  int32_t mine = 1, all[kMaxRanks] = {};
  for (size_t i = 0; i < envs_.size() && mine; ++i) {
    const Environment* e = envs_[i];
    const EnvState es = e->SaveState();
    const Span<const uint8_t> arena = e->arenaBytes();
    FileHead head;
    std::memset(&head, 0, sizeof head);
    std::memcpy(head.magic, kMagic, sizeof kMagic);
    head.version = kVersion;
    head.env = e->index();
    head.generation = generation;
    head.stateBytes = sizeof es;
    head.solveBytes = sizeof state;
    head.arenaBytes = arena.size();
    head.numEnvs = numEnvs_;
    uint32_t crc = Crc(0, nullptr, 0);
    crc = Crc(crc, &es, sizeof es);
    crc = Crc(crc, &state, sizeof state);
    head.crc = Crc(crc, arena.data(), arena.size());
    const os::FilePart parts[] = {{&head, sizeof head},
                                  {&es, sizeof es},
                                  {&state, sizeof state},
                                  {arena.data(), arena.size()}};
    if (!os::WriteFileAtomic(paths_[2 * i + slot].c_str(), parts, 4, nullptr, why)) mine = 0;
  }
  transport_->AllGather(&mine, sizeof mine, all);
  bool ok = true;
  for (int k = 0; k < transport_->size(); ++k) ok = ok && all[k] != 0;
  // Rank 0: the manifest names the checkpoint once every file is on the disk.
  int32_t committed = 0, commits[kMaxRanks] = {};
  if (ok && transport_->rank() == 0) {
    const int n = std::snprintf(
        manifest_.data(), manifest_.size(),
        "%sgeneration %llu\nslot %c\nrounds %llu\nshots %llu\nelapsed %.3f\nenvironment_files "
        "%u\n%s",
        kManifestHead, static_cast<unsigned long long>(generation), "ab"[slot],
        static_cast<unsigned long long>(state.result.rounds),
        static_cast<unsigned long long>(state.result.shots), state.totals.elapsed, numEnvs_,
        identity_.c_str());
    CHECK(n > 0 && static_cast<size_t>(n) < manifest_.size());
    const os::FilePart part = {manifest_.data(), static_cast<size_t>(n)};
    committed = os::WriteFileAtomic(manifestPath_.c_str(), &part, 1, nullptr, why) ? 1 : 0;
  }
  transport_->AllGather(&committed, sizeof committed, commits);
  writeSeconds_ += os::Seconds() - t0;
  if (commits[0] == 0) {
    ++failed_;
    if (!mine || (ok && transport_->rank() == 0))
      os::PrintErr("vismask: rank %d: the checkpoint of round %llu was not written: %s (%s)\n",
                   transport_->rank(), static_cast<unsigned long long>(state.result.rounds), why,
                   generation_ > 0 ? "the previous one stays" : "there is none yet");
    return false;
  }
  generation_ = generation;
  lastRounds_ = state.result.rounds;
  lastElapsed_ = state.totals.elapsed;
  ++written_;
  return true;
}

}  // namespace vismask
