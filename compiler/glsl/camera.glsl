//! The first part of the renderer (after the scene functions; then marching.glsl, trace.glsl):
//! small helpers and the camera, twins of compiler/render/camera.cpp.

// ---------------------------------------------------------------------------------------
// The renderer: a line-by-line twin of sdfc's CPU renderer (runtime/cpu/tracer.cpp).
// ---------------------------------------------------------------------------------------

float sdf_inf() { return uintBitsToFloat(0x7f800000u); }
bool sdf_finite(float v) { return !isnan(v) && !isinf(v); }
bool sdf_finite3(vec3 v) { return sdf_finite(v.x) && sdf_finite(v.y) && sdf_finite(v.z); }
float sdf_max3(vec3 v) { return max(v.x, max(v.y, v.z)); }
float sdf_maxabs3(vec3 v) { return max(abs(v.x), max(abs(v.y), abs(v.z))); }
float sdf_nonneg(float v) { return v > 0.0 ? (sdf_finite(v) ? v : 1e30) : 0.0; }
float sdf_clamp01(float v) { return v > 0.0 ? (v < 1.0 ? v : 1.0) : 0.0; }

// 0, but not a compile-time constant (set from the viewport size in sdf_render): loops that
// call map() start from it so that shader compilers do not unroll them into many copies of
// the scene (the Shadertoy idiom `min(iFrame, 0)`).
int sdf_zero;

// Camera (compiler/render/camera.cpp).
vec3 sdf_eye, sdf_fwd, sdf_right, sdf_up;
float sdf_half_w, sdf_half_h, sdf_inv_w, sdf_inv_h, sdf_foot_base, sdf_foot_slope;

void sdf_setup_camera(vec3 position, vec3 target, vec3 up_in, float fov_in, float ortho_height, vec2 res) {
    float width = max(res.x, 1.0), height = max(res.y, 1.0);
    sdf_eye = sdf_finite3(position) ? position : vec3(0.0, 0.0, 5.0);
    vec3 f = target - sdf_eye;
    sdf_fwd = (sdf_finite3(f) && dot(f, f) > 1e-20) ? normalize(f) : vec3(0.0, 0.0, -1.0);
    vec3 up = (sdf_finite3(up_in) && dot(up_in, up_in) > 1e-20) ? normalize(up_in) : vec3(0.0, 1.0, 0.0);
    vec3 r = cross(sdf_fwd, up);
    if (dot(r, r) < 1e-12) {
        up = abs(sdf_fwd.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0);
        r = cross(sdf_fwd, up);
    }
    sdf_right = normalize(r);
    sdf_up = cross(sdf_right, sdf_fwd);
    float aspect = width / height;
    if (SDF_ORTHO) {
        float h = (sdf_finite(ortho_height) && ortho_height > 0.0) ? ortho_height : 2.0;
        sdf_half_h = 0.5 * h;
        sdf_half_w = sdf_half_h * aspect;
        sdf_foot_base = 0.70710678 * h / height;
        sdf_foot_slope = 0.0;
    } else {
        float fov = sdf_finite(fov_in) ? clamp(fov_in, 1e-3, 179.0) : 45.0;
        sdf_half_h = tan(0.5 * radians(fov));
        sdf_half_w = sdf_half_h * aspect;
        sdf_foot_base = 0.0;
        sdf_foot_slope = 0.70710678 * 2.0 * sdf_half_h / height;
    }
    sdf_inv_w = 1.0 / width;
    sdf_inv_h = 1.0 / height;
}

// The ray through image point (px, py) in pixels, row 0 at the top.
void sdf_camera_ray(float px, float py, out vec3 o, out vec3 d) {
    float u = (2.0 * px * sdf_inv_w - 1.0) * sdf_half_w;
    float v = (1.0 - 2.0 * py * sdf_inv_h) * sdf_half_h;
    if (SDF_ORTHO) {
        o = sdf_eye + u * sdf_right + v * sdf_up;
        d = sdf_fwd;
    } else {
        o = sdf_eye;
        d = normalize(sdf_fwd + u * sdf_right + v * sdf_up);
    }
}

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
