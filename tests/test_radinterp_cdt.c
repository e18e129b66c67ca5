/* Unit tests of radinterp.h's private toolkit: the exact predicates and the
   constrained Delaunay triangulation. The validity check is independent of
   the triangulation code: neighbour symmetry, counter-clockwise triangles,
   area = convex hull area, every input point a vertex, every constraint a
   chain of constrained edges along its segment, and every other interior edge
   locally Delaunay (by the exact incircle test). */
#define RADINTERP_IMPLEMENTATION
#include "../radinterp.h"
#include "test.h"

static const radinterp_allocator heap = {NULL, NULL, NULL};

/* ---- a small deterministic generator for the test data ---- */
static uint64_t rng_state = 1;
static double rnd(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}
static uint32_t rnd_int(uint32_t n) { return (uint32_t)(rnd() * n) % n; }

/* ---- convex hull area (monotone chain) for the coverage check ---- */
static int cmp_xy(const void *a, const void *b)
{
    const double *p = (const double *)a, *q = (const double *)b;
    if (p[0] != q[0]) return p[0] < q[0] ? -1 : 1;
    if (p[1] != q[1]) return p[1] < q[1] ? -1 : 1;
    return 0;
}
static double cross3(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
static double hull_area(const double *xy, uint32_t n)
{
    double *p = (double *)malloc(n * 2 * sizeof(double)), *h = (double *)malloc((2 * n + 2) * 2 * sizeof(double));
    uint32_t i, k = 0, t;
    double area = 0.0;
    memcpy(p, xy, n * 2 * sizeof(double));
    qsort(p, n, 2 * sizeof(double), cmp_xy);
    for (i = 0; i < n; i++) {
        while (k >= 2 && cross3(h + 2 * (k - 2), h + 2 * (k - 1), p + 2 * i) <= 0) k--;
        h[2 * k] = p[2 * i]; h[2 * k + 1] = p[2 * i + 1]; k++;
    }
    for (i = n - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross3(h + 2 * (k - 2), h + 2 * (k - 1), p + 2 * i) <= 0) k--;
        h[2 * k] = p[2 * i]; h[2 * k + 1] = p[2 * i + 1]; k++;
    }
    for (i = 0; i + 1 < k; i++) area += h[2 * i] * h[2 * i + 3] - h[2 * i + 2] * h[2 * i + 1];
    free(p);
    free(h);
    return 0.5 * area;
}

/* ---- the validity check ---- */
static int edge_constrained(const radinterp__cdt *c, uint32_t a, uint32_t b)
{
    uint32_t t;
    int k;
    return radinterp__cdt_find_edge(c, a, b, &t, &k) && ((c->tri[t].flags >> k) & 1u);
}

/* Is there a path of constrained edges from a to b through vertices on the
   segment (within tol of its line, in increasing order along it)? Searched
   depth first, because overlapping constraints share some pieces. */
static int constraint_present(const radinterp__cdt *c, uint32_t a, uint32_t b, double tol)
{
    const double *pa = c->xy + 2 * a, *pb = c->xy + 2 * b;
    double dx = pb[0] - pa[0], dy = pb[1] - pa[1], len2 = dx * dx + dy * dy, len = sqrt(len2);
    uint32_t *stack, *seen, top = 0, found = 0;
    if (a == b) return 1;
    stack = (uint32_t *)malloc(sizeof(uint32_t) * (c->vertex_count + 1) * 8);
    seen = (uint32_t *)calloc(c->vertex_count, sizeof(uint32_t));
    stack[top++] = a;
    seen[a] = 1;
    while (top && !found) {
        uint32_t cur = stack[--top], s = c->vtri[cur], t = s, guard = 0;
        const double *pc = c->xy + 2 * cur;
        double s_cur = ((pc[0] - pa[0]) * dx + (pc[1] - pa[1]) * dy) / len2;
        do {
            int i = radinterp__cdt_index(c, t, cur), e;
            for (e = 1; e <= 2; e++) {
                uint32_t w = c->tri[t].v[(i + e) % 3];
                const double *q;
                double sw, dist;
                if (w == RADINTERP__GHOST || seen[w] || !edge_constrained(c, cur, w)) continue;
                q = c->xy + 2 * w;
                sw = ((q[0] - pa[0]) * dx + (q[1] - pa[1]) * dy) / len2;
                dist = fabs((q[0] - pa[0]) * dy - (q[1] - pa[1]) * dx) / len;
                if (!(sw > s_cur - 1e-12 && sw <= 1.0 + 1e-12 && dist <= tol * len)) continue; /* ties: rounding */
                if (w == b) found = 1;
                seen[w] = 1;
                stack[top++] = w;
            }
            t = c->tri[t].n[(i + 1) % 3];
        } while (t != s && ++guard < c->tri_count);
    }
    free(stack);
    free(seen);
    return (int)found;
}

