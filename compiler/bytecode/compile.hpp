// The compiler's front door: Scene (shape tree + settings) -> CompiledScene (immutable
// programs + settings resolved to numbers for the CPU renderer).
//
//   Scene --lower (compiler/scene/lower.cpp)--> IR Graph --codegen (compiler/bytecode/codegen.cpp)--> Program
#pragma once
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "compiler/bytecode/program.hpp"
#include "compiler/scene/scene.hpp"

namespace sdfc {

struct ResolvedCamera {
    glm::vec3 position{0, 0, 5}, target{0, 0, 0}, up{0, 1, 0};
    float fov = 45.0f;  // vertical, degrees
    bool orthographic = false;
    float ortho_height = 2.0f;
};

struct ResolvedLight {
    bool directional = false;
    glm::vec3 position{0}, direction{0, -1, 0};  // direction: where the light travels (normalised)
    glm::vec3 color{1};
    float intensity = 1.0f;
    float radius = 0.0f;
};

// Where the scene's surfaces can be (compiler/scene/lower.hpp shape_bounds, clip_regions):
// `bounds`; when that is infinite because of floor planes, every surface lies in
// solid_bounds (possibly empty) or in one of the half-spaces n.p <= w (unit n).
struct SceneBounds {
    Bounds bounds;
    Bounds solid_bounds;
    std::vector<glm::vec4> half_spaces;
};
SceneBounds scene_bounds(const Scene& scene);

struct CompiledScene {
    Program distance;  // outputs: "d", a 1-Lipschitz bound of the distance
    Program shading;   // outputs: "d", then the kMatChannels material channels
    ResolvedCamera camera;
    std::vector<ResolvedLight> lights;  // the script's (none: the render plan's default rig)
    glm::vec3 ambient{0.05f}, background{0.0f};
    RenderSettings render;
    Bounds bounds;
    // When `bounds` is infinite because of floor planes (clip_regions, compiler/scene/lower.hpp):
    // every surface lies in solid_bounds (possibly empty) or in one of these half-spaces
    // n.p <= w (unit n). Empty otherwise.
    Bounds solid_bounds;
    std::vector<glm::vec4> half_spaces;
    // The scene without its floor planes, when they make the bounds infinite and the rest's
    // bounds are unknown (a custom field): the mesher finds its box by the intervals.
    // Empty (no outputs) otherwise.
    Program solid;
    bool is_2d = false;
    bool raw_field = false;
    float time = 0.0f;
};

// What is wrong with a camera (not finite, too far, position == target, up zero or along
// the view), or "" when nothing is; compile_scene and the command line's camera flags.
std::string camera_problem(const ResolvedCamera& cam);

// Whether the box [lo, hi] lies wholly outside a perspective camera's view (every corner
// beyond one side of its pyramid) for a picture of that aspect (width / height).
bool out_of_view(const ResolvedCamera& cam, const glm::vec3& lo, const glm::vec3& hi, float aspect);

// Throws CompileError (at the setting's location) if a setting is not a constant.
CompiledScene compile_scene(const Scene& scene);

// The two IR roots compile_scene turns into programs (also used by the GLSL emitter).
struct LoweredScene {
    NodeId distance;
    NodeId shading_distance;
    MaterialN material;
};
LoweredScene lower_scene(Graph& g, const Scene& scene);

}  // namespace sdfc
