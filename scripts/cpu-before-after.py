#!/usr/bin/env python3
"""Two pathstream builds' CPU speed side by side: M paths/s of each on the
built-in scenes and the mesh scenes, at one thread and at two, in rounds
that alternate the builds (and which goes first), so that a VM whose speed
drifts affects both alike. Prints a Markdown table: each build's median
(range) and the median (range) of the per-round ratio B/A.

Not part of the tests (minutes). Build the two binaries first, e.g. the
commit before a change in a worktree of its own:

    git worktree add /tmp/before <commit>
    (cd /tmp/before && cargo build --release)
    cargo build --release
    python3 scripts/cpu-before-after.py --a /tmp/before/target/release/pathstream \\
        --b target/release/pathstream [--rounds 5] [--threads 1,2] \\
        [--scenes cornell,...] [--mesh-sizes 10000,100000,1000000,4000000]

Scenes are written as JSON by build B (`pathstream scenes --json`), so an
older build A renders the very same scene even where it lacks the name.
Renders: `--size`x`--size`, `--spp` samples, box filter, uniform sampling,
the scene's own quality otherwise (depth, roulette, sampler) as build B
writes it. The mesh sizes are the bumpy spheres of `pathstream bench
--sections meshes` (its "CPU M paths/s" column), each build's own generator.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

SCENES = "cornell,cornell-glass,cornell-quads,smallpt,furnace,cornell-mesh,cornell-glass-mesh"


def run(cmd, threads):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads), PATHSTREAM_LOG="warn")
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{out.stderr}")
    return out.stdout + out.stderr


def render_rate(exe, scene, args, threads, out):
    """M paths/s of one render of `scene` (a JSON file)."""
    text = run([
        exe, "render", "--scene", scene, "--width", str(args.size), "--height",
        str(args.size), "--spp", str(args.spp), "--filter", "box", "--adaptive",
        "off", "--backend", "cpu", "--out", out,
    ], threads)
    m = re.search(r"([0-9.]+) M paths/s", text)
    if not m:
        sys.exit(f"no M paths/s in: {text}")
    return float(m.group(1))


def mesh_rates(exe, sizes, seconds, threads):
    """M paths/s of `bench --sections meshes` per mesh size: its table's
    "CPU M paths/s" column, in the rows that start with a triangle count."""
    text = run([
        exe, "bench", "--backend", "cpu", "--sections", "meshes", "--mesh-sizes",
        sizes, "--throughput-seconds", str(seconds),
    ], threads)
    rates, column = [], None
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if "CPU M paths/s" in cells:
            column = cells.index("CPU M paths/s")
        elif column is not None and re.fullmatch(r"[0-9,]+", cells[0]):
            rates.append(float(cells[column]))
    return rates


def summary(values):
    return f"{statistics.median(values):.3f} ({min(values):.3f}-{max(values):.3f})"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--a", required=True, help="the build before")
    ap.add_argument("--b", required=True, help="the build after")
    ap.add_argument("--scenes", default=SCENES)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", type=int, default=32)
    ap.add_argument("--mesh-sizes", default="10000,100000,1000000,4000000",
                    help="bumpy-sphere sizes ('' for none)")
    ap.add_argument("--mesh-seconds", type=float, default=2.0)
    args = ap.parse_args()
    threads = [int(t) for t in args.threads.split(",")]
    tmp = tempfile.mkdtemp(prefix="before-after-")
    scenes = []
    for name in [n for n in args.scenes.split(",") if n]:
        path = os.path.join(tmp, f"{name}.json")
        with open(path, "w") as f:
            f.write(subprocess.run([args.b, "scenes", "--json", name],
                                   capture_output=True, text=True, check=True).stdout)
        scenes.append((name, path))
    sizes = [s for s in args.mesh_sizes.split(",") if s]
    rows = {}  # (what, threads) -> ([a], [b])
    out = os.path.join(tmp, "out.pfm")
    for r in range(args.rounds):
        order = [("a", args.a), ("b", args.b)]
        if r % 2:
            order.reverse()
        for t in threads:
            for name, path in scenes:
                for which, exe in order:
                    rate = render_rate(exe, path, args, t, out)
                    rows.setdefault((name, t), ([], []))[which == "b"].append(rate)
            if sizes:
                for which, exe in order:
                    rates = mesh_rates(exe, ",".join(sizes), args.mesh_seconds, t)
                    if len(rates) != len(sizes):
                        sys.exit(f"{exe}: {len(rates)} mesh rows for {len(sizes)} sizes")
                    for size, rate in zip(sizes, rates):
                        key = (f"bumpy sphere, {int(size):,} triangles", t)
                        rows.setdefault(key, ([], []))[which == "b"].append(rate)
        print(f"round {r + 1} of {args.rounds} done", file=sys.stderr, flush=True)
    print(f"| scene | threads | A: M paths/s | B: M paths/s | B / A (per round) |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for (what, t), (a, b) in rows.items():
        ratios = [y / x for x, y in zip(a, b)]
        print(f"| {what} | {t} | {summary(a)} | {summary(b)} | {summary(ratios)} |")


if __name__ == "__main__":
    main()
