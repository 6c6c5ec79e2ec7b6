// Shader programs for the renderer (gl_objects.h).
#include "gl_objects.h"

#include "shaders.h"

#include <fmt/format.h>

#include <array>
#include <string>

namespace mr::render {

namespace {

Result<GLuint> compile(GLenum stage, const char* body, const char* what) {
    const GLuint s = glCreateShader(stage);
    const char* sources[] = {glsl::kCommon, body};
    glShaderSource(s, 2, sources, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        std::array<char, 4096> log{};
        glGetShaderInfoLog(s, static_cast<GLsizei>(log.size()), nullptr, log.data());
        glDeleteShader(s);
        std::string msg(log.data());
        std::replace(msg.begin(), msg.end(), '\n', ' ');
        return Error{fmt::format("renderer: {} shader does not compile: {}", what, msg)};
    }
    return s;
}

}  // namespace

Result<GLuint> link(const char* vert, const char* frag, const char* what) {
    auto vs = compile(GL_VERTEX_SHADER, vert, what);
    if (!vs) return vs.error();
    auto fs = compile(GL_FRAGMENT_SHADER, frag, what);
    if (!fs) {
        glDeleteShader(vs.value());
        return fs.error();
    }
    const GLuint p = glCreateProgram();
    glAttachShader(p, vs.value());
    glAttachShader(p, fs.value());
    glLinkProgram(p);
    glDeleteShader(vs.value());
    glDeleteShader(fs.value());
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        std::array<char, 4096> log{};
        glGetProgramInfoLog(p, static_cast<GLsizei>(log.size()), nullptr, log.data());
        glDeleteProgram(p);
        return Error{fmt::format("renderer: {} program does not link: {}", what, log.data())};
    }
    return p;
}

}  // namespace mr::render
