/* The glTF metallic-roughness BSDF: render/ggx/mod.rs and ggx/glass.rs,
 * operation for operation (see there for the model). T is the scene's
 * `ggx` array: the host's directional-albedo tables, TABLE_N x TABLE_N
 * floats of A, as many of B, then TABLE_N averages of each (GGX_TABLE_LEN
 * floats); where a material transmits, the rough glass's table follows. A
 * material's pbr field holds (metallic, alpha, roughness, f0), its glass
 * field (transmission, ior, 1 for a thin wall), its coat field (clear coat
 * weight, alpha, roughness). Directions are in the shading frame (z the
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

#if HAS_TRANSMISSION
/* The rough dielectric lobe (ggx/glass.rs, Glass): alpha, eta (the far
 * side's index over wo's side's), scale = 1 / E(mu_o); where tinted,
 * KHR_materials_specular's Tint (f0, spec_f0, spec_f90). */
typedef struct {
    float alpha, eta, scale;
    int thin; /* a thin wall: transmission is the reflection mirrored */
    int tinted;
    float f0, spec_f90;
    float3 spec_f0;
} GgxGlass;

/* Table::albedo: E(mu) of the glass table G at roughness and ior, for
 * light arriving from outside (entering) or inside; trilinear. */
static inline float glass_albedo(__global const float *G, float mu, float roughness, float ior, int entering) {
    uint n = GGX_TABLE_N;
    uint i, j;
    float tx = ggx_cell(mu, &i);
    float ty = ggx_cell(roughness, &j);
    float x = (ior - 1.0f) / (ior + 1.0f);
    float s = fmin(fmax(x * as_float(GLASS_IOR_SCALE_BITS), 0.0f), 1.0f) * (float)(GLASS_IOR_N - 1u);
    uint k = min((uint)s, GLASS_IOR_N - 2u);
    float tz = s - (float)k;
    uint side = entering ? 0u : 1u;
    float plane[2];
    for (uint q = 0u; q < 2u; q++) {
        __global const float *t = G + (side * GLASS_IOR_N + k + q) * n * n;
        float row0 = t[j * n + i] * (1.0f - tx) + t[j * n + i + 1u] * tx;
        float row1 = t[(j + 1u) * n + i] * (1.0f - tx) + t[(j + 1u) * n + i + 1u] * tx;
        plane[q] = row0 * (1.0f - ty) + row1 * ty;
    }
    return plane[0] * (1.0f - tz) + plane[1] * tz;
}

/* fresnel::exact(cos_i, 1, eta).reflectance. */
static inline float glass_fresnel(float c, float eta, float *cos_t) {
    float ct = cos_transmitted(c, 1.0f, eta);
    if (ct < 0.0f) {
        *cos_t = 0.0f;
        return 1.0f;
    }
    *cos_t = ct;
    return fresnel_exact(c, ct, 1.0f, eta);
}

/* glass.rs, tinted: *r the reflectance per channel of exact Fresnel
 * reflectance f under the glass's tint; returns the probability of
 * reflecting (its largest channel). */
static inline float glass_tinted(const GgxGlass *g, float f, float3 *r) {
    if (!g->tinted) {
        *r = (float3)(f);
        return f;
    }
    if (f >= 1.0f) { /* total internal reflection: all is reflected */
        *r = (float3)(1.0f);
        return 1.0f;
    }
    float s = fmin(fmax((f - g->f0) / (1.0f - g->f0), 0.0f), 1.0f);
    *r = g->spec_f0 + ((float3)(g->spec_f90) - g->spec_f0) * s;
    return fmax(fmax(r->x, r->y), r->z);
}

/* Glass::split_at: the reflectance per channel at a microfacet seen at
 * cosine c, and the probability of reflecting. */
static inline float glass_split_at(const GgxGlass *g, float c, float3 *r) {
    float cos_t;
    return glass_tinted(g, glass_fresnel(c, g->eta, &cos_t), r);
}

/* The refraction's half vector facing wo's side; 0 where no microfacet
 * refracts wo to wi. */
