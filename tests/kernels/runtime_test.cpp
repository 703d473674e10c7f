// The OpenCL runtime on the machine's real device (PoCL's CPU device in CI).
#include <gtest/gtest.h>

#include "core/error.h"
#include "kernels/library.h"
#include "kernels/runtime.h"

namespace proctex::ocl {
namespace {

TEST(Runtime, ListsAtLeastOneDevice) {
  const auto devices = list_devices();
  ASSERT_FALSE(devices.empty());
  for (size_t i = 0; i < devices.size(); ++i) {
    EXPECT_EQ(devices[i].index, static_cast<int>(i));
    EXPECT_FALSE(devices[i].name.empty());
    EXPECT_GT(devices[i].compute_units, 0u);
  }
}

TEST(Runtime, ChoosesByIndexTypeAndName) {
  const auto devices = list_devices();
  EXPECT_EQ(choose_device("0").name, devices[0].name);
  // PoCL's device is a CPU: "cpu" must find a CPU device whenever one exists.
  for (const auto& d : devices)
    if (!d.is_gpu) {
      EXPECT_FALSE(choose_device("cpu").is_gpu);
      break;
    }
  const std::string part = devices[0].name.substr(0, 4);
  EXPECT_NE(choose_device(part).name.find(part), std::string::npos);
}

TEST(Runtime, DefaultPrefersGpuElseFirst) {
  const auto devices = list_devices();
  bool any_gpu = false;
  for (const auto& d : devices) any_gpu |= d.is_gpu;
  unsetenv("PROCTEX_DEVICE");
  const auto chosen = choose_device("");
  if (any_gpu) EXPECT_TRUE(chosen.is_gpu);
  else EXPECT_EQ(chosen.index, 0);
}

TEST(Runtime, UnknownSelectorIsAUsageError) {
  EXPECT_THROW(choose_device("no-such-device-xyz"), UsageError);
  EXPECT_THROW(choose_device("999"), UsageError);
}

TEST(Runtime, EnvironmentSelectsDevice) {
  setenv("PROCTEX_DEVICE", "0", 1);
  EXPECT_EQ(choose_device("").index, 0);
  setenv("PROCTEX_DEVICE", "no-such-device-xyz", 1);
  EXPECT_THROW(choose_device(""), UsageError);
  unsetenv("PROCTEX_DEVICE");
}

TEST(Runtime, CompileErrorNamesFileAndLine) {
  auto& rt = Runtime::instance();
  const std::string source = line_directive("shaders/test/broken.cl", 1) +
                             "__kernel void k(__global float* o) {\n"
                             "  o[0] = 1.0f;\n"
                             "  o[1] = not_declared;\n"
                             "}\n";
  try {
    rt.program(source);
    FAIL() << "expected a compile error";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("shaders/test/broken.cl:3"), std::string::npos) << e.message();
    EXPECT_NE(e.message().find("not_declared"), std::string::npos) << e.message();
  }
}

TEST(Runtime, BuildsEachProgramOncePerProcess) {
  auto& rt = Runtime::instance();
  const std::string source = "__kernel void once(__global float* o) { o[get_global_id(0)] = 2.0f; }\n";
  cl::Program first = rt.program(source);
  const double after_first = rt.build_seconds();
  cl::Program second = rt.program(source);
  EXPECT_EQ(rt.build_seconds(), after_first);
  EXPECT_EQ(first(), second());
}

TEST(Runtime, FirstCompilerErrorPicksTheErrorLine) {
  EXPECT_EQ(first_compiler_error("warning: x\nfile.cl:3:1: error: bad\nmore"), "file.cl:3:1: error: bad");
  EXPECT_EQ(first_compiler_error(""), "the compiler gave no log");
}

}  // namespace
}  // namespace proctex::ocl
