#pragma once
// Small numeric helpers shared by the metric implementations (internal to metrics/).
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

namespace proctex::metrics::detail {

// A square single-channel plane.
struct Plane {
  int size = 0;
  std::vector<float> v;
  float& at(int x, int y) { return v[static_cast<std::size_t>(y) * size + x]; }
  float at(int x, int y) const { return v[static_cast<std::size_t>(y) * size + x]; }
};

// Separable 5-tap binomial blur [1 4 6 4 1]/16 with mirrored borders (photos do not wrap).
Plane blur5(const Plane& in);
// Keeps every second pixel of every second row (size must be even).
Plane decimate(const Plane& in);
// blur5 then decimate: one level of a Gaussian pyramid.
inline Plane reduce(const Plane& in) { return decimate(blur5(in)); }

double mean(std::span<const float> x);
// Vectorised float reductions (OpenMP simd, fixed lane order: deterministic for one build).
// Sums are accumulated per row-sized chunk in float and across chunks in double.
float dot(const float* a, const float* b, std::size_t n);
double sum(std::span<const float> x);
// Subtracts the mean in place; returns the sum of squares after centring.
double centre(std::span<float> x);
// Pearson correlation of two equally long sequences (0 when either is constant).
double correlation(std::span<const float> a, std::span<const float> b);
// Normalised circular autocorrelation of a mean-removed plane at offset (dx, dy).
double autocorrelation(const Plane& p, int dx, int dy);
// Same, with the plane's sum of squares given (it is the same for every offset).
double autocorrelation(const Plane& p, int dx, int dy, double energy);

// sqrt(sum w_i (a_i - b_i)^2 / sum w_i).
double weighted_rms(std::span<const float> a, std::span<const float> b,
                    std::span<const double> w);

}  // namespace proctex::metrics::detail
