#!/usr/bin/env python3
"""Where Mitsuba 3's time goes on the comparison scene, and pathstream's.

`mitsuba-compare.py` says how fast each renderer is; this says what each
spends its time on, per sample and thread: Mitsuba's rays (Embree's
nearest-hit queries, `intersect`, and its shadow queries, `occluded`) and
everything else (its JIT-compiled shading for the `llvm` variants, its
plugins for `scalar_rgb`), and pathstream's path rays, shadow rays and
the rest, from the call chain of each perf sample (`ray_kind`): Embree's
packets as the lane loop calls them, or the own BVH's queries.

Mitsuba renders the scene of `mitsuba-compare.py` (the same vertices,
albedos, lamp, camera, depth and filter) once to compile its kernels, then
`--renders` times while `perf record` samples the process; pathstream
renders it under `perf record --call-graph dwarf` too. Each time is divided by the samples
traced, then split by the sampled shares. Not part of the test suite.
Needs what `mitsuba-compare.py` needs, plus perf and binutils
(`apt-get install linux-perf binutils`) and a pathstream built with line
tables (`cargo build --profile profiling -p pathstream`). Run from the
repository root:

    /tmp/mi/bin/python scripts/mitsuba-profile.py [--variant llvm_ad_rgb]
        [--spp 256] [--renders 3] [--scene cornell-mesh] [--size 128]
        [--max-depth 6] [--threads 2]
        [--profiling target/profiling/pathstream] [--exe target/release/pathstream]
        [--depths 1,2,3,4,6 [--repeats 3]]

`--depths` profiles both at each depth and prints what each further
vertex adds: which rays and which shading Mitsuba's lead is made of.
"""

import argparse
import importlib.util
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from compare_common import add_arguments, render_args, run, scene_json  # noqa: E402


