// Tests for backend parsing and resolution: auto falls back, cuda without a GPU is a clear error.
#include <gtest/gtest.h>

#include "host/backends/backend_choice.h"
#include "kernels/device_info.h"
#include "model/backend.h"
#include "model/input_error.h"

using namespace inc;

TEST(Backend, ParsesTheThreeNamesAndRejectsOthers) {
  EXPECT_EQ(parseBackend("auto"), BackendKind::Auto);
  EXPECT_EQ(parseBackend("cuda"), BackendKind::Cuda);
  EXPECT_EQ(parseBackend("cpu"), BackendKind::Cpu);
  try {
    parseBackend("vulkan", "scene.json", "solver.backend");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "solver.backend");
    EXPECT_NE(std::string(e.what()).find("vulkan"), std::string::npos);
  }
}

TEST(Backend, AutoResolvesToSomethingRunnableWithANote) {
  BackendChoice c = resolveBackend(BackendKind::Auto);
  EXPECT_NE(c.kind, BackendKind::Auto);
  EXPECT_FALSE(c.note.empty());
  const auto dev = cuda::queryDevices();
  if (dev.device_count == 0) {
    EXPECT_EQ(c.kind, BackendKind::Cpu);
    EXPECT_NE(c.note.find("falling back to the CPU"), std::string::npos);
  } else {
    EXPECT_EQ(c.kind, BackendKind::Cuda);
  }
}

TEST(Backend, CudaWithoutGpuIsAnInputErrorNotACrash) {
  if (cuda::queryDevices().device_count > 0) GTEST_SKIP() << "a GPU is present here";
  EXPECT_THROW(resolveBackend(BackendKind::Cuda), InputError);
}
