// Tests of the texture similarity metrics: the contract (identity, symmetry, range, tags,
// errors), behaviour (monotonic fall with blur, noise, colour shift; same texture beats a
// different one) and invariances (spectrum under translation).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <thread>

#include "core/error.h"
#include "metrics/composite.h"
#include "metrics/metric.h"
#include "metrics/colour.h"
#include "metrics/spectrum.h"

using namespace proctex;
using namespace proctex::metrics;

namespace {

const std::string kShared = PROCTEX_SHARED_DIR;

const Image& photo(const std::string& name) {
  static std::map<std::string, Image> cache;
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, load_image(kShared + "/textures/" + name)).first;
  return it->second;
}

// Two non-overlapping 256 x 256 crops of a 512 x 512 photo.
Image crop_a(const std::string& name) { return crop(photo(name), 0, 0, 256, 256); }
Image crop_b(const std::string& name) { return crop(photo(name), 256, 256, 256, 256); }

Image gaussian_blur(const Image& in, double sigma) {
  if (sigma <= 0) return in;
  const int r = static_cast<int>(std::ceil(3 * sigma));
  std::vector<float> k(2 * r + 1);
  float sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = static_cast<float>(std::exp(-i * i / (2 * sigma * sigma)));
  for (float& v : k) v /= sum;
  auto pass = [&](const Image& src, bool horizontal) {
    Image out(src.width, src.height);
    for (int y = 0; y < src.height; ++y)
      for (int x = 0; x < src.width; ++x)
        for (int c = 0; c < 3; ++c) {
          float acc = 0;
          for (int i = -r; i <= r; ++i) {
            int xx = horizontal ? std::clamp(x + i, 0, src.width - 1) : x;
            int yy = horizontal ? y : std::clamp(y + i, 0, src.height - 1);
            acc += k[i + r] * src.pixel(xx, yy)[c];
          }
          out.pixel(x, y)[c] = acc;
        }
    return out;
  };
  return pass(pass(in, true), false);
}

Image add_noise(const Image& in, double sigma, unsigned seed = 42) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, 1.0f);
  Image out = in;
  // The same noise field scaled, so larger sigma is strictly more of the same perturbation.
  for (size_t i = 0; i < out.pixels.size(); i += 3) {
    float v = n(rng) * static_cast<float>(sigma);
    for (int c = 0; c < 3; ++c) out.pixels[i + c] = std::max(0.0f, out.pixels[i + c] + v);
  }
  return out;
}

Image tint(const Image& in, float amount) {
  Image out = in;
  for (size_t i = 0; i < out.pixels.size(); i += 3) {
    out.pixels[i] *= 1.0f + amount;
    out.pixels[i + 2] *= 1.0f / (1.0f + amount);
  }
  return out;
}

Image circular_shift(const Image& in, int dx, int dy) {
  Image out(in.width, in.height);
  for (int y = 0; y < in.height; ++y)
    for (int x = 0; x < in.width; ++x) {
      const float* p = in.pixel(x, y);
      float* q = out.pixel((x + dx) % in.width, (y + dy) % in.height);
      q[0] = p[0];
      q[1] = p[1];
      q[2] = p[2];
    }
  return out;
}

// A periodic (tileable) broadband texture: white noise blurred circularly (so it wraps without
// a seam) plus an oriented sinusoid with an integer frequency.
Image periodic_texture(int n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> noise(static_cast<size_t>(n) * n), blurred(noise.size(), 0.0f);
  for (float& v : noise) v = u(rng);
  const int r = 2;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      float acc = 0;
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) acc += noise[((y + j + n) % n) * n + (x + i + n) % n];
      blurred[y * n + x] = acc / ((2 * r + 1) * (2 * r + 1));
    }
  Image img(n, n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double t = 2 * M_PI / n;
      float v = 0.3f + 0.3f * blurred[y * n + x] + 0.08f * static_cast<float>(std::sin(t * (8 * x + 3 * y)));
      float* p = img.pixel(x, y);
      p[0] = v;
      p[1] = 0.8f * v;
      p[2] = 0.6f * v;
    }
  return img;
}

std::vector<std::string> all_metrics() { return metric_names(); }

}  // namespace

TEST(Metrics, RegistryHasBuiltInsAndDefault) {
  auto names = metric_names();
  for (const char* id : {"spectrum", "pyramid", "colour", "structure", "composite"})
    EXPECT_NE(std::find(names.begin(), names.end(), id), names.end()) << id;
  EXPECT_EQ(default_metric().id(), "composite");
  EXPECT_EQ(get_metric("DEFAULT").id(), "composite");
  EXPECT_EQ(get_metric("color").id(), "colour");
  EXPECT_THROW(get_metric("nope"), proctex::Error);
}

