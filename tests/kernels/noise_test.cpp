// The OpenCL noise library evaluated on the device through a small test kernel: ranges,
// determinism, seeding, continuity and the defining properties of each noise.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "kernels/library.h"
#include "kernels/runtime.h"

namespace proctex::ocl {
namespace {

constexpr int kSide = 128;

// Evaluates `expr` (a float expression of float2 p and uint seed) over a kSide^2 grid starting at
// `origin` with spacing `step`.
std::vector<float> evaluate(const std::string& expr, uint32_t seed, float step = 0.173f, float origin = 3.1f) {
  auto& rt = Runtime::instance();
  const std::string source = library_source() + line_directive("noise_test_kernel", 1) +
                             "__kernel void eval(__global float* out, uint seed, float step, float origin) {\n"
                             "  const int x = get_global_id(0), y = get_global_id(1);\n"
                             "  const float2 p = (float2)(origin + x * step, origin + y * step);\n"
                             "  const float fw = 0.0f;\n"
                             "  out[y * get_global_size(0) + x] = " + expr + ";\n}\n";
  cl::Program program = rt.program(source);
  cl::Kernel kernel(program, "eval");
  std::vector<float> out(kSide * kSide);
  cl::Buffer buf(rt.context(), CL_MEM_WRITE_ONLY, out.size() * sizeof(float));
  kernel.setArg(0, buf);
  kernel.setArg(1, seed);
  kernel.setArg(2, step);
  kernel.setArg(3, origin);
  rt.queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(kSide, kSide));
  rt.queue().enqueueReadBuffer(buf, CL_TRUE, 0, out.size() * sizeof(float), out.data());
  return out;
}

double mean(const std::vector<float>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); }

double stddev(const std::vector<float>& v) {
  const double m = mean(v);
  double s = 0;
  for (float x : v) s += (x - m) * (x - m);
  return std::sqrt(s / v.size());
}

void expect_all_finite_in(const std::vector<float>& v, float lo, float hi) {
  for (float x : v) {
    ASSERT_TRUE(std::isfinite(x));
    ASSERT_GE(x, lo);
    ASSERT_LE(x, hi);
  }
}

class NoiseFunction : public ::testing::TestWithParam<const char*> {};

TEST_P(NoiseFunction, DeterministicSeededAndVaried) {
  const auto a = evaluate(GetParam(), 7);
  const auto b = evaluate(GetParam(), 7);
  const auto c = evaluate(GetParam(), 8);
  EXPECT_EQ(a, b) << "same seed must give the same values";
  EXPECT_NE(a, c) << "another seed must give another texture";
  EXPECT_GT(stddev(a), 0.05) << "noise must vary";
}

TEST_P(NoiseFunction, ContinuousAtFineSteps) {
  // Neighbouring samples 0.002 apart must differ little: the noises are smooth (cellular F1 and
  // F2 are continuous too, though not smooth).
  const auto v = evaluate(GetParam(), 3, 0.002f);
  float worst = 0;
  for (int y = 0; y < kSide; ++y)
    for (int x = 1; x < kSide; ++x) worst = std::max(worst, std::fabs(v[y * kSide + x] - v[y * kSide + x - 1]));
  EXPECT_LT(worst, 0.05f);
}

INSTANTIATE_TEST_SUITE_P(Library, NoiseFunction,
                         ::testing::Values("pt_gnoise(p, seed)", "pt_vnoise(p, seed)",
                                           "pt_cellular_f1(p, 1.0f, seed)", "pt_cellular_f2(p, 1.0f, seed)",
                                           "pt_fbm(p, fw, 5, 2.0f, 0.5f, seed)",
                                           "pt_turbulence(p, fw, 5, 2.0f, 0.5f, seed)",
                                           "pt_ridged(p, fw, 5, 2.0f, 0.5f, seed)",
                                           "pt_warp(p, fw, 0.5f, 1.0f, 3, seed).x"));