typedef struct check_result {
    int symmetric, ccw, delaunay, area, vertices, constraints;
    uint32_t triangles;
} check_result;

static check_result cdt_check(const radinterp__cdt *c, const double *pts, uint32_t n, const uint32_t *ids,
                              const uint32_t *seg, uint32_t nseg)
{
    check_result r;
    uint32_t t, i;
    double area = 0.0, want;
    memset(&r, 0, sizeof r);
    r.symmetric = r.ccw = r.delaunay = r.vertices = r.constraints = 1;
    for (t = 0; t < c->tri_count; t++) {
        const radinterp__cdt_tri *T = &c->tri[t];
        int k;
        for (k = 0; k < 3; k++) {
            uint32_t u = T->n[k];
            int j = u < c->tri_count ? radinterp__cdt_neighbour_index(c, u, t) : -1;
            if (j < 0 || c->tri[u].v[(j + 1) % 3] != T->v[(k + 2) % 3] || c->tri[u].v[(j + 2) % 3] != T->v[(k + 1) % 3] ||
                ((c->tri[u].flags >> j) & 1u) != ((T->flags >> k) & 1u)) {
                r.symmetric = 0;
                continue;
            }
            if (!radinterp__cdt_is_ghost(c, t) && !radinterp__cdt_is_ghost(c, u) && !((T->flags >> k) & 1u) &&
                radinterp__incircle(c->xy + 2 * T->v[0], c->xy + 2 * T->v[1], c->xy + 2 * T->v[2],
                                    c->xy + 2 * c->tri[u].v[j]) > 0.0)
                r.delaunay = 0;
        }
        if (radinterp__cdt_is_ghost(c, t)) continue;
        r.triangles++;
        if (!(radinterp__orient2d(c->xy + 2 * T->v[0], c->xy + 2 * T->v[1], c->xy + 2 * T->v[2]) > 0.0)) r.ccw = 0;
        area += 0.5 * cross3(c->xy + 2 * T->v[0], c->xy + 2 * T->v[1], c->xy + 2 * T->v[2]);
    }
    want = hull_area(pts, n);
    {
        /* shoelace sums round: allow 1e-9 relative plus 1e-12 of the bounding box
           (nearly collinear inputs have hull areas near rounding level) */
        double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
        for (i = 0; i < n; i++) {
            lo[0] = fmin(lo[0], pts[2 * i]); hi[0] = fmax(hi[0], pts[2 * i]);
            lo[1] = fmin(lo[1], pts[2 * i + 1]); hi[1] = fmax(hi[1], pts[2 * i + 1]);
        }
        r.area = fabs(area - want) <= 1e-9 * want + 1e-12 * (hi[0] - lo[0]) * (hi[1] - lo[1]);
    }
    for (i = 0; i < n; i++) {
        uint32_t v = ids[i];
        if (v >= c->vertex_count || c->vtri[v] == RADINTERP__NONE || radinterp__cdt_index(c, c->vtri[v], v) < 0 ||
            c->xy[2 * v] != pts[2 * i] || c->xy[2 * v + 1] != pts[2 * i + 1])
            r.vertices = 0;
    }
    for (i = 0; i < nseg; i++)
        if (!constraint_present(c, ids[seg[2 * i]], ids[seg[2 * i + 1]], 1e-9)) r.constraints = 0;
    return r;
}

static void expect_valid(const radinterp__cdt *c, const double *pts, uint32_t n, const uint32_t *ids,
                         const uint32_t *seg, uint32_t nseg, const char *what)
{
    check_result r = cdt_check(c, pts, n, ids, seg, nseg);
    CHECK_MSG(!c->failed, "%s: triangulation failed", what);
    CHECK_MSG(r.symmetric, "%s: neighbour links not symmetric", what);
    CHECK_MSG(r.ccw, "%s: a triangle is not counter-clockwise", what);
    CHECK_MSG(r.area, "%s: triangles do not cover the convex hull", what);
    CHECK_MSG(r.vertices, "%s: an input point is not a vertex", what);
    CHECK_MSG(r.constraints, "%s: a constraint is missing", what);
    CHECK_MSG(r.delaunay, "%s: an unconstrained edge is not locally Delaunay", what);
}

