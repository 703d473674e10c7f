// proctex shaders list | show NAME: the shader library and each shader's parameter table.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "image/image.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"

namespace proctex::cli {
namespace {

std::string format_default(const ParamDecl& p) {
  const auto j = param_to_json(p, p.default_value.data());
  if (p.type == ParamType::Color)
    return fmt::format("({:.3g}, {:.3g}, {:.3g})", p.default_value[0], p.default_value[1], p.default_value[2]);
  if (j.is_string()) return j.get<std::string>();
  if (p.type == ParamType::Float) return fmt::format("{:.4g}", p.default_value[0]);
  return j.dump();
}

std::string format_range(const ParamDecl& p) {
  if (p.type == ParamType::Bool) return "true|false";
  if (p.type == ParamType::Enum) {
    std::string s;
    for (const auto& v : p.enum_values) s += (s.empty() ? "" : "|") + v;
    return s;
  }
  return fmt::format("[{:.4g}, {:.4g}]", p.min, p.max);
}

// ", period 360/points", ", exchange width/height" or ", needs wave" for a parameter with a
// declared symmetry or dependency (shader.h).
std::string period_text(const ParamDecl& p) {
  std::string text;
  if (p.period > 0.0f) text += fmt::format(", period {:.4g}{}", p.period, p.period_per.empty() ? "" : "/" + p.period_per);
  if (!p.exchange.empty()) text += fmt::format(", exchange {}/{}", p.exchange[0], p.exchange[1]);
  if (!p.needs.empty()) text += ", needs " + p.needs;
  return text;
}

nlohmann::json param_json(const ParamDecl& p) {
  nlohmann::json j = {{"name", p.name}, {"type", to_string(p.type)},
                      {"default", param_to_json(p, p.default_value.data())},
                      {"scale", to_string(p.scale)}, {"searchable", p.searchable}, {"help", p.help}};
  if (p.period > 0.0f) j["period"] = p.period_per.empty() ? nlohmann::json(p.period) : nlohmann::json(fmt::format("{:.4g}/{}", p.period, p.period_per));
  if (!p.exchange.empty()) j["exchange"] = p.exchange;
  if (!p.needs.empty()) j["needs"] = p.needs;
  if (p.type == ParamType::Enum) j["values"] = p.enum_values;
  else if (p.type != ParamType::Bool) j["range"] = {p.min, p.max};
  return j;
}

nlohmann::json shader_json(const ShaderDecl& d, bool with_params) {
  nlohmann::json j = {{"name", d.name}, {"family", d.family}, {"help", d.help}, {"path", d.path},
                      {"source_hash", d.source_hash}, {"parameter_count", d.params.size()}};
  if (with_params) {
    j["params"] = nlohmann::json::array();
    for (const auto& p : d.params) j["params"].push_back(param_json(p));
  }
  return j;
}

void list(bool json, const std::string& family) {
  const auto& lib = ShaderLibrary::builtin();
  nlohmann::json out = nlohmann::json::array();
  std::vector<std::vector<std::string>> rows = {{"name", "family", "params", "description"}};
  for (const auto& d : lib.shaders()) {
    if (!family.empty() && d.family != family) continue;
    out.push_back(shader_json(d, false));
    rows.push_back({d.name, d.family, std::to_string(d.params.size()), d.help});
  }
  if (json) return print_json(out);
  print_table(rows);
  std::printf("\n%zu shaders. 'proctex shaders show NAME' lists a shader's parameters.\n", rows.size() - 1);
}

void show(const std::string& name, bool json) {
  const ShaderDecl& d = ShaderLibrary::builtin().get(name);
  if (json) return print_json(shader_json(d, true));
  std::printf("%s (%s): %s\nsource: %s\n\n", d.name.c_str(), d.family.c_str(), d.help.c_str(), d.path.c_str());
  std::vector<std::vector<std::string>> rows = {{"parameter", "type", "default", "range", "scale", "search", "help"}};
  for (const auto& p : d.params)
    rows.push_back({p.name, to_string(p.type), format_default(p), format_range(p),
                    p.discrete() || p.type == ParamType::Color ? "-" : to_string(p.scale) + period_text(p),
                    p.searchable ? "yes" : "fixed", p.help});
  print_table(rows);
  std::printf("\nexample: proctex render '%s:%s=%s' -o %s.png\n", d.name.c_str(),
              d.params.empty() ? "" : d.params.front().name.c_str(),
              d.params.empty() ? "" : format_default(d.params.front()).c_str(), d.name.c_str());
}

struct SheetOptions {
  std::string output;
  std::string family;
  std::vector<std::string> names;
  int size = 192;
  int columns = 0;
  uint32_t seed = 0;
};

// Renders every selected shader at its defaults, one launch per shader, into a labelled grid.
void sheet(const SheetOptions& o, const GlobalOptions& global) {
  const auto& lib = ShaderLibrary::builtin();
  std::vector<const ShaderDecl*> chosen;
  if (!o.names.empty()) {
    for (const auto& n : o.names) chosen.push_back(&lib.get(n));
  } else {
    for (const auto& d : lib.shaders())
      if (o.family.empty() || d.family == o.family) chosen.push_back(&d);
  }
  if (chosen.empty()) throw UsageError("no shader in family '" + o.family + "'", "run 'proctex shaders list'");
  Renderer renderer(lib);
  RenderSettings settings;
  settings.width = settings.height = o.size;
  std::vector<Image> tiles;
  std::vector<std::string> labels;
  Progress progress("rendering", static_cast<long>(chosen.size()), global.quiet);
  for (const auto* d : chosen) {
    progress.update(static_cast<long>(tiles.size()), d->name);
    tiles.push_back(std::move(renderer.render_batch(*d, {d->default_packed()}, {o.seed}, settings).front()));
    labels.push_back(d->name);
  }
  progress.finish();
  const int columns = o.columns > 0 ? o.columns : static_cast<int>(std::ceil(std::sqrt(double(tiles.size()))));
  save_image(contact_sheet(tiles, labels, columns, o.size), o.output);
  if (!global.quiet) std::printf("%s: %zu shaders at their defaults\n", o.output.c_str(), tiles.size());
}

// The part of docs/shaders.md written by hand: how to write a shader.
constexpr const char* kGalleryHeader = R"MD(# Shader library

Generated by `proctex shaders gallery docs` - do not edit by hand; the format description below is
part of the generator (cli/cmd_shaders.cpp).

## Writing a shader
A shader is one OpenCL C file, `shaders/<family>/<name>.cl` (or any folder on `PROCTEX_SHADER_PATH`),
with its parameters declared in comments the host reads as data:

```c
// @shader "Running-bond brick wall with mortar joints"
// @param int   rows   = 8    [2, 32]              "Brick rows per texture tile"
// @param float mortar = 0.06 [0.01, 0.3] log      "Mortar width, fraction of a brick's height"
// @param color brick  = (0.45, 0.18, 0.12)        "Mean brick colour (linear RGB)"
// @param enum  bond   = running {running, stack}  "Bond pattern"
// @param bool  worn   = false fixed               "Chipped brick edges"
float3 shade(float2 p, float fw, uint seed, const Params P) { ... }
```

- Types: `float`, `int`, `bool`, `color` (linear RGB, range [0, 1] unless given), `enum` (values
  become constants `BOND_RUNNING`, `BOND_STACK`). Flags: `log` (log-scaled search, min > 0),
  `fixed` (never searched), `period=P` or `period=P/COUNT` (a symmetry: the values v and v + P render
  the same image, P divided by the int parameter COUNT when given - the star's
  `rotation ... period=360/points`; the matcher reports the value reduced into [min, min + period)
  and bench_match_eval compares values modulo the period; tests/shaders checks each declared
  period by rendering), `exchange=A/B` (a symmetry across the ends of the range: the value at one
  end renders as the other end with the float parameters A and B exchanged - the rectangle's and
  superellipse's `rotation ... [0, 90] exchange=width/height`; the pixel polish carries a point
  stopped at one end to the other; tests/shaders checks it by rendering), `needs=G` (a dependency:
  this float or int has no effect while the linear float G is at its minimum - the stripes'
  `wave_frequency ... needs=wave`, the grid's `subdivisions` and `minor_width ... needs=minor_strength`;
  the polish of a clean pattern scans two floats jointly, since one at a time neither leaves
  straight stripes, and an answer with G off reports the parameter at its default; tests/shaders
  checks it by rendering). Every parameter needs a one-line help text.
- `p` is the texture coordinate (the image height spans 1 unit, y down), `fw` the pixel footprint
  in texture units (filter with it: `pt_filtered_step`, `pt_coverage`, fractal sums take it),
  `seed` the texture's seed (all randomness must come from the `pt_hash*` functions with it).
- The shared OpenCL library is in `kernels/cl/`: hashing, gradient/value/cellular noise, fBm,
  turbulence, ridged multifractal, domain warping, filtered patterns, tiling, colour helpers.
- Every point of every declared range must render a valid, non-constant image: the test suite
  renders every shader at its defaults, range corners and random points.

## Gallery
Each strip shows the defaults and three random points of the parameter space (seed 1).
)MD";

struct GalleryOptions {
  std::string folder = "docs";
  int size = 128;
  int variants = 3;
};

// docs/shaders.md and docs/gallery/<name>.jpg: a strip per shader and its parameter table.
void gallery(const GalleryOptions& o, const GlobalOptions& global) {
  namespace fs = std::filesystem;
  const auto& lib = ShaderLibrary::builtin();
  const fs::path images = fs::path(o.folder) / "gallery";
  fs::create_directories(images);
  std::string md = kGalleryHeader;
  for (const auto& d : lib.shaders()) md += "[" + d.name + "](#" + d.name + ") ";
  md += "\n";
  Renderer renderer(lib);
  RenderSettings settings;
  settings.width = settings.height = o.size;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Progress progress("gallery", static_cast<long>(lib.shaders().size()), global.quiet);
  long done = 0;
  for (const auto& d : lib.shaders()) {
    progress.update(done++, d.name);
    const ParameterSpace space(d);
    std::vector<std::vector<float>> params = {d.default_packed()};
    std::vector<std::string> labels = {"defaults"};
    for (int v = 0; v < o.variants; ++v) {
      std::vector<double> x(space.dimensions());
      for (auto& c : x) c = unit(rng);
      params.push_back(space.to_packed(x));
      labels.push_back("random " + std::to_string(v + 1));
    }
    const auto tiles = renderer.render_batch(d, params, std::vector<uint32_t>(params.size(), 1), settings);
    save_image(contact_sheet(tiles, labels, static_cast<int>(tiles.size()), o.size), images / (d.name + ".jpg"));
    md += "\n### " + d.name + "\n" + d.help + " (`" + d.path + "`)\n\n![" + d.name + "](gallery/" + d.name + ".jpg)\n\n";
    md += "| parameter | type | default | range | scale | search | help |\n|---|---|---|---|---|---|---|\n";
    for (const auto& p : d.params)
      md += "| " + p.name + " | " + to_string(p.type) + " | " + format_default(p) + " | " + format_range(p) + " | " +
            (p.discrete() || p.type == ParamType::Color ? "-" : to_string(p.scale)) + period_text(p) + " | " +
            (p.searchable ? "yes" : "fixed") + " | " + p.help + " |\n";
  }
  progress.finish();
  const fs::path doc = fs::path(o.folder) / "shaders.md";
  std::ofstream out(doc);
  if (!(out << md)) throw Error("cannot write '" + doc.string() + "'", "check the folder is writable");
  if (!global.quiet) std::printf("%s: %zu shaders, strips in %s\n", doc.c_str(), lib.shaders().size(), images.c_str());
}

}  // namespace

