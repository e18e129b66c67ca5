/* raster.h - software rasterizer for the examples: triangles into a depth
   buffer, a triangle-ID buffer and a perspective-correct barycentric buffer
   (Hardt's online phase, section 3.4), tiled and parallel.

       ex_raster r;
       ex_raster_init(&r, 640, 480);
       r.pool = pool;                           // optional ex_pool, NULL = serial
       ex_raster_clear(&r);
       ex_raster_draw(&r, &camera, positions, indices, tri_count, 0);
       ex_raster_draw(&r, &camera, bunny_pos, bunny_idx, bunny_tris, tri_count);
       ... r.id[p] (EX_RASTER_EMPTY or id_base + triangle), r.bary[2p], r.bary[2p+1]
       // or both meshes in one pass: ex_raster_draw_meshes(&r, &camera, meshes, 2),
       // each ex_raster_mesh with its vertex_count (0: found from the indices)
       ex_raster_free(&r);

   A frame can instead leave the clear to its draw (ex_raster_clear_deferred:
   each tile job starts its tile empty), draw all its meshes in one pass
   (ex_raster_draw_meshes) and shade in the tile jobs (r.tile_done, called
   on each finished tile with the tile's own depth, id and barycentric
   buffers while they are in the cache); r.skip then spares the frame
   buffers nobody else reads.

   How a tile is drawn: each mesh vertex is taken to view space, tested
   against the clip planes and snapped to the screen once per draw (the
   walkthrough's vertices are shared by six triangles on average);
   triangles are set up from their corners in parallel batches and binned,
   batch by batch in parallel too, to the 64 x 64 tiles they overlap, in
   input order; each tile job draws
   its bin into a visibility buffer of its own (depth and the winning
   triangle per pixel; only depth is tested, as 1/z, and z divided out only
   where a triangle may win), then computes ids and barycentrics once per
   visible pixel, so overdraw costs a depth test and nothing more. The
   inner loops over a row's covered span are branchless, SIMD where the
   compiler can vectorize them; edge values step in doubles, exact for
   these integers. Tiles are independent and triangles keep input order in
   every tile, so frames are bit-identical for any thread count.

   The barycentric pair of a pixel holds the weights of the triangle's second
   and third vertex at the pixel centre (the first vertex gets 1 - u - v),
   interpolated perspective-correctly. Depth is the distance along the view
   axis.

   Exact coverage: vertices are snapped to 1/256 pixel and edge functions are
   evaluated in 64-bit integers with a tie rule equivalent to moving every
   pixel centre by an infinitesimal fixed offset (the top-left rule up to
   convention), so a pixel centre inside a mesh is covered by exactly one of
   its triangles: no cracks, no double coverage along shared edges or at shared
   vertices. Each row's covered span is found by solving the three edge
   inequalities for x in the same integers (the quotients stepped from row
   to row, no division per row), so only covered pixels are visited. ex_raster_count() counts coverage instead of depth testing, to
   check exactly that. Triangles are clipped against the near plane and a
   guard band in view space (clip points computed the same way for both
   triangles of a shared edge); one wholly beside the screen is dropped
   before its projection. Both faces are drawn (no culling). Only
   perspective cameras rasterize. */
#ifndef EXAMPLES_COMMON_RASTER_H
#define EXAMPLES_COMMON_RASTER_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "pool.h"

#define EX_RASTER_EMPTY 0xFFFFFFFFu
#define EX_RASTER_TILE 64            /* tile side in pixels: one parallel job per tile */
#define EX_RASTER_SUBPIXEL 256       /* fixed-point steps per pixel */
#define EX_RASTER_GUARD 16.0f        /* guard band, in half screen widths */

typedef struct ex_raster_tri {
    int64_t x[3], y[3];          /* snapped screen positions, 1/256 pixel */
    float inv_z[3];              /* 1 / view depth at each corner */
    float inv_area;              /* 1 / twice the snapped area, in (1/256 pixel)^2 */
    float u[3], v[3];            /* original barycentric weights at each corner */
    uint32_t id;
    int x0, y0, x1, y1;          /* pixel bounds, inclusive, inside the image */
} ex_raster_tri;

/* Triangles of one draw: xyz positions, 3 indices per triangle; their pixel
   ids are id_base + triangle index. vertex_count is the number of
   positions (a draw with an index at or past it fails), or 0: one more
   than the largest index, found by reading the indices. */
typedef struct ex_raster_mesh {
    const float *positions;
    const uint32_t *indices;
    uint32_t tri_count, id_base;
    uint32_t vertex_count;
} ex_raster_mesh;

/* A mesh vertex as every triangle that shares it sees it: in view space,
   which clip planes and sides of the screen it lies beyond, and, when it
   lies inside every clip plane, snapped to the screen. The setup computes
   each vertex once per draw instead of once per triangle corner. */
typedef struct ex__raster_vertex {
    float p[3];                  /* view space */
    float inv_z;                 /* 1 / p[2] (where snapped) */
    int64_t x, y;                /* snapped screen position, 1/256 pixel (where clip = 0) */
    unsigned clip;               /* bit k: outside clip plane k (ex__clip_distance) */
    unsigned side;               /* bits: beyond the widened screen's right, left, top, bottom (ex__raster_side) */
} ex__raster_vertex;

/* The vertices of one mesh, or the part of them one setup job transforms. */
typedef struct ex__raster_vertices {
    const ex_raster_mesh *mesh;
    ex__raster_vertex *v;        /* the mesh's vertex 0 */
    uint32_t count;              /* the mesh's vertex count */
    uint32_t first, end;         /* this job's vertices */
} ex__raster_vertices;

/* The snapped triangles of one batch of at most EX__RASTER_BATCH input
   triangles of one mesh: the setup's parallel jobs each fill one, in input
   order. */
typedef struct ex__raster_batch {
    ex_raster_tri *tris;
    uint32_t count, capacity;
    const ex_raster_mesh *mesh;  /* its input: triangles [first, end) of mesh */
    const ex__raster_vertices *vertices;   /* the mesh's transformed vertices */
    uint32_t first, end;
    int failed;                  /* out of memory, or an index past the vertices */
} ex__raster_batch;

/* A finished tile as ex_raster.tile_done sees it: its pixels [x0, x1) x
   [y0, y1) with their depth, id and barycentrics in the tile job's own
   buffers (in the cache), pixel (x, y) at index
   (y - y0) * EX_RASTER_TILE + (x - x0), twice that for bary. */
typedef struct ex_raster_tile {
    int x0, y0, x1, y1;
    const float *depth;
    const uint32_t *id;
    const float *bary;
} ex_raster_tile;

/* ex_raster.skip: frame buffers the draws leave unwritten */
#define EX_RASTER_SKIP_DEPTH 1
#define EX_RASTER_SKIP_ID 2
#define EX_RASTER_SKIP_BARY 4

