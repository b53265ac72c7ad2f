// What a person sees of PGE's trees in three.js (GLTFLoader, the client's own mipmaps, in
// headless Chromium), measured or pictured.
//
//   node views.mjs coverage MODULES OUT SPECIES.glb... --forest FOREST.glb
//   node views.mjs gallery  MODULES OUT SPECIES.glb... --forest FOREST.glb
//
// coverage: each species alone on a plain sky, a fixed field of view, the camera level with
// the crown's centre at 20 m, 125 m and 250 m from the trunk. The foliage (every
// alpha-masked material, drawn alone) covers some pixels; its pixel count times the distance
// squared (the area it covers, as seen) must keep at least 80 % of its 20 m value at 125 m
// and at 250 m: leaf cards whose mean alpha falls under the cutoff in the mipmaps thin out
// with distance, and this sees it. The forest is seen from the air: of the pixels its trees
// cover when drawn from their full-resolution textures (no mipmaps: what the textures draw),
// at least 80 % must be leaves drawn with the client's mipmaps (a green canopy, not winter
// branches). Writes OUT/coverage.json and a picture per view; exits 1 below a threshold.
//
// gallery: pictures of every species from 2 m (the eye at 1.6 m, looking at the trunk at
// 1.2 m, a low sun across the bark) and whole, and the forest from the air and at eye level,
// under a sky, as OUT/NAME-close.jpg, NAME-far.jpg, forest-air.jpg, forest-eye.jpg.

import { writeFileSync, mkdirSync } from "node:fs";
import { basename, join } from "node:path";
import { importMap, open } from "./harness.mjs";

const args = process.argv.slice(2);
const [mode, modules, out] = args;
const rest = args.slice(3);
const forestAt = rest.indexOf("--forest");
const forest = forestAt >= 0 ? rest[forestAt + 1] : null;
const species = rest.filter((_, i) => forestAt < 0 || (i !== forestAt && i !== forestAt + 1));
if (!["coverage", "gallery"].includes(mode) || !modules || !out || (species.length === 0 && !forest)) {
  console.error("usage: node views.mjs coverage|gallery NODE_MODULES OUT_DIR SPECIES.glb... [--forest FOREST.glb]");
  process.exit(2);
}
mkdirSync(out, { recursive: true });

const WIDTH = mode === "coverage" ? 1024 : 960;
const HEIGHT = mode === "coverage" ? 768 : 720;
// The share of the near foliage area kept at each far distance, and of the forest's tree
// pixels that must be canopy.
const KEEP = 0.8;
const DISTANCES = [20, 125, 250];

