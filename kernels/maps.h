/* Texture maps: render/texture.rs, render/maps.rs and
 * render/world/textures.rs, operation for operation (texels decoded by the
 * host's sRGB table, the same bilinear weights in the same order), so that
 * both backends see the same floats (spheres' coordinates use atan2 and
 * acos, which may differ in the last bit). */

#if HAS_TEXTURES
/* Wrap::index: texel i of a row or column n long (REPEAT 0, CLAMP 1,
 * MIRROR 2). */
static inline int wrap_index(uint mode, int i, int n) {
    if (mode == 1u) {
        return clamp(i, 0, n - 1);
    }
    if (mode == 2u) {
        int k = i % (2 * n);
        k = k < 0 ? k + 2 * n : k;
        return k >= n ? 2 * n - 1 - k : k;
    }
    int k = i % n;
    return k < 0 ? k + n : k;
}

/* texture.rs, split: the lower texel of coordinate x (texels) and the
 * upper one's weight. */
static inline int tex_split(float x, float *f) {
    x = isnan(x) ? 0.0f : x - 0.5f;
    float lo = fmin(fmax(floor(x), -16777216.0f), 16777216.0f);
    *f = fmin(fmax(x - lo, 0.0f), 1.0f);
    return (int)lo;
}

static inline float4 tex_decode(const Scene *sc, uint texel, int srgb) {
    uint r = texel & 255u, g = (texel >> 8) & 255u, b = (texel >> 16) & 255u;
    float k = 1.0f / 255.0f;
    float4 c;
    if (srgb) {
        c.x = sc->srgb[r];
        c.y = sc->srgb[g];
        c.z = sc->srgb[b];
    } else {
        c.x = (float)r * k;
        c.y = (float)g * k;
        c.z = (float)b * k;
    }
    c.w = (float)(texel >> 24) * k;
    return c;
}

/* texture::lookup: slot s's texture, bilinear, at coordinates uv. */
static inline float4 tex_lookup(const Scene *sc, __global const MapSlot *s, float2 uv, int srgb) {
    float u = s->xf_u.x * uv.x + s->xf_u.y * uv.y + s->xf_u.z;
    float v = s->xf_v.x * uv.x + s->xf_v.y * uv.y + s->xf_v.z;
    __global const TexImage *im = &sc->tex_images[s->info.x];
    int w = (int)im->width, h = (int)im->height;
    float fx, fy;
    int x0 = tex_split(u * (float)w, &fx);
    int y0 = tex_split(v * (float)h, &fy);
    size_t xa = (size_t)wrap_index(s->info.z, x0, w);
    size_t xb = (size_t)wrap_index(s->info.z, x0 + 1, w);
    size_t ya = (size_t)wrap_index(s->info.w, y0, h) * (size_t)w;
    size_t yb = (size_t)wrap_index(s->info.w, y0 + 1, h) * (size_t)w;
    __global const uint *t = sc->texels + im->offset;
    float4 t00 = tex_decode(sc, t[ya + xa], srgb);
    float4 t10 = tex_decode(sc, t[ya + xb], srgb);
    float4 t01 = tex_decode(sc, t[yb + xa], srgb);
    float4 t11 = tex_decode(sc, t[yb + xb], srgb);
    float gx = 1.0f - fx, gy = 1.0f - fy;
    return (t00 * gx + t10 * fx) * gy + (t01 * gx + t11 * fx) * fy;
}

/* maps::TexCoords. */
typedef struct {
    float2 uv[2];
    float3 tangent;
    float sign;
} TexCoords;

/* World::texcoords: the coordinates and tangent at h on its surface sf. */
static inline TexCoords texcoords(const Scene *sc, const Hit *h, const Surf *sf) {
    __global const Object *ob = &sc->objects[h->object];
    TexCoords tc;
    tc.uv[0] = (float2)(0.0f);
    tc.uv[1] = (float2)(0.0f);
    tc.tangent = (float3)(0.0f);
    tc.sign = 1.0f;
#if HAS_MESHES
    if (ob->kind == KIND_INSTANCE) {
        __global const Instance *in = &sc->instances[ob->pad0];
        size_t k = (size_t)(h->slot - in->tri_base) * 3u;
        float3 b = h->bary;
        if (in->uv_base != NO_NORMALS) {
            __global const float4 *c = sc->uvs + (size_t)in->uv_base * 3u + k;
            float4 m = c[0] * b.x + c[1] * b.y + c[2] * b.z;
            tc.uv[0] = m.xy;
            tc.uv[1] = m.zw;
        }
        if (in->tangent_base != NO_NORMALS) {
            __global const float4 *t = sc->tangents + (size_t)in->tangent_base * 3u + k;
            float3 tt = t[0].xyz * b.x + t[1].xyz * b.y + t[2].xyz * b.z;
            float det = dot3(in->cam_from_obj[2].xyz, cross3(in->cam_from_obj[0].xyz, in->cam_from_obj[1].xyz));
            float sign = t[0].w < 0.0f ? -1.0f : 1.0f;
            tc.tangent = xf_vector(in->cam_from_obj, tt);
            tc.sign = det < 0.0f ? -sign : sign;
        }
        return tc;
    }
#endif
#if HAS_QUADS
    if (ob->kind == KIND_QUAD) {
        float3 d = sf->p - ob->p0.xyz;
        float a = dot3(ob->p4.xyz, cross3(d, ob->p2.xyz));
        float bq = dot3(ob->p4.xyz, cross3(ob->p1.xyz, d));
        tc.uv[0] = (float2)(a, 1.0f - bq);
        tc.uv[1] = tc.uv[0];
        tc.tangent = ob->p1.xyz;
        return tc;
    }
#endif
    float3 n = sf->ng;
    tc.uv[0] = (float2)(0.5f + atan2(n.x, n.z) * (0.5f * M_1_PI_F), acos(clamp(n.y, -1.0f, 1.0f)) / M_PI_F);
    tc.uv[1] = tc.uv[0];
    tc.tangent = (float3)(n.z, 0.0f, -n.x);
    return tc;
}

