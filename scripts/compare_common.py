"""What the side-by-side comparison scripts share (`mitsuba-compare.py`,
`cycles-luxcore-compare.py`): pathstream's renders and error measure, the
scene and its long reference, PFM output, and the time-to-error summary."""

import json
import math
import os
import re
import subprocess
import sys

import numpy as np


def run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{out.stderr}")
    return out.stdout + out.stderr


# Russian roulette may end pathstream's paths after this many bounces (it
# decides the next one). Renderers that count path vertices (Mitsuba,
# LuxCore) get RR_DEPTH + 1 for the same bounce; Cycles, which counts the
# bounces before the one decided, RR_DEPTH - 1.
RR_DEPTH = 5


def render_args(exe, scene, args, spp, path, adaptive=False):
    """A pathstream `render` of `scene` (a JSON file) to `path` with the
    comparison's settings, less the sampler and seed; uniform sampling
    unless `adaptive` (then `spp` is the mean)."""
    return [
        exe, "render", "--scene", scene, "--width", str(args.size),
        "--height", str(args.size), "--spp", str(spp),
        "--max-depth", str(args.max_depth), "--rr-depth", str(RR_DEPTH),
        "--filter", "box", "--adaptive", "on" if adaptive else "off",
        "--backend", "cpu", "--out", path,
    ]


def pathstream_render(exe, scene, args, spp, sampler, seed, path, adaptive=False):
    """Renders `scene` (a JSON file) to `path`; the render's own seconds."""
    text = run(render_args(exe, scene, args, spp, path, adaptive)
               + ["--sampler", sampler, "--seed", str(seed)])
    m = re.search(r"in ([0-9.]+) s,", text)
    if not m:
        sys.exit(f"no render time in: {text}")
    return float(m.group(1))


def rel_error(exe, reference, image):
    """Relative RMS error of `image` against `reference` (`pathstream diff`)."""
    text = run([exe, "diff", reference, image])
    m = re.search(r"relative RMS error ([0-9.]+)%", text)
    if not m:
        sys.exit(f"no error in: {text}")
    return float(m.group(1)) / 100.0


def write_pfm(path, rgb_bottom_up):
    """A (height, width, 3) float array, its first row the image's bottom
    (PFM's own order), as a little-endian PFM file."""
    h, w, _ = rgb_bottom_up.shape
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        f.write(np.ascontiguousarray(rgb_bottom_up, dtype="<f4").tobytes())


def scene_json(args):
    """pathstream's JSON of `args.scene` with the camera's near clip set to
    `args.near_clip`, written to `args.out`: the file and the parsed scene.

    pathstream starts a camera ray `near_clip` along itself (on a sphere,
    as smallpt does); Mitsuba, Cycles and LuxCore clip on a plane. With
    `cornell-mesh`'s 140 (smallpt's camera, which has to start past
    smallpt's front wall) the top row of pixels meets the ceiling at
    138-141 units along the view axis, so a plane at 140 hides 62% of
    that row's ceiling and a sphere hides almost none: the renderers'
    images differed by 0.42% there alone. `cornell-mesh` has nothing that
    close to the camera, so the default, 0, gives every renderer the same
    picture."""
    os.makedirs(args.out, exist_ok=True)
    scene = json.loads(run([args.exe, "scenes", "--json", args.scene]))
    scene["camera"]["near_clip"] = args.near_clip
    scene_file = os.path.join(args.out, f"{args.scene}.json")
    with open(scene_file, "w") as f:
        json.dump(scene, f)
    return scene_file, scene


def scene_and_reference(args):
    """pathstream's JSON of `args.scene` (written to `args.out`), parsed,
    and the path of its long pathstream reference (rendered once)."""
    scene_file, scene = scene_json(args)
    reference = os.path.join(
        args.out, f"{args.scene}-{args.size}-d{args.max_depth}-nc{args.near_clip:g}"
        f"-ref{args.reference_spp}.pfm"
    )
    if not os.path.exists(reference):
        print(f"reference: pathstream, {args.reference_spp} spp ...", flush=True)
        pathstream_render(args.exe, scene_file, args, args.reference_spp, "sobol", 7, reference)
    return scene_file, scene, reference


def diffuse_meshes(scene, kinds=("diffuse",)):
    """The scene's objects as (index, object, material), after checking that
    every one is a mesh whose material is of one of `kinds` (what a script
    compares: diffuse, or for Mitsuba also mirror and smooth glass)."""
    out = []
    for i, obj in enumerate(scene["objects"]):
        if obj["type"] != "mesh":
            sys.exit(f"object {i}: only meshes are compared (this is {obj['type']})")
        mat = scene["materials"][obj["material"]]
        if mat["type"] not in kinds:
            sys.exit(f"object {i}: only {', '.join(kinds)} materials are compared")
        t = obj.get("transform")
        if t and set(t) - {"translate", "scale"}:
            sys.exit(f"object {i}: only translate and scale transforms are compared")
        out.append((i, obj, mat))
    return out


