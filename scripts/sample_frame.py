#!/usr/bin/python3
"""Composes one simulated frame and its object-id mask side by side (docs figure).

usage: scripts/sample_frame.py DATASET TIMESTAMP_NS OUT.png
Needs Debian's python3-matplotlib (installed by scripts/setup.sh)."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np

dataset, stamp, out = sys.argv[1], sys.argv[2], sys.argv[3]
img = mpimg.imread(f"{dataset}/mav0/cam0/data/{stamp}.png")
mask = mpimg.imread(f"{dataset}/mav0/cam0/mask/{stamp}.png")
ids = np.rint(mask * 255).astype(int)
fig, axes = plt.subplots(1, 2, figsize=(15, 5.2), dpi=80)
axes[0].imshow(img, cmap="gray", vmin=0, vmax=1)
axes[0].set_title(f"cam0 image, t = {stamp} ns")
overlay = np.dstack([img, img, img])
colors = plt.get_cmap("tab20")
for k in np.unique(ids[ids > 0]):
    overlay[ids == k] = 0.45 * overlay[ids == k] + 0.55 * np.array(colors(k % 20)[:3])
axes[1].imshow(overlay)
axes[1].set_title(f"object-id mask over the image: {100 * (ids > 0).mean():.1f}% on moving vehicles")
for a in axes:
    a.axis("off")
plt.tight_layout(pad=1.2)
plt.savefig(out)
