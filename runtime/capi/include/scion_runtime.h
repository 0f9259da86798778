/* The Scion runtime's C library (libscion_runtime.a, crate scion-runtime-c).
 *
 * Scenes (Wavefront OBJ), the logical BVH (binned SAH with the runtime's defaults, as
 * `scion trace` builds it), the ScionTreeView that generated code packs from, the primary
 * camera rays of `scion trace`, the reference closest hit, and the hits checksum that
 * `scion trace` prints. See docs/c-abi.md.
 *
 * Every function that can fail returns a status (SCION_RT_OK or an SCION_RT_ERR_* code) and,
 * when `err` is not NULL, writes a NUL-terminated message of at most `err_len` bytes there.
 * No function unwinds into C: internal failures come back as SCION_RT_ERR_INTERNAL.
 * Every handle has its free function; freeing NULL does nothing.
 *
 * Link with: -lscion_runtime -lpthread -ldl -lm
 */
#ifndef SCION_RUNTIME_H
#define SCION_RUNTIME_H

#include <stddef.h>
#include <stdint.h>

#ifndef SCION_STATIC_ASSERT
#if defined(__cplusplus)
#define SCION_STATIC_ASSERT(c, msg) static_assert(c, msg)
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
#define SCION_STATIC_ASSERT(c, msg) _Static_assert(c, msg)
#else
#define SCION_STATIC_ASSERT_CAT2(a, b) a##b
#define SCION_STATIC_ASSERT_CAT(a, b) SCION_STATIC_ASSERT_CAT2(a, b)
#define SCION_STATIC_ASSERT(c, msg) \
    typedef char SCION_STATIC_ASSERT_CAT(scion_static_assert_, __LINE__)[(c) ? 1 : -1]
#endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* The runtime contract's structs; the same definitions as in every header of
 * `scionc --emit=header`, so both can be included together. */
#ifndef SCION_ABI_TYPES_DEFINED
#define SCION_ABI_TYPES_DEFINED
/* A triangle (40 bytes), the same in the logical tree and in packed layouts. */
typedef struct ScionTriangle {
    float p0[3];
    float p1[3];
    float p2[3];
    uint32_t id;
} ScionTriangle;
/* A strand segment (36 bytes): the axis from p0 to p1, radius r0 at p0 and r1 at p1. */
typedef struct ScionSegment {
    float p0[3];
    float r0;
    float p1[3];
    float r1;
    uint32_t id;
} ScionSegment;
/* Four triangles stored lane by lane (160 bytes): each coordinate of each corner an array over
 * the lanes; a block of fewer than four repeats its last triangle. */
typedef struct ScionTriangle4 {
    float x0[4], y0[4], z0[4];
    float x1[4], y1[4], z1[4];
    float x2[4], y2[4], z2[4];
    uint32_t id[4];
} ScionTriangle4;
/* The logical tree as generated code reads it (32 bytes): node_count nodes of the layout's
 * tree type (its ScionLogical_<Type> struct in the layout's header), 8-byte aligned. */
