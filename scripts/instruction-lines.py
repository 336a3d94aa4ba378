#!/usr/bin/env python3
"""Instructions per sample of a CPU render, by source line of pathstream's code.

`scripts/profile-lines.py` says where a render's time goes, from perf's
samples; this says how many instructions each line executes, exactly,
from valgrind's callgrind. Time without instructions points at latency;
instructions without purpose point at waste that sampling blurs: the
twenty-fourth session found the alpha test's hash hoisted by LLVM into
every ray's search this way (75 instructions a ray, in scenes without a
single alpha-tested triangle; docs/BENCHMARKS.md, "Instructions per
sample").

Valgrind has no AVX-512: the AVX2 copy of the loops runs (same images,
nearly the same code). One render thread, so that the counts are the
render's alone. Needs valgrind (`apt-get install valgrind`) and a binary
with line tables:

    cargo build --profile profiling -p pathstream
    python3 scripts/instruction-lines.py target/profiling/pathstream \\
        --scene cornell-mesh --width 64 --height 64 --spp 16 \\
        --max-depth 6 --rr-depth 5 --filter box --adaptive off

Arguments after the binary go to `pathstream render` (`--backend cpu`
and `--out` are added). Counts are per sample (pixels x spp); callgrind
collects inside `render_span` only, so the scene's set-up (parsing, the
BVH build) stays out. Not part of the tests.
"""

import argparse
import collections
import os
import re
import subprocess
import tempfile


def run(binary, render_args, out_dir, branches=False):
    """Runs the render under callgrind (simulating branch prediction with
    `branches`); (callgrind file, samples)."""
    cg = os.path.join(out_dir, "callgrind.out")
    # Only inside the render loop: the scene's set-up stays out.
    cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={cg}",
           "--toggle-collect=*render_span*"] + (["--branch-sim=yes"] if branches else []) + [
           binary,
           "render", "--backend", "cpu", "--out", os.path.join(out_dir, "i.pfm")]
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    done = subprocess.run(cmd + render_args, capture_output=True, text=True, env=env, check=True)
    m = re.search(r"(\d+)x(\d+): (\d+) spp", done.stdout + done.stderr)
    if not m:
        raise SystemExit("no 'WxH: N spp' line in the render's output")
    w, h, spp = map(int, m.groups())
    return cg, w * h * spp


def annotate(cg, *flags):
    return subprocess.run(["callgrind_annotate", *flags, cg],
                          capture_output=True, text=True, check=True).stdout


def functions(cg, event):
    """Inclusive counts of `event` in the render's functions."""
    found = {}
    for line in annotate(cg, "--inclusive=yes", f"--show={event}", f"--sort={event}").splitlines():
        # "file.rs:function", or "???:function" in a binary without line tables.
        m = re.match(r"\s*([\d,]+) \(.*?\)\s+(?:\S+?\.rs|\?\?\?):(\S+)", line)
        if m and re.search(r"render_span|World::nearest_|PickTable::pick_point", m.group(2)):
            name = m.group(2).split("::", 3)[-1] if "World" not in m.group(2) else "World::" + m.group(2).split("World::")[-1]
            found[name] = max(found.get(name, 0), int(m.group(1).replace(",", "")))
    return found


def lines(cg, event):
    """(count of `event`, 'file:line', text) for every annotated line of
    server/src."""
    rows, src, lineno = [], None, None
    for line in annotate(cg, "--auto=yes", "--context=0", "--threshold=100",
                         f"--show={event}", f"--sort={event}").splitlines():
        m = re.match(r"-- Auto-annotated source: (.*)", line)
        if m:
            path = m.group(1)
            src = path.split("server/src/", 1)[1] if "server/src/" in path else None
            continue
        m = re.match(r"-- line (\d+) ", line)
        if m:
            lineno = m.group(1)
            continue
        m = re.match(r"\s*([\d,]+) \(\s*[\d.]+%\)\s+(.*)", line)
        if m and src and not m.group(2).startswith("=>") and m.group(2) != "events annotated":
            rows.append((int(m.group(1).replace(",", "")), f"{src}:{lineno}", m.group(2).strip()))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("binary")
    ap.add_argument("--top", type=int, default=40, help="lines to list")
    ap.add_argument("--branches", action="store_true",
                    help="mispredicted conditional branches instead of instructions "
                         "(callgrind's simulated predictor, not the CPU's: where, not how many)")
    args, render_args = ap.parse_known_args()
    event = "Bcm" if args.branches else "Ir"
    what = "mispredicted branches" if args.branches else "instructions"
    digits = 2 if args.branches else 0
    with tempfile.TemporaryDirectory() as out_dir:
        cg, samples = run(args.binary, render_args, out_dir, args.branches)
        print(f"{samples} samples; {what} per sample\n")
        for name, n in sorted(functions(cg, event).items(), key=lambda kv: -kv[1]):
            print(f"{n / samples:9.{digits}f}  {name} (inclusive)")
        rows = lines(cg, event)
    by_file = collections.Counter()
    for n, where, _ in rows:
        by_file[where.rsplit(":", 1)[0]] += n
    print("\nby file (server/src, its own lines; inlined library code not counted):")
    for f, n in by_file.most_common(20):
        print(f"{n / samples:9.{digits}f}  {f}")
    print("\nby line:")
    for n, where, text in sorted(rows, reverse=True)[: args.top]:
        print(f"{n / samples:9.{digits}f}  {where:34s} {text[:80]}")


if __name__ == "__main__":
    main()
