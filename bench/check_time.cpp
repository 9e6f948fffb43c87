// In-process time of `sdfc check` (interpret + lower + codegen), without the process
// start-up (a few ms since OpenImageIO became a module opened at the first image written).
//   sdfc_check_time FILE [REPEAT=5]    prints wall and CPU time
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <time.h>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"

using namespace sdfc;

static double cpu_ms() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: sdfc_check_time FILE [REPEAT]\n");
        return 2;
    }
    int repeat = argc > 2 ? std::atoi(argv[2]) : 5;
    std::vector<double> ms, cpu;
    size_t instrs = 0;
    for (int r = 0; r < repeat; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        double c0 = cpu_ms();
        SourceManager sm;
        Scene s = load_scene(sm, argv[1]);
        CompiledScene cs = compile_scene(s);
        instrs = cs.distance.code.size() + cs.shading.code.size();
        cpu.push_back(cpu_ms() - c0);
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(ms.begin(), ms.end());
    std::sort(cpu.begin(), cpu.end());
    std::printf("median_ms=%.1f min_ms=%.1f cpu_median_ms=%.1f instructions=%zu\n", ms[ms.size() / 2], ms.front(),
                cpu[cpu.size() / 2], instrs);
}