def time_to(target, rows):
    """Seconds to reach `target` error from the renders (spp, s, error), in
    order of spp, and how it was found. Between the last render above the
    target and the first at or below it, time is interpolated in log-log
    (each sampler's own rate of convergence between the two); outside
    them, the nearest render is extrapolated by error ~ 1/sqrt(time),
    which flatters a sampler that converges faster than that when it is
    the first render that is already below the target."""
    for i, (spp, s, err) in enumerate(rows):
        if err > target:
            continue
        if i == 0:
            return s * (err / target) ** 2, f"below {spp} spp, extrapolated"
        spp0, s0, err0 = rows[i - 1]
        slope = (math.log(s) - math.log(s0)) / (math.log(err) - math.log(err0))
        t = s0 * math.exp((math.log(target) - math.log(err0)) * slope)
        return t, f"between {spp0} and {spp} spp"
    spp, s, err = rows[-1]
    return s * (err / target) ** 2, "extrapolated"


def spread(values, fmt="{:.2f}"):
    """The median of `values`, and their range where there are several."""
    m = fmt.format(float(np.median(values)))
    if len(values) == 1:
        return m
    return f"{m} ({fmt.format(min(values))}-{fmt.format(max(values))})"


def rate_and_time(rows, pixels):
    """One round's renders (spp, s, error) of a run: M samples/s (median
    over its renders) and the time to 1% error with how it was found."""
    rate = float(np.median([spp * pixels / s / 1e6 for spp, s, _ in rows]))
    return (rate, *time_to(0.01, rows))


def print_summary(summary, pixels):
    """Per renderer and sampler: samples/s (median over its renders) and
    the time to 1% error, each the median (range) over the rounds; then
    each other renderer's lead over pathstream, round by round: its
    samples/s over pathstream's Sobol points', and pathstream's adaptive
    time to 1% over its own."""
    rounds = len(summary[0][2])
    print(f"\n{rounds} round(s); median (range) over them")
    print("\n| renderer | sampler | M samples/s (median) | seconds to 1% error |")
    print("| --- | --- | ---: | ---: |")
    found = {}
    for who, sampler, by_round in summary:
        got = [rate_and_time(rows, pixels) for rows in by_round]
        found[(who, sampler)] = got
        hows = sorted({how for _, _, how in got})
        print(f"| {who} | {sampler} | {spread([g[0] for g in got])} "
              f"| {spread([g[1] for g in got])} ({'; '.join(hows)}) |")
    sobol = found.get(("pathstream", "sobol"))
    adaptive = found.get(("pathstream", "sobol-adaptive"))
    if not (sobol and adaptive):
        return
    print("\n| renderer | sampler | samples/s over pathstream sobol | "
          "pathstream adaptive's time to 1% over its |")
    print("| --- | --- | ---: | ---: |")
    for (who, sampler), got in found.items():
        if who == "pathstream":
            continue
        rate = [g[0] / p[0] for g, p in zip(got, sobol)]
        time = [a[1] / g[1] for g, a in zip(got, adaptive)]
        print(f"| {who} | {sampler} | {spread(rate)} | {spread(time)} |")


def add_arguments(ap, out, spp, reference_spp, rounds=True):
    """The options every comparison takes (defaults: `out`, `spp`,
    `reference_spp`), with `--rounds` where the script times renders
    through `measure`."""
    ap.add_argument("--scene", default="cornell-mesh")
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--spp", default=spp)
    ap.add_argument("--max-depth", type=int, default=6)
    ap.add_argument("--near-clip", type=float, default=0.0,
                    help="the camera's near clip for every renderer (see scene_json)")
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--reference-spp", type=int, default=reference_spp)
    ap.add_argument("--exe", default="target/release/pathstream")
    if rounds:
        ap.add_argument("--rounds", type=int, default=1,
                        help="render everything this many times, the runs in turn "
                             "(reversed every other round); times are medians and ranges")
    ap.add_argument("--out", default=out)


def pathstream_runs(args, scene_file):
    """pathstream's two samplers as runs for `measure`, then its Sobol points
    with adaptive sampling (on by default with the `final` and `reference`
    presets), which the other renderers lack: what a user of each waits
    for an image at a given error, not a per-sample comparison."""
    def run_with(sampler, adaptive=False):
        return lambda spp, path: pathstream_render(
            args.exe, scene_file, args, spp, sampler, 1, path, adaptive)
    return [("pathstream", s, run_with(s)) for s in ("random", "sobol")] + [
        ("pathstream", "sobol-adaptive", run_with("sobol", True))
    ]


