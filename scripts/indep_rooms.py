#!/usr/bin/env python3
"""Rooms from a second, independent generator, for cross-checks: not
door_scene_sim's conventions (casing on the leaf's swing side only, leaves
closed flush with a face or centred in the wall, hinges at the leaf's
swing-side face, 1-2 doors each opening onto a corridor or a room), its own
analytic ray caster (oriented boxes, slab test), a terrestrial scanner at two
stations 1.0-1.8 m high, 400k rays each, 3 mm range noise.

  /usr/bin/python3 scripts/indep_rooms.py --seed N --out PREFIX [--rays 400000] [--stats]
      [--angle DEG] [--mode flush|centred] [--swing into|away] [--casing 0|1]
      [--handle 0|1] [--casing-side swing|room|both] [--single]

Writes PREFIX.s0.pcd, PREFIX.s1.pcd (one station each, VIEWPOINT = the
station), PREFIX.merged.pcd (both, VIEWPOINT 0 0 0 1 0 0 0, as registered
exports write it) and PREFIX.truth.json. Frame: z up, floor at z=0, the room
yawed and shifted at random. The forcing options set one property of every
door after all draws (the rest of the scene stays as its seed draws it).
Scored by scripts/indep_score.py. Written by a helper as a new user would
(session 37): figures in doc/results.md.
"""
import argparse, json, math, struct
import numpy as np

CLOSED_BELOW, OPEN_FROM = 5.0, 90.0
CASING_SIDE = 'swing'  # casing on the leaf's (swing) side; --casing-side room|both for ablations   # the package's defaults (README)


class Scene:
    def __init__(self):
        self.c, self.ax, self.h, self.label = [], [], [], []

    def add(self, centre, axes, half, label):
        self.c.append(np.asarray(centre, float)); self.ax.append(np.asarray(axes, float))
        self.h.append(np.asarray(half, float)); self.label.append(label)
        return len(self.c) - 1

    def add_wallbox(self, W, u0, u1, n0, n1, z0, z1, label):
        """Box in wall coordinates (u along the wall, n inward normal)."""
        uc, nc = 0.5 * (u0 + u1), 0.5 * (n0 + n1)
        p = W['p0'] + uc * W['a'] + nc * W['n']
        axes = [[W['a'][0], W['a'][1], 0], [W['n'][0], W['n'][1], 0], [0, 0, 1]]
        return self.add([p[0], p[1], 0.5 * (z0 + z1)], axes,
                        [0.5 * abs(u1 - u0), 0.5 * abs(n1 - n0), 0.5 * (z1 - z0)], label)

    def cast(self, o, d, chunk=100000):
        """First hit of rays o (3,) + t d (N,3). Returns t (inf = none), box index."""
        N = d.shape[0]
        tbest = np.full(N, np.inf); ibest = np.full(N, -1, int)
        for s in range(0, N, chunk):
            dd = d[s:s + chunk]
            tb = np.full(dd.shape[0], np.inf); ib = np.full(dd.shape[0], -1, int)
            for k in range(len(self.c)):
                A, h = self.ax[k], self.h[k]
                op = A @ (o - self.c[k])
                dp = dd @ A.T
                with np.errstate(divide='ignore', invalid='ignore'):
                    inv = 1.0 / dp
                    t1 = (-h - op) * inv; t2 = (h - op) * inv
                tmin = np.nanmax(np.minimum(t1, t2), axis=1)
                tmax = np.nanmin(np.maximum(t1, t2), axis=1)
                hit = (tmax >= tmin) & (tmin > 1e-6) & (tmin < tb)
                tb[hit] = tmin[hit]; ib[hit] = k
            tbest[s:s + chunk] = tb; ibest[s:s + chunk] = ib
        return tbest, ibest


def walls_of(Lx, Ly):
    return {
        'S': dict(p0=np.array([0., 0.]), a=np.array([1., 0.]), n=np.array([0., 1.]), L=Lx),
        'N': dict(p0=np.array([0., Ly]), a=np.array([1., 0.]), n=np.array([0., -1.]), L=Lx),
        'W': dict(p0=np.array([0., 0.]), a=np.array([0., 1.]), n=np.array([1., 0.]), L=Ly),
        'E': dict(p0=np.array([Lx, 0.]), a=np.array([0., 1.]), n=np.array([-1., 0.]), L=Ly),
    }


def state_of(angle):
    return 'closed' if angle < CLOSED_BELOW else ('open' if angle >= OPEN_FROM else 'semi_open')


