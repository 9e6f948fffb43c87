// Writing output files safely. A regular file is written to a temporary file in its folder,
// every write, the fsync and the close checked, then renamed over the target: a full disk,
// a crash, a kill or an interrupt never leaves a partial file and an existing output is
// replaced only by a complete one. A symlink keeps being a link (its target is replaced);
// a character device or FIFO is written through, the way Unix tools do; anything else that
// is not a regular file (a directory, a socket) is refused. Every error names the user's
// path and the OS reason: "cannot write 'PATH': REASON". The path "-" is standard output.
#pragma once
#include <memory>
#include <string>
#include <string_view>

namespace sdfc {

// Where the bytes for a user's output path go (resolve_output).
struct OutputTarget {
    std::string path;            // as the user named it: every message names this
    std::string file;            // the regular file to replace (a symlink resolved), or the node written through
    bool write_through = false;  // a character device or a FIFO: opened and written, never replaced
    bool exists = false;         // `file` exists (a regular file keeps its permission bits)
    unsigned mode = 0;
};

// Checks a path can be written before any work is done: its folder exists and is writable,
// it is not a directory or another node that cannot be written. Throws std::runtime_error.
OutputTarget resolve_output(const std::string& path);

// A temporary name beside `target` ("dir/.out.tmp-<pid>-<n>.png"), the extension kept and
// the stem shortened so the name stays within NAME_MAX however long the target's name is.
std::string temp_path_for(const std::string& target);

// Writes `bytes` to `path` as described at the top. Throws std::runtime_error.
void write_file(const std::string& path, std::string_view bytes);
// Two files that go together (a shader and the tape it loads): both are written to their
// temporary files before either appears, so a failure leaves neither. `first` appears
// first, unless only `second` is written through (a device, a FIFO, standard output),
// which can fail late: then it goes first.
void write_files(const std::string& first, std::string_view first_bytes, const std::string& second, std::string_view second_bytes);
// Text (GLSL, HTML): write_file under another name.
void write_text_file(const std::string& path, const std::string& text);

// "cannot write 'PATH': REASON", with the temporary name (if any) replaced by PATH in REASON.
std::string write_error(const std::string& path, std::string reason, const std::string& temp = "");

// A temporary file that is removed when this goes out of scope (unless kept) and, while it
// lives, by the SIGINT/SIGTERM/SIGHUP/SIGQUIT/SIGPIPE handlers of install_temp_cleanup().
class TempFile {
public:
    explicit TempFile(std::string path);
    ~TempFile();
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    const std::string& path() const { return path_; }
    void keep();  // renamed away: nothing to remove any more

private:
    std::string path_;
    int slot_ = -1;
    bool keep_ = false;
};

// write_file in two steps: the constructor writes the bytes to a temporary file beside the
// target (or, for a node written through and standard output, only checks the path and
// keeps the bytes); commit() renames it over the target (or writes them through). A staged
// file never committed leaves nothing. Both throw std::runtime_error.
class StagedFile {
public:
    StagedFile(const std::string& path, std::string_view bytes);
    ~StagedFile();
    StagedFile(const StagedFile&) = delete;
    StagedFile& operator=(const StagedFile&) = delete;
    void commit();
    bool written_through() const { return through_; }

private:
    std::string path_;
    OutputTarget target_;
    bool through_ = false;
    std::string_view bytes_;  // (written through: the caller's, alive until commit)
    std::unique_ptr<TempFile> tmp_;
};

// Installs the signal handlers that remove live temporary files before the process dies of
// the signal (re-raised with its default action), and makes a file over the size limit
// (SIGXFSZ) a write error instead of a kill. Call once, early in main.
void install_temp_cleanup();

}  // namespace sdfc
