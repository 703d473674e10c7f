#pragma once
// The analysis caches' binary vectors (synth/analysis.cpp, synth/graph_synthesis.cpp): a length,
// then the raw elements. A read checks the length against what the header promised, so a
// truncated or foreign file is a cache miss, not a crash.
#include <cstdint>
#include <fstream>
#include <vector>

namespace proctex::synth::detail {

template <typename T>
void write_vec(std::ofstream& f, const std::vector<T>& v) {
  const uint64_t n = v.size();
  f.write(reinterpret_cast<const char*>(&n), sizeof n);
  f.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
}

template <typename T>
bool read_vec(std::ifstream& f, std::vector<T>& v, uint64_t expected) {
  uint64_t n = 0;
  f.read(reinterpret_cast<char*>(&n), sizeof n);
  if (!f || n != expected) return false;
  v.resize(n);
  f.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T)));
  return static_cast<bool>(f);
}

}  // namespace proctex::synth::detail
