// skinhil live view: draws the updates of /events (server-sent events) on canvases.
// Raster: channels on y, board time scrolling right to left over WINDOW_S seconds.
"use strict";

const WINDOW_S = 10;          // board seconds across the raster
const PSP_WINDOW_S = 5;       // board seconds across the PSP traces
const MAX_DECISIONS = 18;     // rows of the decision table
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
  decisions: [], psp: [], pspFirst: -1, lastLink: null, decisionsSeen: 0,
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

const raster = document.getElementById("raster");
const rctx = raster.getContext("2d");
const psp = document.getElementById("psp");
const pctx = psp.getContext("2d");

function setupRaster(n) {
  const rowPx = Math.max(1, Math.floor(700 / n));
  raster.height = n <= 700 ? n * rowPx : 700;
  view.rowPx = rowPx;
  rctx.fillStyle = "#000";
  rctx.fillRect(0, 0, raster.width, raster.height);
  document.getElementById("raster-info").textContent =
    `${n} channels on y (address 0 at the top), ${WINDOW_S} s of board time on x`;
}

function drawRaster(m) {
  const W = raster.width, H = raster.height, n = view.config.n_channels;
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
    const scale = W / (WINDOW_S * 1e6);
    const h = n <= 700 ? view.rowPx : 1;
    for (let i = 0; i < s.n; i++) {
      const x = Math.floor(W - 1 - (now - (s.t0_us + t[i])) * scale);
      if (x < 0 || x >= W) continue;
      const y0 = n <= 700 ? a[i] * view.rowPx : Math.floor(a[i] * H / n);
      for (let y = y0; y < y0 + h && y < H; y++) {
        const k = (y * W + x) * 4;
        px[k] = 255; px[k + 1] = 230; px[k + 2] = 120; px[k + 3] = 255;
      }
    }
    rctx.putImageData(img, 0, 0);
    view.spikesDrawn += s.n;
  }
  view.notDrawn += s.not_drawn;
  document.getElementById("raster-left").textContent = ((now * 1e-6) - WINDOW_S).toFixed(1) + " s";
  document.getElementById("raster-right").textContent = (now * 1e-6).toFixed(1) + " s";
}

function addPsp(m) {
  const p = m.psp, k = view.config.psp_sensors.length;
  if (p.n === 0) return;
  const v = new Float32Array(bytes(p.values));
  for (let i = 0; i < p.n; i++) view.psp.push(v.subarray(i * k, (i + 1) * k));
  const keep = Math.round(PSP_WINDOW_S * view.config.psp_rate_hz);
  if (view.psp.length > keep) view.psp.splice(0, view.psp.length - keep);
}

function drawPsp() {
  const W = psp.width, H = psp.height, k = view.config.psp_sensors.length;
  const keep = Math.round(PSP_WINDOW_S * view.config.psp_rate_hz);
  pctx.fillStyle = "#000";
  pctx.fillRect(0, 0, W, H);
  const lane = H / k;
  let top = 1;
  for (const row of view.psp) for (const x of row) if (x > top) top = x;
  pctx.font = "11px sans-serif";
  for (let c = 0; c < k; c++) {
    const base = (c + 1) * lane - 3;
    pctx.strokeStyle = `hsl(${(c * 360) / k}, 70%, 60%)`;
    pctx.beginPath();
    const off = keep - view.psp.length;
    view.psp.forEach((row, i) => {
      const x = ((off + i) / keep) * W, y = base - (row[c] / top) * (lane - 6);
      if (i === 0) pctx.moveTo(x, y); else pctx.lineTo(x, y);
    });
    pctx.stroke();
    pctx.fillStyle = "#bbb";
    pctx.fillText(view.config.psp_labels[c], 4, base - lane + 16);
  }
}

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
  document.getElementById("accuracy").textContent = s.accuracy === null ? "" :
    `running ${(100 * s.accuracy).toFixed(1)} % of ${s.scored} (${s.misses} missed, ` +
    `${s.false_alarms} false alarms)`;
}

function showConfusion(s) {
  const t = document.getElementById("confusion");
  t.innerHTML = "";
  const head = document.createElement("tr");
  head.appendChild(document.createElement("th"));
  for (const c of s.classes) {
    const th = document.createElement("th");
    th.textContent = String(c);
    th.title = name(c);
    head.appendChild(th);
  }
  t.appendChild(head);
  s.confusion.forEach((row, i) => {
    const tr = document.createElement("tr");
    const th = document.createElement("th");
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
  const t = document.getElementById(id);
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

function onUpdate(m) {
  view.updates += 1;
  drawRaster(m);
  addPsp(m);
  drawPsp();
  showDecisions(m);
  showConfusion(m.score);
  showTable("counters", COUNTERS.map(([k, f]) => [k, f(m)]));
  document.getElementById("answers-panel").hidden = !m.answers;
  if (m.answers) showTable("answers", ANSWERS.map(([k, label]) => [label, m.answers[k]]));
  for (const e of m.link_errors) document.getElementById("status").textContent = "link error: " + e;
  document.getElementById("clock").textContent = `board time ${(m.t_board_us * 1e-6).toFixed(2)} s`;
  view.lastLink = m.link;
  if (view.updates % 5 === 0) {
    report({kind: "state", updates: view.updates, spikes_drawn: view.spikesDrawn,
            decisions_shown: view.decisionsSeen, events_decoded: m.link.events_decoded,
            t_board_us: m.t_board_us, scored: m.score.scored});
  }
}

const source = new EventSource("/events");
const status = document.getElementById("status");
source.addEventListener("config", (e) => {
  view.config = JSON.parse(e.data);
  setupRaster(view.config.n_channels);
  view.decisions = view.config.recent_decisions.slice().reverse();
  status.textContent = "live";
  status.className = "live";
});
source.addEventListener("update", (e) => { if (view.config) onUpdate(JSON.parse(e.data)); });
source.onerror = () => { status.textContent = "stream ended (reconnecting…)"; status.className = "down"; };
