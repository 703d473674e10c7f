#include "search/colour_fit.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include <Eigen/Dense>
#include <nlopt.hpp>

#include "image/image.h"
#include "metrics/aligned.h"
#include "metrics/pixels.h"

namespace proctex::search {
namespace {

// The grey each colour is set to for its basis image. Not white: shaders vary a colour's
// brightness (up to 2x) and clamp to [0, 1], which would bend a white basis; a dark grey stays
// in the linear range.
constexpr float kBasisLevel = 0.25f;
// The least squares' ridge for pixel-exact colours (fit_colours_to_pixels; LinearModel::solve).
constexpr double kPixelRidge = 1e-12;

// Free colour parameters: searchable and not pinned by --fix.
std::vector<const ParamDecl*> free_colours(const ShaderDecl& decl, const std::vector<std::string>& pinned) {
  std::vector<const ParamDecl*> out;
  for (const auto& p : decl.params)
    if (p.type == ParamType::Color && p.searchable && std::find(pinned.begin(), pinned.end(), p.name) == pinned.end())
      out.push_back(&p);
  return out;
}

// b + sum_j w_j * colour_j, per channel. Colours are 3K values, colour j's channel c at 3j + c.
struct LinearModel {
  Image offset;
  std::vector<Image> weights;  // one per free colour
  std::vector<double> lower, upper;

  size_t pixels() const { return offset.pixels.size() / 3; }

  Image combine(const std::vector<double>& colours) const {
    Image out = offset;
    for (size_t j = 0; j < weights.size(); ++j) {
      const float* w = weights[j].pixels.data();
      for (size_t i = 0; i < out.pixels.size(); ++i) out.pixels[i] += w[i] * float(colours[3 * j + i % 3]);
    }
    return out;
  }

  // Least-squares colours that make the model reproduce `wanted` (3 floats per pixel), per channel.
  // `mask` (optional, one byte per pixel): only the pixels where it is non-zero count.
  // `bounds` (colour_fit.h ColourBounds): Clamped - each colour clamped into its declared range
  // after the solve; Unconstrained - the unconstrained optimum; Bounded - the optimum inside the
  // ranges (a box-constrained least squares, exact: every subset of the colours held at a bound).
  // `ridge`: added to the normal equations' diagonal, relative to its largest entry (a colour that
  // shows nowhere stays put). 1e-6 biases a colour that covers few pixels (a small ring's: 1e-4 of
  // its value, RMS 6e-6 of the whole image - the pixel polish's floor, below which the ring's width
  // and softness traded freely); fit_colours_to_pixels uses 1e-12.
  std::vector<double> solve(const std::vector<float>& wanted, const std::vector<uint8_t>* mask = nullptr,
                            ColourBounds bounds = ColourBounds::Clamped, double ridge = 1e-6) const {
    const size_t k = weights.size();
    std::vector<double> colours(3 * k, 0.0);
    for (int ch = 0; ch < 3; ++ch) {
      Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(k, k);
      Eigen::VectorXd atb = Eigen::VectorXd::Zero(k);
      for (size_t i = 0; i < pixels(); ++i) {
        if (mask && !(*mask)[i]) continue;
        const size_t at = 3 * i + ch;
        const double residual = wanted[at] - offset.pixels[at];
        for (size_t a = 0; a < k; ++a) {
          const double wa = weights[a].pixels[at];
          atb[a] += wa * residual;
          for (size_t b = a; b < k; ++b) ata(a, b) += wa * weights[b].pixels[at];
        }
      }
      ata = ata.selfadjointView<Eigen::Upper>();
      ata.diagonal().array() += ridge * (1.0 + ata.diagonal().maxCoeff());  // a colour that shows nowhere stays put
      const Eigen::VectorXd x = ata.ldlt().solve(atb);
      const auto inside = [&](size_t a, double v) { return std::clamp(v, lower[3 * a + ch], upper[3 * a + ch]); };
      bool out_of_range = false;
      for (size_t a = 0; a < k; ++a) out_of_range = out_of_range || inside(a, x[a]) != x[a];
      if (bounds == ColourBounds::Bounded && out_of_range) {
        const Eigen::VectorXd best = bounded(ata, atb, ch);
        for (size_t a = 0; a < k; ++a) colours[3 * a + ch] = best[a];
        continue;
      }
      for (size_t a = 0; a < k; ++a) colours[3 * a + ch] = bounds == ColourBounds::Unconstrained ? x[a] : inside(a, x[a]);
    }
    return colours;
  }

