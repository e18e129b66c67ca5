/* Unit tests of radinterp.h part 5, the solver at scale (issue 13's
   acceptance tests that fit in make test; buildings are in
   tests/bench_radinterp_building.c): the clustered solve against the
   unclustered one on the Cornell box, no light through a
   solid wall between two rooms, triangle-soup input (T-junctions, slivers,
   zero-area triangles, duplicates, coplanar overlaps), cancel from every
   progress call of the solve and of the mesh build without a leak, progress
   paced by work, and the accepted coordinate range. */

/* The pacer's clock (RADINTERP_CPU_SECONDS) is simulated work: it moves
   when costly_for charges the jobs it runs, and by clock_step at every
   reading, so progress calls come at the same places in every run (the
   cancel sweeps count them) and a test can give work a cost. */
static double work_seconds, clock_step;
static long clock_readings;
#define RADINTERP_CPU_SECONDS() (clock_readings++, work_seconds += clock_step)
#define RADINTERP_IMPLEMENTATION
#include "../radinterp.h"
#include "examples/common/obj.h"
#include "test.h"
#include "test_radinterp_scenes.h"

#define PI 3.14159265358979323846

/* ---- scenes ---------------------------------------------------------------- */
/* Scenes are tests/test_radinterp_scenes.h's (its building and its box
   faces), a few shapes of their own, and the examples' OBJ files. */
static void add_tri(rb_scene *s, const float *a, const float *b, const float *c, uint32_t mat)
{
    uint32_t *q;
    rb__grow(s, 3, 1);
    q = s->patch + 4 * s->np;
    q[0] = rb__vertex(s, a); q[1] = rb__vertex(s, b); q[2] = rb__vertex(s, c); q[3] = RADINTERP_NO_VERTEX;
    s->mat[s->np++] = mat;
}

static void grey_material(rb_scene *s, int i, float rho, float e) { rb_material(s, i, rho, rho, rho, e); }

/* An OBJ+MTL scene as patches (faces of 3 or 4 corners, emission pi Ke);
   its materials into *mats (malloc'd). */
static int load_scene(rb_scene *s, radinterp_material **mats, uint32_t *material_count, const char *path)
{
    char err[256];
    obj_scene obj;
    uint32_t f, k;
    memset(s, 0, sizeof *s);
    *mats = NULL;
    if (obj_load(path, &obj, err, sizeof err) != 0) {
        CHECK_MSG(0, "%s", err);
        return 0;
    }
    rb__grow(s, obj.vertex_count, obj.face_count);
    for (k = 0; k < obj.vertex_count; k++) rb__vertex(s, obj.positions + 3 * k);
    for (f = 0; f < obj.face_count; f++) {
        uint32_t n = obj.face_start[f + 1] - obj.face_start[f];
        for (k = 0; k < 4; k++) s->patch[4 * f + k] = k < n ? obj.face_vertices[obj.face_start[f] + k] : RADINTERP_NO_VERTEX;
        s->mat[f] = obj.face_material[f];
    }
    s->np = obj.face_count;
    *mats = (radinterp_material *)calloc(obj.material_count, sizeof **mats);
    *material_count = obj.material_count;
    for (f = 0; f < obj.material_count; f++)
        for (k = 0; k < 3; k++) {
            (*mats)[f].reflectance[k] = obj.materials[f].kd[k];
            (*mats)[f].emission[k] = (float)PI * obj.materials[f].ke[k];
        }
    obj_free(&obj);
    return 1;
}

static double lum(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

/* Patch radiosities (luminance) of a solve, or NULL when it failed. */
static double *solve_patches(const radinterp_desc *d, radinterp_info *info)
{
    radinterp_solution *sol;
    double *b;
    uint32_t i;
    if (!CHECK_EQ_INT(radinterp_solve(d, &sol), RADINTERP_OK)) return NULL;
    b = (double *)malloc(sizeof(double) * d->patch_count);
    for (i = 0; i < d->patch_count; i++) {
        float rgb[3] = {0, 0, 0};
        CHECK_EQ_INT(radinterp_patch_radiosity(sol, i, rgb), RADINTERP_OK);
        b[i] = lum(rgb);
    }
    if (info) radinterp_solution_info(sol, info);
    radinterp_solution_destroy(sol);
    return b;
}

/* ---- clustered = unclustered ---------------------------------------------- */
/* The clustered solve against the unclustered one, same eps. Two solves
   differ by where refinement stopped (links within their tolerance, 5% of
   the receiver's irradiance by default, are left as they are), so the
   solvers are compared with themselves first, each with another seed:
   the larger of the two spreads is what two equally good solutions of
   this eps differ by (up to 3% on faces that stand on the floor in the
   Cornell box, whose light comes through hundreds of links at min_area).
   A patch passes within 1% of its radiosity (of a fifth of the scene's
   mean where it is darker) plus twice that spread; the mean difference over the patches, where the
   spread averages out, is held to 1% alone. Before the refinement estimate
   sampled the receiver point nearest the source, the Cornell box's short
   block face was 3.7% darker clustered (eps 0.005) while its spread was
   under 0.5%. */
static void compare_clustering(const char *path, float eps)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_info ic, iu;
    double *bc, *bu, *bs, *bcs, mean = 0.0, sum_rel = 0.0, worst = 0.0;
    uint32_t i, n = 0, worst_patch = 0;
    radinterp_material *mats;
    uint32_t nm;
    if (!load_scene(&s, &mats, &nm, path)) { rb_free(&s); return; }
    d = rb_desc(&s);
    d.materials = mats;
    d.material_count = nm;
    d.eps = eps;
    d.clustering = RADINTERP_CLUSTERING_ON;
    bc = solve_patches(&d, &ic);
    d.clustering = RADINTERP_CLUSTERING_OFF;
    bu = solve_patches(&d, &iu);
    d.seed = 1;
    bs = solve_patches(&d, NULL);
    d.clustering = RADINTERP_CLUSTERING_ON;
    bcs = solve_patches(&d, NULL);
    if (bc && bu && bs && bcs) {
        CHECK(ic.cluster_count > 0);
        CHECK_EQ_INT(iu.cluster_count, 0);
        for (i = 0; i < s.np; i++)
            if (lum(mats[s.mat[i]].emission) == 0.0f) { mean += bu[i]; n++; }
        mean = n ? mean / n : 1.0;
        for (i = 0; i < s.np; i++) {
            double scale = bu[i] > 0.2 * mean ? bu[i] : 0.2 * mean, diff = fabs(bc[i] - bu[i]);
            double spread = fabs(bs[i] - bu[i]) > fabs(bcs[i] - bc[i]) ? fabs(bs[i] - bu[i]) : fabs(bcs[i] - bc[i]);
            CHECK_MSG(diff <= 0.01 * scale + 2.0 * spread, "%s patch %u: clustered %.5f (another seed %.5f), unclustered %.5f "
                      "(another seed %.5f)", path, i, bc[i], bcs[i], bu[i], bs[i]);
            sum_rel += diff / scale;
            if (diff / scale > worst) { worst = diff / scale; worst_patch = i; }
        }
        CHECK_MSG(sum_rel / s.np <= 0.01, "%s: mean difference %.2f%%", path, 100.0 * sum_rel / s.np);
        test_note("%s: clustered vs unclustered: mean %.2f%%, largest %.2f%% (patch %u; another seed moves the unclustered "
                  "solve by %.2f%% there, the clustered one by %.2f%%); links %u + %u cluster links vs %u", path,
                  100.0 * sum_rel / s.np, 100.0 * worst, worst_patch,
                  100.0 * fabs(bs[worst_patch] - bu[worst_patch]) / (bu[worst_patch] > 0.2 * mean ? bu[worst_patch] : 0.2 * mean),
                  100.0 * fabs(bcs[worst_patch] - bc[worst_patch]) / (bu[worst_patch] > 0.2 * mean ? bu[worst_patch] : 0.2 * mean),
                  ic.link_count, ic.cluster_link_count, iu.link_count);
    }
    free(bc);
    free(bu);
    free(bs);
    free(bcs);
    free(mats);
    rb_free(&s);
}

/* The Cornell box with the defaults. The office is not held to it: there
   the clustered solve leaves the lamp's pole 5% darker than the
   unclustered one (12% with eps_relative 0.02), while another seed moves
   it by 0.2%: the near field of the lamp shade, which the pole touches, is
   refined differently, and that is not resolved yet. */
static void test_clustered_equals_unclustered(void)
{
    compare_clustering("examples/data/cornell_box.obj", 0.0f);
}

/* ---- a solid wall between two rooms ------------------------------------- */
/* Which rooms of a two-room building (tests/test_radinterp_scenes.h) a
   patch is inside: bit 0 the left room, bit 1 the right one, 0 for the
   building's outer faces. */
static unsigned patch_room(const rb_scene *b, uint32_t p)
{
    const float split = RB_WALL + RB_ROOM_W + 0.5f * RB_WALL;   /* the middle of the wall between them */
    float x = 0.0f;
    uint32_t k, n = 0;
    if (b->mat[p] == RB_OUTSIDE) return 0;
    for (k = 0; k < 4 && b->patch[4 * p + k] != RADINTERP_NO_VERTEX; k++, n++) x += b->pos[3 * b->patch[4 * p + k]];
    return x / n < split ? 1u : 2u;
}

