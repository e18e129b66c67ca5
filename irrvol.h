/* irrvol.h - v0.3.0 - irradiance volume for lighting moving objects - public domain or MIT, see end of file

   IRRVOL.H: a bilevel grid of directional irradiance samples that lights moving objects by interpolation.

   The irradiance volume (Greger 1996) samples the irradiance distribution
   function H(x, w) of a static scene at the vertices of a bilevel grid: a
   regular first-level grid over the scene, refined by a second-level grid in
   every cell that contains geometry. At each grid vertex ("sample") radiance
   is gathered along 2k^2 equal-area directions of the Shirley-Chiu concentric
   map (k x k bins per hemisphere), and the irradiance of a surface facing each
   bin direction is summed from it (eq. 4.3, or the moment of order n, eq. 4.8).
   A query at any position and normal finds the cell (eq. 4.4-4.6), the bin of
   the direction (inverse concentric map) and interpolates trilinearly between
   the cell's eight samples: tens of millions of queries per second, enough to
   re-light every vertex of moving objects every frame. A moving object's
   diffuse radiance is then reflectance * H / pi (eq. 4.7).

   Radiance comes from the header's own ray caster (a BVH over the caller's
   triangles: per-material radiance, optional per-vertex radiance, mirror
   chains) or from the caller's radiance callback (a radiosity solution, a
   path tracer, a picture-based environment).

   DO THIS

       #define IRRVOL_IMPLEMENTATION
       #include "irrvol.h"

   in exactly one C or C++ file; include "irrvol.h" without the define
   everywhere else.

   EXAMPLE

       irrvol_material mats[2] = {{{0.2f, 0.2f, 0.2f}}, {{40.0f, 36.0f, 28.0f}}}; // radiance
       irrvol_desc d = {0};
       irrvol *vol;
       d.positions = xyz;  d.vertex_count = nv;
       d.indices = idx;    d.triangle_count = nt;
       d.triangle_materials = mat_of_tri;
       d.materials = mats; d.material_count = 2;
       mats[1].flags = IRRVOL_MATERIAL_IMPORTANT;   // the lamp: never missed
       if (irrvol_build(&d, &vol) != IRRVOL_OK) ...;
       for each vertex of a moving object:
           float h[3];
           irrvol_query(vol, p, n, h);              // irradiance W/m^2
           colour = reflectance * h / pi;           // eq. 4.7
       irrvol_destroy(vol);

   CONFIGURATION MACROS

       IRRVOL_STATIC              make every function static (private to one file)
       IRRVOL_API                 linkage of public functions (default: extern)
       IRRVOL_MALLOC, IRRVOL_FREE replace malloc/free (define both or neither)
       IRRVOL_BVH_BINS            SAH bins of the BVH build (default 16)
       IRRVOL_BVH_SIMD            1 (default): SSE2 (x86-64) or NEON (AArch64) BVH kernels
                                  when the compiler offers them; 0: the portable scalar
                                  kernels only (the same hits, bit for bit)
       IRRVOL_MAX_RESOLUTION      largest k accepted (default 64; the shared
                                  weight matrix holds (2k^2)^2 floats)
       IRRVOL_MAX_GRID_SAMPLES    largest first-level samples per axis (default 1024)
       IRRVOL_MAX_SUBGRID_SAMPLES largest second-level samples per axis (default 33)
       IRRVOL_MAX_MOMENT          largest moment order n (default 1024)

   FUNCTION REFERENCE

     build and destroy
       irrvol_result irrvol_build(const irrvol_desc *desc, irrvol **out);
       void          irrvol_destroy(irrvol *vol);
       irrvol_result irrvol_info(const irrvol *vol, irrvol_volume_info *info);
     query (thread-safe, no allocation, no failure: positions outside the
     bounds clamp to the boundary, NaN inputs give finite lookups)
       void     irrvol_query(const irrvol *vol, const float pos[3], const float dir[3], float rgb[3]);
       void     irrvol_query_filter(const irrvol *vol, irrvol_filter filter, const float pos[3],
                                    const float dir[3], float rgb[3]);
       void     irrvol_query_glossy(const irrvol *vol, const float pos[3], const float normal[3],
                                    const float to_eye[3], float rgb[3]);
       void     irrvol_query_many(const irrvol *vol, irrvol_filter filter, uint32_t count,
                                  const float *pos, size_t pos_stride, const float *dir,
                                  size_t dir_stride, float *rgb);
     samples and bins (inspection, irradiance spheres, tests)
       irrvol_result irrvol_sample(const irrvol *vol, uint32_t index, irrvol_sample_info *info);
       irrvol_result irrvol_sample_values(const irrvol *vol, uint32_t index, float *irradiance,
                                          float *radiance);   // bins x rgb each, or NULL
       void     irrvol_bin_direction(const irrvol *vol, uint32_t bin, float dir[3]);
       uint32_t irrvol_direction_bin(const irrvol *vol, const float dir[3]);
     self-occlusion of dynamic meshes (thesis 6.1.3)
       irrvol_result irrvol_visibility_ratio(const irrvol_visibility_desc *desc, float *ratio);
     serialization
       irrvol_result irrvol_save(const irrvol *vol, irrvol_write_fn write, void *user);
       irrvol_result irrvol_load(const irrvol_allocator *a, irrvol_read_fn read, void *user, irrvol **out);
       irrvol_result irrvol_save_to_memory(const irrvol *vol, const irrvol_allocator *a,
                                           void **data, size_t *size);
       irrvol_result irrvol_load_from_memory(const void *data, size_t size,
                                             const irrvol_allocator *a, irrvol **out);
       void          irrvol_free_memory(const irrvol_allocator *a, void *data);
     errors
       const char   *irrvol_result_string(irrvol_result r);

   DETAILS

   Grid. desc.grid_samples[3] first-level samples per axis (Greger: 7^3) over
   the scene bounds shrunk by desc.inset on each side, so that samples and
   cells stay off the outer walls (4.1), or over desc.bounds_min/max exactly.
   Every first-level cell that a non-degenerate triangle overlaps (separating
   axis test of Akenine-Moller) gets a second-level grid of
   desc.subgrid_samples per axis, corners included (Greger: 3^3, so a refined
   cell holds 2^3 sub-cells). Neighbouring second-level grids share the samples
   on their common faces. A cell face between a refined and an unrefined cell
   interpolates differently from its two sides (as in the thesis).

   Bins. Bin b of a sample: hemisphere h = b / k^2 (0: z >= 0, 1: z < 0),
   row j = (b / k) % k, column i = b % k of the k x k square of the concentric
   map of that hemisphere. The lower hemisphere mirrors z, so both squares
   meet along the equator with equal (i, j): the BILINEAR filter blends across
   it. Every bin has solid angle 4 pi / 2k^2.

   Radiance (4.2.2). With desc.radiance set, it is called for every ray
   (concurrently from parallel jobs). Otherwise the built-in tracer (or
   desc.trace) finds the first hit: a material flagged IGNORE gives zero (light
   transfer exploration, 5.4); else the radiance is the material's radiance (or
   the per-vertex radiance interpolated with the hit's barycentrics) plus, for
   a mirror coefficient specular > 0, specular times the radiance along the
   reflected ray. The chain follows at most desc.max_depth reflections and
   stops when the remaining weight falls under desc.min_weight; a cut chain and
   a ray that leaves the scene see desc.background. With desc.supersamples = s
   > 1, each bin averages s x s jittered rays (one stratum each).

   Irradiance (4.2.3, 4.4). H^n(w_j) = sum_i L_i W(i, j), with W(i, j) =
   (n+1)/2 times the integral of max(0, w . w_j)^n over bin i (eq. 4.1 with
   the radiance constant over each bin; n = 1 is eq. 4.3). The integral is
   evaluated at w x w sub-directions per bin (desc.weight_subdivisions,
   default 4), so that a uniform radiance L gives pi L within 0.05 % at
   k = 17; weight_subdivisions = 1 evaluates eq. 4.3 / 4.8 literally at the
   bin centres (0.7 % off at k = 17). The weights form one (2k^2)^2 matrix
   shared by all samples; each sample's irradiance is a matrix product,
   summed exactly, never approximated.

   Informed sampling (6.1.1). Triangles of IMPORTANT materials (light
   sources) are never missed: for each sample, points are sampled on every
   IMPORTANT triangle (stratified; desc.important_rays in all, shared by solid
   angle, plus 16 per bin covered) and their radiance enters eq. 4.3 / 4.8 with
   each point's own direction and solid angle, while the bin rays that point
   at an IMPORTANT triangle count zero; bins such a triangle overlaps also
   get important_rays extra rays for the rest of the bin. A lamp far smaller
   than a bin then costs a few hundred rays per sample and is integrated to
   about 0.1 % at any k, where plain sampling misses it or overweights it.

   Queries. NEAREST (the thesis) returns the bin that contains the direction;
   BILINEAR (future work, 6.1.2) interpolates the four nearest bin centres on
   the concentric square, across the equator too: 4x the memory reads.
   irrvol_query_glossy mirrors the view vector about the normal (fig. 4.17) for
   moment volumes (desc.moment > 1). irrvol_query_many answers a batch (the
   vertices of a moving object) with the same results, faster: it prepares
   each query a few ahead and prefetches the values it will read.

   Determinism. Each sample draws its jitter from a stream seeded by
   (desc.seed, sample index): a volume is bit-identical for any thread count.

   Threads. Every function taking a const irrvol * (queries, irrvol_info,
   irrvol_sample, irrvol_sample_values, the bin functions, irrvol_save and
   irrvol_save_to_memory) only reads the volume, so any number of threads may
   call them on one volume at once, and irrvol_visibility_ratio keeps no
   shared state, so concurrent calls on one const desc with distinct ratio
   arrays are safe too.

   LIMITS

   k <= IRRVOL_MAX_RESOLUTION (64). Objects lit from the volume cast no shadows
   and do not see themselves: irrvol_visibility_ratio gives the fraction of
   each vertex's hemisphere its own mesh leaves open (cosine-weighted), a
   factor for the queried irradiance (thesis 5.1.3, 6.1.3). A sample that lies
   inside a closed object sees its inside.

   PAPER

       Gene S. Greger, The Irradiance Volume, M.S. thesis, Cornell University, 1996.
       Equation numbers in comments refer to it.
*/
#ifndef IRRVOL_H
#define IRRVOL_H

#include <stddef.h>
#include <stdint.h>

#define IRRVOL_VERSION_MAJOR 0
#define IRRVOL_VERSION_MINOR 3
#define IRRVOL_VERSION_PATCH 0
#define IRRVOL_FILE_FORMAT_VERSION 1

#ifndef IRRVOL_API
#  ifdef IRRVOL_STATIC
#    define IRRVOL_API static
#  else
#    define IRRVOL_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum irrvol_result {
    IRRVOL_OK = 0,
    IRRVOL_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    IRRVOL_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    IRRVOL_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    IRRVOL_ERROR_VERSION,           /* serialized data has an unsupported format version */
    IRRVOL_ERROR_CANCELLED,         /* the progress callback asked to stop */
    IRRVOL_ERROR_IO                 /* a read or write callback failed */
} irrvol_result;

/* Run-time allocator; zero fields mean IRRVOL_MALLOC / IRRVOL_FREE. */
typedef struct irrvol_allocator {
    void *(*alloc)(size_t size, void *user);
    void (*free)(void *ptr, void *user);
    void *user;
} irrvol_allocator;

/* Job hook: run job(ctx, i) for every i in [0, count), in any order, on any
   threads, and return when all are done. */
typedef void (*irrvol_job_fn)(void *ctx, uint32_t index);

/* A ray hit reported by a caller's ray caster. */
typedef struct irrvol_hit {
    float t;            /* distance along the ray in units of |dir| */
    float u, v;         /* barycentric weights of the triangle's 2nd and 3rd vertex */
    uint32_t triangle;  /* index into desc.indices / 3 */
} irrvol_hit;

/* Closest hit along org + t dir, 0 < t < tmax; returns 1 on a hit. */
typedef int (*irrvol_trace_fn)(void *user, const float org[3], const float dir[3], float tmax,
                               irrvol_hit *hit);

/* Radiance seen from org looking along the unit direction dir: the light
   that arrives at org from that direction. */
typedef void (*irrvol_radiance_fn)(void *user, const float org[3], const float dir[3], float rgb[3]);

typedef int (*irrvol_write_fn)(void *user, const void *bytes, size_t n); /* 0 = ok */
typedef int (*irrvol_read_fn)(void *user, void *bytes, size_t n);        /* 0 = all n bytes read */

enum {
    IRRVOL_MATERIAL_IGNORE = 1u,     /* rays that hit it see zero radiance (light transfer exploration) */
    IRRVOL_MATERIAL_IMPORTANT = 2u   /* informed sampling: bins that see it get extra rays */
};

typedef struct irrvol_material {
    float radiance[3];   /* outgoing diffuse radiance (emitted + reflected), W/(m^2 sr) */
    float specular[3];   /* mirror coefficient: reflected radiance is added with this weight */
    uint32_t flags;      /* IRRVOL_MATERIAL_* */
} irrvol_material;

typedef enum irrvol_filter {
    IRRVOL_FILTER_DEFAULT = 0,  /* the volume's filter (desc.filter), NEAREST if unset */
    IRRVOL_FILTER_NEAREST,      /* the bin containing the direction (thesis 4.3) */
    IRRVOL_FILTER_BILINEAR      /* bilinear between the four nearest bins (thesis 6.1.2) */
} irrvol_filter;

