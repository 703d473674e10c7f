#include "catalog/sampling.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <thread>

#include "catalog/thumbnail.h"
#include "core/error.h"
#include "core/parallel.h"
#include "kernels/runtime.h"
#include "shaders/parameter_space.h"

namespace proctex::catalog {

// ---------------------------------------------------------------------------------------------
// Settings

nlohmann::json SamplingSettings::to_json() const {
  return {{"mode", mode}, {"metric", metric}, {"samples", samples}, {"resolution", resolution},
          {"screen_resolution", screen_resolution}, {"thumbnail", thumbnail}, {"omega", omega},
          {"initial_factor", initial_factor}, {"global_factor", global_factor},
          {"isolated_factor", isolated_factor}, {"local_per_isolated", local_per_isolated},
          {"local_radius", local_radius}, {"smoothness_probes", smoothness_probes},
          {"smoothness_radius", smoothness_radius}, {"alpha", alpha}, {"beta", beta}, {"sigma", sigma},
          {"kappa_threshold", kappa_threshold}, {"coverage_target", coverage_target}, {"coverage_tolerance", coverage_tolerance}, {"prune", prune},
          {"max_iterations", max_iterations}, {"pruned_samples", pruned_samples}, {"probes", probes},
          {"batch", batch}};
}

SamplingSettings SamplingSettings::from_json(const nlohmann::json& j) {
  SamplingSettings s;
  const nlohmann::json known = s.to_json();
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!known.contains(it.key()))
      throw UsageError("unknown catalogue setting '" + it.key() + "'",
                       "settings: " + [&] {
                         std::string names;
                         for (auto k = known.begin(); k != known.end(); ++k) names += (names.empty() ? "" : ", ") + k.key();
                         return names;
                       }());
  }
  try {
    auto get = [&](const char* key, auto& field) {
      if (j.contains(key)) field = j.at(key).get<std::decay_t<decltype(field)>>();
    };
    get("mode", s.mode); get("metric", s.metric); get("samples", s.samples); get("resolution", s.resolution);
    get("screen_resolution", s.screen_resolution); get("thumbnail", s.thumbnail); get("omega", s.omega);
    get("initial_factor", s.initial_factor); get("global_factor", s.global_factor);
    get("isolated_factor", s.isolated_factor); get("local_per_isolated", s.local_per_isolated);
    get("local_radius", s.local_radius); get("smoothness_probes", s.smoothness_probes);
    get("smoothness_radius", s.smoothness_radius); get("alpha", s.alpha); get("beta", s.beta);
    get("sigma", s.sigma); get("kappa_threshold", s.kappa_threshold); get("coverage_target", s.coverage_target);
    get("coverage_tolerance", s.coverage_tolerance); get("prune", s.prune);
    get("max_iterations", s.max_iterations); get("pruned_samples", s.pruned_samples); get("probes", s.probes);
    get("batch", s.batch);
  } catch (const nlohmann::json::exception& e) {
    throw UsageError(std::string("bad catalogue setting: ") + e.what(), "numbers for thresholds, strings for mode and metric");
  }
  return s;
}

void SamplingSettings::apply(const std::string& key, const std::string& value) {
  nlohmann::json j = to_json();
  if (!j.contains(key)) from_json({{key, 0}});  // throws the "unknown setting" error
  nlohmann::json v;
  if (j[key].is_string()) {
    v = value;
  } else {
    try {
      size_t used = 0;
      const double d = std::stod(value, &used);
      if (used != value.size()) throw std::invalid_argument(value);
      if (j[key].is_number_integer()) {
        if (d != std::floor(d)) throw std::invalid_argument(value);
        v = static_cast<int>(d);
      } else {
        v = d;
      }
    } catch (const std::exception&) {
      throw UsageError("catalogue setting '" + key + "' needs a number, got '" + value + "'",
                       "e.g. --set " + key + "=" + j[key].dump());
    }
  }
  j[key] = v;
  *this = from_json(j);
}

