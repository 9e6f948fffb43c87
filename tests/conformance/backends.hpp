// The conformance suite's backend adapters: thin structs with one shape per evaluator kind,
// so the generic test bodies (test_points.cpp, test_boxes.cpp) are stamped onto each with
// TEMPLATE_TEST_CASE, and only these adapters touch the evaluator APIs (Fidget's model).
//   point backends:  values at points        Scalar, BatchVm, Simplify*, GlslLlvmpipe
//   box backends:    an interval over boxes  ScalarInterval, BatchInterval
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "compiler/bytecode/program.hpp"
#include "conformance/cases.hpp"
#include "runtime/eval/interval.hpp"

namespace sdfc::conformance {

// A box of points, [x.lo, x.hi] x [y.lo, y.hi] x [z.lo, z.hi] (both ends NaN: any value).
struct Box {
    Interval x, y, z;
};
struct BoxResult {
    Interval value;
    std::vector<uint8_t> choices;  // one per choice op (is_choice_op), in program order
};

// --- point backends: eval() gives output 0 at every point; "" from unavailable() ---

// eval_scalar (compiler/bytecode/codegen.cpp): eval_op one instruction at a time.
struct Scalar {
    static constexpr bool kVmFloats = false;  // scalar libm: may differ from the VM in an ulp
    std::string unavailable() const { return ""; }
    std::vector<float> eval(const Program& p, const std::vector<Point>& pts, float time);
};

// The batch VM (runtime/eval/vm.hpp), kBatch lanes at a time.
struct BatchVm {
    static constexpr bool kVmFloats = true;
    std::string unavailable() const { return ""; }
    std::vector<float> eval(const Program& p, const std::vector<Point>& pts, float time);
};

// Tapes simplified for a box (runtime/eval/interval.hpp), run by the VM: bit for bit the
// full program's floats at every point of the box. Three ways to simplify:
// SignOnly: simplify_batch(compact) of a tape marked for its sign alone (Tape::mark_sign_only,
// as the 2D renderer does): not the same floats, only the same "< 0" at every point.
// MinChain: simplify_batch(compact) after prune_min_chains (Tape::mark_min_chains, as the
// tape tree does): the same floats.
// Sweep: no tapes made: simplify_masks, then SweepVM runs the full tape for every box at
// once (as the 2D renderer's leaves do): the traces' floats, so the same floats.
enum class Simplifier { One, BatchCompact, BatchTrace, SignOnly, MinChain, Sweep };
template <Simplifier S>
struct SimplifiedTape {
    static constexpr bool kVmFloats = true;
    std::string unavailable() const { return ""; }
    // Each point in a box of its own (random size, the point anywhere in it).
    std::vector<float> eval(const Program& p, const std::vector<Point>& pts, float time);
    // pts[i] (all inside boxes[i]) through the tape simplified for boxes[i].
    std::vector<std::vector<float>> eval_in_boxes(const Program& p, const std::vector<Box>& boxes,
                                                  const std::vector<std::vector<Point>>& pts, float time);
};
using SimplifyOne = SimplifiedTape<Simplifier::One>;
using SimplifyBatchCompact = SimplifiedTape<Simplifier::BatchCompact>;
using SimplifyBatchTrace = SimplifiedTape<Simplifier::BatchTrace>;
using SimplifySignOnly = SimplifiedTape<Simplifier::SignOnly>;
using SimplifyMinChain = SimplifiedTape<Simplifier::MinChain>;
using SimplifySweep = SimplifiedTape<Simplifier::Sweep>;

// The GLSL emitter (compiler/glsl/glsl_emit.hpp) on Mesa llvmpipe: each case is a fragment
// shader that reads the points from a float texture and writes the value's bits as RGBA8.
// Unavailable without EGL (at build time or at run time).
struct GlslLlvmpipe {
    static constexpr bool kVmFloats = false;
    std::string unavailable() const;
    std::vector<float> eval(const Program& p, const std::vector<Point>& pts, float time);  // empty: see error
    // `tape`: through the tape interpreter (compiler/glsl/glsl_tape.hpp) instead.
    std::vector<float> run(const Program& p, const std::vector<Point>& pts, float time, bool tape);
    std::string error;  // the last eval's shader log, when it failed
    // Where llvmpipe is known to differ from opcodes.def's semantics (results GLSL ES 3.00
    // leaves undefined, or to the implementation's precision): why, or "". The point suite
    // counts and reports these instead of failing; any other difference fails.
    static std::string known_difference(const Case& c, const Point& p, float got);
};

// The same shader's tape interpreter (compiler/glsl/glsl_tape.hpp), the program as data: what
// big scenes' shaders run. Guards skip their regions here, which must change no value
// (only shapes whose distance is never below their box's are guarded).
struct GlslTapeLlvmpipe : GlslLlvmpipe {
    std::vector<float> eval(const Program& p, const std::vector<Point>& pts, float time) { return run(p, pts, time, true); }
};

// --- box backends: an interval of output 0 over each box, and each choice op's decision ---

// eval_interval (the scalar interval semantics), one instruction at a time.
struct ScalarInterval {
    std::vector<BoxResult> eval(const Program& p, const std::vector<Box>& boxes, float time);
};

// IntervalEvaluator over a Tape, kIvLanes boxes at a time.
struct BatchInterval {
    std::vector<BoxResult> eval(const Program& p, const std::vector<Box>& boxes, float time);
};

}  // namespace sdfc::conformance
