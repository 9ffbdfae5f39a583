// nerfpt serve CAPTURE_DIR in headless chromium: a capture's folder made from the training test's model (live.npt,
// lego at 1/8) with eval's real output on 2 held-out views, a 4-frame turntable from nerfpt view and a
// capture.json written here. The viewer links the report; the report lists the stages and the views' metrics,
// a held-out comparison image loads, and the video is played when this chromium decodes H.264 (said, not
// failed, when it cannot). Screenshot: $SHOTS/serve_report.png.
import { spawn, execFileSync } from 'node:child_process';
import { copyFileSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';

const { NERFPT, LEGO, WORK, SHOTS, CHROMIUM } = process.env;
const fail = (msg) => { console.error('FAILED: ' + msg); process.exitCode = 1; throw new Error(msg); };
const check = (ok, msg) => { if (!ok) fail(msg); console.log('ok: ' + msg); };

const dir = `${WORK}/capture`;
rmSync(dir, { recursive: true, force: true });
mkdirSync(dir, { recursive: true });
copyFileSync(`${WORK}/live.npt`, `${dir}/model.npt`);
const t0 = Date.now();
execFileSync(NERFPT, ['eval', `${dir}/model.npt`, LEGO, '--split', 'test', '--every', '100', '--downscale', '8',
  '-o', `${dir}/eval`, '-q', '--threads', '2'], { stdio: 'inherit' });
execFileSync(NERFPT, ['view', `${dir}/model.npt`, '-o', `${dir}/turntable.mp4`, '--orbit', '4', '--res', '64x64',
  '--threads', '2', '-q'], { stdio: 'inherit' });
console.log(`made the capture's eval and turntable in ${((Date.now() - t0) / 1000).toFixed(1)} s`);
const metrics = JSON.parse(readFileSync(`${dir}/eval/metrics.json`, 'utf8'));
writeFileSync(`${dir}/capture.json`, JSON.stringify({
  version: 1, video: '/videos/lego.mp4',
  stages: {
    curate: { kept: 100, decoded: 200, video_frames: 600, seconds: 10 },
    poses: { frames: 100, registered: 100, points: 5000, reprojection_px: 0.6, path_jumps: 0, extraction_seconds: 2,
      matching_seconds: 5, mapping_seconds: 20, seconds: 27 },
    split: { every: 8, train: 88, test: 12 },
    train: { steps: 120, seconds: 60, downscale: 8, width: 100, height: 100 },
    eval: { views: metrics.images.length, psnr: metrics.mean.psnr, ssim: metrics.mean.ssim, seconds: metrics.seconds },
    turntable: { file: 'turntable.mp4', frames: 4, res: '64x64', object: false, elevation_deg: 20, distance: 4, seconds: 3 },
  },
}, null, 2));
writeFileSync(`${dir}/report.md`, '# nerfpt capture of /videos/lego.mp4\n');

const server = spawn(NERFPT, ['serve', dir, '--port', '0', '--preview', '2', '--res', '80x60', '--threads', '2'],
  { stdio: ['ignore', 'pipe', 'inherit'] });
let out = '';
const [viewerUrl, reportUrl] = await new Promise((resolve, reject) => {
  server.stdout.on('data', (d) => {
    out += d;
    const v = out.match(/ at (http:\/\/\S+)\n/), r = out.match(/report at (http:\/\/\S+)/);
    if (v && r) resolve([v[1], r[1]]);
  });
  server.on('exit', (code) => reject(new Error('nerfpt serve exited with ' + code)));
  setTimeout(() => reject(new Error('nerfpt serve printed no URLs in 30 s')), 30000).unref();  // not kept waiting
});
console.log(`serving the capture at ${viewerUrl}, its report at ${reportUrl}`);
const browser = await puppeteer.launch({
  executablePath: CHROMIUM, headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--window-size=1200,900',
    '--autoplay-policy=no-user-gesture-required'],
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1200, height: 900 });
  page.on('pageerror', (e) => console.error('page error: ' + e.message));
  await page.goto(viewerUrl);
  await page.waitForFunction(() => window.nerfpt && window.nerfpt.frames > 0 && window.nerfpt.reportLink, { timeout: 30000 });
  const href = await page.evaluate(() => document.getElementById('report-link').href);
  check(href.startsWith(reportUrl.split('?')[0]), `the viewer shows the model and links the report (${href})`);

  await page.goto(reportUrl);
  await page.waitForFunction(() => window.nerfpt && (window.nerfpt.report || window.nerfpt.error), { timeout: 30000 });
  const err = await page.evaluate(() => window.nerfpt.error);
  check(!err, `the report loads${err ? ': ' + err : ''}`);
  const rows = await page.evaluate(() => [...document.querySelectorAll('#stages tr')].map((tr) => tr.cells[1].textContent));
  check(rows.length === 8 && rows.filter((s) => s === 'done').length === 6, `the stage table: ${rows.join(', ')}`);
  const evalRows = await page.evaluate(() => document.getElementById('eval-table').tBodies[0].rows.length);
  check(evalRows === metrics.images.length, `${evalRows} held-out views with their PSNR/SSIM`);
  await page.waitForFunction(() => { const i = document.querySelector('img.strip'); return i && i.complete && i.naturalWidth > 0; },
    { timeout: 30000 });
  const w = await page.evaluate(() => document.querySelector('img.strip').naturalWidth);
  check(w === 3 * metrics.width, `the held-out comparison image loads (${w} px wide: truth | render | error)`);
  await page.waitForFunction(() => window.nerfpt.video !== 'loading', { timeout: 30000 });
  const video = await page.evaluate(() => ({ state: window.nerfpt.video, w: document.getElementById('turntable').videoWidth,
    mp4: document.createElement('video').canPlayType('video/mp4; codecs="avc1.64001e"') }));
  if (video.state === 'playable') check(video.w === 64, `the turntable plays (H.264 in MP4, ${video.w} px wide)`);
  else console.log(`note: this chromium cannot play the turntable (canPlayType H.264: "${video.mp4}"): the page says so`);
  await page.screenshot({ path: `${SHOTS}/serve_report.png`, fullPage: true });
} finally {
  await browser.close();
  server.kill('SIGINT');
}
