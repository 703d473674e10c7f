// proctex rgbn stereo / mip / ptm: acquisition from lit photos, normal-map filtering for display,
// polynomial texture maps.
#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "cli/cmd_rgbn.h"
#include "cli/output.h"
#include "core/error.h"
#include "rgbn/acquire.h"
#include "rgbn/mip.h"
#include "rgbn/synth.h"
#include "rgbn/view.h"
#include "synth/analysis.h"

namespace proctex::cli::rgbn_cli {
namespace {
namespace fs = std::filesystem;
using namespace proctex::rgbn;
using nlohmann::json;

struct LitOptions {
  std::vector<std::string> images, lights;
  std::string lights_file, output, preview, light = "90,60";
  bool robust = false, json = false;
  float shadow = 0.1f, specular = 0.15f;
  int width = 0, height = 0, patch = 32;
  uint64_t seed = 1;
};

void run_stereo(const LitOptions& o, const GlobalOptions& g) {
  std::vector<Image> photos;
  std::vector<Vec3> dirs;
  load_lit_photos(o.images, o.lights, o.lights_file, photos, dirs, 3);
  StereoOptions so;
  so.robust = o.robust, so.shadow = o.shadow, so.specular = o.specular;
  StereoReport rep;
  const Rgbn out = photometric_stereo(photos, dirs, so, &rep);
  save_output(out, o.output, o.preview);
  const json j = {{"output", o.output}, {"photos", photos.size()}, {"robust", o.robust},
                  {"rms_residual", rep.mean_residual}, {"samples_dropped", rep.samples_dropped},
                  {"light_condition", rep.condition}, {"integrability", integrability_error(out)}};
  if (o.json) print_json(j);
  else if (!g.quiet)
    std::printf("%s: %dx%d from %zu photos (rms residual %.4g, %.1f%% samples ignored)\n", o.output.c_str(), out.width,
                out.height, photos.size(), rep.mean_residual, 100 * rep.samples_dropped);
}

void run_ptm_fit(const LitOptions& o, const GlobalOptions& g) {
  std::vector<Image> photos;
  std::vector<Vec3> dirs;
  load_lit_photos(o.images, o.lights, o.lights_file, photos, dirs, 6);
  PtmReport rep;
  const Ptm ptm = fit_ptm(photos, dirs, &rep);
  save_ptm(ptm, o.output);
  if (o.json) print_json({{"output", o.output}, {"photos", photos.size()}, {"rms_residual", rep.rms_residual}, {"condition", rep.condition}});
  else if (!g.quiet) std::printf("%s: PTM %dx%d from %zu photos (rms residual %.4g)\n", o.output.c_str(), ptm.width, ptm.height, photos.size(), rep.rms_residual);
}

void run_ptm_render(const LitOptions& o, const GlobalOptions&) {
  if (o.images.size() != 1) throw UsageError("give one PTM file", "proctex rgbn ptm render wall.ptm.exr --light 135,45 -o lit.png");
  const Ptm ptm = load_ptm(o.images[0]);
  Image img = render_ptm(ptm, parse_light(o.light));
  for (float& v : img.pixels) v = std::max(0.0f, v);
  save_image(img, o.output);
}

void run_ptm_synth(const LitOptions& o, const GlobalOptions& g) {
  if (o.images.size() != 1) throw UsageError("give one example PTM file", "proctex rgbn ptm synth ex.ptm.exr --size 512,512 -o big.ptm.exr");
  const Ptm ex = load_ptm(o.images[0]);
  const auto start = std::chrono::steady_clock::now();
  const Ptm out = synthesize_ptm(ex, o.width, o.height, o.patch, o.seed);
  save_ptm(out, o.output);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (o.json) print_json({{"output", o.output}, {"width", o.width}, {"height", o.height}, {"patch", o.patch}, {"seed", o.seed}, {"seconds", s}});
  else if (!g.quiet) std::printf("%s: %dx%d PTM (seed %llu) in %s\n", o.output.c_str(), o.width, o.height, (unsigned long long)o.seed, format_seconds(s).c_str());
}

struct MipCliOptions {
  std::string input, output_dir, light = "120,55";
  std::vector<std::string> methods = {"naive", "toksvig", "vmf", "sh"};
  std::vector<int> footprints = {2, 4, 8, 16};
  std::vector<float> exponents = {8, 32, 128};
  int lobes = MipOptions{}.lobes, sh_order = 6;
  float shade_exponent = 64;
  bool json = false, errors = true;
};

void run_mip(const MipCliOptions& o, const GlobalOptions& g) {
  const Rgbn fine = load_input(o.input);
  std::vector<MipMethod> methods;
  for (const auto& m : o.methods) methods.push_back(parse_mip_method(m));
  fs::create_directories(o.output_dir);
  MipOptions mo;
  mo.lobes = o.lobes, mo.sh_order = o.sh_order;
  if (o.lobes < 1 || o.lobes > 16) throw UsageError("--lobes must be in [1, 16]", "e.g. --lobes 6");
  if (o.sh_order < 0 || o.sh_order > 16) throw UsageError("--sh-order must be in [0, 16]", "e.g. --sh-order 6");
  const Vec3 l = parse_light(o.light);
  Vec3 h = {l[0], l[1], l[2] + 1};
  const float hl = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  for (float& c : h) c /= hl;
  json j = {{"input", o.input}, {"levels", json::array()}};
  std::vector<std::vector<std::string>> rows = {{"footprint", "exponent"}};
  for (auto m : methods) rows[0].push_back(mip_method_name(m));
  Progress progress("mip", long(o.footprints.size()), g.quiet);
  long done = 0;
  for (int f : o.footprints) {
    const bool vmf = std::find(methods.begin(), methods.end(), MipMethod::Vmf) != methods.end();
    const bool sh = std::find(methods.begin(), methods.end(), MipMethod::Sh) != methods.end();
    const MipLevel L = build_level(fine, f, mo, vmf, sh);
    json lj = {{"footprint", f}, {"width", L.width}, {"height", L.height}, {"files", json::object()}, {"error", json::object()}};
    for (auto m : methods) {
      const std::string name = mip_method_name(m);
      const fs::path file = fs::path(o.output_dir) / fmt::format("{}_f{}.exr", name, f);
      save_level(L, m, file);
      lj["files"][name] = file.string();
      // Specular highlight of the level under --light, and the supersampled truth.
      Image img(L.width, L.height), truth(L.width, L.height);
      for (int y = 0; y < L.height; ++y)
        for (int x = 0; x < L.width; ++x) {
          const float v = mip_specular(L, size_t(y) * L.width + x, m, h, o.shade_exponent);
          std::fill(img.pixel(x, y), img.pixel(x, y) + 3, std::max(0.0f, v));
          const float t = truth_specular(fine, f, x, y, h, o.shade_exponent);
          std::fill(truth.pixel(x, y), truth.pixel(x, y) + 3, t);
        }
      save_image(img, fs::path(o.output_dir) / fmt::format("{}_f{}_spec.png", name, f));
      if (m == methods.front()) save_image(truth, fs::path(o.output_dir) / fmt::format("truth_f{}_spec.png", f));
    }
    if (o.errors)
      for (float s : o.exponents) {
        std::vector<std::string> row = {std::to_string(f), fmt::format("{}", s)};
        for (auto m : methods) {
          const double e = mip_error(fine, L, m, s);
          lj["error"][mip_method_name(m)][fmt::format("{}", s)] = e;
          row.push_back(fmt::format("{:.4f}", e));
        }
        rows.push_back(row);
      }
    j["levels"].push_back(lj);
    progress.update(++done);
  }
  progress.finish();
  if (o.json) print_json(j);
  else if (!g.quiet) {
    std::printf("levels in %s; relative L2 error of the Blinn-Phong highlight against the supersampled truth:\n",
                o.output_dir.c_str());
    print_table(rows);
  }
}

struct SynthCliOptions {
  std::string example, output, fill, mask, order = "hilbert", preview, method = "synth";
  int width = 256, height = 256, neighbourhood = 5, windows = 16, passes = 2;
  double jump = 0.05, xi = -1;
  float normal_weight = 1.0f, coherence = 2.0f;
  std::vector<float> randomness;
  uint64_t seed = 1;
  bool compose = false, no_compose = false, json = false, no_cache = false;
};

fs::path synth_cache_dir() { return proctex::synth::default_cache_dir(); }

void run_synth(const SynthCliOptions& o, const GlobalOptions& g) {
  if (o.method != "jump" && o.method != "synth")
    throw UsageError("unknown synthesis method '" + o.method + "'", "use --method synth (Lefebvre-Hoppe) or jump (jump maps)");
  if (o.xi != -1 && !(o.xi >= 0 && o.xi < 90)) throw UsageError("--xi must be in [0, 90) degrees", "e.g. --xi 10");
  if (o.fill.empty() && (o.compose || o.no_compose))
    throw UsageError("--compose and --no-compose apply to --fill", "drop them or give --fill");
  if (o.compose && o.no_compose) throw UsageError("--compose and --no-compose exclude each other", "give one");
  // A fill composes the example's detail on the region's base normals unless told not to.
  const bool compose = !o.fill.empty() && !o.no_compose;
  if (!o.fill.empty() && o.mask.empty())
    throw UsageError("--fill needs --mask (white = fill)", "e.g. --fill wall.exr --mask hole.png");
  const Rgbn ex = load_input(o.example);
  Rgbn target;
  Mask mask;
  if (!o.fill.empty()) {
    target = load_input(o.fill);
    mask = image_mask(load_image(o.mask), target.width, target.height);
  }
  const auto start = std::chrono::steady_clock::now();
  json j = {{"output", o.output}, {"seed", o.seed}, {"method", o.method}, {"compose", compose}};
  if (o.xi >= 0) j["xi"] = o.xi;
  Rgbn image;
  size_t visited = 0;
  std::string detail;
  if (o.method == "synth") {
    ExemplarSynthOptions so;
    so.seed = o.seed, so.normal_weight = o.normal_weight, so.randomness = o.randomness, so.passes = o.passes;
    so.coherence = o.coherence, so.compose = o.compose, so.xi = o.xi, so.windows = o.windows;
    so.compose = compose;
    if (!o.no_cache) so.cache_dir = synth_cache_dir();
    Progress progress(o.fill.empty() ? "synthesising" : "trying windows", 100, g.quiet || o.json);
    so.progress = [&](double f) { progress.update(long(f * 100)); };
    ExemplarSynthResult r = o.fill.empty() ? exemplar_synthesize(ex, o.width, o.height, so)
                                           : exemplar_fill(ex, target, mask, so);
    progress.finish();
    image = std::move(r.image);
    visited = r.visited;
    j.update({{"normal_weight", o.normal_weight}, {"passes", o.passes}, {"coherence", o.coherence},
              {"levels", r.levels}, {"example_tiles", r.example_tiles}, {"analysis_cached", r.analysis_cached},
              {"analysis_seconds", r.analysis_seconds}, {"window", {r.window_x, r.window_y}}});
    if (!o.randomness.empty()) j["randomness"] = o.randomness;
    if (!o.fill.empty()) j.update({{"windows", o.windows}, {"ring_error", r.ring_error}});
    detail = fmt::format("Lefebvre-Hoppe, window at ({}, {})", r.window_x, r.window_y);
  } else {
    JumpMapOptions jo;
    jo.neighbourhood = o.neighbourhood, jo.seed = o.seed;
    const JumpMap map = build_jump_map(ex, jo);
    const double analysis = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    JumpSynthOptions so;
    so.order = parse_order(o.order), so.jump_probability = o.jump, so.seed = o.seed, so.compose = compose;
    so.xi = o.xi;
    JumpSynthResult r = o.fill.empty() ? jump_synthesize(ex, map, o.width, o.height, so)
                                       : jump_fill(ex, map, target, mask, so);
    image = std::move(r.image);
    visited = r.visited;
    j.update({{"order", o.order}, {"jump_probability", o.jump}, {"mean_run", r.mean_run},
              {"pca_dimensions", map.dimensions}, {"analysis_seconds", analysis}});
    detail = fmt::format("jump maps, mean run {:.1f}", r.mean_run);
  }
  save_output(image, o.output, o.preview);
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  j.update({{"width", image.width}, {"height", image.height}, {"pixels", visited}, {"seconds", total}});
  if (o.json) print_json(j);
  else if (!g.quiet)
    std::printf("%s: %dx%d, %zu pixels synthesised (%s, seed %llu) in %s\n", o.output.c_str(), image.width,
                image.height, visited, detail.c_str(), (unsigned long long)o.seed, format_seconds(total).c_str());
}

void lit_flags(CLI::App* cmd, LitOptions& o) {
  cmd->add_option("photos", o.images, "Photos (linear after sRGB decoding), one --light each, in order");
  cmd->add_option("--light", o.lights, "Light direction per photo: azimuth,elevation (degrees) or x,y,z")
      ->expected(1)
      ->allow_extra_args(false)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--lights", o.lights_file, "JSON list [{\"image\":..., \"light\":[x,y,z] or \"az,el\"}, ...]");
  cmd->add_option("-o,--output", o.output, "Output file")->required();
  cmd->add_flag("--json", o.json, "Print a JSON report");
}

}  // namespace

void add_display_commands(CLI::App& rgbn, GlobalOptions& global) {
  {
    auto o = std::make_shared<LitOptions>();
    auto* cmd = rgbn.add_subcommand("stereo", "Photometric stereo: an RGBN from 3+ photos under known light directions");
    cmd->footer("  proctex rgbn stereo a.png b.png c.png d.png --light 0,45 --light 90,45 --light 180,45 --light 270,45 -o s.exr\n"
                "--robust ignores shadowed samples (darker than --shadow x the brightest) and highlights\n"
                "(brighter than the Lambert fit by --specular x albedo).");
    lit_flags(cmd, *o);
    cmd->add_flag("--robust", o->robust, "Ignore shadowed and specular samples");
    cmd->add_option("--shadow", o->shadow, "Shadow threshold (fraction of the brightest sample)")->capture_default_str();
    cmd->add_option("--specular", o->specular, "Highlight threshold (fraction of the albedo)")->capture_default_str();
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->callback([o, &global] { run_stereo(*o, global); });
  }
  {
    auto* ptm = rgbn.add_subcommand("ptm", "Polynomial texture maps (relightable textures): fit, render, synth");
    ptm->require_subcommand(1);
    auto fit = std::make_shared<LitOptions>();
    auto* cf = ptm->add_subcommand("fit", "Fit a PTM (6 coefficients per pixel and channel) to 6+ photos under known lights");
    lit_flags(cf, *fit);
    cf->callback([fit, &global] { run_ptm_fit(*fit, global); });
    auto ren = std::make_shared<LitOptions>();
    auto* cr = ptm->add_subcommand("render", "Render a PTM under a light");
    cr->add_option("ptm", ren->images, "PTM file (.exr)")->required();
    cr->add_option("-o,--output", ren->output, "Output image")->required();
    cr->add_option("--light", ren->light, "azimuth,elevation or x,y,z")->capture_default_str();
    cr->callback([ren, &global] { run_ptm_render(*ren, global); });
    auto syn = std::make_shared<LitOptions>();
    auto* cs = ptm->add_subcommand("synth", "Synthesise a larger PTM that looks like the example under every light");
    cs->footer("Patches are chosen by their overlap distance in the orthonormal Legendre basis (coefficient distance =\n"
               "reflectance-function distance) and alpha-blended; the same --seed gives the same PTM.");
    cs->add_option("ptm", syn->images, "Example PTM (.exr)")->required();
    cs->add_option("-o,--output", syn->output, "Output PTM (.exr)")->required();
    cs->add_option("--width", syn->width, "Output width")->required()->check(CLI::Range(8, 16384));
    cs->add_option("--height", syn->height, "Output height")->required()->check(CLI::Range(8, 16384));
    cs->add_option("--patch", syn->patch, "Patch size in pixels")->capture_default_str();
    cs->add_option("--seed", syn->seed, "Seed")->capture_default_str();
    cs->add_flag("--json", syn->json, "Print a JSON report");
    cs->callback([syn, &global] { run_ptm_synth(*syn, global); });
  }
  {
    auto o = std::make_shared<SynthCliOptions>();
    auto* cmd = rgbn.add_subcommand("synth", "Grow an RGBN or fill a region from an example (Lefebvre-Hoppe or jump maps)");
    cmd->footer("  proctex rgbn synth leather.exr --width 512 --height 512 -o big.exr\n"
                "  proctex rgbn synth leather.exr --fill wall.exr --mask hole.png -o patched.exr\n"
                "  proctex rgbn synth leather.exr --method jump --order dfs --jump 0.05 --width 512 --height 512 -o big.exr\n"
                "--method synth (default) runs proctex synth's synthesiser (Lefebvre-Hoppe, the same options) on the\n"
                "albedo and the normals together (example 16..512 px a side); a fill tries --windows candidate windows\n"
                "and keeps the one that best matches the pixels around the region. --method jump walks the output in\n"
                "Hilbert or shuffled-DFS order continuing runs of the example (Zelinka-Garland, as Pereira & Velho).\n"
                "Every synthesised pixel takes an example pixel's colour and normal together; a fill re-expresses\n"
                "the example's normals as detail on its smoothed normals and composes it on the target's smoothed\n"
                "(base) normals (--no-compose: copy them). The same --seed gives the same result.");
    cmd->add_option("example", o->example, "Example RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output RGBN (.exr)")->required();
    cmd->add_option("--method", o->method, "synth (Lefebvre-Hoppe, via synth/) or jump (jump maps)")->capture_default_str();
    cmd->add_option("--width", o->width, "Output width (grow)")->capture_default_str()->check(CLI::Range(1, 16384));
    cmd->add_option("--height", o->height, "Output height (grow)")->capture_default_str()->check(CLI::Range(1, 16384));
    cmd->add_option("--fill", o->fill, "Fill a region of this RGBN instead of growing");
    cmd->add_option("--mask", o->mask, "Region to fill (white)");
    cmd->add_flag("--compose", o->compose, "Fill: compose the example's detail on the target's base normals (the default)");
    cmd->add_flag("--no-compose", o->no_compose, "Fill: copy the example's normals as they are");
    cmd->add_option("--xi", o->xi, "Keep synthesised normals at n_z >= sin(xi) (degrees)");
    cmd->add_option("--normal-weight", o->normal_weight, "synth: weight of the normals against the colour in matching")
        ->capture_default_str();
    cmd->add_option("--randomness", o->randomness, "synth: jitter per level, coarse to fine (default: proctex synth's)")
        ->delimiter(',');
    cmd->add_option("--passes", o->passes, "synth: correction passes per level")->capture_default_str();
    cmd->add_option("--coherence", o->coherence, "synth: preference for growing patches")->capture_default_str();
    cmd->add_option("--windows", o->windows, "synth --fill: candidate windows tried")->capture_default_str();
    cmd->add_flag("--no-cache", o->no_cache, "synth: do not read or write the analysis cache");
    cmd->add_option("--order", o->order, "jump: hilbert or dfs (shuffled depth-first, for arbitrary regions)")->capture_default_str();
    cmd->add_option("--jump", o->jump, "jump: jump probability per pixel (mean run ~ 1/p)")->capture_default_str();
    cmd->add_option("--neighbourhood", o->neighbourhood, "jump: analysis neighbourhood M (odd)")->capture_default_str();
    cmd->add_option("--seed", o->seed, "Seed (synth uses its low 32 bits)")->capture_default_str();
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_synth(*o, global); });
  }
  {
    auto o = std::make_shared<MipCliOptions>();
    auto* cmd = rgbn.add_subcommand("mip", "Normal-map MIP levels for display: naive, Toksvig, vMF mixture, SH (+ truth)");
    cmd->footer(
        "Writes DIR/<method>_f<F>.exr (naive/toksvig: N.X,N.Y,N.Z - Toksvig keeps the unnormalised mean; vmf:\n"
        "lobeJ.{A,X,Y,Z,K}; sh: sh.K) and the specular highlight of each level under --light next to the\n"
        "supersampled truth (truth_f<F>_spec.png), and prints the relative L2 error of Blinn-Phong shading against\n"
        "the truth over 64 half vectors per texel.");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output_dir, "Output folder")->required();
    cmd->add_option("--methods", o->methods, "naive, toksvig, vmf, sh")->delimiter(',');
    cmd->add_option("--footprints", o->footprints, "Footprint sizes in texels")->delimiter(',');
    cmd->add_option("--exponents", o->exponents, "Blinn-Phong exponents for the error table")->delimiter(',');
    cmd->add_option("--lobes", o->lobes, "vMF lobes per texel")->capture_default_str();
    cmd->add_option("--sh-order", o->sh_order, "Spherical-harmonics order")->capture_default_str();
    cmd->add_option("--light", o->light, "Light of the highlight pictures (azimuth,elevation)")->capture_default_str();
    cmd->add_option("--shade-exponent", o->shade_exponent, "Exponent of the highlight pictures")->capture_default_str();
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_mip(*o, global); });
  }
}

}  // namespace proctex::cli::rgbn_cli
