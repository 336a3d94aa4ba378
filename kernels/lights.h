/* The emitter the power table picks from x, and in *u what x leaves,
 * stretched to [0, 1) (light/pick.rs, PickTable::pick_point): from the
 * guide entry of x's column on to the emitter whose interval holds x's
 * top 31 bits (the last with weight ends at 2^31, past every x). */
static inline uint pick_light(__global const Light *lights, uint count, uint x, float *u) {
    x >>= 1;
    uint i = lights[(uint)(((ulong)x * (ulong)count) >> 31)].guide;
    while (x >= lights[i].upper) {
        i += 1u;
    }
    uint lower = lights[i].lower;
    *u = fmin((float)(x - lower) / (float)(lights[i].upper - lower), as_float(ONE_BELOW_BITS));
    return i;
}

#if HAS_SUN
/* Whether unit direction d looks into the sun's disc (SunLight::covers). */
static inline int sun_covers(__global const Params *P, float3 d) {
    float3 w = d - P->sun.xyz;
    return 0.5f * dot3(w, w) <= P->sun.w;
}

/* A direction uniformly in the sun's cone and 1/pdf (SunLight::sample). */
static inline void sun_sample(__global const Params *P, float2 u, float3 *dir, float *weight) {
    float a = u.x * P->sun.w;
    float cos_t = 1.0f - a;
    float sin_t = sqrt(fmax(a * (2.0f - a), 0.0f));
    float2 sc = sincos_turns(u.y);
    float3 axis = P->sun.xyz;
    float3 t, b;
    basis(axis, &t, &b);
    *dir = t * (sin_t * sc.y) + b * (sin_t * sc.x) + axis * cos_t;
    *weight = 2.0f * M_PI_F * P->sun.w;
}
#endif

#if HAS_SPHERE_LIGHTS
/* A sphere (centre c, radius r) seen from p (emitter.rs, SphereView): 0
 * where p is on its outside (on_self and facing away), else *to_center,
 * *d2 and whether p is inside (area sampling) or not (cone). */
static inline int sphere_view(float3 c, float r, float3 p, float3 nl, int on_self, float3 *to_center, float *d2,
                              int *inside) {
    *to_center = c - p;
    *d2 = dot3(*to_center, *to_center);
    *inside = on_self ? dot3(nl, *to_center) > 0.0f : *d2 < r * r;
    return *inside || !on_self;
}

/* 1 - cos(theta_max) of the cone a sphere fills, without cancellation. */
static inline float one_minus_cos_max(float r2, float d2) {
    float sin2 = r2 / d2;
    float cos_max = sqrt(fmax(1.0f - sin2, 0.0f));
    return sin2 / (1.0f + cos_max);
}
#endif

/* Next-event estimation directions: light.rs. Returns 0 when the emitter
 * contributes nothing; otherwise *dir and *weight (1/pdf in solid angle). */
