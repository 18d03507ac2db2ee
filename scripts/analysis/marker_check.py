#!/usr/bin/python3
"""Do a rendered dataset's images agree with its calibration? Marker corners checked.

Usage: scripts/analysis/marker_check.py DATASET   (Debian python3 with numpy, yaml, cv2: python3-opencv)
DATASET is an undistorted render (`idyvins simulate --family validation`). Each marker corner
of meta.json, projected with the written calibration and the ground-truth pose into both
cameras (every 5th frame, 0.5-20 m, facing the camera), is refined on the rendered image
(cv2.cornerSubPix) and compared: per camera the error's mean and median, and the disparity
error (measured minus predicted, px). A biased renderer would show here.
"""
import glob
import json
import os
import sys

import cv2
import numpy as np

from sim_geometry import Rig

if len(sys.argv) != 2:
    sys.exit(__doc__)
ds = sys.argv[1]
rig = Rig(ds)
corners = np.array(json.load(open(ds + '/meta.json'))['marker_corners_w'])
stamps = sorted(int(os.path.basename(f)[:-4]) for f in glob.glob(ds + '/mav0/cam0/data/*.png'))
errors, disparity = [[], []], []
crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
for t in stamps[::5]:
    images = [cv2.imread(ds + f'/mav0/cam{i}/data/{t}.png', 0) for i in range(2)]
    for k, p_w in enumerate(corners):
        proj = [rig.project(i, t, p_w) for i in range(2)]
        if any(z < 0.5 or z > 20 or not (15 < uv[0] < 737 and 15 < uv[1] < 465) for uv, z in proj):
            continue
        m = k // 9 * 9  # 3 x 3 corners per marker: its normal must face the camera
        n = np.cross(corners[m + 3] - corners[m], corners[m + 1] - corners[m])
        to_cam = rig.pose[t][0][1] - p_w
        if abs(n @ to_cam) < 0.5 * np.linalg.norm(n) * np.linalg.norm(to_cam):
            continue
        refined = []
        for i in range(2):
            pt = np.array([[proj[i][0] + np.array([1.0, -0.7])]], np.float32)  # start off the corner
            cv2.cornerSubPix(images[i], pt, (4, 4), (-1, -1), crit)
            refined.append(pt[0, 0].astype(float))
            errors[i].append(refined[i] - proj[i][0])
        disparity.append((refined[0][0] - refined[1][0]) - (proj[0][0][0] - proj[1][0][0]))
for i in range(2):
    e = np.array(errors[i])
    print(f'cam{i}: {len(e)} corners, error (u, v) mean {e.mean(0).round(3)} median {np.median(e, 0).round(3)} px')
d = np.array(disparity)
print(f'disparity error (measured - predicted): mean {d.mean():+.3f} median {np.median(d):+.3f} px')