typedef struct ex_raster {
    int width, height;
    float *depth;                /* view depth of the nearest surface; FLT_MAX where empty */
    uint32_t *id;
    float *bary;                 /* 2 per pixel */
    uint32_t *coverage;          /* per pixel hit count, filled by ex_raster_count */
    float near_plane;            /* default 1e-3 (scene units) */
    ex_pool *pool;               /* optional */
    /* scratch reused by every draw */
    ex__raster_batch *batches;
    uint32_t batch_count, batch_capacity;
    ex__raster_vertex *vertices;           /* every mesh's, in turn */
    size_t vertex_capacity;
    ex__raster_vertices *vertex_jobs;      /* one per mesh and EX__RASTER_BATCH vertices */
    uint32_t vertex_job_capacity;
    const ex_camera *camera;     /* the draw in progress (read by the setup jobs) */
    uint32_t *bin_start, *bin_items, bin_capacity;   /* items: batch << EX__RASTER_BATCH_BITS | index */
    uint32_t *bin_counts;        /* per batch and tile: its items, then their positions (ex__raster_bin) */
    size_t bin_counts_capacity;
    int bin_filling;
    int tiles_x, tiles_y;
    int counting;
    int clear_pending;           /* ex_raster_clear_deferred: the next draw's tile jobs clear their tiles */
    int coverage_used;           /* ex_raster_count ran since coverage was last zeroed */
    /* optional, set by the caller: run at the end of each tile job of every
       draw, on the finished tile; a shading pass fused with the raster
       while the tile's buffers are in the cache */
    void (*tile_done)(void *user, const ex_raster_tile *tile);
    void *tile_user;
    /* optional: EX_RASTER_SKIP_* of frame buffers the draws need not fill
       (memory traffic saved when tile_done is all that reads them). A draw
       with no clear before it starts from the frame buffers, so a skipping
       frame clears first (ex_raster_clear_deferred) and draws all its
       meshes in one ex_raster_draw_meshes. */
    int skip;
} ex_raster;

EX_FN void ex_raster_free(ex_raster *r)
{
    uint32_t i;
    if (!r) return;
    free(r->depth);
    free(r->id);
    free(r->bary);
    free(r->coverage);
    if (r->batches)
        for (i = 0; i < r->batch_capacity; i++) free(r->batches[i].tris);
    free(r->batches);
    free(r->vertices);
    free(r->vertex_jobs);
    free(r->bin_start);
    free(r->bin_items);
    free(r->bin_counts);
    memset(r, 0, sizeof *r);
}

EX_FN int ex_raster_init(ex_raster *r, int width, int height)
{
    size_t n;
    memset(r, 0, sizeof *r);
    if (width <= 0 || height <= 0 || width > (1 << 14) || height > (1 << 14)) return -1;
    n = (size_t)width * (size_t)height;
    r->width = width;
    r->height = height;
    r->near_plane = 1e-3f;
    r->tiles_x = (width + EX_RASTER_TILE - 1) / EX_RASTER_TILE;
    r->tiles_y = (height + EX_RASTER_TILE - 1) / EX_RASTER_TILE;
    r->depth = (float *)malloc(n * sizeof(float));
    r->id = (uint32_t *)malloc(n * sizeof(uint32_t));
    r->bary = (float *)malloc(2 * n * sizeof(float));
    r->coverage = (uint32_t *)calloc(n, sizeof(uint32_t));
    r->bin_start = (uint32_t *)malloc(((size_t)r->tiles_x * (size_t)r->tiles_y + 1) * sizeof(uint32_t));
    if (!r->depth || !r->id || !r->bary || !r->coverage || !r->bin_start) {
        ex_raster_free(r);
        return -1;
    }
    return 0;
}

/* Empties the pixels [x0, x1) x [y0, y1): depth, id, barycentrics, and
   the coverage counts when ex_raster_count has used them. */
static void ex__raster_clear_box(ex_raster *r, int x0, int y0, int x1, int y1)
{
    int x, y;
    for (y = y0; y < y1; y++) {
        size_t row = (size_t)y * (size_t)r->width;
        for (x = x0; x < x1; x++) {
            r->depth[row + (size_t)x] = FLT_MAX;
            r->id[row + (size_t)x] = EX_RASTER_EMPTY;
            r->bary[2 * (row + (size_t)x)] = r->bary[2 * (row + (size_t)x) + 1] = 0.0f;
        }
        if (r->coverage_used) memset(r->coverage + row + x0, 0, (size_t)(x1 - x0) * sizeof(uint32_t));
    }
}

/* Clears one row of tiles (a job of ex_raster_clear). */
static void ex__raster_clear_band(void *ctx, uint32_t band)
{
    ex_raster *r = (ex_raster *)ctx;
    int y0 = (int)band * EX_RASTER_TILE, y1 = y0 + EX_RASTER_TILE < r->height ? y0 + EX_RASTER_TILE : r->height;
    ex__raster_clear_box(r, 0, y0, r->width, y1);
}

static void ex__raster_clear_now(ex_raster *r)
{
    ex_pool_parallel_for(r->pool, ex__raster_clear_band, r, (uint32_t)r->tiles_y);
    r->coverage_used = 0;
    r->clear_pending = 0;
}

/* Empties every buffer, in parallel on the pool when there is one (16
   bytes per pixel, and the coverage counts after ex_raster_count). */
EX_FN void ex_raster_clear(ex_raster *r)
{
    ex__raster_clear_now(r);
}

/* The same, done by the next draw: each of its tile jobs clears its tile
   just before drawing into it, while the tile is in the cache (a frame then
   writes its buffers once instead of twice). Reading the buffers before a
   draw, or an empty draw, clears at once. */
EX_FN void ex_raster_clear_deferred(ex_raster *r)
{
    r->clear_pending = 1;
}

/* ---- clipping in view space ----------------------------------------------- */

typedef struct ex__clip_vertex { float p[3]; float u, v; } ex__clip_vertex;

/* Signed distance to a clip plane (inside >= 0). Planes: 0 near, 1-4 guard band. */
static inline float ex__clip_distance(const float p[3], int plane, float near_plane, float ax, float ay)
{
    switch (plane) {
    case 0: return p[2] - near_plane;
    case 1: return EX_RASTER_GUARD * ax * p[2] - p[0];
    case 2: return EX_RASTER_GUARD * ax * p[2] + p[0];
    case 3: return EX_RASTER_GUARD * ay * p[2] - p[1];
    default: return EX_RASTER_GUARD * ay * p[2] + p[1];
    }
}

/* The crossing point of segment a-b with the plane, computed from the
   endpoint that sorts first so that both triangles of a shared edge get the
   same point. */
static ex__clip_vertex ex__clip_cross(const ex__clip_vertex *a, float da, const ex__clip_vertex *b, float db)
{
    ex__clip_vertex out;
    float t;
    int k;
    if (a->p[0] > b->p[0] || (a->p[0] == b->p[0] && (a->p[1] > b->p[1] || (a->p[1] == b->p[1] && a->p[2] > b->p[2])))) {
        const ex__clip_vertex *tv = a;
        float td = da;
        a = b; da = db;
        b = tv; db = td;
    }
    t = da / (da - db);
    for (k = 0; k < 3; k++) out.p[k] = a->p[k] + t * (b->p[k] - a->p[k]);
    out.u = a->u + t * (b->u - a->u);
    out.v = a->v + t * (b->v - a->v);
    return out;
}

