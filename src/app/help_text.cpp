// The --help texts of `vismask` (options.h, UsageText, HelpText); `vismask
// view`'s is in viewer.cpp. The prose around the options is here; each
// option's lines come from its row of the option table (options_table.h),
// so a new option is listed where it is defined.
#include <algorithm>
#include <string>
#include <vector>

#include "vismask/app/options.h"
#include "vismask/app/options_table.h"

namespace vismask {

namespace {

constexpr const char* kUsageHead = R"(vismask - fixed-memory progressive-refinement radiosity

usage:
  vismask render SCENE [options]         solve the scene's diffuse light and
                                         render it into --out DIR (out/)
  vismask footprint SCENE [options]      the memory a render would reserve
  vismask compare A.pfm B.pfm            relative RMSE of A against B
  vismask view OUT_DIR                   look around a render --export mesh
  vismask --help all                     every option, outputs, exit status

scenes read: Wavefront OBJ with its MTL files (Kd reflectance, Ke emitted
exitance, map_Kd textures: PNG, JPEG, BMP, TGA), and glTF 2.0 (.gltf, .glb:
triangles, base colour and its texture, emission, double-sided materials,
the first camera). The light is the faces that emit, those of the
materials --emit NAME=R,G,B names, and the sky and sun outside (--sky,
--sun), which need no emitter in the scene.

)";

constexpr const char* kUsageExamples = R"(examples:
  vismask render scenes/cornell.obj --out out
      the Cornell box, default view, into out/image.png (and .pfm, csv)
  vismask render scenes/real/CornellBox-Glossy.obj --emit light=17,12,4
      a published scene whose light's material its MTL lacks
  vismask render scenes/gltf-cornell/cornell_box.gltf --width 256 --height 256
      a Blender glTF export, its emissive light and double-sided walls
  vismask render scenes/skylight.obj --sky 0.3,0.4,0.6 --sun 1,4,0.5,30,28,25
      a room with no lamp, lit by the sky and the sun through its skylight
  vismask render scenes/cornell.obj --export out/box.glb && vismask view out
      the solved mesh as glTF, to walk through in a browser
)";

constexpr const char* kHelpHead = R"(vismask - fixed-memory progressive-refinement radiosity

usage:
  vismask render SCENE [options]         solve and render a scene (SCENE.obj,
                                         SCENE.gltf or SCENE.glb)
  vismask footprint SCENE [options]      the memory each environment and rank
                                         would reserve, without solving
                                         (render's options; --json for JSON)
  vismask compare A.pfm B.pfm [--exclude MASK.pgm]
                                         relative RMSE and max abs error of A
                                         against B (pixels where MASK.pgm is
                                         nonzero left out)
  vismask verify OUT_DIR                 whether OUT_DIR holds one run's
                                         complete outputs, as its run.json
                                         lists them (exit 0; 1 if not)
  vismask view OUT_DIR [--glb NAME.glb] [--port P]
                                         serve the solved mesh (render
                                         --export) in the viewer page on
                                         localhost and print its URL
                                         ('vismask view --help')
  vismask scene-dump SCENE [options] --out FILE.json
                                         the scene as vismask loads it, with
                                         the camera render would use, as JSON
                                         ('vismask scene-dump --help')
  vismask --help                         this text

)";

constexpr const char* kHelpTail = R"(outputs (in --out DIR):
  image.png         tone-mapped sRGB image
  image.pfm         linear float RGB radiance (B/pi, with the ambient term)
  patches.csv       id,env,cx,cy,cz,nx,ny,nz,area,kd_r,kd_g,kd_b,ke_r,ke_g,ke_b,b_r,b_g,b_b
                    (b = solved radiosity, without the ambient term)
  convergence.csv   shot,seconds,unshot_fraction (one row per round: each
                    environment's shots of that round); with --reference two
                    more columns, relative_rmse,error_seconds (filled on the
                    rows where the error was measured; error_seconds is the
                    total spent measuring so far, not part of seconds)
  run.json          options, counts, energy balance, timings, memory
  FILE.glb          with --export (where it names): the solved mesh, glTF 2.0

view (vismask view OUT_DIR):
  serves, on 127.0.0.1 with python3's http.server, the viewer page and
  OUT_DIR, and prints the URL: the mesh 'render --export OUT_DIR/NAME.glb'
  wrote, shown as image.png shows it (exposure slider, sRGB), to orbit
  (drag) or fly through (F; W A S D), starting from run.json's camera.
  --glb NAME.glb       the mesh in OUT_DIR (default: the one .glb there)
  --port P             the port (default: any free port)
  The page is found beside the binary: PREFIX/share/vismask/viewer when
  installed (make install), viewer/ in the source tree (make viewer).

exit status: 0 success; 1 an output could not be written (view: the viewer
page or python3 is missing); 2 bad input or
options (the message names file:line or the option); 3 a rank was lost
or silent (--rank-timeout); 4 the solve stalled (no environment could shoot
while power was left); with --checkpoint, 128 + the signal (130 for SIGINT)
after a signal, its checkpoint written
)";

