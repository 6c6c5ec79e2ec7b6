// GL helpers private to the targets that draw or compute with OpenGL (mr_render's
// renderer, mr_gpu's compute stages): a shader compiled and a program linked with the
// driver's log as the error, and the driver's strings for reports. Needs a current
// context (gl_context.h or a window's).
#pragma once

#include <metariver/core.h>

#include <epoxy/gl.h>

#include <initializer_list>
#include <string>

namespace mr::gl {

/// A shader of `type` (GL_VERTEX_SHADER, GL_COMPUTE_SHADER, ...) from `sources`, in
/// order; on failure the error's message is the driver's log on one line (the caller
/// says which shader it was).
Result<GLuint> compile_shader(GLenum type, std::initializer_list<const char*> sources);
/// A program of `shaders`, which are deleted (linked or not); on failure the error's
/// message is the driver's log on one line.
Result<GLuint> link_program(std::initializer_list<GLuint> shaders);
/// glGetString(name) of the current context, "?" when the driver gives none.
std::string gl_string(GLenum name);

}  // namespace mr::gl
