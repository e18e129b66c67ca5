/* radinterp.h - v0.2.0 - radiosity with per-pixel quadratic irradiance interpolants - public domain or MIT, see end of file

   RADINTERP.H: hierarchical radiosity, ranked discontinuities and quadratic irradiance interpolants evaluated per pixel.

   This version holds the offline foundation of Hardt's method: a
   hierarchical radiosity solver over planar convex patches (chapter 4) and
   an accurate irradiance-at-a-point query with exact visibility by
   backprojection onto the sources (chapter 6), plus the robust constrained
   Delaunay triangulation both need. The discontinuity mesh, the quadratic
   interpolants and the per-pixel phase build on it.

   DO THIS

       #define RADINTERP_IMPLEMENTATION
       #include "radinterp.h"

   in exactly one C or C++ file; include "radinterp.h" without the define
   everywhere else.

   EXAMPLE

       radinterp_material mat[2] = {
           {{0.7f, 0.7f, 0.7f}, {0, 0, 0}},            // grey wall
           {{0.8f, 0.8f, 0.8f}, {100.f, 100.f, 100.f}} // emitter: E = pi * Ke
       };
       radinterp_desc d = {0};
       radinterp_solution *sol;
       float rgb[3];
       d.positions = xyz;  d.vertex_count = nv;
       d.patches = quads;  d.patch_count = np;    // 4 indices per patch
       d.patch_materials = mat_of_patch;
       d.materials = mat;  d.material_count = 2;
       if (radinterp_solve(&d, &sol) != RADINTERP_OK) ...;
       radinterp_irradiance_at_point(sol, patch, point, NULL, rgb);  // W/m^2
       radinterp_solution_destroy(sol);

   SCENE AND UNITS

   A patch is a planar convex polygon of 3 or 4 vertices given by indices
   into `positions` (4 per patch; the 4th is RADINTERP_NO_VERTEX for a
   triangle), counter-clockwise seen from the side that reflects and emits
   light (its front; the back is invisible, as in a radiosity solver). Patches
   must not interpenetrate. A material has a diffuse reflectance rho in [0, 1]
   and an emission E: the radiosity the patch emits by itself, in W/m^2. A
   diffuse emitter of radiance L emits E = pi * L, so a caller reading an MTL
   file, whose Ke is emitted radiance, passes E = pi * Ke. Radiosity
   B = E + rho * H where H is the irradiance (W/m^2); the outgoing radiance of
   a patch is B / pi.

   Validation: NULL arrays, zero counts, indices out of range, NaN or infinite
   coordinates or material values, reflectance outside [0, 1], negative
   emission, non-planar quadrilaterals (4th vertex farther than
   planarity_tolerance times the patch diagonal from the plane of the other
   three) and non-convex or self-intersecting quadrilaterals give
   RADINTERP_ERROR_INVALID_ARGUMENT, with the patch named through the log
   callback. Zero-area patches are skipped and counted (info.skipped_patches);
   repeated or collinear corners reduce a quadrilateral to a triangle.

   METHOD

   radinterp_solve (chapter 4): one quadtree per patch (quadrilaterals and
   triangles split in four at their edge midpoints); a link between every
   ordered pair of patches that face each other, with its potential blockers
   from shaft culling (Haines and Wallace) through a BVH of the patches; link
   form factors = the mean of eq. 6.1 at a jittered grid of receiver points,
   each scaled by the visible fraction of the source (shadow rays through the
   BVH or desc.trace), with horizon clipping of both elements (4.2); Jacobi
   gather + push-pull iterations (4.3); after each, transport refinement
   (4.4.1): a link whose B_src times the spread of the point factors over
   its receiver (taken at fixed points) exceeds eps is split at its larger
   element, and a link whose source's children differ by more than eps / F
   is split at the source. Parts of a patch enclosed by geometry resting on
   it (the floor under a box) are found by rays and left out of its
   radiosity (radinterp_leaf.open).

   radinterp_irradiance_at_point (chapter 6): the sum of B_src * F over the
   links of the leaf containing p and of its ancestors. F is eq. 6.1 for the
   source clipped to p's tangent plane and moved push_off behind its plane;
   with blockers, every blocker's part inside the pyramid from p to the
   source (cut in 3D) is projected onto the source plane: its shadow. A
   source point is hidden exactly when it lies in a shadow, so F is eq. 6.1
   of the source minus eq. 6.1 of the union of the shadows, which is built
   as disjoint convex pieces (each shadow minus the pieces so far; faces
   turned toward p first), eq. 6.1 being additive over a partition. Every
   piece edge keeps the line of the plane that made it, never a line
   through two computed corners, so no decision rests on rounding noise; a
   shadow that cannot be represented so (a sliver between nearly equal
   lines, more than 48 pieces) sends that source to Hardt's method:
   the source outline and the projected edges go into a constrained
   Delaunay triangulation (exact adaptive predicates), one ray per region
   decides whether it is visible, and eq. 6.1 over the visible triangles
   gives F (desc.visibility selects it for every source). A projected
   blocker that covers the whole source ends the work early. Where a source
   node's children differ enough to matter at p, they are used in its
   place.

   PARAMETERS (Hardt, appendix A; zero means the default)

       eps                Gur::eps, transport error bound in W/m^2: a link is
                          refined while B_src * (max - min of the point form
                          factors over its receiver) exceeds it.
                          default half the mean emitted radiosity (emitted
                          power / total area): 0.13 W/m^2 for the office,
                          near the paper's 0.1
       min_area           Gur::aeps, no node is split into children smaller
                          than this (m^2).          default (diagonal / 200)^2
       rel_error_cutoff   Basis::relErrorCutoff, convergence: every leaf's
                          radiosity changes by less than this fraction in an
                          iteration.                                default 1e-3
       max_iterations     gather/push-pull iterations at most.       default 64
       ff_samples         receiver points per link form factor (a square
                          number gives a jittered grid).              default 9
       visibility_rays    shadow rays per receiver point when shaft culling
                          left blockers (weighted like the form factor).
                                                                      default 8
       push_off           Polygon::ffPushOff: sources are moved this far behind
                          their plane in point queries (6.4). default 1e-5 * diag
       nudge              nudgeAmt: a query point moves this far toward
                          `toward` for visibility (6.3).       default 1e-6 * diag
       min_bp_segment     Backprojection::minBPSegment: shorter projected blocker
                          edges are not inserted.             default 1e-9 * diag
       epsilon            _m_eps_f: coordinates closer than epsilon * diag are
                          equal (facing and coplanarity tests). default 1e-6
       planarity_tolerance  see validation.                      default 1e-3
       visibility         how point queries find the visible part of a partly
                          hidden source: RADINTERP_VISIBILITY_SHADOWS (the
                          default) or RADINTERP_VISIBILITY_TRIANGULATION
                          (Hardt's CDT and rays, slower; same results).
   `diag` is the diagonal of the scene's bounding box.

   CONFIGURATION MACROS

       RADINTERP_STATIC          make every function static (private to one file)
       RADINTERP_API             linkage of public functions (default: extern)
       RADINTERP_MALLOC, RADINTERP_FREE  replace malloc/free (define both or neither)
       RADINTERP_BVH_BINS        SAH bins of the built-in BVH (default 16)

   FUNCTION REFERENCE

       const char *radinterp_result_string(radinterp_result r);   name of an error code
       radinterp_result radinterp_solve(const radinterp_desc *desc, radinterp_solution **out);
                                    hierarchical radiosity solution of the scene
       void radinterp_solution_destroy(radinterp_solution *s);
       void radinterp_solution_info(const radinterp_solution *s, radinterp_info *info);
       radinterp_result radinterp_patch_radiosity(const radinterp_solution *s, uint32_t patch, float rgb[3]);
                                    area-average radiosity B of a patch (enclosed parts at E)
       uint32_t radinterp_leaf_count(const radinterp_solution *s);
       radinterp_result radinterp_get_leaf(const radinterp_solution *s, uint32_t index, radinterp_leaf *leaf);
                                    the quadtree leaves (elements) with their radiosity
       radinterp_result radinterp_irradiance_at_point(const radinterp_solution *s, uint32_t patch,
                                    const float p[3], const float toward[3], float rgb[3]);
                                    Hardt's IrradianceAtPoint (chapter 6), W/m^2
       radinterp_result radinterp_radiosity_at_point(const radinterp_solution *s, uint32_t patch,
                                    const float p[3], const float toward[3], float rgb[3]);
                                    E + rho * IrradianceAtPoint
       double radinterp_form_factor_point_polygon(const float p[3], const float n[3],
                                    const float *verts, uint32_t count);
                                    differential area to polygon form factor (eq. 6.1)

   THREADS

   radinterp_solve runs its independent work (link form factors, open
   fractions, gathers, push-pull) through desc.parallel_for when given;
   results are bit-identical for any thread count. A trace callback must then
   be thread-safe. Queries on a finished solution are const and may run from
   many threads at once; each uses up to about 100 KB of stack (its
   triangulation moves to the allocator only when it outgrows 32 KB).

   LIMITS

   Patches are planar convex polygons of 3 or 4 vertices (curved surfaces must
   be tessellated by the caller). Links are directional (one per receiver and
   source) and there is no clustering, so the initial linking is quadratic in
   the patch count: the method suits scenes of hundreds to a few thousand
   patches, as the paper's. Radiosity is constant over each element, so
   points a few millimetres from a corner, or at the foot of an object, see
   their nearest sources at the elements' mean: expect errors of several
   percent there (about 2% on average elsewhere in the Cornell box with
   eps = 5 mW/m^2). A point query costs a shadow union per partly visible
   source: about 6,700 per second on one core on the office scene, where
   nearly every point has one (about 28 such sources of 52, 5.6 shadows
   each), and over 300,000 per second where none is; with the triangulation
   method about 2,200.

   PAPER

       Stephen L. Hardt, High Fidelity Radiosity Rendering at Interactive Rates, M.Eng. thesis, MIT, 1996.
       Hanrahan, Salzman, Aupperle, A Rapid Hierarchical Radiosity Algorithm, SIGGRAPH 1991.
       Haines, Wallace, Shaft Culling for Efficient Ray-Traced Radiosity, 1991.
       Shewchuk, Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates, 1997.
*/
#ifndef RADINTERP_H
#define RADINTERP_H

#define RADINTERP_VERSION_MAJOR 0
#define RADINTERP_VERSION_MINOR 2
#define RADINTERP_VERSION_PATCH 0

#include <stddef.h>
#include <stdint.h>

#ifndef RADINTERP_API
#  ifdef RADINTERP_STATIC
#    define RADINTERP_API static
#  else
#    define RADINTERP_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum radinterp_result {
    RADINTERP_OK = 0,
    RADINTERP_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    RADINTERP_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    RADINTERP_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    RADINTERP_ERROR_VERSION,           /* serialized data has an unsupported format version */
    RADINTERP_ERROR_CANCELLED,         /* the progress callback asked to stop */
    RADINTERP_ERROR_IO                 /* a read or write callback failed */
} radinterp_result;

/* The 4th index of a triangular patch. */
#define RADINTERP_NO_VERTEX 0xFFFFFFFFu

typedef struct radinterp_allocator {
    void *(*alloc)(size_t size, void *user);  /* NULL: RADINTERP_MALLOC */
    void (*free)(void *ptr, void *user);      /* NULL: RADINTERP_FREE */
    void *user;
} radinterp_allocator;

typedef void (*radinterp_job_fn)(void *ctx, uint32_t index);

/* A ray hit as Embree reports it: u, v = barycentric weights of the
   triangle's 2nd and 3rd vertex. */
typedef struct radinterp_hit {
    float t;
    float u, v;
    uint32_t triangle;
} radinterp_hit;

/* Replaces the built-in BVH for the solver's shadow rays: returns 1 when
   anything lies along org + t * dir for 0 < t < tmax (dir has unit length). */
typedef int (*radinterp_trace_fn)(void *user, const float org[3], const float dir[3], float tmax,
                                  radinterp_hit *hit);

typedef struct radinterp_material {
    float reflectance[3];  /* diffuse reflectance rho, each in [0, 1] */
    float emission[3];     /* emitted radiosity E in W/m^2 (= pi * emitted radiance, e.g. pi * Ke of an MTL file) */
} radinterp_material;

/* How IrradianceAtPoint finds the part of a partly hidden source that a
   point sees (desc.visibility). Both give the exact visible form factor; the
   triangulation is Hardt's method (6.2.3), kept for comparison. */
typedef enum radinterp_visibility {
    RADINTERP_VISIBILITY_DEFAULT = 0,          /* = RADINTERP_VISIBILITY_SHADOWS */
    RADINTERP_VISIBILITY_SHADOWS = 1,          /* F(source) - F(union of the blockers' shadows), shadows as convex pieces */
    RADINTERP_VISIBILITY_TRIANGULATION = 2     /* CDT of the projected blocker edges, one ray per region */
} radinterp_visibility;

typedef struct radinterp_desc {
    /* scene */
    const float *positions;            /* xyz per vertex */
    size_t position_stride;            /* bytes between vertices; 0 = 3 floats */
    uint32_t vertex_count;
    const uint32_t *patches;           /* 4 vertex indices per patch; 4th = RADINTERP_NO_VERTEX for a triangle */
    uint32_t patch_count;
    const uint32_t *patch_materials;   /* material of each patch; NULL = material 0 for all */
    const radinterp_material *materials;
    uint32_t material_count;

    /* parameters, see PARAMETERS above; zero = default */
    float eps;
    float min_area;
    float rel_error_cutoff;
    uint32_t max_iterations;
    uint32_t ff_samples;
    uint32_t visibility_rays;
    float push_off;
    float nudge;
    float min_bp_segment;
    float epsilon;
    float planarity_tolerance;
    radinterp_visibility visibility;   /* point queries' visibility method, see PARAMETERS */
    uint64_t seed;                     /* random choices (sample points); results depend only on it */

    /* optional callbacks */
    radinterp_trace_fn trace;          /* NULL: the built-in BVH over the patches */
    void *trace_user;
    radinterp_allocator allocator;
    void (*parallel_for)(void *user, radinterp_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    int (*progress)(void *user, uint64_t done, uint64_t total);  /* non-zero cancels */
    void *progress_user;
    void (*log)(void *user, const char *message);
    void *log_user;
} radinterp_desc;

typedef struct radinterp_solution radinterp_solution;

typedef struct radinterp_info {
    uint32_t patch_count;        /* patches given */
    uint32_t skipped_patches;    /* zero-area patches left out */
    uint32_t node_count;         /* quadtree nodes, roots included */
    uint32_t leaf_count;         /* quadtree leaves (elements) */
    uint32_t link_count;         /* links (one per receiver node and source node) */
    uint64_t blocker_entries;    /* sum of the links' blocker-list lengths */
    uint32_t iterations;         /* gather/push-pull iterations run */
    int converged;               /* the last iteration changed no leaf by more than rel_error_cutoff */
    float max_relative_change;   /* of the last iteration */
    uint64_t shadow_rays;        /* rays cast for link visibility */
    size_t bytes;                /* memory held by the solution */
} radinterp_info;

/* One quadtree leaf: a convex polygon of 3 or 4 corners on its patch. */
typedef struct radinterp_leaf {
    uint32_t patch;
    uint32_t depth;              /* 0 = the patch itself */
    uint32_t vertex_count;       /* 3 or 4 */
    float vertices[4][3];
    float radiosity[3];          /* B of the element's open part, W/m^2 */
    float area;
    float open;                  /* fraction of the element not enclosed by geometry resting on it
                                    (the floor under a box): enclosed parts are dark, at radiosity E */
} radinterp_leaf;

RADINTERP_API const char *radinterp_result_string(radinterp_result r);

RADINTERP_API radinterp_result radinterp_solve(const radinterp_desc *desc, radinterp_solution **out);
RADINTERP_API void radinterp_solution_destroy(radinterp_solution *s);
RADINTERP_API void radinterp_solution_info(const radinterp_solution *s, radinterp_info *info);
RADINTERP_API radinterp_result radinterp_patch_radiosity(const radinterp_solution *s, uint32_t patch,
                                                         float rgb[3]);
RADINTERP_API uint32_t radinterp_leaf_count(const radinterp_solution *s);
RADINTERP_API radinterp_result radinterp_get_leaf(const radinterp_solution *s, uint32_t index,
                                                  radinterp_leaf *leaf);

/* Irradiance (W/m^2) at point p of a patch from every source linked to the
   leaf containing p and to its ancestors (Hardt chapter 6): exact form
   factors (eq. 6.1) with horizon clipping, and exact visibility by
   backprojection of the blockers onto the source. p should lie on the
   patch (it is used as given). toward (may be NULL) is a point on the patch
   from which p is approached: p moves `nudge` toward it for visibility, so
   a point on a blocker's edge takes the visibility of the side it is
   approached from (6.3). */
RADINTERP_API radinterp_result radinterp_irradiance_at_point(const radinterp_solution *s, uint32_t patch,
                                                             const float p[3], const float toward[3],
                                                             float rgb[3]);
/* Radiosity B = E + rho * IrradianceAtPoint (W/m^2). */
RADINTERP_API radinterp_result radinterp_radiosity_at_point(const radinterp_solution *s, uint32_t patch,
                                                            const float p[3], const float toward[3],
                                                            float rgb[3]);

/* Form factor from a differential area at p with normal n (need not be unit
   length) to a polygon of `count` xyz vertices (either winding), in double
   precision: F = 1/(2 pi) sum_g n . Gamma_g (Hardt eq. 6.1). The polygon is
   clipped to the hemisphere above p first, so it may cross p's tangent plane;
   a polygon in that plane, or p on the polygon's plane, gives 0. Returns 0
   for NULL pointers, count < 3, a zero n or non-finite input. */
RADINTERP_API double radinterp_form_factor_point_polygon(const float p[3], const float n[3],
                                                         const float *verts, uint32_t count);

#ifdef __cplusplus
}
#endif
#endif /* RADINTERP_H */

/* ------------------------------------------------------------------------ */
#if defined(RADINTERP_IMPLEMENTATION) && !defined(RADINTERP_IMPLEMENTATION_INCLUDED)
#define RADINTERP_IMPLEMENTATION_INCLUDED

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(RADINTERP_MALLOC) != defined(RADINTERP_FREE)
#  error "radinterp.h: define both RADINTERP_MALLOC and RADINTERP_FREE, or neither"
#endif
#ifndef RADINTERP_MALLOC
#  define RADINTERP_MALLOC(size) malloc(size)
#  define RADINTERP_FREE(ptr) free(ptr)
#endif

/* The exact predicates below rely on IEEE double arithmetic rounded to
   nearest with no extended precision (x86-64 SSE2, ARM64): do not compile
   this file with -ffast-math. Fused multiply-adds are harmless. */

#define RADINTERP__NONE 0xFFFFFFFFu

/* Private functions that some builds do not call (the triangulation toolkit
   is shared with the mesher). */
#if defined(__GNUC__) || defined(__clang__)
#  define RADINTERP__MAYBE_UNUSED __attribute__((unused))
#else
#  define RADINTERP__MAYBE_UNUSED
#endif

/* ======================================================================
   1. allocation
   ---------------------------------------------------------------------- */
/* In the declarations (public):

   typedef struct radinterp_allocator {
       void *(*alloc)(size_t size, void *user);  // NULL: RADINTERP_MALLOC
       void (*free)(void *ptr, void *user);      // NULL: RADINTERP_FREE
       void *user;
   } radinterp_allocator;
*/

/* Both callbacks or neither: a lone alloc would leak through RADINTERP_FREE. */
static int radinterp__allocator_valid(const radinterp_allocator *a)
{
    return (a->alloc == NULL) == (a->free == NULL);
}

static void *radinterp__alloc(const radinterp_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    return a->alloc ? a->alloc(size, a->user) : RADINTERP_MALLOC(size);
}

/* count * item bytes, or NULL when the product overflows. */
static void *radinterp__alloc_array(const radinterp_allocator *a, size_t count, size_t item)
{
    if (item && count > SIZE_MAX / item) return NULL;
    return radinterp__alloc(a, count * item);
}

static void radinterp__free(const radinterp_allocator *a, void *p)
{
    if (!p) return;
    if (a->free) a->free(p, a->user);
    else RADINTERP_FREE(p);
}

/* Zero means default: the documented default replaces a zero field. */
#define radinterp__def(v, d) ((v) ? (v) : (d))

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
typedef struct radinterp__vec3 { float x, y, z; } radinterp__vec3;

static radinterp__vec3 radinterp__v3(float x, float y, float z) { radinterp__vec3 r; r.x = x; r.y = y; r.z = z; return r; }
static radinterp__vec3 radinterp__v3_load(const float *p) { return radinterp__v3(p[0], p[1], p[2]); }
static radinterp__vec3 radinterp__sub(radinterp__vec3 a, radinterp__vec3 b) { return radinterp__v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static float radinterp__dot(radinterp__vec3 a, radinterp__vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static radinterp__vec3 radinterp__cross(radinterp__vec3 a, radinterp__vec3 b)
{
    return radinterp__v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static float radinterp__minf(float a, float b) { return a < b ? a : b; }
static float radinterp__maxf(float a, float b) { return a > b ? a : b; }
static int radinterp__finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }


/* ======================================================================
   3. counter-based random numbers
   A stream is a pure function of (seed, stream id): jobs seed their own
   stream from (desc.seed, job index) and never share state, so results are
   bit-identical for any thread count.
   ---------------------------------------------------------------------- */
typedef struct radinterp__rng { uint64_t state; } radinterp__rng;

/* SplitMix64 finaliser (Steele, Lea, Flood 2014). */
static uint64_t radinterp__mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static radinterp__rng radinterp__rng_stream(uint64_t seed, uint64_t stream)
{
    radinterp__rng r;
    r.state = radinterp__mix64(seed + 0x9E3779B97F4A7C15ull) ^ radinterp__mix64(stream * 0xD1B54A32D192ED03ull + 1u);
    return r;
}

static uint32_t radinterp__rng_u32(radinterp__rng *r)
{
    r->state += 0x9E3779B97F4A7C15ull;
    return (uint32_t)(radinterp__mix64(r->state) >> 32);
}

/* Uniform in [0, 1): 24 random bits, exactly representable. */
static float radinterp__rng_float(radinterp__rng *r)
{
    return (float)(radinterp__rng_u32(r) >> 8) * (1.0f / 16777216.0f);
}

/* ======================================================================
   4. BVH over triangles
   Binned SAH build (RADINTERP_BVH_BINS bins over centroid bounds), nodes flattened
   depth first (left child follows its parent), ordered traversal (nearer
   child box first), watertight ray/triangle test (Woop, Benthin, Wald 2013),
   any-hit for shadow rays. Triangles are copied into leaf order (9 floats and
   the caller's triangle index) because the traversal reads them in that order;
   nothing else of the caller's data is kept.
   ---------------------------------------------------------------------- */
#ifndef RADINTERP_BVH_BINS
#define RADINTERP_BVH_BINS 16
#endif
#define RADINTERP__BVH_LEAF_MAX 4    /* triangles per leaf */
#define RADINTERP__BVH_MAX_DEPTH 60  /* deeper nodes split at the median: bounds the traversal stack */
#define RADINTERP__BVH_STACK (RADINTERP__BVH_MAX_DEPTH + 34) /* + 32 median halvings of a uint32_t count */

typedef struct radinterp__bvh_node {
    float lo[3];
    uint32_t first;  /* leaf: first triangle; inner: index of the right child */
    float hi[3];
    uint32_t count;  /* leaf: triangle count (>0); inner: 0 */
} radinterp__bvh_node;

typedef struct radinterp__bvh_tri {
    float v0[3], v1[3], v2[3];
    uint32_t id;     /* the caller's triangle index */
} radinterp__bvh_tri;

typedef struct radinterp__bvh {
    radinterp__bvh_node *nodes;
    radinterp__bvh_tri *tris;
    uint32_t node_count, tri_count;
    uint32_t degenerate_count;  /* zero-area triangles skipped by the build */
} radinterp__bvh;

typedef struct radinterp__hit {
    float t;         /* distance along the ray in units of |dir| */
    float u, v;      /* barycentric weights of the triangle's 2nd and 3rd vertex */
    uint32_t tri;    /* the caller's triangle index; RADINTERP__NO_HIT when missed */
} radinterp__hit;
#define RADINTERP__NO_HIT 0xFFFFFFFFu

/* Caller's triangle soup: positions with a byte stride, 3 indices per triangle. */
typedef struct radinterp__mesh_view {
    const float *positions;
    size_t stride;             /* bytes between vertices; 0 = 3 floats */
    const uint32_t *indices;
    uint32_t tri_count;
} radinterp__mesh_view;

static const float *radinterp__vertex(const radinterp__mesh_view *m, uint32_t v)
{
    size_t stride = m->stride ? m->stride : 3 * sizeof(float);
    return (const float *)((const char *)m->positions + (size_t)v * stride);
}

typedef struct radinterp__bvh_ref {   /* build-time record of one triangle */
    float lo[3], hi[3], c[3];
    uint32_t tri;
} radinterp__bvh_ref;

typedef struct radinterp__bvh_bin { float lo[3], hi[3]; uint32_t count; } radinterp__bvh_bin;

static void radinterp__box_empty(float lo[3], float hi[3])
{
    lo[0] = lo[1] = lo[2] = FLT_MAX;
    hi[0] = hi[1] = hi[2] = -FLT_MAX;
}
static void radinterp__box_grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        lo[k] = radinterp__minf(lo[k], plo[k]);
        hi[k] = radinterp__maxf(hi[k], phi[k]);
    }
}
static float radinterp__box_area(const float lo[3], const float hi[3])
{
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    if (dx < 0.0f) return 0.0f;
    return dx * dy + dy * dz + dz * dx;
}

/* Chooses the binned-SAH split of refs[0..n); returns 0 when no split beats a
   leaf, else the axis (1-based in *axis) and the bin boundary in *split_bin. */
static int radinterp__bvh_find_split(const radinterp__bvh_ref *refs, uint32_t n, const float clo[3],
                              const float chi[3], int *axis, int *split_bin)
{
    float best = FLT_MAX, leaf_cost = (float)n;
    float node_lo[3], node_hi[3];
    int k, b, found = 0;
    uint32_t i;
    radinterp__box_empty(node_lo, node_hi);
    for (i = 0; i < n; i++) radinterp__box_grow(node_lo, node_hi, refs[i].lo, refs[i].hi);
    for (k = 0; k < 3; k++) {
        radinterp__bvh_bin bins[RADINTERP_BVH_BINS];
        float right_area[RADINTERP_BVH_BINS];
        uint32_t right_count[RADINTERP_BVH_BINS];
        float extent = chi[k] - clo[k], scale, lo[3], hi[3];
        uint32_t count;
        if (!(extent > 0.0f)) continue;
        scale = (float)RADINTERP_BVH_BINS / extent;
        for (b = 0; b < RADINTERP_BVH_BINS; b++) { radinterp__box_empty(bins[b].lo, bins[b].hi); bins[b].count = 0; }
        for (i = 0; i < n; i++) {
            int bin = (int)((refs[i].c[k] - clo[k]) * scale);
            if (bin >= RADINTERP_BVH_BINS) bin = RADINTERP_BVH_BINS - 1;
            if (bin < 0) bin = 0;
            bins[bin].count++;
            radinterp__box_grow(bins[bin].lo, bins[bin].hi, refs[i].lo, refs[i].hi);
        }
        /* sweep from the right, then from the left evaluating each boundary */
        radinterp__box_empty(lo, hi);
        count = 0;
        for (b = RADINTERP_BVH_BINS - 1; b > 0; b--) {
            radinterp__box_grow(lo, hi, bins[b].lo, bins[b].hi);
            count += bins[b].count;
            right_area[b] = radinterp__box_area(lo, hi);
            right_count[b] = count;
        }
        radinterp__box_empty(lo, hi);
        count = 0;
        for (b = 1; b < RADINTERP_BVH_BINS; b++) {
            float cost;
            radinterp__box_grow(lo, hi, bins[b - 1].lo, bins[b - 1].hi);
            count += bins[b - 1].count;
            if (count == 0 || right_count[b] == 0) continue;
            cost = 1.0f + (radinterp__box_area(lo, hi) * (float)count +
                           right_area[b] * (float)right_count[b]) / radinterp__box_area(node_lo, node_hi);
            if (cost < best) { best = cost; *axis = k; *split_bin = b; found = 1; }
        }
    }
    return found && (best < leaf_cost || n > RADINTERP__BVH_LEAF_MAX);
}

/* Partitions refs[0..n) so that the first part lies left of the chosen
   boundary. Returns the size of the left part (always in 1..n-1). */
