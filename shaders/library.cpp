#include "shaders/library.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace proctex::embedded {
const std::vector<std::pair<std::string, std::string>>& shader_files();
}

namespace proctex {
namespace {

// Levenshtein distance, for "did you mean" suggestions.
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot read shader file '" + path.string() + "'", "check its permissions");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

void ShaderLibrary::add(ShaderDecl decl) {
  auto same = [&](const ShaderDecl& d) { return d.name == decl.name; };
  shaders_.erase(std::remove_if(shaders_.begin(), shaders_.end(), same), shaders_.end());
  shaders_.push_back(std::move(decl));
  std::sort(shaders_.begin(), shaders_.end(), [](const ShaderDecl& a, const ShaderDecl& b) {
    return std::tie(a.family, a.name) < std::tie(b.family, b.name);
  });
}

ShaderLibrary ShaderLibrary::from_directory(const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(folder))
    throw Error("shader folder '" + folder.string() + "' does not exist", "fix PROCTEX_SHADER_PATH");
  ShaderLibrary lib;
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(folder))
    if (entry.is_regular_file() && entry.path().extension() == ".cl") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) lib.add(parse_shader(f.string(), read_file(f)));
  return lib;
}

const ShaderLibrary& ShaderLibrary::builtin() {
  static const ShaderLibrary lib = [] {
    ShaderLibrary l;
    for (const auto& [path, source] : embedded::shader_files()) l.add(parse_shader(path, source));
    if (const char* extra = std::getenv("PROCTEX_SHADER_PATH"); extra && *extra) {
      std::stringstream dirs(extra);
      std::string dir;
      while (std::getline(dirs, dir, ':')) {
        if (dir.empty()) continue;
        const ShaderLibrary user = from_directory(dir);  // keep alive: range-for over a temporary's member dangles
        for (const auto& d : user.shaders()) l.add(d);
      }
    }
    return l;
  }();
  return lib;
}

const ShaderDecl* ShaderLibrary::find(const std::string& name) const {
  for (const auto& d : shaders_)
    if (d.name == name) return &d;
  return nullptr;
}

const ShaderDecl& ShaderLibrary::get(const std::string& name) const {
  if (const auto* d = find(name)) return *d;
  std::vector<std::pair<size_t, std::string>> close;
  for (const auto& d : shaders_) {
    const size_t dist = edit_distance(name, d.name);
    if (dist <= std::max<size_t>(2, name.size() / 3) || d.name.find(name) != std::string::npos)
      close.emplace_back(dist, d.name);
  }
  std::sort(close.begin(), close.end());
  std::string hint = "run 'proctex shaders list' to see all shaders";
  if (!close.empty()) {
    hint = "did you mean ";
    for (size_t i = 0; i < std::min<size_t>(3, close.size()); ++i)
      hint += (i ? ", " : "") + close[i].second;
    hint += "?";
  }
  throw UsageError("unknown shader '" + name + "'", hint);
}

std::vector<std::string> ShaderLibrary::names() const {
  std::vector<std::string> out;
  for (const auto& d : shaders_) out.push_back(d.name);
  return out;
}

}  // namespace proctex
