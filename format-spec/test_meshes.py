#!/usr/bin/env python3
"""Test meshes for reference_decoder.py (see check_decoder.sh). Writes into DIR:

  triangle.obj  the worked example of FORMAT.md §11
  mixed.obj     a latitude-longitude sphere (its vertex tree suits the ancestor
                predictor), a torus of quads with two holes (a handle, polygons),
                a fin of three triangles on one edge (a non-manifold edge), a
                hexagon, degenerate faces (side faces: four on edges, one verbatim),
                three isolated vertices
  mixed_small.obj  the same with a 6 x 10 sphere (at -q 10 -l 9: the gate
                predictor with its weights left out, §8.5.1 bit 7)
  irregular.obj  a 30 x 30 grid of jittered points on a wavy sheet, quads
                split along random diagonals, then 2,000 random edge flips:
                irregular valences, so at level 0 its run values take tables
                (mode 1, §8.3.1), which the forged cases then damage
  loose.obj     irregular(20) and 150 vertices no face uses, scattered just
                off the sheet: in a progressive file they fill the loose
                section (§4.8), each coded from its nearest level vertex
  fan.obj       a fan of 300 triangles around a wavy rim: the rim is a path of
                the vertex tree whose coordinates follow a linear recurrence,
                so at -l 9 the ancestor predictor (K = 3 or 4) wins
  lattice.obj   a marching-tetrahedra isosurface on a 20^3 voxel grid: every
                vertex lies on a grid edge, so many coordinates share voxel planes
                (the geometry lattice), plus an isolated vertex
  box.obj       a box of 6 quads, each with its own 4 corners (24 vertices on 2
                planes per axis, the far ones at qmax: coded from the top,
                §8.5.2)
  unused_vt.obj  an irregular grid of 338 triangles on one texture coordinate,
                and 100,000 texture coordinates no corner uses (table-coded
                at level 0, §8.12.1, they test the decoder's bound on unused
                values)

  attributes.obj  mixed(12, 20) with vertex colours, corner `vt u v w` (a
                3-component generic 'texcoord3') and corner `vn` with seams,
                shared and unused values
  attributes.ply  mixed(12, 20) with vertex, face and corner attributes of
                every kind and type
  flat.ply      a flat-shaded sphere and box (a vertex per face corner carrying
                the face's normal, slivers, a vertex on no face): welded (§8.13)
  cad.ply       a cylinder with a smooth side and flat caps, slivers flat on the
                grid and an overlapping copy: welded (§8.13), normals predicted
                from the geometry (§8.12, the stray)
  cad.obj       the same with shared position and normal lists: points out
                with point ranks (§8.13)
  uv_vertex.ply   curved surfaces with per-vertex texture coordinates (s t) in
                smooth charts, one mirrored: predictor 2 in the vertex domain
  uv_corner.obj   a UV sphere, a torus and a box with corner texture
                coordinates (vt u v) in charts with seams, some mirrored:
                predictor 2 in the corner domain (segmented: values shared
                across segment borders)

Usage: test_meshes.py DIR
       test_meshes.py --add-metadata SRC.tsm DST.tsm KEY=VALUE ...
       test_meshes.py --add-metadata SRC.tsm DST.tsm --raw HEX   (a malformed payload)
         (with --zstd: the section zstd-coded, by the zstd command)
       test_meshes.py --replace-in-mesh SRC.tsm DST.tsm OLD_HEX NEW_HEX   (a forged mesh section)
       test_meshes.py --forge-topology SRC.tsm DST.tsm mode=N | cut=K
         (the mesh section's topology stream with its first byte, the run
         coding mode of §8.3.1, set to N, or cut to its first K bytes)
       test_meshes.py --set-version SRC.tsm DST.tsm N
         (the preamble's version field set to N, the header checksum
         rewritten to match)
"""
import math
import os
import struct
import sys


def write_obj(path, V, F):
    with open(path, 'w') as f:
        for p in V:
            f.write('v %.6f %.6f %.6f\n' % p)
        for fa in F:
            f.write('f ' + ' '.join(str(i + 1) for i in fa) + '\n')


def fan(n=300):
    V = [(0.0, 0.0, 0.3)]
    for i in range(n):
        a = 2 * math.pi * i / n
        V.append((math.cos(a), math.sin(a), 0.2 * math.sin(3 * a)))
    return V, [[0, 1 + i, 1 + (i + 1) % n] for i in range(n)]


def unused_vt(path, n=14, unused=100000):
    """An n x n grid, quads split along random diagonals (irregular runs: at
    level 0 the run values take tables), every corner on texture coordinate 1,
    then `unused` random ones no corner uses: table-coded (§8.12.1) they fill the bit stream while the range-coded stream stays
    short, which the decoder's bound on unused values has to allow."""
    import random
    rng = random.Random(7)
    with open(path, 'w') as f:
        for y in range(n):
            for x in range(n):
                f.write('v %d %d %.3f\n' % (x, y, rng.randrange(100) / 1000))
        f.write('vt 0.5 0.5\n')
        for _ in range(unused):
            f.write('vt %.4f %.4f\n' % (rng.randrange(4096) / 4095, rng.randrange(4096) / 4095))
        for y in range(n - 1):
            for x in range(n - 1):
                a, b, c, d = y * n + x + 1, y * n + x + 2, (y + 1) * n + x + 1, (y + 1) * n + x + 2
                tris = [(a, b, d), (a, d, c)] if rng.randrange(2) else [(a, b, c), (b, d, c)]
                for t in tris:
                    f.write('f %d/1 %d/1 %d/1\n' % t)


