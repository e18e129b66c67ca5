/* Unit tests of radinterp.h part 2: the closed-form quadratic interpolant
   (exact reproduction of quadratics), the EV/VE discontinuities of a square
   source over a square blocker against the analytic penumbra and umbra
   boundaries, the activation rules (max_leaf_dsets, active in every leaf
   crossed or in none, greedy by weight) checked geometrically over the
   whole quadtree, crack-free rasterization of a small room, per-pixel
   shading, save/load with every truncation and corruption, validation,
   allocation failures, cancellation and determinism. Scenes are small (the
   tests run under the sanitizers); the office-scale checks are in
   ref_radinterp_mesh.c. */
/* A stopped clock for the pacer (RADINTERP_CPU_SECONDS): batches grow to
   their largest, so progress calls come at the same places in every run, as
   the cancel tests, which count them, require. */
#define RADINTERP_CPU_SECONDS() 0.0
/* Batches of leaf lists far smaller than the default (16 MB), so that the
   mesh builds here run many batches (test_leaf_lists_bounded). */
#define RADINTERP__LEAF_BATCH_BYTES ((size_t)16 << 10)
#define RADINTERP_IMPLEMENTATION
#include "../radinterp.h"
#include "examples/common/camera.h"
#include "examples/common/pool.h"
#include "examples/common/raster.h"
#include "test.h"
#include <limits.h>

#define PI 3.14159265358979323846

/* ---- scenes built in code (z up) ---------------------------------------- */
typedef struct scene {
    float pos[3 * 512];
    uint32_t patch[4 * 128], mat[128];
    uint32_t nv, np;
    radinterp_material m[8];
    uint32_t nm;
} scene;

static uint32_t add_vertex(scene *s, float x, float y, float z)
{
    s->pos[3 * s->nv] = x; s->pos[3 * s->nv + 1] = y; s->pos[3 * s->nv + 2] = z;
    return s->nv++;
}

static uint32_t add_quad(scene *s, const float *a, const float *b, const float *c, const float *d, uint32_t mat)
{
    uint32_t i = s->np++;
    s->patch[4 * i] = add_vertex(s, a[0], a[1], a[2]);
    s->patch[4 * i + 1] = add_vertex(s, b[0], b[1], b[2]);
    s->patch[4 * i + 2] = add_vertex(s, c[0], c[1], c[2]);
    s->patch[4 * i + 3] = d ? add_vertex(s, d[0], d[1], d[2]) : RADINTERP_NO_VERTEX;
    s->mat[i] = mat;
    return i;
}

/* Axis-aligned rectangle at height z facing up (+z) or down. */
static uint32_t add_hrect(scene *s, float x0, float y0, float x1, float y1, float z, int up, uint32_t mat)
{
    float a[3], b[3], c[3], d[3];
    a[0] = x0; a[1] = y0; a[2] = z;
    b[0] = x1; b[1] = y0; b[2] = z;
    c[0] = x1; c[1] = y1; c[2] = z;
    d[0] = x0; d[1] = y1; d[2] = z;
    return up ? add_quad(s, a, b, c, d, mat) : add_quad(s, a, d, c, b, mat);
}

static uint32_t add_material(scene *s, float rho, float e)
{
    radinterp_material *m = &s->m[s->nm];
    m->reflectance[0] = m->reflectance[1] = m->reflectance[2] = rho;
    m->emission[0] = m->emission[1] = m->emission[2] = e;
    return s->nm++;
}

static radinterp_desc scene_desc(const scene *s)
{
    radinterp_desc d;
    memset(&d, 0, sizeof d);
    d.positions = s->pos;
    d.vertex_count = s->nv;
    d.patches = s->patch;
    d.patch_count = s->np;
    d.patch_materials = s->mat;
    d.materials = s->m;
    d.material_count = s->nm;
    return d;
}

/* An inward-facing box [x0,x1] x [y0,y1] x [z0,z1] without its ceiling. */
static void add_room(scene *s, float x0, float y0, float z0, float x1, float y1, float z1, uint32_t mat)
{
    float c[8][3];
    int i;
    for (i = 0; i < 8; i++) {
        c[i][0] = i & 1 ? x1 : x0;
        c[i][1] = (i >> 1) & 1 ? y1 : y0;
        c[i][2] = (i >> 2) & 1 ? z1 : z0;
    }
    add_quad(s, c[0], c[1], c[3], c[2], mat);  /* floor, facing +z */
    add_quad(s, c[0], c[4], c[5], c[1], mat);  /* y = y0, facing +y */
    add_quad(s, c[2], c[3], c[7], c[6], mat);  /* y = y1, facing -y */
    add_quad(s, c[0], c[2], c[6], c[4], mat);  /* x = x0, facing +x */
    add_quad(s, c[1], c[5], c[7], c[3], mat);  /* x = x1, facing -x */
}

/* An outward-facing box standing on z = z0 (no bottom face). */
static void add_block(scene *s, float x0, float y0, float z0, float x1, float y1, float z1, uint32_t mat)
{
    float c[8][3];
    int i;
    for (i = 0; i < 8; i++) {
        c[i][0] = i & 1 ? x1 : x0;
        c[i][1] = (i >> 1) & 1 ? y1 : y0;
        c[i][2] = (i >> 2) & 1 ? z1 : z0;
    }
    add_quad(s, c[4], c[5], c[7], c[6], mat);  /* top, +z */
    add_quad(s, c[0], c[1], c[5], c[4], mat);  /* y = y0, -y */
    add_quad(s, c[2], c[6], c[7], c[3], mat);  /* y = y1, +y */
    add_quad(s, c[0], c[4], c[6], c[2], mat);  /* x = x0, -x */
    add_quad(s, c[1], c[3], c[7], c[5], mat);  /* x = x1, +x */
}

static uint64_t rng_state = 7;
static double rnd(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* The tests here look at every discontinuity found, not only at the
   candidates the mesh keeps by default (test_candidates_only_by_default). */
static radinterp_mesh_desc mesh_desc(void)
{
    radinterp_mesh_desc md;
    memset(&md, 0, sizeof md);
    md.keep_all_discontinuities = 1;
    return md;
}

/* ---- the interpolant ------------------------------------------------------ */

/* Any quadratic R(s, t) = A s^2 + 2B st + 2C s + D t^2 + 2E t + F comes back
   from its six samples: coefficients to float precision, and the values at
   the sample points. */
static void test_fit_reproduces_quadratics(void)
{
    static const double at[6][2] = {{0, 0}, {0.5, 0}, {1, 0}, {0.5, 0.5}, {0, 1}, {0, 0.5}};
    double worst = 0.0, worst_value = 0.0;
    int trial, i;
    for (trial = 0; trial < 2000; trial++) {
        double c[6], scale = trial % 3 == 0 ? 1e3 : 1.0, big = 0.0;
        float r[6], got[6], want[6];
        for (i = 0; i < 6; i++) { c[i] = (2.0 * rnd() - 1.0) * scale; big = fabs(c[i]) > big ? fabs(c[i]) : big; }
        for (i = 0; i < 6; i++) {
            double s = at[i][0], t = at[i][1];
            r[i] = (float)(c[0] * s * s + 2 * c[1] * s * t + 2 * c[2] * s + c[3] * t * t + 2 * c[4] * t + c[5]);
        }
        radinterp_fit_quadratic(r, got);
        want[0] = (float)c[0]; want[1] = (float)(2 * c[1]); want[2] = (float)(2 * c[2]);
        want[3] = (float)c[3]; want[4] = (float)(2 * c[4]); want[5] = (float)c[5];
        for (i = 0; i < 6; i++) {
            double e = fabs((double)got[i] - want[i]) / big;
            worst = e > worst ? e : worst;
        }
        for (i = 0; i < 6; i++) {
            float s = (float)at[i][0], t = (float)at[i][1];
            double v = s * (got[0] * s + got[1] * t + got[2]) + t * (got[3] * t + got[4]) + got[5];
            double e = fabs(v - r[i]) / big;
            worst_value = e > worst_value ? e : worst_value;
        }
    }
    /* the samples are rounded to float and the closed form adds up to 12
       of them (|weight| <= 4): a few float ulps of the largest coefficient */
    CHECK_MSG(worst < 2e-6, "coefficients off by %g of the largest", worst);
    CHECK_MSG(worst_value < 2e-6, "sample values off by %g of the largest coefficient", worst_value);
    test_note("quadratic reproduction over 2000 random quadratics: coefficients within %.2g, samples within %.2g "
              "(relative to the largest coefficient)", worst, worst_value);
}

/* ---- discontinuity geometry --------------------------------------------- */

/* Square source [-a, a]^2 at height H facing down, a blocker
   [bx0, bx1] x [by0, by1] at height h facing up, a 4 x 4 floor. */
#define SRC_A 0.25
#define SRC_H 2.0
#define BLK_H 0.8
static const double blk[4] = {-0.1, -0.2, 0.3, 0.15};  /* bx0, by0, bx1, by1 */

static radinterp_solution *penumbra_scene(scene *s)
{
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t grey, light;
    memset(s, 0, sizeof *s);
    grey = add_material(s, 0.5f, 0.0f);
    light = add_material(s, 0.0f, 100.0f);
    add_hrect(s, -2, -2, 2, 2, 0, 1, grey);                                                           /* 0: floor */
    add_hrect(s, -(float)SRC_A, -(float)SRC_A, (float)SRC_A, (float)SRC_A, (float)SRC_H, 0, light);   /* 1: source */
    add_hrect(s, (float)blk[0], (float)blk[1], (float)blk[2], (float)blk[3], (float)BLK_H, 1, grey);  /* 2: blocker */
    d = scene_desc(s);
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    return sol;
}

/* Does the segment a-b cross the rectangle r (x0, y0, x1, y1) at z = BLK_H? */
static int crosses_rect(const double *a, const double *b, const double *r)
{
    double t, x, y;
    if (!((a[2] - BLK_H) * (b[2] - BLK_H) < 0.0)) return 0;
    t = (BLK_H - a[2]) / (b[2] - a[2]);
    x = a[0] + t * (b[0] - a[0]);
    y = a[1] + t * (b[1] - a[1]);
    return x > r[0] && x < r[2] && y > r[1] && y < r[3];
}

/* Leaf lists mark a link hidden from a whole leaf when one blocker covers
   every segment from the leaf's box, grown by the lists' margin, to the
   source at its place and pushed off (radinterp__leaf_hides); point queries
   then skip its backprojection. The penumbra scene with a blocker [-1, 1]^2
   facing the floor (turned toward the points, as the library requires; at
   BLK_H, under the source [-SRC_A, SRC_A]^2 at SRC_H): seen from a floor
   point x, the source projects onto the blocker's plane as
   [0.6 x - 0.1, 0.6 x + 0.1] in each axis, inside the blocker for |x| < 1.5:
   the umbra. Random flat boxes on the floor: the verdict must be "hidden"
   for those inside |x|, |y| < 1.5 and "not hidden" for those reaching
   outside it, except within 1e-3 of that boundary, where the margins (a few
   epsilon * diag, about 2e-5 m here) decide. Each "hidden" is also checked
   by segments from random points of the box to random points of the source
   (pushed off by up to push_off): every one must cross the blocker. Boxes
   above the blocker, or straddling its plane, are never hidden. */
static void test_leaf_hidden_links(void)
{
    static const double wide[4] = {-1.0, -1.0, 1.0, 1.0};
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t i, k, grey, light, hidden = 0, open = 0, bad = 0;
    const radinterp__node *src;
    radinterp__leaf_shaft ls;
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 100.0f);
    add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);                                                              /* 0: floor */
    add_hrect(&s, -(float)SRC_A, -(float)SRC_A, (float)SRC_A, (float)SRC_A, (float)SRC_H, 0, light);      /* 1: source */
    add_hrect(&s, (float)wide[0], (float)wide[1], (float)wide[2], (float)wide[3], (float)BLK_H, 0, grey); /* 2: blocker */
    d = scene_desc(&s);
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK);
    if (!sol) return;
    src = &sol->nodes[sol->patches[1].root];
    for (i = 0; i < 2000; i++) {
        float lo[3], hi[3];
        double outer = 0.0;   /* largest |x| or |y| of the box */
        int j, verdict;
        for (j = 0; j < 2; j++) {
            double c = -2.0 + 4.0 * rnd(), w = 0.5 * rnd();
            lo[j] = (float)(c - w);
            hi[j] = (float)(c + w);
            outer = fabs(lo[j]) > outer ? fabs(lo[j]) : outer;
            outer = fabs(hi[j]) > outer ? fabs(hi[j]) : outer;
        }
        lo[2] = hi[2] = 0.0f;   /* flat, as a floor leaf's box */
        radinterp__leaf_shaft_make(sol, lo, hi, src, &ls);
        verdict = radinterp__leaf_hides(sol, &ls, 2);
        if (outer < 1.5 - 1e-3) CHECK_MSG(verdict, "box out to %g not hidden", outer);
        if (outer > 1.5 + 1e-3) CHECK_MSG(!verdict, "box out to %g hidden", outer);
        if (!verdict) { open++; continue; }
        hidden++;
        for (k = 0; k < 100; k++) {
            double a[3], b[3], u = rnd(), v = rnd();
            for (j = 0; j < 3; j++) {
                a[j] = lo[j] + rnd() * ((double)hi[j] - lo[j]);
                b[j] = (1 - u) * (1 - v) * src->v[0][j] + u * (1 - v) * src->v[1][j] + u * v * src->v[2][j] +
                       (1 - u) * v * src->v[3][j];
            }
            b[2] += rnd() * sol->push_off;   /* moved behind the source, which faces down */
            bad += !crosses_rect(a, b, wide);
        }
    }
    CHECK(hidden > 100 && open > 100);   /* both verdicts are exercised */
    CHECK_EQ_INT(bad, 0);
    {   /* above the blocker, and straddling its plane: never */
        float lo1[3] = {-0.1f, -0.1f, 1.0f}, hi1[3] = {0.1f, 0.1f, 1.2f};
        float lo2[3] = {-0.1f, -0.1f, 0.7f}, hi2[3] = {0.1f, 0.1f, 0.9f};
        radinterp__leaf_shaft_make(sol, lo1, hi1, src, &ls);
        CHECK(!radinterp__leaf_hides(sol, &ls, 2));
        radinterp__leaf_shaft_make(sol, lo2, hi2, src, &ls);
        CHECK(!radinterp__leaf_hides(sol, &ls, 2));
    }
    test_note("leaf verdicts: %u of 2000 random floor boxes hidden by the blocker, every one confirmed by 100 segments",
         hidden);
    radinterp_solution_destroy(sol);
}

