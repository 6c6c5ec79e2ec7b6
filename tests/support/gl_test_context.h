// Shared by the test programs that draw or compute with OpenGL (render_tests, gpu_tests):
// one headless OpenGL context for the whole test program; REQUIRE_GL skips a test, with
// the reason, where none can be made.
#pragma once

#include <metariver/gl_context.h>

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include "require.h"

namespace mr::test {

/// One context for the whole test program (creating one costs ~50 ms on llvmpipe).
inline gl::HeadlessContext* context() {
    static std::unique_ptr<gl::HeadlessContext> ctx;
    static std::string error;
    static bool tried = false;
    if (!tried) {
        tried = true;
        auto r = gl::HeadlessContext::create();
        if (r) ctx = std::move(r.value());
        else error = r.error().message;
    }
    return ctx.get();
}

inline std::string context_error() {
    auto r = gl::HeadlessContext::create();
    return r ? std::string() : r.error().message;
}

}  // namespace mr::test

#define REQUIRE_GL()                                                                                   \
    do {                                                                                                \
        if (!::mr::test::context())                                                                     \
            MR_SKIP_OR_FAIL("no headless OpenGL 4.5 (EGL surfaceless): " << ::mr::test::context_error()); \
    } while (0)
