// Types of the tsm decoder's JavaScript API (tsm.js).

export declare const ErrorCode: Readonly<{
  OK: 0; INVALID_ARGUMENT: 1; IO_ERROR: 2; PARSE_ERROR: 3; CORRUPT_DATA: 4;
  UNSUPPORTED: 5; LIMIT_EXCEEDED: 6; INTERNAL: 7;
}>;
export type AttributeKind = 'generic' | 'normal' | 'color' | 'texcoord';
export type AttributeDomain = 'vertex' | 'face' | 'corner';
export type AttributeType = 'f32' | 'u8' | 'u16' | 'i32';
export declare const AttributeKinds: readonly AttributeKind[];
export declare const AttributeDomains: readonly AttributeDomain[];
export declare const AttributeTypes: readonly AttributeType[];

export declare class TsmError extends Error {
  readonly name: 'TsmError';
  /** One of ErrorCode's values. */
  readonly code: number;
  /** 'invalid_argument', 'corrupt_data', 'limit_exceeded', ... */
  readonly codeName: string;
  /** Set when the file needs the full module and it is not loaded (decode, feed, finish): await loadFull(). */
  readonly needsFull?: boolean;
}

export type Bytes = Uint8Array | ArrayBuffer | ArrayBufferView;
export type ByteSource = ReadableStream<Uint8Array> | Uint8Array | ArrayBuffer
  | Iterable<Bytes> | AsyncIterable<Bytes>;

/** Limits checked before anything is allocated; 0 or absent: none. */
export interface DecodeOptions {
  maxVertices?: number;
  maxFaces?: number;
  maxCorners?: number;
}

export interface Attribute {
  /** 'normal', 'texcoord', 'color' or the file's own name. */
  name: string;
  kind: AttributeKind;
  domain: AttributeDomain;
  /** How the values were stored; the values are floats here. */
  type: AttributeType;
  /** 1..4 floats per value. */
  components: number;
  /** components × valueCount floats. */
  values: Float32Array;
  /** Corner domain: one value number per face corner; else null. */
  indices: Uint32Array | null;
  valueStart: number;
  valueCount: number;
}

export interface MetadataEntry {
  key: string;
  value: Uint8Array;
}

export interface DecodedMesh {
  /** 3 floats per vertex. */
  positions: Float32Array;
  /** The corners of every face (3 per triangle). */
  indices: Uint32Array;
  /** faceCount + 1 offsets into indices; only when some face is not a triangle. */
  faceOffsets?: Uint32Array;
  vertexStart: number;
  vertexCount: number;
  faceStart: number;
  faceCount: number;
  cornerStart: number;
  attributes: Attribute[];
  metadata: MetadataEntry[];
}

/** A piece of a streamed mesh: new vertices, faces and attribute values (see web/README.md). */
export interface Segment extends Omit<DecodedMesh, 'metadata'> {
  index: number;
  segmentCount: number;
  segmentsDone: number;
  bytesIn: number;
  decodeMs: number;
  /** Present on the piece where the metadata first appears. */
  metadata?: MetadataEntry[];
  /** Progressive files: true on a level of detail, the whole current mesh (draw it instead of what came before). */
  level?: boolean;
  /** With level: refinement batches applied (0 = the base). */
  batchesDone?: number;
  /** With level: the encoder's error of the level (model units), -1 while unknown. */
  levelError?: number;
}

export interface LoadOptions {
  /** Where tsm_decoder.wasm, the core module, is (default: beside tsm.js). */
  wasmUrl?: string | URL;
  /** The core module's bytes: no fetch (Node). */
  wasmBinary?: ArrayBuffer | Uint8Array;
  /** Where tsm_decoder_full.wasm is (default: beside tsm.js); fetched when a file first needs it. */
  fullWasmUrl?: string | URL;
  /** The full module's bytes (Node). */
  fullWasmBinary?: ArrayBuffer | Uint8Array;
  /** Load the full module now: decode() then handles every file without decodeAsync. */
  full?: boolean;
}

export declare class TsmStream {
  readonly segmentCount: number;
  readonly segmentsDone: number;
  /** The segments this chunk finished (often none). */
  feed(chunk: Bytes): Segment[];
  /** Throws a TsmError on a truncated file. */
  finish(): Segment[];
  /** feed() and finish(), loading the full module when the file needs it. */
  feedAsync(chunk: Bytes): Promise<Segment[]>;
  finishAsync(): Promise<Segment[]>;
  free(): void;
}

export declare class TsmDecoder {
  readonly version: string;
  readonly hasStreaming: boolean;
  readonly hasAttributes: boolean;
  /** Throws a TsmError on a damaged, truncated or over-limit file, and (needsFull)
   *  on a file that needs the full module while only the core is loaded. */
  decode(bytes: Bytes, options?: DecodeOptions): DecodedMesh;
  /** decode(), loading the full module first when the file needs it. */
  decodeAsync(bytes: Bytes, options?: DecodeOptions): Promise<DecodedMesh>;
  /** Loads the full module (progressive batches, keep-order, zstd-coded sections) once. */
  loadFull(): Promise<TsmDecoder>;
  createStream(options?: DecodeOptions): TsmStream;
  decodeStream(source: ByteSource, options?: DecodeOptions): AsyncGenerator<Segment, void, undefined>;
}

export declare function loadTsm(options?: LoadOptions): Promise<TsmDecoder>;

/** A module Worker running tsm-worker.js, to reuse across decodes. */
export declare function createTsmWorker(workerUrl?: string | URL): Worker;

export interface WorkerOptions {
  /** Kept after the call; without it a worker is made and ended for the call. */
  worker?: Worker;
  workerUrl?: string | URL;
  wasmUrl?: string | URL;
  decodeOptions?: DecodeOptions;
}

export declare function decodeStreamInWorker(source: ByteSource, options?: WorkerOptions):
  AsyncGenerator<Segment, void, undefined>;
export declare function decodeInWorker(bytes: Bytes, options?: WorkerOptions): Promise<DecodedMesh>;
