//! The script of the --target html page (page.html), pasted inline at its @PAGE_JS@ line:
//! WebGL2 setup, progressive drawing (a quick low-resolution picture, then every sample of the
//! full one in bands, summed in a float texture), the orbit camera, the knobs (samples, steps,
//! bounces, resolution) and the script's parameters as uniforms, #capture for tests/gpu, and
//! the live mode of `sdfc preview` (shaders and script errors from its /events stream).
//! glsl_html.hpp fills in @LIVE@; the scene's facts come as JSON in #sdf-scene.
(function () {
  'use strict';
  // #capture: no controls, the canvas fills the window, one frame at the script's camera and
  // time 0, drawn to the end before the page counts as loaded; #capture=WxH: a canvas of
  // exactly W x H CSS pixels. The console says when the first picture and the last were done.
  var cap = /(?:^|[#&?])capture(?:=(\d+)x(\d+))?(?:$|&)/.exec(location.hash);
  var capture = !!cap;
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
  // Float targets for the sum of samples; without them every sample is drawn in one pass.
  var floats = !!gl.getExtension('EXT_color_buffer_float');

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
  var kUniforms = ['iResolution', 'iTime', 'iMouse', 'uOrbit', 'uPan', 'sdf_tape', 'uPass', 'uSample', 'uSum', 'uQuick',
                   'uSamples', 'uMaxSteps', 'uMaxBounces'];
  // A linked program and its uniforms, or an Error with the driver's log.
  var linked = 0;  // programs linked (a param's slider must not add one)
  function program(fs, params) {
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
    ++linked;
    var loc = {};
    kUniforms.forEach(function (n) { loc[n] = gl.getUniformLocation(prog, n); });
    params.forEach(function (p) { loc['param:' + p.name] = gl.getUniformLocation(prog, p.uniform); });
    return { prog: prog, loc: loc };
  }

  // The tape of a long scene (compiler/glsl/glsl_tape.hpp): base64 words, uploaded as an
  // RGBA32UI texture of 1024 texels a row on unit 0, where the shader's sdf_tape reads it.
  var tapeTex = null;
  // A tape taller than the GPU's textures is an error on the page, and the last one stays.
  function uploadTape(b64) {
    var bin = b64 ? atob(b64) : '', width = 1024, texels = bin.length >> 4, rows = Math.max(1, Math.ceil(texels / width));
    var most = gl.getParameter(gl.MAX_TEXTURE_SIZE);
    if (b64 && rows > most)
      throw new Error('the scene\'s tape (' + texels + ' texels) is over this GPU\'s texture size (' + width + ' x ' + most +
                      '): simplify the scene, or use sdfc glsl --target shadertoy');
    if (tapeTex) { gl.deleteTexture(tapeTex); tapeTex = null; }
    if (!b64) return;
    var bytes = new Uint8Array(rows * width * 16);
    for (var i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    tapeTex = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, tapeTex);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32UI, width, rows, 0, gl.RGBA_INTEGER, gl.UNSIGNED_INT, new Uint32Array(bytes.buffer));
  }

  // The scene: its facts (knob defaults, parameters, time) and the program drawing it.
  var scene = { uses_time: false, samples: 1, max_steps: 256, max_bounces: 3, params: [] };
  var cur = null, tCompile = 0;
  var knobs = { samples: 0, steps: 0, bounces: -1 };  // 0 / -1: the script's
  var paramValues = Object.create(null), controls = false;  // (no inherited names: a param may be called constructor)
  function setScene(info) {
    scene = info;
    scene.params = scene.params || [];
    scene.params.forEach(function (p) { if (!(p.name in paramValues)) paramValues[p.name] = p.value; });
    if (controls) buildControls();
  }
  if (!live) {
    setScene(JSON.parse(document.getElementById('sdf-scene').textContent));
    tCompile = performance.now();
    try {
      uploadTape(document.getElementById('sdf-tape').textContent.trim());
      cur = program(document.getElementById('sdf-fragment').textContent.replace(/^\s+/, ''), scene.params);
    } catch (e) {
      fail(String(e.message || e));
      return;
    }
    tCompile = performance.now() - tCompile;
  }

  // ---- drawing ----
  // View state: the script's camera until the user moves it.
  var view = { on: false, yaw: 0, pitch: 0, zoom: 1, panX: 0, panY: 0 };
  var time = 0, playing = false, scale = 1, dirty = true, lastMs = 0;
  // The sum of samples (RGBA16F, alpha: their weight) and the quick picture, sized to the canvas.
  var tg = { w: 0, h: 0, qw: 0, qh: 0, sum: null, sumFbo: null, quick: null, quickFbo: null };
  // Progress: 'quick', then 'refine' (sample `sample`, rows from `row` down, `rows` a band), then 'done'.
  var pg = { phase: 'quick', sample: 0, row: 0, rows: 8, t0: 0, first: 0, last: 0 };

  function floatTarget(w, h, filter) {
    var t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, filter);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA16F, w, h, 0, gl.RGBA, gl.HALF_FLOAT, null);
    var f = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, f);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, t, 0);
    var ok = gl.checkFramebufferStatus(gl.FRAMEBUFFER) === gl.FRAMEBUFFER_COMPLETE;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return ok ? { tex: t, fbo: f } : null;
  }
  function sizeTargets(w, h) {
    if (tg.w === w && tg.h === h) return;
    [tg.sum, tg.quick].forEach(function (t) { if (t) gl.deleteTexture(t); });
    [tg.sumFbo, tg.quickFbo].forEach(function (f) { if (f) gl.deleteFramebuffer(f); });
    // The quick picture: at most a quarter of the size, and about 160 x 90 pixels.
    var s = Math.min(0.25, Math.sqrt(14400 / (w * h)));
    tg.w = w; tg.h = h; tg.qw = Math.max(1, Math.round(w * s)); tg.qh = Math.max(1, Math.round(h * s));
    var a = floatTarget(w, h, gl.NEAREST), b = floatTarget(tg.qw, tg.qh, gl.LINEAR);
    if (!a || !b) { floats = false; return; }
    tg.sum = a.tex; tg.sumFbo = a.fbo; tg.quick = b.tex; tg.quickFbo = b.fbo;
  }
  function samples() { return knobs.samples || scene.samples; }
  function uniforms(w, h, pass) {
    var loc = cur.loc;
    gl.useProgram(cur.prog);
    gl.uniform3f(loc.iResolution, w, h, 1);
    gl.uniform1f(loc.iTime, time);
    gl.uniform4f(loc.iMouse, 0, 0, 0, 0);
    gl.uniform4f(loc.uOrbit, view.yaw, view.pitch, view.zoom, view.on ? 1 : 0);
    gl.uniform2f(loc.uPan, view.panX, view.panY);
    gl.uniform1i(loc.uPass, pass);
    gl.uniform1i(loc.uSample, pg.sample);
    gl.uniform1i(loc.uSamples, samples());
    gl.uniform1i(loc.uMaxSteps, knobs.steps || scene.max_steps);
    gl.uniform1i(loc.uMaxBounces, knobs.bounces >= 0 ? knobs.bounces : scene.max_bounces);
    scene.params.forEach(function (p) { gl.uniform1f(loc['param:' + p.name], paramValues[p.name]); });
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, tapeTex);
    gl.uniform1i(loc.sdf_tape, 0);
    gl.uniform1i(loc.uSum, 1);
    gl.uniform1i(loc.uQuick, 2);
    // The sum and quick textures are bound only to be read: a target bound as a texture is a loop.
    gl.activeTexture(gl.TEXTURE1);
    gl.bindTexture(gl.TEXTURE_2D, pass === 2 ? tg.sum : null);
    gl.activeTexture(gl.TEXTURE2);
    gl.bindTexture(gl.TEXTURE_2D, pass === 2 ? tg.quick : null);
  }
  // Waits for the GPU (a one-pixel read): the times the page reports are the GPU's.
  var px1 = new Float32Array(4), px8 = new Uint8Array(4);
  function sync(fbo) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
    if (fbo) gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.FLOAT, px1);
    else gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px8);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }
  function restart() {
    pg.phase = 'quick'; pg.sample = 0; pg.row = 0; pg.t0 = performance.now();
    if (floats && tg.sumFbo) {
      gl.bindFramebuffer(gl.FRAMEBUFFER, tg.sumFbo);
      gl.clearColor(0, 0, 0, 0);
      gl.clear(gl.COLOR_BUFFER_BIT);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    }
  }
  // One step of the progression; true while there is more to draw.
  function step(budgetMs) {
    var w = canvas.width, h = canvas.height;
    if (!floats) {  // every sample at once, display-ready
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.viewport(0, 0, w, h);
      uniforms(w, h, 0);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      sync(null);
      pg.first = pg.last = performance.now() - pg.t0;
      pg.phase = 'done';
      return false;
    }
    if (pg.phase === 'quick') {
      gl.bindFramebuffer(gl.FRAMEBUFFER, tg.quickFbo);
      gl.viewport(0, 0, tg.qw, tg.qh);
      gl.clearColor(0, 0, 0, 0);
      gl.clear(gl.COLOR_BUFFER_BIT);
      pg.sample = 0;
      uniforms(tg.qw, tg.qh, 1);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      sync(tg.quickFbo);
      pg.phase = 'refine';
      pg.row = 0;
      pg.first = pg.last = performance.now() - pg.t0;
      return true;
    }
    if (pg.phase !== 'refine') return false;
    // Bands of whole rows from the top, sized to take about budgetMs each.
    var rows = Math.max(1, Math.min(h - pg.row, pg.rows));
    var t = performance.now();
    gl.bindFramebuffer(gl.FRAMEBUFFER, tg.sumFbo);
    gl.viewport(0, 0, w, h);
    gl.enable(gl.SCISSOR_TEST);
    gl.scissor(0, h - pg.row - rows, w, rows);
    gl.enable(gl.BLEND);
    gl.blendFunc(gl.ONE, gl.ONE);
    uniforms(w, h, 1);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    gl.disable(gl.BLEND);
    gl.disable(gl.SCISSOR_TEST);
    sync(tg.sumFbo);
    var took = Math.max(performance.now() - t, 0.5);
    pg.rows = Math.max(1, Math.min(h, Math.round(rows * Math.min(4, budgetMs / took))));
    pg.row += rows;
    if (pg.row >= h) {
      pg.row = 0;
      if (++pg.sample >= samples()) pg.phase = 'done';
    }
    pg.last = performance.now() - pg.t0;
    return pg.phase !== 'done';
  }
  // The sum so far (the quick picture where it has nothing), tone mapped, on the canvas.
  function show() {
    var w = canvas.width, h = canvas.height;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, w, h);
    uniforms(w, h, 2);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }
  function resize() {
    var dpr = window.devicePixelRatio || 1;
    var s = capture ? 1 : scale;
    var w = Math.max(1, Math.round(canvas.clientWidth * dpr * s));
    var h = Math.max(1, Math.round(canvas.clientHeight * dpr * s));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    if (floats) sizeTargets(w, h);
  }

  // ---- controls ----
  var playBtn = document.getElementById('play'), slider = document.getElementById('time');
  var tlabel = document.getElementById('tlabel'), stats = document.getElementById('stats');
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
  [['samples', 'samples'], ['steps', 'steps'], ['bounces', 'bounces']].forEach(function (k) {
    document.getElementById(k[0]).addEventListener('change', function (e) { knobs[k[1]] = parseInt(e.target.value, 10); dirty = true; });
  });
  // A param's value as its slider shows it: a whole number as it is (a count reads 6, not
  // 6.00), else 3 significant digits without trailing zeros.
  function shown(v) { v = Number(v); return Number.isInteger(v) ? String(v) : String(Number(v.toPrecision(3))); }
  // The script's parameters (param name = value in [lo, hi]): a slider each, a uniform each.
  function buildControls() {
    tlabel.title = scene.uses_time ? '' : 'This scene does not depend on time';
    var box = document.getElementById('params');
    if (!box) return;
    box.textContent = '';
    scene.params.forEach(function (p) {
      var label = document.createElement('label'), input = document.createElement('input'), out = document.createElement('span');
      input.type = 'range';
      input.min = String(p.min); input.max = String(p.max); input.step = String(p.step);
      input.value = String(paramValues[p.name]);
      input.setAttribute('data-param', p.name);
      out.textContent = shown(paramValues[p.name]);
      input.addEventListener('input', function () {
        paramValues[p.name] = parseFloat(input.value);
        out.textContent = shown(paramValues[p.name]);
        dirty = true;
      });
      label.appendChild(document.createTextNode(p.name + ' '));
      label.appendChild(input);
      label.appendChild(out);
      box.appendChild(label);
    });
  }
  controls = true;
  buildControls();
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

  if (capture) {
    // The whole progression now, each band up to a second, before the page counts as loaded;
    // then each &param=NAME:VALUE of the address through its slider, and again.
    var run = function (what) {
      resize();
      restart();
      step(1000);
      show();
      console.log('sdfc preview: ' + what + 'first picture at ' + performance.now().toFixed(0) + ' ms (' + tg.qw + 'x' + tg.qh +
                  ', shader compiled and linked in ' + tCompile.toFixed(0) + ' ms)');
      while (step(1000)) {}
      show();
      sync(null);
      gl.readPixels(canvas.width >> 1, canvas.height >> 1, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px8);
      console.log('sdfc preview: ' + what + 'refined picture at ' + performance.now().toFixed(0) + ' ms (' + canvas.width + 'x' +
                  canvas.height + ', ' + samples() + ' samples, ' + linked + ' program linked, centre pixel ' + px8[0] + ',' + px8[1] +
                  ',' + px8[2] + ')');
    };
    run('');
    var sets = location.hash.match(/param=[A-Za-z_][A-Za-z0-9_]*:[-0-9.e]+/g) || [];
    sets.forEach(function (kv) {
      var m = /param=([^:]+):(.*)/.exec(kv), input = document.querySelector('input[data-param="' + m[1] + '"]');
      if (!input) { console.log('sdfc preview: no param ' + m[1]); return; }
      input.value = m[2];
      input.dispatchEvent(new Event('input'));
      run('after ' + m[1] + ' = ' + m[2] + ': ');
    });
    // The finished picture, read back, as an image in place of the canvas and on the console
    // (tests/gpu reads it there: Chromium's headless --screenshot may show the page before
    // the progression ends).
    var w = canvas.width, h = canvas.height, pixels = new Uint8Array(w * h * 4);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    var c2 = document.createElement('canvas');
    c2.width = w;
    c2.height = h;
    var ctx = c2.getContext('2d'), data = ctx.createImageData(w, h);
    for (var y = 0; y < h; ++y) data.data.set(pixels.subarray((h - 1 - y) * w * 4, (h - y) * w * 4), y * w * 4);  // rows from the top
    ctx.putImageData(data, 0, 0);
    var img = document.createElement('img');
    img.id = 'captured';
    img.src = c2.toDataURL('image/png');
    console.log('sdfc preview: picture ' + img.src);
    img.style.cssText = 'display:block;width:' + canvas.style.width + ';height:' + canvas.style.height;
    canvas.style.display = 'none';
    document.body.insertBefore(img, canvas);
    document.title = 'sdfc preview: rendered';
    return;
  }

  var reportDue = false;  // live: tell the server what the page shows, after the next picture

  function frame(ms) {
    if (playing) {
      if (lastMs) setTime(time + (ms - lastMs) / 1000);
      lastMs = ms;
    }
    if (cur) {
      if (dirty) {
        resize();
        restart();
        dirty = false;
      }
      if (pg.phase !== 'done') {
        // While the view moves, quick pictures only; then the bands, about 40 ms a frame.
        step(40);
        show();
      }
      stats.textContent = canvas.width + '\u00d7' + canvas.height + ' \u00b7 shader ' + tCompile.toFixed(0) + ' ms \u00b7 first picture ' +
                          (pg.first / 1000).toFixed(2) + ' s \u00b7 ' + (pg.phase === 'done' ? samples() : pg.sample) + '/' + samples() +
                          ' samples \u00b7 ' + (pg.last / 1000).toFixed(2) + ' s';
    } else {
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.clearColor(0.07, 0.07, 0.07, 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
    }
    if (reportDue && (!cur || pg.phase === 'done')) report();
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
        var next = program(m.shader, m.scene.params || []);
        try {
          uploadTape(m.tape || '');
        } catch (err) {
          gl.deleteProgram(next.prog);
          throw err;
        }
        if (cur) gl.deleteProgram(cur.prog);
        cur = next;
        drawnVersion = m.version;
        setScene(m.scene);
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
      reportDue = true;
    });
    events.onerror = function () { stats.textContent = 'sdfc preview is not answering (retrying)'; };
  }
  // What the page shows: the newest version it has, the one it draws, the error it shows,
  // and the colour at the centre of the canvas (GET /report on the server answers it back).
  function report() {
    reportDue = false;
    var px = new Uint8Array(4);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    if (cur) gl.readPixels(canvas.width >> 1, canvas.height >> 1, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    var body = new URLSearchParams({ server: seen.server, version: String(seen.version), drawn: String(drawnVersion),
                                     error: problemText, compile_ms: tCompile.toFixed(0), width: String(canvas.width),
                                     height: String(canvas.height), pixel: px[0] + ',' + px[1] + ',' + px[2] });
    fetch('/report', { method: 'POST', body: body }).catch(function () {});
  }
  if (live) listen();
  requestAnimationFrame(frame);
})();
