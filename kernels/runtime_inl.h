#pragma once
#include <string>

#include "core/error.h"

namespace proctex::ocl {

template <typename Fn>
auto with_cl_errors(const char* what, Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const cl::Error& e) {
    throw Error(std::string(what) + " failed: " + e.what() + " (" + error_name(e.err()) + ")",
                "check the device with 'proctex devices'; a smaller --size may help with "
                "CL_OUT_OF_RESOURCES or CL_MEM_OBJECT_ALLOCATION_FAILURE");
  }
}

}  // namespace proctex::ocl
