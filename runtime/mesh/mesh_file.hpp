// Mesh files: binary STL, OBJ and binary PLY (both with per-vertex colour when the mesh has
// colours) and 3MF (mesh_3mf.hpp, colour per triangle corner), chosen by the extension. Encoded in memory, then written through
// runtime/io/atomic_file.hpp (checked writes, renamed when complete).
#pragma once
#include <cstdint>
#include <string>

#include "runtime/mesh/mesh.hpp"

namespace sdfc::mesh {

enum class MeshFormat { Stl, Obj, Ply, ThreeMf, Unknown };

// The format an output path's extension names (case-insensitive), or Unknown.
MeshFormat mesh_format(const std::string& path);

std::string encode_mesh(const Mesh& m, MeshFormat f);

// Colours are linear in the scene, sRGB in files (as viewers show them, as the renderer
// encodes its pictures): in [0, 1], and as a byte.
float srgb_of(float linear);
uint8_t srgb_byte(float linear);

// Throws std::runtime_error ("cannot write 'PATH': REASON", or an unknown extension).
void write_mesh(const std::string& path, const Mesh& m);

}  // namespace sdfc::mesh
