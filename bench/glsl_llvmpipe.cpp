// Times a Shadertoy-target shader (`sdfc glsl SCENE --target shadertoy`) drawn by Mesa's
// llvmpipe (the CPU "GPU") through headless EGL: surfaceless platform, GLES 3.0, an RGBA8
// FBO, one full-screen triangle; each draw is timed to glFinish, after one warm-up draw
// (shader JIT). llvmpipe's thread count is LP_NUM_THREADS (set here from THREADS).
// With SDFC_GL=device the same draws go to the first EGL device (a real GPU driver, e.g.
// NVIDIA's, headless through EGL_EXT_platform_device) and THREADS is ignored.
//   sdfc_llvmpipe SHADER.glsl W H [THREADS=2] [REPEAT=5]
// prints `median_ms=… min_ms=… first_ms=… renderer=…` (first_ms: compile, link and first draw).
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

const char* kVertex = R"(#version 300 es
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
)";

GLuint compile(GLenum type, const char* src) {
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        std::vector<char> buf(16384);
        glGetShaderInfoLog(s, GLsizei(buf.size()), nullptr, buf.data());
        std::fprintf(stderr, "shader: %s\n", buf.data());
        std::exit(1);
    }
    return s;
}

int fail(const char* what) {
    std::fprintf(stderr, "sdfc_llvmpipe: %s (EGL error 0x%x)\n", what, unsigned(eglGetError()));
    return 1;
}

// The first device EGL enumerates: how a GPU driver renders without a window system.
EGLDisplay device_display() {
    auto query = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    if (!query) return eglGetDisplay(EGL_DEFAULT_DISPLAY);
    EGLDeviceEXT devices[8];
    EGLint n = 0;
    if (!query(8, devices, &n) || n < 1) return eglGetDisplay(EGL_DEFAULT_DISPLAY);
    return eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[0], nullptr);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: sdfc_llvmpipe SHADER.glsl W H [THREADS] [REPEAT]\n");
        return 2;
    }
    std::ifstream in(argv[1]);
    std::stringstream ss;
    ss << in.rdbuf();
    const int w = std::atoi(argv[2]), h = std::atoi(argv[3]);
    const int threads = argc > 4 ? std::atoi(argv[4]) : 2;
    const int repeat = argc > 5 ? std::max(1, std::atoi(argv[5])) : 5;
    const char* mode = std::getenv("SDFC_GL");
    const bool device = mode && std::string(mode) == "device";
    EGLDisplay dpy = EGL_NO_DISPLAY;
    if (device) {
        dpy = device_display();
        if (dpy == EGL_NO_DISPLAY) return fail("no EGL device (EGL_EXT_device_enumeration)");
    } else {
        setenv("LIBGL_ALWAYS_SOFTWARE", "1", 1);
        setenv("GALLIUM_DRIVER", "llvmpipe", 1);
        setenv("LP_NUM_THREADS", std::to_string(threads).c_str(), 1);
        dpy = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
        if (dpy == EGL_NO_DISPLAY) return fail("eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA)");
    }
    EGLint major = 0, minor = 0;
    if (!eglInitialize(dpy, &major, &minor)) return fail("eglInitialize");
    if (!eglBindAPI(EGL_OPENGL_ES_API)) return fail("eglBindAPI");
    // Surfaceless: no window configs; ask for pbuffer ones, else any surface type.
    const EGLint pbuf[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_NONE};
    const EGLint any[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_SURFACE_TYPE, EGL_DONT_CARE, EGL_NONE};
    EGLConfig cfg = nullptr;
    EGLint n = 0;
    if ((!eglChooseConfig(dpy, pbuf, &cfg, 1, &n) || n < 1) && (!eglChooseConfig(dpy, any, &cfg, 1, &n) || n < 1))
        return fail("no GLES 3 config");
    const EGLint ctx_attr[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0, EGL_NONE};
    EGLContext ctx = eglCreateContext(dpy, cfg, EGL_NO_CONTEXT, ctx_attr);
    if (ctx == EGL_NO_CONTEXT) return fail("eglCreateContext");
    if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) return fail("eglMakeCurrent");

    GLuint fbo = 0, rb = 0, vao = 0;
    glGenFramebuffers(1, &fbo);
    glGenRenderbuffers(1, &rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb);
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);

    const auto t_first = std::chrono::steady_clock::now();
    const std::string frag = "#version 300 es\nprecision highp float;\nprecision highp int;\n"
                             "uniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\nout vec4 sdf_out;\n" +
                             ss.str() + "\nvoid main() { mainImage(sdf_out, gl_FragCoord.xy); }\n";
    GLuint prog = glCreateProgram();
    glAttachShader(prog, compile(GL_VERTEX_SHADER, kVertex));
    glAttachShader(prog, compile(GL_FRAGMENT_SHADER, frag.c_str()));
    glLinkProgram(prog);
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) return fail("link");
    std::fprintf(stderr, "linked_ms=%.1f\n",
                 std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_first).count());
    glUseProgram(prog);
    glUniform3f(glGetUniformLocation(prog, "iResolution"), float(w), float(h), 1.0f);
    glUniform1f(glGetUniformLocation(prog, "iTime"), 0.0f);
    glUniform4f(glGetUniformLocation(prog, "iMouse"), 0.0f, 0.0f, 0.0f, 0.0f);
    glViewport(0, 0, w, h);
    std::vector<double> ms;
    double first_ms = 0;
    for (int r = 0; r <= repeat; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glFinish();
        const auto t1 = std::chrono::steady_clock::now();
        if (r > 0) ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        else first_ms = std::chrono::duration<double, std::milli>(t1 - t_first).count();  // the first draw compiles
    }
    std::sort(ms.begin(), ms.end());
    const char* rn = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    std::printf("median_ms=%.3f min_ms=%.3f first_ms=%.1f renderer=%s\n", ms[ms.size() / 2], ms.front(), first_ms,
                rn ? rn : "?");
    eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    return 0;
}