typedef struct irrvol_desc {
    /* Scene: triangles with per-triangle materials. Needed for the built-in
       radiance and for the second level; may be empty with desc.radiance and
       explicit bounds. */
    const float *positions;          /* xyz per vertex */
    size_t position_stride;          /* bytes between vertices; 0 = 3 floats */
    uint32_t vertex_count;
    const uint32_t *indices;         /* 3 per triangle, < vertex_count */
    uint32_t triangle_count;
    const uint32_t *triangle_materials; /* material of each triangle; NULL = material 0 */
    const irrvol_material *materials;
    uint32_t material_count;
    const float *vertex_radiance;    /* optional rgb per vertex, replaces the materials' radiance */
    size_t vertex_radiance_stride;   /* bytes between vertices; 0 = 3 floats */

    /* Grid. */
    uint32_t grid_samples[3];        /* first-level samples per axis, >= 2; 0 = 7 */
    uint32_t subgrid_samples;        /* second-level samples per axis, corners included; 0 = 3; 2 = none */
    float inset;                     /* fraction of the scene extent kept free on each side; 0 = 0.01 */
    float bounds_min[3], bounds_max[3]; /* grid bounds used as given; all zero = scene bounds with inset */

    /* Directions. */
    uint32_t resolution;             /* k: 2k^2 bins per sample; 0 = 17 (578 bins) */
    uint32_t supersamples;           /* s x s jittered rays per bin; 0 = 1 ray through the bin centre */
    uint32_t moment;                 /* n of eq. 4.8; 0 = 1 (irradiance, eq. 4.3) */
    uint32_t weight_subdivisions;    /* w x w sub-directions integrate each bin's weight; 0 = 4 */
    irrvol_filter filter;            /* filter of irrvol_query; 0 = NEAREST */

    /* Radiance. */
    irrvol_radiance_fn radiance;     /* replaces the built-in radiance when set */
    void *radiance_user;
    irrvol_trace_fn trace;           /* replaces the built-in BVH when set */
    void *trace_user;
    float background[3];             /* radiance of rays that leave the scene or cut chains */
    uint32_t max_depth;              /* mirror reflections followed; 0 = 6 */
    float min_weight;                /* chain weight floor; 0 = 0.01 */
    float ray_offset;                /* reflected rays start this far off the surface; 0 = 1e-4 * diagonal */
    uint32_t important_rays;         /* points on IMPORTANT triangles per sample, extra rays per bin; 0 = 64 */
    int keep_radiance;               /* non-zero: keep the gathered radiance (irrvol_sample) */

    uint64_t seed;                   /* jitter streams */
    irrvol_allocator allocator;
    void (*parallel_for)(void *user, irrvol_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    int (*progress)(void *user, uint64_t done, uint64_t total); /* samples; non-zero cancels */
    void *progress_user;
    void (*log)(void *user, const char *message);
    void *log_user;
} irrvol_desc;

typedef struct irrvol irrvol;

typedef struct irrvol_volume_info {
    uint32_t sample_count;           /* all samples */
    uint32_t first_level_samples;    /* grid_samples[0] * [1] * [2] */
    uint32_t second_level_samples;   /* samples added by second-level grids (shared ones once) */
    uint32_t grid_samples[3];
    uint32_t subgrid_samples;
    uint32_t cell_count;             /* first-level cells */
    uint32_t refined_cells;          /* cells with a second-level grid */
    uint32_t resolution;             /* k */
    uint32_t bins;                   /* 2k^2 */
    uint32_t moment;
    irrvol_filter filter;
    float bounds_min[3], bounds_max[3];
    uint64_t rays;                   /* rays cast by the build (kept by save/load) */
    uint32_t degenerate_triangles;   /* zero-area triangles skipped by the build */
    int has_radiance;                /* built with keep_radiance */
    size_t bytes;                    /* memory held by the volume */
} irrvol_volume_info;

typedef struct irrvol_sample_info {
    float position[3];
    int level;                       /* 1 or 2 */
} irrvol_sample_info;

/* Self-occlusion of a dynamic mesh (thesis 6.1.3): for each vertex, the
   cosine-weighted fraction of the hemisphere around its normal that the mesh
   itself leaves open. */
typedef struct irrvol_visibility_desc {
    const float *positions;          /* xyz per vertex */
    size_t position_stride;          /* 0 = 3 floats */
    uint32_t vertex_count;
    const uint32_t *indices;         /* 3 per triangle */
    uint32_t triangle_count;
    const float *normals;            /* optional xyz per vertex; NULL = area-weighted face normals */
    size_t normal_stride;            /* 0 = 3 floats */
    uint32_t rays;                   /* per vertex, rounded up to a square; 0 = 64 */
    float ray_offset;                /* rays start this far along the normal; 0 = 1e-4 * diagonal */
    float max_distance;              /* farther occluders do not count; 0 = unlimited */
    uint64_t seed;
    irrvol_allocator allocator;
    void (*parallel_for)(void *user, irrvol_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    int (*progress)(void *user, uint64_t done, uint64_t total); /* vertices; non-zero cancels */
    void *progress_user;
    void (*log)(void *user, const char *message);
    void *log_user;
} irrvol_visibility_desc;

IRRVOL_API irrvol_result irrvol_build(const irrvol_desc *desc, irrvol **out);
IRRVOL_API void irrvol_destroy(irrvol *vol);
IRRVOL_API irrvol_result irrvol_info(const irrvol *vol, irrvol_volume_info *info);

IRRVOL_API void irrvol_query(const irrvol *vol, const float pos[3], const float dir[3], float rgb[3]);
IRRVOL_API void irrvol_query_filter(const irrvol *vol, irrvol_filter filter, const float pos[3],
                                    const float dir[3], float rgb[3]);
IRRVOL_API void irrvol_query_glossy(const irrvol *vol, const float pos[3], const float normal[3],
                                    const float to_eye[3], float rgb[3]);
IRRVOL_API void irrvol_query_many(const irrvol *vol, irrvol_filter filter, uint32_t count,
                                  const float *pos, size_t pos_stride, const float *dir,
                                  size_t dir_stride, float *rgb);

IRRVOL_API irrvol_result irrvol_sample(const irrvol *vol, uint32_t index, irrvol_sample_info *info);
IRRVOL_API irrvol_result irrvol_sample_values(const irrvol *vol, uint32_t index, float *irradiance,
                                              float *radiance);
IRRVOL_API void irrvol_bin_direction(const irrvol *vol, uint32_t bin, float dir[3]);
IRRVOL_API uint32_t irrvol_direction_bin(const irrvol *vol, const float dir[3]);

IRRVOL_API irrvol_result irrvol_visibility_ratio(const irrvol_visibility_desc *desc, float *ratio);

IRRVOL_API irrvol_result irrvol_save(const irrvol *vol, irrvol_write_fn write, void *user);
IRRVOL_API irrvol_result irrvol_load(const irrvol_allocator *allocator, irrvol_read_fn read, void *user,
                                     irrvol **out);
IRRVOL_API irrvol_result irrvol_save_to_memory(const irrvol *vol, const irrvol_allocator *allocator,
                                               void **data, size_t *size);
IRRVOL_API irrvol_result irrvol_load_from_memory(const void *data, size_t size,
                                                 const irrvol_allocator *allocator, irrvol **out);
IRRVOL_API void irrvol_free_memory(const irrvol_allocator *allocator, void *data);

IRRVOL_API const char *irrvol_result_string(irrvol_result r);

#ifdef __cplusplus
}
#endif
#endif /* IRRVOL_H */

/* ------------------------------------------------------------------------ */
#if defined(IRRVOL_IMPLEMENTATION) && !defined(IRRVOL_IMPLEMENTATION_INCLUDED)
#define IRRVOL_IMPLEMENTATION_INCLUDED

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#if defined(IRRVOL_MALLOC) != defined(IRRVOL_FREE)
#  error "irrvol.h: define both IRRVOL_MALLOC and IRRVOL_FREE, or neither"
#endif
#ifndef IRRVOL_MALLOC
#  include <stdlib.h>
#  define IRRVOL_MALLOC(size) malloc(size)
#  define IRRVOL_FREE(ptr) free(ptr)
#endif

#ifndef IRRVOL_MAX_RESOLUTION
#define IRRVOL_MAX_RESOLUTION 64
#endif
#ifndef IRRVOL_MAX_GRID_SAMPLES
#define IRRVOL_MAX_GRID_SAMPLES 1024
#endif
#ifndef IRRVOL_MAX_SUBGRID_SAMPLES
#define IRRVOL_MAX_SUBGRID_SAMPLES 33
#endif
#ifndef IRRVOL_MAX_MOMENT
#define IRRVOL_MAX_MOMENT 1024
#endif
#if (IRRVOL_MAX_GRID_SAMPLES) * ((IRRVOL_MAX_SUBGRID_SAMPLES) - 1) >= (1 << 21)
#  error "irrvol.h: the fine lattice must fit 21 bits per axis (grid samples x subgrid cells)"
#endif
#define IRRVOL__MAX_SUPERSAMPLES 16      /* s x s rays per bin */
#define IRRVOL__MAX_WEIGHT_SUBDIVISIONS 16
#define IRRVOL__IMPORTANT_MAX_SIDE 16    /* at most 16 x 16 extra rays per bin */
#define IRRVOL__BATCH_BYTES ((size_t)8 << 20) /* scratch of one batch of sample jobs */

/* The query path is a handful of small functions: force them inline. */
#if defined(__GNUC__) || defined(__clang__)
#  define IRRVOL__HOT static inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#  define IRRVOL__HOT static __forceinline
#else
#  define IRRVOL__HOT static
#endif

/* Prefetching for the pipelined irrvol_query_many; a no-op elsewhere. */
#if defined(__GNUC__) || defined(__clang__)
#  define IRRVOL__PREFETCH(p) __builtin_prefetch(p)
#else
#  define IRRVOL__PREFETCH(p) ((void)(p))
#endif
#define IRRVOL__AHEAD 8   /* queries prepared ahead in irrvol_query_many */

#if defined(__cplusplus)
#  if defined(__GNUC__) || defined(__clang__) || defined(_MSC_VER)
#    define IRRVOL__RESTRICT __restrict
#  else
#    define IRRVOL__RESTRICT
#  endif
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L
#  define IRRVOL__RESTRICT restrict
#else
#  define IRRVOL__RESTRICT
#endif

/* ======================================================================
   1. allocation
   ---------------------------------------------------------------------- */
/* Both callbacks or neither: a lone alloc would leak through IRRVOL_FREE. */
static int irrvol__allocator_valid(const irrvol_allocator *a)
{
    return (a->alloc == NULL) == (a->free == NULL);
}

static void *irrvol__alloc(const irrvol_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    return a->alloc ? a->alloc(size, a->user) : IRRVOL_MALLOC(size);
}

/* count * item bytes, or NULL when the product overflows. */
static void *irrvol__alloc_array(const irrvol_allocator *a, size_t count, size_t item)
{
    if (item && count > SIZE_MAX / item) return NULL;
    return irrvol__alloc(a, count * item);
}

static void irrvol__free(const irrvol_allocator *a, void *p)
{
    if (!p) return;
    if (a->free) a->free(p, a->user);
    else IRRVOL_FREE(p);
}

/* Zero means default: the documented default replaces a zero field. */
#define irrvol__def(v, d) ((v) ? (v) : (d))

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
typedef struct irrvol__vec3 { float x, y, z; } irrvol__vec3;

static irrvol__vec3 irrvol__v3(float x, float y, float z) { irrvol__vec3 r; r.x = x; r.y = y; r.z = z; return r; }
static irrvol__vec3 irrvol__v3_load(const float *p) { return irrvol__v3(p[0], p[1], p[2]); }
static irrvol__vec3 irrvol__add(irrvol__vec3 a, irrvol__vec3 b) { return irrvol__v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static irrvol__vec3 irrvol__sub(irrvol__vec3 a, irrvol__vec3 b) { return irrvol__v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static irrvol__vec3 irrvol__scale(irrvol__vec3 a, float s) { return irrvol__v3(a.x * s, a.y * s, a.z * s); }
static float irrvol__dot(irrvol__vec3 a, irrvol__vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static irrvol__vec3 irrvol__cross(irrvol__vec3 a, irrvol__vec3 b)
{
    return irrvol__v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static float irrvol__length(irrvol__vec3 a) { return sqrtf(irrvol__dot(a, a)); }
static irrvol__vec3 irrvol__normalize(irrvol__vec3 a)
{
    float l = irrvol__length(a);
    return l > 0.0f ? irrvol__scale(a, 1.0f / l) : a;
}
static float irrvol__minf(float a, float b) { return a < b ? a : b; }
static float irrvol__maxf(float a, float b) { return a > b ? a : b; }
static int irrvol__finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

/* An orthonormal basis (t, b, n) around unit n (Duff et al. 2017, branchless). */
static void irrvol__basis(irrvol__vec3 n, irrvol__vec3 *t, irrvol__vec3 *b)
{
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    *t = irrvol__v3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = irrvol__v3(c, s + n.y * n.y * a, -n.y);
}

/* ======================================================================
   3. counter-based random numbers
   A stream is a pure function of (seed, stream id): jobs seed their own
   stream from (desc.seed, job index) and never share state, so results are
   bit-identical for any thread count.
   ---------------------------------------------------------------------- */
typedef struct irrvol__rng { uint64_t state; } irrvol__rng;

/* SplitMix64 finaliser (Steele, Lea, Flood 2014). */
static uint64_t irrvol__mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static irrvol__rng irrvol__rng_stream(uint64_t seed, uint64_t stream)
{
    irrvol__rng r;
    r.state = irrvol__mix64(seed + 0x9E3779B97F4A7C15ull) ^ irrvol__mix64(stream * 0xD1B54A32D192ED03ull + 1u);
    return r;
}

static uint32_t irrvol__rng_u32(irrvol__rng *r)
{
    r->state += 0x9E3779B97F4A7C15ull;
    return (uint32_t)(irrvol__mix64(r->state) >> 32);
}

/* Uniform in [0, 1): 24 random bits, exactly representable. */
static float irrvol__rng_float(irrvol__rng *r)
{
    return (float)(irrvol__rng_u32(r) >> 8) * (1.0f / 16777216.0f);
}

/* ======================================================================
   4. BVH over triangles
   An 8-wide BVH (Embree's BVH8: Wald et al. 2014). Build: a binary tree by
   binned SAH (IRRVOL_BVH_BINS bins over the centroid bounds, all three axes
   binned in one pass; a leaf costs one test per block of four triangles),
   then collapsed into 8-wide nodes by opening, again and again, the child of
   largest surface area. A node keeps its eight child boxes in rows
   (structure of arrays) and a leaf is a run of blocks of four triangles in
   rows, so one SIMD instruction tests four boxes or four triangles. Nodes are
   stored depth first; the blocks hold copies of the vertices, nothing of the
   caller's data is kept. Traversal: nearest child first, every stack entry
   keeps its entry distance so that entries behind a closer hit are dropped;
   the watertight ray/triangle test (Woop, Benthin, Wald 2013); any-hit for
   shadow rays. IRRVOL_BVH_SIMD selects the SSE2 (x86-64) or NEON (AArch64)
   kernels. The scalar kernels do the same float operations lane by lane, are
   always compiled, and find the same hits bit for bit (bvh->simd = 0 selects
   them).
   ---------------------------------------------------------------------- */
#ifndef IRRVOL_BVH_BINS
#define IRRVOL_BVH_BINS 16
#endif
#ifndef IRRVOL_BVH_SIMD
#define IRRVOL_BVH_SIMD 1
#endif
#if IRRVOL_BVH_SIMD && (defined(__SSE2__) || defined(_M_X64) || defined(_M_AMD64))
#define IRRVOL__SSE 1
#include <emmintrin.h>
#elif IRRVOL_BVH_SIMD && defined(__aarch64__) && (defined(__GNUC__) || defined(__clang__))
#define IRRVOL__NEON 1
#include <arm_neon.h>
#endif
#if defined(IRRVOL__SSE) || defined(IRRVOL__NEON)
#define IRRVOL__SIMD 1
#else
#define IRRVOL__SIMD 0
#endif
/* Where the target fuses a * b + c (FMA on x86 with -mfma, every AArch64),
   both kernels fuse it explicitly: a compiler that contracts on its own
   (GCC's -ffp-contract=fast, clang's default) then has nothing left to fuse
   differently in the scalar kernel. Without FMA nothing can be fused. */
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__FMA__) || defined(__aarch64__))
#define IRRVOL__BVH_FMA 1
#if defined(IRRVOL__SSE)
#include <immintrin.h>
#endif
#else
#define IRRVOL__BVH_FMA 0
#endif

#define IRRVOL__BVH_WIDTH 8        /* children per node */
#define IRRVOL__BVH_LEAF_MAX 16    /* triangles per leaf: four blocks */
#define IRRVOL__BVH_NODE_COST 2.0f /* SAH cost of a binary node, in block tests (measured best of 0.5-4) */
#define IRRVOL__BVH_MAX_DEPTH 60   /* deeper nodes split at the median: bounds the stacks */
#define IRRVOL__BVH_MAX_BINARY_DEPTH (IRRVOL__BVH_MAX_DEPTH + 33) /* + 32 halvings of a uint32_t count */
#define IRRVOL__BVH_STACK ((IRRVOL__BVH_WIDTH - 1) * IRRVOL__BVH_MAX_BINARY_DEPTH + IRRVOL__BVH_WIDTH)
#define IRRVOL__BVH_LEAF 0x80000000u /* a leaf's child reference: LEAF | first block << 3 | blocks - 1 */
#define IRRVOL__BVH_MAX_BLOCKS (1u << 28)
#define IRRVOL__BVH_NONE 0xFFFFFFFFu
/* Far plane distances are rounded up by 1 + 2 gamma_3 (Ize 2013): a box that
   the ray touches is never lost to the rounding of three operations. */
#define IRRVOL__BVH_ROUND_UP 1.00000036f

typedef struct irrvol__bvh_node {
    float box[6][IRRVOL__BVH_WIDTH]; /* rows lo x, hi x, lo y, hi y, lo z, hi z; column = child.
                           An unused child has lo = +inf, hi = -inf: no ray enters it */
    uint32_t child[IRRVOL__BVH_WIDTH]; /* inner node index, or a leaf reference (IRRVOL__BVH_LEAF) */
} irrvol__bvh_node;

typedef struct irrvol__bvh_tris {
    float v[9][4];      /* rows x, y, z of vertex 0, of vertex 1, of vertex 2; column = triangle */
    uint32_t id[4];     /* the caller's triangle indices; unused columns repeat the last triangle */
} irrvol__bvh_tris;

typedef struct irrvol__bvh {
    irrvol__bvh_node *nodes;    /* both in one allocation, from a cache line boundary */
    irrvol__bvh_tris *blocks;
    char *memory;
    uint32_t node_count, block_count, tri_count;
    uint32_t root;              /* a node index or a leaf reference; unused when tri_count is 0 */
    uint32_t degenerate_count;  /* zero-area triangles skipped by the build */
    int simd;                   /* 1: the SIMD kernels (when compiled in); 0: the scalar ones */
} irrvol__bvh;

typedef struct irrvol__hit {
    float t;         /* distance along the ray in units of |dir| */
    float u, v;      /* barycentric weights of the triangle's 2nd and 3rd vertex */
    uint32_t tri;    /* the caller's triangle index; IRRVOL__NO_HIT when missed */
} irrvol__hit;
#define IRRVOL__NO_HIT 0xFFFFFFFFu

/* Caller's triangle soup: positions with a byte stride, 3 indices per triangle. */
typedef struct irrvol__mesh_view {
    const float *positions;
    size_t stride;             /* bytes between vertices; 0 = 3 floats */
    const uint32_t *indices;
    uint32_t tri_count;
} irrvol__mesh_view;

static const float *irrvol__vertex(const irrvol__mesh_view *m, uint32_t v)
{
    size_t stride = m->stride ? m->stride : 3 * sizeof(float);
    return (const float *)((const char *)m->positions + (size_t)v * stride);
}

typedef struct irrvol__bvh_ref {   /* build-time record of one triangle */
    float lo[3], hi[3], c[3];
    uint32_t tri;
} irrvol__bvh_ref;

typedef struct irrvol__bvh_bnode { /* build-time binary node, flattened depth first */
    float lo[3];
    uint32_t first;  /* leaf: first ref; inner: index of the right child (the left is next) */
    float hi[3];
    uint32_t count;  /* leaf: ref count (> 0); inner: 0 */
} irrvol__bvh_bnode;

typedef struct irrvol__bvh_bin { float lo[3], hi[3]; uint32_t count; } irrvol__bvh_bin;

static void irrvol__box_empty(float lo[3], float hi[3])
{
    lo[0] = lo[1] = lo[2] = FLT_MAX;
    hi[0] = hi[1] = hi[2] = -FLT_MAX;
}
static void irrvol__box_grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        lo[k] = irrvol__minf(lo[k], plo[k]);
        hi[k] = irrvol__maxf(hi[k], phi[k]);
    }
}
static float irrvol__box_area(const float lo[3], const float hi[3])
{
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    if (dx < 0.0f) return 0.0f;
    return dx * dy + dy * dz + dz * dx;
}

static uint32_t irrvol__bvh_blocks(uint32_t n) { return (n + 3) / 4; }

/* The bin of a centroid coordinate. */
static int irrvol__bvh_bin_of(float c, float lo, float scale)
{
    float f = (c - lo) * scale;   /* NaN or inf when a denormal extent overflows scale */
    return f >= (float)(IRRVOL_BVH_BINS - 1) ? IRRVOL_BVH_BINS - 1 : f > 0.0f ? (int)f : 0;
}

/* Chooses the binned-SAH split of refs[0..n) (node box lo..hi, centroid box
   clo..chi): returns 0 when a leaf is cheaper or no axis can split, else the
   axis in *axis and the first bin of the right side in *split_bin. */
static int irrvol__bvh_find_split(const irrvol__bvh_ref *refs, uint32_t n, const float lo[3], const float hi[3],
                                  const float clo[3], const float chi[3], int *axis, int *split_bin)
{
    irrvol__bvh_bin bins[3][IRRVOL_BVH_BINS];
    float scale[3], right_area[IRRVOL_BVH_BINS], best = FLT_MAX;
    float leaf_cost = (float)irrvol__bvh_blocks(n), inv_area = 1.0f / irrvol__box_area(lo, hi);
    uint32_t right_count[IRRVOL_BVH_BINS], i;
    int k, b, found = 0;
    for (k = 0; k < 3; k++) {
        scale[k] = chi[k] > clo[k] ? (float)IRRVOL_BVH_BINS / (chi[k] - clo[k]) : 0.0f;
        for (b = 0; b < IRRVOL_BVH_BINS; b++) { irrvol__box_empty(bins[k][b].lo, bins[k][b].hi); bins[k][b].count = 0; }
    }
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) {
            irrvol__bvh_bin *bin = &bins[k][irrvol__bvh_bin_of(refs[i].c[k], clo[k], scale[k])];
            bin->count++;
            irrvol__box_grow(bin->lo, bin->hi, refs[i].lo, refs[i].hi);
        }
    for (k = 0; k < 3; k++) {
        float blo[3], bhi[3];
        uint32_t count = 0;
        if (scale[k] == 0.0f) continue;   /* all centroids in one plane across k */
        /* sweep from the right, then from the left evaluating each boundary */
        irrvol__box_empty(blo, bhi);
        for (b = IRRVOL_BVH_BINS - 1; b > 0; b--) {
            irrvol__box_grow(blo, bhi, bins[k][b].lo, bins[k][b].hi);
            count += bins[k][b].count;
            right_area[b] = irrvol__box_area(blo, bhi);
            right_count[b] = count;
        }
        irrvol__box_empty(blo, bhi);
        count = 0;
        for (b = 1; b < IRRVOL_BVH_BINS; b++) {
            float cost;
            irrvol__box_grow(blo, bhi, bins[k][b - 1].lo, bins[k][b - 1].hi);
            count += bins[k][b - 1].count;
            if (count == 0 || right_count[b] == 0) continue;
            cost = IRRVOL__BVH_NODE_COST + (irrvol__box_area(blo, bhi) * (float)irrvol__bvh_blocks(count) +
                                            right_area[b] * (float)irrvol__bvh_blocks(right_count[b])) * inv_area;
            if (cost < best) { best = cost; *axis = k; *split_bin = b; found = 1; }
        }
    }
    return found && (best < leaf_cost || n > IRRVOL__BVH_LEAF_MAX);
}

/* Splits refs[0..n) in two: by the SAH when it pays, else (coincident
   centroids, the depth cap) by count. Returns the size of the left part, 0
   when the refs should stay a leaf. */
static uint32_t irrvol__bvh_partition(irrvol__bvh_ref *refs, uint32_t n, const float lo[3], const float hi[3],
                                      const float clo[3], const float chi[3], uint32_t depth)
{
    int axis = 0, split_bin = 0;
    uint32_t i, j;
    if (depth < IRRVOL__BVH_MAX_DEPTH && irrvol__bvh_find_split(refs, n, lo, hi, clo, chi, &axis, &split_bin)) {
        float scale = (float)IRRVOL_BVH_BINS / (chi[axis] - clo[axis]);
        for (i = 0, j = n; i < j;) {
            if (irrvol__bvh_bin_of(refs[i].c[axis], clo[axis], scale) < split_bin) i++;
            else { irrvol__bvh_ref t = refs[i]; refs[i] = refs[--j]; refs[j] = t; }
        }
        return i;   /* both sides hold refs: the split's bins are not empty */
    }
    return n <= IRRVOL__BVH_LEAF_MAX ? 0 : n / 2;
}

/* Bounds of every non-degenerate triangle; counts the degenerate ones. The
   area test runs in double: a tiny triangle (a scene at scale 1e-12) is not
   zero because its float cross product underflows. */
static uint32_t irrvol__bvh_collect(irrvol__bvh *bvh, const irrvol__mesh_view *m, irrvol__bvh_ref *refs)
{
    uint32_t i, n = 0;
    for (i = 0; i < m->tri_count; i++) {
        const float *p0 = irrvol__vertex(m, m->indices[3 * i + 0]);
        const float *p1 = irrvol__vertex(m, m->indices[3 * i + 1]);
        const float *p2 = irrvol__vertex(m, m->indices[3 * i + 2]);
        double e1[3], e2[3], cx, cy, cz;
        int k;
        for (k = 0; k < 3; k++) {
            e1[k] = (double)p1[k] - p0[k];
            e2[k] = (double)p2[k] - p0[k];
        }
        cx = e1[1] * e2[2] - e1[2] * e2[1];
        cy = e1[2] * e2[0] - e1[0] * e2[2];
        cz = e1[0] * e2[1] - e1[1] * e2[0];
        if (cx == 0.0 && cy == 0.0 && cz == 0.0) { bvh->degenerate_count++; continue; }
        for (k = 0; k < 3; k++) {
            refs[n].lo[k] = irrvol__minf(p0[k], irrvol__minf(p1[k], p2[k]));
            refs[n].hi[k] = irrvol__maxf(p0[k], irrvol__maxf(p1[k], p2[k]));
            refs[n].c[k] = 0.5f * (refs[n].lo[k] + refs[n].hi[k]);
        }
        refs[n].tri = i;
        n++;
    }
    return n;
}

typedef struct irrvol__bvh_task {
    uint32_t parent, begin, end, depth;
    int is_right;    /* the parent learns a right child's index when it is popped */
} irrvol__bvh_task;

/* The binary tree over refs[0..n) (n > 0) into bn (room for 2n - 1 nodes).
   Returns the node count; *blocks receives the leaves' block count. */
static uint32_t irrvol__bvh_build_binary(irrvol__bvh_bnode *bn, irrvol__bvh_ref *refs, uint32_t n, uint32_t *blocks)
{
    irrvol__bvh_task stack[IRRVOL__BVH_MAX_BINARY_DEPTH + 1];
    uint32_t top = 0, count = 0, i;
    *blocks = 0;
    stack[top].parent = 0; stack[top].begin = 0; stack[top].end = n;
    stack[top].depth = 0; stack[top].is_right = 0; top++;
    while (top) {
        irrvol__bvh_task t = stack[--top];
        uint32_t index = count++, mid;
        irrvol__bvh_bnode *node = &bn[index];
        float clo[3], chi[3];
        if (t.is_right) bn[t.parent].first = index;
        irrvol__box_empty(node->lo, node->hi);
        irrvol__box_empty(clo, chi);
        for (i = t.begin; i < t.end; i++) {
            irrvol__box_grow(node->lo, node->hi, refs[i].lo, refs[i].hi);
            irrvol__box_grow(clo, chi, refs[i].c, refs[i].c);
        }
        mid = t.end - t.begin < 2 ? 0 : irrvol__bvh_partition(refs + t.begin, t.end - t.begin, node->lo, node->hi, clo, chi, t.depth);
        if (mid == 0) {
            node->first = t.begin;
            node->count = t.end - t.begin;
            *blocks += irrvol__bvh_blocks(node->count);
            continue;
        }
        node->count = 0;
        /* right pushed first so the left child is popped next: left = index + 1 */
        stack[top].parent = index; stack[top].begin = t.begin + mid; stack[top].end = t.end;
        stack[top].depth = t.depth + 1; stack[top].is_right = 1; top++;
        stack[top].parent = index; stack[top].begin = t.begin; stack[top].end = t.begin + mid;
        stack[top].depth = t.depth + 1; stack[top].is_right = 0; top++;
    }
    return count;
}

/* The children of the wide node made from binary node i: i's two children,
   then again and again the inner one of largest area replaced by its two. */
static int irrvol__bvh_open(const irrvol__bvh_bnode *bn, uint32_t i, uint32_t kids[IRRVOL__BVH_WIDTH])
{
    int k = 2;
    kids[0] = i + 1;
    kids[1] = bn[i].first;
    while (k < IRRVOL__BVH_WIDTH) {
        int j, best = -1;
        float best_area = -1.0f;
        for (j = 0; j < k; j++) {
            float area = irrvol__box_area(bn[kids[j]].lo, bn[kids[j]].hi);
            if (bn[kids[j]].count == 0 && area > best_area) { best_area = area; best = j; }
        }
        if (best < 0) break;
        kids[k++] = bn[kids[best]].first;
        kids[best] = kids[best] + 1;
    }
    return k;
}

/* A leaf's triangles into blocks of four from bvh->blocks[first]. */
static void irrvol__bvh_store_leaf(irrvol__bvh *bvh, const irrvol__mesh_view *m, const irrvol__bvh_ref *refs,
                                   uint32_t count, uint32_t first)
{
    uint32_t i;
    for (i = 0; i < 4 * irrvol__bvh_blocks(count); i++) {
        irrvol__bvh_tris *b = &bvh->blocks[first + i / 4];
        uint32_t tri = refs[i < count ? i : count - 1].tri;
        int j, k;
        for (j = 0; j < 3; j++) {
            const float *p = irrvol__vertex(m, m->indices[3 * (size_t)tri + (uint32_t)j]);
            for (k = 0; k < 3; k++) b->v[3 * j + k][i % 4] = p[k];
        }
        b->id[i % 4] = tri;
    }
}

