// The preview's HTTP server (server_api.hpp): cpp-httplib on threads of its own. The page
// keeps one server-sent-events stream open; each published build goes to every open stream.
// The page reports what it shows (POST /report): printed when it is news, kept for GET.
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <httplib.h>

#include "cli/preview/server_api.hpp"

namespace sdfc::cli {

struct PreviewServer {
    httplib::Server http;
    std::thread thread;
    struct Shared {
        std::mutex m;
        std::condition_variable changed;
        long version = 0;            // events published so far
        std::string event, good;     // the newest event, and the newest good one
        std::string report = "{}";   // the page's last report, as JSON
        std::string token;           // this server's: a page of an earlier one is refused
        bool stopping = false;
        int streams = 0;             // /events streams open now
    };
    std::shared_ptr<Shared> shared = std::make_shared<Shared>();
};

namespace {

// httplib's default pool has max(8, cores - 1) threads: five open pages, their streams and
// kept-alive connections, were enough to stall the next page load.
constexpr int kWorkers = 64, kMaxStreams = 48;

void routes(httplib::Server& http, const std::shared_ptr<PreviewServer::Shared>& live, const std::string& page) {
    http.Get("/", [page](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        res.set_content(page, "text/html; charset=utf-8");
    });
    // The stream: the newest build at once, then each new one; a comment every 15 s finds
    // pages that went away (the write fails and the thread is free again).
    // Each open stream holds one of the server's threads (kWorkers) for as long as its page
    // lives: past kMaxStreams a new one is refused (503), so page loads and reports always
    // find a thread.
    http.Get("/events", [live](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        {
            std::lock_guard<std::mutex> lock(live->m);
            if (live->streams >= kMaxStreams) {
                res.status = 503;
                res.set_content(fmt::format("{} pages are open on this preview already\n", kMaxStreams), "text/plain");
                return;
            }
            ++live->streams;
        }
        // Counted open while any copy of the provider lives.
        auto slot = std::shared_ptr<void>(nullptr, [live](void*) {
            std::lock_guard<std::mutex> lock(live->m);
            --live->streams;
        });
        res.set_chunked_content_provider("text/event-stream", [live, slot, sent = 0L](size_t, httplib::DataSink& sink) mutable {
            std::unique_lock<std::mutex> lock(live->m);
            live->changed.wait_for(lock, std::chrono::seconds(15), [&] { return live->version != sent || live->stopping; });
            if (live->stopping) return false;
            std::string msg = live->version != sent ? live->event : std::string(": still here\n\n");
            if (sent == 0 && !live->good.empty() && live->good != live->event) msg = live->good + msg;
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
        bool news = false;
        {
            std::lock_guard<std::mutex> lock(live->m);
            if (param("server") != live->token) {
                res.status = 409;
                return;
            }
            news = live->report != json;
            live->report = json;
        }
        // What the terminal does not know yet: the page drew a build, or the browser could
        // not compile its shader (a script error was printed by the build already).
        if (news && version == drawn)
            std::fprintf(stderr, "sdfc preview: the page draws version %s (%sx%s, shader compiled in %s ms)\n", version.c_str(),
                         param("width").c_str(), param("height").c_str(), param("compile_ms").c_str());
        else if (news && error.rfind("The shader", 0) == 0)
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

PreviewServer* start(const std::string& host, int port, const std::string& page, const std::string& token, int* bound, std::string* error) {
    auto s = std::make_unique<PreviewServer>();
    s->shared->token = token;
    routes(s->http, s->shared, page);
    s->http.new_task_queue = [] { return new httplib::ThreadPool(kWorkers); };
    // SO_REUSEADDR only: httplib's default, SO_REUSEPORT, lets a second preview bind the same
    // port, and the kernel then splits the connections between the two.
    s->http.set_socket_options([](socket_t sock) {
        int yes = 1;
        ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    const int b = port == 0 ? s->http.bind_to_any_port(host) : (s->http.bind_to_port(host, port) ? port : -1);
    if (b < 0) {
        *error = fmt::format("cannot serve on {}:{} (in use? --port 0 takes any free port)", host, port);
        return nullptr;
    }
    *bound = b;
    PreviewServer* raw = s.get();
    s->thread = std::thread([raw] { raw->http.listen_after_bind(); });
    return s.release();
}

void publish(PreviewServer* s, const std::string& event, bool good) {
    std::lock_guard<std::mutex> lock(s->shared->m);
    ++s->shared->version;
    s->shared->event = event;
    if (good) s->shared->good = event;
    s->shared->changed.notify_all();
}

void stop(PreviewServer* s) {
    {
        std::lock_guard<std::mutex> lock(s->shared->m);
        s->shared->stopping = true;
        s->shared->changed.notify_all();
    }
    s->http.stop();
    if (s->thread.joinable()) s->thread.join();
    delete s;
}

const PreviewServerApi kApi{kPreviewServerApiVersion, start, publish, stop};

}  // namespace

}  // namespace sdfc::cli

extern "C" __attribute__((visibility("default"))) const sdfc::cli::PreviewServerApi* sdfc_preview_server() { return &sdfc::cli::kApi; }
