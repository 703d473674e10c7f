// proctex rgbn: images with a colour and a normal per pixel (Pereira & Velho, "Editing RGBNs").
//   import / export / height      conversions (normal maps in GL or DX convention, height maps)
//   light / view                  shaded renders and the paper's views
//   filter / curvature / segment  filters on the slope field, K and H, Felzenszwalb-Huttenlocher
//   stamp / pen / edit            local edits as replayable JSON operations (cmd_rgbn_edit.cpp)
//   stereo / mip / ptm / synth    acquisition, display filtering, relightable textures, synthesis
#include "cli/cmd_rgbn.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "cli/output.h"
#include "core/error.h"
#include "rgbn/analysis.h"
#include "rgbn/filter.h"
#include "rgbn/view.h"

namespace proctex::cli {
namespace rgbn_cli {
namespace fs = std::filesystem;
using namespace proctex::rgbn;

Rgbn load_input(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".exr")
    throw UsageError("'" + path + "' is not an RGBN file", "RGBNs are EXR files; convert a normal map with 'proctex rgbn import'");
  return load_rgbn(path);
}

void save_output(const Rgbn& image, const std::string& path, const std::string& preview) {
  save_rgbn(image, path);
  if (!preview.empty()) {
    ShadeOptions so;
    save_image(shade(image, so), preview);
  }
}

void load_lit_photos(const std::vector<std::string>& images, const std::vector<std::string>& lights,
                     const std::string& lights_file, std::vector<Image>& photos, std::vector<Vec3>& dirs,
                     size_t min_photos) {
  std::vector<std::string> files;
  if (!lights_file.empty()) {
    std::ifstream in(lights_file);
    if (!in) throw Error("cannot read '" + lights_file + "'", "check the path");
    nlohmann::json j;
    try {
      in >> j;
    } catch (const std::exception& e) {
      throw Error("'" + lights_file + "' is not valid JSON: " + e.what(), "write [{\"image\":\"a.png\",\"light\":[0.3,0.2,0.93]}, ...]");
    }
    if (!j.is_array()) throw Error("'" + lights_file + "' must hold a JSON array", "write [{\"image\":\"a.png\",\"light\":\"135,45\"}, ...]");
    const fs::path base = fs::path(lights_file).parent_path();
    for (const auto& e : j) {
      if (!e.is_object() || !e.contains("image") || !e.contains("light") || !e["image"].is_string())
        throw Error("each entry of '" + lights_file + "' needs \"image\" and \"light\"", "e.g. {\"image\":\"a.png\",\"light\":[0.3,0.2,0.93]}");
      fs::path p = e["image"].get<std::string>();
      if (p.is_relative()) p = base / p;
      files.push_back(p.string());
      if (e["light"].is_string()) {
        dirs.push_back(parse_light(e["light"].get<std::string>()));
      } else if (e["light"].is_array() && e["light"].size() == 3) {
        std::string s;
        for (const auto& v : e["light"]) {
          if (!v.is_number()) throw Error("a light must be 3 numbers or \"az,el\"", "e.g. [0.3,0.2,0.93]");
          s += (s.empty() ? "" : ",") + fmt::format("{}", v.get<double>());
        }
        dirs.push_back(parse_light(s));
      } else {
        throw Error("a light must be [x,y,z] or \"az,el\"", "e.g. [0.3,0.2,0.93] or \"135,45\"");
      }
    }
    if (!images.empty()) throw UsageError("give photos either in --lights or on the command line, not both", "drop one");
  } else {
    files = images;
    if (images.size() < min_photos)
      throw UsageError("this needs at least " + std::to_string(min_photos) + " photos under different lights, got " +
                           std::to_string(images.size()),
                       "add photos lit from other directions");
    if (lights.size() != images.size())
      throw UsageError(std::to_string(images.size()) + " photos but " + std::to_string(lights.size()) + " --light options",
                       "give one --light az,el (or x,y,z) per photo, in order, or a --lights file");
    for (const auto& l : lights) dirs.push_back(parse_light(l));
  }
  for (const auto& f : files) photos.push_back(load_image(f));
}

}  // namespace rgbn_cli

