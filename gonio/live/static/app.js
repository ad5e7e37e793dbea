// The page of `gonio serve`: polls the JSON endpoints and draws them with plots.js (Plotly.js
// served by this server; no network beyond it). The control token comes from the URL's
// fragment (#token=…, never sent to a server) or the form, and is sent in the
// X-Gonio-Token header.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { run: null, token: null, pointsVersion: "", points: null, overview: null, overlay: null,
  healthKey: "", requested: null };
const PANELS = ["hemisphere", "inplane", "fit", "slice", "temperature", "voltage", "drift"];

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
      drawSamples();
    }
  } catch (e) {
    message(e.message, true);
  }
  setTimeout(poll, 1000);
}

function drawSamples() {
  const p = state.points;
  if (!p) return;
  $("unit").textContent = drawHemisphere($("hemisphere"), p, $("colour").value, state.overlay);
  $("shown").textContent = `${p.shown} of ${p.measured} samples shown; ${p.pending} targets to measure.`;
  drawInPlane($("inplane"), p, $("scale").value, state.overlay);
  $("fit-caption").textContent = drawFit($("fit"), p, $("scale").value);
  $("slice-caption").textContent = drawSlice($("slice"), p);
}

function showOverview(o) {
  state.overview = o;
  $("run-name").textContent = o.name;
  $("plan").textContent = o.plan || "";
  $("rig").textContent = o.rig || "";
  $("scene").textContent = o.scene || (o.backend === "simulated" ? "" : o.backend || "");
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
  // A request's message stays until the next request, or until the run ends.
  if (state.requested && !live) {
    state.requested = null;
    message("");
  }
  showEvents(o.events);
  const key = `${o.health.length}:${o.calibrations.length}`;
  if (key !== state.healthKey) {  // redrawn when a reading lands, not every poll
    state.healthKey = key;
    drawHealth($("temperature"), $("voltage"), o);
    drawDrift($("drift"), o);
  }
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
    state.requested = action;
  } catch (e) {
    message(e.message, true);
  }
}

// -- overlays: another run of the folder, or a file's export ----------------------------
async function listOverlays() {
  try {
    const body = await getJSON("/api/runs");
    const chosen = $("overlay").value;
    const options = body.runs.filter((r) => r.name !== state.run && r.state !== "unreadable").map((r) => {
      const option = document.createElement("option");
      option.value = option.textContent = r.name;
      return option;
    });
    const none = document.createElement("option");
    none.value = "";
    none.textContent = "none";
    $("overlay").replaceChildren(none, ...options);
    $("overlay").value = options.some((o) => o.value === chosen) ? chosen : "";
  } catch (e) {
    message(e.message, true);
  }
  setTimeout(listOverlays, 10000);
}

async function chooseOverlay(name) {
  $("overlay-file").value = "";
  try {
    state.overlay = name ? overlayOfPoints(await getJSON("/api/points?run=" + encodeURIComponent(name))) : null;
    $("overlay-note").textContent = state.overlay ? `overlay: ${name}, open red rings and dotted curves` : "";
  } catch (e) {
    state.overlay = null;
    message(e.message, true);
  }
  drawSamples();
}

async function readOverlayFile(file) {
  if (!file) return;
  $("overlay").value = "";
  try {
    state.overlay = overlayOfCsv(file.name, await file.text());
    $("overlay-note").textContent = `overlay: ${file.name} (${state.overlay.value.length} samples), open red rings and dotted curves`;
  } catch (e) {
    state.overlay = null;
    message(e.message, true);
  }
  drawSamples();
}

// -- save any panel as PNG or SVG --------------------------------------------------------
function addSaveButtons() {
  for (const id of PANELS) {
    const box = document.createElement("span");
    box.className = "save";
    for (const format of ["png", "svg"]) {
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = format.toUpperCase();
      b.title = `save this panel as ${format.toUpperCase()}`;
      b.dataset.save = `${id}.${format}`;
      b.onclick = () => save($(id), format, `${(state.run || "run").replace(/[^\w.-]+/g, "_")}-${id}`);
      box.appendChild(b);
    }
    $(id).parentElement.appendChild(box);
  }
}

// -- start -------------------------------------------------------------------------------
function start() {
  readToken();
  $("pause").onclick = () => send("pause");
  $("resume").onclick = () => send("resume");
  $("stop").onclick = () => { if (confirm("Stop the run? It stays resumable.")) send("stop"); };
  $("colour").onchange = drawSamples;
  $("scale").onchange = drawSamples;
  $("overlay").onchange = () => chooseOverlay($("overlay").value);
  $("overlay-file").onchange = () => readOverlayFile($("overlay-file").files[0]);
  addSaveButtons();
  $("token-set").onclick = () => { state.token = $("token").value.trim() || null; $("token-form").hidden = true; };
  const m = location.pathname.match(/^\/run\/(.+)$/);
  if (m) {
    state.run = decodeURI(m[1]);
    $("run").hidden = false;
    poll();
    listOverlays();
  } else {
    showRuns().catch((e) => message(e.message, true));
  }
}

start();
