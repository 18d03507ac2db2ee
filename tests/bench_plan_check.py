#!/usr/bin/env python3
"""bench as independent jobs: `bench --plan` writes a small sweep (standard suite, seed 1, 3 s
sequences, baseline and idy: 16 jobs); one job is killed mid-sweep and GNU parallel (2 slots,
localhost) runs the others; `bench --collect` names the killed job and exits 1; running the plan
again completes only it; one job re-run through the Slurm array script and one through the
Kubernetes Indexed Job's command (their environment variables set by hand); then the collected
results.json is byte-identical to a local `bench` of the same suite. Runs of another commit or
config are refused with one line. Debian's python3 (with yaml).

Usage: bench_plan_check.py IDYVINS_BINARY WORK_DIR SOURCE_DIR"""
import json
import os
import shutil
import subprocess
import sys

import yaml

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def sh(cmd, **kw):
    return subprocess.run(cmd, shell=True, capture_output=True, text=True, **kw)


def finished(out):
    runs = os.path.join(out, "runs")
    return {d: os.stat(os.path.join(runs, d, "stats.json")).st_mtime_ns for d in sorted(os.listdir(runs))
            if os.path.exists(os.path.join(runs, d, "stats.json"))}


def errors(r):
    return [l for l in r.stderr.splitlines() if l.strip()]


def main(idy, work, src):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    data, sharded, local, plan = (os.path.join(work, n) for n in ("data", "sharded", "local", "plan.txt"))
    suite = ["--suite", "standard", "--seeds", "1", "--duration", "3", "--modes", "baseline,idy", "--data", data]
    r = subprocess.run([idy, "bench"] + suite + ["--out", sharded, "--plan", plan], capture_output=True, text=True)
    lines = open(plan).read().splitlines() if r.returncode == 0 else []
    check(r.returncode == 0 and len(lines) == 16 and os.path.exists(os.path.join(sharded, "bench.json")) and
          not os.path.exists(os.path.join(sharded, "runs", "city_none_s1_idy")),
          "--plan: 16 jobs, bench.json, nothing run (%s)" % r.stderr.strip()[-200:])
    # One camera: the same jobs on cam0 alone, each from a copy of its config with num_of_cam 1.
    mono, mono_plan = os.path.join(work, "mono"), os.path.join(work, "mono_plan.txt")
    r = subprocess.run([idy, "bench"] + suite + ["--out", mono, "--plan", mono_plan, "--cameras", "mono"],
                       capture_output=True, text=True)
    jobs = json.load(open(os.path.join(mono, "bench.json")))["jobs"] if r.returncode == 0 else []
    configs = [open(j["config"]).read() for j in jobs]
    check(len(jobs) == 16 and all("\nnum_of_cam: 1\n" in c and "num_of_cam: 2" not in c for c in configs) and
          all(j["config"].startswith(os.path.join(mono, "configs_mono")) for j in jobs),
          "--cameras mono: 16 jobs, each config a copy with num_of_cam 1 (%s)" % r.stderr.strip()[-200:])
    killed = [l for l in lines if "# parking_lot_mid_s1_idy " in l]
    check(len(killed) == 1, "the plan names each job")
    sh("timeout -s KILL 1 bash -c %s" % json.dumps(killed[0]))  # killed mid-run
    rest = os.path.join(work, "rest.txt")
    open(rest, "w").write("\n".join(l for l in lines if l not in killed) + "\n")
    r = sh("parallel --will-cite -j2 < %s" % rest)
    check(r.returncode == 0 and len(finished(sharded)) == 15, "GNU parallel, 2 slots: 15 jobs finished")
    r = subprocess.run([idy, "bench", "--collect", sharded], capture_output=True, text=True)
    named = [l for l in errors(r) if l.startswith("job ")]
    check(r.returncode == 1 and len(named) == 1 and "parking_lot_mid_s1_idy: failed or killed" in named[0],
          "--collect names the killed job and exits 1: %s" % named)
    before = finished(sharded)
    r = sh("parallel --will-cite -j2 < %s" % plan)
    after = finished(sharded)
    check(r.returncode == 0 and len(after) == 16 and all(after[k] == v for k, v in before.items()),
          "the plan run again completes only the killed job")
    # The Slurm array script and the Kubernetes Indexed Job's command, on one job each.
    for name, run in (("city_low_s1_baseline", lambda i: sh("%s/scripts/jobs/bench.sbatch %s" % (src, plan),
                                                            env=dict(os.environ, SLURM_ARRAY_TASK_ID=str(i),
                                                                     SLURM_SUBMIT_DIR=src))),
                      ("city_high_s1_idy", lambda i: k8s(src, plan, i - 1))):
        index = [k for k, l in enumerate(lines, 1) if "# %s " % name in l][0]
        shutil.rmtree(os.path.join(sharded, "runs", name))
        r = run(index)
        check(r.returncode == 0 and os.path.exists(os.path.join(sharded, "runs", name, "stats.json")),
              "job %d (%s) re-run by %s (%s)" % (index, name, "Slurm" if "city_low" in name else "Kubernetes",
                                                 r.stderr.strip()[-200:]))
    r = subprocess.run([idy, "bench", "--collect", sharded], capture_output=True, text=True)
    check(r.returncode == 0, "--collect: every job (%s)" % r.stderr.strip()[-200:])
    r = subprocess.run([idy, "bench"] + suite + ["--out", local, "--jobs", "2"], capture_output=True, text=True)
    same = open(os.path.join(local, "results.json"), "rb").read() == open(os.path.join(sharded, "results.json"),
                                                                          "rb").read()
    check(r.returncode == 0 and same, "results.json of the sharded and the local bench byte-identical")
    for where in (local, sharded):  # the suite page and one page per sequence, from --collect too
        pages = sorted(os.listdir(os.path.join(where, "pages"))) if os.path.isdir(os.path.join(where, "pages")) else []
        suite_page = open(os.path.join(where, "report.html")).read() if os.path.exists(os.path.join(where, "report.html")) else ""
        check(len(pages) == 8 and "Table I" in suite_page and all('href="pages/%s"' % p in suite_page for p in pages),
              "%s: report.html links %d sequence pages" % (os.path.basename(where), len(pages)))
    refusals(idy, sharded)
    return 1 if failures else 0