// Where an option's description starts, and the width it wraps to.
constexpr size_t kHelpColumn = 23;
constexpr size_t kHelpWidth = 79;

// `items` in lines of at most `width` characters, `gap` spaces between two
// on a line.
std::vector<std::string> Wrap(const std::vector<std::string>& items, size_t gap, size_t width) {
  std::vector<std::string> lines(1);
  for (const std::string& item : items) {
    if (!lines.back().empty() && lines.back().size() + gap + item.size() > width)
      lines.emplace_back();
    if (!lines.back().empty()) lines.back().append(gap, ' ');
    lines.back() += item;
  }
  return lines;
}

// `text`'s words in lines of at most `width` characters.
std::vector<std::string> Wrap(const std::string& text, size_t width) {
  std::vector<std::string> words;
  for (size_t at = 0, end = 0; at < text.size(); at = end + 1) {
    end = std::min(text.find(' ', at), text.size());
    if (end > at) words.push_back(text.substr(at, end - at));
  }
  return Wrap(words, 1, width);
}

// "a, b and c".
std::string AllOf(const std::vector<std::string>& items) {
  std::string text;
  for (size_t k = 0; k < items.size(); ++k)
    text += (k == 0 ? "" : k + 1 == items.size() ? " and " : ", ") + items[k];
  return text;
}

// The options --resume lets differ from the checkpoint's (itself aside).
std::string MayDiffer() {
  std::vector<std::string> names;
  for (const OptionSpec& s : OptionTable())
    if (s.resume == ResumeRule::kMayDiffer && std::string(s.name) != "--resume")
      names.push_back(s.name);
  return AllOf(names);
}

// One entry of --help all: the label, then the description beside it
// (under it when the label is too long). A description with %may-differ%
// is one paragraph, wrapped here once the list is filled in.
void AppendEntry(const std::string& label, const char* help, std::string* out) {
  std::string text = help;
  const std::string mark = "%may-differ%";
  std::vector<std::string> lines;
  if (text.find(mark) != std::string::npos) {
    text.replace(text.find(mark), mark.size(), MayDiffer());
    lines = Wrap(text, kHelpWidth - kHelpColumn);
  } else {
    for (size_t at = 0, end = 0; at <= text.size(); at = end + 1) {
      end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      lines.push_back(text.substr(at, end - at));
    }
  }
  std::string head = "  " + label;
  if (head.size() < kHelpColumn)
    head.append(kHelpColumn - head.size(), ' ');
  else
    head += "\n" + std::string(kHelpColumn, ' ');
  for (size_t k = 0; k < lines.size(); ++k)
    *out += (k == 0 ? head : std::string(kHelpColumn, ' ')) + lines[k] + "\n";
}

std::string Label(const OptionSpec& s) {
  return s.arg ? std::string(s.name) + " " + s.arg : std::string(s.name);
}

// A section of --help all: its options' entries, in the table's order.
std::string OptionEntries(HelpSection section) {
  std::string out;
  for (const OptionSpec& s : OptionTable()) {
    if (s.section != section) continue;
    AppendEntry(Label(s), s.help, &out);
    if (s.moreLabel) AppendEntry(s.moreLabel, s.moreHelp, &out);
  }
  return out;
}

// The short --help's list of the options the table marks for it.
std::string CommonOptions() {
  std::vector<std::string> items;
  for (const OptionSpec& s : OptionTable())
    if (s.usage) items.push_back(s.arg ? std::string(s.name) + " " + s.arg : std::string(s.name));
  std::string out = "common options (vismask --help all says what each does):\n";
  for (const std::string& line : Wrap(items, 2, kHelpWidth - 2)) out += "  " + line + "\n";
  return out + "\n";
}

}  // namespace

const char* UsageText() {
  static const std::string text = kUsageHead + CommonOptions() + kUsageExamples;
  return text.c_str();
}

const char* HelpText() {
  static const std::string text = kHelpHead +
                                  ("render options:\n" + OptionEntries(HelpSection::kRender)) +
                                  "\nlocal environments and visibility masks:\n" +
                                  OptionEntries(HelpSection::kEnvironments) + "\n" + kHelpTail;
  return text.c_str();
}

}  // namespace vismask