void SamplingSettings::validate() const {
  auto bad = [](const std::string& what, const std::string& hint) { throw UsageError(what, hint); };
  if (mode != "adaptive" && mode != "uniform") bad("sampling mode must be adaptive or uniform, got '" + mode + "'", "use --mode adaptive or --mode uniform");
  if (samples < 1 || samples > 100000) bad("--samples must be in [1, 100000], got " + std::to_string(samples), "the default is " + std::to_string(kDefaultSamples) + "; the thesis used about 200");
  auto check_res = [&](const char* name, int r) {
    if (r < metrics::kMinResolution || r > metrics::kMaxResolution || r % 16 != 0)
      bad(std::string(name) + " must be a multiple of 16 in [64, 4096], got " + std::to_string(r), "use 64, 128 or 256");
  };
  check_res("resolution", resolution);
  check_res("screen_resolution", screen_resolution);
  if (screen_resolution > resolution) bad("screen_resolution must not exceed resolution", "use --set screen_resolution=64");
  if (thumbnail < 8 || thumbnail > 1024) bad("thumbnail must be in [8, 1024]", "use 64");
  if (!(omega > 0 && omega <= 1)) bad("omega must be in (0, 1]", "0.85 keeps near-duplicates out");
  if (!(initial_factor > 0) || !(global_factor >= 0) || !(isolated_factor >= 0)) bad("sampling factors must be positive", "see docs/catalog.md");
  if (local_per_isolated < 0 || smoothness_probes < 0) bad("sample counts must be >= 0", "see docs/catalog.md");
  if (!(local_radius > 0 && local_radius <= 1) || !(smoothness_radius > 0 && smoothness_radius <= 1))
    bad("radii must be in (0, 1]", "they are distances in the unit parameter cube");
  if (prune != "coverage" && prune != "lambda") bad("prune must be coverage or lambda, got '" + prune + "'", "see docs/catalog.md");
  if (!(sigma >= 1)) bad("sigma must be >= 1", "2 is the default");
  if (max_iterations < 0 || max_iterations > 1000) bad("max_iterations must be in [0, 1000]", "6 is the default");
  if (pruned_samples < 0 || probes < 0 || probes > 100000) bad("pruned_samples and probes must be >= 0", "see docs/catalog.md");
  if (batch < 1 || batch > 1024) bad("batch must be in [1, 1024]", "16 to 64 images per launch");
  metrics::get_metric(metric);
}

int SamplingSettings::pruned_target() const {
  return pruned_samples > 0 ? std::min(pruned_samples, samples) : std::min(samples, std::max(4, samples / 10));
}

uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

uint64_t hash_string(uint64_t seed, const std::string& s) {
  uint64_t h = mix64(seed);
  for (unsigned char c : s) h = mix64(h ^ c);
  return h;
}

std::string SamplingSettings::hash(uint64_t seed) const {
  const auto& m = metrics::get_metric(metric);
  nlohmann::json j = to_json();
  j.erase("batch");  // launch size does not change results
  j["metric"] = m.id();
  j["metric_version"] = m.version();
  j["seed"] = std::to_string(seed);
  return stable_hash(j.dump());
}

uint32_t render_seed(uint64_t seed, const std::string& shader) {
  return static_cast<uint32_t>(hash_string(seed, "render:" + shader) & 0x7fffffffu);
}

nlohmann::json Coverage::to_json() const {
  return {{"probes", probes}, {"mean", mean}, {"median", median}, {"p10", p10}, {"min", min}, {"max", max}};
}

void ShaderCatalogue::finalise_hash() {
  std::string data;
  auto add = [&](const void* p, size_t n) { data.append(static_cast<const char*>(p), n); };
  for (const auto& s : samples) {
    add(s.unit.data(), s.unit.size() * 4);
    add(s.packed.data(), s.packed.size() * 4);
    add(&s.seed, 4);
    data += s.features.metric + std::to_string(s.features.version);
    add(s.features.values.data(), s.features.values.size() * 4);
  }
  for (int p : pruned) add(&p, 4);
  content_hash = stable_hash(data);
}

// ---------------------------------------------------------------------------------------------
// Graph measures

double kappa(const std::vector<double>& sims, int n, double sigma) {
  if (n < 2) return 0.0;
  double sum = 0;
  for (int l = 0; l < n; ++l)
    for (int m = l + 1; m < n; ++m) sum += std::pow(std::max(0.0, 1.0 - sims[size_t(l) * n + m]), sigma);
  const double edges = 0.5 * double(n) * (n - 1);
  return std::pow(sum, 1.0 / sigma) / edges;
}

