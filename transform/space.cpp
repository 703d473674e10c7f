#include "transform/space.h"

#include <algorithm>
#include <cmath>

namespace proctex::transform {

MorphSpace::MorphSpace(const ShaderDecl& decl) : original_(&decl), all_(std::make_unique<ShaderDecl>(decl)) {
  // A parameter with an empty range has nothing to interpolate (and would divide by zero).
  for (auto& p : all_->params) p.searchable = p.max > p.min;
  space_ = std::make_unique<ParameterSpace>(*all_);
}

double MorphSpace::distance(const std::vector<float>& a, const std::vector<float>& b) const {
  const auto ua = to_unit(a), ub = to_unit(b);
  double s = 0;
  for (size_t i = 0; i < ua.size(); ++i) s += (ua[i] - ub[i]) * (ua[i] - ub[i]);
  return std::sqrt(s);
}

int MorphSpace::max_discrete_step(const std::vector<float>& a, const std::vector<float>& b) const {
  int steps = 0;
  for (const auto& d : space_->dims())
    if (d.levels) {
      const int o = d.param->offset + d.channel;
      steps = std::max(steps, static_cast<int>(std::lround(std::fabs(a[o] - b[o]))));
    }
  return steps;
}

double MorphSpace::max_continuous_difference(const std::vector<float>& a, const std::vector<float>& b) const {
  const auto ua = to_unit(a), ub = to_unit(b);
  double m = 0;
  for (size_t i = 0; i < ua.size(); ++i)
    if (!space_->dims()[i].levels) m = std::max(m, std::fabs(ua[i] - ub[i]));
  return m;
}

std::vector<double> MorphSpace::discrete_crossings(const std::vector<float>& a, const std::vector<float>& b) const {
  const auto ua = to_unit(a), ub = to_unit(b);
  std::vector<double> out;
  for (size_t i = 0; i < ua.size(); ++i) {
    const int levels = space_->dims()[i].levels;
    if (!levels || ua[i] == ub[i]) continue;
    // Bin k covers [k / levels, (k + 1) / levels): every boundary between the two bins.
    const int ka = std::clamp(static_cast<int>(std::floor(ua[i] * levels)), 0, levels - 1);
    const int kb = std::clamp(static_cast<int>(std::floor(ub[i] * levels)), 0, levels - 1);
    for (int k = std::min(ka, kb) + 1; k <= std::max(ka, kb); ++k) {
      const double t = (double(k) / levels - ua[i]) / (ub[i] - ua[i]);
      if (t > 0 && t < 1) out.push_back(t);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<float> MorphSpace::lerp(const std::vector<float>& a, const std::vector<float>& b, double t) const {
  auto ua = to_unit(a);
  const auto ub = to_unit(b);
  for (size_t i = 0; i < ua.size(); ++i) ua[i] += t * (ub[i] - ua[i]);
  auto out = to_packed(ua);
  // Exact endpoints: the unit round trip of a float may move it by an ulp.
  if (t <= 0) return a;
  if (t >= 1) return b;
  return out;
}

std::vector<float> MorphSpace::with_fixed_from(std::vector<float> packed, const std::vector<float>& from) const {
  for (const auto& p : original_->params)
    if (!p.searchable)
      for (int c = 0; c < p.width(); ++c) packed[p.offset + c] = from[p.offset + c];
  return packed;
}

}  // namespace proctex::transform
