// The option table: one row per `vismask render` / `footprint` option,
// with everything the program says or does about it: its name, the field it
// sets, how its value is read and the range it must lie in, its --help
// lines, whether the short --help names it, whether --resume must see it
// unchanged, and its run.json key. ParseArgs reads the command line from
// it, and --help, --help all (so the man page), run.json's options section
// and the checkpoint's comparison of options are made from it: a new
// option is one row. `vismask view`'s two options are parsed apart
// (ParseArgs).
#pragma once
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "vismask/app/options.h"

namespace vismask {

// How an option's value is read.
enum class OptionKind : uint8_t {
  kFlag,    // no value (sets a bool, or runs `parse` with an empty value)
  kCount,   // an unsigned integer: digits, or an exact integer in scientific
            // notation (1e6, 2.5e3; not 1.5), range-checked
  kNumber,  // a finite decimal number, range-checked
  kChoice,  // one word of `choices` ("power|fixed")
  kText,    // any non-empty string (a file or directory)
  kCustom,  // its own syntax: `parse` reads it
};

// Whether --resume must see the option as the checkpoint was written with.
enum class ResumeRule : uint8_t {
  kMustMatch,  // it changes the result: a difference is refused
  kMayDiffer,  // it leaves the result as it is (where it runs, what it prints)
  kByMeaning,  // --envs: compared by the environments it gives (EnvSpec)
};

// The Options member an option sets. A choice stores its index into an
// enum, true for the first word into a bool, or the word into a string.
using OptionField =
    std::variant<std::monostate, bool Options::*, int Options::*, uint32_t Options::*,
                 uint64_t Options::*, float Options::*, double Options::*, std::string Options::*,
                 Options::RayAlloc Options::*, MaskMethod Options::*, CentreChoice Options::*,
                 ViewSide Options::*>;

// The section of `--help all` an option is listed in.
enum class HelpSection : uint8_t { kRender, kEnvironments };

struct OptionSpec {
  const char* name = "";  // "--rays"
  OptionKind kind = OptionKind::kFlag;
  OptionField field;
  bool Options::*given = nullptr;  // set true when the option is given (hasRays)
  // The accepted range: lo <= v <= hi, or lo < v / v < hi when open. A
  // count's bounds are integers; hi = kNoLimit: none.
  double lo = 0.0, hi = 0.0;
  bool loOpen = false, hiOpen = false;
  // The error's "expected ..." words ("an integer in [1, 1e8]"); a choice's
  // are made from its words ("power or fixed").
  const char* expected = "";
  // A float field: the words for a value float rounds to 0 (nullptr: such
  // a value is taken).
  const char* tiny = nullptr;
  const char* choices = nullptr;  // kChoice: the words, '|' between them
  // kCustom, or a flag whose field is not a plain member: reads the value
  // (empty for a flag) into the options; the error names the flag.
  Status (*parse)(const std::string& flag, const std::string& value, Options* o) = nullptr;
  // --help all: the value's name ("N"; nullptr: a flag) and the lines
  // describing it, pre-wrapped to fit beside the names ('\n' between
  // lines; one paragraph wrapped by HelpText when it holds %may-differ%,
  // the options --resume lets differ).
  const char* arg = nullptr;
  const char* help = nullptr;
  // A second entry under the same option (--envs auto[:N]).
  const char* moreLabel = nullptr;
  const char* moreHelp = nullptr;
  HelpSection section = HelpSection::kRender;
  bool usage = false;  // also named by the short --help
  ResumeRule resume = ResumeRule::kMustMatch;
  // run.json's key for the option in "options" (nullptr: not recorded
  // there). The value is the field's, after ParseArgs and init resolved it
  // (run_json.cpp: those init decides, and those written only when set).
  const char* json = nullptr;
};

constexpr double kNoLimit = 1e300;

// Every option of render and footprint, in --help all's order.
const std::vector<OptionSpec>& OptionTable();

// The row of `name` ("--rays"), or nullptr.
const OptionSpec* FindOption(const std::string& name);

// A choice's words, in order ("power|fixed" -> {"power", "fixed"}).
std::vector<std::string> ChoiceWords(const OptionSpec& spec);

// The index of the word a choice option's field holds, or -1. Does not
// allocate (run.json is written after init).
int ChosenIndex(const OptionSpec& spec, const Options& o);

// A choice's word `index` as a pointer into `choices` and its length;
// false when there is none. Does not allocate.
bool ChoiceWordAt(const OptionSpec& spec, int index, const char** word, size_t* length);

}  // namespace vismask
