// Builds the page into dist/: the bundles (esbuild) and the engine's WebAssembly module
// (built by cargo: `.ci/web` or README.md), copied from the target folder.
//   node build.mjs [WASM_DIR]   (default ../target/wasm32-unknown-emscripten/web)
import { copyFileSync, existsSync, mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import * as esbuild from 'esbuild';

const here = dirname(fileURLToPath(import.meta.url));
const wasmDir = resolve(process.argv[2] ?? join(here, '../target/wasm32-unknown-emscripten/web'));
const dist = join(here, 'dist');
mkdirSync(dist, { recursive: true });
for (const [from, to] of [['pge-web.js', 'pge-web.js'], ['pge_web.wasm', 'pge-web.wasm']]) {
  const file = join(wasmDir, from);
  if (!existsSync(file)) {
    console.error(`build: ${file} is missing: build the engine first (see the playground in README.md)`);
    process.exit(1);
  }
  copyFileSync(file, join(dist, to));
}
const common = { bundle: true, minify: true, sourcemap: true, target: 'es2022', logLevel: 'warning' };
await esbuild.build({ ...common, entryPoints: [join(here, 'src/main.js')], outfile: join(dist, 'main.js'), format: 'esm' });
await esbuild.build({ ...common, entryPoints: [join(here, 'src/worker.js')], outfile: join(dist, 'worker.js'), format: 'iife' });
console.log(`build: ${dist}`);
