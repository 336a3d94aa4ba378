/* Counter-based random numbers: the CPU twin is server/src/render/sampler.rs
 * (same constants, same bits, so both make the same decisions). */

inline ulong mix64(ulong z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9UL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBUL;
    return z ^ (z >> 31);
}

typedef struct {
    ulong key;
    ulong dim;
} Sampler;

inline Sampler sampler_new(ulong seed, ulong pixel, ulong sample) {
    Sampler s;
    s.key = mix64(mix64(mix64(seed ^ 0x5851F42D4C957F2DUL) ^ pixel) ^ sample);
    s.dim = 0;
    return s;
}

inline ulong next_bits(Sampler *s) {
    s->dim += 1;
    return mix64(s->key + s->dim * 0x9E3779B97F4A7C15UL);
}

inline float next_f32(Sampler *s) {
    return (float)(next_bits(s) >> 40) * (1.0f / 16777216.0f);
}

inline float2 next_2d(Sampler *s) {
    ulong bits = next_bits(s);
    return (float2)((float)(bits >> 40), (float)((bits >> 16) & 0xFFFFFFUL)) * (1.0f / 16777216.0f);
}

/* sin and cos of 2 pi u, as math.rs's sincos_turns. */
inline float2 sincos_turns(float u) {
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
inline void basis(float3 n, float3 *t, float3 *b) {
    float sign = copysign(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float bb = n.x * n.y * a;
    *t = (float3)(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
    *b = (float3)(bb, sign + n.y * n.y * a, -n.y);
}

inline float max3(float3 v) {
    return fmax(v.x, fmax(v.y, v.z));
}