def irregular(n=30, flips=2000, seed=5):
    """An n x n grid of jittered points on a wavy sheet, quads split along
    random diagonals, then random edge flips (each keeps the orientation and
    makes no edge twice): valences from 3 to about 12, irregular enough that
    at level 0 the run values take tables (§8.3.1)."""
    import random
    rng = random.Random(seed)
    V = [(x + rng.uniform(-.2, .2), y + rng.uniform(-.2, .2), 3 * math.sin(x / 7.0) * math.cos(y / 9.0))
         for y in range(n) for x in range(n)]
    F = []
    for y in range(n - 1):
        for x in range(n - 1):
            a, b, c, d = y * n + x, y * n + x + 1, (y + 1) * n + x, (y + 1) * n + x + 1
            F += [[a, b, d], [a, d, c]] if rng.randrange(2) else [[a, b, c], [b, d, c]]
    he = {}                                                # half-edge -> face
    for i, f in enumerate(F):
        for k in range(3):
            he[f[k], f[(k + 1) % 3]] = i
    keys = list(he)
    for _ in range(flips):
        a, b = keys[rng.randrange(len(keys))]
        if (a, b) not in he or (b, a) not in he:
            continue
        i, j = he[a, b], he[b, a]                          # (a, b, c) and (b, a, d)
        c = [v for v in F[i] if v not in (a, b)][0]
        d = [v for v in F[j] if v not in (a, b)][0]
        if c == d or (c, d) in he or (d, c) in he:
            continue
        for f in (F[i], F[j]):
            for k in range(3):
                del he[f[k], f[(k + 1) % 3]]
        F[i], F[j] = [a, d, c], [b, c, d]                  # the quad a d b c, cut along c-d
        for idx in (i, j):
            f = F[idx]
            for k in range(3):
                he[f[k], f[(k + 1) % 3]] = idx
        keys += [(c, d), (d, c)]
    return V, F


def loose(n=20, extra=150, seed=9):
    """irregular(n) and `extra` vertices no face uses, each just off the
    sheet (within half a grid cell of it)."""
    import random
    rng = random.Random(seed)
    V, F = irregular(n, flips=600, seed=seed)
    for _ in range(extra):
        x, y = rng.uniform(0, n - 1), rng.uniform(0, n - 1)
        V.append((x, y, 3 * math.sin(x / 7.0) * math.cos(y / 9.0) + rng.uniform(-.5, .5)))
    return V, F


def box():
    V, F = [], []
    for axis in range(3):
        for side in (0, 1):
            face = []
            for u, w in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0, 0, 0]
                p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, u, w
                face.append(len(V))
                V.append(tuple(p))
            F.append(face if side else face[::-1])
    return V, F


