#pragma once
// Buffer and launch helpers over the process-wide runtime: the few OpenCL calls every user of the
// device repeats, with OpenCL errors turned into proctex::Error.
#include <cstddef>
#include <vector>

#include "kernels/runtime.h"

namespace proctex::ocl {

// A read-only device buffer holding a copy of `data` (at least one element, so empty inputs work).
template <typename T>
cl::Buffer upload(const T* data, size_t count) {
  auto& rt = Runtime::instance();
  return with_cl_errors("uploading a buffer", [&] {
    if (count == 0) return cl::Buffer(rt.context(), CL_MEM_READ_ONLY, sizeof(T));
    return cl::Buffer(rt.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, count * sizeof(T), const_cast<T*>(data));
  });
}

template <typename T>
cl::Buffer upload(const std::vector<T>& data) {
  return upload(data.data(), data.size());
}

// An uninitialised device buffer the kernel writes.
inline cl::Buffer output_buffer(size_t bytes) {
  auto& rt = Runtime::instance();
  return with_cl_errors("allocating a device buffer", [&] { return cl::Buffer(rt.context(), CL_MEM_WRITE_ONLY, bytes); });
}

// Sets the kernel's arguments in order and enqueues it over `global` (local size left to the driver).
template <typename... Args>
void launch(cl::Kernel& kernel, const cl::NDRange& global, const Args&... args) {
  with_cl_errors("launching a kernel", [&] {
    cl_uint index = 0;
    (kernel.setArg(index++, args), ...);
    Runtime::instance().queue().enqueueNDRangeKernel(kernel, cl::NullRange, global);
    return 0;
  });
}

// Queues a copy of `count` elements from `offset` (in elements) of the buffer to `dst`; call
// finish() before reading `dst`.
template <typename T>
void download_async(const cl::Buffer& buffer, size_t offset, size_t count, T* dst) {
  with_cl_errors("reading a device buffer", [&] {
    Runtime::instance().queue().enqueueReadBuffer(buffer, CL_FALSE, offset * sizeof(T), count * sizeof(T), dst);
    return 0;
  });
}

inline void finish() {
  with_cl_errors("waiting for the device", [] {
    Runtime::instance().queue().finish();
    return 0;
  });
}

}  // namespace proctex::ocl