def own_reference(args, renderer, render):
    """`renderer`'s own long render of the scene (`render(spp, path)` at
    `args.reference_spp`), made once into `args.out` and reused: a
    renderer's error is measured against its own, so that the renderers'
    small differences in the scene do not count as its noise."""
    path = os.path.abspath(os.path.join(
        args.out,
        f"{renderer}-{args.scene}-{args.size}-d{args.max_depth}-nc{args.near_clip:g}"
        f"-ref{args.reference_spp}.pfm",
    ))
    if not os.path.exists(path):
        print(f"{renderer}: rendering its reference ({args.reference_spp} spp) once", flush=True)
        render(args.reference_spp, path)
    return path


def measure(args, reference, runs):
    """Renders each run, (renderer, sampler, render(spp, path) -> seconds,
    or (seconds, the samples per pixel it took) where a sampler rounds the
    count it is asked for), at every spp of `args.spp`, `args.rounds`
    times (the runs in turn, in reverse order every other round, so that a
    machine's drift falls on all of them); prints a row per render, then
    the summary. Rows, rates and times use the spp taken. A run may end
    with a reference of its own renderer's to measure its error against
    (else: `reference`, pathstream's), so that the two renderers' small
    differences in the scene do not count as noise. Every render is
    seeded, so its error is the same in every round: only times vary."""
    spps = [int(s) for s in args.spp.split(",")]
    pixels = args.size * args.size
    print(
        f"\n{args.scene}, {args.size}x{args.size}, max depth {args.max_depth}, box filter, "
        f"{args.threads} threads; error against a {args.reference_spp}-spp reference "
        f"(pathstream's, or the renderer's own where it has one)\n"
    )
    for own in sorted({r[3] for r in runs if len(r) > 3}):
        print(f"{os.path.basename(own)} against pathstream's reference: "
              f"{rel_error(args.exe, reference, own) * 100:.2f}%")
    print("| round | renderer | sampler | spp | seconds | M samples/s | error |")
    print("| ---: | --- | --- | ---: | ---: | ---: | ---: |")
    errors = {}
    by_run = [[] for _ in runs]
    for r in range(args.rounds):
        order = list(range(len(runs)))
        for k in order if r % 2 == 0 else reversed(order):
            who, sampler, render, *own = runs[k]
            rows = []
            for spp in spps:
                name = f"{who.split()[0].lower()}-{sampler}-{spp}.pfm"
                path = os.path.abspath(os.path.join(args.out, name))
                s = render(spp, path)
                s, taken = s if isinstance(s, tuple) else (s, spp)
                if (k, spp) not in errors:
                    errors[(k, spp)] = rel_error(args.exe, own[0] if own else reference, path)
                err = errors[(k, spp)]
                rows.append((taken, s, err))
                print(
                    f"| {r + 1} | {who} | {sampler} | {taken} | {s:.3f} "
                    f"| {taken * pixels / s / 1e6:.2f} | {err * 100:.2f}% |",
                    flush=True,
                )
            by_run[k].append(rows)
    summary = [(who, sampler, by_run[k]) for k, (who, sampler, *_) in enumerate(runs)]
    print_summary(summary, pixels)
    write_results(args, summary)


def write_results(args, summary):
    """`times.csv` in `args.out` (a row per render), and with matplotlib
    installed `time-to-error.png`: error against seconds, log-log, a line
    per renderer and sampler, and the 1% level."""
    path = os.path.join(args.out, "times.csv")
    with open(path, "w") as f:
        f.write("round,renderer,sampler,spp,seconds,error\n")
        for who, sampler, by_round in summary:
            for r, rows in enumerate(by_round):
                for spp, s, err in rows:
                    f.write(f"{r + 1},{who},{sampler},{spp},{s:.4f},{err:.6f}\n")
    print(f"\nrenders: {path}")
    try:
        import matplotlib
    except ImportError:
        print("(no plot: pip install matplotlib)")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    for who, sampler, by_round in summary:
        # Each render's median time over the rounds (its error is the same).
        seconds = np.median([[s for _, s, _ in rows] for rows in by_round], axis=0)
        errors = [100 * err for _, _, err in by_round[0]]
        ax.plot(seconds, errors, marker="o",
                label=f"{who.split()[0]} {sampler}",
                linestyle="-" if who == "pathstream" else "--")
    ax.axhline(1.0, color="grey", linewidth=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"seconds ({args.threads} threads)")
    ax.set_ylabel("relative RMS error, %")
    ax.set_title(f"{args.scene}, {args.size}x{args.size}: error against render time")
    plain = matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(plain)
        axis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(args.out, "time-to-error.png")
    fig.savefig(png)
    print(f"plot: {png}")