static uint32_t radinterp__bvh_partition(radinterp__bvh_ref *refs, uint32_t n, const float clo[3],
                                  const float chi[3], int depth)
{
    int axis = 0, split_bin = 0;
    uint32_t i, j;
    if (depth < RADINTERP__BVH_MAX_DEPTH && radinterp__bvh_find_split(refs, n, clo, chi, &axis, &split_bin)) {
        float scale = (float)RADINTERP_BVH_BINS / (chi[axis] - clo[axis]);
        for (i = 0, j = n; i < j;) {
            int bin = (int)((refs[i].c[axis] - clo[axis]) * scale);
            if (bin >= RADINTERP_BVH_BINS) bin = RADINTERP_BVH_BINS - 1;
            if (bin < split_bin) i++;
            else { radinterp__bvh_ref t = refs[i]; refs[i] = refs[--j]; refs[j] = t; }
        }
        if (i > 0 && i < n) return i;
    }
    return n / 2; /* no useful SAH split (coincident centroids, depth cap): halve by count */
}

typedef struct radinterp__bvh_task {
    uint32_t parent, begin, end, depth;
    int is_right;    /* the parent learns a right child's index when it is popped */
} radinterp__bvh_task;

/* Copies the triangles into leaf order. */
static void radinterp__bvh_store_tris(radinterp__bvh *bvh, const radinterp__mesh_view *m, const radinterp__bvh_ref *refs)
{
    uint32_t i;
    for (i = 0; i < bvh->tri_count; i++) {
        radinterp__bvh_tri *t = &bvh->tris[i];
        uint32_t tri = refs[i].tri;
        memcpy(t->v0, radinterp__vertex(m, m->indices[3 * tri + 0]), sizeof t->v0);
        memcpy(t->v1, radinterp__vertex(m, m->indices[3 * tri + 1]), sizeof t->v1);
        memcpy(t->v2, radinterp__vertex(m, m->indices[3 * tri + 2]), sizeof t->v2);
        t->id = tri;
    }
}

/* Bounds of every non-degenerate triangle; counts the degenerate ones. */
static uint32_t radinterp__bvh_collect(radinterp__bvh *bvh, const radinterp__mesh_view *m, radinterp__bvh_ref *refs)
{
    uint32_t i, n = 0;
    for (i = 0; i < m->tri_count; i++) {
        const float *p0 = radinterp__vertex(m, m->indices[3 * i + 0]);
        const float *p1 = radinterp__vertex(m, m->indices[3 * i + 1]);
        const float *p2 = radinterp__vertex(m, m->indices[3 * i + 2]);
        radinterp__vec3 c = radinterp__cross(radinterp__sub(radinterp__v3_load(p1), radinterp__v3_load(p0)),
                               radinterp__sub(radinterp__v3_load(p2), radinterp__v3_load(p0)));
        int k;
        if (radinterp__dot(c, c) == 0.0f) { bvh->degenerate_count++; continue; }
        for (k = 0; k < 3; k++) {
            refs[n].lo[k] = radinterp__minf(p0[k], radinterp__minf(p1[k], p2[k]));
            refs[n].hi[k] = radinterp__maxf(p0[k], radinterp__maxf(p1[k], p2[k]));
            refs[n].c[k] = 0.5f * (refs[n].lo[k] + refs[n].hi[k]);
        }
        refs[n].tri = i;
        n++;
    }
    return n;
}

/* Builds the BVH of m's non-degenerate triangles. Indices must be in range and
   coordinates finite (validate first). Returns 0, or -1 when out of memory. */
static int radinterp__bvh_build(radinterp__bvh *bvh, const radinterp__mesh_view *m, const radinterp_allocator *a)
{
    radinterp__bvh_task stack[RADINTERP__BVH_STACK];
    radinterp__bvh_ref *refs;
    uint32_t i, n, top = 0;
    memset(bvh, 0, sizeof *bvh);
    refs = (radinterp__bvh_ref *)radinterp__alloc_array(a, m->tri_count, sizeof *refs);
    if (!refs) return -1;
    n = radinterp__bvh_collect(bvh, m, refs);
    bvh->nodes = (radinterp__bvh_node *)radinterp__alloc_array(a, n ? 2 * (size_t)n - 1 : 1, sizeof(radinterp__bvh_node));
    bvh->tris = (radinterp__bvh_tri *)radinterp__alloc_array(a, n, sizeof(radinterp__bvh_tri));
    if (!bvh->nodes || !bvh->tris) {
        radinterp__free(a, refs);
        radinterp__free(a, bvh->nodes);
        radinterp__free(a, bvh->tris);
        memset(bvh, 0, sizeof *bvh);
        return -1;
    }
    bvh->tri_count = n;
    if (n == 0) { /* an empty root leaf: every ray misses */
        radinterp__box_empty(bvh->nodes[0].lo, bvh->nodes[0].hi);
        bvh->nodes[0].first = bvh->nodes[0].count = 0;
        bvh->node_count = 1;
    } else {
        stack[top].parent = 0; stack[top].begin = 0; stack[top].end = n;
        stack[top].depth = 0; stack[top].is_right = 0; top++;
    }
    while (top) {
        radinterp__bvh_task t = stack[--top];
        uint32_t index = bvh->node_count++, count = t.end - t.begin;
        radinterp__bvh_node *node = &bvh->nodes[index];
        float clo[3], chi[3];
        if (t.is_right) bvh->nodes[t.parent].first = index;
        radinterp__box_empty(node->lo, node->hi);
        radinterp__box_empty(clo, chi);
        for (i = t.begin; i < t.end; i++) {
            radinterp__box_grow(node->lo, node->hi, refs[i].lo, refs[i].hi);
            radinterp__box_grow(clo, chi, refs[i].c, refs[i].c);
        }
        if (count <= RADINTERP__BVH_LEAF_MAX) {
            node->first = t.begin;
            node->count = count;
        } else {
            uint32_t mid = t.begin + radinterp__bvh_partition(refs + t.begin, count, clo, chi, (int)t.depth);
            node->count = 0;
            /* right pushed first so the left child is popped next: left = index + 1 */
            stack[top].parent = index; stack[top].begin = mid; stack[top].end = t.end;
            stack[top].depth = t.depth + 1; stack[top].is_right = 1; top++;
            stack[top].parent = index; stack[top].begin = t.begin; stack[top].end = mid;
            stack[top].depth = t.depth + 1; stack[top].is_right = 0; top++;
        }
    }
    radinterp__bvh_store_tris(bvh, m, refs);
    radinterp__free(a, refs);
    return 0;
}

static void radinterp__bvh_free(radinterp__bvh *bvh, const radinterp_allocator *a)
{
    radinterp__free(a, bvh->nodes);
    radinterp__free(a, bvh->tris);
    memset(bvh, 0, sizeof *bvh);
}

/* Per-ray constants of the watertight test and of the slab test. */
typedef struct radinterp__ray {
    float org[3], dir[3], inv[3];
    int kx, ky, kz;          /* dir[kz] has the largest magnitude */
    float sx, sy, sz;        /* shear that maps dir to +z */
} radinterp__ray;

static void radinterp__ray_setup(radinterp__ray *r, const float org[3], const float dir[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        /* a zero component would give 0 * inf = NaN in the slab test */
        float d = dir[k];
        if (fabsf(d) < 1e-30f) d = d < 0.0f ? -1e-30f : 1e-30f;
        r->org[k] = org[k];
        r->dir[k] = dir[k];
        r->inv[k] = 1.0f / d;
    }
    r->kz = fabsf(dir[0]) > fabsf(dir[1]) ? (fabsf(dir[0]) > fabsf(dir[2]) ? 0 : 2)
                                          : (fabsf(dir[1]) > fabsf(dir[2]) ? 1 : 2);
    r->kx = (r->kz + 1) % 3;
    r->ky = (r->kx + 1) % 3;
    if (dir[r->kz] < 0.0f) { int t = r->kx; r->kx = r->ky; r->ky = t; } /* keep winding */
    r->sx = dir[r->kx] / dir[r->kz];
    r->sy = dir[r->ky] / dir[r->kz];
    r->sz = 1.0f / dir[r->kz];
}

/* Entry distance of the ray into the box, or FLT_MAX when it misses within
   [tmin, tmax]. The tmax bound is widened by 2 ulp-ish factors so that a hit
   exactly on a box face is not lost to rounding (Ize 2013). */
static float radinterp__ray_box(const radinterp__ray *r, const float lo[3], const float hi[3], float tmin, float tmax)
{
    int k;
    for (k = 0; k < 3; k++) {
        float t0 = (lo[k] - r->org[k]) * r->inv[k];
        float t1 = (hi[k] - r->org[k]) * r->inv[k];
        if (t0 > t1) { float t = t0; t0 = t1; t1 = t; }
        tmin = radinterp__maxf(tmin, t0);
        tmax = radinterp__minf(tmax, t1 * 1.00000024f);
    }
    return tmin <= tmax ? tmin : FLT_MAX;
}

/* Watertight ray/triangle test (Woop, Benthin, Wald 2013): edge functions in
   a sheared space where the ray is the +z axis; edges shared by two triangles
   are hit by exactly one of them. Double precision only when an edge function
   is exactly zero. Updates *hit when closer than hit->t. */
static int radinterp__ray_tri(const radinterp__ray *r, const radinterp__bvh_tri *tri, float tmin, radinterp__hit *hit)
{
    float ax = tri->v0[r->kx] - r->org[r->kx], ay = tri->v0[r->ky] - r->org[r->ky], az = tri->v0[r->kz] - r->org[r->kz];
    float bx = tri->v1[r->kx] - r->org[r->kx], by = tri->v1[r->ky] - r->org[r->ky], bz = tri->v1[r->kz] - r->org[r->kz];
    float cx = tri->v2[r->kx] - r->org[r->kx], cy = tri->v2[r->ky] - r->org[r->ky], cz = tri->v2[r->kz] - r->org[r->kz];
    float u, v, w, det, t;
    ax -= r->sx * az; ay -= r->sy * az;
    bx -= r->sx * bz; by -= r->sy * bz;
    cx -= r->sx * cz; cy -= r->sy * cz;
    u = cx * by - cy * bx;
    v = ax * cy - ay * cx;
    w = bx * ay - by * ax;
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        u = (float)((double)cx * by - (double)cy * bx);
        v = (float)((double)ax * cy - (double)ay * cx);
        w = (float)((double)bx * ay - (double)by * ax);
    }
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return 0;
    det = u + v + w;
    if (det == 0.0f) return 0;
    t = (u * az + v * bz + w * cz) * r->sz / det;
    if (!(t > tmin && t < hit->t)) return 0;
    hit->t = t;
    hit->u = v / det;
    hit->v = w / det;
    hit->tri = tri->id;
    return 1;
}

/* Closest hit in (tmin, tmax). Returns 1 and fills *hit, else hit->tri = RADINTERP__NO_HIT. */
static int radinterp__bvh_intersect(const radinterp__bvh *bvh, const float org[3], const float dir[3],
                             float tmin, float tmax, radinterp__hit *hit)
{
    uint32_t stack[RADINTERP__BVH_STACK], top = 0, index = 0;
    radinterp__ray r;
    radinterp__ray_setup(&r, org, dir);
    hit->t = tmax;
    hit->u = hit->v = 0.0f;
    hit->tri = RADINTERP__NO_HIT;
    if (radinterp__ray_box(&r, bvh->nodes[0].lo, bvh->nodes[0].hi, tmin, tmax) == FLT_MAX) return 0;
    for (;;) {
        const radinterp__bvh_node *node = &bvh->nodes[index];
        if (node->count) {
            uint32_t i;
            for (i = node->first; i < node->first + node->count; i++)
                radinterp__ray_tri(&r, &bvh->tris[i], tmin, hit);
        } else {
            uint32_t left = index + 1, right = node->first;
            float tl = radinterp__ray_box(&r, bvh->nodes[left].lo, bvh->nodes[left].hi, tmin, hit->t);
            float tr = radinterp__ray_box(&r, bvh->nodes[right].lo, bvh->nodes[right].hi, tmin, hit->t);
            if (tl != FLT_MAX && tr != FLT_MAX) {
                if (tr < tl) { uint32_t t = left; left = right; right = t; }
                stack[top++] = right; /* the farther child waits */
                index = left;
                continue;
            }
            if (tl != FLT_MAX) { index = left; continue; }
            if (tr != FLT_MAX) { index = right; continue; }
        }
        if (!top) break;
        index = stack[--top];
    }
    return hit->tri != RADINTERP__NO_HIT;
}

/* Any hit in (tmin, tmax): for shadow rays. */
static int radinterp__bvh_occluded(const radinterp__bvh *bvh, const float org[3], const float dir[3],
                            float tmin, float tmax)
{
    uint32_t stack[RADINTERP__BVH_STACK], top = 0, index = 0;
    radinterp__ray r;
    radinterp__hit hit;
    radinterp__ray_setup(&r, org, dir);
    hit.t = tmax;
    hit.tri = RADINTERP__NO_HIT;
    for (;;) {
        const radinterp__bvh_node *node = &bvh->nodes[index];
        if (radinterp__ray_box(&r, node->lo, node->hi, tmin, tmax) != FLT_MAX) {
            if (node->count) {
                uint32_t i;
                for (i = node->first; i < node->first + node->count; i++)
                    if (radinterp__ray_tri(&r, &bvh->tris[i], tmin, &hit)) return 1;
            } else {
                stack[top++] = node->first;
                index = index + 1;
                continue;
            }
        }
        if (!top) return 0;
        index = stack[--top];
    }
}

/* ======================================================================
   7. jobs: the caller's parallel_for, or a serial loop
   ---------------------------------------------------------------------- */
/* In the declarations (public):

   typedef void (*radinterp_job_fn)(void *ctx, uint32_t index);
   // in the desc:
   void (*parallel_for)(void *user, radinterp_job_fn job, void *ctx, uint32_t count);
   void *parallel_user;
   int (*progress)(void *user, uint64_t done, uint64_t total);   // non-zero cancels
   void *progress_user;

   Long builds run their jobs in batches and call progress between batches,
   from the calling thread, so a callback never runs concurrently with itself. */
static void radinterp__run_jobs(void (*parallel_for)(void *, radinterp_job_fn, void *, uint32_t), void *user,
                         radinterp_job_fn job, void *ctx, uint32_t count)
{
    uint32_t i;
    if (count == 0) return;
    if (parallel_for) { parallel_for(user, job, ctx, count); return; }
    for (i = 0; i < count; i++) job(ctx, i);
}

/* ======================================================================
   8. exact geometric predicates (the technique of Shewchuk 1997)
   orient2d and incircle are first evaluated in double precision with a
   forward error bound; only when the sign is not certain are they evaluated
   exactly with expansion arithmetic: a value is kept as a sum of doubles
   (an expansion) of increasing magnitude whose components do not overlap, so
   sums and products lose nothing. Degenerate inputs (collinear, cocircular)
   therefore get exactly 0, which the triangulation relies on.
   ---------------------------------------------------------------------- */
#define RADINTERP__ROUND 1.1102230246251565e-16 /* 2^-53: relative rounding error of a double */

/* x + y = a + b exactly, x = fl(a + b) (Knuth's two-sum). */
static void radinterp__two_sum(double a, double b, double *x, double *y)
{
    double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

/* Same for |a| >= |b| (Dekker), three operations. */
static void radinterp__fast_two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    *x = s;
    *y = b - (s - a);
}

/* x + y = a * b exactly: the fused multiply-add returns the rounding error
   of the product exactly. */
static void radinterp__two_product(double a, double b, double *x, double *y)
{
    double p = a * b;
    *x = p;
    *y = fma(a, b, -p);
}

/* a - b as an expansion of 1 or 2 components; returns the length. */
static int radinterp__diff_expansion(double a, double b, double *h)
{
    double x, y;
    radinterp__two_sum(a, -b, &x, &y);
    if (y != 0.0) { h[0] = y; h[1] = x; return 2; }
    h[0] = x;
    return 1;
}

/* h = e + f for non-overlapping expansions (merge by magnitude, then one
   carry sweep). Zero components are dropped; a zero sum is {0}. h must not
   alias e or f. */
static int radinterp__expansion_sum(int elen, const double *e, int flen, const double *f, double *h)
{
    double q, hh, g;
    int i = 0, j = 0, k = 0, first = 1;
    q = 0.0;
    while (i < elen || j < flen) {
        if (j >= flen || (i < elen && fabs(e[i]) < fabs(f[j]))) g = e[i++];
        else g = f[j++];
        if (first) { q = g; first = 0; continue; }
        radinterp__two_sum(q, g, &q, &hh);
        if (hh != 0.0) h[k++] = hh;
    }
    if (q != 0.0 || k == 0) h[k++] = q;
    return k;
}

/* h = e * b (Shewchuk's scale-expansion), zero components dropped. */
static int radinterp__scale_expansion(int elen, const double *e, double b, double *h)
{
    double q, hh, prod, err, sum;
    int i, k = 0;
    radinterp__two_product(e[0], b, &q, &hh);
    if (hh != 0.0) h[k++] = hh;
    for (i = 1; i < elen; i++) {
        radinterp__two_product(e[i], b, &prod, &err);
        radinterp__two_sum(q, err, &sum, &hh);
        if (hh != 0.0) h[k++] = hh;
        radinterp__fast_two_sum(prod, sum, &q, &hh);
        if (hh != 0.0) h[k++] = hh;
    }
    if (q != 0.0 || k == 0) h[k++] = q;
    return k;
}

/* h = e * f for expansions of at most 16 components each (at most 512
   components out): the sum of e scaled by each component of f. */
static int radinterp__expansion_product(int elen, const double *e, int flen, const double *f, double *h)
{
    double part[32], acc[2][512];
    int j, len = 1, cur = 0;
    acc[0][0] = 0.0;
    for (j = 0; j < flen; j++) {
        int plen = radinterp__scale_expansion(elen, e, f[j], part);
        len = radinterp__expansion_sum(len, acc[cur], plen, part, acc[1 - cur]);
        cur = 1 - cur;
    }
    memcpy(h, acc[cur], (size_t)len * sizeof(double));
    return len;
}

/* The sign of an expansion is the sign of its largest component. */
static double radinterp__expansion_sign(int len, const double *e)
{
    double top = e[len - 1];
    return top > 0.0 ? 1.0 : (top < 0.0 ? -1.0 : 0.0);
}

static double radinterp__orient2d_exact(const double *a, const double *b, const double *c)
{
    double acx[2], acy[2], bcx[2], bcy[2], left[8], right[8], det[16];
    int nacx = radinterp__diff_expansion(a[0], c[0], acx);
    int nacy = radinterp__diff_expansion(a[1], c[1], acy);
    int nbcx = radinterp__diff_expansion(b[0], c[0], bcx);
    int nbcy = radinterp__diff_expansion(b[1], c[1], bcy);
    int nl = radinterp__expansion_product(nacx, acx, nbcy, bcy, left);
    int nr = radinterp__expansion_product(nacy, acy, nbcx, bcx, right), i, n;
    for (i = 0; i < nr; i++) right[i] = -right[i];
    n = radinterp__expansion_sum(nl, left, nr, right, det);
    return radinterp__expansion_sign(n, det);
}

/* Positive when a, b, c turn counter-clockwise, negative when clockwise,
   exactly zero when collinear. Only the sign is meaningful. */
static double radinterp__orient2d(const double *a, const double *b, const double *c)
{
    double left = (a[0] - c[0]) * (b[1] - c[1]);
    double right = (a[1] - c[1]) * (b[0] - c[0]);
    double det = left - right, sum;
    if (left > 0.0) {
        if (right <= 0.0) return det;
        sum = left + right;
    } else if (left < 0.0) {
        if (right >= 0.0) return det;
        sum = -left - right;
    } else {
        return det;
    }
    if (fabs(det) >= (3.0 + 16.0 * RADINTERP__ROUND) * RADINTERP__ROUND * sum) return det;
    return radinterp__orient2d_exact(a, b, c);
}

/* x^2 + y^2 for coordinate differences given as expansions. */
static int radinterp__lift(int nx, const double *x, int ny, const double *y, double *h)
{
    double xx[8], yy[8];
    int nxx = radinterp__expansion_product(nx, x, nx, x, xx);
    int nyy = radinterp__expansion_product(ny, y, ny, y, yy);
    return radinterp__expansion_sum(nxx, xx, nyy, yy, h);
}

/* u_x * v_y - u_y * v_x for expansions. */
static int radinterp__cross_expansion(int nux, const double *ux, int nuy, const double *uy,
                                      int nvx, const double *vx, int nvy, const double *vy, double *h)
{
    double l[8], r[8];
    int nl = radinterp__expansion_product(nux, ux, nvy, vy, l);
    int nr = radinterp__expansion_product(nuy, uy, nvx, vx, r), i;
    for (i = 0; i < nr; i++) r[i] = -r[i];
    return radinterp__expansion_sum(nl, l, nr, r, h);
}

static double radinterp__incircle_exact(const double *a, const double *b, const double *c, const double *d)
{
    double adx[2], ady[2], bdx[2], bdy[2], cdx[2], cdy[2];
    double lift[16], cross[16], term[3][512], ab[1024], det[1536];
    int n[6], nl, nc, nt[3], nab, ndet, k;
    const double *p[3];
    n[0] = radinterp__diff_expansion(a[0], d[0], adx);
    n[1] = radinterp__diff_expansion(a[1], d[1], ady);
    n[2] = radinterp__diff_expansion(b[0], d[0], bdx);
    n[3] = radinterp__diff_expansion(b[1], d[1], bdy);
    n[4] = radinterp__diff_expansion(c[0], d[0], cdx);
    n[5] = radinterp__diff_expansion(c[1], d[1], cdy);
    p[0] = a; p[1] = b; p[2] = c;
    for (k = 0; k < 3; k++) {
        /* term k = lift(point k) * cross(point k+1, point k+2), all relative to d */
        const double *x[3], *y[3];
        int nx[3], ny[3], i0 = k, i1 = (k + 1) % 3, i2 = (k + 2) % 3;
        x[0] = adx; x[1] = bdx; x[2] = cdx;
        y[0] = ady; y[1] = bdy; y[2] = cdy;
        nx[0] = n[0]; nx[1] = n[2]; nx[2] = n[4];
        ny[0] = n[1]; ny[1] = n[3]; ny[2] = n[5];
        nl = radinterp__lift(nx[i0], x[i0], ny[i0], y[i0], lift);
        nc = radinterp__cross_expansion(nx[i1], x[i1], ny[i1], y[i1], nx[i2], x[i2], ny[i2], y[i2], cross);
        nt[k] = radinterp__expansion_product(nl, lift, nc, cross, term[k]);
    }
    (void)p;
    nab = radinterp__expansion_sum(nt[0], term[0], nt[1], term[1], ab);
    ndet = radinterp__expansion_sum(nab, ab, nt[2], term[2], det);
    return radinterp__expansion_sign(ndet, det);
}

/* Positive when d lies inside the circle through a, b, c (counter-clockwise),
   negative outside, exactly zero on it. Only the sign is meaningful. */
static double radinterp__incircle(const double *a, const double *b, const double *c, const double *d)
{
    double adx = a[0] - d[0], ady = a[1] - d[1];
    double bdx = b[0] - d[0], bdy = b[1] - d[1];
    double cdx = c[0] - d[0], cdy = c[1] - d[1];
    double bc1 = bdx * cdy, bc2 = cdx * bdy, ca1 = cdx * ady, ca2 = adx * cdy, ab1 = adx * bdy, ab2 = bdx * ady;
    double alift = adx * adx + ady * ady, blift = bdx * bdx + bdy * bdy, clift = cdx * cdx + cdy * cdy;
    double det = alift * (bc1 - bc2) + blift * (ca1 - ca2) + clift * (ab1 - ab2);
    double permanent = (fabs(bc1) + fabs(bc2)) * alift + (fabs(ca1) + fabs(ca2)) * blift +
                       (fabs(ab1) + fabs(ab2)) * clift;
    if (fabs(det) > (10.0 + 96.0 * RADINTERP__ROUND) * RADINTERP__ROUND * permanent) return det;
    return radinterp__incircle_exact(a, b, c, d);
}

/* ======================================================================
   9. constrained Delaunay triangulation (CDT)
   Incremental: a point is located by a stochastic walk, splits the
   triangle or edge it falls in, and Lawson flips restore the (constrained)
   Delaunay property without ever flipping a constraint. A segment is
   inserted by flipping away the edges it crosses (Sloan 1993), then the
   touched edges are made locally Delaunay again. A segment that passes
   through a vertex is split there; one that crosses another constraint is
   split at the crossing, which becomes a vertex splitting the other one too.
   Exact duplicates (and points closer than merge_distance) are merged.

   The hull is closed by ghost triangles that share the vertex at infinity
   RADINTERP__GHOST, so points outside the current hull need no special
   case: a ghost contains p when p lies strictly outside its hull edge (or on
   it), which is its "circumcircle".

   Interface (part of the private toolkit reused by the mesher):
     radinterp__cdt_init(c, allocator, mem, bytes)  optional caller memory used first
     radinterp__cdt_clear(c) / radinterp__cdt_free(c)
     radinterp__cdt_add_point(c, x, y)      -> vertex id (an existing one when merged),
                                              RADINTERP__NONE when out of memory
     radinterp__cdt_add_points(c, xy, n, ids)  bulk, in spatial (Hilbert) order
     radinterp__cdt_add_segment(c, a, b)    constraint between two vertex ids
     c->tri[0 .. c->tri_count): v[3] counter-clockwise, n[3] neighbour across
       the edge opposite v[i], flags bit i = that edge is a constraint;
       radinterp__cdt_is_real(c, t) is false for ghost triangles.
     c->xy[2 * v], c->vertex_count; vertices made at constraint crossings
       follow the caller's. c->failed is set when memory ran out or a step
       limit stopped an insertion (the triangulation stays valid).
   ---------------------------------------------------------------------- */
#define RADINTERP__GHOST 0xFFFFFFFEu
#define RADINTERP__CDT_STEP_LIMIT 4000000u

typedef struct radinterp__cdt_tri {
    uint32_t v[3];     /* counter-clockwise; a ghost has one vertex RADINTERP__GHOST */
    uint32_t n[3];     /* n[i]: the triangle across the edge opposite v[i] */
    uint32_t flags;    /* bit i: the edge opposite v[i] is a constraint */
} radinterp__cdt_tri;

typedef struct radinterp__u32s {
    uint32_t *data;
    uint32_t count, cap;
    int owned;         /* data came from the allocator */
} radinterp__u32s;

typedef struct radinterp__cdt {
    radinterp_allocator alloc;
    double *xy;                  /* 2 per vertex */
    uint32_t *vtri;              /* a triangle incident to each vertex (NONE before the first triangle) */
    uint32_t vertex_count, vertex_cap;
    radinterp__cdt_tri *tri;
    uint32_t tri_count, tri_cap;
    radinterp__u32s fix;         /* triangles around a new vertex whose far edge needs a check */
    radinterp__u32s segs;        /* segment pieces still to insert (vertex pairs) */
    radinterp__u32s queue;       /* crossing edges (vertex pairs) */
    radinterp__u32s touched;     /* triangles changed while a segment went in */
    uint32_t last;               /* a triangle: where point location starts */
    uint32_t rng;
    int started;                 /* a first triangle exists */
    int owns_xy, owns_tri;
    double merge_distance2;
    int failed;
} radinterp__cdt;

static void *radinterp__grow_block(radinterp__cdt *c, void *old, int *owned, size_t old_bytes, size_t new_bytes)
{
    void *p = radinterp__alloc(&c->alloc, new_bytes);
    if (!p) { c->failed = 1; return NULL; }
    if (old_bytes) memcpy(p, old, old_bytes);
    if (*owned) radinterp__free(&c->alloc, old);
    *owned = 1;
    return p;
}

static int radinterp__u32s_push(radinterp__cdt *c, radinterp__u32s *s, uint32_t v)
{
    if (s->count == s->cap) {
        uint32_t cap = s->cap ? s->cap * 2 : 64;
        void *p;
        if (cap < s->cap) { c->failed = 1; return 0; }
        p = radinterp__grow_block(c, s->data, &s->owned, (size_t)s->count * 4, (size_t)cap * 4);
        if (!p) return 0;
        s->data = (uint32_t *)p;
        s->cap = cap;
    }
    s->data[s->count++] = v;
    return 1;
}

static int radinterp__u32s_push2(radinterp__cdt *c, radinterp__u32s *s, uint32_t a, uint32_t b)
{
    return radinterp__u32s_push(c, s, a) && radinterp__u32s_push(c, s, b);
}

/* Carves the optional caller block (stack memory for small triangulations)
   into the arrays; they move to the allocator when they outgrow it. */
