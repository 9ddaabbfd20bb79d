// End-to-end test of `tetcut serve`: start it on a free port with the default scene (the femur),
// open its page in headless Chromium (Debian's, driven by playwright-core) with every request off
// 127.0.0.1 refused, and work it with real mouse events: pull the top with the hook and see the
// surface move, drag the scalpel across the shaft until it is in two pieces (checked from
// /api/state and from the page's pixels: two piece colours), download the recording and replay
// it with `tetcut sim` to the same pieces (two that hold the material, and at most fragments
// besides: see the scalpel below), and stop the server with Ctrl-C, which writes
// its own recording. Prints frames received per second and how soon cuts were seen.
//
//   node viewer/test/live_e2e.mjs --tetcut build/release/bin/tetcut --work DIR

import { argument, check, failed, launchBrowser } from './harness.mjs';
import { execFileSync, spawn } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import path from 'node:path';

const tetcut = path.resolve(argument('tetcut'));
const work = path.resolve(argument('work'));
const browserPath = argument('chromium', '/usr/bin/chromium');
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));
// A timeout that does not keep the process alive once everything else is done.
const deadline = (ms) => new Promise((resolve) => setTimeout(resolve, ms).unref());

const median = (values) => {
  const sorted = [...values].sort((a, b) => a - b);
  return sorted.length ? sorted[Math.floor(sorted.length / 2)] : NaN;
};

rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });
const serverRecording = path.join(work, 'server-recording.json');

// --- the server --------------------------------------------------------------------------------
const server = spawn(tetcut, ['serve', '--port', '0', '--record', serverRecording], { stdio: ['ignore', 'pipe', 'pipe'] });
let serverOutput = '';
server.stdout.on('data', (d) => { serverOutput += d; });
server.stderr.on('data', (d) => { serverOutput += d; });
const serverExit = new Promise((resolve) => server.on('exit', (code, signal) => resolve({ code, signal })));
// A check that throws (a timeout) must not leave the server simulating on its own.
process.on('exit', () => { if (server.exitCode === null && server.signalCode === null) server.kill('SIGKILL'); });
let url = null;
for (let waited = 0; !url && waited < 120_000; waited += 100) {
  url = serverOutput.match(/http:\/\/127\.0\.0\.1:\d+\/\?token=[0-9a-f]+/)?.[0] ?? null;
  if (!url) await sleep(100);
}
if (!url) {
  console.log(serverOutput);
  throw new Error('tetcut serve printed no address');
}
const base = new URL(url);
const token = base.searchParams.get('token');
const state = async () => (await fetch(`${base.origin}/api/state?token=${token}`)).json();

check((await fetch(`${base.origin}/`)).status === 403, 'the page without the token: 403');
check((await fetch(`${base.origin}/?token=0123`)).status === 403, 'the page with a wrong token: 403');
check((await fetch(`${base.origin}/api/state`)).status === 403, '/api/state without the token: 403');

const browser = await launchBrowser(browserPath);
const context = await browser.newContext({ viewport: { width: 1000, height: 700 }, acceptDownloads: true });
const offMachine = [];
await context.route('**/*', (route) => {
  const host = new URL(route.request().url()).hostname;
  if (host === '127.0.0.1') return route.continue();
  offMachine.push(route.request().url());
  return route.abort();
});
const page = await context.newPage();
const pageErrors = [];
page.on('pageerror', (error) => pageErrors.push(error.message));
page.on('console', (message) => { if (message.type() === 'error') pageErrors.push(message.text()); });

await page.goto(url);
await page.waitForFunction(() => window.tetcutLive?.ready && window.tetcutLive.framesReceived > 3, null, { timeout: 60_000 });
const live = (expression) => page.evaluate(expression);
check(await live(() => window.tetcutLive.connected), 'the page connected over WebSocket');

// Frames received per second, uncut and idle.
const framesBefore = await live(() => window.tetcutLive.framesReceived);
await sleep(3000);
const idleFps = ((await live(() => window.tetcutLive.framesReceived)) - framesBefore) / 3;
console.log(`     frames received: ${idleFps.toFixed(1)} per second (idle)`);
// Speed is measured, not asserted (this also runs in the sanitizer build): frames keep coming.
check(idleFps >= 1, `the page receives frames as the session runs (${idleFps.toFixed(1)} per second)`);

