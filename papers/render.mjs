// Renders, in headless Chromium (Debian's, driven by playwright-core from the
// viewer build's node_modules), the report's pictures:
//   - PAGE.html=OUT.png: a page `shatter export --format html` wrote (Fig. 6.2),
//     its mesh tree's leaves exploded, every fragment in its own colour;
//   - REC.glb=PREFIX: a `shatter simulate --record` recording (Fig. 6.4), served
//     by `shatter view` (--shatter), one frame at each of --times seconds, written
//     to PREFIX-0.png, PREFIX-1.png, ..., the camera following the pieces.
//
//   node papers/render.mjs --node-modules DIR --chromium PATH [--explode X]
//        [--shatter BIN --times T0,T1,...] PAGE.html=OUT.png ... REC.glb=PREFIX ...
//
// Prints one JSON line per image ({"page", "png", "seconds", "coverage", ...});
// exits 1 when a page fails to load, reports an error on the console, or renders
// blank (a render that shows nothing is a defect, not a figure).

import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

function parse(argv) {
  const options = { explode: 0.6, pages: [], times: [] };
  for (let i = 0; i < argv.length; ++i) {
    const arg = argv[i];
    if (arg === '--node-modules') options.nodeModules = argv[++i];
    else if (arg === '--chromium') options.chromium = argv[++i];
    else if (arg === '--explode') options.explode = Number(argv[++i]);
    else if (arg === '--shatter') options.shatter = argv[++i];
    else if (arg === '--times') options.times = argv[++i].split(',').map(Number);
    else if (arg.includes('=')) {
      const [page, png] = arg.split('=');
      options.pages.push({ page, png });
    } else throw new Error(`unknown argument ${arg}`);
  }
  if (!options.nodeModules || !options.chromium || options.pages.length === 0) {
    throw new Error('usage: node papers/render.mjs --node-modules DIR --chromium PATH [--explode X] '
      + '[--shatter BIN --times T0,T1,...] PAGE.html=OUT.png ... REC.glb=PREFIX ...');
  }
  const recordings = options.pages.filter(({ page }) => page.endsWith('.glb'));
  if (recordings.length > 0 && (!options.shatter || options.times.length === 0
    || options.times.some((t) => !Number.isFinite(t) || t < 0))) {
    throw new Error('a recording needs --shatter BIN (to serve it) and --times with times >= 0 in seconds');
  }
  return options;
}

// The share of the view's pixels that differ from its top-left corner's colour
// (the background): a blank render is close to 0.
async function coverage(page) {
  return page.evaluate(() => {
    const canvas = document.querySelector('canvas');
    const copy = document.createElement('canvas');
    copy.width = canvas.width;
    copy.height = canvas.height;
    const context = copy.getContext('2d');
    context.drawImage(canvas, 0, 0);
    const { data } = context.getImageData(0, 0, copy.width, copy.height);
    let differing = 0;
    for (let i = 0; i < data.length; i += 4) {
      if (Math.abs(data[i] - data[0]) + Math.abs(data[i + 1] - data[1]) + Math.abs(data[i + 2] - data[2]) > 24) ++differing;
    }
    return differing / (data.length / 4);
  });
}