  // min x'Ax - 2b'x over lower <= x <= upper (channel `ch`): the problem is convex, so its optimum
  // is the best feasible one of the candidates that hold each subset of the colours at one of its
  // bounds and solve the rest (3^k candidates; k is 1-4 colours).
  Eigen::VectorXd bounded(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, int ch) const {
    const size_t k = weights.size();
    Eigen::VectorXd best = Eigen::VectorXd::Zero(k);
    double best_value = 1e300;
    size_t states = 1;
    for (size_t i = 0; i < k; ++i) states *= 3;
    for (size_t code = 0; code < states; ++code) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(k);
      std::vector<size_t> free;
      size_t c = code;
      for (size_t i = 0; i < k; ++i, c /= 3) {
        if (c % 3 == 0) free.push_back(i);
        else x[i] = c % 3 == 1 ? lower[3 * i + ch] : upper[3 * i + ch];
      }
      if (!free.empty()) {
        const size_t f = free.size();
        Eigen::MatrixXd af(f, f);
        Eigen::VectorXd bf(f);
        for (size_t i = 0; i < f; ++i) {
          bf[i] = b[free[i]];
          for (size_t j = 0; j < k; ++j)
            if (std::find(free.begin(), free.end(), j) == free.end()) bf[i] -= a(free[i], j) * x[j];
          for (size_t j = 0; j < f; ++j) af(i, j) = a(free[i], free[j]);
        }
        const Eigen::VectorXd xf = af.ldlt().solve(bf);
        bool feasible = true;
        for (size_t i = 0; i < f; ++i) {
          const size_t at = 3 * free[i] + ch;
          if (!(xf[i] >= lower[at] - 1e-9 && xf[i] <= upper[at] + 1e-9)) feasible = false;
          x[free[i]] = std::clamp(xf[i], lower[at], upper[at]);
        }
        if (!feasible) continue;
      }
      const double value = x.dot(a * x) - 2.0 * b.dot(x);
      if (value < best_value) {
        best_value = value;
        best = x;
      }
    }
    return best;
  }
};

// Pixel order of a per-pixel key (ascending).
std::vector<uint32_t> order_by(const std::vector<float>& key) {
  std::vector<uint32_t> order(key.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
  return order;
}

// Each pixel gets the target colour of its rank (the target has as many pixels as the model).
std::vector<float> assign_by_rank(const std::vector<uint32_t>& order, const std::vector<float>& sorted_target, bool reverse) {
  std::vector<float> wanted(3 * order.size());
  const size_t n = order.size();
  for (size_t r = 0; r < n; ++r) {
    const size_t t = reverse ? n - 1 - r : r;
    std::copy_n(&sorted_target[3 * t], 3, &wanted[3 * order[r]]);
  }
  return wanted;
}

double colour_similarity(const ColourTarget& target, const Image& image) {
  return target.colour_metric->similarity(target.colour, target.colour_metric->features(image, target.resolution));
}

// Histogram matching projected on the model, from an initial ranking of the pixels.
float along(const std::array<float, 3>& axis, const float* rgb) {
  return axis[0] * rgb[0] + axis[1] * rgb[1] + axis[2] * rgb[2];
}

// Histogram matching projected on the model, from an initial ranking of the pixels, along the
// target's sort axis `axis` (ColourTarget::axes).
std::vector<double> rank_fit(const LinearModel& model, const ColourTarget& target, std::vector<float> key, bool reverse,
                             size_t axis) {
  std::vector<double> colours;
  for (int iteration = 0; iteration < 4; ++iteration) {
    colours = model.solve(assign_by_rank(order_by(key), target.sorted[axis], reverse));
    const Image now = model.combine(colours);
    for (size_t i = 0; i < key.size(); ++i) key[i] = along(target.axes[axis], now.pixel(0, 0) + 3 * i);
    reverse = false;  // from now on the model's own colours order the pixels
  }
  return colours;
}

// The target's principal colour axis (unit, linear RGB), or nothing when ordering the pixels
// along it would be ordering them by luminance (correlation of the two projections above
// kSameOrderCorrelation: a grey or one-hue target).
constexpr double kSameOrderCorrelation = 0.98;
std::optional<std::array<float, 3>> principal_colour_axis(const Image& rgb) {
  const size_t n = rgb.pixels.size() / 3;
  if (n < 2) return std::nullopt;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) mean += Eigen::Vector3d(rgb.pixels[3 * i], rgb.pixels[3 * i + 1], rgb.pixels[3 * i + 2]);
  mean /= double(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(rgb.pixels[3 * i], rgb.pixels[3 * i + 1], rgb.pixels[3 * i + 2]) - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
  const Eigen::Vector3d axis = eigen.eigenvectors().col(2);  // largest eigenvalue last
  const Eigen::Vector3d lum(0.2126, 0.7152, 0.0722);
  // Correlation of the projections: (a' C l) / sqrt(a' C a * l' C l).
  const double cross = axis.dot(cov * lum), va = axis.dot(cov * axis), vl = lum.dot(cov * lum);
  if (!(va > 0.0 && vl > 0.0) || std::fabs(cross) / std::sqrt(va * vl) > kSameOrderCorrelation) return std::nullopt;
  return std::array<float, 3>{float(axis[0]), float(axis[1]), float(axis[2])};
}

struct PolishContext {
  const LinearModel* model;
  const ColourTarget* target;
  double best;
  std::vector<double> best_x;
};

double polish_objective(unsigned n, const double* x, double*, void* data) {
  auto& c = *static_cast<PolishContext*>(data);
  std::vector<double> colours(x, x + n);
  const double s = colour_similarity(*c.target, c.model->combine(colours));
  if (s > c.best) {
    c.best = s;
    c.best_x = colours;
  }
  return std::log(std::max(s, 1e-300));  // flat far from the target otherwise (see refine.cpp)
}

void polish(const LinearModel& model, const ColourTarget& target, std::vector<double>& colours, double& similarity) {
  const unsigned n = static_cast<unsigned>(colours.size());
  nlopt::opt opt(nlopt::LN_SBPLX, n);
  opt.set_lower_bounds(model.lower);
  opt.set_upper_bounds(model.upper);
  opt.set_initial_step(std::vector<double>(n, 0.05));
  opt.set_maxeval(40 * static_cast<int>(n));
  opt.set_xtol_abs(1e-3);
  PolishContext context{&model, &target, similarity, colours};
  opt.set_max_objective(polish_objective, &context);
  std::vector<double> x = colours;
  double f = 0.0;
  try {
    opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited&) {
  } catch (const nlopt::forced_stop&) {
  }
  colours = context.best_x;
  similarity = context.best;
}

// The target's pixels moved to where `render` has the same pattern (metrics/aligned.h's best
// shift): what a least-squares colour fit should reproduce pixel for pixel, on `overlap` (the
// render's pixels that the shifted target covers).
std::vector<float> registered_pixels(const ColourTarget& target, const Image& render, std::vector<uint8_t>& overlap) {
  const metrics::AlignedMetric aligned(target.resolution);
  const auto [dx, dy] = aligned.best_shift(aligned.features(target.rgb, target.resolution).values,
                                           aligned.features(render, target.resolution).values);
  // best_shift: render(x) ~ target(x + (dx, dy)); moved_target's convention is the opposite.
  return metrics::moved_target(target.rgb, -dx, -dy, overlap);
}

}  // namespace

ColourTarget make_colour_target(const Image& image, int resolution) {
  ColourTarget t;
  t.resolution = resolution;
  t.rgb = resize(center_crop_square(image), resolution, resolution);
  const size_t n = t.rgb.pixels.size() / 3;
  t.axes.push_back({0.2126f, 0.7152f, 0.0722f});  // luminance (image.h)
  if (const auto axis = principal_colour_axis(t.rgb)) t.axes.push_back(*axis);
  for (const auto& axis : t.axes) {
    std::vector<float> key(n);
    for (size_t i = 0; i < n; ++i) key[i] = along(axis, &t.rgb.pixels[3 * i]);
    const auto order = order_by(key);
    auto& sorted = t.sorted.emplace_back(3 * n);
    for (size_t r = 0; r < n; ++r) std::copy_n(&t.rgb.pixels[3 * order[r]], 3, &sorted[3 * r]);
  }
  t.colour_metric = &metrics::get_metric("colour");
  t.colour = t.colour_metric->features(t.rgb, resolution);
  return t;
}

long colour_fit_renders(const ShaderDecl& decl, const std::vector<std::string>& pinned, size_t starts) {
  const auto k = free_colours(decl, pinned).size();
  return static_cast<long>(starts * (k ? k + 3 : 1));
}

std::vector<ColourFitResult> fit_colours(const ShaderDecl& decl, const std::vector<std::vector<float>>& packed,
                                         const std::vector<uint32_t>& seeds, const std::vector<std::string>& pinned,
                                         const ColourTarget& target, Renderer& renderer, bool polish_fit,
                                         bool registered) {
  const auto colours = free_colours(decl, pinned);
  const size_t k = colours.size();
  // One launch: per start, all free colours black, each colour grey alone, and the start itself.
  std::vector<std::vector<float>> batch;
  std::vector<uint32_t> batch_seeds;
  for (size_t s = 0; s < packed.size(); ++s) {
    if (k) {
      for (size_t white = 0; white <= k; ++white) {  // white == k: all black
        auto p = packed[s];
        for (size_t j = 0; j < k; ++j)
          for (int ch = 0; ch < 3; ++ch) p[colours[j]->offset + ch] = j == white ? kBasisLevel : 0.0f;
        batch.push_back(std::move(p));
      }
    }
    batch.push_back(packed[s]);
    if (k) {  // the linearity check: the start's colours halved, inside the range no shader clamps
      auto p = packed[s];
      for (const auto* c : colours)
        for (int ch = 0; ch < 3; ++ch) p[c->offset + ch] *= 0.5f;
      batch.push_back(std::move(p));
    }
    batch_seeds.insert(batch_seeds.end(), k ? k + 3 : 1, seeds[s]);
  }
  RenderSettings settings;
  settings.width = settings.height = target.resolution;
  const auto images = renderer.render_batch(decl, batch, batch_seeds, settings);

  std::vector<ColourFitResult> results;
  size_t at = 0;
  for (size_t s = 0; s < packed.size(); ++s) {
    ColourFitResult r;
    r.packed = packed[s];
    if (!k) {
      r.preview = images[at++];
      r.before = r.after = colour_similarity(target, r.preview);
      results.push_back(std::move(r));
      continue;
    }
    LinearModel model;
    model.offset = images[at + k];
    for (size_t j = 0; j < k; ++j) {
      Image w = images[at + j];
      for (size_t i = 0; i < w.pixels.size(); ++i) w.pixels[i] = (w.pixels[i] - model.offset.pixels[i]) / kBasisLevel;
      model.weights.push_back(std::move(w));
    }
    const Image& actual = images[at + k + 1];
    const Image& check = images[at + k + 2];
    at += k + 3;
    std::vector<double> start;
    for (const auto* c : colours)
      for (int ch = 0; ch < 3; ++ch) {
        start.push_back(packed[s][c->offset + ch]);
        model.lower.push_back(c->min);
        model.upper.push_back(c->max);
      }
    // Linearity check at half the start's colours: a shader that transforms its colours
    // (contrast, hue shifts, colour-dependent masks) would make the basis lie. (At the start's own
    // colours a shader may clamp bright pixels; the fit's colours are re-rendered by the refinement.)
    std::vector<double> halved = start;
    for (auto& v : halved) v *= 0.5;
    const Image predicted = model.combine(halved);
    float peak = 1.0f;
    for (size_t i = 0; i < check.pixels.size(); ++i) {
      peak = std::max(peak, std::fabs(check.pixels[i]));
      r.linearity_error = std::max<double>(r.linearity_error, std::fabs(predicted.pixels[i] - check.pixels[i]));
    }
    r.preview = actual;
    r.before = r.after = colour_similarity(target, actual);
    if (r.linearity_error > 2e-3 * peak) {
      results.push_back(std::move(r));
      continue;
    }
    if (registered) {
      r.fitted = true;
      std::vector<uint8_t> overlap;
      const auto wanted = registered_pixels(target, actual, overlap);
      const auto colours_ls = model.solve(wanted, &overlap);
      r.preview = model.combine(colours_ls);
      r.after = colour_similarity(target, r.preview);
      for (size_t j = 0; j < k; ++j)
        for (int ch = 0; ch < 3; ++ch) r.packed[colours[j]->offset + ch] = float(colours_ls[3 * j + ch]);
      results.push_back(std::move(r));
      continue;
    }
    // Initial rankings: each colour's mask, both ways, along each of the target's sort axes.
    std::vector<double> best_colours = start;
    double best = r.before;
    for (size_t axis = 0; axis < target.axes.size(); ++axis) {
      for (size_t j = 0; j < k; ++j) {
        std::vector<float> key(model.pixels());
        for (size_t i = 0; i < key.size(); ++i) key[i] = luminance(model.weights[j].pixel(0, 0) + 3 * i);
        for (bool reverse : {false, true}) {
          const auto fitted = rank_fit(model, target, key, reverse, axis);
          const double sim = colour_similarity(target, model.combine(fitted));
          if (sim > best) {
            best = sim;
            best_colours = fitted;
          }
        }
      }
    }
    if (polish_fit) polish(model, target, best_colours, best);
    if (best > r.before) {
      r.fitted = true;
      r.after = best;
      r.preview = model.combine(best_colours);
      for (size_t j = 0; j < k; ++j)
        for (int ch = 0; ch < 3; ++ch) r.packed[colours[j]->offset + ch] = float(best_colours[3 * j + ch]);
    }
    results.push_back(std::move(r));
  }
  return results;
}

}  // namespace proctex::search

