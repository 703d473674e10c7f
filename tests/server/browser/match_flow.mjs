// Browser test of proctex serve's web UI in headless chromium (puppeteer-core):
//   node match_flow.mjs URL PHOTO OUT_DIR [CHROMIUM]
// Match page: upload the photo, see the live preview update, the result appear, move a slider and
// see the render change; library page: a shader renders live. Screenshots go to OUT_DIR.
// Exits 0 when every check passes, 1 with the reason on stderr otherwise.
import puppeteer from "puppeteer-core";
import fs from "node:fs";
import path from "node:path";

const [url, photo, outDir, chromium = "/usr/bin/chromium"] = process.argv.slice(2);
if (!url || !photo || !outDir) {
  console.error("usage: node match_flow.mjs URL PHOTO OUT_DIR [CHROMIUM]");
  process.exit(2);
}
fs.mkdirSync(outDir, { recursive: true });
const check = (ok, what) => { if (!ok) throw new Error("check failed: " + what); console.log("ok: " + what); };

// A checksum of what an <img> shows (drawn into a canvas), to tell two renders apart.
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

const browser = await puppeteer.launch({
  executablePath: chromium, headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run"],
});
let failed = false;
const page = await browser.newPage();
const consoleErrors = [];
page.on("pageerror", e => consoleErrors.push(String(e)));
try {
  await page.setViewport({ width: 1280, height: 760 });
  await page.goto(url, { waitUntil: "networkidle0" });
  check((await page.title()).includes("match"), "the match page loads");

  const t0 = Date.now();
  const input = await page.$("#file");
  await input.uploadFile(path.resolve(photo));
  await page.waitForFunction(() => parseInt(document.querySelector("#preview").dataset.updates || "0") >= 1, { timeout: 60000 });
  const firstPreview = (Date.now() - t0) / 1000;
  console.log(`first live preview ${firstPreview.toFixed(2)} s after the upload`);
  await page.screenshot({ path: path.join(outDir, "match-live.png") });
  const stage = await page.$eval("#stage", e => e.textContent);
  check(/screened|race|refine|final|done/.test(stage), "the stage is shown while searching: " + stage);

  await page.waitForFunction(() => document.body.dataset.done === "1", { timeout: 120000 });
  const updates = await page.$eval("#preview", e => parseInt(e.dataset.updates || "0"));
  console.log(`${updates} preview updates before the result`);
  const similarity = parseFloat(await page.$eval("#similarity", e => e.textContent));
  const verdict = await page.$eval("#verdict", e => e.textContent);
  check(similarity > 0 && similarity <= 1, "the result shows a similarity: " + similarity);
  check(["good", "approximate", "no-match"].includes(verdict), "the result shows a verdict: " + verdict);
  const why = await page.$eval("#verdict-why", e => e.textContent);
  check(why.startsWith(verdict + ": "), "the verdict says why: " + why);
  const sliders = await page.$$("#params input[type=range]");
  check(sliders.length > 0, "the result's parameters are sliders (" + sliders.length + ")");

  // Move a slider twice; each move re-renders, and the two renders differ.
  const move = async (value) => {
    const before = await page.$eval("#preview", e => parseInt(e.dataset.renders || "0"));
    await sliders[0].evaluate((el, v) => { el.value = String(v); el.dispatchEvent(new Event("input", { bubbles: true })); },
                              value === "min" ? await sliders[0].evaluate(e => e.min) : await sliders[0].evaluate(e => e.max));
    await page.waitForFunction(n => parseInt(document.querySelector("#preview").dataset.renders || "0") > n, { timeout: 20000 }, before);
    return imageSum(page, "#preview");
  };
  const a = await move("min");
  const b = await move("max");
  check(a !== b, "moving a slider changes the render");
  await page.screenshot({ path: path.join(outDir, "match-result.png"), fullPage: true });

  await page.goto(url.replace(/\/?$/, "/") + "library?shader=bricks", { waitUntil: "networkidle0" });
  await page.waitForFunction(() => parseInt(document.querySelector("#render").dataset.renders || "0") >= 1, { timeout: 20000 });
  check((await page.$$("#params .param")).length > 3, "the library page shows the shader's parameters");
  await page.screenshot({ path: path.join(outDir, "library.png") });
  check(consoleErrors.length === 0, "no script errors: " + consoleErrors.join("; "));
} catch (e) {
  failed = true;
  console.error(String(e.stack || e));
  await page.screenshot({ path: path.join(outDir, "failure.png") }).catch(() => {});
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
