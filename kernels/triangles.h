/* Mesh instances: world/instance.rs and shape/triangle.rs, operation for
 * operation (the CPU's error bounds hold only for its rounding). */

#if HAS_MESHES
#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#endif

/* glam's Mat3A * v: x * v.x + y * v.y + z * v.z, in that order. */
static inline float3 xf_vector(__global const float4 *m, float3 v) {
    return m[0].xyz * v.x + m[1].xyz * v.y + m[2].xyz * v.z;
}

/* glam's Affine3A::transform_point3a: the matrix, then the translation. */
static inline float3 xf_point(__global const float4 *m, float3 p) {
    return xf_vector(m, p) + m[3].xyz;
}

static inline float3 unit_axis(int k) {
    return (float3)(k == 0 ? 1.0f : 0.0f, k == 1 ? 1.0f : 0.0f, k == 2 ? 1.0f : 0.0f);
}

static inline float component(float3 v, int k) {
    return k == 0 ? v.x : (k == 1 ? v.y : v.z);
}

/* A ray prepared for the watertight test (TriRay): the rows of its
 * permute-and-shear map. */
typedef struct {
    float3 org;
    float3 rx;
    float3 ry;
    float3 rz;
} TriRay;

static inline TriRay tri_ray(float3 o, float3 d) {
    float3 a = fabs(d);
    int kz = (a.x > a.y && a.x > a.z) ? 0 : (a.y > a.z ? 1 : 2);
    int kx = (kz + 1) % 3;
    int ky = (kz + 2) % 3;
    if (component(d, kz) < 0.0f) {
        int k = kx;
        kx = ky;
        ky = k;
    }
    float dz = component(d, kz);
    float sx = component(d, kx) / dz;
    float sy = component(d, ky) / dz;
    float sz = 1.0f / dz;
    TriRay r;
    r.org = o;
    r.rx = unit_axis(kx) - unit_axis(kz) * sx;
    r.ry = unit_axis(ky) - unit_axis(kz) * sy;
    r.rz = unit_axis(kz) * sz;
    return r;
}

/* An edge function recomputed where f32 gave an exact zero: in f64, where
 * products of floats are exact (Woop et al.'s fallback). */
static inline float edge_exact(float p, float q, float r, float s) {
#ifdef cl_khr_fp64
    return (float)((double)p * (double)q - (double)r * (double)s);
#else
    return p * q - r * s; /* not reached: meshes need fp64 (opencl::unsupported) */
#endif
}

/* TriRay::intersect: 1 and (*t, *bary) when the ray meets the triangle
 * strictly between 0 and t_max. */
static inline int tri_intersect(const TriRay *r, float3 p0, float3 p1, float3 p2, float t_max, float *t_out,
                         float3 *bary) {
    float3 a = p0 - r->org;
    float3 b = p1 - r->org;
    float3 c = p2 - r->org;
    float ax = dot3(r->rx, a), ay = dot3(r->ry, a);
    float bx = dot3(r->rx, b), by = dot3(r->ry, b);
    float cx = dot3(r->rx, c), cy = dot3(r->ry, c);
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        u = edge_exact(cx, by, cy, bx);
        v = edge_exact(ax, cy, ay, cx);
        w = edge_exact(bx, ay, by, ax);
    }
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) {
        return 0;
    }
    float det = u + v + w;
    if (det == 0.0f) {
        return 0;
    }
    float t_scaled = u * dot3(r->rz, a) + v * dot3(r->rz, b) + w * dot3(r->rz, c);
    float t = t_scaled / det;
    if (!(t > 0.0f && t <= t_max)) {
        return 0;
    }
    float inv = 1.0f / det;
    *t_out = t;
    *bary = (float3)(u * inv, v * inv, w * inv);
    return 1;
}

#if HAS_ALPHA
/* alpha.rs, blend_u: a number in [0, 1) from the camera-space ray (o, d)
 * and triangle `index`. */
