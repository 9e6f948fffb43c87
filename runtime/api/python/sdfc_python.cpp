// `import sdfc`: the public C++ API (runtime/api/sdfc.hpp) for Python, with pybind11 and
// numpy arrays. A script's error raises sdfc.CompileError carrying file, line, column and
// message (and every diagnostic); the long calls (distances, pictures, meshes) let other
// Python threads run.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <map>
#include <optional>
#include <string>

#include "runtime/api/sdfc.hpp"

namespace py = pybind11;
using namespace sdfc::api;

namespace {

py::handle g_compile_error;  // sdfc.CompileError, made at import (the module holds it)

py::dict diagnostic_dict(const Diagnostic& d) {
    py::dict o;
    o["file"] = d.file, o["line"] = d.line, o["column"] = d.column;
    o["severity"] = d.severity, o["message"] = d.message, o["text"] = d.text;
    return o;
}

[[noreturn]] void raise_compile_error(const std::vector<Diagnostic>& ds, const std::string& what) {
    const Diagnostic* first = nullptr;
    for (const Diagnostic& d : ds)
        if (d.severity == "error") {
            first = &d;
            break;
        }
    py::object e = g_compile_error(py::str(first ? first->text : what));
    e.attr("file") = first ? py::cast(first->file) : py::none();
    e.attr("line") = first ? first->line : 0;
    e.attr("column") = first ? first->column : 0;
    e.attr("message") = first ? first->message : what;
    py::list all;
    for (const Diagnostic& d : ds) all.append(diagnostic_dict(d));
    e.attr("diagnostics") = all;
    PyErr_SetObject(g_compile_error.ptr(), e.ptr());
    throw py::error_already_set();
}

// A scene that compiled (compile() raises otherwise).
struct PyScene {
    Scene scene;
};

// A -D value as the language writes it: a str is taken as an expression; booleans, numbers
// and lists or tuples of them (numpy's too) are written out.
std::string expression_of(const py::handle& v) {
    if (py::isinstance<py::str>(v)) return v.cast<std::string>();
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v) || py::isinstance<py::array>(v)) {
        std::string out = "[";
        for (const py::handle& item : v) out += (out.size() > 1 ? ", " : "") + expression_of(item);
        return out + "]";
    }
    return py::str(v).cast<std::string>();
}

Options options_of(float time, const std::map<std::string, py::object>& defines) {
    Options o;
    o.time = time;
    for (const auto& [name, value] : defines) o.defines.emplace_back(name, expression_of(value));
    return o;
}

PyScene compile(const py::object& source, std::optional<std::string> name, float time, const std::map<std::string, py::object>& defines) {
    const Options o = options_of(time, defines);
    // A path: an os.PathLike, or a str naming a .sdf or .vm file (one line, no ';').
    std::optional<std::string> path;
    py::module_ os = py::module_::import("os");
    if (py::isinstance(source, os.attr("PathLike"))) path = py::str(os.attr("fspath")(source)).cast<std::string>();
    else if (!py::isinstance<py::str>(source)) throw py::type_error("compile() takes a script (str) or a path (str or os.PathLike)");
    else {
        const std::string s = source.cast<std::string>();
        const bool one_line = s.find('\n') == std::string::npos && s.find(';') == std::string::npos;
        const bool ext = s.size() > 4 && (s.compare(s.size() - 4, 4, ".sdf") == 0 || s.compare(s.size() - 3, 3, ".vm") == 0);
        if (one_line && ext) path = s;
    }
    const std::string text = path ? std::string() : source.cast<std::string>();  // with the GIL held
    Scene scene;
    {
        py::gil_scoped_release unlocked;
        scene = path ? compile_file(*path, o) : compile_string(text, name.value_or("<string>"), o);
    }
    if (!scene.ok()) raise_compile_error(scene.diagnostics(), "the scene did not compile");
    return PyScene{scene};
}

template <class F>
auto translated(F&& f) {
    try {
        return f();
    } catch (const Error& e) {
        if (!e.diagnostics().empty()) raise_compile_error(e.diagnostics(), e.what());
        throw py::value_error(e.what());
    }
}

py::array_t<float> eval_points(const PyScene& s, const py::array_t<float, py::array::c_style | py::array::forcecast>& points) {
    if (points.ndim() != 2 || points.shape(1) != 3) throw py::value_error("eval() takes an array of shape (N, 3)");
    const size_t n = size_t(points.shape(0));
    std::vector<float> x(n), y(n), z(n);
    const float* p = points.data();
    for (size_t i = 0; i < n; ++i) x[i] = p[3 * i], y[i] = p[3 * i + 1], z[i] = p[3 * i + 2];
    py::array_t<float> out{py::ssize_t(n)};
    float* o = out.mutable_data();
    translated([&] {
        py::gil_scoped_release unlocked;
        s.scene.distances(x.data(), y.data(), z.data(), o, n);
        return 0;
    });
    return out;
}

py::array_t<float> render(const PyScene& s, int width, int height, int samples, int threads, bool alpha) {
    RenderSettings rs{width, height, samples, threads, alpha};
    Image img = translated([&] {
        py::gil_scoped_release unlocked;
        return s.scene.render(rs);
    });
    const size_t k = alpha ? 4 : 3, n = size_t(img.width) * img.height;
    py::array_t<float> out({py::ssize_t(img.height), py::ssize_t(img.width), py::ssize_t(k)});
    float* o = out.mutable_data();
    for (size_t p = 0; p < n; ++p) {
        for (size_t c = 0; c < 3; ++c) o[p * k + c] = img.rgb[p * 3 + c];
        if (alpha) o[p * k + 3] = img.alpha[p];
    }
    return out;
}

