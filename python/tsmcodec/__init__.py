"""tsmcodec: tsm triangle-mesh compression for Python (numpy arrays in and out).

    import numpy as np, tsmcodec
    data = tsmcodec.encode(positions, faces)          # bytes, as `tsm encode` writes
    mesh = tsmcodec.decode(data)                      # mesh.positions (N,3) float32, mesh.faces (M,3) uint32
    mesh = tsmcodec.read("bunny.ply"); tsmcodec.write("bunny.obj", mesh)
    tsmcodec.info(data)["face_count"]
    stream = tsmcodec.StreamDecoder()                 # decoding as the bytes arrive
    for chunk in chunks: stream.feed(chunk)           # stream.mesh grows segment by segment
    stream.finish(); mesh = stream.take_mesh()
    small = tsmcodec.simplify(mesh, max_error_percent=0.5)   # guaranteed within 0.5% of the diagonal
    tsmcodec.distance(mesh, small)["hausdorff_bound"]      # Metro-style distances, as `tsm compare`

Errors raise tsmcodec.Error with the library's message.
"""
from ._tsmcodec import (Attribute, Error, Mesh, StreamDecoder, __version__, decode, distance, encode, encode_mapped,
                        info, read, simplify, write)

__all__ = ["Attribute", "Error", "Mesh", "StreamDecoder", "__version__", "decode", "distance", "encode",
           "encode_mapped", "info", "read", "simplify", "write"]
