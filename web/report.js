// The report of a finished capture (nerfpt serve CAPTURE_DIR): /capture/report.json (src/serve/capture_report.h)
// shown as the stage table the live-training page uses (stages.js), the held-out views' PSNR/SSIM with eval's
// truth | render | error images, and the turntable video. Exposes window.nerfpt for the browser test.
import { fmtTime, fillStages } from '/stages.js';

const $ = (id) => document.getElementById(id);
const test = { report: null, error: null, video: null };
window.nerfpt = test;
const fmt = (v, d) => (v == null || !isFinite(v) ? '–' : v.toFixed(d));

$('back').href = '/' + location.search;

function showEval(ev) {
  if (!ev) return;
  $('eval-box').hidden = false;
  const size = ev.width && ev.height ? ` at ${ev.width}x${ev.height}` : '';
  $('eval-title').textContent = `${ev.views} held-out views${size}: mean PSNR ${fmt(ev.psnr, 2)} dB, SSIM ${fmt(ev.ssim, 4)} ` +
    '(over a white background, sRGB values)';
  const body = $('eval-table').tBodies[0];
  for (const v of ev.images) {
    const tr = body.insertRow();
    tr.insertCell().textContent = v.name;
    tr.insertCell().textContent = fmt(v.psnr, 2);
    tr.insertCell().textContent = fmt(v.ssim, 4);
    const links = tr.insertCell();
    for (const [key, label] of [['render', 'render'], ['compare', 'comparison'], ['alpha', 'alpha']]) {
      if (!v[key]) continue;
      const a = document.createElement('a');
      a.href = v[key]; a.textContent = label; a.target = '_blank';
      links.append(a, ' ');
    }
    if (!v.compare) continue;
    const fig = document.createElement('figure');
    const img = document.createElement('img');
    img.src = v.compare;
    img.alt = `${v.name}: truth | render | error`;
    img.className = 'strip';
    const cap = document.createElement('figcaption');
    cap.textContent = `${v.name}: truth | render | error ×4 · PSNR ${fmt(v.psnr, 2)} dB · SSIM ${fmt(v.ssim, 4)}`;
    fig.append(img, cap);
    $('strips').append(fig);
  }
}

function showTurntable(t) {
  if (!t) return;
  $('turntable-box').hidden = false;
  $('turntable-title').textContent = `turntable: ${t.file}, ${t.frames} frames of ${t.res}` +
    (t.object ? ' (the object alone)' : '');
  const video = $('turntable');
  const note = $('turntable-note');
  test.video = 'loading';
  video.addEventListener('loadeddata', () => { test.video = 'playable'; });
  video.addEventListener('error', () => {
    test.video = 'error';
    note.textContent = 'this browser cannot play it (H.264 in MP4): download it from the link';
  });
  video.src = t.url;
  const a = document.createElement('a');
  a.href = t.url; a.textContent = t.file; a.download = t.file;
  note.append(a);
}

try {
  const res = await fetch('/capture/report.json' + location.search);
  if (!res.ok) throw new Error(`/capture/report.json: HTTP ${res.status} (is this nerfpt serve of a capture's folder?)`);
  const r = await res.json();
  test.report = r;
  document.title = r.title;
  $('title').textContent = r.title;
  fillStages($('stages'), r.stages);
  $('total').textContent = `total ${fmtTime(r.total_seconds)} (${fmt(r.total_seconds, 1)} s) · the model: ${r.model}` +
    (r.scene_model ? ` (the whole scene: ${r.scene_model})` : '') +
    (r.object ? ` · the object ${fmt(r.object.metric ? r.object.height_m : r.object.height, 3)} ${r.object.metric ? 'm' : 'capture units'} high` : '');
  if (r.report_md) { $('report-md').href = r.report_md; $('report-md').hidden = false; }
  showEval(r.eval);
  showTurntable(r.turntable);
  for (const n of r.notes) { const li = document.createElement('li'); li.textContent = n; $('notes').append(li); }
  $('status').textContent = '';
} catch (e) {
  test.error = String(e.message || e);
  $('status').textContent = test.error;
}
