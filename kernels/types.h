/* Types shared with the host. Their Rust twins, with the same names and
 * layout (sizes asserted on both sides), are in
 * server/src/render/backend/opencl/layout.rs, and so are the shared
 * constants (KIND_*, MAT_*, NO_OBJECT, MAX_BVH_STACK, ...): the host passes
 * them to every build as -D options, so they are written once. The scene's
 * buffers are listed once, in scene_arrays.h.
 *
 * Floating point: no contraction of a * b + c into fma, as in the Rust twins
 * (which never fuse), so that both round every operation the same way and the
 * CPU's error bounds hold here; division and sqrt are correctly rounded
 * (-cl-fp32-correctly-rounded-divide-sqrt, see program.rs). */
#ifndef ALLOW_CONTRACTION
#pragma OPENCL FP_CONTRACT OFF
#endif

/* Vector products as the Rust twins (glam) compute them, product by
 * product: OpenCL's dot, cross and normalize may use fma or rsqrt (NVIDIA's
 * do), so the kernel never calls them. dot3 adds left to right, as glam's
 * dot3_in_x; normalize3 is v * (1 / |v|), as glam's normalize. */
static inline float dot3(float3 a, float3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

static inline float3 cross3(float3 a, float3 b) {
    return (float3)(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

static inline float3 normalize3(float3 v) {
    return v * (1.0f / sqrt(dot3(v, v)));
}

/* glam's normalize_or_zero: v * (1 / |v|) when that is finite and > 0. */
static inline float3 normalize_or_zero(float3 v) {
    float rcp = 1.0f / sqrt(dot3(v, v));
    return (isfinite(rcp) && rcp > 0.0f) ? v * rcp : (float3)(0.0f);
}

typedef struct {
    float4 p0;  /* sphere: centre.xyz, radius  | quad: corner.xyz, area */
    float4 p1;  /* sphere: k = |c|^2 - r^2, 1/r | quad: edge_u.xyz       */
    float4 p2;  /*                               quad: edge_v.xyz       */
    float4 p3;  /*                               quad: unit normal.xyz  */
    float4 p4;  /*                               quad: (u x v)/|u x v|^2 */
    uint kind;
    uint material;
    uint pad0;
    uint pad1;
} Object;

typedef struct {
    float4 albedo;   /* w: index of refraction (glass) */
    float4 emission;
    uint kind;
    uint schlick;
    uint emissive;
    uint maps;       /* its MaterialMaps, or NO_MAPS */
    float4 pbr;      /* MAT_PBR: metallic, alpha, roughness, f0 (ggx.h) */
    float4 glass;    /* MAT_PBR: transmission, ior, thin wall (ggx.h) */
    float4 absorb;   /* absorption per unit inside (HAS_VOLUME); w unused */
    float4 coat;     /* MAT_PBR: clear coat weight, alpha, roughness (HAS_COAT) */
    float4 spec;     /* MAT_PBR: the dielectric's Schlick F0 (rgb) and F90 */
} Material;

/* A material's texture slot (opencl/textures.rs, MapSlot): its UV
 * transform's rows (u' = xf_u.x u + xf_u.y v + xf_u.z, v' likewise), then
 * texture (NO_TEXTURE: unused), UV set, wrap along u and along v (Wrap). */
typedef struct {
    float4 xf_u;
    float4 xf_v;
    uint4 info;
} MapSlot;

/* A material's maps (maps.rs, WorldMaps): a slot per texture::Map, at
 * index MAP_*; factors: metallic, roughness, normal scale, 1 where
 * metallic and roughness share one lookup; layers: transmission, clear
 * coat weight and roughness, specular; spec_color: the specular colour
 * and the clear coat normal map's scale. */
typedef struct {
    MapSlot slot[MAP_SLOTS];
    float4 factors;
    float4 layers;
    float4 spec_color;
} MaterialMaps;

/* A mesh slot's alpha test (render/alpha.rs, AlphaTest): the base colour
 * texture whose alpha channel multiplies `factor` (tex.info.x NO_TEXTURE:
 * none); mode 0 opaque, 1 mask (alpha >= cutoff), 2 blend. */
typedef struct {
    MapSlot tex;
    float cutoff;
    float factor;
    uint mode;
    uint pad0;
} AlphaTest;

/* Where a texture's RGBA8 texels start in `texels`, and its size. */
typedef struct {
    uint offset;
    uint width;
    uint height;
    uint pad0;
} TexImage;

typedef struct {
    float4 forward;  /* w: near_clip */
    float4 right;    /* scaled by the image plane's width at distance 1 */
    float4 up;       /* scaled by its height */
    ulong seed;
    uint width;
    uint height;
    uint max_depth;
    uint rr_depth;
    uint nee;
    uint filter;     /* 0 = tent2x2, 1 = box */
    float clamp;
    uint num_objects;
    uint num_lights;
    uint sampler;    /* 0 = random, 1 = sobol */
    uint use_bvh;    /* nearest hits through the BVH (nodes, prims, big) */
    uint num_big;    /* objects tested one by one before the BVH */
    float lens_x;    /* thin lens: radius / |right|, 0 for a pinhole */
    float lens_y;    /* radius / |up|; right.w: the focus distance */
    float4 environment; /* radiance of rays that leave the scene; with a map,
                           what camera rays see where it is hidden (w: 1 where
                           it is visible) */
    float4 env;      /* environment map: rotation's cos, sin; intensity */
    uint4 env_size;  /* its width and height (0: no map) */
    uint4 camera;    /* x: the projection (PROJ_*) */
    float4 sun;      /* a sky's sun: unit direction towards it; w: 1 - cos(radius) */
    float4 sun_radiance; /* w: 1 where there is a sun */
} Params;

/* A BVH node (render/bvh/mod.rs, BvhNode): four children's boxes as
 * structure of arrays, bounds[0..3] the min x, y, z and bounds[3..6] the
 * max x, y, z of children 0..3. Child i is an inner node (count[i] == 0,
 * child[i] its index), a leaf (count[i] > 0 slots from child[i]), or empty
 * (an inverted box that no ray meets). */
typedef struct {
    float4 bounds[6];
    uint child[4];
    uint count[4];
} BvhNode;

/* An emitter and its entries of the power pick table (layout.rs, Light;
 * render/light/pick.rs): it owns the 31-bit x in [lower, upper); guide is
 * the table's guide entry i, the emitter owning column i's first x. */
typedef struct {
    uint object;     /* the object a shadow ray must hit to see it */
    uint prim;       /* and its triangle, or NO_PRIM */
    uint lower;
    uint upper;
    float pmf;
    uint kind;       /* LIGHT_OBJECT (its Object), LIGHT_TRIANGLE, LIGHT_ENVIRONMENT, LIGHT_ENV_MAP, LIGHT_SUN */
    uint maps;       /* its material's maps where they have an emission map, else NO_MAPS */
    uint guide;
    float4 emission;
    float4 p0;       /* a triangle in camera space: p0 + e1 b1 + e2 b2 */
    float4 e1;
    float4 e2;
    float4 n;        /* unit normal; w: area */
} Light;

/* A triangle as a mesh stores it in leaf order (shape/triangle.rs,
 * TriVerts): v0.w is its index in the mesh and v1.w its material slot,
 * both as bits. */
typedef struct {
    float4 v0;
    float4 v1;
    float4 v2;
} TriVerts;

/* A placed mesh (opencl/meshes.rs, Instance): glam Affine3A columns. */
typedef struct {
    float4 obj_from_cam[4];
    float4 cam_from_obj[4];
    float4 normal_from_obj[3];
    float rt_a;        /* |obj(cam(p)) - p| <= rt_a max|p| + rt_b */
    float rt_b;
    uint node_base;    /* the mesh's nodes and triangles in the shared buffers */
    uint tri_base;
    uint slot_base;    /* this instance's material of each mesh slot */
    uint normal_base;  /* 3 vertex normals per triangle from here, or NO_NORMALS */
    uint uv_base;      /* 3 corners' (u0, v0, u1, v1) per triangle, or NO_NORMALS */
    uint tangent_base; /* 3 corners' tangents (w: sign) per triangle, or NO_NORMALS */
    uint alpha_base;   /* its mesh slots' alpha tests in `alpha`, or NO_NORMALS */
    uint color_base;   /* 3 corners' vertex colours per triangle, or NO_NORMALS */
    uint pad1;
    uint pad2;
} Instance;

/* The nearest hit: object, triangle (NO_PRIM for spheres and quads), the
 * triangle's slot in the shared buffer, its barycentrics. */
typedef struct {
    float t;
    uint object;
    uint prim;
    uint slot;
    float3 bary;
} Hit;

/* The scene's buffers (scene_arrays.h), as one argument for the routines
 * that read them. */
#define SCENE_FIELD(T, name) __global const T *name;
typedef struct {
    SCENE_ARRAYS(SCENE_FIELD)
} Scene;
#undef SCENE_FIELD

/* Whether render adds the denoiser's feature sums (a job's setting, given
 * to every program; none where a build names none, as the checks do). */
#ifndef FEATURES
#define FEATURES 0
#endif

/* What the program was specialised for. Without SPECIALISED every feature is
 * compiled in and counts and switches are read from Params (the generic
 * program the benchmark compares against). */
#ifndef SPECIALISED
#define HAS_SPHERES 1
#define HAS_QUADS 1
#define HAS_DIFFUSE 1
#define HAS_MIRROR 1
#define HAS_GLASS 1
#define HAS_GGX 1
#define HAS_TRANSMISSION 1
#define HAS_VOLUME 1
#define HAS_COAT 1
#define HAS_COAT_NORMAL 1
#define HAS_VERTEX_COLORS 1
#define HAS_SCHLICK 1
#define HAS_EXACT 1
#define HAS_SPHERE_LIGHTS 1
#define HAS_QUAD_LIGHTS 1
#define HAS_BVH 1
#define BVH_STACK MAX_BVH_STACK
#define HAS_MESHES 1
#define MESH_STACK MAX_BVH_STACK
#define HAS_TRI_LIGHTS 1
#define HAS_ENV 1
#define HAS_ENV_MAP 1
#define HAS_SUN 1
#define HAS_LENS 1
#define HAS_TEXTURES 1
#define HAS_ALPHA 1
#define USE_BVH (P->use_bvh != 0u)
#define OBJECT_COUNT (P->num_objects)
#define LIGHT_COUNT (P->num_lights)
#define MAX_DEPTH (P->max_depth)
#define RR_DEPTH (P->rr_depth)
#define USE_NEE (P->nee != 0u)
#define USE_BOX_FILTER (P->filter != 0u)
#define USE_SOBOL (P->sampler != 0u)
#define USE_ENV_MAP (P->env_size.x != 0u)
#define USE_SUN (P->sun_radiance.w != 0.0f)
#define CAMERA_PROJECTION (P->camera.x)
#else
#define CAMERA_PROJECTION PROJECTION
#define USE_BVH HAS_BVH
#define OBJECT_COUNT NUM_OBJECTS
#define LIGHT_COUNT NUM_LIGHTS
#define MAX_DEPTH MAX_DEPTH_VALUE
#define RR_DEPTH (P->rr_depth)
#define USE_NEE NEE
#define USE_BOX_FILTER BOX_FILTER
#define USE_SOBOL SOBOL
#define USE_ENV_MAP HAS_ENV_MAP
#define USE_SUN HAS_SUN
#endif
/* A hit's material: a private copy where textures or vertex colours can
 * change it per hit (maps.h), else the scene's own. */
#if HAS_TEXTURES || HAS_VERTEX_COLORS
typedef const Material *MatRef;
#else
typedef __global const Material *MatRef;
#endif
/* Multiple importance sampling: at MAT_PBR vertices, and at diffuse ones
 * under an environment map (integrator.rs, World::diffuse_mis). */
#define HAS_MIS (HAS_GGX || HAS_ENV_MAP)
