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
static inline uint bvh_test(__global const BvhNode *node, float3 o, float3 inv, int3 neg, float t_max, float4 *t_near) {
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

#if HAS_BVH
/* Nearest-first search of the BVH `NODES` (bvh/traverse.rs) for the ray
 * (O, D) up to T_MAX (an lvalue: leaves may shorten it). At each leaf,
 * LEAF runs with leaf_first and leaf_count (slots). Stack entries: child
 * << 3 | count (leaves hold at most 7) and the entry distance. */
#define BVH_SEARCH(NODES, STACK, O, D, T_MAX, LEAF)                                   \
    {                                                                                 \
        float3 inv_ = (float3)(1.0f) / (D);                                           \
        int3 neg_ = (int3)(signbit((D).x), signbit((D).y), signbit((D).z));            \
        uint stack_[STACK];                                                           \
        float stack_t_[STACK];                                                        \
        int top_ = 1;                                                                 \
        stack_[0] = 0u;                                                               \
        stack_t_[0] = 0.0f;                                                           \
        while (top_ > 0) {                                                            \
            top_ -= 1;                                                                \
            uint entry_ = stack_[top_];                                               \
            if (stack_t_[top_] > (T_MAX)) {                                           \
                continue;                                                             \
            }                                                                         \
            uint child_ = entry_ >> 3;                                                \
            uint count_ = entry_ & 7u;                                                \
            if (count_ > 0u) {                                                        \
                uint leaf_first = child_;                                             \
                uint leaf_count = count_;                                             \
                LEAF;                                                                 \
                continue;                                                             \
            }                                                                         \
            float4 tv_;                                                               \
            uint mask_ = bvh_test(&(NODES)[child_], (O), inv_, neg_, (T_MAX), &tv_);  \
            float tn_[4] = {tv_.x, tv_.y, tv_.z, tv_.w};                              \
            /* The children hit, by entry distance, nearest last. */                 \
            uint hits_[4];                                                            \
            float hits_t_[4];                                                         \
            int n_ = 0;                                                               \
            for (int i_ = 0; i_ < 4; ++i_) {                                          \
                if (!(mask_ & (1u << i_))) {                                          \
                    continue;                                                         \
                }                                                                     \
                uint e_ = (NODES)[child_].child[i_] << 3 | (NODES)[child_].count[i_]; \
                int j_ = n_;                                                          \
                while (j_ > 0 && hits_t_[j_ - 1] < tn_[i_]) {                         \
                    hits_[j_] = hits_[j_ - 1];                                        \
                    hits_t_[j_] = hits_t_[j_ - 1];                                    \
                    j_ -= 1;                                                          \
                }                                                                     \
                hits_[j_] = e_;                                                       \
                hits_t_[j_] = tn_[i_];                                                \
                n_ += 1;                                                              \
            }                                                                         \
            for (int i_ = 0; i_ < n_; ++i_) {                                         \
                stack_[top_ + i_] = hits_[i_];                                        \
                stack_t_[top_ + i_] = hits_t_[i_];                                    \
            }                                                                         \
            top_ += n_;                                                               \
        }                                                                             \
    }
#endif