def sphere_rings(v, n_, m_):
    """The rings of a latitude-longitude unit sphere, made with v(x, y, z):
    ring[i, j] for latitudes 1 .. n_ - 1 and longitudes 0 .. m_ - 1."""
    ring = {}
    for i in range(1, n_):
        th = math.pi * i / n_
        for j in range(m_):
            ph = 2 * math.pi * j / m_
            ring[i, j] = v(math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
    return ring


def double_sided(V, F):
    """Every face also given reversed on the same vertices (as exporters
    write thin geometry): one stitch per vertex, coded by candidates
    (§8.3.2)."""
    return V, [list(f) for f in F] + [list(f[::-1]) for f in F]


def mixed(n_=30, m_=60):
    V, F = [], []

    def v(x, y, z):
        V.append((x, y, z))
        return len(V) - 1
    top = v(0, 0, 1)
    ring = sphere_rings(v, n_, m_)
    bot = v(0, 0, -1)
    for j in range(m_):
        F.append([top, ring[1, j], ring[1, (j + 1) % m_]])
        F.append([ring[n_ - 1, j], bot, ring[n_ - 1, (j + 1) % m_]])
    for i in range(1, n_ - 1):
        for j in range(m_):
            F.append([ring[i, j], ring[i + 1, j], ring[i + 1, (j + 1) % m_]])
            F.append([ring[i, j], ring[i + 1, (j + 1) % m_], ring[i, (j + 1) % m_]])
    S = 0.15
    N, M, R, r = 10, 6, 3.0 * S, 1.0 * S
    idx = {}
    for i in range(N):
        for j in range(M):
            a, b = 2 * math.pi * i / N, 2 * math.pi * j / M
            idx[i, j] = v(2.5 + (R + r * math.cos(b)) * math.cos(a), (R + r * math.cos(b)) * math.sin(a),
                          r * math.sin(b))
    for i in range(N):
        for j in range(M):
            if (i, j) in ((3, 4), (7, 1)):
                continue                                   # two holes
            q = [idx[i, j], idx[(i + 1) % N, j], idx[(i + 1) % N, (j + 1) % M], idx[i, (j + 1) % M]]
            if (i + j) % 5 == 0:
                F.append(q[:3])
                F.append([q[0], q[2], q[3]])
            else:
                F.append(q)                                # quads: polygons
    a = v(2.5, 0, -1.2)
    b = v(2.5, 0, -1.0)
    for k in range(3):                                     # three triangles on edge a-b
        ang = 2 * math.pi * k / 3
        F.append([a, b, v(2.5 + 0.2 * math.cos(ang), 0.2 * math.sin(ang), -1.1)])
    hc = [v(-2.5 + 0.4 * math.cos(2 * math.pi * k / 6), 0.4 * math.sin(2 * math.pi * k / 6), 0.05 * k)
          for k in range(6)]
    F.append(hc)                                           # a hexagon
    F.append([hc[0], hc[5], v(-1.9, -0.3, 0.2)])
    F.append([hc[1], hc[2], hc[2]])                        # degenerate faces on edges (side faces)
    F.append([hc[2], hc[1], hc[2]])
    F.append([hc[1], hc[1], hc[2]])
    F.append([hc[3], hc[0], hc[0]])                        # on a polygon diagonal
    F.append([hc[1], hc[1], hc[4]])                        # on no edge: verbatim
    v(2.6, 0.05, 0.3)                                      # isolated vertices
    v(-3, -3, 2)
    v(-2.45, 0.1, 0.1)
    return V, F


def lattice():
    G = 20

    def f(x, y, z):
        a = 1 / ((x - 8) ** 2 + (y - 10) ** 2 + (z - 10) ** 2 + 1e-9) ** 0.5 * 5.0
        b = 1 / ((x - 13) ** 2 + (y - 10) ** 2 + (z - 9) ** 2 + 1e-9) ** 0.5 * 4.0
        c = (math.hypot(x - 10, y - 10) - 6) ** 2 + (z - 10) ** 2
        return a + b + 2.0 / (c + 0.5) - 1.0

    def grad(x, y, z, e=1e-4):
        return (f(x + e, y, z) - f(x - e, y, z), f(x, y + e, z) - f(x, y - e, z), f(x, y, z + e) - f(x, y, z - e))
    val = {}
    for i in range(G + 1):
        for j in range(G + 1):
            for k in range(G + 1):
                val[i, j, k] = f(i + 0.001, j + 0.002, k + 0.003)
    V, F, vid = [], [], {}

    def edge_vertex(p, q):
        key = (min(p, q), max(p, q))
        if key not in vid:
            a, b = val[p], val[q]
            t = a / (a - b)
            V.append(tuple(p[i] + t * (q[i] - p[i]) for i in range(3)))
            vid[key] = len(V) - 1
        return vid[key]

    def tri_out(a, b, c):
        pa, pb, pc = V[a], V[b], V[c]
        n = [(pb[1] - pa[1]) * (pc[2] - pa[2]) - (pb[2] - pa[2]) * (pc[1] - pa[1]),
             (pb[2] - pa[2]) * (pc[0] - pa[0]) - (pb[0] - pa[0]) * (pc[2] - pa[2]),
             (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0])]
        g = grad(*[(pa[i] + pb[i] + pc[i]) / 3 for i in range(3)])
        F.append([a, c, b] if n[0] * g[0] + n[1] * g[1] + n[2] * g[2] > 0 else [a, b, c])
    perms = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    for i in range(G):
        for j in range(G):
            for k in range(G):
                for pm in perms:                           # Kuhn: 6 tetrahedra per cube
                    p = [i, j, k]
                    pts = [tuple(p)]
                    for ax in pm:
                        p = list(p)
                        p[ax] += 1
                        pts.append(tuple(p))
                    I = [x for x in pts if val[x] > 0]
                    O = [x for x in pts if val[x] <= 0]
                    if len(I) in (0, 4):
                        continue
                    if len(I) in (1, 3):
                        lone, rest = (I[0], O) if len(I) == 1 else (O[0], I)
                        tri_out(*[edge_vertex(lone, x) for x in rest])
                    else:
                        e0, e1 = edge_vertex(I[0], O[0]), edge_vertex(I[0], O[1])
                        e2, e3 = edge_vertex(I[1], O[1]), edge_vertex(I[1], O[0])
                        tri_out(e0, e1, e2)
                        tri_out(e0, e2, e3)
    V.append((10.5, 10.25, 10.0))
    return V, F



def unit(x, y, z):
    n = math.sqrt(x * x + y * y + z * z)
    return (x / n, y / n, z / n) if n > 0 else (0.0, 0.0, 1.0)


def face_normal(V, fa):
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = V[fa[0]], V[fa[1]], V[fa[-1]]
    u, w = (bx - ax, by - ay, bz - az), (cx - ax, cy - ay, cz - az)
    return unit(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])


def attr_obj(path, V, F):
    """mixed() with v colours (a vertex colour), `vt u v w` with w != 0 (a
    3-component generic corner attribute 'texcoord3', grid-quantized) and `vn`
    (a corner normal, octahedral): values shared by the corners of a vertex,
    seams (several values at a vertex, more than 4 at the poles), values shared
    by far-apart corners (the hexagon, the torus quads' face normals) and
    values no corner uses."""
    VT, VN = [], []

    def vt(u, v, w=0.5):
        VT.append((u, v, w))
        return len(VT)

    def vn(x, y, z):
        VN.append(unit(x, y, z))
        return len(VN)
    vt(0.9, 0.9)                                           # unused
    vn(1, 1, 1)                                            # unused
    base_t = [vt(0.5 + 0.3 * x, 0.5 + 0.3 * y, 0.25 + 0.1 * z) for x, y, z in V]
    base_n = [vn(*p) for p in V]
    seam_t = {}
    hex_t = vt(0.1, 0.2, 0.3)
    pole_t = [vt(0.05 * k, 1.0, 0.75) for k in range(7)]
    vt(0.7, 0.1, 0.9)                                      # unused
    vn(0, 0, -1)                                           # unused
    face_n = {}
    lines = []
    for i, (x, y, z) in enumerate(V):
        lines.append('v %.6f %.6f %.6f %.4f %.4f %.4f\n' % (x, y, z, (x + 3) / 6, (y + 3) / 6, (z + 2) / 4))
    for fi, fa in enumerate(F):
        corners = []
        for k, c in enumerate(fa):
            if len(fa) == 6:
                t = hex_t                                  # one value, six vertices
            elif c == 0:
                t = pole_t[fi % 7]                         # 7 values at the north pole
            elif fi % 9 == 0:
                if c not in seam_t:
                    x, y, z = V[c]
                    seam_t[c] = vt(0.4 - 0.2 * x, 0.6 + 0.2 * y, 0.5)
                t = seam_t[c]                              # a seam: a second value at c
            else:
                t = base_t[c]
            if len(fa) == 4:
                if fi not in face_n:
                    face_n[fi] = vn(*face_normal(V, fa))
                n = face_n[fi]                             # flat quads: a crease at every edge
            else:
                n = base_n[c]
            corners.append('%d/%d/%d' % (c + 1, t, n))
        lines.append('f ' + ' '.join(corners) + '\n')
    with open(path, 'w') as f:
        f.write('# test mesh for reference_decoder.py: corner and vertex attributes\n')
        f.writelines(lines[:len(V)])
        f.writelines('vt %.6f %.6f %.6f\n' % t for t in VT)
        f.writelines('vn %.6f %.6f %.6f\n' % n for n in VN)
        f.writelines(lines[len(V):])


