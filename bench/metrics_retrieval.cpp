// Texture-retrieval evaluation of the similarity metrics and the fit of the composite weights
// (issue 3; results in docs/metrics.md).
//
// Items and textures:
//   photos   each photo of ../shared/textures cut into a --grid x --grid grid of non-overlapping
//            crops (default 4 x 4); the crops of one photo are one texture.
//   shaders  every library shader except the shape family (one centred shape is not a texture),
//            --specs random parameter vectors (uniform in the shader's search space), each with
//            --neighbours perturbed copies (unit coordinates + N(0, --perturb^2), clamped): other
//            textures that look alike, the hard negatives a catalogue search meets. Each spec
//            rendered three times: seeds 1, 2, 3 at the same origin. Where seed 2 gives the same
//            image as seed 1 (a shader, or a spec, that ignores the seed: checker, grid, stripes,
//            polkadots without jitter, ...), renders 2 and 3 are taken at other origins
//            (RenderSettings origin_u/v, away from the first) instead: other crops of the same
//            texture. Specs that render a (nearly) flat image carry no texture and are dropped.
//            The three renders of one spec are one texture; other specs are other textures, also
//            of the same shader (hard negatives).
// Every item queries all others of its pool; relevant = the other items of its texture. Top-1 =
// the most similar item is relevant; MRR = mean of 1/rank of the first relevant item; ties count
// pessimistically.
//
// Splits: even-numbered base specs of every shader (with their neighbours) form the TUNE split,
// odd-numbered ones the REPORT split. The composite weights are chosen by a grid search on the tune split (mean MRR of its
// colour and greyscale versions); the report split and the photos (never used in the fit) give
// the numbers in the docs. Greyscale versions: luminance copied to all channels.
//
// Usage: bench_metrics_retrieval [--shared DIR] [--resolution N] [--specs K] [--neighbours M]
//                                [--perturb SIGMA] [--grid G] [--step W] [--no-shaders]
//                                [--skip SHADER]...
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "image/image.h"
#include "metrics/calibration.h"
#include "metrics/composite.h"
#include "metrics/metric.h"
#include "metrics/structure.h"
#ifdef PROCTEX_BENCH_SHADERS
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"
#endif

using namespace proctex;

namespace {

enum Split { kTune = 0, kReport = 1, kPhoto = 2 };

struct Item {
  std::string texture;  // class label
  std::string source;   // photo file or shader name (for the per-source breakdown)
  int split = kPhoto;
  bool grey = false;
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
      for (int gx = 0; gx < grid; ++gx) {
        Item it;
        it.texture = it.source = name;
        it.image = crop(img, gx * w, gy * h, w, h);
        items.push_back(std::move(it));
      }
  }
  return items;
}

double mean_abs_diff(const Image& a, const Image& b) {
  double s = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) s += std::abs(a.pixels[i] - b.pixels[i]);
  return s / static_cast<double>(a.pixels.size());
}

double max_channel_std(const Image& img) {
  double best = 0;
  const size_t n = static_cast<size_t>(img.width) * img.height;
  for (int c = 0; c < 3; ++c) {
    double m = 0, m2 = 0;
    for (size_t i = 0; i < n; ++i) {
      const double v = img.pixels[3 * i + c];
      m += v;
      m2 += v * v;
    }
    m /= n;
    best = std::max(best, std::sqrt(std::max(0.0, m2 / n - m * m)));
  }
  return best;
}

