// Validates glTF files (.glb / .gltf) with the Khronos glTF Validator (npm package
// gltf-validator) and prints one JSON line per file:
//   {"file", "validator", "errors", "warnings", "infos", "hints", "issues": [first 20 messages]}
// Exit status: 0 when no file has an error, 1 when one has, 3 when the validator is not
// installed (scripts/install-deps.sh puts it in build/npm; run with NODE_PATH=build/npm/node_modules).
// Usage: NODE_PATH=build/npm/node_modules node scripts/gltf_validate.cjs FILE...
'use strict';
const fs = require('fs');
const path = require('path');

let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error('gltf-validator is not installed (npm install --prefix build/npm gltf-validator; scripts/install-deps.sh does it)');
  process.exit(3);
}

(async () => {
  let failed = 0;
  for (const file of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file),
      maxIssues: 1000,
    });
    const summary = report.issues;
    const line = {
      file,
      validator: validator.version(),
      errors: summary.numErrors,
      warnings: summary.numWarnings,
      infos: summary.numInfos,
      hints: summary.numHints,
      issues: summary.messages.slice(0, 20).map((m) => `${m.severity} ${m.code} ${m.pointer || ''}: ${m.message}`),
    };
    console.log(JSON.stringify(line));
    if (summary.numErrors > 0) failed += 1;
  }
  process.exit(failed ? 1 : 0);
})().catch((e) => {
  console.error(`gltf-validator: ${e}`);
  process.exit(2);
});
