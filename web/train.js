// The live-training page (nerfpt train --serve, nerfpt capture --serve): loss and PSNR charts drawn on small
// canvases, the held-out strip (truth | render | error) and the current model orbited through three.js's
// OrbitControls (only the controls: the server renders). Exposes window.nerfpt for the browser test.
import { fmtTime, fillStages } from '/stages.js';
import { reconnectingSocket } from '/socket.js';

const $ = (id) => document.getElementById(id);
const test = { trains: 0, evals: 0, frames: 0, strips: 0, state: null, lastTrain: null, lastEval: null, errors: [] };
window.nerfpt = test;

const hist = { step: [], loss: [], psnr: [] };
let evals = [];
let run = null;

const fmt = (v, d) => (v == null || !isFinite(v) ? '–' : v.toFixed(d));

// --- charts ---------------------------------------------------------------------------------------------------
// A line chart of one or more series [{x, y, colour, dots}] with axes labelled at round values.
function drawChart(canvas, series, { log = false } = {}) {
  const g = canvas.getContext('2d');
  const W = canvas.width, H = canvas.height, L = 52, R = 10, T = 8, B = 24;
  g.clearRect(0, 0, W, H);
  const tf = (v) => (log ? Math.log10(Math.max(v, 1e-12)) : v);
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const s of series)
    for (let i = 0; i < s.x.length; ++i) {
      if (s.y[i] == null || !isFinite(s.y[i])) continue;
      x0 = Math.min(x0, s.x[i]); x1 = Math.max(x1, s.x[i]);
      y0 = Math.min(y0, tf(s.y[i])); y1 = Math.max(y1, tf(s.y[i]));
    }
  g.strokeStyle = '#444'; g.strokeRect(L, T, W - L - R, H - T - B);
  if (!isFinite(x0)) return;
  if (x1 === x0) x1 = x0 + 1;
  if (y1 - y0 < 1e-9) { y0 -= 0.5; y1 += 0.5; }
  const pad = (y1 - y0) * 0.05; y0 -= pad; y1 += pad;
  const px = (x) => L + (x - x0) / (x1 - x0) * (W - L - R);
  const py = (y) => T + (1 - (tf(y) - y0) / (y1 - y0)) * (H - T - B);
  g.fillStyle = '#999'; g.font = '11px system-ui'; g.textAlign = 'right'; g.textBaseline = 'middle';
  for (let k = 0; k <= 4; ++k) {
    const yv = y0 + (y1 - y0) * k / 4, yy = T + (1 - k / 4) * (H - T - B);
    const label = log ? String(Number(Math.pow(10, yv).toPrecision(2))) : yv.toFixed(1);
    g.fillText(label, L - 4, yy);
    g.strokeStyle = '#2a2a2a'; g.beginPath(); g.moveTo(L, yy); g.lineTo(W - R, yy); g.stroke();
  }
  g.textAlign = 'center'; g.textBaseline = 'top';
  for (let k = 0; k <= 4; ++k) g.fillText(String(Math.round(x0 + (x1 - x0) * k / 4)), L + k / 4 * (W - L - R), H - B + 4);
  for (const s of series) {
    g.strokeStyle = s.colour; g.fillStyle = s.colour; g.lineWidth = 1.5;
    g.beginPath();
    let started = false;
    for (let i = 0; i < s.x.length; ++i) {
      if (s.y[i] == null || !isFinite(s.y[i])) continue;
      const X = px(s.x[i]), Y = py(s.y[i]);
      if (started) g.lineTo(X, Y); else { g.moveTo(X, Y); started = true; }
    }
    g.stroke();
    if (s.dots) for (let i = 0; i < s.x.length; ++i) if (s.y[i] != null && isFinite(s.y[i])) { g.beginPath(); g.arc(px(s.x[i]), py(s.y[i]), 3, 0, 7); g.fill(); }
  }
}

