/* irrvol.h - v0.5.6 - irradiance volume for lighting moving objects - public domain or MIT, see end of file

   IRRVOL.H: a bilevel grid of directional irradiance samples that lights moving objects by interpolation.

   The irradiance volume (Greger 1996) samples the irradiance distribution
   function H(x, w) of a static scene at the vertices of a bilevel grid: a
   regular first-level grid over the scene, refined by a second-level grid in
   every cell that contains geometry or across which the light changes. At
   each grid vertex ("sample") radiance is gathered along 2k^2 equal-area
   directions of the Shirley-Chiu concentric map (k x k bins per hemisphere),
   and the irradiance of a surface facing each bin direction is summed from
   it (eq. 4.3, or the moment of order n, eq. 4.8). A query at any position
   and normal finds the cell (eq. 4.4-4.6), the bins of the direction
   (inverse concentric map) and interpolates between the cell's eight
   samples: millions of queries per second and core (tests/bench_irrvol.c
   prints the rates of every filter and weighting), enough to re-light
   every vertex of moving objects every frame. A moving object's diffuse radiance
   is then reflectance * H / pi (eq. 4.7).

   Built for real levels, as engines expect of probe volumes today (DDGI,
   Unity's adaptive probe volumes, EEVEE): no light through walls (each
   sample keeps the distances its rays travelled and queries weigh samples
   by a visibility test, samples inside walls move out or drop out), no
   seams between the levels (hanging samples), compact spherical-harmonic
   encodings with a GLSL evaluator, refinement where the light changes.

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
       d.indices = idx;    d.triangle_count = nt;   // front faces wind counter-clockwise
       d.triangle_materials = mat_of_tri;
       d.materials = mats; d.material_count = 2;
       mats[1].flags = IRRVOL_MATERIAL_IMPORTANT;   // the lamp: never missed
       if (irrvol_build(&d, &vol) != IRRVOL_OK) ...;
       for each vertex of a moving object:
           float h[3];
           irrvol_query(vol, p, n, h);              // irradiance W/m^2, leak-safe
           colour = reflectance * h / pi;           // eq. 4.7
       irrvol_destroy(vol);

   CONFIGURATION MACROS

       IRRVOL_STATIC              make every function static (private to one file)
       IRRVOL_API                 linkage of public functions (default: extern)
       IRRVOL_MALLOC, IRRVOL_FREE replace malloc/free (define both or neither)
       IRRVOL_BVH_BINS            SAH bins of the BVH build (default 16)
       IRRVOL_NO_SIMD             the queries' portable scalar code only (the same bits as SSE2)
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
       void     irrvol_query_filter(const irrvol *vol, irrvol_filter filter, irrvol_weighting weighting,
                                    const float pos[3], const float dir[3], float rgb[3]);
       void     irrvol_query_glossy(const irrvol *vol, const float pos[3], const float normal[3],
                                    const float to_eye[3], float rgb[3]);
       void     irrvol_query_many(const irrvol *vol, irrvol_filter filter, irrvol_weighting weighting,
                                  uint32_t count, const float *pos, size_t pos_stride, const float *dir,
                                  size_t dir_stride, float *rgb);
       void     irrvol_query_sh(const irrvol *vol, uint32_t order, irrvol_weighting weighting,
                                const float pos[3], const float dir[3], float rgb[3]);
     samples and bins (inspection, irradiance spheres, tests)
       irrvol_result irrvol_sample(const irrvol *vol, uint32_t index, irrvol_sample_info *info);
       irrvol_result irrvol_sample_values(const irrvol *vol, uint32_t index, float *irradiance,
                                          float *radiance);   // bins x rgb each, or NULL
       void     irrvol_bin_direction(const irrvol *vol, uint32_t bin, float dir[3]);
       uint32_t irrvol_direction_bin(const irrvol *vol, const float dir[3]);
     the volume on the GPU
       irrvol_result irrvol_gpu_export(const irrvol *vol, uint32_t sh_order, irrvol_gpu_layout *layout,
                                       uint32_t *index, size_t index_capacity, float *data,
                                       size_t data_capacity);
       size_t   irrvol_glsl_source(char *buffer, size_t capacity);
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
   cell holds 2^3 sub-cells). Neighbouring second-level grids share the
   samples on their common faces.

   Refinement by light (6.1.1). The first level is gathered first. Trilinear
   interpolation is exact where light changes linearly, so what counts is
   how far the first-level samples bend away from a straight line: along
   each axis through a sample, the second difference of its neighbours'
   irradiance spheres (luminance, summed over the bins) over 8 times their
   level, the error a parabola through the three leaves midway. A cell is
   refined when that predicted error exceeds desc.refine_threshold (default
   0.05) at one of its corners: near lights, across shadow edges, not along
   smooth gradients. info.light_refined_cells counts those cells and
   info.bytes reports the memory; a negative threshold refines only where
   geometry is (the thesis).

   No seams. A second-level sample on a face or an edge of an unrefined cell
   is a hanging sample (as in adaptive finite elements): it gathers nothing
   and holds the unrefined cell's own bilinear (face) or linear (edge) blend
   of the first-level samples around it, so both sides of every cell face
   interpolate the same values. Leak-safe queries replace a hanging sample by
   those first-level samples, each weighed by its own visibility, so they are
   seamless too; float rounding remains (largest relative jump 9e-7 over the
   faces of a room with a lamp, tests/test_irrvol_levels.c).

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
   reflected ray. Emitters are two-sided: either side of a triangle has its
   material's radiance. The chain follows at most desc.max_depth reflections
   and stops when the remaining weight falls under desc.min_weight; a cut
   chain and a ray that leaves the scene see the sky (desc.background or
   desc.environment), and glass passes light (GLASS AND SKY below). With
   desc.supersamples = s > 1, each bin averages s x s jittered rays (one
   stratum each).

   Rays and desc.trace. Gather rays start at a sample with a unit direction
   and tmax = FLT_MAX; hit.t is the distance along it, hit.u and hit.v the
   barycentric weights of the triangle's second and third vertex, and
   hit.triangle the triangle's index (out of range, negative or non-finite
   answers count as misses). desc.trace and desc.radiance are called from
   the parallel_for jobs at once: they must be thread-safe. With
   desc.radiance and triangles, each gather ray is also traced (desc.trace or
   the built-in BVH) for its hit distance. IMPORTANT sampling always uses a
   small internal BVH over the IMPORTANT triangles, also with desc.trace.

   Glass and sky. A material with transmittance t > 0 (any channel) is a
   thin dielectric, as in the examples' tracer and the reference renderer:
   a gather ray that meets it, from either side, gets the pane's own
   radiance plus t times the radiance straight behind it (no refraction,
   no change of direction), per RGB channel; the ray goes on from just past
   the pane. A ray crosses at most IRRVOL_MAX_GLASS_LAYERS (16) panes; the
   next one blocks it (it sees nothing more). A transmitting material's
   specular coefficient is not followed (put a pane's reflection in its
   radiance). Rays that leave the scene, through glass or not, see the
   sky: desc.background, the constant sky radiance, or desc.environment, a
   small HDR map of environment_width x environment_height rgb floats,
   latitude-longitude with +y up: row r covers the angle theta from +y in
   [pi r / height, pi (r + 1) / height) (row 0 at the zenith), column c the
   azimuth phi = atan2(z, x) in [2 pi c / width - pi, 2 pi (c + 1) / width
   - pi); a direction takes its texel's radiance (no filtering, so the map
   is exactly piecewise constant; a map of one radiance L is the constant
   sky L bit for bit). This is the layout of the examples' ex_sky
   (examples/common/scene_sky.h). The map is read during the build only.
   Leak prevention and glass: a pane counts as a wall. Each sample's hit
   distances end at the first surface, glass included, so a query on one
   side of a window is not interpolated from samples on the other side.
   That is what the light does: behind glass the irradiance is the
   outside's times t at most, plus the room's own light, a jump across the
   pane like the jump across a wall, and the samples on the room side
   already gather what comes through the window. A pane's back face does
   not count toward "inside geometry" (a pane has no inside), so samples
   behind panes that face away stay valid. Measured against the reference
   (tests/ref_irrvol_glass.c, a closed room with a window in the ceiling
   under a sky, single and double glazing, an environment map): every bin
   facing up of the samples under the window within 2 % (largest 1.9 %,
   the reference's standard error 0.6 %).

   Leak-safe queries (the default weighting, VISIBILITY). Each sample keeps
   what its rays saw of the surfaces around it, per texel of an n x n
   octahedral map (desc.visibility_resolution, default 8): where DDGI
   (Majercik et al. 2019) keeps the mean and mean square hit distance, this
   keeps a least-squares fit of the inverse hit distance s = 1 / d over a
   cos^p lobe around the texel (p ~ 13 at 8 x 8, 50 at 16 x 16), s(w) = g . w,
   and the variance the fit leaves. 1 / d of a plane is exactly linear in
   the direction, so a wall is predicted exactly at any angle, however close
   the sample stands to it, where averaged distances blur it by the lobe's
   width; so 8 x 8 texels (1.6 KB a sample with their mirrored border) do
   what 16 x 16 do on the office (relative L1 error 5.1 % against 4.9 %).
   A query weighs each corner by its trilinear weight times
   (1 + n . toward the sample) / 2 + 0.2 (DDGI's backface term, which
   squares the first part; unsquared it bends the weights less where no
   surface is: 4.9 % against 5.9 % on the office) and, when the test point
   lies beyond the predicted surface (1/r < g . w), the Chebyshev bound
   (var / (var + (g . w - 1/r)^2))^3; weights under 0.2 fade as w^3 / 0.04
   and the weights are renormalised. The test point is the
   query point moved info.normal_bias (desc.normal_bias, default 0.02, times
   the finest sample spacing) along the query direction. When no corner is
   visible, or an input is NaN, the plain weights stand. Without triangles
   no sample sees a surface: only the backface term remains. The queries
   read what these weights need in few cache lines: each sub-cell keeps a
   record of its eight corners' ids, origins and reaches (192 bytes; one
   with hanging corners also the list of samples that stand in for them,
   12 bytes a term, made at build and load), and
   a test point within its sample's reach (0.999 over the largest |g| of
   the map: no point there can lie beyond a predicted surface) skips the
   map, with the same result to the bit. So does a sample whose map puts
   no surface closer than any point of the query's sub-cell (grown by the
   normal bias; each record keeps a mask of those samples, made at build
   and load): on the office 54 % of a random query's samples skip their
   maps instead of the 36 % within reach (the generated 4k-triangle
   building: 21 % instead of 10 %), and a group of four that all skip
   (41 % on the office) locates no texel. A sub-cell with hanging corners
   reads up to 32 terms (a corner's parents in its place), but they name
   eight distinct samples (the parents are corners of the refined cell
   around it), so its record holds those eight, origins and reaches, and a
   leak-safe query adds each sample's term weights first and weighs eight
   samples, as in any other sub-cell, instead of every term: the same
   weights up to float rounding (largest difference 2.4e-7 of the result
   on 1M random office queries), 1.09x the leak-safe rate on the office.
   Plain (TRILINEAR) queries still add every term, so NEAREST's bits do
   not change. A leak-safe query asks for the bins' values it will sum
   before its texels, and computes the weights while both arrive (the same
   bits; PERFORMANCE).
   IRRVOL_WEIGHTING_TRILINEAR is the thesis's plain trilinear interpolation.
   Two closed rooms behind a 2 cm wall, one lit, one dark: the leak-safe
   query gives 0.00 % of the lit side 1 cm and 10 cm into the dark room
   where the plain query gives 81 % and 70 % (tests/test_irrvol_levels.c).

   Samples inside geometry. A triangle's front is the side from which it
   winds counter-clockwise ((v1 - v0) x (v2 - v0) points out of solids and
   into rooms); materials flagged TWO_SIDED have two fronts. A sample that
   sees back faces over more than a quarter of its sphere (each bin counts
   its solid angle) is inside geometry: it moves through the nearest back
   face it saw to 5 % of its spacing in front of that surface and gathers
   again (DDGI's relocation, Unity's virtual offset) if that is within 45 %
   of its spacing; otherwise, or if it is still inside, it is invalid.
   Invalid samples never enter a leak-safe query; their stored values are
   the mean of their valid neighbours (dilation), which plain trilinear
   queries and the harmonics use. Scenes whose triangles wind at random
   make samples invalid: fix the winding or flag the materials TWO_SIDED.
   irrvol_sample reports each sample's state (valid, relocated, invalid,
   hanging) and origin, where it gathered; irrvol_sample_values gives an
   invalid sample's dilated values and a hanging sample's blend.

   Irradiance (4.2.3, 4.4). H^n(w_j) = sum_i L_i W(i, j), with W(i, j) =
   (n+1)/2 times the integral of max(0, w . w_j)^n over bin i (eq. 4.1 with
   the radiance constant over each bin; n = 1 is eq. 4.3). The integral is
   evaluated at w x w sub-directions per bin (desc.weight_subdivisions,
   default 4), so that a uniform radiance L gives pi L within 0.05 % at
   k = 17; weight_subdivisions = 1 evaluates eq. 4.3 / 4.8 literally at the
   bin centres (0.7 % off at k = 17). The weights form one (2k^2)^2 matrix
   shared by all samples; each sample's irradiance is a matrix product,
   summed exactly, never approximated.

   Precision (the compact store, the default). The bins are kept in
   32-bit RGB9E5 words, the shared-exponent format GPUs filter: three 9-bit
   mantissas under the largest channel's 5-bit exponent, the volume scaled
   by a power of two that puts its largest value at the top of the range.
   Rounding to the nearest mantissa errs by at most 2^-9 (0.2 %) of a bin's
   largest channel, in every channel: a channel 1/4 of the largest can be
   0.8 % off, one 1/64 of it 12 %; a query, a weighted mean of bins, errs by
   at most 2^-9 of the sum of its channels (test_compact_store in
   tests/test_irrvol.c). Values below 2^-40 of the volume's largest,
   negative ones (a radiance callback can return them) and NaN are stored
   as 0. A third of the memory (4 bytes a bin instead of 12: 2.3 KB a
   sample at k = 17), so random queries miss the caches and the TLB less.
   The gather, refinement by light, dilation and the harmonics work in
   floats; only the stored bins are rounded, once, at the end of the build.
   desc.full_precision keeps three floats a bin (an engine that reads the
   bins back for its own processing, tests of the gather's accuracy);
   info.bin_bytes says which store a volume has, and saved volumes keep it.

   Harmonics (Ramamoorthi and Hanrahan 2001). Each sample also holds the
   radiance projected on the real spherical harmonics of order l <= 2 (the
   bins integrated like the weights), each band scaled by the lobe's A_l:
   irradiance E(n) = sum A_l L_lm Y_lm(n), nine coefficients x rgb (L2) or
   the first four (L1). irrvol_query_sh evaluates them with the volume's
   weighting (clamped at zero); irrvol_gpu_export writes them with the
   grid, the hanging samples and the visibility moments into two flat
   arrays, and irrvol_glsl_source gives the GLSL function that evaluates
   them like irrvol_query_sh. On the office the L2 harmonics give the bins'
   irradiance with a median difference of 1.7 % (L1: 8 %).

   On the GPU.

       irrvol_gpu_layout l;
       irrvol_gpu_export(vol, 2, &l, NULL, 0, NULL, 0);             // sizes
       uint32_t *index = malloc(l.index_count * 4);
       float *data = malloc(l.data_count * 4);
       irrvol_gpu_export(vol, 2, &l, index, l.index_count, data, l.data_count);
       // upload index to storage buffer binding 0, data to binding 1
       size_t n = irrvol_glsl_source(NULL, 0);
       char *glsl = malloc(n + 1);
       irrvol_glsl_source(glsl, n + 1);
       // shader text: "#version 430\n" + glsl, then in any stage:
       //     vec3 e = irrvol_irradiance(position, normal);   // W/m^2

   The text defines IRRVOL_INDEX(i) and IRRVOL_DATA(i) to read the buffers
   unless the engine defines them first (a texture fetch, other bindings:
   IRRVOL_INDEX_BINDING, IRRVOL_DATA_BINDING). The arrays hold the volume's
   own tables: the first-level samples first in x-fastest order, each
   sample's origin and validity, its bordered visibility map and its
   harmonics; irrvol_gpu_layout names the offsets.

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
   BILINEAR (future work 6.1.2, the default) interpolates the four nearest
   bin centres on the concentric square, across the equator too: 4x the
   memory reads. irrvol_query_glossy mirrors the view vector about the normal
   (fig. 4.17) for moment volumes (desc.moment > 1). irrvol_query_many answers
   a batch (the vertices of a moving object) with the same results, faster:
   it prepares each query a few ahead and prefetches the values it will read.
   With SSE2 (every x86-64 compiler) a query finds its cell and sub-cell
   with the three axes in one register (the sub-cell worked out while the
   cell is read), its direction's square point with selects where branches
   would mispredict on random directions (both major-axis cases in two
   lanes, one kept), BILINEAR's four bins in one register and their words
   four samples at a time; the portable code (IRRVOL_NO_SIMD) gives the
   same bits. BILINEAR adds its
   terms by lanes (every fourth term, the lanes pairwise at the end), which
   differs from adding them in turn by float rounding only (at most 4.6e-7
   of a query's largest channel on 1M random office queries).

   Determinism. Each sample draws its jitter from a stream seeded by
   (desc.seed, sample index): a volume is bit-identical for any thread count.

   Threads. Every function taking a const irrvol * (queries, irrvol_info,
   irrvol_sample, irrvol_sample_values, the bin functions, irrvol_gpu_export,
   irrvol_save and irrvol_save_to_memory) only reads the volume, so any
   number of threads may call them on one volume at once, and
   irrvol_visibility_ratio keeps no shared state, so concurrent calls on one
   const desc with distinct ratio arrays are safe too.

   Progress. desc.progress(user, done, total) counts gathered samples; with
   refinement by light the total is known after the first level and grows
   once, when the refined cells' samples join.

   PERFORMANCE

   tests/bench_irrvol.c prints the query rates on the default office volume
   (one thread, thread CPU time, -O2, the load average beside them); the
   README quotes them. What a query costs, counted by callgrind over
   200,000 random office queries (v0.5.5, GCC 12, -O2): NEAREST plain 456
   instructions (v0.5.4: 486), BILINEAR plain 759 (754), NEAREST leak-safe
   1,202 (1,269), the leak-safe BILINEAR default 1,513 (1,724). Every
   v0.5.5 change keeps every result to the bit: v0.5.4 and v0.5.5 gave the
   same floats on 2M random queries (every filter and weighting, single
   and batched, on the office; NEAREST and the default on building_1k,
   building_4k and the Cornell box), and on office queries with zero,
   infinite and NaN inputs built with GCC, with clang and with
   IRRVOL_NO_SIMD.
   What bounds the rates: a random office query reads the corners' words
   in one bin row, 3.45 distinct cache lines on average (NEAREST), 13.8 in
   four rows (BILINEAR), besides its sub-cell's record; the leak-safe
   weights read the record's three lines and two rows of texels for each
   sample that reads its map (about half of them on the office). The office volume is 6.1 MB, its bins 3.6 MB, against 1 MB of
   L2 per core on the benchmark's machine (AMD EPYC Zen 4), so most of
   those lines come from L3 or memory. The misses of one query overlap
   each other; those of consecutive single queries overlap only as far as
   the processor's reorder window (about 320 instructions on Zen 4) reaches
   into the next query, and a NEAREST query is longer than that: its sum
   adds the terms in order, one term at a time, to give the thesis's value
   bit for bit, about 13 instructions a term. irrvol_query_many prepares
   queries ahead and prefetches, so its misses overlap (1.3x the single
   rate at a load of 1, 2.5x at a load of 5). 20 M single NEAREST
   queries/s is 50 ns a query: without misses one takes 40-55 ns (8
   repeated queries), with the office's misses about 70 ns at a load of 1
   (v0.5.4) and 150 ns at a load of 5, when other processes take the
   shared caches.

   VALIDATION AND CONTRACT (tests/test_irrvol_contract.c)

   What each function checks (a failed check returns the named code and
   changes nothing), and what the caller must guarantee (unchecked: breaking
   it is undefined behaviour).
     irrvol_build        checks: desc and out non-NULL; allocator both or
                         neither; every position finite; every index below
                         vertex_count and triangle_count <= UINT32_MAX / 3;
                         every material index below material_count; material
                         values and vertex radiance finite and >= 0,
                         transmittances at most 1; background finite and
                         >= 0; environment NULL, or 1..65536 texels a side
                         with every texel finite and >= 0; strides
                         >= 12 bytes; grid, resolution and option ranges;
                         bounds finite with min < max (INVALID_ARGUMENT),
                         all before the first allocation except the scene's
                         own bounds (zero size along an axis: a flat
                         scene), found with the grid, which frees what it
                         allocated. Zero-area triangles are skipped and
                         counted.
                         Contract: positions hold vertex_count vertices at
                         the stride, indices 3 * triangle_count entries,
                         triangle_materials triangle_count entries,
                         materials material_count entries, vertex_radiance
                         vertex_count entries, environment 3 * width *
                         height floats; none change during the build;
                         trace and radiance are thread-safe under
                         parallel_for.
     irrvol_destroy      accepts NULL. Contract: vol came from build or load
                         and is destroyed once.
     irrvol_info, irrvol_sample, irrvol_sample_values
                         check NULL pointers, the index, and that radiance
                         was kept (INVALID_ARGUMENT). Contract: irradiance and
                         radiance hold bins x 3 floats (either may be NULL).
     queries             check nothing and never fail: positions outside
                         the bounds (infinite and NaN ones too) take the
                         boundary's cell and weights, and the leak-safe
                         weights test the point itself when it is finite
                         (else the plain weights stand); zero, infinite and
                         NaN directions give a bin in range; unknown filter
                         values act as NEAREST and unknown weightings as
                         TRILINEAR; order 0 or 1 reads L1, any other L2.
                         Contract: vol is a built volume; pos, dir, normal,
                         to_eye hold 3 floats, rgb 3 (irrvol_query_many:
                         count of each at their strides; count 0 reads
                         nothing).
     irrvol_bin_direction, irrvol_direction_bin
                         bins past the last give +z; vol may be NULL for
                         irrvol_bin_direction. Contract: irrvol_direction_bin
                         needs a volume.
     irrvol_gpu_export   checks vol and layout non-NULL, sh_order 1 or 2,
                         both arrays NULL (sizes only) or both given with
                         capacities of at least layout counts
                         (INVALID_ARGUMENT); offsets past 32 bits give
                         OUT_OF_MEMORY. Contract: the capacities are true.
     irrvol_glsl_source  writes at most capacity bytes, zero-terminated when
                         capacity > 0; returns the full length.
     irrvol_visibility_ratio
                         checks like irrvol_build (positions, normals,
                         indices, strides, ranges). Contract: ratio holds
                         vertex_count floats; buffers as for irrvol_build.
     irrvol_save, irrvol_save_to_memory
                         check NULL pointers (INVALID_ARGUMENT); a failing
                         write gives IO (OUT_OF_MEMORY for memory). The
                         buffer of irrvol_save_to_memory comes from the given
                         allocator (NULL: IRRVOL_MALLOC) and goes back
                         through irrvol_free_memory with the same one.
     irrvol_load, irrvol_load_from_memory
                         check NULL pointers and the allocator (both
                         callbacks or neither: INVALID_ARGUMENT, *out NULL,
                         nothing allocated), and treat the input as
                         hostile: every size is checked against the
                         declared payload before allocating, every value's
                         range, finiteness and consistency, the CRC;
                         truncation and corruption give CORRUPT_DATA,
                         another format version VERSION; the volume is
                         read from the start of the buffer (bytes after its
                         CRC are left alone). Contract: data holds size
                         bytes.
     irrvol_free_memory  accepts NULL data; the allocator must be the one the
                         data was saved with.

   LIMITS

   k <= IRRVOL_MAX_RESOLUTION (64); supersamples <= IRRVOL_MAX_SUPERSAMPLES
   (16 x 16 rays per bin); weight_subdivisions <=
   IRRVOL_MAX_WEIGHT_SUBDIVISIONS (16); important_rays <=
   IRRVOL_MAX_IMPORTANT_RAYS (256, so at most 16 x 16 extra rays per bin);
   visibility_resolution <= IRRVOL_MAX_VISIBILITY_RESOLUTION (64);
   triangle_count <= UINT32_MAX / 3. Objects lit from the volume cast no
   shadows and do not see themselves: irrvol_visibility_ratio gives the
   fraction of each vertex's hemisphere its own mesh leaves open
   (cosine-weighted), a factor for the queried irradiance (thesis 5.1.3,
   6.1.3). Leak prevention is statistical where the surfaces around a
   sample are not planar within a texel's lobe (edges, curved objects):
   there the fit's variance softens the test and a little light can pass;
   a wall thinner than the normal bias can let light through as well.
   Glass is thin and straight-through: no refraction, no caustics, no
   frosted glass, at most IRRVOL_MAX_GLASS_LAYERS panes along a ray. With
   desc.radiance the callback answers for glass and sky itself.
   Harmonics of order 2 cannot hold sharp lobes: high moments and small
   bright lights lose detail in them (the bins keep it). The compact store
   keeps each bin to 2^-9 of its largest channel (Precision in DETAILS): weak
   channels of strongly coloured light lose relative precision, negative
   irradiance is stored as 0; desc.full_precision avoids both.

   PAPER

       Gene S. Greger, The Irradiance Volume, M.S. thesis, Cornell University, 1996.
       Equation numbers in comments refer to it. Leak prevention after
       Z. Majercik, J.-P. Guertin, D. Nowrouzezahrai, M. McGuire, Dynamic
       Diffuse Global Illumination with Ray-Traced Irradiance Fields, JCGT
       8(2), 2019; harmonics after R. Ramamoorthi and P. Hanrahan, An
       Efficient Representation for Irradiance Environment Maps, SIGGRAPH
       2001.
*/
#ifndef IRRVOL_H
#define IRRVOL_H

#include <stddef.h>
#include <stdint.h>

#define IRRVOL_VERSION_MAJOR 0
#define IRRVOL_VERSION_MINOR 5
#define IRRVOL_VERSION_PATCH 6
#define IRRVOL_FILE_FORMAT_VERSION 3

/* Fixed limits of the desc's fields (see LIMITS). */
#define IRRVOL_MAX_SUPERSAMPLES 16             /* s x s rays per bin */
#define IRRVOL_MAX_WEIGHT_SUBDIVISIONS 16      /* w x w sub-directions per bin */
#define IRRVOL_MAX_IMPORTANT_RAYS 256          /* 16 x 16 */
#define IRRVOL_MAX_VISIBILITY_RESOLUTION 64    /* n x n visibility texels per sample */
#define IRRVOL_MAX_ENVIRONMENT_SIZE 65536      /* texels per side of desc.environment */
#define IRRVOL_MAX_GLASS_LAYERS 16             /* panes a ray crosses; one more blocks it */

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
    float t;            /* distance along the ray in units of |dir| (dir is unit length) */
    float u, v;         /* barycentric weights of the triangle's 2nd and 3rd vertex */
    uint32_t triangle;  /* index into desc.indices / 3 */
} irrvol_hit;

/* Closest hit along org + t dir, 0 < t < tmax; returns 1 on a hit. Called
   concurrently from the build's jobs. */
typedef int (*irrvol_trace_fn)(void *user, const float org[3], const float dir[3], float tmax,
                               irrvol_hit *hit);

/* Radiance seen from org looking along the unit direction dir: the light
   that arrives at org from that direction. Called concurrently. */
typedef void (*irrvol_radiance_fn)(void *user, const float org[3], const float dir[3], float rgb[3]);

typedef int (*irrvol_write_fn)(void *user, const void *bytes, size_t n); /* 0 = ok */
typedef int (*irrvol_read_fn)(void *user, void *bytes, size_t n);        /* 0 = all n bytes read */

enum {
    IRRVOL_MATERIAL_IGNORE = 1u,     /* rays that hit it see zero radiance (light transfer exploration) */
    IRRVOL_MATERIAL_IMPORTANT = 2u,  /* informed sampling: bins that see it get extra rays */
    IRRVOL_MATERIAL_TWO_SIDED = 4u   /* both sides are front faces (foliage, cloth, unclosed planes) */
};

typedef struct irrvol_material {
    float radiance[3];   /* outgoing diffuse radiance (emitted + reflected), W/(m^2 sr), both sides */
    float specular[3];   /* mirror coefficient: reflected radiance is added with this weight */
    uint32_t flags;      /* IRRVOL_MATERIAL_* */
    float transmittance[3]; /* thin glass: this share of the radiance behind passes straight through,
                               in [0, 1] per channel; 0 = opaque (see GLASS AND SKY) */
} irrvol_material;

typedef enum irrvol_filter {
    IRRVOL_FILTER_DEFAULT = 0,  /* the volume's filter (desc.filter), BILINEAR if unset */
    IRRVOL_FILTER_NEAREST,      /* the bin containing the direction (thesis 4.3) */
    IRRVOL_FILTER_BILINEAR      /* bilinear between the four nearest bins (thesis 6.1.2) */
} irrvol_filter;

typedef enum irrvol_weighting {
    IRRVOL_WEIGHTING_DEFAULT = 0,  /* the volume's weighting (desc.weighting), VISIBILITY if unset */
    IRRVOL_WEIGHTING_VISIBILITY,   /* leak-safe: trilinear x visibility x backface, renormalised */
    IRRVOL_WEIGHTING_TRILINEAR     /* plain trilinear interpolation (thesis 4.3) */
} irrvol_weighting;

