/* trace.h - a small ray tracer for the examples: a BVH over an OBJ scene (the
   same binned-SAH BVH, watertight test and traversal as the project's
   headers), rigid moving instances with their own BVHs, and shading with
   direct light from emissive triangles (one area-light sample and shadow ray)
   plus a chosen number of cosine-sampled diffuse bounces.

       ex_tracer *t = ex_tracer_create(&scene);
       int bunny = ex_tracer_add_instance(t, &bunny_mesh, grey);
       ex_tracer_set_transform(t, bunny, m);          // 3x4 object-to-world, row-major
       ex_rng rng = ex_rng_stream(seed, pixel_index);
       ex_tracer_shade(t, org, dir, 1, &rng, rgb, &hit);
       ex_tracer_destroy(t);

   Surfaces are one-sided as in radiosity: a back face is black and does not
   emit. Materials: Kd (Lambert), Ks/Ns (normalized Phong, direct light only),
   Ke (emitted radiance), tf (straight-through transmittance: thin glass).
   Queries are thread-safe; set_transform and set_sky are not (call them
   between frames).

   Glass and sky: a surface with transmittance tf passes tf of the light
   straight through, from either side (no refraction); shadow rays are
   attenuated by every such surface they cross (ex_tracer_transmittance;
   ex_tracer_transmittance_static leaves the instances out),
   and a path crossing one goes on through it or bounces, chosen in
   proportion to tf and Kd, without using up a bounce. A sky
   (ex_tracer_set_sky, scene_sky.h: constant or an environment map) is seen
   by camera rays that leave the scene and lights every diffuse hit as
   direct light: one cosine-distributed ray per hit, attenuated by the glass
   it crosses. ex_tracer_intersect_through finds the first opaque surface
   behind the panes along a ray, with the panes' transmittance (what a
   camera sees through a window). Scenes without glass or sky trace
   exactly as before (no extra random numbers). */
#ifndef EXAMPLES_COMMON_TRACE_H
#define EXAMPLES_COMMON_TRACE_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "obj.h"
#include "scene_sky.h"

#include "base.h"

#define TR__FN EX_FN
#define TR_MALLOC(size) malloc(size)
#define TR_FREE(ptr) free(ptr)

typedef struct tr_allocator {
    void *(*alloc)(size_t size, void *user);
    void (*free)(void *ptr, void *user);
    void *user;
} tr_allocator;

/* ======================================================================
   1. allocation
   ---------------------------------------------------------------------- */

/* Both callbacks or neither: a lone alloc would leak through TR_FREE. */
TR__FN int tr__allocator_valid(const tr_allocator *a)
{
    return (a->alloc == NULL) == (a->free == NULL);
}

TR__FN void *tr__alloc(const tr_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    return a->alloc ? a->alloc(size, a->user) : TR_MALLOC(size);
}

/* count * item bytes, or NULL when the product overflows. */
TR__FN void *tr__alloc_array(const tr_allocator *a, size_t count, size_t item)
{
    if (item && count > SIZE_MAX / item) return NULL;
    return tr__alloc(a, count * item);
}

TR__FN void tr__free(const tr_allocator *a, void *p)
{
    if (!p) return;
    if (a->free) a->free(p, a->user);
    else TR_FREE(p);
}

/* Zero means default: the documented default replaces a zero field. */
#define tr__def(v, d) ((v) ? (v) : (d))

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
typedef struct tr__vec3 { float x, y, z; } tr__vec3;

