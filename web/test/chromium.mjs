// Headless Debian Chromium through playwright-core, for the browser test and
// the bench. No browser download: the system's /usr/bin/chromium (CHROMIUM=
// overrides). WebGL runs on SwiftShader (no GPU here); the network flags keep
// Chromium from calling out.
import { chromium } from 'playwright-core';
import { startServer } from '../serve.mjs';

export const CHROMIUM_ARGS = ['--headless=new', '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader',
  '--use-angle=swiftshader', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--disable-dev-shm-usage'];

export function launch() {
  return chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args: CHROMIUM_ARGS });
}

// Serves web/, opens a bench page (path and query under the server's root),
// waits until it sets window.benchResult to a state other than 'running' and
// returns that result with the Chromium version; the server and the browser
// are closed whatever happens.
export async function runBenchPage(pagePath, timeoutMs) {
  const server = await startServer();
  const browser = await launch();
  try {
    const page = await browser.newPage();
    page.on('pageerror', (e) => console.error('page error:', e.message));
    await page.goto(`http://localhost:${server.address().port}/${pagePath}`);
    await page.waitForFunction(() => window.benchResult && window.benchResult.state !== 'running', null, { timeout: timeoutMs });
    const r = await page.evaluate(() => window.benchResult);
    r.chromium = browser.version();
    return r;
  } finally {
    await browser.close();
    server.close();
  }
}
