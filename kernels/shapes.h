/* Ray/shape intersection: shape/sphere.rs and shape/quad.rs. */

/* Sphere: the constant term as o.o - 2 o.c + K (K = |c|^2 - r^2 in f64 on
 * the host) and the stable root pair q, C/q. far_only: the ray starts on
 * this sphere and goes into it. */
static inline float sphere_intersect(__global const Object *ob, float3 o, float3 d, float oo, float od, int far_only) {
    float3 c = ob->p0.xyz;
    float b = od - dot3(d, c);
    float cc = (oo + ob->p1.x) - 2.0f * dot3(o, c);
    float disc = b * b - cc;
    if (disc < 0.0f) {
        return INFINITY;
    }
    float s = sqrt(disc);
    float q = b > 0.0f ? -(b + s) : s - b;
    float other = cc / q;
    float t0 = fmin(q, other);
    float t1 = fmax(q, other);
    if (!far_only && t0 > 0.0f) {
        return t0;
    }
    return t1 > 0.0f ? t1 : INFINITY;
}

static inline float quad_intersect(__global const Object *ob, float3 o, float3 d) {
    float3 n = ob->p3.xyz;
    float3 to_corner = ob->p0.xyz - o;
    float t = dot3(n, to_corner) / dot3(n, d);
    if (!(t > 0.0f && t < INFINITY)) {
        return INFINITY;
    }
    float3 q = d * t - to_corner;
    float a = dot3(ob->p4.xyz, cross3(q, ob->p2.xyz));
    float b = dot3(ob->p4.xyz, cross3(ob->p1.xyz, q));
    return (a >= 0.0f && a <= 1.0f && b >= 0.0f && b <= 1.0f) ? t : INFINITY;
}

/* Takes (t, object, prim) if it comes before *h: nearer, or as near with a
 * lower (object, prim) (world/mod.rs, Hit::offer). */
static inline void offer_hit(Hit *h, float t, uint object, uint prim, uint slot, float3 bary) {
    if (t < h->t || (t == h->t && t < INFINITY && (object < h->object || (object == h->object && prim < h->prim)))) {
        h->t = t;
        h->object = object;
        h->prim = prim;
        h->slot = slot;
        h->bary = bary;
    }
}

/* Where a path met a surface (world/mod.rs, Surface): for triangles also
 * what rays leaving it need (instance, object-space point and normal, and
 * how far off the plane they start). */
typedef struct {
    float3 p;
    float3 ng;  /* unit geometric normal (outward for spheres) */
    float3 ns;  /* unit shading normal */
    int smooth; /* ns is a mesh's interpolated normal */
#if HAS_COAT_NORMAL
    float3 nc; /* a clear coat's own unit normal (zero: ns), World::shade */
#endif
    uint material;
    uint object;
    uint prim;
    uint instance; /* NO_OBJECT: not a triangle */
    float3 p_obj;
    float3 n_obj;
    float dist;
} Surf;

static inline float3 object_normal(__global const Object *ob, float3 p) {
#if HAS_SPHERES && HAS_QUADS
    if (ob->kind == KIND_SPHERE) {
        return (p - ob->p0.xyz) * ob->p1.y;
    }
    return ob->p3.xyz;
#elif HAS_SPHERES
    return (p - ob->p0.xyz) * ob->p1.y;
#else
    return ob->p3.xyz;
#endif
}
