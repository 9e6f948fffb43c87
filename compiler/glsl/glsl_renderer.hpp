// The GLSL renderer, pasted around the scene functions by compiler/glsl/glsl.cpp. Its rules
// (camera rays, over-relaxed sphere tracing, raw-field refinement, soft shadows, normals,
// material clamps, Fresnel, Blinn-Phong, AO, clipping, the tile pre-march, sRGB) are
// compiler/render/rules.h's, the same text the CPU renderer (runtime/cpu/) compiles; what is
// written here is the shader's scheduling: mirror/glass bounces from an explicit stack (GLSL
// has no recursion) and every ray of a sample as one state machine around one map() call.
//
// It expects, defined before it (compiler/glsl/glsl.cpp prints them from the render plan):
//   const int SDF_MAX_STEPS, SDF_MAX_BOUNCES, SDF_SAMPLES, SDF_NUM_LIGHTS, SDF_NUM_PLANES;
//   const float SDF_MAX_DIST, SDF_EPSILON, SDF_MIN_WEIGHT, SDF_SAMPLE_WEIGHT;
//   const bool SDF_SHADOWS, SDF_AO, SDF_CONE, SDF_2D, SDF_CLIP, SDF_DEFAULT_LIGHTS, SDF_ORTHO, SDF_RAW,
//              SDF_PREMARCH;
//   const float SDF_RELAX, SDF_RAW_INV_LIPSCHITZ, SDF_RAW_MAX_STEP;
//   const vec3 SDF_LO, SDF_HI, SDF_SOLID_LO, SDF_SOLID_HI; const vec4 SDF_PLANES[];
//   const vec2 SDF_OFFSETS[SDF_SAMPLES];
//   float map(vec3 p); Material sdf_material(vec3 p); void sdf_settings();
//   and the globals of head.glsl that sdf_settings() assigns.
//
// The text lives in files that the build embeds (compiler/glsl/embed.cmake):
//   kSharedRules   compiler/render/rules.h, turned into GLSL by shared_rules_glsl()
//   kRendererHead  head.glsl      declarations the scene functions need (before map, ...)
//   kRendererBody  camera.glsl    the frame's camera, the interactive orbit (after sdf_settings)
//                  marching.glsl  ray clipping and the tile pre-march with the plan's constants
//                  trace.glsl     materials, sdf_trace's state machine, sdf_render
#pragma once
#include <string>

#include "compiler/glsl/renderer_body.glsl.hpp"
#include "compiler/glsl/renderer_head.glsl.hpp"
#include "compiler/glsl/rules.h.hpp"

namespace sdfc::glsl {

// compiler/render/rules.h as GLSL: its `#ifdef __cplusplus` blocks removed, SDF_FN dropped,
// SDF_INOUT(T) / SDF_OUT(T) as `inout T` / `out T`, SDF_AND / SDF_OR as && / ||.
std::string shared_rules_glsl(std::string_view rules_h);

}  // namespace sdfc::glsl
