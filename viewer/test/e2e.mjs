// End-to-end test of `tetcut view`: simulate a scene with cuts, write its page, open the page in
// headless Chromium (Debian's, driven by playwright-core) from file:// with the network off, and
// check through the page's own controls that it draws, colours pieces, shows the tet edges and
// steps frames. Pixels are read from screenshots, so what is checked is what a person would see.
//
//   node viewer/test/e2e.mjs --tetcut build/release/bin/tetcut --scene examples/fig3-progressive-tet.json --work DIR

import { argument, check, failed, launchBrowser } from './harness.mjs';
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, rmSync, statSync } from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const tetcut = path.resolve(argument('tetcut'));
const scene = path.resolve(argument('scene'));
const work = path.resolve(argument('work'));
const browserPath = argument('chromium', '/usr/bin/chromium');

rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
const simDir = path.join(work, 'sim');
// Enough frames to pass the scene's first cuts, so the topology changes between frames.
execFileSync(tetcut, ['sim', scene, '-o', simDir, '--frames', '42'], { stdio: 'inherit' });
execFileSync(tetcut, ['view', simDir], { stdio: 'inherit' });
const page_path = path.join(simDir, 'view.html');
check(existsSync(page_path) && statSync(page_path).size > 100_000, 'tetcut view wrote a page with the viewer inlined');

// A page made from a single mesh file (no frames to step), with the tet edges on by a control.
execFileSync(tetcut, ['view', path.join(simDir, 'mesh_0000.vtu'), '-o', path.join(work, 'mesh.html')], { stdio: 'inherit' });

const browser = await launchBrowser(browserPath);

// Statistics of a screenshot of the 3D view, decoded by the browser itself in a blank page;
// with `reference` (an earlier result), also how many pixels changed from it.
let shots = 0;
async function pixels(page, reference = null) {
  // Kept in the work directory, for a look when a check fails.
  const png = await page.locator('#view canvas').screenshot({ path: path.join(work, `shot_${shots++}.png`) });
  // The control panel floats over the view: its pixels are not the scene's. (The canvas fills the
  // page, so page and canvas coordinates agree.)
  const panel = await page.locator('#panel').boundingBox();
  const reader = await browser.newPage();
  try {
    const stats = await reader.evaluate(async ([base64, before, panel]) => {
      const decode = async (data) => {
        const image = new Image();
        image.src = `data:image/png;base64,${data}`;
        await image.decode();
        const canvas = document.createElement('canvas');
        canvas.width = image.width;
        canvas.height = image.height;
        const context = canvas.getContext('2d');
        context.drawImage(image, 0, 0);
        return context.getImageData(0, 0, image.width, image.height);
      };
      const { data, width } = await decode(base64);
      const old = before ? (await decode(before)).data : null;
      let drawn = 0, saturated = 0, changed = 0;
      const hues = new Set();
      let total = 0;
      for (let i = 0; i < data.length; i += 4) {
        const x = (i / 4) % width, y = Math.floor(i / 4 / width);
        if (x >= panel.x && x < panel.x + panel.width && y >= panel.y && y < panel.y + panel.height) continue;
        total += 1;
        const [r, g, b] = [data[i], data[i + 1], data[i + 2]];
        if (old && old.length === data.length &&
            Math.abs(r - old[i]) + Math.abs(g - old[i + 1]) + Math.abs(b - old[i + 2]) > 30) changed += 1;
        if (Math.abs(r - 242) + Math.abs(g - 242) + Math.abs(b - 242) <= 6) continue;  // background
        drawn += 1;
        const max = Math.max(r, g, b), min = Math.min(r, g, b);
        if (max - min > 40) {
          saturated += 1;
          // Hue in 12 bins: lighting changes brightness, not hue.
          const h = max === r ? ((g - b) / (max - min) + 6) % 6 : max === g ? (b - r) / (max - min) + 2 : (r - g) / (max - min) + 4;
          hues.add(Math.floor(h * 2));
        }
      }
      return { total, drawn, saturated, changed, hues: hues.size };
    }, [png.toString('base64'), reference ? reference.png : null, panel]);
    return { ...stats, png: png.toString('base64') };
  } finally {
    await reader.close();
  }
}