static void radinterp__cdt_init(radinterp__cdt *c, const radinterp_allocator *a, void *mem, size_t bytes)
{
    memset(c, 0, sizeof *c);
    c->alloc = *a;
    c->last = RADINTERP__NONE;
    c->rng = 0x9E3779B9u;
    if (mem && bytes >= 1024) {
        /* per vertex: 16 (xy) + 4 (vtri) + 2 triangles of 28 + lists of 4 x 4 words */
        size_t vcap = bytes / (16 + 4 + 2 * sizeof(radinterp__cdt_tri) + 64) - 4;
        char *p = (char *)mem;
        c->xy = (double *)(void *)p;                 p += vcap * 16;
        c->tri = (radinterp__cdt_tri *)(void *)p;    p += 2 * vcap * sizeof(radinterp__cdt_tri);
        c->vtri = (uint32_t *)(void *)p;             p += vcap * 4;
        c->fix.data = (uint32_t *)(void *)p;         p += vcap * 16;
        c->segs.data = (uint32_t *)(void *)p;        p += vcap * 16;
        c->queue.data = (uint32_t *)(void *)p;       p += vcap * 16;
        c->touched.data = (uint32_t *)(void *)p;
        c->vertex_cap = (uint32_t)vcap;
        c->tri_cap = (uint32_t)(2 * vcap);
        c->fix.cap = c->segs.cap = c->queue.cap = c->touched.cap = (uint32_t)(4 * vcap);
    }
}

static void radinterp__cdt_clear(radinterp__cdt *c)
{
    c->vertex_count = c->tri_count = 0;
    c->fix.count = c->segs.count = c->queue.count = c->touched.count = 0;
    c->last = RADINTERP__NONE;
    c->started = 0;
    c->failed = 0;
}

static void radinterp__cdt_free(radinterp__cdt *c)
{
    if (c->owns_xy) { radinterp__free(&c->alloc, c->xy); radinterp__free(&c->alloc, c->vtri); }
    if (c->owns_tri) radinterp__free(&c->alloc, c->tri);
    if (c->fix.owned) radinterp__free(&c->alloc, c->fix.data);
    if (c->segs.owned) radinterp__free(&c->alloc, c->segs.data);
    if (c->queue.owned) radinterp__free(&c->alloc, c->queue.data);
    if (c->touched.owned) radinterp__free(&c->alloc, c->touched.data);
    memset(c, 0, sizeof *c);
}

static int radinterp__cdt_reserve(radinterp__cdt *c, uint32_t vertices, uint32_t triangles)
{
    if (c->vertex_count + vertices > c->vertex_cap) {
        uint32_t cap = c->vertex_cap ? c->vertex_cap : 32;
        int owned = c->owns_xy;
        double *xy;
        uint32_t *vtri;
        while (cap < c->vertex_count + vertices) {
            if (cap > 0x3FFFFFFFu) { c->failed = 1; return 0; }
            cap *= 2;
        }
        xy = (double *)radinterp__alloc_array(&c->alloc, cap, 2 * sizeof(double));
        vtri = (uint32_t *)radinterp__alloc_array(&c->alloc, cap, sizeof(uint32_t));
        if (!xy || !vtri) {
            radinterp__free(&c->alloc, xy);
            radinterp__free(&c->alloc, vtri);
            c->failed = 1;
            return 0;
        }
        if (c->vertex_count) {
            memcpy(xy, c->xy, (size_t)c->vertex_count * 2 * sizeof(double));
            memcpy(vtri, c->vtri, (size_t)c->vertex_count * sizeof(uint32_t));
        }
        if (owned) { radinterp__free(&c->alloc, c->xy); radinterp__free(&c->alloc, c->vtri); }
        c->xy = xy;
        c->vtri = vtri;
        c->vertex_cap = cap;
        c->owns_xy = 1;
    }
    if (c->tri_count + triangles > c->tri_cap) {
        uint32_t cap = c->tri_cap ? c->tri_cap : 64;
        void *p;
        while (cap < c->tri_count + triangles) {
            if (cap > 0x3FFFFFFFu) { c->failed = 1; return 0; }
            cap *= 2;
        }
        p = radinterp__grow_block(c, c->tri, &c->owns_tri, (size_t)c->tri_count * sizeof(radinterp__cdt_tri),
                                  (size_t)cap * sizeof(radinterp__cdt_tri));
        if (!p) return 0;
        c->tri = (radinterp__cdt_tri *)p;
        c->tri_cap = cap;
    }
    return 1;
}

static int radinterp__cdt_is_ghost(const radinterp__cdt *c, uint32_t t)
{
    const uint32_t *v = c->tri[t].v;
    return v[0] == RADINTERP__GHOST || v[1] == RADINTERP__GHOST || v[2] == RADINTERP__GHOST;
}

RADINTERP__MAYBE_UNUSED static int radinterp__cdt_is_real(const radinterp__cdt *c, uint32_t t)
{
    return t < c->tri_count && !radinterp__cdt_is_ghost(c, t);
}

static int radinterp__cdt_ghost_index(const radinterp__cdt *c, uint32_t t)
{
    const uint32_t *v = c->tri[t].v;
    return v[0] == RADINTERP__GHOST ? 0 : (v[1] == RADINTERP__GHOST ? 1 : (v[2] == RADINTERP__GHOST ? 2 : -1));
}

static int radinterp__cdt_index(const radinterp__cdt *c, uint32_t t, uint32_t v)
{
    const uint32_t *w = c->tri[t].v;
    return w[0] == v ? 0 : (w[1] == v ? 1 : (w[2] == v ? 2 : -1));
}

static int radinterp__cdt_neighbour_index(const radinterp__cdt *c, uint32_t t, uint32_t of)
{
    const uint32_t *n = c->tri[t].n;
    return n[0] == of ? 0 : (n[1] == of ? 1 : (n[2] == of ? 2 : -1));
}

static const double *radinterp__cdt_p(const radinterp__cdt *c, uint32_t v) { return c->xy + 2 * (size_t)v; }

static void radinterp__cdt_set(radinterp__cdt *c, uint32_t t, uint32_t a, uint32_t b, uint32_t d,
                               uint32_t na, uint32_t nb, uint32_t nd, uint32_t flags)
{
    radinterp__cdt_tri *r = &c->tri[t];
    r->v[0] = a; r->v[1] = b; r->v[2] = d;
    r->n[0] = na; r->n[1] = nb; r->n[2] = nd;
    r->flags = flags;
}

/* Points neighbour t's link that went to `from` at `to` instead. */
static void radinterp__cdt_relink(radinterp__cdt *c, uint32_t t, uint32_t from, uint32_t to)
{
    int k = radinterp__cdt_neighbour_index(c, t, from);
    if (k >= 0) c->tri[t].n[k] = to;
}

static void radinterp__cdt_touch(radinterp__cdt *c, uint32_t t)
{
    int k;
    for (k = 0; k < 3; k++) {
        uint32_t v = c->tri[t].v[k];
        if (v != RADINTERP__GHOST) c->vtri[v] = t;
    }
}

/* Is d strictly inside the circumcircle of t? For a ghost: is d strictly
   outside its hull edge, or on the open edge itself. */
static int radinterp__cdt_in_circle(const radinterp__cdt *c, uint32_t t, uint32_t d)
{
    const uint32_t *v = c->tri[t].v;
    int g = radinterp__cdt_ghost_index(c, t);
    const double *pa, *pb, *pd;
    double o;
    if (d == RADINTERP__GHOST) return 0;
    pd = radinterp__cdt_p(c, d);
    if (g < 0)
        return radinterp__incircle(radinterp__cdt_p(c, v[0]), radinterp__cdt_p(c, v[1]),
                                   radinterp__cdt_p(c, v[2]), pd) > 0.0;
    pa = radinterp__cdt_p(c, v[(g + 1) % 3]);
    pb = radinterp__cdt_p(c, v[(g + 2) % 3]);
    o = radinterp__orient2d(pa, pb, pd);
    if (o != 0.0) return o > 0.0;
    {
        double ex = pb[0] - pa[0], ey = pb[1] - pa[1];
        double s = (pd[0] - pa[0]) * ex + (pd[1] - pa[1]) * ey;
        return s > 0.0 && s < ex * ex + ey * ey;
    }
}

/* Flipping the edge opposite v[k] of t gives (a, b, d) and (a, d, c):
   allowed when neither is a real triangle turned clockwise or flat. */
static int radinterp__cdt_flip_ok(const radinterp__cdt *c, uint32_t t, int k)
{
    uint32_t a = c->tri[t].v[k], b = c->tri[t].v[(k + 1) % 3], cc = c->tri[t].v[(k + 2) % 3];
    uint32_t u = c->tri[t].n[k];
    int j = radinterp__cdt_neighbour_index(c, u, t);
    uint32_t d = c->tri[u].v[j];
    if (a != RADINTERP__GHOST && b != RADINTERP__GHOST && d != RADINTERP__GHOST &&
        !(radinterp__orient2d(radinterp__cdt_p(c, a), radinterp__cdt_p(c, b), radinterp__cdt_p(c, d)) > 0.0))
        return 0;
    if (a != RADINTERP__GHOST && d != RADINTERP__GHOST && cc != RADINTERP__GHOST &&
        !(radinterp__orient2d(radinterp__cdt_p(c, a), radinterp__cdt_p(c, d), radinterp__cdt_p(c, cc)) > 0.0))
        return 0;
    return 1;
}

/* Replaces the edge (b, c) opposite a = v[k] of t = (a, b, c) by (a, d),
   where d is the far vertex of the neighbour u = (d, c, b). Afterwards
   t = (a, b, d) and u = (a, d, c); both still contain a. */
static void radinterp__cdt_flip(radinterp__cdt *c, uint32_t t, int k)
{
    radinterp__cdt_tri T = c->tri[t], U;
    uint32_t u = T.n[k], a = T.v[k], b = T.v[(k + 1) % 3], cc = T.v[(k + 2) % 3], d;
    uint32_t n_bd, n_dc, n_ca = T.n[(k + 1) % 3], n_ab = T.n[(k + 2) % 3];
    uint32_t f_bd, f_dc, f_ca = (T.flags >> ((k + 1) % 3)) & 1u, f_ab = (T.flags >> ((k + 2) % 3)) & 1u;
    int j = radinterp__cdt_neighbour_index(c, u, t);
    U = c->tri[u];
    d = U.v[j];
    n_bd = U.n[(j + 1) % 3];
    n_dc = U.n[(j + 2) % 3];
    f_bd = (U.flags >> ((j + 1) % 3)) & 1u;
    f_dc = (U.flags >> ((j + 2) % 3)) & 1u;
    radinterp__cdt_set(c, t, a, b, d, n_bd, u, n_ab, f_bd | (f_ab << 2));
    radinterp__cdt_set(c, u, a, d, cc, n_dc, n_ca, t, f_dc | (f_ca << 1));
    radinterp__cdt_relink(c, n_bd, u, t);
    radinterp__cdt_relink(c, n_ca, t, u);
    radinterp__cdt_touch(c, t);
    radinterp__cdt_touch(c, u);
}

/* Lawson's legalisation around the new vertex p: every triangle on c->fix
   contains p; its far edge is flipped when not locally Delaunay. */
static void radinterp__cdt_legalize(radinterp__cdt *c, uint32_t p)
{
    while (c->fix.count) {
        uint32_t t = c->fix.data[--c->fix.count], u, d;
        int k = radinterp__cdt_index(c, t, p), j;
        if (k < 0 || (c->tri[t].flags >> k) & 1u) continue;
        u = c->tri[t].n[k];
        j = radinterp__cdt_neighbour_index(c, u, t);
        d = c->tri[u].v[j];
        if (!radinterp__cdt_in_circle(c, t, d) || !radinterp__cdt_flip_ok(c, t, k)) continue;
        radinterp__cdt_flip(c, t, k);
        if (!radinterp__u32s_push2(c, &c->fix, t, u)) return;
    }
}

/* p inside t = (a, b, c) (for a ghost: beyond its hull edge) becomes the
   apex of three triangles. Two slots are reserved by the caller. */
static void radinterp__cdt_split_triangle(radinterp__cdt *c, uint32_t t, uint32_t p)
{
    radinterp__cdt_tri T = c->tri[t];
    uint32_t t1 = c->tri_count++, t2 = c->tri_count++;
    uint32_t a = T.v[0], b = T.v[1], cc = T.v[2];
    radinterp__cdt_set(c, t, p, b, cc, T.n[0], t1, t2, T.flags & 1u);
    radinterp__cdt_set(c, t1, a, p, cc, t, T.n[1], t2, T.flags & 2u);
    radinterp__cdt_set(c, t2, a, b, p, t, t1, T.n[2], T.flags & 4u);
    radinterp__cdt_relink(c, T.n[1], t, t1);
    radinterp__cdt_relink(c, T.n[2], t, t2);
    radinterp__cdt_touch(c, t1);
    radinterp__cdt_touch(c, t2);
    radinterp__cdt_touch(c, t);
    c->fix.count = 0;
    radinterp__u32s_push(c, &c->fix, t);
    radinterp__u32s_push(c, &c->fix, t1);
    radinterp__u32s_push(c, &c->fix, t2);
}

/* p on the edge opposite v[k] of t splits t and its neighbour in two each;
   a constraint there stays a constraint in both halves. */
static void radinterp__cdt_split_edge(radinterp__cdt *c, uint32_t t, int k, uint32_t p)
{
    radinterp__cdt_tri T = c->tri[t], U;
    uint32_t u = T.n[k], a = T.v[k], b = T.v[(k + 1) % 3], cc = T.v[(k + 2) % 3], d;
    uint32_t t2 = c->tri_count++, u2 = c->tri_count++;
    uint32_t nb_t = T.n[(k + 1) % 3], nc_t = T.n[(k + 2) % 3], fb_t, fc_t, ce, nb_u, nc_u, fb_u, fc_u;
    int j = radinterp__cdt_neighbour_index(c, u, t);
    U = c->tri[u];
    d = U.v[j];
    ce = (T.flags >> k) & 1u;
    fb_t = (T.flags >> ((k + 1) % 3)) & 1u;
    fc_t = (T.flags >> ((k + 2) % 3)) & 1u;
    nc_u = U.n[(j + 1) % 3];  /* across (b, d), opposite c */
    nb_u = U.n[(j + 2) % 3];  /* across (d, c), opposite b */
    fc_u = (U.flags >> ((j + 1) % 3)) & 1u;
    fb_u = (U.flags >> ((j + 2) % 3)) & 1u;
    radinterp__cdt_set(c, t, a, b, p, u2, t2, nc_t, ce | (fc_t << 2));
    radinterp__cdt_set(c, t2, a, p, cc, u, nb_t, t, ce | (fb_t << 1));
    radinterp__cdt_set(c, u, d, cc, p, t2, u2, nb_u, ce | (fb_u << 2));
    radinterp__cdt_set(c, u2, d, p, b, t, nc_u, u, ce | (fc_u << 1));
    radinterp__cdt_relink(c, nb_t, t, t2);
    radinterp__cdt_relink(c, nc_u, u, u2);
    radinterp__cdt_touch(c, t2);
    radinterp__cdt_touch(c, u2);
    radinterp__cdt_touch(c, u);
    radinterp__cdt_touch(c, t);
    c->fix.count = 0;
    radinterp__u32s_push(c, &c->fix, t);
    radinterp__u32s_push(c, &c->fix, t2);
    radinterp__u32s_push(c, &c->fix, u);
    radinterp__u32s_push(c, &c->fix, u2);
}

static uint32_t radinterp__cdt_rand(radinterp__cdt *c)
{
    c->rng ^= c->rng << 13;
    c->rng ^= c->rng >> 17;
    c->rng ^= c->rng << 5;
    return c->rng;
}

/* Where p lies relative to ghost t's hull edge (a, b) when collinear with it:
   0 on the open edge, 1 beyond b, 2 beyond a, 3 at a, 4 at b. */
static int radinterp__cdt_along(const double *pa, const double *pb, const double *p)
{
    double ex = pb[0] - pa[0], ey = pb[1] - pa[1];
    double s = (p[0] - pa[0]) * ex + (p[1] - pa[1]) * ey, l = ex * ex + ey * ey;
    if (p[0] == pa[0] && p[1] == pa[1]) return 3;
    if (p[0] == pb[0] && p[1] == pb[1]) return 4;
    if (s <= 0.0) return 2;
    if (s >= l) return 1;
    return 0;
}

/* Classifies p against triangle t: -1 outside (sets *next to the triangle to
   walk to), 0 inside, 1 on the edge opposite v[*k], 2 at vertex v[*k]. */
static int radinterp__cdt_classify(radinterp__cdt *c, uint32_t t, const double *p, int *k, uint32_t *next)
{
    const radinterp__cdt_tri *T = &c->tri[t];
    int g = radinterp__cdt_ghost_index(c, t), i, zeros = 0, zero_edge = -1, r;
    double o[3];
    if (g >= 0) {
        const double *pa = radinterp__cdt_p(c, T->v[(g + 1) % 3]), *pb = radinterp__cdt_p(c, T->v[(g + 2) % 3]);
        double s = radinterp__orient2d(pa, pb, p);
        if (s > 0.0) return 0;
        if (s < 0.0) { *next = T->n[g]; return -1; }
        switch (radinterp__cdt_along(pa, pb, p)) {
        case 0: *k = g; return 1;
        case 3: *k = (g + 1) % 3; return 2;
        case 4: *k = (g + 2) % 3; return 2;
        case 1: *next = T->n[(g + 1) % 3]; return -1;
        default: *next = T->n[(g + 2) % 3]; return -1;
        }
    }
    r = (int)(radinterp__cdt_rand(c) % 3u);
    for (i = 0; i < 3; i++) {
        int e = (r + i) % 3;
        o[e] = radinterp__orient2d(radinterp__cdt_p(c, T->v[(e + 1) % 3]), radinterp__cdt_p(c, T->v[(e + 2) % 3]), p);
        if (o[e] < 0.0) { *next = T->n[e]; return -1; }
    }
    for (i = 0; i < 3; i++)
        if (o[i] == 0.0) { zeros++; zero_edge = i; }
    if (zeros == 0) return 0;
    if (zeros == 1) { *k = zero_edge; return 1; }
    for (i = 0; i < 3; i++)
        if (o[i] != 0.0) { *k = i; return 2; } /* on two edges: the vertex they share */
    return 2;
}

static uint32_t radinterp__cdt_locate(radinterp__cdt *c, const double *p, int *where, int *k)
{
    uint32_t t = c->last, steps = 0, next = 0, limit = 3 * c->tri_count + 64, i;
    if (t >= c->tri_count) t = 0;
    for (;;) {
        int w = radinterp__cdt_classify(c, t, p, k, &next);
        if (w >= 0) { *where = w; return t; }
        t = next;
        if (++steps > limit) break;
    }
    /* the walk did not settle (it cannot cycle forever, but be certain): scan */
    for (i = 0; i < c->tri_count; i++) {
        int w = radinterp__cdt_classify(c, i, p, k, &next);
        if (w >= 0) { *where = w; return i; }
    }
    *where = -1;
    return RADINTERP__NONE;
}

/* Inserts the stored vertex v into the triangulation; returns v, or the
   vertex it coincides with (v is then left out). */
static uint32_t radinterp__cdt_insert_vertex(radinterp__cdt *c, uint32_t v)
{
    const double *p = radinterp__cdt_p(c, v);
    int where = 0, k = 0, i;
    uint32_t t = radinterp__cdt_locate(c, p, &where, &k);
    if (t == RADINTERP__NONE) { c->failed = 1; return RADINTERP__NONE; }
    if (where == 2) return c->tri[t].v[k];
    if (c->merge_distance2 > 0.0) {
        for (i = 0; i < 3; i++) {
            uint32_t w = c->tri[t].v[i];
            const double *q;
            if (w == RADINTERP__GHOST) continue;
            q = radinterp__cdt_p(c, w);
            if ((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) <= c->merge_distance2) return w;
        }
    }
    if (!radinterp__cdt_reserve(c, 0, 2)) return RADINTERP__NONE;
    if (where == 0) radinterp__cdt_split_triangle(c, t, v);
    else radinterp__cdt_split_edge(c, t, k, v);
    radinterp__cdt_legalize(c, v);
    c->last = c->vtri[v];
    return v;
}

/* The first triangle, from three non-collinear stored vertices, closed by
   three ghosts. */
static void radinterp__cdt_start(radinterp__cdt *c, uint32_t a, uint32_t b, uint32_t d)
{
    uint32_t T = 0, G0 = 1, G1 = 2, G2 = 3, G = RADINTERP__GHOST;
    radinterp__cdt_set(c, T, a, b, d, G0, G1, G2, 0);
    radinterp__cdt_set(c, G0, d, b, G, G2, G1, T, 0);
    radinterp__cdt_set(c, G1, a, d, G, G0, G2, T, 0);
    radinterp__cdt_set(c, G2, b, a, G, G1, G0, T, 0);
    c->tri_count = 4;
    c->vtri[a] = c->vtri[b] = c->vtri[d] = T;
    c->last = T;
    c->started = 1;
}

/* Before the first triangle exists every point waits (all so far are
   collinear); the first point off their line starts the triangulation. */
static uint32_t radinterp__cdt_add_waiting(radinterp__cdt *c, const double *p)
{
    uint32_t i, v, n = c->vertex_count, third = RADINTERP__NONE;
    for (i = 0; i < n; i++) {
        const double *q = radinterp__cdt_p(c, i);
        double dx = q[0] - p[0], dy = q[1] - p[1];
        if ((dx == 0.0 && dy == 0.0) || dx * dx + dy * dy <= c->merge_distance2) return i;
    }
    if (!radinterp__cdt_reserve(c, 1, 4)) return RADINTERP__NONE;
    v = c->vertex_count++;
    c->xy[2 * v] = p[0];
    c->xy[2 * v + 1] = p[1];
    c->vtri[v] = RADINTERP__NONE;
    if (v < 2) return v;
    if (radinterp__orient2d(radinterp__cdt_p(c, 0), radinterp__cdt_p(c, 1), p) == 0.0) return v;
    third = v;
    if (radinterp__orient2d(radinterp__cdt_p(c, 0), radinterp__cdt_p(c, 1), p) > 0.0) radinterp__cdt_start(c, 0, 1, third);
    else radinterp__cdt_start(c, 1, 0, third);
    for (i = 2; i < v; i++) radinterp__cdt_insert_vertex(c, i); /* the collinear ones that waited */
    return v;
}

static uint32_t radinterp__cdt_add_point(radinterp__cdt *c, double x, double y)
{
    double p[2];
    uint32_t v, w;
    p[0] = x;
    p[1] = y;
    if (!(fabs(x) < 1e300 && fabs(y) < 1e300)) { c->failed = 1; return RADINTERP__NONE; }
    if (!c->started) return radinterp__cdt_add_waiting(c, p);
    if (!radinterp__cdt_reserve(c, 1, 2)) return RADINTERP__NONE;
    v = c->vertex_count;
    c->xy[2 * v] = x;
    c->xy[2 * v + 1] = y;
    c->vtri[v] = RADINTERP__NONE;
    c->vertex_count++;
    w = radinterp__cdt_insert_vertex(c, v);
    if (w != v) c->vertex_count--; /* merged into w (or failed): drop the copy */
    return w;
}

/* Hilbert-curve index of a point on a 65536 x 65536 grid. */
static uint32_t radinterp__hilbert(uint32_t x, uint32_t y)
{
    uint32_t s, d = 0;
    for (s = 1u << 15; s > 0; s >>= 1) {
        uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
        d += s * s * ((3u * rx) ^ ry);
        if (ry == 0) {
            uint32_t t;
            if (rx == 1) { x = 0xFFFFu - x; y = 0xFFFFu - y; }
            t = x; x = y; y = t;
        }
    }
    return d;
}

static int radinterp__cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : (x > y ? 1 : 0);
}

/* Adds n points in Hilbert order, so that each walk is short; ids[i]
   receives the vertex of point i. Returns 0, or -1 when out of memory. */
RADINTERP__MAYBE_UNUSED static int radinterp__cdt_add_points(radinterp__cdt *c, const double *xy, uint32_t n, uint32_t *ids)
{
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX}, sx, sy;
    uint64_t *keys;
    uint32_t i;
    if (n == 0) return 0;
    keys = (uint64_t *)radinterp__alloc_array(&c->alloc, n, sizeof(uint64_t));
    if (!keys) { c->failed = 1; return -1; }
    for (i = 0; i < n; i++) {
        lo[0] = xy[2 * i] < lo[0] ? xy[2 * i] : lo[0];
        lo[1] = xy[2 * i + 1] < lo[1] ? xy[2 * i + 1] : lo[1];
        hi[0] = xy[2 * i] > hi[0] ? xy[2 * i] : hi[0];
        hi[1] = xy[2 * i + 1] > hi[1] ? xy[2 * i + 1] : hi[1];
    }
    sx = hi[0] > lo[0] ? 65535.0 / (hi[0] - lo[0]) : 0.0;
    sy = hi[1] > lo[1] ? 65535.0 / (hi[1] - lo[1]) : 0.0;
    for (i = 0; i < n; i++) {
        double fx = (xy[2 * i] - lo[0]) * sx, fy = (xy[2 * i + 1] - lo[1]) * sy;
        uint32_t qx = fx >= 0.0 && fx <= 65535.0 ? (uint32_t)fx : 0u, qy = fy >= 0.0 && fy <= 65535.0 ? (uint32_t)fy : 0u;
        keys[i] = ((uint64_t)radinterp__hilbert(qx, qy) << 32) | i;
    }
    qsort(keys, n, sizeof(uint64_t), radinterp__cmp_u64);
    for (i = 0; i < n; i++) {
        uint32_t j = (uint32_t)(keys[i] & 0xFFFFFFFFu);
        ids[j] = radinterp__cdt_add_point(c, xy[2 * j], xy[2 * j + 1]);
        if (ids[j] == RADINTERP__NONE) { radinterp__free(&c->alloc, keys); return -1; }
    }
    radinterp__free(&c->alloc, keys);
    return 0;
}

/* Finds the edge (u, v): sets *t and *k (the edge is opposite v[*k] of *t). */
static int radinterp__cdt_find_edge(const radinterp__cdt *c, uint32_t u, uint32_t v, uint32_t *t, int *k)
{
    uint32_t s = c->vtri[u], cur = s, guard = 0;
    if (s == RADINTERP__NONE) return 0;
    do {
        int i = radinterp__cdt_index(c, cur, u);
        if (i < 0) return 0;
        if (c->tri[cur].v[(i + 1) % 3] == v) { *t = cur; *k = (i + 2) % 3; return 1; }
        if (c->tri[cur].v[(i + 2) % 3] == v) { *t = cur; *k = (i + 1) % 3; return 1; }
        cur = c->tri[cur].n[(i + 1) % 3];
    } while (cur != s && ++guard < c->tri_count);
    return 0;
}

static void radinterp__cdt_mark(radinterp__cdt *c, uint32_t t, int k, int on)
{
    uint32_t u = c->tri[t].n[k];
    int j = radinterp__cdt_neighbour_index(c, u, t);
    if (on) { c->tri[t].flags |= 1u << k; c->tri[u].flags |= 1u << j; }
    else { c->tri[t].flags &= ~(1u << k); c->tri[u].flags &= ~(1u << j); }
}

static int radinterp__cdt_constrain(radinterp__cdt *c, uint32_t a, uint32_t b)
{
    uint32_t t;
    int k;
    if (!radinterp__cdt_find_edge(c, a, b, &t, &k)) return 0;
    radinterp__cdt_mark(c, t, k, 1);
    return 1;
}

/* The edge (a, b) near triangle hint: *t, *k with the edge opposite
   v[*k] of *t, found in the hint when it still holds the edge (the common
   case while flipping), else around a. */
static int radinterp__cdt_edge_near(const radinterp__cdt *c, uint32_t a, uint32_t b, uint32_t hint, uint32_t *t, int *k)
{
    if (hint < c->tri_count) {
        int i = radinterp__cdt_index(c, hint, a), j = radinterp__cdt_index(c, hint, b);
        if (i >= 0 && j >= 0) { *t = hint; *k = 3 - i - j; return 1; }
    }
    return radinterp__cdt_find_edge(c, a, b, t, k);
}

static int radinterp__cdt_queue_edge(radinterp__cdt *c, uint32_t a, uint32_t b, uint32_t hint)
{
    return radinterp__u32s_push2(c, &c->queue, a, b) && radinterp__u32s_push(c, &c->queue, hint);
}

/* Lawson flips over the edges queued in c->queue (vertex pairs with a
   triangle hint) until each of them, and every edge a flip exposes, is
   constrained or locally Delaunay. */
