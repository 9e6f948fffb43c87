// `sdfc preview SCENE [--port N] [--host ADDR] [--debounce MS]`: a live preview in the browser.
// An HTTP server (cpp-httplib) on 127.0.0.1 serves the --target html page in its live mode;
// the page keeps one server-sent-events stream open (/events) and gets every new build of
// the scene on it: the WebGL2 shader after each save of the scene or a file it imports, or the
// script's error (path:line:col, the line and a caret), shown over the last good picture. The
// page never reloads, so its orbit camera, time and resolution stay as the user left them.
// It tells the server what it shows (POST /report: the version drawn, a shader the browser
// could not compile, the centre pixel); the server prints that and answers it at GET /report
// (for scripts and the tests). Ctrl-C ends it.
#include <signal.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>

#include "cli/common.hpp"
#include "cli/file_watch.hpp"
#include "compiler/glsl/glsl.hpp"
#include "lang/load.hpp"
#include "runtime/eval/vm.hpp"

namespace sdfc::cli {
namespace {

std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (unsigned char c : s) {
        switch (c) {
            case '"': o += "\\\""; break;
            case '\\': o += "\\\\"; break;
            case '\n': o += "\\n"; break;
            case '\r': o += "\\r"; break;
            case '\t': o += "\\t"; break;
            // `<` too: the text may hold `</script>`; harmless in JSON, safer anywhere HTML.
            case '<': o += "\\u003c"; break;
            default:
                if (c < 0x20) o += fmt::format("\\u{:04x}", c);
                else o += char(c);
        }
    }
    return o + "\"";
}

// What the server shares between the build loop and the HTTP threads.
struct Live {
    std::mutex m;
    std::condition_variable changed;
    long version = 0;     // builds so far; each is one event
    std::string event;    // the newest build as one server-sent event
    std::string good;     // the newest build that worked, as one: a page that connects after an
                          // error gets the last good picture under the error
    std::string report;   // the page's last report, as JSON ("{}" before the first)
    std::string server;   // this server's token: a reconnecting page knows a new server
};

// One build of the scene: its shader, or its error as the user would see it in a terminal.
struct Build {
    bool ok = false;
    std::string shader, message;
    bool uses_time = false;
};

Build build_shader(const std::string& path, const Common& c) {
    Build b;
    try {
        SourceManager sm;
        InterpretOptions o = c.interp;
        o.time = std::nullopt;  // `time` becomes iTime
        Scene s = load_scene(sm, path, o);
        print_warnings(s);
        b.shader = emit_glsl(s, GlslTarget::HtmlShader, sample_batch, &b.uses_time);
        b.ok = true;
    } catch (const CompileError& e) {
        b.message = e.formatted();
    } catch (const std::exception& e) {
        b.message = fmt::format("sdfc: error: {}\n", e.what());
    }
    return b;
}

void publish(Live& live, const Build& b, const std::string& title) {
    std::lock_guard<std::mutex> lock(live.m);
    ++live.version;
    const std::string head = fmt::format("{{\"server\":{},\"version\":{}", json_string(live.server), live.version);
    if (b.ok)
        live.event = live.good = fmt::format("retry: 1000\nevent: scene\ndata: {},\"title\":{},\"uses_time\":{},\"shader\":{}}}\n\n", head,
                                 json_string(title), b.uses_time ? "true" : "false", json_string(b.shader));
    else
        live.event = fmt::format("retry: 1000\nevent: failed\ndata: {},\"message\":{}}}\n\n", head, json_string(b.message));
    live.changed.notify_all();
}

void serve(httplib::Server& http, const std::shared_ptr<Live>& live, const std::string& page) {
    http.Get("/", [page](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        res.set_content(page, "text/html; charset=utf-8");
    });
    // The stream: the newest build at once, then each new one; a comment every 15 s finds
    // pages that went away (their write fails and the thread is free again).
    http.Get("/events", [live](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        res.set_chunked_content_provider("text/event-stream", [live, sent = 0L](size_t, httplib::DataSink& sink) mutable {
            std::unique_lock<std::mutex> lock(live->m);
            live->changed.wait_for(lock, std::chrono::seconds(15), [&] { return live->version != sent; });
            std::string msg = live->version != sent ? live->event : std::string(": still here\n\n");
            if (sent == 0 && live->good != live->event) msg = live->good + msg;
            sent = live->version;
            lock.unlock();
            return sink.write(msg.data(), msg.size());
        });
    });
    http.Post("/report", [live](const httplib::Request& req, httplib::Response& res) {
        auto param = [&](const char* k) { return req.has_param(k) ? req.get_param_value(k) : std::string(); };
        const std::string version = param("version"), drawn = param("drawn"), error = param("error");
        std::string json = "{";
        for (const char* k : {"server", "version", "drawn", "error", "compile_ms", "width", "height", "pixel"})
            json += fmt::format("{}{}:{}", json.size() > 1 ? "," : "", json_string(k), json_string(param(k)));
        json += "}";
        bool shown_before = false;
        {
            std::lock_guard<std::mutex> lock(live->m);
            if (param("server") != live->server) {  // a page of an earlier server
                res.status = 409;
                return;
            }
            shown_before = live->report == json;
            live->report = json;
        }
        // The browser's own trouble (a shader its driver refuses) is news to the terminal;
        // a script error was printed by the build already.
        if (!shown_before && version == drawn)
            std::fprintf(stderr, "sdfc preview: the page draws version %s (%sx%s, shader compiled in %s ms)\n", version.c_str(),
                         param("width").c_str(), param("height").c_str(), param("compile_ms").c_str());
        else if (!shown_before && !error.empty() && error.rfind("The shader", 0) == 0)
            std::fprintf(stderr, "sdfc preview: the browser cannot draw version %s: %s\n", version.c_str(), error.c_str());
        res.set_content("ok\n", "text/plain");
    });
    http.Get("/report", [live](const httplib::Request&, httplib::Response& res) {
        std::lock_guard<std::mutex> lock(live->m);
        res.set_header("Cache-Control", "no-store");
        res.set_content(live->report, "application/json");
    });
    http.set_payload_max_length(1 << 20);  // a report is small; nothing else is posted
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

    auto live = std::make_shared<Live>();
    live->server = std::to_string(std::chrono::steady_clock::now().time_since_epoch().count());
    live->report = "{}";
    httplib::Server http;
    serve(http, live, html_live_page(title));
    const std::string addr = host ? *host : "127.0.0.1";
    const int bound = port == 0 ? http.bind_to_any_port(addr) : (http.bind_to_port(addr, port) ? port : -1);
    if (bound < 0) throw UsageError(fmt::format("cannot serve on {}:{} (in use? try --port 0 for any free port)", addr, port));
    ::signal(SIGPIPE, SIG_IGN);  // a page closed mid-write: the write fails, the server goes on
    std::thread server([&http] { http.listen_after_bind(); });
    struct Stop {  // an error below (a folder that cannot be watched) stops the server first
        httplib::Server& http;
        std::thread& thread;
        ~Stop() { http.stop(), thread.join(); }
    } stop{http, server};

    std::fprintf(stderr, "sdfc preview: http://%s:%d/ (Ctrl-C to stop)\n", addr.c_str(), bound);
    for (long n = 1;; ++n) {
        (void)take_loaded_paths();
        forget_warnings();
        const auto t0 = std::chrono::steady_clock::now();
        const Build b = build_shader(path, c);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!b.ok) std::fputs(b.message.c_str(), stderr);
        publish(*live, b, title);
        const auto files = files_read({"preview", path});
        std::fprintf(stderr, "sdfc preview: version %ld %s in %.1f ms; watching %zu file%s\n", n, b.ok ? "ok" : "failed", ms, files.size(),
                     files.size() == 1 ? "" : "s");
        wait_for_change(files, debounce_ms);
    }
}

}  // namespace sdfc::cli
