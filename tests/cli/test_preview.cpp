// sdfc preview (issue 15): the server end to end (the page, the event stream: a new shader
// on each save, the script's error on a bad one), then a real page in headless Chromium:
// a save changes what the page draws (its centre pixel, from its report), a script error
// shows on the page while the last good picture stays.
#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <thread>
#include <vector>

#include <httplib.h>

#include "run.hpp"

using namespace sdfc;
namespace fs = std::filesystem;

namespace {

std::string q(const std::string& s) { return "'" + s + "'"; }

void save(const std::string& path, const std::string& text) {  // as editors do: rename over
    std::ofstream(path + ".tmp", std::ios::binary) << text;
    fs::rename(path + ".tmp", path);
}

// A background process, killed at the end of the test.
struct Background {
    int pid = -1;
    Background(const std::string& cmd, const std::string& log) {
        const std::string pidfile = log + ".pid";
        REQUIRE(std::system(("(" + cmd + " >" + q(log) + " 2>&1 </dev/null & echo $! >" + q(pidfile) + ")").c_str()) == 0);
        pid = std::atoi(test::slurp(pidfile).c_str());
    }
    ~Background() {
        if (pid > 0) ::kill(pid, SIGTERM);
    }
};

// Polls `get` (up to 90 s: sanitizer builds and SwiftShader are slow) until `ok` holds.
template <class Get, class Ok>
bool eventually(Get get, Ok ok) {
    for (int i = 0; i < 900; ++i) {
        if (ok(get())) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
}

int port_from(const std::string& log) {
    std::smatch m;
    int port = -1;
    eventually([&] { return test::slurp(log); },
               [&](const std::string& s) {
                   if (std::regex_search(s, m, std::regex("sdfc preview: http://127\\.0\\.0\\.1:(\\d+)/"))) port = std::stoi(m[1]);
                   return port > 0;
               });
    return port;
}

// The first `n` events on /events (what a page gets when it connects), as sent: read from a
// socket of its own, closed after them (the stream itself never ends) unless `keep` takes it.
std::string first_events(int port, int n = 1, int* keep = nullptr) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    REQUIRE(fd >= 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(uint16_t(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    timeval tv{60, 0};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    std::string got;
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
        const std::string req = "GET /events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
        if (::send(fd, req.data(), req.size(), 0) == ssize_t(req.size())) {
            char buf[65536];
            for (int seen = 0; seen < n;) {
                const ssize_t k = ::recv(fd, buf, sizeof buf, 0);
                if (k <= 0) break;
                got.append(buf, size_t(k));
                if (got.size() >= 12 && got.compare(0, 12, "HTTP/1.1 200") != 0) break;  // refused: no stream
                seen = 0;
                for (size_t at = 0; (at = got.find("\n\n", at)) != std::string::npos; at += 2) ++seen;
            }
        }
    }
    if (keep) *keep = fd;
    else ::close(fd);
    if (got.compare(0, 12, "HTTP/1.1 200") != 0) return "";
    const size_t body = got.find("\r\n\r\n");  // after the headers, the chunks: their sizes on lines of their own
    std::string events;
    for (size_t at = body == std::string::npos ? got.size() : body + 4; at < got.size();) {
        const size_t eol = got.find("\r\n", at);
        if (eol == std::string::npos) break;
        const size_t len = std::stoul(got.substr(at, eol - at), nullptr, 16);
        events += got.substr(eol + 2, len);
        at = eol + 2 + len + 2;
    }
    return events;
}

std::string field(const std::string& json, const std::string& key) {
    std::smatch m;
    if (!std::regex_search(json, m, std::regex("\"" + key + "\":\"([^\"]*)\""))) return "";
    return m[1];
}

std::string find_chromium() {
    if (const char* e = std::getenv("SDFC_CHROMIUM"); e && *e) return e;
    for (const char* p : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
        if (::access(p, X_OK) == 0) return p;
    return "";
}

const char* kRed = "background([0, 0, 0]);\ncolor([1, 0, 0]) sphere(1.5);\n";
const char* kBlue = "background([0, 0, 0]);\ncolor([0, 0, 1]) sphere(1.5);\n";
const char* kBroken = "background([0, 0, 0]);\ncolor([0, 0, 1]) sphere(1.5;\n";

// A preview of kRed in a folder of its own, serving once its first build is done.
struct Served {
    std::string scene, log;
    std::unique_ptr<Background> server;
    int port = -1;
    explicit Served(const std::string& name) {
        const std::string dir = test::temp_dir() + "/" + name;
        fs::create_directories(dir);
        scene = dir + "/scene.sdf", log = dir + "/log.txt";
        save(scene, kRed);
        server = std::make_unique<Background>("'" + std::string(SDFC_BIN_PATH) + "' preview --port 0 --debounce 50 " + q(scene), log);
        port = port_from(log);
        REQUIRE(port > 0);
        REQUIRE(eventually([&] { return test::slurp(log); }, [](const std::string& s) { return s.find("version 1 ok in ") != std::string::npos; }));
    }
};

}  // namespace

TEST_CASE("preview serves the live page and sends each save's shader or error") {
    const Served served("preview");
    const std::string &scene = served.scene, &log = served.log;
    const int port = served.port;

    httplib::Client cli("127.0.0.1", port);
    auto page = cli.Get("/");
    REQUIRE(page);
    CHECK(page->status == 200);
    CHECK(page->body.find("var live = true;") != std::string::npos);
    CHECK(page->body.find("new EventSource('/events')") != std::string::npos);

    std::string e = first_events(port);
    CHECK(e.rfind("retry: 1000\nevent: scene\ndata: {", 0) == 0);
    CHECK(e.find("\"version\":1,") != std::string::npos);
    CHECK(e.find("\"title\":\"scene\"") != std::string::npos);
    CHECK(e.find("#version 300 es\\n") != std::string::npos);

    save(scene, kBroken);
    REQUIRE(eventually([&] { return test::slurp(log); }, [](const std::string& s) { return s.find("version 2 failed in ") != std::string::npos; }));
    CHECK(test::slurp(log).find("scene.sdf:2:28: error: expected ')'") != std::string::npos);
    // A page that connects now gets the last good shader, then the error over it.
    e = first_events(port, 2);
    CHECK(e.rfind("retry: 1000\nevent: scene\n", 0) == 0);
    CHECK(e.find("\n\nretry: 1000\nevent: failed\n") != std::string::npos);
    CHECK(e.find("\"version\":2,") != std::string::npos);
    CHECK(e.find("scene.sdf:2:28: error: expected ')'") != std::string::npos);
    CHECK(e.find("sphere(1.5;\\n") != std::string::npos);  // the line and its caret

    CHECK(cli.Get("/nothing-here")->status == 404);
    auto stale = cli.Post("/report", "server=someone-else&version=9", "application/x-www-form-urlencoded");
    REQUIRE(stale);
    CHECK(stale->status == 409);
}

TEST_CASE("many open pages: each has its stream, page loads still answer, past 48 streams a 503") {
    const Served served("preview-many");
    const std::string &scene = served.scene, &log = served.log;
    const int port = served.port;
    std::vector<int> open;
    for (int i = 0; i < 48; ++i) {  // httplib's own pool had 8 threads: the 9th page waited for ever
        int fd = -1;
        REQUIRE(first_events(port, 1, &fd).find("\"version\":1,") != std::string::npos);
        open.push_back(fd);
    }
    httplib::Client cli("127.0.0.1", port);
    cli.set_read_timeout(20, 0);
    auto page = cli.Get("/");
    REQUIRE(page);
    CHECK(page->status == 200);
    auto refused = cli.Get("/events");
    REQUIRE(refused);
    CHECK(refused->status == 503);
    CHECK(refused->body == "48 pages are open on this preview already\n");
    // A page goes away (reset, so the server's next write fails at once): its slot is free.
    linger reset{1, 0};
    ::setsockopt(open.back(), SOL_SOCKET, SO_LINGER, &reset, sizeof reset);
    ::close(open.back());
    open.pop_back();
    save(scene, kBlue);
    CHECK(eventually([&] { return test::slurp(log); }, [](const std::string& s) { return s.find("version 2 ok in ") != std::string::npos; }));
    CHECK(eventually([&] { return first_events(port); }, [](const std::string& e) { return e.find("\"version\":2,") != std::string::npos; }));
    for (int fd : open) ::close(fd);
}

TEST_CASE("preview's usage errors") {
    CHECK(test::run_sdfc("preview").err == "sdfc: error: preview needs a scene file\n");
    CHECK(test::run_sdfc("preview -").err == "sdfc: error: preview needs a scene file: standard input (-) is read once\n");
    CHECK(test::run_sdfc("preview x.sdf --port 70000").err == "sdfc: error: --port must be from 0 to 65535, not 70000\n");
    CHECK(test::run_sdfc("preview x.sdf --prot 1").status == 2);
}

TEST_CASE("a page in headless Chromium follows the saves: new picture, error over the last one", "[chromium]") {
    const std::string chromium = find_chromium();
    if (chromium.empty()) {
        WARN("SKIPPED: no chromium (apt-get install chromium), so the live page is not checked in a browser");
        return;
    }
    const std::string dir = test::temp_dir() + "/preview-browser";
    fs::create_directories(dir);
    const std::string scene = dir + "/scene.sdf", log = dir + "/log.txt";
    save(scene, kRed);
    Background server("'" + std::string(SDFC_BIN_PATH) + "' preview --port 0 --debounce 50 " + q(scene), log);
    const int port = port_from(log);
    REQUIRE(port > 0);
    Background browser("timeout 300 " + q(chromium) +
                           " --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --disable-background-networking"
                           " --disable-gpu-sandbox --no-first-run --user-data-dir=" +
                           q(dir + "/profile") + " --window-size=160,120 http://127.0.0.1:" + std::to_string(port) + "/",
                       dir + "/chromium.log");
    httplib::Client cli("127.0.0.1", port);
    std::string report;
    auto get = [&] {
        auto r = cli.Get("/report");
        report = r ? r->body : "";
        return report;
    };
    // The lit sphere's centre: its own colour well over the other two channels.
    auto pixel = [&] {
        int r = -1, g = -1, b = -1;
        std::sscanf(field(report, "pixel").c_str(), "%d,%d,%d", &r, &g, &b);
        return std::array<int, 3>{r, g, b};
    };
    // Version 1: the red sphere at the centre.
    REQUIRE(eventually(get, [](const std::string& s) { return field(s, "drawn") == "1"; }));
    CAPTURE(report);
    CHECK(field(report, "error") == "");
    CHECK((pixel()[0] > 100 && pixel()[0] > 2 * pixel()[1] && pixel()[0] > 2 * pixel()[2]));
    CHECK(eventually([&] { return test::slurp(log); }, [](const std::string& s) { return s.find("the page draws version 1 (") != std::string::npos; }));
    // A save: the page draws the blue one, without a reload.
    save(scene, kBlue);
    REQUIRE(eventually(get, [](const std::string& s) { return field(s, "drawn") == "2"; }));
    CAPTURE(report);
    CHECK((pixel()[2] > 100 && pixel()[2] > 2 * pixel()[0] && pixel()[2] > 2 * pixel()[1]));
    // A script error: shown on the page at its line, the blue picture stays.
    save(scene, kBroken);
    REQUIRE(eventually(get, [](const std::string& s) { return field(s, "version") == "3"; }));
    CAPTURE(report);
    CHECK(field(report, "drawn") == "2");
    CHECK(field(report, "error").find("scene.sdf:2:28: error: expected ')'") != std::string::npos);
    CHECK((pixel()[2] > 100 && pixel()[2] > 2 * pixel()[0]));
    // Mended: the error goes, the picture is the red one again.
    save(scene, kRed);
    REQUIRE(eventually(get, [](const std::string& s) { return field(s, "drawn") == "4"; }));
    CAPTURE(report);
    CHECK(field(report, "error") == "");
    CHECK((pixel()[0] > 100 && pixel()[0] > 2 * pixel()[2]));
}
