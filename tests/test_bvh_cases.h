/* The BVH test cases, written once for the three headers that carry a copy of
   the BVH. Included by tests/test_bvh.h once per header, with
       BVH(x)         the header's private BVH name of x (irrvol__##x)
       BVH_NO_HIT     its miss marker
       BVH_LEAF       its leaf reference flag
       BVH_ALLOCATOR  its allocator type
       T(x)           this instance's name of test helper x
   and the scenes of tests/test_bvh.h (bvh_scene, make_ray). */

static int T(build)(BVH(bvh) *bvh, const bvh_scene *s)
{
    BVH(mesh_view) m;
    BVH_ALLOCATOR a;
    memset(&a, 0, sizeof a);
    m.positions = s->positions;
    m.stride = 0;
    m.indices = s->indices;
    m.tri_count = s->tri_count;
    return BVH(bvh_build)(bvh, &m, &a);
}

static void T(release)(BVH(bvh) *bvh)
{
    BVH_ALLOCATOR a;
    memset(&a, 0, sizeof a);
    BVH(bvh_free)(bvh, &a);
}

/* Levels of the wide tree (0: a root leaf or no tree). */
static uint32_t T(depth)(const BVH(bvh) *bvh, uint32_t ref)
{
    uint32_t i, deepest = 0;
    if (bvh->tri_count == 0 || (ref & BVH_LEAF)) return 0;
    for (i = 0; i < sizeof bvh->nodes[ref].child / sizeof bvh->nodes[ref].child[0]; i++) {
        uint32_t d;
        if (bvh->nodes[ref].box[0][i] > bvh->nodes[ref].box[1][i]) continue;   /* an unused slot */
        d = T(depth)(bvh, bvh->nodes[ref].child[i]);
        if (d > deepest) deepest = d;
    }
    return deepest + 1;
}

/* The closest hit without the tree: every block through the scalar kernel. */
static int T(brute_force)(const BVH(bvh) *bvh, const float o[3], const float d[3], BVH(hit) *h)
{
    BVH(ray) r;
    uint32_t b;
    BVH(ray_setup)(&r, o, d);
    h->t = FLT_MAX;
    h->u = h->v = 0.0f;
    h->tri = BVH_NO_HIT;
    for (b = 0; b < bvh->block_count; b++) BVH(leaf_hit_scalar)(&r, &bvh->blocks[b], 0.0f, h);
    return h->tri != BVH_NO_HIT;
}

/* One ray through one path: its closest hit, and any-hit queries that
   must agree with it: nothing before half its distance, something before
   1.5 times it (nothing at all on a miss). */
static void T(trace)(BVH(bvh) *bvh, int simd, const float o[3], const float d[3], BVH(hit) *h, int any[2])
{
    bvh->simd = simd;
    if (BVH(bvh_intersect)(bvh, o, d, 0.0f, FLT_MAX, h)) {
        any[0] = BVH(bvh_occluded)(bvh, o, d, 0.0f, 0.5f * h->t);
        any[1] = BVH(bvh_occluded)(bvh, o, d, 0.0f, 1.5f * h->t);
    } else {
        any[0] = 0;
        any[1] = BVH(bvh_occluded)(bvh, o, d, 0.0f, FLT_MAX);
    }
}

/* `rays` rays through the SIMD and the scalar path: identical hits (t, u,
   v, triangle, bit for bit) and any-hit answers; the first `checked` also
   against the brute force: the same distance, bit for bit (another triangle
   at that distance is a tie: rays through a vertex or a shared edge). */
static void T(compare)(const char *header, const bvh_scene *s, uint32_t rays, uint32_t checked)
{
    BVH(bvh) bvh;
    uint32_t i, hits = 0, differ = 0, any_wrong = 0, noise = 0, brute_wrong = 0, ties = 0;
    if (!CHECK(T(build)(&bvh, s) == 0)) return;
    CHECK_EQ_INT(bvh.tri_count + bvh.degenerate_count, s->tri_count);
    CHECK_EQ_INT(bvh.degenerate_count, s->degenerate_count);
    for (i = 0; i < rays; i++) {
        float o[3], d[3];
        BVH(hit) h[2], b;
        int any[2][2], hit;
        make_ray(s, i, o, d);
        T(trace)(&bvh, 1, o, d, &h[0], any[0]);
        T(trace)(&bvh, 0, o, d, &h[1], any[1]);
        hit = h[1].tri != BVH_NO_HIT;
        hits += (uint32_t)hit;
        if (memcmp(&h[0], &h[1], sizeof h[0]) != 0 || memcmp(any[0], any[1], sizeof any[0]) != 0) differ++;
        /* a hit within rounding of the origin (a ray leaving a triangle
           hits it again near t = 0) has a distance of pure rounding error,
           which boxes need not agree with: not judged closer than 100 ulp */
        if (hit && h[1].t * (fabsf(d[0]) + fabsf(d[1]) + fabsf(d[2])) <
                       1e-5f * (fabsf(o[0]) + fabsf(o[1]) + fabsf(o[2])))
            noise++;
        else if (any[1][0] != 0 || any[1][1] != hit) any_wrong++;
        if (i >= checked) continue;
        T(brute_force)(&bvh, o, d, &b);
        if (memcmp(&b.t, &h[1].t, sizeof b.t) != 0) brute_wrong++;
        else if (b.tri != h[1].tri) ties++;
    }
    test_note("%s BVH, %s (%u triangles, %u degenerate, %u nodes, %u levels, %u blocks): %u rays, %u hit, "
              "SIMD/scalar differences %u, any-hit disagreements %u (%u self hits at t ~ 0 not judged); "
              "%u checked by brute force: %u different, %u ties",
              header, s->name, s->tri_count, bvh.degenerate_count, bvh.node_count, T(depth)(&bvh, bvh.root),
              bvh.block_count, rays, hits,
              differ, any_wrong, noise, checked, brute_wrong, ties);
    CHECK_EQ_INT(differ, 0);
    CHECK_EQ_INT(any_wrong, 0);
    CHECK_EQ_INT(brute_wrong, 0);
    CHECK(s->expect_hits ? hits > 0 : hits == 0);
    T(release)(&bvh);
}

/* Out of memory at every allocation of the build: -1, nothing leaked
   (ASan), and the BVH left empty. */
static void T(allocation_failures)(const bvh_scene *s)
{
    int fail_at;
    for (fail_at = 0; fail_at < 8; fail_at++) {
        BVH(bvh) bvh;
        BVH(mesh_view) m;
        BVH_ALLOCATOR a;
        failing f;
        int r;
        f.count = 0;
        f.fail_at = fail_at;
        f.live = 0;
        memset(&a, 0, sizeof a);
        a.alloc = failing_alloc;
        a.free = failing_free;
        a.user = &f;
        m.positions = s->positions;
        m.stride = 0;
        m.indices = s->indices;
        m.tri_count = s->tri_count;
        r = BVH(bvh_build)(&bvh, &m, &a);
        if (r == 0) {
            CHECK(f.count <= fail_at);   /* it succeeded before reaching the failing call */
            BVH(bvh_free)(&bvh, &a);
        } else {
            CHECK_EQ_INT(r, -1);
            CHECK(bvh.nodes == NULL && bvh.blocks == NULL && bvh.tri_count == 0);
        }
        CHECK_EQ_INT(f.live, 0);
    }
}
