// `sdfc mesh`: the files it writes, and its errors before any work (the box, the grid's
// size, the output) in the usual forms.
#include <catch2/catch.hpp>

#include <cstring>
#include <filesystem>

#include "run.hpp"

using namespace sdfc;
using test::run_sdfc;
namespace fs = std::filesystem;

namespace {
std::string q(const std::string& s) { return "'" + s + "'"; }
}  // namespace

TEST_CASE("mesh writes a binary STL, an OBJ, a PLY and a 3MF of the scene") {
    const std::string s = test::write_temp("mesh_box.sdf", "material(color = [1, 0, 0]) box([1, 1, 1]);\n");
    const std::string stl = test::temp_dir() + "/box.stl";
    auto r = run_sdfc("mesh " + q(s) + " -o " + q(stl) + " --resolution 10");
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.rfind("sdfc: wrote " + stl + " (", 0) == 0);
    const std::string bytes = test::slurp(stl);
    REQUIRE(bytes.size() >= 84);
    uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    CHECK(n > 12);
    CHECK(bytes.size() == 84 + 50 * size_t(n));
    CHECK(r.err.find(std::to_string(n) + " triangles") != std::string::npos);
    const std::string obj = test::temp_dir() + "/box.obj";
    REQUIRE(run_sdfc("mesh " + q(s) + " -o " + q(obj) + " --cell 0.1 --quiet").status == 0);
    const std::string text = test::slurp(obj);
    CHECK(text.find("\nv 0.5 0.5 0.5 1 0 0\n") != std::string::npos);  // a corner, sharp, red
    const std::string tmf = test::temp_dir() + "/box.3mf";
    REQUIRE(run_sdfc("mesh " + q(s) + " -o " + q(tmf) + " --resolution 8 -q").status == 0);
    CHECK(test::slurp(tmf).rfind("PK", 0) == 0);  // a zip package
    const std::string ply = test::temp_dir() + "/box.ply";
    REQUIRE(run_sdfc("mesh " + q(s) + " -o " + q(ply) + " --bounds -1,-1,-1,0,1,1 --resolution 8 -q").status == 0);
    CHECK(test::slurp(ply).rfind("ply\nformat binary_little_endian 1.0\n", 0) == 0);
}

