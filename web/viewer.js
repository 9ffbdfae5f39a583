// nerfpt serve's page: shows the frames the server path-traces, sends camera moves (orbit, WASD fly) and edits
// (the volume gizmo, the panel), and exposes window.nerfpt for the browser test.
import { reconnectingSocket } from '/socket.js';

const statusEl = document.getElementById('status');
const statsEl = document.getElementById('stats');
function say(text, error = false) {
  statusEl.textContent = text;
  statusEl.className = error ? 'error' : '';
}
// A note that goes away by itself (unless something else was said meanwhile).
function sayBriefly(text) {
  say(text);
  setTimeout(() => { if (statusEl.textContent === text) say(''); }, 4000);
}

let THREE, OrbitControls, TransformControls, GUI;
try {
  THREE = await import('three');
  ({ OrbitControls } = await import('three/addons/controls/OrbitControls.js'));
  ({ TransformControls } = await import('three/addons/controls/TransformControls.js'));
  ({ GUI } = await import('/vendor/lil-gui/lil-gui.esm.js'));
} catch (e) {
  const status = await (await fetch('/vendor/status.txt')).text();
  say('three.js / lil-gui are not in this build (' + status.trim() + '): rebuild with npm reachable', true);
  throw e;
}

const imageCanvas = document.getElementById('image');
const overlay = document.getElementById('overlay');
const ctx2d = imageCanvas.getContext('2d');
const test = { frames: 0, header: null, state: null, errors: [], messages: [] };
window.nerfpt = test;

// --- the socket -------------------------------------------------------------------------------------------
// A dropped socket (nerfpt serve restarted, a connection reset) is opened again, with backoff, for as long as the
// page is open. The server greets a new socket as a new page (its state; a view from the start camera), so after
// a reconnect the page re-sends what is its own: its camera, and the edits it made while disconnected or just
// before the drop.
const socket = reconnectingSocket({ onOpen, onMessage, onDrop });
let awaitingState = false;    // reconnected: the server's first state re-syncs the panel, then edits are re-sent
let awaitingOwnView = false;  // reconnected: frames from the start camera are not this page's view
// Edits made while disconnected, the newest per control: they are absolute values, so sending the last one is
// the edit. One-off actions (save, render, keyframes) are not kept: they are refused, visibly.
const unsent = new Map();
const keptTypes = new Set(['volume', 'light', 'settings', 'use_camera']);
// Those sent just before a drop may not have reached the server (a reset loses what it had not read): the last
// second's are sent again after a reconnect. Absolute values: one that did arrive is only applied again.
const recentlySent = [];
const recentMs = 1000;
test.connects = 0;
test.closes = [];

function onOpen() {
  if (++test.connects === 1) return;
  sayBriefly('reconnected to nerfpt serve');
  awaitingState = awaitingOwnView = true;
  sendCamera();
}
function onDrop(e, nextTryMs) {
  if (test.connects) test.closes.push({ code: e.code, reason: e.reason, clean: e.wasClean, at: Date.now() });
  keepRecentlySent();
  const waiting = unsent.size ? ` · ${unsent.size} edit${unsent.size > 1 ? 's wait' : ' waits'} to be sent` : '';
  say(`${test.connects ? 'reconnecting' : 'connecting'} to nerfpt serve… (next try in ${(nextTryMs / 1000).toFixed(1)} s${waiting})`, true);
}
function send(msg) {
  const kept = keptTypes.has(msg.type);
  if (socket.isOpen() && !(kept && awaitingState)) {
    if (msg.type === 'use_camera') awaitingOwnView = false;  // the server places the view: follow it
    socket.send(JSON.stringify(msg));
    if (kept) recentlySent.push({ msg, at: performance.now() });
    while (recentlySent.length && performance.now() - recentlySent[0].at > recentMs) recentlySent.shift();
  } else if (kept) {
    unsent.set(editKey(msg), msg);
  } else if (msg.type !== 'camera') {  // the camera is re-sent on reconnect
    say(`not connected to nerfpt serve: '${msg.type}' was not sent; do it again once reconnected`, true);
  }
}
test.send = send;
// Which control a message sets: a later message for the same control replaces it.
function editKey(msg) {
  const fields = Object.keys(msg).filter((k) => k !== 'type' && k !== 'index').sort();
  return `${msg.type}:${msg.index ?? ''}:${fields.join(',')}`;
}
function keepRecentlySent() {
  const newer = new Set(unsent.keys());  // made while disconnected: newer than anything sent before
  for (const { msg, at } of recentlySent)
    if (performance.now() - at <= recentMs && !newer.has(editKey(msg))) unsent.set(editKey(msg), msg);
  recentlySent.length = 0;
}
function sendUnsent() {
  const n = unsent.size;
  const edits = [...unsent.values()];
  unsent.clear();
  for (const m of edits) send(m);
  if (n) sayBriefly(`reconnected to nerfpt serve; sent the ${n} edit${n > 1 ? 's' : ''} it may have missed`);
}

