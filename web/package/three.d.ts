// Types of atmo-sky/three (docs/web.md).
import * as THREE from 'three';

import type { Model, SkyViewTable, ViewRequest } from './index.js';

export interface SkyViewOptions extends ViewRequest {
  tableWidth?: number;
  tableHeight?: number;
}

export declare class AtmoSky extends THREE.Mesh<THREE.BoxGeometry, THREE.ShaderMaterial> {
  constructor(glsl: string);
  table: SkyViewTable | null;
  update(model: Model, view?: SkyViewOptions, renderer?: THREE.WebGLRenderer | null): SkyViewTable;
  setTable(table: SkyViewTable, sunElevation: number, sunAzimuth: number, sunDisc?: boolean,
           renderer?: THREE.WebGLRenderer | null): void;
  sunDirection(target?: THREE.Vector3): THREE.Vector3;
  dispose(): void;
}

export declare function atmoCubeTexture(model: Model, view?: ViewRequest & { size?: number }, scale?: number): THREE.CubeTexture;

export declare function atmoEnvironment(renderer: THREE.WebGLRenderer, model: Model,
                                        view?: ViewRequest & { size?: number }):
    { texture: THREE.Texture; intensity: number; renderTarget: THREE.WebGLRenderTarget };