/* The rooms an element (a quadtree node or a cluster) holds patches of. */
static unsigned element_rooms(const radinterp_solution *sol, const rb_scene *b, uint32_t el)
{
    unsigned rooms = 0;
    uint32_t i;
    if (!radinterp__is_cluster(el)) return patch_room(b, sol->first_caller[sol->nodes[el].patch]);
    for (i = 0; i < radinterp__cl(sol, el)->count; i++)
        rooms |= patch_room(b, sol->first_caller[sol->cluster_order[radinterp__cl(sol, el)->first + i]]);
    return rooms;
}

/* Two rooms of the generated building (desk, cabinet, lamp each; exported
   as triangles) with the wall between them solid, the right room's lamp
   switched off. The right room must stay exactly black, and no link may
   carry light between patches of the two rooms: with clustering the first
   links join clusters that span both, and those must be dropped or split
   until nothing crosses (a cluster link whose rays were all blocked but
   that planes could not prove hidden is kept at a transfer of zero, to be
   split if it could ever carry more). */
static void test_wall_between_rooms(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    radinterp_info info;
    uint32_t i, crossing = 0, lit = 0, right = 0;
    rb_building(&s, 2, 1, 1, RB_NO_DOORS | RB_TRIANGLES);
    for (i = 0; i < s.np; i++)
        if (s.mat[i] == RB_LAMP && patch_room(&s, i) == 2) s.mat[i] = RB_LAMP_FRAME;
    d = rb_desc(&s);
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
    radinterp_solution_info(sol, &info);
    for (i = 0; i < sol->link_count; i++)
        crossing += sol->links[i].ff > 0.0f &&
                    (element_rooms(sol, &s, sol->links[i].receiver) | element_rooms(sol, &s, sol->links[i].source)) == 3u;
    for (i = 0; i < sol->clink_count; i++)
        crossing += sol->clinks[i].k > 0.0f &&
                    (element_rooms(sol, &s, sol->clinks[i].receiver) | element_rooms(sol, &s, sol->clinks[i].source)) == 3u;
    CHECK_EQ_INT(crossing, 0);
    for (i = 0; i < radinterp_leaf_count(sol); i++) {
        radinterp_leaf leaf;
        radinterp_get_leaf(sol, i, &leaf);
        if (patch_room(&s, leaf.patch) != 2) continue;
        right++;
        lit += leaf.radiosity[0] != 0.0f || leaf.radiosity[1] != 0.0f || leaf.radiosity[2] != 0.0f;
    }
    CHECK(right > 0);
    CHECK_EQ_INT(lit, 0);
    {   /* and the left room is lit: its floor (about 0.26 W/m^2) */
        float rgb[3] = {0, 0, 0};
        for (i = 0; i < s.np; i++)
            if (s.mat[i] == RB_FLOOR && patch_room(&s, i) == 1) break;
        radinterp_patch_radiosity(sol, i, rgb);
        CHECK(rgb[0] > 0.1f);
    }
    test_note("two rooms (%u patches): %u links, %u cluster links, %llu pairs dropped as hidden, %u crossing, "
              "%u of %u right-room leaves lit", s.np, info.link_count, info.cluster_link_count,
              (unsigned long long)info.culled_links, crossing, lit, right);
    radinterp_solution_destroy(sol);
    rb_free(&s);
}

/* Three rooms in a row with doors between them, the lamp of the left one
   alone lit (the others' lamps made frames): the right rooms are lit only
   through the doors, dim enough that the eps floors set their tolerances. */
static void rooms_lit_from_the_left(rb_scene *s)
{
    uint32_t i;
    rb_building(s, 3, 1, 1, 0);
    for (i = 0; i < s->np; i++)
        if (s->mat[i] == RB_LAMP && s->pos[3 * s->patch[4 * i]] > RB_ROOM_W + RB_WALL) s->mat[i] = RB_LAMP_FRAME;
}

/* The solution's source summaries (radinterp__source_sums), made serially. */
static radinterp__source_sum *source_sums_of(const radinterp_solution *sol)
{
    radinterp_desc d;
    radinterp__run run;
    memset(&d, 0, sizeof d);
    memset(&run, 0, sizeof run);
    run.desc = &d;
    return radinterp__source_sums(sol, &run);
}

/* A link's transport error (radinterp__link_error) from its source node. */
static double node_link_error(const radinterp_solution *s, const radinterp__link *l)
{
    const float *b = s->nodes[l->source].b;
    return (double)radinterp__maxf(b[0], radinterp__maxf(b[1], b[2])) * (double)l->dff;
}

/* A link whose source is partly hidden from its receiver measures the
   source's variation over its leaves, not its children (radinterp__link_
   source_spread): three rooms in a row, doors between them, a lamp in the
   left one only, a few iterations (refinement still under way). Push-pull
   keeps each node's spread of its open leaves' radiosities (checked against
   the leaves); partly hidden links whose source's leaves differ by more
   than its children exist here (the floors and ceilings run under the
   partitions), and each link's source error (what refinement and the receiver
   budget count) is its factor times the leaves' spread when it is partly
   hidden, the children's otherwise. With the children's spread alone (the
   mechanism broken) the last check fails; test_refine_decisions checks the
   decisions made of it. */
static void test_partly_hidden_source_spread(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    uint32_t i, partly = 0, deeper = 0, over = 0, bad_spread = 0, wrong = 0;
    radinterp__source_sum *ss;
    rooms_lit_from_the_left(&s);
    d = rb_desc(&s);
    d.max_iterations = 3;
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
    for (i = 0; i < sol->node_count; i++) {   /* the spread of each node's open leaves */
        double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, want = 0.0;
        uint32_t stack[64], n = 0, j;
        int k;
        if (sol->nodes[i].child == RADINTERP__NONE) { bad_spread += sol->nodes[i].spread != 0.0f; continue; }
        stack[n++] = i;
        while (n) {
            const radinterp__node *nd = &sol->nodes[stack[--n]];
            if (nd->child != RADINTERP__NONE) {
                for (j = 0; j < 4 && n < 64; j++) stack[n++] = nd->child + j;
                continue;
            }
            for (k = 0; k < 3 && nd->open > 0.0f; k++) {
                lo[k] = nd->b[k] < lo[k] ? nd->b[k] : lo[k];
                hi[k] = nd->b[k] > hi[k] ? nd->b[k] : hi[k];
            }
        }
        for (k = 0; k < 3; k++) want = hi[k] - lo[k] > want ? hi[k] - lo[k] : want;
        bad_spread += fabs((double)sol->nodes[i].spread - want) > 1e-5 * (want > 1e-3 ? want : 1e-3);
    }
    ss = source_sums_of(sol);
    CHECK(ss != NULL);
    for (i = 0; ss && i < sol->link_count; i++) {
        const radinterp__link *l = &sol->links[i];
        double near = radinterp__source_spread(sol, l->source), deep = sol->nodes[l->source].spread;
        double ff = radinterp__link_ff_max(l), tol = radinterp__tolerance(sol, sol->nodes[l->receiver].dim);
        double want = (l->flags & RADINTERP__LINK_PARTLY) && deep > near ? deep * ff : near * ff;
        wrong += radinterp__source_error(ss, l) != want;
        if (!(l->flags & RADINTERP__LINK_PARTLY)) continue;
        partly++;
        if (deep <= near) continue;
        deeper++;
        over += deep * ff > tol && !(near * ff > tol);   /* over its tolerance by the leaves alone */
    }
    CHECK_EQ_INT(bad_spread, 0);
    CHECK(deeper > 0);
    CHECK_EQ_INT(wrong, 0);
    test_note("three rooms, one lamp: %u links, %u partly hidden, %u of them from sources whose leaves differ more than "
              "their children, %u of those over their tolerance by the leaves alone; %u links misjudged",
              sol->link_count, partly, deeper, over, wrong);
    radinterp__free(&sol->allocator, ss);
    radinterp_solution_destroy(sol);
    rb_free(&s);
}

/* A source's variation has its own floor, eps_source (default a tenth of
   eps): splitting a source adds links, not leaves, so the lampless room's
   sources are split finer than its receivers. Three rooms in a row, doors,
   a lamp in the left room only, a default solve: the right rooms' receivers
   are dim enough that the floors set their tolerances. Checks that the
   floors are as documented (explicit eps: eps_source = eps), that links
   whose tolerance eps's floor sets above the source floor's exist (the
   case), and that after the solve no link that could still split its source
   carries a source error beyond a quarter over its source tolerance (the
   iterations after the last refinement pass move the radiosities a little).
   With eps_source = eps (built with -DRADINTERP__EPS_SOURCE_FLOOR=0.01, the
   mechanism off) the first and the last check fail. */
