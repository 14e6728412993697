// skinhil live view: draws the updates of /events (server-sent events) on canvases.
// Raster: channels on y, board time scrolling right to left over WINDOW_S seconds; spikes
// add brightness, so a crowded pixel row (many channels) shows where the activity is.
// Skin map: each place's spike rate above its sensors' own baselines (a z-score computed by
// the server, skinhil/view/rate_map.py), top view; its overlay canvas carries what is drawn
// over the skin (the picked PSP sensors; the contact footprint goes there too).
// A page that connects late draws the server's history (the config's last seconds of
// updates) first, then the updates after it.
"use strict";

const WINDOW_S = 10;          // board seconds across the raster
const PSP_WINDOW_S = 5;       // board seconds across the PSP traces
const MAP_Z_FLOOR = 3;        // the map is black up to this z (the noise)
const MAP_Z_TOP = 12;         // the map's colour scale reaches at least this z
const LABEL_ROWS = 3;         // rows of onset labels at the raster's top (then thinned)
const MAX_DECISIONS = 12;     // rows of the decision table
const ONSET = "#3cf", TRUTH_ONSET = "#7e7", END_MARK = "#567";
const ANSWERS = [
  ["sent", "DECISIONs sent"], ["acked", "ACKed"], ["nacked", "NACKed"], ["unsent", "not sent"],
];
const COUNTERS = [
  ["events decoded", (m) => m.link.events_decoded],
  ["frames ok", (m) => m.link.frames_ok],
  ["CRC errors", (m) => m.link.crc_errors],
  ["sequence gaps", (m) => m.link.seq_gaps],
  ["frames lost", (m) => m.link.frames_lost],
  ["lost on the link", (m) => m.link.lost_on_link],
  ["late events (receiver)", (m) => m.link.late_events],
  ["board generated", (m) => m.board && m.board.events_generated],
  ["board sent", (m) => m.board && m.board.events_sent],
  ["board dropped", (m) => m.board && m.board.events_dropped],
  ["  FIFO full", (m) => m.board && m.board.dropped_fifo_full],
  ["  stopped", (m) => m.board && m.board.dropped_stopped],
  ["  link down", (m) => m.board && m.board.dropped_link_down],
  ["  shutdown", (m) => m.board && m.board.dropped_shutdown],
  ["board late ticks", (m) => m.board && m.board.late_ticks],
  ["spikes not drawn", (m) => view.notDrawn],
];

const view = {
  config: null, nowUs: null, shiftRest: 0, updates: 0, spikesDrawn: 0, notDrawn: 0,
  decisions: [], psp: [], pspEnd: 0, lastLink: null, decisionsSeen: 0,
  markers: [], onsetsSeen: 0, onsetsDrawn: 0, run: {state: "waiting", reason: ""},
  ended: false, mapZ: null, mapMaxZ: 0, picked: [], grasp: null, lastSeq: 0,
  history: {updates: 0, spikes: 0, markers: 0}, labelsDrawn: 0, labelsThinned: 0,
};

function report(body) {
  try {
    fetch("/client", {method: "POST", body: JSON.stringify(body)}).catch(() => {});
  } catch (e) { /* nothing to report to */ }
}
window.addEventListener("error", (e) => report({kind: "error", message: String(e.message)}));
window.addEventListener("unhandledrejection",
  (e) => report({kind: "error", message: "unhandled rejection: " + String(e.reason)}));
const consoleError = console.error.bind(console);
console.error = (...args) => { report({kind: "error", message: args.join(" ")}); consoleError(...args); };

function bytes(b64) {
  const s = atob(b64);
  const out = new Uint8Array(s.length);
  for (let i = 0; i < s.length; i++) out[i] = s.charCodeAt(i);
  return out.buffer;
}

function name(id) {
  if (id === null || id === undefined) return "–";
  return (view.config && view.config.names[String(id)]) || String(id);
}

function traceColour(c, k) { return `hsl(${(c * 360) / Math.max(k, 1)}, 70%, 60%)`; }

