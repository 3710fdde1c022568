// Reads a KTX 2.0 file with the npm package ktx-parse (a reader atmo did not write) and prints
// what tests/cubemap_test.cc checks, as JSON: the header, the data format descriptor, the
// key/value data, each level's byte length and the texels asked for on the command line
// ("level,face,i,j", decoded from R16G16B16A16_SFLOAT or R32G32B32A32_SFLOAT), and whether
// ktx-parse's own writer, given what it read, writes the same bytes (the same layout, padding
// and level order).
//   node ktx2_inspect.mjs FILE [level,face,i,j ...]     (NODE_PATH: where ktx-parse is installed)
import { readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import { pathToFileURL } from 'node:url';
import path from 'node:path';

// ktx-parse is an ES module; resolve it through NODE_PATH explicitly (ES imports ignore it).
const roots = (process.env.NODE_PATH || '').split(path.delimiter).filter(Boolean);
let ktx = null;
for (const root of roots) {
  try {
    const require = createRequire(path.join(root, 'noop.js'));
    ktx = await import(pathToFileURL(require.resolve('ktx-parse')).href);
    break;
  } catch (e) { /* try the next root */ }
}
if (ktx === null) ktx = await import('ktx-parse');

const file = process.argv[2];
const bytes = new Uint8Array(readFileSync(file));
const c = ktx.read(bytes);

function half(h) {
  const s = h & 0x8000 ? -1 : 1;
  const e = (h >> 10) & 0x1f;
  const m = h & 0x3ff;
  if (e === 0) return s * m * 2 ** -24;
  if (e === 31) return m ? NaN : s * Infinity;
  return s * (1 + m / 1024) * 2 ** (e - 15);
}

const typeSize = c.typeSize;
const texels = [];
for (const spec of process.argv.slice(3)) {
  const [level, face, i, j] = spec.split(',').map(Number);
  const size = Math.max(1, c.pixelWidth >> level);
  const data = c.levels[level].levelData;
  const view = new DataView(data.buffer, data.byteOffset, data.byteLength);
  const texel = ((face * size + j) * size + i) * 4;
  const rgba = [];
  for (let k = 0; k < 4; ++k) {
    rgba.push(typeSize === 2 ? half(view.getUint16((texel + k) * 2, true)) : view.getFloat32((texel + k) * 4, true));
  }
  texels.push({ level, face, i, j, rgba });
}

const again = ktx.write(c, { keepWriter: true });
const identical = again.byteLength === bytes.byteLength && again.every((b, k) => b === bytes[k]);
const dfd = c.dataFormatDescriptor[0];
console.log(JSON.stringify({
  vkFormat: c.vkFormat, typeSize: c.typeSize, pixelWidth: c.pixelWidth, pixelHeight: c.pixelHeight,
  pixelDepth: c.pixelDepth, layerCount: c.layerCount, faceCount: c.faceCount, levelCount: c.levelCount,
  supercompressionScheme: c.supercompressionScheme,
  levels: c.levels.map((l) => ({ byteLength: l.levelData.byteLength, uncompressedByteLength: l.uncompressedByteLength })),
  dfd: { colorModel: dfd.colorModel, colorPrimaries: dfd.colorPrimaries, transferFunction: dfd.transferFunction,
         flags: dfd.flags, bytesPlane0: dfd.bytesPlane[0],
         samples: dfd.samples.map((s) => ({ bitOffset: s.bitOffset, bitLength: s.bitLength, channelType: s.channelType })) },
  keyValue: c.keyValue,
  texels,
  rewrittenIdentical: identical,
}));