static void test_source_floor(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    uint32_t i, floor_set = 0, over = 0;
    radinterp__source_sum *ss;
    rooms_lit_from_the_left(&s);
    d = rb_desc(&s);
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
    CHECK_CLOSE(sol->eps_source, 0.1 * sol->eps, 1e-12, 0.0);
    ss = source_sums_of(sol);
    CHECK(ss != NULL);
    for (i = 0; ss && i < sol->link_count; i++) {   /* the source tolerance recomputed: eps_relative of the level, 0.1 eps */
        const radinterp__link *l = &sol->links[i];
        double level = sol->nodes[l->receiver].dim, err = radinterp__source_error(ss, l);
        double src_tol = sol->eps_relative * level > 0.1 * sol->eps ? sol->eps_relative * level : 0.1 * sol->eps;
        floor_set += radinterp__tolerance(sol, level) > 1.25 * src_tol;
        over += !(l->flags & RADINTERP__LINK_FINAL) && radinterp__can_split(sol, &sol->nodes[l->source]) &&
                err > 1.25 * src_tol;
    }
    test_note("three rooms, one lamp: %u links, %u where eps's floor sets the tolerance above the source's by a "
              "quarter, %u over their source tolerance by a quarter", sol->link_count, floor_set, over);
    CHECK(floor_set > 0);
    CHECK_EQ_INT(over, 0);
    radinterp__free(&sol->allocator, ss);
    radinterp_solution_destroy(sol);
    d.eps = 0.01f;   /* explicit: one floor, as before */
    if (CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) {
        CHECK(sol->eps_source == sol->eps);
        radinterp_solution_destroy(sol);
    }
    rb_free(&s);
}

/* The planes search between two boxes (radinterp__planes_hide) keeps the
   patches whose planes separate them, once each, in the order the walk
   meets them; it finds them by hash and skips a patch's second triangle.
   A plain scan of the list kept so far (the search before) must end the
   same walk with the same answer, visits and list, for every pair of
   elements the solve of a building of 3 x 2 rooms of quadrilaterals (two
   triangles a patch), with doors and without, linked and for the pairs of
   its largest clusters, of which some must fill the list or stop at the
   visit limit, and some must be hidden. The scan reads the planes from the
   patches, the library from its compact copy (radinterp__plane): a copy
   that differs makes the walks differ. For each plane found, the range of
   the segments' crossings (radinterp__crossings_range, corner heights
   computed once) must equal, bit for bit, the range computed segment by
   segment. Pairs whose boxes overlap are answered without the walk
   (radinterp__boxes_inseparable): no patch of the scene may separate such
   a pair. Judging the overlap on x and y alone, 27 of the 1,082 pairs
   skipped had a separating patch. */
static int scan_visit(void *ctx_, uint32_t b)
{
    radinterp__hide_ctx *c = (radinterp__hide_ctx *)ctx_;
    const radinterp__patch *pt = &c->s->patches[b];
    uint32_t i;
    if (++c->visits > RADINTERP__HIDE_VISITS) return 0;
    if (pt->glass || !radinterp__plane_separates(c, pt->n, pt->d)) return 1;
    for (i = 0; i < c->count; i++)
        if (c->found[i] == b) return 1;
    if (c->count == RADINTERP__HIDE_PATCHES) return 0;
    c->found[c->count++] = b;
    return 1;
}

/* The range of the crossings as plane_covers computed it before, each
   segment's end heights computed for the segment. */
static void scan_crossings(const radinterp__hide_ctx *c, const double *n, double d, const double *e1, const double *e2,
                           double *lo, double *hi)
{
    int i, j, k;
    for (i = 0; i < 8; i++)
        for (j = 0; j < 8; j++) {
            double a[3], b[3], ta, tb, t, x[3];
            for (k = 0; k < 3; k++) {
                a[k] = (i >> k) & 1 ? c->hi[0][k] : c->lo[0][k];
                b[k] = (j >> k) & 1 ? c->hi[1][k] : c->lo[1][k];
            }
            ta = radinterp__d3_dot(n, a) - d;
            tb = radinterp__d3_dot(n, b) - d;
            t = ta != tb ? ta / (ta - tb) : 0.0;
            t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
            for (k = 0; k < 3; k++) x[k] = a[k] + t * (b[k] - a[k]);
            for (k = 0; k < 2; k++) {
                double u = radinterp__d3_dot(x, k ? e2 : e1);
                lo[k] = u < lo[k] ? u : lo[k];
                hi[k] = u > hi[k] ? u : hi[k];
            }
        }
}

typedef struct planes_tally {
    uint32_t pairs, differ, full, hidden, planes, crossings_differ;
    uint32_t inseparable, separated;   /* pairs radinterp__boxes_inseparable skips; of them, with a separating patch */
} planes_tally;
static void planes_search_matches(const radinterp_solution *sol, const float *alo, const float *ahi, const float *blo,
                                  const float *bhi, planes_tally *t)
{
    radinterp__hide_ctx c, ref;
    int got, want;
    uint32_t i;
    radinterp__hide_init(&c, sol, alo, ahi, blo, bhi);
    radinterp__hide_init(&ref, sol, alo, ahi, blo, bhi);
    got = radinterp__bvh_walk(sol, radinterp__hide_box, radinterp__hide_visit, &c);
    want = radinterp__bvh_walk(sol, radinterp__hide_box, scan_visit, &ref);
    t->pairs++;
    t->differ += got != want || c.visits != ref.visits || c.count != ref.count ||
                 memcmp(c.found, ref.found, c.count * sizeof c.found[0]) != 0;
    t->full += !want;
    t->hidden += (uint32_t)radinterp__planes_hide(sol, alo, ahi, blo, bhi);
    if (radinterp__boxes_inseparable(&c)) {   /* no patch of the scene may separate them */
        uint32_t p, any = 0;
        for (p = 0; p < sol->patch_count; p++) any |= (uint32_t)radinterp__plane_separates(&c, sol->planes[p].n, sol->planes[p].d);
        t->inseparable++;
        t->separated += any;
    }
    for (i = 0; i < c.count; i++) {   /* the crossings of each separating plane found, in a skewed frame */
        static const double e1[3] = {0.6, 0.8, 0.0}, e2[3] = {0.0, 0.28, 0.96};
        const radinterp__patch *pt = &sol->patches[c.found[i]];
        double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX}, rlo[2] = {DBL_MAX, DBL_MAX},
               rhi[2] = {-DBL_MAX, -DBL_MAX};
        radinterp__crossings_range(&c, pt->n, pt->d, e1, e2, lo, hi);
        scan_crossings(&c, pt->n, pt->d, e1, e2, rlo, rhi);
        t->planes++;
        t->crossings_differ += memcmp(lo, rlo, sizeof lo) != 0 || memcmp(hi, rhi, sizeof hi) != 0;
    }
}

static void test_planes_search(void)
{
    static const unsigned flags[2] = {0, RB_NO_DOORS};
    planes_tally t;
    uint32_t i, j, f;
    memset(&t, 0, sizeof t);
    for (f = 0; f < 2; f++) {
        rb_scene s;
        radinterp_desc d;
        radinterp_solution *sol;
        uint32_t big[8], nbig = 0;
        rb_building(&s, 3, 2, 1, flags[f]);
        d = rb_desc(&s);
        d.eps_relative = 0.5f;   /* a coarse solve: the pairs, not the links, are tested */
        if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
        for (i = 0; i < sol->link_count; i += 7) {
            const radinterp__node *r = &sol->nodes[sol->links[i].receiver], *src = &sol->nodes[sol->links[i].source];
            planes_search_matches(sol, r->lo, r->hi, src->lo, src->hi, &t);
        }
        for (i = 0; i < sol->cluster_count; i++) {   /* the 8 clusters of most patches */
            for (j = nbig < 8 ? nbig++ : 8; j > 0 && sol->clusters[big[j - 1]].count < sol->clusters[i].count; j--)
                if (j < 8) big[j] = big[j - 1];
            if (j < 8) big[j] = i;
        }
        for (i = 0; i < nbig; i++)
            for (j = 0; j < sol->cluster_count; j += 3)
                planes_search_matches(sol, sol->clusters[big[i]].lo, sol->clusters[big[i]].hi, sol->clusters[j].lo,
                                      sol->clusters[j].hi, &t);
        radinterp_solution_destroy(sol);
        rb_free(&s);
    }
    test_note("%u pairs: %u differ from the scan, %u stopped (list full or visit limit), %u hidden; crossings of %u "
              "planes: %u differ; %u pairs overlap (no walk), %u of them with a separating patch", t.pairs, t.differ,
              t.full, t.hidden, t.planes, t.crossings_differ, t.inseparable, t.separated);
    CHECK(t.inseparable > 0);
    CHECK_EQ_INT(t.separated, 0);
    CHECK_EQ_INT(t.differ, 0);
    CHECK_EQ_INT(t.crossings_differ, 0);
    CHECK(t.planes > 0);
    CHECK(t.full > 0 && t.hidden > 0);
}

