// Drawing a Shadertoy shader on the test GLES context (gles.hpp) into an Rgb8 picture.
#pragma once
#include <string>
#include <vector>

#include "compiler/glsl/glsl_tape.hpp"
#include "gles.hpp"
#include "gpu_common.hpp"

namespace sdfc::gpu_test {

// What shadertoy.com puts around a shader (GLSL ES 3.00).
inline std::string shadertoy_wrap(const std::string& code) {
    return "#version 300 es\nprecision highp float;\nprecision highp int;\n"
           "uniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\nout vec4 sdf_shadertoy_out;\n" +
           code + "\nvoid main() { mainImage(sdf_shadertoy_out, gl_FragCoord.xy); }\n";
}

// GL's RGBA rows (row 0 at the bottom) as RGB rows from the top.
inline Rgb8 rgb_top_down(const std::vector<uint8_t>& rgba, int width, int height) {
    Rgb8 out{width, height, std::vector<uint8_t>(static_cast<size_t>(width) * height * 3)};
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                out.px[(static_cast<size_t>(y) * width + x) * 3 + c] = rgba[(static_cast<size_t>(height - 1 - y) * width + x) * 4 + c];
    return out;
}

// Draws `frag` with Shadertoy's uniforms at width x height (time 0, mouse up); fills `out`
// (row 0 at the top). Returns the compile or link log on failure, else "".
inline std::string draw_shadertoy(Gles& gles, const std::string& frag, int width, int height, Rgb8& out) {
    std::vector<uint8_t> rgba;
    const std::string err = gles.draw(frag, width, height, rgba, [&](GLuint prog) {
        glUniform3f(glGetUniformLocation(prog, "iResolution"), static_cast<float>(width), static_cast<float>(height), 1.0f);
        glUniform1f(glGetUniformLocation(prog, "iTime"), 0.0f);
        glUniform4f(glGetUniformLocation(prog, "iMouse"), 0.0f, 0.0f, 0.0f, 0.0f);
    });
    if (!err.empty()) return err;
    out = rgb_top_down(rgba, width, height);
    return "";
}

// Draws the html page's shader (GlslTarget::HtmlShader) as the page does (page.js): its tape,
// if it has one, as the RGBA32UI texture sdf_tape on unit 0; each of the script's samples
// (or `samples`) in a pass of its own (pass 1), summed in an RGBA16F texture by blending;
// then pass 2 shows the sum. The script's camera (no orbit), time 0.
inline std::string draw_html_shader(Gles& gles, const GlslOutput& shader, int width, int height, Rgb8& out, int samples = 0) {
    std::vector<uint8_t> rgba;
    GLuint tex = 0, sum = 0, sum_fbo = 0;
    std::string fail;
    const std::string err = gles.draw(shader.text, width, height, rgba, [&](GLuint prog) {
        auto u = [&](const char* n) { return glGetUniformLocation(prog, n); };
        glUniform3f(u("iResolution"), static_cast<float>(width), static_cast<float>(height), 1.0f);
        glUniform1f(u("iTime"), 0.0f);
        glUniform4f(u("iMouse"), 0.0f, 0.0f, 0.0f, 0.0f);
        glUniform4f(u("uOrbit"), 0.0f, 0.0f, 1.0f, 0.0f);
        glUniform2f(u("uPan"), 0.0f, 0.0f);
        glUniform1i(u("uSamples"), samples > 0 ? samples : shader.samples);
        glUniform1i(u("uMaxSteps"), shader.max_steps);
        glUniform1i(u("uMaxBounces"), shader.max_bounces);
        if (!shader.tape_words.empty()) {
            const size_t w = glsl::kTapeTextureWidth, rows = glsl::tape_texture_rows(shader.tape_words.size() / 4);
            const std::vector<uint32_t> data = glsl::tape_texture_words(shader.tape_words);
            glGenTextures(1, &tex);
            glActiveTexture(GL_TEXTURE0);
            glBindTexture(GL_TEXTURE_2D, tex);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
            glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
            glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
            glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32UI, GLsizei(w), GLsizei(rows), 0, GL_RGBA_INTEGER, GL_UNSIGNED_INT, data.data());
            glUniform1i(u("sdf_tape"), 0);
        }
        GLint target = 0;
        glGetIntegerv(GL_FRAMEBUFFER_BINDING, &target);
        glGenTextures(1, &sum);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, sum);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, width, height, 0, GL_RGBA, GL_HALF_FLOAT, nullptr);
        glBindTexture(GL_TEXTURE_2D, 0);
        glGenFramebuffers(1, &sum_fbo);
        glBindFramebuffer(GL_FRAMEBUFFER, sum_fbo);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, sum, 0);
        if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) fail = "the RGBA16F sum is not renderable";
        glViewport(0, 0, width, height);
        glClearColor(0, 0, 0, 0);
        glClear(GL_COLOR_BUFFER_BIT);
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glUniform1i(u("uPass"), 1);
        for (int s = 0; s < (samples > 0 ? samples : shader.samples); ++s) {
            glUniform1i(u("uSample"), s);
            glDrawArrays(GL_TRIANGLES, 0, 3);
        }
        glDisable(GL_BLEND);
        glBindFramebuffer(GL_FRAMEBUFFER, GLuint(target));
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, sum);
        glUniform1i(u("uSum"), 1);
        glUniform1i(u("uQuick"), 1);
        glUniform1i(u("uPass"), 2);  // gles.draw draws it
    });
    if (tex) glDeleteTextures(1, &tex);
    if (sum) glDeleteTextures(1, &sum);
    if (sum_fbo) glDeleteFramebuffers(1, &sum_fbo);
    if (!err.empty()) return err;
    if (!fail.empty()) return fail;
    out = rgb_top_down(rgba, width, height);
    return "";
}

}  // namespace sdfc::gpu_test
