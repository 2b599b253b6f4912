// inkstep web view: one websocket to the server, a canvas for the drawing, and
// the controls. Everything the machine does arrives as JSON messages (see
// host/src/web/link.rs); everything the page asks is a message back.
//
// The drawing is painted in layers so that a status report costs only what it
// adds: the grid and the planned job are drawn once into an offscreen canvas
// (again only when the job, the size or the view changes), the drawn path is
// appended to a second one, and each frame copies both and draws the pen.
"use strict";
const $ = (id) => document.getElementById(id);
// The token: taken from the address once, then kept out of it (history,
// bookmarks and screenshots of the address bar).
const token = (() => {
  const q = new URLSearchParams(location.search), t = q.get("token");
  if (t) { sessionStorage.setItem("inkstep-token", t); history.replaceState(null, "", location.pathname); }
  return t || sessionStorage.getItem("inkstep-token");
})();
const S = (window.inkstep = {
  id: 0, role: "watch", holder: null, status: null, path: [], job: null,
  settings: [], answers: {}, done: null, link: null, alarm: null, fw: "",
  limits: { message: 1 << 20, job: 64 << 20 }, paints: [], loading: null,
});
let ws = null;
let nextId = 1;

// A piece of the job's preview, binary: the job's generation (u32), then rows of
// five f32 (x0, y0, x1, y1, drawn), little-endian (the page's own byte order on
// every browser that runs it). The pieces are kept as they come, typed arrays:
// a 10 MB job is half a million moves, 10 MB of f32 this way, where as many small
// arrays would be that many objects for the garbage collector to mark.
function previewRows(buf) {
  const gen = new DataView(buf).getUint32(0, true);
  if (!S.job || gen !== S.job.gen) return;
  const f = new Float32Array(buf, 4, Math.floor((buf.byteLength - 4) / 20) * 5);
  if (f.length === 0) return;
  // The job's extent, kept as the pieces come (never a pass over all of it).
  const b = S.job.box || [Infinity, Infinity, -Infinity, -Infinity], pv = S.job.preview;
  for (let k = 0; k < f.length; k += 5) {
    if (f[k] < b[0]) b[0] = f[k]; if (f[k + 2] < b[0]) b[0] = f[k + 2]; if (f[k] > b[2]) b[2] = f[k]; if (f[k + 2] > b[2]) b[2] = f[k + 2];
    if (f[k + 1] < b[1]) b[1] = f[k + 1]; if (f[k + 3] < b[1]) b[1] = f[k + 3]; if (f[k + 1] > b[3]) b[3] = f[k + 1]; if (f[k + 3] > b[3]) b[3] = f[k + 3];
    if (f[k + 4]) pv.drawn++;
  }
  pv.pieces.push(f); pv.moves += f.length / 5;
  S.job.box = b;
}

function connect() {
  const q = token ? "?token=" + encodeURIComponent(token) : "";
  ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws" + q);
  ws.binaryType = "arraybuffer";
  ws.onmessage = (e) => (typeof e.data === "string" ? handle(JSON.parse(e.data)) : previewRows(e.data));
  ws.onclose = () => {
    S.status = null; showState();
    $("link").textContent = "server gone: reconnecting";
    setTimeout(connect, 1000);
  };
}

function send(m) { if (ws && ws.readyState === 1) { ws.send(JSON.stringify(m)); return true; } return false; }
function command(line, what) { const id = nextId++; if (what) S.answers[id] = what; send({ t: "cmd", id, line }); return id; }
function log(text) {
  const l = $("log"), end = l.scrollHeight - l.scrollTop - l.clientHeight < 20;
  l.textContent += text + "\n";
  if (l.textContent.length > 60000) l.textContent = l.textContent.slice(-40000);
  if (end) l.scrollTop = l.scrollHeight;
}
function fmtTime(s) { s = Math.max(0, Math.round(s)); return Math.floor(s / 60) + ":" + String(s % 60).padStart(2, "0"); }

