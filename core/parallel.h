#pragma once
// fn(0) ... fn(n - 1) on several threads, for independent items (catalogue samples, frames,
// synthesis levels, the match's race lanes). The calling thread works too; the first exception
// stops the hand-out of further items and is rethrown once every thread has stopped.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace proctex {

// jobs <= 0: one thread per hardware thread.
template <typename Fn>
void parallel_for(size_t n, int jobs, Fn&& fn) {
  const int hw = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const size_t threads = std::min<size_t>(n, static_cast<size_t>(jobs > 0 ? jobs : hw));
  if (threads <= 1) {
    for (size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (size_t i; (i = next++) < n;) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace proctex
