#!/usr/bin/env python3
"""`idyvins report` end to end (CTest ReportInBrowser; docs/report.md).

    report_check.py IDYVINS WORK SOURCE_DIR SHARED_DATA

1. A short simulated city sequence with traffic, run in baseline and idy; their report opened in
   headless Chromium by tests/report/browser_test.mjs (no console errors, the 3D views drew, the
   dynamic layers toggle, numbers equal stats.json); screenshots saved under WORK/screens/.
2. The real EuRoC excerpt (it has no ground truth): the page renders and says why it has no
   ground-truth panels; a run folder without groundtruth.tum given `--groundtruth DATASET`.
3. Damaged and missing run files, runs of two sequences: one clear line each, exit 1, no page.
"""
import json
import os
import shutil
import subprocess
import sys

exe, work, src, shared = sys.argv[1:5]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)


def run(*args, **kw):
    return subprocess.run([exe, *args], capture_output=True, text=True, **kw)


def browser(page, runs, prefix, *flags):
    p = subprocess.run(["node", os.path.join(src, "tests/report/browser_test.mjs"), page, ",".join(runs), prefix, *flags],
                       capture_output=True, text=True)
    print(p.stdout + p.stderr)
    return p.returncode == 0


# 1. simulated sequence with moving cars, baseline and idy side by side
seq = os.path.join(work, "city")
r = run("simulate", "--scene", "city", "--level", "high", "--seed", "1", "--duration", "8", "--out", seq)
check(r.returncode == 0, "simulate: " + r.stderr[-300:])
cfg = os.path.join(seq, "config/sim_stereo_imu_config.yaml")
runs = []
for mode in ("baseline", "idy"):
    out = os.path.join(work, mode)
    r = run("run", "-c", cfg, "-d", seq, "-o", out, "--mode", mode)
    check(r.returncode == 0 and os.path.exists(os.path.join(out, "run.json")) and
          os.path.exists(os.path.join(out, "groundtruth.tum")), f"run {mode} writes run.json and groundtruth.tum")
    runs.append(out)
    ghosts = os.path.join(out, "map_static_on_moving.ply")
    n = int(next(l.split()[2] for l in open(ghosts) if l.startswith("element vertex"))) if os.path.exists(ghosts) else -1
    want = json.load(open(os.path.join(out, "stats.json")))["summary"]["classification"]["static_map_points_on_moving"]
    check(n == want, f"{mode}: map_static_on_moving.ply holds the {want} static-map points on moving objects ({n})")
page = os.path.join(work, "report.html")
r = run("report", *runs, "--html", page)
check(r.returncode == 0 and os.path.exists(page), "report of baseline and idy: " + r.stdout.strip() + r.stderr)
size = os.path.getsize(page) if os.path.exists(page) else 0
check(size > 300_000 and "<script" in open(page).read() and "http" not in open(page).read().split('id="idy-data"')[0][-200:],
      f"one self-contained page ({size} bytes)")
screens = os.path.join(work, "screens")
os.makedirs(screens)
check(browser(page, runs, os.path.join(screens, "demo_")), "browser checks of the simulated runs' page")

# 2. a run without ground truth: the EuRoC excerpt (its state_groundtruth_estimate0 holds no data.csv)
euroc = os.path.join(work, "euroc_no_gt")
os.makedirs(os.path.join(euroc, "mav0"))
for part in ("cam0", "cam1", "imu0", "body.yaml"):
    os.symlink(os.path.join(shared, "euroc_v101_micro/mav0", part), os.path.join(euroc, "mav0", part))
out = os.path.join(work, "euroc_idy")
r = run("run", "-c", os.path.join(src, "config/euroc/euroc_stereo_imu_config.yaml"), "-d", euroc, "-o", out, "--mode", "idy")
check(r.returncode == 0 and not os.path.exists(os.path.join(out, "groundtruth.tum")), "EuRoC excerpt without ground truth runs")
r = run("report", out)
check(r.returncode == 0 and os.path.exists(os.path.join(out, "report.html")), "report without --html writes OUT/report.html")
check(browser(os.path.join(out, "report.html"), [out], os.path.join(screens, "euroc_no_gt_"), "--no-gt"),
      "browser checks of the page without ground truth")

# ... and a run folder without groundtruth.tum given the dataset's ground truth on the command line
bare = os.path.join(work, "baseline_bare")
shutil.copytree(runs[0], bare)
os.remove(os.path.join(bare, "groundtruth.tum"))
page_gt = os.path.join(work, "bare_gt.html")
r = run("report", bare, "--html", page_gt, "--groundtruth", seq)
data = json.loads(open(page_gt).read().split('id="idy-data" type="application/json">')[1].split("</script>")[0]) if r.returncode == 0 else {}
run0 = (data.get("runs") or [{}])[0]
want = json.load(open(os.path.join(runs[0], "stats.json")))["summary"]["ate_rmse_m"]
got = run0.get("ate_stats", {}).get("rmse", -1)
check(r.returncode == 0 and abs(got - want) < 1e-9 and "gt_note" not in run0,
      f"report --groundtruth DATASET: ATE {got} (stats.json {want})")

# 3. missing and damaged files: one line naming the file (and line), exit 1, no page
def broken(name, damage, expect):
    bad = os.path.join(work, "broken_" + name)
    shutil.copytree(runs[1], bad)
    damage(bad)
    html = os.path.join(work, name + ".html")
    r = run("report", bad, "--html", html)
    lines = r.stderr.strip().splitlines()
    check(r.returncode == 1 and len(lines) == 1 and expect in lines[0] and not os.path.exists(html),
          f"{name}: exit {r.returncode}, '{r.stderr.strip()}'")


def truncate(path, keep):
    data = open(path, "rb").read()
    open(path, "wb").write(data[:keep])


broken("no_stats", lambda d: os.remove(os.path.join(d, "stats.json")), "stats.json: missing")
broken("cut_stats", lambda d: truncate(os.path.join(d, "stats.json"), 5000), "stats.json:")
broken("no_trajectory", lambda d: os.remove(os.path.join(d, "trajectory.tum")), "trajectory.tum")
broken("cut_ply", lambda d: truncate(os.path.join(d, "map_dynamic.ply"), 3000), "map_dynamic.ply:")
broken("bad_gt", lambda d: open(os.path.join(d, "groundtruth.tum"), "a").write("1 2 three\n"), "groundtruth.tum:")
r = run("report", runs[0], out, "--html", os.path.join(work, "mixed.html"))
check(r.returncode == 1 and "another sequence" in r.stderr and len(r.stderr.strip().splitlines()) == 1,
      "runs of two sequences refused: " + r.stderr.strip())
r = run("report", os.path.join(work, "nowhere"))
check(r.returncode == 1 and "nowhere" in r.stderr, "a folder that is not there: " + r.stderr.strip())

print(f"{len(failures)} failure(s)" if failures else "all report checks passed")
sys.exit(1 if failures else 0)
