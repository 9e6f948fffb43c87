// Drawing a Shadertoy shader on the test GLES context (gles.hpp) into an Rgb8 picture.
#pragma once
#include <string>
#include <vector>

#include "gles.hpp"
#include "gpu_common.hpp"

namespace sdfc::gpu_test {

// What shadertoy.com puts around a shader (GLSL ES 3.00).
inline std::string shadertoy_wrap(const std::string& code) {
    return "#version 300 es\nprecision highp float;\nprecision highp int;\n"
           "uniform vec3 iResolution;\nuniform float iTime;\nuniform vec4 iMouse;\nout vec4 sdf_shadertoy_out;\n" +
           code + "\nvoid main() { mainImage(sdf_shadertoy_out, gl_FragCoord.xy); }\n";
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
    out = Rgb8{width, height, std::vector<uint8_t>(static_cast<size_t>(width) * height * 3)};
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 3; ++c)
                out.px[(static_cast<size_t>(y) * width + x) * 3 + c] = rgba[(static_cast<size_t>(height - 1 - y) * width + x) * 4 + c];
    return "";
}

}  // namespace sdfc::gpu_test
