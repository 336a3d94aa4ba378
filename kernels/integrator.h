/* The path tracer, loop for loop as integrator.rs. Its Russian roulette
 * cap is the host's MAX_SURVIVAL, passed as its bits (MAX_SURVIVAL_BITS). */

#if HAS_DIFFUSE
/* Le * V * cos / pdf of one shadow ray from surface sf towards emitter L,
 * as light/mod.rs's `one`. What a scene cannot have is decided when the
 * program is built (on PoCL the cheapest scenes feel every test here). */
inline float3 direct_from(const Scene *sc, __global const Light *L, const Surf *sf, float3 nl, float3 ns, float2 u) {
    float3 dir;
    float weight;
    if (!sample_emitter(sc, L, sf->p, sf->object, sf->prim, nl, ns, u, &dir, &weight)) {
        return (float3)(0.0f);
    }
    float cos_s = dot(ns, dir);
#if HAS_MESHES
    if (!(cos_s > 0.0f && dot(nl, dir) > 0.0f)) {
#else
    if (!(cos_s > 0.0f)) { /* ns is nl */
#endif
        return (float3)(0.0f);
    }
    Hit h;
    nearest(sc, spawn(sc, sf, dir), dir, sf->object, sf->prim, dot(dir, sf->ng) < 0.0f, &h);
    int visible = h.object == L->object;
#if HAS_TRI_LIGHTS
    visible = visible && (L->prim == NO_PRIM || h.prim == L->prim);
#endif
#if HAS_ENV
    if (L->kind == LIGHT_ENVIRONMENT) {
        visible = h.object == NO_OBJECT;
    }
#endif
    if (!visible) {
        return (float3)(0.0f);
    }
    return L->emission.xyz * (cos_s * weight);
}
#endif

/* One path (integrator.rs, Path::advance until it ends). */
inline float3 radiance(const Scene *sc, float3 o, float3 d, Sampler *s) {
    __global const Params *P = sc->P;
    __global const Material *materials = sc->materials;
    __global const Light *lights = sc->lights;
    int nee = USE_NEE; /* a variable: `x || !CONSTANT` draws a warning */
    float3 l = (float3)(0.0f);
    float3 beta = (float3)(1.0f);
    int specular = 1;
    uint from = NO_OBJECT;
    uint from_prim = NO_PRIM;
    int entering = 0;
    uint bounces = 0;
    for (;;) {
        Hit hit;
        nearest(sc, o, d, from, from_prim, entering, &hit);
        if (hit.object == NO_OBJECT) {
#if HAS_ENV
            /* Left the scene: the environment, counted as an emitter's hit. */
            if (specular || !nee) {
                l += beta * P->environment.xyz;
            }
#endif
            break;
        }
        at_vertex(s, bounces);
        Surf sf = surface_at(sc, &hit, o, d);
        __global const Material *m = &materials[sf.material];
        if (m->emissive && (specular || !nee)) {
            l += beta * m->emission.xyz;
        }
        if (MAX_DEPTH != 0u && bounces >= MAX_DEPTH) {
            break;
        }
        /* Geometric and shading normals on the side the ray came from. */
        int arriving = dot(d, sf.ng) < 0.0f;
        float3 nl = arriving ? sf.ng : -sf.ng;
        float3 ns = !sf.smooth ? nl : (dot(sf.ns, nl) < 0.0f ? -sf.ns : sf.ns);
#if HAS_DIFFUSE
        if (nee && m->kind == MAT_DIFFUSE) {
            float3 direct = (float3)(0.0f);
            if (LIGHT_COUNT > 0u) {
                /* One emitter, picked in proportion to its power
                 * (light/mod.rs): no random number when there is one. */
                uint j = 0u;
                if (LIGHT_COUNT > 1u) {
                    ulong bits = light_pick(s, LIGHT_COUNT);
                    uint column = (uint)(((bits >> 32) * (ulong)LIGHT_COUNT) >> 32);
                    uint threshold = lights[column].threshold;
                    int keep = (uint)bits < threshold || threshold == 0xFFFFFFFFu;
                    j = keep ? column : lights[column].alias;
                }
                direct = direct_from(sc, &lights[j], &sf, nl, ns, light_2d(s, 0u));
                if (LIGHT_COUNT > 1u) {
                    direct = direct / lights[j].pmf;
                }
            }
            l += beta * m->albedo.xyz * direct * M_1_PI_F;
            if (MAX_DEPTH != 0u && bounces + 1u >= MAX_DEPTH) {
                break;
            }
        }
#endif
        float3 weight;
        int transmitted;
        float3 next = scatter(m, sc->ggx, d, arriving, ns, s, &weight, &specular, &transmitted);
        /* A shading normal can send a direction to the wrong side of the
         * actual surface: such a sample has no contribution. */
        if (sf.smooth && (dot(next, nl) > 0.0f) == transmitted) {
            break;
        }
        beta *= weight;
        bounces += 1u;
        if (bounces > RR_DEPTH || !(max3(beta) > 0.0f)) {
            float q = fmin(max3(beta), as_float(MAX_SURVIVAL_BITS));
            if (!(roulette(s) < q)) {
                break;
            }
            beta /= q;
        }
        from = hit.object;
        from_prim = hit.prim;
        entering = dot(next, sf.ng) < 0.0f;
        o = spawn(sc, &sf, next);
        d = next;
    }
    if (P->clamp > 0.0f) {
        float peak = max3(l);
        if (peak > P->clamp) {
            l *= P->clamp / peak;
        }
    }
    return l;
}