typedef struct irrvol_desc {
    /* Scene: triangles with per-triangle materials. Needed for the built-in
       radiance, the second level and leak prevention; may be empty with
       desc.radiance and explicit bounds. */
    const float *positions;          /* xyz per vertex */
    size_t position_stride;          /* bytes between vertices; 0 = 3 floats */
    uint32_t vertex_count;
    const uint32_t *indices;         /* 3 per triangle, < vertex_count; front faces counter-clockwise */
    uint32_t triangle_count;         /* <= UINT32_MAX / 3 */
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
    float refine_threshold;          /* refine cells whose corners' light differs more (6.1.1); 0 = 0.25;
                                        negative = refine only where geometry is */

    /* Directions. */
    uint32_t resolution;             /* k: 2k^2 bins per sample; 0 = 17 (578 bins) */
    uint32_t supersamples;           /* s x s jittered rays per bin; 0 = 1 ray through the bin centre */
    uint32_t moment;                 /* n of eq. 4.8; 0 = 1 (irradiance, eq. 4.3) */
    uint32_t weight_subdivisions;    /* w x w sub-directions integrate each bin's weight; 0 = 4 */
    irrvol_filter filter;            /* filter of irrvol_query; 0 = BILINEAR */

    /* Leak prevention. */
    irrvol_weighting weighting;      /* weighting of irrvol_query; 0 = VISIBILITY */
    uint32_t visibility_resolution;  /* n: n x n octahedral texels of hit distances per sample; 0 = 8 */
    float normal_bias;               /* the visibility test point moves this fraction of the finest sample
                                        spacing along the query direction; 0 = 0.02, negative = none */

    /* Radiance. */
    irrvol_radiance_fn radiance;     /* replaces the built-in radiance when set */
    void *radiance_user;
    irrvol_trace_fn trace;           /* replaces the built-in BVH when set */
    void *trace_user;
    float background[3];             /* the sky: radiance of rays that leave the scene or cut chains */
    const float *environment;        /* optional sky map, rgb per texel, latitude-longitude with +y up
                                        (GLASS AND SKY); replaces background; NULL = constant */
    uint32_t environment_width;      /* texels per row, 1..IRRVOL_MAX_ENVIRONMENT_SIZE */
    uint32_t environment_height;     /* rows, from the zenith (+y) down to the nadir */
    uint32_t max_depth;              /* mirror reflections followed; 0 = 6 */
    float min_weight;                /* chain weight floor; 0 = 0.01 */
    float ray_offset;                /* reflected rays start this far off the surface; 0 = 1e-4 * diagonal */
    uint32_t important_rays;         /* points on IMPORTANT triangles per sample, extra rays per bin; 0 = 64 */
    int keep_radiance;               /* non-zero: keep the gathered radiance (irrvol_sample_values) */
    int full_precision;              /* non-zero: irradiance bins as 3 floats (12 bytes); 0 = the compact
                                        store, shared-exponent RGB9E5 (4 bytes, DETAILS: Precision) */

    uint64_t seed;                   /* jitter streams */
    irrvol_allocator allocator;
    void (*parallel_for)(void *user, irrvol_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    int (*progress)(void *user, uint64_t done, uint64_t total); /* samples gathered; non-zero cancels */
    void *progress_user;
    void (*log)(void *user, const char *message);
    void *log_user;
} irrvol_desc;

typedef struct irrvol irrvol;

typedef struct irrvol_volume_info {
    uint32_t sample_count;           /* all samples */
    uint32_t first_level_samples;    /* grid_samples[0] * [1] * [2] */
    uint32_t second_level_samples;   /* samples added by second-level grids (shared ones once) */
    uint32_t hanging_samples;        /* second-level samples on faces of unrefined cells: no gather */
    uint32_t invalid_samples;        /* inside geometry, left out of leak-safe queries */
    uint32_t relocated_samples;      /* moved out of geometry */
    uint32_t grid_samples[3];
    uint32_t subgrid_samples;
    uint32_t cell_count;             /* first-level cells */
    uint32_t refined_cells;          /* cells with a second-level grid */
    uint32_t light_refined_cells;    /* of which refined for their light alone (6.1.1) */
    uint32_t resolution;             /* k */
    uint32_t bins;                   /* 2k^2 */
    uint32_t moment;
    uint32_t visibility_resolution;  /* n */
    irrvol_filter filter;
    irrvol_weighting weighting;
    float normal_bias;               /* in world units */
    float bounds_min[3], bounds_max[3];
    uint64_t rays;                   /* rays cast by the build (kept by save/load) */
    uint32_t degenerate_triangles;   /* zero-area triangles skipped by the build */
    int has_radiance;                /* built with keep_radiance */
    uint32_t bin_bytes;              /* bytes of one irradiance bin: 4 (RGB9E5, the default) or 12 (full_precision) */
    size_t bytes;                    /* memory held by the volume */
} irrvol_volume_info;

enum {   /* irrvol_sample_info.state */
    IRRVOL_SAMPLE_VALID = 0,
    IRRVOL_SAMPLE_RELOCATED,         /* moved out of geometry: origin differs from position */
    IRRVOL_SAMPLE_INVALID,           /* inside geometry: never in a leak-safe query */
    IRRVOL_SAMPLE_HANGING            /* the blend of first-level samples (no seams) */
};

typedef struct irrvol_sample_info {
    float position[3];               /* on the grid: interpolation weights refer to it */
    float origin[3];                 /* where it gathered, and where visibility is measured from */
    int level;                       /* 1 or 2 */
    int state;                       /* IRRVOL_SAMPLE_* */
} irrvol_sample_info;

/* The flat arrays of irrvol_gpu_export. The index array (uint32) starts
   with a header of 16 entries: [0] layout version, [1..3] first-level
   cells per axis, [4] samples, [5] the first hanging sample, [6] n of the
   visibility texels, [7] coefficients per sample, [8..14] the offsets
   below; the data array (float) with 16: [0..2] bounds min, [3..5] cells
   per unit length, [6..8] cells per axis, [9] the normal bias. */
typedef struct irrvol_gpu_layout {
    size_t index_count;              /* uint32 entries of the index array */
    size_t data_count;               /* floats of the data array */
    uint32_t sh_order;               /* 1 or 2 */
    uint32_t coefficients;           /* 4 or 9 per sample and channel */
    uint32_t cells_at;               /* index: per first-level cell, its table's offset in the ids and its side */
    uint32_t ids_at;                 /* index: the tables of sample ids, side^3 per cell, x fastest */
    uint32_t parents_at;             /* index: 4 first-level parents per hanging sample */
    uint32_t origins_at;             /* data: per sample xyz of its origin and 1 (valid) or 0 (invalid) */
    uint32_t visibility_at;          /* data: per sample before the hanging ones, (n + 2)^2 texels, row-major
                                        octahedral with a border of mirrored texels, each the fit of the
                                        inverse hit distance: gradient xyz and residual variance */
    uint32_t sh_at;                  /* data: per sample, coefficients x rgb of the irradiance */
    uint32_t parent_weights_at;      /* data: 4 weights per hanging sample */
} irrvol_gpu_layout;

/* Self-occlusion of a dynamic mesh (thesis 6.1.3): for each vertex, the
   cosine-weighted fraction of the hemisphere around its normal that the mesh
   itself leaves open. */
typedef struct irrvol_visibility_desc {
    const float *positions;          /* xyz per vertex */
    size_t position_stride;          /* 0 = 3 floats */
    uint32_t vertex_count;
    const uint32_t *indices;         /* 3 per triangle */
    uint32_t triangle_count;         /* <= UINT32_MAX / 3 */
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
IRRVOL_API void irrvol_query_filter(const irrvol *vol, irrvol_filter filter, irrvol_weighting weighting,
                                    const float pos[3], const float dir[3], float rgb[3]);
IRRVOL_API void irrvol_query_glossy(const irrvol *vol, const float pos[3], const float normal[3],
                                    const float to_eye[3], float rgb[3]);
IRRVOL_API void irrvol_query_many(const irrvol *vol, irrvol_filter filter, irrvol_weighting weighting,
                                  uint32_t count, const float *pos, size_t pos_stride, const float *dir,
                                  size_t dir_stride, float *rgb);
IRRVOL_API void irrvol_query_sh(const irrvol *vol, uint32_t order, irrvol_weighting weighting, const float pos[3],
                                const float dir[3], float rgb[3]);

IRRVOL_API irrvol_result irrvol_sample(const irrvol *vol, uint32_t index, irrvol_sample_info *info);
IRRVOL_API irrvol_result irrvol_sample_values(const irrvol *vol, uint32_t index, float *irradiance,
                                              float *radiance);
IRRVOL_API void irrvol_bin_direction(const irrvol *vol, uint32_t bin, float dir[3]);
IRRVOL_API uint32_t irrvol_direction_bin(const irrvol *vol, const float dir[3]);

IRRVOL_API irrvol_result irrvol_gpu_export(const irrvol *vol, uint32_t sh_order, irrvol_gpu_layout *layout,
                                           uint32_t *index, size_t index_capacity, float *data,
                                           size_t data_capacity);
IRRVOL_API size_t irrvol_glsl_source(char *buffer, size_t capacity);

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
#define IRRVOL__NORMAL_BIAS 0.02f         /* default desc.normal_bias: of the finest sample spacing */
#define IRRVOL__REFINE_THRESHOLD 0.05f    /* default desc.refine_threshold: predicted interpolation error */
#ifndef IRRVOL__VISIBILITY_RESOLUTION
#define IRRVOL__VISIBILITY_RESOLUTION 8u  /* default desc.visibility_resolution */
#endif
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

/* SSE2 (every x86-64 compiler offers it) computes four visibility weights
   and the rgb sums at once; the portable scalar code computes the same
   operations in the same order, so both give the same bits.
   IRRVOL_NO_SIMD keeps to the scalar code. */
#if !defined(IRRVOL_NO_SIMD) && (defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2))
#  include <emmintrin.h>
#  define IRRVOL__SSE2 1
#endif

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
/* All three finite: x - x is 0 for a finite x and NaN for an infinite or NaN one. */
IRRVOL__HOT int irrvol__finite3(const float *p) { return (p[0] - p[0]) + (p[1] - p[1]) + (p[2] - p[2]) == 0.0f; }

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
/* Node boxes are pushed outward by 2^-20 of each bound plus 1e-20 (in the
   scene's units). A ray with a zero direction component (its inverse is
   1e30, irrvol__ray_setup) that runs exactly in the plane of a box's face
   would otherwise leave the box at t = 0 and miss a triangle lying on that
   face; pushed out, it stays inside for t of 1e10 or more. The boxes grow by
   a millionth. */
#define IRRVOL__BVH_PAD_RELATIVE 9.5367431640625e-07f   /* 2^-20 */
#define IRRVOL__BVH_PAD_ABSOLUTE 1e-20f

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

/* A box bound v pushed outward (side -1 for a lower bound, +1 for an
   upper one): see IRRVOL__BVH_PAD_RELATIVE. */
static float irrvol__bvh_pad(float v, float side)
{
    return v + side * (fabsf(v) * IRRVOL__BVH_PAD_RELATIVE + IRRVOL__BVH_PAD_ABSOLUTE);
}

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
                        node->box[2 * r][j] = j < k ? irrvol__bvh_pad(bn[kids[j]].lo[r], -1.0f) : INFINITY;
                        node->box[2 * r + 1][j] = j < k ? irrvol__bvh_pad(bn[kids[j]].hi[r], 1.0f) : -INFINITY;
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
/* n 4-byte items (floats or uint32), little-endian bytes a buffer at a
   time: one write callback per 4 KiB, not per item. */
static void irrvol__put_array32(irrvol__writer *w, const void *items, size_t n)
{
    unsigned char buf[4096];
    const unsigned char *f = (const unsigned char *)items;
    size_t i = 0;
    while (i < n) {
        size_t m = n - i < sizeof buf / 4 ? n - i : sizeof buf / 4, j;
        for (j = 0; j < m; j++) {
            uint32_t v;
            memcpy(&v, f + 4 * (i + j), 4);
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
    uint64_t available;  /* payload bytes the input can hold at most, when known (memory) */
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

#ifdef IRRVOL__SSE2
/* mask ? a : b, lane by lane, for a comparison's mask: no branch. */
IRRVOL__HOT __m128 irrvol__select(__m128 mask, __m128 a, __m128 b)
{
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}
#endif

/* Inverse of irrvol__square_to_hemisphere for any non-zero direction (not
   necessarily unit length); hemisphere 1 is z < 0, mirrored. Zero, infinite
   and NaN directions land on a valid square point. The disk radius
   sqrt(1 - |z| / |d|) and the ratio of the minor to the major component are
   independent: two short dependency chains instead of a normalization
   followed by both. With SSE2 the same operations, every choice a select:
   random directions take each side of each choice half the time, which as
   branches (compilers do not turn these into selects) cost a query about
   three mispredictions. Lane 0 works out the point as if x were the major
   axis, lane 1 as if y were (one division, one arctangent polynomial for
   both), and one select at the end keeps the right one: the same bits as
   choosing the numerator and denominator first, in half the instructions. */
#ifdef IRRVOL__SSE2
/* c in lanes 0 and 1, for the two-lane steps below: a constant the compiler
   keeps whole in memory and uses as an operand (GCC at -O2 broadcasts a
   constant of four equal lanes from a scalar, two instructions). */
#define IRRVOL__LANES2(c) _mm_set_ps(0.0f, 0.0f, (c), (c))

IRRVOL__HOT __m128 irrvol__direction_to_square4(const float dir[3], uint32_t *hemisphere)
{
    const __m128 zero = _mm_setzero_ps(), one = IRRVOL__LANES2(1.0f), sign = IRRVOL__LANES2(-0.0f);
    __m128 x = _mm_load_ss(dir), y = _mm_load_ss(dir + 1), z = _mm_load_ss(dir + 2);
    __m128 len = _mm_sqrt_ss(_mm_add_ss(_mm_add_ss(_mm_mul_ss(x, x), _mm_mul_ss(y, y)), _mm_mul_ss(z, z)));
    __m128 pos = _mm_cmpgt_ss(len, zero), ax = _mm_andnot_ps(sign, x), ay = _mm_andnot_ps(sign, y);
    __m128 one_minus_z = irrvol__select(pos, _mm_sub_ss(one, _mm_div_ss(_mm_andnot_ps(sign, z), irrvol__select(pos, len, one))), one);
    __m128 r = _mm_sqrt_ss(_mm_max_ss(one_minus_z, zero));
    __m128 xmajor = _mm_cmpge_ss(ax, ay);
    __m128 den = _mm_unpacklo_ps(x, y), num = _mm_unpacklo_ps(y, x);   /* lane 0: x major, lane 1: y major */
    __m128 nonzero = _mm_cmpneq_ps(den, zero);
    __m128 t = _mm_and_ps(nonzero, _mm_div_ps(num, _mm_or_ps(den, _mm_andnot_ps(nonzero, one))));   /* |t| <= 1 */
    __m128 t2 = _mm_mul_ps(t, t), t4 = _mm_mul_ps(t2, t2), t8 = _mm_mul_ps(t4, t4);   /* irrvol__atan_unit */
    __m128 p01 = _mm_sub_ps(IRRVOL__LANES2(0.9999994372f), _mm_mul_ps(IRRVOL__LANES2(0.3333010801f), t2));
    __m128 p23 = _mm_sub_ps(IRRVOL__LANES2(0.1994852321f), _mm_mul_ps(IRRVOL__LANES2(0.1391586880f), t2));
    __m128 p45 = _mm_sub_ps(IRRVOL__LANES2(0.09656416154f), _mm_mul_ps(IRRVOL__LANES2(0.05606523185f), t2));
    __m128 p67 = _mm_sub_ps(IRRVOL__LANES2(0.02194796030f), _mm_mul_ps(IRRVOL__LANES2(0.004073664390f), t2));
    __m128 atan_t = _mm_mul_ps(t, _mm_add_ps(_mm_add_ps(p01, _mm_mul_ps(p23, t4)), _mm_mul_ps(_mm_add_ps(p45, _mm_mul_ps(p67, t4)), t8)));
    __m128 major = _mm_xor_ps(_mm_shuffle_ps(r, r, 0), _mm_and_ps(_mm_cmplt_ps(den, zero), sign));
    __m128 minor = _mm_mul_ps(_mm_mul_ps(major, IRRVOL__LANES2((float)(4.0 / IRRVOL__PI))), atan_t);
    __m128 both = _mm_unpacklo_ps(major, minor);                     /* x major: u v; y major: v u */
    __m128 uv = irrvol__select(_mm_shuffle_ps(xmajor, xmajor, 0), both, _mm_shuffle_ps(both, both, _MM_SHUFFLE(2, 3, 2, 3)));
    *hemisphere = (uint32_t)_mm_movemask_ps(_mm_cmplt_ss(z, zero)) & 1u;
    uv = _mm_mul_ps(IRRVOL__LANES2(0.5f), _mm_add_ps(uv, one));
    return _mm_min_ps(_mm_max_ps(uv, zero), one);   /* as irrvol__unit_clamp: NaN gives 0 */
}

IRRVOL__HOT void irrvol__direction_to_square(const float dir[3], float *u, float *v, uint32_t *hemisphere)
{
    __m128 uv = irrvol__direction_to_square4(dir, hemisphere);
    *u = _mm_cvtss_f32(uv);
    *v = _mm_cvtss_f32(_mm_shuffle_ps(uv, uv, 1));
}
#else
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
#endif

/* Bin b's direction through the point (u, v) of its square. */
static irrvol__vec3 irrvol__bin_point(uint32_t k, uint32_t bin, float fu, float fv)
{
    uint32_t kk = k * k, h = bin / kk, j = (bin % kk) / k, i = bin % k;
    irrvol__vec3 d = irrvol__square_to_hemisphere(((float)i + fu) / (float)k, ((float)j + fv) / (float)k);
    if (h) d.z = -d.z;
    return d;
}

/* Octahedral map (Cigolle et al. 2014) of the visibility texels: the
   point (u, t) of [0,1]^2 -> direction, the lower hemisphere folded over
   the corners. Cheaper than the concentric map (one division, no
   arctangent); its square folds onto itself along the edges, which the
   bordered maps of section 13 copy. The forward map lives in
   irrvol__visibility_weight (and its SSE2 steps, and the GLSL). */
IRRVOL__HOT float irrvol__sign1(float x) { return x >= 0.0f ? 1.0f : -1.0f; }

static irrvol__vec3 irrvol__oct_decode(float u, float t)
{
    float px = 2.0f * u - 1.0f, py = 2.0f * t - 1.0f, z = 1.0f - fabsf(px) - fabsf(py);
    if (z < 0.0f) {
        float qx = (1.0f - fabsf(py)) * irrvol__sign1(px);
        py = (1.0f - fabsf(px)) * irrvol__sign1(py);
        px = qx;
    }
    return irrvol__normalize(irrvol__v3(px, py, z));
}

/* Texel (i, j) of an n x n octahedral square, one step past an edge
   included: the square's border folds onto itself mirrored (the points
   (0, v) and (0, 1 - v) are one direction), so the neighbour across an edge
   is the mirrored texel on the same edge, and past a corner the opposite
   corner (all four corners are the -z pole). */
IRRVOL__HOT uint32_t irrvol__oct_texel(int i, int j, int n)
{
    if (i < 0) { i = 0; j = n - 1 - j; }
    else if (i >= n) { i = n - 1; j = n - 1 - j; }
    if (j < 0) { j = 0; i = n - 1 - i; }
    else if (j >= n) { j = n - 1; i = n - 1 - i; }
    return (uint32_t)(j * n + i);
}
/* ======================================================================
   9. the volume: bilevel grid (4.1, 4.3) without seams
   Samples are numbered first level first (x fastest: a dense 3D array),
   then the second-level samples that carry data of their own, then the
   hanging ones (below). Every first-level cell has a table of side^3
   sample ids (side 2 for an unrefined cell: its corners; subgrid_samples
   for a refined one), so a query runs the same code at either level.
   Irradiance is stored bin-major: for each bin, every sample's rgb (one
   RGB9E5 word in the compact store, three floats at full precision). The
   eight corners of a query read the same bin of eight samples, and the two
   corners along x are usually consecutive samples, so a query touches four
   to six cache lines instead of eight.

   Hanging samples. A second-level sample that lies on a face or an edge of
   an unrefined cell would make the two sides of that face interpolate
   different data: the refined side its own samples, the unrefined side the
   cell's corners (the thesis's seams). Such a sample is a hanging node, as
   in adaptive finite elements: it gathers nothing, and its value is the
   unrefined cell's own interpolation at its position, the bilinear (on a
   face, four coarse parents) or linear (on an edge, two) blend of the
   first-level samples around it. Trilinear interpolation reproduces a
   bilinear face exactly, so both sides of every face agree. Queries
   replace a hanging corner by its parents (its weight times theirs): the
   compact store rounds a hanging sample's blend on its own, and leak-safe
   queries weigh samples by visibility, which is not linear, each parent on
   its own; both sides again evaluate the same parents with the same
   weights.
   ---------------------------------------------------------------------- */
typedef struct irrvol__cell {
    uint32_t offset;   /* first id of the cell's table in vol->ids */
    uint32_t side;     /* samples per axis of the table */
    uint32_t corners;  /* its first sub-cell's record in vol->corners, (side - 1)^3 of them, x fastest */
} irrvol__cell;

/* A (sub-)cell's eight corners as the queries read them: their sample
   ids and, for the leak-safe weights, their probes (origin and reach,
   section 13) by coordinate, four corners to a register. Three cache lines
   where the id table, eight probes and the cell took up to a dozen. */
typedef struct irrvol__corners {
    float x[8], y[8], z[8], reach2[8];   /* the probes of the samples in id */
    uint32_t id[8];                      /* the corner samples, x fastest (irrvol__table_corners); merged: the
                                            distinct samples of the terms */
    uint32_t hanging;                    /* non-zero: a corner is hanging, its parents stand in: the number of
                                            terms of the sub-cell, vol->terms[first...], a multiple of 4 */
    uint32_t first;
    uint32_t merged;                     /* non-zero: hanging, and its terms name at most eight samples, in id
                                            (each term's slot): leak-safe queries weigh those (irrvol__merge_hanging) */
    uint32_t clear;                      /* bit k: no point of the sub-cell lies beyond a surface sample id[k]
                                            predicts (irrvol__make_clear): its map is skipped there */
    uint32_t pad[4];                     /* 192 bytes: three lines */
} irrvol__corners;

/* A term of a sub-cell with hanging corners (irrvol__expand_hanging): a
   sample, the corner it stands in for and its weight there (1 for the
   corner itself, a parent's weight for a hanging corner's parent), and
   the sample's slot among the record's distinct samples (merged records). */
typedef struct irrvol__term {
    uint32_t id;
    uint16_t corner, slot;   /* both 0..7 */
    float weight;
} irrvol__term;

enum {   /* why a first-level cell is refined (vol->refined) */
    IRRVOL__UNREFINED = 0,
    IRRVOL__REFINED_GEOMETRY = 1,   /* a triangle overlaps it (4.1) */
    IRRVOL__REFINED_LIGHT = 2       /* its corners' irradiance differs (6.1.1) */
};

#define IRRVOL__SH_COEFFS 9        /* spherical harmonics l <= 2 */
#define IRRVOL__SH_FLOATS 27       /* 9 coefficients x rgb per sample */

struct irrvol {
    irrvol_allocator allocator;
    float lo[4], hi[4];    /* the grid's bounds; the fourth float of these and the next three is 0, so a
                              query loads each in one register (irrvol__locate) */
    float scale[4];        /* first-level cells per unit length: num_cells / (max - min), eq. 4.4 */
    float cell_limit[4];   /* cells per axis as float: the clamp bound of q_d */
    float last_cell[4];    /* cells per axis less 1, as float: the cell of q_d = num_cells */
    float sub_cells[4];    /* sub-cells per axis of a refined cell (subgrid - 1), as float; the fourth float
                              of this and the next two is 0 too (irrvol__create zeroes the struct) */
    float sub_last[4];     /* sub_cells less 1: the sub-cell of a point on a refined cell's upper face */
    float sub_stride[4];   /* 1, sub_cells, sub_cells^2: a sub-cell's record from its coordinates */
    uint32_t samples[3];   /* first-level samples per axis */
    uint32_t cells[3];     /* first-level cells per axis */
    uint32_t subgrid;      /* second-level samples per axis, corners included */
    uint32_t cell_count, refined_count, light_refined_count;
    unsigned char *refined;   /* per cell: IRRVOL__UNREFINED, _GEOMETRY or _LIGHT */
    irrvol__cell *cell;
    uint32_t *ids;
    size_t id_count;
    uint32_t sample_count, first_level_count;
    uint32_t hanging_begin;   /* samples [hanging_begin, sample_count) are hanging */
    float *positions;      /* grid position xyz per sample */
    float *origins;        /* per sample: where it gathered (xyz; moved out of geometry when relocated)
                              and w = 1 for a valid sample, 0 for an invalid one */
    uint32_t *parents;     /* 4 first-level sample ids per hanging sample */
    float *parent_weights; /* their weights (unused slots 0) */
    uint32_t k, bins;
    float kf;
    uint32_t moment;
    irrvol_filter filter;
    irrvol_weighting weighting;
    float *irradiance;     /* bins x sample_count x rgb during the build, and after it with full precision;
                              else NULL: the compact store holds it */
    uint32_t *packed;      /* the compact store: bins x sample_count RGB9E5 words, bin-major like irradiance */
    int32_t pack_shift;    /* the words hold the irradiance times 2^-pack_shift (irrvol__pack_shift) */
    float unpack[32];      /* a word's mantissas times unpack[its exponent field] are its irradiance */
    float unshift[2];      /* 2^pack_shift as two factors, each a normal float (queries scale their sums) */
    float *radiance;       /* same layout, or NULL */
    float *sh;             /* per sample 9 coefficients x rgb of the irradiance, l <= 2 */
    uint32_t vis_res;      /* n: n x n octahedral visibility texels per sample */
    uint32_t texels;       /* n^2 */
    uint32_t map_texels;   /* (n + 2)^2: the map with a border of mirrored texels, as stored */
    float *visibility;     /* per sample before hanging_begin: an (n + 2)^2 map of the fit of the inverse hit
                              distance, gradient xyz and residual variance (section 13), its border the
                              mirrored texels across the octahedral square's edges */
    irrvol__corners *corners; /* per sub-cell (of every cell), aligned to 64 bytes */
    void *corner_block;    /* the allocation that holds them */
    irrvol__term *terms;   /* the terms of the sub-cells with hanging corners */
    uint32_t term_count;
    float *probes;         /* what a leak-safe query reads of a sample before hanging_begin, in one 16-byte
                              record: its origin xyz and its reach squared, a distance within which no test
                              point lies beyond the surface its map predicts, or -1 when it is invalid */
    float bias;            /* the visibility test point moves this far along the query direction */
    uint64_t rays;
    uint32_t degenerate, invalid_count, relocated_count;
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
        v->last_cell[d] = (float)(v->cells[d] - 1);
        v->sub_cells[d] = (float)(subgrid - 1);
        v->sub_last[d] = (float)(subgrid - 2);
    }
    v->sub_stride[0] = 1.0f;
    v->sub_stride[1] = (float)(subgrid - 1);
    v->sub_stride[2] = (float)((subgrid - 1) * (subgrid - 1));
    v->subgrid = subgrid;
    v->first_level_count = samples[0] * samples[1] * samples[2];
}

/* The smallest distance between neighbouring samples of the finest level. */
static double irrvol__finest_spacing(const irrvol *v)
{
    double s = DBL_MAX;
    int d;
    for (d = 0; d < 3; d++) {
        double c = ((double)v->hi[d] - (double)v->lo[d]) / v->cells[d] / (v->refined_count ? v->subgrid - 1 : 1);
        if (c < s) s = c;
    }
    return s;
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

/* Whether the fine lattice point g lies on the closure of an unrefined
   cell; if so, its first-level parents and their weights: the coarse
   lattice points around g, blended linearly along the axes where g lies
   between them (two parents on a coarse edge, four on a coarse face).
   Unused slots get weight 0 and the first parent's id. */
static int irrvol__hanging_parents(const irrvol *v, const unsigned char *refined, const uint32_t g[3],
                                   uint32_t parent[4], float weight[4])
{
    uint32_t f = v->subgrid - 1, q[3], r[3], lo[3], hi[3], x, y, z, n = 0, corner;
    int d, hanging = 0;
    for (d = 0; d < 3; d++) {
        q[d] = g[d] / f;
        r[d] = g[d] % f;
        /* on a coarse plane the point touches the cells on both sides */
        lo[d] = r[d] == 0 && q[d] > 0 ? q[d] - 1 : q[d];
        hi[d] = q[d] < v->cells[d] ? q[d] : v->cells[d] - 1;
    }
    for (z = lo[2]; z <= hi[2]; z++)
        for (y = lo[1]; y <= hi[1]; y++)
            for (x = lo[0]; x <= hi[0]; x++)
                if (!refined[x + v->cells[0] * (y + v->cells[1] * z)]) hanging = 1;
    if (!hanging) return 0;
    for (corner = 0; corner < 8; corner++) {
        uint32_t at[3];
        double w = 1.0;
        int skip = 0;
        for (d = 0; d < 3; d++) {
            uint32_t bit = (corner >> d) & 1u;
            if (r[d] == 0) { skip |= (int)bit; at[d] = q[d]; continue; }
            at[d] = q[d] + bit;
            w *= bit ? (double)r[d] / f : 1.0 - (double)r[d] / f;
        }
        if (skip) continue;
        parent[n] = at[0] + v->samples[0] * (at[1] + v->samples[1] * at[2]);
        weight[n] = (float)w;
        n++;
    }
    for (; n < 4; n++) { parent[n] = parent[0]; weight[n] = 0.0f; }
    return 1;
}

/* Numbers the hanging samples after the others, keeping creation order
   within each group: perm[i] is the new id - first_level_count of fine
   sample i. Sets hanging_begin. */
static void irrvol__number_hanging(irrvol *v, const unsigned char *refined, const uint32_t *fine, uint32_t *perm)
{
    uint32_t fine_count = v->sample_count - v->first_level_count, i, next = 0, parent[4];
    float weight[4];
    for (i = 0; i < fine_count; i++) {
        int hanging = irrvol__hanging_parents(v, refined, &fine[3 * (size_t)i], parent, weight);
        perm[i] = hanging ? UINT32_MAX : next++;
    }
    v->hanging_begin = v->first_level_count + next;
    for (i = 0; i < fine_count; i++)
        if (perm[i] == UINT32_MAX) perm[i] = next++;
}

/* Renumbers the tables and moves the fine coordinates along with perm, then
   records the hanging samples' parents. perm is used up. */
static void irrvol__apply_numbering(irrvol *v, const unsigned char *refined, uint32_t *fine, uint32_t *perm)
{
    uint32_t first = v->first_level_count, fine_count = v->sample_count - first, i, h;
    size_t at;
    for (at = 0; at < v->id_count; at++)
        if (v->ids[at] >= first) v->ids[at] = first + perm[v->ids[at] - first];
    for (i = 0; i < fine_count; i++) {   /* place each cycle of the permutation */
        uint32_t g[3], to;
        if (perm[i] & 0x80000000u) continue;   /* placed by an earlier cycle */
        memcpy(g, &fine[3 * (size_t)i], sizeof g);
        for (to = perm[i];; to = perm[to] & 0x7FFFFFFFu) {
            uint32_t next[3];
            memcpy(next, &fine[3 * (size_t)to], sizeof next);
            memcpy(&fine[3 * (size_t)to], g, sizeof g);
            memcpy(g, next, sizeof g);
            perm[to] |= 0x80000000u;
            if (to == i) break;
        }
    }
    for (h = 0; v->hanging_begin + h < v->sample_count; h++)
        irrvol__hanging_parents(v, refined, &fine[3 * ((size_t)v->hanging_begin - first + h)], v->parents + 4 * (size_t)h,
                                v->parent_weights + 4 * (size_t)h);
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

/* Builds the id tables, the hanging samples and the sample positions of a
   grid whose dimensions are set, given which cells are refined. */
static irrvol_result irrvol__make_grid(irrvol *v, const unsigned char *refined)
{
    const irrvol_allocator *a = &v->allocator;
    uint64_t side3 = (uint64_t)v->subgrid * v->subgrid * v->subgrid, ids, upper, capacity = 16;
    uint32_t *fine, *perm, c;
    irrvol__id_map map;
    irrvol_result r = IRRVOL_OK;
    v->refined_count = v->light_refined_count = 0;
    for (c = 0; c < v->cell_count; c++) {
        v->refined_count += refined[c] ? 1u : 0u;
        v->light_refined_count += refined[c] == IRRVOL__REFINED_LIGHT ? 1u : 0u;
    }
    ids = (uint64_t)(v->cell_count - v->refined_count) * 8u + (uint64_t)v->refined_count * side3;
    upper = (uint64_t)v->first_level_count + (uint64_t)v->refined_count * (side3 - 8u);   /* nothing shared */
    if (ids > UINT32_MAX || upper >= UINT32_MAX || ids > SIZE_MAX / 8 || upper > SIZE_MAX / 32)
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
        size_t fine_count;
        memset(map.keys, 0xFF, (size_t)capacity * sizeof(uint64_t));
        v->sample_count = irrvol__fill_tables(v, refined, &map, fine);
        fine_count = (size_t)v->sample_count - v->first_level_count;
        perm = (uint32_t *)irrvol__alloc_array(a, fine_count, sizeof(uint32_t));
        if (perm) irrvol__number_hanging(v, refined, fine, perm);
        v->parents = (uint32_t *)irrvol__alloc_array(a, v->sample_count - v->hanging_begin, 4 * sizeof(uint32_t));
        v->parent_weights = (float *)irrvol__alloc_array(a, v->sample_count - v->hanging_begin, 4 * sizeof(float));
        v->positions = (float *)irrvol__alloc_array(a, (size_t)v->sample_count * 3, sizeof(float));
        if (perm && v->parents && v->parent_weights && v->positions) {
            irrvol__apply_numbering(v, refined, fine, perm);
            irrvol__sample_positions(v, fine);
        } else {
            r = IRRVOL_ERROR_OUT_OF_MEMORY;
        }
        irrvol__free(a, perm);
    } else {
        r = IRRVOL_ERROR_OUT_OF_MEMORY;
    }
    irrvol__free(a, fine);
    irrvol__free(a, map.keys);
    irrvol__free(a, map.values);
    return r;
}

/* Per-sample arrays sized by the grid: values, origins, visibility. */
/* The per-sample arrays; compact: the irradiance in the compact store
   (a volume being loaded), else as floats (every build gathers floats). */
static irrvol_result irrvol__alloc_samples(irrvol *v, int keep_radiance, int compact)
{
    const irrvol_allocator *a = &v->allocator;
    uint64_t floats = (uint64_t)v->sample_count * v->bins * 3;
    uint64_t vis = (uint64_t)v->hanging_begin * v->map_texels * 4;
    if (floats > SIZE_MAX / sizeof(float) || vis > SIZE_MAX / sizeof(float)) return IRRVOL_ERROR_OUT_OF_MEMORY;
    if (compact) v->packed = (uint32_t *)irrvol__alloc_array(a, (size_t)floats / 3, sizeof(uint32_t));
    else v->irradiance = (float *)irrvol__alloc_array(a, (size_t)floats + 1, sizeof(float));
    if (keep_radiance) v->radiance = (float *)irrvol__alloc_array(a, (size_t)floats, sizeof(float));
    v->sh = (float *)irrvol__alloc_array(a, (size_t)v->sample_count * IRRVOL__SH_FLOATS + 1, sizeof(float));
    v->origins = (float *)irrvol__alloc_array(a, v->sample_count, 4 * sizeof(float));
    v->visibility = (float *)irrvol__alloc_array(a, (size_t)vis, sizeof(float));
    if (!(v->irradiance || v->packed) || (keep_radiance && !v->radiance) || !v->sh || !v->origins || !v->visibility)
        return IRRVOL_ERROR_OUT_OF_MEMORY;
    /* the rgb sums load four floats at a time: one past the last sample's */
    if (v->irradiance) v->irradiance[floats] = 0.0f;
    v->sh[(size_t)v->sample_count * IRRVOL__SH_FLOATS] = 0.0f;
    return IRRVOL_OK;
}

/* Sub-cells of all cells: the corner records. */
static uint64_t irrvol__corner_count(const irrvol *v)
{
    uint64_t n = 0;
    uint32_t c;
    for (c = 0; c < v->cell_count; c++) {
        uint64_t f = v->cell[c].side - 1;
        n += f * f * f;
    }
    return n;
}

/* Bytes of one irradiance bin: an RGB9E5 word or three floats. */
static uint32_t irrvol__bin_bytes(const irrvol *v) { return v->packed ? 4u : 12u; }

static size_t irrvol__bytes(const irrvol *v)
{
    size_t per_sample = (size_t)v->bins * 3 * sizeof(float);
    size_t hanging = (size_t)v->sample_count - v->hanging_begin;
    return sizeof *v + v->cell_count * (sizeof(irrvol__cell) + 1) + v->id_count * sizeof(uint32_t) +
           (size_t)v->sample_count * (7 * sizeof(float) + IRRVOL__SH_FLOATS * sizeof(float) +
                                      (size_t)v->bins * irrvol__bin_bytes(v) + (v->radiance ? per_sample : 0)) +
           hanging * 4 * (sizeof(uint32_t) + sizeof(float)) +
           (size_t)v->hanging_begin * (v->map_texels + 1) * 4 * sizeof(float) +
           (v->corner_block ? (irrvol__corner_count(v) + 1) * sizeof(irrvol__corners) : 0) +
           (size_t)v->term_count * sizeof(irrvol__term);
}

IRRVOL_API void irrvol_destroy(irrvol *vol)
{
    irrvol_allocator a;
    if (!vol) return;
    a = vol->allocator;
    irrvol__free(&a, vol->refined);
    irrvol__free(&a, vol->cell);
    irrvol__free(&a, vol->ids);
    irrvol__free(&a, vol->positions);
    irrvol__free(&a, vol->origins);
    irrvol__free(&a, vol->parents);
    irrvol__free(&a, vol->parent_weights);
    irrvol__free(&a, vol->irradiance);
    irrvol__free(&a, vol->packed);
    irrvol__free(&a, vol->radiance);
    irrvol__free(&a, vol->sh);
    irrvol__free(&a, vol->visibility);
    irrvol__free(&a, vol->probes);
    irrvol__free(&a, vol->corner_block);
    irrvol__free(&a, vol->terms);
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

/* Fills the border of one sample's (n + 2)^2 visibility map from its
   interior: past an edge of the octahedral square lies the mirrored texel
   of the same edge (irrvol__oct_texel), so a bilinear lookup anywhere in
   the square reads four stored texels and needs no wrapping. */
static void irrvol__map_border(const irrvol *v, float *map)
{
    int n = (int)v->vis_res, w = n + 2, i, j;
    for (j = 0; j < w; j++)
        for (i = 0; i < w; i++) {
            uint32_t from;
            if (i > 0 && i <= n && j > 0 && j <= n) continue;
            from = irrvol__oct_texel(i - 1, j - 1, n);
            memcpy(map + 4 * (size_t)(j * w + i), map + 4 * ((from / (uint32_t)n + 1) * (uint32_t)w + from % (uint32_t)n + 1),
                   4 * sizeof(float));
        }
}

/* The 8 corner ids of sub-cell (x, y, z) of a cell's table, x fastest. */
IRRVOL__HOT void irrvol__table_corners(const irrvol *v, const irrvol__cell *cell, uint32_t x, uint32_t y, uint32_t z,
                                       uint32_t ids[8])
{
    uint32_t row = cell->side, slab = cell->side * cell->side;
    const uint32_t *t = v->ids + cell->offset + x + row * y + slab * z;
    ids[0] = t[0];          ids[1] = t[1];
    ids[2] = t[row];        ids[3] = t[row + 1];
    ids[4] = t[slab];       ids[5] = t[slab + 1];
    ids[6] = t[slab + row]; ids[7] = t[slab + row + 1];
}

/* The corner records of every sub-cell, from the id tables and the probes. */
/* The terms of sub-cell record r (irrvol__expand_hanging) into out (NULL:
   only counted), padded to a multiple of 4 with weight 0; returns their
   number. A hanging corner's parents of weight 0 are left out. */
static uint32_t irrvol__record_terms(const irrvol *v, const irrvol__corners *r, irrvol__term *out)
{
    uint32_t k, j, m = 0;
    for (k = 0; k < 8; k++) {
        if (r->id[k] < v->hanging_begin) {
            if (out) { out[m].id = r->id[k]; out[m].corner = (uint16_t)k; out[m].weight = 1.0f; }
            m++;
            continue;
        }
        for (j = 0; j < 4; j++) {
            size_t h = 4 * (size_t)(r->id[k] - v->hanging_begin) + j;
            if (!(v->parent_weights[h] > 0.0f)) continue;
            if (out) { out[m].id = v->parents[h]; out[m].corner = (uint16_t)k; out[m].weight = v->parent_weights[h]; }
            m++;
        }
    }
    for (; m % 4; m++)
        if (out) { out[m].id = out[0].id; out[m].corner = 0; out[m].weight = 0.0f; }
    return m;
}

/* A sub-cell's terms name few samples: each hanging corner's parents are
   first-level corners of the refined cell around it (section 9), so the
   parents and the corners that stand for themselves are eight samples or
   fewer (on every grid this header builds). The record then lists them in
   id, with their probes, and each term names its sample's slot there: a
   leak-safe query weighs eight samples, like a sub-cell without hanging
   corners, instead of every term (up to 32). A record whose terms name
   more samples keeps merged 0 and the queries weigh every term. */
static void irrvol__merge_terms(const irrvol *v, irrvol__corners *r)
{
    irrvol__term *t = v->terms + r->first;
    uint32_t ids[8], m = 0, i, j;
    for (i = 0; i < r->hanging; i++) {
        for (j = 0; j < m && ids[j] != t[i].id; j++) continue;
        if (j == m) {
            if (m == 8) return;   /* more than eight samples: r->merged stays 0 */
            ids[m++] = t[i].id;
        }
    }
    for (i = 0; i < r->hanging; i++)
        for (j = 0; j < m; j++)
            if (ids[j] == t[i].id) t[i].slot = (uint16_t)j;
    for (j = 0; j < 8; j++) {   /* slots past the last sample repeat the first; their weight stays 0 */
        const float *p = v->probes + 4 * (size_t)ids[j < m ? j : 0];
        r->id[j] = ids[j < m ? j : 0];
        r->x[j] = p[0];
        r->y[j] = p[1];
        r->z[j] = p[2];
        r->reach2[j] = p[3];
    }
    r->merged = 1;
}

/* The largest g . (x - o) over the points x of the box [lo, hi] (relative
   to o) for the texels g of map: a vertex of the box maximises each. */
static double irrvol__map_box_max(const irrvol *v, const float *map, const double lo[3], const double hi[3])
{
    double most = -DBL_MAX;
    uint32_t t;
    int a;
    for (t = 0; t < v->map_texels; t++) {
        const float *g = map + 4 * (size_t)t;
        double m = 0.0;
        for (a = 0; a < 3; a++) {
            double l = (double)g[a] * lo[a], h = (double)g[a] * hi[a];
            m += l > h ? l : h;
        }
        most = m > most ? m : most;
    }
    return most;
}

/* Bit k of a record's clear mask: sample id[k] is valid and predicts no
   surface closer than any point of the sub-cell, grown by the normal bias
   (the test point x = pos + bias n) and by a margin for the float rounding
   of the cell's position. Then g . (x - o) < 1 for every texel of its map
   at every such x, so its Chebyshev test cannot act there: a query in the
   sub-cell (its position within the volume's bounds) skips the map, with
   the same weights to the bit, as within the reach (irrvol__make_probes).
   The texels' blend is a convex mix, so the largest texel bounds it; the
   bound is kept under 0.999 less a margin 1e-5 times the size of the
   products, a hundred times the float rounding of the blend and the dot
   product. */
static void irrvol__record_clear(const irrvol *v, irrvol__corners *r, const double box_lo[3], const double box_hi[3])
{
    uint32_t k;
    int a;
    r->clear = 0;
    if (r->hanging && !r->merged) return;   /* its terms are weighed one by one */
    for (k = 0; k < 8; k++) {
        const float *o = v->probes + 4 * (size_t)r->id[k];
        double lo[3], hi[3], size = 0.0, gmax = 0.0;
        uint32_t t;
        if (!(o[3] >= 0.0f)) continue;   /* invalid: near anyway */
        for (a = 0; a < 3; a++) {
            lo[a] = box_lo[a] - o[a];
            hi[a] = box_hi[a] - o[a];
            size = fmax(size, fmax(fabs(lo[a]), fabs(hi[a])) + fabs(o[a]) + fmax(fabs(box_lo[a]), fabs(box_hi[a])));
        }
        for (t = 0; t < 3 * v->map_texels; t++) {
            const float *g = v->visibility + ((size_t)r->id[k] * v->map_texels + t / 3) * 4;
            gmax = fmax(gmax, fabs((double)g[t % 3]));
        }
        if (irrvol__map_box_max(v, v->visibility + (size_t)r->id[k] * v->map_texels * 4, lo, hi) +
                1e-5 * 3.0 * gmax * size <= 0.999)
            r->clear |= 1u << k;
    }
}

/* Every record's clear mask (irrvol__record_clear), over its sub-cell's
   box: the positions of its first and last table corners. */
static void irrvol__make_clear(irrvol *v)
{
    uint32_t c, x, y, z, ids[8];
    int a;
    for (c = 0; c < v->cell_count; c++) {
        const irrvol__cell *cell = &v->cell[c];
        uint32_t f = cell->side - 1, at = cell->corners;
        for (z = 0; z < f; z++)
            for (y = 0; y < f; y++)
                for (x = 0; x < f; x++) {
                    double lo[3], hi[3];
                    irrvol__table_corners(v, cell, x, y, z, ids);
                    for (a = 0; a < 3; a++) {
                        double l = v->positions[3 * (size_t)ids[0] + a], h = v->positions[3 * (size_t)ids[7] + a];
                        double grow = (double)v->bias * 1.001 + 1e-3 * (h - l) + 1e-6 * fmax(fabs(l), fabs(h));
                        lo[a] = l - grow;
                        hi[a] = h + grow;
                    }
                    irrvol__record_clear(v, &v->corners[at++], lo, hi);
                }
    }
}

/* Every sub-cell with hanging corners gets its terms, in v->terms. */
static irrvol_result irrvol__make_terms(irrvol *v, uint32_t records)
{
    uint64_t total = 0;
    uint32_t i;
    for (i = 0; i < records; i++)
        if (v->corners[i].hanging) total += irrvol__record_terms(v, &v->corners[i], NULL);
    if (total > UINT32_MAX || total > SIZE_MAX / sizeof(irrvol__term)) return IRRVOL_ERROR_OUT_OF_MEMORY;
    v->term_count = (uint32_t)total;
    if (!total) return IRRVOL_OK;
    v->terms = (irrvol__term *)irrvol__alloc_array(&v->allocator, (size_t)total, sizeof(irrvol__term));
    if (!v->terms) return IRRVOL_ERROR_OUT_OF_MEMORY;
    for (total = 0, i = 0; i < records; i++) {
        irrvol__corners *r = &v->corners[i];
        if (!r->hanging) continue;
        r->first = (uint32_t)total;
        r->hanging = irrvol__record_terms(v, r, v->terms + total);
        irrvol__merge_terms(v, r);
        total += r->hanging;
    }
    return IRRVOL_OK;
}

static irrvol_result irrvol__make_corners(irrvol *v)
{
    uint64_t count = irrvol__corner_count(v);
    uint32_t c, at = 0, x, y, z, k;
    if (count + 1 > UINT32_MAX || count + 2 > SIZE_MAX / sizeof(irrvol__corners)) return IRRVOL_ERROR_OUT_OF_MEMORY;
    v->corner_block = irrvol__alloc_array(&v->allocator, (size_t)count + 2, sizeof(irrvol__corners));
    if (!v->corner_block) return IRRVOL_ERROR_OUT_OF_MEMORY;
    v->corners = (irrvol__corners *)(void *)((unsigned char *)v->corner_block +
                                             (64 - (uintptr_t)v->corner_block % 64) % 64);
    for (c = 0; c < v->cell_count; c++) {
        irrvol__cell *cell = &v->cell[c];
        uint32_t f = cell->side - 1;
        cell->corners = at;
        for (z = 0; z < f; z++)
            for (y = 0; y < f; y++)
                for (x = 0; x < f; x++) {
                    irrvol__corners *r = &v->corners[at++];
                    memset(r, 0, sizeof *r);
                    irrvol__table_corners(v, cell, x, y, z, r->id);
                    for (k = 0; k < 8; k++) {
                        const float *p;
                        if (r->id[k] >= v->hanging_begin) {
                            r->hanging = 1;
                            continue;
                        }
                        p = v->probes + 4 * (size_t)r->id[k];
                        r->x[k] = p[0];
                        r->y[k] = p[1];
                        r->z[k] = p[2];
                        r->reach2[k] = p[3];
                    }
                }
    }
    {
        irrvol_result r = irrvol__make_terms(v, (uint32_t)count);
        if (r == IRRVOL_OK) irrvol__make_clear(v);
        return r;
    }
}

/* The probes: each sample's origin and reach in one record. A test point
   x at distance r from the origin lies beyond the predicted surface when
   g . (x - o) > 1 (section 13), g the bilinear blend of four texels'
   gradients, so |g| <= G, the largest gradient of the map, and no point
   with r G < 1 can be beyond it: there the Chebyshev test changes nothing
   and the queries skip the map (irrvol__lanes4_fetch). The reach is
   stored squared as (0.999 / G)^2, G rounded up: the margin dwarfs the
   float rounding of the blend and of g . (x - o), so skipping gives the
   same weights bit for bit. No surface seen: FLT_MAX; invalid: -1. */
static irrvol_result irrvol__make_probes(irrvol *v)
{
    uint32_t s, t;
    v->probes = (float *)irrvol__alloc_array(&v->allocator, (size_t)v->hanging_begin + 1, 4 * sizeof(float));
    if (!v->probes) return IRRVOL_ERROR_OUT_OF_MEMORY;
    for (s = 0; s < v->hanging_begin; s++) {
        const float *map = v->visibility + (size_t)s * v->map_texels * 4;
        double g2 = 0.0, reach;
        for (t = 0; t < v->map_texels; t++) {
            const float *g = map + 4 * (size_t)t;
            double l2 = (double)g[0] * g[0] + (double)g[1] * g[1] + (double)g[2] * g[2];
            g2 = l2 > g2 ? l2 : g2;
        }
        reach = g2 > 0.0 ? 0.999 / (sqrt(g2) * (1.0 + 1e-6)) : 0.0;
        memcpy(v->probes + 4 * (size_t)s, v->origins + 4 * (size_t)s, 3 * sizeof(float));
        v->probes[4 * (size_t)s + 3] = v->origins[4 * (size_t)s + 3] == 0.0f ? -1.0f
                                       : (g2 > 0.0 ? (float)(reach * reach * (1.0 - 1e-6)) : FLT_MAX);
    }
    return irrvol__make_corners(v);
}

/* Volume-wide settings that follow from the resolutions. */
static void irrvol__set_resolutions(irrvol *v, uint32_t k, uint32_t vis_res)
{
    v->k = k;
    v->bins = 2 * k * k;
    v->kf = (float)k;
    v->vis_res = vis_res;
    v->texels = vis_res * vis_res;
    v->map_texels = (vis_res + 2) * (vis_res + 2);
}

/* ======================================================================
   10. second-level refinement: where geometry is (4.1), where the light
   changes (6.1.1)
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
                    if (irrvol__tri_box_overlap(centre, half, tri)) refined[c] = IRRVOL__REFINED_GEOMETRY;
                }
    }
}


static float irrvol__luminance(const float *rgb)
{
    return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
}

/* Adaptive refinement by light (6.1.1: "if the eight samples surrounding
   each cell differed by a specified tolerance, the cell would be
   subdivided"). Trilinear interpolation is exact for light that changes
   linearly, so the metric is how far the samples along each axis bend away
   from a straight line: for a first-level sample s and its two neighbours
   a and b along an axis, the luminance of every bin j gives the second
   difference D_j = Y_a,j - 2 Y_s,j + Y_b,j, and

       E = sum_j |D_j| / 8 / sum_j (Y_a,j + 2 Y_s,j + Y_b,j) / 4

   is the interpolation error a parabola through the three would leave
   midway (h^2 f'' / 8 against the level). A cell is refined when E exceeds
   the threshold at any of its corners along any axis: where a light falls
   off fast and across shadow edges, not along a smooth gradient. Invalid
   samples do not count. irradiance holds the first-level samples bin-major
   (bin * first_level_count + sample); valid[4 s + 3] is 0 for invalid
   ones. bend is scratch for one float per first-level sample. */
static void irrvol__mark_light(const irrvol *v, const float *irradiance, const float *valid, float threshold,
                               unsigned char *refined, float *bend)
{
    uint32_t n = v->first_level_count, s, cx, cy, cz, c = 0, bin;
    for (s = 0; s < n; s++) {
        uint32_t g[3], step = 1, d;
        g[0] = s % v->samples[0];
        g[1] = (s / v->samples[0]) % v->samples[1];
        g[2] = s / (v->samples[0] * v->samples[1]);
        bend[s] = 0.0f;
        for (d = 0; d < 3; step *= v->samples[d], d++) {
            uint32_t a = s - step, b = s + step;
            double dev = 0.0, level = 0.0;
            if (g[d] == 0 || g[d] + 1 == v->samples[d] || valid[4 * (size_t)s + 3] == 0.0f ||
                valid[4 * (size_t)a + 3] == 0.0f || valid[4 * (size_t)b + 3] == 0.0f)
                continue;
            for (bin = 0; bin < v->bins; bin++) {
                const float *h = irradiance + 3 * (size_t)bin * n;
                double ya = irrvol__luminance(h + 3 * (size_t)a), ys = irrvol__luminance(h + 3 * (size_t)s);
                double yb = irrvol__luminance(h + 3 * (size_t)b);
                dev += fabs(ya - 2.0 * ys + yb);
                level += ya + 2.0 * ys + yb;
            }
            if (level > 0.0 && dev / 8.0 / (level / 4.0) > bend[s]) bend[s] = (float)(dev / 8.0 / (level / 4.0));
        }
    }
    for (cz = 0; cz < v->cells[2]; cz++)
        for (cy = 0; cy < v->cells[1]; cy++)
            for (cx = 0; cx < v->cells[0]; cx++, c++) {
                uint32_t i;
                if (refined[c]) continue;
                for (i = 0; i < 8; i++) {
                    uint32_t t = (cx + (i & 1u)) + v->samples[0] * ((cy + ((i >> 1) & 1u)) + v->samples[1] * (cz + (i >> 2)));
                    if (bend[t] > threshold) refined[c] = IRRVOL__REFINED_LIGHT;
                }
            }
}

/* ======================================================================
   11. spherical harmonics of the irradiance (Ramamoorthi and Hanrahan 2001)
   The compact encoding for shaders: the radiance projected on the real
   harmonics Y_lm, l <= 2, each band scaled by the lobe's A_l (eq. 7-8 of
   the paper: pi, 2 pi / 3, pi / 4 for the cosine). E(n) = sum A_l L_lm
   Y_lm(n) then costs nine multiply-adds per channel; L1 keeps the first
   four coefficients.
   ---------------------------------------------------------------------- */
/* Y_lm of a unit direction, ordered (0,0), (1,-1), (1,0), (1,1), (2,-2),
   (2,-1), (2,0), (2,1), (2,2). */
IRRVOL__HOT void irrvol__sh_basis(float x, float y, float z, float ylm[IRRVOL__SH_COEFFS])
{
    ylm[0] = 0.282094792f;
    ylm[1] = 0.488602512f * y;
    ylm[2] = 0.488602512f * z;
    ylm[3] = 0.488602512f * x;
    ylm[4] = 1.092548431f * x * y;
    ylm[5] = 1.092548431f * y * z;
    ylm[6] = 0.315391565f * (3.0f * z * z - 1.0f);
    ylm[7] = 1.092548431f * x * z;
    ylm[8] = 0.546274215f * (x * x - y * y);
}

/* A_l of the moment-n lobe (n+1)/2 max(0, cos)^n (eq. 4.8):
   2 pi (n+1)/2 integral_0^1 t^n P_l(t) dt; n = 1 gives pi, 2 pi / 3, pi / 4. */
static double irrvol__sh_lobe(uint32_t n, uint32_t l)
{
    double m = (double)n;
    if (l == 0) return IRRVOL__PI;
    if (l == 1) return IRRVOL__PI * (m + 1.0) / (m + 2.0);
    return 0.5 * IRRVOL__PI * (3.0 * (m + 1.0) / (m + 3.0) - 1.0);
}

/* The band l of coefficient j. */
static uint32_t irrvol__sh_band(uint32_t j) { return j == 0 ? 0u : (j < 4 ? 1u : 2u); }

/* ======================================================================
   12. build: radiance gathering (4.2.1, 4.2.2), validity and relocation,
   irradiance (4.2.3, 4.4), harmonics and visibility moments; invalid
   samples dilated, hanging samples constrained
   ---------------------------------------------------------------------- */
#define IRRVOL__BACK_FRACTION 0.25  /* back faces over more of the sphere: the sample is inside geometry */
#define IRRVOL__RELOCATE_LIMIT 0.45f  /* a sample moves at most this fraction of its local spacing */
#define IRRVOL__RELOCATE_MARGIN 0.05f /* and ends this fraction of it in front of the surface it crossed */

/* Where the sample jobs of a pass store their results: irradiance and
   radiance bin-major ((bin * stride + sample) * 3), the rest per sample. */
typedef struct irrvol__sink {
    float *irradiance, *radiance, *sh, *origins, *visibility;
    uint32_t *rays;
    unsigned char *state;     /* IRRVOL_SAMPLE_VALID, _RELOCATED or _INVALID */
    uint32_t stride;
} irrvol__sink;

typedef struct irrvol__build {
    const irrvol_desc *desc;
    irrvol *vol;
    irrvol__mesh_view mesh;
    int can_trace;             /* hit distances exist: triangles through the BVH or desc.trace */
    irrvol__bvh bvh;
    irrvol__bvh important_bvh; /* over the IMPORTANT triangles; ids index b->important */
    uint32_t *important_indices;
    uint32_t supersamples, weight_subdivisions, max_depth, important_side;
    float min_weight, ray_offset;
    float coarse_spacing, fine_spacing;   /* smallest sample spacing of each level */
    float *dirs;            /* bin centre directions, xyz per bin */
    float *dir_soa;         /* the same: all x, all y, all z */
    float *weights;         /* bins x bins: row i = radiance bin, column j = irradiance bin */
    float *sh_weights;      /* bins x 9: A_l times the integral of Y_lm over bin i */
    float *vis_weights;     /* bins x 4 texels: per texel the lobe around its direction times the bin
                               direction (x, y, z) and the lobe alone; the lobe sums to 1 */
    float *vis_inverse;     /* per texel the inverse of sum lobe w w^T over the bin directions w (3 x 3) */
    float vis_lobe;         /* exponent of that lobe */
    double sh_lobe[3];      /* A_l, l = 0, 1, 2 */
    uint32_t *important;    /* triangles of IMPORTANT materials */
    uint32_t important_count;
    float bin_solid_angle;  /* 4 pi / bins, eq. 4.2 */
    float bin_angle;        /* sqrt of it: the angular size of a bin */
    unsigned char *scratch; /* per job of a batch */
    size_t scratch_stride;  /* bytes per job */
    uint32_t scratch_jobs;  /* jobs it has room for */
    uint32_t batch_begin;
    irrvol__sink sink;
} irrvol__build;

/* One sample job's scratch: every array it needs, carved from one block. */
typedef struct irrvol__scratch {
    double *part;          /* bins x rgb: the important part's radiance integral per bin */
    float *direct;         /* 3 x bins, planar rgb: the important part's irradiance */
    float *sh_direct;      /* 3 x 9, planar rgb: the important part's harmonics */
    float *radiance;       /* 3 x bins, planar rgb */
    float *irradiance;     /* 3 x bins, planar rgb */
    float *inverse;        /* 3 x bins, planar: mean and mean square inverse hit distance, zeros */
    float *moments;        /* 3 x 4 texels, planar: the lobe's sums for the visibility fit */
    float *sh;             /* 3 x 9, planar rgb */
    float *lobe;           /* bins: one direction's lobe over the bin directions */
    uint32_t *rows;        /* bins: the non-zero rows of a matrix product */
    unsigned char *extra;  /* bins: the bins an important triangle overlaps */
} irrvol__scratch;

static void *irrvol__carve(unsigned char *base, size_t *at, size_t bytes)
{
    void *p = base ? (void *)(base + *at) : NULL;
    *at += (bytes + 15) & ~(size_t)15;
    return p;
}

/* The layout of one job's scratch in base (or, base NULL, only its size).
   Returns the bytes it takes, a multiple of a cache line. */
static size_t irrvol__scratch_layout(unsigned char *base, uint32_t bins, uint32_t texels, irrvol__scratch *sc)
{
    size_t at = 0, planar = 3 * (size_t)bins * sizeof(float);
    sc->part = (double *)irrvol__carve(base, &at, 3 * (size_t)bins * sizeof(double));
    sc->direct = (float *)irrvol__carve(base, &at, planar);
    sc->sh_direct = (float *)irrvol__carve(base, &at, IRRVOL__SH_FLOATS * sizeof(float));
    sc->radiance = (float *)irrvol__carve(base, &at, planar);
    sc->irradiance = (float *)irrvol__carve(base, &at, planar);
    sc->inverse = (float *)irrvol__carve(base, &at, planar);
    sc->moments = (float *)irrvol__carve(base, &at, 12 * (size_t)texels * sizeof(float));
    sc->sh = (float *)irrvol__carve(base, &at, IRRVOL__SH_FLOATS * sizeof(float));
    sc->lobe = (float *)irrvol__carve(base, &at, (size_t)bins * sizeof(float));
    sc->rows = (uint32_t *)irrvol__carve(base, &at, (size_t)bins * sizeof(uint32_t));
    sc->extra = (unsigned char *)irrvol__carve(base, &at, bins);
    return (at + 63) & ~(size_t)63;
}

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

/* Row i of the three matrices, from w x w equal-area sub-directions of bin
   i (the radiance is taken constant over the bin):
   - irradiance: W(i, j) = (n+1)/2 * integral over bin i of max(0, w . w_j)^n
     dw (eq. 4.8; one sub-direction is eq. 4.8 at the bin centre, eq. 4.3
     for n = 1);
   - harmonics: A_l * integral over bin i of Y_lm;
   - visibility: the lobe max(0, w_i . t)^p of each texel direction t at
     the bin centre, times w_i and alone (normalised afterwards). */
static void irrvol__weight_row_job(void *ctx, uint32_t i)
{
    const irrvol__build *b = (const irrvol__build *)ctx;
    const irrvol *v = b->vol;
    uint32_t w = b->weight_subdivisions, n = v->moment, bins = v->bins, s, j, t;
    float sub[IRRVOL_MAX_WEIGHT_SUBDIVISIONS * IRRVOL_MAX_WEIGHT_SUBDIVISIONS][3];
    double quad = 4.0 * IRRVOL__PI / ((double)bins * w * w), scale = 0.5 * (n + 1.0) * quad;
    double sh[IRRVOL__SH_COEFFS] = {0};
    const float *di = b->dirs + 3 * (size_t)i;
    float *row = b->weights + (size_t)i * bins;
    for (s = 0; s < w * w; s++) {
        irrvol__vec3 d = irrvol__bin_point(v->k, i, ((float)(s % w) + 0.5f) / (float)w,
                                           ((float)(s / w) + 0.5f) / (float)w);
        float ylm[IRRVOL__SH_COEFFS];
        sub[s][0] = d.x; sub[s][1] = d.y; sub[s][2] = d.z;
        irrvol__sh_basis(d.x, d.y, d.z, ylm);
        for (j = 0; j < IRRVOL__SH_COEFFS; j++) sh[j] += ylm[j];
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
    for (j = 0; j < IRRVOL__SH_COEFFS; j++)
        b->sh_weights[(size_t)i * IRRVOL__SH_COEFFS + j] = (float)(b->sh_lobe[irrvol__sh_band(j)] * quad * sh[j]);
    for (t = 0; t < v->texels; t++) {
        irrvol__vec3 c = irrvol__oct_decode(((float)(t % v->vis_res) + 0.5f) / (float)v->vis_res,
                                            ((float)(t / v->vis_res) + 0.5f) / (float)v->vis_res);
        double cs = (double)c.x * di[0] + (double)c.y * di[1] + (double)c.z * di[2];
        float *out = b->vis_weights + 4 * ((size_t)i * v->texels + t), lobe = cs > 0.0 ? (float)pow(cs, b->vis_lobe) : 0.0f;
        out[0] = lobe * di[0];
        out[1] = lobe * di[1];
        out[2] = lobe * di[2];
        out[3] = lobe;
    }
}

/* Inverts the symmetric 3 x 3 matrix m (row-major) into inv; a small
   multiple of the trace on the diagonal keeps a lobe of nearly parallel
   directions solvable (it then shrinks the fitted gradient a little). */
static void irrvol__invert3(const double m[9], float inv[9])
{
    double a[9], det, k = 1e-6 * (m[0] + m[4] + m[8]);
    int i;
    for (i = 0; i < 9; i++) a[i] = m[i] + (i % 4 == 0 ? k : 0.0);
    det = a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
    if (!(fabs(det) > 0.0)) { for (i = 0; i < 9; i++) inv[i] = 0.0f; return; }
    inv[0] = (float)((a[4] * a[8] - a[5] * a[7]) / det);
    inv[1] = (float)((a[2] * a[7] - a[1] * a[8]) / det);
    inv[2] = (float)((a[1] * a[5] - a[2] * a[4]) / det);
    inv[3] = (float)((a[5] * a[6] - a[3] * a[8]) / det);
    inv[4] = (float)((a[0] * a[8] - a[2] * a[6]) / det);
    inv[5] = (float)((a[2] * a[3] - a[0] * a[5]) / det);
    inv[6] = (float)((a[3] * a[7] - a[4] * a[6]) / det);
    inv[7] = (float)((a[1] * a[6] - a[0] * a[7]) / det);
    inv[8] = (float)((a[0] * a[4] - a[1] * a[3]) / det);
}

/* Scales each texel's lobe to sum 1 (a texel that no bin centre reaches,
   possible only at tiny k, takes its nearest bin) and inverts the texel's
   sum lobe w w^T, the normal matrix of the fit (section 13). */
static void irrvol__finish_visibility_weights(irrvol__build *b)
{
    const irrvol *v = b->vol;
    uint32_t t, i;
    for (t = 0; t < v->texels; t++) {
        double sum = 0.0, m[9] = {0};
        int j, k;
        for (i = 0; i < v->bins; i++) sum += b->vis_weights[4 * ((size_t)i * v->texels + t) + 3];
        if (!(sum > 0.0)) {
            irrvol__vec3 c = irrvol__oct_decode(((float)(t % v->vis_res) + 0.5f) / (float)v->vis_res,
                                                ((float)(t / v->vis_res) + 0.5f) / (float)v->vis_res);
            float dir[3], *w;
            dir[0] = c.x; dir[1] = c.y; dir[2] = c.z;
            i = irrvol_direction_bin(v, dir);
            w = b->vis_weights + 4 * ((size_t)i * v->texels + t);
            for (j = 0; j < 3; j++) w[j] = b->dirs[3 * (size_t)i + (size_t)j];
            w[3] = 1.0f;
            sum = 1.0;
        }
        for (i = 0; i < v->bins; i++) {
            float *w = b->vis_weights + 4 * ((size_t)i * v->texels + t);
            const float *d = b->dirs + 3 * (size_t)i;
            for (j = 0; j < 4; j++) w[j] = (float)(w[j] / sum);
            for (j = 0; j < 3; j++)
                for (k = 0; k < 3; k++) m[3 * j + k] += (double)w[3] * d[j] * d[k];
        }
        irrvol__invert3(m, b->vis_inverse + 9 * (size_t)t);
    }
}

/* out = W^T in for a rows x cols matrix W and three planar channels: eq.
   4.3 / 4.8 for every irradiance bin at once (W the weight matrix), the
   harmonics and the visibility moments alike. Zero rows of in add nothing
   and are skipped. The inner loop is a contiguous multiply-add the compiler
   vectorizes; four rows per pass over out load and store it a quarter as
   often. nonzero is scratch for the indices of the non-zero rows. */
static void irrvol__matrix_product(const float *IRRVOL__RESTRICT weights, uint32_t rows, uint32_t cols,
                                   const float *IRRVOL__RESTRICT in, float *IRRVOL__RESTRICT out, uint32_t *nonzero)
{
    float *IRRVOL__RESTRICT hr = out;
    float *IRRVOL__RESTRICT hg = out + cols;
    float *IRRVOL__RESTRICT hb = out + 2 * (size_t)cols;
    const float *lr = in, *lg = in + rows, *lb = in + 2 * (size_t)rows;
    uint32_t i, j, n = 0, r;
    memset(out, 0, 3 * (size_t)cols * sizeof(float));
    for (i = 0; i < rows; i++)
        if (lr[i] != 0.0f || lg[i] != 0.0f || lb[i] != 0.0f) nonzero[n++] = i;
    for (r = 0; r + 4 <= n; r += 4) {
        const float *IRRVOL__RESTRICT w0 = weights + (size_t)nonzero[r] * cols;
        const float *IRRVOL__RESTRICT w1 = weights + (size_t)nonzero[r + 1] * cols;
        const float *IRRVOL__RESTRICT w2 = weights + (size_t)nonzero[r + 2] * cols;
        const float *IRRVOL__RESTRICT w3 = weights + (size_t)nonzero[r + 3] * cols;
        float r0 = lr[nonzero[r]], r1 = lr[nonzero[r + 1]], r2 = lr[nonzero[r + 2]], r3 = lr[nonzero[r + 3]];
        float g0 = lg[nonzero[r]], g1 = lg[nonzero[r + 1]], g2 = lg[nonzero[r + 2]], g3 = lg[nonzero[r + 3]];
        float b0 = lb[nonzero[r]], b1 = lb[nonzero[r + 1]], b2 = lb[nonzero[r + 2]], b3 = lb[nonzero[r + 3]];
        for (j = 0; j < cols; j++) {
            float x0 = w0[j], x1 = w1[j], x2 = w2[j], x3 = w3[j];
            hr[j] += (r0 * x0 + r1 * x1) + (r2 * x2 + r3 * x3);
            hg[j] += (g0 * x0 + g1 * x1) + (g2 * x2 + g3 * x3);
            hb[j] += (b0 * x0 + b1 * x1) + (b2 * x2 + b3 * x3);
        }
    }
    for (; r < n; r++) {
        const float *IRRVOL__RESTRICT w0 = weights + (size_t)nonzero[r] * cols;
        float r0 = lr[nonzero[r]], g0 = lg[nonzero[r]], b0 = lb[nonzero[r]];
        for (j = 0; j < cols; j++) {
            hr[j] += r0 * w0[j];
            hg[j] += g0 * w0[j];
            hb[j] += b0 * w0[j];
        }
    }
}

/* First hit through the caller's ray caster or the built-in BVH. A hit on
   a triangle index out of range, or at a negative or non-finite distance,
   counts as a miss. */
static int irrvol__trace(const irrvol__build *b, const float org[3], const float dir[3], irrvol_hit *hit)
{
    const irrvol_desc *d = b->desc;
    if (d->trace) {
        if (!d->trace(d->trace_user, org, dir, FLT_MAX, hit)) return 0;
        return hit->triangle < d->triangle_count && hit->t >= 0.0f && isfinite(hit->t) && isfinite(hit->u) &&
               isfinite(hit->v);
    } else {
        irrvol__hit h;
        if (!irrvol__bvh_intersect(&b->bvh, org, dir, 0.0f, FLT_MAX, &h)) return 0;
        hit->t = h.t; hit->u = h.u; hit->v = h.v; hit->triangle = h.tri;
        return 1;
    }
}

static const irrvol_material *irrvol__hit_material(const irrvol_desc *d, uint32_t triangle)
{
    if (!d->materials) return NULL;
    return &d->materials[d->triangle_materials ? d->triangle_materials[triangle] : 0];
}

/* The geometric normal of a triangle, (v1 - v0) x (v2 - v0): it points to
   the front side, the side from which the triangle winds counter-clockwise. */
static irrvol__vec3 irrvol__triangle_normal(const irrvol__build *b, uint32_t triangle)
{
    const uint32_t *tri = b->desc->indices + 3 * (size_t)triangle;
    irrvol__vec3 p0 = irrvol__v3_load(irrvol__vertex(&b->mesh, tri[0]));
    return irrvol__cross(irrvol__sub(irrvol__v3_load(irrvol__vertex(&b->mesh, tri[1])), p0),
                         irrvol__sub(irrvol__v3_load(irrvol__vertex(&b->mesh, tri[2])), p0));
}

/* Whether a material passes light (thin glass): a transmittance above 0. */
static int irrvol__transmits(const irrvol_material *mat)
{
    return mat && (mat->transmittance[0] > 0.0f || mat->transmittance[1] > 0.0f || mat->transmittance[2] > 0.0f);
}

/* Whether a ray along dir meets the hit triangle from behind; never for
   TWO_SIDED materials, nor for glass: a pane is a sheet with no inside, so
   seeing its back says nothing about being inside geometry. */
static int irrvol__back_face(const irrvol__build *b, const irrvol_hit *hit, const float dir[3])
{
    const irrvol_material *mat = irrvol__hit_material(b->desc, hit->triangle);
    if (mat && ((mat->flags & IRRVOL_MATERIAL_TWO_SIDED) || irrvol__transmits(mat))) return 0;
    return irrvol__dot(irrvol__triangle_normal(b, hit->triangle), irrvol__v3_load(dir)) > 0.0f;
}

/* The diffuse radiance of the surface at a hit: per-vertex radiance
   interpolated with the barycentrics, or the material's. Either side of a
   triangle emits it (emitters are two-sided). */
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

/* The sky along the unit direction dir: the texel of desc.environment it
   falls in (latitude-longitude, +y up: row = floor(theta / pi * height) with
   theta the angle from +y, column = floor((phi + pi) / (2 pi) * width) with
   phi = atan2(z, x); no filtering, so a map is exactly a piecewise constant
   radiance), or desc.background without a map. */
static void irrvol__sky(const irrvol_desc *d, const float dir[3], float rgb[3])
{
    const float *src = d->background;
    if (d->environment) {
        double cos_theta = dir[1], theta, phi;
        uint32_t row, col;
        if (!(cos_theta >= -1.0)) cos_theta = -1.0;   /* NaN too */
        if (cos_theta > 1.0) cos_theta = 1.0;
        theta = acos(cos_theta);
        phi = atan2((double)dir[2], (double)dir[0]);
        if (!(phi >= -IRRVOL__PI)) phi = -IRRVOL__PI;
        row = (uint32_t)(theta / IRRVOL__PI * d->environment_height);
        col = (uint32_t)((phi + IRRVOL__PI) / (2.0 * IRRVOL__PI) * d->environment_width);
        if (row >= d->environment_height) row = d->environment_height - 1;
        if (col >= d->environment_width) col = d->environment_width - 1;
        src = d->environment + 3 * ((size_t)row * d->environment_width + col);
    }
    rgb[0] = src[0];
    rgb[1] = src[1];
    rgb[2] = src[2];
}

/* Adds w times the sky along dir to rgb. */
static void irrvol__add_sky(const irrvol_desc *d, const float w[3], irrvol__vec3 dir, float rgb[3])
{
    float dirf[3], sky[3];
    int c;
    dirf[0] = dir.x; dirf[1] = dir.y; dirf[2] = dir.z;
    irrvol__sky(d, dirf, sky);
    for (c = 0; c < 3; c++) rgb[c] += w[c] * sky[c];
}

/* Built-in radiance along a ray (4.2.2) whose first hit is known (NULL:
   it leaves the scene): the first surface's radiance plus, through mirror
   surfaces, the specularly reflected radiance weighted by the product of
   the specular coefficients, until a diffuse surface, the depth limit or
   the weight floor (then the sky stands for the rest). Glass (a
   transmittance above 0) adds its own radiance and passes the rest of the
   ray straight on, weighted by its transmittance; a ray that crosses more
   than IRRVOL_MAX_GLASS_LAYERS panes counts as blocked there. Rays that
   leave the scene see the sky. */
static void irrvol__builtin_radiance(const irrvol__build *b, const float org[3], const float dir[3],
                                     const irrvol_hit *first, float rgb[3])
{
    const irrvol_desc *d = b->desc;
    float o[3], w[3] = {1.0f, 1.0f, 1.0f};
    irrvol__vec3 dv = irrvol__v3_load(dir);
    uint32_t reflections = 0, layers = 0;
    int c;
    memcpy(o, org, sizeof o);
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    for (;;) {
        irrvol_hit hit;
        const irrvol_material *mat;
        float le[3], dirf[3];
        irrvol__vec3 n, p;
        float dn;
        int traced = reflections > 0 || layers > 0;
        dirf[0] = dv.x; dirf[1] = dv.y; dirf[2] = dv.z;
        if (!traced ? first == NULL : !irrvol__trace(b, o, dirf, &hit)) {
            irrvol__add_sky(d, w, dv, rgb);
            return;
        }
        if (!traced) hit = *first;
        mat = irrvol__hit_material(d, hit.triangle);
        if (mat && (mat->flags & IRRVOL_MATERIAL_IGNORE)) return;   /* 5.4: contributes zero */
        irrvol__surface_radiance(b, &hit, mat, le);
        for (c = 0; c < 3; c++) rgb[c] += w[c] * le[c];
        if (!irrvol__transmits(mat) &&
            (!mat || (mat->specular[0] <= 0.0f && mat->specular[1] <= 0.0f && mat->specular[2] <= 0.0f)))
            return;
        n = irrvol__normalize(irrvol__triangle_normal(b, hit.triangle));
        dn = irrvol__dot(dv, n);
        if (irrvol__transmits(mat)) {
            /* straight on from just behind the pane, on the far side of
               the surface from where the ray came */
            if (++layers > IRRVOL_MAX_GLASS_LAYERS) return;
            for (c = 0; c < 3; c++) w[c] *= mat->transmittance[c];
            p = irrvol__add(irrvol__v3_load(o), irrvol__scale(dv, hit.t));
            p = irrvol__add(p, irrvol__scale(n, dn < 0.0f ? -b->ray_offset : b->ray_offset));
            o[0] = p.x; o[1] = p.y; o[2] = p.z;
            continue;
        }
        for (c = 0; c < 3; c++) w[c] *= mat->specular[c];
        reflections++;
        /* mirror about the geometric normal; the next ray starts off the
           surface on the side the ray came from and a little back along it,
           so that a hit on the edge of a concave corner still finds the
           other face instead of leaving through it */
        p = irrvol__add(irrvol__v3_load(o), irrvol__scale(dv, hit.t - b->ray_offset));
        dv = irrvol__normalize(irrvol__sub(dv, irrvol__scale(n, 2.0f * dn)));
        if (reflections > b->max_depth || irrvol__maxf(w[0], irrvol__maxf(w[1], w[2])) < b->min_weight) {
            irrvol__add_sky(d, w, dv, rgb);   /* the cut chain: the sky along the reflected ray */
            return;
        }
        p = irrvol__add(p, irrvol__scale(n, dn < 0.0f ? b->ray_offset : -b->ray_offset));
        o[0] = p.x; o[1] = p.y; o[2] = p.z;
    }
}

/* The first surface along a ray: its distance t (FLT_MAX when the ray
   leaves the scene or nothing can be traced) and whether it is met from
   behind. Fills *hit and returns 1 on a hit. */
static int irrvol__first_hit(const irrvol__build *b, const float org[3], const float dir[3], irrvol_hit *hit,
                             float *t, int *back)
{
    *t = FLT_MAX;
    *back = 0;
    if (!b->can_trace || !irrvol__trace(b, org, dir, hit)) return 0;
    *t = hit->t;
    *back = irrvol__back_face(b, hit, dir);
    return 1;
}

/* A gather ray: the radiance from the caller's callback or the built-in
   shading, and the first hit's distance and side. */
static void irrvol__gather_ray(const irrvol__build *b, const float org[3], irrvol__vec3 dir, float rgb[3], float *t,
                               int *back)
{
    irrvol_hit hit;
    float d[3];
    int found;
    d[0] = dir.x; d[1] = dir.y; d[2] = dir.z;
    found = irrvol__first_hit(b, org, d, &hit, t, back);
    if (b->desc->radiance) b->desc->radiance(b->desc->radiance_user, org, d, rgb);
    else irrvol__builtin_radiance(b, org, d, found ? &hit : NULL, rgb);
}

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
                extra[irrvol_direction_bin(b->vol, dir)] = 1;
            }
    }
}

/* One direction of the important part, radiance w L arriving along the
   unit dir: adds (n+1)/2 w L max(0, dir . w_j)^n to every irradiance bin j
   (eq. 4.8 for a single direction; direct is planar rgb) and A_l w L
   Y_lm(dir) to the harmonics (sh_direct, planar rgb). Bin directions are
   stored by component, so the loops over bins are contiguous and vectorize. */
static void irrvol__add_direction(const irrvol__build *b, const float dir[3], const double wl[3],
                                  const irrvol__scratch *sc)
{
    const irrvol *v = b->vol;
    uint32_t bins = v->bins, j;
    const float *IRRVOL__RESTRICT dx = b->dir_soa;
    const float *IRRVOL__RESTRICT dy = dx + bins;
    const float *IRRVOL__RESTRICT dz = dy + bins;
    float *IRRVOL__RESTRICT lobe = sc->lobe;
    float *IRRVOL__RESTRICT hr = sc->direct;
    float *IRRVOL__RESTRICT hg = hr + bins;
    float *IRRVOL__RESTRICT hb = hg + bins;
    double scale = 0.5 * (v->moment + 1.0);
    float r = (float)(scale * wl[0]), g = (float)(scale * wl[1]), bl = (float)(scale * wl[2]);
    float ylm[IRRVOL__SH_COEFFS];
    for (j = 0; j < bins; j++) {
        float cs = dir[0] * dx[j] + dir[1] * dy[j] + dir[2] * dz[j];
        lobe[j] = cs > 0.0f ? cs : 0.0f;
    }
    if (v->moment > 1)
        for (j = 0; j < bins; j++) lobe[j] = (float)irrvol__powi(lobe[j], v->moment);
    for (j = 0; j < bins; j++) {
        hr[j] += lobe[j] * r;
        hg[j] += lobe[j] * g;
        hb[j] += lobe[j] * bl;
    }
    irrvol__sh_basis(dir[0], dir[1], dir[2], ylm);
    for (j = 0; j < IRRVOL__SH_COEFFS; j++) {
        double a = b->sh_lobe[irrvol__sh_band(j)] * ylm[j];
        sc->sh_direct[j] += (float)(a * wl[0]);
        sc->sh_direct[IRRVOL__SH_COEFFS + j] += (float)(a * wl[1]);
        sc->sh_direct[2 * IRRVOL__SH_COEFFS + j] += (float)(a * wl[2]);
    }
}

/* The important set's part: stratified points uniform in area on each
   important triangle, weighted by their solid angle A cos(theta) / (r^2 M).
   Each adds w L to its bin's radiance integral (sc->part, for the kept
   radiance) and its lobe to the irradiance and harmonics (add_direction).
   desc.important_rays points per sample, shared among the triangles by
   solid angle, plus 16 per bin they cover; at least 2 x 2 per triangle.
   Returns the rays cast. */
static uint32_t irrvol__important_part(const irrvol__build *b, const float p[3], irrvol__rng *rng,
                                       const irrvol__scratch *sc)
{
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
                float dir[3], rgb[3], dist;
                double *acc;
                irrvol__hit hit;
                int back;
                for (c = 0; c < 3; c++) pt[c] = w0 * q[0][c] + w1 * q[1][c] + w2 * q[2][c];
                r2 = pt[0] * pt[0] + pt[1] * pt[1] + pt[2] * pt[2];
                r = sqrt(r2);
                if (!(r > 0.0)) continue;
                for (c = 0; c < 3; c++) dir[c] = (float)(pt[c] / r);
                weight = 0.5 * fabs(n[0] * pt[0] + n[1] * pt[1] + n[2] * pt[2]) / (r * r2) / ((double)side * side);
                /* count the direction here only if this triangle is the first important one along it */
                if (!irrvol__bvh_intersect(&b->important_bvh, p, dir, 0.0f, FLT_MAX, &hit) || hit.tri != t) continue;
                irrvol__gather_ray(b, p, irrvol__v3_load(dir), rgb, &dist, &back);
                rays++;
                for (c = 0; c < 3; c++) wl[c] = weight * rgb[c];
                if (wl[0] == 0.0 && wl[1] == 0.0 && wl[2] == 0.0) continue;
                acc = sc->part + 3 * (size_t)irrvol_direction_bin(b->vol, dir);
                acc[0] += wl[0]; acc[1] += wl[1]; acc[2] += wl[2];
                irrvol__add_direction(b, dir, wl, sc);
            }
    }
    return rays;
}

/* What a gather saw, for the validity test. */
typedef struct irrvol__gather_stats {
    uint32_t rays;          /* rays cast */
    double back;            /* the fraction of the sphere where the bin rays met back faces */
    float back_t;           /* the nearest back-face hit */
    float back_dir[3];      /* and its direction */
} irrvol__gather_stats;

/* Gathers radiance at p in every bin (4.2.2): s x s jittered rays per bin
   (or one through the centre), extra rays in the bins an important triangle
   overlaps, and the important part. Leaves in sc the bin radiance (planar),
   the important part, and the mean and mean square inverse hit distance of
   each bin's rays. */
static void irrvol__gather_at(const irrvol__build *b, const float p[3], irrvol__rng *rng, const irrvol__scratch *sc,
                              irrvol__gather_stats *st)
{
    const irrvol *v = b->vol;
    uint32_t bins = v->bins, bin;
    int c;
    memset(st, 0, sizeof *st);
    st->back_t = FLT_MAX;
    memset(sc->extra, 0, bins);
    memset(sc->part, 0, 3 * (size_t)bins * sizeof(double));
    memset(sc->direct, 0, 3 * (size_t)bins * sizeof(float));
    memset(sc->sh_direct, 0, IRRVOL__SH_FLOATS * sizeof(float));
    if (b->important_count) {
        irrvol__mark_important_bins(b, p, sc->extra);
        st->rays += irrvol__important_part(b, p, rng, sc);
    }
    for (bin = 0; bin < bins; bin++) {
        double sum[3] = {0.0, 0.0, 0.0}, inv = 0.0, inv2 = 0.0;
        uint32_t ss = b->supersamples, count = 0, back_count = 0, pass;
        for (pass = 0; pass < 2; pass++) {
            uint32_t side = pass == 0 ? ss : (sc->extra[bin] ? b->important_side : 0), x, y;
            for (y = 0; y < side; y++)
                for (x = 0; x < side; x++) {
                    float rgb[3], dir[3], fu = 0.5f, fv = 0.5f, t;
                    irrvol_hit hit;
                    irrvol__vec3 d;
                    int back;
                    if (pass == 1 || ss > 1) {   /* jitter in stratum (x, y) */
                        fu = ((float)x + irrvol__rng_float(rng)) / (float)side;
                        fv = ((float)y + irrvol__rng_float(rng)) / (float)side;
                    }
                    d = irrvol__bin_point(v->k, bin, fu, fv);
                    dir[0] = d.x; dir[1] = d.y; dir[2] = d.z;
                    count++;
                    if (b->important_count && irrvol__bvh_occluded(&b->important_bvh, p, dir, 0.0f, FLT_MAX)) {
                        /* an important direction: its radiance comes from the important part */
                        irrvol__first_hit(b, p, dir, &hit, &t, &back);
                    } else {
                        irrvol__gather_ray(b, p, d, rgb, &t, &back);
                        sum[0] += rgb[0]; sum[1] += rgb[1]; sum[2] += rgb[2];
                    }
                    st->rays++;
                    if (t < FLT_MAX) {   /* a miss is infinitely far: 1 / t = 0 */
                        double s = 1.0 / irrvol__maxf(t, b->ray_offset);
                        inv += s;
                        inv2 += s * s;
                    }
                    if (back) {
                        back_count++;
                        if (t < st->back_t) { st->back_t = t; memcpy(st->back_dir, dir, sizeof dir); }
                    }
                }
        }
        for (c = 0; c < 3; c++) sc->radiance[(size_t)c * bins + bin] = (float)(sum[c] / count);
        sc->inverse[bin] = (float)(inv / count);
        sc->inverse[bins + bin] = (float)(inv2 / count);
        sc->inverse[2 * (size_t)bins + bin] = 0.0f;
        st->back += (double)back_count / count / bins;   /* equal-area bins: the extra rays do not tip it */
    }
}

/* The smallest spacing between p's neighbours: the second level's where a
   cell around a first-level sample holds geometry (relocation moves samples
   out of geometry by a fraction of it). */
static float irrvol__local_spacing(const irrvol__build *b, uint32_t s)
{
    const irrvol *v = b->vol;
    uint32_t g[3], x, y, z, lo[3], hi[3];
    int d;
    if (s >= v->first_level_count) return b->fine_spacing;
    g[0] = s % v->samples[0];
    g[1] = (s / v->samples[0]) % v->samples[1];
    g[2] = s / (v->samples[0] * v->samples[1]);
    for (d = 0; d < 3; d++) {
        lo[d] = g[d] > 0 ? g[d] - 1 : 0;
        hi[d] = g[d] < v->cells[d] ? g[d] : v->cells[d] - 1;
    }
    for (z = lo[2]; z <= hi[2]; z++)
        for (y = lo[1]; y <= hi[1]; y++)
            for (x = lo[0]; x <= hi[0]; x++)
                if (v->refined[x + v->cells[0] * (y + v->cells[1] * z)] == IRRVOL__REFINED_GEOMETRY) return b->fine_spacing;
    return b->coarse_spacing;
}

/* The results of a sample's gather: eq. 4.3 / 4.8 by the weight matrix
   plus the important part, the kept radiance, the harmonics and the
   visibility fit, into the sink. */
static void irrvol__store_sample(const irrvol__build *b, uint32_t s, const irrvol__scratch *sc)
{
    const irrvol *v = b->vol;
    const irrvol__sink *k = &b->sink;
    uint32_t bins = v->bins, bin, j, t;
    float *vis = k->visibility + (size_t)s * v->map_texels * 4;
    int c;
    irrvol__matrix_product(b->weights, bins, bins, sc->radiance, sc->irradiance, sc->rows);
    irrvol__matrix_product(b->sh_weights, bins, IRRVOL__SH_COEFFS, sc->radiance, sc->sh, sc->rows);
    irrvol__matrix_product(b->vis_weights, bins, 4 * v->texels, sc->inverse, sc->moments, sc->rows);
    for (bin = 0; bin < bins; bin++) {
        float *out = k->irradiance + ((size_t)bin * k->stride + s) * 3;
        for (c = 0; c < 3; c++) out[c] = sc->irradiance[(size_t)c * bins + bin] + sc->direct[(size_t)c * bins + bin];
        if (k->radiance) {
            out = k->radiance + ((size_t)bin * k->stride + s) * 3;
            for (c = 0; c < 3; c++)
                out[c] = (float)(sc->radiance[(size_t)c * bins + bin] + sc->part[3 * (size_t)bin + (size_t)c] / b->bin_solid_angle);
        }
    }
    for (j = 0; j < IRRVOL__SH_COEFFS; j++)
        for (c = 0; c < 3; c++)
            k->sh[(size_t)s * IRRVOL__SH_FLOATS + 3 * j + (size_t)c] =
                sc->sh[(size_t)c * IRRVOL__SH_COEFFS + j] + sc->sh_direct[(size_t)c * IRRVOL__SH_COEFFS + j];
    for (t = 0; t < v->texels; t++) {   /* the fit: g = (sum lobe w w^T)^-1 sum lobe s w, and its residual */
        const float *m = b->vis_inverse + 9 * (size_t)t, *bt = sc->moments + 4 * (size_t)t;
        float mean2 = sc->moments[4 * (size_t)v->texels + 4 * (size_t)t + 3];
        float *out = vis + 4 * ((t / v->vis_res + 1) * (v->vis_res + 2) + t % v->vis_res + 1);
        for (c = 0; c < 3; c++) out[c] = m[3 * c] * bt[0] + m[3 * c + 1] * bt[1] + m[3 * c + 2] * bt[2];
        out[3] = irrvol__maxf(mean2 - (out[0] * bt[0] + out[1] * bt[1] + out[2] * bt[2]), 0.0f);
    }
    irrvol__map_border(v, vis);
}

/* One sample: gather (4.2.2); a sample that sees back faces over more than
   a quarter of its sphere is inside geometry (DDGI's classification).
   It moves through the nearest back face it saw, to a margin in front of
   that surface, and gathers again (DDGI's relocation, Unity's virtual
   offset) when that is within IRRVOL__RELOCATE_LIMIT of its spacing;
   otherwise, or if it is still inside, it is invalid: it never enters a
   leak-safe query and its values are dilated from its neighbours. */
static void irrvol__sample_job(void *ctx, uint32_t index)
{
    irrvol__build *b = (irrvol__build *)ctx;
    const irrvol *v = b->vol;
    uint32_t s = b->batch_begin + index;
    irrvol__scratch sc;
    irrvol__gather_stats st;
    irrvol__rng rng = irrvol__rng_stream(b->desc->seed, s);
    float p[3], *origin = b->sink.origins + 4 * (size_t)s;
    unsigned char state = IRRVOL_SAMPLE_VALID;
    uint32_t rays;
    irrvol__scratch_layout(b->scratch + (size_t)index * b->scratch_stride, v->bins, v->texels, &sc);
    memcpy(p, v->positions + 3 * (size_t)s, sizeof p);
    irrvol__gather_at(b, p, &rng, &sc, &st);
    rays = st.rays;
    if (st.back > IRRVOL__BACK_FRACTION) {
        float spacing = irrvol__local_spacing(b, s);
        float move = st.back_t + IRRVOL__RELOCATE_MARGIN * spacing;
        state = IRRVOL_SAMPLE_INVALID;
        if (move <= IRRVOL__RELOCATE_LIMIT * spacing) {
            float q[3];
            int c;
            for (c = 0; c < 3; c++) q[c] = p[c] + move * st.back_dir[c];
            irrvol__gather_at(b, q, &rng, &sc, &st);
            rays += st.rays;
            if (st.back <= IRRVOL__BACK_FRACTION) {
                state = IRRVOL_SAMPLE_RELOCATED;
                memcpy(p, q, sizeof p);
            }
        }
    }
    irrvol__store_sample(b, s, &sc);
    origin[0] = p[0]; origin[1] = p[1]; origin[2] = p[2];
    origin[3] = state == IRRVOL_SAMPLE_INVALID ? 0.0f : 1.0f;
    b->sink.state[s] = state;
    b->sink.rays[s] = rays;
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

/* Whether every one of the 3 * triangle_count indices is below
   vertex_count. The count of indices is taken in 64 bits and the triangle
   count is capped at UINT32_MAX / 3, so that 3 * t indexes in uint32_t
   everywhere after validation (0x55555556 triangles would wrap to 2
   indices in 32 bits and let the build read past the buffer). */
static int irrvol__indices_valid(const uint32_t *indices, uint32_t triangle_count, uint32_t vertex_count)
{
    uint64_t i, n = 3 * (uint64_t)triangle_count;
    if (triangle_count > UINT32_MAX / 3) return 0;
    for (i = 0; i < n; i++)
        if (indices[i] >= vertex_count) return 0;
    return 1;
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
    if (!irrvol__indices_valid(d->indices, d->triangle_count, d->vertex_count))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a vertex index is out of range (or over UINT32_MAX / 3 triangles)");
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

/* No map, or a map of sensible size whose texels are finite and >= 0. */
static int irrvol__environment_valid(const irrvol_desc *d)
{
    size_t i, n;
    if (!d->environment) return 1;
    if (d->environment_width < 1 || d->environment_height < 1 || d->environment_width > IRRVOL_MAX_ENVIRONMENT_SIZE ||
        d->environment_height > IRRVOL_MAX_ENVIRONMENT_SIZE)
        return 0;
    if (d->environment_height > (size_t)-1 / 3 / d->environment_width) return 0;   /* 32-bit size_t */
    n = (size_t)d->environment_width * d->environment_height;
    for (i = 0; i < n; i++)
        if (!irrvol__nonnegative3(d->environment + 3 * i)) return 0;
    return 1;
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
            if (!irrvol__nonnegative3(d->materials[i].radiance) || !irrvol__nonnegative3(d->materials[i].specular) ||
                !irrvol__nonnegative3(d->materials[i].transmittance) || d->materials[i].transmittance[0] > 1.0f ||
                d->materials[i].transmittance[1] > 1.0f || d->materials[i].transmittance[2] > 1.0f)
                IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: a material value is negative, NaN or infinite, "
                                                    "or a transmittance above 1");
    }
    if (!irrvol__environment_valid(d))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: environment map of 0 or over IRRVOL_MAX_ENVIRONMENT_SIZE "
                                            "texels a side, or a texel negative, NaN or infinite");
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
    if (d->resolution > IRRVOL_MAX_RESOLUTION || d->supersamples > IRRVOL_MAX_SUPERSAMPLES ||
        d->moment > IRRVOL_MAX_MOMENT || d->weight_subdivisions > IRRVOL_MAX_WEIGHT_SUBDIVISIONS ||
        d->important_rays > IRRVOL_MAX_IMPORTANT_RAYS || d->visibility_resolution > IRRVOL_MAX_VISIBILITY_RESOLUTION)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: resolution, supersamples, moment, weight_subdivisions, "
                                            "important_rays or visibility_resolution too large");
    if ((int)d->filter < 0 || (int)d->filter > (int)IRRVOL_FILTER_BILINEAR)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: unknown filter");
    if ((int)d->weighting < 0 || (int)d->weighting > (int)IRRVOL_WEIGHTING_TRILINEAR)
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: unknown weighting");
    if (!irrvol__nonnegative3(d->background) || !(d->min_weight >= 0.0f) || !isfinite(d->min_weight) ||
        !(d->ray_offset >= 0.0f) || !isfinite(d->ray_offset))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: background, min_weight or ray_offset negative, NaN or infinite");
    if (!isfinite(d->normal_bias) || d->normal_bias > 1.0f || !isfinite(d->refine_threshold))
        IRRVOL__REJECT(d->log, d->log_user, "irrvol_build: normal_bias above 1, or normal_bias or refine_threshold NaN "
                                            "or infinite");
    return IRRVOL_OK;
}

