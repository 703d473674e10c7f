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

// Composite weights (sum to 1): S = prod S_k^{w_k}. Fitted by grid search (step 0.05) on the
// tune split of bench_metrics_retrieval (mean MRR of its colour and grey versions); reported on
// the held-out split, docs/metrics.md. The spectrum got weight 0 (it adds nothing the pyramid does
// not have): its features are still computed, and breakdown() still reports its similarity.
inline constexpr double kWeightSpectrum = 0.0;
inline constexpr double kWeightPyramid = 0.50;
inline constexpr double kWeightColour = 0.45;
inline constexpr double kWeightStructure = 0.05;

}  // namespace proctex::metrics::calibration