/* Which clip planes (bit k for plane k of ex__clip_distance) a point in
   view space lies outside. */
static inline unsigned ex__clip_outside(const float p[3], float near_plane, float ax, float ay)
{
    unsigned bits = 0;
    int plane;
    for (plane = 0; plane < 5; plane++) bits |= (unsigned)(ex__clip_distance(p, plane, near_plane, ax, ay) < 0) << plane;
    return bits;
}

/* Which sides of the screen widened by two pixels (sx = ax (1 + 4 / width),
   sy likewise) a point in view space lies beyond: right, left, top,
   bottom. A triangle needing no clipping whose corners all lie beyond one
   side projects at least two pixels outside the image, far more than the
   projection's rounding, so its box holds no pixel centre and it would be
   dropped after its projection; most of a level's triangles lie beside
   the view, and this spares their projection and snapping. */
static inline unsigned ex__raster_side(const float p[3], float sx, float sy)
{
    return (unsigned)(p[0] > sx * p[2]) | (unsigned)(p[0] < -sx * p[2]) << 1 | (unsigned)(p[1] > sy * p[2]) << 2 |
           (unsigned)(p[1] < -sy * p[2]) << 3;
}

/* Sutherland-Hodgman against the five planes; returns the vertex count.
   Most triangles lie wholly inside every plane or wholly outside one: they
   are answered before any pass (with what the passes would give). */
static int ex__clip_polygon(ex__clip_vertex *poly, int n, float near_plane, float ax, float ay)
{
    ex__clip_vertex tmp[16];
    int plane, crossed = 0;
    for (plane = 0; plane < 5; plane++) {
        int i, inside = 0;
        for (i = 0; i < n; i++) inside += ex__clip_distance(poly[i].p, plane, near_plane, ax, ay) >= 0;
        if (inside == 0) return 0;
        crossed |= inside < n;
    }
    if (!crossed) return n;
    for (plane = 0; plane < 5 && n > 0; plane++) {
        int i, m = 0;
        for (i = 0; i < n; i++) {
            const ex__clip_vertex *a = &poly[i], *b = &poly[(i + 1) % n];
            float da = ex__clip_distance(a->p, plane, near_plane, ax, ay);
            float db = ex__clip_distance(b->p, plane, near_plane, ax, ay);
            if (da >= 0) tmp[m++] = *a;
            if ((da >= 0) != (db >= 0)) tmp[m++] = ex__clip_cross(a, da, b, db);
        }
        memcpy(poly, tmp, (size_t)m * sizeof *poly);
        n = m;
    }
    return n;
}

/* ---- setup and binning ---------------------------------------------------- */

#define EX__RASTER_NONE 0xFFFFFFFFu  /* no triangle: not a position in the bins */
#define EX__RASTER_BATCH 1024u      /* input triangles per setup job */
#define EX__RASTER_BATCH_BITS 13     /* a batch holds at most 6 * 1024 < 2^13 triangles (clipping
                                        by 5 planes leaves at most 8 corners: 6 triangles) */

static int ex__raster_reserve(ex__raster_batch *batch, uint32_t tris)
{
    if (tris > batch->capacity) {
        uint32_t cap = batch->capacity ? batch->capacity : 1024;
        ex_raster_tri *p;
        while (cap < tris) cap *= 2;
        p = (ex_raster_tri *)realloc(batch->tris, (size_t)cap * sizeof *p);
        if (!p) return -1;
        batch->tris = p;
        batch->capacity = cap;
    }
    return 0;
}

/* A point in view space snapped to the screen: 1/256 pixel, and 1 / depth. */
static inline void ex__raster_snap(const ex_raster *r, const float p[3], int64_t *x, int64_t *y, float *inv_z)
{
    const ex_camera *c = r->camera;
    float aspect = (float)r->width / (float)r->height, z = p[2];
    float sx = (p[0] / (z * c->tan_half * aspect) + 1.0f) * 0.5f * (float)r->width;
    float sy = (1.0f - p[1] / (z * c->tan_half)) * 0.5f * (float)r->height;
    *x = (int64_t)floor((double)sx * EX_RASTER_SUBPIXEL + 0.5);
    *y = (int64_t)floor((double)sy * EX_RASTER_SUBPIXEL + 0.5);
    *inv_z = 1.0f / z;
}

/* Appends the snapped triangle at batch->tris[batch->count] (corners,
   1 / depth and weights filled in) when it covers any pixel centre's
   bounding box: turned to positive area, boxed, given its id. */
static void ex__raster_finish(const ex_raster *r, ex__raster_batch *batch, uint32_t id)
{
    ex_raster_tri *t = &batch->tris[batch->count];
    int64_t area, lo_x, hi_x, lo_y, hi_y;
    int k;
    area = (t->x[1] - t->x[0]) * (t->y[2] - t->y[0]) - (t->y[1] - t->y[0]) * (t->x[2] - t->x[0]);
    if (area == 0) return;
    if (area < 0) { /* make the edge functions positive inside */
        int64_t tx = t->x[1], ty = t->y[1];
        float tz = t->inv_z[1], tu = t->u[1], tv = t->v[1];
        t->x[1] = t->x[2]; t->y[1] = t->y[2]; t->inv_z[1] = t->inv_z[2]; t->u[1] = t->u[2]; t->v[1] = t->v[2];
        t->x[2] = tx; t->y[2] = ty; t->inv_z[2] = tz; t->u[2] = tu; t->v[2] = tv;
    }
    lo_x = t->x[0]; hi_x = t->x[0]; lo_y = t->y[0]; hi_y = t->y[0];
    for (k = 1; k < 3; k++) {
        if (t->x[k] < lo_x) lo_x = t->x[k];
        if (t->x[k] > hi_x) hi_x = t->x[k];
        if (t->y[k] < lo_y) lo_y = t->y[k];
        if (t->y[k] > hi_y) hi_y = t->y[k];
    }
    /* pixels whose centre (x + 1/2) lies in the box */
    lo_x = (lo_x - EX_RASTER_SUBPIXEL / 2 + EX_RASTER_SUBPIXEL - 1) / EX_RASTER_SUBPIXEL;
    lo_y = (lo_y - EX_RASTER_SUBPIXEL / 2 + EX_RASTER_SUBPIXEL - 1) / EX_RASTER_SUBPIXEL;
    hi_x = (hi_x - EX_RASTER_SUBPIXEL / 2) >= 0 ? (hi_x - EX_RASTER_SUBPIXEL / 2) / EX_RASTER_SUBPIXEL : -1;
    hi_y = (hi_y - EX_RASTER_SUBPIXEL / 2) >= 0 ? (hi_y - EX_RASTER_SUBPIXEL / 2) / EX_RASTER_SUBPIXEL : -1;
    if (lo_x < 0) lo_x = 0;
    if (lo_y < 0) lo_y = 0;
    if (hi_x > r->width - 1) hi_x = r->width - 1;
    if (hi_y > r->height - 1) hi_y = r->height - 1;
    if (lo_x > hi_x || lo_y > hi_y) return;
    /* edge 0 (vertex 1 to 2) at vertex 0: twice the area, positive */
    t->inv_area = 1.0f / (float)((t->x[2] - t->x[1]) * (t->y[0] - t->y[1]) - (t->y[2] - t->y[1]) * (t->x[0] - t->x[1]));
    t->x0 = (int)lo_x; t->x1 = (int)hi_x;
    t->y0 = (int)lo_y; t->y1 = (int)hi_y;
    t->id = id;
    batch->count++;
}

