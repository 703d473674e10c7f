// Screenshots of the web UI for docs/service.md and the README (not a test):
//   node docs_screenshots.mjs URL PHOTO OUT_DIR [CHROMIUM]
// Match page while searching and with the result, library page, morph page with a finished morph.
import puppeteer from "puppeteer-core";
import path from "node:path";

const [url, photo, outDir, chromium = "/usr/bin/chromium"] = process.argv.slice(2);
const base = url.replace(/\/?$/, "/");
const browser = await puppeteer.launch({ executablePath: chromium, headless: true,
                                         args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"] });
const page = await browser.newPage();
await page.setViewport({ width: 1280, height: 820 });
await page.goto(base, { waitUntil: "networkidle0" });
await (await page.$("#file")).uploadFile(path.resolve(photo));
await page.waitForFunction(() => parseInt(document.querySelector("#preview").dataset.updates || "0") >= 3, { timeout: 120000 });
await page.screenshot({ path: path.join(outDir, "ui-match-live.png") });
await page.waitForFunction(() => document.body.dataset.done === "1", { timeout: 300000 });
await new Promise(r => setTimeout(r, 1500));
await page.screenshot({ path: path.join(outDir, "ui-match-result.png"), fullPage: true });
const job = await page.evaluate(() => document.body.dataset.job);

await page.goto(base + "library?shader=marble", { waitUntil: "networkidle0" });
await page.waitForFunction(() => parseInt(document.querySelector("#render").dataset.renders || "0") >= 1, { timeout: 30000 });
await page.screenshot({ path: path.join(outDir, "ui-library.png") });

const key = encodeURIComponent(JSON.stringify({ shader: "bricks", params: { rows: 6 }, seed: 1 }));
await page.goto(base + "morph?job=" + job + "&key=" + key, { waitUntil: "networkidle0" });
await page.$eval("#frames", e => e.value = "16");
await page.$eval("#size", e => e.value = "128");
await page.click("#go");
await page.waitForFunction(() => !document.querySelector("#out").hidden, { timeout: 300000 });
await new Promise(r => setTimeout(r, 1500));
await page.screenshot({ path: path.join(outDir, "ui-morph.png"), fullPage: true });
await browser.close();
