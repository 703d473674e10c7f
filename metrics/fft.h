#pragma once
// FFTW plumbing shared by the metrics (internal to metrics/, but a header so tests can use it).
// FFTW's planner is not thread-safe: plans are created under one mutex, cached per (kind, size)
// for the life of the process, and executed with the new-array functions, which are thread-safe.
// Plans use FFTW_ESTIMATE (measured plans are faster for c2c but differ from run to run): deterministic (the same plan, so bit-identical features, in every
// process - a catalogue compares cached features with fresh ones) and no measuring at start-up.
#include <complex>
#include <cstddef>

namespace proctex::metrics::detail {

using Complex = std::complex<float>;  // layout-compatible with fftwf_complex

// Heap array allocated with fftwf_malloc (SIMD alignment the cached plans assume). The contents
// start uninitialised: write before reading.
template <typename T>
class FftwArray {
 public:
  FftwArray() = default;
  explicit FftwArray(std::size_t n);
  ~FftwArray();
  FftwArray(const FftwArray&) = delete;
  FftwArray& operator=(const FftwArray&) = delete;
  FftwArray(FftwArray&& other) noexcept : data_(other.data_), size_(other.size_) {
    other.data_ = nullptr;
    other.size_ = 0;
  }
  FftwArray& operator=(FftwArray&& other) noexcept;

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// 2-D real-to-complex forward transform of rows x cols real values into rows x (cols/2 + 1)
// complex values (unnormalised). `in` is scratch: FFTW's multi-dimensional r2c may overwrite it.
void fft_r2c(int rows, int cols, FftwArray<float>& in, FftwArray<Complex>& out);
// 2-D complex-to-real inverse of rows x (cols/2 + 1) Hermitian half-spectrum values into rows x
// cols real values (unnormalised). `in` is scratch: c2r always overwrites its input.
void fft_c2r(int rows, int cols, FftwArray<Complex>& in, FftwArray<float>& out);
// 2-D complex transform (unnormalised); inverse = FFTW_BACKWARD. in and out must not alias.
void fft_c2c(int rows, int cols, const FftwArray<Complex>& in, FftwArray<Complex>& out,
             bool inverse);

}  // namespace proctex::metrics::detail
