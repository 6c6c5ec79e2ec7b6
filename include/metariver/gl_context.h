// metariver gl: an OpenGL 4.5 core context without a window (headless EGL), the one
// thing the renderer (render.h) and the GPU compute stages (gpu_pbf.h, gpu_field.h)
// share besides the GL helpers private to them. This header carries no OpenGL type.
#pragma once

#include <metariver/core.h>

#include <memory>

namespace mr::gl {

/// AddressSanitizer builds only (a no-op otherwise): keeps every library loaded now
/// mapped until the process exits. Call before tearing down an OpenGL context: Mesa
/// unloads its driver then, and LeakSanitizer, which runs at exit, could no longer name
/// the module of what the driver still held ("<unknown module>"), so the suppressions
/// of tests/sanitizers/lsan.supp, which name Mesa's libraries, did not match.
void keep_loaded_libraries_under_asan();

/// An OpenGL 4.5 core context without a window or display: EGL on Mesa's surfaceless
/// platform (EGL_PLATFORM_SURFACELESS_MESA, EGL_NO_CONFIG_KHR, no surface), or where EGL
/// has no such platform (NVIDIA's) the first EGL device that initializes
/// (EGL_PLATFORM_DEVICE_EXT; METARIVER_EGL_PLATFORM=device picks it on Mesa too). Current
/// on the creating thread until destroyed. Sets XDG_RUNTIME_DIR to /tmp when unset (Mesa
/// warns otherwise).
class HeadlessContext {
public:
    /// Fails (one line, no abort) when libEGL, a headless platform or a 4.5 core context
    /// is not available.
    static Result<std::unique_ptr<HeadlessContext>> create();
    ~HeadlessContext();
    HeadlessContext(const HeadlessContext&) = delete;
    HeadlessContext& operator=(const HeadlessContext&) = delete;

private:
    HeadlessContext() = default;
    void* display_ = nullptr;
    void* context_ = nullptr;
};

}  // namespace mr::gl
