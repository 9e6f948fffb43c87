// libFuzzer target over the whole pipeline (see pipeline.hpp for what one input runs).
// Any crash, sanitizer report, leak, timeout, uncaught exception (anything but a
// CompileError: every error a script causes must be a located diagnostic) or VM result
// that differs from the reference evaluation is a finding.
//
// Build (clang only):  CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -G Ninja \
//                        -DSDFC_FUZZ=ON -DSDFC_BUILD_TESTS=OFF && cmake --build build-fuzz
// Run:                 .ci/fuzz   (seeds: examples/, snippets of the tests, tests/bad/,
//                                  tests/fuzz/seeds/ and tests/fuzz/regressions/)
// Keep each crasher in tests/fuzz/regressions/: tests/lang/test_fuzz_regressions.cpp
// replays them all.
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "pipeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string problem = sdfc::fuzz::run(std::string(reinterpret_cast<const char*>(data), size));
    if (!problem.empty()) {
        std::fprintf(stderr, "%s\n", problem.c_str());
        std::abort();
    }
    return 0;
}
