#!/usr/bin/python3
"""`idyvins run` stopped by signals into an existing output folder (CTest).

signal_check.py IDYVINS WORK

A first run (--frames 30) fills OUT. Runs into the same OUT are then stopped by SIGTERM and SIGINT
at several points, and killed by SIGKILL at several points. After each, OUT holds one run, never a
mix: either the previous one unchanged (killed, or stopped before the handler was in place, or stopped
before the first frame with exit 128+signal), or the new one complete, or the new one marked partial
("partial": true, "stopped_by") with exit 128+signal;
every file of the set present, none under a temporary name, trajectory.tum and state.csv with as
many poses as stats.json says.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import time

FILES = {"trajectory.tum", "trajectory.csv", "state.csv", "stats.json", "resets.csv", "map_static.ply",
         "map_dynamic.ply", "map_all.ply", "run.json", "groundtruth.tum", "map_static_on_moving.ply",
         "idyvins_manifest.json"}
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def rows(path):
    return len([l for l in open(path) if l.strip() and not l.startswith("#")])


def snapshot(out):
    return {f: open(os.path.join(out, f), "rb").read() for f in sorted(os.listdir(out))}


def consistent(out, what):
    names = set(os.listdir(out))
    check(names == FILES, "%s: the output set exactly (%s)" % (what, sorted(names ^ FILES) or "same"))
    if names != FILES:
        return None
    s = json.load(open(os.path.join(out, "stats.json")))["summary"]
    check(rows(os.path.join(out, "trajectory.tum")) == s["poses"] == rows(os.path.join(out, "state.csv")),
          "%s: trajectory.tum, state.csv and stats.json from one run (%d poses)" % (what, s["poses"]))
    return s


def main(idy, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    seq, out = os.path.join(work, "seq"), os.path.join(work, "out")
    r = subprocess.run([idy, "simulate", "--scene", "city", "--level", "mid", "--seed", "3", "--duration", "6",
                        "--out", seq], capture_output=True, text=True)
    check(r.returncode == 0, "simulate")
    cmd = [idy, "run", "-c", os.path.join(seq, "config", "sim_stereo_imu_config.yaml"), "-d", seq, "-o", out,
           "--mode", "idy"]
    check(subprocess.run(cmd + ["--frames", "30"], capture_output=True).returncode == 0, "first run fills OUT")
    first = snapshot(out)
    for sig, delay in [(signal.SIGTERM, 0.2), (signal.SIGTERM, 1.5), (signal.SIGINT, 2.5), (signal.SIGTERM, 4.0),
                       (signal.SIGKILL, 0.5), (signal.SIGKILL, 1.5), (signal.SIGKILL, 3.0)]:
        before = snapshot(out)
        p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        time.sleep(delay)
        p.send_signal(sig)
        _, err = p.communicate(timeout=120)
        what = "%s after %.1f s (exit %d)" % (signal.Signals(sig).name, delay, p.returncode)
        s = consistent(out, what)
        if p.returncode == 0:  # finished before the signal
            check(s is not None and not s["partial"], what + ": complete")
        elif p.returncode == 128 + sig and "before the first frame" in err:  # a loaded machine: nothing written
            check(snapshot(out) == before, what + ": stopped before the first frame, OUT still the previous run")
        elif p.returncode == 128 + sig:
            check(s is not None and s["partial"] and s["stopped_by"] == signal.Signals(sig).name,
                  what + ": marked partial, stopped by %s" % signal.Signals(sig).name)
            check("partial result" in err, what + ": says so: " + err.strip()[-120:])
        else:  # killed (SIGKILL, or a signal before the handler): the previous run untouched
            check(p.returncode == -sig, what + ": killed by the signal")
            check(snapshot(out) == before, what + ": OUT still the previous run, byte for byte")
        for leftover in [d for d in os.listdir(work) if d.startswith("out.partial-")]:
            shutil.rmtree(os.path.join(work, leftover))  # what a killed run leaves beside OUT
    check(first != snapshot(out), "the new runs did replace the first one")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
