#pragma once
// Analysis of an exemplar, done once and cached on disk by content hash (Lefebvre & Hoppe 2005/2006):
//   - a Gaussian stack: levels l = 0..L, every level the full exemplar size, level l filtered at
//     scale h_l = 2^(L-l) (toroidally when the exemplar tiles, mirrored at the borders otherwise);
//   - appearance space per level: the 5x5 neighbourhood at spacing h_l of every channel, reduced by
//     PCA to 8 dimensions and quantised to signed bytes;
//   - the matching neighbourhood N(u): the appearance vectors at u and its eight neighbours
//     u + h_l (dx, dy), dx, dy in {-1, 0, 1} (9 x 8 = 72 values; the 4 diagonals alone, LH06's
//     reduced neighbourhood, cut structures more: docs/synth.md), reduced by a second PCA to 8 dimensions with an
//     integer projection, so synthesis on any device computes bit-identical distances;
//   - k-coherence candidates (k = 2 by default, 3 on request): every texel itself and its most
//     similar texel at least 5% of the exemplar size away (spatially dispersed), found by a
//     PatchMatch search; with k = 3 also the most similar texel 5% away from both of those.
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "synth/exemplar.h"

namespace proctex::synth {

inline constexpr int kAppearanceDims = 8;
inline constexpr int kNeighbourTaps = 9;  // the 3x3 taps at spacing h_l
inline constexpr int kNeighbourDims = kAppearanceDims * kNeighbourTaps;
inline constexpr int kProjectionShift = 8;  // fixed-point bits of the integer projection
inline constexpr int kAnalysisVersion = 6;  // 6: k = 3 candidates (coherent2)
inline constexpr int kMaxShifts = 64;

enum class Tiling { Auto, Toroidal, Bounded };

struct AnalysisOptions {
  Tiling tiling = Tiling::Auto;
  int candidates = 2;  // k of the k-coherence candidates: 2 or 3 (issue 13, session 11)
};

struct AnalysisLevel {
  int spacing = 1;                       // h_l
  std::vector<int8_t> appearance;        // w * h * 8
  std::vector<int16_t> neighbourhood;    // w * h * 8: projected N(u)
  std::vector<int32_t> coherent;         // w * h: index y * w + x of the k = 2 candidate
  std::vector<int32_t> coherent2;        // w * h with k = 3 (the third candidate), else empty
  std::vector<int32_t> projection;       // 72 * 8: fixed-point PCA basis, row-major [tap*8+dim][out]
};

struct Analysis {
  int width = 0, height = 0;
  int levels = 0;  // L: levels 0..L are stored (L + 1 entries)
  bool toroidal = false;
  int candidates = 2;  // k
  std::string hash;  // content hash (exemplar pixels, maps, weights, options, version)
  std::vector<AnalysisLevel> level;
  // The matching channels at the finest level, quantised (round(255 v); colour sRGB-encoded, maps
  // weighted as in Channels), interleaved: texel i's channel c at texels[i * texel_channels + c].
  // Not cached: derived from the pixels on every load (the final re-match scores on them).
  std::vector<int16_t> texels;
  int texel_channels = 0;
  // Structure-keeping shifts for the layout jitter: the translations t under which the exemplar
  // is most similar to itself (local maxima of its circular autocorrelation over every channel,
  // |t_x| >= w/8 or |t_y| >= h/8 so that a shift changes the content), best first, at most
  // kMaxShifts, as (dx, dy) pairs. Derived from the pixels on every load, like texels.
  std::vector<int32_t> shifts;
  // The autocorrelation at each shift divided by that at 0 (1 = the exemplar is the same under
  // the shift, about 0 = unrelated content), one per (dx, dy) pair of `shifts`.
  std::vector<float> shift_correlation;
  double seconds = 0;    // analysis time (0 when loaded from the cache)
  bool from_cache = false;
};

// True when the exemplar wraps around without a visible seam: the mean colour step across the wrap
// (last row to first, last column to first) is no larger than 1.1x the 95th percentile of the mean
// steps between adjacent rows (columns) inside.
bool tiles_seamlessly(const Exemplar& exemplar);

// Analyses without the cache.
Analysis analyse(const Exemplar& exemplar, const AnalysisOptions& options = {});

// The cache folder: $PROCTEX_CACHE_DIR/synth, else $XDG_CACHE_HOME/proctex/synth, else
// ~/.cache/proctex/synth.
std::filesystem::path default_cache_dir();

// Analyses, or loads the analysis cached in `cache_dir` under the exemplar's content hash (an empty
// path disables the cache). A damaged cache file is ignored and rewritten.
Analysis analyse_cached(const Exemplar& exemplar, const AnalysisOptions& options,
                        const std::filesystem::path& cache_dir);

// Exposed for tests: the synthesis-side integer projection of a 72-value neighbourhood.
std::array<int16_t, kAppearanceDims> project_neighbourhood(const AnalysisLevel& level, const int8_t* taps);

}  // namespace proctex::synth
