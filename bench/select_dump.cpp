// Evidence for the shader selection (issue 12): for each labelled photo, the default metric's 20
// group distances between the photo and every catalogue sample, at one or more scales of the photo.
//   bench_select_dump --db CATALOG --list LIST.tsv --out DIR
// LIST.tsv: one photo per line, "path<TAB>accepted shaders (comma-separated)<TAB>split<TAB>kind".
// DIR/evidence.json: shaders, sample counts, group names, photos with labels and scales;
// DIR/distances.f32: float32 little-endian, [photo][scale][sample of the catalogue in shader order][group];
// DIR/targets.f32: float32, [photo][scale][feature] (the photo's composite features);
// DIR/structural.f32: float32, [photo][shader]: the best structural similarity of the shader's
// samples to the whole photo (what match's structural scan computes);
// DIR/colour.f32: float32, [photo][search::kColourStatistics]: the photo's colour statistics
// (search::colour_statistics; for the --synthetic rows, of the sample rendered again at 256 px with
// its seed: catalogue samples have random colours, and the colour term must be measured on them too).
// DIR/shape.f32: float32, [photo][scale][search::kShapeStatistics]: each view's orientation and
// elongation statistics (search::shape_statistics; --synthetic rows: of the sample rendered again);
// DIR/catalog_shape.f32: float32, [sample of the catalogue in shader-name order][kShapeStatistics]:
// the same of every sample of --db, rendered again (evidence.json "shape_shaders": that order).
// --augment N: N photo-like renders of every catalogue sample (another zoom, a lighting gradient,
// blur, sensor noise; seeded by --augment-seed), their features in DIR/augmented.f32
// [render][feature] and their shader indices in evidence.json "augmented": training rows for
// what a shader looks like when photographed rather than rendered cleanly.
// --grey: after each listed photo, its greyscale copy (linear-RGB luminance in all three channels)
// as another row with the same label, "grey": true and "source" (the photo's row): features and
// colour statistics from the grey image, so its colour term is left out, as for a greyscale photo.
// --match-json DIR: the targets of bench_match_eval --pictures JSONs in DIR (each file's
// target.spec rendered as bench_match_eval does, 256 px) as rows of split "match", accepted = the
// target's shader, "file" = the JSON's name: the selection of a new model on those targets.
// --micro: each shape row also holds search::micro_statistics (local binary patterns) after the
// shape statistics: shape_size = kShapeStatistics + kMicroStatistics, "micro_size" the latter.
// DIR/evidence.json "db": the catalogue (absolute path).
// The fit of the selection weights reads these files (bench/fit_selection.py).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catalog/store.h"
#include "core/error.h"
#include "metrics/composite.h"
#include "metrics/metric.h"
#include "search/match.h"
#include "search/selection.h"
#include "shaders/library.h"
#include "shaders/renderer.h"

using namespace proctex;
namespace fs = std::filesystem;

namespace {

// One photo-like view of a sample: zoom 0.5..2 (log-uniform) at a random origin, a linear lighting
// gradient of up to +-35 % across the image, blur (down- and up-sampling by 0.5..1), Gaussian noise
// of up to 3 % (linear RGB).
Image photographed(Renderer& renderer, const ShaderDecl& decl, const catalog::Sample& sample, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  RenderSettings settings;
  settings.extent = std::exp2(2.0f * u(rng) - 1.0f);
  settings.origin_u = 10.0f * u(rng);
  settings.origin_v = 10.0f * u(rng);
  Image img = renderer.render_batch(decl, {sample.packed}, {sample.seed}, settings).front();
  const float angle = 6.2831853f * u(rng), strength = 0.7f * u(rng);
  const float gx = std::cos(angle) * strength, gy = std::sin(angle) * strength;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const float gain = 1.0f + gx * (float(x) / img.width - 0.5f) + gy * (float(y) / img.height - 0.5f);
      for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] *= gain;
    }
  const int small = static_cast<int>(img.width * (0.5f + 0.5f * u(rng)));
  if (small < img.width) img = resize(resize(img, small, small), img.width, img.height);
  std::normal_distribution<float> noise(0.0f, 0.03f * u(rng));
  for (float& v : img.pixels) v = std::max(0.0f, v + noise(rng));
  return img;
}

// The greyscale copy of a photo: every pixel's linear-RGB luminance (Rec. 709) in all channels.
Image greyscale(const Image& photo) {
  Image g = photo;
  for (size_t i = 0; i + 2 < g.pixels.size(); i += 3) {
    const float y = 0.2126729f * g.pixels[i] + 0.7151522f * g.pixels[i + 1] + 0.0721750f * g.pixels[i + 2];
    g.pixels[i] = g.pixels[i + 1] = g.pixels[i + 2] = y;
  }
  return g;
}

}  // namespace

