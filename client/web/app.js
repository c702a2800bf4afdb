// The live job page: one WebSocket to `omega view` (docs/web.md), the job list with controls,
// and the job view whose image converges tile by tile from float pixels tone-mapped here.
"use strict";

const $ = (id) => document.getElementById(id);

const state = {
  ws: null,
  nextId: 1,
  user: "",
  jobs: new Map(),     // job id -> job fields (as the last list had them)
  open: null,          // the job id the view shows
  film: null,          // {width, height, rgb, vr, image (ImageData)}
  tiles: 0,            // float tiles applied to the open job's film
  done: null,          // the open job's final state once it ended
  curve: [],           // [elapsed_s, rel_error] of the open job
  pending: new Map(),  // request id -> what it was
};
window.omegaView = state;  // for the browser test and the console

function send(msg) {
  msg.id = state.nextId++;
  state.pending.set(msg.id, msg);
  state.ws.send(JSON.stringify(msg));
  return msg.id;
}

function displayParams() {
  return { mode: $("mode").value, exposure: parseFloat($("exposure").value), gamma: parseFloat($("gamma").value) || 2.2 };
}

// ---------------------------------------------------------------- login

function login(ev) {
  ev.preventDefault();
  if (state.ws) state.ws.close();
  $("login-error").hidden = true;
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.binaryType = "arraybuffer";
  state.ws = ws;
  ws.onopen = () => send({ type: "login", user: $("user").value, token: $("token").value });
  ws.onmessage = (e) => (typeof e.data === "string" ? onText(JSON.parse(e.data)) : onBinary(e.data));
  ws.onclose = () => {
    if (state.ws !== ws) return;
    state.ws = null;
    if ($("login").hidden) showError("the connection to omega view closed; log in again");
    $("login").hidden = false;
  };
}

function showError(text) {
  $("login-error").textContent = text;
  $("login-error").hidden = false;
}

// ---------------------------------------------------------------- messages

function onText(m) {
  const req = state.pending.get(m.id);
  state.pending.delete(m.id);
  switch (m.type) {
    case "welcome":
      state.user = m.user;
      $("who").textContent = `${m.user} @ ${m.server}`;
      $("login").hidden = true;
      $("list").hidden = false;
      break;
    case "error":
      if (!state.user || (req && req.type === "login")) showError(`${m.code}: ${m.message}`);
      else $("action-status").textContent = `${req ? req.type + " " + (req.job || "") + ": " : ""}${m.code}: ${m.message}`;
      break;
    case "jobs": showJobs(m.jobs); break;
    case "ok": $("action-status").textContent = `job ${m.job}: ${m.request} done`; break;
    case "job": openView(m); break;
    case "progress": if (m.job === state.open) onProgress(m.state, m.progress); break;
    case "done":
      if (m.job !== state.open) break;
      state.done = m.state;
      onProgress(m.state, m.progress);
      break;
    case "warnings": if (m.job === state.open) showWarnings(m.warnings, m.nonfinite); break;
  }
}

function onBinary(buf) {
  const dv = new DataView(buf);
  const magic = String.fromCharCode(dv.getUint8(0), dv.getUint8(1), dv.getUint8(2), dv.getUint8(3));
  const job = Number(dv.getBigUint64(8, true));
  if (magic === "OEXR") return saveExr(job, buf.slice(16));
  if (magic !== "OTF1" || job !== state.open) return;
  const flags = dv.getUint32(4, true);
  const [x0, y0, x1, y1, fw, fh] = [16, 20, 24, 28, 32, 36].map((o) => dv.getUint32(o, true));
  const w = x1 - x0, h = y1 - y0, n = w * h * 3;
  const rgb = new Float32Array(buf, 48, n);
  const vr = flags & 1 ? new Float32Array(buf, 48 + 4 * n, n) : null;
  if (!state.film || state.film.width !== fw || state.film.height !== fh) newFilm(fw, fh);
  const f = state.film;
  for (let y = 0; y < h; ++y) {
    const dst = 3 * ((y0 + y) * fw + x0), src = 3 * y * w;
    f.rgb.set(rgb.subarray(src, src + 3 * w), dst);
    if (vr) f.vr.set(vr.subarray(src, src + 3 * w), dst);
  }
  state.tiles++;
  paint(x0, y0, x1, y1);
  updateStatus();
}

// ---------------------------------------------------------------- job list

function rate(v) {
  if (v >= 1e9) return (v / 1e9).toFixed(2) + "G";
  if (v >= 1e6) return (v / 1e6).toFixed(2) + "M";
  if (v >= 1e3) return (v / 1e3).toFixed(1) + "k";
  return v.toFixed(0);
}

