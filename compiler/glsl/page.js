//! The script of the --target html page (page.html), pasted inline at its @PAGE_JS@ line:
//! WebGL2 setup, the orbit camera, time and resolution controls, #capture for tests/gpu, and
//! the live mode of `sdfc preview` (shaders and script errors from its /events stream).
//! glsl_html.hpp fills in @USES_TIME@ and @LIVE@.
(function () {
  'use strict';
  // #capture: no controls, the canvas fills the window, one frame at the script's camera and
  // time 0 (redrawn if the window is resized); #capture=WxH: a canvas of exactly W x H CSS pixels.
  var cap = /(?:^|[#&?])capture(?:=(\d+)x(\d+))?(?:$|&)/.exec(location.hash);
  var capture = !!cap;
  var usesTime = @USES_TIME@;
  var live = @LIVE@;  // sdfc preview's page: the shader comes from the server
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
  // A linked program and its uniforms, or an Error with the driver's log.
  function program(fs) {
    var prog = gl.createProgram();
    try {
      gl.attachShader(prog, compile(gl.VERTEX_SHADER, vs));
      gl.attachShader(prog, compile(gl.FRAGMENT_SHADER, fs));
      gl.linkProgram(prog);
      if (!gl.getProgramParameter(prog, gl.LINK_STATUS) && !gl.isContextLost())
        throw new Error('The shader does not link:\n' + gl.getProgramInfoLog(prog));
    } catch (e) {
      gl.deleteProgram(prog);
      throw e;
    }
    var loc = {};
    ['iResolution', 'iTime', 'iMouse', 'uOrbit', 'uPan'].forEach(function (n) { loc[n] = gl.getUniformLocation(prog, n); });
    return { prog: prog, loc: loc };
  }
  var cur = null, tCompile = 0;  // the program drawn; ms its compile and link took
  if (!live) {
    tCompile = performance.now();
    try {
      cur = program(document.getElementById('sdf-fragment').textContent.replace(/^\s+/, ''));
    } catch (e) {
      fail(String(e.message || e));
      return;
    }
    tCompile = performance.now() - tCompile;
  }

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
    dirty = false;
    if (!cur) { gl.clearColor(0.07, 0.07, 0.07, 1); gl.clear(gl.COLOR_BUFFER_BIT); return; }
    var loc = cur.loc;
    gl.useProgram(cur.prog);
    gl.uniform3f(loc.iResolution, w, h, 1);
    gl.uniform1f(loc.iTime, time);
    gl.uniform4f(loc.iMouse, 0, 0, 0, 0);
    gl.uniform4f(loc.uOrbit, view.yaw, view.pitch, view.zoom, view.on ? 1 : 0);
    gl.uniform2f(loc.uPan, view.panX, view.panY);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
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

  var reportDue = false;  // live: tell the server what the page shows, after the next draw

  function frame(ms) {
    if (playing) {
      if (lastMs) setTime(time + (ms - lastMs) / 1000);
      lastMs = ms;
    }
    if (dirty) {
      draw();
      stats.textContent = canvas.width + '\u00d7' + canvas.height;
    }
    if (reportDue) report();
    requestAnimationFrame(frame);
  }

  // ---- live: sdfc preview sends each scene's shader (event `scene`) or its error (`failed`).
  // The view, the time and the resolution stay; a script error shows over the last picture.
  var seen = { server: '', version: 0 }, drawnVersion = 0, problemText = '';
  function showProblem(text) {
    problemText = text;
    var box = document.getElementById('problem');
    box.textContent = text;
    box.style.display = text ? 'block' : 'none';
  }
  function fresh(m) {  // not a resend of what the page has (a reconnect resends the newest)
    if (m.server === seen.server && m.version <= seen.version) return false;
    seen = { server: m.server, version: m.version };
    return true;
  }
  function listen() {
    stats.textContent = 'waiting for sdfc preview';
    var events = new EventSource('/events');
    events.addEventListener('scene', function (e) {
      var m = JSON.parse(e.data);
      if (!fresh(m)) return;
      var t0 = performance.now();
      try {
        var next = program(m.shader);
        if (cur) gl.deleteProgram(cur.prog);
        cur = next;
        drawnVersion = m.version;
        usesTime = m.uses_time;
        tlabel.title = usesTime ? '' : 'This scene does not depend on time';
        document.title = m.title + ' - sdfc preview';
        showProblem('');
      } catch (err) {
        showProblem(String(err.message || err));
      }
      tCompile = performance.now() - t0;
      dirty = reportDue = true;
    });
    events.addEventListener('failed', function (e) {
      var m = JSON.parse(e.data);
      if (!fresh(m)) return;
      showProblem(m.message);
      dirty = reportDue = true;
    });
    events.onerror = function () { stats.textContent = 'sdfc preview is not answering (retrying)'; };
  }
  // What the page shows: the newest version it has, the one it draws, the error it shows,
  // and the colour at the centre of the canvas (GET /report on the server answers it back).
  function report() {
    reportDue = false;
    var px = new Uint8Array(4);
    if (cur) gl.readPixels(canvas.width >> 1, canvas.height >> 1, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    var body = new URLSearchParams({ server: seen.server, version: String(seen.version), drawn: String(drawnVersion),
                                     error: problemText, compile_ms: tCompile.toFixed(0), width: String(canvas.width),
                                     height: String(canvas.height), pixel: px[0] + ',' + px[1] + ',' + px[2] });
    fetch('/report', { method: 'POST', body: body }).catch(function () {});
  }
  if (live) listen();
  requestAnimationFrame(frame);
})();
