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

#include "compiler/ir/ir.hpp"

namespace sdfc {

using Vec3N = std::array<NodeId, 3>;

// Material channels, in this order, in every material value and material program.
enum MatChannel { kMatR, kMatG, kMatB, kMatSpecular, kMatShininess, kMatReflect, kMatTransparency, kMatIor,
                  kMatEmitR, kMatEmitG, kMatEmitB, kMatChannels };
using MaterialN = std::array<NodeId, kMatChannels>;
MaterialN default_material(Graph& g);

#define SDFC_SHAPE_KINDS(X)                                                                     \
    /* primitives */                                                                            \
    X(Sphere) X(Box) X(RoundBox) X(BoxFrame) X(Torus) X(CappedTorus) X(Link) X(Cylinder)       \
    X(RoundCylinder) X(Capsule) X(Cone) X(Plane) X(Ellipsoid) X(Octahedron) X(Pyramid)         \
    X(HexPrism) X(TriPrism) X(Gyroid) X(SchwarzP) X(Field) X(Empty)                            \
    /* CSG: children */                                                                         \
    X(Union) X(Intersection) X(Difference) X(Xor)                                              \
    X(SmoothUnion) X(SmoothIntersection) X(SmoothDifference)                                   \
    X(ChamferUnion) X(ChamferIntersection) X(ChamferDifference)                                \
    X(StairsUnion) X(StairsIntersection) X(StairsDifference)                                   \
    /* params[0] ? children[0] : children[1], a condition on time alone (GLSL's iTime) */      \
    X(Choose)                                                                                  \
    /* modifiers: one child */                                                                  \
    X(Translate) X(Rotate) X(Scale) X(Mirror) X(Repeat) X(RepeatFinite) X(PolarRepeat)         \
    X(Symmetry) X(Elongate) X(Twist) X(Bend) X(Round) X(Onion) X(Displace) X(Material)

enum class ShapeKind {
#define X(n) n,
    SDFC_SHAPE_KINDS(X)
#undef X
};
const char* shape_kind_name(ShapeKind k);

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

struct Shape {
    ShapeKind kind;
    Loc loc;
    // Parameters, flattened in the order documented in compiler/scene/lower.cpp for each kind
    // (vectors as consecutive components). Rotate holds a row-major 3x3 matrix.
    std::vector<NodeId> params;
    std::vector<ShapePtr> children;
    MaterialN material{};  // Material
    FieldFn field;         // Field
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
    bool shadows = true, ao = true;
    std::string aa = "grid";  // "grid" (stratified supersampling) or "cone"
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
    float time = 0.0f;       // the time the scene was built at (when not symbolic)
    std::shared_ptr<void> keepalive;  // what field closures need (the interpreter's state)
};

// Sets the settings of LANGUAGE.md section 8's defaults (camera at [0, 0, 5] looking at
// the origin, fov 45, ambient 0.05, black background) as constants of scene.graph.
void set_default_settings(Scene& scene);

}  // namespace sdfc
