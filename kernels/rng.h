/* Random numbers for paths: the CPU twin is server/src/render/sampler/
 * (same constants, same bits, so both make the same decisions). A sampler
 * is `random` (independent numbers drawn in order) or `sobol` (padded,
 * Owen-scrambled Sobol points, one dimension per use of a vertex). */

/* A path's numbers by use (Sampler::camera_2d, light_pick_2d, ...): random
 * draws in order, Sobol takes the use's own dimension at the vertex: Sobol
 * points for the camera, the first SOBOL_VERTICES vertices and every
 * roulette, independent numbers (pad_bits) for the rest. */
/* 0 is unused: it was the light pick's (now light_pick_2d's x). */
#define USE_LIGHT_POSITION 1UL
#define USE_BSDF_CHOICE 2UL
#define USE_BSDF_DIRECTION 3UL
#define USE_ROULETTE 4UL
#define VERTEX_USES 5UL

#ifndef SAMPLER_AHEAD
#define SAMPLER_AHEAD 0
#endif

static inline ulong mix64(ulong z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9UL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBUL;
    return z ^ (z >> 31);
}

typedef struct {
    ulong key;
    ulong rkey;    /* sobol: the key of the sample's independent numbers */
    ulong dim;     /* random: dimensions drawn */
    uint rindex;   /* sobol: the sample's index in its half, bit-reversed */
    uint vertex;   /* sobol: the vertex whose numbers are drawn */
    int sobol;
#if SAMPLER_AHEAD
    /* sobol: the camera's point and vertex 0's light position and BSDF
     * direction (dimensions 0, 2 and 4), made with the sampler (32-bit
     * fixed point: the light pick reads all of the light's x). */
    uint2 ahead[3];
#endif
} Sampler;

static inline uint reverse32(uint x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
    x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
    return (x >> 16) | (x << 16);
}

/* The `random` numbers of a sample (sampler/mod.rs, Sampler::new). */
static inline Sampler sampler_new(ulong seed, ulong pixel, ulong sample) {
    Sampler s;
    s.key = mix64(mix64(mix64(seed ^ 0x5851F42D4C957F2DUL) ^ pixel) ^ sample);
    s.rkey = 0UL;
    s.dim = 0;
    s.rindex = 0u;
    s.vertex = 0u;
    s.sobol = 0;
    return s;
}

static inline uint2 sobol_2d_bits(const Sampler *s, ulong d);

/* The dimension of one use of the sampler at its vertex. */
static inline ulong vertex_dim(const Sampler *s, ulong use) {
    return 1UL + (ulong)s->vertex * VERTEX_USES + use;
}

/* A sample's numbers of either kind (Sampler::of_kind). With
 * SAMPLER_AHEAD (the host sets it for CPU devices), a Sobol sampler makes
 * the three 2-D points every path draws first together, as the CPU does:
 * three independent chains of multiplies side by side instead of each on
 * the critical path where it is used (21% more paths/s on PoCL's cornell).
 * The same numbers either way; GPUs keep them lazy until measured, since
 * the points would be held in six registers across the camera ray. */
static inline Sampler sampler_of_kind(int sobol, ulong seed, ulong pixel, ulong sample) {
    if (!sobol) {
        return sampler_new(seed, pixel, sample);
    }
    Sampler s;
    s.key = mix64(mix64(mix64(seed ^ 0x5851F42D4C957F2DUL) ^ pixel) ^ (sample & 1UL) ^ 0xA0761D6478BD642FUL);
    s.dim = 0;
    s.rindex = reverse32((uint)(sample >> 1));
    s.rkey = mix64(s.key ^ (ulong)s.rindex);
    s.vertex = 0u;
    s.sobol = 1;
#if SAMPLER_AHEAD
    s.ahead[0] = sobol_2d_bits(&s, 0UL);
    s.ahead[1] = sobol_2d_bits(&s, vertex_dim(&s, USE_LIGHT_POSITION));
    s.ahead[2] = sobol_2d_bits(&s, vertex_dim(&s, USE_BSDF_DIRECTION));
#endif
    return s;
}

