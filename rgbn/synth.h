#pragma once
// Texture synthesis on RGBNs with jump maps (Zelinka & Garland, as Pereira & Velho §1.6 use it).
// Analysis: every example pixel gets a short list of "jumps" to pixels with similar M x M
// neighbourhoods of colour and normal (PCA-reduced features, nearest neighbours among a seeded
// candidate subset). Synthesis walks the output in Hilbert or shuffled-DFS order, continuing the
// source of an already synthesised neighbour (advanced by the same offset) and taking a jump with
// probability p per pixel (expected run ~ 1/p) or when the source leaves the example; among the
// candidates it keeps the one whose example neighbourhood fits the known output best. Every output
// value is a copy of an example value; with `compose`, normals are the example's detail (relative
// to its smoothed base normals) composed on the smoothed base normals of the target region.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "rgbn/filter.h"
#include "rgbn/rgbn.h"

namespace proctex::rgbn {

struct JumpMapOptions {
  int neighbourhood = 5;       // M (odd)
  int jumps = 4;               // jumps kept per pixel
  int candidates = 4096;       // example pixels searched per pixel (seeded subset; all when fewer)
  double variance = 0.97;      // PCA variance kept
  uint64_t seed = 1;
};
struct JumpMap {
  int width = 0, height = 0;
  std::vector<std::vector<int>> jumps;  // per example pixel: target pixel indices, best first
  int dimensions = 0;                   // PCA dimensions kept
};
JumpMap build_jump_map(const Rgbn& example, const JumpMapOptions& options = {});

enum class Order { Hilbert, ShuffledDfs };
Order parse_order(const std::string& name);  // "hilbert", "dfs"

struct JumpSynthOptions {
  Order order = Order::Hilbert;
  double jump_probability = 0.05;
  uint64_t seed = 1;
  bool compose = false;     // fill: compose the example's detail on the target's base normals
  float base_sigma = 6.0f;  // smoothing that defines base normals
  double xi = -1;           // degrees; >= 0: synthesised normals keep n_z >= sin(xi) (edit.h's bound)
};
struct JumpSynthResult {
  Rgbn image;
  std::vector<int> source;   // example pixel per output pixel (-1 where not synthesised)
  double mean_run = 0;       // mean number of consecutive continued pixels between jumps
  size_t visited = 0;
};
// Grows a w x h RGBN from the example.
JumpSynthResult jump_synthesize(const Rgbn& example, const JumpMap& map, int w, int h, const JumpSynthOptions& o);
// Fills the pixels of `target` where mask > 0 (other pixels are copied unchanged).
JumpSynthResult jump_fill(const Rgbn& example, const JumpMap& map, const Rgbn& target, const Mask& mask,
                          const JumpSynthOptions& o);

// --- synthesis with synth/'s exemplar synthesiser (Lefebvre & Hoppe 2005/2006) ---------------
// The example's albedo is the exemplar colour and its normals an exemplar normal map (matched on
// their components with weight `normal_weight`); synth/ returns exemplar coordinates per output
// pixel, and every output pixel copies the example's (albedo, normal) pair at its coordinate, so
// colour and normal stay paired. Growing synthesises the window (0, 0, w, h) of synth/'s infinite
// plane. Filling synthesises `windows` candidate windows over the region's bounding box (seeded
// offsets on the plane), keeps the one whose pixels best match the target on a ring of `ring`
// pixels around the region, and copies it inside the region; with `compose`, the example's
// normals are re-expressed as detail on its base (smoothed) normals and composed on the target's
// base normals (as jump_fill does). The example must be 16..512 pixels a side (synth/'s limits).
struct ExemplarSynthOptions {
  uint64_t seed = 1;                 // synth/'s seed (low 32 bits) and the fill's window offsets
  float normal_weight = 1.0f;        // weight of the normal channels against the colour in matching
  std::vector<float> randomness;     // synth/'s jitter per level, coarse to fine; empty = its default
  int passes = 2;                    // correction passes per level
  float coherence = 2.0f;            // synth/'s kappa
  bool compose = false;              // fill: compose detail on the target's base normals
  float base_sigma = 6.0f;
  double xi = -1;                    // degrees; >= 0: keep n_z >= sin(xi)
  int windows = 16;                  // fill: candidate windows tried
  int ring = 4;                      // fill: width of the matching ring around the region (pixels)
  bool tile_scoring = true;          // fill: score candidates on the ring's 64^2 tiles only when
                                     // they cover at most half the window (same result, faster)
  std::filesystem::path cache_dir;   // synth/'s analysis cache; empty = no cache
  std::function<void(double)> progress;  // optional: fraction done, after each strip or window
};
struct ExemplarSynthResult {
  Rgbn image;
  std::vector<int> source;       // example pixel per output pixel (-1 where not synthesised)
  size_t visited = 0;
  int64_t window_x = 0, window_y = 0;  // the synthesised window's offset on synth/'s plane
  double ring_error = 0;         // fill: mean squared (albedo + normal) difference on the ring
  int levels = 0;                // synth/'s analysis levels
  bool example_tiles = false;    // synth/ judged the example tileable
  bool analysis_cached = false;
  double analysis_seconds = 0;
};
ExemplarSynthResult exemplar_synthesize(const Rgbn& example, int w, int h, const ExemplarSynthOptions& o);
ExemplarSynthResult exemplar_fill(const Rgbn& example, const Rgbn& target, const Mask& mask,
                                  const ExemplarSynthOptions& o);

// Shared by both methods: the example normal at `source`, re-expressed as detail on the example's
// base normal and composed on `target_base` (a unit normal); returns the unit result.
Vec3 compose_detail(const Rgbn& example, const Rgbn& example_base, int source, const Vec3& target_base);
// Normals smoothed by a Gaussian of `sigma` on the slopes (the base of compose_detail).
Rgbn base_normals(const Rgbn& image, float sigma);

// The order the synthesis visits the masked pixels of a w x h grid (each exactly once).
std::vector<int> visit_order(int w, int h, const std::vector<char>& inside, Order order, uint64_t seed);

namespace detail {
// Moves every synthesised normal (source >= 0) that is below n_z = sin(xi) back along its arc from
// the normal it replaced (`before`; (0, 0, 1) when growing) to the farthest admissible point.
void saturate_synthesised(Rgbn& out, const Rgbn& before, const std::vector<int>& source, double xi);
}  // namespace detail

}  // namespace proctex::rgbn
