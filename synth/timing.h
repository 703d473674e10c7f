#pragma once
// Phase timings of a synthesis on stderr, for profiling (issue 13): set PROCTEX_SYNTH_TIMING=1 and
// every mark() prints one line `proctex: timing: <phase>  wall +X ms  cpu +Y ms  (total wall, cpu)`.
// Wall is measured from the process start (/proc/self/stat, 10 ms resolution for the first line;
// then steady_clock), CPU is the process's user + system time over all threads (getrusage), so the
// first line includes the process start-up. While enabled, the synthesis waits for the device after
// each phase (clFinish) so device work is charged to its phase; results do not change.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace proctex::synth::timing {

inline bool enabled() {
  static const bool on = [] {
    const char* e = std::getenv("PROCTEX_SYNTH_TIMING");
    return e && *e && std::string(e) != "0";
  }();
  return on;
}

namespace detail {
inline double cpu_ms() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return (ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) * 1e3 + (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-3;
}
// Milliseconds since the process started (boot-time clock against the process's start tick).
inline double since_start_ms() {
  std::ifstream stat("/proc/self/stat");
  std::string s((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const auto close = s.rfind(')');
  if (close == std::string::npos) return 0;
  // Fields after the command name: state is field 3; starttime is field 22.
  size_t pos = close + 2;
  for (int field = 3; field < 22 && pos != std::string::npos; ++field) pos = s.find(' ', pos) + 1;
  const double start_ticks = std::strtod(s.c_str() + pos, nullptr);
  timespec now{};
  clock_gettime(CLOCK_BOOTTIME, &now);
  return (now.tv_sec + now.tv_nsec * 1e-9) * 1e3 - start_ticks * 1e3 / static_cast<double>(sysconf(_SC_CLK_TCK));
}
struct State {
  std::chrono::steady_clock::time_point origin = std::chrono::steady_clock::now();
  double origin_ms = since_start_ms();
  double last_wall = 0, last_cpu = 0;  // the first line covers the process start
};
inline State& state() {
  static State s;
  return s;
}
}  // namespace detail

inline void mark(const std::string& phase) {
  if (!enabled()) return;
  auto& s = detail::state();
  const double wall =
      s.origin_ms + std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - s.origin).count();
  const double cpu = detail::cpu_ms();
  std::fprintf(stderr, "proctex: timing: %-34s wall %+8.2f ms  cpu %+8.2f ms   (total %8.1f / %8.1f)\n", phase.c_str(),
               wall - s.last_wall, cpu - s.last_cpu, wall, cpu);
  s.last_wall = wall;
  s.last_cpu = cpu;
}

}  // namespace proctex::synth::timing
