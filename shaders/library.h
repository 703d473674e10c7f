#pragma once
// The shader library: every shaders/<family>/<name>.cl embedded in the binary, plus the .cl files
// of the folders listed in $PROCTEX_SHADER_PATH (colon-separated) for users' own shaders.
#include <filesystem>
#include <string>
#include <vector>

#include "shaders/shader.h"

namespace proctex {

class ShaderLibrary {
 public:
  // The embedded library plus $PROCTEX_SHADER_PATH; parsed once per process.
  static const ShaderLibrary& builtin();
  // Only the .cl files found (recursively) in `folder`.
  static ShaderLibrary from_directory(const std::filesystem::path& folder);

  // Throws UsageError naming close matches when `name` is unknown.
  const ShaderDecl& get(const std::string& name) const;
  const ShaderDecl* find(const std::string& name) const;
  const std::vector<ShaderDecl>& shaders() const { return shaders_; }
  std::vector<std::string> names() const;

  // Adds a shader; a later shader with the same name replaces the earlier one (user overrides).
  void add(ShaderDecl decl);

 private:
  std::vector<ShaderDecl> shaders_;  // sorted by family, then name
};

}  // namespace proctex