// Errors and alarms where the user is looking: a banner under the bar.
function banner(text, alarm) {
  $("bannertext").textContent = text;
  $("banner").hidden = !text;
  $("banner").classList.toggle("alarm", !!alarm);
  $("bunlock").hidden = $("bhome").hidden = !alarm;
}

function handle(m) {
  switch (m.t) {
    case "hello":
      S.id = m.id; S.role = m.role; S.holder = m.holder; S.path = []; S.limits = m.limits || S.limits;
      $("log").textContent = ""; resetPath(); showRole(); break;
    case "control": S.holder = m.holder; showRole(); break;
    case "link":
      S.link = m;
      $("link").textContent = m.up ? "● " + m.port : "○ " + m.port + (m.error ? ": " + m.error : "");
      if (!m.up) { S.status = null; S.fw = ""; $("fw").textContent = ""; }
      else if (S.done && /^connection lost/.test(S.done.why)) { S.done = null; $("jobstate").textContent = ""; }
      showState(); break;
    case "fw": S.fw = m.text; $("fw").textContent = m.text; break;
    case "status": showStatus(m); break;
    case "path":
      if (!m.from) resetPath();
      for (const p of m.pts) addPoint(p);
      draw(); break;
    case "clear": resetPath(); S.done = null; draw(); break;
    case "job":
      S.job = { at: performance.now(), name: m.name, lines: m.lines, est_s: m.est_s, gen: m.gen, moves: m.moves, preview: { pieces: [], moves: 0, drawn: 0 }, complete: false, page: m.page, left_out: m.left_out || [] };
      S.done = null; S.loading = null;
      $("jobinfo").textContent = m.name + ": " + m.lines + " lines, about " + fmtTime(m.est_s) + (m.moves ? " · receiving the preview…" : "");
      $("progress").value = 0; $("jobstate").textContent = "";
      fitView(); invalidate(); showState(); break;
    case "preview_end":
      if (S.job) {
        S.job.complete = true; S.job.took = performance.now() - S.job.at;
        $("jobinfo").textContent = S.job.name + ": " + S.job.lines + " lines, about " + fmtTime(S.job.est_s);
        fitView(); invalidate();
      }
      break;
    case "done":
      S.done = m; $("jobstate").textContent = m.ok ? "done" : m.why;
      if (m.ok) $("progress").value = 1;
      else if (m.why) banner(m.why, /alarm/i.test(m.why));
      showState(); break;
    case "alarm": S.alarm = m; showState(); break;
    case "resumable": S.resumable = m.line; showState(); break;
    case "estimate":
      if (S.job && m.gen === S.job.gen) { S.job.est_s = m.est_s; if (S.job.complete || !S.job.moves) showJobInfo(); }
      break;
    case "settings": S.settings = m.list; showSettings(); if (!S.job) invalidate(); break;
    case "answer": answered(m); break;
    case "log": log(m.text); break;
    case "error":
      log("error: " + m.text); banner(m.text, false);
      if (S.loading) { S.loading = null; showJobInfo(); }
      break;
    case "denied": log("not done: " + m.why); banner(m.why, false); break;
  }
}

function showJobInfo() {
  $("jobinfo").textContent = S.job ? S.job.name + ": " + S.job.lines + " lines, about " + fmtTime(S.job.est_s) : "nothing loaded";
}

function showRole() {
  const mine = S.holder === S.id;
  $("role").textContent = S.role === "watch" ? "watching" : mine ? "you control" : S.holder ? "another browser controls" : "";
  $("take").hidden = S.role !== "control" || mine;
  document.body.classList.toggle("watch", S.role === "watch");
}

