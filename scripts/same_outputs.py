#!/usr/bin/python3
"""Fingerprints of every output of `idyvins run`, to show that a change leaves them as they were.

same_outputs.py record IDYVINS DATA WORK FINGERPRINTS [--quick]
same_outputs.py compare BEFORE AFTER

record renders (once, cached in DATA) the demo sequence (20 s city high, seed 1), a 60 s standard
sequence (city mid, seed 1) and a 60 s validation sequence (parking_lot mid, seed 1), runs every
shipped mode on each with --threads 1 and --threads 2 (two runs at a time, each into WORK), and
writes one line per output file: sequence/mode/threads/file and the SHA-256 of its content. The
timing fields of stats.json (wall clock) and the machine-dependent fields of run.json (command, cwd,
build commit) are left out of the hash; everything else counts, byte for byte. --quick: the demo
sequence only. compare lists every file whose fingerprint differs and exits 1 when one does.
"""
import concurrent.futures
import hashlib
import json
import os
import subprocess
import sys

MODES = ["baseline", "ransac", "seg", "idy", "idy-pre", "idy-ba"]
SEQUENCES = [  # name, simulate arguments
    ("demo_city_high_s1", ["--scene", "city", "--level", "high", "--seed", "1", "--duration", "20"]),
    ("city_mid_s1", ["--scene", "city", "--level", "mid", "--seed", "1", "--duration", "60"]),
    ("validation_parking_lot_mid_s1",
     ["--family", "validation", "--scene", "parking_lot", "--level", "mid", "--seed", "1", "--duration", "60"]),
]
TIMING_SUFFIXES = ("_ms", "wall_s", "realtime_factor")
RUN_JSON_VOLATILE = ("command", "cwd", "build")


def without_timing(value):
    """stats.json content without wall-clock fields (they differ between any two runs)."""
    if isinstance(value, dict):
        return {k: without_timing(v) for k, v in value.items()
                if not k.endswith(TIMING_SUFFIXES) and k != "build"}
    if isinstance(value, list):
        return [without_timing(v) for v in value]
    return value


def file_digest(path):
    name = os.path.basename(path)
    with open(path, "rb") as f:
        data = f.read()
    if name == "stats.json":
        data = json.dumps(without_timing(json.loads(data)), sort_keys=True).encode()
    elif name == "run.json":
        record = json.loads(data)
        data = json.dumps({k: v for k, v in record.items() if k not in RUN_JSON_VOLATILE}, sort_keys=True).encode()
    return hashlib.sha256(data).hexdigest()


def render(idyvins, data, name, args):
    folder = os.path.join(data, name)
    if not os.path.isfile(os.path.join(folder, "meta.json")):
        subprocess.run([idyvins, "simulate", *args, "--out", folder], check=True, stdout=subprocess.DEVNULL)
    return folder


def run_one(idyvins, folder, out, mode, threads):
    config = os.path.join(folder, "config", "sim_stereo_imu_config.yaml")
    cmd = [idyvins, "run", "-c", config, "-d", folder, "-o", out, "--mode", mode, "--threads", str(threads)]
    done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if done.returncode not in (0, 4):
        raise SystemExit(f"{' '.join(cmd)}: exit {done.returncode}: {done.stderr.strip()}")
    return out


def record(idyvins, data, work, fingerprints, quick):
    os.makedirs(data, exist_ok=True)
    jobs = []
    for name, args in SEQUENCES[:1] if quick else SEQUENCES:
        folder = render(idyvins, data, name, args)
        for mode in MODES:
            for threads in (1, 2):
                jobs.append((folder, os.path.join(work, name, mode, f"t{threads}"), mode, threads))
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        outs = list(pool.map(lambda j: run_one(idyvins, *j), jobs))
    lines = []
    for out in outs:
        for file in sorted(os.listdir(out)):
            path = os.path.join(out, file)
            if os.path.isfile(path) and file != "idyvins_manifest.json":
                lines.append(f"{os.path.relpath(path, work)} {file_digest(path)}")
    with open(fingerprints, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"{len(lines)} files of {len(outs)} runs fingerprinted in {fingerprints}")


def compare(before, after):
    def load(path):
        with open(path) as f:
            return dict(line.split() for line in f if line.strip())
    a, b = load(before), load(after)
    differ = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
    for k in differ:
        print(f"differs: {k} ({'missing after' if k not in b else 'new' if k not in a else 'content'})")
    print(f"{len(a)} files before, {len(b)} after, {len(differ)} differ")
    return 1 if differ else 0


def main(argv):
    if len(argv) >= 5 and argv[0] == "record":
        record(argv[1], argv[2], argv[3], argv[4], "--quick" in argv[5:])
        return 0
    if len(argv) == 3 and argv[0] == "compare":
        return compare(argv[1], argv[2])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
