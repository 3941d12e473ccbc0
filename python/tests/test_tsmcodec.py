"""tsmcodec against the library and the tsm tool (TSM_CLI: the built tool)."""
import os
import subprocess
import threading

import numpy as np
import pytest

import tsmcodec


def grid(n=12):
    xs, ys = np.meshgrid(np.arange(n + 1, dtype=np.float32), np.arange(n + 1, dtype=np.float32))
    zs = ((xs * ys) % 5).astype(np.float32) * 0.3
    positions = np.stack([xs.ravel(), ys.ravel(), zs.ravel()], axis=1)
    faces = []
    for y in range(n):
        for x in range(n):
            a = y * (n + 1) + x
            b, c = a + 1, a + n + 1
            faces += [(a, b, c + 1), (a, c + 1, c)]
    return positions, np.array(faces, dtype=np.int32)


def test_round_trip_triangles():
    positions, faces = grid()
    data = tsmcodec.encode(positions, faces)
    assert isinstance(data, bytes)
    mesh = tsmcodec.decode(data)
    assert mesh.vertex_count == len(positions)
    assert mesh.face_count == len(faces)
    assert mesh.positions.dtype == np.float32 and mesh.positions.shape == positions.shape
    assert mesh.faces.dtype == np.uint32 and mesh.faces.shape == faces.shape
    # Positions come back on the quantization grid, close to what went in,
    # as the same set of triangles over the same positions.
    got = {tuple(sorted(tuple(np.round(mesh.positions[v], 3)) for v in f)) for f in mesh.faces}
    want = {tuple(sorted(tuple(np.round(positions[v], 3)) for v in f)) for f in faces}
    assert got == want


def test_face_index_types_give_the_same_bytes():
    positions, faces = grid(6)
    ref = tsmcodec.encode(positions, faces)
    assert tsmcodec.encode(positions, faces.astype(np.uint32)) == ref
    assert tsmcodec.encode(positions.astype(np.float64), faces.astype(np.int64)) == ref
    assert tsmcodec.encode(tsmcodec.Mesh(positions, faces)) == ref


def test_vertex_attributes():
    positions, faces = grid(6)
    colors = np.random.default_rng(1).random((len(positions), 3), dtype=np.float32)
    data = tsmcodec.encode(positions, faces, {"color": colors, "weight": positions[:, 0] * 2})
    mesh = tsmcodec.decode(data)
    names = {a.name: a for a in mesh.attributes}
    assert names["color"].kind == "color" and names["color"].values.shape == (len(positions), 3)
    assert names["weight"].kind == "generic" and names["weight"].components == 1
    assert tsmcodec.info(data)["attributes"][0]["name"] in ("color", "weight")


def test_options_and_info():
    positions, faces = grid()
    small = tsmcodec.encode(positions, faces, quantization_bits=8, level=9)
    info = tsmcodec.info(small)
    assert info["quantization_bits"] == 8 and info["level"] == 9
    assert info["vertex_count"] == len(positions) and info["face_count"] == len(faces)
    assert info["file_bytes"] == len(small)


def test_errors_raise_with_the_library_message():
    with pytest.raises(tsmcodec.Error) as e:
        tsmcodec.decode(b"not a tsm file at all")
    assert str(e.value)
    positions, faces = grid(2)
    with pytest.raises(tsmcodec.Error):
        tsmcodec.encode(positions, faces, quantization_bits=99)
    with pytest.raises(ValueError):
        tsmcodec.encode(positions[:, :2], faces)
    with pytest.raises(ValueError):
        tsmcodec.encode(positions, -faces - 1)
    with pytest.raises(tsmcodec.Error):
        tsmcodec.read("/nonexistent/mesh.ply")


def test_read_write_files(tmp_path):
    positions, faces = grid(4)
    mesh = tsmcodec.decode(tsmcodec.encode(positions, faces))
    for ext in (".ply", ".obj", ".off", ".stl", ".glb"):
        path = str(tmp_path / ("m" + ext))
        tsmcodec.write(path, mesh)
        back = tsmcodec.read(path)
        assert back.face_count == len(faces), ext


def test_mixed_polygons():
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], dtype=np.float32)
    indices = np.array([0, 1, 2, 3, 1, 4, 2], dtype=np.uint32)
    offsets = np.array([0, 4, 7], dtype=np.uint32)
    mesh = tsmcodec.decode(tsmcodec.encode(tsmcodec.Mesh(positions, indices, offsets)))
    assert mesh.face_count == 2
    assert list(np.diff(mesh.face_offsets)) == [4, 3]
    with pytest.raises(ValueError):
        mesh.faces


