#include "lang/source.hpp"

#include <algorithm>
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
    std::string out = fmt::format("{}:{}:{}: error: {}\n", d.loc.file->path, d.loc.line, d.loc.col, d.message);
    std::string_view src = d.loc.file->line(d.loc.line);
    out += src;
    out += '\n';
    // Keep tabs so the caret lines up in a terminal.
    for (uint32_t i = 1; i < d.loc.col && i - 1 < src.size(); ++i) out += src[i - 1] == '\t' ? '\t' : ' ';
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

static bool valid_utf8(std::string_view s, size_t& bad_at) {
    size_t i = 0;
    while (i < s.size()) {
        unsigned char c = static_cast<unsigned char>(s[i]);
        size_t n = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
        if (n == 0 || i + n > s.size()) { bad_at = i; return false; }
        for (size_t k = 1; k < n; ++k)
            if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) { bad_at = i; return false; }
        i += n;
    }
    return true;
}

const SourceFile& SourceManager::add(std::string path, std::string text) {
    files_.push_back(std::make_unique<SourceFile>(std::move(path), std::move(text)));
    return *files_.back();
}

const SourceFile& SourceManager::load(const std::string& path, Loc from, size_t max_bytes) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw CompileError(from, fmt::format("cannot open '{}'", path));
    in.seekg(0, std::ios::end);
    std::streamoff size = in.tellg();
    if (size < 0) throw CompileError(from, fmt::format("cannot read '{}' (is it a directory?)", path));
    if (static_cast<size_t>(size) > max_bytes)
        throw CompileError(from, fmt::format("'{}' is {} bytes, over the limit of {} bytes (--max-file-size)",
                                             path, size, max_bytes));
    in.seekg(0);
    std::string text(static_cast<size_t>(size), '\0');
    if (size > 0 && !in.read(text.data(), size)) throw CompileError(from, fmt::format("cannot read '{}'", path));
    const SourceFile& f = add(path, std::move(text));
    size_t nul = f.text.find('\0');
    size_t bad = 0;
    auto loc_of = [&](size_t off) {
        auto it = std::upper_bound(f.line_starts.begin(), f.line_starts.end(), off);
        uint32_t line = static_cast<uint32_t>(it - f.line_starts.begin());
        return Loc{&f, line, static_cast<uint32_t>(off - f.line_starts[line - 1] + 1)};
    };
    if (nul != std::string::npos) throw CompileError(loc_of(nul), "binary file: NUL byte in source text");
    if (!valid_utf8(f.text, bad)) throw CompileError(loc_of(bad), "invalid UTF-8 in source text");
    return f;
}

std::string nearest_name(std::string_view name, const std::vector<std::string>& candidates) {
    std::string best;
    // Close enough to be a typo: at most a third of the name wrong, and never all of it.
    size_t best_d = std::min(std::max<size_t>(1, name.size() / 3), name.size() - 1) + 1;
    for (const auto& c : candidates) {
        std::vector<size_t> prev(c.size() + 1), cur(c.size() + 1);
        for (size_t j = 0; j <= c.size(); ++j) prev[j] = j;
        for (size_t i = 1; i <= name.size(); ++i) {
            cur[0] = i;
            for (size_t j = 1; j <= c.size(); ++j)
                cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (name[i - 1] == c[j - 1] ? 0 : 1)});
            std::swap(prev, cur);
        }
        if (prev[c.size()] < best_d) { best_d = prev[c.size()]; best = c; }
    }
    return best;
}

}  // namespace sdfc
