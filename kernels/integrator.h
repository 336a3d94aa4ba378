/* The path tracer, loop for loop as integrator.rs. */

#define MAX_SURVIVAL 0.99f

#if HAS_DIFFUSE
/* Le * V * cos / pdf of one shadow ray from p (on object `at`, normal n,
 * nl facing the path) towards emitter `light`, as light/mod.rs's `one`. */
inline float3 direct_from(const Scene *sc, uint light, float3 p, float3 n, float3 nl, uint at, float2 u) {
    __global const Object *light_ob = &sc->objects[light];
    float3 dir;
    float weight;
    if (!sample_light(light_ob, light, p, nl, at, u, &dir, &weight)) {
        return (float3)(0.0f);
    }
    float cos_s = dot(nl, dir);
    if (!(cos_s > 0.0f)) {
        return (float3)(0.0f);
    }
    uint shadow_hit;
    intersect(sc, p, dir, at, dot(dir, n) < 0.0f, &shadow_hit);
    if (shadow_hit != light) {
        return (float3)(0.0f);
    }
    return sc->materials[light_ob->material].emission.xyz * (cos_s * weight);
}
#endif

inline float3 radiance(const Scene *sc, float3 o, float3 d, Sampler *s) {
    __global const Params *P = sc->P;
    __global const Object *objects = sc->objects;
    __global const Material *materials = sc->materials;
    __global const Light *lights = sc->lights;
    int nee = USE_NEE; /* a variable: `x || !CONSTANT` draws a warning */
    float3 l = (float3)(0.0f);
    float3 beta = (float3)(1.0f);
    int specular = 1;
    uint from = NO_OBJECT;
    int entering = 0;
    uint bounces = 0;
    for (;;) {
        uint hit;
        float t = intersect(sc, o, d, from, entering, &hit);
        if (hit == NO_OBJECT) {
            break;
        }
        __global const Object *ob = &objects[hit];
        __global const Material *m = &materials[ob->material];
        if (m->emissive && (specular || !nee)) {
            l += beta * m->emission.xyz;
        }
        if (MAX_DEPTH != 0u && bounces >= MAX_DEPTH) {
            break;
        }
        float3 p = o + d * t;
        float3 n = object_normal(ob, p);
#if HAS_DIFFUSE
        if (nee && m->kind == MAT_DIFFUSE) {
            float3 nl = dot(d, n) < 0.0f ? n : -n;
            float3 direct = (float3)(0.0f);
            if (LIGHT_COUNT > 0u) {
                /* One emitter, picked in proportion to its power
                 * (light/mod.rs): no random number when there is one. */
                uint j = 0u;
                if (LIGHT_COUNT > 1u) {
                    ulong bits = next_bits(s);
                    uint column = (uint)(((bits >> 32) * (ulong)LIGHT_COUNT) >> 32);
                    uint threshold = lights[column].threshold;
                    int keep = (uint)bits < threshold || threshold == 0xFFFFFFFFu;
                    j = keep ? column : lights[column].alias;
                }
                direct = direct_from(sc, lights[j].object, p, n, nl, hit, next_2d(s));
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
        float3 next = scatter(m, d, n, s, &weight, &specular);
        beta *= weight;
        bounces += 1u;
        if (bounces > RR_DEPTH || !(max3(beta) > 0.0f)) {
            float q = fmin(max3(beta), MAX_SURVIVAL);
            if (!(next_f32(s) < q)) {
                break;
            }
            beta /= q;
        }
        from = hit;
        entering = dot(next, n) < 0.0f;
        o = p;
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
