#!/usr/bin/env python3
"""An independent decoder for .tsm files (format version 12, the only one), written from
format-spec/FORMAT.md alone (section numbers below refer to it). Pure Python 3,
no third-party modules (zstd-compressed sections, codec 1, need the optional
`zstandard` module; the reference encoder writes them only for the metadata
section, §4.6, when that is smaller).

Decodes connectivity, geometry, segments, attributes (§8.12) and checks the
metadata section's layout (§4.6).

Usage:
  reference_decoder.py FILE.tsm                      print a summary
  reference_decoder.py FILE.tsm --compare OUT.ply    compare with `tsm decode FILE.tsm -o OUT.ply`:
                                                     a binary PLY byte for byte (positions, faces and
                                                     every attribute, as io_ply.cpp writes them);
                                                     an ASCII PLY by positions' float bits and faces
  reference_decoder.py FILE.tsm --compare-obj OUT.obj  compare with `tsm decode FILE.tsm -o OUT.obj`:
                                                     positions, vertex colours, the vt and vn value
                                                     lists (float bits) and every corner's indices
                                                     (a corner attribute's shared values, unused ones)
  reference_decoder.py FILE.tsm --write-ply OUT.ply  write the PLY `tsm decode` would write
  reference_decoder.py FILE.tsm --dump               print faces, grid indices, positions, attributes
  reference_decoder.py FILE.tsm --dump-attributes    print attribute headers, values (integers and
                                                     hex floats) and corner indices
  reference_decoder.py FILE.tsm --trace              also trace the geometry decoding

Exit status: 0 decoded (and equal, with --compare), 1 differs, 2 corrupt/unsupported.
"""
import copy
import math
import struct
import sys

NONE = 0xFFFFFFFF          # kNone
INVALID = 0xFFFFFFFF
UNKNOWN = 255              # act[v] before v is decoded
FLT_MAX = struct.unpack('<f', b'\xff\xff\x7f\x7f')[0]


def f32_below(c):
    """The binary32 value next below the binary32 value c (c finite, not -FLT_MAX)."""
    bits = struct.unpack('<I', struct.pack('<f', c))[0]
    if c > 0:
        bits -= 1
    elif c < 0:
        bits += 1
    else:
        bits = 0x80000001            # below +-0: the negative denormal of least magnitude
    return struct.unpack('<f', struct.pack('<I', bits))[0]


class Corrupt(Exception):
    pass


class Unsupported(Exception):
    pass


def reject(why):
    raise Corrupt(why)


# ---------------------------------------------------------------- §1 conventions

def xxh32(data, seed=0):
    P1, P2, P3, P4, P5 = 2654435761, 2246822519, 3266489917, 668265263, 374761393
    M = 0xFFFFFFFF

    def rotl(x, r):
        return ((x << r) | (x >> (32 - r))) & M

    def rnd(acc, lane):
        acc = (acc + lane * P2) & M
        return (rotl(acc, 13) * P1) & M

    n = len(data)
    i = 0
    if n >= 16:
        v1 = (seed + P1 + P2) & M
        v2 = (seed + P2) & M
        v3 = seed & M
        v4 = (seed - P1) & M
        while i + 16 <= n:
            a, b, c, d = struct.unpack_from('<4I', data, i)
            v1, v2, v3, v4 = rnd(v1, a), rnd(v2, b), rnd(v3, c), rnd(v4, d)
            i += 16
        h = (rotl(v1, 1) + rotl(v2, 7) + rotl(v3, 12) + rotl(v4, 18)) & M
    else:
        h = (seed + P5) & M
    h = (h + n) & M
    while i + 4 <= n:
        h = (h + struct.unpack_from('<I', data, i)[0] * P3) & M
        h = (rotl(h, 17) * P4) & M
        i += 4
    while i < n:
        h = (h + data[i] * P5) & M
        h = (rotl(h, 11) * P1) & M
        i += 1
    h ^= h >> 15
    h = (h * P2) & M
    h ^= h >> 13
    h = (h * P3) & M
    h ^= h >> 16
    return h


def read_varint(buf, pos, end):
    """§1: unsigned LEB128, at most 10 bytes, the 10th only 0x00 or 0x01."""
    v = 0
    for i in range(10):
        if pos >= end:
            reject('varint runs past the end')
        b = buf[pos]
        pos += 1
        if i == 9:
            if b > 1:
                reject('bad 10th varint byte')
            return v | (b << 63), pos
        v |= (b & 0x7F) << (7 * i)
        if not b & 0x80:
            return v, pos
    reject('unreachable')


# ---------------------------------------------------------------- §2-§4 container

MAGIC = b'TSM\x1a'
FORMAT_VERSION = 12


def read_container(data):
    n = len(data)
    if n < 4 or data[:4] != MAGIC:
        reject('not a .tsm file')                                   # step 1
    version, p = read_varint(data, 4, n)                            # step 2
    if version != FORMAT_VERSION:
        raise Unsupported('format version %d (this decoder reads version %d only)'
                          % (version, FORMAT_VERSION))              # step 3
    h = {'version': version}
    h['vertex_count'], p = read_varint(data, p, n)                  # step 4
    h['face_count'], p = read_varint(data, p, n)
    h['corner_count'], p = read_varint(data, p, n)
    if n - p < 2 + 12 + 4:
        reject('header fields')                                     # step 5
    grid, level = data[p], data[p + 1]
    h['bits'] = grid & 0x1F
    axis = grid >> 6
    h['level'] = level & 0x0F
    p += 2
    h['origin'] = list(struct.unpack_from('<3f', data, p))
    p += 12
    top = struct.unpack_from('<f', data, p)[0]
    p += 4
    h['segment_count'] = 1
    if level & 0x10:                                                # step 6: several segments
        h['segment_count'], p = read_varint(data, p, n)
    h['exact'] = None
    if grid & 0x20:                                                 # step 7, §5.1: the exact grid
        if n - p < 8:
            reject('header fields')
        step = struct.unpack_from('<d', data, p)[0]
        p += 8
        base = []
        for _ in range(3):
            z, p = read_varint(data, p, n)
            base.append((z >> 1) ^ -(z & 1))
        if not (math.isfinite(step) and step > 0) or any(abs(b) > 1 << 62 for b in base):
            reject('exact grid')
        h['exact'] = (step, base)
    if axis > 2:
        reject('grid axis')                                         # step 8
    if level & 0xE0 or (level & 0x10 and not 2 <= h['segment_count'] <= 0xFFFFFFFF):
        reject('level byte or segment count')                       # step 9
    if not all(math.isfinite(o) for o in h['origin']):
        reject('origin')                                            # step 10
    if not (math.isfinite(top) and top >= h['origin'][axis]):
        reject('bounding-box maximum')                              # step 11
    h['extent'] = top - h['origin'][axis]
    if not 1 <= h['bits'] <= 30:
        reject('quantization bits')                                 # step 12
    sections = {}
    segments = []
    refinements = []
    order = []
    pos = p
    covered = 0                          # §4.1: the first section's checksum covers the header too
    while True:
        tag, pos = read_varint(data, pos, n)                        # step 13
        if tag == 0:                                                # step 14: the end marker
            break
        sid, codec = tag >> 1, tag & 1
        if sid == 0 or sid > 0xFFFF:
            reject('section id')                                    # step 15
        stored, pos = read_varint(data, pos, n)                     # step 16
        raw = stored
        if codec == 1:
            raw, pos = read_varint(data, pos, n)
        if stored > n - pos or n - pos - stored < 4:
            reject('stored length')                                 # step 17
        if codec == 1 and raw > stored * 1024:
            reject('expansion')                                     # step 18
        body = data[pos:pos + stored]
        pos += stored
        if struct.unpack_from('<I', data, pos)[0] != xxh32(data[covered:pos]):
            reject('section checksum')                              # step 19
        pos += 4
        covered = pos
        if sid == 7:                                                # step 20, §4.3
            if h['segment_count'] == 1 or len(segments) >= h['segment_count']:
                reject('segment section')
        elif sid == 12:                                             # §4.3, §4.8: repeats
            if 13 in sections or 11 in sections or 14 in sections:
                reject('refinement after the loose vertices or in a keep-order or lossless file')
            if not (10 in sections if h['segment_count'] == 1 else len(segments) == h['segment_count']):
                reject('refinement before the base mesh')
            if len(refinements) >= 64:
                reject('too many refinement sections')
        elif sid == 13 and not refinements:
            reject('loose vertices before any refinement')
        elif sid in (11, 14) and refinements:
            reject('order or exceptions in a progressive file')
        elif sid in sections:
            reject('duplicate section id')
        elif 3 <= sid <= 6 or sid == 8:
            reject('reserved section id %d' % sid)
        elif sid == 10 and h['segment_count'] > 1:
            reject('mesh section in a segmented file')
        if codec == 1:                                              # step 21
            try:
                import zstandard
            except ImportError:
                if sid == 9:        # metadata: only its layout is checked (§4.6); skip it
                    sections[sid] = None
                    order.append(sid)
                    if len(order) > 4096:
                        reject('too many sections')                 # step 22
                    continue
                raise Unsupported('zstd section (install the zstandard module)')
            try:
                body = zstandard.ZstdDecompressor().decompress(body, max_output_size=raw)
            except Exception:
                reject('zstd')
            if len(body) != raw:
                reject('zstd length')
        if sid == 7:
            segments.append(bytes(body))
            continue
        if sid == 12:
            refinements.append(bytes(body))
            continue
        sections[sid] = bytes(body)
        order.append(sid)
        if len(order) > 4096:
            reject('too many sections')                             # step 22
    if pos != n:
        reject('bytes after the end marker')                        # step 23
    sections[7] = segments
    sections[12] = refinements
    return h, sections


# ---------------------------------------------------------------- §8.1 range decoder and models

class RangeDecoder:
    def __init__(self, data):
        self.s = data
        self.pos = 0
        self.overrun = 0
        self.range = 0xFFFFFFFF
        self.code = 0
        for _ in range(4):
            self.code = ((self.code << 8) | self.next_byte()) & 0xFFFFFFFF

    def next_byte(self):
        if self.pos < len(self.s):
            b = self.s[self.pos]
            self.pos += 1
            return b
        self.overrun += 1
        return 0

    def normalize(self):
        while self.range < (1 << 24):
            self.range = (self.range << 8) & 0xFFFFFFFF
            self.code = ((self.code << 8) | self.next_byte()) & 0xFFFFFFFF

    def bit(self, probs, i):
        """probs: a list of models (p | n << 16: probability and update
        count, §8.1), i: index of the one to use and adapt."""
        b = self.bit_fixed(probs[i] & 0xFFFF)
        adapt(probs, i, b)
        return b

    def bit_fixed(self, p):
        """A decision with probability p of a 0 bit, nothing adapted."""
        bound = (self.range >> 15) * p
        if self.code < bound:
            self.range = bound
            b = 0
        else:
            self.code -= bound
            self.range -= bound
            b = 1
        self.normalize()
        return b

    def direct(self, n):
        v = 0
        for _ in range(n):
            self.range >>= 1
            b = 1 if self.code >= self.range else 0
            if b:
                self.code -= self.range
            v = (v << 1) | b
            self.normalize()
        return v

    def truncated(self):
        return self.overrun > 8


# shift(n) = min(7, floor(log2(n + 2))) for update counts n = 0 .. 128 (§8.1)
SHIFT = [min(7, (n + 2).bit_length() - 1) for n in range(129)]


def probs(n):
    return [16384] * n           # p = 16384, count 0


def adapt(probs, i, b):
    """§8.1: the model's update after bit b (its shift grows with its update count)."""
    p = probs[i] & 0xFFFF
    n = probs[i] >> 16
    s = SHIFT[n]
    p = min(p + ((32768 - p) >> s), 32704) if b == 0 else max(p - (p >> s), 64)
    probs[i] = p | (min(n + 1, 128) << 16)


# §8.1.1 logistic mixing
SQUASH_T = [1, 2, 4, 6, 10, 17, 27, 45, 74, 120, 194, 311, 488, 747, 1102, 1546, 2048, 2550, 2994, 3349,
            3608, 3785, 3902, 3976, 4022, 4051, 4069, 4079, 4086, 4090, 4092, 4094, 4095]


def squash(t):
    t = min(max(t, -2047), 2047)
    j, w = (t + 2048) >> 7, (t + 2048) & 127
    return (SQUASH_T[j] * (128 - w) + SQUASH_T[j + 1] * w + 64) >> 7


def _stretch_table():
    st = []
    for t in range(-2047, 2048):
        while len(st) <= squash(t):
            st.append(t)
    return st + [2047] * (4096 - len(st))


STRETCH = _stretch_table()


def mixed_bit(d, pa, ia, pb, ib, w):
    """One decision from models pa[ia] and pb[ib] mixed with weights w (§8.1.1)."""
    x = (STRETCH[(pa[ia] & 0xFFFF) >> 3], STRETCH[(pb[ib] & 0xFFFF) >> 3], 256)
    t = (w[0] * x[0] + w[1] * x[1] + w[2] * x[2]) >> 16      # floor
    p = squash(t)
    b = d.bit_fixed(min(max(p << 3, 64), 32704))
    adapt(pa, ia, b)
    adapt(pb, ib, b)
    err = (0 if b else 4095) - p
    for k in range(3):
        w[k] = min(max(w[k] + ((x[k] * err) >> 9), -(1 << 22)), 1 << 22)
    return b


def mix_weights():
    return [[32768, 32768, 0] for _ in range(14)]


def decode_mixed_sint(d, A, B, W):
    """A signed integer as SIntModel(6) codes it, each decision mixed from A and B (§8.1.1)."""
    if mixed_bit(d, A.p, 0, B.p, 0, W[0]) == 0:
        return 0
    neg = mixed_bit(d, A.p, 1, B.p, 1, W[1])
    node = 1
    for k in range(6):
        node = (node << 1) | mixed_bit(d, A.magnitude.length.p, node, B.magnitude.length.p, node, W[2 + k])
    n = node - 64
    if n > 32:
        return -0x7FFFFFFF if neg else 0x7FFFFFFF
    x = 1
    ctx = 1
    top = min(n, 6)
    ma, mb = A.magnitude.mantissa[n], B.magnitude.mantissa[n]
    for k in range(top):
        b = mixed_bit(d, ma, ctx, mb, ctx, W[8 + k])
        ctx = (ctx << 1) | b
        x = (x << 1) | b
    rest = n - top
    if rest > 0:
        x = (x << rest) | d.direct(rest)
    m = min(x, 0x7FFFFFFF)
    return -m if neg else m


class BitTree:
    def __init__(self, k):
        self.k = k
        self.p = probs(1 << k)

    def decode(self, d):
        node = 1
        for _ in range(self.k):
            node = (node << 1) | d.bit(self.p, node)
        return node - (1 << self.k)


class UIntModel:
    def __init__(self, m=2):
        self.m = m
        self.length = BitTree(6)
        self.mantissa = [probs(1 << m) for _ in range(33)]

    def decode(self, d):
        n = self.length.decode(d)
        if n > 32:
            return INVALID
        x = 1
        node = 1
        top = min(n, self.m)
        mp = self.mantissa[n]
        for _ in range(top):
            b = d.bit(mp, node)
            node = (node << 1) | b
            x = (x << 1) | b
        rest = n - top
        if rest > 0:
            x = (x << rest) | d.direct(rest)
        v = x - 1
        return INVALID if v >= 0xFFFFFFFF else v


class SIntModel:
    def __init__(self, m=2):
        self.p = probs(2)          # [zero, sign]
        self.magnitude = UIntModel(m)

    def decode(self, d):
        if d.bit(self.p, 0) == 0:
            return 0
        neg = d.bit(self.p, 1)
        m = self.magnitude.decode(d)
        if m >= 0x7FFFFFFF:
            m = 0x7FFFFFFE
        v = m + 1
        return -v if neg else v


# ---------------------------------------------------------------- §8.6 bounding loop

def bounding_loop(lparent, jumps):
    """lparent: local parents (lparent[0] = NONE); jumps: list of [corner, partner].
    Returns loop (local vertices) and loop_twin."""
    n = len(lparent)
    nj = len(jumps)
    children = [[] for _ in range(n)]
    for v in range(1, n):                                   # step 1
        if lparent[v] == NONE or lparent[v] >= v:
            reject('loop: parent after child')
        children[lparent[v]].append(v)                      # increasing position
    slots = []                                              # step 2: tree slots
    for v in range(n):
        sl = ([lparent[v]] if v != 0 else []) + children[v]
        slots.append(sl)
    deg = [len(s) for s in slots]

    def slot_back(v, w):      # the slot of w pointing back to v
        if w != 0 and lparent[w] == v:
            return 0
        base = 1 if w != 0 else 0
        for i in range(base, deg[w]):
            if slots[w][i] == v:
                return i
        return None

    tour = 2 * (n - 1)                                      # step 3
    corner_v = [0] * tour
    corner_s = [0] * tour
    v, s = 0, 0
    for step in range(tour):
        w = slots[v][s]
        back = slot_back(v, w)
        if back is None:
            reject('loop: tree slot without a way back')
        qq = (step + 1) % tour
        corner_v[qq] = w
        corner_s[qq] = back
        v = w
        s = (back + 1) % deg[w]
    for i in range(nj):                                     # step 4
        c, pt = jumps[i]
        if c >= tour or pt >= nj or pt == i or jumps[pt][1] != i:
            reject('loop: bad jump endpoint')
        if i > 0 and jumps[i - 1][0] > c:
            reject('loop: jump corners decrease')
    # step 5: full slots: entries ('t', tree slot index) or ('j', endpoint)
    at_corner = {}
    for i in range(nj):
        c = jumps[i][0]
        at_corner.setdefault((corner_v[c], corner_s[c]), []).append(i)
    full = []                  # full[v] = list of slot descriptors
    jump_slot = [None] * nj    # endpoint -> (v, index in full[v])
    tree_slot = []             # tree_slot[v][s] -> index in full[v]
    for v in range(n):
        fl = []
        ts = []
        for s in range(deg[v]):
            ts.append(len(fl))
            fl.append(('t', s))
            for i in at_corner.get((v, s), []):
                jump_slot[i] = (v, len(fl))
                fl.append(('j', i))
        full.append(fl)
        tree_slot.append(ts)

    def reverse(v, k):         # (owner, index) of the reverse of full slot k of v
        kind, x = full[v][k]
        if kind == 't':
            w = slots[v][x]
            ws = slot_back(v, w)
            if ws is None:
                reject('loop: no reverse slot')
            return w, tree_slot[w][ws]
        return jump_slot[jumps[x][1]]

    L = 2 * (n - 1) + nj
    loop = []
    left_at = {}
    slot_of = []
    cur = (0, 0)                                            # step 6
    while True:
        if len(loop) >= L or cur in left_at:
            reject('loop: walk does not close')
        left_at[cur] = len(loop)
        slot_of.append(cur)
        loop.append(cur[0])
        w, r = reverse(*cur)
        nxt = r + 1 if r + 1 < len(full[w]) else 0
        cur = (w, nxt)
        if cur == (0, 0):
            break
    if len(loop) != L:
        reject('loop: wrong length')
    loop_twin = []                                          # step 7
    for p in range(L):
        r = reverse(*slot_of[p])
        if r not in left_at:
            reject('loop: slot never left')
        loop_twin.append(left_at[r])
    return loop, loop_twin


# ---------------------------------------------------------------- §8.8 triangle tree walk (+ §8.10 step 1 marks)

