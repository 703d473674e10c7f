#pragma once
// Written by bench/fit_selection.py (do not edit by hand): the shader-selection model of
// search/selection.h, fitted on the tune split of the labelled real photos (bench/realset).
// Command: fit_selection.py /tmp/ev-shared --passes 0 --write search/selection_weights.h --version 0
// Tune split: log-loss 1.949, top-1 0.500, top-3 0.750.
namespace proctex::search::selection {

inline constexpr int kVersion = 0;
struct Group {
  const char* name;
  double median;  // median distance of the group between a labelled photo and a catalogue sample
  double weight;
};
inline constexpr Group kGroups[] = {
    {"spectrum.radial", 1.38854, 1},
    {"spectrum.orientation", 0.58967, 1},
    {"pyramid.level0", 0.178966, 1},
    {"pyramid.level1", 0.165895, 1},
    {"pyramid.level2", 0.156177, 1},
    {"pyramid.level3", 0.131065, 1},
    {"pyramid.level4", 0.100612, 1},
    {"colour.mean-L", 28.5242, 0},
    {"colour.mean-ab", 31.3268, 0},
    {"colour.covariance", 16.4914, 0},
    {"colour.quantiles-L", 29.8975, 0},
    {"colour.quantiles-ab", 27.0426, 0},
    {"structure.energy", 2.82711, 1},
    {"structure.sparseness", 5.22887, 1},
    {"structure.kurtosis", 1.84052, 1},
    {"structure.orient-corr", 1.56519, 1},
    {"structure.scale-corr", 1.61707, 1},
    {"structure.lowpass-ac", 3.5999, 1},
    {"structure.energy-ac", 3.20139, 1},
    {"structure.pixel", 3.66907, 1},
};
// Added to the distance of each view of search::target_views (whole, half, quarter).
inline constexpr double kViewPenalty[] = {0, 0};
inline constexpr double kTemperature = 1;
inline constexpr double kSelectionWeight = 0.5;
inline constexpr double kGoodProbability = 0.5;

}  // namespace proctex::search::selection
