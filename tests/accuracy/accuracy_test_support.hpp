// Shared set-up for the accuracy suites: one headless EGL context per suite.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "gles/egl_context.hpp"

namespace probelight::testing {

class GpuSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    context_ = gles::EglContext::createHeadless(error).release();
    ASSERT_NE(context_, nullptr) << error;
  }
  static void TearDownTestSuite() {
    delete context_;
    context_ = nullptr;
  }
  static inline gles::EglContext* context_ = nullptr;
};

}  // namespace probelight::testing
