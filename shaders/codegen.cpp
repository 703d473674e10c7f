#include "shaders/codegen.h"

#include <algorithm>
#include <cctype>
#include <sstream>

#include "kernels/library.h"

namespace proctex {
namespace {

const char* cl_type(ParamType t) {
  switch (t) {
    case ParamType::Float: return "float";
    case ParamType::Color: return "float3";
    default: return "int";  // int, bool (0/1) and enum (index)
  }
}

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

std::string params_struct(const ShaderDecl& decl) {
  std::ostringstream s;
  for (const auto& p : decl.params) {
    if (p.type != ParamType::Enum) continue;
    for (size_t i = 0; i < p.enum_values.size(); ++i)
      s << "#define " << enum_constant(p, p.enum_values[i]) << " " << i << "\n";
  }
  s << "typedef struct {\n";
  for (const auto& p : decl.params) s << "  " << cl_type(p.type) << " " << p.name << ";\n";
  if (decl.params.empty()) s << "  int unused_;\n";  // C forbids empty structs
  s << "} Params;\n";
  return s.str();
}

std::string unpack_and_kernel(const ShaderDecl& decl) {
  std::ostringstream s;
  s << "Params pt_unpack(__global const float* v) {\n  Params P;\n";
  for (const auto& p : decl.params) {
    const int o = p.offset;
    switch (p.type) {
      case ParamType::Float: s << "  P." << p.name << " = v[" << o << "];\n"; break;
      case ParamType::Color:
        s << "  P." << p.name << " = (float3)(v[" << o << "], v[" << o + 1 << "], v[" << o + 2 << "]);\n";
        break;
      default:  // discrete: the host packs exact integers; round defends against float noise
        s << "  P." << p.name << " = (int)rint(v[" << o << "]);\n";
    }
  }
  if (decl.params.empty()) s << "  P.unused_ = 0;\n";
  s << "  return P;\n}\n\n";
  s << R"(__kernel void pt_render(__global const float* params, int stride, __global const uint* seeds,
                        float4 window, int y_offset, int supersample, __global float* out) {
  const int x = get_global_id(0);
  const int y = get_global_id(1);
  const int s = get_global_id(2);
  const int width = get_global_size(0);
  const int rows = get_global_size(1);
  const Params P = pt_unpack(params + (size_t)s * stride);
  const uint seed = seeds[s];
  const float pixel = window.z;
  // window.w scales the footprint: 1 filters over the (sub)pixel, 0 point-samples.
  const float sub = window.w * pixel / (float)supersample;
  float3 sum = (float3)(0.0f);
  for (int j = 0; j < supersample; ++j) {
    for (int i = 0; i < supersample; ++i) {
      const float2 p = (float2)(window.x + ((float)x + ((float)i + 0.5f) / supersample) * pixel,
                                window.y + ((float)(y + y_offset) + ((float)j + 0.5f) / supersample) * pixel);
      sum += shade(p, sub, seed, P);
    }
  }
  sum /= (float)(supersample * supersample);
  vstore3(sum, ((size_t)s * rows + y) * width + x, out);
}
)";
  return s.str();
}

}  // namespace

std::string enum_constant(const ParamDecl& p, const std::string& value) {
  return upper(p.name) + "_" + upper(value);
}

std::string generate_program(const ShaderDecl& decl) {
  std::string program = ocl::library_source();
  const std::string generated = "<generated for " + decl.name + ">";
  program += ocl::line_directive(generated, 1);
  program += params_struct(decl);
  program += ocl::line_directive(decl.path, 1);
  program += decl.source;
  if (!program.empty() && program.back() != '\n') program += '\n';
  program += ocl::line_directive(generated, 100);
  program += unpack_and_kernel(decl);
  return program;
}

}  // namespace proctex
