// The web view in a real browser: headless Chromium (Debian's) driven through
// puppeteer-core against `cargo host serve` linked to a simulated (or emulated)
// machine. Usage: node test.mjs URL REPO_ROOT [SCREENSHOT_DIR]
//
// Checks, in one browser session: the page loads and shows the machine; star.nc
// runs, the drawn path grows while it runs and ends at the program's last
// position; hold stops the pen and resume finishes the job; a setting changes
// (and a bad value shows Grbl's error); a line of text is previewed and drawn;
// an SVG's text is named as left out and shown in orange.
import puppeteer from "puppeteer-core";
import path from "node:path";
import fs from "node:fs";

const [url, root, shots] = process.argv.slice(2);
const results = [];
let failed = 0;

function check(name, ok, detail = "") {
  results.push(name);
  if (ok) console.log(`ok   ${name}${detail ? ": " + detail : ""}`);
  else { failed++; console.log(`FAIL ${name}${detail ? ": " + detail : ""}`); }
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

async function waitFor(page, fn, arg, what, timeout = 30000) {
  try {
    await page.waitForFunction(fn, { timeout, polling: 50 }, arg);
    return true;
  } catch {
    const s = await page.evaluate(() => JSON.stringify({ status: window.inkstep.status, done: window.inkstep.done }));
    console.log(`  timed out waiting for ${what}: ${s}`);
    return false;
  }
}

const state = (page) => page.evaluate(() => ({
  state: window.inkstep.status && window.inkstep.status.state,
  pos: window.inkstep.status && window.inkstep.status.pos,
  path: window.inkstep.path.length,
  done: window.inkstep.done,
}));

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  userDataDir: fs.mkdtempSync("/tmp/inkstep-chromium-"),
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1280, height: 900 });
  page.on("pageerror", (e) => check("no script error", false, e.message));

  // 1. The page loads, connects and shows the machine and its settings.
  await page.goto(url, { waitUntil: "load" });
  const up = await waitFor(page, () => window.inkstep.status && window.inkstep.settings.length > 20, null, "status and settings");
  const s0 = await state(page);
  check("page loads and shows the machine", up && s0.state === "Idle",
    `state ${s0.state}, ${await page.$$eval("#settings tr", (r) => r.length)} settings`);

  // 2. star.nc runs; the path grows while it runs.
  const input = await page.$("#file");
  await input.uploadFile(path.join(root, "bench/star.nc"));
  await waitFor(page, () => window.inkstep.job && window.inkstep.job.name === "star.nc", null, "star.nc loaded");
  const planned = await page.evaluate(() => window.inkstep.job.preview.length);
  check("star.nc loads with a preview", planned >= 5, `${planned} moves planned`);
  await page.click("#run");
  await waitFor(page, () => window.inkstep.status.state === "Run" && window.inkstep.path.length >= 3, null, "drawing");
  const a = await state(page);
  await sleep(300);
  const b = await state(page);
  check("the drawn path grows while the job runs", b.path > a.path, `${a.path} -> ${b.path} points`);

  // 3. Hold: the pen stops; resume: it goes on.
  await page.click("#hold");
  const held = await waitFor(page, () => window.inkstep.status.state === "Hold:0", null, "Hold:0");
  const h1 = await state(page);
  if (shots) await page.screenshot({ path: path.join(shots, "web-view.png") });
  await sleep(400);
  const h2 = await state(page);
  check("hold stops the pen", held && JSON.stringify(h1.pos) === JSON.stringify(h2.pos),
    `held at ${h1.pos}, 400 ms later ${h2.pos}`);
  await page.click("#resume");
  const resumed = await waitFor(page, () => window.inkstep.status.state === "Run" || (window.inkstep.done && window.inkstep.done.ok), null, "Run after resume");
  check("resume goes on", resumed);

  // 4. The job ends where the program ends (star.nc returns to X0 Y0).
  const finished = await waitFor(page, () => window.inkstep.done && window.inkstep.status.state === "Idle", null, "job done", 60000);
  const end = await state(page);
  const last = await page.evaluate(() => window.inkstep.path[window.inkstep.path.length - 1]);
  const bbox = await page.evaluate(() => {
    const p = window.inkstep.path;
    return [Math.min(...p.map((q) => q[0])), Math.max(...p.map((q) => q[0])), Math.min(...p.map((q) => q[1])), Math.max(...p.map((q) => q[1]))];
  });
  const progress = await page.$eval("#progress", (e) => e.value);
  check("star.nc finishes at X0 Y0 with its path drawn",
    finished && end.done.ok && end.pos[0] === 0 && end.pos[1] === 0 && last[0] === 0 && last[1] === 0 && progress === 1 &&
    bbox[0] < -30 && bbox[1] > 30 && bbox[2] < -70,
    `ok ${end.done && end.done.ok}, at ${end.pos}, ${end.path} points, x ${bbox[0].toFixed(1)}..${bbox[1].toFixed(1)}, y from ${bbox[2].toFixed(1)}`);

  // 5. A setting changes; a bad value shows Grbl's error.
  const setTo = async (n, v) => {
    const sel = `#settings input[data-n="${n}"]`;
    await page.$eval(sel, (e) => { e.value = ""; });
    await page.type(sel, v);
    await page.keyboard.press("Enter");
  };
  await setTo(110, "2500");
  const changed = await waitFor(page, () => {
    const r = window.inkstep.settings.find((s) => s[0] === 110);
    return r && parseFloat(r[1]) === 2500;
  }, null, "$110=2500 read back");
  check("a setting changes ($110 = 2500, read back with $$)", changed);
  await setTo(110, "-5");
  const bad = await waitFor(page, () => /error:/.test(document.querySelector('#settings tr[data-n="110"] .err').textContent), null, "error shown");
  const err = await page.$eval('#settings tr[data-n="110"] .err', (e) => e.textContent);
  check("a bad value shows Grbl's error", bad, err);
  await setTo(110, "5000");

  // 6. A line of text: preview, run, drawn.
  await page.$eval("#textsize", (e) => { e.value = "8"; });
  await page.type("#text", "一帆风顺 Hi");
  await page.click("#textgo");
  const loaded = await waitFor(page, () => window.inkstep.job && window.inkstep.job.name === "text", null, "text preview");
  const moves = await page.evaluate(() => window.inkstep.job.preview.filter((m) => m[4]).length);
  check("a text is previewed", loaded && moves > 10, `${moves} pen-down moves planned`);
  await page.click("#run");
  await waitFor(page, () => window.inkstep.status.state === "Run" && window.inkstep.status.job.done > 0.5, null, "text half drawn");
  if (shots) await page.screenshot({ path: path.join(shots, "web-view-text.png") });
  const textDone = await waitFor(page, () => window.inkstep.done && window.inkstep.status.state === "Idle", null, "text done", 60000);
  const t = await state(page);
  const drawn = await page.evaluate(() => window.inkstep.path.filter((p) => p[2]).length);
  check("the text is drawn and the pen parks at the origin",
    textDone && t.done.ok && t.pos[0] === 0 && t.pos[1] === 0 && drawn > 10, `${drawn} pen-down points, at ${t.pos}`);

  // 7. An SVG with text: what is not drawn is named in the log and shown in
  // orange on the page outline.
  const svgPath = path.join(fs.mkdtempSync("/tmp/inkstep-svg-"), "label.svg");
  fs.writeFileSync(svgPath, '<svg xmlns="http://www.w3.org/2000/svg" width="60mm" height="40mm" viewBox="0 0 60 40">' +
    '<rect x="5" y="5" width="20" height="20" fill="none" stroke="black"/>' +
    '<text id="label" x="30" y="30" font-size="8">Left out</text></svg>');
  await (await page.$("#file")).uploadFile(svgPath);
  const svgLoaded = await waitFor(page, () => window.inkstep.job && window.inkstep.job.name === "label.svg", null, "svg loaded");
  const left = await page.evaluate(() => window.inkstep.job.left_out.map((o) => o.kind + ": " + o.name));
  const logged = await page.$eval("#log", (e) => e.textContent.includes('not drawn (text): label "Left out"'));
  const orange = await page.$eval("#plot", (c) => {
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] > 220 && d[i + 1] > 110 && d[i + 1] < 190 && d[i + 2] < 90) n++;
    return n;
  });
  check("an SVG's text is named as left out and shown in orange",
    svgLoaded && left.length === 1 && left[0] === 'text: label "Left out"' && logged && orange > 50,
    `${JSON.stringify(left)}, logged ${logged}, ${orange} orange pixels`);
} catch (e) {
  check("browser session", false, e.stack);
} finally {
  await browser.close();
}
console.log(`${results.length - failed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