// Screen points of the model: where the surface is under the cursor along a row at height t
// (0: bottom, 1: top) of the model's box.
async function rowAcross(t) {
  const row = await page.evaluate((t) => {
    const api = window.tetcutLive;
    const { min, max } = api.surfaceBox();
    const centre = [(min[0] + max[0]) / 2, (min[1] + max[1]) / 2, min[2] + t * (max[2] - min[2])];
    const { y } = api.screenOf(centre);
    if (!Number.isFinite(y)) return { error: `the surface's box is ${JSON.stringify({ min, max })}` };
    // A coarse scan, then each edge found to a pixel by bisection (a ray against the whole
    // surface costs milliseconds).
    const hits = [];
    for (let x = 0; x < window.innerWidth; x += 12) if (api.hitAt(x, y)) hits.push(x);
    if (!hits.length) return null;
    const edge = (inside, outside) => {
      while (Math.abs(inside - outside) > 1) {
        const mid = Math.round((inside + outside) / 2);
        if (api.hitAt(mid, y)) inside = mid; else outside = mid;
      }
      return inside;
    };
    return { y, left: edge(hits[0], hits[0] - 12), right: edge(hits[hits.length - 1], hits[hits.length - 1] + 12) };
  }, t);
  if (row?.error) {
    await page.screenshot({ path: path.join(work, `failed_${Date.now()}.png`) });
    throw new Error(`${row.error}; the server's state: ${JSON.stringify(await state())}`);
  }
  return row;
}

// The panel floats over the view: the model is drawn to its right; rows are read there.
const panel = await page.locator('#panel').boundingBox();

// --- pin: hold the top, so that the piece the scalpel frees stays in view -------------------
await page.keyboard.press('3');
{
  const row = await rowAcross(0.95);
  check(row !== null, `the top of the femur is on screen (${JSON.stringify(row)})`);
  await page.mouse.click((row.left + row.right) / 2, row.y);
}

// --- hook: pull the shaft sideways, see the surface move -------------------------------------
await page.keyboard.press('2');
const top = await rowAcross(0.75);
check(top !== null, `the femur is on screen (${JSON.stringify(top)})`);
const boxBefore = await live(() => window.tetcutLive.surfaceBox());
{
  const x = (top.left + top.right) / 2;
  await page.mouse.move(x, top.y);
  await page.mouse.down();
  for (let i = 1; i <= 20; ++i) {
    await page.mouse.move(x + 6 * i, top.y);
    await sleep(30);
  }
  await sleep(800);
  const pulled = await live(() => window.tetcutLive.surfaceBox());
  const moved = Math.max(...[0, 1, 2].map((c) => Math.abs(pulled.max[c] - boxBefore.max[c]) + Math.abs(pulled.min[c] - boxBefore.min[c])));
  check(moved > 0.02 * (boxBefore.max[2] - boxBefore.min[2]), `the hook pulled the surface (its box moved by ${moved.toFixed(3)})`);
  check((await state()).hooks === 1, 'the server holds one hook while the button is down');
  await page.mouse.up();
  await sleep(300);
  check((await state()).hooks === 0, 'letting go released the hook');
}
await sleep(1500);  // let it swing back