// The state in the bar; without a link to the machine, no state or position at all.
function showState() {
  const st = $("state"), m = S.status;
  if (!S.link || !S.link.up || !m) {
    st.textContent = S.link && !S.link.up ? "disconnected" : "…";
    st.className = "state Disconnected";
    $("pos").textContent = "X – Y –"; $("pen").textContent = "";
  } else {
    st.textContent = m.state; st.className = "state " + m.state.split(":")[0];
  }
  const alarm = m && /^Alarm/.test(m.state);
  $("run").disabled = !S.job || !m || alarm || m.state !== "Idle";
  // A stopped job can go on where it stopped (after an alarm: unlock or home first).
  const rj = $("rejob");
  rj.hidden = !S.job || S.resumable == null;
  rj.textContent = "Continue at line " + S.resumable;
  rj.disabled = !m || alarm || m.state !== "Idle";
  if (alarm) {
    const a = S.alarm;
    banner((a ? "ALARM:" + a.n + " – " + a.text : "Alarm: the machine is locked") +
      ". Unlock to move again, or Home.", true);
  } else if ($("banner").classList.contains("alarm")) banner("", false);
}

function showStatus(m) {
  S.status = m;
  showState();
  const p = m.pos.map((v) => v.toFixed(2));
  $("pos").textContent = "X " + p[0] + " Y " + p[1];
  $("pen").textContent = (m.down ? "pen down" : "pen up") + " · F " + Math.round(m.feed);
  $("ov").textContent = "now: feed " + m.ov[0] + "%, rapid " + m.ov[1] + "%";
  if (m.point) addPoint(m.point);
  if (m.job) {
    $("progress").value = m.job.done;
    $("jobstate").textContent = Math.round(100 * m.job.done) + "% · " + fmtTime(m.job.left_s) + " left · " +
      m.job.acked + "/" + m.job.lines + " lines";
  }
  draw();
}

function showSettings() {
  const body = $("settings").tBodies[0];
  body.textContent = "";
  for (const [n, v, name] of S.settings) {
    const tr = body.insertRow();
    tr.dataset.n = n;
    tr.insertCell().textContent = "$" + n;
    const inp = document.createElement("input");
    inp.value = v; inp.dataset.n = n; inp.dataset.was = v;
    inp.onkeydown = (e) => { if (e.key === "Enter") inp.blur(); };
    inp.onchange = () => setSetting(n, inp.value, tr);
    tr.insertCell().appendChild(inp);
    tr.insertCell().textContent = name;
    tr.insertCell().className = "err";
  }
}

function setSetting(n, v, tr) {
  tr.cells[3].textContent = "…";
  command("$" + n + "=" + v.trim(), tr);
}

function answered(m) {
  const what = S.answers[m.id];
  delete S.answers[m.id];
  if (what instanceof HTMLElement) {
    // A setting: its error beside it, and the field back to the value it has.
    what.cells[3].textContent = m.ok ? "" : m.error;
    if (!m.ok) { const inp = what.cells[1].firstChild; inp.value = inp.dataset.was; }
  } else if (typeof what === "string") {
    log((m.ok ? "ok  " : "") + what + (m.ok ? "" : ": " + m.error));
    if (!m.ok) banner(what + ": " + m.error, false);
  } else if (!m.ok && m.id) { log(m.error); banner(m.error, false); }
}

// ---- The drawing ----------------------------------------------------------
const V = (S.view = { zoom: 1, px: 0, py: 0 }); // zoom and pan (CSS px) over the fitted view
let plan = null, ink = null, inkDone = 0, geo = null, pathBox = null;

function resetPath() { S.path = []; pathBox = null; inkDone = 0; ink = null; }
function addPoint(p) {
  S.path.push(p);
  if (!pathBox) pathBox = [p[0], p[1], p[0], p[1]];
  else {
    const b = pathBox, out = p[0] < b[0] || p[1] < b[1] || p[0] > b[2] || p[1] > b[3];
    pathBox = [Math.min(b[0], p[0]), Math.min(b[1], p[1]), Math.max(b[2], p[0]), Math.max(b[3], p[1])];
    // Off the fitted area with no job to frame it: fit again.
    if (out && !S.job && geo && (p[0] < geo.b[0] || p[1] < geo.b[1] || p[0] > geo.b[2] || p[1] > geo.b[3])) invalidate();
  }
}

