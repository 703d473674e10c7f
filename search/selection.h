#pragma once
// Which material is this photo? The shader selection of `proctex match` (issue 12).
//
// A photo shows a material at an unknown scale, and a flexible shader refined against the
// similarity can tune itself into a statistical look-alike of almost anything (a metamer of the
// metric). So the material is decided on evidence the refinement cannot game: the distances of
// the photo's views (several scales) to the catalogue's samples, weighted per feature group with
// weights fitted to material categories on a labelled set of real photos (bench/realset,
// bench/fit_selection.py), not to same-texture retrieval. The refinement only tunes the
// parameters of the selected shaders; the selection's probability enters the verdict.
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

// The fitted selection model: weight / median per feature group of the default metric (colour
// groups are 0: a catalogue sample's colours are random until fitted), a penalty per view (a
// closer view is a weaker hypothesis), and the softmax temperature of the probabilities.
struct SelectionModel {
  int version = 0;                   // bumped with every refit (recorded in match results)
  std::vector<double> group_scale;   // weight_g / median_g
  std::vector<double> view_penalty;  // per view of target_views(), in order
  double temperature = 1.0;
};
const SelectionModel& default_selection();

// The target's side of the selection: features of every view, computed once.
class SelectionTarget {
 public:
  SelectionTarget(const Image& photo, const metrics::Metric& metric, int resolution,
                  const SelectionModel& model = default_selection());
  // Smallest weighted group distance of the views to one catalogue sample's features (>= 0);
  // `view` receives the index of the view that gave it.
  double distance(std::span<const float> sample, int* view = nullptr) const;
  const std::vector<std::string>& view_names() const { return names_; }
  const SelectionModel& model() const { return model_; }

 private:
  const metrics::Metric& metric_;
  const SelectionModel& model_;
  std::vector<std::string> names_;
  std::vector<metrics::Features> views_;
};

// Softmax probabilities of shaders from their selection distances (the smallest over each
// shader's samples), in the same order.
std::vector<double> selection_probabilities(const std::vector<double>& distances, const SelectionModel& model);

}  // namespace proctex::search
