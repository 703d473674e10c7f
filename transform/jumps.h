#pragma once
// Jump points between two shaders (thesis section 5.3): pairs (x in p_a, y in p_b) whose renders
// look alike, where a morph can cut from one shader to the other.
//   1. candidate regions: compare sparse samples of both shaders (the pruned catalogue graphs;
//      stored features, no render) and take the most similar pairs, each sample used once;
//   2. refine each pair by alternating local optimisation: optimise y against the render of x,
//      then x against the render of y, ... until a round gains less than the tolerance
//      (search::refine, NLopt, at a coarse resolution);
//   3. score the result at the catalogue resolution; a refinement that does not beat its start
//      there keeps the start pair (the coarse optimum is only a proxy).
// `proctex catalog link` stores them as jump edges (catalog::Store::write_jumps).
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catalog/store.h"
#include "shaders/library.h"
#include "shaders/renderer.h"

namespace proctex::transform {

struct LinkOptions {
  int jumps = 3;            // jump edges kept per shader pair
  int sparse = 0;           // samples per shader compared (0: its pruned graph)
  int neighbours = 4;       // each shader is linked to its `neighbours` most similar partners
  int resolution = 128;     // refinement resolution (at most the catalogue's)
  int rounds = 3;           // alternating rounds
  long evaluations = 40;    // renders per local optimisation
  double tolerance = 1e-3;  // stop when a round gains less similarity than this
};

struct PairReport {
  std::string a, b;
  double sparse_best = 0;               // best similarity among the sparse samples
  std::vector<double> start, refined;   // per jump edge, at the catalogue resolution
  long renders = 0;
  double seconds = 0;
  nlohmann::json to_json() const;
};

// Jump edges of one pair of catalogued shaders, best first.
std::vector<catalog::JumpEdge> find_jumps(const catalog::ShaderCatalogue& a, const catalog::ShaderCatalogue& b,
                                          Renderer& renderer, const LinkOptions& options, PairReport* report = nullptr);

struct LinkProgress {
  std::string a, b;
  int index = 0, total = 0;  // pair being linked
};

struct LinkReport {
  std::vector<PairReport> pairs;
  double seconds = 0;
  nlohmann::json to_json() const;
};

// The pairs to link among `shaders`: each shader with its `neighbours` most similar partners by
// sparse-sample similarity (all pairs when there are few shaders). Sorted by name.
std::vector<std::pair<std::string, std::string>> choose_pairs(catalog::Store& store, const std::vector<std::string>& shaders,
                                                             const LinkOptions& options);

// Finds and stores (one transaction per pair, replacing the pair's old edges) jump edges for
// `pairs`. Every shader must be catalogued with the current metric.
LinkReport link(catalog::Store& store, const std::vector<std::pair<std::string, std::string>>& pairs,
                const LinkOptions& options, Renderer& renderer,
                const std::function<void(const LinkProgress&)>& progress = {});

}  // namespace proctex::transform
