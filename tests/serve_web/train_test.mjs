// nerfpt train --serve's page in headless chromium: a short CPU training of NeRF-synthetic lego at 1/8 size;
// the page shows the loss chart growing, the held-out strip (truth | render | error) arriving and updating,
// an orbit render after a drag, reconnects after the server drops its socket, says when training has finished,
// and says plainly that nerfpt has stopped once it has. Screenshot: $SHOTS/serve_training.png.
import { spawn } from 'node:child_process';
import puppeteer from 'puppeteer-core';

const { NERFPT, LEGO, WORK, SHOTS, CHROMIUM } = process.env;
const fail = (msg) => { console.error('FAILED: ' + msg); process.exitCode = 1; throw new Error(msg); };
const check = (ok, msg) => { if (!ok) fail(msg); console.log('ok: ' + msg); };

const server = spawn(NERFPT, ['train', LEGO, '-o', `${WORK}/live.npt`, '--force', '--steps', '120', '--downscale', '8',
  '--serve', '--port', '0', '--serve-eval-every', '2', '--serve-eval-share', '0.5', '--threads', '2'], { stdio: ['ignore', 'pipe', 'inherit'] });
let out = '';
const url = await new Promise((resolve, reject) => {
  server.stdout.on('data', (d) => { out += d; const m = out.match(/page at (http:\/\/\S+)/); if (m) resolve(m[1]); });
  server.on('exit', (code) => reject(new Error('nerfpt train --serve exited with ' + code)));
  setTimeout(() => reject(new Error('nerfpt train --serve printed no URL in 60 s')), 60000);
});
console.log('training page at ' + url);
const browser = await puppeteer.launch({
  executablePath: CHROMIUM, headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--window-size=1200,800'],
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1200, height: 800 });
  page.on('pageerror', (e) => console.error('page error: ' + e.message));
  await page.goto(url);
  await page.waitForFunction(() => window.nerfpt && window.nerfpt.trains > 0 && window.nerfpt.chartPoints > 0, { timeout: 120000 });
  const first = await page.evaluate(() => ({ points: window.nerfpt.chartPoints, step: window.nerfpt.lastTrain.step }));
  await page.waitForFunction((n) => window.nerfpt.chartPoints > n, { timeout: 120000 }, first.points);
  const later = await page.evaluate(() => window.nerfpt.chartPoints);
  check(later > first.points, `the loss chart grows: ${first.points} -> ${later} points`);
  await page.waitForFunction(() => window.nerfpt.strips >= 1 && document.getElementById('strip').naturalWidth > 0, { timeout: 120000 });
  const e1 = await page.evaluate(() => window.nerfpt.lastEval);
  check(Number.isFinite(e1.psnr) && e1.split === 'test', `held-out PSNR ${e1.psnr.toFixed(2)} dB at step ${e1.step} (split ${e1.split})`);
  const w = await page.evaluate(() => document.getElementById('strip').naturalWidth);
  check(w === 3 * e1.strip_height, `the strip is three views wide (${w} px)`);
  // A drag on the orbit view: a render of the current model from the new camera.
  const box = await (await page.$('#orbit-box')).boundingBox();
  const framesBefore = await page.evaluate(() => window.nerfpt.frames);
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 8; ++i) await page.mouse.move(box.x + box.width / 2 + 10 * i, box.y + box.height / 2, { steps: 2 });
  await page.mouse.up();
  await page.waitForFunction((n) => window.nerfpt.frames > n, { timeout: 60000 }, framesBefore);
  check(true, 'a drag on the orbit view brought a render of the current model');
  // The server drops the page's socket (a message over its size limit): the page reconnects, takes the state
  // again and re-sends its orbit camera, so status messages and an orbit render follow.
  const at = await page.evaluate(() => ({ trains: window.nerfpt.trains, frames: window.nerfpt.frames }));
  await page.evaluate(() => window.nerfpt.send({ type: 'camera', pad: 'x'.repeat(70 * 1024) }));
  await page.waitForFunction((a) => window.nerfpt.connects === 2 && window.nerfpt.trains > a.trains && window.nerfpt.frames > a.frames,
    { timeout: 60000 }, at);
  check(true, 'the page reconnected after the server dropped its socket: status and an orbit render follow');
  await page.waitForFunction((s) => window.nerfpt.strips >= 2 && window.nerfpt.lastEval.step > s, { timeout: 180000 }, e1.step);
  const e2 = await page.evaluate(() => window.nerfpt.lastEval);
  check(true, `the strip updated: step ${e1.step} -> ${e2.step}, PSNR ${e1.psnr.toFixed(2)} -> ${e2.psnr.toFixed(2)} dB`);
  await page.waitForFunction(() => window.nerfpt.finished === true, { timeout: 300000 });
  await page.waitForFunction(() => window.nerfpt.lastEval && window.nerfpt.lastEval.step >= 120, { timeout: 120000 });
  const banner = await page.evaluate(() => document.getElementById('banner').textContent);
  check(/finished/.test(banner), `the page says training finished ("${banner.slice(0, 40)}…")`);
  check(/stays up until Ctrl-C/.test(out), 'nerfpt keeps serving after training');
  await new Promise((r) => setTimeout(r, 500));
  await page.screenshot({ path: `${SHOTS}/serve_training.png` });
  // nerfpt stops: after a few tries the page says so.
  server.kill('SIGINT');
  await page.waitForFunction(() => /nerfpt has stopped/.test(document.getElementById('status').textContent), { timeout: 30000 });
  check(true, `once nerfpt has stopped the page says "${(await page.evaluate(() => document.getElementById('status').textContent)).slice(0, 60)}…"`);
} finally {
  await browser.close();
  server.kill('SIGINT');
}