// --- scalpel: cut across the shaft until the femur is in two pieces ---------------------------
await page.keyboard.press('1');
let pieces = (await state()).pieces;
check(pieces === 1, 'one piece before the scalpel');
const cutFramesBefore = await live(() => window.tetcutLive.framesReceived);
const cutStart = Date.now();
for (let stroke = 0; stroke < 4 && pieces < 2; ++stroke) {
  const row = await rowAcross(0.55 + 0.04 * stroke);
  if (!row) continue;
  // One stroke from beside the model, across it, to beyond its other side.
  await page.mouse.move(row.left - 30, row.y);
  await page.mouse.down();
  for (let i = 1; i <= 30; ++i) {
    const x = row.left - 30 + ((row.right - row.left + 60) * i) / 30;
    await page.mouse.move(x, row.y);
    await sleep(33);
  }
  await page.mouse.up();
  for (let waited = 0; waited < 3000 && pieces < 2; waited += 100) {
    await sleep(100);
    pieces = (await state()).pieces;
  }
  const after = await state();
  console.log(`     stroke ${stroke + 1} at row ${JSON.stringify(row)}: ${after.pieces} pieces, ${after.cuts} cuts, ${after.tets} tets`);
  await page.screenshot({ path: path.join(work, `stroke_${stroke + 1}.png`) });
}
const cutSeconds = (Date.now() - cutStart) / 1000;
const cutFps = ((await live(() => window.tetcutLive.framesReceived)) - cutFramesBefore) / cutSeconds;
const cuttingState = await state();
// The femur swings and sags as it is cut, at times faster than the blade crosses it, so that the
// blade's path through the material can fold back on itself and cut off a fragment as well (seen
// in about one run in ten: 5 tet copies holding 1e-7 of the volume, replayed exactly by
// `tetcut sim`). So the live count may exceed two; the replay's volumes below tell a fragment
// from a third part.
check(pieces >= 2, `the scalpel cut the femur apart (/api/state: ${pieces} pieces)`);
if (pieces > 2) console.log(`     ${pieces - 2} more piece(s): checked as fragments from the replay's volumes`);
if (pieces < 2) {
  // Kept for diagnosis: the session so far, replayable by `tetcut sim`.
  const kept = path.join(work, 'failed-stroke-recording.json');
  writeFileSync(kept, await (await fetch(`${base.origin}/api/recording?token=${token}`)).text());
  console.log(`     the session so far: ${kept}`);
}
await sleep(1000);  // the freed top swings on its pin
await page.click('#pause');
await page.waitForFunction((n) => window.tetcutLive.stats?.paused === true && window.tetcutLive.pieces === n, pieces, { timeout: 10_000 });
const pausedAt = (await state()).steps;
await sleep(600);
check((await state()).steps === pausedAt, 'pause holds the simulation');

// Pixels: two piece colours on screen (the panel excluded).
const shot = await page.locator('#view canvas').screenshot({ path: path.join(work, 'cut.png') });
const colours = await page.evaluate(async ([base64, panel]) => {
  const image = new Image();
  image.src = `data:image/png;base64,${base64}`;
  await image.decode();
  const canvas = document.createElement('canvas');
  canvas.width = image.width;
  canvas.height = image.height;
  const context = canvas.getContext('2d');
  context.drawImage(image, 0, 0);
  const { data, width } = context.getImageData(0, 0, image.width, image.height);
  const hues = new Map();
  for (let i = 0; i < data.length; i += 4) {
    const x = (i / 4) % width, y = Math.floor(i / 4 / width);
    if (x < panel.x + panel.width + 4 && y < panel.y + panel.height + 4) continue;
    const r = data[i] / 255, g = data[i + 1] / 255, b = data[i + 2] / 255;
    const max = Math.max(r, g, b), min = Math.min(r, g, b);
    if (max - min < 0.25) continue;  // grey: background, shadows
    let hue = 0;
    if (max === r) hue = ((g - b) / (max - min)) % 6;
    else if (max === g) hue = (b - r) / (max - min) + 2;
    else hue = (r - g) / (max - min) + 4;
    const bin = Math.round(((hue * 60 + 360) % 360) / 30) % 12;
    hues.set(bin, (hues.get(bin) ?? 0) + 1);
  }
  return [...hues.entries()].filter(([, n]) => n > 200).map(([bin]) => bin);
}, [shot.toString('base64'), panel]);
check(colours.length >= 2, `two piece colours on screen (hue bins ${colours.join(', ')})`);

const latencies = await live(() => window.tetcutLive.cutLatencies);
const serverState = cuttingState;
console.log(`     while cutting: ${cutFps.toFixed(1)} frames received per second; cuts seen ${median(latencies).toFixed(0)} ms ` +
            `(median of ${latencies.length}, max ${Math.max(...latencies).toFixed(0)}) after the blade pose left the page; ` +
            `server: ${serverState.steps_per_second.toFixed(1)} steps/s, cut ${serverState.cut_ms.toFixed(1)} ms, ` +
            `new topology ${serverState.topology_ms.toFixed(1)} ms, pose to topology sent ${serverState.cut_latency_ms.toFixed(1)} ms`);
check(latencies.length > 0, 'cuts reached the page as new topology');
const phases = await live(() => window.tetcutLive.cutPhases);
const phase = (k) => median(phases.map((row) => row[k])).toFixed(0);
console.log(`     of which (medians): pose to the server's "cut" reply ${phase(0)} ms, to its topology arriving ${phase(1)} ms, ` +
            `reading it ${phase(2)} ms, to its first frame ${phase(3)} ms`);
