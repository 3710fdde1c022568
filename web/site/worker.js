// The page's model worker: atmo.wasm off the main thread, so that looking around stays smooth
// while a model builds its tables (source4d takes seconds in one thread). Messages in:
//   {id, type: 'model', name, config, skyView}   build a model (atmo.Model), and with skyView (a
//                                        request) its first sky-view table
//   {id, type: 'skyView', request}       the sky-view table of the current model (Model.skyView)
//   {id, type: 'frame', request}         a frame as `atmo render` makes it (Model.renderFrame)
//   {id, type: 'cubeMap', request}       a cube map in three.js's order (Model.cubeMap)
//   {id, type: 'ktx2', request}          the cube map as KTX2 file bytes (atmo.encodeKtx2)
//   {id, type: 'sample', point: [altitude m, sun zenith, view zenith, azimuth from the sun (deg)]}
//                                        the model's luminance there (Model.sample, cd/m^2)
//   {id, type: 'sampleMany', altitude, sunZenith, viewZenith, azimuth}   arrays of points: Model.sample
//   {id, type: 'sun', date, latitude, longitude}   the sun from date and place (libnova)
// Each answer is {id, ok: true, value} or {id, ok: false, error: the library's one-line message}.
// The threaded module where the page is cross-origin isolated (its server sends COOP and COEP:
// shared memory) on more than one core, the single-threaded one elsewhere; the model's answer
// says how many threads ran (atmo.threads()).
const threaded = self.crossOriginIsolated && (navigator.hardwareConcurrency || 1) > 1;
const atmoReady = import(threaded ? './atmo_mt.mjs' : './atmo.mjs').then((module) => module.default());

let model = null;

function transferables(value) {
  const list = [];
  const visit = (v) => {
    if (ArrayBuffer.isView(v)) list.push(v.buffer);
    else if (Array.isArray(v)) v.forEach(visit);
    else if (v && typeof v === 'object') Object.values(v).forEach(visit);
  };
  visit(value);
  return list;
}

self.onmessage = async (event) => {
  const { id, type } = event.data;
  try {
    const atmo = await atmoReady;
    let value;
    if (type === 'model') {
      const next = new atmo.Model(event.data.name, event.data.config);
      if (model) model.delete();
      model = next;
      value = { name: model.name, preset: model.preset, precomputeMs: model.precomputeMs, passes: model.passTimes(),
                threads: atmo.threads(), channels: model.channelCount, topAltitude: model.topAltitude,
                parameterHash: model.parameterHash };
      // With its first sky-view table, when asked: one round trip for a parameter change.
      if (event.data.skyView) value.table = model.skyView(event.data.skyView);
    } else if (type === 'sun') {
      value = atmo.sunFromDate(event.data.date, event.data.latitude, event.data.longitude);
    } else {
      if (!model) throw new Error('no model yet');
      if (type === 'skyView') value = model.skyView(event.data.request);
      else if (type === 'frame') value = model.renderFrame(event.data.request);
      else if (type === 'cubeMap') value = model.cubeMap(event.data.request);
      else if (type === 'ktx2') value = model.ktx2(event.data.request);
      else if (type === 'sampleMany') {
        const { altitude, sunZenith, viewZenith, azimuth } = event.data;
        value = model.sample(altitude, sunZenith, viewZenith, azimuth, 'luminance');
      } else if (type === 'sample') {
        const [altitude, sunZenith, viewZenith, azimuth] = event.data.point;
        value = { luminance: model.sample([altitude], [sunZenith], [viewZenith], [azimuth], 'luminance').radiance[0] };
      }
      else throw new Error(`unknown request '${type}'`);
    }
    self.postMessage({ id, ok: true, value }, transferables(value));
  } catch (error) {
    self.postMessage({ id, ok: false, error: error instanceof Error ? error.message : String(error) });
  }
};
