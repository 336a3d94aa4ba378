/* Environment maps: light/envmap.rs and light/distribution.rs, operation
 * for operation (the routine checks compare them bit for bit). The map's
 * texels are env_texels (RGB, three floats each, row by row from the top);
 * its tables env_dist: the marginal's cumulative masses (height + 1) and
 * densities (height), then per row the conditional's cumulative masses
 * (width + 1 each) and densities (width each). P->env_size.xy is the
 * map's size, P->env.xyz its rotation's cos and sin and its intensity;
 * P->environment holds the colour camera rays see when the map is hidden
 * (w: 1 when it is visible). */

/* atan2(y, x) in turns (math.rs, atan2_turns). */
static inline float atan2_turns(float y, float x) {
    float ax = fabs(x);
    float ay = fabs(y);
    int steep = ay > ax;
    float num = steep ? ax : ay;
    float den = steep ? ay : ax;
    if (!(den > 0.0f)) {
        return 0.0f;
    }
    float t = num / den;
    float base = 0.0f;
    if (t > 0.41421357f) {
        base = 0.78539816f; /* pi / 4 */
        t = (t - 1.0f) / (t + 1.0f);
    }
    float z = t * t;
    float p = (((8.0537445e-2f * z - 1.3877686e-1f) * z + 1.9977711e-1f) * z - 3.333295e-1f) * z * t + t;
    float a = base + p;
    if (steep) {
        a = 1.5707964f - a;
    }
    if (x < 0.0f) {
        a = 3.1415927f - a;
    }
    if (y < 0.0f) {
        a = -a;
    }
    return a * (0.5f * 0.31830987f);
}

/* map_direction: the map direction of point (u, v) and sin(theta) (also
 * the panorama camera's rays). */
static inline float3 env_map_direction(float u, float v, float *sin_theta) {
    float2 t = sincos_turns(v * 0.5f);
    float2 p = sincos_turns(u);
    *sin_theta = t.x;
    return (float3)(-(t.x * p.x), t.y, t.x * p.y);
}

#if HAS_ENV_MAP
static inline float3 env_texel(const Scene *sc, uint w, uint i, uint j) {
    uint k = 3u * (j * w + i);
    return (float3)(sc->env_texels[k], sc->env_texels[k + 1u], sc->env_texels[k + 2u]);
}

/* EnvMap::lookup: bilinear, wrapping in u, clamped at the poles. */
static inline float3 env_lookup(const Scene *sc, float u, float v) {
    uint w = sc->P->env_size.x;
    uint h = sc->P->env_size.y;
    float x = u * (float)w - 0.5f;
    float y = v * (float)h - 0.5f;
    float x0 = floor(x);
    float y0 = floor(y);
    float fx = x - x0;
    float fy = y - y0;
    int iw = (int)w;
    int ih = (int)h;
    uint i0 = (uint)((((int)x0 % iw) + iw) % iw);
    uint i1 = i0 + 1u == w ? 0u : i0 + 1u;
    uint j0 = (uint)clamp((int)y0, 0, ih - 1);
    uint j1 = (uint)clamp((int)y0 + 1, 0, ih - 1);
    float3 top = env_texel(sc, w, i0, j0) * (1.0f - fx) + env_texel(sc, w, i1, j0) * fx;
    float3 bottom = env_texel(sc, w, i0, j1) * (1.0f - fx) + env_texel(sc, w, i1, j1) * fx;
    return top * (1.0f - fy) + bottom * fy;
}

/* map_uv: the point of the square that map direction m looks at. */
static inline float2 env_map_uv(float3 m) {
    float u = 0.5f + atan2_turns(m.x, -m.z);
    float s = sqrt(m.x * m.x + m.z * m.z);
    float v = 2.0f * atan2_turns(s, m.y);
    return (float2)(u, v);
}

static inline float3 env_to_map(__global const Params *P, float3 d) {
    float c = P->env.x;
    float s = P->env.y;
    return (float3)(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

static inline float3 env_from_map(__global const Params *P, float3 m) {
    float c = P->env.x;
    float s = P->env.y;
    return (float3)(c * m.x + s * m.z, m.y, c * m.z - s * m.x);
}

/* EnvLight::radiance: what arrives from unit direction d. */
static inline float3 env_radiance(const Scene *sc, float3 d) {
    float2 uv = env_map_uv(env_to_map(sc->P, d));
    return env_lookup(sc, uv.x, uv.y) * sc->P->env.z;
}

/* distribution.rs, invert: the last cell of cdf[0..n] at most u, and *du
 * where u falls inside it. */
static inline uint env_invert(__global const float *cdf, uint n, float u, float *du) {
    uint lo = 0u;
    uint hi = n;
    while (hi - lo > 1u) {
        uint mid = lo + (hi - lo) / 2u;
        if (cdf[mid] <= u) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    float width = cdf[lo + 1u] - cdf[lo];
    float d = width > 0.0f ? (u - cdf[lo]) / width : 0.0f;
    *du = fmin(fmax(d, 0.0f), as_float(ONE_BELOW_BITS));
    return lo;
}

static inline float env_cell_pdf(const Scene *sc, uint col, uint row) {
    uint w = sc->P->env_size.x;
    uint h = sc->P->env_size.y;
    __global const float *t = sc->env_dist;
    uint cond_pdf = 2u * h + 1u + h * (w + 1u);
    return t[h + 1u + row] * t[cond_pdf + row * w + col];
}

/* EnvLight::sample: a direction drawn in proportion to the map's
 * brightness, and 1/pdf (solid angle); 0 where the density vanishes. */
static inline int env_sample(const Scene *sc, float2 u, float3 *dir, float *weight) {
    __global const Params *P = sc->P;
    uint w = P->env_size.x;
    uint h = P->env_size.y;
    float dv, du;
    uint row = env_invert(sc->env_dist, h, u.y, &dv);
    uint col = env_invert(sc->env_dist + 2u * h + 1u + row * (w + 1u), w, u.x, &du);
    float one_below = as_float(ONE_BELOW_BITS);
    float x = fmin(((float)col + du) / (float)w, one_below);
    float y = fmin(((float)row + dv) / (float)h, one_below);
    float pdf = env_cell_pdf(sc, col, row);
    float sin_theta;
    float3 m = env_map_direction(x, y, &sin_theta);
    float wt = as_float(TWO_PI2_BITS) * sin_theta / pdf;
    if (!(wt > 0.0f && isfinite(wt))) {
        return 0;
    }
    *dir = env_from_map(P, m);
    *weight = wt;
    return 1;
}

/* EnvLight::pdf: the density (solid angle) of env_sample giving d. */
static inline float env_pdf(const Scene *sc, float3 d) {
    __global const Params *P = sc->P;
    float3 m = env_to_map(P, d);
    float2 uv = env_map_uv(m);
    float sin_theta = sqrt(m.x * m.x + m.z * m.z);
    uint w = P->env_size.x;
    uint h = P->env_size.y;
    uint col = min((uint)(uv.x * (float)w), w - 1u);
    uint row = min((uint)(uv.y * (float)h), h - 1u);
    float pdf = env_cell_pdf(sc, col, row) / (as_float(TWO_PI2_BITS) * sin_theta);
    return isfinite(pdf) ? pdf : 0.0f;
}
#endif