py::dict mesh(const PyScene& s, int resolution, float simplify, bool colors, std::optional<std::vector<float>> bounds) {
    MeshSettings ms;
    ms.resolution = resolution, ms.simplify = simplify, ms.colors = colors;
    if (bounds) {
        if (bounds->size() != 6) throw py::value_error("bounds takes six numbers: x0, y0, z0, x1, y1, z1");
        std::copy(bounds->begin(), bounds->end(), ms.bounds.begin());
    }
    Mesh m = translated([&] {
        py::gil_scoped_release unlocked;
        return s.scene.mesh(ms);
    });
    py::array_t<float> pos({py::ssize_t(m.positions.size()), py::ssize_t(3)});
    std::memcpy(pos.mutable_data(), m.positions.data(), m.positions.size() * sizeof(m.positions[0]));
    py::array_t<uint32_t> tri({py::ssize_t(m.triangles.size()), py::ssize_t(3)});
    std::memcpy(tri.mutable_data(), m.triangles.data(), m.triangles.size() * sizeof(m.triangles[0]));
    py::dict out;
    out["positions"] = pos, out["triangles"] = tri;
    if (colors) {
        py::array_t<float> col({py::ssize_t(m.colors.size()), py::ssize_t(3)});
        std::memcpy(col.mutable_data(), m.colors.data(), m.colors.size() * sizeof(m.colors[0]));
        out["colors"] = col;
    }
    return out;
}

void write_mesh_file(const py::dict& m, const std::string& path) {
    Mesh mesh;
    auto pos = m["positions"].cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
    auto tri = m["triangles"].cast<py::array_t<uint32_t, py::array::c_style | py::array::forcecast>>();
    if (pos.ndim() != 2 || pos.shape(1) != 3 || tri.ndim() != 2 || tri.shape(1) != 3)
        throw py::value_error("positions and triangles must have shape (N, 3)");
    mesh.positions.resize(size_t(pos.shape(0)));
    std::memcpy(mesh.positions.data(), pos.data(), mesh.positions.size() * sizeof(mesh.positions[0]));
    mesh.triangles.resize(size_t(tri.shape(0)));
    std::memcpy(mesh.triangles.data(), tri.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            if (v >= mesh.positions.size()) throw py::value_error("a triangle names a vertex that is not there");
    if (m.contains("colors")) {
        auto col = m["colors"].cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
        if (col.ndim() != 2 || col.shape(0) != pos.shape(0) || col.shape(1) != 3) throw py::value_error("colors must have shape (V, 3)");
        mesh.colors.resize(size_t(col.shape(0)));
        std::memcpy(mesh.colors.data(), col.data(), mesh.colors.size() * sizeof(mesh.colors[0]));
    }
    translated([&] {
        write_mesh(mesh, path);
        return 0;
    });
}

}  // namespace

PYBIND11_MODULE(sdfc, m) {
    m.doc() = "sdfc: compile .sdf signed-distance-field scenes; distances, pictures, GLSL and meshes";
    py::object base = py::reinterpret_borrow<py::object>(PyExc_Exception);
    py::object error = py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
        "sdfc.CompileError", "A script's error: .file, .line, .column, .message, and .diagnostics (every one, as dicts).",
        base.ptr(), nullptr));
    m.attr("CompileError") = error;
    g_compile_error = error;
    m.attr("__version__") = version();

    py::class_<PyScene>(m, "Scene", "A compiled scene (immutable; usable from several threads).")
        .def_property_readonly(
            "warnings",
            [](const PyScene& s) {
                py::list w;
                for (const Diagnostic& d : s.scene.diagnostics())
                    if (d.severity == "warning") w.append(diagnostic_dict(d));
                return w;
            },
            "The script's warnings, as dicts (file, line, column, severity, message, text).")
        .def("eval", &eval_points, py::arg("points"), "Signed distances at an (N, 3) array of points: an (N,) float32 array.")
        .def("render", &render, py::kw_only(), py::arg("width") = 0, py::arg("height") = 0, py::arg("samples") = 0,
             py::arg("threads") = 0, py::arg("alpha") = false,
             "The picture as an (H, W, 3) float32 array of linear RGB (0: the script's settings); alpha=True: (H, W, 4), "
             "RGB premultiplied by the coverage A.")
        .def("glsl", [](const PyScene& s, const std::string& target) { return translated([&] { return s.scene.glsl(target); }); },
             py::arg("target") = "shadertoy", "The scene as GLSL: 'shadertoy', 'glsl330' or 'html' (a WebGL2 page).")
        .def("mesh", &mesh, py::kw_only(), py::arg("resolution") = 256, py::arg("simplify") = 0.0f, py::arg("colors") = false,
             py::arg("bounds") = py::none(),
             "A closed mesh: {'positions': (V, 3) float32, 'triangles': (T, 3) uint32[, 'colors': (V, 3)]}.");
    m.def("compile", &compile, py::arg("source"), py::kw_only(), py::arg("name") = py::none(), py::arg("time") = 0.0f,
          py::arg("defines") = std::map<std::string, py::object>{},
          "Compiles a script (str) or a file (os.PathLike, or a str ending in .sdf or .vm). defines: {'NAME': value} "
          "as -D NAME=VALUE. Raises CompileError.");
    m.def("write_mesh", &write_mesh_file, py::arg("mesh"), py::arg("path"), "Writes a mesh() result as .stl, .obj, .ply or .3mf.");
}
