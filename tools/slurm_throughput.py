#!/usr/bin/env python3
"""Throughput of a sharded render on a one-node Slurm cluster, and the figures of the
cost model in docs/cluster.md.

    python3 tools/slurm_throughput.py [--scene pbrt-scenes/v3/caustic-ring.pbrt]
        [--passes 128] [--tasks 1,2,4] [--runs 3] [--out target/slurm-bench]

Starts tools/slurm/local-cluster.sh with as many CPUs as the machine has, then, round
after round, submits `pbrt-sppm plan --slurm` scripts with 1, 2 and 4 shards of one CPU
each and times submit-to-merged-image. Prints medians (and ranges) beside the same
render without Slurm, and the cost model's terms: scene loading per shard, seconds per
pass on one thread, merge time and part size.
"""
import argparse
import sys
import os
import shutil
import statistics
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "target", "release", "pbrt-sppm")
CLUSTER = os.path.join(ROOT, "tools", "slurm", "local-cluster.sh")


def timed(cmd, **kw):
    t = time.monotonic()
    subprocess.run(cmd, check=True, **kw)
    return time.monotonic() - t


def sharded(o, env, k, run):
    d = os.path.join(o.out, f"k{k}-{run}")
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    script = os.path.join(d, "submit.sh")
    out = os.path.join(d, "image.exr")
    subprocess.run([BIN, "plan", "--slurm", "--passes", str(o.passes), "--shards", str(k), o.scene,
                    "--parts", os.path.join(d, "parts"), "--outfile", out, "--write", script], check=True)
    t = time.monotonic()
    subprocess.run(["sh", script], check=True, env=env, capture_output=True)
    while not os.path.exists(out):
        if time.monotonic() - t > 1800:
            raise SystemExit(f"{d}: no image after 30 minutes")
        time.sleep(0.05)
    return time.monotonic() - t, d


def fmt(v):
    return f"{statistics.median(v):.2f} s ({min(v):.2f}–{max(v):.2f})"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default=os.path.join(ROOT, "pbrt-scenes/v3/caustic-ring.pbrt"))
    ap.add_argument("--passes", type=int, default=128)
    ap.add_argument("--tasks", default="1,2,4")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--out", default=os.path.join(ROOT, "target", "slurm-bench"))
    o = ap.parse_args()
    o.scene = os.path.abspath(o.scene)
    tasks = [int(t) for t in o.tasks.split(",")]
    os.makedirs(o.out, exist_ok=True)
    cluster = os.path.join(o.out, "cluster")
    start = subprocess.run(["sh", CLUSTER, "start", cluster], capture_output=True, text=True)
    if start.returncode != 0:
        raise SystemExit(f"Slurm could not start: {start.stderr.strip()}")
    env = dict(os.environ, SLURM_CONF=os.path.join(cluster, "slurm.conf"),
               PATH=os.environ.get("PATH", "") + ":/usr/sbin")
    try:
        walls = {k: [] for k in tasks}
        plain = {1: [], 2: []}
        last = {}
        for run in range(o.runs):
            for threads in plain:
                img = os.path.join(o.out, "plain.exr")
                plain[threads].append(timed([BIN, "render", o.scene, "--spp", str(o.passes), "--passes",
                                             "independent", "--nthreads", str(threads), "-q", "--outfile", img]))
            for k in tasks:
                w, last[k] = sharded(o, env, k, run)
                walls[k].append(w)
        model(o, plain, walls, last)
    finally:
        subprocess.run(["sh", CLUSTER, "stop", cluster])


def model(o, plain, walls, last):
    print(f"scene {os.path.basename(o.scene)}, {o.passes} independent passes, {o.runs} runs each, median (range)")
    print("| run | wall |")
    print("|---|---|")
    for t, v in plain.items():
        print(f"| no Slurm, one process, {t} thread{'s' if t > 1 else ''} | {fmt(v)} |")
    for k, v in walls.items():
        print(f"| Slurm, {k} shard{'s' if k > 1 else ''} of 1 CPU, then the merge job | {fmt(v)} |")
    # The cost model's terms, measured on one thread.
    one = os.path.join(o.out, "one.part.exr")
    loads, passes = [], []
    for _ in range(o.runs):
        for n in (1, 5):
            t = timed([BIN, "render", o.scene, "--spp", str(o.passes), "--pass-range", f"0..{n}", "--partial",
                       one, "--nthreads", "1", "-q"])
            (loads if n == 1 else passes).append(t)
    per_pass = (statistics.median(passes) - statistics.median(loads)) / 4
    load = statistics.median(loads) - per_pass
    k = max(last)
    parts = sorted(os.path.join(last[k], "parts", f) for f in os.listdir(os.path.join(last[k], "parts"))
                   if f.endswith(".exr"))
    merge = [timed([BIN, "merge", *parts, "--outfile", os.path.join(o.out, "m.exr"), "-q"]) for _ in range(o.runs)]
    size = statistics.mean(os.path.getsize(p) for p in parts)
    print(f"loading and writing per shard (one pass's process minus a pass): {load:.3f} s")
    print(f"per pass on one thread: {per_pass:.3f} s")
    print(f"merge of {len(parts)} parts: {fmt(merge)}")
    print(f"part size: {size / 1e6:.2f} MB")


if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import docsection

    sys.exit(docsection.run(main, "slurm-throughput"))