def test_threads_code_in_parallel():
    positions, faces = grid(40)
    ref = tsmcodec.encode(positions, faces)
    out = [None] * 4

    def work(i):
        out[i] = tsmcodec.encode(positions, faces, threads=1)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(o == ref for o in out)


@pytest.mark.skipif(not os.environ.get("TSM_CLI"), reason="TSM_CLI (the tsm tool) not given")
@pytest.mark.parametrize("args,kwargs", [([], {}), (["-q", "10", "-l", "2"], {"quantization_bits": 10, "level": 2})])
def test_bytes_equal_the_tools(tmp_path, args, kwargs):
    positions, faces = grid(20)
    ply = str(tmp_path / "grid.ply")
    tsmcodec.write(ply, tsmcodec.Mesh(positions, faces))
    out = str(tmp_path / "grid.tsm")
    subprocess.run([os.environ["TSM_CLI"], "encode", ply, "-o", out] + args, check=True, capture_output=True)
    with open(out, "rb") as f:
        tool = f.read()
    assert tsmcodec.encode(tsmcodec.read(ply), **kwargs) == tool


@pytest.mark.skipif(not os.environ.get("TSM_CLI"), reason="TSM_CLI (the tsm tool) not given")
def test_reads_a_compressed_gltf(tmp_path):
    positions, faces = grid(10)
    plain = str(tmp_path / "grid.glb")
    tsmcodec.write(plain, tsmcodec.Mesh(positions, faces))
    packed = str(tmp_path / "packed.glb")
    subprocess.run([os.environ["TSM_CLI"], "encode", plain, "-o", packed], check=True, capture_output=True)
    with open(packed, "rb") as f:
        assert b"TSM_mesh_compression" in f.read()
    back = tsmcodec.read(packed)
    assert back.face_count == len(faces)
    assert len(back.positions) == len(positions)


def test_stream_decoder_grows_segment_by_segment():
    positions, faces = grid(30)
    data = tsmcodec.encode(positions, faces, segment_faces=400)
    whole = tsmcodec.decode(data)
    stream = tsmcodec.StreamDecoder(threads=1)
    assert stream.segment_count == 0 and not stream.done
    seen = []
    for i in range(0, len(data), 97):
        stream.feed(data[i:i + 97])
        seen.append((stream.segments_done, stream.mesh.face_count))
    stream.finish()
    assert stream.done and stream.segment_count > 1
    assert stream.segments_done == stream.segment_count
    # The mesh grows in steps, never shrinks, and some step is a proper part.
    assert seen == sorted(seen)
    assert any(0 < f < len(faces) for _, f in seen)
    mesh = stream.take_mesh()
    assert np.array_equal(mesh.positions, whole.positions)
    assert np.array_equal(mesh.faces, whole.faces)