TR__FN tr__vec3 tr__v3(float x, float y, float z) { tr__vec3 r; r.x = x; r.y = y; r.z = z; return r; }
TR__FN tr__vec3 tr__v3_load(const float *p) { return tr__v3(p[0], p[1], p[2]); }
TR__FN tr__vec3 tr__add(tr__vec3 a, tr__vec3 b) { return tr__v3(a.x + b.x, a.y + b.y, a.z + b.z); }
TR__FN tr__vec3 tr__sub(tr__vec3 a, tr__vec3 b) { return tr__v3(a.x - b.x, a.y - b.y, a.z - b.z); }
TR__FN tr__vec3 tr__scale(tr__vec3 a, float s) { return tr__v3(a.x * s, a.y * s, a.z * s); }
TR__FN float tr__dot(tr__vec3 a, tr__vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
TR__FN tr__vec3 tr__cross(tr__vec3 a, tr__vec3 b)
{
    return tr__v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
TR__FN float tr__length(tr__vec3 a) { return sqrtf(tr__dot(a, a)); }
TR__FN tr__vec3 tr__normalize(tr__vec3 a)
{
    float l = tr__length(a);
    return l > 0.0f ? tr__scale(a, 1.0f / l) : a;
}
TR__FN float tr__minf(float a, float b) { return a < b ? a : b; }
TR__FN float tr__maxf(float a, float b) { return a > b ? a : b; }
TR__FN int tr__finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

/* An orthonormal basis (t, b, n) around unit n (Duff et al. 2017, branchless). */
TR__FN void tr__basis(tr__vec3 n, tr__vec3 *t, tr__vec3 *b)
{
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    *t = tr__v3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = tr__v3(c, s + n.y * n.y * a, -n.y);
}

/* ======================================================================
   3. counter-based random numbers
   A stream is a pure function of (seed, stream id): jobs seed their own
   stream from (desc.seed, job index) and never share state, so results are
   bit-identical for any thread count.
   ---------------------------------------------------------------------- */
typedef struct tr__rng { uint64_t state; } tr__rng;

/* SplitMix64 finaliser (Steele, Lea, Flood 2014). */
TR__FN uint64_t tr__mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

TR__FN tr__rng tr__rng_stream(uint64_t seed, uint64_t stream)
{
    tr__rng r;
    r.state = tr__mix64(seed + 0x9E3779B97F4A7C15ull) ^ tr__mix64(stream * 0xD1B54A32D192ED03ull + 1u);
    return r;
}

TR__FN uint32_t tr__rng_u32(tr__rng *r)
{
    r->state += 0x9E3779B97F4A7C15ull;
    return (uint32_t)(tr__mix64(r->state) >> 32);
}

/* Uniform in [0, 1): 24 random bits, exactly representable. */
TR__FN float tr__rng_float(tr__rng *r)
{
    return (float)(tr__rng_u32(r) >> 8) * (1.0f / 16777216.0f);
}

/* ======================================================================
   4. BVH over triangles
   Binned SAH build (TR_BVH_BINS bins over centroid bounds), nodes flattened
   depth first (left child follows its parent), ordered traversal (nearer
   child box first), watertight ray/triangle test (Woop, Benthin, Wald 2013),
   any-hit for shadow rays. Triangles are copied into leaf order (9 floats and
   the caller's triangle index) because the traversal reads them in that order;
   nothing else of the caller's data is kept.
   ---------------------------------------------------------------------- */
#ifndef TR_BVH_BINS
#define TR_BVH_BINS 16
#endif
#define TR__BVH_LEAF_MAX 4    /* triangles per leaf */
#define TR__BVH_MAX_DEPTH 60  /* deeper nodes split at the median: bounds the traversal stack */
#define TR__BVH_STACK (TR__BVH_MAX_DEPTH + 34) /* + 32 median halvings of a uint32_t count */

typedef struct tr__bvh_node {
    float lo[3];
    uint32_t first;  /* leaf: first triangle; inner: index of the right child */
    float hi[3];
    uint32_t count;  /* leaf: triangle count (>0); inner: 0 */
} tr__bvh_node;

typedef struct tr__bvh_tri {
    float v0[3], v1[3], v2[3];
    uint32_t id;     /* the caller's triangle index */
} tr__bvh_tri;

typedef struct tr__bvh {
    tr__bvh_node *nodes;
    tr__bvh_tri *tris;
    uint32_t node_count, tri_count;
    uint32_t degenerate_count;  /* zero-area triangles skipped by the build */
} tr__bvh;

typedef struct tr__hit {
    float t;         /* distance along the ray in units of |dir| */
    float u, v;      /* barycentric weights of the triangle's 2nd and 3rd vertex */
    uint32_t tri;    /* the caller's triangle index; TR__NO_HIT when missed */
} tr__hit;
#define TR__NO_HIT 0xFFFFFFFFu

/* Caller's triangle soup: positions with a byte stride, 3 indices per triangle. */
typedef struct tr__mesh_view {
    const float *positions;
    size_t stride;             /* bytes between vertices; 0 = 3 floats */
    const uint32_t *indices;
    uint32_t tri_count;
} tr__mesh_view;

TR__FN const float *tr__vertex(const tr__mesh_view *m, uint32_t v)
{
    size_t stride = m->stride ? m->stride : 3 * sizeof(float);
    return (const float *)((const char *)m->positions + (size_t)v * stride);
}

typedef struct tr__bvh_ref {   /* build-time record of one triangle */
    float lo[3], hi[3], c[3];
    uint32_t tri;
} tr__bvh_ref;

typedef struct tr__bvh_bin { float lo[3], hi[3]; uint32_t count; } tr__bvh_bin;

TR__FN void tr__box_empty(float lo[3], float hi[3])
{
    lo[0] = lo[1] = lo[2] = FLT_MAX;
    hi[0] = hi[1] = hi[2] = -FLT_MAX;
}
TR__FN void tr__box_grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        lo[k] = tr__minf(lo[k], plo[k]);
        hi[k] = tr__maxf(hi[k], phi[k]);
    }
}
TR__FN float tr__box_area(const float lo[3], const float hi[3])
{
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    if (dx < 0.0f) return 0.0f;
    return dx * dy + dy * dz + dz * dx;
}

/* Chooses the binned-SAH split of refs[0..n); returns 0 when no split beats a
   leaf, else the axis (1-based in *axis) and the bin boundary in *split_bin. */
TR__FN int tr__bvh_find_split(const tr__bvh_ref *refs, uint32_t n, const float clo[3],
                              const float chi[3], int *axis, int *split_bin)
{
    float best = FLT_MAX, leaf_cost = (float)n;
    float node_lo[3], node_hi[3];
    int k, b, found = 0;
    uint32_t i;
    tr__box_empty(node_lo, node_hi);
    for (i = 0; i < n; i++) tr__box_grow(node_lo, node_hi, refs[i].lo, refs[i].hi);
    for (k = 0; k < 3; k++) {
        tr__bvh_bin bins[TR_BVH_BINS];
        float right_area[TR_BVH_BINS];
        uint32_t right_count[TR_BVH_BINS];
        float extent = chi[k] - clo[k], scale, lo[3], hi[3];
        uint32_t count;
        if (!(extent > 0.0f)) continue;
        scale = (float)TR_BVH_BINS / extent;
        for (b = 0; b < TR_BVH_BINS; b++) { tr__box_empty(bins[b].lo, bins[b].hi); bins[b].count = 0; }
        for (i = 0; i < n; i++) {
            int bin = (int)((refs[i].c[k] - clo[k]) * scale);
            if (bin >= TR_BVH_BINS) bin = TR_BVH_BINS - 1;
            if (bin < 0) bin = 0;
            bins[bin].count++;
            tr__box_grow(bins[bin].lo, bins[bin].hi, refs[i].lo, refs[i].hi);
        }
        /* sweep from the right, then from the left evaluating each boundary */
        tr__box_empty(lo, hi);
        count = 0;
        for (b = TR_BVH_BINS - 1; b > 0; b--) {
            tr__box_grow(lo, hi, bins[b].lo, bins[b].hi);
            count += bins[b].count;
            right_area[b] = tr__box_area(lo, hi);
            right_count[b] = count;
        }
        tr__box_empty(lo, hi);
        count = 0;
        for (b = 1; b < TR_BVH_BINS; b++) {
            float cost;
            tr__box_grow(lo, hi, bins[b - 1].lo, bins[b - 1].hi);
            count += bins[b - 1].count;
            if (count == 0 || right_count[b] == 0) continue;
            cost = 1.0f + (tr__box_area(lo, hi) * (float)count +
                           right_area[b] * (float)right_count[b]) / tr__box_area(node_lo, node_hi);
            if (cost < best) { best = cost; *axis = k; *split_bin = b; found = 1; }
        }
    }
    return found && (best < leaf_cost || n > TR__BVH_LEAF_MAX);
}

/* Partitions refs[0..n) so that the first part lies left of the chosen
   boundary. Returns the size of the left part (always in 1..n-1). */