std::vector<int> prune(const std::vector<double>& sims, int n, int keep) {
  std::vector<char> alive(n, 1);
  std::vector<double> lambda(n, 0.0);
  for (int l = 0; l < n; ++l)
    for (int m = 0; m < n; ++m)
      if (m != l) lambda[l] += sims[size_t(l) * n + m];
  for (int count = n; count > keep; --count) {
    int worst = -1;
    for (int l = 0; l < n; ++l)
      if (alive[l] && (worst < 0 || lambda[l] > lambda[worst])) worst = l;
    if (worst < 0) break;
    alive[worst] = 0;
    for (int l = 0; l < n; ++l)
      if (alive[l]) lambda[l] -= sims[size_t(l) * n + worst];
  }
  std::vector<int> out;
  for (int l = 0; l < n; ++l)
    if (alive[l]) out.push_back(l);
  return out;
}

std::vector<int> prune_coverage(const std::vector<double>& ref_sims, int R, int V, int keep) {
  std::vector<char> alive(V, 1);
  std::vector<int> best(R, -1), second(R, -1);
  auto at = [&](int r, int v) { return ref_sims[size_t(r) * V + v]; };
  auto rank = [&](int r) {
    best[r] = second[r] = -1;
    for (int v = 0; v < V; ++v) {
      if (!alive[v]) continue;
      if (best[r] < 0 || at(r, v) > at(r, best[r])) {
        second[r] = best[r];
        best[r] = v;
      } else if (second[r] < 0 || at(r, v) > at(r, second[r])) {
        second[r] = v;
      }
    }
  };
  for (int r = 0; r < R; ++r) rank(r);
  for (int count = V; count > keep; --count) {
    // Loss of removing v: what the references it serves best fall back to.
    std::vector<double> loss(V, 0.0);
    for (int r = 0; r < R; ++r)
      if (best[r] >= 0) loss[best[r]] += at(r, best[r]) - (second[r] >= 0 ? at(r, second[r]) : 0.0);
    int victim = -1;
    for (int v = 0; v < V; ++v)
      if (alive[v] && (victim < 0 || loss[v] < loss[victim])) victim = v;
    if (victim < 0) break;
    alive[victim] = 0;
    for (int r = 0; r < R; ++r)
      if (best[r] == victim || second[r] == victim) rank(r);
  }
  std::vector<int> out;
  for (int v = 0; v < V; ++v)
    if (alive[v]) out.push_back(v);
  return out;
}

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Portable random stream: splitmix64, doubles from the top 53 bits (std distributions are
// implementation-defined, which would break "same seed -> same catalogue" across compilers).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() { return mix64(state_++ * 0x2545f4914f6cdd1dULL + 0x632be59bd9b4e019ULL); }
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }

 private:
  uint64_t state_;
};

struct Point {
  std::vector<double> unit;  // snapped
  std::vector<float> packed;
};

// Everything one shader's build needs: parameter space, render + features helpers, timings.
class Sampler {
 public:
  Sampler(const ShaderDecl& decl, const SamplingSettings& s, uint64_t seed, Renderer& renderer, int jobs,
          const std::function<void(const SamplingProgress&)>& progress)
      : decl_(decl), s_(s), space_(decl), metric_(metrics::get_metric(s.metric)), renderer_(renderer),
        jobs_(jobs), progress_(progress), render_seed_(render_seed(seed, decl.name)),
        rng_(hash_string(seed, "samples:" + decl.name)) {}

  ShaderCatalogue run();
  const ParameterSpace& space() const { return space_; }

  Point make_point(std::vector<double> unit) const {
    Point p;
    p.unit = space_.snap(unit);
    for (auto& u : p.unit) u = std::clamp(u, 0.0, 1.0);
    // Round-trip through float: the stored vector is float32, and the renders must match it.
    for (auto& u : p.unit) u = static_cast<double>(static_cast<float>(u));
    p.packed = space_.to_packed(p.unit);
    return p;
  }
  Point random_point() {
    std::vector<double> u(space_.dimensions());
    for (auto& x : u) x = rng_.uniform();
    return make_point(std::move(u));
  }
  Point near_point(const std::vector<double>& centre, double radius) {
    std::vector<double> u(centre);
    for (auto& x : u) x += radius * (2.0 * rng_.uniform() - 1.0);
    return make_point(std::move(u));
  }

