#pragma once
// The texture spec: one JSON shape used everywhere (render input, match output, morph key frames).
//   {"shader": "bricks", "params": {"rows": 8, "mortar_color": [0.6, 0.6, 0.6]}, "seed": 7}
// On the command line a spec is a JSON file, a bare shader name, or inline
//   bricks:rows=8,brick_width=0.3,mortar_color=(0.6,0.6,0.6),seed=7
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "shaders/shader.h"

namespace proctex {

class ShaderLibrary;

struct TextureSpec {
  std::string shader;
  std::map<std::string, nlohmann::json> params;  // only the parameters given; others default
  uint32_t seed = 0;

  nlohmann::json to_json() const;
  static TextureSpec from_json(const nlohmann::json& j);  // throws UsageError on a bad shape
};

// Reads a spec argument: an existing file (JSON), `name`, or `name:key=value,...`.
// Values: numbers, true/false, enum names, colours as (r,g,b) or #rrggbb (sRGB hex, linearised).
TextureSpec parse_spec_argument(const std::string& argument);

// Checks every given parameter against the declaration and returns the full packed vector
// (defaults for the rest). Unknown names, wrong types and out-of-range values throw UsageError
// naming the parameter, its type and range.
std::vector<float> resolve(const ShaderDecl& decl, const TextureSpec& spec);

// The spec with every parameter written out, from a packed vector (for match results).
TextureSpec spec_from_packed(const ShaderDecl& decl, const std::vector<float>& packed,
                             uint32_t seed);

// A parameter's packed value as JSON (number, integer, bool, enum name or [r, g, b]).
nlohmann::json param_to_json(const ParamDecl& p, const float* packed_value);

}  // namespace proctex
