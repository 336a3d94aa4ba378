#!/usr/bin/env python3
"""pathstream's CPU backend side by side with Mitsuba 3 on one triangle scene
(`cornell-mesh` by default; `--scene cornell-mesh-specular` for its mirror
and glass balls).

Both render the same scene (pathstream's own `scenes --json` output, turned
into a Mitsuba scene here: the same f32 vertices, normals, albedos, lamp and
camera) at the same resolution, samples per pixel, path depth and pixel
filter, on the same threads. Reported per renderer and sampler: samples per
second (render time only: Mitsuba's first render, which compiles its
kernels, is not timed) and the relative RMS error (`pathstream diff`)
against a long reference of the same renderer's, then the time each needs
to reach 1% error. How far Mitsuba's reference is from pathstream's is
printed first: the two renderers' own small differences in the scene,
which would otherwise count as error in every Mitsuba image.

Not part of the test suite (it needs Mitsuba and minutes). Setup, once:

    apt-get install -y libllvm19          # Mitsuba's llvm variants
    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    cargo build --release

Run (from the repository root):

    /tmp/mi/bin/python scripts/mitsuba-compare.py [--scene cornell-mesh]
        [--size 128] [--spp 64,256,1024] [--max-depth 6] [--threads 2]
        [--reference-spp 8192] [--out target/mitsuba-compare]
        [--variant llvm_ad_rgb|scalar_rgb]

`llvm_ad_rgb` (the default) traces wide batches of paths; `scalar_rgb`
one path at a time, which shows what the batches are worth.

Depths: pathstream's --max-depth counts scattering events, Mitsuba's
max_depth path vertices, so Mitsuba gets max_depth + 1. Russian roulette
starts after 5 bounces in both: pathstream's --rr-depth 5, Mitsuba's
rr_depth 6 (it counts vertices too; its rr_depth 5 would let roulette end
paths a bounce earlier, trading fewer rays for more noise). Samplers: pathstream's `random` against
Mitsuba's `independent`, its `sobol` (Owen-scrambled) against Mitsuba's
`multijitter` and `ldsampler`.
"""

import argparse
import os
import sys
import time

import numpy as np

from compare_common import (
    RR_DEPTH, add_arguments, diffuse_meshes, measure, own_reference, pathstream_runs,
    scene_and_reference,
)


def mitsuba_bsdf(mat):
    """pathstream's material as Mitsuba's BSDF: diffuse; a mirror as a
    conductor with no Fresnel falloff (`material: none`) tinted by the
    albedo; smooth glass as a dielectric of the same index, its exact
    Fresnel split, both lobes tinted by the albedo."""
    albedo = {"type": "rgb", "value": mat.get("albedo", [1.0, 1.0, 1.0])}
    if mat["type"] == "glass":
        if mat.get("fresnel", "exact") != "exact":
            sys.exit("only glass with exact Fresnel is compared")
        return {
            "type": "dielectric",
            "int_ior": mat.get("ior", 1.5),
            "ext_ior": 1.0,
            "specular_reflectance": albedo,
            "specular_transmittance": albedo,
        }
    # pathstream's opaque surfaces reflect on both sides, Mitsuba's on
    # their front only.
    if mat["type"] == "mirror":
        inner = {"type": "conductor", "material": "none", "specular_reflectance": albedo}
    else:
        inner = {"type": "diffuse", "reflectance": albedo}
    return {"type": "twosided", "bsdf": inner}


