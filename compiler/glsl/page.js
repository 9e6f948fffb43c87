//! The script of the --target html page (page.html), pasted inline at its @PAGE_JS@ line:
//! WebGL2 setup, the orbit camera, time and resolution controls, and #capture for tests/gpu.
//! glsl_html.hpp fills in @USES_TIME@.
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