/* Bounds of the vertices the triangles use. */
static void irrvol__scene_bounds(const irrvol__mesh_view *m, float lo[3], float hi[3])
{
    uint32_t t;
    int e;
    irrvol__box_empty(lo, hi);
    for (t = 0; t < m->tri_count; t++)
        for (e = 0; e < 3; e++) {
            const float *p = irrvol__vertex(m, m->indices[3 * (size_t)t + (size_t)e]);
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
   outer walls), dimensions and the cells geometry refines; the distances
   that follow from them. */
static irrvol_result irrvol__setup_grid(irrvol__build *b)
{
    const irrvol_desc *d = b->desc;
    irrvol *v = b->vol;
    uint32_t samples[3];
    float slo[3], shi[3];
    double diag2 = 0.0;
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
        diag2 += ((double)v->hi[k] - v->lo[k]) * ((double)v->hi[k] - v->lo[k]);
    }
    b->ray_offset = d->ray_offset > 0.0f ? d->ray_offset : 1e-4f * (float)sqrt(diag2);
    irrvol__grid_dims(v, samples, irrvol__def(d->subgrid_samples, 3u));
    v->refined = (unsigned char *)irrvol__alloc(&v->allocator, v->cell_count);
    if (!v->refined) return IRRVOL_ERROR_OUT_OF_MEMORY;
    memset(v->refined, 0, v->cell_count);
    if (v->subgrid > 2) irrvol__mark_refined(v, &b->mesh, v->refined);
    b->coarse_spacing = FLT_MAX;
    for (k = 0; k < 3; k++)
        b->coarse_spacing = irrvol__minf(b->coarse_spacing, (float)(((double)v->hi[k] - v->lo[k]) / v->cells[k]));
    b->fine_spacing = b->coarse_spacing / (float)(v->subgrid - 1);
    return IRRVOL_OK;
}

