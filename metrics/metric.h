#pragma once
// Texture similarity: the metric contract every folder ranks textures with.
//
//   const auto& m = proctex::metrics::get_metric("default");
//   Features fa = m.features(photo);       // once per image; cacheable (id, version, resolution)
//   Features fb = m.features(render);
//   double s = m.similarity(fa, fb);       // in (0, 1], symmetric, exactly 1 for equal features
//
// Two images of one texture rarely share a pixel, so metrics compare statistics (spectra,
// band-pass histograms, colour distributions, oriented filter statistics), never pixels.
// A metric is a stateless plug-in: every member is const and safe to call from many threads.
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "image/image.h"

namespace proctex::metrics {

inline constexpr int kDefaultResolution = 256;
inline constexpr int kMinResolution = 64;    // the pyramid and filter bank need 5 octaves
inline constexpr int kMaxResolution = 4096;
inline constexpr int kMinImageSide = 8;      // smaller inputs carry no texture: proctex::Error

// What every metric analyses: the image centre-cropped to a square (so the aspect ratio, and with
// it every orientation, is kept), then resized area-correctly to resolution x resolution. A crop
// rather than a stretch because stretching changes orientations and frequencies, which is exactly
// what the structural metrics measure. Images smaller than the resolution are enlarged by the
// same resize (blocky, but it keeps the feature length fixed; prefer a smaller resolution).
struct Analysis {
  int size = 0;                  // side in pixels (= resolution)
  Image rgb;                     // linear RGB, size x size
  std::vector<float> L, a, b;    // CIELAB (D65) planes; L in [0, 100]
  std::vector<float> lightness;  // L / 100: the structural metrics' input (perceptual, not linear)
};

// Throws proctex::Error for an empty image, one smaller than kMinImageSide on a side, non-finite
// pixels, or a resolution outside [kMinResolution, kMaxResolution] or not a multiple of 16.
Analysis prepare_analysis(const Image& image, int resolution = kDefaultResolution);

// Linear sRGB (D65) -> CIELAB. Exposed for tests and the colour metric.
void linear_rgb_to_lab(float r, float g, float b, float& L, float& A, float& B);

// A feature vector with the tag that makes it cacheable: a catalogue stores `values` as a float32
// BLOB under (metric, version, resolution) and recomputes when any of them differs.
struct Features {
  std::string metric;
  int version = 0;
  int resolution = 0;
  std::vector<float> values;
};

class Metric {
 public:
  virtual ~Metric() = default;

  // Stable lowercase id ("spectrum", "pyramid", ...); never reused for a different computation.
  virtual std::string id() const = 0;
  // Bumped whenever the feature computation or layout changes (stale cached features).
  virtual int version() const = 0;
  virtual std::string summary() const = 0;
  // Length of the feature vector (independent of the resolution).
  virtual std::size_t feature_size() const = 0;

  // Raw feature vector of a prepared analysis.
  virtual std::vector<float> compute(const Analysis& analysis) const = 0;
  // Distance between two raw feature vectors: >= 0, 0 for equal vectors. Callers should use
  // similarity(), which also makes the result exactly symmetric.
  virtual double distance(std::span<const float> a, std::span<const float> b) const = 0;
  // The distance that maps to similarity 1/e (calibrated per metric, see docs/metrics.md).
  virtual double scale() const = 0;

  // Feature groups: the distance split into parts (>= 0, 0 for equal vectors) that the default
  // metric weights separately (composite.h). By default one group: distance() / scale().
  virtual std::size_t group_count() const { return 1; }
  virtual std::string group_name(std::size_t group) const;
  // Writes group_count() values to `out`.
  virtual void group_distances(std::span<const float> a, std::span<const float> b, double* out) const {
    out[0] = distance(a, b) / scale();
  }

  Features features(const Image& image, int resolution = kDefaultResolution) const;
  Features features(const Analysis& analysis) const;

  // exp(-distance / scale): in (0, 1], exactly 1 for equal vectors, exactly symmetric (the pair
  // is put in a canonical order before the distance is computed).
  double similarity(std::span<const float> a, std::span<const float> b) const;
  // Same, after checking that both tags name this metric, its version and one resolution
  // (throws proctex::Error otherwise: stale or mixed cached features).
  double similarity(const Features& a, const Features& b) const;
  // Convenience: features of both images, then similarity.
  double similarity(const Image& a, const Image& b, int resolution = kDefaultResolution) const;

  // Throws proctex::Error unless `f` is this metric's current features (id, version, length).
  void check(const Features& f) const;
};

// Plug-in registry. Built-in metrics: "spectrum", "pyramid", "colour", "structure",
// "composite" (alias "default"). Names are case-insensitive; "color" is accepted for "colour".
// Throws proctex::Error listing the known names for an unknown one.
const Metric& get_metric(std::string_view name);
const Metric& default_metric();
// Ids of the registered metrics in registration order (built-ins first, composite last).
std::vector<std::string> metric_names();
// Adds or replaces (same id) a metric. Not to be called while other threads look metrics up.
void register_metric(std::shared_ptr<const Metric> metric);

}  // namespace proctex::metrics
