/* Types shared with the host. Their Rust twins, with the same names and
 * layout (sizes asserted on both sides), are in
 * server/src/render/backend/opencl/layout.rs, and so are the shared
 * constants (KIND_*, MAT_*, NO_OBJECT): the host passes them to every build
 * as -D options, so they are written once.
 *
 * Floating point: no contraction of a * b + c into fma, as in the Rust twins
 * (which never fuse), so that both round every operation the same way and the
 * CPU's error bounds hold here; division and sqrt are correctly rounded
 * (-cl-fp32-correctly-rounded-divide-sqrt, see program.rs). */
#ifndef ALLOW_CONTRACTION
#pragma OPENCL FP_CONTRACT OFF
#endif

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
    uint pad0;
} Material;

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
    uint pad0;
    uint use_bvh;    /* nearest hits through the BVH (nodes, prims, big) */
    uint num_big;    /* objects tested one by one before the BVH */
    uint pad1;
    uint pad2;
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

/* An emitter and its column of the power alias table (layout.rs, Light;
 * render/light/alias.rs): index column kept when the low 32 bits of the
 * pick are below threshold (or threshold is all ones), else alias. */
typedef struct {
    uint object;
    uint threshold;
    uint alias;
    float pmf;
} Light;

/* The scene's buffers, as one argument for the routines that read them. */
typedef struct {
    __global const Params *P;
    __global const Object *objects;
    __global const Material *materials;
    __global const Light *lights;
    __global const BvhNode *nodes; /* the objects' BVH (use_bvh) */
    __global const uint *prims;    /* object of each leaf slot */
    __global const uint *big;      /* objects tested before the BVH */
} Scene;

/* What the program was specialised for. Without SPECIALISED every feature is
 * compiled in and counts and switches are read from Params (the generic
 * program the benchmark compares against). */
#ifndef SPECIALISED
#define HAS_SPHERES 1
#define HAS_QUADS 1
#define HAS_DIFFUSE 1
#define HAS_MIRROR 1
#define HAS_GLASS 1
#define HAS_SCHLICK 1
#define HAS_EXACT 1
#define HAS_SPHERE_LIGHTS 1
#define HAS_QUAD_LIGHTS 1
#define HAS_BVH 1
#define BVH_STACK 196
#define USE_BVH (P->use_bvh != 0u)
#define OBJECT_COUNT (P->num_objects)
#define LIGHT_COUNT (P->num_lights)
#define MAX_DEPTH (P->max_depth)
#define RR_DEPTH (P->rr_depth)
#define USE_NEE (P->nee != 0u)
#define USE_BOX_FILTER (P->filter != 0u)
#else
#define USE_BVH HAS_BVH
#define OBJECT_COUNT NUM_OBJECTS
#define LIGHT_COUNT NUM_LIGHTS
#define MAX_DEPTH MAX_DEPTH_VALUE
#define RR_DEPTH (P->rr_depth)
#define USE_NEE NEE
#define USE_BOX_FILTER BOX_FILTER
#endif
