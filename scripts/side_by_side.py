#!/usr/bin/env python3
"""hooke against the peer implementations (../shared/peer), side by side.

The machines this was measured on are noisy (the same binary has measured 112 and 196 M
spring updates/s a minute apart), so a figure is only worth comparing with one measured in the
same minutes. This runs each contender once per round, alternating, for several rounds, and
prints the range and median of each: the 256x256 cloth, f64, symplectic Euler, damping and
ground on. A round's figure is measured alike for both: bench_taichi.py reports the best of its
three timed runs (its --repeat 3), so hooke's is the best of three runs too (--hooke-repeat).

    cargo build --release
    ../shared/peer/setup.sh                      # the peers' Python environment, once
    scripts/side_by_side.py --rounds 8           # hooke and Taichi at 1 and 2 threads
    scripts/side_by_side.py --rounds 3 --all     # also Warp (CPU) and NumPy, 1 thread
    scripts/side_by_side.py --baseline OLD --no-peers   # this build against another, alone

Standard library only. Exits 2 with a message when a contender cannot be run.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rounds", type=int, default=8, help="alternating rounds (default 8)")
    p.add_argument("--threads", default="1,2", help="thread counts, comma-separated (default 1,2)")
    p.add_argument("--hooke", default=os.path.join(ROOT, "target", "release", "hooke"),
                   help="the hooke binary (default target/release/hooke)")
    p.add_argument("--peer", default=os.path.join(ROOT, "..", "shared", "peer"),
                   help="the peer directory, with its .venv (default ../shared/peer)")
    p.add_argument("--all", action="store_true", help="also Warp and NumPy (one thread each)")
    p.add_argument("--baseline", help="another hooke binary (an earlier commit's), measured in "
                   "the same alternating rounds")
    p.add_argument("--no-peers", action="store_true",
                   help="hooke (and the baseline) alone, without the peer environment")
    p.add_argument("--hooke-repeat", type=int, default=3,
                   help="hooke runs per round, the best kept: the Taichi peer's own protocol "
                        "(bench_taichi.py --repeat, default 3); 1 for a single run (default 3)")
    a = p.parse_args()
    try:
        a.threads = [int(t) for t in a.threads.split(",")]
    except ValueError:
        p.error(f"--threads: not a comma-separated list of integers: {a.threads!r}")
    if a.rounds < 1 or a.hooke_repeat < 1 or any(t < 1 for t in a.threads):
        p.error("--rounds, --hooke-repeat and every --threads value must be at least 1")
    return a


def machine():
    """The CPU as /proc/cpuinfo names it: model, family/model numbers, widest vector extension,
    and the cores this process may use (what `hooke bench` prints beside its figures)."""
    info = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, _, value = line.partition(":")
                info.setdefault(key.strip(), value.strip())
    except OSError:
        return "unknown CPU"
    flags = info.get("flags", "").split()
    simd = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "no AVX2"
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return (f"{info.get('model name', 'unknown CPU')} (family {info.get('cpu family', '?')}, "
            f"model {info.get('model', '?')}, {simd}), {cores} cores")


def fail(msg):
    print(f"side_by_side: {msg}", file=sys.stderr)
    sys.exit(2)


def last_json(cmd, cwd=None):
    """Runs cmd and returns its last JSON line, parsed."""
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd)
    lines = [l for l in r.stdout.splitlines() if l.startswith("{")]
    if r.returncode != 0 or not lines:
        fail(f"{' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()[-400:]}")
    return json.loads(lines[-1])


def main():
    a = parse_args()
    python = os.path.join(a.peer, ".venv", "bin", "python")
    if not os.access(a.hooke, os.X_OK):
        fail(f"no hooke binary at {a.hooke}: run `cargo build --release` first")
    if a.baseline and not os.access(a.baseline, os.X_OK):
        fail(f"no baseline binary at {a.baseline}")
    if not a.no_peers and not os.access(python, os.X_OK):
        fail(f"no peer environment at {python}: run {os.path.join(a.peer, 'setup.sh')} first")
    scene = os.path.join(ROOT, "assets", "scenes", "bench", "cloth256.ron")
    peer = lambda script, steps, t: [python, os.path.join(a.peer, script), "--size", "256", "256",
                                     "--steps", str(steps), "--threads", str(t), "--fp", "64"]
    # (name, threads, command, runs per round: the best is kept)
    contenders = []
    for t in a.threads:
        run = ["run", "--scene", scene, "--steps", "600", "--threads", str(t), "--json"]
        contenders.append(("hooke", t, [a.hooke] + run, a.hooke_repeat))
        if a.baseline:
            contenders.append(("hooke-baseline", t, [a.baseline] + run, a.hooke_repeat))
        if not a.no_peers:
            contenders.append(("taichi-gather", t, peer("bench_taichi.py", 575, t), 1))
    if a.all and not a.no_peers:
        contenders.append(("warp-cpu", 1, peer("bench_warp.py", 300, 1), 1))
        contenders.append(("numpy", 1, peer("bench_numpy.py", 40, 1), 1))
    results = {(name, t): [] for name, t, _, _ in contenders}
    for r in range(a.rounds):
        for name, t, cmd, runs in contenders:
            best = max(last_json(cmd)["spring_updates_per_s"] for _ in range(runs))
            results[(name, t)].append(best / 1e6)
        print(f"round {r + 1}/{a.rounds} done", file=sys.stderr)
    print(f"on {machine()}")
    peers = "" if a.no_peers else " and of Taichi's 3 timed runs"
    print("M spring updates/s, 256x256 cloth, f64, symplectic Euler; range (median) over "
          f"{a.rounds} alternating rounds; a round's figure is the best of hooke's "
          f"{a.hooke_repeat} run(s){peers}")
    print(f"{'implementation':15s} {'threads':>7s} {'min':>7s} {'median':>7s} {'max':>7s}")
    for (name, t), v in results.items():
        print(f"{name:15s} {t:7d} {min(v):7.1f} {statistics.median(v):7.1f} {max(v):7.1f}")


if __name__ == "__main__":
    main()
