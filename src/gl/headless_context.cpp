// A headless OpenGL 4.5 core context: EGL on Mesa's surfaceless platform, no display,
// no window, no surface (rendering goes to the renderer's framebuffer object).
//
// libepoxy resolves EGL and GL entry points; <epoxy/egl.h> is included instead of
// <EGL/egl.h> (the two declare khronos_boolean_enum_t twice). libepoxy aborts the
// process when libEGL cannot be loaded, so its presence is checked with dlopen first:
// a machine without Mesa gets an error value, not a crash.
#include <metariver/gl_context.h>

#include <epoxy/egl.h>
#include <fmt/format.h>

#include <cstdlib>
#include <dlfcn.h>
#include <link.h>

#include <string>
#include <vector>

#if defined(__SANITIZE_ADDRESS__)
#define METARIVER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define METARIVER_ASAN 1
#endif
#endif

namespace mr::gl {

namespace {

std::string egl_error_name(EGLint e) {
    switch (e) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        default: return fmt::format("EGL error 0x{:x}", e);
    }
}

}  // namespace

void keep_loaded_libraries_under_asan() {
#ifdef METARIVER_ASAN
    std::vector<std::string> names;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
            if (info->dlpi_name && info->dlpi_name[0]) static_cast<std::vector<std::string>*>(out)->emplace_back(info->dlpi_name);
            return 0;
        },
        &names);
    for (const std::string& n : names) dlopen(n.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);  // never closed
#endif
}

Result<std::unique_ptr<HeadlessContext>> HeadlessContext::create() {
    setenv("XDG_RUNTIME_DIR", "/tmp", 0);  // keeps Mesa from warning; never overrides
    static void* libegl = dlopen("libEGL.so.1", RTLD_NOW | RTLD_GLOBAL);
    if (!libegl) return Error{"headless OpenGL: libEGL.so.1 not found (install libegl1 and libegl-mesa0)"};

    const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    const std::string ext = client_ext ? client_ext : "";
    const auto has = [](const std::string& list, const char* name) {
        return (" " + list + " ").find(std::string(" ") + name + " ") != std::string::npos;
    };
    if (!has(ext, "EGL_EXT_platform_base"))
        return Error{"headless OpenGL: EGL has no platform displays (EGL_EXT_platform_base; install libegl-mesa0)"};
    // Mesa's surfaceless platform; else (NVIDIA's EGL, which has no Mesa platform) the
    // first EGL device that initializes.
    EGLDisplay dpy = EGL_NO_DISPLAY;
    EGLint major = 0, minor = 0;
    std::string why = "EGL has neither the surfaceless platform (EGL_MESA_platform_surfaceless; install "
                      "libegl-mesa0) nor a device platform (EGL_EXT_platform_device)";
    // METARIVER_EGL_PLATFORM=device skips the surfaceless platform (to try, on Mesa, the
    // path NVIDIA's EGL takes).
    const char* forced = std::getenv("METARIVER_EGL_PLATFORM");
    const bool device_only = forced && std::string(forced) == "device";
    if (has(ext, "EGL_MESA_platform_surfaceless") && !device_only) {
        dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (dpy == EGL_NO_DISPLAY) return Error{"headless OpenGL: no EGL surfaceless display"};
        if (!eglInitialize(dpy, &major, &minor))
            return Error{fmt::format("headless OpenGL: eglInitialize failed ({})", egl_error_name(eglGetError()))};
    } else if (has(ext, "EGL_EXT_platform_device") &&
               (has(ext, "EGL_EXT_device_enumeration") || has(ext, "EGL_EXT_device_base"))) {
        EGLDeviceEXT devices[16];
        EGLint count = 0;
        if (!eglQueryDevicesEXT(16, devices, &count) || count <= 0) {
            why = "EGL lists no devices (eglQueryDevicesEXT)";
            count = 0;
        }
        for (EGLint k = 0; k < count && dpy == EGL_NO_DISPLAY; ++k) {
            EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[k], nullptr);
            if (d == EGL_NO_DISPLAY) continue;
            if (eglInitialize(d, &major, &minor)) dpy = d;
            else why = fmt::format("eglInitialize failed on every EGL device ({})", egl_error_name(eglGetError()));
        }
    }
    if (dpy == EGL_NO_DISPLAY) return Error{"headless OpenGL: " + why};
    const char* dpy_ext_c = eglQueryString(dpy, EGL_EXTENSIONS);
    const std::string dpy_ext = dpy_ext_c ? dpy_ext_c : "";
    if (!has(dpy_ext, "EGL_KHR_surfaceless_context")) {
        eglTerminate(dpy);
        return Error{"headless OpenGL: EGL lacks EGL_KHR_surfaceless_context"};
    }
    // Without EGL_KHR_no_config_context: any config that renders desktop OpenGL.
    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (!has(dpy_ext, "EGL_KHR_no_config_context")) {
        const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint found = 0;
        if (!eglChooseConfig(dpy, want, &config, 1, &found) || found < 1) {
            eglTerminate(dpy);
            return Error{"headless OpenGL: EGL lacks EGL_KHR_no_config_context and has no desktop OpenGL config"};
        }
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        eglTerminate(dpy);
        return Error{"headless OpenGL: EGL cannot bind the desktop OpenGL API"};
    }
    const EGLint attrs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                            EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, attrs);
    if (ctx == EGL_NO_CONTEXT) {
        const EGLint e = eglGetError();
        eglTerminate(dpy);
        return Error{fmt::format("headless OpenGL: no OpenGL 4.5 core context ({})", egl_error_name(e))};
    }
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        const EGLint e = eglGetError();
        eglDestroyContext(dpy, ctx);
        eglTerminate(dpy);
        return Error{fmt::format("headless OpenGL: eglMakeCurrent failed ({})", egl_error_name(e))};
    }
    auto out = std::unique_ptr<HeadlessContext>(new HeadlessContext());
    out->display_ = dpy;
    out->context_ = ctx;
    return out;
}

HeadlessContext::~HeadlessContext() {
    if (!display_) return;
    keep_loaded_libraries_under_asan();
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    eglTerminate(display_);
}

}  // namespace mr::gl