def k8s(src, plan, completion_index):
    """The Indexed Job's container command, run here with its working dir and index."""
    manifest = yaml.safe_load(open(os.path.join(src, "scripts", "jobs", "bench-k8s.yaml")))
    c = manifest["spec"]["template"]["spec"]["containers"][0]
    cmd = [a.replace("/shared/plan.txt", plan) for a in c["command"]]
    return subprocess.run(cmd, cwd=src, capture_output=True, text=True,
                          env=dict(os.environ, JOB_COMPLETION_INDEX=str(completion_index)))


def refusals(idy, sharded):
    stats = os.path.join(sharded, "runs", "city_mid_s1_idy", "stats.json")
    original = open(stats).read()
    for key, value, expect in (("build", {"commit": "0" * 40}, "mixed commits"),
                               ("config_fnv1a64", "0123456789abcdef", "mixed configs")):
        s = json.loads(original)
        s["summary"][key] = value
        open(stats, "w").write(json.dumps(s))
        r = subprocess.run([idy, "bench", "--collect", sharded], capture_output=True, text=True)
        check(r.returncode == 1 and len(errors(r)) == 1 and expect in r.stderr and "city_mid_s1_idy" in r.stderr,
              "a run of another %s refused: %s" % (key, r.stderr.strip()))
    open(stats, "w").write(original)
    empty = os.path.join(os.path.dirname(sharded), "empty")
    os.makedirs(empty, exist_ok=True)
    r = subprocess.run([idy, "bench", "--collect", empty], capture_output=True, text=True)
    check(r.returncode == 1 and len(errors(r)) == 1 and "bench.json" in r.stderr,
          "--collect of a folder without a sweep: %s" % r.stderr.strip())


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], sys.argv[3]))
