// 3MF files through lib3mf: the mesh with a colour per triangle corner (sRGB, as 3MF
// wants), and the reader the tests check files with.
#pragma once
#include <string>

#include "runtime/mesh/mesh.hpp"

namespace sdfc::mesh {

std::string encode_3mf(const Mesh& m);  // throws std::runtime_error
Mesh decode_3mf(const std::string& bytes);  // positions and triangles

}  // namespace sdfc::mesh
