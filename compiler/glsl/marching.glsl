//! The shader's side of ray set-up: clipping to where surfaces can be and the tile pre-march,
//! with the constants compiler/glsl/glsl.cpp prints from the render plan. The rules they
//! apply are compiler/render/rules.h's, as runtime/cpu/frame.hpp and marcher.cpp apply them.

// Clips [t_min, t_max] to where surfaces can be: the scene's bounding box, or in a scene
// with floor planes the hull of the ray's parts in the box of everything else and under a
// plane. An empty interval gets t_min = inf.
void sdf_clip_ray(vec3 o, vec3 d, inout float t_min, inout float t_max) {
    if (SDF_NUM_PLANES > 0) {
        float a = sdf_inf(), b = -sdf_inf();
        sdf_hull_box(SDF_SOLID_LO, SDF_SOLID_HI, o, d, t_min, t_max, a, b);
        for (int i = 0; i < SDF_NUM_PLANES; ++i) sdf_hull_plane(SDF_PLANES[i], o, d, t_min, t_max, a, b);
        t_min = a;
        t_max = b;
        if (!(t_min <= t_max)) t_min = sdf_inf();
        return;
    }
    if (SDF_CLIP) sdf_clip_box(SDF_LO, SDF_HI, o, d, t_min, t_max);
}

// The tile pre-march: primary rays of a tile (sdf_tile_size pixels square, from the top
// left) start where one march along the tile's central ray, less the cone around the
// tile's rays, ended: the CPU's start, so grazing rays sample where the CPU samples them.
// sdf_trace marches it (SDF_ST_PRE) once per pixel, the first time sdf_start < 0.
vec3 sdf_pre_o, sdf_pre_d;
vec2 sdf_pre_r;  // the cone around the tile's rays: r0 + r1 t
float sdf_pre_t0;  // where the pre-march begins (sdf_premarch_begin)
float sdf_start;

void sdf_setup_premarch(float x, float row, vec2 res) {
    float tile = float(sdf_tile_size(SDF_SAMPLES));
    float x0 = floor(x / tile) * tile, y0 = floor(row / tile) * tile;
    float x1 = min(x0 + tile, res.x), y1 = min(y0 + tile, res.y);
    sdf_tile_cone(sdf_cam, x0, y0, x1, y1, sdf_pre_o, sdf_pre_d, sdf_pre_r);
    sdf_pre_t0 = SDF_CLIP && SDF_NUM_PLANES == 0 ? sdf_premarch_begin(SDF_LO, SDF_HI, sdf_pre_o, sdf_pre_d, sdf_pre_r, SDF_MAX_DIST) : 0.0;
    sdf_start = -1.0;
}
