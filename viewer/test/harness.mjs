// What the browser tests share: their command-line arguments, checks that print as they go and
// are counted, and headless Chromium with WebGL in software.

import { chromium } from 'playwright-core';

/// The value after --name on the command line; `fallback` when absent (none: an error).
export function argument(name, fallback) {
  const i = process.argv.indexOf(`--${name}`);
  if (i >= 0 && i + 1 < process.argv.length) return process.argv[i + 1];
  if (fallback === undefined) throw new Error(`missing --${name}`);
  return fallback;
}

let failures = 0;
const started = Date.now();
/// Prints the check with the seconds since the test began, and counts it when it fails.
export function check(condition, message) {
  const at = ((Date.now() - started) / 1000).toFixed(1).padStart(5);
  console.log(`${condition ? 'ok  ' : 'FAIL'} ${at} s  ${message}`);
  if (!condition) failures += 1;
}
export const failed = () => failures;

/// Debian's Chromium, headless; no GPU in CI: WebGL through SwiftShader, its software renderer.
export function launchBrowser(executablePath) {
  return chromium.launch({
    executablePath,
    args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
  });
}
