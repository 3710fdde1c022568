// scripts/web_bench.sh's WebAssembly half: builds a model `repeats` times in atmo.wasm (one more
// first, to warm V8's optimising tier), takes each pass's minimum, and prints it beside the native
// minimum from `atmo bench`'s output (NATIVE_FILE), with the ratio.
//   node web/bench.mjs BUILD_WEB_DIR MODEL REPEATS NATIVE_FILE
import fs from 'node:fs';
import path from 'node:path';

const [dir, name, repeatsText, nativeFile] = process.argv.slice(2);
const { default: createAtmo } = await import(path.resolve(dir, 'atmo.mjs'));
const atmo = await createAtmo({ wasmBinary: fs.readFileSync(path.join(dir, 'atmo.wasm')) });
const native = {};
for (const line of fs.readFileSync(nativeFile, 'utf8').split('\n')) {
  const f = line.trim().split(/\s+/);
  if (f.length === 4 && Number.isFinite(Number(f[2]))) native[f[0]] = Number(f[2]);  // min_ms
}
const best = {};
let bestTotal = Infinity;
for (let i = 0; i <= Number(repeatsText); ++i) {
  const model = new atmo.Model(name, { preset: 'earth' });
  if (i > 0) {
    for (const [pass, ms] of Object.entries(model.passTimes())) best[pass] = Math.min(best[pass] ?? Infinity, ms);
    bestTotal = Math.min(bestTotal, model.precomputeMs);
  }
  model.delete();
}
console.log(`${name}: pass, native single-thread min ms, wasm min ms, wasm / native`);
let nativeSum = 0;
let wasmSum = 0;
for (const [pass, ms] of Object.entries(best)) {
  const n = native[pass];
  if (n === undefined) continue;
  nativeSum += n;
  wasmSum += ms;
  console.log(`  ${pass.padEnd(28)} ${n.toFixed(2).padStart(9)} ${ms.toFixed(2).padStart(9)} ${(ms / n).toFixed(2).padStart(6)}`);
}
console.log(`  ${'sum of the passes'.padEnd(28)} ${nativeSum.toFixed(2).padStart(9)} ${wasmSum.toFixed(2).padStart(9)} ` +
            `${(wasmSum / nativeSum).toFixed(2).padStart(6)}   (wasm model build ${bestTotal.toFixed(1)} ms)`);
