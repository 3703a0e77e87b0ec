// de-resonator dash: the page. It talks only to host-sim's dash server: the board's replies
// and the stream's records come as server-sent events (/api/events), requests go as the
// protocol's own lines (/api/command) and come back verbatim. It draws at most once an
// animation frame, over the chosen window of the records it holds.
"use strict";

// Okabe–Ito: told apart by colour-blind readers; dashes as the second cue.
const C = { blue: "#0072B2", orange: "#E69F00", green: "#009E73", red: "#D55E00",
  sky: "#56B4E9", purple: "#CC79A7", black: "#000000", grey: "#777777" };
const KEEP_SECONDS = 60;
// What a request that acts carries (the server refuses one without it: another site's page).
const ACT = { "X-Dash-Request": "1" };

// What the page knows; `window.dash` is read by the browser tests and the benchmark.
const dash = window.dash = {
  hello: null, tickHz: NaN, columns: {}, received: 0, gaps: 0, restarts: 0, lastSeq: null,
  redraws: 0, fps: 0, drawMs: 0, lastReplyMs: NaN, lastReply: "", status: null, connected: false,
  lastTick: null, tickBase: 0, board: { state: "up" }, control: { controls: true },
  lastRecordAt: 0, errors: [],
};

// The records held, a column each (time in s from the board's tick).
const cols = { t: [], volts: [], amp: [], cap: [], stretch: [], sensed: [], lo: [], hi: [],
  current: [], fhz: [], q: [], bias: [], phase: [], fault: [] };
// Which optional inputs the board has sent (a plot shows only once its data exists).
const seen = { current: false, track: false };
dash.cols = cols;
let dirty = false;
let paused = false;
let windowSeconds = 10;

const $ = (id) => document.getElementById(id);
const fmt = (x, digits = 4) => (x == null || !isFinite(x)) ? "—" : Number(x).toPrecision(digits);

// --- requests ---------------------------------------------------------------------------

async function send(line) {
  const t0 = performance.now();
  let text, ok = false;
  try {
    const r = await fetch("/api/command", { method: "POST", body: line, headers: ACT });
    const j = await r.json();
    ok = !!j.ok;
    text = j.reply !== undefined ? j.reply : "error: " + j.error;
  } catch (e) {
    text = "error: no answer from dash (" + e + ")";
  }
  dash.lastReplyMs = performance.now() - t0;
  dash.lastReply = text;
  const out = $("reply");
  out.textContent = "> " + line + "\n" + text;
  out.classList.toggle("err", !ok);
  return text;
}

// The controls that change the board: off while another connection controls it (STOP stays:
// any connection may stop the board).
const ACTING = ["target-send", "ac-send", "start", "trim", "clear", "set-send", "save"];

function bind() {
  // An emergency stop is always sent; if the board is out of reach, the page says what
  // that means.
  $("stop").onclick = async () => {
    const reply = await send("stop");
    if (!reply.startsWith("ok") && dash.board.state !== "up") {
      $("reply").textContent += "\nthe board is lost: dash cannot reach it to stop it (it goes " +
        "on as last told, or its own faults act). Check the board and its power.";
    }
  };
  $("start").onclick = () => send("start");
  $("trim").onclick = () => send("trim");
  $("clear").onclick = () => send("clear");
  $("faults-refresh").onclick = () => send("faults");
  $("target-form").onsubmit = (e) => { e.preventDefault(); send("target " + $("target-hz").value.trim()); };
  $("ac-form").onsubmit = (e) => {
    e.preventDefault();
    send("ac " + $("ac-volts").value.trim() + " " + $("ac-hz").value.trim());
  };
  $("set-form").onsubmit = (e) => {
    e.preventDefault();
    send("set " + $("setting").value + " " + $("setting-value").value.trim());
  };
  $("get-send").onclick = () => send("get " + $("setting").value);
  $("save").onclick = () => send("save");
  $("setting").onchange = showSetting;
  $("raw-form").onsubmit = (e) => { e.preventDefault(); send($("raw").value.trim()); };
  $("window").onchange = () => { windowSeconds = Number($("window").value); dirty = true; };
  $("pause").onchange = () => { paused = $("pause").checked; dirty = true; };
  $("record-start").onclick = () => record("start");
  $("record-stop").onclick = () => record("stop");
}

