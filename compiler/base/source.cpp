#include "compiler/base/source.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include <mutex>
#include <optional>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

namespace sdfc {

SourceFile::SourceFile(std::string p, std::string t) : path(std::move(p)), text(std::move(t)) {
    line_starts.push_back(0);
    for (size_t i = 0; i < text.size(); ++i) {
        // A lone CR (classic Mac OS line ends) ends a line as editors show it; the grammar
        // knows "\n" and "\r\n" only, and a // comment would run to the file's end.
        if (text[i] == '\r' && (i + 1 == text.size() || text[i + 1] != '\n')) text[i] = '\n';
        if (text[i] == '\n') line_starts.push_back(i + 1);
    }
}

std::string_view SourceFile::line(uint32_t n) const {
    if (n == 0 || n > line_starts.size()) return {};
    size_t b = line_starts[n - 1];
    size_t e = n < line_starts.size() ? line_starts[n] - 1 : text.size();
    if (e > b && text[e - 1] == '\r') --e;
    return std::string_view(text).substr(b, e - b);
}

namespace {
// The columns a terminal gives a code point: 2 for East Asian wide and full-width characters
// and emoji, 0 for combining marks, zero-width spaces and variation selectors, else 1
// (the caret of a line with CJK text or emoji then sits under its column).
int display_width(uint32_t c) {
    if ((c >= 0x0300 && c <= 0x036F) || (c >= 0x200B && c <= 0x200F) || (c >= 0xFE00 && c <= 0xFE0F) || c == 0x20E3) return 0;
    const bool wide = (c >= 0x1100 && c <= 0x115F) || (c >= 0x2E80 && c <= 0x303E) || (c >= 0x3041 && c <= 0x33FF) ||
                      (c >= 0x3400 && c <= 0x4DBF) || (c >= 0x4E00 && c <= 0x9FFF) || (c >= 0xA000 && c <= 0xA4CF) ||
                      (c >= 0xAC00 && c <= 0xD7A3) || (c >= 0xF900 && c <= 0xFAFF) || (c >= 0xFE30 && c <= 0xFE4F) ||
                      (c >= 0xFF00 && c <= 0xFF60) || (c >= 0xFFE0 && c <= 0xFFE6) || (c >= 0x1F300 && c <= 0x1F64F) ||
                      (c >= 0x1F900 && c <= 0x1F9FF) || (c >= 0x20000 && c <= 0x3FFFD);
    return wide ? 2 : 1;
}

// The code point starting at byte i of s (a lead byte), and how many bytes it takes.
uint32_t decode_at(std::string_view s, size_t i, size_t& len) {
    const auto u = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned char b = u(i);
    len = b < 0x80 ? 1 : b >= 0xF0 ? 4 : b >= 0xE0 ? 3 : b >= 0xC0 ? 2 : 1;
    for (size_t k = 1; k < len; ++k)
        if (i + k >= s.size() || (u(i + k) & 0xC0) != 0x80) len = 1;  // (not well formed: a byte of its own)
    uint32_t c = len == 1 ? b : len == 2 ? (b & 0x1Fu) : len == 3 ? (b & 0x0Fu) : (b & 0x07u);
    for (size_t k = 1; k < len; ++k) c = (c << 6) | (u(i + k) & 0x3Fu);
    return c;
}
}  // namespace

namespace {

// A message that quotes a huge name or string (a 1 MB identifier) keeps its start and end.
std::string shortened(const std::string& m) {
    constexpr size_t kMost = 600, kHead = 400, kTail = 150;
    if (m.size() <= kMost) return m;
    auto boundary = [&](size_t i) {  // back to a UTF-8 character's first byte
        while (i > 0 && (static_cast<unsigned char>(m[i]) & 0xC0) == 0x80) --i;
        return i;
    };
    const size_t head = boundary(kHead), tail = boundary(m.size() - kTail);
    return m.substr(0, head) + " [... " + std::to_string(tail - head) + " bytes ...] " + m.substr(tail);
}

}  // namespace

std::string format_diagnostic(const Diagnostic& d, const char* kind) {
    if (!d.loc.known()) return fmt::format("sdfc: {}: {}\n", kind, shortened(d.message));
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
    std::string out = fmt::format("{}:{}:{}: {}: {}\n", file.path, line, chars + 1, kind, shortened(d.message));
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
    // Keep tabs so the caret lines up in a terminal; wide characters take two columns.
    out.append(lead.size(), ' ');
    for (size_t i = b; i < col;) {
        size_t len = 1;
        if (src[i] == '\t') out += '\t';
        else if (!continuation(i)) out.append(size_t(display_width(decode_at(src, i, len))), ' ');
        i += len;
    }
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
bool valid_utf8(std::string_view s, size_t& bad_at) {
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

namespace {
std::mutex g_loaded_mutex;
std::vector<std::string> g_loaded;
void note_loaded(const std::string& path) {
    std::lock_guard<std::mutex> lock(g_loaded_mutex);
    g_loaded.push_back(path);
}
}  // namespace

std::vector<std::string> take_loaded_paths() {
    std::lock_guard<std::mutex> lock(g_loaded_mutex);
    std::vector<std::string> out;
    out.swap(g_loaded);
    return out;
}

const SourceFile& SourceManager::load(const std::string& path, Loc from, size_t max_bytes) {
    note_loaded(path);
    std::string text;
    bool known = false;
    if (snapshot_) {
        std::lock_guard<std::mutex> lock(snapshot_->m);
        if (auto it = snapshot_->texts.find(path); it != snapshot_->texts.end()) text = it->second, known = true;
    }
    if (known) {
        if (text.size() > max_bytes)
            throw CompileError(from, fmt::format("'{}' is over the limit of {} bytes (--max-file-size)", path, max_bytes));
    } else {
        text = read(path, from, max_bytes);
        if (snapshot_) {
            std::lock_guard<std::mutex> lock(snapshot_->m);
            snapshot_->texts.emplace(path, text);
        }
    }
    const SourceFile& f = add(path, std::move(text));
    check_source_text(f);
    return f;
}

std::string SourceManager::read(const std::string& path, Loc from, size_t max_bytes) {
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
    // The reason, as the OS says it: a missing file, a symlink loop, no permission.
    if (ec) throw CompileError(from, fmt::format("cannot open '{}': {}", path, ec.message()));
    errno = 0;
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        const int err = errno;
        throw CompileError(from, err ? fmt::format("cannot open '{}': {}", path, std::strerror(err))
                                     : fmt::format("cannot open '{}'", path));
    }
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
    return text;
}

const SourceFile& SourceManager::load_stdin(size_t max_bytes) {
    note_loaded("-");
    static std::optional<std::string> cached;
    if (!cached) {
        std::string text;
        char buf[1 << 16];
        for (;;) {
            const ssize_t n = ::read(STDIN_FILENO, buf, sizeof buf);
            if (n < 0 && errno == EINTR) continue;
            if (n < 0) throw CompileError(Loc{}, fmt::format("cannot read standard input: {}", std::strerror(errno)));
            if (n == 0) break;
            text.append(buf, size_t(n));
            if (text.size() > max_bytes)
                throw CompileError(Loc{}, fmt::format("standard input is over the limit of {} bytes (--max-file-size)", max_bytes));
        }
        if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);
        cached = std::move(text);
    }
    if (cached->size() > max_bytes)
        throw CompileError(Loc{}, fmt::format("standard input is over the limit of {} bytes (--max-file-size)", max_bytes));
    const SourceFile& f = add("<stdin>", *cached);
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

std::string shown_number(float v) { return v != v ? std::string("nan") : fmt::format("{}", v); }

}  // namespace sdfc
