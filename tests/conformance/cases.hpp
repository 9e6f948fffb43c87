// The conformance suite's one list of cases: every opcodes.def row, every shape and
// operation, every example. A case is a distance program, points, and what each point must
// give (from the opcode's semantics column, a hand-derived value or a double-precision
// formula, or the scalar reference interpreter). Every backend adapter (backends.hpp) runs
// the same list; only the adapters touch the evaluator APIs.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "compiler/bytecode/program.hpp"

namespace sdfc::conformance {

struct Point {
    float x, y, z;
};

// What a backend's value v at a point must satisfy.
struct Expect {
    enum Kind { Near, Less, Greater } kind = Near;
    double want = 0.0;  // Near: |v - want| <= tol * (1 + |want|) (NaN: v is NaN); Less: v < want
    double tol = 1e-5;
};

struct Case {
    enum Kind { Opcode, Shape, Example } kind = Shape;
    std::string name;       // what a failure prints: "op mul_i k=0.75", a script, an example's path
    Program program;        // output 0 is the value tested
    float time = 0.0f;
    std::vector<Point> points;
    std::vector<Expect> expect;  // one per point
    float range = 3.0f;     // the box suite draws boxes inside [-range, range]^3 (Opcode: its own)
    Op op = Op::Const;      // Opcode: the row (program is test::single_op_program(op, k))
    float k = 0.0f;
    std::shared_ptr<const void> sources;  // keeps the script text the program's locs point into
};

bool satisfies(float v, const Expect& e);
std::string describe(const Expect& e);

// Every opcode, once per immediate for the rows that read one; inputs (var_x ...) too.
const std::vector<Case>& opcode_cases();
// Every primitive (cases_shapes.cpp) and every operation (cases_operations.cpp).
const std::vector<Case>& shape_cases();
// Every examples/*.sdf: random points in its bounds against eval_scalar.
const std::vector<Case>& example_cases();

// Builds shape cases from scripts: known values at chosen points, and a reference formula
// at random points (evaluated at the float point the program sees).
class ShapeCases {
public:
    using Ref = std::function<double(double x, double y, double z)>;
    explicit ShapeCases(std::vector<Case>& out) : out_(out) {}
    ShapeCases& script(const std::string& src, float range = 3.0f);  // later calls add to it
    ShapeCases& at(float x, float y, float z, double want, double tol = 1e-5);
    ShapeCases& less(float x, float y, float z, double bound);
    ShapeCases& greater(float x, float y, float z, double bound);
    // n random points in [-range, range]^3 (seeded per script), want = ref at each.
    ShapeCases& random(const Ref& ref, double range = 3.0, int n = 400, double tol = 1e-5, unsigned seed = 1234);
    // The same, with an inequality: v <= ref + slack where `bound_only(p)`, near elsewhere.
    ShapeCases& random_bound(const Ref& ref, const std::function<bool(double, double, double)>& bound_only, double slack,
                             double range, int n, unsigned seed, double tol = 1e-5);

private:
    Case& cur();
    std::vector<Case>& out_;
};

void add_primitive_cases(std::vector<Case>& out);
void add_operation_cases(std::vector<Case>& out);

}  // namespace sdfc::conformance