/* Snaps one clipped triangle to the screen and appends it when it covers any
   pixel centre's bounding box. */
static void ex__raster_emit(const ex_raster *r, ex__raster_batch *batch, const ex__clip_vertex *a,
                            const ex__clip_vertex *b, const ex__clip_vertex *d, uint32_t id)
{
    ex_raster_tri *t = &batch->tris[batch->count];
    const ex__clip_vertex *cv[3];
    int k;
    cv[0] = a; cv[1] = b; cv[2] = d;
    for (k = 0; k < 3; k++) {
        ex__raster_snap(r, cv[k]->p, &t->x[k], &t->y[k], &t->inv_z[k]);
        t->u[k] = cv[k]->u;
        t->v[k] = cv[k]->v;
    }
    ex__raster_finish(r, batch, id);
}

/* One vertex job: its vertices into view space, their clip planes and
   screen sides, and those inside every clip plane snapped. */
static void ex__raster_vertex_job(void *ctx, uint32_t index)
{
    ex_raster *r = (ex_raster *)ctx;
    const ex_camera *c = r->camera;
    const ex__raster_vertices *job = &r->vertex_jobs[index];
    float aspect = (float)r->width / (float)r->height, ax = c->tan_half * aspect, ay = c->tan_half;
    float sx = ax * (1.0f + 4.0f / (float)r->width), sy = ay * (1.0f + 4.0f / (float)r->height);
    uint32_t i;
    for (i = job->first; i < job->end; i++) {
        const float *p = job->mesh->positions + 3 * (size_t)i;
        ex__raster_vertex *v = &job->v[i];
        float d[3];
        d[0] = p[0] - c->eye[0];
        d[1] = p[1] - c->eye[1];
        d[2] = p[2] - c->eye[2];
        v->p[0] = ex__dot(d, c->right);
        v->p[1] = ex__dot(d, c->up);
        v->p[2] = ex__dot(d, c->forward);
        v->clip = ex__clip_outside(v->p, r->near_plane, ax, ay);
        v->side = ex__raster_side(v->p, sx, sy);
        if (v->clip == 0) ex__raster_snap(r, v->p, &v->x, &v->y, &v->inv_z);
    }
}

/* One setup job: the batch's input triangles into r->batches[index],
   clipped and snapped. A triangle outside one clip plane is dropped, one
   inside them all takes its corners' snapped positions (or is dropped
   beside the screen), the others are clipped. */
static void ex__raster_setup_job(void *ctx, uint32_t index)
{
    ex_raster *r = (ex_raster *)ctx;
    const ex_camera *c = r->camera;
    ex__raster_batch *batch = &r->batches[index];
    const ex_raster_mesh *mesh = batch->mesh;
    const ex__raster_vertex *vertices = batch->vertices->v;
    uint32_t vertex_count = batch->vertices->count, i;
    float aspect = (float)r->width / (float)r->height, ax = c->tan_half * aspect, ay = c->tan_half;
    batch->count = 0;
    batch->failed = 0;
    for (i = batch->first; i < batch->end; i++) {
        const uint32_t *corner = mesh->indices + 3 * (size_t)i;
        const ex__raster_vertex *v[3];
        int k, n;
        if (corner[0] >= vertex_count || corner[1] >= vertex_count || corner[2] >= vertex_count ||
            ex__raster_reserve(batch, batch->count + 6) != 0) {
            batch->failed = 1;
            return;
        }
        for (k = 0; k < 3; k++) v[k] = &vertices[corner[k]];
        if (v[0]->clip & v[1]->clip & v[2]->clip) continue;        /* outside one plane */
        if ((v[0]->clip | v[1]->clip | v[2]->clip) == 0) {         /* nothing to clip */
            ex_raster_tri *t = &batch->tris[batch->count];
            if (v[0]->side & v[1]->side & v[2]->side) continue;    /* beside the screen */
            for (k = 0; k < 3; k++) {
                t->x[k] = v[k]->x;
                t->y[k] = v[k]->y;
                t->inv_z[k] = v[k]->inv_z;
                t->u[k] = k == 1 ? 1.0f : 0.0f;
                t->v[k] = k == 2 ? 1.0f : 0.0f;
            }
            ex__raster_finish(r, batch, mesh->id_base + i);
        } else {
            ex__clip_vertex poly[16];
            for (k = 0; k < 3; k++) {
                memcpy(poly[k].p, v[k]->p, sizeof poly[k].p);
                poly[k].u = k == 1 ? 1.0f : 0.0f;
                poly[k].v = k == 2 ? 1.0f : 0.0f;
            }
            n = ex__clip_polygon(poly, 3, r->near_plane, ax, ay);
            for (k = 1; k + 1 < n; k++) ex__raster_emit(r, batch, &poly[0], &poly[k], &poly[k + 1], mesh->id_base + i);
        }
    }
}

/* A mesh's vertex count: as given, or one more than its largest index. */
static uint32_t ex__raster_vertex_count(const ex_raster_mesh *mesh)
{
    uint32_t n = 0, i;
    if (mesh->vertex_count > 0 || mesh->tri_count == 0) return mesh->vertex_count;
    for (i = 0; i < 3 * mesh->tri_count; i++)
        if (mesh->indices[i] >= n) n = mesh->indices[i] + 1;
    return n;
}

/* Lays out the vertex jobs (one per mesh and EX__RASTER_BATCH vertices) and
   room for every mesh's vertices; -1 when out of memory. */
