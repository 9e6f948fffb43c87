// The opcode and example cases, and the helpers that build shape cases from scripts.
#include "conformance/cases.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <sstream>

#include "compiler/bytecode/compile.hpp"
#include "lang/load.hpp"
#include "support.hpp"

namespace sdfc::conformance {

namespace fs = std::filesystem;

bool satisfies(float v, const Expect& e) {
    switch (e.kind) {
        case Expect::Near:
            if (std::isnan(e.want) || std::isnan(v)) return std::isnan(e.want) && std::isnan(v);
            if (std::isinf(e.want) || std::isinf(v)) return double(v) == e.want;
            return std::fabs(double(v) - e.want) <= e.tol * (1 + std::fabs(e.want));
        case Expect::Less: return double(v) < e.want;
        case Expect::Greater: return double(v) > e.want;
    }
    return false;
}

std::string describe(const Expect& e) {
    std::ostringstream s;
    s.precision(9);
    if (e.kind == Expect::Near) s << "near " << e.want << " (tol " << e.tol << ")";
    else s << (e.kind == Expect::Less ? "< " : "> ") << e.want;
    return s.str();
}

// --- opcodes ---

namespace {

// The inputs of the old per-backend opcode tests: the VM's 64 lanes (signs, zero, fractions,
// the [-1, 1] domain of asin/acos) and combinations of special values.
std::vector<Point> opcode_points() {
    std::vector<Point> pts;
    for (int i = 0; i < 64; ++i)
        pts.push_back({-3.25f + 0.11f * float(i), 0.8f - 0.05f * float(i), (i % 3 == 0) ? 0.0f : 1.5f - 0.07f * float(i)});
    const float specials[] = {0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -2.5f, 3.0f, 1e-3f, -1e-3f, 7.25f, -100.0f, 1.5707964f, 3.1415927f, 0.75f};
    std::mt19937 rng(4321);
    const int n = int(std::size(specials));
    for (int i = 0; i < 64; ++i) pts.push_back({specials[rng() % n], specials[rng() % n], specials[rng() % n]});
    for (float v : specials) pts.push_back({v, v, v});  // equal operands (eq, le, min ties)
    return pts;
}

Case opcode_case(Op op, float k) {
    Case c;
    c.kind = Case::Opcode;
    c.op = op;
    c.k = k;
    std::ostringstream name;
    name << "op " << op_info(op).mnemonic;
    if (op_info(op).has_imm) name << " k=" << k;
    c.name = name.str();
    c.program = test::single_op_program(op, k);
    c.time = 2.5f;
    c.points = opcode_points();
    for (const Point& p : c.points) {
        float want;
        switch (op) {
            case Op::VarX: want = p.x; break;
            case Op::VarY: want = p.y; break;
            case Op::VarZ: want = p.z; break;
            case Op::Time: want = c.time; break;
            default: want = eval_op(op, p.x, p.y, p.z, k);
        }
        // Vectorised libm and the scalar one may differ in the last ulp for transcendental ops.
        c.expect.push_back({Expect::Near, double(want), 2e-6});
    }
    return c;
}

}  // namespace

const std::vector<Case>& opcode_cases() {
    static const std::vector<Case> cases = [] {
        std::vector<Case> out;
        for (int o = 0; o < kOpCount; ++o) {
            const Op op = static_cast<Op>(o);
            if (!op_info(op).has_imm) {
                out.push_back(opcode_case(op, 0.75f));
                continue;
            }
            if (op == Op::Param) {  // k: which param (the backends' params are all 0)
                for (float k : {0.0f, 3.0f}) out.push_back(opcode_case(op, k));
                continue;
            }
            for (float k : {0.75f, -2.5f, 0.0f, 3.0f}) out.push_back(opcode_case(op, k));
        }
        return out;
    }();
    return cases;
}

// --- shapes ---

Case& ShapeCases::cur() { return out_.back(); }

ShapeCases& ShapeCases::script(const std::string& src, float range) {
    if (!out_.empty() && out_.back().name == src) return *this;
    auto compiled = test::compile_text(src);
    Case c;
    c.kind = Case::Shape;
    c.name = src;
    c.program = compiled->cs.distance;
    c.time = compiled->cs.time;
    c.range = range;
    c.sources = std::shared_ptr<const test::Compiled>(std::move(compiled));
    out_.push_back(std::move(c));
    return *this;
}

ShapeCases& ShapeCases::at(float x, float y, float z, double want, double tol) {
    cur().points.push_back({x, y, z});
    cur().expect.push_back({Expect::Near, want, tol});
    return *this;
}

ShapeCases& ShapeCases::less(float x, float y, float z, double bound) {
    cur().points.push_back({x, y, z});
    cur().expect.push_back({Expect::Less, bound});
    return *this;
}

ShapeCases& ShapeCases::greater(float x, float y, float z, double bound) {
    cur().points.push_back({x, y, z});
    cur().expect.push_back({Expect::Greater, bound});
    return *this;
}

ShapeCases& ShapeCases::random(const Ref& ref, double range, int n, double tol, unsigned seed) {
    return random_bound(ref, nullptr, 0.0, range, n, seed, tol);
}

ShapeCases& ShapeCases::random_bound(const Ref& ref, const std::function<bool(double, double, double)>& bound_only,
                                     double slack, double range, int n, unsigned seed, double tol) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-range, range);
    for (int i = 0; i < n; ++i) {
        const double px = u(rng), py = u(rng), pz = u(rng);
        const float x = float(px), y = float(py), z = float(pz);
        // The reference at the float point the program sees.
        const double want = ref(x, y, z);
        cur().points.push_back({x, y, z});
        if (bound_only && bound_only(x, y, z)) cur().expect.push_back({Expect::Less, want + slack});
        else cur().expect.push_back({Expect::Near, want, tol});
    }
    return *this;
}

