// Loads glb files in three.js's GLTFLoader inside headless Chromium, renders each framed by
// its bounding box and keeps the pictures. Fails (exit 1) on any loader error, page error,
// GLTFLoader warning, a file without a scene or without the run's extras on its scene, or an
// empty frame (every pixel background). Files named `empty_*.glb` are models with nothing in
// them: they must load into an empty scene (and are not rendered).
//
//   node three.mjs MODULES OUT FILE.glb...
//
// MODULES is a node_modules folder holding `three` and `playwright-core`; OUT receives one
// NAME.png per file and `three.json` (what the loader built for each file). Chromium is
// Debian's (/usr/bin/chromium, or $CHROMIUM); the page and the files are served on
// 127.0.0.1 only, each file by its path, so a glb whose buffer is a file beside it (a tile
// that refers to its world's `../variants.bin`) is loaded as a viewer loads it from disk.

import { writeFileSync, mkdirSync } from "node:fs";
import { basename, join } from "node:path";
import { importMap, open } from "./harness.mjs";

const [modules, out, ...files] = process.argv.slice(2);
if (!modules || !out || files.length === 0) {
  console.error("usage: node three.mjs NODE_MODULES OUT_DIR FILE.glb...");
  process.exit(2);
}
mkdirSync(out, { recursive: true });

const WIDTH = 640;
const HEIGHT = 480;

// The page names an empty icon: else Chromium asks for /favicon.ico, and the 404's console
// error could land while the first file is shown (a flake seen once in CI).
const page_html = `<!doctype html>
<html><head><meta charset="utf-8"><link rel="icon" href="data:,"><style>body{margin:0;background:#000}</style>
${importMap}</head>
<body><canvas id="view" width="${WIDTH}" height="${HEIGHT}"></canvas>
<script type="module">
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";

const BUDGET = 3e6;
const canvas = document.getElementById("view");
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
renderer.setSize(${WIDTH}, ${HEIGHT}, false);
const gl = renderer.getContext();

function pixels() {
  const px = new Uint8Array(${WIDTH} * ${HEIGHT} * 4);
  gl.readPixels(0, 0, ${WIDTH}, ${HEIGHT}, gl.RGBA, gl.UNSIGNED_BYTE, px);
  return px;
}

// Renders "scene" seen by "camera" and counts the pixels that differ from the background
// (taken from the same scene rendered without its content).
function render(scene, content, camera) {
  content.visible = false;
  renderer.render(scene, camera);
  const empty = pixels();
  content.visible = true;
  renderer.render(scene, camera);
  const full = pixels();
  let differing = 0;
  for (let i = 0; i < full.length; i += 4) {
    const d = Math.max(Math.abs(full[i] - empty[i]), Math.abs(full[i + 1] - empty[i + 1]),
      Math.abs(full[i + 2] - empty[i + 2]));
    if (d > 6) differing++;
  }
  return differing;
}

window.show = async (url, expectEmpty) => {
  const gltf = await new GLTFLoader().loadAsync(url);
  const result = { scenes: gltf.scenes.length, meshes: 0, instanced: 0, lines: 0, triangles: 0,
    sceneExtras: null, pixels: 0, pixelShare: 0 };
  if (!gltf.scene) {
    throw new Error("the file has no scene (gltf.scene is " + gltf.scene + ")");
  }
  result.sceneExtras = gltf.scene.userData.pge ?? null;
  if (!result.sceneExtras || !result.sceneExtras.generator || !result.sceneExtras.stats) {
    throw new Error("the scene's userData has no pge extras (generator, stats)");
  }
  gltf.scene.traverse((o) => {
    if (o.isInstancedMesh) result.instanced++;
    if (o.isLineSegments || o.isLine) result.lines++;
    if (o.isMesh) {
      result.meshes++;
      const g = o.geometry;
      const n = g.index ? g.index.count : g.attributes.position.count;
      result.triangles += (n / 3) * (o.isInstancedMesh ? o.count : 1);
    }
  });
  // Software rendering draws some millions of triangles a second: a forest of 100,000 trees
  // is loaded whole but drawn with its instance counts cut to a budget (the first ones).
  result.drawn = result.triangles;
  if (result.triangles > BUDGET) {
    const keep = BUDGET / result.triangles;
    result.drawn = 0;
    gltf.scene.traverse((o) => {
      if (!o.isMesh) return;
      const g = o.geometry;
      const n = (g.index ? g.index.count : g.attributes.position.count) / 3;
      if (o.isInstancedMesh) o.count = Math.max(1, Math.floor(o.count * keep));
      result.drawn += n * (o.isInstancedMesh ? o.count : 1);
    });
  }
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x55606b);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404040, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  scene.add(sun);
  scene.add(gltf.scene);
  gltf.scene.updateMatrixWorld(true);
  if (expectEmpty) {
    if (result.meshes > 0 || result.lines > 0) throw new Error("an empty model drew something");
    return result;
  }
  // Framed by the model: a sky dome (the node named "sky") is the background around it.
  const box = new THREE.Box3();
  for (const child of gltf.scene.children) {
    if (child.name !== "sky") box.expandByObject(child, true);
  }
  result.sky = gltf.scene.children.some((c) => c.name === "sky");
  if (box.isEmpty()) {
    throw new Error("the scene's bounding box is empty");
  }
  const center = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  const camera = new THREE.PerspectiveCamera(40, ${WIDTH} / ${HEIGHT}, radius / 100, radius * 100);
  const direction = new THREE.Vector3(0.8, 0.55, 1.0).normalize();
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(20)) * 1.05;
  camera.position.copy(center).addScaledVector(direction, distance);
  camera.lookAt(center);
  sun.position.copy(camera.position).add(new THREE.Vector3(0, radius, 0));
  sun.target.position.copy(center);
  scene.add(sun.target);
  result.pixels = render(scene, gltf.scene, camera);
  result.pixelShare = result.pixels / (${WIDTH} * ${HEIGHT});
  return result;
};
window.ready = true;
</script></body></html>`;

