// inkstep web view: one websocket to the server, a canvas for the drawing, and
// the controls. Everything the machine does arrives as JSON messages (see
// host/src/web/link.rs); everything the page asks is a message back.
"use strict";
const $ = (id) => document.getElementById(id);
const token = new URLSearchParams(location.search).get("token");
const S = (window.inkstep = {
  id: 0, role: "watch", holder: null, status: null, path: [], job: null,
  settings: [], answers: {}, done: null, link: null,
});
let ws = null;
let nextId = 1;

function connect() {
  const q = token ? "?token=" + encodeURIComponent(token) : "";
  ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws" + q);
  ws.onmessage = (e) => handle(JSON.parse(e.data));
  ws.onclose = () => { $("link").textContent = "server gone: reconnecting"; setTimeout(connect, 1000); };
}

function send(m) { if (ws && ws.readyState === 1) ws.send(JSON.stringify(m)); }
function command(line) { const id = nextId++; send({ t: "cmd", id, line }); return id; }
function log(text) { const l = $("log"); l.textContent += text + "\n"; l.scrollTop = l.scrollHeight; }
function fmtTime(s) { s = Math.max(0, Math.round(s)); return Math.floor(s / 60) + ":" + String(s % 60).padStart(2, "0"); }

function handle(m) {
  switch (m.t) {
    case "hello":
      S.id = m.id; S.role = m.role; S.holder = m.holder; S.path = []; $("log").textContent = "";
      showRole(); break;
    case "control": S.holder = m.holder; showRole(); break;
    case "link":
      S.link = m; $("link").textContent = m.up ? "● " + m.port : "○ " + m.port + " " + m.error; break;
    case "status": showStatus(m); break;
    case "path": S.path = m.pts; draw(); break;
    case "clear": S.path = []; S.done = null; draw(); break;
    case "job":
      S.job = m; S.done = null;
      $("jobinfo").textContent = m.name + ": " + m.lines + " lines, about " + fmtTime(m.est_s);
      $("run").disabled = false; $("progress").value = 0; $("jobstate").textContent = "";
      draw(); break;
    case "done":
      S.done = m; $("jobstate").textContent = m.ok ? "done" : m.why;
      if (m.ok) $("progress").value = 1; break;
    case "settings": S.settings = m.list; showSettings(); break;
    case "answer": answered(m); break;
    case "log": log(m.text); break;
    case "error": log("error: " + m.text); break;
    case "denied": log("not done: " + m.why); break;
  }
}

function showRole() {
  const mine = S.holder === S.id;
  $("role").textContent = S.role === "watch" ? "watching" : mine ? "you control" : S.holder ? "another browser controls" : "";
  $("take").hidden = S.role !== "control" || mine;
  document.body.classList.toggle("watch", S.role === "watch");
}

function showStatus(m) {
  S.status = m;
  const st = $("state");
  st.textContent = m.state; st.className = "state " + m.state.split(":")[0];
  const p = m.pos.map((v) => v.toFixed(3));
  $("pos").textContent = "X " + p[0] + " Y " + p[1] + " Z " + p[2];
  $("feed").textContent = "F " + Math.round(m.feed) + " mm/min" + (m.down ? " · pen down" : " · pen up");
  $("ov").textContent = "Ov feed " + m.ov[0] + "% rapid " + m.ov[1] + "%";
  if (m.point) S.path.push(m.point);
  if (m.job) {
    $("progress").value = m.job.done;
    $("jobstate").textContent = m.job.acked + "/" + m.job.lines + " lines · " +
      Math.round(100 * m.job.done) + "% · " + fmtTime(m.job.left_s) + " left";
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
    inp.value = v; inp.dataset.n = n;
    inp.onkeydown = (e) => { if (e.key === "Enter") inp.blur(); };
    inp.onchange = () => setSetting(n, inp.value, tr);
    tr.insertCell().appendChild(inp);
    tr.insertCell().textContent = name;
    tr.insertCell().className = "err";
  }
}

function setSetting(n, v, tr) {
  tr.cells[3].textContent = "…";
  S.answers[command("$" + n + "=" + v.trim())] = tr;
}

function answered(m) {
  const tr = S.answers[m.id];
  if (tr) { tr.cells[3].textContent = m.ok ? "" : m.error; delete S.answers[m.id]; }
  else if (!m.ok) log(m.error);
}

// The drawing: fitted to the job, the path and the pen (the machine area,
// from $130/$131, when there is neither), the planned job in grey, an SVG's
// page outline and what it leaves out (text, images, fills: orange), the path
// from the status reports (pen down blue, pen-up travel red dashed), the pen.
function bounds() {
  let b = null;
  const grow = (x, y) => { b = b ? [Math.min(b[0], x), Math.min(b[1], y), Math.max(b[2], x), Math.max(b[3], y)] : [x, y, x, y]; };
  if (S.job) for (const m of S.job.preview) { grow(m[0], m[1]); grow(m[2], m[3]); }
  if (S.job && S.job.page) { grow(0, 0); grow(S.job.page[0], S.job.page[1]); }
  if (S.job) for (const o of S.job.left_out || []) for (const r of o.outline) for (const p of r) grow(p[0], p[1]);
  for (const p of S.path) grow(p[0], p[1]);
  if (S.status) grow(S.status.pos[0], S.status.pos[1]);
  if (!b || (!S.job && S.path.length < 2)) {
    const set = (n) => { const r = S.settings.find((s) => s[0] === n); return r ? parseFloat(r[1]) : 100; };
    grow(0, 0); grow(set(130), set(131));
  }
  const m = Math.max(b[2] - b[0], b[3] - b[1], 10) * 0.04;
  return [b[0] - m, b[1] - m, Math.max(b[2], b[0] + 10) + m, Math.max(b[3], b[1] + 10) + m];
}

