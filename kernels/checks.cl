/* Routine checks: each kernel runs one routine of the path tracer on inputs
 * from the host, which compares the outputs with the routine's Rust twin
 * (server/tests/opencl_parity.rs). Arguments: the output buffer, the item
 * count n, then the inputs; item i < n writes its own outputs only. Scenes
 * are built with designated initialisers: the fields a check leaves out are
 * null, whatever order scene_arrays.h gives them. */

/* The sampler: 8 draws from sampler_new(seed, pixel, sample), given as 3
 * ulongs per item. */
__kernel void check_rng(__global ulong *out, uint n, __global const ulong *in) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Sampler s = sampler_new(in[3 * i], in[3 * i + 1], in[3 * i + 2]);
    for (uint k = 0; k < 8u; ++k) {
        out[8 * i + k] = next_bits(&s);
    }
}

/* A path's numbers by use from sampler_of_kind(sobol, seed, pixel, sample)
 * (4 ulongs per item: sobol, seed, pixel, sample): at vertices 0 and 3,
 * the camera's 2-D, the lens's 2-D, the light pick's 2-D, light 2-D for
 * emitters 0 and 2, the BSDF's choice and 2-D, the roulette: 14 floats per
 * vertex as bits (the pick's x as it is), 28 per item. */
__kernel void check_sampler_uses(__global uint *out, uint n, __global const ulong *in) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Sampler s = sampler_of_kind((int)in[4 * i], in[4 * i + 1], in[4 * i + 2], in[4 * i + 3]);
    __global uint *o = out + 28 * i;
    for (uint k = 0; k < 2u; ++k) {
        at_vertex(&s, 3u * k);
        float2 c = camera_2d(&s);
        float2 lens = lens_2d(&s);
        uint pick;
        float pick_y = light_pick_2d(&s, &pick);
        float2 l0 = light_2d(&s, 0u);
        float2 l2 = light_2d(&s, 2u);
        float b = bsdf_choice(&s);
        float2 d = bsdf_2d(&s);
        float r = roulette(&s);
        uint v[14] = {as_uint(c.x),  as_uint(c.y),    as_uint(lens.x), as_uint(lens.y), pick,
                      as_uint(pick_y), as_uint(l0.x), as_uint(l0.y),   as_uint(l2.x),   as_uint(l2.y),
                      as_uint(b),    as_uint(d.x),    as_uint(d.y),    as_uint(r)};
        for (uint j = 0; j < 14u; ++j) {
            o[14 * k + j] = v[j];
        }
    }
}

/* sincos_turns(u): (sin, cos). */
__kernel void check_sincos(__global float *out, uint n, __global const float *u) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    float2 r = sincos_turns(u[i]);
    vstore2(r, 0, out + 2 * i);
}

/* pixel_offset(P, sample = i, (u[2i], u[2i+1])) with P's filter, stratified
 * as P's sampler is. */
__kernel void check_pixel_offset(__global float *out, uint n, __global const float *u, __global const Params *P) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    float2 r = pixel_offset(P, (ulong)i, (float2)(u[2 * i], u[2 * i + 1]), P->sampler != 0u);
    vstore2(r, 0, out + 2 * i);
}

/* Ray i = (rays[2i].xyz origin, rays[2i+1].xyz unit direction) against every
 * object: its distance to each (the nearer root for spheres), then the
 * nearest hit by intersect() as (t, object index as float bits), through
 * the BVH when P says so. P gives the object count. Outputs per item:
 * num_objects + 2. */
__kernel void check_intersect(__global float *out, uint n, __global const float4 *rays,
                              __global const Object *objects, __global const Params *P,
                              __global const BvhNode *nodes, __global const uint *prims, __global const uint *big) {
    Scene sc = {.P = P, .objects = objects, .nodes = nodes, .prims = prims, .big = big};
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    float3 o = rays[2 * i].xyz;
    float3 d = rays[2 * i + 1].xyz;
    uint count = P->num_objects;
    __global float *r = out + (size_t)i * (count + 2u);
    for (uint j = 0; j < count; ++j) {
        __global const Object *ob = &objects[j];
        r[j] = ob->kind == KIND_SPHERE ? sphere_intersect(ob, o, d, dot3(o, o), dot3(o, d), 0)
                                       : quad_intersect(ob, o, d);
    }
    uint hit;
    r[count] = intersect(&sc, o, d, NO_OBJECT, 0, &hit);
    r[count + 1u] = as_float(hit);
}

