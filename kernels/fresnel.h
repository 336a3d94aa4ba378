/* How much light a smooth dielectric boundary reflects: fresnel.rs. */

/* cos of the transmitted angle, or -1 under total internal reflection. */
static inline float cos_transmitted(float cos_i, float n1, float n2) {
    float cos2_t = ((n2 - n1) * (n2 + n1) + n1 * n1 * cos_i * cos_i) / (n2 * n2);
    return cos2_t > 0.0f ? sqrt(cos2_t) : -1.0f;
}

#if (HAS_GLASS && HAS_EXACT) || HAS_TRANSMISSION
static inline float fresnel_exact(float cos_i, float cos_t, float n1, float n2) {
    float rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    float rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    float r = 0.5f * (rs * rs + rp * rp);
    return isfinite(r) ? fmin(r, 1.0f) : 1.0f;
}
#endif

#if HAS_GLASS && HAS_SCHLICK
static inline float fresnel_schlick(float cos_i, float cos_t, float n1, float n2) {
    float r0 = (n1 - n2) / (n1 + n2);
    r0 = r0 * r0;
    float c = n1 <= n2 ? cos_i : cos_t;
    float m = 1.0f - c;
    return r0 + (1.0f - r0) * m * m * m * m * m;
}
#endif