typedef struct irrvol__bvh_place { uint32_t bnode, parent, slot; } irrvol__bvh_place;

/* Collapses the binary tree into 4-wide nodes, depth first. With
   bvh->nodes NULL it only counts them (into bvh->node_count). */
static void irrvol__bvh_collapse(irrvol__bvh *bvh, const irrvol__bvh_bnode *bn, const irrvol__bvh_ref *refs,
                                 const irrvol__mesh_view *m)
{
    irrvol__bvh_place stack[IRRVOL__BVH_STACK];
    uint32_t top = 0, nodes = 0, blocks = 0;
    stack[top].bnode = 0; stack[top].parent = IRRVOL__BVH_NONE; stack[top].slot = 0; top++;
    while (top) {
        irrvol__bvh_place p = stack[--top];
        const irrvol__bvh_bnode *b = &bn[p.bnode];
        uint32_t ref;
        if (b->count) {
            ref = IRRVOL__BVH_LEAF | blocks << 3 | (irrvol__bvh_blocks(b->count) - 1);
            if (bvh->nodes) irrvol__bvh_store_leaf(bvh, m, refs + b->first, b->count, blocks);
            blocks += irrvol__bvh_blocks(b->count);
        } else {
            uint32_t kids[IRRVOL__BVH_WIDTH];
            int k = irrvol__bvh_open(bn, p.bnode, kids), j, r;
            ref = nodes++;
            if (bvh->nodes) {
                irrvol__bvh_node *node = &bvh->nodes[ref];
                for (j = 0; j < IRRVOL__BVH_WIDTH; j++) {
                    for (r = 0; r < 3; r++) {
                        node->box[2 * r][j] = j < k ? bn[kids[j]].lo[r] : INFINITY;
                        node->box[2 * r + 1][j] = j < k ? bn[kids[j]].hi[r] : -INFINITY;
                    }
                    node->child[j] = 0;
                }
            }
            for (j = k - 1; j >= 0; j--) {   /* the first child is placed next */
                stack[top].bnode = kids[j]; stack[top].parent = ref; stack[top].slot = (uint32_t)j; top++;
            }
        }
        if (!bvh->nodes) continue;
        if (p.parent == IRRVOL__BVH_NONE) bvh->root = ref;
        else bvh->nodes[p.parent].child[p.slot] = ref;
    }
    bvh->node_count = nodes;
}

/* Builds the BVH of m's non-degenerate triangles. Indices must be in range and
   coordinates finite (validate first). Returns 0, or -1 when out of memory. */
static int irrvol__bvh_build(irrvol__bvh *bvh, const irrvol__mesh_view *m, const irrvol_allocator *a)
{
    irrvol__bvh_ref *refs;
    irrvol__bvh_bnode *bn = NULL;
    uint32_t n;
    memset(bvh, 0, sizeof *bvh);
    bvh->simd = IRRVOL__SIMD;
    refs = (irrvol__bvh_ref *)irrvol__alloc_array(a, m->tri_count, sizeof *refs);
    if (!refs) return -1;
    n = irrvol__bvh_collect(bvh, m, refs);
    if (n) bn = (irrvol__bvh_bnode *)irrvol__alloc_array(a, 2 * (size_t)n - 1, sizeof *bn);
    if (n && bn) {
        irrvol__bvh_build_binary(bn, refs, n, &bvh->block_count);
        irrvol__bvh_collapse(bvh, bn, refs, m);   /* counts the nodes */
        if (bvh->block_count <= IRRVOL__BVH_MAX_BLOCKS) {
            size_t nb = (size_t)bvh->node_count * sizeof *bvh->nodes, bb = (size_t)bvh->block_count * sizeof *bvh->blocks;
            bvh->memory = (char *)irrvol__alloc(a, nb + bb + 64);
            if (bvh->memory) {   /* nodes and blocks from a cache line boundary */
                char *p = bvh->memory + (64 - (size_t)((uintptr_t)bvh->memory % 64)) % 64;
                bvh->nodes = (irrvol__bvh_node *)(void *)p;
                bvh->blocks = (irrvol__bvh_tris *)(void *)(p + nb);
            }
        }
        if (bvh->nodes && bvh->blocks) irrvol__bvh_collapse(bvh, bn, refs, m);
    }
    irrvol__free(a, refs);
    irrvol__free(a, bn);
    if (n && (!bvh->nodes || !bvh->blocks)) {
        irrvol__free(a, bvh->memory);
        memset(bvh, 0, sizeof *bvh);
        return -1;
    }
    bvh->tri_count = n;   /* 0: an empty tree, every ray misses */
    return 0;
}

static void irrvol__bvh_free(irrvol__bvh *bvh, const irrvol_allocator *a)
{
    irrvol__free(a, bvh->memory);
    memset(bvh, 0, sizeof *bvh);
}

/* Four floats, and a mask of four lanes, for the SIMD kernels. */
#if defined(IRRVOL__SSE)
typedef __m128 irrvol__f4;
typedef __m128 irrvol__m4;
static irrvol__f4 irrvol__f4_load(const float *p) { return _mm_loadu_ps(p); }
static void irrvol__f4_store(float *p, irrvol__f4 a) { _mm_storeu_ps(p, a); }
static irrvol__f4 irrvol__f4_set(float x) { return _mm_set1_ps(x); }
static irrvol__f4 irrvol__f4_add(irrvol__f4 a, irrvol__f4 b) { return _mm_add_ps(a, b); }
static irrvol__f4 irrvol__f4_sub(irrvol__f4 a, irrvol__f4 b) { return _mm_sub_ps(a, b); }
static irrvol__f4 irrvol__f4_mul(irrvol__f4 a, irrvol__f4 b) { return _mm_mul_ps(a, b); }
static irrvol__f4 irrvol__f4_div(irrvol__f4 a, irrvol__f4 b) { return _mm_div_ps(a, b); }
#if IRRVOL__BVH_FMA
static irrvol__f4 irrvol__f4_madd(irrvol__f4 a, irrvol__f4 b, irrvol__f4 c) { return _mm_fmadd_ps(a, b, c); }
static irrvol__f4 irrvol__f4_det2(irrvol__f4 a, irrvol__f4 b, irrvol__f4 c, irrvol__f4 d)
{
    irrvol__f4 w = _mm_mul_ps(c, d);
    return _mm_sub_ps(_mm_fmsub_ps(a, b, w), _mm_fmsub_ps(c, d, w));
}
#else
static irrvol__f4 irrvol__f4_madd(irrvol__f4 a, irrvol__f4 b, irrvol__f4 c) { return _mm_add_ps(_mm_mul_ps(a, b), c); }
static irrvol__f4 irrvol__f4_det2(irrvol__f4 a, irrvol__f4 b, irrvol__f4 c, irrvol__f4 d)
{
    return _mm_sub_ps(_mm_mul_ps(a, b), _mm_mul_ps(c, d));
}
#endif
static irrvol__f4 irrvol__f4_min(irrvol__f4 a, irrvol__f4 b) { return _mm_min_ps(a, b); }  /* a < b ? a : b */
static irrvol__f4 irrvol__f4_max(irrvol__f4 a, irrvol__f4 b) { return _mm_max_ps(a, b); }  /* a > b ? a : b */
static irrvol__m4 irrvol__f4_lt(irrvol__f4 a, irrvol__f4 b) { return _mm_cmplt_ps(a, b); }
static irrvol__m4 irrvol__f4_le(irrvol__f4 a, irrvol__f4 b) { return _mm_cmple_ps(a, b); }
static irrvol__m4 irrvol__f4_eq(irrvol__f4 a, irrvol__f4 b) { return _mm_cmpeq_ps(a, b); }
static irrvol__m4 irrvol__m4_and(irrvol__m4 a, irrvol__m4 b) { return _mm_and_ps(a, b); }
static irrvol__m4 irrvol__m4_or(irrvol__m4 a, irrvol__m4 b) { return _mm_or_ps(a, b); }
static irrvol__m4 irrvol__m4_andnot(irrvol__m4 a, irrvol__m4 b) { return _mm_andnot_ps(a, b); } /* ~a & b */
static unsigned irrvol__m4_bits(irrvol__m4 a) { return (unsigned)_mm_movemask_ps(a); }
#elif defined(IRRVOL__NEON)
typedef float32x4_t irrvol__f4;
typedef uint32x4_t irrvol__m4;
static irrvol__f4 irrvol__f4_load(const float *p) { return vld1q_f32(p); }
static void irrvol__f4_store(float *p, irrvol__f4 a) { vst1q_f32(p, a); }
static irrvol__f4 irrvol__f4_set(float x) { return vdupq_n_f32(x); }
static irrvol__f4 irrvol__f4_add(irrvol__f4 a, irrvol__f4 b) { return vaddq_f32(a, b); }
static irrvol__f4 irrvol__f4_sub(irrvol__f4 a, irrvol__f4 b) { return vsubq_f32(a, b); }
static irrvol__f4 irrvol__f4_mul(irrvol__f4 a, irrvol__f4 b) { return vmulq_f32(a, b); }
static irrvol__f4 irrvol__f4_div(irrvol__f4 a, irrvol__f4 b) { return vdivq_f32(a, b); }
static irrvol__f4 irrvol__f4_madd(irrvol__f4 a, irrvol__f4 b, irrvol__f4 c) { return vfmaq_f32(c, a, b); }
static irrvol__f4 irrvol__f4_det2(irrvol__f4 a, irrvol__f4 b, irrvol__f4 c, irrvol__f4 d)   /* Kahan, as the scalar */
{
    irrvol__f4 w = vmulq_f32(c, d), nw = vnegq_f32(w);
    return vsubq_f32(vfmaq_f32(nw, a, b), vfmaq_f32(nw, c, d));
}
/* compare and select: the scalar kernels' a < b ? a : b, NaN included (vminq_f32 differs) */
static irrvol__f4 irrvol__f4_min(irrvol__f4 a, irrvol__f4 b) { return vbslq_f32(vcltq_f32(a, b), a, b); }
static irrvol__f4 irrvol__f4_max(irrvol__f4 a, irrvol__f4 b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
static irrvol__m4 irrvol__f4_lt(irrvol__f4 a, irrvol__f4 b) { return vcltq_f32(a, b); }
static irrvol__m4 irrvol__f4_le(irrvol__f4 a, irrvol__f4 b) { return vcleq_f32(a, b); }
static irrvol__m4 irrvol__f4_eq(irrvol__f4 a, irrvol__f4 b) { return vceqq_f32(a, b); }
static irrvol__m4 irrvol__m4_and(irrvol__m4 a, irrvol__m4 b) { return vandq_u32(a, b); }
static irrvol__m4 irrvol__m4_or(irrvol__m4 a, irrvol__m4 b) { return vorrq_u32(a, b); }
static irrvol__m4 irrvol__m4_andnot(irrvol__m4 a, irrvol__m4 b) { return vbicq_u32(b, a); } /* ~a & b */
static unsigned irrvol__m4_bits(irrvol__m4 a)
{
    static const uint32_t weight[4] = {1, 2, 4, 8};
    return vaddvq_u32(vandq_u32(a, vld1q_u32(weight)));
}
#endif

/* a * b + c, fused where IRRVOL__BVH_FMA (the shear and the distance). */
static float irrvol__bvh_madd(float a, float b, float c)
{
#if IRRVOL__BVH_FMA
    return fmaf(a, b, c);
#else
    return a * b + c;
#endif
}

/* Per-ray constants of the watertight test and of the slab test. */
typedef struct irrvol__ray {
    float org[3], dir[3], inv[3];
    int kx, ky, kz;          /* dir[kz] has the largest magnitude */
    float sx, sy, sz;        /* shear that maps dir to +z */
    float nsx, nsy;          /* -sx, -sy */
    int near[3];             /* box row offset (in floats) of the entry plane per axis; far = near ^ WIDTH */
#if IRRVOL__SIMD
    irrvol__f4 org4[3], inv4[3], nsx4, nsy4, sz4;
#endif
} irrvol__ray;

static void irrvol__ray_setup(irrvol__ray *r, const float org[3], const float dir[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        /* a zero component would give 0 * inf = NaN in the slab test */
        float d = dir[k];
        if (fabsf(d) < 1e-30f) d = d < 0.0f ? -1e-30f : 1e-30f;
        r->org[k] = org[k];
        r->dir[k] = dir[k];
        r->inv[k] = 1.0f / d;
        r->near[k] = 2 * IRRVOL__BVH_WIDTH * k + (r->inv[k] < 0.0f ? IRRVOL__BVH_WIDTH : 0);
    }
    r->kz = fabsf(dir[0]) > fabsf(dir[1]) ? (fabsf(dir[0]) > fabsf(dir[2]) ? 0 : 2)
                                          : (fabsf(dir[1]) > fabsf(dir[2]) ? 1 : 2);
    r->kx = (r->kz + 1) % 3;
    r->ky = (r->kx + 1) % 3;
    if (dir[r->kz] < 0.0f) { int t = r->kx; r->kx = r->ky; r->ky = t; } /* keep winding */
    r->sx = dir[r->kx] / dir[r->kz];
    r->sy = dir[r->ky] / dir[r->kz];
    r->sz = 1.0f / dir[r->kz];
    r->nsx = -r->sx;
    r->nsy = -r->sy;
#if IRRVOL__SIMD
    for (k = 0; k < 3; k++) {
        r->org4[k] = irrvol__f4_set(r->org[k]);
        r->inv4[k] = irrvol__f4_set(r->inv[k]);
    }
    r->nsx4 = irrvol__f4_set(r->nsx);
    r->nsy4 = irrvol__f4_set(r->nsy);
    r->sz4 = irrvol__f4_set(r->sz);
#endif
}

/* Entry distances t[i] of the ray into a node's child boxes, clipped to
   [tmin, tmax]; returns the mask of the children it enters. */
static unsigned irrvol__node_hits_scalar(const irrvol__ray *r, const irrvol__bvh_node *n, float tmin, float tmax,
                                         float t[IRRVOL__BVH_WIDTH])
{
    const float *box = n->box[0];
    unsigned mask = 0;
    int i;
    for (i = 0; i < IRRVOL__BVH_WIDTH; i++) {
        float nx = (box[r->near[0] + i] - r->org[0]) * r->inv[0];
        float ny = (box[r->near[1] + i] - r->org[1]) * r->inv[1];
        float nz = (box[r->near[2] + i] - r->org[2]) * r->inv[2];
        float fx = (box[(r->near[0] ^ IRRVOL__BVH_WIDTH) + i] - r->org[0]) * r->inv[0];
        float fy = (box[(r->near[1] ^ IRRVOL__BVH_WIDTH) + i] - r->org[1]) * r->inv[1];
        float fz = (box[(r->near[2] ^ IRRVOL__BVH_WIDTH) + i] - r->org[2]) * r->inv[2];
        float tn = irrvol__maxf(irrvol__maxf(nx, ny), irrvol__maxf(nz, tmin));
        float tf = irrvol__minf(irrvol__minf(fx, fy), irrvol__minf(fz, tmax)) * IRRVOL__BVH_ROUND_UP;
        t[i] = tn;
        if (tn <= tf) mask |= 1u << i;
    }
    return mask;
}

/* An edge function a * b - c * d. With FMA, Kahan's algorithm: within two
   ulp of the exact value, so its sign is exact. Without, the two rounded
   products: the sign is exact or the value zero (Woop et al.), and a zero
   is computed again exactly in double by irrvol__bvh_edges_double. */
static float irrvol__bvh_det2(float a, float b, float c, float d)
{
#if IRRVOL__BVH_FMA
    float w = c * d;
    return fmaf(a, b, -w) - fmaf(c, d, -w);
#else
    return a * b - c * d;
#endif
}

/* The edge functions u, v, w exactly (products of floats are exact in
   double) and rounded once. */
static void irrvol__bvh_edges_double(float ax, float ay, float bx, float by, float cx, float cy, float e[3])
{
    e[0] = (float)((double)cx * by - (double)cy * bx);
    e[1] = (float)((double)ax * cy - (double)ay * cx);
    e[2] = (float)((double)bx * ay - (double)by * ax);
}

/* Watertight ray/triangle test (Woop, Benthin, Wald 2013): edge functions in
   a sheared space where the ray is the +z axis; an edge shared by two
   triangles is never missed by both. Updates *hit when closer than hit->t;
   returns 1 then. */
static int irrvol__leaf_hit_scalar(const irrvol__ray *r, const irrvol__bvh_tris *b, float tmin, irrvol__hit *hit)
{
    int i, found = 0;
    for (i = 0; i < 4; i++) {
        float ax = b->v[r->kx][i] - r->org[r->kx], ay = b->v[r->ky][i] - r->org[r->ky], az = b->v[r->kz][i] - r->org[r->kz];
        float bx = b->v[3 + r->kx][i] - r->org[r->kx], by = b->v[3 + r->ky][i] - r->org[r->ky], bz = b->v[3 + r->kz][i] - r->org[r->kz];
        float cx = b->v[6 + r->kx][i] - r->org[r->kx], cy = b->v[6 + r->ky][i] - r->org[r->ky], cz = b->v[6 + r->kz][i] - r->org[r->kz];
        float u, v, w, det, inv_det, t;
        ax = irrvol__bvh_madd(r->nsx, az, ax); ay = irrvol__bvh_madd(r->nsy, az, ay);
        bx = irrvol__bvh_madd(r->nsx, bz, bx); by = irrvol__bvh_madd(r->nsy, bz, by);
        cx = irrvol__bvh_madd(r->nsx, cz, cx); cy = irrvol__bvh_madd(r->nsy, cz, cy);
        u = irrvol__bvh_det2(cx, by, cy, bx);
        v = irrvol__bvh_det2(ax, cy, ay, cx);
        w = irrvol__bvh_det2(bx, ay, by, ax);
        if (!IRRVOL__BVH_FMA && (u == 0.0f || v == 0.0f || w == 0.0f)) {
            float e[3];
            irrvol__bvh_edges_double(ax, ay, bx, by, cx, cy, e);
            u = e[0]; v = e[1]; w = e[2];
        }
        if ((u < 0.0f || v < 0.0f || w < 0.0f) && (0.0f < u || 0.0f < v || 0.0f < w)) continue;
        det = u + v + w;
        if (det == 0.0f) continue;
        inv_det = 1.0f / det;
        u = u * inv_det; v = v * inv_det; w = w * inv_det;   /* barycentrics first: u * az underflows at 1e-13 m */
        t = irrvol__bvh_madd(u, az, irrvol__bvh_madd(v, bz, w * cz)) * r->sz;
        if (!(tmin < t && t < hit->t)) continue;
        hit->t = t;
        hit->u = v;
        hit->v = w;
        hit->tri = b->id[i];
        found = 1;
    }
    return found;
}

#if IRRVOL__SIMD
/* irrvol__node_hits_scalar four lanes at a time. */
static unsigned irrvol__node_hits_simd(const irrvol__ray *r, const irrvol__bvh_node *n, float tmin, float tmax,
                                       float t[IRRVOL__BVH_WIDTH])
{
    const irrvol__f4 lo = irrvol__f4_set(tmin), hi = irrvol__f4_set(tmax), up = irrvol__f4_set(IRRVOL__BVH_ROUND_UP);
    unsigned mask = 0;
    int i;
    for (i = 0; i < IRRVOL__BVH_WIDTH; i += 4) {
        const float *box = n->box[0] + i;
        irrvol__f4 nx = irrvol__f4_mul(irrvol__f4_sub(irrvol__f4_load(box + r->near[0]), r->org4[0]), r->inv4[0]);
        irrvol__f4 ny = irrvol__f4_mul(irrvol__f4_sub(irrvol__f4_load(box + r->near[1]), r->org4[1]), r->inv4[1]);
        irrvol__f4 nz = irrvol__f4_mul(irrvol__f4_sub(irrvol__f4_load(box + r->near[2]), r->org4[2]), r->inv4[2]);
        irrvol__f4 fx = irrvol__f4_mul(irrvol__f4_sub(irrvol__f4_load(box + (r->near[0] ^ IRRVOL__BVH_WIDTH)), r->org4[0]), r->inv4[0]);
        irrvol__f4 fy = irrvol__f4_mul(irrvol__f4_sub(irrvol__f4_load(box + (r->near[1] ^ IRRVOL__BVH_WIDTH)), r->org4[1]), r->inv4[1]);
        irrvol__f4 fz = irrvol__f4_mul(irrvol__f4_sub(irrvol__f4_load(box + (r->near[2] ^ IRRVOL__BVH_WIDTH)), r->org4[2]), r->inv4[2]);
        irrvol__f4 tn = irrvol__f4_max(irrvol__f4_max(nx, ny), irrvol__f4_max(nz, lo));
        irrvol__f4 tf = irrvol__f4_mul(irrvol__f4_min(irrvol__f4_min(fx, fy), irrvol__f4_min(fz, hi)), up);
        irrvol__f4_store(t + i, tn);
        mask |= irrvol__m4_bits(irrvol__f4_le(tn, tf)) << i;
    }
    return mask;
}

/* irrvol__leaf_hit_scalar on four lanes at once; the closest accepted lane
   (the first of equals, as the scalar loop keeps it) updates *hit. */
static int irrvol__leaf_hit_simd(const irrvol__ray *r, const irrvol__bvh_tris *b, float tmin, irrvol__hit *hit)
{
    const irrvol__f4 zero = irrvol__f4_set(0.0f);
    irrvol__f4 ax = irrvol__f4_sub(irrvol__f4_load(b->v[r->kx]), r->org4[r->kx]);
    irrvol__f4 ay = irrvol__f4_sub(irrvol__f4_load(b->v[r->ky]), r->org4[r->ky]);
    irrvol__f4 az = irrvol__f4_sub(irrvol__f4_load(b->v[r->kz]), r->org4[r->kz]);
    irrvol__f4 bx = irrvol__f4_sub(irrvol__f4_load(b->v[3 + r->kx]), r->org4[r->kx]);
    irrvol__f4 by = irrvol__f4_sub(irrvol__f4_load(b->v[3 + r->ky]), r->org4[r->ky]);
    irrvol__f4 bz = irrvol__f4_sub(irrvol__f4_load(b->v[3 + r->kz]), r->org4[r->kz]);
    irrvol__f4 cx = irrvol__f4_sub(irrvol__f4_load(b->v[6 + r->kx]), r->org4[r->kx]);
    irrvol__f4 cy = irrvol__f4_sub(irrvol__f4_load(b->v[6 + r->ky]), r->org4[r->ky]);
    irrvol__f4 cz = irrvol__f4_sub(irrvol__f4_load(b->v[6 + r->kz]), r->org4[r->kz]);
    irrvol__f4 u, v, w, det, inv_det, t;
    irrvol__m4 ok;
    float tl[4], vl[4], wl[4];
    unsigned mask;
    int i, best;
    ax = irrvol__f4_madd(r->nsx4, az, ax); ay = irrvol__f4_madd(r->nsy4, az, ay);
    bx = irrvol__f4_madd(r->nsx4, bz, bx); by = irrvol__f4_madd(r->nsy4, bz, by);
    cx = irrvol__f4_madd(r->nsx4, cz, cx); cy = irrvol__f4_madd(r->nsy4, cz, cy);
    u = irrvol__f4_det2(cx, by, cy, bx);
    v = irrvol__f4_det2(ax, cy, ay, cx);
    w = irrvol__f4_det2(bx, ay, by, ax);
    if (!IRRVOL__BVH_FMA && irrvol__m4_bits(irrvol__m4_or(irrvol__m4_or(irrvol__f4_eq(u, zero), irrvol__f4_eq(v, zero)),
                                      irrvol__f4_eq(w, zero)))) {
        float e[9][4];   /* the lanes with a zero edge function again in double */
        irrvol__f4_store(e[0], u); irrvol__f4_store(e[1], v); irrvol__f4_store(e[2], w);
        irrvol__f4_store(e[3], ax); irrvol__f4_store(e[4], ay); irrvol__f4_store(e[5], bx);
        irrvol__f4_store(e[6], by); irrvol__f4_store(e[7], cx); irrvol__f4_store(e[8], cy);
        for (i = 0; i < 4; i++) {
            float exact[3];
            if (e[0][i] != 0.0f && e[1][i] != 0.0f && e[2][i] != 0.0f) continue;
            irrvol__bvh_edges_double(e[3][i], e[4][i], e[5][i], e[6][i], e[7][i], e[8][i], exact);
            e[0][i] = exact[0]; e[1][i] = exact[1]; e[2][i] = exact[2];
        }
        u = irrvol__f4_load(e[0]); v = irrvol__f4_load(e[1]); w = irrvol__f4_load(e[2]);
    }
    ok = irrvol__m4_andnot(
        irrvol__m4_and(irrvol__m4_or(irrvol__m4_or(irrvol__f4_lt(u, zero), irrvol__f4_lt(v, zero)), irrvol__f4_lt(w, zero)),
                       irrvol__m4_or(irrvol__m4_or(irrvol__f4_lt(zero, u), irrvol__f4_lt(zero, v)), irrvol__f4_lt(zero, w))),
        irrvol__f4_eq(zero, zero));
    det = irrvol__f4_add(irrvol__f4_add(u, v), w);
    ok = irrvol__m4_andnot(irrvol__f4_eq(det, zero), ok);
    inv_det = irrvol__f4_div(irrvol__f4_set(1.0f), det);
    u = irrvol__f4_mul(u, inv_det); v = irrvol__f4_mul(v, inv_det); w = irrvol__f4_mul(w, inv_det);
    t = irrvol__f4_mul(irrvol__f4_madd(u, az, irrvol__f4_madd(v, bz, irrvol__f4_mul(w, cz))), r->sz4);
    ok = irrvol__m4_and(ok, irrvol__m4_and(irrvol__f4_lt(irrvol__f4_set(tmin), t), irrvol__f4_lt(t, irrvol__f4_set(hit->t))));
    mask = irrvol__m4_bits(ok);
    if (!mask) return 0;
    irrvol__f4_store(tl, t);
    for (best = -1, i = 0; i < 4; i++)
        if ((mask >> i & 1) && (best < 0 || tl[i] < tl[best])) best = i;
    irrvol__f4_store(vl, v); irrvol__f4_store(wl, w);
    hit->t = tl[best];
    hit->u = vl[best];
    hit->v = wl[best];
    hit->tri = b->id[best];
    return 1;
}
#endif

static unsigned irrvol__bvh_node_hits(const irrvol__bvh *bvh, const irrvol__ray *r, const irrvol__bvh_node *n,
                                      float tmin, float tmax, float t[IRRVOL__BVH_WIDTH])
{
#if IRRVOL__SIMD
    if (bvh->simd) return irrvol__node_hits_simd(r, n, tmin, tmax, t);
#endif
    (void)bvh;
    return irrvol__node_hits_scalar(r, n, tmin, tmax, t);
}

static int irrvol__bvh_leaf_hit(const irrvol__bvh *bvh, const irrvol__ray *r, const irrvol__bvh_tris *b, float tmin,
                                irrvol__hit *hit)
{
#if IRRVOL__SIMD
    if (bvh->simd) return irrvol__leaf_hit_simd(r, b, tmin, hit);
#endif
    (void)bvh;
    return irrvol__leaf_hit_scalar(r, b, tmin, hit);
}

typedef struct irrvol__bvh_entry { uint32_t ref; float t; } irrvol__bvh_entry;

/* Index of the lowest set bit of a non-zero mask. */
static uint32_t irrvol__bvh_first_bit(unsigned mask)
{
#if defined(__GNUC__) || defined(__clang__)
    return (uint32_t)__builtin_ctz(mask);
#else
    uint32_t i = 0;
    while (!(mask >> i & 1)) i++;
    return i;
#endif
}

/* Pushes the children in mask, the farthest first, so that they pop nearest
   first (equal distances in child order); returns the nearest, not pushed. */
static uint32_t irrvol__bvh_push_children(const irrvol__bvh_node *n, unsigned mask, const float t[IRRVOL__BVH_WIDTH],
                                          irrvol__bvh_entry *stack, uint32_t *top)
{
    irrvol__bvh_entry e[IRRVOL__BVH_WIDTH];
    uint32_t k = 0, i = irrvol__bvh_first_bit(mask), j, rest = mask & (mask - 1);
    if (!rest) return n->child[i];   /* one child: nothing to push */
    j = irrvol__bvh_first_bit(rest);
    if (!(rest & (rest - 1))) {      /* two children */
        uint32_t near = t[j] < t[i] ? j : i, far = near == i ? j : i;
        stack[*top].ref = n->child[far];
        stack[*top].t = t[far];
        (*top)++;
        return n->child[near];
    }
    for (; mask; mask &= mask - 1) {   /* insertion sort, stable */
        i = irrvol__bvh_first_bit(mask);
        for (j = k++; j > 0 && e[j - 1].t > t[i]; j--) e[j] = e[j - 1];
        e[j].ref = n->child[i];
        e[j].t = t[i];
    }
    while (--k) stack[(*top)++] = e[k];
    return e[0].ref;
}

/* Closest hit in (tmin, hit->t), or with any_hit the first hit found. */
static int irrvol__bvh_traverse(const irrvol__bvh *bvh, const irrvol__ray *r, float tmin, irrvol__hit *hit, int any_hit)
{
    irrvol__bvh_entry stack[IRRVOL__BVH_STACK];
    uint32_t top = 0, ref = bvh->root;
    if (bvh->tri_count == 0) return 0;   /* an empty tree: no root to enter */
    for (;;) {
        if (ref & IRRVOL__BVH_LEAF) {
            uint32_t b = (ref & ~IRRVOL__BVH_LEAF) >> 3, end = b + (ref & 7u) + 1;
            for (; b < end; b++)
                if (irrvol__bvh_leaf_hit(bvh, r, &bvh->blocks[b], tmin, hit) && any_hit) return 1;
        } else {
            float t[IRRVOL__BVH_WIDTH];
            const irrvol__bvh_node *n = &bvh->nodes[ref];
            unsigned mask = irrvol__bvh_node_hits(bvh, r, n, tmin, hit->t, t);
            if (mask) {
                ref = irrvol__bvh_push_children(n, mask, t, stack, &top);
                continue;
            }
        }
        do {   /* entries behind the closest hit are skipped */
            if (!top) return hit->tri != IRRVOL__NO_HIT;
            top--;
        } while (stack[top].t > hit->t * IRRVOL__BVH_ROUND_UP);
        ref = stack[top].ref;
    }
}

/* Closest hit in (tmin, tmax). Returns 1 and fills *hit, else hit->tri = IRRVOL__NO_HIT. */
static int irrvol__bvh_intersect(const irrvol__bvh *bvh, const float org[3], const float dir[3],
                                 float tmin, float tmax, irrvol__hit *hit)
{
    irrvol__ray r;
    irrvol__ray_setup(&r, org, dir);
    hit->t = tmax;
    hit->u = hit->v = 0.0f;
    hit->tri = IRRVOL__NO_HIT;
    return irrvol__bvh_traverse(bvh, &r, tmin, hit, 0);
}

/* Any hit in (tmin, tmax): for shadow rays. */
static int irrvol__bvh_occluded(const irrvol__bvh *bvh, const float org[3], const float dir[3],
                                float tmin, float tmax)
{
    irrvol__ray r;
    irrvol__hit hit;
    irrvol__ray_setup(&r, org, dir);
    hit.t = tmax;
    hit.u = hit.v = 0.0f;
    hit.tri = IRRVOL__NO_HIT;
    return irrvol__bvh_traverse(bvh, &r, tmin, &hit, 1);
}

/* ======================================================================
   5. CRC32 and little-endian byte streams
   A saved object is: magic (8 bytes), format version (u32), payload size
   (u64), payload, CRC32 of everything before it (u32). Values are written
   byte by byte in little-endian order, never as raw structs. A loader treats
   its input as hostile: it checks every count against the declared payload
   size before allocating, and the CRC at the end.
   ---------------------------------------------------------------------- */
/* CRC-32 (IEEE 802.3, reflected, as zlib and PNG). The table is built on the
   stack per stream: 256 entries, cheaper than one page of data. */
typedef struct irrvol__crc { uint32_t table[256]; uint32_t value; } irrvol__crc;

static void irrvol__crc_init(irrvol__crc *c)
{
    uint32_t i, k;
    for (i = 0; i < 256; i++) {
        uint32_t v = i;
        for (k = 0; k < 8; k++) v = (v & 1u) ? 0xEDB88320u ^ (v >> 1) : v >> 1;
        c->table[i] = v;
    }
    c->value = 0xFFFFFFFFu;
}
static void irrvol__crc_add(irrvol__crc *c, const void *bytes, size_t n)
{
    const unsigned char *p = (const unsigned char *)bytes;
    uint32_t v = c->value;
    while (n--) v = c->table[(v ^ *p++) & 0xFFu] ^ (v >> 8);
    c->value = v;
}
static uint32_t irrvol__crc_final(const irrvol__crc *c) { return c->value ^ 0xFFFFFFFFu; }

typedef struct irrvol__writer {
    irrvol_write_fn write;
    void *user;
    irrvol__crc crc;
    int failed;        /* a write callback failed: IRRVOL_ERROR_IO */
} irrvol__writer;

static void irrvol__put(irrvol__writer *w, const void *bytes, size_t n)
{
    if (w->failed || n == 0) return;
    irrvol__crc_add(&w->crc, bytes, n);
    if (w->write(w->user, bytes, n) != 0) w->failed = 1;
}
static void irrvol__put_u32(irrvol__writer *w, uint32_t v)
{
    unsigned char b[4];
    b[0] = (unsigned char)v; b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16); b[3] = (unsigned char)(v >> 24);
    irrvol__put(w, b, 4);
}
static void irrvol__put_u64(irrvol__writer *w, uint64_t v)
{
    irrvol__put_u32(w, (uint32_t)v);
    irrvol__put_u32(w, (uint32_t)(v >> 32));
}
static void irrvol__put_f32(irrvol__writer *w, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    irrvol__put_u32(w, v);
}
/* Little-endian bytes a buffer at a time: one write callback per 4 KiB,
   not per float. */
