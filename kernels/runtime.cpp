#include "kernels/runtime.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

#include "core/error.h"
#include "core/hash.h"

namespace proctex::ocl {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  const auto e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

struct DeviceHandle {
  DeviceInfo info;
  cl::Device device;
};

std::vector<DeviceHandle> enumerate() {
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error&) {
    platforms.clear();  // CL_PLATFORM_NOT_FOUND_KHR when no ICD is installed
  }
  std::vector<DeviceHandle> out;
  for (auto& platform : platforms) {
    std::vector<cl::Device> devices;
    try {
      platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;  // a platform without devices is not an error
    }
    for (auto& d : devices) {
      DeviceHandle h;
      h.device = d;
      h.info.index = static_cast<int>(out.size());
      h.info.name = trim(d.getInfo<CL_DEVICE_NAME>());
      h.info.platform = trim(platform.getInfo<CL_PLATFORM_NAME>());
      h.info.vendor = trim(d.getInfo<CL_DEVICE_VENDOR>());
      h.info.version = trim(d.getInfo<CL_DEVICE_VERSION>());
      h.info.driver = trim(d.getInfo<CL_DRIVER_VERSION>());
      h.info.is_gpu = (d.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
      h.info.compute_units = d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
      h.info.global_memory = d.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
      h.info.max_allocation = d.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
      out.push_back(std::move(h));
    }
  }
  if (out.empty()) {
    throw Error("no OpenCL device found",
                "install an OpenCL driver, e.g. 'apt-get install pocl-opencl-icd' (scripts/install-deps.sh does)");
  }
  return out;
}

const DeviceHandle& select(const std::vector<DeviceHandle>& all, std::string selector) {
  if (selector.empty()) {
    if (const char* env = std::getenv("PROCTEX_DEVICE")) selector = env;
  }
  if (selector.empty()) {
    for (const auto& h : all)
      if (h.info.is_gpu) return h;
    return all.front();
  }
  const bool numeric = std::all_of(selector.begin(), selector.end(), ::isdigit);
  if (numeric) {
    const auto i = std::stoul(selector);
    if (i < all.size()) return all[i];
  } else {
    const std::string want = lower(selector);
    for (const auto& h : all) {
      if (want == "gpu" && h.info.is_gpu) return h;
      if (want == "cpu" && !h.info.is_gpu) return h;
    }
    for (const auto& h : all) {
      if (lower(h.info.name).find(want) != std::string::npos ||
          lower(h.info.platform).find(want) != std::string::npos)
        return h;
    }
  }
  throw UsageError("no OpenCL device matches '" + selector + "'",
                   "run 'proctex devices' and pass an index or part of a name to --device");
}

// Some drivers (PoCL) print compiler diagnostics straight to stderr; proctex reports the first
// error itself as one line, so stderr is silenced during builds unless PROCTEX_VERBOSE is set.
class StderrSilencer {
 public:
  StderrSilencer() {
    const char* verbose = std::getenv("PROCTEX_VERBOSE");
    if (verbose && *verbose) return;
    std::fflush(stderr);
    saved_ = dup(STDERR_FILENO);
    const int null_fd = open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null_fd >= 0) dup2(null_fd, STDERR_FILENO);
    if (null_fd >= 0) close(null_fd);
  }
  ~StderrSilencer() {
    if (saved_ < 0) return;
    std::fflush(stderr);
    dup2(saved_, STDERR_FILENO);
    close(saved_);
  }

 private:
  int saved_ = -1;
};

// Program binaries cache. PoCL caches compiled kernels too, but finding them costs a full
// preprocessing of the source (about 65 ms per shader program, measured with perf: most of a
// match's screening time across 53 shaders). A binary from clGetProgramInfo, rebuilt with
// clCreateProgramWithBinary, skips it. Keyed by device, driver, options and source; a binary the
// driver refuses is rebuilt from source. The cache is an optimisation: I/O errors are ignored.
std::filesystem::path binary_cache_dir() {
  if (const char* dir = std::getenv("PROCTEX_KERNEL_CACHE"); dir && *dir) return dir;
  if (const char* pocl = std::getenv("POCL_CACHE_DIR"); pocl && *pocl)
    return std::filesystem::path(pocl) / "proctex-binaries";
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "proctex/kernels";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache/proctex/kernels";
  return {};
}

std::vector<unsigned char> read_binary(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_binary(const std::filesystem::path& path, const std::vector<unsigned char>& bytes) {
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  const auto tmp = path.string() + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) return;
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) return;
  }
  std::filesystem::rename(tmp, path, ec);  // atomic: readers never see half a binary
  if (ec) std::filesystem::remove(tmp, ec);
}

std::string g_selector;
std::mutex g_instance_mutex;
std::unique_ptr<Runtime> g_instance;

}  // namespace

std::vector<DeviceInfo> list_devices() {
  std::vector<DeviceInfo> out;
  for (auto& h : enumerate()) out.push_back(h.info);
  return out;
}

