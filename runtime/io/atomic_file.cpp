#include "runtime/io/atomic_file.hpp"

#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <thread>

namespace sdfc {

namespace fs = std::filesystem;

namespace {

// ---- the registry of live temporary files, read by the signal handler ----
// Fixed buffers and atomics only: the handler may run at any moment, on any thread.
constexpr int kSlots = 64;
char g_temp_path[kSlots][PATH_MAX];
std::atomic<int> g_temp_state[kSlots];  // 0 free, 1 being filled, 2 live

int register_temp(const std::string& path) {
    if (path.size() >= PATH_MAX) return -1;
    for (int i = 0; i < kSlots; ++i) {
        int expect = 0;
        if (!g_temp_state[i].compare_exchange_strong(expect, 1)) continue;
        std::memcpy(g_temp_path[i], path.c_str(), path.size() + 1);
        g_temp_state[i].store(2);
        return i;
    }
    return -1;  // more live temporaries than slots: still removed on every ordinary path
}

void unregister_temp(int slot) {
    if (slot >= 0) g_temp_state[slot].store(0);
}

extern "C" void remove_temps_and_die(int sig) {
    for (int i = 0; i < kSlots; ++i)
        if (g_temp_state[i].load() == 2) ::unlink(g_temp_path[i]);
    ::signal(sig, SIG_DFL);
    ::raise(sig);  // delivered when the handler returns: the process ends as the signal says
}

std::string os_reason(int err) { return std::strerror(err); }

[[noreturn]] void fail(const std::string& path, const std::string& reason) { throw std::runtime_error(write_error(path, reason)); }

// Every byte, or the OS reason (a full disk: "No space left on device").
void write_all(int fd, const char* p, size_t n, const std::string& path) {
    while (n > 0) {
        ssize_t w = ::write(fd, p, n < (size_t(1) << 30) ? n : (size_t(1) << 30));
        if (w < 0) {
            if (errno == EINTR) continue;
            fail(path, os_reason(errno));
        }
        if (w == 0) fail(path, "the device took no more bytes");
        p += w;
        n -= size_t(w);
    }
}

// Test hook (tests/cli/test_output_safety.cpp): hold the temporary file open this long, so
// a signal can be sent while it exists. Off unless the environment asks for it.
void test_delay() {
    if (const char* ms = std::getenv("SDFC_TEST_WRITE_DELAY_MS"))
        std::this_thread::sleep_for(std::chrono::milliseconds(std::atoi(ms)));
}

}  // namespace

std::string write_error(const std::string& path, std::string reason, const std::string& temp) {
    if (!temp.empty())
        for (size_t p; (p = reason.find(temp)) != std::string::npos;) reason.replace(p, temp.size(), path);
    while (!reason.empty() && (reason.back() == '\n' || reason.back() == ' ' || reason.back() == '.')) reason.pop_back();
    if (reason.empty()) reason = "unknown error";
    return "cannot write '" + path + "': " + reason;
}

TempFile::TempFile(std::string path) : path_(std::move(path)), slot_(register_temp(path_)) {}

TempFile::~TempFile() {
    if (!keep_) ::unlink(path_.c_str());
    unregister_temp(slot_);
}

void TempFile::keep() {
    keep_ = true;
    unregister_temp(slot_);
    slot_ = -1;
}

void install_temp_cleanup() {
    struct sigaction sa {};
    sa.sa_handler = remove_temps_and_die;
    sigemptyset(&sa.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE}) {
        struct sigaction old {};
        // A signal the parent set to be ignored (nohup, a shell's background job) stays ignored.
        if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        ::sigaction(sig, &sa, nullptr);
    }
    ::signal(SIGXFSZ, SIG_IGN);  // over `ulimit -f`: write() fails with EFBIG, reported like a full disk
}

std::string temp_path_for(const std::string& target) {
    static std::atomic<unsigned> counter{0};
    fs::path t(target);
    const std::string ext = t.extension().string();
    std::string stem = t.stem().string();
    const std::string tag = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    // "." + stem + tag + ext must fit in one directory entry.
    const size_t fixed = 1 + tag.size() + (ext.size() < 64 ? ext.size() : 0);
    if (stem.size() + fixed > NAME_MAX) stem.resize(NAME_MAX > fixed ? NAME_MAX - fixed : 0);
    const std::string name = "." + stem + tag + (ext.size() < 64 ? ext : std::string());
    return (t.parent_path() / name).string();
}

