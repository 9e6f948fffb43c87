// Micro benchmark of the batch VM: brute-force evaluation of a file's distance program on
// an N x N grid over [-1,1]^2 (z = 0), single thread, and ns per instruction per batch.
//   sdfc_vm_micro FILE [N=1024] [REPEAT=5]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include <time.h>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"

using namespace sdfc;

static double cpu_ms() {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: sdfc_vm_micro FILE [N] [REPEAT]\n");
        return 2;
    }
    int N = argc > 2 ? std::atoi(argv[2]) : 1024;
    int repeat = argc > 3 ? std::atoi(argv[3]) : 5;
    SourceManager sm;
    Scene s = load_scene(sm, argv[1]);
    CompiledScene cs = compile_scene(s);
    const Program& p = cs.distance;
    Evaluator ev(p);
    std::vector<double> ms, cpu;
    double checksum = 0;
    for (int r = 0; r < repeat; ++r) {
        auto t0 = std::chrono::steady_clock::now();
        double c0 = cpu_ms();
        long inside = 0;
        float xs[kBatch], ys[kBatch], zs[kBatch] = {};
        for (int y = 0; y < N; ++y) {
            float yv = 1.0f - 2.0f * float(y) / float(N - 1);
            for (int x0 = 0; x0 < N; x0 += kBatch) {
                int n = std::min(kBatch, N - x0);
                for (int i = 0; i < n; ++i) {
                    xs[i] = -1.0f + 2.0f * float(x0 + i) / float(N - 1);
                    ys[i] = yv;
                }
                ev.eval(xs, ys, zs, n);
                const float* d = ev.output(0);
                for (int i = 0; i < n; ++i) inside += d[i] < 0.0f;
            }
        }
        ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        cpu.push_back(cpu_ms() - c0);
        checksum = double(inside);
    }
    std::sort(ms.begin(), ms.end());
    std::sort(cpu.begin(), cpu.end());
    double batches = double(N) * ((N + kBatch - 1) / kBatch);
    std::printf("instrs=%zu regs=%u wall_median_ms=%.1f cpu_min_ms=%.1f cpu_ns_per_instr_batch=%.2f inside=%.0f\n",
                p.code.size(), p.num_regs, ms[ms.size() / 2], cpu.front(),
                cpu.front() * 1e6 / (batches * double(p.code.size())), checksum);
}
