// The page of `gonio serve`: polls the JSON endpoints and draws on canvases (no library,
// no network beyond this server). The control token comes from the URL's fragment
// (#token=…, never sent to a server) or the form, and is sent in the X-Gonio-Token header.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { run: null, token: null, version: -1, pointsVersion: "", single: false, points: null };

function readToken() {
  const hash = new URLSearchParams(location.hash.slice(1));
  const token = hash.get("token");
  if (token) {
    state.token = token;
    history.replaceState(null, "", location.pathname + location.search);
  }
}

function headers() {
  return state.token ? { "X-Gonio-Token": state.token } : {};
}

async function getJSON(url) {
  const r = await fetch(url, { headers: headers(), cache: "no-store" });
  const body = await r.json();
  if (!r.ok) throw new Error(body.error || r.statusText);
  return body;
}

function duration(s) {
  if (s === null || s === undefined || !isFinite(s)) return "–";
  s = Math.max(0, Math.round(s));
  const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), sec = s % 60;
  return h ? `${h} h ${m} min` : m ? `${m} min ${sec} s` : `${sec} s`;
}

function message(text, bad) {
  const el = $("message");
  el.textContent = text || "";
  el.className = bad ? "bad" : "";
}

// -- the runs of a folder ----------------------------------------------------------------
async function showRuns() {
  const body = await getJSON("/api/runs");
  if (body.single && body.runs.length === 1) {
    location.replace("/run/" + encodeURI(body.runs[0].name) + location.hash);
    return;
  }
  $("runs").hidden = false;
  const rows = body.runs.map((r) => {
    const tr = document.createElement("tr");
    tr.className = r.state;  // "unreadable": the plan's cell holds the one line why
    const cells = [r.name, r.state, r.plan || r.error || "", r.measured === undefined ? "" : `${r.measured} / ${r.targets}`,
      r.progress === undefined ? "" : `${(100 * r.progress).toFixed(1)} %`, duration(r.eta_s)];
    cells.forEach((c, i) => {
      const td = document.createElement("td");
      if (i === 0) {
        const a = document.createElement("a");
        a.href = "/run/" + encodeURI(r.name);
        a.textContent = c;
        td.appendChild(a);
      } else td.textContent = c;
      tr.appendChild(td);
    });
    return tr;
  });
  $("runs-body").replaceChildren(...rows);
  setTimeout(() => showRuns().catch((e) => message(e.message, true)), 2000);
}

// -- one run -----------------------------------------------------------------------------
async function poll() {
  try {
    const o = await getJSON("/api/overview?run=" + encodeURIComponent(state.run));
    showOverview(o);
    const wanted = `${o.version}:${o.derived}`;
    if (wanted !== state.pointsVersion) {
      const p = await getJSON("/api/points?run=" + encodeURIComponent(state.run));
      state.pointsVersion = wanted;
      state.points = p;
      drawHemisphere(p);
      drawInPlane(p);
      drawSlice(p);
    }
  } catch (e) {
    message(e.message, true);
  }
  setTimeout(poll, 1000);
}

function showOverview(o) {
  $("run-name").textContent = o.name;
  const st = $("state");
  st.textContent = o.state;
  st.className = "state " + o.state;
  st.dataset.state = o.state;
  $("count").textContent = o.measured;
  $("of").textContent = ` of ${o.targets}` + (o.fly ? " (fly)" : "");
  $("progress").value = o.progress;
  $("percent").textContent = `${(100 * o.progress).toFixed(1)} %`;
  $("itime").textContent = duration(o.instrument_time_s);
  $("predicted").textContent = `predicted for these: ${duration(o.predicted_done_s)}; the plan: ${duration(o.predicted_s)}`;
  $("rate").textContent = o.rate_per_s ? `${o.rate_per_s.toFixed(2)} samples/s` : "–";
  $("eta").textContent = duration(o.eta_s);
  $("skipped").textContent = o.skipped;
  $("resume-line").hidden = !o.resume;
  $("resume-command").textContent = o.resume || "";
  const live = o.state === "running" || o.state === "paused";
  $("control").hidden = !live;
  $("token-form").hidden = !live || !!state.token;
  $("pause").disabled = !state.token || o.state !== "running";
  $("resume").disabled = !state.token || o.state !== "paused";
  $("stop").disabled = !state.token;
  showEvents(o.events);
  drawHealth(o);
  drawDrift(o);
}

