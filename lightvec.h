/* lightvec.h - v0.4.10 - cached 5D indirect light vectors - public domain or MIT, see end of file

   LIGHTVEC.H: cached light vectors over position and direction for interactive glossy global illumination.

   A light vector (Zaninetti & Peroche 1998) replaces the light arriving at a
   surface point by a virtual light: a direction D (eq. 2) and an RGB
   magnitude M (eq. 3) chosen so that the radiance the point reflects toward
   the viewer direction w_r is L = M * f_r(D -> w_r) * cos(n, D). Computing
   one takes a hemisphere of rays (lightvec_gather, eq. 5), so light vectors
   are cached like Ward's irradiance records and interpolated between
   neighbours when the validity criteria allow (section 4.2). Crespin &
   Peroche extend the cache to five dimensions: a record also remembers the
   viewer direction sigma it was computed for; directions are organised by a
   recursive icosahedron (20 faces, a face splits in four when it holds more
   than a threshold) and each face keeps the positions of its records in 3D
   kd-trees, so a lookup descends only into the faces near the viewer
   direction. The BRDF is Lambert plus a normalized Phong lobe; a record
   holds two light vectors, a diffuse one that serves every viewer and a
   glossy one carried to nearby viewers by its view gradient (GLOSSY
   SURFACES). A cache of direct light vectors (DLV, the paper's future work)
   reuses the same machinery for the light of area sources.

   DO THIS

       #define LIGHTVEC_IMPLEMENTATION
       #include "lightvec.h"

   in exactly one C or C++ file; include "lightvec.h" without the define
   everywhere else.

   EXAMPLE (the loop of figure 2 of the paper, one pixel)

       lightvec_scene *scene;               // triangles + materials, built once
       lightvec_cache *cache;
       lightvec_scene_desc sd = {0};  sd.positions = xyz; sd.vertex_count = nv;
       sd.indices = idx; sd.triangle_count = nt; sd.material_ids = mat;
       sd.materials = mats; sd.material_count = nm;
       if (lightvec_scene_create(&sd, &scene) != LIGHTVEC_OK) ...
       lightvec_cache_desc cd = {0};        // zero = the documented defaults
       if (lightvec_cache_create(&cd, &cache) != LIGHTVEC_OK) ...

       lightvec_lookup_result r;            // p, n (facing the eye), to_eye
       lightvec_lookup(cache, p, n, to_eye, &r);
       if (!r.hit) {                        // too few valid vectors: compute one
           lightvec_gather_desc gd = {0};
           lightvec_surface s = {0};        // p, n, to_eye and the material of the hit
           lightvec_record rec;
           if (lightvec_gather(scene, &gd, &s, pixel_index, &rec) == LIGHTVEC_OK) {
               lightvec_insert(cache, &rec, NULL);   // OUT_OF_MEMORY: the cache is unchanged
               r.vector = rec.vector;
           }
       }
       lightvec_radiance(&material, n, to_eye, &r.vector, rgb);   // indirect light

   CONFIGURATION MACROS

       LIGHTVEC_STATIC          make every function static (private to one file)
       LIGHTVEC_API             linkage of public functions (default: extern)
       LIGHTVEC_MALLOC, LIGHTVEC_FREE  replace malloc/free (define both or neither)
       LIGHTVEC_BVH_BINS        SAH bins of the built-in BVH (default 16)
       LIGHTVEC_BVH_SIMD        1 (default): SSE2 (x86-64) or NEON (AArch64) BVH kernels
                                when the compiler offers them; 0: the portable scalar
                                kernels only (the same hits, bit for bit)

   FUNCTION REFERENCE (what each checks; what the caller guarantees)

     Every function taking pointers checks them for NULL and returns
     LIGHTVEC_ERROR_INVALID_ARGUMENT (void functions: do nothing, outputs
     zeroed); on any error its outputs are zero/NULL and nothing it owns has
     changed. What cannot be checked is the caller's contract: an array holds
     as many elements as its count says, a callback behaves as documented,
     objects are not used after destroy, and the THREADS rules.

     scene and built-in renderer
       lightvec_scene_create(desc, &scene)    BVH over the triangles, emitter list.
           Checks: positions, indices, materials non-NULL; vertex_count,
           triangle_count, material_count > 0; triangle_count <=
           LIGHTVEC_MAX_TRIANGLES; stride 0 or a multiple of 4 >= 12; every
           vertex finite; every index < vertex_count; every material id <
           material_count; every material finite and non-negative, exponent
           <= 1e6, transmittance <= 1; sky finite and non-negative;
           environment NULL or 1..65536 texels a side, every texel finite and
           non-negative; allocator both callbacks or none. Zero-area triangles are
           skipped and counted. Contract: positions holds vertex_count vertices
           at `stride`, indices 3 * triangle_count, material_ids triangle_count
           (or NULL), materials material_count, environment 3 * width *
           height floats. The scene copies what it keeps (the map too);
           the caller's arrays may go once it returns.
       lightvec_scene_destroy(scene)          NULL: nothing.
       lightvec_scene_info(scene, &info)      counts and bounds.
       lightvec_scene_intersect(scene, org, dir, tmax, &hit)   closest hit (primary
           rays): 0 for NULL or non-finite org/dir, or tmax <= 0. dir need not be
           unit (t is in units of |dir|).
     light vectors
       lightvec_gather(scene, gdesc, surface, index, &record)   ILV: eq. 5, gradient,
           d_avg, and on a glossy surface the lobe's G, dG/dw_r, d_g.
           Checks: strata <= 256 x 512, bounces <= 64, light_samples <= 4096,
           glossy_samples <= 65536; min/max_distance finite, >= 0, min <= max;
           surface position finite, normal non-zero and finite (normalised),
           outgoing likewise unless VIEW_INDEPENDENT, material valid, no unknown
           flag, no VIEW_INDEPENDENT glossy surface; scene non-NULL unless
           incoming_radiance is given; every incoming radiance finite and >= 0
           and every distance > 0 (else INVALID_ARGUMENT). Contract: the normal
           faces the viewer (its side is the one gathered), the scene is the
           one the surface lies on. Same (desc.seed, index): same record.
       lightvec_gather_direct(scene, gdesc, surface, index, &record)   DLV from the
           emitters; the same checks (scene required).
       lightvec_brdf(material, normal, wi, wo, f)       Lambert + normalized Phong;
           f = 0 for NULL or zero vectors. Vectors need not be unit.
       lightvec_radiance(material, normal, wo, vector, rgb)   the vector's light
           toward wo: M rho_d / pi cos(n, D) + M_g f_s(D_g -> wo) cos(n, D_g);
           wo NULL: the diffuse term only. Result saturated at FLT_MAX: finite
           for finite input. rgb = 0 for NULL arguments.
       lightvec_direction_angle(exponent)     degrees of view change a glossy
           record of this Phong exponent tolerates (GLOSSY SURFACES); 180 for 0
           or NaN. To describe another lobe, give a record the exponent of the
           Phong lobe of the same width (GGX roughness a: about 2 / a^2 - 2).
     cache
       lightvec_cache_create(desc, &cache)    desc NULL = defaults. Checks: kind,
           interpolation known; radius_scale in [0, 1e6], change >= 0, angles in
           [0.1, 180] degrees (or 0), max_face_depth <= 12, max_neighbors <=
           256, front_tolerance >= 0, all finite; no unknown flag; allocator.
       lightvec_cache_destroy(cache)          NULL: nothing.
       lightvec_insert(cache, record, &id)    writer. Checks the record: flags
           known; position finite; normal, D non-zero finite (normalised); D_g
           zero or non-zero finite; sigma likewise unless VIEW_INDEPENDENT;
           magnitudes, irradiance, G >= 0 finite; gradients finite; 0 < distance
           <= 1e30; 0 <= glossy_distance <= 1e30; exponent in [0, 1e6];
           glossy_share, visibility in [0, 1]; `radius` is ignored (the cache
           sets it). OUT_OF_MEMORY when a chunk, a merge or a face split cannot
           get memory, or past 2^32 - 1 records: then the cache is exactly as
           before the call. Neighbour clamping may shrink the radii of records
           already stored (lightvec_cache_record shows them).
       lightvec_lookup(cache, p, n, wo, &result)    reader: weights 4.2, interpolation.
           Checks: p finite, n non-zero finite, wo NULL (a 3D query) or non-zero
           finite; all normalised. Contract: n faces the viewer (wo . n > 0);
           a 5D query sees 5D records only, a 3D one 3D records only. Every
           magnitude of the result is finite (saturated).
       lightvec_find(cache, p, n, wo, ids, weights, capacity, &count)   every valid
           record and its weight w (the diffuse one), capacity of them; count =
           all valid. Checks as lookup, and ids/weights non-NULL when capacity > 0.
       lightvec_priority(rc_priority, W)              render-cache priority (4.3)
       lightvec_cache_optimize(cache)                 writer: one kd-tree per face.
           OUT_OF_MEMORY when a face's tree cannot get memory (the faces rebuilt
           so far stay rebuilt, the others as they were: a valid cache either
           way); CANCELLED when progress asks. When the list of memory awaiting
           readers cannot grow, the writer waits for the readers instead and
           the call still succeeds (also in insert).
       lightvec_cache_record(cache, id, &record)      reader; id < record count;
           radius = the validity radius in effect.
       lightvec_cache_info(cache, &info)
       lightvec_cache_face(cache, i, &face)           icosahedron faces (inspection)
       lightvec_cache_locate(cache, direction, &i)    leaf face holding a direction
     serialization
       lightvec_save(cache, write, user)              IO when write fails.
       lightvec_load(desc, read, user, &cache)        desc: allocator, parallel_for,
           logging (the settings come from the data). Input is hostile: every
           size, setting and record checked as by create and insert, the CRC at
           the end; CORRUPT_DATA for anything off, VERSION for another format.
       lightvec_save_to_memory(cache, a, &data, &size)
       lightvec_load_from_memory(data, size, desc, &cache)   data NULL only with size 0; reads
                                                      the cache at the start of the buffer
                                                      (bytes after its CRC are left alone).
       lightvec_free_memory(a, data)                  a: the allocator save used.
       lightvec_result_string(result)

   THREADS

     A cache has one writer and any number of readers. lightvec_lookup,
     lightvec_find and lightvec_cache_record take a const cache and may run on
     any number of threads at once, also while ONE thread runs lightvec_insert
     or lightvec_cache_optimize: the caller serializes the writers (one
     inserting thread, or a mutex around insert). Readers never block: the
     kd-trees are immutable once published (but for the radii neighbour
     clamping shrinks, read and written atomically), new vectors go to a small
     per-face list whose length is published with release semantics, and a
     restructured face is published with one atomic pointer store. Memory a
     reader may still see is freed only after every reader that started
     before its replacement has finished (two reader counters, flipped by the
     writer; the writer waits for the old one to drain, which takes one
     lookup). lightvec_save, lightvec_cache_info and lightvec_cache_face must
     not overlap a writer. Atomics use the GCC/Clang __atomic builtins or the
     MSVC Interlocked functions; other compilers get plain accesses
     (single-threaded use only). A scene is read-only after creation: gathers
     may run on any threads.

   VALIDITY (section 4.2; B = a cached record, A = the query point)

     spatial     |AB| < R_B, R_B = radius_scale * d_avg_B (d_avg: harmonic mean hit
                 distance) clamped by the neighbours' radii (below)
                 |AB| |grad E_B| / E_B < I_B = max_irradiance_change   (luminance, grad from eq. 6)
                 cos(n_A, n_B) > S_curv = cos(max_normal_angle)
                 (A - B) . (n_A + n_B) / 2 >= -front_tolerance * R_B (Ward 1988: B is not
                 in front of A; 0 on smooth surfaces, negative across a step)
                 w_B = (1 - |AB|/R_B) / (1 + |AB| |grad E_B| / E_B) * (cos(n_A,n_B) - S_curv) / (1 - S_curv)
     directional cos(w, sigma) > S_dir = cos(max_direction_angle)
                 w_sigma = (cos(w, sigma) - S_dir) / (1 - S_dir)
     global      w = w_B * w_sigma weighs the diffuse vector; the glossy part has its
                 own w_g (GLOSSY SURFACES). The max_neighbors valid records of largest w
                 are interpolated (k-nearest cap); a hit needs min_valid of them (and as
                 many valid for their glossy part where they have one, and the DLV
                 visibility rule): D = normalize(sum w D_i), W = mean of the w, and M by
                 `interpolation`:
                 PLAIN (the paper)  M = sum w M_i / sum w
                 PROJECTED          M = (sum w M_i cos(n_i, D_i) / sum w) / cos(n_A, D)
                 GRADIENT (default) PROJECTED with each term times 1 + grad E_c . (A - B) / E_c

     Neighbour clamping (Krivanek et al. 2006): radii of
     records that can be interpolated together obey R_i <= R_j + |B_i - B_j|
     both ways, the triangle inequality the distance field itself obeys. A
     record whose rays missed a nearby occluder (too large a d_avg) is held
     back by neighbours that saw it and cannot reach over the occluder's
     shadow. Insertion clamps the new radius by the records within it, then
     the radii of the records whose sphere holds the new one; "together" means
     both view independent, or both 5D with sigmas within max_direction_angle.
     On the glossy Cornell floor below (128 x 128) it takes the moved frame's
     error from 5.1% to 4.4%. LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP turns it off.

     The k-nearest cap (max_neighbors, default 16): a lookup interpolates the
     valid records of largest weight (ties to the smaller id), selected once
     the search is done; valid_count still counts all. Where more than 16 are
     valid the ones left out weigh least (near the edge of their spheres or of
     their direction cones): on the glossy Cornell floor (128 x 128, the moved
     frame) the error is 4.38% with no cap, 4.37% with 16, 4.50% with 8; it
     bounds the interpolation's cost (one cache line per kept record without
     a valid glossy part, in its leaf's block; two more with one) in dense
     caches. It does not bound
     the search, which still tests every record whose sphere holds A: every
     valid record counts in valid_count, so no subtree can be skipped once
     the k best are known.

     Defaults and why they differ from the paper's bare criteria: the paper
     bounds |AB| by d_avg itself (radius_scale 1) and leaves I_B, S_curv,
     S_dir and the minimum count open. On the Cornell box (tests/ref_lightvec.c)
     radius 1 * d_avg gives 10-15% mean error on the walls (15% with the plain
     interpolation, 10% with the gradient one); radius 0.3 * d_avg (Ward's
     accuracy a = 0.3), at least 3 valid vectors and gradient-corrected
     interpolation give about 3% against a converged gather, at 98% hits for a
     512 x 512 image. radius_scale = 1, interpolation = PLAIN reproduce the
     paper.

     Lambertian surfaces: their light vector does not depend on the viewer.
     Passing outgoing = NULL (lookup) or the flag
     LIGHTVEC_RECORD_VIEW_INDEPENDENT (gather, insert) treats a point in 3D as
     the original light vectors do: such records skip the icosahedron and the
     directional criterion, and only lookups with outgoing = NULL find them.
     With a viewer direction every surface is handled in 5D, as in the paper.

   GLOSSY SURFACES

     One light vector per (position, viewer direction) cannot carry glossy
     light: eq. 3 divides by f_r(D -> w_r), tiny where the lobe misses D (M
     reached 2e14 on a purely glossy floor, and inf with a float denominator),
     and a vector made for sigma says nothing about how the lobe's light
     changes for another viewer. So a record splits the light (eq. 4 treats
     components apart; eq. 5 already gathers with the diffuse part rho_d):

     diffuse vector  D of eq. 2, M = E / cos(n, D) (eq. 3 with the Lambert term, which
                     cancels): exact for every viewer, interpolated with the weights above.
     glossy part     G(sigma) = integral of lobe(w -> sigma) L cos theta, the radiance the
                     normalized Phong lobe (exponent + 2) / (2 pi) cos^exponent alpha
                     reflects toward sigma per unit specular reflectance, and its view
                     gradient dG/dw_r (the derivative of the lobe under the same integral,
                     in the tangent plane of sigma). A lookup for viewer w carries each
                     valid record to w to first order, G_B + dG_B/dw . (w - sigma_B), and
                     builds the glossy light vector toward w: D_g = the mirror direction
                     of w, where the lobe peaks, and M_g = G / (lobe(D_g -> w) cos(n, D_g)),
                     eq. 3 for the lobe alone: it divides by the largest lobe value there
                     is, so M_g stays of the order of G. lightvec_radiance then gives
                     rho_d / pi E + rho_s G.

     The gather estimates G, its gradient and d_g (the lobe's harmonic mean
     distance) from the strata and from glossy_samples rays drawn from the
     lobe (a quarter of the strata by default; in antithetic pairs, which
     cancel the gradient's odd noise), combined by the balance heuristic of
     multiple importance sampling (Veach 1997): every ray weighs
     1 / (MN / 2 pi + K pdf_lobe(w)). Its records remember the lobe's exponent
     and the glossy share s = rho_s G / (rho_d E / pi + rho_s G) (luminance).

     Validity of the glossy part (derivation). The glossy radiance seen along
     w is the incident light blurred by the lobe around the mirror direction
     of w; cos^n alpha ~ exp(-n alpha^2 / 2) is a Gaussian of angular radius
     s_n = acos(exp(-1 / (2n))) (where it falls to e^-1/2; about 1/sqrt(n)).
     Turning the viewer by psi turns the mirror direction by psi. The first
     order expansion misses at most 1/2 max|G''| psi^2, and the worst light
     under a Gaussian blur, a step of contrast C, has max|G''| = C phi(1) /
     s_n^2 (phi the normal density, phi(1) = 0.242). Bounding the remainder
     by eps C gives psi <= s_n sqrt(2 eps / phi(1)); with eps = 0.1 that is
     0.909 s_n: 11.6 degrees for exponent 20, 5.2 for 100, 36 for 2
     (lightvec_direction_angle). The remainder counts in what the viewer sees
     in proportion to the glossy share, so a record's angle is that over
     sqrt(s) (a faint gloss on a diffuse floor tolerates more), never wider
     than max_direction_angle (the cone the faces are searched in). The angle
     psi is the view change |w - sigma| plus the parallax of the move from B
     to A seen along A's lobe, |(A - B) off the mirror direction| / d_g (a
     point at distance t turns by |AB_perp| / t; d_g weighs the nearest
     surfaces most): a conservative sum, used for validity only (the view
     change is extrapolated, the parallax is not). Then, as the paper's
     irradiance-change criterion applied to G along that angle:
       w_g = w_B * (cos psi - S_B) / (1 - S_B) / (1 + psi |grad G_B| / G_B * s),
       valid while cos psi > S_B (cos psi = 1 - psi^2 / 2: the paper's w_sigma
       exactly when there is no parallax) and psi |grad G_B| / G_B * s < I_B.
     Measured (tests/ref_lightvec.c; 256 x 256, default settings, mean
     relative error of the floor against a converged gather, hit rate of the
     frame): a floor of 0.3 Lambert + 0.4 Phong exponent 20 seen from the
     Cornell camera, moved 15 cm, then turned 10 degrees: 3.7%, 3.7%, 3.5%
     at 95.3%, 98.0%, 98.8% hits (v0.2: 8.0%, 13.4%, 8.0% at 128 x 128; now
     4.9%, 4.4%, 3.6% there); a purely glossy floor after the move: median
     4.6% (v0.2: 851%). Every result is finite: magnitudes are computed in
     double and saturated at FLT_MAX.

   DIRECT LIGHT VECTORS (LIGHTVEC_KIND_DIRECT)

     A DLV record holds the light of the emitters alone (lightvec_gather_direct:
     stratified samples over the emitting triangles with shadow rays), d_avg is
     the harmonic mean distance to the light samples, the gradient is the exact
     derivative of the unoccluded estimate, and the record keeps the fraction
     of unoccluded samples; on a glossy surface the same samples give G, its
     view gradient and d_g. Direct light changes smoothly where every sample is
     visible (or none is), and abruptly across shadow boundaries, so a DLV
     lookup interpolates only when every valid record is fully lit, or every one
     is fully in umbra; a penumbra record among them, or lit and shadowed
     records together, make it a miss. Valid: open lit areas, umbrae, the smooth
     falloff of large sources. Not valid: penumbrae (every point there is
     gathered), shadows of occluders smaller than the record spacing (no record
     sees them, so interpolation crosses them), and the onset of a shadow
     before the first penumbra record exists nearby. Its defaults are tighter
     than the indirect ones (radius_scale 0.25, irradiance change 0.1).
     Caustic light vectors (CLV) are not implemented: the built-in renderer has
     no specular transport.

   GLASS AND SKY

     A scene material with transmittance t > 0 (any channel) is thin glass,
     as in the examples' tracer and the reference renderer: light passes
     straight through it (no refraction), times t per RGB channel, from
     either side. The built-in renderer crosses panes without using up a
     bounce: a path that meets a pane from the front goes through with
     probability lum(t) / (lum(t) + lum(diffuse)) and otherwise reflects
     off it (always through when no bounce is left, or from the back);
     shadow rays to the emitters and to the sky are attenuated by every
     pane they cross. At most LIGHTVEC_MAX_GLASS_LAYERS (16) panes along a
     ray; the next one blocks it. Rays that leave the scene see the sky:
     desc.sky, a constant radiance, or desc.environment, a small HDR map of
     environment_width x environment_height rgb floats, latitude-longitude
     with +y up: row r covers the angle theta from +y in [pi r / height,
     pi (r + 1) / height) (row 0 at the zenith), column c the azimuth
     phi = atan2(z, x) in [2 pi c / width - pi, 2 pi (c + 1) / width - pi);
     a direction takes its texel (no filtering; a map of one radiance L is
     the constant sky L bit for bit). It is the layout of the examples'
     ex_sky (examples/common/scene_sky.h). The sky counts as light at every
     hit of a path (one cosine-distributed ray, through glass) and, seen
     straight along a gather ray, through windows or not, it is part of the
     indirect light vector: the direct light vectors hold the emitters'
     light only, so a sky-lit room needs no DLV for its daylight.
     Validity and glass: a gather ray's distance is that of the first
     surface it meets, a pane included, so d_avg (and every radius) is what
     it would be with the window opaque: the light through a window changes
     across the window's edges, which stand where the pane is; a radius
     never grows because there is glass. For direct light vectors a sample
     seen through glass counts as visible (dimmed by t): a pane dims evenly
     and casts no shadow edge of its own (its frame does). Measured against
     the reference (tests/ref_lightvec_glass.c: a closed grey room lit only
     through a window in the ceiling, single and double glazing, a
     reflecting pane, an environment map): gathered irradiance on the floor
     within 0.6 % under the constant sky (standard error 0.5 %), looked up
     within 0.5 %; under the environment map 0.5 % and 2.6 % (standard
     error 1.1 %, the map's bright texels seen through few strata). Materials
     with transmittance 0 and a black sky give the results of v0.3 bit for
     bit. With incoming_radiance the callback answers for glass and sky.

   PERFORMANCE

     Lookups at 10^5 records on the walls of a room (tests/bench_lightvec.c,
     one thread, CPU time, medians of 5 passes; v0.4.7, three runs at a
     load of 1.3 to 2.3): 6 valid records per query 0.76 to 0.77 us in a
     random query order (every one a cache miss), 0.52 us sorted by
     position (as a frame's pixels come); 45 valid 1.88 to 1.95 us random,
     1.58 to 1.60 us sorted (after lightvec_cache_optimize 1.77 and 1.48
     us). At 10^6 records, 6 valid: 2.6 us random (memory latency), 1.03
     us sorted. The random figures rise with the load, as other programs
     take the shared caches: 2.0 to 2.6 us dense at a load of 2 to 7. What
     each version changed follows, oldest first. v0.4.3 on a load of 7 to
     8: 0.81, 0.54, 2.25, 1.57, 1.91, 1.35, 2.7, 1.07 us in the order
     above. (v0.4.2 on the same
     runs: 0.92, 0.56, 2.41, 1.58, 2.12, 1.35, 3.45, 1.21 us.) v0.4.5
     merges the kd-trees of a face at a ratio of 64 instead of 8 (fewer,
     larger trees: 4.6 instead of 7 per dense lookup). The same records
     are kept with the same weights; only the order they are summed in (in
     double) can differ, and all 2 x 10^5 results of the two benchmark
     caches came out the same bit for bit. Both versions in one process,
     alternating passes of 10^5 random lookups (thread CPU, medians of 21,
     load 15 to 17, which inflates both): dense 2.69 us against 2.90
     (0.93x), sparse 1.35 against 1.50 (0.90x); the benchmark itself, run
     alternately (medians of 3, load 14 to 17): dense 2.88 us random, 1.67
     sorted against 3.46 and 1.83, sparse 1.16 against 1.23 (v0.4.4 took
     2.18 us dense at a load of 1: the 2 us target is not met under this
     load, and at a low one is not shown). Insertions take 1.5x
     (dense) to 2.4x (sparse, 10^5) as long: 26 and 18 us.
     A kd-tree node holds eight child boxes in rows (three binary levels),
     tested with a few SIMD compares; a leaf is a block of 8 records whose
     tested fields sit together, and the tests that need no square root run
     over the whole block at once. The walk prefetches the first two lines
     of the blocks it reaches (positions and radii) and queues them; then a
     first sweep drops the blocks where no sphere holds A (about half of a
     dense lookup's: a record's sphere covers about a third of its leaf's
     box) and prefetches the other five lines of the rest, and a second
     visits those in the walk's order, so that their memory latencies
     overlap. A node whose children that hold A are all leaves hands them
     over at once instead of pushing them (v0.4.6). What the
     interpolation reads of a valid record (its head, one cache line) sits
     in its leaf's block after the rows, so it comes from the page the
     criteria have just read; the k-nearest selection runs once, over all
     the valid records, at the end: a quickselect of the 16th largest rank
     whose passes split the ranks without a branch on them (about 3n
     compares; counting, as v0.4.3 did, took n^2 and 9% of a dense lookup),
     then the records at or above it in the order the walk found them. Where a dense lookup goes (45 valid):
     2.6 faces, 7 kd-trees (4.6 in v0.4.5), 26 nodes (22), 33 leaves (about 260 records
     tested, 83 inside their sphere; 12 leaves hold A in none), 16
     interpolated, about 330 cache lines; in a random order it waits on memory (the same
     lookups with their data in cache take 1.2 us). These left the time as
     it was or made it longer, with the same results: walking all the
     kd-trees of a lookup together level by level; the other criteria from
     the item rather than from rows; nodes of 4 or 16 children; and, last
     round, bounding a leaf's viewer directions and normals by cones (they
     would skip 2.5 of 29 full leaves). In v0.4.5, measured the same way:
     a quick test per leaf on three cache lines (positions, radii, sigma in
     16-bit fixed point) and the exact fields read only for the records
     that pass (182 lines per dense lookup instead of about 250: 4 to 10%
     slower, the entries' extra pages and a dependent load outweigh the
     lines; with transparent huge pages it was 2 to 10% faster); visiting queued blocks
     while the walk goes on; splitting kd-trees on the radius too, and
     finer icosahedron faces (both visit more leaves: the records within
     reach of A share their sigmas). A dense lookup's data held in cache
     takes 1.1 us: about half of its time in a random order is
     arithmetic, half memory. Transparent huge pages for the
     trees (an allocator that asks for them, or glibc's
     glibc.malloc.hugetlb=1) took about 5% off the dense random figure.
     v0.4.6 loads a leaf's last five lines only where a sphere holds A
     (earlier rounds measured no gain; the paired figures below say 6%)
     and hands last-level leaves over without pushing them; every result
     is the same bit for bit (2 x 10^5 lookups of the benchmark's sparse
     and dense caches compared). Both versions in one process over the
     benchmark's caches and queries, in chunks of 2,000 lookups run old,
     new, new, old, the ratio of each chunk pair (thread CPU, load 13 to
     15; medians, quartiles in brackets): dense random 2.94 against 3.21
     us, 0.94x (0.89-1.00); sparse random 1.10 against 1.15, 0.94x
     (0.91-0.98); sorted queries, whose blocks are in cache, pay for the
     extra sweep: dense 1.70 against 1.66, 1.03x (1.01-1.04), sparse
     1.01x (0.96-1.05). Dense random lookups stay above the 2 us target
     (2.33 us at load 1 for v0.4.5 less 6%). Tried in v0.4.6 and left
     out, each against v0.4.5 paired the same way: child boxes in 8 bits
     in the node's frame (128-byte nodes, the leaves found a superset):
     1.11x dense, 1.20x sparse, the per-axis thresholds lengthen the chain
     of dependent loads the walk is; per-child boxes of sigma, and kd-tree
     splits on sigma besides position (dense lookups reached 29.4 to 30
     leaves instead of 30; more splits on sigma reached more: 37 at a
     quarter of the weight); walking every tree of a lookup breadth first,
     the pending blocks sorted back into depth-first order (1.02x to
     1.36x); merging a face's kd-trees at a ratio of 256 or 512 instead of
     64 (one tree per face at 10^5 records; with the sweep above 0.90x and
     0.91x dense, against 0.95x for the sweep alone, but insertions from 24
     to 44 us: the walkthrough, where every gather inserts, would lose more
     than its lookups gain); leaves of 16 records (1.0x dense, 1.13x
     sparse, in alternating passes of 10^5 lookups). Transparent huge pages
     (glibc.malloc.hugetlb=1, v0.4.5) took 8 to 17% off dense random
     lookups in three alternating runs of this round.
     v0.4.7 tests a kd-tree node's eight child boxes in one AVX step where
     the target has AVX (the same masks as the SSE, NEON and scalar
     kernels), prefetches the roots of a face's kd-trees at once, keeps a
     face's tail at 8 items, one block (every lookup of a face tests its
     whole tail), and prefetches the tail's position rows; kd-tree builds
     move 20-byte keys instead of reading entries through a permutation
     (the same trees). Every result is the same bit for bit (2 x 10^5
     lookups of the benchmark's caches). A dense lookup at 10^5 records
     now reaches 2.63 faces, 4.85 kd-trees, 67 node tests, 26.3 leaves
     (19.2 with a sphere holding A) and 2.63 tail blocks (v0.4.6, a tail
     of 16: 4.62 trees, 66 node tests, 26.5 leaves, 3.5 tail blocks; after
     lightvec_cache_optimize 2.63 trees, 64 node tests, 25 leaves, no
     tail). Both versions in one process, chunks of 2,000
     lookups old, new, new, old (thread CPU, load 6; medians of 250 chunk
     ratios, quartiles in brackets): dense random 0.957x (0.91-1.00),
     2.66 against 2.81 us; sparse random 0.932x (0.88-0.98); dense sorted
     0.963x (0.95-0.98); insertions 1.04x dense and 1.08x sparse (the
     smaller tail merges twice as often). The benchmark run alternately
     with v0.4.6 at load 5 to 7 printed 2.58 and 2.42 us dense random
     (v0.4.6: 2.80 and 2.29): at that load its swing is larger than the
     change (at a load of 1.3 to 2.3 it prints 1.88 to 1.95 us, under the
     2 us target: see the first paragraph). Tried and left out, paired the same way against the version before it:
     the rest of 4.2's tests and the weights four slots at a time in SIMD
     (the same weights bit for bit; 1.02x: the block visits wait on
     memory and on the branches per valid slot more than on square roots
     and divisions); on top of it, appending all eight slots of a block as
     candidates without a branch on which are valid (1.07x); the first
     sweep without a branch on its test (1.00x); prefetching and handing
     over a last-level node's leaves in one loop (1.00x); faces split at
     32768 records instead of 8192 (0.99x); a merge ratio of 256 (0.95x
     to 0.97x, insertions 1.6x). lightvec_cache_optimize, one kd-tree per
     face, takes 0.92x to 0.95x in the same harness, because a random
     lookup's time follows the cache lines it touches, and the second tree
     and the tail of each face cost more lines than node tests suggest:
     counted through the prefetches, a dense lookup touches 290 distinct
     lines on 26.0 distinct 4 KB pages as inserted, 268 lines on 20.7 pages
     after it (sparse: 104 lines, 16.4 pages against 84, 11.2): node lines
     88.5 against 78.9, tail 7.9 against none, leaf blocks and heads 193
     against 189. Not placement: the same trees copied bit for bit to fresh
     memory, face after face, took 1.01x; with transparent huge pages
     optimize still took 0.94x to 0.95x. An optimized cache against itself
     with records inserted after: 60 (tails of about 3 records) 0.97x, 400
     (a tail and a second tree of about 20 records per face) 0.925x. Left
     out: merging all of a face's trees once the records outside its
     largest come to 1/1, 1/8 or 1/32 of it (1.00x, 0.99x, 1.03x: a face
     still has a second tree between rebuilds, and its size does not
     matter); the root's address computed from the tree pointer, so that
     its prefetch does not wait for the tree's head (0.99x); the tail's
     near test at once, queued only where a sphere holds A (1.00x dense,
     0.99x sparse). One tree per face at all times would rebuild a face at
     every merge (every 8 insertions): about 140 us per insertion at 5,000
     records per face, against 20 us. The benchmark run alternately with
     v0.4.6 at load 2 to 4, three runs each: 2.02, 2.06 and 2.03 us dense
     random (v0.4.6: 2.10, 2.59, 2.22), 1.57 to 1.61 us sorted (1.65 to
     1.75), 0.76 to 0.77 us sparse (0.84 to 0.95).
     Memory: 534 bytes per record at 10^5 (545 before v0.4.7; records,
     radii, items, blocks, nodes). Insertion with neighbour clamping (v0.4.4): 4.8 us at 10^5 records,
     10.5 us in the dense cache (a gather takes about 1 ms);
     lightvec_cache_optimize of 10^5 records 28 ms (22 ms dense).

   LIMITS

     Up to 2^32 - 1 records per cache, LIGHTVEC_MAX_TRIANGLES triangles per
     scene. Strata: at most 256 x 512 cells. The built-in renderer shades hit
     points as Lambertian (direct light by area sampling of the emitters,
     each sample picking an emitter by its importance at the hit: power,
     distance and both cosines bounded over the emitter's sphere, so lamps
     behind the hit or far away rarely take a sample, though lamps behind a
     wall still do: the cost is linear in the emitter count; plus
     `bounces - 1` cosine-sampled bounces); surfaces are one-sided as in
     radiosity (the front is the side the counter-clockwise winding faces; a
     back face is black and emits nothing, unless it is glass); rays that
     escape see the sky (black by default). Glass is thin and straight-through:
     no refraction, no caustics, no frosted glass, at most
     LIGHTVEC_MAX_GLASS_LAYERS panes along a ray.
     A glossy part is exact at the viewer it was computed for and first-order
     around it; highlights sharper than the lobe's gradient can follow are
     gathered anew. Records of different materials are interpolated together:
     for Lambert the albedo cancels out of M and G is per unit specular
     reflectance, but records of different exponents mix their lobes (the
     glossy vector uses their weighted mean exponent): keep one cache per
     glossy exponent if that matters.

   PAPER

       Rodolphe Crespin and Bernard Peroche, Light Vectors for a Moving Observer, WSCG 2004.
       Jacques Zaninetti and Bernard Peroche, A vector model for global illumination in
       ray tracing, WSCG 1998.
       Gregory J. Ward and Paul Heckbert, Irradiance gradients, Eurographics Workshop on
       Rendering 1992 (the gradient of eq. 6, the gradient-corrected interpolation).
       Gregory J. Ward, Francis M. Rubinstein and Robert D. Clear, A ray tracing solution
       for diffuse interreflection, SIGGRAPH 1988 (irradiance caching, d_avg, the
       "in front" test).
       Jaroslav Krivanek, Pascal Gautron, Sumanta Pattanaik and Kadi Bouatouch, Radiance
       caching for efficient global illumination computation, IEEE TVCG 2005 (caching
       glossy light with its gradients).
       Jaroslav Krivanek, Kadi Bouatouch, Sumanta Pattanaik and Jiri Zara, Making
       radiance and irradiance caching practical: adaptive caching and neighbor
       clamping, EGSR 2006 (neighbour clamping).
       Alejandro Conty Estevez and Christopher Kulla, Importance sampling of many lights
       with adaptive tree splitting, HPG 2018 (the emitter importance at a gather hit).
       Eric Veach, Robust Monte Carlo methods for light transport simulation, PhD thesis,
       Stanford 1997 (the balance heuristic).
       J. L. Bentley and J. B. Saxe, Decomposable searching problems I: static-to-dynamic
       transformation, J. Algorithms 1980 (the insertion scheme of the kd-trees).
*/
#ifndef LIGHTVEC_H
#define LIGHTVEC_H

#include <stddef.h>
#include <stdint.h>

#define LIGHTVEC_VERSION_MAJOR 0
#define LIGHTVEC_VERSION_MINOR 4
#define LIGHTVEC_VERSION_PATCH 10
#define LIGHTVEC_FILE_FORMAT_VERSION 2

#ifndef LIGHTVEC_API
#  ifdef LIGHTVEC_STATIC
#    define LIGHTVEC_API static
#  else
#    define LIGHTVEC_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum lightvec_result {
    LIGHTVEC_OK = 0,
    LIGHTVEC_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    LIGHTVEC_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    LIGHTVEC_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    LIGHTVEC_ERROR_VERSION,           /* serialized data has an unsupported format version */
    LIGHTVEC_ERROR_CANCELLED,         /* the progress callback asked to stop */
    LIGHTVEC_ERROR_IO                 /* a read or write callback failed */
} lightvec_result;

typedef struct lightvec_allocator {
    void *(*alloc)(size_t size, void *user);  /* NULL: LIGHTVEC_MALLOC */
    void (*free)(void *ptr, void *user);      /* NULL: LIGHTVEC_FREE */
    void *user;
} lightvec_allocator;

typedef void (*lightvec_job_fn)(void *ctx, uint32_t index);
typedef void (*lightvec_parallel_for_fn)(void *user, lightvec_job_fn job, void *ctx, uint32_t count);
typedef int (*lightvec_progress_fn)(void *user, uint64_t done, uint64_t total); /* non-zero cancels */
typedef void (*lightvec_log_fn)(void *user, const char *message);
typedef int (*lightvec_write_fn)(void *user, const void *bytes, size_t n);  /* 0 = ok */
typedef int (*lightvec_read_fn)(void *user, void *bytes, size_t n);         /* 0 = all n bytes read */

/* A ray hit as Embree reports it: u, v = barycentric weights of the
   triangle's 2nd and 3rd vertex, t in units of |dir|. */
typedef struct lightvec_hit {
    float t;
    float u, v;
    uint32_t triangle;
} lightvec_hit;