static void irrvol__put_f32_array(irrvol__writer *w, const float *f, size_t n)
{
    unsigned char buf[4096];
    size_t i = 0;
    while (i < n) {
        size_t m = n - i < sizeof buf / 4 ? n - i : sizeof buf / 4, j;
        for (j = 0; j < m; j++) {
            uint32_t v;
            memcpy(&v, &f[i + j], 4);
            buf[4 * j] = (unsigned char)v; buf[4 * j + 1] = (unsigned char)(v >> 8);
            buf[4 * j + 2] = (unsigned char)(v >> 16); buf[4 * j + 3] = (unsigned char)(v >> 24);
        }
        irrvol__put(w, buf, 4 * m);
        i += m;
    }
}
typedef struct irrvol__reader {
    irrvol_read_fn read;
    void *user;
    irrvol__crc crc;
    uint64_t remaining;  /* payload bytes not yet read, from the header */
    int failed;          /* short read or a size past the payload: corrupt */
} irrvol__reader;

static void irrvol__get(irrvol__reader *r, void *bytes, size_t n)
{
    if (r->failed) { memset(bytes, 0, n); return; }
    if (n > r->remaining || r->read(r->user, bytes, n) != 0) {
        r->failed = 1;
        memset(bytes, 0, n);
        return;
    }
    r->remaining -= n;
    irrvol__crc_add(&r->crc, bytes, n);
}
static uint32_t irrvol__get_u32(irrvol__reader *r)
{
    unsigned char b[4];
    irrvol__get(r, b, 4);
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}
static uint64_t irrvol__get_u64(irrvol__reader *r)
{
    uint64_t lo = irrvol__get_u32(r);
    return lo | ((uint64_t)irrvol__get_u32(r) << 32);
}
static float irrvol__get_f32(irrvol__reader *r)
{
    uint32_t v = irrvol__get_u32(r);
    float f;
    memcpy(&f, &v, 4);
    return f;
}
/* True when count items of item_bytes each can still be in the payload:
   call before allocating anything sized by a count read from the input. */
static int irrvol__can_hold(irrvol__reader *r, uint64_t count, uint64_t item_bytes)
{
    if (item_bytes && count > r->remaining / item_bytes) { r->failed = 1; return 0; }
    return !r->failed;
}

/* Memory-buffer streams behind the public save_to_memory/load_from_memory. */
typedef struct irrvol__membuf {
    unsigned char *data;
    size_t size, capacity, pos;
    const irrvol_allocator *a;
} irrvol__membuf;

static int irrvol__membuf_write(void *user, const void *bytes, size_t n)
{
    irrvol__membuf *m = (irrvol__membuf *)user;
    if (n > m->capacity - m->size) {
        size_t cap = m->capacity ? m->capacity : 4096;
        unsigned char *p;
        while (cap - m->size < n) {
            if (cap > SIZE_MAX / 2) return -1;
            cap *= 2;
        }
        p = (unsigned char *)irrvol__alloc(m->a, cap);
        if (!p) return -1;
        if (m->size) memcpy(p, m->data, m->size);
        irrvol__free(m->a, m->data);
        m->data = p;
        m->capacity = cap;
    }
    memcpy(m->data + m->size, bytes, n);
    m->size += n;
    return 0;
}

static int irrvol__membuf_read(void *user, void *bytes, size_t n)
{
    irrvol__membuf *m = (irrvol__membuf *)user;
    if (n > m->size - m->pos) return -1;
    memcpy(bytes, m->data + m->pos, n);
    m->pos += n;
    return 0;
}

/* ======================================================================
   6. Shirley-Chiu concentric map (Shirley and Chiu 1997)
   Square [0,1]^2 -> unit disk -> hemisphere around +z, preserving area: equal
   squares map to equal solid angles. The inverse used by queries is in
   section 8.
   ---------------------------------------------------------------------- */
#define IRRVOL__PI 3.14159265358979323846

static void irrvol__square_to_disk(float u, float v, float *dx, float *dy)
{
    float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f, r, phi;
    if (a == 0.0f && b == 0.0f) { *dx = *dy = 0.0f; return; }
    if (a * a > b * b) { r = a; phi = (float)(IRRVOL__PI / 4) * (b / a); }
    else { r = b; phi = (float)(IRRVOL__PI / 2) - (float)(IRRVOL__PI / 4) * (a / b); }
    *dx = r * cosf(phi);
    *dy = r * sinf(phi);
}

/* Square -> hemisphere (z >= 0): the disk point lifted by z = 1 - r^2. */
static irrvol__vec3 irrvol__square_to_hemisphere(float u, float v)
{
    float dx, dy, r2, s;
    irrvol__square_to_disk(u, v, &dx, &dy);
    r2 = dx * dx + dy * dy;
    s = sqrtf(irrvol__maxf(0.0f, 2.0f - r2));
    return irrvol__v3(dx * s, dy * s, 1.0f - r2);
}

/* ======================================================================
   7. jobs: the caller's parallel_for, or a serial loop
   ---------------------------------------------------------------------- */
static void irrvol__run_jobs(void (*parallel_for)(void *, irrvol_job_fn, void *, uint32_t), void *user,
                         irrvol_job_fn job, void *ctx, uint32_t count)
{
    uint32_t i;
    if (count == 0) return;
    if (parallel_for) { parallel_for(user, job, ctx, count); return; }
    for (i = 0; i < count; i++) job(ctx, i);
}

/* ======================================================================
   8. fast inverse concentric map for queries
   Direction -> (u, v) on the square of its hemisphere. In the disk, the
   azimuth of the direction is the disk angle and the radius is sqrt(1 - |z|);
   the square coordinate along the minor axis is (4/pi) atan(minor/major),
   evaluated by a polynomial: one sqrt, one division, no atan2, no branch
   the compiler cannot turn into a select.
   ---------------------------------------------------------------------- */
/* atan(t) for |t| <= 1: odd least-squares polynomial of degree 15,
   |error| < 1.6e-7 rad in float. Estrin's scheme: a short dependency chain. */
IRRVOL__HOT float irrvol__atan_unit(float t)
{
    float t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
    float p01 = 0.9999994372f - 0.3333010801f * t2, p23 = 0.1994852321f - 0.1391586880f * t2;
    float p45 = 0.09656416154f - 0.05606523185f * t2, p67 = 0.02194796030f - 0.004073664390f * t2;
    return t * ((p01 + p23 * t4) + (p45 + p67 * t4) * t8);
}

/* Clamp to [0, 1]; NaN gives 0. */
IRRVOL__HOT float irrvol__unit_clamp(float x)
{
    x = x > 0.0f ? x : 0.0f;
    return x < 1.0f ? x : 1.0f;
}

/* Inverse of irrvol__square_to_hemisphere for any non-zero direction (not
   necessarily unit length); hemisphere 1 is z < 0, mirrored. Zero, infinite
   and NaN directions land on a valid square point. The disk radius
   sqrt(1 - |z| / |d|) and the ratio of the minor to the major component are
   independent: two short dependency chains instead of a normalization
   followed by both. */
IRRVOL__HOT void irrvol__direction_to_square(const float dir[3], float *u, float *v, uint32_t *hemisphere)
{
    float x = dir[0], y = dir[1], z = dir[2];
    float len = sqrtf(x * x + y * y + z * z);
    float one_minus_z = len > 0.0f ? 1.0f - fabsf(z) / len : 1.0f;
    float r = sqrtf(one_minus_z > 0.0f ? one_minus_z : 0.0f);   /* disk radius: |z| = 1 - r^2 */
    int xmajor = fabsf(x) >= fabsf(y);
    float num = xmajor ? y : x, den = xmajor ? x : y;
    float t = den != 0.0f ? num / den : 0.0f;                   /* |t| <= 1 */
    float major = den < 0.0f ? -r : r;
    float minor = major * (float)(4.0 / IRRVOL__PI) * irrvol__atan_unit(t);
    *hemisphere = z < 0.0f ? 1u : 0u;
    *u = irrvol__unit_clamp(0.5f * ((xmajor ? major : minor) + 1.0f));
    *v = irrvol__unit_clamp(0.5f * ((xmajor ? minor : major) + 1.0f));
}

/* Bin b's direction through the point (u, v) of its square. */
static irrvol__vec3 irrvol__bin_point(uint32_t k, uint32_t bin, float fu, float fv)
{
    uint32_t kk = k * k, h = bin / kk, j = (bin % kk) / k, i = bin % k;
    irrvol__vec3 d = irrvol__square_to_hemisphere(((float)i + fu) / (float)k, ((float)j + fv) / (float)k);
    if (h) d.z = -d.z;
    return d;
}

/* ======================================================================
   9. the volume: bilevel grid (4.1, 4.3)
   Samples are numbered first level first (x fastest), then the new samples
   of the second-level grids in cell order. Every first-level cell has a
   table of side^3 sample ids (side 2 for an unrefined cell: its corners;
   subgrid_samples for a refined one), so a query runs the same code at either
   level. Irradiance is stored bin-major: for each bin, rgb of every sample.
   The eight corners of a query read the same bin of eight samples, and the
   two corners along x are usually consecutive samples, so a query touches
   four to six cache lines instead of eight.
   ---------------------------------------------------------------------- */
typedef struct irrvol__cell {
    uint32_t offset;   /* first id of the cell's table in vol->ids */
    uint32_t side;     /* samples per axis of the table */
} irrvol__cell;

struct irrvol {
    irrvol_allocator allocator;
    float lo[3], hi[3];
    float scale[3];        /* first-level cells per unit length: num_cells / (max - min), eq. 4.4 */
    float cell_limit[3];   /* cells per axis as float: the clamp bound of q_d */
    uint32_t samples[3];   /* first-level samples per axis */
    uint32_t cells[3];     /* first-level cells per axis */
    uint32_t subgrid;      /* second-level samples per axis, corners included */
    uint32_t cell_count, refined_count;
    irrvol__cell *cell;
    uint32_t *ids;
    size_t id_count;
    uint32_t sample_count, first_level_count;
    float *positions;      /* xyz per sample */
    uint32_t k, bins;
    float kf;
    uint32_t moment;
    irrvol_filter filter;
    float *irradiance;     /* bins x sample_count x rgb */
    float *radiance;       /* same layout, or NULL */
    uint64_t rays;
    uint32_t degenerate;
};