static void radinterp__cdt_lawson(radinterp__cdt *c)
{
    uint32_t steps = 0;
    while (c->queue.count >= 3) {
        uint32_t hint = c->queue.data[--c->queue.count], b = c->queue.data[--c->queue.count];
        uint32_t a = c->queue.data[--c->queue.count], t, u, d;
        int k, j;
        if (++steps > RADINTERP__CDT_STEP_LIMIT) { c->failed = 1; return; }
        if (!radinterp__cdt_edge_near(c, a, b, hint, &t, &k)) continue;
        if ((c->tri[t].flags >> k) & 1u || radinterp__cdt_is_ghost(c, t)) continue;
        u = c->tri[t].n[k];
        if (radinterp__cdt_is_ghost(c, u)) continue;
        j = radinterp__cdt_neighbour_index(c, u, t);
        d = c->tri[u].v[j];
        if (!radinterp__cdt_in_circle(c, t, d) || !radinterp__cdt_flip_ok(c, t, k)) continue;
        radinterp__cdt_flip(c, t, k);
        /* t = (x, y, d), u = (x, d, z): recheck the four outer edges */
        if (!radinterp__cdt_queue_edge(c, c->tri[t].v[0], c->tri[t].v[1], t) ||
            !radinterp__cdt_queue_edge(c, c->tri[t].v[1], c->tri[t].v[2], t) ||
            !radinterp__cdt_queue_edge(c, c->tri[u].v[1], c->tri[u].v[2], u) ||
            !radinterp__cdt_queue_edge(c, c->tri[u].v[2], c->tri[u].v[0], u))
            return;
    }
}

/* After a segment went in: every edge of the triangles it changed. */
static void radinterp__cdt_restore(radinterp__cdt *c)
{
    uint32_t i;
    c->queue.count = 0;
    for (i = 0; i < c->touched.count; i++) {
        uint32_t t = c->touched.data[i];
        const uint32_t *v = c->tri[t].v;
        int e;
        for (e = 0; e < 3; e++) {
            uint32_t a = v[(e + 1) % 3], b = v[(e + 2) % 3];
            if (a != RADINTERP__GHOST && b != RADINTERP__GHOST && !radinterp__cdt_queue_edge(c, a, b, t)) return;
        }
    }
    radinterp__cdt_lawson(c);
}

/* Does the edge (p, q) cross the line through a and b, strictly? */
static int radinterp__cdt_crosses(const radinterp__cdt *c, uint32_t a, uint32_t b, uint32_t p, uint32_t q)
{
    double op = radinterp__orient2d(radinterp__cdt_p(c, a), radinterp__cdt_p(c, b), radinterp__cdt_p(c, p));
    double oq = radinterp__orient2d(radinterp__cdt_p(c, a), radinterp__cdt_p(c, b), radinterp__cdt_p(c, q));
    return (op > 0.0 && oq < 0.0) || (op < 0.0 && oq > 0.0);
}

/* Squared distance of p from the line through a and b, and where along
   (a, b) its projection falls (0 at a, 1 at b). */
static double radinterp__cdt_line_distance2(const double *a, const double *b, const double *p, double *along)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
    double c = (p[0] - a[0]) * dy - (p[1] - a[1]) * dx;
    *along = l2 > 0.0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0.0;
    return l2 > 0.0 ? c * c / l2 : 0.0;
}

/* The segment (a, b) crosses the constraint (r, l). Where the two are so
   close to collinear that their crossing point is ill-conditioned (an
   endpoint of one lies within RADINTERP__CDT_SNAP of their lengths from
   the other's line), the segment bends through that endpoint; otherwise
   the crossing point becomes a vertex that splits both. */
#define RADINTERP__CDT_SNAP 1e-11
static void radinterp__cdt_split_crossing(radinterp__cdt *c, uint32_t a, uint32_t b, uint32_t r, uint32_t l)
{
    const double *pa = radinterp__cdt_p(c, a), *pb = radinterp__cdt_p(c, b);
    const double *pr = radinterp__cdt_p(c, r), *pl = radinterp__cdt_p(c, l);
    double ab2 = (pb[0] - pa[0]) * (pb[0] - pa[0]) + (pb[1] - pa[1]) * (pb[1] - pa[1]);
    double rl2 = (pl[0] - pr[0]) * (pl[0] - pr[0]) + (pl[1] - pr[1]) * (pl[1] - pr[1]);
    double tol2 = RADINTERP__CDT_SNAP * RADINTERP__CDT_SNAP * (ab2 > rl2 ? ab2 : rl2), s, x, y, along;
    double dr = radinterp__cdt_line_distance2(pa, pb, pr, &along), sr = along;
    double dl = radinterp__cdt_line_distance2(pa, pb, pl, &along), sl = along;
    double da = radinterp__cdt_line_distance2(pr, pl, pa, &along), ta = along;
    double db = radinterp__cdt_line_distance2(pr, pl, pb, &along), tb = along;
    uint32_t v = RADINTERP__NONE;
    if (dr <= tol2 && sr > 0.0 && sr < 1.0 && (dr <= dl || !(sl > 0.0 && sl < 1.0))) v = r;
    else if (dl <= tol2 && sl > 0.0 && sl < 1.0) v = l;
    else if (da <= tol2 && ta > 0.0 && ta < 1.0) v = a;
    else if (db <= tol2 && tb > 0.0 && tb < 1.0) v = b;
    if (v == RADINTERP__NONE) {
        double dx = pb[0] - pa[0], dy = pb[1] - pa[1];
        double or_ = dx * (pr[1] - pa[1]) - dy * (pr[0] - pa[0]);
        double ol = dx * (pl[1] - pa[1]) - dy * (pl[0] - pa[0]);
        s = or_ - ol != 0.0 ? or_ / (or_ - ol) : 0.5;
        if (!(s >= 0.0)) s = 0.0;
        if (s > 1.0) s = 1.0;
        x = pr[0] + s * (pl[0] - pr[0]);
        y = pr[1] + s * (pl[1] - pr[1]);
        v = radinterp__cdt_add_point(c, x, y);
        if (v == RADINTERP__NONE) return;
    }
    if (v != r && v != l) {
        uint32_t t;
        int k;
        if (radinterp__cdt_find_edge(c, r, l, &t, &k)) {
            /* no longer a constraint: it must be Delaunay again (or flipped away) */
            radinterp__cdt_mark(c, t, k, 0);
            c->queue.count = 0;
            radinterp__cdt_queue_edge(c, r, l, t);
            radinterp__cdt_lawson(c);
        }
        radinterp__u32s_push2(c, &c->segs, v, b);
        radinterp__u32s_push2(c, &c->segs, a, v);
        radinterp__u32s_push2(c, &c->segs, r, v);
        radinterp__u32s_push2(c, &c->segs, v, l);
    } else {
        radinterp__u32s_push2(c, &c->segs, v, b);
        radinterp__u32s_push2(c, &c->segs, a, v);
    }
}

/* One piece (a, b) of a segment: either it ends early at a vertex on it
   (the rest is pushed back), or a crossing constraint splits it, or the
   crossed edges are flipped away until (a, end) is an edge. */
static void radinterp__cdt_segment_piece(radinterp__cdt *c, uint32_t a, uint32_t b)
{
    const double *pa = radinterp__cdt_p(c, a), *pb = radinterp__cdt_p(c, b);
    uint32_t s = c->vtri[a], t = s, right = 0, left = 0, end, guard = 0, head, steps = 0;
    int found = 0;
    /* 1. the triangle at a that the segment leaves through */
    do {
        int i = radinterp__cdt_index(c, t, a);
        uint32_t p = c->tri[t].v[(i + 1) % 3], q = c->tri[t].v[(i + 2) % 3];
        if (p != RADINTERP__GHOST && q != RADINTERP__GHOST) {
            const double *pp = radinterp__cdt_p(c, p), *pq = radinterp__cdt_p(c, q);
            double o1 = radinterp__orient2d(pa, pp, pb), o2 = radinterp__orient2d(pa, pq, pb);
            if (o1 == 0.0 && (pp[0] - pa[0]) * (pb[0] - pa[0]) + (pp[1] - pa[1]) * (pb[1] - pa[1]) > 0.0) {
                radinterp__cdt_mark(c, t, (i + 2) % 3, 1);  /* p lies on the segment */
                radinterp__u32s_push2(c, &c->segs, p, b);
                return;
            }
            if (o2 == 0.0 && (pq[0] - pa[0]) * (pb[0] - pa[0]) + (pq[1] - pa[1]) * (pb[1] - pa[1]) > 0.0) {
                radinterp__cdt_mark(c, t, (i + 1) % 3, 1);
                radinterp__u32s_push2(c, &c->segs, q, b);
                return;
            }
            if (o1 > 0.0 && o2 < 0.0) { right = p; left = q; found = 1; break; }
        }
        t = c->tri[t].n[(i + 1) % 3];
    } while (t != s && ++guard < c->tri_count);
    if (!found) { c->failed = 1; return; }
    /* 2. walk across the crossed edges */
    c->queue.count = 0;
    for (;;) {
        uint32_t u, e;
        int m = radinterp__cdt_index(c, t, right) , w;
        m = 3 - m - radinterp__cdt_index(c, t, left);  /* the vertex opposite (right, left) */
        if ((c->tri[t].flags >> m) & 1u) { radinterp__cdt_split_crossing(c, a, b, right, left); return; }
        if (!radinterp__u32s_push2(c, &c->queue, right, left)) return;
        u = c->tri[t].n[m];
        w = radinterp__cdt_neighbour_index(c, u, t);
        e = c->tri[u].v[w];
        if (e == RADINTERP__GHOST || ++steps > c->tri_count) { c->failed = 1; return; }
        if (e == b) { end = b; break; }
        {
            double o = radinterp__orient2d(pa, pb, radinterp__cdt_p(c, e));
            if (o == 0.0) { end = e; radinterp__u32s_push2(c, &c->segs, e, b); break; }
            if (o > 0.0) left = e;
            else right = e;
        }
        t = u;
    }
    /* 3. flip the crossed edges away (Sloan): an edge whose quadrilateral is
       not convex waits at the back of the queue */
    c->touched.count = 0;
    head = 0;
    steps = 0;
    while (head < c->queue.count) {
        uint32_t p = c->queue.data[head], q = c->queue.data[head + 1], tt, x, d;
        int k;
        head += 2;
        if (++steps > RADINTERP__CDT_STEP_LIMIT) { c->failed = 1; return; }
        if (!radinterp__cdt_find_edge(c, p, q, &tt, &k)) continue;
        if (!radinterp__cdt_flip_ok(c, tt, k)) {
            if (!radinterp__u32s_push2(c, &c->queue, p, q)) return;
            continue;
        }
        x = c->tri[tt].n[k];
        radinterp__cdt_flip(c, tt, k);
        radinterp__u32s_push(c, &c->touched, tt);
        radinterp__u32s_push(c, &c->touched, x);
        d = c->tri[tt].v[2];  /* tt = (apex, b, d): the new edge is (apex, d) */
        if (radinterp__cdt_crosses(c, a, end, c->tri[tt].v[0], d) &&
            !radinterp__u32s_push2(c, &c->queue, c->tri[tt].v[0], d))
            return;
        if (head > 4096 && head * 2 > c->queue.count) { /* keep the queue short */
            memmove(c->queue.data, c->queue.data + head, (size_t)(c->queue.count - head) * 4);
            c->queue.count -= head;
            head = 0;
        }
    }
    if (!radinterp__cdt_constrain(c, a, end)) { c->failed = 1; return; }
    radinterp__cdt_restore(c);
}

/* Makes the segment between vertices a and b a union of constrained edges.
   Returns 0, or -1 when it could not be completed (c->failed is set). */
static int radinterp__cdt_add_segment(radinterp__cdt *c, uint32_t a, uint32_t b)
{
    uint32_t steps = 0;
    if (!c->started || a >= c->vertex_count || b >= c->vertex_count) return -1;
    if (c->vtri[a] == RADINTERP__NONE || c->vtri[b] == RADINTERP__NONE) return -1;
    c->segs.count = 0;
    if (!radinterp__u32s_push2(c, &c->segs, a, b)) return -1;
    while (c->segs.count >= 2 && !c->failed) {
        uint32_t y = c->segs.data[--c->segs.count], x = c->segs.data[--c->segs.count];
        if (x == y) continue;
        if (++steps > RADINTERP__CDT_STEP_LIMIT) { c->failed = 1; break; }
        if (radinterp__cdt_constrain(c, x, y)) continue;
        radinterp__cdt_segment_piece(c, x, y);
    }
    return c->failed ? -1 : 0;
}

/* ======================================================================
   10. polygons in double precision and the point-to-polygon form factor
   ---------------------------------------------------------------------- */
#define RADINTERP__PI 3.14159265358979323846
#define RADINTERP__POLY_MAX 16   /* a quadrilateral clipped by up to 12 planes */

static void radinterp__d3_sub(const double *a, const double *b, double *r) { r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2]; }
static double radinterp__d3_dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void radinterp__d3_cross(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}
static void radinterp__d3_from_f(const float *f, double *d) { d[0] = f[0]; d[1] = f[1]; d[2] = f[2]; }
static double radinterp__d3_len(const double *a) { return sqrt(radinterp__d3_dot(a, a)); }

/* One edge's term of eq. 6.1 without the 1/(2 pi): n . Gamma_g, where
   Gamma_g has the length of the angle gamma between ra and rb (the edge's
   ends seen from p) and the direction of ra x rb. atan2 keeps gamma exact
   for nearly parallel and nearly opposite vectors; an edge through p (whose
   direction is undefined) contributes nothing. */
static double radinterp__ff_edge(const double *ra, const double *rb, const double *n)
{
    double c[3], s;
    radinterp__d3_cross(ra, rb, c);
    s = radinterp__d3_len(c);
    if (s == 0.0) return 0.0;
    return atan2(s, radinterp__d3_dot(ra, rb)) * radinterp__d3_dot(n, c) / s;
}

/* Eq. 6.1 for a polygon wholly in front of p's tangent plane: positive when
   the polygon winds counter-clockwise seen from the side facing p. */
static double radinterp__ff_poly(const double *p, const double *n, const double (*v)[3], int count)
{
    double r[RADINTERP__POLY_MAX][3], sum = 0.0;
    int i;
    for (i = 0; i < count; i++) radinterp__d3_sub(v[i], p, r[i]);
    for (i = 0; i < count; i++) sum += radinterp__ff_edge(r[i], r[(i + 1) % count], n);
    return -sum / (2.0 * RADINTERP__PI);
}

/* Sutherland-Hodgman: the part of the convex polygon in n . x >= d.
   Returns the vertex count of out (at most count + 1; < 3 means empty). */
static int radinterp__clip_poly(const double (*in)[3], int count, const double *n, double d, double (*out)[3])
{
    int i, m = 0;
    for (i = 0; i < count; i++) {
        const double *a = in[i], *b = in[(i + 1) % count];
        double da = radinterp__d3_dot(n, a) - d, db = radinterp__d3_dot(n, b) - d;
        if (da >= 0.0 && m < RADINTERP__POLY_MAX) { out[m][0] = a[0]; out[m][1] = a[1]; out[m][2] = a[2]; m++; }
        if (((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0)) && m < RADINTERP__POLY_MAX) {
            double s = da / (da - db);
            out[m][0] = a[0] + s * (b[0] - a[0]);
            out[m][1] = a[1] + s * (b[1] - a[1]);
            out[m][2] = a[2] + s * (b[2] - a[2]);
            m++;
        }
    }
    return m;
}

static void radinterp__copy_poly(const double (*in)[3], int count, double (*out)[3])
{
    memcpy(out, in, (size_t)count * sizeof(double[3]));
}

/* Area of a planar polygon (Newell), with its unnormalised normal. */
static double radinterp__poly_area(const double (*v)[3], int count)
{
    double s[3] = {0.0, 0.0, 0.0}, c[3];
    int i;
    for (i = 0; i < count; i++) {
        radinterp__d3_cross(v[i], v[(i + 1) % count], c);
        s[0] += c[0]; s[1] += c[1]; s[2] += c[2];
    }
    return 0.5 * radinterp__d3_len(s);
}

/* Streaming form of eq. 6.1 for the public function: vertices arrive one by
   one (already clipped), so no buffer bounds the polygon size. */
typedef struct radinterp__ff_stream {
    double p[3], n[3], first[3], prev[3], sum;
    uint32_t count;
} radinterp__ff_stream;

static void radinterp__ff_stream_add(radinterp__ff_stream *s, const double *x)
{
    double r[3];
    radinterp__d3_sub(x, s->p, r);
    if (s->count == 0) memcpy(s->first, r, sizeof r);
    else s->sum += radinterp__ff_edge(s->prev, r, s->n);
    memcpy(s->prev, r, sizeof r);
    s->count++;
}

RADINTERP_API double radinterp_form_factor_point_polygon(const float p[3], const float n[3],
                                                         const float *verts, uint32_t count)
{
    radinterp__ff_stream st;
    double len, d, front = 0.0;
    uint32_t i;
    if (!p || !n || !verts || count < 3) return 0.0;
    if (!radinterp__finite3(p) || !radinterp__finite3(n)) return 0.0;
    for (i = 0; i < count; i++)
        if (!radinterp__finite3(verts + 3 * (size_t)i)) return 0.0;
    memset(&st, 0, sizeof st);
    radinterp__d3_from_f(p, st.p);
    radinterp__d3_from_f(n, st.n);
    len = radinterp__d3_len(st.n);
    if (!(len > 0.0)) return 0.0;
    st.n[0] /= len; st.n[1] /= len; st.n[2] /= len;
    d = radinterp__d3_dot(st.n, st.p);
    /* horizon clipping to n . x >= n . p, one edge at a time */
    for (i = 0; i < count; i++) {
        double a[3], b[3], da, db;
        radinterp__d3_from_f(verts + 3 * (size_t)i, a);
        radinterp__d3_from_f(verts + 3 * (size_t)((i + 1) % count), b);
        da = radinterp__d3_dot(st.n, a) - d;
        db = radinterp__d3_dot(st.n, b) - d;
        if (da > front) front = da;
        if (da >= 0.0) radinterp__ff_stream_add(&st, a);
        if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0)) {
            double s = da / (da - db), x[3];
            x[0] = a[0] + s * (b[0] - a[0]);
            x[1] = a[1] + s * (b[1] - a[1]);
            x[2] = a[2] + s * (b[2] - a[2]);
            radinterp__ff_stream_add(&st, x);
        }
    }
    if (!(front > 0.0) || st.count < 3) return 0.0; /* nothing above the tangent plane */
    st.sum += radinterp__ff_edge(st.prev, st.first, st.n);
    return fabs(st.sum) / (2.0 * RADINTERP__PI);
}

/* ======================================================================
   11. solution data: patches, quadtree nodes, links, blockers
   The solution is the hierarchical radiosity state the point queries and the
   mesher read:
   - patches[i]: the caller's patch i (same index), its plane, corners,
     material and quadtree root; count == 0 marks a skipped (zero-area) one.
   - nodes: every quadtree node of every patch. Children of a node are four
     consecutive nodes: for a quadrilateral (v0 v1 v2 v3) the children are
     (v0 m01 c m30) (m01 v1 m12 c) (c m12 v2 m23) (m30 c m23 v3) with m the
     edge midpoints and c the centre; for a triangle (v0 v1 v2) they are the
     three corner triangles (v0 m01 m20) (m01 v1 m12) (m20 m12 v2) and the
     middle one (m12 m20 m01). Children wind like their parent.
   - links: each carries energy from a source node to a receiver node (a
     "gather" link; the two directions of an interaction are two links).
     Links are sorted by receiver: node.first_link .. + link_count are the
     links the node gathers. A point's irradiance comes from the links of its
     leaf and of every ancestor.
   - blockers: a link's potential occluders (patch indices) from shaft
     culling, blockers[link.first_blocker .. + link.blocker_count).
   - node.b is the radiosity of the node's open part and node.open the
     fraction of the node not enclosed by geometry resting on it.
   Helpers the mesher reuses: radinterp__node_split(s, node) (children with
   the parent's radiosity; ancestors' links keep delivering to them, so a
   split after solving needs no new links), radinterp__node_openness,
   radinterp__locate_leaf(s, patch, p), radinterp__node_poly, and the point
   query radinterp__irradiance(s, patch, p, toward, h, NULL) of section 14.
   ---------------------------------------------------------------------- */
typedef struct radinterp__patch {
    float v[4][3];            /* corners, counter-clockwise seen from the front */
    uint32_t count;           /* 3 or 4; 0 = skipped (zero area) */
    uint32_t material;
    uint32_t root;            /* quadtree root node; NONE when skipped */
    double n[3], d;           /* unit front normal and plane n . x = d */
    double area;
    float lo[3], hi[3];       /* bounding box */
    double centre[3], radius; /* bounding sphere */
    float rho[3], e[3];       /* reflectance and emitted radiosity */
} radinterp__patch;

typedef struct radinterp__node {
    float v[4][3];            /* corners, as the patch's */
    uint32_t count;           /* 3 or 4 */
    uint32_t patch;
    uint32_t parent;          /* NONE for a root */
    uint32_t child;           /* first of four consecutive children; NONE for a leaf */
    uint32_t depth;           /* 0 for a root */
    uint32_t first_link, link_count;   /* the links this node gathers */
    float area;
    float lo[3], hi[3];
    float b[3];               /* radiosity B (W/m^2) of the node's open part, constant over it */
    float h[3];               /* irradiance gathered by this node's own links (mean over the whole node) */
    float open;               /* fraction of the node not enclosed by touching geometry (such as the
                                 floor under a box standing on it); enclosed parts receive and show nothing */
} radinterp__node;

#define RADINTERP__LINK_FINAL 1u   /* may not be refined further */
#define RADINTERP__LINK_DEAD 2u    /* carries nothing: dropped at the next rebuild */

typedef struct radinterp__link {
    uint32_t receiver, source;         /* nodes */
    float ff;                          /* F: mean point-to-source factor over the receiver (4.2) */
    float dff;                         /* max - min of the point factors: transport error / B_src */
    uint32_t first_blocker, blocker_count;
    uint32_t flags;
} radinterp__link;

struct radinterp_solution {
    radinterp_allocator allocator;
    /* parameters after defaults */
    double eps, min_area, rel_error_cutoff, push_off, nudge, min_bp_segment, epsilon, diag;
    uint32_t max_iterations, ff_samples, visibility_rays;
    uint32_t visibility;               /* radinterp_visibility of point queries, never DEFAULT */
    uint64_t seed;
    radinterp_trace_fn trace;
    void *trace_user;
    /* scene */
    radinterp__patch *patches;
    uint32_t patch_count, skipped_patches;
    float scene_lo[3], scene_hi[3];
    radinterp__bvh bvh;
    uint32_t *tri_patch;               /* BVH triangle -> patch */
    /* hierarchy */
    radinterp__node *nodes;
    uint32_t node_count, node_cap;
    radinterp__link *links;
    uint32_t link_count;
    uint32_t *blockers;
    uint64_t blocker_count;
    uint32_t *leaves;                  /* leaf node indices in patch order */
    uint32_t leaf_count;
    /* statistics */
    uint32_t iterations;
    int converged;
    float max_relative_change;
    uint64_t shadow_rays;
};


/* ---- patch geometry ---------------------------------------------------- */

