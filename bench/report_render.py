#!/usr/bin/env python3
"""How the report's 3D view copes with large maps (docs/report.md#large-maps).

    bench/report_render.py IDYVINS RUN_DIR WORK [N,N,...]

For each N, a copy of RUN_DIR whose static map is N points (the run's own, repeated with a small
offset), its page (`idyvins report --max-map-points N`), opened in Debian's headless Chromium:
page size, time until drawn, and mean ms per frame while orbiting (software WebGL, SwiftShader:
a pessimistic figure; a GPU draws faster). Prints a markdown table.
"""
import os
import shutil
import subprocess
import sys

exe, run, work = sys.argv[1:4]
sizes = [int(n) for n in (sys.argv[4] if len(sys.argv) > 4 else "100000,300000,1000000,3000000").split(",")]
here = os.path.dirname(os.path.abspath(__file__))
os.makedirs(work, exist_ok=True)
lines = open(os.path.join(run, "map_static.ply")).read().splitlines()
body = lines[lines.index("end_header") + 1:]
header = lines[:lines.index("end_header") + 1]
print("| map points | page MB | drawn in (ms) | ms per frame, orbiting |\n| --- | --- | --- | --- |")
for n in sizes:
    d = os.path.join(work, f"map_{n}")
    shutil.rmtree(d, ignore_errors=True)
    shutil.copytree(run, d)
    with open(os.path.join(d, "map_static.ply"), "w") as f:
        f.write("\n".join(h if not h.startswith("element vertex") else f"element vertex {n}" for h in header) + "\n")
        for i in range(n):
            x, y, z, *rest = body[i % len(body)].split()
            k = i // len(body)
            f.write(f"{float(x) + 0.01 * (k % 7):.4f} {float(y) + 0.01 * (k % 5):.4f} {float(z):.4f} {' '.join(rest)}\n")
    page = os.path.join(d, "report.html")
    subprocess.run([exe, "report", d, "--html", page, "--max-map-points", str(n + 100000)], check=True, capture_output=True)
    out = subprocess.run(["node", os.path.join(here, "report_render.mjs"), page], capture_output=True, text=True, check=True)
    drawn, per_frame = out.stdout.split()
    print(f"| {n:,} | {os.path.getsize(page) / 1e6:.1f} | {float(drawn):.0f} | {float(per_frame):.1f} |", flush=True)
