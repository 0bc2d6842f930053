// The option table drives the command line's outputs: every row is listed
// by --help all, the short --help names exactly the rows marked for it,
// run.json's options section holds exactly the rows' keys, and --resume's
// comparison holds exactly the rows that change the result.
#include "vismask/app/options_table.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.h"
#include "vismask/app/options.h"
#include "vismask/solve/checkpoint.h"

namespace vismask {
namespace {

using namespace test;

std::string Listed(const OptionSpec& s) {
  return s.arg ? std::string(s.name) + " " + s.arg : std::string(s.name);
}

// The lines of `text`.
std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(OptionTableTest, NamesAreUniqueAndFound) {
  std::set<std::string> names, keys;
  for (const OptionSpec& s : OptionTable()) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_EQ(FindOption(s.name), &s) << s.name;
    if (s.json) {
      EXPECT_TRUE(keys.insert(s.json).second) << s.json;
    }
    EXPECT_TRUE(s.help && *s.help) << s.name << ": no help";
    if (s.kind == OptionKind::kChoice) {
      EXPECT_GE(ChoiceWords(s).size(), 2u) << s.name;
    }
    if (s.kind == OptionKind::kCustom) {
      EXPECT_TRUE(s.parse) << s.name;
    }
  }
  EXPECT_EQ(FindOption("--bogus"), nullptr);
}

// Each row's entry starts a line of --help all (the name and its value's
// name, then its description or a line break), in the table's order.
TEST(OptionTableTest, HelpAllListsEveryRowInOrder) {
  const std::vector<std::string> lines = Lines(HelpText());
  size_t at = 0;
  for (const OptionSpec& s : OptionTable()) {
    const std::string entry = "  " + Listed(s);
    auto starts = [&](const std::string& line) {
      return line.rfind(entry, 0) == 0 &&
             (line.size() == entry.size() || line[entry.size()] == ' ');
    };
    size_t k = at;
    while (k < lines.size() && !starts(lines[k])) ++k;
    ASSERT_LT(k, lines.size()) << entry << " not listed (after line " << at << ")";
    at = k + 1;
  }
}

// The short --help's "common options" block names the rows marked usage,
// and only those.
TEST(OptionTableTest, ShortHelpNamesTheUsageRows) {
  const std::vector<std::string> lines = Lines(UsageText());
  std::string block;
  bool in = false;
  for (const std::string& line : lines) {
    if (line.rfind("common options", 0) == 0) {
      in = true;
      continue;
    }
    if (in && line.empty()) break;
    if (in) block += line + "  ";
  }
  ASSERT_FALSE(block.empty()) << UsageText();
  size_t usage = 0;
  for (const OptionSpec& s : OptionTable()) {
    const bool named = block.find(" " + Listed(s) + "  ") != std::string::npos;
    EXPECT_EQ(named, s.usage) << s.name << "\n" << block;
    usage += s.usage;
  }
  EXPECT_GT(usage, 0u);
}

// A valid value for each row (the args that give it), from its kind and
// range, or written out where the row's syntax is its own or it needs
// another option.
std::vector<std::string> Sample(const OptionSpec& s) {
  static const std::map<std::string, std::vector<std::string>> kSamples = {
      {"--export", {"--export", "a.glb"}},
      {"--camera", {"--camera", "0,0,-5,0,0,0,0,1,0,40"}},
      {"--envs", {"--envs", "1"}},
      {"--env-order", {"--env-order", "0"}},
      {"--mem-budget", {"--mem-budget", "1G"}},
      {"--max-rays", {"--max-rays", "100"}},  // not below --min-rays' default
      {"--sky", {"--sky", "1,1,1"}},
      {"--sun", {"--sun", "0,1,0,1,1,1"}},
      {"--emit", {"--emit", "light=1,1,1"}},
      {"--error-every", {"--reference", "r.pfm", "--error-every", "2"}},
      {"--exclude", {"--reference", "r.pfm", "--exclude", "m.pgm"}},
  };
  auto it = kSamples.find(s.name);
  if (it != kSamples.end()) return it->second;
  char value[64] = "";
  switch (s.kind) {
    case OptionKind::kFlag:
      return {s.name};
    case OptionKind::kCount:
      std::snprintf(value, sizeof value, "%.0f", s.lo < 1 ? 1.0 : s.lo);
      break;
    case OptionKind::kNumber:
      std::snprintf(value, sizeof value, "%.9g", s.hi >= kNoLimit ? s.lo + 1 : (s.lo + s.hi) / 2);
      break;
    case OptionKind::kChoice:
      return {s.name, ChoiceWords(s)[0]};
    case OptionKind::kText:
      return {s.name, "x"};
    case OptionKind::kCustom:
      ADD_FAILURE() << s.name << ": a custom row needs a sample here";
      return {};
  }
  return {s.name, value};
}

// The checkpoint identity a command line gives.
std::string Identity(const std::vector<std::string>& args, Options* o) {
  std::vector<const char*> argv = {"vismask"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  Status st = ParseArgs(static_cast<int>(argv.size()), argv.data(), o);
  EXPECT_TRUE(st.ok()) << st.ToString();
  return CheckpointIdentity(1, 2, EnvSpec(*o), o->resultArgs);
}

// Every row given alone: its name is in the arguments a checkpoint
// compares exactly when the row says it changes the result; a row that may
// differ leaves the checkpoint's identity as it is without it.
TEST(OptionTableTest, ResumeComparesTheResultChangingRows) {
  for (const OptionSpec& s : OptionTable()) {
    const std::string command = std::string(s.name) == "--json" ? "footprint" : "render";
    std::vector<std::string> base = {command, "scene.obj"};
    std::vector<std::string> args = base;
    for (const std::string& a : Sample(s)) args.push_back(a);
    Options with, without;
    const std::string given = Identity(args, &with);
    const std::string plain = Identity(base, &without);
    bool compared = false;
    for (const std::string& a : with.resultArgs) compared = compared || a == s.name;
    EXPECT_EQ(compared, s.resume == ResumeRule::kMustMatch) << s.name;
    if (s.resume == ResumeRule::kMayDiffer) {
      EXPECT_EQ(given, plain) << s.name;
    }
    if (s.resume == ResumeRule::kMustMatch) {
      EXPECT_NE(given, plain) << s.name;
    }
  }
  // --envs by its meaning: "--envs 2" and "--envs 2x1x1" are the same.
  Options a, b;
  EXPECT_EQ(Identity({"render", "s.obj", "--envs", "2", "--direct-samples", "0"}, &a),
            Identity({"render", "s.obj", "--envs", "2x1x1", "--direct-samples", "0"}, &b));
}

// The keys of run.json's "options" object (its lines up to the closing brace).
std::set<std::string> OptionKeys(const std::string& json) {
  std::set<std::string> keys;
  size_t at = json.find("\"options\": {");
  const size_t end = json.find("\n  }", at);
  while (at != std::string::npos && at < end) {
    at = json.find("\n    \"", at);
    if (at == std::string::npos || at >= end) break;
    at += 6;
    keys.insert(json.substr(at, json.find('"', at) - at));
  }
  return keys;
}

// A render with the conditional keys' options on: run.json's options hold
// every row's key, and no key but those and the ones a row's value brings
// beside its own.
TEST(OptionTableTest, RunJsonHoldsEveryRowsKey) {
  TempDir dir;
  auto r = RunMain({"render", "scenes/cornell.obj", "--quiet", "--width", "16", "--height", "16",
                    "--max-shots", "5", "--two-sided", "--export", dir.File("m.glb"), "--out",
                    dir.File("out")});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::set<std::string> keys = OptionKeys(ReadFile(dir.File("out/run.json")));
  ASSERT_FALSE(keys.empty());
  std::set<std::string> expected = {"exposure_auto", "camera_from_scene", "view_auto",
                                    "view_choice",   "envs_auto",         "env_planes"};
  for (const OptionSpec& s : OptionTable()) {
    if (!s.json) continue;
    EXPECT_EQ(keys.count(s.json), 1u) << s.name << ": no \"" << s.json << "\" in run.json";
    expected.insert(s.json);
  }
  for (const std::string& k : keys) EXPECT_EQ(expected.count(k), 1u) << k << ": no row's";
}

// A value run.json reads from the row's field, as given.
TEST(OptionTableTest, RunJsonWritesGivenValues) {
  TempDir dir;
  auto r = RunMain({"render",
                    "scenes/cornell.obj",
                    "--quiet",
                    "--width",
                    "16",
                    "--height",
                    "24",
                    "--max-shots",
                    "5",
                    "--seed",
                    "77",
                    "--sampler",
                    "random",
                    "--aa",
                    "off",
                    "--crease",
                    "12.5",
                    "--mask-method",
                    "B",
                    "--out",
                    dir.File("out")});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string json = ReadFile(dir.File("out/run.json"));
  for (const char* pair :
       {"\"width\": 16", "\"height\": 24", "\"seed\": 77", "\"sampler\": \"random\"",
        "\"aa\": false", "\"smooth\": true", "\"crease\": 12.5", "\"mask_method\": \"B\""})
    EXPECT_NE(json.find(pair), std::string::npos) << pair << "\n" << json;
}

}  // namespace
}  // namespace vismask
