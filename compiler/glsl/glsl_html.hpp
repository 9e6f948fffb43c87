// The `--target html` page: one self-contained file (no network access; all script inline)
// that runs the WebGL2 version of the shader with an orbit camera, a time slider and a
// resolution scale. `page.html#capture` fills the window with the canvas at exact size, hides
// the controls and draws one frame at the script's camera and time 0 (for screenshots;
// tests/gpu drives it with headless Chromium).
#pragma once
#include <string>
#include <string_view>

namespace sdfc::glsl {

inline constexpr const char* kHtmlTemplate = R"HTML(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="sdfc">
<title>@TITLE@ - sdfc preview</title>
<style>
  html, body { margin: 0; padding: 0; width: 100%; height: 100%; overflow: hidden; background: #111; }
  #view { display: block; width: 100%; height: 100%; touch-action: none; cursor: grab; }
  #view.dragging { cursor: grabbing; }
  #ui { position: fixed; left: 8px; bottom: 8px; right: 8px; display: flex; flex-wrap: wrap; gap: 10px;
        align-items: center; padding: 6px 10px; border-radius: 6px; background: rgba(20, 20, 24, 0.78);
        color: #eee; font: 13px/1.4 system-ui, sans-serif; user-select: none; }
  #ui button, #ui select { font: inherit; color: #eee; background: #333; border: 1px solid #555;
        border-radius: 4px; padding: 2px 8px; }
  #ui input[type=range] { flex: 1 1 160px; min-width: 100px; }
  #ui .dim { color: #aaa; }
  #message { display: none; position: fixed; left: 50%; top: 50%; transform: translate(-50%, -50%);
        box-sizing: border-box; width: 36em; max-width: 94vw; max-height: 94vh; overflow: auto;
        padding: 16px 20px; border-radius: 8px; background: #fff; color: #222;
        font: 15px/1.5 system-ui, sans-serif; white-space: pre-wrap; box-shadow: 0 4px 24px rgba(0,0,0,0.5); }
  body.capture #ui, body.failed #ui { display: none; }
</style>
</head>
<body>
<canvas id="view"></canvas>
<div id="ui">
  <button id="play" title="Play / pause (space)">Play</button>
  <span id="tlabel">t = 0.00 s</span>
  <input id="time" type="range" min="0" max="20" step="0.01" value="0" title="Scene time (the script's `time`)">
  <label>resolution <select id="scale" title="Rendering resolution relative to the window">
    <option value="0.25">25%</option><option value="0.5">50%</option><option value="0.75">75%</option>
    <option value="1" selected>100%</option><option value="1.5">150%</option><option value="2">200%</option>
  </select></label>
  <button id="reset" title="Back to the script's camera (double-click works too)">Reset view</button>
  <span class="dim" id="help">drag: orbit &middot; right/shift-drag: pan &middot; wheel: zoom</span>
  <span class="dim" id="stats"></span>
