#include "runtime/mesh/mesh_file.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "runtime/io/atomic_file.hpp"
#include "runtime/io/image.hpp"
#include "runtime/mesh/mesh_3mf.hpp"

namespace sdfc::mesh {
namespace {

template <typename T>
void put(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // little-endian hosts only (x86-64, arm64)
    s.append(b, sizeof(T));
}

}  // namespace

float srgb_of(float linear) { return linear_to_srgb(std::clamp(linear, 0.0f, 1.0f)); }
uint8_t srgb_byte(float linear) { return static_cast<uint8_t>(std::lround(srgb_of(linear) * 255.0f)); }

namespace {

std::string stl(const Mesh& m) {
    std::string s;
    s.reserve(84 + 50 * m.triangles.size());
    std::string header = "binary STL written by sdfc";
    header.resize(80, ' ');
    s += header;
    put<uint32_t>(s, static_cast<uint32_t>(m.triangles.size()));
    for (const auto& t : m.triangles) {
        const glm::vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
        glm::vec3 n = glm::cross(b - a, c - a);
        const float l = glm::length(n);
        n = l > 0.0f ? n / l : glm::vec3(0.0f);
        for (const glm::vec3& v : {n, a, b, c})
            for (int k = 0; k < 3; ++k) put<float>(s, v[k]);
        put<uint16_t>(s, 0);
    }
    return s;
}

std::string obj(const Mesh& m) {
    std::string s = "# written by sdfc\n";
    const bool colors = m.colors.size() == m.positions.size() && !m.colors.empty();
    for (size_t i = 0; i < m.positions.size(); ++i) {
        const glm::vec3& p = m.positions[i];
        if (colors) {
            const glm::vec3& c = m.colors[i];
            s += fmt::format("v {} {} {} {} {} {}\n", p.x, p.y, p.z, srgb_of(c.x), srgb_of(c.y), srgb_of(c.z));  // the common colour extension
        } else {
            s += fmt::format("v {} {} {}\n", p.x, p.y, p.z);
        }
    }
    for (const auto& t : m.triangles) s += fmt::format("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    return s;
}

std::string ply(const Mesh& m) {
    const bool colors = m.colors.size() == m.positions.size() && !m.colors.empty();
    std::string s = fmt::format("ply\nformat binary_little_endian 1.0\ncomment written by sdfc\nelement vertex {}\n"
                                "property float x\nproperty float y\nproperty float z\n",
                                m.positions.size());
    if (colors) s += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    s += fmt::format("element face {}\nproperty list uchar uint vertex_indices\nend_header\n", m.triangles.size());
    for (size_t i = 0; i < m.positions.size(); ++i) {
        for (int k = 0; k < 3; ++k) put<float>(s, m.positions[i][k]);
        if (colors)
            for (int k = 0; k < 3; ++k) put<uint8_t>(s, srgb_byte(m.colors[i][k]));
    }
    for (const auto& t : m.triangles) {
        put<uint8_t>(s, 3);
        for (uint32_t v : t) put<uint32_t>(s, v);
    }
    return s;
}

}  // namespace

MeshFormat mesh_format(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext == ".stl") return MeshFormat::Stl;
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".ply") return MeshFormat::Ply;
    if (ext == ".3mf") return MeshFormat::ThreeMf;
    return MeshFormat::Unknown;
}

std::string encode_mesh(const Mesh& m, MeshFormat f) {
    switch (f) {
        case MeshFormat::Stl: return stl(m);
        case MeshFormat::Obj: return obj(m);
        case MeshFormat::Ply: return ply(m);
        case MeshFormat::ThreeMf: return encode_3mf(m);
        case MeshFormat::Unknown: break;
    }
    throw std::runtime_error("unknown mesh format");
}

void write_mesh(const std::string& path, const Mesh& m) {
    const MeshFormat f = mesh_format(path);
    if (f == MeshFormat::Unknown)
        throw std::runtime_error(fmt::format("cannot write '{}': unknown mesh format (use .stl, .obj, .ply or .3mf)", path));
    write_file(path, encode_mesh(m, f));
}

}  // namespace sdfc::mesh