function button(text, cls, job, onclick) {
  const b = document.createElement("button");
  b.textContent = text;
  b.className = cls;
  b.dataset.job = job;
  b.onclick = (e) => { e.stopPropagation(); onclick(); };
  return b;
}

function controls(j) {
  const td = document.createElement("td");
  if (!j.mine) return td;
  const live = ["queued", "running", "paused"].includes(j.state);
  if (!live) return td;
  if (j.state === "paused") td.append(button("resume", "resume", j.job, () => send({ type: "resume", job: j.job })));
  else td.append(button("pause", "pause", j.job, () => send({ type: "pause", job: j.job })));
  td.append(button("cancel", "cancel", j.job, () => send({ type: "cancel", job: j.job })));
  const pri = document.createElement("input");
  Object.assign(pri, { type: "number", min: -1000, max: 1000, value: j.priority, className: "priority" });
  pri.dataset.job = j.job;
  pri.onclick = (e) => e.stopPropagation();
  pri.onchange = () => send({ type: "set_priority", job: j.job, priority: parseInt(pri.value, 10) || 0 });
  td.append(pri);
  return td;
}

// Updates the table in place: a row, its cells and its controls are replaced only when what
// they show changes, so a click is never lost to a refresh (the list comes every second).
function showJobs(jobs) {
  const body = $("jobs").tBodies[0];
  const focused = document.activeElement;
  if (focused && focused.classList.contains("priority")) return;  // don't replace what is being typed
  const rows = new Map([...body.rows].map((r) => [Number(r.dataset.job), r]));
  state.jobs.clear();
  jobs.forEach((j, i) => {
    state.jobs.set(j.job, j);
    let tr = rows.get(j.job);
    rows.delete(j.job);
    if (!tr) {
      tr = document.createElement("tr");
      tr.dataset.job = j.job;
      for (let k = 0; k < 8; ++k) tr.append(document.createElement("td"));
      tr.onclick = () => send({ type: "open", job: j.job });
    }
    tr.className = "state-" + j.state + (j.mine ? " mine" : "");
    [j.job, j.state, j.priority, j.owner, j.progress_text, rate(j.progress.samples_per_s), j.label].forEach((v, k) => {
      if (tr.cells[k].textContent !== String(v)) tr.cells[k].textContent = v;
    });
    // Which buttons the row shows: queued and running show the same ones, kept across the change.
    const key = !j.mine ? "none" : j.state === "paused" ? "paused" : ["queued", "running"].includes(j.state) ? "live" : "none";
    if (tr.dataset.controls !== key) {
      tr.dataset.controls = key;
      tr.replaceChild(controls(j), tr.cells[7]);
    }
    const pri = tr.cells[7].querySelector("input.priority");
    if (pri && pri.value !== String(j.priority)) pri.value = j.priority;
    if (body.rows[i] !== tr) body.insertBefore(tr, body.rows[i] || null);
  });
  for (const tr of rows.values()) tr.remove();
}

// ---------------------------------------------------------------- job view

function openView(j) {
  state.open = j.job;
  state.film = null;
  state.tiles = 0;
  state.done = null;
  state.curve = [];
  state.info = j;
  $("job-title").textContent = `job ${j.job}${j.label ? ": " + j.label : ""} (${j.owner})`;
  $("warnings").replaceChildren(Object.assign(document.createElement("li"), { textContent: "(waiting for the first tile)" }));
  $("job").hidden = false;
  $("list").hidden = true;
  onProgress(j.state, j.progress);
}

function newFilm(w, h) {
  const c = $("image");
  c.width = w;
  c.height = h;
  const image = c.getContext("2d").createImageData(w, h);
  state.film = { width: w, height: h, rgb: new Float32Array(3 * w * h), vr: new Float32Array(3 * w * h), image };
}

function paint(x0, y0, x1, y1) {
  const f = state.film;
  ToneMap.rect(f, f.image, x0, y0, x1, y1, displayParams());
  $("image").getContext("2d").putImageData(f.image, 0, 0, x0, y0, x1 - x0, y1 - y0);
}

function repaint() {
  $("exposure-value").textContent = parseFloat($("exposure").value).toFixed(1);
  $("error-legend").hidden = $("mode").value !== "error";
  if (state.film) paint(0, 0, state.film.width, state.film.height);
}

function onProgress(st, p) {
  state.progress = { state: st, ...p };
  if (p.rel_error !== undefined && p.elapsed_s >= 0) {
    const last = state.curve[state.curve.length - 1];
    if (!last || p.elapsed_s > last[0]) state.curve.push([p.elapsed_s, p.rel_error]);
    drawCurve();
  }
  updateStatus();
}

