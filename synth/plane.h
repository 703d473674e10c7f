#pragma once
// Internal helpers shared by synth/'s single-exemplar and graph synthesis (not a public API):
// index arithmetic on the exemplar (wrap or mirror), the level count of an exemplar, the plane's
// coordinate bound and the fixed-work-group kernel launch.
#include <algorithm>
#include <cstdint>

#include "kernels/runtime.h"

namespace proctex::synth::detail {

inline int wrap(int x, int n) {
  const int r = x % n;
  return r < 0 ? r + n : r;
}

// Mirror without repeating the edge texel (period 2n - 2): no wrap-around across the border.
inline int reflect(int x, int n) {
  if (n == 1) return 0;
  const int p = 2 * n - 2;
  x = wrap(x, p);
  return x >= n ? p - x : x;
}

// Reads an exemplar of w x h texels at any integer position: toroidal or mirrored.
struct Sampler {
  int w, h;
  bool toroidal;
  int ix(int x) const { return toroidal ? wrap(x, w) : reflect(x, w); }
  int iy(int y) const { return toroidal ? wrap(y, h) : reflect(y, h); }
};

// L = ceil(log2 of the larger side): the levels of the Gaussian stack.
inline int level_count(int w, int h) {
  int L = 0;
  while ((1 << L) < std::max(w, h)) ++L;
  return L;
}

// Window offsets are accepted within +-2^60 (the hashes and coordinates stay exact).
inline constexpr int64_t kMaxCoordinate = int64_t(1) << 60;

// A fixed work-group size: PoCL compiles a kernel once per local size, and with the driver's
// choice every new window size cost a compilation (~0.4 s CPU). Global sizes are rounded up; the
// kernels ignore the extra items.
inline constexpr int kLocalX = 16, kLocalY = 4;

template <typename... Args>
void launch2d(const char* what, cl::Kernel& kernel, int gx, int gy, const Args&... args) {
  ocl::with_cl_errors(what, [&] {
    cl_uint index = 0;
    (kernel.setArg(index++, args), ...);
    const int rx = (gx + kLocalX - 1) / kLocalX * kLocalX, ry = (gy + kLocalY - 1) / kLocalY * kLocalY;
    ocl::Runtime::instance().queue().enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(rx, ry),
                                                          cl::NDRange(kLocalX, kLocalY));
    return 0;
  });
}

}  // namespace proctex::synth::detail
