// nerfpt serve's page in headless chromium: it loads, frames arrive, a pixel of the constant-emission wall has
// the wall's colour, a drag moves the camera, a dropped socket is reopened by the page (its own view kept), a
// gizmo drag saved and rendered by `nerfpt render` moves the cube, and the page outlives a restart of nerfpt
// serve (an edit made meanwhile reaches the new server). Screenshots go to $SHOTS (docs/images/ when run for the
// README).
import { spawn, execFileSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import puppeteer from 'puppeteer-core';

const { NERFPT, SCENE, SHOTS, CHROMIUM } = process.env;
const fail = (msg) => { console.error('FAILED: ' + msg); process.exitCode = 1; throw new Error(msg); };
const check = (ok, msg) => { if (!ok) fail(msg); console.log('ok: ' + msg); };

// nerfpt serve on `port` (0: any); resolves to the process and the URL it prints.
const startServer = (port) => new Promise((resolve, reject) => {
  const proc = spawn(NERFPT, ['serve', SCENE, '--port', String(port), '--preview', '2'], { stdio: ['ignore', 'pipe', 'inherit'] });
  let out = '';
  proc.stdout.on('data', (d) => { out += d; const m = out.match(/at (http:\/\/\S+)/); if (m) resolve({ proc, url: m[1] }); });
  proc.on('exit', (code) => reject(new Error('nerfpt serve exited with ' + code)));
  setTimeout(() => reject(new Error('nerfpt serve printed no URL in 30 s')), 30000);
});
let { proc: server, url } = await startServer(0);
console.log('serving at ' + url);
const browser = await puppeteer.launch({
  executablePath: CHROMIUM, headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--window-size=1200,800'],
});
let page = null;
try {
  page = await browser.newPage();
  await page.setViewport({ width: 1200, height: 800 });
  page.on('pageerror', (e) => console.error('page error: ' + e.message));
  // Why a socket ended, when it does: chromium says so in the console when it fails a WebSocket; a crashed
  // renderer closes the page's socket too (the server logs "Close frame, code 1001" for it and for an unload).
  page.on('error', (e) => console.error('page crashed: ' + e.message));
  page.on('console', (m) => { if (/WebSocket/.test(m.text())) console.error('page console: ' + m.text()); });
  await page.goto(url);
  // The wall's linear (0.5, 0.25, 0.125) through the sRGB curve: (188, 137, 99).
  await page.waitForFunction(() => window.nerfpt && window.nerfpt.header && window.nerfpt.header.spp >= 4, { timeout: 30000 });
  const wall = await page.evaluate(() => window.nerfpt.pixel(130, 100));
  const near = (a, b, tol) => a.every((v, k) => Math.abs(v - b[k]) <= tol);
  check(near(wall, [188, 137, 99], 6), `wall pixel ${wall} is the wall's colour (188,137,99) within JPEG error`);
  const cubeX = Math.round(80 - 60 / (5 * Math.tan(Math.PI / 9)));
  const cube = await page.evaluate((x) => window.nerfpt.pixel(x, 60), cubeX);
  check(cube.every((v) => v >= 240), `cube pixel ${cube} at (${cubeX}, 60) is white`);
  await page.screenshot({ path: `${SHOTS}/serve_viewer.png` });

  // The panel's "show" list: the normal view paints the wall (facing +z) (0.5, 0.5, 1) -> (128, 128, 255); back
  // to the render after.
  const show = async (view) => {
    const framesBefore = await page.evaluate(() => window.nerfpt.frames);
    await page.evaluate((v) => {
      const ctl = [...document.querySelectorAll('.lil-controller')].find((c) => c.querySelector('.lil-name')?.textContent === 'show');
      const sel = ctl.querySelector('select');
      sel.selectedIndex = [...sel.options].findIndex((o) => o.textContent === v);
      sel.dispatchEvent(new Event('change'));
    }, view);
    await page.waitForFunction((v, n) => window.nerfpt.state.view === v && window.nerfpt.frames > n + 1 &&
      window.nerfpt.header.spp >= 4 && !window.nerfpt.header.preview, { timeout: 30000 }, view, framesBefore);
  };
  await show('normal');
  const normal = await page.evaluate(() => window.nerfpt.pixel(130, 100));
  check(near(normal, [128, 128, 255], 6), `normal view: the wall pixel ${normal} is (128,128,255)`);
  await page.screenshot({ path: `${SHOTS}/serve_normals.png` });
  await show('beauty');

  // A drag on the view orbits the camera: a frame from another camera arrives.
  const before = await page.evaluate(() => window.nerfpt.header.camera.position);
  const box = await (await page.$('#overlay')).boundingBox();
  await page.mouse.move(box.x + box.width * 0.7, box.y + box.height * 0.8);
  await page.mouse.down();
  for (let i = 1; i <= 10; ++i) await page.mouse.move(box.x + box.width * 0.7 + 15 * i, box.y + box.height * 0.8, { steps: 2 });
  await page.mouse.up();
  await page.waitForFunction((p) => {
    const c = window.nerfpt.header.camera.position;
    return Math.hypot(c[0] - p[0], c[1] - p[1], c[2] - p[2]) > 0.05;
  }, { timeout: 20000 }, before);
  const after = await page.evaluate(() => window.nerfpt.header.camera.position);
  check(true, `a drag moved the camera from [${before.map((v) => v.toFixed(2))}] to [${after.map((v) => v.toFixed(2))}]`);

  // The server drops the page's socket (a message over its size limit: Beast fails the connection), and an edit
  // sent right behind that message is lost with it. The page reconnects, the server greets it as a new page (a
  // view from the start camera), and the page puts its own camera back and sends the edit again: frames resume
  // from where the page looks. A frame's camera_from names the connection whose camera it was rendered from (0:
  // the server's start camera).
  const own = await page.evaluate(() => window.nerfpt.camera().position);
  const fromBefore = await page.evaluate(() => window.nerfpt.header.camera_from);
  await page.evaluate(() => {
    window.nerfpt.send({ type: 'camera', pad: 'x'.repeat(70 * 1024) });
    window.nerfpt.send({ type: 'settings', exposure: 0.25 });
  });
  await page.waitForFunction((from, p) => {
    const t = window.nerfpt, h = t.header, c = h.camera.position;
    return t.connects === 2 && h.camera_from !== from && h.camera_from !== 0 && h.spp >= 1 &&
      Math.hypot(c[0] - p[0], c[1] - p[1], c[2] - p[2]) < 1e-3 && t.state.exposure === 0.25;
  }, { timeout: 30000 }, fromBefore, own);
  const drop = await page.evaluate(() => ({ connects: window.nerfpt.connects, closes: window.nerfpt.closes, at: window.nerfpt.camera().position }));
  check(drop.connects === 2 && drop.closes.length === 1, `the page reconnected after the server dropped its socket (close code ${drop.closes[0]?.code})`);
  const moved = Math.hypot(...drop.at.map((v, k) => v - own[k]));
  check(moved < 1e-6, `frames resumed from the page's own camera [${own.map((v) => v.toFixed(2))}] (it moved ${moved.toExponential(1)}), the lost edit applied`);

  // Back to the scene's camera; select the cube and drag its gizmo's X arrow to the right.
  await page.evaluate(() => window.nerfpt.send({ type: 'use_camera', index: 0 }));
  await page.waitForFunction(() => Math.abs(window.nerfpt.header.camera.position[0]) < 1e-6 && window.nerfpt.header.spp >= 1, { timeout: 20000 });
  await new Promise((r) => setTimeout(r, 300));
  await page.evaluate(() => window.nerfpt.select(0));
  await new Promise((r) => setTimeout(r, 200));
  const [sx, sy] = await page.evaluate(() => window.nerfpt.project([-1 + 0.42, 0, 0]));
  await page.mouse.move(sx, sy);
  await page.mouse.down();
  for (let i = 1; i <= 20; ++i) await page.mouse.move(sx + 20 * i, sy, { steps: 2 });
  await page.mouse.up();
  await page.waitForFunction(() => window.nerfpt.state.volumes[0].translation[0] > 0.2, { timeout: 20000 });
  const tx = await page.evaluate(() => window.nerfpt.state.volumes[0].translation[0]);
  check(true, `the gizmo drag moved the cube to x = ${tx.toFixed(3)}`);
  await page.waitForFunction(() => window.nerfpt.header.spp >= 4, { timeout: 30000 });
  await page.screenshot({ path: `${SHOTS}/serve_gizmo.png` });
  const savedBefore = await page.evaluate(() => window.nerfpt.messages.filter((m) => m.type === 'saved').length);
  await page.evaluate(() => window.nerfpt.send({ type: 'save' }));
  await page.waitForFunction((n) => window.nerfpt.messages.filter((m) => m.type === 'saved').length > n, { timeout: 20000 }, savedBefore);
  // Where the cube was saved: the drag sends the gizmo's position once per animation frame, and on a loaded
  // machine the state read above can be one of the drag's earlier positions; every move sent before the save
  // has been applied (and its state sent) by the time the save's reply arrives.
  const txSaved = await page.evaluate(() => window.nerfpt.state.volumes[0].translation[0]);
  check(txSaved >= tx, `saved with the cube at x = ${txSaved.toFixed(3)}`);

  // nerfpt render of the saved file: the cube where the gizmo put it, the wall where it was.
  const out = SCENE.replace(/scene\.json$/, 'saved_render.exr');
  execFileSync(NERFPT, ['render', SCENE, '-o', out, '--spp', '1', '-q']);
  const png = readFileSync(out.replace(/\.exr$/, '.png')).toString('base64');
  const xNew = Math.round(80 + txSaved * 60 / (5 * Math.tan(Math.PI / 9)));
  const pixels = await page.evaluate(async (data, xs) => {
    const img = new Image();
    img.src = 'data:image/png;base64,' + data;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width; c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    return xs.map((x) => Array.from(g.getImageData(x, 60, 1, 1).data.slice(0, 3)));
  }, png, [xNew, cubeX]);
  check(pixels[0].every((v) => v >= 240), `rendered saved scene: the cube at x pixel ${xNew} (${pixels[0]})`);
  check(near(pixels[1], [188, 137, 99], 2), `rendered saved scene: the wall where the cube was (${pixels[1]})`);

  // nerfpt serve stops (killed) and runs again on the same port: the page says it is reconnecting, keeps an
  // edit made meanwhile, and sends it to the new server once it is back.
  const port = new URL(url).port;
  const statusText = () => page.evaluate(() => document.getElementById('status').textContent);
  const framesBeforeKill = await page.evaluate(() => window.nerfpt.frames);
  server.kill('SIGKILL');
  await page.waitForFunction(() => /reconnecting to nerfpt serve/.test(document.getElementById('status').textContent), { timeout: 30000 });
  check(true, `while nerfpt serve is down the page says "${await statusText()}"`);
  await page.evaluate(() => window.nerfpt.send({ type: 'settings', exposure: 1 }));
  ({ proc: server } = await startServer(port));
  await page.waitForFunction((n) => window.nerfpt.connects === 3 && window.nerfpt.frames > n && window.nerfpt.state.exposure === 1,
    { timeout: 30000 }, framesBeforeKill);
  const back = await page.evaluate(() => window.nerfpt.state.volumes[0].translation[0]);
  check(Math.abs(back - txSaved) < 1e-4, `reconnected to the restarted nerfpt serve: its state (the saved cube at x = ${back.toFixed(3)}) and the exposure set while it was down`);
} catch (e) {
  // What the page knew about its socket, for a failure that is about it (a crashed page never answers).
  const diag = page && await Promise.race([
    page.evaluate(() => window.nerfpt && ({ connects: window.nerfpt.connects, closes: window.nerfpt.closes,
      frames: window.nerfpt.frames, status: document.getElementById('status').textContent })),
    new Promise((resolve) => setTimeout(() => resolve('no answer in 5 s'), 5000))]).catch((d) => 'unreachable: ' + d.message);
  console.error('the page at the failure: ' + JSON.stringify(diag));
  throw e;
} finally {
  await browser.close();
  server.kill();
}