TEST(Metrics, IdentityIsExactlyOneAndFeatureLengthIsFixed) {
  const Image a = crop_a("brick.png");
  for (const auto& name : all_metrics()) {
    const Metric& m = get_metric(name);
    Features f = m.features(a);
    EXPECT_EQ(f.metric, name);
    EXPECT_EQ(f.version, m.version());
    EXPECT_EQ(f.resolution, kDefaultResolution);
    EXPECT_EQ(f.values.size(), m.feature_size()) << name;
    for (float v : f.values) ASSERT_TRUE(std::isfinite(v)) << name;
    EXPECT_EQ(m.similarity(f, f), 1.0) << name;
    // Recomputing gives bit-identical features (deterministic FFT plans): still exactly 1.
    EXPECT_EQ(m.similarity(f, m.features(a)), 1.0) << name;
    // Any size, any aspect ratio: same feature length.
    EXPECT_EQ(m.features(photo("hubble_deep_field.jpg")).values.size(), m.feature_size());
    EXPECT_EQ(m.features(crop(photo("grass.png"), 0, 0, 100, 60)).values.size(), m.feature_size());
    EXPECT_EQ(m.features(a, 64).values.size(), m.feature_size());
  }
}

TEST(Metrics, SymmetricAndInRange) {
  const Image a = crop_a("brick.png"), b = crop_a("gravel.png");
  for (const auto& name : all_metrics()) {
    const Metric& m = get_metric(name);
    Features fa = m.features(a), fb = m.features(b);
    const double ab = m.similarity(fa, fb), ba = m.similarity(fb, fa);
    EXPECT_EQ(ab, ba) << name;
    EXPECT_GT(ab, 0.0) << name;
    EXPECT_LT(ab, 1.0) << name;
  }
}

TEST(Metrics, FallsMonotonicallyWithBlur) {
  const Image a = crop_a("gravel.png");
  for (const char* name : {"spectrum", "pyramid", "structure", "composite"}) {
    const Metric& m = get_metric(name);
    Features fa = m.features(a);
    double last = 1.0;
    for (double sigma : {0.5, 1.0, 2.0, 4.0}) {
      double s = m.similarity(fa, m.features(gaussian_blur(a, sigma)));
      EXPECT_LT(s, last) << name << " blur sigma " << sigma;
      last = s;
    }
  }
}

TEST(Metrics, FallsMonotonicallyWithNoise) {
  const Image a = crop_a("brick.png");
  for (const auto& name : all_metrics()) {
    const Metric& m = get_metric(name);
    Features fa = m.features(a);
    double last = 1.0;
    for (double sigma : {0.01, 0.03, 0.1, 0.3}) {
      double s = m.similarity(fa, m.features(add_noise(a, sigma)));
      EXPECT_LT(s, last) << name << " noise sigma " << sigma;
      last = s;
    }
  }
}

TEST(Metrics, FallsMonotonicallyWithColourShift) {
  const Image a = crop(photo("hubble_deep_field.jpg"), 0, 0, 436, 436);
  const Image g = crop_a("grass.png");
  for (const char* name : {"colour", "composite"}) {
    const Metric& m = get_metric(name);
    for (const Image* img : {&a, &g}) {
      Features fa = m.features(*img);
      double last = 1.0;
      for (float amount : {0.05f, 0.15f, 0.4f, 1.0f}) {
        double s = m.similarity(fa, m.features(tint(*img, amount)));
        EXPECT_LT(s, last) << name << " tint " << amount;
        last = s;
      }
    }
  }
}

TEST(Metrics, SameTextureOtherCropBeatsDifferentTexture) {
  const std::vector<std::string> photos = {"brick.png", "grass.png", "gravel.png"};
  for (const char* name : {"spectrum", "pyramid", "structure", "composite"}) {
    const Metric& m = get_metric(name);
    std::vector<Features> fa, fb;
    for (const auto& p : photos) {
      fa.push_back(m.features(crop_a(p)));
      fb.push_back(m.features(crop_b(p)));
    }
    Features hubble = m.features(crop(photo("hubble_deep_field.jpg"), 0, 0, 436, 436));
    for (size_t i = 0; i < photos.size(); ++i) {
      const double same = m.similarity(fa[i], fb[i]);
      for (size_t j = 0; j < photos.size(); ++j) {
        if (i == j) continue;
        EXPECT_GT(same, m.similarity(fa[i], fb[j])) << name << " " << photos[i] << " vs " << photos[j];
        EXPECT_GT(same, m.similarity(fa[i], fa[j])) << name << " " << photos[i] << " vs " << photos[j];
      }
      EXPECT_GT(same, m.similarity(fa[i], hubble)) << name << " " << photos[i] << " vs hubble";
    }
  }
}

