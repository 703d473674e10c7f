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

// A jump anchored at a texture, found at morph time: the point of shader `other` whose render looks
// most like the render of `packed` in `shader` (features `features`, seed `key_seed`, catalogue
// resolution). Starts: the `starts` catalogue samples of `other` most similar to the texture
// (stored features, no render), each as is and with the parameters both shaders name alike taken
// from the texture, and each with its colours fitted to the texture (search::fit_colours). The two
// best starts are refined with search::refine at `resolution`, as find_jumps does; the refined
// point and the best start are scored at the catalogue resolution with `seed` (the morph's) and the
// better one is kept. `base` gives the values of other's non-searchable
// parameters. The edge's `shader_a` end is the texture itself.
struct AnchorOptions {
  long evaluations = 160;  // renders of the refinement, split over its two best starts
  int starts = 3;          // catalogue samples tried as starts
  int resolution = 128;
};
catalog::JumpEdge anchor_jump(const std::string& shader, const std::vector<float>& packed, uint32_t key_seed,
                              const metrics::Features& features, const catalog::ShaderCatalogue& other,
                              const std::vector<float>& base, uint32_t seed, Renderer& renderer,
                              const AnchorOptions& options);

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
