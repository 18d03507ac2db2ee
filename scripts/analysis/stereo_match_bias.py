#!/usr/bin/python3
"""Is the left -> right KLT match biased? Checked against the tracks' ground-truth points.

Usage: scripts/analysis/stereo_match_bias.py OBS.csv DATASET   (Debian python3 with numpy, yaml, cv2: python3-opencv)
OBS.csv is `idyvins run --dump-observations` of an undistorted render DATASET. Each static
track seen at least 6 times is triangulated from its left-image positions and the ground-truth
camera poses; the point, projected into the right camera, is where a right match should be.
Prints the error du = found - predicted right u (positive: disparity too small, depth too
large) of the tracker's own right matches (the dump's u_right; overall, by depth, with the
share more than 2 px off and the rest's mean, and per track), then of cv2.calcOpticalFlowPyrLK
searching the right image from the left position (every 3rd observation of every 2nd frame)
with several windows and pyramid depths. Also
prints how well the tracks fit their triangulated points.
"""
import csv
import sys
from collections import defaultdict

import cv2
import numpy as np

from sim_geometry import Rig

if len(sys.argv) != 3:
    sys.exit(__doc__)
obs_file, ds = sys.argv[1], sys.argv[2]
rig = Rig(ds)
tracks, right = defaultdict(list), {}
for r in csv.DictReader(open(obs_file)):
    if r['on_moving'] == '0':
        tracks[r['id']].append((int(r['t_ns']), float(r['u']), float(r['v'])))
        if r.get('u_right'):
            right[(r['id'], int(r['t_ns']))] = (float(r['u_right']), float(r['v_right']))


per_frame, residuals, tracker, per_track = defaultdict(list), [], [], []
for tid, ob in tracks.items():
    if len(ob) < 6:
        continue
    X = rig.triangulate([(t, (u, v)) for t, u, v in ob])
    for t, u, v in ob:
        residuals.append(np.linalg.norm(rig.project(0, t, X)[0] - (u, v)))
    for t, u, v in ob[::3]:
        per_frame[t].append((u, v, X))
    found = [(right[(tid, t)], rig.project(1, t, X)) for t, _, _ in ob if (tid, t) in right]
    du = [(m[0] - p[0], m[1] - p[1], z) for m, (p, z) in found if abs(m[1] - p[1]) < 2]
    tracker += du
    if len(du) >= 4:
        per_track.append(np.mean([d[0] for d in du]))
print(f'tracks against their ground-truth points: median {np.median(residuals):.3f} px over {len(residuals)} observations')
if tracker:
    r = np.array(tracker)
    print(f'tracker right matches: {len(r)}, du mean {r[:, 0].mean():+.4f} median {np.median(r[:, 0]):+.4f}, '
          f'5 / 95 % {np.percentile(r[:, 0], 5):+.3f} / {np.percentile(r[:, 0], 95):+.3f} px')
    for lo, hi in [(0, 5), (5, 10), (10, 20), (20, 40), (40, np.inf)]:
        s = r[(r[:, 2] >= lo) & (r[:, 2] < hi)]
        if len(s):
            near = s[np.abs(s[:, 0]) < 2, 0]
            print(f'  {lo}-{hi} m: {len(s)}, du mean {s[:, 0].mean():+.4f} median {np.median(s[:, 0]):+.4f} px; '
                  f'|du| > 2 px {100 * np.mean(np.abs(s[:, 0]) >= 2):.2f} % (du > 2 px {100 * np.mean(s[:, 0] >= 2):.2f} %), '
                  f'within 2 px mean {near.mean():+.4f} median {np.median(near):+.4f} px')
    t = np.array(per_track)
    big = t[np.abs(t) > 0.2]
    print(f'  per track (4+ matches): {len(t)} tracks, {100 * len(big) / len(t):.1f} % with mean |du| > 0.2 px, '
          f'{100 * (big > 0).mean():.0f} % of those positive')
else:
    print('no u_right column in OBS.csv: the tracker\'s matches are not checked')
searches = {'13 px, 4 levels (default)': (13, 4), '21 px, 3 levels (VINS-Fusion)': (21, 3), '31 px, 3 levels': (31, 3)}
found = {name: [] for name in searches}
crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)
for t in sorted(per_frame)[::2]:
    left = cv2.imread(ds + f'/mav0/cam0/data/{t}.png', 0)
    right = cv2.imread(ds + f'/mav0/cam1/data/{t}.png', 0)
    pts = np.array([[u, v] for u, v, _ in per_frame[t]], np.float32)
    truth = [rig.project(1, t, X) for _, _, X in per_frame[t]]
    for name, (w, levels) in searches.items():
        out, st, _ = cv2.calcOpticalFlowPyrLK(left, right, pts.copy(), None, winSize=(w, w), maxLevel=levels, criteria=crit)
        found[name] += [(*(out[j] - truth[j][0]), truth[j][1]) for j in range(len(pts)) if st[j, 0]]
for name, rows in found.items():
    r = np.array(rows)
    near = np.linalg.norm(r[:, :2], axis=1) < 2
    print(f'{name}: {len(r)} matches, {100 * near.mean():.1f} % within 2 px (the rows below)')
    for lo, hi in [(0, 5), (5, 10), (10, 20), (20, 40), (40, np.inf)]:
        s = r[near & (r[:, 2] >= lo) & (r[:, 2] < hi)]
        if len(s):
            print(f'  {lo}-{hi} m: {len(s)}, du mean {s[:, 0].mean():+.4f} median {np.median(s[:, 0]):+.4f} px')