static int ex__raster_plan_vertices(ex_raster *r, const ex_raster_mesh *meshes, uint32_t mesh_count, uint32_t *jobs)
{
    size_t total = 0;
    uint32_t m, i, count = 0;
    for (m = 0; m < mesh_count; m++) {
        uint32_t n = ex__raster_vertex_count(&meshes[m]);
        if (meshes[m].tri_count == 0) continue;
        total += n;
        count += n / EX__RASTER_BATCH + 1;   /* + 1: a mesh always has a job, its vertex count */
    }
    if (total > r->vertex_capacity) {
        ex__raster_vertex *p = (ex__raster_vertex *)realloc(r->vertices, total * sizeof *p);
        if (!p) return -1;
        r->vertices = p;
        r->vertex_capacity = total;
    }
    if (count > r->vertex_job_capacity) {
        ex__raster_vertices *p = (ex__raster_vertices *)realloc(r->vertex_jobs, (size_t)count * sizeof *p);
        if (!p) return -1;
        r->vertex_jobs = p;
        r->vertex_job_capacity = count;
    }
    for (m = 0, total = 0, count = 0; m < mesh_count; m++) {
        uint32_t n = ex__raster_vertex_count(&meshes[m]);
        if (meshes[m].tri_count == 0) continue;
        for (i = 0; i == 0 || i < n; i += EX__RASTER_BATCH, count++) {
            ex__raster_vertices *job = &r->vertex_jobs[count];
            job->mesh = &meshes[m];
            job->v = r->vertices + total;
            job->count = n;
            job->first = i;
            job->end = n - i > EX__RASTER_BATCH ? i + EX__RASTER_BATCH : n;
        }
        total += n;
    }
    *jobs = count;
    return 0;
}

/* Sets up the meshes' triangles in batches, in parallel on the pool, after
   their vertices; the batches keep input order (meshes in turn), so the
   result does not depend on the thread count. */
static int ex__raster_setup(ex_raster *r, const ex_camera *c, const ex_raster_mesh *meshes, uint32_t mesh_count)
{
    uint32_t batches = 0, jobs, i, m, b, j;
    for (m = 0; m < mesh_count; m++) {
        uint32_t n = meshes[m].tri_count / EX__RASTER_BATCH + (meshes[m].tri_count % EX__RASTER_BATCH != 0);
        if (n >= (1u << (32 - EX__RASTER_BATCH_BITS)) - batches) return -1;   /* bin items would overflow */
        batches += n;
    }
    if (batches > r->batch_capacity) {
        ex__raster_batch *p = (ex__raster_batch *)realloc(r->batches, (size_t)batches * sizeof *p);
        if (!p) return -1;
        memset(p + r->batch_capacity, 0, (size_t)(batches - r->batch_capacity) * sizeof *p);
        r->batches = p;
        r->batch_capacity = batches;
    }
    if (ex__raster_plan_vertices(r, meshes, mesh_count, &jobs) != 0) return -1;
    r->batch_count = batches;
    r->camera = c;
    for (m = 0, b = 0, j = 0; m < mesh_count; m++) {
        if (meshes[m].tri_count == 0) continue;
        for (i = 0; i < meshes[m].tri_count; i += EX__RASTER_BATCH, b++) {
            r->batches[b].mesh = &meshes[m];
            r->batches[b].vertices = &r->vertex_jobs[j];
            r->batches[b].first = i;
            r->batches[b].end = meshes[m].tri_count - i > EX__RASTER_BATCH ? i + EX__RASTER_BATCH : meshes[m].tri_count;
        }
        while (j < jobs && r->vertex_jobs[j].mesh == &meshes[m]) j++;
    }
    ex_pool_parallel_for(r->pool, ex__raster_vertex_job, r, jobs);
    ex_pool_parallel_for(r->pool, ex__raster_setup_job, r, batches);
    for (i = 0; i < batches; i++)
        if (r->batches[i].failed) return -1;
    return 0;
}

/* One binning job: batch `batch`'s triangles, in input order, and the
   tiles each overlaps. Counting (r->bin_filling 0), it counts them into
   its row of r->bin_counts (one count per tile); filling, those are its
   items' positions, and it stores each item (batch << EX__RASTER_BATCH_BITS
   | index) at the tile's position, counting on. */
static void ex__raster_bin_job(void *ctx, uint32_t batch)
{
    ex_raster *r = (ex_raster *)ctx;
    const ex__raster_batch *b = &r->batches[batch];
    size_t tiles = (size_t)r->tiles_x * (size_t)r->tiles_y;
    uint32_t *row = r->bin_counts + (size_t)batch * tiles, i;
    if (!r->bin_filling) memset(row, 0, tiles * sizeof(uint32_t));
    for (i = 0; i < b->count; i++) {
        const ex_raster_tri *t = &b->tris[i];
        int tx, ty;
        for (ty = t->y0 / EX_RASTER_TILE; ty <= t->y1 / EX_RASTER_TILE; ty++)
            for (tx = t->x0 / EX_RASTER_TILE; tx <= t->x1 / EX_RASTER_TILE; tx++) {
                size_t tile = (size_t)ty * (size_t)r->tiles_x + (size_t)tx;
                if (r->bin_filling) r->bin_items[row[tile]++] = batch << EX__RASTER_BATCH_BITS | i;
                else row[tile]++;
            }
    }
}

/* Buckets triangles per tile, in input order (so results do not depend on
   how tiles are scheduled), in parallel on the pool: every batch counts
   its triangles per tile, each tile's items are laid out batch after
   batch, and every batch stores its own. */
static int ex__raster_bin(ex_raster *r)
{
    size_t tiles = (size_t)r->tiles_x * (size_t)r->tiles_y, cells = (size_t)r->batch_count * tiles, tile;
    uint64_t total = 0;
    uint32_t batch;
    if (cells > r->bin_counts_capacity) {
        uint32_t *p = (uint32_t *)realloc(r->bin_counts, cells * sizeof(uint32_t));
        if (!p) return -1;
        r->bin_counts = p;
        r->bin_counts_capacity = cells;
    }
    r->bin_filling = 0;
    ex_pool_parallel_for(r->pool, ex__raster_bin_job, r, r->batch_count);
    for (tile = 0; tile < tiles; tile++) {   /* counts to positions */
        r->bin_start[tile] = (uint32_t)total;
        for (batch = 0; batch < r->batch_count; batch++) {
            uint32_t *count = r->bin_counts + (size_t)batch * tiles + tile, n = *count;
            *count = (uint32_t)total;
            total += n;
        }
        if (total >= EX__RASTER_NONE) return -1;   /* a position must not read as no winner */
    }
    r->bin_start[tiles] = (uint32_t)total;
    if (total > r->bin_capacity) {
        uint32_t *p = (uint32_t *)realloc(r->bin_items, (size_t)total * sizeof(uint32_t));
        if (!p) return -1;
        r->bin_items = p;
        r->bin_capacity = (uint32_t)total;
    }
    r->bin_filling = 1;
    ex_pool_parallel_for(r->pool, ex__raster_bin_job, r, r->batch_count);
    return 0;
}

/* ---- per tile --------------------------------------------------------- */

/* Whether an edge's on-line points belong to the triangle to its left: true
   for exactly one of an edge and its reverse, as if every pixel centre moved
   by an infinitesimal (-1, -eta). */
static int ex__edge_owns_ties(int64_t dx, int64_t dy) { return dy > 0 || (dy == 0 && dx < 0); }

/* Floor of a / b for b > 0, exact in 64-bit integers. */
static int64_t ex__floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

