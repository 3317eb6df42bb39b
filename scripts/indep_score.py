#!/usr/bin/env python3
"""Scores door_state_cli's reports on scripts/indep_rooms.py's rooms.

  /usr/bin/python3 scripts/indep_score.py DIR KIND FIRST LAST [-v]

DIR holds sN.truth.json (indep_rooms.py --out DIR/sN) and the reports
sN.KIND.json for seeds FIRST..LAST, KIND a name of your choosing (single:
only station 0's leaf visibility is printed). A report matches a true door
when their opening centres lie within 0.5 m (greedy, nearest first). Prints
recall, precision, the matched doors in the right state (over measured
leaves alone), the angle error of measured leaves; with -v each miss, wrong
state or angle error over 5 deg, and false report. For example:

  mkdir -p /tmp/ir; for s in $(seq 1 30); do
    /usr/bin/python3 scripts/indep_rooms.py --seed $s --out /tmp/ir/s$s
    build/bin/door_state_cli --json /tmp/ir/s$s.single.json /tmp/ir/s$s.s0.pcd
    build/bin/door_state_cli --json /tmp/ir/s$s.merged.json /tmp/ir/s$s.merged.pcd
  done
  /usr/bin/python3 scripts/indep_score.py /tmp/ir single 1 30   # and merged

(indep_rooms.py needs numpy: Debian's python3-numpy, hence /usr/bin/python3)
"""
import json, sys, math, os
base, kind, a, b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
ND = NR = M = SR = 0; aerr = []; aerr_b = []; fails = []; nmeas = nmeas_right = 0
for s in range(a, b + 1):
    tp, rp = '%s/s%d.truth.json' % (base, s), '%s/s%d.%s.json' % (base, s, kind)
    if not (os.path.exists(tp) and os.path.exists(rp)):
        continue
    T = json.load(open(tp)); R = json.load(open(rp))
    td, rd = T['doors'], R['doors']
    ND += len(td); NR += len(rd)
    pairs = sorted((math.hypot(t['opening_center'][0] - r['opening_center'][0], t['opening_center'][1] - r['opening_center'][1]), i, j)
                   for i, t in enumerate(td) for j, r in enumerate(rd))
    mt, mr = {}, {}
    for dist, i, j in pairs:
        if dist <= 0.5 and i not in mt and j not in mr:
            mt[i] = j; mr[j] = i
    vp = 'vp' if R.get('viewpoint') else 'novp(%d st)' % len(R.get('stations') or [])
    for i, t in enumerate(td):
        vis = t['leaf_visible_share'] if kind != 'single' else t['leaf_visible_share'][:1]
        tag = 's%d d%d %s %s %.1f %s %s cas=%d hdl=%d w=%.2f vis=%s [%s]' % (s, i, t['wall'], t['state'], t['opening_angle_deg'], t['swing'], t['closed_mode'], t['casing'], t['handle'], t['width'], ','.join('%.2f' % v for v in vis), vp)
        if i not in mt:
            fails.append('MISS  ' + tag); continue
        r = rd[mt[i]]; M += 1
        e = abs(r['opening_angle_deg'] - t['opening_angle_deg'])
        (aerr_b if r['angle_is_lower_bound'] else aerr).append(e)
        ok = r['state'] == t['state']
        if not r['angle_is_lower_bound']:
            nmeas += 1; nmeas_right += ok
        SR += ok
        if not ok or (e > 5 and not r['angle_is_lower_bound']):
            fails.append('%s %s -> %s %.1f%s (err %.1f) w=%.2f' % ('STATE' if not ok else 'ANGLE', tag, r['state'], r['opening_angle_deg'], ' LB' if r['angle_is_lower_bound'] else '', e, r['width']))
    for j, r in enumerate(rd):
        if j not in mr:
            near = min([math.hypot(t['opening_center'][0] - r['opening_center'][0], t['opening_center'][1] - r['opening_center'][1]) for t in td] + [99])
            fails.append('FALSE s%d report %s %.1f at (%.2f,%.2f) w=%.2f nearest true door %.2f m [%s]' % (s, r['state'], r['opening_angle_deg'], r['opening_center'][0], r['opening_center'][1], r['width'], near, vp))
med = lambda x: sorted(x)[len(x) // 2] if x else float('nan')
mae = lambda x: sum(x) / len(x) if x else float('nan')
print('%-7s doors %d reports %d | recall %.3f (%d) precision %.3f | state right %d/%d = %.3f (measured %d/%d) | angle MAE measured %.1f (median %.1f, n=%d); bounds n=%d' % (
    kind, ND, NR, M / max(ND, 1), M, M / max(NR, 1), SR, M, SR / max(M, 1), nmeas_right, nmeas, mae(aerr), med(aerr), len(aerr), len(aerr_b)))
if '-v' in sys.argv:
    for f in fails: print('   ' + f)
