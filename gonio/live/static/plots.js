// The page's plots, drawn by Plotly.js (served by `gonio serve` from the installed plotly
// package; no network beyond this server). Each `draw…` takes the JSON of the endpoints
// (`/api/points`, `/api/overview`) and an overlay (`overlayOf…`: another run's samples or
// a file's export, the same fields in degrees) and redraws one panel with Plotly.react.
"use strict";

const CONFIG = { responsive: true, displaylogo: false, modeBarButtonsToRemove: ["select2d", "lasso2d"] };
const FONT = { family: "system-ui, sans-serif", size: 12, color: "#1d2125" };
const GRID = "#e4e7ea";
const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];

function viridis(t) {
  t = Math.min(1, Math.max(0, t)) * (VIRIDIS.length - 1);
  const i = Math.min(Math.floor(t), VIRIDIS.length - 2), f = t - i;
  const c = VIRIDIS[i].map((v, k) => Math.round(v + f * (VIRIDIS[i + 1][k] - v)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}

function logRange(values) {
  const logs = values.filter((v) => v !== null && v > 0).map(Math.log10).sort((a, b) => a - b);
  if (!logs.length) return [0, 1];
  const lo = logs[Math.floor(0.02 * (logs.length - 1))], hi = logs[Math.floor(0.98 * (logs.length - 1))];
  return hi > lo ? [lo, hi] : [lo - 0.5, lo + 0.5];
}

function base(extra) {
  return { font: FONT, paper_bgcolor: "#fff", plot_bgcolor: "#fff", margin: { l: 64, r: 24, t: 16, b: 48 },
    uirevision: "keep", showlegend: false, ...extra };
}

function axis(title, extra) {
  return { title: { text: title }, gridcolor: GRID, zeroline: false, automargin: true, ...extra };
}

function note(text) {  // a line in the middle of an empty panel
  return [{ text, showarrow: false, xref: "paper", yref: "paper", x: 0.5, y: 0.5, font: { color: "#6b737b" } }];
}

// -- the overlays: another run, or a file's export (csv) --------------------------------------
function overlayOfPoints(p) {
  return { name: p.name, unit: p.unit, theta_i: p.theta_i_deg, phi_i: p.phi_i_deg, theta_o: p.theta_o_deg,
    phi_o: p.phi_o_deg, value: p.value, sigma: p.sigma };
}

function overlayOfCsv(name, text) {
  const lines = text.split(/\r?\n/).filter((l) => l.length);
  const head = lines[0].split(",");
  const col = (key) => {
    const k = head.indexOf(key);
    if (k < 0) throw new Error(`${name}: no column ${key} (expected gonio export --format csv)`);
    return k;
  };
  const keys = ["theta_i_rad", "phi_i_rad", "theta_o_rad", "phi_o_rad", "brdf_per_sr", "sigma_per_sr"].map(col);
  const rows = lines.slice(1).map((l) => l.split(","));
  const num = (k, scale) => rows.map((r) => (r[k] === "" ? null : Number(r[k]) * scale));
  const deg = 180 / Math.PI;
  return { name, unit: "sr⁻¹", theta_i: num(keys[0], deg), phi_i: num(keys[1], deg), theta_o: num(keys[2], deg),
    phi_o: num(keys[3], deg), value: num(keys[4], 1), sigma: num(keys[5], 1) };
}

// φo turned so that ωi lies at 180° (the plane of incidence along 0°–180°), as the server does.
function turned(phiO, phiI) {
  return phiO.map((v, k) => (((v - phiI[k] + 180) % 360) + 360) % 360);
}

// The in-plane samples of an overlay (ωo within 5° of the plane of incidence), as the server picks them.
function inPlaneOf(o) {
  const phi = turned(o.phi_o, o.phi_i), out = { theta_o_deg: [], theta_i_deg: [], value: [], sigma: [] };
  phi.forEach((a, k) => {
    const off = Math.min(a, Math.abs(180 - a), 360 - a);
    if (off <= 5 || o.theta_o[k] < 1e-4) {
      out.theta_o_deg.push((a < 90 || a > 270 ? 1 : -1) * o.theta_o[k]);
      out.theta_i_deg.push(o.theta_i[k]);
      out.value.push(o.value[k]);
      out.sigma.push(o.sigma[k]);
    }
  });
  const whole = out.theta_i_deg.map(Math.round);
  const binned = new Set(whole).size > 8;  // as the server's incidence_groups
  out.group_deg = binned ? out.theta_i_deg.map((t) => Math.floor(t / 10) * 10 + 5) : whole;
  out.group_width_deg = binned ? 10 : 1;
  return out;
}

function groupName(g, width) {
  return width > 1 ? `θi ${g - width / 2}–${g + width / 2}°` : `θi ${g}°`;
}

// -- the hemisphere ---------------------------------------------------------------------------
function sectorOf(p, phi) {
  if (!p.isotropic || !phi.length) return [0, 360];
  if (phi.every((a) => a <= 180.5)) return [0, 180];
  if (phi.every((a) => a >= 179.5)) return [180, 360];
  return [0, 360];
}

const HOVER = "θi %{customdata[0]:.1f}°, φi %{customdata[1]:.1f}°<br>θo %{customdata[2]:.1f}°, φo %{customdata[3]:.1f}°"
  + "<br>f = %{customdata[4]:.4g} ± %{customdata[5]:.2g} UNIT<br>sample %{customdata[6]} (target %{customdata[7]}), t = %{customdata[8]:.1f} s";

function drawHemisphere(el, p, colour, overlay) {
  const residual = colour === "residual" && p.residual !== null;
  const [lo, hi] = logRange(p.value);
  const n = p.value.length;
  const custom = p.value.map((v, k) => [p.theta_i_deg[k], p.phi_i_deg[k], p.theta_o_deg[k], p.phi_o_deg[k], v,
    p.sigma[k], p.index[k], p.target[k], p.t_s[k], residual ? p.residual[k] : null]);
  const colours = residual ? p.residual : p.value.map((v) => (v !== null && v > 0 ? Math.log10(v) : null));
  const kind = n > 3000 ? "scatterpolargl" : "scatterpolar";
  const traces = [{
    type: kind, mode: "markers", name: "to measure", r: p.pending_theta_o_deg, theta: p.pending_phi_deg,
    marker: { color: "#c5ccd3", size: 3 }, hoverinfo: "skip",
  }, {
    type: kind, mode: "markers", name: p.name, r: p.theta_o_deg, theta: p.phi_deg, customdata: custom,
    hovertemplate: HOVER.replace("UNIT", p.unit) + (residual ? "<br>residual %{customdata[9]:.2f}σ" : "") + "<extra></extra>",
    marker: {
      color: colours, size: n > 5000 ? 4 : 7,
      colorscale: residual ? "RdBu" : "Viridis", reversescale: residual,
      cmin: residual ? -3 : lo, cmax: residual ? 3 : hi,
      colorbar: { title: { text: residual ? `(f − fit)/σ<br>${p.fit.model}` : `log₁₀ f<br>(${p.unit})`, side: "top" },
        thickness: 14, len: 0.8 },
    },
  }];
  if (overlay) {
    traces.push({
      type: kind, mode: "markers", name: overlay.name, r: overlay.theta_o, theta: turned(overlay.phi_o, overlay.phi_i),
      marker: { symbol: "circle-open", color: "#e0523f", size: 8, line: { width: 1.2 } },
      customdata: overlay.value.map((v, k) => [overlay.theta_i[k], overlay.phi_i[k], overlay.theta_o[k], overlay.phi_o[k], v, overlay.sigma[k]]),
      hovertemplate: `${overlay.name}<br>θi %{customdata[0]:.1f}°, φi %{customdata[1]:.1f}°<br>θo %{customdata[2]:.1f}°, φo %{customdata[3]:.1f}°`
        + `<br>f = %{customdata[4]:.4g} ± %{customdata[5]:.2g} ${overlay.unit}<extra></extra>`,
    });
  }
  const layout = base({
    margin: { l: 40, r: 40, t: 30, b: 30 },
    polar: {
      sector: sectorOf(p, p.phi_deg.concat(p.pending_phi_deg)),
      radialaxis: { range: [0, 90], tickvals: [0, 15, 30, 45, 60, 75, 90], ticktext: ["0°", "15°", "30°", "45°", "60°", "75°", "90°"], angle: 0, tickangle: 0,
        gridcolor: GRID },
      angularaxis: { dtick: 30, ticksuffix: "°", direction: "counterclockwise", rotation: 0, gridcolor: GRID },
    },
  });
  Plotly.react(el, traces, layout, CONFIG);
  el.dataset.colour = residual ? "residual" : "value";
  el.dataset.samples = String(p.measured);
  el.dataset.overlay = overlay ? overlay.name : "";
  return residual
    ? `colour: (f − f_fit)/σ of ${p.fit.model}, −3 … +3 (χ²/dof ${p.fit.chi2_red}, fitted at ${p.fit.measured} samples)`
    : `colour: log₁₀ f (${p.unit})` + (p.fit && p.fit.error ? `; fit: ${p.fit.error}` : p.residual === null ? "; fit: not yet" : "");
}

// -- the plane of incidence: a curve per θi, ±1σ ---------------------------------------------
function curves(q, opts) {
  const groups = new Map();
  q.group_deg.forEach((g, k) => {
    if (q.value[k] === null) return;
    if (!groups.has(g)) groups.set(g, []);
    groups.get(g).push(k);
  });
  return [...groups.keys()].sort((a, b) => a - b).map((g) => {
    const ks = groups.get(g).sort((a, b) => q.theta_o_deg[a] - q.theta_o_deg[b]);
    return {  // a band of θi (a plan whose θi vary continuously): its samples, not a line through them
      type: "scatter", mode: q.group_width_deg > 1 ? "markers" : opts.mode, name: groupName(g, q.group_width_deg) + opts.suffix, legendgroup: String(g),
      x: ks.map((k) => q.theta_o_deg[k]), y: ks.map((k) => q.value[k]),
      error_y: { type: "data", array: ks.map((k) => q.sigma[k] || 0), visible: true, thickness: 1 },
      line: { color: viridis(g / 90), dash: opts.dash, width: 1.5 },
      marker: { color: viridis(g / 90), size: 6, symbol: opts.symbol },
      hovertemplate: `${groupName(g, q.group_width_deg)}${opts.suffix}<br>θo %{x:.1f}°<br>f = %{y:.4g} ± %{error_y.array:.2g}<extra></extra>`,
    };
  });
}

function drawInPlane(el, p, scale, overlay) {
  const traces = curves(p.in_plane, { mode: "lines+markers", suffix: "", dash: "solid", symbol: "circle" });
  if (overlay) traces.push(...curves(inPlaneOf(overlay), { mode: "lines+markers", suffix: ` · ${overlay.name}`, dash: "dot", symbol: "circle-open" }));
  const layout = base({
    showlegend: true, legend: { font: { size: 11 } },
    xaxis: axis("signed θo (°)", { range: [-90, 90], dtick: 15, ticksuffix: "°" }),
    yaxis: axis(`f (${p.unit})`, { type: scale, exponentformat: "power" }),
    annotations: traces.length ? [] : note("no sample within 5° of the plane of incidence yet"),
  });
  Plotly.react(el, traces, layout, CONFIG);
  el.dataset.curves = String(traces.length);
}

// -- the fit: its curves in the plane of incidence over the in-plane samples -----------------
function drawFit(el, p, scale) {
  const traces = curves(p.in_plane, { mode: "markers", suffix: "", dash: "solid", symbol: "circle" });
  const width = p.in_plane.group_width_deg;
  for (const c of p.fit_curves) {
    traces.push({ type: "scatter", mode: "lines", name: `${p.fit.model}, ${groupName(c.theta_i_deg, width)}`,
      x: c.theta_o_deg, y: c.f, line: { color: viridis(c.theta_i_deg / 90), width: 2 },
      hovertemplate: `fit at ${groupName(c.theta_i_deg, width)}<br>θo %{x:.1f}°<br>f = %{y:.4g}<extra></extra>` });
  }
  const fit = p.fit;
  const why = !fit ? "not yet" : fit.error ? fit.error : !p.fit_curves.length ? "no in-plane sample yet" : null;
  Plotly.react(el, traces, base({
    showlegend: true, legend: { font: { size: 11 } },
    xaxis: axis("signed θo (°)", { range: [-90, 90], dtick: 15, ticksuffix: "°" }),
    yaxis: axis(`f (${p.unit})`, { type: scale, exponentformat: "power" }),
    annotations: why ? note(`fit: ${why}`) : [],
  }), CONFIG);
  el.dataset.fitted = fit && !fit.error ? String(fit.measured) : "";
  return fit && !fit.error
    ? `${fit.model} (lines) over the in-plane samples (points), χ²/dof ${fit.chi2_red}, fitted to ${fit.used} of ${fit.measured} samples`
    : `fit: ${why}`;
}

// -- the reconstruction's slice ---------------------------------------------------------------
const ANGLE = /^(theta|phi)/;
const SYMBOL = { theta: "θ", phi: "φ" };
function coordinate(name) {  // theta_h → θh (°), others as they are
  const m = name.match(/^(theta|phi)_?(.*)$/);
  return m ? `${SYMBOL[m[1]]}${m[2]} (°)` : name;
}

function drawSlice(el, p) {
  const s = p.slice;
  if (!s) {
    Plotly.react(el, [], base({ xaxis: { visible: false }, yaxis: { visible: false },
      annotations: note(p.fit && p.fit.slice_error ? p.fit.slice_error : "not yet") }), CONFIG);
    el.dataset.filled = "0";
    return p.fit && p.fit.slice_error ? p.fit.slice_error : "not yet";
  }
  const scale = (name) => (ANGLE.test(name) ? 180 / Math.PI : 1);
  const grid = (range, name) => Array.from({ length: s.n }, (_, i) => (range[0] + (i * (range[1] - range[0])) / (s.n - 1)) * scale(name));
  const z = [];
  let filled = 0;
  for (let j = 0; j < s.n; j++) {
    z.push(s.f.slice(j * s.n, (j + 1) * s.n).map((v) => {
      if (v !== null && v > 0) { filled++; return Math.log10(v); }
      return null;
    }));
  }
  const [lo, hi] = logRange(s.f);
  Plotly.react(el, [{
    type: "heatmap", x: grid(s.x, s.names[0]), y: grid(s.y, s.names[1]), z, zmin: lo, zmax: hi, colorscale: "Viridis",
    colorbar: { title: { text: `log₁₀ f<br>(${p.unit})`, side: "top" }, thickness: 14 },
    hovertemplate: `${s.names[0]} %{x:.1f}<br>${s.names[1]} %{y:.1f}<br>log₁₀ f %{z:.3f}<extra></extra>`,
  }], base({ xaxis: axis(coordinate(s.names[0])), yaxis: axis(coordinate(s.names[1])), plot_bgcolor: "#e4e7ea" }), CONFIG);
  el.dataset.filled = String(filled);
  const show = (k, v) => (ANGLE.test(k) ? `${(v * 180 / Math.PI).toFixed(0)}°` : v.toFixed(2));
  const fixed = Object.entries(s.fixed).map(([k, v]) => `${k} = ${show(k, v)}`).join(", ");
  return `${fixed}; rbf from ${s.samples} samples at ${p.fit.measured}; grey: outside the domain or unsupported`;
}

// -- health and drift over instrument time ----------------------------------------------------
function drawSeries(el, rows, key, limits, unit) {
  const names = new Set();
  rows.forEach((r) => Object.keys(r[key] || {}).forEach((n) => names.add(n)));
  const traces = [...names].map((n, i) => ({
    type: "scatter", mode: "lines+markers", name: n, x: rows.map((r) => r.t_s), y: rows.map((r) => (r[key] || {})[n] ?? null),
    line: { color: viridis((i / Math.max(names.size - 1, 1)) * 0.85) }, marker: { size: 4 },
    hovertemplate: `${n}: %{y:.3g} ${unit} at %{x:.0f} s<extra></extra>`,
  }));
  const shapes = limits.map((l) => ({ type: "line", xref: "paper", x0: 0, x1: 1, y0: l, y1: l, line: { color: "#e0523f", dash: "dash", width: 1 } }));
  Plotly.react(el, traces, base({
    showlegend: names.size > 1, shapes, margin: { l: 56, r: 16, t: 10, b: 40 },
    xaxis: axis("instrument time (s)"), yaxis: axis(unit),
    annotations: traces.length ? [] : note("no reading yet"),
  }), CONFIG);
}

function drawHealth(temperature, voltage, o) {
  const lim = o.health_limits;
  drawSeries(temperature, o.health, "temperatures_c", [lim.max_temperature_c], "°C");
  drawSeries(voltage, o.health, "voltages_v", [lim.min_voltage_v, lim.max_voltage_v], "V");
}

function drawDrift(el, o) {
  const rows = o.calibrations.map((c) => ({ t_s: c.t_s, d: { reference: 100 * (c.drift || 0) } }));
  drawSeries(el, rows, "d", [], "%");
}

// -- save a panel -----------------------------------------------------------------------------
function save(el, format, filename) {
  return Plotly.downloadImage(el, { format, filename, width: el.clientWidth, height: el.clientHeight, scale: format === "png" ? 2 : 1 });
}
