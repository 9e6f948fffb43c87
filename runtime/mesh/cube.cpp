#include "runtime/mesh/cube.hpp"

#include <cstddef>
#include <vector>

namespace sdfc::mesh {
namespace {

int find(int* parent, int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
}

// Face f's corners in cyclic order.
std::array<int, 4> face_corners(int f) {
    const int axis = f / 2, u = (axis + 1) % 3, v = (axis + 2) % 3, s = (f & 1) << axis;
    return {s, s | (1 << u), s | (1 << u) | (1 << v), s | (1 << v)};
}

Patches make(uint8_t config, uint8_t flipped) {
    auto inside = [&](int c) { return (config >> c) & 1; };
    auto crosses = [&](int e) {
        const auto c = edge_corners(e);
        return inside(c[0]) != inside(c[1]);
    };
    int parent[12];
    for (int e = 0; e < 12; ++e) parent[e] = e;
    auto link = [&](int a, int b) { parent[find(parent, a)] = find(parent, b); };
    for (int f = 0; f < 6; ++f) {
        const std::array<int, 4> c = face_corners(f), fe = face_edges(f);
        int n = 0;
        for (int i = 0; i < 4; ++i) n += crosses(fe[i]);
        if (n == 2) {
            int a = -1;
            for (int i = 0; i < 4; ++i)
                if (crosses(fe[i])) {
                    if (a < 0) a = fe[i];
                    else link(a, fe[i]);
                }
        } else if (n == 4) {  // ambiguous: corner i lies between edges i - 1 and i
            const bool linked_side = !((flipped >> f) & 1);
            for (int i = 0; i < 4; ++i)
                if (bool(inside(c[i])) == linked_side) link(fe[(i + 3) % 4], fe[i]);
        }
    }
    Patches p;
    int id_of_root[12];
    for (int e = 0; e < 12; ++e) id_of_root[e] = -1;
    for (int e = 0; e < 12; ++e) {
        if (!crosses(e)) {
            p.of_edge[e] = -1;
            continue;
        }
        const int r = find(parent, e);
        if (id_of_root[r] < 0) id_of_root[r] = p.count++;
        p.of_edge[e] = static_cast<int8_t>(id_of_root[r]);
    }
    return p;
}

// Every configuration with every set of flipped faces: 16,384 entries, built at the first
// use (a mesh), a few milliseconds.
struct Table {
    std::vector<Patches> p;
    Table() : p(256 * 64) {
        for (int f = 0; f < 64; ++f)
            for (int c = 0; c < 256; ++c) p[std::size_t(f * 256 + c)] = make(static_cast<uint8_t>(c), static_cast<uint8_t>(f));
    }
};

}  // namespace

std::array<int, 4> face_edges(int f) {
    const std::array<int, 4> c = face_corners(f);
    return {edge_between(c[0], c[1]), edge_between(c[1], c[2]), edge_between(c[2], c[3]), edge_between(c[3], c[0])};
}

const Patches& patches(uint8_t config, uint8_t flipped) {
    static const Table table;
    return table.p[std::size_t(flipped & 63) * 256 + config];
}

}  // namespace sdfc::mesh
