/* Scattering: material.rs (the Fresnel equations: fresnel.h). */

static inline float3 cosine_hemisphere(float3 n, float2 u) {
    float2 sc = sincos_turns(u.x);
    float r = sqrt(u.y);
    float z = sqrt(fmax(1.0f - u.y, 0.0f));
    float3 t, b;
    basis(n, &t, &b);
    return t * (r * sc.y) + b * (r * sc.x) + n * z;
}

static inline float3 reflect_dir(float3 d, float3 n) {
    return d - n * (2.0f * dot3(d, n));
}

/* Samples the continuation of a ray along unit d that arrived at a
 * surface from outside (entering) or inside, nl the shading normal on the
 * side it came from, nc a clear coat's own normal on that side (zero: nl;
 * material.rs, scatter_with); ggx is the scene's table for
 * MAT_PBR. Returns the new direction; *weight is BSDF cos / pdf,
 * *specular whether it was a delta lobe, *transmitted whether it went
 * through, *pdf the density of a MAT_PBR direction for MIS, else 0
 * (Scattered::pdf). */
static inline float3 scatter(MatRef m, __global const float *ggx, float3 d, int entering, float3 nl, float3 nc,
                             Sampler *s, float3 *weight, int *specular, int *transmitted, float *pdf) {
    *weight = m->albedo.xyz;
    *pdf = 0.0f;
    *transmitted = 0;
#if HAS_DIFFUSE
    if (m->kind == MAT_DIFFUSE) {
        *specular = 0;
        return cosine_hemisphere(nl, bsdf_2d(s));
    }
#endif
#if HAS_GGX
    if (m->kind == MAT_PBR) {
        *specular = 0;
        float choice = bsdf_choice(s);
        float2 u = bsdf_2d(s);
        float3 t, b;
        basis(nl, &t, &b);
        float3 wo = (float3)(-dot3(d, t), -dot3(d, b), -dot3(d, nl));
        float3 cn = (float3)(dot3(nc, t), dot3(nc, b), dot3(nc, nl));
        float3 wi;
        if (ggx_sample(ggx, m->pbr, m->glass, m->coat, m->spec, m->albedo.xyz, wo, entering, cn, choice, u, &wi, weight,
                       pdf)) {
            *transmitted = wi.z < 0.0f;
            return normalize3(t * wi.x + b * wi.y + nl * wi.z);
        }
        /* Below the surface: no contribution (the path ends on its zero
         * weight). */
        *weight = (float3)(0.0f);
        *pdf = 0.0f;
        return nl;
    }
#endif
    *specular = 1;
#if HAS_GLASS
    if (m->kind == MAT_GLASS) {
        float ior = m->albedo.w;
        float n1 = entering ? 1.0f : ior;
        float n2 = entering ? ior : 1.0f;
        float cos_i = fmin(fmax(-dot3(d, nl), 0.0f), 1.0f);
        float cos_t = cos_transmitted(cos_i, n1, n2);
        float r = 1.0f;
        if (cos_t >= 0.0f) {
#if HAS_SCHLICK && HAS_EXACT
            r = m->schlick ? fresnel_schlick(cos_i, cos_t, n1, n2) : fresnel_exact(cos_i, cos_t, n1, n2);
#elif HAS_SCHLICK
            r = fresnel_schlick(cos_i, cos_t, n1, n2);
#else
            r = fresnel_exact(cos_i, cos_t, n1, n2);
#endif
        }
        if (bsdf_choice(s) < r) {
            return reflect_dir(d, nl);
        }
        *transmitted = 1;
        float eta = n1 / n2;
        return normalize3(d * eta + nl * (eta * cos_i - cos_t));
    }
#endif
    return reflect_dir(d, nl);
}

/* scatter() off a surface of outward normal n (the routine checks). */
static inline float3 scatter_outward(MatRef m, __global const float *ggx, float3 d, float3 n, Sampler *s,
                              float3 *weight, int *specular) {
    int entering = dot3(d, n) < 0.0f;
    int transmitted;
    float pdf;
    return scatter(m, ggx, d, entering, entering ? n : -n, (float3)(0.0f), s, weight, specular, &transmitted, &pdf);
}
