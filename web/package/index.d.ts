// Types of atmo-sky (docs/web.md). Units: metres, degrees, cd/m^2 (luminance frames and tables, in
// linear sRGB), W m^-2 sr^-1 nm^-1 (unit 'radiance'), sr^-1 per unit solar irradiance ('relative').

export type Unit = 'relative' | 'radiance' | 'luminance';

export interface ModelConfig {
  preset?: string;          // 'earth', 'earth-spectral', 'us-standard', ... (atmo presets)
  json?: string;            // a whole parameter set as atmo's JSON (instead of preset)
  spectral?: number;        // resample to N wavelengths over 360-830 nm
  wavelengths?: number[];   // or to these wavelengths (nm)
  options?: Record<string, string | number>;  // model options (--option KEY=VALUE)
  aerosol?: string;         // OPAC aerosol type
  aod?: number;             // aerosol optical depth at 550 nm
  angstrom?: number;
  visibility?: number;      // km
  turbidity?: number;       // Linke turbidity
}

export interface ViewRequest {
  altitude?: number;        // m
  sunElevation?: number;    // degrees
  sunAzimuth?: number;      // compass degrees (0 north, 90 east)
  sunDisc?: boolean;
  ground?: boolean;
}

export interface FrameRequest extends ViewRequest {
  camera?: 'perspective' | 'fisheye' | 'equirect';
  width?: number;
  height?: number;
  fov?: number;             // horizontal, degrees
  yaw?: number;             // compass degrees of the view centre
  pitch?: number;           // degrees
  unit?: Unit;
}

export interface Frame {
  width: number;
  height: number;
  channels: number;
  pixels: Float32Array;     // rows from the top, `channels` floats per pixel
  alpha: Float32Array | null;
  ms: number;
}

export interface SkyViewTable {
  width: number;
  height: number;
  texels: Float32Array;     // RGBA, linear sRGB cd/m^2, hillaire's sky-view mapping
  rKm: number;
  bottomRadiusKm: number;
  topRadiusKm: number;
  horizonNadirAngle: number;
  sunDisc: Float64Array;    // the disc's centre radiance, linear sRGB cd/m^2
  sunAngularRadius: number; // radians
  autoEv100: number;
  ms: number;
}

export interface CubeMap {
  size: number;
  faces: Float32Array[];    // three.js's order px, nx, py, ny, pz, nz and orientation; RGB cd/m^2
  ms: number;
}

export interface Sample {
  radiance: Float64Array;
  transmittance: Float64Array;
  standardError: Float64Array;
  channels: number;
}

export declare class Model {
  constructor(name: 'hillaire' | 'source4d' | 'elek' | 'simple', config?: ModelConfig);
  readonly name: string;
  readonly preset: string;
  readonly channelCount: number;
  readonly precomputeMs: number;
  readonly topAltitude: number;
  readonly groundRadius: number;
  readonly sunAngularRadius: number;
  readonly parameterHash: string;
  parametersJson(): string;
  wavelengths(): Float64Array;
  solarIrradiance(): Float64Array;
  sample(altitude: ArrayLike<number>, sunZenith: ArrayLike<number>, viewZenith: ArrayLike<number>,
         azimuthFromSun: ArrayLike<number>, unit: Unit): Sample;
  renderFrame(request?: FrameRequest): Frame;
  skyView(request?: ViewRequest & { width?: number; height?: number }): SkyViewTable;
  cubeMap(request?: ViewRequest & { size?: number }): CubeMap;
  ktx2(request?: ViewRequest & { size?: number; mips?: boolean; float32?: boolean }): Uint8Array;
  delete(): void;
}

export interface Atmo {
  Model: typeof Model;
  modelNames(): string[];
  presetNames(): string[];
  presetJson(name: string): string;
  sunFromDate(isoDate: string, latitude: number, longitude: number): { elevation: number; azimuth: number };
  version(): string;
  /** The threads the module's table loops run on: 1 in this package's single-threaded module. */
  threads(): number;
}

export declare function loadAtmo(options?: { wasmBinary?: ArrayBuffer | Uint8Array }): Promise<Atmo>;
export declare function loadSkyGlsl(): Promise<string>;
export declare const kSkyShading: string;
export declare function skyUniformValues(table: SkyViewTable, sunElevationDeg: number, sunAzimuthDeg: number,
                                         sunDisc?: boolean): Record<string, number | number[]>;
export declare function exposureFromEv100(ev100: number): number;
