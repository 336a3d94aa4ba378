/* Ray/shape intersection: shape/sphere.rs and shape/quad.rs. */

/* Sphere: the constant term as o.o - 2 o.c + K (K = |c|^2 - r^2 in f64 on
 * the host) and the stable root pair q, C/q. far_only: the ray starts on
 * this sphere and goes into it. */
inline float sphere_intersect(__global const Object *ob, float3 o, float3 d, float oo, float od, int far_only) {
    float3 c = ob->p0.xyz;
    float b = od - dot(d, c);
    float cc = (oo + ob->p1.x) - 2.0f * dot(o, c);
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

inline float quad_intersect(__global const Object *ob, float3 o, float3 d) {
    float3 n = ob->p3.xyz;
    float3 to_corner = ob->p0.xyz - o;
    float t = dot(n, to_corner) / dot(n, d);
    if (!(t > 0.0f && t < INFINITY)) {
        return INFINITY;
    }
    float3 q = d * t - to_corner;
    float a = dot(ob->p4.xyz, cross(q, ob->p2.xyz));
    float b = dot(ob->p4.xyz, cross(ob->p1.xyz, q));
    return (a >= 0.0f && a <= 1.0f && b >= 0.0f && b <= 1.0f) ? t : INFINITY;
}

/* Offers object i to the nearest hit so far (*best, *hit), never the
 * surface the ray starts on (world/mod.rs, offer_object): a sphere the ray
 * leaves outwards is skipped, one it enters gives its far root; a quad it
 * starts on is skipped. Ties go to the lower object index. */
inline void offer_object(__global const Object *objects, uint i, float3 o, float3 d, float oo, float od, uint from,
                         int entering, float *best, uint *hit) {
    __global const Object *ob = &objects[i];
    float t;
#if HAS_SPHERES && HAS_QUADS
    if (ob->kind == KIND_SPHERE) {
#endif
#if HAS_SPHERES
        if (i == from && !entering) {
            return;
        }
        t = sphere_intersect(ob, o, d, oo, od, i == from);
#endif
#if HAS_SPHERES && HAS_QUADS
    } else {
#endif
#if HAS_QUADS
        if (i == from) {
            return;
        }
        t = quad_intersect(ob, o, d);
#endif
#if HAS_SPHERES && HAS_QUADS
    }
#endif
    if (t < *best || (t == *best && t < INFINITY && i < *hit)) {
        *best = t;
        *hit = i;
    }
}
inline float3 object_normal(__global const Object *ob, float3 p) {
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