/* Builds a CDT of points and segments (segments given by point index). */
static void build(radinterp__cdt *c, const double *pts, uint32_t n, uint32_t *ids, const uint32_t *seg, uint32_t nseg,
                  int bulk)
{
    uint32_t i;
    if (bulk) CHECK(radinterp__cdt_add_points(c, pts, n, ids) == 0);
    else
        for (i = 0; i < n; i++) ids[i] = radinterp__cdt_add_point(c, pts[2 * i], pts[2 * i + 1]);
    for (i = 0; i < nseg; i++) radinterp__cdt_add_segment(c, ids[seg[2 * i]], ids[seg[2 * i + 1]]);
}

/* ---- predicates ---- */
static void test_orient2d_exact(void)
{
    /* points on the line y = x / 3 + 1e-3 are collinear only in exact arithmetic
       of their rounded coordinates; compare with an exact rational check made
       from integers scaled by powers of two */
    double a[2] = {0.5, 0.5}, b[2] = {12.0, 12.0}, c[2] = {24.0, 24.0}, d[2];
    int i, wrong = 0;
    CHECK(radinterp__orient2d(a, b, c) == 0.0);
    for (i = 0; i < 1000; i++) {
        /* c nudged by one ulp off the diagonal: the naive determinant rounds to 0 */
        double t = 0.5 + rnd() * 100.0;
        double p[2], q[2];
        p[0] = t; p[1] = t;
        q[0] = nextafter(t * 3.0, 1e9); q[1] = t * 3.0;
        /* (a, p, q): q lies just right of the line y = x, so the turn is clockwise */
        if (!(radinterp__orient2d(a, p, q) < 0.0)) wrong++;
        q[0] = t * 3.0; q[1] = nextafter(t * 3.0, 1e9);
        if (!(radinterp__orient2d(a, p, q) > 0.0)) wrong++;
    }
    CHECK_EQ_INT(wrong, 0);
    d[0] = 1.0; d[1] = 0.0;
    CHECK(radinterp__orient2d(a, d, b) > 0.0);
}

static void test_incircle_exact(void)
{
    /* four points on the unit circle scaled by a power of two are exactly
       cocircular; a one-ulp move inside or outside must be seen */
    double s = 1024.0, a[2], b[2], c[2], d[2];
    int wrong = 0, i;
    a[0] = s; a[1] = 0.0;
    b[0] = 0.0; b[1] = s;
    c[0] = -s; c[1] = 0.0;
    d[0] = 0.0; d[1] = -s;
    CHECK(radinterp__incircle(a, b, c, d) == 0.0);
    d[1] = nextafter(-s, 0.0);
    CHECK(radinterp__incircle(a, b, c, d) > 0.0);
    d[1] = nextafter(-s, -2 * s);
    CHECK(radinterp__incircle(a, b, c, d) < 0.0);
    /* Pythagorean points (3,4,5 family) on a circle of radius 5 * 2^k, translated
       by a large offset so that the naive evaluation cancels badly */
    for (i = 0; i < 200; i++) {
        double off = (double)rnd_int(1u << 20) * 1024.0; /* an integer: the sums stay exact */
        double p[4][2] = {{3, 4}, {-4, 3}, {-3, -4}, {4, -3}};
        int k;
        for (k = 0; k < 4; k++) { p[k][0] += off; p[k][1] += off; }
        if (radinterp__incircle(p[0], p[1], p[2], p[3]) != 0.0) wrong++;
    }
    CHECK_EQ_INT(wrong, 0);
}

/* ---- triangulations ---- */
static void test_cdt_random_points(void)
{
    enum { N = 3000 };
    static double pts[2 * N];
    static uint32_t ids[N];
    radinterp__cdt c;
    uint32_t i;
    for (i = 0; i < N; i++) { pts[2 * i] = rnd(); pts[2 * i + 1] = rnd(); }
    radinterp__cdt_init(&c, &heap, NULL, 0);
    build(&c, pts, N, ids, NULL, 0, 1);
    expect_valid(&c, pts, N, ids, NULL, 0, "random points");
    radinterp__cdt_free(&c);
}

