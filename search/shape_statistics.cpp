// Orientation and elongation statistics of a texture's lightness (search/selection.h).
#include <algorithm>
#include <cmath>
#include <vector>

#include "image/image.h"
#include "search/selection.h"

namespace proctex::search {

namespace {

// A single-channel image; borders are clamped (a photo does not wrap around).
struct Plane {
  int w = 0, h = 0;
  std::vector<float> v;
  float at(int x, int y) const { return v[static_cast<size_t>(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)]; }
};

Plane blurred(const Plane& in, float sigma) {
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0f * sigma)));
  std::vector<float> k(2 * radius + 1);
  float total = 0;
  for (int i = -radius; i <= radius; ++i) total += k[i + radius] = std::exp(-0.5f * i * i / (sigma * sigma));
  for (float& x : k) x /= total;
  Plane tmp = in, out = in;
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      float s = 0;
      for (int i = -radius; i <= radius; ++i) s += k[i + radius] * in.at(x + i, y);
      tmp.v[static_cast<size_t>(y) * in.w + x] = s;
    }
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      float s = 0;
      for (int i = -radius; i <= radius; ++i) s += k[i + radius] * tmp.at(x, y + i);
      out.v[static_cast<size_t>(y) * in.w + x] = s;
    }
  return out;
}

Plane halved(const Plane& in) {
  Plane out{in.w / 2, in.h / 2, {}};
  out.v.resize(static_cast<size_t>(out.w) * out.h);
  for (int y = 0; y < out.h; ++y)
    for (int x = 0; x < out.w; ++x)
      out.v[static_cast<size_t>(y) * out.w + x] =
          0.25f * (in.at(2 * x, 2 * y) + in.at(2 * x + 1, 2 * y) + in.at(2 * x, 2 * y + 1) + in.at(2 * x + 1, 2 * y + 1));
  return out;
}

// The statistics of one pyramid level, appended to `out` (kShapeStatisticsPerLevel values).
void level_statistics(const Plane& level, std::vector<double>& out) {
  const Plane smooth = blurred(level, 1.0f);
  const int w = level.w, h = level.h;
  const size_t n = static_cast<size_t>(w) * h;
  Plane jxx{w, h, std::vector<float>(n)}, jxy = jxx, jyy = jxx;
  double gxx = 0, gxy = 0, gyy = 0;  // the whole level's gradient tensor
  double ridge_num = 0, ridge_den = 0, blob = 0, polarity = 0, polarity_den = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float c = smooth.at(x, y);
      const float gx = 0.5f * (smooth.at(x + 1, y) - smooth.at(x - 1, y));
      const float gy = 0.5f * (smooth.at(x, y + 1) - smooth.at(x, y - 1));
      jxx.v[i] = gx * gx;
      jxy.v[i] = gx * gy;
      jyy.v[i] = gy * gy;
      gxx += gx * gx;
      gxy += gx * gy;
      gyy += gy * gy;
      // Hessian: a ridge (blade, crack, vein) has one large curvature, a blob (pebble, cell) two of
      // one sign; the sign of the large one says bright or dark.
      const float hxx = smooth.at(x + 1, y) - 2 * c + smooth.at(x - 1, y);
      const float hyy = smooth.at(x, y + 1) - 2 * c + smooth.at(x, y - 1);
      const float hxy = 0.25f * (smooth.at(x + 1, y + 1) - smooth.at(x - 1, y + 1) - smooth.at(x + 1, y - 1) +
                                 smooth.at(x - 1, y - 1));
      const double m = 0.5 * (hxx + hyy), r = std::hypot(0.5 * (hxx - hyy), static_cast<double>(hxy));
      const double h1 = m + r, h2 = m - r;
      const double big = std::abs(h1) >= std::abs(h2) ? h1 : h2, small = std::abs(h1) >= std::abs(h2) ? h2 : h1;
      const double weight = std::abs(big) + std::abs(small);
      ridge_num += std::abs(big) - std::abs(small);
      ridge_den += weight;
      // a blob curves strongly both ways: counted by the smaller curvature (a straight ridge's
      // second curvature is ~0 with either sign)
      if (h1 * h2 > 0) blob += 2.0 * std::abs(small);
      // weighted by |big|: the sign of the strongest curvatures (a thin line's centre, not the
      // wider, weaker shoulders around it, whose sum cancels the centre's)
      polarity += big * std::abs(big);
      polarity_den += big * big;
    }
  auto ratio = [](double a, double b) { return b > 1e-20 ? a / b : 0.0; };
  // Coherence of the local structure tensor at a small and a wide integration scale: elongated
  // structures (blades, grain, stripes) stay coherent over the wide window, blobs and noise do not.
  for (float sigma : {1.5f, 4.0f}) {
    const Plane a = blurred(jxx, sigma), b = blurred(jxy, sigma), d = blurred(jyy, sigma);
    double coherent = 0, trace_total = 0, coherent_share = 0, cos4 = 0, sin4 = 0;
    for (size_t i = 0; i < n; ++i) {
      const double trace = a.v[i] + d.v[i];
      const double dx = a.v[i] - d.v[i], dy = 2.0 * b.v[i];
      const double diff = std::hypot(dx, dy);
      coherent += diff;
      trace_total += trace;
      if (diff > 0.6 * trace) coherent_share += trace;
      if (sigma < 2.0f && diff > 1e-20) {  // doubled orientation (dx, dy) / diff, squared again: 4 theta
        cos4 += (dx * dx - dy * dy) / diff;
        sin4 += 2.0 * dx * dy / diff;
      }
    }
    out.push_back(ratio(coherent, trace_total));
    out.push_back(ratio(coherent_share, trace_total));
    if (sigma < 2.0f) out.push_back(ratio(std::hypot(cos4, sin4), coherent));  // square grids: two directions
  }
  // One dominant direction over the whole level (stripes, grain, brushed metal, a lawn's blades).
  out.push_back(ratio(std::hypot(gxx - gyy, 2.0 * gxy), gxx + gyy));
  out.push_back(ratio(ridge_num, ridge_den));
  out.push_back(ratio(blob, ridge_den));
  out.push_back(ratio(polarity, polarity_den));
}

