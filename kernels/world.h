/* The scene as a path meets it (world/mod.rs): the nearest hit over every
 * object, the surface there, and where rays leaving it start. */

/* Offers object i to *best, never the surface the ray starts on
 * (offer_object): a sphere the ray leaves outwards is skipped, one it
 * enters gives its far root; a quad it starts on is skipped; an instance
 * skips the triangle it starts on. */
static inline void offer_object(const Scene *sc, uint i, float3 o, float3 d, float oo, float od, uint from, uint from_prim,
                         int entering, Hit *best) {
    __global const Object *ob = &sc->objects[i];
#if HAS_MESHES
    if (ob->kind == KIND_INSTANCE) {
        offer_instance(sc, i, ob, o, d, i == from ? from_prim : NO_PRIM, best);
        return;
    }
#endif
    float t;
#if HAS_SPHERES && HAS_QUADS
    if (ob->kind == KIND_SPHERE) {
#endif
#if HAS_SPHERES
        if (i == from && !entering) {
            return;
        }
        t = sphere_intersect(ob, o, d, oo, od, i == from);
#endif
#if HAS_SPHERES && HAS_QUADS
    } else {
#endif
#if HAS_QUADS
        if (i == from) {
            return;
        }
        t = quad_intersect(ob, o, d);
#endif
#if HAS_SPHERES && HAS_QUADS
    }
#endif
#if HAS_SPHERES || HAS_QUADS
    offer_hit(best, t, i, NO_PRIM, 0u, (float3)(0.0f));
#endif
}

/* Nearest hit along (o, d), never the surface the ray starts on (object
 * `from`, triangle `from_prim`): every object in turn, or the objects too
 * large for a BVH in turn and then the BVH. h->object is NO_OBJECT when
 * nothing is hit. */
static inline void nearest(const Scene *sc, float3 o, float3 d, uint from, uint from_prim, int entering, Hit *h) {
    __global const Params *P = sc->P;
    float oo = dot3(o, o);
    float od = dot3(o, d);
    h->t = INFINITY;
    h->object = NO_OBJECT;
    h->prim = NO_PRIM;
    h->slot = 0u;
    h->bary = (float3)(0.0f);
#if HAS_BVH
    if (USE_BVH) {
        for (uint j = 0; j < P->num_big; ++j) {
            offer_object(sc, sc->big[j], o, d, oo, od, from, from_prim, entering, h);
        }
        __global const BvhNode *nodes = sc->nodes;
        BVH_SEARCH(nodes, BVH_STACK, o, d, h->t, {
            for (uint slot = leaf_first; slot < leaf_first + leaf_count; ++slot) {
                offer_object(sc, sc->prims[slot], o, d, oo, od, from, from_prim, entering, h);
            }
        });
        return;
    }
#endif
    for (uint i = 0; i < OBJECT_COUNT; ++i) {
        offer_object(sc, i, o, d, oo, od, from, from_prim, entering, h);
    }
}

/* The nearest hit's distance and object (the routine checks' view). */
static inline float intersect(const Scene *sc, float3 o, float3 d, uint from, int entering, uint *hit) {
    Hit h;
    nearest(sc, o, d, from, NO_PRIM, entering, &h);
    *hit = h.object;
    return h.t;
}

/* World::surface: the surface at h, found along (o, d). */
static inline Surf surface_at(const Scene *sc, const Hit *h, float3 o, float3 d) {
    __global const Object *ob = &sc->objects[h->object];
    Surf sf;
    sf.object = h->object;
    sf.prim = h->prim;
    sf.instance = NO_OBJECT;
    sf.smooth = 0;
#if HAS_COAT_NORMAL
    sf.nc = (float3)(0.0f);
#endif
#if HAS_MESHES
    if (ob->kind == KIND_INSTANCE) {
        mesh_surface(sc, h, &sf);
        return sf;
    }
#endif
    sf.p = o + d * h->t;
    sf.ng = object_normal(ob, sf.p);
    sf.ns = sf.ng;
    sf.material = ob->material;
    return sf;
}

/* World::spawn: where a ray leaving sf along dir starts. */
static inline float3 spawn(const Scene *sc, const Surf *sf, float3 dir) {
#if HAS_MESHES
    if (sf->instance != NO_OBJECT) {
        return mesh_spawn(sc, sf, dir);
    }
#endif
    return sf->p;
}