typedef struct ScionTreeView {
    const void *nodes;
    uint32_t node_count;
    uint32_t root; /* UINT32_MAX for the empty tree */
    const void *prims; /* prim_count records of the layout's primitive: ScionTriangle,
                          ScionSegment for a layout over strands, or ScionTriangle4 for one
                          over blocks of four triangles (its schema's primitive) */
    uint32_t prim_count;
} ScionTreeView;
/* What the runtime writes into a field of a logical node (docs/c-abi.md). */
#define SCION_ROLE_BOUNDS 1       /* the node's box: float[6] */
#define SCION_ROLE_CHILD_BOUNDS 2 /* the boxes of child slots slot..slot+count: float[count][6] */
#define SCION_ROLE_CHILDREN 3     /* child slots slot..slot+count: uint32_t node indices */
#define SCION_ROLE_PRIM_COUNT 4   /* a leaf's primitive count: an unsigned int of width bytes */
#define SCION_ROLE_PRIM_OFFSET 5  /* a leaf's first primitive: uint32_t */
#define SCION_ROLE_DOP14_BOUNDS 6 /* the node's DOP-14: float[14], axis mins, maxes, diagonal mins, maxes */
#define SCION_ROLE_CHILD_OBBS 7   /* oriented boxes of child slots: float[count][15], columns vx, vy, vz of M, then the box of M*x */
#define SCION_SHARED 0xFFFFFFFFu  /* `variant` of a field every variant has */
typedef struct ScionLogicalField {
    uint32_t role, variant, offset, slot, count, width;
} ScionLogicalField;
/* What a tree type's leaves hold (ScionLogicalSchema.primitive; ScionTreeView.prims). */
#define SCION_PRIM_TRIANGLE 0  /* ScionTriangle */
#define SCION_PRIM_SEGMENT 1   /* ScionSegment (strands) */
#define SCION_PRIM_TRIANGLE4 2 /* ScionTriangle4 (the tree's leaves cut into blocks of four) */
/* The shape of a tree type's logical nodes (its scion_logical_<Type> constant). */
typedef struct ScionLogicalSchema {
    uint32_t node_size, node_align, interior, leaf, arity, field_count;
    const ScionLogicalField *fields;
    uint32_t primitive; /* SCION_PRIM_* */
} ScionLogicalSchema;
SCION_STATIC_ASSERT(sizeof(ScionTriangle) == 40, "ScionTriangle is 40 bytes");
SCION_STATIC_ASSERT(sizeof(ScionSegment) == 36, "ScionSegment is 36 bytes");
SCION_STATIC_ASSERT(sizeof(ScionTriangle4) == 160, "ScionTriangle4 is 160 bytes");
SCION_STATIC_ASSERT(sizeof(ScionTreeView) == 32, "ScionTreeView is 32 bytes");
SCION_STATIC_ASSERT(offsetof(ScionTreeView, root) == 12, "ScionTreeView.root at 12");
SCION_STATIC_ASSERT(offsetof(ScionTreeView, prims) == 16, "ScionTreeView.prims at 16");
SCION_STATIC_ASSERT(sizeof(ScionLogicalField) == 24, "ScionLogicalField is 24 bytes");
SCION_STATIC_ASSERT(sizeof(ScionLogicalSchema) == 40, "ScionLogicalSchema is 40 bytes");
SCION_STATIC_ASSERT(offsetof(ScionLogicalSchema, primitive) == 32, "ScionLogicalSchema.primitive at 32");
#endif

/* A ray (32 bytes): hits have tmin < t < tmax. The same bytes as the query record
 * `scion_closest_hit_query` of the closest-hit entry points. */
typedef struct ScionRay {
    float origin[3];
    float dir[3];
    float tmin;
    float tmax;
} ScionRay;
SCION_STATIC_ASSERT(sizeof(ScionRay) == 32, "ScionRay is 32 bytes");

/* A closest hit (8 bytes): t = +inf and prim = UINT32_MAX on a miss. */
typedef struct ScionHit {
    float t;
    uint32_t prim;
} ScionHit;
SCION_STATIC_ASSERT(sizeof(ScionHit) == 8, "ScionHit is 8 bytes");

/* A closest point (20 bytes): the result record `scion_closest_point_query_result` of the
 * closest-point entry points. */
typedef struct ScionClosestPoint {
    float distance;
    uint32_t prim; /* UINT32_MAX: none */
    float point[3];
} ScionClosestPoint;
SCION_STATIC_ASSERT(sizeof(ScionClosestPoint) == 20, "ScionClosestPoint is 20 bytes");

/* Status codes. */
#define SCION_RT_OK 0
#define SCION_RT_ERR_ARGUMENT 1 /* a NULL pointer or a value out of range */
#define SCION_RT_ERR_SCENE 2    /* the scene could not be read or parsed */
#define SCION_RT_ERR_EMPTY 3    /* the scene has no triangles: nothing to aim rays at */
#define SCION_RT_ERR_INTERNAL 4 /* a bug in the runtime (reported, never unwound into C) */

typedef struct ScionScene ScionScene; /* a loaded scene */
typedef struct ScionTree ScionTree;   /* a logical BVH over a scene's triangles */

