#pragma once
// The space a morph moves through: every parameter of one shader as unit coordinates, the
// searchable ones and the fixed ones alike (a key texture may set a fixed parameter, e.g. marble's
// octaves, and the path has to carry it). Log mapping where declared; discrete parameters live in
// equal bins, so interpolated coordinates always map to whole values (ParameterSpace).
#include <memory>
#include <string>
#include <vector>

#include "shaders/parameter_space.h"
#include "shaders/shader.h"

namespace proctex::transform {

class MorphSpace {
 public:
  explicit MorphSpace(const ShaderDecl& decl);
  MorphSpace(const MorphSpace&) = delete;
  MorphSpace& operator=(const MorphSpace&) = delete;

  const ShaderDecl& decl() const { return *original_; }  // what the renderer gets
  int dimensions() const { return space_->dimensions(); }

  std::vector<double> to_unit(const std::vector<float>& packed) const { return space_->to_unit(packed); }
  std::vector<float> to_packed(const std::vector<double>& unit) const { return space_->to_packed(unit); }

  // Euclidean distance of two packed vectors in unit coordinates (the "normalised space").
  double distance(const std::vector<float>& a, const std::vector<float>& b) const;
  // Largest difference of a discrete parameter between two packed vectors, in whole steps.
  int max_discrete_step(const std::vector<float>& a, const std::vector<float>& b) const;
  // Largest difference of a continuous coordinate (unit space).
  double max_continuous_difference(const std::vector<float>& a, const std::vector<float>& b) const;
  // Every t in (0, 1) where a discrete parameter changes its whole value along the straight line
  // from a to b in unit coordinates, ascending.
  std::vector<double> discrete_crossings(const std::vector<float>& a, const std::vector<float>& b) const;
  // Linear interpolation in unit coordinates; discrete values snap to their bins.
  std::vector<float> lerp(const std::vector<float>& a, const std::vector<float>& b, double t) const;
  // `packed` with its non-searchable parameters taken from `from` (the catalogue samples only
  // vary the searchable ones; the keys may set the others).
  std::vector<float> with_fixed_from(std::vector<float> packed, const std::vector<float>& from) const;

 private:
  const ShaderDecl* original_;
  std::unique_ptr<ShaderDecl> all_;  // copy with every parameter searchable
  std::unique_ptr<ParameterSpace> space_;
};

}  // namespace proctex::transform