/* ---- refinement's decisions ---------------------------------------------------- */
/* Refinement decides every link first, in parallel jobs (budget marks, then
   decisions), and splits after. The pass it replaces decided link by link,
   each after the splits of the links before it; the decisions must be the
   same. The reference here is that pass (its code as it was, one scratch
   array for the budgets, splitting nodes as it goes) on a building of
   3 x 2 rooms stopped after 3 iterations (much left to refine), against the
   library's jobs run last to first. Some links must see a source split
   earlier in the pass (the case the claim is about), and each kind of
   decision must occur. The reference reads the nodes, the library its
   summaries of them (radinterp__source_sums): with their B's largest
   channel taken as its first, 54 of 25,378 links were decided otherwise. */
static void reversed_for(void *user, radinterp_job_fn job, void *ctx, uint32_t count)
{
    (void)user;
    while (count > 0) job(ctx, --count);
}

static unsigned char reference_decision(const radinterp_solution *s, const radinterp__link *l, unsigned char mark)
{
    double error = node_link_error(s, l), tol = radinterp__tolerance(s, s->nodes[l->receiver].dim);
    /* a receiver that holds a wall's foot near min_area: to its children (v0.8.19) */
    if (!(l->flags & RADINTERP__LINK_FINAL) && radinterp__divided_below(s, &s->nodes[l->receiver]))
        return RADINTERP__REFINE_RECEIVER;
    if (!(l->flags & RADINTERP__LINK_FINAL) && mark == RADINTERP__SPLIT_SOURCE) return RADINTERP__REFINE_SOURCE;
    if (!(l->flags & RADINTERP__LINK_FINAL) && (error > tol || mark)) {
        const radinterp__node *r = &s->nodes[l->receiver], *src = &s->nodes[l->source];
        int rs = radinterp__can_split(s, r), ss = radinterp__can_split(s, src);
        if (rs && (r->area >= src->area || !ss)) return RADINTERP__REFINE_RECEIVER;
        if (ss) return RADINTERP__REFINE_SOURCE;
        return RADINTERP__REFINE_FINAL;
    }
    {   /* a partly hidden source: the spread of its leaves where that is more (its children may be alike) */
        double spread = radinterp__source_spread(s, l->source), leaves = s->nodes[l->source].spread;
        double src_tol = radinterp__source_tolerance(s, s->nodes[l->receiver].dim);   /* eps_source's floor */
        if ((l->flags & RADINTERP__LINK_PARTLY) && leaves > spread) spread = leaves;
        if (!(l->flags & RADINTERP__LINK_FINAL) && spread * radinterp__link_ff_max(l) > src_tol) return RADINTERP__REFINE_SOURCE;
    }
    return RADINTERP__REFINE_KEEP;
}

static void test_refine_decisions(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    radinterp__run run;
    radinterp__source_sum *ss;
    unsigned char *got, *want;
    double *err;
    uint32_t i, most = 1, nodes_before, differ = 0, after_split = 0, kinds[4] = {0, 0, 0, 0};
    rb_building(&s, 3, 2, 1, 0);
    d = rb_desc(&s);
    d.max_iterations = 3;
    d.parallel_for = reversed_for;
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
    memset(&run, 0, sizeof run);
    run.desc = &d;
    ss = radinterp__source_sums(sol, &run);
    got = ss ? radinterp__budget_marks(sol, ss, &run) : NULL;
    want = (unsigned char *)calloc(sol->link_count ? sol->link_count : 1, 1);
    for (i = 0; i < sol->node_count; i++) most = sol->nodes[i].link_count > most ? sol->nodes[i].link_count : most;
    err = (double *)malloc(most * sizeof(double));
    if (CHECK(got && want && err)) {
        radinterp__decide_ctx dc;
        dc.s = sol;
        dc.ss = ss;
        dc.mark = got;
        reversed_for(NULL, radinterp__decide_job, &dc, (sol->link_count + RADINTERP__REFINE_BLOCK - 1) / RADINTERP__REFINE_BLOCK);
        for (i = 0; i < sol->node_count; i++)
            if (sol->nodes[i].link_count) radinterp__spread_budget(sol, ss, &sol->nodes[i], err, want + sol->nodes[i].first_link);
        nodes_before = sol->node_count;
        for (i = 0; i < sol->link_count; i++) {
            const radinterp__link *l = &sol->links[i];
            uint32_t src = l->source;
            after_split += sol->nodes[src].child >= nodes_before && sol->nodes[src].child != RADINTERP__NONE;
            want[i] = reference_decision(sol, l, want[i]);
            differ += got[i] != want[i];
            kinds[want[i]]++;
            if (want[i] == RADINTERP__REFINE_RECEIVER || want[i] == RADINTERP__REFINE_SOURCE)
                CHECK_EQ_INT(radinterp__node_split(sol, want[i] == RADINTERP__REFINE_SOURCE ? src : l->receiver), 0);
        }
        test_note("%u links: %u differ; kept %u, to receivers' children %u, to sources' children %u, final %u; "
                  "%u met a source split earlier in the pass", sol->link_count, differ, kinds[0], kinds[1], kinds[2],
                  kinds[3], after_split);
        CHECK_EQ_INT(differ, 0);
        CHECK(kinds[0] > 0 && kinds[1] > 0 && kinds[2] > 0 && after_split > 0);
    }
    radinterp__free(&sol->allocator, got);
    radinterp__free(&sol->allocator, ss);
    free(want);
    free(err);
    radinterp_solution_destroy(sol);
    rb_free(&s);
}

/* radinterp__install_links reuses the link and blocker arrays: refinement
   packs the kept links at the front, and the new ones are merged in from
   the back. The result must be what installing into fresh arrays gives:
   each receiver's kept links, then its live pending ones in their order,
   every link's blockers in one pool in link order, and the nodes' link
   ranges. Checked on a solved building against such a reference, keeping
   every third link and installing the others as pending links in reverse
   order (so not sorted by receiver), every fifth of them dead. With the
   merge placing a receiver's pending links before its kept ones (> for
   >=), 21,278 of the 21,995 links installed differed. */
typedef struct install_key { uint32_t receiver, seq; } install_key;

static int cmp_install_key(const void *a, const void *b)
{
    const install_key *x = (const install_key *)a, *y = (const install_key *)b;
    if (x->receiver != y->receiver) return x->receiver < y->receiver ? -1 : 1;
    return x->seq < y->seq ? -1 : x->seq > y->seq;
}

static radinterp__pending pending_from_link(const radinterp__link *l, uint32_t first)
{
    radinterp__pending p;
    memset(&p, 0, sizeof p);
    p.receiver = l->receiver;
    p.source = l->source;
    p.ff = l->ff;
    p.dff = l->dff;
    p.vis = l->vis;
    p.gff = l->gff;
    memcpy(p.glass, l->glass, sizeof p.glass);
    p.partly = (l->flags & RADINTERP__LINK_PARTLY) != 0;
    p.first = first;
    p.kept = l->blocker_count;
    return p;
}

