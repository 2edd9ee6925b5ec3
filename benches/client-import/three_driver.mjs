// Drives headless Chromium (Debian's, through playwright-core) on
// three.html: loads each .glb given, renders it at several times, and
// prints one JSON line per file: load and first-frame times, GL errors,
// how many pixels differ from the background at each time, and the first
// mesh's vertex positions at those times (as three.js evaluates them).
//   node three_driver.mjs PORT FILE.glb[:t1,t2,...] ...
import { chromium } from 'playwright-core';
const port = process.argv[2];
const browser = await chromium.launch({
  executablePath: '/usr/bin/chromium',
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader',
         '--use-angle=swiftshader', '--disable-quic', '--no-first-run',
         '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
for (const spec of process.argv.slice(3)) {
  const [file, times] = spec.split(':');
  const page = await browser.newPage({ viewport: { width: 640, height: 480 } });
  const logs = [];
  page.on('console', (m) => logs.push(m.text()));
  page.on('pageerror', (e) => logs.push('pageerror: ' + e.message));
  const started = Date.now();
  await page.goto(`http://127.0.0.1:${port}/three.html?file=${encodeURIComponent(file)}`);
  await page.waitForFunction(() => window.result || null, null, { timeout: 600000 });
  const result = await page.evaluate(() => window.result);
  result.page_ms = Date.now() - started;
  result.file = file;
  result.frames = [];
  for (const t of (times || '0').split(',').map(Number)) {
    const r = await page.evaluate((t) => window.renderAt(t), t);
    const shot = await page.screenshot();
    const px = await page.evaluate(async (b64) => {
      const img = new Image(); img.src = 'data:image/png;base64,' + b64; await img.decode();
      const c = new OffscreenCanvas(img.width, img.height); const g = c.getContext('2d');
      g.drawImage(img, 0, 0); const d = g.getImageData(0, 0, img.width, img.height).data;
      let n = 0; for (let i = 0; i < d.length; i += 4) {
        if (Math.abs(d[i] - 0x20) + Math.abs(d[i + 1] - 0x24) + Math.abs(d[i + 2] - 0x28) > 30) n++;
      }
      return n;
    }, shot.toString('base64'));
    result.frames.push({ t, glError: r.glError, drawn_pixels: px, positions: r.positions });
  }
  result.logs = logs.slice(0, 10);
  console.log('RESULT ' + JSON.stringify(result));
  await page.close();
}
await browser.close();