DeviceInfo choose_device(const std::string& selector) {
  const auto all = enumerate();
  return select(all, selector).info;
}

void Runtime::configure(const std::string& selector) { g_selector = selector; }

Runtime& Runtime::instance() {
  std::lock_guard lock(g_instance_mutex);
  if (!g_instance) {
    const auto all = enumerate();
    g_instance.reset(new Runtime(select(all, g_selector).info));
  }
  return *g_instance;
}

Runtime::Runtime(const DeviceInfo& info) : device_(info) {
  // Enumeration order is stable within a process, so the index finds the same device again.
  const auto all = enumerate();
  cl_device_ = all.at(info.index).device;
  with_cl_errors("creating the OpenCL context", [&] {
    context_ = cl::Context(cl_device_);
    queue_ = cl::CommandQueue(context_, cl_device_);
    return 0;
  });
}

cl::Program Runtime::program(const std::string& source, const std::string& options) {
  const std::string key = options + '\0' + source;
  std::lock_guard lock(mutex_);
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;

  const auto start = std::chrono::steady_clock::now();
  const auto cache_dir = binary_cache_dir();
  const std::filesystem::path cached =
      cache_dir.empty() ? cache_dir
                        : cache_dir / (fnv1a_hex(device_.platform + '\0' + device_.name + '\0' + device_.driver + '\0' +
                                                 device_.version + '\0' + key) + ".bin");
  if (!cached.empty()) {
    if (auto bytes = read_binary(cached); !bytes.empty()) {
      try {
        StderrSilencer quiet;
        cl::Program program(context_, {cl_device_}, cl::Program::Binaries{bytes});
        program.build({cl_device_}, options.c_str());
        build_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        programs_.emplace(key, program);
        return program;
      } catch (const cl::Error&) {
        // Refused (another driver version, a damaged file): build from source and replace it.
      }
    }
  }
  cl::Program program(context_, source);
  try {
    StderrSilencer quiet;
    program.build({cl_device_}, options.c_str());
  } catch (const cl::Error& e) {
    std::string log;
    try {
      log = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(cl_device_);
    } catch (const cl::Error&) {
    }
    if (const char* verbose = std::getenv("PROCTEX_VERBOSE"); verbose && *verbose) {
      fprintf(stderr, "%s\n", log.c_str());
    }
    throw Error("OpenCL compile error: " + first_compiler_error(log),
                "fix the shader source; set PROCTEX_VERBOSE=1 to print the full compiler log");
  }
  if (!cached.empty()) {
    try {
      const auto binaries = program.getInfo<CL_PROGRAM_BINARIES>();
      if (!binaries.empty() && !binaries.front().empty()) write_binary(cached, binaries.front());
    } catch (const cl::Error&) {
    }
  }
  build_seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  programs_.emplace(key, program);
  return program;
}

std::string first_compiler_error(const std::string& log) {
  std::istringstream in(log);
  std::string line, first;
  while (std::getline(in, line)) {
    line = trim(line);
    if (line.empty()) continue;
    if (first.empty()) first = line;
    if (line.find("error:") != std::string::npos) return line;
  }
  return first.empty() ? "the compiler gave no log" : first;
}

std::string error_name(int code) {
  switch (code) {
#define PT_CASE(x) \
  case x:          \
    return #x;
    PT_CASE(CL_DEVICE_NOT_FOUND)
    PT_CASE(CL_DEVICE_NOT_AVAILABLE)
    PT_CASE(CL_COMPILER_NOT_AVAILABLE)
    PT_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    PT_CASE(CL_OUT_OF_RESOURCES)
    PT_CASE(CL_OUT_OF_HOST_MEMORY)
    PT_CASE(CL_BUILD_PROGRAM_FAILURE)
    PT_CASE(CL_INVALID_VALUE)
    PT_CASE(CL_INVALID_DEVICE)
    PT_CASE(CL_INVALID_CONTEXT)
    PT_CASE(CL_INVALID_COMMAND_QUEUE)
    PT_CASE(CL_INVALID_MEM_OBJECT)
    PT_CASE(CL_INVALID_PROGRAM)
    PT_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
    PT_CASE(CL_INVALID_KERNEL_NAME)
    PT_CASE(CL_INVALID_KERNEL)
    PT_CASE(CL_INVALID_ARG_INDEX)
    PT_CASE(CL_INVALID_ARG_VALUE)
    PT_CASE(CL_INVALID_ARG_SIZE)
    PT_CASE(CL_INVALID_KERNEL_ARGS)
    PT_CASE(CL_INVALID_WORK_DIMENSION)
    PT_CASE(CL_INVALID_WORK_GROUP_SIZE)
    PT_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
    PT_CASE(CL_INVALID_BUFFER_SIZE)
#undef PT_CASE
    default:
      return "OpenCL error " + std::to_string(code);
  }
}

}  // namespace proctex::ocl
