// The oak's times, page against native, printed (never checked): the page's first generation
// and its regrowths (OUT_DIR/browser.json, from test/browser.mjs) against native `pge run`
// of the same script, timed here right after, several times. Run by .ci/web:
//   node test/times.mjs PGE_BINARY OUT_DIR
// `#ms` in the page is the worker's call into the engine (the script run, growth, meshing,
// textures, glb written, the glb copied out of the module's memory); native is `--stats`'s
// `seconds` (the same, the file written). A regrowth finds the oak's textures in the engine's
// texture cache (they depend on the bark and leaf parameters, not on the tree's shape), where
// every `pge run` makes them anew: so native is also shown without its textures phase.
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const repo = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const [pge, out] = process.argv.slice(2).map((p) => resolve(p));
if (!pge || !out) {
  console.error('usage: node test/times.mjs PGE_BINARY OUT_DIR');
  process.exit(2);
}
const SCRIPT = 'scripts/species/oak.lua';
const RUNS = 5;

const page = JSON.parse(readFileSync(join(out, 'browser.json'), 'utf8'));
const tmp = mkdtempSync(join(tmpdir(), 'pge-web-times-'));
// Native `pge run` of the oak, RUNS times, on every core (the default) and on one thread
// (as the page runs): its seconds and its textures phase, in milliseconds.
const native = (threads) => {
  const runs = [];
  for (let i = 0; i < RUNS; i++) {
    const args = ['run', SCRIPT, '-o', join(tmp, 'oak.glb'), '--quiet', '--stats', '--seed', '1'];
    if (threads) args.push('--threads', String(threads));
    const env = { ...process.env, PGE_LIBRARY: join(repo, 'scripts') };
    const run = spawnSync(pge, args, { cwd: repo, encoding: 'utf8', env });
    if (run.status !== 0) {
      console.error(`times: pge run failed: ${run.error ?? run.stderr}`);
      process.exit(1);
    }
    const stats = JSON.parse(run.stdout);
    const textures = stats.phases?.textures ?? 0;
    runs.push({ ms: 1000 * stats.seconds, withoutTexturesMs: 1000 * (stats.seconds - textures) });
  }
  return runs;
};
let all, one;
try {
  all = native(null);
  one = native(1);
} finally {
  rmSync(tmp, { recursive: true, force: true });
}

const best = (xs) => Math.min(...xs);
const median = (xs) => [...xs].sort((a, b) => a - b)[(xs.length - 1) >> 1];
const f = (x) => x.toFixed(0);
const r = (a, b) => `${(a / b).toFixed(2)}x`;
const regrow = page.oakRegrowMs;
const n = { best: best(all.map((x) => x.ms)), median: median(all.map((x) => x.ms)) };
const n1 = { best: best(one.map((x) => x.ms)), median: median(one.map((x) => x.ms)) };
const bare = best(all.map((x) => x.withoutTexturesMs));
const p = { first: page.oakFirstMs, best: best(regrow), median: median(regrow) };
console.log(`web: the oak in the page: first generation (the page just opened) ${f(p.first)} ms, regrowth best ${f(p.best)} / median ${f(p.median)} ms (of ${regrow.length})`);
console.log(`web: from the edit to the regrown oak in the page's view: median ${f(median(page.oakRegrowShownMs))} ms ` +
  `(the editor's ${page.debounceMs} ms pause, the generation, three.js reading the glb and its maps)`);
console.log(`web: native release pge run: best ${f(n.best)} / median ${f(n.median)} ms (of ${RUNS}); one thread ${f(n1.best)} / ${f(n1.median)} ms; best without its textures ${f(bare)} ms`);
console.log(`web: page/native: regrowth ${r(p.best, n.best)} (medians ${r(p.median, n.median)}), first ${r(p.first, n.best)}; ` +
  `regrowth against native without textures ${r(p.best, bare)}`);
writeFileSync(join(out, 'times.json'), JSON.stringify({ page: { ...p, shownMedian: median(page.oakRegrowShownMs) }, native: n, nativeOneThread: n1, nativeWithoutTexturesBest: bare }) + '\n');