def attr_ply(path, V, F):
    """mixed() as ASCII PLY with attributes of every domain and type: vertex
    normal (nx ny nz), colour (uchar RGBA), generic float, a 3-component
    generic (w_0 w_1 w_2), ushort and int generics; face colour (uchar RGB),
    face normal (nx ny nz), float and int generics; per-corner lists: a normal, a float, a ushort pair."""
    with open(path, 'w') as f:
        f.write('ply\nformat ascii 1.0\ncomment test mesh for reference_decoder.py\n')
        f.write('element vertex %d\n' % len(V))
        f.write(''.join('property float %s\n' % n for n in ('x', 'y', 'z', 'nx', 'ny', 'nz')))
        f.write(''.join('property uchar %s\n' % n for n in ('red', 'green', 'blue', 'alpha')))
        f.write('property float temperature\nproperty float w_0\nproperty float w_1\nproperty float w_2\n')
        f.write('property ushort label\nproperty int id32\n')
        f.write('element face %d\nproperty list uchar int vertex_indices\n' % len(F))
        f.write('property float quality\nproperty int group\n')
        f.write(''.join('property uchar %s\n' % n for n in ('red', 'green', 'blue')))
        f.write(''.join('property float %s\n' % n for n in ('nx', 'ny', 'nz')))
        f.write('property list uchar float normal\nproperty list uchar float shade\n')
        f.write('property list uchar ushort pair\nend_header\n')
        for i, (x, y, z) in enumerate(V):
            nx, ny, nz = unit(x, y, z)
            f.write('%.6f %.6f %.6f %.6f %.6f %.6f %d %d %d %d %.5f %.4f %.4f %.4f %d %d\n' % (
                x, y, z, nx, ny, nz, int(127 + 120 * nx), int(127 + 120 * ny), int(127 + 120 * nz), 255 - i % 3,
                20 + 5 * z + 0.01 * i, x * y, y * z, z * x, i // 7, (i * 7919) % 2001 - 1000))
        for fi, fa in enumerate(F):
            fn = face_normal(V, fa) if len(set(fa)) >= 3 else (0.0, 0.0, 1.0)
            rec = ['%d' % len(fa)] + ['%d' % c for c in fa]
            rec += ['%.3f' % (0.5 + 0.5 * fn[2]), '%d' % (fi // 10 - 5),
                    '%d %d %d' % (fi % 256, (3 * fi) % 256, 200), '%.6f %.6f %.6f' % fn]
            rec.append('%d ' % (3 * len(fa)) + ' '.join('%.6f %.6f %.6f' % (fn if fi % 3 else unit(*V[c]))
                                                         for c in fa))
            rec.append('%d ' % len(fa) + ' '.join('%.4f' % (0.25 * k + 0.01 * fi) for k in range(len(fa))))
            rec.append('%d ' % (2 * len(fa)) + ' '.join('%d %d' % (c % 100, fi % 50) for c in fa))
            f.write(' '.join(rec) + '\n')



def uv_surfaces():
    """Curved surfaces with smooth texture charts (for the texture placement
    predictor 2 of §8.12): a wavy open cylinder (triangles and some quads), a
    mirrored copy (the other texture orientation, sigma -1), a sphere cap and an
    isolated vertex. Returns V, F, UV (per vertex), chart (per vertex)."""
    V, F, UV = [], [], []

    def v(p, uv):
        V.append(p)
        UV.append(uv)
        return len(V) - 1
    for mirror in (0, 1):
        N, M = 36, 14
        g = {}
        for i in range(N + 1):
            th = 1.5 * math.pi * i / N
            for j in range(M + 1):
                z = 2.0 * j / M
                r = 1 + 0.12 * math.sin(3 * th) * math.cos(1.7 * z)
                s = 0.05 + 0.9 * i / N + 0.02 * math.sin(2.3 * z)
                t = 0.05 + 0.45 * j / M + 0.01 * math.cos(2 * th)
                if mirror:
                    s = 1 - s
                    t += 0.5
                g[i, j] = v((r * math.cos(th) + 3 * mirror, r * math.sin(th), z), (s, t))
        for i in range(N):
            for j in range(M):
                a, b, c, d = g[i, j], g[i + 1, j], g[i + 1, j + 1], g[i, j + 1]
                if (i + 2 * j) % 7 == 0:
                    F.append([a, b, c, d])                 # a quad: both sides of a polygon
                elif (i + j) % 2:
                    F += [[a, b, c], [a, c, d]]
                else:
                    F += [[a, b, d], [b, c, d]]
    n_, m_ = 8, 16                                         # a sphere cap
    top = v((0, 0, 4), (0.5, 0.5))
    ring = {}
    for i in range(1, n_ + 1):
        th = 0.6 * math.pi * i / n_
        for j in range(m_):
            ph = 2 * math.pi * j / m_
            rr = 0.45 * i / n_
            ring[i, j] = v((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), 3 + math.cos(th)),
                           (0.5 + rr * math.cos(ph), 0.5 + rr * math.sin(ph)))
    for j in range(m_):
        F.append([top, ring[1, j], ring[1, (j + 1) % m_]])
    for i in range(1, n_):
        for j in range(m_):
            F += [[ring[i, j], ring[i + 1, j], ring[i + 1, (j + 1) % m_]],
                  [ring[i, j], ring[i + 1, (j + 1) % m_], ring[i, (j + 1) % m_]]]
    v((5, 5, 5), (0.3, 0.7))                               # an isolated vertex
    return V, F, UV


def write_normal_ply(path, V, N, F):
    """An ascii PLY of positions V, vertex normals N and faces F."""
    with open(path, 'w') as f:
        f.write('ply\nformat ascii 1.0\nelement vertex %d\n' % len(V))
        f.write('property float x\nproperty float y\nproperty float z\n')
        f.write('property float nx\nproperty float ny\nproperty float nz\n')
        f.write('element face %d\nproperty list uchar int vertex_indices\nend_header\n' % len(F))
        for (x, y, z), (a, b, c) in zip(V, N):
            f.write('%.6f %.6f %.6f %.6f %.6f %.6f\n' % (x, y, z, a, b, c))
        for fa in F:
            f.write('%d %s\n' % (len(fa), ' '.join(map(str, fa))))


def flat_ply(path):
    """A sphere and a box, flat-shaded as glTF has it: every face has vertices
    of its own carrying its normal (nx ny nz), plus a few slivers (r, r, o) on
    split vertices and a vertex on no face: welded (§8.13)."""
    V0, F0 = [(0.0, 0.0, -1.0), (0.0, 0.0, 1.0)], []
    n_, m_ = 8, 12
    for i in range(1, n_):
        th = math.pi * i / n_
        for j in range(m_):
            ph = 2 * math.pi * j / m_
            V0.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), -math.cos(th)))
    r = lambda i, j: 2 + (i - 1) * m_ + j % m_
    for j in range(m_):
        F0.append([0, r(1, j + 1), r(1, j)])
        F0.append([1, r(n_ - 1, j), r(n_ - 1, j + 1)])
        for i in range(1, n_ - 1):
            F0.append([r(i, j), r(i, j + 1), r(i + 1, j + 1)])
            F0.append([r(i, j), r(i + 1, j + 1), r(i + 1, j)])
    B, FB = box()
    F0 = F0 + [[x + len(V0) for x in fa] for fa in FB]
    V0 = V0 + [(x + 2.5, y, z) for x, y, z in B]
    V, N, F = [], [], []
    for fa in F0:
        nx, ny, nz = face_normal(V0, fa)
        F.append(list(range(len(V), len(V) + len(fa))))
        for x in fa:
            V.append(V0[x])
            N.append((nx, ny, nz))
    for k in range(0, 30, 7):
        fa = F[k]
        F.append([fa[0], fa[0], fa[1]])
    V.append(V[0])
    N.append((0.0, 0.0, 1.0))
    write_normal_ply(path, V, N, F)


