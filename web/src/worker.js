// The engine in a Web Worker: the page posts requests, the worker answers with the glb and
// its statistics (or the failure), so typing never waits for a model.
/* global importScripts, createPge */
import { wrapEngine } from './engine.mjs';

importScripts('pge-web.js');
const ready = createPge({
  // The glue looks for the .wasm under its crate's name: it is served beside this script.
  locateFile: (path, dir) => (path.endsWith('.wasm') ? dir + 'pge-web.wasm' : dir + path),
}).then(wrapEngine);

self.onmessage = async ({ data: { id, request } }) => {
  try {
    const engine = await ready;
    if (request === 'library') {
      self.postMessage({ id, library: engine.library() });
      return;
    }
    const t = performance.now();
    const result = engine.generate(request);
    result.ms = performance.now() - t;
    self.postMessage({ id, ...result }, result.glb ? [result.glb.buffer] : []);
  } catch (e) {
    // The module aborted (out of memory beyond the limit's reach, a trap): it is unusable.
    self.postMessage({ id, fatal: String(e && e.message ? e.message : e) });
  }
};
