/* Pinhole and thin-lens camera, pixel filters: camera.rs and filter.rs. */

static inline float tent(float u) {
    float r = 2.0f * u;
    return r < 1.0f ? sqrt(r) - 1.0f : 1.0f - sqrt(2.0f - r);
}

/* Offset inside the pixel for sample `sample`: random numbers take the
 * sub-pixel from the sample index (samples 2k, 2k+1 share one), Sobol
 * points from each coordinate's top bit (filter.rs,
 * pixel_offset_stratified). */
static inline float2 pixel_offset(__global const Params *P, ulong sample, float2 u, int stratified) {
    if (USE_BOX_FILTER) {
        return u;
    }
    float sx, sy;
    if (stratified) {
        float2 t = 2.0f * u;
        sx = t.x >= 1.0f ? 1.0f : 0.0f;
        sy = t.y >= 1.0f ? 1.0f : 0.0f;
        u = t - (float2)(sx, sy);
    } else {
        uint sub = (uint)((sample >> 1) & 3UL);
        sx = (float)(sub & 1u);
        sy = (float)(sub >> 1);
    }
    return (float2)((sx + 0.5f + tent(u.x)) * 0.5f, (sy + 0.5f + tent(u.y)) * 0.5f);
}

/* The ray through raster (x, y) (CameraRays::ray, lens_ray): from the
 * pinhole, or from a point of the lens drawn from s towards where the
 * pinhole ray meets the plane in focus; parallel to forward from the
 * image rectangle (orthographic); or in the direction an environment map's
 * point (x/w, y/h) has (panorama: right, up and -forward unit vectors). */
static inline void camera_ray(__global const Params *P, float x, float y, Sampler *s, float3 *origin, float3 *dir) {
    if (CAMERA_PROJECTION == PROJ_ORTHOGRAPHIC) {
        float3 o = P->right.xyz * (x * (1.0f / (float)P->width) - 0.5f)
            + P->up.xyz * (0.5f - y * (1.0f / (float)P->height));
        *dir = P->forward.xyz;
        *origin = o + P->forward.xyz * P->forward.w;
        return;
    }
    if (CAMERA_PROJECTION == PROJ_PANORAMA) {
        float sin_theta;
        float3 m = env_map_direction(x * (1.0f / (float)P->width), y * (1.0f / (float)P->height), &sin_theta);
        *dir = normalize3(P->right.xyz * m.x + P->up.xyz * m.y - P->forward.xyz * m.z);
        *origin = *dir * P->forward.w;
        return;
    }
    float3 d = P->forward.xyz
        + P->right.xyz * (x * (1.0f / (float)P->width) - 0.5f)
        + P->up.xyz * (0.5f - y * (1.0f / (float)P->height));
#if HAS_LENS
    if (P->lens_x > 0.0f) {
        float2 u = lens_2d(s);
        float r = sqrt(u.x);
        float2 sc = sincos_turns(u.y);
        float3 o = P->right.xyz * (P->lens_x * (r * sc.y)) + P->up.xyz * (P->lens_y * (r * sc.x));
        *dir = normalize3(d * P->right.w - o);
        *origin = o + *dir * P->forward.w;
        return;
    }
#endif
    /* near_clip along the ray itself (smallpt's camera), not to a plane. */
    *dir = normalize3(d);
    *origin = *dir * P->forward.w;
}