/* Bin directions, the three weight matrices and the informed-sampling list. */
static irrvol_result irrvol__setup_directions(irrvol__build *b)
{
    const irrvol_desc *d = b->desc;
    irrvol *v = b->vol;
    const irrvol_allocator *a = &v->allocator;
    uint32_t i, l;
    double texel_angle;
    b->dirs = (float *)irrvol__alloc_array(a, (size_t)v->bins * 3, sizeof(float));
    b->dir_soa = (float *)irrvol__alloc_array(a, (size_t)v->bins * 3, sizeof(float));
    b->weights = (float *)irrvol__alloc_array(a, (size_t)v->bins * v->bins, sizeof(float));
    b->sh_weights = (float *)irrvol__alloc_array(a, (size_t)v->bins * IRRVOL__SH_COEFFS, sizeof(float));
    b->vis_weights = (float *)irrvol__alloc_array(a, (size_t)v->bins * v->texels, 4 * sizeof(float));
    b->vis_inverse = (float *)irrvol__alloc_array(a, v->texels, 9 * sizeof(float));
    if (!b->dirs || !b->dir_soa || !b->weights || !b->sh_weights || !b->vis_weights || !b->vis_inverse)
        return IRRVOL_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < v->bins; i++) {
        irrvol__vec3 dir = irrvol__bin_point(v->k, i, 0.5f, 0.5f);
        b->dirs[3 * i] = dir.x; b->dirs[3 * i + 1] = dir.y; b->dirs[3 * i + 2] = dir.z;
        b->dir_soa[i] = dir.x; b->dir_soa[v->bins + i] = dir.y; b->dir_soa[2 * v->bins + i] = dir.z;
    }
    b->bin_solid_angle = (float)(4.0 * IRRVOL__PI / v->bins);   /* eq. 4.2 */
    b->bin_angle = sqrtf(b->bin_solid_angle);
    for (l = 0; l < 3; l++) b->sh_lobe[l] = irrvol__sh_lobe(v->moment, l);
    /* the visibility lobe's half width at half maximum: three quarters of
       a texel (DDGI's cos^50 at 16 x 16), at least a bin, at most a radian */
    texel_angle = 0.75 * sqrt(4.0 * IRRVOL__PI / v->texels);
    if (texel_angle < b->bin_angle) texel_angle = b->bin_angle;
    if (texel_angle > 1.0) texel_angle = 1.0;
    b->vis_lobe = (float)(log(0.5) / log(cos(texel_angle)));
    irrvol__run_jobs(d->parallel_for, d->parallel_user, irrvol__weight_row_job, b, v->bins);
    irrvol__finish_visibility_weights(b);
    if (d->materials && d->triangle_count) {
        uint32_t t, n = 0;
        for (t = 0; t < d->triangle_count; t++)
            if (irrvol__hit_material(d, t)->flags & IRRVOL_MATERIAL_IMPORTANT) n++;
        if (n) {
            irrvol__mesh_view m = b->mesh;
            b->important = (uint32_t *)irrvol__alloc_array(a, n, sizeof(uint32_t));
            b->important_indices = (uint32_t *)irrvol__alloc_array(a, n, 3 * sizeof(uint32_t));
            if (!b->important || !b->important_indices) return IRRVOL_ERROR_OUT_OF_MEMORY;
            for (t = 0; t < d->triangle_count; t++)
                if (irrvol__hit_material(d, t)->flags & IRRVOL_MATERIAL_IMPORTANT) {
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

/* Arrays of a sink for count samples (the first level of the light pass). */
static irrvol_result irrvol__sink_alloc(irrvol__build *b, irrvol__sink *k, uint32_t count)
{
    const irrvol *v = b->vol;
    const irrvol_allocator *a = &v->allocator;
    memset(k, 0, sizeof *k);
    k->stride = count;
    k->irradiance = (float *)irrvol__alloc_array(a, (size_t)count * v->bins, 3 * sizeof(float));
    if (b->desc->keep_radiance) k->radiance = (float *)irrvol__alloc_array(a, (size_t)count * v->bins, 3 * sizeof(float));
    k->sh = (float *)irrvol__alloc_array(a, count, IRRVOL__SH_FLOATS * sizeof(float));
    k->origins = (float *)irrvol__alloc_array(a, count, 4 * sizeof(float));
    k->visibility = (float *)irrvol__alloc_array(a, (size_t)count * v->map_texels, 4 * sizeof(float));
    k->rays = (uint32_t *)irrvol__alloc_array(a, count, sizeof(uint32_t));
    k->state = (unsigned char *)irrvol__alloc(a, count);
    if (!k->irradiance || (b->desc->keep_radiance && !k->radiance) || !k->sh || !k->origins || !k->visibility ||
        !k->rays || !k->state)
        return IRRVOL_ERROR_OUT_OF_MEMORY;
    return IRRVOL_OK;
}

static void irrvol__sink_free(const irrvol_allocator *a, irrvol__sink *k)
{
    irrvol__free(a, k->irradiance);
    irrvol__free(a, k->radiance);
    irrvol__free(a, k->sh);
    irrvol__free(a, k->origins);
    irrvol__free(a, k->visibility);
    irrvol__free(a, k->rays);
    irrvol__free(a, k->state);
    memset(k, 0, sizeof *k);
}

/* Runs the sample jobs of samples [begin, end) into b->sink, in batches;
   progress (done counts on from *done, out of total) and cancel between
   batches. */
static irrvol_result irrvol__gather(irrvol__build *b, uint32_t begin, uint32_t end, uint64_t *done, uint64_t total)
{
    const irrvol_desc *d = b->desc;
    const irrvol_allocator *a = &b->vol->allocator;
    irrvol__scratch sc;
    uint32_t s, batch;
    b->scratch_stride = irrvol__scratch_layout(NULL, b->vol->bins, b->vol->texels, &sc);
    batch = (uint32_t)(IRRVOL__BATCH_BYTES / b->scratch_stride);
    batch = batch < 1 ? 1 : (batch > 256 ? 256 : batch);
    if (batch > end - begin) batch = end - begin;
    if (batch > b->scratch_jobs) {   /* scratch for one batch of jobs */
        irrvol__free(a, b->scratch);
        b->scratch = (unsigned char *)irrvol__alloc_array(a, batch, b->scratch_stride);
        b->scratch_jobs = b->scratch ? batch : 0;
        if (!b->scratch) return IRRVOL_ERROR_OUT_OF_MEMORY;
    }
    for (s = begin; s < end;) {
        uint32_t n = end - s < batch ? end - s : batch;
        b->batch_begin = s;
        irrvol__run_jobs(d->parallel_for, d->parallel_user, irrvol__sample_job, b, n);
        s += n;
        *done += n;
        if (d->progress && d->progress(d->progress_user, *done, total)) {
            irrvol__log(d->log, d->log_user, "irrvol_build: cancelled by the progress callback");
            return IRRVOL_ERROR_CANCELLED;
        }
    }
    return IRRVOL_OK;
}


/* The compact store (the default; desc.full_precision keeps floats). Each
   bin's rgb is one RGB9E5 word, the shared-exponent format of GPUs
   (EXT_texture_shared_exponent): three 9-bit mantissas m and a 5-bit
   exponent e, each channel m 2^(e - 24). The exponent is the largest
   channel's, whose mantissa then lies in [256, 511]; rounding to the
   nearest mantissa errs by at most half a unit: 2^-9 of the largest
   channel, for every channel (a channel far below the largest keeps that
   absolute error). The words hold the irradiance times 2^-pack_shift, the
   power of two that brings the volume's largest value into [2^14, 2^15):
   the format's exponents reach 2^-40 of it; smaller values, negative ones
   (a radiance callback can give them) and NaN store 0. A third of the
   memory, so random queries miss the caches and the TLB less. */
static int32_t irrvol__pack_shift(const float *x, size_t n)
{
    float m = 0.0f;
    size_t i;
    int e;
    for (i = 0; i < n; i++)
        if (x[i] > m && x[i] <= FLT_MAX) m = x[i];
    if (m == 0.0f) return 0;
    (void)frexpf(m, &e);   /* m = f 2^e, f in [0.5, 1) */
    return e - 15;
}

static void irrvol__set_unpack(irrvol *v, int32_t shift)
{
    int e;
    v->pack_shift = shift;
    for (e = 0; e < 32; e++) v->unpack[e] = ldexpf(1.0f, e - 24 + shift);
    v->unshift[0] = ldexpf(1.0f, shift / 2);
    v->unshift[1] = ldexpf(1.0f, shift - shift / 2);
}

static uint32_t irrvol__rgb9e5(const float rgb[3], int32_t shift)
{
    float c[3], m = 0.0f, unit;
    uint32_t word;
    int i, e;
    for (i = 0; i < 3; i++) {
        float x = ldexpf(rgb[i], -shift);
        c[i] = x > 0.0f ? (x < 65408.0f ? x : 65408.0f) : 0.0f;   /* 65408: the largest word; NaN gives 0 */
        m = c[i] > m ? c[i] : m;
    }
    (void)frexpf(m, &e);                    /* floor(log2 m) = e - 1 */
    e = (e - 1 > -16 ? e - 1 : -16) + 16;   /* the shared exponent: bias 15, plus 1 for 9-bit mantissas */
    unit = ldexpf(1.0f, e - 24);
    if (floorf(m / unit + 0.5f) >= 512.0f) {   /* the largest mantissa rounds up to 2^9 */
        e++;
        unit *= 2.0f;
    }
    word = (uint32_t)e << 27;
    for (i = 0; i < 3; i++) word |= (uint32_t)floorf(c[i] / unit + 0.5f) << (9 * i);
    return word;
}

/* The irradiance of one bin of one sample, from either store. */
static void irrvol__bin_value(const irrvol *v, size_t at, float rgb[3])
{
    if (v->packed) {
        uint32_t word = v->packed[at];
        int c;
        for (c = 0; c < 3; c++) rgb[c] = (float)(word >> (9 * c) & 0x1FFu) * v->unpack[word >> 27];
    } else {
        memcpy(rgb, v->irradiance + 3 * at, 3 * sizeof(float));
    }
}

/* Moves the gathered irradiance into the compact store. */
static irrvol_result irrvol__pack(irrvol *v)
{
    size_t n = (size_t)v->sample_count * v->bins, i;
    v->packed = (uint32_t *)irrvol__alloc_array(&v->allocator, n, sizeof(uint32_t));
    if (!v->packed) return IRRVOL_ERROR_OUT_OF_MEMORY;
    irrvol__set_unpack(v, irrvol__pack_shift(v->irradiance, 3 * n));
    for (i = 0; i < n; i++) v->packed[i] = irrvol__rgb9e5(v->irradiance + 3 * i, v->pack_shift);
    irrvol__free(&v->allocator, v->irradiance);
    v->irradiance = NULL;
    return IRRVOL_OK;
}

/* Every value a sample holds (irradiance and radiance bins, harmonics) as
   sum_i w_i value(from_i) over n samples; to is not among them. */
static void irrvol__blend_values(irrvol *v, uint32_t to, const uint32_t *from, const float *w, uint32_t n)
{
    uint32_t bin, i, j;
    int c;
    for (bin = 0; bin < v->bins; bin++) {
        size_t base = (size_t)bin * v->sample_count;
        for (c = 0; c < 3; c++) {
            float h = 0.0f, l = 0.0f;
            for (i = 0; i < n; i++) {
                h += w[i] * v->irradiance[(base + from[i]) * 3 + (size_t)c];
                if (v->radiance) l += w[i] * v->radiance[(base + from[i]) * 3 + (size_t)c];
            }
            v->irradiance[(base + to) * 3 + (size_t)c] = h;
            if (v->radiance) v->radiance[(base + to) * 3 + (size_t)c] = l;
        }
    }
    for (j = 0; j < IRRVOL__SH_FLOATS; j++) {
        float s = 0.0f;
        for (i = 0; i < n; i++) s += w[i] * v->sh[(size_t)from[i] * IRRVOL__SH_FLOATS + j];
        v->sh[(size_t)to * IRRVOL__SH_FLOATS + j] = s;
    }
}

/* Dilation (Unity's adaptive probe volumes): an invalid sample takes the
   mean of the valid samples it shares a sub-cell with, counted once per
   shared sub-cell; samples no valid one touches wait for the next pass,
   when the ones just filled count as valid. So the plain trilinear query
   and the exported harmonics never blend in what a sample saw inside
   geometry. Leak-safe queries never read an invalid sample's values. */
static irrvol_result irrvol__dilate(irrvol *v)
{
    const irrvol_allocator *a = &v->allocator;
    uint32_t n = v->hanging_begin, s, c;
    unsigned char *filled = (unsigned char *)irrvol__alloc(a, n);
    uint32_t *first = (uint32_t *)irrvol__alloc_array(a, (size_t)n + 1, sizeof(uint32_t));
    uint32_t *from = NULL;
    float *w = NULL;
    irrvol_result r = IRRVOL_OK;
    if (!filled || !first) r = IRRVOL_ERROR_OUT_OF_MEMORY;
    for (s = 0; s < n && r == IRRVOL_OK; s++) filled[s] = v->origins[4 * (size_t)s + 3] != 0.0f;
    while (r == IRRVOL_OK) {
        uint32_t total = 0, step;
        memset(first, 0, ((size_t)n + 1) * sizeof(uint32_t));
        for (step = 0; step < 2; step++) {   /* count the neighbours, then list them */
            for (c = 0; c < v->cell_count; c++) {
                const irrvol__cell *cell = &v->cell[c];
                uint32_t x, y, z, ids[8], i, j;
                for (z = 0; z + 1 < cell->side; z++)
                    for (y = 0; y + 1 < cell->side; y++)
                        for (x = 0; x + 1 < cell->side; x++) {
                            irrvol__table_corners(v, cell, x, y, z, ids);
                            for (i = 0; i < 8; i++) {
                                if (ids[i] >= n || filled[ids[i]]) continue;
                                for (j = 0; j < 8; j++) {
                                    if (ids[j] >= n || !filled[ids[j]]) continue;
                                    if (step == 0) first[ids[i] + 1]++;
                                    else from[first[ids[i]]++] = ids[j];
                                }
                            }
                        }
            }
            if (step == 0) {
                for (s = 0; s < n; s++) first[s + 1] += first[s];
                total = first[n];
                if (total == 0) break;
                irrvol__free(a, from);
                from = (uint32_t *)irrvol__alloc_array(a, total, sizeof(uint32_t));
                if (!from) { r = IRRVOL_ERROR_OUT_OF_MEMORY; break; }
            }
        }
        if (r != IRRVOL_OK || total == 0) break;
        /* first[s] now ends s's list, which starts where s - 1's ends */
        irrvol__free(a, w);
        w = (float *)irrvol__alloc_array(a, total, sizeof(float));
        if (!w) { r = IRRVOL_ERROR_OUT_OF_MEMORY; break; }
        for (s = n; s-- > 0;) {
            uint32_t begin = s ? first[s - 1] : 0, end = first[s], i;
            if (end == begin) continue;
            for (i = begin; i < end; i++) w[i] = 1.0f / (float)(end - begin);
            irrvol__blend_values(v, s, from + begin, w + begin, end - begin);
        }
        for (s = 0; s < n; s++)
            if (!filled[s] && first[s] > (s ? first[s - 1] : 0)) filled[s] = 2;   /* filled in this pass */
        for (s = 0; s < n; s++) filled[s] = filled[s] != 0;
    }
    irrvol__free(a, filled);
    irrvol__free(a, first);
    irrvol__free(a, from);
    irrvol__free(a, w);
    return r;
}

/* Hanging samples take their parents' blend (section 9), after dilation so
   that an invalid parent contributes its dilated values. */
static void irrvol__constrain_hanging(irrvol *v)
{
    uint32_t s;
    for (s = v->hanging_begin; s < v->sample_count; s++) {
        size_t h = (size_t)(s - v->hanging_begin);
        float *o = v->origins + 4 * (size_t)s;
        irrvol__blend_values(v, s, v->parents + 4 * h, v->parent_weights + 4 * h, 4);
        memcpy(o, v->positions + 3 * (size_t)s, 3 * sizeof(float));
        o[3] = 1.0f;
    }
}

/* Moves the light pass's first-level results into the volume's arrays. */
static void irrvol__take_first_level(irrvol *v, const irrvol__sink *t, irrvol__sink *k)
{
    uint32_t n = v->first_level_count, bin;
    for (bin = 0; bin < v->bins; bin++) {
        memcpy(k->irradiance + (size_t)bin * k->stride * 3, t->irradiance + (size_t)bin * n * 3, (size_t)n * 3 * sizeof(float));
        if (k->radiance)
            memcpy(k->radiance + (size_t)bin * k->stride * 3, t->radiance + (size_t)bin * n * 3, (size_t)n * 3 * sizeof(float));
    }
    memcpy(k->sh, t->sh, (size_t)n * IRRVOL__SH_FLOATS * sizeof(float));
    memcpy(k->origins, t->origins, (size_t)n * 4 * sizeof(float));
    memcpy(k->visibility, t->visibility, (size_t)n * v->map_texels * 4 * sizeof(float));
    memcpy(k->rays, t->rays, (size_t)n * sizeof(uint32_t));
    memcpy(k->state, t->state, n);
}

/* The gather passes: with light refinement, the first level alone, then
   the cells whose corners differ get their second level too; then every
   sample that carries data, dilation and the hanging samples. */
static irrvol_result irrvol__gather_all(irrvol__build *b)
{
    const irrvol_desc *d = b->desc;
    irrvol *v = b->vol;
    const irrvol_allocator *a = &v->allocator;
    irrvol__sink first;
    uint64_t done = 0;
    uint32_t s, begin = 0;
    int light = v->subgrid > 2 && !(d->refine_threshold < 0.0f);
    irrvol_result r = IRRVOL_OK;
    memset(&first, 0, sizeof first);
    if (light) {
        v->positions = (float *)irrvol__alloc_array(a, v->first_level_count, 3 * sizeof(float));
        r = v->positions ? irrvol__sink_alloc(b, &first, v->first_level_count) : IRRVOL_ERROR_OUT_OF_MEMORY;
        if (r == IRRVOL_OK) {
            v->sample_count = v->first_level_count;
            irrvol__sample_positions(v, NULL);
            b->sink = first;
            r = irrvol__gather(b, 0, v->first_level_count, &done, v->first_level_count);
            memset(&b->sink, 0, sizeof b->sink);   /* first owns those arrays */
        }
        if (r == IRRVOL_OK) {
            float *bend = (float *)irrvol__alloc_array(a, v->first_level_count, sizeof(float));
            if (bend) irrvol__mark_light(v, first.irradiance, first.origins, irrvol__def(d->refine_threshold, IRRVOL__REFINE_THRESHOLD),
                                         v->refined, bend);
            else r = IRRVOL_ERROR_OUT_OF_MEMORY;
            irrvol__free(a, bend);
        }
        irrvol__free(a, v->positions);
        v->positions = NULL;
        begin = v->first_level_count;
    }
    if (r == IRRVOL_OK) r = irrvol__make_grid(v, v->refined);
    if (r == IRRVOL_OK) r = irrvol__alloc_samples(v, d->keep_radiance, 0);
    if (r == IRRVOL_OK) {
        b->sink.irradiance = v->irradiance;
        b->sink.radiance = v->radiance;
        b->sink.sh = v->sh;
        b->sink.origins = v->origins;
        b->sink.visibility = v->visibility;
        b->sink.stride = v->sample_count;
        b->sink.rays = (uint32_t *)irrvol__alloc_array(a, v->hanging_begin, sizeof(uint32_t));
        b->sink.state = (unsigned char *)irrvol__alloc(a, v->hanging_begin);
        if (!b->sink.rays || !b->sink.state) r = IRRVOL_ERROR_OUT_OF_MEMORY;
    }
    if (r == IRRVOL_OK) {
        if (light) irrvol__take_first_level(v, &first, &b->sink);
        r = irrvol__gather(b, begin, v->hanging_begin, &done, v->hanging_begin);
    }
    if (r == IRRVOL_OK) {
        for (s = 0; s < v->hanging_begin; s++) {
            v->rays += b->sink.rays[s];
            v->invalid_count += b->sink.state[s] == IRRVOL_SAMPLE_INVALID;
            v->relocated_count += b->sink.state[s] == IRRVOL_SAMPLE_RELOCATED;
        }
        r = irrvol__dilate(v);
    }
    if (r == IRRVOL_OK) irrvol__constrain_hanging(v);
    if (r == IRRVOL_OK && !d->full_precision) r = irrvol__pack(v);
    irrvol__sink_free(a, &first);
    irrvol__free(a, b->sink.rays);
    irrvol__free(a, b->sink.state);
    return r;
}

IRRVOL_API irrvol_result irrvol_build(const irrvol_desc *desc, irrvol **out)
{
    irrvol__build b;
    irrvol *v;
    irrvol_result r;
    float bias;
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
    b.can_trace = desc->triangle_count > 0;
    b.supersamples = irrvol__def(desc->supersamples, 1u);
    b.weight_subdivisions = irrvol__def(desc->weight_subdivisions, 4u);
    b.max_depth = irrvol__def(desc->max_depth, 6u);
    b.min_weight = desc->min_weight > 0.0f ? desc->min_weight : 0.01f;
    for (b.important_side = 1; b.important_side * b.important_side < irrvol__def(desc->important_rays, 64u);)
        b.important_side++;
    v = b.vol = irrvol__create(&desc->allocator);
    if (!v) return IRRVOL_ERROR_OUT_OF_MEMORY;
    irrvol__set_resolutions(v, irrvol__def(desc->resolution, 17u),
                            irrvol__def(desc->visibility_resolution, IRRVOL__VISIBILITY_RESOLUTION));
    v->moment = irrvol__def(desc->moment, 1u);
    v->filter = desc->filter == IRRVOL_FILTER_DEFAULT ? IRRVOL_FILTER_BILINEAR : desc->filter;
    v->weighting = desc->weighting == IRRVOL_WEIGHTING_DEFAULT ? IRRVOL_WEIGHTING_VISIBILITY : desc->weighting;
    if (desc->triangle_count) v->degenerate = irrvol__count_degenerate(&b.mesh);
    r = irrvol__setup_grid(&b);
    if (r == IRRVOL_OK && desc->triangle_count && !desc->trace && irrvol__bvh_build(&b.bvh, &b.mesh, &v->allocator) != 0)
        r = IRRVOL_ERROR_OUT_OF_MEMORY;
    if (r == IRRVOL_OK) r = irrvol__setup_directions(&b);
    if (r == IRRVOL_OK) r = irrvol__gather_all(&b);
    if (r == IRRVOL_OK) r = irrvol__make_probes(v);
    irrvol__bvh_free(&b.bvh, &v->allocator);
    irrvol__free(&v->allocator, b.dirs);
    irrvol__free(&v->allocator, b.dir_soa);
    irrvol__free(&v->allocator, b.weights);
    irrvol__free(&v->allocator, b.sh_weights);
    irrvol__free(&v->allocator, b.vis_weights);
    irrvol__free(&v->allocator, b.vis_inverse);
    irrvol__free(&v->allocator, b.important);
    irrvol__free(&v->allocator, b.important_indices);
    irrvol__bvh_free(&b.important_bvh, &v->allocator);
    irrvol__free(&v->allocator, b.scratch);
    if (r == IRRVOL_ERROR_OUT_OF_MEMORY) irrvol__log(desc->log, desc->log_user, "irrvol_build: out of memory");
    if (r != IRRVOL_OK) { irrvol_destroy(v); return r; }
    bias = desc->normal_bias < 0.0f ? 0.0f : irrvol__def(desc->normal_bias, IRRVOL__NORMAL_BIAS);
    v->bias = bias * (float)irrvol__finest_spacing(v);
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
    info->hanging_samples = vol->sample_count - vol->hanging_begin;
    info->invalid_samples = vol->invalid_count;
    info->relocated_samples = vol->relocated_count;
    for (k = 0; k < 3; k++) {
        info->grid_samples[k] = vol->samples[k];
        info->bounds_min[k] = vol->lo[k];
        info->bounds_max[k] = vol->hi[k];
    }
    info->subgrid_samples = vol->subgrid;
    info->cell_count = vol->cell_count;
    info->refined_cells = vol->refined_count;
    info->light_refined_cells = vol->light_refined_count;
    info->resolution = vol->k;
    info->bins = vol->bins;
    info->moment = vol->moment;
    info->visibility_resolution = vol->vis_res;
    info->filter = vol->filter;
    info->weighting = vol->weighting;
    info->normal_bias = vol->bias;
    info->rays = vol->rays;
    info->degenerate_triangles = vol->degenerate;
    info->has_radiance = vol->radiance != NULL;
    info->bin_bytes = irrvol__bin_bytes(vol);
    info->bytes = irrvol__bytes(vol);
    return IRRVOL_OK;
}

/* ======================================================================
   13. queries (4.3): eq. 4.4-4.6 at either level, trilinear weights of
   the cell's eight samples, times their visibility (leak-safe), the bin
   of the direction
   ---------------------------------------------------------------------- */
/* Eq. 4.4-4.6: the first-level cell containing pos and the offsets in it.
   Positions outside the bounds (and NaN) clamp to the boundary. */
IRRVOL__HOT void irrvol__cell_coords(const irrvol *v, const float pos[3], uint32_t c[3], float o[3])
{
    int d;
    for (d = 0; d < 3; d++) {
        float q = (pos[d] - v->lo[d]) * v->scale[d];            /* eq. 4.4 */
        q = q > 0.0f ? q : 0.0f;
        q = q < v->cell_limit[d] ? q : v->cell_limit[d];
        c[d] = (uint32_t)q;                                     /* eq. 4.5 */
        c[d] = c[d] < v->cells[d] ? c[d] : v->cells[d] - 1;     /* the upper face */
        o[d] = q - (float)c[d];                                 /* eq. 4.6 */
    }
}

/* The eight samples of cell c around offsets o (the same steps inside the
   cell's own table: its sub-cell at the second level) and their trilinear
   weights; returns the sub-cell's corner record. */
IRRVOL__HOT const irrvol__corners *irrvol__cell_corners(const irrvol *v, const uint32_t c[3], const float o[3],
                                                        uint32_t ids[8], float w[8])
{
    const irrvol__cell *cell = &v->cell[c[0] + v->cells[0] * (c[1] + v->cells[1] * c[2])];
    const irrvol__corners *rec;
    uint32_t side = cell->side, s[3];
    float f = (float)(side - 1), t[3];
    int d;
    for (d = 0; d < 3; d++) {
        float q = o[d] * f;
        s[d] = (uint32_t)q;
        s[d] = s[d] < side - 2 ? s[d] : side - 2;
        t[d] = q - (float)s[d];
    }
    rec = v->corners + cell->corners + s[0] + (side - 1) * (s[1] + (side - 1) * s[2]);
    memcpy(ids, rec->id, sizeof rec->id);
    {
        float x1 = t[0], y1 = t[1], z1 = t[2], x0 = 1.0f - x1, y0 = 1.0f - y1, z0 = 1.0f - z1;
        w[0] = x0 * y0 * z0; w[1] = x1 * y0 * z0;
        w[2] = x0 * y1 * z0; w[3] = x1 * y1 * z0;
        w[4] = x0 * y0 * z1; w[5] = x1 * y0 * z1;
        w[6] = x0 * y1 * z1; w[7] = x1 * y1 * z1;
    }
    return rec;
}

/* Eq. 4.4-4.6 and the sub-cell: the record of the eight samples around
   pos and their trilinear weights. With SSE2 the three axes share a
   register (the same operations, so the same bits): no loop, and the
   integer clamps become float minima of whole numbers. Every refined cell
   has subgrid samples a side, so the sub-cell and its offsets are worked
   out as if the cell were refined while the cell is read (an unrefined
   cell, of side 2, keeps its first-level offsets, which is what its one
   sub-cell would give): no computation waits for the cell but the choice. */
#ifdef IRRVOL__SSE2
IRRVOL__HOT const irrvol__corners *irrvol__locate(const irrvol *v, const float pos[3], uint32_t ids[8], float w[8])
{
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    const irrvol__cell *cell;
    const irrvol__corners *rec;
    __m128 p = _mm_movelh_ps(_mm_unpacklo_ps(_mm_load_ss(pos), _mm_load_ss(pos + 1)), _mm_load_ss(pos + 2));
    __m128 q = _mm_mul_ps(_mm_sub_ps(p, _mm_loadu_ps(v->lo)), _mm_loadu_ps(v->scale));   /* eq. 4.4 */
    __m128 c, o, s, t, u, xs, ys, xy, z0, z1, sum, refined;
    __m128i ci;
    uint32_t sub;
    q = _mm_min_ps(_mm_max_ps(q, zero), _mm_loadu_ps(v->cell_limit));   /* NaN gives 0 */
    c = _mm_min_ps(_mm_cvtepi32_ps(_mm_cvttps_epi32(q)), _mm_loadu_ps(v->last_cell));   /* eq. 4.5 */
    o = _mm_sub_ps(q, c);                                                                /* eq. 4.6 */
    ci = _mm_cvttps_epi32(c);
    cell = &v->cell[(uint32_t)_mm_cvtsi128_si32(ci) +
                    v->cells[0] * ((uint32_t)_mm_cvtsi128_si32(_mm_shuffle_epi32(ci, 0x55)) +
                                   v->cells[1] * (uint32_t)_mm_cvtsi128_si32(_mm_shuffle_epi32(ci, 0xAA)))];
    q = _mm_mul_ps(o, _mm_loadu_ps(v->sub_cells));
    s = _mm_min_ps(_mm_cvtepi32_ps(_mm_cvttps_epi32(q)), _mm_loadu_ps(v->sub_last));
    sum = _mm_mul_ps(s, _mm_loadu_ps(v->sub_stride));   /* whole numbers below 2^15: exact */
    sum = _mm_add_ps(sum, _mm_movehl_ps(sum, sum));
    sub = (uint32_t)_mm_cvtsi128_si32(_mm_cvttps_epi32(_mm_add_ss(sum, _mm_shuffle_ps(sum, sum, 1))));
    refined = _mm_castsi128_ps(_mm_set1_epi32(cell->side > 2 ? -1 : 0));
    t = irrvol__select(refined, _mm_sub_ps(q, s), o);
    rec = v->corners + cell->corners + (cell->side > 2 ? sub : 0u);
    u = _mm_unpacklo_ps(_mm_sub_ps(one, t), t);      /* x0 x1 y0 y1 */
    xs = _mm_shuffle_ps(u, u, _MM_SHUFFLE(1, 0, 1, 0));
    ys = _mm_shuffle_ps(u, u, _MM_SHUFFLE(3, 3, 2, 2));
    xy = _mm_mul_ps(xs, ys);
    z1 = _mm_shuffle_ps(t, t, _MM_SHUFFLE(2, 2, 2, 2));
    z0 = _mm_sub_ps(one, z1);
    _mm_storeu_ps(w, _mm_mul_ps(xy, z0));
    _mm_storeu_ps(w + 4, _mm_mul_ps(xy, z1));
    memcpy(ids, rec->id, sizeof rec->id);
    return rec;
}
#else
IRRVOL__HOT const irrvol__corners *irrvol__locate(const irrvol *v, const float pos[3], uint32_t ids[8], float w[8])
{
    uint32_t c[3];
    float o[3];
    irrvol__cell_coords(v, pos, c, o);
    return irrvol__cell_corners(v, c, o, ids, w);
}
#endif

/* The bin that contains the square point (u, v) of hemisphere h. */
IRRVOL__HOT uint32_t irrvol__square_bin(const irrvol *v, float u, float w, uint32_t h)
{
    uint32_t i = (uint32_t)(u * v->kf), j = (uint32_t)(w * v->kf);
    i = i < v->k ? i : v->k - 1;
    j = j < v->k ? j : v->k - 1;
    return (h * v->k + j) * v->k + i;
}

/* The four bins around the square point (u, t) of hemisphere h and their
   bilinear weights (6.1.2). Past the outer bin centres the neighbour is the
   bin with the same (i, j) in the other hemisphere: both squares share their
   boundary, the equator. */
#ifdef IRRVOL__SSE2
/* With SSE2 the four bins' lanes in one register: the same operations, the
   integer ones on whole numbers held exactly as floats (bins < 2^24). */
IRRVOL__HOT void irrvol__bilinear_bins(const irrvol *v, float u, float t, uint32_t h, uint32_t bins[4], float w[4])
{
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps(), kf = _mm_set1_ps(v->kf);
    __m128 f = _mm_sub_ps(_mm_mul_ps(_mm_unpacklo_ps(_mm_set_ss(u), _mm_set_ss(t)), kf), _mm_set1_ps(0.5f));  /* fu fv */
    __m128 fl = _mm_sub_ps(_mm_cvtepi32_ps(_mm_cvttps_epi32(_mm_add_ps(f, one))), one);   /* iu iv: floor for f > -1 */
    __m128 tt = _mm_sub_ps(f, fl), next = _mm_add_ps(fl, one), last = _mm_sub_ps(kf, one);
    __m128 ij = _mm_unpacklo_ps(_mm_max_ps(fl, zero), _mm_min_ps(next, last));          /* i0 i1 j0 j1 */
    __m128 out = _mm_unpacklo_ps(_mm_cmplt_ps(fl, zero), _mm_cmpgt_ps(next, last));      /* ou0 ou1 ov0 ov1 */
    __m128 tw = _mm_unpacklo_ps(_mm_sub_ps(one, tt), tt);                                 /* 1-tu tu 1-tv tv */
    __m128 flip = _mm_or_ps(_mm_shuffle_ps(out, out, _MM_SHUFFLE(1, 0, 1, 0)), _mm_shuffle_ps(out, out, _MM_SHUFFLE(3, 3, 2, 2)));
    __m128 hf = _mm_set1_ps((float)h), hh = irrvol__select(flip, _mm_sub_ps(one, hf), hf);   /* h ^ outside */
    __m128 b = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(hh, kf), _mm_shuffle_ps(ij, ij, _MM_SHUFFLE(3, 3, 2, 2))), kf),
                          _mm_shuffle_ps(ij, ij, _MM_SHUFFLE(1, 0, 1, 0)));
    _mm_storeu_si128((__m128i *)(void *)bins, _mm_cvttps_epi32(b));
    _mm_storeu_ps(w, _mm_mul_ps(_mm_shuffle_ps(tw, tw, _MM_SHUFFLE(1, 0, 1, 0)), _mm_shuffle_ps(tw, tw, _MM_SHUFFLE(3, 3, 2, 2))));
}
#else
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
#endif