/* A triangle's edge functions over its pixels in one tile. Edge k goes from
   vertex k+1 to k+2; it is zero on that edge and positive at vertex k, so its
   value over the area, times inv_area, is vertex k's weight.

   A pixel at offset x from the row's first one is inside edge k when
   w(x) + bias > 0 with w(x) = row - step * x, i.e. step * x <= room with
   room = row + bias - 1: for step > 0 that bounds the span above by
   floor(room / step), for step < 0 below by -floor(room / -step), for
   step = 0 it holds on the whole row or nowhere. Row to row room grows by
   down, so the bound's quotient and remainder are stepped exactly in
   integers (a Bresenham walk: the quotient of down once, then an add and
   a carry per row) instead of dividing on every row. */
typedef struct ex__raster_edges {
    int64_t row[3];              /* values at the current row's first pixel centre */
    int64_t step[3];             /* decrease per pixel to the right */
    int64_t down[3];             /* increase per row down */
    int64_t quot[3], rem[3];     /* floor(room / |step|) and its remainder, in [0, |step|) */
    int64_t down_quot[3], down_rem[3];   /* the same for down */
    int64_t div[3];              /* |step|, or INT64_MAX (no carry ever) when step = 0 */
    int bias[3];                 /* tie rule (ex__edge_owns_ties) */
    int x0, y0, x1, y1;          /* the triangle's pixel box in the tile, inclusive */
} ex__raster_edges;

/* Starts triangle t's edges at the top-left pixel of its box within the
   tile's [tx0, tx1] x [ty0, ty1]; 0 when the boxes do not meet. */
static inline int ex__raster_edges_begin(const ex_raster_tri *t, int tx0, int ty0, int tx1, int ty1, ex__raster_edges *e)
{
    int64_t px0, py0;
    int k;
    e->x0 = t->x0 > tx0 ? t->x0 : tx0;
    e->x1 = t->x1 < tx1 ? t->x1 : tx1;
    e->y0 = t->y0 > ty0 ? t->y0 : ty0;
    e->y1 = t->y1 < ty1 ? t->y1 : ty1;
    if (e->x0 > e->x1 || e->y0 > e->y1) return 0;
    px0 = (int64_t)e->x0 * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
    py0 = (int64_t)e->y0 * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
    for (k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        int64_t dx = t->x[b] - t->x[a], dy = t->y[b] - t->y[a], div = dy < 0 ? -dy : dy;
        e->row[k] = dx * (py0 - t->y[a]) - dy * (px0 - t->x[a]);
        e->bias[k] = ex__edge_owns_ties(dx, dy);
        e->step[k] = dy * EX_RASTER_SUBPIXEL;
        e->down[k] = dx * EX_RASTER_SUBPIXEL;
        e->quot[k] = e->rem[k] = e->down_quot[k] = e->down_rem[k] = 0;
        e->div[k] = INT64_MAX;
        if (div != 0) {
            int64_t room = e->row[k] + e->bias[k] - 1;
            div *= EX_RASTER_SUBPIXEL;
            e->div[k] = div;
            e->quot[k] = ex__floor_div(room, div);
            e->rem[k] = room - e->quot[k] * div;
            e->down_quot[k] = ex__floor_div(e->down[k], div);
            e->down_rem[k] = e->down[k] - e->down_quot[k] * div;
        }
    }
    return 1;
}

/* The current row's covered pixels, as offsets [*lo, *hi] from e->x0 (empty
   when *lo > *hi): exactly the pixels whose three edge tests pass. */
static inline void ex__raster_edges_span(const ex__raster_edges *e, int64_t *lo, int64_t *hi)
{
    int k;
    *lo = 0;
    *hi = e->x1 - e->x0;
    for (k = 0; k < 3; k++) {
        if (e->step[k] > 0) {
            if (e->quot[k] < *hi) *hi = e->quot[k];
        } else if (e->step[k] < 0) {
            if (-e->quot[k] > *lo) *lo = -e->quot[k];
        } else if (e->row[k] + e->bias[k] - 1 < 0) {
            *hi = -1;   /* the whole row is outside this edge */
        }
    }
}

static inline void ex__raster_edges_next_row(ex__raster_edges *e)
{
    int k;
    for (k = 0; k < 3; k++) {
        int64_t rem = e->rem[k] + e->down_rem[k], carry = rem >= e->div[k];   /* branchless: a carry is a coin toss */
        e->row[k] += e->down[k];
        e->quot[k] += e->down_quot[k] + carry;
        e->rem[k] = rem - (e->div[k] & -carry);
    }
}

/* Counts triangle t's coverage of the tile's pixels (ex_raster_count). */
static void ex__raster_tri_count(ex_raster *r, const ex_raster_tri *t, int tx0, int ty0, int tx1, int ty1)
{
    ex__raster_edges e;
    int y;
    if (!ex__raster_edges_begin(t, tx0, ty0, tx1, ty1, &e)) return;
    for (y = e.y0; y <= e.y1; y++, ex__raster_edges_next_row(&e)) {
        uint32_t *row = r->coverage + (size_t)y * (size_t)r->width + (size_t)e.x0;
        int64_t lo, hi, x;
        ex__raster_edges_span(&e, &lo, &hi);
        for (x = lo; x <= hi; x++) row[x]++;
    }
}

#define EX__RASTER_TILE_PIXELS (EX_RASTER_TILE * EX_RASTER_TILE)

/* One tile's buffers, in the tile job's own memory (they stay in the
   core's cache): per pixel, the nearest triangle drawn so far in this pass
   (a visibility buffer). Only depth is tested while triangles are drawn;
   ids and barycentrics are computed afterwards, once per pixel, for the
   triangle that won, so overdraw costs a depth test and nothing more.
   Pixel (x, y) of the tile is index (y - y0) * EX_RASTER_TILE + (x - x0).
   The depth test runs over whole groups of EX__RASTER_LANES pixels (see
   ex__raster_tri_depth): its buffers have room for the last group. The
   groups are of 8 where the target has 8-lane float vectors (AVX), which
   the compiler then fills with no remainder loop; elsewhere of 1: measured
   at -O2 for plain x86-64 (SSE2), where the loop stays scalar, 8 made the
   frame 10% slower (the spare lanes' work done one by one). */
#if defined(__AVX__)
#define EX__RASTER_LANES 8
#else
#define EX__RASTER_LANES 1
#endif
#define EX__RASTER_DEPTH_PIXELS (EX__RASTER_TILE_PIXELS + EX__RASTER_LANES)
typedef struct ex__raster_local {
    float inv_z[EX__RASTER_DEPTH_PIXELS];   /* 1 / depth of this pass's winner; 0 where none */
    float z[EX__RASTER_DEPTH_PIXELS];       /* depth: the winner's, else the frame's (FLT_MAX cleared) */
    uint32_t ref[EX__RASTER_DEPTH_PIXELS];  /* the winner's position in r->bin_items, EX__RASTER_NONE where none */
    uint32_t id[EX__RASTER_TILE_PIXELS];   /* resolved: as the frame's id and bary */
    float bary[2 * EX__RASTER_TILE_PIXELS];
} ex__raster_local;

