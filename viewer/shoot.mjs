// The viewer in a real browser: starts `vismask view OUT_DIR`, opens the URL
// it prints in headless Chromium (puppeteer-core, WebGL by SwiftShader),
// waits for the first frame, saves a screenshot and, with --compare, measures
// it against vismask's own image. Prints one JSON object on stdout; the test
// (tests/viewer_test.cpp) and make viewer-screenshot use it.
//
//   node viewer/shoot.mjs --vismask build/vismask --out OUT_DIR
//        --width W --height H --screenshot SHOT.png [--panel] [--aa off]
//        [--compare OUT_DIR/image.png] [--diff DIFF.png] [--chromium PATH]
//        [--drag DX,DY]   (a mouse drag from the centre before the shot: orbits)
//        [--probe-orbit]  (after the shot, a drag; the JSON's orbit gives the
//                          eye and target before and after it)
//
// JSON: url, renderer (WebGL's), console_errors (console.error, uncaught
// exceptions, failed requests and HTTP errors), viewer_error, and with
// --compare the per-channel differences in 8-bit codes: mean_abs (all
// pixels and channels), p50/p90/p99/p999/max of each pixel's largest channel
// difference, and over_16 (the share of pixels whose largest exceeds 16).
// Exit status: 0 when it measured (the test judges the figures), 1 when it
// could not (no URL, no browser, the page never became ready).
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import { PNG } from 'pngjs';
import puppeteer from 'puppeteer-core';

function Args(argv) {
  const a = { panel: false, chromium: '/usr/bin/chromium' };
  for (let i = 2; i < argv.length; ++i) {
    const k = argv[i].replace(/^--/, '');
    if (k === 'panel') a.panel = true;
    else if (k === 'probe-orbit') a[k] = true;
    else a[k] = argv[++i];
  }
  for (const k of ['vismask', 'out', 'width', 'height', 'screenshot'])
    if (!a[k]) throw new Error('shoot.mjs: --' + k + ' is required');
  a.width = Number(a.width);
  a.height = Number(a.height);
  return a;
}

// `vismask view` and the URL it prints first.
function StartServer(bin, out, glb) {
  const args = ['view', out];
  if (glb) args.push('--glb', glb);
  const child = spawn(bin, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stderr = '';
  child.stderr.on('data', (d) => { stderr += d; });
  const url = new Promise((resolve, reject) => {
    let stdout = '';
    const timer = setTimeout(() => reject(new Error('vismask view printed no URL in 30 s: ' + stderr)), 30000);
    child.stdout.on('data', (d) => {
      stdout += d;
      const line = stdout.split('\n');
      if (line.length > 1) {
        clearTimeout(timer);
        resolve(line[0].trim());
      }
    });
    child.on('exit', (code) => {
      clearTimeout(timer);
      reject(new Error('vismask view exited with ' + code + ': ' + stderr));
    });
  });
  return { child, url };
}

function Percentile(sorted, q) {
  return sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];
}

// Differences between two 8-bit images of the same size (alpha ignored).
function Compare(shot, ref, diffPath) {
  if (shot.width !== ref.width || shot.height !== ref.height)
    throw new Error('sizes differ: screenshot ' + shot.width + 'x' + shot.height + ', image ' + ref.width + 'x' + ref.height);
  const n = shot.width * shot.height;
  const worst = new Uint8Array(n);
  let sum = 0, over16 = 0;
  const diff = diffPath ? new PNG({ width: shot.width, height: shot.height }) : null;
  for (let i = 0; i < n; ++i) {
    let m = 0;
    for (let c = 0; c < 3; ++c) {
      const d = Math.abs(shot.data[4 * i + c] - ref.data[4 * i + c]);
      sum += d;
      m = Math.max(m, d);
    }
    worst[i] = m;
    if (m > 16) ++over16;
    if (diff) {
      diff.data.fill(Math.min(255, 4 * m), 4 * i, 4 * i + 3);
      diff.data[4 * i + 3] = 255;
    }
  }
  if (diff) fs.writeFileSync(diffPath, PNG.sync.write(diff));
  const sorted = Array.from(worst).sort((x, y) => x - y);
  return {
    mean_abs: sum / (3 * n), p50: Percentile(sorted, 0.5), p90: Percentile(sorted, 0.9),
    p99: Percentile(sorted, 0.99), p999: Percentile(sorted, 0.999), max: sorted[n - 1], over_16: over16 / n,
  };
}

async function Main() {
  const a = Args(process.argv);
  const server = StartServer(a.vismask, a.out, a.glb);
  let browser = null;
  try {
    const url = (await server.url) + (a.panel ? '' : '&panel=0') + (a.aa === 'off' ? '&aa=0' : '');
    browser = await puppeteer.launch({
      executablePath: a.chromium,
      headless: true,
      // As root Chromium needs --no-sandbox; WebGL without a GPU is
      // SwiftShader's, which newer Chromium enables only when asked.
      args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--hide-scrollbars',
             '--force-color-profile=srgb'],
    });
    const page = await browser.newPage();
    const errors = [];
    page.on('console', (m) => { if (m.type() === 'error') errors.push('console: ' + m.text()); });
    page.on('pageerror', (e) => errors.push('exception: ' + e.message));
    page.on('requestfailed', (r) => errors.push('request failed: ' + r.url() + ' ' + (r.failure() || {}).errorText));
    page.on('response', (r) => { if (r.status() >= 400) errors.push('HTTP ' + r.status() + ': ' + r.url()); });
    await page.setViewport({ width: a.width, height: a.height, deviceScaleFactor: 1 });
    await page.goto(url, { waitUntil: 'load', timeout: 30000 });
    await page.waitForFunction('window.vismaskViewer && (window.vismaskViewer.ready || window.vismaskViewer.error)',
                               { timeout: 30000 });
    const info = await page.evaluate(() => {
      const gl = document.querySelector('canvas').getContext('webgl2');
      const ext = gl && gl.getExtension('WEBGL_debug_renderer_info');
      return {
        error: window.vismaskViewer.error,
        renderer: gl ? gl.getParameter(ext ? ext.UNMASKED_RENDERER_WEBGL : gl.RENDERER) : null,
      };
    });
    const drag = async (spec) => {
      const [dx, dy] = spec.split(',').map(Number);
      const x = a.width / 2, y = a.height / 2;
      await page.mouse.move(x, y);
      await page.mouse.down();
      for (let i = 1; i <= 10; ++i) await page.mouse.move(x + dx * i / 10, y + dy * i / 10);
      await page.mouse.up();
      // Two frames: the one drawn after the drag, presented.
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    };
    if (a.drag) await drag(a.drag);
    await page.screenshot({ path: a.screenshot, type: 'png' });
    const result = { url, renderer: info.renderer, viewer_error: info.error, console_errors: errors };
    if (a['probe-orbit'] !== undefined) {
      const before = await page.evaluate(() => window.vismaskViewer.view());
      await drag('-40,10');
      result.orbit = { before, after: await page.evaluate(() => window.vismaskViewer.view()) };
    }
    if (a.compare) {
      const shot = PNG.sync.read(fs.readFileSync(a.screenshot));
      const ref = PNG.sync.read(fs.readFileSync(a.compare));
      Object.assign(result, Compare(shot, ref, a.diff));
    }
    process.stdout.write(JSON.stringify(result) + '\n');
  } finally {
    if (browser) await browser.close();
    server.child.kill('SIGTERM');
  }
}

Main().catch((e) => {
  process.stderr.write('shoot.mjs: ' + (e.stack || e) + '\n');
  process.exit(1);
});