/* scatter() off material `material` for direction in[2i].xyz and outward
 * normal in[2i+1].xyz, with the sampler of (seed 0, pixel i, sample 0):
 * (dir.xyz, weight.xyz, specular, 0) per item. */
__kernel void check_scatter(__global float *out, uint n, __global const float4 *in,
                            __global const Material *materials, uint material, __global const float *ggx) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Sampler s = sampler_new(0UL, (ulong)i, 0UL);
    float3 weight;
    int specular;
    Material mat = materials[material]; /* MatRef: private in the generic build */
    float3 dir = scatter_outward(&mat, ggx, in[2 * i].xyz, in[2 * i + 1].xyz, &s, &weight, &specular);
    __global float *r = out + (size_t)i * 8u;
    vstore3(dir, 0, r);
    vstore3(weight, 0, r + 3);
    r[6] = (float)specular;
    r[7] = 0.0f;
}

/* The nearest hit of ray i (as check_intersect's rays) by intersect(),
 * through the BVH when P says so: (t, object index as float bits). */
__kernel void check_nearest(__global float *out, uint n, __global const float4 *rays, __global const Object *objects,
                            __global const Params *P, __global const BvhNode *nodes, __global const uint *prims,
                            __global const uint *big) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.P = P, .objects = objects, .nodes = nodes, .prims = prims, .big = big};
    uint hit;
    out[2 * i] = intersect(&sc, rays[2 * i].xyz, rays[2 * i + 1].xyz, NO_OBJECT, 0, &hit);
    out[2 * i + 1] = as_float(hit);
}

/* The nearest hit of ray i (as check_intersect's rays) in a scene with
 * mesh instances: (t, object, triangle as float bits). */
__kernel void check_nearest_meshes(__global float *out, uint n, __global const float4 *rays,
                                   __global const Object *objects, __global const Params *P,
                                   __global const BvhNode *nodes, __global const uint *prims, __global const uint *big,
                                   __global const Instance *instances, __global const BvhNode *mesh_nodes,
                                   __global const TriVerts *tris, __global const float4 *normals,
                                   __global const uint *slots) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.P = P,
                .objects = objects,
                .nodes = nodes,
                .prims = prims,
                .big = big,
                .instances = instances,
                .mesh_nodes = mesh_nodes,
                .tris = tris,
                .normals = normals,
                .slots = slots};
    Hit h;
    nearest(&sc, rays[2 * i].xyz, rays[2 * i + 1].xyz, NO_OBJECT, NO_PRIM, 0, &h);
    out[3 * i] = h.t;
    out[3 * i + 1] = as_float(h.object);
    out[3 * i + 2] = as_float(h.prim);
}

/* The watertight test of ray i (origin, direction: rays[2i], rays[2i+1])
 * against triangle i (tris[3i..3i+3]): (t, b0, b1, b2), or t = -1 for no
 * hit. */
__kernel void check_triangle(__global float *out, uint n, __global const float4 *rays,
                             __global const float4 *tris) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    TriRay r = tri_ray(rays[2 * i].xyz, rays[2 * i + 1].xyz);
    float t;
    float3 b;
    __global float *o = out + (size_t)i * 4u;
    if (tri_intersect(&r, tris[3 * i].xyz, tris[3 * i + 1].xyz, tris[3 * i + 2].xyz, INFINITY, &t, &b)) {
        o[0] = t;
        vstore3(b, 0, o + 1);
    } else {
        o[0] = -1.0f;
        o[1] = 0.0f;
        o[2] = 0.0f;
        o[3] = 0.0f;
    }
}

/* The power pick from x[i] among P->num_lights emitters: (index, pmf and
 * what x leaves, as float bits). */
__kernel void check_light_pick(__global uint *out, uint n, __global const uint *x, __global const Params *P,
                               __global const Light *lights) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    float u;
    uint j = pick_light(lights, P->num_lights, x[i], &u);
    out[3 * i] = j;
    out[3 * i + 1] = as_uint(lights[j].pmf);
    out[3 * i + 2] = as_uint(u);
}

/* sample_emitter for emitter light[i] from the point in[3i] (xyz; w: the
 * object it lies on, as bits, or NO_OBJECT) with normal in[3i+1].xyz (as
 * both nl and ns) and numbers in[3i+2].xy: (dir.xyz, 1/pdf) or w = -1. */