static void irrvol__log(void (*log)(void *, const char *), void *user, const char *message)
{
    if (log) log(user, message);
}

/* Key of a point of the global fine lattice (21 bits per axis suffice:
   1023 cells x 32 sub-cells). */
static uint64_t irrvol__lattice_key(uint32_t i, uint32_t j, uint32_t k)
{
    return (uint64_t)i | ((uint64_t)j << 21) | ((uint64_t)k << 42);
}

/* Open-addressing map from lattice keys to sample ids, for sharing the
   samples on faces and edges between neighbouring second-level grids. */
typedef struct irrvol__id_map {
    uint64_t *keys;
    uint32_t *values;
    size_t mask;
} irrvol__id_map;

static uint32_t irrvol__id_map_get(irrvol__id_map *m, uint64_t key, uint32_t *next_id, int *created)
{
    size_t slot = (size_t)irrvol__mix64(key) & m->mask;
    for (;;) {
        if (m->keys[slot] == UINT64_MAX) {
            m->keys[slot] = key;
            m->values[slot] = (*next_id)++;
            *created = 1;
            return m->values[slot];
        }
        if (m->keys[slot] == key) { *created = 0; return m->values[slot]; }
        slot = (slot + 1) & m->mask;
    }
}

static void irrvol__grid_dims(irrvol *v, const uint32_t samples[3], uint32_t subgrid)
{
    int d;
    v->cell_count = 1;
    for (d = 0; d < 3; d++) {
        v->samples[d] = samples[d];
        v->cells[d] = samples[d] - 1;
        v->cell_count *= v->cells[d];
        v->scale[d] = (float)((double)v->cells[d] / ((double)v->hi[d] - (double)v->lo[d]));
        v->cell_limit[d] = (float)v->cells[d];
    }
    v->subgrid = subgrid;
    v->first_level_count = samples[0] * samples[1] * samples[2];
}

/* Fills the cells' id tables in cell order. A refined cell's table holds
   its side^3 points of the global fine lattice (f sub-cells per cell); a
   point on the coarse lattice is a first-level sample, any other point gets
   a new id the first time a cell meets it, so neighbours share it. The fine
   coordinates of each new sample go to fine[]. Returns the sample count. */
static uint32_t irrvol__fill_tables(irrvol *v, const unsigned char *refined, irrvol__id_map *map, uint32_t *fine)
{
    uint32_t f = v->subgrid - 1, c = 0, cx, cy, cz, next = v->first_level_count;
    size_t at = 0;
    for (cz = 0; cz < v->cells[2]; cz++)
        for (cy = 0; cy < v->cells[1]; cy++)
            for (cx = 0; cx < v->cells[0]; cx++, c++) {
                /* table side and the lattice spacing of its points */
                uint32_t s = refined[c] ? v->subgrid : 2, spacing = refined[c] ? 1 : f, lx, ly, lz;
                v->cell[c].offset = (uint32_t)at;
                v->cell[c].side = s;
                for (lz = 0; lz < s; lz++)
                    for (ly = 0; ly < s; ly++)
                        for (lx = 0; lx < s; lx++) {
                            uint32_t gi = cx * f + lx * spacing, gj = cy * f + ly * spacing, gk = cz * f + lz * spacing;
                            int created;
                            uint32_t id;
                            if (gi % f == 0 && gj % f == 0 && gk % f == 0) {
                                v->ids[at++] = gi / f + v->samples[0] * (gj / f + v->samples[1] * (gk / f));
                                continue;
                            }
                            id = irrvol__id_map_get(map, irrvol__lattice_key(gi, gj, gk), &next, &created);
                            if (created) {
                                uint32_t *p = &fine[3 * (size_t)(id - v->first_level_count)];
                                p[0] = gi; p[1] = gj; p[2] = gk;
                            }
                            v->ids[at++] = id;
                        }
            }
    return next;
}

/* Sample positions from their fine-lattice coordinates. */
static void irrvol__sample_positions(irrvol *v, const uint32_t *fine)
{
    uint32_t f = v->subgrid - 1;
    size_t i;
    for (i = 0; i < v->sample_count; i++) {
        uint32_t g[3];
        int d;
        if (i < v->first_level_count) {
            g[0] = (uint32_t)(i % v->samples[0]) * f;
            g[1] = (uint32_t)((i / v->samples[0]) % v->samples[1]) * f;
            g[2] = (uint32_t)(i / ((size_t)v->samples[0] * v->samples[1])) * f;
        } else {
            memcpy(g, &fine[3 * (i - v->first_level_count)], sizeof g);
        }
        for (d = 0; d < 3; d++) {
            double t = (double)g[d] / ((double)v->cells[d] * f);
            v->positions[3 * i + d] = (float)((double)v->lo[d] + t * ((double)v->hi[d] - (double)v->lo[d]));
        }
    }
}

/* Builds the id tables and sample positions of a grid whose dimensions are
   set, given which cells are refined. */
static irrvol_result irrvol__make_grid(irrvol *v, const unsigned char *refined)
{
    const irrvol_allocator *a = &v->allocator;
    uint64_t side3 = (uint64_t)v->subgrid * v->subgrid * v->subgrid, ids, upper, capacity = 16;
    uint32_t *fine, c;
    irrvol__id_map map;
    irrvol_result r = IRRVOL_OK;
    v->refined_count = 0;
    for (c = 0; c < v->cell_count; c++) v->refined_count += refined[c] ? 1u : 0u;
    ids = (uint64_t)(v->cell_count - v->refined_count) * 8u + (uint64_t)v->refined_count * side3;
    upper = (uint64_t)v->first_level_count + (uint64_t)v->refined_count * (side3 - 8u);   /* nothing shared */
    if (ids > UINT32_MAX || upper >= UINT32_MAX || ids > SIZE_MAX / 8 || upper > SIZE_MAX / 16)
        return IRRVOL_ERROR_OUT_OF_MEMORY;
    while (capacity < 2 * (uint64_t)v->refined_count * side3) capacity *= 2;
    v->id_count = (size_t)ids;
    v->cell = (irrvol__cell *)irrvol__alloc_array(a, v->cell_count, sizeof(irrvol__cell));
    v->ids = (uint32_t *)irrvol__alloc_array(a, v->id_count, sizeof(uint32_t));
    fine = (uint32_t *)irrvol__alloc_array(a, (size_t)(upper - v->first_level_count) * 3 + 3, sizeof(uint32_t));
    map.keys = (uint64_t *)irrvol__alloc_array(a, (size_t)capacity, sizeof(uint64_t));
    map.values = (uint32_t *)irrvol__alloc_array(a, (size_t)capacity, sizeof(uint32_t));
    map.mask = (size_t)capacity - 1;
    if (v->cell && v->ids && fine && map.keys && map.values) {
        memset(map.keys, 0xFF, (size_t)capacity * sizeof(uint64_t));
        v->sample_count = irrvol__fill_tables(v, refined, &map, fine);
        v->positions = (float *)irrvol__alloc_array(a, (size_t)v->sample_count * 3, sizeof(float));
        if (v->positions) irrvol__sample_positions(v, fine);
        else r = IRRVOL_ERROR_OUT_OF_MEMORY;
    } else {
        r = IRRVOL_ERROR_OUT_OF_MEMORY;
    }
    irrvol__free(a, fine);
    irrvol__free(a, map.keys);
    irrvol__free(a, map.values);
    return r;
}

static size_t irrvol__bytes(const irrvol *v)
{
    size_t per_sample = (size_t)v->bins * 3 * sizeof(float);
    return sizeof *v + v->cell_count * sizeof(irrvol__cell) + v->id_count * sizeof(uint32_t) +
           (size_t)v->sample_count * (3 * sizeof(float) + per_sample * (v->radiance ? 2 : 1));
}

IRRVOL_API void irrvol_destroy(irrvol *vol)
{
    irrvol_allocator a;
    if (!vol) return;
    a = vol->allocator;
    irrvol__free(&a, vol->cell);
    irrvol__free(&a, vol->ids);
    irrvol__free(&a, vol->positions);
    irrvol__free(&a, vol->irradiance);
    irrvol__free(&a, vol->radiance);
    irrvol__free(&a, vol);
}

static irrvol *irrvol__create(const irrvol_allocator *a)
{
    irrvol *v = (irrvol *)irrvol__alloc(a, sizeof(irrvol));
    if (!v) return NULL;
    memset(v, 0, sizeof *v);
    v->allocator = *a;
    return v;
}

/* ======================================================================
   10. second-level refinement: triangle/box overlap
   ---------------------------------------------------------------------- */
/* Separating axis test of Akenine-Moller ("Fast 3D triangle-box overlap
   testing", 2001): the three box normals, the triangle normal and the nine
   cross products of box axes and triangle edges. Box given by centre and
   half sizes; touching counts as overlap. */
static int irrvol__tri_box_overlap(const double centre[3], const double half[3], double tri[3][3])
{
    double v[3][3], e[3][3], n[3], lo, hi, r;
    int i, j, k;
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++) v[i][k] = tri[i][k] - centre[k];
    for (k = 0; k < 3; k++) {
        e[0][k] = v[1][k] - v[0][k];
        e[1][k] = v[2][k] - v[1][k];
        e[2][k] = v[0][k] - v[2][k];
    }
    for (j = 0; j < 3; j++)         /* nine axes: unit_k x e_j */
        for (k = 0; k < 3; k++) {
            double axis[3], p[3];
            int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            axis[k] = 0.0;
            axis[k1] = -e[j][k2];
            axis[k2] = e[j][k1];
            for (i = 0; i < 3; i++) p[i] = axis[0] * v[i][0] + axis[1] * v[i][1] + axis[2] * v[i][2];
            lo = p[0] < p[1] ? (p[0] < p[2] ? p[0] : p[2]) : (p[1] < p[2] ? p[1] : p[2]);
            hi = p[0] > p[1] ? (p[0] > p[2] ? p[0] : p[2]) : (p[1] > p[2] ? p[1] : p[2]);
            r = half[0] * fabs(axis[0]) + half[1] * fabs(axis[1]) + half[2] * fabs(axis[2]);
            if (lo > r || hi < -r) return 0;
        }
    for (k = 0; k < 3; k++) {       /* box normals: the triangle's bounds */
        lo = v[0][k] < v[1][k] ? (v[0][k] < v[2][k] ? v[0][k] : v[2][k]) : (v[1][k] < v[2][k] ? v[1][k] : v[2][k]);
        hi = v[0][k] > v[1][k] ? (v[0][k] > v[2][k] ? v[0][k] : v[2][k]) : (v[1][k] > v[2][k] ? v[1][k] : v[2][k]);
        if (lo > half[k] || hi < -half[k]) return 0;
    }
    n[0] = e[0][1] * e[1][2] - e[0][2] * e[1][1];   /* triangle plane vs box */
    n[1] = e[0][2] * e[1][0] - e[0][0] * e[1][2];
    n[2] = e[0][0] * e[1][1] - e[0][1] * e[1][0];
    r = half[0] * fabs(n[0]) + half[1] * fabs(n[1]) + half[2] * fabs(n[2]);
    return fabs(n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2]) <= r;
}

/* Marks the first-level cells that a non-degenerate triangle overlaps (4.1
   step 2). Each triangle tests only the cells its bounds reach. */
static void irrvol__mark_refined(const irrvol *v, const irrvol__mesh_view *m, unsigned char *refined)
{
    uint32_t t;
    for (t = 0; t < m->tri_count; t++) {
        double tri[3][3], tlo[3], thi[3], size[3];
        uint32_t c0[3], c1[3], x, y, z;
        int d, i, outside = 0;
        irrvol__vec3 e;
        for (i = 0; i < 3; i++) {
            const float *p = irrvol__vertex(m, m->indices[3 * t + (uint32_t)i]);
            for (d = 0; d < 3; d++) tri[i][d] = p[d];
        }
        e = irrvol__cross(irrvol__v3((float)(tri[1][0] - tri[0][0]), (float)(tri[1][1] - tri[0][1]), (float)(tri[1][2] - tri[0][2])),
                          irrvol__v3((float)(tri[2][0] - tri[0][0]), (float)(tri[2][1] - tri[0][1]), (float)(tri[2][2] - tri[0][2])));
        if (irrvol__dot(e, e) == 0.0f) continue;   /* degenerate: skipped, counted by the BVH */
        for (d = 0; d < 3; d++) {
            double qlo, qhi;
            tlo[d] = fmin(tri[0][d], fmin(tri[1][d], tri[2][d]));
            thi[d] = fmax(tri[0][d], fmax(tri[1][d], tri[2][d]));
            size[d] = ((double)v->hi[d] - (double)v->lo[d]) / v->cells[d];
            qlo = (tlo[d] - v->lo[d]) / size[d];
            qhi = (thi[d] - v->lo[d]) / size[d];
            if (qhi < 0.0 || qlo > (double)v->cells[d]) { outside = 1; break; }
            /* clamped before the conversion: a huge triangle must not overflow it */
            c0[d] = qlo <= 0.0 ? 0u : qlo >= (double)v->cells[d] ? v->cells[d] - 1 : (uint32_t)qlo;
            c1[d] = qhi >= (double)v->cells[d] ? v->cells[d] - 1 : (uint32_t)qhi;
            /* a bound on a cell face also touches the cell before it */
            if (c0[d] > 0 && qlo == (double)c0[d]) c0[d]--;
        }
        if (outside) continue;
        for (z = c0[2]; z <= c1[2]; z++)
            for (y = c0[1]; y <= c1[1]; y++)
                for (x = c0[0]; x <= c1[0]; x++) {
                    uint32_t c = x + v->cells[0] * (y + v->cells[1] * z);
                    double centre[3], half[3];
                    uint32_t cc[3];
                    if (refined[c]) continue;
                    cc[0] = x; cc[1] = y; cc[2] = z;
                    for (d = 0; d < 3; d++) {
                        half[d] = 0.5 * size[d];
                        centre[d] = (double)v->lo[d] + ((double)cc[d] + 0.5) * size[d];
                    }
                    if (irrvol__tri_box_overlap(centre, half, tri)) refined[c] = 1;
                }
    }
}

/* ======================================================================
   11. build: radiance gathering (4.2.1, 4.2.2) and irradiance (4.2.3, 4.4)
   ---------------------------------------------------------------------- */
typedef struct irrvol__build {
    const irrvol_desc *desc;
    irrvol *vol;
    irrvol__mesh_view mesh;
    irrvol__bvh bvh;
    irrvol__bvh important_bvh; /* over the IMPORTANT triangles; ids index b->important */
    uint32_t *important_indices;
    uint32_t supersamples, weight_subdivisions, max_depth, important_side;
    float min_weight, ray_offset;
    float *dirs;            /* bin centre directions, xyz per bin */
    float *dir_soa;         /* the same: all x, all y, all z */
    float *weights;         /* bins x bins: row i = radiance bin, column j = irradiance bin */
    uint32_t *important;    /* triangles of IMPORTANT materials */
    uint32_t important_count;
    float bin_solid_angle;  /* 4 pi / bins, eq. 4.2 */
    float bin_angle;        /* sqrt of it: the angular size of a bin */
    unsigned char *scratch; /* per job of a batch */
    size_t scratch_stride;
    uint32_t batch_begin;
    uint32_t *ray_counts;   /* per sample, summed after the build */
} irrvol__build;

/* x^n by squaring. */
static double irrvol__powi(double x, uint32_t n)
{
    double r = 1.0;
    while (n) {
        if (n & 1u) r *= x;
        x *= x;
        n >>= 1;
    }
    return r;
}

/* Row i of the weight matrix: W(i, j) = (n+1)/2 * integral over bin i of
   max(0, w . w_j)^n dw, by w x w equal-area sub-directions (eq. 4.8 with the
   radiance constant over bin i; one sub-direction is eq. 4.8 at the bin
   centre, eq. 4.3 for n = 1). */
static void irrvol__weight_row_job(void *ctx, uint32_t i)
{
    const irrvol__build *b = (const irrvol__build *)ctx;
    const irrvol *v = b->vol;
    uint32_t w = b->weight_subdivisions, n = v->moment, bins = v->bins, s, j;
    float sub[IRRVOL__MAX_WEIGHT_SUBDIVISIONS * IRRVOL__MAX_WEIGHT_SUBDIVISIONS][3];
    double scale = 0.5 * (n + 1.0) * 4.0 * IRRVOL__PI / ((double)bins * w * w);
    float *row = b->weights + (size_t)i * bins;
    for (s = 0; s < w * w; s++) {
        irrvol__vec3 d = irrvol__bin_point(v->k, i, ((float)(s % w) + 0.5f) / (float)w,
                                           ((float)(s / w) + 0.5f) / (float)w);
        sub[s][0] = d.x; sub[s][1] = d.y; sub[s][2] = d.z;
    }
    for (j = 0; j < bins; j++) {
        const float *dj = b->dirs + 3 * (size_t)j;
        double sum = 0.0;
        for (s = 0; s < w * w; s++) {
            double c = (double)sub[s][0] * dj[0] + (double)sub[s][1] * dj[1] + (double)sub[s][2] * dj[2];
            if (c > 0.0) sum += irrvol__powi(c, n);
        }
        row[j] = (float)(scale * sum);
    }
}

/* Eq. 4.3 / 4.8 for every irradiance bin at once: H = W^T L, summed over
   all radiance bins (zero-radiance bins add nothing and are skipped). L and H
   are planar (all red, all green, all blue) so that the inner loop is a
   contiguous multiply-add the compiler vectorizes; four radiance bins per
   pass over H load and store H a quarter as often. rows is scratch for the
   indices of the non-zero radiance bins. */
static void irrvol__irradiance(const float *IRRVOL__RESTRICT weights, uint32_t bins,
                              const float *IRRVOL__RESTRICT radiance, float *IRRVOL__RESTRICT out, uint32_t *rows)
{
    float *IRRVOL__RESTRICT hr = out;
    float *IRRVOL__RESTRICT hg = out + bins;
    float *IRRVOL__RESTRICT hb = out + 2 * (size_t)bins;
    const float *lr = radiance, *lg = radiance + bins, *lb = radiance + 2 * (size_t)bins;
    uint32_t i, j, n = 0, r;
    memset(out, 0, 3 * (size_t)bins * sizeof(float));
    for (i = 0; i < bins; i++)
        if (lr[i] != 0.0f || lg[i] != 0.0f || lb[i] != 0.0f) rows[n++] = i;
    for (r = 0; r + 4 <= n; r += 4) {
        const float *IRRVOL__RESTRICT w0 = weights + (size_t)rows[r] * bins;
        const float *IRRVOL__RESTRICT w1 = weights + (size_t)rows[r + 1] * bins;
        const float *IRRVOL__RESTRICT w2 = weights + (size_t)rows[r + 2] * bins;
        const float *IRRVOL__RESTRICT w3 = weights + (size_t)rows[r + 3] * bins;
        float r0 = lr[rows[r]], r1 = lr[rows[r + 1]], r2 = lr[rows[r + 2]], r3 = lr[rows[r + 3]];
        float g0 = lg[rows[r]], g1 = lg[rows[r + 1]], g2 = lg[rows[r + 2]], g3 = lg[rows[r + 3]];
        float b0 = lb[rows[r]], b1 = lb[rows[r + 1]], b2 = lb[rows[r + 2]], b3 = lb[rows[r + 3]];
        for (j = 0; j < bins; j++) {
            float x0 = w0[j], x1 = w1[j], x2 = w2[j], x3 = w3[j];
            hr[j] += (r0 * x0 + r1 * x1) + (r2 * x2 + r3 * x3);
            hg[j] += (g0 * x0 + g1 * x1) + (g2 * x2 + g3 * x3);
            hb[j] += (b0 * x0 + b1 * x1) + (b2 * x2 + b3 * x3);
        }
    }
    for (; r < n; r++) {
        const float *IRRVOL__RESTRICT w0 = weights + (size_t)rows[r] * bins;
        float r0 = lr[rows[r]], g0 = lg[rows[r]], b0 = lb[rows[r]];
        for (j = 0; j < bins; j++) {
            hr[j] += r0 * w0[j];
            hg[j] += g0 * w0[j];
            hb[j] += b0 * w0[j];
        }
    }
}

/* First hit through the caller's ray caster or the built-in BVH. A hit on
   a triangle index out of range counts as a miss. */
static int irrvol__trace(const irrvol__build *b, const float org[3], const float dir[3], irrvol_hit *hit)
{
    const irrvol_desc *d = b->desc;
    if (d->trace) {
        if (!d->trace(d->trace_user, org, dir, FLT_MAX, hit)) return 0;
        return hit->triangle < d->triangle_count && isfinite(hit->t) && isfinite(hit->u) && isfinite(hit->v);
    } else {
        irrvol__hit h;
        if (!irrvol__bvh_intersect(&b->bvh, org, dir, 0.0f, FLT_MAX, &h)) return 0;
        hit->t = h.t; hit->u = h.u; hit->v = h.v; hit->triangle = h.tri;
        return 1;
    }
}

/* The diffuse radiance of the surface at a hit: per-vertex radiance
   interpolated with the barycentrics, or the material's. */
static void irrvol__surface_radiance(const irrvol__build *b, const irrvol_hit *hit,
                                     const irrvol_material *mat, float rgb[3])
{
    const irrvol_desc *d = b->desc;
    int c;
    if (d->vertex_radiance) {
        size_t stride = d->vertex_radiance_stride ? d->vertex_radiance_stride : 3 * sizeof(float);
        const uint32_t *tri = d->indices + 3 * (size_t)hit->triangle;
        const float *l0 = (const float *)((const char *)d->vertex_radiance + tri[0] * stride);
        const float *l1 = (const float *)((const char *)d->vertex_radiance + tri[1] * stride);
        const float *l2 = (const float *)((const char *)d->vertex_radiance + tri[2] * stride);
        float w0 = 1.0f - hit->u - hit->v;
        for (c = 0; c < 3; c++) rgb[c] = w0 * l0[c] + hit->u * l1[c] + hit->v * l2[c];
    } else if (mat) {
        for (c = 0; c < 3; c++) rgb[c] = mat->radiance[c];
    } else {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
    }
}

