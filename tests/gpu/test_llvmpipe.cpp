// The GLSL backend against the CPU renderer: every example's Shadertoy-target shader, inside
// a Shadertoy-like wrapper, drawn by Mesa's llvmpipe through headless EGL (surfaceless
// platform, GLES 3.0 context, an FBO, glReadPixels), must match `sdfc render --samples 1` at
// the same size with PSNR >= 40 dB. Without a usable EGL/llvmpipe the test is skipped with a
// warning (CI installs libegl-dev libgles-dev libgl1-mesa-dri).
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>
#include <dlfcn.h>
#include <link.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "gpu_common.hpp"

namespace {

using namespace sdfc;
using namespace sdfc::gpu_test;

constexpr int kWidth = 160, kHeight = 90;
constexpr double kMinPsnr = 40.0;

const char* kVertex = R"(#version 300 es
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
)";

// What shadertoy.com puts around a shader (GLSL ES 3.00).
std::string shadertoy_wrap(const std::string& code) {
    return "#version 300 es\nprecision highp float;\nprecision highp int;\n"
           "uniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\nout vec4 sdf_shadertoy_out;\n" +
           code + "\nvoid main() { mainImage(sdf_shadertoy_out, gl_FragCoord.xy); }\n";
}

// Keeps Mesa's DRI driver (swrast_dri.so, loaded by eglInitialize) in memory after
// eglTerminate unloads it. The driver's globals hold a few small allocations to the end of
// the process; once it is unmapped, LeakSanitizer (.ci/sanitize) sees them as leaks from an
// unknown module, which no suppression can name. Loaded, they stay reachable.
void keep_dri_driver_loaded() {
    std::vector<std::string> drivers;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
            if (info->dlpi_name && std::strstr(info->dlpi_name, "_dri.so"))
                static_cast<std::vector<std::string>*>(out)->push_back(info->dlpi_name);
            return 0;
        },
        &drivers);
    for (const auto& d : drivers) dlopen(d.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);  // no handle kept: it stays
}

class Gles {
public:
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
        glBindRenderbuffer(GL_RENDERBUFFER, rb_);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, kWidth, kHeight);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb_);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) return "the RGBA8 framebuffer is incomplete";
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

    // Compiles and draws `frag` into the FBO; fills `out` (row 0 at the top) or returns the log.
    std::string draw(const std::string& frag, Rgb8& out) {
        std::string log;
        GLuint vs = compile(GL_VERTEX_SHADER, kVertex, log);
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
        glUniform3f(glGetUniformLocation(prog, "iResolution"), kWidth, kHeight, 1.0f);
        glUniform1f(glGetUniformLocation(prog, "iTime"), 0.0f);
        glUniform4f(glGetUniformLocation(prog, "iMouse"), 0.0f, 0.0f, 0.0f, 0.0f);
        glViewport(0, 0, kWidth, kHeight);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        std::vector<uint8_t> rgba(static_cast<size_t>(kWidth) * kHeight * 4);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, kWidth, kHeight, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
        glDeleteProgram(prog);
        if (GLenum e = glGetError(); e != GL_NO_ERROR) return "GL error " + std::to_string(e);
        out = Rgb8{kWidth, kHeight, std::vector<uint8_t>(static_cast<size_t>(kWidth) * kHeight * 3)};
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                for (int c = 0; c < 3; ++c)
                    out.px[(static_cast<size_t>(y) * kWidth + x) * 3 + c] = rgba[(static_cast<size_t>(kHeight - 1 - y) * kWidth + x) * 4 + c];
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
    std::string renderer_;
};

}  // namespace

TEST_CASE("every example drawn by llvmpipe from the Shadertoy GLSL matches the CPU renderer", "[gpu][llvmpipe]") {
    Gles gles;
    const std::string why = gles.init();
    if (!why.empty()) {
        WARN("SKIPPED: no headless GLES 3 through EGL/llvmpipe here: " << why);
        return;
    }
    std::printf("GL_RENDERER: %s\n", gles.renderer().c_str());
    if (gles.renderer().find("llvmpipe") == std::string::npos)
        WARN("the GLES renderer is '" << gles.renderer() << "', not llvmpipe");
    const auto files = examples();
    REQUIRE_FALSE(files.empty());
    double lowest = INFINITY;
    std::string lowest_name;
    const fs::path out = out_dir();
    for (const std::string& path : files) {
        const std::string name = fs::path(path).stem().string();
        INFO("example " << path);
        auto t0 = std::chrono::steady_clock::now();
        const Rgb8 cpu = cpu_render(path, kWidth, kHeight);
        auto t1 = std::chrono::steady_clock::now();
        Rgb8 gpu;
        const std::string err = gles.draw(shadertoy_wrap(glsl_of(path, GlslTarget::Shadertoy)), gpu);
        auto t2 = std::chrono::steady_clock::now();
        REQUIRE(err == "");
        const double p = psnr(cpu, gpu);
        std::printf("  %-28s PSNR %7.2f dB   (cpu %5.0f ms, llvmpipe %6.0f ms)\n", name.c_str(), p,
                    std::chrono::duration<double, std::milli>(t1 - t0).count(), std::chrono::duration<double, std::milli>(t2 - t1).count());
        std::fflush(stdout);
        if (p < lowest) lowest = p, lowest_name = name;
        if (p < kMinPsnr || std::getenv("SDFC_GPU_OUT")) {
            save(cpu, out / (name + ".cpu.png"));
            save(gpu, out / (name + ".llvmpipe.png"));
        }
        CHECK(p >= kMinPsnr);
    }
    std::printf("lowest PSNR: %.2f dB (%s) over %zu examples at %dx%d\n", lowest, lowest_name.c_str(), files.size(), kWidth, kHeight);
}
