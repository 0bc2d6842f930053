// run.json's "options" section, made from the option table
// (options_table.h): every row with a run.json key writes it, in the
// table's order, as the value the run used. Rank 0 writes it without
// allocating (run.h).
#include <type_traits>

#include "../app/run.h"
#include "vismask/app/options_table.h"

namespace vismask::run {

namespace {

// The "key": value pairs of one JSON object, a comma between them.
class Fields {
 public:
  explicit Fields(TextWriter* w) : w_(w) {}
  // Starts the pair `key`; the caller writes the value.
  TextWriter& Key(const char* key) {
    w_->Printf("%s\n    \"%s\": ", count_++ ? "," : "", key);
    return *w_;
  }
  void Bool(const char* key, bool v) { Key(key).Printf("%s", v ? "true" : "false"); }
  void String(const char* key, const std::string& v) {  // null when empty
    if (v.empty())
      Key(key).Printf("null");
    else
      JsonString(&Key(key), v.c_str());
  }

 private:
  TextWriter* w_;
  int count_ = 0;
};

struct Context {
  const RunState& r;
  const Options& o;
  float exposure;
};

// The keys whose value init resolved (the patch size, the camera, the
// environments' planes), that add keys beside their own, or that are
// written only when set (so a run without them has no such key).
void PatchSize(Fields& f, const Context& c) {
  f.Key("patch_size").Printf("%.9g", c.r.patchSize);
  // Only when --max-seconds planned it (PlanPatchSize).
  if (c.o.patchSizePlanned) f.Bool("patch_size_planned", true);
}
void Rays(Fields& f, const Context& c) {
  f.Key("rays").Printf("%u", RayCap(c.o));
}
void EmittedRays(Fields& f, const Context& c) {
  f.Key("emitted_rays").Printf("%llu", static_cast<unsigned long long>(c.o.emittedRays));
  // Only when --max-seconds planned --emitted-rays (its value is the plan).
  if (c.o.emittedRaysPlanned) f.Bool("emitted_rays_planned", true);
  // Only when the solve was paced (pace.h): the --emitted-rays its last
  // ray quantum is worth (the plan's over the quantum's last scale).
  if (c.o.emittedRaysPaced > 0)
    f.Key("emitted_rays_paced")
        .Printf("%llu", static_cast<unsigned long long>(c.o.emittedRaysPaced));
}
void Exposure(Fields& f, const Context& c) {
  f.Key("exposure").Printf("%.9g", c.exposure);
  f.Bool("exposure_auto", !c.o.hasExposure);
}
void CameraKeys(Fields& f, const Context& c) {
  const Camera& k = c.r.cam.camera;  // as --camera takes it: eye, target, up, fovy
  f.Key("camera").Printf("[%.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g, %.9g]", k.eye.x,
                         k.eye.y, k.eye.z, k.target.x, k.target.y, k.target.z, k.up.x, k.up.y,
                         k.up.z, k.fovyDeg);
}
// The side the camera frames (null with --camera), whether it was chosen
// (no --view), and how (null when --camera, --view or the scene's camera
// decided): the best side's image (its shares of front and back hits, one
// wall or not) and the best inside candidate's; then whether the camera is
// the scene's.
void ViewKeys(Fields& f, const Context& c) {
  const RunState& r = c.r;
  if (r.cam.hasSide)
    f.Key("view").Printf("\"%s\"", ViewSideName(r.cam.side));
  else
    f.Key("view").Printf("%s", r.cam.inside ? "\"inside\"" : "null");
  f.Bool("view_auto", r.cam.sideChosen);
  const ViewChoice& v = r.cam.viewChoice;
  if (!r.cam.viewProbed)
    f.Key("view_choice").Printf("null");
  else {
    TextWriter& w = f.Key("view_choice");
    w.Printf(
        "{\"side\": \"%s\", \"side_front_share\": %.6g, \"side_back_share\": %.6g, "
        "\"side_one_wall\": %s, \"inside_candidate\": %d, \"inside_front_share\": %.6g, "
        "\"inside_score\": %.6g, \"inside\": %s, \"inside_by_light\": %s, \"inside_scores\": [",
        ViewSideName(v.side), v.sideFront, v.sideBack, v.sideOneWall ? "true" : "false",
        v.candidate, v.candidateFront, v.candidateScore, v.inside ? "true" : "false",
        v.byLight ? "true" : "false");
    // Every candidate's geometric and lit score (-1: not probed; ViewChoice).
    for (int k = 0; k < kInsideCandidates; ++k) w.Printf("%s%.6g", k ? ", " : "", v.geometric[k]);
    w.Printf("], \"inside_lit_scores\": [");
    for (int k = 0; k < kInsideCandidates; ++k) w.Printf("%s%.6g", k ? ", " : "", v.lit[k]);
    // The light the lit scores count: lamps, and the sun's and the sky's from outside.
    w.Printf("], \"inside_lit_by\": {\"lamps\": %d, \"sun\": %s, \"sky\": %s}}", v.lamps,
             v.sun ? "true" : "false", v.sky ? "true" : "false");
  }
  f.Bool("camera_from_scene", r.cam.fromScene);
}
// --sky (radiance) and --sun (towards it, irradiance, angular diameter): null without.
void Sky(Fields& f, const Context& c) {
  const OutsideLight& lit = c.o.outside;
  if (!lit.skyFile.empty())  // a map: its file
  {
    TextWriter& w = f.Key("sky");
    w.Printf("{\"file\": ");
    JsonString(&w, lit.skyFile.c_str());
    w.Printf("}");
  } else if (lit.HasSky())
    f.Key("sky").Printf("[%.9g, %.9g, %.9g]", lit.sky.x, lit.sky.y, lit.sky.z);
  else
    f.Key("sky").Printf("null");
}
void Sun(Fields& f, const Context& c) {
  const OutsideLight& lit = c.o.outside;
  if (!lit.HasSun()) {
    f.Key("sun").Printf("null");
    return;
  }
  f.Key("sun").Printf(
      "{\"toward\": [%.9g, %.9g, %.9g], \"irradiance\": [%.9g, %.9g, %.9g], \"degrees\": %.9g}",
      lit.sunToward.x, lit.sunToward.y, lit.sunToward.z, lit.sun.x, lit.sun.y, lit.sun.z,
      lit.sunDegrees);
}
// The grid, --envs auto:N (null: --envs NXxNYxNZ) and the planes the grid
// was cut at, per axis from the scene box's low to its high side.
void Envs(Fields& f, const Context& c) {
  const Options& o = c.o;
  f.Key("envs").Printf("[%d, %d, %d]", o.envs[0], o.envs[1], o.envs[2]);
  if (o.envsAuto)
    f.Key("envs_auto").Printf("%d", o.envsAutoCount);
  else
    f.Key("envs_auto").Printf("null");
  TextWriter& w = f.Key("env_planes");
  w.Printf("[");
  for (int a = 0; a < 3; ++a) {
    w.Printf("%s[", a ? ", " : "");
    for (int k = 0; k <= c.r.envGrid.n[a]; ++k)
      w.Printf("%s%.9g", k ? ", " : "", c.r.envGrid.Plane(a, k));
    w.Printf("]");
  }
  w.Printf("]");
}
// Only when one of them is on, and --export only when given.
void TwoSided(Fields& f, const Context& c) {
  if (c.o.twoSided || c.o.twoSidedEmitters) f.Bool("two_sided", c.o.twoSided);
}
void TwoSidedEmitters(Fields& f, const Context& c) {
  if (c.o.twoSided || c.o.twoSidedEmitters) f.Bool("two_sided_emitters", c.o.twoSidedEmitters);
}
void Export(Fields& f, const Context& c) {
  if (!c.o.exportPath.empty()) f.String("export", c.o.exportPath);
}

struct Resolved {
  const char* key;
  void (*write)(Fields& f, const Context& c);
};
constexpr Resolved kResolved[] = {
    {"patch_size", PatchSize},
    {"rays", Rays},
    {"emitted_rays", EmittedRays},
    {"exposure", Exposure},
    {"camera", CameraKeys},
    {"view", ViewKeys},
    {"sky", Sky},
    {"sun", Sun},
    {"envs", Envs},
    {"two_sided", TwoSided},
    {"two_sided_emitters", TwoSidedEmitters},
    {"export", Export},
};

// The field's value as the row reads it: a count, a number (float to 9
// digits, double to 17), a choice's word (on|off as a JSON boolean), a
// flag as a boolean, a text as a string (null when empty).
void Generic(Fields& f, const OptionSpec& s, const Options& o) {
  if (s.kind == OptionKind::kChoice) {
    const int k = ChosenIndex(s, o);
    const char* word = nullptr;
    size_t length = 0;
    if (std::strcmp(s.choices, "on|off") == 0)
      f.Bool(s.json, k == 0);
    else if (ChoiceWordAt(s, k, &word, &length))
      f.Key(s.json).Printf("\"%.*s\"", static_cast<int>(length), word);
    else
      f.Key(s.json).Printf("null");
    return;
  }
  std::visit(
      [&](auto field) {
        if constexpr (!std::is_same_v<decltype(field), std::monostate>) {
          const auto& v = o.*field;
          using V = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<V, bool>)
            f.Bool(s.json, v);
          else if constexpr (std::is_same_v<V, std::string>)
            f.String(s.json, v);
          else if constexpr (std::is_same_v<V, float>)
            f.Key(s.json).Printf("%.9g", v);
          else if constexpr (std::is_same_v<V, double>)
            f.Key(s.json).Printf("%.17g", v);
          else if constexpr (std::is_same_v<V, int>)
            f.Key(s.json).Printf("%d", v);
          else if constexpr (std::is_integral_v<V>)
            f.Key(s.json).Printf("%llu", static_cast<unsigned long long>(v));
        }
      },
      s.field);
}

}  // namespace

void WriteRunJsonOptions(TextWriter* w, const RunState& r, float exposure) {
  const Context c{r, r.options, exposure};
  Fields f(w);
  w->Printf("  \"options\": {");
  for (const OptionSpec& s : OptionTable()) {
    if (!s.json) continue;
    const Resolved* resolved = nullptr;
    for (const Resolved& x : kResolved)
      if (std::strcmp(x.key, s.json) == 0) resolved = &x;
    if (resolved)
      resolved->write(f, c);
    else
      Generic(f, s, r.options);
  }
  w->Printf("\n  },\n");
}

}  // namespace vismask::run