  // Renders points at `size` in launches of `per_launch` and computes features (jobs threads).
  // `keep` receives each image before it is dropped (thumbnails).
  std::vector<std::vector<float>> features(const std::vector<Point>& pts, int size,
                                           const std::function<void(size_t, const Image&)>& keep = {}) {
    std::vector<std::vector<float>> out(pts.size());
    const size_t per_launch = size <= 64 ? 64 : size_t(s_.batch);
    for (size_t first = 0; first < pts.size(); first += per_launch) {
      const size_t count = std::min(per_launch, pts.size() - first);
      std::vector<std::vector<float>> packed;
      for (size_t i = 0; i < count; ++i) packed.push_back(pts[first + i].packed);
      RenderSettings rs;
      rs.width = rs.height = size;
      auto t0 = Clock::now();
      const std::vector<Image> images =
          renderer_.render_batch(decl_, packed, std::vector<uint32_t>(count, render_seed_), rs);
      timings_[size == s_.resolution ? "render" : "screen_render"] += since(t0);
      renders_ += count;
      t0 = Clock::now();
      parallel_for(count, jobs_, [&](size_t i) {
        out[first + i] = metric_.features(images[i], size).values;
        if (keep) keep(first + i, images[i]);
      });
      timings_[size == s_.resolution ? "features" : "screen_features"] += since(t0);
    }
    return out;
  }

  void report(const std::string& stage, double fraction) {
    if (progress_) progress_({stage, std::clamp(fraction, 0.0, 1.0)});
  }

  uint32_t seed() const { return render_seed_; }
  const metrics::Metric& metric() const { return metric_; }
  std::map<std::string, double>& timings() { return timings_; }
  long renders() const { return renders_; }
  int jobs() const { return jobs_; }

 private:
  const ShaderDecl& decl_;
  const SamplingSettings& s_;
  ParameterSpace space_;
  const metrics::Metric& metric_;
  Renderer& renderer_;
  int jobs_;
  std::function<void(const SamplingProgress&)> progress_;
  uint32_t render_seed_;
  Rng rng_;
  std::map<std::string, double> timings_;
  long renders_ = 0;
};

// The graph of the adaptive loop, at the screen resolution.
struct Graph {
  std::vector<Point> points;
  std::vector<std::vector<float>> feats;
  std::vector<double> h_sum;     // eq 4.2 accumulated: sum of (1 - S) / ||x - d|| over D
  std::vector<int> h_count;      // |D| so far
  std::vector<std::vector<double>> sims;  // symmetric, grown row by row
  std::vector<std::vector<double>> ref_sims;  // per vertex: similarity to each reference candidate

  int size() const { return static_cast<int>(points.size()); }
  double H(int v) const { return h_count[v] ? h_sum[v] / h_count[v] : 0.0; }
};

}  // namespace