function showEvents(events) {
  const rows = events.slice().reverse().map((e) => {
    const tr = document.createElement("tr");
    tr.className = e.kind;
    const detail = Object.entries(e).filter(([k]) => !["id", "kind", "target", "t_s", "utc"].includes(k))
      .map(([k, v]) => `${k}: ${typeof v === "object" ? JSON.stringify(v) : v}`).join("; ");
    [e.utc.replace("T", " ").slice(0, 19), e.kind, e.target === null ? "" : e.target, detail].forEach((c) => {
      const td = document.createElement("td");
      td.textContent = c;
      tr.appendChild(td);
    });
    return tr;
  });
  $("events").replaceChildren(...rows);
}

async function send(action) {
  message("");
  try {
    const r = await fetch("/api/control?run=" + encodeURIComponent(state.run), {
      method: "POST",
      headers: { ...headers(), "Content-Type": "application/json" },
      body: JSON.stringify({ action }),
    });
    const body = await r.json();
    if (!r.ok) throw new Error(body.error || r.statusText);
    message(`${action} requested; it takes effect between targets`);
  } catch (e) {
    message(e.message, true);
  }
}

// -- drawing -----------------------------------------------------------------------------
function viridis(t) {
  const stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(Math.floor(t), stops.length - 2), f = t - i;
  const c = stops[i].map((v, k) => Math.round(v + f * (stops[i + 1][k] - v)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function logRange(values) {
  const logs = values.filter((v) => v !== null && v > 0).map(Math.log10).sort((a, b) => a - b);
  if (!logs.length) return [0, 1];
  const lo = logs[Math.floor(0.02 * (logs.length - 1))], hi = logs[Math.floor(0.98 * (logs.length - 1))];
  return hi > lo ? [lo, hi] : [lo - 0.5, lo + 0.5];
}

function drawHemisphere(p) {
  const c = $("hemisphere"), g = c.getContext("2d");
  const r = c.width / 2 - 14, cx = c.width / 2, cy = c.height / 2;
  g.clearRect(0, 0, c.width, c.height);
  g.strokeStyle = "#c5ccd3";
  for (const deg of [30, 60, 90]) {
    g.beginPath();
    g.arc(cx, cy, r * Math.sin((deg * Math.PI) / 180), 0, 2 * Math.PI);
    g.stroke();
  }
  g.beginPath(); g.moveTo(cx - r, cy); g.lineTo(cx + r, cy); g.stroke();
  g.fillStyle = "#b9bfc6";
  for (let k = 0; k < p.pending_xy.length; k += 2) {
    g.fillRect(cx + r * p.pending_xy[k] - 1, cy - r * p.pending_xy[k + 1] - 1, 2, 2);
  }
  const [lo, hi] = logRange(p.value);
  const size = p.shown > 5000 ? 2 : 4;
  const residual = $("colour").value === "residual" && p.residual !== null;
  for (let k = 0; k < p.value.length; k++) {
    const v = p.value[k];
    if (residual) {
      const e = p.residual[k];
      g.fillStyle = e === null ? "#b9bfc6" : diverging(e / 3);
    } else {
      g.fillStyle = v !== null && v > 0 ? viridis((Math.log10(v) - lo) / (hi - lo)) : "#e0523f";
    }
    g.fillRect(cx + r * p.xy[2 * k] - size / 2, cy - r * p.xy[2 * k + 1] - size / 2, size, size);
  }
  const fit = p.fit;
  $("unit").textContent = residual
    ? `residual (f − fit)/σ of ${fit.model}, blue −3 … red +3 (χ²/dof ${fit.chi2_red}, fitted at ${fit.measured} samples)`
    : `log₁₀ value (${p.unit}), ${lo.toFixed(2)}…${hi.toFixed(2)}`
      + (fit && fit.error ? `; fit: ${fit.error}` : fit === null || p.residual === null ? "; fit: not yet" : "");
  c.dataset.colour = residual ? "residual" : "value";
  $("shown").textContent = `${p.shown} of ${p.measured} samples shown; ${p.pending} targets to measure`;
  c.dataset.samples = String(p.measured);
}

function diverging(t) {
  t = Math.min(1, Math.max(-1, t));
  const a = [59, 76, 192], w = [235, 235, 235], b = [180, 4, 38];
  const [from, to, f] = t < 0 ? [w, a, -t] : [w, b, t];
  const c = from.map((v, k) => Math.round(v + f * (to[k] - v)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function drawSlice(p) {
  const c = $("slice"), g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  const s = p.slice;
  if (!s) {
    $("slice-caption").textContent = p.fit && p.fit.slice_error ? p.fit.slice_error : "not yet";
    c.dataset.filled = "0";
    return;
  }
  const [lo, hi] = logRange(s.f);
  const m = 30, w = (c.width - m - 4) / s.n, h = (c.height - m - 4) / s.n;
  let filled = 0;
  for (let j = 0; j < s.n; j++) {
    for (let i = 0; i < s.n; i++) {
      const v = s.f[j * s.n + i];
      g.fillStyle = v !== null && v > 0 ? viridis((Math.log10(v) - lo) / (hi - lo)) : "#e4e7ea";
      if (v !== null && v > 0) filled++;
      g.fillRect(m + i * w, c.height - m - (j + 1) * h, Math.ceil(w), Math.ceil(h));
    }
  }
  g.fillStyle = "#6b737b"; g.font = "11px system-ui";
  // angles (θ…, φ…) in degrees, the other coordinates as they are
  const show = (name, x) => /^(theta|phi)/.test(name) ? (x * 180 / Math.PI).toFixed(0) + "°" : x.toFixed(2);
  g.fillText(`${s.names[0]} ${show(s.names[0], s.x[0])} … ${show(s.names[0], s.x[1])}`, m, c.height - 10);
  g.save(); g.translate(12, c.height - m); g.rotate(-Math.PI / 2);
  g.fillText(`${s.names[1]} ${show(s.names[1], s.y[0])} … ${show(s.names[1], s.y[1])}`, 0, 0); g.restore();
  const fixed = Object.entries(s.fixed).map(([k, v]) => `${k} = ${show(k, v)}`).join(", ");
  $("slice-caption").textContent = `${fixed}; rbf from ${s.samples} samples at ${p.fit.measured}; log₁₀ f ${lo.toFixed(2)}…${hi.toFixed(2)}`;
  c.dataset.filled = String(filled);
}

function axes(g, c, xr, yr, xlabel, ylabel) {
  const m = { l: 44, r: 8, t: 8, b: 26 };
  const w = c.width - m.l - m.r, h = c.height - m.t - m.b;
  g.clearRect(0, 0, c.width, c.height);
  g.strokeStyle = "#c5ccd3"; g.fillStyle = "#6b737b"; g.font = "11px system-ui";
  g.strokeRect(m.l, m.t, w, h);
  g.fillText(xlabel, m.l + w / 2 - 20, c.height - 6);
  g.fillText(`${+yr[1].toPrecision(3)}`, 2, m.t + 10);
  g.fillText(`${+yr[0].toPrecision(3)}`, 2, m.t + h);
  g.fillText(`${+xr[0].toPrecision(3)}`, m.l, m.t + h + 12);
  g.fillText(`${+xr[1].toPrecision(3)}`, m.l + w - 24, m.t + h + 12);
  g.save(); g.translate(10, m.t + h / 2 + 20); g.rotate(-Math.PI / 2); g.fillText(ylabel, 0, 0); g.restore();
  const X = (x) => m.l + ((x - xr[0]) / (xr[1] - xr[0] || 1)) * w;
  const Y = (y) => m.t + h - ((y - yr[0]) / (yr[1] - yr[0] || 1)) * h;
  return [X, Y];
}

function drawInPlane(p) {
  const c = $("inplane"), g = c.getContext("2d");
  const q = p.in_plane, keep = [];
  for (let k = 0; k < q.value.length; k++) if (q.value[k] !== null && q.value[k] > 0) keep.push(k);
  const [lo, hi] = logRange(keep.map((k) => q.value[k]));
  const [X, Y] = axes(g, c, [-90, 90], [lo, hi], "signed θo (deg)", "log₁₀ value");
  for (const k of keep) {
    const v = q.value[k], s = q.sigma[k] || 0;
    const t = q.theta_i_deg[k] / 90;
    g.strokeStyle = g.fillStyle = viridis(t);
    const y0 = Math.log10(Math.max(v - s, v * 1e-3)), y1 = Math.log10(v + s);
    g.beginPath(); g.moveTo(X(q.theta_o_deg[k]), Y(y0)); g.lineTo(X(q.theta_o_deg[k]), Y(y1)); g.stroke();
    g.fillRect(X(q.theta_o_deg[k]) - 2, Y(Math.log10(v)) - 2, 4, 4);
  }
  c.dataset.points = String(keep.length);
}

function series(c, rows, key, limits, label) {
  const g = c.getContext("2d");
  const names = new Set();
  rows.forEach((r) => Object.keys(r[key] || {}).forEach((n) => names.add(n)));
  const ts = rows.map((r) => r.t_s);
  const vals = rows.flatMap((r) => Object.values(r[key] || {}));
  const all = vals.concat(limits);
  const xr = ts.length ? [Math.min(...ts), Math.max(...ts)] : [0, 1];
  if (xr[1] <= xr[0]) xr[1] = xr[0] + 1;  // one reading: a point, not a line
  const yr = all.length ? [Math.min(...all) - 1, Math.max(...all) + 1] : [0, 1];
  const [X, Y] = axes(g, c, xr, yr, "instrument time (s)", label);
  g.setLineDash([4, 4]); g.strokeStyle = "#e0523f";
  for (const l of limits) { g.beginPath(); g.moveTo(X(xr[0]), Y(l)); g.lineTo(X(xr[1]), Y(l)); g.stroke(); }
  g.setLineDash([]);
  [...names].forEach((n, i) => {
    g.strokeStyle = viridis(i / Math.max(names.size - 1, 1) * 0.85);
    g.fillStyle = g.strokeStyle;
    g.beginPath();
    rows.forEach((r, k) => { const v = (r[key] || {})[n]; if (v !== undefined) (k ? g.lineTo : g.moveTo).call(g, X(r.t_s), Y(v)); });
    g.stroke();
    rows.forEach((r) => { const v = (r[key] || {})[n]; if (v !== undefined) g.fillRect(X(r.t_s) - 2, Y(v) - 2, 4, 4); });
  });
}

function drawHealth(o) {
  const lim = o.health_limits;
  series($("temperature"), o.health, "temperatures_c", [lim.max_temperature_c], "°C");
  series($("voltage"), o.health, "voltages_v", [lim.min_voltage_v, lim.max_voltage_v], "V");
}

function drawDrift(o) {
  const rows = o.calibrations.map((c) => ({ t_s: c.t_s, d: { reference: 100 * (c.drift || 0) } }));
  series($("drift"), rows, "d", [], "%");
}

// -- start -------------------------------------------------------------------------------
function start() {
  readToken();
  $("pause").onclick = () => send("pause");
  $("resume").onclick = () => send("resume");
  $("stop").onclick = () => { if (confirm("Stop the run? It stays resumable.")) send("stop"); };
  $("colour").onchange = () => { if (state.points) drawHemisphere(state.points); };
  $("token-set").onclick = () => { state.token = $("token").value.trim() || null; $("token-form").hidden = true; };
  const m = location.pathname.match(/^\/run\/(.+)$/);
  if (m) {
    state.run = decodeURI(m[1]);
    $("run").hidden = false;
    poll();
  } else {
    showRuns().catch((e) => message(e.message, true));
  }
}

start();
