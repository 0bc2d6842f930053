// Internal to src/app: how the option table's rows are written
// (options_table.h has the table itself). A row is made by its kind's
// builder, then what applies is chained on; the rows are added section by
// section (options_rows_run.cpp, options_rows_scene.cpp).
#pragma once
#include <string>
#include <vector>

#include "vismask/app/options_table.h"

namespace vismask {
namespace option_rows {

// The least normal float: options stored as float refuse anything smaller
// rather than silently becoming 0 (--patch-size 0 is "automatic").
constexpr double kFloatMin = 1.17549435e-38;

using O = Options;  // the rows name fields as &O::field

// A row under construction: the kind's constructor, then what applies.
struct Row {
  OptionSpec s;
  Row& Given(bool Options::*g) { return s.given = g, *this; }
  Row& Open(bool lo, bool hi) { return s.loOpen = lo, s.hiOpen = hi, *this; }
  Row& Tiny(const char* words) { return s.tiny = words, *this; }
  // The help is written as a raw string that starts on the line after
  // its opening R"(: that first line end is not part of the text.
  static const char* Text(const char* help) { return help + (*help == '\n'); }
  Row& Help(const char* arg, const char* help) { return s.arg = arg, s.help = Text(help), *this; }
  Row& More(const char* label, const char* help) {
    return s.moreLabel = label, s.moreHelp = Text(help), *this;
  }
  Row& Usage() { return s.usage = true, *this; }
  Row& Envs() { return s.section = HelpSection::kEnvironments, *this; }
  Row& Resume(ResumeRule rule) { return s.resume = rule, *this; }
  Row& MayDiffer() { return Resume(ResumeRule::kMayDiffer); }
  Row& Json(const char* key) { return s.json = key, *this; }
};

inline Row Make(const char* name, OptionKind kind, OptionField field) {
  Row r;
  r.s.name = name;
  r.s.kind = kind;
  r.s.field = field;
  return r;
}
inline Row Flag(const char* name, OptionField field) {
  return Make(name, OptionKind::kFlag, field);
}
inline Row Count(const char* name, OptionField field, double lo, double hi, const char* expected) {
  Row r = Make(name, OptionKind::kCount, field);
  r.s.lo = lo, r.s.hi = hi, r.s.expected = expected;
  return r;
}
inline Row Number(const char* name, OptionField field, double lo, double hi, const char* expected) {
  Row r = Count(name, field, lo, hi, expected);
  r.s.kind = OptionKind::kNumber;
  return r;
}
inline Row Choice(const char* name, OptionField field, const char* choices) {
  Row r = Make(name, OptionKind::kChoice, field);
  r.s.choices = choices;
  return r;
}
inline Row Text(const char* name, OptionField field, const char* expected) {
  Row r = Make(name, OptionKind::kText, field);
  r.s.expected = expected;
  return r;
}
inline Row Custom(const char* name, decltype(OptionSpec::parse) parse) {
  Row r = Make(name, OptionKind::kCustom, std::monostate());
  r.s.parse = parse;
  return r;
}
inline Row Flag(const char* name, decltype(OptionSpec::parse) parse) {
  Row r = Custom(name, parse);
  r.s.kind = OptionKind::kFlag;
  return r;
}

// The options whose syntax is their own (options_table.cpp).
Status ParseExport(const std::string& a, const std::string& v, Options* o);
Status ParseCamera(const std::string& a, const std::string& v, Options* o);
Status ParseEnvs(const std::string& a, const std::string& v, Options* o);
Status ParseEnvOrder(const std::string& a, const std::string& v, Options* o);
Status ParseMemBudget(const std::string& a, const std::string& v, Options* o);
Status ParseSkyOption(const std::string& a, const std::string& v, Options* o);
Status ParseSunOption(const std::string& a, const std::string& v, Options* o);
Status ParseEmit(const std::string& a, const std::string& v, Options* o);
Status ParseStrict(const std::string&, const std::string&, Options* o);
Status ParseJson(const std::string&, const std::string&, Options* o);

// The rows, a section each (in --help all's order: solve, image, scene,
// environments, run).
std::vector<Row> SolveRows();
std::vector<Row> ImageRows();
std::vector<Row> SceneRows();
std::vector<Row> EnvironmentRows();
std::vector<Row> RunRows();

}  // namespace option_rows
}  // namespace vismask