function updateStatus() {
  const p = state.progress || {};
  const err = p.rel_error !== undefined ? `, error ${(100 * p.rel_error).toFixed(2)}%` : "";
  const done = state.done ? ` (ended: ${state.done})` : "";
  $("job-status").textContent =
    `${p.state || ""}: ${p.spp || 0} spp in ${(p.elapsed_s || 0).toFixed(1)} s, ` +
    `${rate(p.samples_per_s || 0)} samples/s${err}; ${state.tiles} tiles received${done}`;
  $("job-status").dataset.state = state.done || p.state || "";
}

function drawCurve() {
  const c = $("curve"), g = c.getContext("2d"), pts = state.curve;
  g.clearRect(0, 0, c.width, c.height);
  g.strokeStyle = "#888";
  g.strokeRect(30.5, 0.5, c.width - 31, c.height - 21);
  if (!pts.length) return;
  const tMax = Math.max(pts[pts.length - 1][0], 1e-3);
  const ls = pts.map((p) => Math.log10(Math.max(p[1], 1e-6)));
  const lo = Math.floor(Math.min(...ls)), hi = Math.ceil(Math.max(...ls) + 1e-9);
  const X = (t) => 31 + (t / tMax) * (c.width - 33), Y = (l) => 1 + ((hi - l) / Math.max(hi - lo, 1)) * (c.height - 23);
  g.fillStyle = "#888";
  g.font = "10px sans-serif";
  for (let l = lo; l <= hi; ++l) g.fillText(`1e${l}`, 0, Math.min(Math.max(Y(l) + 3, 9), c.height - 21));
  g.fillText(`${tMax.toFixed(1)} s`, c.width - 40, c.height - 6);
  g.strokeStyle = "#e63";
  g.beginPath();
  pts.forEach((p, i) => (i ? g.lineTo(X(p[0]), Y(ls[i])) : g.moveTo(X(p[0]), Y(ls[i]))));
  g.stroke();
}

// Path-class warnings come from the renderer as "REGEX (what the paths are): missing, why"
// (renderer/pathspace/classify.cpp); the page says them in words, the regex last.
function showWarnings(list, nonfinite) {
  const ul = $("warnings");
  ul.replaceChildren();
  const li = (t) => ul.append(Object.assign(document.createElement("li"), { textContent: t }));
  if (!list.length) li("Nothing: this integrator can sample every kind of light path in this scene.");
  for (const w of list) {
    const m = /^(.+?) \((.+)\): missing, (.*)$/.exec(w);
    li(m ? `Missing from this image: ${m[2]}. Why: ${m[3]}. (Light paths ${m[1]}.)` : w);
  }
  if (nonfinite > 0) li(`${nonfinite} samples were NaN or infinite and were left out.`);
}

function onPointer(e) {
  const f = state.film;
  if (!f) return;
  const c = $("image"), r = c.getBoundingClientRect();
  const x = Math.floor(((e.clientX - r.left) / r.width) * f.width), y = Math.floor(((e.clientY - r.top) / r.height) * f.height);
  if (x < 0 || y < 0 || x >= f.width || y >= f.height) return;
  const i = 3 * (y * f.width + x);
  const v = [0, 1, 2].map((k) => f.rgb[i + k].toPrecision(4)).join(", ");
  const err = (100 * ToneMap.relError(f.rgb, f.vr, i)).toFixed(2);
  $("pixel").textContent = `(${x}, ${y}): RGB ${v}; relative error ${err}%`;
}

function saveExr(job, bytes) {
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([bytes], { type: "image/x-exr" }));
  const j = state.jobs.get(job);
  a.download = `${j && j.label ? j.label : "job-" + job}.exr`;
  document.body.append(a);
  a.click();
  a.remove();
  state.lastExr = { job, size: bytes.byteLength };
}

// ---------------------------------------------------------------- wiring

function init() {
  const hash = new URLSearchParams(location.hash.slice(1));
  if (hash.get("key")) $("token").value = hash.get("key");
  if (hash.get("user")) $("user").value = hash.get("user");
  $("login-form").onsubmit = login;
  for (const id of ["mode", "exposure", "gamma"]) $(id).oninput = repaint;
  $("image").onmousemove = onPointer;
  $("download").onclick = () => state.open && send({ type: "fetch", job: state.open });
  $("back").onclick = () => {
    send({ type: "close" });
    state.open = null;
    $("job").hidden = true;
    $("list").hidden = false;
  };
  drawCurve();
}

init();