const page_html = `<!doctype html>
<html><head><meta charset="utf-8"><link rel="icon" href="data:,"><style>body{margin:0;background:#000}</style>
${importMap}</head>
<body><canvas id="view" width="${WIDTH}" height="${HEIGHT}"></canvas>
<script type="module">
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { Sky } from "three/addons/objects/Sky.js";

const W = ${WIDTH}, H = ${HEIGHT};
const canvas = document.getElementById("view");
const renderer = new THREE.WebGLRenderer({ canvas, antialias: ${mode === "gallery"}, preserveDrawingBuffer: true });
renderer.setSize(W, H, false);
const gl = renderer.getContext();
const PLAIN = new THREE.Color(0x9fc3e6);
let model = null;

function pixels() {
  const px = new Uint8Array(W * H * 4);
  gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
  return px;
}

// Which pixels of "scene" seen by "camera" differ from the plain background (a mask).
function mask(scene, camera) {
  renderer.render(scene, camera);
  const px = pixels();
  const bg = [PLAIN.r, PLAIN.g, PLAIN.b].map((c) => Math.round(new THREE.Color(c, 0, 0).convertLinearToSRGB().r * 255));
  const m = new Uint8Array(W * H);
  for (let i = 0, k = 0; i < px.length; i += 4, k++) {
    const d = Math.max(Math.abs(px[i] - bg[0]), Math.abs(px[i + 1] - bg[1]), Math.abs(px[i + 2] - bg[2]));
    m[k] = d > 6 ? 1 : 0;
  }
  return m;
}
const count = (m) => m.reduce((s, v) => s + v, 0);

function isLeaf(o) {
  const mats = Array.isArray(o.material) ? o.material : [o.material];
  return mats.some((m) => m && m.alphaTest > 0);
}
function isTerrain(o) {
  return o.name === "terrain" || (o.parent && o.parent.name === "terrain");
}

// Shows only the meshes "which" accepts.
function only(which) {
  model.traverse((o) => { if (o.isMesh) o.visible = which(o); });
}

// The leaf textures drawn with the client's mipmaps (as loaded) or from their full
// resolution only.
function mipmaps(on) {
  model.traverse((o) => {
    if (!o.isMesh || !isLeaf(o)) return;
    const mats = Array.isArray(o.material) ? o.material : [o.material];
    for (const m of mats) {
      for (const t of [m.map, m.alphaMap]) {
        if (!t) continue;
        if (t.userData.minFilter === undefined) t.userData.minFilter = t.minFilter;
        t.minFilter = on ? t.userData.minFilter : THREE.LinearFilter;
        t.generateMipmaps = on;
        t.needsUpdate = true;
      }
    }
  });
}

window.load = async (url) => {
  const gltf = await new GLTFLoader().loadAsync(url);
  model = gltf.scene;
  model.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromObject(model, true);
  let leaves = 0;
  model.traverse((o) => { if (o.isMesh && isLeaf(o)) leaves++; });
  return { min: box.min.toArray(), max: box.max.toArray(), leafMeshes: leaves };
};

function plainScene() {
  const scene = new THREE.Scene();
  scene.background = PLAIN;
  scene.add(new THREE.HemisphereLight(0xffffff, 0x505050, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  sun.position.set(30, 60, 40);
  scene.add(sun);
  scene.add(model);
  return scene;
}

// The foliage's pixels with the camera level with the crown's centre, "d" metres from the
// trunk (the vertical axis through the model's centre), field of view 40 degrees.
window.foliage = (d) => {
  const scene = plainScene();
  const box = new THREE.Box3().setFromObject(model, true);
  const c = box.getCenter(new THREE.Vector3());
  const camera = new THREE.PerspectiveCamera(40, W / H, 0.1, 5000);
  const dir = new THREE.Vector3(0.6, 0, 0.8);
  camera.position.set(c.x + dir.x * d, c.y, c.z + dir.z * d);
  camera.lookAt(c);
  mipmaps(true);
  only(isLeaf);
  const m = mask(scene, camera);
  only(() => true);
  return count(m);
};

// The forest from the air: tree pixels (every mesh but the terrain, leaves from their full
// resolution) and, of those, the ones the leaves cover with the client's mipmaps.
window.canopy = () => {
  const scene = plainScene();
  const box = new THREE.Box3().setFromObject(model, true);
  const c = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3());
  const camera = new THREE.PerspectiveCamera(40, W / H, 1, 10000);
  const reach = Math.max(size.x, size.z);
  camera.position.set(c.x, box.max.y + reach * 0.9, c.z + reach * 0.75);
  camera.lookAt(c.x, box.min.y, c.z);
  mipmaps(false);
  only((o) => !isTerrain(o));
  const trees = mask(scene, camera);
  mipmaps(true);
  only(isLeaf);
  const leaves = mask(scene, camera);
  only(() => true);
  let both = 0;
  for (let k = 0; k < trees.length; k++) both += trees[k] & leaves[k];
  return { trees: count(trees), canopy: both };
};

// A picture under a sky: the sun low across the view for close-ups.
window.picture = (view) => {
  const scene = new THREE.Scene();
  renderer.toneMapping = THREE.ACESFilmicToneMapping;
  renderer.toneMappingExposure = 0.6;
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = THREE.PCFShadowMap;
  const sky = new Sky();
  sky.scale.setScalar(45000);
  const u = sky.material.uniforms;
  u.turbidity.value = 4; u.rayleigh.value = 1.2; u.mieCoefficient.value = 0.004; u.mieDirectionalG.value = 0.8;
  const elevation = THREE.MathUtils.degToRad(view.sunElevation);
  const azimuth = THREE.MathUtils.degToRad(view.sunAzimuth);
  const toSun = new THREE.Vector3().setFromSphericalCoords(1, Math.PI / 2 - elevation, azimuth);
  u.sunPosition.value.copy(toSun);
  scene.add(sky);
  const pmrem = new THREE.PMREMGenerator(renderer);
  const env = new THREE.Scene();
  env.add(sky.clone());
  scene.environment = pmrem.fromScene(env).texture;
  scene.environmentIntensity = 0.5;
  scene.add(new THREE.HemisphereLight(0xbfd8ff, 0x4a5a3a, 0.6));
  const box = new THREE.Box3().setFromObject(model, true);
  const c = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3());
  const reach = Math.max(size.x, size.y, size.z);
  const sun = new THREE.DirectionalLight(0xfff4e0, 3.0);
  sun.position.copy(c).addScaledVector(toSun, reach * 2);
  sun.target.position.copy(c);
  sun.castShadow = true;
  sun.shadow.mapSize.set(2048, 2048);
  const s = sun.shadow.camera;
  s.left = s.bottom = -reach * 0.75; s.right = s.top = reach * 0.75;
  s.near = reach * 0.1; s.far = reach * 4;
  sun.shadow.bias = -0.0005;
  sun.shadow.normalBias = 0.02;
  scene.add(sun, sun.target);
  let terrain = false;
  model.traverse((o) => {
    if (!o.isMesh) return;
    o.castShadow = !isTerrain(o);
    o.receiveShadow = true;
    if (isTerrain(o)) terrain = true;
  });
  if (!terrain) {
    const ground = new THREE.Mesh(new THREE.CircleGeometry(Math.max(reach * 4, 40), 64),
      new THREE.MeshStandardMaterial({ color: 0x5b6b3c, roughness: 1 }));
    ground.rotation.x = -Math.PI / 2;
    ground.position.y = box.min.y;
    ground.receiveShadow = true;
    scene.add(ground);
  }
  scene.add(model);
  const camera = new THREE.PerspectiveCamera(view.fov, W / H, 0.05, 20000);
  if (view.kind === "close") {
    camera.position.set(2 * 0.6, 1.6, 2 * 0.8);
    camera.lookAt(0, 1.2, 0);
  } else if (view.kind === "far") {
    const r = size.length() / 2;
    const d = r / Math.sin(THREE.MathUtils.degToRad(view.fov / 2)) * 1.0;
    camera.position.set(c.x + d * 0.6, c.y + r * 0.15, c.z + d * 0.8);
    camera.lookAt(c);
  } else if (view.kind === "air") {
    camera.position.set(c.x, box.max.y + reach * 0.55, c.z + reach * 0.7);
    camera.lookAt(c.x, box.min.y, c.z - reach * 0.05);
  } else {
    // Eye level: 1.7 m above the ground near the forest's edge, looking across it.
    const x = c.x - size.x * 0.3, z = c.z + size.z * 0.3;
    const ray = new THREE.Raycaster(new THREE.Vector3(x, box.max.y + 10, z), new THREE.Vector3(0, -1, 0));
    const terrainMeshes = [];
    model.traverse((o) => { if (o.isMesh && isTerrain(o)) terrainMeshes.push(o); });
    const hit = ray.intersectObjects(terrainMeshes, false)[0];
    const y = hit ? hit.point.y : box.min.y;
    camera.position.set(x, y + 1.7, z);
    camera.lookAt(c.x + size.x * 0.1, y + 6, c.z - size.z * 0.1);
  }
  renderer.render(scene, camera);
  return true;
};
window.ready = true;
</script></body></html>`;