TR__FN uint32_t tr__bvh_partition(tr__bvh_ref *refs, uint32_t n, const float clo[3],
                                  const float chi[3], int depth)
{
    int axis = 0, split_bin = 0;
    uint32_t i, j;
    if (depth < TR__BVH_MAX_DEPTH && tr__bvh_find_split(refs, n, clo, chi, &axis, &split_bin)) {
        float scale = (float)TR_BVH_BINS / (chi[axis] - clo[axis]);
        for (i = 0, j = n; i < j;) {
            int bin = (int)((refs[i].c[axis] - clo[axis]) * scale);
            if (bin >= TR_BVH_BINS) bin = TR_BVH_BINS - 1;
            if (bin < split_bin) i++;
            else { tr__bvh_ref t = refs[i]; refs[i] = refs[--j]; refs[j] = t; }
        }
        if (i > 0 && i < n) return i;
    }
    return n / 2; /* no useful SAH split (coincident centroids, depth cap): halve by count */
}

typedef struct tr__bvh_task {
    uint32_t parent, begin, end, depth;
    int is_right;    /* the parent learns a right child's index when it is popped */
} tr__bvh_task;

/* Copies the triangles into leaf order. */
TR__FN void tr__bvh_store_tris(tr__bvh *bvh, const tr__mesh_view *m, const tr__bvh_ref *refs)
{
    uint32_t i;
    for (i = 0; i < bvh->tri_count; i++) {
        tr__bvh_tri *t = &bvh->tris[i];
        uint32_t tri = refs[i].tri;
        memcpy(t->v0, tr__vertex(m, m->indices[3 * tri + 0]), sizeof t->v0);
        memcpy(t->v1, tr__vertex(m, m->indices[3 * tri + 1]), sizeof t->v1);
        memcpy(t->v2, tr__vertex(m, m->indices[3 * tri + 2]), sizeof t->v2);
        t->id = tri;
    }
}

/* Bounds of every non-degenerate triangle; counts the degenerate ones. */
TR__FN uint32_t tr__bvh_collect(tr__bvh *bvh, const tr__mesh_view *m, tr__bvh_ref *refs)
{
    uint32_t i, n = 0;
    for (i = 0; i < m->tri_count; i++) {
        const float *p0 = tr__vertex(m, m->indices[3 * i + 0]);
        const float *p1 = tr__vertex(m, m->indices[3 * i + 1]);
        const float *p2 = tr__vertex(m, m->indices[3 * i + 2]);
        tr__vec3 c = tr__cross(tr__sub(tr__v3_load(p1), tr__v3_load(p0)),
                               tr__sub(tr__v3_load(p2), tr__v3_load(p0)));
        int k;
        if (tr__dot(c, c) == 0.0f) { bvh->degenerate_count++; continue; }
        for (k = 0; k < 3; k++) {
            refs[n].lo[k] = tr__minf(p0[k], tr__minf(p1[k], p2[k]));
            refs[n].hi[k] = tr__maxf(p0[k], tr__maxf(p1[k], p2[k]));
            refs[n].c[k] = 0.5f * (refs[n].lo[k] + refs[n].hi[k]);
        }
        refs[n].tri = i;
        n++;
    }
    return n;
}

/* Builds the BVH of m's non-degenerate triangles. Indices must be in range and
   coordinates finite (validate first). Returns 0, or -1 when out of memory. */
TR__FN int tr__bvh_build(tr__bvh *bvh, const tr__mesh_view *m, const tr_allocator *a)
{
    tr__bvh_task stack[TR__BVH_STACK];
    tr__bvh_ref *refs;
    uint32_t i, n, top = 0;
    memset(bvh, 0, sizeof *bvh);
    refs = (tr__bvh_ref *)tr__alloc_array(a, m->tri_count, sizeof *refs);
    if (!refs) return -1;
    n = tr__bvh_collect(bvh, m, refs);
    bvh->nodes = (tr__bvh_node *)tr__alloc_array(a, n ? 2 * (size_t)n - 1 : 1, sizeof(tr__bvh_node));
    bvh->tris = (tr__bvh_tri *)tr__alloc_array(a, n, sizeof(tr__bvh_tri));
    if (!bvh->nodes || !bvh->tris) {
        tr__free(a, refs);
        tr__free(a, bvh->nodes);
        tr__free(a, bvh->tris);
        memset(bvh, 0, sizeof *bvh);
        return -1;
    }
    bvh->tri_count = n;
    if (n == 0) { /* an empty root leaf: every ray misses */
        tr__box_empty(bvh->nodes[0].lo, bvh->nodes[0].hi);
        bvh->nodes[0].first = bvh->nodes[0].count = 0;
        bvh->node_count = 1;
    } else {
        stack[top].parent = 0; stack[top].begin = 0; stack[top].end = n;
        stack[top].depth = 0; stack[top].is_right = 0; top++;
    }
    while (top) {
        tr__bvh_task t = stack[--top];
        uint32_t index = bvh->node_count++, count = t.end - t.begin;
        tr__bvh_node *node = &bvh->nodes[index];
        float clo[3], chi[3];
        if (t.is_right) bvh->nodes[t.parent].first = index;
        tr__box_empty(node->lo, node->hi);
        tr__box_empty(clo, chi);
        for (i = t.begin; i < t.end; i++) {
            tr__box_grow(node->lo, node->hi, refs[i].lo, refs[i].hi);
            tr__box_grow(clo, chi, refs[i].c, refs[i].c);
        }
        if (count <= TR__BVH_LEAF_MAX) {
            node->first = t.begin;
            node->count = count;
        } else {
            uint32_t mid = t.begin + tr__bvh_partition(refs + t.begin, count, clo, chi, (int)t.depth);
            node->count = 0;
            /* right pushed first so the left child is popped next: left = index + 1 */
            stack[top].parent = index; stack[top].begin = mid; stack[top].end = t.end;
            stack[top].depth = t.depth + 1; stack[top].is_right = 1; top++;
            stack[top].parent = index; stack[top].begin = t.begin; stack[top].end = mid;
            stack[top].depth = t.depth + 1; stack[top].is_right = 0; top++;
        }
    }
    tr__bvh_store_tris(bvh, m, refs);
    tr__free(a, refs);
    return 0;
}

TR__FN void tr__bvh_free(tr__bvh *bvh, const tr_allocator *a)
{
    tr__free(a, bvh->nodes);
    tr__free(a, bvh->tris);
    memset(bvh, 0, sizeof *bvh);
}

/* Per-ray constants of the watertight test and of the slab test. */
typedef struct tr__ray {
    float org[3], dir[3], inv[3];
    int kx, ky, kz;          /* dir[kz] has the largest magnitude */
    float sx, sy, sz;        /* shear that maps dir to +z */
} tr__ray;