def build(seed, force=None):
    rng = np.random.default_rng(seed)
    Lx, Ly = rng.uniform(4, 7), rng.uniform(3.5, 6)
    H = rng.uniform(2.4, 3.0)
    t = rng.uniform(0.10, 0.25)
    W = walls_of(Lx, Ly)
    sc = Scene()
    info = dict(room=[Lx, Ly], height=H, wall_thickness=t)
    # floor / ceiling slabs, large enough for the neighbouring spaces
    sc.add([Lx / 2, Ly / 2, -0.05], np.eye(3), [Lx / 2 + 8, Ly / 2 + 8, 0.05], 'floor')
    sc.add([Lx / 2, Ly / 2, H + 0.05], np.eye(3), [Lx / 2 + 8, Ly / 2 + 8, 0.05], 'ceiling')

    ndoors = int(rng.integers(1, 3))
    names = list(rng.permutation(['S', 'N', 'W', 'E']))[:ndoors]
    doors = []
    for wn in names:
        Wl = W[wn]
        w = rng.uniform(0.75, 1.0)
        hd = rng.uniform(2.0, 2.1)
        margin = 0.6
        for _ in range(100):
            u0 = rng.uniform(margin, Wl['L'] - margin - w)
            hinge_left = bool(rng.random() < 0.5)
            into = bool(rng.random() < 0.5)
            # hinge position in room xy (inner face) for overlap checks
            uh = u0 if hinge_left else u0 + w
            hp = Wl['p0'] + uh * Wl['a']
            ok = True
            for d in doors:
                if np.linalg.norm(hp - d['_hp']) < w + d['width'] + 0.2:
                    ok = False
            if ok:
                break
        b = int(rng.integers(0, 4))
        angle = [0.0, rng.uniform(5, 30), rng.uniform(30, 80), rng.uniform(80, 120)][b]
        mode = 'flush' if rng.random() < 0.5 else 'centred'
        if angle > 90 and mode == 'centred':
            mode = 'flush'  # a leaf recessed into the reveal cannot pass 90 deg without hitting the jamb
        doors.append(dict(wall=wn, width=w, height=hd, u0=u0, hinge_left=hinge_left, into_room=into,
                          angle=angle, closed_mode=mode, casing=bool(rng.random() < 0.5),
                          handle=bool(rng.random() < 0.5), _hp=hp))

    # controlled overrides (applied after every draw, so the rest of the scene is unchanged)
    for d in doors:
        for k, v in (force or {}).items():
            d[k] = v
        if d['angle'] > 90 and d['closed_mode'] == 'centred':
            d['closed_mode'] = 'flush'

    # walls with doorways
    for wn, Wl in W.items():
        ds = [d for d in doors if d['wall'] == wn]
        if not ds:
            sc.add_wallbox(Wl, -t, Wl['L'] + t, -t, 0, 0, H, 'wall_' + wn)
        else:
            d = ds[0]
            sc.add_wallbox(Wl, -t, d['u0'], -t, 0, 0, H, 'wall_' + wn)
            sc.add_wallbox(Wl, d['u0'] + d['width'], Wl['L'] + t, -t, 0, 0, H, 'wall_' + wn)
            sc.add_wallbox(Wl, d['u0'], d['u0'] + d['width'], -t, 0, d['height'], H, 'wall_' + wn)

    # neighbouring spaces
    for di, d in enumerate(doors):
        Wl = W[d['wall']]
        if rng.random() < 0.5:
            kind, D = 'corridor', rng.uniform(1.5, 2.0)
            ua, ub = -t, Wl['L'] + t
        else:
            kind, D = 'room', rng.uniform(2.0, 5.0)
            ua = max(-t, d['u0'] - rng.uniform(1.2, 3.0))
            ub = min(Wl['L'] + t, d['u0'] + d['width'] + rng.uniform(1.2, 3.0))
        d['beyond'] = dict(kind=kind, depth=D)
        tw = 0.15
        sc.add_wallbox(Wl, ua - tw, ub + tw, -t - D - tw, -t - D, 0, H, 'beyond%d' % di)
        sc.add_wallbox(Wl, ua - tw, ua, -t - D, -t, 0, H, 'beyond%d' % di)
        sc.add_wallbox(Wl, ub, ub + tw, -t - D, -t, 0, H, 'beyond%d' % di)

    # leaves, casings, handles
    for di, d in enumerate(doors):
        Wl = W[d['wall']]
        w, hd, u0 = d['width'], d['height'], d['u0']
        lt = rng.uniform(0.035, 0.045); wl = w - 0.01
        d['leaf_thickness'] = lt
        su = 1.0 if d['hinge_left'] else -1.0
        sn = 1.0 if d['into_room'] else -1.0
        uh = u0 + 0.005 if d['hinge_left'] else u0 + w - 0.005
        # n of the leaf's swing-side face when closed
        if d['closed_mode'] == 'flush':
            nh = 0.0 if d['into_room'] else -t
        else:
            nh = -t / 2 + sn * lt / 2
        th = math.radians(d['angle'])
        # in (u, n): along the leaf from the hinge, and across it (towards the non-swing side when closed)
        e = np.array([su * math.cos(th), sn * math.sin(th)])
        f = np.array([su * math.sin(th), -sn * math.cos(th)])  # perpendicular to e, (0,-sn) at th=0
        def uv2xy(uv):
            return Wl['p0'] + uv[0] * Wl['a'] + uv[1] * Wl['n']
        hinge_uv = np.array([uh, nh])
        ctr_uv = hinge_uv + e * wl / 2 + f * lt / 2
        exy = e[0] * Wl['a'] + e[1] * Wl['n']; fxy = f[0] * Wl['a'] + f[1] * Wl['n']
        assert abs(exy @ fxy) < 1e-9
        cxy = uv2xy(ctr_uv)
        zl0, zl1 = 0.01, hd - 0.005
        li = sc.add([cxy[0], cxy[1], 0.5 * (zl0 + zl1)], [[exy[0], exy[1], 0], [fxy[0], fxy[1], 0], [0, 0, 1]],
                    [wl / 2, lt / 2, 0.5 * (zl1 - zl0)], 'leaf%d' % di)
        d['_leaf_box'] = li
        hxy = uv2xy(hinge_uv)
        lxy = uv2xy(hinge_uv + e * wl)
        d['hinge_xy'] = hxy; d['latch_xy'] = lxy
        d['leaf_corners'] = [[hxy[0], hxy[1], zl0], [lxy[0], lxy[1], zl0], [lxy[0], lxy[1], zl1], [hxy[0], hxy[1], zl1]]
        if d['handle']:
            for side in (-1, 1):  # both faces
                off = (lt / 2 + 0.06 + 0.01) * side
                huv = hinge_uv + e * (wl - 0.10) + f * (lt / 2 + off)
                hxy2 = uv2xy(huv)
                sc.add([hxy2[0], hxy2[1], 1.0], [[exy[0], exy[1], 0], [fxy[0], fxy[1], 0], [0, 0, 1]],
                       [0.06, 0.01, 0.01], 'handle%d' % di)
        cw, cp = rng.uniform(0.05, 0.08), rng.uniform(0.01, 0.02)  # drawn always: the rng stream does not depend on it
        if d['casing']:
            d['casing_width'], d['casing_proud'] = cw, cp
            sides = {'swing': [d['into_room']], 'room': [True], 'both': [True, False]}[CASING_SIDE]
            d['casing_sides'] = ['room' if x else 'beyond' for x in sides]
            for inner in sides:
                n0, n1 = (0.0, cp) if inner else (-t - cp, -t)
                sc.add_wallbox(Wl, u0 - cw, u0, n0, n1, 0, hd + cw, 'casing%d' % di)
                sc.add_wallbox(Wl, u0 + w, u0 + w + cw, n0, n1, 0, hd + cw, 'casing%d' % di)
                sc.add_wallbox(Wl, u0, u0 + w, n0, n1, hd, hd + cw, 'casing%d' % di)
        cen = uv2xy(np.array([u0 + w / 2, -t / 2]))
        d['opening_center_xy'] = cen
        d['wall_normal_in'] = Wl['n'].copy()

    # furniture
    def fp_rect(Wl, ua, ub, n0, n1):
        pts = np.array([Wl['p0'] + u * Wl['a'] + n * Wl['n'] for u in (ua, ub) for n in (n0, n1)])
        return pts.min(0), pts.max(0)

    def rect_overlap(r1, r2, m=0.0):
        return np.all(r1[0] - m < r2[1]) and np.all(r2[0] - m < r1[1])

    excl = []
    for d in doors:
        Wl = W[d['wall']]
        excl.append(fp_rect(Wl, d['u0'] - 0.3, d['u0'] + d['width'] + 0.3, 0, d['width'] + 0.3))
    furn = []
    nf = int(rng.integers(0, 4))
    for _ in range(nf):
        for _try in range(50):
            wn = rng.choice(['S', 'N', 'W', 'E']); Wl = W[wn]
            if rng.random() < 0.5:
                kind, dep, ht, wid = 'cupboard', rng.uniform(0.4, 0.6), rng.uniform(1.8, 2.2), rng.uniform(0.6, 1.5)
            else:
                kind, dep, ht, wid = 'desk', rng.uniform(0.6, 0.8), 0.75, rng.uniform(1.0, 1.6)
            if wid > Wl['L'] - 0.1:
                continue
            ua = rng.uniform(0.02, Wl['L'] - wid - 0.02)
            r = fp_rect(Wl, ua, ua + wid, 0.01, 0.01 + dep)
            if any(rect_overlap(r, e) for e in excl) or any(rect_overlap(r, f['rect'], 0.05) for f in furn):
                continue
            sc.add_wallbox(Wl, ua, ua + wid, 0.01, 0.01 + dep, 0, ht, 'furniture_' + kind)
            furn.append(dict(kind=kind, wall=wn, rect=r, height=ht))
            break

    # stations
    stations = []
    for si in range(2):
        for _try in range(500):
            p = np.array([rng.uniform(0.5, Lx - 0.5), rng.uniform(0.5, Ly - 0.5)])
            if any(np.all(p > f['rect'][0] - 0.4) and np.all(p < f['rect'][1] + 0.4) for f in furn):
                continue
            if any(np.linalg.norm(p - d['hinge_xy']) < d['width'] + 0.15 for d in doors):
                continue
            if stations and np.linalg.norm(p - stations[0][:2]) < (1.5 if _try < 300 else 0.8):
                continue
            break
        stations.append(np.array([p[0], p[1], rng.uniform(1.0, 1.8)]))

    # global placement: yaw + shift
    yaw = rng.uniform(-math.pi, math.pi)
    shift = np.array([rng.uniform(-20, 20), rng.uniform(-20, 20), 0.0])
    return sc, doors, furn, stations, info, yaw, shift, rng


