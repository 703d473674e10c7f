#pragma once
// Generates the OpenCL program of one shader: the shared library, the Params struct and enum
// constants, the shader's own source (with #line so errors name its file), and the batch kernel
// `pt_render` over (x, y, sample).
#include <string>

#include "shaders/shader.h"

namespace proctex {

inline constexpr const char* kRenderKernelName = "pt_render";

// Kernel arguments, in order:
//   0 __global const float* params   N packed parameter vectors, `stride` floats apart
//   1 int stride
//   2 __global const uint* seeds     one seed per sample
//   3 float4 window                  (u0, v0, texture units per pixel, filter scale)
//   4 int y_offset                   first image row of this launch (tiled renders)
//   5 int supersample                samples per pixel along each axis
//   6 __global float* out            RGB, [sample][row][column][3]
// Global size: (width, rows, samples).
std::string generate_program(const ShaderDecl& decl);

// "BOND_RUNNING": the constant the generated code defines for an enum value.
std::string enum_constant(const ParamDecl& p, const std::string& value);

}  // namespace proctex
