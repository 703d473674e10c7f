#pragma once
// The align stage of a deterministic pattern's polish (search/match.cpp step 5; docs/search.md
// "Align"): with the counts right, a short search on the registered-pixel metric
// (metrics/aligned.h) moves the shape - a duty, a softness, an amplitude, a twist - which the
// statistics and the Fourier magnitude see weakly and pixels see directly. Colours drop out of
// that metric (they are solved afterwards).
//
// Coarse to fine: the renders at the final resolution area-averaged by 8, then 4, then 2. A fine
// pattern's pixels make a narrow basin (a swirl's twist 0.1% of its range off turns 15 arms by half
// a period at the rim); averaging widens it, so each stage starts inside the next one's basin.
//
// The rescue: the magnitude polish before this stage is blind to where a shape starts, so it can
// hand over an alias that is the target's complement shifted by half the image (a soft rotated
// superellipse at width 0.65, height 0.90 in swapped colours for the target's 0.93, 0.67). No
// local search leaves it: the registered pixels are flat (similarity ~0.002) everywhere near it.
// When the stages end farther from the target than the pixel polish can start from
// (kPixelPolishStartRmse), a line scan of every continuous parameter across its range
// (refine.h scan_coordinates) on the coarsest stage looks for the basin, and when it finds one
// (kAlignRescueGain) the stages run again from there; the better end point is kept.
#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/image.h"
#include "metrics/aligned.h"
#include "search/refine.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"

namespace proctex::search {

// Renders of one align run across its stages.
inline constexpr long kAlignEvaluations = 300;
// The rescue's line scan: values per continuous parameter and passes (24 x 5 x 2 = 240 renders for
// a superellipse; 24 levels in one pass already found the basin above, 16 too).
inline constexpr int kAlignRescueLevels = 24;
inline constexpr int kAlignRescueRounds = 2;
// The stages run again from the scan's end only if it is at most this share of the start's
// distance on the scan's metric (the superellipse: 0.007 from 0.124).
inline constexpr double kAlignRescueGain = 0.5;

struct AlignStage {
  metrics::AlignedMetric metric;
  metrics::Features target;
  double share;         // of kAlignEvaluations
  double initial_step;  // simplex size per unit dimension
};

struct AlignStages {
  std::vector<AlignStage> stages;  // coarse to fine
  // The rescue's scan: the coarsest stage's metric on renders at `scan_resolution` (twice its
  // side, at least 64: it only has to find the basin, which the stages then refine at the full
  // resolution; 64 px renders cost a tenth of the 256 px ones and found the superellipse's basin
  // as well).
  metrics::Features scan_target;
  int scan_resolution = 0;
};

// `resolution`: the renders' (the final score's, 256 px): a shader's own antialiasing at a lower
// resolution is not the area average of the target's pixels, and on a fine pattern that bias moved
// the optimum (a 15-arm swirl's true point scored 0.43 rendered at 128 px against the 256 px target
// averaged to 128, a wrong one 0.52). So both are rendered at `resolution` and averaged alike.
AlignStages align_stages(const Image& target, int resolution);

// At most this many renders does one rescue add (the scan and a second run of the stages).
long align_rescue_renders(const ParameterSpace& space);

// Whether an align end point's similarity (on the last stage) is too far from the target for the
// pixel polish to start from: what makes the rescue run.
bool align_missed(const AlignStages& stages, double similarity);

// The stages from the best of `starts` (the first stage picks it). Returns the end point with its
// last stage's similarity; `evaluations` counts the renders. With `rescue`, a missed end point gets
// the rescue (above); `report` (when given) gets {"before", "scan_from", "scanned", "after",
// "evaluations", "kept"} of it ("after": null when the scan found no other basin).
RefineResult align_pattern(const ParameterSpace& space, const std::vector<std::vector<double>>& starts,
                           const AlignStages& stages, Renderer& renderer, uint32_t seed, int resolution,
                           const RefineOptions& base, long& evaluations, bool rescue = false,
                           nlohmann::json* report = nullptr);

}  // namespace proctex::search
