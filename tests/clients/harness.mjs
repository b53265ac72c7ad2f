// What the three.js client scripts share: a server on 127.0.0.1 for a page, three.js's
// modules and the glb files (each by its absolute path, so that a glb's external buffer
// beside it resolves as on disk), and headless Chromium (Debian's, software WebGL).
//
//   const h = await open(modulesDir, files, pageHtml, { width, height });
//   h.page, h.url(file); ...; await h.close();

import { createServer } from "node:http";
import { createRequire } from "node:module";
import { readFileSync, existsSync } from "node:fs";
import { dirname, join, resolve, extname } from "node:path";

const types = { ".js": "text/javascript", ".mjs": "text/javascript", ".html": "text/html" };

// The import map every page uses: `three` and `three/addons/` from the served package.
export const importMap = `<script type="importmap">{"imports": {"three": "/three/build/three.module.js",
 "three/addons/": "/three/examples/jsm/"}}</script>`;

// The Chromium flags for a machine with no GPU and no network: background networking off
// (its requests are refused here), WebGL by SwiftShader, which must be asked for.
const chromiumArgs = [
  "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync",
  "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
];

// Serves `html` at "/", three.js at "/three/", and the given files (and what lies in their
// folders and the folders above them, nothing else) at "/fs/ABSOLUTE/PATH"; opens a page of
// `width` x `height` on it in headless Chromium and waits for `window.ready`. Console errors
// and warnings and page errors are collected in `messages` (the caller clears it).
export async function open(modules, files, html, { width, height }) {
  const require = createRequire(join(resolve(modules), "noop.js"));
  const { chromium } = require("playwright-core");
  const threeDir = join(resolve(modules), "three");
  const roots = [...new Set(files.map((f) => dirname(dirname(resolve(f)))))];
  const server = createServer((req, res) => {
    const url = new URL(req.url, "http://127.0.0.1");
    let body = null;
    let type = "application/octet-stream";
    if (url.pathname === "/") {
      body = html;
      type = "text/html";
    } else if (url.pathname.startsWith("/three/")) {
      const path = resolve(threeDir, "." + decodeURIComponent(url.pathname.slice(6)));
      if (path.startsWith(threeDir + "/") && existsSync(path)) {
        body = readFileSync(path);
        type = types[extname(path)] ?? type;
      }
    } else if (url.pathname.startsWith("/fs/")) {
      const path = resolve("/" + url.pathname.slice(4).split("/").map(decodeURIComponent).join("/"));
      if (roots.some((root) => path.startsWith(root + "/")) && existsSync(path)) {
        body = readFileSync(path);
        type = extname(path) === ".glb" ? "model/gltf-binary" : type;
      }
    }
    if (body === null) {
      res.writeHead(404);
      res.end();
      return;
    }
    res.writeHead(200, { "content-type": type });
    res.end(body);
  });
  await new Promise((ok) => server.listen(0, "127.0.0.1", ok));
  const base = `http://127.0.0.1:${server.address().port}`;
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
    headless: true,
    args: chromiumArgs,
  });
  const messages = [];
  try {
    const page = await browser.newPage({ viewport: { width, height } });
    page.on("console", (m) => {
      if (m.type() === "error" || m.type() === "warning") messages.push(`${m.type()}: ${m.text()}`);
    });
    page.on("pageerror", (e) => messages.push(`page error: ${e.message}`));
    await page.goto(base + "/");
    await page.waitForFunction(() => window.ready === true, null, { timeout: 60000 });
    return {
      page,
      messages,
      url: (f) => base + "/fs" + resolve(f).split("/").map(encodeURIComponent).join("/"),
      close: async () => {
        await browser.close();
        server.close();
      },
    };
  } catch (e) {
    await browser.close();
    server.close();
    throw e;
  }
}
