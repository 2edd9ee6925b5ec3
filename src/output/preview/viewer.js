// leafmagic preview: plays recorded motion in 3-D, offline, with no library.
// WebGL when the browser has it, Canvas 2D (painter's algorithm) when not;
// both draw the same shaded triangles and lines from the same camera.
// URL hash or query: t=SECONDS (paused there), follow=OBJECT, speed=X,
// renderer=2d|webgl, yaw=DEG, pitch=DEG.
'use strict';
(function () {
  // ----- data -----
  const data = JSON.parse(document.getElementById('leafmagic-data').textContent);
  function f32(b64) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Float32Array(bytes.buffer);
  }
  // Each object holds the frames of its own life, from clip frame `first`
  // (a particle born or killed during the shot); outside it, it is hidden.
  // A marker (a particle, a path from video) comes as its centre per frame
  // and its size, and is drawn as three crossed lines that size.
  const objs = data.objects.map(function (o) {
    const P = f32(o.pos);
    const mk = o.marker || 0, n = mk ? 6 : o.n;
    return { name: o.name, kind: o.kind, label: o.label, color: o.color, n: n, np: o.n, mk: mk,
      tris: o.tris, segs: mk ? [0, 1, 2, 3, 4, 5] : o.segs, P: P, first: o.first || 0, still: !!o.still,
      frames: o.n > 0 ? P.length / (o.n * 3) : 1, shown: true, cur: new Float32Array(n * 3) };
  });
  // A directed scene's verdicts: each leaf coloured by whether it met all
  // its goals, and labelled with those it missed and by how far.
  const GOAL = [1.0, 0.72, 0.2], MET = [0.3, 0.9, 0.4], MISSED = [0.95, 0.25, 0.25];
  const verdicts = {};
  (data.goals || []).forEach(function (g) {
    g.leaves.forEach(function (l) { (verdicts[l.name] = verdicts[l.name] || []).push([g.name, l]); });
  });
  objs.forEach(function (o) {
    const v = verdicts[o.name];
    if (!v) return;
    const missed = v.filter(function (x) { return !x[1].met; });
    o.color = missed.length ? MISSED : MET;
    o.label = missed.length
      ? 'missed: ' + missed.map(function (x) { return x[0] + ' (' + x[1].distance.toFixed(3) + ' m off)'; }).join(', ')
      : 'met: ' + v.map(function (x) { return x[0]; }).join(', ');
  });
  const F = data.frames, fps = data.fps, T = Math.max(0, (F - 1) / fps);
  // More labelled objects than this in view, and only the followed one is labelled.
  const MAX_LABELS = 40;

  function params() {
    const p = {};
    const s = (location.hash || '').replace(/^#/, '') + '&' + (location.search || '').replace(/^\?/, '');
    s.split('&').forEach(function (kv) {
      if (!kv) return;
      const i = kv.indexOf('=');
      const k = decodeURIComponent(i < 0 ? kv : kv.slice(0, i));
      p[k] = i < 0 ? '' : decodeURIComponent(kv.slice(i + 1));
    });
    return p;
  }
  const P = params();

  // ----- state -----
  const st = { t: 0, playing: true, speed: 1, follow: '', yaw: -0.9, pitch: 0.55, dist: 1,
    align: !!data.grid && P.align !== '0' };
  if (P.t !== undefined && isFinite(parseFloat(P.t))) {
    st.t = Math.min(Math.max(parseFloat(P.t), 0), T);
    st.playing = false;
  }
  // A grid of bred leaves is laid along x: look along +y so it reads left to right.
  if (data.grid) { st.yaw = -Math.PI / 2; st.pitch = 0.6; }
  if (P.speed && isFinite(parseFloat(P.speed))) st.speed = parseFloat(P.speed);
  if (P.yaw && isFinite(parseFloat(P.yaw))) st.yaw = parseFloat(P.yaw) * Math.PI / 180;
  if (P.pitch && isFinite(parseFloat(P.pitch))) st.pitch = parseFloat(P.pitch) * Math.PI / 180;
  if (P.follow && objs.some(function (o) { return o.name === P.follow; })) st.follow = P.follow;
  // A recorded fall beside its still path: the camera on the fall, its
  // path passing by (all objects at once would make a 5 cm plate a dot on
  // a metres-long line).
  const movers = objs.filter(function (o) { return !o.still; });
  if (P.follow === undefined && movers.length === 1 && movers.length < objs.length) st.follow = movers[0].name;

  // Positions of every object at time t (linear between frames, as glTF
  // LINEAR plays the exported file), and which objects live then.
  function update(t) {
    const g = Math.min(Math.max(t * fps, 0), F - 1);
    objs.forEach(function (o) {
      const G = o.frames, f = g - o.first;
      // Half a frame's grace at either end, so that a life of one frame shows.
      // A still object (a record's path) holds one frame, shown throughout.
      o.shown = o.still || (f > -0.5 && f < G - 0.5);
      // Outside its life it keeps the pose of its nearest frame: a camera
      // on it waits where it will appear, or stays where it went.
      const fc = Math.min(Math.max(f, 0), G - 1);
      const k = Math.min(Math.floor(fc), Math.max(G - 2, 0));
      const a = G > 1 ? fc - k : 0;
      const k1 = G > 1 ? k + 1 : k;
      const s = k * o.np * 3, e = k1 * o.np * 3, P = o.P, c = o.cur;
      for (let i = 0; i < o.np * 3; i++) c[i] = P[s + i] * (1 - a) + P[e + i] * a;
      if (o.mk) {
        const x = c[0], y = c[1], z = c[2], h = o.mk / 2;
        for (let i = 0; i < 6; i++) {
          const d = i >> 1, sg = i & 1 ? 1 : -1;
          c[3 * i] = x + (d === 0 ? sg * h : 0);
          c[3 * i + 1] = y + (d === 1 ? sg * h : 0);
          c[3 * i + 2] = z + (d === 2 ? sg * h : 0);
        }
      }
      // Side by side, bred leaves fall at different speeds and drift, and
      // soon lie metres apart; aligned, each is drawn about its centre of
      // mass in its own place of the grid (its descent and drift go into
      // the label), so attitude and spin compare at a glance.
      const m = [0, 0, 0];
      for (let i = 0; i < o.n; i++) for (let d = 0; d < 3; d++) m[d] += c[3 * i + d] / o.n;
      if (!o.home) o.home = [0, 1, 2].map(function (d) {
        let h = 0;
        for (let i = 0; i < o.np; i++) h += P[3 * i + d] / o.np;
        return h;
      });
      o.z = m[2] - o.home[2];
      o.drift = Math.hypot(m[0] - o.home[0], m[1] - o.home[1]);
      if (st.align) {
        for (let i = 0; i < o.n; i++) for (let d = 0; d < 3; d++) c[3 * i + d] += o.home[d] - m[d];
      }
    });
  }
  function centre(o) {
    const c = [0, 0, 0];
    for (let i = 0; i < o.n; i++) for (let d = 0; d < 3; d++) c[d] += o.cur[3 * i + d];
    return c.map(function (x) { return x / Math.max(o.n, 1); });
  }
  function radius(o, c) {
    let r = 0;
    for (let i = 0; i < o.n; i++) {
      const dx = o.cur[3 * i] - c[0], dy = o.cur[3 * i + 1] - c[1], dz = o.cur[3 * i + 2] - c[2];
      r = Math.max(r, Math.sqrt(dx * dx + dy * dy + dz * dz));
    }
    return r;
  }
  // The camera's target: the chosen object's centre (alive or not), or the
  // mean of the centres of all objects alive (the paper's user-centred
  // camera follows an object); with none alive, where it last was.
  let lastTarget = [0, 0, 0];
  function live() { return objs.filter(function (o) { return o.shown; }); }
  function target() {
    if (st.follow) {
      const o = objs.find(function (o) { return o.name === st.follow; });
      if (o) return (lastTarget = centre(o));
    }
    const on = live();
    if (on.length === 0) return lastTarget;
    const c = [0, 0, 0];
    on.forEach(function (o) { const m = centre(o); for (let d = 0; d < 3; d++) c[d] += m[d] / on.length; });
    return (lastTarget = c);
  }
  // The first time anything lives (a cache whose particles are all born
  // after its first key shows nothing at 0).
  const born = objs.reduce(function (t, o) { return Math.min(t, o.first / fps); }, T);
  function fitDistance() {
    update(st.t);
    // Fit the view to the objects alive, or, with none, to the first born.
    if (!st.follow && live().length === 0) update(born);
    const c = target();
    let r = 0;
    (st.follow ? objs : live()).forEach(function (o) {
      if (st.follow && o.name !== st.follow) return;
      const m = centre(o);
      const d = Math.hypot(m[0] - c[0], m[1] - c[1], m[2] - c[2]) + radius(o, m);
      r = Math.max(r, d);
    });
    // One object: leave room to see it move; all: fit them in the view.
    st.dist = Math.max(st.follow ? 4 * r : (data.grid ? 2.0 : 2.4) * r, 0.12);
    update(st.t);
  }
  fitDistance();
  const R0 = st.dist;
  // Where the objects start: line primitives are drawn along their axis
  // nearest to it (an axis is infinite; its glyph should be in view).
  update(0);
  if (live().length === 0) update(born);
  const C0 = target();
  update(st.t);

  // ----- math -----
  function sub(a, b) { return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]; }
  function cross(a, b) { return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]; }
  function dot(a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  function norm(a) { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; }
  function add(a, b, s) { return [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]; }
  // Column-major 4×4 (WebGL's layout).
  function mul(a, b) {
    const r = new Float32Array(16);
    for (let i = 0; i < 4; i++) for (let j = 0; j < 4; j++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += a[k * 4 + j] * b[i * 4 + k];
      r[i * 4 + j] = s;
    }
    return r;
  }
  function camera(w, h) {
    const c = target();
    const cp = Math.cos(st.pitch);
    const eye = [c[0] + st.dist * cp * Math.cos(st.yaw), c[1] + st.dist * cp * Math.sin(st.yaw),
      c[2] + st.dist * Math.sin(st.pitch)];
    const f = norm(sub(c, eye));
    const s = norm(cross(f, [0, 0, 1]));
    const u = cross(s, f);
    const view = new Float32Array([s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
      -dot(s, eye), -dot(u, eye), dot(f, eye), 1]);
    const near = st.dist * 0.01, far = st.dist * 200;
    const fy = 1 / Math.tan(Math.PI / 8), asp = w / Math.max(h, 1);
    const proj = new Float32Array([fy / asp, 0, 0, 0, 0, fy, 0, 0, 0, 0, (far + near) / (near - far), -1,
      0, 0, 2 * far * near / (near - far), 0]);
    return { m: mul(proj, view), centre: c, near: near, eye: eye, f: f };
  }
  function project(m, p, w, h) {
    const x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
    const y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
    const cw = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
    return [(x / cw + 1) * w / 2, (1 - y / cw) * h / 2, cw];
  }

  // ----- geometry of a frame: shaded triangles and coloured lines -----
  const LIGHT = norm([0.35, -0.45, 0.82]);
  const GRID = [0.42, 0.47, 0.54], WIND = [0.25, 0.8, 0.95];
  function glyphs() {
    const L = [];
    function seg(a, b) { L.push([a, b, WIND]); }
    function arrow(from, to) {
      seg(from, to);
      const d = norm(sub(to, from)), len = Math.hypot(to[0] - from[0], to[1] - from[1], to[2] - from[2]);
      let p = norm(cross(d, [0, 0, 1]));
      if (Math.hypot(p[0], p[1], p[2]) < 0.5 || !isFinite(p[0])) p = norm(cross(d, [1, 0, 0]));
      seg(to, add(add(to, d, -0.3 * len), p, 0.15 * len));
      seg(to, add(add(to, d, -0.3 * len), p, -0.15 * len));
    }
    const S = 0.25 * R0;
    (data.wind || []).forEach(function (g) {
      const p = g.point, d = g.direction;
      const out = g.strength >= 0;
      if (g.kind === 'uniform') {
        arrow(add(p, d, -S / 2), add(p, d, S / 2));
      } else if (g.kind === 'point_source' || g.kind === 'point_sink') {
        const sink = (g.kind === 'point_sink') === out;
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]].forEach(function (e) {
          if (sink) arrow(add(p, e, 0.6 * S), add(p, e, 0.1 * S)); else arrow(add(p, e, 0.1 * S), add(p, e, 0.6 * S));
        });
      } else {
        const along = dot(sub(C0, p), d);
        const o = add(p, d, along);
        seg(add(o, d, -2 * S), add(o, d, 2 * S));
        let u = norm(cross(d, [0, 0, 1]));
        if (!isFinite(u[0]) || Math.abs(dot(d, [0, 0, 1])) > 0.99) u = norm(cross(d, [1, 0, 0]));
        const v = cross(d, u);
        if (g.kind === 'line_vortex') {
          const r = 0.4 * S, n = 24, sign = g.strength >= 0 ? 1 : -1;
          let prev = null;
          for (let i = 0; i <= n; i++) {
            const a = sign * 2 * Math.PI * i / n;
            const q = add(add(o, u, r * Math.cos(a)), v, r * Math.sin(a));
            if (prev) { if (i === n) arrow(prev, q); else seg(prev, q); }
            prev = q;
          }
        } else {
          const sink = (g.kind === 'line_sink') === out;
          [u, v, [-u[0], -u[1], -u[2]], [-v[0], -v[1], -v[2]]].forEach(function (e) {
            if (sink) arrow(add(o, e, 0.6 * S), add(o, e, 0.1 * S)); else arrow(add(o, e, 0.1 * S), add(o, e, 0.6 * S));
          });
        }
      }
    });
    return L;
  }
  const windLines = glyphs();
  // The goals, still: a landing polygon on the ground, boxes, and marks
  // as rings of their tolerance in the three planes (an entered bin is
  // drawn as the object it is).
  function goalLines() {
    const L = [];
    function seg(a, b) { L.push([a, b, GOAL]); }
    (data.goals || []).forEach(function (g) {
      if (g.polygon) {
        const z = (g.ground || 0) + 1e-3, n = g.polygon.length;
        g.polygon.forEach(function (p, i) {
          const q = g.polygon[(i + 1) % n];
          seg([p[0], p[1], z], [q[0], q[1], z]);
        });
      }
      if (g.min && g.max) {
        const a = g.min, b = g.max;
        function c(i) { return [i & 1 ? b[0] : a[0], i & 2 ? b[1] : a[1], i & 4 ? b[2] : a[2]]; }
        for (let i = 0; i < 8; i++) [1, 2, 4].forEach(function (bit) { if (!(i & bit)) seg(c(i), c(i | bit)); });
      }
      if (g.point) {
        const p = g.point, r = g.tolerance || 0, n = 32;
        [[0, 1], [0, 2], [1, 2]].forEach(function (ax) {
          let prev = null;
          for (let i = 0; i <= n; i++) {
            const q = p.slice(), a = 2 * Math.PI * i / n;
            q[ax[0]] += r * Math.cos(a); q[ax[1]] += r * Math.sin(a);
            if (prev) seg(prev, q);
            prev = q;
          }
        });
      }
    });
    return L;
  }
  const goalGlyphs = goalLines();
  function groundLines(c) {
    if (data.ground === null || data.ground === undefined) return [];
    const z = data.ground;
    const step = Math.pow(10, Math.floor(Math.log10(Math.max(st.dist, 1e-3) / 2)));
    const n = 12, x0 = Math.round(c[0] / step) * step, y0 = Math.round(c[1] / step) * step;
    const L = [];
    for (let i = -n; i <= n; i++) {
      L.push([[x0 + i * step, y0 - n * step, z], [x0 + i * step, y0 + n * step, z], GRID]);
      L.push([[x0 - n * step, y0 + i * step, z], [x0 + n * step, y0 + i * step, z], GRID]);
    }
    return L;
  }
  // Cuts a line at the near plane (2 × near, to stay clear of it): a line
  // that passes behind the camera must not be dropped (Canvas 2D cannot
  // project it) nor left to the GPU (some software rasterisers lose it).
  function clipLine(ln, cam) {
    const lim = 2 * cam.near;
    const da = dot(sub(ln[0], cam.eye), cam.f), db = dot(sub(ln[1], cam.eye), cam.f);
    if (da < lim && db < lim) return null;
    if (da >= lim && db >= lim) return ln;
    const s = (lim - da) / (db - da);
    const p = add(ln[0], sub(ln[1], ln[0]), s);
    return da < lim ? [p, ln[1], ln[2]] : [ln[0], p, ln[2]];
  }
  function frame(cam) {
    const c = cam.centre;
    const tris = [], lines = [];
    live().forEach(function (o) {
      const q = o.cur;
      function v(i) { return [q[3 * i], q[3 * i + 1], q[3 * i + 2]]; }
      for (let k = 0; k < o.tris.length; k += 3) {
        const a = v(o.tris[k]), b = v(o.tris[k + 1]), cc = v(o.tris[k + 2]);
        const nrm = norm(cross(sub(b, a), sub(cc, a)));
        const s = 0.35 + 0.65 * Math.abs(dot(nrm, LIGHT));
        tris.push([a, b, cc, [o.color[0] * s, o.color[1] * s, o.color[2] * s]]);
      }
      for (let k = 0; k < o.segs.length; k += 2) lines.push([v(o.segs[k]), v(o.segs[k + 1]), o.color]);
    });
    const clipped = [];
    groundLines(c).concat(windLines, goalGlyphs, lines).forEach(function (ln) {
      const l = clipLine(ln, cam);
      if (l) clipped.push(l);
    });
    return { tris: tris, lines: clipped };
  }

  // ----- renderers -----
  const canvas = document.getElementById('scene');
  const overlay = document.getElementById('overlay');
  const BG = [0.114, 0.141, 0.188];
  function rgb(c) { return 'rgb(' + Math.round(255 * Math.min(c[0], 1)) + ',' + Math.round(255 * Math.min(c[1], 1)) + ',' + Math.round(255 * Math.min(c[2], 1)) + ')'; }

  function webgl() {
    let gl = null;
    try { gl = canvas.getContext('webgl', { antialias: true, preserveDrawingBuffer: true }); } catch (e) { gl = null; }
    if (!gl) return null;
    function shader(type, src) {
      const s = gl.createShader(type);
      gl.shaderSource(s, src);
      gl.compileShader(s);
      if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
      return s;
    }
    let prog;
    try {
      prog = gl.createProgram();
      gl.attachShader(prog, shader(gl.VERTEX_SHADER,
        'attribute vec3 p; attribute vec3 c; uniform mat4 m; varying vec3 v;' +
        'void main() { v = c; gl_Position = m * vec4(p, 1.0); }'));
      gl.attachShader(prog, shader(gl.FRAGMENT_SHADER,
        'precision mediump float; varying vec3 v; void main() { gl_FragColor = vec4(v, 1.0); }'));
      gl.linkProgram(prog);
      if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) return null;
    } catch (e) { return null; }
    const buf = gl.createBuffer();
    const ap = gl.getAttribLocation(prog, 'p'), ac = gl.getAttribLocation(prog, 'c');
    const um = gl.getUniformLocation(prog, 'm');
    function draw(mode, arr, count) {
      if (!count) return;
      gl.bindBuffer(gl.ARRAY_BUFFER, buf);
      gl.bufferData(gl.ARRAY_BUFFER, arr, gl.STREAM_DRAW);
      gl.enableVertexAttribArray(ap);
      gl.enableVertexAttribArray(ac);
      gl.vertexAttribPointer(ap, 3, gl.FLOAT, false, 24, 0);
      gl.vertexAttribPointer(ac, 3, gl.FLOAT, false, 24, 12);
      gl.drawArrays(mode, 0, count);
    }
    return {
      name: 'WebGL',
      render: function (w, h, cam, fr) {
        gl.viewport(0, 0, w, h);
        gl.clearColor(BG[0], BG[1], BG[2], 1);
        gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
        gl.enable(gl.DEPTH_TEST);
        gl.useProgram(prog);
        gl.uniformMatrix4fv(um, false, cam.m);
        const t = new Float32Array(fr.tris.length * 18);
        fr.tris.forEach(function (tr, i) {
          for (let j = 0; j < 3; j++) t.set([tr[j][0], tr[j][1], tr[j][2], tr[3][0], tr[3][1], tr[3][2]], i * 18 + j * 6);
        });
        draw(gl.TRIANGLES, t, fr.tris.length * 3);
        const l = new Float32Array(fr.lines.length * 12);
        fr.lines.forEach(function (ln, i) {
          l.set([ln[0][0], ln[0][1], ln[0][2], ln[2][0], ln[2][1], ln[2][2],
            ln[1][0], ln[1][1], ln[1][2], ln[2][0], ln[2][1], ln[2][2]], i * 12);
        });
        draw(gl.LINES, l, fr.lines.length * 2);
      }
    };
  }

  function canvas2d() {
    const g = canvas.getContext('2d');
    return {
      name: 'Canvas 2D',
      render: function (w, h, cam, fr) {
        g.fillStyle = rgb(BG);
        g.fillRect(0, 0, w, h);
        g.lineWidth = Math.max(1, w / 900);
        // Lines and triangles sorted together, far first (painter's algorithm).
        const items = [];
        fr.lines.forEach(function (ln) {
          const a = project(cam.m, ln[0], w, h), b = project(cam.m, ln[1], w, h);
          items.push([(a[2] + b[2]) / 2, 0, [a, b], ln[2]]);
        });
        fr.tris.forEach(function (tr) {
          const p = [project(cam.m, tr[0], w, h), project(cam.m, tr[1], w, h), project(cam.m, tr[2], w, h)];
          if (p[0][2] > cam.near && p[1][2] > cam.near && p[2][2] > cam.near) {
            items.push([(p[0][2] + p[1][2] + p[2][2]) / 3, 1, p, tr[3]]);
          }
        });
        items.sort(function (a, b) { return b[0] - a[0]; });
        items.forEach(function (it) {
          const p = it[2], col = rgb(it[3]);
          g.beginPath();
          g.moveTo(p[0][0], p[0][1]);
          for (let i = 1; i < p.length; i++) g.lineTo(p[i][0], p[i][1]);
          g.strokeStyle = col;
          if (it[1]) { g.closePath(); g.fillStyle = col; g.fill(); }
          g.stroke();
        });
      }
    };
  }

  let renderer = null;
  if (P.renderer !== '2d') renderer = webgl();
  if (!renderer) renderer = canvas2d();
  document.getElementById('renderer').textContent = renderer.name;

  // ----- drawing -----
  const og = overlay.getContext('2d');
  function render() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr)), h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    if (overlay.width !== w || overlay.height !== h) { overlay.width = w; overlay.height = h; }
    update(st.t);
    const cam = camera(w, h);
    renderer.render(w, h, cam, frame(cam));
    og.clearRect(0, 0, w, h);
    og.font = Math.round(13 * dpr) + 'px system-ui, sans-serif';
    og.textAlign = 'center';
    const lh = 15 * dpr;
    // Labels for every object but in a crowd (a particle cache's hundreds),
    // where only the followed one is labelled.
    const crowd = live().filter(function (o) { return o.label || data.grid; }).length > MAX_LABELS;
    objs.forEach(function (o, k) {
      if (!o.shown || (!o.label && !data.grid)) return;
      if (crowd && o.name !== st.follow) return;
      const c = centre(o);
      // Labels alternate above and below so that neighbours do not overlap.
      const up = k % 2 === 0;
      const r = radius(o, c) * 1.6;
      const p = project(cam.m, [c[0], c[1], c[2] + (up ? r : -r)], w, h);
      if (p[2] <= cam.near) return;
      og.fillStyle = '#f4f6f8';
      const lines = [o.label ? o.name + ' · ' + o.label : o.name];
      if (st.align) lines.push('fell ' + (-o.z).toFixed(2) + ' m, drift ' + o.drift.toFixed(2) + ' m');
      const y0 = up ? p[1] - (lines.length - 1) * lh : p[1] + lh;
      lines.forEach(function (t, i) { og.fillText(t, p[0], y0 + i * lh); });
    });
    og.textAlign = 'left';
    og.fillStyle = '#aab4c0';
    og.fillText(data.name + ' — drag to orbit, wheel to zoom, space to play', 10 * dpr, 18 * dpr);
    document.getElementById('clock').textContent = st.t.toFixed(2) + ' / ' + T.toFixed(2) + ' s';
    slider.value = String(st.t);
    play.innerHTML = st.playing ? '&#10074;&#10074;' : '&#9654;';
  }

  // ----- controls -----
  const slider = document.getElementById('time');
  slider.max = String(T);
  slider.step = String(1 / fps / 4);
  const play = document.getElementById('play');
  const speed = document.getElementById('speed');
  const follow = document.getElementById('follow');
  const all = document.createElement('option');
  all.value = ''; all.textContent = 'all objects';
  follow.appendChild(all);
  objs.forEach(function (o) {
    const e = document.createElement('option');
    e.value = o.name; e.textContent = o.name + (o.label ? ' (' + o.label + ')' : '');
    follow.appendChild(e);
  });
  follow.value = st.follow;
  const align = document.getElementById('align');
  if (data.grid) document.getElementById('alignbox').hidden = false;
  align.checked = st.align;
  align.addEventListener('change', function () { st.align = align.checked; fitDistance(); render(); });
  speed.value = String(st.speed);
  play.addEventListener('click', function () { st.playing = !st.playing; if (st.t >= T) st.t = 0; render(); });
  slider.addEventListener('input', function () { st.t = parseFloat(slider.value); st.playing = false; render(); });
  speed.addEventListener('change', function () { st.speed = parseFloat(speed.value); });
  follow.addEventListener('change', function () { st.follow = follow.value; fitDistance(); render(); });
  window.addEventListener('keydown', function (e) {
    if (e.code === 'Space') { st.playing = !st.playing; e.preventDefault(); render(); }
  });
  let drag = null;
  canvas.addEventListener('pointerdown', function (e) { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener('pointerup', function () { drag = null; });
  canvas.addEventListener('pointermove', function (e) {
    if (!drag) return;
    st.yaw -= (e.clientX - drag[0]) * 0.008;
    st.pitch = Math.min(1.55, Math.max(-1.55, st.pitch + (e.clientY - drag[1]) * 0.008));
    drag = [e.clientX, e.clientY];
    render();
  });
  canvas.addEventListener('wheel', function (e) {
    st.dist *= Math.exp(e.deltaY * 0.001);
    e.preventDefault();
    render();
  }, { passive: false });
  window.addEventListener('resize', render);

  let last = null;
  function loop(now) {
    if (last !== null && st.playing) {
      st.t += (now - last) / 1000 * st.speed;
      if (st.t > T) st.t = 0;
      render();
    }
    last = now;
    requestAnimationFrame(loop);
  }
  render();
  document.body.setAttribute('data-ready', renderer.name);
  requestAnimationFrame(loop);
})();