static void test_install_links_in_place(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    radinterp__run run;
    radinterp__link *old, *want;
    radinterp__pending *pend;
    install_key *key;
    uint32_t *old_pool, *pend_pool, i, n, kept = 0, np = 0, live = 0, at = 0, wrong = 0, bad_ranges = 0, r;
    uint64_t pool_at = 0;
    rb_building(&s, 3, 2, 1, 0);
    d = rb_desc(&s);
    d.max_iterations = 3;
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
    memset(&run, 0, sizeof run);
    run.desc = &d;
    n = sol->link_count;
    old = (radinterp__link *)malloc(n * sizeof *old);
    want = (radinterp__link *)malloc(n * sizeof *want);
    pend = (radinterp__pending *)malloc(n * sizeof *pend);
    key = (install_key *)malloc(n * sizeof *key);
    old_pool = (uint32_t *)malloc((size_t)(sol->blocker_count + 1) * sizeof *old_pool);
    pend_pool = (uint32_t *)malloc((size_t)(sol->blocker_count + 1) * sizeof *pend_pool);
    if (!CHECK(n > 1000 && old && want && pend && key && old_pool && pend_pool)) goto done;
    memcpy(old, sol->links, n * sizeof *old);
    memcpy(old_pool, sol->blockers, (size_t)sol->blocker_count * sizeof *old_pool);
    for (i = 0; i < n; i++)
        if (i % 3 == 0) {
            key[kept].receiver = old[i].receiver;
            key[kept].seq = i;   /* kept links come first in their receiver, in link order */
            sol->links[kept++] = old[i];
        }
    for (i = n; i-- > 0;) {
        if (i % 3 == 0) continue;
        pend[np] = pending_from_link(&old[i], at);
        if (old[i].blocker_count) memcpy(pend_pool + at, old_pool + old[i].first_blocker, old[i].blocker_count * sizeof *pend_pool);
        at += old[i].blocker_count;
        pend[np].dead = np % 5 == 4;
        if (!pend[np].dead) {
            key[kept + live].receiver = old[i].receiver;
            key[kept + live].seq = n + np;   /* then the live pending ones, in their order */
            live++;
        }
        np++;
    }
    qsort(key, kept + live, sizeof *key, cmp_install_key);
    for (i = 0; i < kept + live; i++) {
        if (key[i].seq < n) want[i] = old[key[i].seq];
        else {
            const radinterp__pending *p = &pend[key[i].seq - n];
            want[i] = old[0];
            want[i].receiver = p->receiver;
            want[i].source = p->source;
            want[i].ff = p->ff;
            want[i].dff = p->dff;
            want[i].vis = p->vis;
            want[i].gff = p->gff;
            memcpy(want[i].glass, p->glass, sizeof p->glass);
            want[i].flags = p->partly ? RADINTERP__LINK_PARTLY : 0u;
            want[i].blocker_count = p->kept;
        }
    }
    if (!CHECK_EQ_INT(radinterp__install_links(sol, &run, kept, pend, np, pend_pool), RADINTERP_OK)) goto done;
    CHECK_EQ_INT(sol->link_count, kept + live);
    for (i = 0; i < sol->link_count && i < kept + live; i++) {
        const radinterp__link *got = &sol->links[i], *w = &want[i];
        const uint32_t *wb = key[i].seq < n ? old_pool + w->first_blocker : pend_pool + pend[key[i].seq - n].first;
        int same = got->receiver == w->receiver && got->source == w->source && got->ff == w->ff && got->dff == w->dff &&
                   got->vis == w->vis && got->gff == w->gff && !memcmp(got->glass, w->glass, sizeof w->glass) &&
                   got->flags == w->flags && got->blocker_count == w->blocker_count && got->first_blocker == pool_at;
        if (same && w->blocker_count) same = !memcmp(sol->blockers + got->first_blocker, wb, w->blocker_count * sizeof *wb);
        wrong += !same;
        pool_at += got->blocker_count;
    }
    CHECK(pool_at == sol->blocker_count);
    for (r = 0, i = 0; r < sol->node_count; r++) {   /* each node's range: its links, in order */
        uint32_t first = i;
        while (i < sol->link_count && sol->links[i].receiver == r) i++;
        bad_ranges += sol->nodes[r].first_link != first || sol->nodes[r].link_count != i - first;
    }
    test_note("%u links: %u kept, %u pending (%u live); %u differ from a fresh install, %u node ranges wrong", n, kept, np,
              live, wrong, bad_ranges);
    CHECK_EQ_INT(wrong, 0);
    CHECK_EQ_INT(bad_ranges, 0);
done:
    free(old);
    free(want);
    free(pend);
    free(key);
    free(old_pool);
    free(pend_pool);
    radinterp_solution_destroy(sol);
    rb_free(&s);
}

/* ---- triangle soup ----------------------------------------------------------- */
static void v3(float *v, float x, float y, float z) { v[0] = x; v[1] = y; v[2] = z; }

/* A closed room 4 x 3 x 2.5 m as an engine exports it: every rectangle two
   triangles, the floor's left half three triangles meeting the right
   half's edge at a T-junction, a lamp panel, a cabinet one of whose faces
   comes twice (a duplicate), a rug lying on the floor (a coplanar overlap),
   a sliver (1 m x 0.1 um), a triangle with three collinear corners and one
   with a repeated corner (zero area). */
static void soup_room(rb_scene *s, int soup)
{
    float a[3], b[3], c[3], d[3], lo[3], hi[3];
    const uint32_t grey = 0, lamp = 1, rug = 2;
    int axis;
    memset(s, 0, sizeof *s);
    grey_material(s, grey, 0.7f, 0.0f);
    grey_material(s, lamp, 0.5f, 20.0f);
    grey_material(s, rug, 0.4f, 0.0f);
    s->flags = soup ? RB_TRIANGLES : 0;
    /* walls and ceiling: two triangles per rectangle (the inward box faces split) */
    lo[0] = 0; lo[1] = 0; lo[2] = 0; hi[0] = 4; hi[1] = 3; hi[2] = 2.5f;
    for (axis = 0; axis < 3; axis++) {
        int side;
        for (side = 0; side < 2; side++)
            if (axis != 2 || side != 0) rb_box_face(s, lo, hi, axis, side, 1, grey);   /* the floor comes below */
    }
    if (soup) {   /* floor (facing +z): left half with a T-junction at (2, 1.5) */
        v3(a, 0, 0, 0); v3(b, 2, 0, 0); v3(c, 2, 1.5f, 0); v3(d, 0, 3, 0);
        add_tri(s, a, b, c, grey);
        add_tri(s, a, c, d, grey);
        v3(a, 2, 1.5f, 0); v3(b, 2, 3, 0);
        add_tri(s, a, b, d, grey);
        v3(a, 2, 0, 0); v3(b, 4, 0, 0); v3(c, 4, 3, 0); v3(d, 2, 3, 0);
        add_tri(s, a, b, c, grey);
        add_tri(s, a, c, d, grey);
    } else rb_box_face(s, lo, hi, 2, 0, 1, grey);
    s->flags = 0;   /* the rest as quadrilaterals */
    lo[0] = 1.5f; lo[1] = 1.0f; lo[2] = 2.45f; hi[0] = 2.5f; hi[1] = 2.0f; hi[2] = 2.5f;
    rb_box_face(s, lo, hi, 2, 0, 0, lamp);
    lo[0] = 2.8f; lo[1] = 0.5f; lo[2] = 0.0f; hi[0] = 3.6f; hi[1] = 1.1f; hi[2] = 0.9f;
    rb_box(s, lo, hi, RB_ALL_FACES, grey);
    if (!soup) return;
    rb_box_face(s, lo, hi, 0, 0, 0, grey);                             /* the cabinet's -x face again */
    v3(a, 0.5f, 1.5f, 0); v3(b, 1.5f, 1.5f, 0); v3(c, 1.5f, 2.5f, 0); v3(d, 0.5f, 2.5f, 0);
    rb_quad(s, a, b, c, d, rug);                                       /* the rug, on the floor */
    v3(a, 1.0f, 2.0f, 1.0f); v3(b, 2.0f, 2.0f, 1.0f); v3(c, 1.5f, 2.0f, 1.0f + 1e-7f);
    add_tri(s, a, b, c, grey);                                         /* the sliver */
    v3(a, 1.0f, 1.0f, 1.2f); v3(b, 2.0f, 1.0f, 1.2f); v3(c, 3.0f, 1.0f, 1.2f);
    add_tri(s, a, b, c, grey);                                         /* collinear corners */
    add_tri(s, a, b, a, grey);                                         /* a repeated corner */
}

static void test_triangle_soup(void)
{
    rb_scene soup, clean;
    radinterp_desc d;
    radinterp_solution *sol = NULL, *ref = NULL;
    radinterp_info info;
    radinterp_mesh *mesh = NULL;
    radinterp_mesh_desc md;
    radinterp_mesh_info mi;
    uint32_t i, bad = 0;
    float rs[3], rc[3];
    soup_room(&soup, 1);
    soup_room(&clean, 0);
    d = rb_desc(&soup);
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) goto done;
    d = rb_desc(&clean);
    if (!CHECK_EQ_INT(radinterp_solve(&d, &ref), RADINTERP_OK)) goto done;
    radinterp_solution_info(sol, &info);
    CHECK_EQ_INT(info.skipped_patches, 2);        /* the collinear and the repeated-corner triangles */
    /* the four walls', the ceiling's and the floor's right half's triangle
       pairs at least (the left half's triangles may pair too: 7 measured) */
    CHECK(info.merged_patches >= 6);
    /* bounded: every radiosity finite, at most the emission over (1 - rho);
       the memory held is that of a small room */
    for (i = 0; i < radinterp_leaf_count(sol); i++) {
        radinterp_leaf leaf;
        int k;
        radinterp_get_leaf(sol, i, &leaf);
        for (k = 0; k < 3; k++) bad += !(leaf.radiosity[k] >= 0.0f && leaf.radiosity[k] <= 20.0f / (1.0f - 0.7f));
    }
    CHECK_EQ_INT(bad, 0);
    CHECK(info.bytes < (size_t)64 << 20);
    /* handled: the far wall (x = 4, away from every defect) as in the clean
       room within 3% (the duplicate face and the rug change the light a
       little: about 1%) */
    radinterp_patch_radiosity(sol, 2, rs);
    radinterp_patch_radiosity(ref, 1, rc);
    CHECK_MSG(fabs(rs[0] - rc[0]) <= 0.03 * rc[0], "far wall: soup %.4f, clean %.4f", rs[0], rc[0]);
    /* and it meshes */
    memset(&md, 0, sizeof md);
    md.min_leaf_area = 0.25f;   /* coarse: this is about the input, not the mesh's accuracy */
    if (CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &mesh), RADINTERP_OK)) {
        radinterp_mesh_data data;
        radinterp_mesh_get_info(mesh, &mi);
        radinterp_mesh_get_data(mesh, &data);
        for (i = 0; i < 18 * mi.triangle_count; i++) bad += !isfinite(data.coefficients[i]);
        CHECK_EQ_INT(bad, 0);
        CHECK(mi.triangle_count > 0);
        test_note("soup room: %u patches given, %u merged, %u skipped; far wall %.4f (clean %.4f); mesh %u triangles, "
                  "%u patches left out", info.patch_count, info.merged_patches, info.skipped_patches, rs[0], rc[0],
                  mi.triangle_count, mi.skipped_patches);
    }
