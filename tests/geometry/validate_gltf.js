// SPDX-License-Identifier: GPL-3.0-or-later
// Runs the Khronos glTF validator (npm package gltf-validator) on one .gltf/.glb file.
// Usage: node validate_gltf.js NODE_MODULES_DIR FILE
// Prints "errors=N warnings=N infos=N hints=N" and then each error/warning; exits 0 when the
// validator ran (the caller judges the counts), 2 when it could not run.
//
// The validator (2.0.0-dev.3.10, the newest) does not support KHR_texture_basisu
// (KhronosGroup/glTF-Validator#177): it warns that a KTX2 image's mimeType is not PNG or JPEG and
// that its format is unrecognized. Those two warnings, on exactly the images that a texture's
// KHR_texture_basisu names, are not counted (they are listed as "known"); the KTX2 files
// themselves are checked by three.js's transcoder in texfab's tests.
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
  const ktx2 = new Set(basisuImages(bytes, file).map((index) => `/images/${index}`));
  const known = (m) =>
    m.severity === 1 &&
    ((m.code === 'VALUE_NOT_IN_LIST' && ktx2.has((m.pointer || '').replace(/\/mimeType$/, '')) && m.message.includes("'image/ktx2'")) ||
     (m.code === 'IMAGE_UNRECOGNIZED_FORMAT' && ktx2.has(m.pointer)));
  const counted = i.messages.filter((m) => m.severity <= 1 && !known(m));
  const errors = counted.filter((m) => m.severity === 0).length, warnings = counted.length - errors;
  if (i.truncated) throw new Error('the report was truncated');
  console.log(`errors=${errors} warnings=${warnings} infos=${i.numInfos} hints=${i.numHints}`);
  for (const m of i.messages)
    if (m.severity <= 1) console.log(`${known(m) ? 'known' : m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer || ''}: ${m.message}`);
}

// The images that textures name as their KHR_texture_basisu source.
function basisuImages(bytes, file) {
  let text;
  if (file.endsWith('.glb')) {
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    text = new TextDecoder().decode(bytes.subarray(20, 20 + view.getUint32(12, true)));
  } else {
    text = new TextDecoder().decode(bytes);
  }
  const textures = JSON.parse(text).textures || [];
  return textures.map((t) => t.extensions?.KHR_texture_basisu?.source).filter((s) => s !== undefined);
}

main().catch((e) => {
  console.log('validator failed: ' + e);
  process.exit(2);
});