async function open(file) {
  const context = await browser.newContext({ viewport: { width: 900, height: 650 }, offline: true });
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (error) => errors.push(error.message));
  page.on('console', (message) => { if (message.type() === 'error') errors.push(message.text()); });
  page.on('request', (request) => {
    if (!request.url().startsWith('file:') && !request.url().startsWith('data:')) errors.push(`fetched ${request.url()}`);
  });
  await page.goto(pathToFileURL(file).href);
  await page.waitForFunction(() => window.tetcutViewer && (window.tetcutViewer.ready || window.tetcutViewer.error), null,
                             { timeout: 60_000 });
  return { page, errors };
}

try {
  const { page, errors } = await open(page_path);
  const viewer = () => page.evaluate(() => ({ ...window.tetcutViewer }));
  const state = await viewer();
  check(state.ready && !state.error, `the page is ready (error: ${state.error})`);
  check(state.frameCount === 43, `it holds the 43 frames written (${state.frameCount})`);

  const first = await pixels(page);
  check(first.drawn > 0.01 * first.total, `frame 1 draws: ${first.drawn} of ${first.total} pixels are not background`);
  check(first.saturated > 0.5 * first.drawn, `pieces are coloured (${first.saturated} coloured pixels)`);
  check(await page.locator('#frame-label').textContent().then((t) => t.startsWith('frame 1 / 43')), 'the label shows frame 1 / 43');

  // Step with the button and with the keyboard, and jump with the slider.
  await page.click('#next');
  check((await viewer()).frame === 1, 'the next button steps to frame 2');
  await page.keyboard.press('ArrowRight');
  check((await viewer()).frame === 2, 'the right arrow key steps to frame 3');
  await page.keyboard.press('ArrowLeft');
  check((await viewer()).frame === 1, 'the left arrow key steps back to frame 2');
  await page.locator('#slider').fill('42');
  const last = await viewer();
  check(last.frame === 42, `the slider jumps to the last frame (${last.frame})`);
  check((await page.locator('#frame-label').textContent()).startsWith('frame 43 / 43'), 'the label follows');
  const lastPixels = await pixels(page);
  check(lastPixels.drawn > 0.01 * lastPixels.total, 'the last frame draws');
  check(lastPixels.hues > first.hues, `cut pieces appear as new colours (${first.hues} hues at frame 1, ${lastPixels.hues} at frame 43)`);
  const stats = await page.locator('#stats').textContent();
  check(/ 16 pieces/.test(stats), `the last frame has the scene's 16 pieces ("${stats}")`);
  await page.click('#next');
  check((await viewer()).frame === 42, 'stepping past the last frame stays on it');

  // Colour by piece off: one grey material.
  await page.uncheck('#pieces');
  const grey = await pixels(page);
  check(grey.drawn > 0.01 * grey.total && grey.saturated < 0.02 * grey.drawn,
        `without piece colours the surface is grey (${grey.saturated} coloured of ${grey.drawn})`);
  await page.check('#pieces');

  // The embedding tets: their edges darken pixels.
  await page.check('#tets');
  const withTets = await pixels(page, lastPixels);
  check(withTets.changed > 0.002 * withTets.total && withTets.drawn > lastPixels.drawn,
        `the tet edges draw (${withTets.changed} pixels change, ${withTets.drawn - lastPixels.drawn} more drawn)`);
  await page.uncheck('#tets');

  // Play advances frames by itself; pause stops it.
  await page.locator('#slider').fill('0');
  await page.click('#play');
  await page.waitForFunction(() => window.tetcutViewer.frame >= 3, null, { timeout: 20_000 });
  await page.click('#play');
  const paused = (await viewer()).frame;
  await page.waitForTimeout(300);
  check((await viewer()).frame === paused && paused >= 3, `play runs the frames and pause holds them (at frame ${paused + 1})`);
  check(errors.length === 0, `no page errors or network requests (${errors.join('; ')})`);

  // A single mesh file: one frame, the tet edges on request.
  const single = await open(path.join(work, 'mesh.html'));
  const one = await single.page.evaluate(() => ({ ...window.tetcutViewer }));
  check(one.ready && one.frameCount === 1, 'a mesh file gives a one-frame page');
  const boundary = await pixels(single.page);
  await single.page.check('#tets');
  const meshPixels = await pixels(single.page, boundary);
  check(boundary.drawn > 0.01 * boundary.total && meshPixels.changed > 0.002 * meshPixels.total,
        `it draws the boundary, and the tet edges over it (${meshPixels.changed} pixels change)`);
  check(single.errors.length === 0, `no page errors (${single.errors.join('; ')})`);
} finally {
  await browser.close();
}

if (failed() > 0) {
  console.error(`${failed()} check(s) failed`);
  process.exit(1);
}
console.log('viewer end-to-end: all checks passed');
