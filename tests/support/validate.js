const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');
// External buffers (a tile's shared variants, `../variants.bin`) are read beside the file.
const external = (file) => (uri) => new Promise((resolve, reject) => {
  fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
    err ? reject(err.toString()) : resolve(new Uint8Array(data)));
});
(async () => {
  let failed = 0;
  for (const f of process.argv.slice(2)) {
    const data = new Uint8Array(fs.readFileSync(f));
    const r = await validator.validateBytes(data, {maxIssues: 100, uri: f, externalResourceFunction: external(f)});
    const i = r.issues;
    console.log(`${f}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages) if (m.severity <= 1) console.log(`  ${m.severity==0?'error':'warning'} ${m.code}: ${m.message} (${m.pointer||''})`);
    if (i.numErrors > 0) failed++;
  }
  process.exit(failed ? 1 : 0);
})();