// --- three.js: a camera that matches the server's, helpers drawn over the image ------------------------------
const renderer = new THREE.WebGLRenderer({ canvas: overlay, alpha: true, antialias: true });
renderer.setClearColor(0x000000, 0);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 4 / 3, 0.01, 1e5);
const controls = new OrbitControls(camera, overlay);
controls.enableDamping = false;
const gizmo = new TransformControls(camera, overlay);
scene.add(gizmo.getHelper ? gizmo.getHelper() : gizmo);
let volumeGroups = [];
let selected = -1;
let state = null;
let lastCameraSent = 0;
let cameraDirty = false;

// Both canvases hold the image's pixels and are shown as large as the view allows, at the image's aspect.
function fitCanvases() {
  const view = document.getElementById('view').getBoundingClientRect();
  const w = imageCanvas.width, h = imageCanvas.height;
  const s = Math.min(view.width / w, view.height / h);
  for (const c of [imageCanvas, overlay]) { c.style.width = `${Math.floor(w * s)}px`; c.style.height = `${Math.floor(h * s)}px`; }
}
window.addEventListener('resize', fitCanvases);
function setSize(w, h) {
  if (imageCanvas.width !== w || imageCanvas.height !== h) {
    imageCanvas.width = w; imageCanvas.height = h;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    fitCanvases();
  }
}

function applyServerCamera(c) {
  const p = new THREE.Vector3(...c.position), f = new THREE.Vector3(...c.forward).normalize();
  camera.position.copy(p);
  camera.up.set(...c.up);
  camera.fov = c.fov_deg;
  camera.updateProjectionMatrix();
  const dist = Math.max(0.5, controls.target.distanceTo(p) || 3);
  controls.target.copy(p.clone().addScaledVector(f, dist));
  camera.lookAt(controls.target);
  controls.update();
}

function cameraMessage() {
  const f = new THREE.Vector3();
  camera.getWorldDirection(f);
  const up = new THREE.Vector3(0, 1, 0).applyQuaternion(camera.quaternion);
  return { type: 'camera', position: camera.position.toArray(), forward: f.toArray(), up: up.toArray(), fov_deg: camera.fov };
}
function sendCamera() {
  lastCameraSent = performance.now();
  send(cameraMessage());
}
controls.addEventListener('change', () => { cameraDirty = true; });

