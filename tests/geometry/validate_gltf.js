// SPDX-License-Identifier: GPL-3.0-or-later
// Runs the Khronos glTF validator (npm package gltf-validator) on one .gltf/.glb file.
// Usage: node validate_gltf.js NODE_MODULES_DIR FILE
// Prints "errors=N warnings=N infos=N hints=N" and then each error/warning; exits 0 when the
// validator ran (the caller judges the counts), 2 when it could not run.
'use strict';
const fs = require('fs');
const path = require('path');

async function main() {
  const [modulesDir, file] = process.argv.slice(2);
  const validator = require(path.resolve(modulesDir, 'gltf-validator'));
  const bytes = new Uint8Array(fs.readFileSync(file));
  const folder = path.dirname(path.resolve(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        const target = path.resolve(folder, decodeURIComponent(uri));
        if (!target.startsWith(folder + path.sep)) return reject(new Error('outside folder: ' + uri));
        fs.readFile(target, (err, data) => (err ? reject(err) : resolve(new Uint8Array(data))));
      }),
  });
  const i = report.issues;
  console.log(`errors=${i.numErrors} warnings=${i.numWarnings} infos=${i.numInfos} hints=${i.numHints}`);
  for (const m of i.messages) if (m.severity <= 1) console.log(`${m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer || ''}: ${m.message}`);
}

main().catch((e) => {
  console.log('validator failed: ' + e);
  process.exit(2);
});
