#pragma once
// Synthesis on a multiscale exemplar graph (Han 2011, ch. 5) with the parallel, windowed,
// integer-exact machinery of synthesis.h. A synthesis pixel is a pointer (exemplar i, stack level k,
// texel u) plus a colour offset R (Han's inconsistency correction, constant-offset transfer). Per
// synthesis level t = 1..T (T = L + zoom): upsample (k + 1, the child's texel as in LH05, R
// interpolated bilinearly from the four nearest parents), jitter, then correction passes whose
// candidates are, for each of the 3x3 neighbours: its own texel, its k-coherence candidate and its
// links along the graph's edges (the best matching texel of the destination stack level with the
// colour offset b = mean of the 5x5 neighbourhood differences; b = 0 inside one exemplar). Only the
// stack levels of the level schedule (graph.h) are accepted, so the finest level of an exemplar is
// left for a finer one until the output level.
//
// Matching happens in ONE appearance space shared by every stack level of every exemplar (5x5
// colour neighbourhoods, PCA to 8 dimensions; diagonal taps, second PCA), so a pixel's neighbours
// may point into different exemplars. A colour offset shifts an appearance vector linearly, which
// the kernels apply in integer arithmetic: the result is bit-identical for any window, thread count
// or device, like the single-exemplar synthesis.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"
#include "synth/graph.h"
#include "synth/synthesis.h"

namespace proctex::synth {

inline constexpr int kOffsetUnits = 4096;  // colour offsets are integers in 1/4096 of the sRGB range

struct GraphAnalysis {
  int width = 0, height = 0;
  int levels = 0;  // L, the same for every exemplar
  int exemplars = 0;
  int slots = 0;   // link slots per stack level (the largest number of explicit out edges)
  std::vector<unsigned char> toroidal;  // per exemplar
  // Per node n = i * (L + 1) + k and texel t = y * width + x:
  std::vector<int8_t> appearance;    // [n][t][8] shared appearance space
  std::vector<int16_t> feature;      // [n][t][8] projected matching neighbourhood
  std::vector<int32_t> coherent;     // [n][t] a dispersed similar texel of the same stack level
  std::vector<int32_t> link_node;    // [n][slot] destination node of the slot's edge, -1 = none
  std::vector<int32_t> link_texel;   // [n][slot][t] best matching texel in the destination
  std::vector<int16_t> link_offset;  // [n][slot][t][4] colour offset b (r, g, b, 0), kOffsetUnits
  std::vector<int32_t> projection;   // [40][8] fixed-point second PCA (shift 8)
  std::vector<int32_t> offset_response;  // [8][3] appearance change per colour offset (shift 16)
  std::vector<float> colour;         // [n][t][3] the stack level's colour, sRGB-encoded
  std::string hash;                  // content hash of the exemplars and edges
  double seconds = 0;       // analysis time (0 when loaded from the cache)
  bool from_cache = false;
  size_t nodes() const { return static_cast<size_t>(exemplars) * (levels + 1); }
};

struct LoadedGraph {
  ExemplarGraph graph;
  std::vector<Image> images;               // linear RGB, one per exemplar
  std::vector<unsigned char> toroidal;     // resolved "tiles"
};

// Loads and checks the graph's exemplars (each like `proctex synth EXEMPLAR`: readable, 16..512 px,
// finite; all the same size) and resolves "tiles": auto.
LoadedGraph load_graph(const std::filesystem::path& file);
LoadedGraph load_graph(ExemplarGraph graph);

// L: the stack depth of the graph's exemplars (levels 0..L).
int graph_levels(const LoadedGraph& graph);

GraphAnalysis analyse_graph(const LoadedGraph& graph);

// Analyses, or loads the analysis cached in `cache_dir` (file graph-HASH.bin, HASH over the exemplars'
// pixels, "tiles" and the edges); an empty path disables the cache, a damaged file is ignored.
GraphAnalysis analyse_graph_cached(const LoadedGraph& graph, const std::filesystem::path& cache_dir);

// One synthesised pixel: exemplar texel (x, y) of stack level `level` of exemplar `exemplar`, and
// the colour offset (r, g, b) in kOffsetUnits.
struct GraphPixel {
  int32_t x, y, exemplar, level, r, g, b;
};

class GraphSynthesizer {
 public:
  GraphSynthesizer(const LoadedGraph& graph, const GraphAnalysis& analysis);
  ~GraphSynthesizer();
  GraphSynthesizer(const GraphSynthesizer&) = delete;
  GraphSynthesizer& operator=(const GraphSynthesizer&) = delete;

  // The window of the infinite plane at output level L + zoom (an output pixel spans 2^-zoom root
  // texels). Uses options.seed, randomness (per synthesis level 1..T, the last value repeating),
  // passes and kappa; jitter maps, pastes and periods are not supported (UsageError).
  std::vector<GraphPixel> synthesise(const Window& window, const SynthOptions& options, int zoom);

  // sRGB-encoded colour (3 floats per pixel) of synthesised pixels: the stack level's texel plus the offset.
  std::vector<float> colours(const std::vector<GraphPixel>& pixels) const;

  const GraphAnalysis& analysis() const { return analysis_; }

 private:
  struct Device;
  const LoadedGraph& graph_;
  const GraphAnalysis& analysis_;
  std::unique_ptr<Device> device_;
};

}  // namespace proctex::synth
