// The playground page: a script in the editor regrows its model in a worker (the engine as
// WebAssembly), shown with three.js. Errors are marked at their line while the last good
// model stays; parameters are sliders; the glb can be downloaded and the script shared.
import { EditorView, basicSetup } from 'codemirror';
import { StreamLanguage } from '@codemirror/language';
import { lua } from '@codemirror/legacy-modes/mode/lua';
import { lintGutter, setDiagnostics } from '@codemirror/lint';
import { Annotation } from '@codemirror/state';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { Sky } from 'three/examples/jsm/objects/Sky.js';

// A page's run stops after this long (the desktop's is 300 s): the page says so.
const TIME_LIMIT = 60;
const DEBOUNCE_MS = 350;
const DEFAULT_SCRIPT = 'scripts/species/oak.lua';

const $ = (id) => document.getElementById(id);
const state = {
  path: DEFAULT_SCRIPT,
  overrides: {}, // parameters set with the sliders: name -> value
  glb: null, // the last good model's bytes
  frameNext: true, // frame the camera on the next model (a new script)
  generation: 0, // results shown so far (the tests wait on it)
  library: [],
};

// ---- the worker ---------------------------------------------------------------------------
let worker = null;
let nextId = 1;
const waiting = new Map();
function startWorker() {
  worker = new Worker(new URL('worker.js', import.meta.url));
  worker.onmessage = ({ data }) => {
    const done = waiting.get(data.id);
    waiting.delete(data.id);
    if (done) done(data);
  };
}
function call(request) {
  return new Promise((resolve) => {
    const id = nextId++;
    waiting.set(id, resolve);
    worker.postMessage({ id, request });
  });
}

// ---- the view -----------------------------------------------------------------------------
const canvas = $('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.toneMapping = THREE.ACESFilmicToneMapping;
renderer.toneMappingExposure = 0.6;
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.05, 5000);
camera.position.set(12, 8, 16);
const controls = new OrbitControls(camera, canvas);
controls.enableDamping = true;
const sky = new Sky();
sky.scale.setScalar(10000);
const sunDirection = new THREE.Vector3().setFromSphericalCoords(1, THREE.MathUtils.degToRad(55), THREE.MathUtils.degToRad(140));
sky.material.uniforms.sunPosition.value.copy(sunDirection);
sky.material.uniforms.turbidity.value = 4;
sky.material.uniforms.rayleigh.value = 1.5;
scene.add(sky);
const sun = new THREE.DirectionalLight(0xfff2e0, 3.0);
scene.add(sun, sun.target);
scene.add(new THREE.HemisphereLight(0xcfe3ff, 0x4a3b2a, 1.6));
const ground = new THREE.Mesh(new THREE.CircleGeometry(1, 64), new THREE.MeshStandardMaterial({ color: 0x3d4a35, roughness: 1 }));
ground.rotation.x = -Math.PI / 2;
scene.add(ground);
let model = null;

function resize() {
  const { clientWidth: w, clientHeight: h } = canvas;
  if (canvas.width !== w || canvas.height !== h) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }
}
// Drawn when something changed (a model, the camera, the canvas's size), not at every frame:
// a still view costs nothing, and the worker growing the next model has the processor to itself.
let drawing = false;
function draw() {
  if (drawing) return;
  drawing = true;
  requestAnimationFrame(() => {
    drawing = false;
    resize();
    controls.update(); // while the camera glides to a stop (damping) this asks for the next frame
    renderer.render(scene, camera);
  });
}
controls.addEventListener('change', draw);
new ResizeObserver(draw).observe(canvas);

function frame(object) {
  const box = new THREE.Box3();
  for (const child of object.children) if (child.name !== 'sky') box.expandByObject(child, true);
  if (box.isEmpty()) return;
  const center = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-3);
  const distance = (radius / Math.sin(THREE.MathUtils.degToRad(20))) * 1.05;
  camera.position.copy(center).addScaledVector(new THREE.Vector3(0.8, 0.45, 1).normalize(), distance);
  camera.near = radius / 100;
  camera.far = radius * 200;
  camera.updateProjectionMatrix();
  controls.target.copy(center);
  ground.scale.setScalar(radius * 4);
  ground.position.y = box.min.y - radius * 0.002;
  sun.position.copy(center).addScaledVector(sunDirection, radius * 4);
  sun.target.position.copy(center);
}