async function record(what) {
  try {
    const r = await fetch("/api/record/" + what, { method: "POST", headers: ACT });
    const j = await r.json();
    if (j.error) $("record-state").textContent = j.error;
  } catch (e) {
    $("record-state").textContent = "no answer from dash (" + e + ")";
  }
}

// --- events -----------------------------------------------------------------------------

function connect() {
  const events = new EventSource("/api/events");
  events.addEventListener("hello", (e) => hello(JSON.parse(e.data)));
  events.addEventListener("records", (e) => records(JSON.parse(e.data)));
  events.addEventListener("status", (e) => status(JSON.parse(e.data)));
  events.addEventListener("faults", (e) => faults(JSON.parse(e.data)));
  events.addEventListener("notice", (e) => notice(JSON.parse(e.data)));
  events.addEventListener("exchange", (e) => logEntry(JSON.parse(e.data)));
  events.addEventListener("settings", (e) => settingsValues(JSON.parse(e.data)));
  events.addEventListener("link", (e) => link(JSON.parse(e.data)));
  events.addEventListener("stream", (e) => streamSaid(JSON.parse(e.data)));
  events.addEventListener("recording", (e) => recordingSaid(JSON.parse(e.data)));
  events.addEventListener("board", (e) => boardLink(JSON.parse(e.data)));
  events.addEventListener("control", (e) => control(JSON.parse(e.data)));
  events.addEventListener("curve", (e) => curveSaid(JSON.parse(e.data)));
  events.onopen = () => { dash.connected = true; connView(); };
  events.onerror = () => {
    // Nothing the page holds of the board is known to hold any more.
    dash.connected = false;
    unknown("dash lost — state unknown");
    connView();
  };
}

// The bar when nothing is known of the board: never its last voltage.
function unknown(words) {
  dash.status = null;
  dash.last = null;
  dirty = true;
  $("curve-now").textContent = "";
  const out = $("output");
  out.className = "badge lost";
  out.textContent = words;
  $("phase").textContent = "";
  $("fault").textContent = "";
  $("fault").classList.remove("active");
}

// The connection to the board, as dash tells it: up, silent, or lost (dash reconnecting).
function boardLink(b) {
  dash.board = b;
  if (b.state === "lost") unknown("board lost — state unknown");
  if (b.state === "silent") unknown("board not answering — state unknown");
  connView();
}

// Who controls the board: this page's dash, or another connection (then only STOP acts).
function control(c) {
  dash.control = c;
  const el = $("control");
  el.hidden = c.controls;
  el.textContent = c.controls ? "" : "view only: " + (c.controller || "another connection") +
    " controls the board; this page takes over when it leaves. STOP still stops the board.";
  for (const id of ACTING) $(id).disabled = !c.controls;
}

// The bar's word on the link: dash, the board, the stream.
function connView() {
  const b = dash.board;
  let words;
  if (!dash.connected) {
    words = "dash not reachable (restarted? open the new URL it printed): the page cannot see " +
      "or stop the board";
  }
  else if (b.state === "lost") {
    words = "reconnecting to the board (attempt " + b.attempt + ", every " + b.retry_seconds +
      " s): " + b.why;
  } else if (b.state === "silent") words = "the board does not answer: " + b.why;
  else if (dash.hello && dash.hello.stream && performance.now() - dash.lastRecordAt > 2000) {
    words = "live; no records for " + fmt((performance.now() - dash.lastRecordAt) / 1000, 2) +
      " s (the stream: " + (dash.streamReply || "not asked") + ")";
  } else words = "live";
  $("conn").textContent = words;
}

