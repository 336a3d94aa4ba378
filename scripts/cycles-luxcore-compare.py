#!/usr/bin/env python3
"""pathstream's CPU backend side by side with Blender Cycles and LuxCoreRender.

All three render one triangle scene. The scene is pathstream's own `scenes --json`
output, handed to Blender (`bpy`) and to LuxCore (`pyluxcore`) as the same
f32 vertices, normals, albedos, lamp and camera. They use the same
resolution, samples per pixel, path depth, box pixel filter and threads.
Reported per renderer and sampler:
- samples per second;
- the relative RMS error (`pathstream diff`) at each spp against a long
  render of the same renderer's (its distance from pathstream's is
  printed first: the renderers' own small differences in the scene, which
  would otherwise count as noise);
- the time each needs to reach 1% error.

Cycles and LuxCore are timed without their fixed costs (scene sync, BVH
build, thread start): each renders 1 spp and N spp, and the rate is
(N - 1) samples per pixel over the difference of the two wall times.
pathstream's time is its render's own, which excludes loading the scene.

Not part of the test suite (it needs Blender, LuxCore and minutes). Setup,
once (Python 3.11, which `bpy` 5.0 requires):

    python3 -m venv /tmp/cy && /tmp/cy/bin/pip install bpy pyluxcore numpy
    cargo build --release

Run (from the repository root):

    /tmp/cy/bin/python scripts/cycles-luxcore-compare.py [--scene cornell-mesh]
        [--size 128] [--spp 64,256] [--max-depth 6] [--threads 2]
        [--reference-spp 4096] [--out target/cycles-luxcore-compare]

Depths: pathstream's --max-depth counts scattering events, so direct light
alone is depth 1. In Cycles that is max_bounces 0, and it gets
max_depth - 1. LuxCore's path.pathdepth.total counts path vertices, as
Mitsuba's max_depth does, and gets max_depth + 1. Measured: at max_depth it
lost 1.6% of the reference's mean, at max_depth + 1 it is within 0.1%. Samplers: pathstream's `random` and
`sobol`, Cycles' default (tabulated Sobol-Burley), and LuxCore's `RANDOM`
and `SOBOL`. Adaptive sampling, denoising and clamping are off everywhere.
Russian roulette first decides the 6th bounce in all three (pathstream's
--rr-depth 5, Cycles' min_light_bounces 4, LuxCore's
path.russianroulette.depth 6); before 2026-11-30 Cycles' acted from the
first bounce and LuxCore's a bounce early, each tracing fewer rays per
sample than pathstream.
"""

import argparse
import os
import sys
import time

import numpy as np

from compare_common import (
    RR_DEPTH, add_arguments, diffuse_meshes, measure, own_reference, pathstream_runs,
    scene_and_reference, write_pfm,
)


def camera_frame(cam):
    """The camera's right, up and forward unit vectors."""
    pos, target, up = (np.array(cam[k], dtype=np.float64) for k in ("position", "look_at", "up"))
    fwd = target - pos
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    return right, np.cross(right, fwd), fwd


def object_matrix(obj):
    """The object's translate-and-scale placement as a 4x4 matrix."""
    t = obj.get("transform") or {}
    s = t.get("scale", 1.0)
    s = s if isinstance(s, list) else [s, s, s]
    m = np.diag([s[0], s[1], s[2], 1.0])
    m[:3, 3] = t.get("translate", [0.0, 0.0, 0.0])
    return m


# ---------------------------------------------------------------- Cycles


