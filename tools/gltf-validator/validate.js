// Validate a .glb with the Khronos glTF validator and print one JSON line:
// {"errors": N, "warnings": N, "infos": N, "hints": N, "messages": [...]}.
// Usage: node tools/gltf-validator/validate.js FILE.glb
const fs = require('fs');
const validator = require('gltf-validator');
const file = process.argv[2];
if (!file) {
  console.error('usage: node validate.js FILE.glb');
  process.exit(2);
}
validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), { maxIssues: 100 })
  .then((report) => {
    const i = report.issues;
    const messages = i.messages.map((m) => `${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer || ''}: ${m.message}`);
    console.log(JSON.stringify({ errors: i.numErrors, warnings: i.numWarnings, infos: i.numInfos, hints: i.numHints, messages }));
  })
  .catch((e) => {
    console.error(`validation failed: ${e}`);
    process.exit(1);
  });
