#pragma once
// FNV-1a 64-bit of a string as 16 hex digits: stable across runs, compilers and platforms, so it
// can key files on disk (catalogue staleness, the kernel binary cache).
#include <cstdint>
#include <cstdio>
#include <string>

namespace proctex {

inline std::string fnv1a_hex(const std::string& text) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace proctex
