// Browser test of the replay viewer: Debian's chromium (never a downloaded browser
// build), driven headless by playwright-core, loads the page `plamo view` wrote,
// presses play, waits, takes two screenshots and checks that the canvas is not blank
// and that the displayed simulated time advanced.
// usage: node test/browser.mjs PAGE.html OUT_DIR
import { chromium } from "playwright-core";
import { existsSync, mkdirSync } from "node:fs";
import { resolve, join } from "node:path";
import { pathToFileURL } from "node:url";

const [page_, outDir] = process.argv.slice(2);
if (!page_ || !outDir) {
  console.error("usage: node test/browser.mjs PAGE.html OUT_DIR");
  process.exit(2);
}
const executablePath = process.env.CHROMIUM ?? ["/usr/bin/chromium", "/usr/bin/chromium-browser"].find(existsSync);
if (!executablePath) {
  console.error("no chromium: install Debian's (`apt-get install -y chromium`) or set CHROMIUM");
  process.exit(2);
}
mkdirSync(outDir, { recursive: true });

function fail(msg) {
  console.error(`FAIL: ${msg}`);
  process.exitCode = 1;
}

// WebGL without a GPU: SwiftShader through ANGLE.
const browser = await chromium.launch({
  executablePath,
  headless: true,
  args: ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--no-sandbox"],
});
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 720 } });
  const errors = [];
  page.on("pageerror", (e) => errors.push(String(e)));
  page.on("console", (m) => m.type() === "error" && errors.push(m.text()));
  // Anything fetched from the network would be a bug: the page must be self-contained.
  const requests = [];
  page.on("request", (r) => {
    if (!r.url().startsWith("file:") && !r.url().startsWith("data:") && !r.url().startsWith("blob:")) requests.push(r.url());
  });
  await page.goto(pathToFileURL(resolve(page_)).href);
  await page.waitForFunction(() => window.plamoViewer && window.plamoViewer.ready, null, { timeout: 30000 });
  const timeText = () => page.locator("#time").innerText();
  const seconds = (s) => Number((s.match(/t = ([\d.]+) s/) || [])[1]);
  const t0 = seconds(await timeText());
  await page.click("#play");
  await page.waitForTimeout(1500);
  const shot1 = join(outDir, "viewer-1.png");
  await page.screenshot({ path: shot1 });
  const t1 = seconds(await timeText());
  await page.waitForTimeout(2500);
  const shot2 = join(outDir, "viewer-2.png");
  await page.screenshot({ path: shot2 });
  const t2 = seconds(await timeText());
  console.log(`displayed sim time: ${t0} s -> ${t1} s -> ${t2} s; screenshots ${shot1}, ${shot2}`);
  if (!(t1 > t0 && t2 > t1)) fail(`displayed sim time did not advance (${t0}, ${t1}, ${t2})`);

  // The WebGL canvas itself (not the HTML overlay): many distinct colours and a spread
  // of brightness, i.e. a rendered scene rather than a cleared screen.
  const stats = await page.evaluate(() => {
    const c = document.querySelector("canvas");
    const w = 320;
    const h = Math.round((w * c.height) / c.width);
    const off = document.createElement("canvas");
    off.width = w;
    off.height = h;
    const g = off.getContext("2d");
    g.drawImage(c, 0, 0, w, h);
    const px = g.getImageData(0, 0, w, h).data;
    const colors = new Set();
    let min = 255;
    let max = 0;
    for (let i = 0; i < px.length; i += 4) {
      colors.add((px[i] >> 3) * 1024 + (px[i + 1] >> 3) * 32 + (px[i + 2] >> 3));
      const l = (px[i] + px[i + 1] + px[i + 2]) / 3;
      min = Math.min(min, l);
      max = Math.max(max, l);
    }
    return { colors: colors.size, min, max };
  });
  console.log(`canvas: ${stats.colors} distinct colours, brightness ${stats.min.toFixed(0)}..${stats.max.toFixed(0)}`);
  if (stats.colors < 50 || stats.max - stats.min < 60) fail(`canvas looks blank (${JSON.stringify(stats)})`);
  if (errors.length) fail(`page errors: ${errors.join("; ")}`);
  if (requests.length) fail(`the page fetched from the network: ${requests.join(", ")}`);
  const hud = await page.locator("#hud").innerText();
  for (const want of ["speed", "head height", "XY error"]) {
    if (!hud.includes(want)) fail(`overlay lacks "${want}": ${hud}`);
  }
  console.log(`overlay: ${hud.replace(/\s+/g, " ")}`);
} finally {
  await browser.close();
}
if (!process.exitCode) console.log("viewer browser test passed");
