// The engine's WebAssembly module behind three functions. `Module` is what emscripten's
// factory (`createPge`) resolved to; used by the page's worker and by the Node test.

export function wrapEngine(Module) {
  const generateRaw = Module.cwrap('pge_web_generate', 'number', ['string']);
  const info = Module.cwrap('pge_web_info', 'number', []);
  const glb = Module.cwrap('pge_web_glb', 'number', []);
  const glbLen = Module.cwrap('pge_web_glb_len', 'number', []);
  const library = Module.cwrap('pge_web_library', 'number', []);
  return {
    // `request`: {path, source, seed, params, timeLimit, memoryLimitMib, instructionLimit}.
    // Returns {ok: true, info, glb: Uint8Array (a copy)} or {ok: false, info: {error, file, line}}.
    generate(request) {
      const status = generateRaw(JSON.stringify(request));
      const parsed = JSON.parse(Module.UTF8ToString(info() >>> 0));
      if (status !== 0) return { ok: false, info: parsed };
      const start = glb() >>> 0;
      const bytes = Module.HEAPU8.slice(start, start + (glbLen() >>> 0));
      return { ok: true, info: parsed, glb: bytes };
    },
    // The library's scripts: [[path, text], ...].
    library() {
      return JSON.parse(Module.UTF8ToString(library() >>> 0));
    },
  };
}