def cad_part():
    """A CAD-like part as glTF has it: a cylinder with a smooth side (radial
    normals) and flat caps (their own vertices at the rims), slivers flat on
    the grid (a rim edge and its midpoint), and a second copy of the whole
    part 10^-5 away (overlapping parts, on the same grid points). Returns
    (positions, normals, faces), a vertex per (position, normal)."""
    S, R = 32, 4
    V, N, F = [], [], []

    def vertex(p, n):
        V.append(p)
        N.append(n)
        return len(V) - 1
    for copy in range(2):
        side = [[vertex((math.cos(2 * math.pi * j / S), math.sin(2 * math.pi * j / S), 2.0 * r / R),
                        (math.cos(2 * math.pi * j / S), math.sin(2 * math.pi * j / S), 0.0))
                 for j in range(S)] for r in range(R + 1)]
        for r in range(R):
            for j in range(S):
                k = (j + 1) % S
                F.append([side[r][j], side[r][k], side[r + 1][k]])
                F.append([side[r][j], side[r + 1][k], side[r + 1][j]])
        for top in range(2):
            z, nz = (2.0, 1.0) if top else (0.0, -1.0)
            rows = [[vertex(((1 - r / 3) * math.cos(2 * math.pi * j / S), (1 - r / 3) * math.sin(2 * math.pi * j / S), z),
                            (0.0, 0.0, nz)) for j in range(S)] for r in range(3)]
            c = vertex((0.0, 0.0, z), (0.0, 0.0, nz))
            for r in range(2):
                for j in range(S):
                    k = (j + 1) % S
                    a, b, d, e = rows[r][j], rows[r][k], rows[r + 1][k], rows[r + 1][j]
                    F.extend([[a, b, d], [a, d, e]] if top else [[a, d, b], [a, e, d]])
            for j in range(S):
                a, b = rows[2][j], rows[2][(j + 1) % S]
                F.append([a, b, c] if top else [a, c, b])
        if copy == 0:
            for j in range(0, S, 4):
                x, y = math.cos(2 * math.pi * j / S), math.sin(2 * math.pi * j / S)
                F.append([side[0][j], side[R][j], vertex((x, y, 1.0), (x, y, 0.0))])
            first = len(V)
    V = V[:first] + [(x + 1e-5, y, z) for x, y, z in V[first:]]
    return V, N, F


