#include "runtime/cpu/slice.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "runtime/eval/vm.hpp"

namespace sdfc {
namespace {

// Runs body(y) for each row in parallel with a per-thread Evaluator of `prog`.
template <class F>
void for_rows(const Program& prog, int h, int threads, F&& body) {
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    tbb::enumerable_thread_specific<std::unique_ptr<Evaluator>> evs([&] { return std::make_unique<Evaluator>(prog); });
    tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& r) {
        Evaluator& ev = *evs.local();
        for (int y = r.begin(); y < r.end(); ++y) body(ev, y);
    });
}

float smoothstep(float a, float b, float x) {
    float t = std::clamp((x - a) / (b - a), 0.0f, 1.0f);
    return t * t * (3 - 2 * t);
}

}  // namespace

Image render_slice(const CompiledScene& scene, const SliceOptions& opt) {
    int ua = opt.axis == 2 ? 0 : opt.axis == 1 ? 0 : 2;
    int va = opt.axis == 2 ? 1 : opt.axis == 1 ? 2 : 1;
    std::array<float, 4> r;
    if (opt.range) {
        r = *opt.range;
    } else {
        const Bounds& b = scene.bounds;
        auto lo = [&](int a) { return b.lo[a] > -1e29f ? b.lo[a] : -5.0f; };
        auto hi = [&](int a) { return b.hi[a] < 1e29f ? b.hi[a] : 5.0f; };
        float u0 = lo(ua), u1 = hi(ua), v0 = lo(va), v1 = hi(va);
        if (!(u1 > u0)) { u0 = -5; u1 = 5; }
        if (!(v1 > v0)) { v0 = -5; v1 = 5; }
        float mu = 0.1f * (u1 - u0) + 0.05f, mv = 0.1f * (v1 - v0) + 0.05f;
        r = {u0 - mu, u1 + mu, v0 - mv, v1 + mv};
        // Both sizes given: widen the range along one axis to the image's aspect, so that
        // pixels stay square (a circle stays a circle).
        if (opt.height > 0 && opt.width > 0) {
            const float want = float(opt.width) / float(opt.height), have = (r[1] - r[0]) / (r[3] - r[2]);
            if (have < want) {
                const float grow = 0.5f * ((r[3] - r[2]) * want - (r[1] - r[0]));
                r[0] -= grow, r[1] += grow;
            } else {
                const float grow = 0.5f * ((r[1] - r[0]) / want - (r[3] - r[2]));
                r[2] -= grow, r[3] += grow;
            }
        }
    }
    int w = opt.width;
    // (in doubles, clamped before the conversion: a range of 1e-30 by 2 is 16384 rows, not int overflow)
    const double rows = double(w) * (double(r[3]) - double(r[2])) / (double(r[1]) - double(r[0]));
    int h = opt.height > 0 ? opt.height : int(std::lround(std::clamp(std::isfinite(rows) ? rows : 1.0, 1.0, 16384.0)));
    h = std::min(h, 16384);
    Image img(w, h, 3);
    float pix = (r[1] - r[0]) / float(w);
    for_rows(scene.distance, h, opt.threads, [&](Evaluator& ev, int y) {
        float p[3][kBatch];
        for (int x0 = 0; x0 < w; x0 += kBatch) {
            int n = std::min(kBatch, w - x0);
            for (int i = 0; i < n; ++i) {
                float u = r[0] + (float(x0 + i) + 0.5f) * (r[1] - r[0]) / float(w);
                float v = r[3] - (float(y) + 0.5f) * (r[3] - r[2]) / float(h);
                p[ua][i] = u;
                p[va][i] = v;
                p[opt.axis][i] = opt.at;
            }
            ev.eval(p[0], p[1], p[2], n, scene.time);
            const float* d = ev.output(0);
            for (int i = 0; i < n; ++i) {
                float dv = std::isfinite(d[i]) ? d[i] : 1e6f;
                // Quilez's distance-field palette: warm outside, cool inside, bands every 0.1.
                float col[3] = {0.9f, 0.6f, 0.3f};
                if (dv < 0) { col[0] = 0.65f; col[1] = 0.85f; col[2] = 1.0f; }
                float shade = (1.0f - std::exp(-4.0f * std::fabs(dv))) * (0.8f + 0.2f * std::cos(62.83185f * dv));
                float iso = 1.0f - smoothstep(0.0f, 1.5f * pix, std::fabs(dv));
                for (int c = 0; c < 3; ++c) {
                    float v = col[c] * (0.25f + 0.75f * shade);
                    v = v + (1.0f - v) * iso;
                    img.at(x0 + i, y, c) = v;
                }
            }
        }
    });
    return img;
}

}  // namespace sdfc
