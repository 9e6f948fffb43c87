// The HTTP side of `sdfc preview` (server.cpp, on cpp-httplib), in the module
// libsdfc_preview.so: only `sdfc preview` opens it, so no other command loads httplib's TLS
// and compression libraries at start-up (a sanitizer or fuzz build links it in).
#pragma once
#include <string>

#include <fmt/format.h>

namespace sdfc::cli {

struct PreviewServer;  // the server and what its threads share

struct PreviewServerApi {
    int version;  // kPreviewServerApiVersion
    // Binds host:port (0: any free port; *bound says which) and serves on threads of its own:
    // `page` at /, each published event at /events (the newest at once to a page that
    // connects, after the newest good one if that differs), the page's reports at POST and
    // GET /report (those of a page of another server `token` are refused). nullptr and
    // *error when it cannot bind.
    PreviewServer* (*start)(const std::string& host, int port, const std::string& page, const std::string& token, int* bound,
                            std::string* error);
    // A new build as one server-sent event; `good`: a shader (else a script error).
    void (*publish)(PreviewServer* s, const std::string& event, bool good);
    void (*stop)(PreviewServer* s);  // and frees it
};

constexpr int kPreviewServerApiVersion = 1;

// A JSON string; `<` escaped too, so the text is safe inside HTML.
inline std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (unsigned char c : s) {
        switch (c) {
            case '"': o += "\\\""; break;
            case '\\': o += "\\\\"; break;
            case '\n': o += "\\n"; break;
            case '\r': o += "\\r"; break;
            case '\t': o += "\\t"; break;
            case '<': o += "\\u003c"; break;
            default:
                if (c < 0x20) o += fmt::format("\\u{:04x}", c);
                else o += char(c);
        }
    }
    return o + "\"";
}

}  // namespace sdfc::cli

extern "C" const sdfc::cli::PreviewServerApi* sdfc_preview_server();