const $ = (id) => document.getElementById(id);
const raster = $("raster"), rctx = raster.getContext("2d");
const marks = $("raster-marks"), mctx = marks.getContext("2d");
const psp = $("psp"), pctx = psp.getContext("2d");
const mapCanvas = $("map"), mapCtx = mapCanvas.getContext("2d");
const overlay = $("map-overlay"), octx = overlay.getContext("2d");

// -- layout: canvases as wide as their column --------------------------------------------
function fitWidths() {
  const w = Math.max(200, Math.floor($("left").clientWidth));
  for (const c of [raster, marks, $("raster-axis"), psp, $("psp-axis"), $("grasp"), $("grasp-axis")]) {
    c.width = w;
  }
}

// -- raster ------------------------------------------------------------------------------
function setupRaster(n) {
  fitWidths();
  const H = raster.height;
  view.rowPx = n <= H ? Math.max(1, Math.floor(H / n)) : 0;
  view.perRow = n <= H ? 1 : n / H;  // channels per pixel row
  // brightness a spike adds: a pixel row of one channel lights fully; a row of many
  // channels needs several spikes, so noise stays dim and a touched band stands out
  view.spikeGain = n <= H ? 255 : Math.max(24, Math.round(510 / view.perRow));
  rctx.fillStyle = "#000";
  rctx.fillRect(0, 0, raster.width, H);
  $("raster-info").textContent = `${n} channels on y (address 0 at the top), ` +
    `${WINDOW_S} s of board time on x; onsets in blue`;
}

function channelRow(a) {
  const n = view.config.n_channels, H = raster.height;
  return view.rowPx ? [a * view.rowPx, view.rowPx] : [Math.floor(a * H / n), 1];
}

function drawRaster(m) {
  const W = raster.width, H = raster.height;
  const now = m.t_board_us;
  if (view.nowUs === null) view.nowUs = now;
  const dx = (now - view.nowUs) / (WINDOW_S * 1e6) * W + view.shiftRest;
  const shift = Math.floor(dx);
  view.shiftRest = dx - shift;
  view.nowUs = now;
  if (shift > 0) {
    rctx.drawImage(raster, -shift, 0);
    rctx.fillStyle = "#000";
    rctx.fillRect(W - shift, 0, shift, H);
  }
  const s = m.spikes;
  if (s.n > 0) {
    const t = new Uint32Array(bytes(s.t));
    const a = new Uint16Array(bytes(s.addr));
    const img = rctx.getImageData(0, 0, W, H);
    const px = img.data;
    const scale = W / (WINDOW_S * 1e6), gain = view.spikeGain;
    for (let i = 0; i < s.n; i++) {
      const x = Math.floor(W - 1 - (now - (s.t0_us + t[i])) * scale);
      if (x < 0 || x >= W) continue;
      const [y0, h] = channelRow(a[i]);
      for (let y = y0; y < y0 + h && y < H; y++) {
        const k = (y * W + x) * 4;
        const v = Math.min(255, px[k] + gain);
        px[k] = v; px[k + 1] = Math.round(v * 0.9); px[k + 2] = Math.round(v * 0.47);
        px[k + 3] = 255;
      }
    }
    rctx.putImageData(img, 0, 0);
    view.spikesDrawn += s.n;
  }
  view.notDrawn += s.not_drawn;
}

// x (px) of board time t_us on a plot whose right edge is end_us and that spans window_s
function timeX(t_us, end_us, window_s, W) { return W - 1 - (end_us - t_us) / (window_s * 1e6) * W; }

// the markers to draw: the stream's, and the operator's truth where the stream has none
// at that time (the same onset told twice is drawn once)
function shownMarkers() {
  const stream = view.markers.filter((mk) => mk.source !== "truth");
  return view.markers.filter((mk) => mk.source !== "truth" || !stream.some(
    (s) => s.phase.startsWith("onset") === mk.phase.startsWith("onset") &&
           Math.abs(s.t_us - mk.t_us) <= 1000));
}