static inline float4 map_read(const Scene *sc, __global const MapSlot *s, const TexCoords *tc, int srgb) {
    return tex_lookup(sc, s, tc->uv[s->info.y & 1u], srgb);
}

#if HAS_GGX
/* maps::shade_pbr: *m's pbr parameters times their textures at tc, the
 * derived values made again (Pbr::coated, Pbr::specular). */
static inline void shade_pbr_maps(const Scene *sc, const TexCoords *tc, __global const MaterialMaps *mm, Material *m) {
    __global const MapSlot *sl = mm->slot;
    float metallic = mm->factors.x;
    float roughness = mm->factors.y;
    float4 mr = (float4)(0.0f);
    if (sl[MAP_METALLIC].info.x != NO_TEXTURE) {
        mr = map_read(sc, &sl[MAP_METALLIC], tc, 0);
        metallic *= mr.z;
    }
    if (sl[MAP_ROUGHNESS].info.x != NO_TEXTURE) {
        if (mm->factors.w == 0.0f) {
            mr = map_read(sc, &sl[MAP_ROUGHNESS], tc, 0);
        }
        roughness *= mr.y;
    }
    m->pbr = (float4)(metallic, fmax(roughness * roughness, as_float(ALPHA_MIN_BITS)), roughness, m->pbr.w);
    if (sl[MAP_TRANSMISSION].info.x != NO_TEXTURE) {
        m->glass.x = mm->layers.x * map_read(sc, &sl[MAP_TRANSMISSION], tc, 0).x;
    }
    int coat = sl[MAP_CLEARCOAT].info.x != NO_TEXTURE;
    int coat_rough = sl[MAP_CLEARCOAT_ROUGHNESS].info.x != NO_TEXTURE;
    if (coat || coat_rough) {
        float weight = mm->layers.y;
        float rough = mm->layers.z;
        if (coat) {
            weight *= map_read(sc, &sl[MAP_CLEARCOAT], tc, 0).x;
        }
        if (coat_rough) {
            rough *= map_read(sc, &sl[MAP_CLEARCOAT_ROUGHNESS], tc, 0).y;
        }
        m->coat = (float4)(weight, fmax(rough * rough, as_float(ALPHA_MIN_BITS)), rough, m->coat.w);
    }
    int spec = sl[MAP_SPECULAR].info.x != NO_TEXTURE;
    int spec_color = sl[MAP_SPECULAR_COLOR].info.x != NO_TEXTURE;
    if (spec || spec_color) {
        float factor = mm->layers.w;
        float3 color = mm->spec_color.xyz;
        if (spec) {
            factor *= map_read(sc, &sl[MAP_SPECULAR], tc, 0).w;
        }
        if (spec_color) {
            color = color * map_read(sc, &sl[MAP_SPECULAR_COLOR], tc, 1).xyz;
        }
        m->spec = (float4)(fmin(color * m->pbr.w, (float3)(1.0f)) * factor, factor);
    }
}
#endif

/* maps::turned: unit normal n turned by the tangent-space normal map in
 * slot sl (x and y times scale); n where the hit has no tangent. */
static inline float3 map_turned(const Scene *sc, __global const MapSlot *sl, float scale, const TexCoords *tc,
                                float3 n) {
    float4 c = map_read(sc, sl, tc, 0);
    float x = (c.x * 2.0f - 1.0f) * scale;
    float y = (c.y * 2.0f - 1.0f) * scale;
    float z = c.z * 2.0f - 1.0f;
    float3 t = normalize_or_zero(tc->tangent - n * dot3(n, tc->tangent));
    if (t.x == 0.0f && t.y == 0.0f && t.z == 0.0f) {
        return n;
    }
    float3 b = cross3(n, t) * tc->sign;
    float3 turned = t * x + b * y + n * z;
    float rcp = 1.0f / sqrt(dot3(turned, turned));
    return isfinite(rcp) && rcp > 0.0f ? turned * rcp : n;
}