TEST(Noise, GradientNoiseIsZeroAtLatticePointsAndCentred) {
  const auto at_lattice = evaluate("pt_gnoise(p, seed)", 11, 1.0f, 0.0f);
  for (float x : at_lattice) ASSERT_NEAR(x, 0.0f, 1e-5f);
  const auto v = evaluate("pt_gnoise(p, seed)", 11);
  expect_all_finite_in(v, -1.0f, 1.0f);
  EXPECT_NEAR(mean(v), 0.0, 0.05);
}

TEST(Noise, ValueNoiseInRange) { expect_all_finite_in(evaluate("pt_vnoise(p, seed)", 5), -1.0f, 1.0f); }

TEST(Noise, CellularDistancesAreOrdered) {
  const auto f1 = evaluate("pt_cellular_f1(p, 1.0f, seed)", 9);
  const auto f2 = evaluate("pt_cellular_f2(p, 1.0f, seed)", 9);
  const auto d = evaluate("pt_cellular_f2_minus_f1(p, 1.0f, seed)", 9);
  for (size_t i = 0; i < f1.size(); ++i) {
    ASSERT_GE(f1[i], 0.0f);
    ASSERT_LE(f1[i], f2[i]);
    ASSERT_NEAR(d[i], f2[i] - f1[i], 1e-5f);
  }
  // With one point per unit cell, nearest distances stay below the cell diagonal.
  expect_all_finite_in(f1, 0.0f, 1.5f);
}

TEST(Noise, CellularWithoutJitterIsARegularGrid) {
  // Feature points at cell centres: F1 at a cell centre is 0.
  const auto f1 = evaluate("pt_cellular_f1(p, 0.0f, seed)", 1, 1.0f, 0.5f);
  for (float x : f1) ASSERT_NEAR(x, 0.0f, 1e-5f);
}

TEST(Noise, FractalsStayInTheirRanges) {
  expect_all_finite_in(evaluate("pt_fbm(p, fw, 6, 2.0f, 0.5f, seed)", 2), -1.0f, 1.0f);
  expect_all_finite_in(evaluate("pt_turbulence(p, fw, 6, 2.0f, 0.5f, seed)", 2), 0.0f, 1.0f);
  expect_all_finite_in(evaluate("pt_ridged(p, fw, 6, 2.0f, 0.5f, seed)", 2), 0.0f, 1.0f);
}

TEST(Noise, FootprintRemovesFineOctaves) {
  // A footprint of 0.08 filters out octaves whose period spans fewer than two footprints: with
  // gain 1/2 every octave adds the same slope, and independent octaves add in quadrature, so
  // keeping about 2.6 of 6 octaves leaves about sqrt(2.6 / 6) = 0.66 of the summed slope (measured
  // at a step finer than every octave); unfiltered it stays at 1.
  const auto sharp = evaluate("pt_fbm(p * 8.0f, 0.0f, 6, 2.0f, 0.5f, seed)", 4, 0.001f);
  const auto filtered = evaluate("pt_fbm(p * 8.0f, 0.08f, 6, 2.0f, 0.5f, seed)", 4, 0.001f);
  auto roughness = [](const std::vector<float>& v) {
    double s = 0;
    for (int y = 0; y < kSide; ++y)
      for (int x = 1; x < kSide; ++x) s += std::fabs(v[y * kSide + x] - v[y * kSide + x - 1]);
    return s;
  };
  EXPECT_LT(roughness(filtered), 0.8 * roughness(sharp));
  // A footprint covering many periods of every octave sees the mean: zero.
  for (float x : evaluate("pt_fbm(p, 10.0f, 6, 2.0f, 0.5f, seed)", 4)) ASSERT_NEAR(x, 0.0f, 1e-6f);
}

TEST(Noise, FilteredPulseTrainAveragesToDuty) {
  // Over a footprint of many periods the filtered pulse train equals its duty cycle.
  const auto v = evaluate("pt_filtered_pulsetrain(0.3f, p.x, 10.0f)", 0);
  for (float x : v) ASSERT_NEAR(x, 0.3f, 1e-3f);
}

}  // namespace
}  // namespace proctex::ocl