const std::vector<Case>& shape_cases() {
    static const std::vector<Case> cases = [] {
        std::vector<Case> out;
        add_primitive_cases(out);
        add_operation_cases(out);
        return out;
    }();
    return cases;
}

// --- examples ---

const std::vector<Case>& example_cases() {
    static const std::vector<Case> cases = [] {
        std::vector<Case> out;
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(fs::path(SDFC_SOURCE_DIR) / "examples"))
            if (e.is_regular_file() && e.path().extension() == ".sdf") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const fs::path& f : files) {
            auto sm = std::make_shared<SourceManager>();
            const CompiledScene cs = compile_scene(load_scene(*sm, f.string()));
            Case c;
            c.kind = Case::Example;
            c.name = "example " + f.filename().string();
            c.program = cs.distance;
            c.time = cs.time;
            c.sources = sm;
            // Points in the scene's bounds (grown a little), else around the camera's target.
            glm::vec3 lo = cs.bounds.lo, hi = cs.bounds.hi;
            if (!cs.bounds.finite()) {
                const float r = glm::length(cs.camera.position - cs.camera.target);
                lo = cs.camera.target - glm::vec3(r), hi = cs.camera.target + glm::vec3(r);
            }
            const glm::vec3 mid = 0.5f * (lo + hi), half = 0.6f * (hi - lo);
            c.range = std::max({std::fabs(mid.x) + half.x, std::fabs(mid.y) + half.y, std::fabs(mid.z) + half.z});
            std::mt19937 rng(77);
            std::uniform_real_distribution<float> u(-1.0f, 1.0f);
            for (int i = 0; i < 256; ++i) {
                const Point p{mid.x + half.x * u(rng), mid.y + half.y * u(rng), mid.z + half.z * u(rng)};
                c.points.push_back(p);
                const float want = eval_scalar(c.program, p.x, p.y, p.z, c.time)[0];
                c.expect.push_back({Expect::Near, double(want), 1e-5});
            }
            out.push_back(std::move(c));
        }
        return out;
    }();
    return cases;
}

}  // namespace sdfc::conformance