function markLabel(mk) { return mk.label || name(mk.stimulus_id); }

function drawMarks() {
  const W = marks.width, H = marks.height, now = view.nowUs;
  mctx.clearRect(0, 0, W, H);
  mctx.font = "11px sans-serif";
  let drawn = 0, labels = 0, thinned = 0;
  const rowEnd = new Array(LABEL_ROWS).fill(-Infinity);  // right end (px) of each row's last label
  const shown = shownMarkers().sort((a, b) => a.t_us - b.t_us), boxes = [];
  for (const mk of shown) {
    const x = Math.round(timeX(mk.t_us, now, WINDOW_S, W));
    if (x < 0 || x >= W) continue;
    const onset = mk.phase.startsWith("onset");
    mctx.fillStyle = onset ? (mk.source === "truth" ? TRUTH_ONSET : ONSET) : END_MARK;
    mctx.fillRect(x, 0, onset ? 2 : 1, H);
    if (!onset) continue;
    drawn += 1;
    // a label goes in the first row where it clears the label before it; none: left out
    const text = markLabel(mk), w = mctx.measureText(text).width;
    const lx = Math.max(30, Math.min(x + 3, W - w - 2));  // clear of the channel ticks
    const row = rowEnd.findIndex((end) => lx > end + 4);
    if (row < 0) { thinned += 1; continue; }
    rowEnd[row] = lx + w;
    const y = 11 + 12 * row;
    mctx.fillStyle = "rgba(0, 0, 0, 0.65)";
    mctx.fillRect(lx - 1, y - 10, w + 2, 12);
    mctx.fillStyle = mk.source === "truth" ? TRUTH_ONSET : ONSET;
    mctx.fillText(text, lx, y);
    boxes.push([lx, y - 10, w, 12]);
    labels += 1;
  }
  view.onsetsDrawn = drawn;
  view.labelsDrawn = labels;
  view.labelsThinned = thinned;
  view.labelBoxes = boxes;  // [x, y, w, h] of each label drawn (px)
  // channel ticks on the left edge
  const n = view.config.n_channels;
  mctx.fillStyle = "#8a8a8a";
  for (let k = 0; k <= 4; k++) {
    const a = Math.min(n - 1, Math.round((k * (n - 1)) / 4));
    const [y] = channelRow(a);
    mctx.fillRect(0, Math.min(y, H - 1), 5, 1);
    mctx.fillText(String(a), 7, Math.min(Math.max(y + 4, 10), H - 2));
  }
}

function drawTimeAxis(canvas, end_us, window_s, step_s) {
  const ctx = canvas.getContext("2d"), W = canvas.width, H = canvas.height;
  ctx.clearRect(0, 0, W, H);
  ctx.fillStyle = "#999";
  ctx.font = "11px sans-serif";
  const end = end_us * 1e-6, start = end - window_s;
  for (let t = Math.ceil(start / step_s) * step_s; t <= end + 1e-9; t += step_s) {
    const x = Math.round(timeX(t * 1e6, end_us, window_s, W));
    const major = Math.abs(t / (2 * step_s) - Math.round(t / (2 * step_s))) < 1e-6;
    ctx.fillRect(x, 0, 1, major ? 6 : 3);
    if (major && t >= 0 && x > 14 && x < W - 24) ctx.fillText(`${t.toFixed(step_s < 1 ? 1 : 0)} s`, x - 12, 16);
  }
}

// -- PSP ---------------------------------------------------------------------------------
function addPsp(m) {
  const p = m.psp, k = view.config.psp_sensors.length;
  if (p.n === 0) return;
  const v = new Float32Array(bytes(p.values));
  for (let i = 0; i < p.n; i++) view.psp.push(v.subarray(i * k, (i + 1) * k));
  view.pspEnd = p.first + p.n;
  const keep = Math.round(PSP_WINDOW_S * view.config.psp_rate_hz);
  if (view.psp.length > keep) view.psp.splice(0, view.psp.length - keep);
}

