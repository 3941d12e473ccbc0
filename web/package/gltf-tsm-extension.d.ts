// Types of the three.js GLTFLoader plugin (gltf-tsm-extension.js).
import type { GLTFLoaderPlugin, GLTFParser } from 'three/examples/jsm/loaders/GLTFLoader.js';
import type { DecodeOptions, TsmDecoder } from './tsm.js';

export declare const EXTENSION_NAME: 'TSM_mesh_compression';

export interface GLTFTsmExtensionOptions {
  /** Streams of at least this many bytes are decoded in a Web Worker (default 262144; Infinity: never, 0: always). */
  workerThreshold?: number;
  wasmUrl?: string | URL;
  workerUrl?: string | URL;
  decodeOptions?: DecodeOptions;
  /** A decoder from loadTsm(), shared between loaders. */
  decoder?: TsmDecoder;
  /** A worker from createTsmWorker(), shared between loaders (kept). */
  worker?: Worker;
}

/** loader.register((parser) => new GLTFTsmExtension(parser, options)) */
export declare class GLTFTsmExtension implements GLTFLoaderPlugin {
  readonly name: 'TSM_mesh_compression';
  constructor(parser: GLTFParser, options?: GLTFTsmExtensionOptions);
}
