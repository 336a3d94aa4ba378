/* The path tracer, loop for loop as integrator.rs. */

#define MAX_SURVIVAL 0.99f

inline float3 radiance(const Scene *sc, float3 o, float3 d, Sampler *s) {
    __global const Params *P = sc->P;
    __global const Object *objects = sc->objects;
    __global const Material *materials = sc->materials;
    __global const uint *lights = sc->lights;
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
            for (uint j = 0; j < LIGHT_COUNT; ++j) {
                uint light = lights[j];
                float2 u = next_2d(s);
                float3 dir;
                float weight;
                if (!sample_light(&objects[light], light, p, nl, hit, u, &dir, &weight)) {
                    continue;
                }
                float cos_s = dot(nl, dir);
                if (!(cos_s > 0.0f)) {
                    continue;
                }
                uint shadow_hit;
                intersect(sc, p, dir, hit, dot(dir, n) < 0.0f, &shadow_hit);
                if (shadow_hit == light) {
                    direct += materials[objects[light].material].emission.xyz * (cos_s * weight);
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
