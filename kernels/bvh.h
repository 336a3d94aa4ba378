/* The nearest hit: every object in turn, or the objects too large for a BVH
 * in turn and then the BVH (world/mod.rs, World::intersect, and
 * bvh/traverse.rs). The traversal is the CPU's: a node's four boxes tested
 * at once with the conservative slab test (exit distances scaled by
 * BVH_ROBUST, 1 + 2 gamma(3), and NaN planes ignored: fmin/fmax drop NaN as
 * SSE's min/max do there), the children hit pushed farthest first, and a
 * child skipped when it is popped beyond the nearest hit so far. */

#if HAS_BVH
/* Entry distances of a node's four boxes; bit i of the result: child i is
 * met before t_max. */
inline uint bvh_test(__global const BvhNode *node, float3 o, float3 inv, int3 neg, float t_max, float4 *t_near) {
    float4 lo_x = neg.x ? node->bounds[3] : node->bounds[0];
    float4 hi_x = neg.x ? node->bounds[0] : node->bounds[3];
    float4 lo_y = neg.y ? node->bounds[4] : node->bounds[1];
    float4 hi_y = neg.y ? node->bounds[1] : node->bounds[4];
    float4 lo_z = neg.z ? node->bounds[5] : node->bounds[2];
    float4 hi_z = neg.z ? node->bounds[2] : node->bounds[5];
    float4 nx = (lo_x - o.x) * inv.x;
    float4 fx = (hi_x - o.x) * inv.x;
    float4 ny = (lo_y - o.y) * inv.y;
    float4 fy = (hi_y - o.y) * inv.y;
    float4 nz = (lo_z - o.z) * inv.z;
    float4 fz = (hi_z - o.z) * inv.z;
    /* fmax(x, acc) is acc where x is NaN, like max_or in traverse.rs. */
    float4 tn = fmax(nz, fmax(ny, fmax(nx, (float4)(0.0f))));
    float4 tf = fmin(fz, fmin(fy, fmin(fx, (float4)(t_max)))) * as_float(BVH_ROBUST_BITS);
    *t_near = tn;
    int4 hit = isless(tn, tf) | isequal(tn, tf);
    return (hit.x ? 1u : 0u) | (hit.y ? 2u : 0u) | (hit.z ? 4u : 0u) | (hit.w ? 8u : 0u);
}
#endif

/* Nearest hit along (o, d), never the surface the ray starts on. Returns
 * the distance; *hit is the object index or NO_OBJECT. */
inline float intersect(const Scene *sc, float3 o, float3 d, uint from, int entering, uint *hit) {
    __global const Params *P = sc->P;
    float oo = dot(o, o);
    float od = dot(o, d);
    float best = INFINITY;
    *hit = NO_OBJECT;
#if HAS_BVH
    if (USE_BVH) {
        for (uint j = 0; j < P->num_big; ++j) {
            offer_object(sc->objects, sc->big[j], o, d, oo, od, from, entering, &best, hit);
        }
        float3 inv = (float3)(1.0f) / d;
        int3 neg = (int3)(signbit(d.x), signbit(d.y), signbit(d.z));
        /* Entries: child << 3 | count (leaves hold at most 7), and the
         * entry distance. */
        uint stack[BVH_STACK];
        float stack_t[BVH_STACK];
        int top = 1;
        stack[0] = 0u;
        stack_t[0] = 0.0f;
        while (top > 0) {
            top -= 1;
            uint entry = stack[top];
            if (stack_t[top] > best) {
                continue;
            }
            uint child = entry >> 3;
            uint count = entry & 7u;
            if (count > 0u) {
                for (uint slot = child; slot < child + count; ++slot) {
                    offer_object(sc->objects, sc->prims[slot], o, d, oo, od, from, entering, &best, hit);
                }
                continue;
            }
            __global const BvhNode *node = &sc->nodes[child];
            float4 tv;
            uint mask = bvh_test(node, o, inv, neg, best, &tv);
            float tn[4] = {tv.x, tv.y, tv.z, tv.w};
            /* The children hit, by entry distance, nearest last. */
            uint hits[4];
            float hits_t[4];
            int n = 0;
            for (int i = 0; i < 4; ++i) {
                if (!(mask & (1u << i))) {
                    continue;
                }
                uint e = node->child[i] << 3 | node->count[i];
                int j = n;
                while (j > 0 && hits_t[j - 1] < tn[i]) {
                    hits[j] = hits[j - 1];
                    hits_t[j] = hits_t[j - 1];
                    j -= 1;
                }
                hits[j] = e;
                hits_t[j] = tn[i];
                n += 1;
            }
            for (int i = 0; i < n; ++i) {
                stack[top + i] = hits[i];
                stack_t[top + i] = hits_t[i];
            }
            top += n;
        }
        return best;
    }
#endif
    for (uint i = 0; i < OBJECT_COUNT; ++i) {
        offer_object(sc->objects, i, o, d, oo, od, from, entering, &best, hit);
    }
    return best;
}