// WASD fly: moves the camera and the orbit target together.
const keys = new Set();
overlay.addEventListener('keydown', (e) => {
  const k = e.key.toLowerCase();
  if ('wasdqe'.includes(k) && k.length === 1) keys.add(k);
  if (k === '1') gizmo.setMode('translate');
  if (k === '2') gizmo.setMode('rotate');
  if (k === '3') gizmo.setMode('scale');
  if (k === 'escape') select(-1);
});
overlay.addEventListener('keyup', (e) => keys.delete(e.key.toLowerCase()));
overlay.addEventListener('pointerdown', () => overlay.focus());
const ui = { flySpeed: 1.0 };
let lastTime = performance.now();
function tick(now) {
  const dt = Math.min(0.1, (now - lastTime) / 1000);
  lastTime = now;
  if (keys.size) {
    const f = new THREE.Vector3(); camera.getWorldDirection(f);
    const r = new THREE.Vector3().crossVectors(f, camera.up).normalize();
    const u = camera.up.clone().normalize();
    const d = new THREE.Vector3();
    if (keys.has('w')) d.add(f); if (keys.has('s')) d.sub(f);
    if (keys.has('d')) d.add(r); if (keys.has('a')) d.sub(r);
    if (keys.has('e')) d.add(u); if (keys.has('q')) d.sub(u);
    d.multiplyScalar(ui.flySpeed * dt);
    camera.position.add(d); controls.target.add(d);
    cameraDirty = true;
  }
  if (cameraDirty) {  // at most one camera message per animation frame
    cameraDirty = false;
    sendCamera();
  }
  renderer.render(scene, camera);
  requestAnimationFrame(tick);
}
requestAnimationFrame(tick);

// --- volumes: boxes and the gizmo ---------------------------------------------------------------------------
function buildVolumes() {
  for (const g of volumeGroups) scene.remove(g);
  volumeGroups = state.volumes.map((v, i) => {
    const g = new THREE.Group();
    const size = v.local_max.map((m, k) => m - v.local_min[k]);
    const centre = v.local_max.map((m, k) => 0.5 * (m + v.local_min[k]));
    const box = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.BoxGeometry(...size)),
                                       new THREE.LineBasicMaterial({ color: 0xffcc33 }));
    box.position.set(...centre);
    g.add(box);
    g.userData.index = i;
    scene.add(g);
    return g;
  });
  syncVolumes();
}
function syncVolumes() {
  state.volumes.forEach((v, i) => {
    const g = volumeGroups[i];
    if (!g || (gizmo.dragging && selected === i)) return;
    g.position.set(...v.translation);
    g.quaternion.set(...v.rotation);
    g.scale.set(...v.scale);
    g.children[0].material.color.set(i === selected ? 0x33ddff : 0xffcc33);
    g.visible = ui.showBoxes;
  });
}
function select(i) {
  selected = i;
  if (i >= 0 && volumeGroups[i]) gizmo.attach(volumeGroups[i]); else gizmo.detach();
  if (state) syncVolumes();
  refreshVolumePanel();
}
gizmo.addEventListener('dragging-changed', (e) => { controls.enabled = !e.value; });
let gizmoPending = false;
gizmo.addEventListener('objectChange', () => {
  if (selected < 0 || gizmoPending) return;
  gizmoPending = true;
  requestAnimationFrame(() => {
    gizmoPending = false;
    const g = volumeGroups[selected];
    send({ type: 'volume', index: selected, translation: g.position.toArray(),
           rotation: [g.quaternion.x, g.quaternion.y, g.quaternion.z, g.quaternion.w], scale: g.scale.toArray() });
  });
});
// A click on a box selects it.
const raycaster = new THREE.Raycaster();
overlay.addEventListener('dblclick', (e) => {
  const rect = overlay.getBoundingClientRect();
  const p = new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
  raycaster.setFromCamera(p, camera);
  const boxes = volumeGroups.map((g) => g.children[0]);
  const hits = raycaster.intersectObjects(boxes, false);
  select(hits.length ? hits[0].object.parent.userData.index : -1);
});