static inline uint alpha_mix(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

static inline float blend_u(float3 o, float3 d, uint index) {
    uint h = 0x9E3779B9u;
    h = alpha_mix(h ^ as_uint(o.x));
    h = alpha_mix(h ^ as_uint(o.y));
    h = alpha_mix(h ^ as_uint(o.z));
    h = alpha_mix(h ^ as_uint(d.x));
    h = alpha_mix(h ^ as_uint(d.y));
    h = alpha_mix(h ^ as_uint(d.z));
    h = alpha_mix(h ^ index);
    return (float)(h >> 8) * (1.0f / 16777216.0f);
}

#if HAS_TEXTURES
static inline float alpha_texel(const Scene *sc, __global const Instance *in, __global const AlphaTest *a, uint slot,
                                float3 bary);
#endif

/* AlphaTest::passes: whether the ray (o, d) stops at leaf slot `slot`
 * (triangle `index`, mesh material slot `mslot`) of instance `in`. */
static inline int alpha_passes(const Scene *sc, __global const Instance *in, uint slot, uint index, uint mslot,
                               float3 bary, float3 o, float3 d) {
    __global const AlphaTest *a = &sc->alpha[in->alpha_base + mslot];
    if (a->mode == 0u) {
        return 1;
    }
    float alpha = a->factor;
#if HAS_TEXTURES
    if (a->tex.info.x != NO_TEXTURE) {
        alpha = alpha_texel(sc, in, a, slot, bary);
    }
#endif
    if (a->mode == 1u) {
        return alpha >= a->cutoff;
    }
    return blend_u(o, d, index) < alpha;
}
#endif

/* The triangles of leaf slots first .. first+count of instance `in`,
 * offered to *best (all but triangle `skip`); (o, d) the camera-space ray
 * (alpha tests hash it). */
static inline void offer_triangles(const Scene *sc, __global const Instance *in, uint id, const TriRay *r, uint first,
                            uint count, uint skip, float3 o, float3 d, Hit *best) {
    for (uint k = first; k < first + count; ++k) {
        uint slot = in->tri_base + k;
        __global const TriVerts *tri = &sc->tris[slot];
        uint index = as_uint(tri->v0.w);
        if (index == skip) {
            continue;
        }
        float t;
        float3 bary;
        if (tri_intersect(r, tri->v0.xyz, tri->v1.xyz, tri->v2.xyz, best->t, &t, &bary)) {
#if HAS_ALPHA
            if (in->alpha_base != NO_NORMALS && !alpha_passes(sc, in, slot, index, as_uint(tri->v1.w), bary, o, d)) {
                continue;
            }
#else
            (void)o;
            (void)d;
#endif
            offer_hit(best, t, id, index, slot, bary);
        }
    }
}

/* Instance::offer: the ray mapped into object space (direction not
 * normalised, so distances stay the camera ray's) meets the mesh's BVH. */
static inline void offer_instance(const Scene *sc, uint id, __global const Object *ob, float3 o, float3 d, uint skip,
                           Hit *best) {
    __global const Instance *in = &sc->instances[ob->pad0];
    float3 oo = xf_point(in->obj_from_cam, o);
    float3 dd = xf_vector(in->obj_from_cam, d);
    TriRay r = tri_ray(oo, dd);
    __global const BvhNode *nodes = sc->mesh_nodes + in->node_base;
    BVH_SEARCH(nodes, MESH_STACK, oo, dd, best->t,
               offer_triangles(sc, in, id, &r, leaf_first, leaf_count, skip, o, d, best));
}

/* Instance::surface, into *sf. */
static inline void mesh_surface(const Scene *sc, const Hit *h, Surf *sf) {
    __global const Instance *in = &sc->instances[sc->objects[h->object].pad0];
    __global const TriVerts *tri = &sc->tris[h->slot];
    float3 v0 = tri->v0.xyz, v1 = tri->v1.xyz, v2 = tri->v2.xyz;
    float3 t0 = v0 * h->bary.x, t1 = v1 * h->bary.y, t2 = v2 * h->bary.z;
    float3 p_obj = t0 + t1 + t2;
    float3 err = (fabs(t0) + fabs(t1) + fabs(t2)) * as_float(GAMMA7_BITS);
    float3 n_obj = normalize_or_zero(cross3(v1 - v0, v2 - v0));
    float3 ng = normalize_or_zero(xf_vector(in->normal_from_obj, n_obj));
    sf->ng = ng;
    sf->ns = ng;
    sf->smooth = 0;
    if (in->normal_base != NO_NORMALS) {
        __global const float4 *n = sc->normals + (size_t)(in->normal_base + (h->slot - in->tri_base)) * 3u;
        float3 sn = n[0].xyz * h->bary.x + n[1].xyz * h->bary.y + n[2].xyz * h->bary.z;
        float3 m = xf_vector(in->normal_from_obj, sn);
        float rcp = 1.0f / sqrt(dot3(m, m));
        if (isfinite(rcp) && rcp > 0.0f) {
            sf->ns = m * rcp;
            sf->smooth = 1;
        }
    }
    float3 ap = fabs(p_obj);
    err = err + (float3)(in->rt_a * fmax(fmax(ap.x, ap.y), ap.z) + in->rt_b);
    sf->p = xf_point(in->cam_from_obj, p_obj);
    sf->material = sc->slots[in->slot_base + as_uint(tri->v1.w)];
    sf->instance = sc->objects[h->object].pad0;
    sf->p_obj = p_obj;
    sf->n_obj = n_obj;
    sf->dist = dot3(fabs(n_obj), err);
}

/* Instance::spawn_origin: the object-space hit point moved sf->dist off
 * the plane to the side dir goes, each coordinate rounded away from it. */
static inline float3 mesh_spawn(const Scene *sc, const Surf *sf, float3 dir) {
    float3 shift = dot3(dir, sf->ng) > 0.0f ? sf->n_obj * sf->dist : sf->n_obj * -sf->dist;
    float3 p = sf->p_obj + shift;
    p.x = shift.x > 0.0f ? nextafter(p.x, INFINITY) : (shift.x < 0.0f ? nextafter(p.x, -INFINITY) : p.x);
    p.y = shift.y > 0.0f ? nextafter(p.y, INFINITY) : (shift.y < 0.0f ? nextafter(p.y, -INFINITY) : p.y);
    p.z = shift.z > 0.0f ? nextafter(p.z, INFINITY) : (shift.z < 0.0f ? nextafter(p.z, -INFINITY) : p.z);
    return xf_point(sc->instances[sf->instance].cam_from_obj, p);
}
#endif
