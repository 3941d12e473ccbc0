// Draco decoding as three.js's DRACOLoader does it, for the benches (the
// bench pages and web/tools/node-bench.mjs): decode, then the indices and
// each attribute out through the heap with one copy each. `ids`: the
// attributes' unique ids (a glTF primitive's KHR_draco_mesh_compression
// attributes); without them, the positions.
export function dracoDecode(draco, bytes, ids) {
  const decoder = new draco.Decoder();
  const mesh = new draco.Mesh();
  try {
    const status = decoder.DecodeArrayToMesh(bytes, bytes.byteLength, mesh);
    if (!status.ok() || mesh.ptr === 0) throw new Error('draco: ' + status.error_msg());
    const faceCount = mesh.num_faces(), vertexCount = mesh.num_points();
    const n = faceCount * 3;
    let ptr = draco._malloc(n * 4);
    decoder.GetTrianglesUInt32Array(mesh, n * 4, ptr);
    const indices = new Uint32Array(draco.HEAPU32.buffer, ptr, n).slice();
    draco._free(ptr);
    const attributes = (ids ? ids.map((id) => decoder.GetAttributeByUniqueId(mesh, id))
      : [decoder.GetAttribute(mesh, decoder.GetAttributeId(mesh, draco.POSITION))]).map((attr) => {
      const k = vertexCount * attr.num_components();
      ptr = draco._malloc(k * 4);
      decoder.GetAttributeDataArrayForAllPoints(mesh, attr, draco.DT_FLOAT32, k * 4, ptr);
      const values = new Float32Array(draco.HEAPF32.buffer, ptr, k).slice();
      draco._free(ptr);
      return values;
    });
    return { indices, attributes, vertexCount, faceCount };
  } finally {
    draco.destroy(mesh);
    draco.destroy(decoder);
  }
}