// What is fitted: the job (an SVG's page and what it leaves out included), else the path and the pen, else the machine area ($130/$131).
function bounds() {
  let b = null;
  const grow = (x, y) => { b = b ? [Math.min(b[0], x), Math.min(b[1], y), Math.max(b[2], x), Math.max(b[3], y)] : [x, y, x, y]; };
  if (S.job && S.job.box) b = S.job.box.slice();
  else if (S.job) grow(0, 0);
  // An SVG's page and what it leaves out are framed too.
  if (S.job && S.job.page) { grow(0, 0); grow(S.job.page[0], S.job.page[1]); }
  if (S.job) for (const o of S.job.left_out || []) for (const r of o.outline) for (const p of r) grow(p[0], p[1]);
  else {
    if (pathBox && S.path.length > 1) { grow(pathBox[0], pathBox[1]); grow(pathBox[2], pathBox[3]); }
    else {
      const set = (n) => { const r = S.settings.find((s) => s[0] === n); return r ? parseFloat(r[1]) : 100; };
      grow(0, 0); grow(set(130), set(131));
    }
    if (S.status) grow(S.status.pos[0], S.status.pos[1]);
  }
  const m = Math.max(b[2] - b[0], b[3] - b[1], 10) * 0.04;
  return [b[0] - m, b[1] - m, Math.max(b[2], b[0] + 10) + m, Math.max(b[3], b[1] + 10) + m];
}

function invalidate() { geo = null; plan = null; ink = null; inkDone = 0; draw(); }
function fitView() { V.zoom = 1; V.px = 0; V.py = 0; }

function geometry(c) {
  const r = window.devicePixelRatio || 1, w = c.clientWidth * r, h = c.clientHeight * r;
  if (geo && geo.w === w && geo.h === h) return geo;
  const b = bounds(), pad = 12 * r;
  const k0 = Math.min((w - 2 * pad) / (b[2] - b[0]), (h - 2 * pad) / (b[3] - b[1]));
  const k = k0 * V.zoom, cx = (b[0] + b[2]) / 2, cy = (b[1] + b[3]) / 2;
  const ox = w / 2 + V.px * r - cx * k, oy = h / 2 + V.py * r + cy * k;
  geo = { w, h, r, b, k, k0, cx, cy, X: (x) => ox + x * k, Y: (y) => oy - y * k, x: (X) => (X - ox) / k, y: (Y) => (oy - Y) / k };
  plan = null; ink = null; inkDone = 0;
  return geo;
}

function layer(g) { const c = document.createElement("canvas"); c.width = g.w; c.height = g.h; return c; }

// The grid, then the planned job a slice at a time (about 4 ms a frame, so
// a job of half a million moves never holds the page). The job's lines are
// set as pixels straight into the layer's ImageData (Bresenham, clipped to the
// canvas): the canvas's own anti-aliased stroking of dense, self-crossing
// paths took hundreds of ms per thousand moves without a GPU.
const DRAWN = 0xffc8c8c8, TRAVEL = 0xffe4e4e4; // #c8c8c8, #e4e4e4 (ABGR)
function paintPlan(G) {
  const c = layer(G), g = c.getContext("2d", { willReadFrequently: true }), { X, Y, r } = G;
  g.fillStyle = "#fff"; g.fillRect(0, 0, G.w, G.h);
  g.strokeStyle = "#eee"; g.lineWidth = 1;
  const x0 = G.x(0), x1 = G.x(G.w), y0 = G.y(G.h), y1 = G.y(0);
  const step = 10 * Math.pow(10, Math.max(0, Math.floor(Math.log10(80 / (G.k * 10 / r)))));
  g.beginPath();
  for (let x = Math.ceil(x0 / step) * step; x <= x1; x += step) { g.moveTo(X(x), 0); g.lineTo(X(x), G.h); }
  for (let y = Math.ceil(y0 / step) * step; y <= y1; y += step) { g.moveTo(0, Y(y)); g.lineTo(G.w, Y(y)); }
  g.stroke();
  // An SVG's page outline, and what it leaves out (text, images, fills) in orange.
  if (S.job && S.job.page) {
    const p = S.job.page;
    g.strokeStyle = "#999"; g.lineWidth = r; g.strokeRect(X(0), Y(p[1]), X(p[0]) - X(0), Y(0) - Y(p[1]));
  }
  for (const o of (S.job && S.job.left_out) || []) {
    g.beginPath();
    for (const ring of o.outline) ring.forEach((p, i) => i ? g.lineTo(X(p[0]), Y(p[1])) : g.moveTo(X(p[0]), Y(p[1])));
    g.fillStyle = "rgba(240,140,0,0.25)"; g.fill("evenodd");
    g.strokeStyle = "#f08c00"; g.lineWidth = 1.5 * r; g.stroke();
  }
  const img = g.getImageData(0, 0, G.w, G.h);
  return { c, g, img, px: new Uint32Array(img.data.buffer), piece: 0, row: 0, drawn: 0 };
}

