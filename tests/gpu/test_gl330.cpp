// The GLSL 330 target drawn by desktop OpenGL 3.3 (core profile) on Mesa llvmpipe, through
// headless EGL: a scene whose tape is over NVIDIA's 1,024-texel limit for constant arrays,
// with the tape in a texture (sdfc glsl --target glsl330 --tape-file), uploaded as the
// shader's header says. Its picture must match the CPU's, PSNR >= 40 dB. Built where EGL
// and libOpenGL are found (Debian: libegl-dev, libopengl-dev, libgl-dev).
#define GL_GLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include <catch2/catch.hpp>

#include "dri.hpp"
#include "gpu_common.hpp"

#include "compiler/glsl/glsl_tape.hpp"

using namespace sdfc;
using namespace sdfc::gpu_test;

namespace {

// Empty when the shader compiled, else its log.
std::string compile(GLuint s, const std::string& src) {
    const char* c = src.c_str();
    glShaderSource(s, 1, &c, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (ok) return "";
    std::vector<char> log(16384);
    glGetShaderInfoLog(s, GLsizei(log.size()), nullptr, log.data());
    return log.data();
}

}  // namespace

TEST_CASE("glsl330 with its tape in a texture draws the CPU's picture on desktop GL 3.3", "[gpu][gl330][tape]") {
    const std::string path = (fs::path(SDFC_SOURCE_DIR) / "tests/gpu/scenes/big/tree-2047.sdf").string();
    const int w = 96, h = 54;
    SourceManager sm;
    InterpretOptions o;
    o.time = std::nullopt;
    Scene s = load_scene(sm, path, o);
    s.render.samples = 1;
    GlslOptions go;
    go.tape_texture = true;
    const GlslOutput g = compile_glsl(s, GlslTarget::Glsl330, go);
    REQUIRE(g.tape_texels > kNvidiaConstArrayTexels);

    setenv("LIBGL_ALWAYS_SOFTWARE", "1", 0);
    setenv("GALLIUM_DRIVER", "llvmpipe", 0);
    EGLDisplay dpy = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, nullptr, nullptr) || !eglBindAPI(EGL_OPENGL_API)) {
        WARN("SKIPPED: no desktop OpenGL through EGL here");
        return;
    }
    const EGLint cfg_attr[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_NONE};
    EGLConfig cfg = nullptr;
    EGLint n = 0;
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3, EGL_CONTEXT_OPENGL_PROFILE_MASK,
                               EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext ctx = EGL_NO_CONTEXT;
    if (eglChooseConfig(dpy, cfg_attr, &cfg, 1, &n) && n > 0) ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        eglTerminate(dpy);
        WARN("SKIPPED: no OpenGL 3.3 core context through EGL here");
        return;
    }
    GLuint fbo = 0, rb = 0, vao = 0, tex = 0;
    glGenFramebuffers(1, &fbo);
    glGenRenderbuffers(1, &rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb);
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    const GLuint vs = glCreateShader(GL_VERTEX_SHADER), fs_ = glCreateShader(GL_FRAGMENT_SHADER);
    CHECK(compile(vs, "#version 330 core\nvoid main() {\n"
                      "    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);\n"
                      "    gl_Position = vec4(p, 0.0, 1.0);\n}\n") == "");
    const std::string log = compile(fs_, g.text);
    INFO(log);
    REQUIRE(log == "");
    const GLuint prog = glCreateProgram();
    glAttachShader(prog, vs);
    glAttachShader(prog, fs_);
    glLinkProgram(prog);
    GLint linked = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &linked);
    REQUIRE(linked);
    glUseProgram(prog);
    // The upload the shader's header asks for: whole rows of kTapeTextureWidth texels.
    const size_t tw = glsl::kTapeTextureWidth, rows = glsl::tape_texture_rows(g.tape_texels);
    const std::vector<uint32_t> data = glsl::tape_texture_words(g.tape_words);
    glGenTextures(1, &tex);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32UI, GLsizei(tw), GLsizei(rows), 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, data.data());
    glUniform1i(glGetUniformLocation(prog, "sdf_tape"), 0);
    glUniform2f(glGetUniformLocation(prog, "iResolution"), float(w), float(h));
    glUniform1f(glGetUniformLocation(prog, "iTime"), 0.0f);
    glUniform4f(glGetUniformLocation(prog, "iMouse"), 0.0f, 0.0f, 0.0f, 0.0f);
    glViewport(0, 0, w, h);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    std::vector<uint8_t> px(size_t(w) * h * 4);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, px.data());
    CHECK(glGetError() == GL_NO_ERROR);
    Rgb8 gpu;
    gpu.width = w;
    gpu.height = h;
    gpu.px.resize(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)  // GL's rows go up
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) gpu.px[(size_t(y) * w + x) * 3 + c] = px[(size_t(h - 1 - y) * w + x) * 4 + c];
    glDeleteTextures(1, &tex);
    glDeleteProgram(prog);
    glDeleteShader(vs);
    glDeleteShader(fs_);
    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, ctx);
    keep_dri_driver_loaded();
    eglTerminate(dpy);
    const Rgb8 cpu = cpu_render(path, w, h);
    const double db = psnr(gpu, cpu);
    INFO("PSNR " << db << " dB");
    CHECK(db >= 40.0);
}
