/* Entry point: one work-item per pixel of pixels [pixel_base, pixel_end)
 * (a launch may cover a range of the image; the range is a kernel argument
 * rather than a global offset, which some drivers specialise kernels on)
 * adds samples first .. first+count-1,
 * in index order, to the device film. The film keeps each sum as a pair of
 * floats (hi + lo, compensated with TwoSum) for the even and the odd
 * samples: FILM_FLOATS floats per pixel, [even hi rgb, even lo rgb, odd hi
 * rgb, odd lo rgb]. That keeps ~44 bits (the 1e8-sample check) and, since
 * every pixel's samples are added in order, an image that does not depend on
 * how samples were split into launches. Non-finite samples are counted in
 * *rejected and add nothing. Built with FEATURES, each sample also adds its
 * path's guide for the denoiser to `guides` (GUIDE_FLOATS per pixel:
 * albedo rgb, normal rgb).
 *
 * Adaptive sampling (mode != 0) gives each tile of ADAPTIVE_TILE^2 pixels
 * its own first sample, in uint4 entries (tile, first low, first high,
 * flag): a compacted list (WORK_LIST: work-item i renders pixel i mod T^2
 * of entry i / T^2's tile) or one entry per tile of the image (WORK_DENSE:
 * work-item i renders pixel i; a flag of 0 skips its tile). Every
 * work-item renders `count` samples (the host splits tiles' counts into
 * powers of two, one launch each). */

static inline void add_compensated(__global float *hi, __global float *lo, float x) {
    float h = *hi;
    float s = h + x;
    float bp = s - h;
    float e = (h - (s - bp)) + (x - bp);
    e += *lo;
    float nh = s + e;
    *lo = e - (nh - s);
    *hi = nh;
}

/* The scene's arrays first, in SCENE_ARRAYS order, then the launch's own
 * arguments (buffers.rs, SceneBuffers::set_args, binds them by position). */
#define SCENE_PARAM(T, name) __global const T *name,
#define SCENE_NAME(T, name) name,
__kernel void render(SCENE_ARRAYS(SCENE_PARAM) __global float *film, __global float *guides, __global uint *rejected, ulong first,
                     uint count, uint pixel_base, uint pixel_end, __global const uint4 *work, uint mode) {
    Scene sc = {SCENE_ARRAYS(SCENE_NAME)};
    uint gid = pixel_base + (uint)get_global_id(0);
    if (gid >= pixel_end) {
        return;
    }
    /* Adaptive work: an entry is (tile, first sample low, high, flag); the
     * sample count stays the launch's own, so that the loop bound is the
     * same for every work-item (drivers vectorise across work-items). */
    if (mode != 0u) {
        uint tile_cols = (P->width + ADAPTIVE_TILE - 1u) / ADAPTIVE_TILE;
        uint4 w;
        uint lx, ly;
        if (mode == WORK_LIST) {
            w = work[gid / (ADAPTIVE_TILE * ADAPTIVE_TILE)];
            uint l = gid % (ADAPTIVE_TILE * ADAPTIVE_TILE);
            lx = (w.x % tile_cols) * ADAPTIVE_TILE + l % ADAPTIVE_TILE;
            ly = (w.x / tile_cols) * ADAPTIVE_TILE + l / ADAPTIVE_TILE;
        } else {
            lx = gid % P->width;
            ly = gid / P->width;
            w = work[(ly / ADAPTIVE_TILE) * tile_cols + lx / ADAPTIVE_TILE];
        }
        if (w.w == 0u || lx >= P->width || ly >= P->height) {
            return;
        }
        gid = ly * P->width + lx;
        first = ((ulong)w.z << 32) | (ulong)w.y;
    }
    uint x = gid % P->width;
    uint y = gid / P->width;
    __global float *px = film + (size_t)gid * FILM_FLOATS;
#if FEATURES
    /* The launch's guides summed privately, added to the buffer once. */
    float3 albedo_sum = (float3)(0.0f);
    float3 normal_sum = (float3)(0.0f);
#endif
    for (uint k = 0; k < count; ++k) {
        ulong sample = first + (ulong)k;
        Sampler s = sampler_of_kind(USE_SOBOL, P->seed, (ulong)gid, sample);
        float2 off = pixel_offset(P, sample, camera_2d(&s), s.sobol);
        float3 o, d;
        camera_ray(P, (float)x + off.x, (float)y + off.y, &s, &o, &d);
        Guide g;
        float3 l = radiance(&sc, o, d, &s, &g);
#if !FEATURES
        (void)g;
#endif
#if FEATURES
        /* The denoiser's guides (features.rs): each sample's, whether or
         * not its radiance is rejected below. */
        albedo_sum += g.albedo;
        normal_sum += g.normal;
#endif
#ifdef INJECT_NAN_EVERY
        if (sample % INJECT_NAN_EVERY == 0UL) {
            l.y = NAN;
        }
#endif
        if (!(isfinite(l.x) && isfinite(l.y) && isfinite(l.z))) {
            atomic_inc(rejected);
            continue;
        }
        __global float *sums = px + ((sample & 1UL) ? FILM_FLOATS / 2u : 0u);
        add_compensated(sums + 0, sums + 3, l.x);
        add_compensated(sums + 1, sums + 4, l.y);
        add_compensated(sums + 2, sums + 5, l.z);
    }
#if FEATURES
    __global float *gp = guides + (size_t)gid * GUIDE_FLOATS;
    gp[0] += albedo_sum.x;
    gp[1] += albedo_sum.y;
    gp[2] += albedo_sum.z;
    gp[3] += normal_sum.x;
    gp[4] += normal_sum.y;
    gp[5] += normal_sum.z;
#endif
}
#undef SCENE_PARAM
#undef SCENE_NAME