/* Built-in radiance along a ray (4.2.2): the first surface's radiance plus,
   through mirror surfaces, the specularly reflected radiance weighted by the
   product of the specular coefficients, until a diffuse surface, the depth
   limit or the weight floor (then the background stands for the rest). */
static void irrvol__builtin_radiance(const irrvol__build *b, const float org[3], const float dir[3], float rgb[3])
{
    const irrvol_desc *d = b->desc;
    float o[3], w[3] = {1.0f, 1.0f, 1.0f};
    irrvol__vec3 dv = irrvol__v3_load(dir);
    uint32_t reflections = 0;
    int c;
    memcpy(o, org, sizeof o);
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (;;) {
        irrvol_hit hit;
        const irrvol_material *mat = NULL;
        float le[3], dirf[3];
        irrvol__vec3 p0, n, p;
        float dn;
        dirf[0] = dv.x; dirf[1] = dv.y; dirf[2] = dv.z;
        if (!irrvol__trace(b, o, dirf, &hit)) {
            for (c = 0; c < 3; c++) rgb[c] += w[c] * d->background[c];
            return;
        }
        if (d->materials)
            mat = &d->materials[d->triangle_materials ? d->triangle_materials[hit.triangle] : 0];
        if (mat && (mat->flags & IRRVOL_MATERIAL_IGNORE)) return;   /* 5.4: contributes zero */
        irrvol__surface_radiance(b, &hit, mat, le);
        for (c = 0; c < 3; c++) rgb[c] += w[c] * le[c];
        if (!mat || (mat->specular[0] <= 0.0f && mat->specular[1] <= 0.0f && mat->specular[2] <= 0.0f)) return;
        for (c = 0; c < 3; c++) w[c] *= mat->specular[c];
        reflections++;
        if (reflections > b->max_depth || irrvol__maxf(w[0], irrvol__maxf(w[1], w[2])) < b->min_weight) {
            for (c = 0; c < 3; c++) rgb[c] += w[c] * d->background[c];
            return;
        }
        /* mirror about the geometric normal; the next ray starts off the
           surface on the side the ray came from and a little back along it,
           so that a hit on the edge of a concave corner still finds the
           other face instead of leaving through it */
        p0 = irrvol__v3_load(irrvol__vertex(&b->mesh, d->indices[3 * (size_t)hit.triangle]));
        n = irrvol__normalize(irrvol__cross(
            irrvol__sub(irrvol__v3_load(irrvol__vertex(&b->mesh, d->indices[3 * (size_t)hit.triangle + 1])), p0),
            irrvol__sub(irrvol__v3_load(irrvol__vertex(&b->mesh, d->indices[3 * (size_t)hit.triangle + 2])), p0)));
        p = irrvol__add(irrvol__v3_load(o), irrvol__scale(dv, hit.t - b->ray_offset));
        dn = irrvol__dot(dv, n);
        dv = irrvol__normalize(irrvol__sub(dv, irrvol__scale(n, 2.0f * dn)));
        p = irrvol__add(p, irrvol__scale(n, dn < 0.0f ? b->ray_offset : -b->ray_offset));
        o[0] = p.x; o[1] = p.y; o[2] = p.z;
    }
}

static void irrvol__ray_radiance(const irrvol__build *b, const float org[3], irrvol__vec3 dir, float rgb[3])
{
    float d[3];
    d[0] = dir.x; d[1] = dir.y; d[2] = dir.z;
    if (b->desc->radiance) b->desc->radiance(b->desc->radiance_user, org, d, rgb);
    else irrvol__builtin_radiance(b, org, d, rgb);
}

static uint32_t irrvol__nearest_bin(const irrvol *v, const float dir[3]);

/* Informed sampling (6.1.1). The directions that point at IMPORTANT
   triangles (light sources: the "important set") are integrated apart, from
   points sampled on the triangles themselves, so a source is captured however
   small it is next to a bin:

     H^n(w_j) = sum over bins i of L_i W(i, j)                      (eq. 4.8)
              + (n+1)/2 * integral over the important set of L max(0, w . w_j)^n dw

   where L_i is the mean of the bin's rays, a ray toward an important
   triangle counting zero. The second term is a stratified estimate with each
   point's exact direction, so the source is not smeared over its bin either.
   A direction that meets several important triangles belongs to the first
   one along it, so triangles seen behind one another count once. Bins that
   an important triangle overlaps also get extra stratified rays, for the rest
   of the bin. The kept radiance of a bin (keep_radiance) includes the
   important part: the mean of L over the whole bin. */

/* The triangle's corners relative to p, their distances and its solid angle
   seen from p (Van Oosterom and Strackee 1983); 0 when p is on its plane. */
static double irrvol__important_corners(const irrvol__build *b, uint32_t t, const float p[3], double q[3][3])
{
    const uint32_t *tri = b->desc->indices + 3 * (size_t)b->important[t];
    double len[3], det, den;
    int c, e;
    for (e = 0; e < 3; e++) {
        const float *x = irrvol__vertex(&b->mesh, tri[e]);
        for (c = 0; c < 3; c++) q[e][c] = (double)x[c] - p[c];
        len[e] = sqrt(q[e][0] * q[e][0] + q[e][1] * q[e][1] + q[e][2] * q[e][2]);
    }
    if (!(len[0] > 0.0 && len[1] > 0.0 && len[2] > 0.0)) return 0.0;
    det = q[0][0] * (q[1][1] * q[2][2] - q[1][2] * q[2][1]) - q[0][1] * (q[1][0] * q[2][2] - q[1][2] * q[2][0]) +
          q[0][2] * (q[1][0] * q[2][1] - q[1][1] * q[2][0]);
    den = len[0] * len[1] * len[2] +
          (q[0][0] * q[1][0] + q[0][1] * q[1][1] + q[0][2] * q[1][2]) * len[2] +
          (q[0][0] * q[2][0] + q[0][1] * q[2][1] + q[0][2] * q[2][2]) * len[1] +
          (q[1][0] * q[2][0] + q[1][1] * q[2][1] + q[1][2] * q[2][2]) * len[0];
    return 2.0 * atan2(fabs(det), den);
}

/* Marks the bins an important triangle's directions from p fall into, from
   a barycentric grid over the triangle spaced a third of a bin apart. */
static void irrvol__mark_important_bins(const irrvol__build *b, const float p[3], unsigned char *extra)
{
    uint32_t t;
    for (t = 0; t < b->important_count; t++) {
        double q[3][3], cosmin = 1.0;
        uint32_t steps, i, j;
        int c, e;
        if (!(irrvol__important_corners(b, t, p, q) > 0.0)) continue;   /* edge-on: no ray meets it */
        for (e = 0; e < 3; e++) {       /* widest angle between two corner directions */
            const double *x = q[e], *y = q[(e + 1) % 3];
            double cs = (x[0] * y[0] + x[1] * y[1] + x[2] * y[2]) /
                        sqrt((x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) * (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]));
            if (cs < cosmin) cosmin = cs;
        }
        steps = (uint32_t)ceil(3.0 * acos(cosmin < -1.0 ? -1.0 : cosmin) / b->bin_angle);
        steps = steps < 1 ? 1 : (steps > 64 ? 64 : steps);
        for (i = 0; i <= steps; i++)
            for (j = 0; i + j <= steps; j++) {
                double s = (double)i / steps, r = (double)j / steps;
                float dir[3];
                for (c = 0; c < 3; c++) dir[c] = (float)(q[0][c] + s * (q[1][c] - q[0][c]) + r * (q[2][c] - q[0][c]));
                extra[irrvol__nearest_bin(b->vol, dir)] = 1;
            }
    }
}

/* Adds (n+1)/2 w L max(0, dir . w_j)^n to every irradiance bin j (eq. 4.8
   for one direction). Bin directions are stored by component so that the
   loop over bins is a contiguous multiply-add. */
/* h += max(0, dir . d_j) * rgb for every bin j: restrict parameters, so
   that compilers vectorize it. */
static void irrvol__cosine_axpy(uint32_t bins, const float *IRRVOL__RESTRICT dx, const float *IRRVOL__RESTRICT dy,
                                const float *IRRVOL__RESTRICT dz, float x, float y, float z, float r, float g,
                                float bl, float *IRRVOL__RESTRICT hr, float *IRRVOL__RESTRICT hg,
                                float *IRRVOL__RESTRICT hb)
{
    uint32_t j;
    for (j = 0; j < bins; j++) {
        float cs = x * dx[j] + y * dy[j] + z * dz[j];
        cs = cs > 0.0f ? cs : 0.0f;
        hr[j] += cs * r;
        hg[j] += cs * g;
        hb[j] += cs * bl;
    }
}

static void irrvol__add_lobe(const irrvol__build *b, const float dir[3], const double wl[3], float *direct)
{
    const irrvol *v = b->vol;
    uint32_t bins = v->bins, j;
    const float *dx = b->dir_soa, *dy = dx + bins, *dz = dy + bins;
    double lobe = 0.5 * (v->moment + 1.0);
    float r = (float)(lobe * wl[0]), g = (float)(lobe * wl[1]), bl = (float)(lobe * wl[2]);
    if (v->moment == 1) {
        irrvol__cosine_axpy(bins, dx, dy, dz, dir[0], dir[1], dir[2], r, g, bl, direct, direct + bins,
                            direct + 2 * (size_t)bins);
        return;
    }
    for (j = 0; j < bins; j++) {
        float cs = dir[0] * dx[j] + dir[1] * dy[j] + dir[2] * dz[j];
        float f = cs > 0.0f ? (float)irrvol__powi(cs, v->moment) : 0.0f;
        direct[j] += f * r;
        direct[bins + j] += f * g;
        direct[2 * (size_t)bins + j] += f * bl;
    }
}

/* The important set's part: stratified points uniform in area on each
   important triangle, weighted by their solid angle A cos(theta) / (r^2 M).
   Each adds w L to its bin's radiance integral (part, for the kept radiance)
   and (n+1)/2 w L max(0, w . w_j)^n to every irradiance bin j (direct, planar
   rgb). desc.important_rays points per sample, shared among the triangles by
   solid angle, plus 16 per bin they cover; at least 2 x 2 per triangle.
   Returns the rays cast. */
static uint32_t irrvol__important_part(const irrvol__build *b, const float p[3], irrvol__rng *rng, double *part,
                                       float *direct)
{
    const irrvol *v = b->vol;
    uint32_t t, rays = 0;
    double total = 0.0;
    for (t = 0; t < b->important_count; t++) {   /* the solid angle of the whole important set */
        double q[3][3], omega = irrvol__important_corners(b, t, p, q);
        if (omega > 0.0) total += omega;
    }
    for (t = 0; t < b->important_count; t++) {
        double q[3][3], n[3], area2, want;
        double omega = irrvol__important_corners(b, t, p, q);
        uint32_t side, x, y;
        int c;
        if (!(omega > 0.0)) continue;
        n[0] = (q[1][1] - q[0][1]) * (q[2][2] - q[0][2]) - (q[1][2] - q[0][2]) * (q[2][1] - q[0][1]);
        n[1] = (q[1][2] - q[0][2]) * (q[2][0] - q[0][0]) - (q[1][0] - q[0][0]) * (q[2][2] - q[0][2]);
        n[2] = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
        area2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);   /* twice the area */
        if (!(area2 > 0.0)) continue;
        /* important_rays points shared by solid angle, and 16 per bin covered */
        want = (double)b->important_side * b->important_side * omega / total + 16.0 * omega / b->bin_solid_angle;
        for (side = 2; side < 64 && (double)side * side < want;) side++;
        for (y = 0; y < side; y++)
            for (x = 0; x < side; x++) {
                double u1 = ((double)x + irrvol__rng_float(rng)) / side, u2 = ((double)y + irrvol__rng_float(rng)) / side;
                double sq = sqrt(u1), w0 = 1.0 - sq, w1 = sq * (1.0 - u2), w2 = sq * u2, pt[3], r2, r, weight, wl[3];
                float dir[3], rgb[3];
                double *acc;
                irrvol__hit hit;
                for (c = 0; c < 3; c++) pt[c] = w0 * q[0][c] + w1 * q[1][c] + w2 * q[2][c];
                r2 = pt[0] * pt[0] + pt[1] * pt[1] + pt[2] * pt[2];
                r = sqrt(r2);
                if (!(r > 0.0)) continue;
                for (c = 0; c < 3; c++) dir[c] = (float)(pt[c] / r);
                weight = 0.5 * fabs(n[0] * pt[0] + n[1] * pt[1] + n[2] * pt[2]) / (r * r2) / ((double)side * side);
                /* count the direction here only if this triangle is the first important one along it */
                if (!irrvol__bvh_intersect(&b->important_bvh, p, dir, 0.0f, FLT_MAX, &hit) || hit.tri != t) continue;
                irrvol__ray_radiance(b, p, irrvol__v3_load(dir), rgb);
                rays++;
                for (c = 0; c < 3; c++) wl[c] = weight * rgb[c];
                if (wl[0] == 0.0 && wl[1] == 0.0 && wl[2] == 0.0) continue;
                acc = part + 3 * (size_t)irrvol__nearest_bin(v, dir);
                acc[0] += wl[0]; acc[1] += wl[1]; acc[2] += wl[2];
                irrvol__add_lobe(b, dir, wl, direct);
            }
    }
    return rays;
}

/* One sample: gather radiance in every bin (4.2.2), s x s jittered rays per
   bin (or one through the centre) plus the important part, then the
   irradiance (4.2.3). */
static void irrvol__sample_job(void *ctx, uint32_t index)
{
    irrvol__build *b = (irrvol__build *)ctx;
    irrvol *v = b->vol;
    uint32_t s = b->batch_begin + index, bins = v->bins, bin, rays = 0;
    double *part = (double *)(b->scratch + (size_t)index * b->scratch_stride);
    float *direct = (float *)(part + 3 * (size_t)bins);
    float *radiance = direct + 3 * (size_t)bins;
    float *irradiance = radiance + 3 * (size_t)bins;
    uint32_t *rows = (uint32_t *)(irradiance + 3 * (size_t)bins);
    unsigned char *extra = (unsigned char *)(rows + bins);
    const float *p = v->positions + 3 * (size_t)s;
    irrvol__rng rng = irrvol__rng_stream(b->desc->seed, s);
    int c;
    memset(extra, 0, bins);
    if (b->important_count) {
        memset(part, 0, 3 * (size_t)bins * sizeof(double));
        memset(direct, 0, 3 * (size_t)bins * sizeof(float));
        irrvol__mark_important_bins(b, p, extra);
        rays += irrvol__important_part(b, p, &rng, part, direct);
    }
    for (bin = 0; bin < bins; bin++) {
        double sum[3] = {0.0, 0.0, 0.0};
        uint32_t ss = b->supersamples, count = 0, pass;
        for (pass = 0; pass < 2; pass++) {
            uint32_t side = pass == 0 ? ss : (extra[bin] ? b->important_side : 0), x, y;
            for (y = 0; y < side; y++)
                for (x = 0; x < side; x++) {
                    float rgb[3], dir[3], fu = 0.5f, fv = 0.5f;
                    irrvol__vec3 d;
                    if (pass == 1 || ss > 1) {   /* jitter in stratum (x, y) */
                        fu = ((float)x + irrvol__rng_float(&rng)) / (float)side;
                        fv = ((float)y + irrvol__rng_float(&rng)) / (float)side;
                    }
                    d = irrvol__bin_point(v->k, bin, fu, fv);
                    dir[0] = d.x; dir[1] = d.y; dir[2] = d.z;
                    count++;
                    if (b->important_count && irrvol__bvh_occluded(&b->important_bvh, p, dir, 0.0f, FLT_MAX))
                        continue;   /* an important direction: integrated by the important part */
                    irrvol__ray_radiance(b, p, d, rgb);
                    sum[0] += rgb[0]; sum[1] += rgb[1]; sum[2] += rgb[2];
                    rays++;
                }
        }
        for (c = 0; c < 3; c++) radiance[(size_t)c * bins + bin] = (float)(sum[c] / count);
    }
    irrvol__irradiance(b->weights, bins, radiance, irradiance, rows);
    for (bin = 0; bin < bins; bin++) {
        float *out = v->irradiance + ((size_t)bin * v->sample_count + s) * 3;
        for (c = 0; c < 3; c++) {
            size_t at = (size_t)c * bins + bin;
            out[c] = b->important_count ? irradiance[at] + direct[at] : irradiance[at];
        }
        if (v->radiance) {
            out = v->radiance + ((size_t)bin * v->sample_count + s) * 3;
            for (c = 0; c < 3; c++)
                out[c] = b->important_count ? (float)(radiance[(size_t)c * bins + bin] + part[3 * (size_t)bin + (size_t)c] /
                                                                                          b->bin_solid_angle)
                                            : radiance[(size_t)c * bins + bin];
        }
    }
    b->ray_counts[s] = rays;
}

#define IRRVOL__REJECT(log, user, message) \
    do { irrvol__log(log, user, message); return IRRVOL_ERROR_INVALID_ARGUMENT; } while (0)

static int irrvol__bounds_given(const irrvol_desc *d)
{
    int k;
    for (k = 0; k < 3; k++)
        if (d->bounds_min[k] != 0.0f || d->bounds_max[k] != 0.0f) return 1;
    return 0;
}

static int irrvol__nonnegative3(const float *p)
{
    return irrvol__finite3(p) && p[0] >= 0.0f && p[1] >= 0.0f && p[2] >= 0.0f;
}

static irrvol_result irrvol__validate_scene(const irrvol_desc *d)
{
    size_t stride = d->position_stride ? d->position_stride : 3 * sizeof(float);
    uint32_t i;
    if (!d->positions || !d->indices || !d->vertex_count)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: triangles need positions, indices and vertex_count");
    if (stride < 3 * sizeof(float))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: position_stride under 3 floats");
    for (i = 0; i < d->vertex_count; i++)
        if (!irrvol__finite3((const float *)((const char *)d->positions + (size_t)i * stride)))
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a position is NaN or infinite");
    for (i = 0; i < 3 * d->triangle_count; i++)
        if (d->indices[i] >= d->vertex_count)
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a vertex index is out of range");
    if (!d->radiance && !d->materials && !d->vertex_radiance)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: built-in radiance needs materials or vertex_radiance");
    if (d->triangle_materials) {
        if (!d->materials)
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: triangle_materials without materials");
        for (i = 0; i < d->triangle_count; i++)
            if (d->triangle_materials[i] >= d->material_count)
                IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a material index is out of range");
    }
    if (d->vertex_radiance) {
        size_t rs = d->vertex_radiance_stride ? d->vertex_radiance_stride : 3 * sizeof(float);
        if (rs < 3 * sizeof(float))
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: vertex_radiance_stride under 3 floats");
        for (i = 0; i < d->vertex_count; i++)
            if (!irrvol__nonnegative3((const float *)((const char *)d->vertex_radiance + (size_t)i * rs)))
                IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a vertex radiance is negative, NaN or infinite");
    }
    return IRRVOL_OK;
}

static irrvol_result irrvol__validate(const irrvol_desc *d)
{
    uint32_t i;
    int k;
    if (!irrvol__allocator_valid(&d->allocator))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: allocator needs both alloc and free, or neither");
    if (d->triangle_count) {
        irrvol_result r = irrvol__validate_scene(d);
        if (r != IRRVOL_OK) return r;
    } else if (!d->radiance || !irrvol__bounds_given(d)) {
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: no triangles: give a radiance callback and the bounds");
    }
    if (d->materials) {
        if (!d->material_count)
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: materials with material_count 0");
        for (i = 0; i < d->material_count; i++)
            if (!irrvol__nonnegative3(d->materials[i].radiance) || !irrvol__nonnegative3(d->materials[i].specular))
                IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a material value is negative, NaN or infinite");
    }
    for (k = 0; k < 3; k++)
        if (d->grid_samples[k] == 1 || d->grid_samples[k] > IRRVOL_MAX_GRID_SAMPLES)
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: grid_samples must be 2..IRRVOL_MAX_GRID_SAMPLES");
    if (d->subgrid_samples == 1 || d->subgrid_samples > IRRVOL_MAX_SUBGRID_SAMPLES)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: subgrid_samples must be 2..IRRVOL_MAX_SUBGRID_SAMPLES");
    if (!(d->inset >= 0.0f && d->inset < 0.5f))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: inset must be in [0, 0.5)");
    if (irrvol__bounds_given(d))
        for (k = 0; k < 3; k++)
            if (!isfinite(d->bounds_min[k]) || !isfinite(d->bounds_max[k]) || !(d->bounds_min[k] < d->bounds_max[k]))
                IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: bounds must be finite with min < max");
    if (d->resolution > IRRVOL_MAX_RESOLUTION || d->supersamples > IRRVOL__MAX_SUPERSAMPLES ||
        d->moment > IRRVOL_MAX_MOMENT || d->weight_subdivisions > IRRVOL__MAX_WEIGHT_SUBDIVISIONS ||
        d->important_rays > IRRVOL__IMPORTANT_MAX_SIDE * IRRVOL__IMPORTANT_MAX_SIDE)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: resolution, supersamples, moment, weight_subdivisions "
                                            "or important_rays too large");
    if ((int)d->filter < 0 || (int)d->filter > (int)IRRVOL_FILTER_BILINEAR)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: unknown filter");
    if (!irrvol__nonnegative3(d->background) || !(d->min_weight >= 0.0f) || !isfinite(d->min_weight) ||
        !(d->ray_offset >= 0.0f) || !isfinite(d->ray_offset))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: background, min_weight or ray_offset negative, NaN or infinite");
    return IRRVOL_OK;
}

/* Bounds of the vertices the triangles use. */
static void irrvol__scene_bounds(const irrvol__mesh_view *m, float lo[3], float hi[3])
{
    uint32_t i;
    irrvol__box_empty(lo, hi);
    for (i = 0; i < 3 * m->tri_count; i++) {
        const float *p = irrvol__vertex(m, m->indices[i]);
        irrvol__box_grow(lo, hi, p, p);
    }
}

