#pragma once
// The search space of a shader: the unit hypercube over its searchable parameters (one dimension
// per float, int, bool or enum; three per colour), with log mapping where declared. Discrete
// parameters (int, bool, enum) map to whole values only: the shader is never evaluated at a
// non-integer count (the thesis's star-shader failure).
#include <map>
#include <string>
#include <vector>

#include "shaders/shader.h"

namespace proctex {

struct Dimension {
  const ParamDecl* param = nullptr;
  int channel = 0;  // 0..2 for colours
  int levels = 0;   // number of distinct values for discrete parameters, 0 for continuous
};

class ParameterSpace {
 public:
  // `base` holds the values of the parameters that are not searched (defaults unless pinned);
  // names in `pinned` are excluded from the search on top of the declared fixed ones.
  ParameterSpace(const ShaderDecl& decl, std::vector<float> base, const std::vector<std::string>& pinned = {});
  explicit ParameterSpace(const ShaderDecl& decl);

  int dimensions() const { return static_cast<int>(dims_.size()); }
  const std::vector<Dimension>& dims() const { return dims_; }
  const ShaderDecl& decl() const { return *decl_; }

  // Unit coordinates (clamped to [0, 1]) to a packed parameter vector.
  std::vector<float> to_packed(const std::vector<double>& unit) const;
  // A packed vector to unit coordinates (discrete values land at the centre of their bin).
  std::vector<double> to_unit(const std::vector<float>& packed) const;
  // Snaps unit coordinates of discrete dimensions to the centres of their bins.
  std::vector<double> snap(const std::vector<double>& unit) const;

 private:
  const ShaderDecl* decl_;
  std::vector<float> base_;
  std::vector<Dimension> dims_;
};

}  // namespace proctex
