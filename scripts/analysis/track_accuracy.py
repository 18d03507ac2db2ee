#!/usr/bin/python3
"""How far do the tracker's observations lie from the scene? Checked with the rendered depth.

Usage: scripts/analysis/track_accuracy.py OBS.csv DATASET [FRAMES]   (Debian python3 with numpy, yaml, cv2)
DATASET is a render written with `idyvins simulate --depth`; OBS.csv is
`idyvins run --dump-observations` of it. Each static track's first observation, lifted with
the depth image at that pixel (inverse depth interpolated), is the scene point the track
should follow; its projections with the ground-truth poses are where the later left
observations and the right matches should be. Tracks are grouped by the depth around their
first pixel (7 x 7 px): smooth (max / min < 1.02), slanted (< 1.2), edge (a depth step) and
sky (touching the sky). Prints, per group, the share of observations and the error along
the image flow since the first observation (positive: the track moved further than the
scene point) by track age, its ratio to the flow (a scale error of the tracks), and the
right matches' error along the epipolar line (positive: disparity too small, depth too large).
Only the first FRAMES frames (default 400) are used.
"""
import csv
import sys
from collections import defaultdict

import cv2
import numpy as np

from sim_geometry import Rig

if len(sys.argv) not in (3, 4):
    sys.exit(__doc__)
obs_file, ds = sys.argv[1], sys.argv[2]
max_frames = int(sys.argv[3]) if len(sys.argv) == 4 else 400
rig = Rig(ds)
tracks = defaultdict(list)
for r in csv.DictReader(open(obs_file)):
    if r['on_moving'] == '0':
        right = (float(r['u_right']), float(r['v_right'])) if r.get('u_right') else None
        tracks[r['id']].append((int(r['t_ns']), np.array((float(r['u']), float(r['v']))), right))
keep = set(sorted({o[0] for ob in tracks.values() for o in ob})[:max_frames])


def depth_image(t):
    d = cv2.imread(f'{ds}/mav0/cam0/depth/{t}.tiff', cv2.IMREAD_UNCHANGED)
    if d is None:
        sys.exit(f'{ds}/mav0/cam0/depth/{t}.tiff: cannot read, expected a render written with simulate --depth')
    return d


def group_and_point(t, uv):
    """The track's group and its scene point (world), or None at the image border."""
    d = depth_image(t)
    iu, iv = int(uv[0]), int(uv[1])
    if iu < 3 or iv < 3 or iu > d.shape[1] - 4 or iv > d.shape[0] - 4:
        return None, None
    around = d[iv - 3:iv + 4, iu - 3:iu + 4]
    four = d[iv:iv + 2, iu:iu + 2]
    if (around <= 0).any():
        group = 'sky'
    else:
        ratio = around.max() / around.min()
        group = 'smooth' if ratio < 1.02 else 'slanted' if ratio < 1.2 else 'edge'
    if (four <= 0).any():
        return group, None
    a, b = uv[0] - iu, uv[1] - iv
    w = np.array([[(1 - a) * (1 - b), a * (1 - b)], [(1 - a) * b, a * b]])
    z = 1.0 / (w / four).sum() if four.max() / four.min() < 1.2 else four.min()
    R, p = rig.pose[t][0]
    return group, R @ (rig.normalized(0, uv) * z) + p


rows = defaultdict(list)  # group -> (age, flow px, along px, depth m, right along px)
count = defaultdict(int)
for ob in tracks.values():
    t0, uv0, _ = ob[0]
    if t0 not in keep:
        continue
    group, X = group_and_point(t0, uv0)
    if group is None:
        continue
    count[group] += len(ob)
    if X is None:
        continue
    for age, (t, uv, right) in enumerate(ob):
        if t not in keep:
            continue
        pred, z = rig.project(0, t, X)
        flow = pred - uv0
        err = uv - pred
        if np.linalg.norm(err) > 3 or z <= 0:
            continue
        along = err @ flow / np.linalg.norm(flow) if np.linalg.norm(flow) > 1e-6 else 0.0
        r_along = np.nan
        if right is not None:
            q, _ = rig.project(1, t, X)
            R, p = rig.pose[t][0]
            q_far, _ = rig.project(1, t, p + (X - p) * 1.05)
            e = (q_far - q) / np.linalg.norm(q_far - q)
            d = np.array(right) - q
            r_along = d @ e if np.linalg.norm(d) < 3 else np.nan
        rows[group].append((age, np.linalg.norm(flow), along, z, r_along))
total = sum(count.values())
print(f'{total} static observations of tracks starting in the first {len(keep)} frames')
for group in ['smooth', 'slanted', 'edge', 'sky']:
    if group not in rows:
        continue
    r = np.array(rows[group])
    print(f'{group}: {100 * count[group] / total:.1f} % of the observations, |error| median '
          f'{np.median(np.abs(r[:, 2])):.3f} px along the flow')
    for lo, hi in [(1, 4), (4, 16), (16, 64), (64, 100000)]:
        s = r[(r[:, 0] >= lo) & (r[:, 0] < hi)]
        moved = s[s[:, 1] > 2]
        if len(s):
            print(f'  age {lo}-{hi}: {len(s)}, along mean {s[:, 2].mean():+.4f} median {np.median(s[:, 2]):+.4f} px; '
                  f'/ flow (> 2 px) median {100 * np.median(moved[:, 2] / moved[:, 1]) if len(moved) else 0:+.3f} %; '
                  f'right along mean {np.nanmean(s[:, 4]):+.4f} px')