let drawPending = false;
function draw() {
  if (drawPending) return;
  drawPending = true;
  requestAnimationFrame(() => { drawPending = false; paint(); });
}

function paint() {
  const c = $("plot"), r = window.devicePixelRatio || 1;
  c.width = c.clientWidth * r; c.height = c.clientHeight * r;
  const g = c.getContext("2d");
  const b = bounds(), pad = 12 * r;
  const k = Math.min((c.width - 2 * pad) / (b[2] - b[0]), (c.height - 2 * pad) / (b[3] - b[1]));
  const X = (x) => pad + (x - b[0]) * k, Y = (y) => c.height - pad - (y - b[1]) * k;
  g.fillStyle = "#fff"; g.fillRect(0, 0, c.width, c.height);
  g.strokeStyle = "#eee"; g.lineWidth = 1;
  for (let x = Math.ceil(b[0] / 10) * 10; x <= b[2]; x += 10) { g.beginPath(); g.moveTo(X(x), Y(b[1])); g.lineTo(X(x), Y(b[3])); g.stroke(); }
  for (let y = Math.ceil(b[1] / 10) * 10; y <= b[3]; y += 10) { g.beginPath(); g.moveTo(X(b[0]), Y(y)); g.lineTo(X(b[2]), Y(y)); g.stroke(); }
  const lines = (segs, style, width, dash) => {
    g.strokeStyle = style; g.lineWidth = width * r; g.setLineDash(dash.map((d) => d * r)); g.beginPath();
    for (const s of segs) { g.moveTo(X(s[0]), Y(s[1])); g.lineTo(X(s[2]), Y(s[3])); }
    g.stroke(); g.setLineDash([]);
  };
  if (S.job && S.job.page) {
    g.strokeStyle = "#999"; g.lineWidth = r;
    g.strokeRect(X(0), Y(S.job.page[1]), S.job.page[0] * k, S.job.page[1] * k);
  }
  if (S.job) for (const o of S.job.left_out || []) {
    g.beginPath();
    for (const ring of o.outline) ring.forEach((p, i) => i ? g.lineTo(X(p[0]), Y(p[1])) : g.moveTo(X(p[0]), Y(p[1])));
    g.fillStyle = "rgba(240,140,0,0.25)"; g.fill("evenodd");
    g.strokeStyle = "#f08c00"; g.lineWidth = 1.5 * r; g.stroke();
  }
  if (S.job) {
    lines(S.job.preview.filter((m) => m[4]), "#c8c8c8", 2, []);
    lines(S.job.preview.filter((m) => !m[4]), "#e4e4e4", 1, [4, 3]);
  }
  const down = [], up = [];
  for (let i = 1; i < S.path.length; i++) {
    const a = S.path[i - 1], p = S.path[i];
    (a[2] && p[2] ? down : up).push([a[0], a[1], p[0], p[1]]);
  }
  lines(up, "#dc3c3c", 1, [5, 4]);
  g.lineCap = "round"; g.lineJoin = "round";
  lines(down, "#143c8c", 2.5, []);
  if (S.status) {
    g.fillStyle = S.status.down ? "#143c8c" : "#1e9e3c";
    g.beginPath(); g.arc(X(S.status.pos[0]), Y(S.status.pos[1]), 5 * r, 0, 7); g.fill();
  }
}

function load(kind, name, data, size) { $("jobinfo").textContent = "preparing " + name + "…"; send({ t: "load", kind, name, data, size }); }

document.addEventListener("click", (e) => {
  const b = e.target.closest("button");
  if (!b) return;
  if (b.dataset.rt) send({ t: "rt", b: parseInt(b.dataset.rt, 10) });
  if (b.dataset.cmd) command(b.dataset.cmd);
  if (b.dataset.jog) {
    const [dx, dy] = b.dataset.jog.split(",").map(Number), s = parseFloat($("jogstep").value);
    command("$J=G91 G21 X" + (dx * s) + " Y" + (dy * s) + " F" + parseFloat($("jogfeed").value));
  }
});
$("take").onclick = () => send({ t: "take" });
$("run").onclick = () => send({ t: "run" });
$("stop").onclick = () => send({ t: "stop" });
$("textgo").onclick = () => load("text", "text", $("text").value, parseFloat($("textsize").value));
$("file").onchange = () => {
  const f = $("file").files[0];
  if (!f) return;
  f.text().then((t) => load(/\.svg$/i.test(f.name) ? "svg" : "gcode", f.name, t));
};
window.addEventListener("resize", draw);
connect();
