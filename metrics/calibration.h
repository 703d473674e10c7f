#pragma once
// Constants chosen by the retrieval evaluation (bench/metrics_retrieval.cpp, docs/metrics.md).
// Changing one changes similarities but not features: no version bump is needed for a scale or a
// composite weight (cached features stay valid).
namespace proctex::metrics::calibration {

// Per-metric distance that maps to similarity 1/e: roughly the median distance between two crops
// of one texture times 3, so that same-texture pairs score about 0.7 and different textures fall
// towards 0 (see docs/metrics.md, "Similarity scale").
inline constexpr double kSpectrumScale = 0.30;   // decades of power
inline constexpr double kPyramidScale = 0.060;   // EMD on the compressed band-value axis
inline constexpr double kColourScale = 6.0;      // CIELAB Delta E
inline constexpr double kStructureScale = 1.0;   // normalised statistic units

// The default metric "composite" (product form, composite.h): S = prod_k S_k^{w_k}, equal weights.
// (A fit of these four weights, 0 / 0.50 / 0.45 / 0.05, made the centred shapes near-duplicates.)
inline constexpr double kWeightSpectrum = 0.25;
inline constexpr double kWeightPyramid = 0.25;
inline constexpr double kWeightColour = 0.25;
inline constexpr double kWeightStructure = 0.25;

// The "grouped" metric (composite.h, grouped form): d = (sum_g (weight_g / median_g) d_g)^
// kCompositeExponent and S = exp(-d / kCompositeScale). median_g is the median distance of group g between two renders
// of one texture (tune split, colour), so weight 1 gives every group the same say for a typical
// same-texture pair. The weights were fitted by bench_metrics_retrieval --fit-groups on the tune
// split only (coordinate descent, objective mean MRR of the colour and grey pools, under the
// constraint that no two library shaders at their defaults score >= 0.55, i.e. the distinctness
// test keeps a margin); held-out numbers in docs/metrics.md. Changing a weight, a median or the
// scale changes similarities but not features: bump kOwnVersionGrouped in composite.cpp (cached
// similarities, e.g. catalogue graph edges, go stale) but the components need no bump. Not the
// default yet: with these weights the matcher takes a 4-pointed star for a circle
// (tests/search/match_test.cpp), the shapes get too little weight; see docs/metrics.md.
struct Group {
  const char* name;
  double median;
  double weight;
};
inline constexpr Group kGroups[] = {
    {"spectrum.radial", 0.07898, 0.0625},
    {"spectrum.orientation", 0.06424, 0.5},
    {"pyramid.level0", 0.002664, 2},
    {"pyramid.level1", 0.003825, 0.5},
    {"pyramid.level2", 0.005709, 1},
    {"pyramid.level3", 0.008584, 0.03125},
    {"pyramid.level4", 0.01261, 0.25},
    {"colour.mean-L", 0.1936, 0.125},
    {"colour.mean-ab", 0.2819, 2},
    {"colour.covariance", 0.3881, 1},
    {"colour.quantiles-L", 0.3671, 1},
    {"colour.quantiles-ab", 0.3727, 0.125},
    {"structure.energy", 0.1491, 0},
    {"structure.sparseness", 0.5248, 0.125},
    {"structure.kurtosis", 0.268, 0},
    {"structure.orient-corr", 0.3207, 0},
    {"structure.scale-corr", 0.2359, 0},
    {"structure.lowpass-ac", 0.6227, 0},
    {"structure.energy-ac", 0.7497, 0},
    {"structure.pixel", 0.1197, 0},
};
// Distance mapping to 1/e: the median distance d of two renders of one texture (tune split,
// colour) divided by -ln 0.7, so that such pairs score 0.7 at the median.
inline constexpr double kCompositeExponent = 0.5;
inline constexpr double kCompositeScale = 9.453;

// The "layout" metric (grouped form, own version 3; NOT the default): the same 20 groups refitted
// by bench_metrics_retrieval --fit-from-grouped --fit-passes 5 --probe-margin 1.3 on the tune split
// with one more constraint: the shape probes (the 4-pointed star target of
// tests/search/match_test.cpp, 40 near 4-pointed stars, 180 random circles / rectangles /
// superellipses in its colours, 40 stars with 3 or 5-12 points) must keep the nearest other shape
// or point count >= 1.3 x the median near star's distance from the target. Retrieval: it beats every
// single metric and reaches 95.7% colour top-1 (docs/metrics.md), but with it as the default the
// matcher still returns an 8-pointed star for the 4-pointed target (tests/search/match_test.cpp),
// so the default stays the product. S = exp(-d^kLayoutExponent / kLayoutScale), d = sum_g
// (weight_g / median_g) d_g; the scale puts the median same-texture pair of the tune split at 0.7.
inline constexpr Group kLayoutGroups[] = {
    {"spectrum.radial", 0.07718, 0},
    {"spectrum.orientation", 0.06486, 4},
    {"pyramid.level0", 0.00265, 16},
    {"pyramid.level1", 0.003744, 0.5},
    {"pyramid.level2", 0.005637, 2},
    {"pyramid.level3", 0.008631, 0},
    {"pyramid.level4", 0.01285, 0},
    {"colour.mean-L", 0.1976, 1},
    {"colour.mean-ab", 0.2852, 2},
    {"colour.covariance", 0.3874, 1},
    {"colour.quantiles-L", 0.3641, 0.03125},
    {"colour.quantiles-ab", 0.3675, 4},
    {"structure.energy", 0.1481, 0},
    {"structure.sparseness", 0.5001, 0.25},
    {"structure.kurtosis", 0.2626, 0.03125},
    {"structure.orient-corr", 0.3085, 0},
    {"structure.scale-corr", 0.2332, 0.0625},
    {"structure.lowpass-ac", 0.6263, 0},
    {"structure.energy-ac", 0.7459, 0.0625},
    {"structure.pixel", 0.1194, 0.0625},
};
inline constexpr double kLayoutExponent = 0.5;
inline constexpr double kLayoutScale = 17.95;

}  // namespace proctex::metrics::calibration