/* A point query takes one shadow as hiding the whole source when it leaves
   less of the source than the union takes for rounding
   (radinterp__stage_shadow): a blocker spanning the whole pyramid from the
   point over the source is clipped by the pyramid's sides to the source's
   outline, its corners moved by rounding, and the exact containment test
   alone fails for some of them. The scene of test_leaf_hidden_links (blocker
   [-1, 1]^2 facing the floor, umbra |x|, |y| < 1.5 on the floor, see there):
   at random floor points (a quarter of them within 1e-6 of the umbra's edge)
   the staged blocker must hide the source inside the umbra and must not
   outside it, except within 1e-7 of its edge: BLK_H as
   a float is 0.8 + 1.2e-8, which moves the edge by about 1.2e-8, and from a
   point 1e-7 outside a strip of about 1e-7 of the source's width is
   uncovered, far above the 1e-12 of its area that counts as rounding. */
static void test_one_shadow_hides(void)
{
    static const uint32_t blocker = 2;
    static radinterp__query q;   /* about 110 KB */
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t i, grey, light, inside = 0, by_area = 0, outside = 0;
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 100.0f);
    add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);                                                          /* 0: floor */
    add_hrect(&s, -(float)SRC_A, -(float)SRC_A, (float)SRC_A, (float)SRC_A, (float)SRC_H, 0, light);  /* 1: source */
    add_hrect(&s, -1, -1, 1, 1, (float)BLK_H, 0, grey);                                               /* 2: blocker */
    d = scene_desc(&s);
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK);
    if (!sol) return;
    for (i = 0; i < 4000; i++) {
        const radinterp__patch *ps = &sol->patches[1];
        float p[3];
        double Sc[RADINTERP__POLY_MAX][3], full, outer;
        radinterp__bp bp;
        int nc, n, hides;
        p[0] = (float)(-2.0 + 4.0 * rnd());
        p[1] = (float)(-2.0 + 4.0 * rnd());
        p[2] = 0.0f;
        if (i % 4 == 0)   /* within 1e-6 of the umbra's edge, either side */
            p[0] = (float)((rnd() < 0.5 ? -1.0 : 1.0) * (1.5 + (rnd() < 0.5 ? -1e-6 : 1e-6) * (0.2 + rnd())));
        outer = fabs(p[0]) > fabs(p[1]) ? fabs(p[0]) : fabs(p[1]);
        if (fabs(outer - 1.5) < 1e-7) continue;
        radinterp__query_start(&q, sol, 0, p, NULL);
        nc = radinterp__query_source(&q, ps->root, Sc, &full);
        CHECK_EQ_INT(nc, 4);
        q.blk = &blocker;
        q.nblk = 1;
        radinterp__bp_setup(&q, &bp, NULL, (const double (*)[3])Sc, nc, ps->n, ps->d - sol->push_off, sol->push_off);
        n = radinterp__bp_stage(&q, &bp, &hides);
        if (outer > 1.5) {
            CHECK_MSG(!hides && n <= 1, "point (%g, %g) outside the umbra: hidden %d, %d shadows", p[0], p[1], hides, n);
            outside++;
            continue;
        }
        CHECK_MSG(hides, "point (%g, %g) inside the umbra not hidden", p[0], p[1]);
        inside++;
        by_area += !radinterp__covers((const double (*)[2])q.staged[0].v, q.staged[0].count,
                                      (const double (*)[2])bp.sc2, bp.nc);
    }
    CHECK(inside > 500 && outside > 500);
    CHECK(by_area > 0);   /* the rule is exercised: containment alone misses some */
    test_note("one shadow hides the source at %u of %u floor points in the umbra, %u of them by the area rule; "
              "none of %u outside", inside, inside, by_area, outside);
    radinterp_solution_destroy(sol);
}

/* The staged shadows' areas are computed once, where the shadow is made
   (radinterp__bp_shadow_piece), and kept for the covered test and the
   largest-first order: each kept area must equal the area of the shadow
   staged in its slot, bit for bit, and the order must be by those areas
   (ties by list position). A source over a floor with five overlapping
   blockers, some turned toward the floor and some away (staged after the
   order). Also radinterp__next, the polygon loops' next corner, against
   (i + 1) % n. */
/* A square source (patch 1) 2 m over a floor (patch 0) with five
   overlapping blockers between them (patches 2..6, the second and fourth
   turned up, away from the floor), solved. */
static radinterp_solution *five_blockers_scene(uint32_t *blocker)
{
    static const float blk[5][5] = {   /* x0, y0, x1, y1, z */
        {-0.9f, -0.6f, 0.3f, 0.5f, 0.6f}, {-0.2f, -0.9f, 0.8f, 0.2f, 0.9f}, {-0.5f, 0.1f, 0.6f, 0.9f, 1.2f},
        {-0.7f, -0.4f, 0.1f, 0.4f, 1.5f}, {0.0f, -0.5f, 0.7f, 0.6f, 0.4f}};
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t grey, light, k;
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 100.0f);
    add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);
    add_hrect(&s, -0.5f, -0.5f, 0.5f, 0.5f, 2.0f, 0, light);
    for (k = 0; k < 5; k++)
        blocker[k] = add_hrect(&s, blk[k][0], blk[k][1], blk[k][2], blk[k][3], blk[k][4], (int)(k & 1), grey);
    d = scene_desc(&s);
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK);
    return sol;
}

/* Query i of the five blockers' scene started in q, its source's pyramid in
   bp: a point over the floor (p, drawn with rnd), on the floor, or with
   `air` in the air for odd i, where two of every three queries take one of
   the source's children instead of its root (a smaller pyramid). blk: the
   blockers the query stages (NULL for none). Returns 0 when the source
   has fewer than 3 corners left in front of the point (no query). */
static int five_blockers_query(const radinterp_solution *sol, uint32_t i, int air, const uint32_t *blk,
                               radinterp__query *q, radinterp__bp *bp, float p[3])
{
    const radinterp__patch *ps = &sol->patches[1];
    uint32_t node = ps->root;
    double Sc[RADINTERP__POLY_MAX][3], full;
    int nc;
    p[0] = (float)(-1.5 + 3.0 * rnd());
    p[1] = (float)(-1.5 + 3.0 * rnd());
    p[2] = (float)(air && i % 2 ? 1.9 * rnd() : 0.0);
    if (air && i % 3 && sol->nodes[node].child != RADINTERP__NONE) node = sol->nodes[node].child + (uint32_t)(i % 4);
    radinterp__query_start(q, sol, 0, p, NULL);
    nc = radinterp__query_source(q, node, Sc, &full);
    if (nc < 3) return 0;
    q->blk = blk;
    q->nblk = blk ? 5 : 0;
    radinterp__bp_setup(q, bp, NULL, (const double (*)[3])Sc, nc, ps->n, ps->d - sol->push_off, sol->push_off);
    return 1;
}

static void test_staged_shadow_areas(void)
{
    static radinterp__query q;   /* about 110 KB */
    radinterp_solution *sol;
    uint32_t blocker[5], i;
    int n, m, multi = 0, later = 0, next_ok = 1;
    for (n = 1; n <= RADINTERP__POLY_MAX; n++)
        for (m = 0; m < n; m++) next_ok &= radinterp__next(m, n) == (m + 1) % n;
    CHECK(next_ok);
    sol = five_blockers_scene(blocker);
    if (!sol) return;
    for (i = 0; i < 3000; i++) {
        float p[3];
        radinterp__bp bp;
        int hides, j;
        if (!five_blockers_query(sol, i, 0, blocker, &q, &bp, p)) continue;
        n = radinterp__bp_stage(&q, &bp, &hides);
        if (n < 0 || hides) continue;
        for (j = 0; j < (int)q.nlater; j++)   /* turned away: each staged as the union reaches it */
            if (radinterp__stage_shadow(&q, &bp, q.later[j], &n) != 0) break;
        if (j < (int)q.nlater || n < 2) continue;
        multi++;
        for (j = 0; j < n; j++) {
            double a = fabs(radinterp__area2((const double (*)[2])q.staged[j].v, q.staged[j].count));
            CHECK_MSG(memcmp(&a, &q.staged_area[j], sizeof a) == 0, "point (%g, %g): shadow %d's kept area %.17g, its area %.17g",
                      p[0], p[1], j, q.staged_area[j], a);
            later += !radinterp__faces_point(&q, &bp, blocker[q.staged_at[j]]);
        }
        for (j = 1; j < n; j++) {   /* faces toward the point first, largest first */
            int a = q.order[j - 1], b = q.order[j];
            if (!radinterp__faces_point(&q, &bp, blocker[q.staged_at[b]])) break;
            CHECK_MSG(q.staged_area[a] > q.staged_area[b] ||
                      (q.staged_area[a] == q.staged_area[b] && q.staged_at[a] < q.staged_at[b]),
                      "point (%g, %g): shadows %d, %d out of order", p[0], p[1], a, b);
        }
    }
    CHECK(multi > 500);
    CHECK(later > 100);   /* shadows staged after the order are checked too */
    test_note("%d floor points staged 2 or more shadows (%d of blockers turned away)", multi, later);
    radinterp_solution_destroy(sol);
}

/* The union of a query's shadows in radinterp__bp_stage's order,
   everything staged first (as radinterp__union_staged did before it
   staged the faces turned away itself), into e's pieces: -1, 0 hidden or
   1 with *count pieces. */
static int union_all_staged(radinterp__query *e, const radinterp__bp *bp, int *count)
{
    int hides, n = radinterp__bp_stage(e, bp, &hides), r;
    uint32_t k;
    if (n < 0) return -1;
    if (hides) return 0;
    for (k = 0; k < e->nlater; k++)
        if ((r = radinterp__stage_shadow(e, bp, e->later[k], &n)) != 0) return r > 0 ? 0 : -1;
    r = radinterp__union_staged(e, bp, n, 0, count);
    return r < 0 ? -1 : r == 0 ? 0 : 1;
}

/* radinterp__union_staged stages the shadows of faces turned away only when
   the union reaches them. Its verdict and pieces must be those of staging
   every shadow first, and where the shadows of the faces turned toward the
   point hide the source, no shadow of a face turned away may be made.
   The five blockers (two turned up) at points on the floor and in the air,
   over the source and its children. */
static void test_later_shadows_when_reached(void)
{
    static radinterp__query q, e;   /* about 110 KB each */
    radinterp_solution *sol;
    uint32_t blocker[5], i, skipped = 0, reached = 0, unions = 0;
    sol = five_blockers_scene(blocker);
    if (!sol) return;
    for (i = 0; i < 4000; i++) {
        float p[3];
        radinterp__bp bp;
        int n, hides, raw, r, re, count = 0, count_e = 0, k, front = 0, away = 0;
        if (!five_blockers_query(sol, i, 1, blocker, &q, &bp, p)) continue;
        radinterp__query_start(&e, sol, 0, p, NULL);   /* the same point, everything staged first */
        e.blk = blocker;
        e.nblk = 5;
        re = union_all_staged(&e, &bp, &count_e);
        for (k = 0; k < RADINTERP__BP_MAX_SURVIVORS; k++) q.staged_at[k] = RADINTERP__NONE;
        n = radinterp__bp_stage(&q, &bp, &hides);
        if (n < 0 || hides) {
            CHECK_MSG(re == (n < 0 ? -1 : 0), "point (%g, %g, %g): staging gave %d, everything staged first %d", p[0],
                      p[1], p[2], n < 0 ? -1 : 0, re);
            continue;
        }
        raw = radinterp__union_staged(&q, &bp, n, q.nlater, &count);
        r = raw < 0 ? -1 : raw == 1 ? 1 : 0;
        unions++;
        CHECK_MSG(r == re, "point (%g, %g, %g): union %d, everything staged first %d", p[0], p[1], p[2], r, re);
        if (r == 1 && re == 1) {
            CHECK_EQ_INT(count, count_e);
            for (k = 0; k < count && k < count_e; k++)
                CHECK_MSG(q.piece[k].count == e.piece[k].count &&
                          memcmp(q.piece[k].v, e.piece[k].v, (size_t)q.piece[k].count * sizeof q.piece[k].v[0]) == 0 &&
                          memcmp(q.piece[k].ln, e.piece[k].ln, (size_t)q.piece[k].count * sizeof q.piece[k].ln[0]) == 0,
                          "point (%g, %g, %g): piece %d differs", p[0], p[1], p[2], k);
        }
        for (k = 0; k < RADINTERP__BP_MAX_SURVIVORS; k++) {   /* the shadows made, by the faces' sides */
            if (q.staged_at[k] == RADINTERP__NONE) continue;
            if (radinterp__faces_point(&q, &bp, blocker[q.staged_at[k]])) front++;
            else away++;
        }
        reached += away > 0;
        if (raw == 0 && count <= front && q.nlater > 0) {   /* hidden before the faces turned away */
            CHECK_MSG(away == 0, "point (%g, %g, %g): hidden by %d shadows, yet %d of faces turned away made", p[0],
                      p[1], p[2], count, away);
            skipped++;
        }
    }
    CHECK(unions > 1000 && reached > 500 && skipped > 20);
    test_note("%u unions, %u of them staged shadows of faces turned away, %u ended hidden without making theirs",
              unions, reached, skipped);
    radinterp_solution_destroy(sol);
}

/* radinterp__pyramid_cut leaves out the corner tests of a plane that has a
   blocker's bounding sphere well inside it (radinterp__sphere_inside): its
   verdict (culled, or which planes cut) must be the one testing every
   corner against every plane gives. Points on the floor and in the air
   around and between the five blockers, over the source and its children
   (smaller pyramids). */
