// flexdigit live: the digit's shape, its gauges and the contact estimate, streamed from the rig loop.
// One WebSocket (/ws) brings a "hello" (the digit, what may be asked) then "frame"s at 25 Hz; the page sends
// requests (setpoint, load, clear, pause, speed) that the server validates, clamps and rate-limits.
// The digit is the hello's: its length scales the view, its sections' supports and its G gauges (1-8) are drawn,
// one gauge trace each with a legend; with two cables the slider runs below zero (bending the other way).
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);
  const HISTORY_S = 10;
  // one colour per gauge (up to 8): the first three are the thesis page's
  const COLORS = ["#2f6fb5", "#d1495b", "#2e8b57", "#e0a100", "#7b3fa0", "#17becf", "#8c564b", "#e377c2"];
  // mm, the shape canvas's window: the thesis's 270 mm digit in -15..300 x -90..90, scaled to the hello's digit
  const view = { x0: -15, x1: 300, y0: -90, y1: 90, grid: 50 };
  const stats = (window.flexdigit = {
    frames: 0, draws: 0, samples: 0, latenciesMs: [], drawTimes: [], errors: [], hello: null,
    last: null, connected: false, reconnects: 0, traces: 0,
  });
  let ws = null, hello = null, last = null, samples = [], dirty = false, paused = false, lastSend = 0;
  let pendingSetpoint = null, locMap = null, synced = false, pauseSent = 0;

  // ---------------------------------------------------------------------------------------------- connection
  function connect() {
    ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
    ws.onopen = () => { stats.connected = true; setConn(true); };
    ws.onclose = () => {
      if (stats.connected || !document.body.classList.contains("stale")) {
        // what is on the screen is no longer the digit: say so, and grey it out until the server is back
        $("status").textContent = "server unreachable: the view is frozen at its last update";
        $("rate").textContent = "";
        document.body.classList.add("stale");
      }
      dirty = false; // a frame that came just before the close must not redraw over the notice
      stats.connected = false;
      setConn(false);
      setTimeout(() => { stats.reconnects += 1; connect(); }, 500);
    };
    ws.onerror = () => {}; // onclose follows and reconnects
    ws.onmessage = (event) => {
      const msg = JSON.parse(event.data);
      if (msg.type === "hello") return onHello(msg);
      if (msg.type === "frame") return onFrame(msg);
      if (msg.type === "error") { $("error").textContent = msg.message; stats.errors.push(msg.message); }
      if (msg.type === "ack") $("error").textContent = "";
    };
  }
  function setConn(on) {
    $("conn").textContent = on ? "live" : "reconnecting";
    $("conn").className = "pill " + (on ? "on" : "off");
  }
  function send(obj) {
    if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(obj));
  }

  function onHello(msg) {
    hello = stats.hello = msg;
    samples = [];
    locMap = null;
    synced = false; // the controls take the server's state from its first frame
    document.body.classList.remove("stale");
    $("backend").textContent = msg.backend + " (" + msg.kind + ", " + msg.orientation +
      (msg.cable ? "" : ", cable detached") + (msg.cables === 2 ? ", two cables" : "") + "; " +
      msg.section_count + " section" + (msg.section_count === 1 ? "" : "s") + ", " +
      (msg.digit_length_m * 1e3).toFixed(0) + " mm, " + msg.gauges_m.length + " gauge" +
      (msg.gauges_m.length === 1 ? "" : "s") + ")";
    setView(msg.digit_length_m);
    gaugeLegend(msg.gauges_m);
    const slider = $("setpoint");
    slider.min = msg.setpoint_range[0];
    slider.max = msg.setpoint_range[1];
    slider.step = msg.setpoint_unit === "deg" ? 0.5 : 1;
    slider.disabled = !msg.can_command;
    $("sp-unit").textContent = msg.setpoint_unit === "deg" ? "deg (beam rotation)" : "(servo command)";
    const mass = $("mass");
    mass.innerHTML = "";
    for (const g of msg.loads_g) {
      const o = document.createElement("option");
      o.value = g; o.textContent = g + " g"; if (g === 25) o.selected = true;
      mass.appendChild(o);
    }
    $("mass-row").style.display = msg.can_load ? "" : "none";
    $("clear").style.display = msg.can_load ? "" : "none";
    $("legend-true").style.display = msg.kind === "twin" ? "" : "none";
    $("click-hint").textContent = msg.can_load ? "click the digit to hang the weight there" : "";
    const speeds = $("speeds");
    speeds.innerHTML = "";
    if (msg.speeds.length > 1) {
      for (const s of msg.speeds) {
        const b = document.createElement("button");
        b.type = "button"; b.textContent = s + "x"; b.dataset.speed = s;
        b.onclick = () => send({ type: "speed", speed: s });
        speeds.appendChild(b);
      }
    }
  }

  function setView(lengthM) { // the window keeps the thesis page's proportions to the digit's length
    const L = lengthM * 1e3, k = L / 270;
    view.x0 = -15 * k; view.x1 = 300 * k; view.y0 = -90 * k; view.y1 = 90 * k;
    view.grid = L <= 200 ? 25 : L <= 400 ? 50 : 100;
  }
  function gaugeLegend(gaugesM) { // one entry per gauge: its colour, its name and its place on the strip
    const legend = $("gauge-legend");
    legend.innerHTML = "";
    gaugesM.forEach((sm, i) => {
      const item = document.createElement("span");
      item.className = "gauge-key";
      const sw = document.createElement("i");
      sw.className = "sw"; sw.style.background = COLORS[i % COLORS.length];
      item.appendChild(sw);
      item.appendChild(document.createTextNode("gauge " + (i + 1) + " at " + (sm * 1e3).toFixed(0) + " mm"));
      legend.appendChild(item);
    });
  }

  function onFrame(msg) {
    stats.frames += 1;
    last = stats.last = msg;
    for (const s of msg.samples) samples.push(s);
    stats.samples += msg.samples.length;
    if (samples.length) {
      const tEnd = samples[samples.length - 1].t;
      let cut = 0;
      while (cut < samples.length && samples[cut].t < tEnd - HISTORY_S) cut++;
      if (cut > 0) samples = samples.slice(cut);
    }
    if (msg.locatability) locMap = stats.locMap = msg.locatability; // sent when it changes (with the command)
    if (msg.samples.length) dirty = true;
    syncControls(msg.state);
  }

  // the controls show the server's state, not this page's last gesture: after a reconnection, a server restart,
  // or another page's request (the slider only while it is not being moved, the pause button always)
  function syncControls(st) {
    const slider = $("setpoint");
    const idle = pendingSetpoint === null && document.activeElement !== slider &&
      performance.now() - lastSend > 1000;
    if ((!synced || idle) && st.setpoint !== null && st.setpoint !== undefined) {
      slider.value = st.setpoint;
      $("sp-value").textContent = Number(st.setpoint).toFixed(1);
    }
    if (!synced || (st.paused !== paused && performance.now() - pauseSent > 1000)) setPaused(st.paused);
    synced = true;
  }
  function setPaused(on) {
    paused = on;
    $("pause").textContent = paused ? "resume" : "pause";
    $("pause").classList.toggle("active", paused);
  }

  // ---------------------------------------------------------------------------------------------- controls
  $("setpoint").addEventListener("input", (e) => {
    pendingSetpoint = parseFloat(e.target.value);
    $("sp-value").textContent = pendingSetpoint.toFixed(1);
  });
  $("setpoint").addEventListener("change", (e) => { pendingSetpoint = parseFloat(e.target.value); });
  setInterval(() => { // at most 10 setpoints a second, the last one always
    if (pendingSetpoint !== null && performance.now() - lastSend > 100) {
      send({ type: "setpoint", value: pendingSetpoint });
      pendingSetpoint = null;
      lastSend = performance.now();
    }
  }, 50);
  $("clear").onclick = () => send({ type: "clear" });
  $("pause").onclick = () => {
    setPaused(!paused);
    pauseSent = performance.now();
    send({ type: "pause", paused: paused });
  };
  $("shape").addEventListener("click", (e) => {
    if (!hello || !hello.can_load || !last) return;
    const c = $("shape");
    const r = c.getBoundingClientRect();
    const px = (e.clientX - r.left) * (c.width / r.width), py = (e.clientY - r.top) * (c.height / r.height);
    const [x, y] = toWorld(c, px, py);
    const line = (last.truth && last.truth.length ? last.truth.map((p) => [p[0] * 1e3, p[1] * 1e3]) : null) ||
      (last.shape ? last.shape.centre_line_m.map((p) => [p[0] * 1e3, p[1] * 1e3]) : null);
    if (!line) return;
    const s = last.shape.s_m;
    let best = 0, bestD = Infinity;
    for (let i = 0; i < line.length; i++) {
      const d = Math.hypot(line[i][0] - x, line[i][1] - y);
      if (d < bestD) { bestD = d; best = i; }
    }
    if (bestD > 25) { $("error").textContent = "click on the digit"; return; }
    send({ type: "load", position_m: s[best], mass_g: parseFloat($("mass").value), kind: "weight" });
  });

  // ---------------------------------------------------------------------------------------------- drawing
  function scale(c) { return Math.min(c.width / (view.x1 - view.x0), c.height / (view.y1 - view.y0)); }
  function toPx(c, x, y) { const k = scale(c); return [(x - view.x0) * k, c.height - (y - view.y0) * k]; }
  function toWorld(c, px, py) { const k = scale(c); return [px / k + view.x0, (c.height - py) / k + view.y0]; }
  function polyline(ctx, c, pts) {
    ctx.beginPath();
    pts.forEach((p, i) => { const [x, y] = toPx(c, p[0], p[1]); if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y); });
  }
  function along(pts, s, sm) { // point on a polyline at arc position sm (m), pts in mm
    if (sm === null || sm === undefined) return null;
    let i = 0;
    while (i < s.length - 2 && s[i + 1] < sm) i++;
    const w = Math.min(Math.max((sm - s[i]) / (s[i + 1] - s[i]), 0), 1);
    return [pts[i][0] + w * (pts[i + 1][0] - pts[i][0]), pts[i][1] + w * (pts[i + 1][1] - pts[i][1])];
  }

  function fitView(lines) { // a digit that bends or sags past the window widens it (never narrows: no jitter)
    for (const line of lines) for (const p of line) {
      const margin = 0.08 * (view.x1 - view.x0);
      if (p[1] + margin > view.y1) view.y1 = p[1] + margin;
      if (p[1] - margin < view.y0) view.y0 = p[1] - margin;
      if (p[0] + margin > view.x1) view.x1 = p[0] + margin;
    }
  }

  function drawShape() {
    const c = $("shape"), ctx = c.getContext("2d");
    if (last && last.shape) {
      const toMm = (line) => line.map((p) => [p[0] * 1e3, p[1] * 1e3]);
      fitView([toMm(last.shape.centre_line_m)].concat(last.truth && last.truth.length ? [toMm(last.truth)] : []));
    }
    ctx.clearRect(0, 0, c.width, c.height);
    ctx.strokeStyle = "#e6eaee"; ctx.lineWidth = 1; ctx.fillStyle = "#8a97a5"; ctx.font = "11px system-ui";
    const step = view.grid;
    for (let x = 0; x <= view.x1; x += step) { polyline(ctx, c, [[x, view.y0], [x, view.y1]]); ctx.stroke(); }
    for (let y = step * Math.ceil(view.y0 / step); y <= view.y1; y += step) {
      polyline(ctx, c, [[view.x0, y], [view.x1, y]]); ctx.stroke();
    }
    for (let x = 0; x <= view.x1 - step / 2; x += step) {
      const [px, py] = toPx(c, x, view.y0); ctx.fillText(x + " mm", px + 2, py - 4);
    }
    const [cx0, cy0] = toPx(c, view.x0, 12), [cx1, cy1] = toPx(c, 0, -12);
    ctx.fillStyle = "#56616d"; ctx.fillRect(cx0, cy0, cx1 - cx0, cy1 - cy0); // the clamp
    if (!last || !last.shape) return;
    const sh = last.shape, s = sh.s_m;
    const pts = sh.centre_line_m.map((p) => [p[0] * 1e3, p[1] * 1e3]);
    // where the gauges cannot place a load (the page's threshold), shaded along the estimated line
    if (locMap && hello) {
      ctx.lineWidth = 16; ctx.strokeStyle = "rgba(150,158,168,0.35)"; ctx.lineCap = "butt";
      for (let i = 0; i < locMap.s_m.length; i++) {
        const sd = locMap.sd_m[i];
        if (sd !== null && sd <= hello.located_sd_m) continue;
        const a = along(pts, s, locMap.s_m[i] - 0.0025), b = along(pts, s, locMap.s_m[i] + 0.0025);
        polyline(ctx, c, [a, b]); ctx.stroke();
      }
    }
    // the estimate's band (two standard deviations normal to the line)
    const upper = [], lower = [];
    for (let i = 0; i < pts.length; i++) {
      const j = Math.min(i + 1, pts.length - 1), h = Math.max(i - 1, 0);
      const dx = pts[j][0] - pts[h][0], dy = pts[j][1] - pts[h][1], n = Math.hypot(dx, dy) || 1;
      const sd = Math.min(sh.sd_normal_m[i] === null ? 0.05 : sh.sd_normal_m[i], 0.05) * 2e3;
      upper.push([pts[i][0] - dy / n * sd, pts[i][1] + dx / n * sd]);
      lower.push([pts[i][0] + dy / n * sd, pts[i][1] - dx / n * sd]);
    }
    polyline(ctx, c, upper.concat(lower.reverse()));
    ctx.closePath(); ctx.fillStyle = "rgba(47,111,181,0.18)"; ctx.fill();
    ctx.lineWidth = 3; ctx.strokeStyle = "#2f6fb5"; ctx.lineCap = "round";
    polyline(ctx, c, pts); ctx.stroke();
    // supports and gauges
    ctx.fillStyle = "#56616d";
    for (const sm of hello ? hello.supports_m : []) {
      const p = along(pts, s, sm); const [px, py] = toPx(c, p[0], p[1]); ctx.fillRect(px - 4, py - 7, 8, 14);
    }
    ctx.fillStyle = "#111";
    (hello ? hello.gauges_m : []).forEach((sm, i) => {
      const p = along(pts, s, sm); const [px, py] = toPx(c, p[0], p[1]);
      ctx.beginPath(); ctx.arc(px, py, 4, 0, 2 * Math.PI); ctx.fill(); ctx.fillText("g" + (i + 1), px - 6, py + 18);
    });
    // the twin's true centre line and its hung load
    if (last.truth && last.truth.length) {
      const truth = last.truth.map((p) => [p[0] * 1e3, p[1] * 1e3]);
      ctx.setLineDash([6, 4]); ctx.lineWidth = 1.5; ctx.strokeStyle = "#111";
      polyline(ctx, c, truth); ctx.stroke(); ctx.setLineDash([]);
      for (const [mass, sm] of last.state.loads || []) {
        const p = along(truth, s, sm); const [px, py] = toPx(c, p[0], p[1]);
        ctx.fillStyle = "#c0392b"; ctx.beginPath();
        ctx.moveTo(px - 7, py + 10); ctx.lineTo(px + 7, py + 10); ctx.lineTo(px, py + 22); ctx.closePath(); ctx.fill();
        ctx.fillText((mass * 1e3).toFixed(1) + " g", px + 9, py + 22);
      }
    }
    // the contact estimate: its position and the interval consistent with the readings
    const ce = last.contact && last.contact[0];
    if (ce && ce.contact && ce.position_from_base_m !== null) {
      if (ce.position_interval_m && ce.position_interval_m[0] !== null) {
        const lo = ce.position_interval_m[0], hi = ce.position_interval_m[1], seg = [];
        for (let sm = lo; sm <= hi + 1e-9; sm += 0.002) seg.push(along(pts, s, Math.min(sm, hi)));
        if (seg.length > 1) {
          ctx.lineWidth = 10; ctx.strokeStyle = "rgba(224,112,26,0.35)"; polyline(ctx, c, seg); ctx.stroke();
        }
      }
      const p = along(pts, s, ce.position_from_base_m); const [px, py] = toPx(c, p[0], p[1]);
      ctx.fillStyle = "#e0701a"; ctx.beginPath(); ctx.arc(px, py, 7, 0, 2 * Math.PI); ctx.fill();
    }
  }

  function drawTraces(id, series, yLabel, inlineNames = true) {
    const c = $(id), ctx = c.getContext("2d");
    ctx.clearRect(0, 0, c.width, c.height);
    const left = 46, right = c.width - 8, top = 16, bottom = c.height - 20;
    if (!samples.length) return;
    const tEnd = samples[samples.length - 1].t;
    let lo = Infinity, hi = -Infinity;
    for (const ser of series) for (const smp of samples) {
      const v = ser.get(smp); if (v === null || v === undefined || !isFinite(v)) continue;
      lo = Math.min(lo, v); hi = Math.max(hi, v);
    }
    if (!isFinite(lo)) { lo = 0; hi = 1; }
    const pad = Math.max((hi - lo) * 0.1, 1e-3); lo -= pad; hi += pad;
    const X = (t) => left + (t - (tEnd - HISTORY_S)) / HISTORY_S * (right - left);
    const Y = (v) => bottom - (v - lo) / (hi - lo) * (bottom - top);
    ctx.strokeStyle = "#d8dee4"; ctx.lineWidth = 1; ctx.strokeRect(left, top, right - left, bottom - top);
    ctx.fillStyle = "#66788a"; ctx.font = "11px system-ui";
    ctx.fillText(hi.toPrecision(3), 2, top + 8); ctx.fillText(lo.toPrecision(3), 2, bottom);
    ctx.fillText("-10 s", left, c.height - 4); ctx.fillText("now", right - 22, c.height - 4);
    ctx.fillText(yLabel, left + 4, 12);
    let lx = left + 140;
    for (const ser of series) {
      ctx.strokeStyle = ser.color; ctx.lineWidth = 1.5; ctx.setLineDash(ser.dash || []);
      ctx.beginPath();
      let started = false;
      for (const smp of samples) {
        const v = ser.get(smp);
        if (v === null || v === undefined || !isFinite(v)) { started = false; continue; }
        if (started) ctx.lineTo(X(smp.t), Y(v)); else { ctx.moveTo(X(smp.t), Y(v)); started = true; }
      }
      ctx.stroke(); ctx.setLineDash([]);
      if (!inlineNames) continue; // named in the legend below the canvas
      ctx.fillStyle = ser.color; ctx.fillText(ser.name, lx, 12); lx += ctx.measureText(ser.name).width + 14;
    }
    return series.length;
  }

  function fmtMm(m) { return m === null || m === undefined ? "–" : (m * 1e3).toFixed(1) + " mm"; }

  function drawPanels() {
    const st = last.state, sh = last.shape;
    $("status").textContent = st.status + (st.overruns ? " (" + st.overruns + " overruns)" : "") +
      (st.lag_s > 0 ? "; " + st.lag_s.toFixed(2) + " s behind the wall clock (a machine slower than real time)" : "") +
      (st.estimate_error ? "; estimate failed: " + st.estimate_error : "");
    const how = st.controller ? "controller " + st.controller : "open loop";
    $("ctrl-state").textContent = (hello && hello.kind === "replay" ? "recorded " + (st.controller ? "under " : "") + how : how) +
      (hello && !hello.can_command ? "; no actuation here" : "") + (st.paused ? "; paused" : "") +
      (hello && hello.kind === "replay" ? "; replay at " + st.speed + "x" : "");
    const replay = hello && hello.kind === "replay";
    const straight = hello ? hello.straight_command : 8;
    $("engaged").textContent = replay ? "(as recorded)" : st.engaged ? "(holding)" : "(relaxed: command " + straight + ")";
    const lastSample = samples[samples.length - 1];
    if (replay && lastSample) { // a replay's setpoint is the recording's, sample by sample
      const sp = lastSample.setpoint;
      $("sp-value").textContent = sp === null || sp === undefined ? "–" : Number(sp).toFixed(1);
      if (sp !== null && sp !== undefined) $("setpoint").value = sp;
    }
    if (lastSample) {
      $("cmd-value").textContent = lastSample.command;
      $("y-value").textContent = lastSample.y === null ? "–" : lastSample.y.toFixed(1) + (st.unit === "deg" ? " deg" : "");
    }
    if (sh) $("tip").textContent = "(" + fmtMm(sh.tip_m[0]) + ", " + fmtMm(sh.tip_m[1]) + ") ±" +
      fmtMm(Math.max(sh.tip_sd_m[0] || 0, sh.tip_sd_m[1] || 0)) + ", " + (sh.tip_angle_deg || 0).toFixed(1) + " deg";
    $("loads").textContent = st.loads && st.loads.length ?
      "hung: " + st.loads.map(([m, s]) => (m * 1e3).toFixed(1) + " g at " + (s * 1e3).toFixed(0) + " mm").join(", ") : "nothing hung";
    const ce = last.contact && last.contact[0];
    if (ce) {
      $("c-yes").textContent = ce.contact ? "contact" : "no contact";
      $("c-source").textContent = "(" + ce.source + ")";
      $("c-pos").textContent = ce.contact ? fmtMm(ce.position_from_base_m) + (ce.position_sd_m === null ? " (not locatable)" : " ± " + fmtMm(ce.position_sd_m)) : "–";
      $("c-int").textContent = ce.contact && ce.position_interval_m ? fmtMm(ce.position_interval_m[0]) + " … " + fmtMm(ce.position_interval_m[1]) : "–";
      $("c-force").textContent = ce.force_n === null ? "–" : ce.force_n.toFixed(3) + " N";
      $("c-mass").textContent = ce.mass_kg === null ? "" : "(" + (ce.mass_kg * 1e3).toFixed(1) + " g)";
      $("c-note").textContent = ce.note;
      $("contact").dataset.located = ce.located ? "yes" : "no";
      $("c-others").textContent = last.contact.slice(1).map((o) => o.source + ": " +
        (o.contact ? fmtMm(o.position_from_base_m) : "no contact")).join("; ");
    }
  }

  let rateWindow = [];
  function frame() {
    if (dirty && !paused && last && stats.connected) {
      const t0 = performance.now();
      drawShape();
      const gauges = hello ? hello.gauges_m.length : 0; // one trace per gauge of the digit
      stats.traces = drawTraces("gauges", Array.from({ length: gauges }, (_, i) => ({
        name: "gauge " + (i + 1), color: COLORS[i % COLORS.length], get: (s) => s.gauges_v[i],
      })), "V", false);
      drawTraces("actuator", [
        { name: "command", color: "#111", get: (s) => s.command },
        { name: "setpoint", color: "#2e8b57", dash: [5, 3], get: (s) => s.setpoint },
        { name: "measured", color: "#7b3fa0", get: (s) => s.y },
        { name: "pot x10 V", color: "#999", get: (s) => (s.pot_v === null ? null : 10 * s.pot_v) },
      ], hello && hello.setpoint_unit === "deg" ? "command / deg" : "command");
      drawPanels();
      const now = Date.now();
      const newest = samples[samples.length - 1];
      if (newest) {
        stats.latenciesMs.push(now - newest.wall_ms);
        if (stats.latenciesMs.length > 5000) stats.latenciesMs.shift();
      }
      stats.draws += 1;
      stats.drawTimes.push(performance.now() - t0);
      if (stats.drawTimes.length > 1000) stats.drawTimes.shift();
      rateWindow.push(performance.now());
      while (rateWindow.length && rateWindow[0] < performance.now() - 2000) rateWindow.shift();
      $("rate").textContent = (rateWindow.length / 2).toFixed(0) + " updates/s";
      dirty = false;
    }
    requestAnimationFrame(frame);
  }
  // where on the screen arc position s_m (m from the clamp) of the digit is drawn: for scripted clicks (the tests)
  stats.pointFor = function (sm) {
    if (!last || !last.shape) return null;
    const line = last.truth && last.truth.length ? last.truth : last.shape.centre_line_m;
    const p = along(line.map((q) => [q[0] * 1e3, q[1] * 1e3]), last.shape.s_m, sm);
    const c = $("shape"), r = c.getBoundingClientRect(), [px, py] = toPx(c, p[0], p[1]);
    return { x: r.left + px * (r.width / c.width), y: r.top + py * (r.height / c.height) };
  };
  connect();
  requestAnimationFrame(frame);
})();