/* maps::shade: material *m (which has maps) at coordinates tc, the unit
 * shading normal *ns turned by its normal map, and *nc the clear coat's
 * own normal where it can differ from *ns (else left). */
static inline void shade_maps(const Scene *sc, const TexCoords *tc, Material *m, float3 *ns, float3 *nc) {
    __global const MaterialMaps *mm = &sc->maps[m->maps];
    __global const MapSlot *sl = mm->slot;
    if (sl[MAP_EMISSION].info.x != NO_TEXTURE) {
        m->emission.xyz = m->emission.xyz * map_read(sc, &sl[MAP_EMISSION], tc, 1).xyz;
    }
    if (sl[MAP_BASE_COLOR].info.x != NO_TEXTURE) {
        float4 c = map_read(sc, &sl[MAP_BASE_COLOR], tc, 1);
        m->albedo.xyz = m->albedo.xyz * c.xyz;
    }
#if HAS_GGX
    if (m->kind == MAT_PBR) {
        shade_pbr_maps(sc, tc, mm, m);
    }
#endif
    float3 unmapped = *ns;
    if (sl[MAP_NORMAL].info.x != NO_TEXTURE) {
        *ns = map_turned(sc, &sl[MAP_NORMAL], mm->factors.z, tc, unmapped);
    }
#if HAS_COAT_NORMAL
    if (m->kind == MAT_PBR && m->coat.x > 0.0f) {
        if (sl[MAP_CLEARCOAT_NORMAL].info.x != NO_TEXTURE) {
            *nc = map_turned(sc, &sl[MAP_CLEARCOAT_NORMAL], mm->spec_color.w, tc, unmapped);
        } else if (sl[MAP_NORMAL].info.x != NO_TEXTURE) {
            *nc = unmapped;
        }
    }
#else
    (void)nc;
#endif
}

/* World::shade: material *m (which has maps) as it is at h, sf's shading
 * normal turned by its normal map and its coat's normal set. */
static inline void apply_maps(const Scene *sc, const Hit *h, Surf *sf, Material *m) {
    TexCoords tc = texcoords(sc, h, sf);
    float3 ns = sf->ns;
    float3 nc = (float3)(0.0f);
    shade_maps(sc, &tc, m, &ns, &nc);
#if HAS_COAT_NORMAL
    if ((nc.x != ns.x || nc.y != ns.y || nc.z != ns.z) && (nc.x != 0.0f || nc.y != 0.0f || nc.z != 0.0f)) {
        sf->nc = nc;
        sf->smooth = 1;
    }
#endif
    if (ns.x != sf->ns.x || ns.y != sf->ns.y || ns.z != sf->ns.z) {
        sf->ns = ns;
        sf->smooth = 1;
    }
}

/* World::emitted: the radiance of emitter L (which has an emission map)
 * at h, where the shadow ray from o along d met it. */
static inline float3 emitted(const Scene *sc, __global const Light *L, const Hit *h, float3 o, float3 d) {
    Surf sf = surface_at(sc, h, o, d);
    TexCoords tc = texcoords(sc, h, &sf);
    return L->emission.xyz * map_read(sc, &sc->maps[L->maps].slot[MAP_EMISSION], &tc, 1).xyz;
}

#if HAS_ALPHA
/* AlphaTest::alpha with a texture: its factor times the alpha channel at
 * the triangle's interpolated coordinates (0, 0 without any). */
static inline float alpha_texel(const Scene *sc, __global const Instance *in, __global const AlphaTest *a, uint slot,
                                float3 bary) {
    float2 uv = (float2)(0.0f);
    if (in->uv_base != NO_NORMALS) {
        __global const float4 *c = sc->uvs + (size_t)(in->uv_base + slot - in->tri_base) * 3u;
        float4 m = c[0] * bary.x + c[1] * bary.y + c[2] * bary.z;
        uv = (a->tex.info.y & 1u) != 0u ? m.zw : m.xy;
    }
    return a->factor * tex_lookup(sc, &a->tex, uv, 0).w;
}
#endif
#endif

#if HAS_VERTEX_COLORS && HAS_MESHES
/* World::shade's vertex colour: the base colour times the mesh's
 * interpolated vertex colour at h (Mesh::color), where it has them. */
static inline void apply_vertex_color(const Scene *sc, const Hit *h, Material *m) {
    __global const Object *ob = &sc->objects[h->object];
    if (ob->kind != KIND_INSTANCE) {
        return;
    }
    __global const Instance *in = &sc->instances[ob->pad0];
    if (in->color_base == NO_NORMALS) {
        return;
    }
    size_t k = (size_t)(h->slot - in->tri_base) * 3u;
    __global const float4 *c = sc->colors + (size_t)in->color_base * 3u + k;
    float3 b = h->bary;
    float3 col = c[0].xyz * b.x + c[1].xyz * b.y + c[2].xyz * b.z;
    m->albedo.xyz = m->albedo.xyz * col;
}
#endif