const pageTimes = await live(() => ({ topology: window.tetcutLive.topologyMs, draw: window.tetcutLive.drawMs, bytes: window.tetcutLive.topologyBytes }));
console.log(`     topology messages: the first ${(pageTimes.bytes[0] / 1e6).toFixed(2)} MB (whole), then ${pageTimes.bytes.length - 1} changes ` +
            `of ${(median(pageTimes.bytes.slice(1)) / 1e3).toFixed(1)} KB (median; max ${(Math.max(...pageTimes.bytes.slice(1)) / 1e3).toFixed(1)} KB)`);
// (A page that falls behind gets a whole topology again, so this looks at the median.)
check(pageTimes.bytes.length > 1 && median(pageTimes.bytes.slice(1)) < 0.1 * pageTimes.bytes[0], 'cuts were sent as changes, a small part of the whole topology');
console.log(`     the page: ${median(pageTimes.topology).toFixed(1)} ms to read a topology (median), ` +
            `${median(pageTimes.draw).toFixed(1)} ms to draw a frame (median; SwiftShader, no GPU)`);

// --- the recording: downloaded from the page, replayed by tetcut sim --------------------------
const [download] = await Promise.all([page.waitForEvent('download'), page.click('#download')]);
const recordingPath = path.join(work, 'recording.json');
await download.saveAs(recordingPath);
const recording = JSON.parse(readFileSync(recordingPath, 'utf8'));
check(['blade', 'grab', 'pin'].every((kind) => recording.events.some((e) => kind in e)),
      `the recording holds the blade, the hook and the pin (${recording.events.length} events)`);
execFileSync(tetcut, ['sim', recordingPath, '-o', path.join(work, 'replay')], { stdio: 'inherit' });
const replay = JSON.parse(readFileSync(path.join(work, 'replay', 'summary.json'), 'utf8'));
check(replay.pieces === pieces, `tetcut sim replays the recording to ${replay.pieces} pieces`);
{
  const volumes = replay.piece_volumes ?? [];
  const total = volumes.reduce((a, b) => a + b, 0);
  const rest = volumes.slice(2).reduce((a, b) => a + b, 0);
  check(volumes.length === replay.pieces && volumes[1] > 0.05 * total,
        `two parts hold the material (volumes ${volumes.slice(0, 2).map((v) => v.toExponential(3)).join(', ')})`);
  check(rest <= 1e-3 * total, `any other pieces are fragments (${volumes.length - 2} holding ${(rest / total).toExponential(1)} of the volume)`);
}

// --- reset, and a second page watching the same session ---------------------------------------
const second = await context.newPage();
second.on('pageerror', (error) => pageErrors.push(error.message));
await second.goto(url);
await second.waitForFunction((n) => window.tetcutLive?.framesReceived > 0 && window.tetcutLive.pieces === n, pieces, { timeout: 30_000 });
check(true, 'a second page joins and sees the same pieces');
await page.click('#reset');
await page.waitForFunction(() => window.tetcutLive.pieces === 1, null, { timeout: 60_000 });
await second.waitForFunction(() => window.tetcutLive.pieces === 1, null, { timeout: 30_000 });
check((await state()).pieces === 1, 'reset: one piece again, on both pages');

check(pageErrors.length === 0, `no page errors${pageErrors.length ? ': ' + pageErrors.join(' | ') : ''}`);
check(offMachine.length === 0, `no requests off the machine${offMachine.length ? ': ' + offMachine.join(', ') : ''}`);
await browser.close();

// --- Ctrl-C --------------------------------------------------------------------------------------
server.kill('SIGINT');
const exit = await Promise.race([serverExit, deadline(30_000).then(() => null)]);
check(exit !== null && exit.code === 0, `Ctrl-C stopped the server cleanly (${JSON.stringify(exit)})`);
check(existsSync(serverRecording), 'and it wrote its --record file');
writeFileSync(path.join(work, 'server.log'), serverOutput);

const summary = { idle_fps: idleFps, cutting_fps: cutFps, cut_latency_ms_median: median(latencies), cut_latency_ms_max: Math.max(...latencies),
                  server_steps_per_second: serverState.steps_per_second, server_cut_latency_ms: serverState.cut_latency_ms,
                  page_topology_ms_median: median(pageTimes.topology), page_draw_ms_median: median(pageTimes.draw) };
writeFileSync(path.join(work, 'live_summary.json'), JSON.stringify(summary, null, 2));
if (failed() > 0) {
  console.log(serverOutput);
  console.log(`${failed()} check(s) failed`);
  process.exit(1);
}
console.log('all checks passed');
