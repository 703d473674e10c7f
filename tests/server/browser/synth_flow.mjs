// Browser test of the synth page of proctex serve in headless chromium (puppeteer-core):
//   node synth_flow.mjs URL EXEMPLAR OUT_DIR [CHROMIUM]
// Drops the exemplar on the page (a real drop event carrying the file), sees the result appear
// beside it, switches to tileable and sees the 2x2 tiling, asks for a new seed and sees another
// texture. Screenshots go to OUT_DIR. Exits 0 when every check passes, 1 with the reason otherwise.
import puppeteer from "puppeteer-core";
import fs from "node:fs";
import path from "node:path";

const [url, exemplar, outDir, chromium = "/usr/bin/chromium"] = process.argv.slice(2);
if (!url || !exemplar || !outDir) {
  console.error("usage: node synth_flow.mjs URL EXEMPLAR OUT_DIR [CHROMIUM]");
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const check = (ok, what) => { if (!ok) throw new Error("check failed: " + what); console.log("ok: " + what); };

const imageSum = (page, sel) => page.$eval(sel, img => new Promise(resolve => {
  const done = () => {
    const c = document.createElement("canvas");
    c.width = 64; c.height = 64;
    const g = c.getContext("2d");
    g.drawImage(img, 0, 0, 64, 64);
    const d = g.getImageData(0, 0, 64, 64).data;
    let s = 0;
    for (let i = 0; i < d.length; ++i) s = (s * 31 + d[i]) >>> 0;
    resolve(s);
  };
  if (img.complete && img.naturalWidth) done(); else img.onload = done;
}));
const settle = () => new Promise(r => setTimeout(r, 400));  // transitions, before a screenshot
const results = page => page.evaluate(() => parseInt(document.body.dataset.done || "0"));
const waitResults = (page, n) => page.waitForFunction(k => parseInt(document.body.dataset.done || "0") >= k, { timeout: 90000 }, n);

const browser = await puppeteer.launch({
  executablePath: chromium, headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run"],
});
let failed = false;
const page = await browser.newPage();
const errors = [];
page.on("pageerror", e => errors.push(String(e)));
try {
  await page.setViewport({ width: 1280, height: 900 });
  await page.goto(url.replace(/\/?$/, "/") + "synth", { waitUntil: "networkidle0" });
  check((await page.title()).includes("synth"), "the synth page loads");

  // Drop the exemplar: a DataTransfer with the file, as a drag from the desktop delivers it.
  const bytes = fs.readFileSync(exemplar).toString("base64");
  const t0 = Date.now();
  await page.evaluate(async (b64, name) => {
    const data = Uint8Array.from(atob(b64), c => c.charCodeAt(0));
    const dt = new DataTransfer();
    dt.items.add(new File([data], name, { type: "image/png" }));
    const drop = document.getElementById("drop");
    drop.dispatchEvent(new DragEvent("dragover", { dataTransfer: dt, bubbles: true, cancelable: true }));
    drop.dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, bytes, path.basename(exemplar));
  await waitResults(page, 1);
  console.log(`first result ${((Date.now() - t0) / 1000).toFixed(2)} s after the drop`);
  const size = parseInt(await page.$eval("#size", e => e.value));
  const natural = await page.$eval("#result-img", e => [e.naturalWidth, e.naturalHeight]);
  check(natural[0] === size && natural[1] === size, `the result is ${size}x${size}: ${natural}`);
  check((await page.$eval("#drop img", e => e.naturalWidth)) > 0, "the exemplar is shown beside the result");
  const bg = await page.$eval("#result", e => e.style.backgroundImage);
  check(bg.includes("/files/synth.png"), "the result panel shows the synthesised PNG");
  check(await page.$eval("#result-info", e => e.dataset.seed === "1"), "the seed (1) is shown");
  check(await page.$eval("#dl-png", e => e.href.includes("synth.png") && e.href.includes("download=1")), "a PNG download link");
  await settle();
  await page.screenshot({ path: path.join(outDir, "synth-result.png") });

  // Tileable: re-run on the same upload, shown as a 2x2 tiling.
  await page.click("#tileable");
  await waitResults(page, 2);
  const tiling = await page.$eval("#result", e => ({ tiled: e.dataset.tiled, repeat: e.style.backgroundRepeat,
                                                      tile: parseFloat(e.style.backgroundSize), view: e.clientWidth }));
  check(tiling.tiled === "1" && tiling.repeat === "repeat" && Math.abs(2 * tiling.tile - tiling.view) <= 2,
        "a tileable result is shown as a 2x2 tiling: " + JSON.stringify(tiling));
  await settle();
  await page.screenshot({ path: path.join(outDir, "synth-tiled.png") });
  const tiled = await imageSum(page, "#result-img");

  // A new seed: another texture from the same exemplar.
  const before = await results(page);
  await page.click("#new-seed");
  await waitResults(page, before + 1);
  const seed = await page.$eval("#seed", e => e.value);
  check(await page.$eval("#result-info", (e, s) => e.dataset.seed === s, seed), "the new seed is recorded: " + seed);
  check((await imageSum(page, "#result-img")) !== tiled, "another seed gives another texture");
  check(errors.length === 0, "no script errors: " + errors.join("; "));
} catch (e) {
  failed = true;
  console.error(String(e.stack || e));
  await page.screenshot({ path: path.join(outDir, "synth-failure.png") }).catch(() => {});
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