TEST(Metrics, SpectrumIsTranslationInvariant) {
  const Metric& m = get_metric("spectrum");
  // A periodic texture shifted circularly is the same texture (no seam appears): the spectrum
  // ignores phase, so only the windows' view of the noise changes.
  const Image p = periodic_texture(256);
  Features fp = m.features(p);
  const Image other = crop_a("grass.png");
  const double different = m.similarity(fp, m.features(other));
  for (auto [dx, dy] : {std::pair{37, 91}, std::pair{128, 0}, std::pair{5, 200}}) {
    const double s = m.similarity(fp, m.features(circular_shift(p, dx, dy)));
    EXPECT_GT(s, 0.75) << dx << "," << dy;  // windowed estimates of a noise field vary a little
    EXPECT_GT(s, different);
  }
  // A translated window of a photo scores as the same texture, above any other photo.
  const Image& brick = photo("brick.png");
  Features fa = m.features(crop(brick, 100, 100, 256, 256));
  const double shifted = m.similarity(fa, m.features(crop(brick, 107, 93, 256, 256)));
  EXPECT_GT(shifted, 0.9);
  EXPECT_GT(shifted, m.similarity(fa, m.features(crop_a("gravel.png"))));
  // Half-plane power of one crop layout: the same numbers whatever the shift of a constant image.
  const std::vector<float> flat(256 * 256, 0.5f);
  for (float v : SpectrumMetric::averaged_power(flat, 256)) EXPECT_LT(v, 1e-10f);
}

TEST(Metrics, GarbageInputGivesClearError) {
  for (const auto& name : all_metrics()) {
    const Metric& m = get_metric(name);
    EXPECT_THROW(m.features(Image()), proctex::Error) << name;
    EXPECT_THROW(m.features(Image(1, 1, 0.5f)), proctex::Error) << name;
    EXPECT_THROW(m.features(Image(300, 4, 0.5f)), proctex::Error) << name;
  }
  Image nan_image(32, 32, 0.5f);
  nan_image.pixels[10] = std::nanf("");
  EXPECT_THROW(default_metric().features(nan_image), proctex::Error);
  EXPECT_THROW(default_metric().features(crop_a("brick.png"), 100), proctex::Error);
  EXPECT_THROW(default_metric().features(crop_a("brick.png"), 32), proctex::Error);
  try {
    default_metric().features(Image(1, 1, 0.5f));
    FAIL();
  } catch (const proctex::Error& e) {
    EXPECT_NE(std::string(e.what()).find("too small"), std::string::npos) << e.what();
    EXPECT_FALSE(e.hint().empty());
  }
}

TEST(Metrics, MismatchedFeaturesAreRejected) {
  const Image a = crop_a("brick.png");
  Features spectrum = get_metric("spectrum").features(a);
  Features colour = get_metric("colour").features(a);
  EXPECT_THROW(get_metric("spectrum").similarity(spectrum, colour), proctex::Error);
  Features stale = spectrum;
  stale.version += 1;
  EXPECT_THROW(get_metric("spectrum").similarity(spectrum, stale), proctex::Error);
  Features other_res = get_metric("spectrum").features(a, 128);
  EXPECT_THROW(get_metric("spectrum").similarity(spectrum, other_res), proctex::Error);
}

TEST(Metrics, CompositeBreakdownMatchesComponents) {
  // The default (product form): S = prod S_k^{w_k}; breakdown() gives every S_k.
  const auto& composite = dynamic_cast<const CompositeMetric&>(default_metric());
  const Image a = crop_a("brick.png"), b = crop_b("grass.png");
  Features fa = composite.features(a), fb = composite.features(b);
  const auto parts = composite.breakdown(fa.values, fb.values);
  ASSERT_EQ(parts.size(), composite.components().size());
  double log_s = 0;
  for (size_t i = 0; i < parts.size(); ++i) {
    const Metric& m = get_metric(parts[i].first);
    EXPECT_NEAR(parts[i].second, m.similarity(m.features(a), m.features(b)), 1e-9) << parts[i].first;
    log_s += composite.components()[i].weight * std::log(parts[i].second);
  }
  EXPECT_NEAR(composite.similarity(fa, fb), std::exp(log_s), 1e-9);
  // A grouped-form metric's breakdown reports the same component similarities.
  const auto& def = dynamic_cast<const CompositeMetric&>(get_metric("layout"));
  const auto parts_default = def.breakdown(def.features(a).values, def.features(b).values);
  ASSERT_EQ(parts_default.size(), parts.size());
  for (size_t i = 0; i < parts.size(); ++i) EXPECT_EQ(parts_default[i], parts[i]);
}