function pspEndUs() { return view.pspEnd * 1e6 / view.config.psp_rate_hz; }

function drawPsp() {
  const W = psp.width, H = psp.height, k = view.config.psp_sensors.length;
  const keep = Math.round(PSP_WINDOW_S * view.config.psp_rate_hz);
  pctx.fillStyle = "#000";
  pctx.fillRect(0, 0, W, H);
  const endUs = pspEndUs();
  for (const mk of shownMarkers()) {  // onsets under the traces
    const x = Math.round(timeX(mk.t_us, endUs, PSP_WINDOW_S, W));
    if (x < 0 || x >= W) continue;
    const onset = mk.phase.startsWith("onset");
    pctx.fillStyle = onset ? (mk.source === "truth" ? TRUTH_ONSET : ONSET) : END_MARK;
    pctx.fillRect(x, 0, onset ? 2 : 1, H);
  }
  const lane = H / k;
  let top = 1;
  for (const row of view.psp) for (const x of row) if (x > top) top = x;
  pctx.font = "11px sans-serif";
  for (let c = 0; c < k; c++) {
    const base = (c + 1) * lane - 2;
    pctx.strokeStyle = traceColour(c, k);
    pctx.beginPath();
    const off = keep - view.psp.length;
    view.psp.forEach((row, i) => {
      const x = ((off + i) / keep) * W, y = base - (row[c] / top) * (lane - 4);
      if (i === 0) pctx.moveTo(x, y); else pctx.lineTo(x, y);
    });
    pctx.stroke();
    pctx.fillStyle = traceColour(c, k);
    pctx.fillText(view.config.psp_labels[c], 4, base - lane + 13);
  }
}

function pick(address) {
  const list = view.picked.filter((a) => a !== address);
  if (list.length === view.picked.length) list.push(address);
  while (list.length > Math.min(8, view.config.max_traces)) list.shift();
  if (list.length === 0) return;
  view.picked = list;
  fetch("/psp", {method: "POST", body: JSON.stringify({board: view.config.board, sensors: list})})
    .catch(() => {});
}

// -- grasp (the held object's truth, from the board: demo --task grasp) -------------------
// view.grasp holds the points of the last GRASP_WINDOW_S board seconds as columns, and each
// lift's outcome; points come once in the config (history) and then in each update.
const GRASP_WINDOW_S = 10;
const GRASP_LINES = [["grip_n", "#fc6", "grip (held)"], ["normal_n", "#6d6", "normal force"],
                     ["load_n", "#9cf", "load"]];
const SLIP_MM = "#e8e", GRASP_KEYS = ["t_us", "lift", "slip", "grip_n", "normal_n", "load_n", "slip_mm"];

function enableGrasp() {
  if (view.grasp) return;
  view.grasp = {outcomes: [], points: 0};
  for (const k of GRASP_KEYS) view.grasp[k] = [];
  // room for the panel in a laptop's window: shorter raster and PSP canvases
  raster.height = marks.height = 180;
  psp.height = 150;
  $("grasp-panel").hidden = false;
  if (view.rowPx !== undefined) setupRaster(view.config.n_channels);  // drawn before: again
}

function addGrasp(g) {
  const v = view.grasp, last = v.t_us.length ? v.t_us[v.t_us.length - 1] : -Infinity;
  for (let i = 0; i < g.t_us.length; i++) {
    if (g.t_us[i] <= last) continue;  // the config's history and the first update overlap
    for (const k of GRASP_KEYS) v[k].push(g[k][i]);
    v.points += 1;
  }
  for (const mk of g.outcomes) if (!v.outcomes.some((o) => o.lift === mk.lift)) v.outcomes.push(mk);
  if (!v.t_us.length) return;
  const horizon = v.t_us[v.t_us.length - 1] - GRASP_WINDOW_S * 1e6;
  let cut = 0;
  while (cut < v.t_us.length && v.t_us[cut] < horizon) cut++;
  if (cut) for (const k of GRASP_KEYS) v[k].splice(0, cut);
}