static void test_pyramid_cut_skips(void)
{
    static radinterp__query q;   /* about 110 KB */
    radinterp_solution *sol;
    uint32_t blocker[5], i, k, skipped = 0, cutting = 0, culled = 0;
    sol = five_blockers_scene(blocker);
    if (!sol) return;
    for (i = 0; i < 4000; i++) {
        float p[3];
        radinterp__bp bp;
        if (!five_blockers_query(sol, i, 1, NULL, &q, &bp, p)) continue;
        for (k = 0; k < 5; k++) {
            const radinterp__patch *pb = &sol->patches[blocker[k]];
            double poly[RADINTERP__POLY_MAX][3], all[RADINTERP__POLY_MAX][3];
            uint32_t cut, cut_all = 0;
            int m = radinterp__pyramid_cut(sol, &bp, pb, poly, &cut), m_all = radinterp__patch_poly(pb, all), j, c;
            int none = 0, sphere_out = 0;
            for (j = 0; j < bp.np; j++) {
                int in = 0;
                double sd = radinterp__d3_dot(bp.plane_n[j], pb->centre) - bp.plane_d[j];
                sphere_out |= sd < -pb->radius;
                for (c = 0; c < m_all; c++) in += radinterp__d3_dot(bp.plane_n[j], all[c]) >= bp.plane_d[j];
                none |= in == 0;
                if (in > 0 && in < m_all) cut_all |= 1u << j;
                skipped += !sphere_out && radinterp__sphere_inside(pb, radinterp__sphere_size(pb), sd, bp.plane_d[j]);
            }
            if (sphere_out || fabs(radinterp__d3_dot(pb->n, bp.pv) - pb->d) <= sol->epsilon * sol->diag) {
                CHECK_EQ_INT(m, 0);
                continue;
            }
            CHECK_MSG(m == (none ? 0 : m_all), "point (%g, %g, %g), blocker %u: %d corners, expected %d", p[0], p[1], p[2], k,
                      m, none ? 0 : m_all);
            if (m && !none) CHECK_MSG(cut == cut_all, "point (%g, %g, %g), blocker %u: cut %x, expected %x", p[0], p[1],
                                      p[2], k, cut, cut_all);
            culled += none;
            cutting += !none && cut_all != 0;
        }
    }
    CHECK(skipped > 10000 && cutting > 1000 && culled > 1000);
    test_note("%u planes' corner tests left out; %u blockers cut, %u culled by their corners", skipped, cutting, culled);
    radinterp_solution_destroy(sol);
}

/* The rays from a source edge at coordinate xs through a blocker edge at xb
   meet the floor at xb + t (xb - xs), t = h / (H - h): for xs = -a, a and
   xb = both blocker edges, four lines per axis bound the penumbra and the
   umbra; along the other axis each spans the blocker's projection through
   the whole source. */
typedef struct expected_line { int axis; double at, lo, hi; double covered_lo, covered_hi; int hits; } expected_line;

static void test_penumbra_boundaries(void)
{
    scene s;
    radinterp_solution *sol = penumbra_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    expected_line L[8];
    double t = BLK_H / (SRC_H - BLK_H), worst = 0.0;
    uint32_t i, n = 0, on_floor = 0, others = 0;
    int k, axis, e;
    if (!sol) return;
    md.min_discont_weight = 1e-3f;   /* every discontinuity counts */
    md.min_leaf_area = 4.0f;         /* the floor alone: only the discontinuities matter here */
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    for (axis = 0; axis < 2; axis++)
        for (k = 0; k < 2; k++)
            for (e = 0; e < 2; e++) {
                double xs = k ? SRC_A : -SRC_A, xb = blk[axis + 2 * e];
                double o0 = blk[1 - axis], o1 = blk[3 - axis];
                L[n].axis = axis;
                L[n].at = xb + t * (xb - xs);
                L[n].lo = o0 + t * (o0 - SRC_A);
                L[n].hi = o1 + t * (o1 + SRC_A);
                L[n].covered_lo = 1e9;
                L[n].covered_hi = -1e9;
                L[n].hits = 0;
                n++;
            }
    for (i = 0; i < radinterp_mesh_discontinuity_count(m); i++) {
        radinterp_discontinuity d;
        uint32_t j, best = 0;
        double best_d = 1e9;
        radinterp_mesh_get_discontinuity(m, i, &d);
        if (d.receiver != 0) continue;
        if (d.type != RADINTERP_DISCONTINUITY_EV && d.type != RADINTERP_DISCONTINUITY_VE) { others++; continue; }
        on_floor++;
        for (j = 0; j < 8; j++) {
            double dd = fabs(d.a[L[j].axis] - L[j].at) + fabs(d.b[L[j].axis] - L[j].at);
            if (dd < best_d) { best_d = dd; best = j; }
        }
        {
            expected_line *l = &L[best];
            double u0 = d.a[1 - l->axis], u1 = d.b[1 - l->axis];
            double lo = u0 < u1 ? u0 : u1, hi = u0 < u1 ? u1 : u0;
            double err = fabs(d.a[l->axis] - l->at);
            err = fabs(d.b[l->axis] - l->at) > err ? fabs(d.b[l->axis] - l->at) : err;
            err = l->lo - lo > err ? l->lo - lo : err;   /* not past the extent */
            err = hi - l->hi > err ? hi - l->hi : err;
            worst = err > worst ? err : worst;
            CHECK_MSG(err < 1e-5, "discontinuity %u (%s) off its analytic line by %g", i,
                      d.type == RADINTERP_DISCONTINUITY_EV ? "EV" : "VE", err);
            CHECK(fabs(d.a[2]) < 1e-6 && fabs(d.b[2]) < 1e-6);
            if (lo < l->covered_lo) l->covered_lo = lo;
            if (hi > l->covered_hi) l->covered_hi = hi;
            l->hits++;
        }
    }
    CHECK_EQ_INT(others, 0);  /* no horizon, no contact on the floor */
    for (i = 0; i < 8; i++) {
        /* each boundary is found, over its whole extent (the pieces overlap) */
        CHECK_MSG(L[i].hits >= 2, "line %u (axis %d at %g) has %d discontinuities", i, L[i].axis, L[i].at, L[i].hits);
        CHECK_CLOSE(L[i].covered_lo, L[i].lo, 0, 1e-5);
        CHECK_CLOSE(L[i].covered_hi, L[i].hi, 0, 1e-5);
        if (fabs(L[i].covered_lo - L[i].lo) > worst) worst = fabs(L[i].covered_lo - L[i].lo);
        if (fabs(L[i].covered_hi - L[i].hi) > worst) worst = fabs(L[i].covered_hi - L[i].hi);
    }
    test_note("penumbra test: %u EV/VE discontinuities on the floor on 8 analytic lines, largest deviation %.2g m",
              on_floor, worst);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* Weights: geometric factor max(d_sb / d_br) times the source's radiosity.
   For the boundary at x = xb + t (xb - xs) the ratio is (H - h) / h along
   every ray, so every EV/VE weight on the floor is B_src (H - h) / h. */
static void test_weights(void)
{
    scene s;
    radinterp_solution *sol = penumbra_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    float src[3];
    uint32_t i, checked = 0;
    if (!sol) return;
    md.min_discont_weight = 1e-3f;
    md.min_leaf_area = 4.0f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    radinterp_patch_radiosity(sol, 1, src);
    for (i = 0; i < radinterp_mesh_discontinuity_count(m); i++) {
        radinterp_discontinuity d;
        radinterp_mesh_get_discontinuity(m, i, &d);
        if (d.receiver != 0) continue;
        CHECK_CLOSE(d.weight, src[0] * (SRC_H - BLK_H) / BLK_H, 1e-4, 0);
        CHECK(d.source == 1 && d.blocker == 2);
        checked++;
    }
    CHECK(checked > 0);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* EV/VE counts on the floor (receiver 0) by source and blocker patch. */
static uint32_t events_on_floor(const radinterp_mesh *m, uint32_t source, uint32_t blocker, int active_only)
{
    uint32_t i, n = 0;
    for (i = 0; i < radinterp_mesh_discontinuity_count(m); i++) {
        radinterp_discontinuity d;
        radinterp_mesh_get_discontinuity(m, i, &d);
        if (d.receiver != 0 || (d.type != RADINTERP_DISCONTINUITY_EV && d.type != RADINTERP_DISCONTINUITY_VE)) continue;
        if (d.source == source && d.blocker == blocker && (d.active || !active_only)) n++;
    }
    return n;
}

/* A candidate event must happen: the penumbra scene with a second, smaller
   blocker (patch 3) at height 0.4 under the first. Every line from the
   source through the small blocker's outline crosses z = 0.8 inside
   [-0.0625, 0.2125] x [-0.1375, 0.1], within the large blocker
   [-0.1, 0.3] x [-0.2, 0.15]: the small blocker stands in the large one's
   umbra and none of its events is seen, while the lines bounding the large
   one's penumbra pass beside it (at z = 0.4 they lie at x <= -0.2167 or
   x >= 0.483). Without the large blocker (the control) the small one casts
   its own shadow and its events are kept. */
static void test_hidden_events(void)
{
    int with_large;
    uint32_t small_events[2] = {0, 0}, large_events = 0, large_alone;
    scene s;
    radinterp_solution *sol;
    {   /* the large blocker's events with nothing else: the count to keep */
        radinterp_mesh_desc md = mesh_desc();
        radinterp_mesh *m = NULL;
        sol = penumbra_scene(&s);
        if (!sol) return;
        md.min_discont_weight = 1e-3f;
        md.min_leaf_area = 4.0f;
        CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
        large_alone = m ? events_on_floor(m, 1, 2, 0) : 0;
        radinterp_mesh_destroy(m);
        radinterp_solution_destroy(sol);
    }
    for (with_large = 0; with_large < 2; with_large++) {
        radinterp_desc d;
        radinterp_mesh_desc md = mesh_desc();
        radinterp_mesh *m = NULL;
        uint32_t grey, light;
        memset(&s, 0, sizeof s);
        grey = add_material(&s, 0.5f, 0.0f);
        light = add_material(&s, 0.0f, 100.0f);
        add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);                                                          /* 0 */
        add_hrect(&s, -(float)SRC_A, -(float)SRC_A, (float)SRC_A, (float)SRC_A, (float)SRC_H, 0, light);  /* 1 */
        add_hrect(&s, with_large ? (float)blk[0] : 1.5f, with_large ? (float)blk[1] : 1.5f,               /* 2 */
                  with_large ? (float)blk[2] : 1.6f, with_large ? (float)blk[3] : 1.6f, (float)BLK_H, 1, grey);
        add_hrect(&s, 0.0f, -0.1f, 0.2f, 0.05f, 0.4f, 1, grey);                                            /* 3 */
        d = scene_desc(&s);
        CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
        if (!sol) return;
        md.min_discont_weight = 1e-3f;
        md.min_leaf_area = 4.0f;
        CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
        if (m) {
            small_events[with_large] = events_on_floor(m, 1, 3, 0);
            if (with_large) large_events = events_on_floor(m, 1, 2, 0);
        }
        radinterp_mesh_destroy(m);
        radinterp_solution_destroy(sol);
    }
    CHECK_MSG(small_events[0] >= 8, "the small blocker alone casts %u events", small_events[0]);
    CHECK_EQ_INT(small_events[1], 0);
    CHECK_EQ_INT(large_events, large_alone);
    test_note("hidden events: the small blocker casts %u EV/VE alone and %u in the large one's umbra; the large "
              "one %u (%u alone)", small_events[0], small_events[1], large_events, large_alone);
}

/* min_discont_contrast: a second source (patch 3, beside the first) 1000
   times dimmer. Seen from the floor it reaches at most B F = 0.1 * 0.0195
   (F of a 0.5 m square 2 m straight above), about 0.0024 of the floor's mean
   irradiance (about 0.8 from the bright source), far below the default 1/32:
   its discontinuities are not candidates, while the bright source's are
   (B F up to 100 * 0.0195, 2.4 times the mean). FLT_MIN keeps both, as the
   thesis does. */
static void test_contrast(void)
{
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t grey, light, dim, pass, counts[2][2];
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 100.0f);
    dim = add_material(&s, 0.0f, 0.1f);
    add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);                                                          /* 0 */
    add_hrect(&s, -(float)SRC_A, -(float)SRC_A, (float)SRC_A, (float)SRC_A, (float)SRC_H, 0, light);  /* 1 */
    add_hrect(&s, (float)blk[0], (float)blk[1], (float)blk[2], (float)blk[3], (float)BLK_H, 1, grey); /* 2 */
    add_hrect(&s, 0.6f, -(float)SRC_A, 1.1f, (float)SRC_A, (float)SRC_H, 0, dim);                     /* 3 */
    d = scene_desc(&s);
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    if (!sol) return;
    for (pass = 0; pass < 2; pass++) {
        radinterp_mesh_desc md = mesh_desc();
        radinterp_mesh *m = NULL;
        md.min_discont_weight = 1e-3f;   /* the weight alone would keep both sources */
        md.min_leaf_area = 4.0f;
        md.min_discont_contrast = pass ? FLT_MIN : 0.0f;
        CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
        counts[pass][0] = m ? events_on_floor(m, 1, 2, 1) : 0;
        counts[pass][1] = m ? events_on_floor(m, 3, 2, 1) : 0;
        radinterp_mesh_destroy(m);
    }
    CHECK(counts[0][0] > 0 && counts[0][0] == counts[1][0]);
    CHECK_EQ_INT(counts[0][1], 0);
    CHECK(counts[1][1] > 0);
    test_note("contrast: active events of the bright / dim source %u / %u by default, %u / %u with FLT_MIN",
              counts[0][0], counts[0][1], counts[1][0], counts[1][1]);
    radinterp_solution_destroy(sol);
}

/* 5.4: the geometric factor is kept, the weight cached; it is recomputed
   once the solver has run again (new radiosities), not before. */
static void test_weight_cache(void)
{
    scene s;
    radinterp_solution *sol = penumbra_scene(&s);
    radinterp__disc d;
    float w0, w1;
    uint32_t root;
    if (!sol) return;
    memset(&d, 0, sizeof d);
    d.type = RADINTERP_DISCONTINUITY_EV;
    d.source = 1;
    d.geom = 1.5f;
    root = sol->patches[1].root;
    w0 = radinterp__disc_weight(sol, &d);
    CHECK_CLOSE(w0, 1.5 * sol->nodes[root].b[0], 1e-6, 0);
    sol->nodes[root].b[0] *= 2.0f;                       /* radiosities change ... */
    CHECK(radinterp__disc_weight(sol, &d) == w0);        /* ... but the cache is only invalidated by a new pass */
    sol->iterations++;
    w1 = radinterp__disc_weight(sol, &d);
    CHECK_CLOSE(w1, 2.0 * w0, 1e-6, 0);
    d.type = RADINTERP_DISCONTINUITY_CONTACT;
    d.weight_stamp = 0;
    CHECK(radinterp__disc_weight(sol, &d) == FLT_MAX);   /* contacts: infinite */
    radinterp_solution_destroy(sol);
}

/* Horizon and contact: a wall standing on the floor and a light facing the
   floor beside it. The wall's plane splits the floor (horizon, weight B_src
   = the wall's radiosity times 1) and its foot is a contact (FLT_MAX). */