function hello(h) {
  // A hello again (the events reconnected, perhaps to a new dash): a fresh start.
  dash.hello = h;
  dash.lastSeq = null; dash.lastTick = null; dash.tickBase = 0;
  clearColumns();
  dash.tickHz = h.tick_hz;
  h.columns.forEach((name, i) => { dash.columns[name] = i; });
  const crc = h.image_crc || "?";
  $("device").textContent = (h.firmware || "") + ", image " + crc;
  facts($("board"), [
    ["board", h.board], ["firmware", h.firmware], ["image CRC", crc], ["tick", h.tick_hz + " Hz"],
    ["stream", h.stream || "none (give dash --stream-…)"],
    ...Object.entries(h.device || {}).map(([k, v]) => [k, String(v)]),
  ]);
  const select = $("setting");
  select.innerHTML = "";
  for (const s of h.settings) {
    const o = document.createElement("option");
    o.value = s.key; o.textContent = s.key; o.dataset.help = s.help; o.dataset.value = s.value;
    select.appendChild(o);
  }
  showSetting();
  const ac = Object.fromEntries(h.settings.map((s) => [s.key, s.value]));
  if (ac.ac_volts !== undefined && !$("ac-volts").value) $("ac-volts").value = ac.ac_volts;
  if (ac.ac_hz !== undefined && !$("ac-hz").value) $("ac-hz").value = ac.ac_hz;
  showRange(h);
  $("log").tBodies[0].innerHTML = "";
  (h.log || []).forEach(logEntry);
  $("notices").innerHTML = "";
  (h.notices || []).forEach((line) => notice({ line }));
  dash.board = h.board_link || { state: "up" };
  if (h.status && h.status.fields) status(h.status);
  else unknown("output ?");
  boardLink(dash.board);
  control(h.control || { controls: true });
  if (h.faults && h.faults.summary) faults(h.faults);
  if (h.link) link(h.link);
  streamSaid({ reply: h.stream_reply });
  recordingSaid({ on: h.recording });
  makePlots();
}

// The tunable range: the board's own (`info`'s, its table's), narrowed by the curve's under
// the margin in force (a margin set above the image's narrows what the board takes).
function tunableRange(h) {
  const f = {};
  for (const w of String(h.info || "").split(" ")) {
    const [k, v] = w.split("=");
    if (v !== undefined) f[k] = Number(v);
  }
  const curve = h.curve ? h.curve.tunable_range_hz : null;
  if (!(isFinite(f.tunable_low_hz) && isFinite(f.tunable_high_hz))) return curve;
  const r = curve ? [Math.max(f.tunable_low_hz, curve[0]), Math.min(f.tunable_high_hz, curve[1])]
    : [f.tunable_low_hz, f.tunable_high_hz];
  r.board = true;
  return r;
}

function showRange(h) {
  const range = tunableRange(h);
  if (range) {
    $("range").textContent = "tunable range " + inward(range[0], 1) + " – " + inward(range[1], -1) +
      " Hz (" + (range.board ? "the board's table, as `info` says it, under the margin " :
        "the device's curve under the margin ") + (h.curve ? h.curve.margin : "?") + ")";
  } else {
    $("range").textContent = "no tuning curve: " + (h.curve_problem || "the board names no device");
  }
}

// A new margin: the curve's highest bias and the tunable range again.
function curveSaid(c) {
  dash.hello.curve = c.curve;
  dash.hello.curve_problem = c.curve_problem;
  showRange(dash.hello);
  if (plots && plots.curve) plots.curve.destroy();
  if (plots) plots.curve = curvePlot();
  dirty = true;
}

// A range's end rounded inward to 6 digits (up for the low end, down for the high): a target
// typed as shown is one the board takes.
function inward(x, up) {
  const p = Math.pow(10, 5 - Math.floor(Math.log10(Math.abs(x))));
  return String((up > 0 ? Math.ceil(x * p) : Math.floor(x * p)) / p);
}

