#pragma once
// Power-spectrum similarity (Bourque thesis eq 4.10, S_F = 1 - ||F_ps(T1) - F_ps(T2)||_2).
//
// Features: lightness (L*/100), nine half-size crops on a 3 x 3 grid overlapping by half
// (Welch's method: one window gives a noisy periodogram), each with its window-weighted mean
// removed and a 2-D Hann
// window applied, FFTW real-to-complex; the power |F|^2 / sum(w^2) is averaged over the crops and
// binned over the half plane:
//   - kRadialBins radial bins from 1 cycle per crop to Nyquist, uniform in ln(1 + r/4) (log-spaced
//     at high frequencies, wider at the lowest, which would otherwise hold 2-3 noisy
//     coefficients): log10 of mean power;
//   - kOrientationBins orientations (0..180 deg) in each of kOrientationBands radial bands
//     (1/16..1/4, 1/4..1/2, 1/2..1 of Nyquist): log10 of the band's power in that orientation
//     over the band's mean power (anisotropy, independent of contrast).
// Distance: weighted RMS of the differences; radial weights fall linearly from 1 at the lowest
// to 0.25 at the highest bin ("differences weighted radially to favour low (structural)
// frequencies", thesis 4.5); orientation terms weigh 0.5. Units: decades of power.
// The exponential mapping exp(-d / scale) replaces the thesis's 1 - d, which can go negative.
// Translation invariance: the power spectrum ignores phase, so a circular shift changes nothing
// but the window's view (tested).
#include "metrics/metric.h"

namespace proctex::metrics {

class SpectrumMetric final : public Metric {
 public:
  static constexpr int kRadialBins = 12;
  static constexpr int kOrientationBins = 6;
  static constexpr int kOrientationBands = 3;

  std::string id() const override { return "spectrum"; }
  int version() const override { return 1; }
  std::string summary() const override {
    return "windowed power spectrum of lightness, radial + orientation bins (thesis eq 4.10)";
  }
  std::size_t feature_size() const override {
    return kRadialBins + kOrientationBins * kOrientationBands;
  }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override;
  // Feature groups for the default metric (composite.h): RMS difference of the radial log powers, RMS difference of the orientation log ratios.
  std::size_t group_count() const override;
  std::string group_name(std::size_t group) const override;
  void group_distances(std::span<const float> a, std::span<const float> b, double* out) const override;

  // The crop-averaged, windowed power spectrum of a square plane as (size/2) x (size/4 + 1)
  // half-plane values (exposed for tests: translation invariance).
  static std::vector<float> averaged_power(const std::vector<float>& plane, int size);
};

}  // namespace proctex::metrics
