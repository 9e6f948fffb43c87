// The GLSL backend: the scene's programs as GLSL, generated from the same IR and opcode
// table as the VM, with the CPU renderer's camera, tracing and shading.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/bytecode/program.hpp"
#include "compiler/scene/scene.hpp"

namespace sdfc {

enum class GlslTarget {
    Shadertoy,  // mainImage(out vec4, in vec2); iResolution, iTime, iMouse; pastes into shadertoy.com
    Glsl330,    // desktop `#version 330 core` fragment shader with main() and documented uniforms
    Html,       // one self-contained WebGL2 page with an orbit camera and a time slider
    HtmlShader, // the Html page's WebGL2 fragment shader alone (sdfc preview sends it to its page)
};

// How the scene's programs become shader code: straight-line GLSL (a statement per
// instruction), or data for the tape interpreter (compiler/glsl/glsl_tape.hpp); Auto picks
// the tape for programs of kTapeThreshold instructions or more.
enum class GlslCode { Auto, Straight, Tape };
inline constexpr size_t kTapeThreshold = 10000;  // distance + shading instructions (the measurements: docs/architecture.md)
// The most uvec4s NVIDIA's GLSL compiler (driver 580) takes in one array constructor: 2,048
// fail with "error C1068: too much data in type constructor" (measured on an H200).
inline constexpr size_t kNvidiaConstArrayTexels = 1024;

struct GlslOptions {
    GlslCode code = GlslCode::Auto;
    // Glsl330 with a tape: the tape in `uniform usampler2D sdf_tape` (RGBA32UI,
    // glsl::kTapeTextureWidth texels a row) instead of a constant array, its words in
    // GlslOutput::tape_words for the host to upload (sdfc glsl --tape-file). NVIDIA's compiler
    // refuses constant arrays over kNvidiaConstArrayTexels.
    bool tape_texture = false;
    // Evaluates the distance program for the raw-field Lipschitz estimate (the runtime's
    // sample_batch is the fast one; the result is the same).
    FieldSampler sample = sample_scalar;
};

struct GlslOutput {
    std::string text;                  // the shader, or the page for Html
    bool uses_time = false;            // the shader depends on iTime
    bool tape = false;                 // the programs are a tape
    size_t tape_texels = 0;            // its uvec4s (Shadertoy and GLSL 330: one constant array of them)
    std::vector<uint32_t> tape_words;  // HtmlShader, or Glsl330 with tape_texture: the words of its sdf_tape texture
    size_t instructions = 0;           // of the distance and shading programs
    int samples = 1, max_steps = 256, max_bounces = 3;  // the knobs' values for the script (Html: their uniforms)
    std::string scene_json;            // what the html page reads besides the shader (time, knobs, parameters)
    Program distance;                  // the distance the shader computes, as bytecode (its `time` reads the time given)
    std::vector<glm::vec3> probes;     // the origin, and the camera's position and target where they are constant
};

// `scene` must be built with a symbolic time (InterpretOptions::time = nullopt) so `time`
// becomes iTime. Throws CompileError for settings GLSL cannot express.
GlslOutput compile_glsl(const Scene& scene, GlslTarget target, const GlslOptions& options = {});

// The text of compile_glsl; `uses_time`, if given, is set to whether the shader depends on iTime.
std::string emit_glsl(const Scene& scene, GlslTarget target, FieldSampler sample = sample_scalar, bool* uses_time = nullptr);

// The page of `sdfc preview`: the Html page with no shader of its own; it takes each new
// shader (HtmlShader) or script error from the server's /events stream and keeps its view.
std::string html_live_page(const std::string& title);

}  // namespace sdfc
