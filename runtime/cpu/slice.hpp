// 2D pictures of a field: the classic distance-field cross-section (`sdfc slice`) and the
// Prospero-style inside/outside image of 2D .vm models.
#pragma once
#include <array>
#include <memory>
#include <optional>

#include "compiler/bytecode/compile.hpp"
#include "runtime/io/image.hpp"
#include "runtime/cpu/tracer.hpp"

namespace sdfc {

struct SliceOptions {
    int axis = 2;    // 0 = x, 1 = y, 2 = z: the plane `axis = at`
    float at = 0.0f;
    std::optional<std::array<float, 4>> range;  // umin, umax, vmin, vmax; default: the scene's bounds
    int width = 800, height = 0;                // height 0: from the range's aspect
    int threads = 0;
};

// Plane axes: axis z -> (u, v) = (x, y); axis y -> (x, z); axis x -> (z, y).
// Inside and outside in two colours, iso-lines every 0.1 units, the zero line in white.
Image render_slice(const CompiledScene& scene, const SliceOptions& opt);

// The Prospero image: w x h pixels over [-1, 1]^2, grid including both ends, row 0 at
// y = +1, white where the field is < 0. `baseline` disables interval pruning.
Image render_2d(const CompiledScene& scene, int w, int h, int threads = 0, bool baseline = false,
                RenderStats* stats = nullptr);

// A 2D model prepared for many pictures (bench's repeats, an API scene rendered again): its
// root tape, linked and marked for the sign, made once, and the scratch of earlier renders,
// kept warm (as much memory as one render's scratch, held while it lives). render() gives
// render_2d's image; it may run from several threads at once. The scene must outlive it
// and have a distance output.
class Raster2d {
public:
    explicit Raster2d(const CompiledScene& scene);
    ~Raster2d();
    Raster2d(const Raster2d&) = delete;
    Raster2d& operator=(const Raster2d&) = delete;
    Image render(int w, int h, int threads = 0, RenderStats* stats = nullptr) const;

private:
    struct Prepared;
    std::unique_ptr<Prepared> p_;
};

}  // namespace sdfc
