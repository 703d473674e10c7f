#include "metrics/metric.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <mutex>
#include <shared_mutex>

#include "core/error.h"
#include "metrics/colour.h"
#include "metrics/composite.h"
#include "metrics/pyramid.h"
#include "metrics/spectrum.h"
#include "metrics/structure.h"

namespace proctex::metrics {
namespace {

// CIELAB f(t) = cbrt(t) above (6/29)^3, linear below. cbrt per channel per pixel costs more than
// the rest of the colour metric, so [0, 1] goes through a table with linear interpolation
// (error < 1e-3 in L*); values above 1 (HDR) fall back to std::cbrt.
constexpr int kLabTableSize = 8192;
const std::array<float, kLabTableSize + 2>& lab_table() {
  static const auto table = [] {
    std::array<float, kLabTableSize + 2> t{};
    for (int i = 0; i <= kLabTableSize + 1; ++i) {
      double x = static_cast<double>(i) / kLabTableSize;
      constexpr double d = 6.0 / 29.0;
      t[i] = static_cast<float>(x > d * d * d ? std::cbrt(x) : x / (3 * d * d) + 4.0 / 29.0);
    }
    return t;
  }();
  return table;
}

inline float lab_f(float x) {
  if (!(x > 0.0f)) x = 0.0f;  // negative (out-of-gamut EXR) and NaN-safe
  if (x >= 1.0f) return std::cbrt(x);
  const auto& t = lab_table();
  float p = x * kLabTableSize;
  int i = static_cast<int>(p);
  float fr = p - static_cast<float>(i);
  return t[i] + fr * (t[i + 1] - t[i]);
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

struct Registry {
  std::shared_mutex mutex;
  std::vector<std::shared_ptr<const Metric>> metrics;
  std::vector<std::shared_ptr<const Metric>> retired;  // replaced ones stay alive (references)

  Registry() {
    auto spectrum = std::make_shared<SpectrumMetric>();
    auto pyramid = std::make_shared<PyramidMetric>();
    auto colour = std::make_shared<ColourMetric>();
    auto structure = std::make_shared<StructureMetric>();
    metrics = {spectrum, pyramid, colour, structure, CompositeMetric::make_grouped(),
               CompositeMetric::make_layout(), CompositeMetric::make_default()};
  }
};

Registry& registry() {
  static Registry* r = new Registry();  // never destroyed: metrics outlive static destructors
  return *r;
}

}  // namespace

void linear_rgb_to_lab(float r, float g, float b, float& L, float& A, float& B) {
  // sRGB primaries, D65 white, normalised by the white point.
  float x = (0.4124564f * r + 0.3575761f * g + 0.1804375f * b) / 0.95047f;
  float y = 0.2126729f * r + 0.7151522f * g + 0.0721750f * b;
  float z = (0.0193339f * r + 0.1191920f * g + 0.9503041f * b) / 1.08883f;
  float fx = lab_f(x), fy = lab_f(y), fz = lab_f(z);
  L = 116.0f * fy - 16.0f;
  A = 500.0f * (fx - fy);
  B = 200.0f * (fy - fz);
}

Analysis prepare_analysis(const Image& image, int resolution) {
  if (resolution < kMinResolution || resolution > kMaxResolution || resolution % 16 != 0) {
    throw Error("analysis resolution " + std::to_string(resolution) + " is not supported",
                "use a multiple of 16 between " + std::to_string(kMinResolution) + " and " +
                    std::to_string(kMaxResolution) + " (default " +
                    std::to_string(kDefaultResolution) + ")");
  }
  if (image.empty()) {
    throw Error("cannot compare an empty image", "give an image with at least " +
                                                     std::to_string(kMinImageSide) + " x " +
                                                     std::to_string(kMinImageSide) + " pixels");
  }
  if (image.width < kMinImageSide || image.height < kMinImageSide) {
    throw Error("image of " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                    " pixels is too small to have a texture",
                "give an image with at least " + std::to_string(kMinImageSide) + " pixels on "
                "each side (" + std::to_string(kDefaultResolution) + " or more is best)");
  }
  if (image.pixels.size() != static_cast<size_t>(image.width) * image.height * 3) {
    throw Error("image pixel buffer does not match its size", "this is a bug in the caller");
  }
  for (float v : image.pixels) {
    if (!std::isfinite(v)) {
      throw Error("image has non-finite (NaN or infinite) pixels",
                  "clamp or repair the image before comparing it");
    }
  }

  Analysis an;
  an.size = resolution;
  const Image* src = &image;
  Image square;
  if (image.width != image.height) {
    square = center_crop_square(image);
    src = &square;
  }
  if (src->width == resolution) {
    an.rgb = *src;
  } else {
    an.rgb = resize(*src, resolution, resolution);
  }
  const size_t n = static_cast<size_t>(resolution) * resolution;
  an.L.resize(n);
  an.a.resize(n);
  an.b.resize(n);
  an.lightness.resize(n);
  const float* p = an.rgb.pixels.data();
  for (size_t i = 0; i < n; ++i) {
    // A pattern's flat regions repeat one colour pixel after pixel: the cube roots are skipped.
    if (i > 0 && p[3 * i] == p[3 * i - 3] && p[3 * i + 1] == p[3 * i - 2] && p[3 * i + 2] == p[3 * i - 1]) {
      an.L[i] = an.L[i - 1];
      an.a[i] = an.a[i - 1];
      an.b[i] = an.b[i - 1];
    } else {
      linear_rgb_to_lab(p[3 * i], p[3 * i + 1], p[3 * i + 2], an.L[i], an.a[i], an.b[i]);
    }
    an.lightness[i] = an.L[i] * 0.01f;
  }
  return an;
}

std::string Metric::group_name(std::size_t group) const {
  return group == 0 && group_count() == 1 ? id() : id() + "." + std::to_string(group);
}

Features Metric::features(const Image& image, int resolution) const {
  return features(prepare_analysis(image, resolution));
}

Features Metric::features(const Analysis& analysis) const {
  Features f;
  f.metric = id();
  f.version = version();
  f.resolution = analysis.size;
  f.values = compute(analysis);
  return f;
}

double Metric::similarity(std::span<const float> a, std::span<const float> b) const {
  if (a.size() != feature_size() || b.size() != feature_size()) {
    throw Error("feature vector of length " + std::to_string(a.size() != feature_size() ? a.size() : b.size()) +
                    " given to metric '" + id() + "', which expects " +
                    std::to_string(feature_size()),
                "recompute the features with this metric (cached features may be stale)");
  }
  if (std::equal(a.begin(), a.end(), b.begin())) return 1.0;
  // Canonical order makes the result bit-for-bit symmetric whatever the distance's rounding.
  if (std::lexicographical_compare(b.begin(), b.end(), a.begin(), a.end())) std::swap(a, b);
  double d = distance(a, b);
  if (!(d >= 0.0)) d = 0.0;
  double s = std::exp(-d / scale());
  // Keep it strictly positive: a similarity of 0 is outside the contract's (0, 1].
  return std::max(s, 1e-300);
}

void Metric::check(const Features& f) const {
  if (f.metric != id() || f.version != version() || f.values.size() != feature_size()) {
    throw Error("features of '" + f.metric + "' version " + std::to_string(f.version) +
                    " (length " + std::to_string(f.values.size()) + ") do not belong to metric '" +
                    id() + "' version " + std::to_string(version()),
                "recompute the features with the current metric");
  }
}

double Metric::similarity(const Features& a, const Features& b) const {
  check(a);
  check(b);
  if (a.resolution != b.resolution) {
    throw Error("features computed at different analysis resolutions (" +
                    std::to_string(a.resolution) + " and " + std::to_string(b.resolution) + ")",
                "compute both at the same resolution");
  }
  return similarity(std::span<const float>(a.values), std::span<const float>(b.values));
}

double Metric::similarity(const Image& a, const Image& b, int resolution) const {
  Analysis aa = prepare_analysis(a, resolution);
  Analysis ab = prepare_analysis(b, resolution);
  return similarity(features(aa), features(ab));
}

const Metric& get_metric(std::string_view name) {
  std::string key = lower(name);
  if (key == "default") key = "composite";
  if (key == "color") key = "colour";
  Registry& r = registry();
  std::shared_lock lock(r.mutex);
  for (const auto& m : r.metrics) {
    if (m->id() == key) return *m;
  }
  std::string known;
  for (const auto& m : r.metrics) known += (known.empty() ? "" : ", ") + m->id();
  throw Error("unknown metric '" + std::string(name) + "'", "known metrics: " + known +
                                                                 " (default = composite)");
}

const Metric& default_metric() { return get_metric("composite"); }

std::vector<std::string> metric_names() {
  Registry& r = registry();
  std::shared_lock lock(r.mutex);
  std::vector<std::string> names;
  for (const auto& m : r.metrics) names.push_back(m->id());
  return names;
}

void register_metric(std::shared_ptr<const Metric> metric) {
  if (!metric) throw Error("register_metric was given no metric", "this is a bug in the caller");
  Registry& r = registry();
  std::unique_lock lock(r.mutex);
  for (auto& m : r.metrics) {
    if (m->id() == metric->id()) {
      r.retired.push_back(m);
      m = std::move(metric);
      return;
    }
  }
  r.metrics.push_back(std::move(metric));
}

}  // namespace proctex::metrics
