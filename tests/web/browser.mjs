// Drives Debian's chromium headless for tests/web/test_web.py, one command per stdin line (JSON),
// one JSON answer per stdout line. puppeteer-core comes from tests/web/node_modules
// (scripts/install-deps runs `npm ci` there). Usage: node browser.mjs CHROMIUM
//   {"cmd": "goto", "url": U}                    -> {}
//   {"cmd": "eval", "js": EXPR}                  -> {"value": the expression's JSON value}
//   {"cmd": "wait", "js": EXPR, "timeout": S}    -> {"value": ...} once EXPR is truthy
//   {"cmd": "click", "selector": S}              -> {}   (a real mouse click at its centre)
//   {"cmd": "hover", "selector": S}              -> {}
//   {"cmd": "type", "selector": S, "text": T}    -> {}   (replaces the field's value)
//   {"cmd": "screenshot", "path": P}             -> {}
//   {"cmd": "quit"}
// A failure answers {"error": message}; the page's console and errors go to stderr.
import { createInterface } from "node:readline";
import puppeteer from "puppeteer-core";

const browser = await puppeteer.launch({
  executablePath: process.argv[2] || "/usr/bin/chromium",
  headless: true,
  args: ["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run", "--disable-extensions"],
});
const page = await browser.newPage();
await page.setViewport({ width: 1100, height: 700 });
page.on("console", (m) => process.stderr.write(`  page console: ${m.text()}\n`));
page.on("pageerror", (e) => process.stderr.write(`  page error: ${e.message}\n`));

const run = {
  async goto(c) { await page.goto(c.url, { waitUntil: "load" }); return {}; },
  async eval(c) { return { value: await page.evaluate(c.js) }; },
  async wait(c) {
    const h = await page.waitForFunction(c.js, { timeout: (c.timeout || 30) * 1000, polling: 50 });
    return { value: await h.jsonValue() };
  },
  async click(c) { await page.click(c.selector); return {}; },
  async hover(c) { await page.hover(c.selector); return {}; },
  async type(c) {
    await page.$eval(c.selector, (el) => { el.value = ""; });
    await page.type(c.selector, c.text);
    return {};
  },
  async screenshot(c) { await page.screenshot({ path: c.path, fullPage: true }); return {}; },
};

const lines = createInterface({ input: process.stdin });
for await (const line of lines) {
  const c = JSON.parse(line);
  if (c.cmd === "quit") break;
  let out;
  try {
    out = await run[c.cmd](c);
  } catch (e) {
    out = { error: String(e && e.message ? e.message : e) };
  }
  process.stdout.write(JSON.stringify(out) + "\n");
}
await browser.close();
