#pragma once
// Differential geometry and segmentation of an RGBN (Pereira & Velho §1.4).
#include <string>
#include <vector>

#include "rgbn/rgbn.h"

namespace proctex::rgbn {

// Gaussian (K) and mean (H) curvature per pixel, in 1/pixel, from the first and second
// fundamental forms of the height field whose slopes are (p, q) = (-n_x/n_z, -n_y/n_z); second
// derivatives by central differences of p and q. Sign convention: H > 0 where the surface bulges
// towards the viewer (the top of a bump), H < 0 in a pit; K > 0 at both, K < 0 at saddles.
struct Curvature {
  std::vector<float> K;
  std::vector<float> H;
};
Curvature curvature(const Rgbn& image, bool wrap = false);

// Felzenszwalb-Huttenlocher graph segmentation on colour and normals. Edge weight between
// 8-neighbours: g(dc, dn) with dc = |c_i - c_j| (linear RGB), dn = |n_i - n_j|, combined by
// min, max, or the mix (1 - alpha) dc + alpha dn (the paper's three choices).
enum class EdgeWeight { Min, Max, Mix };
EdgeWeight parse_edge_weight(const std::string& name);
struct SegmentOptions {
  float k = 0.5f;          // scale: larger k, larger segments
  int min_size = 50;       // merge smaller segments into a neighbour
  EdgeWeight weight = EdgeWeight::Mix;
  float alpha = 0.7f;      // weight of the normal distance in Mix
};
struct Segmentation {
  std::vector<int> labels;  // 0..count-1 per pixel
  int count = 0;
};
Segmentation segment(const Rgbn& image, const SegmentOptions& options);

}  // namespace proctex::rgbn
