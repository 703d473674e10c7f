// Texture-retrieval evaluation of the similarity metrics (issue 3; results in docs/metrics.md).
//
// Every texture is split into non-overlapping crops; each crop queries all the others; a query's
// relevant items are the other crops of its texture. Reported per metric: top-1 accuracy (the
// most similar item is of the same texture) and mean reciprocal rank of the first relevant item.
// Sets:
//   photos        ../shared/textures: each photo in a 2 x 2 grid of crops
//   photos-9      the same photos in a 3 x 3 grid of smaller crops (harder: less texture each)
//   photos-16     a 4 x 4 grid analysed at half the resolution (hardest photo set)
//   grey          photos-9 and photos-16 with colour removed (luminance in all channels)
//   shaders       (when built with the shader library and an OpenCL device) for every library
//                 shader, --specs random parameter vectors, each rendered with 3 seeds: the same
//                 spec with another seed is the same texture, another spec a different one
// Usage: bench_metrics_retrieval [--shared DIR] [--resolution N] [--specs K] [--no-shaders]
//                                [--distances]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/error.h"
#include "image/image.h"
#include "metrics/metric.h"
#ifdef PROCTEX_BENCH_SHADERS
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"
#endif

using namespace proctex;

namespace {

struct Item {
  std::string texture;  // class label
  Image image;
};

Image to_grey(const Image& in) {
  Image out = in;
  const std::vector<float> y = luminance(in);
  for (size_t i = 0; i < y.size(); ++i) out.pixels[3 * i] = out.pixels[3 * i + 1] = out.pixels[3 * i + 2] = y[i];
  return out;
}

std::vector<Item> photo_items(const std::string& shared, int grid) {
  std::vector<Item> items;
  for (const char* name : {"brick.png", "grass.png", "gravel.png", "hubble_deep_field.jpg"}) {
    Image img = load_image(shared + "/textures/" + name);
    const int w = img.width / grid, h = img.height / grid;
    for (int gy = 0; gy < grid; ++gy)
      for (int gx = 0; gx < grid; ++gx) items.push_back({name, crop(img, gx * w, gy * h, w, h)});
  }
  return items;
}

#ifdef PROCTEX_BENCH_SHADERS
std::vector<Item> shader_items(int specs, int resolution) {
  std::vector<Item> items;
  Renderer renderer;
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RenderSettings settings;
  settings.width = settings.height = resolution;
  for (const ShaderDecl& decl : renderer.library().shaders()) {
    ParameterSpace space(decl);
    for (int s = 0; s < specs; ++s) {
      std::vector<double> unit(space.dimensions());
      for (double& x : unit) x = u(rng);
      const std::vector<float> packed = space.to_packed(unit);
      const std::vector<uint32_t> seeds = {1, 2, 3};
      std::vector<Image> images = renderer.render_batch(decl, {packed, packed, packed}, seeds, settings);
      for (Image& img : images) items.push_back({decl.name + "#" + std::to_string(s), std::move(img)});
    }
  }
  return items;
}
#endif

struct Result {
  double top1 = 0, mrr = 0;
  double same = 0, different = 0;  // mean similarity of same-texture / different-texture pairs
  double ms_per_item = 0;
};

Result evaluate(const metrics::Metric& m, const std::vector<Item>& items, int resolution) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::vector<float>> f;
  for (const Item& it : items) f.push_back(m.features(it.image, resolution).values);
  const auto t1 = std::chrono::steady_clock::now();
  Result r;
  r.ms_per_item = std::chrono::duration<double, std::milli>(t1 - t0).count() / items.size();
  int queries = 0;
  long same_n = 0, diff_n = 0;
  for (size_t q = 0; q < items.size(); ++q) {
    std::vector<std::pair<double, bool>> ranked;
    for (size_t j = 0; j < items.size(); ++j) {
      if (j == q) continue;
      const double s = m.similarity(f[q], f[j]);
      const bool rel = items[j].texture == items[q].texture;
      ranked.push_back({s, rel});
      (rel ? r.same : r.different) += s;
      (rel ? same_n : diff_n)++;
    }
    if (std::none_of(ranked.begin(), ranked.end(), [](auto& p) { return p.second; })) continue;
    // Pessimistic on ties: an irrelevant item with an equal score ranks first.
    std::stable_sort(ranked.begin(), ranked.end(), [](auto& a, auto& b) {
      return a.first != b.first ? a.first > b.first : (!a.second && b.second);
    });
    ++queries;
    for (size_t k = 0; k < ranked.size(); ++k) {
      if (ranked[k].second) {
        r.mrr += 1.0 / (k + 1);
        if (k == 0) r.top1 += 1;
        break;
      }
    }
  }
  r.top1 /= queries;
  r.mrr /= queries;
  r.same /= std::max(1L, same_n);
  r.different /= std::max(1L, diff_n);
  return r;
}