def scan(sc, o, nrays, rng, noise=0.003):
    n_el = int(round(math.sqrt(nrays / 2.4)))
    n_az = int(round(nrays / n_el))
    az = np.linspace(0, 2 * math.pi, n_az, endpoint=False)
    el = np.radians(np.linspace(-60, 90, n_el))
    A, E = np.meshgrid(az, el)
    A, E = A.ravel(), E.ravel()
    d = np.stack([np.cos(E) * np.cos(A), np.cos(E) * np.sin(A), np.sin(E)], 1)
    t, idx = sc.cast(o, d)
    ok = np.isfinite(t) & (t < 30)
    t = t[ok] + rng.normal(0, noise, ok.sum())
    return o + d[ok] * t[:, None], idx[ok]


def leaf_visibility(sc, d, o):
    """Share of sample points on the leaf's two big faces visible from o (the better face)."""
    k = d['_leaf_box']
    c, A, h = sc.c[k], sc.ax[k], sc.h[k]
    best = 0.0
    for side in (-1, 1):
        s = np.array([[a, b] for a in np.linspace(-0.9, 0.9, 8) for b in np.linspace(-0.9, 0.9, 16)])
        P = c + (s[:, 0:1] * h[0]) * A[0] + side * (h[1] + 1e-4) * A[1] + (s[:, 1:2] * h[2]) * A[2]
        v = P - o; dist = np.linalg.norm(v, axis=1); v /= dist[:, None]
        t, idx = sc.cast(o, v)
        vis = (idx == k) & (np.abs(t - dist) < 0.01)
        best = max(best, float(vis.mean()))
    return best


