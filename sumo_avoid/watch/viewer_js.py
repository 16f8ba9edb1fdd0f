"""The run viewer's style sheet and script (plain ES2017, no library), inlined into the page by
:mod:`sumo_avoid.watch.viewer`. ``window.RUN`` holds the data (:func:`sumo_avoid.watch.viewer.page_data`)."""

CSS = ("body{font-family:sans-serif;margin:0;font-size:13px}#top{padding:6px 10px;background:#223;color:#fff}"
       "#main{display:flex}#cv{border:1px solid #999;background:#eef1ea;cursor:grab;flex:none}"
       "#side{padding:0 10px;width:330px;max-height:640px;overflow:auto}#side h3{margin:8px 0 3px;font-size:13px}"
       "#bar{padding:6px 10px}#track{position:relative;width:1000px;margin-top:4px}#slider{width:100%}"
       "#marks{position:relative;height:14px}.mark{position:absolute;top:0;width:6px;height:12px;margin-left:-3px;"
       "border:none;padding:0;cursor:pointer}.collision{background:#e00000}.ssm{background:#e0a800}"
       ".violation{background:#ff6a00}.ev{display:block;border:none;background:none;text-align:left;cursor:pointer;"
       "padding:1px 0;color:#036}.ev:hover{text-decoration:underline}table{border-collapse:collapse}"
       "td{padding:1px 4px;border-bottom:1px solid #eee}")

