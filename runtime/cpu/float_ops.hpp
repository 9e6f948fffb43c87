// Small float helpers the CPU tracer's files share (sanitising material and scene values,
// box sizes).
#pragma once
#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace sdfc::cpu {

inline float nonneg(float v) { return v > 0.0f ? (std::isfinite(v) ? v : 1e30f) : 0.0f; }  // NaN -> 0
inline float clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }
inline float max3(const glm::vec3& v) { return std::max(v.x, std::max(v.y, v.z)); }
inline float maxabs3(const glm::vec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

}  // namespace sdfc::cpu