OutputTarget resolve_output(const std::string& path) {
    OutputTarget t;
    t.path = t.file = path;
    if (path.empty()) fail(path, "the output path is empty");
    if (path == "-") {  // standard output, written through
        t.write_through = true;
        return t;
    }
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
        // The link stays a link: what it points to is written (created if it dangles).
        fs::path p(path);
        for (int hops = 0; ::lstat(p.c_str(), &st) == 0 && S_ISLNK(st.st_mode); ++hops) {
            std::error_code ec;
            fs::path to = fs::read_symlink(p, ec);
            if (ec) fail(path, os_reason(ec.value()));
            if (hops == 40) fail(path, os_reason(ELOOP));
            p = (to.is_absolute() ? to : p.parent_path() / to).lexically_normal();
        }
        t.file = p.string();
    }
    if (::stat(t.file.c_str(), &st) == 0) {
        t.exists = true;
        t.mode = unsigned(st.st_mode & 07777);
        if (S_ISDIR(st.st_mode)) fail(path, os_reason(EISDIR));
        if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) {
            t.write_through = true;
            if (::access(t.file.c_str(), W_OK) != 0) fail(path, os_reason(errno));
            return t;
        }
        if (!S_ISREG(st.st_mode)) fail(path, "not a regular file, a character device or a FIFO");
        if (::access(t.file.c_str(), W_OK) != 0) fail(path, os_reason(errno));
    } else if (errno != ENOENT) {
        fail(path, os_reason(errno));
    }
    // A new or replaced file: its folder must exist and take new entries.
    fs::path dir = fs::path(t.file).parent_path();
    const std::string d = dir.empty() ? std::string(".") : dir.string();
    if (::stat(d.c_str(), &st) != 0) fail(path, "folder '" + d + "': " + os_reason(errno));
    if (!S_ISDIR(st.st_mode)) fail(path, "'" + d + "' is not a folder");
    if (::access(d.c_str(), W_OK | X_OK) != 0) fail(path, "folder '" + d + "': " + os_reason(errno));
    return t;
}

namespace {
void write_stdout_bytes(std::string_view bytes) {
    // After what the program printed there itself.
    std::fflush(stdout);
    try {
        write_all(STDOUT_FILENO, bytes.data(), bytes.size(), "-");
    } catch (const std::runtime_error& e) {
        const std::string what = e.what(), prefix = "cannot write '-': ";
        throw std::runtime_error("cannot write to standard output: " + (what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what));
    }
}
}  // namespace

StagedFile::StagedFile(const std::string& path, std::string_view bytes) : path_(path) {
    if (path == "-") {
        through_ = true;
        bytes_ = bytes;
        return;
    }
    target_ = resolve_output(path);
    if (target_.write_through) {
        through_ = true;
        bytes_ = bytes;
        return;
    }
    tmp_ = std::make_unique<TempFile>(temp_path_for(target_.file));
    int fd = ::open(tmp_->path().c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) fail(path, os_reason(errno));
    try {
        test_delay();
        write_all(fd, bytes.data(), bytes.size(), path);
        if (target_.exists) (void)::fchmod(fd, target_.mode);  // a replaced file keeps its permissions
        // The data must be on the disk before the rename makes it the output (some file
        // systems report a full disk only here).
        if (::fsync(fd) != 0 && errno != EINVAL) fail(path, os_reason(errno));
    } catch (...) {
        ::close(fd);
        throw;
    }
    if (::close(fd) != 0 && errno != EINTR) fail(path, os_reason(errno));
}

StagedFile::~StagedFile() = default;

void StagedFile::commit() {
    if (path_ == "-") return write_stdout_bytes(bytes_);
    if (through_) {
        int fd = ::open(target_.file.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
        if (fd < 0) fail(path_, os_reason(errno));
        try {
            write_all(fd, bytes_.data(), bytes_.size(), path_);
        } catch (...) {
            ::close(fd);
            throw;
        }
        if (::close(fd) != 0 && errno != EINTR) fail(path_, os_reason(errno));
        return;
    }
    if (::rename(tmp_->path().c_str(), target_.file.c_str()) != 0) fail(path_, os_reason(errno));
    tmp_->keep();
    // The rename itself to the disk; a folder that cannot be synced is no error.
    fs::path dir = fs::path(target_.file).parent_path();
    int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)::fsync(dfd);
        ::close(dfd);
    }
}

void write_file(const std::string& path, std::string_view bytes) { StagedFile(path, bytes).commit(); }

void write_files(const std::string& first, std::string_view first_bytes, const std::string& second, std::string_view second_bytes) {
    StagedFile a(first, first_bytes), b(second, second_bytes);
    // A node written through can still fail after a rename could no longer be taken back:
    // it goes first, then the renames, which fail only if the folder changed meanwhile.
    if (b.written_through() && !a.written_through()) {
        b.commit();
        a.commit();
    } else {
        a.commit();
        b.commit();
    }
}

void write_text_file(const std::string& path, const std::string& text) { write_file(path, text); }

}  // namespace sdfc