TR__FN void tr__ray_setup(tr__ray *r, const float org[3], const float dir[3])
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
TR__FN float tr__ray_box(const tr__ray *r, const float lo[3], const float hi[3], float tmin, float tmax)
{
    int k;
    for (k = 0; k < 3; k++) {
        float t0 = (lo[k] - r->org[k]) * r->inv[k];
        float t1 = (hi[k] - r->org[k]) * r->inv[k];
        if (t0 > t1) { float t = t0; t0 = t1; t1 = t; }
        tmin = tr__maxf(tmin, t0);
        tmax = tr__minf(tmax, t1 * 1.00000024f);
    }
    return tmin <= tmax ? tmin : FLT_MAX;
}

/* Watertight ray/triangle test (Woop, Benthin, Wald 2013): edge functions in
   a sheared space where the ray is the +z axis; edges shared by two triangles
   are hit by exactly one of them. Double precision only when an edge function
   is exactly zero. Updates *hit when closer than hit->t. */
TR__FN int tr__ray_tri(const tr__ray *r, const tr__bvh_tri *tri, float tmin, tr__hit *hit)
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

/* Closest hit in (tmin, tmax). Returns 1 and fills *hit, else hit->tri = TR__NO_HIT. */
TR__FN int tr__bvh_intersect(const tr__bvh *bvh, const float org[3], const float dir[3],
                             float tmin, float tmax, tr__hit *hit)
{
    uint32_t stack[TR__BVH_STACK], top = 0, index = 0;
    tr__ray r;
    tr__ray_setup(&r, org, dir);
    hit->t = tmax;
    hit->u = hit->v = 0.0f;
    hit->tri = TR__NO_HIT;
    if (tr__ray_box(&r, bvh->nodes[0].lo, bvh->nodes[0].hi, tmin, tmax) == FLT_MAX) return 0;
    for (;;) {
        const tr__bvh_node *node = &bvh->nodes[index];
        if (node->count) {
            uint32_t i;
            for (i = node->first; i < node->first + node->count; i++)
                tr__ray_tri(&r, &bvh->tris[i], tmin, hit);
        } else {
            uint32_t left = index + 1, right = node->first;
            float tl = tr__ray_box(&r, bvh->nodes[left].lo, bvh->nodes[left].hi, tmin, hit->t);
            float tr = tr__ray_box(&r, bvh->nodes[right].lo, bvh->nodes[right].hi, tmin, hit->t);
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
    return hit->tri != TR__NO_HIT;
}

/* Any hit in (tmin, tmax): for shadow rays. */
TR__FN int tr__bvh_occluded(const tr__bvh *bvh, const float org[3], const float dir[3],
                            float tmin, float tmax)
{
    uint32_t stack[TR__BVH_STACK], top = 0, index = 0;
    tr__ray r;
    tr__hit hit;
    tr__ray_setup(&r, org, dir);
    hit.t = tmax;
    hit.tri = TR__NO_HIT;
    for (;;) {
        const tr__bvh_node *node = &bvh->nodes[index];
        if (tr__ray_box(&r, node->lo, node->hi, tmin, tmax) != FLT_MAX) {
            if (node->count) {
                uint32_t i;
                for (i = node->first; i < node->first + node->count; i++)
                    if (tr__ray_tri(&r, &bvh->tris[i], tmin, &hit)) return 1;
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
   6. Shirley-Chiu concentric map (Shirley and Chiu 1997)
   Square [0,1]^2 -> unit disk -> hemisphere around +z, preserving area: equal
   squares map to equal solid angles. The inverse maps a direction back to the
   square.
   ---------------------------------------------------------------------- */
#define TR__PI 3.14159265358979323846

TR__FN void tr__square_to_disk(float u, float v, float *dx, float *dy)
{
    float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f, r, phi;
    if (a == 0.0f && b == 0.0f) { *dx = *dy = 0.0f; return; }
    if (a * a > b * b) { r = a; phi = (float)(TR__PI / 4) * (b / a); }
    else { r = b; phi = (float)(TR__PI / 2) - (float)(TR__PI / 4) * (a / b); }
    *dx = r * cosf(phi);
    *dy = r * sinf(phi);
}

TR__FN void tr__disk_to_square(float dx, float dy, float *u, float *v)
{
    float r = sqrtf(dx * dx + dy * dy), phi = atan2f(dy, dx), a, b;
    if (phi < (float)(-TR__PI / 4)) phi += (float)(2 * TR__PI); /* phi in [-pi/4, 7pi/4) */
    if (phi < (float)(TR__PI / 4)) { a = r; b = phi * a / (float)(TR__PI / 4); }
    else if (phi < (float)(3 * TR__PI / 4)) { b = r; a = -(phi - (float)(TR__PI / 2)) * b / (float)(TR__PI / 4); }
    else if (phi < (float)(5 * TR__PI / 4)) { a = -r; b = (phi - (float)TR__PI) * a / (float)(TR__PI / 4); }
    else { b = -r; a = -(phi - (float)(3 * TR__PI / 2)) * b / (float)(TR__PI / 4); }
    *u = 0.5f * (a + 1.0f);
    *v = 0.5f * (b + 1.0f);
}

/* Square -> hemisphere (z >= 0): the disk point lifted by z = 1 - r^2. */
TR__FN tr__vec3 tr__square_to_hemisphere(float u, float v)
{
    float dx, dy, r2, s;
    tr__square_to_disk(u, v, &dx, &dy);
    r2 = dx * dx + dy * dy;
    s = sqrtf(tr__maxf(0.0f, 2.0f - r2));
    return tr__v3(dx * s, dy * s, 1.0f - r2);
}

/* Hemisphere -> square for a unit direction with d.z >= 0. */
TR__FN void tr__hemisphere_to_square(tr__vec3 d, float *u, float *v)
{
    float r2 = tr__maxf(0.0f, 1.0f - d.z), s = sqrtf(tr__maxf(0.0f, 2.0f - r2));
    if (s > 0.0f) tr__disk_to_square(d.x / s, d.y / s, u, v);
    else tr__disk_to_square(0.0f, 0.0f, u, v);
}

/* ======================================================================
   the tracer
   ---------------------------------------------------------------------- */
#define EX_TRACE_STATIC 0xFFFFFFFFu   /* instance index of the static scene */
#define EX_TRACE_MAX_INSTANCES 16
#define EX_TRACE_MAX_PASSES 16        /* glass surfaces a ray crosses before it counts as blocked */

typedef tr__rng ex_rng;
TR__FN ex_rng ex_rng_stream(uint64_t seed, uint64_t stream) { return tr__rng_stream(seed, stream); }
TR__FN float ex_rng_float(ex_rng *r) { return tr__rng_float(r); }

typedef struct ex_trace_hit {
    float t;
    uint32_t tri;        /* triangle of the static scene or of the instance mesh */
    uint32_t instance;   /* EX_TRACE_STATIC or the instance index */
    float u, v;          /* barycentric weights of the 2nd and 3rd vertex */
    float pos[3];        /* world-space hit point */
    float normal[3];     /* world-space unit geometric normal (front side) */
    int front;           /* the ray hit the front face */
} ex_trace_hit;

typedef struct ex__instance {
    tr__bvh bvh;
    const float *positions;
    const uint32_t *indices;
    float kd[3];
    float to_world[12], to_object[12];   /* 3x4 row-major affine maps */
} ex__instance;

typedef struct ex_tracer {
    const obj_scene *scene;
    tr__bvh bvh;
    float *tri_normal;          /* unit normal per static triangle */
    float *tri_area;
    uint32_t *emitters;         /* static triangles with emission */
    float *emitter_cdf;         /* by power (area * luminance of Ke) */
    uint32_t emitter_count;
    float emitter_power;
    float epsilon;              /* ray offset: 1e-5 of the scene's size */
    ex__instance instances[EX_TRACE_MAX_INSTANCES];
    int instance_count;
    int has_glass;              /* some material has tf > 0 */
    int has_sky;
    ex_sky sky;
} ex_tracer;

/* Cosine-weighted direction around +z: a concentric-disk point lifted to the
   hemisphere (Malley's method), pdf = cos / pi. */
static tr__vec3 ex__sample_cosine(ex_rng *r)
{
    float x, y;
    tr__square_to_disk(ex_rng_float(r), ex_rng_float(r), &x, &y);
    return tr__v3(x, y, sqrtf(tr__maxf(0.0f, 1.0f - x * x - y * y)));
}

static float ex__luminance(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

static void ex__affine_point(const float m[12], const float p[3], float out[3])
{
    int r;
    for (r = 0; r < 3; r++) out[r] = m[4 * r] * p[0] + m[4 * r + 1] * p[1] + m[4 * r + 2] * p[2] + m[4 * r + 3];
}

static void ex__affine_vector(const float m[12], const float v[3], float out[3])
{
    int r;
    for (r = 0; r < 3; r++) out[r] = m[4 * r] * v[0] + m[4 * r + 1] * v[1] + m[4 * r + 2] * v[2];
}

/* Inverse of an affine 3x4 map; false when singular. */
static int ex__affine_invert(const float m[12], float out[12])
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], i = m[10];
    double det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g), inv[9];
    int r;
    if (!(fabs(det) > 1e-20)) return 0;
    inv[0] = (e * i - f * h) / det; inv[1] = (c * h - b * i) / det; inv[2] = (b * f - c * e) / det;
    inv[3] = (f * g - d * i) / det; inv[4] = (a * i - c * g) / det; inv[5] = (c * d - a * f) / det;
    inv[6] = (d * h - e * g) / det; inv[7] = (b * g - a * h) / det; inv[8] = (a * e - b * d) / det;
    for (r = 0; r < 3; r++) {
        out[4 * r] = (float)inv[3 * r];
        out[4 * r + 1] = (float)inv[3 * r + 1];
        out[4 * r + 2] = (float)inv[3 * r + 2];
        out[4 * r + 3] = (float)-(inv[3 * r] * m[3] + inv[3 * r + 1] * m[7] + inv[3 * r + 2] * m[11]);
    }
    return 1;
}

static void ex__tracer_triangle_geometry(const float *positions, const uint32_t *tri, float n[3], float *area)
{
    tr__vec3 a = tr__v3_load(positions + 3 * (size_t)tri[0]);
    tr__vec3 c = tr__cross(tr__sub(tr__v3_load(positions + 3 * (size_t)tri[1]), a),
                           tr__sub(tr__v3_load(positions + 3 * (size_t)tri[2]), a));
    float l = tr__length(c);
    *area = 0.5f * l;
    n[0] = l > 0 ? c.x / l : 0;
    n[1] = l > 0 ? c.y / l : 0;
    n[2] = l > 0 ? c.z / l : 1;
}

EX_FN void ex_tracer_destroy(ex_tracer *t)
{
    tr_allocator a;
    int i;
    if (!t) return;
    memset(&a, 0, sizeof a);
    tr__bvh_free(&t->bvh, &a);
    for (i = 0; i < t->instance_count; i++) tr__bvh_free(&t->instances[i].bvh, &a);
    free(t->tri_normal);
    free(t->tri_area);
    free(t->emitters);
    free(t->emitter_cdf);
    free(t);
}

/* The static scene: its BVH, normals and emitter table. The scene must
   outlive the tracer. Returns NULL when out of memory. */
EX_FN ex_tracer *ex_tracer_create(const obj_scene *scene)
{
    tr_allocator a;
    tr__mesh_view view;
    ex_tracer *t = (ex_tracer *)calloc(1, sizeof *t);
    float lo[3], hi[3], sum = 0;
    uint32_t i;
    if (!t) return NULL;
    memset(&a, 0, sizeof a);
    t->scene = scene;
    t->tri_normal = (float *)malloc(sizeof(float) * 3 * (scene->tri_count + 1));
    t->tri_area = (float *)malloc(sizeof(float) * (scene->tri_count + 1));
    t->emitters = (uint32_t *)malloc(sizeof(uint32_t) * (scene->tri_count + 1));
    t->emitter_cdf = (float *)malloc(sizeof(float) * (scene->tri_count + 1));
    view.positions = scene->positions;
    view.stride = 0;
    view.indices = scene->tri_indices;
    view.tri_count = scene->tri_count;
    if (!t->tri_normal || !t->tri_area || !t->emitters || !t->emitter_cdf || tr__bvh_build(&t->bvh, &view, &a) != 0) {
        ex_tracer_destroy(t);
        return NULL;
    }
    for (i = 0; i < scene->tri_count; i++) {
        float power;
        ex__tracer_triangle_geometry(scene->positions, scene->tri_indices + 3 * (size_t)i, t->tri_normal + 3 * (size_t)i, &t->tri_area[i]);
        power = t->tri_area[i] * ex__luminance(scene->materials[scene->tri_material[i]].ke);
        if (power <= 0) continue;
        sum += power;
        t->emitters[t->emitter_count] = i;
        t->emitter_cdf[t->emitter_count++] = sum;
    }
    t->emitter_power = sum;
    for (i = 0; i < scene->material_count; i++)
        t->has_glass |= scene->materials[i].tf[0] > 0 || scene->materials[i].tf[1] > 0 || scene->materials[i].tf[2] > 0;
    t->epsilon = 1e-5f;
    if (obj_bounds(scene, lo, hi))
        t->epsilon = 1e-5f * sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    return t;
}

/* A moving object: its triangles (mesh must outlive the tracer) with one
   diffuse reflectance, placed by ex_tracer_set_transform (identity at first).
   Returns its index, or -1. */
EX_FN int ex_tracer_add_instance(ex_tracer *t, const obj_scene *mesh, const float kd[3])
{
    static const float identity[12] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0 };
    tr_allocator a;
    tr__mesh_view view;
    ex__instance *in;
    if (!t || !mesh || t->instance_count >= EX_TRACE_MAX_INSTANCES) return -1;
    memset(&a, 0, sizeof a);
    in = &t->instances[t->instance_count];
    view.positions = mesh->positions;
    view.stride = 0;
    view.indices = mesh->tri_indices;
    view.tri_count = mesh->tri_count;
    if (tr__bvh_build(&in->bvh, &view, &a) != 0) return -1;
    in->positions = mesh->positions;
    in->indices = mesh->tri_indices;
    memcpy(in->kd, kd, sizeof in->kd);
    memcpy(in->to_world, identity, sizeof identity);
    memcpy(in->to_object, identity, sizeof identity);
    return t->instance_count++;
}

/* Object-to-world map of an instance, 3x4 row-major. Returns -1 when singular. */
EX_FN int ex_tracer_set_transform(ex_tracer *t, int instance, const float m[12])
{
    float inv[12];
    if (!t || instance < 0 || instance >= t->instance_count || !ex__affine_invert(m, inv)) return -1;
    memcpy(t->instances[instance].to_world, m, sizeof inv);
    memcpy(t->instances[instance].to_object, inv, sizeof inv);
    return 0;
}

/* The environment seen by rays that leave the scene (scene_sky.h); NULL or
   a black constant sky turns it off. The map must outlive the tracer.
   Returns -1 when the sky is invalid (negative, NaN, bad map size). */
EX_FN int ex_tracer_set_sky(ex_tracer *t, const ex_sky *sky)
{
    if (!t || (sky && !ex_sky_valid(sky))) return -1;
    t->has_sky = sky && (sky->map || sky->radiance[0] > 0 || sky->radiance[1] > 0 || sky->radiance[2] > 0);
    if (sky) t->sky = *sky;
    return 0;
}

/* Fills the world-space point, normal and side of a hit. */
static void ex__tracer_finish_hit(const ex_tracer *t, const float org[3], const float dir[3], ex_trace_hit *h)
{
    const float *positions;
    const uint32_t *tri;
    float area, n[3];
    int k;
    if (h->instance == EX_TRACE_STATIC) {
        memcpy(n, t->tri_normal + 3 * (size_t)h->tri, sizeof n);
    } else {
        const ex__instance *in = &t->instances[h->instance];
        const float *m = in->to_object; /* normals map by the inverse transpose */
        float no[3];
        positions = in->positions;
        tri = in->indices + 3 * (size_t)h->tri;
        ex__tracer_triangle_geometry(positions, tri, no, &area);
        for (k = 0; k < 3; k++) n[k] = m[k] * no[0] + m[4 + k] * no[1] + m[8 + k] * no[2];
        tr__vec3 nv = tr__normalize(tr__v3_load(n));
        n[0] = nv.x; n[1] = nv.y; n[2] = nv.z;
    }
    for (k = 0; k < 3; k++) h->pos[k] = org[k] + h->t * dir[k];
    h->front = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2] < 0;
    memcpy(h->normal, n, sizeof n);
}

/* Closest hit along org + t dir, t in (0, tmax), over the static scene and
   every instance. */
/* ex_tracer_intersect against the static scene and the first `instances`
   instances (all of them, or none for the static scene alone). */
static int ex__tracer_intersect(const ex_tracer *t, const float org[3], const float dir[3], float tmax, int instances,
                                ex_trace_hit *hit)
{
    tr__hit h;
    int i;
    hit->t = tmax;
    hit->tri = TR__NO_HIT;
    hit->instance = EX_TRACE_STATIC;
    if (tr__bvh_intersect(&t->bvh, org, dir, 0.0f, tmax, &h)) {
        hit->t = h.t; hit->tri = h.tri; hit->u = h.u; hit->v = h.v;
    }
    for (i = 0; i < instances; i++) {
        const ex__instance *in = &t->instances[i];
        float o[3], d[3];
        ex__affine_point(in->to_object, org, o);
        ex__affine_vector(in->to_object, dir, d); /* unnormalised: t stays a world distance */
        if (tr__bvh_intersect(&in->bvh, o, d, 0.0f, hit->t, &h)) {
            hit->t = h.t; hit->tri = h.tri; hit->u = h.u; hit->v = h.v;
            hit->instance = (uint32_t)i;
        }
    }
    if (hit->tri == TR__NO_HIT) return 0;
    ex__tracer_finish_hit(t, org, dir, hit);
    return 1;
}

EX_FN int ex_tracer_intersect(const ex_tracer *t, const float org[3], const float dir[3], float tmax,
                              ex_trace_hit *hit)
{
    return ex__tracer_intersect(t, org, dir, tmax, t->instance_count, hit);
}

EX_FN int ex_tracer_occluded(const ex_tracer *t, const float org[3], const float dir[3], float tmax)
{
    int i;
    if (tr__bvh_occluded(&t->bvh, org, dir, 0.0f, tmax)) return 1;
    for (i = 0; i < t->instance_count; i++) {
        float o[3], d[3];
        ex__affine_point(t->instances[i].to_object, org, o);
        ex__affine_vector(t->instances[i].to_object, dir, d);
        if (tr__bvh_occluded(&t->instances[i].bvh, o, d, 0.0f, tmax)) return 1;
    }
    return 0;
}

/* The transmittance of a hit's surface: glass of the static scene, else 0. */
static const float *ex__tracer_tf(const ex_tracer *t, const ex_trace_hit *h)
{
    static const float opaque[3] = { 0, 0, 0 };
    return h->instance == EX_TRACE_STATIC ? t->scene->materials[t->scene->tri_material[h->tri]].tf : opaque;
}

static int ex__passes(const float tf[3]) { return tf[0] > 0 || tf[1] > 0 || tf[2] > 0; }

/* Moves a ray's origin o (direction dir) just past the surface of its hit h,
   along the ray so that the ray stays the same line: to a distance epsilon
   behind the surface (the step capped at 100 epsilon for grazing rays).
   Returns the step in units of |dir|. */
static float ex__tracer_step_through(const ex_tracer *t, const ex_trace_hit *h, const float dir[3], float o[3])
{
    float cos_n = fabsf(h->normal[0] * dir[0] + h->normal[1] * dir[1] + h->normal[2] * dir[2]);
    float step = h->t + t->epsilon / tr__maxf(cos_n, 0.01f * tr__length(tr__v3_load(dir)));
    int k;
    for (k = 0; k < 3; k++) o[k] += step * dir[k];
    return step;
}

/* The first opaque surface along org + t dir, t in (0, tmax), seen through
   glass: every pane met on the way multiplies through (rgb, starting at 1)
   by its transmittance and the ray goes on straight past it; hit->t is the
   distance from org. Returns 1 with that surface in hit, or 0 when the ray
   leaves the scene (through: what the glass passes of the sky). The pane
   after EX_TRACE_MAX_PASSES crossed counts as opaque (it is the hit). */
static int ex__tracer_intersect_through(const ex_tracer *t, const float org[3], const float dir[3], float tmax,
                                        int instances, ex_trace_hit *hit, float through[3])
{
    float o[3], travelled = 0.0f;
    int pass, k;
    through[0] = through[1] = through[2] = 1.0f;
    memcpy(o, org, sizeof o);
    for (pass = 0;; pass++) {
        const float *tf;
        float step;
        if (!ex__tracer_intersect(t, o, dir, tmax, instances, hit)) return 0;
        tf = ex__tracer_tf(t, hit);
        if (!ex__passes(tf) || pass == EX_TRACE_MAX_PASSES) break;
        for (k = 0; k < 3; k++) through[k] *= tf[k];
        step = ex__tracer_step_through(t, hit, dir, o);
        travelled += step;
        tmax -= step;
        if (!(tmax > 0)) return 0;
    }
    hit->t += travelled;
    return 1;
}

EX_FN int ex_tracer_intersect_through(const ex_tracer *t, const float org[3], const float dir[3], float tmax,
                                      ex_trace_hit *hit, float through[3])
{
    return ex__tracer_intersect_through(t, org, dir, tmax, t->instance_count, hit, through);
}

/* ex_tracer_transmittance with the first `instances` instances in the way. */
static int ex__tracer_transmittance(const ex_tracer *t, const float org[3], const float dir[3], float tmax,
                                    int instances, float rgb[3])
{
    ex_trace_hit h;
    if (!t->has_glass) {
        rgb[0] = rgb[1] = rgb[2] = 1.0f;
        if (instances == t->instance_count ? !ex_tracer_occluded(t, org, dir, tmax)
                                           : !tr__bvh_occluded(&t->bvh, org, dir, 0.0f, tmax))
            return 1;
    } else if (!ex__tracer_intersect_through(t, org, dir, tmax, instances, &h, rgb)) {
        return 1;
    }
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    return 0;
}

/* What reaches org + tmax dir from org: rgb = the product of the
   transmittances of the glass crossed, 0 when something opaque is in the
   way (or more than EX_TRACE_MAX_PASSES panes). Returns whether any light
   gets through. Without glass in the scene, a shadow ray. */
EX_FN int ex_tracer_transmittance(const ex_tracer *t, const float org[3], const float dir[3], float tmax, float rgb[3])
{
    return ex__tracer_transmittance(t, org, dir, tmax, t->instance_count, rgb);
}

/* The same with the static scene alone in the way (the instances let
   everything through). */
EX_FN int ex_tracer_transmittance_static(const ex_tracer *t, const float org[3], const float dir[3], float tmax,
                                         float rgb[3])
{
    return ex__tracer_transmittance(t, org, dir, tmax, 0, rgb);
}

/* Material of a hit: reflectances and emission. */
static void ex__tracer_material(const ex_tracer *t, const ex_trace_hit *h, const float **kd,
                                const float **ks, float *ns, const float **ke)
{
    static const float black[3] = { 0, 0, 0 };
    if (h->instance != EX_TRACE_STATIC) {
        *kd = t->instances[h->instance].kd;
        *ks = *ke = black;
        *ns = 1;
    } else {
        const obj_material *m = &t->scene->materials[t->scene->tri_material[h->tri]];
        *kd = m->kd;
        *ks = m->ks;
        *ns = m->ns;
        *ke = m->ke;
    }
}

/* Direct light reflected at a hit towards -dir: one point on an emitter,
   chosen by power, with a shadow ray. */
static void ex__tracer_direct(const ex_tracer *t, const ex_trace_hit *h, const float dir[3], ex_rng *r, float rgb[3])
{
    const float *kd, *ks, *ke, *lke;
    float ns, pick = ex_rng_float(r) * t->emitter_power, su, sv, y[3], wi[3], d2, d, cos_x, cos_y, f, g, org[3], through[3];
    uint32_t lo = 0, hi, tri;
    const uint32_t *v;
    const float *p = t->scene->positions;
    int k;
    rgb[0] = rgb[1] = rgb[2] = 0;
    if (!t->emitter_count) return;
    hi = t->emitter_count - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (t->emitter_cdf[mid] <= pick) lo = mid + 1;
        else hi = mid;
    }
    tri = t->emitters[lo];
    v = t->scene->tri_indices + 3 * (size_t)tri;
    su = sqrtf(ex_rng_float(r));
    sv = ex_rng_float(r);
    for (k = 0; k < 3; k++)
        y[k] = (1 - su) * p[3 * v[0] + k] + su * (1 - sv) * p[3 * v[1] + k] + su * sv * p[3 * v[2] + k];
    /* the shadow ray leaves from the point pushed off its surface and stops
       just short of the light */
    for (k = 0; k < 3; k++) org[k] = h->pos[k] + t->epsilon * h->normal[k];
    for (k = 0; k < 3; k++) wi[k] = y[k] - org[k];
    d2 = wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2];
    if (!(d2 > 0)) return;
    d = sqrtf(d2);
    for (k = 0; k < 3; k++) wi[k] /= d;
    cos_x = wi[0] * h->normal[0] + wi[1] * h->normal[1] + wi[2] * h->normal[2];
    cos_y = -(wi[0] * t->tri_normal[3 * tri] + wi[1] * t->tri_normal[3 * tri + 1] + wi[2] * t->tri_normal[3 * tri + 2]);
    if (cos_x <= 0 || cos_y <= 0) return;
    if (!ex_tracer_transmittance(t, org, wi, d * (1.0f - 1e-4f) - t->epsilon, through)) return;
    ex__tracer_material(t, h, &kd, &ks, &ns, &ke);
    lke = t->scene->materials[t->scene->tri_material[tri]].ke;
    g = cos_x * cos_y / d2 * t->emitter_power / ex__luminance(lke); /* pdf_area = lum/power */
    {
        /* normalized Phong around the mirror direction of the viewer */
        float vn = -(dir[0] * h->normal[0] + dir[1] * h->normal[1] + dir[2] * h->normal[2]), c = 0;
        for (k = 0; k < 3; k++) c += (dir[k] + 2 * vn * h->normal[k]) * wi[k];
        f = c > 0 ? (ns + 2) / (float)(2 * TR__PI) * powf(c, ns) : 0;
    }
    for (k = 0; k < 3; k++) rgb[k] = lke[k] * (kd[k] / (float)TR__PI + ks[k] * f) * g;
    if (t->has_glass)
        for (k = 0; k < 3; k++) rgb[k] *= through[k];
}