// Clips the segment to [0, w) x [0, h) (Liang-Barsky); null when it misses.
function clip(x0, y0, x1, y1, w, h) {
  if (x0 >= 0 && x1 >= 0 && y0 >= 0 && y1 >= 0 && x0 < w - 1 && x1 < w - 1 && y0 < h - 1 && y1 < h - 1) return [x0, y0, x1, y1];
  let t0 = 0, t1 = 1;
  const dx = x1 - x0, dy = y1 - y0;
  for (const [p, q] of [[-dx, x0], [dx, w - 1 - x0], [-dy, y0], [dy, h - 1 - y0]]) {
    if (p === 0) { if (q < 0) return null; continue; }
    const t = q / p;
    if (p < 0) { if (t > t1) return null; if (t > t0) t0 = t; } else { if (t < t0) return null; if (t < t1) t1 = t; }
  }
  return [x0 + t0 * dx, y0 + t0 * dy, x0 + t1 * dx, y0 + t1 * dy];
}

function pixLine(P, s, color, thick, dash) {
  const { px, img } = P, w = img.width, h = img.height;
  let x0 = Math.round(s[0]), y0 = Math.round(s[1]);
  const x1 = Math.round(s[2]), y1 = Math.round(s[3]);
  const dx = Math.abs(x1 - x0), dy = -Math.abs(y1 - y0), sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  let err = dx + dy, n = 0;
  for (;;) {
    if (!dash || n % 7 < 4) {
      const i = y0 * w + x0;
      if (color === DRAWN || px[i] !== DRAWN) px[i] = color;
      if (thick) {
        if (x0 + 1 < w) px[i + 1] = color;
        if (y0 + 1 < h) { px[i + w] = color; if (x0 + 1 < w) px[i + w + 1] = color; }
      }
    }
    if (x0 === x1 && y0 === y1) break;
    const e2 = 2 * err;
    if (e2 >= dy) { err += dy; x0 += sx; }
    if (e2 <= dx) { err += dx; y0 += sy; }
    n++;
  }
}

function planMore(G, budget) {
  const pieces = S.job ? S.job.preview.pieces : [], { X, Y } = G, t0 = performance.now(), thick = true;
  while (plan.piece < pieces.length && performance.now() - t0 < budget) {
    const f = pieces[plan.piece], end = Math.min(f.length, plan.row + 500);
    for (let k = plan.row; k < end; k += 5) {
      const s = clip(X(f[k]), Y(f[k + 1]), X(f[k + 2]), Y(f[k + 3]), G.w, G.h);
      if (s) pixLine(plan, s, f[k + 4] ? DRAWN : TRAVEL, thick && f[k + 4], !f[k + 4]);
    }
    plan.drawn += (end - plan.row) / 5;
    if (end < f.length) plan.row = end; else { plan.piece++; plan.row = 0; }
  }
  // Copying the pixels in costs a few ms: every 250 ms while painting, and at the end.
  const finished = plan.piece >= pieces.length;
  if (!plan.shown && (finished || performance.now() - (plan.put || 0) > 250)) {
    plan.g.putImageData(plan.img, 0, 0); plan.put = performance.now(); plan.shown = finished;
  }
  return finished;
}