static inline int sample_light(__global const Object *light_ob, uint light, float3 p, float3 nl, uint at, float2 u,
                        float3 *dir, float *weight) {
#if HAS_SPHERE_LIGHTS && HAS_QUAD_LIGHTS
    if (light_ob->kind == KIND_SPHERE) {
#endif
#if HAS_SPHERE_LIGHTS
        float3 to_center;
        float d2;
        int inside;
        float r = light_ob->p0.w;
        float r2 = r * r;
        if (!sphere_view(light_ob->p0.xyz, r, p, nl, light == at, &to_center, &d2, &inside)) {
            return 0;
        }
        if (inside) {
            float z = 1.0f - 2.0f * u.x;
            float rxy = sqrt(fmax(1.0f - z * z, 0.0f));
            float2 sc = sincos_turns(u.y);
            float3 m = (float3)(rxy * sc.y, rxy * sc.x, z);
            float3 w = light_ob->p0.xyz + m * r - p;
            float dist2 = dot3(w, w);
            if (!(dist2 > 0.0f)) {
                return 0;
            }
            *dir = w / sqrt(dist2);
            *weight = fabs(dot3(m, *dir)) * 4.0f * M_PI_F * r2 / dist2;
            return 1;
        }
        float cone = one_minus_cos_max(r2, d2);
        float a = u.x * cone;
        float cos_t = 1.0f - a;
        float sin_t = sqrt(fmax(a * (2.0f - a), 0.0f));
        float2 sc = sincos_turns(u.y);
        float3 axis = to_center / sqrt(d2);
        float3 t, b;
        basis(axis, &t, &b);
        *dir = t * (sin_t * sc.y) + b * (sin_t * sc.x) + axis * cos_t;
        *weight = 2.0f * M_PI_F * cone;
        return 1;
#endif
#if HAS_SPHERE_LIGHTS && HAS_QUAD_LIGHTS
    }
#endif
#if HAS_QUAD_LIGHTS
    if (light == at) {
        return 0;
    }
    float3 w = light_ob->p0.xyz + light_ob->p1.xyz * u.x + light_ob->p2.xyz * u.y - p;
    float dist2 = dot3(w, w);
    if (!(dist2 > 0.0f)) {
        return 0;
    }
    *dir = w / sqrt(dist2);
    *weight = fabs(dot3(light_ob->p3.xyz, *dir)) * light_ob->p0.w / dist2;
    return 1;
#endif
#if !HAS_QUAD_LIGHTS
    return 0;
#endif
}

/* The direction from p to q on a flat emitter (unit normal n, area) and
 * 1/pdf in solid angle (emitter.rs, toward_point). */
static inline int toward_point(float3 p, float3 q, float3 n, float area, float3 *dir, float *weight) {
    float3 w = q - p;
    float dist2 = dot3(w, w);
    if (!(dist2 > 0.0f)) {
        return 0;
    }
    *dir = w / sqrt(dist2);
    *weight = fabs(dot3(n, *dir)) * area / dist2;
    return 1;
}

/* Emitter::sample_direction for emitter L seen from point p on (object,
 * prim), nl and ns its geometric and shading normals on the side the path
 * came from. */
static inline int sample_emitter(const Scene *sc, __global const Light *L, float3 p, uint object, uint prim, float3 nl,
                          float3 ns, float2 u, float3 *dir, float *weight) {
#if HAS_TRI_LIGHTS
    if (L->kind == LIGHT_TRIANGLE) {
        if (L->object == object && L->prim == prim) {
            return 0;
        }
        float r = sqrt(u.x);
        float b1 = 1.0f - r;
        float b2 = u.y * r;
        return toward_point(p, L->p0.xyz + L->e1.xyz * b1 + L->e2.xyz * b2, L->n.xyz, L->n.w, dir, weight);
    }
#endif
#if HAS_ENV_MAP
    if (L->kind == LIGHT_ENV_MAP) {
        return env_sample(sc, u, dir, weight);
    }
#endif
#if HAS_SUN
    if (L->kind == LIGHT_SUN) {
        sun_sample(sc->P, u, dir, weight);
        return 1;
    }
#endif
#if HAS_ENV
    if (L->kind == LIGHT_ENVIRONMENT) {
        *dir = cosine_hemisphere(ns, u);
        float c = dot3(ns, *dir);
        if (!(c > 0.0f)) {
            return 0;
        }
        *weight = M_PI_F / c;
        return 1;
    }
#endif
#if HAS_SPHERE_LIGHTS || HAS_QUAD_LIGHTS
    return sample_light(&sc->objects[L->object], L->object, p, nl, object, u, dir, weight);
#else
    return 0;
#endif
}

#if HAS_MIS
/* The index of the emitter that is triangle prim of object (or the whole
 * object, prim NO_PRIM), or -1 (Lights::index_of): a binary search, the
 * list being in (object, prim) order. */
static inline int light_index(const Scene *sc, uint object, uint prim) {
    __global const Params *P = sc->P; /* LIGHT_COUNT in the generic program */
    (void)P;
    uint lo = 0u;
    uint hi = LIGHT_COUNT;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        __global const Light *L = &sc->lights[mid];
        if (L->object < object || (L->object == object && L->prim < prim)) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    if (lo < LIGHT_COUNT && sc->lights[lo].object == object && sc->lights[lo].prim == prim) {
        return (int)lo;
    }
    return -1;
}

