//! The first part of the renderer (after the scene functions; then marching.glsl, trace.glsl):
//! the frame's camera and the interactive orbit. The rules both renderers share (camera rays,
//! marching, shading, sRGB) are in compiler/render/rules.h, pasted before the scene functions.

// 0, but not a compile-time constant (set from the viewport size in sdf_render): loops that
// call map() start from it so that shader compilers do not unroll them into many copies of
// the scene (the Shadertoy idiom `min(iFrame, 0)`).
int sdf_zero;

// This frame's camera (sdf_make_camera in compiler/render/rules.h), set by sdf_render.
SdfCamera sdf_cam;

// Interactive camera: orbit = (yaw, pitch, zoom, on), pan in units of the orbit radius.
// Turns the script's camera around its target (about its up vector); off: the script's view.
void sdf_orbit(inout vec3 pos, inout vec3 target, vec3 up_in, vec4 orbit, vec2 pan) {
    vec3 up = dot(up_in, up_in) > 1e-20 ? normalize(up_in) : vec3(0.0, 1.0, 0.0);
    vec3 off = pos - target;
    float r = length(off);
    if (!(r > 1e-6) || !sdf_finite(r)) { off = vec3(0.0, 0.0, 1.0); r = 1.0; }
    vec3 dir = off / r;
    vec3 h = dir - up * dot(dir, up);
    vec3 e1 = dot(h, h) > 1e-8 ? normalize(h) : normalize(cross(up, abs(up.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 0.0, 1.0)));
    vec3 e2 = cross(up, e1);
    float el = clamp(asin(clamp(dot(dir, up), -1.0, 1.0)) + orbit.y, -1.5, 1.5);
    vec3 nd = cos(el) * (cos(orbit.x) * e1 + sin(orbit.x) * e2) + sin(el) * up;
    float rr = r * max(orbit.z, 1e-4);
    vec3 right = normalize(cross(-nd, up));
    vec3 vup = cross(right, -nd);
    target += (right * pan.x + vup * pan.y) * rr;
    pos = target + nd * rr;
}

// Shadertoy's iMouse (xy: current, zw: where the button went down, z > 0 while down) as an
// orbit: dragging turns the camera; released, the script's camera is used.
vec4 sdf_mouse_orbit(vec4 mouse, vec2 res) {
    if (mouse.z <= 0.0) return vec4(0.0);
    vec2 d = (mouse.xy - abs(mouse.zw)) / max(res, vec2(1.0));
    return vec4(-6.2831853 * d.x, -3.1415927 * d.y, 1.0, 1.0);
}