__kernel void check_light_sample(__global float *out, uint n, __global const float4 *in,
                                 __global const uint *which, __global const Object *objects,
                                 __global const Light *lights) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.objects = objects, .lights = lights};
    __global const Light *L = &lights[which[i]];
    Surf sf;
    sf.p = in[3 * i].xyz;
    sf.object = as_uint(in[3 * i].w);
    sf.prim = sf.object == NO_OBJECT ? NO_PRIM : L->prim;
    float3 n3 = in[3 * i + 1].xyz;
    sf.ng = n3;
    sf.ns = n3;
    float3 dir;
    float weight;
    __global float *o = out + (size_t)i * 4u;
    if (sample_emitter(&sc, L, sf.p, sf.object, sf.prim, n3, n3, in[3 * i + 2].xy, &dir, &weight)) {
        vstore3(dir, 0, o);
        o[3] = weight;
    } else {
        o[0] = 0.0f;
        o[1] = 0.0f;
        o[2] = 0.0f;
        o[3] = -1.0f;
    }
}

/* emitter_pdf for emitter lights[which[i]] from the point in[4i] (xyz;
 * w: the object it lies on, as bits, or NO_OBJECT) with normal in[4i+1].xyz
 * (as both nl and ns), along in[4i+2].xyz meeting the emitter at
 * in[4i+3].xyz. */
__kernel void check_emitter_pdf(__global float *out, uint n, __global const float4 *in, __global const uint *which,
                                __global const Object *objects, __global const Light *lights) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.objects = objects, .lights = lights};
    __global const Light *L = &lights[which[i]];
    uint object = as_uint(in[4 * i].w);
    uint prim = object == NO_OBJECT ? NO_PRIM : L->prim;
    float3 n3 = in[4 * i + 1].xyz;
    out[i] = emitter_pdf(&sc, L, in[4 * i].xyz, object, prim, n3, n3, in[4 * i + 2].xyz, in[4 * i + 3].xyz);
}

/* light_index of (keys[2i], keys[2i+1]), environment_light, and the power
 * heuristic of (ab[2i], ab[2i+1]) as bits: three words per item. */
__kernel void check_mis_routines(__global uint *out, uint n, __global const uint *keys, __global const float *ab,
                                 __global const Params *P, __global const Light *lights) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.P = P, .lights = lights};
    out[3 * i] = (uint)light_index(&sc, keys[2 * i], keys[2 * i + 1]);
    out[3 * i + 1] = (uint)environment_light(&sc);
    out[3 * i + 2] = as_uint(power_heuristic(ab[2 * i], ab[2 * i + 1]));
}

/* The environment map's routines (envmap.h) on direction dirs[i].xyz and
 * numbers u[i]: radiance (3), pdf, sample (ok, dir (3), weight) and
 * atan2_turns(d.y, d.x): ten floats per item. */
__kernel void check_env_map(__global float *out, uint n, __global const float4 *dirs, __global const float2 *u,
                            __global const Params *P, __global const float *env_texels,
                            __global const float *env_dist) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.P = P, .env_texels = env_texels, .env_dist = env_dist};
    float3 d = dirs[i].xyz;
    float3 r = env_radiance(&sc, d);
    float3 dir = (float3)(0.0f);
    float weight = 0.0f;
    int ok = env_sample(&sc, u[i], &dir, &weight);
    __global float *o = out + 10 * i;
    vstore3(r, 0, o);
    o[3] = env_pdf(&sc, d);
    o[4] = ok ? 1.0f : 0.0f;
    vstore3(dir, 0, o + 5);
    o[8] = weight;
    o[9] = atan2_turns(d.y, d.x);
}

#if HAS_SUN
/* The sun's routines (lights.h) on numbers u[i] and direction dirs[i].xyz:
 * sun_sample's dir (3) and 1/pdf, sun_covers, and the density emitter_pdf
 * gives the sun's emitter lights[which]: six floats per item. */
__kernel void check_sun(__global float *out, uint n, __global const float2 *u, __global const float4 *dirs,
                        __global const Params *P, __global const Light *lights, uint which) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.P = P, .lights = lights};
    float3 dir;
    float weight;
    sun_sample(P, u[i], &dir, &weight);
    float3 d = dirs[i].xyz;
    __global float *o = out + 6 * i;
    vstore3(dir, 0, o);
    o[3] = weight;
    o[4] = sun_covers(P, d) ? 1.0f : 0.0f;
    o[5] = emitter_pdf(&sc, &lights[which], (float3)(0.0f), NO_OBJECT, NO_PRIM, d, d, d, d);
}
#endif