/* Replaces the built-in BVH: closest hit in (0, tmax), 1 on a hit. */
typedef int (*lightvec_trace_fn)(void *user, const float org[3], const float dir[3], float tmax,
                                 lightvec_hit *hit);

/* Replaces the built-in renderer in lightvec_gather: the radiance arriving at
   org from direction dir (unit, pointing away from org) and the distance to
   the surface it comes from (INFINITY or any value >= 1e30 when the ray
   escapes). Radiance must be finite and non-negative. */
typedef void (*lightvec_incoming_fn)(void *user, const float org[3], const float dir[3],
                                     float radiance[3], float *distance);

/* Lambert + normalized Phong:
   f_r(wi -> wo) = diffuse / pi + specular * (exponent + 2) / (2 pi) * max(0, cos alpha)^exponent,
   alpha = angle between wo and the mirror image of wi about the normal. */
typedef struct lightvec_material {
    float diffuse[3];    /* Lambert reflectance */
    float specular[3];   /* Phong reflectance */
    float exponent;      /* Phong exponent, >= 0 */
    float emission[3];   /* emitted radiance W/(m^2 sr), front face only (scene materials) */
    float transmittance[3]; /* thin glass (scene materials): this share of the light passes straight
                               through, in [0, 1] per channel; 0 = opaque (see GLASS AND SKY) */
} lightvec_material;

/* The light arriving at a point as two virtual lights (see GLOSSY SURFACES):
   the diffuse light vector (D, M) of eq. 2 and 3 with the Lambert term, which
   holds for every viewer, and the glossy light vector (D_g, M_g), eq. 3 with
   the glossy lobe for the viewer it was made for:
     L(w_r) = M rho_d / pi cos(n, D) + M_g f_s(D_g -> w_r) cos(n, D_g). */
typedef struct lightvec_vector {
    float direction[3];          /* D: unit, toward the mean incident light (eq. 2) */
    float magnitude[3];          /* M = E / cos(n, D): the irradiance it carries */
    float glossy_direction[3];   /* D_g: unit, the mirror direction of the viewer; 0 = no glossy part */
    float glossy_magnitude[3];   /* M_g = G / (lobe(D_g -> w_r) cos(n, D_g)) (eq. 3 for the lobe) */
} lightvec_vector;

/* Record flags. */
#define LIGHTVEC_RECORD_VIEW_INDEPENDENT 1u  /* Lambertian: found by lookups with outgoing = NULL */

/* One cached light vector (section 3.2: x, n, w, the vector, gradient, d_avg,
   irradiance; and the glossy lobe's radiance with its view gradient). */
typedef struct lightvec_record {
    float position[3];      /* B */
    float normal[3];        /* unit surface normal at B */
    float outgoing[3];      /* unit sigma: toward the viewer it was computed for */
    lightvec_vector vector; /* the light vectors at (B, sigma) */
    float irradiance[3];    /* E_B of the gathered light */
    float gradient[3][3];   /* dE/dx: gradient[channel][axis] (eq. 6, Ward & Heckbert) */
    float glossy[3];        /* G(sigma): radiance the normalized Phong lobe reflects toward sigma per
                               unit specular reflectance (the glossy part is specular * G) */
    float glossy_gradient[3][3];  /* dG/dw_r at sigma: [channel][axis], perpendicular to sigma */
    float distance;         /* d_avg: harmonic mean distance to the gathered surfaces */
    float glossy_distance;  /* d_g: harmonic mean distance along the lobe (its parallax); 0 = no glossy part */
    float exponent;         /* Phong exponent of the lobe of G; sets the record's direction tolerance */
    float glossy_share;     /* specular * G / the whole radiance toward sigma (luminance): how much of
                               what the viewer sees the glossy part is, which scales its tolerances;
                               0 = 1 */
    float radius;           /* validity radius in effect (set by the cache: radius_scale * distance,
                               clamped by its neighbours); ignored by lightvec_insert */
    float visibility;       /* DLV: fraction of unoccluded light samples; 1 for indirect */
    uint32_t flags;         /* LIGHTVEC_RECORD_* */
} lightvec_record;

/* ---- scene and built-in renderer ---------------------------------------- */

/* Largest triangle_count: 3 * count indices stay addressable in 32 bits. */
#define LIGHTVEC_MAX_TRIANGLES 0x55555555u
#define LIGHTVEC_MAX_ENVIRONMENT_SIZE 65536u  /* texels per side of the sky map */
#define LIGHTVEC_MAX_GLASS_LAYERS 16u         /* panes a ray crosses; one more blocks it */

typedef struct lightvec_scene_desc {
    const float *positions;      /* xyz per vertex */
    size_t stride;               /* bytes between vertices; 0 = 3 floats */
    uint32_t vertex_count;
    const uint32_t *indices;     /* 3 per triangle */
    uint32_t triangle_count;
    const uint32_t *material_ids;           /* per triangle; NULL = material 0 */
    const lightvec_material *materials;     /* copied */
    uint32_t material_count;
    lightvec_trace_fn trace;     /* NULL = the built-in BVH */
    void *trace_user;
    float sky[3];                /* radiance of rays that leave the scene (a constant sky); 0 = none */
    const float *environment;    /* optional sky map (copied), rgb per texel, latitude-longitude with +y
                                    up (GLASS AND SKY); replaces sky; NULL = the constant sky */
    uint32_t environment_width;  /* texels per row, 1..LIGHTVEC_MAX_ENVIRONMENT_SIZE */
    uint32_t environment_height; /* rows, from the zenith (+y) down to the nadir */
    lightvec_allocator allocator;
    lightvec_log_fn log;
    void *log_user;
} lightvec_scene_desc;

typedef struct lightvec_scene lightvec_scene;

typedef struct lightvec_scene_stats {
    uint32_t triangle_count;
    uint32_t degenerate_count;   /* zero-area triangles, skipped */
    uint32_t emitter_count;      /* triangles with non-zero emission */
    uint32_t bvh_node_count;
    float bounds_min[3], bounds_max[3];
    float ray_offset;            /* origin offset along the normal of secondary rays */
} lightvec_scene_stats;

/* The point a light vector is computed for. */
typedef struct lightvec_surface {
    float position[3];
    float normal[3];             /* unit, on the side of the viewer */
    float outgoing[3];           /* unit, toward the viewer (ignored with VIEW_INDEPENDENT) */
    uint32_t flags;              /* LIGHTVEC_RECORD_VIEW_INDEPENDENT: 3D record, Lambert only */
    lightvec_material material;
} lightvec_surface;

typedef struct lightvec_gather_desc {
    uint32_t strata_theta;       /* eq. 5 zenith strata (equal solid angle); 0 = 20 */
    uint32_t strata_phi;         /* eq. 5 azimuth strata; 0 = 3 * strata_theta */
    uint32_t bounces;            /* reflections of the gathered light: 1 = direct light reflected
                                    at the hit points, each more = one diffuse bounce; 0 = 2 */
    uint32_t light_samples;      /* emitter samples per hit point, each picking an emitter by its
                                    importance there (power, distance, cosines); 0 = 1 */
    uint32_t glossy_samples;     /* rays sampled from the glossy lobe (in antithetic pairs: rounded
                                    down to even), combined with the strata by multiple importance
                                    sampling; 0 = a quarter of the strata (glossy surfaces only) */
    float min_distance;          /* clamp of d_avg (world units); 0 = none */
    float max_distance;          /* 0 = none */
    uint64_t seed;               /* random stream = (seed, index) */
    lightvec_incoming_fn incoming_radiance;   /* NULL = the built-in renderer */
    void *incoming_user;
} lightvec_gather_desc;

/* ---- cache ----------------------------------------------------------------- */

typedef enum lightvec_kind {
    LIGHTVEC_KIND_DEFAULT = 0,   /* indirect */
    LIGHTVEC_KIND_INDIRECT = 1,  /* ILV */
    LIGHTVEC_KIND_DIRECT = 2     /* DLV: visibility rule, tighter defaults */
} lightvec_kind;

/* How valid vectors are combined (4.2.3). */
typedef enum lightvec_interpolation {
    LIGHTVEC_INTERPOLATION_DEFAULT = 0,   /* GRADIENT */
    LIGHTVEC_INTERPOLATION_PLAIN = 1,     /* the paper: M = sum w M_i / sum w, D = normalize(sum w D_i) */
    LIGHTVEC_INTERPOLATION_PROJECTED = 2, /* M cos(n, D) is interpolated, then divided by cos(n_A, D):
                                             for Lambert exactly Ward's interpolation of irradiance */
    LIGHTVEC_INTERPOLATION_GRADIENT = 3   /* PROJECTED, each record first moved to A by its gradient:
                                             times 1 + grad E_c . (A - B) / E_c (Ward & Heckbert) */
} lightvec_interpolation;

/* Cache flags. */
#define LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP 1u  /* keep R_B = radius_scale * d_avg (no neighbour clamping) */

typedef struct lightvec_cache_desc {
    lightvec_kind kind;
    lightvec_interpolation interpolation;
    float radius_scale;          /* R_B = radius_scale * d_avg_B (Ward's accuracy a; the paper
                                    uses 1); 0 = 0.3 ILV, 0.25 DLV */
    float max_irradiance_change; /* I_B, relative; 0 = 0.5 ILV, 0.1 DLV */
    float max_normal_angle;      /* degrees, S_curv = cos; 0 = 20 ILV, 10 DLV */
    float max_direction_angle;   /* degrees: the largest S_dir angle (a glossy record's own angle
                                    follows its lobe, lightvec_direction_angle); 0 = 15 */
    uint32_t min_valid;          /* valid vectors needed to interpolate; 0 = 3 */
    uint32_t max_neighbors;      /* a lookup interpolates at most this many valid vectors, those of
                                    the largest weights (k-nearest cap); 0 = 16 */
    float front_tolerance;       /* Ward's "in front" test: B is skipped when A lies behind B's
                                    surface, (A - B) . (n_A + n_B) / 2 < -front_tolerance * R_B; 0 = 0.05 */
    uint32_t flags;              /* LIGHTVEC_CACHE_*; 0 = defaults */
    uint32_t face_split_threshold;  /* a leaf face holding more splits in four; 0 = 8192 */
    uint32_t max_face_depth;     /* 0 = 8 (20 * 4^8 faces at most) */
    lightvec_allocator allocator;
    lightvec_parallel_for_fn parallel_for;   /* optimize and load; NULL = serial */
    void *parallel_user;
    lightvec_progress_fn progress;
    void *progress_user;
    lightvec_log_fn log;
    void *log_user;
} lightvec_cache_desc;

typedef struct lightvec_cache lightvec_cache;

typedef struct lightvec_lookup_result {
    lightvec_vector vector;      /* interpolated D and M (when hit) */
    float weight;                /* W: mean global weight of the interpolated vectors (4.3); 0 if none */
    uint32_t valid_count;        /* vectors that passed every criterion */
    uint32_t used_count;         /* of those, interpolated: min(valid_count, max_neighbors) */
    int hit;                     /* used_count >= min_valid (and the DLV visibility rule) */
} lightvec_lookup_result;

typedef struct lightvec_cache_stats {
    lightvec_kind kind;
    uint64_t record_count;
    uint32_t face_count;         /* icosahedron faces, inner and leaves */
    uint32_t leaf_count;
    uint32_t max_depth;          /* deepest leaf */
    uint32_t tree_count;         /* kd-trees over all leaves */
    size_t bytes;                /* memory held */
    float radius_scale, max_irradiance_change, cos_normal, cos_direction;  /* effective */
    float front_tolerance;
    lightvec_interpolation interpolation;
    uint32_t min_valid, max_neighbors, face_split_threshold, max_face_depth, flags;
} lightvec_cache_stats;

typedef struct lightvec_face_info {
    float vertices[3][3];        /* unit, counter-clockwise seen from outside */
    uint32_t depth;              /* 0 = one of the 20 faces of the icosahedron */
    uint32_t leaf;               /* 1 = holds records (not split) */
    uint64_t record_count;       /* records in the face (leaf) or below it */
} lightvec_face_info;

#define LIGHTVEC_PRIORITY_MAX 1e30f  /* lightvec_priority when W is 0 */

LIGHTVEC_API const char *lightvec_result_string(lightvec_result r);

LIGHTVEC_API lightvec_result lightvec_scene_create(const lightvec_scene_desc *desc, lightvec_scene **out);
LIGHTVEC_API void lightvec_scene_destroy(lightvec_scene *scene);
LIGHTVEC_API lightvec_result lightvec_scene_info(const lightvec_scene *scene, lightvec_scene_stats *info);
LIGHTVEC_API int lightvec_scene_intersect(const lightvec_scene *scene, const float org[3], const float dir[3],
                                          float tmax, lightvec_hit *hit);

LIGHTVEC_API lightvec_result lightvec_gather(const lightvec_scene *scene, const lightvec_gather_desc *desc,
                                             const lightvec_surface *surface, uint64_t index,
                                             lightvec_record *out);
LIGHTVEC_API lightvec_result lightvec_gather_direct(const lightvec_scene *scene, const lightvec_gather_desc *desc,
                                                    const lightvec_surface *surface, uint64_t index,
                                                    lightvec_record *out);
LIGHTVEC_API void lightvec_brdf(const lightvec_material *m, const float normal[3], const float wi[3],
                                const float wo[3], float f[3]);
LIGHTVEC_API void lightvec_radiance(const lightvec_material *m, const float normal[3], const float *outgoing,
                                    const lightvec_vector *v, float rgb[3]);
LIGHTVEC_API float lightvec_direction_angle(float exponent);

LIGHTVEC_API lightvec_result lightvec_cache_create(const lightvec_cache_desc *desc, lightvec_cache **out);
LIGHTVEC_API void lightvec_cache_destroy(lightvec_cache *cache);
LIGHTVEC_API lightvec_result lightvec_insert(lightvec_cache *cache, const lightvec_record *record, uint32_t *id);
LIGHTVEC_API lightvec_result lightvec_lookup(const lightvec_cache *cache, const float position[3], const float normal[3],
                                             const float *outgoing, lightvec_lookup_result *out);
LIGHTVEC_API lightvec_result lightvec_find(const lightvec_cache *cache, const float position[3], const float normal[3],
                                           const float *outgoing, uint32_t *ids, float *weights,
                                           uint32_t capacity, uint32_t *count);
LIGHTVEC_API float lightvec_priority(float rc_priority, float W);
LIGHTVEC_API lightvec_result lightvec_cache_optimize(lightvec_cache *cache);
LIGHTVEC_API lightvec_result lightvec_cache_record(const lightvec_cache *cache, uint32_t id, lightvec_record *out);
LIGHTVEC_API lightvec_result lightvec_cache_info(const lightvec_cache *cache, lightvec_cache_stats *info);
LIGHTVEC_API lightvec_result lightvec_cache_face(const lightvec_cache *cache, uint32_t index, lightvec_face_info *out);
LIGHTVEC_API lightvec_result lightvec_cache_locate(const lightvec_cache *cache, const float direction[3],
                                                   uint32_t *index);

LIGHTVEC_API lightvec_result lightvec_save(const lightvec_cache *cache, lightvec_write_fn write, void *user);
LIGHTVEC_API lightvec_result lightvec_load(const lightvec_cache_desc *desc, lightvec_read_fn read, void *user,
                                           lightvec_cache **out);
LIGHTVEC_API lightvec_result lightvec_save_to_memory(const lightvec_cache *cache, const lightvec_allocator *a,
                                                     void **data, size_t *size);
LIGHTVEC_API lightvec_result lightvec_load_from_memory(const void *data, size_t size, const lightvec_cache_desc *desc,
                                                       lightvec_cache **out);
LIGHTVEC_API void lightvec_free_memory(const lightvec_allocator *a, void *data);

#ifdef __cplusplus
}
#endif
#endif /* LIGHTVEC_H */

/* ------------------------------------------------------------------------ */
#if defined(LIGHTVEC_IMPLEMENTATION) && !defined(LIGHTVEC_IMPLEMENTATION_INCLUDED)
#define LIGHTVEC_IMPLEMENTATION_INCLUDED

#if defined(LIGHTVEC_MALLOC) != defined(LIGHTVEC_FREE)
#  error "lightvec.h: define both LIGHTVEC_MALLOC and LIGHTVEC_FREE, or neither"
#endif
#ifndef LIGHTVEC_MALLOC
#  include <stdlib.h>
#  define LIGHTVEC_MALLOC(size) malloc(size)
#  define LIGHTVEC_FREE(ptr) free(ptr)
#endif

#include <string.h>
#include <math.h>
#include <float.h>
#include <stdio.h>

LIGHTVEC_API const char *lightvec_result_string(lightvec_result r)
{
    switch (r) {
    case LIGHTVEC_OK: return "ok";
    case LIGHTVEC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case LIGHTVEC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case LIGHTVEC_ERROR_CORRUPT_DATA: return "corrupt data";
    case LIGHTVEC_ERROR_VERSION: return "unsupported format version";
    case LIGHTVEC_ERROR_CANCELLED: return "cancelled";
    case LIGHTVEC_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

/* ======================================================================
   1. allocation
   ---------------------------------------------------------------------- */
/* In the declarations (public):

   typedef struct lightvec_allocator {
       void *(*alloc)(size_t size, void *user);  // NULL: LIGHTVEC_MALLOC
       void (*free)(void *ptr, void *user);      // NULL: LIGHTVEC_FREE
       void *user;
   } lightvec_allocator;
*/

/* Both callbacks or neither: a lone alloc would leak through LIGHTVEC_FREE. */
static int lightvec__allocator_valid(const lightvec_allocator *a)
{
    return (a->alloc == NULL) == (a->free == NULL);
}

static void *lightvec__alloc(const lightvec_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    return a->alloc ? a->alloc(size, a->user) : LIGHTVEC_MALLOC(size);
}

/* count * item bytes, or NULL when the product overflows. */
static void *lightvec__alloc_array(const lightvec_allocator *a, size_t count, size_t item)
{
    if (item && count > SIZE_MAX / item) return NULL;
    return lightvec__alloc(a, count * item);
}

static void lightvec__free(const lightvec_allocator *a, void *p)
{
    if (!p) return;
    if (a->free) a->free(p, a->user);
    else LIGHTVEC_FREE(p);
}

/* Zero means default: the documented default replaces a zero field. */
#define lightvec__def(v, d) ((v) ? (v) : (d))

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
typedef struct lightvec__vec3 { float x, y, z; } lightvec__vec3;

static lightvec__vec3 lightvec__v3(float x, float y, float z) { lightvec__vec3 r; r.x = x; r.y = y; r.z = z; return r; }
static lightvec__vec3 lightvec__v3_load(const float *p) { return lightvec__v3(p[0], p[1], p[2]); }
static lightvec__vec3 lightvec__add(lightvec__vec3 a, lightvec__vec3 b) { return lightvec__v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static lightvec__vec3 lightvec__sub(lightvec__vec3 a, lightvec__vec3 b) { return lightvec__v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static lightvec__vec3 lightvec__scale(lightvec__vec3 a, float s) { return lightvec__v3(a.x * s, a.y * s, a.z * s); }
static float lightvec__dot(lightvec__vec3 a, lightvec__vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static lightvec__vec3 lightvec__cross(lightvec__vec3 a, lightvec__vec3 b)
{
    return lightvec__v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static float lightvec__length(lightvec__vec3 a) { return sqrtf(lightvec__dot(a, a)); }
static lightvec__vec3 lightvec__normalize(lightvec__vec3 a)
{
    float l = lightvec__length(a);
    return l > 0.0f ? lightvec__scale(a, 1.0f / l) : a;
}
static float lightvec__minf(float a, float b) { return a < b ? a : b; }
static float lightvec__maxf(float a, float b) { return a > b ? a : b; }
static int lightvec__finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

/* An orthonormal basis (t, b, n) around unit n (Duff et al. 2017, branchless). */
static void lightvec__basis(lightvec__vec3 n, lightvec__vec3 *t, lightvec__vec3 *b)
{
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    *t = lightvec__v3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    *b = lightvec__v3(c, s + n.y * n.y * a, -n.y);
}

/* ======================================================================
   3. counter-based random numbers
   A stream is a pure function of (seed, stream id): jobs seed their own
   stream from (desc.seed, job index) and never share state, so results are
   bit-identical for any thread count.
   ---------------------------------------------------------------------- */
typedef struct lightvec__rng { uint64_t state; } lightvec__rng;

/* SplitMix64 finaliser (Steele, Lea, Flood 2014). */
static uint64_t lightvec__mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static lightvec__rng lightvec__rng_stream(uint64_t seed, uint64_t stream)
{
    lightvec__rng r;
    r.state = lightvec__mix64(seed + 0x9E3779B97F4A7C15ull) ^ lightvec__mix64(stream * 0xD1B54A32D192ED03ull + 1u);
    return r;
}

static uint32_t lightvec__rng_u32(lightvec__rng *r)
{
    r->state += 0x9E3779B97F4A7C15ull;
    return (uint32_t)(lightvec__mix64(r->state) >> 32);
}

/* Uniform in [0, 1): 24 random bits, exactly representable. */
static float lightvec__rng_float(lightvec__rng *r)
{
    return (float)(lightvec__rng_u32(r) >> 8) * (1.0f / 16777216.0f);
}

/* ======================================================================
   4. BVH over triangles
   An 8-wide BVH (Embree's BVH8: Wald et al. 2014). Build: a binary tree by
   binned SAH (LIGHTVEC_BVH_BINS bins over the centroid bounds, all three axes
   binned in one pass; a leaf costs one test per block of four triangles),
   then collapsed into 8-wide nodes by opening, again and again, the child of
   largest surface area. A node keeps its eight child boxes in rows
   (structure of arrays) and a leaf is a run of blocks of four triangles in
   rows, so one SIMD instruction tests four boxes or four triangles. Nodes are
   stored depth first; the blocks hold copies of the vertices, nothing of the
   caller's data is kept. Traversal: nearest child first, every stack entry
   keeps its entry distance so that entries behind a closer hit are dropped;
   the watertight ray/triangle test (Woop, Benthin, Wald 2013); any-hit for
   shadow rays. LIGHTVEC_BVH_SIMD selects the SSE2 (x86-64) or NEON (AArch64)
   kernels. The scalar kernels do the same float operations lane by lane, are
   always compiled, and find the same hits bit for bit (bvh->simd = 0 selects
   them).
   ---------------------------------------------------------------------- */
#ifndef LIGHTVEC_BVH_BINS
#define LIGHTVEC_BVH_BINS 16
#endif
#ifndef LIGHTVEC_BVH_SIMD
#define LIGHTVEC_BVH_SIMD 1
#endif
#if LIGHTVEC_BVH_SIMD && (defined(__SSE2__) || defined(_M_X64) || defined(_M_AMD64))
#define LIGHTVEC__SSE 1
#include <emmintrin.h>
#if defined(__AVX__)
#include <immintrin.h>
#endif
#elif LIGHTVEC_BVH_SIMD && defined(__aarch64__) && (defined(__GNUC__) || defined(__clang__))
#define LIGHTVEC__NEON 1
#include <arm_neon.h>
#endif
#if defined(LIGHTVEC__SSE) || defined(LIGHTVEC__NEON)
#define LIGHTVEC__SIMD 1
#else
#define LIGHTVEC__SIMD 0
#endif
/* Where the target fuses a * b + c (FMA on x86 with -mfma, every AArch64),
   both kernels fuse it explicitly: a compiler that contracts on its own
   (GCC's -ffp-contract=fast, clang's default) then has nothing left to fuse
   differently in the scalar kernel. Without FMA nothing can be fused. */
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__FMA__) || defined(__aarch64__))
#define LIGHTVEC__BVH_FMA 1
#if defined(LIGHTVEC__SSE)
#include <immintrin.h>
#endif
#else
#define LIGHTVEC__BVH_FMA 0
#endif

#define LIGHTVEC__BVH_WIDTH 8        /* children per node */
#define LIGHTVEC__BVH_LEAF_MAX 16    /* triangles per leaf: four blocks */
#define LIGHTVEC__BVH_NODE_COST 2.0f /* SAH cost of a binary node, in block tests (measured best of 0.5-4) */
#define LIGHTVEC__BVH_MAX_DEPTH 60   /* deeper nodes split at the median: bounds the stacks */
#define LIGHTVEC__BVH_MAX_BINARY_DEPTH (LIGHTVEC__BVH_MAX_DEPTH + 33) /* + 32 halvings of a uint32_t count */
#define LIGHTVEC__BVH_STACK ((LIGHTVEC__BVH_WIDTH - 1) * LIGHTVEC__BVH_MAX_BINARY_DEPTH + LIGHTVEC__BVH_WIDTH)
#define LIGHTVEC__BVH_LEAF 0x80000000u /* a leaf's child reference: LEAF | first block << 3 | blocks - 1 */
#define LIGHTVEC__BVH_MAX_BLOCKS (1u << 28)
#define LIGHTVEC__BVH_NONE 0xFFFFFFFFu
/* Far plane distances are rounded up by 1 + 2 gamma_3 (Ize 2013): a box that
   the ray touches is never lost to the rounding of three operations. */
#define LIGHTVEC__BVH_ROUND_UP 1.00000036f
/* Node boxes are pushed outward by 2^-20 of each bound plus 1e-20 (in the
   scene's units). A ray with a zero direction component (its inverse is
   1e30, lightvec__ray_setup) that runs exactly in the plane of a box's face
   would otherwise leave the box at t = 0 and miss a triangle lying on that
   face; pushed out, it stays inside for t of 1e10 or more. The boxes grow by
   a millionth. */
#define LIGHTVEC__BVH_PAD_RELATIVE 9.5367431640625e-07f   /* 2^-20 */
#define LIGHTVEC__BVH_PAD_ABSOLUTE 1e-20f

typedef struct lightvec__bvh_node {
    float box[6][LIGHTVEC__BVH_WIDTH]; /* rows lo x, hi x, lo y, hi y, lo z, hi z; column = child.
                           An unused child has lo = +inf, hi = -inf: no ray enters it */
    uint32_t child[LIGHTVEC__BVH_WIDTH]; /* inner node index, or a leaf reference (LIGHTVEC__BVH_LEAF) */
} lightvec__bvh_node;

typedef struct lightvec__bvh_tris {
    float v[9][4];      /* rows x, y, z of vertex 0, of vertex 1, of vertex 2; column = triangle */
    uint32_t id[4];     /* the caller's triangle indices; unused columns repeat the last triangle */
} lightvec__bvh_tris;

typedef struct lightvec__bvh {
    lightvec__bvh_node *nodes;    /* both in one allocation, from a cache line boundary */
    lightvec__bvh_tris *blocks;
    char *memory;
    uint32_t node_count, block_count, tri_count;
    uint32_t root;              /* a node index or a leaf reference; unused when tri_count is 0 */
    uint32_t degenerate_count;  /* zero-area triangles skipped by the build */
    int simd;                   /* 1: the SIMD kernels (when compiled in); 0: the scalar ones */
} lightvec__bvh;

typedef struct lightvec__hit {
    float t;         /* distance along the ray in units of |dir| */
    float u, v;      /* barycentric weights of the triangle's 2nd and 3rd vertex */
    uint32_t tri;    /* the caller's triangle index; LIGHTVEC__NO_HIT when missed */
} lightvec__hit;
#define LIGHTVEC__NO_HIT 0xFFFFFFFFu

/* Caller's triangle soup: positions with a byte stride, 3 indices per triangle. */
typedef struct lightvec__mesh_view {
    const float *positions;
    size_t stride;             /* bytes between vertices; 0 = 3 floats */
    const uint32_t *indices;
    uint32_t tri_count;
} lightvec__mesh_view;

static const float *lightvec__vertex(const lightvec__mesh_view *m, uint32_t v)
{
    size_t stride = m->stride ? m->stride : 3 * sizeof(float);
    return (const float *)((const char *)m->positions + (size_t)v * stride);
}

typedef struct lightvec__bvh_ref {   /* build-time record of one triangle */
    float lo[3], hi[3], c[3];
    uint32_t tri;
} lightvec__bvh_ref;

typedef struct lightvec__bvh_bnode { /* build-time binary node, flattened depth first */
    float lo[3];
    uint32_t first;  /* leaf: first ref; inner: index of the right child (the left is next) */
    float hi[3];
    uint32_t count;  /* leaf: ref count (> 0); inner: 0 */
} lightvec__bvh_bnode;

typedef struct lightvec__bvh_bin { float lo[3], hi[3]; uint32_t count; } lightvec__bvh_bin;

static void lightvec__box_empty(float lo[3], float hi[3])
{
    lo[0] = lo[1] = lo[2] = FLT_MAX;
    hi[0] = hi[1] = hi[2] = -FLT_MAX;
}
static void lightvec__box_grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        lo[k] = lightvec__minf(lo[k], plo[k]);
        hi[k] = lightvec__maxf(hi[k], phi[k]);
    }
}
static float lightvec__box_area(const float lo[3], const float hi[3])
{
    float dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    if (dx < 0.0f) return 0.0f;
    return dx * dy + dy * dz + dz * dx;
}

static uint32_t lightvec__bvh_blocks(uint32_t n) { return (n + 3) / 4; }

/* The bin of a centroid coordinate. */
static int lightvec__bvh_bin_of(float c, float lo, float scale)
{
    float f = (c - lo) * scale;   /* NaN or inf when a denormal extent overflows scale */
    return f >= (float)(LIGHTVEC_BVH_BINS - 1) ? LIGHTVEC_BVH_BINS - 1 : f > 0.0f ? (int)f : 0;
}

/* Chooses the binned-SAH split of refs[0..n) (node box lo..hi, centroid box
   clo..chi): returns 0 when a leaf is cheaper or no axis can split, else the
   axis in *axis and the first bin of the right side in *split_bin. */
static int lightvec__bvh_find_split(const lightvec__bvh_ref *refs, uint32_t n, const float lo[3], const float hi[3],
                                  const float clo[3], const float chi[3], int *axis, int *split_bin)
{
    lightvec__bvh_bin bins[3][LIGHTVEC_BVH_BINS];
    float scale[3], right_area[LIGHTVEC_BVH_BINS], best = FLT_MAX;
    float leaf_cost = (float)lightvec__bvh_blocks(n), inv_area = 1.0f / lightvec__box_area(lo, hi);
    uint32_t right_count[LIGHTVEC_BVH_BINS], i;
    int k, b, found = 0;
    for (k = 0; k < 3; k++) {
        scale[k] = chi[k] > clo[k] ? (float)LIGHTVEC_BVH_BINS / (chi[k] - clo[k]) : 0.0f;
        for (b = 0; b < LIGHTVEC_BVH_BINS; b++) { lightvec__box_empty(bins[k][b].lo, bins[k][b].hi); bins[k][b].count = 0; }
    }
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) {
            lightvec__bvh_bin *bin = &bins[k][lightvec__bvh_bin_of(refs[i].c[k], clo[k], scale[k])];
            bin->count++;
            lightvec__box_grow(bin->lo, bin->hi, refs[i].lo, refs[i].hi);
        }
    for (k = 0; k < 3; k++) {
        float blo[3], bhi[3];
        uint32_t count = 0;
        if (scale[k] == 0.0f) continue;   /* all centroids in one plane across k */
        /* sweep from the right, then from the left evaluating each boundary */
        lightvec__box_empty(blo, bhi);
        for (b = LIGHTVEC_BVH_BINS - 1; b > 0; b--) {
            lightvec__box_grow(blo, bhi, bins[k][b].lo, bins[k][b].hi);
            count += bins[k][b].count;
            right_area[b] = lightvec__box_area(blo, bhi);
            right_count[b] = count;
        }
        lightvec__box_empty(blo, bhi);
        count = 0;
        for (b = 1; b < LIGHTVEC_BVH_BINS; b++) {
            float cost;
            lightvec__box_grow(blo, bhi, bins[k][b - 1].lo, bins[k][b - 1].hi);
            count += bins[k][b - 1].count;
            if (count == 0 || right_count[b] == 0) continue;
            cost = LIGHTVEC__BVH_NODE_COST + (lightvec__box_area(blo, bhi) * (float)lightvec__bvh_blocks(count) +
                                            right_area[b] * (float)lightvec__bvh_blocks(right_count[b])) * inv_area;
            if (cost < best) { best = cost; *axis = k; *split_bin = b; found = 1; }
        }
    }
    return found && (best < leaf_cost || n > LIGHTVEC__BVH_LEAF_MAX);
}

/* Splits refs[0..n) in two: by the SAH when it pays, else (coincident
   centroids, the depth cap) by count. Returns the size of the left part, 0
   when the refs should stay a leaf. */
static uint32_t lightvec__bvh_partition(lightvec__bvh_ref *refs, uint32_t n, const float lo[3], const float hi[3],
                                      const float clo[3], const float chi[3], uint32_t depth)
{
    int axis = 0, split_bin = 0;
    uint32_t i, j;
    if (depth < LIGHTVEC__BVH_MAX_DEPTH && lightvec__bvh_find_split(refs, n, lo, hi, clo, chi, &axis, &split_bin)) {
        float scale = (float)LIGHTVEC_BVH_BINS / (chi[axis] - clo[axis]);
        for (i = 0, j = n; i < j;) {
            if (lightvec__bvh_bin_of(refs[i].c[axis], clo[axis], scale) < split_bin) i++;
            else { lightvec__bvh_ref t = refs[i]; refs[i] = refs[--j]; refs[j] = t; }
        }
        return i;   /* both sides hold refs: the split's bins are not empty */
    }
    return n <= LIGHTVEC__BVH_LEAF_MAX ? 0 : n / 2;
}

/* Bounds of every non-degenerate triangle; counts the degenerate ones. The
   area test runs in double: a tiny triangle (a scene at scale 1e-12) is not
   zero because its float cross product underflows. */
static uint32_t lightvec__bvh_collect(lightvec__bvh *bvh, const lightvec__mesh_view *m, lightvec__bvh_ref *refs)
{
    uint32_t i, n = 0;
    for (i = 0; i < m->tri_count; i++) {
        const float *p0 = lightvec__vertex(m, m->indices[3 * i + 0]);
        const float *p1 = lightvec__vertex(m, m->indices[3 * i + 1]);
        const float *p2 = lightvec__vertex(m, m->indices[3 * i + 2]);
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
            refs[n].lo[k] = lightvec__minf(p0[k], lightvec__minf(p1[k], p2[k]));
            refs[n].hi[k] = lightvec__maxf(p0[k], lightvec__maxf(p1[k], p2[k]));
            refs[n].c[k] = 0.5f * (refs[n].lo[k] + refs[n].hi[k]);
        }
        refs[n].tri = i;
        n++;
    }
    return n;
}

typedef struct lightvec__bvh_task {
    uint32_t parent, begin, end, depth;
    int is_right;    /* the parent learns a right child's index when it is popped */
} lightvec__bvh_task;

/* The binary tree over refs[0..n) (n > 0) into bn (room for 2n - 1 nodes).
   Returns the node count; *blocks receives the leaves' block count. */
