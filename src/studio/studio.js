// leafmagic studio: a grid of falling candidates, each in its own canvas,
// drawn with a plain 2-D projection (as the preview's fallback renderer
// does); picks go to the server, which breeds the next generation in the
// background while the page draws each candidate as its drops finish.
// Kept leaves make a collection that falls side by side and exports.
// URL query: token=TOKEN (required), t=SECONDS (clock held there, for
// screenshots).
'use strict';
(function () {
  const query = new URLSearchParams(location.search);
  const token = query.get('token') || '';
  const heldAt = query.has('t') && isFinite(parseFloat(query.get('t'))) ? parseFloat(query.get('t')) : null;
  const $ = function (id) { return document.getElementById(id); };
  const gridEl = $('grid'), statusEl = $('status'), scaleEl = $('scale'), treeEl = $('tree');
  const TRAIL_S = 2.0;        // trail length, seconds
  const LIKE_POOL = 3;        // session.rs's LIKE_POOL
  const YAW = -0.9, PITCH = 0.45;
  let state = null, cells = [], picks = [], busy = false, start = performance.now();
  let together = [];  // the collection's falls, prepared

  function api(path, body) {
    const headers = { 'X-Leafmagic-Token': token };
    const opt = { headers: headers };
    if (body !== undefined) {
      opt.method = 'POST';
      headers['Content-Type'] = 'application/json';
      opt.body = JSON.stringify(body);
    }
    return fetch(path, opt).then(function (r) {
      return r.ok ? r.json() : r.text().then(function (t) { throw new Error(t); });
    });
  }

  function f32(b64) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Float32Array(bytes.buffer);
  }

  function fmt(x, d) { return Number(x).toFixed(d); }

  function originText(c) {
    if (c.origin === 'variation') return 'variation of #' + c.parents[0];
    if (c.origin === 'crossover') return 'crossover of #' + c.parents.join(' × #');
    if (c.origin === 'wild') return 'wild card';
    if (c.origin === 'archive') return 'wild card from #' + c.parents[0] + '\'s cell';
    if (c.origin === 'prototype') return 'varied prototype';
    return 'uniform draw';
  }

  // Per candidate: vertices per frame, centre per frame, extent.
  function prepare(c) {
    const m = c.motion;
    const o = { c: c, n: m.vertices, F: m.frames, tris: m.triangles, P: m.frames ? f32(m.positions) : null };
    if (!o.P) return o;
    o.com = new Float32Array(o.F * 3);
    let zmin = Infinity, ext = 0;
    for (let f = 0; f < o.F; f++) {
      let x = 0, y = 0, z = 0;
      for (let i = 0; i < o.n; i++) {
        const k = (f * o.n + i) * 3;
        x += o.P[k]; y += o.P[k + 1]; z += o.P[k + 2];
        zmin = Math.min(zmin, o.P[k + 2]);
      }
      o.com[f * 3] = x / o.n; o.com[f * 3 + 1] = y / o.n; o.com[f * 3 + 2] = z / o.n;
    }
    for (let i = 0; i < o.n; i++) {
      for (let j = 0; j < 3; j++) ext = Math.max(ext, Math.abs(o.P[i * 3 + j] - o.com[j]));
    }
    o.ground = zmin;
    // The view spans a few chords (at least 15 cm): the sway shows, and a
    // small leaf is not lost in it.
    o.span = Math.max(0.15, 6 * ext);
    return o;
  }

  function infoHtml(c) {
    let rate = c.class === 'diverged' ? c.error :
      fmt(c.descent_m_s, 2) + ' m/s · drift ' + fmt(c.drift_ratio, 2) + ' · ' +
      fmt(c.spin_rad_s, 1) + ' rad/s · kept ' + c.kept + '/' + c.releases;
    if (c.distance !== null && c.distance !== undefined) rate += ' · distance ' + fmt(c.distance, 2);
    if (typeof c.taste === 'number') rate += ' · taste ' + fmt(c.taste, 2);
    return '<b>#' + c.id + ' ' + c.class + '</b> ' + (c.regime || '') + '<br>' + rate +
      '<br><span class="origin">' + originText(c) + '</span>';
  }

  function isKept(id) {
    return state.collection.some(function (k) { return k.id === id; });
  }

  // A cell's contents: the candidate's numbers and Keep button, or (while
  // its drops run) a placeholder.
  function fill(k, c) {
    const o = cells[k];
    if (!c) {
      o.info.textContent = 'dropping…';
      o.el.classList.add('pending');
      return;
    }
    Object.assign(o, prepare(c));
    o.el.classList.remove('pending');
    o.el.dataset.id = c.id;
    o.info.innerHTML = infoHtml(c);
    const keep = document.createElement('button');
    keep.className = 'keep' + (isKept(c.id) ? ' kept' : '');
    keep.textContent = isKept(c.id) ? 'kept' : 'keep';
    keep.title = 'add this leaf to the collection (again: take it out)';
    keep.addEventListener('click', function (e) {
      e.stopPropagation();
      keepLeaf(c.id, !isKept(c.id));
    });
    o.info.insertBefore(keep, o.info.firstChild);
    if (state.candidates.some(function (x) { return x.id === c.id; }) && c.class !== 'diverged' && c.class !== 'undetermined') {
      const like = document.createElement('button');
      like.className = 'like';
      like.textContent = '≈';
      like.title = 'more like this: breed the next generation toward this leaf\'s fall: ' + LIKE_POOL + '× the grid evaluated, the closest kept';
      like.addEventListener('click', function (e) {
        e.stopPropagation();
        moreLike(c.id);
      });
      o.info.insertBefore(like, keep.nextSibling);
    }
  }

  // The grid of `list` (candidates, or null for those still dropping).
  function build(list, keepClock) {
    gridEl.innerHTML = '';
    const n = list.length;
    const cols = Math.ceil(Math.sqrt(n * 4 / 3));
    gridEl.style.gridTemplateColumns = 'repeat(' + cols + ', minmax(0, 1fr))';
    cells = list.map(function (c, k) {
      const el = document.createElement('div');
      el.className = 'cell';
      const canvas = document.createElement('canvas');
      const key = document.createElement('span');
      key.className = 'key';
      key.textContent = k < 10 ? String((k + 1) % 10) : '';
      const info = document.createElement('div');
      info.className = 'info';
      el.appendChild(key); el.appendChild(canvas); el.appendChild(info);
      el.addEventListener('click', function () { toggle(k); });
      gridEl.appendChild(el);
      return { el: el, canvas: canvas, info: info, P: null, F: 0, drawn: false };
    });
    list.forEach(function (c, k) { fill(k, c); });
    picks = [];
    if (!keepClock) start = performance.now();
  }

  // The grid in the order it is shown: with "by taste" on and a model of
  // the person's taste fitted, most liked first (ties keep grid order).
  function ordered(list) {
    if (!$('by-taste').checked || !list.some(function (c) { return typeof c.taste === 'number'; })) return list;
    const t = function (c) { return typeof c.taste === 'number' ? c.taste : -1; };
    return list.map(function (c, k) { return [c, k]; })
      .sort(function (a, b) { return t(b[0]) - t(a[0]) || a[1] - b[1]; })
      .map(function (p) { return p[0]; });
  }

  function showState(keepClock) {
    build(ordered(state.candidates), keepClock);
    showTree();
    showCollection();
    showStatus();
    document.body.dataset.generation = state.generation.index;
  }

  // A candidate's fall ("leaf-ID") by its number, typed descriptors as typed.
  function towardLabel(t) {
    if (t.source.indexOf('leaf-') === 0) return '#' + t.source.slice(5);
    return Object.keys(t.descriptors).map(function (k) { return k + '=' + t.descriptors[k]; }).join(' ');
  }

  function showTree() {
    treeEl.innerHTML = 'history: ';
    state.tree.forEach(function (g) {
      const s = document.createElement('span');
      s.textContent = 'g' + g.index + (g.parent === null ? '' : ' ← g' + g.parent + ' (' + (g.auto ? 'auto: ' : '') + (g.like !== null && g.like !== undefined ? 'like ' : '') +
        (g.toward ? 'toward ' + towardLabel(g.toward) + ' ' : '') +
        g.picks.map(function (p) { return '#' + p; }).join(', ') + ')');
      if (g.index === state.generation.index) s.className = 'here';
      s.addEventListener('click', function () { act('/api/goto', { generation: g.index }); });
      treeEl.appendChild(s);
    });
  }

  function showCollection() {
    const list = $('kept');
    list.innerHTML = '';
    together = state.collection.map(function (c) {
      const s = document.createElement('span');
      s.textContent = '#' + c.id + ' ' + c.class + ' (g' + c.generation + ') ✕';
      s.title = 'take #' + c.id + ' out of the collection';
      s.addEventListener('click', function () { keepLeaf(c.id, false); });
      list.appendChild(s);
      return prepare(c);
    });
    $('kept-count').textContent = '(' + together.length + ')';
    $('export').disabled = together.length === 0;
    // The example fall (studio --like) is shown first, labelled as such.
    const shown = together.length;
    if (state.example) {
      const e = prepare({ id: 'example', class: state.example.class, motion: state.example.motion });
      e.label = 'example: ' + state.example.name + ' (' + state.example.class + ')';
      together.unshift(e);
      const b = document.createElement('button');
      b.textContent = '≈ example';
      b.title = 'more like the example: one generation bred toward its fall (what Auto N breeds toward)';
      b.addEventListener('click', function () { autoBreed(1); });
      list.insertBefore(b, list.firstChild);
    }
    // Two or more kept leaves (or one beside the example) fall side by
    // side in one view.
    $('together').style.display = together.length >= 2 ? 'block' : 'none';
    document.body.dataset.kept = shown;
  }

  function showStatus(text) {
    if (text) { statusEl.textContent = text; return; }
    const g = state.generation;
    statusEl.textContent = (state.aero_law === 'unsteady' ? 'real-paper law' : state.aero_law === 'linear' ? "paper's law" : state.aero_law + ' law') +
      ' · generation ' + g.index + (g.parent === null ? '' : ' (from g' + g.parent + ')') +
      ' · its variation ' + fmt(g.scale, 2) + ' · picked: ' +
      (picks.length ? picks.map(function (k) { return '#' + cells[k].c.id; }).join(', ') : 'none (click or 1–9, 0)') +
      ' · Enter breeds, Backspace goes back · ' + state.dir;
    $('back').disabled = busy || g.parent === null;
    $('auto').disabled = busy;
    $('breed').disabled = busy || picks.length === 0;
  }

  function toggle(k) {
    if (busy || k >= cells.length || !cells[k].c) return;
    const i = picks.indexOf(k);
    if (i < 0) picks.push(k); else picks.splice(i, 1);
    cells[k].el.classList.toggle('picked', i < 0);
    showStatus();
  }

  function act(path, body, what) {
    if (busy) return;
    busy = true;
    showStatus(what || 'working…');
    api(path, body).then(function (s) {
      busy = false; state = s; showState();
      scaleEl.value = fmt(state.next_scale, 2);
    }).catch(function (e) {
      busy = false; showStatus('refused: ' + e.message);
    });
  }

  function keepLeaf(id, keep) {
    api('/api/keep', { id: id, keep: keep }).then(function (s) {
      // The grid stays as it is (its clock too); only the marks change.
      state.collection = s.collection;
      cells.forEach(function (o) {
        if (!o.c) return;
        const b = o.info.querySelector('button.keep');
        b.classList.toggle('kept', isKept(o.c.id));
        b.textContent = isKept(o.c.id) ? 'kept' : 'keep';
      });
      showCollection();
    }).catch(function (e) { $('exported').textContent = 'refused: ' + e.message; });
  }

  function exportCollection() {
    const body = { fps: parseFloat($('fps').value), start_height_m: parseFloat($('height').value) };
    $('exported').textContent = 'exporting ' + state.collection.length + ' leaves…';
    $('export').disabled = true;
    api('/api/export', body).then(function (r) {
      $('exported').textContent = 'wrote ' + r.files.length + ' files in ' + r.dir + ': ' + r.files.join(', ');
      document.body.dataset.exported = r.files.length;
    }).catch(function (e) {
      $('exported').textContent = 'refused: ' + e.message;
    }).then(function () { $('export').disabled = state.collection.length === 0; });
  }

  // ----- breeding in the background -----
  // The server answers Breed at once; the page polls its progress and
  // draws each candidate as its drops finish.
  let got = 0, following = null;
  function showProgress(b) {
    const bar = $('progress');
    bar.style.visibility = b ? 'visible' : 'hidden';
    if (!b) return;
    bar.firstChild.style.width = (100 * b.drops_done / Math.max(1, b.drops)) + '%';
    showStatus((b.auto ? 'auto ' + b.auto[0] + ' of ' + b.auto[1] + ': ' : '') +
      'breeding generation ' + b.generation + ' from ' + b.picks.map(function (i) { return '#' + i; }).join(', ') +
      ': ' + b.done + ' of ' + b.candidates + ' candidates (' + b.drops_done + ' of ' + b.drops + ' drops)');
  }

  function follow(b) {
    busy = true;
    got = 0;
    following = b.generation;
    build(new Array(b.candidates).fill(null));
    document.body.dataset.generation = b.generation;
    showProgress(b);
    poll();
  }

  function poll() {
    api('/api/progress?from=' + got).then(function (p) {
      const b = p.breeding;
      if (b && b.generation !== following) {
        // Auto N moved on to its next generation: a fresh grid for it.
        follow(b);
        return;
      }
      if (b) {
        b.finished.forEach(function (c) { fill(c.slot, c); });
        got += b.finished.length;
        showProgress(b);
        setTimeout(poll, 100);
        return;
      }
      return api('/api/state').then(function (s) {
        busy = false; state = s;
        showProgress(null);
        showState(true);
        scaleEl.value = fmt(state.next_scale, 2);
        if (p.breed_error) showStatus('breeding failed: ' + p.breed_error);
      });
    }).catch(function (e) {
      // The server went away, or refused: say so, try again shortly.
      showStatus('lost the studio: ' + e.message);
      setTimeout(poll, 1000);
    });
  }

  function breed() {
    if (!picks.length || busy) return;
    const ids = picks.map(function (k) { return cells[k].c.id; });
    const scale = parseFloat(scaleEl.value);
    const body = { picks: ids };
    if (isFinite(scale)) body.scale = scale;
    busy = true;
    showStatus('breeding from ' + ids.map(function (i) { return '#' + i; }).join(', ') + '…');
    api('/api/breed', body).then(function (s) {
      state = s;
      follow(s.breeding);
    }).catch(function (e) {
      busy = false; showStatus('refused: ' + e.message);
    });
  }

  function moreLike(id) {
    if (busy) return;
    const scale = parseFloat(scaleEl.value);
    const body = { id: id };
    if (isFinite(scale)) body.scale = scale;
    busy = true;
    showStatus('breeding toward #' + id + '\'s fall…');
    api('/api/like', body).then(function (s) {
      state = s;
      follow(s.breeding);
    }).catch(function (e) {
      busy = false; showStatus('refused: ' + e.message);
    });
  }

  function autoBreed(count) {
    if (busy) return;
    const n = typeof count === 'number' ? count : parseInt($('auto-n').value, 10);
    // Typed descriptors first; else one picked candidate: toward its fall;
    // else toward the session's class (or its example).
    const toward = $('auto-toward').value.trim();
    const body = { generations: n };
    let aim = '';
    if (toward) { body.toward = toward; aim = ' toward ' + toward; }
    else if (picks.length === 1) { body.like = cells[picks[0]].c.id; aim = ' toward #' + body.like + '\'s fall'; }
    busy = true;
    showStatus('breeding ' + n + ' generations from the machine\'s picks' + aim + '…');
    api('/api/auto', body).then(function (s) {
      state = s;
      follow(s.breeding);
    }).catch(function (e) {
      busy = false; showStatus('refused: ' + e.message);
    });
  }

  function back() { if (state.generation.parent !== null) act('/api/back', {}, 'going back…'); }

  $('breed').addEventListener('click', breed);
  $('back').addEventListener('click', back);
  $('export').addEventListener('click', exportCollection);
  $('auto').addEventListener('click', autoBreed);
  $('by-taste').addEventListener('change', function () { if (!busy) showState(true); });
  document.addEventListener('keydown', function (e) {
    if (e.target.tagName === 'INPUT') { if (e.target === scaleEl && e.key === 'Enter') breed(); return; }
    if (e.key >= '0' && e.key <= '9') toggle((parseInt(e.key, 10) + 9) % 10);
    else if (e.key === 'Enter') breed();
    else if (e.key === 'Backspace') { e.preventDefault(); back(); }
  });

  // ----- drawing -----
  const cy = Math.cos(YAW), sy = Math.sin(YAW), cp = Math.cos(PITCH), sp = Math.sin(PITCH);
  // Screen coordinates (right, up) and depth of a point relative to the view centre.
  function project(x, y, z) {
    const r = x * cy + y * sy, f = -x * sy + y * cy;
    return [r, z * cp + f * sp, f * cp - z * sp];
  }

  function frameAt(o, t) { return Math.min(Math.max(t * state.fps, 0), o.F - 1); }

  function comAt(o, g) {
    const k = Math.min(Math.floor(g), o.F - 2), a = o.F > 1 ? g - k : 0, C = o.com;
    if (o.F < 2) return [C[0], C[1], C[2]];
    return [0, 1, 2].map(function (j) { return C[k * 3 + j] * (1 - a) + C[(k + 1) * 3 + j] * a; });
  }

  // Draws the prepared falls `list` in canvas `cv` at time t, side by
  // side in columns at one scale (the largest view span fits its column),
  // each followed by its own view: one fall fills a grid cell; kept
  // leaves compare size, sway and spin directly.
  function drawView(cv, list, t) {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(cv.clientWidth * dpr)), h = Math.max(1, Math.round(cv.clientHeight * dpr));
    if (cv.width !== w || cv.height !== h) { cv.width = w; cv.height = h; }
    const ctx = cv.getContext('2d');
    ctx.fillStyle = '#10161f';
    ctx.fillRect(0, 0, w, h);
    const n = Math.max(1, list.length), cw = w / n;
    const big = list.reduce(function (m, o) { return Math.max(m, o.P ? o.span : 0); }, 0);
    const s = Math.min(cw, h) / (big || 1);
    let any = false;
    list.forEach(function (o, k) {
      ctx.save();
      ctx.beginPath(); ctx.rect(k * cw, 0, cw, h); ctx.clip();
      ctx.translate(k * cw, 0);
      if (o.P) {
        drawOne(ctx, o, t, cw, h, s, dpr);
        any = true;
      } else {
        ctx.fillStyle = o.c ? '#c06060' : '#8893a2';
        ctx.font = Math.round(12 * dpr) + 'px system-ui, sans-serif';
        ctx.fillText(o.c ? 'no fall to show' : 'dropping…', 10 * dpr, 20 * dpr);
      }
      if (o.label) {
        ctx.fillStyle = '#e0c070';
        ctx.font = Math.round(11 * dpr) + 'px system-ui, sans-serif';
        ctx.fillText(o.label, 6 * dpr, h - 8 * dpr);
      }
      ctx.restore();
      if (k > 0) {
        ctx.strokeStyle = '#2c3542'; ctx.lineWidth = 1;
        ctx.beginPath(); ctx.moveTo(k * cw, 0); ctx.lineTo(k * cw, h); ctx.stroke();
      }
    });
    return any;
  }

  // One fall in a w × h view at s pixels a metre, following its centre:
  // the wall and ground for scale, its trail and the leaf.
  function drawOne(ctx, o, t, w, h, s, dpr) {
    const g = frameAt(o, t), c = comAt(o, g);
    const sx = function (p) { return w / 2 + s * p[0]; }, syy = function (p) { return h / 2 - s * p[1]; };
    const rel = function (x, y, z) { return project(x - c[0], y - c[1], z - c[2]); };
    // Scale: a back wall of 10 cm squares, fixed in the world, so the fall
    // is seen against it; and the ground (the fall's lowest point) as a grid.
    ctx.lineWidth = 1;
    ctx.strokeStyle = 'rgba(120,140,170,0.25)';
    ctx.beginPath();
    const half = Math.max(w, h) / s, step = 0.1, wallY = c[1] + o.span;
    for (let z = Math.floor((c[2] - half) / step) * step; z <= c[2] + half; z += step) {
      const a = rel(c[0] - half, wallY, z), b = rel(c[0] + half, wallY, z);
      ctx.moveTo(sx(a), syy(a)); ctx.lineTo(sx(b), syy(b));
    }
    for (let x = Math.floor((c[0] - half) / step) * step; x <= c[0] + half; x += step) {
      const a = rel(x, wallY, c[2] - half), b = rel(x, wallY, c[2] + half);
      ctx.moveTo(sx(a), syy(a)); ctx.lineTo(sx(b), syy(b));
    }
    ctx.stroke();
    if (o.ground > c[2] - half) {
      ctx.strokeStyle = 'rgba(150,170,120,0.5)';
      ctx.beginPath();
      const n = Math.ceil(half / step);
      for (let k = -n; k <= n; k++) {
        let a = rel(c[0] + k * step, c[1] - half, o.ground), b = rel(c[0] + k * step, c[1] + half, o.ground);
        ctx.moveTo(sx(a), syy(a)); ctx.lineTo(sx(b), syy(b));
        a = rel(c[0] - half, c[1] + k * step, o.ground); b = rel(c[0] + half, c[1] + k * step, o.ground);
        ctx.moveTo(sx(a), syy(a)); ctx.lineTo(sx(b), syy(b));
      }
      ctx.stroke();
    }
    drawFall(ctx, o, g, rel, sx, syy, dpr);
  }

  // One fall: the trail of its centre over the last TRAIL_S seconds,
  // fading with age, and the leaf's triangles, far first, shaded by how
  // they face the light.
  function drawFall(ctx, o, g, rel, sx, syy, dpr) {
    const first = Math.max(0, Math.floor(g - TRAIL_S * state.fps));
    ctx.lineWidth = Math.max(1.5, 2 * dpr);
    let prev = null;
    for (let f = first; f <= Math.floor(g); f++) {
      const p = rel(o.com[f * 3], o.com[f * 3 + 1], o.com[f * 3 + 2]);
      if (prev) {
        ctx.strokeStyle = 'rgba(255,150,40,' + fmt(0.9 * (1 - (g - f) / (TRAIL_S * state.fps)), 3) + ')';
        ctx.beginPath(); ctx.moveTo(sx(prev), syy(prev)); ctx.lineTo(sx(p), syy(p)); ctx.stroke();
      }
      prev = p;
    }
    const k0 = Math.min(Math.floor(g), o.F - 1), k1 = Math.min(k0 + 1, o.F - 1), a = g - k0;
    const V = [];
    for (let i = 0; i < o.n; i++) {
      const p0 = (k0 * o.n + i) * 3, p1 = (k1 * o.n + i) * 3, P = o.P;
      V.push([P[p0] * (1 - a) + P[p1] * a, P[p0 + 1] * (1 - a) + P[p1 + 1] * a, P[p0 + 2] * (1 - a) + P[p1 + 2] * a]);
    }
    const tris = [];
    for (let i = 0; i + 2 < o.tris.length; i += 3) {
      const A = V[o.tris[i]], B = V[o.tris[i + 1]], C = V[o.tris[i + 2]];
      const u = [B[0] - A[0], B[1] - A[1], B[2] - A[2]], v = [C[0] - A[0], C[1] - A[1], C[2] - A[2]];
      const nz = u[0] * v[1] - u[1] * v[0], nl = Math.hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], nz) || 1;
      const pa = rel(A[0], A[1], A[2]), pb = rel(B[0], B[1], B[2]), pc = rel(C[0], C[1], C[2]);
      tris.push({ p: [pa, pb, pc], d: pa[2] + pb[2] + pc[2], light: 0.45 + 0.55 * Math.abs(nz / nl) });
    }
    tris.sort(function (x, y) { return y.d - x.d; });
    tris.forEach(function (tr) {
      const l = tr.light;
      ctx.fillStyle = 'rgb(' + Math.round(70 * l) + ',' + Math.round(200 * l) + ',' + Math.round(90 * l) + ')';
      ctx.strokeStyle = 'rgba(20,60,30,0.8)';
      ctx.beginPath();
      ctx.moveTo(sx(tr.p[0]), syy(tr.p[0])); ctx.lineTo(sx(tr.p[1]), syy(tr.p[1])); ctx.lineTo(sx(tr.p[2]), syy(tr.p[2]));
      ctx.closePath(); ctx.fill(); ctx.stroke();
    });
  }

  function draw(o, t) {
    o.drawn = drawView(o.canvas, [o], t);
  }

  function tick() {
    if (state && cells.length) {
      // One clock for all: every candidate falls in sync, looping over the
      // longest fall with a second's pause at the end.
      const F = cells.reduce(function (m, o) { return Math.max(m, o.F || 1); }, 1);
      const T = (F - 1) / state.fps;
      const t = heldAt !== null ? Math.min(heldAt, T) : ((performance.now() - start) / 1000) % (T + 1);
      cells.forEach(function (o) { draw(o, t); });
      if (!busy && cells.every(function (o) { return o.drawn; })) document.body.dataset.drawn = state.generation.index;
      if (together.length >= 2) {
        const tw = drawView($('together'), together, t);
        if (tw) document.body.dataset.together = together.length;
      }
    }
    requestAnimationFrame(tick);
  }

  api('/api/state').then(function (s) {
    state = s; showState();
    scaleEl.value = fmt(state.next_scale, 2);
    // Opened (or reloaded) while a generation is being bred: follow it.
    if (s.breeding) follow(s.breeding);
    requestAnimationFrame(tick);
  }).catch(function (e) { showStatus('could not load the session: ' + e.message); });
})();
