#pragma once
// OpenCL runtime: device discovery and choice, one context and queue per process, programs built
// once per process (PoCL additionally caches compiled kernels on disk in POCL_CACHE_DIR).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "kernels/opencl.h"

namespace proctex::ocl {

struct DeviceInfo {
  int index = 0;  // position in list_devices(), stable for a given machine
  std::string name;
  std::string platform;
  std::string vendor;
  std::string version;       // OpenCL version string of the device
  std::string driver;
  bool is_gpu = false;
  unsigned compute_units = 0;
  uint64_t global_memory = 0;     // bytes
  uint64_t max_allocation = 0;    // bytes, largest single buffer
};

// Every OpenCL device of every platform. Throws proctex::Error when there is none.
std::vector<DeviceInfo> list_devices();

// Picks a device: selector "" means $PROCTEX_DEVICE, and if that is unset the first GPU, else the
// first device. A selector is a list_devices() index or a case-insensitive substring of the
// device or platform name ("cpu" and "gpu" select by type).
DeviceInfo choose_device(const std::string& selector = "");

// Where a line of a generated program came from, for mapping compiler messages back.
struct SourceLocation {
  std::string file;
  int line = 0;
};

// Process-wide OpenCL state. Created on first use with the selector given to configure() (or the
// default choice); every program is built at most once per process.
class Runtime {
 public:
  // Sets the device selector for the process; must be called before the first instance() call to
  // have an effect (the CLI calls it with --device).
  static void configure(const std::string& selector);
  static Runtime& instance();

  const DeviceInfo& device() const { return device_; }
  cl::Context& context() { return context_; }
  cl::CommandQueue& queue() { return queue_; }

  // Builds `source` (or returns the program built earlier from the same source and options).
  // On a compile error throws proctex::Error whose message names the first error's file and line
  // (the source carries #line directives) and whose hint points at the full log.
  cl::Program program(const std::string& source, const std::string& options = "");

  // Seconds spent in program builds so far (shown by benchmarks and --verbose output).
  double build_seconds() const { return build_seconds_; }

 private:
  explicit Runtime(const DeviceInfo& info);

  DeviceInfo device_;
  cl::Device cl_device_;
  cl::Context context_;
  cl::CommandQueue queue_;
  std::mutex mutex_;
  std::unordered_map<std::string, cl::Program> programs_;  // key: options + '\0' + source
  double build_seconds_ = 0;
};

// Turns an OpenCL error code into a readable name ("CL_OUT_OF_RESOURCES").
std::string error_name(int code);

// Runs `fn` and converts cl::Error into proctex::Error with `what` as context.
template <typename Fn>
auto with_cl_errors(const char* what, Fn&& fn) -> decltype(fn());

// The first "file:line:col: error: ..." line of a compiler log, or the log's first line.
std::string first_compiler_error(const std::string& log);

}  // namespace proctex::ocl

#include "kernels/runtime_inl.h"