namespace {
using namespace proctex::rgbn;
using namespace rgbn_cli;

void print_or_json(bool json, const nlohmann::json& j, const std::string& text, bool quiet) {
  if (json) print_json(j);
  else if (!quiet && !text.empty()) std::printf("%s\n", text.c_str());
}

// --- import ------------------------------------------------------------------------------------
struct ImportOptions {
  std::string input, output, albedo, convention = "gl", height, preview;
  float scale = 1.0f;
  bool tile = false, json = false;
};

void run_import(const ImportOptions& o, const GlobalOptions& g) {
  Rgbn out;
  std::string source;
  if (!o.height.empty()) {
    const Image h = load_image(o.height);
    out = from_height(height_from_image(h), o.scale, o.tile);
    source = "height " + o.height;
  } else {
    if (o.input.empty()) throw UsageError("give a normal map, or --height FILE", "see 'proctex rgbn import --help'");
    out = load_normal_map(o.input, parse_convention(o.convention));
    source = "normal map " + o.input + " (" + convention_name(parse_convention(o.convention)) + ")";
  }
  if (!o.albedo.empty()) set_albedo(out, load_image(o.albedo));
  save_output(out, o.output, o.preview);
  print_or_json(o.json,
                {{"output", o.output}, {"width", out.width}, {"height", out.height}, {"source", source},
                 {"integrability", integrability_error(out)}},
                fmt::format("{}: {}x{} RGBN from {}", o.output, out.width, out.height, source), g.quiet);
}

// --- export ------------------------------------------------------------------------------------
struct ExportOptions {
  std::string input, output, convention = "gl", albedo;
  int bits = 8;
  bool json = false;
};

void run_export(const ExportOptions& o, const GlobalOptions& g) {
  const Convention c = parse_convention(o.convention);
  const Rgbn in = load_input(o.input);
  save_normal_map(in, o.output, c, o.bits);
  if (!o.albedo.empty()) save_image(albedo_image(in), o.albedo);
  print_or_json(o.json, {{"output", o.output}, {"convention", convention_name(c)}, {"bits", o.bits}},
                fmt::format("{}: {} normal map ({})", o.output, convention_name(c) == "gl" ? "OpenGL" : "DirectX",
                            fs::path(o.output).extension() == ".exr" ? "float" : std::to_string(o.bits) + "-bit"),
                g.quiet);
}

// --- height ------------------------------------------------------------------------------------
struct HeightOptions {
  std::string input, output;
  bool periodic = false, json = false;
};

void run_height(const HeightOptions& o, const GlobalOptions& g) {
  const Rgbn in = load_input(o.input);
  const Integration r = to_height(in, o.periodic);
  std::string ext = fs::path(o.output).extension().string();
  Image img(r.z.width, r.z.height);
  const auto [lo, hi] = std::minmax_element(r.z.z.begin(), r.z.z.end());
  const bool normalise = ext != ".exr";
  for (size_t i = 0; i < r.z.z.size(); ++i) {
    const float v = normalise ? (r.z.z[i] - *lo) / std::max(*hi - *lo, 1e-12f) : r.z.z[i];
    img.pixels[3 * i] = img.pixels[3 * i + 1] = img.pixels[3 * i + 2] = normalise ? srgb_to_linear(v) : v;
  }
  save_image(img, o.output);
  print_or_json(o.json,
                {{"output", o.output}, {"periodic", o.periodic}, {"integrability", r.integrability},
                 {"slope_residual", r.residual}, {"min", *lo}, {"max", *hi}},
                fmt::format("{}: height range {:.3f} px (integrability error {:.4g}, slope residual {:.4g}){}", o.output,
                            *hi - *lo, r.integrability, r.residual, normalise ? ", written scaled to [0,1]" : ""),
                g.quiet);
}

// --- light / view ------------------------------------------------------------------------------
struct LightOptions {
  std::string input, output, light = "135,45", model = "lambert";
  float ambient = 0.05f, specular = 0.3f, exponent = 32.0f, intensity = 1.0f;
  bool grey = false;
};

ShadeOptions shade_options(const LightOptions& o) {
  ShadeOptions so;
  so.light = parse_light(o.light);
  if (o.model == "lambert") so.model = Shading::Lambert;
  else if (o.model == "blinn" || o.model == "blinn-phong") so.model = Shading::BlinnPhong;
  else throw UsageError("unknown shading model '" + o.model + "'", "use lambert or blinn");
  so.ambient = o.ambient, so.specular = o.specular, so.exponent = o.exponent, so.intensity = o.intensity;
  so.use_albedo = !o.grey;
  return so;
}

void run_light(const LightOptions& o, const GlobalOptions&) {
  const Rgbn in = load_input(o.input);
  save_image(shade(in, shade_options(o)), o.output);
}

struct ViewOptions {
  LightOptions light;
  std::string view = "shaded";
  int spacing = 12;
  float range = 0;
  float base_sigma = 3;
};

void run_view(const ViewOptions& o, const GlobalOptions&) {
  const Rgbn in = load_input(o.light.input);
  Image out;
  if (o.view == "shaded") out = shade(in, shade_options(o.light));
  else if (o.view == "shaded-normals") {
    ShadeOptions so = shade_options(o.light);
    so.use_albedo = false;
    out = shade(in, so);
  } else if (o.view == "albedo") out = view_albedo(in);
  else if (o.view == "normals") out = view_normals(in);
  else if (o.view == "base") {
    // The paper's base normals: the bilateral-smoothed copy that stamps and pens may compose on
    // (edit op "base_sigma"), colour-coded like `normals`.
    BilateralOptions bo;
    bo.sigma_s = o.base_sigma, bo.sigma_n = 0.5f, bo.albedo = false;
    out = view_normals(bilateral(in, bo));
  }
  else if (o.view == "needles") out = view_needles(in, o.spacing);
  else if (o.view == "mean" || o.view == "gaussian") {
    const Curvature c = curvature(in);
    out = view_signed(o.view == "mean" ? c.H : c.K, in.width, in.height, o.range);
  } else if (o.view == "segments") {
    out = view_labels(segment(in, {}).labels, in.width, in.height);
  } else {
    throw UsageError("unknown view '" + o.view + "'",
                     "use shaded, shaded-normals, albedo, normals, base, needles, mean, gaussian or segments");
  }
  save_image(out, o.light.output);
}

// --- filter ------------------------------------------------------------------------------------
struct FilterCliOptions {
  std::string input, output, kind = "smooth", mask, preview;
  float sigma = 2, sigma2 = 6, amount = 1, sigma_c = 0.1f, sigma_n = 0.2f;
  std::vector<float> brush;
  bool wrap = false, albedo = false, json = false;
};

void run_filter(const FilterCliOptions& o, const GlobalOptions& g) {
  const Rgbn in = load_input(o.input);
  Mask m;
  const Mask* mp = nullptr;
  if (!o.brush.empty()) {
    if (o.brush.size() < 3) throw UsageError("--brush needs x,y,radius[,feather]", "e.g. --brush 200,150,40,10");
    m = disc_mask(in.width, in.height, o.brush[0], o.brush[1], o.brush[2], o.brush.size() > 3 ? o.brush[3] : 0.0f);
    mp = &m;
  } else if (!o.mask.empty()) {
    m = image_mask(load_image(o.mask), in.width, in.height);
    mp = &m;
  }
  const auto start = std::chrono::steady_clock::now();
  Rgbn out;
  if (o.kind == "bilateral") {
    BilateralOptions bo;
    bo.sigma_s = o.sigma, bo.sigma_c = o.sigma_c, bo.sigma_n = o.sigma_n;
    out = bilateral(in, bo, mp);
  } else {
    FilterOptions fo;
    fo.kind = parse_filter_kind(o.kind);
    fo.sigma = o.sigma, fo.sigma2 = o.sigma2, fo.amount = o.amount, fo.wrap = o.wrap, fo.albedo = o.albedo;
    out = filter(in, fo, mp);
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  save_output(out, o.output, o.preview);
  const double before = integrability_error(in, mp), after = integrability_error(out, mp);
  print_or_json(o.json,
                {{"output", o.output}, {"filter", o.kind}, {"seconds", secs}, {"integrability_before", before},
                 {"integrability_after", after}},
                fmt::format("{}: {} in {} (integrability {:.4g} -> {:.4g})", o.output, o.kind, format_seconds(secs), before,
                            after),
                g.quiet);
}

// --- curvature / segment -----------------------------------------------------------------------
struct CurvatureOptions {
  std::string input, gaussian, mean;
  bool wrap = false, json = false;
  float range = 0;
};

void run_curvature(const CurvatureOptions& o, const GlobalOptions& g) {
  if (o.gaussian.empty() && o.mean.empty() && !o.json)
    throw UsageError("nothing to do", "give --gaussian K.png and/or --mean H.png (EXR keeps the values), or --json");
  const Rgbn in = load_input(o.input);
  const Curvature c = curvature(in, o.wrap);
  auto write = [&](const std::vector<float>& v, const std::string& path) {
    if (path.empty()) return;
    if (fs::path(path).extension() == ".exr") {
      Image img(in.width, in.height);
      for (size_t i = 0; i < v.size(); ++i) img.pixels[3 * i] = img.pixels[3 * i + 1] = img.pixels[3 * i + 2] = v[i];
      save_image(img, path);
    } else {
      save_image(view_signed(v, in.width, in.height, o.range), path);
    }
  };
  write(c.K, o.gaussian);
  write(c.H, o.mean);
  auto stats = [](const std::vector<float>& v) {
    double s = 0, a = 0;
    for (float x : v) s += x, a += std::abs(x);
    return nlohmann::json{{"mean", s / double(v.size())}, {"mean_abs", a / double(v.size())}};
  };
  print_or_json(o.json, {{"gaussian", stats(c.K)}, {"mean", stats(c.H)}, {"units", "1/pixel (K: 1/pixel^2)"}}, "", g.quiet);
}

struct SegmentCliOptions {
  std::string input, output, weight = "mix", labels;
  float k = 0.5f, alpha = 0.7f, prefilter = 0.0f;
  int min_size = 50;
  bool json = false;
};

void run_segment(const SegmentCliOptions& o, const GlobalOptions& g) {
  Rgbn in = load_input(o.input);
  if (o.prefilter > 0) {
    BilateralOptions bo;
    bo.sigma_s = o.prefilter;
    in = bilateral(in, bo);
  }
  SegmentOptions so;
  so.k = o.k, so.min_size = o.min_size, so.weight = parse_edge_weight(o.weight), so.alpha = o.alpha;
  const Segmentation s = segment(in, so);
  save_image(view_labels(s.labels, in.width, in.height), o.output);
  if (!o.labels.empty()) {
    nlohmann::json j = {{"width", in.width}, {"height", in.height}, {"count", s.count}, {"labels", s.labels}};
    write_text_file(o.labels, j.dump() + "\n");
  }
  print_or_json(o.json, {{"output", o.output}, {"segments", s.count}}, fmt::format("{}: {} segments", o.output, s.count),
                g.quiet);
}

void add_light_flags(CLI::App* cmd, LightOptions& o) {
  cmd->add_option("--light", o.light, "Light direction: azimuth,elevation in degrees (0 = right, 90 = up) or x,y,z")
      ->capture_default_str();
  cmd->add_option("--model", o.model, "Shading: lambert or blinn (Blinn-Phong)")->capture_default_str();
  cmd->add_option("--ambient", o.ambient, "Ambient term")->capture_default_str();
  cmd->add_option("--specular", o.specular, "Blinn-Phong specular strength")->capture_default_str();
  cmd->add_option("--exponent", o.exponent, "Blinn-Phong exponent")->capture_default_str()->check(CLI::Range(0.0f, 1e5f));
  cmd->add_option("--intensity", o.intensity, "Light intensity")->capture_default_str();
  cmd->add_flag("--grey", o.grey, "Shade a grey surface instead of the albedo");
}

}  // namespace

void add_rgbn_command(CLI::App& app, GlobalOptions& global) {
  auto* rgbn = app.add_subcommand("rgbn", "Edit, synthesise and relight RGBN images (a colour and a normal per pixel)");
  rgbn->require_subcommand(1);
  rgbn->footer(
      "An RGBN is an EXR with channels R,G,B (linear albedo) and N.X,N.Y,N.Z (unit normal, +X right, +Y up, +Z\n"
      "towards the viewer: the OpenGL convention). Start with 'proctex rgbn import'.\n"
      "  proctex rgbn import wall_normal.png --convention dx --albedo wall.png -o wall.exr\n"
      "  proctex rgbn import --height bumps.png --scale 8 -o bumps.exr\n"
      "  proctex rgbn light wall.exr --light 135,30 --model blinn -o lit.png\n"
      "  proctex rgbn filter wall.exr --filter sharpen --sigma 2 --amount 1.5 -o sharp.exr\n"
      "  proctex rgbn edit session.json wall.exr -o edited.exr");

  {
    auto o = std::make_shared<ImportOptions>();
    auto* cmd = rgbn->add_subcommand("import", "Make an RGBN from a normal map (8/16-bit PNG/TIFF, EXR) or a height map");
    cmd->footer(
        "Normal maps encode x,y,z as (c+1)/2 per channel; OpenGL (gl) maps have +Y up (green brighter towards the top\n"
        "of bumps lit from above: Blender, Maya, Substance 'OpenGL'), DirectX (dx) maps have +Y down (Unreal, 3ds Max).\n"
        "A wrong convention flips every bump in y: check with 'proctex rgbn light' before editing.\n"
        "--height takes a grey image (luminance, scaled to [0,1]) times --scale pixels as the height.");
    cmd->add_option("normal_map", o->input, "Normal map file (.png, .tif, .exr)");
    cmd->add_option("-o,--output", o->output, "Output RGBN (.exr)")->required();
    cmd->add_option("--convention", o->convention, "Normal-map convention of the input: gl or dx")->capture_default_str();
    cmd->add_option("--albedo", o->albedo, "Colour image of the same size (default: grey 0.5)");
    cmd->add_option("--height", o->height, "Make the normals from this height map instead");
    cmd->add_option("--scale", o->scale, "Height of white in pixels (with --height)")->capture_default_str();
    cmd->add_flag("--tile", o->tile, "Treat the height map as tileable (periodic differences at the edges)");
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_import(*o, global); });
  }
  {
    auto o = std::make_shared<ExportOptions>();
    auto* cmd = rgbn->add_subcommand("export", "Write the normals as a normal map (8/16-bit PNG/TIFF or float EXR)");
    cmd->footer("  proctex rgbn export wall.exr -o wall_n.png --convention dx --bits 16\n"
                "8-bit: c = round((x+1)*127.5), so (0,0,1) is (128,128,255). EXR stores x,y,z as floats.");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output normal map (.png, .tif, .exr)")->required();
    cmd->add_option("--convention", o->convention, "gl (+Y up) or dx (+Y down)")->required();
    cmd->add_option("--bits", o->bits, "Bits per channel for PNG/TIFF: 8 or 16")->capture_default_str();
    cmd->add_option("--albedo", o->albedo, "Also write the albedo to this image");
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_export(*o, global); });
  }
  {
    auto o = std::make_shared<HeightOptions>();
    auto* cmd = rgbn->add_subcommand("height", "Integrate the normals to a height map (FFT least squares)");
    cmd->footer("The integrability error (mean |dq/dx - dp/dy|) says how far the normals are from any height field;\n"
                "EXR output keeps heights in pixels, PNG/TIFF output is scaled to [0,1].");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output height map (.exr keeps pixel units; .png is scaled to [0,1])")->required();
    cmd->add_flag("--periodic", o->periodic, "The RGBN tiles: integrate periodically (else mirror to avoid wrap-around)");
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_height(*o, global); });
  }
  {
    auto o = std::make_shared<LightOptions>();
    auto* cmd = rgbn->add_subcommand("light", "Render the RGBN under a light (Lambert or Blinn-Phong)");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output image")->required();
    add_light_flags(cmd, *o);
    cmd->callback([o, &global] { run_light(*o, global); });
  }
  {
    auto o = std::make_shared<ViewOptions>();
    auto* cmd = rgbn->add_subcommand("view", "The paper's views: shaded, albedo, normals, needles, curvature, segments");
    cmd->add_option("rgbn", o->light.input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->light.output, "Output image")->required();
    cmd->add_option("--view", o->view,
                    "shaded, shaded-normals, albedo, normals (colour-coded), base (smoothed normals), needles, mean, "
                    "gaussian (curvature), segments")
        ->capture_default_str();
    cmd->add_option("--base-sigma", o->base_sigma, "base: bilateral spatial sigma in pixels")->capture_default_str();
    cmd->add_option("--spacing", o->spacing, "Needle spacing in pixels")->capture_default_str();
    cmd->add_option("--range", o->range, "Curvature shown at full colour (default: 99th percentile)");
    add_light_flags(cmd, o->light);
    cmd->callback([o, &global] { run_view(*o, global); });
  }
  {
    auto o = std::make_shared<FilterCliOptions>();
    auto* cmd = rgbn->add_subcommand("filter", "Filters that respect the surface (on the slopes n_x/n_z, n_y/n_z)");
    cmd->footer(
        "smooth: Gaussian; sharpen: 1 + amount (1 - G); edge: 1 + amount (G_sigma - G_sigma2); detail: G_sigma -\n"
        "G_sigma2 alone (a detail normal texture for stamps); scale: gradient x amount (deepen > 1, flatten < 1);\n"
        "bilateral: colour and normal ranges --sigma-c, --sigma-n. Filtering the slopes of normals(z) gives exactly\n"
        "normals(z * g). --brush or --mask restricts the filter; pixels outside stay bit-identical.");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output RGBN (.exr)")->required();
    cmd->add_option("--filter", o->kind, "smooth, sharpen, edge, detail, scale or bilateral")->capture_default_str();
    cmd->add_option("--sigma", o->sigma, "Gaussian width in pixels")->capture_default_str();
    cmd->add_option("--sigma2", o->sigma2, "Wider Gaussian of edge/detail")->capture_default_str();
    cmd->add_option("--amount", o->amount, "Strength (sharpen, edge) or gradient scale (scale)")->capture_default_str();
    cmd->add_option("--sigma-c", o->sigma_c, "Bilateral colour range")->capture_default_str();
    cmd->add_option("--sigma-n", o->sigma_n, "Bilateral normal range")->capture_default_str();
    cmd->add_option("--brush", o->brush, "Disc brush x,y,radius[,feather] in pixels")->delimiter(',');
    cmd->add_option("--mask", o->mask, "Brush mask image (white = filter)");
    cmd->add_flag("--wrap", o->wrap, "Periodic borders (tileable RGBNs)");
    cmd->add_flag("--albedo", o->albedo, "Filter the albedo too (smooth, sharpen, edge)");
    cmd->add_option("--preview", o->preview, "Also write a shaded preview image");
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_filter(*o, global); });
  }
  {
    auto o = std::make_shared<CurvatureOptions>();
    auto* cmd = rgbn->add_subcommand("curvature", "Gaussian (K) and mean (H) curvature maps");
    cmd->footer("H > 0 where the surface bulges towards the viewer, H < 0 in pits; K > 0 on bumps and pits, K < 0 at\n"
                "saddles. PNG output is blue (-) / white (0) / red (+); EXR keeps the values (1/pixel).");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("--gaussian", o->gaussian, "Output K map");
    cmd->add_option("--mean", o->mean, "Output H map");
    cmd->add_option("--range", o->range, "Value shown at full colour (default: 99th percentile)");
    cmd->add_flag("--wrap", o->wrap, "Periodic borders");
    cmd->add_flag("--json", o->json, "Print mean values as JSON");
    cmd->callback([o, &global] { run_curvature(*o, global); });
  }
  {
    auto o = std::make_shared<SegmentCliOptions>();
    auto* cmd = rgbn->add_subcommand("segment", "Felzenszwalb-Huttenlocher segmentation on colour and normals");
    cmd->add_option("rgbn", o->input, "Input RGBN (.exr)")->required();
    cmd->add_option("-o,--output", o->output, "Output label image (one colour per segment)")->required();
    cmd->add_option("--k", o->k, "Scale: larger k gives larger segments")->capture_default_str();
    cmd->add_option("--min-size", o->min_size, "Smallest segment in pixels")->capture_default_str();
    cmd->add_option("--weight", o->weight, "Edge weight: min, max or mix of colour and normal distance")->capture_default_str();
    cmd->add_option("--alpha", o->alpha, "Normal share of the mix")->capture_default_str();
    cmd->add_option("--prefilter", o->prefilter, "Bilateral prefilter width in pixels (0 = none)")->capture_default_str();
    cmd->add_option("--labels", o->labels, "Also write the labels as JSON");
    cmd->add_flag("--json", o->json, "Print a JSON report");
    cmd->callback([o, &global] { run_segment(*o, global); });
  }
  add_edit_commands(*rgbn, global);
  add_display_commands(*rgbn, global);
}

}  // namespace proctex::cli
