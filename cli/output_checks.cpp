#include "cli/output_checks.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "cli/args.hpp"
#include "runtime/io/image.hpp"
#include "runtime/eval/vm.hpp"

namespace sdfc::cli {

namespace fs = std::filesystem;

bool is_exr(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e == ".exr";
}

namespace {

bool same_file(const std::string& a, const std::string& b) {
    std::error_code ec;
    return fs::equivalent(a, b, ec) && !ec;  // false when either does not exist
}

}  // namespace

void check_picture_output(const std::string& out, const std::string& format) {
    try {
        check_image_output(out, format);
    } catch (const UsageError&) {
        throw;
    } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        // An extension that names no image format is the command line's mistake (exit 2, as
        // mesh's); a folder that is missing or read-only is not.
        if (out != "-" && (m.find("': unknown image format '") != std::string::npos ||
                           m.find("': no extension to choose the image format") != std::string::npos))
            throw UsageError(m);
        if (out != "-") throw;
        const size_t at = m.find("': ");
        throw UsageError(fmt::format("--format {}: {}", format, at == std::string::npos ? m : m.substr(at + 3)));
    }
}

void check_not_input(const std::string& out, const std::string& scene) {
    if (same_file(out, scene)) throw std::runtime_error(fmt::format("cannot write '{}': it is the scene file '{}'", out, scene));
}

void check_not_input(const std::string& out, const SourceManager& sm) {
    const std::vector<std::string> paths = sm.paths();
    for (size_t i = 0; i < paths.size(); ++i)
        if (same_file(out, paths[i]))
            throw std::runtime_error(i == 0 ? fmt::format("cannot write '{}': it is the scene file '{}'", out, paths[i])
                                            : fmt::format("cannot write '{}': the scene imports it ('{}')", out, paths[i]));
}

void InputFiles::add(const std::string& path, bool scene) {
    struct stat st {};
    if (path == "-" || ::stat(path.c_str(), &st) != 0) return;
    for (const Id& id : ids_)
        if (id.dev == st.st_dev && id.ino == st.st_ino) return;
    ids_.push_back(Id{st.st_dev, st.st_ino, path, scene});
}

void InputFiles::check(const std::string& out) const {
    struct stat st {};
    if (ids_.empty() || out == "-" || ::stat(out.c_str(), &st) != 0) return;
    for (const Id& id : ids_)
        if (id.dev == st.st_dev && id.ino == st.st_ino)
            throw std::runtime_error(id.scene ? fmt::format("cannot write '{}': it is the scene file '{}'", out, id.path)
                                              : fmt::format("cannot write '{}': a scene imports it ('{}')", out, id.path));
}

std::string read_bounded(const std::string& path, size_t max_bytes) {
    const bool in = path == "-";
    const std::string what = in ? "standard input" : "'" + path + "'";
    FILE* f = stdin;
    if (!in) {
        struct stat st {};
        if (::stat(path.c_str(), &st) != 0) throw std::runtime_error(fmt::format("cannot read {}: {}", what, std::strerror(errno)));
        if (S_ISDIR(st.st_mode)) throw std::runtime_error(fmt::format("cannot read {}: {}", what, std::strerror(EISDIR)));
        f = std::fopen(path.c_str(), "rb");
        if (!f) throw std::runtime_error(fmt::format("cannot read {}: {}", what, std::strerror(errno)));
    }
    auto close = [&] {
        if (!in) std::fclose(f);
    };
    std::string data;
    char buf[1 << 16];
    for (;;) {
        size_t n = std::fread(buf, 1, sizeof buf, f);
        data.append(buf, n);
        if (data.size() > max_bytes) {
            close();
            throw std::runtime_error(fmt::format("{} is over the limit of {} bytes (raise it with --max-file-size)", what, max_bytes));
        }
        if (n < sizeof buf) break;
    }
    const bool failed = std::ferror(f);
    const int err = errno;
    close();
    if (failed) throw std::runtime_error(fmt::format("cannot read {}: {}", what, std::strerror(err)));
    return data;
}

void report_stdout_error(int err) {
    static bool reported = false;
    if (reported) return;
    reported = true;
    std::fprintf(stderr, "sdfc: error: cannot write to standard output: %s\n", err ? std::strerror(err) : "write error");
}

void write_stdout(std::string_view text) {
    errno = 0;
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size()) report_stdout_error(errno);
}

namespace {

bool has_user_field(const Shape& s) {
    if (s.kind == ShapeKind::Field) return true;
    for (const auto& c : s.children)
        if (c && has_user_field(*c)) return true;
    return false;
}

Loc first_known(const Shape& s) {
    if (s.loc.known()) return s.loc;
    for (const auto& c : s.children)
        if (c) {
            Loc l = first_known(*c);
            if (l.known()) return l;
        }
    return {};
}

}  // namespace

static void check_finite_at(const Scene& s, const Program& distance, const std::vector<glm::vec3>& at, float time) {
    if (s.raw_field || !s.root || has_user_field(*s.root) || distance.outputs.empty()) return;
    Evaluator ev(distance);
    float d0 = 0.0f;
    for (size_t i = 0; i < at.size(); ++i) {
        float d = ev.eval1(at[i].x, at[i].y, at[i].z, time);
        if (!std::isnan(d) && d > -INFINITY) return;  // +inf is an empty scene: nothing anywhere
        if (i == 0) d0 = d;
    }
    throw CompileError(first_known(*s.root),
                       fmt::format("the scene's distance is not a number ({} at the origin and at the camera): "
                                   "a size or a scale overflows",
                                   d0));
}

void check_field_finite(const Scene& s, const CompiledScene& cs) {
    check_finite_at(s, cs.distance, {glm::vec3(0.0f), cs.camera.position, cs.camera.target}, cs.time);
}

void check_field_finite(const Scene& s, const Program& distance, const std::vector<glm::vec3>& at) {
    // (a shape sized by `time` may be fine later on: `sphere(1 / time)`)
    if (distance.uses_time) return;
    // A shader's params (uniforms, which the VM reads as 0) at the values the page starts with.
    Program p = distance;
    for (Instr& in : p.code)
        if (in.op == Op::Param) {
            const size_t k = static_cast<size_t>(in.k);
            in.op = Op::Const;
            in.k = k < s.params.size() ? s.params[k].value : 0.0f;
        }
    check_finite_at(s, p, at, 0.0f);
}

}  // namespace sdfc::cli
