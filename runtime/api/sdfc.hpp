// sdfc's public C++ API, installed as <sdfc/sdfc.hpp> (find_package(sdfc): sdfc::sdfc, or
// pkg-config sdfc). Compile a script (a file or a string) to a scene; its errors and warnings
// come back as values; then ask the scene for distances, a picture, GLSL or a mesh. A Scene
// is immutable and cheap to copy (shared); its methods may be called from several threads.
// Nothing here needs another header of sdfc's or of its dependencies.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#if defined(SDFC_BUILDING_API)
#define SDFC_API __attribute__((visibility("default")))
#else
#define SDFC_API
#endif

namespace sdfc::api {

struct Diagnostic {
    std::string file;          // the script's path ("<string>" or the name given for text)
    int line = 0, column = 0;  // 1-based; 0 when not known
    std::string severity;      // "error" or "warning"
    std::string message;
    std::string text;  // as the sdfc command prints it: path:line:col: error: message, the line, a caret
};

// Thrown by a Scene that did not compile (its diagnostics), or for an argument out of range.
class SDFC_API Error : public std::runtime_error {
public:
    explicit Error(const std::string& what, std::vector<Diagnostic> diagnostics = {});
    const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

private:
    std::vector<Diagnostic> diagnostics_;
};

struct Options {
    float time = 0.0f;  // the script's `time` (GLSL keeps it a uniform)
    // `-D NAME=VALUE`: the script's top-level `let NAME` takes VALUE (an expression).
    std::vector<std::pair<std::string, std::string>> defines;
};

struct SDFC_API Image {
    int width = 0, height = 0;
    std::vector<float> rgb;    // linear RGB, 3 floats a pixel, row 0 at the top
    std::vector<float> alpha;  // coverage, a float a pixel (RenderSettings::alpha; else empty);
                               // rgb is then premultiplied by it (the background left out)
    // The picture as 8-bit sRGB, 3 bytes a pixel (clipped to [0, 1], encoded, rounded; with
    // alpha, 4: the colour straight, divided by alpha, as PNG holds it).
    std::vector<std::uint8_t> srgb8() const;
};

struct RenderSettings {
    int width = 0, height = 0, samples = 0;  // 0: the script's render(...) (else 640 x 480, 1)
    int threads = 0;                         // 0: every hardware thread
    bool alpha = false;                      // coverage in Image::alpha
};

struct MeshSettings {
    int resolution = 256;   // cells along the longest side of the box
    float simplify = 0.0f;  // above 0: fewer triangles, all within this distance of the surface
    bool colors = false;    // per-vertex colours from the materials
    // The box meshed: lo x, y, z then hi x, y, z; all zero: found from the scene.
    std::array<float, 6> bounds{};
};

struct Mesh {
    std::vector<std::array<float, 3>> positions;
    std::vector<std::array<float, 3>> colors;  // empty unless MeshSettings::colors
    std::vector<std::array<std::uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

class SDFC_API Scene {
public:
    Scene();  // compiled from nothing: not ok()
    bool ok() const;
    // Errors (when not ok) and warnings, in the order the compiler found them.
    const std::vector<Diagnostic>& diagnostics() const;

    // The signed distance at `n` points (x[i], y[i], z[i]) into out[i].
    void distances(const float* x, const float* y, const float* z, float* out, std::size_t n) const;
    float distance(float x, float y, float z) const;
    // The picture `sdfc render` makes (camera, lights and settings of the script).
    Image render(const RenderSettings& settings = {}) const;
    // "shadertoy", "glsl330" or "html" (the page): what `sdfc glsl --target` writes. The
    // script is read again (a file from disk) with `time` left to the shader.
    std::string glsl(const std::string& target = "shadertoy") const;
    // A closed, oriented mesh of the solid (dual contouring), as `sdfc mesh` makes it.
    Mesh mesh(const MeshSettings& settings = {}) const;

    struct Impl;

private:
    explicit Scene(std::shared_ptr<const Impl> impl);
    const Impl& compiled() const;  // throws Error when not ok
    std::shared_ptr<const Impl> impl_;
    friend SDFC_API Scene compile_file(const std::string&, const Options&);
    friend SDFC_API Scene compile_string(const std::string&, const std::string&, const Options&);
};

// A .sdf script or a .vm model from a file. Never throws for the script's errors: see ok().
SDFC_API Scene compile_file(const std::string& path, const Options& options = {});
// A .sdf script from text; `name` is its path in diagnostics (imports relative to the
// working folder).
SDFC_API Scene compile_string(const std::string& text, const std::string& name = "<string>", const Options& options = {});

// `.stl`, `.obj`, `.ply` or `.3mf`, by the path's extension; written whole or not at all.
SDFC_API void write_mesh(const Mesh& mesh, const std::string& path);

SDFC_API const char* version();

}  // namespace sdfc::api
