#!/usr/bin/env python3
"""Test meshes for reference_decoder.py (see check_decoder.sh). Writes into DIR:

  triangle.obj  the worked example of FORMAT.md §11
  mixed.obj     a latitude-longitude sphere (its vertex tree suits the ancestor
                predictor), a torus of quads with two holes (a handle, polygons),
                a fin of three triangles on one edge (a non-manifold edge), a
                hexagon, a degenerate face (a side face), three isolated vertices
  mixed_small.obj  the same with a 6 x 10 sphere (at -q 10 -l 9: ancestors
                with lattice planes)
  lattice.obj   a marching-tetrahedra isosurface on a 20^3 voxel grid: every
                vertex lies on a grid edge, so many coordinates share voxel planes
                (the geometry lattice), plus an isolated vertex

Usage: test_meshes.py DIR
"""
import math
import os
import sys


def write_obj(path, V, F):
    with open(path, 'w') as f:
        for p in V:
            f.write('v %.6f %.6f %.6f\n' % p)
        for fa in F:
            f.write('f ' + ' '.join(str(i + 1) for i in fa) + '\n')


def mixed(n_=30, m_=60):
    V, F = [], []

    def v(x, y, z):
        V.append((x, y, z))
        return len(V) - 1
    top = v(0, 0, 1)
    ring = {}
    for i in range(1, n_):
        th = math.pi * i / n_
        for j in range(m_):
            ph = 2 * math.pi * j / m_
            ring[i, j] = v(math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
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
    F.append([hc[1], hc[2], hc[2]])                        # a degenerate face
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


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else '.'
    os.makedirs(out, exist_ok=True)
    write_obj(os.path.join(out, 'triangle.obj'), [(0, 0, 0), (2, 0, 0), (0, 1, 0.5)], [[0, 1, 2]])
    write_obj(os.path.join(out, 'mixed.obj'), *mixed())
    write_obj(os.path.join(out, 'mixed_small.obj'), *mixed(6, 10))
    write_obj(os.path.join(out, 'lattice.obj'), *lattice())


if __name__ == '__main__':
    main()
