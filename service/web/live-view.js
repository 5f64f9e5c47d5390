// The live view's page (docs/live-view.md): one WebSocket to the service (`/ws`), whose `frame`
// messages carry state lines (docs/service.md §4), GNSS fixes and echo rays; a canvas in metres
// (x East, y North) redrawn at most once per animation frame, whatever the rate of the states.
'use strict';

const TRAIL_POINTS = 20000;  // kept trail points (a drive of hours at 5 cm spacing)
const TRAIL_SPACING_M = 0.05;
const FIXES = 300;           // GNSS fixes kept
const ECHO_AGE_S = 1.0;      // log time an echo stays drawn

const params = new URLSearchParams(location.search);
const token = params.get('token');
const givenScale = Number(params.get('scale')) || 0;  // ?scale=PX_PER_M instead of fitting the map
const $ = (id) => document.getElementById(id);
const canvas = $('view');
const ctx = canvas.getContext('2d');

const view = {
  cx: 0, cy: 0, scale: 20,  // world point at the canvas centre (m), pixels per metre
  follow: true,
};
let ws = null;
let reconnectDelayMs = 500;
let watched = params.get('session') || '';
let sessions = [];
let scene = null;       // the watched session's `scene` message
let state = null;       // its newest `state`
let trail = [];         // [x, y]
let fixes = [];         // gnss lines
let echoes = [];        // echo lines
let frames = 0, dropped = 0, fixesTotal = 0, echoesTotal = 0;  // since the session was watched
let dirty = true, scheduled = false;

// ----- connection ---------------------------------------------------------------------------------

function setStatus(text, kind) {
  $('status').textContent = text;
  $('status').dataset.state = kind;
}

