// node tools/gltf/validate.mjs FILE.glb...
// Runs Khronos' glTF-Validator (npm gltf-validator, installed here by
// `npm ci`) on each file and prints one line of counts per file:
//   FILE: validator VERSION: N errors, N warnings, N infos, N hints
// followed by every error and warning (code, pointer, message). Exits 1 if
// any file has an error or a warning (or cannot be read), 2 on bad usage.
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node tools/gltf/validate.mjs FILE.glb...');
  process.exit(2);
}

let failed = false;
for (const file of files) {
  let bytes;
  try {
    bytes = new Uint8Array(readFileSync(file));
  } catch (e) {
    console.log(`${file}: cannot read: ${e.message}`);
    failed = true;
    continue;
  }
  let report;
  try {
    report = await validator.validateBytes(bytes, { uri: file, maxIssues: 0 });
  } catch (e) {
    console.log(`${file}: the validator refused it: ${e}`);
    failed = true;
    continue;
  }
  const i = report.issues;
  console.log(`${file}: validator ${report.validatorVersion}: ${i.numErrors} errors, ` +
              `${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
  for (const m of i.messages) {
    const kind = ['error', 'warning', 'info', 'hint'][m.severity] ?? `severity ${m.severity}`;
    console.log(`  ${kind} ${m.code} ${m.pointer ?? ''} ${m.message}`);
  }
  if (i.numErrors > 0 || i.numWarnings > 0) failed = true;
}
process.exit(failed ? 1 : 0);