function records(rows) {
  dash.lastRecordAt = performance.now();
  const k = dash.columns;
  const tickHz = dash.tickHz;
  for (const r of rows) {
    const seq = r[k.sequence];
    // The receiver's rule (stream.rs): a step forward of less than 2³¹ is records lost (the
    // u32 wraps); a step back is the board counting again from a reset.
    if (dash.lastSeq !== null) {
      const missing = (seq - dash.lastSeq - 1) >>> 0;
      if (missing < 2 ** 31) dash.gaps += missing;
      else { dash.restarts += 1; clearColumns(); dash.tickBase = 0; dash.lastTick = null; }
    }
    dash.lastSeq = seq;
    dash.received += 1;
    // The board's tick is a u32: past its wrap, time goes on.
    const tick = r[k.tick];
    if (dash.lastTick !== null && tick < dash.lastTick) dash.tickBase += 2 ** 32;
    dash.lastTick = tick;
    const t = (dash.tickBase + tick) / tickHz;
    cols.t.push(t);
    cols.volts.push(r[k.volts]);
    cols.amp.push(r[k.amplifier_volts]);
    cols.cap.push(r[k.max_volts]);
    cols.stretch.push(r[k.stretch]);
    const s = r[k.sensed_stretch], sd = r[k.sensed_sigma];
    cols.sensed.push(s);
    cols.lo.push(s == null || sd == null ? null : s - sd);
    cols.hi.push(s == null || sd == null ? null : s + sd);
    cols.current.push(r[k.current_amps]);
    seen.current = seen.current || r[k.current_amps] != null;
    seen.track = seen.track || r[k.natural_hz] != null;
    cols.fhz.push(r[k.natural_hz]);
    cols.q.push(r[k.quality_factor]);
    cols.bias.push(r[k.bias_volts]);
    cols.phase.push(r[k.phase]);
    cols.fault.push(r[k.fault]);
    dash.last = r;
  }
  // Older than the longest window: dropped in one piece now and then.
  const t = cols.t;
  if (t.length && t[0] < t[t.length - 1] - KEEP_SECONDS * 1.1) {
    const cut = lowerBound(t, t[t.length - 1] - KEEP_SECONDS);
    for (const c of Object.values(cols)) c.splice(0, cut);
  }
  dirty = true;
}

function clearColumns() { for (const c of Object.values(cols)) c.length = 0; }

function lowerBound(a, x) {
  let lo = 0, hi = a.length;
  while (lo < hi) { const m = (lo + hi) >> 1; if (a[m] < x) lo = m + 1; else hi = m; }
  return lo;
}

function status(s) {
  if (dash.board.state !== "up") return;
  dash.status = s;
  const f = s.fields || {};
  const out = $("output");
  const on = f.output === "on";
  out.className = "badge " + (f.output === undefined ? "unknown" : on ? "on" : "off");
  out.textContent = "output " + (f.output === undefined ? "?" : on ? "ON " + fmt(f.volts, 5) + " V" : "off 0 V");
  const cap = ", cap " + fmt(f.max_volts, 5) + " V (" + (f.max_by || "?") + ")";
  // At rest (off at 0 V, nothing planned): said so, not "holding … bias 0 V".
  const rest = !on && Number(f.volts) === 0 && Number(f.bias_volts) === 0 &&
    (f.phase === "holding" || f.phase === "ramping");
  $("phase").textContent = f.phase === "refused" ? "refused: the board runs nothing" : rest
    ? "at rest, 0 V: start or target switches the high voltage on" + cap
    : (f.phase || "?") + ", target " + fmt(f.target_hz, 4) + " Hz, bias " +
      fmt(f.bias_volts, 5) + " V" + cap;
  const fault = $("fault");
  const words = f.fault && f.fault !== "none" ? String(s.line).split(" fault=")[1] : "";
  fault.textContent = words ? "FAULT: " + words : "no fault";
  fault.classList.toggle("active", !!words);
  $("fault-words").textContent = words ? "latched: " + words + " (clear, then start)" : "";
  dirty = true;
}

// The fault log in words: how many, then each entry read back (`faults <n>`): when, what.
function faults(f) {
  const list = $("faults");
  list.innerHTML = "";
  const count = Number((String(f.summary).match(/^ok faults=(\d+)/) || [])[1]);
  const head = document.createElement("li");
  head.className = "head";
  head.textContent = !isFinite(count) ? f.summary : count === 0 ? "no fault logged"
    : count + (count === 1 ? " fault" : " faults") + " logged, the newest first" +
      (count > (f.entries || []).length ? " (" + f.entries.length + " shown)" : "");
  list.appendChild(head);
  for (const e of f.entries || []) {
    const li = document.createElement("li");
    const x = e.fields || {};
    const words = String(e.line).split(" words=")[1];
    li.textContent = x.sequence === undefined ? e.line
      : "#" + x.sequence + " at " + fmt(x.seconds, 6) + " s (tick " + x.tick + "), from " +
        fmt(x.volts, 5) + " V: " + (words || x.cause);
    li.title = e.line;
    list.appendChild(li);
  }
}

