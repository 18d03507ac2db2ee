#!/usr/bin/python3
"""How often does KLT come back to where it started? The forward-backward distance on a render.

Usage: scripts/analysis/klt_forward_backward.py DATASET [FIRST LAST STEP]   (Debian python3 with numpy, yaml, cv2)
DATASET is a render of `idyvins simulate` (its config and ground truth are read). On left
frames FIRST, FIRST + STEP, ... < LAST (default 200 600 8), OpenCV's corners (150, 30 px
apart, as VINS-Fusion detects) are tracked into the next frame with the tracker's KLT
(13 px window, maxLevel 4, 30 iterations or 0.01 px) and back with its backward check
(maxLevel 1, started at the forward start point). Prints the distance between the start
point and where the backward KLT ends (99 px when either direction fails) and the share
above the tracker's `flow_back_px` (0.5), for KLT started at the previous position (as the
tracker does) and started where the ground-truth rotation between the two frames puts the
corner (a rotation-only prediction, the best a gyroscope could give), and for two wider
windows; and the median image motion of the corners KLT followed both ways (first setting). A
share that the rotation does not lower is not a capture-range problem.
"""
import os
import sys

import cv2
import numpy as np

from sim_geometry import Rig

if len(sys.argv) not in (2, 5):
    sys.exit(__doc__)
ds = sys.argv[1]
first, last, step = (int(a) for a in sys.argv[2:5]) if len(sys.argv) == 5 else (200, 600, 8)
if not os.path.isfile(ds + '/config/sim_stereo_imu_config.yaml') or not os.path.isdir(ds + '/mav0/cam0/data'):
    sys.exit(f'{ds}: not a render of idyvins simulate (config/sim_stereo_imu_config.yaml, mav0/cam0/data expected)')
rig = Rig(ds)
names = sorted(n for n in os.listdir(ds + '/mav0/cam0/data') if n.endswith('.png'))
stamps = [int(n[:-4]) for n in names]
crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)


def image(i):
    path = f'{ds}/mav0/cam0/data/{names[i]}'
    img = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
    if img is None:
        sys.exit(f'{path}: not a readable image')
    return img


def rotated(i, p0):
    """Where the rotation from frame i to i + 1 alone moves the pixels p0 (N x 1 x 2)."""
    R0, _ = rig.pose[stamps[i]][0]
    R1, _ = rig.pose[stamps[i + 1]][0]
    R = R1.T @ R0
    k = rig.K[0]
    out = []
    for uv in p0[:, 0, :]:
        ray = R @ rig.normalized(0, uv)
        x, y = rig.distort(0, ray[0] / ray[2], ray[1] / ray[2])
        out.append([k['fx'] * x + k['cx'], k['fy'] * y + k['cy']])
    return np.array(out, np.float32).reshape(-1, 1, 2)


def distances(window, start_rotated):
    d, motion = [], []
    for i in range(first, min(last, len(names) - 1), step):
        a, b = image(i), image(i + 1)
        p0 = cv2.goodFeaturesToTrack(a, 150, 0.01, 30)
        if p0 is None:
            continue
        win = (window, window)
        if start_rotated:
            p1, ok1, _ = cv2.calcOpticalFlowPyrLK(a, b, p0, rotated(i, p0), winSize=win, maxLevel=4, criteria=crit,
                                                  flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
        else:
            p1, ok1, _ = cv2.calcOpticalFlowPyrLK(a, b, p0, None, winSize=win, maxLevel=4, criteria=crit)
        back, ok2, _ = cv2.calcOpticalFlowPyrLK(b, a, p1, p0.copy(), winSize=win, maxLevel=1, criteria=crit,
                                                flags=cv2.OPTFLOW_USE_INITIAL_FLOW)
        fb = np.linalg.norm((back - p0)[:, 0, :], axis=1)
        failed = (ok1[:, 0] == 0) | (ok2[:, 0] == 0)
        fb[failed] = 99
        d.extend(fb)
        motion.extend(np.linalg.norm((p1 - p0)[:, 0, :], axis=1)[~failed])
    return np.array(d), np.array(motion)


print(f'{ds}: frames {first}..{last} step {step}')
for label, window, start_rotated in (('13 px, from the previous position', 13, False),
                                     ('13 px, from the ground-truth rotation', 13, True),
                                     ('21 px, from the previous position', 21, False),
                                     ('31 px, from the previous position', 31, False)):
    fb, motion = distances(window, start_rotated)
    if not len(fb):
        sys.exit(f'{ds}: no corners on frames {first}..{last}')
    print(f'  {label}: {len(fb)} corners, median {np.median(fb):.3f} px, p90 {np.percentile(fb, 90):.2f} px, '
          f'above 0.5 px {100 * np.mean(fb > 0.5):.1f} %, image motion median {np.median(motion):.1f} px')