/* The visibility weight of sample s for the test point x of a surface
   with unit normal n, after DDGI (Majercik et al. 2019):
   - backface: (dot(to the sample, n) + 1) / 2 + 0.2, samples behind the
     surface count less (DDGI squares the first term; unsquared it bends
     the trilinear weights less where no surface is: on the office, the
     relative L1 error of random queries is 4.9 % against 5.9 %);
   - Chebyshev: the sample's fit of the inverse hit distance around the
     direction w toward x (section 13, bilinear between the four nearest
     texels of its bordered octahedral map) predicts the surface there at
     1 / (g . w), exactly for a plane; a point beyond it, 1/r < g . w, is
     visible with probability at most var / (var + (g . w - 1/r)^2), cubed:
     a sample behind a wall, however thin and however oblique, all but
     drops out;
   - weights under 0.2 fade as w^3 / 0.04, invalid samples weigh 0.
   This scalar code defines the weight; the irrvol__lanes4 steps compute
   four with SSE2 in the same operations and order, and the GLSL follows it. */
IRRVOL__HOT float irrvol__visibility_weight(const irrvol *v, uint32_t s, const float x[3], const float n[3])
{
    const float *o = v->probes + 4 * (size_t)s, *m, *t00, *t01;
    float ok = o[3] >= 0.0f ? 1.0f : 0.0f;
    float dx = x[0] - o[0], dy = x[1] - o[1], dz = x[2] - o[2], fn = (float)v->vis_res;
    float r2 = dx * dx + dy * dy + dz * dz, r, inv_r, w, a, inv_a, px, py, u, t, fu, ft, g[4], gd, beyond;
    int i0, j0, c;
    if (!(r2 > 0.0f)) return ok;
    r = sqrtf(r2);
    inv_r = 1.0f / r;
    w = 0.5f - 0.5f * ((dx * n[0] + dy * n[1] + dz * n[2]) * inv_r);
    w = w + 0.2f;
    if (r2 <= o[3] || !ok) {   /* within reach (irrvol__make_probes), or invalid: no texels */
        if (w < 0.2f) w = w * (w * w * 25.0f);
        return w * ok;
    }
    /* the octahedral map: direction -> [0.5, n + 0.5] in the bordered map */
    a = fabsf(dx) + fabsf(dy) + fabsf(dz);
    inv_a = 1.0f / a;
    px = dx * inv_a;
    py = dy * inv_a;
    if (dz < 0.0f) {
        float qx = (1.0f - fabsf(py)) * (px < 0.0f ? -1.0f : 1.0f);
        py = (1.0f - fabsf(px)) * (py < 0.0f ? -1.0f : 1.0f);
        px = qx;
    }
    u = irrvol__minf(irrvol__maxf((px * 0.5f + 0.5f) * fn + 0.5f, 0.5f), fn + 0.5f);
    t = irrvol__minf(irrvol__maxf((py * 0.5f + 0.5f) * fn + 0.5f, 0.5f), fn + 0.5f);
    i0 = (int)u;
    j0 = (int)t;
    fu = u - (float)i0;
    ft = t - (float)j0;
    m = v->visibility + ((size_t)s * v->map_texels + (size_t)j0 * (v->vis_res + 2) + (size_t)i0) * 4;
    t00 = m;
    t01 = m + 4 * (v->vis_res + 2);
    for (c = 0; c < 4; c++)
        g[c] = (t00[c] * (1.0f - fu) + t00[4 + c] * fu) * (1.0f - ft) + (t01[c] * (1.0f - fu) + t01[4 + c] * fu) * ft;
    gd = g[0] * dx + g[1] * dy + g[2] * dz;
    beyond = (gd - 1.0f) * inv_r;   /* g . w - 1/r */
    if (beyond > 0.0f) {
        float den = g[3] + beyond * beyond, cheb = den > 0.0f ? g[3] / den : 1.0f;
        w = w * (cheb * cheb * cheb);
    }
    if (w < 0.2f) w = w * (w * w * 25.0f);
    return w * ok;
}