function notice(n) {
  const li = document.createElement("li");
  li.textContent = (n.at ? new Date(n.at).toLocaleTimeString() + " " : "") + n.line;
  const list = $("notices");
  list.prepend(li);
  while (list.children.length > 200) list.lastChild.remove();
}

function logEntry(e) {
  const body = $("log").tBodies[0];
  const tr = document.createElement("tr");
  tr.className = (e.ok ? "" : "err ") + (e.origin === "dash" ? "dash" : "");
  for (const text of [new Date(e.at).toLocaleTimeString(), e.origin, e.request, e.reply, fmt(e.ms, 2)]) {
    const td = document.createElement("td");
    td.textContent = text;
    tr.appendChild(td);
  }
  body.prepend(tr);
  while (body.rows.length > 200) body.deleteRow(body.rows.length - 1);
}

function settingsValues(values) {
  for (const o of $("setting").options) {
    if (values[o.value] !== undefined) o.dataset.value = values[o.value];
  }
  showSetting();
}

function showSetting() {
  const o = $("setting").selectedOptions[0];
  if (!o) return;
  $("setting-help").textContent = o.dataset.help + " — now " + o.dataset.value;
  $("setting-value").placeholder = o.dataset.value;
}

function link(l) {
  dash.link = l;
  facts($("link"), [
    ["records", l.records + " (at dash)"], ["lost", l.lost + " (board → dash)"],
    ["bad frames", String(l.bad_frames)], ["on this page", dash.received + ", " + dash.gaps + " gaps"],
    ["dropped", l.dropped_to_pages + " (dash → pages)"],
    ["redraw", fmt(dash.fps, 3) + " /s, " + fmt(dash.drawMs, 2) + " ms each"],
    ["last reply", isFinite(dash.lastReplyMs) ? fmt(dash.lastReplyMs, 3) + " ms" : "—"],
  ]);
}

function streamSaid(s) {
  dash.streamReply = s.reply;
  dash.lastRecordAt = performance.now();
  const note = !dash.hello || !dash.hello.stream
    ? "no telemetry stream: start dash with --stream-port, --stream-tcp or --stream-unix"
    : s.reply && !s.reply.startsWith("ok") ? "the board's stream: " + s.reply : "";
  $("plot-note").textContent = note;
}

function recordingSaid(r) {
  $("record-start").disabled = !!r.on;
  $("record-stop").disabled = !r.on;
  if (r.on) $("record-state").textContent = "recording…";
  else if (r.records !== undefined) {
    $("record-state").textContent = r.records + " records, " + r.lost + " lost, " + r.bad_frames +
      " bad frames";
    $("record-file").hidden = false;
  }
}

function facts(dl, pairs) {
  dl.innerHTML = "";
  for (const [k, v] of pairs) {
    const dt = document.createElement("dt"); dt.textContent = k;
    const dd = document.createElement("dd"); dd.textContent = v == null ? "—" : v;
    dl.append(dt, dd);
  }
}

// --- plots ------------------------------------------------------------------------------

let plots = null;

function width() { return Math.max(300, $("plots").clientWidth - 4); }

function line(label, colour, extra = {}) {
  return Object.assign({ label, stroke: colour, width: 1.5, spanGaps: false,
    value: (u, v) => fmt(v, 5) }, extra);
}

function timePlot(id, title, yLabel, series, extra = {}) {
  const opts = Object.assign({
    title, width: width(), height: 180,
    scales: { x: { time: false } },
    axes: [{ label: "time on the board, s" }, { label: yLabel, size: 70 }],
    series: [{ label: "t, s", value: (u, v) => fmt(v, 6) }, ...series],
    legend: { live: true },
  }, extra);
  const el = $(id);
  el.innerHTML = "";
  return new uPlot(opts, [[], ...series.map(() => [])], el);
}

