// Placeholder until the GLSL backend lands (issue 4).
#include "compiler/glsl.hpp"
namespace sdfc {
std::string emit_glsl(const Scene& scene, GlslTarget) { throw CompileError(scene.root ? scene.root->loc : Loc{}, "GLSL output is not built yet"); }
}  // namespace sdfc
