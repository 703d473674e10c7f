#pragma once
// Synthetic RGBNs with known truth for the rgbn tests.
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <unistd.h>

#include "rgbn/rgbn.h"

namespace rgbn_test {

using proctex::rgbn::HeightField;
using proctex::rgbn::Rgbn;

// A smooth periodic height field: a few random sinusoids with whole periods over the image.
inline HeightField periodic_field(int w, int h, unsigned seed, float amplitude = 3.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  HeightField z{w, h, std::vector<float>(size_t(w) * h, 0.0f)};
  for (int k = 0; k < 6; ++k) {
    const int fx = 1 + int(u(rng) * 3), fy = int(u(rng) * 3);
    const float ph = u(rng) * 6.28f, a = amplitude * (0.3f + u(rng)) / (fx + fy);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) z.at(x, y) += a * std::sin(6.2831853f * (fx * x / float(w) + fy * y / float(h)) + ph);
  }
  return z;
}

// Angle between two (unit) vectors, accurate for small angles too (atan2 of |a x b| and a.b).
inline double angle_deg(const float* a, const float* b) {
  const double d = double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2];
  const double cx = double(a[1]) * b[2] - double(a[2]) * b[1], cy = double(a[2]) * b[0] - double(a[0]) * b[2],
               cz = double(a[0]) * b[1] - double(a[1]) * b[0];
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), d) * 180.0 / M_PI;
}

inline double max_angle(const Rgbn& a, const Rgbn& b) {
  double m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, angle_deg(&a.normal[3 * i], &b.normal[3 * i]));
  return m;
}

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) {
    path = std::filesystem::temp_directory_path() / ("proctex-rgbn-" + std::to_string(getpid()) + "-" + name);
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

}  // namespace rgbn_test