/* The environment's emitter (always the last), or -1. */
static inline int environment_light(const Scene *sc) {
#if HAS_ENV || HAS_ENV_MAP
    __global const Params *P = sc->P;
    (void)P;
    if (LIGHT_COUNT > 0u) {
        uint kind = sc->lights[LIGHT_COUNT - 1u].kind;
        if (kind == LIGHT_ENVIRONMENT || kind == LIGHT_ENV_MAP) {
            return (int)(LIGHT_COUNT - 1u);
        }
    }
#endif
    return -1;
}

/* The sun's emitter (just before the environment's, or the last), or -1
 * (Lights::sun). */
static inline int sun_light(const Scene *sc) {
#if HAS_SUN
    __global const Params *P = sc->P;
    (void)P;
    for (uint i = LIGHT_COUNT > 2u ? LIGHT_COUNT - 2u : 0u; i < LIGHT_COUNT; i++) {
        if (sc->lights[i].kind == LIGHT_SUN) {
            return (int)i;
        }
    }
#endif
    return -1;
}

/* The density (solid angle) with which sample_emitter from p on (object,
 * prim), normals nl and ns, gives direction dir meeting L at q
 * (Emitter::pdf_direction): the same branches and formulas. */
static inline float emitter_pdf(const Scene *sc, __global const Light *L, float3 p, uint object, uint prim, float3 nl,
                                float3 ns, float3 dir, float3 q) {
    int on_self = L->object == object && L->prim == prim;
    float weight = 0.0f;
#if HAS_ENV_MAP
    if (L->kind == LIGHT_ENV_MAP) {
        return env_pdf(sc, dir);
    }
#endif
#if HAS_SUN
    if (L->kind == LIGHT_SUN) {
        __global const Params *P = sc->P;
        return sun_covers(P, dir) ? 1.0f / (2.0f * M_PI_F * P->sun.w) : 0.0f;
    }
#endif
#if HAS_TRI_LIGHTS
    if (L->kind == LIGHT_TRIANGLE) {
        if (on_self) {
            return 0.0f;
        }
        float3 w = q - p;
        weight = fabs(dot3(L->n.xyz, dir)) * L->n.w / dot3(w, w);
    } else
#endif
#if HAS_ENV
    if (L->kind == LIGHT_ENVIRONMENT) {
        float c = dot3(ns, dir);
        if (!(c > 0.0f)) {
            return 0.0f;
        }
        weight = M_PI_F / c;
    } else
#endif
    {
#if HAS_SPHERE_LIGHTS || HAS_QUAD_LIGHTS
        __global const Object *ob = &sc->objects[L->object];
#if HAS_SPHERE_LIGHTS && HAS_QUAD_LIGHTS
        if (ob->kind == KIND_SPHERE) {
#endif
#if HAS_SPHERE_LIGHTS
            float3 to_center;
            float d2;
            int inside;
            float r = ob->p0.w;
            float r2 = r * r;
            if (!sphere_view(ob->p0.xyz, r, p, nl, on_self, &to_center, &d2, &inside)) {
                return 0.0f;
            }
            if (inside) {
                float3 m = (q - ob->p0.xyz) * (1.0f / r);
                float3 w = q - p;
                weight = fabs(dot3(m, dir)) * 4.0f * M_PI_F * r2 / dot3(w, w);
            } else {
                weight = 2.0f * M_PI_F * one_minus_cos_max(r2, d2);
            }
#endif
#if HAS_SPHERE_LIGHTS && HAS_QUAD_LIGHTS
        } else {
#endif
#if HAS_QUAD_LIGHTS
            if (on_self) {
                return 0.0f;
            }
            float3 w = q - p;
            weight = fabs(dot3(ob->p3.xyz, dir)) * ob->p0.w / dot3(w, w);
#endif
#if HAS_SPHERE_LIGHTS && HAS_QUAD_LIGHTS
        }
#endif
#endif
    }
    return weight > 0.0f ? 1.0f / weight : 0.0f;
}
#endif