/* Sky light reflected at a hit by its diffuse lobe: one cosine-distributed
   direction (weight f cos / pdf = kd), through the glass on its way out. */
static void ex__tracer_sky(const ex_tracer *t, const ex_trace_hit *h, const float kd[3], ex_rng *r, float rgb[3])
{
    tr__vec3 n = tr__v3_load(h->normal), tb, bb, s;
    float org[3], dir[3], through[3], sky[3];
    int k;
    rgb[0] = rgb[1] = rgb[2] = 0;
    tr__basis(n, &tb, &bb);
    s = ex__sample_cosine(r);
    s = tr__add(tr__add(tr__scale(tb, s.x), tr__scale(bb, s.y)), tr__scale(n, s.z));
    dir[0] = s.x; dir[1] = s.y; dir[2] = s.z;
    for (k = 0; k < 3; k++) org[k] = h->pos[k] + t->epsilon * h->normal[k];
    if (!ex_tracer_transmittance(t, org, dir, FLT_MAX, through)) return;
    ex_sky_radiance(&t->sky, dir, sky);
    for (k = 0; k < 3; k++) rgb[k] = kd[k] * through[k] * sky[k];
}

/* Whether the path goes straight on through glass at a hit (from the back
   side always, else chosen in proportion to tf against kd, or always when
   no bounce is left to take); scales throughput by what it chose. */
