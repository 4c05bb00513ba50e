// Renders pages that `shatter export --format html` wrote, in headless Chromium
// (Debian's, driven by playwright-core from the viewer build's node_modules), for
// the report's Fig. 2: each mesh tree exploded, every fragment in its own colour.
//
//   node papers/render.mjs --node-modules DIR --chromium PATH --explode X PAGE.html=OUT.png ...
//
// Prints one JSON line per image ({"page", "png", "seconds"}); exits 1 when a page
// fails to load, reports an error on the console, or renders blank (a render that
// shows nothing is a defect, not a figure).

import { createRequire } from 'node:module';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

function parse(argv) {
  const options = { explode: 0.6, pages: [] };
  for (let i = 0; i < argv.length; ++i) {
    const arg = argv[i];
    if (arg === '--node-modules') options.nodeModules = argv[++i];
    else if (arg === '--chromium') options.chromium = argv[++i];
    else if (arg === '--explode') options.explode = Number(argv[++i]);
    else if (arg.includes('=')) {
      const [page, png] = arg.split('=');
      options.pages.push({ page, png });
    } else throw new Error(`unknown argument ${arg}`);
  }
  if (!options.nodeModules || !options.chromium || options.pages.length === 0) {
    throw new Error('usage: node papers/render.mjs --node-modules DIR --chromium PATH [--explode X] PAGE.html=OUT.png ...');
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