static inline int glass_refraction_half(const GgxGlass *g, float3 wo, float3 wi, float3 *h) {
    float3 v = wo + wi * g->eta;
    float len = sqrt(dot3(v, v));
    if (!(len > 0.0f)) {
        return 0;
    }
    *h = v.z < 0.0f ? -v / len : v / len;
    return dot3(wo, *h) > 0.0f && dot3(wi, *h) < 0.0f;
}

/* Glass::thin_eval_cos. */
static inline float4 glass_thin_eval_cos(const GgxGlass *g, float3 wo, float3 wi) {
    float3 w = (float3)(wi.x, wi.y, fabs(wi.z));
    float a = g->alpha;
    float ro = ggx_smith_r(wo, a);
    float ri = ggx_smith_r(w, a);
    float3 h = normalize3(wo + w);
    float3 f;
    float m = glass_split_at(g, fmax(dot3(wo, h), 0.0f), &f);
    float spec = ggx_d(h, a) / (2.0f * (ro * w.z + ri * wo.z)) * w.z * g->scale;
    return wi.z > 0.0f ? (float4)(f * spec, 0.0f) : (float4)(0.0f, 0.0f, 0.0f, (1.0f - m) * spec);
}

/* Glass::eval_cos: reflected BSDF |cos_i| per channel (xyz), transmitted
 * (w, white). */
static inline float4 glass_eval_cos(const GgxGlass *g, float3 wo, float3 wi) {
    if (g->thin) {
        return glass_thin_eval_cos(g, wo, wi);
    }
    float a = g->alpha;
    float ro = ggx_smith_r(wo, a);
    float ri = ggx_smith_r(wi, a);
    float3 f;
    if (wi.z > 0.0f) {
        float3 h = normalize3(wo + wi);
        glass_split_at(g, fmax(dot3(wo, h), 0.0f), &f);
        float spec = ggx_d(h, a) / (2.0f * (ro * wi.z + ri * wo.z));
        return (float4)(f * (spec * wi.z * g->scale), 0.0f);
    }
    float3 h;
    if (!glass_refraction_half(g, wo, wi, &h)) {
        return (float4)(0.0f);
    }
    float oh = dot3(wo, h);
    float ih = -dot3(wi, h);
    float m = glass_split_at(g, oh, &f);
    float ci = -wi.z;
    float denom = oh - g->eta * ih;
    float t = (1.0f - m) * ggx_d(h, a) * g->eta * g->eta * oh * ih * 2.0f * ci / ((ro * ci + ri * wo.z) * (denom * denom));
    return (float4)(0.0f, 0.0f, 0.0f, t * g->scale);
}

/* Glass::pdf. */
static inline float glass_pdf(const GgxGlass *g, float3 wo, float3 wi) {
    float a = g->alpha;
    float ro = ggx_smith_r(wo, a);
    float3 r;
    if (g->thin) {
        float3 w = (float3)(wi.x, wi.y, fabs(wi.z));
        float3 h = normalize3(wo + w);
        float f = glass_split_at(g, fmax(dot3(wo, h), 0.0f), &r);
        float vndf = ggx_d(h, a) / (2.0f * (wo.z + ro));
        return (wi.z > 0.0f ? f : 1.0f - f) * vndf;
    }
    if (wi.z > 0.0f) {
        float3 h = normalize3(wo + wi);
        float f = glass_split_at(g, fmax(dot3(wo, h), 0.0f), &r);
        return f * ggx_d(h, a) / (2.0f * (wo.z + ro));
    }
    float3 h;
    if (!glass_refraction_half(g, wo, wi, &h)) {
        return 0.0f;
    }
    float oh = dot3(wo, h);
    float ih = -dot3(wi, h);
    float f = glass_split_at(g, oh, &r);
    float denom = oh - g->eta * ih;
    return (1.0f - f) * 2.0f * ggx_d(h, a) * oh * g->eta * g->eta * ih / ((wo.z + ro) * (denom * denom));
}