static const ex_raster_tri *ex__raster_item(const ex_raster *r, uint32_t position)
{
    uint32_t item = r->bin_items[position];
    return &r->batches[item >> EX__RASTER_BATCH_BITS].tris[item & ((1u << EX__RASTER_BATCH_BITS) - 1u)];
}

/* The tile's starting point: empty when the frame is to be cleared, else
   the frame's pixels. */
static void ex__raster_local_begin(const ex_raster *r, ex__raster_local *L, int x0, int y0, int x1, int y1)
{
    int x, y, n = x1 - x0 + 1;
    memset(L->inv_z, 0, sizeof L->inv_z);
    memset(L->ref, 0xFF, sizeof L->ref);
    for (x = EX__RASTER_TILE_PIXELS; x < EX__RASTER_DEPTH_PIXELS; x++) L->z[x] = FLT_MAX;   /* read, never taken */
    for (y = y0; y <= y1; y++) {
        int q = (y - y0) * EX_RASTER_TILE;
        size_t p = (size_t)y * (size_t)r->width + (size_t)x0;
        if (r->clear_pending) {   /* ids and barycentrics: ex__raster_resolve writes every pixel */
            for (x = 0; x < n; x++) L->z[q + x] = FLT_MAX;
        } else {
            memcpy(L->z + q, r->depth + p, (size_t)n * sizeof(float));
            memcpy(L->id + q, r->id + p, (size_t)n * sizeof(uint32_t));
            memcpy(L->bary + 2 * q, r->bary + 2 * p, 2 * (size_t)n * sizeof(float));
        }
    }
}

/* Depth-tests triangle t (bin position ref) on its covered pixels of the
   tile. A pixel takes it when its depth z = 1 / sum(a) is nearer than the
   pixel's and, where the sums (1/z) tie or fall, z cannot be nearer: the
   test on both gives the same pixels as testing z alone, and the branchless
   loop over a row's span runs as SIMD lanes where the compiler can. It
   runs over whole groups of EX__RASTER_LANES pixels, the lanes past the
   span writing back what they read (the rest of the row, the next row,
   the buffers' spare room): a span is about 9 pixels at 1920x1080, and a
   remainder done one pixel at a time, with a branch per pixel, took a
   third of the test's time. The edge values step in doubles: they are
   integers below 2^53, exact there, and rounded to float as the 64-bit
   integers would be. */
static void ex__raster_tri_depth(ex__raster_local *L, const ex_raster_tri *t, uint32_t ref, int tx0, int ty0,
                                 int tx1, int ty1)
{
    ex__raster_edges e;
    const float area = t->inv_area, z0 = t->inv_z[0], z1 = t->inv_z[1], z2 = t->inv_z[2];
    int y;
    if (!ex__raster_edges_begin(t, tx0, ty0, tx1, ty1, &e)) return;
    for (y = e.y0; y <= e.y1; y++, ex__raster_edges_next_row(&e)) {
        int q = (y - ty0) * EX_RASTER_TILE + (e.x0 - tx0);
        int64_t lo, hi;
        int i, n, groups;
        double w0, w1, w2, d0 = (double)e.step[0], d1 = (double)e.step[1], d2 = (double)e.step[2];
        float *inv_z, *z;
        uint32_t *refs;
        ex__raster_edges_span(&e, &lo, &hi);
        if (lo > hi) continue;
        n = (int)(hi - lo + 1);
        inv_z = L->inv_z + q + lo;
        z = L->z + q + lo;
        refs = L->ref + q + lo;
        w0 = (double)(e.row[0] - e.step[0] * lo);
        w1 = (double)(e.row[1] - e.step[1] * lo);
        w2 = (double)(e.row[2] - e.step[2] * lo);
        groups = (n + EX__RASTER_LANES - 1) & ~(EX__RASTER_LANES - 1);
        for (i = 0; i < groups; i++) {
            double x = (double)i;
            float a0 = (float)(w0 - d0 * x) * area * z0;
            float a1 = (float)(w1 - d1 * x) * area * z1;
            float a2 = (float)(w2 - d2 * x) * area * z2;
            float sum = a0 + a1 + a2, depth = 1.0f / sum;
            int win = (i < n) & (sum > inv_z[i]) & (depth < z[i]);
            inv_z[i] = win ? sum : inv_z[i];
            z[i] = win ? depth : z[i];
            refs[i] = win ? ref : refs[i];
        }
    }
}

/* The winners' ids and perspective-correct barycentrics (the vertex weights
   a[k] z, blending the corners' original weights), a run of pixels of one
   triangle in a row at a time: its edge values start exact at the run's
   first pixel and step in doubles (as in ex__raster_tri_depth), so every
   pixel gets the bits of its own exact 64-bit edge values. */
static void ex__raster_resolve(const ex_raster *r, ex__raster_local *L, int x0, int y0, int x1, int y1)
{
    int x, y, n = x1 - x0 + 1;
    for (y = y0; y <= y1; y++) {
        const int q = (y - y0) * EX_RASTER_TILE;
        const uint32_t *refs = L->ref + q;
        for (x = 0; x < n;) {
            const ex_raster_tri *t;
            const float *z;
            float *bary, area, iz[3], u[3], v[3];
            double w[3], d[3];
            int64_t px, py;
            int end = x + 1, i, k;
            if (refs[x] == EX__RASTER_NONE) {   /* not drawn: the frame's pixel, or empty when cleared */
                if (r->clear_pending) {
                    L->id[q + x] = EX_RASTER_EMPTY;
                    L->bary[2 * (q + x)] = L->bary[2 * (q + x) + 1] = 0.0f;
                }
                x++;
                continue;
            }
            while (end < n && refs[end] == refs[x]) end++;
            t = ex__raster_item(r, refs[x]);
            px = (int64_t)(x0 + x) * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
            py = (int64_t)y * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
            for (k = 0; k < 3; k++) {
                int a = (k + 1) % 3, b = (k + 2) % 3;
                w[k] = (double)((t->x[b] - t->x[a]) * (py - t->y[a]) - (t->y[b] - t->y[a]) * (px - t->x[a]));
                d[k] = (double)((t->y[b] - t->y[a]) * EX_RASTER_SUBPIXEL);
                iz[k] = t->inv_z[k];
                u[k] = t->u[k];
                v[k] = t->v[k];
            }
            area = t->inv_area;
            z = L->z + q + x;
            bary = L->bary + 2 * (q + x);
            for (i = 0; i < end - x; i++) {
                double s = (double)i;
                float a0 = (float)(w[0] - d[0] * s) * area * iz[0];
                float a1 = (float)(w[1] - d[1] * s) * area * iz[1];
                float a2 = (float)(w[2] - d[2] * s) * area * iz[2];
                bary[2 * i] = (a0 * u[0] + a1 * u[1] + a2 * u[2]) * z[i];
                bary[2 * i + 1] = (a0 * v[0] + a1 * v[1] + a2 * v[2]) * z[i];
            }
            for (i = x; i < end; i++) L->id[q + i] = t->id;
            x = end;
        }
    }
}

