// RaySet: a batch of rays (or hit points) in structure-of-arrays form, the unit of work the
// tracer's stages pass each other (primary rays -> march -> hits -> shade -> next bounce).
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace sdfc::cpu {

// For a hit set, `o` is the hit point and `t0` the path length from the eye to it.
struct RaySet {
    std::vector<float> ox, oy, oz, dx, dy, dz, tmin, tmax, t0, wr, wg, wb;
    std::vector<uint32_t> prim;  // primary sample index within the tile
    std::vector<uint8_t> inside;
    size_t size() const { return n_; }
    void clear() { n_ = 0; }
    // Arrays are only grown, never shrunk: pushing is a bounds check and twelve stores.
    void push(const glm::vec3& o, const glm::vec3& d, float t_min, float t_max, float path, const glm::vec3& w, uint32_t p,
              bool in) {
        if (n_ == ox.size()) grow();
        const size_t i = n_++;
        ox[i] = o.x, oy[i] = o.y, oz[i] = o.z;
        dx[i] = d.x, dy[i] = d.y, dz[i] = d.z;
        tmin[i] = t_min, tmax[i] = t_max, t0[i] = path;
        wr[i] = w.x, wg[i] = w.y, wb[i] = w.z;
        prim[i] = p;
        inside[i] = in ? 1 : 0;
    }
    glm::vec3 o(size_t i) const { return {ox[i], oy[i], oz[i]}; }
    glm::vec3 d(size_t i) const { return {dx[i], dy[i], dz[i]}; }
    glm::vec3 w(size_t i) const { return {wr[i], wg[i], wb[i]}; }

private:
    size_t n_ = 0;
    void grow() {
        const size_t cap = std::max<size_t>(256, ox.size() * 2);
        for (auto* v : {&ox, &oy, &oz, &dx, &dy, &dz, &tmin, &tmax, &t0, &wr, &wg, &wb}) v->resize(cap);
        prim.resize(cap);
        inside.resize(cap);
    }
};

}  // namespace sdfc::cpu
