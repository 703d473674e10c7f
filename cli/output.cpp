#include "cli/output.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "core/error.h"

namespace proctex::cli {

void print_json(const nlohmann::json& j) { std::printf("%s\n", j.dump(2).c_str()); }

void print_table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> widths;
  for (const auto& row : rows)
    for (size_t i = 0; i < row.size(); ++i) {
      if (widths.size() <= i) widths.push_back(0);
      widths[i] = std::max(widths[i], row[i].size());
    }
  for (const auto& row : rows) {
    std::string line;
    for (size_t i = 0; i < row.size(); ++i) {
      line += row[i];
      if (i + 1 < row.size()) line += std::string(widths[i] - row[i].size() + 2, ' ');
    }
    std::printf("%s\n", line.c_str());
  }
}

void write_text_file(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!(out << text)) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw Error("cannot write '" + path + "'", "check that the folder exists and is writable");
    }
  }
  std::filesystem::rename(tmp, path);
}

bool stderr_is_terminal() { return isatty(STDERR_FILENO) != 0; }

std::string format_seconds(double s) {
  if (s < 1.0) return fmt::format("{:.0f} ms", s * 1000.0);
  if (s < 120.0) return fmt::format("{:.2f} s", s);
  return fmt::format("{}m{:02d}s", static_cast<int>(s / 60), static_cast<int>(s) % 60);
}

Progress::Progress(std::string stage, long total, bool quiet)
    : stage_(std::move(stage)), total_(total), enabled_(!quiet && stderr_is_terminal()),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(long done, const std::string& detail) {
  if (!enabled_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::string eta;
  if (done > 0 && done < total_) eta = "  ETA " + format_seconds(elapsed * (total_ - done) / done);
  std::fprintf(stderr, "\r\033[K%s  %ld/%ld  %s%s%s%s", stage_.c_str(), done, total_,
               format_seconds(elapsed).c_str(), eta.c_str(), detail.empty() ? "" : "  ", detail.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
}

}  // namespace proctex::cli