static void test_horizon_and_contact(void)
{
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    uint32_t grey, light, i, horizon = 0, contact = 0;
    float wall[4][3] = {{0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {0.5f, 0.5f, 1}, {0.5f, -0.5f, 1}};  /* x = 0.5, facing -x */
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 50.0f);
    add_hrect(&s, -1, -1, 1, 1, 0, 1, grey);
    add_quad(&s, wall[0], wall[3], wall[2], wall[1], grey);
    add_hrect(&s, -0.3f, -0.2f, 0.1f, 0.2f, 1.5f, 0, light);
    d = scene_desc(&s);
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    if (!sol) return;
    md.min_discont_weight = 1e-3f;
    md.min_leaf_area = 1.0f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    for (i = 0; m && i < radinterp_mesh_discontinuity_count(m); i++) {
        radinterp_discontinuity dc;
        radinterp_mesh_get_discontinuity(m, i, &dc);
        if (dc.receiver != 0) continue;
        if (dc.type == RADINTERP_DISCONTINUITY_HORIZON) {
            float b[3];
            horizon++;
            CHECK(dc.source == 1);
            CHECK_CLOSE(dc.a[0], 0.5, 0, 1e-6);
            CHECK_CLOSE(dc.b[0], 0.5, 0, 1e-6);
            CHECK_CLOSE(fabs(dc.a[1] - dc.b[1]), 2.0, 0, 1e-6);   /* across the whole floor */
            radinterp_patch_radiosity(sol, 1, b);
            CHECK_CLOSE(dc.weight, b[0], 1e-5, 0);
        }
        if (dc.type == RADINTERP_DISCONTINUITY_CONTACT) {
            contact++;
            CHECK(dc.blocker == 1);
            CHECK_CLOSE(dc.a[0], 0.5, 0, 1e-6);
            CHECK_CLOSE(fabs(dc.a[1] - dc.b[1]), 1.0, 0, 1e-6);
            CHECK(dc.weight == FLT_MAX);
            CHECK(dc.active);                                   /* infinite weight: first in line */
        }
    }
    CHECK_EQ_INT(horizon, 1);
    CHECK_EQ_INT(contact, 1);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* ---- activation over the whole quadtree --------------------------------- */

/* Leaf corners and a segment in the leaf's patch plane (z = 0 here). Does
   the segment cross the leaf's interior shrunk by inset? Returns the
   parameters of the crossing piece. */
static int crosses_leaf(const radinterp_mesh_leaf *l, const float *a, const float *b, double inset, double *t0, double *t1)
{
    uint32_t i, n = l->vertex_count;
    *t0 = 0.0; *t1 = 1.0;
    for (i = 0; i < n; i++) {
        const float *p = l->vertices[i], *q = l->vertices[(i + 1) % n];
        double dx = q[0] - p[0], dy = q[1] - p[1], len = sqrt(dx * dx + dy * dy);
        double fa = (-dy * (a[0] - p[0]) + dx * (a[1] - p[1])) / len - inset;
        double fb = (-dy * (b[0] - p[0]) + dx * (b[1] - p[1])) / len - inset;
        if (fa < 0 && fb < 0) return 0;
        if (fa >= 0 && fb >= 0) continue;
        if (fa < 0) { double t = fa / (fa - fb); if (t > *t0) *t0 = t; }
        else { double t = fa / (fa - fb); if (t < *t1) *t1 = t; }
    }
    return *t1 > *t0;
}

/* Distance from p to the nearest discontinuity edge among a leaf's triangles. */
static double to_discontinuity_edge(const radinterp_mesh_data *md, const radinterp_mesh_leaf *l, const double *p)
{
    double best = 1e9;
    uint32_t t;
    int e;
    for (t = l->first_triangle; t < l->first_triangle + l->triangle_count; t++)
        for (e = 0; e < 3; e++) {
            const float *a, *b;
            double dx, dy, s, x, y, dd;
            if (!((md->edge_flags[t] >> (3 + e)) & 1)) continue;
            a = md->positions + 3 * (size_t)md->indices[3 * (size_t)t + (size_t)(e + 1) % 3];
            b = md->positions + 3 * (size_t)md->indices[3 * (size_t)t + (size_t)(e + 2) % 3];
            dx = b[0] - a[0]; dy = b[1] - a[1];
            s = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
            s = s < 0 ? 0 : (s > 1 ? 1 : s);
            x = a[0] + s * dx - p[0];
            y = a[1] + s * dy - p[1];
            dd = sqrt(x * x + y * y);
            best = dd < best ? dd : best;
        }
    return best;
}

static void test_activation_rules(void)
{
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    radinterp_mesh_data data;
    radinterp_mesh_info info;
    uint32_t grey, light, i, j, checked_pieces = 0, inactive_checked = 0, max_seen = 0;
    const uint32_t max_dsets = 3;
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 100.0f);
    add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);                    /* the receiver */
    add_hrect(&s, -0.3f, -0.3f, 0.3f, 0.3f, 2.0f, 0, light);
    add_hrect(&s, -0.4f, -0.5f, 0.1f, -0.1f, 0.6f, 1, grey);    /* three blockers at different heights */
    add_hrect(&s, 0.2f, 0.1f, 0.6f, 0.4f, 1.0f, 1, grey);
    add_hrect(&s, -0.7f, 0.3f, -0.3f, 0.9f, 0.3f, 1, grey);
    d = scene_desc(&s);
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    if (!sol) return;
    md.min_discont_weight = 1.0f;
    md.max_leaf_dsets = max_dsets;
    md.min_leaf_area = 0.2f;  /* a coarse tree: many discontinuities compete for each leaf */
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    radinterp_mesh_get_data(m, &data);
    radinterp_mesh_get_info(m, &info);
    CHECK(info.max_leaf_active_dsets <= max_dsets);
    CHECK(info.active_discontinuities > 0 && info.active_discontinuities < info.candidates);
    for (j = 0; j < radinterp_mesh_leaf_count(m); j++) {
        radinterp_mesh_leaf l;
        uint32_t dsets[64], nd = 0, k;
        radinterp_mesh_get_leaf(m, j, &l);
        if (l.patch != 0) continue;
        CHECK(l.active_dsets <= max_dsets);
        /* recount from the geometry: active DSets crossing the leaf (well inside) */
        for (i = 0; i < radinterp_mesh_discontinuity_count(m); i++) {
            radinterp_discontinuity dc;
            double t0, t1;
            radinterp_mesh_get_discontinuity(m, i, &dc);
            if (dc.receiver != 0 || !dc.active || !crosses_leaf(&l, dc.a, dc.b, 1e-4, &t0, &t1)) continue;
            for (k = 0; k < nd && dsets[k] != dc.dset; k++) {}
            if (k == nd && nd < 64) dsets[nd++] = dc.dset;
        }
        CHECK_MSG(nd <= max_dsets, "leaf %u: %u active DSets cross it", j, nd);
        if (nd > max_seen) max_seen = nd;
    }
    for (i = 0; i < radinterp_mesh_discontinuity_count(m); i++) {
        radinterp_discontinuity dc;
        int blocked = 0, crossed = 0;
        radinterp_mesh_get_discontinuity(m, i, &dc);
        if (dc.receiver != 0) continue;
        for (j = 0; j < radinterp_mesh_leaf_count(m); j++) {
            radinterp_mesh_leaf l;
            double t0, t1;
            radinterp_mesh_get_leaf(m, j, &l);
            if (l.patch != 0) continue;
            if (!crosses_leaf(&l, dc.a, dc.b, 1e-4, &t0, &t1)) {
                /* crossing it within the library's tolerance only: it may still count there */
                if (!dc.active && crosses_leaf(&l, dc.a, dc.b, 0.0, &t0, &t1) && l.active_dsets == max_dsets) blocked = 1;
                continue;
            }
            crossed = 1;
            if (dc.active) {
                /* in every leaf it crosses: its piece there lies on discontinuity edges */
                int q;
                for (q = 0; q <= 8; q++) {
                    double u = t0 + (t1 - t0) * q / 8.0, p[2];
                    p[0] = dc.a[0] + u * (dc.b[0] - dc.a[0]);
                    p[1] = dc.a[1] + u * (dc.b[1] - dc.a[1]);
                    CHECK_MSG(to_discontinuity_edge(&data, &l, p) < 1e-5, "active discontinuity %u missing from leaf %u", i, j);
                }
                checked_pieces++;
            } else if (l.active_dsets == max_dsets) {
                blocked = 1;
            }
        }
        if (!dc.active && dc.weight >= md.min_discont_weight && crossed) {
            /* greedy by weight: it stayed out only because a leaf was full */
            CHECK_MSG(blocked, "inactive discontinuity %u (weight %g) crosses no full leaf", i, dc.weight);
            inactive_checked++;
        }
    }
    CHECK(checked_pieces > 0 && inactive_checked > 0);
    test_note("activation: %u candidates, %u active, max %u active DSets per leaf (limit %u); %u leaf pieces of "
              "active discontinuities found in the triangulations, %u inactive ones blocked by a full leaf",
              info.candidates, info.active_discontinuities, max_seen, max_dsets, checked_pieces, inactive_checked);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* ---- crack-free output ---------------------------------------------------- */

/* A room (floor, four walls) with a block on the floor and a light: the
   patches meet along their edges, and the block's foot is a contact. */
static radinterp_solution *room_scene(scene *s)
{
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t grey, light;
    memset(s, 0, sizeof *s);
    grey = add_material(s, 0.6f, 0.0f);
    light = add_material(s, 0.0f, 30.0f);
    add_room(s, 0, 0, 0, 2, 1.5f, 1.2f, grey);
    add_block(s, 0.6f, 0.4f, 0, 1.1f, 0.9f, 0.45f, grey);
    add_hrect(s, 0.8f, 0.5f, 1.4f, 1.0f, 1.2f, 0, light);
    d = scene_desc(s);
    d.eps = 0.5f;
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    return sol;
}

/* Squared distance from x to the segment (a, b) and its position t along it. */
static double edge_distance2(const float *a, const float *b, const float *x, double *t)
{
    double d[3], e[3], l2 = 0, dist2 = 0, u;
    int j;
    for (j = 0; j < 3; j++) { d[j] = (double)b[j] - a[j]; e[j] = (double)x[j] - a[j]; l2 += d[j] * d[j]; }
    *t = (d[0] * e[0] + d[1] * e[1] + d[2] * e[2]) / l2;
    u = *t < 0 ? 0 : (*t > 1 ? 1 : *t);
    for (j = 0; j < 3; j++) dist2 += (e[j] - u * d[j]) * (e[j] - u * d[j]);
    return dist2;
}

/* Vertices on the outline of their patch's triangles (an edge no other
   triangle of the patch shares). */
static unsigned char *outline_vertices(const radinterp_mesh_data *md)
{
    unsigned char *on = (unsigned char *)calloc(md->vertex_count, 1);
    uint32_t t, u, e, f;
    for (t = 0; t < md->triangle_count; t++)
        for (e = 0; e < 3; e++) {
            uint32_t a = md->indices[3 * t + (e + 1) % 3], b = md->indices[3 * t + (e + 2) % 3];
            int shared = 0;
            for (u = 0; u < md->triangle_count && !shared; u++) {
                if (u == t || md->triangle_patch[u] != md->triangle_patch[t]) continue;
                for (f = 0; f < 3; f++)
                    if (md->indices[3 * u + (f + 1) % 3] == b && md->indices[3 * u + (f + 2) % 3] == a) shared = 1;
            }
            if (!shared) on[a] = on[b] = 1;
        }
    return on;
}

/* Appends a triangulation of the polygon ring[0..nr) (positions in pos,
   counter-clockwise seen from the front n) to idx: the constrained Delaunay
   triangulation of part 1, so that its triangles are as well shaped as the
   polygon allows (a fan from one point would be slivers along rows of close
   vertices, which the rasterizer's 1/256-pixel snapping can fold over). */
static int triangulate_ring(const float *pos, const uint32_t *ring, uint32_t nr, const double *n, uint32_t *idx,
                            uint32_t *nt)
{
    radinterp__cdt c;
    radinterp_allocator a;
    double *xy = (double *)malloc(sizeof(double) * 2 * nr), e1[3], e2[3], len;
    uint32_t *ids = (uint32_t *)malloc(sizeof(uint32_t) * nr), *back, i, t, *stack, top = 0;
    unsigned char *inside;
    const float *o = pos + 3 * ring[0], *p1 = pos + 3 * ring[1];
    int k, ok = 1;
    for (k = 0; k < 3; k++) e1[k] = (double)p1[k] - o[k];
    len = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (k = 0; k < 3; k++) e1[k] /= len;
    e2[0] = n[1] * e1[2] - n[2] * e1[1];
    e2[1] = n[2] * e1[0] - n[0] * e1[2];
    e2[2] = n[0] * e1[1] - n[1] * e1[0];
    for (i = 0; i < nr; i++) {
        const float *x = pos + 3 * ring[i];
        double d[3];
        for (k = 0; k < 3; k++) d[k] = (double)x[k] - o[k];
        xy[2 * i] = d[0] * e1[0] + d[1] * e1[1] + d[2] * e1[2];
        xy[2 * i + 1] = d[0] * e2[0] + d[1] * e2[1] + d[2] * e2[2];
    }
    memset(&a, 0, sizeof a);
    radinterp__cdt_init(&c, &a, NULL, 0);
    if (radinterp__cdt_add_points(&c, xy, nr, ids) != 0) ok = 0;
    for (i = 0; i < nr && ok; i++)
        if (ids[i] != ids[(i + 1) % nr] && radinterp__cdt_add_segment(&c, ids[i], ids[(i + 1) % nr]) != 0) ok = 0;
    if (ok && c.vertex_count != nr) ok = 0;   /* the ring crossed itself */
    back = (uint32_t *)malloc(sizeof(uint32_t) * (nr + 1));
    inside = (unsigned char *)malloc(c.tri_count + 1);
    stack = (uint32_t *)malloc(sizeof(uint32_t) * (c.tri_count + 1));
    for (i = 0; i < nr; i++) back[ids[i]] = ring[i];
    for (t = 0; t < c.tri_count; t++) {
        inside[t] = (unsigned char)radinterp__cdt_is_real(&c, t);
        if (!inside[t]) stack[top++] = t;
    }
    while (top) {  /* outside: reachable from the hull without crossing the ring */
        t = stack[--top];
        for (k = 0; k < 3; k++) {
            uint32_t u = c.tri[t].n[k];
            if (((c.tri[t].flags >> k) & 1u) || !inside[u]) continue;
            inside[u] = 0;
            stack[top++] = u;
        }
    }
    for (t = 0; t < c.tri_count && ok; t++) {
        if (!inside[t]) continue;
        for (k = 0; k < 3; k++) idx[3 * *nt + k] = back[c.tri[t].v[k]];
        (*nt)++;
    }
    radinterp__cdt_free(&c);
    free(xy); free(ids); free(back); free(inside); free(stack);
    return ok;
}

