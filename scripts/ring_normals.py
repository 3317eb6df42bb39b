#!/usr/bin/env python3
"""Normals of an organized LiDAR sweep from its ring grid, against the truth's labels.

  /usr/bin/python3 scripts/ring_normals.py SWEEP.pcd [...]

SWEEP.pcd is a door_scene_sim sweep (--sensor lidar16|lidar32|lidar64|lidar128,
or scripts/eval_sweep.py --out DIR): binary, fields x y z label, rows = beams.
Each point's normal is the cross product of the step along its ring (the
points either side) with the step across the rings (the point above and
below), where both stay short (a step along a ring under 5 % of the range +
2 cm, across under 25 % + 5 cm: no jump to another surface). Printed per
sweep: the wall points (label 3) with such a normal and how many of them are
near horizontal (|n_z| < 0.3), the floor points (label 1) and how many are near
vertical (|n_z| > 0.9). doc/results.md ("sparse LiDAR rings") compares it
with the pipeline's PCA normals.
"""
import sys

import numpy as np


def ring_normals(path):
    raw = open(path, 'rb').read()
    i = raw.index(b'DATA binary\n') + len(b'DATA binary\n')
    hdr = raw[:i].decode().splitlines()
    field = lambda k: [l for l in hdr if l.startswith(k)][0].split()[1:]
    if field('FIELDS') != ['x', 'y', 'z', 'label']:
        sys.exit(f'{path}: fields x y z label expected')
    W, H = int(field('WIDTH')[0]), int(field('HEIGHT')[0])
    a = np.frombuffer(raw[i:], dtype=np.dtype([('x', '<f4'), ('y', '<f4'), ('z', '<f4'), ('l', '<u4')]), count=W * H)
    P = np.stack([a['x'], a['y'], a['z']], -1).reshape(H, W, 3).astype(np.float64)
    L = a['l'].reshape(H, W)
    h = np.roll(P, -1, 1) - np.roll(P, 1, 1)  # along the ring (azimuth wraps)
    v = np.full_like(P, np.nan)                 # across the rings
    v[1:-1] = P[2:] - P[:-2]
    v[0], v[-1] = P[1] - P[0], P[-1] - P[-2]
    rng = np.linalg.norm(P, axis=2)
    with np.errstate(invalid='ignore'):
        ok = (np.isfinite(h).all(2) & np.isfinite(v).all(2) & (np.linalg.norm(h, axis=2) < 0.05 * rng + 0.02) &
              (np.linalg.norm(v, axis=2) < 0.25 * rng + 0.05))
        n = np.cross(h, v)
        norm = np.linalg.norm(n, axis=2)
        ok &= norm > 1e-9
        n = n / np.where(ok, norm, 1)[..., None]
    finite = np.isfinite(P).all(2)
    nz = np.abs(n[..., 2])
    wall, floor = (L == 3) & finite, (L == 1) & finite
    print(f'{path}: wall points {wall.sum()}, with a ring normal {(wall & ok).sum()}, horizontal '
          f'{(wall & ok & (nz < 0.3)).sum()}; floor points {floor.sum()}, with a ring normal {(floor & ok).sum()}, '
          f'vertical {(floor & ok & (nz > 0.9)).sum()}')


if __name__ == '__main__':
    if len(sys.argv) < 2 or sys.argv[1] in ('-h', '--help'):
        print(__doc__.strip())
        sys.exit(0 if len(sys.argv) >= 2 else 2)
    for p in sys.argv[1:]:
        ring_normals(p)
