// The scene: what the interpreter (lang/) hands the compiler. A tree of shapes plus the
// settings statements. Numbers are IR nodes of the Graph the scene was built in, so a
// parameter may depend on `time` (GLSL keeps it symbolic; a CPU frame folds it away).
#pragma once
#include <array>
#include <glm/glm.hpp>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "compiler/base/source.hpp"
#include "compiler/ir/ir.hpp"

namespace sdfc {

using Vec3N = std::array<NodeId, 3>;

// Material channels, in this order, in every material value and material program
// (compiler/scene/materials.def).
enum MatChannel {
#define SDFC_MATERIAL(ch, ...) kMat##ch,
#include "compiler/scene/materials.def"
#undef SDFC_MATERIAL
    kMatChannels
};
enum class MatClamp { NonNeg, Unit, Shininess, Ior };
struct MatChannelInfo {
    const char* output;  // the shading program's output
    const char* glsl;    // a GLSL local holding it
    float def;
    MatClamp clamp;
    const char* param;   // material()'s parameter
    int component;       // of that parameter (0, 1, 2 for a 3-vector)
};
inline constexpr MatChannelInfo kMatChannelInfo[kMatChannels] = {
#define SDFC_MATERIAL(ch, output, glsl, def, clamp, param, component) {output, glsl, def, MatClamp::clamp, #param, component},
#include "compiler/scene/materials.def"
#undef SDFC_MATERIAL
};
using MaterialN = std::array<NodeId, kMatChannels>;
MaterialN default_material(Graph& g);

// Shape kinds, families and parameter slots, from the one table (compiler/scene/shapes.def).
enum class ShapeKind {
#define SDFC_SHAPE(kind, ...) kind,
#define SDFC_INNER_SHAPE(kind, ...) kind,
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
};
enum class ShapeFamily { Primitive, Csg, Modifier };
const char* shape_kind_name(ShapeKind k);
ShapeFamily shape_family(ShapeKind k);
size_t shape_slots(ShapeKind k);  // the size of Shape::params

// Where each parameter sits in Shape::params: SphereP::r, RoundBoxP::size (3 slots, then
// RoundBoxP::r), kSlots in all.
#define SDFC_SLOTS_Num(n) n,
#define SDFC_SLOTS_Bool(n) n,
#define SDFC_SLOTS_Vec3(n) n, n##_y_, n##_z_,
#define SDFC_SLOTS_NumOrVec3(n) n, n##_y_, n##_z_,
#define SDFC_SLOTS_NumOrVec2(n) n, n##_y_,
#define SDFC_SLOTS_Mat3(n) n, n##_01_, n##_02_, n##_10_, n##_11_, n##_12_, n##_20_, n##_21_, n##_22_,
#define SDFC_P(name, type, ...) SDFC_SLOTS_##type(name)
#define SDFC_ARG(...)
#define SDFC_SLOT(name, type) SDFC_SLOTS_##type(name)
#define SDFC_SHAPE(kind, name, family, build, params) struct kind##P { enum : size_t { params kSlots }; };
#define SDFC_INNER_SHAPE(kind, family, params) struct kind##P { enum : size_t { params kSlots }; };
#include "compiler/scene/shapes.def"
#undef SDFC_SHAPE
#undef SDFC_INNER_SHAPE
#undef SDFC_P
#undef SDFC_ARG
#undef SDFC_SLOT
#undef SDFC_SLOTS_Num
#undef SDFC_SLOTS_Bool
#undef SDFC_SLOTS_Vec3
#undef SDFC_SLOTS_NumOrVec3
#undef SDFC_SLOTS_NumOrVec2
#undef SDFC_SLOTS_Mat3

// Axis-aligned bounds of the scene's surface (infinite components for unbounded scenes).
struct Bounds {
    glm::vec3 lo{-1e30f}, hi{1e30f};
    bool finite() const { return lo.x > -1e29f && lo.y > -1e29f && lo.z > -1e29f && hi.x < 1e29f && hi.y < 1e29f && hi.z < 1e29f; }
};

struct Shape;
using ShapePtr = std::shared_ptr<const Shape>;

// A custom field's body, evaluated by the interpreter on a symbolic point. Returns the raw
// distance node (the compiler divides by `bound`).
using FieldFn = std::function<NodeId(Graph&, const Vec3N& p)>;
// The same body read as a colour, [r, g, b] at the point (`color(field (p) -> ...)`).
using ColorFn = std::function<Vec3N(Graph&, const Vec3N& p)>;

struct Shape {
    ShapeKind kind;
    Loc loc;
    // Parameters, flattened in the order of the kind's row in compiler/scene/shapes.def
    // (vectors as consecutive components; name them as SphereP::r). Rotate holds a row-major
    // 3x3 matrix.
    std::vector<NodeId> params;
    std::vector<ShapePtr> children;
    MaterialN material{};  // Material
    FieldFn field;         // Field
    ColorFn field_rgb;     // Field: its body as a colour
    ColorFn color_at;      // Material: when set, the colour at each point (local coordinates)
    float bound = 1.0f;    // Field: the user's Lipschitz bound
    int depth = 1;         // height of this subtree (bounded so lowering cannot overflow the stack)
    size_t tree_size = 1;  // shapes lowering visits here: this one and its subtree, a shared child at each use
    bool iterations = false;  // Union: a `for` statement's iterations (see csg in lang/builtins.cpp)
};

struct CameraSettings {
    Loc loc;
    Vec3N position, target, up;
    NodeId fov;
    bool orthographic = false;
    NodeId ortho_height;
};

struct LightSettings {
    Loc loc;
    bool directional = false;
    Vec3N position;   // point light
    Vec3N direction;  // directional: the direction the light travels
    Vec3N color;
    NodeId intensity;
    NodeId radius;
};

struct RenderSettings {
    Loc loc;
    int width = 640, height = 480, samples = 1, max_steps = 256, max_bounces = 3;
    float max_distance = 100.0f, epsilon = 1e-4f;
    bool max_distance_set = false;  // by the script or a flag: else the plan fits it to the scene
    bool shadows = true, ao = true;
    std::string aa = "grid";  // "grid" (stratified supersampling) or "cone"
    float exposure = 1.0f;          // the picture's radiance is multiplied by it, then
    std::string tonemap = "none";   // mapped: "none" (clipped at 1), "reinhard" or "aces"
};

// A script's `let name = param(value, min, max, step)`: a number the html page turns with a
// slider (a uniform, sdf_param[index]); the CPU and Shadertoy take its value (-D sets it).
struct SceneParam {
    std::string name;
    float value = 0.0f, min = 0.0f, max = 1.0f, step = 0.001f;
    Loc loc;
};

struct Scene {
    std::shared_ptr<Graph> graph;  // owns every NodeId below
    ShapePtr root;                 // union of the top-level statements (Empty if none)
    CameraSettings camera;
    std::vector<LightSettings> lights;  // empty: the default lights
    Vec3N ambient, background;
    RenderSettings render;
    bool is_2d = false;      // a 2D .vm model (Prospero image)
    bool raw_field = false;  // a .vm model: root is a Field, no Lipschitz claim
    bool reads_time = false;  // the script reads `time` (its bounds may move: no framed default camera)
    float time = 0.0f;       // the time the scene was built at (when not symbolic)
    std::shared_ptr<void> keepalive;  // what field closures need (the interpreter's state)
    // What the script does that is legal but likely not meant (an intersection of one
    // shape, an empty difference, an alpha that is ignored): the commands print them.
    std::vector<Diagnostic> warnings;
    // The params, when they stay symbolic (GLSL: InterpretOptions::time is nullopt), in
    // the order of their Param nodes' k.
    std::vector<SceneParam> params;
};

// Sets the settings of LANGUAGE.md section 8's defaults (camera at [0, 0, 5] looking at
// the origin, fov 45, ambient 0.05, black background) as constants of scene.graph.
void set_default_settings(Scene& scene);

}  // namespace sdfc