/* Every pixel is covered by the mesh as often as by the patches drawn
   plainly, each as a polygon through its corners and every vertex of any
   patch's mesh outline that lies on its edges (found here geometrically,
   each on its nearest edge). Where patches share an edge their plain
   outlines are then the same, so the plain drawing covers each pixel once
   per layer; a crack or an overlap in the mesh (a T-vertex inside a patch,
   or a seam whose two sides differ) changes the count. */
static int coverage_matches(const scene *s, const radinterp_mesh_data *md, const unsigned char *on_outline,
                            const ex_camera *cam, ex_raster *r, long *pixels)
{
    uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * 3 * (md->vertex_count * 4 + 64));
    uint32_t *mesh_count, p, nt = 0, *ring = (uint32_t *)malloc(sizeof(uint32_t) * (md->vertex_count + 4));
    double *ts = (double *)malloc(sizeof(double) * (md->vertex_count + 4));
    size_t i, n = (size_t)r->width * (size_t)r->height;
    int ok = 1;
    for (p = 0; p < s->np; p++) {
        uint32_t c = s->patch[4 * p + 3] == RADINTERP_NO_VERTEX ? 3 : 4, k, v, nr = 0;
        double nrm[3] = {0, 0, 0}, len;
        for (k = 0; k < c; k++) {
            const float *a = s->pos + 3 * s->patch[4 * p + k], *b = s->pos + 3 * s->patch[4 * p + (k + 1) % c];
            uint32_t first = nr, q;
            nrm[0] += ((double)a[1] - b[1]) * ((double)a[2] + b[2]);
            nrm[1] += ((double)a[2] - b[2]) * ((double)a[0] + b[0]);
            nrm[2] += ((double)a[0] - b[0]) * ((double)a[1] + b[1]);
            for (v = 0; v < md->vertex_count; v++) {  /* outline vertices on this edge, by position along it */
                const float *x = md->positions + 3 * v;
                double t, dist2 = edge_distance2(a, b, x, &t), other_t;
                uint32_t j;
                int nearest = 1;
                if (!on_outline[v] || t < -1e-9 || t >= 1.0 - 1e-9 || dist2 > 1e-11) continue;
                for (j = 0; j < c; j++)
                    if (j != k && edge_distance2(s->pos + 3 * s->patch[4 * p + j], s->pos + 3 * s->patch[4 * p + (j + 1) % c], x,
                                                 &other_t) < dist2)
                        nearest = 0;
                if (!nearest) continue;
                for (q = nr; q > first && ts[q - 1] > t; q--) { ts[q] = ts[q - 1]; ring[q] = ring[q - 1]; }
                ts[q] = t;
                ring[q] = v;
                nr++;
            }
        }
        len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        nrm[0] /= len; nrm[1] /= len; nrm[2] /= len;
        if (nr < 3 || !triangulate_ring(md->positions, ring, nr, nrm, idx, &nt)) ok = 0;
    }
    mesh_count = (uint32_t *)malloc(sizeof(uint32_t) * n);
    memset(r->coverage, 0, n * sizeof(uint32_t));
    ex_raster_count(r, cam, md->positions, md->indices, md->triangle_count);
    memcpy(mesh_count, r->coverage, n * sizeof(uint32_t));
    memset(r->coverage, 0, n * sizeof(uint32_t));
    ex_raster_count(r, cam, md->positions, idx, nt);
    for (i = 0; i < n; i++) {
        if (r->coverage[i]) (*pixels)++;
        if (mesh_count[i] != r->coverage[i]) ok = 0;
    }
    free(idx);
    free(ring);
    free(ts);
    free(mesh_count);
    return ok;
}

static void test_crack_free_room(void)
{
    scene s;
    radinterp_solution *sol = room_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    radinterp_mesh_data data;
    radinterp_mesh_info info;
    ex_raster r;
    long pixels = 0;
    int c, bad = 0;
    unsigned char *on;
    if (!sol) return;
    md.min_discont_weight = 0.05f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    radinterp_mesh_get_data(m, &data);
    radinterp_mesh_get_info(m, &info);
    CHECK(info.hanging_vertices > 0);     /* case A occurred and was closed */
    CHECK(info.seam_vertices > 0);        /* case C occurred and was closed */
    CHECK(info.active_discontinuities > 0);
    CHECK_EQ_INT(info.fallback_patches, 0);
    if (ex_raster_init(&r, 160, 120) != 0) { CHECK(0); return; }
    on = outline_vertices(&data);
    for (c = 0; c < 6; c++) {
        float eye[3], target[3] = {1.0f, 0.75f, 0.3f}, up[3] = {0, 0, 1};
        ex_camera cam;
        double a = 0.9 + c * 1.1;
        eye[0] = (float)(1.0 + 0.8 * cos(a));
        eye[1] = (float)(0.75 + 0.6 * sin(a));
        eye[2] = (float)(0.6 + 0.1 * c);
        cam = ex_camera_look_at(eye, target, up, 70.0f, 160, 120);
        if (!coverage_matches(&s, &data, on, &cam, &r, &pixels)) bad++;
    }
    CHECK_MSG(bad == 0, "%d of 6 views have cracks or overlaps", bad);
    test_note("crack-free room: %u triangles, %u T-vertices closed inside patches, %u seam vertices; %ld covered "
              "pixels over 6 views, %d views with a mismatch", info.triangle_count, info.hanging_vertices,
              info.seam_vertices, pixels, bad);
    free(on);
    ex_raster_free(&r);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* Is corner k of triangle t at a vertex on a contact discontinuity (an end of
   an edge on one of any listed triangle, on_disc)? */
static int own_corner(const radinterp__otri *t, uint32_t k, const unsigned char *on_disc)
{
    return on_disc[t->v[k]] != 0;
}

/* Do triangles t and u share an edge through corner k of t that lies on no
   contact discontinuity in either? */
static int sector_neighbours(const radinterp__otri *t, uint32_t k, const radinterp__otri *u)
{
    uint32_t e, f;
    if (t->patch != u->patch) return 0;
    for (e = 0; e < 3; e++) {   /* edge e of t: corners e + 1, e + 2 */
        uint32_t a = t->v[(e + 1) % 3], c = t->v[(e + 2) % 3];
        if (e == k || (t->flags & (RADINTERP__EDGE_JUMP << e))) continue;
        for (f = 0; f < 3; f++) {
            uint32_t x = u->v[(f + 1) % 3], y = u->v[(f + 2) % 3];
            if (((x == a && y == c) || (x == c && y == a)) && !(u->flags & (RADINTERP__EDGE_JUMP << f))) return 1;
        }
    }
    return 0;
}

/* Samples at vertices on a contact discontinuity, one per side of it
   (radinterp__disc_sectors): in the room with a block on the floor, the
   sectors of the triangles around each such vertex are found here by a
   flood across the edges through it that lie on no contact discontinuity.
   Two corners there must share their sample exactly when they are of one
   sector, taken toward the centre of its first triangle (in list order);
   the other samples are as before, one per vertex and edge of a patch but
   one per triangle at the midpoint of an edge on the discontinuity, so the
   count of points is known. Some sectors must hold several triangles and
   some vertices several sectors (both sides of the block's foot). */
static void test_disc_sectors(void)
{
    scene s;
    radinterp_solution *sol = room_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp__builder b;
    radinterp__buf pts;
    const radinterp__otri *tris;
    const radinterp__spoint *sp;
    const float *pos;
    uint32_t n, i, k, j, e, *list = NULL, *tri_pt = NULL, *label = NULL, *stack = NULL, sectors = 0, shared_corners = 0;
    uint32_t plain = 0, own_edges = 0, split_vertices = 0, wrong_share = 0, wrong_toward = 0;
    unsigned char *on_disc = NULL;
    if (!sol) return;
    md.min_discont_weight = 0.05f;
    radinterp__buf_init(&pts, sizeof(radinterp__spoint));
    if (!CHECK_EQ_INT(radinterp__builder_init(&b, sol, &md), RADINTERP_OK) ||
        !CHECK_EQ_INT(radinterp__find_discontinuities(&b), RADINTERP_OK) ||
        !CHECK_EQ_INT(radinterp__build_trees(&b), RADINTERP_OK) || !CHECK_EQ_INT(radinterp__mesh_pass(&b), RADINTERP_OK))
        goto done;
    tris = (const radinterp__otri *)b.tris.data;
    pos = (const float *)b.pos.data;
    n = (uint32_t)b.tris.count;
    list = (uint32_t *)malloc(sizeof(uint32_t) * (n + 1));
    tri_pt = (uint32_t *)malloc(sizeof(uint32_t) * (6 * n + 1));
    label = (uint32_t *)malloc(sizeof(uint32_t) * (3 * n + 1));
    stack = (uint32_t *)malloc(sizeof(uint32_t) * (3 * n + 1));
    on_disc = (unsigned char *)calloc(b.pos.count / 3 + 1, 1);
    if (!CHECK(list && tri_pt && label && stack && on_disc)) goto done;
    for (i = 0; i < n; i++) list[i] = i;
    for (i = 0; i < n; i++)
        for (e = 0; e < 3; e++)
            if (tris[i].flags & (RADINTERP__EDGE_JUMP << e)) on_disc[tris[i].v[(e + 1) % 3]] = on_disc[tris[i].v[(e + 2) % 3]] = 1;
    if (!CHECK_EQ_INT(radinterp__sample_points(&b, list, n, &pts, tri_pt), 0)) goto done;
    sp = (const radinterp__spoint *)pts.data;
    /* sectors by flood fill; label = the sector's first corner 3 i + k (i in list order) */
    for (i = 0; i < 3 * n; i++) label[i] = RADINTERP__NONE;
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) {
            uint32_t top = 0, size = 0;
            if (!own_corner(&tris[i], k, on_disc) || label[3 * i + k] != RADINTERP__NONE) continue;
            label[3 * i + k] = 3 * i + k;
            stack[top++] = 3 * i + k;
            sectors++;
            while (top) {
                uint32_t c = stack[--top], t = c / 3, v = tris[t].v[c % 3];
                size++;
                for (j = 0; j < n; j++)
                    for (e = 0; e < 3; e++)
                        if (tris[j].v[e] == v && label[3 * j + e] == RADINTERP__NONE &&
                            sector_neighbours(&tris[t], c % 3, &tris[j])) {
                            label[3 * j + e] = 3 * i + k;
                            stack[top++] = 3 * j + e;
                        }
            }
            if (size > 1) shared_corners += size;
        }
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) {
            uint32_t c = 3 * i + k, first, t0;
            float toward[3];
            if (label[c] == RADINTERP__NONE) continue;
            first = label[c];
            t0 = first / 3;
            if (tri_pt[6 * i + 2 * k] != tri_pt[6 * t0 + 2 * (first % 3)]) wrong_share++;
            for (j = 0; j < n; j++)   /* corners of other sectors at the same vertex and patch: other samples */
                for (e = 0; e < 3; e++)
                    if (tris[j].v[e] == tris[i].v[k] && tris[j].patch == tris[i].patch && label[3 * j + e] != first &&
                        tri_pt[6 * j + 2 * e] == tri_pt[6 * i + 2 * k])
                        wrong_share++;
            radinterp__point_in(pos + 3 * tris[t0].v[0], pos + 3 * tris[t0].v[1], pos + 3 * tris[t0].v[2], 1.0 / 3.0,
                                1.0 / 3.0, toward);
            if (memcmp(sp[tri_pt[6 * i + 2 * k]].toward, toward, sizeof toward) != 0) wrong_toward++;
            if (first != c) continue;
            for (j = 0; j < i; j++)   /* a vertex with a sector before this one: sides apart */
                for (e = 0; e < 3; e++)
                    if (tris[j].v[e] == tris[i].v[k] && tris[j].patch == tris[i].patch && label[3 * j + e] != first &&
                        label[3 * j + e] != RADINTERP__NONE && label[3 * j + e] / 3 == j && label[3 * j + e] % 3 == e) {
                        split_vertices++;
                        j = i;
                        break;
                    }
        }
    /* the other points: distinct (vertex, patch) off the discontinuities and (edge, patch) off them, and each
       triangle's own midpoint of an edge on one */
    for (i = 0; i < n; i++)
        for (e = 0; e < 3; e++) {
            uint32_t a = tris[i].v[e], c = tris[i].v[(e + 1) % 3], u;
            int seen = 0;
            if (!on_disc[a]) {
                for (j = 0; j < i && !seen; j++)
                    for (u = 0; u < 3; u++)
                        if (tris[j].v[u] == a && tris[j].patch == tris[i].patch) seen = 1;
                plain += !seen;
            }
            seen = 0;
            if (tris[i].flags & (RADINTERP__EDGE_JUMP << ((e + 2) % 3))) { own_edges++; continue; }
            for (j = 0; j < i && !seen; j++)
                for (u = 0; u < 3; u++) {
                    uint32_t x = tris[j].v[u], y = tris[j].v[(u + 1) % 3];
                    if (tris[j].patch == tris[i].patch && ((x == a && y == c) || (x == c && y == a)) &&
                        !(tris[j].flags & (RADINTERP__EDGE_JUMP << ((u + 2) % 3))))
                        seen = 1;
                }
            plain += !seen;
        }
    CHECK_MSG(wrong_share == 0, "%u corners at a contact discontinuity share a sample across sectors or miss "
              "their sector's", wrong_share);
    CHECK_MSG(wrong_toward == 0, "%u samples not taken toward their sector's first triangle", wrong_toward);
    CHECK_EQ_INT(pts.count, plain + own_edges + sectors);
    CHECK(shared_corners > 0);
    CHECK(split_vertices > 0);
    test_note("contact sectors: %u triangles, %u samples (%u at vertices and edges off contact discontinuities, %u "
              "midpoints of edges on them, %u sectors); %u corners in sectors of several, %u vertices with two or "
              "more sectors", n, (unsigned)pts.count, plain, own_edges, sectors, shared_corners, split_vertices);
done:
    free(list);
    free(tri_pt);
    free(label);
    free(stack);
    free(on_disc);
    radinterp__buf_free(&b.a, &pts);
    radinterp__builder_free(&b);
    radinterp_solution_destroy(sol);
}

