#include "metrics/fft.h"

#include <fftw3.h>

#include <map>
#include <mutex>
#include <new>
#include <tuple>

namespace proctex::metrics::detail {

template <typename T>
FftwArray<T>::FftwArray(std::size_t n) : size_(n) {
  data_ = static_cast<T*>(fftwf_malloc(sizeof(T) * (n ? n : 1)));
  if (!data_) throw std::bad_alloc();
  // Left uninitialised (float and std::complex<float> need no construction): every user writes
  // an array before reading it, and zeroing cost more than a 2-D FFT of the same size.
}

template <typename T>
FftwArray<T>::~FftwArray() {
  if (data_) fftwf_free(data_);
}

template <typename T>
FftwArray<T>& FftwArray<T>::operator=(FftwArray&& other) noexcept {
  if (this != &other) {
    if (data_) fftwf_free(data_);
    data_ = other.data_;
    size_ = other.size_;
    other.data_ = nullptr;
    other.size_ = 0;
  }
  return *this;
}

template class FftwArray<float>;
template class FftwArray<Complex>;

namespace {

enum class Kind { r2c, c2r, c2c_forward, c2c_backward };
using Key = std::tuple<Kind, int, int>;

std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// Plans live until the process exits (a handful of sizes; never destroyed, so no ordering
// problem with static destruction).
fftwf_plan plan_for(Kind kind, int rows, int cols) {
  static std::map<Key, fftwf_plan>* plans = new std::map<Key, fftwf_plan>();
  std::lock_guard<std::mutex> lock(planner_mutex());
  Key key{kind, rows, cols};
  auto it = plans->find(key);
  if (it != plans->end()) return it->second;
  const std::size_t n = static_cast<std::size_t>(rows) * cols;
  fftwf_plan plan = nullptr;
  if (kind == Kind::r2c) {
    FftwArray<float> in(n);
    FftwArray<Complex> out(static_cast<std::size_t>(rows) * (cols / 2 + 1));
    plan = fftwf_plan_dft_r2c_2d(rows, cols, in.data(),
                                 reinterpret_cast<fftwf_complex*>(out.data()), FFTW_ESTIMATE);
  } else if (kind == Kind::c2r) {
    FftwArray<Complex> in(static_cast<std::size_t>(rows) * (cols / 2 + 1));
    FftwArray<float> out(n);
    plan = fftwf_plan_dft_c2r_2d(rows, cols, reinterpret_cast<fftwf_complex*>(in.data()),
                                 out.data(), FFTW_ESTIMATE);
  } else {
    FftwArray<Complex> in(n), out(n);
    plan = fftwf_plan_dft_2d(rows, cols, reinterpret_cast<fftwf_complex*>(in.data()),
                             reinterpret_cast<fftwf_complex*>(out.data()),
                             kind == Kind::c2c_forward ? FFTW_FORWARD : FFTW_BACKWARD,
                             FFTW_ESTIMATE);
  }
  if (!plan) throw std::bad_alloc();
  plans->emplace(key, plan);
  return plan;
}

}  // namespace

void fft_r2c(int rows, int cols, FftwArray<float>& in, FftwArray<Complex>& out) {
  fftwf_plan plan = plan_for(Kind::r2c, rows, cols);
  fftwf_execute_dft_r2c(plan, in.data(),
                        reinterpret_cast<fftwf_complex*>(out.data()));
}

void fft_c2r(int rows, int cols, FftwArray<Complex>& in, FftwArray<float>& out) {
  fftwf_plan plan = plan_for(Kind::c2r, rows, cols);
  fftwf_execute_dft_c2r(plan, reinterpret_cast<fftwf_complex*>(in.data()), out.data());
}

void fft_c2c(int rows, int cols, const FftwArray<Complex>& in, FftwArray<Complex>& out,
             bool inverse) {
  fftwf_plan plan = plan_for(inverse ? Kind::c2c_backward : Kind::c2c_forward, rows, cols);
  fftwf_execute_dft(plan, reinterpret_cast<fftwf_complex*>(const_cast<Complex*>(in.data())),
                    reinterpret_cast<fftwf_complex*>(out.data()));
}

}  // namespace proctex::metrics::detail