/* camera_ray through raster (xy[2i], xy[2i+1]) with the numbers of
 * sampler_of_kind(in[4i..4i+4]) (sobol, seed, pixel, sample), after its
 * camera_2d: origin.xyz, dir.xyz as 6 floats. */
__kernel void check_camera_ray(__global float *out, uint n, __global const float *xy, __global const ulong *in,
                               __global const Params *P) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Sampler s = sampler_of_kind((int)in[4 * i], in[4 * i + 1], in[4 * i + 2], in[4 * i + 3]);
    (void)camera_2d(&s);
    float3 o, d;
    camera_ray(P, xy[2 * i], xy[2 * i + 1], &s, &o, &d);
    __global float *r = out + 6 * i;
    vstore3(o, 0, r);
    vstore3(d, 0, r + 3);
}

#if HAS_TEXTURES
/* maps.h's shade_maps for material which[i] at coordinates in[3i] (set 0
 * in xy, set 1 in zw), shading normal in[3i + 1].xyz and tangent
 * in[3i + 2] (w: the sign): albedo (3), pbr (4), normal (3), emission
 * (3), transmission, coat (3), spec (4), the coat's normal (3): 24 floats
 * per item. */
__kernel void check_maps(__global float *out, uint n, __global const float4 *in, __global const uint *which,
                         __global const Material *materials, __global const MaterialMaps *maps,
                         __global const TexImage *tex_images, __global const uint *texels, __global const float *srgb) {
    uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    Scene sc = {.materials = materials, .maps = maps, .tex_images = tex_images, .texels = texels, .srgb = srgb};
    TexCoords tc;
    tc.uv[0] = in[3 * i].xy;
    tc.uv[1] = in[3 * i].zw;
    tc.tangent = in[3 * i + 2].xyz;
    tc.sign = in[3 * i + 2].w;
    Material m = materials[which[i]];
    float3 ns = in[3 * i + 1].xyz;
    float3 nc = (float3)(0.0f);
    shade_maps(&sc, &tc, &m, &ns, &nc);
    __global float *o = out + 24 * i;
    vstore3(m.albedo.xyz, 0, o);
    vstore4(m.pbr, 0, o + 3);
    vstore3(ns, 0, o + 7);
    vstore3(m.emission.xyz, 0, o + 10);
    o[13] = m.glass.x;
    vstore3(m.coat.xyz, 0, o + 14);
    vstore4(m.spec, 0, o + 17);
    vstore3(nc, 0, o + 21);
}
#endif

/* sizeof of every shared struct, for the host's layout check. */
__kernel void check_layout_sizes(__global uint *out, uint n) {
    if (get_global_id(0) != 0) {
        return;
    }
    out[0] = (uint)sizeof(Object);
    out[1] = (uint)sizeof(Material);
    out[2] = (uint)sizeof(Params);
    out[3] = (uint)sizeof(BvhNode);
    out[4] = (uint)sizeof(Light);
    out[5] = (uint)sizeof(Instance);
    out[6] = (uint)sizeof(TriVerts);
}

/* sizeof of each scene array's element type, in SCENE_ARRAYS order: the
 * host compares them with its table's element sizes (buffers.rs). */
#define SCENE_ARRAY_SIZE(T, name) out[i++] = (uint)sizeof(T);
__kernel void check_scene_array_sizes(__global uint *out, uint n) {
    if (get_global_id(0) != 0) {
        return;
    }
    uint i = 0;
    SCENE_ARRAYS(SCENE_ARRAY_SIZE)
}
#undef SCENE_ARRAY_SIZE

/* Adds `value` to a compensated sum `count` times, as the film does: the
 * host checks that 1e8 additions keep the value to 1e-6. */
__kernel void check_accumulate(__global float *sum, uint n, float value, uint count) {
    if (get_global_id(0) != 0) {
        return;
    }
    sum[0] = 0.0f;
    sum[1] = 0.0f;
    for (uint i = 0; i < count; ++i) {
        add_compensated(sum + 0, sum + 1, value);
    }
}