SCRIPT = r"""
"use strict";
(function () {
const R = window.RUN, cv = document.getElementById("cv"), g = cv.getContext("2d");
const $ = id => document.getElementById(id), slider = $("slider"), errors = [];
window.addEventListener("error", e => errors.push(String(e.message)));
const A = R.actors, T = R.times, N = T.length;
const KIND = {road: "#a9a9a9", sidewalk: "#d9cdb8", bike: "#d98c7a", bus: "#e8c95a"};
const EGO = "#0046c7", OTHER = "#2f8f2f", PERSON = "#7a2bd1";
const LIGHT = {G: "#00c000", g: "#007a00", y: "#ffd000", Y: "#ffd000", r: "#e00000", R: "#e00000", u: "#ff8000",
               s: "#8000c0"};
let frame = 0, playing = false, simT = T[0], last = null, follow = true, drag = null;
const view = {cx: 0, cy: 0, s: 4};  // centre (net m) and scale (px per m)
slider.max = N - 1;

const esc = t => String(t).replace(/[&<>"]/g, c => ({"&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;"})[c]);
const X = x => (x - view.cx) * view.s + cv.width / 2, Y = y => cv.height / 2 - (y - view.cy) * view.s;

// the road users of frame f: 7 numbers each (actor, x, y, heading, speed, vx, vy)
function rows(f) {
  const a = R.frames[f], out = [];
  for (let i = 0; i < a.length; i += 7)
    out.push({a: A[a[i]], x: a[i + 1], y: a[i + 2], h: a[i + 3], v: a[i + 4], vx: a[i + 5], vy: a[i + 6]});
  return out;
}
function corners(r) {
  const c = Math.cos(r.h), s = Math.sin(r.h), l = r.a.length / 2, w = r.a.width / 2;
  return [[l, w], [-l, w], [-l, -w], [l, -w]].map(p => [r.x + p[0] * c - p[1] * s, r.y + p[0] * s + p[1] * c]);
}
function proj(P, ax) {
  let lo = Infinity, hi = -Infinity;
  for (const p of P) { const d = p[0] * ax[0] + p[1] * ax[1]; lo = Math.min(lo, d); hi = Math.max(hi, d); }
  return [lo, hi];
}
// separating-axis test of two rectangles, closer than tol (m) counts as touching
function touch(P, Q, tol) {
  for (const S of [P, Q]) for (let i = 0; i < 4; i++) {
    const e = [S[(i + 1) % 4][0] - S[i][0], S[(i + 1) % 4][1] - S[i][1]], n = Math.hypot(e[0], e[1]) || 1;
    const ax = [-e[1] / n, e[0] / n], a = proj(P, ax), b = proj(Q, ax);
    if (a[1] + tol < b[0] || b[1] + tol < a[0]) return false;
  }
  return true;
}
function frameAt(t) {  // the last frame at or before t
  let lo = 0, hi = N - 1;
  while (lo < hi) { const m = (lo + hi + 1) >> 1; if (T[m] <= t + 1e-9) lo = m; else hi = m - 1; }
  return lo;
}
function fit() {  // the egos' whole path if it fits, else follow the ego
  const xs = [], ys = [];
  for (const r of rows(0).concat(rows(N - 1))) { xs.push(r.x); ys.push(r.y); }
  for (let f = 0; f < N; f += Math.max(1, N >> 6)) for (const r of rows(f)) if (r.a.ego) { xs.push(r.x); ys.push(r.y); }
  const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
  const w = x1 - x0 + 40, h = y1 - y0 + 40;
  view.cx = (x0 + x1) / 2; view.cy = (y0 + y1) / 2;
  if (w < 130 && h < 90) { follow = false; view.s = Math.min(cv.width / w, cv.height / h); } else view.s = cv.width / 60;
  $("follow").checked = follow;
}
function path(P, close) {
  g.beginPath();
  P.forEach((p, i) => i ? g.lineTo(X(p[0]), Y(p[1])) : g.moveTo(X(p[0]), Y(p[1])));
  if (close) g.closePath();
}
function road() {
  const rd = R.road;
  g.fillStyle = "#eef1ea"; g.fillRect(0, 0, cv.width, cv.height);
  g.lineCap = "butt"; g.lineJoin = "round";
  for (const w of rd.walking || []) { path(w, true); g.fillStyle = KIND.sidewalk; g.fill(); }
  for (const j of rd.junctions) { path(j, true); g.fillStyle = KIND.road; g.fill(); }
  for (const pass of [0, 1]) for (const l of rd.lanes) {  // white under each lane: the lines between lanes
    if (l.internal && !pass) continue;
    path(l.shape, false);
    g.lineWidth = Math.max(1, (l.width - (pass ? 0.3 : 0)) * view.s);
    g.strokeStyle = pass ? KIND[l.kind] || KIND.road : "#ffffff"; g.stroke();
  }
  for (const c of rd.crossings) {
    path(c.shape, false); g.lineWidth = c.width * view.s; g.strokeStyle = "#fff"; g.stroke();
    g.setLineDash([0.5 * view.s, 0.5 * view.s]); g.lineWidth = c.width * 0.8 * view.s; g.strokeStyle = "#666";
    g.stroke(); g.setLineDash([]);
  }
}
function lights(sig) {  // a bar per traffic-light link at its stop line, in the link's state
  g.lineWidth = Math.max(2, 0.5 * view.s); g.lineCap = "butt";
  for (const b of R.road.signals || []) {
    const st = sig[b[0]], c = st ? LIGHT[st[b[1]]] : null;
    if (!c) continue;
    g.strokeStyle = c; g.beginPath(); g.moveTo(X(b[2][0]), Y(b[2][1])); g.lineTo(X(b[3][0]), Y(b[3][1])); g.stroke();
  }
}
function mark(x, y, col, txt, i) {  // an event: a cross and its label (the i-th near this time)
  if (x === null || y === null) return;
  const u = 7;
  g.strokeStyle = col; g.lineWidth = 3; g.beginPath();
  g.moveTo(X(x) - u, Y(y) - u); g.lineTo(X(x) + u, Y(y) + u); g.moveTo(X(x) - u, Y(y) + u); g.lineTo(X(x) + u, Y(y) - u);
  g.stroke();
  g.font = "11px sans-serif";
  const ty = Y(y) - 12 - 15 * i;
  g.fillStyle = "rgba(255,255,255,0.85)"; g.fillRect(X(x) + 7, ty - 11, g.measureText(txt).width + 4, 14);
  g.fillStyle = col; g.fillText(txt, X(x) + 9, ty);
}
const colour = k => k === "collision" ? "#e00000" : k === "ssm conflict" ? "#e0a800" : "#ff6a00";
function state() {  // what the page shows, for tools and tests (window.viewerState, <pre id="state">)
  const rs = rows(frame), fp = {}, touching = [];
  for (const r of rs) fp[r.a.id] = corners(r);
  for (const r of rs) if (r.a.ego) for (const q of rs)
    if (q !== r && (!q.a.ego || q.a.id > r.a.id) && touch(fp[r.a.id], fp[q.a.id], 0.05)) touching.push([r.a.id, q.a.id]);
  return {time_s: T[frame], frame: frame, frames: N, stride: R.stride, footprints: fp, touching: touching,
          errors: errors, view: view};
}
function signalsAt(t) {
  const sig = {};
  for (const s of R.signals) if (s[0] <= t + 1e-9) sig[s[1]] = s[2];
  return sig;
}
function draw() {
  const rs = rows(frame), ego = rs.find(r => r.a.ego), sig = signalsAt(T[frame]);
  if (follow && ego) { view.cx = ego.x; view.cy = ego.y; }
  road();
  lights(sig);
  for (const gl of R.goals) { g.fillStyle = "gold"; g.beginPath(); g.arc(X(gl[1]), Y(gl[2]), 6, 0, 7); g.fill(); }
  rs.sort((a, b) => a.a.ego - b.a.ego);  // egos on top
  for (const r of rs) {
    g.fillStyle = r.a.ego ? EGO : r.a.person ? PERSON : OTHER;
    if (r.a.person) {
      g.beginPath(); g.arc(X(r.x), Y(r.y), Math.max(2, Math.max(0.3, r.a.length / 2) * view.s), 0, 7); g.fill();
      continue;
    }
    path(corners(r), true); g.fill(); g.strokeStyle = "#111"; g.lineWidth = 1; g.stroke();
    if (r.a.ego || view.s > 6) { g.fillStyle = "#000"; g.font = "11px sans-serif"; g.fillText(r.a.id, X(r.x) + 4, Y(r.y) - 8); }
  }
  for (const r of rs) if (r.a.ego) {  // the ego's recorded velocity: where it is in 1 s
    g.strokeStyle = "#00b3ff"; g.lineWidth = 2; g.beginPath(); g.moveTo(X(r.x), Y(r.y));
    g.lineTo(X(r.x + r.vx), Y(r.y + r.vy)); g.stroke();
  }
  R.events.filter(e => Math.abs(e.t - T[frame]) < 3).forEach((e, i) => mark(e.x, e.y, colour(e.kind), e.label, i));
  const det = R.detections[String(frame)] || [];
  g.fillStyle = "#ff2d2d";
  for (let i = 0; i < det.length; i += 2) { g.beginPath(); g.arc(X(det[i]), Y(det[i + 1]), 3, 0, 7); g.fill(); }
  const st = state();
  $("clock").textContent = `t = ${T[frame].toFixed(2)} s of ${T[N - 1].toFixed(1)} s`
    + (R.stride > 1 ? ` (every ${R.stride}th step shown)` : "");
  $("now").innerHTML = rs.filter(r => r.a.ego)
    .map(r => `${esc(r.a.id)}: ${r.v.toFixed(2)} m/s at (${r.x.toFixed(1)}, ${r.y.toFixed(1)})`).join("<br>")
    + `<br>${rs.length} road users` + (st.touching.length ? `<br><b style="color:#e00000">touching: `
    + esc(st.touching.map(p => p.join("–")).join(", ")) + "</b>" : "");
  $("sig").textContent = Object.keys(sig).length ? Object.entries(sig).map(e => e[0] + ": " + e[1]).join("\n")
    : "(none recorded)";
  window.viewerState = st;
  $("state").textContent = JSON.stringify(st);
}
function setFrame(f) { frame = Math.max(0, Math.min(N - 1, f)); slider.value = frame; simT = T[frame]; draw(); }
function tick(ts) {  // playing: recorded time runs at the chosen speed
  if (!playing) return;
  if (last !== null) {
    simT += (ts - last) / 1000 * +$("speed").value;
    const f = frameAt(simT);
    if (f !== frame) { frame = f; slider.value = f; draw(); }
    if (frame >= N - 1) { playing = false; $("play").textContent = "play"; }
  }
  last = ts;
  requestAnimationFrame(tick);
}
slider.addEventListener("input", () => { frame = +slider.value; simT = T[frame]; draw(); });
$("play").onclick = () => {
  playing = !playing; last = null; $("play").textContent = playing ? "pause" : "play";
  if (playing) { if (frame >= N - 1) setFrame(0); requestAnimationFrame(tick); }
};
$("follow").onchange = e => { follow = e.target.checked; draw(); };
cv.addEventListener("wheel", e => { e.preventDefault(); view.s *= e.deltaY < 0 ? 1.2 : 1 / 1.2; draw(); });
cv.addEventListener("mousedown", e => { drag = [e.clientX, e.clientY]; });
window.addEventListener("mouseup", () => { drag = null; });
cv.addEventListener("mousemove", e => {
  if (!drag) return;
  follow = false; $("follow").checked = false;
  view.cx -= (e.clientX - drag[0]) / view.s; view.cy += (e.clientY - drag[1]) / view.s; drag = [e.clientX, e.clientY];
  draw();
});
const span = Math.max(1e-9, T[N - 1] - T[0]);
R.events.forEach(e => {  // a mark on the timeline and a line in the list, each jumping there
  const b = document.createElement("button");
  b.className = "mark " + (e.kind === "collision" ? "collision" : e.kind === "ssm conflict" ? "ssm" : "violation");
  b.style.left = (100 * (e.t - T[0]) / span) + "%"; b.title = e.label; b.onclick = () => setFrame(frameAt(e.t));
  $("marks").appendChild(b);
  const l = document.createElement("button");
  l.className = "ev"; l.textContent = e.label; l.style.color = colour(e.kind); l.onclick = () => setFrame(frameAt(e.t));
  $("evlist").appendChild(l);
});
if (!R.events.length) $("evlist").textContent = "none";
$("metrics").innerHTML = "<table>" + R.metrics
  .map(m => `<tr><td>${esc(m[0])}</td><td>${m[1] === null ? "n/a" : esc(m[1])}</td></tr>`).join("") + "</table>";
$("sig").style.whiteSpace = "pre";
fit();
const h = /[#&]t=([-0-9.]+)/.exec(location.hash);  // FILE.html#t=57.3: the slider moved there, as by a user
if (h) { slider.value = frameAt(+h[1]); slider.dispatchEvent(new Event("input")); } else draw();
})();
"""