/* Newell's normal of a polygon (twice the area vector). */
static void radinterp__newell(const double (*v)[3], int count, double *n)
{
    int i;
    n[0] = n[1] = n[2] = 0.0;
    for (i = 0; i < count; i++) {
        const double *a = v[i], *b = v[(i + 1) % count];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
}

/* Removes repeated corners and corners on the line through their
   neighbours (a quadrilateral may so become a triangle). */
static int radinterp__simplify_corners(double (*v)[3], int count, double scale)
{
    int i, changed = 1;
    while (changed && count >= 3) {
        changed = 0;
        for (i = 0; i < count; i++) {
            const double *p = v[(i + count - 1) % count], *q = v[i], *r = v[(i + 1) % count];
            double e1[3], e2[3], c[3];
            radinterp__d3_sub(q, p, e1);
            radinterp__d3_sub(r, q, e2);
            radinterp__d3_cross(e1, e2, c);
            if (radinterp__d3_len(c) <= 1e-12 * scale * scale) {
                memmove(v[i], v[i + 1], (size_t)(count - i - 1) * sizeof(double[3]));
                count--;
                changed = 1;
                break;
            }
        }
    }
    return count;
}

typedef enum radinterp__patch_check {
    RADINTERP__PATCH_OK,
    RADINTERP__PATCH_DEGENERATE,
    RADINTERP__PATCH_NONPLANAR,
    RADINTERP__PATCH_NONCONVEX
} radinterp__patch_check;

/* Fills the geometry of a patch from its corners; reports degenerate,
   non-planar or non-convex input. */
static radinterp__patch_check radinterp__patch_setup(radinterp__patch *pt, double (*v)[3], int count,
                                                     double scene_diag, double planarity, double *deviation)
{
    double n[3], len, size = 0.0, c[3] = {0.0, 0.0, 0.0};
    int i, k;
    for (i = 0; i < count; i++)
        for (k = 0; k < count; k++) {
            double d[3];
            radinterp__d3_sub(v[i], v[k], d);
            if (radinterp__d3_len(d) > size) size = radinterp__d3_len(d);
        }
    count = radinterp__simplify_corners(v, count, size > 0.0 ? size : 1.0);
    *deviation = 0.0;
    if (count < 3) return RADINTERP__PATCH_DEGENERATE;
    radinterp__newell((const double (*)[3])v, count, n);
    len = radinterp__d3_len(n);
    if (!(len > 0.0) || 0.5 * len <= 1e-14 * scene_diag * scene_diag) return RADINTERP__PATCH_DEGENERATE;
    n[0] /= len; n[1] /= len; n[2] /= len;
    for (i = 0; i < count; i++) { c[0] += v[i][0] / count; c[1] += v[i][1] / count; c[2] += v[i][2] / count; }
    for (i = 0; i < count; i++) {
        double d[3], dev;
        radinterp__d3_sub(v[i], c, d);
        dev = fabs(radinterp__d3_dot(d, n));
        if (dev > *deviation) *deviation = dev;
    }
    if (*deviation > planarity * size) return RADINTERP__PATCH_NONPLANAR;
    for (i = 0; i < count; i++) {
        double e1[3], e2[3], x[3];
        radinterp__d3_sub(v[i], v[(i + count - 1) % count], e1);
        radinterp__d3_sub(v[(i + 1) % count], v[i], e2);
        radinterp__d3_cross(e1, e2, x);
        if (!(radinterp__d3_dot(x, n) > 0.0)) return RADINTERP__PATCH_NONCONVEX;
    }
    pt->count = (uint32_t)count;
    pt->area = 0.5 * len;
    memcpy(pt->n, n, sizeof n);
    pt->d = radinterp__d3_dot(n, c);
    for (k = 0; k < 3; k++) { pt->lo[k] = FLT_MAX; pt->hi[k] = -FLT_MAX; }
    pt->radius = 0.0;
    for (i = 0; i < count; i++) {
        double d[3];
        for (k = 0; k < 3; k++) {
            pt->v[i][k] = (float)v[i][k];
            pt->lo[k] = radinterp__minf(pt->lo[k], pt->v[i][k]);
            pt->hi[k] = radinterp__maxf(pt->hi[k], pt->v[i][k]);
        }
        radinterp__d3_sub(v[i], c, d);
        if (radinterp__d3_len(d) > pt->radius) pt->radius = radinterp__d3_len(d);
    }
    memcpy(pt->centre, c, sizeof c);
    pt->radius *= 1.0 + 1e-6;
    return RADINTERP__PATCH_OK;
}

/* Corners of a patch or node as doubles. */
static int radinterp__node_poly(const radinterp__node *nd, double (*v)[3])
{
    uint32_t i;
    for (i = 0; i < nd->count; i++) radinterp__d3_from_f(nd->v[i], v[i]);
    return (int)nd->count;
}

static int radinterp__patch_poly(const radinterp__patch *pt, double (*v)[3])
{
    uint32_t i;
    for (i = 0; i < pt->count; i++) radinterp__d3_from_f(pt->v[i], v[i]);
    return (int)pt->count;
}

/* Largest signed distance of a patch's corners from a plane. */
static double radinterp__patch_front(const radinterp__patch *pt, const double *n, double d)
{
    double best = -DBL_MAX;
    uint32_t i;
    for (i = 0; i < pt->count; i++) {
        double x[3], s;
        radinterp__d3_from_f(pt->v[i], x);
        s = radinterp__d3_dot(n, x) - d;
        if (s > best) best = s;
    }
    return best;
}

static double radinterp__node_front(const radinterp__node *nd, const double *n, double d)
{
    double best = -DBL_MAX;
    uint32_t i;
    for (i = 0; i < nd->count; i++) {
        double x[3], s;
        radinterp__d3_from_f(nd->v[i], x);
        s = radinterp__d3_dot(n, x) - d;
        if (s > best) best = s;
    }
    return best;
}

/* ---- quadtree nodes ---------------------------------------------------- */

static void radinterp__node_bounds(radinterp__node *nd)
{
    uint32_t i;
    int k;
    double v[4][3];
    for (k = 0; k < 3; k++) { nd->lo[k] = FLT_MAX; nd->hi[k] = -FLT_MAX; }
    for (i = 0; i < nd->count; i++)
        for (k = 0; k < 3; k++) {
            nd->lo[k] = radinterp__minf(nd->lo[k], nd->v[i][k]);
            nd->hi[k] = radinterp__maxf(nd->hi[k], nd->v[i][k]);
        }
    radinterp__node_poly(nd, v);
    nd->area = (float)radinterp__poly_area((const double (*)[3])v, (int)nd->count);
}

static int radinterp__nodes_reserve(radinterp_solution *s, uint32_t extra)
{
    radinterp__node *p;
    uint32_t cap;
    if (s->node_count + extra <= s->node_cap) return 1;
    cap = s->node_cap ? s->node_cap : 256;
    while (cap < s->node_count + extra) {
        if (cap > 0x3FFFFFFFu) return 0;
        cap *= 2;
    }
    p = (radinterp__node *)radinterp__alloc_array(&s->allocator, cap, sizeof *p);
    if (!p) return 0;
    if (s->node_count) memcpy(p, s->nodes, (size_t)s->node_count * sizeof *p);
    radinterp__free(&s->allocator, s->nodes);
    s->nodes = p;
    s->node_cap = cap;
    return 1;
}

static void radinterp__mid(const float *a, const float *b, float *m)
{
    m[0] = 0.5f * (a[0] + b[0]);
    m[1] = 0.5f * (a[1] + b[1]);
    m[2] = 0.5f * (a[2] + b[2]);
}

static void radinterp__set_corners(radinterp__node *nd, const float *a, const float *b, const float *c,
                                   const float *d)
{
    memcpy(nd->v[0], a, 3 * sizeof(float));
    memcpy(nd->v[1], b, 3 * sizeof(float));
    memcpy(nd->v[2], c, 3 * sizeof(float));
    if (d) memcpy(nd->v[3], d, 3 * sizeof(float));
    nd->count = d ? 4u : 3u;
}

/* Splits a leaf into four children (4.1) that start with its radiosity.
   Returns 0, or -1 when out of memory. The node array may move. */
static int radinterp__node_split(radinterp_solution *s, uint32_t index)
{
    radinterp__node *nd, *ch;
    float m[4][3], c[3];
    uint32_t first, k;
    if (s->nodes[index].child != RADINTERP__NONE) return 0;
    if (!radinterp__nodes_reserve(s, 4)) return -1;
    nd = &s->nodes[index];
    first = s->node_count;
    ch = &s->nodes[first];
    memset(ch, 0, 4 * sizeof *ch);
    if (nd->count == 4) {
        radinterp__mid(nd->v[0], nd->v[1], m[0]);
        radinterp__mid(nd->v[1], nd->v[2], m[1]);
        radinterp__mid(nd->v[2], nd->v[3], m[2]);
        radinterp__mid(nd->v[3], nd->v[0], m[3]);
        for (k = 0; k < 3; k++) c[k] = 0.25f * (nd->v[0][k] + nd->v[1][k] + nd->v[2][k] + nd->v[3][k]);
        radinterp__set_corners(&ch[0], nd->v[0], m[0], c, m[3]);
        radinterp__set_corners(&ch[1], m[0], nd->v[1], m[1], c);
        radinterp__set_corners(&ch[2], c, m[1], nd->v[2], m[2]);
        radinterp__set_corners(&ch[3], m[3], c, m[2], nd->v[3]);
    } else {
        radinterp__mid(nd->v[0], nd->v[1], m[0]);
        radinterp__mid(nd->v[1], nd->v[2], m[1]);
        radinterp__mid(nd->v[2], nd->v[0], m[2]);
        radinterp__set_corners(&ch[0], nd->v[0], m[0], m[2], NULL);
        radinterp__set_corners(&ch[1], m[0], nd->v[1], m[1], NULL);
        radinterp__set_corners(&ch[2], m[2], m[1], nd->v[2], NULL);
        radinterp__set_corners(&ch[3], m[1], m[2], m[0], NULL);
    }
    for (k = 0; k < 4; k++) {
        ch[k].patch = nd->patch;
        ch[k].parent = index;
        ch[k].child = RADINTERP__NONE;
        ch[k].depth = nd->depth + 1;
        ch[k].first_link = 0;
        ch[k].link_count = 0;
        memcpy(ch[k].b, nd->b, sizeof nd->b);
        ch[k].open = -1.0f; /* measured before the node is used */
        radinterp__node_bounds(&ch[k]);
    }
    nd->child = first;
    s->node_count += 4;
    return 0;
}

static double radinterp__side(const float *a, const float *b, const double *p, const double *n)
{
    double e[3], q[3], c[3], x[3];
    radinterp__d3_from_f(a, x);
    e[0] = (double)b[0] - x[0]; e[1] = (double)b[1] - x[1]; e[2] = (double)b[2] - x[2];
    radinterp__d3_sub(p, x, q);
    radinterp__d3_cross(e, q, c);
    return radinterp__d3_dot(c, n);
}

static int radinterp__same_side(const float *a, const float *b, const double *p, const float *ref, const double *n)
{
    double r[3];
    radinterp__d3_from_f(ref, r);
    return radinterp__side(a, b, p, n) * radinterp__side(a, b, r, n) > 0.0;
}

/* The leaf of a patch's quadtree that contains p (a point on the patch):
   at each level the child is chosen by the lines that split the node. */
static uint32_t radinterp__locate_leaf(const radinterp_solution *s, uint32_t patch, const double *p)
{
    const double *n = s->patches[patch].n;
    uint32_t node = s->patches[patch].root;
    while (s->nodes[node].child != RADINTERP__NONE) {
        const radinterp__node *nd = &s->nodes[node], *ch = &s->nodes[nd->child];
        uint32_t pick;
        if (nd->count == 4) {
            /* u splits along m01-m23, v along m30-m12 */
            int hi_u = radinterp__same_side(ch[0].v[1], ch[2].v[3], p, nd->v[1], n);
            int hi_v = radinterp__same_side(ch[0].v[3], ch[1].v[2], p, nd->v[3], n);
            pick = hi_v ? (hi_u ? 2u : 3u) : (hi_u ? 1u : 0u);
        } else if (radinterp__same_side(ch[0].v[1], ch[0].v[2], p, nd->v[0], n)) {
            pick = 0;
        } else if (radinterp__same_side(ch[1].v[0], ch[1].v[2], p, nd->v[1], n)) {
            pick = 1;
        } else if (radinterp__same_side(ch[2].v[0], ch[2].v[1], p, nd->v[2], n)) {
            pick = 2;
        } else {
            pick = 3;
        }
        node = nd->child + pick;
    }
    return node;
}

/* Fraction of a node that is open: at a 3 x 3 grid of its points, a point
   is enclosed when rays in five directions of its hemisphere all meet back
   faces (it lies inside closed geometry resting on it, like the floor under
   a box). Enclosed parts neither receive nor show light, so radiosities are
   kept for the open part; without this a node half under a box would carry
   half its real radiosity to everything that sees its open half. */
static float radinterp__node_openness(const radinterp_solution *s, const radinterp__node *nd)
{
    const radinterp__patch *pt = &s->patches[nd->patch];
    radinterp__vec3 n = radinterp__v3((float)pt->n[0], (float)pt->n[1], (float)pt->n[2]), t, b;
    double off = 10.0 * s->epsilon * s->diag;
    int i, j, open = 0, k, r;
    /* a basis around n (Duff et al. 2017) */
    {
        float sg = n.z >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (sg + n.z), c = n.x * n.y * a;
        t = radinterp__v3(1.0f + sg * n.x * n.x * a, sg * c, -sg * n.x);
        b = radinterp__v3(c, sg + n.y * n.y * a, -n.y);
    }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double u = (i + 0.5) / 3.0, v = (j + 0.5) / 3.0, p[3];
            int enclosed = 1;
            for (k = 0; k < 3; k++) {
                if (nd->count == 4)
                    p[k] = (1 - u) * (1 - v) * nd->v[0][k] + u * (1 - v) * nd->v[1][k] + u * v * nd->v[2][k] + (1 - u) * v * nd->v[3][k];
                else
                    p[k] = (1 - sqrt(u)) * nd->v[0][k] + sqrt(u) * (1 - v) * nd->v[1][k] + sqrt(u) * v * nd->v[2][k];
            }
            for (r = 0; r < 5 && enclosed; r++) {
                static const float ct[5] = {0.0f, 0.866f, -0.866f, 0.0f, 0.0f}, cb[5] = {0.0f, 0.0f, 0.0f, 0.866f, -0.866f};
                float org[3], dir[3];
                float cn = r == 0 ? 1.0f : 0.5f;
                radinterp__hit hit;
                dir[0] = cn * n.x + ct[r] * t.x + cb[r] * b.x;
                dir[1] = cn * n.y + ct[r] * t.y + cb[r] * b.y;
                dir[2] = cn * n.z + ct[r] * t.z + cb[r] * b.z;
                for (k = 0; k < 3; k++) org[k] = (float)(p[k] + off * pt->n[k]);
                if (!radinterp__bvh_intersect(&s->bvh, org, dir, 0.0f, FLT_MAX, &hit)) enclosed = 0;
                else {
                    const double *hn = s->patches[s->tri_patch[hit.tri]].n;
                    if (hn[0] * dir[0] + hn[1] * dir[1] + hn[2] * dir[2] < 0.0) enclosed = 0; /* a front face */
                }
            }
            open += !enclosed;
        }
    return (float)open / 9.0f;
}

typedef struct radinterp__open_ctx { radinterp_solution *s; uint32_t first, count; } radinterp__open_ctx;

static void radinterp__open_job(void *ctx_, uint32_t index)
{
    radinterp__open_ctx *ctx = (radinterp__open_ctx *)ctx_;
    uint32_t i = ctx->first + index * 64, end = i + 64;
    if (end > ctx->first + ctx->count) end = ctx->first + ctx->count;
    for (; i < end; i++) ctx->s->nodes[i].open = radinterp__node_openness(ctx->s, &ctx->s->nodes[i]);
}

/* ---- shaft culling (Haines and Wallace) ------------------------------- */
typedef struct radinterp__shaft {
    double lo[3], hi[3];       /* union of the two boxes */
    double pn[12][3], pd[12];  /* x is outside when pn . x > pd */
    int planes;
} radinterp__shaft;

/* The shaft between two boxes: their union box cut by the planes through
   an edge of each box wherever one box alone reaches one face of the union
   and the other box alone reaches an adjacent face. */
static void radinterp__shaft_build(radinterp__shaft *sh, const float *alo, const float *ahi, const float *blo,
                                   const float *bhi)
{
    int i, j, si, sj, k;
    double A[2][3], B[2][3];
    for (k = 0; k < 3; k++) {
        A[0][k] = alo[k]; A[1][k] = ahi[k];
        B[0][k] = blo[k]; B[1][k] = bhi[k];
        sh->lo[k] = A[0][k] < B[0][k] ? A[0][k] : B[0][k];
        sh->hi[k] = A[1][k] > B[1][k] ? A[1][k] : B[1][k];
    }
    sh->planes = 0;
    for (i = 0; i < 3; i++)
        for (j = i + 1; j < 3; j++)
            for (si = 0; si < 2; si++)
                for (sj = 0; sj < 2; sj++) {
                    double ui = si ? sh->hi[i] : sh->lo[i], uj = sj ? sh->hi[j] : sh->lo[j];
                    int a_i = A[si][i] == ui, b_i = B[si][i] == ui, a_j = A[sj][j] == uj, b_j = B[sj][j] == uj;
                    double pa[2], pb[2], nx, ny, s;
                    if (!((a_i && !b_i && b_j && !a_j) || (b_i && !a_i && a_j && !b_j))) continue;
                    pa[0] = A[si][i]; pa[1] = A[sj][j];
                    pb[0] = B[si][i]; pb[1] = B[sj][j];
                    nx = pb[1] - pa[1];
                    ny = -(pb[0] - pa[0]);
                    s = nx * (ui - pa[0]) + ny * (uj - pa[1]); /* the union's corner is outside */
                    if (s == 0.0) continue;
                    if (s < 0.0) { nx = -nx; ny = -ny; }
                    sh->pn[sh->planes][0] = sh->pn[sh->planes][1] = sh->pn[sh->planes][2] = 0.0;
                    sh->pn[sh->planes][i] = nx;
                    sh->pn[sh->planes][j] = ny;
                    sh->pd[sh->planes] = nx * pa[0] + ny * pa[1];
                    sh->planes++;
                }
}

/* Is a box wholly outside the shaft (by more than margin)? */
static int radinterp__shaft_culls(const radinterp__shaft *sh, const float *lo, const float *hi, double margin)
{
    int k, p;
    for (k = 0; k < 3; k++)
        if ((double)lo[k] > sh->hi[k] + margin || (double)hi[k] < sh->lo[k] - margin) return 1;
    for (p = 0; p < sh->planes; p++) {
        const double *n = sh->pn[p];
        double m = 0.0, len = sqrt(radinterp__d3_dot(n, n));
        for (k = 0; k < 3; k++) m += n[k] * (n[k] > 0.0 ? (double)lo[k] : (double)hi[k]);
        if (m > sh->pd[p] + margin * len) return 1;
    }
    return 0;
}

/* Can patch b block light between receiver node r and source node src?
   Its box meets the shaft, and part of it lies in front of both planes. */
static int radinterp__may_block(const radinterp_solution *s, const radinterp__shaft *sh, uint32_t b,
                                const radinterp__node *r, const radinterp__node *src)
{
    const radinterp__patch *pb = &s->patches[b], *pr = &s->patches[r->patch], *ps = &s->patches[src->patch];
    double tol = s->epsilon * s->diag;
    if (b == r->patch || b == src->patch || pb->count == 0) return 0;
    /* a box that only touches the shaft's boundary cannot block: it must
       reach tol inside */
    if (radinterp__shaft_culls(sh, pb->lo, pb->hi, -tol)) return 0;
    if (radinterp__patch_front(pb, pr->n, pr->d) <= tol) return 0;
    if (radinterp__patch_front(pb, ps->n, ps->d) <= tol) return 0;
    return 1;
}

/* ======================================================================
   12. hierarchical radiosity (Hardt chapter 4, after Hanrahan et al.)
   ---------------------------------------------------------------------- */
/* A link waiting for its form factor: made by the initial linking or by
   splitting a link. Its candidate blockers are its parent's (filtered here
   by the new, narrower shaft) or the shaft culling result. */
typedef struct radinterp__pending {
    uint32_t receiver, source;
    uint32_t first, count;       /* candidates in the input pool; results at the same offset of the output pool */
    uint32_t filter;             /* candidates still need the shaft test */
    uint32_t kept;               /* blockers kept */
    float ff, dff;
    uint32_t dead;               /* no part of either element faces the other */
    uint32_t rays;
} radinterp__pending;

typedef struct radinterp__ff_ctx {
    radinterp_solution *s;
    radinterp__pending *pending;
    uint32_t begin, end, per_job;
    const uint32_t *in_pool;
    uint32_t *out_pool;
} radinterp__ff_ctx;

/* A uniformly distributed point of a convex polygon: u1 picks a fan triangle
   by area (and is reused inside it), u2 the position across it. */
static void radinterp__poly_point(const double (*v)[3], int count, const double *tri_area, double total, double u1,
                                  double u2, double *out)
{
    int t = 1, k;
    double acc = 0.0, a, b, x = u1 * total;
    while (t < count - 2 && acc + tri_area[t] < x) { acc += tri_area[t]; t++; }
    u1 = tri_area[t] > 0.0 ? (x - acc) / tri_area[t] : 0.5;
    if (u1 < 0.0) u1 = 0.0;
    if (u1 > 1.0) u1 = 1.0;
    a = sqrt(u1);
    b = u2;
    for (k = 0; k < 3; k++) out[k] = (1.0 - a) * v[0][k] + a * (1.0 - b) * v[t][k] + a * b * v[t + 1][k];
}

/* Areas of the fan triangles (v0, vt, vt+1), stored at index t. */
static double radinterp__fan_areas(const double (*v)[3], int count, double *tri_area)
{
    double total = 0.0;
    int t;
    for (t = 1; t + 1 < count; t++) {
        double e1[3], e2[3], c[3];
        radinterp__d3_sub(v[t], v[0], e1);
        radinterp__d3_sub(v[t + 1], v[0], e2);
        radinterp__d3_cross(e1, e2, c);
        tri_area[t] = 0.5 * radinterp__d3_len(c);
        total += tri_area[t];
    }
    return total;
}

static float radinterp__rng_unit(radinterp__rng *r) { return radinterp__rng_float(r); }

/* Sample i of n on a receiver polygon, with its weight (mean 1 over the
   polygon). When n is a square k x k the samples are jittered in a k x k
   grid of strata: mapped bilinearly onto a quadrilateral (weighted by the
   map's area density, 1 for a parallelogram) or area-preservingly onto a
   triangle. Otherwise they are stratified along the fan of triangles. */
static double radinterp__receiver_point(const double (*v)[3], int count, const double *tri_area, double total,
                                        uint32_t i, uint32_t n, radinterp__rng *rng, double *out)
{
    uint32_t k = (uint32_t)(sqrt((double)n) + 0.5);
    double u = radinterp__rng_unit(rng), w = radinterp__rng_unit(rng);
    int j;
    if (k * k == n && (count == 3 || count == 4)) {
        double a = ((i % k) + u) / k, b = ((i / k) + w) / k;
        if (count == 4) {
            double du[3], dv[3], c[3];
            for (j = 0; j < 3; j++) {
                out[j] = (1 - a) * (1 - b) * v[0][j] + a * (1 - b) * v[1][j] + a * b * v[2][j] + (1 - a) * b * v[3][j];
                du[j] = (1 - b) * (v[1][j] - v[0][j]) + b * (v[2][j] - v[3][j]);
                dv[j] = (1 - a) * (v[3][j] - v[0][j]) + a * (v[2][j] - v[1][j]);
            }
            radinterp__d3_cross(du, dv, c);
            return total > 0.0 ? radinterp__d3_len(c) / total : 1.0;
        }
        a = sqrt(a);
        for (j = 0; j < 3; j++) out[j] = (1 - a) * v[0][j] + a * (1 - b) * v[1][j] + a * b * v[2][j];
        return 1.0;
    }
    radinterp__poly_point(v, count, tri_area, total, (i + u) / n, w, out);
    return 1.0;
}

/* Is the segment from a to b blocked? Through the caller's ray caster or
   the built-in BVH. */
static int radinterp__segment_blocked(const radinterp_solution *s, const double *a, const double *b)
{
    float org[3], dir[3];
    int k;
    for (k = 0; k < 3; k++) {
        org[k] = (float)a[k];
        dir[k] = (float)(b[k] - a[k]);
    }
    if (s->trace) {
        radinterp_hit hit;
        float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        if (!(len > 0.0f)) return 0;
        dir[0] /= len; dir[1] /= len; dir[2] /= len;
        hit.t = len; hit.u = hit.v = 0.0f; hit.triangle = RADINTERP__NONE;
        return s->trace(s->trace_user, org, dir, len, &hit) != 0;
    }
    return radinterp__bvh_occluded(&s->bvh, org, dir, 0.0f, 1.0f);
}

/* Visible fraction of the source seen from q (on the receiver), weighted
   like the form factor: rays to stratified points of the source polygon,
   each counting with the kernel cos cos / r^2 of its end point, so that a
   blocker hiding the near (bright) part of the source weighs more than one
   hiding the far part. Both ends leave their surface by a small offset
   along its normal, so neither end hits its own surface. */
static double radinterp__visible_fraction(const radinterp_solution *s, const double *q, const double *nr,
                                          const double (*src)[3], int count, const double *ns, radinterp__rng *rng,
                                          uint32_t rays)
{
    double tri_area[RADINTERP__POLY_MAX], total = radinterp__fan_areas(src, count, tri_area), off = 10.0 * s->epsilon * s->diag;
    double a[3], b[3], open = 0.0, all = 0.0;
    uint32_t i;
    int k;
    for (k = 0; k < 3; k++) a[k] = q[k] + off * nr[k];
    for (i = 0; i < rays; i++) {
        double u1 = (i + radinterp__rng_unit(rng)) / rays, u2 = radinterp__rng_unit(rng), d[3], r2, w;
        radinterp__poly_point(src, count, tri_area, total, u1, u2, b);
        radinterp__d3_sub(b, q, d);
        r2 = radinterp__d3_dot(d, d);
        w = r2 > 0.0 ? radinterp__d3_dot(d, nr) * -radinterp__d3_dot(d, ns) / (r2 * r2) : 0.0;
        if (!(w > 0.0)) continue;
        for (k = 0; k < 3; k++) b[k] += off * ns[k];
        all += w;
        if (!radinterp__segment_blocked(s, a, b)) open += w;
    }
    return all > 0.0 ? open / all : 1.0;
}

/* Keeps the candidates that may block between the two nodes. */
static uint32_t radinterp__filter_blockers(const radinterp_solution *s, const radinterp__node *r,
                                           const radinterp__node *src, const uint32_t *in, uint32_t count,
                                           uint32_t *out)
{
    radinterp__shaft sh;
    uint32_t i, kept = 0;
    radinterp__shaft_build(&sh, r->lo, r->hi, src->lo, src->hi);
    for (i = 0; i < count; i++)
        if (radinterp__may_block(s, &sh, in[i], r, src)) out[kept++] = in[i];
    return kept;
}

/* Link form factor (4.2, method 3): the mean of the point-to-polygon factors
   (eq. 6.1) at stratified points of the receiver, times the visible fraction
   of the source at each point when blockers remain. Each polygon is first
   clipped to the other's front half-space (horizon); the receiver's clipped
   area ratio scales the result. dff is the spread of the point values. */
static void radinterp__link_compute(radinterp_solution *s, radinterp__pending *pl, const uint32_t *in, uint32_t *out)
{
    const radinterp__node *r = &s->nodes[pl->receiver], *src = &s->nodes[pl->source];
    const radinterp__patch *pr = &s->patches[r->patch], *ps = &s->patches[src->patch];
    double R[RADINTERP__POLY_MAX][3], S[RADINTERP__POLY_MAX][3], Rc[RADINTERP__POLY_MAX][3], Sc[RADINTERP__POLY_MAX][3];
    double tri_area[RADINTERP__POLY_MAX], total, ratio, sum = 0.0, lo = DBL_MAX, hi = 0.0, tiny;
    int nR = radinterp__node_poly(r, R), nS = radinterp__node_poly(src, S), nRc, nSc, clipped;
    uint32_t i, n = s->ff_samples;
    radinterp__rng rng;
    if (pl->filter) pl->kept = radinterp__filter_blockers(s, r, src, in + pl->first, pl->count, out + pl->first);
    else {
        if (pl->count) memcpy(out + pl->first, in + pl->first, pl->count * sizeof(uint32_t));
        pl->kept = pl->count;
    }
    pl->ff = pl->dff = 0.0f;
    pl->rays = 0;
    pl->dead = 1;
    nSc = radinterp__clip_poly((const double (*)[3])S, nS, pr->n, pr->d, Sc);
    nRc = radinterp__clip_poly((const double (*)[3])R, nR, ps->n, ps->d, Rc);
    tiny = 1e-12 * s->diag * s->diag;
    if (nSc < 3 || nRc < 3) return;
    if (radinterp__poly_area((const double (*)[3])Sc, nSc) <= tiny) return;
    total = radinterp__fan_areas((const double (*)[3])Rc, nRc, tri_area);
    if (total <= tiny) return;
    pl->dead = 0;
    clipped = radinterp__node_front(r, ps->n, ps->d) > 0.0 && total < 0.999999 * r->area;
    ratio = clipped ? total / r->area : 1.0;
    /* unclipped receivers use the same points for every source (seeded by
       the receiver alone), so the factors of a closed scene sum to one */
    rng = radinterp__rng_stream(s->seed, clipped ? ((uint64_t)pl->receiver << 32 | pl->source) : pl->receiver);
    for (i = 0; i < n; i++) {
        double q[3], f, w = radinterp__receiver_point((const double (*)[3])Rc, nRc, tri_area, total, i, n, &rng, q);
        f = w * radinterp__ff_poly(q, pr->n, (const double (*)[3])Sc, nSc);
        if (f < 0.0) f = 0.0;
        if (pl->kept && f > 0.0) {
            radinterp__rng vis = radinterp__rng_stream(s->seed ^ 0xA5A5A5A5u, ((uint64_t)pl->receiver << 32 | pl->source) * 64u + i);
            f *= radinterp__visible_fraction(s, q, pr->n, (const double (*)[3])Sc, nSc, ps->n, &vis, s->visibility_rays);
            pl->rays += s->visibility_rays;
        }
        sum += f;
    }
    /* The refinement estimate comes from fixed points, the receiver's
       corners pulled a fifth toward its centre, and the centre: if it came
       from the random points, the links whose points happened to miss a peak
       of the factor (near a shared edge) would be the ones kept, and the kept
       factors would be biased low. */
    {
        double c[3] = {0.0, 0.0, 0.0};
        int k, j;
        for (k = 0; k < nRc; k++)
            for (j = 0; j < 3; j++) c[j] += Rc[k][j] / nRc;
        for (k = 0; k <= nRc; k++) {
            double q[3], f;
            for (j = 0; j < 3; j++) q[j] = k < nRc ? 0.8 * Rc[k][j] + 0.2 * c[j] : c[j];
            f = radinterp__ff_poly(q, pr->n, (const double (*)[3])Sc, nSc);
            if (f < 0.0) f = 0.0;
            if (pl->kept && f > 0.0) {
                radinterp__rng vis = radinterp__rng_stream(s->seed ^ 0x5A5A5A5Au, ((uint64_t)pl->receiver << 32 | pl->source) * 64u + (uint64_t)k);
                f *= radinterp__visible_fraction(s, q, pr->n, (const double (*)[3])Sc, nSc, ps->n, &vis, s->visibility_rays);
                pl->rays += s->visibility_rays;
            }
            lo = f < lo ? f : lo;
            hi = f > hi ? f : hi;
        }
    }
    pl->ff = (float)(ratio * sum / n);
    pl->dff = (float)(ratio * (hi - lo));
}

static void radinterp__ff_job(void *ctx_, uint32_t index)
{
    radinterp__ff_ctx *ctx = (radinterp__ff_ctx *)ctx_;
    uint32_t i = ctx->begin + index * ctx->per_job, end = i + ctx->per_job;
    if (end > ctx->end) end = ctx->end;
    for (; i < end; i++) radinterp__link_compute(ctx->s, &ctx->pending[i], ctx->in_pool, ctx->out_pool);
}

typedef struct radinterp__run {
    const radinterp_desc *desc;
    uint32_t iteration;          /* for progress reports */
} radinterp__run;

static int radinterp__cancelled(const radinterp_solution *s, const radinterp__run *run)
{
    const radinterp_desc *d = run->desc;
    (void)s;
    return d->progress && d->progress(d->progress_user, run->iteration, s->max_iterations) != 0;
}

/* Computes every pending link, in batches with a progress check between. */
static radinterp_result radinterp__compute_pending(radinterp_solution *s, const radinterp__run *run,
                                                   radinterp__pending *pending, uint32_t count,
                                                   const uint32_t *in_pool, uint32_t *out_pool)
{
    const uint32_t batch = 16384, per_job = 64;
    uint32_t begin;
    for (begin = 0; begin < count; begin += batch) {
        radinterp__ff_ctx ctx;
        uint32_t i;
        ctx.s = s;
        ctx.pending = pending;
        ctx.begin = begin;
        ctx.end = begin + batch < count ? begin + batch : count;
        ctx.per_job = per_job;
        ctx.in_pool = in_pool;
        ctx.out_pool = out_pool;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__ff_job, &ctx,
                            (ctx.end - ctx.begin + per_job - 1) / per_job);
        for (i = ctx.begin; i < ctx.end; i++) s->shadow_rays += pending[i].rays;
        if (radinterp__cancelled(s, run)) return RADINTERP_ERROR_CANCELLED;
    }
    return RADINTERP_OK;
}

/* Replaces the link list by the kept links plus the live pending ones,
   sorted by receiver (stable), with their blockers copied into one pool. */