</div>
<div id="message" role="alert"></div>
<script type="x-shader/x-fragment" id="sdf-fragment">@SHADER@</script>
<script>
(function () {
  'use strict';
  // #capture: no controls, the canvas fills the window, one frame at the script's camera and
  // time 0 (redrawn if the window is resized); #capture=WxH: a canvas of exactly W x H CSS pixels.
  var cap = /(?:^|[#&?])capture(?:=(\d+)x(\d+))?(?:$|&)/.exec(location.hash);
  var capture = !!cap;
  var usesTime = @USES_TIME@;
  var canvas = document.getElementById('view');
  if (capture) {
    document.body.className = 'capture';
    if (cap[1]) { canvas.style.width = cap[1] + 'px'; canvas.style.height = cap[2] + 'px'; }
  }
  var message = document.getElementById('message');
  function fail(text) {
    message.textContent = text;
    message.style.display = 'block';
    document.body.className = 'failed';
    document.title = 'sdfc preview: error';
  }
  var gl = null;
  try {
    gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: false, stencil: false,
                                       preserveDrawingBuffer: true, powerPreference: 'high-performance' });
  } catch (e) { gl = null; }
  if (!gl) {
    fail('WebGL2 is not available here, so this preview cannot draw the scene.\n\n' +
         'It needs a browser with WebGL2 enabled: a current Firefox, Chrome, Edge or Safari, with ' +
         'hardware acceleration turned on. You can still paste the output of ' +
         '`sdfc glsl --target shadertoy` into shadertoy.com, or render with `sdfc render`.');
    return;
  }

  function compile(type, src) {
    var s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS) && !gl.isContextLost())
      throw new Error('The shader does not compile:\n' + gl.getShaderInfoLog(s));
    return s;
  }
  var vs = '#version 300 es\nvoid main() {\n' +
           '  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);\n' +
           '  gl_Position = vec4(p, 0.0, 1.0);\n}\n';
  var fs = document.getElementById('sdf-fragment').textContent.replace(/^\s+/, '');
  var prog, tCompile = performance.now();
  try {
    prog = gl.createProgram();
    gl.attachShader(prog, compile(gl.VERTEX_SHADER, vs));
    gl.attachShader(prog, compile(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS) && !gl.isContextLost())
      throw new Error('The shader does not link:\n' + gl.getProgramInfoLog(prog));
  } catch (e) {
    fail(String(e.message || e));
    return;
  }
  gl.useProgram(prog);
  tCompile = performance.now() - tCompile;
  var loc = {};
  ['iResolution', 'iTime', 'iMouse', 'uOrbit', 'uPan'].forEach(function (n) { loc[n] = gl.getUniformLocation(prog, n); });

  // View state: the script's camera until the user moves it.
  var view = { on: false, yaw: 0, pitch: 0, zoom: 1, panX: 0, panY: 0 };
  var time = 0, playing = false, scale = 1, dirty = true, lastMs = 0;

  function draw() {
    var dpr = window.devicePixelRatio || 1;
    var s = capture ? 1 : scale;
    var w = Math.max(1, Math.round(canvas.clientWidth * dpr * s));
    var h = Math.max(1, Math.round(canvas.clientHeight * dpr * s));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    gl.viewport(0, 0, w, h);
    gl.uniform3f(loc.iResolution, w, h, 1);
    gl.uniform1f(loc.iTime, time);
    gl.uniform4f(loc.iMouse, 0, 0, 0, 0);
    gl.uniform4f(loc.uOrbit, view.yaw, view.pitch, view.zoom, view.on ? 1 : 0);
    gl.uniform2f(loc.uPan, view.panX, view.panY);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    dirty = false;
  }

  if (capture) {
    // One frame at the script's camera and time 0, finished before the page counts as loaded.
    var tDraw = performance.now();
    draw();
    gl.finish();
    tDraw = performance.now() - tDraw;
    document.title = 'sdfc preview: rendered';
    console.log('sdfc preview: shader compiled and linked in ' + tCompile.toFixed(0) + ' ms, frame drawn in ' + tDraw.toFixed(0) + ' ms');
    window.addEventListener('resize', function () { draw(); gl.finish(); });
    return;
  }

  var playBtn = document.getElementById('play'), slider = document.getElementById('time');
  var tlabel = document.getElementById('tlabel'), stats = document.getElementById('stats');
  if (!usesTime) tlabel.title = 'This scene does not depend on time';
  function setTime(t) {
    var max = parseFloat(slider.max);
    if (t > max) t = t % max;
    time = t;
    slider.value = String(t);
    tlabel.textContent = 't = ' + t.toFixed(2) + ' s';
    dirty = true;
  }
  playBtn.addEventListener('click', function () { playing = !playing; playBtn.textContent = playing ? 'Pause' : 'Play'; lastMs = 0; });
  slider.addEventListener('input', function () { setTime(parseFloat(slider.value)); });
  document.getElementById('scale').addEventListener('change', function (e) { scale = parseFloat(e.target.value); dirty = true; });
  function reset() { view = { on: false, yaw: 0, pitch: 0, zoom: 1, panX: 0, panY: 0 }; dirty = true; }
  document.getElementById('reset').addEventListener('click', reset);
  canvas.addEventListener('dblclick', reset);
  window.addEventListener('keydown', function (e) { if (e.code === 'Space' && e.target === document.body) { e.preventDefault(); playBtn.click(); } });

  var drag = null;
  canvas.addEventListener('contextmenu', function (e) { e.preventDefault(); });
  canvas.addEventListener('pointerdown', function (e) {
    drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.button === 1 || e.shiftKey };
    canvas.setPointerCapture(e.pointerId);
    canvas.className = 'dragging';
  });
  canvas.addEventListener('pointermove', function (e) {
    if (!drag) return;
    var dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    var W = Math.max(canvas.clientWidth, 1), H = Math.max(canvas.clientHeight, 1);
    view.on = true;
    if (drag.pan) {
      view.panX -= dx / H;
      view.panY += dy / H;
    } else {
      view.yaw -= 2 * Math.PI * dx / W;
      view.pitch = Math.max(-3, Math.min(3, view.pitch + Math.PI * dy / H));
    }
    dirty = true;
  });
  function endDrag(e) { drag = null; canvas.className = ''; }
  canvas.addEventListener('pointerup', endDrag);
  canvas.addEventListener('pointercancel', endDrag);
  canvas.addEventListener('wheel', function (e) {
    e.preventDefault();
    view.on = true;
    view.zoom = Math.max(0.02, Math.min(50, view.zoom * Math.exp(e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015))));
    dirty = true;
  }, { passive: false });
  window.addEventListener('resize', function () { dirty = true; });
  canvas.addEventListener('webglcontextlost', function (e) { e.preventDefault(); fail('The WebGL context was lost (the shader may take too long for this GPU). Reload the page, perhaps with a lower resolution.'); });

  function frame(ms) {
    if (playing) {
      if (lastMs) setTime(time + (ms - lastMs) / 1000);
      lastMs = ms;
    }
    if (dirty) {
      draw();
      stats.textContent = canvas.width + '\u00d7' + canvas.height;
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);
})();
</script>
</body>
</html>
)HTML";

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

// The page for `shader` (a complete GLSL ES 3.00 fragment shader starting with #version).
inline std::string html_page(std::string_view title, std::string_view shader, bool uses_time) {
    std::string page = kHtmlTemplate;
    auto put = [&](std::string_view key, std::string_view value) {
        size_t p = page.find(key);
        if (p != std::string::npos) page.replace(p, key.size(), value);
    };
    put("@TITLE@", html_escape(title));
    put("@USES_TIME@", uses_time ? "true" : "false");
    put("@SHADER@", shader);  // last: the shader's text is not searched for keys
    return page;
}

}  // namespace sdfc::glsl
