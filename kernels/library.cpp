#include "kernels/library.h"

#include <algorithm>
#include <array>

namespace proctex::embedded {
const std::vector<std::pair<std::string, std::string>>& opencl_library_files();
}

namespace proctex::ocl {

const std::vector<std::pair<std::string, std::string>>& library_files() {
  static const auto ordered = [] {
    // Dependency order: later files call functions of earlier ones.
    // A new library file must be added here; unknown files would go last in name order.
    static const std::array<const char*, 9> order = {"hash.cl",  "noise.cl", "fractal.cl", "pattern.cl", "color.cl",
                                                     "sdf.cl",   "tiling.cl", "fabric.cl",  "wood.cl"};
    auto files = embedded::opencl_library_files();
    auto rank = [](const std::string& path) {
      for (size_t i = 0; i < order.size(); ++i)
        if (path.ends_with(order[i])) return i;
      return order.size();
    };
    std::stable_sort(files.begin(), files.end(),
                     [&](const auto& a, const auto& b) { return rank(a.first) < rank(b.first); });
    return files;
  }();
  return ordered;
}

std::string line_directive(const std::string& file, int line) {
  return "#line " + std::to_string(line) + " \"" + file + "\"\n";
}

const std::string& library_source() {
  static const std::string source = [] {
    std::string s;
    for (const auto& [path, text] : library_files()) {
      s += line_directive(path, 1);
      s += text;
      if (!s.empty() && s.back() != '\n') s += '\n';
    }
    return s;
  }();
  return source;
}

}  // namespace proctex::ocl