done:
    radinterp_mesh_destroy(mesh);
    radinterp_solution_destroy(sol);
    radinterp_solution_destroy(ref);
    rb_free(&soup);
    rb_free(&clean);
}

/* ---- progress and cancel ----------------------------------------------------- */
typedef struct counting { long live, calls; } counting;
static void *count_alloc(size_t n, void *user) { ((counting *)user)->live++; return malloc(n); }
static void count_free(void *p, void *user) { if (p) ((counting *)user)->live--; free(p); }

typedef struct progress_state { long calls, cancel_at, before_samples; uint64_t last_done; int backwards; } progress_state;
static int progress_cb(void *user, uint64_t done, uint64_t total)
{
    progress_state *p = (progress_state *)user;
    p->backwards |= done > total;
    p->before_samples += done == 0 && total == 1;   /* the mesh build's calls before its samples */
    p->last_done = done;
    return ++p->calls == p->cancel_at;
}

/* The soup room's desc with a counting allocator and progress_cb. */
static radinterp_desc counted_soup(rb_scene *s, counting *cnt, progress_state *ps)
{
    radinterp_desc d;
    soup_room(s, 1);
    memset(cnt, 0, sizeof *cnt);
    memset(ps, 0, sizeof *ps);
    d = rb_desc(s);
    d.allocator.alloc = count_alloc;
    d.allocator.free = count_free;
    d.allocator.user = cnt;
    d.progress = progress_cb;
    d.progress_user = ps;
    return d;
}

/* The soup room's mesh desc: a coarse tree, d's counting allocator, and
   progress(user). */
static radinterp_mesh_desc counted_mesh_desc(const radinterp_desc *d, int (*progress)(void *, uint64_t, uint64_t),
                                             void *user)
{
    radinterp_mesh_desc md;
    memset(&md, 0, sizeof md);
    md.min_leaf_area = 0.25f;
    md.allocator = d->allocator;
    md.progress = progress;
    md.progress_user = user;
    return md;
}

/* Cancels solves at `parts` calls spread over the first `calls` ones (every
   one when there are fewer): each returns CANCELLED and no solution. */
static void cancel_solve_sweep(const radinterp_desc *d, progress_state *ps, long calls, long parts)
{
    long k, step = (calls + parts - 1) / parts;
    for (k = 1; k <= calls; k += step) {
        radinterp_solution *c = NULL;
        memset(ps, 0, sizeof *ps);
        ps->cancel_at = k;
        CHECK_EQ_INT(radinterp_solve(d, &c), RADINTERP_ERROR_CANCELLED);
        CHECK(c == NULL);
    }
}

/* Cancels mesh builds at `parts` calls spread over the first `calls` ones
   (every one when there are fewer): each returns CANCELLED and no mesh. */
static void cancel_mesh_sweep(const radinterp_solution *sol, const radinterp_mesh_desc *md, progress_state *ps,
                              long calls, long parts)
{
    long k, step = (calls + parts - 1) / parts;
    for (k = 1; k <= calls; k += step) {
        radinterp_mesh *c = NULL;
        memset(ps, 0, sizeof *ps);
        ps->cancel_at = k;
        CHECK_EQ_INT(radinterp_build_mesh(sol, md, &c), RADINTERP_ERROR_CANCELLED);
        CHECK(c == NULL);
    }
}

/* Cancel from progress calls spread over the run (every one up to 8, else
   8 evenly spaced): the solve and the mesh build return CANCELLED and free
   everything they allocated. A receiver's discontinuity search (a slab lit
   by a storey's lamps takes seconds at building scale) also reports between
   its sources once the interval has passed: with a clock that moves a
   second at every reading it reports at every lit source, and a cancel from
   16 of the calls before the samples frees everything too. */
static void test_cancel_everywhere(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_mesh_desc md;
    radinterp_solution *sol = NULL;
    radinterp_mesh *mesh = NULL;
    counting cnt;
    progress_state ps;
    long n;
    d = counted_soup(&s, &cnt, &ps);
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) { rb_free(&s); return; }
    n = ps.calls;
    CHECK(n >= 3);
    CHECK(!ps.backwards);
    cancel_solve_sweep(&d, &ps, n, 8);
    md = counted_mesh_desc(&d, progress_cb, &ps);
    memset(&ps, 0, sizeof ps);
    if (CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &mesh), RADINTERP_OK)) {
        long m = ps.calls, stopped = ps.before_samples, running;
        CHECK(m >= 3);
        CHECK(!ps.backwards);
        radinterp_mesh_destroy(mesh);
        mesh = NULL;
        cancel_mesh_sweep(sol, &md, &ps, m, 8);
        clock_step = 1.0;
        memset(&ps, 0, sizeof ps);
        CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &mesh), RADINTERP_OK);
        radinterp_mesh_destroy(mesh);
        running = ps.before_samples;
        /* stopped: one call a patch while discontinuities are found, one
           while they are triangulated; running: one more at every lit
           source of a receiver */
        CHECK_MSG(running > stopped + (long)s.np, "%ld calls before the samples with a running clock, %ld stopped", running,
                  stopped);
        cancel_mesh_sweep(sol, &md, &ps, running, 16);
        clock_step = 0.0;
        test_note("cancelled from %ld of %ld solve progress calls and %ld of %ld mesh ones; %ld calls before the samples with "
                  "a clock that runs (%ld stopped), cancelled from 16", n < 8 ? n : 8, n,
                  m < 8 ? m : 8, m, running, stopped);
    }
    radinterp_solution_destroy(sol);
    CHECK_EQ_INT(cnt.live, 0);
    rb_free(&s);
}

/* ---- progress paced by work ------------------------------------------------ */
/* The jobs of the solve's loops that the pacer sizes, with a progress call
   after each batch: link form factors, cluster links. */
static int paced_solve_job(radinterp_job_fn job)
{
    return job == radinterp__ff_job || job == radinterp__clink_job;
}
typedef struct cost_model { double job_cost; int paced_only; } cost_model;

/* A parallel_for that runs the jobs in order on the calling thread and
   charges each job_cost seconds of the simulated clock: with paced_only, only
   the jobs of the loops the pacer sizes (link form factors, cluster links,
   leaf lists, mesh samples), so that a gap measures those loops alone. */
static void costly_for(void *user, radinterp_job_fn job, void *ctx, uint32_t count)
{
    const cost_model *c = (const cost_model *)user;
    uint32_t i;
    int paced = paced_solve_job(job) || job == radinterp__leaf_lists_job || job == radinterp__point_job ||
                job == radinterp__error_job;
    for (i = 0; i < count; i++) job(ctx, i);
    if (paced || !c->paced_only) work_seconds += c->job_cost * count;
}

typedef struct pace_state { double last, widest; long calls; } pace_state;
static int pace_cb(void *user, uint64_t done, uint64_t total)
{
    pace_state *p = (pace_state *)user;
    (void)done; (void)total;
    if (work_seconds - p->last > p->widest) p->widest = work_seconds - p->last;
    p->last = work_seconds;
    p->calls++;
    return 0;
}

/* Radiosities then mesh coefficients of sol and mesh, into out (n floats). */
static float *results_of(const radinterp_solution *sol, const radinterp_mesh *mesh, size_t *n)
{
    radinterp_info info;
    radinterp_mesh_info mi;
    radinterp_mesh_data data;
    float *out;
    uint32_t i;
    radinterp_solution_info(sol, &info);
    radinterp_mesh_get_info(mesh, &mi);
    radinterp_mesh_get_data(mesh, &data);
    *n = 3 * (size_t)info.patch_count + 18 * (size_t)mi.triangle_count;
    out = (float *)calloc(*n ? *n : 1, sizeof(float));
    for (i = 0; i < info.patch_count; i++) radinterp_patch_radiosity(sol, i, out + 3 * i);
    memcpy(out + 3 * (size_t)info.patch_count, data.coefficients, sizeof(float) * 18 * mi.triangle_count);
    return out;
}

/* One solve and mesh build with jobs of the given cost; the longest gap
   between progress calls, in seconds of simulated work, and the results. */
static float *paced_run(const rb_scene *s, const cost_model *c, double *solve_gap, double *mesh_gap, long *calls, size_t *n)
{
    radinterp_desc d = rb_desc(s);
    radinterp_mesh_desc md;
    radinterp_solution *sol = NULL;
    radinterp_mesh *mesh = NULL;
    pace_state ps;
    float *out = NULL;
    memset(&ps, 0, sizeof ps);
    work_seconds = 0.0;
    d.parallel_for = costly_for;
    d.parallel_user = (void *)c;
    d.progress = pace_cb;
    d.progress_user = &ps;
    memset(&md, 0, sizeof md);
    md.min_leaf_area = 0.25f;
    md.parallel_for = costly_for;
    md.parallel_user = (void *)c;
    md.progress = pace_cb;
    md.progress_user = &ps;
    *n = 0;
    if (CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) {
        *solve_gap = ps.widest;
        *calls = ps.calls;
        ps.widest = 0.0;
        if (CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &mesh), RADINTERP_OK)) out = results_of(sol, mesh, n);
        *mesh_gap = ps.widest;
        *calls += ps.calls;
    }
    radinterp_mesh_destroy(mesh);
    radinterp_solution_destroy(sol);
    return out;
}