function makePlots() {
  if (plots) for (const p of Object.values(plots)) if (p) p.destroy();
  const h = dash.hello;
  const limit = h.curve && h.curve.limit;
  plots = {
    volts: timePlot("plot-volts", "voltage", "V", [
      line("commanded", C.blue),
      line("measured (amplifier)", C.orange, { dash: [6, 3] }),
      line("cap in force", C.red, { dash: [2, 3] }),
      line("plan's bias", C.grey, { dash: [10, 4], width: 1 }),
      line(limit ? "limit (" + limit.mode + ", static)" : "limit", C.black, { dash: [12, 4, 2, 4], width: 1 }),
    ]),
    stretch: timePlot("plot-stretch", "stretch λ", "λ", [
      line("sensor", C.blue),
      line("λ from C", C.green, { dash: [6, 3] }),
      line("λ from C − σ", C.green, { width: 0.5 }),
      line("λ from C + σ", C.green, { width: 0.5 }),
      line("static limit", C.black, { dash: [12, 4, 2, 4], width: 1 }),
    ], { bands: [{ series: [4, 3], fill: "rgba(0,158,115,0.15)" }] }),
    current: timePlot("plot-current", "current", "A", [line("current", C.purple)]),
    track: timePlot("plot-track", "tracking: f and Q", "Hz", [
      line("f tracked", C.blue),
      line("Q", C.orange, { dash: [6, 3], scale: "q" }),
    ], { axes: [{ label: "time on the board, s" }, { label: "Hz", size: 70 },
      { label: "Q", scale: "q", side: 1, size: 60, grid: { show: false } }] }),
    curve: curvePlot(),
  };
  dirty = true;
}

// The flashed device's tuning curve: f against bias to the limit, the margin's highest bias,
// the tunable range; the operating point (the voltage commanded now) moving on it.
function curvePlot() {
  const el = $("plot-curve");
  el.innerHTML = "";
  const c = dash.hello.curve;
  if (!c) { el.textContent = "no tuning curve: " + (dash.hello.curve_problem || ""); return null; }
  const x = c.points.map((p) => p.bias_volts);
  const inside = c.points.map((p) => (p.beyond_margin ? null : p.natural_frequency_hz));
  // Dashed from the last point within the margin on, so the two parts join.
  const beyond = c.points.map((p, i) => {
    const next = c.points[i + 1];
    return p.beyond_margin || (next && next.beyond_margin) ? p.natural_frequency_hz : null;
  });
  dash.curve = { x, f: c.points.map((p) => p.natural_frequency_hz) };
  const opts = {
    title: "tuning curve (model, from the image's device): f against bias",
    width: width(), height: 240,
    scales: { x: { time: false } },
    axes: [{ label: "bias, V" }, { label: "natural frequency, Hz", size: 70 }],
    series: [
      { label: "bias, V", value: (u, v) => fmt(v, 5) },
      line("within the margin", C.blue, { width: 2 }),
      line("beyond the margin (refused)", C.blue, { dash: [3, 3] }),
    ],
    hooks: { draw: [(u) => curveMarks(u, c)] },
  };
  return new uPlot(opts, [x, inside, beyond], el);
}