static inline ulong next_bits(Sampler *s) {
    s->dim += 1;
    return mix64(s->key + s->dim * 0x9E3779B97F4A7C15UL);
}

/* 24 bits as a number in [0, 1) (sampler/mod.rs, unit_24). */
static inline float unit_24(ulong bits) {
    return (float)(bits & 0xFFFFFFUL) * (1.0f / 16777216.0f);
}

/* A random 2-D sample from 64 bits: the top 24 and the next 24 (pair_24). */
static inline float2 pair_24(ulong bits) {
    return (float2)(unit_24(bits >> 40), unit_24(bits >> 16));
}

static inline float next_f32(Sampler *s) {
    return unit_24(next_bits(s) >> 40);
}

static inline float2 next_2d(Sampler *s) {
    return pair_24(next_bits(s));
}

/* Sobol points, as sampler/sobol.rs: 2-D Owen-scrambled, 1-D shuffled. */
static inline uint lk_hash(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

static inline uint hash32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    return x ^ (x >> 16);
}

static inline uint superset_sum(uint y) {
    y ^= (y >> 1) & 0x55555555u;
    y ^= (y >> 2) & 0x33333333u;
    y ^= (y >> 4) & 0x0F0F0F0Fu;
    y ^= (y >> 8) & 0x00FF00FFu;
    y ^= (y >> 16) & 0x0000FFFFu;
    return y;
}

static inline float unit_f32(uint v) {
    return (float)(v >> 8) * (1.0f / 16777216.0f);
}

/* Seeds of dimension d (index shuffle, x, y) and the shuffled index. */
static inline uint sobol_index(const Sampler *s, ulong d, uint *sx, uint *sy) {
    ulong h = mix64(s->key + d * 0x9E3779B97F4A7C15UL);
    *sx = (uint)(h >> 32);
    *sy = hash32(*sx ^ 0x2545F491u);
    return reverse32(lk_hash(s->rindex, (uint)h));
}

/* 1-D: the van der Corput point of the shuffled index, which is the
 * shuffle's hash itself (sobol.rs, sample_1d). */
static inline uint sobol_1d(const Sampler *s, ulong d) {
    return lk_hash(s->rindex, (uint)mix64(s->key + d * 0x9E3779B97F4A7C15UL));
}

static inline uint2 sobol_2d_bits(const Sampler *s, ulong d) {
    uint sx, sy;
    uint i = sobol_index(s, d, &sx, &sy);
    return (uint2)(reverse32(lk_hash(i, sx)), reverse32(lk_hash(superset_sum(i), sy)));
}

static inline float2 unit_2d(uint2 v) {
    return (float2)(unit_f32(v.x), unit_f32(v.y));
}

static inline float2 sobol_2d(const Sampler *s, ulong d) {
    return unit_2d(sobol_2d_bits(s, d));
}

static inline int stratified(const Sampler *s) {
    return s->vertex < SOBOL_VERTICES;
}

static inline ulong pad_bits(const Sampler *s, ulong d) {
    return mix64(s->rkey + d * 0x9E3779B97F4A7C15UL);
}

static inline float2 pad_2d(const Sampler *s, ulong d) {
    return pair_24(pad_bits(s, d));
}

static inline float number_1d(const Sampler *s, ulong d, int strat) {
    return strat ? unit_f32(sobol_1d(s, d)) : unit_24(pad_bits(s, d) >> 40);
}

static inline void at_vertex(Sampler *s, uint v) {
    s->vertex = v;
}

static inline float2 camera_2d(Sampler *s) {
#if SAMPLER_AHEAD
    return s->sobol ? unit_2d(s->ahead[0]) : next_2d(s);
#else
    return s->sobol ? sobol_2d(s, 0UL) : next_2d(s);
#endif
}