function connect() {
  const scheme = location.protocol === 'https:' ? 'wss' : 'ws';
  const url = `${scheme}://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : '');
  setStatus('connecting…', 'connecting');
  ws = new WebSocket(url);
  ws.onopen = () => {
    reconnectDelayMs = 500;
    setStatus('connected', 'live');
    if (watched) send({ type: 'watch', session: watched });
  };
  ws.onmessage = (event) => {
    let frame;
    try { frame = JSON.parse(event.data); } catch (e) { return; }
    if (frame.type !== 'frame') return;
    ++frames;
    dropped += frame.dropped || 0;
    for (const line of frame.lines) handle(line);
    schedule();
  };
  ws.onclose = () => {
    ws = null;
    scene = null;  // a restarted service sends the scene again when the session is back
    setStatus(`disconnected: retrying in ${(reconnectDelayMs / 1000).toFixed(1)} s`, 'closed');
    setTimeout(connect, reconnectDelayMs);
    reconnectDelayMs = Math.min(reconnectDelayMs * 2, 5000);
  };
}

function send(message) {
  if (ws && ws.readyState === WebSocket.OPEN) ws.send(JSON.stringify(message));
}

function watch(name) {
  watched = name;
  scene = null; state = null; trail = []; fixes = []; echoes = []; fixesTotal = 0; echoesTotal = 0;
  if (name) send({ type: 'watch', session: name });
  const url = new URL(location.href);
  if (name) url.searchParams.set('session', name); else url.searchParams.delete('session');
  history.replaceState(null, '', url);
  dirty = true;
  schedule();
}

// ----- messages -----------------------------------------------------------------------------------

function handle(line) {
  switch (line.type) {
    case 'sessions': onSessions(line.sessions); break;
    case 'scene': if (line.session === watched) onScene(line); break;
    case 'state': if (line.session === watched) onState(line); break;
    case 'gnss':
      if (line.session === watched) { fixes.push(line); ++fixesTotal; if (fixes.length > FIXES) fixes.shift(); }
      break;
    case 'echo': if (line.session === watched) { echoes.push(line); ++echoesTotal; } break;
    case 'error': setStatus(`${line.code}: ${line.message}`, 'error'); break;
    default: break;  // subscribed, unsubscribed: nothing to show
  }
  dirty = true;
}

function onSessions(list) {
  sessions = list.map((s) => s.session).sort();
  const select = $('session-select');
  const current = Array.from(select.options).map((o) => o.value).filter((v) => v);
  if (current.join('\n') !== sessions.join('\n')) {
    select.replaceChildren();
    const none = new Option(sessions.length ? '(pick a session)' : '(no session open)', '');
    select.add(none);
    for (const name of sessions) select.add(new Option(name, name));
  }
  if (watched && !sessions.includes(watched) && scene) {
    setStatus(`session ${watched} is closed`, 'closed');
  } else if (!watched && sessions.length) {
    watch(sessions[0]);
  } else if (watched && sessions.includes(watched) && !scene) {
    send({ type: 'watch', session: watched });  // opened after we asked
  }
  select.value = sessions.includes(watched) ? watched : '';
}

function onScene(message) {
  scene = message;
  setStatus('live', 'live');
  trail = []; fixes = []; echoes = []; state = null; fixesTotal = 0; echoesTotal = 0;
  fitMap();
}

function onState(s) {
  if (state && state.t !== null && s.t !== null && s.t < state.t) return;  // an older get_state reply
  state = s;
  if (!s.initialised) return;
  const last = trail[trail.length - 1];
  if (!last || Math.hypot(s.x_m - last[0], s.y_m - last[1]) >= TRAIL_SPACING_M) {
    trail.push([s.x_m, s.y_m]);
    if (trail.length > TRAIL_POINTS) trail.splice(0, trail.length - TRAIL_POINTS);
  }
}

// ----- view ---------------------------------------------------------------------------------------

function mapBounds() {
  let xmin = Infinity, ymin = Infinity, xmax = -Infinity, ymax = -Infinity;
  for (const row of (scene ? scene.rows : [])) {
    for (const [x, y] of row.points) {
      xmin = Math.min(xmin, x); xmax = Math.max(xmax, x); ymin = Math.min(ymin, y); ymax = Math.max(ymax, y);
    }
  }
  return xmin <= xmax ? { xmin, ymin, xmax, ymax } : null;
}

function fitMap() {
  const b = mapBounds();
  if (!b) return;
  view.cx = (b.xmin + b.xmax) / 2;
  view.cy = (b.ymin + b.ymax) / 2;
  const w = canvas.clientWidth || 800, h = canvas.clientHeight || 600;
  view.scale = givenScale || 0.9 * Math.min(w / Math.max(b.xmax - b.xmin, 1), h / Math.max(b.ymax - b.ymin, 1));
  dirty = true;
}

function schedule() {
  if (scheduled) return;
  scheduled = true;
  // requestAnimationFrame: at most one drawing per display frame; the timeout draws in a background
  // tab (no animation frames) so that the panel stays true.
  const run = () => { if (scheduled) { scheduled = false; draw(); } };
  requestAnimationFrame(run);
  setTimeout(run, 250);
}

function draw() {
  if (!dirty) return;
  dirty = false;
  const dpr = window.devicePixelRatio || 1;
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
  }
  if (view.follow && state && state.initialised) { view.cx = state.x_m; view.cy = state.y_m; }
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  const s = view.scale * dpr;
  // World metres to the canvas: x right, y up.
  ctx.setTransform(s, 0, 0, -s, canvas.width / 2 - view.cx * s, canvas.height / 2 + view.cy * s);
  const px = 1 / s;  // one device pixel in metres
  drawGrid(px, w, h, dpr);
  drawRows(px);
  drawFixes(px);
  drawTrail(px);
  drawEchoes(px);
  drawVehicle(px);
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  drawScaleBar(h);
  updatePanel();
}

function drawGrid(px, w, h, dpr) {
  const step = Math.pow(10, Math.ceil(Math.log10(80 / view.scale)));  // about 80 px or more
  const halfW = w * dpr * px / 2, halfH = h * dpr * px / 2;
  ctx.beginPath();
  for (let x = Math.floor((view.cx - halfW) / step) * step; x <= view.cx + halfW; x += step) {
    ctx.moveTo(x, view.cy - halfH); ctx.lineTo(x, view.cy + halfH);
  }
  for (let y = Math.floor((view.cy - halfH) / step) * step; y <= view.cy + halfH; y += step) {
    ctx.moveTo(view.cx - halfW, y); ctx.lineTo(view.cx + halfW, y);
  }
  ctx.strokeStyle = '#e4e6df'; ctx.lineWidth = px; ctx.stroke();
}

function drawRows(px) {
  let n = 0;
  ctx.strokeStyle = '#3d7a35'; ctx.lineWidth = 2 * px; ctx.lineJoin = 'round';
  for (const row of (scene ? scene.rows : [])) {
    if (row.points.length < 2) continue;
    ctx.beginPath();
    ctx.moveTo(row.points[0][0], row.points[0][1]);
    for (const [x, y] of row.points.slice(1)) ctx.lineTo(x, y);
    if (row.closed) { ctx.closePath(); ctx.fillStyle = 'rgba(61,122,53,0.12)'; ctx.fill(); }
    ctx.stroke();
    ++n;
  }
  $('rows-drawn').textContent = n;
}

function drawFixes(px) {
  for (const f of fixes) {
    const color = f.accepted === false ? '#c8322b' : (f.accepted ? '#2d62c4' : '#8a8f96');
    ctx.strokeStyle = color; ctx.lineWidth = px;
    ctx.beginPath(); ctx.arc(f.x_m, f.y_m, Math.max(f.sigma_m, px), 0, 2 * Math.PI); ctx.stroke();
    ctx.beginPath();
    ctx.moveTo(f.x_m - 3 * px, f.y_m); ctx.lineTo(f.x_m + 3 * px, f.y_m);
    ctx.moveTo(f.x_m, f.y_m - 3 * px); ctx.lineTo(f.x_m, f.y_m + 3 * px);
    ctx.stroke();
  }
  $('gnss-drawn').textContent = fixes.length;
}

function drawTrail(px) {
  if (trail.length > 1) {
    ctx.beginPath();
    ctx.moveTo(trail[0][0], trail[0][1]);
    for (let i = 1; i < trail.length; ++i) ctx.lineTo(trail[i][0], trail[i][1]);
    ctx.strokeStyle = '#5f5f5f'; ctx.lineWidth = 1.5 * px; ctx.stroke();
  }
  $('trail-drawn').textContent = trail.length;
}

function drawEchoes(px) {
  const now = state && state.t !== null ? state.t : -Infinity;
  echoes = echoes.filter((e) => e.t >= now - ECHO_AGE_S);
  for (const e of echoes) {
    const used = e.outcome === 'accepted';
    ctx.strokeStyle = used ? '#e08a1e' : '#a4a8ad'; ctx.lineWidth = 1.5 * px;
    ctx.beginPath(); ctx.moveTo(e.from[0], e.from[1]); ctx.lineTo(e.to[0], e.to[1]); ctx.stroke();
    if (e.segment) {
      ctx.strokeStyle = used ? 'rgba(224,138,30,0.55)' : 'rgba(164,168,173,0.5)'; ctx.lineWidth = 5 * px;
      ctx.beginPath(); ctx.moveTo(e.segment[0][0], e.segment[0][1]); ctx.lineTo(e.segment[1][0], e.segment[1][1]);
      ctx.stroke();
    }
  }
  $('echoes-drawn').textContent = echoes.length;
}

/// The outline: the wheels' bounding box grown by the wheel radius along x and 0.1 m across.
function vehicleOutline(vehicle) {
  let xmin = Infinity, xmax = -Infinity, ymin = Infinity, ymax = -Infinity;
  for (const w of vehicle.wheels) {
    xmin = Math.min(xmin, w.x_m - w.radius_m); xmax = Math.max(xmax, w.x_m + w.radius_m);
    ymin = Math.min(ymin, w.y_m - 0.1); ymax = Math.max(ymax, w.y_m + 0.1);
  }
  return { xmin, xmax, ymin, ymax };
}

function drawVehicle(px) {
  if (!state || !state.initialised) return;
  const e = state.ellipse_2sigma;
  ctx.beginPath();
  ctx.ellipse(state.x_m, state.y_m, Math.max(e.semi_major_m, px), Math.max(e.semi_minor_m, px), e.angle_rad, 0, 2 * Math.PI);
  ctx.fillStyle = 'rgba(194,48,107,0.15)'; ctx.fill();
  ctx.strokeStyle = '#c2306b'; ctx.lineWidth = 1.5 * px; ctx.stroke();
  if (!scene) return;
  ctx.save();
  ctx.translate(state.x_m, state.y_m);
  ctx.rotate(state.phi_rad);
  const o = vehicleOutline(scene.vehicle);
  ctx.fillStyle = 'rgba(36,53,42,0.25)'; ctx.strokeStyle = '#24352a'; ctx.lineWidth = 2 * px;
  ctx.fillRect(o.xmin, o.ymin, o.xmax - o.xmin, o.ymax - o.ymin);
  ctx.strokeRect(o.xmin, o.ymin, o.xmax - o.xmin, o.ymax - o.ymin);
  ctx.fillStyle = '#24352a';
  for (const w of scene.vehicle.wheels) ctx.fillRect(w.x_m - w.radius_m, w.y_m - 0.06, 2 * w.radius_m, 0.12);
  ctx.beginPath();  // heading
  ctx.moveTo(0, 0); ctx.lineTo(o.xmax + 0.3, 0);
  ctx.strokeStyle = '#c2306b'; ctx.stroke();
  ctx.restore();
}

function drawScaleBar(h) {
  const metres = Math.pow(10, Math.floor(Math.log10(120 / view.scale)));
  const length = metres * view.scale;
  ctx.strokeStyle = '#1d2327'; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(12, h - 14); ctx.lineTo(12 + length, h - 14); ctx.stroke();
  ctx.fillStyle = '#1d2327'; ctx.font = '12px system-ui, sans-serif';
  ctx.fillText(`${metres >= 1 ? metres : metres.toFixed(2)} m`, 12, h - 20);
}

// ----- panel --------------------------------------------------------------------------------------

const fixed = (v, digits) => (typeof v === 'number' && isFinite(v) ? v.toFixed(digits) : '–');

function updatePanel() {
  $('session').textContent = watched || '–';
  $('vehicle').textContent = scene ? `${scene.vehicle.name} / ${scene.map || 'no map'}` : '–';
  $('frames').textContent = frames;
  $('dropped').textContent = dropped;
  $('gnss-total').textContent = fixesTotal;
  $('echoes-total').textContent = echoesTotal;
  const s = state;
  $('t').textContent = s ? fixed(s.t, 3) : '–';
  $('initialised').textContent = !s ? '–' : (s.initialised ? 'initialised' : 'waiting for the first GNSS fix');
  const ok = s && s.initialised;
  $('x').textContent = ok ? fixed(s.x_m, 3) : '–';
  $('y').textContent = ok ? fixed(s.y_m, 3) : '–';
  $('phi').textContent = ok ? fixed(s.phi_rad, 4) : '–';
  $('heading-deg').textContent = ok ? fixed(s.phi_rad * 180 / Math.PI, 1) : '–';
  $('ellipse').textContent = ok ? `${fixed(s.ellipse_2sigma.semi_major_m, 3)} × ${fixed(s.ellipse_2sigma.semi_minor_m, 3)}` : '–';
  $('speed').textContent = ok ? fixed(Math.hypot(s.velocity.x_mps, s.velocity.y_mps), 2) : '–';
  $('yaw-rate').textContent = ok ? fixed(s.velocity.yaw_rate_radps, 3) : '–';
  updateWheels(ok ? s : null);
  updateSensors(s);
  const h = s ? s.health : null;
  $('fix-age').textContent = !h ? '–' : (h.last_fix_age_s === null ? 'no fix yet' : `${fixed(h.last_fix_age_s, 2)} s`);
  $('pending').textContent = h ? h.pending : '–';
  $('rejected').textContent = h ? h.rejected_messages : '–';
  $('last-rejection').textContent = h && h.last_rejection ? h.last_rejection : '–';
}

function updateWheels(s) {
  const box = $('wheels');
  const names = scene ? scene.vehicle.wheels.map((w) => w.name) : [];
  if (box.dataset.names !== names.join(',')) {
    box.replaceChildren();
    for (const name of names) {
      const div = document.createElement('div');
      div.className = 'wheel';
      div.innerHTML = '<span class="name"></span><span class="bar"><span class="fill"></span></span>' +
                      '<span class="value"></span><span class="radius"></span>';
      div.querySelector('.name').textContent = name;
      box.appendChild(div);
    }
    box.dataset.names = names.join(',');
  }
  names.forEach((name, i) => {
    const div = box.children[i];
    const slip = s && s.slip ? s.slip[name] : undefined;
    const fill = div.querySelector('.fill');
    const v = typeof slip === 'number' ? Math.max(-0.5, Math.min(0.5, slip)) : 0;  // bars span |slip| <= 0.5
    fill.style.left = `${50 + Math.min(v, 0) * 100}%`;
    fill.style.width = `${Math.abs(v) * 100}%`;
    fill.classList.toggle('negative', v < 0);
    div.querySelector('.value').textContent = fixed(slip, 3);
    const c = s && s.wheel_calibration ? s.wheel_calibration[name] : null;
    div.querySelector('.radius').textContent = c
      ? `R ${fixed(c.rolling_radius_m, 4)} ± ${fixed(c.rolling_radius_sigma_m, 4)} m`
      : 'R: no slip-aware odometry';
  });
}

function updateSensors(s) {
  const body = $('sensors').tBodies[0];
  const sensors = s && s.health ? s.health.sensors : {};
  const names = Object.keys(sensors).sort();
  while (body.rows.length > names.length) body.deleteRow(-1);
  names.forEach((name, i) => {
    const row = body.rows[i] || body.insertRow();
    while (row.cells.length < 4) row.insertCell();
    const c = sensors[name];
    row.cells[0].textContent = name;
    row.cells[1].textContent = c.accepted;
    row.cells[2].textContent = c.gated;
    row.cells[3].textContent = fixed(c.last_nis, 2);
  });
}

// ----- input --------------------------------------------------------------------------------------

function setFollow(on) { view.follow = on; $('follow').checked = on; dirty = true; schedule(); }

$('follow').addEventListener('change', (e) => setFollow(e.target.checked));
$('fit').addEventListener('click', () => { setFollow(false); fitMap(); schedule(); });
$('session-select').addEventListener('change', (e) => watch(e.target.value));
document.addEventListener('keydown', (e) => { if (e.key === 'f') setFollow(!view.follow); });
let drag = null;
canvas.addEventListener('pointerdown', (e) => {
  drag = { x: e.clientX, y: e.clientY };
  canvas.setPointerCapture(e.pointerId);
  canvas.classList.add('dragging');
});
canvas.addEventListener('pointermove', (e) => {
  if (!drag) return;
  if (view.follow) setFollow(false);
  view.cx -= (e.clientX - drag.x) / view.scale;
  view.cy += (e.clientY - drag.y) / view.scale;
  drag = { x: e.clientX, y: e.clientY };
  dirty = true; schedule();
});
canvas.addEventListener('pointerup', () => { drag = null; canvas.classList.remove('dragging'); });
canvas.addEventListener('wheel', (e) => {
  e.preventDefault();
  const r = canvas.getBoundingClientRect();
  const mx = e.clientX - r.left - r.width / 2, my = e.clientY - r.top - r.height / 2;
  const before = { x: view.cx + mx / view.scale, y: view.cy - my / view.scale };  // the point under the cursor stays
  view.scale = Math.min(2000, Math.max(0.05, view.scale * Math.exp(-e.deltaY * 0.0015)));
  if (!view.follow) { view.cx = before.x - mx / view.scale; view.cy = before.y + my / view.scale; }
  dirty = true; schedule();
}, { passive: false });
window.addEventListener('resize', () => { dirty = true; schedule(); });

connect();
schedule();