// `shatter view FILE --port 0` serving on a free port: resolves with its address and process.
function serve(shatter, file) {
  return new Promise((resolve, reject) => {
    const proc = spawn(shatter, ['view', file, '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let err = '';
    const timer = setTimeout(() => { proc.kill('SIGINT'); reject(new Error(`shatter view printed no address in 120 s: ${err}`)); },
      120000);
    proc.stdout.on('data', (chunk) => {
      out += chunk;
      const match = /at (http:\/\/127\.0\.0\.1:\d+\/) \(Ctrl-C stops\)/.exec(out);
      if (match) {
        clearTimeout(timer);
        resolve({ url: match[1], proc });
      }
    });
    proc.stderr.on('data', (chunk) => { err += chunk; });
    proc.on('exit', (code) => {
      clearTimeout(timer);
      reject(new Error(`shatter view exited with ${code} before serving: ${err.trim()}`));
    });
  });
}

// Opens `url` in a new page and waits for the viewer to have loaded its file; the
// errors the page reports are collected in the returned list.
async function openViewer(browser, url) {
  const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
  const errors = [];
  page.on('console', (message) => { if (message.type() === 'error') errors.push(message.text()); });
  page.on('pageerror', (error) => errors.push(String(error)));
  await page.goto(url, { timeout: 180000 });
  await page.waitForFunction(() => window.shatterViewer && (window.shatterViewer.ready || window.shatterViewer.error),
    null, { timeout: 180000 });
  const error = await page.evaluate(() => window.shatterViewer.error);
  if (error) errors.push(`viewer: ${error}`);
  return { page, errors };
}

// Hides every part of the page but the canvas, so the image is the model alone.
async function canvasOnly(page) {
  await page.evaluate(() => {
    for (const element of document.querySelectorAll('body > *')) {
      if (!element.querySelector('canvas') && element.tagName !== 'CANVAS') element.style.visibility = 'hidden';
    }
  });
}

const twoFrames = (page) => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

// One frame of a recording per time in `times` (clamped to its duration), the
// camera following the pieces as the viewer does by default.
async function renderRecording(browser, options, file, prefix) {
  const server = await serve(options.shatter, path.resolve(file));
  const results = [];
  try {
    const { page, errors } = await openViewer(browser, server.url);
    await canvasOnly(page);
    const duration = await page.evaluate(() => window.shatterViewer.viewer.replay.duration);
    for (const [k, time] of options.times.entries()) {
      const started = Date.now();
      const shown = Math.min(time, duration);
      await page.evaluate((t) => {
        const element = document.getElementById('time');
        element.value = String(t);
        element.dispatchEvent(new Event('input', { bubbles: true }));
      }, shown);
      await twoFrames(page);
      const png = `${prefix}-${k}.png`;
      await page.locator('canvas').first().screenshot({ path: png });
      const covered = await coverage(page);
      const frameErrors = [...errors];
      if (covered < 0.02) frameErrors.push(`the render is blank (${(100 * covered).toFixed(2)} % of the view drawn)`);
      results.push({ page: file, png, time: shown, duration, seconds: (Date.now() - started) / 1000, coverage: covered,
        errors: frameErrors });
    }
    await page.close();
  } finally {
    server.proc.kill('SIGINT');
  }
  return results;
}

async function main() {
  const options = parse(process.argv.slice(2));
  const require = createRequire(path.join(path.resolve(options.nodeModules), 'package.json'));
  const { chromium } = require('playwright-core');
  const browser = await chromium.launch({
    executablePath: options.chromium,
    headless: true,
    // WebGL on the CPU (SwiftShader): no GPU here; nothing goes to the network.
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--no-first-run', '--allow-file-access-from-files'],
  });
  let failed = false;
  try {
    for (const { page: file, png } of options.pages) {
      if (file.endsWith('.glb')) {
        for (const result of await renderRecording(browser, options, file, png)) {
          console.log(JSON.stringify(result));
          if (result.errors.length > 0) failed = true;
        }
        continue;
      }
      const started = Date.now();
      // preserveDrawingBuffer is off in the viewer: the canvas is read in the same
      // frame it is drawn, after the two frames below.
      const page = await browser.newPage({ viewport: { width: 900, height: 700 } });
      const errors = [];
      page.on('console', (message) => { if (message.type() === 'error') errors.push(message.text()); });
      page.on('pageerror', (error) => errors.push(String(error)));
      await page.goto(pathToFileURL(path.resolve(file)).href, { timeout: 180000 });
      await page.waitForFunction(() => window.shatterViewer && (window.shatterViewer.ready || window.shatterViewer.error),
        null, { timeout: 180000 });
      const error = await page.evaluate(() => window.shatterViewer.error);
      if (error) errors.push(`viewer: ${error}`);
      // The leaves, exploded; the side panels hidden so the image is the model alone.
      await page.evaluate(([explode]) => {
        const set = (id, value) => {
          const element = document.getElementById(id);
          element.value = String(value);
          element.dispatchEvent(new Event('input', { bubbles: true }));
        };
        const depth = document.getElementById('depth');
        set('depth', depth.max);
        set('explode', explode);
        for (const element of document.querySelectorAll('body > *')) {
          if (!element.querySelector('canvas') && element.tagName !== 'CANVAS') element.style.visibility = 'hidden';
        }
        // Framed again around the exploded pieces, which spread past the assembled model's view.
        window.shatterViewer.viewer.frameCamera();
      }, [options.explode]);
      await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
      await page.locator('canvas').first().screenshot({ path: png });
      const covered = await coverage(page);
      if (covered < 0.02) errors.push(`the render is blank (${(100 * covered).toFixed(2)} % of the view drawn)`);
      console.log(JSON.stringify({ page: file, png, seconds: (Date.now() - started) / 1000, coverage: covered, errors }));
      if (errors.length > 0) failed = true;
      await page.close();
    }
  } finally {
    await browser.close();
  }
  process.exit(failed ? 1 : 0);
}

main().catch((error) => {
  console.error(`papers/render.mjs: ${error.message}`);
  process.exit(1);
});
