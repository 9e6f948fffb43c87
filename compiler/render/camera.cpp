#include "compiler/render/camera.hpp"

#include <algorithm>
#include <cmath>

namespace sdfc {

namespace {
bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
}  // namespace

Camera::Camera(const ResolvedCamera& cam, int width, int height) {
    width = std::max(width, 1);
    height = std::max(height, 1);
    pos_ = finite3(cam.position) ? cam.position : glm::vec3(0, 0, 5);
    glm::vec3 f = cam.target - pos_;
    // Degenerate inputs (target == position, up parallel to the view) get sane fallbacks
    // rather than NaN rays.
    fwd_ = (finite3(f) && glm::dot(f, f) > 1e-20f) ? glm::normalize(f) : glm::vec3(0, 0, -1);
    glm::vec3 up = finite3(cam.up) && glm::dot(cam.up, cam.up) > 1e-20f ? glm::normalize(cam.up) : glm::vec3(0, 1, 0);
    glm::vec3 r = glm::cross(fwd_, up);
    if (glm::dot(r, r) < 1e-12f) {
        up = std::fabs(fwd_.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, 1);
        r = glm::cross(fwd_, up);
    }
    right_ = glm::normalize(r);
    up_ = glm::cross(right_, fwd_);

    const float aspect = static_cast<float>(width) / static_cast<float>(height);
    ortho_ = cam.orthographic;
    if (ortho_) {
        float h = std::isfinite(cam.ortho_height) && cam.ortho_height > 0 ? cam.ortho_height : 2.0f;
        half_h_ = 0.5f * h;
        half_w_ = half_h_ * aspect;
        // Footprint: radius of the disc circumscribing one pixel (0.5 * sqrt(2) pixels).
        foot_base_ = 0.70710678f * h / static_cast<float>(height);
        foot_slope_ = 0.0f;
    } else {
        float fov = std::isfinite(cam.fov) ? std::clamp(cam.fov, 1e-3f, 179.0f) : 45.0f;
        half_h_ = std::tan(0.5f * glm::radians(fov));
        half_w_ = half_h_ * aspect;
        foot_base_ = 0.0f;
        foot_slope_ = 0.70710678f * 2.0f * half_h_ / static_cast<float>(height);
    }
    inv_w_ = 1.0f / static_cast<float>(width);
    inv_h_ = 1.0f / static_cast<float>(height);
}

Ray Camera::ray(float px, float py) const {
    const float u = (2.0f * px * inv_w_ - 1.0f) * half_w_;  // right
    const float v = (1.0f - 2.0f * py * inv_h_) * half_h_;  // up (row 0 at the top)
    if (ortho_) return {pos_ + u * right_ + v * up_, fwd_};
    return {pos_, glm::normalize(fwd_ + u * right_ + v * up_)};
}

glm::vec2 Camera::project(const glm::vec3& p) const {
    const glm::vec3 v = p - pos_;
    float u = glm::dot(v, right_), w = glm::dot(v, up_);
    if (!ortho_) {
        const float z = glm::dot(v, fwd_);
        u /= z, w /= z;
    }
    return {(u / half_w_ + 1.0f) * 0.5f / inv_w_, (1.0f - w / half_h_) * 0.5f / inv_h_};
}

}  // namespace sdfc
