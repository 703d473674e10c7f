#pragma once
// Row-parallel loops for the per-pixel operators (std::thread, one band of rows per core).
#include <algorithm>
#include <thread>
#include <vector>

namespace proctex::rgbn::detail {

// Calls body(row_begin, row_end) on disjoint bands covering [0, rows).
template <typename F>
void parallel_rows(int rows, F&& body, int min_rows_per_thread = 64) {
  const int hw = std::max(1u, std::thread::hardware_concurrency());
  const int threads = std::clamp(rows / std::max(1, min_rows_per_thread), 1, hw);
  if (threads <= 1) {
    body(0, rows);
    return;
  }
  std::vector<std::thread> pool;
  const int band = (rows + threads - 1) / threads;
  for (int t = 1; t < threads; ++t) {
    const int b = t * band, e = std::min(rows, b + band);
    if (b < e) pool.emplace_back([&body, b, e] { body(b, e); });
  }
  body(0, std::min(rows, band));
  for (auto& th : pool) th.join();
}

}  // namespace proctex::rgbn::detail