#ifdef PROCTEX_BENCH_SHADERS
std::vector<Item> shader_items(int specs, int neighbours, double perturb, int resolution,
                               const std::set<std::string>& skip) {
  std::vector<Item> items;
  Renderer renderer;
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RenderSettings settings;
  settings.width = settings.height = resolution;
  std::printf("\nShader renders (%d x %d, %d random specs per shader, each with %d neighbours at "
              "sigma %.2f):\n\n", resolution, resolution, specs, neighbours, perturb);
  std::printf("| shader | specs kept | same texture by | dropped (flat) |\n|---|---|---|---|\n");
  for (const ShaderDecl& decl : renderer.library().shaders()) {
    if (decl.family == "shape" || skip.count(decl.name)) {
      std::printf("| %s | - | excluded (%s) | - |\n", decl.name.c_str(),
                  decl.family == "shape" ? "a single centred shape, not a texture" : "--skip");
      continue;
    }
    ParameterSpace space(decl);
    // Base specs uniform in the unit cube; each followed by `neighbours` perturbed copies
    // (Gaussian, sigma `perturb` per unit dimension): different textures that look alike.
    std::normal_distribution<double> g(0.0, perturb);
    std::vector<std::vector<float>> packed;
    std::vector<int> base_of;
    for (int b = 0; b < specs; ++b) {
      std::vector<double> unit(space.dimensions());
      for (double& x : unit) x = u(rng);
      packed.push_back(space.to_packed(unit));
      base_of.push_back(b);
      for (int m = 0; m < neighbours; ++m) {
        std::vector<double> v = unit;
        for (double& x : v) x = std::clamp(x + g(rng), 0.0, 1.0);
        packed.push_back(space.to_packed(v));
        base_of.push_back(b);
      }
    }
    const int total = static_cast<int>(packed.size());
    try {
      auto batch = [&](uint32_t seed, float ou, float ov, const std::vector<std::vector<float>>& p) {
        RenderSettings st = settings;
        st.origin_u = ou;
        st.origin_v = ov;
        return renderer.render_batch(decl, p, std::vector<uint32_t>(p.size(), seed), st);
      };
      std::vector<Image> r1 = batch(1, 0, 0, packed), r2 = batch(2, 0, 0, packed), r3 = batch(3, 0, 0, packed);
      // Specs whose seed changes nothing: other crops of the texture instead of other seeds.
      std::vector<int> fixed;
      std::vector<std::vector<float>> fixed_packed;
      for (int s = 0; s < total; ++s)
        if (mean_abs_diff(r1[s], r2[s]) < 1e-4) {
          fixed.push_back(s);
          fixed_packed.push_back(packed[s]);
        }
      if (!fixed.empty()) {
        std::vector<Image> o2 = batch(2, 1.37f, 0.61f, fixed_packed), o3 = batch(3, 2.71f, 1.93f, fixed_packed);
        for (size_t k = 0; k < fixed.size(); ++k) {
          r2[fixed[k]] = std::move(o2[k]);
          r3[fixed[k]] = std::move(o3[k]);
        }
      }
      int kept = 0, flat = 0;
      for (int s = 0; s < total; ++s) {
        if (max_channel_std(r1[s]) < 2e-3) {
          ++flat;
          continue;
        }
        ++kept;
        for (Image* img : {&r1[s], &r2[s], &r3[s]}) {
          Item it;
          it.texture = decl.name + "#" + std::to_string(s);
          it.source = decl.name;
          it.split = base_of[s] % 2 == 0 ? kTune : kReport;  // a base and its neighbours together
          it.image = std::move(*img);
          items.push_back(std::move(it));
        }
      }
      const char* how = fixed.empty() ? "seeds" : static_cast<int>(fixed.size()) == total ? "origins (seed ignored)" : "seeds; origins where the seed is ignored";
      std::printf("| %s | %d | %s%s | %d |\n", decl.name.c_str(), kept, how,
                  !fixed.empty() && static_cast<int>(fixed.size()) != total
                      ? (" (" + std::to_string(fixed.size()) + " specs)").c_str()
                      : "",
                  flat);
    } catch (const std::exception& e) {
      std::printf("| %s | - | skipped: %s | - |\n", decl.name.c_str(), e.what());
    }
    std::fflush(stdout);
  }
  return items;
}
#endif

// Per-component features of every item, and each component's feature time.
struct FeatureTable {
  std::vector<const metrics::Metric*> metrics;  // components
  std::vector<std::vector<std::vector<float>>> f;  // [component][item]
  std::vector<double> ms;                          // per component, per image
  double prepare_ms = 0;
};

FeatureTable compute_features(const metrics::CompositeMetric& composite, const std::vector<Item>& items,
                              int resolution) {
  FeatureTable t;
  for (const auto& c : composite.components()) t.metrics.push_back(c.metric.get());
  const size_t k = t.metrics.size();
  t.f.assign(k, {});
  t.ms.assign(k, 0.0);
  using clock = std::chrono::steady_clock;
  for (const Item& it : items) {
    auto t0 = clock::now();
    metrics::Analysis an = metrics::prepare_analysis(it.image, resolution);
    auto t1 = clock::now();
    t.prepare_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
    for (size_t c = 0; c < k; ++c) {
      auto a = clock::now();
      t.f[c].push_back(t.metrics[c]->compute(an));
      t.ms[c] += std::chrono::duration<double, std::milli>(clock::now() - a).count();
    }
  }
  t.prepare_ms /= items.size();
  for (double& m : t.ms) m /= items.size();
  return t;
}

