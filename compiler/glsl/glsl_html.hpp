// The `--target html` page: one self-contained file (no network access; all script inline)
// that runs the WebGL2 version of the shader with an orbit camera, a time slider and a
// resolution scale. `page.html#capture` fills the window with the canvas at exact size, hides
// the controls and draws one frame at the script's camera and time 0 (for screenshots;
// tests/gpu drives it with headless Chromium). Its text is compiler/glsl/page.html with
// page.js at its @PAGE_JS@ line, both embedded by the build (compiler/glsl/embed.cmake).
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "compiler/glsl/glsl_tape.hpp"
#include "compiler/glsl/page.html.hpp"
#include "compiler/glsl/page_main.glsl.hpp"
#include "compiler/glsl/page.js.hpp"

namespace sdfc::glsl {

inline std::string html_escape(std::string_view s) {
    std::string o;
    for (char c : s) {
        switch (c) {
            case '&': o += "&amp;"; break;
            case '<': o += "&lt;"; break;
            case '>': o += "&gt;"; break;
            case '"': o += "&quot;"; break;
            default: o += c;
        }
    }
    return o;
}

// The page for `shader` (a complete GLSL ES 3.00 fragment shader starting with #version), the
// scene's facts as JSON (glsl.cpp scene_json: time, knobs, parameters) and the words of its
// tape texture, if it has one (compiler/glsl/glsl_tape.hpp); live: no shader, the page
// listens to sdfc preview's /events for them.
inline std::string html_page(std::string_view title, std::string_view shader, std::string_view scene_json, bool live = false,
                             const std::vector<uint32_t>& tape = {}) {
    std::string page(kPageHtml);
    auto put = [&](std::string_view key, std::string_view value) {
        size_t p = page.find(key);
        if (p != std::string::npos) page.replace(p, key.size(), value);
    };
    put("@PAGE_JS@\n", kPageJs);  // first: the script holds @LIVE@
    put("@TITLE@", html_escape(title));
    put("@LIVE@", live ? "true" : "false");
    put("@SCENE@", scene_json.empty() ? std::string_view("{}") : scene_json);
    put("@TAPE@", tape.empty() ? std::string() : tape_base64(tape));
    put("@SHADER@", shader);  // last: the shader's text is not searched for keys
    return page;
}

}  // namespace sdfc::glsl
