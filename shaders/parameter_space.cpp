#include "shaders/parameter_space.h"

#include <algorithm>
#include <cmath>

namespace proctex {
namespace {

// Discrete values split [0, 1] into `levels` equal bins; bin k holds value min + k.
float discrete_value(const ParamDecl& p, int levels, double u) {
  const int k = std::clamp(static_cast<int>(std::floor(u * levels)), 0, levels - 1);
  return p.min + static_cast<float>(k);
}

double discrete_unit(const ParamDecl& p, int levels, float value) {
  const int k = std::clamp(static_cast<int>(std::lround(value - p.min)), 0, levels - 1);
  return (k + 0.5) / levels;
}

float continuous_value(const ParamDecl& p, double u) {
  if (p.scale == Scale::Log) return static_cast<float>(p.min * std::pow(double(p.max) / p.min, u));
  return static_cast<float>(p.min + (double(p.max) - p.min) * u);
}

double continuous_unit(const ParamDecl& p, float v) {
  if (p.scale == Scale::Log) return std::log(double(v) / p.min) / std::log(double(p.max) / p.min);
  return (double(v) - p.min) / (double(p.max) - p.min);
}

}  // namespace

ParameterSpace::ParameterSpace(const ShaderDecl& decl) : ParameterSpace(decl, decl.default_packed()) {}

ParameterSpace::ParameterSpace(const ShaderDecl& decl, std::vector<float> base, const std::vector<std::string>& pinned)
    : decl_(&decl), base_(std::move(base)) {
  for (const auto& p : decl.params) {
    if (!p.searchable || std::find(pinned.begin(), pinned.end(), p.name) != pinned.end()) continue;
    const int levels = p.type == ParamType::Bool ? 2 : p.discrete() ? static_cast<int>(p.max - p.min) + 1 : 0;
    for (int c = 0; c < p.width(); ++c) dims_.push_back({&p, c, levels});
  }
}

std::vector<float> ParameterSpace::to_packed(const std::vector<double>& unit) const {
  std::vector<float> packed = base_;
  for (size_t i = 0; i < dims_.size(); ++i) {
    const auto& d = dims_[i];
    const double u = std::clamp(i < unit.size() ? unit[i] : 0.5, 0.0, 1.0);
    const float v = d.levels ? discrete_value(*d.param, d.levels, u) : continuous_value(*d.param, u);
    packed[d.param->offset + d.channel] = std::clamp(v, d.param->min, d.param->max);
  }
  return packed;
}

std::vector<double> ParameterSpace::to_unit(const std::vector<float>& packed) const {
  std::vector<double> unit(dims_.size());
  for (size_t i = 0; i < dims_.size(); ++i) {
    const auto& d = dims_[i];
    const float v = packed[d.param->offset + d.channel];
    unit[i] = std::clamp(d.levels ? discrete_unit(*d.param, d.levels, v) : continuous_unit(*d.param, v), 0.0, 1.0);
  }
  return unit;
}

std::vector<double> ParameterSpace::snap(const std::vector<double>& unit) const {
  return to_unit(to_packed(unit));
}

}  // namespace proctex
