#pragma once
// The one place that includes the OpenCL C++ bindings, with the version macros that compile on
// Debian 12 (300/120 does not; 300/200 does - see DESIGN.md).
#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 300
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 200
#endif
#define CL_HPP_ENABLE_EXCEPTIONS
#include <CL/opencl.hpp>
