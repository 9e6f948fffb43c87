// The GLSL twin of the CPU renderer (compiler/render/camera.cpp + runtime/cpu/tracer.cpp), pasted
// around the scene functions by compiler/glsl/glsl.cpp. Same camera, marching rules (over-relaxed sphere
// tracing, cone tracing, raw-field bisection), tetrahedral normals, materials sanitising,
// Blinn-Phong, hard/soft shadows, AO, mirror/glass bounces (an explicit stack instead of the
// CPU's ray wavefronts: GLSL has no recursion), background, sRGB. Keep the two in step:
// tests/gpu compares the pictures.
//
// It expects, defined before it (compiler/glsl/glsl.cpp writes them from the scene):
//   const int SDF_MAX_STEPS, SDF_MAX_BOUNCES, SDF_SAMPLES, SDF_NUM_LIGHTS;
//   const float SDF_MAX_DIST, SDF_EPSILON, SDF_MIN_WEIGHT, SDF_SAMPLE_WEIGHT;
//   const bool SDF_SHADOWS, SDF_AO, SDF_CONE, SDF_2D, SDF_CLIP, SDF_DEFAULT_LIGHTS, SDF_ORTHO, SDF_RAW;
//   const float SDF_RELAX, SDF_RAW_INV_LIPSCHITZ, SDF_RAW_MAX_STEP;
//   const vec3 SDF_LO, SDF_HI; const vec2 SDF_OFFSETS[SDF_SAMPLES];
//   float map(vec3 p); Material sdf_material(vec3 p); void sdf_settings();
//   and the globals of head.glsl that sdf_settings() assigns.
//
// The text lives in .glsl files that the build embeds (compiler/glsl/embed.cmake):
//   kRendererHead  head.glsl      declarations the scene functions need (before map, ...)
//   kRendererBody  camera.glsl    helpers and the camera               (after sdf_settings)
//                  marching.glsl  the marching rules, one distance value at a time
//                  trace.glsl     normals, materials, sdf_trace's state machine, sdf_render
#pragma once

#include "compiler/glsl/renderer_body.glsl.hpp"
#include "compiler/glsl/renderer_head.glsl.hpp"
