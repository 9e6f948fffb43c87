// `sdfc preview SCENE [--port N] [--host ADDR] [--debounce MS]`: a live preview in the browser.
// An HTTP server (cli/preview/server.cpp, cpp-httplib, in the module libsdfc_preview.so) on
// 127.0.0.1 serves the --target html page in its live mode; the page keeps one
// server-sent-events stream open and gets every new build of the scene on it: the WebGL2
// shader after each save of the scene or a file it imports, or the script's error
// (path:line:col, the line and a caret), shown over the last good picture. The page never
// reloads, so its orbit camera, time and resolution stay as the user left them. It reports
// what it shows (POST /report: the version drawn, a shader the browser could not compile,
// the centre pixel); the server prints that and answers it at GET /report (for scripts and
// the tests). Ctrl-C ends it.
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include <fmt/format.h>

#include "cli/common.hpp"
#include "cli/output_checks.hpp"
#include "cli/file_watch.hpp"
#include "cli/preview/server_api.hpp"
#include "compiler/glsl/glsl.hpp"
#include "compiler/glsl/glsl_tape.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"
#include "runtime/io/module.hpp"

namespace sdfc::cli {
namespace {

// One build of the scene: its shader, or its error as the user would see it in a terminal.
struct Build {
    bool ok = false;
    std::string shader, message;
    std::string tape;  // base64 words of the shader's tape texture ("" for straight-line code)
    std::string scene;  // the page's facts of the scene (JSON: time, knobs, parameters)
};

Build build_shader(const std::string& path, const Common& c) {
    Build b;
    try {
        SourceManager sm;
        InterpretOptions o = c.interp;
        o.time = std::nullopt;  // `time` becomes iTime
        Scene s = load_scene(sm, path, o);
        GlslOptions go;
        go.sample = sample_batch;
        GlslOutput out = compile_then_warn(s, [&] { return compile_glsl(s, GlslTarget::HtmlShader, go); });
        check_field_finite(s, out.distance, out.probes);  // (as sdfc glsl and render)
        b.shader = std::move(out.text);
        b.scene = std::move(out.scene_json);
        if (!out.tape_words.empty()) b.tape = glsl::tape_base64(out.tape_words);
        b.ok = true;
    } catch (const CompileError& e) {
        b.message = e.formatted();
    } catch (const std::exception& e) {
        b.message = fmt::format("sdfc: error: {}\n", e.what());
    }
    return b;
}

// The build as one server-sent event: `scene` (the shader) or `failed` (the error's text).
std::string event_of(const Build& b, const std::string& token, long version, const std::string& title) {
    const std::string head = fmt::format("{{\"server\":{},\"version\":{}", json_string(token), version);
    if (b.ok)
        return fmt::format("retry: 1000\nevent: scene\ndata: {},\"title\":{},\"scene\":{},\"shader\":{},\"tape\":{}}}\n\n", head,
                           json_string(title), b.scene, json_string(b.shader), json_string(b.tape));
    return fmt::format("retry: 1000\nevent: failed\ndata: {},\"message\":{}}}\n\n", head, json_string(b.message));
}

const PreviewServerApi& server_api() {
#ifdef SDFC_PREVIEW_BUILTIN
    return *sdfc_preview_server();
#else
    std::string failure;
    auto entry = reinterpret_cast<const PreviewServerApi* (*)()>(
        module_entry("libsdfc_preview.so", "SDFC_PREVIEW_MODULE", "sdfc_preview_server", failure));
    const PreviewServerApi* api = entry ? entry() : nullptr;
    if (entry && (!api || api->version != kPreviewServerApiVersion)) failure = "it is not this build's preview module";
    if (!api || !failure.empty()) throw std::runtime_error("cannot load the preview server libsdfc_preview.so: " + failure);
    return *api;
#endif
}

}  // namespace

int cmd_preview(Args& a) {
    Common c = read_common(a);
    auto port_s = a.value("--port");
    auto host = a.value("--host");
    auto debounce_s = a.value("--debounce");
    const std::string path = one_scene(a, "preview");
    if (path == "-") throw UsageError("preview needs a scene file: standard input (-) is read once");
    const int port = port_s ? Args::to_int("--port", *port_s, 0, 65535) : 8421;
    const int debounce_ms = debounce_s ? Args::to_int("--debounce", *debounce_s, 0, 60000) : 100;
    const std::string title = std::filesystem::path(path).stem().string();

    const PreviewServerApi& api = server_api();
    const std::string token = std::to_string(std::chrono::system_clock::now().time_since_epoch().count());
    const std::string addr = host ? *host : "127.0.0.1";
    int bound = 0;
    std::string why;
    PreviewServer* server = api.start(addr, port, html_live_page(title), token, &bound, &why);
    if (!server) throw UsageError(why);
    ::signal(SIGPIPE, SIG_IGN);  // a page closed mid-write: the write fails, the server goes on
    struct Stop {  // an error below (a folder that cannot be watched) stops the server first
        const PreviewServerApi& api;
        PreviewServer* s;
        ~Stop() { api.stop(s); }
    } stop{api, server};

    std::fprintf(stderr, "sdfc preview: http://%s:%d/ (Ctrl-C to stop)\n", addr.c_str(), bound);
    for (long n = 1;; ++n) {
        (void)take_loaded_paths();
        forget_warnings();
        const auto t0 = std::chrono::steady_clock::now();
        const Build b = build_shader(path, c);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!b.ok) std::fputs(b.message.c_str(), stderr);
        api.publish(server, event_of(b, token, n, title), b.ok);
        const auto files = files_read({"preview", path});
        std::fprintf(stderr, "sdfc preview: version %ld %s in %.1f ms; watching %zu file%s\n", n, b.ok ? "ok" : "failed", ms, files.size(),
                     files.size() == 1 ? "" : "s");
        wait_for_change(files, debounce_ms);
    }
}

}  // namespace sdfc::cli
