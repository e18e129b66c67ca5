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
       ex_raster_free(&r);

   A frame can instead leave the clear to its first draw
   (ex_raster_clear_deferred: each tile job clears its tile just before
   drawing into it) and shade in the last draw's tile jobs (r.tile_done,
   called on each finished tile while its buffers are in the cache): the
   buffers are then written once and read once per frame.

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
   inequalities for x in the same integers, so only covered pixels are
   visited. ex_raster_count() counts coverage instead of depth testing, to
   check exactly that. Triangles are clipped against the near plane and a
   guard band in view space (clip points computed the same way for both
   triangles of a shared edge). Both faces are drawn (no culling). Only
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
    float u[3], v[3];            /* original barycentric weights at each corner */
    uint32_t id;
    int x0, y0, x1, y1;          /* pixel bounds, inclusive, inside the image */
} ex_raster_tri;

/* The snapped triangles of one batch of EX__RASTER_BATCH input triangles:
   the setup's parallel jobs each fill one, in input order. */
typedef struct ex__raster_batch {
    ex_raster_tri *tris;
    uint32_t count, capacity;
    int failed;                  /* out of memory */
} ex__raster_batch;

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
    const ex_camera *camera;     /* the draw in progress (read by the setup jobs) */
    const float *positions;
    const uint32_t *indices;
    uint32_t tri_count, id_base;
    uint32_t *bin_start, *bin_items, bin_capacity;   /* items: batch << EX__RASTER_BATCH_BITS | index */
    int tiles_x, tiles_y;
    int counting;
    int clear_pending;           /* ex_raster_clear_deferred: the next draw's tile jobs clear their tiles */
    int coverage_used;           /* ex_raster_count ran since coverage was last zeroed */
    /* optional, set by the caller: run at the end of each tile job of every
       draw, on that tile's pixels (x0, y0 inclusive, x1, y1 exclusive) once
       the tile's triangles are in; a shading pass fused with the raster
       while the tile's buffers are in the cache */
    void (*tile_done)(void *user, int x0, int y0, int x1, int y1);
    void *tile_user;
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
    free(r->bin_start);
    free(r->bin_items);
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
static float ex__clip_distance(const ex__clip_vertex *v, int plane, float near_plane, float ax, float ay)
{
    switch (plane) {
    case 0: return v->p[2] - near_plane;
    case 1: return EX_RASTER_GUARD * ax * v->p[2] - v->p[0];
    case 2: return EX_RASTER_GUARD * ax * v->p[2] + v->p[0];
    case 3: return EX_RASTER_GUARD * ay * v->p[2] - v->p[1];
    default: return EX_RASTER_GUARD * ay * v->p[2] + v->p[1];
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

/* Sutherland-Hodgman against the five planes; returns the vertex count.
   Most triangles lie wholly inside every plane or wholly outside one: they
   are answered before any pass (with what the passes would give). */
static int ex__clip_polygon(ex__clip_vertex *poly, int n, float near_plane, float ax, float ay)
{
    ex__clip_vertex tmp[16];
    int plane, crossed = 0;
    for (plane = 0; plane < 5; plane++) {
        int i, inside = 0;
        for (i = 0; i < n; i++) inside += ex__clip_distance(&poly[i], plane, near_plane, ax, ay) >= 0;
        if (inside == 0) return 0;
        crossed |= inside < n;
    }
    if (!crossed) return n;
    for (plane = 0; plane < 5 && n > 0; plane++) {
        int i, m = 0;
        for (i = 0; i < n; i++) {
            const ex__clip_vertex *a = &poly[i], *b = &poly[(i + 1) % n];
            float da = ex__clip_distance(a, plane, near_plane, ax, ay);
            float db = ex__clip_distance(b, plane, near_plane, ax, ay);
            if (da >= 0) tmp[m++] = *a;
            if ((da >= 0) != (db >= 0)) tmp[m++] = ex__clip_cross(a, da, b, db);
        }
        memcpy(poly, tmp, (size_t)m * sizeof *poly);
        n = m;
    }
    return n;
}

/* ---- setup and binning ---------------------------------------------------- */

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

/* Snaps one clipped triangle to the screen and appends it when it covers any
   pixel centre's bounding box. */
static void ex__raster_emit(const ex_raster *r, ex__raster_batch *batch, const ex__clip_vertex *a,
                            const ex__clip_vertex *b, const ex__clip_vertex *d, uint32_t id)
{
    const ex_camera *c = r->camera;
    const ex__clip_vertex *cv[3];
    ex_raster_tri *t = &batch->tris[batch->count];
    float aspect = (float)r->width / (float)r->height;
    int64_t area, lo_x, hi_x, lo_y, hi_y;
    int k;
    cv[0] = a; cv[1] = b; cv[2] = d;
    for (k = 0; k < 3; k++) {
        float z = cv[k]->p[2];
        float sx = (cv[k]->p[0] / (z * c->tan_half * aspect) + 1.0f) * 0.5f * (float)r->width;
        float sy = (1.0f - cv[k]->p[1] / (z * c->tan_half)) * 0.5f * (float)r->height;
        t->x[k] = (int64_t)floor((double)sx * EX_RASTER_SUBPIXEL + 0.5);
        t->y[k] = (int64_t)floor((double)sy * EX_RASTER_SUBPIXEL + 0.5);
        t->inv_z[k] = 1.0f / z;
        t->u[k] = cv[k]->u;
        t->v[k] = cv[k]->v;
    }
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
    t->x0 = (int)lo_x; t->x1 = (int)hi_x;
    t->y0 = (int)lo_y; t->y1 = (int)hi_y;
    t->id = id;
    batch->count++;
}

/* One setup job: input triangles [batch * EX__RASTER_BATCH, ...) into
   r->batches[batch], transformed to view space, clipped and snapped. */
static void ex__raster_setup_job(void *ctx, uint32_t index)
{
    ex_raster *r = (ex_raster *)ctx;
    const ex_camera *c = r->camera;
    ex__raster_batch *batch = &r->batches[index];
    float aspect = (float)r->width / (float)r->height, ax = c->tan_half * aspect, ay = c->tan_half;
    uint32_t i, end = index * EX__RASTER_BATCH + EX__RASTER_BATCH;
    batch->count = 0;
    batch->failed = 0;
    if (end > r->tri_count) end = r->tri_count;
    for (i = index * EX__RASTER_BATCH; i < end; i++) {
        ex__clip_vertex poly[16];
        int k, n;
        if (ex__raster_reserve(batch, batch->count + 6) != 0) {
            batch->failed = 1;
            return;
        }
        for (k = 0; k < 3; k++) {
            const float *p = r->positions + 3 * (size_t)r->indices[3 * (size_t)i + (size_t)k];
            float d[3];
            d[0] = p[0] - c->eye[0];
            d[1] = p[1] - c->eye[1];
            d[2] = p[2] - c->eye[2];
            poly[k].p[0] = ex__dot(d, c->right);
            poly[k].p[1] = ex__dot(d, c->up);
            poly[k].p[2] = ex__dot(d, c->forward);
            poly[k].u = k == 1 ? 1.0f : 0.0f;
            poly[k].v = k == 2 ? 1.0f : 0.0f;
        }
        n = ex__clip_polygon(poly, 3, r->near_plane, ax, ay);
        for (k = 1; k + 1 < n; k++) ex__raster_emit(r, batch, &poly[0], &poly[k], &poly[k + 1], r->id_base + i);
    }
}

/* Sets up the draw's triangles in batches, in parallel on the pool; the
   batches keep input order, so the result does not depend on the thread
   count. */
static int ex__raster_setup(ex_raster *r, const ex_camera *c, const float *positions,
                            const uint32_t *indices, uint32_t tri_count, uint32_t id_base)
{
    uint32_t batches = (tri_count + EX__RASTER_BATCH - 1) / EX__RASTER_BATCH, i;
    if (batches > r->batch_capacity) {
        ex__raster_batch *p = (ex__raster_batch *)realloc(r->batches, (size_t)batches * sizeof *p);
        if (!p) return -1;
        memset(p + r->batch_capacity, 0, (size_t)(batches - r->batch_capacity) * sizeof *p);
        r->batches = p;
        r->batch_capacity = batches;
    }
    r->batch_count = batches;
    r->camera = c;
    r->positions = positions;
    r->indices = indices;
    r->tri_count = tri_count;
    r->id_base = id_base;
    ex_pool_parallel_for(r->pool, ex__raster_setup_job, r, batches);
    for (i = 0; i < batches; i++)
        if (r->batches[i].failed) return -1;
    return 0;
}

/* One pass over the set-up triangles in input order and the tiles each
   overlaps: counts them into bin_start[tile + 1] when fill is NULL, else
   stores each triangle's item (batch << EX__RASTER_BATCH_BITS | index) at
   fill[tile]++. Returns the number of (triangle, tile) pairs. */
static uint32_t ex__raster_bin_pass(ex_raster *r, uint32_t *fill)
{
    uint32_t batch, i, total = 0;
    for (batch = 0; batch < r->batch_count; batch++)
        for (i = 0; i < r->batches[batch].count; i++) {
            const ex_raster_tri *t = &r->batches[batch].tris[i];
            int tx, ty;
            for (ty = t->y0 / EX_RASTER_TILE; ty <= t->y1 / EX_RASTER_TILE; ty++)
                for (tx = t->x0 / EX_RASTER_TILE; tx <= t->x1 / EX_RASTER_TILE; tx++) {
                    int tile = ty * r->tiles_x + tx;
                    if (fill) r->bin_items[fill[tile]++] = batch << EX__RASTER_BATCH_BITS | i;
                    else r->bin_start[tile + 1]++;
                    total++;
                }
        }
    return total;
}

/* Buckets triangles per tile, in input order (so results do not depend on
   how tiles are scheduled). */
static int ex__raster_bin(ex_raster *r)
{
    uint32_t tiles = (uint32_t)(r->tiles_x * r->tiles_y), i, total, *fill;
    memset(r->bin_start, 0, (tiles + 1) * sizeof(uint32_t));
    total = ex__raster_bin_pass(r, NULL);
    for (i = 0; i < tiles; i++) r->bin_start[i + 1] += r->bin_start[i];
    if (total > r->bin_capacity) {
        uint32_t *p = (uint32_t *)realloc(r->bin_items, (size_t)total * sizeof(uint32_t));
        if (!p) return -1;
        r->bin_items = p;
        r->bin_capacity = total;
    }
    fill = (uint32_t *)malloc((tiles + 1) * sizeof(uint32_t));
    if (!fill) return -1;
    memcpy(fill, r->bin_start, (tiles + 1) * sizeof(uint32_t));
    ex__raster_bin_pass(r, fill);
    free(fill);
    return 0;
}

/* ---- per tile --------------------------------------------------------- */

/* Whether an edge's on-line points belong to the triangle to its left: true
   for exactly one of an edge and its reverse, as if every pixel centre moved
   by an infinitesimal (-1, -eta). */
static int ex__edge_owns_ties(int64_t dx, int64_t dy) { return dy > 0 || (dy == 0 && dx < 0); }

/* Floor of a / b for b > 0, exact in 64-bit integers. */
static int64_t ex__floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

/* Narrows the span [*lo, *hi] (pixel offsets from the row's first pixel) to
   the pixels where edge value w(x) = w0 - step * x satisfies w(x) + bias > 0,
   i.e. w0 + bias - step * x >= 1: solved exactly for x, so the span holds
   exactly the pixels a per-pixel test would accept. */
static void ex__edge_span(int64_t w0, int64_t step, int bias, int64_t *lo, int64_t *hi)
{
    int64_t room = w0 + bias - 1;   /* step * x <= room */
    if (step == 0) {
        if (room < 0) *hi = -1;     /* the whole row is outside this edge */
    } else if (step > 0) {
        int64_t x = ex__floor_div(room, step);
        if (x < *hi) *hi = x;
    } else {
        int64_t x = -ex__floor_div(room, -step);   /* x >= ceil(room / step) = -floor(room / -step) */
        if (x > *lo) *lo = x;
    }
}

/* Rasterizes triangle t inside the tile's pixel box. Each row's covered
   pixels are found by solving the three edge inequalities for x (exact
   integer arithmetic, the same pixels as testing each one), so the loop
   over a row runs over covered pixels only; there, the edge values give the
   barycentric weights as before. */
static void ex__raster_tri_in_tile(ex_raster *r, const ex_raster_tri *t, int tx0, int ty0, int tx1, int ty1)
{
    int64_t e_dx[3], e_dy[3], row[3], step[3];
    int bias[3], k, x, y;
    int x0 = t->x0 > tx0 ? t->x0 : tx0, x1 = t->x1 < tx1 ? t->x1 : tx1;
    int y0 = t->y0 > ty0 ? t->y0 : ty0, y1 = t->y1 < ty1 ? t->y1 : ty1;
    int64_t px0 = (int64_t)x0 * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
    int64_t py0 = (int64_t)y0 * EX_RASTER_SUBPIXEL + EX_RASTER_SUBPIXEL / 2;
    float inv_area;
    if (x0 > x1 || y0 > y1) return;
    /* edge k goes from vertex k+1 to k+2; it is zero on that edge and positive
       at vertex k, so its value over the area is vertex k's weight */
    for (k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        e_dx[k] = t->x[b] - t->x[a];
        e_dy[k] = t->y[b] - t->y[a];
        row[k] = e_dx[k] * (py0 - t->y[a]) - e_dy[k] * (px0 - t->x[a]);
        bias[k] = ex__edge_owns_ties(e_dx[k], e_dy[k]);
        step[k] = e_dy[k] * EX_RASTER_SUBPIXEL;
    }
    /* twice the area: edge 0's value at vertex 0 */
    inv_area = 1.0f / (float)(e_dx[0] * (t->y[0] - t->y[1]) - e_dy[0] * (t->x[0] - t->x[1]));
    for (y = y0; y <= y1; y++) {
        int64_t lo = 0, hi = x1 - x0;
        for (k = 0; k < 3; k++) ex__edge_span(row[k], step[k], bias[k], &lo, &hi);
        for (x = x0 + (int)lo; x <= x0 + (int)hi; x++) {
            int64_t dx = x - x0;
            size_t p = (size_t)y * (size_t)r->width + (size_t)x;
            if (r->counting) {
                r->coverage[p]++;
            } else {
                float l0 = (float)(row[0] - step[0] * dx) * inv_area, l1 = (float)(row[1] - step[1] * dx) * inv_area;
                float l2 = (float)(row[2] - step[2] * dx) * inv_area;
                float a0 = l0 * t->inv_z[0], a1 = l1 * t->inv_z[1], a2 = l2 * t->inv_z[2];
                float z = 1.0f / (a0 + a1 + a2);
                if (z < r->depth[p]) {
                    r->depth[p] = z;
                    r->id[p] = t->id;
                    r->bary[2 * p] = (a0 * t->u[0] + a1 * t->u[1] + a2 * t->u[2]) * z;
                    r->bary[2 * p + 1] = (a0 * t->v[0] + a1 * t->v[1] + a2 * t->v[2]) * z;
                }
            }
        }
        row[0] += e_dx[0] * EX_RASTER_SUBPIXEL;
        row[1] += e_dx[1] * EX_RASTER_SUBPIXEL;
        row[2] += e_dx[2] * EX_RASTER_SUBPIXEL;
    }
}

static void ex__raster_tile_job(void *ctx, uint32_t tile)
{
    ex_raster *r = (ex_raster *)ctx;
    int tx = (int)tile % r->tiles_x, ty = (int)tile / r->tiles_x;
    int x0 = tx * EX_RASTER_TILE, y0 = ty * EX_RASTER_TILE;
    int x1 = x0 + EX_RASTER_TILE - 1, y1 = y0 + EX_RASTER_TILE - 1;
    uint32_t i;
    if (x1 >= r->width) x1 = r->width - 1;
    if (y1 >= r->height) y1 = r->height - 1;
    if (r->clear_pending) ex__raster_clear_box(r, x0, y0, x1 + 1, y1 + 1);
    for (i = r->bin_start[tile]; i < r->bin_start[tile + 1]; i++) {
        uint32_t item = r->bin_items[i];
        const ex__raster_batch *batch = &r->batches[item >> EX__RASTER_BATCH_BITS];
        ex__raster_tri_in_tile(r, &batch->tris[item & ((1u << EX__RASTER_BATCH_BITS) - 1u)], x0, y0, x1, y1);
    }
    if (r->tile_done) r->tile_done(r->tile_user, x0, y0, x1 + 1, y1 + 1);
}

static int ex__raster_run(ex_raster *r, const ex_camera *c, const float *positions,
                          const uint32_t *indices, uint32_t tri_count, uint32_t id_base)
{
    if (!r || !c || c->kind != EX_CAMERA_PERSPECTIVE || c->width != r->width || c->height != r->height)
        return -1;
    if (tri_count > 0 && !positions) return -1;
    if (tri_count > 0 && !indices) return -1;
    if (ex__raster_setup(r, c, positions, indices, tri_count, id_base) != 0 || ex__raster_bin(r) != 0)
        return -1;
    if (r->counting) r->coverage_used = 1;
    if (tri_count == 0 && !r->tile_done) {   /* nothing to draw: at most the clear */
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
    if (r) r->counting = 0;
    return ex__raster_run(r, c, positions, indices, tri_count, id_base);
}

/* Adds to r->coverage how many of the triangles cover each pixel centre, with
   no depth test: the tool to check that a mesh covers each pixel once. */
EX_FN int ex_raster_count(ex_raster *r, const ex_camera *c, const float *positions,
                          const uint32_t *indices, uint32_t tri_count)
{
    int result;
    if (!r) return -1;
    r->counting = 1;
    result = ex__raster_run(r, c, positions, indices, tri_count, 0);
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
