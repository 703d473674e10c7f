// proctex render SPEC -o out.png: renders a texture spec at any size.
#include <chrono>
#include <filesystem>

#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "image/image.h"
#include "kernels/runtime.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"

namespace proctex::cli {
namespace {

struct RenderOptions {
  std::string spec;
  std::string output;
  int size = 1024;
  int width = 0;
  int height = 0;
  int supersample = 1;
  int64_t seed = -1;
  float extent = 1.0f;
  std::string spec_out;
  bool json = false;
};

void run(const RenderOptions& o, const GlobalOptions& global) {
  TextureSpec spec = parse_spec_argument(o.spec);
  if (o.seed >= 0) spec.seed = static_cast<uint32_t>(o.seed);
  RenderSettings settings;
  settings.width = o.width > 0 ? o.width : o.size;
  settings.height = o.height > 0 ? o.height : o.size;
  settings.supersample = o.supersample;
  settings.extent = o.extent;

  Renderer renderer;
  const ShaderDecl& decl = renderer.library().get(spec.shader);
  const TextureSpec full = spec_from_packed(decl, resolve(decl, spec), spec.seed);
  Progress progress("rendering " + decl.name, 100, global.quiet);
  settings.on_progress = [&](double done) { progress.update(static_cast<long>(done * 100)); };
  const auto start = std::chrono::steady_clock::now();
  const Image image = renderer.render(spec, settings);
  progress.finish();
  const double render_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  save_image(image, o.output);
  if (!o.spec_out.empty()) write_text_file(o.spec_out, full.to_json().dump(2) + "\n");

  if (o.json) {
    print_json({{"output", o.output}, {"width", settings.width}, {"height", settings.height},
                {"supersample", settings.supersample}, {"spec", full.to_json()}, {"seconds", render_s},
                {"device", ocl::Runtime::instance().device().name}});
  } else if (!global.quiet) {
    std::printf("%s: %s %dx%d seed %u in %s\n", o.output.c_str(), decl.name.c_str(), settings.width,
                settings.height, spec.seed, format_seconds(render_s).c_str());
  }
}

}  // namespace

void add_render_command(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<RenderOptions>();
  auto* cmd = app.add_subcommand("render", "Render a texture spec to an image at any size");
  cmd->footer(
      "SPEC is a JSON spec file, a shader name, or inline NAME:key=value,...\n"
      "  proctex render bricks -o bricks.png\n"
      "  proctex render 'checker:squares=4,color_a=#a0522d,seed=3' -o c.png --size 4096\n"
      "  proctex render match.json -o big.exr --size 8192 --supersample 2\n"
      "Colours: (r,g,b) linear in [0,1] or #rrggbb (sRGB). PNG/JPEG/TIFF are written sRGB, EXR linear.");
  cmd->add_option("spec", o->spec, "Texture spec: file.json, NAME, or NAME:key=value,...")->required();
  cmd->add_option("-o,--output", o->output, "Output image (.png, .jpg, .tif, .exr)")->required();
  cmd->add_option("--size", o->size, "Width and height in pixels")->capture_default_str()->check(CLI::Range(1, 65536));
  cmd->add_option("--width", o->width, "Width (overrides --size)")->check(CLI::Range(1, 65536));
  cmd->add_option("--height", o->height, "Height (overrides --size)")->check(CLI::Range(1, 65536));
  cmd->add_option("--supersample", o->supersample, "Samples per pixel along each axis, for final renders")
      ->capture_default_str()->check(CLI::Range(1, 16));
  cmd->add_option("--seed", o->seed, "Seed (overrides the spec's seed)")->check(CLI::Range(int64_t(0), int64_t(0xffffffff)));
  cmd->add_option("--extent", o->extent, "Texture units across the image height (2 = zoom out to twice the area)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--spec-out", o->spec_out, "Also write the full spec (every parameter and the seed) as JSON");
  cmd->add_flag("--json", o->json, "Print what was rendered as JSON");
  cmd->callback([o, &global] { run(*o, global); });
}

}  // namespace proctex::cli
