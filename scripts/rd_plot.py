#!/usr/bin/python3
"""Rate-distortion plot of a progressive file against single-rate files.

Error: the symmetric Hausdorff distance (`tsm compare`, sampled maximum, %
of the bounding-box diagonal) between the input mesh and the decoded mesh.
Bytes: for the progressive file, each prefix that ends after the base or a
refinement batch, decoded with `tsm decode --max-bytes N`; for tsm
single-rate files and Draco (`draco_encoder -cl 10`), the whole file at
quantization 6 .. 14. Attributes are dropped on both sides (Draco's PLY
reader keeps positions and faces of a scan).

    scripts/rd_plot.py [--mesh ../shared/corpus/bun_zipper.ply] [--out docs/rate_distortion.png]

Needs Debian's python3 with python3-matplotlib (scripts/setup.sh), a release build of the CLI
(build/release/cli/tsm) and Draco's draco_encoder/draco_decoder (Debian
`draco`; the Draco curve is left out without them). Prints the figures as a
table too.
"""
import argparse
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(*args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def varint(buf, pos):
    value, shift = 0, 0
    while True:
        b = buf[pos]
        pos += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if b < 0x80:
            return value, pos


def level_ends(path):
    """Byte offsets where the base mesh and each refinement batch end (FORMAT.md §2-4)."""
    data = open(path, 'rb').read()
    pos = 4
    for _ in range(4):  # version, vertex, face and corner counts
        _, pos = varint(data, pos)
    grid, level = data[pos], data[pos + 1]
    pos += 18  # grid, level, origin, top
    if level & 0x10:  # several segments: their count
        _, pos = varint(data, pos)
    if grid & 0x20:  # the exact grid's step and base
        pos += 8
        for _ in range(3):
            _, pos = varint(data, pos)
    ends, base_end = [], None
    while True:
        tag, pos = varint(data, pos)
        if tag == 0:
            break
        sid = tag >> 1
        stored, pos = varint(data, pos)
        if tag & 1:
            _, pos = varint(data, pos)
        pos += stored + 4
        if sid in (7, 10):
            base_end = pos
        elif sid == 12:
            if not ends:
                ends.append(base_end)
            ends.append(pos)
    ends[-1] = len(data)  # the last level: the whole file (loose vertices, end marker)
    return ends


def hausdorff_percent(tsm, reference, mesh, samples):
    out = run(tsm, 'compare', reference, mesh, '--json', '--samples', str(samples))
    return json.loads(out)['hausdorff_percent']


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--mesh', default=os.path.join(ROOT, '..', 'shared', 'corpus', 'bun_zipper.ply'))
    ap.add_argument('--tsm', default=os.path.join(ROOT, 'build', 'release', 'cli', 'tsm'))
    ap.add_argument('--out', default=os.path.join(ROOT, 'docs', 'rate_distortion.png'))
    ap.add_argument('--samples', type=int, default=1000000, help='tsm compare --samples')
    ap.add_argument('--q', type=int, default=14, help="the progressive file's quantization")
    args = ap.parse_args()
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    name = os.path.splitext(os.path.basename(args.mesh))[0]
    work = tempfile.mkdtemp(prefix='tsm-rd-')
    rows = []
    try:
        prog = os.path.join(work, 'progressive.tsm')
        run(args.tsm, 'encode', args.mesh, '--drop-attributes', '--progressive', '-q', str(args.q), '-o', prog, '-f')
        level = os.path.join(work, 'level.ply')
        progressive = []
        for k, end in enumerate(level_ends(prog)):
            run(args.tsm, 'decode', prog, '--max-bytes', str(end), '-o', level, '-f')
            e = hausdorff_percent(args.tsm, args.mesh, level, args.samples)
            progressive.append((end, e))
            rows.append(('progressive q%d' % args.q, 'base' if k == 0 else 'batch %d' % (k - 1), end, e))
        single, draco = [], []
        have_draco = shutil.which('draco_encoder') and shutil.which('draco_decoder')
        for q in range(6, 15):
            f = os.path.join(work, 'q%d.tsm' % q)
            run(args.tsm, 'encode', args.mesh, '--drop-attributes', '-q', str(q), '-o', f, '-f')
            single.append((os.path.getsize(f), hausdorff_percent(args.tsm, args.mesh, f, args.samples)))
            rows.append(('tsm single-rate', 'q %d' % q) + single[-1])
            if have_draco:
                d, back = os.path.join(work, 'q%d.drc' % q), os.path.join(work, 'q%d_drc.ply' % q)
                run('draco_encoder', '-i', args.mesh, '-o', d, '-qp', str(q), '-cl', '10')
                run('draco_decoder', '-i', d, '-o', back)
                draco.append((os.path.getsize(d), hausdorff_percent(args.tsm, args.mesh, back, args.samples)))
                rows.append(('Draco cl10', 'q %d' % q) + draco[-1])
    finally:
        shutil.rmtree(work, ignore_errors=True)

    print('| file | level | bytes | Hausdorff % of diagonal |')
    print('|---|---|---:|---:|')
    for kind, what, size, e in rows:
        print('| %s | %s | %d | %.4f |' % (kind, what, size, e))

    fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=110)
    ax.step([b / 1024 for b, _ in progressive], [e for _, e in progressive], where='post', color='C0',
            label='tsm progressive (q %d): prefixes, one level per batch' % args.q)
    ax.plot([b / 1024 for b, _ in progressive], [e for _, e in progressive], 'o', color='C0', markersize=3)
    ax.plot([b / 1024 for b, _ in single], [e for _, e in single], 's-', color='C1', markersize=4,
            label='tsm single-rate, q 6..14')
    if draco:
        ax.plot([b / 1024 for b, _ in draco], [e for _, e in draco], '^-', color='C2', markersize=4,
                label='Draco cl10, q 6..14')
    for (b, e), q in zip(single, range(6, 15)):
        ax.annotate(str(q), (b / 1024, e), textcoords='offset points', xytext=(4, 3), fontsize=7, color='C1')
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('file bytes (KiB)')
    ax.set_ylabel('symmetric Hausdorff, % of the diagonal')
    ax.set_title('%s: error against bytes (tsm compare)' % name)
    ax.grid(True, which='both', alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out)
    print('wrote %s' % args.out)


if __name__ == '__main__':
    sys.exit(main())