/* Glass::sample: 0 where the direction leaves on the wrong side. */
static inline int glass_sample(const GgxGlass *g, float3 wo, float choice, float2 u, float3 *wi) {
    float3 h = ggx_visible_normal(wo, g->alpha, u);
    float c = fmax(dot3(wo, h), 0.0f);
    float cos_t;
    float3 r;
    float f = glass_tinted(g, glass_fresnel(c, g->eta, &cos_t), &r);
    if (g->thin) {
        float3 wr = ggx_reflect(wo, h);
        *wi = choice < f ? wr : (float3)(wr.x, wr.y, -wr.z);
        return wr.z > 0.0f;
    }
    if (choice < f) {
        *wi = ggx_reflect(wo, h);
        return wi->z > 0.0f;
    }
    *wi = normalize3(h * (c / g->eta - cos_t) - wo / g->eta);
    return wi->z < 0.0f;
}
#endif

#if HAS_COAT
/* The clear coat at one shading point (ggx/coat.rs, Coat): weight 0 where
 * there is none. */
typedef struct {
    float weight, alpha, roughness, e_o, e_avg, fms, keep, p;
#if HAS_COAT_NORMAL
    /* Its own frame in the base's (coat.rs, Frame), where framed. */
    float3 ft, fb, fn;
    int framed;
#endif
} GgxCoat;
#endif

typedef struct {
    float e_o, a_avg, b_avg;
    float3 fms_metal;
    float3 f0, fms_diel, es_o, es_avg; /* the dielectric's F0 per channel */
    float f90, p_spec;
#if HAS_TRANSMISSION
    float p_glass;
    GgxGlass glass;
#endif
#if HAS_COAT
    GgxCoat coat;
#endif
} GgxLobes;

