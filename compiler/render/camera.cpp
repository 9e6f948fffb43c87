#include "compiler/render/camera.hpp"

#include <algorithm>
#include <cmath>

namespace sdfc {

Camera::Camera(const ResolvedCamera& cam, int width, int height)
    : c_(rules::sdf_make_camera(cam.position, cam.target, cam.up, cam.fov, cam.orthographic, cam.ortho_height,
                                static_cast<float>(std::max(width, 1)), static_cast<float>(std::max(height, 1)))) {}

Ray Camera::ray(float px, float py) const {
    Ray r;
    rules::sdf_camera_ray(c_, px, py, r.origin, r.dir);
    return r;
}

glm::vec2 Camera::project(const glm::vec3& p) const {
    const glm::vec3 v = p - c_.eye;
    float u = glm::dot(v, c_.right), w = glm::dot(v, c_.up);
    if (!c_.ortho) {
        const float z = glm::dot(v, c_.fwd);
        u /= z, w /= z;
    }
    return {(u / c_.half_w + 1.0f) * 0.5f / c_.inv_w, (1.0f - w / c_.half_h) * 0.5f / c_.inv_h};
}

}  // namespace sdfc
