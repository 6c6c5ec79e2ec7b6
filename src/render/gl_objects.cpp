// Shader programs for the renderer (gl_objects.h).
#include "gl_objects.h"

#include "gl_shader.h"
#include "shaders.h"

#include <fmt/format.h>

namespace mr::render {

Result<GLuint> link(const char* vert, const char* frag, const char* what) {
    auto vs = gl::compile_shader(GL_VERTEX_SHADER, {glsl::kCommon, vert});
    if (!vs) return Error{fmt::format("renderer: {} shader does not compile: {}", what, vs.error().message)};
    auto fs = gl::compile_shader(GL_FRAGMENT_SHADER, {glsl::kCommon, frag});
    if (!fs) {
        glDeleteShader(vs.value());
        return Error{fmt::format("renderer: {} shader does not compile: {}", what, fs.error().message)};
    }
    auto p = gl::link_program({vs.value(), fs.value()});
    if (!p) return Error{fmt::format("renderer: {} program does not link: {}", what, p.error().message)};
    return p.value();
}

}  // namespace mr::render