// --- the panel ------------------------------------------------------------------------------------------------
const gui = new GUI({ title: 'nerfpt serve' });
ui.camera = '';
ui.spp = 64; ui.max_depth = 16; ui.exposure = 0; ui.preview = 4; ui.showBoxes = true; ui.view = 'beauty';
ui.volume = -1; ui.mode = 'translate';
ui.density_scale = 1; ui.emission_scale = 1; ui.shading = 'auto';
ui.crop = { on: false, min: [0, 0, 0], max: [1, 1, 1] };
ui.secondsPerKey = 1;
const viewFolder = gui.addFolder('View');
let cameraCtl = null;
viewFolder.add(ui, 'flySpeed', 0.01, 20).name('fly speed (units/s)');
// What the picture shows: the render, or a layer of its film (alpha, albedo, normal as 0.5 + n/2, depth as grey).
viewFolder.add(ui, 'view', ['beauty', 'alpha', 'albedo', 'normal', 'depth']).name('show').onFinishChange((v) => send({ type: 'settings', view: v }));
viewFolder.add(ui, 'exposure', -10, 10, 0.1).onFinishChange((v) => send({ type: 'settings', exposure: v }));
viewFolder.add(ui, 'spp', 1, 4096, 1).name('target spp').onFinishChange((v) => send({ type: 'settings', spp: v }));
viewFolder.add(ui, 'max_depth', 0, 64, 1).name('bounces').onFinishChange((v) => send({ type: 'settings', max_depth: v }));
viewFolder.add(ui, 'preview', 1, 16, 1).name('preview divisor').onFinishChange((v) => send({ type: 'settings', preview_divisor: v }));
viewFolder.add(ui, 'showBoxes').name('show volume boxes').onChange(() => state && syncVolumes());
const volFolder = gui.addFolder('Volume');
let volumeCtl = null;
const fillCtls = [];
fillCtls.push(volFolder.add(ui, 'mode', ['translate', 'rotate', 'scale']).name('gizmo').onChange((m) => gizmo.setMode(m)));
fillCtls.push(volFolder.add(ui, 'density_scale', 0, 100).name('density scale').onFinishChange((v) => selected >= 0 && send({ type: 'volume', index: selected, density_scale: v })));
fillCtls.push(volFolder.add(ui, 'emission_scale', 0, 20).name('emission scale').onFinishChange((v) => selected >= 0 && send({ type: 'volume', index: selected, emission_scale: v })));
const shadingCtl = volFolder.add(ui, 'shading', ['auto', 'emissive', 'relit']).name('shading').onFinishChange((v) => {
  if (selected >= 0 && v !== 'auto') send({ type: 'volume', index: selected, shading: v });
});
const cropFolder = volFolder.addFolder('crop box (model space)');
cropFolder.add(ui.crop, 'on').name('crop').onFinishChange(() => sendCrop());
for (const [which, label] of [['min', 'min'], ['max', 'max']])
  for (let k = 0; k < 3; ++k)
    cropFolder.add(ui.crop[which], k, -4, 5, 0.005).name(`${label} ${'xyz'[k]}`).onFinishChange(() => sendCrop());
function sendCrop() {
  if (selected < 0) return;
  send({ type: 'volume', index: selected, crop: ui.crop.on ? { min: ui.crop.min, max: ui.crop.max } : null });
}
const lightFolder = gui.addFolder('Lights');
const sceneFolder = gui.addFolder('Scene');
ui.save = () => send({ type: 'save' });
ui.render = () => send({ type: 'render' });
ui.addKey = () => send({ type: 'keyframe_add' });
ui.clearKeys = () => send({ type: 'keyframes_clear' });
ui.savePath = () => send({ type: 'keyframes_save', seconds_per_key: ui.secondsPerKey });
const saveCtl = sceneFolder.add(ui, 'save').name('Save edits into the scene file');
sceneFolder.add(ui, 'render').name('Render still (full res, target spp)');
const keyCtl = sceneFolder.add(ui, 'addKey').name('Add keyframe (0)');
sceneFolder.add(ui, 'clearKeys').name('Clear keyframes');
sceneFolder.add(ui, 'secondsPerKey', 0.1, 20, 0.1).name('seconds per keyframe');
sceneFolder.add(ui, 'savePath').name('Save camera path');

