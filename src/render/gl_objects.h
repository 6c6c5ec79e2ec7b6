// Small OpenGL helpers of the renderer (renderer.cpp): shader programs from the GLSL of
// shaders.h, a buffer refilled whole each frame, an offscreen colour + depth target.
#pragma once

#include <metariver/render.h>

#include <epoxy/gl.h>

#include <algorithm>
#include <cstddef>

namespace mr::render {

/// A program from a vertex and a fragment shader body (each after glsl::kCommon);
/// errors name `what` and carry the driver's log on one line.
Result<GLuint> link(const char* vert, const char* frag, const char* what);

/// A GL buffer refilled whole each time: created once; orphaned with glBufferData
/// before each refill (the driver hands out fresh storage instead of waiting for draws
/// still reading the old one) and grown by 1.5x when the data outgrows it.
struct DynamicBuffer {
    GLuint id = 0;
    size_t capacity = 0;
    size_t size = 0;

    void upload(const void* data, size_t bytes, RenderStats& stats) {
        if (bytes > capacity) {
            capacity = std::max({bytes, capacity + capacity / 2, size_t{4096}});
            ++stats.buffer_reallocations;
        }
        glNamedBufferData(id, static_cast<GLsizeiptr>(capacity), nullptr, GL_DYNAMIC_DRAW);
        if (bytes) glNamedBufferSubData(id, 0, static_cast<GLsizeiptr>(bytes), data);
        size = bytes;
        stats.bytes_uploaded += bytes;
        stats.last_upload_bytes += bytes;
    }
};

/// A framebuffer with a colour texture and a depth texture, re-specified on resize.
struct Target {
    GLuint fbo = 0, color = 0, depth = 0;
    int width = 0, height = 0;

    void resize(int w, int h) {
        if (w == width && h == height) return;
        width = w;
        height = h;
        glBindTexture(GL_TEXTURE_2D, color);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        glBindTexture(GL_TEXTURE_2D, depth);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, w, h, 0, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
        glBindTexture(GL_TEXTURE_2D, 0);
        glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, color, 0);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth, 0);
    }
};

}  // namespace mr::render