/* ---- online phase ------------------------------------------------------------ */

static void test_shading(void)
{
    scene s;
    radinterp_solution *sol = room_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    radinterp_mesh_data data;
    const size_t n = 5000;
    uint32_t *ids = (uint32_t *)malloc(n * sizeof(uint32_t));
    float *st = (float *)malloc(2 * n * sizeof(float)), *rgb = (float *)malloc(3 * n * sizeof(float));
    float *rgb2 = (float *)malloc(3 * n * sizeof(float)), *gou = (float *)malloc(3 * n * sizeof(float));
    ex_pool *pool = ex_pool_create(3);
    size_t i;
    int ok = 1, gok = 1, same = 1, untouched = 1;
    if (!sol) return;
    md.min_leaf_area = 0.05f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    radinterp_mesh_get_data(m, &data);
    for (i = 0; i < n; i++) {
        double a = rnd(), b = rnd();
        if (a + b > 1) { a = 1 - a; b = 1 - b; }
        ids[i] = i % 10 == 9 ? RADINTERP_NO_TRIANGLE : (i % 10 == 8 ? data.triangle_count + 5 : (uint32_t)(rnd() * data.triangle_count));
        st[2 * i] = (float)a;
        st[2 * i + 1] = (float)b;
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = -7.0f;
        gou[3 * i] = gou[3 * i + 1] = gou[3 * i + 2] = -7.0f;
    }
    CHECK_EQ_INT(radinterp_shade(m, ids, st, n, rgb), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_shade_gouraud(m, ids, st, n, gou), RADINTERP_OK);
    for (i = 0; i < n; i++) {
        float e[3], h[3];
        int k;
        if (ids[i] >= data.triangle_count) {
            untouched &= rgb[3 * i] == -7.0f && gou[3 * i + 2] == -7.0f;  /* other ids are left alone */
            continue;
        }
        radinterp_eval(m, ids[i], st[2 * i], st[2 * i + 1], e);
        radinterp_eval_irradiance(m, ids[i], st[2 * i], st[2 * i + 1], h);
        for (k = 0; k < 3; k++) {
            const float *c = data.corner_radiosity + 9 * (size_t)ids[i];
            float w = 1.0f - st[2 * i] - st[2 * i + 1];
            float g = w * c[k] + st[2 * i] * c[3 + k] + st[2 * i + 1] * c[6 + k];
            float b = data.emission[3 * (size_t)ids[i] + k] + data.reflectance[3 * (size_t)ids[i] + k] * h[k];
            /* same polynomial, evaluated in another order: float rounding */
            if (fabsf(rgb[3 * i + k] - (e[k] > 0 ? e[k] : 0)) > 1e-5f * (1 + fabsf(e[k]))) ok = 0;
            if (fabsf(e[k] - b) > 1e-4f * (1 + fabsf(b))) ok = 0;
            if (fabsf(gou[3 * i + k] - (g > 0 ? g : 0)) > 1e-5f * (1 + fabsf(g))) gok = 0;
        }
    }
    CHECK(ok && gok && untouched);
    /* a corner's Gouraud value is the interpolant there */
    {
        float e[3];
        radinterp_eval(m, 0, 1.0f, 0.0f, e);
        CHECK_CLOSE(data.corner_radiosity[3], e[0], 1e-5, 1e-6);
    }
    /* the same with a pool: identical bits */
    radinterp_mesh_set_parallel_for(m, ex_pool_parallel_for, pool);
    memcpy(rgb2, rgb, 3 * n * sizeof(float));
    CHECK_EQ_INT(radinterp_shade(m, ids, st, n, rgb2), RADINTERP_OK);
    for (i = 0; i < 3 * n; i++) same &= rgb[i] == rgb2[i];
    CHECK(same);
    CHECK_EQ_INT(radinterp_shade(NULL, ids, st, n, rgb), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_shade(m, NULL, st, n, rgb), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_shade(m, ids, st, 0, rgb), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_eval(m, data.triangle_count, 0, 0, rgb), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_eval(m, 0, 0, 0, NULL), RADINTERP_ERROR_INVALID_ARGUMENT);
    /* vertex radiosity: the mean of the corners sharing the vertex */
    {
        uint32_t v = data.indices[0], t, k, uses = 0;
        double sum = 0;
        for (t = 0; t < data.triangle_count; t++)
            for (k = 0; k < 3; k++)
                if (data.indices[3 * t + k] == v) { sum += data.corner_radiosity[9 * t + 3 * k]; uses++; }
        CHECK_CLOSE(data.vertex_radiosity[3 * v], sum / uses, 1e-5, 1e-6);
    }
    free(ids); free(st); free(rgb); free(rgb2); free(gou);
    ex_pool_destroy(pool);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* The interpolants against IrradianceAtPoint on an unoccluded floor (smooth
   irradiance): quadratic pieces fit it closely, and far better than
   the constant radiosity of the leaves. */
static void test_interpolant_accuracy(void)
{
    scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    radinterp_mesh_data data;
    uint32_t grey, light, t;
    double worst = 0, peak = 0;
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.0f, 100.0f);
    add_hrect(&s, -2, -2, 2, 2, 0, 1, grey);
    add_hrect(&s, -0.2f, -0.2f, 0.2f, 0.2f, 1.0f, 0, light);
    d = scene_desc(&s);
    /* the thesis's absolute transport bound at half the mean emitted
       radiosity: a coarse solution, so that the representation-based
       refinement below has leaves to split */
    d.eps = 0.5f;
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    if (!sol) return;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    radinterp_mesh_get_data(m, &data);
    for (t = 0; t < data.triangle_count; t++) {
        const float *a = data.positions + 3 * (size_t)data.indices[3 * t], *b = data.positions + 3 * (size_t)data.indices[3 * t + 1];
        const float *c = data.positions + 3 * (size_t)data.indices[3 * t + 2];
        float p[3], h[3], e[3], u = 0.2f + 0.3f * (float)rnd(), v = 0.2f + 0.3f * (float)rnd();
        int k;
        if (data.triangle_patch[t] != 0) continue;
        for (k = 0; k < 3; k++) p[k] = a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]);
        radinterp_irradiance_at_point(sol, 0, p, NULL, h);
        radinterp_eval_irradiance(m, t, u, v, e);
        if (fabs(e[0] - h[0]) > worst) worst = fabs(e[0] - h[0]);
        if (h[0] > peak) peak = h[0];
    }
    /* quadratic pieces over the solver's leaves: within 1% of the peak */
    CHECK_MSG(worst < 0.01 * peak, "interpolants miss by %g (peak %g)", worst, peak);
    test_note("unoccluded floor: interpolants within %.3g%% of the peak irradiance (%u triangles)", 100 * worst / peak,
              data.triangle_count);
    radinterp_mesh_destroy(m);
    /* representation-based refinement to a tighter bound */
    md.refine = 1;
    md.refine_eps = (float)(0.002 * peak);
    md.refine_samples = 2;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (m) {
        radinterp_mesh_info info;
        uint32_t j, over = 0;
        radinterp_mesh_get_info(m, &info);
        CHECK(info.refine_passes >= 2 && info.refined_leaves > 0);
        for (j = 0; j < radinterp_mesh_leaf_count(m); j++) {
            radinterp_mesh_leaf l;
            radinterp_mesh_get_leaf(m, j, &l);
            CHECK(l.error >= 0.0f);
            over += l.error > md.refine_eps;
        }
        test_note("refinement to %.3g W/m^2: %u passes, %u leaves split, %u leaves, %u still above (at the pass limit "
                  "or the minimum area)", md.refine_eps, info.refine_passes, info.refined_leaves, info.leaf_count, over);
        radinterp_mesh_destroy(m);
    }
    radinterp_solution_destroy(sol);
}

/* ---- save / load ------------------------------------------------------------- */

typedef struct mem_reader { const unsigned char *data; size_t size, pos; } mem_reader;
static int read_mem(void *user, void *bytes, size_t n)
{
    mem_reader *r = (mem_reader *)user;
    if (n > r->size - r->pos) return -1;
    memcpy(bytes, r->data + r->pos, n);
    r->pos += n;
    return 0;
}
static int failing_write(void *user, const void *bytes, size_t n)
{
    (void)user; (void)bytes; (void)n;
    return -1;
}

/* A floor under a light with one blocker: a small mesh with a few
   discontinuities, so that every truncation length can be tried. */
static radinterp_solution *small_scene(scene *s)
{
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t grey, light;
    memset(s, 0, sizeof *s);
    grey = add_material(s, 0.5f, 0.0f);
    light = add_material(s, 0.0f, 100.0f);
    add_hrect(s, 0, 0, 1, 1, 0, 1, grey);
    add_hrect(s, 0.4f, 0.4f, 0.6f, 0.6f, 1.0f, 0, light);
    add_hrect(s, 0.3f, 0.45f, 0.5f, 0.65f, 0.4f, 1, grey);
    d = scene_desc(s);
    d.eps = 5.0f;
    CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK);
    return sol;
}

