#pragma once
// Helpers shared by image.cpp and io.cpp (internal to image/).
#include <filesystem>
#include <string>

namespace proctex::detail {

std::string quoted(const std::filesystem::path& path);
std::string lower_extension(const std::filesystem::path& path);
// What the file's first bytes say it is (the libraries we read directly, or anything else).
enum class Format { Png, Jpeg, Other };
Format sniff(const std::filesystem::path& path);
// Throws proctex::Error when the target's directory does not exist.
void check_parent_directory(const std::filesystem::path& path);
// An empty, uniquely named file beside `target` with the same extension.
std::filesystem::path create_temporary(const std::filesystem::path& target);

}  // namespace proctex::detail
