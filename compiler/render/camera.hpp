// Camera: maps a continuous image position (in pixels) to a world-space ray.
// Pinhole (vertical field of view) or orthographic (ortho_height world units tall).
// Pixel (x, y) covers [x, x+1) x [y, y+1); its centre is (x + 0.5, y + 0.5); row 0 is the top.
#pragma once
#include <glm/glm.hpp>

#include "compiler/bytecode/compile.hpp"

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
    float footprint_base() const { return foot_base_; }
    float footprint_slope() const { return foot_slope_; }

    bool orthographic() const { return ortho_; }
    const glm::vec3& position() const { return pos_; }
    const glm::vec3& forward() const { return fwd_; }
    const glm::vec3& right() const { return right_; }
    const glm::vec3& up() const { return up_; }

private:
    glm::vec3 pos_, fwd_, right_, up_;
    float half_w_ = 1, half_h_ = 1;  // perspective: tan-space half extents; ortho: world half extents
    float inv_w_ = 1, inv_h_ = 1;
    float foot_base_ = 0, foot_slope_ = 0;
    bool ortho_ = false;
};

}  // namespace sdfc
