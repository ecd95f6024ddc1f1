#pragma once
// A GoogleTest fixture with a headless OpenGL 4.5 context (`auto`: EGL, then OSMesa) and a
// renderer on it; the test is skipped, saying why, where no context can be made.
#include <gtest/gtest.h>

#include <exception>
#include <memory>

#include "render/context.h"
#include "render/renderer.h"

namespace quadrix {

class GlTest : public ::testing::Test {
protected:
  void SetUp() override {
    try {
      context_ = render::create_context("auto");
    } catch (const std::exception& e) {
      GTEST_SKIP() << "no headless OpenGL 4.5 context: " << e.what();
    }
    renderer_ = std::make_unique<render::Renderer>(*context_);
  }

  std::unique_ptr<render::GlContext> context_;
  std::unique_ptr<render::Renderer> renderer_;
};

}  // namespace quadrix