#define IRRVOL__MAX_TERMS 32   /* a query's samples: 8 corners, each a hanging sample of up to 4 parents */

#ifdef IRRVOL__SSE2
/* The test point and normal of the irrvol__lanes4 steps, each coordinate in
   all four lanes. */
typedef struct irrvol__point4 { __m128 x, y, z, nx, ny, nz; } irrvol__point4;

IRRVOL__HOT irrvol__point4 irrvol__point4_set(const float x[3], const float n[3])
{
    irrvol__point4 p;
    p.x = _mm_set1_ps(x[0]); p.y = _mm_set1_ps(x[1]); p.z = _mm_set1_ps(x[2]);
    p.nx = _mm_set1_ps(n[0]); p.ny = _mm_set1_ps(n[1]); p.nz = _mm_set1_ps(n[2]);
    return p;
}

/* Four lanes of irrvol__visibility_weight between its three steps. */
typedef struct irrvol__lanes4 {
    __m128 dx, dy, dz, inv_r, w, pos, ok;   /* toward x, 1 / r, the backface term, r > 0, valid */
    int near;                               /* bit k: lane k within its sample's reach, or invalid: no texels */
    const float *texel[4];                  /* each lane's 2 x 2 texels: the top left one */
    __m128 fu, ft;                          /* and the bilinear weights, by lane */
    __m128 fit[4];                          /* each lane's blended fit: gx, gy, gz, var */
} irrvol__lanes4;

/* Step 1 for lanes that read their maps: the octahedral point of the
   direction toward x, the texels around it and the bilinear weights. */
IRRVOL__HOT void irrvol__lanes4_texels(const irrvol *v, const uint32_t s[4], irrvol__lanes4 *l)
{
    const __m128 one = _mm_set1_ps(1.0f), half = _mm_set1_ps(0.5f), zero = _mm_setzero_ps();
    const __m128 sign = _mm_set1_ps(-0.0f), fn = _mm_set1_ps((float)v->vis_res);
    __m128 inv_a, px, py, neg, qx, qy, u, t, fi, fj;
    __m128i i0, j0;
    int at[4], k;
    inv_a = _mm_div_ps(one, _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, l->dx), _mm_andnot_ps(sign, l->dy)),
                                       _mm_andnot_ps(sign, l->dz)));
    px = _mm_mul_ps(l->dx, inv_a);
    py = _mm_mul_ps(l->dy, inv_a);
    neg = _mm_cmplt_ps(l->dz, zero);
    qx = _mm_mul_ps(_mm_sub_ps(one, _mm_andnot_ps(sign, py)), irrvol__select(_mm_cmplt_ps(px, zero), _mm_set1_ps(-1.0f), one));
    qy = _mm_mul_ps(_mm_sub_ps(one, _mm_andnot_ps(sign, px)), irrvol__select(_mm_cmplt_ps(py, zero), _mm_set1_ps(-1.0f), one));
    px = irrvol__select(neg, qx, px);
    py = irrvol__select(neg, qy, py);
    u = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(px, half), half), fn), half);
    t = _mm_add_ps(_mm_mul_ps(_mm_add_ps(_mm_mul_ps(py, half), half), fn), half);
    u = _mm_min_ps(_mm_max_ps(u, half), _mm_add_ps(fn, half));   /* as irrvol__minf / maxf: NaN gives the bound */
    t = _mm_min_ps(_mm_max_ps(t, half), _mm_add_ps(fn, half));
    i0 = _mm_cvttps_epi32(u);
    j0 = _mm_cvttps_epi32(t);
    fi = _mm_cvtepi32_ps(i0);
    fj = _mm_cvtepi32_ps(j0);
    l->fu = _mm_sub_ps(u, fi);
    l->ft = _mm_sub_ps(t, fj);
    /* the texel in its map, j0 (n + 2) + i0: whole numbers below 2^13, exact as floats */
    _mm_storeu_si128((__m128i *)(void *)at, _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(fj, _mm_add_ps(fn, _mm_set1_ps(2.0f))), fi)));
    for (k = 0; k < 4; k++) {   /* a select, not a branch: which lanes are near is random */
        size_t texel = ((size_t)s[k] * v->map_texels + (size_t)at[k]) * 4;
        l->texel[k] = v->visibility + (l->near >> k & 1 ? 0 : texel);
    }
}

/* Step 1: directions, the backface term and the texels of four samples
   s, their probes (ox, oy, oz, reach2) by lane; bit k of clear: lane k
   skips its map (irrvol__make_clear). When every lane is near (within
   reach, invalid or clear), no texel is located. */
IRRVOL__HOT void irrvol__lanes4_locate(const irrvol *v, const uint32_t s[4], __m128 ox, __m128 oy, __m128 oz,
                                       __m128 reach2, unsigned clear, const irrvol__point4 *p, irrvol__lanes4 *l)
{
    const __m128 one = _mm_set1_ps(1.0f), half = _mm_set1_ps(0.5f), zero = _mm_setzero_ps();
    __m128 r2, w;
    l->ok = _mm_and_ps(_mm_cmpge_ps(reach2, zero), one);
    l->dx = _mm_sub_ps(p->x, ox);
    l->dy = _mm_sub_ps(p->y, oy);
    l->dz = _mm_sub_ps(p->z, oz);
    r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(l->dx, l->dx), _mm_mul_ps(l->dy, l->dy)), _mm_mul_ps(l->dz, l->dz));
    l->pos = _mm_cmpgt_ps(r2, zero);
    l->near = _mm_movemask_ps(_mm_or_ps(_mm_cmple_ps(r2, reach2), _mm_cmplt_ps(reach2, zero))) | (int)clear;   /* or invalid */
    l->inv_r = _mm_div_ps(one, _mm_sqrt_ps(r2));
    w = _mm_add_ps(_mm_add_ps(_mm_mul_ps(l->dx, p->nx), _mm_mul_ps(l->dy, p->ny)), _mm_mul_ps(l->dz, p->nz));
    w = _mm_sub_ps(half, _mm_mul_ps(half, _mm_mul_ps(w, l->inv_r)));
    l->w = _mm_add_ps(w, _mm_set1_ps(0.2f));
    l->fu = l->ft = zero;
    if (l->near != 15) irrvol__lanes4_texels(v, s, l);   /* a lane reads its map: where */
}

/* Step 1 for any four samples: their probes gathered by lane. */
IRRVOL__HOT void irrvol__lanes4_locate_samples(const irrvol *v, const uint32_t s[4], const irrvol__point4 *p,
                                               irrvol__lanes4 *l)
{
    __m128 ox = _mm_loadu_ps(v->probes + 4 * (size_t)s[0]), oy = _mm_loadu_ps(v->probes + 4 * (size_t)s[1]);
    __m128 oz = _mm_loadu_ps(v->probes + 4 * (size_t)s[2]), reach2 = _mm_loadu_ps(v->probes + 4 * (size_t)s[3]);
    _MM_TRANSPOSE4_PS(ox, oy, oz, reach2);
    irrvol__lanes4_locate(v, s, ox, oy, oz, reach2, 0, p, l);
}

/* The bilinear blend of the 2 x 2 texels from m (rows row texels apart)
   with weights su, sv (in every lane). */
IRRVOL__HOT __m128 irrvol__texels_blend(const float *m, uint32_t row, __m128 su, __m128 sv)
{
    const __m128 one = _mm_set1_ps(1.0f), cu = _mm_sub_ps(one, su), cv = _mm_sub_ps(one, sv);
    const float *m1 = m + 4 * (size_t)row;
    __m128 r0 = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(m), cu), _mm_mul_ps(_mm_loadu_ps(m + 4), su));
    __m128 r1 = _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(m1), cu), _mm_mul_ps(_mm_loadu_ps(m1 + 4), su));
    return _mm_add_ps(_mm_mul_ps(r0, cv), _mm_mul_ps(r1, sv));
}

/* Step 2: each lane's four texels, blended; a lane within reach takes a
   zero fit, which predicts no surface: g . (x - o) - 1 < 0, as its texels
   would give. */
IRRVOL__HOT void irrvol__lanes4_fetch(const irrvol *v, irrvol__lanes4 *l)
{
    const uint32_t row = v->vis_res + 2;
    const __m128 zero = _mm_setzero_ps();
    __m128 fu = l->fu, ft = l->ft;   /* each lane's weights broadcast from the register: no store and reload */
    l->fit[0] = l->near & 1 ? zero : irrvol__texels_blend(l->texel[0], row, _mm_shuffle_ps(fu, fu, 0x00), _mm_shuffle_ps(ft, ft, 0x00));
    l->fit[1] = l->near & 2 ? zero : irrvol__texels_blend(l->texel[1], row, _mm_shuffle_ps(fu, fu, 0x55), _mm_shuffle_ps(ft, ft, 0x55));
    l->fit[2] = l->near & 4 ? zero : irrvol__texels_blend(l->texel[2], row, _mm_shuffle_ps(fu, fu, 0xAA), _mm_shuffle_ps(ft, ft, 0xAA));
    l->fit[3] = l->near & 8 ? zero : irrvol__texels_blend(l->texel[3], row, _mm_shuffle_ps(fu, fu, 0xFF), _mm_shuffle_ps(ft, ft, 0xFF));
}

/* Step 3: the Chebyshev bound, the fade, validity. */
IRRVOL__HOT void irrvol__lanes4_weigh(irrvol__lanes4 *l, float out[4])
{
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps();
    __m128 w = l->w;
    if (l->near != 15) {   /* every lane near: zero fits, g . (x - o) - 1 < 0, no bound acts */
        __m128 g0 = l->fit[0], g1 = l->fit[1], g2 = l->fit[2], g3 = l->fit[3], beyond, den, cheb;
        _MM_TRANSPOSE4_PS(g0, g1, g2, g3);
        beyond = _mm_add_ps(_mm_add_ps(_mm_mul_ps(g0, l->dx), _mm_mul_ps(g1, l->dy)), _mm_mul_ps(g2, l->dz));
        beyond = _mm_mul_ps(_mm_sub_ps(beyond, one), l->inv_r);
        den = _mm_add_ps(g3, _mm_mul_ps(beyond, beyond));
        cheb = irrvol__select(_mm_cmpgt_ps(den, zero), _mm_div_ps(g3, den), one);
        cheb = _mm_mul_ps(_mm_mul_ps(cheb, cheb), cheb);
        w = irrvol__select(_mm_cmpgt_ps(beyond, zero), _mm_mul_ps(w, cheb), w);
    }
    w = irrvol__select(_mm_cmplt_ps(w, _mm_set1_ps(0.2f)), _mm_mul_ps(w, _mm_mul_ps(_mm_mul_ps(w, w), _mm_set1_ps(25.0f))), w);
    w = irrvol__select(l->pos, _mm_mul_ps(w, l->ok), l->ok);
    _mm_storeu_ps(out, w);
}

#endif

/* The visibility weights of count samples into out. With SSE2, four at a
   time, each step for every group before the next step: the groups' long
   chains of divisions and loads overlap. */
IRRVOL__HOT void irrvol__visibility_weights(const irrvol *v, const uint32_t *s, uint32_t count, const float x[3],
                                            const float n[3], float *out)
{
    uint32_t i = 0;
#ifdef IRRVOL__SSE2
    irrvol__lanes4 l[IRRVOL__MAX_TERMS / 4];
    irrvol__point4 p = irrvol__point4_set(x, n);
    uint32_t groups = count / 4, g;
    for (g = 0; g < groups; g++) irrvol__lanes4_locate_samples(v, s + 4 * g, &p, &l[g]);
    for (g = 0; g < groups; g++) irrvol__lanes4_fetch(v, &l[g]);
    for (g = 0; g < groups; g++) irrvol__lanes4_weigh(&l[g], out + 4 * g);
    i = 4 * groups;
#endif
    for (; i < count; i++) out[i] = irrvol__visibility_weight(v, s[i], x, n);
}

/* Asks the caches for the values of samples ids in bins (the words, or
   the floats, that the sums read), so that they arrive while other work
   runs: a leak-safe query's visibility weights, the next queries of
   irrvol_query_many. id_count is a multiple of 4 (a record's eight
   samples, or a padded term list): each bin's row of the store is found
   once and its ids asked for four at a time, a few instructions each
   where a loop per value cost about nine. */
IRRVOL__HOT void irrvol__prefetch_values(const irrvol *v, const uint32_t *bins, uint32_t bin_count, const uint32_t *ids,
                                         uint32_t id_count)
{
    const size_t size = v->packed ? sizeof *v->packed : 3 * sizeof *v->irradiance;
    const char *store = v->packed ? (const char *)v->packed : (const char *)v->irradiance;
    uint32_t j, k;
    for (k = 0; k < bin_count; k++) {
        const char *row = store + (size_t)bins[k] * v->sample_count * size;
        for (j = 0; j < id_count; j += 4) {
            IRRVOL__PREFETCH(row + ids[j] * size);
            IRRVOL__PREFETCH(row + ids[j + 1] * size);
            IRRVOL__PREFETCH(row + ids[j + 2] * size);
            IRRVOL__PREFETCH(row + ids[j + 3] * size);
        }
    }
}

/* The visibility weights of a record's eight samples (its corners, or a
   merged record's samples): irrvol__visibility_weights of its ids, the
   probes read from its record; bit k of clear: sample k skips its map (the
   record's clear mask, when the query point is in its sub-cell). The
   samples' values in bins (bin_count of them, 0: none) are asked for
   first, before the texels: their misses and the texels' overlap. */
IRRVOL__HOT void irrvol__corner_weights(const irrvol *v, const irrvol__corners *r, unsigned clear, const float x[3],
                                        const float n[3], const uint32_t *bins, uint32_t bin_count, float out[8])
{
#ifdef IRRVOL__SSE2
    irrvol__lanes4 l[2];
    irrvol__point4 p = irrvol__point4_set(x, n);
    int g;
    irrvol__prefetch_values(v, bins, bin_count, r->id, 8);
    for (g = 0; g < 2; g++)
        irrvol__lanes4_locate(v, r->id + 4 * g, _mm_load_ps(r->x + 4 * g), _mm_load_ps(r->y + 4 * g),
                              _mm_load_ps(r->z + 4 * g), _mm_load_ps(r->reach2 + 4 * g), clear >> 4 * g & 15u, &p, &l[g]);
    for (g = 0; g < 2; g++) irrvol__lanes4_fetch(v, &l[g]);
    for (g = 0; g < 2; g++) irrvol__lanes4_weigh(&l[g], out + 4 * g);
#else
    (void)clear;   /* the scalar code reads the map: the same weights */
    irrvol__prefetch_values(v, bins, bin_count, r->id, 8);
    irrvol__visibility_weights(v, r->id, 8, x, n, out);
#endif
}