def triangle_walk(L, root, march, branch, loop, n, read_bit):
    """read_bit(va, vb, prev, vr, vl) reads one marching bit with context
    bit[va][vb][prev][vr][vl] (vr, vl: loop visits of the candidates, 0..2)."""
    nr = len(march)
    if L < 4 or root >= L:
        reject('walk: L or root')
    if nr < 1:
        reject('walk: no runs')
    t1 = [0] * nr
    stack = []
    for i in range(nr - 1, -1, -1):                          # step 2
        s = march[i] + 1
        if branch[i]:
            if len(stack) < 2:
                reject('walk: branch lacks subtrees')
            s1 = stack.pop()
            s2 = stack.pop()
            t1[i] = s1
            s += s1 + s2
        if s > L:
            reject('walk: subtree too big')
        stack.append(s)
    if len(stack) != 1 or stack[0] != L - 3:
        reject('walk: sizes')

    def fwd(p, d):
        return (p + d) % L

    def bwd(p, d):
        return (p + L - d) % L

    tris = []       # (a, b, x) loop positions
    parent = []
    slot = []
    marks = []      # per triangle: [mark edge0, edge1, edge2] (loop edge or None)
    val = [0] * n   # valences so far, per local vertex
    visits = [0] * n  # loop positions per local vertex (its degree in the cut)
    for p in range(L):
        visits[loop[p]] += 1

    class Tris(list):
        def append(self, t):
            for c in t:
                val[loop[c]] += 1
            list.append(self, t)
    tris = Tris()
    r = root
    tris.append((bwd(r, 1), r, fwd(r, 1)))                   # step 3
    parent.append(NONE)
    slot.append(0)
    marks.append([bwd(r, 1), r, None])
    gate = (bwd(r, 1), fwd(r, 1), 0, 2)                      # a, b, owner, slot
    gstack = []
    for i in range(nr):                                      # step 4
        prev = 2
        for _ in range(march[i]):
            a, b, par, sl = gate
            span = (a - b) % L
            if span < 3:
                reject('walk: march step without room')
            bit = read_bit(min(val[loop[a]], 7), min(val[loop[b]], 7), prev,
                           min(visits[loop[fwd(b, 1)]], 3) - 1, min(visits[loop[bwd(a, 1)]], 3) - 1)
            prev = bit
            k = len(tris)
            if bit == 0:
                x = fwd(b, 1)
                tris.append((a, b, x))
                marks.append([None, b, None])
                gate = (a, x, k, 2)
            else:
                x = bwd(a, 1)
                tris.append((a, b, x))
                marks.append([None, None, x])
                gate = (x, b, k, 1)
            parent.append(par)
            slot.append(sl)
        a, b, par, sl = gate
        span = (a - b) % L
        k = len(tris)
        if not branch[i]:
            if span != 2:
                reject('walk: leaf does not close')
            tris.append((a, b, fwd(b, 1)))
            marks.append([None, b, fwd(b, 1)])
            parent.append(par)
            slot.append(sl)
            if not gstack:
                if i != nr - 1:
                    reject('walk: runs left over')
                break
            gate = gstack.pop()
        else:
            off = t1[i] + 1
            if off + 2 > span:
                reject('walk: Y-vertex outside')
            x = fwd(b, off)
            tris.append((a, b, x))
            marks.append([None, None, None])
            parent.append(par)
            slot.append(sl)
            gstack.append((a, x, k, 2))
            gate = (x, b, k, 1)
    if len(tris) != L - 2:
        reject('walk: triangle count')                       # step 5
    return tris, parent, slot, marks


# ---------------------------------------------------------------- §8.3 connectivity

def stitch_targets_by_candidates(nstitch, P, tri, twin, virtual, stitch_to, run_value,
                                 o_position, o_distance, o_rank, do, overrun):
    """§8.3.2: every stitch position, then each target by its
    rank among the candidates (or, rank 0, as a distance)."""
    stitched = [0] * P
    at_list = []
    at = 0
    for i in range(nstitch):
        d = run_value(o_position, do, 6)
        if overrun() or at + d >= P or (i > 0 and d == 0):
            reject('stitch position')
        at += d
        stitched[at] = 1
        at_list.append(at)
    first_he = [NONE] * P                  # the last half-edge in decode order leaving p
    for h, x in enumerate(tri):
        if x < P:
            first_he[x] = h

    def ring(p):                           # at most 16 heads of half-edges leaving p
        out = []
        h0 = h = first_he[p]
        for _ in range(16):
            if h >= len(tri):
                break
            t = h - h % 3
            out.append(tri[t + (h % 3 + 1) % 3])
            h = twin[t + (h % 3 + 2) % 3]
            if h == h0:
                break
        return out

    def vertex(n, d):                      # the vertex position n stands for, seen from stitch d
        if n >= P or virtual[n]:
            return NONE
        if not stitched[n]:
            return n
        return stitch_to[n] if n < d else NONE

    for d in at_list:
        known = [r for r in (vertex(n, d) for n in ring(d)) if r != NONE]
        near = set(known)
        votes = {}
        for r in known:
            for x in ring(r):
                c = vertex(x, d)
                if c != NONE and c < d and c not in near:
                    votes[c] = votes.get(c, 0) + 1
        ranked = sorted(votes, key=lambda c: (-votes[c], -c))
        ctx = 1 if ranked and votes[ranked[0]] >= 3 else 0
        rank = o_rank[ctx].decode(do)
        if overrun() or rank == INVALID:
            reject('stitch target rank')
        if rank == 0:
            dist = run_value(o_distance, do, 7)
            if dist >= d:
                reject('stitch target')
            t = d - dist - 1
        else:
            if rank > len(ranked):
                reject('stitch target rank')
            t = ranked[rank - 1]
        if virtual[t] or stitched[t]:
            reject('stitch to a vertex without position')
        stitch_to[d] = t


def decode_connectivity(s3, s4, s5, vertex_count, face_count, corner_count):
    tables = rbits = None
    if len(s5) < 1:                                         # §8.3.1: the mode byte
        reject('topology stream is empty (no run coding mode)')
    if s5[0] > 3:
        reject('topology mode %d' % s5[0])
    welded = (s5[0] & 2) != 0                               # §8.13
    if s5[0] & 1:
        tables, rbits, p = read_tables(s5, 1, 8, 1, 'run values')
        s5 = s5[p:]
    else:
        s5 = s5[1:]

    def run_value(model, d, c):                             # §8.3.1: with mode 1 from the tables
        if tables is None:
            return model.decode(d)
        v = table_residual(tables, rbits, c, 'run values')
        return INVALID if v < 0 else v

    dv, dt, do = RangeDecoder(s3), RangeDecoder(s4), RangeDecoder(s5)
    # §8.2 models
    v_length = [UIntModel(), UIntModel()]
    v_leaf = probs(2)
    v_last = probs(2)             # last[child index 1, or 2 and more]
    t_root = UIntModel()
    t_march = [[UIntModel(), UIntModel()], [UIntModel(), UIntModel()]]  # [previous end][this end]
    t_end = [probs(2), probs(2)]   # [previous end][the end before it]
    t_bit = probs(8 * 8 * 3 * 9)   # bit[va][vb][prev][vr][vl] at ((8 va + vb) 3 + prev) 9 + 3 vr + vl
    t_diag = probs(2)
    o_count, o_corner, o_partner, o_position, o_distance, o_face_size, o_index = (UIntModel() for _ in range(7))
    o_rank = [UIntModel(), UIntModel()]                      # §8.3.2
    o_has_poly = probs(1)
    o_on_edges = probs(1)                                    # §8.3.3
    o_edge_any = probs(4)                                    # [prev][touched] at 2 prev + touched
    o_edge_more = probs(1)
    o_edge_count = UIntModel()
    o_edge_end = probs(2)

    def overrun():
        return dv.overrun > 8 or dt.overrun > 8 or do.overrun > 8

    max_positions = vertex_count + 2 * corner_count
    C = o_count.decode(do)
    polygons = do.bit(o_has_poly, 0)
    if C > max_positions:
        reject('component count')
    parent = []           # global pre-order parents
    tri = []              # §8.10 tri[]: 3 positions per global triangle
    tparent = []          # global parent triangle
    tslot = []
    glued = []
    twin = []
    prev_leaf = 1
    info = {'components': C, 'jump_edges': 0}
    for c in range(C):
        start = len(parent)
        # -- vertex tree §8.4
        stack = []
        root_run = True
        while True:
            if overrun():
                reject('vertex tree truncated')
            ln = run_value(v_length[prev_leaf], dv, prev_leaf)
            if ln == INVALID or len(parent) + ln + 1 > max_positions:
                reject('vertex run length')
            leaf = dv.bit(v_leaf, prev_leaf)
            prev_leaf = leaf
            par = NONE
            if not root_run:
                if not stack:
                    reject('run without parent')
                par = stack[-1][0]
                idx = stack[-1][1]
                stack[-1][1] += 1
                if idx > 0 and dv.bit(v_last, 1 if idx > 1 else 0) == 1:
                    stack.pop()
            root_run = False
            for _ in range(ln + 1):
                parent.append(par)
                par = len(parent) - 1
            if leaf == 0:
                stack.append([par, 0])              # branching vertex, child runs so far
            if leaf == 1 and not stack:
                break
        n = len(parent) - start
        if n < 2:
            continue
        if n == 2:
            reject('two-vertex component')
        # -- jump edges (stream 5)
        nj = o_count.decode(do)
        if nj > 2843 * (len(s5) + 8) // 6 or nj % 2 or overrun():
            reject('jump count')
        jumps = []
        corner = 0
        for i in range(nj):
            d = o_corner.decode(do)
            if d > 2 * n:
                reject('jump corner')
            corner += d
            jumps.append([corner, NONE])
        for i in range(nj):
            if jumps[i][1] != NONE:
                continue
            d = o_partner.decode(do)
            if d >= nj or i + 1 + d >= nj or jumps[i + 1 + d][1] != NONE:
                reject('jump partner')
            jumps[i][1] = i + 1 + d
            jumps[i + 1 + d][1] = i
        info['jump_edges'] += nj // 2
        if overrun():
            reject('topology truncated')
        lparent = [NONE if parent[start + i] == NONE else parent[start + i] - start for i in range(n)]
        loop, loop_twin = bounding_loop(lparent, jumps)
        L = len(loop)
        # -- triangle tree (stream 4)
        root = t_root.decode(dt)
        total = 0
        leaves = branches = 0
        prev_end = prev_end2 = 1
        march, branch = [], []
        while True:
            if overrun():
                reject('triangle tree truncated')
            br = dt.bit(t_end[prev_end], prev_end2)
            m = run_value(t_march[prev_end][br], dt, 2 + 2 * prev_end + br)
            if m == INVALID or total + m + 1 > L:
                reject('march count')
            march.append(m)
            branch.append(br)
            prev_end2 = prev_end
            prev_end = br
            total += m + 1
            if br:
                branches += 1
            else:
                leaves += 1
            if leaves == branches + 1:
                break
        ltris, lpar, lslot, marks = triangle_walk(
            L, root, march, branch, loop, n, lambda va, vb, prev, vr, vl: dt.bit(t_bit, ((8 * va + vb) * 3 + prev) * 9 + 3 * vr + vl))
        if overrun():
            reject('triangle tree truncated')
        T = L - 2
        base = len(tparent)
        # -- §8.10 steps 1-3
        twin.extend([NONE] * (3 * T))
        loop_he = [NONE] * L
        for k in range(T):
            for e in range(3):
                p = marks[k][e]
                if p is not None:
                    if loop_he[p] != NONE:
                        reject('a loop edge belongs to two triangles')
                    loop_he[p] = 3 * (base + k) + e
        for k in range(T):
            for e in range(3):
                p = marks[k][e]
                if p is not None:
                    twin[3 * (base + k) + e] = loop_he[loop_twin[p]]
        for k in range(1, T):
            hp = 3 * (base + lpar[k]) + lslot[k]
            twin[3 * (base + k)] = hp
            twin[hp] = 3 * (base + k)
        for k in range(T):
            for i in range(3):
                tri.append(start + loop[ltris[k][i]])
            tparent.append(NONE if lpar[k] == NONE else base + lpar[k])
            tslot.append(lslot[k])
            g = 0
            if polygons and k > 0:
                g = dt.bit(t_diag, 0 if k == 1 else glued[-1])
            glued.append(g)
        if len(tparent) > corner_count + max_positions:
            reject('too many triangles')
    P = len(parent)
    nvirt = o_count.decode(do)
    if nvirt > P:
        reject('virtual count')
    virtual = [0] * P
    at = 0
    for i in range(nvirt):
        d = run_value(o_position, do, 6)
        if d > P or at + d >= P or (i > 0 and d == 0):
            reject('virtual position')
        at += d
        virtual[at] = 1
    nstitch = o_count.decode(do)
    if nstitch > P:
        reject('stitch count')
    stitch_to = [NONE] * P
    if nstitch > 0:
        stitch_targets_by_candidates(nstitch, P, tri, twin, virtual, stitch_to, run_value,
                                     o_position, o_distance, o_rank, do, overrun)
    # §8.7 numbering
    ids = [NONE] * P
    nxt = 0
    for p in range(P):
        if virtual[p]:
            continue
        if stitch_to[p] != NONE:
            t = stitch_to[p]
            if virtual[t] or stitch_to[t] != NONE:
                reject('stitch to a vertex without position')
            ids[p] = ids[t]
        else:
            ids[p] = nxt
            nxt += 1
    if welded and nxt <= vertex_count:                       # §8.13: the ids are points
        vertex_count = nxt
    if nxt != vertex_count:
        reject('vertex count')
    # §8.10 step 4
    H = len(twin)
    for h in range(H):
        t = twin[h]
        if t >= H or twin[t] != h:
            reject('the cut surface does not close')
    vparent = [NONE] * vertex_count
    for p in range(P):
        if virtual[p] or stitch_to[p] != NONE:
            continue
        if parent[p] != NONE:
            if virtual[parent[p]]:
                reject('virtual parent')
            vparent[ids[p]] = ids[parent[p]]
    # §8.9 faces
    faces = []
    ncorners = [0]

    def push(face):
        if len(faces) >= face_count or ncorners[0] + len(face) > corner_count:
            reject('too many faces/corners')
        faces.append(list(face))
        ncorners[0] += len(face)

    NT = len(tparent)
    # polygon cycles: node lists
    nvert, nnext = [], []
    edge_node = [NONE] * (3 * NT)
    group = [NONE] * NT
    first_node = [NONE] * NT
    for k in range(NT):
        tv = tri[3 * k:3 * k + 3]
        if virtual[tv[0]] or virtual[tv[1]] or virtual[tv[2]]:
            if glued[k]:
                reject('glued virtual triangle')
            continue
        cc = [ids[tv[0]], ids[tv[1]], ids[tv[2]]]
        if not polygons:
            push(cc)
            continue
        if not glued[k]:
            n0 = len(nvert)
            nvert += cc
            nnext += [n0 + 1, n0 + 2, n0]
            for i in range(3):
                edge_node[3 * k + i] = n0 + i
            group[k] = k
            first_node[k] = n0
        else:
            par = tparent[k]
            nd = NONE if par == NONE else edge_node[3 * par + tslot[k]]
            if nd == NONE or group[par] == NONE:
                reject('glued to a missing edge')
            x = len(nvert)
            nvert.append(cc[2])
            nnext.append(nnext[nd])
            nnext[nd] = x
            edge_node[3 * k + 1] = nd
            edge_node[3 * k + 2] = x
            edge_node[3 * par + tslot[k]] = NONE
            group[k] = group[par]
    if polygons:
        members = {}
        for k in range(NT):
            if group[k] != NONE:
                members.setdefault(group[k], []).append(k)
        for k in range(NT):
            if group[k] != k:
                continue
            m = len(members[k])
            cyc = []
            nd = first_node[k]
            while True:
                cyc.append(nvert[nd])
                nd = nnext[nd]
                if nd == first_node[k] or len(cyc) > len(nvert):
                    break
            if len(cyc) != m + 2:
                reject('polygon does not close')
            if m >= 2:
                count = [0] * len(cyc)
                for t in members[k]:
                    for c3 in tri[3 * t:3 * t + 3]:
                        oid = ids[c3]
                        if oid in cyc:
                            count[cyc.index(oid)] += 1
                apex = count.index(max(count))
                cyc = cyc[apex:] + cyc[:apex]
            push(cyc)
    nside = o_count.decode(do)
    if nside > face_count:
        reject('side face count')
    nverbatim = nside
    if nside > 0 and do.bit(o_on_edges, 0):
        # §8.3.3 side faces on edges
        nverbatim = o_count.decode(do)
        if nverbatim >= nside:
            reject('side face count')
        target = nside - nverbatim
        found = 0
        touched = [0] * vertex_count
        prev = 0
        for h in range(len(tri)):
            if found == target:
                break
            if twin[h] < h:
                continue
            a, b = tri[h], tri[h - 2 if h % 3 == 2 else h + 1]
            if virtual[a] or virtual[b] or ids[a] == ids[b]:
                continue
            u, v = ids[a], ids[b]
            anyf = do.bit(o_edge_any, 2 * prev + (touched[u] | touched[v]))
            prev = anyf
            if anyf:
                touched[u] = touched[v] = 1
                n = 1
                if do.bit(o_edge_more, 0):
                    more = o_edge_count.decode(do)
                    if more >= target:
                        reject('side faces on edges')
                    n = 2 + more
                if n > target - found:
                    reject('side faces on edges')
                pe = 0
                for j in range(n):
                    pe = do.bit(o_edge_end, pe)
                    r, o = (v, u) if pe else (u, v)
                    push([r, r, o])
                found += n
            if overrun():
                reject('side faces on edges')
        if found != target:
            reject('side faces on edges')
    for i in range(nverbatim):
        sz = o_face_size.decode(do)
        if sz > corner_count or overrun():
            reject('side face size')
        face = []
        for j in range(sz):
            x = o_index.decode(do)
            if x >= vertex_count:
                reject('side face corner')
            face.append(x)
        push(face)
    if overrun():
        reject('connectivity truncated')
    if len(faces) != face_count or ncorners[0] != corner_count:
        reject('face/corner count mismatch')
    layout = {'tri': tri, 'twin': twin, 'id': ids, 'vparent': vparent, 'vertex_count': vertex_count}
    info.update(virtual=nvirt, stitches=nstitch, side_faces=nside, polygons=polygons, triangles=NT,
                welded=welded, points=vertex_count)
    return faces, layout, info


# ---------------------------------------------------------------- §8.5 geometry

def nxt_he(h):
    return h - 2 if h % 3 == 2 else h + 1


def prv_he(h):
    return h + 2 if h % 3 == 0 else h - 1


def bit_length(x):
    return x.bit_length()


def floordiv(a, b):
    return a // b    # Python's // is floor division for any sign


PREDICTOR_NAMES = ['ancestors', 'parallelograms', 'gate', 'spread', 'raw', 'fan']


def decode_lattice(d, qmax, vc, top=False):
    """§8.5.2: per axis the sorted lattice planes; with top an
    axis of two or more planes has its last plane first, as qmax minus it."""
    lattice_count, lattice_gap = SIntModel(6), SIntModel(6)
    lattice = [[], [], []]
    for a in range(3):
        n = lattice_count.decode(d)
        if n < 0 or n > qmax + 1 or n > vc:
            reject('geometry: lattice count')
        end = qmax + 1
        last = []
        if top and n >= 2:
            end = qmax - lattice_gap.decode(d)
            if end < 0 or end > qmax or d.truncated():
                reject('geometry: lattice top plane')
            last = [end]
            n -= 1
        prev = -1
        for _ in range(n):
            x = prev + 1 + lattice_gap.decode(d)
            if x <= prev or x >= end or d.truncated():
                reject('geometry: lattice plane')
            lattice[a].append(x)
            prev = x
        lattice[a] += last
    return lattice


def decode_geometry_raw(payload, vc, qbits, top=False):
    """§8.5.10: the lattice planes, then each coordinate as
    equiprobable bits: a plane index where its axis has planes, else the grid value."""
    d = RangeDecoder(payload[1:])
    qmax = (1 << qbits) - 1
    lattice = decode_lattice(d, qmax, vc, top)
    nbits = []
    for L in lattice:
        if not L:
            nbits.append(qbits)
        else:
            k = 0
            while (1 << k) < len(L):
                k += 1
            nbits.append(k)
    q = [[0, 0, 0] for _ in range(vc)]
    for v in range(vc):
        for a in range(3):
            x = d.direct(nbits[a])
            if lattice[a]:
                if x >= len(lattice[a]):
                    reject('geometry: plane index')
                x = lattice[a][x]
            q[v][a] = x
        if v % 4096 == 0 and d.truncated():
            reject('geometry: truncated')
    if d.truncated():
        reject('geometry: truncated')
    ginfo = {'predictor': 'raw', 'K': 0, 'lambda': [], 'alpha': [4096, 4096, 4096],
             'lattice_planes': [len(l) for l in lattice], 'overrun': d.overrun,
             'no_triangle': 0, 'anchored': 0, 'on_plane': 0}
    return q, ginfo


class BitReader:
    """§8.5.11: bits most significant first; reading past the end is corrupt."""
    def __init__(self, data, what='geometry'):
        self.data = data
        self.what = what
        self.pos = 0                                      # in bits

    def read(self, n):
        v = 0
        for _ in range(n):
            byte = self.pos >> 3
            if byte >= len(self.data):
                reject(self.what + ': table-coded bit stream is truncated')
            v = (v << 1) | ((self.data[byte] >> (7 - (self.pos & 7))) & 1)
            self.pos += 1
        return v


