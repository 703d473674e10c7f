#pragma once
// A shader's declaration: what the host reads from the comment header of shaders/<family>/<name>.cl.
//
//   // @shader "Running-bond brick wall with mortar joints"
//   // @param int   rows   = 8    [2, 32]              "Brick rows per texture tile"
//   // @param float mortar = 0.06 [0.01, 0.3] log      "Mortar width, fraction of a brick's height"
//   // @param color brick  = (0.45, 0.18, 0.12)        "Mean brick colour (linear RGB)"
//   // @param enum  bond   = running {running, stack}  "Bond pattern"
//   // @param bool  worn   = false fixed               "Chipped brick edges"
//   float3 shade(float2 p, float fw, uint seed, const Params P) { ... }
//
// Flags after the range: `log` (log scale for search; needs min > 0), `fixed` (never searched),
// `period=P` or `period=P/COUNT` (a symmetry: v and v + P render the same image; COUNT an int
// parameter the period is divided by: a star with n points turned by 360/n is the same star):
//   // @param float rotation = 0 [0, 180] period=360/points "Rotation in degrees"
// `exchange=A/B` (a symmetry across the ends of the range: the value at one end renders as the
// value at the other end with the float parameters A and B exchanged - a shape symmetric under a
// half turn, turned through a quarter turn, trades its width for its height):
//   // @param float rotation = 0 [0, 90] exchange=width/height "Rotation in degrees"
// `needs=G` (a dependency: this float or int has no effect while the linear float G is at its
// range's minimum - a wave's frequency while the wave's amplitude is 0 - so a search that scans one
// parameter at a time cannot find it from a point where G is off; it scans the two floats jointly,
// and an answer with G off reports the parameter at its default):
//   // @param float wave_frequency = 3 [1, 12] needs=wave "Waves along each stripe"
// Colours range over [0, 1] per channel unless a range is given.
#include <optional>
#include <string>
#include <vector>

namespace proctex {

enum class ParamType { Float, Int, Bool, Color, Enum };
enum class Scale { Linear, Log };

const char* to_string(ParamType type);
const char* to_string(Scale scale);

struct ParamDecl {
  std::string name;
  ParamType type = ParamType::Float;
  std::vector<float> default_value;  // packed form: 3 floats for a colour, 1 otherwise
  float min = 0.0f;                  // per channel for colours; index range for enums
  float max = 1.0f;
  Scale scale = Scale::Linear;
  bool searchable = true;
  std::string help;
  std::vector<std::string> enum_values;
  // Symmetry (flag `period=P[/COUNT]`, linear floats only): the values v and v + period render
  // the same image at every seed, so the matcher reports one canonical value and the evaluation
  // compares values modulo the period. 0: no symmetry declared. `period_per`: the int parameter
  // the period is divided by ("" for a constant period).
  float period = 0.0f;
  std::string period_per;
  // Flag `exchange=A/B` (linear floats only): min and max of this parameter render the same image
  // with A and B (floats of one range) exchanged. Empty: none declared. The pixel polish moves a
  // point stuck at one end to the other this way (search/pixel_polish.cpp).
  std::vector<std::string> exchange;
  // Flag `needs=G` (floats and ints): this parameter renders nothing different while the linear
  // float G is at its minimum. Empty: none declared. The deterministic polish scans two floats
  // jointly (search/match.cpp scan_pattern); canonical_packed sets the parameter to its default
  // while G is at its minimum.
  std::string needs;
  int line = 0;    // line of the declaration in the shader file
  int offset = 0;  // first float of this parameter in the packed vector

  int width() const { return type == ParamType::Color ? 3 : 1; }
  bool discrete() const { return type == ParamType::Int || type == ParamType::Bool || type == ParamType::Enum; }
};

struct ShaderDecl {
  std::string name;    // file name without .cl
  std::string family;  // folder name
  std::string help;    // the @shader line
  std::string path;    // "shaders/<family>/<name>.cl" (or a user's file path)
  std::string source;  // the whole file
  std::string source_hash;  // stable hex hash of the source (catalogue staleness)
  std::vector<ParamDecl> params;
  int packed_size = 0;  // floats in a packed parameter vector

  const ParamDecl* find(const std::string& param) const;
  std::vector<float> default_packed() const;
};

// Parses the declaration in `source`. Throws proctex::Error naming "path:line" for malformed
// declarations (bad type, default outside range, duplicate name, missing @shader line, ...).
ShaderDecl parse_shader(const std::string& path, const std::string& source);

// The symmetry period of `p` at the point `packed` (its `period` divided by the current value of
// its `period_per` count), or 0 when `p` declares none.
double symmetry_period(const ShaderDecl& decl, const ParamDecl& p, const std::vector<float>& packed);

// `packed` with every periodic parameter reduced into [min, min + period) and every parameter whose
// declared gate (`needs=`) is at its minimum at its default: the one value of each class of
// equivalent values that the matcher reports (the same image, by the declaration).
std::vector<float> canonical_packed(const ShaderDecl& decl, std::vector<float> packed);

// |a - b| for the parameter `p` (packed values), taken modulo its symmetry period at the point
// `packed` (the shorter way round) when it declares one: how far apart two values are as images.
double parameter_difference(const ShaderDecl& decl, const ParamDecl& p, float a, float b,
                            const std::vector<float>& packed);

// FNV-1a 64-bit of a string, as 16 hex digits: stable across runs and platforms.
std::string stable_hash(const std::string& text);

}  // namespace proctex