// The view's lightness (CIE L*/100) at `resolution` x `resolution`: perceptual, so dark and
// bright structure weigh alike.
Plane lightness_plane(const Image& view, int resolution) {
  const Image square = view.width == resolution && view.height == resolution
                           ? view
                           : resize(center_crop_square(view), resolution, resolution);
  Plane level{resolution, resolution, {}};
  level.v.resize(static_cast<size_t>(resolution) * resolution);
  for (size_t i = 0; i < level.v.size(); ++i) {
    const double y = std::max(0.0f, luminance(square.pixels.data() + 3 * i));
    level.v[i] = static_cast<float>(y > 216.0 / 24389.0 ? 1.16 * std::cbrt(y) - 0.16 : y * 24389.0 / 2700.0);
  }
  return level;
}

// Rotation-invariant uniform local binary patterns of one level (Ojala, Pietikainen and Maenpaa
// 2002, "riu2"): P neighbours on a circle of radius R (bilinear), each compared with the centre;
// a circular bit string with at most two 0/1 transitions (a spot, a flat area, an edge, a line
// end, a corner) is labelled by its number of ones (0..P), any other by P + 1. Appends the square
// roots of the P + 2 label shares (the roots give the rare labels weight).
void binary_pattern_histogram(const Plane& level, int points, float radius, std::vector<double>& out) {
  // Differences below this (a tenth of an L* unit) count as equal: a float render's flat area
  // and an 8-bit photo's must give the same labels.
  constexpr float kEqual = 0.001f;
  std::vector<double> histogram(points + 2, 0.0);
  std::vector<float> dx(points), dy(points);
  for (int p = 0; p < points; ++p) {
    const double angle = 2.0 * M_PI * p / points;
    dx[p] = static_cast<float>(radius * std::cos(angle));
    dy[p] = static_cast<float>(-radius * std::sin(angle));
  }
  const int margin = static_cast<int>(std::ceil(radius)) + 1;
  std::vector<int> bits(points);
  for (int y = margin; y < level.h - margin; ++y)
    for (int x = margin; x < level.w - margin; ++x) {
      const float centre = level.at(x, y);
      for (int p = 0; p < points; ++p) {
        const float sx = x + dx[p], sy = y + dy[p];
        const int x0 = static_cast<int>(std::floor(sx)), y0 = static_cast<int>(std::floor(sy));
        const float fx = sx - x0, fy = sy - y0;
        const float v = (1 - fy) * ((1 - fx) * level.at(x0, y0) + fx * level.at(x0 + 1, y0)) +
                        fy * ((1 - fx) * level.at(x0, y0 + 1) + fx * level.at(x0 + 1, y0 + 1));
        bits[p] = v - centre > -kEqual ? 1 : 0;
      }
      int ones = 0, transitions = 0;
      for (int p = 0; p < points; ++p) {
        ones += bits[p];
        transitions += bits[p] != bits[(p + 1) % points];
      }
      histogram[transitions <= 2 ? ones : points + 1] += 1.0;
    }
  double total = 0;
  for (double h : histogram) total += h;
  for (double h : histogram) out.push_back(total > 0 ? std::sqrt(h / total) : 0.0);
}

}  // namespace

std::vector<double> shape_statistics(const Image& view, int resolution) {
  Plane level = lightness_plane(view, resolution);
  std::vector<double> out;
  for (int l = 0; l < kShapeLevels; ++l) {
    level_statistics(level, out);
    if (l + 1 < kShapeLevels) level = halved(level);
  }
  return out;
}

std::vector<double> micro_statistics(const Image& view, int resolution) {
  Plane level = lightness_plane(view, resolution);
  std::vector<double> out;
  for (int l = 0; l < kMicroLevels; ++l) {
    binary_pattern_histogram(level, 8, 1.0f, out);
    binary_pattern_histogram(level, 16, 2.0f, out);
    if (l + 1 < kMicroLevels) level = halved(level);
  }
  return out;
}

}  // namespace proctex::search
