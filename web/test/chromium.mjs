// Headless Debian Chromium through playwright-core, for the browser test and
// the bench. No browser download: the system's /usr/bin/chromium (CHROMIUM=
// overrides). WebGL runs on SwiftShader (no GPU here); the network flags keep
// Chromium from calling out.
import { chromium } from 'playwright-core';

export const CHROMIUM_ARGS = ['--headless=new', '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader',
  '--use-angle=swiftshader', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--disable-dev-shm-usage'];

export function launch() {
  return chromium.launch({ executablePath: process.env.CHROMIUM || '/usr/bin/chromium', args: CHROMIUM_ARGS });
}