ShaderCatalogue sample_shader(const ShaderDecl& decl, const SamplingSettings& settings, uint64_t seed,
                              Renderer& renderer, int jobs, const std::function<void(const SamplingProgress&)>& progress) {
  settings.validate();
  const auto t_total = Clock::now();
  Sampler sm(decl, settings, seed, renderer, jobs, progress);
  const int dims = sm.space().dimensions();
  const int N = settings.samples;
  const metrics::Metric& metric = sm.metric();
  nlohmann::json stats = nlohmann::json::object();

  std::vector<Point> kept;
  std::vector<double> kept_H;
  std::vector<std::vector<float>> screen_feats;

  if (settings.mode == "uniform" || dims == 0) {
    // Uniform random sampling: N independent uniform vectors (discrete dims snapped), no adaptation.
    const int n = dims == 0 ? 1 : N;
    for (int i = 0; i < n; ++i) kept.push_back(sm.random_point());
    kept_H.assign(kept.size(), -1.0);
    stats["candidates"] = n;
    stats["iterations"] = 0;
    stats["stop"] = dims == 0 ? "no searchable parameters" : "uniform";
  } else {
    Graph g;
    long candidates = 0, rejected = 0, duplicates = 0;
    const int screen = settings.screen_resolution;
    // Adds candidates in order; a candidate too similar (> omega) to a vertex is dropped.
    // Returns how many of them were within omega of the graph as it stood before this batch.
    auto distance = [&](const std::vector<double>& a, const std::vector<double>& b) {
      double d = 0;
      for (int i = 0; i < dims; ++i) d += (a[i] - b[i]) * (a[i] - b[i]);
      return std::sqrt(d);
    };
    // `parents[i]` is the vertex a local candidate was drawn around (-1 for global ones): the pair
    // is one more point of D for both in eq 4.2, so local refinement sharpens H for free (the
    // thesis: "new points can be added incrementally").
    std::vector<std::vector<float>> refs;  // features of every global (uniform) candidate
    double fresh_mean_best = 0;            // of the last global batch, before it was added
    auto add_candidates = [&](std::vector<Point> cands, std::vector<int> parents) {
      const bool global = parents.empty();
      parents.resize(cands.size(), -1);
      // Exact duplicates after snapping (discrete-only neighbourhoods) are dropped unrendered.
      std::vector<Point> fresh;
      std::vector<int> fresh_parent;
      for (size_t i = 0; i < cands.size(); ++i) {
        auto& c = cands[i];
        bool dup = false;
        for (const auto& p : g.points) dup = dup || p.unit == c.unit;
        for (const auto& p : fresh) dup = dup || p.unit == c.unit;
        if (dup) {
          ++duplicates;
        } else {
          fresh.push_back(std::move(c));
          fresh_parent.push_back(parents[i]);
        }
      }
      const long covered_dups = static_cast<long>(cands.size() - fresh.size());
      candidates += static_cast<long>(cands.size());
      const auto feats = sm.features(fresh, screen);
      if (global) refs.insert(refs.end(), feats.begin(), feats.end());
      const int before = g.size();
      long covered = covered_dups;
      double sum_best = static_cast<double>(covered_dups);
      for (size_t c = 0; c < fresh.size(); ++c) {
        std::vector<double> row(g.size());
        double best = 0, best_old = 0;
        for (int v = 0; v < g.size(); ++v) {
          row[v] = metric.similarity(feats[c], g.feats[v]);
          best = std::max(best, row[v]);
          if (v < before) best_old = std::max(best_old, row[v]);
        }
        if (best_old > settings.omega) ++covered;
        sum_best += best_old;
        const int parent = fresh_parent[c];
        double h_term = -1;
        if (parent >= 0 && parent < before) {
          h_term = (1.0 - row[parent]) / std::max(1e-9, distance(fresh[c].unit, g.points[parent].unit));
          g.h_sum[parent] += h_term;
          ++g.h_count[parent];
        }
        if (best > settings.omega) {
          ++rejected;
          continue;
        }
        for (int v = 0; v < g.size(); ++v) g.sims[v].push_back(row[v]);
        row.push_back(1.0);
        g.sims.push_back(std::move(row));
        g.points.push_back(fresh[c]);
        g.feats.push_back(feats[c]);
        g.h_sum.push_back(h_term >= 0 ? h_term : 0.0);
        g.h_count.push_back(h_term >= 0 ? 1 : 0);
        g.ref_sims.emplace_back();
      }
      if (!cands.empty()) fresh_mean_best = sum_best / double(cands.size());
      return cands.empty() ? 0.0 : double(covered) / double(cands.size());
    };
    // H (eq 4.2) for every vertex that lacks it: |D| probes in a box around x, rendered at the
    // screen resolution; distances in the unit cube after snapping (probes that snap back onto x
    // are not rendered: they carry no information).
    auto compute_smoothness = [&](const std::vector<int>& which) {
      const auto t0 = Clock::now();
      std::vector<Point> probes;
      std::vector<int> owner;
      std::vector<int> todo;
      for (int v : which) {
        if (g.h_count[v] > 0) continue;
        todo.push_back(v);
        for (int k = 0; k < settings.smoothness_probes; ++k) {
          Point p = sm.near_point(g.points[v].unit, settings.smoothness_radius);
          if (p.unit == g.points[v].unit) continue;
          probes.push_back(std::move(p));
          owner.push_back(v);
        }
      }
      const auto feats = sm.features(probes, screen);
      for (size_t i = 0; i < probes.size(); ++i) {
        const int v = owner[i];
        g.h_sum[v] += (1.0 - metric.similarity(feats[i], g.feats[v])) / distance(probes[i].unit, g.points[v].unit);
        ++g.h_count[v];
      }
      for (int v : todo)
        if (g.h_count[v] == 0) g.h_count[v] = 1;  // every probe snapped back onto x: flat, H = 0
      sm.timings()["smoothness"] += since(t0);
      return static_cast<long>(probes.size());
    };
    auto prune_graph = [&] {
      if (g.size() <= N) return;
      const auto t0 = Clock::now();
      const int n = g.size();
      std::vector<int> keep;
      if (settings.prune == "lambda") {
        std::vector<double> flat(size_t(n) * n);
        for (int l = 0; l < n; ++l)
          for (int m = 0; m < n; ++m) flat[size_t(l) * n + m] = g.sims[l][m];
        keep = prune(flat, n, N);
      } else {
        // Bring every vertex's similarities to the references up to date (parallel), then prune.
        const int R = static_cast<int>(refs.size());
        parallel_for(size_t(n), sm.jobs(), [&](size_t v) {
          auto& col = g.ref_sims[v];
          for (int r = static_cast<int>(col.size()); r < R; ++r) col.push_back(metric.similarity(refs[r], g.feats[v]));
        });
        std::vector<double> flat(size_t(R) * n);
        for (int r = 0; r < R; ++r)
          for (int v = 0; v < n; ++v) flat[size_t(r) * n + v] = g.ref_sims[v][r];
        keep = prune_coverage(flat, R, n, N);
      }
      Graph h;
      for (int l : keep) {
        h.points.push_back(g.points[l]);
        h.feats.push_back(g.feats[l]);
        h.h_sum.push_back(g.h_sum[l]);
        h.h_count.push_back(g.h_count[l]);
        h.ref_sims.push_back(g.ref_sims[l]);
        std::vector<double> row;
        for (int m : keep) row.push_back(g.sims[l][m]);
        h.sims.push_back(std::move(row));
      }
      g = std::move(h);
      sm.timings()["prune"] += since(t0);
    };
    auto graph_kappa = [&] {
      const int n = g.size();
      std::vector<double> flat(size_t(n) * n);
      for (int l = 0; l < n; ++l)
        for (int m = 0; m < n; ++m) flat[size_t(l) * n + m] = g.sims[l][m];
      return kappa(flat, n, settings.sigma);
    };

    // 1. Construction.
    sm.report("construct", 0);
    {
      std::vector<Point> cands;
      const int k = std::max(1, static_cast<int>(std::lround(settings.initial_factor * N)));
      for (int i = 0; i < k; ++i) cands.push_back(sm.random_point());
      add_candidates(std::move(cands), {});
    }
    long smoothness_probes = 0;
    nlohmann::json kappas = nlohmann::json::array(), coverage_fractions = nlohmann::json::array(),
                   fresh_coverage = nlohmann::json::array();
    double last_fresh = -1;
    std::string stop = "iterations";
    int it = 0;
    // 2.-4. Refinement and pruning until the coverage test holds or the iteration cap.
    for (; it < settings.max_iterations; ++it) {
      sm.report("refine " + std::to_string(it + 1) + "/" + std::to_string(settings.max_iterations),
                0.1 + 0.5 * it / std::max(1, settings.max_iterations));
      const double k_now = graph_kappa();
      kappas.push_back(k_now);
      if (settings.kappa_threshold > 0 && k_now <= settings.kappa_threshold && g.size() >= N) {
        stop = "kappa";
        break;
      }
      // Global: k random candidates (at least enough to refill the graph to N).
      std::vector<Point> global;
      const int k = std::max(static_cast<int>(std::lround(settings.global_factor * N)),
                             static_cast<int>(std::ceil(1.2 * (N - g.size()))));
      for (int i = 0; i < k; ++i) global.push_back(sm.random_point());
      const int graph_before_global = g.size();
      const double covered = add_candidates(std::move(global), {});
      coverage_fractions.push_back(covered);
      fresh_coverage.push_back(fresh_mean_best);
      // Convergence compares batches measured against a graph already pruned to N (the first
      // batch meets the larger construction graph and would always look better).
      const bool comparable = graph_before_global <= N;
      const bool converged = comparable && last_fresh >= 0 && fresh_mean_best - last_fresh < settings.coverage_tolerance;
      if (comparable) last_fresh = fresh_mean_best;
      // Local: the q most isolated vertices (gamma, eq 4.4) get random neighbours. H costs renders,
      // so it is computed only for a shortlist: the 3q vertices farthest from their nearest
      // neighbour (the beta term), which is where the top q by gamma come from unless H dominates.
      const int n = g.size();
      const int q = std::min(n, static_cast<int>(std::lround(settings.isolated_factor * N)));
      std::vector<std::pair<double, int>> nearest(n);
      for (int v = 0; v < n; ++v) {
        double d = 1.0;  // min over f of (1 - e): distance to the nearest neighbour
        for (int f = 0; f < n; ++f)
          if (f != v) d = std::min(d, 1.0 - g.sims[v][f]);
        nearest[v] = {d, v};
      }
      std::vector<std::pair<double, int>> shortlist = nearest;
      std::stable_sort(shortlist.begin(), shortlist.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      shortlist.resize(std::min<size_t>(shortlist.size(), size_t(3 * q)));
      std::vector<int> which;
      for (const auto& [d, v] : shortlist) which.push_back(v);
      smoothness_probes += compute_smoothness(which);
      double max_h = 0;
      for (int v : which) max_h = std::max(max_h, g.H(v));
      std::vector<std::pair<double, int>> gamma;
      for (const auto& [d, v] : shortlist)
        gamma.push_back({settings.alpha * (max_h > 0 ? g.H(v) / max_h : 0.0) + settings.beta * d, v});
      std::stable_sort(gamma.begin(), gamma.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      std::vector<Point> local;
      std::vector<int> parents;
      for (int i = 0; i < std::min<int>(q, static_cast<int>(gamma.size())); ++i)
        for (int j = 0; j < settings.local_per_isolated; ++j) {
          local.push_back(sm.near_point(g.points[gamma[i].second].unit, settings.local_radius));
          parents.push_back(gamma[i].second);
        }
      add_candidates(std::move(local), std::move(parents));
      prune_graph();
      if (covered >= settings.coverage_target && g.size() >= std::min(N, 2)) {
        stop = "coverage";
        ++it;
        break;
      }
      if (converged && g.size() >= N) {
        stop = "converged";
        ++it;
        break;
      }
    }
    prune_graph();
    kappas.push_back(graph_kappa());
    kept = g.points;
    {
      std::vector<int> all(g.size());
      for (int v = 0; v < g.size(); ++v) all[v] = v;
      smoothness_probes += compute_smoothness(all);  // every kept vertex stores its H
    }
    for (int v = 0; v < g.size(); ++v) kept_H.push_back(g.H(v));
    screen_feats = g.feats;
    stats["candidates"] = candidates;
    stats["rejected"] = rejected;
    stats["duplicates"] = duplicates;
    stats["smoothness_probes"] = smoothness_probes;
    stats["iterations"] = it;
    stats["kappa"] = kappas;
    stats["covered_fraction"] = coverage_fractions;
    stats["fresh_coverage"] = fresh_coverage;
    stats["references"] = refs.size();
    stats["stop"] = stop;
  }

  // Final: the kept vertices at the analysis resolution -> stored features, thumbnails, edges.
  sm.report("render", 0.65);
  ShaderCatalogue cat;
  cat.shader = decl.name;
  cat.family = decl.family;
  cat.source_hash = decl.source_hash;
  cat.settings = settings;
  cat.settings.metric = metric.id();
  cat.settings_hash = settings.hash(seed);
  cat.seed = seed;
  const int n = static_cast<int>(kept.size());
  cat.samples.resize(n);
  std::vector<std::vector<float>> final_feats;
  auto thumb = [&](size_t i, const Image& img) {
    cat.samples[i].thumbnail = encode_png(img.width == settings.thumbnail ? img : resize(img, settings.thumbnail, settings.thumbnail));
  };
  if (settings.screen_resolution == settings.resolution && !screen_feats.empty()) {
    // Same size: the loop's features are the final ones; render only for the thumbnails.
    final_feats = screen_feats;
    std::vector<std::vector<float>> packed;
    for (const auto& p : kept) packed.push_back(p.packed);
    RenderSettings rs;
    rs.width = rs.height = settings.resolution;
    for (size_t first = 0; first < kept.size(); first += settings.batch) {
      const size_t count = std::min<size_t>(settings.batch, kept.size() - first);
      const auto t0 = Clock::now();
      std::vector<std::vector<float>> part(packed.begin() + first, packed.begin() + first + count);
      const auto images = renderer.render_batch(decl, part, std::vector<uint32_t>(count, sm.seed()), rs);
      sm.timings()["render"] += since(t0);
      parallel_for(count, jobs, [&](size_t i) { thumb(first + i, images[i]); });
    }
  } else {
    final_feats = sm.features(kept, settings.resolution, thumb);
  }
  for (int i = 0; i < n; ++i) {
    Sample& s = cat.samples[i];
    s.unit.assign(kept[i].unit.begin(), kept[i].unit.end());
    s.packed = kept[i].packed;
    s.seed = sm.seed();
    s.smoothness = kept_H[i];
    s.features = {metric.id(), metric.version(), settings.resolution, std::move(final_feats[i])};
  }
  sm.report("edges", 0.85);
  auto t0 = Clock::now();
  cat.edges.assign(size_t(n) * n, 1.0);
  parallel_for(size_t(n), jobs, [&](size_t l) {
    for (int m = static_cast<int>(l) + 1; m < n; ++m) {
      const double e = metric.similarity(cat.samples[l].features.values, cat.samples[m].features.values);
      cat.edges[l * n + m] = e;
      cat.edges[size_t(m) * n + l] = e;
    }
  });
  // The highly pruned graph: the same criterion on the final full graph (its vertices are the
  // references for coverage pruning).
  cat.pruned = settings.prune == "lambda" ? prune(cat.edges, n, std::min(n, settings.pruned_target()))
                                          : prune_coverage(cat.edges, n, n, std::min(n, settings.pruned_target()));
  stats["kappa_final"] = kappa(cat.edges, n, settings.sigma);
  sm.timings()["edges"] += since(t0);

  if (settings.probes > 0) {
    sm.report("coverage", 0.9);
    t0 = Clock::now();
    cat.coverage = measure_coverage(decl, cat.samples, settings, seed, renderer, jobs);
    sm.timings()["coverage"] += since(t0);
  }
  sm.timings()["total"] = since(t_total);
  stats["renders"] = sm.renders();
  stats["seconds"] = sm.timings();
  stats["device"] = ocl::Runtime::instance().device().name;
  stats["jobs"] = jobs;
  cat.stats = stats;
  nlohmann::json decl_json = nlohmann::json::array();
  for (const auto& p : decl.params) {
    decl_json.push_back({{"name", p.name}, {"type", to_string(p.type)}, {"default", p.default_value},
                         {"min", p.min}, {"max", p.max}, {"scale", to_string(p.scale)},
                         {"searchable", p.searchable}, {"enum", p.enum_values}, {"offset", p.offset}});
  }
  cat.declaration = {{"name", decl.name}, {"family", decl.family}, {"help", decl.help}, {"path", decl.path},
                     {"packed_size", decl.packed_size}, {"dimensions", dims}, {"params", decl_json}};
  cat.finalise_hash();
  sm.report("done", 1.0);
  return cat;
}

Coverage measure_coverage(const ShaderDecl& decl, const std::vector<Sample>& samples, const SamplingSettings& settings,
                          uint64_t seed, Renderer& renderer, int jobs) {
  Coverage cov;
  if (settings.probes <= 0 || samples.empty()) return cov;
  const metrics::Metric& metric = metrics::get_metric(settings.metric);
  ParameterSpace space(decl);
  Rng rng(hash_string(seed, "probes:" + decl.name));
  std::vector<std::vector<float>> packed;
  for (int i = 0; i < settings.probes; ++i) {
    std::vector<double> u(space.dimensions());
    for (auto& x : u) x = rng.uniform();
    u = space.snap(u);
    for (auto& x : u) x = static_cast<double>(static_cast<float>(std::clamp(x, 0.0, 1.0)));
    packed.push_back(space.to_packed(u));
  }
  RenderSettings rs;
  rs.width = rs.height = settings.resolution;
  cov.best.assign(packed.size(), 0.0);
  const uint32_t rseed = render_seed(seed, decl.name);
  for (size_t first = 0; first < packed.size(); first += settings.batch) {
    const size_t count = std::min<size_t>(settings.batch, packed.size() - first);
    std::vector<std::vector<float>> part(packed.begin() + first, packed.begin() + first + count);
    const auto images = renderer.render_batch(decl, part, std::vector<uint32_t>(count, rseed), rs);
    parallel_for(count, jobs, [&](size_t i) {
      const auto f = metric.features(images[i], settings.resolution).values;
      double best = 0;
      for (const auto& s : samples) best = std::max(best, metric.similarity(f, s.features.values));
      cov.best[first + i] = best;
    });
  }
  std::vector<double> sorted = cov.best;
  std::sort(sorted.begin(), sorted.end());
  cov.probes = static_cast<int>(sorted.size());
  double sum = 0;
  for (double v : sorted) sum += v;
  cov.mean = sum / sorted.size();
  cov.median = sorted[sorted.size() / 2];
  cov.p10 = sorted[sorted.size() / 10];
  cov.min = sorted.front();
  cov.max = sorted.back();
  return cov;
}

}  // namespace proctex::catalog