int main(int argc, char** argv) {
  std::string db, list, out, synthetic, match_json;
  bool grey = false, micro = false;
  int augment = 0;
  unsigned augment_seed = 1;
  for (const char* flag : {"--grey", "--micro"})
    for (int i = 1; i < argc; ++i)
      if (std::string(argv[i]) == flag) {
        (std::string(flag) == "--grey" ? grey : micro) = true;
        for (int j = i; j + 1 < argc; ++j) argv[j] = argv[j + 1];
        --argc;
        break;
      }
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--db") db = argv[i + 1];
    else if (a == "--list") list = argv[i + 1];
    else if (a == "--out") out = argv[i + 1];
    else if (a == "--synthetic") synthetic = argv[i + 1];
    else if (a == "--match-json") match_json = argv[i + 1];
    else if (a == "--augment") augment = std::stoi(argv[i + 1]);
    else if (a == "--augment-seed") augment_seed = static_cast<unsigned>(std::stoul(argv[i + 1]));
  }
  if (db.empty() || list.empty() || out.empty()) {
    std::fprintf(stderr, "usage: bench_select_dump --db CATALOG --list LIST.tsv --out DIR\n");
    return 2;
  }
  try {
    fs::create_directories(out);
    catalog::Store store(db, catalog::Store::Access::Read);
    const auto& metric = metrics::default_metric();
    const auto* composite = dynamic_cast<const metrics::CompositeMetric*>(&metric);
    std::vector<catalog::ShaderCatalogue> cats;
    nlohmann::json index;
    index["db"] = fs::absolute(db).string();  // fit_selection.py --train-dump reads the catalogue rows from it
    for (const auto& s : store.shaders()) {
      cats.push_back(store.load(s.name, false));
      index["shaders"].push_back({{"name", s.name}, {"samples", cats.back().samples.size()}});
    }
    for (size_t g = 0; g < composite->group_count(); ++g) index["groups"].push_back(composite->group_name(g));
    std::ofstream dist(fs::path(out) / "distances.f32", std::ios::binary);
    std::ofstream targ(fs::path(out) / "targets.f32", std::ios::binary);
    std::ofstream structural(fs::path(out) / "structural.f32", std::ios::binary);
    std::ofstream colour(fs::path(out) / "colour.f32", std::ios::binary);
    std::ofstream shape(fs::path(out) / "shape.f32", std::ios::binary);
    auto write_floats = [](std::ofstream& file, const std::vector<double>& values) {
      for (double v : values) {
        const float f = static_cast<float>(v);
        file.write(reinterpret_cast<const char*>(&f), sizeof f);
      }
    };
    // One shape row: the shape statistics, with --micro followed by the micro statistics.
    auto shape_row = [micro](const Image& image) {
      auto row = search::shape_statistics(image);
      if (micro) {
        const auto m = search::micro_statistics(image);
        row.insert(row.end(), m.begin(), m.end());
      }
      return row;
    };
    {
      // Every sample of the catalogue rendered again, for its shape statistics (not stored in it).
      std::ofstream catalog_shape(fs::path(out) / "catalog_shape.f32", std::ios::binary);
      const auto& library = ShaderLibrary::builtin();
      Renderer renderer(library);
      std::vector<const catalog::ShaderCatalogue*> by_name;
      for (const auto& cat : cats) by_name.push_back(&cat);
      std::sort(by_name.begin(), by_name.end(), [](auto* a, auto* b) { return a->shader < b->shader; });
      size_t done = 0;
      for (const auto* cat : by_name) {
        const ShaderDecl& decl = library.get(cat->shader);
        std::vector<std::vector<float>> packed;
        std::vector<uint32_t> seeds;
        for (const auto& sample : cat->samples) {
          packed.push_back(sample.packed);
          seeds.push_back(sample.seed);
        }
        for (const auto& image : renderer.render_batch(decl, packed, seeds, RenderSettings{}))
          write_floats(catalog_shape, shape_row(image));
        index["shape_shaders"].push_back(cat->shader);
        std::fprintf(stderr, "\rcatalogue shape statistics %zu/%zu shaders", ++done, by_name.size());
      }
      std::fprintf(stderr, "\n");
    }
    auto write_colour = [&](const std::vector<double>& stats) {
      for (double v : stats) {
        const float f = static_cast<float>(v);
        colour.write(reinterpret_cast<const char*>(&f), sizeof f);
      }
    };
    std::ifstream in(list);
    std::string line;
    std::vector<double> groups(composite->group_count());
    // One target's rows: best structural similarity per shader, features, group distances per sample.
    auto write_structural = [&](const metrics::Features& f) {
      for (const auto& cat : cats) {
        float best = 0;
        for (const auto& sample : cat.samples)
          best = std::max(best, float(search::structural_similarity(metric, f, sample.features.values)));
        structural.write(reinterpret_cast<const char*>(&best), sizeof best);
      }
    };
    auto write_target = [&](const metrics::Features& f) {
      targ.write(reinterpret_cast<const char*>(f.values.data()), f.values.size() * sizeof(float));
      for (const auto& cat : cats)
        for (const auto& sample : cat.samples) {
          composite->group_distances(f.values, sample.features.values, groups.data());
          for (double d : groups) {
            const float v = static_cast<float>(d);
            dist.write(reinterpret_cast<const char*>(&v), sizeof v);
          }
        }
    };
    int n = 0;
    // One row: structural similarities, colour statistics and the features of every view.
    auto write_photo = [&](const Image& photo, nlohmann::json entry) {
      const auto views = search::target_views(photo);
      entry["scales"] = views.size();
      write_structural(metric.features(photo, 256));
      write_colour(search::colour_statistics(photo));
      for (const auto& view : views) {
        write_target(metric.features(view.image, 256));
        write_floats(shape, shape_row(view.image));
        entry["views"].push_back(view.name);
      }
      index["photos"].push_back(entry);
    };
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::stringstream ls(line);
      std::string path, accepted, split, kind;
      std::getline(ls, path, '\t');
      std::getline(ls, accepted, '\t');
      std::getline(ls, split, '\t');
      std::getline(ls, kind, '\t');
      const Image photo = search::prepare_target(path, "");
      const nlohmann::json entry = {{"path", path}, {"accepted", accepted}, {"split", split}, {"kind", kind}};
      const size_t row = index["photos"].size();
      write_photo(photo, entry);
      if (grey) {
        auto g = entry;
        g["grey"] = true;
        g["source"] = row;
        write_photo(greyscale(photo), g);
      }
      std::fprintf(stderr, "\r%d photos", ++n);
    }
    // --synthetic CAT2: the samples of another catalogue (another seed) as renders of known shaders,
    // one view each (their stored features), split "synthetic".
    if (!synthetic.empty()) {
      catalog::Store other(synthetic, catalog::Store::Access::Read);
      const auto& library = ShaderLibrary::builtin();
      Renderer renderer(library);
      for (const auto& s : other.shaders()) {
        const auto cat2 = other.load(s.name, false);
        const ShaderDecl& decl = library.get(s.name);
        for (size_t k = 0; k < cat2.samples.size(); ++k) {
          const auto& f = cat2.samples[k].features;
          write_structural(f);
          // the sample rendered again (its random colours), for the colour term a target like it gets
          const Image image =
              renderer.render_batch(decl, {cat2.samples[k].packed}, {cat2.samples[k].seed}, RenderSettings{}).front();
          write_colour(search::colour_statistics(image));
          write_floats(shape, shape_row(image));
          write_target(f);
          index["photos"].push_back({{"path", s.name + "#" + std::to_string(k)}, {"accepted", s.name},
                                     {"split", "synthetic"}, {"kind", s.name}, {"scales", 1}, {"views", {"whole"}}});
        }
      }
    }
    if (!match_json.empty()) {
      const auto& library = ShaderLibrary::builtin();
      Renderer renderer(library);
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(match_json))
        if (e.path().extension() == ".json") files.push_back(e.path());
      std::sort(files.begin(), files.end());
      for (const auto& file : files) {
        std::ifstream in_json(file);
        const auto j = nlohmann::json::parse(in_json);
        if (!j.contains("target") || !j["target"].contains("spec")) continue;
        const auto spec = TextureSpec::from_json(j["target"]["spec"]);
        write_photo(renderer.render(spec, RenderSettings{}),
                    {{"path", spec.shader + "@" + file.filename().string()}, {"accepted", spec.shader},
                     {"split", "match"}, {"kind", spec.shader}, {"file", file.filename().string()}});
      }
    }
    if (augment > 0) {
      std::ofstream aug(fs::path(out) / "augmented.f32", std::ios::binary);
      const auto& library = ShaderLibrary::builtin();
      Renderer renderer(library);
      std::mt19937 rng(augment_seed);
      index["augment_seed"] = augment_seed;
      for (size_t s = 0; s < cats.size(); ++s) {
        const ShaderDecl& decl = library.get(cats[s].shader);
        for (const auto& sample : cats[s].samples)
          for (int k = 0; k < augment; ++k) {
            const auto f = metric.features(photographed(renderer, decl, sample, rng), 256);
            aug.write(reinterpret_cast<const char*>(f.values.data()), f.values.size() * sizeof(float));
            index["augmented"].push_back(s);
          }
        std::fprintf(stderr, "\raugmented %zu/%zu shaders", s + 1, cats.size());
      }
    }
    index["feature_size"] = metric.feature_size();
    index["colour_size"] = search::kColourStatistics;
    index["shape_size"] = search::kShapeStatistics + (micro ? search::kMicroStatistics : 0);
    index["micro_size"] = micro ? search::kMicroStatistics : 0;
    std::ofstream(fs::path(out) / "evidence.json") << index.dump(1);
    std::fprintf(stderr, "\n");
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_select_dump: error: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