static uint32_t irrvol__count_degenerate(const irrvol__mesh_view *m)
{
    uint32_t t, n = 0;
    for (t = 0; t < m->tri_count; t++) {
        irrvol__vec3 p0 = irrvol__v3_load(irrvol__vertex(m, m->indices[3 * t]));
        irrvol__vec3 c = irrvol__cross(irrvol__sub(irrvol__v3_load(irrvol__vertex(m, m->indices[3 * t + 1])), p0),
                                       irrvol__sub(irrvol__v3_load(irrvol__vertex(m, m->indices[3 * t + 2])), p0));
        if (irrvol__dot(c, c) == 0.0f) n++;
    }
    return n;
}

/* Grid bounds (4.1: inset from the scene bounds so samples stay off the
   outer walls), dimensions, refined cells and samples. */
static irrvol_result irrvol__setup_grid(irrvol__build *b)
{
    const irrvol_desc *d = b->desc;
    irrvol *v = b->vol;
    uint32_t samples[3];
    unsigned char *refined;
    float slo[3], shi[3], diag2 = 0.0f;
    irrvol_result r;
    int k;
    if (d->triangle_count) irrvol__scene_bounds(&b->mesh, slo, shi);
    for (k = 0; k < 3; k++) {
        if (irrvol__bounds_given(d)) {
            v->lo[k] = d->bounds_min[k];
            v->hi[k] = d->bounds_max[k];
        } else {
            float inset = irrvol__def(d->inset, 0.01f) * (shi[k] - slo[k]);
            v->lo[k] = slo[k] + inset;
            v->hi[k] = shi[k] - inset;
        }
        if (!(v->lo[k] < v->hi[k]) || !isfinite(v->hi[k] - v->lo[k]))
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: the grid has zero or infinite size along an axis");
        samples[k] = irrvol__def(d->grid_samples[k], 7u);
        diag2 += (v->hi[k] - v->lo[k]) * (v->hi[k] - v->lo[k]);
    }
    b->ray_offset = d->ray_offset > 0.0f ? d->ray_offset : 1e-4f * sqrtf(diag2);
    irrvol__grid_dims(v, samples, irrvol__def(d->subgrid_samples, 3u));
    refined = (unsigned char *)irrvol__alloc(&v->allocator, v->cell_count);
    if (!refined) return IRRVOL_ERROR_OUT_OF_MEMORY;
    memset(refined, 0, v->cell_count);
    if (v->subgrid > 2) irrvol__mark_refined(v, &b->mesh, refined);
    r = irrvol__make_grid(v, refined);
    irrvol__free(&v->allocator, refined);
    return r;
}

/* Bin directions, the shared weight matrix and the informed-sampling list. */
static irrvol_result irrvol__setup_directions(irrvol__build *b)
{
    const irrvol_desc *d = b->desc;
    irrvol *v = b->vol;
    const irrvol_allocator *a = &v->allocator;
    uint32_t i;
    b->dirs = (float *)irrvol__alloc_array(a, (size_t)v->bins * 3, sizeof(float));
    b->dir_soa = (float *)irrvol__alloc_array(a, (size_t)v->bins * 3, sizeof(float));
    b->weights = (float *)irrvol__alloc_array(a, (size_t)v->bins * v->bins, sizeof(float));
    if (!b->dirs || !b->dir_soa || !b->weights) return IRRVOL_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < v->bins; i++) {
        irrvol__vec3 dir = irrvol__bin_point(v->k, i, 0.5f, 0.5f);
        b->dirs[3 * i] = dir.x; b->dirs[3 * i + 1] = dir.y; b->dirs[3 * i + 2] = dir.z;
        b->dir_soa[i] = dir.x; b->dir_soa[v->bins + i] = dir.y; b->dir_soa[2 * v->bins + i] = dir.z;
    }
    irrvol__run_jobs(d->parallel_for, d->parallel_user, irrvol__weight_row_job, b, v->bins);
    b->bin_solid_angle = (float)(4.0 * IRRVOL__PI / v->bins);   /* eq. 4.2 */
    b->bin_angle = sqrtf(b->bin_solid_angle);
    if (d->materials && d->triangle_count) {
        uint32_t t, n = 0;
        for (t = 0; t < d->triangle_count; t++)
            if (d->materials[d->triangle_materials ? d->triangle_materials[t] : 0].flags & IRRVOL_MATERIAL_IMPORTANT) n++;
        if (n) {
            irrvol__mesh_view m = b->mesh;
            b->important = (uint32_t *)irrvol__alloc_array(a, n, sizeof(uint32_t));
            b->important_indices = (uint32_t *)irrvol__alloc_array(a, n, 3 * sizeof(uint32_t));
            if (!b->important || !b->important_indices) return IRRVOL_ERROR_OUT_OF_MEMORY;
            for (t = 0; t < d->triangle_count; t++)
                if (d->materials[d->triangle_materials ? d->triangle_materials[t] : 0].flags & IRRVOL_MATERIAL_IMPORTANT) {
                    memcpy(b->important_indices + 3 * (size_t)b->important_count, d->indices + 3 * (size_t)t,
                           3 * sizeof(uint32_t));
                    b->important[b->important_count++] = t;
                }
            m.indices = b->important_indices;
            m.tri_count = n;
            if (irrvol__bvh_build(&b->important_bvh, &m, a) != 0) return IRRVOL_ERROR_OUT_OF_MEMORY;
        }
    }
    return IRRVOL_OK;
}

