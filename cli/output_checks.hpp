// The checks a command makes around its work so no output is lost or misreported: an output
// that would overwrite the scene or a file it imports, an input read without bound, standard
// output that could not be written, a scene whose distance overflowed to infinity.
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "compiler/base/source.hpp"
#include "compiler/bytecode/compile.hpp"

namespace sdfc::cli {

bool is_exr(const std::string& path);

// Throws std::runtime_error "cannot write 'OUT': ..." when `out` is the scene file, or (with
// the SourceManager of the loaded scene) any file the scene read.
// check_image_output, where a bad --format for standard output (-o - --format stl) is a
// command-line error (exit 2) rather than a write to a made-up file's name.
void check_picture_output(const std::string& out, const std::string& format);
void check_not_input(const std::string& out, const std::string& scene);
void check_not_input(const std::string& out, const SourceManager& sm);

// The files a batch reads (every scene, every import), by identity (device and inode): an
// output of any picture must be none of them.
class InputFiles {
public:
    void add(const std::string& path, bool scene);  // a file that is not there is no input
    void check(const std::string& out) const;         // the std::runtime_error of check_not_input

private:
    struct Id {
        unsigned long long dev, ino;
        std::string path;
        bool scene;
    };
    std::vector<Id> ids_;
};

// The whole file ("-": standard input), at most `max_bytes` of it (a device like /dev/zero
// never ends); a clear error for a directory, a missing or unreadable file, or one over the limit.
std::string read_bounded(const std::string& path, size_t max_bytes);

// Standard output: written here, any failure reported (once) as
// `sdfc: error: cannot write to standard output: REASON`; main exits 1 then.
void write_stdout(std::string_view text);
void report_stdout_error(int err);

// A scene made of the built-in shapes whose distance is NaN or -infinity at the origin,
// the camera or its target (`scale(1e38) sphere(1e38)`: -inf everywhere) is an error at the
// scene's first shape. A user's `field` and a .vm model may compute what they like.
void check_field_finite(const Scene& s, const CompiledScene& cs);
// The same for a distance program and the points to try (sdfc glsl: the origin, and the
// camera where it does not move), when the program does not depend on `time`.
void check_field_finite(const Scene& s, const Program& distance, const std::vector<glm::vec3>& at);

}  // namespace sdfc::cli