void report(const std::string& set, const std::vector<Item>& items, int resolution) {
  std::map<std::string, int> classes;
  for (const Item& it : items) classes[it.texture]++;
  std::printf("\n### %s: %zu images, %zu textures\n\n", set.c_str(), items.size(), classes.size());
  std::printf("| metric | top-1 | MRR | mean S same | mean S different | ms/image |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (const std::string& name : metrics::metric_names()) {
    const Result r = evaluate(metrics::get_metric(name), items, resolution);
    std::printf("| %s | %.1f%% | %.3f | %.3f | %.3f | %.1f |\n", name.c_str(), 100 * r.top1, r.mrr,
                r.same, r.different, r.ms_per_item);
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
#ifdef PROCTEX_SHARED_DIR
  std::string shared = PROCTEX_SHARED_DIR;
#else
  std::string shared = "../shared";
#endif
  int resolution = metrics::kDefaultResolution;
  int specs = 6;
  bool shaders = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--shared") && i + 1 < argc) shared = argv[++i];
    else if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc) resolution = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--specs") && i + 1 < argc) specs = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--no-shaders")) shaders = false;
    else {
      std::fprintf(stderr, "usage: %s [--shared DIR] [--resolution N] [--specs K] [--no-shaders]\n", argv[0]);
      return 2;
    }
  }
  try {
    std::printf("# Texture retrieval, analysis resolution %d\n", resolution);
    std::vector<Item> photos = photo_items(shared, 2);
    std::vector<Item> photos9 = photo_items(shared, 3);
    report("photos (2 x 2 crops)", photos, resolution);
    report("photos-9 (3 x 3 crops)", photos9, resolution);
    // Harder: a 4 x 4 grid of small crops, analysed at half the resolution.
    std::vector<Item> photos16 = photo_items(shared, 4);
    const int half = std::max(metrics::kMinResolution, resolution / 2 / 16 * 16);
    report("photos-16 (4 x 4 crops, resolution " + std::to_string(half) + ")", photos16, half);
    auto grey = [](const std::vector<Item>& set) {
      std::vector<Item> out;
      for (const Item& it : set) out.push_back({it.texture, to_grey(it.image)});
      return out;
    };
    report("grey photos-9 (colour removed)", grey(photos9), resolution);
    report("grey photos-16 (colour removed, resolution " + std::to_string(half) + ")", grey(photos16), half);
#ifdef PROCTEX_BENCH_SHADERS
    if (shaders) {
      std::vector<Item> rendered;
      try {
        rendered = shader_items(specs, resolution);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "shader renders skipped: %s\n", e.what());
      }
      if (!rendered.empty()) {
        report("shaders (random specs x 3 seeds)", rendered, resolution);
        std::vector<Item> all = photos;
        all.insert(all.end(), rendered.begin(), rendered.end());
        report("photos + shaders", all, resolution);
      }
    }
#else
    (void)specs;
    (void)shaders;
#endif
  } catch (const proctex::Error& e) {
    std::fprintf(stderr, "error: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