TEST_CASE("mesh errors come before the work and change nothing") {
    const std::string s = test::write_temp("mesh_sphere.sdf", "sphere(1);\n");
    auto ext = run_sdfc("mesh " + q(s) + " -o " + q(test::temp_dir() + "/x.png"));
    CHECK(ext.status == 2);
    CHECK(ext.err == "sdfc: error: cannot write '" + test::temp_dir() + "/x.png': unknown mesh format (use .stl, .obj, .ply or .3mf)\n");
    auto dir = run_sdfc("mesh " + q(s) + " -o /nonexistent-dir/x.stl");
    CHECK(dir.status == 1);
    CHECK(dir.err.find("sdfc: error: cannot write '/nonexistent-dir/x.stl'") == 0);
    auto self = run_sdfc("mesh " + q(s) + " -o " + q(s.substr(0, s.size() - 4) + ".STL"));
    CHECK(self.status == 0);  // another file: fine
    CHECK(run_sdfc("mesh " + q(s)).err == "sdfc: error: mesh needs -o OUT (.stl, .obj, .ply or .3mf)\n");
    CHECK(run_sdfc("mesh " + q(s) + " -o a.stl --resolution 8 --cell 0.1").err ==
          "sdfc: error: --resolution and --cell are two ways to say the same: give one\n");
    CHECK(run_sdfc("mesh " + q(s) + " -o a.stl --bounds 1,1,1,0,0,0").err ==
          "sdfc: error: --bounds needs X0 < X1, Y0 < Y1 and Z0 < Z1\n");
    CHECK(run_sdfc("mesh " + q(s) + " -o a.stl --bounds -1e30,-1,-1,1e30,1,1").err ==
          "sdfc: error: --bounds must lie within 1e15 of the origin on each axis\n");
    CHECK(run_sdfc("mesh " + q(s) + " -o a.stl --resolution 4000").err ==
          "sdfc: error: a grid of 64384768512 cells is over the limit of 2147483648 (raise it with --max-cells)\n");
    CHECK(run_sdfc("mesh " + q(s) + " -o a.stl --max-cells 1e12").err == "sdfc: error: --max-cells must be from 1 to 68719476736, not 1e12\n");
    CHECK(run_sdfc("mesh " + q(s) + " -o a.stl --max-cells 68719476737").err ==
          "sdfc: error: --max-cells must be from 1 to 68719476736, not 68719476737\n");  // (not rounded as a float)
    const std::string big = test::write_temp("mesh_big.sdf", "sphere(1e20);\n");  // (its squares overflow a float)
    auto r = run_sdfc("mesh " + q(big) + " -o a.stl");
    CHECK(r.status == 1);
    CHECK(r.err == "sdfc: error: " + big + " reaches beyond 1e15 of the origin (-1.04e+20, -1.04e+20, -1.04e+20 to 1.04e+20, "
                   "1.04e+20, 1.04e+20): scale it down to mesh it\n");
    auto raised = run_sdfc("mesh " + q(s) + " -o " + q(test::temp_dir() + "/raised.stl") + " --resolution 8 --max-cells 5e9 -q");
    CHECK(raised.status == 0);  // above the default limit and above what an int holds
    const std::string plane = test::write_temp("mesh_plane.sdf", "plane([0, 1, 0], 0);\n");
    CHECK(run_sdfc("mesh " + q(plane) + " -o a.stl").err ==
          "sdfc: error: the scene is unbounded (a plane, an infinite repetition, a 2D profile not extruded: extrude(h) it, shapes beyond 1e29?): give --bounds X0,Y0,Z0,X1,Y1,Z1\n");
    const std::string empty = test::write_temp("mesh_empty.sdf", "// nothing yet\n");
    auto none = run_sdfc("mesh " + q(empty) + " -o a.stl");
    CHECK(none.status == 1);
    CHECK(none.err == "sdfc: error: " + empty + " has no surface (its distance is the same everywhere): nothing to mesh\n");
    const std::string flat = test::write_temp("mesh_2d.vm", "_0 var-x\n_1 var-y\n_2 square _0\n_3 square _1\n_4 add _2 _3\n");
    CHECK(run_sdfc("mesh " + q(flat) + " -o a.stl").err == "sdfc: error: mesh needs a 3D scene (this one is 2D: render or slice it)\n");
    const std::string out = test::temp_dir() + "/limited.stl";
    fs::remove(out);
    auto lim = run_sdfc("mesh " + q(s) + " -o " + q(out) + " --max-triangles 100");
    CHECK(lim.status == 1);
    CHECK(lim.err.find("over the limit of 100 (raise it with --max-triangles)") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
    auto broken = run_sdfc("mesh " + q(test::write_temp("mesh_bad.sdf", "sphere(;\n")) + " -o " + q(out));
    CHECK(broken.status == 1);
    CHECK(broken.err.find("mesh_bad.sdf:1:8: error:") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("mesh --simplify writes fewer triangles, says from how many, and refuses what is not a distance") {
    const std::string s = test::write_temp("mesh_simplify.sdf", "box([1, 1, 1]);\n");
    const std::string out = test::temp_dir() + "/simplified.stl";
    auto r = run_sdfc("mesh " + q(s) + " -o " + q(out) + " --resolution 16 --simplify 0.01");
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.rfind("sdfc: wrote " + out + " (12 triangles simplified from ", 0) == 0);
    CHECK(test::slurp(out).size() == 84 + 50 * 12);
    CHECK(run_sdfc("mesh " + q(s) + " -o " + q(out) + " --simplify inf").err == "sdfc: error: --simplify takes a number, not 'inf'\n");
    for (const char* bad : {"0", "-1"}) {
        auto e = run_sdfc("mesh " + q(s) + " -o " + q(out) + " --simplify " + bad);
        CHECK(e.status == 2);
        CHECK(e.err == std::string("sdfc: error: --simplify takes a distance above 0 (the most the mesh may be off the surface), not ") + bad + "\n");
    }
    auto fine = run_sdfc("mesh " + q(s) + " -o " + q(out) + " --resolution 16 --simplify 0.0001");
    CHECK(fine.status == 0);
    CHECK(fine.err.rfind("sdfc: warning: --simplify 0.0001 is under 1/25 of a cell (0.0026), the most dual contouring leaves a vertex off the "
                         "surface: few triangles can go\n", 0) == 0);
    CHECK(fine.err.find("(12 triangles simplified from") != std::string::npos);  // flat faces go all the same
}
