// Camera: maps a continuous image position (in pixels) to a world-space ray (the rules of
// compiler/render/rules.h, sdf_make_camera and sdf_camera_ray, which the shader runs too).
// Pinhole (vertical field of view) or orthographic (ortho_height world units tall).
// Pixel (x, y) covers [x, x+1) x [y, y+1); its centre is (x + 0.5, y + 0.5); row 0 is the top.
#pragma once
#include <glm/glm.hpp>

#include "compiler/bytecode/compile.hpp"
#include "compiler/render/rules.h"

namespace sdfc {

struct Ray {
    glm::vec3 origin;
    glm::vec3 dir;  // unit length
};

class Camera {
public:
    Camera(const ResolvedCamera& cam, int width, int height);

    // Ray through the image point (px, py), in pixels.
    Ray ray(float px, float py) const;

    // The inverse: the image point (in pixels) where world point p appears; for a
    // perspective camera only meaningful for points in front of it.
    glm::vec2 project(const glm::vec3& p) const;

    // Radius of one pixel's footprint at distance t along a ray: base + slope * t.
    // Used by cone tracing and as the "close enough" tolerance of rays that run out of steps.
    float footprint_base() const { return c_.foot_base; }
    float footprint_slope() const { return c_.foot_slope; }

    bool orthographic() const { return c_.ortho; }
    const glm::vec3& position() const { return c_.eye; }
    const glm::vec3& forward() const { return c_.fwd; }
    const glm::vec3& right() const { return c_.right; }
    const glm::vec3& up() const { return c_.up; }
    const rules::SdfCamera& rule_camera() const { return c_; }

private:
    rules::SdfCamera c_;  // the camera of both renderers (rules.h)
};

}  // namespace sdfc