function drawGrasp() {
  const c = $("grasp"), ctx = c.getContext("2d"), W = c.width, H = c.height, v = view.grasp;
  ctx.fillStyle = "#000";
  ctx.fillRect(0, 0, W, H);
  if (!v.t_us.length) return;
  const end = v.t_us[v.t_us.length - 1], n = v.t_us.length, top = 14, bottom = H - 4;
  const x = (t) => timeX(t, end, GRASP_WINDOW_S, W);
  for (let i = 0; i < n; i++) {  // slip state under the lines
    if (v.slip[i] < 2) continue;
    const x0 = x(i ? v.t_us[i - 1] : v.t_us[i] - 1e4);
    ctx.fillStyle = v.slip[i] >= 3 ? "rgba(255, 70, 70, 0.45)" : "rgba(230, 200, 60, 0.30)";
    ctx.fillRect(Math.floor(x0), top, Math.max(1, Math.ceil(x(v.t_us[i]) - x0)), bottom - top);
  }
  let fmax = 1, dmax = 1;
  for (const [k] of GRASP_LINES) for (const f of v[k]) fmax = Math.max(fmax, f);
  for (const d of v.slip_mm) dmax = Math.max(dmax, d);
  const line = (k, colour, scale) => {  // a null point (grip with no object held) ends it
    ctx.strokeStyle = colour;
    ctx.beginPath();
    let drawing = false;
    for (let i = 0; i < n; i++) {
      if (v[k][i] === null) { drawing = false; continue; }
      const y = bottom - (v[k][i] / scale) * (bottom - top);
      if (!drawing || v.lift[i] !== v.lift[i - 1]) ctx.moveTo(x(v.t_us[i]), y);
      else ctx.lineTo(x(v.t_us[i]), y);
      drawing = true;
    }
    ctx.stroke();
  };
  ctx.lineWidth = 1.5;
  line("slip_mm", SLIP_MM, 1.1 * dmax);
  for (const [k, colour] of GRASP_LINES.slice().reverse()) line(k, colour, 1.1 * fmax);  // grip on top
  ctx.lineWidth = 1;
  ctx.font = "11px sans-serif";
  for (const mk of v.outcomes) {
    const xm = Math.round(x(mk.t_us));
    if (xm < 0 || xm >= W) continue;
    ctx.fillStyle = mk.held ? "#6d6" : "#f66";
    ctx.fillRect(xm, top, 2, bottom - top);
    ctx.fillText(`lift ${mk.lift} ${mk.held ? "held" : "DROPPED"}`, Math.max(2, Math.min(xm - 70, W - 90)), top + 12);
  }
  let lx = 4;
  for (const [, colour, label] of [...GRASP_LINES, ["", SLIP_MM, "slip distance"]]) {
    ctx.fillStyle = colour;
    ctx.fillText(label, lx, 11);
    lx += ctx.measureText(label).width + 12;
  }
  ctx.fillStyle = "#999";
  ctx.fillText(`${(1.1 * fmax).toFixed(2)} N, ${(1.1 * dmax).toFixed(2)} mm full scale`, lx + 8, 11);
  drawTimeAxis($("grasp-axis"), end, GRASP_WINDOW_S, 1);
}

// -- skin map ----------------------------------------------------------------------------
function setupMap() {
  const c = view.config, [rows, cols] = c.grid, [bh, bw] = c.map_shape;
  const side = 270;
  mapCanvas.width = overlay.width = side;
  mapCanvas.height = overlay.height = Math.max(40, Math.round(side * (rows - 1) / Math.max(cols - 1, 1)));
  Object.assign(view, {xy: new Float32Array(bytes(c.sensor_xy)), bw, bh,
                       mapImg: new ImageData(bw, bh)});
  view.mapTmp = document.createElement("canvas");
  view.mapTmp.width = bw; view.mapTmp.height = bh;
  $("map-info").textContent = `${rows}x${cols}, rate above baseline (z)`;
  $("map-info").title = "top view; each place's recent spike rate above its sensors' own " +
    "baselines, in standard deviations of the noise";
}