def cad_ply(path):
    """cad_part() as PLY: welded (§8.13), its candidates told apart by their
    normals and by the edges that link them, its normals predicted from the
    geometry with every stray class (§8.12)."""
    V, N, F = cad_part()
    write_normal_ply(path, V, N, F)


def cad_obj(path):
    """cad_part() as an OBJ with shared lists (each distinct position and
    normal once, `f v//vn`): points out (§8.13), the copies' positions ranked
    at their grid points."""
    V, N, F = cad_part()
    vid, nid = {}, {}
    with open(path, 'w') as f:
        for p in V:
            if p not in vid:
                vid[p] = len(vid) + 1
                f.write('v %.6f %.6f %.6f\n' % p)
        for n in N:
            if n not in nid:
                nid[n] = len(nid) + 1
                f.write('vn %.6f %.6f %.6f\n' % n)
        for fa in F:
            f.write('f %s\n' % ' '.join('%d//%d' % (vid[V[x]], nid[N[x]]) for x in fa))


def uv_vertex_ply(path):
    """uv_surfaces() as ASCII PLY with per-vertex texture coordinates (s t):
    a vertex-domain texcoord (predictor 2 in the vertex domain)."""
    V, F, UV = uv_surfaces()
    with open(path, 'w') as f:
        f.write('ply\nformat ascii 1.0\nelement vertex %d\n' % len(V))
        f.write('property float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\n')
        f.write('element face %d\nproperty list uchar int vertex_indices\nend_header\n' % len(F))
        for (x, y, z), (s, t) in zip(V, UV):
            f.write('%.6f %.6f %.6f %.6f %.6f\n' % (x, y, z, s, t))
        for fa in F:
            f.write('%d %s\n' % (len(fa), ' '.join(map(str, fa))))


def uv_corner_obj(path):
    """A UV sphere with a latitude-longitude chart (a seam along one meridian,
    one value per face at the poles), a torus of quads and triangles (seams
    both ways), a box with one chart per side (four of them in the other
    texture orientation) and a jittered height field (two charts, texture
    coordinates its x, y, one mirrored), as OBJ with corner texture
    coordinates `vt u v` shared by the corners of a vertex within a chart:
    predictor 2 in the corner domain; segmented, many values are shared
    across segment borders (§8.12 imported values)."""
    V, F, VT = [], [], {}
    lines = []

    def v(x, y, z):
        V.append((x, y, z))
        return len(V) - 1

    def vt(key, u, w):
        if key not in VT:
            VT[key] = (len(VT) + 1, u, w)
        return VT[key][0]

    def face(cs):                                          # cs: (vertex, vt index)
        F.append(cs)
    n_, m_ = 14, 24
    top, bot = v(0, 0, 1), v(0, 0, -1)
    ring = sphere_rings(v, n_, m_)

    def st(i, j):                                          # sphere chart: column m_ is the seam's copy
        return vt(('s', i, j), 0.5 * j / m_, 0.5 * (1 - i / n_))
    for j in range(m_):
        face([(top, vt(('top', j), 0.5 * (j + 0.5) / m_, 0.5)), (ring[1, j], st(1, j)),
              (ring[1, (j + 1) % m_], st(1, j + 1))])
        face([(ring[n_ - 1, j], st(n_ - 1, j)), (bot, vt(('bot', j), 0.5 * (j + 0.5) / m_, 0.0)),
              (ring[n_ - 1, (j + 1) % m_], st(n_ - 1, j + 1))])
    for i in range(1, n_ - 1):
        for j in range(m_):
            a, b = (ring[i, j], st(i, j)), (ring[i + 1, j], st(i + 1, j))
            c, d = (ring[i + 1, (j + 1) % m_], st(i + 1, j + 1)), (ring[i, (j + 1) % m_], st(i, j + 1))
            if (i * 3 + j) % 5 == 0:
                face([a, b, c, d])
            else:
                face([a, b, c])
                face([a, c, d])
    N, M, R, r = 16, 8, 0.9, 0.3                           # a torus
    idx = {}
    for i in range(N):
        for j in range(M):
            al, be = 2 * math.pi * i / N, 2 * math.pi * j / M
            idx[i, j] = v(3 + (R + r * math.cos(be)) * math.cos(al), (R + r * math.cos(be)) * math.sin(al),
                          r * math.sin(be))

    def tt(i, j):
        return vt(('t', i, j), 0.5 + 0.45 * i / N, 0.05 + 0.4 * j / M)
    for i in range(N):
        for j in range(M):
            q = [(idx[i, j], tt(i, j)), (idx[(i + 1) % N, j], tt(i + 1, j)),
                 (idx[(i + 1) % N, (j + 1) % M], tt(i + 1, j + 1)), (idx[i, (j + 1) % M], tt(i, j + 1))]
            if (i + j) % 3 == 0:
                face(q)
            else:
                face(q[:3])
                face([q[0], q[2], q[3]])
    K = 4                                                  # a box, 4 x 4 cells per side
    bv = {}

    def bvert(p):
        if p not in bv:
            bv[p] = v(-3 + 0.5 * p[0] / K, 0.5 * p[1] / K, 0.5 * p[2] / K)
        return bv[p]
    for side in range(6):
        ax, sgn_ = side // 2, side % 2
        u_ax, w_ax = [a for a in range(3) if a != ax]
        for a in range(K):
            for b in range(K):
                corners = []
                for da, db in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = [0, 0, 0]
                    p[ax] = K * sgn_
                    p[u_ax], p[w_ax] = a + da, b + db
                    uu = (a + da) / K if side % 3 else 1 - (a + da) / K      # mirrored on sides 0 and 3
                    corners.append((bvert(tuple(p)),
                                    vt(('b', side, a + da, b + db), 0.5 + 0.08 * side + 0.07 * uu,
                                       0.55 + 0.3 * (b + db) / K)))
                if sgn_:
                    corners.reverse()                      # outward orientation
                if (a + b + side) % 2:
                    face(corners)
                else:
                    face(corners[:3])
                    face([corners[0], corners[2], corners[3]])
    G = 24                                                 # a jittered height field, two charts
    hv, rnd = {}, 12345
    for i in range(G + 1):
        for j in range(G + 1):
            rnd = (rnd * 1103515245 + 12345) % 2 ** 31
            jx, jy = (rnd % 1000) / 1000 - 0.5, (rnd // 1000 % 1000) / 1000 - 0.5
            x, y = (i + 0.35 * jx * (0 < i < G)) / G, (j + 0.35 * jy * (0 < j < G)) / G
            hv[i, j] = (v(x * 2, 3 + y * 2, 0.3 * math.sin(3 * x) * math.cos(2 * y)), x, y)

    def ht(i, j, chart):
        _, x, y = hv[i, j]
        return vt(('h', chart, i, j), 0.02 + 0.45 * x if chart == 0 else 0.98 - 0.45 * x, 0.5 + 0.45 * y)
    for i in range(G):
        for j in range(G):
            chart = int(i >= G // 2)
            q = [(hv[a, b][0], ht(a, b, chart)) for a, b in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1))]
            if (i * 7 + j) % 4:
                face([q[0], q[1], q[3]] if (i + j) % 2 else q[:3])
                face([q[1], q[2], q[3]] if (i + j) % 2 else [q[0], q[2], q[3]])
            else:
                face(q)
    with open(path, 'w') as f:
        f.write('# test mesh for reference_decoder.py: corner texture coordinates (predictor 2)\n')
        f.writelines('v %.6f %.6f %.6f\n' % p for p in V)
        f.writelines('vt %.6f %.6f\n' % (u, w) for _, u, w in sorted(VT.values()))
        f.writelines('f ' + ' '.join('%d/%d' % (c + 1, t) for c, t in fa) + '\n' for fa in F)