/* A thin lens's point on its aperture (Sampler::lens_2d). */
static inline float2 lens_2d(Sampler *s) {
    return s->sobol ? sobol_2d(s, (ulong)LENS_DIMENSION_HI << 32) : next_2d(s);
}

/* Independent numbers for light_pick_2d: x the top 32 bits, the second
 * number the low 24. */
static inline float pad_second(ulong bits, uint *x) {
    *x = (uint)(bits >> 32);
    return unit_24(bits);
}

/* One of several emitters picked and a point on it from one 2-D sample
 * (Sampler::light_pick_2d): *x gets all 32 bits of the light position's
 * first coordinate (pick_light's input), the second comes back in [0, 1). */
static inline float light_pick_2d(Sampler *s, uint *x) {
    if (!s->sobol) {
        return pad_second(next_bits(s), x);
    }
    ulong d = vertex_dim(s, USE_LIGHT_POSITION);
    if (!stratified(s)) {
        return pad_second(pad_bits(s, d), x);
    }
#if SAMPLER_AHEAD
    uint2 v = s->vertex == 0u ? s->ahead[1] : sobol_2d_bits(s, d);
#else
    uint2 v = sobol_2d_bits(s, d);
#endif
    *x = v.x;
    return unit_f32(v.y);
}

static inline float2 light_2d(Sampler *s, uint k) {
    if (!s->sobol) {
        return next_2d(s);
    }
#if SAMPLER_AHEAD
    if (k == 0u && s->vertex == 0u) {
        return unit_2d(s->ahead[1]);
    }
#endif
    ulong d = k == 0u ? vertex_dim(s, USE_LIGHT_POSITION) : (0x8000000000000000UL | ((ulong)s->vertex << 32) | (ulong)k);
    return stratified(s) ? sobol_2d(s, d) : pad_2d(s, d);
}

static inline float bsdf_choice(Sampler *s) {
    return s->sobol ? number_1d(s, vertex_dim(s, USE_BSDF_CHOICE), stratified(s)) : next_f32(s);
}

static inline float2 bsdf_2d(Sampler *s) {
    if (!s->sobol) {
        return next_2d(s);
    }
#if SAMPLER_AHEAD
    if (s->vertex == 0u) {
        return unit_2d(s->ahead[2]);
    }
#endif
    ulong d = vertex_dim(s, USE_BSDF_DIRECTION);
    return stratified(s) ? sobol_2d(s, d) : pad_2d(s, d);
}

static inline float roulette(Sampler *s) {
    return s->sobol ? number_1d(s, vertex_dim(s, USE_ROULETTE), 1) : next_f32(s);
}

/* sin and cos of 2 pi u, as math.rs's sincos_turns. */
static inline float2 sincos_turns(float u) {
    float x = u * 4.0f;
    float quarter = floor(x);
    float a = (x - quarter - 0.5f) * 1.57079632679f;
    float a2 = a * a;
    float s = a * (1.0f + a2 * (-1.0f / 6.0f + a2 * (1.0f / 120.0f + a2 * (-1.0f / 5040.0f))));
    float c = 1.0f + a2 * (-0.5f + a2 * (1.0f / 24.0f + a2 * (-1.0f / 720.0f + a2 * (1.0f / 40320.0f))));
    float sin_q = (s + c) * 0.70710678118f;
    float cos_q = (c - s) * 0.70710678118f;
    int q = ((int)quarter) & 3;
    float2 r = (q & 1) == 0 ? (float2)(sin_q, cos_q) : (float2)(cos_q, -sin_q);
    return q >= 2 ? -r : r;
}

/* Orthonormal basis around unit n (Duff et al. 2017), as math.rs's basis. */
static inline void basis(float3 n, float3 *t, float3 *b) {
    float sign = copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float bb = n.x * n.y * a;
    *t = (float3)(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
    *b = (float3)(bb, sign + n.y * n.y * a, -n.y);
}

static inline float max3(float3 v) {
    return fmax(v.x, fmax(v.y, v.z));
}