function hot(t) {  // black → red → yellow → white
  return [Math.min(1, 3 * t), Math.min(1, Math.max(0, 3 * t - 1)), Math.min(1, Math.max(0, 3 * t - 2))];
}

// the server's map: each place's z above its sensors' baselines, black up to MAP_Z_FLOOR
function updateMap(map) {
  const z = new Float32Array(bytes(map.z));
  let max = 0;
  for (const v of z) if (v > max) max = v;
  view.mapZ = z;
  view.mapMaxZ = max;
  const top = Math.max(MAP_Z_TOP, max), px = view.mapImg.data;
  for (let b = 0; b < z.length; b++) {
    const [r, g, bl] = hot(Math.max(0, z[b] - MAP_Z_FLOOR) / (top - MAP_Z_FLOOR));
    px[4 * b] = 255 * r; px[4 * b + 1] = 255 * g; px[4 * b + 2] = 255 * bl; px[4 * b + 3] = 255;
  }
  view.mapTmp.getContext("2d").putImageData(view.mapImg, 0, 0);
  mapCtx.imageSmoothingEnabled = false;
  mapCtx.drawImage(view.mapTmp, 0, 0, mapCanvas.width, mapCanvas.height);
  drawLegend(top, map.baseline_hz);
  drawOverlay();
}

function drawLegend(top, baselineHz) {
  const c = $("map-legend"), ctx = c.getContext("2d"), W = c.width;
  ctx.clearRect(0, 0, W, c.height);
  for (let x = 0; x < 120; x++) {
    const [r, g, b] = hot(x / 119);
    ctx.fillStyle = `rgb(${255 * r},${255 * g},${255 * b})`;
    ctx.fillRect(x, 2, 1, 10);
  }
  ctx.fillStyle = "#aaa";
  ctx.font = "11px sans-serif";
  ctx.fillText(`z ${MAP_Z_FLOOR}–${top.toFixed(0)}, baseline ${baselineHz.toFixed(1)} Hz`, 126, 11);
}

// map px ↔ grid units (column, row from the top-left mass)
function mapPx(col, row) {
  const [rows, cols] = view.config.grid;
  return [col / Math.max(cols - 1, 1) * mapCanvas.width, row / Math.max(rows - 1, 1) * mapCanvas.height];
}

function nearestSensor(col, row) {
  let best = 0, bestD = Infinity;
  for (let s = 0; s < view.config.n_channels; s++) {
    const d = (view.xy[2 * s] - col) ** 2 + (view.xy[2 * s + 1] - row) ** 2;
    if (d < bestD) { bestD = d; best = s; }
  }
  return best;
}

// What is drawn over the skin: the picked PSP sensors (the contact footprint joins here).
function drawOverlay() {
  octx.clearRect(0, 0, overlay.width, overlay.height);
  const k = view.config.psp_sensors.length;
  view.config.psp_sensors.forEach((a, c) => {
    const [x, y] = mapPx(view.xy[2 * a], view.xy[2 * a + 1]);
    octx.strokeStyle = traceColour(c, k);
    octx.lineWidth = 2;
    octx.beginPath();
    octx.arc(x, y, 5, 0, 2 * Math.PI);
    octx.stroke();
  });
}

// -- tables ------------------------------------------------------------------------------
function showDecisions(m) {
  for (const d of m.decisions) view.decisions.unshift(d);
  view.decisionsSeen += m.decisions.length;
  view.decisions.length = Math.min(view.decisions.length, MAX_DECISIONS);
  const body = document.querySelector("#decisions tbody");
  body.innerHTML = "";
  for (const d of view.decisions) {
    const cls = d.correct === true ? "ok" : d.correct === false ? "wrong" : "none";
    const mark = d.correct === true ? "✓" : d.correct === false ? "✗" : "no marker";
    const tr = document.createElement("tr");
    for (const text of [(d.t_us * 1e-6).toFixed(2), name(d.label), name(d.true_label), mark,
                        d.latency_ms === null ? "" : d.latency_ms.toFixed(0) + " ms"]) {
      const td = document.createElement("td");
      td.textContent = text;
      tr.appendChild(td);
    }
    tr.className = cls;
    body.appendChild(tr);
  }
  const s = m.score;
  $("accuracy").textContent = s.accuracy === null ? "" :
    `${(100 * s.accuracy).toFixed(1)} % of ${s.scored} (${s.misses} missed, ` +
    `${s.false_alarms} false alarms)`;
}