def varint(n):
    """n as a LEB128 varint (FORMAT.md §3)."""
    out = bytearray()
    while True:
        if n < 0x80:
            out.append(n)
            return bytes(out)
        out.append(0x80 | (n & 0x7F))
        n >>= 7


def split_container(data):
    """A .tsm file's bytes as (head, sections): head = the preamble and header
    (§2-3), sections = [id, codec, raw_length, stored bytes] in file order
    (§4.1); checksums are not checked."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from reference_decoder import read_varint
    n = len(data)
    _, p = read_varint(data, 4, n)
    for _ in range(3):
        _, p = read_varint(data, p, n)
    grid, level = data[p], data[p + 1]
    p += 18
    if level & 0x10:
        _, p = read_varint(data, p, n)
    if grid & 0x20:
        p += 8
        for _ in range(3):
            _, p = read_varint(data, p, n)
    head, sections = data[:p], []
    while True:
        tag, p = read_varint(data, p, n)
        if tag == 0:
            return head, sections
        stored, p = read_varint(data, p, n)
        raw = stored
        if tag & 1:
            raw, p = read_varint(data, p, n)
        sections.append([tag >> 1, tag & 1, raw, data[p:p + stored]])
        p += stored + 4


def join_container(head, sections):
    """The file of split_container's parts, every checksum computed (§4.1:
    the first section's covers the head too)."""
    from reference_decoder import xxh32
    out = bytearray(head)
    covered = 0
    for sid, codec, raw, stored in sections:
        out += varint(sid << 1 | codec) + varint(len(stored)) + (varint(raw) if codec else b'') + stored
        out += struct.pack('<I', xxh32(bytes(out[covered:])))
        covered = len(out)
    return bytes(out) + b'\x00'


def add_metadata(src, dst, entries, raw_payload=None, zstd=False):
    """Copies the .tsm file src to dst with a metadata section (id 9, §4.6)
    inserted after the header, as the reference encoder places it.
    entries: (key, value) byte strings; raw_payload: the payload as given (for
    malformed sections); zstd: store it zstd-coded (codec 1, by the zstd
    command), else raw."""
    head, sections = split_container(open(src, 'rb').read())
    if raw_payload is None:
        raw_payload = varint(len(entries)) + b''.join(
            bytes([len(k)]) + k + varint(len(v)) + v for k, v in entries)
    stored = raw_payload
    if zstd:
        import subprocess
        stored = subprocess.run(['zstd', '-q', '-c', '-19'], input=raw_payload, capture_output=True,
                                check=True).stdout
    sections.insert(0, [9, 1 if zstd else 0, len(raw_payload), stored])
    open(dst, 'wb').write(join_container(head, sections))