def mitsuba_scene(mi, scene, args, out_dir):
    """The scene JSON as a Mitsuba scene: meshes through PLY files written
    by Mitsuba itself, so that both read the same f32 data."""
    import drjit as dr

    d = {
        "type": "scene",
        "integrator": {
            "type": "path",
            "max_depth": args.max_depth + 1,
            # Mitsuba's rr_depth counts vertices: one more decides the
            # bounce pathstream's --rr-depth decides first.
            "rr_depth": RR_DEPTH + 1,
        },
    }
    cam = scene["camera"]
    d["sensor"] = {
        "type": "perspective",
        "fov": cam["vfov_deg"],
        "fov_axis": "y",
        "near_clip": cam.get("near_clip") or 0.01,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=cam["position"], target=cam["look_at"], up=cam["up"]
        ),
        "film": {
            "type": "hdrfilm",
            "width": args.size,
            "height": args.size,
            "rfilter": {"type": "box"},
            "pixel_format": "rgb",
        },
        "sampler": {"type": "independent"},
    }
    for i, obj, mat in diffuse_meshes(scene, ("diffuse", "mirror", "glass")):
        data = obj["data"]
        pos = np.array(data["positions"], dtype=np.float32)
        tri = np.array(data["triangles"], dtype=np.uint32)
        emitting = any(c > 0 for c in mat.get("emission", [0, 0, 0]))
        if emitting:
            # Mitsuba's area lights emit on the front side only; the lamp
            # faces the room (pathstream's emitters are two-sided, and the
            # side facing up lights nothing).
            a, b, c = pos[tri[0, 0]], pos[tri[0, 1]], pos[tri[0, 2]]
            if np.cross(b - a, c - a)[1] > 0:
                tri = tri[:, [0, 2, 1]]
        normals = data.get("normals")
        mesh = mi.Mesh(
            f"mesh{i}", len(pos), len(tri), has_vertex_normals=normals is not None
        )
        params = mi.traverse(mesh)
        # Scalar variants hold a mesh's buffers as dynamic scalar arrays.
        floats, ints = (
            (dr.scalar.ArrayXf, dr.scalar.ArrayXu)
            if mi.variant().startswith("scalar")
            else (mi.Float, mi.UInt32)
        )
        params["vertex_positions"] = floats(pos.ravel())
        params["faces"] = ints(tri.ravel())
        if normals is not None:
            params["vertex_normals"] = floats(np.array(normals, dtype=np.float32).ravel())
        params.update()
        ply = os.path.join(out_dir, f"mesh{i}.ply")
        mesh.write_ply(ply)
        shape = {
            "type": "ply",
            "filename": ply,
            "face_normals": normals is None,
            "bsdf": mitsuba_bsdf(mat),
        }
        t = obj.get("transform")
        if t:
            m = mi.ScalarTransform4f().translate(t.get("translate", [0, 0, 0]))
            s = t.get("scale", 1.0)
            shape["to_world"] = m @ mi.ScalarTransform4f().scale(
                s if isinstance(s, list) else [s, s, s]
            )
        if emitting:
            shape["emitter"] = {
                "type": "area",
                "radiance": {"type": "rgb", "value": mat["emission"]},
            }
        d[f"shape{i}"] = shape
    return d


def mitsuba_render(mi, dr, scene_dict, args, spp, sampler, seed, path):
    scene_dict = dict(scene_dict)
    sensor = dict(scene_dict["sensor"])
    sensor["sampler"] = {"type": sampler, "sample_count": spp}
    scene_dict["sensor"] = sensor
    scene = mi.load_dict(scene_dict)
    # The first render compiles Mitsuba's kernels for this scene and spp;
    # the second, timed, reuses them.
    img = mi.render(scene, spp=spp, seed=seed + 1000)
    dr.eval(img)
    dr.sync_thread()
    start = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    seconds = time.perf_counter() - start
    mi.Bitmap(img).write(path)
    # multijitter and ldsampler round the count up (to a product of two
    # close integers, or a power of four): the samples actually taken.
    return seconds, scene.sensors()[0].sampler().sample_count()


def mitsuba_reference(mi, dr, scene_dict, args, path):
    """One untimed render of `args.reference_spp` (multijitter) to `path`."""
    scene_dict = dict(scene_dict)
    sensor = dict(scene_dict["sensor"])
    sensor["sampler"] = {"type": "multijitter", "sample_count": args.reference_spp}
    scene_dict["sensor"] = sensor
    img = mi.render(mi.load_dict(scene_dict), spp=args.reference_spp, seed=4242)
    dr.eval(img)
    mi.Bitmap(img).write(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_arguments(ap, "target/mitsuba-compare", "64,256,1024", 8192)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()
    os.environ["RAYON_NUM_THREADS"] = str(args.threads)

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)

    scene_file, scene, reference = scene_and_reference(args)
    d = mitsuba_scene(mi, scene, args, args.out)

    def with_mitsuba(sampler):
        return lambda spp, path: mitsuba_render(mi, dr, d, args, spp, sampler, 1, path)

    own = own_reference(args, "mitsuba", lambda _spp, path: mitsuba_reference(mi, dr, d, args, path))
    runs = pathstream_runs(args, scene_file) + [
        (f"mitsuba {args.variant}", s, with_mitsuba(s), own)
        for s in ("independent", "multijitter", "ldsampler")
    ]
    measure(args, reference, runs)


if __name__ == "__main__":
    main()
