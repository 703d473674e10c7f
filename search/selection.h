#pragma once
// Which material is this photo? The shader selection of `proctex match` (issue 12).
//
// A photo shows a material at an unknown scale, and a flexible shader refined against the
// similarity can tune itself into a statistical look-alike of almost anything (a metamer of the
// metric). So the material is decided on evidence the refinement cannot game: a classifier from
// the photo's structural statistics (the default metric's spectrum, pyramid and structure
// features of several views of the photo) to the library's shaders, trained on the catalogue's
// renders and on labelled real photos (bench/realset, bench/fit_selection.py; the model is the
// generated search/selection_model.h). The refinement only tunes the parameters of likely
// shaders, the final choice weighs the similarity with the selection's probability, and "good"
// needs that probability (search/match.h).
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "image/image.h"
#include "metrics/metric.h"

namespace proctex::search {

// The photo at the scales the selection compares: the centre square of the whole photo and, when
// the photo is large enough, centre squares of 1/2 and 1/4 of its side (the material seen closer),
// each analysed at the metric's resolution. A view is never enlarged beyond its native pixels.
struct TargetView {
  std::string name;  // "whole", "half", "quarter"
  Image image;
};
std::vector<TargetView> target_views(const Image& photo, int resolution = 256);

// Similarity with the colour component left out: a catalogue sample's colours were drawn at
// random and are fitted afterwards (colour_fit.h), so samples are compared by structure alone. The
// remaining components of the composite keep their relative weights (the whole metric when it is
// not a composite).
double structural_similarity(const metrics::Metric& metric, const metrics::Features& a, std::span<const float> b);

// Colour statistics of a photo, for the selection's colour term (people tell grass, sky, rust,
// marble and bricks apart partly by colour; the structural classifier cannot, because catalogue
// samples have random colours). From the pixels of the centre square in CIELAB (D65, from linear
// RGB): mean and standard deviation of L*, a*, b* and chroma C*, the 10/50/90 % quantiles of each,
// and the chroma-weighted mean hue direction (cos, sin): kColourStatistics values, in that order.
inline constexpr std::size_t kColourStatistics = 22;
std::vector<double> colour_statistics(const Image& photo);
// A photo whose mean chroma is below this (CIELAB units) is taken as a greyscale photo (R = G = B
// gives exactly 0; the least colourful colour photo of the labelled set has 0.54): its colours
// say nothing about the material, so the colour term is left out for it.
inline constexpr double kGreyscaleChroma = 0.5;

// Orientation and elongation statistics of a view's lightness, for the selection's structural
// term (issue 12: a greyscale lawn and a gravel photo have alike spectra and pyramid statistics;
// what tells them apart is that blades are long, thin and mostly upright, and pebbles are blobs).
// At each of kShapeLevels pyramid levels of the view resized to `resolution`: the coherence of
// the local structure tensor (energy-weighted mean, and the share of energy where it exceeds 0.6)
// at integration scales 1.5 and 4 px, the concentration of the local orientation at four times
// its angle (two perpendicular directions: grids, bricks), the anisotropy of the whole level's
// gradient tensor (one dominant direction), and from the Hessian the ridge share, the blob share
// and the polarity (bright or dark structure). All are ratios: invariant to rotation, contrast
// and brightness.
inline constexpr int kShapeLevels = 4;
inline constexpr std::size_t kShapeStatisticsPerLevel = 9;
inline constexpr std::size_t kShapeStatistics = kShapeLevels * kShapeStatisticsPerLevel;
std::vector<double> shape_statistics(const Image& view, int resolution = 256);
// Micro-structure of a view's lightness: rotation-invariant uniform local binary patterns (spots,
// flat areas, edges, line ends, corners; Ojala et al. 2002) with 8 neighbours at radius 1 and 16
// at radius 2, at kMicroLevels pyramid levels of the view resized to `resolution`: the square
// roots of the label shares (10 + 18 per level). Invariant to rotation, contrast and brightness.
// Used by selection models that were fitted with them (selection_model::kMicroFeatures > 0).
inline constexpr int kMicroLevels = 3;
inline constexpr std::size_t kMicroStatisticsPerLevel = 10 + 18;
inline constexpr std::size_t kMicroStatistics = kMicroLevels * kMicroStatisticsPerLevel;
std::vector<double> micro_statistics(const Image& view, int resolution = 256);
// How differently two images are shaped: the RMS difference of their shape statistics, each in
// units of its spread over the selection model's training rows (its standardisation). Not
// optimised by the refinement, so a look-alike that games the similarity is not tuned to it.
double shape_distance(const std::vector<double>& a, const std::vector<double>& b);

// The selection model's version (recorded in match results).
int selection_version();

// The target's side of the selection: the classifier's logits for every view, computed once.
class SelectionTarget {
 public:
  // Throws proctex::Error when `metric` is not the metric the model was fitted on.
  SelectionTarget(const Image& photo, const metrics::Metric& metric);
  // Probability of each of `shaders`: softmax over them of each shader's largest logit over the
  // views divided by kStructuralTemperature, plus its colour logit divided by kColourTemperature
  // (a linear term of colour_statistics fitted on the tune photos; the temperatures are calibrated
  // out of fold, selection_model.h),
  // plus kStructuralWeight * log(its best structural similarity in the catalogue, given in
  // `best_structural`, same order): the nearest-sample evidence recognises clean renders. A shader
  // the model does not know (a user's shader) gets the lowest known logit.
  std::vector<double> probabilities(const std::vector<std::string>& shaders,
                                    const std::vector<double>& best_structural) const;
  const std::vector<std::string>& view_names() const { return names_; }

 private:
  std::vector<std::string> names_;
  std::vector<double> logits_;  // per model shader: largest over the views
};

}  // namespace proctex::search