function redraw() {
  drawChart($('loss'), [{ x: hist.step, y: hist.loss, colour: '#6fa8dc' }], { log: true });
  drawChart($('psnr'), [
    { x: hist.step, y: hist.psnr, colour: '#6fa8dc' },
    { x: evals.map((e) => e.step), y: evals.map((e) => e.psnr), colour: '#f6b26b', dots: true },
  ]);
  test.chartPoints = hist.step.length;
}

function addPoints(p, reset) {
  if (reset) { hist.step = []; hist.loss = []; hist.psnr = []; }
  const last = hist.step.length ? hist.step[hist.step.length - 1] : -1;
  for (let i = 0; i < p.step.length; ++i) {
    if (p.step[i] <= last) continue;  // already in the state this page started from
    hist.step.push(p.step[i]); hist.loss.push(p.loss[i]); hist.psnr.push(p.psnr[i]);
  }
}

function showStrip(b64, split) {
  if (!b64) return;
  $('strip').src = 'data:image/jpeg;base64,' + b64;
  $('strip-title').textContent = split === 'train'
    ? 'a training view (the data set has no held-out views): truth | render | error'
    : 'held-out view: truth | render | error';
  test.strips++;
}

function showStages(stages) {
  if (!stages || !stages.length) return;
  $('stages-box').hidden = false;
  fillStages($('stages'), stages);
}

function showFinished(finished, interrupted) {
  const b = $('banner');
  b.hidden = !finished;
  if (finished) {
    b.textContent = interrupted ? 'training was interrupted (the checkpoint is saved)' : 'training finished: the model is saved; this page stays up until nerfpt is stopped (Ctrl-C)';
    b.className = interrupted ? 'interrupted' : '';
  }
  test.finished = finished;
}

function showStats(t) {
  const target = t.target_steps != null ? ` / ${t.target_steps}` : '';
  const lastEval = evals.length ? evals[evals.length - 1].psnr : null;
  $('stats').textContent = `step ${t.step}${target} · ${fmt(t.steps_per_s, 2)} steps/s · elapsed ${fmtTime(t.elapsed)} · ` +
    `remaining ${t.finished ? '0:00' : fmtTime(t.remaining)} · loss ${fmt(t.loss, 5)} · batch PSNR ${fmt(t.psnr, 2)} dB · ` +
    `held-out PSNR ${fmt(lastEval, 2)} dB` + (run ? ` · ${run.backend} (${run.device})` : '');
  $('phase').textContent = t.phase || '';
}

// --- orbit ----------------------------------------------------------------------------------------------------
let THREE = null, OrbitControls = null;
try {
  THREE = await import('three');
  ({ OrbitControls } = await import('three/addons/controls/OrbitControls.js'));
} catch (e) {
  $('orbit-note').textContent = 'three.js is not in this build: no orbit view';
}
let camera = null, controls = null, lastSent = 0, pending = false;
function sendCamera() {
  if (!camera) return;
  const now = performance.now();
  if (now - lastSent < 66) { if (!pending) { pending = true; setTimeout(() => { pending = false; sendCamera(); }, 70); } return; }
  lastSent = now;
  const f = new THREE.Vector3(); camera.getWorldDirection(f);
  const up = new THREE.Vector3(0, 1, 0).applyQuaternion(camera.quaternion);
  send({ type: 'camera', position: camera.position.toArray(), forward: f.toArray(), up: up.toArray(), fov_deg: camera.fov });
}
function setupOrbit(h) {
  if (!THREE || camera || !h || !h.camera) return;
  const c = h.camera;
  camera = new THREE.PerspectiveCamera(c.fov_deg, h.width / h.height, 0.01, 1e5);
  camera.position.set(...c.position);
  const up = new THREE.Vector3(...c.up);
  // Orbit about the world axis nearest the view's up (NeRF-synthetic: +Z).
  const axes = [[1, 0, 0], [0, 1, 0], [0, 0, 1]].map((a) => new THREE.Vector3(...a));
  let best = axes[2], bestDot = 0;
  for (const a of axes) { const d = up.dot(a); if (Math.abs(d) > Math.abs(bestDot)) { bestDot = d; best = a; } }
  camera.up.copy(best.clone().multiplyScalar(Math.sign(bestDot) || 1));
  controls = new OrbitControls(camera, $('orbit-box'));
  controls.target.set(...(h.target || [0, 0, 0]));
  controls.update();
  controls.addEventListener('change', sendCamera);
  sendCamera();
}