// Leaving one component out renormalises the others' weights: S' = prod_{k != out} S_k^{w_k / (1 - w_out)}.
TEST(Metrics, CompositeSimilarityWithoutOneComponent) {
  const auto& composite = dynamic_cast<const CompositeMetric&>(default_metric());
  const Image a = crop_a("brick.png"), b = crop_b("grass.png");
  Features fa = composite.features(a), fb = composite.features(b);
  const auto parts = composite.breakdown(fa.values, fb.values);
  for (size_t out = 0; out < parts.size(); ++out) {
    double log_s = 0, weight = 0;
    for (size_t i = 0; i < parts.size(); ++i) {
      if (i == out) continue;
      log_s += composite.components()[i].weight * std::log(parts[i].second);
      weight += composite.components()[i].weight;
    }
    EXPECT_NEAR(composite.similarity_without(fa.values, fb.values, parts[out].first), std::exp(log_s / weight), 1e-9)
        << parts[out].first;
  }
  EXPECT_NEAR(composite.similarity_without(fa.values, fa.values, "spectrum"), 1.0, 1e-12);
  EXPECT_THROW(composite.similarity_without(fa.values, fb.values, "no-such-component"), proctex::Error);
}

class GroupedForm : public ::testing::TestWithParam<const char*> {};
INSTANTIATE_TEST_SUITE_P(Metrics, GroupedForm, ::testing::Values("grouped", "layout"));

// "grouped" and "layout": S = exp(-(sum_g w_g d_g)^exponent / scale).
TEST_P(GroupedForm, IsAWeightedSumOfGroupDistances) {
  const auto& composite = dynamic_cast<const CompositeMetric&>(get_metric(GetParam()));
  ASSERT_EQ(composite.group_weights().size(), composite.group_count());
  std::size_t groups = 0;
  for (const auto& c : composite.components()) groups += c.metric->group_count();
  EXPECT_EQ(groups, composite.group_count());
  const Image a = crop_a("brick.png"), b = crop_b("grass.png");
  Features fa = composite.features(a), fb = composite.features(b);
  std::vector<double> g(composite.group_count());
  composite.group_distances(fa.values, fb.values, g.data());
  double d = 0;
  for (size_t k = 0; k < g.size(); ++k) {
    EXPECT_GE(g[k], 0.0) << composite.group_name(k);
    d += composite.group_weights()[k] * g[k];
  }
  EXPECT_NEAR(composite.similarity(fa, fb), std::exp(-std::pow(d, composite.exponent()) / composite.scale()), 1e-9);
  // Every group of equal features is 0.
  composite.group_distances(fa.values, fa.values, g.data());
  for (size_t k = 0; k < g.size(); ++k) EXPECT_EQ(g[k], 0.0) << composite.group_name(k);
}

TEST(Metrics, ProductCompositeForPlugIns) {
  // The product form: S = prod S_k^{w_k} with normalised weights.
  CompositeMetric product({{std::make_shared<SpectrumMetric>(), 1.0}, {std::make_shared<ColourMetric>(), 3.0}},
                          "test-product");
  const Image a = crop_a("brick.png"), b = crop_b("grass.png");
  const Features fa = product.features(a), fb = product.features(b);
  const double s = std::pow(get_metric("spectrum").similarity(get_metric("spectrum").features(a),
                                                              get_metric("spectrum").features(b)), 0.25) *
                   std::pow(get_metric("colour").similarity(get_metric("colour").features(a),
                                                            get_metric("colour").features(b)), 0.75);
  EXPECT_NEAR(product.similarity(fa, fb), s, 1e-9);
  EXPECT_TRUE(product.group_weights().empty());
  EXPECT_THROW(CompositeMetric({{std::make_shared<SpectrumMetric>(), 1.0}}, {1.0}, 1.0), proctex::Error);  // 2 groups
  EXPECT_THROW(CompositeMetric({{std::make_shared<SpectrumMetric>(), 1.0}}, {0.0, 0.0}, 1.0), proctex::Error);
}

TEST(Metrics, ThreadSafeFeatures) {
  const Image a = crop_a("gravel.png");
  const Metric& m = default_metric();
  const std::vector<float> serial = m.features(a, 128).values;
  std::vector<std::vector<float>> results(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] { results[t] = m.features(a, t % 2 ? 128 : 192).values; });
  for (auto& t : threads) t.join();
  EXPECT_EQ(results[1], serial);
  EXPECT_EQ(results[3], serial);
  EXPECT_EQ(results[0], results[2]);
}