async function show(glb) {
  const gltf = await new GLTFLoader().parseAsync(glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength), '');
  if (model) {
    scene.remove(model);
    // Its buffers and textures leave the GPU with it (a regrowth makes new ones).
    model.traverse((o) => {
      if (o.geometry) o.geometry.dispose();
      for (const material of [o.material ?? []].flat()) {
        for (const value of Object.values(material)) if (value && value.isTexture) value.dispose();
        material.dispose();
      }
    });
  }
  model = gltf.scene;
  scene.add(model);
  if (state.frameNext) {
    frame(model);
    state.frameNext = false;
  }
  draw();
}

// ---- the editor ---------------------------------------------------------------------------
let debounce = null;
// Text the page puts in the editor (a script chosen) is not an edit to debounce.
const fromCode = Annotation.define();
const editor = new EditorView({
  parent: $('editor'),
  extensions: [
    basicSetup,
    StreamLanguage.define(lua),
    lintGutter(),
    EditorView.updateListener.of((u) => {
      if (u.docChanged && !u.transactions.some((t) => t.annotation(fromCode))) schedule(DEBOUNCE_MS);
    }),
  ],
});

function setText(text) {
  editor.dispatch({ changes: { from: 0, to: editor.state.doc.length, insert: text }, annotations: fromCode.of(true) });
}

function markError(info) {
  const diagnostics = [];
  if (info && info.line && info.file === state.path && info.line <= editor.state.doc.lines) {
    const line = editor.state.doc.line(info.line);
    diagnostics.push({ from: line.from, to: Math.max(line.to, line.from), severity: 'error', message: info.error });
  }
  editor.dispatch(setDiagnostics(editor.state, diagnostics));
}

// ---- generating ---------------------------------------------------------------------------
function status(text, error = false) {
  $('status').textContent = text;
  $('status').classList.toggle('error', error);
}

function request() {
  return {
    path: state.path,
    source: editor.state.doc.toString(),
    seed: Math.max(0, Math.floor(Number($('seed').value) || 0)),
    params: state.overrides,
    timeLimit: TIME_LIMIT,
  };
}

let busy = false;
let pending = null;
function schedule(delay) {
  clearTimeout(debounce);
  debounce = setTimeout(() => submit(request()), delay);
}
async function submit(req) {
  if (busy) {
    pending = req; // the newest edit runs when this run ends
    return;
  }
  busy = true;
  document.body.dataset.busy = 'true';
  status('Generating…');
  let result = await call(req);
  if (result.fatal) {
    worker.terminate();
    startWorker();
    result = { ok: false, info: { error: `the engine stopped: ${result.fatal}` } };
  }
  await handle(result, req);
  busy = false;
  document.body.dataset.busy = 'false';
  if (pending) {
    const next = pending;
    pending = null;
    submit(next);
  }
}

async function handle(result, req) {
  if (result.ok) {
    state.glb = result.glb;
    try {
      await show(result.glb);
    } catch (e) {
      status(`three.js could not read the model: ${e.message ?? e}`, true);
    }
    markError(null);
    const { triangles, leaves, warnings } = result.info;
    $('triangles').textContent = String(triangles);
    $('leaves').textContent = String(leaves);
    $('ms').textContent = result.ms.toFixed(0);
    $('download').disabled = false;
    params(result.info.params);
    status(warnings.length ? warnings.join('\n') : `${req.path}: ${triangles} triangles in ${result.ms.toFixed(0)} ms`);
  } else {
    // The last good model stays in the view.
    markError(result.info);
    status(result.info.error, true);
  }
  state.generation++;
  document.body.dataset.generation = String(state.generation);
}

// ---- parameters as sliders ----------------------------------------------------------------
function params(list) {
  const box = $('params');
  const signature = JSON.stringify(list.map((p) => [p.name, p.min, p.max, p.default]));
  if (box.dataset.signature !== signature) {
    box.dataset.signature = signature;
    box.replaceChildren();
    for (const p of list) box.append(control(p));
  }
  for (const p of list) {
    const input = box.querySelector(`[data-name="${CSS.escape(p.name)}"]`);
    if (!input || document.activeElement === input) continue;
    if (input.type === 'checkbox') input.checked = Boolean(p.value);
    else input.value = p.value;
    const shown = input.parentElement.querySelector('.value');
    if (shown) shown.textContent = String(p.value);
  }
}