def load_compare():
    """`mitsuba-compare.py` as a module (its file name has a dash)."""
    spec = importlib.util.spec_from_file_location(
        "mitsuba_compare", os.path.join(HERE, "mitsuba-compare.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def perf_report(data, sort):
    """(share in per cent, shared object, symbol) per line of a `perf
    report` of `data` sorted by `sort`."""
    out = subprocess.run(
        ["perf", "report", "-i", data, "--sort", sort, "--stdio"],
        capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        m = re.match(r"\s*([0-9.]+)%\s+(.+?)(?:\s+\[[.k]\]\s+(.*))?$", line)
        if m:
            dso = m.group(2).strip()
            dso = "JIT-compiled code" if dso.startswith("[JIT]") else dso
            yield float(m.group(1)), dso, (m.group(3) or "").rstrip()


def perf_shares(data):
    """(share by shared object, share of each Embree query kind) of a
    `perf record` file, in per cent."""
    dsos = {}
    for share, dso, _ in perf_report(data, "dso"):
        dsos[dso] = dsos.get(dso, 0.0) + share
    queries = {"intersect": 0.0, "occluded": 0.0}
    for share, dso, sym in perf_report(data, "dso,sym"):
        for kind in queries:
            if "embree" in dso and sym.endswith("::" + kind):
                queries[kind] += share
    return dsos, queries


def profile_mitsuba(args, scene):
    """Mitsuba's M samples/s over `args.renders` renders and the perf file
    sampled during them."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)
    mc = load_compare()
    d = mc.mitsuba_scene(mi, scene, args, args.out)
    sensor = dict(d["sensor"])
    sensor["sampler"] = {"type": "multijitter", "sample_count": args.spp}
    d = dict(d, sensor=sensor)
    loaded = mi.load_dict(d)
    img = mi.render(loaded, spp=args.spp, seed=1000)  # compiles, untimed
    dr.eval(img)
    dr.sync_thread()
    data = os.path.join(args.out, "mitsuba.perf")
    perf = subprocess.Popen(
        ["perf", "record", "-q", "-e", "cpu-clock", "-F", "2000", "-p",
         str(os.getpid()), "-o", data],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(1.0)  # perf attaches
    start = time.perf_counter()
    for seed in range(args.renders):
        img = mi.render(loaded, spp=args.spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
    seconds = time.perf_counter() - start
    perf.send_signal(2)
    perf.wait()
    samples = args.renders * args.spp * args.size * args.size
    return samples / seconds / 1e6, data


def ray_kind(chain):
    """What a perf sample of pathstream's render was doing, from its call
    chain (innermost frame first, inlined frames included): "path" or
    "shadow" for a ray query (Embree's packets, reached through
    `intersect_lanes` or `occluded_lanes`, or the own BVH's traversal and
    scans, `World::intersect`/`World::nearest_*`), "rest" for the work
    around the rays (the packets' setup in `intersect_lanes` included),
    None outside the render (loading, BVH builds)."""
    text = "\n".join(chain)
    if "backend::cpu::" not in text or "libtbb" in text:
        return None
    query = "libembree" in chain[0] or re.search(
        r"World>?::(intersect|nearest\w*|occluded) ", text)
    if not query:
        return "rest"
    return "shadow" if ("trace_shadows" in text or "integrator::nee::" in text) else "path"


def profile_pathstream(args, scene_file):
    """pathstream's M samples/s and its path and shadow rays' shares of
    the render (per cent), from the call chains of a `perf record`.

    The chains go through Embree's frames (its packets' stacks are large:
    perf copies 64 KiB of stack per sample) and name each ray query's
    caller among the inlined frames: a shadow ray's query is made by
    `trace_shadows` (the lane loop) or `integrator::nee` (pairs)."""
    data = os.path.join(args.out, "pathstream.perf")
    text = run(
        ["perf", "record", "-q", "-e", "cpu-clock", "-F", "1000",
         "--call-graph", "dwarf,65528", "-o", data]
        + render_args(args.profiling, scene_file, args, args.spp,
                      os.path.join(args.out, "p.pfm")))
    rate = float(re.search(r"([0-9.]+) M paths/s", text).group(1))
    script = subprocess.run(["perf", "script", "-i", data, "-F", "ip,sym,dso"],
                            capture_output=True, text=True, check=True).stdout
    counts = {"path": 0, "shadow": 0, "rest": 0}
    for block in script.split("\n\n"):
        chain = [line.strip() for line in block.strip().splitlines() if line.strip()]
        kind = ray_kind(chain) if chain else None
        if kind:
            counts[kind] += 1
    total = max(1, sum(counts.values()))
    return rate, 100 * counts["path"] / total, 100 * counts["shadow"] / total


def parts(args, scene, scene_file):
    """Per sample, microseconds of one thread at `args.max_depth`:
    {renderer: (M samples/s, path rays, shadow rays, the rest)}, and
    Mitsuba's shares by shared object (per cent)."""
    out = {}
    rate, data = profile_mitsuba(args, scene)
    dsos, queries = perf_shares(data)
    us = args.threads / rate / 100
    rest = 100.0 - sum(queries.values())
    out["mitsuba"] = (rate, queries["intersect"] * us, queries["occluded"] * us, rest * us)
    if os.path.exists(args.profiling):
        rate, path, shadow = profile_pathstream(args, scene_file)
        us = args.threads / rate / 100
        out["pathstream"] = (rate, path * us, shadow * us, (100 - path - shadow) * us)
    return out, dsos


def by_depth(args, scene, scene_file):
    """`--depths`: each part's median over `--repeats` runs at each depth,
    then what each further vertex adds. Mitsuba at depth d traces path rays
    1..d+1 (the last for its emission's MIS weight), pathstream 1..d; both
    trace shadow rays and shade at vertices 1..d."""
    depths = [int(d) for d in args.depths.split(",")]
    table = {}
    for d in depths:
        args.max_depth = d
        runs = [parts(args, scene, scene_file)[0] for _ in range(args.repeats)]
        for who in ("mitsuba", "pathstream"):
            if who in runs[0]:
                cols = list(zip(*(r[who] for r in runs)))
                table[(who, d)] = [statistics.median(c) for c in cols]
    print(f"\n{args.scene}, {args.size}x{args.size}, {args.spp} spp, {args.threads} threads, "
          f"median of {args.repeats}; per sample: microseconds of one thread\n")
    print("| depth | renderer | M samples/s | path rays | shadow rays | the rest |")
    print("| ---: | --- | ---: | ---: | ---: | ---: |")
    for (who, d), (rate, path, shadow, rest) in sorted(table.items(), key=lambda kv: kv[0][1]):
        print(f"| {d} | {who} | {rate:.2f} | {path:.3f} | {shadow:.3f} | {rest:.3f} |")
    print("\nWhat each depth adds to the one before (path rays: Mitsuba's ray d+1, "
          "pathstream's ray d):\n")
    print("| depths | renderer | path rays | shadow rays | the rest |")
    print("| --- | --- | ---: | ---: | ---: |")
    for a, b in zip(depths, depths[1:]):
        for who in ("mitsuba", "pathstream"):
            if (who, a) in table:
                x, y = table[(who, a)], table[(who, b)]
                print(f"| {a} to {b} | {who} | {y[1] - x[1]:.3f} | {y[2] - x[2]:.3f} | "
                      f"{y[3] - x[3]:.3f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_arguments(ap, os.path.join(tempfile.gettempdir(), "mitsuba-profile"),
                  "256", 0, rounds=False)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--renders", type=int, default=3)
    ap.add_argument("--profiling", default="target/profiling/pathstream")
    ap.add_argument("--depths", help="a list of depths (1,2,3,4,6): each part by depth")
    ap.add_argument("--repeats", type=int, default=3, help="runs per depth for --depths")
    args = ap.parse_args()
    args.spp = int(args.spp)
    os.environ["RAYON_NUM_THREADS"] = str(args.threads)
    scene_file, scene = scene_json(args)
    if args.depths:
        by_depth(args, scene, scene_file)
        return

    got, dsos = parts(args, scene, scene_file)
    rate, path, shadow, rest = got["mitsuba"]
    per_sample = args.threads / rate  # microseconds of one thread
    print(f"\n{args.scene}, {args.size}x{args.size}, {args.spp} spp, "
          f"{args.threads} threads; per sample: microseconds of one thread\n")
    print("| renderer | M samples/s | part | share | us per sample |")
    print("| --- | ---: | --- | ---: | ---: |")
    rows = [("Embree `intersect`", path), ("Embree `occluded`", shadow)]
    top = sorted(((k, v) for k, v in dsos.items() if "embree" not in k), key=lambda kv: -kv[1])
    rows += [(k, v / 100 * per_sample) for k, v in top[:4]]
    rows.append(("everything but Embree", rest))
    for part, us in rows:
        print(f"| Mitsuba `{args.variant}` | {rate:.2f} | {part} | "
              f"{us / per_sample * 100:.1f}% | {us:.3f} |")
    if "pathstream" in got:
        rate, path, shadow, rest = got["pathstream"]
        per_sample = args.threads / rate
        rows = (("path rays (nearest hit)", path), ("shadow rays (nearest hit)", shadow),
                ("around the rays", rest))
        for part, us in rows:
            print(f"| pathstream (profiling build) | {rate:.2f} | {part} | "
                  f"{us / per_sample * 100:.1f}% | {us:.3f} |")


if __name__ == "__main__":
    main()
