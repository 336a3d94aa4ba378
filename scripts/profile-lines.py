#!/usr/bin/env python3
"""Where a CPU render's time goes, by source file of pathstream's own code.

The render loop is one function with everything inlined into it
(`span_avx2` and friends), so `perf report` sees one symbol. This script
reads perf's samples, asks addr2line for each sample's chain of inlined
frames, and charges the sample to the innermost frame in `server/src/`:
a table by file and by line. A sample whose chain passes through
`World::intersect`, or that falls in the out-of-line traversal of a BVH
world (`World::nearest_avx512` and its twins), counts as a nearest-hit
query ("rays"), any other as the work around the rays (camera, shading,
light sampling, film). An inlined query (a scan of spheres and quads)
inside `integrator::nee` is a shadow ray, any other a path ray; the
out-of-line traversal's samples do not say which ray they serve.

Needs perf and binutils (`apt-get install linux-perf binutils`), and a
binary with line tables:

    cargo build --profile profiling -p pathstream
    perf record -e cpu-clock -F 2000 -o /tmp/perf.data \\
        target/profiling/pathstream render --scene cornell-mesh \\
        --width 128 --height 128 --spp 256 --max-depth 6 --rr-depth 5 \\
        --filter box --backend cpu --adaptive off --out /tmp/p.pfm
    python3 scripts/profile-lines.py target/profiling/pathstream /tmp/perf.data

Not part of the tests; docs/BENCHMARKS.md ("Where a cornell-mesh sample's
time goes") has its output.
"""

import argparse
import collections
import re
import subprocess


def samples(perf_data):
    """(symbol, offset) -> count for the samples in pathstream's functions."""
    out = subprocess.run(
        ["perf", "script", "-i", perf_data, "-F", "ip,sym,symoff"],
        capture_output=True, text=True, check=True,
    ).stdout
    counts = collections.Counter()
    for line in out.splitlines():
        m = re.search(r"(pathstream::\S+)\+0x([0-9a-f]+)", line)
        if m:
            counts[(m.group(1), int(m.group(2), 16))] += 1
    return counts


def symbol_addresses(binary):
    """Demangled symbol -> address, for the functions perf named."""
    out = subprocess.run(
        ["nm", "-C", binary], capture_output=True, text=True, check=True
    ).stdout
    addr = {}
    for line in out.splitlines():
        m = re.match(r"([0-9a-f]+) [tT] (.*)$", line)
        if m:
            # nm -C keeps the hash suffix perf drops.
            name = re.sub(r"::h[0-9a-f]{16}$", "", m.group(2))
            addr.setdefault(name, int(m.group(1), 16))
    return addr


def frames(binary, addresses):
    """Per address, its inlined frames innermost first: (function, file:line)."""
    text = "\n".join(hex(a) for a in addresses)
    out = subprocess.run(
        ["addr2line", "-e", binary, "-i", "-f", "-C", "-a"],
        input=text, capture_output=True, text=True, check=True,
    ).stdout.splitlines()
    chains, chain = [], None
    i = 0
    while i < len(out):
        if out[i].startswith("0x"):
            chain = []
            chains.append(chain)
            i += 1
            continue
        chain.append((out[i], out[i + 1] if i + 1 < len(out) else "?"))
        i += 2
    return chains


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("binary")
    ap.add_argument("perf_data")
    ap.add_argument("--lines", type=int, default=25, help="top lines to list")
    args = ap.parse_args()

    counts = samples(args.perf_data)
    addr = symbol_addresses(args.binary)
    keys = [k for k in counts if k[0] in addr]
    chains = frames(args.binary, [addr[s] + off for s, off in keys])
    total = sum(counts.values())
    by_file, by_line, kind, around, split = (collections.Counter() for _ in range(5))
    for key, chain in zip(keys, chains):
        n = counts[key]
        ours = [(f, loc) for f, loc in chain if "/server/src/" in loc]
        loc = ours[0][1] if ours else (chain[0][1] if chain else "?")
        loc = loc.split("/server/src/")[-1].split(" ")[0]
        by_line[loc] += n
        by_file[loc.split(":")[0]] += n
        # A BVH world's traversal is a function of its own per instruction
        # set (`World::nearest_avx512` and its twins), which the sample
        # cannot tell a shadow ray's from a path ray's; a scan of spheres
        # and quads, and the camera rays' packets, stay inlined.
        out_of_line = "World::nearest" in key[0]
        # Methods in an `impl` block inlined elsewhere are named
        # `<impl ...::World>::intersect_packet`.
        rays = out_of_line or any(re.search(r"World>?::intersect", f) for f, _ in chain)
        kind["rays (World::intersect and World::nearest_*)" if rays else "around the rays"] += n
        if out_of_line:
            split["rays: out of line (shadow and path rays together)"] += n
        elif rays:
            # A shadow ray's query is inlined into next-event estimation.
            shadow = any("integrator::nee::" in f for f, _ in chain)
            split["rays: shadow (integrator::nee)" if shadow else "rays: path"] += n
        if not rays:
            around[loc.split(":")[0]] += n
    unattributed = total - sum(kind.values())
    if unattributed:
        kind["outside pathstream's code"] += unattributed

    def table(title, counter, limit=None):
        print(f"| {title} | share |\n| --- | ---: |")
        for name, n in counter.most_common(limit):
            print(f"| {name} | {100 * n / total:.1f}% |")
        print()

    print(f"{total} samples\n")
    table("part", kind)
    table("rays by kind", split)
    table("file", by_file)
    table("file (around the rays only)", around)
    table("line", by_line, args.lines)


if __name__ == "__main__":
    main()