/* A query reduced to the samples it reads, their weights and the bins:
   the one piece of code behind every query. */
typedef struct irrvol__prepared {
    uint32_t id[IRRVOL__MAX_TERMS];
    float w[IRRVOL__MAX_TERMS];
    uint32_t count;    /* a multiple of 4: terms past the corners' own have weight 0 */
    uint32_t bin[4];
    float bw[4];
    uint32_t bins;     /* 1 (NEAREST) or 4 (BILINEAR) */
    float scale;       /* 1 / the sum of the weights */
} irrvol__prepared;

/* A sub-cell with hanging corners (section 9): each hanging corner's
   term becomes its parents' terms, the corner's weight times theirs, so
   both sides of a face between the levels read the same first-level
   samples (the stored blend of a hanging sample is rounded on its own in
   the compact store), and the leak-safe weights weigh each parent by its
   own visibility. The record's terms (irrvol__make_terms) list them: a
   load and a product each, padded with weight 0 to whole groups of four
   (irrvol__finish_packed). */
IRRVOL__HOT void irrvol__expand_hanging(const irrvol *v, const irrvol__corners *rec, irrvol__prepared *q)
{
    const irrvol__term *t = v->terms + rec->first;
    uint32_t i;
    float w[8];
    memcpy(w, q->w, sizeof w);
    for (i = 0; i < rec->hanging; i++) {
        q->id[i] = t[i].id;
        q->w[i] = w[t[i].corner] * t[i].weight;
    }
    q->count = rec->hanging;
}

/* A merged record's terms (irrvol__merge_terms) summed per sample: each of
   its eight samples (q->id, from the record) takes the sum of its terms'
   weights, the corner's trilinear weight times the term's, in term order.
   The same weights as the terms' (a sample's visibility is the same for
   each of its terms), up to float rounding. */
IRRVOL__HOT void irrvol__merge_hanging(const irrvol *v, const irrvol__corners *rec, irrvol__prepared *q)
{
    const irrvol__term *t = v->terms + rec->first;
    float w[8], sum[8] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    uint32_t i;
    memcpy(w, q->w, sizeof w);
    for (i = 0; i < rec->hanging; i++) sum[t[i].slot] += w[t[i].corner] * t[i].weight;
    memcpy(q->w, sum, sizeof sum);
}

/* Leak-safe weights: each term's trilinear weight times its sample's
   visibility for the test point pos + bias * n, renormalised. When no
   sample is visible (every corner invalid) or an input is NaN, the plain
   trilinear weights stand. */
IRRVOL__HOT void irrvol__visibility_terms(const irrvol *v, const irrvol__corners *rec, const float pos[3],
                                          const float normal[3], int prefetch, irrvol__prepared *q)
{
    float n[3], x[3], len2 = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2], inv, sum = 0.0f;
    float vis[IRRVOL__MAX_TERMS], w[IRRVOL__MAX_TERMS];
    uint32_t i, j;
    inv = len2 > 0.0f ? 1.0f / sqrtf(len2) : 0.0f;
    for (j = 0; j < 3; j++) {
        n[j] = normal[j] * inv;
        x[j] = pos[j] + v->bias * n[j];
    }
    if (!irrvol__finite3(x) || !irrvol__finite3(n)) return;   /* NaN or infinite: the plain weights stand */
    if (!rec->hanging || rec->merged) {   /* eight samples, probes from the record */
        int inside = pos[0] >= v->lo[0] && pos[0] <= v->hi[0] && pos[1] >= v->lo[1] && pos[1] <= v->hi[1] &&
                     pos[2] >= v->lo[2] && pos[2] <= v->hi[2];   /* then pos is in rec's sub-cell */
        irrvol__corner_weights(v, rec, inside ? rec->clear : 0u, x, n, q->bin, prefetch ? q->bins : 0u, vis);
    }
    else {
        irrvol__prefetch_values(v, q->bin, prefetch ? q->bins : 0u, q->id, q->count);
        irrvol__visibility_weights(v, q->id, q->count, x, n, vis);
    }
    for (i = 0; i < q->count; i += 4) {   /* a multiple of 4: products four at a time, the sum in term order */
        for (j = 0; j < 4; j++) w[i + j] = q->w[i + j] * vis[i + j];
        sum = (((sum + w[i]) + w[i + 1]) + w[i + 2]) + w[i + 3];
    }
    if (sum >= FLT_MIN && sum <= FLT_MAX) {   /* 1 / sum is finite */
        for (i = 0; i < q->count; i += 4) memcpy(q->w + i, w + i, 4 * sizeof(float));
        q->scale = 1.0f / sum;
    }
}

/* The terms of a query at pos from the plain trilinear terms of its
   sub-cell rec in q; normal is the surface normal the visibility weights
   use. prefetch: q's bins are set; the values the sums will read are
   prefetched before the visibility weights are computed, so the weights'
   arithmetic and their texels' misses hide the values' misses: random
   leak-safe queries on the office ran 1.09-1.12x as fast as without (v0.5.4,
   which asked after the texels), and 1.08x faster again asking before them
   (v0.5.5); the weights change how the values are summed, never which are
   read. */
IRRVOL__HOT void irrvol__prepare_terms(const irrvol *v, const irrvol__corners *rec, irrvol_weighting weighting,
                                       const float pos[3], const float normal[3], int prefetch, irrvol__prepared *q)
{
    q->count = 8;
    q->scale = 1.0f;
    if (weighting == IRRVOL_WEIGHTING_DEFAULT) weighting = v->weighting;
    if (weighting != IRRVOL_WEIGHTING_VISIBILITY) {
        if (rec->hanging) irrvol__expand_hanging(v, rec, q);
        return;
    }
    if (rec->merged) irrvol__merge_hanging(v, rec, q);
    else if (rec->hanging) irrvol__expand_hanging(v, rec, q);
    irrvol__visibility_terms(v, rec, pos, normal, prefetch, q);
}

/* The terms of a query at pos. */
IRRVOL__HOT void irrvol__prepare_at(const irrvol *v, irrvol_weighting weighting, const float pos[3],
                                    const float normal[3], irrvol__prepared *q)
{
    irrvol__prepare_terms(v, irrvol__locate(v, pos, q->id, q->w), weighting, pos, normal, 0, q);
}

/* The terms of a query in cell c at offsets o (pos: the same point). */
IRRVOL__HOT void irrvol__prepare_in_cell(const irrvol *v, irrvol_weighting weighting, const uint32_t c[3],
                                         const float o[3], const float pos[3], const float normal[3], irrvol__prepared *q)
{
    irrvol__prepare_terms(v, irrvol__cell_corners(v, c, o, q->id, q->w), weighting, pos, normal, 0, q);
}

/* The bin (NEAREST) or four bins (BILINEAR) of a direction. */
IRRVOL__HOT void irrvol__direction_bins(const irrvol *v, irrvol_filter filter, const float dir[3], irrvol__prepared *q)
{
    float u, t;
    uint32_t h;
    irrvol__direction_to_square(dir, &u, &t, &h);
    if (filter == IRRVOL_FILTER_DEFAULT) filter = v->filter;
    if (filter == IRRVOL_FILTER_BILINEAR) {
        irrvol__bilinear_bins(v, u, t, h, q->bin, q->bw);
        q->bins = 4;
    } else {
        q->bin[0] = irrvol__square_bin(v, u, t, h);
        q->bw[0] = 1.0f;
        q->bins = 1;
    }
}

IRRVOL__HOT void irrvol__prepare(const irrvol *v, irrvol_filter filter, irrvol_weighting weighting, const float pos[3],
                                 const float normal[3], const float dir[3], irrvol__prepared *q)
{
    const irrvol__corners *rec = irrvol__locate(v, pos, q->id, q->w);   /* first: its record's load starts early */
    irrvol__direction_bins(v, filter, dir, q);
    irrvol__prepare_terms(v, rec, weighting, pos, normal, 1, q);
}

/* irrvol__finish from the floats (full precision). With SSE2 the rgb of
   a value and the next float share a register: the same products and
   sums. */
IRRVOL__HOT void irrvol__finish_floats(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    size_t stride = (size_t)v->sample_count * 3;   /* one bin of all samples */
    const float *b0 = v->irradiance + q->bin[0] * stride, *b1 = b0, *b2 = b0, *b3 = b0;
    uint32_t i;
    if (q->bins != 1) {
        b1 = v->irradiance + q->bin[1] * stride;
        b2 = v->irradiance + q->bin[2] * stride;
        b3 = v->irradiance + q->bin[3] * stride;
    }
#ifdef IRRVOL__SSE2
    {
        __m128 sum = _mm_setzero_ps();
        float out[4];
        if (q->bins == 1) {
            for (i = 0; i < q->count; i++)
                sum = _mm_add_ps(sum, _mm_mul_ps(_mm_set1_ps(q->w[i]), _mm_loadu_ps(b0 + 3 * (size_t)q->id[i])));
        } else {
            __m128 w0 = _mm_set1_ps(q->bw[0]), w1 = _mm_set1_ps(q->bw[1]), w2 = _mm_set1_ps(q->bw[2]), w3 = _mm_set1_ps(q->bw[3]);
            for (i = 0; i < q->count; i++) {
                size_t at = 3 * (size_t)q->id[i];
                __m128 x = _mm_add_ps(_mm_add_ps(_mm_mul_ps(w0, _mm_loadu_ps(b0 + at)), _mm_mul_ps(w1, _mm_loadu_ps(b1 + at))),
                                      _mm_add_ps(_mm_mul_ps(w2, _mm_loadu_ps(b2 + at)), _mm_mul_ps(w3, _mm_loadu_ps(b3 + at))));
                sum = _mm_add_ps(sum, _mm_mul_ps(_mm_set1_ps(q->w[i]), x));
            }
        }
        _mm_storeu_ps(out, _mm_mul_ps(sum, _mm_set1_ps(q->scale)));
        rgb[0] = out[0]; rgb[1] = out[1]; rgb[2] = out[2];
    }
#else
    {
        float sum[3] = {0.0f, 0.0f, 0.0f};
        int c;
        for (i = 0; i < q->count; i++) {
            size_t at = 3 * (size_t)q->id[i];
            for (c = 0; c < 3; c++) {
                float x = b0[at + (size_t)c];
                if (q->bins != 1)
                    x = (q->bw[0] * b0[at + (size_t)c] + q->bw[1] * b1[at + (size_t)c]) +
                        (q->bw[2] * b2[at + (size_t)c] + q->bw[3] * b3[at + (size_t)c]);
                sum[c] += q->w[i] * x;
            }
        }
        for (c = 0; c < 3; c++) rgb[c] = sum[c] * q->scale;
    }
#endif
}

/* irrvol__finish from the compact store. A word's channel m (9 bits) and
   exponent field e give m 2^(e - 24) 2^pack_shift.
   NEAREST: the term's weight times unpack[e] scales the word's mantissas,
   left in place (green and blue 2^9 and 2^18 times their value, exact as
   floats), summed term after term; the place values come off once, at
   the end. With SSE2 a word's three channels share a register.
   BILINEAR, four terms at a time (the term list is padded to a multiple of
   four with weight 0): the power 2^(e - 24) is built from the word's bits
   (always a normal float), scaled by the bin's weight, the four bins are
   added and scaled by the term's weight; the sums are scaled by
   2^pack_shift once, at the end (powers of two multiply exactly). Each lane
   sums every fourth term and the lanes are added pairwise at the end: a
   short chain of additions instead of one per term. With SSE2 a lane is a
   term. The scalar code computes the same operations in the same order. */
#ifdef IRRVOL__SSE2
/* sum + term k's word of the bin b times its weight, place values left in. */
IRRVOL__HOT __m128 irrvol__nearest_term(const irrvol *v, const uint32_t *b, const irrvol__prepared *q, uint32_t k,
                                        __m128 sum)
{
    const __m128i mask = _mm_set_epi32(0, 0x1FF << 18, 0x1FF << 9, 0x1FF);
    uint32_t word = b[q->id[k]];
    __m128 m = _mm_cvtepi32_ps(_mm_and_si128(_mm_set1_epi32((int)word), mask));
    return _mm_add_ps(sum, _mm_mul_ps(m, _mm_set1_ps(q->w[k] * v->unpack[word >> 27])));
}

IRRVOL__HOT void irrvol__finish_nearest(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    const uint32_t *b = v->packed + (size_t)q->bin[0] * v->sample_count;
    __m128 sum = _mm_setzero_ps();
    float out[4];
    uint32_t i;
    for (i = 0; i < q->count; i += 4) {   /* a multiple of 4: one loop test a group */
        sum = irrvol__nearest_term(v, b, q, i, sum);
        sum = irrvol__nearest_term(v, b, q, i + 1, sum);
        sum = irrvol__nearest_term(v, b, q, i + 2, sum);
        sum = irrvol__nearest_term(v, b, q, i + 3, sum);
    }
    _mm_storeu_ps(out, _mm_mul_ps(_mm_mul_ps(sum, _mm_set_ps(0.0f, 1.0f / 262144.0f, 1.0f / 512.0f, 1.0f)),
                                  _mm_set1_ps(q->scale)));
    rgb[0] = out[0]; rgb[1] = out[1]; rgb[2] = out[2];
}

/* Four terms' words of one bin, b[id[0..3]]: their channels times 2^(e - 24) times s, by lane. */
IRRVOL__HOT void irrvol__words4(const uint32_t *b, const uint32_t *id, __m128 s, __m128 *r, __m128 *g, __m128 *bl)
{
    const __m128i nine = _mm_set1_epi32(0x1FF);
    __m128i w = _mm_set_epi32((int)b[id[3]], (int)b[id[2]], (int)b[id[1]], (int)b[id[0]]);
    __m128i pow2 = _mm_slli_epi32(_mm_add_epi32(_mm_srli_epi32(w, 27), _mm_set1_epi32(127 - 24)), 23);
    __m128 scale = _mm_mul_ps(s, _mm_castsi128_ps(pow2));
    *r = _mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(w, nine)), scale);
    *g = _mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(w, 9), nine)), scale);
    *bl = _mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(w, 18), nine)), scale);
}

IRRVOL__HOT void irrvol__finish_bilinear(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    const uint32_t *b0 = v->packed + (size_t)q->bin[0] * v->sample_count, *b1 = v->packed + (size_t)q->bin[1] * v->sample_count;
    const uint32_t *b2 = v->packed + (size_t)q->bin[2] * v->sample_count, *b3 = v->packed + (size_t)q->bin[3] * v->sample_count;
    const __m128 w0 = _mm_set1_ps(q->bw[0]), w1 = _mm_set1_ps(q->bw[1]), w2 = _mm_set1_ps(q->bw[2]), w3 = _mm_set1_ps(q->bw[3]);
    __m128 ar = _mm_setzero_ps(), ag = ar, ab = ar, z = ar;
    float o[4];
    uint32_t g;
    for (g = 0; g < q->count; g += 4) {
        __m128 w = _mm_loadu_ps(q->w + g), r0, g0, c0, r1, g1, c1, r2, g2, c2, r3, g3, c3;
        irrvol__words4(b0, q->id + g, w0, &r0, &g0, &c0);
        irrvol__words4(b1, q->id + g, w1, &r1, &g1, &c1);
        irrvol__words4(b2, q->id + g, w2, &r2, &g2, &c2);
        irrvol__words4(b3, q->id + g, w3, &r3, &g3, &c3);
        ar = _mm_add_ps(ar, _mm_mul_ps(w, _mm_add_ps(_mm_add_ps(r0, r1), _mm_add_ps(r2, r3))));
        ag = _mm_add_ps(ag, _mm_mul_ps(w, _mm_add_ps(_mm_add_ps(g0, g1), _mm_add_ps(g2, g3))));
        ab = _mm_add_ps(ab, _mm_mul_ps(w, _mm_add_ps(_mm_add_ps(c0, c1), _mm_add_ps(c2, c3))));
    }
    _MM_TRANSPOSE4_PS(ar, ag, ab, z);   /* rows: lane l's rgb */
    ar = _mm_add_ps(_mm_add_ps(ar, ag), _mm_add_ps(ab, z));
    ar = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(ar, _mm_set1_ps(v->unshift[0])), _mm_set1_ps(v->unshift[1])),
                    _mm_set1_ps(q->scale));
    _mm_storeu_ps(o, ar);
    rgb[0] = o[0]; rgb[1] = o[1]; rgb[2] = o[2];
}
#else
IRRVOL__HOT void irrvol__finish_nearest(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    static const float place[3] = {1.0f, 1.0f / 512.0f, 1.0f / 262144.0f};
    const uint32_t *b = v->packed + (size_t)q->bin[0] * v->sample_count;
    float sum[3] = {0.0f, 0.0f, 0.0f};
    uint32_t i;
    int c;
    for (i = 0; i < q->count; i++) {
        uint32_t word = b[q->id[i]];
        float s = q->w[i] * v->unpack[word >> 27];
        for (c = 0; c < 3; c++) sum[c] += (float)(word & (0x1FFu << (9 * c))) * s;
    }
    for (c = 0; c < 3; c++) rgb[c] = sum[c] * place[c] * q->scale;
}

/* 2^(e - 24) for the exponent field e of a word, from its bits. */
IRRVOL__HOT float irrvol__word_power(uint32_t word)
{
    uint32_t bits = ((word >> 27) + 127u - 24u) << 23;
    float p;
    memcpy(&p, &bits, sizeof p);
    return p;
}

IRRVOL__HOT void irrvol__finish_bilinear(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    float acc[4][3] = {{0.0f}}, t[4][3];
    uint32_t i, k;
    int c;
    for (i = 0; i < q->count; i++) {
        for (k = 0; k < 4; k++) {
            uint32_t word = v->packed[(size_t)q->bin[k] * v->sample_count + q->id[i]];
            float s = q->bw[k] * irrvol__word_power(word);
            for (c = 0; c < 3; c++) t[k][c] = (float)(word >> (9 * c) & 0x1FFu) * s;
        }
        for (c = 0; c < 3; c++) acc[i % 4][c] += q->w[i] * ((t[0][c] + t[1][c]) + (t[2][c] + t[3][c]));
    }
    for (c = 0; c < 3; c++)
        rgb[c] = (((acc[0][c] + acc[1][c]) + (acc[2][c] + acc[3][c])) * v->unshift[0]) * v->unshift[1] * q->scale;
}
#endif

IRRVOL__HOT void irrvol__finish_packed(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    if (q->bins == 1) irrvol__finish_nearest(v, q, rgb);
    else irrvol__finish_bilinear(v, q, rgb);
}

/* sum over samples of weight x (sum over bins of bin weight x value),
   times the scale. NEAREST reads one bin, BILINEAR blends four per sample
   first. */
IRRVOL__HOT void irrvol__finish(const irrvol *v, const irrvol__prepared *q, float rgb[3])
{
    if (v->packed) irrvol__finish_packed(v, q, rgb);
    else irrvol__finish_floats(v, q, rgb);
}

IRRVOL_API void irrvol_query_filter(const irrvol *vol, irrvol_filter filter, irrvol_weighting weighting,
                                    const float pos[3], const float dir[3], float rgb[3])
{
    irrvol__prepared q;
    irrvol__prepare(vol, filter, weighting, pos, dir, dir, &q);
    irrvol__finish(vol, &q, rgb);
}

IRRVOL_API void irrvol_query(const irrvol *vol, const float pos[3], const float dir[3], float rgb[3])
{
    irrvol_query_filter(vol, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_DEFAULT, pos, dir, rgb);
}

/* Fig. 4.17: a moment volume is queried along the view vector mirrored
   about the normal, Q = 2 (N . V) N - V; the visibility weights take the
   surface normal. */
IRRVOL_API void irrvol_query_glossy(const irrvol *vol, const float pos[3], const float normal[3],
                                    const float to_eye[3], float rgb[3])
{
    float n2 = normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2];
    float s = n2 > 0.0f ? 2.0f * (normal[0] * to_eye[0] + normal[1] * to_eye[1] + normal[2] * to_eye[2]) / n2 : 0.0f;
    float d[3];
    irrvol__prepared q;
    d[0] = s * normal[0] - to_eye[0];
    d[1] = s * normal[1] - to_eye[1];
    d[2] = s * normal[2] - to_eye[2];
    irrvol__prepare(vol, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_DEFAULT, pos, normal, d, &q);
    irrvol__finish(vol, &q, rgb);
}

/* Many queries, pipelined: each query is prepared IRRVOL__AHEAD queries
   before it is summed and its values are prefetched meanwhile, so the
   memory latency of one query overlaps the work of the next ones (a
   leak-safe query prefetches its own, irrvol__prepare_terms). The
   results equal irrvol_query_filter's bit for bit. */
IRRVOL_API void irrvol_query_many(const irrvol *vol, irrvol_filter filter, irrvol_weighting weighting, uint32_t count,
                                  const float *pos, size_t pos_stride, const float *dir, size_t dir_stride, float *rgb)
{
    irrvol__prepared ring[IRRVOL__AHEAD];
    uint32_t i;
    int prefetched = (weighting == IRRVOL_WEIGHTING_DEFAULT ? vol->weighting : weighting) == IRRVOL_WEIGHTING_VISIBILITY;
    if (!pos_stride) pos_stride = 3 * sizeof(float);
    if (!dir_stride) dir_stride = 3 * sizeof(float);
    for (i = 0; i < count; i++) {
        irrvol__prepared *q = &ring[i % IRRVOL__AHEAD];
        const float *d = (const float *)((const char *)dir + i * dir_stride);
        if (i >= IRRVOL__AHEAD) irrvol__finish(vol, q, rgb + 3 * (size_t)(i - IRRVOL__AHEAD));
        irrvol__prepare(vol, filter, weighting, (const float *)((const char *)pos + i * pos_stride), d, d, q);
        if (!prefetched) irrvol__prefetch_values(vol, q->bin, q->bins, q->id, q->count);
    }
    for (i = count > IRRVOL__AHEAD ? count - IRRVOL__AHEAD : 0; i < count; i++)
        irrvol__finish(vol, &ring[i % IRRVOL__AHEAD], rgb + 3 * (size_t)i);
}

/* Ramamoorthi and Hanrahan's E(n) = sum A_l L_lm Y_lm(n) at each term's
   sample, weighted like the bins; order 1 reads the first 4 coefficients,
   order 2 all 9. Clamped at zero: a bright light's truncated harmonics
   dip below zero on its far side. */
IRRVOL_API void irrvol_query_sh(const irrvol *vol, uint32_t order, irrvol_weighting weighting, const float pos[3],
                                const float dir[3], float rgb[3])
{
    irrvol__prepared q;
    uint32_t i, j, coeffs = order <= 1 ? 4u : IRRVOL__SH_COEFFS;
    float ylm[IRRVOL__SH_COEFFS], n[3] = {0.0f, 0.0f, 1.0f}, sum[3] = {0.0f, 0.0f, 0.0f};
    float len2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    if (len2 > 0.0f && len2 <= FLT_MAX) {   /* zero, infinite and NaN directions look up +z */
        float inv = 1.0f / sqrtf(len2);
        n[0] = dir[0] * inv; n[1] = dir[1] * inv; n[2] = dir[2] * inv;
    }
    irrvol__prepare_at(vol, weighting, pos, n, &q);
    irrvol__sh_basis(n[0], n[1], n[2], ylm);
#ifdef IRRVOL__SSE2
    {   /* a coefficient's rgb and the next float in one register: the same products and sums */
        __m128 y[IRRVOL__SH_COEFFS], total = _mm_setzero_ps();
        float out[4];
        for (j = 0; j < coeffs; j++) y[j] = _mm_set1_ps(ylm[j]);
        for (i = 0; i < q.count; i++) {
            const float *s = vol->sh + (size_t)q.id[i] * IRRVOL__SH_FLOATS;
            __m128 e = _mm_setzero_ps();
            for (j = 0; j < coeffs; j++) e = _mm_add_ps(e, _mm_mul_ps(_mm_loadu_ps(s + 3 * j), y[j]));
            total = _mm_add_ps(total, _mm_mul_ps(_mm_set1_ps(q.w[i]), e));
        }
        _mm_storeu_ps(out, total);
        memcpy(sum, out, sizeof sum);
    }
#else
    for (i = 0; i < q.count; i++) {
        const float *s = vol->sh + (size_t)q.id[i] * IRRVOL__SH_FLOATS;
        float e[3] = {0.0f, 0.0f, 0.0f};
        for (j = 0; j < coeffs; j++) {
            e[0] += s[3 * j] * ylm[j];
            e[1] += s[3 * j + 1] * ylm[j];
            e[2] += s[3 * j + 2] * ylm[j];
        }
        for (j = 0; j < 3; j++) sum[j] += q.w[i] * e[j];
    }
#endif
    for (j = 0; j < 3; j++) rgb[j] = irrvol__maxf(sum[j] * q.scale, 0.0f);
}