// --- the socket -----------------------------------------------------------------------------------------------
// A dropped socket is opened again, with backoff, while the page is open: the server greets the new one with its
// whole state (the charts start over from it) and the page re-sends its orbit camera, as a new page does. The
// server ends with the training's process: after a few failed tries the page says so, and keeps trying (nerfpt
// may serve here again).
const triesBeforeStopped = 4;
const socket = reconnectingSocket({ onOpen, onMessage, onDrop });
let failedTries = 0;
let reconnected = false;  // the next state is the first after a reconnect
test.connects = 0;
function onOpen() {
  failedTries = 0;
  test.closed = false;
  if (++test.connects === 1) return;
  $('status').textContent = '';
  reconnected = true;
  sendCamera();
}
function onDrop(_closeEvent, nextTryMs) {
  test.closed = true;
  ++failedTries;
  const next = `next try in ${(nextTryMs / 1000).toFixed(1)} s`;
  $('status').textContent = failedTries <= triesBeforeStopped ? `reconnecting to nerfpt… (${next})`
    : test.finished ? `nerfpt has stopped: the training had finished and its model is saved (this page reconnects if nerfpt serves here again; ${next})`
    : `nerfpt is not answering after ${failedTries} tries: the training was stopped, or the machine is overloaded (${next})`;
}
function send(msg) { if (socket.isOpen()) socket.send(JSON.stringify(msg)); }
test.send = send;
// What the orbit was set up for: after a reconnect, a state of another training (on this port) needs a fresh page.
const orbitShape = (m) => JSON.stringify([m.title, m.held_out && m.held_out.camera]);
let lastState = null;
function onMessage(ev) {
  if (typeof ev.data !== 'string') {
    const v = new DataView(ev.data);
    const n = v.getUint32(0, true);
    const header = JSON.parse(new TextDecoder().decode(new Uint8Array(ev.data, 4, n)));
    const blob = new Blob([new Uint8Array(ev.data, 4 + n)], { type: 'image/jpeg' });
    const img = $('orbit');
    const old = img.src;
    img.src = URL.createObjectURL(blob);
    if (old.startsWith('blob:')) URL.revokeObjectURL(old);
    $('orbit-note').textContent = `step ${header.step} · ${header.width}x${header.height} · ${fmt(header.render_ms, 0)} ms`;
    test.frames++;
    test.lastFrame = header;
    return;
  }
  const m = JSON.parse(ev.data);
  if (m.type === 'state') {
    if (reconnected && camera && m.held_out && lastState.held_out && orbitShape(m) !== orbitShape(lastState)) {
      location.reload();
      return;
    }
    reconnected = false;
    lastState = m;
    test.state = m;
    run = m.run;
    $('title').textContent = m.title;
    $('phase').textContent = m.phase;
    hist.step = []; hist.loss = []; hist.psnr = [];
    addPoints(m.history, true);
    evals = m.evals || [];
    if (m.strip) showStrip(m.strip, m.held_out && m.held_out.split);
    showStages(m.stages);
    showFinished(m.finished, m.interrupted);
    if (m.held_out) setupOrbit({ ...m.held_out, target: m.held_out.target });
    redraw();
  } else if (m.type === 'train') {
    test.trains++;
    test.lastTrain = m;
    addPoints(m.points, m.reset);
    showStats(m);
    showFinished(m.finished, false);
    redraw();
  } else if (m.type === 'eval') {
    test.evals++;
    test.lastEval = m;
    evals.push({ step: m.step, psnr: m.psnr });
    showStrip(m.strip, m.split);
    redraw();
  } else if (m.type === 'stages') {
    showStages(m.stages);
  } else if (m.type === 'error') {
    test.errors.push(m.message);
    $('status').textContent = m.message;
  }
}
redraw();
socket.connect();
