// Headless GLES 3.0 through EGL (Mesa's surfaceless platform, llvmpipe): a context, one
// full-screen triangle drawn with a given fragment shader into an RGBA8 framebuffer, and the
// pixels read back. Shared by the GPU tests and the conformance suite; needs EGL and GLESv2
// (Debian: libegl-dev libgles-dev, plus libgl1-mesa-dri at run time).
#pragma once
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>

#include "dri.hpp"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

namespace sdfc::gpu_test {

inline const char* kFullScreenVertex = R"(#version 300 es
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
)";

class Gles {
public:
    Gles() = default;
    Gles(const Gles&) = delete;
    Gles& operator=(const Gles&) = delete;

    // Empty string: ready. Otherwise why not.
    std::string init() {
        setenv("LIBGL_ALWAYS_SOFTWARE", "1", 0);  // llvmpipe, also where a GPU exists
        setenv("GALLIUM_DRIVER", "llvmpipe", 0);
        dpy_ = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (dpy_ == EGL_NO_DISPLAY) return "eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA) failed";
        EGLint major = 0, minor = 0;
        if (!eglInitialize(dpy_, &major, &minor)) return "eglInitialize failed (error " + std::to_string(eglGetError()) + ")";
        if (!eglBindAPI(EGL_OPENGL_ES_API)) return "eglBindAPI(EGL_OPENGL_ES_API) failed";
        const EGLint cfg_attr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_NONE};
        EGLConfig cfg = nullptr;
        EGLint n = 0;
        if (!eglChooseConfig(dpy_, cfg_attr, &cfg, 1, &n) || n < 1) {
            const EGLint any[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_NONE};
            if (!eglChooseConfig(dpy_, any, &cfg, 1, &n) || n < 1) return "no EGL config with EGL_OPENGL_ES3_BIT";
        }
        const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0, EGL_NONE};
        ctx_ = eglCreateContext(dpy_, cfg, EGL_NO_CONTEXT, ctx_attr);
        if (ctx_ == EGL_NO_CONTEXT) return "eglCreateContext(GLES 3.0) failed (error " + std::to_string(eglGetError()) + ")";
        if (!eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx_)) return "eglMakeCurrent(surfaceless) failed";
        const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        renderer_ = r ? r : "?";
        glGenFramebuffers(1, &fbo_);
        glGenRenderbuffers(1, &rb_);
        glGenVertexArrays(1, &vao_);
        glBindVertexArray(vao_);
        return "";
    }
    ~Gles() {
        if (dpy_ != EGL_NO_DISPLAY) {
            eglMakeCurrent(dpy_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            if (ctx_ != EGL_NO_CONTEXT) eglDestroyContext(dpy_, ctx_);
            keep_dri_driver_loaded();
            eglTerminate(dpy_);
        }
    }
    const std::string& renderer() const { return renderer_; }

    // Compiles `frag` (with kFullScreenVertex), lets `setup` set its uniforms and textures,
    // draws width x height pixels and fills `rgba` (4 bytes a pixel, row 0 at the bottom, as
    // glReadPixels gives it). Returns "" or what went wrong (the shader log).
    std::string draw(const std::string& frag, int width, int height, std::vector<uint8_t>& rgba,
                     const std::function<void(GLuint program)>& setup = {}) {
        if (width != fb_width_ || height != fb_height_) {
            glBindRenderbuffer(GL_RENDERBUFFER, rb_);
            glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
            glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
            glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_);
            if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) return "the RGBA8 framebuffer is incomplete";
            fb_width_ = width, fb_height_ = height;
        }
        std::string log;
        GLuint vs = compile(GL_VERTEX_SHADER, kFullScreenVertex, log);
        if (!vs) return "vertex shader: " + log;
        GLuint fs = compile(GL_FRAGMENT_SHADER, frag.c_str(), log);
        if (!fs) {
            glDeleteShader(vs);
            return "fragment shader: " + log;
        }
        GLuint prog = glCreateProgram();
        glAttachShader(prog, vs);
        glAttachShader(prog, fs);
        glLinkProgram(prog);
        glDeleteShader(vs);
        glDeleteShader(fs);
        GLint ok = 0;
        glGetProgramiv(prog, GL_LINK_STATUS, &ok);
        if (!ok) {
            char buf[4096] = {};
            glGetProgramInfoLog(prog, sizeof buf, nullptr, buf);
            glDeleteProgram(prog);
            return std::string("link: ") + buf;
        }
        glUseProgram(prog);
        if (setup) setup(prog);
        glViewport(0, 0, width, height);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        rgba.assign(static_cast<size_t>(width) * height * 4, 0);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
        glDeleteProgram(prog);
        if (GLenum e = glGetError(); e != GL_NO_ERROR) return "GL error " + std::to_string(e);
        return "";
    }

private:
    static GLuint compile(GLenum type, const char* src, std::string& log) {
        GLuint s = glCreateShader(type);
        glShaderSource(s, 1, &src, nullptr);
        glCompileShader(s);
        GLint ok = 0;
        glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
        if (!ok) {
            std::vector<char> buf(16384);
            glGetShaderInfoLog(s, static_cast<GLsizei>(buf.size()), nullptr, buf.data());
            log = buf.data();
            glDeleteShader(s);
            return 0;
        }
        return s;
    }
    EGLDisplay dpy_ = EGL_NO_DISPLAY;
    EGLContext ctx_ = EGL_NO_CONTEXT;
    GLuint fbo_ = 0, rb_ = 0, vao_ = 0;
    int fb_width_ = 0, fb_height_ = 0;
    std::string renderer_;
};

}  // namespace sdfc::gpu_test