/* Progress comes after a bounded amount of work, however costly the jobs:
   with jobs of 10 ms (a penumbra's sample points cost that much at building
   scale) no gap in the paced loops exceeds the default interval of 0.25 s
   (the pacer doubles a batch only while it takes under half the interval, so
   with jobs of even cost a batch never takes longer); with jobs of 1 s a gap
   is one job. The fixed batches of v0.8.5 (256 link jobs, leaf lists by
   the memory they fill, 64 sample jobs) gave gaps of 3.29 s (solve) and
   0.64 s (mesh) at 10 ms a job. The batches never change a result: the
   radiosities and the mesh coefficients are bit-identical to a run whose
   clock never moves (batches at their largest). */
static void test_progress_paced_by_work(void)
{
    static const double costs[] = {0.01, 1.0};
    rb_scene s;
    cost_model free_jobs = {0.0, 0}, c;
    double sg, mg;
    long calls, free_calls;
    size_t n0, n;
    float *ref, *out;
    uint32_t k;
    soup_room(&s, 0);
    {   /* the interval is a parameter like the others: negative or NaN is refused */
        radinterp_desc d = rb_desc(&s);
        radinterp_mesh_desc md;
        radinterp_solution *sol = NULL;
        radinterp_mesh *mesh = NULL;
        d.progress_interval = -1.0f;
        CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
        d.progress_interval = NAN;
        CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
        d.progress_interval = 0.0f;
        if (CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) {
            memset(&md, 0, sizeof md);
            md.progress_interval = -1.0f;
            CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &mesh), RADINTERP_ERROR_INVALID_ARGUMENT);
            CHECK(mesh == NULL);
        }
        radinterp_solution_destroy(sol);
    }
    ref = paced_run(&s, &free_jobs, &sg, &mg, &free_calls, &n0);
    for (k = 0; k < sizeof costs / sizeof costs[0] && ref; k++) {
        c.job_cost = costs[k];
        c.paced_only = 1;
        out = paced_run(&s, &c, &sg, &mg, &calls, &n);
        if (!out) break;
        CHECK_MSG(sg <= (costs[k] > 0.25 ? costs[k] : 0.25) + 1e-9, "jobs of %g s: solve gap %.3f s", costs[k], sg);
        CHECK_MSG(mg <= (costs[k] > 0.25 ? costs[k] : 0.25) + 1e-9, "jobs of %g s: mesh gap %.3f s", costs[k], mg);
        CHECK(calls > free_calls);
        CHECK(n == n0 && !memcmp(out, ref, n * sizeof(float)));
        test_note("jobs of %g s: longest gap %.3f s (solve), %.3f s (mesh); %ld progress calls (%ld with free jobs)",
                  costs[k], sg, mg, calls, free_calls);
        free(out);
    }
    free(ref);
    rb_free(&s);
}

/* ---- progress inside the solve's serial passes ------------------------------- */
/* A parallel_for that counts the batches of the solve's paced loops (a
   progress call after each) in *(long *)user. */
static void batch_counting_for(void *user, radinterp_job_fn job, void *ctx, uint32_t count)
{
    uint32_t i;
    if (paced_solve_job(job)) ++*(long *)user;
    for (i = 0; i < count; i++) job(ctx, i);
}

/* Between the paced batches the solve has serial passes that take seconds
   at building scale: on building_16k (one thread) a wave of 700k cluster
   links split into shaft queries took 1.8 s, refinement's pass over 1.4M
   cluster links 0.9 s, installing the new links 1.7 s, so v0.8.6 left gaps
   of up to 1.9 s between progress calls. These passes now call progress
   too, once the interval has passed. With a stopped clock nothing is due:
   the calls are exactly one per paced batch and one per iteration (so the
   count below is what the passes add). With a clock that moves 1 s at every
   reading every check is due: each iteration's steps report, and so do the
   passes; refinement's pass over a finished solve's links and cluster links
   reports at least once every RADINTERP__TICK_STEPS of them (more often as
   the readings' stride narrows, test_progress_step_stride). A cancel from
   16 of these calls returns CANCELLED and frees everything. */
static void test_progress_in_serial_passes(void)
{
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol = NULL;
    radinterp_info info;
    counting cnt;
    progress_state ps;
    long batches = 0, stopped, calls, passes;
    d = counted_soup(&s, &cnt, &ps);
    d.parallel_for = batch_counting_for;
    d.parallel_user = &batches;
    d.eps_relative = 0.5f;   /* a coarse solve (3k links, not 57k) keeps the test at about 1 s under ASan */
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) goto done;
    radinterp_solution_info(sol, &info);
    stopped = ps.calls;
    CHECK_EQ_INT(stopped, batches + (long)info.iterations);
    radinterp_solution_destroy(sol);
    sol = NULL;
    clock_step = 1.0;
    batches = 0;
    memset(&ps, 0, sizeof ps);
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) goto done;
    radinterp_solution_info(sol, &info);
    calls = ps.calls;
    passes = calls - batches - (long)info.iterations;
    /* two steps of every iteration report; the last refinement pass, which
       split nothing, went over the final links and cluster links */
    CHECK(sol->converged);
    CHECK_MSG(passes >= 2 * (long)info.iterations + (long)((sol->link_count + RADINTERP__TICK_STEPS - 1) / RADINTERP__TICK_STEPS) +
                            (long)((sol->clink_count + RADINTERP__TICK_STEPS - 1) / RADINTERP__TICK_STEPS),
              "%ld calls from the serial passes in %u iterations, %u links, %u cluster links", passes, info.iterations,
              sol->link_count, sol->clink_count);
    cancel_solve_sweep(&d, &ps, calls, 16);
    test_note("%ld progress calls with a stopped clock (batches and iterations), %ld with a running one of which %ld "
              "from the serial passes; %u links, %u cluster links, %u iterations, converged %d",
              stopped, calls, passes, sol->link_count, sol->clink_count, info.iterations, sol->converged);
done:
    clock_step = 0.0;
    radinterp_solution_destroy(sol);
    CHECK_EQ_INT(cnt.live, 0);
    rb_free(&s);
}

/* A loop of short steps reads the process's CPU clock, a system call, every
   64 steps at first (radinterp__solve_step): 600k readings and 3-5% of
   building_1k's and building_4k's solves at every 64 steps. The stride
   doubles while readings come close together, up to 4096 steps, and halves
   when they come far apart: a loop of 100k steps with a stopped clock
   reads it fewer than 100k / 64 / 8 times (at every 64 steps: 1563); with
   a clock that moves 1 s at every reading the stride falls back to one
   step and progress is called at (almost) every step; a new loop starts
   again at 64. */
static void test_progress_step_stride(void)
{
    static radinterp_solution sol;   /* progress reports its iteration count */
    radinterp_desc d;
    radinterp__run run;
    progress_state ps;
    size_t i;
    long stopped, running, restarted;
    memset(&d, 0, sizeof d);
    memset(&ps, 0, sizeof ps);
    d.progress = progress_cb;
    d.progress_user = &ps;
    run.desc = &d;
    run.iteration = 0;
    run.reported = run.read = RADINTERP_CPU_SECONDS();
    run.stride = run.countdown = RADINTERP__TICK_STEPS;
    clock_readings = 0;
    for (i = 0; i < 100000; i++) CHECK(!radinterp__solve_step(&sol, &run, i));
    stopped = clock_readings;
    CHECK_MSG(stopped < 100000 / 64 / 8, "%ld readings in 100k steps with a stopped clock", stopped);
    CHECK_EQ_INT(ps.calls, 0);
    clock_step = 1.0;
    for (i = 0; i < 1000; i++) CHECK(!radinterp__solve_step(&sol, &run, i));
    running = ps.calls;
    CHECK_MSG(running >= 1000 - 2 * RADINTERP__TICK_STEPS, "%ld progress calls in 1000 steps with a running clock", running);
    clock_step = 0.0;
    clock_readings = 0;
    for (i = 0; i < 64 * RADINTERP__TICK_STEPS; i++) CHECK(!radinterp__solve_step(&sol, &run, i));
    restarted = clock_readings;
    CHECK_MSG(restarted >= 6 && restarted <= 8, "%ld readings in a new loop's first %d steps", restarted, 64 * RADINTERP__TICK_STEPS);
    test_note("%ld clock readings in 100k steps with a stopped clock; %ld progress calls in 1000 steps with a running "
              "one; %ld readings in the first %d steps of the next loop", stopped, running, restarted,
              64 * RADINTERP__TICK_STEPS);
}

/* ---- progress inside the mesh build's serial steps ---------------------------- */
/* Progress calls of the mesh build, with the builder they come from: the
   calls that came right before an event test (radinterp__event_seen) are
   the first ones at a multiple of RADINTERP__WEDGE_TICK tests. */