static inline float ggx_fresnel_factor(float f_avg, float e_avg) {
    return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

static inline float ggx_mean3(float3 v) {
    return (v.x + v.y + v.z) * (1.0f / 3.0f);
}

#if HAS_COAT
#define GGX_COAT_F0 0.04f

/* Frame::local: v (base frame) in the coat's frame, where it has one. */
static inline float3 ggx_coat_local(const GgxCoat *c, float3 v) {
#if HAS_COAT_NORMAL
    if (c->framed) {
        return (float3)(dot3(v, c->ft), dot3(v, c->fb), dot3(v, c->fn));
    }
#endif
    return v;
}

/* Coat::framed: the coat of k = (weight, alpha, roughness) seen from wo
 * over a base that reflects base_albedo towards wo, on its own unit normal
 * cn (base frame; zero: the base's). */
static inline GgxCoat ggx_coat(__global const float *T, float4 k, float3 wo, float base_albedo, float3 cn) {
    GgxCoat c;
#if HAS_COAT_NORMAL
    c.framed = cn.x != 0.0f || cn.y != 0.0f || cn.z != 0.0f;
    if (c.framed) {
        basis(cn, &c.ft, &c.fb);
        c.fn = cn;
        wo = ggx_coat_local(&c, wo);
        if (!(wo.z > 0.0f)) {
            c.weight = 0.0f;
            c.keep = 1.0f;
            c.p = 0.0f;
            return c;
        }
    }
#else
    (void)cn;
#endif
    float a_o = ggx_at(T, 0u, wo.z, k.z);
    float b_o = ggx_at(T, 1u, wo.z, k.z);
    c.weight = k.x;
    c.alpha = k.y;
    c.roughness = k.z;
    c.e_o = a_o + b_o;
    c.e_avg = ggx_avg(T, 0u, k.z) + ggx_avg(T, 1u, k.z);
    c.fms = ggx_fresnel_factor(GGX_COAT_F0 + (1.0f - GGX_COAT_F0) * (1.0f / 21.0f), c.e_avg);
    float es_o = GGX_COAT_F0 * a_o + b_o + (1.0f - c.e_o) * c.fms;
    float reflected = k.x * es_o;
    c.keep = 1.0f - reflected;
    c.p = fmin(fmax(reflected / fmax(reflected + c.keep * base_albedo, 1e-6f), 0.05f), 0.95f);
    return c;
}

/* Coat::eval_cos: the coat's BSDF |cos| (weight included; white). */
static inline float ggx_coat_eval_cos(__global const float *T, const GgxCoat *c, float3 wo, float3 wi) {
    wo = ggx_coat_local(c, wo);
    wi = ggx_coat_local(c, wi);
    if (!(wi.z > 0.0f && wo.z > 0.0f)) {
        return 0.0f;
    }
    float a = c->alpha;
    float3 h = normalize3(wo + wi);
    float ro = ggx_smith_r(wo, a);
    float ri = ggx_smith_r(wi, a);
    float spec = ggx_d(h, a) / (2.0f * (ro * wi.z + ri * wo.z));
    float c5 = ggx_pow5(1.0f - fmin(fmax(dot3(wo, h), 0.0f), 1.0f));
    float e_i = ggx_at(T, 0u, wi.z, c->roughness) + ggx_at(T, 1u, wi.z, c->roughness);
    float ms = (1.0f - c->e_o) * (1.0f - e_i) * M_1_PI_F / fmax(1.0f - c->e_avg, 1e-6f);
    return c->weight * ((GGX_COAT_F0 + (1.0f - GGX_COAT_F0) * c5) * spec + c->fms * ms) * wi.z;
}

/* Coat::pdf: the density of wi by the coat's visible normals. */
static inline float ggx_coat_pdf(const GgxCoat *c, float3 wo, float3 wi) {
    wo = ggx_coat_local(c, wo);
    wi = ggx_coat_local(c, wi);
    if (!(wi.z > 0.0f && wo.z > 0.0f)) {
        return 0.0f;
    }
    float3 h = normalize3(wo + wi);
    return ggx_d(h, c->alpha) / (2.0f * (wo.z + ggx_smith_r(wo, c->alpha)));
}
#endif

/* Lobes::framed: the lobes seen from wo on a surface reached from outside
 * (entering) or inside; g: the material's glass field; cn: the coat's own
 * unit normal in the shading frame (zero: the shading normal). */
static inline GgxLobes ggx_lobes(__global const float *T, float4 p, float4 g, float4 k, float4 sp, float3 base,
                                 float3 wo, int entering, float3 cn) {
    GgxLobes L;
    float metallic = p.x;
    float3 f0 = sp.xyz;
    float f90 = sp.w;
    L.f0 = f0;
    L.f90 = f90;
    float a_o = ggx_at(T, 0u, wo.z, p.z);
    float b_o = ggx_at(T, 1u, wo.z, p.z);
    L.a_avg = ggx_avg(T, 0u, p.z);
    L.b_avg = ggx_avg(T, 1u, p.z);
    L.e_o = a_o + b_o;
    float e_avg = L.a_avg + L.b_avg;
    float3 f_avg_metal = base + ((float3)(1.0f) - base) * (1.0f / 21.0f);
    L.fms_metal = (float3)(ggx_fresnel_factor(f_avg_metal.x, e_avg), ggx_fresnel_factor(f_avg_metal.y, e_avg),
                           ggx_fresnel_factor(f_avg_metal.z, e_avg));
    float3 f_avg_diel = f0 + ((float3)(f90) - f0) * (1.0f / 21.0f);
    L.fms_diel = (float3)(ggx_fresnel_factor(f_avg_diel.x, e_avg), ggx_fresnel_factor(f_avg_diel.y, e_avg),
                          ggx_fresnel_factor(f_avg_diel.z, e_avg));
    L.es_o = f0 * a_o + (float3)(f90 * b_o) + L.fms_diel * (1.0f - L.e_o);
    L.es_avg = f0 * L.a_avg + (float3)(f90 * L.b_avg) + L.fms_diel * (1.0f - e_avg);
    float spec = metallic * ggx_mean3(base * a_o + (float3)(b_o)) +
                 (1.0f - metallic) * ggx_mean3(f0 * a_o + (float3)(f90 * b_o));
    float rest = metallic * (1.0f - L.e_o) * ggx_mean3(L.fms_metal) +
                 (1.0f - metallic) * ggx_mean3(L.fms_diel * (1.0f - L.e_o) + ((float3)(1.0f) - L.es_o) * base);
    L.p_spec = fmin(fmax(spec / (spec + rest), 0.05f), 0.95f);
#if HAS_TRANSMISSION
    L.p_glass = (1.0f - metallic) * g.x;
    L.glass.alpha = p.y;
    L.glass.eta = 1.0f;
    L.glass.scale = 0.0f;
    L.glass.thin = g.z != 0.0f;
    /* KHR_materials_specular's tint (glass.rs, Tint::new). */
    L.glass.f0 = p.w;
    L.glass.spec_f0 = f0;
    L.glass.spec_f90 = f90;
    L.glass.tinted = f90 != 1.0f || f0.x != p.w || f0.y != p.w || f0.z != p.w;
    if (L.p_glass > 0.0f && L.glass.thin) {
        L.glass.eta = g.y;
        L.glass.scale = 1.0f / fmax(L.e_o, 0.05f);
    } else if (L.p_glass > 0.0f) {
        float e = glass_albedo(T + GGX_TABLE_LEN, wo.z, p.z, g.y, entering);
        if (L.glass.tinted) { /* Glass::with_tint: towards the clear glass's */
            uint part = 2u * GLASS_IOR_N * GGX_TABLE_N * GGX_TABLE_N;
            float e0 = glass_albedo(T + GGX_TABLE_LEN + part, wo.z, p.z, g.y, entering);
            e = e0 + (e - e0) * f90;
        }
        L.glass.eta = entering ? g.y : 1.0f / g.y;
        L.glass.scale = 1.0f / fmax(e, 0.05f);
    }
#else
    (void)g;
#endif
#if HAS_COAT
    /* The coat faces outwards: both sides of an opaque surface or a thin
     * wall, the outside of a transmitting solid. */
    float p_glass = 0.0f;
    int thin = 0;
#if HAS_TRANSMISSION
    p_glass = L.p_glass;
    thin = L.glass.thin;
#endif
    L.coat.weight = 0.0f;
    if (k.x > 0.0f && (entering || p_glass == 0.0f || thin)) {
        float below = (spec + rest) * (1.0f - p_glass) + p_glass;
        L.coat = ggx_coat(T, k, wo, below, cn);
    }
#else
    (void)k;
    (void)cn;
#endif
    (void)entering;
    return L;
}

/* BSDF |cos| (ggx/mod.rs, eval_reflection): the single-scattering
 * microfacet lobes, the multiple-scattering lobes and the diffuse base. */
static inline float3 ggx_eval_reflection(__global const float *T, float4 p, float4 g, float3 base, const GgxLobes *L,
                                         float3 wo, float3 wi) {
    if (!(wi.z > 0.0f && wo.z > 0.0f)) {
        return (float3)(0.0f);
    }
    float alpha = p.y;
    float metallic = p.x;
    float3 f0 = L->f0;
    float f90 = L->f90;
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
    float3 es_i = f0 * a_i + (float3)(f90 * b_i) + L->fms_diel * (1.0f - e_i);
    float3 diffuse = ((float3)(1.0f) - L->es_o) * ((float3)(1.0f) - es_i) * M_1_PI_F /
                     fmax((float3)(1.0f) - L->es_avg, (float3)(1e-6f));
    float layer = (1.0f - metallic) * (1.0f - g.x);
    float3 single = (base + ((float3)(1.0f) - base) * c5) * (spec * metallic) +
                    (f0 + ((float3)(f90) - f0) * c5) * (spec * layer);
    float3 multiple = L->fms_metal * (ms * metallic) + (base * diffuse + L->fms_diel * ms) * layer;
    return (single + multiple) * wi.z;
}

/* BSDF |cos| (ggx/mod.rs, eval_cos): the lobes above, and the rough glass
 * where the material transmits. */
static inline float3 ggx_eval_cos(__global const float *T, float4 p, float4 g, float3 base, const GgxLobes *L, float3 wo,
                                  float3 wi) {
    float3 out = (float3)(0.0f);
#if HAS_TRANSMISSION
    if (L->p_glass > 0.0f && wo.z > 0.0f) {
        float4 rt = glass_eval_cos(&L->glass, wo, wi);
        out = (rt.xyz + base * rt.w) * L->p_glass;
    }
#endif
    out += ggx_eval_reflection(T, p, g, base, L, wo, wi);
#if HAS_COAT
    if (L->coat.weight > 0.0f) {
        out = out * L->coat.keep + (float3)(ggx_coat_eval_cos(T, &L->coat, wo, wi));
    }
#endif
    return out;
}

/* pdf_under_coat: the density of the lobes under the coat. */
static inline float ggx_pdf_under_coat(float4 p, const GgxLobes *L, float3 wo, float3 wi) {
    if (!(wo.z > 0.0f)) {
        return 0.0f;
    }
    float glass = 0.0f;
    float rest = 1.0f;
#if HAS_TRANSMISSION
    if (L->p_glass > 0.0f) {
        glass = L->p_glass * glass_pdf(&L->glass, wo, wi);
    }
    rest = 1.0f - L->p_glass;
#endif
    if (!(wi.z > 0.0f)) {
        return glass;
    }
    float3 h = normalize3(wo + wi);
    float vndf = ggx_d(h, p.y) / (2.0f * (wo.z + ggx_smith_r(wo, p.y)));
    return (L->p_spec * vndf + (1.0f - L->p_spec) * wi.z * M_1_PI_F) * rest + glass;
}

/* The sampling density of wi (solid angle) from wo (ggx/mod.rs, pdf). */
static inline float ggx_pdf(float4 p, const GgxLobes *L, float3 wo, float3 wi) {
    float under = ggx_pdf_under_coat(p, L, wo, wi);
#if HAS_COAT
    if (L->coat.weight > 0.0f) {
        return L->coat.p * ggx_coat_pdf(&L->coat, wo, wi) + (1.0f - L->coat.p) * under;
    }
#endif
    return under;
}

/* A direction from wo (shading frame) on a surface reached from outside
 * (entering) or inside, *weight = BSDF |cos| / pdf and *pdf its density;
 * returns 0 where the sample leaves on the wrong side (no contribution). */
static inline int ggx_sample(__global const float *T, float4 p, float4 g, float4 k, float4 sp, float3 base,
                             float3 wo, int entering, float3 cn, float choice, float2 u, float3 *wi, float3 *weight,
                             float *pdf_out) {
    if (!(wo.z > 0.0f)) {
        return 0;
    }
    GgxLobes L = ggx_lobes(T, p, g, k, sp, base, wo, entering, cn);
    float3 w;
    int drawn = 0;
    float under = 1.0f; /* what the coat lets through over 1 - its probability */
#if HAS_COAT
    if (L.coat.weight > 0.0f) {
        if (choice < L.coat.p) {
            float3 wc = ggx_coat_local(&L.coat, wo);
            if (!(wc.z > 0.0f)) {
                return 0;
            }
            w = ggx_reflect(wc, ggx_visible_normal(wc, L.coat.alpha, u));
            if (!(w.z > 0.0f)) {
                return 0;
            }
#if HAS_COAT_NORMAL
            if (L.coat.framed) {
                w = L.coat.ft * w.x + L.coat.fb * w.y + L.coat.fn * w.z;
            }
#endif
            drawn = 1;
        } else {
            choice = (choice - L.coat.p) / (1.0f - L.coat.p);
            under = L.coat.keep / (1.0f - L.coat.p);
        }
    }
#endif
    if (!drawn) {
#if HAS_TRANSMISSION
    if (choice < L.p_glass) {
        if (!L.glass.thin && fabs(L.glass.eta - 1.0f) < as_float(GLASS_MATCHED_BITS)) {
            /* Index-matched: straight through, tinted (Glass::matched). */
            *wi = -wo;
            *weight = base * under;
            *pdf_out = 0.0f;
            return 1;
        }
        if (!glass_sample(&L.glass, wo, choice / L.p_glass, u, &w)) {
            return 0;
        }
    } else {
        choice = (choice - L.p_glass) / (1.0f - L.p_glass);
#else
    {
#endif
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
    }
    }
    (void)under;
    float pdf = ggx_pdf(p, &L, wo, w);
    if (!(pdf > 0.0f)) {
        return 0;
    }
    *wi = w;
    *weight = ggx_eval_cos(T, p, g, base, &L, wo, w) / pdf;
    *pdf_out = pdf;
    return 1;
}

#endif
