#pragma once
// A user's shader file for tests of edited shaders: a one-parameter band pattern whose brightness
// is `gain`, written to DIR/mine_bands.cl (load it with PROCTEX_SHADER_PATH=DIR). Writing it again
// with another gain is "the user edits the shader": its source hash changes.
#include <filesystem>
#include <fstream>
#include <string>

namespace proctex::testing {

inline void write_bands_shader(const std::filesystem::path& dir, const std::string& gain) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "mine_bands.cl")
      << "// @shader \"bands for a test\"\n// @param float size = 0.5 [0.1, 1] \"band size\"\n"
         "float3 shade(float2 p, float fw, uint seed, const Params P) {\n"
         "  return (float3)(" << gain << "f * pt_fract(p.x * 4.0f / P.size));\n}\n";
}

}  // namespace proctex::testing