namespace proctex::search {

PixelColourFit fit_colours_to_pixels(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                                     const std::vector<std::string>& pinned, const std::vector<float>& wanted,
                                     const std::vector<uint8_t>& mask, int side, Renderer& renderer,
                                     ColourBounds bounds, bool zero_offset) {
  const auto colours = free_colours(decl, pinned);
  const size_t k = colours.size();
  // Per colour its grey basis alone, then all free colours black (the offset).
  std::vector<std::vector<float>> batch;
  for (size_t white = 0; white <= k - (zero_offset && k > 0 ? 1 : 0); ++white) {
    auto p = packed;
    for (size_t j = 0; j < k; ++j)
      for (int ch = 0; ch < 3; ++ch) p[colours[j]->offset + ch] = j == white ? kBasisLevel : 0.0f;
    batch.push_back(std::move(p));
  }
  RenderSettings settings;
  settings.width = settings.height = side;
  const auto images = renderer.render_batch(decl, batch, std::vector<uint32_t>(batch.size(), seed), settings);
  LinearModel model;
  if (images.size() > k) {
    model.offset = images[k];
  } else {
    model.offset = images[0];
    std::fill(model.offset.pixels.begin(), model.offset.pixels.end(), 0.0f);
  }
  for (size_t j = 0; j < k; ++j) {
    Image w = images[j];
    for (size_t i = 0; i < w.pixels.size(); ++i) w.pixels[i] = (w.pixels[i] - model.offset.pixels[i]) / kBasisLevel;
    model.weights.push_back(std::move(w));
    for (int ch = 0; ch < 3; ++ch) {
      model.lower.push_back(colours[j]->min);
      model.upper.push_back(colours[j]->max);
    }
  }
  PixelColourFit fit;
  fit.packed = packed;
  fit.renders = static_cast<long>(batch.size());
  fit.offset_black = std::all_of(model.offset.pixels.begin(), model.offset.pixels.end(), [](float v) { return v == 0.0f; });
  const auto solved = k ? model.solve(wanted, &mask, bounds, kPixelRidge) : std::vector<double>{};
  for (size_t j = 0; j < k; ++j)
    for (int ch = 0; ch < 3; ++ch)
      fit.packed[colours[j]->offset + ch] =
          float(std::clamp(solved[3 * j + ch], double(colours[j]->min), double(colours[j]->max)));
  const Image predicted = model.combine(solved);
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i]) continue;
    for (int ch = 0; ch < 3; ++ch) {
      const double d = double(predicted.pixels[3 * i + ch]) - wanted[3 * i + ch];
      sum += d * d;
    }
    count += 3;
  }
  fit.mse = count ? sum / double(count) : 1.0;
  return fit;
}

}  // namespace proctex::search
