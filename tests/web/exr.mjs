// A reader for the OpenEXR files `atmo render` writes (scan lines; NONE, ZIPS or ZIP compression;
// FLOAT or HALF channels), for the web tests, which compare the browser's pixels with the native
// renderer's in float precision. Follows the OpenEXR file layout (openexr.com, "OpenEXR File
// Layout"): magic and version, header attributes up to an empty name, the line offset table, then
// chunks of (y, size, data); ZIP data is zlib, then a byte predictor, then two interleaved halves.
import fs from 'node:fs';
import zlib from 'node:zlib';

// Returns {width, height, channels: {NAME: Float32Array(width * height)}} with row 0 at the top.
export function readExr(file) {
  const buffer = fs.readFileSync(file);
  const view = new DataView(buffer.buffer, buffer.byteOffset, buffer.byteLength);
  if (view.getUint32(0, true) !== 20000630) throw new Error(`${file}: not an OpenEXR file`);
  if ((view.getUint32(4, true) & 0x200) !== 0) throw new Error(`${file}: tiled files are not read here`);
  let at = 8;
  const text = () => {
    const end = buffer.indexOf(0, at);
    const s = buffer.toString('latin1', at, end);
    at = end + 1;
    return s;
  };
  const header = {};
  for (;;) {
    const name = text();
    if (name === '') break;
    const type = text();
    const size = view.getInt32(at, true);
    at += 4;
    header[name] = { type, offset: at, size };
    at += size;
  }
  // Channels: name, pixel type (1 HALF, 2 FLOAT), pLinear, reserved, x and y sampling.
  const channels = [];
  for (let p = header.channels.offset; buffer[p] !== 0;) {
    const end = buffer.indexOf(0, p);
    const name = buffer.toString('latin1', p, end);
    p = end + 1;
    channels.push({ name, type: view.getInt32(p, true) });
    p += 16;
  }
  const compression = buffer[header.compression.offset];
  const window = header.dataWindow.offset;
  const [xMin, yMin, xMax, yMax] = [0, 4, 8, 12].map((k) => view.getInt32(window + k, true));
  const width = xMax - xMin + 1;
  const height = yMax - yMin + 1;
  const linesPerChunk = { 0: 1, 2: 1, 3: 16 }[compression];
  if (linesPerChunk === undefined) throw new Error(`${file}: compression ${compression} is not read here`);
  const chunks = Math.ceil(height / linesPerChunk);
  const out = {};
  for (const c of channels) out[c.name] = new Float32Array(width * height);
  const bytesPerPixel = channels.reduce((sum, c) => sum + (c.type === 1 ? 2 : 4), 0);
  for (let k = 0; k < chunks; ++k) {
    const offset = Number(view.getBigUint64(at + 8 * k, true));
    const y0 = view.getInt32(offset, true) - yMin;
    const size = view.getInt32(offset + 4, true);
    const lines = Math.min(linesPerChunk, height - y0);
    let data = buffer.subarray(offset + 8, offset + 8 + size);
    const expected = lines * width * bytesPerPixel;
    if (compression !== 0 && size < expected) {
      const t = zlib.inflateSync(data);
      for (let i = 1; i < t.length; ++i) t[i] = (t[i - 1] + t[i] - 128) & 0xff;
      const u = Buffer.alloc(t.length);
      const half = (t.length + 1) >> 1;
      for (let i = 0; i < t.length; ++i) u[i] = (i & 1) === 0 ? t[i >> 1] : t[half + (i >> 1)];
      data = u;
    }
    const d = new DataView(data.buffer, data.byteOffset, data.byteLength);
    let p = 0;
    for (let line = 0; line < lines; ++line) {
      for (const c of channels) {
        const row = out[c.name].subarray((y0 + line) * width, (y0 + line + 1) * width);
        for (let x = 0; x < width; ++x) {
          row[x] = c.type === 1 ? halfToFloat(d.getUint16(p, true)) : d.getFloat32(p, true);
          p += c.type === 1 ? 2 : 4;
        }
      }
    }
  }
  return { width, height, channels: out };
}

function halfToFloat(h) {
  const sign = h & 0x8000 ? -1 : 1;
  const exponent = (h >> 10) & 0x1f;
  const mantissa = h & 0x3ff;
  if (exponent === 0) return sign * mantissa * 2 ** -24;
  if (exponent === 31) return mantissa ? NaN : sign * Infinity;
  return sign * (1 + mantissa / 1024) * 2 ** (exponent - 15);
}