static void test_cdt_random_crossing_constraints(void)
{
    enum { N = 1500, S = 120 };
    static double pts[2 * N];
    static uint32_t ids[N], seg[2 * S];
    radinterp__cdt c;
    uint32_t i, round;
    for (round = 0; round < 4; round++) {
        for (i = 0; i < N; i++) { pts[2 * i] = rnd(); pts[2 * i + 1] = rnd(); }
        for (i = 0; i < S; i++) { seg[2 * i] = rnd_int(N); seg[2 * i + 1] = rnd_int(N); }
        radinterp__cdt_init(&c, &heap, NULL, 0);
        build(&c, pts, N, ids, seg, S, round & 1);
        expect_valid(&c, pts, N, ids, seg, S, "random crossing constraints");
        test_note("round %u: %u points, %u segments -> %u vertices (crossings added), %u triangles", round, N, S,
                  c.vertex_count, cdt_check(&c, pts, N, ids, seg, S).triangles);
        radinterp__cdt_free(&c);
    }
}

/* Integer grid: every unit square is cocircular, many points collinear;
   constraints run along grid lines (through vertices) and diagonally. */
static void test_cdt_grid_collinear_runs(void)
{
    enum { G = 21, N = G * G, S = 60 };
    static double pts[2 * N];
    static uint32_t ids[N], seg[2 * S];
    radinterp__cdt c;
    uint32_t i, j, k = 0;
    for (j = 0; j < G; j++)
        for (i = 0; i < G; i++) { pts[2 * k] = i; pts[2 * k + 1] = j; k++; }
    for (i = 0; i < S; i++) {
        uint32_t a = rnd_int(N), b;
        if (i % 3 == 0) b = (a / G) * G + rnd_int(G);            /* same row: through collinear vertices */
        else if (i % 3 == 1) b = a % G + G * rnd_int(G);         /* same column */
        else b = rnd_int(N);                                      /* anywhere: crosses others */
        seg[2 * i] = a;
        seg[2 * i + 1] = b;
    }
    radinterp__cdt_init(&c, &heap, NULL, 0);
    build(&c, pts, N, ids, seg, S, 0);
    expect_valid(&c, pts, N, ids, seg, S, "grid");
    radinterp__cdt_free(&c);
}

/* All points on one line first (the triangulation waits), then off it. */
static void test_cdt_collinear_start(void)
{
    enum { N = 200 };
    static double pts[2 * N];
    static uint32_t ids[N], seg[4] = {0, 99, 150, 199};
    radinterp__cdt c;
    uint32_t i;
    for (i = 0; i < 100; i++) { pts[2 * i] = 0.25 * i; pts[2 * i + 1] = 0.5 * i; }
    for (i = 100; i < N; i++) { pts[2 * i] = 50.0 * rnd() - 10.0; pts[2 * i + 1] = 50.0 * rnd(); }
    radinterp__cdt_init(&c, &heap, NULL, 0);
    build(&c, pts, N, ids, seg, 2, 0);
    expect_valid(&c, pts, N, ids, seg, 2, "collinear start");
    radinterp__cdt_free(&c);
}

static void test_cdt_duplicates_and_points_on_constraints(void)
{
    enum { N = 400 };
    static double pts[2 * N];
    static uint32_t ids[N], seg[2 * 6];
    radinterp__cdt c;
    uint32_t i;
    /* a square frame, its diagonals (crossing at the centre), then points
       exactly on them (dyadic fractions are exact) and duplicates */
    double frame[8][2] = {{0, 0}, {8, 0}, {8, 8}, {0, 8}, {0, 4}, {8, 4}, {4, 0}, {4, 8}};
    uint32_t s[12] = {0, 2, 1, 3, 4, 5, 6, 7, 0, 1, 2, 3};
    for (i = 0; i < 8; i++) { pts[2 * i] = frame[i][0]; pts[2 * i + 1] = frame[i][1]; }
    for (i = 8; i < N; i++) {
        double t = (double)(rnd_int(64) + 1) / 64.0;  /* on a constraint */
        switch (i % 5) {
        case 0: pts[2 * i] = 8 * t; pts[2 * i + 1] = 8 * t; break;        /* diagonal */
        case 1: pts[2 * i] = 8 * t; pts[2 * i + 1] = 8 - 8 * t; break;    /* other diagonal */
        case 2: pts[2 * i] = 8 * t; pts[2 * i + 1] = 4; break;            /* midline */
        case 3: pts[2 * i] = pts[2 * (i - 3)]; pts[2 * i + 1] = pts[2 * (i - 3) + 1]; break; /* duplicate */
        default: pts[2 * i] = 8 * rnd(); pts[2 * i + 1] = 8 * rnd(); break;
        }
    }
    memcpy(seg, s, sizeof s);
    radinterp__cdt_init(&c, &heap, NULL, 0);
    /* constraints first, then the points that land on them */
    for (i = 0; i < 8; i++) ids[i] = radinterp__cdt_add_point(&c, pts[2 * i], pts[2 * i + 1]);
    for (i = 0; i < 6; i++) radinterp__cdt_add_segment(&c, ids[seg[2 * i]], ids[seg[2 * i + 1]]);
    for (i = 8; i < N; i++) ids[i] = radinterp__cdt_add_point(&c, pts[2 * i], pts[2 * i + 1]);
    expect_valid(&c, pts, N, ids, seg, 6, "points on constraints");
    for (i = 8; i < N; i++)
        if (i % 5 == 3) CHECK(ids[i] == ids[i - 3]);  /* duplicates merged */
    radinterp__cdt_free(&c);
}