// Appends the path's new segments to the ink layer.
function paintInk(G) {
  if (!ink) { ink = layer(G); inkDone = 0; }
  const g = ink.getContext("2d"), { X, Y, r } = G;
  g.lineCap = "round"; g.lineJoin = "round";
  const down = new Path2D(), up = new Path2D();
  for (let i = Math.max(1, inkDone); i < S.path.length; i++) {
    const a = S.path[i - 1], p = S.path[i], d = a[2] && p[2] ? down : up;
    d.moveTo(X(a[0]), Y(a[1])); d.lineTo(X(p[0]), Y(p[1]));
  }
  inkDone = S.path.length;
  g.strokeStyle = "#dc3c3c"; g.lineWidth = r; g.setLineDash([5 * r, 4 * r]); g.stroke(up);
  g.setLineDash([]); g.strokeStyle = "#143c8c"; g.lineWidth = 2.5 * r; g.stroke(down);
}

let drawPending = false;
function draw() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(() => { drawPending = false; paint(); });
}

function paint() {
  const t0 = performance.now();
  const c = $("plot"), G = geometry(c);
  if (c.width !== G.w || c.height !== G.h) { c.width = G.w; c.height = G.h; }
  const t1 = performance.now();
  if (!plan) plan = paintPlan(G);
  const t2 = performance.now();
  // Only a complete preview is painted (pieces still arriving are not).
  const planned = !S.job || !S.job.complete || planMore(G, 4);
  const t3 = performance.now();
  paintInk(G);
  const t4 = performance.now();
  const g = c.getContext("2d");
  g.drawImage(plan.c, 0, 0); g.drawImage(ink, 0, 0);
  S.parts = [t1 - t0, t2 - t1, t3 - t2, t4 - t3, performance.now() - t4];
  S.planDrawn = plan.drawn; // moves set into the job's layer since it was last laid out
  if (S.status) {
    g.fillStyle = S.status.down ? "#143c8c" : "#1e9e3c";
    g.beginPath(); g.arc(G.X(S.status.pos[0]), G.Y(S.status.pos[1]), 5 * G.r, 0, 7); g.fill();
  }
  // Paint times (and the parts of any slow one) for the browser tests' figures.
  S.paints.push(performance.now() - t0);
  if (performance.now() - t0 > 20) (S.slow = S.slow || []).push(S.parts.map((x) => x.toFixed(0)).join("/"));
  if (S.paints.length > 500) S.paints.splice(0, 250);
  if (!planned) draw();
}

// Zoom by `f` keeping the point at canvas CSS position (mx, my) in place.
function zoomAt(f, mx, my) {
  const c = $("plot"), w = c.clientWidth, h = c.clientHeight;
  const z = Math.min(200, Math.max(0.2, V.zoom * f)); f = z / V.zoom;
  V.px = mx - w / 2 - (mx - w / 2 - V.px) * f; V.py = my - h / 2 - (my - h / 2 - V.py) * f;
  V.zoom = z; invalidate();
}
function panBy(dx, dy) { V.px += dx; V.py += dy; invalidate(); }