static void test_save_load(void)
{
    scene s;
    radinterp_solution *sol = small_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL, *back = NULL;
    radinterp_mesh_data a, b;
    void *bytes = NULL, *bytes2 = NULL;
    size_t size = 0, size2 = 0, cut;
    int k, corrupt_ok = 1, flips_ok = 1;
    if (!sol) return;
    md.min_discont_weight = 1.0f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (!m) { radinterp_solution_destroy(sol); return; }
    radinterp_mesh_get_data(m, &a);
    CHECK_EQ_INT(radinterp_mesh_save_to_memory(m, NULL, &bytes, &size), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_mesh_load_from_memory(bytes, size, NULL, &back), RADINTERP_OK);
    if (back) {
        radinterp_mesh_info ia, ib;
        radinterp_mesh_get_data(back, &b);
        CHECK_EQ_INT(a.triangle_count, b.triangle_count);
        CHECK_EQ_INT(a.vertex_count, b.vertex_count);
        CHECK(memcmp(a.positions, b.positions, 12 * (size_t)a.vertex_count) == 0);
        CHECK(memcmp(a.indices, b.indices, 12 * (size_t)a.triangle_count) == 0);
        CHECK(memcmp(a.coefficients, b.coefficients, 72 * (size_t)a.triangle_count) == 0);
        CHECK(memcmp(a.corner_radiosity, b.corner_radiosity, 36 * (size_t)a.triangle_count) == 0);
        CHECK(memcmp(a.edge_flags, b.edge_flags, a.triangle_count) == 0);
        radinterp_mesh_get_info(m, &ia);
        radinterp_mesh_get_info(back, &ib);
        CHECK_EQ_INT(ia.active_discontinuities, ib.active_discontinuities);
        CHECK_EQ_INT(radinterp_mesh_leaf_count(back), radinterp_mesh_leaf_count(m));
        CHECK_EQ_INT(radinterp_mesh_discontinuity_count(back), radinterp_mesh_discontinuity_count(m));
        CHECK_EQ_INT(radinterp_mesh_save_to_memory(back, NULL, &bytes2, &size2), RADINTERP_OK);
        CHECK(size2 == size && bytes2 && memcmp(bytes, bytes2, size) == 0);
        radinterp_free_memory(NULL, bytes2);
        radinterp_mesh_destroy(back);
    }
    /* every truncation length is corrupt data */
    for (cut = 0; cut < size; cut++) {
        radinterp_result r = radinterp_mesh_load_from_memory(bytes, cut, NULL, &back);
        if (r != RADINTERP_ERROR_CORRUPT_DATA || back) { corrupt_ok = 0; radinterp_mesh_destroy(back); }
    }
    CHECK_MSG(corrupt_ok, "a truncated mesh was not rejected as corrupt");
    {   /* a byte after the CRC is left alone: the same object loads */
        unsigned char *longer = test_with_byte_after(bytes, size);
        void *again = NULL;
        size_t again_size = 0;
        if (CHECK(longer != NULL) && CHECK_EQ_INT(radinterp_mesh_load_from_memory(longer, size + 1, NULL, &back), RADINTERP_OK) &&
            CHECK_EQ_INT(radinterp_mesh_save_to_memory(back, NULL, &again, &again_size), RADINTERP_OK))
            CHECK(again_size == size && memcmp(again, bytes, size) == 0);
        radinterp_free_memory(NULL, again);
        radinterp_mesh_destroy(back);
        free(longer);
    }
    /* random bit flips: corrupt (or, in the version field, a version error) */
    for (k = 0; k < 3000; k++) {
        unsigned char *copy = (unsigned char *)malloc(size);
        size_t at = (size_t)(rnd() * size);
        radinterp_result r;
        memcpy(copy, bytes, size);
        copy[at] ^= (unsigned char)(1u << (int)(rnd() * 8));
        r = radinterp_mesh_load_from_memory(copy, size, NULL, &back);
        if ((r != RADINTERP_ERROR_CORRUPT_DATA && r != RADINTERP_ERROR_VERSION) || back) {
            flips_ok = 0;
            radinterp_mesh_destroy(back);
        }
        free(copy);
    }
    CHECK(flips_ok);
    {
        mem_reader rd;
        rd.data = (const unsigned char *)bytes;
        rd.size = size;
        rd.pos = 0;
        CHECK_EQ_INT(radinterp_mesh_load(NULL, read_mem, &rd, &back), RADINTERP_OK);
        radinterp_mesh_destroy(back);
    }
    CHECK_EQ_INT(radinterp_mesh_save(m, failing_write, NULL), RADINTERP_ERROR_IO);
    CHECK_EQ_INT(radinterp_mesh_save(NULL, failing_write, NULL), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_mesh_load(NULL, NULL, NULL, &back), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_mesh_load_from_memory(NULL, 10, NULL, &back), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_mesh_save_to_memory(m, NULL, NULL, &size2), RADINTERP_ERROR_INVALID_ARGUMENT);
    test_note("save/load: %lu bytes for %u triangles; every truncation and 3000 bit flips rejected",
              (unsigned long)size, a.triangle_count);
    radinterp_free_memory(NULL, bytes);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* ---- validation, allocation failures, cancellation, determinism ----------- */

static void dummy_alloc_free(void *p, void *user) { (void)user; free(p); }

static void test_validation(void)
{
    scene s;
    radinterp_solution *sol = room_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = (radinterp_mesh *)&md;
    if (!sol) return;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, NULL), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_build_mesh(NULL, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK(m == NULL);
    CHECK_EQ_INT(radinterp_build_mesh(sol, NULL, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    md.min_discont_weight = -1.0f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    md = mesh_desc();
    md.refine_eps = NAN;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    md = mesh_desc();
    md.min_leaf_area = INFINITY;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    md = mesh_desc();
    md.min_discont_contrast = -0.5f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    md.min_discont_contrast = NAN;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK(m == NULL);
    md = mesh_desc();
    md.max_leaf_dsets = 100000;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    md = mesh_desc();
    md.allocator.free = dummy_alloc_free;   /* free without alloc */
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK(m == NULL);
    radinterp_mesh_destroy(NULL);
    CHECK_EQ_INT(radinterp_mesh_leaf_count(NULL), 0);
    CHECK_EQ_INT(radinterp_mesh_discontinuity_count(NULL), 0);
    radinterp_solution_destroy(sol);
}

typedef struct counting { long live, calls, fail_after; } counting;
static void *count_alloc(size_t n, void *user)
{
    counting *c = (counting *)user;
    if (c->fail_after >= 0 && c->calls >= c->fail_after) return NULL;
    c->calls++;
    c->live++;
    return malloc(n);
}
static void count_free(void *p, void *user)
{
    counting *c = (counting *)user;
    if (p) c->live--;
    free(p);
}
static int cancel_after;
static int progress_cb(void *user, uint64_t done, uint64_t total)
{
    int *calls = (int *)user;
    (void)done; (void)total;
    return ++*calls >= cancel_after;
}

static void test_allocation_failures_and_cancel(void)
{
    scene s;
    radinterp_solution *sol = small_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    counting cnt;
    int k, oom = 0, ok = 0, calls = 0;
    if (!sol) return;
    memset(&cnt, 0, sizeof cnt);
    md.allocator.alloc = count_alloc;
    md.allocator.free = count_free;
    md.allocator.user = &cnt;
    md.min_discont_weight = 0.1f;
    for (k = 0; k < 3000 && !ok; k++) {
        radinterp_result r;
        cnt.calls = 0;
        cnt.fail_after = k;
        r = radinterp_build_mesh(sol, &md, &m);
        if (r == RADINTERP_OK) { ok = 1; radinterp_mesh_destroy(m); }
        else if (r == RADINTERP_ERROR_OUT_OF_MEMORY) oom++;
        else CHECK_MSG(0, "failure %d gave %s", k, radinterp_result_string(r));
        CHECK_EQ_INT(cnt.live, 0);
    }
    CHECK(ok);
    test_note("mesh build: %d points of allocation failure, each reported as out of memory without leaks", oom);
    cnt.fail_after = -1;
    md.progress = progress_cb;
    md.progress_user = &calls;
    cancel_after = INT_MAX;   /* count the calls of a whole build */
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    radinterp_mesh_destroy(m);
    /* one a patch while discontinuities are found and one a patch while
       they are triangulated, then the samples' batches */
    CHECK_MSG(calls > 2 * (int)s.np, "%d progress calls for %u patches", calls, s.np);
    {
        int total = calls, step = total / 40 > 1 ? total / 40 : 1, cancelled = 0;
        for (cancel_after = 1; cancel_after <= total; cancel_after += step) {   /* every phase */
            calls = 0;
            CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_ERROR_CANCELLED);
            CHECK(m == NULL);
            CHECK_EQ_INT(cnt.live, 0);
            cancelled++;
        }
        test_note("mesh build: %d progress calls; cancelled at %d of them, each without leaks", total, cancelled);
    }
    radinterp_solution_destroy(sol);
}

/* Allocations through a budget: a build that split without end would
   exhaust it and answer out of memory instead of running until the machine
   does. */
typedef struct budget { size_t left; } budget;
static void *budget_alloc(size_t n, void *user)
{
    budget *b = (budget *)user;
    size_t *p;
    if (n > b->left) return NULL;
    p = (size_t *)malloc(n + sizeof(size_t) * 2);
    if (!p) return NULL;
    b->left -= n;
    p[0] = n;
    return p + 2;
}
static void budget_free(void *ptr, void *user)
{
    size_t *p = (size_t *)ptr;
    if (!p) return;
    ((budget *)user)->left += p[-2];
    free(p - 2);
}

/* A lit floor with one more patch (a quadrilateral at z = 0.3 given by its
   corners in the xy plane, facing up): the mesh status and its info. */
static radinterp_result mesh_with_patch(const float (*q)[2], radinterp_mesh_desc *md, radinterp_mesh_info *info,
                                        radinterp_mesh **keep)
{
    static scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    radinterp_mesh *m = NULL;
    radinterp_result r;
    static budget bud;   /* a kept mesh frees through it after this returns */
    float c[4][3];
    uint32_t grey, light, k;
    memset(&s, 0, sizeof s);
    grey = add_material(&s, 0.5f, 0.0f);
    light = add_material(&s, 0.5f, 10.0f);
    add_hrect(&s, 0.0f, 0.0f, 2.0f, 2.0f, 0.0f, 1, grey);
    add_hrect(&s, 0.0f, 0.0f, 2.0f, 2.0f, 1.0f, 0, light);
    for (k = 0; k < 4; k++) { c[k][0] = q[k][0]; c[k][1] = q[k][1]; c[k][2] = 0.3f; }
    add_quad(&s, c[0], c[1], c[2], c[3], grey);
    d = scene_desc(&s);
    if (!CHECK(radinterp_solve(&d, &sol) == RADINTERP_OK)) return RADINTERP_ERROR_INVALID_ARGUMENT;
    bud.left = (size_t)256 << 20;
    md->allocator.alloc = budget_alloc;
    md->allocator.free = budget_free;
    md->allocator.user = &bud;
    r = radinterp_build_mesh(sol, md, &m);
    radinterp_mesh_get_info(m, info);
    if (keep) *keep = m;
    else radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
    return r;
}

/* Degenerate shapes the mesher once mishandled: a quadrilateral with an edge
   one or a few float steps long and a 2 m x 0.1 um strip made the balance
   step split forever (the quarter points of such an edge round onto its own
   corners); a 2 m x 1 um strip failed the whole build. Now they mesh or are
   left out and counted, within a fixed memory budget. */
static void test_degenerate_patches(void)
{
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh_info info;
    /* a convex quadrilateral whose edge from corner 2 to corner 3 is 1, then 4, float steps long */
    float q[4][2] = {{0.5f, 0.5f}, {2.0f, 0.5f}, {2.0f, 1.5f}, {2.0f, 1.5f}};
    int k;
    for (k = 0; k < 4; k++) {
        q[3][0] = nextafterf(q[3][0], 0.0f);
        if (k != 0 && k != 3) continue;
        md = mesh_desc();
        CHECK_EQ_INT(mesh_with_patch((const float (*)[2])q, &md, &info, NULL), RADINTERP_OK);
    }
    {
        const float strip[4][2] = {{0.0f, 0.5f}, {2.0f, 0.5f}, {2.0f, 0.5f + 1e-7f}, {0.0f, 0.5f + 1e-7f}};
        const float wider[4][2] = {{0.0f, 0.5f}, {2.0f, 0.5f}, {2.0f, 0.5f + 1e-6f}, {0.0f, 0.5f + 1e-6f}};
        md = mesh_desc();
        CHECK_EQ_INT(mesh_with_patch(strip, &md, &info, NULL), RADINTERP_OK);
        md = mesh_desc();
        CHECK_EQ_INT(mesh_with_patch(wider, &md, &info, NULL), RADINTERP_OK);
        /* 1 um is below the weld distance (1e-6 of the 3.3 m diagonal): left out, counted */
        CHECK_EQ_INT(info.skipped_patches, 1);
        CHECK(info.triangle_count > 0);
    }
}

/* A build without discontinuities once offset a NULL array (undefined
   behaviour that clang's sanitizer reports); evaluation at a NaN or
   infinite (s, t) returned OK with NaN. */
static void test_no_discontinuities_and_eval_arguments(void)
{
    const float sq[4][2] = {{0.5f, 0.5f}, {1.5f, 0.5f}, {1.5f, 1.5f}, {0.5f, 1.5f}};
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh_info info;
    radinterp_mesh *m = NULL;
    float rgb[3] = {1, 1, 1};
    md.no_discontinuities = 1;
    CHECK_EQ_INT(mesh_with_patch(sq, &md, &info, &m), RADINTERP_OK);
    if (!m) return;
    CHECK_EQ_INT(info.active_discontinuities, 0);
    CHECK_EQ_INT(radinterp_eval(m, 0, 0.25f, 0.25f, rgb), RADINTERP_OK);
    CHECK(isfinite(rgb[0]) && rgb[0] > 0.0f);
    CHECK_EQ_INT(radinterp_eval(m, 0, NAN, 0.25f, rgb), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK(rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 0.0f);
    CHECK_EQ_INT(radinterp_eval(m, 0, 0.25f, INFINITY, rgb), RADINTERP_ERROR_INVALID_ARGUMENT);
    CHECK_EQ_INT(radinterp_eval_irradiance(m, 0, -INFINITY, 0.0f, rgb), RADINTERP_ERROR_INVALID_ARGUMENT);
    radinterp_mesh_destroy(m);
}

/* ---- leaf lists built where they are used ---------------------------------- */
/* Four rooms in a row, each with a ceiling lamp and a desk under it: a
   building small enough for the sanitizers. */
static radinterp_solution *rooms_scene(scene *s, float point_rest)
{
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    uint32_t grey, light, i;
    memset(s, 0, sizeof *s);
    grey = add_material(s, 0.6f, 0.0f);
    light = add_material(s, 0.0f, 50.0f);
    for (i = 0; i < 4; i++) {
        float x = 4.0f * (float)i;
        add_room(s, x, 0.0f, 0.0f, x + 3.8f, 3.0f, 2.5f, grey);
        add_hrect(s, x + 1.4f, 1.2f, x + 2.4f, 1.8f, 2.4f, 0, light);
        add_block(s, x + 1.2f, 1.0f, 0.0f, x + 2.6f, 2.0f, 0.75f, grey);
    }
    d = scene_desc(s);
    d.point_rest = point_rest;
    d.min_area = 0.15f;   /* coarse leaves: fast under the sanitizers */
    CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK);
    return sol;
}

/* The solution keeps no leaf lists (radinterp_info.leaf_list_bytes 0), and
   the mesh build holds the lists of one batch of leaves at a time: this file
   bounds a batch at RADINTERP__LEAF_BATCH_BYTES (16 KB), a batch passes it
   only when one leaf's list alone does, and the lists of all the leaves
   take many times that. A build that kept the lists of every leaf, or let
   a batch grow past its bound, fails. */
static void test_leaf_lists_bounded(void)
{
    scene s;
    radinterp_solution *sol = rooms_scene(&s, 0.0f);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    radinterp_mesh_info mi;
    radinterp_info info;
    size_t all = 0, largest = 0, bound;
    uint32_t i;
    if (!sol) return;
    radinterp_solution_info(sol, &info);
    CHECK(info.leaf_list_bytes == 0 && info.leaf_list_entries == 0 && info.leaf_blocker_entries == 0);
    for (i = 0; i < sol->leaf_count; i++) {
        size_t b = radinterp__leaf_bytes(sol, sol->leaves[i]);
        all += b;
        largest = b > largest ? b : largest;
    }
    /* a batch's arrays take one more item each than its leaves' lists */
    bound = (largest > RADINTERP__LEAF_BATCH_BYTES ? largest : RADINTERP__LEAF_BATCH_BYTES) +
            2 * sizeof(uint32_t) + sizeof(uint64_t) + sizeof(radinterp__leaf_link) + sizeof(uint32_t);
    CHECK_MSG(all > 8 * bound, "the lists of all %u leaves take %zu bytes, a batch at most %zu", sol->leaf_count, all, bound);
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    if (m) {
        radinterp_mesh_get_info(m, &mi);
        CHECK_MSG(mi.leaf_list_bytes > 0 && mi.leaf_list_bytes <= bound, "largest batch %zu bytes, bound %zu",
                  mi.leaf_list_bytes, bound);
        test_note("four rooms: %u leaves, their lists %zu bytes in all; the mesh's largest batch %zu bytes",
                  sol->leaf_count, all, mi.leaf_list_bytes);
    }
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* The batches of the sample points (radinterp__run_batches) and of their
   leaf lists (radinterp__fill_leaf_lists) as a parallel_for sees them: a
   batch's jobs, and where it starts in its run (one run of each per batch
   of leaves). */
typedef struct batch_log { uint32_t jobs[4096], first[4096], n; } batch_log;
static void logging_for(void *user, radinterp_job_fn job, void *ctx, uint32_t count)
{
    batch_log *logs = (batch_log *)user, *l = NULL;
    uint32_t i;
    if (job == radinterp__point_job) l = &logs[0];
    if (job == radinterp__leaf_lists_job) l = &logs[1];
    if (l && l->n < 4096) {
        l->jobs[l->n] = count;
        l->first[l->n++] = l == &logs[0] ? ((const radinterp__sample_ctx *)ctx)->first
                                         : ((const radinterp__leaf_lists *)ctx)->job_first;
    }
    for (i = 0; i < count; i++) job(ctx, i);
}

/* Batches of l not sized as one pacer with a stopped clock sizes them:
   batch k takes min(2^k, cap) jobs, or fewer only as the last of its run.
   *runs: the runs; *full: the batches of cap jobs. */
static uint32_t unpaced_batches(const batch_log *l, uint32_t cap, uint32_t *runs, uint32_t *full)
{
    uint32_t k, want = 1, wrong = 0;
    *runs = *full = 0;
    for (k = 0; k < l->n; k++) {
        int last_of_run = k + 1 == l->n || l->first[k + 1] == 0;
        *runs += l->first[k] == 0;
        *full += l->jobs[k] == cap;
        if (l->jobs[k] != want && !(l->jobs[k] < want && last_of_run)) wrong++;
        want = want < cap / 2 ? want * 2 : cap;
    }
    return wrong;
}

/* Each batch of jobs ends with the threads waiting for its last job, so
   the batches are as large as the pacer allows: with this file's stopped
   clock the pacer doubles a batch after every batch, the sample points' up
   to RADINTERP__SAMPLE_BATCH jobs (at least 512 points), and it keeps its
   size from one run to the next (this file's small batches of leaf lists
   make many runs), for the points and for their leaf lists alike. A pacer
   started afresh for each run (v0.8.13: a first batch of one job, of two
   points or 16 leaves, in every run), or a ceiling of 64 point jobs, fails.
   (With one sample per side of a contact discontinuity at a vertex the
   scene has 4% fewer points, and two batches, not five, reach the ceiling;
   either failure above leaves none.) */
static void test_sample_batches(void)
{
    scene s;
    radinterp_solution *sol = rooms_scene(&s, 0.0f);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *m = NULL;
    static batch_log logs[2];
    uint32_t wrong, runs, full, lists_runs, lists_full;
    if (!sol) return;
    memset(logs, 0, sizeof logs);
    md.parallel_for = logging_for;
    md.parallel_user = logs;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &m), RADINTERP_OK);
    CHECK(RADINTERP__SAMPLE_BATCH * RADINTERP__SAMPLE_JOB >= 512);
    CHECK(logs[0].n > 0 && logs[0].n < 4096 && logs[1].n > 0 && logs[1].n < 4096);
    wrong = unpaced_batches(&logs[0], RADINTERP__SAMPLE_BATCH, &runs, &full);
    CHECK_MSG(wrong == 0, "%u of %u batches of points not sized as the pacer's", wrong, logs[0].n);
    CHECK_MSG(runs > 4 && full > 1, "%u runs of points, %u batches of %u jobs", runs, full, RADINTERP__SAMPLE_BATCH);
    wrong = unpaced_batches(&logs[1], UINT32_MAX, &lists_runs, &lists_full);
    CHECK_MSG(wrong == 0, "%u of %u batches of leaf lists not sized as the pacer's", wrong, logs[1].n);
    CHECK_MSG(lists_runs == runs, "%u runs of leaf lists, %u of points", lists_runs, runs);
    test_note("four rooms: %u batches of sample points in %u runs, %u of them of %u jobs; %u batches of leaf lists",
              logs[0].n, runs, full, RADINTERP__SAMPLE_BATCH, logs[1].n);
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(sol);
}

