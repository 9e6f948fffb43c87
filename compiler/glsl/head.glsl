//! The renderer's declarations, pasted by compiler/glsl/glsl.cpp after the render settings
//! (SDF_NUM_LIGHTS, ...) and before the scene functions, which return a Material and assign
//! these globals in sdf_settings(). Lines starting //! are notes for this file, not part of the
//! shader (compiler/glsl/embed.cmake drops them).
// The 11 material channels of a surface point.
struct Material {
    vec3 color;
    float specular;
    float shininess;
    float reflectance;   // mirror part, 0..1
    float transparency;  // glass part, 0..1
    float ior;
    vec3 emission;
};

struct SdfLight {
    bool directional;
    vec3 position;   // point lights
    vec3 direction;  // directional lights: where the light travels
    vec3 color;
    float intensity;
    float radius;    // > 0: soft shadows
};

// Scene settings, assigned by sdf_settings() (they may depend on the time).
float sdf_time;
vec3 sdf_cam_position, sdf_cam_target, sdf_cam_up;
float sdf_cam_fov, sdf_cam_ortho_height;
SdfLight sdf_lights[SDF_NUM_LIGHTS];
vec3 sdf_ambient, sdf_background;