def read_tables(payload, pos, contexts=210, map_bytes=27, what='geometry'):
    """§8.5.11: bit stream length, used-context map, code lengths; returns
    ({context: {(length, code word): symbol}}, BitReader, offset of the range-coded stream).
    The geometry residuals have 210 contexts and a 27-byte map; the run values
    of §8.3.1 8 contexts and a 1-byte map."""
    if len(payload) < pos + 4 + map_bytes:
        reject(what + ': table block truncated')
    nbytes = struct.unpack_from('<I', payload, pos)[0]
    used = [c for c in range(8 * map_bytes) if payload[pos + 4 + (c >> 3)] >> (c & 7) & 1]
    p = pos + 4 + map_bytes
    tables = {}
    for c in used:
        if c >= contexts:
            reject(what + ': table for a context that does not exist')
        if p >= len(payload):
            reject(what + ': table block truncated')
        S = payload[p]
        p += 1
        if not 1 <= S <= 63:
            reject(what + ': table symbol count')
        if p + (S + 1) // 2 > len(payload):
            reject(what + ': table block truncated')
        lengths = []
        for j in range((S + 1) // 2):
            lengths += [payload[p + j] >> 4, payload[p + j] & 15]
        p += (S + 1) // 2
        if S % 2 and lengths[S]:
            reject(what + ': table padding nibble')
        lengths = lengths[:S]
        if max(lengths) > 11:
            reject(what + ': code length above 11')
        kraft = sum(1 << (11 - l) for l in lengths if l)
        if kraft == 0 or kraft > 2048:
            reject(what + ': table is empty or over-subscribed')
        code, words = 0, {}                                  # canonical: by length, then symbol
        for l in range(1, 12):
            for sym in range(S):
                if lengths[sym] == l:
                    words[(l, code)] = sym
                    code += 1
            code <<= 1
        tables[c] = words
    if nbytes > len(payload) - p:
        reject(what + ': table-coded bit stream longer than the section')
    return tables, BitReader(payload[p:p + nbytes], what), p + nbytes


def table_residual(tables, bits, c, what='geometry'):
    """§8.5.11: one residual (or run value, §8.3.1) of context c."""
    if c not in tables:
        reject(what + ': residual in a context without a table')
    words = tables[c]
    word, length = 0, 0
    while (length, word) not in words:
        if length == 11:
            reject(what + ': code word in no table')
        word = (word << 1) | bits.read(1)
        length += 1
    sym = words[(length, word)]
    if sym <= 6:
        return sym - 3
    n = (sym - 7) // 2 + 3                                   # bit length of |r|
    mag = (1 << (n - 1)) | bits.read(n - 1)
    return -mag if (sym - 7) & 1 else mag


class RansResiduals:
    """§8.5.11: the geometry residuals through static frequency tables and two
    interleaved rANS states; the bits below a symbol in a bit stream of their own."""
    def __init__(self, rans, raw):
        if len(rans) < 8:
            reject('geometry: rANS stream too short')
        self.x = list(struct.unpack_from('<2I', rans, 0))
        if min(self.x) < (1 << 16):
            reject('geometry: rANS state below 2^16')
        self.s = rans
        self.pos = 8
        self.turn = 0
        self.bits = BitReader(raw, 'geometry')
        self.tables = {}

    def read_tables(self, d):
        used, same = probs(1), probs(1)
        count, top_model = UIntModel(2), UIntModel(2)
        exponent = [[BitTree(4) for _ in range(13)] for _ in range(13)]
        above = []
        for c in range(210):
            if d.bit(used, 0) == 0:
                continue
            if above and d.bit(same, 0) == 1:            # the previous table
                self.tables[c] = above
                continue
            S = count.decode(d) + 1                      # INVALID + 1 is above 231 too
            top = top_model.decode(d)
            if S > 231 or top >= S:
                reject('geometry: residual table symbol count or implied symbol')
            f = [0] * S
            prev = 0
            for s in range(S):
                if s == top:
                    continue
                up = min(above[s].bit_length(), 12) if s < len(above) else 0
                e = exponent[prev][up].decode(d)
                if e > 12:
                    reject('geometry: residual table frequency')
                if e >= 2:
                    m = min(e - 1, 2)
                    f[s] = ((1 << m) | d.direct(m)) << (e - 1 - m)
                else:
                    f[s] = e
                prev = e
            if sum(f) >= 4096:
                reject('geometry: residual table frequencies sum above 4095')
            if d.truncated():
                reject('geometry: residual tables truncated')
            f[top] = 4096 - sum(f)
            self.tables[c] = f
            above = f

    def residual(self, c):
        if c not in self.tables:
            reject('geometry: residual in a context without a table')
        f = self.tables[c]
        x = self.x[self.turn]
        slot = x & 4095
        s, start = 0, 0
        while start + f[s] <= slot:
            start += f[s]
            s += 1
        x = f[s] * (x >> 12) + slot - start
        if x < (1 << 16):
            if self.pos + 2 > len(self.s):
                reject('geometry: rANS stream is truncated')
            x = (x << 16) | self.s[self.pos] | (self.s[self.pos + 1] << 8)
            self.pos += 2
        self.x[self.turn] = x
        self.turn ^= 1
        if s <= 14:
            return s - 7
        m = s - 15
        n = m // 8 + 4                                   # bit length of |r|
        mag = ((4 | (m & 3)) << (n - 3)) | self.bits.read(n - 3)
        return -mag if (m >> 2) & 1 else mag

    def finish(self):
        if self.x != [1 << 16, 1 << 16]:
            reject('geometry: rANS states do not end at 2^16')


def decode_geometry(payload, layout, qbits, trace=None):
    vc = layout['vertex_count']
    tri, twin, ids, vparent = layout['tri'], layout['twin'], layout['id'], layout['vparent']
    H = len(tri)
    qmax = (1 << qbits) - 1
    # §8.5.1 header
    if len(payload) < 1:
        reject('geometry: empty')
    predictor = payload[0]
    default_weights = False
    tangent = False
    mix = False
    planes_from_top = False  # bit 4; `top` in code_vertex is the largest residual so far
    tables = None            # bit 3: the rANS-coded residuals of §8.5.11
    table_flag = False
    if predictor & 0x08:                                            # §8.5.1 bit 3: tables
        predictor &= 0xF7
        table_flag = True
    if predictor & 0x10:                                            # §8.5.1 bit 4: top
        predictor &= 0xEF
        planes_from_top = True
    if predictor & 0x20:                                            # §8.5.1 bit 5: mix
        predictor &= 0xDF
        mix = True
        if (predictor & 0x3F) > 3 and (predictor & 0x3F) != 5:
            reject('geometry: predictor without residual models to mix')
    if predictor in (0x41, 0x42, 0x43, 0x45, 0xC1, 0xC2, 0xC3, 0xC5):  # §8.5.1 bit 6: tangent
        predictor &= 0xBF
        tangent = True
    if predictor & 0x80 and predictor != 0x80:                       # §8.5.1 bit 7: default weights
        predictor &= 0x7F
        default_weights = True
        if predictor > 3 and predictor != 5:
            reject('geometry: predictor without weights')
    if predictor > 5:
        reject('geometry: predictor')
    if table_flag and (predictor == 4 or mix):
        reject('geometry: tables with the raw predictor or with mixing')
    if predictor == 4:                                               # §8.5.10 raw
        return decode_geometry_raw(payload, layout['vertex_count'], qbits, planes_from_top)
    pos = 1
    K = 0
    lam = []
    if predictor == 0:
        if len(payload) < 2:
            reject('geometry: K missing')
        K = payload[1]
        if not 1 <= K <= 4:
            reject('geometry: K')
        if len(payload) < 2 + 4 * K:
            reject('geometry: lambdas missing')
        lam = list(struct.unpack_from('<%di' % K, payload, 2))
        for x in lam:
            if x < -(1 << 24) or x > (1 << 24):
                reject('geometry: lambda range')
        pos = 2 + 4 * K
    alpha = [4096, 4096, 4096]
    if predictor != 0 and not default_weights:
        if len(payload) < 7:
            reject('geometry: weights missing')
        alpha = list(struct.unpack_from('<3h', payload, 1))
        pos = 7
    beta = [4096, 4096]
    if tangent:                                                      # §8.5.1
        if len(payload) < pos + 4:
            reject('geometry: tangent weights missing')
        beta = list(struct.unpack_from('<2H', payload, pos))
        if beta[0] > 8192 or beta[1] > 8192:
            reject('geometry: tangent weight range')
        pos += 4
    if table_flag:                                                   # §8.5.11
        streams = []
        for what in ('residual tables', 'rANS stream', 'residual bit stream'):
            if len(payload) < pos + 4 or len(payload) < pos + 4 + struct.unpack_from('<I', payload, pos)[0]:
                reject('geometry: %s cut off' % what)
            n = struct.unpack_from('<I', payload, pos)[0]
            streams.append(payload[pos + 4:pos + 4 + n])
            pos += 4 + n
        tables = RansResiduals(streams[1], streams[2])
        tables.read_tables(RangeDecoder(streams[0]))
    d = RangeDecoder(payload[pos:])
    # §8.2 models
    residual = [[[SIntModel(6) for _ in range(14)] for _ in range(5)] for _ in range(3)]
    on = [probs(3) for _ in range(3)]
    index = [[[SIntModel(6) for _ in range(14)] for _ in range(3)] for _ in range(3)]
    has_anchor = probs(1)
    anchor_gap = UIntModel(2)
    if mix:                                                          # §8.1.1
        residual2 = [[[SIntModel(6) for _ in range(14)] for _ in range(5)] for _ in range(3)]
        mixw = [[mix_weights() for _ in range(8)] for _ in range(3)]
    lattice = decode_lattice(d, qmax, vc, planes_from_top)
    q = [[0, 0, 0] for _ in range(vc)]
    act = [UNKNOWN] * vc
    st = {'last': [(qmax + 1) // 2] * 3, 'last_act': 0, 'prev_act': 0}
    stats = {'no_triangle': 0, 'anchored': 0, 'on_plane': 0}

    def nearest(L, p):
        # the first index j with L[j] >= p
        lo, hi = 0, len(L)
        while lo < hi:
            mid = (lo + hi) // 2
            if L[mid] < p:
                lo = mid + 1
            else:
                hi = mid
        j = lo
        if j == len(L) or (j > 0 and p - L[j - 1] <= L[j] - p):
            j = j - 1 if j > 0 else 0
        return j

    # §8.5.3
    def code_vertex(v, pred, cls, activity, spread=None, normal=None, tset=0):
        sm = 0
        top = 0
        n_on = 0
        order = (0, 1, 2)
        kn = None                                            # the axis nearest the normal
        res = [0, 0, 0]
        if normal is not None:                               # the tangent step
            kn = 0
            for a in (1, 2):
                if abs(normal[a]) > abs(normal[kn]):
                    kn = a
            if normal[kn] == 0:
                kn = None
            else:
                order = tuple(a for a in range(3) if a != kn) + (kn,)
        for i in range(3):
            a = order[i]
            if spread is not None:                           # predictor 3, 2+ parallelograms
                ctx = bit_length(spread[a])
            else:
                ctx = activity if i == 0 else (activity + bit_length(top) + 1) // 2
            ctx = min(ctx, 13)
            p = min(max(pred[a], 0), qmax)
            if a == kn:                                      # through the tangent plane
                b, c = order[0], order[1]
                sg = 1 if normal[kn] > 0 else -1
                num = -sg * (normal[b] * res[b] + normal[c] * res[c])
                p = min(max(pred[a] + div_round(beta[tset] * num, 4096 * sg * normal[kn]), 0), qmax)
            coded = False
            L = lattice[a]
            if L:
                j = nearest(L, p)
                if d.bit(on[a], n_on) == 1:
                    dd = index[a][n_on][ctx].decode(d)
                    k = j + dd
                    if k < 0 or k >= len(L):
                        reject('geometry: plane index')
                    x = L[k]
                    stats['on_plane'] += 1
                    n_on += 1
                    coded = True
            if not coded:
                if mix:                                      # §8.1.1: two models mixed
                    ctx2 = min(bit_length(top) if i else activity if spread is not None else st['prev_act'], 13)
                    r = decode_mixed_sint(d, residual[i][cls][ctx], residual2[i][cls][ctx2], mixw[i][min(ctx, 7)])
                elif tables is not None:                     # §8.5.11: the context's table
                    r = tables.residual((i * 5 + cls) * 14 + ctx)
                else:
                    r = residual[i][cls][ctx].decode(d)      # by coding position i (= a without a normal)
                x = p + r
                if x < 0 or x > qmax:
                    reject('geometry: coordinate outside the grid')
            q[v][a] = x
            res[a] = x - min(max(pred[a], 0), qmax)          # from the clamped prediction before the step
            e = abs(x - p)
            sm += e
            top = max(top, e)
        act[v] = min(bit_length(sm), 254)
        st['prev_act'] = act[v]
        if trace is not None:
            trace.append('v%d pred=%s cls=%d act_in=%d%s -> q=%s act=%d' % (
                v, list(pred), cls, activity,
                ' normal=%s set=%d' % (list(normal), tset) if normal is not None else '', q[v], act[v]))

    def point(v, pred, cls, activity, spread=None, normal=None, tset=0):
        code_vertex(v, pred, cls, activity, spread, normal, tset)
        st['last'] = list(q[v])
        st['last_act'] = act[v]

    def known(p):
        v = ids[p]
        return v if v != NONE and act[v] != UNKNOWN else NONE

    def fan(h0):
        h = h0
        while True:
            yield h
            h = nxt_he(twin[h])
            if h == h0:
                return

    def div_round(s, n):
        return floordiv(2 * s + n, 2 * n)

    # §8.5.4: a normal at c from the triangles (c, u, w), (u, w) in T
    def tangent_normal(c, T):
        if len(T) == 0 or len(T) > 4096:
            return None
        n = [0, 0, 0]
        for u, w in T:
            d1 = [q[u][a] - c[a] for a in range(3)]
            d2 = [q[w][a] - c[a] for a in range(3)]
            if any(abs(x) >= 1 << 20 for x in d1 + d2):
                return None
            n[0] += d1[1] * d2[2] - d1[2] * d2[1]
            n[1] += d1[2] * d2[0] - d1[0] * d2[2]
            n[2] += d1[0] * d2[1] - d1[1] * d2[0]
        sh = max(0, bit_length(max(abs(n[0]), abs(n[1]), abs(n[2]))) - 16)
        return [x >> sh if x >= 0 else -((-x) >> sh) for x in n]

    # §8.5.4
    def predict(h0, multi):
        para = [0, 0, 0]
        nb = [0, 0, 0]
        lo = [0, 0, 0]                 # per axis the smallest and largest single parallelogram
        hi = [0, 0, 0]
        cnt = {'npara': 0, 'nnb': 0, 'actsum': 0}
        T = []                         # the pairs (u, w) found decoded

        def neighbour(u):
            for a in range(3):
                nb[a] += q[u][a]
            cnt['nnb'] += 1
            cnt['actsum'] += act[u]

        def visit(h):
            u = known(tri[nxt_he(h)])
            if u == NONE:
                return
            neighbour(u)
            w = known(tri[prv_he(h)])
            if w == NONE:
                return
            T.append((u, w))
            o = known(tri[prv_he(twin[nxt_he(h)])])
            if o == NONE:
                return
            for a in range(3):
                x = q[u][a] + q[w][a] - q[o][a]
                para[a] += x
                lo[a] = min(lo[a], x) if cnt['npara'] else x
                hi[a] = max(hi[a], x) if cnt['npara'] else x
            cnt['npara'] += 1

        if multi:
            for h in fan(h0):
                visit(h)
        else:
            visit(h0)
            w = known(tri[prv_he(h0)])
            if w != NONE and cnt['npara'] == 0:
                neighbour(w)
        npara, nnb = cnt['npara'], cnt['nnb']
        if npara > 0:
            cls = 1 + min(npara, 3)
            pred = []
            for a in range(3):
                P = div_round(para[a], npara)
                N = div_round(nb[a], nnb)
                pred.append(N + floordiv(alpha[cls - 2] * (P - N) + 2048, 4096))
        elif nnb > 0:
            pred = [div_round(nb[a], nnb) for a in range(3)]
            cls = 1
        else:
            pred = list(st['last'])
            cls = 0
        activity = (cnt['actsum'] + nnb // 2) // nnb if nnb > 0 else st['last_act']
        spread = [hi[a] - lo[a] for a in range(3)] if predictor in (3, 5) and npara >= 2 else None
        normal = tangent_normal(pred, T) if tangent and npara > 0 else None
        return pred, cls, activity, spread, normal        # set 0

    # first_he[v] = the smallest h with id(tri[h]) == v (§8.5.6, §8.5.7), built once
    first_he_cache = []

    def first_half_edges():
        if not first_he_cache:
            first_he_cache.extend([NONE] * vc)
            for h in range(H - 1, -1, -1):
                x = ids[tri[h]]
                if x != NONE:
                    first_he_cache[x] = h
        return first_he_cache

    # §8.5.7
    def anchor_normal(A):                                    # §8.5.7
        h0 = first_half_edges()[A]
        if h0 == NONE:
            return None
        T = []
        for h in fan(h0):
            u = known(tri[nxt_he(h)])
            w = known(tri[prv_he(h)])
            if u != NONE and w != NONE:
                T.append((u, w))
        return tangent_normal(q[A], T)

    def on_no_triangle():
        prev_anchor = 0
        for v in range(vc):
            if act[v] != UNKNOWN:
                continue
            stats['no_triangle'] += 1
            if d.bit(has_anchor, 0) == 1:
                gap = anchor_gap.decode(d)
                if gap == INVALID or prev_anchor + gap >= vc:
                    reject('geometry: anchor out of range')
                anchor = prev_anchor + gap
                if act[anchor] == UNKNOWN:
                    reject('geometry: anchor not decoded')
                prev_anchor = anchor
                stats['anchored'] += 1
                pred = list(q[anchor])
                normal = anchor_normal(anchor) if tangent else None
            else:
                pred = list(st['last'])
                normal = None
            point(v, pred, 0, st['last_act'], None, normal, 1)
            if v % 4096 == 0 and d.truncated():
                reject('geometry: truncated')

    if predictor in (2, 5):                                  # §8.5.5
        for h0 in range(H):
            p = tri[h0]
            if ids[p] == NONE or act[ids[p]] != UNKNOWN:
                continue
            point(ids[p], *predict(h0, predictor == 5))
            if h0 % 4096 == 0 and d.truncated():
                reject('geometry: truncated')
        on_no_triangle()
    elif predictor in (1, 3):                                # §8.5.6
        first_he = first_half_edges()
        npara = [0] * vc
        nnb = [0] * vc
        prio = [0] * vc
        buckets = [[] for _ in range(16)]
        heads = [0] * 16

        def priority(x):
            return 4 * min(npara[x], 3) + min(nnb[x], 3)

        def bump(x):
            pr = priority(x)
            if pr != prio[x]:
                prio[x] = pr
                buckets[pr].append(x)

        def update_counts(v):
            for h in fan(first_he[v]):
                pu = tri[nxt_he(h)]
                pw = tri[prv_he(h)]
                u = known(pu)
                w = known(pw)
                if u == NONE and ids[pu] != NONE:
                    x = ids[pu]
                    nnb[x] = min(nnb[x] + 1, 255)
                    if w != NONE and known(tri[prv_he(twin[prv_he(h)])]) != NONE:
                        npara[x] = min(npara[x] + 1, 255)
                    bump(x)
                if w == NONE and ids[pw] != NONE and u != NONE and known(tri[prv_he(twin[h])]) != NONE:
                    x = ids[pw]
                    npara[x] = min(npara[x] + 1, 255)
                    bump(x)
                if u != NONE and w != NONE:
                    px = tri[prv_he(twin[nxt_he(h)])]
                    if ids[px] != NONE and known(px) == NONE:
                        x = ids[px]
                        npara[x] = min(npara[x] + 1, 255)
                        bump(x)

        scan = 0
        while True:
            v = NONE
            for b in range(15, 0, -1):
                bk = buckets[b]
                while heads[b] < len(bk):
                    x = bk[heads[b]]
                    heads[b] += 1
                    if act[x] == UNKNOWN and prio[x] == b:
                        v = x
                        break
                if v != NONE:
                    break
            if v == NONE:
                while scan < H and (ids[tri[scan]] == NONE or act[ids[tri[scan]]] != UNKNOWN):
                    scan += 1
                if scan == H:
                    break
                v = ids[tri[scan]]
            point(v, *predict(first_he[v], True))
            update_counts(v)
            if v % 4096 == 0 and d.truncated():
                reject('geometry: truncated')
        on_no_triangle()
    else:                                                    # §8.5.8
        for v in range(vc):
            if vparent[v] != NONE and vparent[v] >= v:
                reject('geometry: parent after child')
        root = [(qmax + 1) // 2] * 3
        for v in range(vc):
            anc = []
            x = vparent[v]
            while x != NONE and len(anc) < K:
                anc.append(x)
                x = vparent[x]
            dd = len(anc)
            if dd == 0:
                pred, cls, activity = list(root), 0, 0
            else:
                activity = act[anc[0]]
                if dd < K:
                    pred, cls = list(q[anc[0]]), 1
                else:
                    pred = [floordiv(sum(lam[i] * q[anc[i]][a] for i in range(K)) + (1 << 15), 1 << 16)
                            for a in range(3)]
                    cls = 2
            code_vertex(v, pred, cls, activity)
            if dd == 0:
                root = list(q[v])
            if v % 4096 == 0 and d.truncated():
                reject('geometry: truncated')
    if d.truncated():                                        # §8.5.9
        reject('geometry: truncated')
    if tables is not None:
        tables.finish()
    ginfo = {'predictor': PREDICTOR_NAMES[predictor], 'K': K, 'lambda': lam, 'alpha': alpha,
             'tangent': tangent, 'beta': beta if tangent else None,
             'lattice_planes': [len(l) for l in lattice], 'overrun': d.overrun}
    ginfo.update(stats)
    return q, ginfo


# ---------------------------------------------------------------- §8.12 attributes

KIND_NAMES = ('generic', 'normal', 'color', 'texcoord')
DOMAIN_NAMES = ('vertex', 'face', 'corner')
TYPE_NAMES = ('f32', 'u8', 'u16', 'i32')
MAX_ATTRIBUTES = 64


class AttrHeader:
    """One attribute header (§8.12): name (bytes), kind, domain, type, components,
    quant (0 exact, 1 grid, 2 octahedral), bits, and for quant 1 origin[] and extent;
    per_vertex: a corner attribute coded per vertex (its predictor byte's bit 4)."""

    per_vertex = False
    recent = False

    def description(self):
        return (self.name, self.kind, self.domain, self.type, self.components)

    def ints(self):
        """Integers per value: 2 for octahedral, else the components."""
        return 2 if self.quant == 2 else self.components

    def in_range(self, x):
        if self.quant == 0:
            return -(1 << 30) <= x <= (1 << 30)
        return 0 <= x < (1 << self.bits)


COMMON_NAMES = (b'normal', b'texcoord', b'color', b'texcoord0', b'texcoord1', b'TANGENT', b'JOINTS_0',
                b'WEIGHTS_0', b'_gltf_group', b'_gltf_primitive')     # §8.12: names 0 .. 9


def read_attribute_header(buf, p):
    end = len(buf)
    h = AttrHeader()
    n, p = read_varint(buf, p, end)
    if n < len(COMMON_NAMES):
        h.name = COMMON_NAMES[n]
    else:
        n -= len(COMMON_NAMES)
        if n > 1024:
            reject('attributes: bad attribute name length')
        if n > end - p:
            reject('attributes: truncated attribute header')
        h.name = bytes(buf[p:p + n])
        p += n
    if end - p < 2:
        reject('attributes: truncated attribute header')
    layout, coding = buf[p], buf[p + 1]
    p += 2
    h.kind, h.domain, h.type, h.components = layout & 3, layout >> 2 & 3, layout >> 4 & 3, (layout >> 6) + 1
    h.quant, h.bits = coding & 3, coding >> 2
    if h.domain > 2 or h.quant > 2 or h.bits > 24:
        reject('attributes: bad attribute header')
    if (h.quant == 0) != (h.bits == 0):
        reject('attributes: bad quantization bits')
    if (h.type == 0) == (h.quant == 0):
        reject('attributes: an f32 attribute coded as exact integers' if h.quant == 0 else
               'attributes: an integer attribute not coded as exact integers')
    if h.quant == 2 and h.components != 3:
        reject('attributes: octahedral needs 3 components')
    if (h.kind == 1 and h.components != 3) or (h.kind == 3 and h.components != 2) or \
            (h.kind == 2 and h.components < 3):
        reject('attributes: components do not fit the kind')
    h.origin = []
    h.extent = 0.0
    if h.quant == 1:
        if end - p < 1:
            reject('attributes: truncated attribute header')
        grid = buf[p]
        p += 1
        axis = grid & 3
        if axis >= h.components or grid >> 7 or grid >> (2 + h.components) & ((1 << (4 - h.components)) - 1):
            reject('attributes: bad grid byte')
        values = []
        for bit in [2 + c for c in range(h.components)] + [6]:
            if grid >> bit & 1:                              # short: an i8, the value times 64
                if end - p < 1:
                    reject('attributes: truncated grid')
                values.append(struct.unpack_from('<b', buf, p)[0] / 64.0)
                p += 1
            else:
                if end - p < 4:
                    reject('attributes: truncated grid')
                values.append(struct.unpack_from('<f', buf, p)[0])
                p += 4
        h.origin, top = values[:-1], values[-1]
        if not all(math.isfinite(o) for o in h.origin):
            reject('attributes: bad grid origin')
        if not (math.isfinite(top) and top >= h.origin[axis]):
            reject('attributes: bad grid maximum')
        h.extent = top - h.origin[axis]
    return h, p


def sgn(x):
    return 1.0 if x >= 0 else -1.0          # sgn 0 = +1 (also for -0.0)


def octahedral_ints(x, y, z, bits):
    """The encoder's octahedral mapping of direction (x, y, z) (binary64), §8.12."""
    s = abs(x) + abs(y) + abs(z)
    if not s > 0:
        x, y, z = 0.0, 0.0, 1.0
    else:
        x, y, z = x / s, y / s, z / s
    if z < 0:
        x, y = (1 - abs(y)) * sgn(x), (1 - abs(x)) * sgn(y)
    m = float((1 << bits) - 1)
    u = int(math.floor((x * 0.5 + 0.5) * m + 0.5))
    v = int(math.floor((y * 0.5 + 0.5) * m + 0.5))
    top = (1 << bits) - 1
    if v == 0 or v == top:
        u = min(u, top - u)
    if u == 0 or u == top:
        v = min(v, top - v)
    return [u, v]


def octahedral_value(u, v, bits):
    m = float((1 << bits) - 1)
    x = u / m * 2 - 1
    y = v / m * 2 - 1
    z = 1 - abs(x) - abs(y)
    if z < 0:
        x, y = (1 - abs(y)) * sgn(x), (1 - abs(x)) * sgn(y)
    n = math.sqrt(x * x + y * y + z * z)
    return [f32(x / n), f32(y / n), f32(z / n)]


def attribute_value(h, ints):
    """The floats of one value from its integers (§8.12, "Integers of a value")."""
    if h.quant == 2:
        return octahedral_value(ints[0], ints[1], h.bits)
    if h.quant == 0:
        return [f32(float(x)) for x in ints]
    step = h.extent / float((1 << h.bits) - 1) if h.extent > 0 else 0.0
    out = []
    for c in range(h.components):
        x = float(h.origin[c]) + float(ints[c]) * step
        v = f32(min(max(x, -FLT_MAX), FLT_MAX))
        while v - float(h.origin[c]) > h.extent:                 # §8.12: not past origin + extent
            v = f32_below(v)
        out.append(v)
    return out


def squared_distance(a, b):
    """The squared length of b - a (grid indices), summed x, y, z in binary64."""
    s = 0.0
    for k in range(3):
        d = float(b[k] - a[k])
        s += d * d
    return s


def geometry_normals(faces, rank, q, bits, weights=0):
    """§8.12 "Geometry normals": per own rank the octahedral integers of the
    summed fan cross products, or None where the sum is zero, and per own rank
    the stray (the residuals' class for predictors 1, 3, 4). Sums in face order,
    a face's fan summed first, then added to each of its corners times the
    corner's weight (weights 0: 1, by area; 1: 1 / the vector's length, by face;
    2: 1 / sqrt of the product of the corner's two squared edge lengths, by
    angle)."""
    n = len(q)
    sx, sy, sz = [0.0] * n, [0.0] * n, [0.0] * n
    for f in faces:
        k = len(f)
        if k < 3 or any(rank[c] == NONE for c in f):
            continue
        nx, ny, nz = fan_vector(f, rank, q)
        length = math.sqrt((nx * nx + ny * ny) + nz * nz)
        for i, c in enumerate(f):
            w = 1.0
            if weights == 1:
                w = 1 / length if length > 0 else 0.0
            elif weights == 2:
                pi = q[rank[c]]
                e = squared_distance(pi, q[rank[f[(i + 1) % k]]]) * squared_distance(pi, q[rank[f[(i - 1) % k]]])
                w = 1 / math.sqrt(e) if e > 0 else 0.0
            r = rank[c]
            sx[r] += nx * w
            sy[r] += ny * w
            sz[r] += nz * w
    out = [None] * n
    for r in range(n):
        if sx[r] != 0 or sy[r] != 0 or sz[r] != 0:
            out[r] = octahedral_ints(sx[r], sy[r], sz[r], bits)
    stray = [2] * n                     # §8.12 "the stray": 2 where there is no normal
    for r in range(n):
        if out[r] is not None:
            stray[r] = 0
    for f in faces:
        k = len(f)
        if k < 3 or any(rank[c] == NONE for c in f):
            continue
        vx, vy, vz = fan_vector(f, rank, q)
        vv = (vx * vx + vy * vy) + vz * vz
        if vv == 0:
            continue
        for c in f:
            r = rank[c]
            if out[r] is None:
                continue
            dot = (vx * sx[r] + vy * sy[r]) + vz * sz[r]
            nn = vv * ((sx[r] * sx[r] + sy[r] * sy[r]) + sz[r] * sz[r])
            cls = 0 if dot > 0 and 100000 * (dot * dot) >= 99998 * nn else \
                1 if dot > 0 and 10000 * (dot * dot) >= 9998 * nn else 2
            stray[r] = max(stray[r], cls)
    return out, stray


def fan_vector(f, rank, q):
    """§8.12 "Geometry normals": a face's vector, its fan's cross products summed."""
    p0 = q[rank[f[0]]]
    nx = ny = nz = 0.0
    for i in range(1, len(f) - 1):
        p1, p2 = q[rank[f[i]]], q[rank[f[i + 1]]]
        a0, a1, a2 = float(p1[0] - p0[0]), float(p1[1] - p0[1]), float(p1[2] - p0[2])
        b0, b1, b2 = float(p2[0] - p0[0]), float(p2[1] - p0[1]), float(p2[2] - p0[2])
        nx += a1 * b2 - a2 * b1
        ny += a2 * b0 - a0 * b2
        nz += a0 * b1 - a1 * b0
    return nx, ny, nz


class AttrModels:
    """The models of one attribute (§8.12), fresh per attribute."""

    def __init__(self):
        self.res = [[[SIntModel(4), SIntModel(4)] for _ in range(4)] for _ in range(3)]   # [cls][component][z]
        self.symbol = [UIntModel(2) for _ in range(6)]
        self.far = UIntModel(2)
        self.unused = UIntModel(2)
        self.imported = [UIntModel(2), UIntModel(2)]     # [the corner's vertex is a reference]
        self.import_id = SIntModel(4)
        self.recent_hit = [UIntModel(2), UIntModel(2)]   # [the previous vertex's value was a hit]
        self.recent_index = UIntModel(2)
        self.sibling_hit = [[UIntModel(2), UIntModel(2)] for _ in range(2)]   # [previous was a hit][> 1 value]
        self.sibling_index = UIntModel(2)
        self.transfer = UIntModel(2)                     # predictor 2 across a seam: the edge's turn
        self.last_zero = [1, 1, 1, 1]
        self.table = None                                # §8.12.1: (tables, bit reader, first context)


def faces_around(faces, n):
    """§8.12 "Faces around a vertex": per part vertex the (face, position) pairs
    of its corners, in face order, then position order."""
    out = [[] for _ in range(n)]
    for f, fa in enumerate(faces):
        for i, v in enumerate(fa):
            out[v].append((f, i))
    return out


def uv_place(pw, pa, pb, ua, ub, pc, uc, sigma):
    """§8.12 "Placement of w from (a, b)": binary64, in the order FORMAT.md gives
    (the integer differences are exact, so subtracting as integers first is the
    same as subtracting their binary64 values)."""
    ex, ey, ez = float(pb[0] - pa[0]), float(pb[1] - pa[1]), float(pb[2] - pa[2])
    l2 = ex * ex + ey * ey + ez * ez
    dx, dy = float(ub[0] - ua[0]), float(ub[1] - ua[1])
    if l2 == 0:
        return float(ua[0]), float(ua[1])
    wx, wy, wz = float(pw[0] - pa[0]), float(pw[1] - pa[1]), float(pw[2] - pa[2])
    t = (wx * ex + wy * ey + wz * ez) / l2
    px, py, pz = wx - t * ex, wy - t * ey, wz - t * ez
    hw = math.sqrt(px * px + py * py + pz * pz)
    if pc is not None:
        cx, cy, cz = float(pc[0] - pa[0]), float(pc[1] - pa[1]), float(pc[2] - pa[2])
        tc = (cx * ex + cy * ey + cz * ez) / l2
        qx, qy, qz = cx - tc * ex, cy - tc * ey, cz - tc * ez
        hc = math.sqrt(qx * qx + qy * qy + qz * qz)
        if hc > 0:
            mx = (float(uc[0] - ua[0]) - tc * dx) / hc
            my = (float(uc[1] - ua[1]) - tc * dy) / hc
            return ua[0] + t * dx - hw * mx, ua[1] + t * dy - hw * my
    h = hw / math.sqrt(l2) * sigma
    return ua[0] + t * dx - h * dy, ua[1] + t * dy + h * dx


def uv_orientation(uv):
    """The sign of the texture-space area (shoelace, exact integers) of a face's values."""
    k = len(uv)
    area = 0
    for i in range(k):
        a, b = uv[i], uv[(i + 1) % k]
        area += a[0] * b[1] - b[0] * a[1]
    area = (area + (1 << 63)) % (1 << 64) - (1 << 63)    # int64, wrapping as attributes.cpp's sum does
    return (area > 0) - (area < 0)


def round_to_grid(x, bits):
    r = math.floor(x + 0.5)
    top = (1 << bits) - 1
    return 0 if r < 0 else top if r > top else int(r)


class AttrWalk:
    """What the prediction of a value may look at: the attribute (header,
    predictor byte), the part (faces with part-local ids, rank: own rank per part
    vertex or NONE, q: own grid indices), the geometry normals (quant 2 only),
    the faces around each vertex and sigma (predictor 2), the values so far and,
    while coding a value, where it is."""

    def __init__(self, h, predictor, faces, rank, q, around):
        self.h, self.predictor, self.faces, self.rank, self.q = h, predictor, faces, rank, q
        weights = {3: 1, 4: 2}.get(predictor, 0)      # predictors 3 and 4: by face, by angle
        self.gnormal, self.stray = geometry_normals(faces, rank, q, h.bits, weights) if h.quant == 2 else (None, None)
        self.around = around            # predictor 2: faces_around()
        self.sigma = 1                  # predictor 2: the texture orientation so far
        self.miss = [0, 0]              # predictor 5: recent misses, affine and conformal
        self.placements = None          # predictor 5: this vertex's (affine, conformal)
        self.prev = [0] * h.ints()      # the previous value decoded (previous vertex / face / new or unused value)
        self.values = []                # integers of the values decoded so far (corner domain: the value list)
        self.alias = []                 # corner domain: per value, the earlier segment's value id it stands for, or None
        self.face_offsets = [0]         # corner domain: first corner of each face, and
        for f in faces:
            self.face_offsets.append(self.face_offsets[-1] + len(f))
        self.index = [None] * self.face_offsets[-1]     # each corner's value id once known
        self.visit = []                 # corner domain: the current face's visiting order
        self.cand = None                # corner domain: candidate value ids per part vertex

    def uv_triangles(self, f, i, known, across, sx=0.0, sy=0.0, conf=None):
        """§8.12 "Prediction at position i of face f": adds its placements to the
        running sum (sx, sy), side after side (the vertex domain carries one sum
        over all faces around the vertex, as attributes.cpp does: summing per
        face first could round differently), and to `conf` (a list of two sums,
        vertex domain) the same placements made without c (conformal).
        Returns (sx, sy, count)."""
        fa = self.faces[f]
        k = len(fa)
        rank, q = self.rank, self.q
        w = fa[i]
        count = 0
        if k < 3 or rank[w] == NONE:
            return sx, sy, 0
        for side in range(2 if k > 3 else 1):
            ia, ib = ((i + 1) % k, (i + 2) % k) if side == 0 else ((i + k - 2) % k, (i + k - 1) % k)
            a, b = fa[ia], fa[ib]
            if a == w or b == w or a == b or rank[a] == NONE or rank[b] == NONE:
                continue
            ua, ub = known(ia), known(ib)
            if ua is None or ub is None:
                continue
            pc = uc = None
            for F, ja in self.around[a]:
                kf = len(self.faces[F])
                if F == f or kf < 3:
                    continue
                fc = self.faces[F]
                if fc[(ja + 1) % kf] == b:
                    jb, jc = (ja + 1) % kf, (ja + 2) % kf
                elif fc[(ja + kf - 1) % kf] == b:
                    jb, jc = (ja + kf - 1) % kf, (ja + kf - 2) % kf
                else:
                    continue
                cv = fc[jc]
                if cv == w or cv == a or cv == b or rank[cv] == NONE:
                    continue
                uc = across(F, ja, jb, jc, ia, ib)
                if uc is not None:
                    pc = q[rank[cv]]
                    break
            x, y = uv_place(q[rank[w]], q[rank[a]], q[rank[b]], ua, ub, pc, uc, self.sigma)
            sx += x
            sy += y
            if conf is not None:
                if pc is not None:
                    x, y = uv_place(q[rank[w]], q[rank[a]], q[rank[b]], ua, ub, None, None, self.sigma)
                conf[0] += x
                conf[1] += y
            count += 1
        return sx, sy, count

    def update_sigma(self, uv):
        o = uv_orientation(uv)
        if o != 0:
            self.sigma = o


def corner_visit_order(walk, g):
    """The order in which the corners of face g are visited (positions in the
    face), §8.12: with predictor 2, first the positions whose vertex has
    candidates when the face is reached, then the others; else face order."""
    fa = walk.faces[g]
    if walk.predictor == 2:
        cand = walk.cand
        order = [i for i in range(len(fa)) if cand[fa[i]]] + [i for i in range(len(fa)) if not cand[fa[i]]]
    else:
        order = list(range(len(fa)))
    walk.visit = order
    return order


def predict_value(walk, item):
    """The prediction of one value and its class (§8.12). item: ('vertex', own
    rank, part vertex), ('face', part face), ('corner', corner index k, part
    vertex w, face g, position i in the face) for a new corner value (walk.index
    holds the value ids of the corners visited so far), or ('unused',) for a
    value no corner uses. Returns (integers, cls)."""
    h = walk.h
    if item[0] == 'vertex':
        r, v = item[1], item[2]
        if walk.predictor in (1, 3, 4):
            if walk.gnormal[r] is None:
                return list(walk.prev), 2
            return list(walk.gnormal[r]) + walk.prev[2:], walk.stray[r]
        if walk.predictor in (2, 5):
            rank, vals = walk.rank, walk.values
            sx = sy = 0.0
            conf = [0.0, 0.0]
            count = 0
            for f, i in walk.around[v]:
                fa = walk.faces[f]

                def known(j, fa=fa):
                    rj = rank[fa[j]]
                    return vals[rj] if rj < r else None

                def across(F, ja, jb, jc, ia, ib):
                    rc = rank[walk.faces[F][jc]]
                    return vals[rc] if rc < r else None
                sx, sy, n = walk.uv_triangles(f, i, known, across, sx, sy, conf)
                count += n
            if count == 0 and walk.predictor == 5:
                sx, sy, count = pair_placement(walk, r, v)
                conf = [sx, sy]
            if count > 0 and walk.predictor == 5:            # "Affine or conformal"
                affine = [round_to_grid(sx / count, h.bits), round_to_grid(sy / count, h.bits)]
                conformal = [round_to_grid(conf[0] / count, h.bits), round_to_grid(conf[1] / count, h.bits)]
                walk.placements = (affine, conformal)
                return list(conformal if walk.miss[1] < walk.miss[0] else affine), min(count, 2)
            if count > 0:
                return [round_to_grid(sx / count, h.bits), round_to_grid(sy / count, h.bits)], min(count, 2)
            return seam_transfer(walk, r, v)
        if walk.predictor == 6:                              # §8.12 "Tangents"
            t = walk.tangent[r]
            return (list(walk.prev), 1) if t is None else (list(t), 0)
        return list(walk.prev), 0
    if item[0] == 'corner' and h.quant == 2:
        r = walk.rank[item[2]]
        if r != NONE and walk.gnormal[r] is not None:
            return list(walk.gnormal[r]), 0
    if item[0] == 'corner' and walk.predictor == 2:
        g, i = item[3], item[4]
        off, index, vals = walk.face_offsets, walk.index, walk.values

        def known(j):
            x = index[off[g] + j]
            return None if x is None else vals[x]

        def across(F, ja, jb, jc, ia, ib):
            if F >= g or index[off[F] + ja] != index[off[g] + ia] or index[off[F] + jb] != index[off[g] + ib]:
                return None
            return vals[index[off[F] + jc]]
        sx, sy, count = walk.uv_triangles(g, i, known, across)
        if count > 0:
            return [round_to_grid(sx / count, h.bits), round_to_grid(sy / count, h.bits)], min(count, 2)
        for j in walk.visit:
            x = index[off[g] + j]
            if x is not None:
                return list(vals[x]), 0
    return list(walk.prev), 0


def pair_placement(walk, r, v):
    """§8.12 "Placement from two neighbours": vertex v (own rank r) that no
    face's triangle places, from a = the first corner of its faces decoded
    before it and b = the first after a (v's faces, then a's) not on the line
    v-a, as the face (v, a, b) or (v, b, a), whichever agrees with v's normal.
    Returns (sx, sy, count)."""
    rank, q, faces = walk.rank, walk.q, walk.faces
    pw = q[r]

    def diff(x, y):
        return [float(x[0] - y[0]), float(x[1] - y[1]), float(x[2] - y[2])]

    def cross(e, g):
        return [e[1] * g[2] - e[2] * g[1], e[2] * g[0] - e[0] * g[2], e[0] * g[1] - e[1] * g[0]]
    n = [0.0, 0.0, 0.0]
    ra = rb = NONE
    cr = [0.0, 0.0, 0.0]

    def second(fa, ra):
        for c in fa:
            rc = rank[c]
            if c == v or rc == NONE or rc >= r or rc == ra:
                continue
            t = cross(diff(q[ra], pw), diff(q[rc], pw))
            if t != [0.0, 0.0, 0.0]:
                return rc, t
        return NONE, None
    for f, i in walk.around[v]:
        fa = faces[f]
        k = len(fa)
        if k < 3:
            continue
        rn, rp = rank[fa[(i + 1) % k]], rank[fa[(i + k - 1) % k]]
        if rn != NONE and rp != NONE:
            t = cross(diff(q[rn], pw), diff(q[rp], pw))
            n = [n[0] + t[0], n[1] + t[1], n[2] + t[2]]
        if rb != NONE:
            continue
        if ra == NONE:
            for m, c in enumerate(fa):
                rc = rank[c]
                if c != v and rc != NONE and rc < r:
                    ra = rc
                    rb, t = second(fa[m + 1:], ra)
                    break
        else:
            rb, t = second(fa, ra)
        if rb != NONE:
            cr = t
    if ra == NONE:
        return 0.0, 0.0, 0
    if rb == NONE:
        for f, _ in walk.around[walk.own_vertex[ra]]:
            rb, t = second(faces[f], ra)
            if rb != NONE:
                cr = t
                break
    if rb == NONE:
        return 0.0, 0.0, 0
    s = cr[0] * n[0] + cr[1] * n[1] + cr[2] * n[2]
    if s == 0:
        return 0.0, 0.0, 0
    if s < 0:
        ra, rb = rb, ra
    x, y = uv_place(pw, q[ra], q[rb], walk.values[ra], walk.values[rb], None, None, walk.sigma)
    return x, y, 1


def first_known_corner(walk, v, r, at=None):
    """§8.12 "Across a seam": the own rank of the first corner of v's faces
    (faces-around order, positions in order) decoded before rank r and, with
    `at`, at that grid position; NONE if none."""
    for f, _ in walk.around[v]:
        for c in walk.faces[f]:
            rc = walk.rank[c]
            if rc != NONE and rc < r and (at is None or tuple(walk.q[rc]) == at):
                return rc
    return NONE


def seam_transfer(walk, r, v):
    """§8.12 "Across a seam": predictor 2 without a placement in the vertex
    domain. Sets walk.transfer to (base, edge) when a transfer is found."""
    ra = first_known_corner(walk, v, r)
    if ra == NONE:
        return list(walk.prev), 0
    base = walk.values[ra]
    s, seen = walk.earlier[r], 0
    while s != NONE and seen < 32:
        rb = first_known_corner(walk, walk.own_vertex[s], r, tuple(walk.q[ra]))
        if rb != NONE:
            walk.transfer = (base, [walk.values[s][c] - walk.values[rb][c] for c in range(2)])
            return list(base), 1
        s, seen = walk.earlier[s], seen + 1
    return list(base), 0


def turned(edge, k):
    x, y = edge
    return [(x, y), (-x, y), (x, -y), (-x, -y), (-y, x), (y, -x), (y, x), (-y, -x)][k]


def decode_value(d, m, walk, item, segmented=False):
    """One value: per integer c a residual from res[cls][c][previous residual of c
    was 0]. A new corner value of a segment first says whether it stands for an
    earlier segment's value (and which)."""
    h = walk.h
    walk.transfer = None
    pred, cls = predict_value(walk, item)
    if walk.transfer is not None:                            # across a seam: the edge's turn
        k = m.transfer.decode(d)
        if k >= 8:
            reject('attributes: vertex values of %r out of range' % h.name)
        base, edge = walk.transfer
        top = (1 << h.bits) - 1
        pred = [min(max(base[c] + e, 0), top) for c, e in enumerate(turned(edge, k))]
    if segmented:
        g = m.imported[1 if walk.rank[item[2]] == NONE else 0].decode(d)
        if g > 1:
            reject('attributes: corner values of %r are invalid' % h.name)
        if g == 1:
            gid = m.last_import + m.import_id.decode(d)
            if not 0 <= gid < 0xFFFFFFFF:
                reject('attributes: corner values of %r are invalid' % h.name)
            m.last_import = gid
            walk.alias.append(gid)
        else:
            walk.alias.append(None)
    elif item[0] in ('corner', 'unused'):
        walk.alias.append(None)
    x = []
    top = (1 << h.bits) - 1
    for c in range(h.ints()):
        if m.table is not None:                              # §8.12.1
            tables, bits, base = m.table
            r = table_residual(tables, bits, base + 8 * cls + 2 * c + m.last_zero[c], 'attributes')
        else:
            r = m.res[cls][0 if h.shared else c][m.last_zero[c]].decode(d)
        v = pred[c] + r
        if h.quant == 2:                                     # octahedral: up to one square beyond an edge
            if not -top <= v <= 2 * top:
                reject('attributes: %s values of %r out of range' % (DOMAIN_NAMES[h.domain], h.name))
        elif not h.in_range(v):
            reject('attributes: %s values of %r out of range' % (DOMAIN_NAMES[h.domain], h.name))
        x.append(v)
        m.last_zero[c] = 1 if r == 0 else 0
    if h.quant == 2:                                         # folded back into the square
        a, b = x
        if a > top:
            a, b = 2 * top - a, top - b
        elif a < 0:
            a, b = -a, top - b
        if b > top:
            a, b = top - a, 2 * top - b
        elif b < 0:
            a, b = top - a, -b
        x = [a, b]
    walk.prev = x
    walk.values.append(x)
    return x


def predictor_allowed(h, pr):
    if pr == 0:
        return True
    if pr == 1:
        return h.domain == 0 and h.quant == 2
    if pr in (3, 4):
        return h.domain in (0, 2) and h.quant == 2
    if pr == 2:
        return h.domain != 1 and h.quant == 1 and h.components == 2
    if pr == 5:
        return h.domain == 0 and h.quant == 1 and h.components == 2
    if pr == 6:
        return h.domain == 0 and h.quant == 1 and h.components == 4
    return False


def corner_angle(e, f):
    """§8.12 "Tangents": A(e, f), a corner's angle through Abramowitz and
    Stegun 4.4.45 (no function a decoder could round differently)."""
    ee = (e[0] * e[0] + e[1] * e[1]) + e[2] * e[2]
    ff = (f[0] * f[0] + f[1] * f[1]) + f[2] * f[2]
    if not (ee > 0 and ff > 0):
        return 0.0
    c = ((e[0] * f[0] + e[1] * f[1]) + e[2] * f[2]) / math.sqrt(ee * ff)
    c = -1.0 if c < -1 else 1.0 if c > 1 else c
    x = abs(c)
    t = math.sqrt(1 - x) * (((-0.0187293 * x + 0.0742610) * x - 0.2121144) * x + 1.5707288)
    return t if c >= 0 else 3.141592653589793 - t


def tangent_add(d, n, g, s):
    """§8.12 "Tangents": add(d, n, g, s)."""
    k = (n[0] * d[0] + n[1] * d[1]) + n[2] * d[2]
    t = [d[c] - n[c] * k for c in range(3)]
    l2 = (t[0] * t[0] + t[1] * t[1]) + t[2] * t[2]
    if not l2 > 0:
        return
    f = g / math.sqrt(l2)
    for c in range(3):
        s[c] = s[c] + t[c] * f


def tangent_predictions(h, faces, rank, q, normals, uvs):
    """§8.12 "Tangents" (predictor 5): per own rank the predicted integers of
    tangent attribute h, or None. normals: the normal source's values (floats),
    uvs: the texcoord source's integers, both per own rank."""
    own = len(q)
    tu = [[0.0, 0.0, 0.0] for _ in range(own)]
    tv = [[0.0, 0.0, 0.0] for _ in range(own)]
    for f in faces:
        if len(f) < 3 or any(rank[c] == NONE for c in f):
            continue
        for i in range(1, len(f) - 1):
            r = [rank[f[0]], rank[f[i]], rank[f[i + 1]]]
            p = [[float(x) for x in q[j]] for j in r]
            u = [uvs[j] for j in r]
            s1, t1 = float(u[1][0]) - u[0][0], float(u[1][1]) - u[0][1]
            s2, t2 = float(u[2][0]) - u[0][0], float(u[2][1]) - u[0][1]
            det = s1 * t2 - s2 * t1
            if det == 0:
                continue
            sg = 1.0 if det > 0 else -1.0
            du, dv = [], []
            for a in range(3):
                e1, e2 = p[1][a] - p[0][a], p[2][a] - p[0][a]
                du.append((e1 * t2 - e2 * t1) * sg)
                dv.append((e2 * s1 - e1 * s2) * sg)
            for j in range(3):
                px, py, pz = p[j], p[(j + 1) % 3], p[(j + 2) % 3]
                g = corner_angle([py[a] - px[a] for a in range(3)], [pz[a] - px[a] for a in range(3)])
                n = [float(x) for x in normals[r[j]]]
                tangent_add(du, n, g, tu[r[j]])
                tangent_add(dv, n, g, tv[r[j]])
    step = h.extent / float((1 << h.bits) - 1) if h.extent > 0 else 0.0
    top = (1 << h.bits) - 1

    def grid(c, x):
        if not step > 0:
            return 0
        return min(max(math.floor((x - float(h.origin[c])) / step + 0.5), 0), top)
    out = []
    for r in range(own):
        n, u, v = [float(x) for x in normals[r]], tu[r], tv[r]
        d = (n[0] * u[0] + n[1] * u[1]) + n[2] * u[2]
        t = [u[c] - n[c] * d for c in range(3)]
        l2 = (t[0] * t[0] + t[1] * t[1]) + t[2] * t[2]
        if not l2 > 0:
            out.append(None)
            continue
        ln = math.sqrt(l2)
        b = [n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]]
        side = (b[0] * v[0] + b[1] * v[1]) + b[2] * v[2]
        out.append([grid(c, t[c] / ln) for c in range(3)] + [grid(3, -1.0 if side < 0 else 1.0)])
    return out


def as_vertex(h):
    """The header a corner attribute coded per vertex is decoded with (§8.12)."""
    c = copy.copy(h)
    c.domain = 0
    return c


def decode_attributes(payload, faces, glob, q, segmented=False):
    """§8.12 for one part. faces: the part's faces (part-local ids); glob: per part
    vertex NONE (own) or a reference; q: the own vertices' grid indices;
    segmented: a segment of a segmented file (new corner values may stand for an
    earlier segment's). Returns per attribute a dict: header, predictor, ints
    (integers of each value), values (floats of each value), indices (corner
    domain: per corner, else None), alias (corner domain: per value the earlier
    segment's value id it stands for, or None)."""
    if len(payload) == 0:
        return []
    A, p = read_varint(payload, 0, len(payload))
    if A > MAX_ATTRIBUTES:
        reject('attributes: bad attribute count')
    headers = []
    for _ in range(A):
        h, p = read_attribute_header(payload, p)
        headers.append(h)
    predictors, tabled = [], []
    for h in headers:
        if p >= len(payload):
            reject('attributes: bad predictor')
        pr = payload[p]
        p += 1
        t = pr & 0x08 != 0                                   # §8.12.1: table-coded residuals
        if t:
            pr &= ~0x08
        h.per_vertex = pr & 0x10 != 0                        # §8.12: a corner attribute coded per vertex
        if h.per_vertex:
            if h.domain != 2 or segmented:
                reject('attributes: per-vertex coding of an attribute that is not a corner attribute of a whole mesh')
            pr &= ~0x10
        h.recent = pr & 0x20 != 0                            # §8.12: recent values (vertex values only)
        if h.recent:
            if h.domain != 0 and not h.per_vertex:
                reject('attributes: %r names recent values but is not coded per vertex' % h.name)
            pr &= ~0x20
        h.siblings = pr & 0x40 != 0                          # §8.12: siblings' values (vertex values only)
        if h.siblings:
            if h.domain != 0 and not h.per_vertex:
                reject("attributes: %r names its siblings' values but is not coded per vertex" % h.name)
            pr &= ~0x40
        h.shared = pr & 0x80 != 0                            # §8.12: component 0's residual models for all
        pr &= ~0x80
        if not predictor_allowed(h if not h.per_vertex else as_vertex(h), pr):
            reject('attributes: bad predictor')
        predictors.append(pr)
        tabled.append(t)
    normal_src = texcoord_src = None                         # §8.12 "Tangents": the sources of predictor 6
    for j, h in enumerate(headers):
        if h.domain == 0 or h.per_vertex:
            if normal_src is None and h.quant == 2:
                normal_src = j
            if texcoord_src is None and h.kind == 3:
                texcoord_src = j
    if 6 in predictors and (normal_src is None or texcoord_src is None):
        reject('attributes: a tangent predicted without a normal and texture coordinates per vertex')
    tables = bits = None
    if any(tabled):                                          # §8.12.1
        tables, bits, p = read_tables(payload, p, 24 * A, 3 * A, 'attributes')
    coded = payload[p:]
    rank = [NONE] * len(glob)
    own_vertex = []
    for v in range(len(glob)):
        if glob[v] == NONE:
            rank[v] = len(own_vertex)
            own_vertex.append(v)
    own = len(own_vertex)
    around = faces_around(faces, len(glob)) if 2 in predictors or 5 in predictors else None
    d = RangeDecoder(coded)
    out = [None] * A
    order = [i for i in range(A) if predictors[i] != 6] + [i for i in range(A) if predictors[i] == 6]
    for ai in order:                                         # §8.12: predictor 6's values come last
        h, pr = headers[ai], predictors[ai]
        m = AttrModels()
        m.last_import = 0
        if tabled[ai]:                                       # §8.12.1: this attribute's contexts
            m.table = (tables, bits, 24 * ai)
        walk = AttrWalk(as_vertex(h) if h.per_vertex else h, pr, faces, rank, q, around)
        if pr == 6:
            walk.tangent = tangent_predictions(h, faces, rank, q, out[normal_src]['values'], out[texcoord_src]['ints'])
        indices = alias = None
        if h.per_vertex:                                     # each corner uses its vertex's value
            indices = [rank[c] for f in faces for c in f]
        if h.domain == 0 or h.per_vertex:                    # vertex: own vertices in output order
            recent, hit_before = [], 0
            earlier, last_at, sibling_before = [NONE] * own, {}, 0
            for r in range(own):                             # the previous own vertex at the same grid position
                key = tuple(q[r])
                earlier[r] = last_at.get(key, NONE)
                last_at[key] = r
            walk.earlier, walk.own_vertex = earlier, own_vertex
            for r in range(own):
                if h.siblings and earlier[r] != NONE:        # one of the siblings' values
                    distinct, s, seen = [], earlier[r], 0
                    while s != NONE and seen < 32:
                        if walk.values[s] not in distinct:
                            distinct.append(walk.values[s])
                        s, seen = earlier[s], seen + 1
                    hit = m.sibling_hit[sibling_before][1 if len(distinct) > 1 else 0].decode(d)
                    if hit > 1:
                        reject('attributes: vertex values of %r out of range' % h.name)
                    sibling_before = hit
                    if hit == 1:
                        j = m.sibling_index.decode(d) if len(distinct) > 1 else 0
                        if j >= len(distinct):
                            reject('attributes: vertex values of %r out of range' % h.name)
                        x = list(distinct[j])
                        walk.prev = x
                        walk.values.append(x)
                        if h.recent:
                            if x in recent:
                                recent.remove(x)
                            recent.insert(0, list(x))
                            del recent[64:]
                        if pr in (2, 5):
                            for f, _ in around[own_vertex[r]]:
                                fa = faces[f]
                                if len(fa) >= 3 and all(rank[c] <= r for c in fa):
                                    walk.update_sigma([walk.values[rank[c]] for c in fa])
                        continue
                walk.placements = None
                if h.recent:                                 # a recent value, or decoded as usual
                    if pr == 5:                              # the placements, for the misses below
                        predict_value(walk, ('vertex', r, own_vertex[r]))
                        walk.transfer = None
                    hit = m.recent_hit[hit_before].decode(d)
                    if hit > 1:
                        reject('attributes: vertex values of %r out of range' % h.name)
                    if hit == 1:
                        j = m.recent_index.decode(d)
                        if j >= len(recent):
                            reject('attributes: vertex values of %r out of range' % h.name)
                        x = list(recent[j])
                        walk.prev = x
                        walk.values.append(x)
                    else:
                        x = decode_value(d, m, walk, ('vertex', r, own_vertex[r]))
                    hit_before = hit
                    if x in recent:
                        recent.remove(x)
                    recent.insert(0, list(x))
                    del recent[64:]
                else:
                    x = decode_value(d, m, walk, ('vertex', r, own_vertex[r]))
                if walk.placements is not None:              # "Affine or conformal": the misses
                    for j, p in enumerate(walk.placements):
                        walk.miss[j] += abs(x[0] - p[0]) + abs(x[1] - p[1]) - (walk.miss[j] >> 3)
                if pr in (2, 5):                             # faces this vertex completes: sigma
                    for f, _ in around[own_vertex[r]]:
                        fa = faces[f]
                        if len(fa) >= 3 and all(rank[c] <= r for c in fa):
                            walk.update_sigma([walk.values[rank[c]] for c in fa])
        elif h.domain == 1:                                  # face: the part's faces in output order
            for f in range(len(faces)):
                decode_value(d, m, walk, ('face', f))
        else:                                                # corner
            cand = walk.cand = [[] for _ in range(len(glob))]
            indices = walk.index
            alias = walk.alias
            for g, f in enumerate(faces):
                for i in corner_visit_order(walk, g):
                    k = walk.face_offsets[g] + i
                    w = f[i]
                    nc = len(cand[w])
                    s = m.symbol[min(nc, 5)].decode(d)
                    have = len(walk.values)
                    if s < nc:
                        vid = cand[w][s]
                    elif s == nc:
                        vid = have
                        decode_value(d, m, walk, ('corner', k, w, g, i), segmented)
                    elif s == nc + 1:
                        back = m.far.decode(d)
                        if back >= have:
                            reject('attributes: corner values of %r are invalid' % h.name)
                        vid = have - 1 - back
                    else:
                        reject('attributes: corner values of %r are invalid' % h.name)
                    indices[k] = vid
                    if s >= nc and nc < 4 and vid not in cand[w]:
                        cand[w].append(vid)
                if pr == 2 and len(f) >= 3:
                    o = walk.face_offsets[g]
                    walk.update_sigma([walk.values[indices[o + i]] for i in range(len(f))])
            U = m.unused.decode(d)
            if U == INVALID or U > 2843 * (len(coded) + 8) + (8 * len(bits.data) if bits else 0):
                reject('attributes: corner values of %r are invalid' % h.name)
            for _ in range(U):
                decode_value(d, m, walk, ('unused',))
        if d.truncated():
            reject('attributes: stream is truncated')
        out[ai] = {'header': h, 'predictor': pr, 'ints': walk.values, 'indices': indices, 'alias': alias,
                   'values': [attribute_value(h, x) for x in walk.values]}
    return out


def join_attributes(parts):
    """§8.12 "Joining parts": parts = per part the list decode_attributes gave
    (dicts: header, ints, values, indices, alias). Vertex and face values are
    concatenated; corner value lists too, except the values that stand for an
    earlier segment's value (alias): those are dropped and their corners use
    that value; each part's other values take the next ids."""
    joined = None
    for part in parts:
        if joined is None:
            for a in part:
                if a['alias'] is not None and any(x is not None for x in a['alias']):
                    reject('the first segment names values of segments before it')
            joined = [dict(a, ints=list(a['ints']), values=list(a['values']), alias=None,
                           indices=None if a['indices'] is None else list(a['indices'])) for a in part]
            continue
        if len(part) != len(joined) or any(j['header'].description() != a['header'].description()
                                           for j, a in zip(joined, part)):
            reject('the segments disagree on the attributes they carry')
        for j, a in zip(joined, part):
            if a['indices'] is None:
                j['ints'].extend(a['ints'])
                j['values'].extend(a['values'])
                continue
            base = len(j['values'])
            ids = []
            for x, (ints, val, al) in enumerate(zip(a['ints'], a['values'], a['alias'])):
                if al is None:
                    ids.append(len(j['values']))
                    j['ints'].append(ints)
                    j['values'].append(val)
                elif al < base:
                    ids.append(al)
                else:
                    reject('attributes: %r: a value names value %d of the segments before, which hold %d'
                           % (a['header'].name, al, base))
            j['indices'].extend(ids[i] for i in a['indices'])
    return joined or []


# ---------------------------------------------------------------- §4.6 metadata

def read_metadata(payload):
    """§4.6 layout checks. Returns the entries as (key, value) byte strings."""
    n = len(payload)
    count, p = read_varint(payload, 0, n)
    if count > (n - p) // 3:
        reject('metadata: bad entry count')
    entries = []
    for i in range(count):
        if p >= n:
            reject('metadata: entry %d is truncated' % i)
        kl = payload[p]
        p += 1
        if kl == 0 or kl > n - p:
            reject('metadata: entry %d is truncated or has an empty key' % i)
        key = bytes(payload[p:p + kl])
        p += kl
        vl, p = read_varint(payload, p, n)
        if vl > n - p:
            reject('metadata: entry %d is truncated' % i)
        entries.append((key, bytes(payload[p:p + vl])))
        p += vl
    if p != n:
        reject('metadata: %d bytes after the last entry' % (n - p))
    if len(set(k for k, _ in entries)) != len(entries):
        reject('metadata: a key appears twice')
    return entries

# ---------------------------------------------------------------- §5 dequantization, §9 payload

def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]


def decode_part(streams, counts, bits, earlier, trace):
    """Steps 26-29 for the whole mesh or one segment (§4.5, §8.11, §8.12). Returns
    faces (part-local ids), q (per own vertex), glob (per part vertex: the
    output id of a reference, NONE for an own vertex), info, attributes (§8.12)."""
    vc, fc, cc, rc = counts
    s3, s4, s5, sr, s6, sa = streams
    if not (vc < 0x3FFFFFFF and cc < 0x3FFFFFFF and fc <= cc):
        reject('counts')                                             # step 26
    if rc > vc:
        reject('references')
    D = lambda b: 2843 * (len(b) + 8)
    split = D(sa) if len(s5) > 0 and s5[0] & 2 else 0                # §8.13
    if vc - rc > D(s6) // 3 + split or cc > 3 * D(s4) + 3 * D(s5):
        reject('stream budget')
    if sr is not None and vc > D(sr):
        reject('references budget')
    faces, layout, info = decode_connectivity(s3, s4, s5, vc, fc, cc)   # step 27
    glob = [NONE] * vc
    if sr is not None:                                               # §8.11
        ids, tri = layout['id'], layout['tri']
        ctx = [0] * vc
        for t in range(0, len(tri), 3):
            c = [ids[tri[t]], ids[tri[t + 1]], ids[tri[t + 2]]]
            hole = NONE in c
            for v in c:
                if v != NONE:
                    ctx[v] = max(ctx[v], 2 if hole else 1)
        d = RangeDecoder(sr)
        flag = [probs(2) for _ in range(3)]
        delta = SIntModel(2)
        prev_flag, prev, found = 0, 0, 0
        for v in range(vc):
            prev_flag = d.bit(flag[ctx[v]], prev_flag)
            if prev_flag:
                found += 1
                if found > rc:
                    reject('references: too many')
                g = prev + delta.decode(d)
                if not 0 <= g < earlier:
                    reject('references: not an earlier vertex')
                glob[v] = g
                prev = g
        if d.truncated():
            reject('references truncated')
        if found != rc:
            reject('references: count')
        rank = [NONE] * vc
        n = 0
        for v in range(vc):
            if glob[v] == NONE:
                rank[v] = n
                n += 1
        own = dict(layout)
        own['vertex_count'] = n
        own['id'] = [NONE if x == NONE else rank[x] for x in ids]
        vparent = [NONE] * n
        for v in range(vc):
            if rank[v] != NONE and layout['vparent'][v] != NONE:
                vparent[rank[v]] = rank[layout['vparent'][v]]
        own['vparent'] = vparent
        layout = own
    q, ginfo = decode_geometry(s6, layout, bits, trace)             # step 28
    info.update(ginfo)
    if not info['welded']:
        attrs = decode_attributes(sa, faces, glob, q, sr is not None)   # step 29
        return faces, q, glob, info, attrs
    if sr is not None:                                              # §8.13
        reject('a segment cannot be welded')
    n, p = read_varint(sa, 0, len(sa))
    if n > len(sa) - p or p + n >= len(sa):
        reject('split stream cut off')
    split, order, sa = sa[p:p + n], sa[p + n], sa[p + n + 1:]
    if order > 7 or order in (4, 5):
        reject('attribute order')
    ranks = b''
    if order & 4:                                                   # §8.13 points out: the rank stream
        if not sa:
            reject('rank stream cut off')
        m, p = read_varint(sa, 0, len(sa))
        if m == 0 or m > len(sa) - p:
            reject('rank stream empty or cut off')
        ranks, sa = sa[p:p + m], sa[p + m:]
    wfaces, walk_out, walk_point, orig = decode_split_layout(split, vc, info['points'], q, faces)
    lst = [w for w in range(len(walk_out)) if orig[w] == w]      # the originals, in the order coded
    if order & 1:
        lst.sort(key=lambda w: walk_out[w])
    rank = {w: k for k, w in enumerate(lst)}
    afaces = [[rank[orig[x]] for x in f] for f in wfaces]
    attrs = decode_attributes(sa, afaces, [NONE] * len(lst), [q[walk_point[w]] for w in lst])   # step 29
    out_q = [None] * vc
    for w in range(vc):
        out_q[walk_out[w]] = q[walk_point[w]]
    for a in attrs:
        if a['header'].per_vertex:                           # §8.13: the corners use their output vertices
            a['indices'] = [walk_out[x] for f in wfaces for x in f]
        if a['header'].domain == 0 or a['header'].per_vertex:
            for key in ('ints', 'values'):
                vals = [None] * vc
                for w in range(vc):
                    vals[walk_out[w]] = a[key][rank[orig[w]]]
                a[key] = vals
    out_faces = [[walk_out[x] for x in f] for f in wfaces]
    if order & 2:
        return points_out(out_faces, q, glob, info, attrs, walk_out, walk_point, ranks)
    return out_faces, out_q, glob, info, attrs


def point_value_ranks(ranks, point, attrs, n, faces):
    """§8.13 points out, the ranks: per output vertex whose point has more than
    one output vertex, its rank (model by its neighbours' ranks decoded so far:
    none, all 0, some above 0); then per corner attribute coded per vertex,
    per output vertex whose value (binary32 bits) another shares, its rank.
    Each below the count sharing it. All 0 when the stream is empty."""
    prank = [0] * n
    vrank = [None] * len(attrs)
    if not ranks:
        return prank, vrank
    d = RangeDecoder(ranks)
    pm, vm = [UIntModel(), UIntModel(), UIntModel()], UIntModel()
    share = {}
    for p in point:
        share[p] = share.get(p, 0) + 1
    nbr = [[] for _ in range(n)]                # output vertices an edge joins (either way)
    for f in faces:
        for i in range(len(f)):
            a, b = f[i], f[(i + 1) % len(f)]
            nbr[a].append(b)
            nbr[b].append(a)
    coded = [None] * n
    for o in range(n):
        if share[point[o]] > 1:
            say = 0
            for x in nbr[o]:
                if coded[x] is not None:
                    say = max(say, 2 if coded[x] > 0 else 1)
            prank[o] = pm[say].decode(d)
            if prank[o] >= share[point[o]]:
                reject('points-out rank')
            coded[o] = prank[o]
    for i, a in enumerate(attrs):
        if a['header'].domain != 2 or not a['header'].per_vertex:
            continue
        bits = [tuple(struct.pack('<f', x) for x in a['values'][o]) for o in range(n)]
        count = {}
        for b in bits:
            count[b] = count.get(b, 0) + 1
        vrank[i] = [0] * n
        for o in range(n):
            if count[bits[o]] > 1:
                vrank[i][o] = vm.decode(d)
                if vrank[i][o] >= count[bits[o]]:
                    reject('points-out value rank')
    if d.overrun > 8:
        reject('rank stream cut off')
    return prank, vrank


def points_out(faces, q, glob, info, attrs, walk_out, walk_point, ranks):
    """§8.13 points out: one output vertex per (point, rank), in that order; a
    vertex attribute takes the value of the vertex's first split vertex; a
    corner attribute coded per vertex gets its value list back: the corners in
    order, a value (binary32 bits) not listed yet listed with every rank the
    output vertices give it, ranks ascending."""
    n = len(walk_out)
    point = [0] * n
    for w, o in enumerate(walk_out):
        point[o] = walk_point[w]
    prank, vrank = point_value_ranks(ranks, point, attrs, n, faces)
    keys = sorted(set(zip(point, prank)))
    vid_of = {k: v for v, k in enumerate(keys)}
    vid = [vid_of[(point[o], prank[o])] for o in range(n)]
    first = [None] * len(keys)
    for o in range(n):
        if first[vid[o]] is None:
            first[vid[o]] = o
    for i, a in enumerate(attrs):
        h = a['header']
        if h.domain == 0:
            for key in ('ints', 'values'):
                a[key] = [a[key][first[v]] for v in range(len(keys))]
        elif h.per_vertex:
            r = vrank[i] or [0] * n
            bits = [tuple(struct.pack('<f', x) for x in a['values'][o]) for o in range(n)]
            have = {}
            for o in range(n):
                have.setdefault(bits[o], set()).add(r[o])
            base, ints, vals, idx = {}, [], [], []
            for o in a['indices']:
                lst = sorted(have[bits[o]])
                if bits[o] not in base:
                    base[bits[o]] = len(vals)
                    ints.extend([a['ints'][o]] * len(lst))
                    vals.extend([a['values'][o]] * len(lst))
                idx.append(base[bits[o]] + lst.index(r[o]))
            a['ints'], a['values'], a['indices'] = ints, vals, idx
    out_q = [q[p] for p, _ in keys]
    return [[vid[x] for x in f] for f in faces], out_q, [NONE] * len(keys), info, attrs


def split_reduced(v):
    """§8.13: a normal to 9 bits a component (floor shifts)."""
    m = max(abs(x) for x in v)
    s = 0
    while (m >> s) >= 512:
        s += 1
    return [x >> s for x in v]


def split_closeness(f, total):
    v = split_reduced(total)
    if not any(f) or not any(v):
        return 5
    dot = f[0] * v[0] + f[1] * v[1] + f[2] * v[2]
    if dot <= 0:
        return 4
    d2 = dot * dot * 1024
    n2 = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    for k, t in enumerate((1023, 1004, 829, 256)):
        if d2 >= t * n2:
            return k
    return 4


def decode_split_layout(stream, vertex_count, points, q, faces):
    """§8.13: the faces' points to walk vertices. Returns the faces (walk vertex
    ids), per walk vertex its output id and its point."""
    d = RangeDecoder(stream)
    fresh = probs(4 * 3 * 6 * 3 * 2 * 2)                   # fresh[nb][before][best][second's class][4 or more][linked]
    rank = [[[[UIntModel(), UIntModel()] for _ in range(2)] for _ in range(6)] for _ in range(6)]   # [best][second][4 or more][linked]
    copy_next = probs(3 * 3 * 6)                            # [next partner][prev kind][closeness]
    copy_prev = probs(3 * 2 * 6)                            # [prev partner][an edge to next][closeness]
    copy_other = probs(2 * 2 * 6)                           # [an edge][more than one][closeness]
    copy_rank = UIntModel()
    for p in faces:
        if any(x >= points for x in p):
            reject('split: a corner outside the points')
    on_faces = set(x for p in faces for x in p)
    joins = vertex_count < sum(len(p) for p in faces) + (points - len(on_faces))
    orig = []                                               # per walk vertex: the one whose values it has
    made = [[] for _ in range(points)]
    total = []                                              # per walk vertex: its faces' normals summed
    edge = {}
    linked = set()                                          # vertex pairs (lower first) an edge of a face so far joins
    out_faces = []
    for f in faces:
        n = len(f)
        ends_next = [0] * n                                 # per corner: across its edge to the next corner
        ends_prev = [0] * n                                 # and from the previous: 0 none, 1 same original, 2 not
        fn = [0, 0, 0]
        if n >= 3:
            d1 = [q[f[1]][a] - q[f[0]][a] for a in range(3)]
            d2 = [q[f[2]][a] - q[f[0]][a] for a in range(3)]
            fn = split_reduced([d1[1] * d2[2] - d1[2] * d2[1], d1[2] * d2[0] - d1[0] * d2[2],
                                d1[0] * d2[1] - d1[1] * d2[0]])
        v = [NONE] * n
        before = 0
        for i in range(n):
            p = f[i]
            if not made[p]:
                v[i] = len(total)
                total.append([0, 0, 0])
                orig.append(v[i])
                made[p].append(v[i])
                before = 1
            else:
                cand = []
                a = edge.get((f[(i + 1) % n], p))
                if a is not None:
                    cand.append(a[1])
                b = edge.get((p, f[(i + n - 1) % n]))
                if b is not None and b[0] not in cand:
                    cand.append(b[0])
                an = a[1] if a is not None else NONE            # the vertices across the two edges
                bp = b[0] if b is not None else NONE
                nb = 0 if not cand else 1 if (a is None or b is None) else 2 if len(cand) == 1 else 3
                for w in reversed(made[p]):
                    if w not in cand:
                        cand.append(w)
                ref = fn
                if not any(fn):                 # a face flat on the grid: its corners' vertices so far
                    ref = split_reduced([sum(total[v[j]][a] for j in range(i)) for a in range(3)])
                close = [split_closeness(ref, total[w]) for w in cand]
                link = [any((min(u, w), max(u, w)) in linked for u in v[:i]) for w in cand]
                order = sorted(range(len(cand)), key=lambda k: (0 if link[k] else 8) + close[k])    # stable
                cand = [cand[k] for k in order]
                best = close[order[0]]
                lf = 1 if link[order[0]] else 0
                second = close[order[1]] if len(cand) > 1 else 6
                sc = 0 if second == 6 else 1 if second <= 3 else 2
                many = 1 if len(cand) >= 4 else 0
                if joins:
                    before = 1 if d.bit(fresh, ((((nb * 3 + before) * 6 + best) * 3 + sc) * 2 + many) * 2 + lf) else 2
                else:
                    before = 1
                if before == 1:
                    v[i] = len(total)
                    o = v[i]
                    cn = orig[an] if an != NONE else NONE                        # the copy choice
                    cp = orig[bp] if bp != NONE and orig[bp] != cn else NONE
                    others = []
                    for w in cand:
                        if orig[w] not in (cn, cp) and orig[w] not in others:
                            others.append(orig[w])
                    pn = ends_prev[0] if i == n - 1 else 0                       # the other ends
                    pp = ends_next[i - 1] if i >= 1 else 0
                    kind = 0 if bp == NONE else 1 if an != NONE and orig[an] == orig[bp] else 2
                    cl = lambda w: split_closeness(ref, total[w]) if w != NONE else 5
                    if cn != NONE and d.bit(copy_next, (pn * 3 + kind) * 6 + cl(an)):
                        o = cn
                    elif cp != NONE and d.bit(copy_prev, (pp * 2 + (1 if cn != NONE else 0)) * 6 + cl(bp)):
                        o = cp
                    elif others:
                        edged = 1 if cn != NONE or cp != NONE else 0
                        if d.bit(copy_other, (edged * 2 + (1 if len(others) > 1 else 0)) * 6 + cl(others[0])):
                            r = copy_rank.decode(d) if len(others) > 1 else 0
                            if r >= len(others):
                                reject('split: copy rank')
                            o = others[r]
                    total.append([0, 0, 0])
                    orig.append(o)
                    made[p].append(v[i])
                else:
                    r = rank[best][second][many][lf].decode(d) if len(cand) > 1 else 0
                    if r >= len(cand):
                        reject('split: vertex rank')
                    v[i] = cand[r]
                ends_next[i] = 0 if an == NONE else 1 if orig[an] == orig[v[i]] else 2
                ends_prev[i] = 0 if bp == NONE else 1 if orig[bp] == orig[v[i]] else 2
            if len(total) > vertex_count or d.truncated():
                reject('split: too many vertices or truncated')
        for i in range(n):
            edge[(f[i], f[(i + 1) % n])] = (v[i], v[(i + 1) % n])
            linked.add((min(v[i], v[(i + 1) % n]), max(v[i], v[(i + 1) % n])))
            total[v[i]] = [total[v[i]][a] + fn[a] for a in range(3)]
        out_faces.append(v)
    walk_out = [NONE] * len(total)
    walk_point = [NONE] * len(total)
    nid = 0
    for p in range(points):
        if not made[p]:
            walk_out.append(nid)
            walk_point.append(p)
            orig.append(len(orig))
            nid += 1
        for w in made[p]:
            walk_out[w] = nid
            walk_point[w] = p
            nid += 1
    if len(walk_out) != vertex_count:
        reject('split: vertex count')
    return out_faces, walk_out, walk_point, orig


def read_streams(body, p, n, what):
    """§4.5, §4.7: n varint lengths from offset p, the n streams, then the rest."""
    lengths = []
    for _ in range(n):
        x, p = read_varint(body, p, len(body))
        lengths.append(x)
    streams = []
    for length in lengths:
        if length > len(body) - p:
            reject(what)
        streams.append(body[p:p + length])
        p += length
    streams.append(body[p:])
    return streams


def decode(data, trace=None):
    h, sections = read_container(data)
    vc, fc, cc = h['vertex_count'], h['face_count'], h['corner_count']
    if not (vc < 0x3FFFFFFF and cc < 0x3FFFFFFF and fc <= cc):
        reject('counts')                                             # §9 the parts
    if h['segment_count'] == 1:                                      # §4.7
        if 10 not in sections:
            reject('mesh section missing')
        s3, s4, s5, s6, rest = read_streams(sections[10], 0, 4, 'mesh section stream length')
        parts = [((s3, s4, s5, None, s6, rest), (vc, fc, cc, 0))]
    else:                                                            # §4.5
        parts = []
        for body in sections[7]:
            p = 0
            counts = []
            for _ in range(4):
                x, p = read_varint(body, p, len(body))
                counts.append(x)
            counts = tuple(counts)
            # the streams, then the rest: the segment's attribute payload (§8.12)
            streams = read_streams(body, p, 5, 'segment stream length')
            if counts[3] > counts[0]:
                reject('segment references')
            parts.append((tuple(streams), counts))
        if len(parts) != h['segment_count']:
            reject('segment count')
        if (sum(c[0] - c[3] for _, c in parts), sum(c[1] for _, c in parts),
                sum(c[2] for _, c in parts)) != (vc, fc, cc):
            reject('segment sums')
    faces, q = [], []
    info = None
    part_attrs = []
    for streams, counts in parts:
        pf, pq, glob, pinfo, pattrs = decode_part(streams, counts, h['bits'], len(q), trace)
        part_attrs.append(pattrs)
        base = len(q)
        out_id = []
        own = 0
        for g in glob:
            if g == NONE:
                out_id.append(base + own)
                own += 1
            else:
                out_id.append(g)
        faces.extend([[out_id[x] for x in f] for f in pf])
        q.extend(pq)
        if info is None:
            info = pinfo
        else:
            for k in ('components', 'jump_edges', 'virtual', 'stitches', 'side_faces', 'polygons'):
                info[k] += pinfo[k]
    info['segments'] = len(parts)
    vc = len(q)                          # §8.13 points out: the points, not the header's split vertices
    attrs = join_attributes(part_attrs)                              # step 29, §8.12
    info['metadata'] = read_metadata(sections[9]) if sections.get(9) is not None else None   # step 30, §4.6
    info['metadata_skipped'] = 9 in sections and sections[9] is None  # zstd-coded, no zstandard module
    positions = [[grid_coordinate(h, a, q[v][a]) for a in range(3)] for v in range(vc)]
    if h['exact'] is not None and sections.get(14) is not None:      # step 31, §5.1
        apply_exceptions(sections[14], positions)
    if sections.get(11) is not None:                                 # step 31, §4.9
        faces, q, positions = apply_order(sections[11], faces, q, positions, attrs)
    if sections[12]:                                                 # step 32, §4.8
        faces, q, positions = apply_refinements(h, sections[12], sections.get(13), faces, positions)
        info['batches'] = len(sections[12])
    return h, faces, q, positions, info, attrs


def grid_step(h):
    return h['extent'] / ((1 << h['bits']) - 1) if h['extent'] > 0 else 0.0


def grid_coordinate(h, a, qa):
    """§5 (and §5.1): the float32 coordinate of grid index qa on axis a."""
    if h['exact'] is not None:
        x = float(h['exact'][1][a] + qa) * h['exact'][0]
        return f32(min(max(x, -FLT_MAX), FLT_MAX))
    x = float(h['origin'][a]) + float(qa) * grid_step(h)
    x = min(max(x, -FLT_MAX), FLT_MAX)
    c = f32(x)
    while c - float(h['origin'][a]) > h['extent']:             # §5: not past origin + extent
        c = f32_below(c)
    return c


# ---------------------------------------------------------------- §4.8 progressive files

def max_decisions(nbytes):
    return 2843 * (nbytes + 8)                                       # §9 step 26's D(S)


class LevelMesh:
    """The level of detail the batches refine: faces, per vertex its grid
    index and the faces that use it."""

    def __init__(self, h, faces, positions):
        self.h = h
        self.faces = faces
        self.positions = positions
        step = grid_step(h)
        qmax = (1 << h['bits']) - 1
        self.q = []
        for pt in positions:
            g = []
            for a in range(3):
                x = math.floor((pt[a] - float(h['origin'][a])) / step + 0.5) if step > 0 else 0.0
                g.append(int(min(max(x, 0.0), qmax)))
            self.q.append(g)
        self.vf = [[] for _ in positions]
        for f, face in enumerate(faces):
            for c in face:
                if not self.vf[c] or self.vf[c][-1] != f:
                    self.vf[c].append(f)

    def ring(self, v):
        """v's closed fan (§4.8) listed from its least vertex, or its open
        fan from its first vertex then GHOST, or None."""
        fs = self.vf[v]
        if not fs:
            return None
        edges = []
        for f in fs:
            c = self.faces[f]
            if len(c) != 3:
                return None
            k = 0 if c[0] == v else 1 if c[1] == v else 2
            edges.append((c[(k + 1) % 3], c[(k + 2) % 3]))
        if any(a == v or b == v or a == b for a, b in edges):
            return None
        edges.sort()
        if any(edges[i][0] == edges[i - 1][0] for i in range(1, len(edges))):
            return None
        nxt = dict(edges)
        ends = set(b for _, b in edges)
        starts = [a for a, _ in edges if a not in ends]
        if len(starts) > 1 or (not starts and len(edges) < 3):
            return None
        ring = []
        at = starts[0] if starts else edges[0][0]
        for _ in edges:
            ring.append(at)
            if at not in nxt:
                return None
            at = nxt[at]
        if starts:
            ring.append(at)
        elif at != ring[0]:
            return None
        if len(set(ring)) != len(ring):
            return None
        return ring + [GHOST] if starts else ring

    def adjacent_to_marked(self, v, marked):
        return any(c < len(marked) and marked[c] for f in self.vf[v] for c in self.faces[f])

    def add_point(self, g):
        self.q.append(list(g))
        self.positions.append([grid_coordinate(self.h, a, g[a]) for a in range(3)])
        self.vf.append([])

    def split(self, v, ring, ia, dist, g):
        u = len(self.q)
        d = len(ring)
        self.add_point(g)
        keep = []
        for f in self.vf[v]:
            c = self.faces[f]
            k = 0 if c[0] == v else 1 if c[1] == v else 2
            first = ring.index(c[(k + 1) % 3]) if c[(k + 1) % 3] in ring else d
            if (first + d - ia) % d < dist:
                c[k] = u
                self.vf[u].append(f)
            else:
                keep.append(f)
        self.vf[v] = keep
        y, x = ring[ia], ring[(ia + dist) % d]
        for face in ([v, u, x], [v, y, u]):
            if GHOST in face:
                continue
            for w in face:
                self.vf[w].append(len(self.faces))
            self.faces.append(face)


GHOST = -1                      # §4.8: closes a border vertex's open fan


class BatchModels:
    def __init__(self):
        self.flag = probs(16)
        self.rank = [[UIntModel(2) for _ in range(4)] for _ in range(32)]
        self.dist = [UIntModel(2) for _ in range(32)]
        self.residual = [[SIntModel(3) for _ in range(3)] for _ in range(24)]
        self.border = [[SIntModel(3) for _ in range(3)] for _ in range(24)]


def plane_offset(level, qv, ring, nrm, order, e1, e2, qmax):
    """§4.8: the new vertex's offset on axis order[0] from the tangent plane."""
    top = abs(nrm[order[0]])
    if not top > 0:
        return 0
    _, ex = math.frexp(top)
    N = [math.floor(math.ldexp(nrm[a], 15 - ex) + 0.5) for a in range(3)]
    real = [r for r in ring if r != GHOST]
    dd = len(real)
    height = 0
    for a in range(3):
        c = (sum(level.q[r][a] for r in real) + dd // 2) // dd
        height += N[a] * (qv[a] - c)
    n0 = N[order[0]]
    t = height - 2 * (N[order[1]] * e1 + N[order[2]] * e2)
    mm = abs(n0)
    o = ((-t if n0 < 0 else t) + mm) // (2 * mm)
    return min(max(o, -qmax), qmax)


def distance(a, b):
    return math.sqrt(sum((float(a[k]) - float(b[k])) ** 2 for k in range(3)))


def arc_order(level, qv, ring, dist):
    """§4.8: the ring positions by the score of the arc of dist faces from each, best first."""
    dd = len(ring)
    length = [0.0 if r == GHOST else distance(level.q[r], qv) for r in ring]
    total = 0.0
    for i in range(dd):
        if ring[i] != GHOST:
            total += length[i]
    mean = total / sum(1 for r in ring if r != GHOST)
    inner = [1.5 * mean if ring[i] == GHOST else length[i] for i in range(dd)]
    end = [mean if ring[i] == GHOST else length[i] for i in range(dd)]
    prefix = [0.0]
    for j in range(2 * dd):
        prefix.append(prefix[-1] + inner[j % dd])
    score = []
    for ia in range(dd):
        y, x = ring[ia], ring[(ia + dist) % dd]
        if dist == 1:
            s = 0.5 * mean if GHOST in (y, x) else distance(level.q[y], level.q[x])
        else:
            s = prefix[ia + dist] - prefix[ia + 1]
        s -= 0.5 * end[ia]
        s -= 0.5 * end[(ia + dist) % dd]
        score.append(s)
    return sorted(range(dd), key=lambda i: (-score[i], i))


def decode_batch(payload, level, m):
    """§4.8: one refinement section's vertex splits, applied to level."""
    if len(payload) < 8:
        reject('refinement header')
    before, after = struct.unpack_from('<2f', payload, 0)
    if not all(math.isfinite(e) and e >= 0 for e in (before, after)):
        reject('refinement error')
    splits, p = read_varint(payload, 8, len(payload))
    border_count, p = read_varint(payload, p, len(payload))
    if border_count > splits:
        reject('border split count')
    stream = payload[p:]
    n = len(level.q)
    if splits == 0 or splits > n or splits > max_decisions(len(stream)) // 4:
        reject('split count')
    d = RangeDecoder(stream)
    marked = [0] * n
    ones = 0
    for i in range(n):                                               # 1. flags
        if ones >= splits:
            break
        if level.adjacent_to_marked(i, marked):
            continue
        ring = level.ring(i)
        if ring is None:
            continue
        b = d.bit(m.flag, min(len(ring), 10) - 3 + (8 if ring[-1] == GHOST else 0))
        marked[i] = b
        ones += b
        if d.truncated():
            reject('refinement flags truncated')
    if ones != splits:
        reject('fewer split flags than the split count')
    qmax = (1 << level.h['bits']) - 1
    for v in range(n):                                               # 2. splits
        if not marked[v]:
            continue
        ring = level.ring(v)
        dd = len(ring)
        ctx = min(dd, 15) + (16 if ring[-1] == GHOST else 0)
        dist = m.dist[ctx].decode(d) + 1
        if not 1 <= dist < dd:
            reject('split ring neighbours')
        rank = m.rank[ctx][min(dist, 4) - 1].decode(d)
        if rank >= dd:
            reject('split ring neighbours')
        ia = arc_order(level, level.q[v], ring, dist)[rank]
        arc = [ring[(ia + k) % dd] for k in range(dist + 1)]
        border = arc[0] == GHOST or arc[-1] == GHOST
        if border:                       # u on v's border: v and its border neighbour
            known = [arc[1] if arc[0] == GHOST else arc[-2]]
        else:
            known = [r for r in arc if r != GHOST]
        qv = level.q[v]
        pred = []
        for a in range(3):
            total = qv[a] + sum(level.q[r][a] for r in known)
            pred.append((total + (len(known) + 1) // 2) // (len(known) + 1))
        span = max(abs(level.q[r][a] - qv[a]) for r in arc if r != GHOST for a in range(3))
        sc = min(bit_length(span), 23)
        nrm = [0.0, 0.0, 0.0]
        for i in range(dd):
            if GHOST in (ring[i], ring[(i + 1) % dd]):
                continue
            ra, rb = level.q[ring[i]], level.q[ring[(i + 1) % dd]]
            e1 = [float(ra[k]) - float(qv[k]) for k in range(3)]
            e2 = [float(rb[k]) - float(qv[k]) for k in range(3)]
            nrm[0] += e1[1] * e2[2] - e1[2] * e2[1]
            nrm[1] += e1[2] * e2[0] - e1[0] * e2[2]
            nrm[2] += e1[0] * e2[1] - e1[1] * e2[0]
        order = [0, 0, 0]
        for a in range(3):
            order[sum(1 for b in range(3) if abs(nrm[b]) > abs(nrm[a]) or (abs(nrm[b]) == abs(nrm[a]) and b < a))] = a
        g = [0, 0, 0]
        e = [0, 0, 0]
        models = m.border[sc] if border else m.residual[sc]
        for k in (1, 2, 0):
            e[k] = models[k].decode(d)
            off = plane_offset(level, qv, ring, nrm, order, e[1], e[2], qmax) if k == 0 and not border else 0
            x = pred[order[k]] + off + e[k]
            if not 0 <= x <= qmax:
                reject('a new vertex off the grid')
            g[order[k]] = x
        if d.truncated():
            reject('refinement splits truncated')
        level.split(v, ring, ia, dist, g)
        border_count -= 1 if border else 0
    if border_count != 0:
        reject('border split count')


def decode_loose(payload, level):
    """§4.8: the loose vertices, appended without faces, then the faces the
    levels left out."""
    count, p = read_varint(payload, 0, len(payload))
    nfaces, p = read_varint(payload, p, len(payload))
    stream = payload[p:]
    most = max_decisions(len(stream)) // 3
    if count + nfaces == 0 or count > most or nfaces > most or count + nfaces > most:
        reject('loose vertex or face count')
    d = RangeDecoder(stream)
    anchor_model = UIntModel(2)
    residual = [SIntModel(3) for _ in range(3)]
    qmax = (1 << level.h['bits']) - 1
    anchors = len(level.q)
    points = []
    anchor = 0
    for _ in range(count):
        anchor += anchor_model.decode(d)
        if anchor >= anchors:
            reject("a loose vertex's anchor")
        qa = level.q[anchor]
        nrm = [0, 0, 0]                  # the anchor's face normal, exact integers
        for f in level.vf[anchor]:
            c = [level.q[w] for w in level.faces[f][:3]]
            e1 = [c[1][k] - c[0][k] for k in range(3)]
            e2 = [c[2][k] - c[0][k] for k in range(3)]
            nrm[0] += e1[1] * e2[2] - e1[2] * e2[1]
            nrm[1] += e1[2] * e2[0] - e1[0] * e2[2]
            nrm[2] += e1[0] * e2[1] - e1[1] * e2[0]
        shift = max(0, max(bit_length(abs(x)) for x in nrm) - 16)
        nrm = [floordiv(x, 1 << shift) for x in nrm]
        order = [0, 0, 0]
        for a in range(3):
            order[sum(1 for b in range(3) if abs(nrm[b]) > abs(nrm[a]) or (abs(nrm[b]) == abs(nrm[a]) and b < a))] = a
        g = [0, 0, 0]
        e = [0, 0, 0]
        for k in (1, 2, 0):
            e[k] = residual[k].decode(d)
            off = 0
            n0 = nrm[order[0]]
            if k == 0 and n0 != 0:
                t = -(nrm[order[1]] * e[1] + nrm[order[2]] * e[2])
                off = floordiv(2 * (-t if n0 < 0 else t) + abs(n0), 2 * abs(n0))
                off = min(max(off, -qmax), qmax)
            g[order[k]] = qa[order[k]] + off + e[k]
            if not 0 <= g[order[k]] <= qmax:
                reject('a loose vertex off the grid')
        if d.truncated():
            reject('loose vertices truncated')
        points.append(g)
    for g in points:
        level.add_point(g)
    first, pick, far = UIntModel(2), [UIntModel(2), UIntModel(2)], [UIntModel(2), UIntModel(2)]
    n = len(level.q)
    a = 0
    for _ in range(nfaces):
        a += first.decode(d)
        if a >= n:
            reject('a left-out face corner')
        c = [a]
        for k in (1, 2):
            cand = set(w for f in level.vf[c[0]] for w in level.faces[f])
            if k == 2:
                cand |= set(w for f in level.vf[c[1]] for w in level.faces[f])
            cand = sorted(cand - set(c))
            x = pick[k - 1].decode(d)
            if x > 0:
                x = cand[x - 1] if x <= len(cand) else n
            else:
                x = a + 1 + far[k - 1].decode(d)
            if x >= n or x <= a or x in c:
                reject('a left-out face corner')
            c.append(x)
        if d.truncated():
            reject('left-out faces truncated')
        for w in c:
            level.vf[w].append(len(level.faces))
        level.faces.append(c)


def apply_refinements(h, batches, loose, faces, positions):
    level = LevelMesh(h, faces, positions)
    m = BatchModels()
    for payload in batches:
        decode_batch(payload, level, m)
    if loose is not None:
        decode_loose(loose, level)
    return level.faces, level.q, level.positions


# ---------------------------------------------------------------- §5.1 exceptions

def apply_exceptions(payload, positions):
    """§5.1: the coordinates the exact grid misses, as differences of bits in value order."""
    n = len(payload)
    count, p = read_varint(payload, 0, n)
    if count > 3 * len(positions) or count > (n - p) // 2:
        reject('exceptions: more exceptions than coordinates or bytes')
    at = 0
    for _ in range(count):
        gap, p = read_varint(payload, p, n)
        z, p = read_varint(payload, p, n)
        if gap >= 3 * len(positions) - at:
            reject('exceptions: a coordinate past the last vertex')
        at += gap
        d = (z >> 1) ^ -(z & 1)
        v, a = divmod(at, 3)
        u = struct.unpack('<I', struct.pack('<f', positions[v][a]))[0]
        o = u if u < 0x80000000 else 0x7FFFFFFF - u
        o += d
        if not -(1 << 31) <= o <= 0x7FFFFFFF:
            reject('exceptions: a correction past the floats')
        u = o if o >= 0 else 0x7FFFFFFF - o
        positions[v][a] = struct.unpack('<f', struct.pack('<I', u))[0]
        at += 1
    if p != n:
        reject('exceptions: bytes after the last exception')


# ---------------------------------------------------------------- §4.8 the order section

SWEEP_AXES = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]


def ordered_bits(x):
    b = bits32(x)
    return (~b & 0xFFFFFFFF) if b & 0x80000000 else b | 0x80000000


def slab_of(x, e):
    """floor(x / 2^e), exact, clamped to -2^62 .. 2^62 - 1; NaN: 2^62."""
    if math.isnan(x):
        return 1 << 62
    q = math.ldexp(x, -e)
    if q >= 2.0 ** 62:
        return (1 << 62) - 1
    if q <= -2.0 ** 62:
        return -(1 << 62)
    return math.floor(q)


class Sweep:
    """§4.9: the items not taken yet in a given order (a Fenwick tree of 0/1)."""
    def __init__(self, positions, ax, e):
        self.init(sorted(range(len(positions)), key=lambda v: (slab_of(positions[v][ax[0]], e),
                                                               ordered_bits(positions[v][ax[1]]),
                                                               ordered_bits(positions[v][ax[2]]), v)))

    @classmethod
    def of_order(cls, order):
        s = cls.__new__(cls)
        s.init(order)
        return s

    def init(self, order):
        n = len(order)
        self.order = order
        self.at = [0] * n
        for i, v in enumerate(self.order):
            self.at[v] = i
        self.tree = [0] * (n + 1)
        for i in range(1, n + 1):
            self.tree[i] += 1
            up = i + (i & -i)
            if up <= n:
                self.tree[up] += self.tree[i]
        self.top = 1
        while self.top * 2 <= n:
            self.top *= 2

    def rank(self, v):
        r, i = 0, self.at[v]
        while i > 0:
            r += self.tree[i]
            i &= i - 1
        return r

    def take(self, v):
        i = self.at[v] + 1
        while i < len(self.tree):
            self.tree[i] -= 1
            i += i & -i

    def at_rank(self, r):
        i, step = 0, self.top
        while step:
            if i + step < len(self.tree) and self.tree[i + step] <= r:
                i += step
                r -= self.tree[i]
            step >>= 1
        return self.order[i]


def lattice_axes(positions):
    """§4.9: per vertex the one axis whose coordinate is on no lattice plane
    while the other two are (a plane: a value that at least 4 times the mean
    number of vertices per distinct value on that axis have), else 3."""
    vc = len(positions)
    on = [0] * vc
    for a in range(3):
        count = {}
        for p in positions:
            b = bits32(p[a])
            count[b] = count.get(b, 0) + 1
        for v, p in enumerate(positions):
            if count[bits32(p[a])] * len(count) >= 4 * vc:
                on[v] |= 1 << a
    return [next((a for a in range(3) if on[v] == 7 & ~(1 << a)), 3) for v in range(vc)]


def turn_context(c, k, prev, picked, axis, positions, detail):
    """§4.9: the turn context of triangle c picked (or not) at corner k."""
    ctx = 1 if picked else 0
    for s in range(3):
        x = c[(k + s) % 3]
        low = 0
        if detail:
            for a in range(3):
                v = positions[x][a]
                low = low * 2 + (1 if all(v <= positions[y][a] for y in c) else 0)
        ctx = (ctx << 6) | (axis[x] << 4) | (low << 1) | (1 if x in prev else 0)
    return ctx


def decode_order(payload, faces, positions):
    """§4.8: per input vertex its decoded vertex, per input face its decoded
    face and first corner."""
    vc, fc = len(positions), len(faces)
    inc = [[] for _ in range(vc)]
    for f, c in enumerate(faces):
        for x in c:
            if not inc[x] or inc[x][-1] != f:
                inc[x].append(f)
    nbr = [set() for _ in range(vc)]
    for c in faces:
        for k in range(len(c)):
            a, b = c[k], c[(k + 1) % len(c)]
            if a != b:
                nbr[a].add(b)
                nbr[b].add(a)
    nbr = [sorted(x) for x in nbr]
    d = RangeDecoder(payload)
    vertex_pick = [[UIntModel() for _ in range(5)] for _ in range(2)]
    window_pick = [[UIntModel() for _ in range(5)] for _ in range(2)]
    face_pick = [[UIntModel() for _ in range(5)] for _ in range(5)]
    turn = [UIntModel() for _ in range(2)]
    turn3 = {}
    vertex_jump, face_jump = SIntModel(), SIntModel()
    used = [False] * vc
    vertices, input_of, picks = [], [0] * vc, []
    axes, slab = d.direct(3), d.direct(8) - 128
    detail = d.direct(1)
    if axes > 5:
        reject('order section: sweep axes %d out of range' % axes)
    sweep = Sweep(positions, SWEEP_AXES[axes], slab)
    for i in range(vc):
        cand = []
        if i:
            p = vertices[-1]
            cand = [u for u in nbr[p] if not used[u]][:16]
            if i > 1 and len(cand) > 1:
                p2 = vertices[-2]
                key = []
                for c in cand:
                    dot = 0.0
                    for a in range(3):
                        dot += (positions[c][a] - positions[p][a]) * (positions[p][a] - positions[p2][a])
                    key.append((-dot if math.isfinite(dot) else math.inf, c))
                cand = [c for _, c in sorted(key)]
        last = 1 if i and picks[-1] else 0
        pick = vertex_pick[last][min(len(cand), 4)].decode(d) if cand else 0
        picks.append(pick)
        if pick > len(cand):
            reject('order section: vertex %d picks a candidate it does not have' % i)
        if pick:
            v = cand[pick - 1]
        else:
            r = (sweep.rank(vertices[-1]) if i else 0) + vertex_jump.decode(d)
            if not 0 <= r < vc - i:
                reject('order section: vertex %d jumps past the unused vertices' % i)
            v = sweep.at_rank(r)
        sweep.take(v)
        used[v] = True
        vertices.append(v)
        input_of[v] = i
        if d.truncated():
            reject('order section: cut off')
    fsweep_key = []
    for f, c in enumerate(faces):
        fsweep_key.append((min(sweep.at[x] for x in c), f))
    fsweep = Sweep.of_order([f for _, f in sorted(fsweep_key)])
    left = [0] * vc                        # per vertex: its unused faces
    for c in faces:
        for x in set(c):
            left[x] += 1
    taken = [False] * fc
    order, rot, new_faces, fpicks = [], [], [], []
    axis = lattice_axes(positions)
    for j in range(fc):
        cand = []                          # the window: corners of the last 16 faces
        for t in range(1, min(16, j) + 1):
            g, r = faces[order[j - t]], rot[j - t]
            for q in range(len(g)):
                x = g[(r + q) % len(g)]
                if len(cand) < 64 and left[x] and x not in cand:
                    cand.append(x)
        last = 1 if j and fpicks[-1] else 0
        pick = window_pick[last][min(len(cand), 4)].decode(d) if cand else 0
        fpicks.append(pick)
        if pick > len(cand):
            reject('order section: face %d picks a corner it does not have' % j)
        if pick:
            x = cand[pick - 1]
            prev = set(faces[order[-1]]) if j else set()
            first, later = [], []
            for f in inc[x]:
                if taken[f]:
                    continue
                shared = len(set(faces[f]) & prev)
                for k, y in enumerate(faces[f]):
                    if y == x:
                        (first if shared >= 2 else later).append((f, k))
            fcand = first + later
            if not fcand:
                reject('order section: face %d: no unused face at its corner' % j)
            q = face_pick[min(pick - 1, 4)][min(len(fcand), 4)].decode(d) if len(fcand) > 1 else 0
            if q >= len(fcand):
                reject('order section: face %d picks a face it does not have' % j)
            f, k = fcand[q]
        else:
            r = (fsweep.rank(order[-1]) if j else 0) + face_jump.decode(d)
            if not 0 <= r < fc - j:
                reject('order section: face %d jumps past the unused faces' % j)
            f, k = fsweep.at_rank(r), 0
        c = faces[f]
        if len(c) == 3:
            ctx = turn_context(c, k, set(faces[order[-1]]) if j else set(), pick, axis, positions, detail)
            t = turn3.setdefault(ctx, BitTree(2)).decode(d)
        else:
            t = turn[1 if pick else 0].decode(d) if len(c) > 1 else 0
        if t >= len(c):
            reject('order section: face %d turns past its corners' % j)
        taken[f] = True
        fsweep.take(f)
        for x in set(c):
            left[x] -= 1
        order.append(f)
        rot.append((k + t) % len(c))
        new_faces.append([input_of[c[(rot[-1] + q) % len(c)]] for q in range(len(c))])
        if d.truncated():
            reject('order section: cut off')
    return order, rot, vertices, new_faces


def apply_order(payload, faces, q, positions, attrs):
    """§4.8: the decoded mesh in the input's order."""
    order, rot, vertices, new_faces = decode_order(payload, faces, positions)
    start = [0]
    for c in faces:
        start.append(start[-1] + len(c))
    for a in attrs:
        dom = a['header'].domain
        if a['indices'] is not None:
            a['indices'] = [a['indices'][start[f] + (r + k) % len(faces[f])]
                            for f, r in zip(order, rot) for k in range(len(faces[f]))]
        elif dom == 0:
            a['ints'] = [a['ints'][v] for v in vertices]
            a['values'] = [a['values'][v] for v in vertices]
        elif dom == 1:
            a['ints'] = [a['ints'][f] for f in order]
            a['values'] = [a['values'][f] for f in order]
    return new_faces, [q[v] for v in vertices], [positions[v] for v in vertices]


# ---------------------------------------------------------------- comparison with `tsm decode` output

def read_ply(path):
    data = open(path, 'rb').read()
    end = data.index(b'end_header') + len(b'end_header')
    if data[end:end + 1] == b'\r':
        end += 1
    if data[end:end + 1] == b'\n':
        end += 1
    header = data[:end].decode('ascii').splitlines()
    fmt = None
    elements = []
    for line in header:
        w = line.split()
        if not w:
            continue
        if w[0] == 'format':
            fmt = w[1]
        elif w[0] == 'element':
            elements.append([w[1], int(w[2]), []])
        elif w[0] == 'property':
            elements[-1][2].append(w[1:])
    tmap = {'char': 'b', 'int8': 'b', 'uchar': 'B', 'uint8': 'B', 'short': 'h', 'int16': 'h', 'ushort': 'H',
            'uint16': 'H', 'int': 'i', 'int32': 'i', 'uint': 'I', 'uint32': 'I', 'float': 'f', 'float32': 'f',
            'double': 'd', 'float64': 'd'}
    verts, faces = [], []
    if fmt == 'ascii':
        toks = data[end:].split()
        ti = 0
        for name, count, props in elements:
            for _ in range(count):
                rec = []
                for pr in props:
                    if pr[0] == 'list':
                        k = int(toks[ti]); ti += 1
                        rec.append([int(t) for t in toks[ti:ti + k]]); ti += k
                    else:
                        rec.append(float(toks[ti]) if tmap[pr[0]] in 'fd' else int(toks[ti])); ti += 1
                if name == 'vertex':
                    verts.append([f32(x) for x in rec[:3]])
                elif name == 'face':
                    faces.append(rec[0])
    else:
        bo = '<' if fmt == 'binary_little_endian' else '>'
        pos = end
        for name, count, props in elements:
            for _ in range(count):
                rec = []
                for pr in props:
                    if pr[0] == 'list':
                        k = struct.unpack_from(bo + tmap[pr[1]], data, pos)[0]
                        pos += struct.calcsize(tmap[pr[1]])
                        t = tmap[pr[2]]
                        rec.append(list(struct.unpack_from(bo + str(k) + t, data, pos)))
                        pos += k * struct.calcsize(t)
                    else:
                        t = tmap[pr[0]]
                        rec.append(struct.unpack_from(bo + t, data, pos)[0])
                        pos += struct.calcsize(t)
                if name == 'vertex':
                    verts.append(rec[:3])
                elif name == 'face':
                    faces.append(rec[0])
    return verts, faces


def bits32(x):
    return struct.unpack('<I', struct.pack('<f', x))[0]


# ---------------------------------------------------------------- output as `tsm decode` writes it

class CannotWrite(Exception):
    pass


PLY_TYPE = {0: (b'float', '<f'), 1: (b'uchar', '<B'), 2: (b'ushort', '<H'), 3: (b'int', '<i')}
TYPE_RANGE = {1: (0, 255), 2: (0, 65535), 3: (-2147483648, 2147483647)}


def ply_scalar(h, x):
    return x if h.type == 0 else int(x)


def ply_bytes(positions, faces, attrs):
    """The binary PLY `tsm decode FILE.tsm -o OUT.ply` writes (io_ply.cpp,
    write_ply): positions as float x y z, faces as 'list uchar uint
    vertex_indices' ('list uint uint' when a face has more than 255 corners),
    then the attributes: vertex and face ones as scalar properties of their
    element (the first normal / colour / texcoord of a domain as nx ny nz /
    red green blue [alpha] / s t, others NAME or NAME_0 .. NAME_k-1), corner
    ones as face list properties after the face scalars ('texcoord', 'normal',
    'color' for the first of each kind, else the name) holding each corner's
    value; property types uchar / ushort / int / float by attribute type."""
    vnames = [b'x', b'y', b'z']
    fnames = [b'vertex_indices']
    first_done = set()
    vprops, fprops, cprops = [], [], []          # header lines
    vcols, fcols, clists = [], [], []            # (attribute, component) / (attribute, wide)
    for k, a in enumerate(attrs):
        h = a['header']
        if h.type != 0:
            lo, hi = TYPE_RANGE[h.type]
            for i, val in enumerate(a['values']):
                for x in val:
                    if not (lo <= x <= hi) or x != math.floor(x):
                        raise CannotWrite('attribute %d (%r): value %s does not fit type %s'
                                          % (k, h.name, x, PLY_TYPE[h.type][0].decode()))
        conventional = h.kind != 0 and (h.domain, h.kind) not in first_done
        if conventional:
            first_done.add((h.domain, h.kind))
        if h.domain == 2:
            names = [h.name if not conventional else {3: b'texcoord', 1: b'normal', 2: b'color'}[h.kind]]
        elif conventional and h.kind == 1:
            names = [b'nx', b'ny', b'nz']
        elif conventional and h.kind == 2:
            names = [b'red', b'green', b'blue'] + ([b'alpha'] if h.components == 4 else [])
        elif conventional and h.kind == 3:
            names = [b's', b't']
        elif h.components == 1:
            names = [h.name]
        else:
            names = [h.name + b'_' + str(c).encode() for c in range(h.components)]
        used = vnames if h.domain == 0 else fnames
        for n in names:
            if not n or any(c <= 0x20 or c >= 0x7f for c in n):
                raise CannotWrite('attribute %d (%r): not a PLY property name' % (k, h.name))
            if n in used:
                raise CannotWrite('attribute %d (%r): property %r taken' % (k, h.name, n))
            used.append(n)
        tname = PLY_TYPE[h.type][0]
        if h.domain == 2:
            wide = max([len(f) * h.components for f in faces] + [0]) > 255
            clists.append((a, wide))
            cprops.append(b'property list ' + (b'uint ' if wide else b'uchar ') + tname + b' ' + names[0] + b'\n')
        else:
            for c in range(h.components):
                (vcols if h.domain == 0 else fcols).append((a, c))
                (vprops if h.domain == 0 else fprops).append(b'property ' + tname + b' ' + names[c] + b'\n')
    wide_count = max([len(f) for f in faces] + [0]) > 255
    out = [b'ply\nformat binary_little_endian 1.0\ncomment written by tsm\n',
           b'element vertex %d\n' % len(positions), b'property float x\nproperty float y\nproperty float z\n']
    out += vprops
    out.append(b'element face %d\n' % len(faces))
    out.append(b'property list uint uint vertex_indices\n' if wide_count
               else b'property list uchar uint vertex_indices\n')
    out += fprops + cprops
    out.append(b'end_header\n')
    vfmt = '<3f' + ''.join(PLY_TYPE[a['header'].type][1][1] for a, _ in vcols)
    for v, pt in enumerate(positions):
        out.append(struct.pack(vfmt, *pt, *[ply_scalar(a['header'], a['values'][v][c]) for a, c in vcols]))
    corner = 0
    for fi, f in enumerate(faces):
        n = len(f)
        out.append(struct.pack('<I' if wide_count else '<B', n))
        out.append(struct.pack('<%dI' % n, *f))
        for a, c in fcols:
            out.append(struct.pack(PLY_TYPE[a['header'].type][1], ply_scalar(a['header'], a['values'][fi][c])))
        for a, wide in clists:
            h = a['header']
            out.append(struct.pack('<I' if wide else '<B', n * h.components))
            t = PLY_TYPE[h.type][1][1]
            vals = []
            for j in range(n):
                vals.extend(ply_scalar(h, x) for x in a['values'][a['indices'][corner + j]])
            out.append(struct.pack('<%d%s' % (len(vals), t), *vals))
        corner += n
    return b''.join(out)


def parse_f32(s):
    """The binary32 nearest to decimal text s (ties to even), as std::from_chars
    gives it: float() then f32 could round twice, so check the neighbours exactly."""
    x = f32(float(s))
    if not math.isfinite(x) or x == 0:
        return x                     # keeps the sign of a zero
    from fractions import Fraction
    exact = Fraction(s)
    u = bits32(x)
    key = u if u < 0x80000000 else -(u & 0x7FFFFFFF)
    best = None
    for k in (key - 1, key, key + 1):
        b = k if k >= 0 else (0x80000000 | -k)
        if b & 0x7F800000 == 0x7F800000:
            continue
        y = struct.unpack('<f', struct.pack('<I', b))[0]
        dist = abs(Fraction(y) - exact)
        cand = (dist, b & 1, y)
        if best is None or cand < best:
            best = cand
    return best[2]


def compare_obj(path, positions, faces, attrs):
    """Compares with `tsm decode FILE.tsm -o OUT.obj` (io_obj.cpp, write_obj): the
    first texcoord attribute (or a 3-component generic 'texcoord3') as the vt
    list, the first normal as the vn list, with the value list and the index of
    every corner (a vertex-domain one indexed by the vertex, a face-domain one by
    the face), the first vertex colour as v x y z r g b (u8 / u16 scaled to 0..1).
    Every float is compared by its bits. Returns a list of differences."""
    tex = nrm = col = None
    for a in attrs:
        if tex is None and a['header'].kind == 3:
            tex = a
    for a in attrs:
        h = a['header']
        if tex is None and h.kind == 0 and h.name == b'texcoord3' and h.components == 3:
            tex = a
    for a in attrs:
        h = a['header']
        if nrm is None and h.kind == 1:
            nrm = a
        if col is None and h.kind == 2 and h.domain == 0:
            col = a
    V, VT, VN, F = [], [], [], []
    for line in open(path, 'rb').read().decode('ascii').splitlines():
        w = line.split()
        if not w or w[0].startswith('#'):
            continue
        if w[0] in ('v', 'vt', 'vn'):
            {'v': V, 'vt': VT, 'vn': VN}[w[0]].append([parse_f32(t) for t in w[1:]])
        elif w[0] == 'f':
            F.append([[int(x) if x else None for x in t.split('/')] for t in w[1:]])
    diffs = []
    scale = 1.0
    if col is not None and col['header'].type in (1, 2):
        scale = 255.0 if col['header'].type == 1 else 65535.0
    exp_v = []
    for v, pt in enumerate(positions):
        row = list(pt)
        if col is not None:
            row += [x if scale == 1.0 else f32(x / scale) for x in col['values'][v][:3]]
        exp_v.append(row)

    def same_list(name, got, want):
        if len(got) != len(want):
            diffs.append('%s: %d entries vs %d' % (name, len(want), len(got)))
            return
        for i, (g, e) in enumerate(zip(got, want)):
            if [bits32(x) for x in g] != [bits32(x) for x in e]:
                diffs.append('%s %d: %s vs %s' % (name, i, e, g))
                return
    same_list('v', V, exp_v)
    same_list('vt', VT, tex['values'] if tex else [])
    same_list('vn', VN, nrm['values'] if nrm else [])

    def ref(a, c, f, v):
        d = a['header'].domain
        return v + 1 if d == 0 else f + 1 if d == 1 else a['indices'][c] + 1
    exp_f = []
    c = 0
    for fi, f in enumerate(faces):
        row = []
        for v in f:
            t = [v + 1]
            if tex or nrm:
                t.append(ref(tex, c, fi, v) if tex else None)
                if nrm:
                    t.append(ref(nrm, c, fi, v))
            row.append(t)
            c += 1
        exp_f.append(row)
    if F != exp_f:
        bad = next(i for i in range(min(len(F), len(exp_f)) + 1) if i >= min(len(F), len(exp_f)) or F[i] != exp_f[i])
        diffs.append('f: %d faces vs %d, first difference at face %d' % (len(exp_f), len(F), bad))
    return diffs


def dump_attributes(attrs):
    for k, a in enumerate(attrs):
        h = a['header']
        print('  attribute %d: %r kind %s domain %s type %s components %d quant %d bits %d%s predictor %d, '
              '%d values%s' % (k, h.name, KIND_NAMES[h.kind], DOMAIN_NAMES[h.domain], TYPE_NAMES[h.type],
                               h.components, h.quant, h.bits,
                               (' origin %s extent %r' % (h.origin, h.extent)) if h.quant == 1 else '',
                               a.get('predictor', 0), len(a['values']),
                               ', %d corners' % len(a['indices']) if a['indices'] is not None else ''))
        for i, (x, val) in enumerate(zip(a['ints'], a['values'])):
            print('    value %d: ints %s = %s' % (i, x, ' '.join(float(y).hex() for y in val)))
        if a['indices'] is not None:
            print('    indices: %s' % ' '.join(map(str, a['indices'])))


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    path = argv[1]
    trace = [] if '--trace' in argv else None
    try:
        h, faces, q, positions, info, attrs = decode(open(path, 'rb').read(), trace)
    except Corrupt as e:
        print('%s: corrupt_data: %s' % (path, e))
        return 2
    except Unsupported as e:
        print('%s: unsupported: %s' % (path, e))
        return 2
    print('%s: %d vertices, %d faces, q=%d; predictor %s%s, lattice planes %s (%d coordinates on planes), '
          '%d vertices on no triangle (%d anchored), geometry overrun %d; '
          'components %d, jump edges %d, virtual %d, stitches %d, side faces %d, polygons %d, segments %d; '
          'attributes %s; metadata %s' % (
              path, len(q), len(faces), h['bits'], info['predictor'],
              (' K=%d lambda=%s' % (info['K'], info['lambda'])) if info['predictor'] == 'ancestors'
              else ' alpha=%s' % info['alpha'] + (' tangent beta=%s' % info['beta'] if info.get('tangent') else ''),
              info['lattice_planes'], info['on_plane'], info['no_triangle'], info['anchored'], info['overrun'],
              info['components'], info['jump_edges'], info['virtual'],
              info['stitches'], info['side_faces'], info['polygons'], info['segments'],
              ', '.join('%s (%s %s)' % (a['header'].name.decode('utf-8', 'replace'), DOMAIN_NAMES[a['header'].domain],
                                        KIND_NAMES[a['header'].kind]) for a in attrs) or 'none',
              'zstd-coded, not checked (no zstandard module)' if info['metadata_skipped'] else
              'none' if info['metadata'] is None else
              '%d entries (%s)' % (len(info['metadata']), ', '.join('%r: %d bytes' % (k, len(v))
                                                                     for k, v in info['metadata']))))
    if trace is not None:
        for line in trace:
            print('  ' + line)
    if '--dump' in argv or trace is not None:
        for i, f in enumerate(faces):
            print('  face %d: %s' % (i, f))
        for v in range(len(q)):
            print('  vertex %d: q=%s pos=%s' % (v, q[v], ['%.9g' % x for x in positions[v]]))
    if '--dump-attributes' in argv or '--dump' in argv:
        dump_attributes(attrs)
    status = 0
    ply = None
    if '--write-ply' in argv or '--compare' in argv:
        try:
            ply = ply_bytes(positions, faces, attrs)
        except CannotWrite as e:
            print('cannot write PLY: %s' % e)
            return 1
    if '--write-ply' in argv:
        open(argv[argv.index('--write-ply') + 1], 'wb').write(ply)
    if '--compare' in argv:
        ref = argv[argv.index('--compare') + 1]
        data = open(ref, 'rb').read()
        if b'format ascii' in data[:data.find(b'end_header')]:
            # ASCII PLY: positions and faces only (the attributes are compared on binary PLY)
            verts, rfaces = read_ply(ref)
            ok = len(verts) == len(positions) and all(
                [bits32(x) for x in verts[v]] == [bits32(x) for x in positions[v]] for v in range(len(verts))) \
                and [list(f) for f in rfaces] == faces
            what = 'ASCII PLY, positions and faces'
        else:
            ok = data == ply
            what = 'binary PLY, byte for byte'
            if not ok:
                hd = ply.find(b'end_header')
                if data[:data.find(b'end_header')] != ply[:hd]:
                    print('headers differ:\n--- reference_decoder.py\n%s--- %s\n%s' % (
                        ply[:hd].decode('ascii', 'replace'), ref,
                        data[:data.find(b'end_header')].decode('ascii', 'replace')))
                else:
                    k = next((i for i in range(min(len(data), len(ply))) if data[i] != ply[i]), min(len(data), len(ply)))
                    print('first differing byte at offset %d (body offset %d); sizes %d vs %d' % (
                        k, k - hd - len(b'end_header\n'), len(ply), len(data)))
        print('compare with %s (%s): %s (%d vertices, %d faces, %d attributes)' % (
            ref, what, 'IDENTICAL' if ok else 'DIFFERENT', len(positions), len(faces), len(attrs)))
        status = status or (0 if ok else 1)
    if '--compare-obj' in argv:
        ref = argv[argv.index('--compare-obj') + 1]
        diffs = compare_obj(ref, positions, faces, attrs)
        for d in diffs:
            print('  ' + d)
        print('compare with %s (OBJ: v, vt, vn lists and f indices): %s' % (ref, 'DIFFERENT' if diffs else 'IDENTICAL'))
        status = status or (1 if diffs else 0)
    return status


if __name__ == '__main__':
    sys.exit(main(sys.argv))