/* Loads the OBJ scene at `path` (UTF-8) into *out. */
int32_t scion_scene_load(const char *path, ScionScene **out, char *err, size_t err_len);
/* The number of triangles of a scene (0 for NULL). */
uint64_t scion_scene_triangle_count(const ScionScene *scene);
void scion_scene_free(ScionScene *scene);

/* Builds the logical tree of `scene` with binned SAH, leaves of up to `max_leaf` triangles
 * (1..15; 0 means the default 15, as `scion trace`), into *out. */
int32_t scion_tree_build(const ScionScene *scene, uint32_t max_leaf, ScionTree **out,
                         char *err, size_t err_len);
/* Fills *view with the tree's nodes in the shape `schema` describes (the constant
 * scion_logical_<Type> of a layout's generated header) and its triangles; valid while the tree
 * lives. Fails when the schema is not one the runtime can fill. */
int32_t scion_tree_view(const ScionTree *tree, const ScionLogicalSchema *schema,
                        ScionTreeView *view, char *err, size_t err_len);
void scion_tree_free(ScionTree *tree);

/* Writes the `n` primary camera rays of `scion trace --rays primary --n N --seed S` for
 * `scene` to rays[0..n) (1 <= n <= 2^32). */
int32_t scion_primary_rays(const ScionScene *scene, uint64_t n, uint64_t seed, ScionRay *rays,
                           char *err, size_t err_len);

/* Writes the `n` secondary rays of `scion trace --rays secondary --n N --seed S` for `scene`
 * (origins and directions uniform in and around its box) to rays[0..n) (1 <= n <= 2^32). */
int32_t scion_secondary_rays(const ScionScene *scene, uint64_t n, uint64_t seed, ScionRay *rays,
                             char *err, size_t err_len);

/* The runtime's reference closest hits of rays[0..n) against `tree`, on `threads` threads
 * (0: one per core), into hits[0..n). */
int32_t scion_reference_closest_hits(const ScionTree *tree, const ScionRay *rays, uint64_t n,
                                     uint32_t threads, ScionHit *hits, char *err,
                                     size_t err_len);

/* Writes the `n` points of `scion run --algorithm closest-point --n N --seed S` for `scene`
 * (uniform in its box) to points[0..3n) as x, y, z. */
int32_t scion_uniform_points(const ScionScene *scene, uint64_t n, uint64_t seed, float *points,
                             char *err, size_t err_len);

/* The closest point of the scene to each of points[0..3n) (x, y, z), by float32 brute force
 * over its triangles on `threads` threads (0: one per core): the answers every layout's
 * closest_point_query returns, bit for bit (distance, then the smaller id on ties). */
int32_t scion_reference_closest_points(const ScionScene *scene, const float *points, uint64_t n,
                                       uint32_t threads, ScionClosestPoint *out, char *err,
                                       size_t err_len);

/* A new scene: `scene` turned by x, y, z degrees about the axes through the centre of its box
 * (x first, then y, then z; computed in double, rounded to float; ids kept), as
 * `scion run --algorithm collide --rotate X,Y,Z` makes its copy. Free it with
 * scion_scene_free. */
int32_t scion_scene_rotated(const ScionScene *scene, double x, double y, double z,
                            ScionScene **out, char *err, size_t err_len);

/* The pairs (id in a, id in b) of triangles of `a` and `b` whose boxes overlap and that the
 * prelude's separating-axis test does not separate: what `collide` returns on every layout.
 * Sorted, no repeats; a sink like the entries' sets: *count is the number of pairs, the first
 * min(count, capacity) are written to pairs. */
int32_t scion_reference_collide(const ScionScene *a, const ScionScene *b, uint32_t (*pairs)[2],
                                uint64_t capacity, uint64_t *count, char *err, size_t err_len);

/* The hit of a closest-hit result record (best t, best id): a miss when id is UINT32_MAX. */
ScionHit scion_hit_from_best(float t, uint32_t prim);

/* The checksum `scion trace` prints (`checksum: %016llx`): 64-bit FNV-1a over the hits file
 * bytes of hits[0..n). */
uint64_t scion_hits_checksum(const ScionHit *hits, uint64_t n);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* SCION_RUNTIME_H */
