// Shaders and programs with the driver's log as the error (gl_shader.h).
#include "gl_shader.h"

#include <algorithm>

namespace mr::gl {

namespace {

/// The info log of a shader or a program, newlines made spaces.
std::string info_log(GLuint object, bool program) {
    GLint length = 0;
    program ? glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length) : glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    program ? glGetProgramInfoLog(object, length, nullptr, log.data())
            : glGetShaderInfoLog(object, length, nullptr, log.data());
    log.resize(log.find('\0') == std::string::npos ? log.size() : log.find('\0'));
    std::replace(log.begin(), log.end(), '\n', ' ');
    return log;
}

}  // namespace

Result<GLuint> compile_shader(GLenum type, std::initializer_list<const char*> sources) {
    const GLuint shader = glCreateShader(type);
    glShaderSource(shader, GLsizei(sources.size()), sources.begin(), nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        std::string log = info_log(shader, false);
        glDeleteShader(shader);
        return Error{std::move(log)};
    }
    return shader;
}

Result<GLuint> link_program(std::initializer_list<GLuint> shaders) {
    const GLuint program = glCreateProgram();
    for (const GLuint s : shaders) glAttachShader(program, s);
    glLinkProgram(program);
    for (const GLuint s : shaders) glDeleteShader(s);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        std::string log = info_log(program, true);
        glDeleteProgram(program);
        return Error{std::move(log)};
    }
    return program;
}

std::string gl_string(GLenum name) {
    const auto* s = reinterpret_cast<const char*>(glGetString(name));
    return s ? s : "?";
}

}  // namespace mr::gl