typedef struct mesh_ticks { const radinterp__builder *b; long calls, event_calls; uint64_t last_event; } mesh_ticks;
static int mesh_tick_cb(void *user, uint64_t done, uint64_t total)
{
    mesh_ticks *t = (mesh_ticks *)user;
    uint64_t e = t->b->event_tests;
    (void)done; (void)total;
    if (e && e % RADINTERP__WEDGE_TICK == 0 && e != t->last_event) t->event_calls++;
    t->last_event = e;
    t->calls++;
    return 0;
}

/* The mesh build's steps before its samples are serial and took seconds
   at building_4k with no progress call inside: grouping one receiver's
   discontinuities into DSets 8.2 s, a source's event tests 9.3 s for 22
   blockers, the quadtrees' copy and restriction and the first pass's
   activation, segments and outlines 6.6 s. Each now calls progress once the
   interval has passed. The steps run here one by one on the soup room, as
   radinterp_build_mesh runs them, with a clock that moves 1 s at every
   reading, so that every check is due and the calls can be counted exactly
   or from below:
   - grouping a receiver's n discontinuities: one call every
     RADINTERP__TICK_STEPS of them and one before the final sort;
   - the search: a call before every RADINTERP__WEDGE_TICK-th event test;
   - the quadtrees: at least one every RADINTERP__TICK_STEPS nodes in the
     restriction's last sweep over all of them;
   - the first pass before its samples: one a patch in activation,
     segments, outlines and triangulation.
   Without these calls the counts are 0, 0 (or a few by chance), 0 and one
   a patch. A cancel from 24 of the build's calls before its samples returns
   CANCELLED and frees everything; the whole build's build_bytes counts at
   least the mesh it returns. */
static void test_progress_in_mesh_steps(void)
{
    long grouping = 0, expected = 0, trees, pass, lit = 0, held = 0;
    uint32_t R;
    radinterp__builder b;
    radinterp__buf pairs, stack;
    mesh_ticks t;
    counting cnt;
    progress_state ps;
    rb_scene s;
    radinterp_desc d;
    radinterp_mesh_desc md;
    radinterp_solution *sol = NULL;
    radinterp_mesh *mesh = NULL;
    d = counted_soup(&s, &cnt, &ps);
    d.eps_relative = 0.5f;   /* a coarse solve keeps the test short under ASan; the mesh's steps are the same */
    if (!CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_OK)) goto done;
    md = counted_mesh_desc(&d, mesh_tick_cb, &t);
    memset(&t, 0, sizeof t);
    t.b = &b;
    clock_step = 1.0;
    held = cnt.live;
    radinterp__buf_init(&pairs, sizeof(uint64_t));
    radinterp__buf_init(&stack, sizeof(uint32_t));
    if (!CHECK_EQ_INT(radinterp__builder_init(&b, sol, &md), RADINTERP_OK)) goto free_builder;
    for (R = 0; R < sol->patch_count; R++) {
        uint32_t n;
        b.disc_first[R] = (uint32_t)b.discs.count;
        if (sol->patches[R].count && !CHECK_EQ_INT(radinterp__receiver_discs(&b, R, &pairs, &stack), 0)) goto free_builder;
        n = b.disc_count[R] = (uint32_t)b.discs.count - b.disc_first[R];
        t.calls = 0;
        if (!CHECK_EQ_INT(radinterp__group_dsets(&b, R), 0)) goto free_builder;
        grouping += t.calls;
        expected += n / RADINTERP__TICK_STEPS + (n > 0);
        if (!CHECK_EQ_INT(radinterp__keep_candidates(&b, R), 0)) goto free_builder;
        lit += sol->patches[R].count != 0;
    }
    CHECK_EQ_INT(grouping, expected);
    CHECK(expected > lit);   /* receivers of more than RADINTERP__TICK_STEPS discontinuities were grouped */
    CHECK(b.event_tests >= 8 * RADINTERP__WEDGE_TICK);
    CHECK_EQ_INT(t.event_calls, (long)(b.event_tests / RADINTERP__WEDGE_TICK));
    t.calls = 0;
    if (!CHECK_EQ_INT(radinterp__build_trees(&b), RADINTERP_OK)) goto free_builder;
    trees = t.calls;
    CHECK_MSG(trees >= (long)((b.nodes.count + RADINTERP__TICK_STEPS - 1) / RADINTERP__TICK_STEPS),
              "%ld calls while %zu nodes were copied and restricted", trees, b.nodes.count);
    t.calls = 0;
    if (!CHECK_EQ_INT(radinterp__mesh_pass(&b), RADINTERP_OK)) goto free_builder;
    pass = t.calls;
    CHECK_MSG(pass >= 3 * (long)sol->patch_count + lit, "%ld calls in the first pass, %u patches", pass, sol->patch_count);
    test_note("%ld calls grouping %zu discontinuities, %ld before %llu event tests, %ld for %zu quadtree nodes, %ld in "
              "the first pass (%u patches)", grouping, (size_t)b.found.count, t.event_calls,
              (unsigned long long)b.event_tests, trees, b.nodes.count, pass, sol->patch_count);
free_builder:
    radinterp__buf_free(&b.a, &pairs);
    radinterp__buf_free(&b.a, &stack);
    radinterp__builder_free(&b);
    CHECK_EQ_INT(cnt.live, held);   /* the solution's */
    md.progress = progress_cb;
    md.progress_user = &ps;
    memset(&ps, 0, sizeof ps);
    if (CHECK_EQ_INT(radinterp_build_mesh(sol, &md, &mesh), RADINTERP_OK)) {
        radinterp_mesh_info mi;
        radinterp_mesh_get_info(mesh, &mi);
        CHECK(mi.bytes > 0 && mi.build_bytes >= mi.bytes);   /* the build held the mesh at its end */
        cancel_mesh_sweep(sol, &md, &ps, ps.before_samples, 24);
    }
    radinterp_mesh_destroy(mesh);
done:
    clock_step = 0.0;
    radinterp_solution_destroy(sol);
    CHECK_EQ_INT(cnt.live, 0);
    rb_free(&s);
}

/* ---- coordinate range ----------------------------------------------------------- */
/* Radiosity does not depend on the scene's scale: the room scaled by 1e-15
   and by 1e15 (inside the accepted range) gives the radiosities of the
   unscaled room, within the spread of another seed plus 1%; scaled out of
   the range (1e20, 1e-20) it is INVALID_ARGUMENT, as are coordinates a
   float cannot square. */
static void test_coordinate_range(void)
{
    static const double scales[] = {1e-15, 1e15};
    rb_scene s;
    radinterp_desc d;
    radinterp_solution *sol;
    double *base, *other;
    float *orig;
    uint32_t i, k;
    soup_room(&s, 0);
    orig = (float *)malloc(sizeof(float) * 3 * s.nv);
    memcpy(orig, s.pos, sizeof(float) * 3 * s.nv);
    d = rb_desc(&s);
    base = solve_patches(&d, NULL);
    d.seed = 7;
    other = solve_patches(&d, NULL);
    d.seed = 0;
    for (k = 0; k < 2 && base && other; k++) {
        double *b, worst = 0.0;
        for (i = 0; i < 3 * s.nv; i++) s.pos[i] = (float)(orig[i] * scales[k]);
        b = solve_patches(&d, NULL);
        for (i = 0; b && i < s.np; i++) {
            double diff = fabs(b[i] - base[i]), spread = fabs(other[i] - base[i]);
            CHECK_MSG(diff <= 0.01 * base[i] + 2.0 * spread, "scale %g, patch %u: %.5f, unscaled %.5f (another seed %.5f)",
                      scales[k], i, b[i], base[i], other[i]);
            if (diff / base[i] > worst) worst = diff / base[i];
        }
        test_note("room scaled by %g: largest patch difference %.2f%%", scales[k], 100.0 * worst);
        free(b);
    }
    for (k = 0; k < 2; k++) {
        double sc = k ? 1e-20 : 1e20;
        for (i = 0; i < 3 * s.nv; i++) s.pos[i] = (float)(orig[i] * sc);
        CHECK_EQ_INT(radinterp_solve(&d, &sol), RADINTERP_ERROR_INVALID_ARGUMENT);
    }
    free(base);
    free(other);
    free(orig);
    rb_free(&s);
}

int main(int argc, char **argv)
{
    TEST_INIT(argc, argv);
    RUN(test_wall_between_rooms);
    RUN(test_partly_hidden_source_spread);
    RUN(test_source_floor);
    RUN(test_planes_search);
    RUN(test_refine_decisions);
    RUN(test_install_links_in_place);
    RUN(test_triangle_soup);
    RUN(test_cancel_everywhere);
    RUN(test_progress_paced_by_work);
    RUN(test_progress_in_serial_passes);
    RUN(test_progress_step_stride);
    RUN(test_progress_in_mesh_steps);
    RUN(test_coordinate_range);
    RUN(test_clustered_equals_unclustered);
    return test_finish();
}