def mesh_section(src):
    """The .tsm file src's parts (split_container), the index of its raw
    mesh section (id 10, §4.7) and that section's payload."""
    head, sections = split_container(open(src, 'rb').read())
    for i, (sid, codec, _, stored) in enumerate(sections):
        if sid == 10 and codec == 0:
            return head, sections, i, stored
    sys.exit('%s: no raw mesh section' % src)


def replace_section(head, sections, i, payload, dst):
    """The file with its section i replaced by a raw mesh section (id 10)
    holding payload, written to dst."""
    sections[i] = [10, 0, len(payload), payload]
    open(dst, 'wb').write(join_container(head, sections))


def replace_in_mesh(src, dst, old, new):
    """Copies the .tsm file src to dst with the first occurrence of the bytes
    old in its raw mesh section (id 10, §4.7) replaced by new, and that
    section's lengths and checksum rewritten to match (a forged file that
    only the payload rules can refuse)."""
    head, sections, i, payload = mesh_section(src)
    if old not in payload:
        sys.exit('%s: %s not in the mesh section' % (src, old.hex()))
    replace_section(head, sections, i, payload.replace(old, new, 1), dst)


def forge_topology(src, dst, op):
    """Copies the one-segment .tsm file src to dst with its mesh section's
    topology stream (the third of §4.7) changed by op: 'mode=N' sets its first
    byte (the run coding mode, §8.3.1), 'cut=K' keeps its first K
    bytes; the stream lengths, the section's lengths and its checksum are
    rewritten to match."""
    from reference_decoder import read_varint
    head, sections, i, payload = mesh_section(src)
    lengths, r = [], 0
    for _ in range(4):
        n, r = read_varint(payload, r, len(payload))
        lengths.append(n)
    streams = []
    for n in lengths:
        streams.append(payload[r:r + n])
        r += n
    topo = bytearray(streams[2])
    key, value = op.split('=')
    if key == 'mode':
        topo[0] = int(value)
    else:
        topo = topo[:int(value)]
    streams[2] = bytes(topo)
    payload = b''.join(varint(len(x)) for x in streams) + b''.join(streams) + payload[r:]
    replace_section(head, sections, i, payload, dst)


def set_version(src, dst, version):
    """Copies the .tsm file src to dst saying format version `version`, with
    the first section's checksum (§4.1, which covers the header) rewritten
    to match: a file that only the version check (§2) can refuse."""
    head, sections = split_container(open(src, 'rb').read())
    head = head[:4] + varint(version) + head[5:]          # version 12 takes one byte
    open(dst, 'wb').write(join_container(head, sections))


def main():
    if len(sys.argv) > 1 and sys.argv[1] == '--set-version':
        # --set-version SRC DST N
        set_version(sys.argv[2], sys.argv[3], int(sys.argv[4]))
        return
    if len(sys.argv) > 1 and sys.argv[1] == '--forge-topology':
        # --forge-topology SRC DST mode=N | cut=K
        forge_topology(sys.argv[2], sys.argv[3], sys.argv[4])
        return
    if len(sys.argv) > 1 and sys.argv[1] == '--replace-in-mesh':
        # --replace-in-mesh SRC DST OLD_HEX NEW_HEX
        replace_in_mesh(sys.argv[2], sys.argv[3], bytes.fromhex(sys.argv[4]), bytes.fromhex(sys.argv[5]))
        return
    if len(sys.argv) > 1 and sys.argv[1] == '--add-metadata':
        # --add-metadata SRC DST KEY=VALUE ...   or   --add-metadata SRC DST --raw HEX
        args = sys.argv[4:]
        zstd = '--zstd' in args
        args = [a for a in args if a != '--zstd']
        if args and args[0] == '--raw':
            add_metadata(sys.argv[2], sys.argv[3], None, bytes.fromhex(args[1]), zstd)
        else:
            add_metadata(sys.argv[2], sys.argv[3], [tuple(a.encode().split(b'=', 1)) for a in args], None, zstd)
        return
    out = sys.argv[1] if len(sys.argv) > 1 else '.'
    os.makedirs(out, exist_ok=True)
    write_obj(os.path.join(out, 'triangle.obj'), [(0, 0, 0), (2, 0, 0), (0, 1, 0.5)], [[0, 1, 2]])
    write_obj(os.path.join(out, 'mixed.obj'), *mixed())
    write_obj(os.path.join(out, 'mixed_small.obj'), *mixed(6, 10))
    write_obj(os.path.join(out, 'lattice.obj'), *lattice())
    write_obj(os.path.join(out, 'fan.obj'), *fan())
    write_obj(os.path.join(out, 'irregular.obj'), *irregular())
    write_obj(os.path.join(out, 'loose.obj'), *loose())
    write_obj(os.path.join(out, 'box.obj'), *box())
    write_obj(os.path.join(out, 'double_sided.obj'), *double_sided(*mixed(16, 30)))
    unused_vt(os.path.join(out, 'unused_vt.obj'))
    attr_obj(os.path.join(out, 'attributes.obj'), *mixed(12, 20))
    attr_ply(os.path.join(out, 'attributes.ply'), *mixed(12, 20))
    uv_vertex_ply(os.path.join(out, 'uv_vertex.ply'))
    flat_ply(os.path.join(out, 'flat.ply'))
    cad_ply(os.path.join(out, 'cad.ply'))
    cad_obj(os.path.join(out, 'cad.obj'))
    uv_corner_obj(os.path.join(out, 'uv_corner.obj'))


if __name__ == '__main__':
    main()