function refreshVolumePanel() {
  if (volumeCtl) volumeCtl.updateDisplay();
  const v = state && selected >= 0 ? state.volumes[selected] : null;
  volFolder.title(v ? `Volume: ${v.name}` : 'Volume (double-click a box)');
  ui.volume = selected;
  if (!v) return;
  ui.density_scale = v.density_scale; ui.emission_scale = v.emission_scale; ui.shading = v.shading;
  ui.crop.on = !!v.crop;
  if (v.crop) { ui.crop.min = [...v.crop.min]; ui.crop.max = [...v.crop.max]; }
  shadingCtl.enable(v.nerf);
  cropFolder.show(v.nerf);
  for (const c of volFolder.controllersRecursive()) c.updateDisplay();
}

// What the panel's lists are made from: a reconnect that finds another scene starts the page afresh.
const sceneShape = (st) => JSON.stringify([st.scene, ...['volumes', 'lights', 'cameras'].map((k) => st[k].map((x) => x.name))]);

function buildLists(st) {
  const names = {}; st.cameras.forEach((c, i) => { names[c.name || `camera ${i}`] = i; });
  if (st.cameras.length) {
    ui.camera = 0;
    cameraCtl = viewFolder.add(ui, 'camera', names).name('scene camera').onChange((i) => send({ type: 'use_camera', index: Number(i) }));
  }
  const volNames = { '(none)': -1 }; st.volumes.forEach((v, i) => { volNames[v.name] = i; });
  volumeCtl = volFolder.add(ui, 'volume', volNames).name('select').onChange((i) => select(Number(i)));
  ui.lights = st.lights.map((l) => ({ scale: l.intensity_scale }));
  st.lights.forEach((l, i) => lightFolder.add(ui.lights[i], 'scale', 0, 10, 0.01).name(`${l.name} (${l.type})`)
    .onFinishChange((v) => send({ type: 'light', index: i, intensity_scale: v })));
  if (!st.lights.length) lightFolder.hide();
}

// The server's settings as the panel shows them: from the first state, and again after a reconnect (another
// page may have changed them meanwhile, or nerfpt serve was restarted).
function fillPanel(st) {
  ui.spp = st.target_spp; ui.max_depth = st.max_depth; ui.exposure = st.exposure; ui.preview = st.preview_divisor; ui.view = st.view || 'beauty';
  st.lights.forEach((l, i) => { ui.lights[i].scale = l.intensity_scale; });
  saveCtl.enable(st.savable);
  saveCtl.name(st.savable ? 'Save edits into the scene file' : 'Save: ' + st.why_not_savable);
  for (const c of gui.controllersRecursive()) c.updateDisplay();
}

// The state as it is once the unsent edits are applied: what the panel shows after a reconnect.
function withUnsent(st) {
  const s = structuredClone(st);
  for (const m of unsent.values()) {
    if (m.type === 'settings')
      for (const [k, v] of Object.entries(m)) if (k !== 'type') s[k === 'spp' ? 'target_spp' : k] = v;
    if (m.type === 'light' && s.lights[m.index]) s.lights[m.index].intensity_scale = m.intensity_scale;
  }
  return s;
}

function onState(st) {
  const first = !state;
  if (awaitingState && !first && sceneShape(st) !== sceneShape(state)) {
    location.reload();  // another scene: this page's lists, selection and unsent edits are not for it
    return;
  }
  const rebuild = first || st.volumes.length !== state.volumes.length;
  state = st;
  test.state = st;
  setSize(st.width, st.height);
  if (first) {
    applyServerCamera(st.camera);
    buildLists(st);
  }
  if (first || awaitingState) fillPanel(withUnsent(st));
  if (rebuild) buildVolumes(); else syncVolumes();
  keyCtl.name(`Add keyframe (${st.keyframes})`);
  refreshVolumePanel();
  if (awaitingState) {
    awaitingState = false;
    sendUnsent();
  }
}