// Scaled distance matrices d_k / scale_k (so that S_k = exp(-D)), one per component.
std::vector<std::vector<float>> distance_matrices(const FeatureTable& t, const std::vector<Item>& items) {
  const size_t n = t.f[0].size();
  std::vector<std::vector<float>> d(t.metrics.size(), std::vector<float>(n * n, 0.0f));
  for (size_t c = 0; c < t.metrics.size(); ++c) {
    const metrics::Metric& m = *t.metrics[c];
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) {
        if (items[i].grey != items[j].grey) continue;  // pools never mix colour and grey
        // -ln S: exactly what similarity() ranks by (canonical order, equal vectors -> 0).
        const double s = m.similarity(t.f[c][i], t.f[c][j]);
        d[c][i * n + j] = d[c][j * n + i] = static_cast<float>(-std::log(s));
      }
  }
  return d;
}

struct Score {
  double top1 = 0, mrr = 0;
  int queries = 0;
};

// Retrieval in `pool` (item indices) with distance sum_k w_k D_k. `per_source` (optional)
// collects top-1 hits and queries per item source.
Score evaluate(const std::vector<std::vector<float>>& D, size_t n, const std::vector<double>& w,
               const std::vector<int>& pool, const std::vector<Item>& items,
               std::map<std::string, std::pair<int, int>>* per_source = nullptr) {
  Score r;
  for (int q : pool) {
    // Best relevant and irrelevant distances, and how many irrelevant items beat the best relevant.
    std::vector<std::pair<double, bool>> ranked;
    ranked.reserve(pool.size());
    bool any = false;
    for (int j : pool) {
      if (j == q) continue;
      double d = 0;
      for (size_t c = 0; c < D.size(); ++c)
        if (w[c] != 0) d += w[c] * D[c][static_cast<size_t>(q) * n + j];
      const bool rel = items[j].texture == items[q].texture;
      any |= rel;
      ranked.push_back({d, rel});
    }
    if (!any) continue;
    double best_rel = 1e300;
    for (auto& p : ranked)
      if (p.second) best_rel = std::min(best_rel, p.first);
    int better = 0;  // irrelevant items at a distance <= the best relevant one (pessimistic ties)
    for (auto& p : ranked)
      if (!p.second && p.first <= best_rel) ++better;
    ++r.queries;
    r.mrr += 1.0 / (better + 1);
    if (better == 0) r.top1 += 1;
    if (per_source) {
      auto& ps = (*per_source)[items[q].source];
      ps.first += better == 0;
      ps.second += 1;
    }
  }
  if (r.queries) {
    r.top1 /= r.queries;
    r.mrr /= r.queries;
  }
  return r;
}

std::vector<int> pool_of(const std::vector<Item>& items, std::initializer_list<int> splits, bool grey) {
  std::vector<int> p;
  for (size_t i = 0; i < items.size(); ++i)
    if (items[i].grey == grey && std::find(splits.begin(), splits.end(), items[i].split) != splits.end())
      p.push_back(static_cast<int>(i));
  return p;
}

