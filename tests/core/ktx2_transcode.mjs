// SPDX-License-Identifier: GPL-3.0-or-later
// Reads a KTX2 file with three.js's Basis Universal transcoder (the one KTX2Loader runs) the way
// KTX2Loader does: KTX2File, isValid, startTranscoding, then every level transcoded. Writes each
// level as raw RGBA8 (cTFRGBA32) to <out-prefix><level>.rgba and checks that the GPU targets
// KTX2Loader picks (ASTC 4x4, BC7, BC1, ETC1) transcode too. Prints one JSON line:
//   {"ok":true,"uastc":true,"width":W,"height":H,"levels":[{"width":w,"height":h,"bytes":n},...]}
// or {"ok":false,"error":"..."} (exit 1).
// Usage: node ktx2_transcode.mjs <node_modules folder holding three> <file.ktx2> <out-prefix>
import { readFileSync, writeFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';

const [modules, file, prefix] = process.argv.slice(2);
const fail = (error) => {
  console.log(JSON.stringify({ ok: false, error }));
  process.exit(1);
};
if (!modules || !file || !prefix) fail('usage: ktx2_transcode.mjs <node_modules> <file.ktx2> <out-prefix>');

const dir = path.join(modules, 'three', 'examples', 'jsm', 'libs', 'basis');
// An Emscripten script that defines BASIS; three's package is ESM, so it cannot be require()d:
// run it as a function body with the CommonJS names it uses.
const script = readFileSync(path.join(dir, 'basis_transcoder.js'), 'utf8');
const BASIS = new Function('require', '__dirname', `${script}\nreturn BASIS;`)(createRequire(import.meta.url), dir);
const basis = await BASIS({ wasmBinary: readFileSync(path.join(dir, 'basis_transcoder.wasm')) });
basis.initializeBasis();

// Transcoder formats (KTX2Loader.TranscoderFormat).
const RGBA32 = 13, GPU = { ASTC_4x4: 10, BC7: 6, BC1: 2, ETC1: 0 };

const ktx2 = new basis.KTX2File(new Uint8Array(readFileSync(file)));
try {
  if (!ktx2.isValid()) fail('KTX2File.isValid() is false');
  const width = ktx2.getWidth(), height = ktx2.getHeight(), count = ktx2.getLevels();
  if (!width || !height || !count) fail(`invalid texture ${width}x${height}, ${count} levels`);
  if (!ktx2.startTranscoding()) fail('startTranscoding() failed');
  const levels = [];
  for (let level = 0; level < count; level++) {
    const info = ktx2.getImageLevelInfo(level, 0, 0);
    const rgba = new Uint8Array(ktx2.getImageTranscodedSizeInBytes(level, 0, 0, RGBA32));
    if (!ktx2.transcodeImage(rgba, level, 0, 0, RGBA32, 0, -1, -1)) fail(`level ${level}: RGBA32 transcode failed`);
    writeFileSync(`${prefix}${level}.rgba`, rgba);
    for (const [name, format] of Object.entries(GPU)) {
      const dst = new Uint8Array(ktx2.getImageTranscodedSizeInBytes(level, 0, 0, format));
      if (!ktx2.transcodeImage(dst, level, 0, 0, format, 0, -1, -1)) fail(`level ${level}: ${name} transcode failed`);
    }
    levels.push({ width: info.origWidth, height: info.origHeight, bytes: rgba.length });
  }
  console.log(JSON.stringify({ ok: true, uastc: ktx2.isUASTC(), hasAlpha: !!ktx2.getHasAlpha(), width, height, levels }));
} finally {
  ktx2.close();
  ktx2.delete();
}