static uint32_t lightvec__bvh_build_binary(lightvec__bvh_bnode *bn, lightvec__bvh_ref *refs, uint32_t n, uint32_t *blocks)
{
    lightvec__bvh_task stack[LIGHTVEC__BVH_MAX_BINARY_DEPTH + 1];
    uint32_t top = 0, count = 0, i;
    *blocks = 0;
    stack[top].parent = 0; stack[top].begin = 0; stack[top].end = n;
    stack[top].depth = 0; stack[top].is_right = 0; top++;
    while (top) {
        lightvec__bvh_task t = stack[--top];
        uint32_t index = count++, mid;
        lightvec__bvh_bnode *node = &bn[index];
        float clo[3], chi[3];
        if (t.is_right) bn[t.parent].first = index;
        lightvec__box_empty(node->lo, node->hi);
        lightvec__box_empty(clo, chi);
        for (i = t.begin; i < t.end; i++) {
            lightvec__box_grow(node->lo, node->hi, refs[i].lo, refs[i].hi);
            lightvec__box_grow(clo, chi, refs[i].c, refs[i].c);
        }
        mid = t.end - t.begin < 2 ? 0 : lightvec__bvh_partition(refs + t.begin, t.end - t.begin, node->lo, node->hi, clo, chi, t.depth);
        if (mid == 0) {
            node->first = t.begin;
            node->count = t.end - t.begin;
            *blocks += lightvec__bvh_blocks(node->count);
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
static int lightvec__bvh_open(const lightvec__bvh_bnode *bn, uint32_t i, uint32_t kids[LIGHTVEC__BVH_WIDTH])
{
    int k = 2;
    kids[0] = i + 1;
    kids[1] = bn[i].first;
    while (k < LIGHTVEC__BVH_WIDTH) {
        int j, best = -1;
        float best_area = -1.0f;
        for (j = 0; j < k; j++) {
            float area = lightvec__box_area(bn[kids[j]].lo, bn[kids[j]].hi);
            if (bn[kids[j]].count == 0 && area > best_area) { best_area = area; best = j; }
        }
        if (best < 0) break;
        kids[k++] = bn[kids[best]].first;
        kids[best] = kids[best] + 1;
    }
    return k;
}

/* A leaf's triangles into blocks of four from bvh->blocks[first]. */
static void lightvec__bvh_store_leaf(lightvec__bvh *bvh, const lightvec__mesh_view *m, const lightvec__bvh_ref *refs,
                                   uint32_t count, uint32_t first)
{
    uint32_t i;
    for (i = 0; i < 4 * lightvec__bvh_blocks(count); i++) {
        lightvec__bvh_tris *b = &bvh->blocks[first + i / 4];
        uint32_t tri = refs[i < count ? i : count - 1].tri;
        int j, k;
        for (j = 0; j < 3; j++) {
            const float *p = lightvec__vertex(m, m->indices[3 * (size_t)tri + (uint32_t)j]);
            for (k = 0; k < 3; k++) b->v[3 * j + k][i % 4] = p[k];
        }
        b->id[i % 4] = tri;
    }
}

typedef struct lightvec__bvh_place { uint32_t bnode, parent, slot; } lightvec__bvh_place;

/* A box bound v pushed outward (side -1 for a lower bound, +1 for an
   upper one): see LIGHTVEC__BVH_PAD_RELATIVE. */
static float lightvec__bvh_pad(float v, float side)
{
    return v + side * (fabsf(v) * LIGHTVEC__BVH_PAD_RELATIVE + LIGHTVEC__BVH_PAD_ABSOLUTE);
}

/* Collapses the binary tree into 4-wide nodes, depth first. With
   bvh->nodes NULL it only counts them (into bvh->node_count). */
static void lightvec__bvh_collapse(lightvec__bvh *bvh, const lightvec__bvh_bnode *bn, const lightvec__bvh_ref *refs,
                                 const lightvec__mesh_view *m)
{
    lightvec__bvh_place stack[LIGHTVEC__BVH_STACK];
    uint32_t top = 0, nodes = 0, blocks = 0;
    stack[top].bnode = 0; stack[top].parent = LIGHTVEC__BVH_NONE; stack[top].slot = 0; top++;
    while (top) {
        lightvec__bvh_place p = stack[--top];
        const lightvec__bvh_bnode *b = &bn[p.bnode];
        uint32_t ref;
        if (b->count) {
            ref = LIGHTVEC__BVH_LEAF | blocks << 3 | (lightvec__bvh_blocks(b->count) - 1);
            if (bvh->nodes) lightvec__bvh_store_leaf(bvh, m, refs + b->first, b->count, blocks);
            blocks += lightvec__bvh_blocks(b->count);
        } else {
            uint32_t kids[LIGHTVEC__BVH_WIDTH];
            int k = lightvec__bvh_open(bn, p.bnode, kids), j, r;
            ref = nodes++;
            if (bvh->nodes) {
                lightvec__bvh_node *node = &bvh->nodes[ref];
                for (j = 0; j < LIGHTVEC__BVH_WIDTH; j++) {
                    for (r = 0; r < 3; r++) {
                        node->box[2 * r][j] = j < k ? lightvec__bvh_pad(bn[kids[j]].lo[r], -1.0f) : INFINITY;
                        node->box[2 * r + 1][j] = j < k ? lightvec__bvh_pad(bn[kids[j]].hi[r], 1.0f) : -INFINITY;
                    }
                    node->child[j] = 0;
                }
            }
            for (j = k - 1; j >= 0; j--) {   /* the first child is placed next */
                stack[top].bnode = kids[j]; stack[top].parent = ref; stack[top].slot = (uint32_t)j; top++;
            }
        }
        if (!bvh->nodes) continue;
        if (p.parent == LIGHTVEC__BVH_NONE) bvh->root = ref;
        else bvh->nodes[p.parent].child[p.slot] = ref;
    }
    bvh->node_count = nodes;
}

/* Builds the BVH of m's non-degenerate triangles. Indices must be in range and
   coordinates finite (validate first). Returns 0, or -1 when out of memory. */
static int lightvec__bvh_build(lightvec__bvh *bvh, const lightvec__mesh_view *m, const lightvec_allocator *a)
{
    lightvec__bvh_ref *refs;
    lightvec__bvh_bnode *bn = NULL;
    uint32_t n;
    memset(bvh, 0, sizeof *bvh);
    bvh->simd = LIGHTVEC__SIMD;
    refs = (lightvec__bvh_ref *)lightvec__alloc_array(a, m->tri_count, sizeof *refs);
    if (!refs) return -1;
    n = lightvec__bvh_collect(bvh, m, refs);
    if (n) bn = (lightvec__bvh_bnode *)lightvec__alloc_array(a, 2 * (size_t)n - 1, sizeof *bn);
    if (n && bn) {
        lightvec__bvh_build_binary(bn, refs, n, &bvh->block_count);
        lightvec__bvh_collapse(bvh, bn, refs, m);   /* counts the nodes */
        if (bvh->block_count <= LIGHTVEC__BVH_MAX_BLOCKS) {
            size_t nb = (size_t)bvh->node_count * sizeof *bvh->nodes, bb = (size_t)bvh->block_count * sizeof *bvh->blocks;
            bvh->memory = (char *)lightvec__alloc(a, nb + bb + 64);
            if (bvh->memory) {   /* nodes and blocks from a cache line boundary */
                char *p = bvh->memory + (64 - (size_t)((uintptr_t)bvh->memory % 64)) % 64;
                bvh->nodes = (lightvec__bvh_node *)(void *)p;
                bvh->blocks = (lightvec__bvh_tris *)(void *)(p + nb);
            }
        }
        if (bvh->nodes && bvh->blocks) lightvec__bvh_collapse(bvh, bn, refs, m);
    }
    lightvec__free(a, refs);
    lightvec__free(a, bn);
    if (n && (!bvh->nodes || !bvh->blocks)) {
        lightvec__free(a, bvh->memory);
        memset(bvh, 0, sizeof *bvh);
        return -1;
    }
    bvh->tri_count = n;   /* 0: an empty tree, every ray misses */
    return 0;
}

static void lightvec__bvh_free(lightvec__bvh *bvh, const lightvec_allocator *a)
{
    lightvec__free(a, bvh->memory);
    memset(bvh, 0, sizeof *bvh);
}

/* Four floats, and a mask of four lanes, for the SIMD kernels. */
#if defined(LIGHTVEC__SSE)
typedef __m128 lightvec__f4;
typedef __m128 lightvec__m4;
static lightvec__f4 lightvec__f4_load(const float *p) { return _mm_loadu_ps(p); }
static void lightvec__f4_store(float *p, lightvec__f4 a) { _mm_storeu_ps(p, a); }
static lightvec__f4 lightvec__f4_set(float x) { return _mm_set1_ps(x); }
static lightvec__f4 lightvec__f4_add(lightvec__f4 a, lightvec__f4 b) { return _mm_add_ps(a, b); }
static lightvec__f4 lightvec__f4_sub(lightvec__f4 a, lightvec__f4 b) { return _mm_sub_ps(a, b); }
static lightvec__f4 lightvec__f4_mul(lightvec__f4 a, lightvec__f4 b) { return _mm_mul_ps(a, b); }
static lightvec__f4 lightvec__f4_div(lightvec__f4 a, lightvec__f4 b) { return _mm_div_ps(a, b); }
#if LIGHTVEC__BVH_FMA
static lightvec__f4 lightvec__f4_madd(lightvec__f4 a, lightvec__f4 b, lightvec__f4 c) { return _mm_fmadd_ps(a, b, c); }
static lightvec__f4 lightvec__f4_det2(lightvec__f4 a, lightvec__f4 b, lightvec__f4 c, lightvec__f4 d)
{
    lightvec__f4 w = _mm_mul_ps(c, d);
    return _mm_sub_ps(_mm_fmsub_ps(a, b, w), _mm_fmsub_ps(c, d, w));
}
#else
static lightvec__f4 lightvec__f4_madd(lightvec__f4 a, lightvec__f4 b, lightvec__f4 c) { return _mm_add_ps(_mm_mul_ps(a, b), c); }
static lightvec__f4 lightvec__f4_det2(lightvec__f4 a, lightvec__f4 b, lightvec__f4 c, lightvec__f4 d)
{
    return _mm_sub_ps(_mm_mul_ps(a, b), _mm_mul_ps(c, d));
}
#endif
static lightvec__f4 lightvec__f4_min(lightvec__f4 a, lightvec__f4 b) { return _mm_min_ps(a, b); }  /* a < b ? a : b */
static lightvec__f4 lightvec__f4_max(lightvec__f4 a, lightvec__f4 b) { return _mm_max_ps(a, b); }  /* a > b ? a : b */
static lightvec__m4 lightvec__f4_lt(lightvec__f4 a, lightvec__f4 b) { return _mm_cmplt_ps(a, b); }
static lightvec__m4 lightvec__f4_le(lightvec__f4 a, lightvec__f4 b) { return _mm_cmple_ps(a, b); }
static lightvec__m4 lightvec__f4_eq(lightvec__f4 a, lightvec__f4 b) { return _mm_cmpeq_ps(a, b); }
static lightvec__m4 lightvec__m4_and(lightvec__m4 a, lightvec__m4 b) { return _mm_and_ps(a, b); }
static lightvec__m4 lightvec__m4_or(lightvec__m4 a, lightvec__m4 b) { return _mm_or_ps(a, b); }
static lightvec__m4 lightvec__m4_andnot(lightvec__m4 a, lightvec__m4 b) { return _mm_andnot_ps(a, b); } /* ~a & b */
static unsigned lightvec__m4_bits(lightvec__m4 a) { return (unsigned)_mm_movemask_ps(a); }
#elif defined(LIGHTVEC__NEON)
typedef float32x4_t lightvec__f4;
typedef uint32x4_t lightvec__m4;
static lightvec__f4 lightvec__f4_load(const float *p) { return vld1q_f32(p); }
static void lightvec__f4_store(float *p, lightvec__f4 a) { vst1q_f32(p, a); }
static lightvec__f4 lightvec__f4_set(float x) { return vdupq_n_f32(x); }
static lightvec__f4 lightvec__f4_add(lightvec__f4 a, lightvec__f4 b) { return vaddq_f32(a, b); }
static lightvec__f4 lightvec__f4_sub(lightvec__f4 a, lightvec__f4 b) { return vsubq_f32(a, b); }
static lightvec__f4 lightvec__f4_mul(lightvec__f4 a, lightvec__f4 b) { return vmulq_f32(a, b); }
static lightvec__f4 lightvec__f4_div(lightvec__f4 a, lightvec__f4 b) { return vdivq_f32(a, b); }
static lightvec__f4 lightvec__f4_madd(lightvec__f4 a, lightvec__f4 b, lightvec__f4 c) { return vfmaq_f32(c, a, b); }
static lightvec__f4 lightvec__f4_det2(lightvec__f4 a, lightvec__f4 b, lightvec__f4 c, lightvec__f4 d)   /* Kahan, as the scalar */
{
    lightvec__f4 w = vmulq_f32(c, d), nw = vnegq_f32(w);
    return vsubq_f32(vfmaq_f32(nw, a, b), vfmaq_f32(nw, c, d));
}
/* compare and select: the scalar kernels' a < b ? a : b, NaN included (vminq_f32 differs) */
static lightvec__f4 lightvec__f4_min(lightvec__f4 a, lightvec__f4 b) { return vbslq_f32(vcltq_f32(a, b), a, b); }
static lightvec__f4 lightvec__f4_max(lightvec__f4 a, lightvec__f4 b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
static lightvec__m4 lightvec__f4_lt(lightvec__f4 a, lightvec__f4 b) { return vcltq_f32(a, b); }
static lightvec__m4 lightvec__f4_le(lightvec__f4 a, lightvec__f4 b) { return vcleq_f32(a, b); }
static lightvec__m4 lightvec__f4_eq(lightvec__f4 a, lightvec__f4 b) { return vceqq_f32(a, b); }
static lightvec__m4 lightvec__m4_and(lightvec__m4 a, lightvec__m4 b) { return vandq_u32(a, b); }
static lightvec__m4 lightvec__m4_or(lightvec__m4 a, lightvec__m4 b) { return vorrq_u32(a, b); }
static lightvec__m4 lightvec__m4_andnot(lightvec__m4 a, lightvec__m4 b) { return vbicq_u32(b, a); } /* ~a & b */
static unsigned lightvec__m4_bits(lightvec__m4 a)
{
    static const uint32_t weight[4] = {1, 2, 4, 8};
    return vaddvq_u32(vandq_u32(a, vld1q_u32(weight)));
}
#endif

/* a * b + c, fused where LIGHTVEC__BVH_FMA (the shear and the distance). */
static float lightvec__bvh_madd(float a, float b, float c)
{
#if LIGHTVEC__BVH_FMA
    return fmaf(a, b, c);
#else
    return a * b + c;
#endif
}

/* Per-ray constants of the watertight test and of the slab test. */
typedef struct lightvec__ray {
    float org[3], dir[3], inv[3];
    int kx, ky, kz;          /* dir[kz] has the largest magnitude */
    float sx, sy, sz;        /* shear that maps dir to +z */
    float nsx, nsy;          /* -sx, -sy */
    int near[3];             /* box row offset (in floats) of the entry plane per axis; far = near ^ WIDTH */
#if LIGHTVEC__SIMD
    lightvec__f4 org4[3], inv4[3], nsx4, nsy4, sz4;
#endif
} lightvec__ray;

static void lightvec__ray_setup(lightvec__ray *r, const float org[3], const float dir[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        /* a zero component would give 0 * inf = NaN in the slab test */
        float d = dir[k];
        if (fabsf(d) < 1e-30f) d = d < 0.0f ? -1e-30f : 1e-30f;
        r->org[k] = org[k];
        r->dir[k] = dir[k];
        r->inv[k] = 1.0f / d;
        r->near[k] = 2 * LIGHTVEC__BVH_WIDTH * k + (r->inv[k] < 0.0f ? LIGHTVEC__BVH_WIDTH : 0);
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
#if LIGHTVEC__SIMD
    for (k = 0; k < 3; k++) {
        r->org4[k] = lightvec__f4_set(r->org[k]);
        r->inv4[k] = lightvec__f4_set(r->inv[k]);
    }
    r->nsx4 = lightvec__f4_set(r->nsx);
    r->nsy4 = lightvec__f4_set(r->nsy);
    r->sz4 = lightvec__f4_set(r->sz);
#endif
}

/* Entry distances t[i] of the ray into a node's child boxes, clipped to
   [tmin, tmax]; returns the mask of the children it enters. */
static unsigned lightvec__node_hits_scalar(const lightvec__ray *r, const lightvec__bvh_node *n, float tmin, float tmax,
                                         float t[LIGHTVEC__BVH_WIDTH])
{
    const float *box = n->box[0];
    unsigned mask = 0;
    int i;
    for (i = 0; i < LIGHTVEC__BVH_WIDTH; i++) {
        float nx = (box[r->near[0] + i] - r->org[0]) * r->inv[0];
        float ny = (box[r->near[1] + i] - r->org[1]) * r->inv[1];
        float nz = (box[r->near[2] + i] - r->org[2]) * r->inv[2];
        float fx = (box[(r->near[0] ^ LIGHTVEC__BVH_WIDTH) + i] - r->org[0]) * r->inv[0];
        float fy = (box[(r->near[1] ^ LIGHTVEC__BVH_WIDTH) + i] - r->org[1]) * r->inv[1];
        float fz = (box[(r->near[2] ^ LIGHTVEC__BVH_WIDTH) + i] - r->org[2]) * r->inv[2];
        float tn = lightvec__maxf(lightvec__maxf(nx, ny), lightvec__maxf(nz, tmin));
        float tf = lightvec__minf(lightvec__minf(fx, fy), lightvec__minf(fz, tmax)) * LIGHTVEC__BVH_ROUND_UP;
        t[i] = tn;
        if (tn <= tf) mask |= 1u << i;
    }
    return mask;
}

/* An edge function a * b - c * d. With FMA, Kahan's algorithm: within two
   ulp of the exact value, so its sign is exact. Without, the two rounded
   products: the sign is exact or the value zero (Woop et al.), and a zero
   is computed again exactly in double by lightvec__bvh_edges_double. */
static float lightvec__bvh_det2(float a, float b, float c, float d)
{
#if LIGHTVEC__BVH_FMA
    float w = c * d;
    return fmaf(a, b, -w) - fmaf(c, d, -w);
#else
    return a * b - c * d;
#endif
}

/* The edge functions u, v, w exactly (products of floats are exact in
   double) and rounded once. */
static void lightvec__bvh_edges_double(float ax, float ay, float bx, float by, float cx, float cy, float e[3])
{
    e[0] = (float)((double)cx * by - (double)cy * bx);
    e[1] = (float)((double)ax * cy - (double)ay * cx);
    e[2] = (float)((double)bx * ay - (double)by * ax);
}

/* Watertight ray/triangle test (Woop, Benthin, Wald 2013): edge functions in
   a sheared space where the ray is the +z axis; an edge shared by two
   triangles is never missed by both. Updates *hit when closer than hit->t;
   returns 1 then. */
static int lightvec__leaf_hit_scalar(const lightvec__ray *r, const lightvec__bvh_tris *b, float tmin, lightvec__hit *hit)
{
    int i, found = 0;
    for (i = 0; i < 4; i++) {
        float ax = b->v[r->kx][i] - r->org[r->kx], ay = b->v[r->ky][i] - r->org[r->ky], az = b->v[r->kz][i] - r->org[r->kz];
        float bx = b->v[3 + r->kx][i] - r->org[r->kx], by = b->v[3 + r->ky][i] - r->org[r->ky], bz = b->v[3 + r->kz][i] - r->org[r->kz];
        float cx = b->v[6 + r->kx][i] - r->org[r->kx], cy = b->v[6 + r->ky][i] - r->org[r->ky], cz = b->v[6 + r->kz][i] - r->org[r->kz];
        float u, v, w, det, inv_det, t;
        ax = lightvec__bvh_madd(r->nsx, az, ax); ay = lightvec__bvh_madd(r->nsy, az, ay);
        bx = lightvec__bvh_madd(r->nsx, bz, bx); by = lightvec__bvh_madd(r->nsy, bz, by);
        cx = lightvec__bvh_madd(r->nsx, cz, cx); cy = lightvec__bvh_madd(r->nsy, cz, cy);
        u = lightvec__bvh_det2(cx, by, cy, bx);
        v = lightvec__bvh_det2(ax, cy, ay, cx);
        w = lightvec__bvh_det2(bx, ay, by, ax);
        if (!LIGHTVEC__BVH_FMA && (u == 0.0f || v == 0.0f || w == 0.0f)) {
            float e[3];
            lightvec__bvh_edges_double(ax, ay, bx, by, cx, cy, e);
            u = e[0]; v = e[1]; w = e[2];
        }
        if ((u < 0.0f || v < 0.0f || w < 0.0f) && (0.0f < u || 0.0f < v || 0.0f < w)) continue;
        det = u + v + w;
        if (det == 0.0f) continue;
        inv_det = 1.0f / det;
        u = u * inv_det; v = v * inv_det; w = w * inv_det;   /* barycentrics first: u * az underflows at 1e-13 m */
        t = lightvec__bvh_madd(u, az, lightvec__bvh_madd(v, bz, w * cz)) * r->sz;
        if (!(tmin < t && t < hit->t)) continue;
        hit->t = t;
        hit->u = v;
        hit->v = w;
        hit->tri = b->id[i];
        found = 1;
    }
    return found;
}

#if LIGHTVEC__SIMD
/* lightvec__node_hits_scalar four lanes at a time. */
static unsigned lightvec__node_hits_simd(const lightvec__ray *r, const lightvec__bvh_node *n, float tmin, float tmax,
                                       float t[LIGHTVEC__BVH_WIDTH])
{
    const lightvec__f4 lo = lightvec__f4_set(tmin), hi = lightvec__f4_set(tmax), up = lightvec__f4_set(LIGHTVEC__BVH_ROUND_UP);
    unsigned mask = 0;
    int i;
    for (i = 0; i < LIGHTVEC__BVH_WIDTH; i += 4) {
        const float *box = n->box[0] + i;
        lightvec__f4 nx = lightvec__f4_mul(lightvec__f4_sub(lightvec__f4_load(box + r->near[0]), r->org4[0]), r->inv4[0]);
        lightvec__f4 ny = lightvec__f4_mul(lightvec__f4_sub(lightvec__f4_load(box + r->near[1]), r->org4[1]), r->inv4[1]);
        lightvec__f4 nz = lightvec__f4_mul(lightvec__f4_sub(lightvec__f4_load(box + r->near[2]), r->org4[2]), r->inv4[2]);
        lightvec__f4 fx = lightvec__f4_mul(lightvec__f4_sub(lightvec__f4_load(box + (r->near[0] ^ LIGHTVEC__BVH_WIDTH)), r->org4[0]), r->inv4[0]);
        lightvec__f4 fy = lightvec__f4_mul(lightvec__f4_sub(lightvec__f4_load(box + (r->near[1] ^ LIGHTVEC__BVH_WIDTH)), r->org4[1]), r->inv4[1]);
        lightvec__f4 fz = lightvec__f4_mul(lightvec__f4_sub(lightvec__f4_load(box + (r->near[2] ^ LIGHTVEC__BVH_WIDTH)), r->org4[2]), r->inv4[2]);
        lightvec__f4 tn = lightvec__f4_max(lightvec__f4_max(nx, ny), lightvec__f4_max(nz, lo));
        lightvec__f4 tf = lightvec__f4_mul(lightvec__f4_min(lightvec__f4_min(fx, fy), lightvec__f4_min(fz, hi)), up);
        lightvec__f4_store(t + i, tn);
        mask |= lightvec__m4_bits(lightvec__f4_le(tn, tf)) << i;
    }
    return mask;
}

/* lightvec__leaf_hit_scalar on four lanes at once; the closest accepted lane
   (the first of equals, as the scalar loop keeps it) updates *hit. */
static int lightvec__leaf_hit_simd(const lightvec__ray *r, const lightvec__bvh_tris *b, float tmin, lightvec__hit *hit)
{
    const lightvec__f4 zero = lightvec__f4_set(0.0f);
    lightvec__f4 ax = lightvec__f4_sub(lightvec__f4_load(b->v[r->kx]), r->org4[r->kx]);
    lightvec__f4 ay = lightvec__f4_sub(lightvec__f4_load(b->v[r->ky]), r->org4[r->ky]);
    lightvec__f4 az = lightvec__f4_sub(lightvec__f4_load(b->v[r->kz]), r->org4[r->kz]);
    lightvec__f4 bx = lightvec__f4_sub(lightvec__f4_load(b->v[3 + r->kx]), r->org4[r->kx]);
    lightvec__f4 by = lightvec__f4_sub(lightvec__f4_load(b->v[3 + r->ky]), r->org4[r->ky]);
    lightvec__f4 bz = lightvec__f4_sub(lightvec__f4_load(b->v[3 + r->kz]), r->org4[r->kz]);
    lightvec__f4 cx = lightvec__f4_sub(lightvec__f4_load(b->v[6 + r->kx]), r->org4[r->kx]);
    lightvec__f4 cy = lightvec__f4_sub(lightvec__f4_load(b->v[6 + r->ky]), r->org4[r->ky]);
    lightvec__f4 cz = lightvec__f4_sub(lightvec__f4_load(b->v[6 + r->kz]), r->org4[r->kz]);
    lightvec__f4 u, v, w, det, inv_det, t;
    lightvec__m4 ok;
    float tl[4], vl[4], wl[4];
    unsigned mask;
    int i, best;
    ax = lightvec__f4_madd(r->nsx4, az, ax); ay = lightvec__f4_madd(r->nsy4, az, ay);
    bx = lightvec__f4_madd(r->nsx4, bz, bx); by = lightvec__f4_madd(r->nsy4, bz, by);
    cx = lightvec__f4_madd(r->nsx4, cz, cx); cy = lightvec__f4_madd(r->nsy4, cz, cy);
    u = lightvec__f4_det2(cx, by, cy, bx);
    v = lightvec__f4_det2(ax, cy, ay, cx);
    w = lightvec__f4_det2(bx, ay, by, ax);
    if (!LIGHTVEC__BVH_FMA && lightvec__m4_bits(lightvec__m4_or(lightvec__m4_or(lightvec__f4_eq(u, zero), lightvec__f4_eq(v, zero)),
                                      lightvec__f4_eq(w, zero)))) {
        float e[9][4];   /* the lanes with a zero edge function again in double */
        lightvec__f4_store(e[0], u); lightvec__f4_store(e[1], v); lightvec__f4_store(e[2], w);
        lightvec__f4_store(e[3], ax); lightvec__f4_store(e[4], ay); lightvec__f4_store(e[5], bx);
        lightvec__f4_store(e[6], by); lightvec__f4_store(e[7], cx); lightvec__f4_store(e[8], cy);
        for (i = 0; i < 4; i++) {
            float exact[3];
            if (e[0][i] != 0.0f && e[1][i] != 0.0f && e[2][i] != 0.0f) continue;
            lightvec__bvh_edges_double(e[3][i], e[4][i], e[5][i], e[6][i], e[7][i], e[8][i], exact);
            e[0][i] = exact[0]; e[1][i] = exact[1]; e[2][i] = exact[2];
        }
        u = lightvec__f4_load(e[0]); v = lightvec__f4_load(e[1]); w = lightvec__f4_load(e[2]);
    }
    ok = lightvec__m4_andnot(
        lightvec__m4_and(lightvec__m4_or(lightvec__m4_or(lightvec__f4_lt(u, zero), lightvec__f4_lt(v, zero)), lightvec__f4_lt(w, zero)),
                       lightvec__m4_or(lightvec__m4_or(lightvec__f4_lt(zero, u), lightvec__f4_lt(zero, v)), lightvec__f4_lt(zero, w))),
        lightvec__f4_eq(zero, zero));
    det = lightvec__f4_add(lightvec__f4_add(u, v), w);
    ok = lightvec__m4_andnot(lightvec__f4_eq(det, zero), ok);
    inv_det = lightvec__f4_div(lightvec__f4_set(1.0f), det);
    u = lightvec__f4_mul(u, inv_det); v = lightvec__f4_mul(v, inv_det); w = lightvec__f4_mul(w, inv_det);
    t = lightvec__f4_mul(lightvec__f4_madd(u, az, lightvec__f4_madd(v, bz, lightvec__f4_mul(w, cz))), r->sz4);
    ok = lightvec__m4_and(ok, lightvec__m4_and(lightvec__f4_lt(lightvec__f4_set(tmin), t), lightvec__f4_lt(t, lightvec__f4_set(hit->t))));
    mask = lightvec__m4_bits(ok);
    if (!mask) return 0;
    lightvec__f4_store(tl, t);
    for (best = -1, i = 0; i < 4; i++)
        if ((mask >> i & 1) && (best < 0 || tl[i] < tl[best])) best = i;
    lightvec__f4_store(vl, v); lightvec__f4_store(wl, w);
    hit->t = tl[best];
    hit->u = vl[best];
    hit->v = wl[best];
    hit->tri = b->id[best];
    return 1;
}
#endif

static unsigned lightvec__bvh_node_hits(const lightvec__bvh *bvh, const lightvec__ray *r, const lightvec__bvh_node *n,
                                      float tmin, float tmax, float t[LIGHTVEC__BVH_WIDTH])
{
#if LIGHTVEC__SIMD
    if (bvh->simd) return lightvec__node_hits_simd(r, n, tmin, tmax, t);
#endif
    (void)bvh;
    return lightvec__node_hits_scalar(r, n, tmin, tmax, t);
}

static int lightvec__bvh_leaf_hit(const lightvec__bvh *bvh, const lightvec__ray *r, const lightvec__bvh_tris *b, float tmin,
                                lightvec__hit *hit)
{
#if LIGHTVEC__SIMD
    if (bvh->simd) return lightvec__leaf_hit_simd(r, b, tmin, hit);
#endif
    (void)bvh;
    return lightvec__leaf_hit_scalar(r, b, tmin, hit);
}

typedef struct lightvec__bvh_entry { uint32_t ref; float t; } lightvec__bvh_entry;

/* Index of the highest set bit of a non-zero mask. */
static uint32_t lightvec__kd_last_bit(unsigned mask)
{
#if defined(__GNUC__) || defined(__clang__)
    return 31u - (uint32_t)__builtin_clz(mask);
#else
    uint32_t i = 31;
    while (!(mask >> i & 1)) i--;
    return i;
#endif
}

/* Index of the lowest set bit of a non-zero mask. */
static uint32_t lightvec__bvh_first_bit(unsigned mask)
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
static uint32_t lightvec__bvh_push_children(const lightvec__bvh_node *n, unsigned mask, const float t[LIGHTVEC__BVH_WIDTH],
                                          lightvec__bvh_entry *stack, uint32_t *top)
{
    lightvec__bvh_entry e[LIGHTVEC__BVH_WIDTH];
    uint32_t k = 0, i = lightvec__bvh_first_bit(mask), j, rest = mask & (mask - 1);
    if (!rest) return n->child[i];   /* one child: nothing to push */
    j = lightvec__bvh_first_bit(rest);
    if (!(rest & (rest - 1))) {      /* two children */
        uint32_t near = t[j] < t[i] ? j : i, far = near == i ? j : i;
        stack[*top].ref = n->child[far];
        stack[*top].t = t[far];
        (*top)++;
        return n->child[near];
    }
    for (; mask; mask &= mask - 1) {   /* insertion sort, stable */
        i = lightvec__bvh_first_bit(mask);
        for (j = k++; j > 0 && e[j - 1].t > t[i]; j--) e[j] = e[j - 1];
        e[j].ref = n->child[i];
        e[j].t = t[i];
    }
    while (--k) stack[(*top)++] = e[k];
    return e[0].ref;
}

/* Closest hit in (tmin, hit->t), or with any_hit the first hit found. */
static int lightvec__bvh_traverse(const lightvec__bvh *bvh, const lightvec__ray *r, float tmin, lightvec__hit *hit, int any_hit)
{
    lightvec__bvh_entry stack[LIGHTVEC__BVH_STACK];
    uint32_t top = 0, ref = bvh->root;
    if (bvh->tri_count == 0) return 0;   /* an empty tree: no root to enter */
    for (;;) {
        if (ref & LIGHTVEC__BVH_LEAF) {
            uint32_t b = (ref & ~LIGHTVEC__BVH_LEAF) >> 3, end = b + (ref & 7u) + 1;
            for (; b < end; b++)
                if (lightvec__bvh_leaf_hit(bvh, r, &bvh->blocks[b], tmin, hit) && any_hit) return 1;
        } else {
            float t[LIGHTVEC__BVH_WIDTH];
            const lightvec__bvh_node *n = &bvh->nodes[ref];
            unsigned mask = lightvec__bvh_node_hits(bvh, r, n, tmin, hit->t, t);
            if (mask) {
                ref = lightvec__bvh_push_children(n, mask, t, stack, &top);
                continue;
            }
        }
        do {   /* entries behind the closest hit are skipped */
            if (!top) return hit->tri != LIGHTVEC__NO_HIT;
            top--;
        } while (stack[top].t > hit->t * LIGHTVEC__BVH_ROUND_UP);
        ref = stack[top].ref;
    }
}

/* Closest hit in (tmin, tmax). Returns 1 and fills *hit, else hit->tri = LIGHTVEC__NO_HIT. */
static int lightvec__bvh_intersect(const lightvec__bvh *bvh, const float org[3], const float dir[3],
                                 float tmin, float tmax, lightvec__hit *hit)
{
    lightvec__ray r;
    lightvec__ray_setup(&r, org, dir);
    hit->t = tmax;
    hit->u = hit->v = 0.0f;
    hit->tri = LIGHTVEC__NO_HIT;
    return lightvec__bvh_traverse(bvh, &r, tmin, hit, 0);
}

/* Any hit in (tmin, tmax): for shadow rays. */
static int lightvec__bvh_occluded(const lightvec__bvh *bvh, const float org[3], const float dir[3],
                                float tmin, float tmax)
{
    lightvec__ray r;
    lightvec__hit hit;
    lightvec__ray_setup(&r, org, dir);
    hit.t = tmax;
    hit.u = hit.v = 0.0f;
    hit.tri = LIGHTVEC__NO_HIT;
    return lightvec__bvh_traverse(bvh, &r, tmin, &hit, 1);
}

/* ======================================================================
   5. CRC32 and little-endian byte streams
   A saved object is: magic (8 bytes), format version (u32), payload size
   (u64), payload, CRC32 of everything before it (u32). Values are written
   byte by byte in little-endian order, never as raw structs. A loader treats
   its input as hostile: it checks every count against the declared payload
   size before allocating, and the CRC at the end.
   ---------------------------------------------------------------------- */
/* In the declarations (public):

   typedef int (*lightvec_write_fn)(void *user, const void *bytes, size_t n); // 0 = ok
   typedef int (*lightvec_read_fn)(void *user, void *bytes, size_t n);        // 0 = all n bytes read
*/

/* CRC-32 (IEEE 802.3, reflected, as zlib and PNG). The table is built on the
   stack per stream: 256 entries, cheaper than one page of data. */
typedef struct lightvec__crc { uint32_t table[256]; uint32_t value; } lightvec__crc;

static void lightvec__crc_init(lightvec__crc *c)
{
    uint32_t i, k;
    for (i = 0; i < 256; i++) {
        uint32_t v = i;
        for (k = 0; k < 8; k++) v = (v & 1u) ? 0xEDB88320u ^ (v >> 1) : v >> 1;
        c->table[i] = v;
    }
    c->value = 0xFFFFFFFFu;
}
static void lightvec__crc_add(lightvec__crc *c, const void *bytes, size_t n)
{
    const unsigned char *p = (const unsigned char *)bytes;
    uint32_t v = c->value;
    while (n--) v = c->table[(v ^ *p++) & 0xFFu] ^ (v >> 8);
    c->value = v;
}
static uint32_t lightvec__crc_final(const lightvec__crc *c) { return c->value ^ 0xFFFFFFFFu; }

typedef struct lightvec__writer {
    lightvec_write_fn write;
    void *user;
    lightvec__crc crc;
    int failed;        /* a write callback failed: LIGHTVEC_ERROR_IO */
} lightvec__writer;

static void lightvec__put(lightvec__writer *w, const void *bytes, size_t n)
{
    if (w->failed || n == 0) return;
    lightvec__crc_add(&w->crc, bytes, n);
    if (w->write(w->user, bytes, n) != 0) w->failed = 1;
}
static void lightvec__put_u32(lightvec__writer *w, uint32_t v)
{
    unsigned char b[4];
    b[0] = (unsigned char)v; b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16); b[3] = (unsigned char)(v >> 24);
    lightvec__put(w, b, 4);
}
static void lightvec__put_u64(lightvec__writer *w, uint64_t v)
{
    lightvec__put_u32(w, (uint32_t)v);
    lightvec__put_u32(w, (uint32_t)(v >> 32));
}
static void lightvec__put_f32(lightvec__writer *w, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    lightvec__put_u32(w, v);
}
static void lightvec__put_f32_array(lightvec__writer *w, const float *f, size_t n)
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
        lightvec__put(w, buf, 4 * m);
        i += m;
    }
}

typedef struct lightvec__reader {
    lightvec_read_fn read;
    void *user;
    lightvec__crc crc;
    uint64_t remaining;  /* payload bytes not yet read, from the header */
    int failed;          /* short read or a size past the payload: corrupt */
} lightvec__reader;

static void lightvec__get(lightvec__reader *r, void *bytes, size_t n)
{
    if (r->failed) { memset(bytes, 0, n); return; }
    if (n > r->remaining || r->read(r->user, bytes, n) != 0) {
        r->failed = 1;
        memset(bytes, 0, n);
        return;
    }
    r->remaining -= n;
    lightvec__crc_add(&r->crc, bytes, n);
}
static uint32_t lightvec__get_u32(lightvec__reader *r)
{
    unsigned char b[4];
    lightvec__get(r, b, 4);
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}
static uint64_t lightvec__get_u64(lightvec__reader *r)
{
    uint64_t lo = lightvec__get_u32(r);
    return lo | ((uint64_t)lightvec__get_u32(r) << 32);
}
static float lightvec__get_f32(lightvec__reader *r)
{
    uint32_t v = lightvec__get_u32(r);
    float f;
    memcpy(&f, &v, 4);
    return f;
}
/* True when count items of item_bytes each can still be in the payload:
   call before allocating anything sized by a count read from the input. */
static int lightvec__can_hold(lightvec__reader *r, uint64_t count, uint64_t item_bytes)
{
    if (item_bytes && count > r->remaining / item_bytes) { r->failed = 1; return 0; }
    return !r->failed;
}

/* Memory-buffer streams behind the public save_to_memory/load_from_memory. */
typedef struct lightvec__membuf {
    unsigned char *data;
    size_t size, capacity, pos;
    const lightvec_allocator *a;
} lightvec__membuf;

static int lightvec__membuf_write(void *user, const void *bytes, size_t n)
{
    lightvec__membuf *m = (lightvec__membuf *)user;
    if (n > m->capacity - m->size) {
        size_t cap = m->capacity ? m->capacity : 4096;
        unsigned char *p;
        while (cap - m->size < n) {
            if (cap > SIZE_MAX / 2) return -1;
            cap *= 2;
        }
        p = (unsigned char *)lightvec__alloc(m->a, cap);
        if (!p) return -1;
        if (m->size) memcpy(p, m->data, m->size);
        lightvec__free(m->a, m->data);
        m->data = p;
        m->capacity = cap;
    }
    memcpy(m->data + m->size, bytes, n);
    m->size += n;
    return 0;
}

static int lightvec__membuf_read(void *user, void *bytes, size_t n)
{
    lightvec__membuf *m = (lightvec__membuf *)user;
    if (n > m->size - m->pos) return -1;
    memcpy(bytes, m->data + m->pos, n);
    m->pos += n;
    return 0;
}


/* ======================================================================
   7. jobs: the caller's parallel_for, or a serial loop
   ---------------------------------------------------------------------- */
/* In the declarations (public):

   typedef void (*lightvec_job_fn)(void *ctx, uint32_t index);
   // in the desc:
   void (*parallel_for)(void *user, lightvec_job_fn job, void *ctx, uint32_t count);
   void *parallel_user;
   int (*progress)(void *user, uint64_t done, uint64_t total);   // non-zero cancels
   void *progress_user;

   Long builds run their jobs in batches and call progress between batches,
   from the calling thread, so a callback never runs concurrently with itself. */
static void lightvec__run_jobs(void (*parallel_for)(void *, lightvec_job_fn, void *, uint32_t), void *user,
                         lightvec_job_fn job, void *ctx, uint32_t count)
{
    uint32_t i;
    if (count == 0) return;
    if (parallel_for) { parallel_for(user, job, ctx, count); return; }
    for (i = 0; i < count; i++) job(ctx, i);
}

/* ======================================================================
   8. atomics: acquire/release publication and sequentially consistent
   reader counters (see THREADS in the documentation)
   ---------------------------------------------------------------------- */
#if defined(__GNUC__) || defined(__clang__)
#define LIGHTVEC__PREFETCH(p) __builtin_prefetch(p)
static uint32_t lightvec__load_u32(const uint32_t *p) { return __atomic_load_n(p, __ATOMIC_ACQUIRE); }
static void lightvec__store_u32(uint32_t *p, uint32_t v) { __atomic_store_n(p, v, __ATOMIC_RELEASE); }
static void *lightvec__load_ptr(void *const *p) { return __atomic_load_n(p, __ATOMIC_ACQUIRE); }
static void lightvec__store_ptr(void **p, void *v) { __atomic_store_n(p, v, __ATOMIC_RELEASE); }
static uint32_t lightvec__load_sc(const uint32_t *p) { return __atomic_load_n(p, __ATOMIC_SEQ_CST); }
static void lightvec__store_sc(uint32_t *p, uint32_t v) { __atomic_store_n(p, v, __ATOMIC_SEQ_CST); }
static void lightvec__add_sc(uint32_t *p, uint32_t v) { (void)__atomic_add_fetch(p, v, __ATOMIC_SEQ_CST); }
static float lightvec__load_f32(const float *p) { float v; __atomic_load(p, &v, __ATOMIC_RELAXED); return v; }
static void lightvec__store_f32(float *p, float v) { __atomic_store(p, &v, __ATOMIC_RELAXED); }
#elif defined(_MSC_VER)
#include <intrin.h>
#define LIGHTVEC__PREFETCH(p) ((void)(p))
/* Interlocked operations are full barriers: stronger than needed, still correct. */
static uint32_t lightvec__load_sc(const uint32_t *p) { return (uint32_t)_InterlockedOr((volatile long *)p, 0); }
static void lightvec__store_sc(uint32_t *p, uint32_t v) { (void)_InterlockedExchange((volatile long *)p, (long)v); }
static void lightvec__add_sc(uint32_t *p, uint32_t v) { (void)_InterlockedExchangeAdd((volatile long *)p, (long)v); }
static uint32_t lightvec__load_u32(const uint32_t *p) { return lightvec__load_sc(p); }
static void lightvec__store_u32(uint32_t *p, uint32_t v) { lightvec__store_sc(p, v); }
static void *lightvec__load_ptr(void *const *p)
{
    return _InterlockedCompareExchangePointer((void *volatile *)p, NULL, NULL);
}
static void lightvec__store_ptr(void **p, void *v) { (void)_InterlockedExchangePointer((void *volatile *)p, v); }
/* aligned 32-bit volatile accesses are single instructions: atomic */
static float lightvec__load_f32(const float *p) { return *(const volatile float *)p; }
static void lightvec__store_f32(float *p, float v) { *(volatile float *)p = v; }
#else
#define LIGHTVEC__PREFETCH(p) ((void)(p))
/* No atomics known for this compiler: single-threaded use only. */
static uint32_t lightvec__load_u32(const uint32_t *p) { return *p; }
static void lightvec__store_u32(uint32_t *p, uint32_t v) { *p = v; }
static void *lightvec__load_ptr(void *const *p) { return *p; }
static void lightvec__store_ptr(void **p, void *v) { *p = v; }
static uint32_t lightvec__load_sc(const uint32_t *p) { return *p; }
static void lightvec__store_sc(uint32_t *p, uint32_t v) { *p = v; }
static void lightvec__add_sc(uint32_t *p, uint32_t v) { *p += v; }
static float lightvec__load_f32(const float *p) { return *p; }
static void lightvec__store_f32(float *p, float v) { *p = v; }
#endif

/* ======================================================================
   9. small helpers: luminance, validation, logging, BRDF
   ---------------------------------------------------------------------- */
#define LIGHTVEC__PI 3.14159265358979323846
#define LIGHTVEC__TWO_PI 6.28318530717958647692
#define LIGHTVEC__FAR 1e30f           /* distance of an escaped ray */
#define LIGHTVEC__MAX_STRATA_THETA 256u
#define LIGHTVEC__MAX_STRATA_PHI 512u
#define LIGHTVEC__MAX_BOUNCES 64u
#define LIGHTVEC__MAX_LIGHT_SAMPLES 4096u
#define LIGHTVEC__MAX_FACE_DEPTH 12u

/* Rec. 709 luminance: the scalar weight of eq. 2 and of the criteria. */
static float lightvec__lumf(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* A message with two integers for the optional logger. */
static void lightvec__logf(lightvec_log_fn log, void *user, const char *fmt, long long a, long long b)
{
    char buf[256];
    if (!log) return;
    snprintf(buf, sizeof buf, fmt, a, b);
    log(user, buf);
}

/* A unit vector from a finite non-zero one, else 0. The length is taken in
   double: the squares of float components neither underflow nor overflow
   there, so a vector of length 1e-20 (whose float squares are subnormal)
   also comes out unit to float precision. */
static int lightvec__unit(const float *in, lightvec__vec3 *out)
{
    double x, y, z, l;
    if (!in || !lightvec__finite3(in)) return 0;
    x = in[0];
    y = in[1];
    z = in[2];
    l = sqrt(x * x + y * y + z * z);
    if (!(l > 1e-20)) return 0;
    /* a vector already unit to float precision is kept as it is, so that
       normalising twice (insert, save, load) changes nothing */
    *out = fabs(l - 1.0) <= 4e-7 ? lightvec__v3_load(in) : lightvec__v3((float)(x / l), (float)(y / l), (float)(z / l));
    return 1;
}

static int lightvec__finite_nonneg_n(const float *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(v[i]) || v[i] < 0.0f) return 0;
    return 1;
}

static int lightvec__finite_nonneg(const float *v, int n) { return lightvec__finite_nonneg_n(v, (size_t)n); }

static int lightvec__material_valid(const lightvec_material *m)
{
    return lightvec__finite_nonneg(m->diffuse, 3) && lightvec__finite_nonneg(m->specular, 3) &&
           lightvec__finite_nonneg(m->emission, 3) && isfinite(m->exponent) && m->exponent >= 0.0f &&
           m->exponent <= 1e6f && lightvec__finite_nonneg(m->transmittance, 3) && m->transmittance[0] <= 1.0f &&
           m->transmittance[1] <= 1.0f && m->transmittance[2] <= 1.0f;
}

/* A double as a float, saturated at FLT_MAX: a magnitude computed in double
   stays finite when stored. */
static float lightvec__to_float(double v)
{
    if (v > (double)FLT_MAX) return FLT_MAX;
    if (v < -(double)FLT_MAX) return -FLT_MAX;
    return (float)v;
}

/* cos alpha of the Phong lobe: the mirror image of wi about n, dotted with
   wo (symmetric in wi and wo). In double: a float cos alpha raised to a high
   exponent loses exponent * 1e-7 of relative precision. */
static double lightvec__mirror_cos(lightvec__vec3 n, lightvec__vec3 wi, lightvec__vec3 wo)
{
    double ci = (double)n.x * wi.x + (double)n.y * wi.y + (double)n.z * wi.z;
    return (2.0 * ci * n.x - wi.x) * wo.x + (2.0 * ci * n.y - wi.y) * wo.y + (2.0 * ci * n.z - wi.z) * wo.z;
}

/* The normalized Phong lobe per unit specular reflectance:
   (exponent + 2) / (2 pi) max(0, cos alpha)^exponent. */
static double lightvec__lobe(double exponent, double cos_alpha)
{
    return cos_alpha > 0.0 ? (exponent + 2.0) / LIGHTVEC__TWO_PI * pow(cos_alpha, exponent) : 0.0;
}

static int lightvec__glossy(const lightvec_material *m)
{
    return m->specular[0] > 0.0f || m->specular[1] > 0.0f || m->specular[2] > 0.0f;
}

/* f_r(wi -> wo) of Lambert + normalized Phong; all vectors unit. */
static void lightvec__brdf_unit(const lightvec_material *m, lightvec__vec3 n, lightvec__vec3 wi, lightvec__vec3 wo,
                                float f[3])
{
    double lobe = lightvec__glossy(m) ? lightvec__lobe(m->exponent, lightvec__mirror_cos(n, wi, wo)) : 0.0;
    int c;
    for (c = 0; c < 3; c++) f[c] = (float)(m->diffuse[c] / LIGHTVEC__PI + m->specular[c] * lobe);
}

LIGHTVEC_API void lightvec_brdf(const lightvec_material *m, const float normal[3], const float wi[3],
                                const float wo[3], float f[3])
{
    lightvec__vec3 n, i, o;
    if (!f) return;
    f[0] = f[1] = f[2] = 0.0f;
    if (!m || !lightvec__unit(normal, &n) || !lightvec__unit(wi, &i) || !lightvec__unit(wo, &o)) return;
    lightvec__brdf_unit(m, n, i, o, f);
}

/* The view change a glossy record tolerates (GLOSSY SURFACES in the
   documentation derives it): the lobe's angular radius
   s = acos(exp(-1 / (2 n))), where cos^n falls to e^-1/2 of its peak (for
   large n, the standard deviation 1 / sqrt(n) of the Gaussian that cos^n
   approaches), times sqrt(2 eps / phi(1)) = LIGHTVEC__LOBE_SPAN. */
#define LIGHTVEC__GLOSSY_ERROR 0.1           /* eps: first-order error / contrast under the lobe */
#define LIGHTVEC__LOBE_SPAN 0.90915          /* sqrt(2 eps / phi(1)), phi(1) = 0.24197 the normal density at 1 */
#define LIGHTVEC__MIN_DIRECTION_ANGLE 0.1    /* degrees */

LIGHTVEC_API float lightvec_direction_angle(float exponent)
{
    double s, a;
    if (!(exponent > 0.0f)) return 180.0f; /* a constant lobe does not depend on the viewer (NaN too) */
    s = acos(exp(-1.0 / (2.0 * (double)exponent)));
    a = LIGHTVEC__LOBE_SPAN * s * (180.0 / LIGHTVEC__PI);
    if (!(a > LIGHTVEC__MIN_DIRECTION_ANGLE)) a = LIGHTVEC__MIN_DIRECTION_ANGLE;
    return a < 180.0 ? (float)a : 180.0f;
}

#define LIGHTVEC__MIN_GLOSSY_COS 1e-3f  /* D_g at least this high above the horizon */

/* The glossy light vector of a point (normal n) seen from w whose lobe
   (exponent) reflects g per unit specular reflectance. D_g is the mirror
   direction of w, where the lobe peaks (raised to LIGHTVEC__MIN_GLOSSY_COS
   above the horizon when the viewer grazes): eq. 3 then divides by the
   largest lobe value there is, and M_g stays of the order of g. M_g is
   computed in double from D_g as stored, so that lightvec_radiance gives back
   specular * g to float rounding. A viewer below the horizon sees no glossy
   light. */
static void lightvec__glossy_vector(lightvec__vec3 n, lightvec__vec3 w, double exponent, const double g[3],
                                    lightvec_vector *v)
{
    float c = lightvec__dot(n, w);
    lightvec__vec3 d;
    double denom;
    int k;
    memset(v->glossy_direction, 0, sizeof v->glossy_direction);
    memset(v->glossy_magnitude, 0, sizeof v->glossy_magnitude);
    if (!(c > 0.0f)) return;
    d = lightvec__sub(lightvec__scale(n, 2.0f * c), w);
    if (c < LIGHTVEC__MIN_GLOSSY_COS) d = lightvec__add(d, lightvec__scale(n, LIGHTVEC__MIN_GLOSSY_COS - c));
    d = lightvec__normalize(d);
    v->glossy_direction[0] = d.x; v->glossy_direction[1] = d.y; v->glossy_direction[2] = d.z;
    denom = lightvec__lobe(exponent, lightvec__mirror_cos(n, d, w)) * lightvec__dot(n, d);
    if (!(denom > 0.0)) return;
    for (k = 0; k < 3; k++) v->glossy_magnitude[k] = lightvec__to_float(g[k] / denom);
}

/* L = M rho_d / pi cos(n, D) + M_g f_s(D_g -> wo) cos(n, D_g): the radiance a
   pair of light vectors sends toward wo. With outgoing NULL the surface is
   taken as Lambertian (the diffuse vector only). */
LIGHTVEC_API void lightvec_radiance(const lightvec_material *m, const float normal[3], const float *outgoing,
                                    const lightvec_vector *v, float rgb[3])
{
    lightvec__vec3 n, d, o;
    double sum[3] = { 0.0, 0.0, 0.0 }, cos_d, lobe;
    int c;
    if (!rgb) return;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (!m || !v || !lightvec__unit(normal, &n)) return;
    if (lightvec__unit(v->direction, &d) && (cos_d = lightvec__dot(n, d)) > 0.0)
        for (c = 0; c < 3; c++) sum[c] += v->magnitude[c] * (m->diffuse[c] / LIGHTVEC__PI) * cos_d;
    if (outgoing && lightvec__glossy(m) && lightvec__unit(outgoing, &o) && lightvec__unit(v->glossy_direction, &d) &&
        (cos_d = lightvec__dot(n, d)) > 0.0) {
        lobe = lightvec__lobe(m->exponent, lightvec__mirror_cos(n, d, o));
        for (c = 0; c < 3; c++) sum[c] += v->glossy_magnitude[c] * (m->specular[c] * lobe) * cos_d;
    }
    for (c = 0; c < 3; c++) rgb[c] = lightvec__to_float(sum[c]);
}

LIGHTVEC_API float lightvec_priority(float rc_priority, float W)
{
    /* 4.3: the render-cache priority times 1/W; a pixel whose vector had no
       valid neighbour (W = 0) gets the highest priority. */
    if (!(W > 0.0f)) return LIGHTVEC_PRIORITY_MAX;
    {
        float p = rc_priority / W;
        return p < LIGHTVEC_PRIORITY_MAX ? p : LIGHTVEC_PRIORITY_MAX;
    }
}

/* ======================================================================
   10. scene and built-in renderer
   ---------------------------------------------------------------------- */
struct lightvec_scene {
    lightvec_allocator a;
    lightvec__bvh bvh;
    int use_bvh;
    lightvec_trace_fn trace;
    void *trace_user;
    uint32_t tri_count, degenerate_count;
    float *normals;                 /* unit geometric normal per triangle (0 if degenerate) */
    uint32_t *tri_material;
    lightvec_material *materials;
    uint32_t material_count;
    uint32_t emitter_count;
    float *emit_verts;              /* 9 per emitter */
    float *emit_normal;             /* 3 per emitter */
    float *emit_cdf;                /* cumulative selection probability, last = 1 */
    float *emit_inv_pdf;            /* area / selection probability: 1 / pdf per unit area */
    float *emit_bound;              /* LIGHTVEC__BOUND per emitter (lightvec__emitter_bound) */
    float *emit_area;
    uint32_t *emit_material;
    float lo[3], hi[3];
    float eps;                      /* ray origin offset */
    int has_glass;                  /* some material transmits */
    int has_sky;                    /* escaping rays bring light: a map, or a sky above 0 */
    float sky[3];
    float *environment;             /* the copied map, or NULL */
    uint32_t env_width, env_height;
};

/* No map, or a map of sensible size whose texels are finite and >= 0. */
static int lightvec__environment_valid(const lightvec_scene_desc *d)
{
    size_t n;
    if (!d->environment) return 1;
    if (d->environment_width < 1 || d->environment_height < 1 || d->environment_width > LIGHTVEC_MAX_ENVIRONMENT_SIZE ||
        d->environment_height > LIGHTVEC_MAX_ENVIRONMENT_SIZE)
        return 0;
    if (d->environment_height > (size_t)-1 / (3 * sizeof(float)) / d->environment_width) return 0; /* 32-bit size_t */
    n = 3 * (size_t)d->environment_width * d->environment_height;
    return lightvec__finite_nonneg_n(d->environment, n);
}

static lightvec_result lightvec__scene_validate(const lightvec_scene_desc *d)
{
    uint32_t i;
    uint64_t k, index_count;
    size_t stride;
    if (!d->positions || !d->indices || !d->materials || d->vertex_count == 0 || d->triangle_count == 0 ||
        d->material_count == 0)
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    if (!lightvec__allocator_valid(&d->allocator)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    stride = d->stride ? d->stride : 3 * sizeof(float);
    if (stride < 3 * sizeof(float) || stride % sizeof(float)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    /* 3 * triangle_count is counted in 64 bits: in 32 it wraps past 0x55555555 */
    if (d->triangle_count > LIGHTVEC_MAX_TRIANGLES) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    index_count = 3u * (uint64_t)d->triangle_count;
    if (index_count > (uint64_t)SIZE_MAX / (9u * sizeof(float))) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < d->vertex_count; i++) {
        const float *p = (const float *)((const char *)d->positions + (size_t)i * stride);
        if (!lightvec__finite3(p)) {
            lightvec__logf(d->log, d->log_user, "lightvec: vertex %lld of %lld is not finite", (long long)i,
                           (long long)d->vertex_count);
            return LIGHTVEC_ERROR_INVALID_ARGUMENT;
        }
    }
    for (k = 0; k < index_count; k++)
        if (d->indices[k] >= d->vertex_count) {
            lightvec__logf(d->log, d->log_user, "lightvec: index %lld out of range (%lld vertices)",
                           (long long)k, (long long)d->vertex_count);
            return LIGHTVEC_ERROR_INVALID_ARGUMENT;
        }
    if (d->material_ids)
        for (i = 0; i < d->triangle_count; i++)
            if (d->material_ids[i] >= d->material_count) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    for (i = 0; i < d->material_count; i++)
        if (!lightvec__material_valid(&d->materials[i])) {
            lightvec__logf(d->log, d->log_user,
                           "lightvec: material %lld of %lld has a negative or non-finite value (or transmittance > 1)",
                           (long long)i, (long long)d->material_count);
            return LIGHTVEC_ERROR_INVALID_ARGUMENT;
        }
    if (!lightvec__finite_nonneg(d->sky, 3) || !lightvec__environment_valid(d)) {
        lightvec__logf(d->log, d->log_user, "lightvec: sky negative or non-finite, or a bad environment map (%lld x %lld)",
                       (long long)d->environment_width, (long long)d->environment_height);
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    }
    return LIGHTVEC_OK;
}

/* The bounds of an emitter triangle (verts: 9 floats, unit normal nl)
   that its importance needs (lightvec__emitter_importance), in
   LIGHTVEC__BOUND floats: the sphere about its centroid through its
   farthest corner, its power up to a constant (area times the luminance
   of its emission), and its plane (normal, offset). */
#define LIGHTVEC__BOUND 9
static void lightvec__emitter_bound(const float *verts, lightvec__vec3 nl, double power, float out[LIGHTVEC__BOUND])
{
    float r2 = 0.0f;
    int k, v;
    for (k = 0; k < 3; k++) out[k] = (verts[k] + verts[3 + k] + verts[6 + k]) / 3.0f;
    for (v = 0; v < 3; v++) {
        float d2 = 0.0f;
        for (k = 0; k < 3; k++) d2 += (verts[3 * v + k] - out[k]) * (verts[3 * v + k] - out[k]);
        r2 = lightvec__maxf(r2, d2);
    }
    out[3] = sqrtf(r2);
    out[4] = (float)power;
    out[5] = nl.x;
    out[6] = nl.y;
    out[7] = nl.z;
    out[8] = out[0] * nl.x + out[1] * nl.y + out[2] * nl.z;
}

/* Normals, materials, bounds; the emitter list with selection proportional
   to area times emitted luminance (lightvec_gather_direct) and each
   emitter's bounds (a gather hit's light samples). */
static int lightvec__scene_fill(lightvec_scene *s, const lightvec_scene_desc *d, const lightvec__mesh_view *m)
{
    uint32_t i, e = 0;
    double total = 0.0, acc = 0.0;
    float diag;
    lightvec__box_empty(s->lo, s->hi);
    for (i = 0; i < d->triangle_count; i++) {
        const float *p0 = lightvec__vertex(m, d->indices[(size_t)3 * i]);
        const float *p1 = lightvec__vertex(m, d->indices[(size_t)3 * i + 1]);
        const float *p2 = lightvec__vertex(m, d->indices[(size_t)3 * i + 2]);
        lightvec__vec3 c = lightvec__cross(lightvec__sub(lightvec__v3_load(p1), lightvec__v3_load(p0)),
                                           lightvec__sub(lightvec__v3_load(p2), lightvec__v3_load(p0)));
        uint32_t mat = d->material_ids ? d->material_ids[i] : 0u;
        lightvec__vec3 n = lightvec__normalize(c);
        if (lightvec__dot(c, c) == 0.0f || !isfinite(n.x)) n = lightvec__v3(0.0f, 0.0f, 0.0f);
        s->normals[(size_t)3 * i] = n.x; s->normals[(size_t)3 * i + 1] = n.y; s->normals[(size_t)3 * i + 2] = n.z;
        s->tri_material[i] = mat;
        lightvec__box_grow(s->lo, s->hi, p0, p0);
        lightvec__box_grow(s->lo, s->hi, p1, p1);
        lightvec__box_grow(s->lo, s->hi, p2, p2);
        if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) continue;
        if (lightvec__lumf(d->materials[mat].emission) > 0.0f) {
            double area = 0.5 * (double)lightvec__length(c);
            memcpy(s->emit_verts + (size_t)9 * e, p0, 3 * sizeof(float));
            memcpy(s->emit_verts + (size_t)9 * e + 3, p1, 3 * sizeof(float));
            memcpy(s->emit_verts + (size_t)9 * e + 6, p2, 3 * sizeof(float));
            s->emit_normal[(size_t)3 * e] = n.x; s->emit_normal[(size_t)3 * e + 1] = n.y; s->emit_normal[(size_t)3 * e + 2] = n.z;
            s->emit_material[e] = mat;
            s->emit_cdf[e] = (float)(area * lightvec__lumf(d->materials[mat].emission)); /* weight for now */
            s->emit_inv_pdf[e] = (float)area;
            s->emit_area[e] = (float)area;
            lightvec__emitter_bound(s->emit_verts + (size_t)9 * e, n, s->emit_cdf[e], s->emit_bound + (size_t)LIGHTVEC__BOUND * e);
            total += s->emit_cdf[e];
            e++;
        }
    }
    s->emitter_count = e;
    for (i = 0; i < e; i++) {
        double w = s->emit_cdf[i] / total;
        acc += w;
        s->emit_cdf[i] = (float)acc;
        s->emit_inv_pdf[i] = (float)(s->emit_inv_pdf[i] / w); /* area / P(select) */
    }
    if (e) s->emit_cdf[e - 1] = 1.0f;
    diag = lightvec__length(lightvec__sub(lightvec__v3_load(s->hi), lightvec__v3_load(s->lo)));
    s->eps = diag > 0.0f ? 1e-4f * diag : 1e-6f;
    return 0;
}

/* The sky and the glass flag: the map copied (the caller's may go). Returns
   -1 when the copy cannot get memory. */
static int lightvec__scene_sky(lightvec_scene *s, const lightvec_scene_desc *d)
{
    uint32_t i;
    for (i = 0; i < d->material_count; i++) {
        const float *t = d->materials[i].transmittance;
        s->has_glass |= t[0] > 0.0f || t[1] > 0.0f || t[2] > 0.0f;
    }
    memcpy(s->sky, d->sky, sizeof s->sky);
    s->has_sky = d->environment || d->sky[0] > 0.0f || d->sky[1] > 0.0f || d->sky[2] > 0.0f;
    if (!d->environment) return 0;
    s->env_width = d->environment_width;
    s->env_height = d->environment_height;
    s->environment = (float *)lightvec__alloc_array(&s->a, (size_t)s->env_width * s->env_height, 3 * sizeof(float));
    if (!s->environment) return -1;
    memcpy(s->environment, d->environment, (size_t)s->env_width * s->env_height * 3 * sizeof(float));
    return 0;
}

LIGHTVEC_API lightvec_result lightvec_scene_create(const lightvec_scene_desc *desc, lightvec_scene **out)
{
    lightvec_scene *s;
    lightvec__mesh_view m;
    lightvec_result r;
    uint32_t n;
    if (!out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!desc) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    r = lightvec__scene_validate(desc);
    if (r != LIGHTVEC_OK) return r;
    s = (lightvec_scene *)lightvec__alloc(&desc->allocator, sizeof *s);
    if (!s) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    memset(s, 0, sizeof *s);
    s->a = desc->allocator;
    s->trace = desc->trace;
    s->trace_user = desc->trace_user;
    n = desc->triangle_count;
    s->tri_count = n;
    s->material_count = desc->material_count;
    s->normals = (float *)lightvec__alloc_array(&s->a, (size_t)n, 3 * sizeof(float));
    s->tri_material = (uint32_t *)lightvec__alloc_array(&s->a, (size_t)n, sizeof(uint32_t));
    s->materials = (lightvec_material *)lightvec__alloc_array(&s->a, desc->material_count, sizeof(lightvec_material));
    s->emit_verts = (float *)lightvec__alloc_array(&s->a, (size_t)n, 9 * sizeof(float));
    s->emit_normal = (float *)lightvec__alloc_array(&s->a, (size_t)n, 3 * sizeof(float));
    s->emit_cdf = (float *)lightvec__alloc_array(&s->a, (size_t)n, sizeof(float));
    s->emit_inv_pdf = (float *)lightvec__alloc_array(&s->a, (size_t)n, sizeof(float));
    s->emit_material = (uint32_t *)lightvec__alloc_array(&s->a, (size_t)n, sizeof(uint32_t));
    s->emit_bound = (float *)lightvec__alloc_array(&s->a, (size_t)n, LIGHTVEC__BOUND * sizeof(float));
    s->emit_area = (float *)lightvec__alloc_array(&s->a, (size_t)n, sizeof(float));
    if (!s->normals || !s->tri_material || !s->materials || !s->emit_verts || !s->emit_normal || !s->emit_cdf ||
        !s->emit_inv_pdf || !s->emit_material || !s->emit_bound || !s->emit_area) {
        lightvec_scene_destroy(s);
        return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    }
    memcpy(s->materials, desc->materials, desc->material_count * sizeof(lightvec_material));
    if (lightvec__scene_sky(s, desc) != 0) {
        lightvec_scene_destroy(s);
        return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    }
    m.positions = desc->positions;
    m.stride = desc->stride;
    m.indices = desc->indices;
    m.tri_count = n;
    lightvec__scene_fill(s, desc, &m);
    if (!s->trace) {
        if (lightvec__bvh_build(&s->bvh, &m, &s->a) != 0) {
            lightvec_scene_destroy(s);
            return LIGHTVEC_ERROR_OUT_OF_MEMORY;
        }
        s->use_bvh = 1;
        s->degenerate_count = s->bvh.degenerate_count;
    } else {
        uint32_t i;
        for (i = 0; i < n; i++)
            if (s->normals[(size_t)3 * i] == 0.0f && s->normals[(size_t)3 * i + 1] == 0.0f &&
                s->normals[(size_t)3 * i + 2] == 0.0f)
                s->degenerate_count++;
    }
    *out = s;
    return LIGHTVEC_OK;
}

LIGHTVEC_API void lightvec_scene_destroy(lightvec_scene *s)
{
    lightvec_allocator a;
    if (!s) return;
    a = s->a;
    if (s->use_bvh) lightvec__bvh_free(&s->bvh, &a);
    lightvec__free(&a, s->normals);
    lightvec__free(&a, s->tri_material);
    lightvec__free(&a, s->materials);
    lightvec__free(&a, s->emit_verts);
    lightvec__free(&a, s->emit_normal);
    lightvec__free(&a, s->emit_cdf);
    lightvec__free(&a, s->emit_inv_pdf);
    lightvec__free(&a, s->emit_material);
    lightvec__free(&a, s->emit_bound);
    lightvec__free(&a, s->emit_area);
    lightvec__free(&a, s->environment);
    lightvec__free(&a, s);
}

LIGHTVEC_API lightvec_result lightvec_scene_info(const lightvec_scene *s, lightvec_scene_stats *info)
{
    if (!s || !info) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(info, 0, sizeof *info);
    info->triangle_count = s->tri_count;
    info->degenerate_count = s->degenerate_count;
    info->emitter_count = s->emitter_count;
    info->bvh_node_count = s->use_bvh ? s->bvh.node_count : 0u;
    memcpy(info->bounds_min, s->lo, sizeof s->lo);
    memcpy(info->bounds_max, s->hi, sizeof s->hi);
    info->ray_offset = s->eps;
    return LIGHTVEC_OK;
}

/* Closest hit through the BVH or the caller's trace callback. A callback hit
   naming a triangle out of range counts as a miss. */
static int lightvec__trace(const lightvec_scene *s, lightvec__vec3 org, lightvec__vec3 dir, float tmax,
                           lightvec__hit *hit)
{
    float o[3], d[3];
    o[0] = org.x; o[1] = org.y; o[2] = org.z;
    d[0] = dir.x; d[1] = dir.y; d[2] = dir.z;
    if (s->use_bvh) return lightvec__bvh_intersect(&s->bvh, o, d, 0.0f, tmax, hit);
    {
        lightvec_hit h;
        h.t = tmax; h.u = h.v = 0.0f; h.triangle = LIGHTVEC__NO_HIT;
        hit->tri = LIGHTVEC__NO_HIT;
        if (!s->trace(s->trace_user, o, d, tmax, &h) || h.triangle >= s->tri_count || !(h.t > 0.0f) ||
            !(h.t <= tmax))
            return 0;
        hit->t = h.t; hit->u = h.u; hit->v = h.v; hit->tri = h.triangle;
        return 1;
    }
}

static int lightvec__occluded(const lightvec_scene *s, lightvec__vec3 org, lightvec__vec3 dir, float tmax)
{
    if (s->use_bvh) {
        float o[3], d[3];
        o[0] = org.x; o[1] = org.y; o[2] = org.z;
        d[0] = dir.x; d[1] = dir.y; d[2] = dir.z;
        return lightvec__bvh_occluded(&s->bvh, o, d, 0.0f, tmax);
    } else {
        lightvec__hit h;
        return lightvec__trace(s, org, dir, tmax, &h);
    }
}

LIGHTVEC_API int lightvec_scene_intersect(const lightvec_scene *s, const float org[3], const float dir[3],
                                          float tmax, lightvec_hit *hit)
{
    lightvec__hit h;
    if (!s || !org || !dir || !hit || !lightvec__finite3(org) || !lightvec__finite3(dir) || !(tmax > 0.0f))
        return 0;
    if (!lightvec__trace(s, lightvec__v3_load(org), lightvec__v3_load(dir), tmax, &h)) return 0;
    hit->t = h.t; hit->u = h.u; hit->v = h.v; hit->triangle = h.tri;
    return 1;
}

/* ---- glass and sky (GLASS AND SKY) ---- */

/* The transmittance of a triangle's material, or NULL when it is opaque. */
static const float *lightvec__glass(const lightvec_scene *s, uint32_t tri)
{
    const float *t = s->materials[s->tri_material[tri]].transmittance;
    return (t[0] > 0.0f || t[1] > 0.0f || t[2] > 0.0f) ? t : NULL;
}

/* The origin of a ray that goes on straight through the surface of its
   hit: the hit point moved eps off the surface, on the far side. */
static lightvec__vec3 lightvec__step_through(const lightvec_scene *s, lightvec__vec3 org, lightvec__vec3 dir,
                                             const lightvec__hit *hit)
{
    lightvec__vec3 n = lightvec__v3_load(s->normals + (size_t)3 * hit->tri);
    lightvec__vec3 y = lightvec__add(org, lightvec__scale(dir, hit->t));
    return lightvec__add(y, lightvec__scale(n, lightvec__dot(n, dir) < 0.0f ? -s->eps : s->eps));
}

/* What reaches org + tmax dir from org (dir unit): through = the product of
   the transmittances of the panes crossed, 0 when something opaque is in
   the way or more than LIGHTVEC_MAX_GLASS_LAYERS panes. Returns whether
   any light gets through. Without glass in the scene, a shadow ray. */
static int lightvec__transmittance(const lightvec_scene *s, lightvec__vec3 org, lightvec__vec3 dir, float tmax,
                                   float through[3])
{
    uint32_t layers;
    through[0] = through[1] = through[2] = 1.0f;
    if (!s->has_glass) {
        if (!lightvec__occluded(s, org, dir, tmax)) return 1;
    } else {
        for (layers = 0; layers <= LIGHTVEC_MAX_GLASS_LAYERS; layers++) {
            lightvec__hit hit;
            const float *t;
            if (!lightvec__trace(s, org, dir, tmax, &hit)) return 1;
            t = lightvec__glass(s, hit.tri);
            if (!t || layers == LIGHTVEC_MAX_GLASS_LAYERS) break;
            through[0] *= t[0]; through[1] *= t[1]; through[2] *= t[2];
            org = lightvec__step_through(s, org, dir, &hit);
            tmax -= hit.t;
            if (!(tmax > 0.0f)) return 1;
        }
    }
    through[0] = through[1] = through[2] = 0.0f;
    return 0;
}

/* The sky along the unit direction dir: the texel of the map it falls in
   (latitude-longitude, +y up: row = floor(theta / pi * height) with theta
   the angle from +y, column = floor((phi + pi) / (2 pi) * width) with
   phi = atan2(z, x); no filtering), or the constant sky. */
static void lightvec__sky(const lightvec_scene *s, lightvec__vec3 dir, float rgb[3])
{
    const float *src = s->sky;
    if (s->environment) {
        double cos_theta = dir.y, theta, phi;
        uint32_t row, col;
        if (!(cos_theta >= -1.0)) cos_theta = -1.0;   /* NaN too */
        if (cos_theta > 1.0) cos_theta = 1.0;
        theta = acos(cos_theta);
        phi = atan2((double)dir.z, (double)dir.x);
        if (!(phi >= -LIGHTVEC__PI)) phi = -LIGHTVEC__PI;
        row = (uint32_t)(theta / LIGHTVEC__PI * s->env_height);
        col = (uint32_t)((phi + LIGHTVEC__PI) / LIGHTVEC__TWO_PI * s->env_width);
        if (row >= s->env_height) row = s->env_height - 1;
        if (col >= s->env_width) col = s->env_width - 1;
        src = s->environment + 3 * ((size_t)row * s->env_width + col);
    }
    rgb[0] = src[0];
    rgb[1] = src[1];
    rgb[2] = src[2];
}

/* A cosine-distributed direction around n from two uniform numbers. */
static lightvec__vec3 lightvec__cosine_direction(lightvec__vec3 n, float u1, float u2)
{
    lightvec__vec3 t, bt, d;
    float r = sqrtf(u1), phi = (float)LIGHTVEC__TWO_PI * u2;
    lightvec__basis(n, &t, &bt);
    d = lightvec__add(lightvec__add(lightvec__scale(t, r * cosf(phi)), lightvec__scale(bt, r * sinf(phi))),
                      lightvec__scale(n, sqrtf(lightvec__maxf(0.0f, 1.0f - u1))));
    return lightvec__normalize(d);
}

/* Sky light at y (normal n) per unit Lambertian reflectance: one
   cosine-distributed direction (weight f cos / pdf = rho), through the glass
   on its way out: rho times this is the radiance y reflects. */
static void lightvec__sky_light(const lightvec_scene *s, lightvec__rng *rng, lightvec__vec3 y, lightvec__vec3 n,
                                double e[3])
{
    float u1 = lightvec__rng_float(rng), u2 = lightvec__rng_float(rng), through[3], sky[3];
    lightvec__vec3 dir = lightvec__cosine_direction(n, u1, u2);
    int c;
    e[0] = e[1] = e[2] = 0.0;
    if (!lightvec__transmittance(s, lightvec__add(y, lightvec__scale(n, s->eps)), dir, FLT_MAX, through)) return;
    lightvec__sky(s, dir, sky);
    for (c = 0; c < 3; c++) e[c] = (double)through[c] * sky[c];
}

/* Whether a path goes on straight through the glass it hit (from the back
   always, else chosen in proportion to the luminance of the transmittance
   against the diffuse reflectance, or always when no bounce is left);
   scales the path's weight by what it chose over its probability. */
static int lightvec__pass_through(const float tf[3], const float rho[3], int front, int last, lightvec__rng *rng,
                                  double through[3])
{
    float p = 1.0f, lt = lightvec__lumf(tf), ld = lightvec__lumf(rho);
    int c;
    if (front && !last) p = lt + ld > 0.0f ? lt / (lt + ld) : 1.0f;
    if (p < 1.0f && lightvec__rng_float(rng) >= p) {
        for (c = 0; c < 3; c++) through[c] *= rho[c] / (1.0 - p);   /* the bounce */
        return 0;
    }
    for (c = 0; c < 3; c++) through[c] *= tf[c] / p;
    return 1;
}

/* Emitter chosen by u in [0, 1) through the CDF (binary search). */
static uint32_t lightvec__pick_emitter(const lightvec_scene *s, float u)
{
    uint32_t lo = 0, hi = s->emitter_count - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (u < s->emit_cdf[mid]) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* Uniform point on emitter e from (u, v) in [0,1)^2 (square-root warp). */
static lightvec__vec3 lightvec__emitter_point(const lightvec_scene *s, uint32_t e, float u, float v)
{
    const float *t = s->emit_verts + (size_t)9 * e;
    float su = sqrtf(u), b0 = 1.0f - su, b1 = su * (1.0f - v), b2 = su * v;
    return lightvec__v3(b0 * t[0] + b1 * t[3] + b2 * t[6], b0 * t[1] + b1 * t[4] + b2 * t[7],
                        b0 * t[2] + b1 * t[5] + b2 * t[8]);
}

/* One light sample seen from x (normal n): direction, distance, the geometric
   term cos_x cos_l / (r^2 pdf) and its visibility. Returns 0 when the sample
   faces away. */
typedef struct lightvec__light_sample {
    lightvec__vec3 point, dir;
    float dist, cos_x, cos_l, inv_pdf;
    uint32_t emitter;
} lightvec__light_sample;

static int lightvec__sample_emitter(const lightvec_scene *s, uint32_t e, lightvec__vec3 x, lightvec__vec3 n,
                                    float u, float v, lightvec__light_sample *ls)
{
    lightvec__vec3 p = lightvec__emitter_point(s, e, u, v), d = lightvec__sub(p, x);
    float r2 = lightvec__dot(d, d), r;
    if (!(r2 > 0.0f)) return 0;
    r = sqrtf(r2);
    ls->point = p;
    ls->dir = lightvec__scale(d, 1.0f / r);
    ls->dist = r;
    ls->cos_x = lightvec__dot(n, ls->dir);
    ls->cos_l = -lightvec__dot(lightvec__v3_load(s->emit_normal + (size_t)3 * e), ls->dir);
    ls->inv_pdf = s->emit_inv_pdf[e];
    ls->emitter = e;
    return ls->cos_x > 0.0f && ls->cos_l > 0.0f;
}

static int lightvec__light_visible(const lightvec_scene *s, lightvec__vec3 x, lightvec__vec3 n,
                                   const lightvec__light_sample *ls, float through[3])
{
    /* from the offset origin to the light point itself, stopping 1e-4 short
       of it (relative) so that the emitter does not shadow itself; glass on
       the way lets its transmittance through */
    lightvec__vec3 org = lightvec__add(x, lightvec__scale(n, s->eps)), d = lightvec__sub(ls->point, org);
    float len = lightvec__length(d);
    if (!(len > 0.0f)) {
        through[0] = through[1] = through[2] = 1.0f;
        return 1;
    }
    return lightvec__transmittance(s, org, lightvec__scale(d, 1.0f / len), len * (1.0f - 1e-4f), through);
}

/* The importance of emitter e at a point x with normal n: what it can
   send there at most, power * cos_x * cos_l / d^2, with both cosines
   bounded over its bounding sphere (centre at distance d, radius r, seen
   under the half angle a: cos(theta - a) <= cos theta + a <= cos theta +
   (pi / 2) sin a, sin a = r / d, cheaper than the exact bound and as safe)
   and d^2 no less than r^2 (Conty Estevez & Kulla 2018, "Importance
   Sampling of Many Lights with Adaptive Tree Splitting", eq. 3, for one
   emitter). It is 0 only where e sends nothing (x behind its plane, or all
   of the sphere below x's horizon), so sampling by it stays unbiased. The
   centre lies on e's plane, so cos_l at the centre is x's height above the
   plane over d. */
static float lightvec__emitter_importance(const lightvec_scene *s, uint32_t e, lightvec__vec3 x, lightvec__vec3 n)
{
    const float *b = s->emit_bound + (size_t)LIGHTVEC__BOUND * e;
    lightvec__vec3 v = lightvec__v3(b[0] - x.x, b[1] - x.y, b[2] - x.z);
    float height = x.x * b[5] + x.y * b[6] + x.z * b[7] - b[8], d2 = lightvec__dot(v, v), inv_d, spread, cx, cl;
    if (height <= 0.0f) return 0.0f;   /* behind: one-sided */
    if (d2 <= b[3] * b[3]) return b[4] / (b[3] * b[3]);   /* inside the sphere: both cosines bounded by 1 */
    inv_d = 1.0f / sqrtf(d2);
    spread = 1.5707964f * b[3] * inv_d;   /* (pi / 2) sin a */
    cx = lightvec__minf(lightvec__dot(v, n) * inv_d + spread, 1.0f);
    if (cx <= 0.0f) return 0.0f;   /* the whole sphere below the horizon */
    cl = lightvec__minf(height * inv_d + spread, 1.0f);
    return b[4] * cx * cl * inv_d * inv_d;
}

/* Direct irradiance at x (normal n) from the emitters, `samples` samples.
   Each sample picks an emitter with probability proportional to its
   importance at x (lightvec__emitter_importance) and a uniform point on
   it, weighted by 1 / pdf: the estimate stays unbiased, and where most
   emitters are far or face away (a building's rooms: lamps of other
   rooms and storeys) the samples go to those that can light x. Picking by
   power alone, a gather hit in a room lit only through a door spent
   nearly every sample on lamps elsewhere and rarely met the near one with
   a huge weight: speckles in converged renders, blotches once a light
   vector spread them (issue 19). The samples are stratified over the
   CDF of importance (sample i at (i + xi) / samples, so an emitter of
   probability p gets samples p up to one), and what is left of a pick's
   stratum inside its emitter's interval places the point on it. The CDF
   is never stored: the picks rise with i, so one sweep over the emitters
   meets them in order (a second pass recomputes the same importances, bit
   for bit; the first LIGHTVEC__KEPT_IMPORTANCES are kept from the first).
   Cost: one importance per emitter and hit point, linear in the emitter
   count (a light tree, Conty Estevez & Kulla 2018, would make it
   logarithmic). On building_4k (82 emitters) a walkthrough gather (16 x 48
   rays, 4 light samples a hit) takes 2.85 ms of one thread against 1.50
   ms by power alone: the importances and the shadow rays that now reach
   their lamps instead of stopping at the first wall. Every call takes
   2 samples + 1 random numbers, whatever the importances. */
#define LIGHTVEC__KEPT_IMPORTANCES 256   /* the first emitters' importances kept from the first pass */
static void lightvec__direct_irradiance(const lightvec_scene *s, lightvec__rng *rng, lightvec__vec3 x,
                                        lightvec__vec3 n, uint32_t samples, double e[3])
{
    float kept[LIGHTVEC__KEPT_IMPORTANCES];
    double total = 0.0, below = 0.0, pick;
    uint32_t i = 0, k, last = 0;
    e[0] = e[1] = e[2] = 0.0;
    for (k = 0; k < s->emitter_count; k++) {
        float imp = lightvec__emitter_importance(s, k, x, n);
        if (k < LIGHTVEC__KEPT_IMPORTANCES) kept[k] = imp;
        if (imp > 0.0f) last = k;
        total += imp;
    }
    if (!(total > 0.0) || !isfinite(total)) {   /* no emitter can light x: take the sweep's numbers all the same, */
        for (i = 0; i <= 2 * samples; i++)        /* so that a hit whose sum rounds to 0 on one tracer and not on */
            (void)lightvec__rng_float(rng);       /* another leaves the rest of the gather's numbers in step */
        return;
    }
    pick = lightvec__rng_float(rng) / samples * total;
    for (k = 0; k <= last && i < samples; k++) {
        double p = k < LIGHTVEC__KEPT_IMPORTANCES ? kept[k] : lightvec__emitter_importance(s, k, x, n), above = below + p;
        while (p > 0.0 && i < samples && (pick < above || k == last)) {   /* the last takes what rounding leaves */
            lightvec__light_sample ls;
            float u = lightvec__minf(lightvec__maxf((float)((pick - below) / p), 0.0f), 0.99999994f);
            float v = lightvec__rng_float(rng), t[3];
            if (lightvec__sample_emitter(s, k, x, n, u, v, &ls) &&
                lightvec__light_visible(s, x, n, &ls, t)) {
                const float *le = s->materials[s->emit_material[k]].emission;
                double g = (double)ls.cos_x * ls.cos_l * s->emit_area[k] * total / (p * (double)ls.dist * ls.dist);
                e[0] += le[0] * t[0] * g; e[1] += le[1] * t[1] * g; e[2] += le[2] * t[2] * g;
            }
            i++;
            pick = ((double)i + lightvec__rng_float(rng)) / samples * total;
        }
        below = above;
    }
    e[0] /= samples; e[1] /= samples; e[2] /= samples;
}

/* Radiance leaving the surface hit by the ray (org, dir) back toward org,
   emission excluded (light straight from an emitter is direct light at the
   gathering point, not indirect): Lambertian reflection of the direct light
   (and of the sky) at the hit, plus (bounces - 1) cosine-sampled diffuse
   bounces, each adding the direct light reflected at its own hit. Glass is
   crossed on the way without using up a bounce (a pane met from the front
   may reflect instead, chosen at random: lightvec__pass_through); the sky
   seen through glass straight along the gather ray counts, a bounce ray's
   sky was counted at its origin (lightvec__sky_light). */
static void lightvec__path_radiance(const lightvec_scene *s, lightvec__rng *rng, lightvec__vec3 org,
                                    lightvec__vec3 dir, const lightvec__hit *first, uint32_t bounces,
                                    uint32_t light_samples, double out[3])
{
    double through[3] = { 1.0, 1.0, 1.0 };
    lightvec__hit hit = *first;
    uint32_t b = 0, layers = 0;
    out[0] = out[1] = out[2] = 0.0;
    for (;;) {
        lightvec__vec3 y = lightvec__add(org, lightvec__scale(dir, hit.t));
        lightvec__vec3 n = lightvec__v3_load(s->normals + (size_t)3 * hit.tri);
        const float *rho = s->materials[s->tri_material[hit.tri]].diffuse;
        const float *glass = s->has_glass ? lightvec__glass(s, hit.tri) : NULL;
        int front = lightvec__dot(n, dir) < 0.0f, last = b + 1 == bounces;
        double e[3];
        int c;
        if (!front && !glass) break; /* back faces are black (one-sided, as in radiosity) */
        if (front) {
            lightvec__direct_irradiance(s, rng, y, n, light_samples, e);
            for (c = 0; c < 3; c++) out[c] += through[c] * rho[c] * (1.0 / LIGHTVEC__PI) * e[c];
            if (s->has_sky) {
                lightvec__sky_light(s, rng, y, n, e);
                for (c = 0; c < 3; c++) out[c] += through[c] * rho[c] * e[c];
            }
        }
        if (glass && layers < LIGHTVEC_MAX_GLASS_LAYERS && lightvec__pass_through(glass, rho, front, last, rng, through)) {
            layers++;
            org = lightvec__step_through(s, org, dir, &hit);
            if (!lightvec__trace(s, org, dir, FLT_MAX, &hit)) {
                if (b == 0 && s->has_sky) {   /* the gather ray itself leaves through the glass */
                    float sky[3];
                    lightvec__sky(s, dir, sky);
                    for (c = 0; c < 3; c++) out[c] += through[c] * sky[c];
                }
                break;
            }
            continue;
        }
        if (!front) break;   /* past the layer limit */
        if (!glass || layers >= LIGHTVEC_MAX_GLASS_LAYERS) {   /* (else the choice above scaled through) */
            if (last) break;
            for (c = 0; c < 3; c++) through[c] *= rho[c]; /* cosine sampling: f cos / pdf = rho */
        }
        if (through[0] == 0.0 && through[1] == 0.0 && through[2] == 0.0) break;
        {
            float u1 = lightvec__rng_float(rng), u2 = lightvec__rng_float(rng);
            org = lightvec__add(y, lightvec__scale(n, s->eps));
            dir = lightvec__cosine_direction(n, u1, u2);
        }
        b++;
        if (!lightvec__trace(s, org, dir, FLT_MAX, &hit)) break;   /* its sky: counted at y */
    }
}

/* ======================================================================
   11. gather: ILV (eq. 2, 3, 5, 6) and DLV
   ---------------------------------------------------------------------- */
typedef struct lightvec__gather_params {
    uint32_t m, n, bounces, light_samples, lobe_samples;
    float min_distance, max_distance;
} lightvec__gather_params;

#define LIGHTVEC__MAX_GLOSSY_SAMPLES 65536u

static lightvec_result lightvec__gather_setup(const lightvec_gather_desc *d, const lightvec_surface *sf,
                                              lightvec__gather_params *g, lightvec__vec3 *n, lightvec__vec3 *wo)
{
    if (!d || !sf) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    g->m = lightvec__def(d->strata_theta, 20u);
    g->n = lightvec__def(d->strata_phi, 3u * g->m);
    g->bounces = lightvec__def(d->bounces, 2u);
    g->light_samples = lightvec__def(d->light_samples, 1u);
    if (g->m > LIGHTVEC__MAX_STRATA_THETA || g->n > LIGHTVEC__MAX_STRATA_PHI || g->bounces > LIGHTVEC__MAX_BOUNCES ||
        g->light_samples > LIGHTVEC__MAX_LIGHT_SAMPLES || d->glossy_samples > LIGHTVEC__MAX_GLOSSY_SAMPLES)
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    g->lobe_samples = lightvec__def(d->glossy_samples, g->m * g->n / 4u) & ~1u; /* antithetic pairs */
    if (!isfinite(d->min_distance) || !isfinite(d->max_distance) || d->min_distance < 0.0f ||
        d->max_distance < 0.0f || (d->max_distance > 0.0f && d->min_distance > d->max_distance))
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    g->min_distance = d->min_distance;
    g->max_distance = d->max_distance > 0.0f ? d->max_distance : LIGHTVEC__FAR;
    if (!lightvec__finite3(sf->position) || !lightvec__unit(sf->normal, n)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    if (!lightvec__material_valid(&sf->material) || (sf->flags & ~LIGHTVEC_RECORD_VIEW_INDEPENDENT))
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    if ((sf->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) && lightvec__glossy(&sf->material))
        return LIGHTVEC_ERROR_INVALID_ARGUMENT; /* a glossy surface depends on the viewer */
    if (sf->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) {
        *wo = *n;
    } else if (!lightvec__unit(sf->outgoing, wo)) {
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    }
    if (!lightvec__glossy(&sf->material)) g->lobe_samples = 0;
    return LIGHTVEC_OK;
}

/* The glossy lobe a gather integrates: around the mirror direction of the
   viewer wo (on = 0 for a Lambertian or view-independent surface). */
typedef struct lightvec__lobe_frame {
    int on;
    lightvec__vec3 n, wo, mirror;
    double exponent;
} lightvec__lobe_frame;

static lightvec__lobe_frame lightvec__lobe_frame_of(const lightvec_surface *sf, lightvec__vec3 n, lightvec__vec3 wo)
{
    lightvec__lobe_frame f;
    f.on = lightvec__glossy(&sf->material) && !(sf->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT);
    f.n = n;
    f.wo = wo;
    f.mirror = lightvec__normalize(lightvec__sub(lightvec__scale(n, 2.0f * lightvec__dot(n, wo)), wo));
    f.exponent = sf->material.exponent;
    return f;
}

/* What a gather accumulates, in double, before the record is made. */
typedef struct lightvec__sums {
    double irr[3];              /* E */
    double dir[3];              /* eq. 2: the integral of Y(L) w */
    double grad[3][3];          /* dE/dx in world axes */
    double glossy[3];           /* G */
    double glossy_grad[3][3];   /* dG/dw_r in world axes, perpendicular to w_r */
    double inv_r, samples;      /* harmonic mean distance: sum of 1 / r over `samples` */
    double lobe_inv_r, lobe_weight;  /* the same along the lobe, weighted by it */
    float visibility;
} lightvec__sums;

/* One incident sample's share of G = integral of lobe(wi -> wo) L cos theta_i
   and of its view gradient: d lobe / d wo = e (e + 2) / (2 pi)
   (r(wi) . wo)^(e - 1) r(wi), r(wi) the mirror image of wi, taken off wo
   sample by sample: r(wi) . wo = c, so r(wi) - c wo (the part a unit wo can
   move along; the part along wo, e times larger, would only add noise).
   scale is the sample's solid angle (its estimator weight), r the distance
   it saw. */
static void lightvec__add_lobe(lightvec__sums *s, const lightvec__lobe_frame *f, lightvec__vec3 wi, const float l[3],
                               double scale, double r)
{
    double c = (double)wi.x * f->mirror.x + (double)wi.y * f->mirror.y + (double)wi.z * f->mirror.z;
    double ci = (double)wi.x * f->n.x + (double)wi.y * f->n.y + (double)wi.z * f->n.z, p, k, kd, rw[3];
    int ch;
    if (!(c > 0.0) || !(ci > 0.0) || !(scale > 0.0)) return;
    p = pow(c, f->exponent);
    k = (f->exponent + 2.0) / LIGHTVEC__TWO_PI * p * ci * scale;
    /* the derivative is singular at the lobe's edge when e < 1: left out there */
    kd = c > 1e-6 ? k * f->exponent / c : 0.0;
    rw[0] = 2.0 * ci * f->n.x - wi.x - c * f->wo.x;
    rw[1] = 2.0 * ci * f->n.y - wi.y - c * f->wo.y;
    rw[2] = 2.0 * ci * f->n.z - wi.z - c * f->wo.z;
    s->lobe_weight += k;
    if (r < (double)LIGHTVEC__FAR) s->lobe_inv_r += k / r;
    for (ch = 0; ch < 3; ch++) {
        s->glossy[ch] += k * l[ch];
        s->glossy_grad[ch][0] += kd * l[ch] * rw[0];
        s->glossy_grad[ch][1] += kd * l[ch] * rw[1];
        s->glossy_grad[ch][2] += kd * l[ch] * rw[2];
    }
}

static float lightvec__clamp_distance(const lightvec__gather_params *g, double d)
{
    if (!(d < (double)g->max_distance)) d = g->max_distance;
    if (d < (double)g->min_distance) d = g->min_distance;
    if (!(d > 0.0)) d = 1e-30;
    return (float)d;
}

/* The record of a gather, from its sums (eq. 2 and 3):
   diffuse vector  D = the eq. 2 integral normalised (the normal when it
                   vanishes or, by float rounding, grazes), M = E / cos(n, D)
                   in double: the Lambert term of eq. 3 cancels;
   glossy part     G and dG/dw_r (in the tangent plane of w_r, along which a
                   unit direction moves), d_g, the exponent, and the glossy
                   light vector toward w_r (lightvec__glossy_vector). */
static void lightvec__fill_record(const lightvec_surface *sf, const lightvec__gather_params *g,
                                  const lightvec__lobe_frame *f, lightvec__vec3 wo, const lightvec__sums *s,
                                  lightvec_record *out)
{
    lightvec__vec3 n = f->n, d = lightvec__v3((float)s->dir[0], (float)s->dir[1], (float)s->dir[2]);
    double cos_d;
    int c, k;
    memset(out, 0, sizeof *out);
    memcpy(out->position, sf->position, sizeof out->position);
    out->normal[0] = n.x; out->normal[1] = n.y; out->normal[2] = n.z;
    out->outgoing[0] = wo.x; out->outgoing[1] = wo.y; out->outgoing[2] = wo.z;
    if (!(lightvec__length(d) > 0.0f) || !isfinite(lightvec__length(d))) d = n;
    d = lightvec__normalize(d);
    if (!(lightvec__dot(n, d) > 1e-6f)) d = n;
    cos_d = lightvec__dot(n, d);
    out->vector.direction[0] = d.x; out->vector.direction[1] = d.y; out->vector.direction[2] = d.z;
    for (c = 0; c < 3; c++) {
        out->vector.magnitude[c] = lightvec__to_float(s->irr[c] / cos_d);
        out->irradiance[c] = lightvec__to_float(s->irr[c]);
        for (k = 0; k < 3; k++) out->gradient[c][k] = lightvec__to_float(s->grad[c][k]);
    }
    if (f->on) {
        for (c = 0; c < 3; c++) {
            out->glossy[c] = lightvec__to_float(s->glossy[c]);
            for (k = 0; k < 3; k++) out->glossy_gradient[c][k] = lightvec__to_float(s->glossy_grad[c][k]);
        }
        out->glossy_distance = lightvec__clamp_distance(
            g, s->lobe_inv_r > 0.0 ? s->lobe_weight / s->lobe_inv_r : (double)LIGHTVEC__FAR);
        out->exponent = (float)f->exponent;
        lightvec__glossy_vector(n, wo, f->exponent, s->glossy, &out->vector);
        {
            double yg = 0.0, yd = 0.0;
            static const double lum[3] = { 0.2126, 0.7152, 0.0722 };
            for (c = 0; c < 3; c++) {
                yg += lum[c] * sf->material.specular[c] * s->glossy[c];
                yd += lum[c] * sf->material.diffuse[c] / LIGHTVEC__PI * s->irr[c];
            }
            out->glossy_share = yg + yd > 0.0 ? (float)(yg / (yg + yd)) : 1.0f;
        }
    }
    out->distance = lightvec__clamp_distance(g, s->inv_r > 0.0 ? s->samples / s->inv_r : (double)LIGHTVEC__FAR);
    out->visibility = s->visibility;
    out->flags = sf->flags;
}

/* One stratum's sample: radiance and distance of the surface it sees. */
typedef struct lightvec__cell { float l[3]; float r; } lightvec__cell;

/* Ward & Heckbert's translational gradient, written for any stratum
   boundaries (the paper's eq. 6 differentiates cos theta with the hit points
   held fixed; Ward & Heckbert move the stratum boundaries instead, which is
   what the paper follows). Moving the point by dx in the tangent plane shifts
   what a boundary shows by the motion of the nearer of the two surfaces seen
   on its sides (distance min(R, R')):
     boundary between zenith strata j-1 and j, at theta_j-, azimuth cell k:
       (2 pi / N) sin theta cos^2 theta (L_jk - L_j-1,k) / min(R) along u_k
       (u_k: the cell's central azimuth);
     boundary between azimuth cells k-1 and k, at phi_k-, zenith stratum j:
       (sin theta_j+ - sin theta_j-) (L_jk - L_j,k-1) / min(R) along v_k-
       (v_k-: perpendicular to the boundary's meridian plane).
   The second factor is the integral of cos theta d theta over the stratum,
   exact for any zenith boundaries (Ward & Heckbert's cosine-weighted strata
   give the same expression). Accumulates in local tangent coordinates. */
static void lightvec__gradient_row(const lightvec__cell *cur, const lightvec__cell *prev, uint32_t j, uint32_t m,
                                   uint32_t n, float min_r, double g[3][2])
{
    double cos_lo = 1.0 - (double)j / m, cos_hi = 1.0 - (double)(j + 1) / m;
    double sin_lo = sqrt(1.0 - cos_lo * cos_lo), sin_hi = sqrt(1.0 - cos_hi * cos_hi);
    double polar = (LIGHTVEC__TWO_PI / n) * sin_lo * cos_lo * cos_lo;
    uint32_t k;
    int c;
    for (k = 0; k < n; k++) {
        const lightvec__cell *a = &cur[k], *b = &cur[(k + n - 1) % n];
        double r = lightvec__maxf(lightvec__minf(a->r, b->r), min_r);
        double phi_b = LIGHTVEC__TWO_PI * k / n, coef;
        if (n > 1 && r < (double)LIGHTVEC__FAR) {
            coef = (sin_hi - sin_lo) / r;
            for (c = 0; c < 3; c++) {
                double dl = coef * ((double)a->l[c] - b->l[c]);
                g[c][0] += -sin(phi_b) * dl;
                g[c][1] += cos(phi_b) * dl;
            }
        }
        if (prev) {
            const lightvec__cell *p = &prev[k];
            double phi_c = LIGHTVEC__TWO_PI * (k + 0.5) / n;
            r = lightvec__maxf(lightvec__minf(a->r, p->r), min_r);
            if (r < (double)LIGHTVEC__FAR) {
                coef = polar / r;
                for (c = 0; c < 3; c++) {
                    double dl = coef * ((double)a->l[c] - p->l[c]);
                    g[c][0] += cos(phi_c) * dl;
                    g[c][1] += sin(phi_c) * dl;
                }
            }
        }
    }
}

/* Incoming radiance and distance along one gather ray. */
static lightvec_result lightvec__incoming(const lightvec_scene *s, const lightvec_gather_desc *d,
                                          const lightvec__gather_params *g, lightvec__rng *rng, lightvec__vec3 org,
                                          lightvec__vec3 dir, lightvec__cell *cell)
{
    if (d->incoming_radiance) {
        float o[3], w[3], dist = LIGHTVEC__FAR;
        o[0] = org.x; o[1] = org.y; o[2] = org.z;
        w[0] = dir.x; w[1] = dir.y; w[2] = dir.z;
        cell->l[0] = cell->l[1] = cell->l[2] = 0.0f;
        d->incoming_radiance(d->incoming_user, o, w, cell->l, &dist);
        if (!lightvec__finite_nonneg(cell->l, 3) || isnan(dist) || !(dist > 0.0f))
            return LIGHTVEC_ERROR_INVALID_ARGUMENT;
        cell->r = dist < LIGHTVEC__FAR ? dist : LIGHTVEC__FAR;
    } else {
        lightvec__hit hit;
        double l[3] = { 0.0, 0.0, 0.0 };
        cell->r = LIGHTVEC__FAR;
        if (lightvec__trace(s, org, dir, FLT_MAX, &hit)) {
            cell->r = hit.t;   /* glass included: a pane counts at its own distance (GLASS AND SKY) */
            lightvec__path_radiance(s, rng, org, dir, &hit, g->bounces, g->light_samples, l);
        } else if (s->has_sky) {
            float sky[3];
            lightvec__sky(s, dir, sky);
            l[0] = sky[0]; l[1] = sky[1]; l[2] = sky[2];
        }
        cell->l[0] = (float)l[0]; cell->l[1] = (float)l[1]; cell->l[2] = (float)l[2];
    }
    return LIGHTVEC_OK;
}

/* The density of the glossy samples of a gather at wi: lobe_samples times
   the Phong sampling density (e + 1) / (2 pi) cos^e alpha, plus that of the
   M N strata, MN / (2 pi). 1 / this is a sample's weight under the balance
   heuristic (Veach 1997), which needs no other knowledge of which technique
   drew the sample. */
static double lightvec__mis_density(const lightvec__lobe_frame *f, const lightvec__gather_params *g, lightvec__vec3 wi)
{
    double c = (double)wi.x * f->mirror.x + (double)wi.y * f->mirror.y + (double)wi.z * f->mirror.z;
    double q = (double)g->m * g->n / LIGHTVEC__TWO_PI;
    if (c > 0.0 && g->lobe_samples) q += g->lobe_samples * (f->exponent + 1.0) / LIGHTVEC__TWO_PI * pow(c, f->exponent);
    return q;
}

/* Pair i of `pairs` drawn from the Phong lobe around f->mirror: cos alpha =
   u^(1 / (e + 1)) with u stratified, the azimuth on a rank-1 lattice (golden
   ratio), both jittered; the second direction of the pair is the first
   turned by 180 degrees about the lobe's axis. Antithetic pairs: the view
   gradient of a lobe is odd about its axis, and a pair cancels that odd part
   for light that does not change across the lobe, where single samples
   would leave it as noise (about sqrt(e) times the gradient itself). */
static void lightvec__lobe_pair(const lightvec__lobe_frame *f, uint32_t i, uint32_t pairs, lightvec__rng *rng,
                                lightvec__vec3 w[2])
{
    lightvec__vec3 t, b, axis;
    float u = ((float)i + lightvec__rng_float(rng)) / (float)pairs, v = lightvec__rng_float(rng);
    float ca = (float)pow((double)u, 1.0 / (f->exponent + 1.0)), sa = sqrtf(lightvec__maxf(0.0f, 1.0f - ca * ca));
    float phi = (float)LIGHTVEC__TWO_PI * (v + 0.6180339887f * (float)i);
    lightvec__vec3 side;
    lightvec__basis(f->mirror, &t, &b);
    side = lightvec__add(lightvec__scale(t, sa * cosf(phi)), lightvec__scale(b, sa * sinf(phi)));
    axis = lightvec__scale(f->mirror, ca);
    w[0] = lightvec__normalize(lightvec__add(axis, side));
    w[1] = lightvec__normalize(lightvec__sub(axis, side));
}

/* eq. 5 over M x N strata of equal solid angle (cos theta uniform in each of
   the M zenith strata, phi uniform in each of the N azimuth cells), one
   jittered ray per stratum, each stratum weighing 2 pi / (M N):
     E     = 2 pi / (MN) sum L_jk cos theta_jk           (eq. 5 with the Lambert term rho_d / pi)
     D     = 2 pi / (MN) sum Y(L_jk) w_jk                (eq. 2, luminance Y)
     d_avg = MN / sum 1 / R_jk                           (harmonic mean, Ward 1988)
   and on a glossy surface, glossy_samples more rays drawn from the lobe:
     G     = sum over all rays of lobe(w -> w_r) L cos theta / q(w)   (q: lightvec__mis_density)
   with its view gradient and d_g from the same rays (lightvec__add_lobe). */
LIGHTVEC_API lightvec_result lightvec_gather(const lightvec_scene *scene, const lightvec_gather_desc *desc,
                                             const lightvec_surface *sf, uint64_t index, lightvec_record *out)
{
    lightvec__cell rows[2][LIGHTVEC__MAX_STRATA_PHI];
    lightvec__gather_params g;
    lightvec__lobe_frame f;
    lightvec__sums sums;
    lightvec__vec3 n, wo, t, b, org;
    lightvec__rng rng;
    double grad[3][2], dw;
    float min_r;
    uint32_t j, k;
    int c;
    lightvec_result r;
    if (!out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    r = lightvec__gather_setup(desc, sf, &g, &n, &wo);
    if (r != LIGHTVEC_OK) return r;
    if (!desc->incoming_radiance && !scene) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(&sums, 0, sizeof sums);
    memset(grad, 0, sizeof grad);
    f = lightvec__lobe_frame_of(sf, n, wo);
    rng = lightvec__rng_stream(desc->seed, index);
    lightvec__basis(n, &t, &b);
    org = lightvec__v3_load(sf->position);
    if (!desc->incoming_radiance) org = lightvec__add(org, lightvec__scale(n, scene->eps));
    min_r = (!desc->incoming_radiance) ? scene->eps : 1e-6f;
    dw = LIGHTVEC__TWO_PI / ((double)g.m * g.n);
    for (j = 0; j < g.m; j++) {
        lightvec__cell *cur = rows[j & 1], *prev = j ? rows[(j + 1) & 1] : NULL;
        for (k = 0; k < g.n; k++) {
            float cos_t = 1.0f - ((float)j + lightvec__rng_float(&rng)) / (float)g.m;
            float phi = (float)LIGHTVEC__TWO_PI * ((float)k + lightvec__rng_float(&rng)) / (float)g.n;
            float sin_t = sqrtf(lightvec__maxf(0.0f, 1.0f - cos_t * cos_t));
            lightvec__vec3 w = lightvec__add(lightvec__add(lightvec__scale(t, sin_t * cosf(phi)),
                                                           lightvec__scale(b, sin_t * sinf(phi))),
                                             lightvec__scale(n, cos_t));
            double y;
            w = lightvec__normalize(w);
            r = lightvec__incoming(scene, desc, &g, &rng, org, w, &cur[k]);
            if (r != LIGHTVEC_OK) return r;
            for (c = 0; c < 3; c++) sums.irr[c] += (double)cur[k].l[c] * cos_t * dw;
            y = 0.2126 * cur[k].l[0] + 0.7152 * cur[k].l[1] + 0.0722 * cur[k].l[2];
            sums.dir[0] += y * w.x * dw; sums.dir[1] += y * w.y * dw; sums.dir[2] += y * w.z * dw;
            if (cur[k].r < LIGHTVEC__FAR) sums.inv_r += 1.0 / lightvec__maxf(cur[k].r, min_r);
            if (f.on) lightvec__add_lobe(&sums, &f, w, cur[k].l, 1.0 / lightvec__mis_density(&f, &g, w), cur[k].r);
        }
        lightvec__gradient_row(cur, prev, j, g.m, g.n, min_r, grad);
    }
    for (k = 0; f.on && k < g.lobe_samples / 2; k++) {
        lightvec__vec3 w[2];
        int i;
        lightvec__lobe_pair(&f, k, g.lobe_samples / 2, &rng, w);
        for (i = 0; i < 2; i++) {
            lightvec__cell cell;
            if (!(lightvec__dot(w[i], n) > 0.0f)) continue; /* below the horizon: no light, the sample still counts */
            r = lightvec__incoming(scene, desc, &g, &rng, org, w[i], &cell);
            if (r != LIGHTVEC_OK) return r;
            lightvec__add_lobe(&sums, &f, w[i], cell.l, 1.0 / lightvec__mis_density(&f, &g, w[i]), cell.r);
        }
    }
    for (c = 0; c < 3; c++) {
        sums.grad[c][0] = grad[c][0] * t.x + grad[c][1] * b.x;
        sums.grad[c][1] = grad[c][0] * t.y + grad[c][1] * b.y;
        sums.grad[c][2] = grad[c][0] * t.z + grad[c][1] * b.z;
    }
    sums.samples = (double)g.m * g.n;
    sums.visibility = 1.0f;
    lightvec__fill_record(sf, &g, &f, wo, &sums, out);
    return LIGHTVEC_OK;
}

/* Direct light vector: M x N stratified samples of the emitters (the square
   [0,1)^2 cut in N x M cells, u picks the emitter through the CDF and, rescaled,
   the point with v), one shadow ray each. With dA the emitter area element and
   p the sample density, the solid angle of a sample is cos_l dA / r^2, so
     E = 1/S sum L_e V cos_x cos_l / (r^2 p),  D = 1/S sum Y(L_e) V w cos_l / (r^2 p),
   G the same sum with lobe(w -> w_r) cos_x, and the record as for indirect
   light. The gradient differentiates each unoccluded term
   G = cos_x cos_l / r^2 exactly with the sample point fixed:
     dG/dx = (-cos_l n + cos_x n_l + 4 cos_x cos_l w) / r^3, projected on the tangent plane
   (visibility changes are not in it: that is what the DLV visibility rule is for). */
LIGHTVEC_API lightvec_result lightvec_gather_direct(const lightvec_scene *s, const lightvec_gather_desc *desc,
                                                    const lightvec_surface *sf, uint64_t index,
                                                    lightvec_record *out)
{
    lightvec__gather_params g;
    lightvec__lobe_frame f;
    lightvec__sums sums;
    lightvec__vec3 n, wo, x;
    lightvec__rng rng;
    uint32_t j, k, facing = 0, visible = 0, total;
    int c;
    lightvec_result r;
    if (!out || !s) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    r = lightvec__gather_setup(desc, sf, &g, &n, &wo);
    if (r != LIGHTVEC_OK) return r;
    memset(&sums, 0, sizeof sums);
    f = lightvec__lobe_frame_of(sf, n, wo);
    rng = lightvec__rng_stream(desc->seed, index);
    x = lightvec__v3_load(sf->position);
    total = g.m * g.n;
    for (j = 0; j < g.m && s->emitter_count; j++) {
        for (k = 0; k < g.n; k++) {
            lightvec__light_sample ls;
            float u = ((float)k + lightvec__rng_float(&rng)) / (float)g.n;
            float v = ((float)j + lightvec__rng_float(&rng)) / (float)g.m, lo, hi;
            uint32_t e = lightvec__pick_emitter(s, u);
            const float *emitted;
            float le[3], through[3];
            double solid, y, sc;
            lightvec__vec3 nl, dg;
            lo = e ? s->emit_cdf[e - 1] : 0.0f;
            hi = s->emit_cdf[e];
            u = hi > lo ? (u - lo) / (hi - lo) : 0.5f;
            if (u >= 1.0f) u = 0.99999994f;
            if (!lightvec__sample_emitter(s, e, x, n, u, v, &ls)) continue;
            facing++;
            sums.inv_r += 1.0 / ls.dist;
            if (!lightvec__light_visible(s, x, n, &ls, through)) continue;
            visible++;   /* through glass too: a pane dims the light evenly, it casts no shadow edge */
            emitted = s->materials[s->emit_material[ls.emitter]].emission;
            for (c = 0; c < 3; c++) le[c] = emitted[c] * through[c];
            solid = (double)ls.cos_l * ls.inv_pdf / ((double)ls.dist * ls.dist) / total;
            for (c = 0; c < 3; c++) sums.irr[c] += le[c] * solid * ls.cos_x;
            y = lightvec__lumf(le) * solid;
            sums.dir[0] += y * ls.dir.x; sums.dir[1] += y * ls.dir.y; sums.dir[2] += y * ls.dir.z;
            nl = lightvec__v3_load(s->emit_normal + (size_t)3 * ls.emitter);
            dg = lightvec__add(lightvec__add(lightvec__scale(n, -ls.cos_l), lightvec__scale(nl, ls.cos_x)),
                               lightvec__scale(ls.dir, 4.0f * ls.cos_x * ls.cos_l));
            dg = lightvec__sub(dg, lightvec__scale(n, lightvec__dot(dg, n)));
            sc = ls.inv_pdf / ((double)ls.dist * ls.dist * ls.dist) / total;
            for (c = 0; c < 3; c++) {
                sums.grad[c][0] += le[c] * sc * dg.x;
                sums.grad[c][1] += le[c] * sc * dg.y;
                sums.grad[c][2] += le[c] * sc * dg.z;
            }
            if (f.on) lightvec__add_lobe(&sums, &f, ls.dir, le, solid, ls.dist);
        }
    }
    sums.samples = facing;
    sums.visibility = facing ? (float)visible / (float)facing : 1.0f;
    lightvec__fill_record(sf, &g, &f, wo, &sums, out);
    return LIGHTVEC_OK;
}

/* ======================================================================
   12. cache structures
   A record lives once in the record array (chunks that never move) and once
   as an item, a compact copy of what the criteria read, in the spatial index
   of the icosahedron face that holds its direction sigma. A leaf face indexes
   its items with kd-trees built by the Bentley-Saxe scheme: new items go to a
   small tail list; a full tail is merged with the smallest kd-trees (each up
   to 64 times what has been merged so far) into one new balanced kd-tree,
   so the trees of a face grow more than 64-fold from one to the next (at
   most log64(n / TAIL) + 1 of them) and an item is rebuilt O(log n) times.
   Every lookup of the face tests its whole tail: a tail of 8 (one block)
   rather than 16 took 1 to 6% off lookups at 10^5 records and added 4 to
   8% to insertions (v0.4.7).
   Trees are immutable once published (but for the radii neighbour clamping
   shrinks, read and written atomically): readers never see a half-built one.
   ---------------------------------------------------------------------- */
#define LIGHTVEC__LEAF 8u            /* items per kd-tree leaf */
#define LIGHTVEC__TAIL 8u            /* items a face holds outside its kd-trees: one block */
#define LIGHTVEC__MAX_TREES 40u      /* > log8(2^32 / TAIL) + 1 */
#define LIGHTVEC__MERGE_RATIO 64u    /* a merge absorbs kd-trees up to 64x its size so far */
#define LIGHTVEC__CHUNK0 1024u       /* records in the first chunk; chunk k holds CHUNK0 << k */
#define LIGHTVEC__CHUNKS 23          /* CHUNK0 * (2^23 - 1) >= 2^32 records */
#define LIGHTVEC__RECLAIM_BYTES ((size_t)1 << 20)
#define LIGHTVEC__FACE_STACK (20 + 4 * (LIGHTVEC__MAX_FACE_DEPTH + 1))
#define LIGHTVEC__RECORD_BYTES 208u  /* serialized record: 51 floats + flags */
#define LIGHTVEC__SETTINGS_BYTES 48u /* serialized settings: 12 values of 4 bytes */
#define LIGHTVEC__MAX_NEIGHBORS 256u

typedef struct lightvec__params {
    lightvec_kind kind;
    float radius_scale, max_change, normal_angle, direction_angle;  /* as given (degrees) */
    float cos_normal, inv_normal;    /* S_curv and 1 / (1 - S_curv) */
    float cos_dir, sin_dir, inv_dir; /* the largest S_dir, sin of its angle, 1 / (1 - S_dir) */
    float dir_angle;                 /* radians */
    float front;                     /* Ward's "in front" tolerance, relative to R_B */
    uint32_t min_valid, max_neighbors, split_threshold, max_depth, flags;
    lightvec_interpolation interpolation;  /* never DEFAULT */
} lightvec__params;

/* All that the interpolation of a diffuse vector reads of a record (A - B
   comes from the criteria): one cache line. */
typedef struct lightvec__head {
    float dir[3];                    /* D */
    float mag[3];                    /* what `interpolation` averages: M (PLAIN) or M cos(n_B, D) */
    float slope[3][3];               /* grad E_c / E_c per channel (0 where E_c = 0) */
    uint32_t kind;                   /* ITEM_* bits */
} lightvec__head;

/* The rest of a record as the index keeps it: 128 bytes, aligned to 64 in
   a kd-tree. The first cache line holds the writer's fields and what the
   glossy criteria read, the second the glossy part itself. Its head lives
   in its leaf block. */
typedef struct lightvec__item {
    float pos[3];                    /* B */
    float inv_glossy_distance;       /* 1 / d_g; 0 = no glossy part */
    float normal[3], rel_gradient;   /* n_B and |grad Y| / Y (luminance) */
    float radius;                    /* R_B as the writer knows it; readers read the leaf block's row */
    uint32_t id;
    float cos_dir;                   /* this record's S_dir (from its lobe) */
    float rel_glossy_gradient;       /* |dY(G)/dw_r| / Y(G) (luminance) times the glossy share */
    float exponent;                  /* of the lobe of G */
    float outgoing[3];               /* sigma; 64 bytes so far */
    float glossy[3];                 /* G(sigma) */
    float glossy_gradient[3][3];     /* dG/dw_r */
    float pad[4];
} lightvec__item;

/* A record's head and item together: what the writer builds and moves. */
typedef struct lightvec__entry {
    lightvec__head head;
    lightvec__item item;
} lightvec__entry;

#define LIGHTVEC__ITEM_LIT 1u        /* visibility 1: every light sample seen (DLV) */
#define LIGHTVEC__ITEM_UMBRA 2u      /* visibility 0: none seen */
#define LIGHTVEC__ITEM_GLOSSY 4u     /* a glossy part (inv_glossy_distance > 0) */

/* A balanced kd-tree over items (median splits on the axis of largest
   extent of the positions), its leaves LEAF consecutive items, every leaf
   full but the last. It is built binary: node i has children 2i+1, 2i+2
   and covers a range of leaves: [a, b) splits at a + (b - a) / 2; one leaf
   is a leaf. Each node has the box of its items' validity spheres
   (B +- R_B), so a query for A descends only into boxes that contain A.
   Stored, three binary levels make one node of up to eight children (the
   binary descendants three levels down, or the leaves above them), their
   boxes in rows, so that a query tests eight boxes with a few SIMD
   compares and one branch per child that holds A (the binary descent
   took one unpredictable branch per box). What the criteria read of a
   leaf's items is one block of rows (LIGHTVEC__ROW_*, LEAF floats each):
   a leaf's tests read a few consecutive cache lines, the first two
   (NEAR_ROWS: positions and R0) alone where no sphere holds A. The block holds its
   items' heads too, so the interpolation of a valid record reads a line
   next to them, and an item only for a valid glossy part. */
#define LIGHTVEC__ROW_X 0
#define LIGHTVEC__ROW_Y 1
#define LIGHTVEC__ROW_Z 2
#define LIGHTVEC__ROW_R0 3           /* R_B when the block was written: never changes (R_B <= R0) */
#define LIGHTVEC__ROW_SX 4           /* sigma */
#define LIGHTVEC__ROW_SY 5
#define LIGHTVEC__ROW_SZ 6
#define LIGHTVEC__ROW_NX 7           /* n_B */
#define LIGHTVEC__ROW_NY 8
#define LIGHTVEC__ROW_NZ 9
#define LIGHTVEC__ROW_REL 10         /* |grad Y| / Y */
#define LIGHTVEC__ROW_GLOSSY 11      /* 1 / d_g; 0 = no glossy part */
#define LIGHTVEC__ROW_ID 12          /* the record's id, its uint32_t bits */
#define LIGHTVEC__ROW_R 13           /* R_B: atomic (neighbour clamping shrinks it under readers) */
#define LIGHTVEC__ROWS 14
#define LIGHTVEC__NEAR_ROWS 4        /* rows X, Y, Z, R0 (the first two cache lines): can a slot's sphere hold A */
#define LIGHTVEC__BLOCK (LIGHTVEC__ROWS * LIGHTVEC__LEAF)

/* A leaf's block: its rows, then a copy of its items' heads. The
   interpolation reads a kept record's head here, beside the rows the
   criteria have just read (the same page, in the hardware prefetchers'
   stream), instead of from the record itself: one memory round trip less
   per valid record in a random query order. */
typedef struct lightvec__block {
    float row[LIGHTVEC__BLOCK];
    lightvec__head head[LIGHTVEC__LEAF];
} lightvec__block;

#define LIGHTVEC__KD_WIDTH 8         /* children per stored kd-tree node: three binary levels */
#define LIGHTVEC__KD_LEAF 0x80000000u /* a child reference to a leaf: KD_LEAF | leaf index */
#define LIGHTVEC__KD_STACK ((LIGHTVEC__KD_WIDTH - 1) * 11 + 1) /* 11 >= levels / 3 + 1 for 2^29 leaves */

typedef struct lightvec__kd_node {
    float box[6][LIGHTVEC__KD_WIDTH];    /* rows lo x, lo y, lo z, hi x, hi y, hi z; column = child.
                                            An unused child has lo = +inf, hi = -inf */
    uint32_t child[LIGHTVEC__KD_WIDTH];  /* node index or KD_LEAF | leaf index */
    uint32_t leaves;                     /* bit j: child j is a leaf */
    uint32_t pad[LIGHTVEC__KD_WIDTH - 1]; /* 256 bytes: a node on four cache lines of its own */
} lightvec__kd_node;

typedef struct lightvec__tree {
    uint32_t count, node_count;
    lightvec__kd_node *nodes;        /* node 0 is the root */
    lightvec__block *blocks;         /* one per leaf */
    lightvec__item *items;           /* count items, leaf after leaf */
    size_t bytes;
} lightvec__tree;

typedef struct lightvec__index {
    uint32_t tree_count;
    uint32_t tail_count;             /* atomic: items of tail[] published */
    lightvec__tree *trees[LIGHTVEC__MAX_TREES];   /* ascending sizes */
    lightvec__block tail_blocks[LIGHTVEC__TAIL / LIGHTVEC__LEAF];
    lightvec__item tail[LIGHTVEC__TAIL];
} lightvec__index;

/* A face of the recursive icosahedron: a spherical triangle, the cap that
   bounds it, and either four children or the index of its records. */
typedef struct lightvec__face {
    float v[3][3];                   /* unit vertices, counter-clockwise from outside */
    float center[3];                 /* normalised vertex sum */
    float cos_r, sin_r, r_angle;     /* bounding cap around center */
    float edge[3][3][3];             /* per edge i (v_i, v_i+1): unit normal of its great
                                        circle, n x v_i and v_i+1 x n */
    float plane[3][3];               /* separate the corner children (set when split) */
    void *children;                  /* atomic: lightvec__face[4], NULL for a leaf */
    void *index;                     /* atomic: lightvec__index, NULL while empty */
    uint32_t depth;
    uint32_t count;                  /* records of a leaf (writer only) */
} lightvec__face;

typedef struct lightvec__retired { void *ptr; size_t bytes; } lightvec__retired;

/* Reader registration: the epoch and each counter on its own cache line. A
   separate block, so that the read-only queries take a const cache: the
   registration is the only state a reader writes. */
typedef struct lightvec__readers {
    uint32_t epoch;
    char pad[60];
    uint32_t count[2][16];
} lightvec__readers;

struct lightvec_cache {
    lightvec_allocator a;
    lightvec__params p;
    lightvec_parallel_for_fn parallel_for;
    void *parallel_user;
    lightvec_progress_fn progress;
    void *progress_user;
    lightvec_log_fn log;
    void *log_user;
    lightvec__face roots[20];
    lightvec__face omni;             /* view-independent records: one leaf, never split */
    lightvec_record *chunks[LIGHTVEC__CHUNKS];
    float *radii[LIGHTVEC__CHUNKS];  /* live R_B per record, beside chunks */
    uint32_t record_count;           /* atomic: records stored */
    lightvec__retired *retired;      /* unpublished memory readers may still see */
    uint32_t retired_count, retired_capacity;
    size_t retired_bytes;
    lightvec__readers *readers;      /* reader registration (readers of a const cache write it) */
};

/* ---- parameters and validation -------------------------------------------- */

static lightvec_result lightvec__params_init(lightvec__params *p, const lightvec_cache_desc *d)
{
    int direct;
    double a;
    if (d->kind != LIGHTVEC_KIND_DEFAULT && d->kind != LIGHTVEC_KIND_INDIRECT && d->kind != LIGHTVEC_KIND_DIRECT)
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    if ((unsigned)d->interpolation > (unsigned)LIGHTVEC_INTERPOLATION_GRADIENT) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    if (!isfinite(d->radius_scale) || d->radius_scale < 0.0f || d->radius_scale > 1e6f ||
        !isfinite(d->max_irradiance_change) || d->max_irradiance_change < 0.0f ||
        !isfinite(d->max_normal_angle) || d->max_normal_angle < 0.0f || d->max_normal_angle > 180.0f ||
        (d->max_normal_angle > 0.0f && d->max_normal_angle < 0.1f) ||
        !isfinite(d->max_direction_angle) || d->max_direction_angle < 0.0f || d->max_direction_angle > 180.0f ||
        (d->max_direction_angle > 0.0f && d->max_direction_angle < LIGHTVEC__MIN_DIRECTION_ANGLE) ||
        d->max_face_depth > LIGHTVEC__MAX_FACE_DEPTH || d->max_neighbors > LIGHTVEC__MAX_NEIGHBORS ||
        !isfinite(d->front_tolerance) || d->front_tolerance < 0.0f || (d->flags & ~LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP))
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    direct = d->kind == LIGHTVEC_KIND_DIRECT;
    p->kind = direct ? LIGHTVEC_KIND_DIRECT : LIGHTVEC_KIND_INDIRECT;
    p->radius_scale = lightvec__def(d->radius_scale, direct ? 0.25f : 0.3f);
    p->max_change = lightvec__def(d->max_irradiance_change, direct ? 0.1f : 0.5f);
    p->normal_angle = lightvec__def(d->max_normal_angle, direct ? 10.0f : 20.0f);
    p->direction_angle = lightvec__def(d->max_direction_angle, 15.0f);
    p->front = lightvec__def(d->front_tolerance, 0.05f);
    p->min_valid = lightvec__def(d->min_valid, 3u);
    p->max_neighbors = lightvec__def(d->max_neighbors, 16u);
    p->flags = d->flags;
    p->interpolation = d->interpolation ? d->interpolation : LIGHTVEC_INTERPOLATION_GRADIENT;
    p->split_threshold = lightvec__def(d->face_split_threshold, 8192u);
    p->max_depth = lightvec__def(d->max_face_depth, 8u);
    a = p->normal_angle * (LIGHTVEC__PI / 180.0);
    p->cos_normal = (float)cos(a);
    p->inv_normal = 1.0f / (1.0f - p->cos_normal);
    a = p->direction_angle * (LIGHTVEC__PI / 180.0);
    p->dir_angle = (float)a;
    p->cos_dir = (float)cos(a);
    p->sin_dir = (float)sin(a);
    p->inv_dir = 1.0f / (1.0f - p->cos_dir);
    return LIGHTVEC_OK;
}

/* A unit vector, or zero for a zero input (an absent glossy light vector);
   0 for anything else. */
static int lightvec__unit_or_zero(const float *in, float out[3])
{
    lightvec__vec3 v;
    if (in[0] == 0.0f && in[1] == 0.0f && in[2] == 0.0f) {
        out[0] = out[1] = out[2] = 0.0f;
        return 1;
    }
    if (!lightvec__unit(in, &v)) return 0;
    out[0] = v.x; out[1] = v.y; out[2] = v.z;
    return 1;
}

/* A record fit for the cache, with its unit vectors normalised and its
   radius set to radius_scale * d_avg. */
static int lightvec__record_clean(const lightvec__params *p, const lightvec_record *r, lightvec_record *out)
{
    lightvec__vec3 n, o, d;
    float g[3];
    int c;
    if ((r->flags & ~LIGHTVEC_RECORD_VIEW_INDEPENDENT) || !lightvec__finite3(r->position) ||
        !lightvec__unit(r->normal, &n) || !lightvec__unit(r->vector.direction, &d) ||
        !lightvec__unit_or_zero(r->vector.glossy_direction, g))
        return 0;
    if (r->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) o = n;
    else if (!lightvec__unit(r->outgoing, &o)) return 0;
    if (!lightvec__finite_nonneg(r->vector.magnitude, 3) || !lightvec__finite_nonneg(r->irradiance, 3) ||
        !lightvec__finite_nonneg(r->vector.glossy_magnitude, 3) || !lightvec__finite_nonneg(r->glossy, 3))
        return 0;
    for (c = 0; c < 3; c++)
        if (!lightvec__finite3(r->gradient[c]) || !lightvec__finite3(r->glossy_gradient[c])) return 0;
    if (!isfinite(r->distance) || !(r->distance > 0.0f) || r->distance > LIGHTVEC__FAR ||
        !isfinite(r->glossy_distance) || r->glossy_distance < 0.0f || r->glossy_distance > LIGHTVEC__FAR ||
        !isfinite(r->exponent) || r->exponent < 0.0f || r->exponent > 1e6f ||
        !(r->glossy_share >= 0.0f && r->glossy_share <= 1.0f) ||
        !(r->visibility >= 0.0f && r->visibility <= 1.0f))
        return 0;
    *out = *r;
    out->normal[0] = n.x; out->normal[1] = n.y; out->normal[2] = n.z;
    out->outgoing[0] = o.x; out->outgoing[1] = o.y; out->outgoing[2] = o.z;
    out->vector.direction[0] = d.x; out->vector.direction[1] = d.y; out->vector.direction[2] = d.z;
    memcpy(out->vector.glossy_direction, g, sizeof g);
    out->radius = lightvec__minf(p->radius_scale * r->distance, FLT_MAX);
    return 1;
}

/* The glossy share of a record, 0 read as 1. */
static float lightvec__share(const lightvec_record *r)
{
    return r->glossy_share > 0.0f ? r->glossy_share : 1.0f;
}

/* S_dir of a record's glossy part: the angle its lobe tolerates
   (lightvec_direction_angle) over sqrt(glossy share): the first-order
   remainder grows as the angle squared and counts in the radiance in
   proportion to the share. Never wider than the cache's max_direction_angle
   (the cone its faces are searched in). */
static float lightvec__record_cos_dir(const lightvec__params *p, const lightvec_record *r)
{
    double a;
    if (!(r->glossy_distance > 0.0f)) return p->cos_dir;
    a = lightvec_direction_angle(r->exponent) * (LIGHTVEC__PI / 180.0) / sqrt((double)lightvec__share(r));
    return a < (double)p->dir_angle ? (float)cos(a) : p->cos_dir;
}

static void lightvec__make_item(const lightvec__params *p, const lightvec_record *r, uint32_t id,
                                lightvec__entry *e)
{
    lightvec__item *it = &e->item;
    lightvec__head *h = &e->head;
    lightvec__vec3 g = lightvec__v3(0.0f, 0.0f, 0.0f);
    float y = lightvec__lumf(r->irradiance), gl;
    int c;
    static const float w[3] = { 0.2126f, 0.7152f, 0.0722f };
    memset(e, 0, sizeof *e);
    for (c = 0; c < 3; c++) g = lightvec__add(g, lightvec__scale(lightvec__v3_load(r->gradient[c]), w[c]));
    gl = lightvec__length(g);
    memcpy(it->pos, r->position, sizeof it->pos);
    it->radius = r->radius;
    memcpy(it->normal, r->normal, sizeof it->normal);
    it->rel_gradient = y > 0.0f ? lightvec__minf(gl / y, FLT_MAX) : (gl > 0.0f ? FLT_MAX : 0.0f);
    memcpy(it->outgoing, r->outgoing, sizeof it->outgoing);
    it->cos_dir = lightvec__record_cos_dir(p, r);
    it->inv_glossy_distance = r->glossy_distance > 0.0f ? 1.0f / r->glossy_distance : 0.0f;
    it->exponent = r->exponent;
    h->kind = (r->visibility >= 1.0f ? LIGHTVEC__ITEM_LIT : 0u) | (r->visibility <= 0.0f ? LIGHTVEC__ITEM_UMBRA : 0u) |
                    (it->inv_glossy_distance > 0.0f ? LIGHTVEC__ITEM_GLOSSY : 0u);
    memcpy(h->dir, r->vector.direction, sizeof h->dir);
    if (p->interpolation == LIGHTVEC_INTERPOLATION_PLAIN) {
        memcpy(h->mag, r->vector.magnitude, sizeof h->mag);
    } else {
        float cos_nd = lightvec__maxf(0.0f, lightvec__dot(lightvec__v3_load(r->normal), lightvec__v3_load(r->vector.direction)));
        for (c = 0; c < 3; c++) h->mag[c] = r->vector.magnitude[c] * cos_nd;
    }
    for (c = 0; c < 3; c++) {
        float e = r->irradiance[c];
        int k;
        float *slope = h->slope[c];
        for (k = 0; k < 3; k++) slope[k] = e > 0.0f ? r->gradient[c][k] / e : 0.0f;
        if (!lightvec__finite3(slope)) slope[0] = slope[1] = slope[2] = 0.0f;
    }
    memcpy(it->glossy, r->glossy, sizeof it->glossy);
    memcpy(it->glossy_gradient, r->glossy_gradient, sizeof it->glossy_gradient);
    g = lightvec__v3(0.0f, 0.0f, 0.0f);
    for (c = 0; c < 3; c++) g = lightvec__add(g, lightvec__scale(lightvec__v3_load(r->glossy_gradient[c]), w[c]));
    gl = lightvec__length(g);
    y = lightvec__lumf(r->glossy);
    /* the change of G relative to the radiance: |grad Y(G)| / Y(G) times the share */
    it->rel_glossy_gradient = y > 0.0f ? lightvec__minf(gl / y * lightvec__share(r), FLT_MAX) : (gl > 0.0f ? FLT_MAX : 0.0f);
    it->id = id;
}

/* ---- record chunks ----------------------------------------------------------- */

/* Record id lives in chunk k at offset o (chunk k holds CHUNK0 << k records). */
static uint32_t lightvec__chunk_of(uint32_t id, uint32_t *offset)
{
    uint64_t q = (uint64_t)id / LIGHTVEC__CHUNK0 + 1u;
    uint32_t k = 0;
    while ((q >> (k + 1)) != 0) k++;
    *offset = (uint32_t)(id - (uint64_t)LIGHTVEC__CHUNK0 * ((1ull << k) - 1u));
    return k;
}

static lightvec_record *lightvec__record_at(const lightvec_cache *c, uint32_t id)
{
    uint32_t o, k = lightvec__chunk_of(id, &o);
    return c->chunks[k] + o;
}

/* The live validity radius of record id (neighbour clamping may shrink it
   after the record is published: read and written atomically). */
static float *lightvec__radius_at(const lightvec_cache *c, uint32_t id)
{
    uint32_t o, k = lightvec__chunk_of(id, &o);
    return c->radii[k] + o;
}

/* The slot of record id (the next one), allocating its chunk. */
static lightvec_record *lightvec__record_reserve(lightvec_cache *c, uint32_t id)
{
    uint32_t o, k = lightvec__chunk_of(id, &o);
    if (k >= LIGHTVEC__CHUNKS) return NULL;
    if (!c->chunks[k]) {
        lightvec_record *rec = (lightvec_record *)lightvec__alloc_array(&c->a, (size_t)LIGHTVEC__CHUNK0 << k,
                                                                        sizeof(lightvec_record));
        float *radii = (float *)lightvec__alloc_array(&c->a, (size_t)LIGHTVEC__CHUNK0 << k, sizeof(float));
        if (!rec || !radii) {
            lightvec__free(&c->a, rec);
            lightvec__free(&c->a, radii);
            return NULL;
        }
        c->chunks[k] = rec;
        c->radii[k] = radii;
    }
    return c->chunks[k] + o;
}

/* ---- kd-tree ------------------------------------------------------------------- */

/* Writes item it into slot k of a leaf block. */
static void lightvec__block_put(lightvec__block *block, uint32_t k, const lightvec__entry *e)
{
    const lightvec__item *it = &e->item;
    float *b = block->row + k;
    block->head[k] = e->head;
    b[LIGHTVEC__ROW_X * LIGHTVEC__LEAF] = it->pos[0];
    b[LIGHTVEC__ROW_Y * LIGHTVEC__LEAF] = it->pos[1];
    b[LIGHTVEC__ROW_Z * LIGHTVEC__LEAF] = it->pos[2];
    b[LIGHTVEC__ROW_R * LIGHTVEC__LEAF] = it->radius;
    b[LIGHTVEC__ROW_R0 * LIGHTVEC__LEAF] = it->radius;
    b[LIGHTVEC__ROW_SX * LIGHTVEC__LEAF] = it->outgoing[0];
    b[LIGHTVEC__ROW_SY * LIGHTVEC__LEAF] = it->outgoing[1];
    b[LIGHTVEC__ROW_SZ * LIGHTVEC__LEAF] = it->outgoing[2];
    b[LIGHTVEC__ROW_NX * LIGHTVEC__LEAF] = it->normal[0];
    b[LIGHTVEC__ROW_NY * LIGHTVEC__LEAF] = it->normal[1];
    b[LIGHTVEC__ROW_NZ * LIGHTVEC__LEAF] = it->normal[2];
    b[LIGHTVEC__ROW_REL * LIGHTVEC__LEAF] = it->rel_gradient;
    b[LIGHTVEC__ROW_GLOSSY * LIGHTVEC__LEAF] = it->inv_glossy_distance;
    memcpy(&b[LIGHTVEC__ROW_ID * LIGHTVEC__LEAF], &it->id, sizeof it->id);
}

/* Leaves over n items: every leaf full but the last. */
static uint32_t lightvec__leaf_count(uint32_t n) { return (n + LIGHTVEC__LEAF - 1) / LIGHTVEC__LEAF; }

static uint32_t lightvec__tree_levels(uint32_t leaves)
{
    uint32_t d = 0;
    while (leaves > 1) { leaves -= leaves / 2; d++; }
    return d;
}

/* What the build of a kd-tree reads of an item, 20 bytes: the build moves
   these (its quickselects and boxes read consecutive memory) instead of a
   permutation of 192-byte entries, which it would read scattered. */
typedef struct lightvec__key {
    float pos[3], radius;
    uint32_t index;                  /* the entry's */
} lightvec__key;

/* Quickselect on keys[lo, hi) by position on axis: afterwards the k-th
   smallest is at k, smaller keys before, larger after. Three-way
   partition around a median-of-three pivot, robust to equal keys. */
static void lightvec__select(lightvec__key *keys, int axis, uint32_t lo, uint32_t hi, uint32_t k)
{
    while (hi - lo > 1) {
        float a = keys[lo].pos[axis], b = keys[lo + (hi - lo) / 2].pos[axis], c = keys[hi - 1].pos[axis], pivot;
        uint32_t lt = lo, i = lo, gt = hi;
        pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
        while (i < gt) {
            float key = keys[i].pos[axis];
            lightvec__key t;
            if (key < pivot) { t = keys[lt]; keys[lt] = keys[i]; keys[i] = t; lt++; i++; }
            else if (key > pivot) { gt--; t = keys[gt]; keys[gt] = keys[i]; keys[i] = t; }
            else i++;
        }
        if (k < lt) hi = lt;
        else if (k >= gt) lo = gt;
        else return;
    }
}

/* Box of the validity spheres of keys[lo, hi), widened by a relative 1e-6 so
   that the float test d^2 < R^2 never accepts a point the box rejects; the
   axis of the positions' largest extent. */
static int lightvec__tree_box(float *box, const lightvec__key *keys, uint32_t lo, uint32_t hi)
{
    float blo[3], bhi[3], clo[3], chi[3];
    uint32_t i;
    int k, axis = 0;
    lightvec__box_empty(blo, bhi);
    lightvec__box_empty(clo, chi);
    for (i = lo; i < hi; i++) {
        const lightvec__key *it = &keys[i];
        for (k = 0; k < 3; k++) {
            float tol = (fabsf(it->pos[k]) + it->radius) * 1e-6f;
            blo[k] = lightvec__minf(blo[k], it->pos[k] - it->radius - tol);
            bhi[k] = lightvec__maxf(bhi[k], it->pos[k] + it->radius + tol);
            clo[k] = lightvec__minf(clo[k], it->pos[k]);
            chi[k] = lightvec__maxf(chi[k], it->pos[k]);
        }
    }
    memcpy(box, blo, sizeof blo);
    memcpy(box + 3, bhi, sizeof bhi);
    for (k = 1; k < 3; k++)
        if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    return axis;
}

/* Binary node `node` over leaves [a, b) of n items: its box (6 floats at
   boxes + 6 node), then its halves. */
static void lightvec__tree_build_node(float *boxes, uint32_t n, lightvec__key *keys, uint32_t node, uint32_t a, uint32_t b)
{
    uint32_t lo = a * LIGHTVEC__LEAF, hi = b * LIGHTVEC__LEAF < n ? b * LIGHTVEC__LEAF : n;
    uint32_t m = a + (b - a) / 2;
    int axis = lightvec__tree_box(boxes + 6 * (size_t)node, keys, lo, hi);
    if (b - a <= 1) return;
    lightvec__select(keys, axis, lo, hi, m * LIGHTVEC__LEAF);
    lightvec__tree_build_node(boxes, n, keys, 2 * node + 1, a, m);
    lightvec__tree_build_node(boxes, n, keys, 2 * node + 2, m, b);
}

typedef struct lightvec__kd_span { uint32_t node, a, b; } lightvec__kd_span; /* binary node over leaves [a, b) */

/* The children of the stored node made of binary node s: its descendants
   three levels down, a leaf above them standing for itself, left to right. */
static uint32_t lightvec__kd_frontier(lightvec__kd_span s, lightvec__kd_span out[LIGHTVEC__KD_WIDTH])
{
    lightvec__kd_span cur[LIGHTVEC__KD_WIDTH];
    uint32_t n = 1, level, i;
    cur[0] = s;
    for (level = 0; level < 3; level++) {
        uint32_t m = 0;
        for (i = 0; i < n; i++) {
            lightvec__kd_span c = cur[i];
            uint32_t mid = c.a + (c.b - c.a) / 2;
            if (c.b - c.a <= 1) { out[m++] = c; continue; }
            out[m].node = 2 * c.node + 1; out[m].a = c.a; out[m].b = mid; m++;
            out[m].node = 2 * c.node + 2; out[m].a = mid; out[m].b = c.b; m++;
        }
        memcpy(cur, out, m * sizeof *cur);
        n = m;
    }
    return n;
}

/* The stored node of binary node s at t->nodes[*next], its subtrees after
   it (depth first). With t->nodes NULL it only counts the nodes. */
static void lightvec__kd_collapse(lightvec__tree *t, const float *boxes, lightvec__kd_span s, uint32_t *next)
{
    lightvec__kd_span f[LIGHTVEC__KD_WIDTH];
    uint32_t n = lightvec__kd_frontier(s, f), self = (*next)++, j, r;
    for (j = 0; j < n; j++) {
        uint32_t ref = LIGHTVEC__KD_LEAF | f[j].a;
        if (f[j].b - f[j].a > 1) {
            ref = *next;
            lightvec__kd_collapse(t, boxes, f[j], next);
        }
        if (t->nodes) t->nodes[self].child[j] = ref;
    }
    if (!t->nodes) return;
    for (j = 0; j < LIGHTVEC__KD_WIDTH; j++) {
        for (r = 0; r < 3; r++) {
            t->nodes[self].box[r][j] = j < n ? boxes[6 * (size_t)f[j].node + r] : INFINITY;
            t->nodes[self].box[3 + r][j] = j < n ? boxes[6 * (size_t)f[j].node + 3 + r] : -INFINITY;
        }
        if (j >= n) t->nodes[self].child[j] = 0;
    }
    t->nodes[self].leaves = 0;
    for (j = 0; j < n; j++) t->nodes[self].leaves |= (unsigned)((t->nodes[self].child[j] & LIGHTVEC__KD_LEAF) != 0) << j;
    memset(t->nodes[self].pad, 0, sizeof t->nodes[self].pad);
}

static lightvec__tree *lightvec__tree_build(const lightvec_allocator *a, const lightvec__entry *src, uint32_t n)
{
    uint32_t leaves = lightvec__leaf_count(n), binary = (2u << lightvec__tree_levels(leaves)) - 1u, nodes = 0, i;
    size_t head = (sizeof(lightvec__tree) + 63u) & ~(size_t)63u, node_bytes, block_bytes, bytes;
    lightvec__kd_span root;
    lightvec__tree *t, shape;
    lightvec__key *keys;
    float *boxes;
    if ((size_t)leaves > (SIZE_MAX - head - 128u) / (sizeof(lightvec__kd_node) + sizeof(lightvec__block) +
                                                      LIGHTVEC__LEAF * sizeof(lightvec__item)))
        return NULL;
    root.node = 0; root.a = 0; root.b = leaves;
    shape.nodes = NULL;
    if (n) lightvec__kd_collapse(&shape, NULL, root, &nodes);   /* at most leaves nodes */
    node_bytes = (size_t)nodes * sizeof(lightvec__kd_node);
    block_bytes = (size_t)leaves * sizeof(lightvec__block);
    bytes = head + node_bytes + block_bytes + (size_t)n * sizeof(lightvec__item) + 64u; /* + room to align */
    t = (lightvec__tree *)lightvec__alloc(a, bytes);
    keys = (lightvec__key *)lightvec__alloc_array(a, n, sizeof *keys);
    boxes = (float *)lightvec__alloc_array(a, binary, 6u * sizeof(float));
    if (!t || !keys || !boxes) {
        lightvec__free(a, t);
        lightvec__free(a, keys);
        lightvec__free(a, boxes);
        return NULL;
    }
    t->count = n;
    t->node_count = nodes;
    t->nodes = (lightvec__kd_node *)((char *)t + head);   /* 256-byte nodes after a 64-byte aligned head */
    t->nodes = (lightvec__kd_node *)((char *)t->nodes + ((64u - ((uintptr_t)t->nodes & 63u)) & 63u));
    t->blocks = (lightvec__block *)(void *)((char *)t->nodes + node_bytes);
    t->items = (lightvec__item *)((char *)t->blocks + block_bytes);
    t->bytes = bytes;
    memset(t->blocks, 0, block_bytes); /* the last leaf's empty slots: radius 0, never inside */
    for (i = 0; i < n; i++) {
        memcpy(keys[i].pos, src[i].item.pos, sizeof keys[i].pos);
        keys[i].radius = src[i].item.radius;
        keys[i].index = i;
    }
    if (n) {
        lightvec__tree_build_node(boxes, n, keys, 0, 0, leaves);
        nodes = 0;
        lightvec__kd_collapse(t, boxes, root, &nodes);
    }
    for (i = 0; i < n; i++) {
        t->items[i] = src[keys[i].index].item;
        lightvec__block_put(&t->blocks[i / LIGHTVEC__LEAF], i % LIGHTVEC__LEAF, &src[keys[i].index]);
    }
    lightvec__free(a, boxes);
    lightvec__free(a, keys);
    return t;
}

/* The children of node nd whose box, grown by reach on every side, holds p
   (reach 0: the boxes holding p), as a bit mask. Exact compares: the SIMD
   and the scalar kernel agree bit for bit. With AVX, all eight children in
   one step. */
static unsigned lightvec__kd_hits(const lightvec__kd_node *nd, const float p[3], float reach)
{
    unsigned mask = 0;
#if defined(LIGHTVEC__SSE) && defined(__AVX__)
    const __m256 g = _mm256_set1_ps(reach);
    __m256 in = _mm256_and_ps(
        _mm256_and_ps(_mm256_cmp_ps(_mm256_sub_ps(_mm256_loadu_ps(nd->box[0]), g), _mm256_set1_ps(p[0]), _CMP_LE_OQ),
                      _mm256_cmp_ps(_mm256_sub_ps(_mm256_loadu_ps(nd->box[1]), g), _mm256_set1_ps(p[1]), _CMP_LE_OQ)),
        _mm256_and_ps(_mm256_cmp_ps(_mm256_sub_ps(_mm256_loadu_ps(nd->box[2]), g), _mm256_set1_ps(p[2]), _CMP_LE_OQ),
                      _mm256_cmp_ps(_mm256_set1_ps(p[0]), _mm256_add_ps(_mm256_loadu_ps(nd->box[3]), g), _CMP_LE_OQ)));
    in = _mm256_and_ps(in, _mm256_and_ps(
        _mm256_cmp_ps(_mm256_set1_ps(p[1]), _mm256_add_ps(_mm256_loadu_ps(nd->box[4]), g), _CMP_LE_OQ),
        _mm256_cmp_ps(_mm256_set1_ps(p[2]), _mm256_add_ps(_mm256_loadu_ps(nd->box[5]), g), _CMP_LE_OQ)));
    mask = (unsigned)_mm256_movemask_ps(in);
#elif LIGHTVEC__SIMD
    const lightvec__f4 px = lightvec__f4_set(p[0]), py = lightvec__f4_set(p[1]), pz = lightvec__f4_set(p[2]);
    const lightvec__f4 g = lightvec__f4_set(reach);
    int i;
    for (i = 0; i < LIGHTVEC__KD_WIDTH; i += 4) {
        lightvec__m4 in = lightvec__m4_and(
            lightvec__m4_and(lightvec__f4_le(lightvec__f4_sub(lightvec__f4_load(nd->box[0] + i), g), px),
                             lightvec__f4_le(lightvec__f4_sub(lightvec__f4_load(nd->box[1] + i), g), py)),
            lightvec__m4_and(lightvec__f4_le(lightvec__f4_sub(lightvec__f4_load(nd->box[2] + i), g), pz),
                             lightvec__f4_le(px, lightvec__f4_add(lightvec__f4_load(nd->box[3] + i), g))));
        in = lightvec__m4_and(in, lightvec__m4_and(lightvec__f4_le(py, lightvec__f4_add(lightvec__f4_load(nd->box[4] + i), g)),
                                                   lightvec__f4_le(pz, lightvec__f4_add(lightvec__f4_load(nd->box[5] + i), g))));
        mask |= lightvec__m4_bits(in) << i;
    }
#else
    int i;
    for (i = 0; i < LIGHTVEC__KD_WIDTH; i++)
        mask |= (unsigned)((nd->box[0][i] - reach <= p[0]) & (nd->box[1][i] - reach <= p[1]) &
                           (nd->box[2][i] - reach <= p[2]) & (p[0] <= nd->box[3][i] + reach) &
                           (p[1] <= nd->box[4][i] + reach) & (p[2] <= nd->box[5][i] + reach)) << i;
#endif
    return mask;
}

typedef void (*lightvec__leaf_fn)(void *ctx, const lightvec__tree *t, uint32_t leaf);

/* A child about to be read: a node whole, a leaf block's NEAR_ROWS (its
   first two lines, what lightvec__block_near reads; lightvec__drain loads
   the rest where a sphere holds A). */
static void lightvec__prefetch_child(const lightvec__tree *t, uint32_t child)
{
    const char *next = child & LIGHTVEC__KD_LEAF ? (const char *)&t->blocks[child & ~LIGHTVEC__KD_LEAF]
                                                 : (const char *)&t->nodes[child];
    LIGHTVEC__PREFETCH(next);
    LIGHTVEC__PREFETCH(next + 64);
    if (!(child & LIGHTVEC__KD_LEAF)) {
        LIGHTVEC__PREFETCH(next + 128);
        LIGHTVEC__PREFETCH(next + 192);
    }
}

/* Calls leaf(ctx, t, i) for every leaf i of t whose box, grown by reach,
   holds p, in the order of the leaves, depth first. The children a node
   holds p in are prefetched at once. When they are all leaves (the nodes
   of the last level), the leaves are handed over at once, in order; when
   they are all nodes, they are pushed last first, so that they pop in
   order; a node with both pushes both. So the stack holds leaves only
   under those rare nodes, and a pop is a node but for them: the branch on
   what a pop holds, which a walk alternating between leaves and nodes
   mispredicts, goes the same way nearly always. */
static void lightvec__tree_walk(const lightvec__tree *t, const float p[3], float reach, lightvec__leaf_fn leaf, void *ctx)
{
    uint32_t stack[LIGHTVEC__KD_STACK], top = 0;
    if (!t->count) return;
    stack[top++] = 0;
    while (top) {
        uint32_t ref = stack[--top];
        const lightvec__kd_node *nd;
        unsigned mask, m;
        if (ref & LIGHTVEC__KD_LEAF) {
            leaf(ctx, t, ref & ~LIGHTVEC__KD_LEAF);
            continue;
        }
        nd = &t->nodes[ref];
        mask = lightvec__kd_hits(nd, p, reach);
        for (m = mask; m; m &= m - 1) lightvec__prefetch_child(t, nd->child[lightvec__bvh_first_bit(m)]);
        if ((mask & nd->leaves) == mask) {
            for (; mask; mask &= mask - 1) leaf(ctx, t, nd->child[lightvec__bvh_first_bit(mask)] & ~LIGHTVEC__KD_LEAF);
            continue;
        }
        for (; mask; mask &= ~(1u << lightvec__kd_last_bit(mask))) stack[top++] = nd->child[lightvec__kd_last_bit(mask)];
    }
}

/* ---- queries -------------------------------------------------------------------- */

/* A leaf block waiting for its visit: its first `count` items. */
#define LIGHTVEC__PENDING 64u
typedef struct lightvec__block_ref {
    const lightvec__block *block;
    const lightvec__item *items;
    uint32_t count;
    int full;                        /* a kd-tree leaf (not a tail block) */
} lightvec__block_ref;

/* A valid record kept for the interpolation (40 bytes). Its rank, kept
   apart, is the bits of w above ~id: w >= +0, whose bits order as it does,
   then the smaller id. */
typedef struct lightvec__candidate {
    float w;                         /* the diffuse vector's weight, w_B w_sigma (the cache's S_dir) */
    float wg;                        /* the glossy part's, w_B w_sigma (the record's S_dir); 0 = not valid */
    float d[3];                      /* A - B */
    const lightvec__head *head;      /* the copy in its leaf block */
    const lightvec__item *it;
} lightvec__candidate;

#define LIGHTVEC__KEPT_SLACK 48u     /* candidates a lookup gathers beyond max_neighbors before it selects */

typedef struct lightvec__query {
    float a[3], n[3], w[3];          /* A, n_A, w */
    float mirror[3];                 /* w mirrored about n_A: the axis of A's lobe */
    int directional;                 /* 0: view-independent query */
    const lightvec__params *p;
    uint32_t count;                  /* valid records */
    uint32_t *ids;                   /* lightvec_find: every valid record, up to capacity */
    float *weights;
    uint32_t capacity;
    lightvec__candidate *kept;       /* lightvec_lookup: candidates for the `best` of largest rank, */
    uint64_t *ranks;                 /* and their ranks */
    uint32_t kept_count, best;       /* best = max_neighbors; room for best + KEPT_SLACK */
    uint64_t floor;                  /* a rank below it has `best` larger ones already (0: none yet) */
    lightvec__block_ref *pending;    /* blocks the walk reached, not visited yet (none between searches) */
    uint32_t pending_count;
} lightvec__query;

/* The angle psi over which record B's glossy part is carried to A's view w:
   the view change |w - sigma| (the chord, the angle to second order) plus
   the parallax of the move from B to A as seen along A's lobe. A point
   A + t m seen from B lies in direction m + (A - B)_perp / t, so the move
   turns what the lobe sees by |(A - B)_perp| / t; d_g, the lobe's harmonic
   mean distance, weighs the nearest surfaces most and bounds it from above.
   The two add (their directions are not known to agree): a conservative
   bound, used for validity only. The view change itself is extrapolated
   with the view gradient, the parallax is not (a single distance cannot
   say how a lobe that sees near and far surfaces shifts). */
static float lightvec__glossy_angle(const lightvec__query *q, const float sigma[3], float inv_dg, float dx, float dy,
                                    float dz)
{
    float vx = q->w[0] - sigma[0], vy = q->w[1] - sigma[1], vz = q->w[2] - sigma[2];
    float along = dx * q->mirror[0] + dy * q->mirror[1] + dz * q->mirror[2];
    float px = dx - along * q->mirror[0], py = dy - along * q->mirror[1], pz = dz - along * q->mirror[2];
    return sqrtf(vx * vx + vy * vy + vz * vz) + sqrtf(px * px + py * py + pz * pz) * inv_dg;
}

/* The `best`-th largest of ranks[0, n) (best < n <= MAX_NEIGHBORS +
   KEPT_SLACK), by quickselect on a copy. Each pass splits the ranks around a
   median of three into those above it and the rest without a branch on the
   data (each rank is written to both sides, and the side that takes it
   advances): about 3n compares in all, against n^2 for counting. Ranks are
   distinct, so the pivot's position decides the side to go on with. */
static uint64_t lightvec__rank_threshold(const uint64_t *ranks, uint32_t n, uint32_t best)
{
    uint64_t buf[2][LIGHTVEC__MAX_NEIGHBORS + LIGHTVEC__KEPT_SLACK], *v = buf[0], *rest = buf[1];
    uint32_t i;
    memcpy(v, ranks, n * sizeof *v);
    for (;;) { /* the answer is the best-th largest of v[0, n), 1 <= best <= n */
        uint64_t a = v[0], b = v[n / 2], c = v[n - 1], pivot, *t;
        uint32_t above = 0, below = 0;
        if (n == 1) return v[0];
        pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
        for (i = 0; i < n; i++) {
            uint64_t r = v[i];
            uint32_t up = r > pivot;
            v[above] = r; /* above <= i: v[i] is read before its slot can be written */
            rest[below] = r;
            above += up;
            below += (r < pivot);
        }
        if (best == above + 1) return pivot;
        if (best <= above) {
            n = above;
        } else {
            best -= above + 1;
            n = below;
            t = v; v = rest; rest = t;
        }
    }
}

/* Keeps the `best` candidates of largest rank of kept[0, n) (all n when
   fewer) in kept[0, best), in their order, and returns how many: those at
   or above the best-th largest rank. Ranks are distinct (ids are), so the
   set is the one a bounded heap would keep, and the result depends on the
   candidates' order alone. */
static uint32_t lightvec__select_best(uint64_t *ranks, lightvec__candidate *kept, uint32_t n, uint32_t best)
{
    uint64_t threshold;
    uint32_t i, m = 0;
    if (n <= best) return n;
    threshold = lightvec__rank_threshold(ranks, n, best);
    for (i = 0; i < n; i++) { /* m <= i: slot m is free or i itself */
        ranks[m] = ranks[i];
        kept[m] = kept[i];
        m += ranks[i] >= threshold;
    }
    return m;
}

/* Keeps a valid record: in the ids of lightvec_find, or among the
   candidates for the max_neighbors of largest weight (ties: the smaller
   id) of lightvec_lookup. A candidate is appended unless `best` larger ones
   are known; when the room is full, the best are selected and the rest
   dropped (amortised: once per KEPT_SLACK candidates at most). */
static void lightvec__keep(lightvec__query *q, const lightvec__item *it, const lightvec__head *head, uint32_t id,
                           float w, float wg, float dx, float dy, float dz)
{
    if (q->ids && q->count < q->capacity) {
        q->ids[q->count] = id;
        q->weights[q->count] = w;
    }
    q->count++;
    if (q->kept) {
        lightvec__candidate *c;
        uint32_t bits, i;
        uint64_t rank;
        memcpy(&bits, &w, sizeof bits);
        rank = (uint64_t)bits << 32 | (uint64_t)(0xFFFFFFFFu - id);
        if (rank < q->floor) return;
        if (q->kept_count == q->best + LIGHTVEC__KEPT_SLACK) {
            q->kept_count = lightvec__select_best(q->ranks, q->kept, q->kept_count, q->best);
            for (q->floor = q->ranks[0], i = 1; i < q->kept_count; i++)
                q->floor = q->ranks[i] < q->floor ? q->ranks[i] : q->floor;
            if (rank < q->floor) return;
        }
        q->ranks[q->kept_count] = rank;
        c = &q->kept[q->kept_count++];
        c->w = w;
        c->wg = wg;
        c->d[0] = dx; c->d[1] = dy; c->d[2] = dz;
        c->head = head;
        c->it = it;
        /* the interpolation reads the head: start loading it now (and the
           item's lines of the glossy part when it is valid) */
        LIGHTVEC__PREFETCH(head);
        if (wg > 0.0f) {
            LIGHTVEC__PREFETCH(it);
            LIGHTVEC__PREFETCH((const char *)it + 64);
        }
    }
}

/* What the criteria of 4.2 compute for the slots of a leaf block. */
typedef struct lightvec__slots {
    float dx[LIGHTVEC__LEAF], dy[LIGHTVEC__LEAF], dz[LIGHTVEC__LEAF]; /* A - B */
    float d2[LIGHTVEC__LEAF];        /* |AB|^2 */
    float cs[LIGHTVEC__LEAF];        /* cos(w, sigma) */
    float cn[LIGHTVEC__LEAF];        /* cos(n_A, n_B) */
    float front[LIGHTVEC__LEAF];     /* (A - B) . (n_A + n_B) / 2 */
} lightvec__slots;

/* The tests of the first n slots of a block that need no square root,
   with the radius R0 the block was written with: |AB| < R0, cos(w, sigma)
   > S_dir, cos(n_A, n_B) > S_curv, B not in front of A (Ward 1988: front
   >= -front_tolerance * R0); a bit per slot that passes. Plain reads of
   rows that never change once published, no branch: the loop vectorizes.
   R_B only shrinks (neighbour clamping, under readers) and a smaller radius
   fails more, so the slots that pass are a superset of the valid ones. */
static unsigned lightvec__block_pass(const lightvec__query *q, const float *block, uint32_t n, float cos_dir,
                                     lightvec__slots *s)
{
    unsigned mask = 0;
    uint32_t k;
    for (k = 0; k < n; k++) {
        const float *b = block + k;
        float nx = b[LIGHTVEC__ROW_NX * LIGHTVEC__LEAF], ny = b[LIGHTVEC__ROW_NY * LIGHTVEC__LEAF];
        float nz = b[LIGHTVEC__ROW_NZ * LIGHTVEC__LEAF], r0 = b[LIGHTVEC__ROW_R0 * LIGHTVEC__LEAF];
        float dx = q->a[0] - b[LIGHTVEC__ROW_X * LIGHTVEC__LEAF], dy = q->a[1] - b[LIGHTVEC__ROW_Y * LIGHTVEC__LEAF];
        float dz = q->a[2] - b[LIGHTVEC__ROW_Z * LIGHTVEC__LEAF], d2 = dx * dx + dy * dy + dz * dz;
        float cs = q->w[0] * b[LIGHTVEC__ROW_SX * LIGHTVEC__LEAF] + q->w[1] * b[LIGHTVEC__ROW_SY * LIGHTVEC__LEAF] +
                   q->w[2] * b[LIGHTVEC__ROW_SZ * LIGHTVEC__LEAF];
        float cn = q->n[0] * nx + q->n[1] * ny + q->n[2] * nz;
        float front = 0.5f * (dx * (q->n[0] + nx) + dy * (q->n[1] + ny) + dz * (q->n[2] + nz));
        s->dx[k] = dx; s->dy[k] = dy; s->dz[k] = dz; s->d2[k] = d2;
        s->cs[k] = cs; s->cn[k] = cn; s->front[k] = front;
        mask |= (unsigned)((d2 < r0 * r0) & (cs > cos_dir) & (cn > q->p->cos_normal) &
                           (front >= -q->p->front * r0)) << k;
    }
    return mask;
}

/* The rest of 4.2 for slot k, which passed lightvec__slot_pass: the tests
   again with R_B (read atomically) where it has shrunk since the block was
   written, the irradiance change |AB| |grad E_B| / E_B < I_B, and the
   weights. The diffuse vector's is the paper's w = w_B * w_sigma with the
   cache's S_dir. The glossy part's is w_g = w_B * w_sigma,B / (1 + psi
   |grad G_B| / G_B) with the record's own S_dir (from its lobe), psi from
   lightvec__glossy_angle (cos psi = 1 - psi^2 / 2, the paper's cos(w,
   sigma) exactly without parallax), valid while psi < acos S_dir,B and
   psi |grad G_B| / G_B < I_B: the irradiance-change criterion and weight
   of 4.2.1, applied to G along the angle. w_g = 0 when either fails. */
static void lightvec__visit(lightvec__query *q, const float *block, uint32_t k, const lightvec__item *it,
                            const lightvec__head *head, const lightvec__slots *s, float cos_dir)
{
    const lightvec__params *p = q->p;
    const float *b = block + k;
    float ws = 1.0f, wg = 0.0f, wb, d, change, inv_dg, radius;
    uint32_t id;
    radius = lightvec__load_f32(b + LIGHTVEC__ROW_R * LIGHTVEC__LEAF);
    if (radius != b[LIGHTVEC__ROW_R0 * LIGHTVEC__LEAF] &&
        !(s->d2[k] < radius * radius && s->front[k] >= -p->front * radius))
        return;
    d = sqrtf(s->d2[k]);
    change = d * b[LIGHTVEC__ROW_REL * LIGHTVEC__LEAF];              /* |AB| |grad E| / E_B < I_B */
    if (!(change < p->max_change)) return;
    wb = (1.0f - d / radius) * (1.0f / (1.0f + change)) * ((s->cn[k] - p->cos_normal) * p->inv_normal);
    if (q->directional) ws = (s->cs[k] - cos_dir) * p->inv_dir;      /* 4.2.2 */
    inv_dg = b[LIGHTVEC__ROW_GLOSSY * LIGHTVEC__LEAF];
    if (q->directional && inv_dg > 0.0f) {                           /* the glossy part */
        float psi = lightvec__glossy_angle(q, it->outgoing, inv_dg, s->dx[k], s->dy[k], s->dz[k]);
        float cos_psi = 1.0f - 0.5f * psi * psi, gchange = psi * it->rel_glossy_gradient;
        if (cos_psi > it->cos_dir && gchange < p->max_change)
            wg = wb * ((cos_psi - it->cos_dir) / (1.0f - it->cos_dir)) * (1.0f / (1.0f + gchange));
    }
    memcpy(&id, &b[LIGHTVEC__ROW_ID * LIGHTVEC__LEAF], sizeof id);
    lightvec__keep(q, it, head, id, wb * ws, wg, s->dx[k], s->dy[k], s->dz[k]);
}

/* The first `count` items of a leaf block: lightvec__slot_pass over the
   whole block at once when it is a full, published one (a kd-tree leaf,
   its empty slots of radius 0; the tail's slots past its count may be
   being written), then lightvec__visit for the slots that passed, one
   branch per passing slot. */
static void lightvec__visit_block(lightvec__query *q, const lightvec__block *block, const lightvec__item *items,
                                  uint32_t count, int full)
{
    lightvec__slots s;
    float cos_dir = q->directional ? q->p->cos_dir : -2.0f; /* a 3D query has w = 0: cs = 0 passes */
    unsigned mask = full ? lightvec__block_pass(q, block->row, LIGHTVEC__LEAF, cos_dir, &s)
                         : lightvec__block_pass(q, block->row, count, cos_dir, &s);
    uint32_t k;
    for (; mask; mask &= mask - 1) {
        k = lightvec__bvh_first_bit(mask);
        lightvec__visit(q, block->row, k, &items[k], &block->head[k], &s, cos_dir);
    }
}

/* Whether any of the first n slots of a block holds A in its sphere of
   radius R0: the first test of lightvec__block_pass, the same float
   operations, on the block's NEAR_ROWS. No slot of a block it rejects
   passes lightvec__block_pass. */
static int lightvec__block_near(const lightvec__query *q, const float *block, uint32_t n)
{
    unsigned near = 0;
    uint32_t k;
    for (k = 0; k < n; k++) {
        const float *b = block + k;
        float dx = q->a[0] - b[LIGHTVEC__ROW_X * LIGHTVEC__LEAF], dy = q->a[1] - b[LIGHTVEC__ROW_Y * LIGHTVEC__LEAF];
        float dz = q->a[2] - b[LIGHTVEC__ROW_Z * LIGHTVEC__LEAF], r0 = b[LIGHTVEC__ROW_R0 * LIGHTVEC__LEAF];
        near |= (unsigned)(dx * dx + dy * dy + dz * dz < r0 * r0);
    }
    return near != 0;
}

/* Visits the pending blocks, in the order they came, in two sweeps. The
   walk prefetched only their NEAR_ROWS, enough to tell whether a slot can
   hold A (in a dense cache half the blocks a lookup reaches hold A in no
   sphere: a record's sphere covers about a third of its leaf's box); the
   first sweep drops those and prefetches the other rows of the rest,
   which the second visits: five cache lines fewer per dropped block. */
static void lightvec__drain(lightvec__query *q)
{
    uint32_t i, line, kept = 0;
    for (i = 0; i < q->pending_count; i++) {
        const lightvec__block_ref *r = &q->pending[i];
        if (!lightvec__block_near(q, r->block->row, r->count)) continue;
        for (line = LIGHTVEC__NEAR_ROWS * LIGHTVEC__LEAF * sizeof(float) / 64u; 64u * line < sizeof r->block->row; line++)
            LIGHTVEC__PREFETCH((const char *)r->block->row + 64u * line);  /* the rows after NEAR_ROWS */
        q->pending[kept++] = *r;
    }
    for (i = 0; i < kept; i++) {
        const lightvec__block_ref *r = &q->pending[i];
        if (r->full) lightvec__visit_block(q, r->block, r->items, LIGHTVEC__LEAF, 1);
        else lightvec__visit_block(q, r->block, r->items, r->count, 0);
    }
    q->pending_count = 0;
}

/* Queues a block for lightvec__visit_block. The walk goes on meanwhile, so
   the blocks it prefetched arrive while it reads the next nodes: the
   memory latencies of a lookup overlap (visiting a block as soon as the
   walk reaches it waits for each one in turn). The order of the visits,
   hence of every result, is the walk's. */
static void lightvec__queue_block(lightvec__query *q, const lightvec__block *block, const lightvec__item *items,
                                  uint32_t count, int full)
{
    lightvec__block_ref *r;
    if (q->pending_count == LIGHTVEC__PENDING) lightvec__drain(q);
    r = &q->pending[q->pending_count++];
    r->block = block;
    r->items = items;
    r->count = count < LIGHTVEC__LEAF ? count : LIGHTVEC__LEAF;
    r->full = full;
}

static void lightvec__query_leaf(void *ctx, const lightvec__tree *t, uint32_t leaf)
{
    uint32_t first = leaf * LIGHTVEC__LEAF;
    lightvec__queue_block((lightvec__query *)ctx, &t->blocks[leaf], t->items + first, t->count - first, 1);
}

/* The tail's published items (tail_count, acquire), block by block. */
static void lightvec__tail_query(const lightvec__index *idx, lightvec__query *q)
{
    uint32_t n = lightvec__load_u32(&idx->tail_count), i;
    for (i = 0; i * LIGHTVEC__LEAF < n; i++) {
        const float *near = idx->tail_blocks[i].row;   /* its NEAR_ROWS, as a leaf's (on three lines at most) */
        LIGHTVEC__PREFETCH(near);
        LIGHTVEC__PREFETCH(near + 16);
        LIGHTVEC__PREFETCH(near + LIGHTVEC__NEAR_ROWS * LIGHTVEC__LEAF - 1);
        lightvec__queue_block(q, &idx->tail_blocks[i], idx->tail + i * LIGHTVEC__LEAF, n - i * LIGHTVEC__LEAF, 0);
    }
}

static void lightvec__index_query(void *ctx, const lightvec__index *idx)
{
    lightvec__query *q = (lightvec__query *)ctx;
    uint32_t i;
    /* the roots at once: a small tree's root is often not in cache, and its
       walk would wait for it after the walks before it */
    for (i = 0; i < idx->tree_count; i++) lightvec__prefetch_child(idx->trees[i], 0);
    for (i = 0; i < idx->tree_count; i++) lightvec__tree_walk(idx->trees[i], q->a, 0.0f, lightvec__query_leaf, q);
    lightvec__tail_query(idx, q);
}

/* ---- icosahedron ------------------------------------------------------------------- */

static void lightvec__face_init(lightvec__face *f, lightvec__vec3 a, lightvec__vec3 b, lightvec__vec3 c,
                                uint32_t depth)
{
    lightvec__vec3 m = lightvec__normalize(lightvec__add(lightvec__add(a, b), c));
    float cr;
    int i;
    memset(f, 0, sizeof *f);
    f->v[0][0] = a.x; f->v[0][1] = a.y; f->v[0][2] = a.z;
    f->v[1][0] = b.x; f->v[1][1] = b.y; f->v[1][2] = b.z;
    f->v[2][0] = c.x; f->v[2][1] = c.y; f->v[2][2] = c.z;
    f->center[0] = m.x; f->center[1] = m.y; f->center[2] = m.z;
    /* a cap of radius < 90 degrees is convex on the sphere: holding the three
       vertices, it holds the spherical triangle */
    cr = lightvec__minf(lightvec__dot(m, a), lightvec__minf(lightvec__dot(m, b), lightvec__dot(m, c))) - 1e-6f;
    f->cos_r = cr;
    f->sin_r = sqrtf(lightvec__maxf(0.0f, 1.0f - cr * cr));
    f->r_angle = acosf(cr);
    f->depth = depth;
    for (i = 0; i < 3; i++) {
        lightvec__vec3 a = lightvec__v3_load(f->v[i]), b = lightvec__v3_load(f->v[(i + 1) % 3]);
        lightvec__vec3 n = lightvec__normalize(lightvec__cross(a, b)), ta = lightvec__cross(n, a), tb = lightvec__cross(b, n);
        f->edge[i][0][0] = n.x; f->edge[i][0][1] = n.y; f->edge[i][0][2] = n.z;
        f->edge[i][1][0] = ta.x; f->edge[i][1][1] = ta.y; f->edge[i][1][2] = ta.z;
        f->edge[i][2][0] = tb.x; f->edge[i][2][1] = tb.y; f->edge[i][2][2] = tb.z;
    }
}

/* The regular icosahedron (vertices (0, +-1, +-t) and cyclic, t the golden ratio). */
static void lightvec__icosahedron(lightvec__face roots[20])
{
    static const float t = 1.6180339887f;
    static const signed char v[12][3] = { { -1, 2, 0 }, { 1, 2, 0 }, { -1, -2, 0 }, { 1, -2, 0 },
                                          { 0, -1, 2 }, { 0, 1, 2 }, { 0, -1, -2 }, { 0, 1, -2 },
                                          { 2, 0, -1 }, { 2, 0, 1 }, { -2, 0, -1 }, { -2, 0, 1 } };
    static const unsigned char f[20][3] = { { 0, 11, 5 }, { 0, 5, 1 },  { 0, 1, 7 },   { 0, 7, 10 }, { 0, 10, 11 },
                                            { 1, 5, 9 },  { 5, 11, 4 }, { 11, 10, 2 }, { 10, 7, 6 }, { 7, 1, 8 },
                                            { 3, 9, 4 },  { 3, 4, 2 },  { 3, 2, 6 },   { 3, 6, 8 },  { 3, 8, 9 },
                                            { 4, 9, 5 },  { 2, 4, 11 }, { 6, 2, 10 },  { 8, 6, 7 },  { 9, 8, 1 } };
    lightvec__vec3 p[12];
    int i, k;
    for (i = 0; i < 12; i++) {
        float c[3];
        for (k = 0; k < 3; k++) c[k] = v[i][k] == 2 ? t : (v[i][k] == -2 ? -t : (float)v[i][k]);
        p[i] = lightvec__normalize(lightvec__v3(c[0], c[1], c[2]));
    }
    for (i = 0; i < 20; i++) {
        lightvec__vec3 a = p[f[i][0]], b = p[f[i][1]], c = p[f[i][2]];
        if (lightvec__dot(lightvec__cross(a, b), c) < 0.0f) { lightvec__vec3 s = b; b = c; c = s; }
        lightvec__face_init(&roots[i], a, b, c, 0);
    }
}

/* The root face holding d: for a regular polyhedron the spherical faces are
   the Voronoi cells of the face centres, so the largest dot product decides. */
static uint32_t lightvec__root_of(const lightvec__face roots[20], const float d[3])
{
    uint32_t i, best = 0;
    float bd = -2.0f;
    for (i = 0; i < 20; i++) {
        float x = roots[i].center[0] * d[0] + roots[i].center[1] * d[1] + roots[i].center[2] * d[2];
        if (x > bd) { bd = x; best = i; }
    }
    return best;
}

/* Children of a split face: 0 = (v0, m01, m20), 1 = (m01, v1, m12),
   2 = (m20, m12, v2), 3 = (m01, m12, m20), the m's edge midpoints pushed onto
   the sphere (figure 4). A direction is in corner child i when it is on the
   corner's side of the great circle through the child's inner edge. */
static void lightvec__make_children(lightvec__face *f, lightvec__face ch[4])
{
    lightvec__vec3 v0 = lightvec__v3_load(f->v[0]), v1 = lightvec__v3_load(f->v[1]), v2 = lightvec__v3_load(f->v[2]);
    lightvec__vec3 m01 = lightvec__normalize(lightvec__add(v0, v1));
    lightvec__vec3 m12 = lightvec__normalize(lightvec__add(v1, v2));
    lightvec__vec3 m20 = lightvec__normalize(lightvec__add(v2, v0));
    lightvec__vec3 pl[3];
    int i;
    pl[0] = lightvec__cross(m01, m20);
    pl[1] = lightvec__cross(m12, m01);
    pl[2] = lightvec__cross(m20, m12);
    for (i = 0; i < 3; i++) { f->plane[i][0] = pl[i].x; f->plane[i][1] = pl[i].y; f->plane[i][2] = pl[i].z; }
    lightvec__face_init(&ch[0], v0, m01, m20, f->depth + 1);
    lightvec__face_init(&ch[1], m01, v1, m12, f->depth + 1);
    lightvec__face_init(&ch[2], m20, m12, v2, f->depth + 1);
    lightvec__face_init(&ch[3], m01, m12, m20, f->depth + 1);
}

static uint32_t lightvec__child_of(const lightvec__face *f, const float d[3])
{
    uint32_t i;
    for (i = 0; i < 3; i++)
        if (f->plane[i][0] * d[0] + f->plane[i][1] * d[1] + f->plane[i][2] * d[2] > 0.0f) return i;
    return 3;
}

static float lightvec__dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Can the face hold a record within the directional cone around w (angle
   below beta = acos S_dir)? First the face's bounding cap: the cone and the
   cap meet when the angle between their axes is at most the sum of their
   radii. Then the spherical triangle itself (about half of its cap): w is
   inside, or within beta of an edge (of the edge's great circle where the
   nearest point falls inside the edge, else of its end points). Slack 1e-6
   keeps records placed on a boundary by float rounding in. */
static int lightvec__face_in_cone(const lightvec__face *f, const lightvec__params *p, const float w[3])
{
    float c = lightvec__dot3(f->center, w), s[3];
    int i;
    if (f->r_angle + p->dir_angle >= (float)LIGHTVEC__PI) return 1;
    if (c < f->cos_r * p->cos_dir - f->sin_r * p->sin_dir - 1e-6f) return 0;
    if (p->dir_angle >= (float)(LIGHTVEC__PI / 2)) return 1;
    for (i = 0; i < 3; i++) s[i] = lightvec__dot3(f->edge[i][0], w);
    if (s[0] >= -1e-6f && s[1] >= -1e-6f && s[2] >= -1e-6f) return 1; /* inside */
    for (i = 0; i < 3; i++) {
        if (s[i] >= 0.0f) continue; /* w is on the inner side of this edge */
        if (lightvec__dot3(f->edge[i][1], w) >= 0.0f && lightvec__dot3(f->edge[i][2], w) >= 0.0f) {
            if (-s[i] < p->sin_dir + 1e-6f) return 1; /* nearest point inside the edge */
        } else if (lightvec__dot3(f->v[i], w) > p->cos_dir - 1e-6f ||
                   lightvec__dot3(f->v[(i + 1) % 3], w) > p->cos_dir - 1e-6f) {
            return 1;
        }
    }
    return 0;
}

/* Faces much smaller than the directional cone would only add faces to
   every search (and kd-trees to descend), so a face splits only while its
   children stay at least as wide as the cone's radius: a search then visits
   a handful of faces. max_depth bounds it too. */
static int lightvec__can_split(const lightvec_cache *c, const lightvec__face *f)
{
    return f != &c->omni && f->depth < c->p.max_depth && f->r_angle >= 2.0f * c->p.dir_angle;
}

/* ---- reader registration and deferred freeing ----------------------------------- */

static uint32_t lightvec__enter(lightvec__readers *r)
{
    for (;;) {
        uint32_t e = lightvec__load_sc(&r->epoch);
        lightvec__add_sc(&r->count[e][0], 1u);
        if (lightvec__load_sc(&r->epoch) == e) return e;
        lightvec__add_sc(&r->count[e][0], 0xFFFFFFFFu); /* the writer flipped meanwhile: retry */
    }
}

static void lightvec__leave(lightvec__readers *r, uint32_t e) { lightvec__add_sc(&r->count[e][0], 0xFFFFFFFFu); }

/* Waits until no reader can hold memory unpublished before this call: flip
   the epoch, then wait for the readers registered under the old one. A reader
   that registers under the old epoch after the flip sees the flip when it
   checks again, and retries under the new one. */
static void lightvec__synchronize(lightvec_cache *c)
{
    uint32_t e = lightvec__load_sc(&c->readers->epoch);
    lightvec__store_sc(&c->readers->epoch, e ^ 1u);
    while (lightvec__load_sc(&c->readers->count[e][0]) != 0) {
        /* readers leave within one lookup */
    }
}

static void lightvec__reclaim(lightvec_cache *c)
{
    uint32_t i;
    if (!c->retired_count) return;
    lightvec__synchronize(c);
    for (i = 0; i < c->retired_count; i++) lightvec__free(&c->a, c->retired[i].ptr);
    c->retired_count = 0;
    c->retired_bytes = 0;
}

static void lightvec__retire(lightvec_cache *c, void *ptr, size_t bytes)
{
    if (!ptr) return;
    if (c->retired_count == c->retired_capacity) {
        uint32_t cap = c->retired_capacity ? 2 * c->retired_capacity : 64u;
        lightvec__retired *r = (lightvec__retired *)lightvec__alloc_array(&c->a, cap, sizeof *r);
        if (!r) { /* no room to defer: wait for the readers now */
            lightvec__reclaim(c);
            lightvec__synchronize(c);
            lightvec__free(&c->a, ptr);
            return;
        }
        if (c->retired_count) memcpy(r, c->retired, c->retired_count * sizeof *r);
        lightvec__free(&c->a, c->retired);
        c->retired = r;
        c->retired_capacity = cap;
    }
    c->retired[c->retired_count].ptr = ptr;
    c->retired[c->retired_count].bytes = bytes;
    c->retired_count++;
    c->retired_bytes += bytes;
}

static void lightvec__maybe_reclaim(lightvec_cache *c)
{
    size_t live = (size_t)c->record_count * sizeof(lightvec__entry);
    if (c->retired_bytes > LIGHTVEC__RECLAIM_BYTES + live / 4) lightvec__reclaim(c);
}

/* ---- building and restructuring faces (writer) ----------------------------------- */

static void lightvec__index_free(lightvec_cache *c, lightvec__index *idx)
{
    uint32_t i;
    if (!idx) return;
    for (i = 0; i < idx->tree_count; i++) lightvec__free(&c->a, idx->trees[i]);
    lightvec__free(&c->a, idx);
}

/* Frees everything below f: its children recursively, or its index (the
   index a split face still points to is on the retired list). */
static void lightvec__face_free(lightvec_cache *c, lightvec__face *f)
{
    lightvec__face *ch = (lightvec__face *)f->children;
    if (ch) {
        int i;
        for (i = 0; i < 4; i++) lightvec__face_free(c, &ch[i]);
        lightvec__free(&c->a, ch);
    } else {
        lightvec__index_free(c, (lightvec__index *)f->index);
    }
    f->children = NULL;
    f->index = NULL;
}

static lightvec__index *lightvec__index_new(lightvec_cache *c)
{
    lightvec__index *idx = (lightvec__index *)lightvec__alloc(&c->a, sizeof *idx);
    if (idx) {
        idx->tree_count = 0;
        idx->tail_count = 0;
    }
    return idx;
}

/* Copies the tail and the first `trees` kd-trees of idx to dst, each item
   with its head from its block; returns the count. */
static uint32_t lightvec__index_items(const lightvec__index *idx, uint32_t trees, lightvec__entry *dst)
{
    uint32_t i, k, n = idx->tail_count;
    for (k = 0; k < n; k++) {
        dst[k].head = idx->tail_blocks[k / LIGHTVEC__LEAF].head[k % LIGHTVEC__LEAF];
        dst[k].item = idx->tail[k];
    }
    for (i = 0; i < trees; i++) {
        const lightvec__tree *t = idx->trees[i];
        for (k = 0; k < t->count; k++, n++) {
            dst[n].head = t->blocks[k / LIGHTVEC__LEAF].head[k % LIGHTVEC__LEAF];
            dst[n].item = t->items[k];
        }
    }
    return n;
}

static lightvec__index *lightvec__index_single(lightvec_cache *c, const lightvec__entry *items, uint32_t n)
{
    lightvec__index *idx = lightvec__index_new(c);
    lightvec__tree *t = lightvec__tree_build(&c->a, items, n);
    if (!idx || !t) {
        lightvec__free(&c->a, idx);
        lightvec__free(&c->a, t);
        return NULL;
    }
    idx->trees[0] = t;
    idx->tree_count = 1;
    return idx;
}

static int lightvec__face_fill(lightvec_cache *c, lightvec__face *f, lightvec__entry *items, uint32_t n);

/* The four children of f holding items[0, n) (figure 4), split again while a
   child still holds more than the threshold. Not published: the caller stores
   the pointer into f->children when the rest of its change is ready. NULL
   when out of memory (nothing is left allocated). */
static lightvec__face *lightvec__face_children(lightvec_cache *c, lightvec__face *f, const lightvec__entry *items,
                                               uint32_t n)
{
    lightvec__face *ch = (lightvec__face *)lightvec__alloc_array(&c->a, 4, sizeof(lightvec__face));
    lightvec__entry *tmp = (lightvec__entry *)lightvec__alloc_array(&c->a, n, sizeof(lightvec__entry));
    uint32_t count[4] = { 0, 0, 0, 0 }, start[4], i;
    int k, failed = 0;
    if (!ch || !tmp) {
        lightvec__free(&c->a, ch);
        lightvec__free(&c->a, tmp);
        return NULL;
    }
    lightvec__make_children(f, ch);
    for (i = 0; i < n; i++) count[lightvec__child_of(f, items[i].item.outgoing)]++;
    start[0] = 0;
    for (k = 1; k < 4; k++) start[k] = start[k - 1] + count[k - 1];
    for (i = 0; i < n; i++) tmp[start[lightvec__child_of(f, items[i].item.outgoing)]++] = items[i];
    for (k = 0; k < 4; k++) start[k] -= count[k];
    for (k = 0; k < 4 && !failed; k++) failed = lightvec__face_fill(c, &ch[k], tmp + start[k], count[k]) != 0;
    lightvec__free(&c->a, tmp);
    if (failed) {
        for (k = 0; k < 4; k++) lightvec__face_free(c, &ch[k]);
        lightvec__free(&c->a, ch);
        return NULL;
    }
    return ch;
}

/* Fills an empty face with items[0, n): children while the threshold allows,
   else one kd-tree. */
static int lightvec__face_fill(lightvec_cache *c, lightvec__face *f, lightvec__entry *items, uint32_t n)
{
    if (n > c->p.split_threshold && lightvec__can_split(c, f)) {
        lightvec__face *ch = lightvec__face_children(c, f, items, n);
        if (!ch) return -1;
        lightvec__store_ptr(&f->children, ch);
        f->count = 0;
        return 0;
    }
    if (n) {
        lightvec__index *idx = lightvec__index_single(c, items, n);
        if (!idx) return -1;
        lightvec__store_ptr(&f->index, idx);
    }
    f->count = n;
    return 0;
}

/* Bentley-Saxe merge of a full tail: the tail and every kd-tree not larger
   than MERGE_RATIO times what is merged so far become one new kd-tree.
   Ratio 2 is the classic binary counter (log2 n trees). A lookup walks
   every tree of the faces it searches, and each tree adds its root path and
   the partly filled leaves at the edge of the query's reach: in the dense
   cache of tests/bench_lightvec.c (10^5 records, 2.6 faces per lookup)
   ratio 8 left 7.0 trees, 26 nodes and 29 leaves per lookup, ratio 64
   leaves 4.6 trees, 22 nodes and 26.5 leaves (one tree per face, after
   lightvec_cache_optimize: 2.6, 20 and 25), about 7% of a dense lookup,
   for insertions 1.5x to 2.4x as long (tens of microseconds, against about
   a millisecond for the gather that makes the record). Ratio 128 kept as
   many trees there. */
static int lightvec__merge(lightvec_cache *c, lightvec__face *f)
{
    lightvec__index *old = (lightvec__index *)f->index, *idx;
    lightvec__entry *items;
    lightvec__tree *t;
    uint64_t acc = old->tail_count;
    uint32_t take = 0, i;
    while (take < old->tree_count &&
           (old->trees[take]->count <= LIGHTVEC__MERGE_RATIO * acc || old->tree_count - take >= LIGHTVEC__MAX_TREES))
        acc += old->trees[take++]->count;
    items = (lightvec__entry *)lightvec__alloc_array(&c->a, (size_t)acc, sizeof *items);
    if (!items) return -1;
    lightvec__index_items(old, take, items);
    t = lightvec__tree_build(&c->a, items, (uint32_t)acc);
    lightvec__free(&c->a, items);
    idx = lightvec__index_new(c);
    if (!t || !idx) {
        lightvec__free(&c->a, t);
        lightvec__free(&c->a, idx);
        return -1;
    }
    idx->trees[0] = t;
    for (i = take; i < old->tree_count; i++) idx->trees[1 + i - take] = old->trees[i];
    idx->tree_count = 1 + old->tree_count - take;
    lightvec__store_ptr(&f->index, idx);
    for (i = 0; i < take; i++) lightvec__retire(c, old->trees[i], old->trees[i]->bytes);
    lightvec__retire(c, old, sizeof *old);
    return 0;
}

/* The children of leaf f holding its items and one more (section 3.2,
   figure 4), unpublished; NULL when out of memory. */
static lightvec__face *lightvec__split_with(lightvec_cache *c, lightvec__face *f, const lightvec__entry *extra)
{
    const lightvec__index *old = (const lightvec__index *)f->index;
    lightvec__entry *items = (lightvec__entry *)lightvec__alloc_array(&c->a, (size_t)f->count + 1u, sizeof *items);
    lightvec__face *ch;
    uint32_t n = 0;
    if (!items) return NULL;
    if (old) n = lightvec__index_items(old, old->tree_count, items);
    items[n++] = *extra;
    ch = lightvec__face_children(c, f, items, n);
    lightvec__free(&c->a, items);
    return ch;
}

/* Publishes the children of a split leaf. f->index keeps pointing at the
   retired index: a reader that saw no children a moment ago still finds every
   record there, and readers that see the children never read it again. */
static void lightvec__publish_split(lightvec_cache *c, lightvec__face *f, lightvec__face *ch)
{
    lightvec__index *old = (lightvec__index *)f->index;
    uint32_t i;
    lightvec__store_ptr(&f->children, ch);
    f->count = 0;
    if (!old) return;
    for (i = 0; i < old->tree_count; i++) lightvec__retire(c, old->trees[i], old->trees[i]->bytes);
    lightvec__retire(c, old, sizeof *old);
}

/* Room for one more item in leaf f: its first index, or a merged tail. */
static int lightvec__face_prepare(lightvec_cache *c, lightvec__face *f)
{
    lightvec__index *idx = (lightvec__index *)f->index;
    if (!idx) {
        idx = lightvec__index_new(c);
        if (!idx) return -1;
        lightvec__store_ptr(&f->index, idx);
        return 0;
    }
    return idx->tail_count == LIGHTVEC__TAIL ? lightvec__merge(c, f) : 0;
}

static void lightvec__face_push(lightvec__face *f, const lightvec__entry *e)
{
    lightvec__index *idx = (lightvec__index *)f->index;
    uint32_t n = idx->tail_count;
    idx->tail[n] = e->item;
    lightvec__block_put(&idx->tail_blocks[n / LIGHTVEC__LEAF], n % LIGHTVEC__LEAF, e);
    lightvec__store_u32(&idx->tail_count, n + 1u); /* publishes the item */
    f->count++;
}

static lightvec__face *lightvec__leaf_for(lightvec_cache *c, const lightvec_record *r)
{
    lightvec__face *f;
    if (r->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) return &c->omni;
    f = &c->roots[lightvec__root_of(c->roots, r->outgoing)];
    while (f->children) f = &((lightvec__face *)f->children)[lightvec__child_of(f, r->outgoing)];
    return f;
}

/* ---- public cache API -------------------------------------------------------------- */

static lightvec_result lightvec__cache_new(const lightvec_cache_desc *desc, lightvec_cache **out)
{
    lightvec_cache_desc zero;
    lightvec_cache *c;
    lightvec__params p;
    lightvec_result r;
    if (!desc) {
        memset(&zero, 0, sizeof zero);
        desc = &zero;
    }
    if (!lightvec__allocator_valid(&desc->allocator)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    r = lightvec__params_init(&p, desc);
    if (r != LIGHTVEC_OK) return r;
    c = (lightvec_cache *)lightvec__alloc(&desc->allocator, sizeof *c);
    if (!c) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    memset(c, 0, sizeof *c);
    c->readers = (lightvec__readers *)lightvec__alloc(&desc->allocator, sizeof *c->readers);
    if (!c->readers) {
        lightvec__free(&desc->allocator, c);
        return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    }
    memset(c->readers, 0, sizeof *c->readers);
    c->a = desc->allocator;
    c->p = p;
    c->parallel_for = desc->parallel_for;
    c->parallel_user = desc->parallel_user;
    c->progress = desc->progress;
    c->progress_user = desc->progress_user;
    c->log = desc->log;
    c->log_user = desc->log_user;
    lightvec__icosahedron(c->roots);
    c->omni.r_angle = (float)LIGHTVEC__PI;
    c->omni.cos_r = -1.0f;
    *out = c;
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_cache_create(const lightvec_cache_desc *desc, lightvec_cache **out)
{
    if (!out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    return lightvec__cache_new(desc, out);
}

LIGHTVEC_API void lightvec_cache_destroy(lightvec_cache *c)
{
    lightvec_allocator a;
    int i;
    if (!c) return;
    a = c->a;
    for (i = 0; i < 20; i++) lightvec__face_free(c, &c->roots[i]);
    lightvec__face_free(c, &c->omni);
    for (i = 0; i < (int)c->retired_count; i++) lightvec__free(&a, c->retired[i].ptr);
    lightvec__free(&a, c->retired);
    for (i = 0; i < LIGHTVEC__CHUNKS; i++) {
        lightvec__free(&a, c->chunks[i]);
        lightvec__free(&a, c->radii[i]);
    }
    lightvec__free(&a, c->readers);
    lightvec__free(&a, c);
}

static lightvec_result lightvec__query_init(const lightvec_cache *c, const float position[3], const float normal[3],
                                            const float *outgoing, lightvec__query *q)
{
    lightvec__vec3 n, w, m;
    if (!c || !position || !lightvec__finite3(position) || !lightvec__unit(normal, &n))
        return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(q, 0, sizeof *q);
    q->p = &c->p;
    memcpy(q->a, position, sizeof q->a);
    q->n[0] = n.x; q->n[1] = n.y; q->n[2] = n.z;
    if (outgoing) {
        if (!lightvec__unit(outgoing, &w)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
        q->w[0] = w.x; q->w[1] = w.y; q->w[2] = w.z;
        m = lightvec__sub(lightvec__scale(n, 2.0f * lightvec__dot(n, w)), w);
        q->mirror[0] = m.x; q->mirror[1] = m.y; q->mirror[2] = m.z;
        q->directional = 1;
    }
    return LIGHTVEC_OK;
}

/* Calls fn for every index that can hold a record valid in the direction
   cone around w (directional), or for the view-independent leaf. The caller
   registers as a reader, unless it is the writer. */
static void lightvec__for_indexes(const lightvec_cache *c, int directional, const float w[3],
                                  void (*fn)(void *ctx, const lightvec__index *idx), void *ctx)
{
    const lightvec__face *stack[LIGHTVEC__FACE_STACK];
    uint32_t top = 0, i;
    if (!directional) {
        const lightvec__index *idx = (const lightvec__index *)lightvec__load_ptr(&c->omni.index);
        if (idx) fn(ctx, idx);
        return;
    }
    for (i = 0; i < 20; i++)
        if (lightvec__face_in_cone(&c->roots[i], &c->p, w)) stack[top++] = &c->roots[i];
    while (top) {
        const lightvec__face *f = stack[--top];
        const lightvec__face *ch = (const lightvec__face *)lightvec__load_ptr(&f->children);
        if (ch) {
            for (i = 0; i < 4; i++)
                if (lightvec__face_in_cone(&ch[i], &c->p, w)) stack[top++] = &ch[i];
        } else {
            const lightvec__index *idx = (const lightvec__index *)lightvec__load_ptr(&f->index);
            if (idx) fn(ctx, idx);
        }
    }
}

/* Every record valid at the query. The caller is a registered reader
   (lightvec__enter) until it has read the candidates too: their heads point
   into leaf blocks that a restructured face retires, and the writer frees
   retired memory once no registered reader is left. */
static void lightvec__search(const lightvec_cache *c, lightvec__query *q)
{
    lightvec__block_ref pending[LIGHTVEC__PENDING];
    q->pending = pending;
    q->pending_count = 0;
    lightvec__for_indexes(c, q->directional, q->w, lightvec__index_query, q);
    lightvec__drain(q);
    q->pending = NULL;
}

/* 4.2.3: the normalised weighted interpolation of the kept records.
   Diffuse vector: the paper averages D and M. Averaging unit directions
   shortens the sum, and its normalised direction leans toward the normal
   more than the records' do, so M * cos(n, D) grows: a bias of a few percent
   on walls lit from many directions. The projected modes average
   M cos(n_B, D_B) (the irradiance, for Lambert) and divide by cos(n_A, D)
   afterwards; GRADIENT first moves each record to A by Ward & Heckbert's
   gradient, E_c(A) = E_c(B) (1 + grad E_c / E_c . (A - B)).
   Glossy vector: G(A, w) = the w_g-weighted mean of max(0, G_B + dG_B/dw .
   (w - sigma_B)) over the records valid for their glossy part, turned into
   the glossy light vector toward w with their mean exponent. */
static void lightvec__interpolate(const lightvec__query *q, lightvec_lookup_result *out)
{
    const lightvec__params *p = q->p;
    double wsum = 0.0, msum[3] = { 0, 0, 0 }, dsum[3] = { 0, 0, 0 }, gsum[3] = { 0, 0, 0 }, gw = 0.0, esum = 0.0, scale;
    uint32_t i, used = q->kept_count, lit = 0, shadow = 0, partial = 0, glossy = 0, glossy_valid = 0;
    lightvec__vec3 d, n = lightvec__v3_load(q->n);
    int k;
    for (i = 0; i < used; i++) {
        const lightvec__candidate *c = &q->kept[i];
        const lightvec__head *h = c->head;
        const lightvec__item *it = c->it;
        double w = c->w, wg = c->wg;
        wsum += w;
        for (k = 0; k < 3; k++) {
            float m = h->mag[k];
            if (p->interpolation == LIGHTVEC_INTERPOLATION_GRADIENT) {
                float f = 1.0f + (h->slope[k][0] * c->d[0] + h->slope[k][1] * c->d[1] + h->slope[k][2] * c->d[2]);
                m *= f > 0.0f ? f : 0.0f;
            }
            msum[k] += w * m;
            dsum[k] += w * h->dir[k];
        }
        glossy += q->directional && (h->kind & LIGHTVEC__ITEM_GLOSSY);
        if (wg > 0.0) {
            float v[3];
            v[0] = q->w[0] - it->outgoing[0]; v[1] = q->w[1] - it->outgoing[1]; v[2] = q->w[2] - it->outgoing[2];
            for (k = 0; k < 3; k++) {
                const float *g = it->glossy_gradient[k];
                float gk = it->glossy[k] + (g[0] * v[0] + g[1] * v[1] + g[2] * v[2]);
                gsum[k] += wg * (gk > 0.0f ? gk : 0.0f);
            }
            gw += wg;
            esum += wg * it->exponent;
            glossy_valid++;
        }
        if (h->kind & LIGHTVEC__ITEM_LIT) lit++;
        else if (h->kind & LIGHTVEC__ITEM_UMBRA) shadow++;
        else partial++;
    }
    out->used_count = used;
    out->weight = used ? (float)(wsum / used) : 0.0f; /* 4.3: average of the weights */
    /* where the kept records have glossy parts, min_valid of them must be
       valid for the glossy part too */
    out->hit = used >= p->min_valid && wsum > 0.0 && (!glossy || glossy_valid >= p->min_valid);
    if (p->kind == LIGHTVEC_KIND_DIRECT && (partial || (lit && shadow))) out->hit = 0;
    if (!out->hit) return;
    d = lightvec__v3((float)dsum[0], (float)dsum[1], (float)dsum[2]);
    d = lightvec__length(d) > 0.0f ? lightvec__normalize(d) : n;
    scale = 1.0 / wsum;
    if (p->interpolation != LIGHTVEC_INTERPOLATION_PLAIN) {
        float cos_d = lightvec__dot(n, d);
        if (!(cos_d > 1e-3f)) { /* the mean light comes from behind A: keep it on A's side */
            d = n;
            cos_d = 1.0f;
        }
        scale /= cos_d;
    }
    out->vector.direction[0] = d.x; out->vector.direction[1] = d.y; out->vector.direction[2] = d.z;
    for (k = 0; k < 3; k++) out->vector.magnitude[k] = lightvec__to_float(msum[k] * scale);
    if (gw > 0.0) {
        for (k = 0; k < 3; k++) gsum[k] /= gw;
        lightvec__glossy_vector(n, lightvec__v3_load(q->w), esum / gw, gsum, &out->vector);
    }
}

LIGHTVEC_API lightvec_result lightvec_lookup(const lightvec_cache *c, const float position[3], const float normal[3],
                                             const float *outgoing, lightvec_lookup_result *out)
{
    lightvec__candidate kept[LIGHTVEC__MAX_NEIGHBORS + LIGHTVEC__KEPT_SLACK];
    uint64_t ranks[LIGHTVEC__MAX_NEIGHBORS + LIGHTVEC__KEPT_SLACK];
    lightvec__query q;
    lightvec_result r;
    uint32_t e;
    if (!out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    r = lightvec__query_init(c, position, normal, outgoing, &q);
    if (r != LIGHTVEC_OK) return r;
    q.kept = kept;
    q.ranks = ranks;
    q.best = c->p.max_neighbors;
    e = lightvec__enter(c->readers);
    lightvec__search(c, &q);
    out->valid_count = q.count;
    q.kept_count = lightvec__select_best(q.ranks, q.kept, q.kept_count, q.best);
    lightvec__interpolate(&q, out); /* reads the kept heads: still registered */
    lightvec__leave(c->readers, e);
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_find(const lightvec_cache *c, const float position[3], const float normal[3],
                                           const float *outgoing, uint32_t *ids, float *weights,
                                           uint32_t capacity, uint32_t *count)
{
    lightvec__query q;
    lightvec_result r;
    uint32_t e;
    if (!count || (capacity && (!ids || !weights))) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *count = 0;
    r = lightvec__query_init(c, position, normal, outgoing, &q);
    if (r != LIGHTVEC_OK) return r;
    q.ids = ids;
    q.weights = weights;
    q.capacity = capacity;
    e = lightvec__enter(c->readers);
    lightvec__search(c, &q);
    lightvec__leave(c->readers, e);
    *count = q.count;
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_cache_record(const lightvec_cache *c, uint32_t id, lightvec_record *out)
{
    if (!c || !out || id >= lightvec__load_u32(&c->record_count)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *out = *lightvec__record_at(c, id);
    out->radius = lightvec__load_f32(lightvec__radius_at(c, id));
    return LIGHTVEC_OK;
}

/* ---- neighbour clamping and insertion (writer) ------------------------------------- */

/* Neighbour clamping (Krivanek et al. 2006): the radii of
   records whose validity spheres overlap obey R_i <= R_j + |B_i - B_j| both
   ways, the triangle inequality the harmonic-mean distance field itself
   obeys. A record whose rays missed a nearby occluder (a large d_avg) is held
   back by neighbours that saw it, so it cannot reach over the occluder's
   shadow. Neighbours are the records a lookup at (B_i, sigma_i) could find:
   the view-independent ones for a view-independent record, else those
   within max_direction_angle of sigma_i. Pass 1 clamps the new radius by the
   records within it; pass 2 clamps every record whose sphere holds B_i by
   the new radius. */
typedef struct lightvec__clamp {
    lightvec_cache *c;
    lightvec__item *it;              /* the new record (its radius is R_i) */
    int directional, pass;
} lightvec__clamp;

static void lightvec__clamp_item(lightvec__clamp *k, float *block, uint32_t slot, lightvec__item *other)
{
    lightvec__item *it = k->it;
    float *b = block + slot;
    float dx = it->pos[0] - b[LIGHTVEC__ROW_X * LIGHTVEC__LEAF], dy = it->pos[1] - b[LIGHTVEC__ROW_Y * LIGHTVEC__LEAF];
    float dz = it->pos[2] - b[LIGHTVEC__ROW_Z * LIGHTVEC__LEAF];
    float d = sqrtf(dx * dx + dy * dy + dz * dz), r = b[LIGHTVEC__ROW_R * LIGHTVEC__LEAF];
    if (k->directional && !(it->outgoing[0] * other->outgoing[0] + it->outgoing[1] * other->outgoing[1] +
                                it->outgoing[2] * other->outgoing[2] > k->c->p.cos_dir))
        return;
    if (k->pass == 1) {
        if (r + d < it->radius) it->radius = r + d;
    } else if (it->radius + d < r) {
        r = it->radius + d;
        lightvec__store_f32(b + LIGHTVEC__ROW_R * LIGHTVEC__LEAF, r);  /* readers may be reading it */
        lightvec__store_f32(lightvec__radius_at(k->c, other->id), r);
        other->radius = r;                   /* what the next rebuild of its tree copies */
    }
}

/* The items of a kd-tree leaf whose sphere box, grown by reach, holds the
   new record (pass 1: reach R_i; pass 2: 0): a superset of the records
   either pass can clamp (r + d < R_i needs d < R_i; R_i + d < r needs
   d < r). */
static void lightvec__clamp_leaf(void *ctx, const lightvec__tree *ct, uint32_t leaf)
{
    lightvec__tree *t = (lightvec__tree *)(uintptr_t)ct; /* the writer's own memory */
    uint32_t i;
    for (i = leaf * LIGHTVEC__LEAF; i < t->count && i < (leaf + 1) * LIGHTVEC__LEAF; i++)
        lightvec__clamp_item((lightvec__clamp *)ctx, t->blocks[leaf].row, i % LIGHTVEC__LEAF,
                             &t->items[i]);
}

static void lightvec__clamp_index(void *ctx, const lightvec__index *cidx)
{
    lightvec__clamp *k = (lightvec__clamp *)ctx;
    lightvec__index *idx = (lightvec__index *)(uintptr_t)cidx; /* the writer's own memory */
    float reach = k->pass == 1 ? k->it->radius : 0.0f;
    uint32_t i;
    for (i = 0; i < idx->tree_count; i++) lightvec__tree_walk(idx->trees[i], k->it->pos, reach, lightvec__clamp_leaf, k);
    for (i = 0; i < idx->tail_count; i++)
        lightvec__clamp_item(k, idx->tail_blocks[i / LIGHTVEC__LEAF].row, i % LIGHTVEC__LEAF, &idx->tail[i]);
}

static void lightvec__clamp_pass(lightvec_cache *c, lightvec__item *it, int directional, int pass)
{
    lightvec__clamp k;
    k.c = c;
    k.it = it;
    k.directional = directional;
    k.pass = pass;
    lightvec__for_indexes(c, directional, it->outgoing, lightvec__clamp_index, &k);
}

LIGHTVEC_API lightvec_result lightvec_insert(lightvec_cache *c, const lightvec_record *rec, uint32_t *id_out)
{
    lightvec_record clean, *slot;
    lightvec__entry e;
    lightvec__face *f;
    uint32_t id;
    int directional, clamp;
    if (!c || !rec) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    if (!lightvec__record_clean(&c->p, rec, &clean)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    id = c->record_count;
    if (id == 0xFFFFFFFFu) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    slot = lightvec__record_reserve(c, id);
    if (!slot) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    directional = !(clean.flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT);
    clamp = !(c->p.flags & LIGHTVEC_CACHE_NO_NEIGHBOR_CLAMP);
    f = lightvec__leaf_for(c, &clean);
    lightvec__make_item(&c->p, &clean, id, &e);
    if (clamp) lightvec__clamp_pass(c, &e.item, directional, 1);
    clean.radius = e.item.radius;
    /* Everything that can fail happens before the record is published: on an
       error the cache is as it was. The record count is published before the
       item, so a reader that finds the item can read its record. */
    if (f->count + 1u > c->p.split_threshold && lightvec__can_split(c, f)) {
        lightvec__face *ch = lightvec__split_with(c, f, &e);
        if (!ch) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
        *slot = clean;
        lightvec__store_f32(lightvec__radius_at(c, id), clean.radius);
        lightvec__store_u32(&c->record_count, id + 1u);
        lightvec__publish_split(c, f, ch);
    } else {
        if (lightvec__face_prepare(c, f) != 0) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
        *slot = clean;
        lightvec__store_f32(lightvec__radius_at(c, id), clean.radius);
        lightvec__store_u32(&c->record_count, id + 1u);
        lightvec__face_push(f, &e);
    }
    if (clamp) lightvec__clamp_pass(c, &e.item, directional, 2);
    lightvec__maybe_reclaim(c);
    if (id_out) *id_out = id;
    return LIGHTVEC_OK;
}

/* ---- walking the faces (writer side) ------------------------------------------------- */

typedef struct lightvec__walk {
    const lightvec__face *stack[LIGHTVEC__FACE_STACK];
    uint32_t top;
} lightvec__walk;

/* Faces in depth-first pre-order: root 0, its subtree, root 1, ... */
static void lightvec__walk_init(lightvec__walk *w, const lightvec_cache *c)
{
    int i;
    w->top = 0;
    for (i = 19; i >= 0; i--) w->stack[w->top++] = &c->roots[i];
}

static const lightvec__face *lightvec__walk_next(lightvec__walk *w)
{
    const lightvec__face *f, *ch;
    int i;
    if (!w->top) return NULL;
    f = w->stack[--w->top];
    ch = (const lightvec__face *)f->children;
    if (ch)
        for (i = 3; i >= 0; i--) w->stack[w->top++] = &ch[i];
    return f;
}

static uint64_t lightvec__face_records(const lightvec__face *f)
{
    const lightvec__face *ch = (const lightvec__face *)f->children;
    if (ch) return lightvec__face_records(&ch[0]) + lightvec__face_records(&ch[1]) +
                   lightvec__face_records(&ch[2]) + lightvec__face_records(&ch[3]);
    return f->count;
}

static size_t lightvec__index_bytes(const lightvec__index *idx, uint32_t *trees)
{
    size_t b = 0;
    uint32_t i;
    if (!idx) return 0;
    for (i = 0; i < idx->tree_count; i++) b += idx->trees[i]->bytes;
    *trees += idx->tree_count;
    return b + sizeof *idx;
}

LIGHTVEC_API lightvec_result lightvec_cache_info(const lightvec_cache *c, lightvec_cache_stats *info)
{
    lightvec__walk w;
    const lightvec__face *f;
    int k;
    if (!c || !info) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(info, 0, sizeof *info);
    info->kind = c->p.kind;
    info->record_count = c->record_count;
    info->bytes = sizeof *c + sizeof *c->readers + c->retired_bytes + (size_t)c->retired_capacity * sizeof(lightvec__retired);
    for (k = 0; k < LIGHTVEC__CHUNKS; k++)
        if (c->chunks[k]) info->bytes += ((size_t)LIGHTVEC__CHUNK0 << k) * (sizeof(lightvec_record) + sizeof(float));
    lightvec__walk_init(&w, c);
    while ((f = lightvec__walk_next(&w)) != NULL) {
        info->face_count++;
        if (f->children) {
            info->bytes += 4 * sizeof(lightvec__face);
            continue;
        }
        info->leaf_count++;
        if (f->depth > info->max_depth) info->max_depth = f->depth;
        info->bytes += lightvec__index_bytes((const lightvec__index *)f->index, &info->tree_count);
    }
    info->bytes += lightvec__index_bytes((const lightvec__index *)c->omni.index, &info->tree_count);
    info->radius_scale = c->p.radius_scale;
    info->max_irradiance_change = c->p.max_change;
    info->cos_normal = c->p.cos_normal;
    info->cos_direction = c->p.cos_dir;
    info->front_tolerance = c->p.front;
    info->min_valid = c->p.min_valid;
    info->max_neighbors = c->p.max_neighbors;
    info->flags = c->p.flags;
    info->interpolation = c->p.interpolation;
    info->face_split_threshold = c->p.split_threshold;
    info->max_face_depth = c->p.max_depth;
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_cache_face(const lightvec_cache *c, uint32_t index, lightvec_face_info *out)
{
    lightvec__walk w;
    const lightvec__face *f;
    uint32_t i = 0;
    if (!c || !out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    lightvec__walk_init(&w, c);
    while ((f = lightvec__walk_next(&w)) != NULL && i < index) i++;
    if (!f) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memcpy(out->vertices, f->v, sizeof out->vertices);
    out->depth = f->depth;
    out->leaf = f->children == NULL;
    out->record_count = lightvec__face_records(f);
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_cache_locate(const lightvec_cache *c, const float direction[3], uint32_t *index)
{
    lightvec__walk w;
    const lightvec__face *f, *leaf;
    lightvec__vec3 d;
    float dd[3];
    uint32_t i = 0;
    if (!c || !index || !lightvec__unit(direction, &d)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    dd[0] = d.x; dd[1] = d.y; dd[2] = d.z;
    leaf = &c->roots[lightvec__root_of(c->roots, dd)];
    while (leaf->children) leaf = &((const lightvec__face *)leaf->children)[lightvec__child_of(leaf, dd)];
    lightvec__walk_init(&w, c);
    while ((f = lightvec__walk_next(&w)) != NULL && f != leaf) i++;
    *index = i;
    return LIGHTVEC_OK;
}

/* ---- optimize: one kd-tree per leaf, built as jobs -------------------------------------- */

typedef struct lightvec__rebuild {
    lightvec_cache *c;
    lightvec__face **faces;
    lightvec__index **built;         /* per face: its new index, NULL on failure */
} lightvec__rebuild;

static void lightvec__rebuild_job(void *ctx, uint32_t i)
{
    lightvec__rebuild *r = (lightvec__rebuild *)ctx;
    const lightvec__index *old = (const lightvec__index *)r->faces[i]->index;
    lightvec__entry *items = (lightvec__entry *)lightvec__alloc_array(&r->c->a, r->faces[i]->count, sizeof *items);
    r->built[i] = NULL;
    if (!items) return;
    lightvec__index_items(old, old->tree_count, items);
    r->built[i] = lightvec__index_single(r->c, items, r->faces[i]->count);
    lightvec__free(&r->c->a, items);
}

/* Leaves whose index has more than one kd-tree or a non-empty tail. */
static uint32_t lightvec__fragmented_leaves(lightvec_cache *c, lightvec__face **out)
{
    lightvec__walk w;
    const lightvec__face *f;
    uint32_t n = 0;
    lightvec__walk_init(&w, c);
    for (f = lightvec__walk_next(&w); f; f = lightvec__walk_next(&w)) {
        const lightvec__index *idx = (const lightvec__index *)f->index;
        if (!f->children && idx && (idx->tree_count > 1 || idx->tail_count > 0)) {
            if (out) out[n] = (lightvec__face *)f;
            n++;
        }
    }
    f = &c->omni;
    if (f->index && (((const lightvec__index *)f->index)->tree_count > 1 ||
                     ((const lightvec__index *)f->index)->tail_count > 0)) {
        if (out) out[n] = (lightvec__face *)f;
        n++;
    }
    return n;
}

LIGHTVEC_API lightvec_result lightvec_cache_optimize(lightvec_cache *c)
{
    lightvec__rebuild r;
    uint32_t n, done = 0, i;
    lightvec_result res = LIGHTVEC_OK;
    const uint32_t batch = 64;
    if (!c) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    n = lightvec__fragmented_leaves(c, NULL);
    if (!n) return LIGHTVEC_OK;
    r.c = c;
    r.faces = (lightvec__face **)lightvec__alloc_array(&c->a, n, sizeof *r.faces);
    r.built = (lightvec__index **)lightvec__alloc_array(&c->a, n, sizeof *r.built);
    if (!r.faces || !r.built) {
        lightvec__free(&c->a, r.faces);
        lightvec__free(&c->a, r.built);
        return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    }
    lightvec__fragmented_leaves(c, r.faces);
    while (done < n && res == LIGHTVEC_OK) {
        uint32_t count = n - done < batch ? n - done : batch;
        lightvec__rebuild sub = r;
        sub.faces += done;
        sub.built += done;
        lightvec__run_jobs(c->parallel_for, c->parallel_user, lightvec__rebuild_job, &sub, count);
        for (i = 0; i < count; i++) {
            lightvec__face *f = sub.faces[i];
            lightvec__index *old = (lightvec__index *)f->index;
            uint32_t t;
            if (!sub.built[i]) { res = LIGHTVEC_ERROR_OUT_OF_MEMORY; continue; }
            lightvec__store_ptr(&f->index, sub.built[i]);
            for (t = 0; t < old->tree_count; t++) lightvec__retire(c, old->trees[t], old->trees[t]->bytes);
            lightvec__retire(c, old, sizeof *old);
        }
        done += count;
        if (res == LIGHTVEC_OK && c->progress && c->progress(c->progress_user, done, n)) res = LIGHTVEC_ERROR_CANCELLED;
    }
    lightvec__reclaim(c);
    lightvec__free(&c->a, r.faces);
    lightvec__free(&c->a, r.built);
    return res;
}

/* ======================================================================
   13. save and load
   ---------------------------------------------------------------------- */
static const unsigned char lightvec__magic[8] = { 'L', 'I', 'G', 'H', 'T', 'V', 'E', 'C' };

/* A record's 51 floats in a fixed order (then its flags). */
#define LIGHTVEC__RECORD_FLOATS 51

static void lightvec__record_floats(const lightvec_record *r, float f[LIGHTVEC__RECORD_FLOATS])
{
    int c;
    memcpy(f, r->position, 12);
    memcpy(f + 3, r->normal, 12);
    memcpy(f + 6, r->outgoing, 12);
    memcpy(f + 9, r->vector.direction, 12);
    memcpy(f + 12, r->vector.magnitude, 12);
    memcpy(f + 15, r->vector.glossy_direction, 12);
    memcpy(f + 18, r->vector.glossy_magnitude, 12);
    memcpy(f + 21, r->irradiance, 12);
    for (c = 0; c < 3; c++) memcpy(f + 24 + 3 * c, r->gradient[c], 12);
    memcpy(f + 33, r->glossy, 12);
    for (c = 0; c < 3; c++) memcpy(f + 36 + 3 * c, r->glossy_gradient[c], 12);
    f[45] = r->distance;
    f[46] = r->glossy_distance;
    f[47] = r->exponent;
    f[48] = r->radius;
    f[49] = r->visibility;
    f[50] = r->glossy_share;
}

static void lightvec__floats_record(const float f[LIGHTVEC__RECORD_FLOATS], lightvec_record *r)
{
    int c;
    memcpy(r->position, f, 12);
    memcpy(r->normal, f + 3, 12);
    memcpy(r->outgoing, f + 6, 12);
    memcpy(r->vector.direction, f + 9, 12);
    memcpy(r->vector.magnitude, f + 12, 12);
    memcpy(r->vector.glossy_direction, f + 15, 12);
    memcpy(r->vector.glossy_magnitude, f + 18, 12);
    memcpy(r->irradiance, f + 21, 12);
    for (c = 0; c < 3; c++) memcpy(r->gradient[c], f + 24 + 3 * c, 12);
    memcpy(r->glossy, f + 33, 12);
    for (c = 0; c < 3; c++) memcpy(r->glossy_gradient[c], f + 36 + 3 * c, 12);
    r->distance = f[45];
    r->glossy_distance = f[46];
    r->exponent = f[47];
    r->radius = f[48];
    r->visibility = f[49];
    r->glossy_share = f[50];
}

static void lightvec__put_record(lightvec__writer *w, const lightvec_record *r)
{
    float f[LIGHTVEC__RECORD_FLOATS];
    lightvec__record_floats(r, f);
    lightvec__put_f32_array(w, f, LIGHTVEC__RECORD_FLOATS);
    lightvec__put_u32(w, r->flags);
}

/* One serialized record, read in one call and decoded little-endian. */
static void lightvec__get_record(lightvec__reader *r, lightvec_record *rec)
{
    unsigned char b[LIGHTVEC__RECORD_BYTES];
    uint32_t v[LIGHTVEC__RECORD_FLOATS + 1];
    float f[LIGHTVEC__RECORD_FLOATS];
    int i;
    lightvec__get(r, b, sizeof b);
    for (i = 0; i <= LIGHTVEC__RECORD_FLOATS; i++)
        v[i] = (uint32_t)b[4 * i] | ((uint32_t)b[4 * i + 1] << 8) | ((uint32_t)b[4 * i + 2] << 16) |
               ((uint32_t)b[4 * i + 3] << 24);
    memcpy(f, v, sizeof f);
    lightvec__floats_record(f, rec);
    rec->flags = v[LIGHTVEC__RECORD_FLOATS];
}

LIGHTVEC_API lightvec_result lightvec_save(const lightvec_cache *c, lightvec_write_fn write, void *user)
{
    lightvec__writer w;
    uint32_t i, n;
    if (!c || !write) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    w.write = write;
    w.user = user;
    w.failed = 0;
    lightvec__crc_init(&w.crc);
    n = c->record_count;
    lightvec__put(&w, lightvec__magic, 8);
    lightvec__put_u32(&w, LIGHTVEC_FILE_FORMAT_VERSION);
    lightvec__put_u64(&w, LIGHTVEC__SETTINGS_BYTES + 8u + (uint64_t)n * LIGHTVEC__RECORD_BYTES);
    lightvec__put_u32(&w, (uint32_t)c->p.kind);
    lightvec__put_f32(&w, c->p.radius_scale);
    lightvec__put_f32(&w, c->p.max_change);
    lightvec__put_f32(&w, c->p.normal_angle);
    lightvec__put_f32(&w, c->p.direction_angle);
    lightvec__put_u32(&w, c->p.min_valid);
    lightvec__put_u32(&w, c->p.split_threshold);
    lightvec__put_u32(&w, c->p.max_depth);
    lightvec__put_u32(&w, (uint32_t)c->p.interpolation);
    lightvec__put_u32(&w, c->p.max_neighbors);
    lightvec__put_f32(&w, c->p.front);
    lightvec__put_u32(&w, c->p.flags);
    lightvec__put_u64(&w, n);
    for (i = 0; i < n && !w.failed; i++) {
        lightvec_record rec = *lightvec__record_at(c, i);
        rec.radius = *lightvec__radius_at(c, i);
        lightvec__put_record(&w, &rec);
    }
    lightvec__put_u32(&w, lightvec__crc_final(&w.crc));
    return w.failed ? LIGHTVEC_ERROR_IO : LIGHTVEC_OK;
}

/* Builds the index of a freshly loaded cache: items go to their root face
   (or the view-independent leaf); each root is filled as one job. */
typedef struct lightvec__bulk {
    lightvec_cache *c;
    lightvec__entry *items;
    uint32_t start[22];              /* 20 roots, the view-independent leaf, end */
    int failed[21];
} lightvec__bulk;

static void lightvec__bulk_job(void *ctx, uint32_t i)
{
    lightvec__bulk *b = (lightvec__bulk *)ctx;
    lightvec__face *f = i < 20 ? &b->c->roots[i] : &b->c->omni;
    b->failed[i] = lightvec__face_fill(b->c, f, b->items + b->start[i], b->start[i + 1] - b->start[i]) != 0;
}

static uint32_t lightvec__slot_of(const lightvec_cache *c, const lightvec_record *r)
{
    return (r->flags & LIGHTVEC_RECORD_VIEW_INDEPENDENT) ? 20u : lightvec__root_of(c->roots, r->outgoing);
}

static lightvec_result lightvec__bulk_index(lightvec_cache *c)
{
    lightvec__bulk b;
    uint32_t n = c->record_count, i, next[21];
    int k, failed = 0;
    memset(&b, 0, sizeof b);
    b.c = c;
    b.items = (lightvec__entry *)lightvec__alloc_array(&c->a, n, sizeof *b.items);
    if (!b.items) return LIGHTVEC_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < n; i++) b.start[lightvec__slot_of(c, lightvec__record_at(c, i)) + 1]++;
    for (k = 1; k < 22; k++) b.start[k] += b.start[k - 1];
    memcpy(next, b.start, sizeof next);
    for (i = 0; i < n; i++) {
        const lightvec_record *r = lightvec__record_at(c, i);
        lightvec__make_item(&c->p, r, i, &b.items[next[lightvec__slot_of(c, r)]++]);
    }
    lightvec__run_jobs(c->parallel_for, c->parallel_user, lightvec__bulk_job, &b, 21);
    lightvec__free(&c->a, b.items);
    for (k = 0; k < 21; k++) failed |= b.failed[k];
    return failed ? LIGHTVEC_ERROR_OUT_OF_MEMORY : LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_load(const lightvec_cache_desc *desc, lightvec_read_fn read, void *user,
                                           lightvec_cache **out)
{
    lightvec__reader r;
    lightvec_cache_desc d;
    lightvec_cache *c = NULL;
    unsigned char magic[8], crc_bytes[4];
    uint32_t version, expected, stored, kind, interp;
    uint64_t payload, count, i;
    lightvec_result res;
    if (!out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!read) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    r.read = read;
    r.user = user;
    r.failed = 0;
    r.remaining = 20u;
    lightvec__crc_init(&r.crc);
    lightvec__get(&r, magic, 8);
    version = lightvec__get_u32(&r);
    payload = lightvec__get_u64(&r);
    if (r.failed || memcmp(magic, lightvec__magic, 8) != 0) return LIGHTVEC_ERROR_CORRUPT_DATA;
    if (version != LIGHTVEC_FILE_FORMAT_VERSION) return LIGHTVEC_ERROR_VERSION;
    r.remaining = payload;
    kind = lightvec__get_u32(&r);
    d.kind = kind == 1u ? LIGHTVEC_KIND_INDIRECT : (kind == 2u ? LIGHTVEC_KIND_DIRECT : (lightvec_kind)99);
    d.radius_scale = lightvec__get_f32(&r);
    d.max_irradiance_change = lightvec__get_f32(&r);
    d.max_normal_angle = lightvec__get_f32(&r);
    d.max_direction_angle = lightvec__get_f32(&r);
    d.min_valid = lightvec__get_u32(&r);
    d.face_split_threshold = lightvec__get_u32(&r);
    d.max_face_depth = lightvec__get_u32(&r);
    interp = lightvec__get_u32(&r);
    d.interpolation = interp >= 1u && interp <= 3u ? (lightvec_interpolation)interp : (lightvec_interpolation)99;
    d.max_neighbors = lightvec__get_u32(&r);
    d.front_tolerance = lightvec__get_f32(&r);
    d.flags = lightvec__get_u32(&r);
    count = lightvec__get_u64(&r);
    if (r.failed || !lightvec__can_hold(&r, count, LIGHTVEC__RECORD_BYTES) || count >= 0xFFFFFFFFu ||
        r.remaining != count * LIGHTVEC__RECORD_BYTES || !(d.radius_scale > 0.0f) ||
        !(d.max_irradiance_change > 0.0f) || !(d.max_normal_angle > 0.0f) || !(d.max_direction_angle > 0.0f) ||
        d.min_valid == 0 || d.face_split_threshold == 0 || d.max_face_depth == 0 || d.max_neighbors == 0 ||
        !(d.front_tolerance > 0.0f))
        return LIGHTVEC_ERROR_CORRUPT_DATA;
    res = lightvec__cache_new(&d, &c);
    if (res == LIGHTVEC_ERROR_INVALID_ARGUMENT && lightvec__allocator_valid(&d.allocator))
        return LIGHTVEC_ERROR_CORRUPT_DATA; /* settings out of range */
    if (res != LIGHTVEC_OK) return res;
    for (i = 0; i < count; i++) {
        lightvec_record rec, clean, *slot;
        lightvec__get_record(&r, &rec);
        if (r.failed || !lightvec__record_clean(&c->p, &rec, &clean) || !isfinite(rec.radius) ||
            !(rec.radius > 0.0f)) {
            res = LIGHTVEC_ERROR_CORRUPT_DATA;
            break;
        }
        clean.radius = rec.radius; /* as neighbour clamping left it */
        slot = lightvec__record_reserve(c, (uint32_t)i);
        if (!slot) { res = LIGHTVEC_ERROR_OUT_OF_MEMORY; break; }
        *slot = clean;
        *lightvec__radius_at(c, (uint32_t)i) = clean.radius;
        c->record_count = (uint32_t)i + 1u;
    }
    if (res == LIGHTVEC_OK) {
        expected = lightvec__crc_final(&r.crc);
        r.remaining = 4u;
        lightvec__get(&r, crc_bytes, 4);
        stored = (uint32_t)crc_bytes[0] | ((uint32_t)crc_bytes[1] << 8) | ((uint32_t)crc_bytes[2] << 16) |
                 ((uint32_t)crc_bytes[3] << 24);
        if (r.failed || stored != expected) res = LIGHTVEC_ERROR_CORRUPT_DATA;
    }
    if (res == LIGHTVEC_OK) res = lightvec__bulk_index(c);
    if (res != LIGHTVEC_OK) {
        lightvec_cache_destroy(c);
        return res;
    }
    *out = c;
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_save_to_memory(const lightvec_cache *c, const lightvec_allocator *a,
                                                     void **data, size_t *size)
{
    lightvec__membuf m;
    lightvec_allocator zero;
    lightvec_result r;
    if (!data || !size) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *data = NULL;
    *size = 0;
    memset(&zero, 0, sizeof zero);
    if (!a) a = &zero;
    if (!c || !lightvec__allocator_valid(a)) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(&m, 0, sizeof m);
    m.a = a;
    r = lightvec_save(c, lightvec__membuf_write, &m);
    if (r != LIGHTVEC_OK) {
        lightvec__free(a, m.data);
        return r == LIGHTVEC_ERROR_IO ? LIGHTVEC_ERROR_OUT_OF_MEMORY : r;
    }
    *data = m.data;
    *size = m.size;
    return LIGHTVEC_OK;
}

LIGHTVEC_API lightvec_result lightvec_load_from_memory(const void *data, size_t size, const lightvec_cache_desc *desc,
                                                       lightvec_cache **out)
{
    lightvec__membuf m;
    if (!out) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!data && size) return LIGHTVEC_ERROR_INVALID_ARGUMENT;
    memset(&m, 0, sizeof m);
    m.data = (unsigned char *)(uintptr_t)data; /* only read */
    m.size = size;
    return lightvec_load(desc, lightvec__membuf_read, &m, out);
}

LIGHTVEC_API void lightvec_free_memory(const lightvec_allocator *a, void *data)
{
    lightvec_allocator zero;
    memset(&zero, 0, sizeof zero);
    lightvec__free(a ? a : &zero, data);
}

#endif /* LIGHTVEC_IMPLEMENTATION */

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