static radinterp_result radinterp__install_links(radinterp_solution *s, const radinterp__link *keep, uint32_t keep_count,
                                                 const radinterp__pending *pend, uint32_t pend_count,
                                                 const uint32_t *pend_pool)
{
    uint32_t *start = NULL, *pool = NULL, i, total = keep_count, at;
    uint64_t blockers = 0;
    radinterp__link *links = NULL;
    for (i = 0; i < keep_count; i++) blockers += keep[i].blocker_count;
    for (i = 0; i < pend_count; i++)
        if (!pend[i].dead) { total++; blockers += pend[i].kept; }
    if (blockers > 0xFFFFFFFFu) return RADINTERP_ERROR_OUT_OF_MEMORY;
    links = (radinterp__link *)radinterp__alloc_array(&s->allocator, total, sizeof *links);
    pool = (uint32_t *)radinterp__alloc_array(&s->allocator, (size_t)blockers, sizeof *pool);
    start = (uint32_t *)radinterp__alloc_array(&s->allocator, (size_t)s->node_count + 1, sizeof *start);
    if (!links || !pool || !start) {
        radinterp__free(&s->allocator, links);
        radinterp__free(&s->allocator, pool);
        radinterp__free(&s->allocator, start);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    memset(start, 0, ((size_t)s->node_count + 1) * sizeof *start);
    for (i = 0; i < keep_count; i++) start[keep[i].receiver + 1]++;
    for (i = 0; i < pend_count; i++)
        if (!pend[i].dead) start[pend[i].receiver + 1]++;
    for (i = 0; i < s->node_count; i++) {
        s->nodes[i].first_link = start[i];
        s->nodes[i].link_count = start[i + 1];
        start[i + 1] += start[i];
    }
    at = 0;
    for (i = 0; i < keep_count; i++) {
        radinterp__link *l = &links[start[keep[i].receiver]++];
        *l = keep[i];
        if (l->blocker_count) memcpy(pool + at, s->blockers + keep[i].first_blocker, l->blocker_count * sizeof *pool);
        l->first_blocker = at;
        at += l->blocker_count;
    }
    for (i = 0; i < pend_count; i++) {
        radinterp__link *l;
        if (pend[i].dead) continue;
        l = &links[start[pend[i].receiver]++];
        l->receiver = pend[i].receiver;
        l->source = pend[i].source;
        l->ff = pend[i].ff;
        l->dff = pend[i].dff;
        l->flags = 0;
        l->blocker_count = pend[i].kept;
        if (l->blocker_count) memcpy(pool + at, pend_pool + pend[i].first, l->blocker_count * sizeof *pool);
        l->first_blocker = at;
        at += l->blocker_count;
    }
    radinterp__free(&s->allocator, start);
    radinterp__free(&s->allocator, s->links);
    radinterp__free(&s->allocator, s->blockers);
    s->links = links;
    s->link_count = total;
    s->blockers = pool;
    s->blocker_count = blockers;
    return RADINTERP_OK;
}

/* Growable arrays for the serial parts of linking and refinement. */
typedef struct radinterp__grow {
    void *data;
    size_t count, cap, item;
} radinterp__grow;

static void *radinterp__grow_push(radinterp_solution *s, radinterp__grow *g)
{
    if (g->count == g->cap) {
        size_t cap = g->cap ? 2 * g->cap : 1024;
        void *p = radinterp__alloc_array(&s->allocator, cap, g->item);
        if (!p) return NULL;
        if (g->count) memcpy(p, g->data, g->count * g->item);
        radinterp__free(&s->allocator, g->data);
        g->data = p;
        g->cap = cap;
    }
    return (char *)g->data + g->item * g->count++;
}

/* Potential blockers of a pair of patches: the patches whose boxes meet the
   shaft, found through the BVH (its leaves hold the patches' triangles). */
static int radinterp__shaft_query(radinterp_solution *s, const radinterp__node *r, const radinterp__node *src,
                                  radinterp__grow *pool, uint32_t *stamp, uint32_t mark, uint32_t *count)
{
    radinterp__shaft sh;
    uint32_t stack[RADINTERP__BVH_STACK], top = 0, index = 0;
    double tol = s->epsilon * s->diag;
    radinterp__shaft_build(&sh, r->lo, r->hi, src->lo, src->hi);
    *count = 0;
    if (s->bvh.tri_count == 0) return 1;
    for (;;) {
        const radinterp__bvh_node *node = &s->bvh.nodes[index];
        if (!radinterp__shaft_culls(&sh, node->lo, node->hi, -tol)) {
            if (node->count) {
                uint32_t i;
                for (i = node->first; i < node->first + node->count; i++) {
                    uint32_t b = s->tri_patch[s->bvh.tris[i].id];
                    uint32_t *slot;
                    if (stamp[b] == mark || !radinterp__may_block(s, &sh, b, r, src)) continue;
                    stamp[b] = mark;
                    slot = (uint32_t *)radinterp__grow_push(s, pool);
                    if (!slot) return 0;
                    *slot = b;
                    (*count)++;
                }
            } else {
                stack[top++] = node->first;
                index = index + 1;
                continue;
            }
        }
        if (!top) break;
        index = stack[--top];
    }
    return 1;
}

/* Initial links (4.1): one per ordered pair of patches that face each other
   (part of each lies in front of the other's plane), with the blockers from
   shaft culling. Sources that can never shine (black, not emitting) get none. */
static radinterp_result radinterp__initial_links(radinterp_solution *s, const radinterp__run *run)
{
    radinterp__grow pend, pool;
    uint32_t *stamp, i, j, mark = 0;
    radinterp_result res = RADINTERP_OK;
    double tol = s->epsilon * s->diag;
    memset(&pend, 0, sizeof pend);
    memset(&pool, 0, sizeof pool);
    pend.item = sizeof(radinterp__pending);
    pool.item = sizeof(uint32_t);
    stamp = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof *stamp);
    if (!stamp) return RADINTERP_ERROR_OUT_OF_MEMORY;
    memset(stamp, 0xFF, (size_t)s->patch_count * sizeof *stamp);
    for (i = 0; i < s->patch_count && res == RADINTERP_OK; i++) {
        const radinterp__patch *pr = &s->patches[i];
        if (!pr->count) continue;
        for (j = 0; j < s->patch_count; j++) {
            const radinterp__patch *ps = &s->patches[j];
            radinterp__pending *pl;
            uint32_t first = (uint32_t)pool.count, count;
            if (j == i || !ps->count) continue;
            if (ps->rho[0] == 0.0f && ps->rho[1] == 0.0f && ps->rho[2] == 0.0f && ps->e[0] == 0.0f &&
                ps->e[1] == 0.0f && ps->e[2] == 0.0f)
                continue;
            if (radinterp__patch_front(pr, ps->n, ps->d) <= tol || radinterp__patch_front(ps, pr->n, pr->d) <= tol)
                continue;
            if (!radinterp__shaft_query(s, &s->nodes[pr->root], &s->nodes[ps->root], &pool, stamp, mark++, &count)) {
                res = RADINTERP_ERROR_OUT_OF_MEMORY;
                break;
            }
            pl = (radinterp__pending *)radinterp__grow_push(s, &pend);
            if (!pl) { res = RADINTERP_ERROR_OUT_OF_MEMORY; break; }
            memset(pl, 0, sizeof *pl);
            pl->receiver = pr->root;
            pl->source = ps->root;
            pl->first = first;
            pl->count = count;
        }
    }
    radinterp__free(&s->allocator, stamp);
    if (res == RADINTERP_OK && pool.count > 0xFFFFFFFFu) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    if (res == RADINTERP_OK) {
        uint32_t *out = (uint32_t *)radinterp__alloc_array(&s->allocator, pool.count, sizeof(uint32_t));
        if (!out) res = RADINTERP_ERROR_OUT_OF_MEMORY;
        if (res == RADINTERP_OK)
            res = radinterp__compute_pending(s, run, (radinterp__pending *)pend.data, (uint32_t)pend.count,
                                             (const uint32_t *)pool.data, out);
        if (res == RADINTERP_OK)
            res = radinterp__install_links(s, NULL, 0, (const radinterp__pending *)pend.data, (uint32_t)pend.count, out);
        radinterp__free(&s->allocator, out);
    }
    radinterp__free(&s->allocator, pend.data);
    radinterp__free(&s->allocator, pool.data);
    return res;
}

static int radinterp__can_split(const radinterp_solution *s, const radinterp__node *nd)
{
    return 0.25 * nd->area >= s->min_area;
}

/* Largest difference between the radiosities of a node's children (0 for
   a leaf): how far the node's mean may be from the part a receiver sees. */
static double radinterp__source_spread(const radinterp_solution *s, uint32_t node)
{
    const radinterp__node *nd = &s->nodes[node];
    double spread = 0.0;
    int k, c;
    if (nd->child == RADINTERP__NONE) return 0.0;
    for (k = 0; k < 3; k++) {
        double lo = DBL_MAX, hi = -DBL_MAX;
        for (c = 0; c < 4; c++) {
            double b = s->nodes[nd->child + c].b[k];
            lo = b < lo ? b : lo;
            hi = b > hi ? b : hi;
        }
        spread = hi - lo > spread ? hi - lo : spread;
    }
    return spread;
}

/* Transport-based refinement (4.4.1): a link whose estimated transport
   error B_src * (max - min point factor) exceeds eps is replaced by four
   links to the children of its larger element (the other one when the
   larger may not be split; a link that can go no further is final). A link
   whose source has children that differ by more than eps / F is replaced by
   links from those children.
   Returns the number of links split, or -1 when out of memory (*res). */
static int radinterp__refine(radinterp_solution *s, const radinterp__run *run, radinterp_result *res)
{
    radinterp__grow keep, pend;
    uint32_t i, k, split = 0, *out = NULL, nodes_before = s->node_count;
    uint64_t cand = 0;
    memset(&keep, 0, sizeof keep);
    memset(&pend, 0, sizeof pend);
    keep.item = sizeof(radinterp__link);
    pend.item = sizeof(radinterp__pending);
    *res = RADINTERP_OK;
    for (i = 0; i < s->link_count; i++) {
        radinterp__link l = s->links[i];
        const float *b = s->nodes[l.source].b;
        double bmax = b[0] > b[1] ? (b[0] > b[2] ? b[0] : b[2]) : (b[1] > b[2] ? b[1] : b[2]);
        int which = -1;
        if (!(l.flags & RADINTERP__LINK_FINAL) && bmax * l.dff > s->eps) {
            const radinterp__node *r = &s->nodes[l.receiver], *src = &s->nodes[l.source];
            int rs = radinterp__can_split(s, r), ss = radinterp__can_split(s, src);
            if (rs && (r->area >= src->area || !ss)) which = 0;
            else if (ss) which = 1;
            else l.flags |= RADINTERP__LINK_FINAL;
        } else if (!(l.flags & RADINTERP__LINK_FINAL) && radinterp__source_spread(s, l.source) * l.ff > s->eps) {
            /* the source is not uniform (its children differ): the link
               carries its mean where the receiver may see a brighter or
               darker part, so it goes to the children */
            which = 1;
        }
        if (which < 0) {
            radinterp__link *slot = (radinterp__link *)radinterp__grow_push(s, &keep);
            if (!slot) { *res = RADINTERP_ERROR_OUT_OF_MEMORY; break; }
            *slot = l;
            continue;
        }
        if (radinterp__node_split(s, which == 0 ? l.receiver : l.source) != 0) {
            *res = RADINTERP_ERROR_OUT_OF_MEMORY;
            break;
        }
        split++;
        for (k = 0; k < 4; k++) {
            radinterp__pending *pl = (radinterp__pending *)radinterp__grow_push(s, &pend);
            if (!pl) { *res = RADINTERP_ERROR_OUT_OF_MEMORY; break; }
            memset(pl, 0, sizeof *pl);
            pl->receiver = which == 0 ? s->nodes[l.receiver].child + k : l.receiver;
            pl->source = which == 1 ? s->nodes[l.source].child + k : l.source;
            pl->first = l.first_blocker;
            pl->count = l.blocker_count;
            pl->filter = 1;
            cand += l.blocker_count;
        }
        if (*res != RADINTERP_OK) break;
    }
    if (*res == RADINTERP_OK && s->node_count > nodes_before) {
        radinterp__open_ctx oc;
        oc.s = s;
        oc.first = nodes_before;
        oc.count = s->node_count - nodes_before;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__open_job, &oc, (oc.count + 63) / 64);
    }
    if (*res == RADINTERP_OK && split) {
        /* the four children of a link share its candidates: give each its own copy */
        radinterp__pending *p = (radinterp__pending *)pend.data;
        size_t n = cand ? (size_t)cand : 1;
        uint32_t *wide = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t)), at = 0;
        out = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
        if (!wide || !out || cand > 0xFFFFFFFFu) *res = RADINTERP_ERROR_OUT_OF_MEMORY;
        for (i = 0; i < pend.count && *res == RADINTERP_OK; i++) {
            if (p[i].count) memcpy(wide + at, s->blockers + p[i].first, p[i].count * sizeof(uint32_t));
            p[i].first = at;
            at += p[i].count;
        }
        if (*res == RADINTERP_OK) *res = radinterp__compute_pending(s, run, p, (uint32_t)pend.count, wide, out);
        radinterp__free(&s->allocator, wide);
        if (*res == RADINTERP_OK)
            *res = radinterp__install_links(s, (const radinterp__link *)keep.data, (uint32_t)keep.count, p,
                                            (uint32_t)pend.count, out);
    } else if (*res == RADINTERP_OK && keep.count) {
        memcpy(s->links, keep.data, keep.count * sizeof(radinterp__link)); /* keeps the final flags */
    }
    radinterp__free(&s->allocator, out);
    radinterp__free(&s->allocator, keep.data);
    radinterp__free(&s->allocator, pend.data);
    return *res == RADINTERP_OK ? (int)split : -1;
}

/* ---- gather and push-pull (4.3) ---------------------------------------- */
typedef struct radinterp__iter_ctx {
    radinterp_solution *s;
    uint32_t per_job;
    double floor;            /* radiosities below it count as this for relative change */
    double *patch_change;    /* largest relative change per patch */
} radinterp__iter_ctx;

/* H = sum over the node's links of F * B_src, from last iteration's B. */
static void radinterp__gather_job(void *ctx_, uint32_t index)
{
    radinterp__iter_ctx *ctx = (radinterp__iter_ctx *)ctx_;
    radinterp_solution *s = ctx->s;
    uint32_t i = index * ctx->per_job, end = i + ctx->per_job;
    if (end > s->node_count) end = s->node_count;
    for (; i < end; i++) {
        radinterp__node *nd = &s->nodes[i];
        double h[3] = {0.0, 0.0, 0.0};
        uint32_t l;
        for (l = nd->first_link; l < nd->first_link + nd->link_count; l++) {
            const radinterp__link *lk = &s->links[l];
            const float *b = s->nodes[lk->source].b;
            h[0] += (double)lk->ff * b[0];
            h[1] += (double)lk->ff * b[1];
            h[2] += (double)lk->ff * b[2];
        }
        nd->h[0] = (float)h[0];
        nd->h[1] = (float)h[1];
        nd->h[2] = (float)h[2];
    }
}

/* Push the irradiance gathered above down to the leaves, B = E + rho H there
   (eq. 2.1), and pull averages back up. Irradiance and radiosity are those
   of the open part of each node: a node's gathered irradiance is a mean over
   the whole node, in which enclosed points count zero, so it is divided by
   the open fraction, and averages weigh children by their open areas. */
static void radinterp__push_pull(radinterp_solution *s, uint32_t index, const double *down, double floor,
                                 double *change, double *b_out)
{
    radinterp__node *nd = &s->nodes[index];
    const radinterp__patch *pt = &s->patches[nd->patch];
    double h[3], b[3], open = nd->open;
    int k;
    for (k = 0; k < 3; k++) h[k] = down[k] + (open > 0.0 ? nd->h[k] / open : 0.0);
    if (nd->child == RADINTERP__NONE) {
        for (k = 0; k < 3; k++) {
            double rel;
            b[k] = pt->e[k] + pt->rho[k] * h[k];
            rel = open > 0.0 ? fabs(b[k] - nd->b[k]) / (b[k] > floor ? b[k] : floor) : 0.0;
            if (rel > *change) *change = rel;
        }
    } else {
        double area = 0.0, cb[3];
        uint32_t c;
        b[0] = b[1] = b[2] = 0.0;
        for (c = 0; c < 4; c++) {
            uint32_t ch = s->nodes[index].child + c;
            double a = (double)s->nodes[ch].area * s->nodes[ch].open;
            radinterp__push_pull(s, ch, h, floor, change, cb);
            for (k = 0; k < 3; k++) b[k] += a * cb[k];
            area += a;
        }
        nd = &s->nodes[index];
        for (k = 0; k < 3; k++) b[k] = area > 0.0 ? b[k] / area : pt->e[k];
    }
    for (k = 0; k < 3; k++) { nd->b[k] = (float)b[k]; b_out[k] = b[k]; }
}

static void radinterp__push_pull_job(void *ctx_, uint32_t index)
{
    radinterp__iter_ctx *ctx = (radinterp__iter_ctx *)ctx_;
    radinterp_solution *s = ctx->s;
    double zero[3] = {0.0, 0.0, 0.0}, b[3], change = 0.0;
    if (s->patches[index].count) radinterp__push_pull(s, s->patches[index].root, zero, ctx->floor, &change, b);
    ctx->patch_change[index] = change;
}

/* Gather + push-pull until no leaf changes by more than rel_error_cutoff,
   refining after each pass while any link is above eps (4.3 steps 2-4). */
static radinterp_result radinterp__iterate(radinterp_solution *s, radinterp__run *run)
{
    radinterp__iter_ctx ctx;
    double emax = 0.0;
    uint32_t i, it;
    int refining = 1;
    radinterp_result res = RADINTERP_OK;
    for (i = 0; i < s->patch_count; i++) {
        int k;
        for (k = 0; k < 3; k++) emax = s->patches[i].e[k] > emax ? s->patches[i].e[k] : emax;
    }
    ctx.s = s;
    ctx.per_job = 4096;
    ctx.floor = emax > 0.0 ? 1e-4 * emax : 1e-30;
    ctx.patch_change = (double *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(double));
    if (!ctx.patch_change) return RADINTERP_ERROR_OUT_OF_MEMORY;
    for (it = 0; it < s->max_iterations; it++) {
        double change = 0.0;
        run->iteration = it;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__gather_job, &ctx,
                            (s->node_count + ctx.per_job - 1) / ctx.per_job);
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__push_pull_job, &ctx,
                            s->patch_count);
        for (i = 0; i < s->patch_count; i++) change = ctx.patch_change[i] > change ? ctx.patch_change[i] : change;
        s->iterations = it + 1;
        s->max_relative_change = (float)change;
        run->iteration = it + 1;
        if (radinterp__cancelled(s, run)) { res = RADINTERP_ERROR_CANCELLED; break; }
        if (refining) {
            int split = radinterp__refine(s, run, &res);
            if (split < 0) break;
            if (split == 0) refining = 0;
        }
        if (!refining && change < s->rel_error_cutoff) { s->converged = 1; break; }
    }
    radinterp__free(&s->allocator, ctx.patch_change);
    return res;
}

/* ======================================================================
   13. irradiance at a point (Hardt chapter 6)
   For every link delivering to the leaf that contains p or to one of its
   ancestors: move the source push_off behind its plane (6.4), clip it to the
   half-space in front of p (horizon, 6.2.1), and take eq. 6.1 directly when
   the link has no blockers (6.2.2). Otherwise backproject (6.2.3): the part
   of each blocker inside the pyramid from p to the source is projected from
   p onto the source plane. A point of the source is hidden exactly when it
   lies in one of these shadows, so the visible factor is F(source) minus
   F(union of the shadows). Two ways to get it:
   - shadows (the default): the union is built as disjoint convex pieces
     (each new shadow minus the pieces so far, by half-plane splits), and
     eq. 6.1 being additive over a partition, F(union) = sum of F(piece).
     No predicate decides anything here: every step moves corners by
     rounding only, so the result is continuous in the geometry.
   - triangulation (Hardt's): the source is triangulated (CDT) with the
     projected edges as constraints, so each face of the arrangement is
     wholly visible or wholly hidden; one ray per face (through one
     triangle's centre) classifies it against the blockers, and eq. 6.1
     summed over the visible triangles gives the factor.
   Both agree to rounding when the rays classify every face correctly.
   Visibility is judged from p moved `nudge` toward `toward` (6.3).
   ---------------------------------------------------------------------- */
#define RADINTERP__BP_BYTES 32768        /* stack memory of one query's triangulation */
#define RADINTERP__BP_MAX_SURVIVORS 64   /* shadows remembered per source */
/* A convex polygon of the source plane, in the frame: its corners and, for
   each edge (from corner i to i + 1), the line it lies on, a u + b v + c = 0
   with (a, b) of unit length and the polygon on the positive side. The
   lines come from the planes that made the edges (never from two computed
   corners, whose direction is noise when they are close), so splitting a
   piece by another piece's edges is as accurate as the corners are. */
#define RADINTERP__PIECE_VERTS 12   /* a quadrilateral clipped by the pyramid of a pentagon has at most 10 */
#define RADINTERP__PIECES 48        /* pieces of one source's shadow union */

typedef struct radinterp__piece {
    int count;
    double lo[2], hi[2];                     /* bounding box */
    double v[RADINTERP__PIECE_VERTS][2];
    double ln[RADINTERP__PIECE_VERTS][3];
} radinterp__piece;

typedef struct radinterp__query {
    const radinterp_solution *s;
    double p[3];          /* the point: form factors are taken here */
    double pv[3];         /* p nudged toward `toward`: visibility is judged from here */
    double n[3], dr;      /* receiver normal and n . p */
    radinterp__cdt cdt;
    int cdt_ready;        /* cdt initialised (on mem) */
    int depth_left;       /* how much deeper into a source's children a query may go */
    uint32_t triangulated; /* sources partly hidden: shadow union or triangulation (statistics) */
    int failed;           /* out of memory in a triangulation */
    double mem[RADINTERP__BP_BYTES / sizeof(double)];
    double shadow[RADINTERP__BP_MAX_SURVIVORS][RADINTERP__POLY_MAX][2];   /* projected blockers, 2D */
    int shadow_count[RADINTERP__BP_MAX_SURVIVORS];
    unsigned char flags[2048];
    radinterp__piece piece[RADINTERP__PIECES];
} radinterp__query;

/* 2D frame on the source plane: origin o, axes e1, e2 with e1 x e2 = n. */
typedef struct radinterp__frame { double o[3], e1[3], e2[3]; } radinterp__frame;

static void radinterp__frame_make(radinterp__frame *f, const double (*poly)[3], const double *n)
{
    double d[3], len, k;
    memcpy(f->o, poly[0], sizeof f->o);
    radinterp__d3_sub(poly[1], poly[0], d);
    k = radinterp__d3_dot(d, n);
    d[0] -= k * n[0]; d[1] -= k * n[1]; d[2] -= k * n[2];
    len = radinterp__d3_len(d);
    f->e1[0] = d[0] / len; f->e1[1] = d[1] / len; f->e1[2] = d[2] / len;
    radinterp__d3_cross(n, f->e1, f->e2);
}

static void radinterp__frame_to2d(const radinterp__frame *f, const double *x, double *uv)
{
    double d[3];
    radinterp__d3_sub(x, f->o, d);
    uv[0] = radinterp__d3_dot(d, f->e1);
    uv[1] = radinterp__d3_dot(d, f->e2);
}

static void radinterp__frame_to3d(const radinterp__frame *f, const double *uv, double *x)
{
    int k;
    for (k = 0; k < 3; k++) x[k] = f->o[k] + uv[0] * f->e1[k] + uv[1] * f->e2[k];
}

/* Does the segment from a to b cross the interior of the patch? */
static int radinterp__ray_hits_patch(const radinterp__patch *pt, const double *a, const double *b)
{
    double da = radinterp__d3_dot(pt->n, a) - pt->d, db = radinterp__d3_dot(pt->n, b) - pt->d, t, x[3];
    uint32_t i;
    int k;
    if ((da > 0.0) == (db > 0.0) || da == db) return 0;
    t = da / (da - db);
    if (!(t > 1e-9 && t < 1.0 - 1e-9)) return 0;
    for (k = 0; k < 3; k++) x[k] = a[k] + t * (b[k] - a[k]);
    for (i = 0; i < pt->count; i++) {
        double e[3], q[3], c[3], v0[3], v1[3];
        radinterp__d3_from_f(pt->v[i], v0);
        radinterp__d3_from_f(pt->v[(i + 1) % pt->count], v1);
        radinterp__d3_sub(v1, v0, e);
        radinterp__d3_sub(x, v0, q);
        radinterp__d3_cross(e, q, c);
        if (radinterp__d3_dot(c, pt->n) < 0.0) return 0;
    }
    return 1;
}

/* Does the convex polygon a (either winding) contain every corner of b? */
static int radinterp__covers(const double (*a)[2], int na, const double (*b)[2], int nb)
{
    double area = 0.0, lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
    int i, j;
    for (i = 0; i < na; i++) {
        lo[0] = a[i][0] < lo[0] ? a[i][0] : lo[0];
        lo[1] = a[i][1] < lo[1] ? a[i][1] : lo[1];
        hi[0] = a[i][0] > hi[0] ? a[i][0] : hi[0];
        hi[1] = a[i][1] > hi[1] ? a[i][1] : hi[1];
    }
    for (j = 0; j < nb; j++) /* bounding boxes first: most pairs fail here */
        if (b[j][0] < lo[0] || b[j][0] > hi[0] || b[j][1] < lo[1] || b[j][1] > hi[1]) return 0;
    for (i = 0; i < na; i++) area += a[i][0] * a[(i + 1) % na][1] - a[(i + 1) % na][0] * a[i][1];
    if (area == 0.0) return 0;
    for (j = 0; j < nb; j++)
        for (i = 0; i < na; i++) {
            double o = radinterp__orient2d(a[i], a[(i + 1) % na], b[j]);
            if (area > 0.0 ? o < 0.0 : o > 0.0) return 0;
        }
    return 1;
}

/* Twice the signed area of a triangle (plain floating point: a size, not a predicate). */
static double radinterp__orient2d_area(const double *a, const double *b, const double *c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
}

/* Twice the signed area of a 2D polygon (positive counter-clockwise). */
static double radinterp__area2(const double (*v)[2], int n)
{
    double a = 0.0;
    int i;
    for (i = 0; i < n; i++) a += v[i][0] * v[(i + 1) % n][1] - v[(i + 1) % n][0] * v[i][1];
    return a;
}

/* One source seen from the query point: what both visibility methods share.
   The source Sr is the real one (visibility is that of the real source, so
   moving it opens no gap at a contact); form factors are taken on the
   moved one, through fr_ff. */
typedef struct radinterp__bp {
    const radinterp__link *lk;
    const double *pv;                     /* visibility is judged from here */
    const double (*Sc_pushed)[3];         /* the moved, clipped source */
    double Sr[RADINTERP__POLY_MAX][3];    /* the real source */
    double sc2[RADINTERP__POLY_MAX][2];   /* its corners in the frame */
    int nc;
    radinterp__frame fr, fr_ff;           /* frame on the real plane, and the same on the moved plane */
    double plane_n[RADINTERP__POLY_MAX + 1][3], plane_d[RADINTERP__POLY_MAX + 1];
    int np;                               /* the pyramid from pv over Sr: x inside when n . x >= d */
    double ns[3], ds, hp;                 /* source normal, real plane, height of pv above it */
    double tol;                           /* 2D distances below it are rounding: 1e-12 of the source's size */
} radinterp__bp;

/* The pyramid from pv over the real source: one plane per edge, and the
   source plane. */
static void radinterp__bp_pyramid(radinterp__bp *bp)
{
    const double *pv = bp->pv;
    double centre[3] = {0.0, 0.0, 0.0};
    int k, nc = bp->nc;
    for (k = 0; k < nc; k++) { centre[0] += bp->Sr[k][0] / nc; centre[1] += bp->Sr[k][1] / nc; centre[2] += bp->Sr[k][2] / nc; }
    bp->np = 0;
    for (k = 0; k < nc; k++) {
        double a[3], b[3], m[3], c[3], len;
        radinterp__d3_sub(bp->Sr[k], pv, a);
        radinterp__d3_sub(bp->Sr[(k + 1) % nc], pv, b);
        radinterp__d3_cross(a, b, m);
        len = radinterp__d3_len(m);
        if (!(len > 0.0)) continue;
        radinterp__d3_sub(centre, pv, c);
        if (radinterp__d3_dot(m, c) < 0.0) len = -len;
        bp->plane_n[bp->np][0] = m[0] / len; bp->plane_n[bp->np][1] = m[1] / len; bp->plane_n[bp->np][2] = m[2] / len;
        bp->plane_d[bp->np] = radinterp__d3_dot(bp->plane_n[bp->np], pv);
        bp->np++;
    }
    memcpy(bp->plane_n[bp->np], bp->ns, 3 * sizeof(double));
    bp->plane_d[bp->np] = bp->ds;
    bp->np++;
}

/* Sets up the source polygon Sc (front normal ns, plane ns . x = ds_pushed,
   already moved push behind the real source) for backprojection. */
