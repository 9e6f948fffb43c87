#include "compiler/base/source.hpp"

#include <pthread.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

namespace sdfc {

SourceFile::SourceFile(std::string p, std::string t) : path(std::move(p)), text(std::move(t)) {
    line_starts.push_back(0);
    for (size_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') line_starts.push_back(i + 1);
}

std::string_view SourceFile::line(uint32_t n) const {
    if (n == 0 || n > line_starts.size()) return {};
    size_t b = line_starts[n - 1];
    size_t e = n < line_starts.size() ? line_starts[n] - 1 : text.size();
    if (e > b && text[e - 1] == '\r') --e;
    return std::string_view(text).substr(b, e - b);
}

std::string format_diagnostic(const Diagnostic& d) {
    if (!d.loc.known()) return fmt::format("sdfc: error: {}\n", d.message);
    const SourceFile& file = *d.loc.file;
    uint32_t line = d.loc.line;
    std::string_view src = file.line(line);
    size_t col = std::min<size_t>(d.loc.col - 1, src.size());  // in bytes
    auto blank = [](std::string_view t) { return t.find_first_not_of(" \t\r\f\v") == std::string_view::npos; };
    // An error at the end of the file (a missing `)` or `}`) is shown after the last token,
    // not on the empty line after the last newline.
    if (line == file.line_starts.size() && line > 1 && blank(src)) {
        uint32_t l = line - 1;
        while (l > 1 && blank(file.line(l))) --l;
        std::string_view t = file.line(l);
        if (!blank(t)) {
            line = l;
            src = t;
            col = t.find_last_not_of(" \t\r\f\v") + 1;
        }
    }
    auto continuation = [&](size_t i) { return (static_cast<unsigned char>(src[i]) & 0xC0) == 0x80; };
    // Columns count characters (UTF-8 code points), not bytes.
    size_t chars = 0;
    for (size_t i = 0; i < col; ++i) chars += continuation(i) ? 0 : 1;
    std::string out = fmt::format("{}:{}:{}: error: {}\n", file.path, line, chars + 1, d.message);
    // A very long line (minified or generated text) is shown as a window around the column.
    constexpr size_t kWindow = 160;
    size_t b = 0, e = src.size();
    if (src.size() > 2 * kWindow) {
        b = col > kWindow / 2 ? col - kWindow / 2 : 0;
        while (b > 0 && continuation(b)) --b;
        e = std::min(src.size(), b + kWindow);
        while (e < src.size() && continuation(e)) ++e;
    }
    std::string_view lead = b > 0 ? "..." : "";
    out += lead;
    out += src.substr(b, e - b);
    if (e < src.size()) out += "...";
    out += '\n';
    // Keep tabs so the caret lines up in a terminal.
    out.append(lead.size(), ' ');
    for (size_t i = b; i < col; ++i)
        if (!continuation(i)) out += src[i] == '\t' ? '\t' : ' ';
    out += "^\n";
    return out;
}

static std::string first_message(const std::vector<Diagnostic>& d) {
    return d.empty() ? std::string("error") : d.front().message;
}

CompileError::CompileError(std::vector<Diagnostic> diags)
    : std::runtime_error(first_message(diags)), diags_(std::move(diags)) {
    for (const auto& d : diags_) formatted_ += format_diagnostic(d);
}

CompileError::CompileError(Loc loc, std::string message)
    : CompileError(std::vector<Diagnostic>{Diagnostic{loc, std::move(message)}}) {}

// Well-formed UTF-8 (Unicode table 3-7): no overlong forms, surrogates or code points
// above U+10FFFF.
static bool valid_utf8(std::string_view s, size_t& bad_at) {
    size_t i = 0;
    while (i < s.size()) {
        unsigned char c = static_cast<unsigned char>(s[i]);
        size_t n = c < 0x80 ? 1 : c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
        if (n == 0 || i + n > s.size()) { bad_at = i; return false; }
        unsigned char lo = 0x80, hi = 0xBF;  // the second byte's range
        if (c == 0xE0) lo = 0xA0;
        if (c == 0xED) hi = 0x9F;
        if (c == 0xF0) lo = 0x90;
        if (c == 0xF4) hi = 0x8F;
        for (size_t k = 1; k < n; ++k) {
            unsigned char b = static_cast<unsigned char>(s[i + k]);
            if (b < (k == 1 ? lo : 0x80) || b > (k == 1 ? hi : 0xBF)) { bad_at = i; return false; }
        }
        i += n;
    }
    return true;
}

const SourceFile& SourceManager::add(std::string path, std::string text) {
    files_.push_back(std::make_unique<SourceFile>(std::move(path), std::move(text)));
    return *files_.back();
}

const SourceFile& SourceManager::load(const std::string& path, Loc from, size_t max_bytes) {
    // Only regular files: opening a FIFO would block, a device may never end.
    std::error_code ec;
    auto st = std::filesystem::status(path, ec);
    if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
        throw CompileError(from, fmt::format("cannot read '{}': not a regular file", path));
    if (!ec && std::filesystem::is_regular_file(st)) {
        std::error_code sec;
        const auto size = std::filesystem::file_size(path, sec);
        if (!sec && size > max_bytes)
            throw CompileError(from, fmt::format("'{}' is {} bytes, over the limit of {} bytes (--max-file-size)", path, size, max_bytes));
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw CompileError(from, fmt::format("cannot open '{}'", path));
    // Read up to the limit rather than trust a size: /proc files say 0 and have text.
    std::string text;
    char buf[1 << 16];
    while (in.read(buf, sizeof buf) || in.gcount() > 0) {
        text.append(buf, size_t(in.gcount()));
        if (text.size() > max_bytes)
            throw CompileError(from, fmt::format("'{}' is over the limit of {} bytes (--max-file-size)", path, max_bytes));
    }
    if (in.bad()) throw CompileError(from, fmt::format("cannot read '{}'", path));
    // A UTF-8 byte-order mark is no text: columns of the first line count from after it.
    if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
    const SourceFile& f = add(path, std::move(text));
    check_source_text(f);
    return f;
}

void check_source_text(const SourceFile& f) {
    size_t nul = f.text.find('\0');
    size_t bad = 0;
    auto loc_of = [&](size_t off) {
        auto it = std::upper_bound(f.line_starts.begin(), f.line_starts.end(), off);
        uint32_t line = static_cast<uint32_t>(it - f.line_starts.begin());
        return Loc{&f, line, static_cast<uint32_t>(off - f.line_starts[line - 1] + 1)};
    };
    if (nul != std::string::npos) throw CompileError(loc_of(nul), "binary file: NUL byte in source text");
    if (!valid_utf8(f.text, bad)) throw CompileError(loc_of(bad), "invalid UTF-8 in source text");
}

std::string nearest_name(std::string_view name, const std::vector<std::string>& candidates) {
    std::string best;
    if (name.empty() || name.size() > 64) return best;  // no typo of a known name; keeps this cheap
    // Edit distance in half steps: a letter of the wrong case costs 1, any other edit 2
    // (substitution, insertion, deletion, or two neighbours swapped: `lenght`). Close enough
    // to be a typo: at most a third of the name wrong, and never all of it; ties go to the
    // first candidate.
    const size_t n = name.size();
    size_t best_d = 2 * (std::min(std::max<size_t>(1, n / 3), n - 1) + 1);
    auto lower = [](char ch) { return (ch >= 'A' && ch <= 'Z') ? char(ch - 'A' + 'a') : ch; };
    std::vector<size_t> prev2, prev, cur;
    for (const auto& c : candidates) {
        const size_t m = c.size();
        if (2 * (m > n ? m - n : n - m) >= best_d) continue;
        prev2.assign(m + 1, 0);
        prev.resize(m + 1);
        cur.resize(m + 1);
        for (size_t j = 0; j <= m; ++j) prev[j] = 2 * j;
        for (size_t i = 1; i <= n; ++i) {
            cur[0] = 2 * i;
            for (size_t j = 1; j <= m; ++j) {
                const char a = name[i - 1], b = c[j - 1];
                const size_t sub = a == b ? 0 : lower(a) == lower(b) ? 1 : 2;
                cur[j] = std::min({prev[j] + 2, cur[j - 1] + 2, prev[j - 1] + sub});
                if (i > 1 && j > 1 && a == c[j - 2] && name[i - 2] == b) cur[j] = std::min(cur[j], prev2[j - 2] + 2);
            }
            std::swap(prev2, prev);
            std::swap(prev, cur);
        }
        if (prev[m] < best_d) {
            best_d = prev[m];
            best = c;
        }
    }
    return best;
}

namespace {

// The lowest usable address of this thread's stack (0 when unknown: no check).
uintptr_t stack_low() {
    thread_local const uintptr_t low = [] {
        pthread_attr_t a;
        if (pthread_getattr_np(pthread_self(), &a) != 0) return uintptr_t(0);
        void* addr = nullptr;
        size_t size = 0;
        int r = pthread_attr_getstack(&a, &addr, &size);
        pthread_attr_destroy(&a);
        return r == 0 ? reinterpret_cast<uintptr_t>(addr) : uintptr_t(0);
    }();
    return low;
}

}  // namespace

bool stack_nearly_exhausted() {
    // Far more than any stage uses between two checks (or to throw and unwind), even
    // with sanitizers' larger frames.
    constexpr uintptr_t kMargin = 512u << 10;
    const uintptr_t low = stack_low();
    const auto here = reinterpret_cast<uintptr_t>(__builtin_frame_address(0));
    return low != 0 && here < low + kMargin;
}

// Sanitizer builds cap the stack of a thread of its own:
// - AddressSanitizer: at most 48 MB. An exception thrown with more than 64 MB of stack in
//   use leaves the stack poisoned (ASan's __asan_handle_no_return gives up), and the
//   unwinding reports false errors.
// - ThreadSanitizer: at most 8 MB. It stops the program ("CHECK failed ... kStackSizeBits")
//   when it records a stack of more than 65,536 frames; 8 MB holds about 40,000 of the
//   parser's (about 200 bytes each).
#if defined(__SANITIZE_ADDRESS__)
#define SDFC_STACK_ASAN 1
#elif defined(__SANITIZE_THREAD__)
#define SDFC_STACK_TSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFC_STACK_ASAN 1
#elif __has_feature(thread_sanitizer)
#define SDFC_STACK_TSAN 1
#endif
#endif

size_t max_thread_stack() {
#if defined(SDFC_STACK_ASAN)
    return 48u << 20;
#elif defined(SDFC_STACK_TSAN)
    return 8u << 20;
#else
    return size_t(4) << 30;
#endif
}

namespace {
void* run_function(void* p) {
    (*static_cast<const std::function<void()>*>(p))();
    return nullptr;
}
}  // namespace

bool run_on_new_stack(size_t bytes, const std::function<void()>& fn) {
    pthread_attr_t attr;
    if (pthread_attr_init(&attr) != 0) return false;
    pthread_t t;
    bool started = pthread_attr_setstacksize(&attr, bytes) == 0 &&
                   pthread_create(&t, &attr, run_function, const_cast<std::function<void()>*>(&fn)) == 0;
    pthread_attr_destroy(&attr);
    if (started) pthread_join(t, nullptr);
    return started;
}

void check_stack(Loc loc) {
    if (stack_nearly_exhausted())
        throw CompileError(loc, "nested too deeply: the C++ stack is nearly exhausted (simplify the script, "
                                "or run with a larger stack: ulimit -s)");
}

}  // namespace sdfc
