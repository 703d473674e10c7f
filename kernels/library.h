#pragma once
// The shared OpenCL C library (hash, noise, fractal, pattern, colour helpers) that every shader
// program starts with. The sources are embedded in the binary at build time.
#include <string>
#include <utility>
#include <vector>

namespace proctex::ocl {

// The library's files as {path relative to the repository, contents}, in dependency order.
const std::vector<std::pair<std::string, std::string>>& library_files();

// All library files concatenated, each preceded by a #line directive naming its file, so compiler
// messages point at kernels/cl/<file>.cl and the right line.
const std::string& library_source();

// "#line <line> \"<file>\"\n": the directive that maps following lines back to a source file.
std::string line_directive(const std::string& file, int line);

}  // namespace proctex::ocl