void add_shaders_command(CLI::App& app, GlobalOptions& global) {
  auto* cmd = app.add_subcommand("shaders", "List the shader library or show one shader's parameters");
  cmd->require_subcommand(1);

  struct Options {
    bool json = false;
    std::string family;
    std::string name;
  };
  auto o = std::make_shared<Options>();
  auto* ls = cmd->add_subcommand("list", "List every shader with its family and description");
  ls->add_flag("--json", o->json, "Print JSON");
  ls->add_option("--family", o->family, "Only this family (masonry, stone, pattern, ...)");
  ls->callback([o] { list(o->json, o->family); });

  auto* sh = cmd->add_subcommand("show", "Show a shader's parameters: type, default, range, scale, help");
  sh->add_option("name", o->name, "Shader name (see 'proctex shaders list')")->required();
  sh->add_flag("--json", o->json, "Print JSON");
  sh->callback([o] { show(o->name, o->json); });

  auto so = std::make_shared<SheetOptions>();
  auto* sheet_cmd = cmd->add_subcommand("sheet", "Render shaders at their defaults into one labelled contact sheet");
  sheet_cmd->add_option("names", so->names, "Shaders to include (default: all, or --family)");
  sheet_cmd->add_option("-o,--output", so->output, "Output image (.png, .jpg, .exr)")->required();
  sheet_cmd->add_option("--family", so->family, "Only this family");
  sheet_cmd->add_option("--size", so->size, "Tile size in pixels")->capture_default_str()->check(CLI::Range(16, 2048));
  sheet_cmd->add_option("--columns", so->columns, "Tiles per row (default: a square grid)")->check(CLI::Range(1, 64));
  sheet_cmd->add_option("--seed", so->seed, "Seed for every tile")->capture_default_str();
  sheet_cmd->callback([so, &global] { sheet(*so, global); });

  auto go = std::make_shared<GalleryOptions>();
  auto* gallery_cmd = cmd->add_subcommand("gallery", "Write the shader gallery: FOLDER/shaders.md and FOLDER/gallery/*.jpg");
  gallery_cmd->add_option("folder", go->folder, "Output folder")->capture_default_str();
  gallery_cmd->add_option("--size", go->size, "Tile size in pixels")->capture_default_str()->check(CLI::Range(32, 512));
  gallery_cmd->add_option("--variants", go->variants, "Random parameter settings per shader")->capture_default_str()->check(CLI::Range(0, 8));
  gallery_cmd->callback([go, &global] { gallery(*go, global); });
}

}  // namespace proctex::cli
