/* The path tracer, loop for loop as integrator.rs. Its Russian roulette
 * cap is the host's MAX_SURVIVAL, passed as its bits (MAX_SURVIVAL_BITS). */

#if HAS_MIS
/* The power heuristic of density a against b (mis.rs, power_heuristic). */
static inline float power_heuristic(float a, float b) {
    if (!(a > 0.0f)) {
        return 0.0f;
    }
    float r = b / a;
    if (isnan(r)) {
        return 0.5f; /* both infinite */
    }
    return 1.0f / (1.0f + r * r);
}

/* Where the last BSDF sample left a vertex that NEE gathered with MIS
 * (mis.rs, BsdfVertex): pdf 0 when the next hit counts emission in full. */
typedef struct {
    float3 p, nl, ns;
    uint object, prim;
    float pdf;
} BsdfVertex;

/* The MIS weight of emission that the sample along dir found at q on
 * emitter e (-1: one no light sample aims at), BsdfVertex::hit_weight. */
static inline float hit_weight(const Scene *sc, const BsdfVertex *v, int e, float3 dir, float3 q) {
    __global const Params *P = sc->P;
    (void)P;
    if (!(v->pdf > 0.0f) || e < 0) {
        return 1.0f;
    }
    __global const Light *L = &sc->lights[e];
    float pmf = LIGHT_COUNT > 1u ? L->pmf : 1.0f;
    float light_pdf = pmf * emitter_pdf(sc, L, v->p, v->object, v->prim, v->nl, v->ns, dir, q);
    return power_heuristic(v->pdf, light_pdf);
}
#endif

#if HAS_DIFFUSE || HAS_GGX
/* What a surface makes of light from a direction, for next-event
 * estimation (integrator/mod.rs, the closures given to nee::direct):
 * cos(theta_s) for diffuse (the caller multiplies by albedo / pi), the
 * BSDF cos weighted against BSDF sampling for MAT_PBR. */
typedef struct {
    int pbr;
#if HAS_GGX
    MatRef m;
    float3 t, b, n, wo;
    GgxLobes lobes;
#endif
} NeeSurface;

/* Le * V * f(dir) / pdf of one shadow ray from surface sf towards emitter
 * L, picked with probability pmf, as nee.rs's `one`. What a scene cannot
 * have is decided when the program is built (on PoCL the cheapest scenes
 * feel every test here). */
