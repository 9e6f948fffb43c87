// The GLSL backend: the scene's programs as GLSL, generated from the same IR and opcode
// table as the VM, with the CPU renderer's camera, tracing and shading.
#pragma once
#include <string>

#include "compiler/bytecode/program.hpp"
#include "compiler/scene/scene.hpp"

namespace sdfc {

enum class GlslTarget {
    Shadertoy,  // mainImage(out vec4, in vec2); iResolution, iTime, iMouse; pastes into shadertoy.com
    Glsl330,    // desktop `#version 330 core` fragment shader with main() and documented uniforms
    Html,       // one self-contained WebGL2 page with an orbit camera and a time slider
    HtmlShader, // the Html page's WebGL2 fragment shader alone (sdfc preview sends it to its page)
};

// `scene` must be built with a symbolic time (InterpretOptions::time = nullopt) so `time`
// becomes iTime. Throws CompileError for settings GLSL cannot express.
// `sample` evaluates the distance program for the raw-field Lipschitz estimate (the
// runtime's sample_batch is the fast one; the result is the same). `uses_time`, if given, is
// set to whether the shader depends on iTime.
std::string emit_glsl(const Scene& scene, GlslTarget target, FieldSampler sample = sample_scalar, bool* uses_time = nullptr);

// The page of `sdfc preview`: the Html page with no shader of its own; it takes each new
// shader (HtmlShader) or script error from the server's /events stream and keeps its view.
std::string html_live_page(const std::string& title);

}  // namespace sdfc