const h = await open(modules, [...species, ...(forest ? [forest] : [])], page_html, { width: WIDTH, height: HEIGHT });
const report = { species: {}, forest: null };
const failures = [];
try {
  const { page, messages } = h;
  // The canvas as drawn (its drawing buffer is preserved), encoded by the page.
  const shot = async (name) => {
    const [ext, type] = mode === "gallery" ? ["jpg", "image/jpeg"] : ["png", "image/png"];
    const data = await page.evaluate((t) => document.getElementById("view").toDataURL(t, 0.85), type);
    writeFileSync(join(out, `${name}.${ext}`), Buffer.from(data.split(",")[1], "base64"));
  };
  for (const file of species) {
    const name = basename(file, ".glb").replace(/^species_/, "");
    messages.length = 0;
    const info = await page.evaluate((url) => window.load(url), h.url(file));
    if (mode === "coverage") {
      if (info.leafMeshes === 0) {
        console.log(`--   ${name}: no alpha-masked foliage`);
        continue;
      }
      const seen = {};
      for (const d of DISTANCES) {
        seen[d] = await page.evaluate((dist) => window.foliage(dist), d);
        if (d === DISTANCES[DISTANCES.length - 1]) await shot(`${name}-${d}m`);
      }
      const near = seen[DISTANCES[0]] * DISTANCES[0] ** 2;
      const kept = Object.fromEntries(DISTANCES.slice(1).map((d) => [d, (seen[d] * d * d) / near]));
      report.species[name] = { pixels: seen, kept };
      const low = Object.entries(kept).filter(([, k]) => !(k >= KEEP));
      const line = DISTANCES.map((d) => `${d} m ${seen[d]} px`).join(", ") + "; kept " +
        Object.entries(kept).map(([d, k]) => `${d} m ${(100 * k).toFixed(0)} %`).join(", ");
      if (low.length > 0 || seen[DISTANCES[0]] === 0) {
        failures.push(name);
        console.log(`FAIL ${name}: ${line} (at least ${100 * KEEP} % at each distance)`);
      } else {
        console.log(`ok   ${name}: ${line}`);
      }
    } else {
      await page.evaluate((v) => window.picture(v), { kind: "close", fov: 55, sunElevation: 14, sunAzimuth: 105 });
      await shot(`${name}-close`);
      await page.evaluate((v) => window.picture(v), { kind: "far", fov: 40, sunElevation: 40, sunAzimuth: 140 });
      await shot(`${name}-far`);
      console.log(`ok   ${name}: ${name}-close.jpg, ${name}-far.jpg`);
    }
    const problems = messages.filter((m) => !m.includes("GPU stall due to ReadPixels"));
    if (problems.length > 0) {
      failures.push(name);
      console.log(`FAIL ${name}: ${problems.join("; ")}`);
    }
  }
  if (forest) {
    messages.length = 0;
    await page.evaluate((url) => window.load(url), h.url(forest));
    if (mode === "coverage") {
      const c = await page.evaluate(() => window.canopy());
      await shot("forest-air");
      const share = c.trees > 0 ? c.canopy / c.trees : 0;
      report.forest = { ...c, share };
      const line = `${c.canopy} of ${c.trees} tree pixels are canopy (${(100 * share).toFixed(1)} %)`;
      if (!(share >= KEEP)) {
        failures.push("forest");
        console.log(`FAIL forest from the air: ${line} (at least ${100 * KEEP} %)`);
      } else {
        console.log(`ok   forest from the air: ${line}`);
      }
    } else {
      await page.evaluate((v) => window.picture(v), { kind: "air", fov: 45, sunElevation: 35, sunAzimuth: 150 });
      await shot("forest-air");
      await page.evaluate((v) => window.picture(v), { kind: "eye", fov: 60, sunElevation: 30, sunAzimuth: 200 });
      await shot("forest-eye");
      console.log("ok   forest: forest-air.jpg, forest-eye.jpg");
    }
    const problems = messages.filter((m) => !m.includes("GPU stall due to ReadPixels"));
    if (problems.length > 0) {
      failures.push("forest");
      console.log(`FAIL forest: ${problems.join("; ")}`);
    }
  }
} finally {
  await h.close();
}
if (mode === "coverage") writeFileSync(join(out, "coverage.json"), JSON.stringify(report, null, 1) + "\n");
if (failures.length > 0) {
  console.log(`views ${mode}: ${failures.length} failed (${failures.join(", ")})`);
  process.exit(1);
}
console.log(`views ${mode}: all pass`);