// The margin's highest bias and the tunable range as labelled lines (drawn on the canvas).
function curveMarks(u, c) {
  const ctx = u.ctx;
  const left = u.bbox.left, top = u.bbox.top, w = u.bbox.width, hgt = u.bbox.height;
  ctx.save();
  ctx.font = 12 * devicePixelRatio + "px system-ui, sans-serif";
  ctx.lineWidth = devicePixelRatio;
  // Each line's label to its left, on a row of its own (two lines close together).
  const vline = (v, colour, dashes, label, row) => {
    const px = u.valToPos(v, "x", true);
    ctx.strokeStyle = colour; ctx.setLineDash(dashes);
    ctx.beginPath(); ctx.moveTo(px, top); ctx.lineTo(px, top + hgt); ctx.stroke();
    ctx.fillStyle = colour; ctx.setLineDash([]);
    ctx.textAlign = "right";
    ctx.fillText(label, px - 4 * devicePixelRatio, top + (14 + 16 * row) * devicePixelRatio);
  };
  const hline = (f, label) => {
    const py = u.valToPos(f, "y", true);
    ctx.strokeStyle = C.grey; ctx.setLineDash([4, 4]);
    ctx.beginPath(); ctx.moveTo(left, py); ctx.lineTo(left + w, py); ctx.stroke();
    ctx.fillStyle = C.grey; ctx.setLineDash([]); ctx.textAlign = "left";
    ctx.fillText(label, left + 4 * devicePixelRatio, py - 4 * devicePixelRatio);
  };
  vline(c.max_bias_volts, C.orange, [6, 4], "margin's highest bias " + fmt(c.max_bias_volts, 5) + " V", 2);
  if (c.limit) vline(c.limit.volts, C.black, [2, 3], c.limit.mode + " limit " + fmt(c.limit.volts, 5) + " V", 3);
  const [lo, hi] = c.tunable_range_hz;
  hline(lo, "tunable " + fmt(lo, 5) + " Hz");
  hline(hi, "tunable " + fmt(hi, 5) + " Hz");
  // The operating point: the voltage commanded now, on the curve, exactly where it is (its
  // words under the plot, where no line's label can cover them).
  const f = dash.now == null ? null : fAt(dash.now);
  if (f != null) {
    const px = u.valToPos(dash.now, "x", true), py = u.valToPos(f, "y", true);
    ctx.fillStyle = C.red; ctx.setLineDash([]);
    ctx.beginPath(); ctx.arc(px, py, 6 * devicePixelRatio, 0, 2 * Math.PI); ctx.fill();
  }
  $("curve-now").textContent = f == null ? "" : "● now " + fmt(dash.now, 5) + " V, " + fmt(f, 5) +
    " Hz on the model's curve";
  ctx.restore();
}

function fAt(volts) {
  const { x, f } = dash.curve;
  if (!(volts >= 0) || volts > x[x.length - 1]) return null;
  const i = Math.max(1, lowerBound(x, volts));
  const s = (volts - x[i - 1]) / (x[i] - x[i - 1] || 1);
  return f[i - 1] + s * (f[i] - f[i - 1]);
}

function draw() {
  const t0 = performance.now();
  const t = cols.t;
  const end = t.length ? t[t.length - 1] : 0;
  const from = lowerBound(t, end - windowSeconds);
  const s = (c) => c.slice(from);
  const limit = dash.hello.curve && dash.hello.curve.limit;
  const tt = s(t);
  const flat = (v) => tt.map(() => v);
  plots.volts.setData([tt, s(cols.volts), s(cols.amp), s(cols.cap), s(cols.bias),
    flat(limit ? limit.volts : null)]);
  plots.stretch.setData([tt, s(cols.stretch), s(cols.sensed), s(cols.lo), s(cols.hi),
    flat(limit ? limit.stretch : null)]);
  for (const [name, id, data] of [["current", "plot-current", [tt, s(cols.current)]],
    ["track", "plot-track", [tt, s(cols.fhz), s(cols.q)]]]) {
    $(id).hidden = !seen[name];
    if (seen[name]) plots[name].setData(data);
  }
  const missing = [!seen.current && "current (no current input)",
    !seen.track && "f and Q (no trim or tracking measured them)"].filter(Boolean);
  $("unmeasured").textContent = missing.length ? "not plotted, nothing received: " + missing.join(", ") : "";
  if (plots.curve && dash.curve) {
    // The operating point, drawn by the curve's hook at the voltage commanded now.
    dash.now = dash.last ? dash.last[dash.columns.volts] : dash.status && dash.status.fields.volts;
    plots.curve.redraw(false, false);
  }
  dash.drawMs = performance.now() - t0;
  dash.redraws += 1;
}

// At most one redraw an animation frame, and only when something changed.
let frames = [];
function frame(now) {
  if (dirty && !paused && plots) {
    dirty = false;
    draw();
    frames.push(now);
  }
  while (frames.length && frames[0] < now - 1000) frames.shift();
  dash.fps = frames.length;
  requestAnimationFrame(frame);
}

// The stream's silence is said as it grows (a stream another connection stopped, a cable).
setInterval(connView, 500);

window.addEventListener("error", (e) => dash.errors.push(String(e.message)));
window.addEventListener("resize", () => {
  if (plots) for (const p of Object.values(plots)) if (p) p.setSize({ width: width(), height: p.height });
});
// The token out of the address bar (and so of the history); the page's cookie keeps it.
if (location.search.includes("token=")) history.replaceState(null, "", location.pathname);
bind();
connect();
requestAnimationFrame(frame);