// One finger scrolls the page (touch-action: pan-x pan-y); two pan and pinch-zoom the drawing.
(() => {
  const c = $("plot");
  let t = null;
  const mid = (e) => {
    const r = c.getBoundingClientRect(), a = e.touches[0], b = e.touches[1];
    return { x: (a.clientX + b.clientX) / 2 - r.left, y: (a.clientY + b.clientY) / 2 - r.top, d: Math.hypot(a.clientX - b.clientX, a.clientY - b.clientY) };
  };
  c.addEventListener("touchstart", (e) => { if (e.touches.length === 2) { t = mid(e); e.preventDefault(); } }, { passive: false });
  c.addEventListener("touchmove", (e) => {
    if (e.touches.length !== 2 || !t) return;
    e.preventDefault();
    const n = mid(e);
    V.px += n.x - t.x; V.py += n.y - t.y;
    zoomAt(n.d / Math.max(1, t.d), n.x, n.y);
    t = n;
  }, { passive: false });
  c.addEventListener("touchend", (e) => { if (e.touches.length < 2) t = null; });
  let drag = null;
  c.addEventListener("pointerdown", (e) => { if (e.pointerType === "mouse") { drag = [e.clientX, e.clientY]; c.setPointerCapture(e.pointerId); } });
  c.addEventListener("pointermove", (e) => { if (drag) { panBy(e.clientX - drag[0], e.clientY - drag[1]); drag = [e.clientX, e.clientY]; } });
  c.addEventListener("pointerup", () => { drag = null; });
  // Wheel zooms only with Ctrl (a trackpad pinch): a plain wheel scrolls the page.
  c.addEventListener("wheel", (e) => {
    if (!e.ctrlKey) return;
    e.preventDefault();
    const r = c.getBoundingClientRect();
    zoomAt(Math.exp(-e.deltaY / 200), e.clientX - r.left, e.clientY - r.top);
  }, { passive: false });
  $("zin").onclick = () => zoomAt(1.5, c.clientWidth / 2, c.clientHeight / 2);
  $("zout").onclick = () => zoomAt(1 / 1.5, c.clientWidth / 2, c.clientHeight / 2);
  $("zfit").onclick = () => { fitView(); invalidate(); };
})();

// ---- Jobs ------------------------------------------------------------------
// A job goes in parts small enough for one message each, whatever the characters.
const PART = 128 * 1024;
function load(kind, name, data, size, bytes) {
  if (bytes > S.limits.job) {
    banner(name + ": " + (bytes / 1e6).toFixed(1) + " MB is over the web view's limit of " + (S.limits.job >> 20) + " MB", false);
    return;
  }
  S.loading = name; S.loadStart = performance.now();
  $("jobinfo").textContent = "preparing " + name + "…" + (S.job ? " (" + S.job.name + " stays loaded until then)" : "");
  const parts = Math.max(1, Math.ceil(data.length / PART));
  if (!send({ t: "load", kind, name, size, parts, bytes })) { S.loading = null; showJobInfo(); banner("not connected: nothing loaded", false); return; }
  for (let i = 0; i < parts; i++) send({ t: "part", data: data.slice(i * PART, (i + 1) * PART) });
}

document.addEventListener("click", (e) => {
  const b = e.target.closest("button");
  if (!b) return;
  if (b.dataset.rt) send({ t: "rt", b: parseInt(b.dataset.rt, 10) });
  if (b.dataset.cmd) command(b.dataset.cmd, b.textContent.trim() + " (" + b.dataset.cmd + ")");
  if (b.dataset.jog) {
    const [dx, dy] = b.dataset.jog.split(",").map(Number), s = parseFloat($("jogstep").value);
    command("$J=G91 G21 X" + (dx * s) + " Y" + (dy * s) + " F" + parseFloat($("jogfeed").value), "jog");
  }
});
$("take").onclick = () => send({ t: "take" });
$("run").onclick = () => send({ t: "run" });
$("stop").onclick = () => send({ t: "stop" });
$("rejob").onclick = () => send({ t: "resume" });
$("bclose").onclick = () => banner("", false);
$("textgo").onclick = () => {
  const t = $("text").value;
  $("file").value = "";
  load("text", "text", t, parseFloat($("textsize").value), new Blob([t]).size);
};
$("file").onchange = () => {
  const f = $("file").files[0];
  if (!f) return;
  if (f.size > S.limits.job) { load("gcode", f.name, "", 0, f.size); $("file").value = ""; return; }
  f.text().then((t) => load(/\.svg$/i.test(f.name) ? "svg" : "gcode", f.name, t, 0, f.size));
};
$("console").onsubmit = (e) => {
  e.preventDefault();
  const line = $("line").value.trim();
  if (!line) return;
  log("> " + line);
  command(line, line);
  $("line").value = "";
};
window.addEventListener("resize", () => { geo = null; draw(); });
showState();
connect();