/* A point's irradiance does not depend on where its leaf's list came from:
   filtered link by link as the query reaches each (radinterp_irradiance_at_
   point) or read from the lists of a batch of leaves (the mesh build's),
   bit for bit. Both agree with the sum over the links' own blockers (no
   leaf lists: leaf_margin 0), which backprojects the same shadows and more,
   to rounding: 1e-12, as test_radinterp_visibility's leaf list test finds
   in the office. Every source is exact (point_rest FLT_MIN): with the
   default, a source left to its link's visible fraction counts whole where
   the leaf's entry holds no blocker, by design. Points: random ones, and
   corners of random leaves nudged toward the leaf's centre, where the mesh
   samples. The meshes built with and without lists must agree to 1e-6 of
   the largest coefficient: their samples agree to rounding, and the fitted
   coefficients are floats (a few float roundings of 6e-8 each). */
static void test_leaf_lists_known_answers(void)
{
    scene s;
    radinterp_solution *sol = rooms_scene(&s, FLT_MIN);
    radinterp__leaf_lists all;
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *with = NULL, *without = NULL;
    uint32_t *sorted, i, differ = 0, hidden = 0, kept = 0;
    double worst = 0.0, margin;
    if (!sol) return;
    sorted = (uint32_t *)malloc(sol->leaf_count * sizeof(uint32_t));
    if (!CHECK(sorted != NULL)) { radinterp_solution_destroy(sol); return; }
    memcpy(sorted, sol->leaves, sol->leaf_count * sizeof(uint32_t));
    qsort(sorted, sol->leaf_count, sizeof(uint32_t), radinterp__cmp_u32);
    CHECK_EQ_INT(radinterp__leaf_lists_make(sol, &sol->allocator, sorted, sol->leaf_count, &all), RADINTERP_OK);
    radinterp__run_jobs(NULL, NULL, radinterp__leaf_lists_job, &all, radinterp__leaf_lists_jobs(&all));
    for (i = 0; i < (all.count ? all.first[all.count] : 0); i++) {   /* both kinds of entry are exercised */
        hidden += all.link[i].count == RADINTERP__LEAF_HIDDEN;
        kept += all.link[i].count != RADINTERP__LEAF_HIDDEN && all.link[i].count > 0;
    }
    CHECK_MSG(hidden > 0 && kept > 0, "%u hidden entries, %u with blockers", hidden, kept);
    margin = sol->leaf_margin;
    for (i = 0; i < 400 && all.count; i++) {
        const radinterp__node *leaf = &sol->nodes[sol->leaves[(uint32_t)(rnd() * sol->leaf_count) % sol->leaf_count]];
        float p[3], centre[3] = {0.0f, 0.0f, 0.0f};
        const float *toward = NULL;
        double h_query[3], h_batch[3], h_links[3];
        uint32_t c = (uint32_t)(rnd() * leaf->count) % leaf->count, j;
        int k;
        for (k = 0; k < 3; k++) {
            for (j = 0; j < leaf->count; j++) centre[k] += leaf->v[j][k] / (float)leaf->count;
            p[k] = i % 2 ? leaf->v[c][k] : centre[k];
        }
        if (i % 2) {   /* a corner, seen from inside its leaf */
            toward = centre;
        } else {       /* a random point of the leaf's first triangle */
            double u = rnd(), v = rnd() * (1.0 - u);
            for (k = 0; k < 3; k++)
                p[k] = (float)(leaf->v[0][k] + u * (leaf->v[1][k] - leaf->v[0][k]) + v * (leaf->v[2][k] - leaf->v[0][k]));
        }
        CHECK_EQ_INT(radinterp__irradiance(sol, leaf->patch, p, toward, h_query, NULL), RADINTERP_OK);
        CHECK_EQ_INT(radinterp__irradiance_listed(sol, &all, leaf->patch, p, toward, h_batch, NULL), RADINTERP_OK);
        differ += memcmp(h_query, h_batch, sizeof h_query) != 0;
        sol->leaf_margin = 0.0;
        CHECK_EQ_INT(radinterp__irradiance(sol, leaf->patch, p, toward, h_links, NULL), RADINTERP_OK);
        sol->leaf_margin = margin;
        for (k = 0; k < 3; k++) {
            double rel = fabs(h_query[k] - h_links[k]) / (h_links[k] > 1e-3 ? h_links[k] : 1e-3);
            worst = rel > worst ? rel : worst;
        }
    }
    CHECK_EQ_INT(differ, 0);
    CHECK_MSG(worst <= 1e-12, "leaf lists against the links' own blockers: %.3g", worst);
    radinterp__leaf_lists_free(&sol->allocator, &all);
    free(sorted);
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &with), RADINTERP_OK);
    sol->leaf_margin = 0.0;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &without), RADINTERP_OK);
    sol->leaf_margin = margin;
    if (with && without) {
        radinterp_mesh_data a, b;
        double top = 0.0, diff = 0.0;
        size_t e;
        radinterp_mesh_get_data(with, &a);
        radinterp_mesh_get_data(without, &b);
        CHECK_EQ_INT(a.triangle_count, b.triangle_count);
        for (e = 0; a.triangle_count == b.triangle_count && e < 18 * (size_t)a.triangle_count; e++) {
            double x = a.irradiance_coefficients[e], y = b.irradiance_coefficients[e];
            top = fabs(y) > top ? fabs(y) : top;
            diff = fabs(x - y) > diff ? fabs(x - y) : diff;
        }
        CHECK_MSG(diff <= 1e-6 * top, "meshes with and without leaf lists differ by %.3g (largest coefficient %.3g)", diff, top);
        test_note("four rooms: %u hidden entries, %u with blockers; points %.2e from the links' own blockers; meshes "
                  "%.2e of the largest coefficient", hidden, kept, worst, top > 0.0 ? diff / top : 0.0);
    }
    radinterp_mesh_destroy(with);
    radinterp_mesh_destroy(without);
    radinterp_solution_destroy(sol);
}

static void test_determinism(void)
{
    scene s;
    radinterp_solution *sol = room_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *a = NULL, *b = NULL;
    void *ba = NULL, *bb = NULL;
    size_t na = 0, nb = 0;
    ex_pool *pool = ex_pool_create(3);
    if (!sol) return;
    md.min_leaf_area = 0.05f;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &a), RADINTERP_OK);
    md.parallel_for = ex_pool_parallel_for;
    md.parallel_user = pool;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &b), RADINTERP_OK);
    if (a && b) {
        radinterp_mesh_save_to_memory(a, NULL, &ba, &na);
        radinterp_mesh_save_to_memory(b, NULL, &bb, &nb);
        CHECK(na == nb && ba && bb && memcmp(ba, bb, na) == 0);  /* bit-identical for any thread count */
    }
    radinterp_free_memory(NULL, ba);
    radinterp_free_memory(NULL, bb);
    radinterp_mesh_destroy(a);
    radinterp_mesh_destroy(b);
    ex_pool_destroy(pool);
    radinterp_solution_destroy(sol);
}

/* Index of the first record at or after `from` in m's list equal to d,
   or the list's count. */
static uint32_t find_discontinuity(const radinterp_mesh *m, uint32_t from, const radinterp_discontinuity *d)
{
    uint32_t n = radinterp_mesh_discontinuity_count(m);
    for (; from < n; from++) {
        radinterp_discontinuity x;
        radinterp_mesh_get_discontinuity(m, from, &x);
        if (memcmp(&x, d, sizeof x) == 0) break;
    }
    return from;
}

/* By default the mesh returns only the candidate discontinuities. Against
   keep_all_discontinuities: the same triangles and interpolants and the
   same counts in info; its list is the candidates of the full list (as
   many as info.candidates), in the same order, with every active one; it
   holds less memory; a save and a load keep the counts of what was found. */
static void test_candidates_only_by_default(void)
{
    scene s;
    radinterp_solution *sol = room_scene(&s);
    radinterp_mesh_desc md = mesh_desc();
    radinterp_mesh *all = NULL, *cand = NULL, *back = NULL;
    radinterp_mesh_info ia, ic, ib;
    radinterp_mesh_data da, dc;
    void *bytes = NULL;
    size_t size = 0;
    uint32_t i, at = 0, active = 0, n;
    if (!sol) return;
    md.min_leaf_area = 0.05f;
    md.min_discont_contrast = 0.25f;   /* leaves most of the room's discontinuities out of the candidates */
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &all), RADINTERP_OK);
    md.keep_all_discontinuities = 0;
    CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &cand), RADINTERP_OK);
    if (!all || !cand) goto done;
    radinterp_mesh_get_info(all, &ia);
    radinterp_mesh_get_info(cand, &ic);
    n = radinterp_mesh_discontinuity_count(cand);
    CHECK_EQ_INT(radinterp_mesh_discontinuity_count(all), ia.discontinuities);
    CHECK_EQ_INT(ia.kept_discontinuities, ia.discontinuities);
    CHECK_EQ_INT(n, ic.candidates);
    CHECK_EQ_INT(ic.kept_discontinuities, n);
    /* the scene must have discontinuities that are not candidates, or the
       test would not see the difference */
    CHECK_MSG(ic.candidates > 0 && ic.candidates * 2 < ic.discontinuities, "%u candidates of %u found",
              ic.candidates, ic.discontinuities);
    CHECK_EQ_INT(ic.discontinuities, ia.discontinuities);
    CHECK_EQ_INT(ic.ev, ia.ev);
    CHECK_EQ_INT(ic.ve, ia.ve);
    CHECK_EQ_INT(ic.horizon, ia.horizon);
    CHECK_EQ_INT(ic.contact, ia.contact);
    CHECK_EQ_INT(ic.dsets, ia.dsets);
    CHECK_EQ_INT(ic.candidates, ia.candidates);
    CHECK_EQ_INT(ic.active_discontinuities, ia.active_discontinuities);
    CHECK(ic.bytes < ia.bytes);
    radinterp_mesh_get_data(all, &da);
    radinterp_mesh_get_data(cand, &dc);
    CHECK(da.triangle_count == dc.triangle_count && da.vertex_count == dc.vertex_count);
    if (da.triangle_count == dc.triangle_count && da.vertex_count == dc.vertex_count) {
        CHECK(memcmp(da.positions, dc.positions, 12 * (size_t)da.vertex_count) == 0);
        CHECK(memcmp(da.indices, dc.indices, 12 * (size_t)da.triangle_count) == 0);
        CHECK(memcmp(da.coefficients, dc.coefficients, 72 * (size_t)da.triangle_count) == 0);
    }
    for (i = 0; i < n; i++) {
        radinterp_discontinuity d;
        radinterp_mesh_get_discontinuity(cand, i, &d);
        at = find_discontinuity(all, at, &d);
        if (!CHECK_MSG(at < ia.discontinuities, "candidate %u is not in the full list after the one before", i)) break;
        at++;
        active += d.active != 0;
    }
    CHECK_EQ_INT(active, ia.active_discontinuities);
    CHECK_EQ_INT(radinterp_mesh_save_to_memory(cand, NULL, &bytes, &size), RADINTERP_OK);
    CHECK_EQ_INT(radinterp_mesh_load_from_memory(bytes, size, NULL, &back), RADINTERP_OK);
    if (back) {
        radinterp_mesh_get_info(back, &ib);
        CHECK_EQ_INT(ib.discontinuities, ic.discontinuities);
        CHECK_EQ_INT(ib.kept_discontinuities, n);
        CHECK_EQ_INT(radinterp_mesh_discontinuity_count(back), n);
    }
    test_note("default list: %u candidates of %u found (%.1f of %.1f KB of mesh)", n, ic.discontinuities,
              ic.bytes / 1024.0, ia.bytes / 1024.0);
done:
    radinterp_free_memory(NULL, bytes);
    radinterp_mesh_destroy(back);
    radinterp_mesh_destroy(all);
    radinterp_mesh_destroy(cand);
    radinterp_solution_destroy(sol);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_fit_reproduces_quadratics);
    RUN(test_penumbra_boundaries);
    RUN(test_leaf_hidden_links);
    RUN(test_one_shadow_hides);
    RUN(test_staged_shadow_areas);
    RUN(test_pyramid_cut_skips);
    RUN(test_later_shadows_when_reached);
    RUN(test_weights);
    RUN(test_weight_cache);
    RUN(test_hidden_events);
    RUN(test_contrast);
    RUN(test_horizon_and_contact);
    RUN(test_activation_rules);
    RUN(test_crack_free_room);
    RUN(test_disc_sectors);
    RUN(test_shading);
    RUN(test_interpolant_accuracy);
    RUN(test_save_load);
    RUN(test_validation);
    RUN(test_allocation_failures_and_cancel);
    RUN(test_degenerate_patches);
    RUN(test_no_discontinuities_and_eval_arguments);
    RUN(test_determinism);
    RUN(test_leaf_lists_bounded);
    RUN(test_sample_batches);
    RUN(test_leaf_lists_known_answers);
    RUN(test_candidates_only_by_default);
    return test_finish();
}
