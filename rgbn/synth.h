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

// The order the synthesis visits the masked pixels of a w x h grid (each exactly once).
std::vector<int> visit_order(int w, int h, const std::vector<char>& inside, Order order, uint64_t seed);

}  // namespace proctex::rgbn
