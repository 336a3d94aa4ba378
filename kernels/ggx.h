/* The glTF metallic-roughness BSDF: render/ggx.rs, operation for operation
 * (see there for the model). T is the scene's `ggx` array: the host's
 * directional-albedo tables, TABLE_N x TABLE_N floats of A, as many of B,
 * then TABLE_N averages of each. A material's pbr field holds (metallic,
 * alpha, roughness, f0). Directions are in the shading frame (z the
 * normal). */

#if HAS_GGX

/* The cell of x in [0, 1] (*i) and the position within it. */
static inline float ggx_cell(float x, uint *i) {
    float s = fmin(fmax(x, 0.0f), 1.0f) * (float)(GGX_TABLE_N - 1u);
    uint c = min((uint)s, GGX_TABLE_N - 2u);
    *i = c;
    return s - (float)c;
}

static inline float ggx_at(__global const float *T, uint part, float mu, float roughness) {
    uint n = GGX_TABLE_N;
    uint i, j;
    float tx = ggx_cell(mu, &i);
    float ty = ggx_cell(roughness, &j);
    __global const float *t = T + part * n * n;
    float row0 = t[j * n + i] * (1.0f - tx) + t[j * n + i + 1u] * tx;
    float row1 = t[(j + 1u) * n + i] * (1.0f - tx) + t[(j + 1u) * n + i + 1u] * tx;
    return row0 * (1.0f - ty) + row1 * ty;
}

static inline float ggx_avg(__global const float *T, uint part, float roughness) {
    uint j;
    float t = ggx_cell(roughness, &j);
    __global const float *a = T + 2u * GGX_TABLE_N * GGX_TABLE_N + part * GGX_TABLE_N;
    return a[j] * (1.0f - t) + a[j + 1u] * t;
}

static inline float ggx_pow5(float x) {
    float x2 = x * x;
    return x2 * x2 * x;
}

static inline float ggx_smith_r(float3 w, float alpha) {
    float s2 = w.x * w.x + w.y * w.y;
    return sqrt(w.z * w.z + alpha * alpha * s2);
}

static inline float ggx_d(float3 h, float alpha) {
    float a2 = alpha * alpha;
    float t = h.x * h.x + h.y * h.y + a2 * (h.z * h.z);
    return a2 / (M_PI_F * (t * t));
}

static inline float3 ggx_reflect(float3 wo, float3 h) {
    return h * (2.0f * dot3(wo, h)) - wo;
}

static inline float3 ggx_visible_normal(float3 wo, float alpha, float2 u) {
    float3 v = normalize3((float3)(wo.x * alpha, wo.y * alpha, wo.z));
    float2 sc = sincos_turns(u.x);
    float z = (1.0f - u.y) * (1.0f + v.z) - v.z;
    float sin_t = sqrt(fmax(1.0f - z * z, 0.0f));
    float3 c = (float3)(sin_t * sc.y, sin_t * sc.x, z) + v;
    return normalize3((float3)(c.x * alpha, c.y * alpha, c.z));
}

typedef struct {
    float e_o, a_avg, b_avg;
    float3 fms_metal;
    float fms_diel, es_o, es_avg, p_spec;
} GgxLobes;

