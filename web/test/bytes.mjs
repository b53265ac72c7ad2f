// The same bytes: for each script below, the glb the WebAssembly build makes (in Node, from
// the script's text as the page sends it) must equal the one native `pge run` writes, byte for
// byte. Run by .ci/web:  node test/bytes.mjs PGE_BINARY DIST_DIR [OUT_DIR]
// Prints one line per script (sizes, times: native `--stats` seconds, wasm in Node) and exits 1
// when any differs; OUT_DIR/bytes.json keeps the times.
import { spawnSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { wrapEngine } from '../src/engine.mjs';

const repo = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const [pge, dist, report] = process.argv.slice(2).map((p) => resolve(p));
if (!pge || !dist) {
  console.error('usage: node test/bytes.mjs PGE_BINARY DIST_DIR');
  process.exit(2);
}

// Scripts whose glb must be identical: L-systems, modellers, examples.
export const CASES = [
  ['scripts/lsystems/city.lua', {}],
  ['scripts/lsystems/signal.lua', {}],
  ['scripts/modellers/tower.lua', {}],
  ['scripts/modellers/city.lua', {}],
  ['scripts/modellers/explorers.lua', {}],
  ['scripts/modellers/fireworks.lua', {}],
  ['scripts/modellers/sierpinski.lua', {}],
  ['scripts/modellers/coral_metaballs.lua', {}],
  ['scripts/examples/terrain.lua', {}],
  ['scripts/modellers/crystals.lua', {}],
  ['scripts/modellers/coral.lua', {}],
  ['scripts/species/oak.lua', {}],
  ['scripts/species/willow.lua', {}],
  ['scripts/species/bonsai.lua', {}],
  ['scripts/species/conifer.lua', {}],
  ['scripts/species/topiary.lua', {}],
  ['scripts/forests/mixed.lua', { size: 100, points: 200, variants: 1 }],
  ['scripts/forests/plantation.lua', { points: 100 }],
  ['scripts/lsystems/koch.lua', {}],
  ['scripts/lsystems/honda.lua', {}],
  ['scripts/examples/spiral.lua', {}],
];

// Scripts that differed while the maths came from the C library (glibc natively, musl in
// emscripten) and from glam's SSE2 code natively: now pge_engine::math (libm) and glam's
// scalar code everywhere, so they must match too. Lua's `^` still calls C's pow: a script
// using it may differ; none here does in a way that changes its output.
export const MATH_DIFFERS = [];

const require = createRequire(import.meta.url);
const createPge = require(join(dist, 'pge-web.js'));
// Emscripten 3.1.6's glue fetch()es the .wasm whenever fetch exists (Node >= 18): hand it the bytes.
const engine = wrapEngine(await createPge({ wasmBinary: readFileSync(join(dist, 'pge-web.wasm')) }));
const out = mkdtempSync(join(tmpdir(), 'pge-web-bytes-'));
const sha = (b) => createHash('sha256').update(b).digest('hex').slice(0, 12);
let failed = 0;
const times = {};
try {
  for (const [script, given, known] of [...CASES, ...MATH_DIFFERS.map((c) => [...c, true])]) {
    const { seed = 1, ...params } = given;
    const file = join(out, 'native.glb');
    const args = ['run', script, '-o', file, '--quiet', '--stats', '--seed', String(seed)];
    for (const [k, v] of Object.entries(params)) args.push('--set', `${k}=${v}`);
    // The library is this checkout's, whichever build of pge runs.
    const env = { ...process.env, PGE_LIBRARY: join(repo, 'scripts') };
    const native = spawnSync(pge, args, { cwd: repo, encoding: 'utf8', env });
    if (native.status !== 0) {
      console.error(`FAIL ${script}: pge run failed: ${native.error ?? native.stderr}`);
      failed++;
      continue;
    }
    const nativeMs = 1000 * JSON.parse(native.stdout).seconds;
    const expected = readFileSync(file);
    const source = readFileSync(join(repo, script), 'utf8');
    const t = performance.now();
    const got = engine.generate({ path: script, source, seed, params });
    const wasmMs = performance.now() - t;
    times[script] = { nativeMs, wasmMs };
    if (!got.ok) {
      console.error(`FAIL ${script}: the wasm build failed: ${got.info.error}`);
      failed++;
      continue;
    }
    const same = Buffer.from(got.glb).equals(expected);
    const line = `${script} ${JSON.stringify(given)}: ${expected.length} B ${sha(expected)} native; ` +
      `${got.glb.length} B ${sha(got.glb)} wasm; ${got.info.triangles} triangles; ` +
      `native ${nativeMs.toFixed(0)} ms, wasm (Node) ${wasmMs.toFixed(0)} ms`;
    let at = 0;
    while (at < expected.length && expected[at] === got.glb[at]) at++;
    if (known) {
      console.log(same ? `NOW IDENTICAL (move it to CASES) ${line}` : `differs (maths) ${line}: first difference at byte ${at}`);
    } else if (same) {
      console.log(`ok   ${line}`);
    } else {
      console.error(`FAIL ${line}: first difference at byte ${at}`);
      failed++;
    }
  }
} finally {
  rmSync(out, { recursive: true, force: true });
}
if (report) {
  mkdirSync(report, { recursive: true });
  writeFileSync(join(report, 'bytes.json'), JSON.stringify(times) + '\n');
}
console.log(failed === 0 ? `bytes: ${CASES.length} scripts identical (${MATH_DIFFERS.length} more run, differing in float maths)` : `bytes: ${failed} failures`);
process.exit(failed === 0 ? 0 : 1);