// --- messages and frames --------------------------------------------------------------------------------------
let drawing = Promise.resolve();
function onMessage(ev) {
  if (typeof ev.data === 'string') {
    const m = JSON.parse(ev.data);
    test.messages.push(m);
    if (m.type === 'state') onState(m);
    else if (m.type === 'error') { test.errors.push(m.message); say(m.message, true); }
    else if (m.type === 'saved') say(`saved ${m.path}` + (m.notes.length ? ` (${m.notes.join('; ')})` : ''));
    else if (m.type === 'render_progress') say(`rendering still: ${(100 * m.fraction).toFixed(0)}%`);
    else if (m.type === 'render_done') say(`wrote ${m.exr} (${m.seconds.toFixed(1)} s)`);
    else if (m.type === 'keyframes_saved') say(`wrote ${m.shot}: ${m.command}`);
    return;
  }
  const view = new DataView(ev.data);
  const n = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(ev.data, 4, n)));
  // After a reconnect the server renders from its start camera until this page's camera arrives: not this view.
  if (awaitingOwnView && header.camera_from === 0) return;
  awaitingOwnView = false;
  const jpeg = new Blob([new Uint8Array(ev.data, 4 + n)], { type: 'image/jpeg' });
  drawing = drawing.then(async () => {
    const bitmap = await createImageBitmap(jpeg);
    setSize(header.full_width, header.full_height);
    ctx2d.imageSmoothingEnabled = true;
    ctx2d.drawImage(bitmap, 0, 0, imageCanvas.width, imageCanvas.height);
    bitmap.close();
    test.frames++;
    test.header = header;
    // A jump to a scene camera (camera_from 0) moved this page's view: follow it unless this page is moving.
    const idle = performance.now() - lastCameraSent > 1000 && !gizmo.dragging && keys.size === 0;
    if (header.camera_from === 0 || idle) {
      const c = header.camera, p = camera.position;
      if (Math.hypot(c.position[0] - p.x, c.position[1] - p.y, c.position[2] - p.z) > 1e-4 || header.camera_from === 0) {
        const f = new THREE.Vector3(); camera.getWorldDirection(f);
        const df = Math.hypot(c.forward[0] - f.x, c.forward[1] - f.y, c.forward[2] - f.z);
        if (df > 1e-4 || Math.hypot(c.position[0] - p.x, c.position[1] - p.y, c.position[2] - p.z) > 1e-4) applyServerCamera(c);
      }
    }
    const sps = header.samples_per_s;
    statsEl.textContent = `${header.preview ? 'preview ' : ''}${header.width}x${header.height} · ${header.spp}/${header.target_spp} spp · ` +
      `${sps >= 1e6 ? (sps / 1e6).toFixed(2) + ' M' : (sps / 1e3).toFixed(1) + ' k'} samples/s` +
      (header.latency_ms !== undefined ? ` · ${header.latency_ms.toFixed(0)} ms after the change` : '') +
      (state ? ` · ${state.backend}` : '');
  });
}

// nerfpt serve CAPTURE_DIR: a link to the capture's report (the server answers /capture/report.json only then).
fetch('/capture/report.json' + location.search, { method: 'HEAD' }).then((r) => {
  if (!r.ok) return;
  const a = document.getElementById('report-link');
  a.href = '/report.html' + location.search;
  a.hidden = false;
  test.reportLink = true;
}).catch(() => {});

// For the browser test: a pixel of the image as shown (x, y in full-resolution pixels).
test.pixel = (x, y) => Array.from(ctx2d.getImageData(x, y, 1, 1).data.slice(0, 3));
test.select = select;
test.gizmo = gizmo;
test.groups = () => volumeGroups;
test.camera = () => cameraMessage();
// Page coordinates of a world point (for the test's gizmo drag).
test.project = (p) => {
  const v = new THREE.Vector3(...p).project(camera);
  const r = overlay.getBoundingClientRect();
  return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
};

socket.connect();  // last: its handlers use everything above
