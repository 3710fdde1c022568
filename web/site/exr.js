// OpenEXR for the page's "view as EXR" download: one scan-line image of 32-bit float channels,
// uncompressed, in the layout of the OpenEXR file format ("OpenEXR File Layout", openexr.com):
// magic and version, the required header attributes, the line offset table, then per line its y,
// its size and each channel's row (channels in alphabetical order, as the format requires).
// Readers: OpenEXR itself, Blender, three.js's EXRLoader, `atmo` (tests/web/page_test.mjs reads
// its output back).

// pixels: Float32Array of width x height x channelNames.length, rows from the top.
// attributes: extra string attributes (name -> text), e.g. the parameters of the view.
export function encodeExr(width, height, channelNames, pixels, attributes = {}) {
  const channels = channelNames.map((name, index) => ({ name, index })).sort((a, b) => (a.name < b.name ? -1 : 1));
  const encoder = new TextEncoder();
  const parts = [];
  const bytes = (array) => parts.push(array instanceof Uint8Array ? array : new Uint8Array(array));
  const text = (s) => bytes([...encoder.encode(s), 0]);
  const int32 = (...values) => bytes(new Uint8Array(new Int32Array(values).buffer));
  const float32 = (...values) => bytes(new Uint8Array(new Float32Array(values).buffer));
  const attribute = (name, type, size, write) => {
    text(name);
    text(type);
    int32(size);
    write();
  };
  bytes(new Uint8Array(new Uint32Array([20000630, 2]).buffer));
  const channelBytes = channels.reduce((n, c) => n + encoder.encode(c.name).length + 1 + 16, 1);
  attribute('channels', 'chlist', channelBytes, () => {
    for (const c of channels) {
      text(c.name);
      int32(2, 0, 1, 1);  // FLOAT; pLinear 0 and three reserved bytes; x and y sampling 1
    }
    bytes([0]);
  });
  attribute('compression', 'compression', 1, () => bytes([0]));
  attribute('dataWindow', 'box2i', 16, () => int32(0, 0, width - 1, height - 1));
  attribute('displayWindow', 'box2i', 16, () => int32(0, 0, width - 1, height - 1));
  attribute('lineOrder', 'lineOrder', 1, () => bytes([0]));
  attribute('pixelAspectRatio', 'float', 4, () => float32(1));
  attribute('screenWindowCenter', 'v2f', 8, () => float32(0, 0));
  attribute('screenWindowWidth', 'float', 4, () => float32(1));
  for (const [name, value] of Object.entries(attributes)) {
    const encoded = encoder.encode(value);
    attribute(name, 'string', encoded.length, () => bytes(encoded));
  }
  bytes([0]);
  const headerLength = parts.reduce((n, p) => n + p.length, 0);
  const lineBytes = 8 + width * 4 * channels.length;
  const offsets = new BigUint64Array(height);
  for (let y = 0; y < height; ++y) offsets[y] = BigInt(headerLength + 8 * height + y * lineBytes);
  bytes(new Uint8Array(offsets.buffer));
  const count = channelNames.length;
  for (let y = 0; y < height; ++y) {
    const line = new DataView(new ArrayBuffer(lineBytes));
    line.setInt32(0, y, true);
    line.setInt32(4, lineBytes - 8, true);
    let at = 8;
    for (const c of channels) {
      for (let x = 0; x < width; ++x, at += 4) line.setFloat32(at, pixels[(y * width + x) * count + c.index], true);
    }
    bytes(new Uint8Array(line.buffer));
  }
  const out = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
  let at = 0;
  for (const p of parts) {
    out.set(p, at);
    at += p.length;
  }
  return out;
}
