// Batch at cluster scale: which frames this task renders (--shard, from the flag or from a
// Slurm job array's or a Kubernetes Indexed Job's variables), one band of a picture
// (--tiles), and `sdfc merge`, which puts the bands together again.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>

#include <fmt/format.h>

#include "cli/common.hpp"
#include "cli/output_checks.hpp"
#include "runtime/io/image.hpp"

namespace sdfc::cli {
namespace {

std::optional<long> env_number(const char* name) {
    const char* v = std::getenv(name);
    if (!v || !*v) return std::nullopt;
    char* end = nullptr;
    const long x = std::strtol(v, &end, 10);
    if (*end != '\0') throw UsageError(fmt::format("{}={} is not a whole number", name, v));
    return x;
}

// I/N as two numbers, 0 <= I < N.
std::pair<int, int> index_of_count(const std::string& flag, const std::string& v) {
    const size_t slash = v.find('/');
    if (slash == std::string::npos) throw UsageError(fmt::format("{} takes I/N (this task's index and the count), not '{}'", flag, v));
    (void)Args::to_int(flag, v.substr(0, slash), 0, 1000000000);  // (a bad I is named before N)
    const int n = Args::to_int(flag, v.substr(slash + 1), 1, 1000000000);
    const int i = Args::to_int(flag, v.substr(0, slash), 0, n - 1);
    return {i, n};
}

// The scheduler's index and count, or nothing when no scheduler set them.
std::optional<Shard> scheduler_shard() {
    if (auto id = env_number("SLURM_ARRAY_TASK_ID")) {
        const long lo = env_number("SLURM_ARRAY_TASK_MIN").value_or(0), step = std::max(1L, env_number("SLURM_ARRAY_TASK_STEP").value_or(1));
        std::optional<long> count = env_number("SLURM_ARRAY_TASK_COUNT");
        if (!count)
            if (auto hi = env_number("SLURM_ARRAY_TASK_MAX")) count = (*hi - lo) / step + 1;
        if (!count) throw UsageError("SLURM_ARRAY_TASK_ID is set but not SLURM_ARRAY_TASK_COUNT: the shard count cannot be known (give --shard I/N)");
        const long index = (*id - lo) / step;
        if (index < 0 || index >= *count)
            throw UsageError(fmt::format("SLURM_ARRAY_TASK_ID={} is outside the array's {} tasks", *id, *count));
        return Shard{int(index), int(*count), "SLURM_ARRAY_TASK_ID"};
    }
    if (auto index = env_number("JOB_COMPLETION_INDEX")) {
        auto count = env_number("SDFC_SHARD_COUNT");
        if (!count)
            throw UsageError("JOB_COMPLETION_INDEX is set but not the Job's completions: the shard count cannot be known "
                             "(set SDFC_SHARD_COUNT to the completions, or give --shard I/N)");
        if (*count < 1 || *index < 0 || *index >= *count)
            throw UsageError(fmt::format("JOB_COMPLETION_INDEX={} is outside SDFC_SHARD_COUNT={}", *index, *count));
        return Shard{int(*index), int(*count), "JOB_COMPLETION_INDEX"};
    }
    return std::nullopt;
}

}  // namespace

Shard read_shard(const std::optional<std::string>& flag, size_t items) {
    if (flag && *flag != "auto") {
        auto [i, n] = index_of_count("--shard", *flag);
        return Shard{i, n, ""};
    }
    std::optional<Shard> s = scheduler_shard();
    if (flag && !s) throw UsageError("--shard auto: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set");
    // Under a scheduler without the flag: a batch is shared out, one picture is not.
    if (!s || (!flag && items <= 1)) return Shard{};
    return *s;
}

std::optional<std::pair<int, int>> read_bands(const std::optional<std::string>& flag) {
    if (!flag) return std::nullopt;
    return index_of_count("--tiles", *flag);
}

std::string picture_id(const CompiledScene& cs, const RenderOptions& ro) {
    uint64_t h = 1469598103934665603ull;  // FNV-1a
    auto bytes = [&](const void* p, size_t n) {
        for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
    };
    auto value = [&](const auto& v) { bytes(&v, sizeof v); };
    for (const Program* p : {&cs.distance, &cs.shading}) {
        bytes(p->code.data(), p->code.size() * sizeof(Instr));
        bytes(p->outputs.data(), p->outputs.size() * sizeof(p->outputs[0]));
    }
    value(cs.camera.position), value(cs.camera.target), value(cs.camera.up), value(cs.camera.fov), value(cs.camera.orthographic);
    value(cs.camera.ortho_height);
    for (const ResolvedLight& l : cs.lights) value(l.position), value(l.direction), value(l.color), value(l.intensity), value(l.radius);
    value(cs.ambient), value(cs.background), value(cs.time);
    const RenderSettings& r = cs.render;
    value(r.width), value(r.height), value(r.samples), value(r.max_steps), value(r.max_bounces), value(r.max_distance), value(r.epsilon);
    value(r.shadows), value(r.ao), value(r.exposure);
    bytes(r.aa.data(), r.aa.size()), bytes(r.tonemap.data(), r.tonemap.size());
    value(ro.alpha), value(ro.view), value(ro.bands), value(ro.baseline);
    for (const std::string& a : ro.aovs) bytes(a.data(), a.size() + 1);
    return fmt::format("{:016x}", h);
}

int cmd_merge(Args& a) {
    auto out = a.value("-o", "--output");
    auto format = a.value("--format");
    const bool quiet = a.flag("--quiet") | a.flag("-q");  // (both read: either may be given, or both)
    const std::vector<std::string> parts = a.positionals();
    if (parts.empty()) throw UsageError("merge needs the bands: sdfc merge PART.exr... -o OUT");
    if (!out) throw UsageError("merge needs -o OUT");
    std::string fmt_ext;
    if (*out == "-") {
        if (!format) throw UsageError("-o - (standard output) needs --format (png, exr, ...)");
        fmt_ext = *format;
    } else if (format) {
        throw UsageError(fmt::format("--format is for -o - (standard output); the extension of '{}' names its format", *out));
    }
    check_picture_output(*out, fmt_ext);
    for (const std::string& p : parts)
        if (std::error_code ec; std::filesystem::equivalent(*out, p, ec) && !ec)
            throw std::runtime_error(fmt::format("cannot write '{}': it is one of the bands merged ('{}')", *out, p));
    std::vector<Image> bands;
    for (const std::string& p : parts) {
        bands.push_back(read_image(p));
        if (bands.back().full_height == 0) throw std::runtime_error(fmt::format("'{}' is a whole picture, not a band of one (render --tiles I/N)", p));
    }
    std::vector<size_t> order(bands.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t x, size_t y) { return bands[x].row0 < bands[y].row0; });
    const Image& first = bands[order[0]];
    // The bands agree and cover the picture's rows before the picture is made: a header
    // claiming a million rows makes nothing until the bands hold them.
    int next = 0;  // the first row not yet filled
    for (size_t k : order) {
        const Image& b = bands[k];
        const std::string& name = parts[k];
        if (b.picture != first.picture)
            throw std::runtime_error(fmt::format("'{}' is a band of another picture than '{}' (another scene, frame, setting, AOV or N of --tiles I/N)", name,
                                                 parts[order[0]]));
        if (b.width != first.width || b.full_height != first.full_height || b.channels != first.channels || b.aovs.size() != first.aovs.size())
            throw std::runtime_error(fmt::format("'{}' is a band of another picture ({}x{}, {} channels) than '{}' ({}x{}, {} channels)", name,
                                                 b.width, b.full_height, b.channels, parts[order[0]], first.width, first.full_height, first.channels));
        for (size_t i = 0; i < b.aovs.size(); ++i)
            if (b.aovs[i].name != first.aovs[i].name) throw std::runtime_error(fmt::format("'{}' has other planes than the first band", name));
        if (b.row0 != next)
            throw std::runtime_error(b.row0 > next ? fmt::format("rows {} to {} are in none of the bands", next, b.row0 - 1)
                                                   : fmt::format("'{}' overlaps another band (rows {} to {})", name, b.row0, next - 1));
        next = b.row0 + b.height;
    }
    if (next != first.full_height) throw std::runtime_error(fmt::format("rows {} to {} are in none of the bands", next, first.full_height - 1));
    Image img(first.width, first.full_height, first.channels);
    for (const AovPlane& p : first.aovs)
        img.aovs.push_back(AovPlane{p.name, p.channels, std::vector<float>(size_t(img.width) * img.height * size_t(p.channels))});
    for (size_t k : order) {
        const Image& b = bands[k];
        std::copy(b.pixels.begin(), b.pixels.end(), img.pixels.begin() + std::ptrdiff_t(size_t(b.row0) * img.width * img.channels));
        for (size_t i = 0; i < img.aovs.size(); ++i) {
            const size_t at = size_t(b.row0) * img.width * size_t(b.aovs[i].channels);
            std::copy(b.aovs[i].data.begin(), b.aovs[i].data.end(), img.aovs[i].data.begin() + std::ptrdiff_t(at));
        }
    }
    write_image(*out, img, WriteOptions{true, fmt_ext});
    if (!quiet)
        std::fprintf(stderr, "sdfc: wrote %s (%dx%d from %zu band%s)\n", *out == "-" ? "standard output" : out->c_str(), img.width, img.height,
                     bands.size(), bands.size() == 1 ? "" : "s");
    return 0;
}

}  // namespace sdfc::cli