std::string weights_str(const std::vector<double>& w) {
  std::string s;
  for (double x : w) {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%s%.2f", s.empty() ? "" : " / ", x);
    s += buf;
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
#ifdef PROCTEX_SHARED_DIR
  std::string shared = PROCTEX_SHARED_DIR;
#else
  std::string shared = "../shared";
#endif
  int resolution = metrics::kDefaultResolution;
  int specs = 8, grid = 4, neighbours = 2;
  double step = 0.05, perturb = 0.15;
  bool shaders = true, structure_groups = false;
  std::set<std::string> skip;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--shared") && i + 1 < argc) shared = argv[++i];
    else if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc) resolution = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--specs") && i + 1 < argc) specs = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--neighbours") && i + 1 < argc) neighbours = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--perturb") && i + 1 < argc) perturb = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--grid") && i + 1 < argc) grid = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--step") && i + 1 < argc) step = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--skip") && i + 1 < argc) skip.insert(argv[++i]);
    else if (!std::strcmp(argv[i], "--no-shaders")) shaders = false;
    else if (!std::strcmp(argv[i], "--structure-groups")) structure_groups = true;
    else {
      std::fprintf(stderr,
                   "usage: %s [--shared DIR] [--resolution N] [--specs K] [--neighbours M] [--perturb SIGMA] "
                   "[--grid G] [--step W] "
                   "[--no-shaders] [--skip SHADER]...\n",
                   argv[0]);
      return 2;
    }
  }
  try {
    const auto& composite = dynamic_cast<const metrics::CompositeMetric&>(metrics::default_metric());
    std::printf("# Texture retrieval, analysis resolution %d\n", resolution);
    std::vector<Item> items = photo_items(shared, grid);
#ifdef PROCTEX_BENCH_SHADERS
    if (shaders) {
      std::vector<Item> rendered = shader_items(specs, neighbours, perturb, resolution, skip);
      for (Item& it : rendered) items.push_back(std::move(it));
    }
#else
    (void)specs;
    (void)shaders;
    (void)neighbours;
    (void)perturb;
#endif
    const size_t colour_n = items.size();
    for (size_t i = 0; i < colour_n; ++i) {
      Item g = items[i];
      g.image = to_grey(items[i].image);
      g.grey = true;
      items.push_back(std::move(g));
    }
    const FeatureTable t = compute_features(composite, items, resolution);
    const auto D = distance_matrices(t, items);
    const size_t n = items.size(), k = t.metrics.size();

    // Weights: grid search over the simplex on the tune split (colour and grey), never the photos.
    const std::vector<int> tune_c = pool_of(items, {kTune}, false), tune_g = pool_of(items, {kTune}, true);
    std::vector<double> best_w(k, 1.0 / k);
    double best = -1, best_top1 = -1;
    std::vector<double> current;
    for (const auto& c : composite.components()) current.push_back(c.weight);
    const int steps = static_cast<int>(std::lround(1.0 / step));
    if (!tune_c.empty()) {
      std::vector<int> idx(k, 0);
      std::function<void(size_t, int)> rec = [&](size_t c, int left) {
        if (c + 1 == k) {
          idx[c] = left;
          std::vector<double> w(k);
          for (size_t i = 0; i < k; ++i) w[i] = idx[i] * step;
          const Score a = evaluate(D, n, w, tune_c, items), b = evaluate(D, n, w, tune_g, items);
          const double obj = 0.5 * (a.mrr + b.mrr), top1 = 0.5 * (a.top1 + b.top1);
          if (obj > best + 1e-12 || (std::abs(obj - best) <= 1e-12 && top1 > best_top1)) {
            best = obj;
            best_top1 = top1;
            best_w = w;
          }
          return;
        }
        for (int v = 0; v <= left; ++v) {
          idx[c] = v;
          rec(c + 1, left - v);
        }
      };
      rec(0, steps);
      std::printf("\nWeight fit (grid step %.2f on the tune split, %zu + %zu queries, objective mean MRR "
                  "colour/grey): best %s -> MRR %.3f, top-1 %.1f%%\n",
                  step, tune_c.size(), tune_g.size(), weights_str(best_w).c_str(), best, 100 * best_top1);
    }

    if (structure_groups) {
      // Each structure feature group alone (unit-scaled mean square), on the tune split; then a
      // coordinate-descent fit of the group weights on the same split (structure alone, MRR).
      size_t sc = 0;
      while (sc < k && t.metrics[sc]->id() != "structure") ++sc;
      const std::vector<int> pool = tune_g;
      const auto groups = metrics::StructureMetric::groups();
      std::vector<std::vector<float>> G(groups.size(), std::vector<float>(n * n, 0.0f));
      size_t at = 0;
      for (size_t gi = 0; gi < groups.size(); ++gi) {
        const auto& g = groups[gi];
        for (int i : pool)
          for (int j : pool) {
            double s2 = 0;
            for (int e = 0; e < g.size; ++e) {
              const double d = (static_cast<double>(t.f[sc][i][at + e]) - t.f[sc][j][at + e]) / g.unit;
              s2 += d * d;
            }
            G[gi][static_cast<size_t>(i) * n + j] = static_cast<float>(s2 / g.size);
          }
        at += g.size;
      }
      std::printf("\nStructure groups (tune split):\n\n| group | top-1 alone | MRR alone | current weight |\n|---|---|---|---|\n");
      std::vector<double> gw;
      for (size_t gi = 0; gi < groups.size(); ++gi) {
        std::vector<double> w(groups.size(), 0.0);
        w[gi] = 1.0;
        const Score r = evaluate(G, n, w, pool, items);
        std::printf("| %s | %.1f%% | %.3f | %.2f |\n", groups[gi].name, 100 * r.top1, r.mrr, groups[gi].weight);
        gw.push_back(groups[gi].weight);
      }
      // Ranking by sum w_g ms_g equals ranking by the structure distance sqrt(sum w ms / sum w).
      double best_g = evaluate(G, n, gw, pool, items).mrr;
      std::printf("\ncurrent group weights: MRR %.3f\n", best_g);
      const double options[] = {0.0, 0.125, 0.25, 0.5, 1.0, 2.0, 4.0};
      for (int pass = 0; pass < 3; ++pass)
        for (size_t gi = 0; gi < groups.size(); ++gi)
          for (double v : options) {
            std::vector<double> w = gw;
            w[gi] = v;
            if (std::all_of(w.begin(), w.end(), [](double x) { return x == 0; })) continue;
            const double m = evaluate(G, n, w, pool, items).mrr;
            if (m > best_g + 1e-9) {
              best_g = m;
              gw = w;
            }
          }
      std::printf("fitted group weights:");
      for (size_t gi = 0; gi < groups.size(); ++gi) std::printf(" %s %.3f", groups[gi].name, gw[gi]);
      std::printf(" -> MRR %.3f\n", best_g);
    }

    struct Row {
      std::string name;
      std::vector<double> w;
    };
    std::vector<Row> rows;
    for (size_t c = 0; c < k; ++c) {
      std::vector<double> w(k, 0.0);
      w[c] = 1.0;
      rows.push_back({t.metrics[c]->id(), w});
    }
    rows.push_back({"composite, equal weights", std::vector<double>(k, 1.0 / k)});
    rows.push_back({"composite, fitted on tune (" + weights_str(best_w) + ")", best_w});
    rows.push_back({"**default** (calibration.h: " + weights_str(current) + ")", current});

    auto table = [&](const std::string& title, std::initializer_list<int> splits) {
      const std::vector<int> pc = pool_of(items, splits, false), pg = pool_of(items, splits, true);
      if (pc.empty()) return;
      std::set<std::string> classes;
      for (int i : pc) classes.insert(items[i].texture);
      std::printf("\n### %s: %zu images, %zu textures\n\n", title.c_str(), pc.size(), classes.size());
      std::printf("| metric | top-1 colour | MRR colour | top-1 grey | MRR grey |\n|---|---|---|---|---|\n");
      for (const Row& r : rows) {
        const Score a = evaluate(D, n, r.w, pc, items), b = evaluate(D, n, r.w, pg, items);
        std::printf("| %s | %.1f%% | %.3f | %.1f%% | %.3f |\n", r.name.c_str(), 100 * a.top1, a.mrr,
                    100 * b.top1, b.mrr);
      }
      std::fflush(stdout);
    };
    table("photos (" + std::to_string(grid) + " x " + std::to_string(grid) + " crops)", {kPhoto});
    table("shaders, report split (odd specs)", {kReport});
    table("**report split + photos** (the headline)", {kReport, kPhoto});
    table("shaders, tune split (even specs; the weights were fitted here)", {kTune});

    // Where the default metric fails: top-1 per source in the report split + photos (colour, grey).
    {
      std::map<std::string, std::pair<int, int>> pc, pg;
      std::vector<std::map<std::string, std::pair<int, int>>> single(k), single_g(k);
      evaluate(D, n, current, pool_of(items, {kReport, kPhoto}, false), items, &pc);
      evaluate(D, n, current, pool_of(items, {kReport, kPhoto}, true), items, &pg);
      for (size_t c = 0; c < k; ++c) {
        std::vector<double> w(k, 0.0);
        w[c] = 1.0;
        evaluate(D, n, w, pool_of(items, {kReport, kPhoto}, false), items, &single[c]);
      }
      std::printf("\n### top-1 per source (report split + photos; colour unless marked)\n\n| source | queries |");
      for (size_t c = 0; c < k; ++c) std::printf(" %s |", t.metrics[c]->id().c_str());
      std::printf(" default | default grey |\n|---|---|");
      for (size_t c = 0; c < k + 2; ++c) std::printf("---|");
      std::printf("\n");
      for (const auto& [src, hq] : pc) {
        std::printf("| %s | %d |", src.c_str(), hq.second);
        for (size_t c = 0; c < k; ++c) std::printf(" %.0f%% |", 100.0 * single[c][src].first / single[c][src].second);
        std::printf(" %.0f%% | %.0f%% |\n", 100.0 * hq.first / hq.second,
                    100.0 * pg[src].first / std::max(1, pg[src].second));
      }
    }

    std::printf("\nFeature time per image (this run, all items): prepare %.2f ms", t.prepare_ms);
    double total = t.prepare_ms;
    for (size_t c = 0; c < k; ++c) {
      std::printf(", %s %.2f ms", t.metrics[c]->id().c_str(), t.ms[c]);
      total += t.ms[c];
    }
    std::printf("; composite %.2f ms\n", total);
  } catch (const proctex::Error& e) {
    std::fprintf(stderr, "error: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