def cycles_scene(bpy, scene, args):
    """Builds the scene in a fresh Blender file."""
    import mathutils

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    for i, obj, mat in diffuse_meshes(scene):
        data = obj["data"]
        pos = np.array(data["positions"], dtype=np.float32)
        tri = np.array(data["triangles"], dtype=np.int64)
        mesh = bpy.data.meshes.new(f"mesh{i}")
        mesh.from_pydata(pos.tolist(), [], tri.tolist())
        normals = data.get("normals")
        if normals is not None:
            mesh.shade_smooth()
            mesh.normals_split_custom_set_from_vertices(
                np.array(normals, dtype=np.float32).tolist()
            )
        mesh.update()
        m = bpy.data.materials.new(f"mat{i}")
        m.use_nodes = True
        nodes, links = m.node_tree.nodes, m.node_tree.links
        nodes.clear()
        out = nodes.new("ShaderNodeOutputMaterial")
        emission = mat.get("emission", [0.0, 0.0, 0.0])
        if any(c > 0 for c in emission):
            # Both renderers' mesh lights emit from both sides.
            shader = nodes.new("ShaderNodeEmission")
            shader.inputs["Color"].default_value = (*emission, 1.0)
            shader.inputs["Strength"].default_value = 1.0
        else:
            shader = nodes.new("ShaderNodeBsdfDiffuse")
            shader.inputs["Color"].default_value = (*mat["albedo"], 1.0)
        links.new(shader.outputs[0], out.inputs["Surface"])
        mesh.materials.append(m)
        ob = bpy.data.objects.new(f"obj{i}", mesh)
        ob.matrix_world = mathutils.Matrix(object_matrix(obj).tolist())
        sc.collection.objects.link(ob)
    cam = scene["camera"]
    cd = bpy.data.cameras.new("camera")
    cd.sensor_fit = "VERTICAL"
    cd.angle_y = np.radians(cam["vfov_deg"])
    cd.clip_start = cam.get("near_clip") or 0.01
    co = bpy.data.objects.new("camera", cd)
    right, up, fwd = camera_frame(cam)
    m = np.identity(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, up, -fwd, cam["position"]
    co.matrix_world = mathutils.Matrix(m.tolist())
    sc.collection.objects.link(co)
    sc.camera = co
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    sc.world = world
    r = sc.render
    r.engine = "CYCLES"
    r.resolution_x = r.resolution_y = args.size
    r.resolution_percentage = 100
    r.threads_mode = "FIXED"
    r.threads = args.threads
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    c = sc.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.max_bounces = c.diffuse_bounces = args.max_depth - 1
    # Cycles' roulette acts from the start unless told otherwise (with
    # probability sqrt(throughput)); the bounce pathstream's --rr-depth
    # decides first is Cycles' bounce RR_DEPTH, past min_light_bounces.
    c.min_light_bounces = RR_DEPTH - 1
    c.caustics_reflective = c.caustics_refractive = True
    c.blur_glossy = 0.0
    sc.view_settings.view_transform = "Standard"
    return sc


def cycles_once(bpy, sc, spp, seed, exr):
    sc.cycles.samples = spp
    sc.cycles.seed = seed
    sc.render.filepath = exr
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start


def cycles_render(bpy, sc, args, spp, seed, path, timed=True):
    """Renders `spp` samples to `path` (PFM); the seconds the samples took
    beyond the first (untimed: one render, None)."""
    exr = path[: -len(".pfm")] + ".exr"
    if timed:
        cycles_once(bpy, sc, spp, seed, exr)  # warm: kernels, caches
        t1 = cycles_once(bpy, sc, 1, seed, exr)
    tn = cycles_once(bpy, sc, spp, seed, exr)
    img = bpy.data.images.load(exr)
    px = np.array(img.pixels[:], dtype=np.float32).reshape(args.size, args.size, 4)
    bpy.data.images.remove(img)
    write_pfm(path, px[:, :, :3])  # Blender's rows start at the bottom too
    return (tn - t1) * spp / (spp - 1) if timed else None


# ---------------------------------------------------------------- LuxCore


def luxcore_scene(lux, scene, args):
    """The scene as LuxCore properties and meshes.

    LuxCore's image comes out offset by one pixel row from pathstream's and
    Mitsuba's (which agree): at 64x64, 16 spp, its error against the
    reference was 74% as is, 41% with the screen window moved by half a
    pixel and 5.0% by a whole one, against 46% at one and a half pixels. So
    the window is moved by one pixel."""
    s = lux.Scene()
    props = lux.Properties()
    for i, obj, mat in diffuse_meshes(scene):
        data = obj["data"]
        pos = [tuple(v) for v in np.array(data["positions"], dtype=np.float32).tolist()]
        tri = [tuple(t) for t in np.array(data["triangles"], dtype=np.int64).tolist()]
        normals = data.get("normals")
        nrm = [tuple(n) for n in normals] if normals is not None else None
        s.DefineMesh(f"mesh{i}", pos, tri, nrm, None, None, None)
        emission = mat.get("emission", [0.0, 0.0, 0.0])
        p = f"scene.materials.mat{i}"
        props.Set(lux.Property(f"{p}.type", "matte"))
        if any(c > 0 for c in emission):
            props.Set(lux.Property(f"{p}.kd", [0.0, 0.0, 0.0]))
            props.Set(lux.Property(f"{p}.emission", list(emission)))
            props.Set(lux.Property(f"{p}.emission.gain", [1.0, 1.0, 1.0]))
            props.Set(lux.Property(f"{p}.emission.power", 0.0))
            props.Set(lux.Property(f"{p}.emission.efficency", 0.0))
            props.Set(lux.Property(f"{p}.emission.normalizebycolor", False))
        else:
            props.Set(lux.Property(f"{p}.kd", list(mat["albedo"])))
        o = f"scene.objects.obj{i}"
        props.Set(lux.Property(f"{o}.shape", f"mesh{i}"))
        props.Set(lux.Property(f"{o}.material", f"mat{i}"))
        # Column-major, as LuxCore reads a transformation.
        props.Set(lux.Property(f"{o}.transformation", object_matrix(obj).T.ravel().tolist()))
    cam = scene["camera"]
    props.Set(lux.Property("scene.camera.type", "perspective"))
    props.Set(lux.Property("scene.camera.lookat.orig", list(cam["position"])))
    props.Set(lux.Property("scene.camera.lookat.target", list(cam["look_at"])))
    props.Set(lux.Property("scene.camera.up", list(cam["up"])))
    props.Set(lux.Property("scene.camera.fieldofview", cam["vfov_deg"]))
    props.Set(lux.Property("scene.camera.cliphither", cam.get("near_clip") or 0.01))
    dy = -2.0 / args.size  # one pixel: the window spans 2
    props.Set(lux.Property("scene.camera.screenwindow", [-1.0, 1.0, -1.0 + dy, 1.0 + dy]))
    s.Parse(props)
    return s


def luxcore_render(lux, lscene, args, spp, sampler, seed, path, timed=True):
    """As `cycles_render`, with LuxCore's PATHCPU engine."""

    def once(n):
        cfg = lux.Properties()
        for k, v in [
            ("renderengine.type", "PATHCPU"),
            ("sampler.type", sampler),
            ("film.width", args.size),
            ("film.height", args.size),
            ("film.filter.type", "BOX"),
            ("film.filter.width", 0.5),
            ("film.outputs.0.type", "RGB"),
            ("film.outputs.0.filename", "unused.exr"),
            ("path.pathdepth.total", args.max_depth + 1),
            ("path.pathdepth.diffuse", args.max_depth + 1),
            # Counted in path vertices, as pathdepth.total is: one more
            # decides the bounce pathstream's --rr-depth decides first.
            ("path.russianroulette.depth", RR_DEPTH + 1),
            ("path.clamping.variance.maxvalue", 0.0),
            ("batch.haltspp", n),
            ("native.threads.count", args.threads),
            ("renderengine.seed", seed + 1),
        ]:
            cfg.Set(lux.Property(k, v))
        config = lux.RenderConfig(cfg, lscene)
        session = lux.RenderSession(config)
        start = time.perf_counter()
        session.Start()
        # Halt conditions are checked where the statistics are updated.
        while True:
            session.UpdateStats()
            if session.HasDone():
                break
            time.sleep(0.001)
        seconds = time.perf_counter() - start
        session.Stop()
        return config, session, seconds

    if timed:
        once(spp)  # warm
        _, _, t1 = once(1)
    _config, session, tn = once(spp)
    buf = np.zeros(args.size * args.size * 3, dtype=np.float32)
    session.GetFilm().GetOutputFloat(lux.FilmOutputType.RGB, buf)
    # LuxCore's rows start at the bottom, as PFM's do.
    write_pfm(path, buf.reshape(args.size, args.size, 3))
    return (tn - t1) * spp / (spp - 1) if timed else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_arguments(ap, "target/cycles-luxcore-compare", "64,256", 4096)
    ap.add_argument("--only", default="pathstream,cycles,luxcore",
                    help="renderers to run, comma-separated")
    args = ap.parse_args()
    if min(int(s) for s in args.spp.split(",")) < 2 or args.max_depth < 1:
        ap.error("every spp must be at least 2 and --max-depth at least 1")
    only = set(args.only.split(","))
    os.environ["RAYON_NUM_THREADS"] = str(args.threads)
    scene_file, scene, reference = scene_and_reference(args)

    runs = pathstream_runs(args, scene_file) if "pathstream" in only else []
    if "cycles" in only:
        import bpy

        sc = cycles_scene(bpy, scene, args)
        own = own_reference(args, "cycles", lambda spp, path: cycles_render(
            bpy, sc, args, spp, 4242, path, timed=False))
        runs.append(("Cycles", "default",
                     lambda spp, path: cycles_render(bpy, sc, args, spp, 1, path), own))
    if "luxcore" in only:
        # LuxCore probes every OpenCL platform on its own, and its bundled
        # libraries crash in PoCL's (installed for pathstream's tests):
        # hide the platforms from it, as it renders on the CPU here.
        os.makedirs(os.path.join(args.out, "no-opencl"), exist_ok=True)
        os.environ["OCL_ICD_VENDORS"] = os.path.abspath(os.path.join(args.out, "no-opencl"))
        import pyluxcore as lux

        lux.Init(lambda _msg: None)
        lscene = luxcore_scene(lux, scene, args)
        own = own_reference(args, "luxcore", lambda spp, path: luxcore_render(
            lux, lscene, args, spp, "SOBOL", 4242, path, timed=False))
        for sampler in ("RANDOM", "SOBOL"):
            runs.append(("LuxCore", sampler.lower(),
                         lambda spp, path, s=sampler: luxcore_render(
                             lux, lscene, args, spp, s, 1, path), own))
    measure(args, reference, runs)
    sys.stdout.flush()
    if "luxcore" in only:
        # pyluxcore's log callback crashes the interpreter's shutdown.
        os._exit(0)


if __name__ == "__main__":
    main()