static inline float3 direct_from(const Scene *sc, __global const Light *L, float pmf, const Surf *sf, float3 nl, float3 ns,
                          float2 u, const NeeSurface *ne) {
    float3 dir;
    float weight;
    if (!sample_emitter(sc, L, sf->p, sf->object, sf->prim, nl, ns, u, &dir, &weight)) {
        return (float3)(0.0f);
    }
    float cos_s = dot3(ns, dir);
#if HAS_MESHES
    if (!(cos_s > 0.0f && dot3(nl, dir) > 0.0f)) {
#else
    if (!(cos_s > 0.0f)) { /* ns is nl */
#endif
        return (float3)(0.0f);
    }
    Hit h;
    float3 from = spawn(sc, sf, dir);
    nearest(sc, from, dir, sf->object, sf->prim, dot3(dir, sf->ng) < 0.0f, &h);
    int visible = h.object == L->object;
#if HAS_TRI_LIGHTS
    visible = visible && (L->prim == NO_PRIM || h.prim == L->prim);
#endif
#if HAS_ENV || HAS_ENV_MAP
    if (L->kind == LIGHT_ENVIRONMENT || L->kind == LIGHT_ENV_MAP || L->kind == LIGHT_SUN) {
        visible = h.object == NO_OBJECT;
    }
#endif
    if (!visible) {
        return (float3)(0.0f);
    }
    float3 f = (float3)(cos_s);
#if HAS_GGX
    if (ne->pbr) {
        float3 wi = (float3)(dot3(dir, ne->t), dot3(dir, ne->b), dot3(dir, ne->n));
        float bsdf_pdf = ggx_pdf(ne->m->pbr, &ne->lobes, ne->wo, wi);
        float w = power_heuristic(pmf / weight, bsdf_pdf);
        f = ggx_eval_cos(sc->ggx, ne->m->pbr, ne->m->glass, ne->m->albedo.xyz, &ne->lobes, ne->wo, wi) * w;
    }
#endif
    float3 le = L->emission.xyz;
#if HAS_TEXTURES
    if (L->maps != NO_MAPS) {
        le = emitted(sc, L, &h, from, dir);
    }
#else
    (void)from;
#endif
#if HAS_ENV_MAP
    __global const Params *P = sc->P; /* USE_ENV_MAP in the generic program */
    (void)P;
    if (!ne->pbr && USE_ENV_MAP) {
        /* Diffuse under a map: weighed against cosine sampling. */
        f = (float3)(cos_s * power_heuristic(pmf / weight, cos_s * M_1_PI_F));
    }
    if (L->kind == LIGHT_ENV_MAP) {
        le = env_radiance(sc, dir);
    }
#endif
    return le * (f * weight);
}
#endif

/* A path's guide for the denoiser (features.rs, Guide): the albedo and
 * normal of its first hit that is not a mirror or glass, tinted by those;
 * what it sees of light where it meets an emitter or leaves the scene. */
typedef struct {
    float3 albedo, normal;
} Guide;

/* One path (integrator.rs, Path::advance until it ends); built with
 * FEATURES, its guide in *g. */
static inline float3 radiance(const Scene *sc, float3 o, float3 d, Sampler *s, Guide *g) {
    __global const Params *P = sc->P;
    __global const Material *materials = sc->materials;
    __global const Light *lights = sc->lights;
    int nee = USE_NEE; /* a variable: `x || !CONSTANT` draws a warning */
    int env_map = USE_ENV_MAP; /* diffuse vertices weigh by MIS under a map */
    float3 l = (float3)(0.0f);
    float3 beta = (float3)(1.0f);
    /* The throughput with which the next hit counts emission (Path::emit). */
    float3 emit = (float3)(1.0f);
    int specular;
    uint from = NO_OBJECT;
    uint from_prim = NO_PRIM;
    int entering = 0;
    uint bounces = 0;
#if HAS_MIS
    BsdfVertex last;
    last.pdf = 0.0f;
#endif
#if FEATURES
    /* Kept in registers, *g written once at the end: `tint` is the mirrors'
     * and glass's product until the guide is found, then its albedo (one
     * float3 fewer live across the loop). */
    float3 tint = (float3)(1.0f);
    float3 g_normal = (float3)(0.0f);
    int guided = 0;
#endif
    for (;;) {
        Hit hit;
        nearest(sc, o, d, from, from_prim, entering, &hit);
        if (hit.object == NO_OBJECT) {
#if HAS_ENV || HAS_ENV_MAP
            /* Left the scene: the environment, counted as an emitter's hit
             * (what a camera ray sees of a map it may not see is no light). */
            float3 le = P->environment.xyz;
            int hidden = 0;
#if HAS_ENV_MAP
            if (USE_ENV_MAP) {
                hidden = bounces == 0u && P->environment.w == 0.0f;
                if (!hidden) {
                    le = env_radiance(sc, d);
                }
            }
#endif
            float w = 1.0f;
#if HAS_MIS
            if (!hidden && last.pdf > 0.0f) {
                w = hit_weight(sc, &last, environment_light(sc), d, (float3)(0.0f));
            }
#endif
            l += hidden ? le : emit * le * w;
#if FEATURES
            if (!guided) {
                tint *= clamp(le, 0.0f, 1.0f);
                guided = 1;
            }
#endif
#if HAS_SUN
            if (!hidden && USE_SUN && sun_covers(P, d)) {
                float ws = 1.0f;
#if HAS_MIS
                if (last.pdf > 0.0f) {
                    ws = hit_weight(sc, &last, sun_light(sc), d, (float3)(0.0f));
                }
#endif
                l += emit * P->sun_radiance.xyz * ws;
            }
#endif
#endif
            break;
        }
        at_vertex(s, bounces);
        Surf sf = surface_at(sc, &hit, o, d);
#if HAS_TEXTURES || HAS_VERTEX_COLORS
        Material shaded = materials[sf.material];
#if HAS_TEXTURES
        if (shaded.maps != NO_MAPS) {
            apply_maps(sc, &hit, &sf, &shaded);
        }
#endif
#if HAS_VERTEX_COLORS && HAS_MESHES
        apply_vertex_color(sc, &hit, &shaded);
#endif
        MatRef m = &shaded;
#else
        MatRef m = &materials[sf.material];
#endif
        /* Geometric side first: a ray that reaches a solid's surface from
         * inside has crossed it, and what it carries is absorbed on the way
         * (Beer-Lambert, integrator.rs). */
        int arriving = dot3(d, sf.ng) < 0.0f;
#if HAS_VOLUME
        if (!arriving && (m->absorb.x != 0.0f || m->absorb.y != 0.0f || m->absorb.z != 0.0f)) {
            float3 kept = exp(-m->absorb.xyz * hit.t);
            beta *= kept;
            emit *= kept;
#if FEATURES
            if (!guided) {
                tint *= kept;
            }
#endif
        }
#endif
        if (m->emissive) {
            float w = 1.0f;
#if HAS_MIS
            if (last.pdf > 0.0f) {
                w = hit_weight(sc, &last, light_index(sc, sf.object, sf.prim), d, sf.p);
            }
#endif
            l += emit * m->emission.xyz * w;
        }
        /* Geometric and shading normals on the side the ray came from. */
        float3 nl = arriving ? sf.ng : -sf.ng;
        float3 ns = !sf.smooth ? nl : (dot3(sf.ns, nl) < 0.0f ? -sf.ns : sf.ns);
        /* A clear coat's own normal, on the same side (zero: ns). */
        float3 nc = (float3)(0.0f);
#if HAS_COAT_NORMAL
        nc = dot3(sf.nc, nl) < 0.0f ? -sf.nc : sf.nc;
#endif
#if FEATURES
        if (!guided) {
            if (m->kind == MAT_MIRROR || m->kind == MAT_GLASS) {
                tint *= m->albedo.xyz;
            } else {
                tint *= m->emissive ? clamp(m->emission.xyz, 0.0f, 1.0f) : m->albedo.xyz;
                g_normal = ns;
                guided = 1;
            }
        }
#endif
        if (MAX_DEPTH != 0u && bounces >= MAX_DEPTH) {
            break;
        }
        int gathered = 0;
#if HAS_DIFFUSE || HAS_GGX
        NeeSurface ne;
        ne.pbr = 0;
#if HAS_DIFFUSE
        gathered = nee && m->kind == MAT_DIFFUSE;
#endif
#if HAS_GGX
        if (nee && m->kind == MAT_PBR) {
            gathered = 1;
            ne.pbr = 1;
            ne.m = m;
            basis(ns, &ne.t, &ne.b);
            ne.n = ns;
            ne.wo = -(float3)(dot3(d, ne.t), dot3(d, ne.b), dot3(d, ns));
            float3 cn = (float3)(dot3(nc, ne.t), dot3(nc, ne.b), dot3(nc, ns));
            ne.lobes = ggx_lobes(sc->ggx, m->pbr, m->glass, m->coat, m->spec, m->albedo.xyz, ne.wo, arriving, cn);
        }
#endif
        if (gathered) {
            float3 direct = (float3)(0.0f);
            if (LIGHT_COUNT > 0u) {
                /* One emitter, picked in proportion to its power by the
                 * light position's x (integrator/nee.rs): no pick when
                 * there is one. */
                uint j = 0u;
                float2 u;
                if (LIGHT_COUNT > 1u) {
                    uint x;
                    float left;
                    u.y = light_pick_2d(s, &x);
                    j = pick_light(lights, LIGHT_COUNT, x, &left);
                    u.x = left;
                } else {
                    u = light_2d(s, 0u);
                }
                float pmf = LIGHT_COUNT > 1u ? lights[j].pmf : 1.0f;
                direct = direct_from(sc, &lights[j], pmf, &sf, nl, ns, u, &ne);
                if (LIGHT_COUNT > 1u) {
                    direct = direct / pmf;
                }
            }
            if (ne.pbr) {
                l += beta * direct;
            } else {
                l += beta * m->albedo.xyz * direct * M_1_PI_F;
                /* The bounce's own hit would not count its emission (under
                 * a map, only its MIS share). */
                if (MAX_DEPTH != 0u && bounces + 1u >= MAX_DEPTH && !env_map) {
                    break;
                }
            }
        }
#endif
        float3 weight;
        float bsdf_pdf;
        int transmitted;
        float3 next = scatter(m, sc->ggx, d, arriving, ns, nc, s, &weight, &specular, &transmitted, &bsdf_pdf);
        /* A shading normal can send a direction to the wrong side of the
         * actual surface: such a sample has no contribution. */
        if (sf.smooth && (dot3(next, nl) > 0.0f) == transmitted) {
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
        /* Light through a surface is BSDF sampling's alone (next-event
         * estimation gathers what it reflects): counted whole. */
        int mis = gathered && !transmitted && (m->kind == MAT_PBR || env_map);
        emit = !gathered || transmitted || mis ? beta : (float3)(0.0f);
#if HAS_MIS
        last.pdf = 0.0f;
        if (mis) {
            last.p = sf.p;
            last.nl = nl;
            last.ns = ns;
            last.object = sf.object;
            last.prim = sf.prim;
            last.pdf = m->kind == MAT_PBR ? bsdf_pdf : dot3(ns, next) * M_1_PI_F;
        }
#endif
        from = hit.object;
        from_prim = hit.prim;
        entering = dot3(next, sf.ng) < 0.0f;
        o = spawn(sc, &sf, next);
        d = next;
    }
    if (P->clamp > 0.0f) {
        float peak = max3(l);
        if (peak > P->clamp) {
            l *= P->clamp / peak;
        }
    }
#if FEATURES
    /* A path that ended before finding its guide has none. */
    g->albedo = guided ? tint : (float3)(0.0f);
    g->normal = g_normal;
#else
    (void)g;
#endif
    return l;
}