static void radinterp__bp_setup(const radinterp__query *q, radinterp__bp *bp, const radinterp__link *lk,
                                const double (*Sc)[3], int nc, const double *ns, double ds_pushed, double push)
{
    double ds = ds_pushed + push;
    int k;
    bp->lk = lk;
    bp->nc = nc;
    bp->pv = q->pv;
    bp->Sc_pushed = Sc;
    if (radinterp__d3_dot(ns, q->p) - ds <= 0.0) { push = 0.0; ds = ds_pushed; } /* p within push of the plane */
    if (radinterp__d3_dot(ns, bp->pv) - ds <= 0.0) bp->pv = q->p; /* nudged behind the source: judge from p */
    for (k = 0; k < nc; k++) {
        bp->Sr[k][0] = Sc[k][0] + push * ns[0];
        bp->Sr[k][1] = Sc[k][1] + push * ns[1];
        bp->Sr[k][2] = Sc[k][2] + push * ns[2];
    }
    memcpy(bp->ns, ns, sizeof bp->ns);
    bp->ds = ds;
    bp->hp = radinterp__d3_dot(ns, bp->pv) - ds;
    radinterp__bp_pyramid(bp);
    radinterp__frame_make(&bp->fr, (const double (*)[3])bp->Sr, ns);
    bp->fr_ff = bp->fr;
    for (k = 0; k < 3; k++) bp->fr_ff.o[k] -= push * ns[k];
    for (k = 0; k < nc; k++) radinterp__frame_to2d(&bp->fr, bp->Sr[k], bp->sc2[k]);
    {
        double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX};
        for (k = 0; k < nc; k++) {
            lo[0] = bp->sc2[k][0] < lo[0] ? bp->sc2[k][0] : lo[0];
            lo[1] = bp->sc2[k][1] < lo[1] ? bp->sc2[k][1] : lo[1];
            hi[0] = bp->sc2[k][0] > hi[0] ? bp->sc2[k][0] : hi[0];
            hi[1] = bp->sc2[k][1] > hi[1] ? bp->sc2[k][1] : hi[1];
        }
        bp->tol = 1e-12 * (hi[0] - lo[0] + hi[1] - lo[1]);
    }
}

/* The blocker's part inside the pyramid (poly, m corners) projected from
   pv onto the source plane, in the frame. */
static void radinterp__bp_project(const radinterp__bp *bp, const double (*poly)[3], int m, double (*shadow)[2])
{
    int j, c;
    for (j = 0; j < m; j++) {
        double h = bp->hp - (radinterp__d3_dot(bp->ns, poly[j]) - bp->ds), tt, y[3];
        if (h < 1e-12 * bp->hp) h = 1e-12 * bp->hp;
        tt = bp->hp / h;
        for (c = 0; c < 3; c++) y[c] = bp->pv[c] + tt * (poly[j][c] - bp->pv[c]);
        radinterp__frame_to2d(&bp->fr, y, shadow[j]);
    }
}

/* The shadow of patch pb on the source: its part inside the pyramid,
   projected from pv. Returns the corner count, 0 when it casts none. Each
   corner is tested against each plane once: a plane that has every corner
   outside culls the blocker, one that has every corner inside needs no
   clipping (the common cases), the others clip. */
static int radinterp__bp_shadow(const radinterp_solution *s, const radinterp__bp *bp, const radinterp__patch *pb,
                                double (*shadow)[2])
{
    double poly[RADINTERP__POLY_MAX][3], tmp[RADINTERP__POLY_MAX][3];
    uint32_t cut = 0;
    int m, j, i;
    for (j = 0; j < bp->np; j++) /* bounding sphere first */
        if (radinterp__d3_dot(bp->plane_n[j], pb->centre) - bp->plane_d[j] < -pb->radius) return 0;
    if (fabs(radinterp__d3_dot(pb->n, bp->pv) - pb->d) <= s->epsilon * s->diag) return 0; /* seen edge-on */
    m = radinterp__patch_poly(pb, poly);
    for (j = 0; j < bp->np; j++) {
        int inside = 0;
        for (i = 0; i < m; i++) inside += radinterp__d3_dot(bp->plane_n[j], poly[i]) >= bp->plane_d[j];
        if (inside == 0) return 0;
        if (inside < m) cut |= 1u << j;
    }
    for (j = 0; j < bp->np && m >= 3; j++) {
        if (!((cut >> j) & 1u)) continue;
        m = radinterp__clip_poly((const double (*)[3])poly, m, bp->plane_n[j], bp->plane_d[j], tmp);
        radinterp__copy_poly((const double (*)[3])tmp, m, poly);
    }
    if (m < 3 || radinterp__poly_area((const double (*)[3])poly, m) <= 1e-14 * s->diag * s->diag) return 0;
    radinterp__bp_project(bp, (const double (*)[3])poly, m, shadow);
    return m;
}

/* The shadows of the link's blockers into q->shadow (at most
   RADINTERP__BP_MAX_SURVIVORS; *overflow is set when more cast one), their
   blockers into survivors. Returns the count, or -1 when one shadow alone
   covers the whole source. */
static int radinterp__bp_collect(radinterp__query *q, const radinterp__bp *bp, uint32_t *survivors, int *overflow)
{
    const radinterp_solution *s = q->s;
    const radinterp__link *lk = bp->lk;
    uint32_t i;
    int count = 0;
    *overflow = 0;
    for (i = 0; i < lk->blocker_count; i++) {
        uint32_t b = s->blockers[lk->first_blocker + i];
        const radinterp__patch *pb = &s->patches[b];
        int m;
        if (count == RADINTERP__BP_MAX_SURVIVORS) {
            double spare[RADINTERP__POLY_MAX][2];
            if (radinterp__bp_shadow(s, bp, pb, spare)) { *overflow = 1; break; }
            continue;
        }
        m = radinterp__bp_shadow(s, bp, pb, q->shadow[count]);
        if (!m) continue;
        if (radinterp__covers((const double (*)[2])q->shadow[count], m, (const double (*)[2])bp->sc2, bp->nc))
            return -1; /* this blocker alone hides the whole source */
        q->shadow_count[count] = m;
        survivors[count++] = b;
    }
    return count;
}

/* ---- visibility by the union of the shadows (the default) -------------- */
#define RADINTERP__TAG_EDGE 32   /* edge tags: pyramid plane j < 32, blocker edge k = 32 + k */

/* Sutherland-Hodgman as radinterp__clip_poly, keeping for each corner the
   tag of the edge that leaves it; edges along the clipping plane get `tag`.
   Returns the corner count, -1 when it would exceed RADINTERP__POLY_MAX. */
static int radinterp__clip_tagged(const double (*in)[3], const int *tin, int count, const double *n, double d,
                                  int tag, double (*out)[3], int *tout)
{
    int i, m = 0, k;
    for (i = 0; i < count; i++) {
        const double *a = in[i], *b = in[(i + 1) % count];
        double da = radinterp__d3_dot(n, a) - d, db = radinterp__d3_dot(n, b) - d;
        if (m + 2 > RADINTERP__POLY_MAX) return -1;
        if (da >= 0.0) {
            memcpy(out[m], a, sizeof(double[3]));
            tout[m++] = (db >= 0.0 || da > 0.0) ? tin[i] : tag;
        }
        if ((da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0)) {
            double s = da / (da - db);
            for (k = 0; k < 3; k++) out[m][k] = a[k] + s * (b[k] - a[k]);
            tout[m++] = da > 0.0 ? tag : tin[i];
        }
    }
    return m;
}

/* The trace of the plane m . X = k on the source plane, as a line of the
   frame with (a, b) of unit length, oriented so that the 2D point `inside`
   is on its positive side. Returns 0 when the plane is (nearly) parallel to
   the source plane. */
static int radinterp__trace_line(const radinterp__bp *bp, const double *m, double k, const double *inside, double *ln)
{
    double a = radinterp__d3_dot(m, bp->fr.e1), b = radinterp__d3_dot(m, bp->fr.e2);
    double len = sqrt(a * a + b * b);
    if (!(len > 1e-9 * radinterp__d3_len(m))) return 0;
    ln[0] = a / len;
    ln[1] = b / len;
    ln[2] = (radinterp__d3_dot(m, bp->fr.o) - k) / len;
    if (ln[0] * inside[0] + ln[1] * inside[1] + ln[2] < 0.0) { ln[0] = -ln[0]; ln[1] = -ln[1]; ln[2] = -ln[2]; }
    return 1;
}

/* The line an edge of a shadow lies on, from its tag: the projection of a
   blocker edge is the trace of the plane through pv and that edge; of a cut
   by a side of the pyramid, the trace of that side (a source edge); of the
   cut by the source plane, the trace of the blocker's own plane. Returns 0
   when ill-conditioned (a blocker edge pointing at pv). */
static int radinterp__shadow_line(const radinterp__bp *bp, const radinterp__patch *pb, int tag, const double *inside,
                                  double *ln)
{
    double m[3];
    if (tag >= RADINTERP__TAG_EDGE) {
        double a[3], b[3], ra[3], rb[3];
        int k = tag - RADINTERP__TAG_EDGE;
        radinterp__d3_from_f(pb->v[k], a);
        radinterp__d3_from_f(pb->v[(k + 1) % pb->count], b);
        radinterp__d3_sub(a, bp->pv, ra);
        radinterp__d3_sub(b, bp->pv, rb);
        radinterp__d3_cross(ra, rb, m);
        if (!(radinterp__d3_len(m) > 1e-9 * radinterp__d3_len(ra) * radinterp__d3_len(rb))) return 0;
        return radinterp__trace_line(bp, m, radinterp__d3_dot(m, bp->pv), inside, ln);
    }
    if (tag == bp->np - 1) return radinterp__trace_line(bp, pb->n, pb->d, inside, ln);
    return radinterp__trace_line(bp, bp->plane_n[tag], bp->plane_d[tag], inside, ln);
}

static void radinterp__piece_bounds(radinterp__piece *pc)
{
    int i;
    pc->lo[0] = pc->lo[1] = DBL_MAX;
    pc->hi[0] = pc->hi[1] = -DBL_MAX;
    for (i = 0; i < pc->count; i++) {
        pc->lo[0] = pc->v[i][0] < pc->lo[0] ? pc->v[i][0] : pc->lo[0];
        pc->lo[1] = pc->v[i][1] < pc->lo[1] ? pc->v[i][1] : pc->lo[1];
        pc->hi[0] = pc->v[i][0] > pc->hi[0] ? pc->v[i][0] : pc->hi[0];
        pc->hi[1] = pc->v[i][1] > pc->hi[1] ? pc->v[i][1] : pc->hi[1];
    }
}

/* The shadow of patch pb as a piece: its part inside the pyramid (clipped
   only by the planes that cut it), projected from pv, with its edges'
   lines. Returns 1; 0 when it casts none; -1 when it cannot be represented
   (the caller then triangulates). */
static int radinterp__bp_shadow_piece(const radinterp_solution *s, const radinterp__bp *bp, const radinterp__patch *pb,
                                      radinterp__piece *out)
{
    double poly[RADINTERP__POLY_MAX][3], tmp[RADINTERP__POLY_MAX][3], inside[2] = {0.0, 0.0};
    int tag[RADINTERP__POLY_MAX], ttmp[RADINTERP__POLY_MAX], m, j, i;
    uint32_t cut = 0;
    for (j = 0; j < bp->np; j++) /* bounding sphere first */
        if (radinterp__d3_dot(bp->plane_n[j], pb->centre) - bp->plane_d[j] < -pb->radius) return 0;
    if (fabs(radinterp__d3_dot(pb->n, bp->pv) - pb->d) <= s->epsilon * s->diag) return 0; /* seen edge-on */
    m = radinterp__patch_poly(pb, poly);
    for (j = 0; j < bp->np; j++) {
        int in = 0;
        for (i = 0; i < m; i++) in += radinterp__d3_dot(bp->plane_n[j], poly[i]) >= bp->plane_d[j];
        if (in == 0) return 0;
        if (in < m) cut |= 1u << j;
    }
    for (i = 0; i < m; i++) tag[i] = RADINTERP__TAG_EDGE + i;
    for (j = 0; j < bp->np && m >= 3; j++) {
        if (!((cut >> j) & 1u)) continue;
        m = radinterp__clip_tagged((const double (*)[3])poly, tag, m, bp->plane_n[j], bp->plane_d[j], j, tmp, ttmp);
        if (m < 0) return -1;
        memcpy(poly, tmp, (size_t)m * sizeof(double[3]));
        memcpy(tag, ttmp, (size_t)m * sizeof(int));
    }
    if (m < 3 || radinterp__poly_area((const double (*)[3])poly, m) <= 1e-14 * s->diag * s->diag) return 0;
    if (m > RADINTERP__PIECE_VERTS) return -1;
    radinterp__bp_project(bp, (const double (*)[3])poly, m, out->v);
    for (i = 0; i < m; i++) { inside[0] += out->v[i][0] / m; inside[1] += out->v[i][1] / m; }
    for (i = 0; i < m; i++)
        if (!radinterp__shadow_line(bp, pb, tag[i], inside, out->ln[i])) return -1;
    /* corners and lines must describe the same polygon: in a sliver between
       two nearly equal lines (a blocker hinged on the source's edge) the
       centre may not tell their sides apart */
    for (i = 0; i < m; i++)
        for (j = 0; j < m; j++)
            if (out->ln[i][0] * out->v[j][0] + out->ln[i][1] * out->v[j][1] + out->ln[i][2] < -bp->tol) return -1;
    out->count = m;
    radinterp__piece_bounds(out);
    return 1;
}

/* Appends corner x, whose leaving edge lies on line ln, to piece p. */
static void radinterp__piece_add(radinterp__piece *p, const double *x, const double *ln, double sign)
{
    p->v[p->count][0] = x[0];
    p->v[p->count][1] = x[1];
    p->ln[p->count][0] = sign * ln[0];
    p->ln[p->count][1] = sign * ln[1];
    p->ln[p->count][2] = sign * ln[2];
    p->count++;
}

/* Splits piece f by line L: its part on L's positive side into pos, the
   rest into neg (whose new edge lies on -L). Corners within tol of L count
   as on it, so no sliver is made. Returns 1 when f lies wholly on the
   positive side, 2 wholly on the negative side (nothing written), 0 when
   split, -1 when a part would have too many corners. */
static int radinterp__split_piece(const radinterp__piece *f, const double *L, double tol, radinterp__piece *pos,
                                  radinterp__piece *neg)
{
    double d[RADINTERP__PIECE_VERTS];
    int i, npos = 0, nneg = 0, n = f->count;
    for (i = 0; i < n; i++) {
        d[i] = L[0] * f->v[i][0] + L[1] * f->v[i][1] + L[2];
        if (fabs(d[i]) <= tol) d[i] = 0.0;
        npos += d[i] > 0.0;
        nneg += d[i] < 0.0;
    }
    if (nneg == 0) return 1;
    if (npos == 0) return 2;
    pos->count = neg->count = 0;
    for (i = 0; i < n; i++) {
        int j = (i + 1) % n;
        if (pos->count + 2 > RADINTERP__PIECE_VERTS || neg->count + 2 > RADINTERP__PIECE_VERTS) return -1;
        if (d[i] >= 0.0) radinterp__piece_add(pos, f->v[i], (d[j] >= 0.0 || d[i] > 0.0) ? f->ln[i] : L, 1.0);
        if (d[i] <= 0.0) {
            if (d[j] <= 0.0 || d[i] < 0.0) radinterp__piece_add(neg, f->v[i], f->ln[i], 1.0);
            else radinterp__piece_add(neg, f->v[i], L, -1.0);
        }
        if ((d[i] > 0.0 && d[j] < 0.0) || (d[i] < 0.0 && d[j] > 0.0)) {
            double t = d[i] / (d[i] - d[j]), x[2];
            x[0] = f->v[i][0] + t * (f->v[j][0] - f->v[i][0]);
            x[1] = f->v[i][1] + t * (f->v[j][1] - f->v[i][1]);
            if (d[i] > 0.0) { radinterp__piece_add(pos, x, L, 1.0); radinterp__piece_add(neg, x, f->ln[i], 1.0); }
            else { radinterp__piece_add(neg, x, L, -1.0); radinterp__piece_add(pos, x, f->ln[i], 1.0); }
        }
    }
    radinterp__piece_bounds(pos);
    radinterp__piece_bounds(neg);
    return 0;
}

/* Is every corner of b within tol of the outside of one of a's edges? */
static int radinterp__outside_an_edge(const radinterp__piece *a, const radinterp__piece *b, double tol)
{
    int i, j;
    for (i = 0; i < a->count; i++) {
        const double *L = a->ln[i];
        for (j = 0; j < b->count; j++)
            if (L[0] * b->v[j][0] + L[1] * b->v[j][1] + L[2] > tol) break;
        if (j == b->count) return 1;
    }
    return 0;
}

/* Do the interiors of two convex pieces miss each other (to within tol)?
   Bounding boxes, then a separating edge of either. */
static int radinterp__pieces_apart(const radinterp__piece *a, const radinterp__piece *b, double tol)
{
    if (a->lo[0] >= b->hi[0] - tol || b->lo[0] >= a->hi[0] - tol || a->lo[1] >= b->hi[1] - tol ||
        b->lo[1] >= a->hi[1] - tol)
        return 1;
    return radinterp__outside_an_edge(a, b, tol) || radinterp__outside_an_edge(b, a, tol);
}

/* Appends the parts of piece f outside piece P to q->piece[*top ..):
   walking P's edges, what lies outside an edge is a part, what lies inside
   goes on to the next edge; what is left at the end lies inside P. Parts
   smaller than tiny (twice the area) are dropped. Returns -1 when the
   pieces outgrow their arrays. */
static int radinterp__subtract_piece(radinterp__query *q, const radinterp__piece *f, const radinterp__piece *P,
                                     int *top, double tol, double tiny)
{
    radinterp__piece rest[2];
    const radinterp__piece *cur = f;
    int j, which = 0;
    for (j = 0; j < P->count && cur->count >= 3; j++) {
        radinterp__piece *out;
        int r;
        if (*top >= RADINTERP__PIECES) return -1;
        out = &q->piece[*top];
        r = radinterp__split_piece(cur, P->ln[j], tol, &rest[which], out);
        if (r < 0) return -1;
        if (r == 1) continue;                       /* wholly inside this edge */
        if (r == 2) { *out = *cur; (*top)++; return 0; } /* wholly outside P */
        if (fabs(radinterp__area2((const double (*)[2])out->v, out->count)) > tiny) (*top)++;
        cur = &rest[which];
        which = 1 - which;
    }
    return 0;
}

/* Adds the piece q->piece[*count] (a new shadow) to the union kept as
   disjoint pieces q->piece[0 .. *count): its parts outside every piece
   already there become new pieces. Returns -1 when the pieces outgrow their
   arrays. */
static int radinterp__union_add(radinterp__query *q, int *count, double tol, double tiny)
{
    int old = *count, first = old, end = old + 1, i, f;
    for (i = 0; i < old && end > first; i++) {
        int top = end, keep = first;
        for (f = first; f < end; f++) {
            if (radinterp__pieces_apart(&q->piece[f], &q->piece[i], tol)) continue;
            if (radinterp__subtract_piece(q, &q->piece[f], &q->piece[i], &top, tol, tiny) != 0) return -1;
            q->piece[f].count = 0; /* replaced by its parts outside piece i */
        }
        for (f = first; f < top; f++) /* close the gaps */
            if (q->piece[f].count) {
                if (f != keep) q->piece[keep] = q->piece[f];
                keep++;
            }
        end = keep;
    }
    *count = end;
    return 0;
}

/* Eq. 6.1 for a convex polygon of the source plane given in the frame f
   (either winding). */
static double radinterp__ff_frame(const radinterp__query *q, const radinterp__frame *f, const double (*v)[2], int n)
{
    double r[RADINTERP__PIECE_VERTS][3], sum = 0.0;
    int i;
    for (i = 0; i < n; i++) {
        radinterp__frame_to3d(f, v[i], r[i]);
        radinterp__d3_sub(r[i], q->p, r[i]);
    }
    for (i = 0; i < n; i++) sum += radinterp__ff_edge(r[i], r[(i + 1) % n], q->n);
    return fabs(sum) / (2.0 * RADINTERP__PI);
}

/* Visible factor = F(source) - sum of F over the disjoint pieces of the
   shadows' union (eq. 6.1 is additive over a partition). Shadows of faces
   turned toward the point go in first: those of one convex object do not
   overlap, and its faces turned away then fall inside them. Returns -1
   when a shadow cannot be represented or the pieces outgrow their arrays
   (the caller triangulates). */
static double radinterp__bp_by_union(radinterp__query *q, const radinterp__bp *bp)
{
    const radinterp_solution *s = q->s;
    const radinterp__link *lk = bp->lk;
    double hidden = 0.0, full, f, tiny, tol = bp->tol;
    uint32_t later[RADINTERP__BP_MAX_SURVIVORS], nlater = 0, i;
    int pass, count = 0, k;
    /* a piece of area below tiny / 2 subtends less than 1e-12 / pi: dropped */
    tiny = 2e-12 * bp->hp * bp->hp;
    /* faces turned away wait in `later`: one pass over the list */
    for (pass = 0; pass < 2; pass++) {
        uint32_t n = pass ? nlater : lk->blocker_count;
        for (i = 0; i < n; i++) {
            uint32_t b = pass ? later[i] : s->blockers[lk->first_blocker + i];
            const radinterp__patch *pb = &s->patches[b];
            radinterp__piece *sh;
            int r;
            if (!pass && !(radinterp__d3_dot(pb->n, bp->pv) > pb->d)) {
                if (nlater == RADINTERP__BP_MAX_SURVIVORS) return -1;
                later[nlater++] = b;
                continue;
            }
            if (count >= RADINTERP__PIECES) return -1;
            sh = &q->piece[count];
            r = radinterp__bp_shadow_piece(s, bp, pb, sh);
            if (r < 0) return -1;
            if (r == 0 || fabs(radinterp__area2((const double (*)[2])sh->v, sh->count)) <= tiny) continue;
            if (radinterp__covers((const double (*)[2])sh->v, sh->count, (const double (*)[2])bp->sc2, bp->nc))
                return 0.0; /* this blocker alone hides the whole source */
            if (radinterp__union_add(q, &count, tol, tiny) != 0) return -1;
        }
    }
    if (count == 0) return radinterp__ff_poly(q->p, q->n, bp->Sc_pushed, bp->nc);
    q->triangulated++;
    for (k = 0; k < count; k++)
        hidden += radinterp__ff_frame(q, &bp->fr_ff, (const double (*)[2])q->piece[k].v, q->piece[k].count);
    full = radinterp__ff_poly(q->p, q->n, bp->Sc_pushed, bp->nc);
    f = full - hidden;
    /* the difference carries the rounding of both sums: a source hidden
       by several shadows together comes out at about 1e-16 of F, not 0 */
    return f > 1e-12 * full ? f : 0.0;
}

/* ---- visibility by triangulation and rays (Hardt 6.2.3) ----------------- */

/* A shadow inside another one adds no edge to the visible region, and a
   ray through it meets the other blocker too: its count becomes 0. */
static void radinterp__drop_covered_shadows(radinterp__query *q, int nsurv)
{
    int i, j;
    for (i = 0; i < nsurv; i++)
        for (j = 0; j < nsurv; j++) {
            if (j == i || q->shadow_count[j] == 0) continue;
            if (radinterp__covers((const double (*)[2])q->shadow[j], q->shadow_count[j],
                                  (const double (*)[2])q->shadow[i], q->shadow_count[i])) {
                q->shadow_count[i] = 0;
                break;
            }
        }
}

/* The CDT of the source outline and the shadows' edges as constraints:
   every shadow is a closed loop, so the flood below cannot leak out of it. */
static void radinterp__bp_triangulate(radinterp__query *q, const radinterp__bp *bp, int nsurv)
{
    const radinterp_solution *s = q->s;
    radinterp__cdt *cdt = &q->cdt;
    uint32_t ids[RADINTERP__POLY_MAX];
    int i, j;
    if (!q->cdt_ready) radinterp__cdt_init(cdt, &s->allocator, q->mem, sizeof q->mem);
    else radinterp__cdt_clear(cdt);
    q->cdt_ready = 1;
    cdt->merge_distance2 = s->min_bp_segment * s->min_bp_segment;
    for (j = 0; j < bp->nc; j++) ids[j] = radinterp__cdt_add_point(cdt, bp->sc2[j][0], bp->sc2[j][1]);
    for (j = 0; j < bp->nc; j++)
        if (ids[j] != RADINTERP__NONE && ids[(j + 1) % bp->nc] != RADINTERP__NONE)
            radinterp__cdt_add_segment(cdt, ids[j], ids[(j + 1) % bp->nc]);
    for (i = 0; i < nsurv; i++) {
        int m = q->shadow_count[i];
        for (j = 0; j < m; j++) ids[j] = radinterp__cdt_add_point(cdt, q->shadow[i][j][0], q->shadow[i][j][1]);
        for (j = 0; j < m; j++) {
            uint32_t a = ids[j], b = ids[(j + 1) % m];
            if (a == RADINTERP__NONE || b == RADINTERP__NONE || a == b) continue;
            radinterp__cdt_add_segment(cdt, a, b);
        }
    }
    if (cdt->failed && cdt->vertex_count == 0) q->failed = 1;
}

/* Is the region around the 2D point c2 of the source visible from pv? It
   must lie inside the source outline and no blocker may cross the ray. */
static int radinterp__bp_region_visible(const radinterp__query *q, const radinterp__bp *bp, const double *c2,
                                        const uint32_t *survivors, int nsurv, int overflow)
{
    const radinterp_solution *s = q->s;
    double c3[3];
    uint32_t i;
    int k;
    for (k = 0; k < bp->nc; k++)
        if (!(radinterp__orient2d(bp->sc2[k], bp->sc2[(k + 1) % bp->nc], c2) > 0.0)) return 0;
    radinterp__frame_to3d(&bp->fr, c2, c3);
    if (overflow) {
        for (i = 0; i < bp->lk->blocker_count; i++)
            if (radinterp__ray_hits_patch(&s->patches[s->blockers[bp->lk->first_blocker + i]], bp->pv, c3)) return 0;
    } else {
        for (k = 0; k < nsurv; k++)
            if (radinterp__ray_hits_patch(&s->patches[survivors[k]], bp->pv, c3)) return 0;
    }
    return 1;
}

/* Classifies the faces: floods each region bounded by constraints, then
   lets its largest triangle's centre decide (a sliver's centre could sit on
   an edge). flags: 1 = hidden or outside, 2 = visible. */
static void radinterp__bp_classify(radinterp__query *q, const radinterp__bp *bp, unsigned char *flags,
                                   const uint32_t *survivors, int nsurv, int overflow)
{
    radinterp__cdt *cdt = &q->cdt;
    uint32_t t;
    int k;
    memset(flags, 0, cdt->tri_count);
    for (t = 0; t < cdt->tri_count; t++) {
        double c2[2], best = -1.0;
        uint32_t r, pick = t;
        int visible;
        if (flags[t] || radinterp__cdt_is_ghost(cdt, t)) continue;
        cdt->queue.count = cdt->touched.count = 0;
        flags[t] = 3; /* in the region being flooded */
        if (!radinterp__u32s_push(cdt, &cdt->queue, t)) break;
        while (cdt->queue.count) {
            uint32_t u = cdt->queue.data[--cdt->queue.count];
            const uint32_t *v = cdt->tri[u].v;
            double area = radinterp__orient2d_area(cdt->xy + 2 * v[0], cdt->xy + 2 * v[1], cdt->xy + 2 * v[2]);
            if (area > best) { best = area; pick = u; }
            if (!radinterp__u32s_push(cdt, &cdt->touched, u)) break;
            for (k = 0; k < 3; k++) {
                uint32_t w = cdt->tri[u].n[k];
                if ((cdt->tri[u].flags >> k) & 1u || flags[w] || radinterp__cdt_is_ghost(cdt, w)) continue;
                flags[w] = 3;
                if (!radinterp__u32s_push(cdt, &cdt->queue, w)) break;
            }
        }
        {
            const uint32_t *v = cdt->tri[pick].v;
            c2[0] = (cdt->xy[2 * v[0]] + cdt->xy[2 * v[1]] + cdt->xy[2 * v[2]]) / 3.0;
            c2[1] = (cdt->xy[2 * v[0] + 1] + cdt->xy[2 * v[1] + 1] + cdt->xy[2 * v[2] + 1]) / 3.0;
        }
        visible = radinterp__bp_region_visible(q, bp, c2, survivors, nsurv, overflow);
        for (r = 0; r < cdt->touched.count; r++) flags[cdt->touched.data[r]] = (unsigned char)(visible ? 2 : 1);
    }
}