static int ex__tracer_pass_through(const float tf[3], const float kd[3], int front, int last, ex_rng *r,
                                   float throughput[3])
{
    float p = 1.0f, lt = ex__luminance(tf), ld = ex__luminance(kd);
    int k;
    if (front && !last) p = lt + ld > 0 ? lt / (lt + ld) : 1.0f;
    if (p < 1.0f && ex_rng_float(r) >= p) {
        for (k = 0; k < 3; k++) throughput[k] *= kd[k] / (1.0f - p);   /* the bounce */
        return 0;
    }
    for (k = 0; k < 3; k++) throughput[k] *= tf[k] / p;
    return 1;
}

/* Radiance towards the ray's origin: emission seen directly, direct light
   (emitters, and the sky when set), and `bounces` more cosine-sampled
   diffuse bounces (each with direct light); glass is crossed on the way.
   first (optional) receives the first hit; returns whether there was one. */
EX_FN int ex_tracer_shade(const ex_tracer *t, const float org[3], const float dir[3], int bounces,
                          ex_rng *r, float rgb[3], ex_trace_hit *first)
{
    float o[3], d[3], throughput[3] = { 1, 1, 1 };
    int depth = 0, passes = 0, k;
    memcpy(o, org, sizeof o);
    memcpy(d, dir, sizeof d);
    rgb[0] = rgb[1] = rgb[2] = 0;
    if (first) first->tri = TR__NO_HIT;
    while (depth <= bounces) {
        ex_trace_hit h;
        const float *kd, *ks, *ke, *tf;
        float ns, direct[3];
        tr__vec3 n, tb, bb, s;
        if (!ex_tracer_intersect(t, o, d, FLT_MAX, &h)) {
            if (depth == 0 && t->has_sky) {   /* the sky seen from the camera, maybe through glass */
                float sky[3];
                ex_sky_radiance(&t->sky, d, sky);
                for (k = 0; k < 3; k++) rgb[k] += throughput[k] * sky[k];
            }
            return depth > 0 || passes > 0;
        }
        if (depth == 0 && passes == 0 && first) *first = h;
        tf = ex__tracer_tf(t, &h);
        if (!h.front && !ex__passes(tf)) return 1;
        ex__tracer_material(t, &h, &kd, &ks, &ns, &ke);
        if (h.front) {
            if (depth == 0)
                for (k = 0; k < 3; k++) rgb[k] += throughput[k] * ke[k];
            ex__tracer_direct(t, &h, d, r, direct);
            for (k = 0; k < 3; k++) rgb[k] += throughput[k] * direct[k];
            if (t->has_sky) {
                ex__tracer_sky(t, &h, kd, r, direct);
                for (k = 0; k < 3; k++) rgb[k] += throughput[k] * direct[k];
            }
        }
        if (ex__passes(tf) && passes < EX_TRACE_MAX_PASSES) {
            if (ex__tracer_pass_through(tf, kd, h.front, depth == bounces, r, throughput)) {
                passes++;
                ex__tracer_step_through(t, &h, d, o);
                continue;
            }
        } else {   /* cosine-sampled continuation: weight f cos / pdf = kd */
            for (k = 0; k < 3; k++) throughput[k] *= kd[k];
        }
        if (!h.front) break;
        n = tr__v3_load(h.normal);
        tr__basis(n, &tb, &bb);
        s = ex__sample_cosine(r);
        s = tr__add(tr__add(tr__scale(tb, s.x), tr__scale(bb, s.y)), tr__scale(n, s.z));
        d[0] = s.x; d[1] = s.y; d[2] = s.z;
        for (k = 0; k < 3; k++) o[k] = h.pos[k] + t->epsilon * h.normal[k];
        depth++;
    }
    return 1;
}

#endif /* EXAMPLES_COMMON_TRACE_H */
