#pragma once
// Adaptive random sampling of one shader's parameter domain (Bourque thesis section 4.3) and the
// uniform baseline. The result is an in-memory ShaderCatalogue; catalog/store.h writes it to SQLite
// in one transaction.
//
// Thesis terms and where they live here (see docs/catalog.md for the full rationale):
//   omega  closeness threshold: a candidate whose similarity to a vertex exceeds it is dropped
//   H      local smoothness, eq 4.2: mean over probes d near x of (1 - S(x, d)) / ||x - d||
//   kappa  coverage, eq 4.3 as printed: (1/|E|) (sum_{l<m} (1 - e_lm)^sigma)^(1/sigma)
//   gamma  isolation, eq 4.4: alpha H(v)/max H + beta min_f (1 - e(v, f))  -- the text's
//          "distance to the nearest neighbour" (min); the printed max would pick the vertex with
//          the farthest partner, which every vertex has.
//   lambda redundancy, eq 4.5: sum_m e(v, m); pruning removes the largest lambda one vertex at a
//          time, updating lambda after each removal (so a cluster keeps one representative).
//          Measured against uniform probes, lambda pruning spreads samples towards the extremes of
//          the texture range and lowers the coverage of typical textures (docs/catalog.md), so the
//          default pruning ("coverage") removes instead the vertex whose loss costs the least
//          coverage of the reference candidates (every globally drawn, uniformly random candidate
//          rendered so far): "most similar to others" measured as redundancy. prune=lambda
//          selects eq 4.5 as printed.
// The adaptive loop runs on cheap "screen" renders (screen_resolution, default 64 px); only the
// kept vertices are rendered at the analysis resolution, and the stored features, edges and
// pruned graph come from those.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "metrics/metric.h"
#include "shaders/renderer.h"
#include "shaders/shader.h"

namespace proctex::catalog {

// Samples kept per shader by default. The thesis used about 200; 48 match photos as well (the same
// 43 report-split answers), recover more deterministic targets exactly (17/18 against 13/18), make
// a match about 20 % faster and the catalogue 4-5x faster to build (docs/performance.md, sessions
// 15 and 17).
inline constexpr int kDefaultSamples = 48;

struct SamplingSettings {
  std::string mode = "adaptive";  // "adaptive" | "uniform"
  std::string metric = "composite";
  int samples = kDefaultSamples;  // N_i: maximum vertices kept per shader
  int resolution = 256;          // render and analysis size of stored samples
  int screen_resolution = 64;    // render and analysis size inside the adaptive loop
  int thumbnail = 64;            // PNG thumbnail side stored per sample
  double omega = 0.85;           // closeness threshold (screen similarity)
  double initial_factor = 3.0;   // construction: k = initial_factor * N random candidates
  double global_factor = 0.5;    // refinement: k = global_factor * N global candidates / iteration
  double isolated_factor = 0.125;  // refinement: q = isolated_factor * N most isolated vertices
  int local_per_isolated = 2;    // local candidates around each isolated vertex
  double local_radius = 0.08;    // half side of the local box in unit parameter space
  int smoothness_probes = 1;     // |D| rendered for a vertex (local refinement adds more to D)
  double smoothness_radius = 0.05;
  double alpha = 0.5;            // gamma weights (eq 4.4)
  double beta = 0.5;
  double sigma = 2.0;            // kappa exponent (eq 4.3)
  double kappa_threshold = 0.0;  // stop when kappa <= this (0: off, see docs/catalog.md)
  double coverage_target = 0.9;  // stop when this fraction of fresh global candidates is within omega
  double coverage_tolerance = 0.003;  // stop when fresh candidates' mean best similarity gains less
  std::string prune = "coverage";  // pruning criterion: "coverage" or "lambda" (eq 4.5 as printed)
  int max_iterations = 4;        // refinement + pruning iterations
  int pruned_samples = 0;        // size of the highly pruned graph (0: max(4, N / 10))
  int probes = 32;               // P: coverage probes (0: no coverage measurement)
  int batch = 32;                // images per render launch at the analysis resolution

  nlohmann::json to_json() const;
  // Unknown keys and bad values throw UsageError naming the key.
  static SamplingSettings from_json(const nlohmann::json& j);
  void apply(const std::string& key, const std::string& value);  // "--set key=value"
  void validate() const;
  int pruned_target() const;
  // Stable hash of everything that changes the result (with the metric version): incremental builds.
  std::string hash(uint64_t seed) const;
};

struct Sample {
  std::vector<float> unit;    // normalised parameter vector (searchable dims, in [0, 1])
  std::vector<float> packed;  // full packed vector the shader received
  uint32_t seed = 0;
  double smoothness = -1;     // H (eq 4.2); -1 = not computed (uniform mode)
  std::vector<unsigned char> thumbnail;  // PNG
  metrics::Features features;
};

struct Coverage {
  int probes = 0;
  double mean = 0, median = 0, p10 = 0, min = 0, max = 0;
  std::vector<double> best;  // best similarity of each probe to the catalogue
  nlohmann::json to_json() const;
};

struct ShaderCatalogue {
  std::string shader, family, source_hash, settings_hash;
  nlohmann::json declaration;  // parameters as data
  SamplingSettings settings;
  uint64_t seed = 0;           // build seed
  std::vector<Sample> samples;
  std::vector<double> edges;   // n x n similarity matrix (row-major, symmetric, diagonal 1)
  std::vector<int> pruned;     // sample indices of the highly pruned graph
  Coverage coverage;
  nlohmann::json stats;        // kappa per iteration, candidate counts, timings, device
  std::string content_hash;    // hash of vectors, seeds, features and graphs (merge conflicts)

  double edge(int a, int b) const { return edges[size_t(a) * samples.size() + b]; }
  void finalise_hash();
};

struct SamplingProgress {
  std::string stage;  // "construct", "refine 2/6", "render", "coverage"
  double fraction = 0;
};

// Builds one shader's catalogue. `jobs` threads compute features; renders go through `renderer`
// in batches. Deterministic: same seed, declaration and settings -> same sample vectors.
ShaderCatalogue sample_shader(const ShaderDecl& decl, const SamplingSettings& settings, uint64_t seed,
                              Renderer& renderer, int jobs,
                              const std::function<void(const SamplingProgress&)>& progress = {});

// Coverage of a set of sample features: renders `settings.probes` random vectors (their own seed
// stream, not in the catalogue) and reports the distribution of their best similarity.
Coverage measure_coverage(const ShaderDecl& decl, const std::vector<Sample>& samples, const SamplingSettings& settings,
                          uint64_t seed, Renderer& renderer, int jobs);

// Kappa (eq 4.3 as printed) of an n x n similarity matrix.
double kappa(const std::vector<double>& sims, int n, double sigma);
// Iterative lambda pruning (eq 4.5): the indices (ascending) of the `keep` vertices that remain.
std::vector<int> prune(const std::vector<double>& sims, int n, int keep);
// Coverage pruning: `ref_sims` is R x V (similarity of reference r to vertex v). Removes, one at a
// time, the vertex whose removal lowers sum_r max_v S(r, v) the least; returns the kept indices.
std::vector<int> prune_coverage(const std::vector<double>& ref_sims, int R, int V, int keep);

// Render seed of every sample of a shader: derived from the build seed and the shader name.
uint32_t render_seed(uint64_t seed, const std::string& shader);
// Deterministic 64-bit mixing (splitmix64) used for every random stream of the catalogue.
uint64_t mix64(uint64_t x);
uint64_t hash_string(uint64_t seed, const std::string& s);

}  // namespace proctex::catalog