function control(p) {
  const div = document.createElement('div');
  div.className = 'param';
  const label = document.createElement('label');
  label.textContent = p.name;
  if (p.doc) label.title = p.doc;
  const value = document.createElement('span');
  value.className = 'value';
  label.append(value);
  const input = document.createElement('input');
  input.dataset.name = p.name;
  if (typeof p.default === 'boolean') {
    input.type = 'checkbox';
  } else if (typeof p.default === 'number' && p.min != null && p.max != null) {
    input.type = 'range';
    input.min = p.min;
    input.max = p.max;
    input.step = Number.isInteger(p.default) && Number.isInteger(p.min) ? 1 : (p.max - p.min) / 200;
  } else {
    input.type = typeof p.default === 'number' ? 'number' : 'text';
  }
  const read = () => (input.type === 'checkbox' ? input.checked : input.type === 'text' ? input.value : Number(input.value));
  input.addEventListener('input', () => {
    value.textContent = String(read());
  });
  input.addEventListener('change', () => {
    state.overrides[p.name] = read();
    schedule(0);
  });
  div.append(label, input);
  return div;
}

// ---- library, download, share --------------------------------------------------------------
function choose(path, text) {
  state.path = path;
  state.overrides = {};
  state.frameNext = true;
  $('params').replaceChildren();
  $('params').dataset.signature = '';
  setText(text);
  markError(null);
  schedule(0);
}

$('script').addEventListener('change', () => {
  const path = $('script').value;
  const found = state.library.find(([p]) => p === path);
  if (found) choose(path, found[1]);
});
$('seed').addEventListener('change', () => schedule(0));

$('download').addEventListener('click', () => {
  if (!state.glb) return;
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([state.glb], { type: 'model/gltf-binary' }));
  a.download = state.path.split('/').pop().replace(/\.lua$/, '') + '.glb';
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
});

// The share link carries the script, deflated, in the URL's hash: #s=BASE64URL.
async function pack(object) {
  const stream = new Blob([JSON.stringify(object)]).stream().pipeThrough(new CompressionStream('deflate-raw'));
  const bytes = new Uint8Array(await new Response(stream).arrayBuffer());
  let text = '';
  for (const b of bytes) text += String.fromCharCode(b);
  return btoa(text).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}
async function unpack(packed) {
  const text = atob(packed.replace(/-/g, '+').replace(/_/g, '/'));
  const bytes = Uint8Array.from(text, (c) => c.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate-raw'));
  return JSON.parse(await new Response(stream).text());
}
$('share').addEventListener('click', async () => {
  const hash = '#s=' + (await pack({ path: state.path, source: editor.state.doc.toString(), seed: Number($('seed').value), params: state.overrides }));
  history.replaceState(null, '', hash);
  const link = location.href;
  try {
    await navigator.clipboard.writeText(link);
    status('The share link is copied (and in the address bar).');
  } catch {
    status('The share link is in the address bar.');
  }
});

// ---- start --------------------------------------------------------------------------------
async function start() {
  startWorker();
  const { library } = await call('library');
  state.library = library;
  const select = $('script');
  const groups = new Map();
  for (const [path] of library) {
    const folder = path.split('/').slice(1, -1).join('/');
    if (!groups.has(folder)) {
      const group = document.createElement('optgroup');
      group.label = folder;
      groups.set(folder, group);
      select.append(group);
    }
    const option = document.createElement('option');
    option.value = path;
    option.textContent = path.split('/').pop();
    groups.get(folder).append(option);
  }
  let shared = null;
  if (location.hash.startsWith('#s=')) {
    try {
      shared = await unpack(location.hash.slice(3));
    } catch {
      status('The share link could not be read.', true);
    }
  }
  if (shared && typeof shared.source === 'string') {
    select.value = shared.path;
    $('seed').value = shared.seed ?? 1;
    choose(shared.path ?? 'scripts/playground.lua', shared.source);
    state.overrides = shared.params ?? {};
  } else {
    // `?script=scripts/lsystems/koch.lua` opens on that library script.
    const asked = new URLSearchParams(location.search).get('script');
    const [path, text] = library.find(([p]) => p === asked) ?? library.find(([p]) => p === DEFAULT_SCRIPT);
    select.value = path;
    choose(path, text);
  }
}

// For the browser test and for poking at the page from the console.
window.playground = { editor, state, scene, renderer, camera, model: () => model, debounceMs: DEBOUNCE_MS };
start();