IRRVOL_API irrvol_result irrvol_sample(const irrvol *vol, uint32_t index, irrvol_sample_info *info)
{
    if (!vol || !info || index >= vol->sample_count) return IRRVOL_ERROR_INVALID_ARGUMENT;
    memcpy(info->position, vol->positions + 3 * (size_t)index, sizeof info->position);
    memcpy(info->origin, vol->origins + 4 * (size_t)index, sizeof info->origin);
    info->level = index < vol->first_level_count ? 1 : 2;
    if (index >= vol->hanging_begin) info->state = IRRVOL_SAMPLE_HANGING;
    else if (vol->origins[4 * (size_t)index + 3] == 0.0f) info->state = IRRVOL_SAMPLE_INVALID;
    else if (memcmp(info->position, info->origin, sizeof info->origin) != 0) info->state = IRRVOL_SAMPLE_RELOCATED;
    else info->state = IRRVOL_SAMPLE_VALID;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_sample_values(const irrvol *vol, uint32_t index, float *irradiance, float *radiance)
{
    uint32_t bin;
    if (!vol || index >= vol->sample_count || (radiance && !vol->radiance)) return IRRVOL_ERROR_INVALID_ARGUMENT;
    for (bin = 0; bin < vol->bins; bin++) {
        size_t at = ((size_t)bin * vol->sample_count + index) * 3;
        if (irradiance) irrvol__bin_value(vol, at / 3, irradiance + 3 * (size_t)bin);
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
    float u, w;
    uint32_t h;
    irrvol__direction_to_square(dir, &u, &w, &h);
    return irrvol__square_bin(vol, u, w, h);
}

/* ======================================================================
   14. self-occlusion of dynamic meshes (6.1.3)
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
    if (!irrvol__indices_valid(d->indices, d->triangle_count, d->vertex_count))
        IRRVOL__REJECT(d->log, d->log_user,
                       "irrvol_visibility_ratio: a vertex index is out of range (or over UINT32_MAX / 3 triangles)");
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
   15. save and load (file format version 3)
   magic "IRRVOL\x1a\n", version u32, payload size u64, payload, CRC32.
   Payload: k, moment, filter, weighting, flags (bit 0: radiance stored,
   bit 1: the compact store), first-level samples x y z, subgrid samples,
   visibility resolution (u32 each), bounds min xyz, max xyz, the
   visibility test's normal bias (f32), sample count, rays (u64),
   degenerate triangles, invalid and relocated samples, one byte per
   first-level cell (0 unrefined, 1 refined by geometry, 2 by light), then
   floats: the origins (xyz, valid) of the samples before the hanging ones,
   irradiance (bin-major: for each bin, rgb of every sample; the compact
   store: its shift, an int32, then one RGB9E5 word per bin and sample, a
   third of the bytes), harmonics (27 per sample), visibility fits (4 per
   texel of the samples before the hanging ones), radiance when flagged.
   The grid tables, the hanging samples and the sample positions are
   rebuilt from these on load.
   ---------------------------------------------------------------------- */
static const unsigned char irrvol__magic[8] = {'I', 'R', 'R', 'V', 'O', 'L', 0x1a, '\n'};
#define IRRVOL__HEADER_FIELDS 92u   /* payload bytes before the cell flags */

/* The header's flags. */
#define IRRVOL__FILE_RADIANCE 1u   /* the radiance follows the visibility maps */
#define IRRVOL__FILE_COMPACT 2u    /* the irradiance is the compact store: its shift, then a word a bin */

/* The 4-byte items after the cell flags: origins, irradiance, harmonics,
   visibility, radiance. */
static uint64_t irrvol__payload_floats(const irrvol *v, uint32_t flags)
{
    uint64_t bins = (uint64_t)v->sample_count * v->bins;
    uint64_t irradiance = flags & IRRVOL__FILE_COMPACT ? 1 + bins : 3 * bins;
    return 4 * (uint64_t)v->hanging_begin + irradiance + (flags & IRRVOL__FILE_RADIANCE ? 3 * bins : 0) +
           (uint64_t)v->sample_count * IRRVOL__SH_FLOATS + (uint64_t)v->hanging_begin * v->texels * 4;
}

static uint32_t irrvol__file_flags(const irrvol *v)
{
    return (v->radiance ? IRRVOL__FILE_RADIANCE : 0u) | (v->packed ? IRRVOL__FILE_COMPACT : 0u);
}

static irrvol_result irrvol__write_all(const irrvol *v, irrvol__writer *w)
{
    uint64_t bins = (uint64_t)v->sample_count * v->bins * 3;
    uint64_t payload = IRRVOL__HEADER_FIELDS + v->cell_count + 4 * irrvol__payload_floats(v, irrvol__file_flags(v));
    uint32_t k, s;
    irrvol__crc_init(&w->crc);
    irrvol__put(w, irrvol__magic, 8);
    irrvol__put_u32(w, IRRVOL_FILE_FORMAT_VERSION);
    irrvol__put_u64(w, payload);
    irrvol__put_u32(w, v->k);
    irrvol__put_u32(w, v->moment);
    irrvol__put_u32(w, (uint32_t)v->filter);
    irrvol__put_u32(w, (uint32_t)v->weighting);
    irrvol__put_u32(w, irrvol__file_flags(v));
    for (k = 0; k < 3; k++) irrvol__put_u32(w, v->samples[k]);
    irrvol__put_u32(w, v->subgrid);
    irrvol__put_u32(w, v->vis_res);
    for (k = 0; k < 3; k++) irrvol__put_f32(w, v->lo[k]);
    for (k = 0; k < 3; k++) irrvol__put_f32(w, v->hi[k]);
    irrvol__put_f32(w, v->bias);
    irrvol__put_u32(w, v->sample_count);
    irrvol__put_u64(w, v->rays);
    irrvol__put_u32(w, v->degenerate);
    irrvol__put_u32(w, v->invalid_count);
    irrvol__put_u32(w, v->relocated_count);
    irrvol__put(w, v->refined, v->cell_count);
    irrvol__put_array32(w, v->origins, 4 * (size_t)v->hanging_begin);
    if (v->packed) {
        irrvol__put_u32(w, (uint32_t)v->pack_shift);
        irrvol__put_array32(w, v->packed, (size_t)bins / 3);
    } else {
        irrvol__put_array32(w, v->irradiance, (size_t)bins);
    }
    irrvol__put_array32(w, v->sh, (size_t)v->sample_count * IRRVOL__SH_FLOATS);
    for (s = 0; s < v->hanging_begin; s++)   /* the maps' interiors, row by row: load rebuilds the borders */
        for (k = 0; k < v->vis_res; k++)
            irrvol__put_array32(w, v->visibility + ((size_t)s * v->map_texels + (k + 1) * (v->vis_res + 2) + 1) * 4,
                                  4 * (size_t)v->vis_res);
    if (v->radiance) irrvol__put_array32(w, v->radiance, (size_t)bins);
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

/* Reads n 4-byte items (little-endian) into items. */
static int irrvol__get_array32(irrvol__reader *r, void *items, size_t n)
{
    unsigned char buf[4096], *f = (unsigned char *)items;
    size_t i = 0;
    while (i < n && !r->failed) {
        size_t m = n - i < sizeof buf / 4 ? n - i : sizeof buf / 4, j;
        irrvol__get(r, buf, 4 * m);
        for (j = 0; j < m; j++, i++) {
            const unsigned char *b = buf + 4 * j;
            uint32_t u = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
            memcpy(f + 4 * i, &u, 4);
        }
    }
    return !r->failed;
}

/* Reads n floats; each must be finite, and at least lower. */
static int irrvol__get_floats(irrvol__reader *r, float *f, size_t n, float lower)
{
    size_t i;
    if (!irrvol__get_array32(r, f, n)) return 0;
    for (i = 0; i < n; i++)
        if (!isfinite(f[i]) || f[i] < lower) { r->failed = 1; return 0; }
    return 1;
}

/* Header fields; 0 when they describe a volume this version can hold. */
static int irrvol__read_fields(irrvol__reader *r, irrvol *v, uint32_t *flags, uint32_t *declared_samples)
{
    uint32_t samples[3], filter, weighting, subgrid, k, vis_res;
    int d;
    k = irrvol__get_u32(r);
    v->moment = irrvol__get_u32(r);
    filter = irrvol__get_u32(r);
    weighting = irrvol__get_u32(r);
    *flags = irrvol__get_u32(r);
    for (d = 0; d < 3; d++) samples[d] = irrvol__get_u32(r);
    subgrid = irrvol__get_u32(r);
    vis_res = irrvol__get_u32(r);
    for (d = 0; d < 3; d++) v->lo[d] = irrvol__get_f32(r);
    for (d = 0; d < 3; d++) v->hi[d] = irrvol__get_f32(r);
    v->bias = irrvol__get_f32(r);
    *declared_samples = irrvol__get_u32(r);
    v->rays = irrvol__get_u64(r);
    v->degenerate = irrvol__get_u32(r);
    v->invalid_count = irrvol__get_u32(r);
    v->relocated_count = irrvol__get_u32(r);
    if (r->failed || k < 1 || k > IRRVOL_MAX_RESOLUTION || v->moment < 1 || v->moment > IRRVOL_MAX_MOMENT ||
        (filter != IRRVOL_FILTER_NEAREST && filter != IRRVOL_FILTER_BILINEAR) ||
        (weighting != IRRVOL_WEIGHTING_VISIBILITY && weighting != IRRVOL_WEIGHTING_TRILINEAR) ||
        *flags > (IRRVOL__FILE_RADIANCE | IRRVOL__FILE_COMPACT) ||
        subgrid < 2 || subgrid > IRRVOL_MAX_SUBGRID_SAMPLES || vis_res < 1 ||
        vis_res > IRRVOL_MAX_VISIBILITY_RESOLUTION || !isfinite(v->bias) || !(v->bias >= 0.0f))
        return -1;
    for (d = 0; d < 3; d++)
        if (samples[d] < 2 || samples[d] > IRRVOL_MAX_GRID_SAMPLES || !isfinite(v->lo[d]) || !isfinite(v->hi[d]) ||
            !(v->lo[d] < v->hi[d]) || !isfinite(v->hi[d] - v->lo[d]))
            return -1;
    v->filter = (irrvol_filter)filter;
    v->weighting = (irrvol_weighting)weighting;
    irrvol__set_resolutions(v, k, vis_res);
    irrvol__grid_dims(v, samples, subgrid);
    return 0;
}

/* Reads the interiors of the visibility maps (every float finite, every
   residual variance >= 0) and rebuilds their borders. */
static int irrvol__read_maps(irrvol__reader *r, irrvol *v)
{
    uint32_t s, k, t;
    for (s = 0; s < v->hanging_begin; s++) {
        float *map = v->visibility + (size_t)s * v->map_texels * 4;
        for (k = 0; k < v->vis_res; k++) {
            float *row = map + ((k + 1) * (v->vis_res + 2) + 1) * 4;
            if (!irrvol__get_floats(r, row, 4 * (size_t)v->vis_res, -FLT_MAX)) return 0;
            for (t = 0; t < v->vis_res; t++)
                if (!(row[4 * t + 3] >= 0.0f)) return 0;
        }
        irrvol__map_border(v, map);
    }
    return 1;
}

/* The irradiance: finite floats, or the compact store's shift (within
   what irrvol__pack_shift gives for finite floats: frexpf exponents
   -148..128, less 15) and its words (any word is a finite value). */
static int irrvol__read_irradiance(irrvol__reader *r, irrvol *v)
{
    size_t n = (size_t)v->sample_count * v->bins;
    int32_t shift;
    if (!v->packed) return irrvol__get_floats(r, v->irradiance, 3 * n, -FLT_MAX);
    shift = (int32_t)irrvol__get_u32(r);
    if (r->failed || shift < -163 || shift > 113) return 0;
    irrvol__set_unpack(v, shift);
    return irrvol__get_array32(r, v->packed, n);
}

/* The origins read back must be finite, flagged 0 or 1, and agree with
   the invalid and relocated counts of the header. */
static int irrvol__origins_consistent(const irrvol *v)
{
    uint32_t s, invalid = 0, relocated = 0;
    for (s = 0; s < v->hanging_begin; s++) {
        const float *o = v->origins + 4 * (size_t)s;
        if (o[3] != 0.0f && o[3] != 1.0f) return 0;
        if (o[3] == 0.0f) invalid++;
        else if (memcmp(o, v->positions + 3 * (size_t)s, 3 * sizeof(float)) != 0) relocated++;
    }
    return invalid == v->invalid_count && relocated == v->relocated_count;
}

static irrvol_result irrvol__read_all(irrvol *v, irrvol__reader *r)
{
    const irrvol_allocator *a = &v->allocator;
    unsigned char magic[8];
    uint32_t version, flags, declared, c, refined_count = 0, expected_crc, s, bin_words;
    uint64_t inner;
    irrvol_result res;
    irrvol__crc_init(&r->crc);
    r->remaining = 20;
    irrvol__get(r, magic, 8);
    version = irrvol__get_u32(r);
    r->remaining = irrvol__get_u64(r);
    if (r->failed || memcmp(magic, irrvol__magic, 8) != 0 || r->remaining > r->available)
        return IRRVOL_ERROR_CORRUPT_DATA;
    if (version != IRRVOL_FILE_FORMAT_VERSION) return IRRVOL_ERROR_VERSION;
    if (irrvol__read_fields(r, v, &flags, &declared) != 0) return IRRVOL_ERROR_CORRUPT_DATA;
    /* every size is checked against the payload before anything is allocated */
    if (!irrvol__can_hold(r, v->cell_count, 1)) return IRRVOL_ERROR_CORRUPT_DATA;
    v->refined = (unsigned char *)irrvol__alloc(a, v->cell_count);
    if (!v->refined) return IRRVOL_ERROR_OUT_OF_MEMORY;
    irrvol__get(r, v->refined, v->cell_count);
    for (c = 0; c < v->cell_count; c++) {
        if (v->refined[c] > IRRVOL__REFINED_LIGHT || (v->refined[c] && v->subgrid == 2)) r->failed = 1;
        refined_count += v->refined[c] ? 1u : 0u;
    }
    /* each refined cell owns its (side - 2)^3 interior samples: a lower bound; a sample's bins take
       one word each in the compact store, three floats at full precision */
    inner = (uint64_t)(v->subgrid - 2) * (v->subgrid - 2) * (v->subgrid - 2);
    bin_words = flags & IRRVOL__FILE_COMPACT ? 1u : 3u;
    if (r->failed || (uint64_t)v->first_level_count + refined_count * inner > declared ||
        !irrvol__can_hold(r, (uint64_t)declared * v->bins * bin_words + (uint64_t)declared * IRRVOL__SH_FLOATS, 4))
        return IRRVOL_ERROR_CORRUPT_DATA;
    res = irrvol__make_grid(v, v->refined);
    if (res != IRRVOL_OK) return res;
    if (v->sample_count != declared || !irrvol__can_hold(r, irrvol__payload_floats(v, flags), 4))
        return IRRVOL_ERROR_CORRUPT_DATA;
    res = irrvol__alloc_samples(v, flags & IRRVOL__FILE_RADIANCE, flags & IRRVOL__FILE_COMPACT);
    if (res != IRRVOL_OK) return res;
    if (!irrvol__get_floats(r, v->origins, 4 * (size_t)v->hanging_begin, -FLT_MAX) || !irrvol__origins_consistent(v) ||
        !irrvol__read_irradiance(r, v) ||
        !irrvol__get_floats(r, v->sh, (size_t)v->sample_count * IRRVOL__SH_FLOATS, -FLT_MAX) ||
        !irrvol__read_maps(r, v) ||
        ((flags & IRRVOL__FILE_RADIANCE) &&
         !irrvol__get_floats(r, v->radiance, (size_t)v->sample_count * v->bins * 3, -FLT_MAX)))
        return IRRVOL_ERROR_CORRUPT_DATA;
    if (r->remaining != 0) return IRRVOL_ERROR_CORRUPT_DATA;   /* payload longer than its contents */
    expected_crc = irrvol__crc_final(&r->crc);
    r->remaining = 4;
    if (irrvol__get_u32(r) != expected_crc || r->failed) return IRRVOL_ERROR_CORRUPT_DATA;
    for (s = v->hanging_begin; s < v->sample_count; s++) {   /* hanging origins: their grid positions */
        memcpy(v->origins + 4 * (size_t)s, v->positions + 3 * (size_t)s, 3 * sizeof(float));
        v->origins[4 * (size_t)s + 3] = 1.0f;
    }
    return irrvol__make_probes(v);
}

/* A load from a stream of at most available payload bytes. */
static irrvol_result irrvol__load(const irrvol_allocator *allocator, irrvol_read_fn read, void *user,
                                  uint64_t available, irrvol **out)
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
    r.available = available;
    res = irrvol__read_all(v, &r);
    if (res != IRRVOL_OK) { irrvol_destroy(v); return res; }
    *out = v;
    return IRRVOL_OK;
}

IRRVOL_API irrvol_result irrvol_load(const irrvol_allocator *allocator, irrvol_read_fn read, void *user,
                                     irrvol **out)
{
    return irrvol__load(allocator, read, user, UINT64_MAX, out);
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
    /* the payload fits between the 20 header bytes and the 4 of the CRC:
       a larger claim is refused before anything is allocated */
    return irrvol__load(allocator, irrvol__membuf_read, &m, size > 24 ? (uint64_t)size - 24 : 0, out);
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

/* ======================================================================
   16. the volume on the GPU: flat arrays and a GLSL evaluator
   irrvol_gpu_export writes the volume's own tables into two flat arrays, a
   uint32 index array and a float data array, for two storage buffers (or,
   section by section, for textures: the first-level samples come first in
   x-fastest order, a dense 3D grid). The GLSL below evaluates harmonics
   with the leak-safe weights of irrvol_query_sh, hanging samples included.
   It is written in the subset GLSL and C share (scalars, structs, loops;
   conversions, abs, sqrt, max and the array reads through macros), so the
   tests compile the very same text as C and compare it with the C query.
   ---------------------------------------------------------------------- */
#define IRRVOL__GPU_FORMAT 1u       /* index[0]: the layout's version */
#define IRRVOL__GPU_HEADER 16u      /* entries of each array's header */

/* Shared GLSL / C text, part 1: the visibility weight of a sample
   (irrvol__visibility_weight, operation by operation). */
#define IRRVOL__GLSL_PART1(X) X( \
struct IrrvolRGB { float r; float g; float b; }; \
float irrvol_visibility(uint s, float x, float y, float z, float nx, float ny, float nz) \
{ \
    uint o = IRRVOL_INDEX(11u) + 4u * s; \
    float dx = x - IRRVOL_DATA(o); \
    float dy = y - IRRVOL_DATA(o + 1u); \
    float dz = z - IRRVOL_DATA(o + 2u); \
    float r2 = dx * dx + dy * dy + dz * dz; \
    if (!(r2 > 0.0f)) return IRRVOL_DATA(o + 3u); \
    float inv_r = 1.0f / IRRVOL_SQRT(r2); \
    float w = 0.5f - 0.5f * ((dx * nx + dy * ny + dz * nz) * inv_r); \
    w = w + 0.2f; \
    float inv_a = 1.0f / (IRRVOL_ABS(dx) + IRRVOL_ABS(dy) + IRRVOL_ABS(dz)); \
    float px = dx * inv_a; \
    float py = dy * inv_a; \
    if (dz < 0.0f) { \
        float qx = (1.0f - IRRVOL_ABS(py)) * (px < 0.0f ? -1.0f : 1.0f); \
        py = (1.0f - IRRVOL_ABS(px)) * (py < 0.0f ? -1.0f : 1.0f); \
        px = qx; \
    } \
    uint n = IRRVOL_INDEX(6u); \
    float fn = IRRVOL_F(n); \
    float u = IRRVOL_MIN(IRRVOL_MAX((px * 0.5f + 0.5f) * fn + 0.5f, 0.5f), fn + 0.5f); \
    float t = IRRVOL_MIN(IRRVOL_MAX((py * 0.5f + 0.5f) * fn + 0.5f, 0.5f), fn + 0.5f); \
    uint i0 = IRRVOL_U(u); \
    uint j0 = IRRVOL_U(t); \
    float fu = u - IRRVOL_F(i0); \
    float ft = t - IRRVOL_F(j0); \
    uint m = IRRVOL_INDEX(12u) + 4u * (s * (n + 2u) * (n + 2u) + j0 * (n + 2u) + i0); \
    uint m1 = m + 4u * (n + 2u); \
    float g[4]; \
    for (uint c = 0u; c < 4u; c++) \
        g[c] = (IRRVOL_DATA(m + c) * (1.0f - fu) + IRRVOL_DATA(m + 4u + c) * fu) * (1.0f - ft) + \
               (IRRVOL_DATA(m1 + c) * (1.0f - fu) + IRRVOL_DATA(m1 + 4u + c) * fu) * ft; \
    float beyond = (g[0] * dx + g[1] * dy + g[2] * dz - 1.0f) * inv_r; \
    if (beyond > 0.0f) { \
        float den = g[3] + beyond * beyond; \
        float cheb = den > 0.0f ? g[3] / den : 1.0f; \
        w = w * (cheb * cheb * cheb); \
    } \
    if (w < 0.2f) w = w * (w * w * 25.0f); \
    return w * IRRVOL_DATA(o + 3u); \
} \
)

/* Part 2: a sample's harmonics toward n. */
#define IRRVOL__GLSL_PART2(X) X( \
IrrvolRGB irrvol_sh_value(uint s, float y0, float y1, float y2, float y3, float y4, float y5, float y6, float y7, \
                          float y8) \
{ \
    uint coeffs = IRRVOL_INDEX(7u); \
    uint c = IRRVOL_INDEX(13u) + s * 3u * coeffs; \
    float ylm[9]; \
    ylm[0] = y0; ylm[1] = y1; ylm[2] = y2; ylm[3] = y3; ylm[4] = y4; ylm[5] = y5; ylm[6] = y6; ylm[7] = y7; ylm[8] = y8; \
    IrrvolRGB e; \
    e.r = 0.0f; e.g = 0.0f; e.b = 0.0f; \
    for (uint j = 0u; j < coeffs; j++) { \
        e.r += IRRVOL_DATA(c + 3u * j) * ylm[j]; \
        e.g += IRRVOL_DATA(c + 3u * j + 1u) * ylm[j]; \
        e.b += IRRVOL_DATA(c + 3u * j + 2u) * ylm[j]; \
    } \
    return e; \
} \
)

/* Part 3: the query. */
#define IRRVOL__GLSL_PART3(X) X( \
IrrvolRGB irrvol_irradiance_sh(float px, float py, float pz, float nx, float ny, float nz) \
{ \
    float len2 = nx * nx + ny * ny + nz * nz; \
    if (len2 > 0.0f && len2 <= 3.40282347e38f) { \
        float inv = 1.0f / IRRVOL_SQRT(len2); \
        nx *= inv; ny *= inv; nz *= inv; \
    } else { \
        nx = 0.0f; ny = 0.0f; nz = 1.0f; \
    } \
    float y0 = 0.282094792f, y1 = 0.488602512f * ny, y2 = 0.488602512f * nz, y3 = 0.488602512f * nx; \
    float y4 = 1.092548431f * nx * ny, y5 = 1.092548431f * ny * nz, y6 = 0.315391565f * (3.0f * nz * nz - 1.0f); \
    float y7 = 1.092548431f * nx * nz, y8 = 0.546274215f * (nx * nx - ny * ny); \
    float p[3]; \
    p[0] = px; p[1] = py; p[2] = pz; \
    uint c[3]; \
    float t[3]; \
    for (uint d = 0u; d < 3u; d++) { \
        float q = (p[d] - IRRVOL_DATA(d)) * IRRVOL_DATA(3u + d); \
        q = q > 0.0f ? q : 0.0f; \
        q = q < IRRVOL_DATA(6u + d) ? q : IRRVOL_DATA(6u + d); \
        c[d] = IRRVOL_U(q); \
        c[d] = c[d] < IRRVOL_INDEX(1u + d) ? c[d] : IRRVOL_INDEX(1u + d) - 1u; \
        t[d] = q - IRRVOL_F(c[d]); \
    } \
    uint cell = IRRVOL_INDEX(8u) + 2u * (c[0] + IRRVOL_INDEX(1u) * (c[1] + IRRVOL_INDEX(2u) * c[2])); \
    uint side = IRRVOL_INDEX(cell + 1u); \
    for (uint d = 0u; d < 3u; d++) { \
        float q = t[d] * IRRVOL_F(side - 1u); \
        c[d] = IRRVOL_U(q); \
        c[d] = c[d] < side - 2u ? c[d] : side - 2u; \
        t[d] = q - IRRVOL_F(c[d]); \
    } \
    uint table = IRRVOL_INDEX(9u) + IRRVOL_INDEX(cell) + c[0] + side * (c[1] + side * c[2]); \
    uint ids[8]; \
    float w[8]; \
    for (uint i = 0u; i < 8u; i++) { \
        uint bx = i & 1u, by = (i >> 1u) & 1u, bz = i >> 2u; \
        ids[i] = IRRVOL_INDEX(table + bx + side * (by + side * bz)); \
        w[i] = (bx == 1u ? t[0] : 1.0f - t[0]) * (by == 1u ? t[1] : 1.0f - t[1]) * (bz == 1u ? t[2] : 1.0f - t[2]); \
    } \
    float bias = IRRVOL_DATA(9u); \
    float x = px + bias * nx, y = py + bias * ny, z = pz + bias * nz; \
    uint hanging = IRRVOL_INDEX(5u); \
    uint terms[32]; \
    float tw[32]; \
    uint m = 0u; \
    for (uint i = 0u; i < 8u; i++) { \
        if (ids[i] >= hanging) { \
            for (uint j = 0u; j < 4u; j++) { \
                uint h = 4u * (ids[i] - hanging) + j; \
                float pw = IRRVOL_DATA(IRRVOL_INDEX(14u) + h); \
                if (pw > 0.0f) { \
                    terms[m] = IRRVOL_INDEX(IRRVOL_INDEX(10u) + h); \
                    tw[m] = w[i] * pw; \
                    m++; \
                } \
            } \
        } else { \
            terms[m] = ids[i]; \
            tw[m] = w[i]; \
            m++; \
        } \
    } \
    float sum = 0.0f; \
    for (uint i = 0u; i < m; i++) { \
        tw[i] *= irrvol_visibility(terms[i], x, y, z, nx, ny, nz); \
        sum += tw[i]; \
    } \
    IrrvolRGB e; \
    e.r = 0.0f; e.g = 0.0f; e.b = 0.0f; \
    for (uint i = 0u; i < m; i++) { \
        IrrvolRGB v = irrvol_sh_value(terms[i], y0, y1, y2, y3, y4, y5, y6, y7, y8); \
        e.r += tw[i] * v.r; e.g += tw[i] * v.g; e.b += tw[i] * v.b; \
    } \
    float scale = 1.0f / sum; \
    if (!(sum >= 1.17549435e-38f && sum <= 3.40282347e38f)) { \
        e.r = 0.0f; e.g = 0.0f; e.b = 0.0f; \
        scale = 1.0f; \
        for (uint i = 0u; i < 8u; i++) { \
            IrrvolRGB v = irrvol_sh_value(ids[i], y0, y1, y2, y3, y4, y5, y6, y7, y8); \
            e.r += w[i] * v.r; e.g += w[i] * v.g; e.b += w[i] * v.b; \
        } \
    } \
    e.r = IRRVOL_MAX(e.r * scale, 0.0f); \
    e.g = IRRVOL_MAX(e.g * scale, 0.0f); \
    e.b = IRRVOL_MAX(e.b * scale, 0.0f); \
    return e; \
} \
)

#define IRRVOL__GLSL_STRING(...) #__VA_ARGS__

/* The GLSL text: the prelude, the three stringified parts (code: one
   line each, broken at statements when copied out) and the vec3 wrapper. */
typedef struct irrvol__glsl_part { const char *text; int code; } irrvol__glsl_part;
static const irrvol__glsl_part irrvol__glsl_parts[] = {
    {
    "/* irrvol.h - the irradiance volume in GLSL: irrvol_irradiance(position, normal)\n"
    "   returns the leak-safe irradiance of the harmonics exported by irrvol_gpu_export.\n"
    "   Needs GLSL 4.30 or newer (storage buffers); define IRRVOL_INDEX(i) and\n"
    "   IRRVOL_DATA(i) to read the two arrays from elsewhere. */\n"
    "#ifndef IRRVOL_INDEX\n"
    "#ifndef IRRVOL_INDEX_BINDING\n#define IRRVOL_INDEX_BINDING 0\n#endif\n"
    "#ifndef IRRVOL_DATA_BINDING\n#define IRRVOL_DATA_BINDING 1\n#endif\n"
    "layout(std430, binding = IRRVOL_INDEX_BINDING) readonly buffer IrrvolIndexBuffer { uint irrvol_index[]; };\n"
    "layout(std430, binding = IRRVOL_DATA_BINDING) readonly buffer IrrvolDataBuffer { float irrvol_data[]; };\n"
    "#define IRRVOL_INDEX(i) irrvol_index[i]\n"
    "#define IRRVOL_DATA(i) irrvol_data[i]\n"
    "#endif\n"
    "#define IRRVOL_U(x) uint(x)\n#define IRRVOL_I(x) int(x)\n#define IRRVOL_F(x) float(x)\n"
    "#define IRRVOL_ABS(x) abs(x)\n#define IRRVOL_SQRT(x) sqrt(x)\n"
    "#define IRRVOL_MIN(a, b) ((a) < (b) ? (a) : (b))\n#define IRRVOL_MAX(a, b) ((a) > (b) ? (a) : (b))\n", 0},
    {IRRVOL__GLSL_PART1(IRRVOL__GLSL_STRING), 1},
    {IRRVOL__GLSL_PART2(IRRVOL__GLSL_STRING), 1},
    {IRRVOL__GLSL_PART3(IRRVOL__GLSL_STRING), 1},
    {"vec3 irrvol_irradiance(vec3 p, vec3 n)\n{\n"
     "    IrrvolRGB e = irrvol_irradiance_sh(p.x, p.y, p.z, n.x, n.y, n.z);\n"
     "    return vec3(e.r, e.g, e.b);\n}\n", 0}
};

static void irrvol__glsl_put(char *buffer, size_t capacity, size_t *length, char c)
{
    if (buffer && *length + 1 < capacity) buffer[*length] = c;
    (*length)++;
}

IRRVOL_API size_t irrvol_glsl_source(char *buffer, size_t capacity)
{
    size_t length = 0, i;
    for (i = 0; i < sizeof irrvol__glsl_parts / sizeof irrvol__glsl_parts[0]; i++) {
        const char *c = irrvol__glsl_parts[i].text;
        int code = irrvol__glsl_parts[i].code, depth = 0, braces = 0, line_start = 1, k;
        for (; *c; c++) {
            if (code && line_start) {   /* a new line: indented by the braces around it */
                if (*c == ' ') continue;
                braces -= *c == '}';
                for (k = 0; k < 4 * braces; k++) irrvol__glsl_put(buffer, capacity, &length, ' ');
                braces += *c == '{';
            } else if (code) {
                braces += (*c == '{') - (*c == '}');
            }
            line_start = 0;
            irrvol__glsl_put(buffer, capacity, &length, *c);
            if (!code) continue;
            depth += (*c == '(') - (*c == ')');
            if (depth == 0 && (*c == ';' || *c == '{' || *c == '}')) {
                irrvol__glsl_put(buffer, capacity, &length, '\n');
                line_start = 1;
            }
        }
    }
    if (buffer && capacity) buffer[length < capacity ? length : capacity - 1] = '\0';
    return length;
}

/* The sizes and section offsets of the export. 0, or -1 when an offset
   would not fit the 32 bits a shader indexes with. */
static int irrvol__gpu_layout(const irrvol *v, uint32_t coeffs, irrvol_gpu_layout *l)
{
    uint64_t hanging = (uint64_t)v->sample_count - v->hanging_begin, at;
    memset(l, 0, sizeof *l);
    l->coefficients = coeffs;
    l->sh_order = coeffs == 4 ? 1u : 2u;
    at = IRRVOL__GPU_HEADER;
    l->cells_at = (uint32_t)at;
    at += 2 * (uint64_t)v->cell_count;
    l->ids_at = (uint32_t)at;
    at += v->id_count;
    l->parents_at = (uint32_t)(at <= UINT32_MAX ? at : 0);
    at += 4 * hanging;
    l->index_count = (size_t)at;
    if (at > UINT32_MAX) return -1;
    at = IRRVOL__GPU_HEADER;
    l->origins_at = (uint32_t)at;
    at += 4 * (uint64_t)v->sample_count;
    l->visibility_at = (uint32_t)(at <= UINT32_MAX ? at : 0);
    at += (uint64_t)v->hanging_begin * v->map_texels * 4;
    l->sh_at = (uint32_t)(at <= UINT32_MAX ? at : 0);
    at += (uint64_t)v->sample_count * 3 * coeffs;
    l->parent_weights_at = (uint32_t)(at <= UINT32_MAX ? at : 0);
    at += 4 * hanging;
    l->data_count = (size_t)at;
    return at > UINT32_MAX ? -1 : 0;
}

static void irrvol__gpu_fill(const irrvol *v, const irrvol_gpu_layout *l, uint32_t *index, float *data)
{
    uint32_t c, s, j;
    int d;
    memset(index, 0, IRRVOL__GPU_HEADER * sizeof(uint32_t));
    memset(data, 0, IRRVOL__GPU_HEADER * sizeof(float));
    index[0] = IRRVOL__GPU_FORMAT;
    for (d = 0; d < 3; d++) {
        index[1 + d] = v->cells[d];
        data[d] = v->lo[d];
        data[3 + d] = v->scale[d];
        data[6 + d] = v->cell_limit[d];
    }
    index[4] = v->sample_count;
    index[5] = v->hanging_begin;
    index[6] = v->vis_res;
    index[7] = l->coefficients;
    index[8] = l->cells_at;
    index[9] = l->ids_at;
    index[10] = l->parents_at;
    index[11] = l->origins_at;
    index[12] = l->visibility_at;
    index[13] = l->sh_at;
    index[14] = l->parent_weights_at;
    data[9] = v->bias;
    for (c = 0; c < v->cell_count; c++) {
        index[l->cells_at + 2 * c] = v->cell[c].offset;
        index[l->cells_at + 2 * c + 1] = v->cell[c].side;
    }
    memcpy(index + l->ids_at, v->ids, v->id_count * sizeof(uint32_t));
    memcpy(index + l->parents_at, v->parents, 4 * ((size_t)v->sample_count - v->hanging_begin) * sizeof(uint32_t));
    memcpy(data + l->origins_at, v->origins, 4 * (size_t)v->sample_count * sizeof(float));
    memcpy(data + l->visibility_at, v->visibility, (size_t)v->hanging_begin * v->map_texels * 4 * sizeof(float));
    for (s = 0; s < v->sample_count; s++)
        for (j = 0; j < l->coefficients; j++)
            memcpy(data + l->sh_at + ((size_t)s * l->coefficients + j) * 3, v->sh + (size_t)s * IRRVOL__SH_FLOATS + 3 * j,
                   3 * sizeof(float));
    memcpy(data + l->parent_weights_at, v->parent_weights,
           4 * ((size_t)v->sample_count - v->hanging_begin) * sizeof(float));
}

IRRVOL_API irrvol_result irrvol_gpu_export(const irrvol *vol, uint32_t sh_order, irrvol_gpu_layout *layout,
                                           uint32_t *index, size_t index_capacity, float *data, size_t data_capacity)
{
    if (!vol || !layout || (sh_order != 1 && sh_order != 2)) return IRRVOL_ERROR_INVALID_ARGUMENT;
    if (irrvol__gpu_layout(vol, sh_order == 1 ? 4u : IRRVOL__SH_COEFFS, layout) != 0) return IRRVOL_ERROR_OUT_OF_MEMORY;
    if (!index && !data) return IRRVOL_OK;   /* sizes only */
    if (!index || !data || index_capacity < layout->index_count || data_capacity < layout->data_count)
        return IRRVOL_ERROR_INVALID_ARGUMENT;
    irrvol__gpu_fill(vol, layout, index, data);
    return IRRVOL_OK;
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