function showConfusion(s) {
  const t = $("confusion");
  t.innerHTML = "";
  const head = document.createElement("tr");
  head.appendChild(document.createElement("th"));
  for (const c of s.classes) {
    const th = document.createElement("th");
    th.className = "col";
    th.textContent = name(c);
    head.appendChild(th);
  }
  t.appendChild(head);
  s.confusion.forEach((row, i) => {
    const tr = document.createElement("tr");
    const th = document.createElement("th");
    th.className = "row";
    th.textContent = name(s.classes[i]);
    tr.appendChild(th);
    row.forEach((v, j) => {
      const td = document.createElement("td");
      td.textContent = v ? String(v) : "·";
      if (v) td.className = i === j ? "diag" : "off";
      tr.appendChild(td);
    });
    t.appendChild(tr);
  });
}

function showTable(id, rows) {
  const t = $(id);
  t.innerHTML = "";
  for (const [k, v] of rows) {
    const tr = document.createElement("tr");
    const a = document.createElement("td"), b = document.createElement("td");
    a.textContent = k;
    b.textContent = v === null || v === undefined ? "–" : String(v);
    tr.appendChild(a); tr.appendChild(b);
    t.appendChild(tr);
  }
}

// -- the run's state ---------------------------------------------------------------------
function showRun(run) {
  view.run = run;
  const st = $("status");
  if (run.state === "ended") {
    st.textContent = "run ended" + (run.reason ? ": " + run.reason : "");
    const banner = $("ended-banner");
    banner.textContent = "Run ended" + (run.reason ? " — " + run.reason : "");
    banner.hidden = false;
  } else {
    st.textContent = run.state + (run.reason ? ": " + run.reason : "");
  }
  st.className = run.state.replace(" ", "-") === "link-lost" ? "down" : run.state;
}

function endRun(run) {
  view.ended = true;
  source.close();
  showRun({state: "ended", reason: (run && run.reason) || "the stream closed"});
  reportState();
}

function reportState() {
  const m = view.lastMsg;
  report({kind: "state", updates: view.updates, spikes_drawn: view.spikesDrawn,
          decisions_shown: view.decisionsSeen, events_decoded: m ? m.link.events_decoded : 0,
          t_board_us: m ? m.t_board_us : 0, scored: m && m.score ? m.score.scored : 0,
          onsets_seen: view.onsetsSeen, run: view.run.state});
}

// what an update draws of the stream: its spikes, markers and PSP samples
function drawStream(m) {
  view.lastSeq = Math.max(view.lastSeq, m.seq);
  for (const mk of m.markers) {
    view.markers.push(mk);
    if (mk.phase.startsWith("onset")) view.onsetsSeen += 1;
  }
  drawRaster(m);
  const horizon = view.nowUs - WINDOW_S * 1e6;
  view.markers = view.markers.filter((mk) => mk.t_us >= horizon);
  drawMarks();
  drawTimeAxis($("raster-axis"), view.nowUs, WINDOW_S, 1);
  addPsp(m);
  drawPsp();
  drawTimeAxis($("psp-axis"), pspEndUs(), PSP_WINDOW_S, 0.5);
}

// a page that connects late: the server's last seconds, drawn as they came
function drawHistory(history) {
  for (const h of history) {
    drawStream(h);
    view.history.updates += 1;
    view.history.spikes += h.spikes.n;
    view.history.markers += h.markers.length;
  }
  if (history.length) $("clock").textContent = `board time ${(view.nowUs * 1e-6).toFixed(2)} s`;
}