/* Eq. 6.1 over the visible triangles: shared edges cancel, so only the
   edges between a visible and a non-visible triangle are summed. */
static double radinterp__bp_visible_ff(const radinterp__query *q, const radinterp__bp *bp, const unsigned char *flags)
{
    const radinterp__cdt *cdt = &q->cdt;
    double sum = 0.0;
    uint32_t t;
    int k;
    for (t = 0; t < cdt->tri_count; t++) {
        if (flags[t] != 2) continue;
        for (k = 0; k < 3; k++) {
            uint32_t w = cdt->tri[t].n[k];
            const uint32_t *v = cdt->tri[t].v;
            double a3[3], b3[3], ra[3], rb[3];
            if (flags[w] == 2 && !radinterp__cdt_is_ghost(cdt, w)) continue;
            radinterp__frame_to3d(&bp->fr_ff, cdt->xy + 2 * v[(k + 1) % 3], a3);
            radinterp__frame_to3d(&bp->fr_ff, cdt->xy + 2 * v[(k + 2) % 3], b3);
            radinterp__d3_sub(a3, q->p, ra);
            radinterp__d3_sub(b3, q->p, rb);
            sum += radinterp__ff_edge(ra, rb, q->n);
        }
    }
    return -sum / (2.0 * RADINTERP__PI);
}

/* Hardt's backprojection: triangulate, classify each region by one ray,
   sum the visible triangles' factors. */
static double radinterp__bp_by_triangulation(radinterp__query *q, const radinterp__bp *bp, uint32_t *survivors,
                                             int nsurv, int overflow)
{
    unsigned char *flags = q->flags;
    int i, kept = 0;
    double f;
    if (!overflow) radinterp__drop_covered_shadows(q, nsurv);
    radinterp__bp_triangulate(q, bp, nsurv);
    for (i = 0; i < nsurv; i++)
        if (q->shadow_count[i]) survivors[kept++] = survivors[i];
    if (kept == 0 && !overflow) return radinterp__ff_poly(q->p, q->n, bp->Sc_pushed, bp->nc);
    if (q->cdt.tri_count > sizeof q->flags) {
        flags = (unsigned char *)radinterp__alloc(&q->s->allocator, q->cdt.tri_count);
        if (!flags) { q->failed = 1; return 0.0; }
    }
    radinterp__bp_classify(q, bp, flags, survivors, kept, overflow);
    f = radinterp__bp_visible_ff(q, bp, flags);
    if (flags != q->flags) radinterp__free(&q->s->allocator, flags);
    return f;
}

/* Visible factor of the source polygon Sc (front normal ns, plane
   ns . x = ds_pushed, already moved push behind the real source) from the
   query point, by backprojection of the link's blockers. */
static double radinterp__backproject(radinterp__query *q, const radinterp__link *lk, const double (*Sc)[3], int nc,
                                     const double *ns, double ds_pushed, double push)
{
    radinterp__bp bp;
    uint32_t survivors[RADINTERP__BP_MAX_SURVIVORS];
    int overflow, nsurv;
    radinterp__bp_setup(q, &bp, lk, Sc, nc, ns, ds_pushed, push);
    if (q->s->visibility == RADINTERP_VISIBILITY_SHADOWS) {
        double f = radinterp__bp_by_union(q, &bp);
        if (f >= 0.0) return f;
    }
    nsurv = radinterp__bp_collect(q, &bp, survivors, &overflow);
    if (nsurv < 0) return 0.0;
    if (nsurv == 0 && !overflow) return radinterp__ff_poly(q->p, q->n, Sc, nc);
    q->triangulated++;
    return radinterp__bp_by_triangulation(q, &bp, survivors, nsurv, overflow);
}

/* Point-to-polygon factor from the query point to one node of a link's
   source, seen past the link's blockers. */
static double radinterp__node_point_ff(radinterp__query *q, const radinterp__link *lk, uint32_t node)
{
    const radinterp_solution *s = q->s;
    const radinterp__node *src = &s->nodes[node];
    const radinterp__patch *ps = &s->patches[src->patch];
    double S[RADINTERP__POLY_MAX][3], Sc[RADINTERP__POLY_MAX][3], ds = ps->d - s->push_off;
    int n = radinterp__node_poly(src, S), nc, i;
    if (radinterp__d3_dot(ps->n, q->p) - ds <= 0.0) return 0.0;  /* p behind the source */
    for (i = 0; i < n; i++) {  /* push-off (6.4) */
        S[i][0] -= s->push_off * ps->n[0];
        S[i][1] -= s->push_off * ps->n[1];
        S[i][2] -= s->push_off * ps->n[2];
    }
    nc = radinterp__clip_poly((const double (*)[3])S, n, q->n, q->dr, Sc);  /* horizon (6.2.1) */
    if (nc < 3) return 0.0;
    if (lk->blocker_count == 0) return radinterp__ff_poly(q->p, q->n, (const double (*)[3])Sc, nc);
    return radinterp__backproject(q, lk, (const double (*)[3])Sc, nc, ps->n, ds, s->push_off);
}

/* Point-to-source factor of one link at the query point. */
RADINTERP__MAYBE_UNUSED static double radinterp__link_point_ff(radinterp__query *q, const radinterp__link *lk)
{
    return radinterp__node_point_ff(q, lk, lk->source);
}

/* Unoccluded factor from the query point to a node (no backprojection): an
   upper bound of its share, to decide whether its children matter. */
static double radinterp__node_point_ff_bound(const radinterp__query *q, uint32_t node)
{
    const radinterp__node *nd = &q->s->nodes[node];
    double S[RADINTERP__POLY_MAX][3], Sc[RADINTERP__POLY_MAX][3];
    int n = radinterp__node_poly(nd, S), nc = radinterp__clip_poly((const double (*)[3])S, n, q->n, q->dr, Sc);
    return nc < 3 ? 0.0 : radinterp__ff_poly(q->p, q->n, (const double (*)[3])Sc, nc);
}

/* B_src * F for one link. The source node's radiosity is a mean; where its
   children differ enough that the mean would misjudge the part seen from p
   (their spread times the node's factor above a tenth of eps), the children
   are taken instead, each with its own factor past the same blockers. */
static void radinterp__link_point_add(radinterp__query *q, const radinterp__link *lk, uint32_t node, double *h)
{
    const radinterp_solution *s = q->s;
    const radinterp__node *nd = &s->nodes[node];
    double f;
    if (nd->child != RADINTERP__NONE && q->depth_left > 0 &&
        radinterp__source_spread(s, node) * radinterp__node_point_ff_bound(q, node) > 0.1 * s->eps) {
        uint32_t c;
        q->depth_left--;
        for (c = 0; c < 4; c++) radinterp__link_point_add(q, lk, nd->child + c, h);
        q->depth_left++;
        return;
    }
    if (nd->b[0] == 0.0f && nd->b[1] == 0.0f && nd->b[2] == 0.0f) return;
    f = radinterp__node_point_ff(q, lk, node);
    h[0] += f * nd->b[0];
    h[1] += f * nd->b[1];
    h[2] += f * nd->b[2];
}

/* ======================================================================
   14. public entry points
   ---------------------------------------------------------------------- */
#include <stdarg.h>

static void radinterp__log(const radinterp_desc *d, const char *fmt, ...)
{
    char msg[320];
    va_list ap;
    if (!d->log) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    d->log(d->log_user, msg);
}

static const float *radinterp__position(const radinterp_desc *d, uint32_t v)
{
    size_t stride = d->position_stride ? d->position_stride : 3 * sizeof(float);
    return (const float *)(const void *)((const char *)d->positions + (size_t)v * stride);
}

static int radinterp__bad_param(float v) { return !(v >= 0.0f) || !isfinite(v); }

/* Arguments, indices, numbers: everything but the patch shapes. */
static radinterp_result radinterp__check_desc(const radinterp_desc *d)
{
    uint32_t i, k;
    if (!radinterp__allocator_valid(&d->allocator)) {
        radinterp__log(d, "radinterp_solve: allocator.alloc and allocator.free must both be set or both be NULL");
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (!d->positions || !d->vertex_count || !d->patches || !d->patch_count || !d->materials || !d->material_count) {
        radinterp__log(d, "radinterp_solve: positions, patches and materials must be non-NULL with non-zero counts");
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (d->position_stride && d->position_stride < 3 * sizeof(float)) {
        radinterp__log(d, "radinterp_solve: position_stride %u is smaller than a vertex", (unsigned)d->position_stride);
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (d->patch_count > 0x3FFFFFFFu) {
        radinterp__log(d, "radinterp_solve: too many patches");
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (radinterp__bad_param(d->eps) || radinterp__bad_param(d->min_area) || radinterp__bad_param(d->rel_error_cutoff) ||
        radinterp__bad_param(d->push_off) || radinterp__bad_param(d->nudge) || radinterp__bad_param(d->min_bp_segment) ||
        radinterp__bad_param(d->epsilon) || radinterp__bad_param(d->planarity_tolerance)) {
        radinterp__log(d, "radinterp_solve: a parameter is negative, NaN or infinite");
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if ((unsigned)d->visibility > (unsigned)RADINTERP_VISIBILITY_TRIANGULATION) {
        radinterp__log(d, "radinterp_solve: visibility %u is not a radinterp_visibility", (unsigned)d->visibility);
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    for (i = 0; i < d->material_count; i++) {
        const radinterp_material *m = &d->materials[i];
        for (k = 0; k < 3; k++) {
            if (!isfinite(m->reflectance[k]) || m->reflectance[k] < 0.0f || m->reflectance[k] > 1.0f) {
                radinterp__log(d, "radinterp_solve: material %u: reflectance must lie in [0, 1]", i);
                return RADINTERP_ERROR_INVALID_ARGUMENT;
            }
            if (!isfinite(m->emission[k]) || m->emission[k] < 0.0f) {
                radinterp__log(d, "radinterp_solve: material %u: emission must be finite and not negative", i);
                return RADINTERP_ERROR_INVALID_ARGUMENT;
            }
        }
    }
    for (i = 0; i < d->patch_count; i++) {
        const uint32_t *p = d->patches + 4 * (size_t)i;
        for (k = 0; k < 4; k++) {
            if (k == 3 && p[k] == RADINTERP_NO_VERTEX) break;
            if (p[k] >= d->vertex_count) {
                radinterp__log(d, "radinterp_solve: patch %u: vertex index %u out of range (%u vertices)", i, p[k],
                               d->vertex_count);
                return RADINTERP_ERROR_INVALID_ARGUMENT;
            }
            if (!radinterp__finite3(radinterp__position(d, p[k]))) {
                radinterp__log(d, "radinterp_solve: patch %u: vertex %u is NaN or infinite", i, p[k]);
                return RADINTERP_ERROR_INVALID_ARGUMENT;
            }
        }
        if (d->patch_materials && d->patch_materials[i] >= d->material_count) {
            radinterp__log(d, "radinterp_solve: patch %u: material %u out of range (%u materials)", i,
                           d->patch_materials[i], d->material_count);
            return RADINTERP_ERROR_INVALID_ARGUMENT;
        }
    }
    return RADINTERP_OK;
}

/* Patch geometry: skipped when degenerate, an error when non-planar or
   non-convex. */
static radinterp_result radinterp__build_patches(radinterp_solution *s, const radinterp_desc *d)
{
    uint32_t i, k;
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, planarity;
    s->patches = (radinterp__patch *)radinterp__alloc_array(&s->allocator, d->patch_count, sizeof *s->patches);
    if (!s->patches) return RADINTERP_ERROR_OUT_OF_MEMORY;
    memset(s->patches, 0, (size_t)d->patch_count * sizeof *s->patches);
    s->patch_count = d->patch_count;
    for (i = 0; i < d->patch_count; i++)
        for (k = 0; k < 4; k++) {
            uint32_t v = d->patches[4 * (size_t)i + k];
            const float *x;
            int c;
            if (k == 3 && v == RADINTERP_NO_VERTEX) break;
            x = radinterp__position(d, v);
            for (c = 0; c < 3; c++) { lo[c] = x[c] < lo[c] ? x[c] : lo[c]; hi[c] = x[c] > hi[c] ? x[c] : hi[c]; }
        }
    for (k = 0; k < 3; k++) { s->scene_lo[k] = (float)lo[k]; s->scene_hi[k] = (float)hi[k]; }
    s->diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(s->diag > 0.0)) s->diag = 1.0;
    planarity = radinterp__def(d->planarity_tolerance, 1e-3f);
    for (i = 0; i < d->patch_count; i++) {
        radinterp__patch *pt = &s->patches[i];
        double v[4][3], dev;
        int count = 0;
        uint32_t m = d->patch_materials ? d->patch_materials[i] : 0;
        radinterp__patch_check r;
        for (k = 0; k < 4; k++) {
            uint32_t vi = d->patches[4 * (size_t)i + k];
            if (k == 3 && vi == RADINTERP_NO_VERTEX) break;
            radinterp__d3_from_f(radinterp__position(d, vi), v[count++]);
        }
        pt->root = RADINTERP__NONE;
        pt->material = m;
        memcpy(pt->rho, d->materials[m].reflectance, sizeof pt->rho);
        memcpy(pt->e, d->materials[m].emission, sizeof pt->e);
        r = radinterp__patch_setup(pt, v, count, s->diag, planarity, &dev);
        if (r == RADINTERP__PATCH_DEGENERATE) {
            pt->count = 0;
            s->skipped_patches++;
            continue;
        }
        if (r == RADINTERP__PATCH_NONPLANAR) {
            radinterp__log(d, "radinterp_solve: patch %u is not planar (a corner lies %g from its plane)", i, dev);
            return RADINTERP_ERROR_INVALID_ARGUMENT;
        }
        if (r == RADINTERP__PATCH_NONCONVEX) {
            radinterp__log(d, "radinterp_solve: patch %u is not convex (or its corners cross)", i);
            return RADINTERP_ERROR_INVALID_ARGUMENT;
        }
    }
    if (s->skipped_patches == s->patch_count) {
        radinterp__log(d, "radinterp_solve: every patch has zero area");
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    return RADINTERP_OK;
}

/* The BVH over the patches' triangles (a quadrilateral gives two). */
static radinterp_result radinterp__build_bvh(radinterp_solution *s)
{
    uint32_t i, k, tris = 0, t = 0;
    float *pos;
    uint32_t *idx;
    radinterp__mesh_view view;
    int ok;
    for (i = 0; i < s->patch_count; i++) tris += s->patches[i].count ? s->patches[i].count - 2 : 0;
    pos = (float *)radinterp__alloc_array(&s->allocator, (size_t)s->patch_count * 4, 3 * sizeof(float));
    idx = (uint32_t *)radinterp__alloc_array(&s->allocator, tris, 3 * sizeof(uint32_t));
    s->tri_patch = (uint32_t *)radinterp__alloc_array(&s->allocator, tris, sizeof(uint32_t));
    if (!pos || !idx || !s->tri_patch) {
        radinterp__free(&s->allocator, pos);
        radinterp__free(&s->allocator, idx);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    for (i = 0; i < s->patch_count; i++) {
        const radinterp__patch *pt = &s->patches[i];
        memcpy(pos + 12 * (size_t)i, pt->v, sizeof pt->v);
        for (k = 1; k + 1 < pt->count; k++) {
            idx[3 * t] = 4 * i;
            idx[3 * t + 1] = 4 * i + k;
            idx[3 * t + 2] = 4 * i + k + 1;
            s->tri_patch[t++] = i;
        }
    }
    view.positions = pos;
    view.stride = 0;
    view.indices = idx;
    view.tri_count = tris;
    ok = radinterp__bvh_build(&s->bvh, &view, &s->allocator) == 0;
    radinterp__free(&s->allocator, pos);
    radinterp__free(&s->allocator, idx);
    return ok ? RADINTERP_OK : RADINTERP_ERROR_OUT_OF_MEMORY;
}

static radinterp_result radinterp__make_roots(radinterp_solution *s, const radinterp__run *run)
{
    uint32_t i;
    for (i = 0; i < s->patch_count; i++) {
        radinterp__patch *pt = &s->patches[i];
        radinterp__node *nd;
        if (!pt->count) continue;
        if (!radinterp__nodes_reserve(s, 1)) return RADINTERP_ERROR_OUT_OF_MEMORY;
        nd = &s->nodes[s->node_count];
        memset(nd, 0, sizeof *nd);
        memcpy(nd->v, pt->v, sizeof pt->v);
        nd->count = pt->count;
        nd->patch = i;
        nd->parent = RADINTERP__NONE;
        nd->child = RADINTERP__NONE;
        memcpy(nd->b, pt->e, sizeof pt->e);
        radinterp__node_bounds(nd);
        pt->root = s->node_count++;
    }
    {
        radinterp__open_ctx oc;
        oc.s = s;
        oc.first = 0;
        oc.count = s->node_count;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__open_job, &oc, (oc.count + 63) / 64);
    }
    return RADINTERP_OK;
}

static radinterp_result radinterp__collect_leaves(radinterp_solution *s)
{
    uint32_t i, n = 0, *stack, top;
    for (i = 0; i < s->node_count; i++) n += s->nodes[i].child == RADINTERP__NONE;
    s->leaves = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
    stack = (uint32_t *)radinterp__alloc_array(&s->allocator, (size_t)s->node_count + 4, sizeof(uint32_t));
    if (!s->leaves || !stack) {
        radinterp__free(&s->allocator, stack);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    s->leaf_count = 0;
    for (i = 0; i < s->patch_count; i++) {
        if (!s->patches[i].count) continue;
        top = 0;
        stack[top++] = s->patches[i].root;
        while (top) {
            uint32_t nd = stack[--top], c = s->nodes[nd].child;
            if (c == RADINTERP__NONE) { s->leaves[s->leaf_count++] = nd; continue; }
            stack[top++] = c + 3; stack[top++] = c + 2; stack[top++] = c + 1; stack[top++] = c;
        }
    }
    radinterp__free(&s->allocator, stack);
    return RADINTERP_OK;
}

RADINTERP_API void radinterp_solution_destroy(radinterp_solution *s)
{
    radinterp_allocator a;
    if (!s) return;
    a = s->allocator;
    radinterp__free(&a, s->patches);
    radinterp__bvh_free(&s->bvh, &a);
    radinterp__free(&a, s->tri_patch);
    radinterp__free(&a, s->nodes);
    radinterp__free(&a, s->links);
    radinterp__free(&a, s->blockers);
    radinterp__free(&a, s->leaves);
    radinterp__free(&a, s);
}

RADINTERP_API radinterp_result radinterp_solve(const radinterp_desc *desc, radinterp_solution **out)
{
    radinterp_solution *s;
    radinterp_result res;
    radinterp__run run;
    if (!out) return RADINTERP_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!desc) return RADINTERP_ERROR_INVALID_ARGUMENT;
    res = radinterp__check_desc(desc);
    if (res != RADINTERP_OK) return res;
    s = (radinterp_solution *)radinterp__alloc(&desc->allocator, sizeof *s);
    if (!s) return RADINTERP_ERROR_OUT_OF_MEMORY;
    memset(s, 0, sizeof *s);
    s->allocator = desc->allocator;
    s->trace = desc->trace;
    s->trace_user = desc->trace_user;
    run.desc = desc;
    run.iteration = 0;
    res = radinterp__build_patches(s, desc);
    if (res == RADINTERP_OK) {
        double diag = s->diag;
        double power = 0.0, area = 0.0;
        uint32_t i;
        for (i = 0; i < s->patch_count; i++) {
            const radinterp__patch *pt = &s->patches[i];
            double e = pt->e[0] > pt->e[1] ? (pt->e[0] > pt->e[2] ? pt->e[0] : pt->e[2]) : (pt->e[1] > pt->e[2] ? pt->e[1] : pt->e[2]);
            power += e * pt->area;
            area += pt->area;
        }
        /* half the mean emitted radiosity: the scale of the light in the scene */
        s->eps = desc->eps > 0.0f ? desc->eps : (area > 0.0 && power > 0.0 ? 0.5 * power / area : 1.0);
        s->min_area = desc->min_area > 0.0f ? desc->min_area : (diag / 200.0) * (diag / 200.0);
        s->rel_error_cutoff = radinterp__def(desc->rel_error_cutoff, 1e-3f);
        s->max_iterations = radinterp__def(desc->max_iterations, 64u);
        s->ff_samples = radinterp__def(desc->ff_samples, 9u);
        s->visibility_rays = radinterp__def(desc->visibility_rays, 8u);
        s->epsilon = radinterp__def(desc->epsilon, 1e-6f);
        s->push_off = desc->push_off > 0.0f ? desc->push_off : 1e-5 * diag;
        s->nudge = desc->nudge > 0.0f ? desc->nudge : 1e-6 * diag;
        s->min_bp_segment = desc->min_bp_segment > 0.0f ? desc->min_bp_segment : 1e-9 * diag;
        s->seed = desc->seed;
        s->visibility = desc->visibility ? (uint32_t)desc->visibility : (uint32_t)RADINTERP_VISIBILITY_SHADOWS;
        res = radinterp__build_bvh(s);
    }
    if (res == RADINTERP_OK) res = radinterp__make_roots(s, &run);
    if (res == RADINTERP_OK) res = radinterp__initial_links(s, &run);
    if (res == RADINTERP_OK) res = radinterp__iterate(s, &run);
    if (res == RADINTERP_OK) res = radinterp__collect_leaves(s);
    if (res != RADINTERP_OK) {
        if (res == RADINTERP_ERROR_OUT_OF_MEMORY) radinterp__log(desc, "radinterp_solve: out of memory");
        radinterp_solution_destroy(s);
        return res;
    }
    *out = s;
    return RADINTERP_OK;
}

RADINTERP_API void radinterp_solution_info(const radinterp_solution *s, radinterp_info *info)
{
    if (!info) return;
    memset(info, 0, sizeof *info);
    if (!s) return;
    info->patch_count = s->patch_count;
    info->skipped_patches = s->skipped_patches;
    info->node_count = s->node_count;
    info->leaf_count = s->leaf_count;
    info->link_count = s->link_count;
    info->blocker_entries = s->blocker_count;
    info->iterations = s->iterations;
    info->converged = s->converged;
    info->max_relative_change = s->max_relative_change;
    info->shadow_rays = s->shadow_rays;
    info->bytes = sizeof *s + (size_t)s->patch_count * sizeof(radinterp__patch) +
                  (size_t)s->node_cap * sizeof(radinterp__node) + (size_t)s->link_count * sizeof(radinterp__link) +
                  (size_t)s->blocker_count * sizeof(uint32_t) + (size_t)s->leaf_count * sizeof(uint32_t) +
                  (size_t)s->bvh.node_count * sizeof(radinterp__bvh_node) +
                  (size_t)s->bvh.tri_count * (sizeof(radinterp__bvh_tri) + sizeof(uint32_t));
}

static int radinterp__patch_ok(const radinterp_solution *s, uint32_t patch)
{
    return s && patch < s->patch_count && s->patches[patch].count != 0;
}

RADINTERP_API radinterp_result radinterp_patch_radiosity(const radinterp_solution *s, uint32_t patch, float rgb[3])
{
    if (!rgb) return RADINTERP_ERROR_INVALID_ARGUMENT;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!radinterp__patch_ok(s, patch)) return RADINTERP_ERROR_INVALID_ARGUMENT;
    {
        /* over the whole patch: open parts at their radiosity, enclosed parts
           at their emission alone */
        const radinterp__patch *pt = &s->patches[patch];
        double acc[3] = {0.0, 0.0, 0.0};
        uint32_t stack[128], top = 0;
        int k;
        stack[top++] = pt->root;
        while (top) {
            const radinterp__node *nd = &s->nodes[stack[--top]];
            if (nd->child != RADINTERP__NONE && top + 4 <= 128) {
                uint32_t c;
                for (c = 0; c < 4; c++) stack[top++] = nd->child + c;
                continue;
            }
            for (k = 0; k < 3; k++) acc[k] += nd->area * (nd->open * nd->b[k] + (1.0 - nd->open) * pt->e[k]);
        }
        for (k = 0; k < 3; k++) rgb[k] = (float)(acc[k] / pt->area);
    }
    return RADINTERP_OK;
}

RADINTERP_API uint32_t radinterp_leaf_count(const radinterp_solution *s) { return s ? s->leaf_count : 0; }

RADINTERP_API radinterp_result radinterp_get_leaf(const radinterp_solution *s, uint32_t index, radinterp_leaf *leaf)
{
    const radinterp__node *nd;
    if (!leaf) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(leaf, 0, sizeof *leaf);
    if (!s || index >= s->leaf_count) return RADINTERP_ERROR_INVALID_ARGUMENT;
    nd = &s->nodes[s->leaves[index]];
    leaf->patch = nd->patch;
    leaf->depth = nd->depth;
    leaf->vertex_count = nd->count;
    memcpy(leaf->vertices, nd->v, sizeof nd->v);
    memcpy(leaf->radiosity, nd->b, sizeof nd->b);
    leaf->area = nd->area;
    leaf->open = nd->open;
    return RADINTERP_OK;
}

/* Irradiance at p on a patch, summed over the links of its leaf and of the
   leaf's ancestors (6.2). */
static radinterp_result radinterp__irradiance(const radinterp_solution *s, uint32_t patch, const float p[3],
                                              const float toward[3], double *h, uint32_t *triangulated)
{
    radinterp__query query, *q = &query;  /* about 40 KB of stack: no allocation in the common case */
    uint32_t node;
    int k;
    h[0] = h[1] = h[2] = 0.0;
    if (!p || !radinterp__patch_ok(s, patch) || !radinterp__finite3(p) || (toward && !radinterp__finite3(toward)))
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    q->s = s;
    q->cdt_ready = 0;
    q->failed = 0;
    q->depth_left = 8;
    q->triangulated = 0;
    radinterp__d3_from_f(p, q->p);
    memcpy(q->n, s->patches[patch].n, sizeof q->n);
    q->dr = radinterp__d3_dot(q->n, q->p);
    memcpy(q->pv, q->p, sizeof q->pv);
    if (toward) {
        double t[3], d[3], len, k2;
        radinterp__d3_from_f(toward, t);
        radinterp__d3_sub(t, q->p, d);
        k2 = radinterp__d3_dot(d, q->n);
        for (k = 0; k < 3; k++) d[k] -= k2 * q->n[k];
        len = radinterp__d3_len(d);
        if (len > 0.0) {
            double step = len < s->nudge ? len : s->nudge;
            for (k = 0; k < 3; k++) q->pv[k] += d[k] * (step / len);
        }
    }
    for (node = radinterp__locate_leaf(s, patch, q->pv); node != RADINTERP__NONE; node = s->nodes[node].parent) {
        const radinterp__node *nd = &s->nodes[node];
        uint32_t l;
        for (l = nd->first_link; l < nd->first_link + nd->link_count; l++)
            radinterp__link_point_add(q, &s->links[l], s->links[l].source, h);
    }
    if (q->cdt_ready) radinterp__cdt_free(&q->cdt);
    if (triangulated) *triangulated = q->triangulated;
    return q->failed ? RADINTERP_ERROR_OUT_OF_MEMORY : RADINTERP_OK;
}

RADINTERP_API radinterp_result radinterp_irradiance_at_point(const radinterp_solution *s, uint32_t patch,
                                                             const float p[3], const float toward[3], float rgb[3])
{
    double h[3];
    radinterp_result r;
    if (!rgb) return RADINTERP_ERROR_INVALID_ARGUMENT;
    r = radinterp__irradiance(s, patch, p, toward, h, NULL);
    rgb[0] = (float)h[0];
    rgb[1] = (float)h[1];
    rgb[2] = (float)h[2];
    return r;
}

RADINTERP_API radinterp_result radinterp_radiosity_at_point(const radinterp_solution *s, uint32_t patch,
                                                            const float p[3], const float toward[3], float rgb[3])
{
    double h[3];
    radinterp_result r;
    int k;
    if (!rgb) return RADINTERP_ERROR_INVALID_ARGUMENT;
    r = radinterp__irradiance(s, patch, p, toward, h, NULL);
    if (r != RADINTERP_OK && r != RADINTERP_ERROR_OUT_OF_MEMORY) { rgb[0] = rgb[1] = rgb[2] = 0.0f; return r; }
    for (k = 0; k < 3; k++) rgb[k] = (float)(s->patches[patch].e[k] + s->patches[patch].rho[k] * h[k]);
    return r;
}

RADINTERP_API const char *radinterp_result_string(radinterp_result r)
{
    switch (r) {
    case RADINTERP_OK: return "ok";
    case RADINTERP_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RADINTERP_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RADINTERP_ERROR_CORRUPT_DATA: return "corrupt data";
    case RADINTERP_ERROR_VERSION: return "unsupported format version";
    case RADINTERP_ERROR_CANCELLED: return "cancelled";
    case RADINTERP_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* RADINTERP_IMPLEMENTATION */

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