def write_pcd(path, pts, vp):
    pts = np.ascontiguousarray(pts, dtype='<f4')
    hdr = ("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
           "COUNT 1 1 1\nWIDTH %d\nHEIGHT 1\nVIEWPOINT %.6f %.6f %.6f 1 0 0 0\nPOINTS %d\nDATA binary\n"
           % (len(pts), vp[0], vp[1], vp[2], len(pts)))
    with open(path, 'wb') as f:
        f.write(hdr.encode()); f.write(pts.tobytes())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seed', type=int, required=True)
    ap.add_argument('--out', required=True)
    ap.add_argument('--rays', type=int, default=400000)
    ap.add_argument('--stats', action='store_true')
    ap.add_argument('--angle', type=float, help='force every door to this opening angle (deg)')
    ap.add_argument('--mode', choices=['flush', 'centred'], help='force the closed position of every leaf')
    ap.add_argument('--swing', choices=['into', 'away'], help='force the swing side of every door')
    ap.add_argument('--casing', type=int, choices=[0, 1], help='force casing off/on')
    ap.add_argument('--handle', type=int, choices=[0, 1], help='force handles off/on')
    ap.add_argument('--casing-side', choices=['swing', 'room', 'both'], default='swing')
    ap.add_argument('--single', action='store_true', help='scan station 0 only (no s1 / merged clouds)')
    a = ap.parse_args()
    global CASING_SIDE
    CASING_SIDE = a.casing_side
    force = {}
    if a.angle is not None: force['angle'] = a.angle
    if a.mode: force['closed_mode'] = a.mode
    if a.swing: force['into_room'] = a.swing == 'into'
    if a.casing is not None: force['casing'] = bool(a.casing)
    if a.handle is not None: force['handle'] = bool(a.handle)
    sc, doors, furn, stations, info, yaw, shift, rng = build(a.seed, force)
    cy, sy = math.cos(yaw), math.sin(yaw)
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    G = lambda p: (Rz @ np.asarray(p, float).reshape(-1, 3).T).T + shift
    G2 = lambda v: (Rz[:2, :2] @ np.asarray(v, float))
    clouds = []
    truth = dict(seed=a.seed, generator='indep/gen.py', **info, yaw_deg=math.degrees(yaw), shift=shift.tolist(),
                 stations=[], doors=[], furniture=[])
    for si, o in enumerate(stations):
        if a.single and si > 0:
            truth['stations'].append(dict(position=G(o)[0].tolist(), points=0, counts={}))
            continue
        pts, idx = scan(sc, o, a.rays, rng)
        clouds.append(pts)
        vp = G(o)[0]
        write_pcd('%s.s%d.pcd' % (a.out, si), G(pts), vp)
        labels = np.array(sc.label)[idx]
        counts = {l: int((labels == l).sum()) for l in sorted(set(sc.label))}
        truth['stations'].append(dict(position=vp.tolist(), points=int(len(pts)), counts=counts))
        if a.stats:
            print('station', si, 'at', np.round(o, 2), 'points', len(pts))
            for l, n in counts.items():
                print('   %-20s %7d' % (l, n))
    if not a.single:
        write_pcd('%s.merged.pcd' % a.out, G(np.concatenate(clouds)), [0, 0, 0])
    for di, d in enumerate(doors):
        lc = G(d['leaf_corners'])
        hinge = G([d['hinge_xy'][0], d['hinge_xy'][1], 0])[0]
        oc = G([d['opening_center_xy'][0], d['opening_center_xy'][1], 0])[0]
        nin = G2(d['wall_normal_in'])
        vis = [leaf_visibility(sc, d, o) for o in (stations[:1] if a.single else stations)]
        leafpts = [truth['stations'][si]['counts'].get('leaf%d' % di, 0) for si in range(len(truth['stations']))]
        truth['doors'].append(dict(
            id=di, wall=d['wall'], width=d['width'], height=d['height'], hinge=hinge.tolist(),
            opening_center=oc.tolist(), opening_angle_deg=d['angle'], state=state_of(d['angle']),
            swing='into_room' if d['into_room'] else 'away_from_room', wall_normal_into_room=[nin[0], nin[1], 0.0],
            hinge_side='left' if d['hinge_left'] else 'right', closed_mode=d['closed_mode'],
            casing=d['casing'], handle=d['handle'], leaf_thickness=d['leaf_thickness'],
            leaf_corners=lc.tolist(), beyond=d['beyond'], leaf_visible_share=vis, leaf_points=leafpts))
    for f in furn:
        c = G([(f['rect'][0][0] + f['rect'][1][0]) / 2, (f['rect'][0][1] + f['rect'][1][1]) / 2, 0])[0]
        truth['furniture'].append(dict(kind=f['kind'], wall=f['wall'], centre=c.tolist(), height=f['height']))
    with open('%s.truth.json' % a.out, 'w') as fh:
        json.dump(truth, fh, indent=1)
    if a.stats:
        for d in truth['doors']:
            print('door', d['id'], d['wall'], d['state'], '%.1f' % d['opening_angle_deg'], d['swing'], d['closed_mode'],
                  'casing' if d['casing'] else '', 'handle' if d['handle'] else '', 'vis', np.round(d['leaf_visible_share'], 2))


if __name__ == '__main__':
    main()
