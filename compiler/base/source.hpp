// Source files, locations and diagnostics: every stage reports through these, so any
// error a script causes reads `path:line:col: error: message`, the line, and a caret.
#pragma once
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "compiler/base/names.hpp"  // nearest_name (did you mean), for the callers of diagnostics
#include "compiler/base/stack.hpp"  // check_stack, run_on_new_stack, for the recursive stages

namespace sdfc {

struct SourceFile {
    std::string path;   // as the user named it (or as resolved for imports)
    std::string text;
    std::vector<size_t> line_starts;  // offset of each line's first byte

    SourceFile(std::string path, std::string text);
    std::string_view line(uint32_t n) const;  // 1-based, without the newline
};

// A point in a script. Cheap to copy; the file outlives every Loc (SourceManager owns it).
struct Loc {
    const SourceFile* file = nullptr;
    uint32_t line = 0;  // 1-based; 0 = unknown
    uint32_t col = 0;   // 1-based, in bytes
    bool known() const { return file != nullptr && line != 0; }
};

struct Diagnostic {
    Loc loc;
    std::string message;
};

// A number as a diagnostic shows it: "nan" for any NaN (fmt writes "-nan" when its sign bit
// is set, which means nothing to a user), "inf", "-inf", else fmt's shortest form.
std::string shown_number(float v);

// `path:line:col: error: message`, the source line, a caret under the column.
std::string format_diagnostic(const Diagnostic& d, const char* kind = "error");  // or "warning"

// Thrown by any stage for errors the user caused. Holds one or more diagnostics.
class CompileError : public std::runtime_error {
public:
    explicit CompileError(std::vector<Diagnostic> diags);
    CompileError(Loc loc, std::string message);
    // Locations point into files that may be gone once the error has propagated out of
    // the stage that loaded them: use them only while that stage is alive.
    const std::vector<Diagnostic>& diagnostics() const { return diags_; }
    // All diagnostics, each formatted, joined; rendered when thrown, so always safe.
    const std::string& formatted() const { return formatted_; }

private:
    std::vector<Diagnostic> diags_;
    std::string formatted_;
};

// Throws CompileError at the first NUL byte (a binary file) or invalid UTF-8 sequence.
void check_source_text(const SourceFile& f);
// Well-formed UTF-8; else false, with the offset of the first bad byte.
bool valid_utf8(std::string_view s, size_t& bad_at);

// Owns every loaded file so Locs stay valid for the whole compilation.
// Every path SourceManager::load or load_stdin was asked for (by any manager) since the
// last call: the files `sdfc watch` watches (a scene and all it imports).
std::vector<std::string> take_loaded_paths();

// The texts of the files a command read, by path: managers that share one (the frames and
// scenes of a render batch) read each file once, so a save during the batch cannot mix two
// versions of a script into one animation.
struct SourceSnapshot {
    std::mutex m;
    std::map<std::string, std::string> texts;
};

class SourceManager {
public:
    SourceManager() = default;
    explicit SourceManager(std::shared_ptr<SourceSnapshot> snapshot) : snapshot_(std::move(snapshot)) {}
    // Reads a file (or takes its text from the snapshot); throws CompileError at `from` (the
    // import or command line) on failure, or for binary/invalid UTF-8 content or a file over
    // `max_bytes`.
    const SourceFile& load(const std::string& path, Loc from = {}, size_t max_bytes = 16u << 20);
    const SourceFile& add(std::string path, std::string text);
    // The script on standard input, as "<stdin>" (its imports are relative to the working
    // folder), with load's checks. Standard input is read once per process: later calls
    // (a scene compiled again per frame) get the same text.
    const SourceFile& load_stdin(size_t max_bytes = 16u << 20);
    // The path of every file loaded or added so far, the first one first (cli/: an output
    // must not overwrite one of them).
    std::vector<std::string> paths() const {
        std::vector<std::string> out;
        for (const auto& f : files_) out.push_back(f->path);
        return out;
    }

private:
    std::string read(const std::string& path, Loc from, size_t max_bytes);
    std::deque<std::unique_ptr<SourceFile>> files_;
    std::shared_ptr<SourceSnapshot> snapshot_;
};

}  // namespace sdfc