def test_stream_decoder_errors():
    positions, faces = grid(8)
    data = tsmcodec.encode(positions, faces)
    stream = tsmcodec.StreamDecoder()
    stream.feed(data[: len(data) // 2])
    with pytest.raises(tsmcodec.Error) as e:
        stream.finish()
    assert str(e.value)
    bad = tsmcodec.StreamDecoder()
    with pytest.raises(tsmcodec.Error):
        bad.feed(b"this is not a tsm stream, not at all")
    with pytest.raises(tsmcodec.Error):  # after an error every call raises it again
        bad.feed(data)


def corpus_file(name):
    """A file of ../shared/corpus (TSM_CORPUS): skipped when absent, a failure in CI."""
    path = os.path.join(os.environ.get("TSM_CORPUS", ""), name)
    if not os.path.isfile(path):
        if os.environ.get("CI", "") not in ("", "0", "false"):
            pytest.fail("corpus file %s is missing; CI is set, so that is a failure" % path)
        pytest.skip("corpus file %s is missing (clone the project beside ../shared or set TSM_CORPUS)" % path)
    return path


@pytest.mark.skipif(not os.environ.get("TSM_CLI"), reason="TSM_CLI (the tsm tool) not given")
def test_corpus_bunny_bytes_equal_the_tools(tmp_path):
    ply = corpus_file("bun_zipper.ply")
    out = str(tmp_path / "bunny.tsm")
    subprocess.run([os.environ["TSM_CLI"], "encode", ply, "-o", out], check=True, capture_output=True)
    with open(out, "rb") as f:
        tool = f.read()
    mesh = tsmcodec.read(ply)
    data = tsmcodec.encode(mesh)
    assert data == tool
    back = tsmcodec.decode(data)
    assert (back.vertex_count, back.face_count) == (35947, 69451)
    # On the grid: every decoded position is within half a grid step of the
    # input's bounding box (14 bits by default over the largest extent).
    lo, hi = mesh.positions.min(axis=0), mesh.positions.max(axis=0)
    step = float((hi - lo).max()) / ((1 << tsmcodec.info(data)["quantization_bits"]) - 1)
    assert (back.positions >= lo - step).all() and (back.positions <= hi + step).all()


def sphere(rings=24, segments=48):
    positions = [(0.0, 0.0, 1.0)]
    for r in range(1, rings):
        th = np.pi * r / rings
        for s in range(segments):
            ph = 2 * np.pi * s / segments
            positions.append((np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)))
    positions.append((0.0, 0.0, -1.0))
    south = len(positions) - 1

    def vid(r, s):
        return 1 + (r - 1) * segments + s % segments

    faces = [(0, vid(1, s), vid(1, s + 1)) for s in range(segments)]
    for r in range(1, rings - 1):
        for s in range(segments):
            faces += [(vid(r, s), vid(r + 1, s), vid(r + 1, s + 1)), (vid(r, s), vid(r + 1, s + 1), vid(r, s + 1))]
    faces += [(south, vid(rings - 1, s + 1), vid(rings - 1, s)) for s in range(segments)]
    return np.array(positions, dtype=np.float32), np.array(faces, dtype=np.int32)


def test_simplify_within_the_bound_and_distance():
    positions, faces = sphere()
    mesh = tsmcodec.Mesh(positions, faces)
    small = tsmcodec.simplify(mesh, max_error_percent=1.0)
    assert 0 < small.face_count < len(faces) // 2
    d = tsmcodec.distance(mesh, small)
    assert d["diagonal"] == pytest.approx(2 * np.sqrt(3), rel=1e-3)
    assert d["hausdorff"] <= d["hausdorff_bound"]
    assert d["hausdorff_bound"] <= 0.01 * d["diagonal"] * 1.0001
    assert d["a_to_b"]["samples"] > 0 and d["b_to_a"]["mean"] <= d["b_to_a"]["max"]
    assert tsmcodec.distance(mesh, mesh)["hausdorff"] < 1e-9
    fewer = tsmcodec.simplify(mesh, ratio=0.25)
    assert fewer.face_count <= round(0.25 * len(faces)) + 2
    with pytest.raises(ValueError):
        tsmcodec.simplify(mesh)
    with pytest.raises(ValueError):
        tsmcodec.simplify(mesh, max_error=0.1, max_error_percent=1.0)


def test_keep_order_and_lossless_round_trip():
    rng = np.random.default_rng(41)
    positions = rng.standard_normal((60, 3)).astype(np.float32)
    positions[3, 1] = np.float32(-0.0)
    positions[7, 2] = np.float32(1e-40)  # a denormal
    faces = rng.permutation(np.array([[i, (i + 1) % 60, (i + 7) % 60] for i in range(60)], dtype=np.uint32))
    data = tsmcodec.encode(positions, faces, keep_order=True, lossless=True)
    mesh = tsmcodec.decode(data)
    assert np.asarray(mesh.positions).tobytes() == positions.tobytes()
    assert np.array_equal(np.asarray(mesh.faces), faces)
    positions[5, 0] = np.nan
    with pytest.raises(Exception, match="allow-nonfinite"):
        tsmcodec.encode(positions, faces, lossless=True)
    back = tsmcodec.decode(tsmcodec.encode(positions, faces, keep_order=True, lossless=True, allow_nonfinite=True))
    assert np.asarray(back.positions).tobytes() == positions.tobytes()


def test_encode_mapped_reindexes_the_input():
    positions, faces = grid(8)
    rng = np.random.default_rng(7)
    order = rng.permutation(len(positions))
    shuffled = np.empty_like(positions)
    shuffled[order] = positions  # input vertex order[i] holds grid vertex i
    mesh = tsmcodec.Mesh(shuffled, order[faces].astype(np.uint32))
    data, mapping = tsmcodec.encode_mapped(mesh, quantization_bits=16)
    assert data == tsmcodec.encode(mesh, quantization_bits=16)  # asking for the mapping changes no byte
    back = tsmcodec.decode(data)
    vf = np.asarray(mapping["vertex_from"])
    assert sorted(vf) == list(range(len(positions)))
    # Decoded vertex v is input vertex vf[v]: positions agree within the 16-bit grid.
    assert np.abs(np.asarray(back.positions) - shuffled[vf]).max() < 12 / (1 << 16)
    ff, fc = np.asarray(mapping["face_from"]), np.asarray(mapping["first_corner"])
    in_faces = np.asarray(mesh.faces)
    for f in range(back.face_count):
        want = np.roll(in_faces[ff[f]], -int(fc[f]))
        assert list(vf[np.asarray(back.faces)[f]]) == list(want)
