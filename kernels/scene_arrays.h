/* The scene's device buffers, written once: SCENE_ARRAYS(X) applies
 * X(element type, name) to each, in order (an X-macro, as Cycles'
 * kernel/data_arrays.h; a macro taking X rather than a file included
 * several times, because the host hands the sources to the compiler as one
 * string, with no include path). types.h expands it into the Scene struct,
 * render.cl into the render kernel's first parameters (each
 * `__global const T *name`) and the Scene it builds from them.
 *
 * Its host twin is SCENE_ARRAYS in
 * server/src/render/backend/opencl/buffers.rs, which uploads, sizes and
 * binds the buffers in this order; opencl/contract_tests.rs reads this file
 * and fails when the two disagree (names, order, element types; the
 * device's sizeof of each element type against the host's). One entry per
 * line. */
#define SCENE_ARRAYS(X)                                                          \
    X(Params, P)                                                                 \
    X(Object, objects)                                                           \
    X(Material, materials)                                                       \
    X(Light, lights)                                                             \
    X(BvhNode, nodes)      /* the objects' BVH (use_bvh) */                      \
    X(uint, prims)         /* object of each leaf slot */                        \
    X(uint, big)           /* objects tested before the BVH */                   \
    X(Instance, instances)                                                       \
    X(BvhNode, mesh_nodes)                                                       \
    X(TriVerts, tris)                                                            \
    X(float4, normals)     /* vertex normals per triangle slot */                \
    X(uint, slots)         /* world material of each instance slot */        \
    X(float, ggx)          /* metallic-roughness albedo tables (ggx.h) */  \
    X(float, env_texels)   /* environment map, RGB per texel (envmap.h) */ \
    X(float, env_dist)     /* its sampling tables (envmap.h) */          \
    X(float4, uvs)         /* texture coordinates per triangle slot */  \
    X(float4, tangents)    /* tangents per triangle slot */              \
    X(float4, colors)      /* vertex colours per triangle slot */        \
    X(MaterialMaps, maps)  /* material texture maps (maps.h) */          \
    X(TexImage, tex_images) /* each texture's place in texels */        \
    X(uint, texels)        /* RGBA8 texels of every texture */           \
    X(float, srgb)         /* sRGB byte -> linear table */               \
    X(AlphaTest, alpha)    /* alpha tests per instance slot (triangles.h) */