/* Copies the tile to the frame buffers r->skip does not name. */
static void ex__raster_store(ex_raster *r, const ex__raster_local *L, int x0, int y0, int x1, int y1)
{
    int y, n = x1 - x0 + 1;
    for (y = y0; y <= y1; y++) {
        int q = (y - y0) * EX_RASTER_TILE;
        size_t p = (size_t)y * (size_t)r->width + (size_t)x0;
        if (!(r->skip & EX_RASTER_SKIP_DEPTH)) memcpy(r->depth + p, L->z + q, (size_t)n * sizeof(float));
        if (!(r->skip & EX_RASTER_SKIP_ID)) memcpy(r->id + p, L->id + q, (size_t)n * sizeof(uint32_t));
        if (!(r->skip & EX_RASTER_SKIP_BARY)) memcpy(r->bary + 2 * p, L->bary + 2 * q, 2 * (size_t)n * sizeof(float));
    }
}

/* Draws the tile's binned triangles, in input order, and hands the tile on. */
static void ex__raster_tile_job(void *ctx, uint32_t tile)
{
    ex_raster *r = (ex_raster *)ctx;
    int tx = (int)tile % r->tiles_x, ty = (int)tile / r->tiles_x;
    int x0 = tx * EX_RASTER_TILE, y0 = ty * EX_RASTER_TILE;
    int x1 = x0 + EX_RASTER_TILE - 1, y1 = y0 + EX_RASTER_TILE - 1;
    uint32_t i;
    ex__raster_local L;
    ex_raster_tile done;
    if (x1 >= r->width) x1 = r->width - 1;
    if (y1 >= r->height) y1 = r->height - 1;
    if (r->counting) {
        if (r->clear_pending) ex__raster_clear_box(r, x0, y0, x1 + 1, y1 + 1);
        for (i = r->bin_start[tile]; i < r->bin_start[tile + 1]; i++)
            ex__raster_tri_count(r, ex__raster_item(r, i), x0, y0, x1, y1);
        return;
    }
    ex__raster_local_begin(r, &L, x0, y0, x1, y1);
    for (i = r->bin_start[tile]; i < r->bin_start[tile + 1]; i++)
        ex__raster_tri_depth(&L, ex__raster_item(r, i), i, x0, y0, x1, y1);
    ex__raster_resolve(r, &L, x0, y0, x1, y1);
    ex__raster_store(r, &L, x0, y0, x1, y1);
    if (r->tile_done) {
        done.x0 = x0;
        done.y0 = y0;
        done.x1 = x1 + 1;
        done.y1 = y1 + 1;
        done.depth = L.z;
        done.id = L.id;
        done.bary = L.bary;
        r->tile_done(r->tile_user, &done);
    }
}

static int ex__raster_run(ex_raster *r, const ex_camera *c, const ex_raster_mesh *meshes, uint32_t mesh_count)
{
    uint32_t m, drawn = 0;
    if (!r || !c || c->kind != EX_CAMERA_PERSPECTIVE || c->width != r->width || c->height != r->height)
        return -1;
    if (mesh_count > 0 && !meshes) return -1;
    for (m = 0; m < mesh_count; m++) {
        if (meshes[m].tri_count > 0 && (!meshes[m].positions || !meshes[m].indices)) return -1;
        drawn += meshes[m].tri_count > 0;
    }
    if (ex__raster_setup(r, c, meshes, mesh_count) != 0 || ex__raster_bin(r) != 0)
        return -1;
    if (r->counting) r->coverage_used = 1;
    if (drawn == 0 && !r->tile_done) {   /* nothing to draw: at most the clear */
        if (r->clear_pending) ex__raster_clear_now(r);
        return 0;
    }
    ex_pool_parallel_for(r->pool, ex__raster_tile_job, r, (uint32_t)(r->tiles_x * r->tiles_y));
    r->clear_pending = 0;
    return 0;
}

/* Draws triangles (xyz positions, 3 indices each) with depth test; pixel ids
   become id_base + triangle index. Returns 0, or -1 on bad arguments (the
   camera must be perspective and of the raster's size) or out of memory. */
EX_FN int ex_raster_draw(ex_raster *r, const ex_camera *c, const float *positions,
                         const uint32_t *indices, uint32_t tri_count, uint32_t id_base)
{
    ex_raster_mesh mesh;
    mesh.positions = positions;
    mesh.indices = indices;
    mesh.tri_count = tri_count;
    mesh.id_base = id_base;
    mesh.vertex_count = 0;
    if (r) r->counting = 0;
    return ex__raster_run(r, c, &mesh, 1);
}

/* Draws several meshes in one pass over the tiles, as if drawn one after
   the other with ex_raster_draw (the same pixels, bit for bit), but every
   tile is visited once: its buffers are written once and r->tile_done sees
   the tile with everything in it. */
EX_FN int ex_raster_draw_meshes(ex_raster *r, const ex_camera *c, const ex_raster_mesh *meshes, uint32_t mesh_count)
{
    if (r) r->counting = 0;
    return ex__raster_run(r, c, meshes, mesh_count);
}

/* Adds to r->coverage how many of the triangles cover each pixel centre, with
   no depth test: the tool to check that a mesh covers each pixel once. */
EX_FN int ex_raster_count(ex_raster *r, const ex_camera *c, const float *positions,
                          const uint32_t *indices, uint32_t tri_count)
{
    ex_raster_mesh mesh;
    int result;
    if (!r) return -1;
    mesh.positions = positions;
    mesh.indices = indices;
    mesh.tri_count = tri_count;
    mesh.id_base = 0;
    mesh.vertex_count = 0;
    r->counting = 1;
    result = ex__raster_run(r, c, &mesh, 1);
    r->counting = 0;
    return result;
}

/* Gouraud resolve: pixels whose id lies in [id_base, id_base + tri_count) get
   the barycentric blend of their triangle's vertex colours. */
EX_FN void ex_raster_resolve_gouraud(const ex_raster *r, const uint32_t *indices, uint32_t tri_count,
                                     uint32_t id_base, const float *vertex_rgb, float *rgb)
{
    size_t p, n = (size_t)r->width * (size_t)r->height;
    for (p = 0; p < n; p++) {
        uint32_t id = r->id[p], tri;
        const uint32_t *v;
        float u, w, o;
        int k;
        if (id == EX_RASTER_EMPTY || id < id_base || id - id_base >= tri_count) continue;
        tri = id - id_base;
        v = indices + 3 * (size_t)tri;
        u = r->bary[2 * p];
        w = r->bary[2 * p + 1];
        o = 1.0f - u - w;
        for (k = 0; k < 3; k++)
            rgb[3 * p + (size_t)k] = o * vertex_rgb[3 * (size_t)v[0] + (size_t)k] +
                                     u * vertex_rgb[3 * (size_t)v[1] + (size_t)k] +
                                     w * vertex_rgb[3 * (size_t)v[2] + (size_t)k];
    }
}

#endif /* EXAMPLES_COMMON_RASTER_H */