function onUpdate(m) {
  view.updates += 1;
  view.lastMsg = m;
  if (m.psp_sensors) {
    view.config.psp_sensors = m.psp_sensors;
    view.config.psp_labels = m.psp_labels;
    view.picked = m.psp_sensors.slice();
    view.psp = [];
  }
  drawStream(m);
  updateMap(m.map);
  if (m.score) {  // a receiver with a decoder (the grasp demo's loop has none)
    showDecisions(m);
    showConfusion(m.score);
  }
  if (m.grasp) {
    enableGrasp();
    addGrasp(m.grasp);
    drawGrasp();
  }
  showTable("counters", COUNTERS.map(([k, f]) => [k, f(m)]));
  $("answers-panel").hidden = !m.answers;
  if (m.answers) showTable("answers", ANSWERS.map(([k, label]) => [label, m.answers[k]]));
  showRun(m.run);
  if (m.boards) showBoards(m.boards);
  for (const e of m.link_errors) $("status").textContent = "link error: " + e;
  $("clock").textContent = `board time ${(m.t_board_us * 1e-6).toFixed(2)} s`;
  view.lastLink = m.link;
  if (view.updates % 5 === 0) reportState();
}

// links to the other boards' pages where several send on the link
function showBoards(keys) {
  if (keys.join("\n") === view.boardsShown) return;
  view.boardsShown = keys.join("\n");
  const boards = $("boards");
  boards.innerHTML = "";
  if (keys.length < 2) return;
  boards.append("boards: ");
  for (const key of keys) {
    const a = document.createElement("a");
    a.href = "?board=" + encodeURIComponent(key);
    a.textContent = key;
    if (key === view.config.board) a.className = "on";
    boards.appendChild(a);
  }
}

function clickAt(canvas, e) {
  const r = canvas.getBoundingClientRect();
  return [(e.clientX - r.left) * canvas.width / r.width, (e.clientY - r.top) * canvas.height / r.height];
}

overlay.addEventListener("click", (e) => {
  if (!view.config) return;
  const [x, y] = clickAt(overlay, e), [rows, cols] = view.config.grid;
  pick(nearestSensor(x / overlay.width * (cols - 1), y / overlay.height * (rows - 1)));
});
marks.addEventListener("click", (e) => {
  if (!view.config) return;
  const [, y] = clickAt(marks, e), n = view.config.n_channels;
  pick(Math.min(n - 1, Math.floor(view.rowPx ? y / view.rowPx : y * n / marks.height)));
});

const board = new URLSearchParams(location.search).get("board");
const source = new EventSource("/events" + (board === null ? "" : "?board=" + encodeURIComponent(board)));
source.addEventListener("config", (e) => {
  view.config = JSON.parse(e.data);
  if (view.config.grasp) {
    enableGrasp();
    addGrasp(view.config.grasp);
  }
  Object.assign(view, {markers: [], psp: [], nowUs: null, shiftRest: 0, lastSeq: 0});  // (again
  // on a reconnection: the history redraws the window)
  setupRaster(view.config.n_channels);
  setupMap();
  updateMap(view.config.map);
  drawHistory(view.config.history);
  view.picked = view.config.psp_sensors.slice();
  view.decisions = view.config.recent_decisions.slice().reverse();
  showBoards(view.config.boards);
  showRun({state: "live", reason: ""});
  if (view.grasp) drawGrasp();
});
source.addEventListener("update", (e) => {
  if (!view.config || view.ended) return;
  const m = JSON.parse(e.data);
  if (m.seq > view.lastSeq) onUpdate(m);  // the history drew the ones before
});
source.addEventListener("end", (e) => endRun(JSON.parse(e.data)));
source.onerror = () => {
  if (view.ended) return;
  $("status").textContent = "stream lost (reconnecting…)";
  $("status").className = "down";
};