static inline float ggx_fresnel_factor(float f_avg, float e_avg) {
    return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

static inline float ggx_mean3(float3 v) {
    return (v.x + v.y + v.z) * (1.0f / 3.0f);
}

static inline GgxLobes ggx_lobes(__global const float *T, float4 p, float3 base, float3 wo) {
    GgxLobes L;
    float f0 = p.w;
    float metallic = p.x;
    float a_o = ggx_at(T, 0u, wo.z, p.z);
    float b_o = ggx_at(T, 1u, wo.z, p.z);
    L.a_avg = ggx_avg(T, 0u, p.z);
    L.b_avg = ggx_avg(T, 1u, p.z);
    L.e_o = a_o + b_o;
    float e_avg = L.a_avg + L.b_avg;
    float3 f_avg_metal = base + ((float3)(1.0f) - base) * (1.0f / 21.0f);
    L.fms_metal = (float3)(ggx_fresnel_factor(f_avg_metal.x, e_avg), ggx_fresnel_factor(f_avg_metal.y, e_avg),
                           ggx_fresnel_factor(f_avg_metal.z, e_avg));
    L.fms_diel = ggx_fresnel_factor(f0 + (1.0f - f0) * (1.0f / 21.0f), e_avg);
    L.es_o = f0 * a_o + b_o + (1.0f - L.e_o) * L.fms_diel;
    L.es_avg = f0 * L.a_avg + L.b_avg + (1.0f - e_avg) * L.fms_diel;
    float spec = metallic * ggx_mean3(base * a_o + (float3)(b_o)) + (1.0f - metallic) * (f0 * a_o + b_o);
    float rest = metallic * (1.0f - L.e_o) * ggx_mean3(L.fms_metal) +
                 (1.0f - metallic) * ((1.0f - L.e_o) * L.fms_diel + (1.0f - L.es_o) * ggx_mean3(base));
    L.p_spec = fmin(fmax(spec / (spec + rest), 0.05f), 0.95f);
    return L;
}

/* BSDF cos (ggx.rs, eval_cos): the single-scattering microfacet lobes,
 * the multiple-scattering lobes and the diffuse base. */
static inline float3 ggx_eval_cos(__global const float *T, float4 p, float3 base, const GgxLobes *L, float3 wo,
                                  float3 wi) {
    if (!(wi.z > 0.0f && wo.z > 0.0f)) {
        return (float3)(0.0f);
    }
    float alpha = p.y;
    float f0 = p.w;
    float metallic = p.x;
    float3 h = normalize3(wo + wi);
    float ro = ggx_smith_r(wo, alpha);
    float ri = ggx_smith_r(wi, alpha);
    float spec = ggx_d(h, alpha) / (2.0f * (ro * wi.z + ri * wo.z));
    float c5 = ggx_pow5(1.0f - fmin(fmax(dot3(wo, h), 0.0f), 1.0f));
    float a_i = ggx_at(T, 0u, wi.z, p.z);
    float b_i = ggx_at(T, 1u, wi.z, p.z);
    float e_i = a_i + b_i;
    float e_avg = L->a_avg + L->b_avg;
    float ms = (1.0f - L->e_o) * (1.0f - e_i) * M_1_PI_F / fmax(1.0f - e_avg, 1e-6f);
    float es_i = f0 * a_i + b_i + (1.0f - e_i) * L->fms_diel;
    float diffuse = (1.0f - L->es_o) * (1.0f - es_i) * M_1_PI_F / fmax(1.0f - L->es_avg, 1e-6f);
    float3 single = (base + ((float3)(1.0f) - base) * c5) * (spec * metallic) +
                    (float3)((f0 + (1.0f - f0) * c5) * spec * (1.0f - metallic));
    float3 multiple = L->fms_metal * (ms * metallic) + (base * diffuse + (float3)(L->fms_diel * ms)) * (1.0f - metallic);
    return (single + multiple) * wi.z;
}

static inline float ggx_pdf(float4 p, const GgxLobes *L, float3 wo, float3 wi) {
    if (!(wi.z > 0.0f && wo.z > 0.0f)) {
        return 0.0f;
    }
    float3 h = normalize3(wo + wi);
    float vndf = ggx_d(h, p.y) / (2.0f * (wo.z + ggx_smith_r(wo, p.y)));
    return L->p_spec * vndf + (1.0f - L->p_spec) * wi.z * M_1_PI_F;
}

/* A direction from wo (shading frame), *weight = BSDF cos / pdf and *pdf
 * its density; returns 0 where the sample leaves below the surface (no
 * contribution). */
static inline int ggx_sample(__global const float *T, float4 p, float3 base, float3 wo, float choice, float2 u, float3 *wi,
                      float3 *weight, float *pdf_out) {
    if (!(wo.z > 0.0f)) {
        return 0;
    }
    GgxLobes L = ggx_lobes(T, p, base, wo);
    float3 w;
    if (choice < L.p_spec) {
        w = ggx_reflect(wo, ggx_visible_normal(wo, p.y, u));
    } else {
        float2 sc = sincos_turns(u.x);
        float r = sqrt(u.y);
        w = (float3)(r * sc.y, r * sc.x, sqrt(fmax(1.0f - u.y, 0.0f)));
    }
    if (!(w.z > 0.0f)) {
        return 0;
    }
    float pdf = ggx_pdf(p, &L, wo, w);
    if (!(pdf > 0.0f)) {
        return 0;
    }
    *wi = w;
    *weight = ggx_eval_cos(T, p, base, &L, wo, w) / pdf;
    *pdf_out = pdf;
    return 1;
}

#endif