/* Nearly collinear, overlapping constraints (as projected blocker edges that
   coincide in space but were computed separately): must terminate valid. */
static void test_cdt_overlapping_near_collinear(void)
{
    enum { N = 64, S = 40 };
    static double pts[2 * N];
    static uint32_t ids[N], seg[2 * S];
    radinterp__cdt c;
    uint32_t i;
    for (i = 0; i < N; i++) {
        double t = rnd();
        pts[2 * i] = t;
        pts[2 * i + 1] = 0.3 * t + 1e-15 * (rnd() - 0.5) * (i % 2);  /* within rounding of one line */
    }
    pts[0] = -1.0; pts[1] = -1.0;
    pts[2] = 2.0; pts[3] = 2.0;
    for (i = 0; i < S; i++) { seg[2 * i] = 2 + rnd_int(N - 2); seg[2 * i + 1] = 2 + rnd_int(N - 2); }
    radinterp__cdt_init(&c, &heap, NULL, 0);
    build(&c, pts, N, ids, seg, S, 0);
    {
        check_result r = cdt_check(&c, pts, N, ids, seg, S);
        CHECK(!c.failed);
        CHECK(r.symmetric && r.ccw && r.area && r.vertices && r.delaunay);
        /* constraints within rounding of each other bend through each
           other's endpoints; they are present to 1e-12 of their length */
        for (i = 0; i < S; i++) CHECK(constraint_present(&c, ids[seg[2 * i]], ids[seg[2 * i + 1]], 1e-12));
    }
    radinterp__cdt_free(&c);
}

/* Caller memory first, then growth through the allocator. */
static void test_cdt_stack_memory_growth(void)
{
    enum { N = 2000, S = 50 };
    static double pts[2 * N];
    static uint32_t ids[N], seg[2 * S];
    double mem[512];
    radinterp__cdt c;
    uint32_t i;
    for (i = 0; i < N; i++) { pts[2 * i] = rnd() * 3.0; pts[2 * i + 1] = rnd(); }
    for (i = 0; i < S; i++) { seg[2 * i] = rnd_int(N); seg[2 * i + 1] = rnd_int(N); }
    radinterp__cdt_init(&c, &heap, mem, sizeof mem);
    CHECK(c.vertex_cap > 0 && !c.owns_xy);
    build(&c, pts, N, ids, seg, S, 0);
    CHECK(c.owns_xy && c.owns_tri);
    expect_valid(&c, pts, N, ids, seg, S, "growth");
    radinterp__cdt_clear(&c);
    build(&c, pts, 100, ids, NULL, 0, 0);
    expect_valid(&c, pts, 100, ids, NULL, 0, "reuse after clear");
    radinterp__cdt_free(&c);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_orient2d_exact);
    RUN(test_incircle_exact);
    RUN(test_cdt_random_points);
    RUN(test_cdt_random_crossing_constraints);
    RUN(test_cdt_grid_collinear_runs);
    RUN(test_cdt_collinear_start);
    RUN(test_cdt_duplicates_and_points_on_constraints);
    RUN(test_cdt_overlapping_near_collinear);
    RUN(test_cdt_stack_memory_growth);
    return test_finish();
}