const h = await open(modules, files, page_html, { width: WIDTH, height: HEIGHT });
const summary = {};
let failures = 0;
try {
  const { page, messages } = h;
  for (const file of files) {
    const name = basename(file, ".glb");
    messages.length = 0;
    const t0 = Date.now();
    let result;
    try {
      result = await page.evaluate(([url, empty]) => window.show(url, empty),
        [h.url(file), name.startsWith("empty_")]);
    } catch (e) {
      result = { error: String(e.message ?? e).split("\n")[0] };
    }
    result.seconds = (Date.now() - t0) / 1000;
    await page.locator("#view").screenshot({ path: join(out, `${name}.png`) });
    const problems = [];
    if (result.error) problems.push(result.error);
    // GLTFLoader reports what it cannot read (unknown extensions, bad data) as warnings.
    problems.push(...messages.filter((m) => !m.includes("GPU stall due to ReadPixels")));
    if (!result.error && result.pixels === 0 && !name.startsWith("empty_")) problems.push("empty frame: every pixel is background");
    result.problems = problems;
    summary[name] = result;
    const what = result.error ? "" :
      `${result.meshes} meshes (${result.instanced} instanced, ${result.lines} lines), ` +
      `${result.triangles} triangles` +
      (result.drawn < result.triangles ? ` (${result.drawn} drawn)` : "") +
      (result.sky ? ", a sky dome" : "") +
      `, ${(100 * result.pixelShare).toFixed(1)} % of the frame`;
    if (problems.length > 0) {
      failures++;
      console.log(`FAIL ${name}: ${problems.join("; ")}`);
    } else {
      console.log(`ok   ${name}: ${what} [${result.seconds.toFixed(1)} s]`);
    }
  }
} finally {
  await h.close();
}
writeFileSync(join(out, "three.json"), JSON.stringify(summary, null, 1) + "\n");
if (failures > 0) {
  console.log(`three.js: ${failures} of ${files.length} files failed`);
  process.exit(1);
}
console.log(`three.js: all ${files.length} files load and render`);
