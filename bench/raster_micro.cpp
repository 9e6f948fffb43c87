// render_2d timing with CPU time, for profiling under a loaded machine:
//   sdfc_raster_micro FILE [SIZE=1024] [THREADS=1] [REPEAT=20] [baseline]
// prints wall median/min and process CPU time per render (median).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <time.h>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "runtime/cpu/slice.hpp"

using namespace sdfc;

static double cpu_ms() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: sdfc_raster_micro FILE [SIZE] [THREADS] [REPEAT] [baseline]\n");
        return 2;
    }
    const int size = argc > 2 ? std::atoi(argv[2]) : 1024;
    const int threads = argc > 3 ? std::atoi(argv[3]) : 1;
    const int repeat = argc > 4 ? std::atoi(argv[4]) : 20;
    const bool baseline = argc > 5 && std::strcmp(argv[5], "baseline") == 0;
    SourceManager sm;
    Scene s = load_scene(sm, argv[1]);
    CompiledScene cs = compile_scene(s);
    std::vector<double> wall, cpu;
    RenderStats st;
    for (int r = 0; r < repeat; ++r) {
        const double c0 = cpu_ms();
        const auto t0 = std::chrono::steady_clock::now();
        Image img = render_2d(cs, size, size, threads, baseline, &st);
        wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        cpu.push_back(cpu_ms() - c0);
    }
    std::sort(wall.begin(), wall.end());
    std::sort(cpu.begin(), cpu.end());
    std::printf("wall_median_ms=%.2f wall_min_ms=%.2f cpu_median_ms=%.2f cpu_min_ms=%.2f evals_per_pixel=%.3f\n",
                wall[wall.size() / 2], wall.front(), cpu[cpu.size() / 2], cpu.front(),
                double(st.distance_points) / (double(size) * size));
}
