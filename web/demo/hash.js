// FNV-1a (32-bit) over the little-endian bytes of a typed array: the checksum
// the browser test compares between the WebAssembly decoder and the native one.
export function fnv1a(view, h = 0x811c9dc5) {
  const b = new Uint8Array(view.buffer, view.byteOffset, view.byteLength);
  for (let i = 0; i < b.length; ++i) {
    h ^= b[i];
    h = Math.imul(h, 0x01000193);
  }
  return h >>> 0;
}

export const hex = (h) => h.toString(16).padStart(8, '0');
