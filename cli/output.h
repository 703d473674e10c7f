#pragma once
// Output helpers shared by the commands: JSON on stdout, aligned tables, progress on stderr.
#include <chrono>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace proctex::cli {

void print_json(const nlohmann::json& j);

// Left-aligned columns separated by two spaces; the first row is the header.
void print_table(const std::vector<std::vector<std::string>>& rows);

// True when stderr is a terminal (progress lines are drawn only then).
bool stderr_is_terminal();

// Progress on stderr: "stage  done/total  elapsed  ETA", redrawn in place on a terminal,
// silent otherwise (and when quiet).
class Progress {
 public:
  Progress(std::string stage, long total, bool quiet);
  ~Progress();
  void update(long done, const std::string& detail = {});
  void finish();

 private:
  std::string stage_;
  long total_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

// Writes a text file through a temporary and a rename, so a failed write leaves no half file.
void write_text_file(const std::string& path, const std::string& text);

// "1.23 s", "45 ms".
std::string format_seconds(double seconds);

}  // namespace proctex::cli