/* Runs the sample jobs in batches; progress and cancel between batches. */
static irrvol_result irrvol__gather(irrvol__build *b)
{
    const irrvol_desc *d = b->desc;
    irrvol *v = b->vol;
    const irrvol_allocator *a = &v->allocator;
    size_t batch;
    uint32_t s;
    b->scratch_stride = (3 * (size_t)v->bins * sizeof(double) + 10 * (size_t)v->bins * sizeof(float) + v->bins + 63) &
                        ~(size_t)63;
    batch = IRRVOL__BATCH_BYTES / b->scratch_stride;
    batch = batch < 1 ? 1 : (batch > 256 ? 256 : batch);
    if (batch > v->sample_count) batch = v->sample_count;
    b->scratch = (unsigned char *)irrvol__alloc_array(a, batch, b->scratch_stride);
    b->ray_counts = (uint32_t *)irrvol__alloc_array(a, v->sample_count, sizeof(uint32_t));
    if (!b->scratch || !b->ray_counts) return IRRVOL_ERROR_OUT_OF_MEMORY;
    for (s = 0; s < v->sample_count;) {
        uint32_t n = v->sample_count - s < batch ? v->sample_count - s : (uint32_t)batch;
        b->batch_begin = s;
        irrvol__run_jobs(d->parallel_for, d->parallel_user, irrvol__sample_job, b, n);
        s += n;
        if (d->progress && d->progress(d->progress_user, s, v->sample_count)) {
            irrvol__log(d->log, d->log_user, "irrvol_build: cancelled by the progress callback");
            return IRRVOL_ERROR_CANCELLED;
        }
    }
    for (s = 0; s < v->sample_count; s++) v->rays += b->ray_counts[s];
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_build(const irrvol_desc *desc, irrvol **out)
{
    irrvol__build b;
    irrvol *v;
    irrvol_result r;
    uint64_t floats;
    if (out) *out = NULL;
    if (!desc || !out) return IRRVOL_ERROR_INVALID_ARGUMENT;
    r = irrvol__validate(desc);
    if (r != IRRVOL_OK) return r;
    memset(&b, 0, sizeof b);
    b.desc = desc;
    b.mesh.positions = desc->positions;
    b.mesh.stride = desc->position_stride;
    b.mesh.indices = desc->indices;
    b.mesh.tri_count = desc->triangle_count;
    b.supersamples = irrvol__def(desc->supersamples, 1u);
    b.weight_subdivisions = irrvol__def(desc->weight_subdivisions, 4u);
    b.max_depth = irrvol__def(desc->max_depth, 6u);
    b.min_weight = desc->min_weight > 0.0f ? desc->min_weight : 0.01f;
    for (b.important_side = 1; b.important_side * b.important_side < irrvol__def(desc->important_rays, 64u);)
        b.important_side++;
    v = b.vol = irrvol__create(&desc->allocator);
    if (!v) return IRRVOL_ERROR_OUT_OF_MEMORY;
    v->k = irrvol__def(desc->resolution, 17u);
    v->bins = 2 * v->k * v->k;
    v->kf = (float)v->k;
    v->moment = irrvol__def(desc->moment, 1u);
    v->filter = desc->filter == IRRVOL_FILTER_DEFAULT ? IRRVOL_FILTER_NEAREST : desc->filter;
    if (desc->triangle_count) v->degenerate = irrvol__count_degenerate(&b.mesh);
    r = irrvol__setup_grid(&b);
    if (r == IRRVOL_OK) {
        floats = (uint64_t)v->sample_count * v->bins * 3;
        if (floats > SIZE_MAX / sizeof(float)) r = IRRVOL_ERROR_OUT_OF_MEMORY;
    }
    if (r == IRRVOL_OK) {
        v->irradiance = (float *)irrvol__alloc_array(&v->allocator, (size_t)floats, sizeof(float));
        if (desc->keep_radiance)
            v->radiance = (float *)irrvol__alloc_array(&v->allocator, (size_t)floats, sizeof(float));
        if (!v->irradiance || (desc->keep_radiance && !v->radiance)) r = IRRVOL_ERROR_OUT_OF_MEMORY;
    }
    if (r == IRRVOL_OK && desc->triangle_count && !desc->radiance && !desc->trace &&
        irrvol__bvh_build(&b.bvh, &b.mesh, &v->allocator) != 0)
        r = IRRVOL_ERROR_OUT_OF_MEMORY;
    if (r == IRRVOL_OK) r = irrvol__setup_directions(&b);
    if (r == IRRVOL_OK) r = irrvol__gather(&b);
    irrvol__bvh_free(&b.bvh, &v->allocator);
    irrvol__free(&v->allocator, b.dirs);
    irrvol__free(&v->allocator, b.dir_soa);
    irrvol__free(&v->allocator, b.weights);
    irrvol__free(&v->allocator, b.important);
    irrvol__free(&v->allocator, b.important_indices);
    irrvol__bvh_free(&b.important_bvh, &v->allocator);
    irrvol__free(&v->allocator, b.scratch);
    irrvol__free(&v->allocator, b.ray_counts);
    if (r == IRRVOL_ERROR_OUT_OF_MEMORY) irrvol__log(desc->log, desc->log_user, "irrvol_build: out of memory");
    if (r != IRRVOL_OK) { irrvol_destroy(v); return r; }
    *out = v;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_info(const irrvol *vol, irrvol_volume_info *info)
{
    int k;
    if (!vol || !info) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memset(info, 0, sizeof *info);
    info->sample_count = vol->sample_count;
    info->first_level_samples = vol->first_level_count;
    info->second_level_samples = vol->sample_count - vol->first_level_count;
    for (k = 0; k < 3; k++) {
        info->grid_samples[k] = vol->samples[k];
        info->bounds_min[k] = vol->lo[k];
        info->bounds_max[k] = vol->hi[k];
    }
    info->subgrid_samples = vol->subgrid;
    info->cell_count = vol->cell_count;
    info->refined_cells = vol->refined_count;
    info->resolution = vol->k;
    info->bins = vol->bins;
    info->moment = vol->moment;
    info->filter = vol->filter;
    info->rays = vol->rays;
    info->degenerate_triangles = vol->degenerate;
    info->has_radiance = vol->radiance != NULL;
    info->bytes = irrvol__bytes(vol);
    return IRRVOL_OK;
}

/* ======================================================================
   12. queries (4.3): eq. 4.4-4.6 at either level, the bin of the direction,
   trilinear interpolation of the eight corner samples
   ---------------------------------------------------------------------- */
/* The eight samples around pos and their trilinear weights. Positions
   outside the bounds (and NaN) clamp to the boundary. */
IRRVOL__HOT void irrvol__locate(const irrvol *v, const float pos[3], uint32_t ids[8], float w[8])
{
    const irrvol__cell *cell;
    const uint32_t *t;
    uint32_t c[3], side, row, slab;
    float o[3], f;
    int d;
    for (d = 0; d < 3; d++) {
        float q = (pos[d] - v->lo[d]) * v->scale[d];            /* eq. 4.4 */
        q = q > 0.0f ? q : 0.0f;
        q = q < v->cell_limit[d] ? q : v->cell_limit[d];
        c[d] = (uint32_t)q;                                     /* eq. 4.5 */
        c[d] = c[d] < v->cells[d] ? c[d] : v->cells[d] - 1;     /* the upper face */
        o[d] = q - (float)c[d];                                 /* eq. 4.6 */
    }
    cell = &v->cell[c[0] + v->cells[0] * (c[1] + v->cells[1] * c[2])];
    side = cell->side;
    f = (float)(side - 1);
    for (d = 0; d < 3; d++) {   /* the same steps inside the cell's own table */
        float q = o[d] * f;
        c[d] = (uint32_t)q;
        c[d] = c[d] < side - 2 ? c[d] : side - 2;
        o[d] = q - (float)c[d];
    }
    row = side;
    slab = side * side;
    t = v->ids + cell->offset + c[0] + side * (c[1] + side * c[2]);
    ids[0] = t[0];          ids[1] = t[1];
    ids[2] = t[row];        ids[3] = t[row + 1];
    ids[4] = t[slab];       ids[5] = t[slab + 1];
    ids[6] = t[slab + row]; ids[7] = t[slab + row + 1];
    {
        float x1 = o[0], y1 = o[1], z1 = o[2], x0 = 1.0f - x1, y0 = 1.0f - y1, z0 = 1.0f - z1;
        w[0] = x0 * y0 * z0; w[1] = x1 * y0 * z0;
        w[2] = x0 * y1 * z0; w[3] = x1 * y1 * z0;
        w[4] = x0 * y0 * z1; w[5] = x1 * y0 * z1;
        w[6] = x0 * y1 * z1; w[7] = x1 * y1 * z1;
    }
}

/* The bin that contains the square point (u, v) of hemisphere h. */
IRRVOL__HOT uint32_t irrvol__square_bin(const irrvol *v, float u, float w, uint32_t h)
{
    uint32_t i = (uint32_t)(u * v->kf), j = (uint32_t)(w * v->kf);
    i = i < v->k ? i : v->k - 1;
    j = j < v->k ? j : v->k - 1;
    return (h * v->k + j) * v->k + i;
}

static uint32_t irrvol__nearest_bin(const irrvol *v, const float dir[3])
{
    float u, w;
    uint32_t h;
    irrvol__direction_to_square(dir, &u, &w, &h);
    return irrvol__square_bin(v, u, w, h);
}

/* The four bins around the square point (u, t) of hemisphere h and their
   bilinear weights (6.1.2). Past the outer bin centres the neighbour is the
   bin with the same (i, j) in the other hemisphere: both squares share their
   boundary, the equator. */
IRRVOL__HOT void irrvol__bilinear_bins(const irrvol *v, float u, float t, uint32_t h, uint32_t bins[4], float w[4])
{
    uint32_t k = v->k, i0, i1, j0, j1, ou0, ou1, ov0, ov1;
    float fu = u * v->kf - 0.5f, fv = t * v->kf - 0.5f, tu, tv;   /* in [-0.5, k - 0.5] */
    int iu = (int)(fu + 1.0f) - 1, iv = (int)(fv + 1.0f) - 1;    /* floor for f > -1 */
    tu = fu - (float)iu;
    tv = fv - (float)iv;
    ou0 = iu < 0;                           /* below the first centre */
    ov0 = iv < 0;
    ou1 = iu + 1 > (int)k - 1;              /* past the last centre */
    ov1 = iv + 1 > (int)k - 1;
    i0 = ou0 ? 0u : (uint32_t)iu;
    j0 = ov0 ? 0u : (uint32_t)iv;
    i1 = ou1 ? k - 1 : (uint32_t)iu + 1;
    j1 = ov1 ? k - 1 : (uint32_t)iv + 1;
    bins[0] = ((h ^ (ou0 | ov0)) * k + j0) * k + i0;
    bins[1] = ((h ^ (ou1 | ov0)) * k + j0) * k + i1;
    bins[2] = ((h ^ (ou0 | ov1)) * k + j1) * k + i0;
    bins[3] = ((h ^ (ou1 | ov1)) * k + j1) * k + i1;
    w[0] = (1.0f - tu) * (1.0f - tv);
    w[1] = tu * (1.0f - tv);
    w[2] = (1.0f - tu) * tv;
    w[3] = tu * tv;
}

/* A query reduced to the values it reads and their weights: eight corner
   samples times one bin (NEAREST) or four bins (BILINEAR), for the
   pipelined irrvol_query_many. */
typedef struct irrvol__prepared {
    const float *value[32];
    float weight[32];
    uint32_t count;
} irrvol__prepared;

IRRVOL__HOT void irrvol__prepare(const irrvol *vol, irrvol_filter filter, const float pos[3], const float dir[3],
                                 irrvol__prepared *q)
{
    uint32_t ids[8], c, h;
    float w[8], u, t;
    size_t stride = (size_t)vol->sample_count * 3;   /* one bin of all samples */
    irrvol__locate(vol, pos, ids, w);
    irrvol__direction_to_square(dir, &u, &t, &h);
    if (filter == IRRVOL_FILTER_DEFAULT) filter = vol->filter;
    if (filter == IRRVOL_FILTER_BILINEAR) {
        uint32_t bins[4], b;
        float bw[4];
        irrvol__bilinear_bins(vol, u, t, h, bins, bw);
        for (b = 0; b < 4; b++) {
            const float *s = vol->irradiance + bins[b] * stride;
            for (c = 0; c < 8; c++) {
                q->value[8 * b + c] = s + 3 * (size_t)ids[c];
                q->weight[8 * b + c] = w[c] * bw[b];
            }
        }
        q->count = 32;
    } else {
        const float *s = vol->irradiance + irrvol__square_bin(vol, u, t, h) * stride;
        for (c = 0; c < 8; c++) {
            q->value[c] = s + 3 * (size_t)ids[c];
            q->weight[c] = w[c];
        }
        q->count = 8;
    }
}

IRRVOL__HOT void irrvol__finish(const irrvol__prepared *q, float rgb[3])
{
    float r = 0.0f, g = 0.0f, b = 0.0f;
    uint32_t i;
    for (i = 0; i < q->count; i++) {
        const float *p = q->value[i];
        float x = q->weight[i];
        r += x * p[0]; g += x * p[1]; b += x * p[2];
    }
    rgb[0] = r; rgb[1] = g; rgb[2] = b;
}

/* One query: eight corner samples, the bin(s) of the direction, trilinear
   (and bilinear) weights. The same sums in the same order as prepare and
   finish, written out so that the single query keeps everything in
   registers. */
IRRVOL__HOT void irrvol__query(const irrvol *vol, irrvol_filter filter, const float pos[3],
                               const float dir[3], float rgb[3])
{
    uint32_t ids[8], c, h;
    float w[8], u, t, r = 0.0f, g = 0.0f, b = 0.0f;
    size_t stride = (size_t)vol->sample_count * 3;   /* one bin of all samples */
    irrvol__locate(vol, pos, ids, w);
    irrvol__direction_to_square(dir, &u, &t, &h);
    if (filter == IRRVOL_FILTER_DEFAULT) filter = vol->filter;
    if (filter == IRRVOL_FILTER_BILINEAR) {
        uint32_t bins[4], q;
        float bw[4];
        irrvol__bilinear_bins(vol, u, t, h, bins, bw);
        for (q = 0; q < 4; q++) {
            const float *s = vol->irradiance + bins[q] * stride;
            for (c = 0; c < 8; c++) {
                const float *p = s + 3 * (size_t)ids[c];
                float x = w[c] * bw[q];
                r += x * p[0]; g += x * p[1]; b += x * p[2];
            }
        }
    } else {
        const float *s = vol->irradiance + irrvol__square_bin(vol, u, t, h) * stride;
        for (c = 0; c < 8; c++) {
            const float *p = s + 3 * (size_t)ids[c];
            r += w[c] * p[0]; g += w[c] * p[1]; b += w[c] * p[2];
        }
    }
    rgb[0] = r; rgb[1] = g; rgb[2] = b;
}

IRRVOL_API void irrvol_query_filter(const irrvol *vol, irrvol_filter filter, const float pos[3],
                                    const float dir[3], float rgb[3])
{
    irrvol__query(vol, filter, pos, dir, rgb);
}

IRRVOL_API void irrvol_query(const irrvol *vol, const float pos[3], const float dir[3], float rgb[3])
{
    irrvol__query(vol, IRRVOL_FILTER_DEFAULT, pos, dir, rgb);
}

/* Fig. 4.17: a moment volume is queried along the view vector mirrored
   about the normal, Q = 2 (N . V) N - V. */
IRRVOL_API void irrvol_query_glossy(const irrvol *vol, const float pos[3], const float normal[3],
                                    const float to_eye[3], float rgb[3])
{
    float n2 = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2];
    float s = n2 > 0.0f ? 2.0f * (normal[0] * to_eye[0] + normal[1] * to_eye[1] + normal[2] * to_eye[2]) / n2 : 0.0f;
    float q[3];
    q[0] = s * normal[0] - to_eye[0];
    q[1] = s * normal[1] - to_eye[1];
    q[2] = s * normal[2] - to_eye[2];
    irrvol__query(vol, IRRVOL_FILTER_DEFAULT, pos, q, rgb);
}

/* Many queries, pipelined: each query is prepared IRRVOL__AHEAD queries
   before it is summed and its values are prefetched meanwhile, so the
   memory latency of one query overlaps the work of the next ones. The
   results equal irrvol_query_filter's bit for bit. */
IRRVOL_API void irrvol_query_many(const irrvol *vol, irrvol_filter filter, uint32_t count,
                                  const float *pos, size_t pos_stride, const float *dir,
                                  size_t dir_stride, float *rgb)
{
    irrvol__prepared ring[IRRVOL__AHEAD];
    uint32_t i, j;
    if (!pos_stride) pos_stride = 3 * sizeof(float);
    if (!dir_stride) dir_stride = 3 * sizeof(float);
    for (i = 0; i < count; i++) {
        irrvol__prepared *q = &ring[i % IRRVOL__AHEAD];
        if (i >= IRRVOL__AHEAD) irrvol__finish(q, rgb + 3 * (size_t)(i - IRRVOL__AHEAD));
        irrvol__prepare(vol, filter, (const float *)((const char *)pos + i * pos_stride),
                        (const float *)((const char *)dir + i * dir_stride), q);
        for (j = 0; j < q->count; j++) IRRVOL__PREFETCH(q->value[j]);
    }
    for (i = count > IRRVOL__AHEAD ? count - IRRVOL__AHEAD : 0; i < count; i++)
        irrvol__finish(&ring[i % IRRVOL__AHEAD], rgb + 3 * (size_t)i);
}

IRRVOL_API irrvol_result irrvol_sample(const irrvol *vol, uint32_t index, irrvol_sample_info *info)
{
    if (!vol || !info || index >= vol->sample_count) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memcpy(info->position, vol->positions + 3 * (size_t)index, sizeof info->position);
    info->level = index < vol->first_level_count ? 1 : 2;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_sample_values(const irrvol *vol, uint32_t index, float *irradiance, float *radiance)
{
    uint32_t bin;
    if (!vol || index >= vol->sample_count || (radiance && !vol->radiance)) return IRRVOL_ERROR_INVALID_ARGUMENT;
    for (bin = 0; bin < vol->bins; bin++) {
        size_t at = ((size_t)bin * vol->sample_count + index) * 3;
        if (irradiance) memcpy(irradiance + 3 * (size_t)bin, vol->irradiance + at, 3 * sizeof(float));
        if (radiance) memcpy(radiance + 3 * (size_t)bin, vol->radiance + at, 3 * sizeof(float));
    }
    return IRRVOL_OK;
}

/* Centre direction of a bin (unit); bins past the last give +z. */
IRRVOL_API void irrvol_bin_direction(const irrvol *vol, uint32_t bin, float dir[3])
{
    irrvol__vec3 d = irrvol__v3(0.0f, 0.0f, 1.0f);
    if (vol && bin < vol->bins) d = irrvol__bin_point(vol->k, bin, 0.5f, 0.5f);
    dir[0] = d.x; dir[1] = d.y; dir[2] = d.z;
}

IRRVOL_API uint32_t irrvol_direction_bin(const irrvol *vol, const float dir[3])
{
    return irrvol__nearest_bin(vol, dir);
}

/* ======================================================================
   13. self-occlusion of dynamic meshes (6.1.3)
   For each vertex, cosine-weighted stratified rays over the hemisphere
   around its normal (concentric disk lifted to the hemisphere, Malley's
   method) against the mesh's own BVH; the unoccluded fraction estimates the
   part of the vertex's irradiance the mesh does not block.
   ---------------------------------------------------------------------- */
typedef struct irrvol__visibility {
    const irrvol_visibility_desc *desc;
    irrvol__mesh_view mesh;
    irrvol__bvh bvh;
    float *normals;          /* computed normals, or NULL when given */
    uint32_t side;
    float offset, max_distance;
    uint32_t batch_begin;
    float *ratio;
} irrvol__visibility;

static irrvol__vec3 irrvol__visibility_normal(const irrvol__visibility *c, uint32_t vertex)
{
    const irrvol_visibility_desc *d = c->desc;
    if (d->normals) {
        size_t stride = d->normal_stride ? d->normal_stride : 3 * sizeof(float);
        return irrvol__normalize(irrvol__v3_load((const float *)((const char *)d->normals + vertex * stride)));
    }
    return irrvol__v3_load(c->normals + 3 * (size_t)vertex);
}

static void irrvol__visibility_job(void *ctx, uint32_t index)
{
    irrvol__visibility *c = (irrvol__visibility *)ctx;
    uint32_t vertex = c->batch_begin + index, x, y, open = 0;
    irrvol__vec3 n = irrvol__visibility_normal(c, vertex), t, bt, p;
    irrvol__rng rng = irrvol__rng_stream(c->desc->seed, vertex);
    float org[3];
    if (irrvol__dot(n, n) == 0.0f) { c->ratio[vertex] = 1.0f; return; }   /* no normal: nothing to say */
    irrvol__basis(n, &t, &bt);
    p = irrvol__add(irrvol__v3_load(irrvol__vertex(&c->mesh, vertex)), irrvol__scale(n, c->offset));
    org[0] = p.x; org[1] = p.y; org[2] = p.z;
    for (y = 0; y < c->side; y++)
        for (x = 0; x < c->side; x++) {
            float dx, dy, dir[3], z;
            irrvol__vec3 d;
            irrvol__square_to_disk(((float)x + irrvol__rng_float(&rng)) / (float)c->side,
                                   ((float)y + irrvol__rng_float(&rng)) / (float)c->side, &dx, &dy);
            z = sqrtf(irrvol__maxf(0.0f, 1.0f - dx * dx - dy * dy));
            d = irrvol__add(irrvol__add(irrvol__scale(t, dx), irrvol__scale(bt, dy)), irrvol__scale(n, z));
            dir[0] = d.x; dir[1] = d.y; dir[2] = d.z;
            if (!irrvol__bvh_occluded(&c->bvh, org, dir, 0.0f, c->max_distance)) open++;
        }
    c->ratio[vertex] = (float)open / (float)(c->side * c->side);
}

static irrvol_result irrvol__validate_visibility(const irrvol_visibility_desc *d)
{
    size_t stride = d->position_stride ? d->position_stride : 3 * sizeof(float);
    size_t nstride = d->normal_stride ? d->normal_stride : 3 * sizeof(float);
    uint32_t i;
    if (!irrvol__allocator_valid(&d->allocator))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: allocator needs both alloc and free, or neither");
    if (!d->positions || !d->indices || !d->vertex_count || !d->triangle_count)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: needs positions, indices and counts");
    if (stride < 3 * sizeof(float) || nstride < 3 * sizeof(float))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: a stride under 3 floats");
    if (d->rays > 65536 || !(d->ray_offset >= 0.0f) || !isfinite(d->ray_offset) ||
        !(d->max_distance >= 0.0f) || !isfinite(d->max_distance))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: rays, ray_offset or max_distance out of range");
    for (i = 0; i < d->vertex_count; i++) {
        if (!irrvol__finite3((const float *)((const char *)d->positions + (size_t)i * stride)))
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: a position is NaN or infinite");
        if (d->normals && !irrvol__finite3((const float *)((const char *)d->normals + (size_t)i * nstride)))
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: a normal is NaN or infinite");
    }
    for (i = 0; i < 3 * d->triangle_count; i++)
        if (d->indices[i] >= d->vertex_count)
            IRRVOL__REJECT(d->log, d->log_user, "irrvol_visibility_ratio: a vertex index is out of range");
    return IRRVOL_OK;
}

/* Area-weighted vertex normals: the sum of the faces' cross products. */
static void irrvol__vertex_normals(const irrvol__mesh_view *m, uint32_t vertex_count, float *normals)
{
    uint32_t t, i;
    memset(normals, 0, 3 * (size_t)vertex_count * sizeof(float));
    for (t = 0; t < m->tri_count; t++) {
        irrvol__vec3 p0 = irrvol__v3_load(irrvol__vertex(m, m->indices[3 * t]));
        irrvol__vec3 c = irrvol__cross(irrvol__sub(irrvol__v3_load(irrvol__vertex(m, m->indices[3 * t + 1])), p0),
                                       irrvol__sub(irrvol__v3_load(irrvol__vertex(m, m->indices[3 * t + 2])), p0));
        for (i = 0; i < 3; i++) {
            float *n = normals + 3 * (size_t)m->indices[3 * t + i];
            n[0] += c.x; n[1] += c.y; n[2] += c.z;
        }
    }
    for (i = 0; i < vertex_count; i++) {
        irrvol__vec3 n = irrvol__normalize(irrvol__v3_load(normals + 3 * (size_t)i));
        normals[3 * i] = n.x; normals[3 * i + 1] = n.y; normals[3 * i + 2] = n.z;
    }
}

IRRVOL_API irrvol_result irrvol_visibility_ratio(const irrvol_visibility_desc *desc, float *ratio)
{
    irrvol__visibility c;
    irrvol_result r = IRRVOL_OK;
    uint32_t v, rays;
    float lo[3], hi[3];
    if (!desc || !ratio) return IRRVOL_ERROR_INVALID_ARGUMENT;
    r = irrvol__validate_visibility(desc);
    if (r != IRRVOL_OK) return r;
    memset(&c, 0, sizeof c);
    c.desc = desc;
    c.ratio = ratio;
    c.mesh.positions = desc->positions;
    c.mesh.stride = desc->position_stride;
    c.mesh.indices = desc->indices;
    c.mesh.tri_count = desc->triangle_count;
    rays = irrvol__def(desc->rays, 64u);
    for (c.side = 1; c.side * c.side < rays;) c.side++;
    irrvol__scene_bounds(&c.mesh, lo, hi);
    c.offset = desc->ray_offset > 0.0f ? desc->ray_offset
             : 1e-4f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                             (hi[2] - lo[2]) * (hi[2] - lo[2]));
    c.max_distance = desc->max_distance > 0.0f ? desc->max_distance : FLT_MAX;
    if (!desc->normals) {
        c.normals = (float *)irrvol__alloc_array(&desc->allocator, (size_t)desc->vertex_count * 3, sizeof(float));
        if (!c.normals) return IRRVOL_ERROR_OUT_OF_MEMORY;
        irrvol__vertex_normals(&c.mesh, desc->vertex_count, c.normals);
    }
    if (irrvol__bvh_build(&c.bvh, &c.mesh, &desc->allocator) != 0) r = IRRVOL_ERROR_OUT_OF_MEMORY;
    for (v = 0; r == IRRVOL_OK && v < desc->vertex_count;) {
        uint32_t n = desc->vertex_count - v < 4096 ? desc->vertex_count - v : 4096;
        c.batch_begin = v;
        irrvol__run_jobs(desc->parallel_for, desc->parallel_user, irrvol__visibility_job, &c, n);
        v += n;
        if (desc->progress && desc->progress(desc->progress_user, v, desc->vertex_count)) r = IRRVOL_ERROR_CANCELLED;
    }
    irrvol__bvh_free(&c.bvh, &desc->allocator);
    irrvol__free(&desc->allocator, c.normals);
    return r;
}

/* ======================================================================
   14. save and load (file format version 1)
   magic "IRRVOL\x1a\n", version u32, payload size u64, payload, CRC32.
   Payload: k, moment, filter, flags (bit 0: radiance stored), first-level
   samples x y z, subgrid samples, bounds min xyz, max xyz, sample count,
   rays (u64), degenerate triangles, one byte per first-level cell (1 =
   refined), irradiance floats (bin-major: for each bin, rgb of every
   sample), radiance floats when flagged. The grid
   tables and sample positions are rebuilt from these on load.
   ---------------------------------------------------------------------- */
static const unsigned char irrvol__magic[8] = {'I', 'R', 'R', 'V', 'O', 'L', 0x1a, '\n'};
#define IRRVOL__HEADER_FIELDS 72u   /* payload bytes before the cell flags */

static irrvol_result irrvol__write_all(const irrvol *v, irrvol__writer *w)
{
    uint64_t floats = (uint64_t)v->sample_count * v->bins * 3;
    uint64_t payload = IRRVOL__HEADER_FIELDS + v->cell_count + floats * 4 * (v->radiance ? 2 : 1);
    unsigned char flags[256];
    uint32_t c, k;
    irrvol__crc_init(&w->crc);
    irrvol__put(w, irrvol__magic, 8);
    irrvol__put_u32(w, IRRVOL_FILE_FORMAT_VERSION);
    irrvol__put_u64(w, payload);
    irrvol__put_u32(w, v->k);
    irrvol__put_u32(w, v->moment);
    irrvol__put_u32(w, (uint32_t)v->filter);
    irrvol__put_u32(w, v->radiance ? 1u : 0u);
    for (k = 0; k < 3; k++) irrvol__put_u32(w, v->samples[k]);
    irrvol__put_u32(w, v->subgrid);
    for (k = 0; k < 3; k++) irrvol__put_f32(w, v->lo[k]);
    for (k = 0; k < 3; k++) irrvol__put_f32(w, v->hi[k]);
    irrvol__put_u32(w, v->sample_count);
    irrvol__put_u64(w, v->rays);
    irrvol__put_u32(w, v->degenerate);
    for (c = 0; c < v->cell_count;) {   /* refined flags, 256 at a time */
        uint32_t n = v->cell_count - c < 256 ? v->cell_count - c : 256, i;
        for (i = 0; i < n; i++) flags[i] = v->cell[c + i].side > 2 ? 1 : 0;
        irrvol__put(w, flags, n);
        c += n;
    }
    irrvol__put_f32_array(w, v->irradiance, (size_t)floats);
    if (v->radiance) irrvol__put_f32_array(w, v->radiance, (size_t)floats);
    irrvol__put_u32(w, irrvol__crc_final(&w->crc));
    return w->failed ? IRRVOL_ERROR_IO : IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_save(const irrvol *vol, irrvol_write_fn write, void *user)
{
    irrvol__writer w;
    if (!vol || !write) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memset(&w, 0, sizeof w);
    w.write = write;
    w.user = user;
    return irrvol__write_all(vol, &w);
}

/* Reads n floats (little-endian) and checks they are finite. */
static int irrvol__get_finite_array(irrvol__reader *r, float *f, size_t n)
{
    unsigned char buf[4096];
    size_t i = 0;
    while (i < n && !r->failed) {
        size_t m = n - i < sizeof buf / 4 ? n - i : sizeof buf / 4, j;
        irrvol__get(r, buf, 4 * m);
        for (j = 0; j < m; j++, i++) {
            const unsigned char *b = buf + 4 * j;
            uint32_t u = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
            memcpy(&f[i], &u, 4);
            if (!isfinite(f[i])) { r->failed = 1; return 0; }
        }
    }
    return !r->failed;
}

/* Header fields; 0 when they describe a volume this version can hold. */
static int irrvol__read_fields(irrvol__reader *r, irrvol *v, uint32_t *flags, uint32_t *declared_samples)
{
    uint32_t samples[3], filter, subgrid;
    int k;
    v->k = irrvol__get_u32(r);
    v->moment = irrvol__get_u32(r);
    filter = irrvol__get_u32(r);
    *flags = irrvol__get_u32(r);
    for (k = 0; k < 3; k++) samples[k] = irrvol__get_u32(r);
    subgrid = irrvol__get_u32(r);
    for (k = 0; k < 3; k++) v->lo[k] = irrvol__get_f32(r);
    for (k = 0; k < 3; k++) v->hi[k] = irrvol__get_f32(r);
    *declared_samples = irrvol__get_u32(r);
    v->rays = irrvol__get_u64(r);
    v->degenerate = irrvol__get_u32(r);
    if (r->failed || v->k < 1 || v->k > IRRVOL_MAX_RESOLUTION || v->moment < 1 || v->moment > IRRVOL_MAX_MOMENT ||
        (filter != IRRVOL_FILTER_NEAREST && filter != IRRVOL_FILTER_BILINEAR) || *flags > 1u ||
        subgrid < 2 || subgrid > IRRVOL_MAX_SUBGRID_SAMPLES)
        return -1;
    for (k = 0; k < 3; k++)
        if (samples[k] < 2 || samples[k] > IRRVOL_MAX_GRID_SAMPLES || !isfinite(v->lo[k]) || !isfinite(v->hi[k]) ||
            !(v->lo[k] < v->hi[k]) || !isfinite(v->hi[k] - v->lo[k]))
            return -1;
    v->filter = (irrvol_filter)filter;
    v->bins = 2 * v->k * v->k;
    v->kf = (float)v->k;
    irrvol__grid_dims(v, samples, subgrid);
    return 0;
}

static irrvol_result irrvol__read_all(irrvol *v, irrvol__reader *r)
{
    const irrvol_allocator *a = &v->allocator;
    unsigned char magic[8], *refined;
    uint32_t version, flags, declared, c, refined_count = 0, expected_crc;
    uint64_t floats, inner;
    irrvol_result res;
    irrvol__crc_init(&r->crc);
    r->remaining = 20;
    irrvol__get(r, magic, 8);
    version = irrvol__get_u32(r);
    r->remaining = irrvol__get_u64(r);
    if (r->failed || memcmp(magic, irrvol__magic, 8) != 0) return IRRVOL_ERROR_CORRUPT_DATA;
    if (version != IRRVOL_FILE_FORMAT_VERSION) return IRRVOL_ERROR_VERSION;
    if (irrvol__read_fields(r, v, &flags, &declared) != 0) return IRRVOL_ERROR_CORRUPT_DATA;
    /* every size is checked against the payload before anything is allocated */
    if (!irrvol__can_hold(r, v->cell_count, 1)) return IRRVOL_ERROR_CORRUPT_DATA;
    refined = (unsigned char *)irrvol__alloc(a, v->cell_count);
    if (!refined) return IRRVOL_ERROR_OUT_OF_MEMORY;
    irrvol__get(r, refined, v->cell_count);
    for (c = 0; c < v->cell_count; c++) {
        if (refined[c] > 1 || (refined[c] && v->subgrid == 2)) r->failed = 1;
        refined_count += refined[c];
    }
    /* each refined cell owns its (side - 2)^3 interior samples: a lower bound */
    inner = (uint64_t)(v->subgrid - 2) * (v->subgrid - 2) * (v->subgrid - 2);
    floats = (uint64_t)declared * v->bins * 3;
    if (r->failed || (uint64_t)v->first_level_count + refined_count * inner > declared ||
        !irrvol__can_hold(r, floats, flags ? 8 : 4)) {
        irrvol__free(a, refined);
        return IRRVOL_ERROR_CORRUPT_DATA;
    }
    res = irrvol__make_grid(v, refined);
    irrvol__free(a, refined);
    if (res != IRRVOL_OK) return res;
    if (v->sample_count != declared) return IRRVOL_ERROR_CORRUPT_DATA;
    v->irradiance = (float *)irrvol__alloc_array(a, (size_t)floats, sizeof(float));
    if (flags) v->radiance = (float *)irrvol__alloc_array(a, (size_t)floats, sizeof(float));
    if (!v->irradiance || (flags && !v->radiance)) return IRRVOL_ERROR_OUT_OF_MEMORY;
    if (!irrvol__get_finite_array(r, v->irradiance, (size_t)floats)) return IRRVOL_ERROR_CORRUPT_DATA;
    if (flags && !irrvol__get_finite_array(r, v->radiance, (size_t)floats)) return IRRVOL_ERROR_CORRUPT_DATA;
    if (r->remaining != 0) return IRRVOL_ERROR_CORRUPT_DATA;   /* payload longer than its contents */
    expected_crc = irrvol__crc_final(&r->crc);
    r->remaining = 4;
    if (irrvol__get_u32(r) != expected_crc || r->failed) return IRRVOL_ERROR_CORRUPT_DATA;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_load(const irrvol_allocator *allocator, irrvol_read_fn read, void *user,
                                     irrvol **out)
{
    irrvol_allocator a;
    irrvol__reader r;
    irrvol *v;
    irrvol_result res;
    if (out) *out = NULL;
    if (!read || !out) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memset(&a, 0, sizeof a);
    if (allocator) a = *allocator;
    if (!irrvol__allocator_valid(&a)) return IRRVOL_ERROR_INVALID_ARGUMENT;
    v = irrvol__create(&a);
    if (!v) return IRRVOL_ERROR_OUT_OF_MEMORY;
    memset(&r, 0, sizeof r);
    r.read = read;
    r.user = user;
    res = irrvol__read_all(v, &r);
    if (res != IRRVOL_OK) { irrvol_destroy(v); return res; }
    *out = v;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_save_to_memory(const irrvol *vol, const irrvol_allocator *allocator,
                                               void **data, size_t *size)
{
    irrvol_allocator a;
    irrvol__membuf m;
    irrvol_result r;
    if (data) *data = NULL;
    if (size) *size = 0;
    if (!vol || !data || !size) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memset(&a, 0, sizeof a);
    if (allocator) a = *allocator;
    if (!irrvol__allocator_valid(&a)) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memset(&m, 0, sizeof m);
    m.a = &a;
    r = irrvol_save(vol, irrvol__membuf_write, &m);
    if (r != IRRVOL_OK) {
        irrvol__free(&a, m.data);
        return r == IRRVOL_ERROR_IO ? IRRVOL_ERROR_OUT_OF_MEMORY : r;   /* only growth can fail */
    }
    *data = m.data;
    *size = m.size;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_load_from_memory(const void *data, size_t size,
                                                 const irrvol_allocator *allocator, irrvol **out)
{
    irrvol__membuf m;
    if (out) *out = NULL;
    if (!data || !out) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memset(&m, 0, sizeof m);
    m.data = (unsigned char *)(uintptr_t)data;   /* read only */
    m.size = size;
    return irrvol_load(allocator, irrvol__membuf_read, &m, out);
}

IRRVOL_API void irrvol_free_memory(const irrvol_allocator *allocator, void *data)
{
    irrvol_allocator a;
    memset(&a, 0, sizeof a);
    if (allocator) a = *allocator;
    if (!irrvol__allocator_valid(&a)) return;
    irrvol__free(&a, data);
}

IRRVOL_API const char *irrvol_result_string(irrvol_result r)
{
    switch (r) {
    case IRRVOL_OK: return "ok";
    case IRRVOL_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case IRRVOL_ERROR_OUT_OF_MEMORY: return "out of memory";
    case IRRVOL_ERROR_CORRUPT_DATA: return "corrupt data";
    case IRRVOL_ERROR_VERSION: return "unsupported format version";
    case IRRVOL_ERROR_CANCELLED: return "cancelled";
    case IRRVOL_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* IRRVOL_IMPLEMENTATION */

/*
------------------------------------------------------------------------------
This software is available under 2 licenses -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT License
Copyright (c) 2026 The irrvol/radinterp/lightvec/rendercache authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:
The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.
In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication for the benefit of the public at large and to
the detriment of our heirs and successors. We intend this dedication to be an
overt act of relinquishment in perpetuity of all present and future rights to
this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN
ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION
WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
------------------------------------------------------------------------------
*/
