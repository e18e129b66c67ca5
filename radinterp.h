/* radinterp.h - v0.8.19 - radiosity with per-pixel quadratic irradiance interpolants - public domain or MIT, see end of file

   RADINTERP.H: hierarchical radiosity, ranked discontinuities and quadratic irradiance interpolants evaluated per pixel.

   Hardt's method in two phases. Offline: a hierarchical radiosity solver
   over planar convex patches (chapter 4); an accurate irradiance-at-a-point
   query with exact visibility by backprojection onto the sources (chapter
   6); the discontinuities of the irradiance (shadow boundaries, horizons,
   contacts) ranked by weight, the strongest of which the quadtree leaves
   are triangulated along (chapter 5); one quadratic irradiance interpolant
   per triangle through six point samples at its corners and edge midpoints,
   shared with its neighbours (chapter 3). Online: an ID buffer
   and a barycentric buffer from any rasterizer become radiosity per pixel
   at 5 multiplies and 5 adds a channel (radinterp_shade), or the triangles
   and their coefficients go to a shader. The output mesh is crack-free.

   DO THIS

       #define RADINTERP_IMPLEMENTATION
       #include "radinterp.h"

   in exactly one C or C++ file; include "radinterp.h" without the define
   everywhere else.

   EXAMPLE

       radinterp_material mat[2] = {
           {{0.7f, 0.7f, 0.7f}, {0, 0, 0}, {0, 0, 0}},            // grey wall
           {{0.8f, 0.8f, 0.8f}, {100.f, 100.f, 100.f}, {0, 0, 0}} // emitter: E = pi * Ke
       };                                   // (a third triple tf > 0 makes glass)
       radinterp_desc d = {0};
       radinterp_solution *sol;
       float rgb[3];
       d.positions = xyz;  d.vertex_count = nv;
       d.patches = quads;  d.patch_count = np;    // 4 indices per patch
       d.patch_materials = mat_of_patch;
       d.materials = mat;  d.material_count = 2;
       if (radinterp_solve(&d, &sol) != RADINTERP_OK) ...;
       radinterp_irradiance_at_point(sol, patch, point, NULL, rgb);  // W/m^2

       radinterp_mesh_desc md = {0};
       radinterp_mesh *mesh;
       radinterp_mesh_data data;
       if (radinterp_build_mesh(sol, &md, &mesh) != RADINTERP_OK) ...;
       radinterp_mesh_get_data(mesh, &data);     // triangles and coefficients
       // every frame: rasterize data.positions / data.indices into an ID
       // buffer (triangle index per pixel) and a perspective-correct
       // barycentric buffer (weights of each triangle's 2nd and 3rd corner):
       radinterp_shade(mesh, ids, st, width * height, rgb_pixels);  // B, W/m^2
       radinterp_mesh_destroy(mesh);
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
   callback, and so does a scene whose size (the diagonal of its bounding
   box) lies outside [RADINTERP_MIN_SCENE_SIZE, RADINTERP_MAX_SCENE_SIZE] =
   [1e-17, 1e18] (element areas are floats; results do not depend on the
   scale inside it). Zero-area patches are skipped and counted (info.skipped_patches);
   repeated or collinear corners reduce a quadrilateral to a triangle. Two
   triangles of one material that share an edge and together form a planar
   convex quadrilateral become one patch, as an engine's export of a
   rectangle as two triangles is one surface (info.merged_patches; every
   caller's patch index still names the patch it became part of;
   desc.keep_triangles turns this off).

   GLASS AND SKY

   A material with a transmittance tf > 0 (any channel) is a pane of thin
   glass, as in the other headers, the examples' tracer and the reference
   renderer: light crosses it straight, from either side, keeping tf of
   itself per channel (no refraction, no change of direction); the pane
   also reflects and emits on its front with its own reflectance and
   emission, like any patch. In radiosity the light that reaches a receiver
   x from a source point y is B(y) cos cos / (pi r^2) times the visibility
   V(x, y); with panes, V is no longer 0 or 1 but the product of the tf of
   the panes the segment crosses (0 when an opaque patch lies on it, or
   more than RADINTERP_MAX_GLASS_LAYERS = 16 panes), so the window passes
   the light of the rooms and of the outside at the right strength. This
   is the issue's "a transmitting patch passes a fraction of its received
   radiosity to the other side": for a thin pane, the radiance leaving its
   far side along a ray is tf times the radiance arriving along it, which
   is what a visibility of tf says, without giving the pane a second
   (back) radiosity that would blur the direction the light keeps.
   In the solver, a link whose shadow rays cross panes splits its factor
   in two: ff, the part of the source seen through no pane, and gff, the
   part seen through panes (counted clear), with that light's mean
   transmittance T per channel (from the same rays): the link carries
   F = ff + gff T. Cluster links carry each channel's visible fraction.
   In a point query (IrradianceAtPoint and the mesh's interpolants), such a
   link's source is seen past every blocker with the panes opaque (F_all)
   and past the opaque blockers alone (F_clear), both by the exact
   backprojection, and F = F_all + T (F_clear - F_all) per channel: exact
   where all the light through panes crosses the same panes (a window,
   single or double glazed), T being the link's mean otherwise. Panes
   never enclose geometry, hide one element from another, or belong to a
   convex solid. Shadow rays that may meet a pane find the panes one by
   one with the built-in BVH (desc.trace is used for the links without
   panes among their blockers).

   The sky is radiance arriving from infinity: desc.sky, a constant
   radiance (W/(m^2 sr)), or desc.environment, a latitude-longitude map of
   environment_width x environment_height rgb texels with +y up (row r
   covers theta from +y in [pi r / height, pi (r + 1) / height), column c
   the azimuth phi = atan2(z, x) in [2 pi c / width - pi, 2 pi (c + 1) /
   width - pi); a direction takes its texel's radiance, no filtering: a
   map of one radiance L is the constant sky L). The map is copied. A
   surface at x receives from it

       E_sky(x) = integral over the front hemisphere of L_sky(w) T(x, w) cos theta dw

   with T(x, w) the transmittance of the ray from x along w to infinity (0
   when it meets an opaque patch, the product of the tf of the panes it
   crosses otherwise). It is estimated with the solver's rays:
   desc.sky_rays directions (default 1024) distributed as cos theta / pi
   and stratified (a k x k jittered grid when sky_rays = k^2), E = pi / n
   sum L T. Each element of the solution gets the mean over its area (one
   ray from each of sky_rays stratified points of the element, each along
   its own direction), measured when the element is made, and adds it to
   the irradiance it gathers at every iteration: the sky is a constant
   source, as emission is, and everything it lights passes its light on
   through the links. Transport refinement treats the sky as a source: an
   element over which E_sky varies by more than its tolerance (max - min at
   its corners pulled a fifth toward its centre and at its centre, each
   from the patch's own sky_rays / 4 directions, so that points differ by
   what they see and not by sampling noise) is split, so the patch of light
   under a window gets elements of its size (building_1k_daylight: 7,800
   leaves instead of 4,400; its solve takes 7.6 s of one core's CPU time).
   A point query adds E_sky at the point itself, with the same directions
   for every point of a patch, so the interpolants are smooth. Everything
   is deterministic for any thread count. The estimate's error is that of
   stratified sampling: a window that covers a fraction f of the
   cosine-weighted hemisphere is seen to within about sqrt(perimeter
   strata) / n, e.g. 0.4% of pi L for a box's opening with 4096 rays
   (tests/test_radinterp_glass.c), and a few percent with the default 1024
   for a small window; raise sky_rays for close-ups of sunlit patches. The
   sky's rays cost a point query about 0.1 ms with the default 1024 (the
   glass room of the tests: 8,500 queries per second on one core instead of
   35,000 without a sky; in a building, where a query sums hundreds of
   sources, a small share). The default error bound eps counts the sky's pi
   L as emitted radiosity (see PARAMETERS). Measured against the reference
   (tests/ref_radinterp_glass.c, a closed room with a glass window in its
   ceiling under a sky of radiance (1, 2, 3) and walls of known emission,
   single and double glazing, panes facing in and out, an environment map;
   4096 sky rays): the irradiance at floor points in the window's light and
   off it, and the floor's mean radiosity, all within 2% + 3 reference
   standard errors (the largest 0.63 of that tolerance); with the default
   1024 rays the window's centre is 1.9% off.

   METHOD

   radinterp_solve (chapter 4): one quadtree per patch (quadrilaterals and
   triangles split in four at their edge midpoints); a link between every
   ordered pair of patches that face each other, with its potential blockers
   from shaft culling (Haines and Wallace) through a BVH of the patches; link
   form factors = the mean of eq. 6.1 at a jittered grid of receiver points,
   each scaled by the visible fraction of the source (shadow rays through the
   BVH or desc.trace; a link whose shaft at most 64 triangles reach tests
   just those, see shadow rays inside a shaft in the implementation), with
   horizon clipping of both elements (4.2); Jacobi
   gather + push-pull iterations (4.3); after each, transport refinement
   (4.4.1): a link whose B_src times the spread of the point factors over
   its receiver exceeds its tolerance (eps, or eps_relative of the least
   irradiance over the receiver's lit parts where that is more) is split at
   its larger element, and a link whose source's children differ by more
   than the tolerance / F is split at the source. The least irradiance, not
   the mean, because a link's error lands on every part of its receiver: a
   wall that runs through two rooms, one lit and one dark, would otherwise
   carry errors of 5% of the lit room's light into the dark one. The spread
   is taken at fixed points: the receiver's corners pulled a fifth toward
   its centre, the centre, and the receiver point nearest to the source's
   centre, where the factor peaks when the source is small and close (a
   block standing on a large floor: without that point such a link could
   stay unrefined at a third of its form factor); a receiver cut by the
   source's plane counts zero beyond it, so the link is split until no
   child that cannot see the source takes its light; the spread also
   covers the random points' factors, so the end of a receiver that runs
   past a partition into a darker room splits its link too. The links one
   element gathers share an error budget, RADINTERP_RECEIVER_BUDGET times
   its tolerance: where their errors add up beyond it, the largest are
   split until the rest fit. Their errors do not cancel: the links that
   bring light through one door share its geometry and each spreads its
   light evenly over a receiver that sees the door from near and far, so a
   room lit through a door came out 30-90% too bright in its far corners
   with each link within its own tolerance. A link's share of that budget
   is its transport error plus (since v0.8.4) its source's variation (the spread of the
   source's children times F): a source element that straddles a wall
   between a lit room and a lampless one is seen from the dark side by its
   dark part alone, and hundreds of such links each carrying the lit mean
   add up as the links through a door do; a link the budget marks for its
   source's variation is split at the source. A link whose source is
   partly hidden from its receiver (some shadow ray blocked, or some
   receiver point that sees none of it) measures that variation over the
   source's leaves rather than its children: the receiver may see only the
   darkest or the brightest of them, and a source whose four children each
   straddle the same wall has children alike and leaves that are not
   (building_1k's lampless room: its leaves gathered 8% more from the
   sources' means than from the leaves they see; this took the 90th
   percentile of the points from 18.7% to 17.1% at 3% more links). The
   source's variation is held to a tolerance of its own, whose floor is a
   tenth of eps's by default (eps_source: 0.1% of the mean emitted
   radiosity, both in the split at the source and in the source's part of
   the budget, each error counted in its own tolerances there): splitting a
   source adds links only, while the receiver splits add the leaves the
   mesh pays for. Where eps's floor sets a dim room's tolerance, a tenth of
   it for the sources took building_1k's 90th percentile from 17.1% to
   14.5% (patches beyond 5% + 3 SE 53 -> 45, the lampless room's points
   +15.9% -> +12.7%) for 0.6% more links and 0.02% more leaves; lowering eps
   itself to that floor did as well (11.0%) but at 36% more links and 11%
   more leaves. A lower source floor changes nothing there: the relative
   bound sets every source tolerance below 0.1%. Parts of a
   patch enclosed by geometry resting on it (the floor under a box, the
   strip of floor under a wall) are found by rays (both rays of an opposite
   pair meet back faces) and left out of its radiosity
   (radinterp_leaf.open). The open fraction is measured on an
   8 x 8 grid of the element's points (a 3 x 3 grid missed the strip under
   a wall along most elements' edges), a link's receiver points found
   enclosed are left out of its factor (they saw the enclosed strip of the
   slab above, inside the wall, unblocked), and cluster links deliver to
   the open part only: building_1k's row sums of the factors (B = 1 on
   every face, against rays cast from the leaves) went from 0.966 to 0.981
   on floors and 0.973 to 0.990 on ceilings, and a closed room on slabs
   that run on under its walls (a furnace, B = E / (1 - rho) exactly) from
   +9.9% to +0.35% (test_radinterp). A node whose open points lie on both
   sides of an enclosed band (on a row or column of that grid: the foot of
   a wall standing on a slab that runs under two rooms), or whose child's
   do, holds a strip of each room, and what it gathers, mostly the lit
   room's light, lit the strip of the dark one, which everything in the
   dark room sees: building_1k's upper floor showed 0.19 W/m^2 in the
   lampless room's 4 cm strip beside the partition, against 0.009 a few
   centimetres on, and the partition's dark face twice its reference. Such
   a node may split down to min_area / 16 (two levels below min_area, so
   that walls thinner than the smallest nodes still get leaves on each
   side), and within three levels of min_area its links go to its children
   whatever their error (each of a lit room's many weak links passes the
   error test, and together they carry the room's light across). On
   building_1k this took the patches beyond 5% + 3 SE from 45 to 18, the
   points' median from 2.96% to 2.21%, their 90th percentile from 14.5% to
   8.75% and the largest from 406% to 52% (the strip: 0.0039 W/m^2), for
   2.3x the links and 27% more leaves; the office's patches beyond from 5
   to 3, its points 1.84% and 6.73% for 1.5x the links. Within one level of
   min_area only: 1.06x the links, 38 patches, 2.70%, 12.7%, and the strip
   still at 0.11 W/m^2; at every level: 3.4x the links for 2.15% and 8.60%.

   radinterp_irradiance_at_point (chapter 6): the sum of B_src * F over the
   links of the leaf containing p and of its ancestors. F is eq. 6.1 for the
   source clipped to p's tangent plane and moved push_off behind its plane;
   the links' blockers are culled once more per leaf at solve time (the
   shaft between the leaf and the source); with blockers, every blocker's
   part inside the pyramid from p to the
   source (cut in 3D) is projected onto the source plane: its shadow. A
   source point is hidden exactly when it lies in a shadow, so F is eq. 6.1
   of the source minus eq. 6.1 of the union of the shadows, which is built
   as disjoint convex pieces (each shadow minus the pieces so far; faces
   turned toward p first), eq. 6.1 being additive over a partition. Faces
   of a convex solid (patches joined edge to edge on the hull of their
   corners, found at solve time) turned away from a point outside it add
   nothing to the union and are left out, unless light could enter the
   solid unseen through an open side. Every
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

   radinterp_build_mesh (chapters 5 and 3) reads the solution and leaves it
   unchanged. Discontinuities (5.2-5.4): for every receiver patch and every
   source patch linked to its quadtree, with the union of those links'
   blockers, EV wedges (a source edge and a blocker vertex) and VE wedges (a
   source vertex and a blocker edge) whose plane supports the blocker (EV)
   or the source (VE), traced onto the receiver plane through the blocker
   and clipped to the part of the receiver in front of the source; horizons
   (a linked source's plane splitting the receiver); contacts (an edge of
   another patch lying on the receiver). Weight w = max(d_sb / d_br) * B_src
   over the segment (horizon: 1 * B_src; contact: FLT_MAX); the geometric
   factor is computed once, the weight cached with the radiosity state of
   the solution it was computed for. EEE surfaces, and EV events between two
   blockers, are ignored as in the thesis. Two tests beyond the thesis keep
   a building's mesh to the discontinuities one can see (its section 8.2
   proposes weights that bound the change in radiosity): a source's
   discontinuities are candidates only when B_src times its largest
   unoccluded point form factor on the receiver (at the receiver's corners,
   centroid and point nearest the source) is at least min_discont_contrast
   of the receiver's mean irradiance, since hiding all of the source changes
   the irradiance by no more; and a candidate EV or VE event must happen:
   its generating line (receiver point, blocker feature, source) must be
   clear of other surfaces at one of the segment's middle and quarter
   points, as in the visibility clipping of discontinuity meshing
   (Lischinski, Tampieri and Greenberg 1992), or the segment is not kept
   (where another blocker stands on that line, the edge lies inside another
   shadow, or is a crease of a solid rather than its outline seen from the
   source). On the 1k building these take the mesh's samples from 1.12 M to
   0.37 M; on the office the Embree comparison (ref_radinterp_mesh) is
   unchanged to the third digit. DSets (5.5.4): collinear
   discontinuities of a receiver (direction within 1e-6 rad, offset within
   epsilon * diag) share a line. The mesh keeps its own copy of the
   solution's quadtrees (down to min_leaf_area), restricted so that
   neighbouring leaves of a patch differ by at most one level; every node
   lists the candidate discontinuities crossing its interior, a child the
   part of its parent's list that crosses it (5.5.6). Activation (5.5.7):
   per patch, by descending weight, a candidate is activated when no leaf it
   crosses would then hold more than max_leaf_dsets active DSets, and it is
   then active in every leaf it crosses. Triangulation: one constrained
   Delaunay triangulation per patch with every leaf edge and every active
   discontinuity edge (the union of a DSet's overlapping active
   discontinuities) as constraints, which is the union of the leaves' own
   triangulations. T-vertices (3.6): case A (leaves one level apart) is
   closed by inserting each leaf edge through its neighbour's corner at its
   midpoint, so the larger leaf's triangles take that vertex; case C
   (patches sharing an edge): the outline vertices of all patches (leaf
   corners, discontinuity ends) are welded within weld_distance and every
   patch outline runs through those on its edges where another patch's edge
   runs along it; case B cannot occur. A triangulation that fails its checks
   (outline, area) is redone without the patch's discontinuities (counted in
   info.fallback_patches); a patch that fails them even so (one thinner than
   weld_distance) is left out of the mesh (info.skipped_patches). The
   restriction ignores quarter points that round onto a leaf's own corners
   (an edge a few float steps long). Interpolants (3.3): IrradianceAtPoint
   at each triangle's corners and edge midpoints, one query per point of a
   patch shared by every triangle that meets there (so neighbours agree
   along their common edge), except on a contact discontinuity, where each
   triangle approaches the point from its own centre and so takes its own
   side of the jump; then the closed form of eq. 3.3 for (A, 2B, 2C, D, 2E,
   F) per channel. With refine, representation-based refinement (4.4.2):
   SAMPLES x SAMPLES more points per triangle measure the interpolant's
   error, leaves above refine_eps are split (children inherit their parent's
   clipped DSets), and the pass repeats; unchanged triangles keep their
   samples.

   Online phase (3.4): radinterp_shade(mesh, ids, st, n, rgb) computes
   B(s, t) = E + rho H(s, t) for each pixel from its triangle id and the
   barycentric weights (s, t) of the triangle's 2nd and 3rd corner (as a
   perspective-correct rasterizer or gl_BaryCoord give them; the first
   corner's weight is 1 - s - t); 5 multiplies and 5 adds per channel in
   the form s (A s + 2B t + 2C) + t (D t + 2E) + F (Hardt counts 8
   multiplies for the expanded form). Pixels whose id is not a triangle of
   the mesh are left as they are, so other objects can be drawn around it.
   radinterp_shade_gouraud blends the corner radiosities instead, for
   comparison (the thesis's "Gouraud shading with discontinuities").
   radinterp_shade_span shades a run of pixels of one triangle (a
   rasterizer's span, a run of a visibility buffer) on the calling thread,
   with the triangle's coefficients loaded once and a pixel's channels in one
   SIMD operation: the bits radinterp_shade gives, which shades its own runs
   of equal ids the same way.

   IN A SHADER

   radinterp_mesh_get_data gives positions (shared vertices are bit-identical,
   which a rasterizer's fill rule needs for crack-free coverage), indices
   (counter-clockwise from the front), the patch of each triangle and 18
   floats per triangle: data.coefficients[18 t + 3 k + c] = coefficient k of
   (A, 2B, 2C, D, 2E, F) of B in channel c (E and rho already applied;
   data.irradiance_coefficients has H itself). Upload them as 6 RGB texels
   per triangle and evaluate with the triangle's barycentrics:

       uniform samplerBuffer radinterp_coeff;     // RGB32F, 6 texels per triangle
       vec3 radinterp_radiosity(int tri, vec2 st) // st = weights of corners 2 and 3
       {
           vec3 A  = texelFetch(radinterp_coeff, 6 * tri + 0).rgb;
           vec3 B2 = texelFetch(radinterp_coeff, 6 * tri + 1).rgb;
           vec3 C2 = texelFetch(radinterp_coeff, 6 * tri + 2).rgb;
           vec3 D  = texelFetch(radinterp_coeff, 6 * tri + 3).rgb;
           vec3 E2 = texelFetch(radinterp_coeff, 6 * tri + 4).rgb;
           vec3 F  = texelFetch(radinterp_coeff, 6 * tri + 5).rgb;
           return max(st.x * (A * st.x + B2 * st.y + C2) + st.y * (D * st.y + E2) + F, 0.0);
       }
       // fragment: radiance = radinterp_radiosity(gl_PrimitiveID, st) / 3.14159265
       // with st = gl_BaryCoordEXT.yz, or a flat-interpolated varying pair
       // (0,0), (1,0), (0,1) at the three corners

   data.corner_radiosity holds B at each triangle's corners (Gouraud) and
   data.vertex_radiosity the mean over the corners sharing each vertex (it
   blends patches that meet there; for per-patch values use an unshared
   vertex list with corner_radiosity).

   PARAMETERS (Hardt, appendix A; zero means the default)

       eps                Gur::eps, transport error bound in W/m^2: a link is
                          refined while B_src * (max - min of the point form
                          factors over its receiver) exceeds its tolerance,
                          the larger of eps and eps_relative times the
                          receiver's least irradiance.  default 1% of the mean
                          emitted radiosity (emitted power / total area,
                          the sky counting pi times its mean radiance): a
                          floor under the relative bound, so that unlit
                          corners still get a bound. A source's variation
                          (the split at the source, see METHOD) has a floor
                          a tenth of that by default (it adds links, not
                          leaves); an explicit eps is both floors
       eps_relative       relative transport error: a link's tolerance is at
                          least this fraction of the least irradiance over
                          its receiver's lit parts, so shadows are resolved
                          in dim rooms as in bright ones.  default 0.05;
                          0 (relative bound off) when eps is given and
                          eps_relative is not, so an explicit eps means
                          what it meant before
       min_area           Gur::aeps, no node is split into children smaller
                          than this (m^2), but for nodes divided by the
                          foot of a wall (see METHOD), which may split to a
                          sixteenth of it.          default (diagonal / 200)^2
       rel_error_cutoff   Basis::relErrorCutoff, convergence: every leaf's
                          radiosity changes by less than this fraction in an
                          iteration.                                default 1e-3
       max_iterations     gather/push-pull iterations at most.       default 64
       ff_samples         receiver points per link form factor (a square
                          number gives a jittered grid).  default 9, at most
                          RADINTERP_MAX_FF_SAMPLES (1024)
       visibility_rays    shadow rays per receiver point when shaft culling
                          left blockers (weighted like the form factor).
                          default 8, at most RADINTERP_MAX_VISIBILITY_RAYS (256)
       push_off           Polygon::ffPushOff: sources are moved this far behind
                          their plane in point queries (6.4). default 1e-5 * diag
       nudge              nudgeAmt: a query point moves this far toward
                          `toward` for visibility (6.3).       default 1e-6 * diag
       min_bp_segment     Backprojection::minBPSegment: shorter projected blocker
                          edges are not inserted.             default 1e-9 * diag
       epsilon            _m_eps_f: coordinates closer than epsilon * diag are
                          equal (facing and coplanarity tests). default 1e-6
       planarity_tolerance  see validation.                      default 1e-3
       clustering         RADINTERP_CLUSTERING_ON (the default): the first
                          links join clusters of patches (see METHOD),
                          refined down to patches where they could carry
                          more than a tenth of the receiver's tolerance;
                          RADINTERP_CLUSTERING_OFF: one link per facing
                          pair of patches (quadratic in the patch count)
       keep_triangles     non-zero: triangles are never merged into
                          quadrilateral patches (see SCENE AND UNITS)
       sky, environment   the sky's radiance, constant or a latitude-longitude
                          map (GLASS AND SKY).                default no sky
       sky_rays           rays toward the sky per element and per point
                          query (a square number gives a jittered grid).
                          default 1024, at most RADINTERP_MAX_SKY_RAYS (4096)
       visibility         how point queries find the visible part of a partly
                          hidden source: RADINTERP_VISIBILITY_SHADOWS (the
                          default) or RADINTERP_VISIBILITY_TRIANGULATION
                          (Hardt's CDT and rays, slower; same results).
       point_rest         point queries (IrradianceAtPoint, the mesh's
                          samples) take their sources in decreasing order of
                          what each could carry to the point (B_src times its
                          unoccluded factor there), with exact visibility,
                          until all those left could carry at most this
                          fraction of the irradiance summed so far; those
                          count with the visible fraction the solver
                          measured for their link. The error this makes is
                          at most that fraction of the result (largest
                          channel). At building scale a point sees hundreds
                          of dim sources past doors and furniture: 1/256
                          leaves 44% of the backprojections of the 1k
                          building's mesh undone (11% on the office). FLT_MIN
                          makes every source exact.        default 1/256
   `diag` is the diagonal of the scene's bounding box.

   MESH PARAMETERS (radinterp_mesh_desc; zero means the default)

       min_discont_weight Tree::minDiscontWeight (W/m^2): weaker
                          discontinuities never enter a triangulation.
                          default 1% of the largest patch radiosity (the
                          thesis used 100 W/m^2 for its office; the brightest
                          patch here is the lamp, about 126 W/m^2)
       min_discont_contrast a source's discontinuities are candidates when
                          hiding all of it could change the receiver's
                          irradiance by at least this fraction of its mean
                          (B_src times the source's largest unoccluded point
                          form factor there, over the receiver's mean
                          irradiance). Measured against Embree
                          (ref_radinterp_mesh, LRMS away from emitters
                          without the reference's noise), thesis ranking /
                          1/32 / 1/8: Cornell box 0.0362 / 0.0366 / 0.0371,
                          office 0.0341 / 0.0341 / 0.0344, with the hidden
                          events dropped in all three; samples of the 1k
                          building 595 k / 370 k / 266 k. FLT_MIN keeps
                          every source (the thesis).      default 1/32
       max_leaf_dsets     Tree::maxLeafDSets: active DSets per leaf at most.
                                                     default 10 (the thesis)
       min_leaf_area      the mesh stops where the solution's quadtrees split
                          into nodes smaller than this (m^2), so a fine
                          solution (accurate sources for IrradianceAtPoint)
                          can be meshed coarsely.  default 0: every leaf
       no_discontinuities non-zero: leaves are triangulated without them
       keep_all_discontinuities non-zero: radinterp_mesh_get_discontinuity
                          returns every discontinuity found, for figures
                          and debugging. By default the mesh keeps only the
                          candidates (those that can enter a triangulation,
                          active or not): the others are most of them and
                          no triangle follows them (building_4k: 41.0 M
                          found, 2.1 GB of records, of which 92,446
                          candidates, 4.8 MB). The counts of info are the
                          same either way.                  default 0
       refine             non-zero: representation-based refinement (4.4.2)
       refine_eps         Gur::eps of that refinement: largest difference, in
                          W/m^2 of irradiance, between an interpolant and
                          IrradianceAtPoint.        default the solution's eps
       refine_samples     SAMPLES (appendix A, 8).                 default 3
       refine_passes      passes at most.                          default 8
       refine_min_area    no leaf is split into children smaller than this
                          (m^2).               default the solution's min_area
       weld_distance      outline vertices of neighbouring patches closer
                          than this are one vertex (m). default 1e-6 * diag

   CONFIGURATION MACROS

       RADINTERP_STATIC          make every function static (private to one file)
       RADINTERP_API             linkage of public functions (default: extern)
       RADINTERP_MALLOC, RADINTERP_FREE  replace malloc/free (define both or neither)
       RADINTERP_BVH_BINS        SAH bins of the built-in BVH (default 16)
       RADINTERP_BVH_SIMD        1 (default): SSE2 (x86-64) or NEON (AArch64) BVH kernels
                                 and shading kernel (radinterp_shade, radinterp_shade_span),
                                 and the SSE2 or AVX form factor kernel of point queries
                                 (where the compiler cannot contract a * b + c: no FMA, or
                                 GCC with -std=c99 or similar) when the compiler offers
                                 them; 0: the portable scalar
                                 kernels only (the same hits and radiosities, bit for bit)
       RADINTERP_RECEIVER_BUDGET the links one element gathers may err by this many of its
                                 tolerances together (default 16; see METHOD). 8 halved
                                 the 90th percentile error of building_1k's points against
                                 Embree's (27% -> 12%) at 3x the office's links, 5x its
                                 solve time and 2x its mesh time; 16 takes it to 18% at
                                 1.1-1.5x the links (measured before the budget counted
                                 the sources' variation, except the 18%)
       RADINTERP_CPU_SECONDS()   the process's CPU time in seconds, negative when there is no
                                 clock; paces progress calls (THREADS). Default: clock()

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

       radinterp_result radinterp_build_mesh(const radinterp_solution *s, const radinterp_mesh_desc *desc,
                                    radinterp_mesh **out);
                                    discontinuity mesh with one quadratic interpolant per triangle
       void radinterp_mesh_destroy(radinterp_mesh *m);
       void radinterp_mesh_get_info(const radinterp_mesh *m, radinterp_mesh_info *info);
                                    counts (discontinuities found/active, leaves, triangles, samples)
       void radinterp_mesh_get_data(const radinterp_mesh *m, radinterp_mesh_data *data);
                                    the arrays: positions, indices, patches, coefficients, radiosities
       uint32_t radinterp_mesh_discontinuity_count(const radinterp_mesh *m);
       radinterp_result radinterp_mesh_get_discontinuity(const radinterp_mesh *m, uint32_t i,
                                    radinterp_discontinuity *d);   segment, kind, weight, active
                                    (the candidates; every one found with keep_all_discontinuities)
       uint32_t radinterp_mesh_leaf_count(const radinterp_mesh *m);
       radinterp_result radinterp_mesh_get_leaf(const radinterp_mesh *m, uint32_t i, radinterp_mesh_leaf *leaf);
                                    a leaf, its DSets and its triangles
       void radinterp_mesh_set_parallel_for(radinterp_mesh *m, parallel_for, void *user);
                                    the job system of radinterp_shade
       void radinterp_fit_quadratic(const float r[6], float coefficients[6]);
                                    eq. 3.3: (A, 2B, 2C, D, 2E, F) from six samples
       radinterp_result radinterp_eval(const radinterp_mesh *m, uint32_t triangle, float s, float t,
                                    float rgb[3]);   radiosity B at barycentric (s, t)
       radinterp_result radinterp_eval_irradiance(const radinterp_mesh *m, uint32_t triangle, float s,
                                    float t, float rgb[3]);   the interpolant H(s, t)
       radinterp_result radinterp_shade(const radinterp_mesh *m, const uint32_t *triangle_ids,
                                    const float *st, size_t count, float *rgb_out);
                                    ID + barycentric buffer -> radiosity per pixel
       radinterp_result radinterp_shade_gouraud(... same ...);   the same, Gouraud-shaded
       radinterp_result radinterp_shade_span(const radinterp_mesh *m, uint32_t triangle, const float *st,
                                    size_t count, float *rgb_out);
                                    a run of pixels of one triangle (a visibility buffer's run, a
                                    rasterizer's span): the bits radinterp_shade gives them, the
                                    coefficients loaded once, each pixel's channels in one SIMD
                                    evaluation (SSE2/NEON with RADINTERP_BVH_SIMD, else the scalar
                                    kernel); on the caller's thread. INVALID_ARGUMENT, rgb_out left
                                    as it was: m NULL, triangle not below the triangle count, st or
                                    rgb_out NULL with count > 0. Contract: st holds 2 * count finite
                                    floats, rgb_out 3 * count
       radinterp_result radinterp_mesh_save(const radinterp_mesh *m, radinterp_write_fn write, void *user);
       radinterp_result radinterp_mesh_load(const radinterp_allocator *a, radinterp_read_fn read, void *user,
                                    radinterp_mesh **out);
       radinterp_result radinterp_mesh_save_to_memory(const radinterp_mesh *m, const radinterp_allocator *a,
                                    void **data, size_t *size);
       radinterp_result radinterp_mesh_load_from_memory(const void *data, size_t size,
                                    const radinterp_allocator *a, radinterp_mesh **out);
       void radinterp_free_memory(const radinterp_allocator *a, void *data);

   CHECKS AND CONTRACTS

   Every function checks what it can and returns INVALID_ARGUMENT (a
   query: zeros in its output) instead of reading or writing past it; what
   it cannot check is the caller's contract: an array holds as many
   elements as its count says, callbacks behave as documented, objects are
   not used after destroy, and the THREADS rules.

     radinterp_solve(desc, &s)  Checks: out and desc non-NULL; positions,
         patches, materials non-NULL with non-zero counts; position_stride 0
         or at least 12; patch_count <= 2^30; every parameter finite and not
         negative; ff_samples, visibility_rays within their limits;
         clustering and visibility known; allocator both callbacks or none;
         every index < vertex_count (the 4th may be RADINTERP_NO_VERTEX);
         every used vertex finite; every material id < material_count;
         reflectance and transmittance in [0, 1], emission finite and >= 0;
         sky finite and >= 0; environment NULL, or 1 to
         RADINTERP_MAX_ENVIRONMENT_SIZE texels a side, every texel finite
         and >= 0;
         sky_rays <= RADINTERP_MAX_SKY_RAYS; quadrilaterals
         planar and convex; the scene's size in [RADINTERP_MIN_SCENE_SIZE,
         RADINTERP_MAX_SCENE_SIZE]; not every patch of zero area. Zero-area
         patches are skipped and counted. Contract: positions holds
         vertex_count vertices at position_stride, patches 4 * patch_count
         indices, patch_materials patch_count ids (or NULL), materials
         material_count, environment 3 * width * height floats; patches do
         not interpenetrate. The solution copies
         what it keeps: the caller's arrays may go once it returns. CANCELLED
         when progress asks, OUT_OF_MEMORY when an allocation fails: nothing
         is leaked and *s is NULL.
     radinterp_solution_destroy(s), radinterp_mesh_destroy(m)   NULL: nothing.
     radinterp_solution_info(s, &info), radinterp_mesh_get_info(m, &info),
     radinterp_mesh_get_data(m, &data)   NULL object: zeros.
     radinterp_patch_radiosity(s, patch, rgb)   Checks: s, rgb non-NULL;
         patch < patch_count and not skipped. Patch indices are the caller's.
     radinterp_get_leaf(s, i, &leaf), radinterp_mesh_get_leaf(m, i, &leaf),
     radinterp_mesh_get_discontinuity(m, i, &d)   Checks: object and output
         non-NULL, i below the count.
     radinterp_irradiance_at_point(s, patch, p, toward, rgb),
     radinterp_radiosity_at_point(...)   Checks: s, p, rgb non-NULL; patch
         valid as above; p (and toward when given) finite. Contract: p lies on
         the patch (it is used as given, not projected), toward on the patch.
         OUT_OF_MEMORY (rgb still the best estimate) when a large
         triangulation cannot get memory.
     radinterp_form_factor_point_polygon(p, n, verts, count)   0 for NULL
         arguments, count < 3, non-finite input or a zero normal. Contract:
         verts holds count xyz vertices of a planar convex polygon.
     radinterp_build_mesh(s, desc, &m)   Checks: s, desc, out non-NULL;
         parameters finite and not negative; max_leaf_dsets <= 4096,
         refine_samples and refine_passes <= 64; allocator both or none.
         Contract: s is a solution from radinterp_solve, left unchanged
         (several meshes may be built from it at once). CANCELLED and
         OUT_OF_MEMORY as for the solve.
     radinterp_fit_quadratic(r, c)   NULL: nothing. Contract: r holds 6 floats.
     radinterp_eval(m, tri, s, t, rgb), radinterp_eval_irradiance(...)   Checks:
         m, rgb non-NULL, tri < triangle count, s and t finite (any finite
         (s, t) is evaluated: the quadratic extends past the triangle).
     radinterp_shade(m, ids, st, count, rgb_out), radinterp_shade_gouraud(...)
         Checks: m non-NULL; ids, st, rgb_out non-NULL when count > 0. Pixels
         whose id is not a triangle of the mesh are left as they are.
         Contract: ids holds count ids, st 2 * count finite floats, rgb_out
         3 * count floats.
     radinterp_shade_span(m, triangle, st, count, rgb_out)   Checks: m
         non-NULL, triangle < triangle count, st and rgb_out non-NULL when
         count > 0; rgb_out is left as it was when a check fails. Contract:
         st holds 2 * count finite floats, rgb_out 3 * count floats.
     radinterp_mesh_set_parallel_for(m, fn, user)   NULL m: nothing. Not
         while radinterp_shade runs on the mesh.
     radinterp_mesh_save(m, write, user), radinterp_mesh_save_to_memory(m, a,
         &data, &size)   Checks: all non-NULL, allocator both or none; IO when
         write fails. radinterp_free_memory(a, data) frees with the allocator
         the save used.
     radinterp_mesh_load(a, read, user, &m), radinterp_mesh_load_from_memory(
         data, size, a, &m)   Input is hostile: every size, index and float
         checked before use, the CRC at the end: CORRUPT_DATA for anything
         off, VERSION for another format version, never a crash. A mesh is
         read from the start of the buffer; bytes after its CRC are left
         alone (objects can be packed one after another).

   SAVED MESHES

   radinterp_mesh_save writes magic "RADIMESH", RADINTERP_FILE_FORMAT_VERSION,
   the payload size, the payload (positions, triangles, irradiance
   coefficients, each patch's reflectance and emission, discontinuities,
   leaves, build statistics; little-endian, field by field) and a CRC-32.
   The loader checks every size against the payload before allocating and
   every index and float: truncated or corrupted data gives
   RADINTERP_ERROR_CORRUPT_DATA (another format version
   RADINTERP_ERROR_VERSION), never a crash. A loaded mesh shades and exports
   like a built one (it needs no solution).

   THREADS

   radinterp_solve runs its independent work (link form factors, open
   fractions, gathers, push-pull) through desc.parallel_for when given;
   results are bit-identical for any thread count. A trace callback must then
   be thread-safe. Queries on a finished solution are const and may run from
   many threads at once; each uses up to about 160 KB of stack (its
   triangulation moves to the allocator only when it outgrows 32 KB; 20 KB
   rank its sources).
   radinterp_build_mesh samples its interpolants through
   mesh_desc.parallel_for (jobs of 1 sample point, up to 512 a batch;
   before the samples, while discontinuities are found and patches
   triangulated, progress is called once a patch with (0, 1)); the mesh is
   bit-identical for any thread count.
   Progress is called from the calling thread, between batches of jobs,
   never concurrently with itself. A batch is sized from the last one's cost
   so that it takes about progress_interval seconds of the process's CPU
   time (default 0.25; RADINTERP_CPU_SECONDS): however costly the jobs, a
   slow region shrinks the batches rather than stretching the gap. The
   serial stretches between batches call progress too once the interval has
   passed (in the mesh build, a receiver's discontinuity search between its
   sources, every 8 blockers and every 8 event tests, the grouping of its
   discontinuities into DSets every 64 of them, the quadtrees' copy and
   restriction every 64 nodes, a pass's activation, segments and outlines
   once a patch; in the solve, refinement's pass over the links, the shaft
   queries of a wave of split cluster links, installing the new links, an
   iteration's gathers): on building_16k the solve's took up to 1.8 s of
   CPU time with v0.8.6; on building_4k the mesh's grouping of one receiver
   8.2 s, one source's event tests 9.3 s, the quadtrees and the first
   pass's steps before its samples 6.6 s. The batches never change a
   result.
   bench_radinterp_building's longest gap on building_1k, one thread: 0.64 s
   with v0.8.5's fixed batches, 0.46 s. radinterp_shade splits
   its pixels into jobs of 16384 through the mesh's parallel_for (the
   build's, or radinterp_mesh_set_parallel_for). Queries on a mesh are const.

   LIMITS

   Patches are planar convex polygons of 3 or 4 vertices (curved surfaces must
   be tessellated by the caller). Glass is thin and straight-through: no
   refraction, no caustics, no frosted glass, at most 16 panes along a ray;
   the sky is sampled, not integrated exactly (GLASS AND SKY). Links are directional (one per receiver and
   source); the first links join clusters of patches (see clusters in the
   implementation), so the initial linking is no longer quadratic in the
   patch count, but with the default relative tolerances the refined
   solution of a building is fine and large. Clustering changes the path
   refinement takes, not the tolerance: on the Cornell box the clustered and
   unclustered solves differ by 0.6% on average over the patches (2% at
   most, where another seed moves a patch by 1%), but on the office the
   lamp's pole, which touches the lamp shade, comes out 5% darker clustered
   (clustering OFF for such a scene). Measured on a 2-core machine
   (tests/bench_radinterp_building.c, one thread, thread CPU time, before
   the refinement estimate's nearest point was added: it adds about 15% of
   links on the Cornell box):
   building_1k (1,250 triangles) solves in about 9 s (23,000 leaves, 212,000
   links, 210 MB held, 450 MB peak); building_4k (4,282 triangles) in about
   105 s (65,000 leaves, 684,000 links and 150,000 cluster links, 2.4 GB
   held, 2.7 GB peak, when the solution kept the per-leaf blocker lists).
   The shadow rays of a link whose shaft few triangles reach test just
   those (shadow rays inside a shaft, in the implementation), and a partly
   enclosed node tests its sample points for enclosure once for all its
   links: the solution is bit-identical, and building_1k solves in 0.81x
   the CPU time (11.6 s against 14.3 s, one thread), building_4k in 0.93x
   (68.4 s against 73.6 s one thread; 70.1 s against 73.7 s of wall time
   on 2 threads; 1.71 M links, 96,827 leaves, 64 iterations), the office
   in 0.96x (measured outside make bench, README).
   radinterp_info says where the memory goes (link_bytes, leaf_list_bytes):
   on building_4k with v0.8.2, 2,221 MB held, of which the leaf lists
   2,066 MB (65.4 M entries of 16 bytes, 1,046 MB, and 255 M blockers,
   1,021 MB), the links 75 MB and their blockers 50 MB (12.5 M, 14.5 per
   link that has any), the nodes 22 MB; on building_1k 273 MB, the leaf
   lists 233 MB (1,818 MB and 172 MB once equal lists were shared). The
   solution no longer keeps them (leaf_list_bytes is 0): a point query
   filters each link's blockers for its own leaf as it reaches the link,
   and the mesh build builds the lists of the leaves a run of its samples
   reads, at most RADINTERP__LEAF_BATCH_BYTES (16 MB) a batch, and frees
   them after those samples (radinterp_mesh_info.leaf_list_bytes: the
   largest batch). Results are bit-identical to the kept lists'. building_
   1k's solution went from 218 MB to 42 MB, the office's from 30 MB to
   8 MB (see README for the times and peaks). radinterp_irradiance_at_point
   pays for the filtering: 0.66-0.83x the calls per second it made with the
   lists kept (office and building_1k, one thread). The
   mesh build does not finish in reasonable time at that scale: a point
   query in a building sums hundreds of partly hidden sources (about 620 a
   point on building_4k, 155 queries per second), and the mesh samples six
   points per triangle of every leaf (even one leaf per patch would take
   tens of thousands of queries). For such scenes use the solution's leaves
   (radinterp_get_leaf, radinterp_patch_radiosity); the office (55
   polygons) meshes in about 15 s of one core. Radiosity is constant over each element,
   so points a few millimetres from a corner, or at the foot of an object, see
   their nearest sources at the elements' mean: expect errors of several
   percent there (about 2% on average elsewhere in the Cornell box with
   eps = 5 mW/m^2). With the defaults on building_1k (tests/
   ref_radinterp_building.c, against Embree) the points' median error is
   4.0% and their 90th percentile 18% (3.6% and 20% before the budget
   counted the sources' variation; 3.8% and 27% before the receiver's
   error budget): the far corner of a room without lamps, lit through its
   door and stair opening, is still 10-50% too bright (90% before), and
   the lit rooms beside it 5-10% too dark. These are errors of the
   solution, not of the point query: integrating the leaves' radiosities
   from the point (path-traced, each hit at its leaf's B) gives the worst
   points' errors within a few percent of the query's. A signed error
   budget at each receiver's corners and centre, with 2 tolerances, took
   the building's 90th percentile to 15% and the office's to 5.8% (median
   1.6%), but at 2x and 4x the links and 3x and 14x the solve time, so it
   is not the default. RADINTERP_RECEIVER_BUDGET 8 took the 90th
   percentile to 12% at 2.3x the links of the default. A point query costs a shadow union per partly visible
   source: about 15,000 per second on one core on the office scene, where
   nearly every point has one (about 28 such sources of 52, 3 shadows each
   once the faces of convex solids turned away from the point are left
   out), and about 500,000 per second where none is; with the triangulation
   method about 2,300.

   The mesh build costs a point query per vertex and edge midpoint of its
   triangles (more with refine), about 2.2 per triangle: the office's 37,879
   triangles take 85,051 queries (131,571 before v0.7.0 dropped hidden and
   faint discontinuities, 357,456 before v0.6.0 shared them), nearly all of
   the build time. building_1k's mesh needs about 370,000 queries (1.12 M
   before v0.7.0) at about 2,000 per second of one core (185 s; v0.7.0:
   about 1,200, before a source's parts shared one union of shadows):
   minutes on two threads, too slow still for a level loaded at run time.
   The build's memory: the mesh keeps its candidate discontinuities
   (radinterp_mesh_get_discontinuity; every one found with
   keep_all_discontinuities), 52 bytes each, in blocks of 16,384 that the
   build fills and the mesh takes over (the last one trimmed to its
   records); the build's own records (104 bytes) are kept only for the
   candidates, and for one receiver's discontinuities while they are
   grouped into DSets (the grouping needs them all for the lines it draws).
   building_1k finds 2.54 M, of which 23,269 are candidates: its mesh holds
   59 MB (190 MB with every discontinuity), and its build's allocations
   beyond the solution peak at 133 MB (264 MB keeping every one, 643 MB
   when every one was held in one growing array of records), the same mesh
   to the bit; build_bytes agrees with an allocator's count within 0.1 MB
   on the office (31.6 MB keeping every one, 29.3 MB by default).
   building_4k finds 41.0 M (92,446 candidates, 5.35 M DSets): kept, they
   were a list of 2.1 GB, and the DSets' lines take 0.34 GB; the receiver
   with the most discontinuities holds about 1.75 GB more while it is
   grouped (measured keeping every one: 4.27 GB beyond the solution, which
   then still kept its leaf lists, before the first sample). In one array
   the records take 3.9 GB there, and 9.7 GB while it doubles (computed;
   v0.8.6 reached 8.2 GB of resident memory).
   radinterp_mesh_info.build_bytes reports the peak of the build's arrays.
   The leaf lists mark the links a whole leaf cannot see: one
   opaque blocker turned toward the leaf meets every segment from the
   leaf's box (grown by the lists' margin) to the source, as the near face
   of a wall does between a leaf and a lamp of the next room. Point queries
   skip those sources' backprojections, which found them hidden anyway,
   and the lists drop their blockers: 10.5 M of the 56 M sources
   building_1k's mesh samples evaluate exactly (the office: 0.33 M of
   7.4 M), and 35% of its lists' blockers (solution 219 MB instead of
   271 MB); its mesh built 1.14x faster (two pairs in one process, thread
   CPU time: 1.14x and 1.15x), the office's 1.03x, while the test makes the solve 1.16x
   slower (the office's 1.06x). Results are equal up to rounding (the
   office's mesh to the bit; on building_1k 14 of 20,000 random points
   moved, by at most 3e-14 of their irradiance, and 561 of the mesh's
   2.87 M interpolant coefficients, by at most 3.7e-9 W/m^2, most likely
   because a skipped source leaves the query's hints as they were).
   Of the 45 M unions of shadows building_1k's mesh samples then build
   (v0.8.2, counted in an instrumented copy), 16.0 M end with the source
   hidden; 10.0 M of those by one shadow the exact containment test had
   missed (a wall spanning the whole pyramid from the point over the source
   is clipped by the pyramid's sides to the source's outline, its corners
   moved by rounding, often just inside), 6.0 M by two or more shadows,
   only 0.67 M of them all in one plane (so a leaf verdict from coplanar
   pieces of a wall would reach few); 18.4 M end partly visible, 6.1 M
   clear, 3.3 M hidden by one shadow or the hints, 1.45 M go to the
   triangulation. Since v0.8.3 a staged shadow that leaves less than 1e-12
   of the source's area (what the union counts as rounding) hides it at
   once, before the other blockers are staged: building_1k's mesh built
   1.04x and 1.09x faster (two pairs in one process, thread CPU time, load
   5-8), the office's as fast (median of 5 pairs' ratios 1.00). The
   meshes' vertices and triangles are the same to the bit; 9,898 of
   building_1k's 3.06 M interpolant coefficients moved, by at most 6e-8
   W/m^2 (its largest is 6.65), and 169 of the office's 739,494, by at most
   1.5e-8 W/m^2: the union, which drops parts below its rounding size and
   triangulates when a later shadow cannot be represented, had left a
   sliver of such a source or triangulated it. What remains is mostly
   staging: the unions then take 128 M shadows, 47 M of them of faces
   turned away from the point, and of the 181 M such faces the queries
   examine, 66 M belong to no closed solid (most likely the generator's
   wall pieces and furniture: boxes without the faces that touch another
   piece, the slab or another wall), so radinterp__back_face_covered
   cannot leave them out.
   Interpolants are only as accurate as IrradianceAtPoint, whose
   sources are the solution's elements: for a more accurate image solve
   with a smaller eps and mesh with a larger min_leaf_area. Discontinuity
   edges that nearly graze a patch outline can make a triangulation fail
   its checks; the patch is then meshed without its discontinuities. The
   output has no T-vertices where patches share an edge or part of one; a
   patch edge that ends on another patch's face (a wall meeting a floor
   away from the floor's edge) needs none.

   PAPER

       Stephen L. Hardt, High Fidelity Radiosity Rendering at Interactive Rates, M.Eng. thesis, MIT, 1996.
       Hanrahan, Salzman, Aupperle, A Rapid Hierarchical Radiosity Algorithm, SIGGRAPH 1991.
       Haines, Wallace, Shaft Culling for Efficient Ray-Traced Radiosity, 1991.
       Shewchuk, Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates, 1997.
*/
#ifndef RADINTERP_H
#define RADINTERP_H

#define RADINTERP_VERSION_MAJOR 0
#define RADINTERP_VERSION_MINOR 8
#define RADINTERP_VERSION_PATCH 19
#define RADINTERP_FILE_FORMAT_VERSION 2   /* of saved meshes */

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

#define RADINTERP__POINT_REST (1.0 / 256.0)   /* default of radinterp_desc.point_rest */
#define RADINTERP__MIN_CONTRAST (1.0 / 32.0)  /* default of radinterp_mesh_desc.min_discont_contrast */
#define RADINTERP__PROGRESS_INTERVAL 0.25     /* default of progress_interval: seconds of CPU time */

/* Limits of radinterp_desc.ff_samples and visibility_rays: a link costs
   ff_samples x visibility_rays shadow rays, so larger values would run for
   hours; they give RADINTERP_ERROR_INVALID_ARGUMENT. */
#define RADINTERP_MAX_FF_SAMPLES 1024u
#define RADINTERP_MAX_VISIBILITY_RAYS 256u
/* The scene's size (diagonal of its bounding box) radinterp_solve accepts:
   element areas are floats, so a scene of 1e20 m (areas past FLT_MAX) or of
   1e-20 m (areas below the normal floats) cannot be represented. Each limit
   is ten times inside the scales measured to work (the Cornell box scaled
   by 1e19 and by 1e-18 solves to the same radiosities). */
#define RADINTERP_MAX_SCENE_SIZE 1e18
#define RADINTERP_MIN_SCENE_SIZE 1e-17
/* Glass and sky (GLASS AND SKY): panes a ray crosses (the next one blocks
   it), texels a side of desc.environment, and desc.sky_rays. */
#define RADINTERP_MAX_GLASS_LAYERS 16u
#define RADINTERP_MAX_ENVIRONMENT_SIZE 65536u
#define RADINTERP_MAX_SKY_RAYS 4096u

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
    float transmittance[3];/* thin glass: this share of the light passes straight through, each in [0, 1];
                              0 = opaque (see GLASS AND SKY) */
} radinterp_material;

/* How IrradianceAtPoint finds the part of a partly hidden source that a
   point sees (desc.visibility). Both give the exact visible form factor; the
   triangulation is Hardt's method (6.2.3), kept for comparison. */
typedef enum radinterp_visibility {
    RADINTERP_VISIBILITY_DEFAULT = 0,          /* = RADINTERP_VISIBILITY_SHADOWS */
    RADINTERP_VISIBILITY_SHADOWS = 1,          /* F(source) - F(union of the blockers' shadows), shadows as convex pieces */
    RADINTERP_VISIBILITY_TRIANGULATION = 2     /* CDT of the projected blocker edges, one ray per region */
} radinterp_visibility;

/* How the solver makes its first links (desc.clustering). */
typedef enum radinterp_clustering {
    RADINTERP_CLUSTERING_DEFAULT = 0,  /* = RADINTERP_CLUSTERING_ON */
    RADINTERP_CLUSTERING_ON = 1,       /* a cluster tree over the patches, linked from the top down (scales
                                          to buildings) */
    RADINTERP_CLUSTERING_OFF = 2       /* one link per pair of facing patches (quadratic in the patch count) */
} radinterp_clustering;

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
    float eps_relative;
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
    float point_rest;                  /* share of a point's irradiance left to the links' visible fractions */
    radinterp_clustering clustering;   /* initial linking, see PARAMETERS */
    int keep_triangles;                /* non-zero: triangles are never merged into quadrilaterals */
    uint64_t seed;                     /* random choices (sample points); results depend only on it */

    /* the sky (GLASS AND SKY): radiance, W/(m^2 sr), arriving from infinity */
    float sky[3];                      /* constant sky radiance; 0 = no sky */
    const float *environment;          /* optional sky map replacing sky: rgb per texel, latitude-longitude with
                                          +y up, row 0 at the zenith (copied); NULL = the constant sky */
    uint32_t environment_width;        /* texels per row, 1..RADINTERP_MAX_ENVIRONMENT_SIZE */
    uint32_t environment_height;       /* rows, 1..RADINTERP_MAX_ENVIRONMENT_SIZE */
    uint32_t sky_rays;                 /* rays toward the sky per element and per point; 0 = 1024 */

    /* optional callbacks */
    radinterp_trace_fn trace;          /* NULL: the built-in BVH over the patches */
    void *trace_user;
    radinterp_allocator allocator;
    void (*parallel_for)(void *user, radinterp_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    int (*progress)(void *user, uint64_t done, uint64_t total);  /* non-zero cancels */
    void *progress_user;
    float progress_interval;           /* seconds of CPU time between progress calls; 0 = 0.25 (THREADS) */
    void (*log)(void *user, const char *message);
    void *log_user;
} radinterp_desc;

typedef struct radinterp_solution radinterp_solution;

typedef struct radinterp_info {
    uint32_t patch_count;        /* patches given */
    uint32_t skipped_patches;    /* zero-area patches left out */
    uint32_t merged_patches;     /* triangles merged into another to make a quadrilateral patch */
    uint32_t node_count;         /* quadtree nodes, roots included */
    uint32_t leaf_count;         /* quadtree leaves (elements) */
    uint32_t link_count;         /* links between quadtree nodes (one per receiver and source) */
    uint32_t cluster_count;      /* clusters above the patches */
    uint32_t cluster_link_count; /* links with a cluster at either end */
    uint64_t culled_links;       /* links dropped because every ray between their ends was blocked */
    uint64_t blocker_entries;    /* sum of the links' blocker-list lengths */
    uint32_t iterations;         /* gather/push-pull iterations run */
    int converged;               /* the last iteration changed no leaf by more than rel_error_cutoff */
    float max_relative_change;   /* of the last iteration */
    uint64_t shadow_rays;        /* rays cast for link visibility */
    size_t bytes;                /* memory held by the solution */
    uint32_t glass_patches;      /* patches that pass light (GLASS AND SKY) */
    size_t link_bytes;           /* of bytes: the links and their blocker lists */
    size_t leaf_list_bytes;      /* of bytes: the leaf lists the solution keeps: 0 since they are built where used
                                    (a point query's per link, the mesh build's per batch: radinterp_mesh_info) */
    uint64_t leaf_list_entries;  /* (leaf, link) entries of the leaf lists kept: 0 */
    uint64_t leaf_blocker_entries; /* blockers the leaf lists kept hold: 0 */
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

/* ---- discontinuity mesh, quadratic interpolants, per-pixel shading ------ */

typedef int (*radinterp_write_fn)(void *user, const void *bytes, size_t n); /* 0 = ok */
typedef int (*radinterp_read_fn)(void *user, void *bytes, size_t n);        /* 0 = all n bytes read */

typedef struct radinterp_mesh radinterp_mesh;

typedef struct radinterp_mesh_desc {
    /* parameters, see MESH PARAMETERS above; zero = default */
    float min_discont_weight;    /* Tree::minDiscontWeight (W/m^2) */
    float min_discont_contrast;  /* least irradiance change a source's discontinuities can make, over the mean */
    uint32_t max_leaf_dsets;     /* Tree::maxLeafDSets */
    float min_leaf_area;         /* the mesh stops where the solution's quadtrees split into smaller nodes (m^2) */
    int no_discontinuities;      /* non-zero: leaves are triangulated without discontinuities */
    int keep_all_discontinuities; /* non-zero: the mesh returns every discontinuity found, not only the candidates */
    int refine;                  /* non-zero: representation-based refinement (4.4.2) */
    float refine_eps;            /* Gur::eps of that refinement, W/m^2 of irradiance */
    uint32_t refine_samples;     /* SAMPLES: SAMPLES x SAMPLES test points per triangle */
    uint32_t refine_passes;      /* refinement passes at most */
    float refine_min_area;       /* leaves are not split into children smaller than this (m^2) */
    float weld_distance;         /* outline vertices of neighbouring patches closer than this are one (m) */

    /* optional callbacks */
    radinterp_allocator allocator;
    void (*parallel_for)(void *user, radinterp_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    int (*progress)(void *user, uint64_t done, uint64_t total);  /* non-zero cancels */
    void *progress_user;
    float progress_interval;           /* seconds of CPU time between progress calls; 0 = 0.25 (THREADS) */
    void (*log)(void *user, const char *message);
    void *log_user;
} radinterp_mesh_desc;

typedef struct radinterp_mesh_info {
    uint32_t triangle_count;
    uint32_t vertex_count;
    uint32_t leaf_count;              /* leaves of the restricted quadtrees */
    uint32_t patch_count;
    uint32_t discontinuities;         /* found: the four kinds below */
    uint32_t ev, ve, horizon, contact;
    uint32_t dsets;                   /* lines carrying collinear discontinuities, over all patches */
    uint32_t candidates;              /* discontinuities with weight >= min_discont_weight and a source
                                         reaching min_discont_contrast */
    uint32_t active_discontinuities;
    uint32_t kept_discontinuities;    /* the records the mesh returns (radinterp_mesh_get_discontinuity): the
                                         candidates, or every one found with keep_all_discontinuities */
    uint32_t active_leaf_dsets;       /* sum over leaves of their active DSets */
    uint32_t max_leaf_active_dsets;   /* the most on one leaf (<= max_leaf_dsets) */
    uint32_t balance_splits;          /* leaves split to restrict the quadtrees */
    uint32_t hanging_vertices;        /* T-vertices inside patches closed (case A) */
    uint32_t seam_vertices;           /* outline vertices taken from neighbouring patches (case C) */
    uint32_t fallback_patches;        /* patches triangulated without their discontinuities */
    uint32_t skipped_patches;         /* patches left out of the mesh: no triangulation of them passed its
                                         checks (thinner than weld_distance) */
    uint32_t refine_passes;           /* representation-based passes run */
    uint32_t refined_leaves;          /* leaves they split */
    float max_fit_error;              /* largest representation error measured (refine only) */
    uint64_t samples;                 /* IrradianceAtPoint calls of the build */
    size_t leaf_list_bytes;           /* the largest batch of leaf lists the samples held at once (the lists are
                                         built for the leaves of a run of samples and freed after them) */
    size_t bytes;                     /* memory held by the mesh */
    size_t build_bytes;               /* the most the build held at once: its arrays at each step (the
                                         discontinuities found, the candidates, the quadtrees, a pass, a batch
                                         of leaf lists) and the mesh; 0 for a loaded mesh */
} radinterp_mesh_info;

/* The mesh as arrays an engine can upload. Pointers stay valid until
   radinterp_mesh_destroy. */
typedef struct radinterp_mesh_data {
    uint32_t vertex_count, triangle_count;
    const float *positions;          /* 3 per vertex; shared vertices are bit-identical */
    const uint32_t *indices;         /* 3 per triangle, counter-clockwise seen from the patch's front */
    const uint32_t *triangle_patch;  /* the caller's patch index of each triangle */
    const uint32_t *triangle_leaf;   /* leaf of each triangle (radinterp_mesh_get_leaf) */
    const float *coefficients;       /* 18 per triangle: radiosity B(s, t) = E + rho H(s, t) as
                                        (A, 2B, 2C, D, 2E, F), each an rgb triple: [6][3] */
    const float *irradiance_coefficients;  /* 18 per triangle: H(s, t), the interpolant itself */
    const float *reflectance;        /* 3 per triangle: rho of its patch */
    const float *emission;           /* 3 per triangle: E of its patch */
    const float *corner_radiosity;   /* 9 per triangle: B at its corners (Gouraud shading) */
    const float *vertex_radiosity;   /* 3 per vertex: mean B of the corners that share it (blends
                                        patches that meet there) */
    const unsigned char *edge_flags; /* per triangle: bit i = the edge opposite corner i lies on a
                                        leaf edge or the patch outline; bit 3 + i = it lies on an
                                        active discontinuity */
} radinterp_mesh_data;

typedef enum radinterp_discontinuity_type {
    RADINTERP_DISCONTINUITY_EV = 1,      /* source edge, blocker vertex */
    RADINTERP_DISCONTINUITY_VE = 2,      /* source vertex, blocker edge */
    RADINTERP_DISCONTINUITY_HORIZON = 3, /* the source's plane splits the receiver */
    RADINTERP_DISCONTINUITY_CONTACT = 4  /* the blocker touches the receiver */
} radinterp_discontinuity_type;

typedef struct radinterp_discontinuity {
    float a[3], b[3];            /* endpoints on the receiver */
    uint32_t type;               /* radinterp_discontinuity_type */
    uint32_t receiver;           /* patches; RADINTERP_NO_PATCH where none takes part */
    uint32_t source;
    uint32_t blocker;
    uint32_t dset;               /* collinear discontinuities on one receiver share it */
    float weight;                /* max(d_sb / d_br) * B_src; FLT_MAX for a contact */
    int active;                  /* in the triangulation of every leaf it crosses */
} radinterp_discontinuity;
#define RADINTERP_NO_PATCH 0xFFFFFFFFu

typedef struct radinterp_mesh_leaf {
    uint32_t patch;
    uint32_t depth;
    uint32_t vertex_count;       /* 3 or 4 */
    float vertices[4][3];
    uint32_t dsets;              /* DSets impinging on it (weight >= min_discont_weight) */
    uint32_t active_dsets;       /* those in its triangulation (<= max_leaf_dsets) */
    uint32_t first_triangle, triangle_count;   /* its triangles are consecutive */
    float error;                 /* representation error (refine), else -1 */
} radinterp_mesh_leaf;

RADINTERP_API radinterp_result radinterp_build_mesh(const radinterp_solution *s, const radinterp_mesh_desc *desc,
                                                    radinterp_mesh **out);
RADINTERP_API void radinterp_mesh_destroy(radinterp_mesh *m);
RADINTERP_API void radinterp_mesh_get_info(const radinterp_mesh *m, radinterp_mesh_info *info);
RADINTERP_API void radinterp_mesh_get_data(const radinterp_mesh *m, radinterp_mesh_data *data);
RADINTERP_API uint32_t radinterp_mesh_discontinuity_count(const radinterp_mesh *m);
RADINTERP_API radinterp_result radinterp_mesh_get_discontinuity(const radinterp_mesh *m, uint32_t index,
                                                                radinterp_discontinuity *d);
RADINTERP_API uint32_t radinterp_mesh_leaf_count(const radinterp_mesh *m);
RADINTERP_API radinterp_result radinterp_mesh_get_leaf(const radinterp_mesh *m, uint32_t index,
                                                       radinterp_mesh_leaf *leaf);
/* The job system radinterp_shade uses (a loaded mesh has none: serial). */
RADINTERP_API void radinterp_mesh_set_parallel_for(radinterp_mesh *m,
                                                   void (*parallel_for)(void *user, radinterp_job_fn job,
                                                                        void *ctx, uint32_t count),
                                                   void *user);

/* Coefficients (A, 2B, 2C, D, 2E, F) of the quadratic through six values at
   the corners and edge midpoints of a triangle (Hardt eq. 3.1-3.3): r[0] at
   (s, t) = (0, 0), r[1] at (1/2, 0), r[2] at (1, 0), r[3] at (1/2, 1/2),
   r[4] at (0, 1), r[5] at (0, 1/2); s, t = weights of the 2nd and 3rd corner. */
RADINTERP_API void radinterp_fit_quadratic(const float r[6], float coefficients[6]);
/* Radiosity B = E + rho * H(s, t) of a triangle at barycentric (s, t). */
RADINTERP_API radinterp_result radinterp_eval(const radinterp_mesh *m, uint32_t triangle, float s, float t,
                                              float rgb[3]);
/* The irradiance interpolant H(s, t) itself (W/m^2). */
RADINTERP_API radinterp_result radinterp_eval_irradiance(const radinterp_mesh *m, uint32_t triangle, float s,
                                                         float t, float rgb[3]);
/* Per pixel: rgb_out[3 i..] = B of triangle triangle_ids[i] at
   (st[2 i], st[2 i + 1]), clamped at 0. Pixels whose id is not a triangle of
   the mesh (RADINTERP_NO_TRIANGLE, other objects' ids) are left unchanged. */
RADINTERP_API radinterp_result radinterp_shade(const radinterp_mesh *m, const uint32_t *triangle_ids,
                                               const float *st, size_t count, float *rgb_out);
/* The same with Gouraud shading: B at the corners, blended linearly. */
RADINTERP_API radinterp_result radinterp_shade_gouraud(const radinterp_mesh *m, const uint32_t *triangle_ids,
                                                       const float *st, size_t count, float *rgb_out);
/* One run of pixels of one triangle: rgb_out[3 i..] = B of `triangle` at
   (st[2 i], st[2 i + 1]), clamped at 0: the bits radinterp_shade gives
   those pixels (when the compiler does not contract a * b + c into fused
   multiply-adds of its own, as C's ISO modes do not). Runs on the calling
   thread; INVALID_ARGUMENT, rgb_out untouched, for a NULL mesh, a triangle
   not in it, or NULL arrays with count > 0. */
RADINTERP_API radinterp_result radinterp_shade_span(const radinterp_mesh *m, uint32_t triangle, const float *st,
                                                    size_t count, float *rgb_out);
#define RADINTERP_NO_TRIANGLE 0xFFFFFFFFu

RADINTERP_API radinterp_result radinterp_mesh_save(const radinterp_mesh *m, radinterp_write_fn write, void *user);
RADINTERP_API radinterp_result radinterp_mesh_load(const radinterp_allocator *allocator, radinterp_read_fn read,
                                                   void *user, radinterp_mesh **out);
RADINTERP_API radinterp_result radinterp_mesh_save_to_memory(const radinterp_mesh *m,
                                                             const radinterp_allocator *allocator, void **data,
                                                             size_t *size);
RADINTERP_API radinterp_result radinterp_mesh_load_from_memory(const void *data, size_t size,
                                                               const radinterp_allocator *allocator,
                                                               radinterp_mesh **out);
RADINTERP_API void radinterp_free_memory(const radinterp_allocator *allocator, void *data);

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
#include <time.h>

#if defined(RADINTERP_MALLOC) != defined(RADINTERP_FREE)
#  error "radinterp.h: define both RADINTERP_MALLOC and RADINTERP_FREE, or neither"
#endif
#ifndef RADINTERP_MALLOC
#  define RADINTERP_MALLOC(size) malloc(size)
#  define RADINTERP_FREE(ptr) free(ptr)
#endif
#ifndef RADINTERP_CPU_SECONDS
#  define RADINTERP_CPU_SECONDS() ((double)clock() / (double)CLOCKS_PER_SEC)   /* (clock_t)-1: no clock */
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

/* A growable array of items of one size (the solver's and the mesher's). */
typedef struct radinterp__buf {
    void *data;
    size_t count, cap, item;
} radinterp__buf;

static void radinterp__buf_init(radinterp__buf *b, size_t item)
{
    b->data = NULL;
    b->count = b->cap = 0;
    b->item = item;
}

static int radinterp__buf_reserve(const radinterp_allocator *a, radinterp__buf *b, size_t n)
{
    size_t cap;
    void *p;
    if (n <= b->cap) return 0;
    cap = b->cap ? b->cap : 64;
    while (cap < n) {
        if (cap > SIZE_MAX / 2 / b->item) return -1;
        cap *= 2;
    }
    p = radinterp__alloc_array(a, cap, b->item);
    if (!p) return -1;
    if (b->count) memcpy(p, b->data, b->count * b->item);
    radinterp__free(a, b->data);
    b->data = p;
    b->cap = cap;
    return 0;
}

/* A new zeroed item at the end, or NULL when out of memory. */
static void *radinterp__buf_push(const radinterp_allocator *a, radinterp__buf *b)
{
    void *p;
    if (b->count == b->cap && radinterp__buf_reserve(a, b, b->count + 1) != 0) return NULL;
    p = (char *)b->data + b->count * b->item;
    memset(p, 0, b->item);
    b->count++;
    return p;
}

static int radinterp__buf_u32(const radinterp_allocator *a, radinterp__buf *b, uint32_t v)
{
    uint32_t *p = (uint32_t *)radinterp__buf_push(a, b);
    if (!p) return -1;
    *p = v;
    return 0;
}

static void radinterp__buf_free(const radinterp_allocator *a, radinterp__buf *b)
{
    radinterp__free(a, b->data);
    b->data = NULL;
    b->count = b->cap = 0;
}

/* Gives back the capacity beyond the count, after a buffer held more for a
   while than it keeps. */
static int radinterp__buf_trim(const radinterp_allocator *a, radinterp__buf *b)
{
    void *p;
    if (b->cap == b->count) return 0;
    if (b->count == 0) { radinterp__buf_free(a, b); return 0; }
    p = radinterp__alloc_array(a, b->count, b->item);
    if (!p) return -1;
    memcpy(p, b->data, b->count * b->item);
    radinterp__free(a, b->data);
    b->data = p;
    b->cap = b->count;
    return 0;
}

#define RADINTERP__U32(b) ((uint32_t *)(b).data)

/* Zero means default: the documented default replaces a zero field. */
#define radinterp__def(v, d) ((v) ? (v) : (d))

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
typedef struct radinterp__vec3 { float x, y, z; } radinterp__vec3;

static radinterp__vec3 radinterp__v3(float x, float y, float z) { radinterp__vec3 r; r.x = x; r.y = y; r.z = z; return r; }
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
   An 8-wide BVH (Embree's BVH8: Wald et al. 2014). Build: a binary tree by
   binned SAH (RADINTERP_BVH_BINS bins over the centroid bounds, all three axes
   binned in one pass; a leaf costs one test per block of four triangles),
   then collapsed into 8-wide nodes by opening, again and again, the child of
   largest surface area. A node keeps its eight child boxes in rows
   (structure of arrays) and a leaf is a run of blocks of four triangles in
   rows, so one SIMD instruction tests four boxes or four triangles. Nodes are
   stored depth first; the blocks hold copies of the vertices, nothing of the
   caller's data is kept. Traversal: nearest child first, every stack entry
   keeps its entry distance so that entries behind a closer hit are dropped;
   the watertight ray/triangle test (Woop, Benthin, Wald 2013); any-hit for
   shadow rays. RADINTERP_BVH_SIMD selects the SSE2 (x86-64) or NEON (AArch64)
   kernels. The scalar kernels do the same float operations lane by lane, are
   always compiled, and find the same hits bit for bit (bvh->simd = 0 selects
   them).
   ---------------------------------------------------------------------- */
#ifndef RADINTERP_BVH_BINS
#define RADINTERP_BVH_BINS 16
#endif
#ifndef RADINTERP_BVH_SIMD
#define RADINTERP_BVH_SIMD 1
#endif
#if RADINTERP_BVH_SIMD && (defined(__SSE2__) || defined(_M_X64) || defined(_M_AMD64))
#define RADINTERP__SSE 1
#include <emmintrin.h>
#elif RADINTERP_BVH_SIMD && defined(__aarch64__) && (defined(__GNUC__) || defined(__clang__))
#define RADINTERP__NEON 1
#include <arm_neon.h>
#endif
#if defined(RADINTERP__SSE) || defined(RADINTERP__NEON)
#define RADINTERP__SIMD 1
#else
#define RADINTERP__SIMD 0
#endif
/* Where the target fuses a * b + c (FMA on x86 with -mfma, every AArch64),
   both kernels fuse it explicitly: a compiler that contracts on its own
   (GCC's -ffp-contract=fast, clang's default) then has nothing left to fuse
   differently in the scalar kernel. Without FMA nothing can be fused. */
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__FMA__) || defined(__aarch64__))
#define RADINTERP__BVH_FMA 1
#if defined(RADINTERP__SSE)
#include <immintrin.h>
#endif
#else
#define RADINTERP__BVH_FMA 0
#endif

#define RADINTERP__BVH_WIDTH 8        /* children per node */
#define RADINTERP__BVH_LEAF_MAX 16    /* triangles per leaf: four blocks */
#define RADINTERP__BVH_NODE_COST 2.0f /* SAH cost of a binary node, in block tests (measured best of 0.5-4) */
#define RADINTERP__BVH_MAX_DEPTH 60   /* deeper nodes split at the median: bounds the stacks */
#define RADINTERP__BVH_MAX_BINARY_DEPTH (RADINTERP__BVH_MAX_DEPTH + 33) /* + 32 halvings of a uint32_t count */
#define RADINTERP__BVH_STACK ((RADINTERP__BVH_WIDTH - 1) * RADINTERP__BVH_MAX_BINARY_DEPTH + RADINTERP__BVH_WIDTH)
#define RADINTERP__BVH_LEAF 0x80000000u /* a leaf's child reference: LEAF | first block << 3 | blocks - 1 */
#define RADINTERP__BVH_MAX_BLOCKS (1u << 28)
#define RADINTERP__BVH_NONE 0xFFFFFFFFu
/* Far plane distances are rounded up by 1 + 2 gamma_3 (Ize 2013): a box that
   the ray touches is never lost to the rounding of three operations. */
#define RADINTERP__BVH_ROUND_UP 1.00000036f
/* Node boxes are pushed outward by 2^-20 of each bound plus 1e-20 (in the
   scene's units). A ray with a zero direction component (its inverse is
   1e30, radinterp__ray_setup) that runs exactly in the plane of a box's face
   would otherwise leave the box at t = 0 and miss a triangle lying on that
   face; pushed out, it stays inside for t of 1e10 or more. The boxes grow by
   a millionth. */
#define RADINTERP__BVH_PAD_RELATIVE 9.5367431640625e-07f   /* 2^-20 */
#define RADINTERP__BVH_PAD_ABSOLUTE 1e-20f

typedef struct radinterp__bvh_node {
    float box[6][RADINTERP__BVH_WIDTH]; /* rows lo x, hi x, lo y, hi y, lo z, hi z; column = child.
                           An unused child has lo = +inf, hi = -inf: no ray enters it */
    uint32_t child[RADINTERP__BVH_WIDTH]; /* inner node index, or a leaf reference (RADINTERP__BVH_LEAF) */
} radinterp__bvh_node;

typedef struct radinterp__bvh_tris {
    float v[9][4];      /* rows x, y, z of vertex 0, of vertex 1, of vertex 2; column = triangle */
    uint32_t id[4];     /* the caller's triangle indices; unused columns repeat the last triangle */
} radinterp__bvh_tris;

typedef struct radinterp__bvh {
    radinterp__bvh_node *nodes;    /* both in one allocation, from a cache line boundary */
    radinterp__bvh_tris *blocks;
    char *memory;
    uint32_t node_count, block_count, tri_count;
    uint32_t root;              /* a node index or a leaf reference; unused when tri_count is 0 */
    uint32_t degenerate_count;  /* zero-area triangles skipped by the build */
    int simd;                   /* 1: the SIMD kernels (when compiled in); 0: the scalar ones */
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

typedef struct radinterp__bvh_bnode { /* build-time binary node, flattened depth first */
    float lo[3];
    uint32_t first;  /* leaf: first ref; inner: index of the right child (the left is next) */
    float hi[3];
    uint32_t count;  /* leaf: ref count (> 0); inner: 0 */
} radinterp__bvh_bnode;

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

static uint32_t radinterp__bvh_blocks(uint32_t n) { return (n + 3) / 4; }

/* The bin of a centroid coordinate. */
static int radinterp__bvh_bin_of(float c, float lo, float scale)
{
    float f = (c - lo) * scale;   /* NaN or inf when a denormal extent overflows scale */
    return f >= (float)(RADINTERP_BVH_BINS - 1) ? RADINTERP_BVH_BINS - 1 : f > 0.0f ? (int)f : 0;
}

/* Chooses the binned-SAH split of refs[0..n) (node box lo..hi, centroid box
   clo..chi): returns 0 when a leaf is cheaper or no axis can split, else the
   axis in *axis and the first bin of the right side in *split_bin. */
static int radinterp__bvh_find_split(const radinterp__bvh_ref *refs, uint32_t n, const float lo[3], const float hi[3],
                                  const float clo[3], const float chi[3], int *axis, int *split_bin)
{
    radinterp__bvh_bin bins[3][RADINTERP_BVH_BINS];
    float scale[3], right_area[RADINTERP_BVH_BINS], best = FLT_MAX;
    float leaf_cost = (float)radinterp__bvh_blocks(n), inv_area = 1.0f / radinterp__box_area(lo, hi);
    uint32_t right_count[RADINTERP_BVH_BINS], i;
    int k, b, found = 0;
    for (k = 0; k < 3; k++) {
        scale[k] = chi[k] > clo[k] ? (float)RADINTERP_BVH_BINS / (chi[k] - clo[k]) : 0.0f;
        for (b = 0; b < RADINTERP_BVH_BINS; b++) { radinterp__box_empty(bins[k][b].lo, bins[k][b].hi); bins[k][b].count = 0; }
    }
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) {
            radinterp__bvh_bin *bin = &bins[k][radinterp__bvh_bin_of(refs[i].c[k], clo[k], scale[k])];
            bin->count++;
            radinterp__box_grow(bin->lo, bin->hi, refs[i].lo, refs[i].hi);
        }
    for (k = 0; k < 3; k++) {
        float blo[3], bhi[3];
        uint32_t count = 0;
        if (scale[k] == 0.0f) continue;   /* all centroids in one plane across k */
        /* sweep from the right, then from the left evaluating each boundary */
        radinterp__box_empty(blo, bhi);
        for (b = RADINTERP_BVH_BINS - 1; b > 0; b--) {
            radinterp__box_grow(blo, bhi, bins[k][b].lo, bins[k][b].hi);
            count += bins[k][b].count;
            right_area[b] = radinterp__box_area(blo, bhi);
            right_count[b] = count;
        }
        radinterp__box_empty(blo, bhi);
        count = 0;
        for (b = 1; b < RADINTERP_BVH_BINS; b++) {
            float cost;
            radinterp__box_grow(blo, bhi, bins[k][b - 1].lo, bins[k][b - 1].hi);
            count += bins[k][b - 1].count;
            if (count == 0 || right_count[b] == 0) continue;
            cost = RADINTERP__BVH_NODE_COST + (radinterp__box_area(blo, bhi) * (float)radinterp__bvh_blocks(count) +
                                            right_area[b] * (float)radinterp__bvh_blocks(right_count[b])) * inv_area;
            if (cost < best) { best = cost; *axis = k; *split_bin = b; found = 1; }
        }
    }
    return found && (best < leaf_cost || n > RADINTERP__BVH_LEAF_MAX);
}

/* Splits refs[0..n) in two: by the SAH when it pays, else (coincident
   centroids, the depth cap) by count. Returns the size of the left part, 0
   when the refs should stay a leaf. */
static uint32_t radinterp__bvh_partition(radinterp__bvh_ref *refs, uint32_t n, const float lo[3], const float hi[3],
                                      const float clo[3], const float chi[3], uint32_t depth)
{
    int axis = 0, split_bin = 0;
    uint32_t i, j;
    if (depth < RADINTERP__BVH_MAX_DEPTH && radinterp__bvh_find_split(refs, n, lo, hi, clo, chi, &axis, &split_bin)) {
        float scale = (float)RADINTERP_BVH_BINS / (chi[axis] - clo[axis]);
        for (i = 0, j = n; i < j;) {
            if (radinterp__bvh_bin_of(refs[i].c[axis], clo[axis], scale) < split_bin) i++;
            else { radinterp__bvh_ref t = refs[i]; refs[i] = refs[--j]; refs[j] = t; }
        }
        return i;   /* both sides hold refs: the split's bins are not empty */
    }
    return n <= RADINTERP__BVH_LEAF_MAX ? 0 : n / 2;
}

/* Bounds of every non-degenerate triangle; counts the degenerate ones. The
   area test runs in double: a tiny triangle (a scene at scale 1e-12) is not
   zero because its float cross product underflows. */
static uint32_t radinterp__bvh_collect(radinterp__bvh *bvh, const radinterp__mesh_view *m, radinterp__bvh_ref *refs)
{
    uint32_t i, n = 0;
    for (i = 0; i < m->tri_count; i++) {
        const float *p0 = radinterp__vertex(m, m->indices[3 * i + 0]);
        const float *p1 = radinterp__vertex(m, m->indices[3 * i + 1]);
        const float *p2 = radinterp__vertex(m, m->indices[3 * i + 2]);
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
            refs[n].lo[k] = radinterp__minf(p0[k], radinterp__minf(p1[k], p2[k]));
            refs[n].hi[k] = radinterp__maxf(p0[k], radinterp__maxf(p1[k], p2[k]));
            refs[n].c[k] = 0.5f * (refs[n].lo[k] + refs[n].hi[k]);
        }
        refs[n].tri = i;
        n++;
    }
    return n;
}

typedef struct radinterp__bvh_task {
    uint32_t parent, begin, end, depth;
    int is_right;    /* the parent learns a right child's index when it is popped */
} radinterp__bvh_task;

/* The binary tree over refs[0..n) (n > 0) into bn (room for 2n - 1 nodes).
   Returns the node count; *blocks receives the leaves' block count. */
static uint32_t radinterp__bvh_build_binary(radinterp__bvh_bnode *bn, radinterp__bvh_ref *refs, uint32_t n, uint32_t *blocks)
{
    radinterp__bvh_task stack[RADINTERP__BVH_MAX_BINARY_DEPTH + 1];
    uint32_t top = 0, count = 0, i;
    *blocks = 0;
    stack[top].parent = 0; stack[top].begin = 0; stack[top].end = n;
    stack[top].depth = 0; stack[top].is_right = 0; top++;
    while (top) {
        radinterp__bvh_task t = stack[--top];
        uint32_t index = count++, mid;
        radinterp__bvh_bnode *node = &bn[index];
        float clo[3], chi[3];
        if (t.is_right) bn[t.parent].first = index;
        radinterp__box_empty(node->lo, node->hi);
        radinterp__box_empty(clo, chi);
        for (i = t.begin; i < t.end; i++) {
            radinterp__box_grow(node->lo, node->hi, refs[i].lo, refs[i].hi);
            radinterp__box_grow(clo, chi, refs[i].c, refs[i].c);
        }
        mid = t.end - t.begin < 2 ? 0 : radinterp__bvh_partition(refs + t.begin, t.end - t.begin, node->lo, node->hi, clo, chi, t.depth);
        if (mid == 0) {
            node->first = t.begin;
            node->count = t.end - t.begin;
            *blocks += radinterp__bvh_blocks(node->count);
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
static int radinterp__bvh_open(const radinterp__bvh_bnode *bn, uint32_t i, uint32_t kids[RADINTERP__BVH_WIDTH])
{
    int k = 2;
    kids[0] = i + 1;
    kids[1] = bn[i].first;
    while (k < RADINTERP__BVH_WIDTH) {
        int j, best = -1;
        float best_area = -1.0f;
        for (j = 0; j < k; j++) {
            float area = radinterp__box_area(bn[kids[j]].lo, bn[kids[j]].hi);
            if (bn[kids[j]].count == 0 && area > best_area) { best_area = area; best = j; }
        }
        if (best < 0) break;
        kids[k++] = bn[kids[best]].first;
        kids[best] = kids[best] + 1;
    }
    return k;
}

/* A leaf's triangles into blocks of four from bvh->blocks[first]. */
static void radinterp__bvh_store_leaf(radinterp__bvh *bvh, const radinterp__mesh_view *m, const radinterp__bvh_ref *refs,
                                   uint32_t count, uint32_t first)
{
    uint32_t i;
    for (i = 0; i < 4 * radinterp__bvh_blocks(count); i++) {
        radinterp__bvh_tris *b = &bvh->blocks[first + i / 4];
        uint32_t tri = refs[i < count ? i : count - 1].tri;
        int j, k;
        for (j = 0; j < 3; j++) {
            const float *p = radinterp__vertex(m, m->indices[3 * (size_t)tri + (uint32_t)j]);
            for (k = 0; k < 3; k++) b->v[3 * j + k][i % 4] = p[k];
        }
        b->id[i % 4] = tri;
    }
}

typedef struct radinterp__bvh_place { uint32_t bnode, parent, slot; } radinterp__bvh_place;

/* A box bound v pushed outward (side -1 for a lower bound, +1 for an
   upper one): see RADINTERP__BVH_PAD_RELATIVE. */
static float radinterp__bvh_pad(float v, float side)
{
    return v + side * (fabsf(v) * RADINTERP__BVH_PAD_RELATIVE + RADINTERP__BVH_PAD_ABSOLUTE);
}

/* Collapses the binary tree into 4-wide nodes, depth first. With
   bvh->nodes NULL it only counts them (into bvh->node_count). */
static void radinterp__bvh_collapse(radinterp__bvh *bvh, const radinterp__bvh_bnode *bn, const radinterp__bvh_ref *refs,
                                 const radinterp__mesh_view *m)
{
    radinterp__bvh_place stack[RADINTERP__BVH_STACK];
    uint32_t top = 0, nodes = 0, blocks = 0;
    stack[top].bnode = 0; stack[top].parent = RADINTERP__BVH_NONE; stack[top].slot = 0; top++;
    while (top) {
        radinterp__bvh_place p = stack[--top];
        const radinterp__bvh_bnode *b = &bn[p.bnode];
        uint32_t ref;
        if (b->count) {
            ref = RADINTERP__BVH_LEAF | blocks << 3 | (radinterp__bvh_blocks(b->count) - 1);
            if (bvh->nodes) radinterp__bvh_store_leaf(bvh, m, refs + b->first, b->count, blocks);
            blocks += radinterp__bvh_blocks(b->count);
        } else {
            uint32_t kids[RADINTERP__BVH_WIDTH];
            int k = radinterp__bvh_open(bn, p.bnode, kids), j, r;
            ref = nodes++;
            if (bvh->nodes) {
                radinterp__bvh_node *node = &bvh->nodes[ref];
                for (j = 0; j < RADINTERP__BVH_WIDTH; j++) {
                    for (r = 0; r < 3; r++) {
                        node->box[2 * r][j] = j < k ? radinterp__bvh_pad(bn[kids[j]].lo[r], -1.0f) : INFINITY;
                        node->box[2 * r + 1][j] = j < k ? radinterp__bvh_pad(bn[kids[j]].hi[r], 1.0f) : -INFINITY;
                    }
                    node->child[j] = 0;
                }
            }
            for (j = k - 1; j >= 0; j--) {   /* the first child is placed next */
                stack[top].bnode = kids[j]; stack[top].parent = ref; stack[top].slot = (uint32_t)j; top++;
            }
        }
        if (!bvh->nodes) continue;
        if (p.parent == RADINTERP__BVH_NONE) bvh->root = ref;
        else bvh->nodes[p.parent].child[p.slot] = ref;
    }
    bvh->node_count = nodes;
}

/* Builds the BVH of m's non-degenerate triangles. Indices must be in range and
   coordinates finite (validate first). Returns 0, or -1 when out of memory. */
static int radinterp__bvh_build(radinterp__bvh *bvh, const radinterp__mesh_view *m, const radinterp_allocator *a)
{
    radinterp__bvh_ref *refs;
    radinterp__bvh_bnode *bn = NULL;
    uint32_t n;
    memset(bvh, 0, sizeof *bvh);
    bvh->simd = RADINTERP__SIMD;
    refs = (radinterp__bvh_ref *)radinterp__alloc_array(a, m->tri_count, sizeof *refs);
    if (!refs) return -1;
    n = radinterp__bvh_collect(bvh, m, refs);
    if (n) bn = (radinterp__bvh_bnode *)radinterp__alloc_array(a, 2 * (size_t)n - 1, sizeof *bn);
    if (n && bn) {
        radinterp__bvh_build_binary(bn, refs, n, &bvh->block_count);
        radinterp__bvh_collapse(bvh, bn, refs, m);   /* counts the nodes */
        if (bvh->block_count <= RADINTERP__BVH_MAX_BLOCKS) {
            size_t nb = (size_t)bvh->node_count * sizeof *bvh->nodes, bb = (size_t)bvh->block_count * sizeof *bvh->blocks;
            bvh->memory = (char *)radinterp__alloc(a, nb + bb + 64);
            if (bvh->memory) {   /* nodes and blocks from a cache line boundary */
                char *p = bvh->memory + (64 - (size_t)((uintptr_t)bvh->memory % 64)) % 64;
                bvh->nodes = (radinterp__bvh_node *)(void *)p;
                bvh->blocks = (radinterp__bvh_tris *)(void *)(p + nb);
            }
        }
        if (bvh->nodes && bvh->blocks) radinterp__bvh_collapse(bvh, bn, refs, m);
    }
    radinterp__free(a, refs);
    radinterp__free(a, bn);
    if (n && (!bvh->nodes || !bvh->blocks)) {
        radinterp__free(a, bvh->memory);
        memset(bvh, 0, sizeof *bvh);
        return -1;
    }
    bvh->tri_count = n;   /* 0: an empty tree, every ray misses */
    return 0;
}

static void radinterp__bvh_free(radinterp__bvh *bvh, const radinterp_allocator *a)
{
    radinterp__free(a, bvh->memory);
    memset(bvh, 0, sizeof *bvh);
}

/* Four floats, and a mask of four lanes, for the SIMD kernels. */
#if defined(RADINTERP__SSE)
typedef __m128 radinterp__f4;
typedef __m128 radinterp__m4;
static radinterp__f4 radinterp__f4_load(const float *p) { return _mm_loadu_ps(p); }
static void radinterp__f4_store(float *p, radinterp__f4 a) { _mm_storeu_ps(p, a); }
static radinterp__f4 radinterp__f4_set(float x) { return _mm_set1_ps(x); }
static radinterp__f4 radinterp__f4_add(radinterp__f4 a, radinterp__f4 b) { return _mm_add_ps(a, b); }
static radinterp__f4 radinterp__f4_sub(radinterp__f4 a, radinterp__f4 b) { return _mm_sub_ps(a, b); }
static radinterp__f4 radinterp__f4_mul(radinterp__f4 a, radinterp__f4 b) { return _mm_mul_ps(a, b); }
static radinterp__f4 radinterp__f4_div(radinterp__f4 a, radinterp__f4 b) { return _mm_div_ps(a, b); }
#if RADINTERP__BVH_FMA
static radinterp__f4 radinterp__f4_madd(radinterp__f4 a, radinterp__f4 b, radinterp__f4 c) { return _mm_fmadd_ps(a, b, c); }
static radinterp__f4 radinterp__f4_det2(radinterp__f4 a, radinterp__f4 b, radinterp__f4 c, radinterp__f4 d)
{
    radinterp__f4 w = _mm_mul_ps(c, d);
    return _mm_sub_ps(_mm_fmsub_ps(a, b, w), _mm_fmsub_ps(c, d, w));
}
#else
static radinterp__f4 radinterp__f4_madd(radinterp__f4 a, radinterp__f4 b, radinterp__f4 c) { return _mm_add_ps(_mm_mul_ps(a, b), c); }
static radinterp__f4 radinterp__f4_det2(radinterp__f4 a, radinterp__f4 b, radinterp__f4 c, radinterp__f4 d)
{
    return _mm_sub_ps(_mm_mul_ps(a, b), _mm_mul_ps(c, d));
}
#endif
static radinterp__f4 radinterp__f4_min(radinterp__f4 a, radinterp__f4 b) { return _mm_min_ps(a, b); }  /* a < b ? a : b */
static radinterp__f4 radinterp__f4_max(radinterp__f4 a, radinterp__f4 b) { return _mm_max_ps(a, b); }  /* a > b ? a : b */
static radinterp__m4 radinterp__f4_lt(radinterp__f4 a, radinterp__f4 b) { return _mm_cmplt_ps(a, b); }
static radinterp__m4 radinterp__f4_le(radinterp__f4 a, radinterp__f4 b) { return _mm_cmple_ps(a, b); }
static radinterp__m4 radinterp__f4_eq(radinterp__f4 a, radinterp__f4 b) { return _mm_cmpeq_ps(a, b); }
static radinterp__m4 radinterp__m4_and(radinterp__m4 a, radinterp__m4 b) { return _mm_and_ps(a, b); }
static radinterp__m4 radinterp__m4_or(radinterp__m4 a, radinterp__m4 b) { return _mm_or_ps(a, b); }
static radinterp__m4 radinterp__m4_andnot(radinterp__m4 a, radinterp__m4 b) { return _mm_andnot_ps(a, b); } /* ~a & b */
static unsigned radinterp__m4_bits(radinterp__m4 a) { return (unsigned)_mm_movemask_ps(a); }
#elif defined(RADINTERP__NEON)
typedef float32x4_t radinterp__f4;
typedef uint32x4_t radinterp__m4;
static radinterp__f4 radinterp__f4_load(const float *p) { return vld1q_f32(p); }
static void radinterp__f4_store(float *p, radinterp__f4 a) { vst1q_f32(p, a); }
static radinterp__f4 radinterp__f4_set(float x) { return vdupq_n_f32(x); }
static radinterp__f4 radinterp__f4_add(radinterp__f4 a, radinterp__f4 b) { return vaddq_f32(a, b); }
static radinterp__f4 radinterp__f4_sub(radinterp__f4 a, radinterp__f4 b) { return vsubq_f32(a, b); }
static radinterp__f4 radinterp__f4_mul(radinterp__f4 a, radinterp__f4 b) { return vmulq_f32(a, b); }
static radinterp__f4 radinterp__f4_div(radinterp__f4 a, radinterp__f4 b) { return vdivq_f32(a, b); }
static radinterp__f4 radinterp__f4_madd(radinterp__f4 a, radinterp__f4 b, radinterp__f4 c) { return vfmaq_f32(c, a, b); }
static radinterp__f4 radinterp__f4_det2(radinterp__f4 a, radinterp__f4 b, radinterp__f4 c, radinterp__f4 d)   /* Kahan, as the scalar */
{
    radinterp__f4 w = vmulq_f32(c, d), nw = vnegq_f32(w);
    return vsubq_f32(vfmaq_f32(nw, a, b), vfmaq_f32(nw, c, d));
}
/* compare and select: the scalar kernels' a < b ? a : b, NaN included (vminq_f32 differs) */
static radinterp__f4 radinterp__f4_min(radinterp__f4 a, radinterp__f4 b) { return vbslq_f32(vcltq_f32(a, b), a, b); }
static radinterp__f4 radinterp__f4_max(radinterp__f4 a, radinterp__f4 b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
static radinterp__m4 radinterp__f4_lt(radinterp__f4 a, radinterp__f4 b) { return vcltq_f32(a, b); }
static radinterp__m4 radinterp__f4_le(radinterp__f4 a, radinterp__f4 b) { return vcleq_f32(a, b); }
static radinterp__m4 radinterp__f4_eq(radinterp__f4 a, radinterp__f4 b) { return vceqq_f32(a, b); }
static radinterp__m4 radinterp__m4_and(radinterp__m4 a, radinterp__m4 b) { return vandq_u32(a, b); }
static radinterp__m4 radinterp__m4_or(radinterp__m4 a, radinterp__m4 b) { return vorrq_u32(a, b); }
static radinterp__m4 radinterp__m4_andnot(radinterp__m4 a, radinterp__m4 b) { return vbicq_u32(b, a); } /* ~a & b */
static unsigned radinterp__m4_bits(radinterp__m4 a)
{
    static const uint32_t weight[4] = {1, 2, 4, 8};
    return vaddvq_u32(vandq_u32(a, vld1q_u32(weight)));
}
#endif

/* a * b + c, fused where RADINTERP__BVH_FMA (the shear and the distance). */
static float radinterp__bvh_madd(float a, float b, float c)
{
#if RADINTERP__BVH_FMA
    return fmaf(a, b, c);
#else
    return a * b + c;
#endif
}

/* Per-ray constants of the watertight test and of the slab test. */
typedef struct radinterp__ray {
    float org[3], dir[3], inv[3];
    int kx, ky, kz;          /* dir[kz] has the largest magnitude */
    float sx, sy, sz;        /* shear that maps dir to +z */
    float nsx, nsy;          /* -sx, -sy */
    int near[3];             /* box row offset (in floats) of the entry plane per axis; far = near ^ WIDTH */
#if RADINTERP__SIMD
    radinterp__f4 org4[3], inv4[3], nsx4, nsy4, sz4;
#endif
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
        r->near[k] = 2 * RADINTERP__BVH_WIDTH * k + (r->inv[k] < 0.0f ? RADINTERP__BVH_WIDTH : 0);
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
#if RADINTERP__SIMD
    for (k = 0; k < 3; k++) {
        r->org4[k] = radinterp__f4_set(r->org[k]);
        r->inv4[k] = radinterp__f4_set(r->inv[k]);
    }
    r->nsx4 = radinterp__f4_set(r->nsx);
    r->nsy4 = radinterp__f4_set(r->nsy);
    r->sz4 = radinterp__f4_set(r->sz);
#endif
}

/* Entry distances t[i] of the ray into a node's child boxes, clipped to
   [tmin, tmax]; returns the mask of the children it enters. */
static unsigned radinterp__node_hits_scalar(const radinterp__ray *r, const radinterp__bvh_node *n, float tmin, float tmax,
                                         float t[RADINTERP__BVH_WIDTH])
{
    const float *box = n->box[0];
    unsigned mask = 0;
    int i;
    for (i = 0; i < RADINTERP__BVH_WIDTH; i++) {
        float nx = (box[r->near[0] + i] - r->org[0]) * r->inv[0];
        float ny = (box[r->near[1] + i] - r->org[1]) * r->inv[1];
        float nz = (box[r->near[2] + i] - r->org[2]) * r->inv[2];
        float fx = (box[(r->near[0] ^ RADINTERP__BVH_WIDTH) + i] - r->org[0]) * r->inv[0];
        float fy = (box[(r->near[1] ^ RADINTERP__BVH_WIDTH) + i] - r->org[1]) * r->inv[1];
        float fz = (box[(r->near[2] ^ RADINTERP__BVH_WIDTH) + i] - r->org[2]) * r->inv[2];
        float tn = radinterp__maxf(radinterp__maxf(nx, ny), radinterp__maxf(nz, tmin));
        float tf = radinterp__minf(radinterp__minf(fx, fy), radinterp__minf(fz, tmax)) * RADINTERP__BVH_ROUND_UP;
        t[i] = tn;
        if (tn <= tf) mask |= 1u << i;
    }
    return mask;
}

/* An edge function a * b - c * d. With FMA, Kahan's algorithm: within two
   ulp of the exact value, so its sign is exact. Without, the two rounded
   products: the sign is exact or the value zero (Woop et al.), and a zero
   is computed again exactly in double by radinterp__bvh_edges_double. */
static float radinterp__bvh_det2(float a, float b, float c, float d)
{
#if RADINTERP__BVH_FMA
    float w = c * d;
    return fmaf(a, b, -w) - fmaf(c, d, -w);
#else
    return a * b - c * d;
#endif
}

/* The edge functions u, v, w exactly (products of floats are exact in
   double) and rounded once. */
static void radinterp__bvh_edges_double(float ax, float ay, float bx, float by, float cx, float cy, float e[3])
{
    e[0] = (float)((double)cx * by - (double)cy * bx);
    e[1] = (float)((double)ax * cy - (double)ay * cx);
    e[2] = (float)((double)bx * ay - (double)by * ax);
}

/* Watertight ray/triangle test (Woop, Benthin, Wald 2013): edge functions in
   a sheared space where the ray is the +z axis; an edge shared by two
   triangles is never missed by both. Updates *hit when closer than hit->t;
   returns 1 then. */
static int radinterp__leaf_hit_scalar(const radinterp__ray *r, const radinterp__bvh_tris *b, float tmin, radinterp__hit *hit)
{
    int i, found = 0;
    for (i = 0; i < 4; i++) {
        float ax = b->v[r->kx][i] - r->org[r->kx], ay = b->v[r->ky][i] - r->org[r->ky], az = b->v[r->kz][i] - r->org[r->kz];
        float bx = b->v[3 + r->kx][i] - r->org[r->kx], by = b->v[3 + r->ky][i] - r->org[r->ky], bz = b->v[3 + r->kz][i] - r->org[r->kz];
        float cx = b->v[6 + r->kx][i] - r->org[r->kx], cy = b->v[6 + r->ky][i] - r->org[r->ky], cz = b->v[6 + r->kz][i] - r->org[r->kz];
        float u, v, w, det, inv_det, t;
        ax = radinterp__bvh_madd(r->nsx, az, ax); ay = radinterp__bvh_madd(r->nsy, az, ay);
        bx = radinterp__bvh_madd(r->nsx, bz, bx); by = radinterp__bvh_madd(r->nsy, bz, by);
        cx = radinterp__bvh_madd(r->nsx, cz, cx); cy = radinterp__bvh_madd(r->nsy, cz, cy);
        u = radinterp__bvh_det2(cx, by, cy, bx);
        v = radinterp__bvh_det2(ax, cy, ay, cx);
        w = radinterp__bvh_det2(bx, ay, by, ax);
        if (!RADINTERP__BVH_FMA && (u == 0.0f || v == 0.0f || w == 0.0f)) {
            float e[3];
            radinterp__bvh_edges_double(ax, ay, bx, by, cx, cy, e);
            u = e[0]; v = e[1]; w = e[2];
        }
        if ((u < 0.0f || v < 0.0f || w < 0.0f) && (0.0f < u || 0.0f < v || 0.0f < w)) continue;
        det = u + v + w;
        if (det == 0.0f) continue;
        inv_det = 1.0f / det;
        u = u * inv_det; v = v * inv_det; w = w * inv_det;   /* barycentrics first: u * az underflows at 1e-13 m */
        t = radinterp__bvh_madd(u, az, radinterp__bvh_madd(v, bz, w * cz)) * r->sz;
        if (!(tmin < t && t < hit->t)) continue;
        hit->t = t;
        hit->u = v;
        hit->v = w;
        hit->tri = b->id[i];
        found = 1;
    }
    return found;
}

#if RADINTERP__SIMD
/* radinterp__node_hits_scalar four lanes at a time. */
static unsigned radinterp__node_hits_simd(const radinterp__ray *r, const radinterp__bvh_node *n, float tmin, float tmax,
                                       float t[RADINTERP__BVH_WIDTH])
{
    const radinterp__f4 lo = radinterp__f4_set(tmin), hi = radinterp__f4_set(tmax), up = radinterp__f4_set(RADINTERP__BVH_ROUND_UP);
    unsigned mask = 0;
    int i;
    for (i = 0; i < RADINTERP__BVH_WIDTH; i += 4) {
        const float *box = n->box[0] + i;
        radinterp__f4 nx = radinterp__f4_mul(radinterp__f4_sub(radinterp__f4_load(box + r->near[0]), r->org4[0]), r->inv4[0]);
        radinterp__f4 ny = radinterp__f4_mul(radinterp__f4_sub(radinterp__f4_load(box + r->near[1]), r->org4[1]), r->inv4[1]);
        radinterp__f4 nz = radinterp__f4_mul(radinterp__f4_sub(radinterp__f4_load(box + r->near[2]), r->org4[2]), r->inv4[2]);
        radinterp__f4 fx = radinterp__f4_mul(radinterp__f4_sub(radinterp__f4_load(box + (r->near[0] ^ RADINTERP__BVH_WIDTH)), r->org4[0]), r->inv4[0]);
        radinterp__f4 fy = radinterp__f4_mul(radinterp__f4_sub(radinterp__f4_load(box + (r->near[1] ^ RADINTERP__BVH_WIDTH)), r->org4[1]), r->inv4[1]);
        radinterp__f4 fz = radinterp__f4_mul(radinterp__f4_sub(radinterp__f4_load(box + (r->near[2] ^ RADINTERP__BVH_WIDTH)), r->org4[2]), r->inv4[2]);
        radinterp__f4 tn = radinterp__f4_max(radinterp__f4_max(nx, ny), radinterp__f4_max(nz, lo));
        radinterp__f4 tf = radinterp__f4_mul(radinterp__f4_min(radinterp__f4_min(fx, fy), radinterp__f4_min(fz, hi)), up);
        radinterp__f4_store(t + i, tn);
        mask |= radinterp__m4_bits(radinterp__f4_le(tn, tf)) << i;
    }
    return mask;
}

/* radinterp__leaf_hit_scalar on four lanes at once; the closest accepted lane
   (the first of equals, as the scalar loop keeps it) updates *hit. */
static int radinterp__leaf_hit_simd(const radinterp__ray *r, const radinterp__bvh_tris *b, float tmin, radinterp__hit *hit)
{
    const radinterp__f4 zero = radinterp__f4_set(0.0f);
    radinterp__f4 ax = radinterp__f4_sub(radinterp__f4_load(b->v[r->kx]), r->org4[r->kx]);
    radinterp__f4 ay = radinterp__f4_sub(radinterp__f4_load(b->v[r->ky]), r->org4[r->ky]);
    radinterp__f4 az = radinterp__f4_sub(radinterp__f4_load(b->v[r->kz]), r->org4[r->kz]);
    radinterp__f4 bx = radinterp__f4_sub(radinterp__f4_load(b->v[3 + r->kx]), r->org4[r->kx]);
    radinterp__f4 by = radinterp__f4_sub(radinterp__f4_load(b->v[3 + r->ky]), r->org4[r->ky]);
    radinterp__f4 bz = radinterp__f4_sub(radinterp__f4_load(b->v[3 + r->kz]), r->org4[r->kz]);
    radinterp__f4 cx = radinterp__f4_sub(radinterp__f4_load(b->v[6 + r->kx]), r->org4[r->kx]);
    radinterp__f4 cy = radinterp__f4_sub(radinterp__f4_load(b->v[6 + r->ky]), r->org4[r->ky]);
    radinterp__f4 cz = radinterp__f4_sub(radinterp__f4_load(b->v[6 + r->kz]), r->org4[r->kz]);
    radinterp__f4 u, v, w, det, inv_det, t;
    radinterp__m4 ok;
    float tl[4], vl[4], wl[4];
    unsigned mask;
    int i, best;
    ax = radinterp__f4_madd(r->nsx4, az, ax); ay = radinterp__f4_madd(r->nsy4, az, ay);
    bx = radinterp__f4_madd(r->nsx4, bz, bx); by = radinterp__f4_madd(r->nsy4, bz, by);
    cx = radinterp__f4_madd(r->nsx4, cz, cx); cy = radinterp__f4_madd(r->nsy4, cz, cy);
    u = radinterp__f4_det2(cx, by, cy, bx);
    v = radinterp__f4_det2(ax, cy, ay, cx);
    w = radinterp__f4_det2(bx, ay, by, ax);
    if (!RADINTERP__BVH_FMA && radinterp__m4_bits(radinterp__m4_or(radinterp__m4_or(radinterp__f4_eq(u, zero), radinterp__f4_eq(v, zero)),
                                      radinterp__f4_eq(w, zero)))) {
        float e[9][4];   /* the lanes with a zero edge function again in double */
        radinterp__f4_store(e[0], u); radinterp__f4_store(e[1], v); radinterp__f4_store(e[2], w);
        radinterp__f4_store(e[3], ax); radinterp__f4_store(e[4], ay); radinterp__f4_store(e[5], bx);
        radinterp__f4_store(e[6], by); radinterp__f4_store(e[7], cx); radinterp__f4_store(e[8], cy);
        for (i = 0; i < 4; i++) {
            float exact[3];
            if (e[0][i] != 0.0f && e[1][i] != 0.0f && e[2][i] != 0.0f) continue;
            radinterp__bvh_edges_double(e[3][i], e[4][i], e[5][i], e[6][i], e[7][i], e[8][i], exact);
            e[0][i] = exact[0]; e[1][i] = exact[1]; e[2][i] = exact[2];
        }
        u = radinterp__f4_load(e[0]); v = radinterp__f4_load(e[1]); w = radinterp__f4_load(e[2]);
    }
    ok = radinterp__m4_andnot(
        radinterp__m4_and(radinterp__m4_or(radinterp__m4_or(radinterp__f4_lt(u, zero), radinterp__f4_lt(v, zero)), radinterp__f4_lt(w, zero)),
                       radinterp__m4_or(radinterp__m4_or(radinterp__f4_lt(zero, u), radinterp__f4_lt(zero, v)), radinterp__f4_lt(zero, w))),
        radinterp__f4_eq(zero, zero));
    det = radinterp__f4_add(radinterp__f4_add(u, v), w);
    ok = radinterp__m4_andnot(radinterp__f4_eq(det, zero), ok);
    inv_det = radinterp__f4_div(radinterp__f4_set(1.0f), det);
    u = radinterp__f4_mul(u, inv_det); v = radinterp__f4_mul(v, inv_det); w = radinterp__f4_mul(w, inv_det);
    t = radinterp__f4_mul(radinterp__f4_madd(u, az, radinterp__f4_madd(v, bz, radinterp__f4_mul(w, cz))), r->sz4);
    ok = radinterp__m4_and(ok, radinterp__m4_and(radinterp__f4_lt(radinterp__f4_set(tmin), t), radinterp__f4_lt(t, radinterp__f4_set(hit->t))));
    mask = radinterp__m4_bits(ok);
    if (!mask) return 0;
    radinterp__f4_store(tl, t);
    for (best = -1, i = 0; i < 4; i++)
        if ((mask >> i & 1) && (best < 0 || tl[i] < tl[best])) best = i;
    radinterp__f4_store(vl, v); radinterp__f4_store(wl, w);
    hit->t = tl[best];
    hit->u = vl[best];
    hit->v = wl[best];
    hit->tri = b->id[best];
    return 1;
}
#endif

static unsigned radinterp__bvh_node_hits(const radinterp__bvh *bvh, const radinterp__ray *r, const radinterp__bvh_node *n,
                                      float tmin, float tmax, float t[RADINTERP__BVH_WIDTH])
{
#if RADINTERP__SIMD
    if (bvh->simd) return radinterp__node_hits_simd(r, n, tmin, tmax, t);
#endif
    (void)bvh;
    return radinterp__node_hits_scalar(r, n, tmin, tmax, t);
}

static int radinterp__bvh_leaf_hit(const radinterp__bvh *bvh, const radinterp__ray *r, const radinterp__bvh_tris *b, float tmin,
                                radinterp__hit *hit)
{
#if RADINTERP__SIMD
    if (bvh->simd) return radinterp__leaf_hit_simd(r, b, tmin, hit);
#endif
    (void)bvh;
    return radinterp__leaf_hit_scalar(r, b, tmin, hit);
}

typedef struct radinterp__bvh_entry { uint32_t ref; float t; } radinterp__bvh_entry;

/* Index of the lowest set bit of a non-zero mask. */
static uint32_t radinterp__bvh_first_bit(unsigned mask)
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
static uint32_t radinterp__bvh_push_children(const radinterp__bvh_node *n, unsigned mask, const float t[RADINTERP__BVH_WIDTH],
                                          radinterp__bvh_entry *stack, uint32_t *top)
{
    radinterp__bvh_entry e[RADINTERP__BVH_WIDTH];
    uint32_t k = 0, i = radinterp__bvh_first_bit(mask), j, rest = mask & (mask - 1);
    if (!rest) return n->child[i];   /* one child: nothing to push */
    j = radinterp__bvh_first_bit(rest);
    if (!(rest & (rest - 1))) {      /* two children */
        uint32_t near = t[j] < t[i] ? j : i, far = near == i ? j : i;
        stack[*top].ref = n->child[far];
        stack[*top].t = t[far];
        (*top)++;
        return n->child[near];
    }
    for (; mask; mask &= mask - 1) {   /* insertion sort, stable */
        i = radinterp__bvh_first_bit(mask);
        for (j = k++; j > 0 && e[j - 1].t > t[i]; j--) e[j] = e[j - 1];
        e[j].ref = n->child[i];
        e[j].t = t[i];
    }
    while (--k) stack[(*top)++] = e[k];
    return e[0].ref;
}

/* Closest hit in (tmin, hit->t), or with any_hit the first hit found. */
static int radinterp__bvh_traverse(const radinterp__bvh *bvh, const radinterp__ray *r, float tmin, radinterp__hit *hit, int any_hit)
{
    radinterp__bvh_entry stack[RADINTERP__BVH_STACK];
    uint32_t top = 0, ref = bvh->root;
    if (bvh->tri_count == 0) return 0;   /* an empty tree: no root to enter */
    for (;;) {
        if (ref & RADINTERP__BVH_LEAF) {
            uint32_t b = (ref & ~RADINTERP__BVH_LEAF) >> 3, end = b + (ref & 7u) + 1;
            for (; b < end; b++)
                if (radinterp__bvh_leaf_hit(bvh, r, &bvh->blocks[b], tmin, hit) && any_hit) return 1;
        } else {
            float t[RADINTERP__BVH_WIDTH];
            const radinterp__bvh_node *n = &bvh->nodes[ref];
            unsigned mask = radinterp__bvh_node_hits(bvh, r, n, tmin, hit->t, t);
            if (mask) {
                ref = radinterp__bvh_push_children(n, mask, t, stack, &top);
                continue;
            }
        }
        do {   /* entries behind the closest hit are skipped */
            if (!top) return hit->tri != RADINTERP__NO_HIT;
            top--;
        } while (stack[top].t > hit->t * RADINTERP__BVH_ROUND_UP);
        ref = stack[top].ref;
    }
}

/* Closest hit in (tmin, tmax). Returns 1 and fills *hit, else hit->tri = RADINTERP__NO_HIT. */
static int radinterp__bvh_intersect(const radinterp__bvh *bvh, const float org[3], const float dir[3],
                                 float tmin, float tmax, radinterp__hit *hit)
{
    radinterp__ray r;
    radinterp__ray_setup(&r, org, dir);
    hit->t = tmax;
    hit->u = hit->v = 0.0f;
    hit->tri = RADINTERP__NO_HIT;
    return radinterp__bvh_traverse(bvh, &r, tmin, hit, 0);
}

/* Any hit in (tmin, tmax): for shadow rays. */
static int radinterp__bvh_occluded(const radinterp__bvh *bvh, const float org[3], const float dir[3],
                                float tmin, float tmax)
{
    radinterp__ray r;
    radinterp__hit hit;
    radinterp__ray_setup(&r, org, dir);
    hit.t = tmax;
    hit.u = hit.v = 0.0f;
    hit.tri = RADINTERP__NO_HIT;
    return radinterp__bvh_traverse(bvh, &r, tmin, &hit, 1);
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

   typedef int (*radinterp_write_fn)(void *user, const void *bytes, size_t n); // 0 = ok
   typedef int (*radinterp_read_fn)(void *user, void *bytes, size_t n);        // 0 = all n bytes read
*/

/* CRC-32 (IEEE 802.3, reflected, as zlib and PNG). The table is built on the
   stack per stream: 256 entries, cheaper than one page of data. */
typedef struct radinterp__crc { uint32_t table[256]; uint32_t value; } radinterp__crc;

static void radinterp__crc_init(radinterp__crc *c)
{
    uint32_t i, k;
    for (i = 0; i < 256; i++) {
        uint32_t v = i;
        for (k = 0; k < 8; k++) v = (v & 1u) ? 0xEDB88320u ^ (v >> 1) : v >> 1;
        c->table[i] = v;
    }
    c->value = 0xFFFFFFFFu;
}
static void radinterp__crc_add(radinterp__crc *c, const void *bytes, size_t n)
{
    const unsigned char *p = (const unsigned char *)bytes;
    uint32_t v = c->value;
    while (n--) v = c->table[(v ^ *p++) & 0xFFu] ^ (v >> 8);
    c->value = v;
}
static uint32_t radinterp__crc_final(const radinterp__crc *c) { return c->value ^ 0xFFFFFFFFu; }

typedef struct radinterp__writer {
    radinterp_write_fn write;
    void *user;
    radinterp__crc crc;
    int failed;        /* a write callback failed: RADINTERP_ERROR_IO */
} radinterp__writer;

static void radinterp__put(radinterp__writer *w, const void *bytes, size_t n)
{
    if (w->failed || n == 0) return;
    radinterp__crc_add(&w->crc, bytes, n);
    if (w->write(w->user, bytes, n) != 0) w->failed = 1;
}
static void radinterp__put_u32(radinterp__writer *w, uint32_t v)
{
    unsigned char b[4];
    b[0] = (unsigned char)v; b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16); b[3] = (unsigned char)(v >> 24);
    radinterp__put(w, b, 4);
}
static void radinterp__put_u64(radinterp__writer *w, uint64_t v)
{
    radinterp__put_u32(w, (uint32_t)v);
    radinterp__put_u32(w, (uint32_t)(v >> 32));
}
static void radinterp__put_f32(radinterp__writer *w, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    radinterp__put_u32(w, v);
}
static void radinterp__put_f32_array(radinterp__writer *w, const float *f, size_t n)
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
        radinterp__put(w, buf, 4 * m);
        i += m;
    }
}
static void radinterp__put_u32_array(radinterp__writer *w, const uint32_t *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) radinterp__put_u32(w, v[i]);
}

typedef struct radinterp__reader {
    radinterp_read_fn read;
    void *user;
    radinterp__crc crc;
    uint64_t remaining;  /* payload bytes not yet read, from the header */
    int failed;          /* short read or a size past the payload: corrupt */
} radinterp__reader;

static void radinterp__get(radinterp__reader *r, void *bytes, size_t n)
{
    if (r->failed) { memset(bytes, 0, n); return; }
    if (n > r->remaining || r->read(r->user, bytes, n) != 0) {
        r->failed = 1;
        memset(bytes, 0, n);
        return;
    }
    r->remaining -= n;
    radinterp__crc_add(&r->crc, bytes, n);
}
static uint32_t radinterp__get_u32(radinterp__reader *r)
{
    unsigned char b[4];
    radinterp__get(r, b, 4);
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}
static uint64_t radinterp__get_u64(radinterp__reader *r)
{
    uint64_t lo = radinterp__get_u32(r);
    return lo | ((uint64_t)radinterp__get_u32(r) << 32);
}
static float radinterp__get_f32(radinterp__reader *r)
{
    uint32_t v = radinterp__get_u32(r);
    float f;
    memcpy(&f, &v, 4);
    return f;
}
/* True when count items of item_bytes each can still be in the payload:
   call before allocating anything sized by a count read from the input. */
static int radinterp__can_hold(radinterp__reader *r, uint64_t count, uint64_t item_bytes)
{
    if (item_bytes && count > r->remaining / item_bytes) { r->failed = 1; return 0; }
    return !r->failed;
}

/* Memory-buffer streams behind the public save_to_memory/load_from_memory. */
typedef struct radinterp__membuf {
    unsigned char *data;
    size_t size, capacity, pos;
    const radinterp_allocator *a;
} radinterp__membuf;

static int radinterp__membuf_write(void *user, const void *bytes, size_t n)
{
    radinterp__membuf *m = (radinterp__membuf *)user;
    if (n > m->capacity - m->size) {
        size_t cap = m->capacity ? m->capacity : 4096;
        unsigned char *p;
        while (cap - m->size < n) {
            if (cap > SIZE_MAX / 2) return -1;
            cap *= 2;
        }
        p = (unsigned char *)radinterp__alloc(m->a, cap);
        if (!p) return -1;
        if (m->size) memcpy(p, m->data, m->size);
        radinterp__free(m->a, m->data);
        m->data = p;
        m->capacity = cap;
    }
    memcpy(m->data + m->size, bytes, n);
    m->size += n;
    return 0;
}

static int radinterp__membuf_read(void *user, void *bytes, size_t n)
{
    radinterp__membuf *m = (radinterp__membuf *)user;
    if (n > m->size - m->pos) return -1;
    memcpy(bytes, m->data + m->pos, n);
    m->pos += n;
    return 0;
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

/* Sizes the batches of a long loop of independent jobs so that progress is
   called after about `interval` seconds of the process's CPU time, whatever
   one job costs (a mesh sample point in a penumbra costs a hundred times one
   in the open). CPU time (RADINTERP_CPU_SECONDS) measures work: a loaded
   machine does not shrink the batches, two threads fill them twice as fast.
   The first batch is one job; a batch doubles while it takes under half the
   interval and shrinks in proportion when it takes longer, so with jobs of
   even cost no batch takes more than the interval or one job. Every batched
   loop in this file is split-invariant (a job writes only its own results;
   what is gathered after a batch is gathered in index order), so the split
   changes how often progress is called, never a result. With no clock (a
   negative reading) batches keep their largest size. */
typedef struct radinterp__pacer {
    uint32_t jobs;      /* jobs in the next batch */
    uint32_t max_jobs;  /* the loop's ceiling (its buffers) */
    double interval;    /* seconds of CPU time between progress calls */
    double start;       /* CPU seconds when the running batch began */
} radinterp__pacer;

/* A desc's progress_interval, its default for 0. */
static double radinterp__progress_interval(float interval)
{
    return interval > 0.0f ? (double)interval : RADINTERP__PROGRESS_INTERVAL;
}

/* Whether progress is due inside a serial loop: the interval has passed
   since the last call (at `reported` CPU seconds). */
static int radinterp__progress_due(double reported, float interval)
{
    return RADINTERP_CPU_SECONDS() - reported >= radinterp__progress_interval(interval);
}

static void radinterp__pacer_init(radinterp__pacer *p, float interval, uint32_t max_jobs)
{
    p->max_jobs = max_jobs ? max_jobs : 1u;
    p->jobs = 1;
    p->interval = radinterp__progress_interval(interval);
    p->start = -1.0;
}

/* Jobs for the next batch (at most remaining); starts its clock. */
static uint32_t radinterp__pacer_next(radinterp__pacer *p, uint32_t remaining)
{
    p->start = RADINTERP_CPU_SECONDS();
    if (!(p->start >= 0.0)) p->jobs = p->max_jobs;
    return p->jobs < remaining ? p->jobs : remaining;
}

/* After a batch: the next one's size from this one's cost. */
static void radinterp__pacer_adapt(radinterp__pacer *p)
{
    double spent = RADINTERP_CPU_SECONDS() - p->start, jobs;
    if (!(p->start >= 0.0) || !(spent >= 0.0)) return;   /* no clock, or one that wrapped: keep the size */
    jobs = spent < 0.5 * p->interval ? 2.0 * p->jobs : spent > p->interval ? p->jobs * (p->interval / spent) : p->jobs;
    p->jobs = jobs >= p->max_jobs ? p->max_jobs : jobs < 1.0 ? 1u : (uint32_t)jobs;
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

/* (i + 1) % n for 0 <= i < n: the next corner of a polygon of n. Without
   the division: a mesh sample's polygon loops (clipping, splitting, areas)
   spent a few percent of a building's mesh in it. */
static int radinterp__next(int i, int n) { return i + 1 < n ? i + 1 : 0; }
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

/* atan2(y, x) for y >= 0, to within 2e-16 relative (checked against the C
   library on millions of arguments by the tests), about twice as fast as
   the library's: the angle of the smaller over the larger of y and |x| is
   taken to |t| <= tan(pi / 8) by atan(a / b) = pi / 4 + atan((a - b) /
   (a + b)), where the rational approximation of atan of Cephes (Moshier)
   holds to full precision. */
static double radinterp__atan2_pos(double y, double x)
{
    static const double P[5] = {-8.750608600031904122785e-01, -1.615753718733365076637e+01,
                                -7.500855792314704667340e+01, -1.228866684490136173410e+02,
                                -6.485021904942025371773e+01};
    static const double Q[5] = {2.485846490142306297962e+01, 1.650270098316988542046e+02,
                                4.328810604912902668951e+02, 4.853903996359136964868e+02,
                                1.945506571482613964425e+02};
    double ax = fabs(x), a, b, t, z, r, base = 0.0;
    int swap = y > ax;
    a = swap ? ax : y;  /* a <= b */
    b = swap ? y : ax;
    if (!(b > 0.0)) return x < 0.0 ? RADINTERP__PI : 0.0;
    if (a > 0.41421356237309504880 * b) {
        t = (a - b) / (a + b);
        base = 0.25 * RADINTERP__PI;
    } else {
        t = a / b;
    }
    z = t * t;
    r = (((P[0] * z + P[1]) * z + P[2]) * z + P[3]) * z + P[4];
    r /= ((((z + Q[0]) * z + Q[1]) * z + Q[2]) * z + Q[3]) * z + Q[4];
    r = base + (t + t * z * r);
    if (swap) r = 0.5 * RADINTERP__PI - r;
    return x < 0.0 ? RADINTERP__PI - r : r;
}

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
    return radinterp__atan2_pos(s, radinterp__d3_dot(ra, rb)) * radinterp__d3_dot(n, c) / s;
}

/* The vector kernel below matches the scalar radinterp__ff_edge only
   where the compiler fuses no a * b + c on its own: no FMA in the target,
   or GCC in an ISO mode (-std=c99 turns its contraction off). Clang
   contracts within an expression by default and GCC's GNU modes across
   them, so there the scalar code serves. Four lanes with AVX, else two
   (SSE2). */
#if defined(RADINTERP__SSE) && \
    (!defined(__FMA__) || (defined(__GNUC__) && !defined(__clang__) && defined(__STRICT_ANSI__)))
#define RADINTERP__FF_SIMD 1
#if defined(__AVX__)
#include <immintrin.h>
typedef __m256d radinterp__vd;
#define RADINTERP__VW 4
#define RADINTERP__V(op) _mm256_##op
#define RADINTERP__VGT(a, b) _mm256_cmp_pd(a, b, _CMP_GT_OQ)
#define RADINTERP__VEQ(a, b) _mm256_cmp_pd(a, b, _CMP_EQ_OQ)
#else
typedef __m128d radinterp__vd;
#define RADINTERP__VW 2
#define RADINTERP__V(op) _mm_##op
#define RADINTERP__VGT(a, b) _mm_cmpgt_pd(a, b)
#define RADINTERP__VEQ(a, b) _mm_cmpeq_pd(a, b)
#endif
#define RADINTERP__VADD(a, b) RADINTERP__V(add_pd)(a, b)
#define RADINTERP__VSUB(a, b) RADINTERP__V(sub_pd)(a, b)
#define RADINTERP__VMUL(a, b) RADINTERP__V(mul_pd)(a, b)
#define RADINTERP__VDIV(a, b) RADINTERP__V(div_pd)(a, b)
#define RADINTERP__VSET(x) RADINTERP__V(set1_pd)(x)

static radinterp__vd radinterp__vsel(radinterp__vd m, radinterp__vd a, radinterp__vd b)
{
    return RADINTERP__V(or_pd)(RADINTERP__V(and_pd)(m, a), RADINTERP__V(andnot_pd)(m, b));
}

/* radinterp__ff_edge for RADINTERP__VW edges at once, operation for
   operation (the same products, sums, quotients and roots in the same
   order, the branches as selections), so every lane is bit for bit the
   scalar result; ax..bz hold the edges' ends. */
static radinterp__vd radinterp__ff_edge_v(radinterp__vd ax, radinterp__vd ay, radinterp__vd az, radinterp__vd bx,
                                          radinterp__vd by, radinterp__vd bz, const double *n)
{
    const radinterp__vd zero = RADINTERP__V(setzero_pd)(), pi = RADINTERP__VSET(RADINTERP__PI);
    radinterp__vd cx = RADINTERP__VSUB(RADINTERP__VMUL(ay, bz), RADINTERP__VMUL(az, by));
    radinterp__vd cy = RADINTERP__VSUB(RADINTERP__VMUL(az, bx), RADINTERP__VMUL(ax, bz));
    radinterp__vd cz = RADINTERP__VSUB(RADINTERP__VMUL(ax, by), RADINTERP__VMUL(ay, bx));
    radinterp__vd s = RADINTERP__V(sqrt_pd)(RADINTERP__VADD(RADINTERP__VADD(RADINTERP__VMUL(cx, cx), RADINTERP__VMUL(cy, cy)),
                                                            RADINTERP__VMUL(cz, cz)));
    radinterp__vd x = RADINTERP__VADD(RADINTERP__VADD(RADINTERP__VMUL(ax, bx), RADINTERP__VMUL(ay, by)), RADINTERP__VMUL(az, bz));
    radinterp__vd nc = RADINTERP__VADD(RADINTERP__VADD(RADINTERP__VMUL(RADINTERP__VSET(n[0]), cx),
                                                       RADINTERP__VMUL(RADINTERP__VSET(n[1]), cy)),
                                       RADINTERP__VMUL(RADINTERP__VSET(n[2]), cz));
    /* radinterp__atan2_pos(s, x) */
    radinterp__vd fx = RADINTERP__V(andnot_pd)(RADINTERP__VSET(-0.0), x), swap = RADINTERP__VGT(s, fx);
    radinterp__vd a = radinterp__vsel(swap, fx, s), b = radinterp__vsel(swap, s, fx);
    radinterp__vd big = RADINTERP__VGT(a, RADINTERP__VMUL(RADINTERP__VSET(0.41421356237309504880), b));
    radinterp__vd t = RADINTERP__VDIV(radinterp__vsel(big, RADINTERP__VSUB(a, b), a), radinterp__vsel(big, RADINTERP__VADD(a, b), b));
    radinterp__vd base = RADINTERP__V(and_pd)(big, RADINTERP__VSET(0.25 * RADINTERP__PI)), z = RADINTERP__VMUL(t, t);
    radinterp__vd num, den, r, neg;
    num = RADINTERP__VADD(RADINTERP__VMUL(RADINTERP__VSET(-8.750608600031904122785e-01), z),
                          RADINTERP__VSET(-1.615753718733365076637e+01));
    num = RADINTERP__VADD(RADINTERP__VMUL(num, z), RADINTERP__VSET(-7.500855792314704667340e+01));
    num = RADINTERP__VADD(RADINTERP__VMUL(num, z), RADINTERP__VSET(-1.228866684490136173410e+02));
    num = RADINTERP__VADD(RADINTERP__VMUL(num, z), RADINTERP__VSET(-6.485021904942025371773e+01));
    den = RADINTERP__VADD(RADINTERP__VMUL(RADINTERP__VADD(z, RADINTERP__VSET(2.485846490142306297962e+01)), z),
                          RADINTERP__VSET(1.650270098316988542046e+02));
    den = RADINTERP__VADD(RADINTERP__VMUL(den, z), RADINTERP__VSET(4.328810604912902668951e+02));
    den = RADINTERP__VADD(RADINTERP__VMUL(den, z), RADINTERP__VSET(4.853903996359136964868e+02));
    den = RADINTERP__VADD(RADINTERP__VMUL(den, z), RADINTERP__VSET(1.945506571482613964425e+02));
    r = RADINTERP__VDIV(num, den);
    r = RADINTERP__VADD(base, RADINTERP__VADD(t, RADINTERP__VMUL(RADINTERP__VMUL(t, z), r)));
    r = radinterp__vsel(swap, RADINTERP__VSUB(RADINTERP__VSET(0.5 * RADINTERP__PI), r), r);
    neg = RADINTERP__VGT(zero, x);
    r = radinterp__vsel(neg, RADINTERP__VSUB(pi, r), r);
    /* atan2_pos's !(b > 0) needs s = 0, masked below, or s NaN, NaN anyway */
    r = RADINTERP__VDIV(RADINTERP__VMUL(r, nc), s);
    return RADINTERP__V(andnot_pd)(RADINTERP__VEQ(s, zero), r);   /* an edge through p: 0 */
}
#endif

#if !defined(RADINTERP__VW)
#define RADINTERP__VW 1
#endif
/* Edge terms are exactly antisymmetric in the edge's ends where no a * b + c
   is fused differently in the two orders, which the guard of the vector
   kernel ensures; elsewhere (a compiler that contracts) radinterp__query_children
   computes every edge. */
#if defined(RADINTERP__FF_SIMD)
#define RADINTERP__FF_SHARE 1
#else
#define RADINTERP__FF_SHARE 0
#endif
#define RADINTERP__FF_ROWS 16   /* edges radinterp__ff_rows takes at once: a quad's four children */

/* radinterp__ff_edge of the edges a -> b given as rows of coordinates
   (a[k][i] is coordinate k of edge i's start) into e[0 .. count), count <=
   RADINTERP__FF_ROWS; each row readable RADINTERP__VW - 1 entries past
   count (those lanes' terms are unused). */
static void radinterp__ff_rows(const double *const a[3], const double *const b[3], int count, const double *n, double *e)
{
#if defined(RADINTERP__FF_SIMD)
    double out[RADINTERP__FF_ROWS + RADINTERP__VW];
    int i;
    for (i = 0; i < count; i += RADINTERP__VW)
        RADINTERP__V(storeu_pd)(out + i, radinterp__ff_edge_v(RADINTERP__V(loadu_pd)(a[0] + i), RADINTERP__V(loadu_pd)(a[1] + i),
                                                             RADINTERP__V(loadu_pd)(a[2] + i), RADINTERP__V(loadu_pd)(b[0] + i),
                                                             RADINTERP__V(loadu_pd)(b[1] + i), RADINTERP__V(loadu_pd)(b[2] + i), n));
    if (count > 0) memcpy(e, out, (size_t)count * sizeof *e);
#else
    int i;
    for (i = 0; i < count; i++) {
        double ra[3], rb[3];
        int k;
        for (k = 0; k < 3; k++) { ra[k] = a[k][i]; rb[k] = b[k][i]; }
        e[i] = radinterp__ff_edge(ra, rb, n);
    }
#endif
}

/* radinterp__ff_edge of the edges r[i] -> r[(i + 1) % count] into e[i]
   (count <= RADINTERP__POLY_MAX), RADINTERP__VW at a time where the vector
   kernel is compiled (RADINTERP__FF_SIMD): the form factors of sources and
   shadow pieces took a seventh (building_1k) to a fifth (the office) of a
   mesh build's time, and their edges are independent. The last lanes repeat the first edges, their
   terms unused. Bit for bit the scalar terms; the callers sum them in edge
   order. */
static void radinterp__ff_edges(const double (*r)[3], int count, const double *n, double *e)
{
    double c[3][RADINTERP__POLY_MAX + RADINTERP__VW];
    const double *a[3], *b[3];
    int i, k, j = 0;
    if (count < 1) return;
    for (i = 0; i < count + RADINTERP__VW; i++, j = radinterp__next(j, count))   /* j = i % count */
        for (k = 0; k < 3; k++) c[k][i] = r[j][k];
    for (k = 0; k < 3; k++) { a[k] = c[k]; b[k] = c[k] + 1; }
    radinterp__ff_rows(a, b, count, n, e);
}

/* Eq. 6.1 from a polygon's edge terms e[0 .. count), summed in edge order. */
static double radinterp__ff_sum(const double *e, int count)
{
    double sum = 0.0;
    int i;
    for (i = 0; i < count; i++) sum += e[i];
    return -sum / (2.0 * RADINTERP__PI);
}

/* Eq. 6.1 for a polygon wholly in front of p's tangent plane: positive when
   the polygon winds counter-clockwise seen from the side facing p. */
static double radinterp__ff_poly(const double *p, const double *n, const double (*v)[3], int count)
{
    double r[RADINTERP__POLY_MAX][3], e[RADINTERP__POLY_MAX];
    int i;
    for (i = 0; i < count; i++) radinterp__d3_sub(v[i], p, r[i]);
    radinterp__ff_edges((const double (*)[3])r, count, n, e);
    return radinterp__ff_sum(e, count);
}

/* Sutherland-Hodgman: the part of the convex polygon in n . x >= d.
   Returns the vertex count of out (at most count + 1; < 3 means empty). */
static int radinterp__clip_poly(const double (*in)[3], int count, const double *n, double d, double (*out)[3])
{
    int i, m = 0;
    for (i = 0; i < count; i++) {
        const double *a = in[i], *b = in[radinterp__next(i, count)];
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
   - leaf lists are not kept: a leaf's list (the links delivering to it,
     its own and its ancestors', in that order, each with the blockers of
     the link that may block between the leaf and the source) is built
     where it is used (section 14): by a point query link by link, by the
     mesh build for a batch of leaves. leaf_margin says where they hold.
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
    float tf[3];              /* transmittance (thin glass); 0 = opaque */
    uint32_t glass;           /* some channel of tf is above 0 */
} radinterp__patch;

/* A patch's plane and glass flag, copied from the patch into an array of
   their own: radinterp__planes_hide's walk tests the plane of every
   triangle it meets, and the patches are five times the size (the walk
   missed the cache on each). */
typedef struct radinterp__plane {
    double n[3], d;
    uint32_t glass;
} radinterp__plane;

typedef struct radinterp__node {
    float v[4][3];            /* corners, as the patch's */
    uint16_t count;           /* 3 or 4 */
    uint16_t enclosed;        /* a partly open node: which points its links sample are enclosed, when
                                 RADINTERP__ENCLOSED_KNOWN is set (radinterp__node_enclosure); beside
                                 count, so that the node keeps its size */
    uint32_t patch;
    uint32_t parent;          /* NONE for a root */
    uint32_t child;           /* first of four consecutive children; NONE for a leaf */
    uint16_t depth;           /* 0 for a root */
    uint16_t divided;         /* its open points, or a child's, lie on both sides of an enclosed band (a wall
                                 standing on it): it may split below min_area (radinterp__can_split) */
    uint32_t first_link, link_count;   /* the links this node gathers */
    uint32_t first_clink, clink_count; /* the cluster links it gathers (section 12) */
    float area;
    float lo[3], hi[3];
    float b[3];               /* radiosity B (W/m^2) of the node's open part, constant over it */
    float h[3];               /* irradiance gathered by this node's own links (mean over the whole node) */
    float level;              /* irradiance (largest channel) over its open part, all links (mean) */
    float dim;                /* least irradiance (largest channel) of its lit open leaves, 0 if none: the
                                 scale its links' errors are measured against (relative refinement) */
    float open;               /* fraction of the node not enclosed by touching geometry (such as the
                                 floor under a box standing on it); enclosed parts receive and show nothing */
    float sky[3];             /* irradiance from the sky (mean over the whole node), measured when made */
    float sky_spread;         /* max - min of the sky's irradiance at fixed points of the node (refinement) */
    float spread;             /* largest max - min over the channels of the radiosities of its open leaves
                                 (push-pull; 0 for a leaf): what a link that sees part of it may misjudge */
} radinterp__node;

#define RADINTERP__ENCLOSED_KNOWN 0x8000u

#define RADINTERP__LINK_FINAL 1u   /* may not be refined further */
#define RADINTERP__LINK_DEAD 2u    /* carries nothing: dropped at the next rebuild */
#define RADINTERP__LINK_PARTLY 4u  /* its source is partly hidden from its receiver (radinterp__link_source_spread) */

typedef struct radinterp__link {
    uint32_t receiver, source;         /* nodes */
    float ff;                          /* F: mean point-to-source factor over the receiver (4.2), of the part
                                          seen through no pane */
    float dff;                         /* max - min of the point factors: transport error / B_src */
    float vis;                         /* what passes (clear, or through panes in their mean channel) over F
                                          with no blockers: the visible fraction */
    uint32_t first_blocker, blocker_count;
    uint32_t flags;
    float gff;                         /* the factor of the part seen through panes, panes counted clear */
    float glass[3];                    /* mean transmittance of that part: F = ff + gff * glass per channel */
} radinterp__link;

/* A cluster of patches (section 12): a node of the binary tree above the
   patches' quadtrees. */
typedef struct radinterp__cluster {
    float lo[3], hi[3];         /* box of its patches */
    uint32_t child[2];          /* elements: clusters (RADINTERP__CLUSTER | index) or patches' root nodes */
    uint32_t parent;            /* NONE at the top */
    uint32_t first, count;      /* its patches: cluster_order[first .. first + count) */
    uint32_t first_link, link_count;   /* the cluster links it gathers */
    float power[6][3];          /* sum of A open B max(0, n . a) over its patches, a = +x -x +y -y +z -z */
    float bound;                /* largest channel of sum_k max(power[+k], power[-k]): at least its power
                                   toward any direction */
    float hmin;                 /* least irradiance (largest channel) of a lit leaf of its patches; 0 when none
                                   is lit */
    float e[6][3];              /* irradiance its own links deliver to a surface facing each a */
    float down[6][3];           /* the same with its ancestors' (pushed to its patches) */
} radinterp__cluster;

struct radinterp_solution {
    radinterp_allocator allocator;
    /* parameters after defaults */
    double eps, min_area, rel_error_cutoff, push_off, nudge, min_bp_segment, epsilon, diag;
    double eps_relative;               /* 0: eps alone */
    double eps_source;                 /* eps's floor for a source's variation (<= eps) */
    double point_rest;                 /* see PARAMETERS */
    double light_scale;                /* mean emitted radiosity (largest channel) */
    int levels_known;                  /* the receivers' levels have been measured (a gather ran) */
    double *patch_hmin;                /* per patch: least irradiance of a lit leaf (largest channel), 0 if none */
    uint32_t max_iterations, ff_samples, visibility_rays;
    uint32_t visibility;               /* radinterp_visibility of point queries, never DEFAULT */
    uint32_t clustering;               /* radinterp_clustering, never DEFAULT */
    uint64_t seed;
    radinterp_trace_fn trace;
    void *trace_user;
    /* glass and sky (GLASS AND SKY) */
    uint32_t glass_patches;            /* patches with a transmittance */
    int has_sky;
    float sky[3];                      /* constant sky radiance, without a map */
    float *environment;                /* copy of desc.environment, or NULL */
    uint32_t environment_width, environment_height, sky_rays;
    /* scene */
    radinterp__patch *patches;
    uint32_t patch_count, skipped_patches;
    uint32_t caller_count, merged_patches;   /* the caller's patches, and triangles merged into another */
    uint32_t *caller_patch;            /* the caller's patch i is patches[caller_patch[i]] */
    uint32_t *first_caller;            /* per patch: the first caller's patch it holds */
    float scene_lo[3], scene_hi[3];
    radinterp__bvh bvh;
    uint32_t *tri_patch;               /* BVH triangle -> patch */
    radinterp__plane *planes;          /* per patch: its plane (radinterp__planes_hide) */
    /* hierarchy */
    radinterp__node *nodes;
    uint32_t node_count, node_cap;
    radinterp__link *links;
    uint32_t link_count;
    uint32_t *blockers;                /* the links' blocker lists, in link order */
    uint64_t blocker_count;
    size_t link_cap, blocker_cap;      /* room in links and blockers (refinement reuses them) */
    struct radinterp__clink *clinks;   /* links with a cluster at either end, by receiver */
    uint32_t clink_count;
    radinterp__cluster *clusters;      /* clusters[0] is the top; parents before children */
    uint32_t cluster_count;
    uint32_t *cluster_order;           /* the patches in cluster order */
    double *cluster_cdf;               /* prefix sums of their areas */
    uint32_t *patch_cluster;           /* the cluster whose child a patch is; NONE without clusters */
    uint64_t culled_links;             /* links dropped because every ray between their ends was blocked */
    uint32_t *leaves;                  /* leaf node indices in patch order */
    uint32_t leaf_count;
    double leaf_margin;                /* the leaf lists hold for points this close to the leaf's box; 0: no leaf
                                          lists, every query reads the links' own blockers */
    /* convex solids (section 13): their back faces cast no shadow of their own */
    uint32_t *patch_solid;             /* solid of each patch; NONE when it belongs to none */
    struct radinterp__solid *solids;
    uint32_t solid_count;
    double (*solid_planes)[4];         /* n, d of each solid's hull planes not covered by patches (holes) */
    uint32_t *solid_plugs;             /* per hole: a patch of another object covering it, or NONE */
    uint32_t solid_plane_count;
    uint32_t *solid_members;           /* patches of each solid, solid after solid */
    uint32_t solid_member_count;
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

/* Area of the largest triangle of three consecutive corners: a quadrilateral
   whose own (signed) area vanishes while this does not crosses itself. */
static double radinterp__largest_corner(const double (*v)[3], int count)
{
    double best = 0.0;
    int i;
    for (i = 0; i < count; i++) {
        double e1[3], e2[3], c[3];
        radinterp__d3_sub(v[i], v[(i + count - 1) % count], e1);
        radinterp__d3_sub(v[(i + 1) % count], v[i], e2);
        radinterp__d3_cross(e1, e2, c);
        if (0.5 * radinterp__d3_len(c) > best) best = 0.5 * radinterp__d3_len(c);
    }
    return best;
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
    if (!(len > 0.0) || 0.5 * len <= 1e-14 * scene_diag * scene_diag)
        return radinterp__largest_corner((const double (*)[3])v, count) > 1e-14 * scene_diag * scene_diag
                   ? RADINTERP__PATCH_NONCONVEX   /* a bow tie whose two lobes cancel */
                   : RADINTERP__PATCH_DEGENERATE;
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

/* Largest signed distance of a polygon's corners (a patch's or a node's)
   from a plane. */
static double radinterp__corners_front(const float (*v)[3], uint32_t count, const double *n, double d)
{
    double best = -DBL_MAX;
    uint32_t i;
    for (i = 0; i < count; i++) {
        double x[3], s;
        radinterp__d3_from_f(v[i], x);
        s = radinterp__d3_dot(n, x) - d;
        if (s > best) best = s;
    }
    return best;
}

static double radinterp__patch_front(const radinterp__patch *pt, const double *n, double d)
{
    return radinterp__corners_front((const float (*)[3])pt->v, pt->count, n, d);
}

static double radinterp__node_front(const radinterp__node *nd, const double *n, double d)
{
    return radinterp__corners_front((const float (*)[3])nd->v, nd->count, n, d);
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

/* Corners of the four children of a node with corners v (3 or 4), in the
   order of section 11. The mesh's quadtrees split with this too, so a
   corner shared by two nodes is one float triple in both trees. */
static void radinterp__child_corners(const float (*v)[3], uint32_t count, float (*ch)[4][3])
{
    float m[4][3], c[3];
    uint32_t k;
    if (count == 4) {
        const float *q[4][4];
        uint32_t i;
        for (k = 0; k < 4; k++) radinterp__mid(v[k], v[(k + 1) % 4], m[k]);
        for (k = 0; k < 3; k++) c[k] = 0.25f * (v[0][k] + v[1][k] + v[2][k] + v[3][k]);
        q[0][0] = v[0]; q[0][1] = m[0]; q[0][2] = c;    q[0][3] = m[3];
        q[1][0] = m[0]; q[1][1] = v[1]; q[1][2] = m[1]; q[1][3] = c;
        q[2][0] = c;    q[2][1] = m[1]; q[2][2] = v[2]; q[2][3] = m[2];
        q[3][0] = m[3]; q[3][1] = c;    q[3][2] = m[2]; q[3][3] = v[3];
        for (k = 0; k < 4; k++)
            for (i = 0; i < 4; i++) memcpy(ch[k][i], q[k][i], 3 * sizeof(float));
    } else {
        memset(ch, 0, 4 * sizeof ch[0]);   /* the unused 4th corners stay zero */
        for (k = 0; k < 3; k++) radinterp__mid(v[k], v[(k + 1) % 3], m[k]);
        memcpy(ch[0][0], v[0], 12); memcpy(ch[0][1], m[0], 12); memcpy(ch[0][2], m[2], 12);
        memcpy(ch[1][0], m[0], 12); memcpy(ch[1][1], v[1], 12); memcpy(ch[1][2], m[1], 12);
        memcpy(ch[2][0], m[2], 12); memcpy(ch[2][1], m[1], 12); memcpy(ch[2][2], v[2], 12);
        memcpy(ch[3][0], m[1], 12); memcpy(ch[3][1], m[2], 12); memcpy(ch[3][2], m[0], 12);
    }
}

/* Splits a leaf into four children (4.1) that start with its radiosity.
   Returns 0, or -1 when out of memory. The node array may move. */
static int radinterp__node_split(radinterp_solution *s, uint32_t index)
{
    radinterp__node *nd, *ch;
    float corners[4][4][3];
    uint32_t first, k;
    if (s->nodes[index].child != RADINTERP__NONE) return 0;
    if (!radinterp__nodes_reserve(s, 4)) return -1;
    nd = &s->nodes[index];
    first = s->node_count;
    ch = &s->nodes[first];
    memset(ch, 0, 4 * sizeof *ch);
    radinterp__child_corners((const float (*)[3])nd->v, nd->count, corners);
    for (k = 0; k < 4; k++) {
        memcpy(ch[k].v, corners[k], sizeof ch[k].v);
        ch[k].count = nd->count;
        ch[k].patch = nd->patch;
        ch[k].parent = index;
        ch[k].child = RADINTERP__NONE;
        ch[k].depth = (uint16_t)(nd->depth + 1);
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

/* Does the ray from org along dir meet the back face of a patch (an
   opaque one: a pane encloses nothing, light passes it)? A miss or a front
   face means the point sees out that way. */
static int radinterp__ray_meets_back(const radinterp_solution *s, const float *org, const float *dir)
{
    radinterp__hit hit;
    const radinterp__patch *hp;
    if (!radinterp__bvh_intersect(&s->bvh, org, dir, 0.0f, FLT_MAX, &hit)) return 0;
    hp = &s->patches[s->tri_patch[hit.tri]];
    return !(hp->n[0] * dir[0] + hp->n[1] * dir[1] + hp->n[2] * dir[2] < 0.0) && !hp->glass;
}

/* Fraction of a node that is open: at a RADINTERP__OPEN_GRID x
   RADINTERP__OPEN_GRID grid of its points, a point
   is enclosed when both rays of an opposite pair, 60 degrees from the
   normal on either side of it (along t, or along b), meet back faces: the
   point lies inside closed geometry resting on it, between two of its
   faces turned away from each other. That covers the floor under a box
   (every direction meets the box's inside) and the strip of floor or
   ceiling inside a wall that stands on it and runs up to the next slab:
   from there the ray along the normal meets the slab's front face, so a
   rule asking every direction for a back face counted the strip open, and
   the strip, which receives nothing, pulled down the radiosity of every
   floor and ceiling it runs under (the building's surfaces came out 4%
   too dark, its points 5.5%). A single one-sided surface (a shelf board
   seen from below) meets one ray of a pair only, so it encloses nothing.
   Enclosed parts neither receive nor show light, so radiosities are kept
   for the open part; without this a node half under a box would carry half
   its real radiosity to everything that sees its open half.
   The grid must resolve such strips: a link's factor is a mean over the
   whole node in which its enclosed points count zero (their rays meet the
   wall's inside), and push-pull divides it by this fraction, so an
   enclosed strip the grid misses darkens the node by the strip's share. A
   3 x 3 grid (points a sixth of the node from its edges) missed the
   10-20 cm strip under a wall on most nodes of a floor or ceiling, and the
   building's floors and ceilings gathered 3.4% and 2.7% less than their
   rays meet (row sums of the factors with B = 1 everywhere; nodes 4 and 5
   levels down 7-9% less). On an 8 x 8 grid the first points lie 1/16 of
   the node from its edges and the row sums agree with the rays within
   0.6% (floors, ceilings, walls) for about 1.5 s of building_1k's solve. */
#define RADINTERP__OPEN_GRID 8

/* Is point p of a patch (normal n) enclosed? The test above, from p moved
   off the patch along n. */
static int radinterp__point_enclosed(const radinterp_solution *s, const double *n, const double *p)
{
    radinterp__vec3 t, b, nv = radinterp__v3((float)n[0], (float)n[1], (float)n[2]);
    double off = 10.0 * s->epsilon * s->diag;
    float org[3];
    int k, pair;
    {   /* a basis around n (Duff et al. 2017) */
        float sg = nv.z >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (sg + nv.z), c = nv.x * nv.y * a;
        t = radinterp__v3(1.0f + sg * nv.x * nv.x * a, sg * c, -sg * nv.x);
        b = radinterp__v3(c, sg + nv.y * nv.y * a, -nv.y);
    }
    for (k = 0; k < 3; k++) org[k] = (float)(p[k] + off * n[k]);
    for (pair = 0; pair < 2; pair++) {
        radinterp__vec3 side = pair == 0 ? t : b;
        float up[3], down[3];
        up[0] = 0.5f * nv.x + 0.866f * side.x; up[1] = 0.5f * nv.y + 0.866f * side.y; up[2] = 0.5f * nv.z + 0.866f * side.z;
        down[0] = 0.5f * nv.x - 0.866f * side.x; down[1] = 0.5f * nv.y - 0.866f * side.y; down[2] = 0.5f * nv.z - 0.866f * side.z;
        if (radinterp__ray_meets_back(s, org, up) && radinterp__ray_meets_back(s, org, down)) return 1;
    }
    return 0;
}

/* Does a row of the openness grid run open, enclosed, open? */
static int radinterp__row_divided(const unsigned char *row, int stride)
{
    int i, state = 0;   /* 0 before any open point, 1 open seen, 2 then an enclosed one */
    for (i = 0; i < RADINTERP__OPEN_GRID; i++) {
        int open = row[i * stride];
        if (open && state == 2) return 1;
        if (open) state = 1;
        else if (state == 1) state = 2;
    }
    return 0;
}

/* The node's open fraction, and in *divided whether an enclosed band
   crosses it with open points on both sides (along a row or a column of
   the grid): the node holds the foot of a wall with a strip of each room
   beside it, which its single radiosity cannot tell apart. */
static float radinterp__node_openness(const radinterp_solution *s, const radinterp__node *nd, int *divided)
{
    const double *n = s->patches[nd->patch].n;
    unsigned char grid[RADINTERP__OPEN_GRID][RADINTERP__OPEN_GRID];
    int i, j, open = 0, k;
    for (i = 0; i < RADINTERP__OPEN_GRID; i++)
        for (j = 0; j < RADINTERP__OPEN_GRID; j++) {
            double u = (i + 0.5) / RADINTERP__OPEN_GRID, v = (j + 0.5) / RADINTERP__OPEN_GRID, p[3];
            for (k = 0; k < 3; k++) {
                if (nd->count == 4)
                    p[k] = (1 - u) * (1 - v) * nd->v[0][k] + u * (1 - v) * nd->v[1][k] + u * v * nd->v[2][k] + (1 - u) * v * nd->v[3][k];
                else
                    p[k] = (1 - sqrt(u)) * nd->v[0][k] + sqrt(u) * (1 - v) * nd->v[1][k] + sqrt(u) * v * nd->v[2][k];
            }
            grid[i][j] = (unsigned char)!radinterp__point_enclosed(s, n, p);
            open += grid[i][j];
        }
    *divided = 0;
    for (i = 0; i < RADINTERP__OPEN_GRID && open > 1 && !*divided; i++)
        *divided = radinterp__row_divided(grid[i], 1) || radinterp__row_divided(&grid[0][i], RADINTERP__OPEN_GRID);
    return (float)open / (float)(RADINTERP__OPEN_GRID * RADINTERP__OPEN_GRID);
}

static void radinterp__node_sky(radinterp_solution *s, uint32_t index);   /* section 12 */
static void radinterp__node_enclosure(radinterp_solution *s, uint32_t index);   /* section 12 */

typedef struct radinterp__open_ctx { radinterp_solution *s; uint32_t first, count; } radinterp__open_ctx;

static void radinterp__open_job(void *ctx_, uint32_t index)
{
    radinterp__open_ctx *ctx = (radinterp__open_ctx *)ctx_;
    uint32_t i = ctx->first + index * 64, end = i + 64;
    if (end > ctx->first + ctx->count) end = ctx->first + ctx->count;
    for (; i < end; i++) {
        int divided;
        ctx->s->nodes[i].open = radinterp__node_openness(ctx->s, &ctx->s->nodes[i], &divided);
        ctx->s->nodes[i].divided = (uint16_t)divided;
        radinterp__node_enclosure(ctx->s, i);
        if (ctx->s->has_sky) radinterp__node_sky(ctx->s, i);
    }
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
static int radinterp__planes_hide(const radinterp_solution *s, const float *alo, const float *ahi, const float *blo,
                                  const float *bhi);   /* section 13 */

/* A link waiting for its form factor: made by the initial linking or by
   splitting a link. Its candidate blockers are its parent's (filtered here
   by the new, narrower shaft) or the shaft culling result. */
typedef struct radinterp__pending {
    uint32_t receiver, source;
    uint32_t first, count;       /* candidates in the input pool; results at the same offset of the output pool */
    uint32_t filter;             /* candidates still need the shaft test */
    uint32_t fresh;              /* candidates from shaft culling here (else the parent link's blockers) */
    uint32_t kept;               /* blockers kept */
    float ff, dff, gff, glass[3], vis;
    uint32_t dead;               /* no part of either element faces the other, or every ray was blocked */
    uint32_t hidden;             /* dead because every ray was blocked */
    uint32_t partly;             /* a shadow ray was blocked, or a receiver point sees none of the source */
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
/* The segment from a to b as a float origin and direction (b at t = 1). */
static void radinterp__segment_floats(const double *a, const double *b, float org[3], float dir[3])
{
    int k;
    for (k = 0; k < 3; k++) {
        org[k] = (float)a[k];
        dir[k] = (float)(b[k] - a[k]);
    }
}

static int radinterp__segment_blocked(const radinterp_solution *s, const double *a, const double *b)
{
    float org[3], dir[3];
    radinterp__segment_floats(a, b, org, dir);
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

/* ---- glass and sky (GLASS AND SKY in the documentation) ----------------
   A pane (a patch whose material has a transmittance) is a thin dielectric
   crossed straight: light along a ray keeps tf of itself per pane, per
   channel, so the visibility between two points is the product of the tf
   of the panes between them (0 when an opaque patch lies between, or more
   than RADINTERP_MAX_GLASS_LAYERS panes). Rays that cross panes use the
   built-in BVH, closest hit after closest hit; scenes without glass keep
   their any-hit shadow rays (and the trace callback). */

/* Light along org + t dir for 0 < t < tmax, per channel, into T: -1 when an
   opaque patch (or a pane past the layer limit) blocks it (T = 0), else the
   number of panes crossed (T the product of their tf). */
static int radinterp__ray_light(const radinterp_solution *s, const float org[3], const float dir[3], float tmax,
                                double T[3])
{
    float tmin = 0.0f;
    int layers = 0, k;
    T[0] = T[1] = T[2] = 1.0;
    for (;;) {
        radinterp__hit hit;
        const radinterp__patch *pt;
        if (!radinterp__bvh_intersect(&s->bvh, org, dir, tmin, tmax, &hit)) return layers;
        pt = &s->patches[s->tri_patch[hit.tri]];
        if (!pt->glass || ++layers > (int)RADINTERP_MAX_GLASS_LAYERS) {
            T[0] = T[1] = T[2] = 0.0;
            return -1;
        }
        for (k = 0; k < 3; k++) T[k] *= pt->tf[k];
        tmin = hit.t;   /* the next surface strictly beyond (a pane given twice, back to back, is one pane) */
    }
}

/* The answer of a ray through no glass: 0 and T = 1 when open, -1 and
   T = 0 when blocked. */
static int radinterp__opaque_light(int blocked, double T[3])
{
    T[0] = T[1] = T[2] = blocked ? 0.0 : 1.0;
    return blocked ? -1 : 0;
}

/* The same for the segment from a to b; without glass on it (glass = 0) a
   plain shadow ray: 0 when open (T = 1), -1 when blocked. */
static int radinterp__segment_light(const radinterp_solution *s, const double *a, const double *b, int glass, double T[3])
{
    float org[3], dir[3];
    if (!glass) return radinterp__opaque_light(radinterp__segment_blocked(s, a, b), T);
    radinterp__segment_floats(a, b, org, dir);
    return radinterp__ray_light(s, org, dir, 1.0f, T);
}

/* How far shadow rays start off the surfaces they join: clear of the
   surfaces' own triangles (and of those they rest on). */
static double radinterp__ray_offset(const radinterp_solution *s) { return 10.0 * s->epsilon * s->diag; }

/* ---- shadow rays inside a shaft ----------------------------------------
   Every shadow ray of a link (or cluster link) runs between points of its
   two elements moved off their surfaces by radinterp__ray_offset, so it
   lies in the shaft (Haines and Wallace) of their boxes grown by that much,
   and, where an end is one surface (not a cluster), on the near side of
   that surface's plane as far as the other end allows. Only the triangles
   that reach that region can block a ray: those of the BVH leaves that
   meet the shaft, less the triangles outside it and those wholly behind
   either end's plane (the receiver's and source's own triangles, which lie
   in the tree's leaves on every ray's path, whenever the other end stands
   clear of the plane). When few are left, the link's rays test just those,
   with the BVH's own triangle test, instead of walking the tree from its
   root for each ray (the walk was 47% of building_1k's solve). A ray is
   blocked when one of these triangles accepts it, as when any triangle of
   the scene does: the triangles left out are ones it cannot meet (tested
   against every triangle in test_radinterp_visibility). The walk of the
   tree answers the same but for rays that run exactly along a face of one
   of its boxes, which it may let through (see radinterp__shaft_rays_box);
   the solutions of the office, the Cornell box and building_1k are
   bit-identical to the walk's. */
#define RADINTERP__SHAFT_TRIS 64   /* more triangles and the rays walk the tree */

typedef struct radinterp__shaft_rays {
    int walk;            /* 1: the rays walk the tree (too many triangles, a trace callback, a one-leaf tree) */
    uint32_t tris;
    uint32_t last;       /* the group of triangles that blocked the last blocked ray: tried first */
    radinterp__bvh_tris block[RADINTERP__SHAFT_TRIS / 4];
    radinterp__bvh_node box[RADINTERP__SHAFT_TRIS / RADINTERP__BVH_WIDTH];   /* the triangles' boxes, block by block */
} radinterp__shaft_rays;

/* One end of a link's rays: its box and, when it is one surface, its plane
   and how far behind that plane the rays may reach (below). */
typedef struct radinterp__ray_end {
    const float *lo, *hi;
    const double *n;     /* NULL for a cluster */
    double d, floor;     /* plane n . x = d; every ray point has n . x - d >= floor */
} radinterp__ray_end;

/* Where the rays run relative to end e's plane: from offset in front at e
   to the other end's points moved by offset, at worst its box's lowest
   corner less offset; pad covers the rounding of the rays' floats. */
static void radinterp__ray_end_floor(radinterp__ray_end *e, const radinterp__ray_end *other, double offset, double pad)
{
    double least = DBL_MAX;
    int c, k;
    if (!e->n) return;
    for (c = 0; c < 8; c++) {
        double x = -e->d;
        for (k = 0; k < 3; k++) x += e->n[k] * (double)((c >> k) & 1 ? other->hi[k] : other->lo[k]);
        least = x < least ? x : least;
    }
    e->floor = (least - offset < offset ? least - offset : offset) - pad;
}

/* Is the triangle wholly behind the region of end e's plane the rays reach? */
static int radinterp__tri_behind(const radinterp__ray_end *e, const radinterp__bvh_tris *b, int lane)
{
    int v;
    if (!e->n) return 0;
    for (v = 0; v < 3; v++)
        if (e->n[0] * b->v[3 * v][lane] + e->n[1] * b->v[3 * v + 1][lane] + e->n[2] * b->v[3 * v + 2][lane] - e->d >=
            e->floor)
            return 0;
    return 1;
}

/* Sets the box of the next triangle: the rays test the boxes first, eight
   at a time with the tree's box test, and then the blocks whose boxes they
   enter. The box is grown by pad: the box test rejects a ray that runs
   exactly along a face of a box (a zero direction component gives a far
   distance of zero there), and a flat triangle's box is all faces. */
static void radinterp__shaft_rays_box(radinterp__shaft_rays *sr, const float *lo, const float *hi, double pad)
{
    radinterp__bvh_node *n = &sr->box[sr->tris / RADINTERP__BVH_WIDTH];
    uint32_t c = sr->tris % RADINTERP__BVH_WIDTH, j;
    int k;
    if (c == 0)   /* a new group: its unused columns are empty boxes, as in the tree */
        for (j = 0; j < RADINTERP__BVH_WIDTH; j++)
            for (k = 0; k < 3; k++) {
                n->box[2 * k][j] = INFINITY;
                n->box[2 * k + 1][j] = -INFINITY;
            }
    for (k = 0; k < 3; k++) {
        n->box[2 * k][c] = (float)(lo[k] - pad);
        n->box[2 * k + 1][c] = (float)(hi[k] + pad);
    }
}

/* Appends the triangles of leaf ref that may meet the rays; 0 when there
   are too many. */
static int radinterp__shaft_rays_leaf(const radinterp_solution *s, radinterp__shaft_rays *sr, const radinterp__shaft *sh,
                                      const radinterp__ray_end *end, double pad, uint32_t ref)
{
    uint32_t block = (ref & ~RADINTERP__BVH_LEAF) >> 3, last = block + (ref & 7u) + 1;
    for (; block < last; block++) {
        const radinterp__bvh_tris *b = &s->bvh.blocks[block];
        int i, k;
        for (i = 0; i < 4; i++) {
            float lo[3], hi[3];
            radinterp__bvh_tris *to;
            if (i > 0 && b->id[i] == b->id[i - 1]) continue;   /* unused columns repeat the last triangle */
            for (k = 0; k < 3; k++) {
                lo[k] = radinterp__minf(b->v[k][i], radinterp__minf(b->v[3 + k][i], b->v[6 + k][i]));
                hi[k] = radinterp__maxf(b->v[k][i], radinterp__maxf(b->v[3 + k][i], b->v[6 + k][i]));
            }
            if (radinterp__shaft_culls(sh, lo, hi, 0.0) || radinterp__tri_behind(&end[0], b, i) ||
                radinterp__tri_behind(&end[1], b, i))
                continue;
            if (sr->tris == RADINTERP__SHAFT_TRIS) return 0;
            radinterp__shaft_rays_box(sr, lo, hi, pad);
            to = &sr->block[sr->tris / 4];
            for (k = 0; k < 9; k++) to->v[k][sr->tris % 4] = b->v[k][i];
            to->id[sr->tris % 4] = b->id[i];
            sr->tris++;
        }
    }
    return 1;
}

/* The triangles the rays between ends a and b may meet (above). */
static void radinterp__shaft_rays_init(const radinterp_solution *s, radinterp__shaft_rays *sr, radinterp__ray_end a,
                                       radinterp__ray_end b)
{
    uint32_t stack[RADINTERP__BVH_STACK], top = 0, ref = s->bvh.root;
    radinterp__shaft sh;
    radinterp__ray_end end[2];
    float glo[2][3], ghi[2][3];
    double size = s->diag, grow = radinterp__ray_offset(s), pad;
    int i, k;
    sr->walk = 1;
    sr->tris = 0;
    sr->last = 0;
    if (s->trace || s->bvh.tri_count == 0 || (ref & RADINTERP__BVH_LEAF)) return;
    for (k = 0; k < 3; k++) {
        size = fabs((double)s->scene_lo[k]) > size ? fabs((double)s->scene_lo[k]) : size;
        size = fabs((double)s->scene_hi[k]) > size ? fabs((double)s->scene_hi[k]) : size;
    }
    pad = 1e-5 * size;   /* float rays round their ends by about 1e-7 of the coordinates */
    end[0] = a;
    end[1] = b;
    radinterp__ray_end_floor(&end[0], &b, grow, pad);
    radinterp__ray_end_floor(&end[1], &a, grow, pad);
    for (k = 0; k < 3; k++) {
        glo[0][k] = (float)(a.lo[k] - grow - pad); ghi[0][k] = (float)(a.hi[k] + grow + pad);
        glo[1][k] = (float)(b.lo[k] - grow - pad); ghi[1][k] = (float)(b.hi[k] + grow + pad);
    }
    radinterp__shaft_build(&sh, glo[0], ghi[0], glo[1], ghi[1]);
    for (;;) {
        const radinterp__bvh_node *n = &s->bvh.nodes[ref];
        for (i = 0; i < RADINTERP__BVH_WIDTH; i++) {
            float lo[3], hi[3];
            lo[0] = n->box[0][i]; lo[1] = n->box[2][i]; lo[2] = n->box[4][i];
            hi[0] = n->box[1][i]; hi[1] = n->box[3][i]; hi[2] = n->box[5][i];
            if (!(lo[0] <= hi[0]) || radinterp__shaft_culls(&sh, lo, hi, 0.0)) continue;
            if (!(n->child[i] & RADINTERP__BVH_LEAF)) stack[top++] = n->child[i];
            else if (!radinterp__shaft_rays_leaf(s, sr, &sh, end, pad, n->child[i])) return;
        }
        if (!top) break;
        ref = stack[--top];
    }
    for (k = (int)sr->tris; k % 4; k++) {   /* the last block's unused columns repeat its last triangle */
        radinterp__bvh_tris *to = &sr->block[k / 4];
        for (i = 0; i < 9; i++) to->v[i][k % 4] = to->v[i][k % 4 - 1];
        to->id[k % 4] = to->id[k % 4 - 1];
    }
    sr->walk = 0;
}

/* An end of a link's rays: element el (a node or a cluster). */
static radinterp__ray_end radinterp__elem_ray_end(const radinterp_solution *s, uint32_t el);   /* below */

/* The shadow ray radinterp__segment_blocked casts from a to b (t in
   (0, 1)), with no hit yet. */
static void radinterp__segment_ray(const double *a, const double *b, radinterp__ray *r, radinterp__hit *hit)
{
    float org[3], dir[3];
    radinterp__segment_floats(a, b, org, dir);
    radinterp__ray_setup(r, org, dir);
    hit->t = 1.0f;
    hit->u = hit->v = 0.0f;
    hit->tri = RADINTERP__NO_HIT;
}

/* Does a triangle of the shaft's group g block ray r (no hit yet)? */
static int radinterp__shaft_group_blocks(const radinterp_solution *s, const radinterp__shaft_rays *sr, const radinterp__ray *r,
                                         radinterp__hit *hit, uint32_t g)
{
    float t[RADINTERP__BVH_WIDTH];
    unsigned mask = radinterp__bvh_node_hits(&s->bvh, r, &sr->box[g], 0.0f, 1.0f, t), i;
    for (i = 0; i < RADINTERP__BVH_WIDTH / 4; i++)
        if ((mask >> (4 * i) & 15u) && radinterp__bvh_leaf_hit(&s->bvh, r, &sr->block[RADINTERP__BVH_WIDTH / 4 * g + i], 0.0f, hit))
            return 1;
    return 0;
}

/* Is the segment from a to b blocked? radinterp__segment_blocked's answer,
   from the shaft's triangles when they are known. The group that blocked
   the link's last blocked ray goes first: the rays of a link that a wall
   hides in part meet that wall again and again. Any hit answers, and a
   group's test does not depend on the groups tried before it (the ray's
   end stays at 1 until a hit), so the order changes no answer. */
static int radinterp__shaft_blocked(const radinterp_solution *s, radinterp__shaft_rays *sr, const double *a,
                                    const double *b)
{
    radinterp__ray r;
    radinterp__hit hit;
    uint32_t g;
    if (sr->walk) return radinterp__segment_blocked(s, a, b);
    radinterp__segment_ray(a, b, &r, &hit);
    if (sr->last * RADINTERP__BVH_WIDTH < sr->tris && radinterp__shaft_group_blocks(s, sr, &r, &hit, sr->last)) return 1;
    for (g = 0; g * RADINTERP__BVH_WIDTH < sr->tris; g++)
        if (g != sr->last && radinterp__shaft_group_blocks(s, sr, &r, &hit, g)) {
            sr->last = g;
            return 1;
        }
    return 0;
}

/* radinterp__segment_light for a ray of the shaft sr (NULL: none known). */
static int radinterp__shaft_light(const radinterp_solution *s, radinterp__shaft_rays *sr, const double *a,
                                  const double *b, int glass, double T[3])
{
    if (glass || !sr) return radinterp__segment_light(s, a, b, glass, T);
    return radinterp__opaque_light(radinterp__shaft_blocked(s, sr, a, b), T);
}

/* The largest of three values. */
static double radinterp__max3(const double *v) { return v[0] > v[1] ? (v[0] > v[2] ? v[0] : v[2]) : (v[1] > v[2] ? v[1] : v[2]); }

/* A link's transmittance where none of its rays crossed a pane (the point
   queries still see through the panes of its blocker list): the mean tf of
   those panes; 1 without any. */
static void radinterp__link_glass_default(const radinterp_solution *s, const uint32_t *list, uint32_t count, float t[3])
{
    double acc[3] = {0.0, 0.0, 0.0};
    uint32_t i, panes = 0;
    int k;
    t[0] = t[1] = t[2] = 1.0f;
    if (!s->glass_patches) return;
    for (i = 0; i < count; i++)
        if (s->patches[list[i]].glass) {
            panes++;
            for (k = 0; k < 3; k++) acc[k] += s->patches[list[i]].tf[k];
        }
    if (panes)
        for (k = 0; k < 3; k++) t[k] = (float)(acc[k] / panes);
}

/* Does any of the patches list[0 .. count) pass light? */
static int radinterp__list_has_glass(const radinterp_solution *s, const uint32_t *list, uint32_t count)
{
    uint32_t i;
    if (!s->glass_patches) return 0;
    for (i = 0; i < count; i++)
        if (s->patches[list[i]].glass) return 1;
    return 0;
}

/* The sky's radiance along the unit direction dir: desc.sky, or the texel
   of the environment map it falls in (latitude-longitude, +y up: row =
   floor(theta / pi * height), theta the angle from +y; column =
   floor((phi + pi) / (2 pi) * width), phi = atan2(z, x); no filtering, so
   a map of one radiance L is the constant sky L). */
static void radinterp__sky_radiance(const radinterp_solution *s, const double *dir, double rgb[3])
{
    const float *src = s->sky;
    if (s->environment) {
        double c = dir[1], theta, phi;
        uint32_t row, col;
        if (!(c >= -1.0)) c = -1.0;   /* NaN too */
        if (c > 1.0) c = 1.0;
        theta = acos(c);
        phi = atan2(dir[2], dir[0]);
        if (!(phi >= -RADINTERP__PI)) phi = -RADINTERP__PI;
        row = (uint32_t)(theta / RADINTERP__PI * s->environment_height);
        col = (uint32_t)((phi + RADINTERP__PI) / (2.0 * RADINTERP__PI) * s->environment_width);
        if (row >= s->environment_height) row = s->environment_height - 1;
        if (col >= s->environment_width) col = s->environment_width - 1;
        src = s->environment + 3 * ((size_t)row * s->environment_width + col);
    }
    rgb[0] = src[0];
    rgb[1] = src[1];
    rgb[2] = src[2];
}

/* pi times the sky's mean radiance (largest channel): the irradiance of a
   surface open to the whole sky, averaged over its orientations. */
static double radinterp__sky_scale(const radinterp_solution *s)
{
    double sum[3] = {0.0, 0.0, 0.0}, weight = 0.0;
    uint32_t r, c;
    int k;
    if (!s->has_sky) return 0.0;
    if (!s->environment) {
        for (k = 0; k < 3; k++) sum[k] = s->sky[k];
        return RADINTERP__PI * radinterp__max3(sum);
    }
    for (r = 0; r < s->environment_height; r++) {   /* each row weighs its solid angle */
        double w = cos(RADINTERP__PI * r / s->environment_height) - cos(RADINTERP__PI * (r + 1) / s->environment_height);
        for (c = 0; c < s->environment_width; c++)
            for (k = 0; k < 3; k++) sum[k] += w * s->environment[3 * ((size_t)r * s->environment_width + c) + k];
        weight += w * s->environment_width;
    }
    for (k = 0; k < 3; k++) sum[k] /= weight;
    return RADINTERP__PI * radinterp__max3(sum);
}

/* Direction j of n toward the sky above a surface of unit normal nrm,
   distributed as cos theta / pi (Malley: a uniform point of the unit disc
   lifted to the hemisphere), stratified: a k x k jittered grid of the unit
   square when n = k^2, else n strata along the first coordinate. The
   estimate of E = integral L cos dw is then pi / n times the sum of the
   radiances that arrive along the n directions. */
static void radinterp__sky_dir(const double *nrm, uint32_t j, uint32_t n, radinterp__rng *rng, double dir[3])
{
    uint32_t k = (uint32_t)(sqrt((double)n) + 0.5);
    double u1 = radinterp__rng_unit(rng), u2 = radinterp__rng_unit(rng), t[3], b[3], r, phi, x, y, z;
    double sg = nrm[2] >= 0.0 ? 1.0 : -1.0, a = -1.0 / (sg + nrm[2]), c = nrm[0] * nrm[1] * a;
    int m;
    if (k * k == n) { u1 = ((j % k) + u1) / k; u2 = ((j / k) + u2) / k; }
    else u1 = (j + u1) / n;
    r = sqrt(u1);
    phi = 2.0 * RADINTERP__PI * u2;
    x = r * cos(phi);
    y = r * sin(phi);
    z = sqrt(1.0 - u1 > 0.0 ? 1.0 - u1 : 0.0);
    /* a basis around nrm (Duff et al. 2017) */
    t[0] = 1.0 + sg * nrm[0] * nrm[0] * a; t[1] = sg * c; t[2] = -sg * nrm[0];
    b[0] = c; b[1] = sg + nrm[1] * nrm[1] * a; b[2] = -nrm[1];
    for (m = 0; m < 3; m++) dir[m] = x * t[m] + y * b[m] + z * nrm[m];
}

/* Radiance arriving at x (on a surface of unit normal nrm, so that the ray
   leaves it by the solver's offset) from the sky along dir, through panes. */
static void radinterp__sky_arriving(const radinterp_solution *s, const double *x, const double *nrm, const double *dir,
                                    double rgb[3])
{
    double off = 10.0 * s->epsilon * s->diag, T[3];
    float org[3], d[3];
    int k;
    for (k = 0; k < 3; k++) {
        org[k] = (float)(x[k] + off * nrm[k]);
        d[k] = (float)dir[k];
    }
    radinterp__sky_radiance(s, dir, rgb);
    if (radinterp__ray_light(s, org, d, FLT_MAX, T) < 0) { rgb[0] = rgb[1] = rgb[2] = 0.0; return; }
    for (k = 0; k < 3; k++) rgb[k] *= T[k];
}

/* The sky's irradiance at the point x of a patch, added to e: n
   stratified directions, the same for every point of the patch (so that
   neighbouring points, and the interpolants through them, see the sky
   alike, and differences between points are differences of visibility,
   not of sampling), E = pi / n sum L T (GLASS AND SKY). */
static void radinterp__sky_at(const radinterp_solution *s, uint32_t patch, const double *x, uint32_t n, double *e)
{
    const double *nrm = s->patches[patch].n;
    radinterp__rng rng = radinterp__rng_stream(s->seed ^ 0x5C5C5C5Cu, (uint64_t)1 << 40 | patch);
    double sum[3] = {0.0, 0.0, 0.0};
    uint32_t j;
    int k;
    for (j = 0; j < n; j++) {
        double dir[3], l[3];
        radinterp__sky_dir(nrm, j, n, &rng, dir);
        radinterp__sky_arriving(s, x, nrm, dir, l);
        for (k = 0; k < 3; k++) sum[k] += l[k];
    }
    for (k = 0; k < 3; k++) e[k] += RADINTERP__PI * sum[k] / n;
}

/* The sky's irradiance on a node, as a mean over the whole node (enclosed
   parts receive none): sky_rays rays from stratified points of the node,
   each along its own stratified direction (point stratum i, direction
   stratum 7919 i mod n: the pairing decorrelates them), eq. E = pi / n sum
   L T. And its spread for refinement: max - min (largest channel) of the
   sky at the node's corners pulled a fifth toward its centre and at its
   centre, each from the patch's own sky_rays / 4 directions (at least 16),
   so that the points differ by what they see, not by sampling noise. */
static void radinterp__node_sky(radinterp_solution *s, uint32_t index)
{
    radinterp__node *nd = &s->nodes[index];
    const double *nrm = s->patches[nd->patch].n;
    double v[RADINTERP__POLY_MAX][3], tri_area[RADINTERP__POLY_MAX], total, e[3] = {0.0, 0.0, 0.0};
    uint32_t i, n = s->sky_rays;
    int count = radinterp__node_poly(nd, v), k;
    radinterp__rng rng = radinterp__rng_stream(s->seed ^ 0x5C5C5C5Cu, index);
    total = radinterp__fan_areas((const double (*)[3])v, count, tri_area);
    for (i = 0; i < n; i++) {
        double q[3], dir[3], l[3], w;
        w = radinterp__receiver_point((const double (*)[3])v, count, tri_area, total, i, n, &rng, q);
        radinterp__sky_dir(nrm, (uint32_t)(((uint64_t)i * 7919u) % n), n, &rng, dir);
        radinterp__sky_arriving(s, q, nrm, dir, l);
        for (k = 0; k < 3; k++) e[k] += w * l[k];
    }
    for (k = 0; k < 3; k++) nd->sky[k] = (float)(RADINTERP__PI * e[k] / n);
    {
        double c[3] = {0.0, 0.0, 0.0}, lo = DBL_MAX, hi = 0.0;
        uint32_t rays = n / 4 > 16 ? n / 4 : 16;
        int j, m;
        for (j = 0; j < count; j++)
            for (m = 0; m < 3; m++) c[m] += v[j][m] / count;
        for (j = 0; j <= count; j++) {
            double q[3], at[3] = {0.0, 0.0, 0.0}, most;
            for (m = 0; m < 3; m++) q[m] = j < count ? 0.8 * v[j][m] + 0.2 * c[m] : c[m];
            radinterp__sky_at(s, nd->patch, q, rays, at);
            most = radinterp__max3(at);
            lo = most < lo ? most : lo;
            hi = most > hi ? most : hi;
        }
        nd->sky_spread = (float)(hi - lo);
    }
}

/* The point query's sky term: sky_rays directions. */
static void radinterp__sky_point_add(const radinterp_solution *s, uint32_t patch, const double *x, double *h)
{
    radinterp__sky_at(s, patch, x, s->sky_rays, h);
}

/* Visible fraction of the source seen from q (on the receiver), weighted
   like the form factor: rays to stratified points of the source polygon,
   each counting with the kernel cos cos / r^2 of its end point, so that a
   blocker hiding the near (bright) part of the source weighs more than one
   hiding the far part. Both ends leave their surface by a small offset
   along its normal, so neither end hits its own surface. With glass among
   the blockers, the rays that cross panes count apart: v->open is the
   fraction seen through no pane, v->glass the fraction seen through panes
   (counted clear) and v->t[c] the light of channel c that passes them. */
typedef struct radinterp__vis { double open, glass, t[3]; } radinterp__vis;

static void radinterp__visible_fraction(const radinterp_solution *s, radinterp__shaft_rays *sr, const double *q,
                                        const double *nr, const double (*src)[3], int count, const double *ns,
                                        radinterp__rng *rng, uint32_t rays, int glass, radinterp__vis *v)
{
    double tri_area[RADINTERP__POLY_MAX], total = radinterp__fan_areas(src, count, tri_area), off = radinterp__ray_offset(s);
    double a[3], b[3], open = 0.0, all = 0.0, through = 0.0, light[3] = {0.0, 0.0, 0.0};
    uint32_t i;
    int k;
    for (k = 0; k < 3; k++) a[k] = q[k] + off * nr[k];
    for (i = 0; i < rays; i++) {
        double u1 = (i + radinterp__rng_unit(rng)) / rays, u2 = radinterp__rng_unit(rng), d[3], r2, w, T[3];
        int panes;
        radinterp__poly_point(src, count, tri_area, total, u1, u2, b);
        radinterp__d3_sub(b, q, d);
        r2 = radinterp__d3_dot(d, d);
        w = r2 > 0.0 ? radinterp__d3_dot(d, nr) * -radinterp__d3_dot(d, ns) / (r2 * r2) : 0.0;
        if (!(w > 0.0)) continue;
        for (k = 0; k < 3; k++) b[k] += off * ns[k];
        all += w;
        panes = radinterp__shaft_light(s, sr, a, b, glass, T);
        if (panes == 0) open += w;
        else if (panes > 0) {
            through += w;
            for (k = 0; k < 3; k++) light[k] += w * T[k];
        }
    }
    v->open = all > 0.0 ? open / all : 1.0;
    v->glass = all > 0.0 ? through / all : 0.0;
    for (k = 0; k < 3; k++) v->t[k] = all > 0.0 ? light[k] / all : 0.0;
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

/* The point of a convex polygon (normal n) nearest to p: p's projection
   onto its plane when that falls inside, else the nearest point of its
   outline. */
static void radinterp__poly_nearest(const double (*v)[3], int count, const double *n, const double *p, double *out)
{
    double d[3], q[3], best = DBL_MAX;
    int i, k, inside = 1;
    radinterp__d3_sub(p, v[0], d);
    for (k = 0; k < 3; k++) q[k] = p[k] - radinterp__d3_dot(d, n) * n[k];
    memcpy(out, v[0], sizeof q);
    for (i = 0; i < count && inside; i++) {
        double e[3], w[3], c[3];
        radinterp__d3_sub(v[(i + 1) % count], v[i], e);
        radinterp__d3_sub(q, v[i], w);
        radinterp__d3_cross(e, w, c);
        inside = radinterp__d3_dot(c, n) >= 0.0;
    }
    if (inside) { memcpy(out, q, sizeof q); return; }
    for (i = 0; i < count; i++) {
        double e[3], w[3], t, ee, x[3], dx[3], d2;
        radinterp__d3_sub(v[(i + 1) % count], v[i], e);
        radinterp__d3_sub(q, v[i], w);
        ee = radinterp__d3_dot(e, e);
        t = ee > 0.0 ? radinterp__d3_dot(w, e) / ee : 0.0;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
        for (k = 0; k < 3; k++) x[k] = v[i][k] + t * e[k];
        radinterp__d3_sub(q, x, dx);
        d2 = radinterp__d3_dot(dx, dx);
        if (d2 < best) { best = d2; memcpy(out, x, sizeof x); }
    }
}

/* Fixed point k of a receiver polygon v (centre c) for the refinement
   estimate (radinterp__link_compute): its corners pulled a fifth toward
   the centre (k < count), its centre (k == count). */
static void radinterp__fixed_point(const double (*v)[3], int count, const double *c, int k, double *q)
{
    int j;
    for (j = 0; j < 3; j++) q[j] = k < count ? 0.8 * v[k][j] + 0.2 * c[j] : c[j];
}

static void radinterp__poly_centre(const double (*v)[3], int count, double *c)
{
    int j, k;
    c[0] = c[1] = c[2] = 0.0;
    for (k = 0; k < count; k++)
        for (j = 0; j < 3; j++) c[j] += v[k][j] / count;
}

/* Which of the points a link samples on a partly enclosed receiver are
   enclosed: bit i the stratified point i, bit ff_samples + k the fixed
   point k (corners and centre). When the source does not clip the
   receiver they depend on the receiver alone (its polygon and its seed),
   so they are found once here, not by up to four rays per point in each
   of the receiver's links (8% of building_1k's solve). */
static void radinterp__node_enclosure(radinterp_solution *s, uint32_t index)
{
    radinterp__node *nd = &s->nodes[index];
    const double *n = s->patches[nd->patch].n;
    double R[RADINTERP__POLY_MAX][3], tri_area[RADINTERP__POLY_MAX], total, c[3], q[3];
    radinterp__rng rng = radinterp__rng_stream(s->seed, index);
    int nR = radinterp__node_poly(nd, R), k;
    uint32_t i;
    nd->enclosed = 0;
    if (!(nd->open < 1.0f) || s->ff_samples + (uint32_t)nR + 1 > 15) return;   /* more: each link tests its points */
    total = radinterp__fan_areas((const double (*)[3])R, nR, tri_area);
    for (i = 0; i < s->ff_samples; i++) {   /* as the link's loop draws them */
        radinterp__receiver_point((const double (*)[3])R, nR, tri_area, total, i, s->ff_samples, &rng, q);
        if (radinterp__point_enclosed(s, n, q)) nd->enclosed = (uint16_t)(nd->enclosed | 1u << i);
    }
    radinterp__poly_centre((const double (*)[3])R, nR, c);
    for (k = 0; k <= nR; k++) {
        radinterp__fixed_point((const double (*)[3])R, nR, c, k, q);
        if (radinterp__point_enclosed(s, n, q)) nd->enclosed = (uint16_t)(nd->enclosed | 1u << (s->ff_samples + (uint32_t)k));
    }
    nd->enclosed = (uint16_t)(nd->enclosed | RADINTERP__ENCLOSED_KNOWN);
}

/* Is point q (sample `bit`, above) of receiver r enclosed? From r's bits
   when `known` (the link samples r's own points), else by its rays. */
static int radinterp__sample_enclosed(const radinterp_solution *s, const radinterp__node *r, int known, uint32_t bit,
                                      const double *q)
{
    return known ? (int)(r->enclosed >> bit & 1u) : radinterp__point_enclosed(s, s->patches[r->patch].n, q);
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
    double tri_area[RADINTERP__POLY_MAX], total, ratio, sum = 0.0, open_sum = 0.0, lo = DBL_MAX, hi = 0.0, tiny;
    double rlo = DBL_MAX, rhi = 0.0;                 /* the random points' least and largest factor */
    double open_w = 0.0, scale;                      /* weight of the open points; sum -> F */
    double gsum = 0.0, tsum[3] = {0.0, 0.0, 0.0};   /* through panes: counted clear, and the light passing */
    int nR = radinterp__node_poly(r, R), nS = radinterp__node_poly(src, S), nRc, nSc, clipped, glass, k;
    uint32_t i, n = s->ff_samples;
    int seen = 0;                  /* some point sees part of the source (before visibility) */
    int partly = r->open < 1.0f;   /* part of the receiver is enclosed: its points there take nothing */
    int own;                       /* the receiver's polygon is unclipped: its enclosure bits hold */
    radinterp__rng rng;
    radinterp__shaft_rays sr;
    if (pl->filter) pl->kept = radinterp__filter_blockers(s, r, src, in + pl->first, pl->count, out + pl->first);
    else {
        if (pl->count) memcpy(out + pl->first, in + pl->first, pl->count * sizeof(uint32_t));
        pl->kept = pl->count;
    }
    glass = radinterp__list_has_glass(s, out + pl->first, pl->kept);
    radinterp__link_glass_default(s, out + pl->first, pl->kept, pl->glass);
    pl->gff = 0.0f;
    pl->ff = pl->dff = 0.0f;
    pl->vis = 1.0f;
    pl->rays = 0;
    pl->dead = 1;
    pl->hidden = 0;
    pl->partly = 0;
    nSc = radinterp__clip_poly((const double (*)[3])S, nS, pr->n, pr->d, Sc);
    nRc = radinterp__clip_poly((const double (*)[3])R, nR, ps->n, ps->d, Rc);
    tiny = 1e-12 * s->diag * s->diag;
    if (nSc < 3 || nRc < 3) return;
    if (radinterp__poly_area((const double (*)[3])Sc, nSc) <= tiny) return;
    total = radinterp__fan_areas((const double (*)[3])Rc, nRc, tri_area);
    if (total <= tiny) return;
    pl->dead = 0;
    if (pl->kept && !glass)
        radinterp__shaft_rays_init(s, &sr, radinterp__elem_ray_end(s, pl->receiver), radinterp__elem_ray_end(s, pl->source));
    else sr.walk = 1;
    clipped = radinterp__node_front(r, ps->n, ps->d) > 0.0 && total < 0.999999 * r->area;
    ratio = clipped ? total / r->area : 1.0;
    /* unclipped receivers use the same points for every source (seeded by
       the receiver alone), so the factors of a closed scene sum to one */
    rng = radinterp__rng_stream(s->seed, clipped ? ((uint64_t)pl->receiver << 32 | pl->source) : pl->receiver);
    own = partly && (r->enclosed & RADINTERP__ENCLOSED_KNOWN) && nRc == nR && memcmp(Rc, R, (size_t)nR * sizeof R[0]) == 0;
    for (i = 0; i < n; i++) {
        double q[3], f, w = radinterp__receiver_point((const double (*)[3])Rc, nRc, tri_area, total, i, n, &rng, q);
        if (partly && radinterp__sample_enclosed(s, r, own && !clipped, i, q)) continue;
        open_w += w;
        f = w * radinterp__ff_poly(q, pr->n, (const double (*)[3])Sc, nSc);
        if (f < 0.0) f = 0.0;
        seen |= f > 0.0;
        open_sum += f;
        if (pl->kept && f > 0.0) {
            radinterp__rng vis = radinterp__rng_stream(s->seed ^ 0xA5A5A5A5u, ((uint64_t)pl->receiver << 32 | pl->source) * 64u + i);
            radinterp__vis v;
            radinterp__visible_fraction(s, &sr, q, pr->n, (const double (*)[3])Sc, nSc, ps->n, &vis, s->visibility_rays, glass, &v);
            gsum += f * v.glass;
            for (k = 0; k < 3; k++) tsum[k] += f * v.t[k];
            f *= v.open;
            pl->rays += s->visibility_rays;
        }
        sum += f;
        rlo = f < rlo ? f : rlo;
        rhi = f > rhi ? f : rhi;
    }
    /* The refinement estimate comes from fixed points, the receiver's
       corners pulled a fifth toward its centre, its centre, and its point
       nearest to the source's centre (where the factor peaks when the source
       is close: a block standing on a large floor), pulled a hundredth toward
       the centre: if it came from the random points, the links whose points
       happened to miss a peak of the factor (near a shared edge) would be the
       ones kept, and the kept factors would be biased low. */
    {
        double c[3], cs[3], near[3] = {0.0, 0.0, 0.0};
        int j;
        radinterp__poly_centre((const double (*)[3])Rc, nRc, c);
        radinterp__poly_centre((const double (*)[3])Sc, nSc, cs);
        radinterp__poly_nearest((const double (*)[3])Rc, nRc, pr->n, cs, near);
        for (k = 0; k <= nRc + 1; k++) {
            double q[3], f;
            if (k <= nRc) radinterp__fixed_point((const double (*)[3])Rc, nRc, c, k, q);
            else
                for (j = 0; j < 3; j++) q[j] = 0.99 * near[j] + 0.01 * c[j];
            if (partly && radinterp__sample_enclosed(s, r, own && k <= nRc, s->ff_samples + (uint32_t)k, q)) continue;
            f = radinterp__ff_poly(q, pr->n, (const double (*)[3])Sc, nSc);
            if (f < 0.0) f = 0.0;
            if (pl->kept && f > 0.0) {
                radinterp__rng vis = radinterp__rng_stream(s->seed ^ 0x5A5A5A5Au, ((uint64_t)pl->receiver << 32 | pl->source) * 64u + (uint64_t)k);
                radinterp__vis v;
                radinterp__visible_fraction(s, &sr, q, pr->n, (const double (*)[3])Sc, nSc, ps->n, &vis, s->visibility_rays, glass, &v);
                /* what arrives in the brightest channel, through panes or not */
                f = f * v.open + f * radinterp__max3(v.t);
                pl->rays += s->visibility_rays;
            }
            lo = f < lo ? f : lo;
            hi = f > hi ? f : hi;
        }
    }
    /* The fixed points can all miss what the random ones saw: a source seen
       only through a stair opening from part of a large receiver, or the
       end of a wall face that runs past a partition into the next room,
       where no fixed point lies and no light arrives. The spread covers
       every point's factor, fixed and random, so such a link is split; it
       can only grow by this, so no link is kept for having missed a peak
       (see above). Without the random points' least, the dark end of a
       receiver took the mean of the lit part, and that end shone into its
       own room (a dark room came out 40% too bright). */
    if (rhi > hi) hi = rhi;
    if (rlo < lo) lo = rlo;
    if (lo > hi) lo = hi = 0.0;   /* every point enclosed */
    /* F is a mean over the whole receiver in which its enclosed points count
       zero (push-pull divides it by the open fraction). Points found
       enclosed are left out rather than counted zero: counting on the
       visibility rays to zero them fails where an enclosed point sees an
       enclosed part of the source (the floor under a wall sees the ceiling
       over it, inside the wall). An unclipped receiver takes the mean over
       its open points times its open fraction, so the few of its points
       that fall in a strip do not move its factors (all its links share
       these points); a clipped one sums its open points, as the clip
       changes which share of it is open. */
    scale = partly && !clipped ? (open_w > 0.0 ? r->open / open_w : 0.0) : ratio / n;
    pl->ff = (float)(scale * sum);
    /* A receiver cut by the source's plane gets nothing on the far side of
       that plane: its factor there is zero, so the spread runs from zero to
       the largest value. Without this a receiver that runs through a wall
       (a wall face across two rooms, a floor under a partition) keeps one
       link for a source on one side and pushes its mean to the part on the
       other side, where the source cannot be seen. */
    pl->dff = (float)(clipped ? hi : hi - lo);
    pl->partly = hi > 0.0 && (clipped || lo == 0.0);
    if (gsum > 0.0) {
        pl->gff = (float)(scale * gsum);
        for (k = 0; k < 3; k++) pl->glass[k] = (float)(tsum[k] / gsum);
    }
    /* the visible fraction point queries use for a dim source (point_rest):
       what passes, clear or through panes (their mean channel) */
    if (open_sum > 0.0) pl->vis = (float)((sum + (tsum[0] + tsum[1] + tsum[2]) / 3.0) / open_sum);
    pl->partly |= pl->vis < 1.0f;
    /* every ray blocked: dropped when planes between them prove it (rays
       miss the visible part of a large element too easily) */
    if (pl->kept && seen && sum == 0.0 && gsum == 0.0 && hi == 0.0 && radinterp__planes_hide(s, r->lo, r->hi, src->lo, src->hi))
        pl->dead = pl->hidden = 1;
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
    double reported;             /* RADINTERP_CPU_SECONDS() at the last progress call */
    double read;                 /* RADINTERP_CPU_SECONDS() at the last reading of a loop of short steps */
    uint32_t stride, countdown;  /* steps between such readings; steps to the next */
} radinterp__run;

static int radinterp__cancelled(const radinterp_solution *s, radinterp__run *run)
{
    const radinterp_desc *d = run->desc;
    run->reported = RADINTERP_CPU_SECONDS();
    return d->progress && d->progress(d->progress_user, run->iteration, s->max_iterations) != 0;
}

/* The same call inside a serial stretch of the solve (refinement's pass
   over the links, a wave of cluster links split into shaft queries, the
   installation of the new links, the steps of an iteration), once
   progress_interval has passed since the last call. At building scale
   each of these takes seconds between two batches. Loops of short steps
   read the clock every few steps (radinterp__solve_step): a reading of the
   process's CPU clock is a system call that costs as much as many steps
   (every 64 steps it was 3% of building_4k's solve). Non-zero: cancel. */
#define RADINTERP__TICK_STEPS 64         /* a loop's first stride */
#define RADINTERP__TICK_MAX_STEPS 4096
static int radinterp__solve_tick(const radinterp_solution *s, radinterp__run *run)
{
    if (!radinterp__progress_due(run->reported, run->desc->progress_interval)) return 0;
    return radinterp__cancelled(s, run);
}

/* The tick of a loop of short steps, at its step i (from 0). It reads the
   clock at step 0 and then every `stride` steps, the stride doubling while
   readings come less than 1/64 of the progress interval apart and halving
   when more than 1/8 apart: a few hundred readings per interval at most,
   whatever a step costs. */
static int radinterp__solve_step(const radinterp_solution *s, radinterp__run *run, size_t i)
{
    double now, interval = radinterp__progress_interval(run->desc->progress_interval);
    if (i == 0) run->stride = RADINTERP__TICK_STEPS;
    else if (--run->countdown > 0) return 0;
    now = RADINTERP_CPU_SECONDS();
    if (i > 0 && now - run->read < interval / 64.0 && run->stride < RADINTERP__TICK_MAX_STEPS) run->stride *= 2;
    else if (i > 0 && now - run->read > interval / 8.0 && run->stride > 1) run->stride /= 2;
    run->countdown = run->stride;
    run->read = now;
    if (now - run->reported < interval) return 0;
    return radinterp__cancelled(s, run);
}

/* Computes every pending link, in batches with a progress check between. */
static radinterp_result radinterp__compute_pending(radinterp_solution *s, radinterp__run *run,
                                                   radinterp__pending *pending, uint32_t count,
                                                   const uint32_t *in_pool, uint32_t *out_pool)
{
    const uint32_t per_job = 64;
    uint32_t begin = 0, jobs;
    radinterp__pacer pacer;
    radinterp__pacer_init(&pacer, run->desc->progress_interval, 16384 / per_job);
    while (begin < count) {
        radinterp__ff_ctx ctx;
        uint32_t i;
        jobs = radinterp__pacer_next(&pacer, (count - begin + per_job - 1) / per_job);
        ctx.s = s;
        ctx.pending = pending;
        ctx.begin = begin;
        ctx.end = count - begin > jobs * per_job ? begin + jobs * per_job : count;
        ctx.per_job = per_job;
        ctx.in_pool = in_pool;
        ctx.out_pool = out_pool;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__ff_job, &ctx, jobs);
        radinterp__pacer_adapt(&pacer);
        for (i = ctx.begin; i < ctx.end; i++) s->shadow_rays += pending[i].rays;
        begin = ctx.end;
        if (radinterp__cancelled(s, run)) return RADINTERP_ERROR_CANCELLED;
    }
    return RADINTERP_OK;
}

/* An array of `item`-byte items with room for n, keeping its first `keep`
   items: arr itself when its capacity *cap holds n, else a larger one (an
   eighth to spare, so that the refinement passes that add a few links find
   room) with the kept items copied and arr freed (also when arr is NULL:
   an empty array is not NULL). NULL when out of memory (arr is kept). */
static void *radinterp__room_for(const radinterp_allocator *a, void *arr, size_t *cap, size_t n, size_t keep, size_t item)
{
    void *p;
    size_t want = n + n / 8;
    if (n <= *cap && arr) return arr;
    p = radinterp__alloc_array(a, want, item);
    if (!p) return NULL;
    if (keep) memcpy(p, arr, keep * item);
    radinterp__free(a, arr);
    *cap = want;
    return p;
}

/* A copy of the first n items of arr, or NULL when out of memory or
   cancelled (*res): copied a few megabytes at a time, with progress
   between (building_16k's blocker pool is most of a gigabyte). */
#define RADINTERP__COPY_CHUNK (1u << 22)   /* bytes between progress checks */
static void *radinterp__copy_ticking(radinterp_solution *s, radinterp__run *run, const void *arr, size_t n, size_t item,
                                     radinterp_result *res)
{
    size_t at, bytes = n * item;
    char *p = (char *)radinterp__alloc_array(&s->allocator, n, item);
    if (!p) { *res = RADINTERP_ERROR_OUT_OF_MEMORY; return NULL; }
    for (at = 0; at < bytes; at += RADINTERP__COPY_CHUNK) {
        memcpy(p + at, (const char *)arr + at, bytes - at < RADINTERP__COPY_CHUNK ? bytes - at : RADINTERP__COPY_CHUNK);
        if (radinterp__solve_tick(s, run)) {
            radinterp__free(&s->allocator, p);
            *res = RADINTERP_ERROR_CANCELLED;
            return NULL;
        }
    }
    return p;
}

/* Gives back the room refinement kept in the link and blocker arrays
   (radinterp__room_for), so that the solution holds what it reports. */
static radinterp_result radinterp__trim_links(radinterp_solution *s, radinterp__run *run)
{
    radinterp_result res = RADINTERP_OK;
    if (s->link_cap > s->link_count) {
        void *p = radinterp__copy_ticking(s, run, s->links, s->link_count, sizeof(radinterp__link), &res);
        if (!p) return res;
        radinterp__free(&s->allocator, s->links);
        s->links = (radinterp__link *)p;
        s->link_cap = s->link_count;
    }
    if (s->blocker_cap > s->blocker_count) {
        void *p = radinterp__copy_ticking(s, run, s->blockers, (size_t)s->blocker_count, sizeof(uint32_t), &res);
        if (!p) return res;
        radinterp__free(&s->allocator, s->blockers);
        s->blockers = (uint32_t *)p;
        s->blocker_cap = (size_t)s->blocker_count;
    }
    return RADINTERP_OK;
}

/* Moves the blockers of the kept links s->links[0 .. keep_count) to the
   front of the pool, in link order. The pool holds the links' lists in
   link order (radinterp__install_links leaves it so, and refinement keeps
   the order of the links it keeps), so each list moves toward the front or
   stays. Returns the blockers kept; *stop non-zero when cancelled. */
static uint64_t radinterp__pack_kept_blockers(radinterp_solution *s, radinterp__run *run, uint32_t keep_count, int *stop)
{
    uint64_t at = 0;
    uint32_t i;
    for (i = 0; i < keep_count && !(*stop = radinterp__solve_step(s, run, i)); i++) {
        radinterp__link *l = &s->links[i];
        if (l->blocker_count && l->first_blocker != at)
            memmove(s->blockers + at, s->blockers + l->first_blocker, l->blocker_count * sizeof(uint32_t));
        l->first_blocker = (uint32_t)at;
        at += l->blocker_count;
    }
    return at;
}

/* Link i of the pending ones, its blockers at pool position at. */
static radinterp__link radinterp__pending_link(const radinterp__pending *p, uint32_t at)
{
    radinterp__link l;
    l.receiver = p->receiver;
    l.source = p->source;
    l.ff = p->ff;
    l.dff = p->dff;
    l.vis = p->vis;
    l.gff = p->gff;
    memcpy(l.glass, p->glass, sizeof l.glass);
    l.flags = p->partly ? RADINTERP__LINK_PARTLY : 0u;
    l.blocker_count = p->kept;
    l.first_blocker = at;
    return l;
}

/* Replaces the link list by the kept links (s->links[0 .. keep_count), in
   receiver order: refinement packs them there) plus the live pending ones,
   sorted by receiver (stable: a receiver's kept links, then its pending
   ones in their order), each link's blockers in one pool in link order.
   The arrays are reused in place: the live pending links, sorted by
   receiver, are merged with the kept ones from the back, each kept link
   and its list moving toward the end or staying. A new array is made only
   when the links outgrow it: copying all links and lists into new arrays
   at every refinement pass touched fresh memory each time (page faults and
   copies were about a tenth of building_4k's solve). */
static radinterp_result radinterp__install_links(radinterp_solution *s, radinterp__run *run, uint32_t keep_count,
                                                 const radinterp__pending *pend, uint32_t pend_count,
                                                 const uint32_t *pend_pool)
{
    uint32_t *start = NULL, *order = NULL, i, total = keep_count, live = 0, w, k, j;
    uint64_t packed, blockers, pw;
    void *grown;
    int stop = 0;
    for (i = 0; i < pend_count; i++) s->culled_links += pend[i].hidden;
    blockers = packed = radinterp__pack_kept_blockers(s, run, keep_count, &stop);
    if (stop) return RADINTERP_ERROR_CANCELLED;   /* the solution is only destroyed now */
    for (i = 0; i < pend_count; i++)
        if (!pend[i].dead) { live++; blockers += pend[i].kept; }
    total += live;
    if (blockers > 0xFFFFFFFFu) return RADINTERP_ERROR_OUT_OF_MEMORY;
    grown = radinterp__room_for(&s->allocator, s->links, &s->link_cap, total, keep_count, sizeof(radinterp__link));
    if (!grown) return RADINTERP_ERROR_OUT_OF_MEMORY;
    s->links = (radinterp__link *)grown;
    grown = radinterp__room_for(&s->allocator, s->blockers, &s->blocker_cap, (size_t)blockers, (size_t)packed, sizeof(uint32_t));
    if (!grown) return RADINTERP_ERROR_OUT_OF_MEMORY;
    s->blockers = (uint32_t *)grown;
    /* the live pending links by receiver (counting sort, stable) */
    start = (uint32_t *)radinterp__alloc_array(&s->allocator, (size_t)s->node_count + 1, sizeof *start);
    order = (uint32_t *)radinterp__alloc_array(&s->allocator, live ? live : 1, sizeof *order);
    if (!start || !order) {
        radinterp__free(&s->allocator, start);
        radinterp__free(&s->allocator, order);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    memset(start, 0, ((size_t)s->node_count + 1) * sizeof *start);
    for (i = 0; i < pend_count; i++)
        if (!pend[i].dead) start[pend[i].receiver + 1]++;
    for (i = 0; i < s->node_count; i++) start[i + 1] += start[i];
    for (i = 0; i < pend_count; i++)
        if (!pend[i].dead) order[start[pend[i].receiver]++] = i;
    radinterp__free(&s->allocator, start);
    /* merge from the back; once the pending ones are placed, the kept ones
       before them are where they belong */
    w = total;
    pw = blockers;
    k = keep_count;
    for (j = live; j > 0; ) {
        if (radinterp__solve_step(s, run, total - w)) {
            radinterp__free(&s->allocator, order);
            return RADINTERP_ERROR_CANCELLED;   /* the solution is only destroyed now */
        }
        if (k == 0 || pend[order[j - 1]].receiver >= s->links[k - 1].receiver) {
            const radinterp__pending *p = &pend[order[--j]];
            pw -= p->kept;
            if (p->kept) memcpy(s->blockers + pw, pend_pool + p->first, p->kept * sizeof(uint32_t));
            s->links[--w] = radinterp__pending_link(p, (uint32_t)pw);
        } else {
            radinterp__link l = s->links[--k];
            pw -= l.blocker_count;
            if (l.blocker_count) memmove(s->blockers + pw, s->blockers + l.first_blocker, l.blocker_count * sizeof(uint32_t));
            l.first_blocker = (uint32_t)pw;
            s->links[--w] = l;
        }
    }
    radinterp__free(&s->allocator, order);
    for (i = 0; i < s->node_count; i++) s->nodes[i].link_count = 0;
    for (i = 0; i < total; i++) s->nodes[s->links[i].receiver].link_count++;
    for (w = 0, i = 0; i < s->node_count; i++) {
        s->nodes[i].first_link = w;
        w += s->nodes[i].link_count;
    }
    s->link_count = total;
    s->blocker_count = blockers;
    return RADINTERP_OK;
}


/* Walks the BVH of the patches (a query of its own: the BVH's build and ray
   traversal stay in section 4): the nodes whose boxes pass `test`, and for
   every triangle of the leaves reached, `visit` with its patch (a patch
   may come once per triangle). visit returns 0 to stop the walk; the walk
   then returns 0. */
typedef int (*radinterp__box_test)(const void *ctx, const float *lo, const float *hi);
typedef int (*radinterp__patch_visit)(void *ctx, uint32_t patch);

static int radinterp__bvh_walk(const radinterp_solution *s, radinterp__box_test test, radinterp__patch_visit visit,
                               void *ctx)
{
    uint32_t stack[RADINTERP__BVH_STACK], top = 0, ref = s->bvh.root;
    if (s->bvh.tri_count == 0) return 1;   /* an empty tree: no root to enter */
    if (ref & RADINTERP__BVH_LEAF) {   /* a root leaf has no node box: its triangles' box is tested */
        float lo[3], hi[3];
        uint32_t block = (ref & ~RADINTERP__BVH_LEAF) >> 3, end = block + (ref & 7u) + 1, i, k;
        radinterp__box_empty(lo, hi);
        for (; block < end; block++)
            for (i = 0; i < 4; i++)
                for (k = 0; k < 9; k++) {
                    float x = s->bvh.blocks[block].v[k][i];
                    lo[k % 3] = radinterp__minf(lo[k % 3], x);
                    hi[k % 3] = radinterp__maxf(hi[k % 3], x);
                }
        if (!test(ctx, lo, hi)) return 1;
    }
    for (;;) {
        if (ref & RADINTERP__BVH_LEAF) {   /* a leaf: its blocks' triangles (unused columns repeat the last) */
            uint32_t block = (ref & ~RADINTERP__BVH_LEAF) >> 3, end = block + (ref & 7u) + 1, i;
            for (; block < end; block++)
                for (i = 0; i < 4; i++) {
                    const uint32_t *id = s->bvh.blocks[block].id;
                    if (i > 0 && id[i] == id[i - 1]) continue;
                    if (!visit(ctx, s->tri_patch[id[i]])) return 0;
                }
        } else {   /* a node: the children whose boxes pass the test */
            const radinterp__bvh_node *node = &s->bvh.nodes[ref];
            int i;
            for (i = RADINTERP__BVH_WIDTH - 1; i >= 0; i--) {   /* pushed last to first: walked in order */
                float lo[3], hi[3];
                lo[0] = node->box[0][i]; lo[1] = node->box[2][i]; lo[2] = node->box[4][i];
                hi[0] = node->box[1][i]; hi[1] = node->box[3][i]; hi[2] = node->box[5][i];
                if (lo[0] <= hi[0] && test(ctx, lo, hi)) stack[top++] = node->child[i];
            }
        }
        if (!top) break;
        ref = stack[--top];
    }
    return 1;
}

static int radinterp__cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : (x > y);
}

typedef struct radinterp__near_ctx {
    const radinterp_solution *s;
    const radinterp_allocator *a;
    float lo[3], hi[3];          /* the box grown by the margin */
    radinterp__buf *out;
} radinterp__near_ctx;

static int radinterp__boxes_meet(const float *alo, const float *ahi, const float *blo, const float *bhi)
{
    return alo[0] <= bhi[0] && blo[0] <= ahi[0] && alo[1] <= bhi[1] && blo[1] <= ahi[1] && alo[2] <= bhi[2] &&
           blo[2] <= ahi[2];
}

static int radinterp__near_test(const void *ctx_, const float *lo, const float *hi)
{
    const radinterp__near_ctx *c = (const radinterp__near_ctx *)ctx_;
    return radinterp__boxes_meet(lo, hi, c->lo, c->hi);
}

static int radinterp__near_visit(void *ctx_, uint32_t patch)
{
    radinterp__near_ctx *c = (radinterp__near_ctx *)ctx_;
    const radinterp__patch *pt = &c->s->patches[patch];
    if (!radinterp__boxes_meet(pt->lo, pt->hi, c->lo, c->hi)) return 1;
    return radinterp__buf_u32(c->a, c->out, patch) == 0;
}

/* The patches whose boxes come within margin of the box [lo, hi], each
   once, in ascending order, into out (uint32_t). Returns -1 when out of
   memory. */
static int radinterp__patches_near(const radinterp_solution *s, const radinterp_allocator *a, const float *lo,
                                   const float *hi, double margin, radinterp__buf *out)
{
    radinterp__near_ctx c;
    uint32_t i, n = 0;
    int k;
    c.s = s;
    c.a = a;
    c.out = out;
    for (k = 0; k < 3; k++) {
        c.lo[k] = (float)((double)lo[k] - margin);
        c.hi[k] = (float)((double)hi[k] + margin);
    }
    out->count = 0;
    if (!radinterp__bvh_walk(s, radinterp__near_test, radinterp__near_visit, &c)) return -1;
    if (out->count > 1) qsort(out->data, out->count, sizeof(uint32_t), radinterp__cmp_u32);
    for (i = 0; i < out->count; i++)
        if (n == 0 || RADINTERP__U32(*out)[n - 1] != RADINTERP__U32(*out)[i]) RADINTERP__U32(*out)[n++] = RADINTERP__U32(*out)[i];
    out->count = n;
    return 0;
}

typedef struct radinterp__shaft_ctx {
    radinterp_solution *s;
    radinterp__shaft sh;
    const radinterp__node *r, *src;
    radinterp__buf *pool;
    uint32_t *stamp, mark, *count;
    double tol;
} radinterp__shaft_ctx;

static int radinterp__shaft_box(const void *ctx_, const float *lo, const float *hi)
{
    const radinterp__shaft_ctx *ctx = (const radinterp__shaft_ctx *)ctx_;
    return !radinterp__shaft_culls(&ctx->sh, lo, hi, -ctx->tol);
}

static int radinterp__shaft_visit(void *ctx_, uint32_t b)
{
    radinterp__shaft_ctx *ctx = (radinterp__shaft_ctx *)ctx_;
    uint32_t *slot;
    if (ctx->stamp[b] == ctx->mark || !radinterp__may_block(ctx->s, &ctx->sh, b, ctx->r, ctx->src)) return 1;
    ctx->stamp[b] = ctx->mark;
    slot = (uint32_t *)radinterp__buf_push(&ctx->s->allocator, ctx->pool);
    if (!slot) return 0;
    *slot = b;
    (*ctx->count)++;
    return 1;
}

/* Potential blockers of a pair of nodes: the patches whose boxes meet the
   shaft, found through the BVH (its leaves hold the patches' triangles). */
static int radinterp__shaft_query(radinterp_solution *s, const radinterp__node *r, const radinterp__node *src,
                                  radinterp__buf *pool, uint32_t *stamp, uint32_t mark, uint32_t *count)
{
    radinterp__shaft_ctx ctx;
    ctx.s = s;
    ctx.r = r;
    ctx.src = src;
    ctx.pool = pool;
    ctx.stamp = stamp;
    ctx.mark = mark;
    ctx.count = count;
    ctx.tol = s->epsilon * s->diag;
    radinterp__shaft_build(&ctx.sh, r->lo, r->hi, src->lo, src->hi);
    *count = 0;
    return radinterp__bvh_walk(s, radinterp__shaft_box, radinterp__shaft_visit, &ctx);
}

/* eps_relative of `level`, or `floor` where that is more. */
static double radinterp__tolerance_over(const radinterp_solution *s, double level, double floor)
{
    double rel = s->eps_relative * level;
    return rel > floor ? rel : floor;
}

/* The transport error a link to a receiver at irradiance `level` (the
   least over its lit parts) may make: eps, or eps_relative of the level
   where that is more (relative refinement, the default). */
static double radinterp__tolerance(const radinterp_solution *s, double level)
{
    return radinterp__tolerance_over(s, level, s->eps);
}

/* The same for what a link's source mean may misjudge
   (radinterp__source_error): its floor is eps_source, lower than eps by
   default. Splitting a source adds links, not leaves to the receiver. */
static double radinterp__source_tolerance(const radinterp_solution *s, double level)
{
    return radinterp__tolerance_over(s, level, s->eps_source);
}

/* A node may split while its children are at least min_area; one that
   is divided (an enclosed band with open points on both sides: the foot of
   a wall, its node holding a strip of each room) down to
   min_area / RADINTERP__DIVIDED_SPLIT, so that a wall thinner than the
   smallest nodes still gets leaves on each side of it. */
#define RADINTERP__DIVIDED_SPLIT 16.0
static int radinterp__can_split(const radinterp_solution *s, const radinterp__node *nd)
{
    return 0.25 * nd->area >= (nd->divided ? s->min_area / RADINTERP__DIVIDED_SPLIT : s->min_area);
}

/* A divided node within three levels of min_area (its children below
   RADINTERP__DIVIDED_NEAR times it): each of its links goes to its
   children whatever its error. Its links deliver one room's light to its
   strip of the other, and the many weak links of a lit room each pass the
   error test (their errors add up in the receiver's budget to most of its
   light, and once split its dark children show their parent's mean, so
   the test cannot see them). Larger divided nodes (a storey's slab as a
   whole) are left to the error test: forcing theirs down as well took
   building_1k's links from 2.3x to 3.4x for little. */
#define RADINTERP__DIVIDED_NEAR 64.0
static int radinterp__divided_below(const radinterp_solution *s, const radinterp__node *nd)
{
    return nd->divided && 0.25 * nd->area < RADINTERP__DIVIDED_NEAR * s->min_area && radinterp__can_split(s, nd);
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

/* ---- clusters (Smits, Arvo and Greenberg 1994; Sillion 1995) ----------
   The patches are the leaves of a binary tree of clusters (median splits
   of their centres along the longest axis). An element is a cluster or a
   quadtree node; id bit RADINTERP__CLUSTER marks a cluster. Linking starts
   at the top: every cluster joins its two children both ways, so every
   pair of patches is represented once, by its lowest common cluster. A
   link with a cluster at either end (a cluster link) carries light between
   the elements' centres: the source's power toward the receiver over
   pi r^2, times the fraction of rays between random points of the two
   that no surface blocks; a link whose rays are all blocked, or none of
   whose point pairs face each other, is dropped when patches in one plane
   between the two hide them from each other (nothing crosses a solid
   wall), else kept at the fraction measured. A cluster's power toward a direction u
   comes from six sums over its patches, one per axis direction a:
   P_a = sum A open B max(0, n . a), P(u) = sum_k |u_k| P_(sign u_k) e_k,
   exact for patches facing along the axes and an upper bound otherwise;
   what a cluster receives is kept the same way (the irradiance of a
   surface facing each axis direction) and pushed down to its patches. A
   cluster link stays while the irradiance it could carry at most, the
   source's power bound over pi times the squared distance between the two
   boxes, is below eps; else its larger element is split (a cluster into
   its two children, a node into its quadtree children). When both ends are
   quadtree nodes the link becomes an ordinary link (4.2) with its blockers
   from shaft culling. */
#define RADINTERP__CLUSTER 0x80000000u   /* element id bit: a cluster; else a quadtree node */
#ifndef RADINTERP__EPS_FLOOR
#define RADINTERP__EPS_FLOOR 0.01        /* default eps: this times the mean emitted radiosity */
#endif
#ifndef RADINTERP__EPS_SOURCE_FLOOR
#define RADINTERP__EPS_SOURCE_FLOOR 0.001 /* default eps for a source's variation: this times the mean emitted radiosity */
#endif
#ifndef RADINTERP__EPS_RELATIVE
#define RADINTERP__EPS_RELATIVE 0.05     /* default eps_relative */
#endif
#ifndef RADINTERP_RECEIVER_BUDGET
#define RADINTERP_RECEIVER_BUDGET 16.0   /* the links into one node may err by this many tolerances together */
#endif
#define RADINTERP__CLUSTER_RAYS 16       /* visibility rays of a cluster link */
#define RADINTERP__CLUSTER_TOLERANCE 0.1 /* a cluster link may carry this much of a link's tolerance at most */

typedef struct radinterp__clink {
    uint32_t receiver, source;  /* elements, one of them at least a cluster */
    float k;                    /* visible fraction / (pi r^2), r between the elements' centres (largest channel) */
    float dir[3];               /* unit vector from the receiver's centre toward the source's */
    float tint[3];              /* each channel's visible fraction over the largest's (panes); 1 without glass */
} radinterp__clink;

static int radinterp__is_cluster(uint32_t el) { return (el & RADINTERP__CLUSTER) != 0; }

static const radinterp__cluster *radinterp__cl(const radinterp_solution *s, uint32_t el)
{
    return &s->clusters[el & ~RADINTERP__CLUSTER];
}

static void radinterp__elem_box(const radinterp_solution *s, uint32_t el, const float **lo, const float **hi)
{
    if (radinterp__is_cluster(el)) { *lo = radinterp__cl(s, el)->lo; *hi = radinterp__cl(s, el)->hi; }
    else { *lo = s->nodes[el].lo; *hi = s->nodes[el].hi; }
}

static radinterp__ray_end radinterp__elem_ray_end(const radinterp_solution *s, uint32_t el)
{
    radinterp__ray_end e;
    radinterp__elem_box(s, el, &e.lo, &e.hi);
    e.n = NULL;
    e.d = e.floor = 0.0;
    if (!radinterp__is_cluster(el)) {   /* its rays start on one patch's plane */
        e.n = s->patches[s->nodes[el].patch].n;
        e.d = s->patches[s->nodes[el].patch].d;
    }
    return e;
}

static void radinterp__elem_centre(const radinterp_solution *s, uint32_t el, double *c)
{
    int k;
    if (radinterp__is_cluster(el)) {
        const radinterp__cluster *cl = radinterp__cl(s, el);
        for (k = 0; k < 3; k++) c[k] = 0.5 * ((double)cl->lo[k] + cl->hi[k]);
    } else {
        const radinterp__node *nd = &s->nodes[el];
        uint32_t i;
        for (k = 0; k < 3; k++) {
            c[k] = 0.0;
            for (i = 0; i < nd->count; i++) c[k] += nd->v[i][k];
            c[k] /= nd->count;
        }
    }
}

static double radinterp__elem_size(const radinterp_solution *s, uint32_t el)
{
    const float *lo, *hi;
    double d2 = 0.0;
    int k;
    radinterp__elem_box(s, el, &lo, &hi);
    for (k = 0; k < 3; k++) d2 += ((double)hi[k] - lo[k]) * ((double)hi[k] - lo[k]);
    return sqrt(d2);
}

/* Power (W / sr * pi: sum of A B cos) an element sends toward unit u. */
static void radinterp__elem_power(const radinterp_solution *s, uint32_t el, const double *u, double *p)
{
    int k, c;
    p[0] = p[1] = p[2] = 0.0;
    if (radinterp__is_cluster(el)) {
        const radinterp__cluster *cl = radinterp__cl(s, el);
        for (k = 0; k < 3; k++) {
            const float *a = cl->power[2 * k + (u[k] < 0.0)];
            for (c = 0; c < 3; c++) p[c] += fabs(u[k]) * a[c];
        }
    } else {
        const radinterp__node *nd = &s->nodes[el];
        double cosine = radinterp__d3_dot(s->patches[nd->patch].n, u), a = (double)nd->area * nd->open;
        if (cosine > 0.0)
            for (c = 0; c < 3; c++) p[c] = a * cosine * nd->b[c];
    }
}

/* The most power an element sends toward any direction (largest channel). */
static double radinterp__elem_power_bound(const radinterp_solution *s, uint32_t el)
{
    if (radinterp__is_cluster(el)) return radinterp__cl(s, el)->bound;
    {
        const radinterp__node *nd = &s->nodes[el];
        return (double)nd->area * nd->open * radinterp__maxf(nd->b[0], radinterp__maxf(nd->b[1], nd->b[2]));
    }
}

/* Irradiance of a surface with unit normal n under light of irradiance e
   (on a surface facing it) from unit direction dir. */
static double radinterp__facing(const double *n, const float *dir)
{
    double c = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
    return c > 0.0 ? c : 0.0;
}

/* A random point of an element with the normal of its surface: a cluster
   picks one of its patches by area. */
static void radinterp__elem_point(const radinterp_solution *s, uint32_t el, radinterp__rng *rng, double *p, double *n)
{
    double v[RADINTERP__POLY_MAX][3], tri_area[RADINTERP__POLY_MAX], total;
    const radinterp__patch *pt;
    int count;
    if (radinterp__is_cluster(el)) {
        const radinterp__cluster *cl = radinterp__cl(s, el);
        double base = cl->first ? s->cluster_cdf[cl->first - 1] : 0.0;
        double x = base + radinterp__rng_float(rng) * (s->cluster_cdf[cl->first + cl->count - 1] - base);
        uint32_t lo = cl->first, hi = cl->first + cl->count - 1;
        while (lo < hi) {  /* the first patch whose prefix area reaches x */
            uint32_t mid = lo + (hi - lo) / 2;
            if (s->cluster_cdf[mid] < x) lo = mid + 1;
            else hi = mid;
        }
        pt = &s->patches[s->cluster_order[lo]];
        count = radinterp__patch_poly(pt, v);
    } else {
        pt = &s->patches[s->nodes[el].patch];
        count = radinterp__node_poly(&s->nodes[el], v);
    }
    total = radinterp__fan_areas((const double (*)[3])v, count, tri_area);
    {
        double u1 = radinterp__rng_float(rng), u2 = radinterp__rng_float(rng);
        radinterp__poly_point((const double (*)[3])v, count, tri_area, total, u1, u2, p);
    }
    memcpy(n, pt->n, 3 * sizeof(double));
}

/* Squared distance between two boxes (0 when they touch or overlap). */
static double radinterp__box_distance2(const float *alo, const float *ahi, const float *blo, const float *bhi)
{
    double d2 = 0.0;
    int k;
    for (k = 0; k < 3; k++) {
        double g = (double)blo[k] - ahi[k] > (double)alo[k] - bhi[k] ? (double)blo[k] - ahi[k] : (double)alo[k] - bhi[k];
        if (g > 0.0) d2 += g * g;
    }
    return d2;
}

/* Does the box lie wholly behind the plane of node nd's patch (within tol)? */
static int radinterp__box_behind(const radinterp_solution *s, const radinterp__node *nd, const float *lo, const float *hi,
                                 double tol)
{
    const radinterp__patch *pt = &s->patches[nd->patch];
    double m = -pt->d;
    int k;
    for (k = 0; k < 3; k++) m += pt->n[k] * (pt->n[k] > 0.0 ? (double)hi[k] : (double)lo[k]);
    return m <= tol;
}


/* Could a cluster link from source to receiver carry more than its share
   of the tolerance (see the clusters above)? The receiver's level is the
   least irradiance of its lit leaves, or before the first gather the mean
   emitted radiosity. */
static int radinterp__clink_too_coarse(const radinterp_solution *s, uint32_t receiver, uint32_t source)
{
    const float *rlo, *rhi, *slo, *shi;
    double d2, level;
    radinterp__elem_box(s, receiver, &rlo, &rhi);
    radinterp__elem_box(s, source, &slo, &shi);
    d2 = radinterp__box_distance2(rlo, rhi, slo, shi);
    if (!(d2 > 0.0)) return 1;
    if (!s->levels_known) level = s->light_scale;
    else level = radinterp__is_cluster(receiver) ? radinterp__cl(s, receiver)->hmin : s->patch_hmin[s->nodes[receiver].patch];
    return radinterp__elem_power_bound(s, source) / (RADINTERP__PI * d2) >
           RADINTERP__CLUSTER_TOLERANCE * radinterp__tolerance(s, level);
}


/* A cluster link waiting for its transfer factor. */
typedef struct radinterp__cpending {
    uint32_t receiver, source;
    float k, dir[3], tint[3];
    uint32_t dead;      /* facing away, or hidden */
    uint32_t hidden;    /* dead because planes between the two hide them from each other */
    uint32_t coarse;    /* could carry too much: to be split (its transfer is not computed) */
    uint32_t rays;
} radinterp__cpending;

/* Transfer factor of a cluster link: centres, facing, visible fraction
   (rays between random points of the two, each weighted by cos cos / r^2
   at its ends, as radinterp__visible_fraction). */
static void radinterp__clink_compute(const radinterp_solution *s, radinterp__cpending *pc)
{
    const float *rlo, *rhi, *slo, *shi;
    double cr[3], cs[3], d[3], r, open[3] = {0.0, 0.0, 0.0}, all = 0.0, off = radinterp__ray_offset(s), tol = s->epsilon * s->diag;
    radinterp__rng rng = radinterp__rng_stream(s->seed ^ 0xC1C1C1C1u, (uint64_t)pc->receiver << 32 | pc->source);
    radinterp__shaft_rays sr;
    int i, k;
    pc->dead = 1;
    pc->hidden = pc->coarse = 0;
    pc->rays = 0;
    pc->k = pc->dir[0] = pc->dir[1] = pc->dir[2] = 0.0f;
    pc->tint[0] = pc->tint[1] = pc->tint[2] = 1.0f;
    radinterp__elem_box(s, pc->receiver, &rlo, &rhi);
    radinterp__elem_box(s, pc->source, &slo, &shi);
    if (!radinterp__is_cluster(pc->receiver) && radinterp__box_behind(s, &s->nodes[pc->receiver], slo, shi, tol)) return;
    if (!radinterp__is_cluster(pc->source) && radinterp__box_behind(s, &s->nodes[pc->source], rlo, rhi, tol)) return;
    pc->coarse = (uint32_t)radinterp__clink_too_coarse(s, pc->receiver, pc->source);
    if (pc->coarse) { /* split unless hidden: a pair hidden as a whole is settled here */
        pc->hidden = (uint32_t)radinterp__planes_hide(s, rlo, rhi, slo, shi);
        pc->dead = pc->hidden;
        return;
    }
    radinterp__elem_centre(s, pc->receiver, cr);
    radinterp__elem_centre(s, pc->source, cs);
    radinterp__d3_sub(cs, cr, d);
    r = radinterp__d3_len(d);
    pc->dead = 0;
    if (!(r > 0.0)) { pc->dir[2] = 1.0f; return; } /* centres at one point: carries nothing, refined at once */
    if (s->glass_patches) sr.walk = 1;
    else radinterp__shaft_rays_init(s, &sr, radinterp__elem_ray_end(s, pc->receiver), radinterp__elem_ray_end(s, pc->source));
    for (k = 0; k < 3; k++) pc->dir[k] = (float)(d[k] / r);
    /* the visible fraction weighs the transfer; rays cannot prove a pair
       hidden (a small close part they miss may carry most of it), so when
       all are blocked the planes decide whether the link is dropped */
    for (i = 0; i < RADINTERP__CLUSTER_RAYS; i++) {
        double a[3], na[3], b[3], nb[3], ab[3], w, r2, T[3];
        radinterp__elem_point(s, pc->receiver, &rng, a, na);
        radinterp__elem_point(s, pc->source, &rng, b, nb);
        radinterp__d3_sub(b, a, ab);
        r2 = radinterp__d3_dot(ab, ab);
        w = r2 > 0.0 ? radinterp__d3_dot(ab, na) * -radinterp__d3_dot(ab, nb) / (r2 * r2) : 0.0;
        if (!(w > 0.0)) continue;
        for (k = 0; k < 3; k++) { a[k] += off * na[k]; b[k] += off * nb[k]; }
        all += w;
        pc->rays++;
        radinterp__shaft_light(s, &sr, a, b, s->glass_patches != 0, T);
        for (k = 0; k < 3; k++) open[k] += w * T[k];
    }
    /* no ray got through, or no pair of points faced each other (then the
       rays say nothing and the transfer would count as unblocked: a desk
       leg's cluster link to the next room through the wall carried light) */
    {
        double most = radinterp__max3(open);
        if (most == 0.0 && radinterp__planes_hide(s, rlo, rhi, slo, shi)) { pc->dead = pc->hidden = 1; return; }
        pc->k = (float)((all > 0.0 ? most / all : 1.0) / (RADINTERP__PI * r * r));
        if (most > 0.0 && s->glass_patches)   /* panes tint the light: each channel's share of the brightest */
            for (k = 0; k < 3; k++) pc->tint[k] = (float)(open[k] / most);
    }
}

typedef struct radinterp__cctx {
    const radinterp_solution *s;
    radinterp__cpending *pending;
    uint32_t begin, end;
} radinterp__cctx;

#define RADINTERP__CLINK_JOB 32

static void radinterp__clink_job(void *ctx_, uint32_t index)
{
    radinterp__cctx *ctx = (radinterp__cctx *)ctx_;
    uint32_t i = ctx->begin + index * RADINTERP__CLINK_JOB, end = i + RADINTERP__CLINK_JOB;
    if (end > ctx->end) end = ctx->end;
    for (; i < end; i++) radinterp__clink_compute(ctx->s, &ctx->pending[i]);
}

/* The sorting bucket of a receiver element: nodes first, then clusters. */
static uint32_t radinterp__bucket(const radinterp_solution *s, uint32_t el)
{
    return radinterp__is_cluster(el) ? s->node_count + (el & ~RADINTERP__CLUSTER) : el;
}

/* Replaces the cluster links by the kept ones plus the live pending ones,
   sorted by receiver (stable): node.first_clink / clink_count and
   cluster.first_link / link_count. */
static radinterp_result radinterp__install_clinks(radinterp_solution *s, const radinterp__clink *keep, uint32_t keep_count,
                                                  const radinterp__cpending *pend, uint32_t pend_count)
{
    uint32_t buckets = s->node_count + s->cluster_count, total = keep_count, i;
    uint32_t *start;
    radinterp__clink *links;
    for (i = 0; i < pend_count; i++) total += !pend[i].dead;
    links = (radinterp__clink *)radinterp__alloc_array(&s->allocator, total, sizeof *links);
    start = (uint32_t *)radinterp__alloc_array(&s->allocator, (size_t)buckets + 1, sizeof *start);
    if (!links || !start) {
        radinterp__free(&s->allocator, links);
        radinterp__free(&s->allocator, start);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    memset(start, 0, ((size_t)buckets + 1) * sizeof *start);
    for (i = 0; i < keep_count; i++) start[radinterp__bucket(s, keep[i].receiver) + 1]++;
    for (i = 0; i < pend_count; i++)
        if (!pend[i].dead) start[radinterp__bucket(s, pend[i].receiver) + 1]++;
    for (i = 0; i < buckets; i++) {
        if (i < s->node_count) { s->nodes[i].first_clink = start[i]; s->nodes[i].clink_count = start[i + 1]; }
        else { s->clusters[i - s->node_count].first_link = start[i]; s->clusters[i - s->node_count].link_count = start[i + 1]; }
        start[i + 1] += start[i];
    }
    for (i = 0; i < keep_count; i++) links[start[radinterp__bucket(s, keep[i].receiver)]++] = keep[i];
    for (i = 0; i < pend_count; i++) {
        radinterp__clink *l;
        if (pend[i].dead) continue;
        l = &links[start[radinterp__bucket(s, pend[i].receiver)]++];
        l->receiver = pend[i].receiver;
        l->source = pend[i].source;
        l->k = pend[i].k;
        memcpy(l->dir, pend[i].dir, sizeof l->dir);
        memcpy(l->tint, pend[i].tint, sizeof l->tint);
    }
    radinterp__free(&s->allocator, start);
    radinterp__free(&s->allocator, s->clinks);
    s->clinks = links;
    s->clink_count = total;
    return RADINTERP_OK;
}

typedef struct radinterp__ckey { float key; uint32_t patch; } radinterp__ckey;

static int radinterp__cmp_ckey(const void *a, const void *b)
{
    const radinterp__ckey *x = (const radinterp__ckey *)a, *y = (const radinterp__ckey *)b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->patch < y->patch ? -1 : (x->patch > y->patch);
}

/* The cluster tree over the patches (see above): clusters[0] is the top, a
   parent comes before its children. Returns 0, or -1 when out of memory. */
static int radinterp__build_clusters(radinterp_solution *s)
{
    uint32_t n = 0, i, top = 0, *stack;
    radinterp__ckey *keys;
    double acc = 0.0;
    s->patch_cluster = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(uint32_t));
    s->cluster_order = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(uint32_t));
    s->cluster_cdf = (double *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(double));
    if (!s->patch_cluster || !s->cluster_order || !s->cluster_cdf) return -1;
    for (i = 0; i < s->patch_count; i++) {
        s->patch_cluster[i] = RADINTERP__NONE;
        if (s->patches[i].count) s->cluster_order[n++] = i;
    }
    if (n < 2) return 0;
    s->clusters = (radinterp__cluster *)radinterp__alloc_array(&s->allocator, n - 1, sizeof *s->clusters);
    keys = (radinterp__ckey *)radinterp__alloc_array(&s->allocator, n, sizeof *keys);
    stack = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof *stack);
    if (!s->clusters || !keys || !stack) {
        radinterp__free(&s->allocator, keys);
        radinterp__free(&s->allocator, stack);
        return -1;
    }
    memset(s->clusters, 0, (size_t)(n - 1) * sizeof *s->clusters);
    s->clusters[0].first = 0;
    s->clusters[0].count = n;
    s->clusters[0].parent = RADINTERP__NONE;
    s->cluster_count = 1;
    stack[top++] = 0;
    while (top) {
        uint32_t c = stack[--top], first = s->clusters[c].first, count = s->clusters[c].count, half[2], h, axis = 0;
        float clo[3], chi[3];
        radinterp__box_empty(clo, chi);
        radinterp__box_empty(s->clusters[c].lo, s->clusters[c].hi);
        for (i = first; i < first + count; i++) {
            const radinterp__patch *pt = &s->patches[s->cluster_order[i]];
            float ctr[3];
            int k;
            for (k = 0; k < 3; k++) ctr[k] = (float)pt->centre[k];
            radinterp__box_grow(clo, chi, ctr, ctr);
            radinterp__box_grow(s->clusters[c].lo, s->clusters[c].hi, pt->lo, pt->hi);
        }
        if (chi[1] - clo[1] > chi[axis] - clo[axis]) axis = 1;
        if (chi[2] - clo[2] > chi[axis] - clo[axis]) axis = 2;
        for (i = 0; i < count; i++) {
            keys[i].patch = s->cluster_order[first + i];
            keys[i].key = (float)s->patches[keys[i].patch].centre[axis];
        }
        qsort(keys, count, sizeof *keys, radinterp__cmp_ckey);
        for (i = 0; i < count; i++) s->cluster_order[first + i] = keys[i].patch;
        half[0] = count / 2;
        half[1] = count - half[0];
        for (h = 0; h < 2; h++) {
            uint32_t hf = first + (h ? half[0] : 0);
            if (half[h] == 1) {
                s->clusters[c].child[h] = s->patches[s->cluster_order[hf]].root;
                s->patch_cluster[s->cluster_order[hf]] = c;
                continue;
            }
            s->clusters[s->cluster_count].first = hf;
            s->clusters[s->cluster_count].count = half[h];
            s->clusters[s->cluster_count].parent = c;
            s->clusters[c].child[h] = RADINTERP__CLUSTER | s->cluster_count;
            stack[top++] = s->cluster_count++;
        }
    }
    for (i = 0; i < n; i++) {
        acc += s->patches[s->cluster_order[i]].area;
        s->cluster_cdf[i] = acc;
    }
    radinterp__free(&s->allocator, keys);
    radinterp__free(&s->allocator, stack);
    return 0;
}

/* Pull (after push-pull): each cluster's power basis from its children. */
static void radinterp__pull_clusters(radinterp_solution *s)
{
    uint32_t c = s->cluster_count, h;
    int a, ch, k;
    while (c-- > 0) {
        radinterp__cluster *cl = &s->clusters[c];
        double p[6][3], bound = 0.0, hmin = 0.0;
        memset(p, 0, sizeof p);
        for (h = 0; h < 2; h++) {
            uint32_t el = cl->child[h];
            double hm = radinterp__is_cluster(el) ? radinterp__cl(s, el)->hmin : s->patch_hmin[s->nodes[el].patch];
            if (hm > 0.0 && (hmin == 0.0 || hm < hmin)) hmin = hm;
            if (radinterp__is_cluster(el)) {
                const radinterp__cluster *cc = radinterp__cl(s, el);
                for (a = 0; a < 6; a++)
                    for (ch = 0; ch < 3; ch++) p[a][ch] += cc->power[a][ch];
            } else {
                const radinterp__node *nd = &s->nodes[el];
                const double *n = s->patches[nd->patch].n;
                double area = (double)nd->area * nd->open;
                for (k = 0; k < 3; k++) {
                    a = 2 * k + (n[k] < 0.0);
                    for (ch = 0; ch < 3; ch++) p[a][ch] += area * fabs(n[k]) * nd->b[ch];
                }
            }
        }
        for (ch = 0; ch < 3; ch++) {
            double sum = 0.0;
            for (k = 0; k < 3; k++) sum += p[2 * k][ch] > p[2 * k + 1][ch] ? p[2 * k][ch] : p[2 * k + 1][ch];
            bound = sum > bound ? sum : bound;
        }
        for (a = 0; a < 6; a++)
            for (ch = 0; ch < 3; ch++) cl->power[a][ch] = (float)p[a][ch];
        cl->bound = (float)bound;
        cl->hmin = (float)hmin;
    }
}

/* Irradiance (rgb, on a surface facing the source) a cluster link delivers. */
static void radinterp__clink_irradiance(const radinterp_solution *s, const radinterp__clink *l, double *e)
{
    double u[3];
    int k;
    for (k = 0; k < 3; k++) u[k] = -(double)l->dir[k];
    radinterp__elem_power(s, l->source, u, e);
    for (k = 0; k < 3; k++) e[k] *= l->k * l->tint[k];
}

/* Gather of the clusters' own links (per axis direction), then push: each
   cluster's down = its parent's down + its own. */
static void radinterp__cluster_gather_job(void *ctx_, uint32_t index)
{
    radinterp_solution *s = (radinterp_solution *)ctx_;
    uint32_t c = index * 64, end = c + 64;
    if (end > s->cluster_count) end = s->cluster_count;
    for (; c < end; c++) {
        radinterp__cluster *cl = &s->clusters[c];
        double e[6][3];
        uint32_t l;
        int a, k, ch;
        memset(e, 0, sizeof e);
        for (l = cl->first_link; l < cl->first_link + cl->link_count; l++) {
            const radinterp__clink *lk = &s->clinks[l];
            double en[3];
            radinterp__clink_irradiance(s, lk, en);
            for (k = 0; k < 3; k++) {
                a = 2 * k + (lk->dir[k] < 0.0f);
                for (ch = 0; ch < 3; ch++) e[a][ch] += fabs((double)lk->dir[k]) * en[ch];
            }
        }
        for (a = 0; a < 6; a++)
            for (ch = 0; ch < 3; ch++) cl->e[a][ch] = (float)e[a][ch];
    }
}

static void radinterp__push_clusters(radinterp_solution *s)
{
    uint32_t c;
    int a, ch;
    for (c = 0; c < s->cluster_count; c++) {
        radinterp__cluster *cl = &s->clusters[c];
        const radinterp__cluster *up = cl->parent != RADINTERP__NONE ? &s->clusters[cl->parent] : NULL;
        for (a = 0; a < 6; a++)
            for (ch = 0; ch < 3; ch++) cl->down[a][ch] = cl->e[a][ch] + (up ? up->down[a][ch] : 0.0f);
    }
}

/* Irradiance the clusters above a patch deliver to it (normal n). */
static void radinterp__cluster_down(const radinterp_solution *s, uint32_t patch, double *h)
{
    const double *n = s->patches[patch].n;
    uint32_t c = s->patch_cluster ? s->patch_cluster[patch] : RADINTERP__NONE;
    int k, ch;
    h[0] = h[1] = h[2] = 0.0;
    if (c == RADINTERP__NONE) return;
    for (k = 0; k < 3; k++) {
        const float *d = s->clusters[c].down[2 * k + (n[k] < 0.0)];
        for (ch = 0; ch < 3; ch++) h[ch] += fabs(n[k]) * d[ch];
    }
}

/* New links made by refinement or by the initial linking of the clusters:
   ordinary links (their candidate blockers are their parent link's, or
   from shaft culling for those split off a cluster link) and cluster
   links. */
typedef struct radinterp__linker {
    radinterp__buf pend;     /* radinterp__pending */
    radinterp__buf cpend;    /* radinterp__cpending */
    radinterp__buf shaft;    /* uint32_t: candidates found by shaft culling here */
    uint32_t *stamp, mark;    /* per patch: the query that listed it last */
    uint64_t candidates;      /* candidates of all pending ordinary links */
} radinterp__linker;

static int radinterp__linker_init(radinterp_solution *s, radinterp__linker *L)
{
    memset(L, 0, sizeof *L);
    L->pend.item = sizeof(radinterp__pending);
    L->cpend.item = sizeof(radinterp__cpending);
    L->shaft.item = sizeof(uint32_t);
    L->stamp = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(uint32_t));
    if (!L->stamp) return 0;
    memset(L->stamp, 0xFF, (size_t)s->patch_count * sizeof(uint32_t));
    return 1;
}

static void radinterp__linker_free(radinterp_solution *s, radinterp__linker *L)
{
    radinterp__free(&s->allocator, L->pend.data);
    radinterp__free(&s->allocator, L->cpend.data);
    radinterp__free(&s->allocator, L->shaft.data);
    radinterp__free(&s->allocator, L->stamp);
}

/* Does this patch never shine (black and not emitting)? */
static int radinterp__patch_dark(const radinterp__patch *pt)
{
    return pt->rho[0] == 0.0f && pt->rho[1] == 0.0f && pt->rho[2] == 0.0f && pt->e[0] == 0.0f && pt->e[1] == 0.0f &&
           pt->e[2] == 0.0f;
}

/* A new link from element src to element r. Returns 0 when out of memory. */
static int radinterp__link_elements(radinterp_solution *s, radinterp__linker *L, uint32_t r, uint32_t src)
{
    radinterp__pending *pl;
    uint32_t first, count;
    if (radinterp__is_cluster(r) || radinterp__is_cluster(src)) {
        radinterp__cpending *pc = (radinterp__cpending *)radinterp__buf_push(&s->allocator, &L->cpend);
        if (!pc) return 0;
        memset(pc, 0, sizeof *pc);
        pc->receiver = r;
        pc->source = src;
        return 1;
    }
    if (radinterp__patch_dark(&s->patches[s->nodes[src].patch])) return 1;
    first = (uint32_t)L->shaft.count;
    if (!radinterp__shaft_query(s, &s->nodes[r], &s->nodes[src], &L->shaft, L->stamp, L->mark++, &count)) return 0;
    if (L->shaft.count > 0xFFFFFFFFu) return 0;
    pl = (radinterp__pending *)radinterp__buf_push(&s->allocator, &L->pend);
    if (!pl) return 0;
    memset(pl, 0, sizeof *pl);
    pl->receiver = r;
    pl->source = src;
    pl->first = first;
    pl->count = count;
    pl->fresh = 1;
    L->candidates += count;
    return 1;
}

/* The four children of a link split at one end (4.4.1): which = 0 splits
   the receiver node, 1 the source node. Returns 0 when out of memory. */
static int radinterp__split_link(radinterp_solution *s, radinterp__linker *L, const radinterp__link *l, int which)
{
    uint32_t k;
    if (radinterp__node_split(s, which == 0 ? l->receiver : l->source) != 0) return 0;
    for (k = 0; k < 4; k++) {
        radinterp__pending *pl = (radinterp__pending *)radinterp__buf_push(&s->allocator, &L->pend);
        if (!pl) return 0;
        memset(pl, 0, sizeof *pl);
        pl->receiver = which == 0 ? s->nodes[l->receiver].child + k : l->receiver;
        pl->source = which == 1 ? s->nodes[l->source].child + k : l->source;
        pl->first = l->first_blocker;
        pl->count = l->blocker_count;
        pl->filter = 1;
        L->candidates += l->blocker_count;
    }
    return 1;
}

/* Splits a cluster link at its cluster end, the larger (by box diagonal)
   when both are clusters. A patch at the other end stays whole: how finely
   it is divided is for the ordinary links it ends up with to decide
   (4.4.1). Returns 0 when out of memory. */
static int radinterp__split_clink(radinterp_solution *s, radinterp__linker *L, uint32_t receiver, uint32_t source)
{
    int at_receiver = radinterp__elem_size(s, receiver) >= radinterp__elem_size(s, source), k;
    const radinterp__cluster *cl;
    if (!radinterp__is_cluster(at_receiver ? receiver : source)) at_receiver = !at_receiver;
    cl = radinterp__cl(s, at_receiver ? receiver : source);
    for (k = 0; k < 2; k++)
        if (!radinterp__link_elements(s, L, at_receiver ? cl->child[k] : receiver, at_receiver ? source : cl->child[k]))
            return 0;
    return 1;
}

/* Computes the pending cluster links in batches, with progress between. */
static radinterp_result radinterp__compute_cpending(radinterp_solution *s, radinterp__run *run,
                                                    radinterp__cpending *pending, uint32_t count)
{
    const uint32_t per_job = RADINTERP__CLINK_JOB;
    uint32_t begin = 0, i, jobs;
    radinterp__pacer pacer;
    radinterp__pacer_init(&pacer, run->desc->progress_interval, 4096 / per_job);
    while (begin < count) {
        radinterp__cctx ctx;
        jobs = radinterp__pacer_next(&pacer, (count - begin + per_job - 1) / per_job);
        ctx.s = s;
        ctx.pending = pending;
        ctx.begin = begin;
        ctx.end = count - begin > jobs * per_job ? begin + jobs * per_job : count;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__clink_job, &ctx, jobs);
        radinterp__pacer_adapt(&pacer);
        for (i = ctx.begin; i < ctx.end; i++) s->shadow_rays += pending[i].rays;
        begin = ctx.end;
        if (radinterp__cancelled(s, run)) return RADINTERP_ERROR_CANCELLED;
    }
    return RADINTERP_OK;
}

/* A node whose child is divided is divided too, though its own grid of
   points, coarser, may have missed the wall between them: its links would
   deliver the lit room's light to the child's strip of the dark room.
   Serial, after the grids of the nodes made since `first`. */
static void radinterp__divide_ancestors(radinterp_solution *s, uint32_t first)
{
    uint32_t i, p;
    for (i = first; i < s->node_count; i++)
        if (s->nodes[i].divided)
            for (p = s->nodes[i].parent; p != RADINTERP__NONE && !s->nodes[p].divided; p = s->nodes[p].parent)
                s->nodes[p].divided = 1;
}

/* Measures the open fractions of the nodes made since *mark. */
static void radinterp__open_new_nodes(radinterp_solution *s, radinterp__run *run, uint32_t *mark)
{
    radinterp__open_ctx oc;
    oc.s = s;
    oc.first = *mark;
    oc.count = s->node_count - *mark;
    radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__open_job, &oc, (oc.count + 63) / 64);
    radinterp__divide_ancestors(s, *mark);
    *mark = s->node_count;
}

/* The pending cluster links in waves: each wave's transfers are computed
   together; a link whose rays were all blocked is dropped, one that could
   carry too much is split at once (its children form the next wave, or
   become pending ordinary links), the others are kept in *accepted. So no
   cluster link carries more than its share of the tolerance, even for one
   iteration. */
static radinterp_result radinterp__resolve_clinks(radinterp_solution *s, radinterp__run *run, radinterp__linker *L,
                                                  radinterp__buf *accepted, uint32_t *mark)
{
    radinterp_result res = RADINTERP_OK;
    while (L->cpend.count && res == RADINTERP_OK) {
        radinterp__buf wave = L->cpend;
        radinterp__cpending *w = (radinterp__cpending *)wave.data;
        uint32_t i;
        memset(&L->cpend, 0, sizeof L->cpend);
        L->cpend.item = sizeof(radinterp__cpending);
        radinterp__open_new_nodes(s, run, mark);
        res = radinterp__compute_cpending(s, run, w, (uint32_t)wave.count);
        for (i = 0; i < wave.count && res == RADINTERP_OK; i++) {
            radinterp__cpending *slot;
            if (radinterp__solve_step(s, run, i)) { res = RADINTERP_ERROR_CANCELLED; break; }
            s->culled_links += w[i].hidden;
            if (w[i].dead) continue;
            if (w[i].coarse) {
                if (!radinterp__split_clink(s, L, w[i].receiver, w[i].source)) res = RADINTERP_ERROR_OUT_OF_MEMORY;
                continue;
            }
            slot = (radinterp__cpending *)radinterp__buf_push(&s->allocator, accepted);
            if (!slot) res = RADINTERP_ERROR_OUT_OF_MEMORY;
            else *slot = w[i];
        }
        radinterp__free(&s->allocator, wave.data);
    }
    return res;
}

/* Resolves the pending cluster links, measures the new nodes' open
   fractions, computes every pending ordinary link and installs them all
   beside the kept ones. */
static radinterp_result radinterp__finish_linking(radinterp_solution *s, radinterp__run *run, radinterp__linker *L,
                                                  uint32_t nodes_before, uint32_t nkeep,
                                                  const radinterp__clink *ckeep, uint32_t nckeep)
{
    radinterp__pending *p;
    radinterp__buf accepted;
    uint32_t *wide = NULL, *out = NULL, i, at = 0, mark = nodes_before;
    size_t n;
    radinterp_result res;
    memset(&accepted, 0, sizeof accepted);
    accepted.item = sizeof(radinterp__cpending);
    res = radinterp__resolve_clinks(s, run, L, &accepted, &mark);
    if (res == RADINTERP_OK) radinterp__open_new_nodes(s, run, &mark);
    if (res == RADINTERP_OK && L->candidates > 0xFFFFFFFFu) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    /* each pending link gets its own copy of its candidates */
    n = L->candidates ? (size_t)L->candidates : 1;
    p = (radinterp__pending *)L->pend.data;
    if (res == RADINTERP_OK) {
        wide = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
        out = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
        if (!wide || !out) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    for (i = 0; i < L->pend.count && res == RADINTERP_OK; i++) {
        const uint32_t *from = p[i].fresh ? (const uint32_t *)L->shaft.data : s->blockers;
        if (radinterp__solve_step(s, run, i)) { res = RADINTERP_ERROR_CANCELLED; break; }
        if (p[i].count) memcpy(wide + at, from + p[i].first, p[i].count * sizeof(uint32_t));
        p[i].first = at;
        at += p[i].count;
    }
    if (res == RADINTERP_OK) res = radinterp__compute_pending(s, run, p, (uint32_t)L->pend.count, wide, out);
    radinterp__free(&s->allocator, wide);
    if (res == RADINTERP_OK) res = radinterp__install_links(s, run, nkeep, p, (uint32_t)L->pend.count, out);
    if (res == RADINTERP_OK && radinterp__solve_tick(s, run)) res = RADINTERP_ERROR_CANCELLED;
    if (res == RADINTERP_OK)
        res = radinterp__install_clinks(s, ckeep, nckeep, (const radinterp__cpending *)accepted.data,
                                        (uint32_t)accepted.count);
    radinterp__free(&s->allocator, out);
    radinterp__free(&s->allocator, accepted.data);
    return res;
}

/* Initial links of the clustered solver: every cluster's two children,
   both ways. */
static radinterp_result radinterp__initial_cluster_links(radinterp_solution *s, radinterp__run *run)
{
    radinterp__linker L;
    radinterp_result res = RADINTERP_OK;
    uint32_t c;
    if (radinterp__build_clusters(s) != 0) return RADINTERP_ERROR_OUT_OF_MEMORY;
    if (!radinterp__linker_init(s, &L)) { radinterp__linker_free(s, &L); return RADINTERP_ERROR_OUT_OF_MEMORY; }
    for (c = 0; c < s->cluster_count && res == RADINTERP_OK; c++) {
        const radinterp__cluster *cl = &s->clusters[c];
        uint32_t a = cl->child[0], b = cl->child[1];
        if (radinterp__solve_step(s, run, c)) { res = RADINTERP_ERROR_CANCELLED; break; }
        if (!radinterp__link_elements(s, &L, a, b) || !radinterp__link_elements(s, &L, b, a)) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    if (res == RADINTERP_OK) res = radinterp__finish_linking(s, run, &L, s->node_count, 0, NULL, 0);
    radinterp__linker_free(s, &L);
    return res;
}

/* A link's factor in its brightest channel: through no pane, and through panes. */
static double radinterp__link_ff_max(const radinterp__link *l)
{
    double t[3];
    t[0] = l->glass[0]; t[1] = l->glass[1]; t[2] = l->glass[2];
    return l->gff > 0.0f ? (double)l->ff + (double)l->gff * radinterp__max3(t) : (double)l->ff;
}

/* The sky's share of transport refinement: a leaf (made before this pass)
   over which the sky's irradiance varies by more than its tolerance (the
   window's light on a floor) is split, as a link to the sky would be; its
   ancestors' links deliver to the children. Returns the leaves split, or
   -1 when out of memory. */
static int radinterp__refine_sky(radinterp_solution *s, uint32_t nodes_before)
{
    uint32_t i;
    int split = 0;
    for (i = 0; i < nodes_before; i++) {
        const radinterp__node *nd = &s->nodes[i];
        if (nd->child != RADINTERP__NONE || !((double)nd->sky_spread > radinterp__tolerance(s, nd->level)) ||
            !radinterp__can_split(s, nd))
            continue;
        if (radinterp__node_split(s, i) != 0) return -1;
        split++;
    }
    return split;
}

/* What refinement reads of a node as a link's source, one entry a node,
   made at the start of each refinement pass: the pass reads it for every
   link (millions), twice, and the node with its four children lies on five
   or six cache lines where this entry takes 16 bytes. The same values as
   the nodes give: bmax the largest channel of B, near the spread of its
   children (radinterp__source_spread), deep the spread of its leaves. */
typedef struct radinterp__source_sum {
    double near;
    float bmax, deep;
} radinterp__source_sum;

#define RADINTERP__SUM_BLOCK 4096   /* nodes a job */

typedef struct radinterp__sums_ctx {
    const radinterp_solution *s;
    radinterp__source_sum *ss;
} radinterp__sums_ctx;

static void radinterp__sums_job(void *ctx_, uint32_t job)
{
    const radinterp__sums_ctx *c = (const radinterp__sums_ctx *)ctx_;
    const radinterp_solution *s = c->s;
    uint32_t i, end = s->node_count - job * RADINTERP__SUM_BLOCK < RADINTERP__SUM_BLOCK ? s->node_count
                                                                                       : (job + 1) * RADINTERP__SUM_BLOCK;
    for (i = job * RADINTERP__SUM_BLOCK; i < end; i++) {
        const float *b = s->nodes[i].b;
        c->ss[i].near = radinterp__source_spread(s, i);
        c->ss[i].bmax = radinterp__maxf(b[0], radinterp__maxf(b[1], b[2]));
        c->ss[i].deep = s->nodes[i].spread;
    }
}

/* Returns NULL when out of memory. */
static radinterp__source_sum *radinterp__source_sums(const radinterp_solution *s, const radinterp__run *run)
{
    radinterp__sums_ctx c;
    c.s = s;
    c.ss = (radinterp__source_sum *)radinterp__alloc_array(&s->allocator, s->node_count ? s->node_count : 1, sizeof *c.ss);
    if (!c.ss) return NULL;
    radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__sums_job, &c,
                        (s->node_count + RADINTERP__SUM_BLOCK - 1) / RADINTERP__SUM_BLOCK);
    return c.ss;
}

/* How far a link's source mean may be from the part of the source its
   receiver sees (ss: radinterp__source_sums): the spread of the source's
   children when the receiver sees all of it, of its leaves when part of it is hidden (the link is
   partly blocked, or some receiver point sees none of it): then the
   receiver may see only the darkest or the brightest leaves, and the
   children of a source that straddles a wall (a floor running under the
   partition between a lit room and a dark one) each straddle it too, so
   their means are alike. A source node made in the pass has no leaves'
   spread yet (0), as it has no children's. */
static double radinterp__link_source_spread(const radinterp__source_sum *ss, const radinterp__link *l)
{
    double near = ss[l->source].near, deep = (double)ss[l->source].deep;
    return (l->flags & RADINTERP__LINK_PARTLY) && deep > near ? deep : near;
}

/* A link's estimated transport error (4.4.1): B_src (largest channel)
   times the spread of its point factors over the receiver. */
static double radinterp__link_error(const radinterp__source_sum *ss, const radinterp__link *l)
{
    return (double)ss[l->source].bmax * (double)l->dff;
}

/* What a link's source mean may misjudge (4.4.1's transport error on the
   source's side): the spread of the source's children times the link's
   factor. Visibility picks a part of the source: a floor element under a
   wall between a lit room and a dark one is seen from the dark room by its
   dark part alone, and the link would carry its lit mean there. */
static double radinterp__source_error(const radinterp__source_sum *ss, const radinterp__link *l)
{
    return radinterp__link_source_spread(ss, l) * radinterp__link_ff_max(l);
}

static int radinterp__cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The receiver's error budget: the links one node gathers may together make
   RADINTERP_RECEIVER_BUDGET times its tolerance, not each of them its
   tolerance. Their errors do not cancel: the links that bring a room's
   light through one door share its geometry, so each deposits its light
   evenly over a receiver that sees the door from near and from far, and
   hundreds of links each within the tolerance left the far corner of a
   lampless room 30-90% too bright (its whole surface 2x too bright there:
   what came in was right in sum, spread too evenly). This marks, for each
   node, its links to be split, largest error first, so that the rest fit
   the budget. The bound B dff is a worst case (max - min over the
   receiver), far from the error the link's mean makes at most points, so
   the budget is several tolerances, not one (one tolerance split the
   office's links 30-fold). A link's share of the budget is both of its
   errors, the transport error across the receiver and the source's
   variation (radinterp__source_error): hundreds of links from sources that
   straddle a wall between a lit room and a lampless one, each carrying a
   little of the lit side's light into the dark room, add up as the links
   through a door do. The source's variation counts in units of its own
   tolerance (radinterp__source_tolerance, scaled to the receiver's: its
   floor is lower, as splitting a source adds no leaves). A link marked for
   the budget is split on the side whose error, so counted, is the larger. */
#define RADINTERP__SPLIT 1          /* budget marks: split the larger element */
#define RADINTERP__SPLIT_SOURCE 2   /* split the source: its variation is most of the error */

static double radinterp__budget_error(const radinterp__source_sum *ss, const radinterp__link *l, double source_scale)
{
    return radinterp__link_error(ss, l) + source_scale * radinterp__source_error(ss, l);
}

static void radinterp__spread_budget(const radinterp_solution *s, const radinterp__source_sum *ss, const radinterp__node *nd,
                                     double *err, unsigned char *mark)
{
    double tol = radinterp__tolerance(s, nd->dim), budget = RADINTERP_RECEIVER_BUDGET * tol, sum = 0.0, limit = DBL_MAX;
    double stol = radinterp__source_tolerance(s, nd->dim);
    double source_scale = stol > 0.0 ? tol / stol : 1.0;   /* a floor flushed to 0 (emission near FLT_MIN) */
    uint32_t j;
    for (j = 0; j < nd->link_count; j++)
        sum += err[j] = radinterp__budget_error(ss, &s->links[nd->first_link + j], source_scale);
    if (sum <= budget) return;
    qsort(err, nd->link_count, sizeof(double), radinterp__cmp_double);
    for (sum = 0.0, j = 0; j < nd->link_count; j++)   /* from the smallest: the first that no longer fits */
        if ((sum += err[j]) > budget) { limit = err[j]; break; }
    for (j = 0; j < nd->link_count; j++) {
        const radinterp__link *l = &s->links[nd->first_link + j];
        if (radinterp__budget_error(ss, l, source_scale) < limit) continue;
        mark[j] = source_scale * radinterp__source_error(ss, l) > radinterp__link_error(ss, l) ? RADINTERP__SPLIT_SOURCE
                                                                                            : RADINTERP__SPLIT;
    }
}

/* Each link's budget mark (above; 0 when the budget keeps it), one job per
   RADINTERP__MARK_JOBS-th of the receivers (blocks of RADINTERP__MARK_BLOCK
   taken in turn, so each job gets its share of the busy ones), each with
   its own scratch for the sort: a node writes only its own links' marks,
   so the marks do not depend on the jobs. */
#define RADINTERP__MARK_JOBS 32
#define RADINTERP__MARK_BLOCK 256

typedef struct radinterp__marks_ctx {
    const radinterp_solution *s;
    const radinterp__source_sum *ss;
    unsigned char *mark;
    double *err;                 /* RADINTERP__MARK_JOBS scratch arrays of `most` */
    uint32_t most;               /* the most links one node gathers */
} radinterp__marks_ctx;

static void radinterp__marks_job(void *ctx_, uint32_t job)
{
    const radinterp__marks_ctx *c = (const radinterp__marks_ctx *)ctx_;
    const radinterp_solution *s = c->s;
    uint32_t b, i;
    for (b = job * RADINTERP__MARK_BLOCK; b < s->node_count; b += RADINTERP__MARK_JOBS * RADINTERP__MARK_BLOCK)
        for (i = b; i < s->node_count && i < b + RADINTERP__MARK_BLOCK; i++)
            if (s->nodes[i].link_count)
                radinterp__spread_budget(s, c->ss, &s->nodes[i], c->err + (size_t)job * c->most, c->mark + s->nodes[i].first_link);
}

/* Returns NULL when out of memory. */
static unsigned char *radinterp__budget_marks(const radinterp_solution *s, const radinterp__source_sum *ss,
                                              const radinterp__run *run)
{
    radinterp__marks_ctx c;
    uint32_t i;
    c.s = s;
    c.ss = ss;
    c.most = 1;
    c.mark = (unsigned char *)radinterp__alloc_array(&s->allocator, s->link_count ? s->link_count : 1, 1);
    if (!c.mark) return NULL;
    memset(c.mark, 0, s->link_count);
    for (i = 0; i < s->node_count; i++) c.most = s->nodes[i].link_count > c.most ? s->nodes[i].link_count : c.most;
    c.err = (double *)radinterp__alloc_array(&s->allocator, (size_t)RADINTERP__MARK_JOBS * c.most, sizeof(double));
    if (!c.err) { radinterp__free(&s->allocator, c.mark); return NULL; }
    radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__marks_job, &c,
                        RADINTERP__MARK_JOBS);
    radinterp__free(&s->allocator, c.err);
    return c.mark;
}

/* What refinement does with a link (below), from its budget mark. */
#define RADINTERP__REFINE_KEEP 0
#define RADINTERP__REFINE_RECEIVER 1   /* to the receiver's children */
#define RADINTERP__REFINE_SOURCE 2     /* to the source's children */
#define RADINTERP__REFINE_FINAL 3      /* kept, marked final: neither end may be split */

static unsigned char radinterp__refine_decision(const radinterp_solution *s, const radinterp__source_sum *ss,
                                                const radinterp__link *l, unsigned char mark)
{
    double tol = radinterp__tolerance(s, s->nodes[l->receiver].dim);
    if (l->flags & RADINTERP__LINK_FINAL) return RADINTERP__REFINE_KEEP;
    if (radinterp__divided_below(s, &s->nodes[l->receiver])) return RADINTERP__REFINE_RECEIVER;
    if (mark == RADINTERP__SPLIT_SOURCE) return RADINTERP__REFINE_SOURCE;
    if (radinterp__link_error(ss, l) > tol || mark) {
        const radinterp__node *r = &s->nodes[l->receiver], *src = &s->nodes[l->source];
        int rs = radinterp__can_split(s, r), src_splits = radinterp__can_split(s, src);
        if (rs && (r->area >= src->area || !src_splits)) return RADINTERP__REFINE_RECEIVER;
        return src_splits ? RADINTERP__REFINE_SOURCE : RADINTERP__REFINE_FINAL;
    }
    /* the source is not uniform (its children differ): the link carries
       its mean where the receiver may see a brighter or darker part, so it
       goes to the children */
    return radinterp__source_error(ss, l) > radinterp__source_tolerance(s, s->nodes[l->receiver].dim)
               ? RADINTERP__REFINE_SOURCE : RADINTERP__REFINE_KEEP;
}

/* Replaces each link's budget mark by its decision, RADINTERP__REFINE_BLOCK
   links a job. */
#define RADINTERP__REFINE_BLOCK 4096

typedef struct radinterp__decide_ctx {
    const radinterp_solution *s;
    const radinterp__source_sum *ss;
    unsigned char *mark;
} radinterp__decide_ctx;

static void radinterp__decide_job(void *ctx_, uint32_t job)
{
    const radinterp__decide_ctx *c = (const radinterp__decide_ctx *)ctx_;
    uint32_t i, end = c->s->link_count - job * RADINTERP__REFINE_BLOCK < RADINTERP__REFINE_BLOCK
                          ? c->s->link_count : (job + 1) * RADINTERP__REFINE_BLOCK;
    for (i = job * RADINTERP__REFINE_BLOCK; i < end; i++)
        c->mark[i] = radinterp__refine_decision(c->s, c->ss, &c->s->links[i], c->mark[i]);
}

/* Transport-based refinement (4.4.1): a link whose estimated transport
   error B_src * (max - min point factor) exceeds eps, or is among the
   largest of its receiver's that overrun the receiver's budget (above), is
   replaced by four links to the children of its larger element (the
   other one when the larger may not be split; a link that can go no
   further is final), or of its source when the budget marked it for the
   source's variation. A link
   whose source has children that differ by more than its source tolerance
   (radinterp__source_tolerance) / F is replaced by links from those children. A cluster link that could carry more than eps
   is split as radinterp__split_clink says.
   The decisions are made first, in parallel (radinterp__decide_job), and
   the splits applied after, in link order: what decides a link (its
   factors, its nodes' radiosities, levels and areas, the spread of its
   source's children, its budget mark) is not changed by the pass's splits
   (a node split in the pass gets children that copy its radiosity, so its
   spread stays 0, as it was without children), so the result is the one a
   link-by-link pass would give. The kept links are packed at the front of
   the link array, in their order (radinterp__install_links merges the new
   ones among them).
   Returns the number of links split, or -1 when out of memory or cancelled
   (*res). */
static int radinterp__refine(radinterp_solution *s, radinterp__run *run, radinterp_result *res)
{
    radinterp__buf ckeep;
    radinterp__linker L;
    uint32_t i, split = 0, kept = 0, nodes_before = s->node_count;
    radinterp__source_sum *ss = radinterp__source_sums(s, run);
    unsigned char *mark = ss ? radinterp__budget_marks(s, ss, run) : NULL;
    memset(&ckeep, 0, sizeof ckeep);
    ckeep.item = sizeof(radinterp__clink);
    *res = RADINTERP_OK;
    if (!radinterp__linker_init(s, &L) || !mark) *res = RADINTERP_ERROR_OUT_OF_MEMORY;
    else {
        radinterp__decide_ctx dc;
        dc.s = s;
        dc.ss = ss;
        dc.mark = mark;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__decide_job, &dc,
                            (s->link_count + RADINTERP__REFINE_BLOCK - 1) / RADINTERP__REFINE_BLOCK);
    }
    radinterp__free(&s->allocator, ss);   /* the decisions are made: the splits below change the nodes */
    for (i = 0; i < s->link_count && *res == RADINTERP_OK; i++) {
        radinterp__link l = s->links[i];
        if (radinterp__solve_step(s, run, i)) { *res = RADINTERP_ERROR_CANCELLED; break; }
        if (mark[i] == RADINTERP__REFINE_KEEP || mark[i] == RADINTERP__REFINE_FINAL) {
            if (mark[i] == RADINTERP__REFINE_FINAL) l.flags |= RADINTERP__LINK_FINAL;
            s->links[kept++] = l;
            continue;
        }
        if (!radinterp__split_link(s, &L, &l, mark[i] == RADINTERP__REFINE_SOURCE)) *res = RADINTERP_ERROR_OUT_OF_MEMORY;
        split++;
    }
    if (s->has_sky && *res == RADINTERP_OK) {
        int more = radinterp__refine_sky(s, nodes_before);
        if (more < 0) *res = RADINTERP_ERROR_OUT_OF_MEMORY;
        else split += (uint32_t)more;
    }
    for (i = 0; i < s->clink_count && *res == RADINTERP_OK; i++) {
        radinterp__clink l = s->clinks[i];
        if (radinterp__solve_step(s, run, i)) { *res = RADINTERP_ERROR_CANCELLED; break; }
        if (!radinterp__clink_too_coarse(s, l.receiver, l.source)) {
            radinterp__clink *slot = (radinterp__clink *)radinterp__buf_push(&s->allocator, &ckeep);
            if (!slot) *res = RADINTERP_ERROR_OUT_OF_MEMORY;
            else *slot = l;
            continue;
        }
        if (!radinterp__split_clink(s, &L, l.receiver, l.source)) *res = RADINTERP_ERROR_OUT_OF_MEMORY;
        split++;
    }
    if (*res == RADINTERP_OK && split)
        *res = radinterp__finish_linking(s, run, &L, nodes_before, kept,
                                         (const radinterp__clink *)ckeep.data, (uint32_t)ckeep.count);
    radinterp__linker_free(s, &L);
    radinterp__free(&s->allocator, mark);
    radinterp__free(&s->allocator, ckeep.data);
    return *res == RADINTERP_OK ? (int)split : -1;
}

/* Initial links without clusters (4.1): one per ordered pair of patches
   that face each other (part of each lies in front of the other's plane),
   with the blockers from shaft culling. Sources that can never shine
   (black, not emitting) get none. */
static radinterp_result radinterp__initial_links(radinterp_solution *s, radinterp__run *run)
{
    radinterp__linker L;
    radinterp_result res = RADINTERP_OK;
    double tol = s->epsilon * s->diag;
    uint32_t i, j;
    if (!radinterp__linker_init(s, &L)) { radinterp__linker_free(s, &L); return RADINTERP_ERROR_OUT_OF_MEMORY; }
    for (i = 0; i < s->patch_count && res == RADINTERP_OK; i++) {
        const radinterp__patch *pr = &s->patches[i];
        if (!pr->count) continue;
        if (radinterp__solve_tick(s, run)) { res = RADINTERP_ERROR_CANCELLED; break; }
        for (j = 0; j < s->patch_count && res == RADINTERP_OK; j++) {
            const radinterp__patch *ps = &s->patches[j];
            if (j == i || !ps->count) continue;
            if (radinterp__patch_front(pr, ps->n, ps->d) <= tol || radinterp__patch_front(ps, pr->n, pr->d) <= tol)
                continue;
            if (!radinterp__link_elements(s, &L, pr->root, ps->root)) res = RADINTERP_ERROR_OUT_OF_MEMORY;
        }
    }
    if (res == RADINTERP_OK) res = radinterp__finish_linking(s, run, &L, s->node_count, 0, NULL, 0);
    radinterp__linker_free(s, &L);
    return res;
}

/* ---- gather and push-pull (4.3) ---------------------------------------- */
typedef struct radinterp__iter_ctx {
    radinterp_solution *s;
    uint32_t per_job;
    double floor;            /* radiosities below it count as this for relative change */
    double *patch_change;    /* largest relative change per patch */
} radinterp__iter_ctx;

/* H = sum over the node's links of F * B_src, and over its cluster links of
   the irradiance they carry times the cosine at the node, from last
   iteration's B. */
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
            if (lk->gff > 0.0f) {   /* F = ff + gff * glass per channel: part of the source is seen through panes */
                int k;
                for (k = 0; k < 3; k++) h[k] += ((double)lk->ff + (double)lk->gff * lk->glass[k]) * b[k];
                continue;
            }
            h[0] += (double)lk->ff * b[0];
            h[1] += (double)lk->ff * b[1];
            h[2] += (double)lk->ff * b[2];
        }
        for (l = nd->first_clink; l < nd->first_clink + nd->clink_count; l++) {
            /* an open surface's irradiance; h is a mean over the whole node */
            double e[3], c = radinterp__facing(s->patches[nd->patch].n, s->clinks[l].dir) * nd->open;
            radinterp__clink_irradiance(s, &s->clinks[l], e);
            h[0] += c * e[0];
            h[1] += c * e[1];
            h[2] += c * e[2];
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
   the open fraction, and averages weigh children by their open areas.
   b_lo / b_hi take in the least and largest radiosity (per channel) of the
   open leaves below, from which each node keeps its spread. */
static void radinterp__push_pull(radinterp_solution *s, uint32_t index, const double *down, double floor,
                                 double *change, double *b_out, double *hmin, double *b_lo, double *b_hi)
{
    radinterp__node *nd = &s->nodes[index];
    const radinterp__patch *pt = &s->patches[nd->patch];
    double h[3], b[3], open = nd->open, level, dim, spread = 0.0;
    int k;
    for (k = 0; k < 3; k++) h[k] = down[k] + (open > 0.0 ? nd->h[k] / open : 0.0);
    if (nd->child == RADINTERP__NONE) {
        if (s->has_sky && open > 0.0)   /* the sky shines on the leaves, a constant source as emission is */
            for (k = 0; k < 3; k++) h[k] += nd->sky[k] / open;
        for (k = 0; k < 3; k++) {
            double rel;
            b[k] = pt->e[k] + pt->rho[k] * h[k];
            rel = open > 0.0 ? fabs(b[k] - nd->b[k]) / (b[k] > floor ? b[k] : floor) : 0.0;
            if (rel > *change) *change = rel;
        }
        level = h[0] > h[1] ? (h[0] > h[2] ? h[0] : h[2]) : (h[1] > h[2] ? h[1] : h[2]);
        dim = open > 0.0 && level > 0.0 ? level : 0.0;
        if (dim > 0.0 && (*hmin == 0.0 || dim < *hmin)) *hmin = dim;
        for (k = 0; k < 3 && open > 0.0; k++) {
            b_lo[k] = b[k] < b_lo[k] ? b[k] : b_lo[k];
            b_hi[k] = b[k] > b_hi[k] ? b[k] : b_hi[k];
        }
    } else {
        double area = 0.0, cb[3], lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
        uint32_t c;
        b[0] = b[1] = b[2] = 0.0;
        level = dim = 0.0;
        for (c = 0; c < 4; c++) {
            uint32_t ch = s->nodes[index].child + c;
            double a = (double)s->nodes[ch].area * s->nodes[ch].open, cd;
            radinterp__push_pull(s, ch, h, floor, change, cb, hmin, lo, hi);
            for (k = 0; k < 3; k++) b[k] += a * cb[k];
            level += a * s->nodes[ch].level;
            area += a;
            cd = s->nodes[ch].dim;
            if (cd > 0.0 && (dim == 0.0 || cd < dim)) dim = cd;
        }
        nd = &s->nodes[index];
        for (k = 0; k < 3; k++) b[k] = area > 0.0 ? b[k] / area : pt->e[k];
        level = area > 0.0 ? level / area : 0.0;
        for (k = 0; k < 3; k++) {
            if (hi[k] - lo[k] > spread) spread = hi[k] - lo[k];
            b_lo[k] = lo[k] < b_lo[k] ? lo[k] : b_lo[k];
            b_hi[k] = hi[k] > b_hi[k] ? hi[k] : b_hi[k];
        }
    }
    nd->spread = (float)spread;
    for (k = 0; k < 3; k++) { nd->b[k] = (float)b[k]; b_out[k] = b[k]; }
    nd->level = (float)level;
    nd->dim = (float)dim;
}

static void radinterp__push_pull_job(void *ctx_, uint32_t index)
{
    radinterp__iter_ctx *ctx = (radinterp__iter_ctx *)ctx_;
    radinterp_solution *s = ctx->s;
    double down[3], b[3], change = 0.0, hmin = 0.0, lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    radinterp__cluster_down(s, index, down);
    if (s->patches[index].count) radinterp__push_pull(s, s->patches[index].root, down, ctx->floor, &change, b, &hmin, lo, hi);
    ctx->patch_change[index] = change;
    s->patch_hmin[index] = hmin;
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
    if (radinterp__sky_scale(s) > emax) emax = radinterp__sky_scale(s);
    ctx.floor = emax > 0.0 ? 1e-4 * emax : 1e-30;
    ctx.patch_change = (double *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(double));
    s->patch_hmin = (double *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(double));
    if (!ctx.patch_change || !s->patch_hmin) {
        radinterp__free(&s->allocator, ctx.patch_change);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    memset(s->patch_hmin, 0, (size_t)s->patch_count * sizeof(double));
    radinterp__pull_clusters(s);
    for (it = 0; it < s->max_iterations; it++) {
        double change = 0.0;
        run->iteration = it;
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__gather_job, &ctx,
                            (s->node_count + ctx.per_job - 1) / ctx.per_job);
        if (radinterp__solve_tick(s, run)) { res = RADINTERP_ERROR_CANCELLED; break; }
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__cluster_gather_job, s,
                            (s->cluster_count + 63) / 64);
        radinterp__push_clusters(s);
        if (radinterp__solve_tick(s, run)) { res = RADINTERP_ERROR_CANCELLED; break; }
        radinterp__run_jobs(run->desc->parallel_for, run->desc->parallel_user, radinterp__push_pull_job, &ctx,
                            s->patch_count);
        radinterp__pull_clusters(s);
        s->levels_known = 1;
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
#define RADINTERP__SOLID_CACHE 16        /* convex solids a query remembers its verdict for (below) */
#define RADINTERP__HINTS 4               /* blockers that hid sources whole, tried first (radinterp__hints_stage) */
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
    double child_tol;     /* a source's children are taken when its mean may be off by more than this */
    uint32_t triangulated; /* sources partly hidden: shadow union or triangulation (statistics) */
    int failed;           /* out of memory in a triangulation */
    double mem[RADINTERP__BP_BYTES / sizeof(double)];
    double shadow[RADINTERP__BP_MAX_SURVIVORS][RADINTERP__POLY_MAX][2];   /* projected blockers, 2D */
    int shadow_count[RADINTERP__BP_MAX_SURVIVORS];
    unsigned char flags[2048];
    radinterp__piece piece[RADINTERP__PIECES];
    radinterp__piece staged[RADINTERP__BP_MAX_SURVIVORS];   /* the shadows before their union */
    unsigned char order[RADINTERP__BP_MAX_SURVIVORS];       /* the order they enter it */
    uint32_t staged_at[RADINTERP__BP_MAX_SURVIVORS];        /* their blockers' positions in the list */
    double staged_area[RADINTERP__BP_MAX_SURVIVORS];        /* their areas (radinterp__order_staged's key) */
    uint32_t later[RADINTERP__BP_MAX_SURVIVORS];            /* faces turned away, staged as the union reaches them */
    uint32_t nlater;
    uint32_t hint[RADINTERP__HINTS];                        /* blockers that hid sources whole, latest first */
    int nhint;
    const uint32_t *blk;  /* the blockers of the link being summed (a leaf list or the link's own) */
    uint32_t nblk;
    uint32_t known_node;  /* a node whose unoccluded factor at p the ranking found already: */
    double known_full;    /* radinterp__query_source takes it from here */
    uint32_t solid_tag[RADINTERP__SOLID_CACHE];  /* solids whose back faces' verdict at pv is known */
    unsigned char solid_skip[RADINTERP__SOLID_CACHE];
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
    for (i = 0; i < na; i++) area += a[i][0] * a[radinterp__next(i, na)][1] - a[radinterp__next(i, na)][0] * a[i][1];
    if (area == 0.0) return 0;
    for (j = 0; j < nb; j++)
        for (i = 0; i < na; i++) {
            double o = radinterp__orient2d(a[i], a[radinterp__next(i, na)], b[j]);
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
    for (i = 0; i < n; i++) a += v[i][0] * v[radinterp__next(i, n)][1] - v[radinterp__next(i, n)][0] * v[i][1];
    return a;
}

/* One source seen from the query point: what both visibility methods share.
   The source Sr is the real one (visibility is that of the real source, so
   moving it opens no gap at a contact); form factors are taken on the
   moved one, through fr_ff. */
typedef struct radinterp__bp {
    const radinterp__link *lk;
    const uint32_t *blk;                  /* its blockers */
    uint32_t nblk;
    const double *pv;                     /* visibility is judged from here */
    const double (*Sc_pushed)[3];         /* the moved, clipped source */
    double full;                          /* its unoccluded factor */
    double push;                          /* Sr = Sc + push * ns */
    double Sr[RADINTERP__POLY_MAX][3];    /* the real source */
    double sc2[RADINTERP__POLY_MAX][2];   /* its corners in the frame */
    int nc;
    radinterp__frame fr, fr_ff;           /* frame on the real plane, and the same on the moved plane */
    double plane_n[RADINTERP__POLY_MAX + 1][3], plane_d[RADINTERP__POLY_MAX + 1];
    int np;                               /* the pyramid from pv over Sr: x inside when n . x >= d */
    double ns[3], ds, hp;                 /* source normal, real plane, height of pv above it */
    double tol;                           /* 2D distances below it are rounding: 1e-12 of the source's size */
    double whole;                         /* the source's area in the frame */
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
        radinterp__d3_sub(bp->Sr[radinterp__next(k, nc)], pv, b);
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
    bp->blk = q->blk;
    bp->nblk = q->nblk;
    bp->nc = nc;
    bp->pv = q->pv;
    bp->Sc_pushed = Sc;
    if (radinterp__d3_dot(ns, q->p) - ds <= 0.0) { push = 0.0; ds = ds_pushed; } /* p within push of the plane */
    if (radinterp__d3_dot(ns, bp->pv) - ds <= 0.0) bp->pv = q->p; /* nudged behind the source: judge from p */
    bp->push = push;
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
    bp->whole = fabs(radinterp__area2((const double (*)[2])bp->sc2, nc));
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

/* Is a shadow (2D, in the frame) too small to matter? Below 1e-12 of the
   square of pv's height above the source it subtends less than 1e-12 / pi.
   Judged on the source, not by the blocker's part in 3D, which is tiny
   when the blocker stands right next to pv yet may hide the whole source.
   area: |radinterp__area2| of the shadow. */
static int radinterp__shadow_negligible(const radinterp__bp *bp, double area)
{
    return area <= 2e-12 * bp->hp * bp->hp;
}

/* Does the bounding sphere of patch pb lie inside the plane n . x >= d so
   far (sd = n . centre - d) that every corner of pb, as the floats it
   keeps, tests inside it (n . x >= d)? The radius is taken from the
   corners before their rounding to float, which moves each by up to 2^-24
   of its coordinates (1.04e-7 of |centre|_1 + radius in length); slack
   1e-6 of |centre|_1 + radius + |d| covers that and the rounding of the
   dot products many times over. size: |centre|_1 + radius
   (radinterp__sphere_size), the same for every plane. */
static int radinterp__sphere_inside(const radinterp__patch *pb, double size, double sd, double d)
{
    return sd > pb->radius + 1e-6 * (size + fabs(d));
}

static double radinterp__sphere_size(const radinterp__patch *pb)
{
    return fabs(pb->centre[0]) + fabs(pb->centre[1]) + fabs(pb->centre[2]) + pb->radius;
}

/* Which planes of bp's pyramid cut patch pb: bit j of *cut for plane j,
   pb's corners into poly. Returns the corner count, 0 when pb casts no
   shadow (its bounding sphere or every corner outside a plane, or seen
   edge-on from pv). Each corner is tested against each plane once: a plane
   that has every corner outside culls the blocker, one that has every
   corner inside needs no clipping (the common cases), the others clip. A
   plane with the bounding sphere well inside (radinterp__sphere_inside)
   has every corner inside without testing them: on building_1k most
   planes of most blockers that cast a shadow. */
static int radinterp__pyramid_cut(const radinterp_solution *s, const radinterp__bp *bp, const radinterp__patch *pb,
                                  double (*poly)[3], uint32_t *cut)
{
    double sd[RADINTERP__POLY_MAX + 1], size;
    int m, j, i;
    *cut = 0;
    for (j = 0; j < bp->np; j++) { /* bounding sphere first */
        sd[j] = radinterp__d3_dot(bp->plane_n[j], pb->centre) - bp->plane_d[j];
        if (sd[j] < -pb->radius) return 0;
    }
    if (fabs(radinterp__d3_dot(pb->n, bp->pv) - pb->d) <= s->epsilon * s->diag) return 0; /* seen edge-on */
    m = radinterp__patch_poly(pb, poly);
    size = radinterp__sphere_size(pb);
    for (j = 0; j < bp->np; j++) {
        int inside = 0;
        if (radinterp__sphere_inside(pb, size, sd[j], bp->plane_d[j])) continue;
        for (i = 0; i < m; i++) inside += radinterp__d3_dot(bp->plane_n[j], poly[i]) >= bp->plane_d[j];
        if (inside == 0) return 0;
        if (inside < m) *cut |= 1u << j;
    }
    return m;
}

/* The shadow of patch pb on the source: its part inside the pyramid,
   projected from pv. Returns the corner count, 0 when it casts none. */
static int radinterp__bp_shadow(const radinterp_solution *s, const radinterp__bp *bp, const radinterp__patch *pb,
                                double (*shadow)[2])
{
    double poly[RADINTERP__POLY_MAX][3], tmp[RADINTERP__POLY_MAX][3];
    uint32_t cut;
    int m, j;
    if ((m = radinterp__pyramid_cut(s, bp, pb, poly, &cut)) == 0) return 0;
    for (j = 0; j < bp->np && m >= 3; j++) {
        if (!((cut >> j) & 1u)) continue;
        m = radinterp__clip_poly((const double (*)[3])poly, m, bp->plane_n[j], bp->plane_d[j], tmp);
        radinterp__copy_poly((const double (*)[3])tmp, m, poly);
    }
    if (m < 3) return 0;
    radinterp__bp_project(bp, (const double (*)[3])poly, m, shadow);
    return radinterp__shadow_negligible(bp, fabs(radinterp__area2((const double (*)[2])shadow, m))) ? 0 : m;
}

/* The shadows of the link's blockers into q->shadow (at most
   RADINTERP__BP_MAX_SURVIVORS; *overflow is set when more cast one), their
   blockers into survivors. Returns the count, or -1 when one shadow alone
   covers the whole source. */
static int radinterp__bp_collect(radinterp__query *q, const radinterp__bp *bp, uint32_t *survivors, int *overflow)
{
    const radinterp_solution *s = q->s;
    uint32_t i;
    int count = 0;
    *overflow = 0;
    for (i = 0; i < bp->nblk; i++) {
        uint32_t b = bp->blk[i];
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

/* ---- convex solids: back faces whose shadows add nothing ----------------- */
/* Most blockers are faces of convex objects: boxes standing on the floor, a
   lamp shade. Seen from a point outside a convex solid, a segment that
   leaves the solid through a face turned away from the point (a back face)
   has entered it through a face turned toward the point, so the back
   face's shadow lies inside the union of the front faces' shadows and
   changes nothing (up to its outline, which has no area). Back faces are
   half of a query's blocker tests and most of the work of the union, so
   they are skipped wherever this holds.
   A solid is a set of patches joined edge to edge (an edge shared by
   exactly two of them, run in opposite directions) lying on the boundary
   of the convex hull of their corners, fronts outward; on each facet of
   the hull they cover, they tile it (no two overlap). Facets of the hull
   that its patches do not wholly cover are holes (the open bottom of a box
   standing on the floor, the ends of a tube): a segment may enter through
   one, so the rule needs the point on the inner side of every hole's plane
   (or on it: a segment from there cannot cross it) as well as in front of
   some face's plane (outside the solid). A face whose plane passes less
   than epsilon * diag behind the point is left out as seen edge-on
   (radinterp__bp_shadow_piece), so it must not be an entrance either: no
   face's plane may pass that close behind the point (a point just beside
   the corner of a box standing on the floor, where a mesh vertex lies,
   would otherwise see through the box). Solids are found once, at solve
   time. The triangulation method does not use them, so the test comparing
   the two methods checks this rule as well.
   A hole may be plugged: wholly covered by one patch of another object in
   its plane (a leg's open top under the table top, a shelf board's open
   back against the wall). A segment entering through it crosses the plug,
   whose shadow is in the union whichever way it faces: taken as a face
   turned toward the point, or in the second pass, or left out as a back
   face of a solid of its own, whose front faces then cover it (each step
   of that argument moves along the segment toward the point, so it ends).
   So a point outside a plugged hole's plane is fine, unless the plug is
   seen edge-on (it would then be left out). */
#define RADINTERP__SOLID_VERTS 32    /* larger groups of patches are not examined */
#define RADINTERP__SOLID_PLANES 32   /* hull facets of a solid at most */

typedef struct radinterp__solid {
    uint32_t first_plane;            /* into solution.solid_planes */
    uint32_t faces, holes;           /* hull facets covered by the solid's patches, and the others (stored) */
    uint32_t first_member, members;  /* into solution.solid_members */
} radinterp__solid;

typedef struct radinterp__edge_rec {
    float key[6];                    /* the edge's ends, the lexicographically smaller first */
    uint32_t patch, forward;         /* forward: the patch runs from key[0..2] to key[3..5] */
    uint32_t corner;                 /* the edge runs from this corner of the patch to the next */
} radinterp__edge_rec;

static int radinterp__edge_cmp(const void *a_, const void *b_)
{
    const float *a = ((const radinterp__edge_rec *)a_)->key, *b = ((const radinterp__edge_rec *)b_)->key;
    int k;
    for (k = 0; k < 6; k++)
        if (a[k] != b[k]) return a[k] < b[k] ? -1 : 1;
    return 0;
}

static int radinterp__point_less(const float *a, const float *b)
{
    return a[0] != b[0] ? a[0] < b[0] : (a[1] != b[1] ? a[1] < b[1] : a[2] < b[2]);
}

static uint32_t radinterp__uf_find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* Joins patches that share an edge used by exactly two patches in opposite
   directions (a leg standing under the edge of a table top makes that edge
   a three-patch edge, which joins nothing). Returns 0, or -1 when out of
   memory. */
/* The edges of the patches (of the triangles alone with only_triangles),
   sorted so that an edge's uses are neighbours; NULL when out of memory. */
static radinterp__edge_rec *radinterp__patch_edges(const radinterp_solution *s, int only_triangles, uint32_t *count)
{
    radinterp__edge_rec *e = (radinterp__edge_rec *)radinterp__alloc_array(&s->allocator, (size_t)s->patch_count * 4, sizeof *e);
    uint32_t i, k, n = 0;
    if (!e) return NULL;
    for (i = 0; i < s->patch_count; i++) {
        const radinterp__patch *pt = &s->patches[i];
        if (only_triangles && pt->count != 3) continue;
        for (k = 0; k < pt->count; k++) {
            const float *a = pt->v[k], *b = pt->v[(k + 1) % pt->count];
            e[n].forward = (uint32_t)radinterp__point_less(a, b);
            memcpy(e[n].key, e[n].forward ? a : b, 3 * sizeof(float));
            memcpy(e[n].key + 3, e[n].forward ? b : a, 3 * sizeof(float));
            e[n].patch = i;
            e[n].corner = k;
            n++;
        }
    }
    qsort(e, n, sizeof *e, radinterp__edge_cmp);
    *count = n;
    return e;
}

static int radinterp__join_patches(const radinterp_solution *s, uint32_t *parent)
{
    uint32_t i, n, run;
    radinterp__edge_rec *e = radinterp__patch_edges(s, 0, &n);
    if (!e) return -1;
    for (i = 0; i < n; i += run) {
        for (run = 1; i + run < n && radinterp__edge_cmp(&e[i], &e[i + run]) == 0; run++) {}
        if (run == 2 && e[i].forward != e[i + 1].forward && e[i].patch != e[i + 1].patch &&
            !s->patches[e[i].patch].glass && !s->patches[e[i + 1].patch].glass)   /* a pane is no solid's face */
            parent[radinterp__uf_find(parent, e[i].patch)] = radinterp__uf_find(parent, e[i + 1].patch);
    }
    radinterp__free(&s->allocator, e);
    return 0;
}

/* The convex hull of n 2D points (Andrew's monotone chain; p is sorted in
   place) into h (room for 2 n + 2), counter-clockwise, its first corner
   repeated at the end. Returns the corner count with that repetition. */
static int radinterp__hull_2d(double (*p)[2], int n, double (*h)[2])
{
    int i, j, m = 0, lower;
    for (i = 1; i < n; i++) /* insertion sort by x, then y */
        for (j = i; j > 0 && (p[j][0] < p[j - 1][0] || (p[j][0] == p[j - 1][0] && p[j][1] < p[j - 1][1])); j--) {
            double t0 = p[j][0], t1 = p[j][1];
            p[j][0] = p[j - 1][0]; p[j][1] = p[j - 1][1];
            p[j - 1][0] = t0; p[j - 1][1] = t1;
        }
    for (i = 0; i < n; i++) {
        while (m >= 2 && radinterp__orient2d_area(h[m - 2], h[m - 1], p[i]) <= 0.0) m--;
        h[m][0] = p[i][0]; h[m][1] = p[i][1]; m++;
    }
    for (i = n - 2, lower = m + 1; i >= 0; i--) {
        while (m >= lower && radinterp__orient2d_area(h[m - 2], h[m - 1], p[i]) <= 0.0) m--;
        h[m][0] = p[i][0]; h[m][1] = p[i][1]; m++;
    }
    return m;
}

/* Area of the convex hull of n 2D points. */
static double radinterp__hull_area(double (*p)[2], int n)
{
    double h[2 * RADINTERP__SOLID_VERTS + 2][2];
    int m = radinterp__hull_2d(p, n, h);
    return m > 3 ? 0.5 * fabs(radinterp__area2((const double (*)[2])h, m - 1)) : 0.0;
}

/* Signed distance of x from the plane (n, d). */
static double radinterp__plane_dist(const double *pl, const double *x) { return radinterp__d3_dot(pl, x) - pl[3]; }

/* The facet planes of the convex hull of v (every plane through three of
   them with all of them behind it, within tol), outward. Returns their
   count, or -1 when there are more than RADINTERP__SOLID_PLANES. */
static int radinterp__hull_planes(const double (*v)[3], int nv, double tol, double (*out)[4])
{
    int i, j, k, l, n = 0;
    for (i = 0; i < nv; i++)
        for (j = i + 1; j < nv; j++)
            for (k = j + 1; k < nv; k++) {
                double a[3], b[3], pl[4], len, lo = 0.0, hi = 0.0;
                radinterp__d3_sub(v[j], v[i], a);
                radinterp__d3_sub(v[k], v[i], b);
                radinterp__d3_cross(a, b, pl);
                len = radinterp__d3_len(pl);
                if (!(len > 1e-9 * (radinterp__d3_dot(a, a) + radinterp__d3_dot(b, b)))) continue; /* collinear */
                pl[0] /= len; pl[1] /= len; pl[2] /= len;
                pl[3] = radinterp__d3_dot(pl, v[i]);
                for (l = 0; l < nv; l++) {
                    double t = radinterp__plane_dist(pl, v[l]);
                    lo = t < lo ? t : lo;
                    hi = t > hi ? t : hi;
                }
                if (hi > tol && lo < -tol) continue;    /* corners on both sides */
                if (hi > tol) { pl[0] = -pl[0]; pl[1] = -pl[1]; pl[2] = -pl[2]; pl[3] = -pl[3]; }
                for (l = 0; l < n; l++)
                    if (radinterp__d3_dot(out[l], pl) > 1.0 - 1e-9 && fabs(out[l][3] - pl[3]) <= tol) break;
                if (l < n) continue;                    /* found before */
                if (n == RADINTERP__SOLID_PLANES) return -1;
                memcpy(out[n++], pl, sizeof pl);
            }
    return n;
}

/* Is every corner of the 2D polygon b within tol of the outside of some
   edge of the counter-clockwise polygon a? */
static int radinterp__outside_edge_2d(const double (*a)[2], int na, const double (*b)[2], int nb, double tol)
{
    int i, j;
    for (i = 0; i < na; i++) {
        const double *p0 = a[i], *p1 = a[radinterp__next(i, na)];
        double len = sqrt((p1[0] - p0[0]) * (p1[0] - p0[0]) + (p1[1] - p0[1]) * (p1[1] - p0[1]));
        for (j = 0; j < nb; j++)
            if (radinterp__orient2d_area(p0, p1, b[j]) > tol * len) break;
        if (j == nb) return 1;
    }
    return 0;
}

#define RADINTERP__SOLID_PATCHES 64  /* patches of one solid at most */

/* Does the solid's group of patches wholly cover the hull facet pl? Its
   patches there must not overlap (a separating edge for every pair: they
   are convex) and must add up to the area of the facet; as their corners
   are corners of the solid, they lie in the facet, so they then tile it. */
static int radinterp__facet_covered(const radinterp_solution *s, const uint32_t *members, uint32_t count,
                                    const double (*v)[3], int nv, const double *pl, double tol)
{
    double uv[RADINTERP__SOLID_VERTS][2], e1[3], e2[3], covered = 0.0, area;
    double on_uv[RADINTERP__SOLID_PATCHES][4][2];
    int on_count[RADINTERP__SOLID_PATCHES];
    int i, m = 0, non = 0, a;
    uint32_t j, k;
    radinterp__frame f;
    memset(&f, 0, sizeof f);
    e1[0] = fabs(pl[0]) < 0.6 ? 1.0 : 0.0; e1[1] = e1[0] == 0.0 ? 1.0 : 0.0; e1[2] = 0.0;
    radinterp__d3_cross(pl, e1, e2);
    radinterp__d3_cross(e2, pl, e1);
    for (k = 0; k < 3; k++) { f.e1[k] = e1[k] / radinterp__d3_len(e1); f.e2[k] = e2[k] / radinterp__d3_len(e2); }
    for (i = 0; i < nv; i++)
        if (fabs(radinterp__plane_dist(pl, v[i])) <= tol) radinterp__frame_to2d(&f, v[i], uv[m++]);
    area = radinterp__hull_area(uv, m);
    for (j = 0; j < count; j++) {
        const radinterp__patch *pt = &s->patches[members[j]];
        double x[3];
        int on = radinterp__d3_dot(pt->n, pl) > 0.0;
        for (k = 0; k < pt->count && on; k++) {
            radinterp__d3_from_f(pt->v[k], x);
            on = fabs(radinterp__plane_dist(pl, x)) <= tol;
        }
        if (!on) continue;
        covered += pt->area;
        for (k = 0; k < pt->count; k++) { /* counter-clockwise in the frame, as e1 x e2 = pl */
            radinterp__d3_from_f(pt->v[k], x);
            radinterp__frame_to2d(&f, x, on_uv[non][k]);
        }
        on_count[non] = (int)pt->count;
        for (a = 0; a < non; a++)
            if (!radinterp__outside_edge_2d((const double (*)[2])on_uv[a], on_count[a], (const double (*)[2])on_uv[non],
                                            on_count[non], tol) &&
                !radinterp__outside_edge_2d((const double (*)[2])on_uv[non], on_count[non], (const double (*)[2])on_uv[a],
                                            on_count[a], tol))
                return 0; /* two patches overlap */
        non++;
    }
    return area > 0.0 && covered >= (1.0 - 1e-6) * area;
}

/* Examines a group of joined patches: the planes of the holes of a convex
   solid into planes, and the counts of its covered facets (faces) and
   holes; returns 0 when the group is not one (too many corners or facets,
   a corner in front of a patch's plane, no facet covered). */
/* A patch outside the group that lies in the plane pl and contains every
   corner of v in that plane (the hole's facet), or NONE. */
static uint32_t radinterp__find_plug(const radinterp_solution *s, const uint32_t *members, uint32_t count,
                                     const double (*v)[3], int nv, const double *pl, double tol, radinterp__buf *near)
{
    float lo[3], hi[3];
    uint32_t i, j, k, m;
    int l;
    radinterp__box_empty(lo, hi);
    for (l = 0; l < nv; l++)   /* the hole's corners: a plug's box holds them all */
        if (fabs(radinterp__plane_dist(pl, v[l])) <= tol) {
            float x[3];
            for (k = 0; k < 3; k++) x[k] = (float)v[l][k];
            radinterp__box_grow(lo, hi, x, x);
        }
    if (!(lo[0] <= hi[0]) || radinterp__patches_near(s, &s->allocator, lo, hi, tol, near) != 0) return RADINTERP__NONE;
    for (m = 0; m < near->count; m++) {
        const radinterp__patch *pt = &s->patches[i = RADINTERP__U32(*near)[m]];
        int inside = 1;
        if (pt->count == 0 || fabs(fabs(radinterp__d3_dot(pt->n, pl)) - 1.0) > 1e-9) continue;
        for (k = 0; k < pt->count && inside; k++) {
            double x[3];
            radinterp__d3_from_f(pt->v[k], x);
            inside = fabs(radinterp__plane_dist(pl, x)) <= tol;
        }
        for (j = 0; j < count && inside; j++) inside = members[j] != i;
        for (l = 0; l < nv && inside; l++) {
            if (fabs(radinterp__plane_dist(pl, v[l])) > tol) continue; /* not a corner of the hole */
            for (k = 0; k < pt->count && inside; k++) { /* within tol inside every edge of the patch */
                double a[3], b[3], e[3], r[3], c[3];
                radinterp__d3_from_f(pt->v[k], a);
                radinterp__d3_from_f(pt->v[(k + 1) % pt->count], b);
                radinterp__d3_sub(b, a, e);
                radinterp__d3_sub(v[l], a, r);
                radinterp__d3_cross(e, r, c);
                inside = radinterp__d3_dot(c, pt->n) >= -tol * radinterp__d3_len(e);
            }
        }
        if (inside) return i;
    }
    return RADINTERP__NONE;
}

static int radinterp__solid_examine(const radinterp_solution *s, const uint32_t *members, uint32_t count,
                                    double (*planes)[4], uint32_t *plugs, uint32_t *faces, uint32_t *holes,
                                    radinterp__buf *near)
{
    double v[RADINTERP__SOLID_VERTS][3], hull[RADINTERP__SOLID_PLANES][4], tol = s->epsilon * s->diag;
    int nv = 0, nh, i, l;
    uint32_t j, k, nf = 0, no = 0;
    for (j = 0; j < count; j++) { /* distinct corners */
        const radinterp__patch *pt = &s->patches[members[j]];
        for (k = 0; k < pt->count; k++) {
            double x[3];
            radinterp__d3_from_f(pt->v[k], x);
            for (l = 0; l < nv; l++) if (x[0] == v[l][0] && x[1] == v[l][1] && x[2] == v[l][2]) break;
            if (l < nv) continue;
            if (nv == RADINTERP__SOLID_VERTS) return 0;
            memcpy(v[nv++], x, sizeof x);
        }
    }
    for (j = 0; j < count; j++) { /* every patch on a supporting plane, front outward */
        const radinterp__patch *pt = &s->patches[members[j]];
        for (l = 0; l < nv; l++)
            if (radinterp__d3_dot(pt->n, v[l]) - pt->d > tol) return 0;
    }
    nh = radinterp__hull_planes((const double (*)[3])v, nv, tol, hull);
    if (nh <= 0) return 0;
    for (i = 0; i < nh; i++) {
        if (radinterp__facet_covered(s, members, count, (const double (*)[3])v, nv, hull[i], tol)) {
            nf++;
        } else {
            plugs[no] = radinterp__find_plug(s, members, count, (const double (*)[3])v, nv, hull[i], tol, near);
            memcpy(planes[no++], hull[i], sizeof hull[i]);
        }
    }
    *faces = nf;
    *holes = no;
    return nf > 0;
}

/* Finds the convex solids among the patches: solution.patch_solid, solids,
   solid_members and solid_planes. Returns 0, or -1 when out of memory. */
static int radinterp__find_solids(radinterp_solution *s)
{
    uint32_t n = s->patch_count, i, pass, *parent, *next, *head;
    int res = 0;
    radinterp__buf near;   /* patches near a hole (a plug; when out of memory for it, a hole counts unplugged) */
    radinterp__buf_init(&near, sizeof(uint32_t));
    parent = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
    next = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
    head = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
    s->patch_solid = (uint32_t *)radinterp__alloc_array(&s->allocator, n, sizeof(uint32_t));
    if (!parent || !next || !head || !s->patch_solid) res = -1;
    for (i = 0; i < n && res == 0; i++) { parent[i] = i; head[i] = RADINTERP__NONE; s->patch_solid[i] = RADINTERP__NONE; }
    if (res == 0) res = radinterp__join_patches(s, parent);
    for (i = n; i-- > 0 && res == 0;) { /* members of each group, in patch order */
        uint32_t r = radinterp__uf_find(parent, i);
        next[i] = head[r];
        head[r] = i;
    }
    /* pass 0 counts the solids, their members and planes, pass 1 stores them */
    for (pass = 0; pass < 2 && res == 0; pass++) {
        uint32_t solids = 0, planes = 0, members_total = 0;
        for (i = 0; i < n; i++) {
            uint32_t members[RADINTERP__SOLID_PATCHES], count = 0, m, faces, holes, plugs[RADINTERP__SOLID_PLANES];
            double pl[RADINTERP__SOLID_PLANES][4];
            if (head[i] == RADINTERP__NONE || next[head[i]] == RADINTERP__NONE) continue; /* not a root, or alone */
            for (m = head[i]; m != RADINTERP__NONE && count < RADINTERP__SOLID_PATCHES; m = next[m]) members[count++] = m;
            if (m != RADINTERP__NONE || !radinterp__solid_examine(s, members, count, pl, plugs, &faces, &holes, &near)) continue;
            if (pass == 1) {
                radinterp__solid *so = &s->solids[solids];
                so->first_plane = planes;
                so->faces = faces;
                so->holes = holes;
                so->first_member = members_total;
                so->members = count;
                memcpy(s->solid_planes[planes], pl, (size_t)holes * sizeof pl[0]);
                memcpy(s->solid_plugs + planes, plugs, (size_t)holes * sizeof plugs[0]);
                memcpy(s->solid_members + members_total, members, (size_t)count * sizeof members[0]);
                for (m = 0; m < count; m++) s->patch_solid[members[m]] = solids;
            }
            solids++;
            planes += holes;
            members_total += count;
        }
        if (pass == 0) {
            s->solids = (radinterp__solid *)radinterp__alloc_array(&s->allocator, solids, sizeof *s->solids);
            s->solid_planes = (double (*)[4])radinterp__alloc_array(&s->allocator, planes, sizeof s->solid_planes[0]);
            s->solid_members = (uint32_t *)radinterp__alloc_array(&s->allocator, members_total, sizeof(uint32_t));
            s->solid_plugs = (uint32_t *)radinterp__alloc_array(&s->allocator, planes, sizeof(uint32_t));
            if (!s->solids || !s->solid_planes || !s->solid_members || !s->solid_plugs) res = -1;
            s->solid_count = solids;
            s->solid_plane_count = planes;
            s->solid_member_count = members_total;
        }
    }
    radinterp__buf_free(&s->allocator, &near);
    radinterp__free(&s->allocator, parent);
    radinterp__free(&s->allocator, next);
    radinterp__free(&s->allocator, head);
    return res;
}

/* May patch b, turned away from the point bp->pv, be left out of the
   shadows? When it is a face of a convex solid that the point lies outside
   of (in front of one of its patches) and on the inner side of every hole
   of, and no patch of the solid is left out as seen edge-on while turned
   toward the point (see above). The patches are judged by the very
   expressions radinterp__bp_by_union and radinterp__bp_shadow_piece use, so
   a patch this rule counts as an entrance is one whose shadow is taken.
   The verdict for q->pv is remembered per solid. */
static int radinterp__back_face_covered(radinterp__query *q, const radinterp__bp *bp, uint32_t b)
{
    const radinterp_solution *s = q->s;
    uint32_t g = s->patch_solid[b], slot = g % RADINTERP__SOLID_CACHE, i;
    const radinterp__solid *so;
    const double (*pl)[4];
    double tol = s->epsilon * s->diag;
    int outside = 0, sealed = 1;
    if (g == RADINTERP__NONE) return 0;
    if (bp->pv == q->pv && q->solid_tag[slot] == g) return q->solid_skip[slot];
    so = &s->solids[g];
    for (i = 0; i < so->members && sealed; i++) {
        const radinterp__patch *pm = &s->patches[s->solid_members[so->first_member + i]];
        if (radinterp__d3_dot(pm->n, bp->pv) > pm->d) {   /* turned toward the point */
            int edge_on = fabs(radinterp__d3_dot(pm->n, bp->pv) - pm->d) <= tol;
            outside |= !edge_on;
            sealed = !edge_on;
        }
    }
    pl = (const double (*)[4])s->solid_planes + so->first_plane;
    for (i = 0; i < so->holes && sealed; i++) {
        uint32_t plug = s->solid_plugs[so->first_plane + i];
        const radinterp__patch *pp = plug != RADINTERP__NONE ? &s->patches[plug] : NULL;
        sealed = radinterp__plane_dist(pl[i], bp->pv) <= 0.0 ||
                 (pp && fabs(radinterp__d3_dot(pp->n, bp->pv) - pp->d) > tol); /* plugged, the plug not edge-on */
    }
    if (bp->pv == q->pv) {
        q->solid_tag[slot] = g;
        q->solid_skip[slot] = (unsigned char)(outside && sealed);
    }
    return outside && sealed;
}

/* ---- visibility by the union of the shadows (the default) -------------- */
#define RADINTERP__TAG_EDGE 32   /* edge tags: pyramid plane j < 32, blocker edge k = 32 + k */

/* Sutherland-Hodgman as radinterp__clip_poly, keeping for each corner the
   tag of the edge that leaves it; edges along the clipping plane get `tag`.
   Returns the corner count, -1 when it would exceed RADINTERP__POLY_MAX. */
static int radinterp__clip_tagged(const double (*in)[3], const int *tin, int count, const double *n, double d,
                                  int tag, double (*out)[3], int *tout)
{
    double dist[RADINTERP__POLY_MAX];
    int i, m = 0, k;
    for (i = 0; i < count; i++) dist[i] = radinterp__d3_dot(n, in[i]) - d;
    for (i = 0; i < count; i++) {
        const double *a = in[i], *b = in[radinterp__next(i, count)];
        double da = dist[i], db = dist[radinterp__next(i, count)];
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
    double a = radinterp__d3_dot(m, bp->fr.e1), b = radinterp__d3_dot(m, bp->fr.e2), len2 = a * a + b * b, len;
    if (!(len2 > 1e-18 * radinterp__d3_dot(m, m))) return 0;
    len = sqrt(len2);
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
        radinterp__d3_from_f(pb->v[radinterp__next(k, (int)pb->count)], b);
        radinterp__d3_sub(a, bp->pv, ra);
        radinterp__d3_sub(b, bp->pv, rb);
        radinterp__d3_cross(ra, rb, m);
        if (!(radinterp__d3_dot(m, m) > 1e-18 * radinterp__d3_dot(ra, ra) * radinterp__d3_dot(rb, rb))) return 0;
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
   lines, and *area, |radinterp__area2| of it. Returns 1; 0 when it casts
   none; -1 when it cannot be represented (the caller then triangulates). */
static int radinterp__bp_shadow_piece(const radinterp_solution *s, const radinterp__bp *bp, const radinterp__patch *pb,
                                      radinterp__piece *out, double *area)
{
    double buf[2][RADINTERP__POLY_MAX][3], (*poly)[3] = buf[0], inside[2] = {0.0, 0.0};
    int tags[2][RADINTERP__POLY_MAX], *tag = tags[0], m, j, i, at = 0;
    uint32_t cut;
    if ((m = radinterp__pyramid_cut(s, bp, pb, poly, &cut)) == 0) return 0;
    for (i = 0; i < m; i++) tag[i] = RADINTERP__TAG_EDGE + i;
    for (j = 0; j < bp->np && m >= 3; j++) {
        if (!((cut >> j) & 1u)) continue;
        at ^= 1;   /* from one buffer into the other */
        m = radinterp__clip_tagged((const double (*)[3])poly, tag, m, bp->plane_n[j], bp->plane_d[j], j, buf[at], tags[at]);
        if (m < 0) return -1;
        poly = buf[at];
        tag = tags[at];
    }
    if (m < 3) return 0;
    if (m > RADINTERP__PIECE_VERTS) return -1;
    radinterp__bp_project(bp, (const double (*)[3])poly, m, out->v);
    *area = fabs(radinterp__area2((const double (*)[2])out->v, m));
    if (radinterp__shadow_negligible(bp, *area)) return 0;
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

/* *dst = *src, its corners only (a piece is mostly unused room). */
static void radinterp__piece_copy(radinterp__piece *dst, const radinterp__piece *src)
{
    dst->count = src->count;
    memcpy(dst->lo, src->lo, sizeof dst->lo);
    memcpy(dst->hi, src->hi, sizeof dst->hi);
    memcpy(dst->v, src->v, (size_t)src->count * sizeof dst->v[0]);
    memcpy(dst->ln, src->ln, (size_t)src->count * sizeof dst->ln[0]);
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
   rest into neg (whose new edge lies on -L; not made when neg is NULL).
   Corners within tol of L count as on it, so no sliver is made. Returns 1
   when f lies wholly on the positive side, 2 wholly on the negative side
   (nothing written), 0 when split, -1 when a part would have too many
   corners. */
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
    pos->count = 0;
    if (neg) neg->count = 0;
    for (i = 0; i < n; i++) {
        int j = radinterp__next(i, n);
        if (pos->count + 2 > RADINTERP__PIECE_VERTS || (neg && neg->count + 2 > RADINTERP__PIECE_VERTS)) return -1;
        if (d[i] >= 0.0) radinterp__piece_add(pos, f->v[i], (d[j] >= 0.0 || d[i] > 0.0) ? f->ln[i] : L, 1.0);
        if (d[i] <= 0.0 && neg) {
            if (d[j] <= 0.0 || d[i] < 0.0) radinterp__piece_add(neg, f->v[i], f->ln[i], 1.0);
            else radinterp__piece_add(neg, f->v[i], L, -1.0);
        }
        if ((d[i] > 0.0 && d[j] < 0.0) || (d[i] < 0.0 && d[j] > 0.0)) {
            double t = d[i] / (d[i] - d[j]), x[2];
            x[0] = f->v[i][0] + t * (f->v[j][0] - f->v[i][0]);
            x[1] = f->v[i][1] + t * (f->v[j][1] - f->v[i][1]);
            radinterp__piece_add(pos, x, d[i] > 0.0 ? L : f->ln[i], 1.0);
            if (neg) radinterp__piece_add(neg, x, d[i] > 0.0 ? f->ln[i] : L, d[i] > 0.0 ? 1.0 : -1.0);
        }
    }
    radinterp__piece_bounds(pos);
    if (neg) radinterp__piece_bounds(neg);
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

/* Appends the parts of piece f outside piece P to pool[*top ..) (pool
   holds RADINTERP__PIECES): walking P's edges, what lies outside an edge is
   a part, what lies inside goes on to the next edge; what is left at the
   end lies inside P. Parts smaller than tiny (twice the area) are dropped.
   Returns -1 when the pieces outgrow their arrays. */
static int radinterp__subtract_piece(radinterp__piece *pool, const radinterp__piece *f, const radinterp__piece *P,
                                     int *top, double tol, double tiny)
{
    radinterp__piece rest[2];
    const radinterp__piece *cur = f;
    int j, which = 0;
    for (j = 0; j < P->count && cur->count >= 3; j++) {
        radinterp__piece *out;
        int r;
        if (*top >= RADINTERP__PIECES) return -1;
        out = &pool[*top];
        r = radinterp__split_piece(cur, P->ln[j], tol, &rest[which], out);
        if (r < 0) return -1;
        if (r == 1) continue;                       /* wholly inside this edge */
        if (r == 2) { radinterp__piece_copy(out, cur); (*top)++; return 0; } /* wholly outside P */
        if (fabs(radinterp__area2((const double (*)[2])out->v, out->count)) > tiny) (*top)++;
        cur = &rest[which];
        which = 1 - which;
    }
    return 0;
}

/* Replaces the pieces pool[first .. *end) by their parts outside piece P,
   packed in their place (*end moves). Returns -1 when the pieces outgrow
   their array. */
static int radinterp__pieces_minus(radinterp__piece *pool, int first, int *end, const radinterp__piece *P, double tol,
                                   double tiny)
{
    int top = *end, keep = first, f;
    for (f = first; f < *end; f++) {
        if (radinterp__pieces_apart(&pool[f], P, tol)) continue;
        if (radinterp__subtract_piece(pool, &pool[f], P, &top, tol, tiny) != 0) return -1;
        pool[f].count = 0; /* replaced by its parts outside P */
    }
    for (f = first; f < top; f++) /* close the gaps */
        if (pool[f].count) {
            if (f != keep) radinterp__piece_copy(&pool[keep], &pool[f]);
            keep++;
        }
    *end = keep;
    return 0;
}

/* Adds the piece q->piece[*count] (a new shadow) to the union kept as
   disjoint pieces q->piece[0 .. *count): its parts outside every piece
   already there become new pieces. Returns -1 when the pieces outgrow their
   arrays. */
static int radinterp__union_add(radinterp__query *q, int *count, double tol, double tiny)
{
    int old = *count, first = old, end = old + 1, i;
    for (i = 0; i < old && end > first; i++)
        if (radinterp__pieces_minus(q->piece, first, &end, &q->piece[i], tol, tiny) != 0) return -1;
    *count = end;
    return 0;
}

/* ---- planar occluders between two boxes (cluster links) ------------------
   Every segment from box A to box B crosses a plane that has A on one side
   and B on the other (either may touch it), and does so inside the convex
   hull of the crossings of the segments between their corners. When
   patches lying in that plane cover this region, every segment meets one
   of them, so nothing in A sees anything in B (the region's bounding
   rectangle in the plane is tested). Where A touches the plane
   (its own wall face lies in it, or A lies flat in it) a segment may start
   on a covering patch: it carries no light only when it leaves that patch
   from behind, so then only patches turned away from B count (and likewise
   for B); when both touch it, nothing is proved. What the patches
   leave uncovered may still lie inside solid matter (where a wall meets
   another wall the plane of either passes through the other's slab, and a
   floor's plane passes under the walls standing on it): a segment crossing
   there is inside a closed solid and must leave it through one of its
   faces. A part counts as inside when from a few of its points rays both
   ways along the plane's normal first meet back faces. Walls and floors
   between rooms are such planes: the test settles for a whole pair of
   clusters what rays could only suggest. */
#define RADINTERP__HIDE_PATCHES 96   /* patches in separating planes examined per pair at most */
#define RADINTERP__HIDE_VISITS 1024  /* triangles the search may visit per pair */
#define RADINTERP__HIDE_INSIDE 8     /* uncovered parts that may be shown inside solids */
#define RADINTERP__HIDE_SLOTS 256    /* hash slots of the patches found: a power of two over 2 x HIDE_PATCHES */

typedef struct radinterp__hide_ctx {
    const radinterp_solution *s;
    float ulo[3], uhi[3];            /* the union of the two boxes */
    float ilo[2][3], ihi[2][3];      /* their interiors (shrunk by tol): nothing wholly inside can separate */
    const float *lo[2], *hi[2];
    double tol;
    uint32_t found[RADINTERP__HIDE_PATCHES], count, visits;
    uint32_t last;                   /* the patch visited last, + 1 (0: none) */
    uint32_t slot[RADINTERP__HIDE_SLOTS];   /* the patches found, + 1, by hash (0: empty) */
} radinterp__hide_ctx;

/* Least and greatest n . x - d over a box. */
static void radinterp__box_range(const double *n, double d, const float *lo, const float *hi, double *mn, double *mx)
{
    int k;
    *mn = *mx = -d;
    for (k = 0; k < 3; k++) {
        *mn += n[k] * (n[k] > 0.0 ? (double)lo[k] : (double)hi[k]);
        *mx += n[k] * (n[k] > 0.0 ? (double)hi[k] : (double)lo[k]);
    }
}

/* Does the plane have one box on each side (touching allowed, not both)? */
static int radinterp__plane_separates(const radinterp__hide_ctx *c, const double *n, double d)
{
    double amn, amx, bmn, bmx, t = c->tol;
    radinterp__box_range(n, d, c->lo[0], c->hi[0], &amn, &amx);
    radinterp__box_range(n, d, c->lo[1], c->hi[1], &bmn, &bmx);
    return (amx <= t && bmn >= -t && (amx < -t || bmn > t)) || (bmx <= t && amn >= -t && (bmx < -t || amn > t));
}

static int radinterp__inside_box(const float *lo, const float *hi, const float *ilo, const float *ihi)
{
    return lo[0] > ilo[0] && lo[1] > ilo[1] && lo[2] > ilo[2] && hi[0] < ihi[0] && hi[1] < ihi[1] && hi[2] < ihi[2];
}

static int radinterp__hide_box(const void *ctx_, const float *lo, const float *hi)
{
    const radinterp__hide_ctx *c = (const radinterp__hide_ctx *)ctx_;
    int k;
    for (k = 0; k < 3; k++)
        if (lo[k] > c->uhi[k] || hi[k] < c->ulo[k]) return 0;
    return !radinterp__inside_box(lo, hi, c->ilo[0], c->ihi[0]) && !radinterp__inside_box(lo, hi, c->ilo[1], c->ihi[1]);
}

/* Keeps patch b when its plane separates the boxes: each such patch once,
   in the order the walk first meets it, stopping at HIDE_VISITS triangles
   or when a patch finds no room (the test's planes_search_matches keeps
   the list by a plain scan and must find the same). */
static int radinterp__hide_visit(void *ctx_, uint32_t b)
{
    radinterp__hide_ctx *c = (radinterp__hide_ctx *)ctx_;
    const radinterp__plane *pt;
    uint32_t i;
    if (++c->visits > RADINTERP__HIDE_VISITS) return 0;
    /* a patch's triangles come one after another: the first settled it */
    if (c->last == b + 1) return 1;
    c->last = b + 1;
    pt = &c->s->planes[b];
    if (pt->glass || !radinterp__plane_separates(c, pt->n, pt->d)) return 1;   /* a pane hides nothing */
    for (i = (b * 2654435761u) >> 24 & (RADINTERP__HIDE_SLOTS - 1); c->slot[i]; i = (i + 1) & (RADINTERP__HIDE_SLOTS - 1))
        if (c->slot[i] == b + 1) return 1;   /* found already */
    if (c->count == RADINTERP__HIDE_PATCHES) return 0;
    c->slot[i] = b + 1;
    c->found[c->count++] = b;
    return 1;
}

/* A convex polygon (counter-clockwise) as a piece: its corners and edge
   lines, edges shorter than tol left out. Returns 0 when it has too many
   corners or too few. */
static int radinterp__piece_from_poly(const double (*v)[2], int n, double tol, radinterp__piece *out)
{
    int i;
    out->count = 0;
    for (i = 0; i < n; i++) {
        const double *a = v[i], *b = v[radinterp__next(i, n)];
        double dx = b[0] - a[0], dy = b[1] - a[1], len = sqrt(dx * dx + dy * dy), ln[3];
        if (!(len > tol)) continue;
        if (out->count == RADINTERP__PIECE_VERTS) return 0;
        ln[0] = -dy / len;
        ln[1] = dx / len;
        ln[2] = -(ln[0] * a[0] + ln[1] * a[1]);
        radinterp__piece_add(out, a, ln, 1.0);
    }
    if (out->count < 3) return 0;
    radinterp__piece_bounds(out);
    return 1;
}

/* Is x inside closed geometry: do rays from it both ways along n first
   meet back faces? */
static int radinterp__inside_solid(const radinterp_solution *s, const double *x, const double *n)
{
    float org[3], dir[3];
    int k, sign;
    for (k = 0; k < 3; k++) org[k] = (float)x[k];
    for (sign = -1; sign <= 1; sign += 2) {
        radinterp__hit hit;
        const double *hn;
        for (k = 0; k < 3; k++) dir[k] = (float)(sign * n[k]);
        if (!radinterp__bvh_intersect(&s->bvh, org, dir, 0.0f, FLT_MAX, &hit)) return 0;
        if (s->patches[s->tri_patch[hit.tri]].glass) return 0;   /* light passes a pane */
        hn = s->patches[s->tri_patch[hit.tri]].n;
        if (!(hn[0] * dir[0] + hn[1] * dir[1] + hn[2] * dir[2] > 0.0)) return 0;   /* a front face, or edge-on */
    }
    return 1;
}

/* The range in the frame (e1, e2) of the points where the segments between
   the two boxes' corners cross the plane n . x = d (a segment that does not
   cross it: its end nearer the plane), into lo and hi (which hold the
   range to widen). The corners' heights over the plane are computed once
   each, not once per segment. */
static void radinterp__crossings_range(const radinterp__hide_ctx *c, const double *n, double d, const double *e1,
                                       const double *e2, double *lo, double *hi)
{
    double corner[2][8][3], height[2][8];
    int i, j, k;
    for (i = 0; i < 8; i++)
        for (j = 0; j < 2; j++) {
            for (k = 0; k < 3; k++) corner[j][i][k] = (i >> k) & 1 ? c->hi[j][k] : c->lo[j][k];
            height[j][i] = radinterp__d3_dot(n, corner[j][i]) - d;
        }
    for (i = 0; i < 8; i++)
        for (j = 0; j < 8; j++) {
            const double *a = corner[0][i], *b = corner[1][j], ta = height[0][i], tb = height[1][j];
            double t, x[3];
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

/* Do the patches of c->found lying in the plane of c->found[first] cover
   the crossings of the segments between the two boxes? */
static int radinterp__plane_covers(const radinterp__hide_ctx *c, uint32_t first, unsigned char *used)
{
    const radinterp_solution *s = c->s;
    const radinterp__plane *p0 = &s->planes[c->found[first]];
    double rect[4][2], lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX}, e1[3], e2[3], len;
    radinterp__piece work[RADINTERP__PIECES], cover;
    int i, k, end = 1, whole = 1, facing = 0;
    uint32_t g;
    {   /* a box touching the plane admits only patches turned away from the
           other box: a segment that starts on such a patch leaves it from
           behind and carries no light, while one that starts on the front of
           a patch turned toward the other box (a box lying flat in the plane,
           a balustrade at a stair opening) is not blocked by it. When both
           boxes touch the plane, segments may run in it: no proof. */
        double amn, amx, bmn, bmx;
        int side_a, side_b, touch_a, touch_b;
        radinterp__box_range(p0->n, p0->d, c->lo[0], c->hi[0], &amn, &amx);
        radinterp__box_range(p0->n, p0->d, c->lo[1], c->hi[1], &bmn, &bmx);
        side_a = amx > c->tol ? 1 : amn < -c->tol ? -1 : 0;   /* 0: lies in the plane */
        side_b = bmx > c->tol ? 1 : bmn < -c->tol ? -1 : 0;
        touch_a = side_a == 0 || (side_a > 0 ? amn <= c->tol : amx >= -c->tol);
        touch_b = side_b == 0 || (side_b > 0 ? bmn <= c->tol : bmx >= -c->tol);
        if (touch_a && touch_b) return 0;
        if (touch_a) facing = -side_b;
        else if (touch_b) facing = -side_a;
    }
    e1[0] = fabs(p0->n[0]) < 0.6 ? 1.0 : 0.0;
    e1[1] = e1[0] == 0.0 ? 1.0 : 0.0;
    e1[2] = 0.0;
    radinterp__d3_cross(p0->n, e1, e2);
    len = radinterp__d3_len(e2);
    for (k = 0; k < 3; k++) e2[k] /= len;
    radinterp__d3_cross(e2, p0->n, e1);   /* e1 x e2 = n: counter-clockwise seen from the front */
    radinterp__crossings_range(c, p0->n, p0->d, e1, e2, lo, hi);
    /* the crossings' bounding rectangle in the plane (a little more than
       their hull: covering it is enough) */
    rect[0][0] = lo[0]; rect[0][1] = lo[1];
    rect[1][0] = hi[0]; rect[1][1] = lo[1];
    rect[2][0] = hi[0]; rect[2][1] = hi[1];
    rect[3][0] = lo[0]; rect[3][1] = hi[1];
    if (!radinterp__piece_from_poly((const double (*)[2])rect, 4, c->tol, &work[0])) return 0;
    for (g = first; g < c->count && end > 0; g++) {
        const radinterp__plane *pl = &s->planes[c->found[g]];   /* the patch itself only when in the plane */
        const radinterp__patch *pt;
        double v[4][2];
        if (used[g] || fabs(fabs(radinterp__d3_dot(pl->n, p0->n)) - 1.0) > 1e-9) continue;
        if (fabs(radinterp__d3_dot(pl->n, p0->n) > 0.0 ? pl->d - p0->d : pl->d + p0->d) > c->tol) continue;
        used[g] = 1;
        if (facing && (radinterp__d3_dot(pl->n, p0->n) > 0.0 ? 1 : -1) != facing) continue;
        pt = &s->patches[c->found[g]];
        for (k = 0; k < (int)pt->count; k++) {  /* counter-clockwise in the frame whichever way it faces */
            int from = radinterp__d3_dot(pl->n, p0->n) > 0.0 ? k : (int)pt->count - 1 - k;
            double x[3];
            radinterp__d3_from_f(pt->v[from], x);
            v[k][0] = radinterp__d3_dot(x, e1);
            v[k][1] = radinterp__d3_dot(x, e2);
        }
        if (!radinterp__piece_from_poly((const double (*)[2])v, (int)pt->count, c->tol, &cover)) continue;
        if (radinterp__pieces_minus(work, 0, &end, &cover, c->tol, c->tol * c->tol) != 0) whole = 0;
        if (!whole) break;
    }
    if (!whole || end > RADINTERP__HIDE_INSIDE) return 0;
    for (i = 0; i < end; i++) {   /* what is left must lie inside solids */
        double centre[2] = {0.0, 0.0};
        for (k = 0; k < work[i].count; k++) {
            centre[0] += work[i].v[k][0] / work[i].count;
            centre[1] += work[i].v[k][1] / work[i].count;
        }
        for (k = -1; k < work[i].count; k++) {
            double uv[2], x[3];
            int a;
            for (a = 0; a < 2; a++) uv[a] = k < 0 ? centre[a] : 0.5 * (centre[a] + work[i].v[k][a]);
            for (a = 0; a < 3; a++) x[a] = p0->d * p0->n[a] + uv[0] * e1[a] + uv[1] * e2[a];
            if (!radinterp__inside_solid(s, x, p0->n)) return 0;
        }
    }
    return 1;
}

/* The search of radinterp__planes_hide between boxes a and b, before its walk. */
static void radinterp__hide_init(radinterp__hide_ctx *c, const radinterp_solution *s, const float *alo, const float *ahi,
                                 const float *blo, const float *bhi)
{
    int k, h;
    c->s = s;
    c->tol = s->epsilon * s->diag;
    c->lo[0] = alo; c->hi[0] = ahi; c->lo[1] = blo; c->hi[1] = bhi;
    for (k = 0; k < 3; k++) {
        c->ulo[k] = radinterp__minf(alo[k], blo[k]);
        c->uhi[k] = radinterp__maxf(ahi[k], bhi[k]);
        for (h = 0; h < 2; h++) {
            c->ilo[h][k] = (float)((double)c->lo[h][k] + c->tol);
            c->ihi[h][k] = (float)((double)c->hi[h][k] - c->tol);
        }
    }
    c->count = c->visits = c->last = 0;
    memset(c->slot, 0, sizeof c->slot);
}

/* Do the boxes overlap by more than 4 tol along every axis? Then no plane
   has one on each side as radinterp__plane_separates asks (at most tol
   into either): along a unit normal their common part spans at least its
   least extent, more than the 2 tol such a plane leaves room for (the
   rest covers rounding), so the walk would keep no patch. Cluster links
   whose boxes overlap are always split (radinterp__clink_too_coarse), and
   each asked the walk first. */
static int radinterp__boxes_inseparable(const radinterp__hide_ctx *c)
{
    int k;
    for (k = 0; k < 3; k++) {
        double lo = radinterp__maxf(c->lo[0][k], c->lo[1][k]), hi = radinterp__minf(c->hi[0][k], c->hi[1][k]);
        if (!(hi - lo > 4.0 * c->tol)) return 0;
    }
    return 1;
}

/* Are boxes a and b hidden from each other by patches in one plane between
   them (see above)? A search that finds too much answers no. */
static int radinterp__planes_hide(const radinterp_solution *s, const float *alo, const float *ahi, const float *blo,
                                  const float *bhi)
{
    radinterp__hide_ctx c;
    unsigned char used[RADINTERP__HIDE_PATCHES];
    uint32_t i;
    radinterp__hide_init(&c, s, alo, ahi, blo, bhi);
    if (radinterp__boxes_inseparable(&c)) return 0;
    if (!radinterp__bvh_walk(s, radinterp__hide_box, radinterp__hide_visit, &c)) return 0;
    memset(used, 0, sizeof used);
    for (i = 0; i < c.count; i++)
        if (!used[i] && radinterp__plane_covers(&c, i, used)) return 1;
    return 0;
}

/* Eq. 6.1 for a convex polygon of the source plane given in the frame f
   (either winding). */
static double radinterp__ff_frame(const radinterp__query *q, const radinterp__frame *f, const double (*v)[2], int n)
{
    double r[RADINTERP__PIECE_VERTS][3], e[RADINTERP__PIECE_VERTS], sum = 0.0;
    int i;
    for (i = 0; i < n; i++) {
        radinterp__frame_to3d(f, v[i], r[i]);
        radinterp__d3_sub(r[i], q->p, r[i]);
    }
    radinterp__ff_edges((const double (*)[3])r, n, q->n, e);
    for (i = 0; i < n; i++) sum += e[i];
    return fabs(sum) / (2.0 * RADINTERP__PI);
}

/* Do disjoint pieces of the source of area `covered` (in the frame) hide
   all of it? When they leave less than 1e-12 of its area, like
   radinterp__visible_rest. */
static int radinterp__source_covered(const radinterp__bp *bp, double covered)
{
    return covered >= (1.0 - 1e-12) * bp->whole;
}

/* Appends the shadow of the blocker at position at of bp's list on bp's
   source to q->staged[*n] when it casts one. Returns 1 when it alone hides
   the whole source (q->staged_at[*n] then names it), -1 when it cannot be
   represented or the array is full, else 0. Alone: it contains the
   source's corners, or it leaves less of the source than
   radinterp__union_staged would take for rounding. The second is the
   common one: a wall that spans the whole pyramid from the point over the
   source is clipped by the pyramid's sides to the source's outline, its
   corners moved by rounding, often just inside. On building_1k 10 M of the
   16 M unions that ended hidden were of this kind; each staged every
   other blocker of the list before the union found it. */
static int radinterp__stage_shadow(radinterp__query *q, const radinterp__bp *bp, uint32_t at, int *n)
{
    radinterp__piece *sh = &q->staged[*n];
    int r;
    if (*n == RADINTERP__BP_MAX_SURVIVORS) return -1;
    r = radinterp__bp_shadow_piece(q->s, bp, &q->s->patches[bp->blk[at]], sh, &q->staged_area[*n]);
    if (r <= 0) return r;
    q->staged_at[*n] = at;
    if (radinterp__covers((const double (*)[2])sh->v, sh->count, (const double (*)[2])bp->sc2, bp->nc) ||
        radinterp__source_covered(bp, q->staged_area[*n]))
        return 1;
    q->order[*n] = (unsigned char)*n;
    (*n)++;
    return 0;
}

/* Is blocker b turned toward the point bp->pv? */
static int radinterp__faces_point(const radinterp__query *q, const radinterp__bp *bp, uint32_t b)
{
    const radinterp__patch *pb = &q->s->patches[b];
    return radinterp__d3_dot(pb->n, bp->pv) > pb->d;
}

/* Orders the staged shadows q->staged[0 .. n) (faces turned toward the
   point) largest first, ties by their blockers' positions in the list, so
   the order does not depend on the order they were staged in. */
static void radinterp__order_staged(radinterp__query *q, int n)
{
    const double *area = q->staged_area;
    int k, j;
    for (k = 0; k < n; k++) q->order[k] = (unsigned char)k;
    for (k = 1; k < n; k++) {   /* insertion sort */
        unsigned char o = q->order[k];
        for (j = k; j > 0; j--) {
            unsigned char p = q->order[j - 1];
            if (area[p] > area[o] || (area[p] == area[o] && q->staged_at[p] < q->staged_at[o])) break;
            q->order[j] = p;
        }
        q->order[j] = o;
    }
}

/* The union of the staged shadows q->order[0 .. n) as disjoint convex
   pieces q->piece[0 .. *count), then of the shadows of the faces turned
   away q->later[0 .. nlater) (positions in bp's list), each staged when the
   union reaches it: when the shadows before it hide the whole source, it
   is never made. On building_1k a fifth of the shadows staged for unions
   are of faces turned away; a third of the unions that end hidden end
   before some that were made for them (4% of all staged shadows are no
   longer made). The verdict and pieces are those of staging every shadow
   first, except where that staging would have failed (the caller then
   triangulated) or found one hiding the source alone while the union ends
   hidden sooner; the query's hints may then differ too. Both give the
   source hidden, up to rounding: building_1k's irradiance coefficients
   moved at 2 of 167126 triangles, by at most 7e-12 (about one float step
   of those; the largest coefficient is 6.7). Returns 0 when the
   pieces together leave less than 1e-12 of the source's area (*count is
   then how many shadows that took), 1 otherwise, 2 when the shadow of a
   face turned away hides the whole source alone, -1 when the pieces
   outgrow their arrays or a shadow cannot be represented. */
static int radinterp__union_staged(radinterp__query *q, const radinterp__bp *bp, int n, uint32_t nlater,
                                   int *count_out)
{
    double tiny, covered = 0.0;
    uint32_t next = 0;
    int count = 0, k, i, r;
    /* a piece of area below tiny / 2 subtends less than 1e-12 / pi: dropped */
    tiny = 2e-12 * bp->hp * bp->hp;
    for (i = 0; i < n || next < nlater; i++) {
        while (i == n && next < nlater)   /* the next face turned away that casts a shadow */
            if ((r = radinterp__stage_shadow(q, bp, q->later[next++], &n)) != 0) return r > 0 ? 2 : -1;
        if (i == n) break;
        if (count >= RADINTERP__PIECES) return -1;
        radinterp__piece_copy(&q->piece[count], &q->staged[q->order[i]]);
        k = count;
        if (radinterp__union_add(q, &count, bp->tol, tiny) != 0) return -1;
        for (; k < count; k++) covered += fabs(radinterp__area2((const double (*)[2])q->piece[k].v, q->piece[k].count));
        if (radinterp__source_covered(bp, covered)) { *count_out = i + 1; return 0; }   /* disjoint pieces inside the source */
    }
    *count_out = count;
    return 1;
}

/* Remembers the blockers of the staged shadows idx[0 .. n), which hide the
   whole of a source, as the query's first candidates for the next sources
   (radinterp__hints_stage), ahead of the older ones. */
static void radinterp__remember_hiders(radinterp__query *q, const radinterp__bp *bp, const unsigned char *idx, int n)
{
    uint32_t keep[RADINTERP__HINTS];
    int k, j, m = 0;
    for (k = 0; k < n && m < RADINTERP__HINTS; k++) keep[m++] = bp->blk[q->staged_at[idx[k]]];
    for (k = 0; k < q->nhint && m < RADINTERP__HINTS; k++) {
        for (j = 0; j < m && keep[j] != q->hint[k]; j++) continue;
        if (j == m) keep[m++] = q->hint[k];
    }
    memcpy(q->hint, keep, (size_t)m * sizeof keep[0]);
    q->nhint = m;
}

/* The same for the one staged shadow q->staged[k] that hides a source alone. */
static void radinterp__remember_hider(radinterp__query *q, const radinterp__bp *bp, int k)
{
    unsigned char idx = (unsigned char)k;
    radinterp__remember_hiders(q, bp, &idx, 1);
}

/* Stages first the shadows of the blockers that hid the query's last
   hidden sources (a wall hides every source of the next room), where they
   are in bp's list and turned toward the point. Returns how many were
   staged, with *hides set when they alone hide the whole source (one, or
   their union); 0 when one cannot be represented (then the caller stages
   from scratch, as without hints). They are shadows the caller would
   stage anyway, ordered by radinterp__order_staged as theirs, so the union
   built from them all is the same. */
static int radinterp__hints_stage(radinterp__query *q, const radinterp__bp *bp, int *hides)
{
    int n = 0, k, r, covering;
    uint32_t j;
    for (k = 0; k < q->nhint; k++) {
        for (j = 0; j < bp->nblk && bp->blk[j] != q->hint[k]; j++) continue;
        if (j == bp->nblk || !radinterp__faces_point(q, bp, q->hint[k])) continue;
        r = radinterp__stage_shadow(q, bp, j, &n);
        if (r < 0) return 0;
        if (r > 0) { radinterp__remember_hider(q, bp, n); *hides = 1; return 0; }
    }
    if (n < 2) return n;
    radinterp__order_staged(q, n);
    r = radinterp__union_staged(q, bp, n, 0, &covering);
    if (r < 0) return 0;
    if (r == 0) { radinterp__remember_hiders(q, bp, q->order, covering); *hides = 1; return 0; }
    return n;
}

/* The shadows of bp's blockers' faces turned toward the point, as pieces,
   into q->staged, in the order q->order gives: largest first (ties in list
   order). The faces turned away that radinterp__back_face_covered cannot
   settle come after them, in list order: they are listed in q->later
   (q->nlater of them), and radinterp__union_staged stages each when the
   union reaches it. Largest first: a small shadow
   inside a large one already in the union is dropped after one pass over
   the large one's edges, while a large shadow added after many small ones
   is cut into parts around each of them (the 1k building's mesh samples
   took 1.7 times as long in list order). The query's hints go first
   (radinterp__hints_stage): on building_1k a third of the sources a point
   query backprojects are hidden whole, and the hints prove it for a
   quarter of those without staging the other shadows. Returns the count
   staged; 0 with *hides set when the shadows so far hide the whole source
   (one alone, or the hints' union); -1 when a shadow cannot be represented
   or there are more than RADINTERP__BP_MAX_SURVIVORS. */
static int radinterp__bp_stage(radinterp__query *q, const radinterp__bp *bp, int *hides)
{
    uint32_t taken[RADINTERP__HINTS], i;
    int n, k, j, r, ntaken;
    *hides = 0;
    q->nlater = 0;
    n = ntaken = radinterp__hints_stage(q, bp, hides);
    if (*hides) return 0;
    for (k = 0; k < ntaken; k++) taken[k] = q->staged_at[k];
    for (i = 0; i < bp->nblk; i++) {
        uint32_t b = bp->blk[i];
        if (!radinterp__faces_point(q, bp, b)) {   /* turned away: after the others */
            if (radinterp__back_face_covered(q, bp, b)) continue;
            if (q->nlater == RADINTERP__BP_MAX_SURVIVORS) return -1;
            q->later[q->nlater++] = i;
            continue;
        }
        for (j = 0; j < ntaken && taken[j] != i; j++) continue;
        if (j < ntaken) continue;   /* staged as a hint */
        if ((r = radinterp__stage_shadow(q, bp, i, &n)) != 0) {
            if (r > 0) radinterp__remember_hider(q, bp, n);
            *hides = r > 0;
            return r > 0 ? 0 : -1;
        }
    }
    radinterp__order_staged(q, n);
    return n;
}

/* The union of the shadows on the source of bp as disjoint convex pieces
   q->piece[0 .. *count_out), the shadows taken in radinterp__bp_stage's
   order: those of one convex object's faces turned toward the point do
   not overlap, and its faces turned away then fall inside them. Returns 1;
   0 when the shadows hide the whole source (one alone, or the pieces
   together leave less than 1e-12 of its area, like
   radinterp__visible_rest: a source behind a wall of several patches); -1
   when a shadow cannot be represented or the pieces outgrow their arrays
   (the caller triangulates). */
static int radinterp__bp_union(radinterp__query *q, const radinterp__bp *bp, int *count_out)
{
    int hides, covering, r, n = radinterp__bp_stage(q, bp, &hides);
    *count_out = 0;
    if (n < 0) return -1;
    if (hides) return 0;
    r = radinterp__union_staged(q, bp, n, q->nlater, &covering);
    if (r < 0) return -1;
    if (r == 2) return 0;
    if (r == 0) { radinterp__remember_hiders(q, bp, q->order, covering); return 0; }
    *count_out = covering;
    return 1;
}

/* full - hidden, where the difference carries the rounding of both sums:
   a source hidden by several shadows together comes out at about 1e-16 of
   F, not 0. */
static double radinterp__visible_rest(double full, double hidden)
{
    double f = full - hidden;
    return f > 1e-12 * full ? f : 0.0;
}

/* Visible factor = F(source) - sum of F over the disjoint pieces of the
   shadows' union (eq. 6.1 is additive over a partition). Returns -1 when
   the union cannot be built (the caller triangulates). */
static double radinterp__bp_by_union(radinterp__query *q, const radinterp__bp *bp)
{
    double hidden = 0.0;
    int count, k, r = radinterp__bp_union(q, bp, &count);
    if (r <= 0) return r < 0 ? -1.0 : 0.0;
    if (count == 0) return bp->full;
    q->triangulated++;
    for (k = 0; k < count; k++)
        hidden += radinterp__ff_frame(q, &bp->fr_ff, (const double (*)[2])q->piece[k].v, q->piece[k].count);
    return radinterp__visible_rest(bp->full, hidden);
}

/* A part of bp's source (a node below the one the union is over) in the
   source's frame: its corners, its edges' lines (its inside on their
   positive side), bounding box and twice its signed area. */
typedef struct radinterp__part {
    double c2[RADINTERP__POLY_MAX][2], L[RADINTERP__POLY_MAX][3], lo[2], hi[2], area;
    int nl;
} radinterp__part;

/* The part of bp's source whose polygon Sc (nc corners) is moved and
   clipped as the source is. Returns 0 when it has no area. */
static int radinterp__part_make(const radinterp__bp *bp, const double (*Sc)[3], int nc, radinterp__part *pt)
{
    int k, j;
    pt->lo[0] = pt->lo[1] = DBL_MAX;
    pt->hi[0] = pt->hi[1] = -DBL_MAX;
    for (k = 0; k < nc; k++) { /* onto the real source plane, then into the frame */
        double x[3];
        for (j = 0; j < 3; j++) x[j] = Sc[k][j] + bp->push * bp->ns[j];
        radinterp__frame_to2d(&bp->fr, x, pt->c2[k]);
        for (j = 0; j < 2; j++) {
            pt->lo[j] = pt->c2[k][j] < pt->lo[j] ? pt->c2[k][j] : pt->lo[j];
            pt->hi[j] = pt->c2[k][j] > pt->hi[j] ? pt->c2[k][j] : pt->hi[j];
        }
    }
    pt->area = radinterp__area2((const double (*)[2])pt->c2, nc);
    if (pt->area == 0.0) return 0;
    pt->nl = 0;
    for (k = 0; k < nc; k++) { /* its edges' lines */
        const double *a = pt->c2[k], *b = pt->c2[radinterp__next(k, nc)];
        double dx = b[0] - a[0], dy = b[1] - a[1], len = sqrt(dx * dx + dy * dy), sg = pt->area > 0.0 ? 1.0 : -1.0;
        double *L = pt->L[pt->nl];
        if (!(len > bp->tol)) continue; /* a vanishing edge: its neighbours' lines enclose it */
        L[0] = -sg * dy / len;
        L[1] = sg * dx / len;
        L[2] = -(L[0] * a[0] + L[1] * a[1]);
        pt->nl++;
    }
    return 1;
}

/* Piece k of the union cut to the part by its edges' lines: *cut points
   to it (into buf or the piece itself), NULL when the piece misses the
   part (its bounding box first). Returns -1 when a cut piece outgrows its
   array. */
static int radinterp__part_cut(const radinterp__query *q, const radinterp__bp *bp, const radinterp__part *pt, int k,
                               radinterp__piece *buf, const radinterp__piece **cut)
{
    const radinterp__piece *cur = &q->piece[k];
    double tol = bp->tol;
    int which = 0, j;
    *cut = NULL;
    if (cur->lo[0] >= pt->hi[0] - tol || pt->lo[0] >= cur->hi[0] - tol || cur->lo[1] >= pt->hi[1] - tol ||
        pt->lo[1] >= cur->hi[1] - tol)
        return 0;
    for (j = 0; j < pt->nl && cur; j++) {
        int r = radinterp__split_piece(cur, pt->L[j], tol, &buf[which], NULL);
        if (r < 0) return -1;
        if (r == 2) cur = NULL;                 /* wholly outside the part */
        else if (r == 0) { cur = &buf[which]; which = 1 - which; }
    }
    if (cur && cur->count >= 3) *cut = cur;
    return 0;
}

/* Does piece f contain the part (nc corners)? Every corner of the part on
   the inner side of every edge line of the piece, exactly: the part is
   then hidden whole, and cutting the piece to it would give the part back
   with its corners moved by rounding, whose factor radinterp__visible_rest
   takes from the part's to leave 0 (or a residue of the order of 1e-14 of
   it). On building_1k a third of the nodes a point takes below a shared
   union are hidden whole. */
static int radinterp__piece_contains(const radinterp__piece *f, const radinterp__part *pt, int nc)
{
    int i, j;
    if (pt->lo[0] < f->lo[0] || pt->hi[0] > f->hi[0] || pt->lo[1] < f->lo[1] || pt->hi[1] > f->hi[1]) return 0;
    for (i = 0; i < f->count; i++)
        for (j = 0; j < nc; j++)
            if (f->ln[i][0] * pt->c2[j][0] + f->ln[i][1] * pt->c2[j][1] + f->ln[i][2] < 0.0) return 0;
    return 1;
}

/* Visible factor of a part of bp's source from the pieces of its union
   (q->piece[0 .. count)): the part's polygon Sc (moved and clipped as the
   source, nc corners, unoccluded factor full), F(part) - sum of F over the
   pieces cut to it, those whose bounding box misses the part left out.
   The nodes below a source node share one union this way
   (radinterp__shared). Returns -1 when a cut piece outgrows its array. */
static double radinterp__part_visible(radinterp__query *q, const radinterp__bp *bp, const double (*Sc)[3], int nc,
                                      double full, int count)
{
    radinterp__part pt;
    radinterp__piece buf[2];
    const radinterp__piece *cut;
    double hidden = 0.0;
    int k, any = 0;
    if (!radinterp__part_make(bp, Sc, nc, &pt)) return 0.0;
    for (k = 0; k < count; k++)
        if (radinterp__piece_contains(&q->piece[k], &pt, nc)) return 0.0;
    for (k = 0; k < count; k++) {
        if (radinterp__part_cut(q, bp, &pt, k, buf, &cut) < 0) return -1.0;
        if (!cut) continue;
        hidden += radinterp__ff_frame(q, &bp->fr_ff, (const double (*)[2])cut->v, cut->count);
        any = 1;
    }
    if (!any) return full;
    q->triangulated++;
    return radinterp__visible_rest(full, hidden);
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
        for (i = 0; i < bp->nblk; i++)
            if (radinterp__ray_hits_patch(&s->patches[bp->blk[i]], bp->pv, c3)) return 0;
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
    if (kept == 0 && !overflow) return bp->full;
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
   ns . x = ds_pushed, already moved push behind the real source; full is
   its unoccluded factor) from the query point, by backprojection of the
   link's blockers. */
static double radinterp__backproject(radinterp__query *q, const radinterp__link *lk, const double (*Sc)[3], int nc,
                                     const double *ns, double ds_pushed, double push, double full)
{
    radinterp__bp bp;
    uint32_t survivors[RADINTERP__BP_MAX_SURVIVORS];
    int overflow, nsurv;
    radinterp__bp_setup(q, &bp, lk, Sc, nc, ns, ds_pushed, push);
    bp.full = full;
    if (q->s->visibility == RADINTERP_VISIBILITY_SHADOWS) {
        double f = radinterp__bp_by_union(q, &bp);
        if (f >= 0.0) return f;
    }
    nsurv = radinterp__bp_collect(q, &bp, survivors, &overflow);
    if (nsurv < 0) return 0.0;
    if (nsurv == 0 && !overflow) return full;
    q->triangulated++;
    return radinterp__bp_by_triangulation(q, &bp, survivors, nsurv, overflow);
}

/* The corners of radinterp__query_source below (the moved, clipped source
   node) without its factor. */
static int radinterp__source_poly(const radinterp__query *q, uint32_t node, double (*Sc)[3])
{
    const radinterp_solution *s = q->s;
    const radinterp__node *src = &s->nodes[node];
    const radinterp__patch *ps = &s->patches[src->patch];
    double S[RADINTERP__POLY_MAX][3];
    int n, nc, i;
    if (radinterp__d3_dot(ps->n, q->p) - (ps->d - s->push_off) <= 0.0) return 0;  /* p behind the source */
    n = radinterp__node_poly(src, S);
    for (i = 0; i < n; i++) {  /* push-off (6.4) */
        S[i][0] -= s->push_off * ps->n[0];
        S[i][1] -= s->push_off * ps->n[1];
        S[i][2] -= s->push_off * ps->n[2];
    }
    nc = radinterp__clip_poly((const double (*)[3])S, n, q->n, q->dr, Sc);  /* horizon (6.2.1) */
    return nc < 3 ? 0 : nc;
}

/* A source node as the query point sees it: moved push_off behind its
   plane (6.4) and clipped by the receiver's horizon (6.2.1), into Sc, and
   its unoccluded factor (eq. 6.1) into *full (q->known_full for
   q->known_node). Returns the corner count; 0 when no part of it lies in
   front of p. */
static int radinterp__query_source(const radinterp__query *q, uint32_t node, double (*Sc)[3], double *full)
{
    int nc = radinterp__source_poly(q, node, Sc);
    *full = 0.0;
    if (nc == 0) return 0;
    *full = node == q->known_node ? q->known_full : radinterp__ff_poly(q->p, q->n, (const double (*)[3])Sc, nc);
    return nc;
}

/* The inner edges the children of a quad (count 4) and of a triangle
   (count 3) share, in section 4's layout: {child c, its edge k, child d,
   its edge e} where edge e of d is edge k of c taken the other way. */
static const unsigned char radinterp__inner_edges[2][4][4] = {
    {{0, 1, 3, 1}, {1, 2, 3, 2}, {2, 0, 3, 0}, {0, 0, 0, 0}},                 /* triangle: the middle child's */
    {{0, 1, 1, 3}, {1, 2, 2, 0}, {2, 3, 3, 1}, {0, 2, 3, 0}}};                /* quad: around the centre */

/* radinterp__query_source for the four children of node at once. An edge
   taken the other way round has exactly the opposite term of eq. 6.1 (the
   cross product's components change sign exactly, its length and the dot
   product do not), and the children meet along inner edges (a quad's
   share four, a triangle's middle child its three with the others): where
   both ends of such an edge are equal, bit for bit, in the two children
   (the horizon cut neither), the second takes the first's term negated,
   12 edge terms instead of 16 for a quad, and the same sums as the
   children taken one by one (where RADINTERP__FF_SHARE allows). */
static void radinterp__query_children(const radinterp__query *q, uint32_t node, double (*Sc)[RADINTERP__POLY_MAX][3],
                                      int *nc, double *full)
{
    const radinterp__node *nd = &q->s->nodes[node];
    double rows[6][RADINTERP__FF_ROWS + RADINTERP__VW], term[RADINTERP__FF_ROWS];
    const double *a[3], *b[3];
    int from[4][RADINTERP__POLY_MAX], c, k, j, m = 0, layout = nd->count == 4;
    int whole = 0;   /* bit c: child c is whole (unclipped), its terms computed together */
    /* edge k of child c: term from[c][k]; a shared edge's partner: ~ its term */
    for (c = 0; c < 4; c++) {
        nc[c] = radinterp__source_poly(q, nd->child + c, Sc[c]);
        full[c] = 0.0;
        if (nd->child + (uint32_t)c == q->known_node) full[c] = q->known_full;
        else if (nc[c] == (int)nd->count) whole |= 1 << c;   /* else clipped: on its own */
        else if (nc[c]) full[c] = radinterp__ff_poly(q->p, q->n, (const double (*)[3])Sc[c], nc[c]);
        for (k = 0; k < nc[c]; k++) from[c][k] = -1;
    }
    for (j = 0; RADINTERP__FF_SHARE && j < (layout ? 4 : 3); j++) {
        const unsigned char *ie = radinterp__inner_edges[layout][j];
        int c0 = ie[0], k0 = ie[1], c1 = ie[2], k1 = ie[3], n0 = (int)nd->count;
        if (((whole >> c0) & (whole >> c1) & 1) && memcmp(Sc[c0][k0], Sc[c1][(k1 + 1) % n0], sizeof Sc[c0][k0]) == 0 &&
            memcmp(Sc[c0][(k0 + 1) % n0], Sc[c1][k1], sizeof Sc[c0][k0]) == 0)
            from[c1][k1] = -2 - (c0 * RADINTERP__POLY_MAX + k0);   /* resolved below */
    }
    for (c = 0; c < 4; c++) {
        if (!((whole >> c) & 1)) continue;
        for (k = 0; k < nc[c]; k++) {
            const double *u = Sc[c][k], *v = Sc[c][radinterp__next(k, nc[c])];
            if (from[c][k] != -1) continue;
            for (j = 0; j < 3; j++) {
                rows[j][m] = u[j] - q->p[j];
                rows[3 + j][m] = v[j] - q->p[j];
            }
            from[c][k] = m++;
        }
    }
    if (m) {
        for (j = 0; j < 6; j++)
            for (k = m; k < m + RADINTERP__VW; k++) rows[j][k] = rows[j][0];   /* unused lanes */
        for (j = 0; j < 3; j++) { a[j] = rows[j]; b[j] = rows[3 + j]; }
        radinterp__ff_rows(a, b, m, q->n, term);
    }
    for (c = 0; c < 4; c++) {
        double e[RADINTERP__POLY_MAX];
        if (!((whole >> c) & 1)) continue;
        for (k = 0; k < nc[c]; k++) {
            int f = from[c][k];
            if (f >= 0) e[k] = term[f];
            else {
                f = -2 - f;
                e[k] = -term[from[f / RADINTERP__POLY_MAX][f % RADINTERP__POLY_MAX]];
            }
        }
        full[c] = radinterp__ff_sum(e, nc[c]);
    }
}

/* Point-to-polygon factor from the query point to one node of a link's
   source (Sc, nc and full from radinterp__query_source), seen past the
   blockers q->blk. */
static double radinterp__node_point_ff(radinterp__query *q, const radinterp__link *lk, uint32_t node,
                                       const double (*Sc)[3], int nc, double full)
{
    const radinterp_solution *s = q->s;
    const radinterp__patch *ps = &s->patches[s->nodes[node].patch];
    if (nc < 3) return 0.0;
    if (q->nblk == 0) return full;
    return radinterp__backproject(q, lk, Sc, nc, ps->n, ps->d - s->push_off, s->push_off, full);
}

/* Are the children of a node to be taken in its place (see below)? */
static int radinterp__take_children(const radinterp__query *q, uint32_t node, int depth_left, double full)
{
    const radinterp_solution *s = q->s;
    return s->nodes[node].child != RADINTERP__NONE && depth_left > 0 &&
           radinterp__source_spread(s, node) * full > q->child_tol;
}

/* One union of shadows over a source node, shared by the nodes below it
   (the parts of the source a query takes in its place, see below): they lie
   inside the node, so the shadows on each of them are the node's pieces cut
   to it (radinterp__part_visible). At building scale a point takes the
   children, grandchildren and deeper of most bright sources; a union built
   again for each of them tests every blocker of the leaf's list again and
   was the larger part of a mesh build's time. The triangulation method
   takes each node on its own, so the tests comparing the two methods at
   random points of the office and the Cornell box, where most points take a
   source's children, check this too. */
typedef struct radinterp__shared {
    radinterp__bp bp;   /* the node the union is over */
    int count;          /* pieces q->piece[0 .. count) */
} radinterp__shared;

/* Visible factor of a node below sh's (Sc, nc, full as
   radinterp__query_source gives them) from the shared pieces; when a cut
   piece outgrows its array, by a backprojection of its own, after which the
   shared union is built again (the same pieces: it is deterministic). */
static double radinterp__shared_ff(radinterp__query *q, radinterp__shared *sh, const radinterp__link *lk,
                                   uint32_t node, const double (*Sc)[3], int nc, double full)
{
    double f;
    if (nc < 3) return 0.0;
    if (sh->count == 0) return full;
    f = radinterp__part_visible(q, &sh->bp, Sc, nc, full, sh->count);
    if (f >= 0.0) return f;
    f = radinterp__node_point_ff(q, lk, node, Sc, nc, full);
    if (radinterp__bp_union(q, &sh->bp, &sh->count) < 0) q->failed = 1;   /* it succeeded before: cannot happen */
    return f;
}

/* B_src * F for node (Sc, nc, full) and the nodes below it a query takes in
   its place (see radinterp__link_point_add), their factors from sh. */
static void radinterp__shared_add(radinterp__query *q, radinterp__shared *sh, const radinterp__link *lk, uint32_t node,
                                  const double (*Sc)[3], int nc, double full, double *h)
{
    const radinterp__node *nd = &q->s->nodes[node];
    double f;
    if (radinterp__take_children(q, node, q->depth_left, full)) {
        double Scc[4][RADINTERP__POLY_MAX][3], fullc[4];
        int ncc[4];
        uint32_t c;
        q->depth_left--;
        radinterp__query_children(q, node, Scc, ncc, fullc);
        for (c = 0; c < 4; c++)
            radinterp__shared_add(q, sh, lk, nd->child + c, (const double (*)[3])Scc[c], ncc[c], fullc[c], h);
        q->depth_left++;
        return;
    }
    if (nd->b[0] == 0.0f && nd->b[1] == 0.0f && nd->b[2] == 0.0f) return;
    f = radinterp__shared_ff(q, sh, lk, node, Sc, nc, full);
    h[0] += f * nd->b[0];
    h[1] += f * nd->b[1];
    h[2] += f * nd->b[2];
}

/* Takes the nodes below node (Sc, nc, full) with one shared union of the
   shadows over node. Returns 0 when that union cannot be built (then each
   is taken on its own). */
static int radinterp__descend_shared(radinterp__query *q, const radinterp__link *lk, uint32_t node,
                                     const double (*Sc)[3], int nc, double full, double *h)
{
    const radinterp_solution *s = q->s;
    const radinterp__patch *ps = &s->patches[s->nodes[node].patch];
    radinterp__shared sh;
    int r;
    if (s->visibility != RADINTERP_VISIBILITY_SHADOWS || q->nblk == 0 || nc < 3) return 0;
    radinterp__bp_setup(q, &sh.bp, lk, Sc, nc, ps->n, ps->d - s->push_off, s->push_off);
    sh.bp.full = full;
    r = radinterp__bp_union(q, &sh.bp, &sh.count);
    if (r < 0) return 0;
    if (r == 0) return 1;   /* hidden whole: so is every node below */
    radinterp__shared_add(q, &sh, lk, node, Sc, nc, full, h);
    return 1;
}

/* B_src * F for one link. The source node's radiosity is a mean; where its
   children differ enough that the mean would misjudge the part seen from p
   (their spread times the node's unoccluded factor above a tenth of eps),
   the children are taken instead (and theirs in turn), each with its own
   factor past the same blockers. */
static void radinterp__link_point_add(radinterp__query *q, const radinterp__link *lk, uint32_t node, double *h)
{
    const radinterp_solution *s = q->s;
    const radinterp__node *nd = &s->nodes[node];
    double f, full, Sc[RADINTERP__POLY_MAX][3];
    int nc = -1;
    if (nd->child != RADINTERP__NONE && q->depth_left > 0 && radinterp__source_spread(s, node) > 0.0) {
        nc = radinterp__query_source(q, node, Sc, &full);
        if (radinterp__take_children(q, node, q->depth_left, full)) {
            uint32_t c;
            if (radinterp__descend_shared(q, lk, node, (const double (*)[3])Sc, nc, full, h)) return;
            q->depth_left--;
            for (c = 0; c < 4; c++) radinterp__link_point_add(q, lk, nd->child + c, h);
            q->depth_left++;
            return;
        }
    }
    if (nd->b[0] == 0.0f && nd->b[1] == 0.0f && nd->b[2] == 0.0f) return;
    if (nc < 0) nc = radinterp__query_source(q, node, Sc, &full);
    f = radinterp__node_point_ff(q, lk, node, (const double (*)[3])Sc, nc, full);
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

/* The sky: radiance finite and >= 0; a map of 1..RADINTERP_MAX_ENVIRONMENT_SIZE
   texels a side, each finite and >= 0; sky_rays within its limit. */
static radinterp_result radinterp__check_sky(const radinterp_desc *d)
{
    size_t i, n;
    int k;
    for (k = 0; k < 3; k++)
        if (!(d->sky[k] >= 0.0f) || !isfinite(d->sky[k])) {
            radinterp__log(d, "radinterp_solve: sky radiance must be finite and not negative");
            return RADINTERP_ERROR_INVALID_ARGUMENT;
        }
    if (d->sky_rays > RADINTERP_MAX_SKY_RAYS) {
        radinterp__log(d, "radinterp_solve: sky_rays %u above its limit (%u)", d->sky_rays, RADINTERP_MAX_SKY_RAYS);
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (!d->environment) return RADINTERP_OK;
    if (d->environment_width < 1 || d->environment_height < 1 || d->environment_width > RADINTERP_MAX_ENVIRONMENT_SIZE ||
        d->environment_height > RADINTERP_MAX_ENVIRONMENT_SIZE ||
        d->environment_height > (size_t)-1 / 3 / sizeof(float) / d->environment_width) {   /* 32-bit size_t */
        radinterp__log(d, "radinterp_solve: environment map of %u x %u texels (1..%u a side)", d->environment_width,
                       d->environment_height, RADINTERP_MAX_ENVIRONMENT_SIZE);
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    n = 3 * (size_t)d->environment_width * d->environment_height;
    for (i = 0; i < n; i++)
        if (!(d->environment[i] >= 0.0f) || !isfinite(d->environment[i])) {
            radinterp__log(d, "radinterp_solve: environment texel %u is negative, NaN or infinite", (unsigned)(i / 3));
            return RADINTERP_ERROR_INVALID_ARGUMENT;
        }
    return RADINTERP_OK;
}

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
    if (radinterp__bad_param(d->eps) || radinterp__bad_param(d->eps_relative) || radinterp__bad_param(d->min_area) || radinterp__bad_param(d->rel_error_cutoff) ||
        radinterp__bad_param(d->push_off) || radinterp__bad_param(d->nudge) || radinterp__bad_param(d->min_bp_segment) ||
        radinterp__bad_param(d->epsilon) || radinterp__bad_param(d->planarity_tolerance) ||
        radinterp__bad_param(d->point_rest) || d->point_rest > 1.0f || radinterp__bad_param(d->progress_interval)) {
        radinterp__log(d, "radinterp_solve: a parameter is negative, NaN or infinite");
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (d->ff_samples > RADINTERP_MAX_FF_SAMPLES || d->visibility_rays > RADINTERP_MAX_VISIBILITY_RAYS) {
        radinterp__log(d, "radinterp_solve: ff_samples %u or visibility_rays %u above its limit (%u, %u)",
                       d->ff_samples, d->visibility_rays, RADINTERP_MAX_FF_SAMPLES, RADINTERP_MAX_VISIBILITY_RAYS);
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if ((unsigned)d->clustering > (unsigned)RADINTERP_CLUSTERING_OFF) {
        radinterp__log(d, "radinterp_solve: clustering %u is not a radinterp_clustering", (unsigned)d->clustering);
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
            if (!(m->transmittance[k] >= 0.0f && m->transmittance[k] <= 1.0f)) {   /* NaN too */
                radinterp__log(d, "radinterp_solve: material %u: transmittance must lie in [0, 1]", i);
                return RADINTERP_ERROR_INVALID_ARGUMENT;
            }
        }
    }
    if (radinterp__check_sky(d) != RADINTERP_OK) return RADINTERP_ERROR_INVALID_ARGUMENT;
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
    if (s->diag > RADINTERP_MAX_SCENE_SIZE || (s->diag > 0.0 && s->diag < RADINTERP_MIN_SCENE_SIZE)) {
        radinterp__log(d, "radinterp_solve: the scene's size %g is outside [%g, %g]", s->diag, RADINTERP_MIN_SCENE_SIZE,
                       RADINTERP_MAX_SCENE_SIZE);
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    if (!(s->diag > 0.0)) s->diag = 1.0;   /* every corner at one point: every patch is skipped */
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
        memcpy(pt->tf, d->materials[m].transmittance, sizeof pt->tf);
        pt->glass = pt->tf[0] > 0.0f || pt->tf[1] > 0.0f || pt->tf[2] > 0.0f;
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

/* ---- merging triangles into quadrilaterals ------------------------------
   An engine exports a level as triangles: two per rectangle of a wall. Two
   triangles of one material that share an edge (run in opposite
   directions by them alone), lie in one plane (normals within 1e-5 rad,
   the fourth corner within 1e-6 of the pair's size of the plane) and
   together form a convex quadrilateral are the same surface as that
   quadrilateral, which is then one patch: half the patches, links and
   blockers. Pairs are taken greedily, longest shared edge first (the
   diagonal of a split rectangle). The caller's indices stay valid: each
   names the patch it became part of (desc.keep_triangles turns this off). */
typedef struct radinterp__merge_cand { double len; uint32_t a, b, ea, eb; } radinterp__merge_cand;

static int radinterp__cmp_merge(const void *x_, const void *y_)
{
    const radinterp__merge_cand *x = (const radinterp__merge_cand *)x_, *y = (const radinterp__merge_cand *)y_;
    if (x->len != y->len) return x->len > y->len ? -1 : 1;
    if (x->a != y->a) return x->a < y->a ? -1 : 1;
    return x->b < y->b ? -1 : (x->b > y->b);
}

/* The quadrilateral of triangle a (edge ea shared) and triangle b (edge eb),
   counter-clockwise; 1 when it is a valid convex patch (into *out). */
static int radinterp__merged_quad(const radinterp_solution *s, uint32_t a, uint32_t ea, uint32_t b, uint32_t eb,
                                  radinterp__patch *out)
{
    const radinterp__patch *pa = &s->patches[a], *pb = &s->patches[b];
    double v[4][3], dev;
    radinterp__d3_from_f(pa->v[ea], v[0]);
    radinterp__d3_from_f(pb->v[(eb + 2) % 3], v[1]);   /* b's corner off the shared edge */
    radinterp__d3_from_f(pa->v[(ea + 1) % 3], v[2]);
    radinterp__d3_from_f(pa->v[(ea + 2) % 3], v[3]);
    *out = *pa;
    if (radinterp__d3_dot(pa->n, pb->n) < 1.0 - 5e-11) return 0;
    if (fabs(radinterp__d3_dot(pa->n, v[1]) - pa->d) > 1e-6 * (pa->radius + pb->radius)) return 0;
    return radinterp__patch_setup(out, v, 4, s->diag, 1e-6, &dev) == RADINTERP__PATCH_OK &&
           fabs(out->area - pa->area - pb->area) <= 1e-9 * out->area;
}

/* Merges the triangle pairs (see above) and compacts the patches: a merged
   pair's second triangle leaves the array; caller_patch maps the caller's
   indices. Returns 0, or -1 when out of memory. */
static int radinterp__merge_triangles(radinterp_solution *s, int merge)
{
    uint32_t n = 0, i, run, nc = 0, at = 0, *partner;
    radinterp__edge_rec *e = NULL;
    radinterp__merge_cand *cand = NULL;
    s->caller_count = s->patch_count;
    s->caller_patch = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(uint32_t));
    s->first_caller = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(uint32_t));
    partner = (uint32_t *)radinterp__alloc_array(&s->allocator, s->patch_count, sizeof(uint32_t));
    if (!s->caller_patch || !s->first_caller || !partner) { radinterp__free(&s->allocator, partner); return -1; }
    for (i = 0; i < s->patch_count; i++) partner[i] = RADINTERP__NONE;
    if (merge) {
        e = radinterp__patch_edges(s, 1, &n);
        cand = (radinterp__merge_cand *)radinterp__alloc_array(&s->allocator, n / 2 + 1, sizeof *cand);
        if (!e || !cand) { radinterp__free(&s->allocator, e); radinterp__free(&s->allocator, cand); radinterp__free(&s->allocator, partner); return -1; }
        for (i = 0; i < n; i += run) {
            const radinterp__edge_rec *x, *y;
            double d[3];
            for (run = 1; i + run < n && radinterp__edge_cmp(&e[i], &e[i + run]) == 0; run++) {}
            if (run != 2) continue;
            x = &e[i];
            y = &e[i + 1];
            if (x->forward == y->forward || x->patch == y->patch ||
                s->patches[x->patch].material != s->patches[y->patch].material)
                continue;
            d[0] = (double)x->key[3] - x->key[0]; d[1] = (double)x->key[4] - x->key[1]; d[2] = (double)x->key[5] - x->key[2];
            cand[nc].len = radinterp__d3_len(d);
            cand[nc].a = x->patch < y->patch ? x->patch : y->patch;
            cand[nc].b = x->patch < y->patch ? y->patch : x->patch;
            cand[nc].ea = x->patch < y->patch ? x->corner : y->corner;
            cand[nc].eb = x->patch < y->patch ? y->corner : x->corner;
            nc++;
        }
        qsort(cand, nc, sizeof *cand, radinterp__cmp_merge);
        for (i = 0; i < nc; i++) {
            radinterp__patch q;
            if (partner[cand[i].a] != RADINTERP__NONE || partner[cand[i].b] != RADINTERP__NONE) continue;
            if (!radinterp__merged_quad(s, cand[i].a, cand[i].ea, cand[i].b, cand[i].eb, &q)) continue;
            s->patches[cand[i].a] = q;
            partner[cand[i].a] = cand[i].b;
            partner[cand[i].b] = cand[i].a;
            s->merged_patches++;
        }
    }
    for (i = 0; i < s->patch_count; i++) {   /* compact: a pair's second triangle goes */
        if (partner[i] != RADINTERP__NONE && partner[i] < i) { s->caller_patch[i] = s->caller_patch[partner[i]]; continue; }
        s->caller_patch[i] = at;
        s->first_caller[at] = i;
        s->patches[at++] = s->patches[i];
    }
    s->patch_count = at;
    radinterp__free(&s->allocator, e);
    radinterp__free(&s->allocator, cand);
    radinterp__free(&s->allocator, partner);
    return 0;
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
    s->planes = (radinterp__plane *)radinterp__alloc_array(&s->allocator, s->patch_count ? s->patch_count : 1,
                                                           sizeof(radinterp__plane));
    if (!pos || !idx || !s->tri_patch || !s->planes) {
        radinterp__free(&s->allocator, pos);
        radinterp__free(&s->allocator, idx);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    for (i = 0; i < s->patch_count; i++) {
        const radinterp__patch *pt = &s->patches[i];
        memcpy(pos + 12 * (size_t)i, pt->v, sizeof pt->v);
        memcpy(s->planes[i].n, pt->n, sizeof pt->n);
        s->planes[i].d = pt->d;
        s->planes[i].glass = pt->glass;
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

static radinterp_result radinterp__make_roots(radinterp_solution *s, radinterp__run *run)
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

/* ---- per-leaf blocker lists --------------------------------------------
   A link's blockers were found by the shaft between its receiver and its
   source, and the receiver is often a large ancestor of the leaf a query
   point lies in: most of them cannot come between that leaf and the source.
   For each leaf and link delivering to it, the link's blockers are culled
   again by the shaft between the leaf and the source, both boxes grown by
   a margin M. The convex hull of two boxes grown by M contains every point
   within M of the hull of the boxes, so a patch that meets a segment from
   a point within M of the leaf to the source reaches at least M (more than
   the shaft test's epsilon * diag) into that shaft and is kept; the tests
   against the receiver's and the source's planes are those the link's list
   passed already. Queries use the lists for points within M / 2 of the
   leaf's box (the point nudged toward `toward` lies within nudge of it).
   Where one blocker of the list hides the whole source from the whole
   grown leaf (radinterp__leaf_hides), the entry keeps no blockers and is
   marked hidden: every query there would find the source hidden, and on
   the buildings a wall between a leaf and a source in the next room is the
   common case (leaf lists of partly hidden links).
   The solution keeps no lists: for every leaf they grow with leaves x
   links x blockers (building_4k's were 1,818 MB of its 2.2 GB, and at
   building_16k their build had not ended after 255 s of one core). A point
   query filters a link's blockers for its own leaf when it reaches the
   link (radinterp__leaf_entry); the mesh build, which queries each leaf
   about ten times, builds the lists of the leaves a run of its sample
   points lies in (radinterp__leaf_lists_make, radinterp__sample_listed:
   at most RADINTERP__LEAF_BATCH_BYTES a batch) and frees them after those
   points.
   Both give each entry the same blockers in the same order, so a point's
   irradiance does not depend on which one it came from. */
#define RADINTERP__LEAF_HIDDEN 0xFFFFFFFFu   /* leaf_link.count of an entry whose source the leaf cannot see */

typedef struct radinterp__leaf_link {
    uint32_t link;
    uint32_t count;   /* blockers kept, or RADINTERP__LEAF_HIDDEN (none kept) */
    uint64_t first;   /* into radinterp__leaf_lists.blockers */
} radinterp__leaf_link;

/* Blockers an entry of this count keeps. */
static uint32_t radinterp__leaf_kept(uint32_t count)
{
    return count == RADINTERP__LEAF_HIDDEN ? 0u : count;
}

/* The lists of some leaves: leaf[i]'s entries are link[first[i] ..
   first[i + 1]), their blockers in blockers from room[i] on (room for all
   the blockers of its links; an entry keeps those of link[e].first ..
   + radinterp__leaf_kept). */
typedef struct radinterp__leaf_lists {
    const radinterp_solution *s;
    uint32_t *leaf;          /* ascending node indices */
    uint32_t count;
    uint32_t *first;         /* count + 1 */
    uint64_t *room;          /* count + 1 */
    radinterp__leaf_link *link;
    uint32_t *blockers;
    size_t bytes;            /* all of the above */
    uint32_t job_first;      /* radinterp__leaf_lists_job's index 0 (a batch of its jobs) */
} radinterp__leaf_lists;

/* The box of a node grown by margin. */
static void radinterp__grown_box(const radinterp__node *nd, double margin, float *lo, float *hi)
{
    int k;
    for (k = 0; k < 3; k++) {
        lo[k] = (float)((double)nd->lo[k] - margin);
        hi[k] = (float)((double)nd->hi[k] + margin);
    }
}

/* A box (a leaf's, grown) and a source node as radinterp__leaf_hides
   tests them: the box's corners and the source's, at its place and
   push_off behind it, where point queries put it (6.4). */
typedef struct radinterp__leaf_shaft {
    const float *lo, *hi;
    double box[8][3], src[8][3];
    double mid_box[3], mid_src[3];   /* their centres */
    int nsrc;                        /* 0 until the corners are needed (radinterp__leaf_corners) */
    const radinterp__node *node;
    double push[3];                  /* push_off times the source's front normal */
} radinterp__leaf_shaft;

/* The centres only: most blockers fail on them (radinterp__leaf_hides). */
static void radinterp__leaf_shaft_make(const radinterp_solution *s, const float *lo, const float *hi,
                                       const radinterp__node *src, radinterp__leaf_shaft *ls)
{
    const double *ns = s->patches[src->patch].n;
    uint32_t i;
    int k;
    for (k = 0; k < 3; k++) {
        ls->push[k] = s->push_off * ns[k];
        ls->mid_box[k] = 0.5 * ((double)lo[k] + (double)hi[k]);
        ls->mid_src[k] = -0.5 * ls->push[k];
        for (i = 0; i < src->count; i++) ls->mid_src[k] += (double)src->v[i][k] / src->count;
    }
    ls->nsrc = 0;
    ls->node = src;
    ls->lo = lo;
    ls->hi = hi;
}

static void radinterp__leaf_corners(radinterp__leaf_shaft *ls)
{
    int i, k, n = radinterp__node_poly(ls->node, ls->src);
    for (i = 0; i < n; i++)
        for (k = 0; k < 3; k++) ls->src[n + i][k] = ls->src[i][k] - ls->push[k];
    ls->nsrc = 2 * n;
    for (i = 0; i < 8; i++)
        for (k = 0; k < 3; k++) ls->box[i][k] = (i >> k) & 1 ? (double)ls->hi[k] : (double)ls->lo[k];
}

/* Does the opaque patch b alone hide the whole source from every point of
   the box (ls)? When the box lies in front of b's plane and the source
   behind it, every segment from the box to the source crosses the plane,
   and the crossings fill the convex hull of the crossings of the segments
   between their corners (the hull of box and source meets the plane in the
   hull of where its edges cross it, and those edges run between a box
   corner and a source corner). b is convex, so the segments all meet it
   when those crossings lie inside it. Every margin is 4 epsilon * diag: no
   point of the box sees b edge-on (radinterp__bp_shadow_piece leaves such
   a blocker out, at epsilon * diag) and b's shadow from any point of the
   box covers the source with room to spare, so a point query there finds
   the source hidden by b, a factor of 0. b turned toward the box is staged
   by every query (a face turned away may be left to the front faces of its
   solid, radinterp__back_face_covered), so only such b count. The
   segment between the centres lies in the hull too: where it crosses the
   plane must lie in b's bounding box, which most blockers fail cheaply. */
static int radinterp__leaf_hides(const radinterp_solution *s, radinterp__leaf_shaft *ls, uint32_t b)
{
    const radinterp__patch *pb = &s->patches[b];
    double margin = 4.0 * s->epsilon * s->diag, mn, mx, dsrc[8], pv[4][3], in[4][3], far2[4], ma, ms;
    int nv, i, j, k, c;
    if (pb->glass || pb->count < 3) return 0;
    ma = radinterp__d3_dot(pb->n, ls->mid_box) - pb->d;
    ms = radinterp__d3_dot(pb->n, ls->mid_src) - pb->d;
    if (!(ma > margin && ms < -margin)) return 0;
    for (k = 0; k < 3; k++) {
        double z = ls->mid_box[k] + ma / (ma - ms) * (ls->mid_src[k] - ls->mid_box[k]);
        if (!(z >= (double)pb->lo[k] - margin && z <= (double)pb->hi[k] + margin)) return 0;
    }
    radinterp__box_range(pb->n, pb->d, ls->lo, ls->hi, &mn, &mx);
    if (!(mn > margin)) return 0;
    if (!ls->nsrc) radinterp__leaf_corners(ls);
    for (i = 0; i < ls->nsrc; i++)
        if (!((dsrc[i] = radinterp__d3_dot(pb->n, ls->src[i]) - pb->d) < -margin)) return 0;
    nv = radinterp__patch_poly(pb, pv);
    for (k = 0; k < nv; k++) { /* inward normals of b's edges in its plane (counter-clockwise seen from the front) */
        double e[3];
        radinterp__d3_sub(pv[(k + 1) % nv], pv[k], e);
        radinterp__d3_cross(pb->n, e, in[k]);
        far2[k] = margin * margin * radinterp__d3_dot(in[k], in[k]);   /* |in| margin, squared */
    }
    for (c = 0; c < 8; c++) {
        const double *a = ls->box[c];
        double da = radinterp__d3_dot(pb->n, a) - pb->d;
        for (i = 0; i < ls->nsrc; i++) {
            double t = da / (da - dsrc[i]), z[3], r[3];
            for (j = 0; j < 3; j++) z[j] = a[j] + t * (ls->src[i][j] - a[j]);
            for (k = 0; k < nv; k++) { /* z at least margin inside edge k */
                double dk;
                radinterp__d3_sub(z, pv[k], r);
                dk = radinterp__d3_dot(in[k], r);
                if (!(dk > 0.0 && dk * dk >= far2[k])) return 0;
            }
        }
    }
    return 1;
}

/* Does one of the blockers blk[0 .. n) hide src from the whole box? */
static int radinterp__leaf_hidden(const radinterp_solution *s, const float *lo, const float *hi,
                                  const radinterp__node *src, const uint32_t *blk, uint32_t n)
{
    radinterp__leaf_shaft ls;
    uint32_t i;
    if (n == 0) return 0;
    radinterp__leaf_shaft_make(s, lo, hi, src, &ls);
    for (i = 0; i < n; i++)
        if (radinterp__leaf_hides(s, &ls, blk[i])) return 1;
    return 0;
}

/* The blockers of link l that may come between leaf, whose box grown by
   the lists' margin is lo, hi (radinterp__grown_box), and the link's
   source, into blk (room for the link's blocker_count); their count.
   With blk NULL: 1 at the first such blocker, else 0. */
static uint32_t radinterp__leaf_filter(const radinterp_solution *s, uint32_t leaf, const float *lo, const float *hi,
                                       uint32_t l, uint32_t *blk)
{
    const radinterp__link *lk = &s->links[l];
    radinterp__shaft sh;
    float slo[3], shi[3];
    uint32_t k, n = 0;
    if (!lk->blocker_count) return 0;
    radinterp__grown_box(&s->nodes[lk->source], s->leaf_margin, slo, shi);
    radinterp__shaft_build(&sh, lo, hi, slo, shi);
    for (k = 0; k < lk->blocker_count; k++) {
        uint32_t b = s->blockers[lk->first_blocker + k];
        if (!radinterp__may_block(s, &sh, b, &s->nodes[leaf], &s->nodes[lk->source])) continue;
        if (!blk) return 1;
        blk[n++] = b;
    }
    return n;
}

/* The entry of link l at leaf (lo, hi as above): its blockers, into blk,
   and their count, or RADINTERP__LEAF_HIDDEN when one of them hides the
   source from the whole box. */
static uint32_t radinterp__leaf_entry(const radinterp_solution *s, uint32_t leaf, const float *lo, const float *hi,
                                      uint32_t l, uint32_t *blk)
{
    uint32_t n = radinterp__leaf_filter(s, leaf, lo, hi, l, blk);
    return radinterp__leaf_hidden(s, lo, hi, &s->nodes[s->links[l].source], blk, n) ? RADINTERP__LEAF_HIDDEN : n;
}

/* A leaf's list: its entries (the links of the leaf and its ancestors) and
   the room their blockers may need. */
static void radinterp__leaf_size(const radinterp_solution *s, uint32_t leaf, uint32_t *entries, uint64_t *room)
{
    uint32_t node, l;
    *entries = 0;
    *room = 0;
    for (node = leaf; node != RADINTERP__NONE; node = s->nodes[node].parent) {
        const radinterp__node *nd = &s->nodes[node];
        *entries += nd->link_count;
        for (l = nd->first_link; l < nd->first_link + nd->link_count; l++) *room += s->links[l].blocker_count;
    }
}

/* Bytes a leaf's list takes in radinterp__leaf_lists. */
static size_t radinterp__leaf_bytes(const radinterp_solution *s, uint32_t leaf)
{
    uint32_t entries;
    uint64_t room;
    radinterp__leaf_size(s, leaf, &entries, &room);
    return (size_t)entries * sizeof(radinterp__leaf_link) + (size_t)room * sizeof(uint32_t) +
           2 * sizeof(uint32_t) + sizeof(uint64_t);
}

#define RADINTERP__LEAF_JOB 16   /* leaves per job */

static void radinterp__leaf_lists_job(void *ctx_, uint32_t index)
{
    radinterp__leaf_lists *ll = (radinterp__leaf_lists *)ctx_;
    const radinterp_solution *s = ll->s;
    uint32_t i = (ll->job_first + index) * RADINTERP__LEAF_JOB, end = i + RADINTERP__LEAF_JOB;
    if (end > ll->count) end = ll->count;
    for (; i < end; i++) {
        uint32_t leaf = ll->leaf[i], node, e = ll->first[i], l;
        uint64_t at = ll->room[i];
        float lo[3], hi[3];
        radinterp__grown_box(&s->nodes[leaf], s->leaf_margin, lo, hi);
        for (node = leaf; node != RADINTERP__NONE; node = s->nodes[node].parent) {
            const radinterp__node *nd = &s->nodes[node];
            for (l = nd->first_link; l < nd->first_link + nd->link_count; l++, e++) {
                radinterp__leaf_link *lk = &ll->link[e];
                lk->link = l;
                lk->first = at;
                lk->count = radinterp__leaf_entry(s, leaf, lo, hi, l, ll->blockers + at);
                at += radinterp__leaf_kept(lk->count);
            }
        }
    }
}

static void radinterp__leaf_lists_free(const radinterp_allocator *a, radinterp__leaf_lists *ll)
{
    radinterp__free(a, ll->leaf);
    radinterp__free(a, ll->first);
    radinterp__free(a, ll->room);
    radinterp__free(a, ll->link);
    radinterp__free(a, ll->blockers);
    memset(ll, 0, sizeof *ll);
}

/* Room for the lists of the n leaves (distinct, ascending node indices;
   copied) in ll, sized serially; radinterp__leaf_lists_job fills them,
   RADINTERP__LEAF_JOB leaves a job (radinterp__leaf_lists_jobs of them). */
static radinterp_result radinterp__leaf_lists_make(const radinterp_solution *s, const radinterp_allocator *a,
                                                   const uint32_t *leaves, uint32_t n, radinterp__leaf_lists *ll)
{
    uint32_t i;
    memset(ll, 0, sizeof *ll);
    ll->s = s;
    ll->count = n;
    ll->leaf = (uint32_t *)radinterp__alloc_array(a, (size_t)n + 1, sizeof(uint32_t));
    ll->first = (uint32_t *)radinterp__alloc_array(a, (size_t)n + 1, sizeof(uint32_t));
    ll->room = (uint64_t *)radinterp__alloc_array(a, (size_t)n + 1, sizeof(uint64_t));
    if (!ll->leaf || !ll->first || !ll->room) { radinterp__leaf_lists_free(a, ll); return RADINTERP_ERROR_OUT_OF_MEMORY; }
    ll->first[0] = 0;
    ll->room[0] = 0;
    for (i = 0; i < n; i++) {
        uint32_t entries;
        uint64_t room;
        radinterp__leaf_size(s, leaves[i], &entries, &room);
        if ((uint64_t)ll->first[i] + entries > 0xFFFFFFFFu) { radinterp__leaf_lists_free(a, ll); return RADINTERP_ERROR_OUT_OF_MEMORY; }
        ll->leaf[i] = leaves[i];
        ll->first[i + 1] = ll->first[i] + entries;
        ll->room[i + 1] = ll->room[i] + room;
    }
    ll->link = (radinterp__leaf_link *)radinterp__alloc_array(a, (size_t)ll->first[n] + 1, sizeof *ll->link);
    if (ll->room[n] < (uint64_t)SIZE_MAX / sizeof(uint32_t))
        ll->blockers = (uint32_t *)radinterp__alloc_array(a, (size_t)ll->room[n] + 1, sizeof(uint32_t));
    if (!ll->link || !ll->blockers) { radinterp__leaf_lists_free(a, ll); return RADINTERP_ERROR_OUT_OF_MEMORY; }
    ll->bytes = ((size_t)n + 1) * (2 * sizeof(uint32_t) + sizeof(uint64_t)) +
                ((size_t)ll->first[n] + 1) * sizeof *ll->link + ((size_t)ll->room[n] + 1) * sizeof(uint32_t);
    return RADINTERP_OK;
}

static uint32_t radinterp__leaf_lists_jobs(const radinterp__leaf_lists *ll)
{
    return (ll->count + RADINTERP__LEAF_JOB - 1) / RADINTERP__LEAF_JOB;
}

/* Where leaf's list is in ll, or NONE. */
static uint32_t radinterp__leaf_lists_find(const radinterp__leaf_lists *ll, uint32_t leaf)
{
    uint32_t lo = 0, hi = ll ? ll->count : 0;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (ll->leaf[mid] < leaf) lo = mid + 1;
        else hi = mid;
    }
    return lo < (ll ? ll->count : 0) && ll->leaf[lo] == leaf ? lo : RADINTERP__NONE;
}

RADINTERP_API void radinterp_solution_destroy(radinterp_solution *s)
{
    radinterp_allocator a;
    if (!s) return;
    a = s->allocator;
    radinterp__free(&a, s->patches);
    radinterp__free(&a, s->caller_patch);
    radinterp__free(&a, s->first_caller);
    radinterp__bvh_free(&s->bvh, &a);
    radinterp__free(&a, s->tri_patch);
    radinterp__free(&a, s->planes);
    radinterp__free(&a, s->nodes);
    radinterp__free(&a, s->links);
    radinterp__free(&a, s->blockers);
    radinterp__free(&a, s->leaves);
    radinterp__free(&a, s->clinks);
    radinterp__free(&a, s->clusters);
    radinterp__free(&a, s->cluster_order);
    radinterp__free(&a, s->cluster_cdf);
    radinterp__free(&a, s->patch_cluster);
    radinterp__free(&a, s->patch_hmin);
    radinterp__free(&a, s->patch_solid);
    radinterp__free(&a, s->solids);
    radinterp__free(&a, s->solid_planes);
    radinterp__free(&a, s->solid_members);
    radinterp__free(&a, s->solid_plugs);
    radinterp__free(&a, s->environment);
    radinterp__free(&a, s);
}

/* Glass and sky parameters of the solution: the panes counted, the sky
   copied (a sky of zero radiance is no sky). */
static radinterp_result radinterp__setup_sky(radinterp_solution *s, const radinterp_desc *d)
{
    uint32_t i;
    int k;
    for (i = 0; i < s->patch_count; i++) s->glass_patches += s->patches[i].count && s->patches[i].glass;
    s->sky_rays = radinterp__def(d->sky_rays, 1024u);
    if (d->environment) {
        size_t n = 3 * (size_t)d->environment_width * d->environment_height, j;
        s->environment = (float *)radinterp__alloc_array(&s->allocator, n, sizeof(float));
        if (!s->environment) return RADINTERP_ERROR_OUT_OF_MEMORY;
        memcpy(s->environment, d->environment, n * sizeof(float));
        s->environment_width = d->environment_width;
        s->environment_height = d->environment_height;
        for (j = 0; j < n; j++) s->has_sky |= s->environment[j] > 0.0f;
    } else {
        for (k = 0; k < 3; k++) s->has_sky |= d->sky[k] > 0.0f;
    }
    memcpy(s->sky, d->sky, sizeof s->sky);
    return RADINTERP_OK;
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
    run.reported = run.read = RADINTERP_CPU_SECONDS();
    run.stride = run.countdown = RADINTERP__TICK_STEPS;
    res = radinterp__build_patches(s, desc);
    if (res == RADINTERP_OK) res = radinterp__setup_sky(s, desc);
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
        /* the mean emitted radiosity is the scale of the light in the scene;
           the sky counts as the radiosity it would give a patch open to
           all of it */
        double mean;
        power += area * radinterp__sky_scale(s);
        mean = area > 0.0 && power > 0.0 ? power / area : 1.0;
        s->light_scale = mean;
        s->eps = desc->eps > 0.0f ? desc->eps : RADINTERP__EPS_FLOOR * mean;
        s->eps_source = desc->eps > 0.0f ? desc->eps : RADINTERP__EPS_SOURCE_FLOOR * mean;
        s->eps_relative = desc->eps_relative > 0.0f ? desc->eps_relative : desc->eps > 0.0f ? 0.0 : RADINTERP__EPS_RELATIVE;
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
        s->point_rest = desc->point_rest > 0.0f ? desc->point_rest : RADINTERP__POINT_REST;
        s->clustering = desc->clustering ? (uint32_t)desc->clustering : (uint32_t)RADINTERP_CLUSTERING_ON;
        res = radinterp__merge_triangles(s, !desc->keep_triangles) != 0 ? RADINTERP_ERROR_OUT_OF_MEMORY : RADINTERP_OK;
        if (res == RADINTERP_OK) res = radinterp__build_bvh(s);
        if (res == RADINTERP_OK && radinterp__find_solids(s) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    if (res == RADINTERP_OK) res = radinterp__make_roots(s, &run);
    if (res == RADINTERP_OK)
        res = s->clustering == RADINTERP_CLUSTERING_OFF ? radinterp__initial_links(s, &run)
                                                          : radinterp__initial_cluster_links(s, &run);
    if (res == RADINTERP_OK) res = radinterp__iterate(s, &run);
    if (res == RADINTERP_OK) res = radinterp__trim_links(s, &run);
    if (res == RADINTERP_OK) res = radinterp__collect_leaves(s);
    s->leaf_margin = 10.0 * (s->nudge + s->epsilon * s->diag);   /* leaf lists (section 14): built where used */
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
    info->patch_count = s->caller_count;
    info->skipped_patches = s->skipped_patches;
    info->merged_patches = s->merged_patches;
    info->node_count = s->node_count;
    info->leaf_count = s->leaf_count;
    info->link_count = s->link_count;
    info->cluster_count = s->cluster_count;
    info->cluster_link_count = s->clink_count;
    info->culled_links = s->culled_links;
    info->blocker_entries = s->blocker_count;
    info->iterations = s->iterations;
    info->converged = s->converged;
    info->max_relative_change = s->max_relative_change;
    info->shadow_rays = s->shadow_rays;
    info->glass_patches = s->glass_patches;
    info->link_bytes = (size_t)s->link_count * sizeof(radinterp__link) + (size_t)s->blocker_count * sizeof(uint32_t);
    info->leaf_list_entries = 0;   /* the solution keeps no leaf lists (section 14: built where they are used) */
    info->leaf_blocker_entries = 0;
    info->leaf_list_bytes = 0;
    info->bytes = sizeof *s + (size_t)s->patch_count * sizeof(radinterp__patch) +
                  (size_t)s->node_cap * sizeof(radinterp__node) + info->link_bytes + (size_t)s->leaf_count * sizeof(uint32_t) +
                  (size_t)s->clink_count * sizeof(radinterp__clink) + (size_t)s->cluster_count * sizeof(radinterp__cluster) +
                  (size_t)s->patch_count * (2 * sizeof(uint32_t) + sizeof(double)) +
                  (size_t)s->patch_count * (sizeof(uint32_t) + sizeof(radinterp__plane)) +
                  (size_t)s->solid_count * sizeof(radinterp__solid) +
                  (size_t)s->solid_plane_count * (sizeof s->solid_planes[0] + sizeof(uint32_t)) +
                  (size_t)s->solid_member_count * sizeof(uint32_t) + info->leaf_list_bytes +
                  (size_t)s->bvh.node_count * sizeof(radinterp__bvh_node) +
                  (size_t)s->bvh.block_count * sizeof(radinterp__bvh_tris) + (size_t)s->bvh.tri_count * sizeof(uint32_t) +
                  (s->environment ? 3 * sizeof(float) * s->environment_width * s->environment_height : 0);
}

static int radinterp__patch_ok(const radinterp_solution *s, uint32_t patch)
{
    return s && patch < s->patch_count && s->patches[patch].count != 0;
}

/* The patch the caller's patch became (merged triangles share one), or
   NONE when out of range. */
static uint32_t radinterp__patch_of(const radinterp_solution *s, uint32_t caller)
{
    return s && caller < s->caller_count ? s->caller_patch[caller] : RADINTERP__NONE;
}

RADINTERP_API radinterp_result radinterp_patch_radiosity(const radinterp_solution *s, uint32_t caller, float rgb[3])
{
    uint32_t patch = radinterp__patch_of(s, caller);
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
    leaf->patch = s->first_caller[nd->patch];
    leaf->depth = nd->depth;
    leaf->vertex_count = nd->count;
    memcpy(leaf->vertices, nd->v, sizeof nd->v);
    memcpy(leaf->radiosity, nd->b, sizeof nd->b);
    leaf->area = nd->area;
    leaf->open = nd->open;
    return RADINTERP_OK;
}

/* Is x within margin of the node's box? */
static int radinterp__near_box(const radinterp__node *nd, const double *x, double margin)
{
    int k;
    for (k = 0; k < 3; k++)
        if (!(x[k] >= (double)nd->lo[k] - margin && x[k] <= (double)nd->hi[k] + margin)) return 0;
    return 1;
}

/* Irradiance (rgb) the cluster links deliver to a point of patch in leaf:
   those of the leaf, of its ancestors and of the clusters above the patch,
   each times the cosine at the point. */
static void radinterp__cluster_links_add(const radinterp_solution *s, uint32_t patch, uint32_t leaf, double *h)
{
    const double *n = s->patches[patch].n;
    uint32_t node, c, l;
    int k;
    for (node = leaf; node != RADINTERP__NONE; node = s->nodes[node].parent)
        for (l = s->nodes[node].first_clink; l < s->nodes[node].first_clink + s->nodes[node].clink_count; l++) {
            double e[3], f = radinterp__facing(n, s->clinks[l].dir);
            if (!(f > 0.0)) continue;
            radinterp__clink_irradiance(s, &s->clinks[l], e);
            for (k = 0; k < 3; k++) h[k] += f * e[k];
        }
    for (c = s->patch_cluster ? s->patch_cluster[patch] : RADINTERP__NONE; c != RADINTERP__NONE; c = s->clusters[c].parent)
        for (l = s->clusters[c].first_link; l < s->clusters[c].first_link + s->clusters[c].link_count; l++) {
            double e[3], f = radinterp__facing(n, s->clinks[l].dir);
            if (!(f > 0.0)) continue;
            radinterp__clink_irradiance(s, &s->clinks[l], e);
            for (k = 0; k < 3; k++) h[k] += f * e[k];
        }
}

/* B_src * F for one link whose blockers q->blk may hold panes (GLASS AND
   SKY): F = F_all + glass (F_clear - F_all) per channel, with F_all the
   factor past every blocker (panes as opaque) and F_clear past the opaque
   ones alone: the part of the source seen only through panes passes with
   the link's transmittance. Exact where all of it crosses the same panes
   (a window, single or double glazed). */
static void radinterp__link_point_glass(radinterp__query *q, const radinterp__link *lk, double *h)
{
    const radinterp_solution *s = q->s;
    const uint32_t *blk = q->blk;
    uint32_t nblk = q->nblk, i, kept = 0, local[256], *opaque = local;
    double all[3] = {0.0, 0.0, 0.0}, clear[3] = {0.0, 0.0, 0.0};
    int k;
    if (!radinterp__list_has_glass(s, blk, nblk)) { radinterp__link_point_add(q, lk, lk->source, h); return; }
    if (nblk > 256) opaque = (uint32_t *)radinterp__alloc_array(&s->allocator, nblk, sizeof(uint32_t));
    radinterp__link_point_add(q, lk, lk->source, all);
    if (!opaque) { q->failed = 1; for (k = 0; k < 3; k++) h[k] += all[k]; return; }
    for (i = 0; i < nblk; i++)
        if (!s->patches[blk[i]].glass) opaque[kept++] = blk[i];
    q->blk = opaque;
    q->nblk = kept;
    radinterp__link_point_add(q, lk, lk->source, clear);
    q->blk = blk;
    q->nblk = nblk;
    if (opaque != local) radinterp__free(&s->allocator, opaque);
    for (k = 0; k < 3; k++) h[k] += all[k] + lk->glass[k] * (clear[k] - all[k]);
}

/* The links that reach a point, ranked by what they could carry there
   (Hardt ranks discontinuities by their weight in the same spirit). Exact
   visibility by backprojection costs one union of shadows per partly hidden
   source, and at building scale a point sees hundreds of sources through
   doors and past furniture, most of them dim; so the links are taken in
   decreasing order of B_src * F_unoccluded at the point, and once all those
   left could together carry no more than point_rest of the
   irradiance summed so far, each of them counts with the visible fraction
   the solver measured for it (links of the point's leaf or its ancestors,
   so measured over a larger receiver), an error of at most that fraction of
   the result (s->point_rest, PARAMETERS). A point whose leaf gathers more
   than RADINTERP__POINT_LINKS links takes them all exactly. */
#define RADINTERP__POINT_LINKS 512

typedef struct radinterp__plink {
    const radinterp__link *lk;
    const uint32_t *blk;      /* its blockers near the point: the leaf list's, or the link's own */
    uint32_t nblk;
    int hidden;               /* the leaf list's entry is hidden (RADINTERP__LEAF_HIDDEN): F = 0 */
    int listed;               /* blk, nblk and hidden hold; else radinterp__plink_filter fills them */
    double full, reach;       /* unoccluded factor at the point, and that times B_src (largest channel); once
                                 ranked, what this source and those after it could carry */
} radinterp__plink;

/* A link's place in the ranking: its reach and its position in pl. */
typedef struct radinterp__rank {
    double reach;
    uint32_t at;
} radinterp__rank;

/* Does a rank before b: larger reach first, ties in link order (the same
   sum on every run)? */
static int radinterp__rank_before(const radinterp__plink *pl, const radinterp__rank *a, const radinterp__rank *b)
{
    if (a->reach != b->reach) return a->reach > b->reach;
    return pl[a->at].lk < pl[b->at].lk;
}

/* Ranks pl[0 .. n) (n <= RADINTERP__POINT_LINKS) by radinterp__rank_before.
   A merge sort of 16-byte keys, then the links moved once along the cycles
   of the permutation: qsort moving the links themselves through a compare
   callback was a twentieth of a building's mesh. The order is total (links
   are distinct), so it is the order any sort finds. */
static void radinterp__rank_links(radinterp__plink *pl, uint32_t n)
{
    radinterp__rank key[RADINTERP__POINT_LINKS], tmp[RADINTERP__POINT_LINKS], *a = key, *b = tmp, *t;
    unsigned char done[RADINTERP__POINT_LINKS];
    uint32_t i, w;
    for (i = 0; i < n; i++) {
        key[i].reach = pl[i].reach;
        key[i].at = i;
    }
    for (w = 1; w < n; w *= 2) {   /* bottom-up: runs of w merged into runs of 2w */
        uint32_t lo;
        for (lo = 0; lo < n; lo += 2 * w) {
            uint32_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n, x = lo, y = mid, o = lo;
            while (x < mid && y < hi) b[o++] = radinterp__rank_before(pl, &a[y], &a[x]) ? a[y++] : a[x++];
            while (x < mid) b[o++] = a[x++];
            while (y < hi) b[o++] = a[y++];
        }
        t = a; a = b; b = t;
    }
    memset(done, 0, n);
    for (i = 0; i < n; i++) {   /* pl[j] = old pl[a[j].at], cycle by cycle */
        radinterp__plink hold;
        uint32_t j = i;
        if (done[i]) continue;
        hold = pl[i];
        for (;;) {
            uint32_t k = a[j].at;
            done[j] = 1;
            if (k == i) { pl[j] = hold; break; }
            pl[j] = pl[k];
            j = k;
        }
    }
}

/* The leaf a query reads and where its links' blockers come from: the
   leaf's list in a batch (radinterp__leaf_lists), or each link's entry
   filtered when the sum reaches it (radinterp__plink_filter), or, for a
   point too far from the leaf's box, the links' own lists. */
typedef struct radinterp__point_leaf {
    uint32_t leaf;
    int lists;                          /* the leaf lists hold at the point */
    const radinterp__leaf_lists *batch; /* lists built for a batch of leaves, or NULL */
    uint32_t slot;                      /* the leaf's place in batch, or NONE */
    float lo[3], hi[3];                 /* the leaf's box grown by the lists' margin */
} radinterp__point_leaf;

/* The leaf a query at p, seen from pv, reads, and whether its leaf lists
   hold there: both points within half the lists' margin of its box. */
static uint32_t radinterp__query_leaf(const radinterp_solution *s, uint32_t patch, const double *p, const double *pv,
                                      int *lists)
{
    uint32_t leaf = radinterp__locate_leaf(s, patch, pv);
    *lists = s->leaf_margin > 0.0 && radinterp__near_box(&s->nodes[leaf], pv, 0.5 * s->leaf_margin) &&
             radinterp__near_box(&s->nodes[leaf], p, 0.5 * s->leaf_margin);
    return leaf;
}

/* Lists the links of the point's leaf (the leaf's and its ancestors', as
   in its leaf list), those at positions first .. first + max, into pl;
   returns the length of the whole list. */
static uint32_t radinterp__point_links(const radinterp__query *q, const radinterp__point_leaf *pt, uint32_t first,
                                       radinterp__plink *pl, uint32_t max)
{
    const radinterp_solution *s = q->s;
    uint32_t n = 0, node, l;
    for (node = pt->leaf; node != RADINTERP__NONE; node = s->nodes[node].parent)
        for (l = s->nodes[node].first_link; l < s->nodes[node].first_link + s->nodes[node].link_count; l++, n++) {
            radinterp__plink *p;
            if (n < first || n - first >= max) continue;
            p = &pl[n - first];
            p->lk = &s->links[l];
            p->listed = 1;
            p->hidden = 0;
            if (!pt->lists) {
                p->blk = s->blockers + s->links[l].first_blocker;
                p->nblk = s->links[l].blocker_count;
            } else if (pt->slot != RADINTERP__NONE) {   /* entries in the order above */
                const radinterp__leaf_link *ll = &pt->batch->link[pt->batch->first[pt->slot] + n];
                p->blk = pt->batch->blockers + ll->first;
                p->nblk = radinterp__leaf_kept(ll->count);
                p->hidden = ll->count == RADINTERP__LEAF_HIDDEN;
            } else {
                p->listed = 0;
            }
        }
    return n;
}

/* Fills p's blockers with the leaf's entry for its link
   (radinterp__leaf_entry) in buf (room for cap), or in *heap, allocated,
   when the link has more blockers; out of memory, the link's own list and
   the query failed. */
static void radinterp__plink_filter(radinterp__query *q, const radinterp__point_leaf *pt, radinterp__plink *p,
                                    uint32_t *buf, uint32_t cap, uint32_t **heap)
{
    const radinterp_solution *s = q->s;
    uint32_t *blk = buf, count;
    p->listed = 1;
    p->hidden = 0;
    if (p->lk->blocker_count > cap) blk = *heap = (uint32_t *)radinterp__alloc_array(&s->allocator, p->lk->blocker_count, sizeof(uint32_t));
    if (!blk) {
        q->failed = 1;
        p->blk = s->blockers + p->lk->first_blocker;
        p->nblk = p->lk->blocker_count;
        return;
    }
    count = radinterp__leaf_entry(s, pt->leaf, pt->lo, pt->hi, (uint32_t)(p->lk - s->links), blk);
    p->blk = blk;
    p->nblk = radinterp__leaf_kept(count);
    p->hidden = count == RADINTERP__LEAF_HIDDEN;
}

/* Sums B_src * F over the listed links into h, exactly (backprojection)
   while the links left could still matter, then by their visible
   fractions (see above). */
static void radinterp__sum_links(radinterp__query *q, const radinterp__point_leaf *pt, radinterp__plink *pl, uint32_t n,
                                 int ranked, double *h)
{
    const radinterp_solution *s = q->s;
    double rest = 0.0, Sc[RADINTERP__POLY_MAX][3];
    uint32_t i, local[256];
    int k;
    if (ranked) {
        for (i = 0; i < n; i++) {
            const radinterp__node *src = &s->nodes[pl[i].lk->source];
            double b[3];
            for (k = 0; k < 3; k++) b[k] = src->b[k];
            radinterp__query_source(q, pl[i].lk->source, Sc, &pl[i].full);
            pl[i].reach = pl[i].full * radinterp__max3(b);
        }
        radinterp__rank_links(pl, n);
        /* each source's reach becomes what it and those after it could
           carry, summed from the smallest: a running difference would leave
           a rounding residue that can fall to zero or below before the last
           sources, and FLT_MIN would then not make them all exact */
        for (i = n; i-- > 0;) {
            rest += pl[i].reach;
            pl[i].reach = rest;
        }
    }
    for (i = 0; i < n; i++) {
        const radinterp__node *src = &s->nodes[pl[i].lk->source];
        uint32_t *heap = NULL;
        if (ranked && pl[i].reach <= s->point_rest * radinterp__max3(h)) {
            /* a blocker in the leaf's entry (hidden ones keep some too) */
            int blocked = pl[i].listed ? pl[i].nblk || pl[i].hidden
                                       : radinterp__leaf_filter(s, pt->leaf, pt->lo, pt->hi,
                                                                (uint32_t)(pl[i].lk - s->links), NULL) != 0;
            double f = blocked ? pl[i].full * pl[i].lk->vis : pl[i].full;
            for (k = 0; k < 3; k++) h[k] += f * src->b[k];
            continue;
        }
        if (!pl[i].listed) radinterp__plink_filter(q, pt, &pl[i], local, 256, &heap);
        if (!pl[i].hidden) {   /* a hidden one adds 0, as its backprojection would */
            q->blk = pl[i].blk;
            q->nblk = pl[i].nblk;
            if (ranked) {
                q->known_node = pl[i].lk->source;
                q->known_full = pl[i].full;
            }
            radinterp__link_point_glass(q, pl[i].lk, h);
            q->known_node = RADINTERP__NONE;
        }
        if (heap) radinterp__free(&s->allocator, heap);
    }
}

/* p nudged toward `toward` (may be NULL) along the patch, by nudge at most:
   where a query at p judges visibility from. */
static void radinterp__nudge(const radinterp_solution *s, uint32_t patch, const double *p, const float toward[3],
                             double *pv)
{
    const double *n = s->patches[patch].n;
    int k;
    memcpy(pv, p, 3 * sizeof(double));
    if (toward) {
        double t[3], d[3], len, k2;
        radinterp__d3_from_f(toward, t);
        radinterp__d3_sub(t, p, d);
        k2 = radinterp__d3_dot(d, n);
        for (k = 0; k < 3; k++) d[k] -= k2 * n[k];
        len = radinterp__d3_len(d);
        if (len > 0.0) {
            double step = len < s->nudge ? len : s->nudge;
            for (k = 0; k < 3; k++) pv[k] += d[k] * (step / len);
        }
    }
}

/* A query at p (valid, finite) on patch, seen from p nudged toward
   `toward` (may be NULL) along the patch (q->pv), with no hints yet. */
static void radinterp__query_start(radinterp__query *q, const radinterp_solution *s, uint32_t patch, const float p[3],
                                   const float toward[3])
{
    q->s = s;
    q->known_node = RADINTERP__NONE;
    q->cdt_ready = 0;
    q->failed = 0;
    q->depth_left = 8;
    q->triangulated = 0;
    memset(q->solid_tag, 0xFF, sizeof q->solid_tag);
    q->nhint = 0;
    radinterp__d3_from_f(p, q->p);
    memcpy(q->n, s->patches[patch].n, sizeof q->n);
    q->dr = radinterp__d3_dot(q->n, q->p);
    radinterp__nudge(s, patch, q->p, toward, q->pv);
}

/* Irradiance at p on a patch, summed over the links of its leaf and of the
   leaf's ancestors (6.2), past the blockers of the leaf lists (from batch
   when it holds the leaf's, may be NULL), and over the cluster links above
   it; pl holds max links for the ranking (see above). */
static radinterp_result radinterp__irradiance_in(const radinterp_solution *s, uint32_t patch, const float p[3],
                                                 const float toward[3], double *h, uint32_t *triangulated,
                                                 radinterp__plink *pl, uint32_t max, const radinterp__leaf_lists *batch)
{
    radinterp__query query, *q = &query;  /* about 110 KB of stack: no allocation in the common case */
    radinterp__point_leaf pt;
    uint32_t n;
    h[0] = h[1] = h[2] = 0.0;
    if (!p || !radinterp__patch_ok(s, patch) || !radinterp__finite3(p) || (toward && !radinterp__finite3(toward)))
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    radinterp__query_start(q, s, patch, p, toward);
    pt.leaf = radinterp__query_leaf(s, patch, q->p, q->pv, &pt.lists);
    pt.batch = batch;
    pt.slot = pt.lists ? radinterp__leaf_lists_find(batch, pt.leaf) : RADINTERP__NONE;
    radinterp__grown_box(&s->nodes[pt.leaf], s->leaf_margin, pt.lo, pt.hi);
    q->child_tol = 0.02 * radinterp__tolerance(s, s->nodes[pt.leaf].level);
    /* first: they count in the sum the ranking compares with */
    radinterp__cluster_links_add(s, patch, pt.leaf, h);
    if (s->has_sky) radinterp__sky_point_add(s, patch, q->pv, h);
    n = radinterp__point_links(q, &pt, 0, pl, max);
    if (n <= max) radinterp__sum_links(q, &pt, pl, n, 1, h);
    else {   /* too many to rank: every one exactly, a chunk at a time */
        uint32_t at;
        for (at = 0; at < n; at += max) {
            if (at) radinterp__point_links(q, &pt, at, pl, max);
            radinterp__sum_links(q, &pt, pl, n - at < max ? n - at : max, 0, h);
        }
    }
    if (q->cdt_ready) radinterp__cdt_free(&q->cdt);
    if (triangulated) *triangulated = q->triangulated;
    return q->failed ? RADINTERP_ERROR_OUT_OF_MEMORY : RADINTERP_OK;
}

/* The same with room for RADINTERP__POINT_LINKS links on the stack. */
static radinterp_result radinterp__irradiance_listed(const radinterp_solution *s, const radinterp__leaf_lists *batch,
                                                     uint32_t patch, const float p[3], const float toward[3], double *h,
                                                     uint32_t *triangulated)
{
    radinterp__plink pl[RADINTERP__POINT_LINKS];   /* 20 KB */
    return radinterp__irradiance_in(s, patch, p, toward, h, triangulated, pl, RADINTERP__POINT_LINKS, batch);
}

/* Without lists built beforehand: each link's entry filtered as it is reached. */
static radinterp_result radinterp__irradiance(const radinterp_solution *s, uint32_t patch, const float p[3],
                                              const float toward[3], double *h, uint32_t *triangulated)
{
    return radinterp__irradiance_listed(s, NULL, patch, p, toward, h, triangulated);
}

RADINTERP_API radinterp_result radinterp_irradiance_at_point(const radinterp_solution *s, uint32_t patch,
                                                             const float p[3], const float toward[3], float rgb[3])
{
    double h[3];
    radinterp_result r;
    if (!rgb) return RADINTERP_ERROR_INVALID_ARGUMENT;
    r = radinterp__irradiance(s, radinterp__patch_of(s, patch), p, toward, h, NULL);
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
    patch = radinterp__patch_of(s, patch);
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

/* ======================================================================
   15. mesh building blocks: growable arrays, a hash map, patch frames
   Part 2 of the method (chapters 3 and 5) starts here. It reads the
   solution through its const interface (patches, nodes, links, blockers,
   radinterp__irradiance) and never changes it: the mesh keeps its own copy
   of the quadtrees, which it restricts and refines.
   ---------------------------------------------------------------------- */

/* Open addressing from keys of `words` 32-bit words to values (NONE marks
   an empty slot, so it cannot be stored). */
typedef struct radinterp__hmap {
    uint32_t *keys;
    uint32_t *vals;
    uint32_t cap, count, words;
} radinterp__hmap;

static uint32_t radinterp__hmap_hash(const uint32_t *k, uint32_t words)
{
    uint64_t h = 0x9E3779B97F4A7C15ull;
    uint32_t i;
    for (i = 0; i < words; i++) h = radinterp__mix64(h ^ ((uint64_t)k[i] << (i & 1 ? 32 : 0)) ^ i);
    return (uint32_t)(h >> 32);
}

static int radinterp__hmap_alloc(const radinterp_allocator *a, radinterp__hmap *m, uint32_t words, uint32_t cap)
{
    uint32_t i;
    m->keys = (uint32_t *)radinterp__alloc_array(a, (size_t)cap * words, sizeof(uint32_t));
    m->vals = (uint32_t *)radinterp__alloc_array(a, cap, sizeof(uint32_t));
    if (!m->keys || !m->vals) {
        radinterp__free(a, m->keys);
        radinterp__free(a, m->vals);
        m->keys = m->vals = NULL;
        return -1;
    }
    for (i = 0; i < cap; i++) m->vals[i] = RADINTERP__NONE;
    m->cap = cap;
    m->count = 0;
    m->words = words;
    return 0;
}

static int radinterp__hmap_init(const radinterp_allocator *a, radinterp__hmap *m, uint32_t words, uint32_t expected)
{
    uint32_t cap = 64;
    while (cap < 2u * expected + 1u) {
        if (cap > 0x3FFFFFFFu) return -1;
        cap *= 2;
    }
    return radinterp__hmap_alloc(a, m, words, cap);
}

static void radinterp__hmap_free(const radinterp_allocator *a, radinterp__hmap *m)
{
    radinterp__free(a, m->keys);
    radinterp__free(a, m->vals);
    memset(m, 0, sizeof *m);
}

static void radinterp__hmap_clear(radinterp__hmap *m)
{
    uint32_t i;
    for (i = 0; i < m->cap; i++) m->vals[i] = RADINTERP__NONE;
    m->count = 0;
}

static uint32_t radinterp__hmap_slot(const radinterp__hmap *m, const uint32_t *key)
{
    uint32_t i = radinterp__hmap_hash(key, m->words) & (m->cap - 1);
    while (m->vals[i] != RADINTERP__NONE &&
           memcmp(m->keys + (size_t)i * m->words, key, m->words * sizeof(uint32_t)) != 0)
        i = (i + 1) & (m->cap - 1);
    return i;
}

static uint32_t radinterp__hmap_get(const radinterp__hmap *m, const uint32_t *key)
{
    return m->cap ? m->vals[radinterp__hmap_slot(m, key)] : RADINTERP__NONE;
}

/* Stores key -> val unless key is present; returns the value stored for key
   (val, or the earlier one), or NONE when out of memory. */
static uint32_t radinterp__hmap_put(const radinterp_allocator *a, radinterp__hmap *m, const uint32_t *key, uint32_t val)
{
    uint32_t i;
    if (2u * (m->count + 1u) > m->cap) {
        radinterp__hmap old = *m;
        uint32_t j;
        if (m->cap > 0x3FFFFFFFu || radinterp__hmap_alloc(a, m, old.words, old.cap * 2) != 0) {
            *m = old;
            return RADINTERP__NONE;
        }
        for (j = 0; j < old.cap; j++) {
            if (old.vals[j] == RADINTERP__NONE) continue;
            i = radinterp__hmap_slot(m, old.keys + (size_t)j * old.words);
            memcpy(m->keys + (size_t)i * m->words, old.keys + (size_t)j * old.words, m->words * sizeof(uint32_t));
            m->vals[i] = old.vals[j];
            m->count++;
        }
        radinterp__hmap_free(a, &old);
    }
    i = radinterp__hmap_slot(m, key);
    if (m->vals[i] != RADINTERP__NONE) return m->vals[i];
    memcpy(m->keys + (size_t)i * m->words, key, m->words * sizeof(uint32_t));
    m->vals[i] = val;
    m->count++;
    return val;
}

/* Key of a float point (and a tag, e.g. a patch): its exact bits, with -0
   folded into +0 so that equal coordinates give equal keys. */
static void radinterp__point_key(const float *p, uint32_t tag, uint32_t *key)
{
    int k;
    for (k = 0; k < 3; k++) {
        float x = p[k] + 0.0f;
        memcpy(&key[k], &x, 4);
    }
    key[3] = tag;
}

/* The frame of a patch (section 13's frame): origin at its first corner, e1
   along its first edge, e2 = n x e1, so counter-clockwise in 2D is
   counter-clockwise seen from the front. */
static void radinterp__patch_frame(radinterp__frame *f, const radinterp__patch *pt)
{
    double v[2][3];
    radinterp__d3_from_f(pt->v[0], v[0]);
    radinterp__d3_from_f(pt->v[1], v[1]);
    radinterp__frame_make(f, (const double (*)[3])v, pt->n);
}

static void radinterp__frame_to2df(const radinterp__frame *f, const float *x, double *uv)
{
    double d[3];
    radinterp__d3_from_f(x, d);
    radinterp__frame_to2d(f, d, uv);
}

static void radinterp__frame_to3df(const radinterp__frame *f, const double *uv, float *x)
{
    double d[3];
    radinterp__frame_to3d(f, uv, d);
    x[0] = (float)d[0]; x[1] = (float)d[1]; x[2] = (float)d[2];
}

/* Clips the segment p + t (q - p), t in [0, 1], to the convex polygon poly
   (counter-clockwise) moved `inset` inward. Returns 1 when a piece of
   positive length remains: [*t0, *t1], with the polygon edge that cut each
   end (-1 where the segment's own end remains). */
static int radinterp__clip_segment2(const double (*poly)[2], int n, double inset, const double *p, const double *q,
                                    double *t0, double *t1, int *e0, int *e1)
{
    int i;
    *t0 = 0.0; *t1 = 1.0; *e0 = *e1 = -1;
    for (i = 0; i < n; i++) {
        const double *a = poly[i], *b = poly[radinterp__next(i, n)];
        double dx = b[0] - a[0], dy = b[1] - a[1], len = sqrt(dx * dx + dy * dy), fp, fq, t;
        if (!(len > 0.0)) continue;
        fp = (-dy * (p[0] - a[0]) + dx * (p[1] - a[1])) / len - inset;
        fq = (-dy * (q[0] - a[0]) + dx * (q[1] - a[1])) / len - inset;
        if (fp < 0.0 && fq < 0.0) return 0;
        if (fp >= 0.0 && fq >= 0.0) continue;
        t = fp / (fp - fq);
        if (fp < 0.0) { if (t > *t0) { *t0 = t; *e0 = i; } }
        else if (t < *t1) { *t1 = t; *e1 = i; }
        if (*t0 >= *t1) return 0;
    }
    return *t1 > *t0;
}

/* Distance from p to the segment (a, b), in 2D. */
static double radinterp__seg_dist(const double *a, const double *b, const double *p)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy, t = 0.0, x, y;
    if (l2 > 0.0) t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    x = a[0] + t * dx - p[0];
    y = a[1] + t * dy - p[1];
    return sqrt(x * x + y * y);
}

/* ======================================================================
   16. discontinuities (Hardt 5.2-5.4)
   For every receiver patch R and every source patch S linked to R's
   quadtree, with the union of those links' blockers B:
   - EV: a source edge e and a blocker vertex v span a wedge; the rays from e
     through v, continued to R's plane, trace a segment on R;
   - VE: a source vertex s and a blocker edge f likewise (rays from s through f);
   - horizon: S's plane splits R (one side of the line sees S's front);
   - contact: a patch resting on R (an edge of it lies on R).
   A wedge counts only when it is a real visual event: its plane supports
   the blocker at v (EV) or the source at s (VE), so the blocker's
   silhouette, seen from the source, changes across it. EEE surfaces are
   ignored, as in the thesis. Segments are clipped to the part of R in front
   of S and kept when they cross R's interior (not just run along its
   outline). Weight (5.3): w = max(d_sb / d_br) * B_src over the segment,
   geometric factor 1 for a horizon, infinite (FLT_MAX) for a contact. The
   geometric factor is computed once; the weight is cached with the state of
   the solution's radiosities and recomputed when they change (5.4).
   ---------------------------------------------------------------------- */
typedef struct radinterp__disc {
    double p[2], q[2];        /* endpoints in the receiver's frame (on the DSet line once grouped) */
    double t0, t1;            /* positions of p and q along the DSet line, t0 < t1 */
    uint32_t on0, on1;        /* 1 + the receiver outline edge that p / q lies on; 0 inside */
    uint32_t receiver, source, blocker, type, dset;
    float geom;               /* max(d_sb / d_br); 1 for a horizon; FLT_MAX for a contact */
    float reach;              /* largest unoccluded point form factor of the source on the receiver (FLT_MAX
                                 for a contact): B_src * reach bounds the irradiance the discontinuity changes */
    float weight;             /* cached geom * B_src */
    uint32_t weight_stamp;    /* radiosity state of the cached weight; 0 = not computed */
    uint32_t active;
    uint32_t found;           /* its record in the list the mesh returns (radinterp__disc_list) */
} radinterp__disc;

/* Every discontinuity found, as the mesh returns them, in blocks of
   2^RADINTERP__DISC_BLOCK_BITS records. The list grows without moving what
   it holds (a doubling array holds up to three times its contents while it
   grows: building_1k finds 2.5M discontinuities), and the mesh takes the
   blocks over as they are. */
#define RADINTERP__DISC_BLOCK_BITS 14
#define RADINTERP__DISC_BLOCK (1u << RADINTERP__DISC_BLOCK_BITS)
#define RADINTERP__DISC_MAX 0xFFFFFFF0u   /* records a list holds: indices are uint32_t */
typedef struct radinterp__disc_list {
    radinterp__buf blocks;    /* radinterp_discontinuity *, each RADINTERP__DISC_BLOCK records */
    uint32_t count;
    int trimmed;              /* the last block holds only its records (radinterp__disc_list_trim) */
} radinterp__disc_list;

static void radinterp__disc_list_init(radinterp__disc_list *l)
{
    radinterp__buf_init(&l->blocks, sizeof(radinterp_discontinuity *));
    l->count = 0;
    l->trimmed = 0;
}

static radinterp_discontinuity *radinterp__disc_list_at(const radinterp__disc_list *l, uint32_t i)
{
    return ((radinterp_discontinuity **)l->blocks.data)[i >> RADINTERP__DISC_BLOCK_BITS] + (i & (RADINTERP__DISC_BLOCK - 1u));
}

/* A new zeroed record at the end, or NULL when memory runs out or the list is full. */
static radinterp_discontinuity *radinterp__disc_list_push(const radinterp_allocator *a, radinterp__disc_list *l)
{
    radinterp_discontinuity *d;
    if (l->count >= RADINTERP__DISC_MAX || l->trimmed) return NULL;
    if ((l->count & (RADINTERP__DISC_BLOCK - 1u)) == 0) {
        radinterp_discontinuity **slot = (radinterp_discontinuity **)radinterp__buf_push(a, &l->blocks);
        if (!slot) return NULL;
        *slot = (radinterp_discontinuity *)radinterp__alloc_array(a, RADINTERP__DISC_BLOCK, sizeof **slot);
        if (!*slot) { l->blocks.count--; return NULL; }
    }
    d = radinterp__disc_list_at(l, l->count++);
    memset(d, 0, sizeof *d);
    return d;
}

/* Frees what the last block holds beyond the list's records, once the
   list is complete: a small mesh's list need not take a whole block
   (16,384 records, 852 KB). A trimmed list takes no more records. */
static int radinterp__disc_list_trim(const radinterp_allocator *a, radinterp__disc_list *l)
{
    uint32_t used = l->count & (RADINTERP__DISC_BLOCK - 1u);
    radinterp_discontinuity **last, *p;
    if (used && !l->trimmed) {
        last = (radinterp_discontinuity **)l->blocks.data + l->blocks.count - 1;
        p = (radinterp_discontinuity *)radinterp__alloc_array(a, used, sizeof *p);
        if (!p) return -1;
        memcpy(p, *last, used * sizeof *p);
        radinterp__free(a, *last);
        *last = p;
    }
    l->trimmed = 1;
    return 0;
}

/* The memory of the list's records (not of its array of blocks). */
static size_t radinterp__disc_list_bytes(const radinterp__disc_list *l)
{
    size_t records = l->trimmed ? l->count : l->blocks.count * (size_t)RADINTERP__DISC_BLOCK;
    return records * sizeof(radinterp_discontinuity);
}

static void radinterp__disc_list_free(const radinterp_allocator *a, radinterp__disc_list *l)
{
    size_t i;
    for (i = 0; i < l->blocks.count; i++) radinterp__free(a, ((radinterp_discontinuity **)l->blocks.data)[i]);
    radinterp__buf_free(a, &l->blocks);
    l->count = 0;
}

/* A DSet's line on a receiver (5.5.4): point o, unit direction d. */
typedef struct radinterp__dset { double o[2], d[2]; uint32_t receiver; } radinterp__dset;

/* A node of the mesh's own quadtrees (a copy of the solution's, restricted
   and refined). Children wind like their parent, as in the solution. */
typedef struct radinterp__mnode {
    float v[4][3];
    double uv[4][2];          /* corners in the patch frame */
    uint32_t count, patch, parent, child, depth;
    uint32_t first_disc, disc_count;   /* discontinuities impinging on it, by DSet (node_discs) */
    uint32_t leaf;            /* index in the leaf list of the current pass */
} radinterp__mnode;

/* An active discontinuity edge of a patch: the union of a DSet's active
   discontinuities that overlap (5.5.7). */
typedef struct radinterp__seg {
    double p[2], q[2];
    float a[3], b[3];
    uint32_t on0, on1;        /* 1 + outline edge of each end; 0 inside */
    uint32_t jump;            /* it holds a contact discontinuity: the irradiance may jump across it */
} radinterp__seg;

/* A vertex on a patch outline: a patch corner, a leaf corner on an outline
   edge, or the end of a discontinuity edge there. */
typedef struct radinterp__bvert {
    float x[3];
    uint32_t patch, edge;     /* the outline edge it lies on (a corner: the edge it starts) */
    uint32_t corner;          /* a corner of the patch */
    uint32_t rep;             /* the vertex it is welded to */
} radinterp__bvert;

typedef struct radinterp__otri {
    uint32_t v[3];
    uint32_t patch, node;
    uint32_t flags;           /* the edge flags of radinterp_mesh_data, and RADINTERP__EDGE_JUMP << k */
} radinterp__otri;
#define RADINTERP__EDGE_JUMP 64u  /* << k: edge k lies on a contact discontinuity (not exported) */

typedef struct radinterp__builder {
    const radinterp_solution *s;
    const radinterp_mesh_desc *desc;
    radinterp_allocator a;
    double tol;                      /* geometric tolerance: epsilon * diag */
    double weld;                     /* outline vertices closer than this are one */
    float min_weight;
    double min_contrast;             /* see min_discont_contrast */
    uint32_t hidden_events;          /* candidate EV/VE events whose generating line is blocked (not kept) */
    uint64_t event_tests;            /* radinterp__event_seen calls */
    uint32_t max_dsets;
    double refine_eps, refine_min_area, min_leaf_area;
    uint32_t refine_samples, refine_passes;
    radinterp__frame *frames;       /* per patch */
    double *outline;                 /* per patch: corners in its frame, 8 doubles */
    /* discontinuities: the list the mesh returns (the candidates, or every
       one found with keep_all_discontinuities), the count of each kind found
       (by radinterp_discontinuity_type), and the candidates
       (radinterp__candidate), grouped by receiver and by DSet inside */
    radinterp__disc_list found;
    uint32_t found_kinds[5];
    radinterp__buf discs, dsets;
    uint32_t *disc_first, *disc_count;
    /* quadtrees */
    radinterp__buf nodes, node_discs;
    uint32_t *roots;
    radinterp__hmap corners;         /* (corner, patch + 1) of every node */
    radinterp__buf leaves;           /* node ids, patch by patch */
    uint32_t *leaf_first, *leaf_count;
    /* one pass: discontinuity edges, outline vertices, output */
    radinterp__buf segs;
    uint32_t *seg_first, *seg_count;
    radinterp__buf pool;             /* radinterp__bvert */
    radinterp__hmap canon;           /* point -> pool index of its representative */
    uint32_t *pool_first;            /* per patch (+ 1): its outline vertices in pool */
    radinterp__buf chains;           /* per patch edge: representatives along it */
    uint32_t *chain_first, *chain_len;
    radinterp__buf pos, tris;        /* output of the pass */
    radinterp__hmap vmap;            /* point -> output vertex */
    double reported;                 /* RADINTERP_CPU_SECONDS() at the last progress call */
    size_t peak_bytes;               /* the most radinterp__note_bytes counted (radinterp_mesh_info.build_bytes) */
    /* statistics */
    uint32_t balance_splits, hanging, seam, fallback, degenerate, skipped;
    uint64_t samples;
    size_t leaf_list_bytes;          /* the largest batch of leaf lists held (radinterp__sample_listed) */
    int cancelled;
} radinterp__builder;

static void radinterp__mesh_log(const radinterp__builder *b, const char *fmt, ...)
{
    char msg[320];
    va_list ap;
    if (!b->desc->log) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    b->desc->log(b->desc->log_user, msg);
}

/* A progress call between the steps that come before the samples: (0, 1),
   none of the sampling's count done yet. A building's discontinuities and
   triangulations take seconds, during which the caller may still see
   progress and cancel. Non-zero: cancel. */
static int radinterp__mesh_cancelled(radinterp__builder *b)
{
    b->reported = RADINTERP_CPU_SECONDS();
    return b->desc->progress && b->desc->progress(b->desc->progress_user, 0, 1) != 0;
}

/* The same call inside one long serial step (a receiver that many sources
   light, a source with thousands of blockers between it and the receiver),
   once progress_interval has passed since the last call. */
static int radinterp__mesh_tick(radinterp__builder *b)
{
    if (!radinterp__progress_due(b->reported, b->desc->progress_interval)) return 0;
    return radinterp__mesh_cancelled(b);
}

/* radinterp__mesh_tick for loops of short steps (i counts them): the clock
   is read every RADINTERP__TICK_STEPS steps (the solve's loops start there
   and widen the stride: radinterp__solve_step). */
static int radinterp__mesh_step(radinterp__builder *b, size_t i)
{
    return i % RADINTERP__TICK_STEPS == 0 && radinterp__mesh_tick(b);
}

/* The result of a step that returns 0, -1 (memory) or 1 (cancel). */
static radinterp_result radinterp__step_result(int r)
{
    return r > 0 ? RADINTERP_ERROR_CANCELLED : (r < 0 ? RADINTERP_ERROR_OUT_OF_MEMORY : RADINTERP_OK);
}

static size_t radinterp__hmap_bytes(const radinterp__hmap *m) { return (size_t)m->cap * (m->words + 1u) * sizeof(uint32_t); }

/* Bytes the builder's arrays hold now (their capacities), plus `extra`
   held beside them; the peak is kept for radinterp_mesh_info.build_bytes.
   Taken at the build's steps: short-lived work arrays inside a step are not
   counted. */
static void radinterp__note_bytes(radinterp__builder *b, size_t extra)
{
    const radinterp__buf *bufs[11];
    size_t n = extra + radinterp__disc_list_bytes(&b->found), k;
    size_t P = b->s->patch_count;
    bufs[0] = &b->found.blocks; bufs[1] = &b->discs; bufs[2] = &b->dsets; bufs[3] = &b->nodes; bufs[4] = &b->node_discs;
    bufs[5] = &b->leaves; bufs[6] = &b->segs; bufs[7] = &b->pool; bufs[8] = &b->chains; bufs[9] = &b->pos;
    bufs[10] = &b->tris;
    for (k = 0; k < 11; k++) n += bufs[k]->cap * bufs[k]->item;
    n += radinterp__hmap_bytes(&b->corners) + radinterp__hmap_bytes(&b->canon) + radinterp__hmap_bytes(&b->vmap);
    n += P * (sizeof(radinterp__frame) + 8 * sizeof(double) + 15 * sizeof(uint32_t));   /* the per-patch arrays */
    n += (b->pool_first ? P + 1 : 0) * sizeof(uint32_t);
    if (n > b->peak_bytes) b->peak_bytes = n;
}

/* Largest channel of a patch's radiosity: B_src of the weights. */
static float radinterp__brightness(const radinterp_solution *s, uint32_t patch)
{
    const float *b = s->nodes[s->patches[patch].root].b;
    return radinterp__maxf(b[0], radinterp__maxf(b[1], b[2]));
}

/* Changes whenever the solver runs another gather and push-pull. */
static uint32_t radinterp__radiosity_stamp(const radinterp_solution *s) { return s->iterations + 1u; }

/* The weight of a discontinuity (5.3), from the cache while the radiosities
   it was computed with still hold (5.4). */
static float radinterp__disc_weight(const radinterp_solution *s, radinterp__disc *d)
{
    uint32_t stamp = radinterp__radiosity_stamp(s);
    if (d->weight_stamp != stamp) {
        if (d->type == RADINTERP_DISCONTINUITY_CONTACT) {
            d->weight = FLT_MAX;
        } else {
            double w = (double)d->geom * radinterp__brightness(s, d->source);
            d->weight = w > FLT_MAX ? FLT_MAX : (float)w;
        }
        d->weight_stamp = stamp;
    }
    return d->weight;
}

/* A candidate discontinuity (5.3, 5.5.6): weight at least min_discont_weight,
   and a source that can change the receiver's irradiance by at least
   min_discont_contrast of its mean (a contact always can). Uses the cached
   weight (radinterp__disc_weight). */
static int radinterp__candidate(const radinterp__builder *b, const radinterp__disc *d)
{
    const radinterp_solution *s = b->s;
    if (!(d->weight >= b->min_weight)) return 0;
    if (d->type == RADINTERP_DISCONTINUITY_CONTACT) return 1;
    return (double)radinterp__brightness(s, d->source) * d->reach >=
           b->min_contrast * s->nodes[s->patches[d->receiver].root].level;
}

static const double (*radinterp__outline_of(const radinterp__builder *b, uint32_t patch))[2]
{
    return (const double (*)[2])(b->outline + 8 * (size_t)patch);
}

/* The part of receiver R in front of S's plane, in R's frame, with the R
   outline edge each of its edges lies on (-1: the cut along S's plane).
   Returns its corner count, 0 when no part of R is in front of S. */
static int radinterp__front_region(const radinterp__builder *b, uint32_t R, uint32_t S, double (*out)[2], int *label)
{
    const radinterp__patch *pr = &b->s->patches[R], *ps = &b->s->patches[S];
    const double (*uv)[2] = radinterp__outline_of(b, R);
    double g[4], lo = DBL_MAX, hi = -DBL_MAX;
    int n = (int)pr->count, i, m = 0;
    for (i = 0; i < n; i++) {
        double x[3];
        radinterp__d3_from_f(pr->v[i], x);
        g[i] = radinterp__d3_dot(ps->n, x) - ps->d;
        lo = g[i] < lo ? g[i] : lo;
        hi = g[i] > hi ? g[i] : hi;
    }
    if (hi <= b->tol) return 0;
    if (lo >= -b->tol) {
        for (i = 0; i < n; i++) { out[i][0] = uv[i][0]; out[i][1] = uv[i][1]; label[i] = i; }
        return n;
    }
    for (i = 0; i < n; i++) {
        int j = (i + 1) % n;
        double s = g[i] / (g[i] - g[j]);
        if (g[i] >= 0.0) {
            out[m][0] = uv[i][0]; out[m][1] = uv[i][1]; label[m++] = i;
            if (g[j] < 0.0) {
                out[m][0] = uv[i][0] + s * (uv[j][0] - uv[i][0]);
                out[m][1] = uv[i][1] + s * (uv[j][1] - uv[i][1]);
                label[m++] = -1;
            }
        } else if (g[j] >= 0.0) {
            out[m][0] = uv[i][0] + s * (uv[j][0] - uv[i][0]);
            out[m][1] = uv[i][1] + s * (uv[j][1] - uv[i][1]);
            label[m++] = i;
        }
    }
    return m;
}

/* 1 + the outline edge of R within tol of uv, or 0. */
static uint32_t radinterp__on_outline(const radinterp__builder *b, uint32_t R, const double *uv)
{
    const double (*o)[2] = radinterp__outline_of(b, R);
    uint32_t i, n = b->s->patches[R].count;
    for (i = 0; i < n; i++)
        if (radinterp__seg_dist(o[i], o[(i + 1) % n], uv) <= b->tol) return i + 1;
    return 0;
}

/* Clips the segment (p, q) of R's plane to region: 1 with the clipped ends
   when a piece of it crosses the region's interior (not only its outline). */
static int radinterp__clip_to_region(const radinterp__builder *b, uint32_t R, const double (*region)[2], const int *label,
                                     int n, const double *p, const double *q, double *cp, double *cq, uint32_t *on_p,
                                     uint32_t *on_q)
{
    double t0, t1, len;
    int e0, e1;
    if (!radinterp__clip_segment2(region, n, b->tol, p, q, &t0, &t1, &e0, &e1)) return 0;
    if (!radinterp__clip_segment2(region, n, 0.0, p, q, &t0, &t1, &e0, &e1)) return 0;
    cp[0] = p[0] + t0 * (q[0] - p[0]); cp[1] = p[1] + t0 * (q[1] - p[1]);
    cq[0] = p[0] + t1 * (q[0] - p[0]); cq[1] = p[1] + t1 * (q[1] - p[1]);
    len = sqrt((cq[0] - cp[0]) * (cq[0] - cp[0]) + (cq[1] - cp[1]) * (cq[1] - cp[1]));
    if (!(len > b->tol)) return 0;
    *on_p = e0 >= 0 && label[e0] >= 0 ? (uint32_t)label[e0] + 1 : (e0 < 0 ? radinterp__on_outline(b, R, cp) : 0);
    *on_q = e1 >= 0 && label[e1] >= 0 ? (uint32_t)label[e1] + 1 : (e1 < 0 ? radinterp__on_outline(b, R, cq) : 0);
    return 1;
}

static int radinterp__push_disc(radinterp__builder *b, uint32_t R, const double *p, const double *q, uint32_t on_p,
                                uint32_t on_q, uint32_t type, uint32_t S, uint32_t B, double geom)
{
    radinterp__disc *d = (radinterp__disc *)radinterp__buf_push(&b->a, &b->discs);
    if (!d) return -1;
    d->p[0] = p[0]; d->p[1] = p[1];
    d->q[0] = q[0]; d->q[1] = q[1];
    d->on0 = on_p;
    d->on1 = on_q;
    d->receiver = R;
    d->source = S;
    d->blocker = B;
    d->type = type;
    d->geom = geom > FLT_MAX ? FLT_MAX : (float)geom;
    d->reach = FLT_MAX;   /* the source's discontinuities get theirs once all are found (radinterp__receiver_discs) */
    return 0;
}

/* Restricts u in [*u0, *u1] to f0 + u (f1 - f0) >= thr. */
static int radinterp__clip_linear(double f0, double f1, double thr, double *u0, double *u1)
{
    double d = f1 - f0, u;
    if (d == 0.0) return f0 >= thr && *u0 < *u1;
    u = (thr - f0) / d;
    if (d > 0.0) { if (u > *u0) *u0 = u; }
    else if (u < *u1) *u1 = u;
    return *u0 < *u1;
}

/* The trace of a wedge on receiver R's plane: rays from a(u) through c(u),
   u in [0, 1], continued past c(u) (one of a, c is a fixed point: the
   blocker vertex of an EV wedge, the source vertex of a VE wedge). Only
   rays that meet the plane after passing c, with c in front of R and of
   the source, count; the trace of the others' limit is a ray, cut where
   the projection grows past 1/tol. Returns 1 with the ends p, q (3D). */
static int radinterp__wedge_trace(const radinterp__builder *b, const radinterp__patch *pr, const radinterp__patch *ps,
                                  const double *a0, const double *a1, const double *c0, const double *c1, double *p,
                                  double *q)
{
    double ha0 = radinterp__d3_dot(pr->n, a0) - pr->d, ha1 = radinterp__d3_dot(pr->n, a1) - pr->d;
    double hc0 = radinterp__d3_dot(pr->n, c0) - pr->d, hc1 = radinterp__d3_dot(pr->n, c1) - pr->d;
    double fs0 = radinterp__d3_dot(ps->n, c0) - ps->d, fs1 = radinterp__d3_dot(ps->n, c1) - ps->d;
    double u0 = 0.0, u1 = 1.0, ends[2];
    int e, k;
    if (!radinterp__clip_linear(hc0, hc1, b->tol, &u0, &u1)) return 0;
    if (!radinterp__clip_linear(ha0 - hc0, ha1 - hc1, b->tol, &u0, &u1)) return 0;
    if (!radinterp__clip_linear(fs0, fs1, b->tol, &u0, &u1)) return 0;
    ends[0] = u0;
    ends[1] = u1;
    for (e = 0; e < 2; e++) {
        double u = ends[e], a[3], c[3], ha, hc, t, *r = e ? q : p;
        for (k = 0; k < 3; k++) {
            a[k] = a0[k] + u * (a1[k] - a0[k]);
            c[k] = c0[k] + u * (c1[k] - c0[k]);
        }
        ha = ha0 + u * (ha1 - ha0);
        hc = hc0 + u * (hc1 - hc0);
        t = hc / (ha - hc);
        for (k = 0; k < 3; k++) r[k] = c[k] + t * (c[k] - a[k]);
    }
    return 1;
}

/* The point x of the line (l0, l1) on the line through f and r (the two
   lines lie in one wedge plane). Returns 0 when they are parallel. */
static int radinterp__line_meet(const double *l0, const double *l1, const double *f, const double *r, double *x)
{
    double d1[3], d2[3], w[3], a, bb, c, d, e, den, t;
    radinterp__d3_sub(l1, l0, d1);
    radinterp__d3_sub(r, f, d2);
    radinterp__d3_sub(l0, f, w);
    a = radinterp__d3_dot(d1, d1);
    bb = radinterp__d3_dot(d1, d2);
    c = radinterp__d3_dot(d2, d2);
    d = radinterp__d3_dot(d1, w);
    e = radinterp__d3_dot(d2, w);
    den = a * c - bb * bb;
    if (!(den > 1e-14 * a * c)) return 0;
    t = (bb * e - c * d) / den;
    x[0] = l0[0] + t * d1[0];
    x[1] = l0[1] + t * d1[1];
    x[2] = l0[2] + t * d1[2];
    return 1;
}

static double radinterp__d3_dist(const double *a, const double *b)
{
    double d[3];
    radinterp__d3_sub(a, b, d);
    return radinterp__d3_len(d);
}

/* d_sb / d_br along the wedge's line through receiver point r (5.3). EV:
   the fixed point f is the blocker vertex and the line meets the source
   edge (l0, l1) at x: |f - x| / |r - f|. VE: f is the source vertex and the
   line meets the blocker edge at y: |y - f| / |r - y|. */
static double radinterp__wedge_ratio(int ev, const double *f, const double *l0, const double *l1, const double *r)
{
    double x[3], dsb, dbr;
    if (!radinterp__line_meet(l0, l1, f, r, x)) return 0.0;
    dsb = radinterp__d3_dist(f, x);
    dbr = ev ? radinterp__d3_dist(r, f) : radinterp__d3_dist(r, x);
    return dbr > 0.0 ? dsb / dbr : DBL_MAX;
}

/* Do all points lie on one side of the plane through o with unit normal m? */
static int radinterp__supports(const double *m, const double *o, const double (*pts)[3], int n, double tol)
{
    int i, pos = 0, neg = 0;
    for (i = 0; i < n; i++) {
        double d[3], h;
        radinterp__d3_sub(pts[i], o, d);
        h = radinterp__d3_dot(m, d);
        pos |= h > tol;
        neg |= h < -tol;
    }
    return !(pos && neg);
}

/* Unit normal of the plane through a, b, c; 0 when they are (nearly) collinear. */
static int radinterp__plane_normal(const double *a, const double *b, const double *c, double *m)
{
    double e1[3], e2[3], len, l1, l2;
    radinterp__d3_sub(b, a, e1);
    radinterp__d3_sub(c, a, e2);
    radinterp__d3_cross(e1, e2, m);
    len = radinterp__d3_len(m);
    l1 = radinterp__d3_len(e1);
    l2 = radinterp__d3_len(e2);
    if (!(len > 1e-9 * l1 * l2)) return 0;
    m[0] /= len; m[1] /= len; m[2] /= len;
    return 1;
}

typedef struct radinterp__wedge_ctx {
    uint32_t R, S, B;
    const double (*region)[2];
    const int *label;
    int region_n;
    int may_count;        /* the source reaches R enough for its discontinuities to be candidates */
    double geom_min;      /* the least geometric factor of a candidate (min_discont_weight / B_src) */
} radinterp__wedge_ctx;

/* Is the open segment from a to b clear? Its ends are pulled in by a
   millionth of its length plus tol, so that the surfaces it starts and
   ends on, and a blocker it grazes there, do not count. Panes let it pass. */
static int radinterp__inner_segment_open(const radinterp__builder *b, const double *a, const double *c)
{
    double d[3], len, t, x0[3], x1[3], T[3];
    int k;
    radinterp__d3_sub(c, a, d);
    len = radinterp__d3_len(d);
    if (!(len > 0.0)) return 1;
    t = 1e-6 + b->tol / len;
    if (t >= 0.5) return 1;
    for (k = 0; k < 3; k++) {
        x0[k] = a[k] + t * d[k];
        x1[k] = c[k] - t * d[k];
    }
    return radinterp__segment_light(b->s, x0, x1, b->s->glass_patches != 0, T) >= 0;
}

/* Does the EV or VE event behind a candidate discontinuity happen? Its
   generating line, from a point r of the discontinuity through the blocker
   feature (vertex f of an EV, the point of the blocker edge (l0, l1) for a
   VE) to the source (its edge (l0, l1) for an EV, its vertex f for a VE),
   must be clear of other surfaces: where something else stands on it, the
   blocker's shadow edge lies inside another shadow (or the edge is a crease
   of a solid, not an outline seen from the source) and the irradiance is
   smooth there. Tested at the segment's middle and quarter points; the
   discontinuity is kept whole when any one of them sees the event. This is
   the visibility clipping of discontinuity meshing (Lischinski, Tampieri and
   Greenberg 1992) reduced to three points. */
static int radinterp__event_seen(const radinterp__builder *b, int ev, const double *f, const double *l0,
                                 const double *l1, const radinterp__frame *fr, const double *cp, const double *cq)
{
    static const double at[3] = {0.5, 0.25, 0.75};
    int i;
    for (i = 0; i < 3; i++) {
        double uv[2], r[3], x[3];
        const double *blocker_point = ev ? f : x, *source_point = ev ? x : f;
        uv[0] = cp[0] + at[i] * (cq[0] - cp[0]);
        uv[1] = cp[1] + at[i] * (cq[1] - cp[1]);
        radinterp__frame_to3d(fr, uv, r);
        if (!radinterp__line_meet(l0, l1, f, r, x)) continue;
        if (radinterp__inner_segment_open(b, r, blocker_point) && radinterp__inner_segment_open(b, blocker_point, source_point))
            return 1;
    }
    return 0;
}

/* Blockers, or event tests (radinterp__event_seen), between clock readings:
   most cost microseconds, some milliseconds (building_4k: a source's 22
   blockers took 9.3 s, about 0.4 s each, in their event tests' rays). */
#define RADINTERP__WEDGE_TICK 8

/* Trace (3D ends p3, q3) -> clipped segment on R with its geometric factor.
   0, or -1 when memory runs out, 1 when progress asks to cancel. */
static int radinterp__wedge_disc(radinterp__builder *b, const radinterp__wedge_ctx *w, int ev, const double *f,
                                 const double *l0, const double *l1, const double *p3, const double *q3)
{
    const radinterp__frame *fr = &b->frames[w->R];
    double p[2], q[2], cp[2], cq[2], r[3], geom, g2;
    uint32_t on_p, on_q;
    radinterp__frame_to2d(fr, p3, p);
    radinterp__frame_to2d(fr, q3, q);
    if (!radinterp__clip_to_region(b, w->R, w->region, w->label, w->region_n, p, q, cp, cq, &on_p, &on_q)) return 0;
    radinterp__frame_to3d(fr, cp, r);
    geom = radinterp__wedge_ratio(ev, f, l0, l1, r);
    radinterp__frame_to3d(fr, cq, r);
    g2 = radinterp__wedge_ratio(ev, f, l0, l1, r);
    if (g2 > geom) geom = g2;
    if (w->may_count && geom >= w->geom_min) {
        if (++b->event_tests % RADINTERP__WEDGE_TICK == 0 && radinterp__mesh_tick(b)) return 1;
        if (!radinterp__event_seen(b, ev, f, l0, l1, fr, cp, cq)) {
            b->hidden_events++;
            return 0;
        }
    }
    return radinterp__push_disc(b, w->R, cp, cq, on_p, on_q,
                                ev ? RADINTERP_DISCONTINUITY_EV : RADINTERP_DISCONTINUITY_VE, w->S, w->B, geom);
}

/* EV and VE discontinuities of one source (clipped to R's front: Sc) and
   one blocker on R. 0, -1 (memory) or 1 (cancel), as radinterp__wedge_disc. */
static int radinterp__wedges(radinterp__builder *b, const radinterp__wedge_ctx *w, const double (*Sc)[3], int nc)
{
    const radinterp_solution *s = b->s;
    const radinterp__patch *pr = &s->patches[w->R], *ps = &s->patches[w->S], *pb = &s->patches[w->B];
    double B[4][3], m[3], p3[3], q3[3];
    int nb = radinterp__patch_poly(pb, B), i, k, r;
    /* EV: source edge (Sc[k], Sc[k+1]), blocker vertex B[i] */
    for (k = 0; k < nc; k++) {
        const double *e0 = Sc[k], *e1 = Sc[(k + 1) % nc];
        for (i = 0; i < nb; i++) {
            if (radinterp__d3_dot(ps->n, B[i]) - ps->d <= b->tol) continue;  /* behind the source */
            if (!radinterp__plane_normal(e0, e1, B[i], m)) continue;
            if (fabs(radinterp__d3_dot(m, ps->n)) > 1.0 - 1e-9) continue;     /* the source's own plane */
            if (!radinterp__supports(m, e0, (const double (*)[3])B, nb, b->tol)) continue;
            if (!radinterp__wedge_trace(b, pr, ps, e0, e1, B[i], B[i], p3, q3)) continue;
            if ((r = radinterp__wedge_disc(b, w, 1, B[i], e0, e1, p3, q3)) != 0) return r;
        }
    }
    /* VE: source vertex Sc[k], blocker edge (B[i], B[i+1]) */
    for (k = 0; k < nc; k++) {
        for (i = 0; i < nb; i++) {
            const double *f0 = B[i], *f1 = B[(i + 1) % nb];
            if (!radinterp__plane_normal(f0, f1, Sc[k], m)) continue;
            if (fabs(radinterp__d3_dot(m, pb->n)) > 1.0 - 1e-9) continue;     /* the blocker's own plane */
            if (!radinterp__supports(m, f0, Sc, nc, b->tol)) continue;
            if (!radinterp__wedge_trace(b, pr, ps, Sc[k], Sc[k], f0, f1, p3, q3)) continue;
            if ((r = radinterp__wedge_disc(b, w, 0, Sc[k], f0, f1, p3, q3)) != 0) return r;
        }
    }
    return 0;
}

/* Horizon: S's plane splits R; the line is one on both sides. */
static int radinterp__horizon(radinterp__builder *b, uint32_t R, uint32_t S)
{
    const radinterp__patch *pr = &b->s->patches[R], *ps = &b->s->patches[S];
    const double (*uv)[2] = radinterp__outline_of(b, R);
    double g[4], lo = DBL_MAX, hi = -DBL_MAX, pts[2][2];
    uint32_t on[2];
    int n = (int)pr->count, i, m = 0;
    for (i = 0; i < n; i++) {
        double x[3];
        radinterp__d3_from_f(pr->v[i], x);
        g[i] = radinterp__d3_dot(ps->n, x) - ps->d;
        lo = g[i] < lo ? g[i] : lo;
        hi = g[i] > hi ? g[i] : hi;
    }
    if (!(lo < -b->tol && hi > b->tol)) return 0;
    for (i = 0; i < n && m < 2; i++) {
        int j = (i + 1) % n;
        double t;
        if ((g[i] >= 0.0) == (g[j] >= 0.0)) continue;
        t = g[i] / (g[i] - g[j]);
        pts[m][0] = uv[i][0] + t * (uv[j][0] - uv[i][0]);
        pts[m][1] = uv[i][1] + t * (uv[j][1] - uv[i][1]);
        on[m++] = (uint32_t)i + 1;
    }
    if (m < 2) return 0;
    if (radinterp__seg_dist(pts[0], pts[0], pts[1]) <= b->tol) return 0;
    return radinterp__push_disc(b, R, pts[0], pts[1], on[0], on[1], RADINTERP_DISCONTINUITY_HORIZON, S,
                                RADINTERP_NO_PATCH, 1.0);
}

/* Contact: edges of other patches lying on R, with the patch rising in
   front of R (or lying flat on it, facing the same way). */
static int radinterp__contacts(radinterp__builder *b, uint32_t R, radinterp__buf *near)
{
    const radinterp_solution *s = b->s;
    const radinterp__patch *pr = &s->patches[R];
    const double (*uv)[2] = radinterp__outline_of(b, R);
    int labels[4] = {0, 1, 2, 3};
    uint32_t m;
    if (radinterp__patches_near(s, &b->a, pr->lo, pr->hi, b->tol, near) != 0) return -1;
    for (m = 0; m < near->count; m++) {
        uint32_t B = RADINTERP__U32(*near)[m];
        const radinterp__patch *pb = &s->patches[B];
        double V[4][3], h[4], lo = DBL_MAX, hi = -DBL_MAX;
        int n, i;
        if (B == R || !pb->count) continue;
        n = radinterp__patch_poly(pb, V);
        for (i = 0; i < n; i++) {
            h[i] = radinterp__d3_dot(pr->n, V[i]) - pr->d;
            lo = h[i] < lo ? h[i] : lo;
            hi = h[i] > hi ? h[i] : hi;
        }
        if (lo < -b->tol) continue;                                            /* reaches behind R */
        if (hi <= b->tol && radinterp__d3_dot(pb->n, pr->n) < 0.5) continue;   /* flat but facing R */
        for (i = 0; i < n; i++) {
            int j = (i + 1) % n;
            double p[2], q[2], cp[2], cq[2];
            uint32_t on_p, on_q;
            if (fabs(h[i]) > b->tol || fabs(h[j]) > b->tol) continue;
            radinterp__frame_to2d(&b->frames[R], V[i], p);
            radinterp__frame_to2d(&b->frames[R], V[j], q);
            if (!radinterp__clip_to_region(b, R, uv, labels, (int)pr->count, p, q, cp, cq, &on_p, &on_q)) continue;
            if (radinterp__push_disc(b, R, cp, cq, on_p, on_q, RADINTERP_DISCONTINUITY_CONTACT, RADINTERP_NO_PATCH, B,
                                     FLT_MAX) != 0)
                return -1;
        }
    }
    return 0;
}

/* Source and blocker pairs of every link delivering to R's quadtree. */
static int radinterp__link_pairs(radinterp__builder *b, uint32_t R, radinterp__buf *pairs, radinterp__buf *stack)
{
    const radinterp_solution *s = b->s;
    uint32_t l, k;
    pairs->count = 0;
    stack->count = 0;
    if (radinterp__buf_u32(&b->a, stack, s->patches[R].root) != 0) return -1;
    while (stack->count) {
        const radinterp__node *nd = &s->nodes[RADINTERP__U32(*stack)[--stack->count]];
        for (l = nd->first_link; l < nd->first_link + nd->link_count; l++) {
            const radinterp__link *lk = &s->links[l];
            uint64_t S = s->nodes[lk->source].patch, *e;
            if (lk->blocker_count == 0) {
                if (!(e = (uint64_t *)radinterp__buf_push(&b->a, pairs))) return -1;
                *e = S << 32 | RADINTERP__NONE;
            }
            for (k = 0; k < lk->blocker_count; k++) {
                if (!(e = (uint64_t *)radinterp__buf_push(&b->a, pairs))) return -1;
                *e = S << 32 | s->blockers[lk->first_blocker + k];
            }
        }
        if (nd->child != RADINTERP__NONE)
            for (k = 0; k < 4; k++)
                if (radinterp__buf_u32(&b->a, stack, nd->child + k) != 0) return -1;
    }
    if (pairs->count) qsort(pairs->data, pairs->count, sizeof(uint64_t), radinterp__cmp_u64);
    return 0;
}

/* The largest unoccluded point form factor (eq. 6.1) of source Sc (S
   clipped to R's front) at points of R's part in front of S (region): its
   corners, its centroid and its point nearest to the source's centroid,
   where a source facing R is seen largest. An estimate from below of the
   maximum over the region, close where it matters: a source that barely
   reaches R (small factor everywhere) is small at all these points. */
static double radinterp__source_reach(const radinterp__builder *b, uint32_t R, const double (*region)[2], int rn,
                                      const double (*Sc)[3], int nc)
{
    const radinterp__patch *pr = &b->s->patches[R];
    double pts[RADINTERP__POLY_MAX + 2][3], c2[2] = {0.0, 0.0}, sc[3] = {0.0, 0.0, 0.0}, best = 0.0;
    int i, k;
    for (i = 0; i < rn; i++) {
        radinterp__frame_to3d(&b->frames[R], region[i], pts[i]);
        c2[0] += region[i][0] / rn;
        c2[1] += region[i][1] / rn;
    }
    for (i = 0; i < nc; i++)
        for (k = 0; k < 3; k++) sc[k] += Sc[i][k] / nc;
    radinterp__frame_to3d(&b->frames[R], c2, pts[rn]);
    radinterp__poly_nearest((const double (*)[3])pts, rn, pr->n, sc, pts[rn + 1]);
    for (i = 0; i < rn + 2; i++) {
        double f = radinterp__ff_poly(pts[i], pr->n, Sc, nc);
        if (f > best) best = f;
    }
    return best;
}

/* Every discontinuity on receiver R (5.5.3: from the links, so only
   mutually visible pairs and their potential blockers are considered).
   0, or -1 when memory runs out, 1 when progress asks to cancel. */
static int radinterp__receiver_discs(radinterp__builder *b, uint32_t R, radinterp__buf *pairs, radinterp__buf *stack)
{
    const radinterp_solution *s = b->s;
    const uint64_t *pr;
    size_t i = 0, j, wedged = 0;
    int r;
    if (radinterp__link_pairs(b, R, pairs, stack) != 0) return -1;
    pr = (const uint64_t *)pairs->data;
    while (i < pairs->count) {
        uint32_t S = (uint32_t)(pr[i] >> 32);
        double region[RADINTERP__POLY_MAX][2], S3[RADINTERP__POLY_MAX][3], Sc[RADINTERP__POLY_MAX][3];
        int label[RADINTERP__POLY_MAX], rn, nc;
        radinterp__wedge_ctx w;
        for (j = i; j < pairs->count && (uint32_t)(pr[j] >> 32) == S; j++) {}
        if (S == R || !(radinterp__brightness(s, S) > 0.0f)) { i = j; continue; }
        if (radinterp__mesh_tick(b)) return 1;
        rn = radinterp__front_region(b, R, S, region, label);
        if (rn >= 3) {
            size_t from = b->discs.count, m;
            double bright = radinterp__brightness(s, S);
            float reach;
            if (radinterp__horizon(b, R, S) != 0) return -1;
            nc = radinterp__clip_poly((const double (*)[3])S3, radinterp__patch_poly(&s->patches[S], S3),
                                      s->patches[R].n, s->patches[R].d, Sc);
            reach = nc >= 3 ? (float)radinterp__source_reach(b, R, (const double (*)[2])region, rn,
                                                             (const double (*)[3])Sc, nc) : 0.0f;
            w.R = R;
            w.S = S;
            w.region = (const double (*)[2])region;
            w.label = label;
            w.region_n = rn;
            w.may_count = bright * reach >= b->min_contrast * s->nodes[s->patches[R].root].level;
            w.geom_min = b->min_weight / bright;
            for (; i < j && nc >= 3; i++) {
                uint32_t B = (uint32_t)(pr[i] & 0xFFFFFFFFu);
                if (B == RADINTERP__NONE || B == R || B == S || !s->patches[B].count) continue;
                if (i > 0 && pr[i - 1] == pr[i]) continue;
                /* building_4k: 380 blockers of one source took 2.8 s (6882 discontinuities) */
                if (++wedged % RADINTERP__WEDGE_TICK == 0 && radinterp__mesh_tick(b)) return 1;
                w.B = B;
                if ((r = radinterp__wedges(b, &w, (const double (*)[3])Sc, nc)) != 0) return r;
            }
            for (m = from; m < b->discs.count; m++) ((radinterp__disc *)b->discs.data)[m].reach = reach;
        }
        i = j;
    }
    return radinterp__contacts(b, R, stack);
}

/* ---- DSets: collinear discontinuities on a receiver (5.5.4) ------------ */

typedef struct radinterp__dkey { double angle, offset; uint32_t id; } radinterp__dkey;

static int radinterp__cmp_dkey_angle(const void *a, const void *b)
{
    const radinterp__dkey *x = (const radinterp__dkey *)a, *y = (const radinterp__dkey *)b;
    if (x->angle != y->angle) return x->angle < y->angle ? -1 : 1;
    return x->id < y->id ? -1 : (x->id > y->id);
}

static int radinterp__cmp_dkey_offset(const void *a, const void *b)
{
    const radinterp__dkey *x = (const radinterp__dkey *)a, *y = (const radinterp__dkey *)b;
    if (x->offset != y->offset) return x->offset < y->offset ? -1 : 1;
    return x->id < y->id ? -1 : (x->id > y->id);
}

static int radinterp__cmp_disc_order(const void *a, const void *b)
{
    const radinterp__disc *x = (const radinterp__disc *)a, *y = (const radinterp__disc *)b;
    if (x->dset != y->dset) return x->dset < y->dset ? -1 : 1;
    if (x->t0 != y->t0) return x->t0 < y->t0 ? -1 : 1;
    if (x->t1 != y->t1) return x->t1 < y->t1 ? -1 : 1;
    return x->type < y->type ? -1 : (x->type > y->type);
}

#define RADINTERP__DSET_ANGLE 1e-6   /* radians: lines closer in direction may be one */
#define RADINTERP__DSET_CUT 0.3      /* line directions are taken in [cut, cut + pi): an angle no axis-aligned line has */

static int radinterp__new_dset(radinterp__builder *b, uint32_t R, const double *o, const double *d)
{
    radinterp__dset *ds = (radinterp__dset *)radinterp__buf_push(&b->a, &b->dsets);
    if (!ds) return -1;
    ds->o[0] = o[0]; ds->o[1] = o[1];
    ds->d[0] = d[0]; ds->d[1] = d[1];
    ds->receiver = R;
    return 0;
}

/* Places disc on line (o, d) of DSet id: ends projected on the line,
   ordered along it. */
static void radinterp__disc_on_line(radinterp__disc *x, const double *o, const double *d, uint32_t id)
{
    double tp = (x->p[0] - o[0]) * d[0] + (x->p[1] - o[1]) * d[1];
    double tq = (x->q[0] - o[0]) * d[0] + (x->q[1] - o[1]) * d[1];
    x->dset = id;
    if (tp > tq) {
        double t = tp;
        uint32_t on = x->on0;
        tp = tq; tq = t;
        x->on0 = x->on1; x->on1 = on;
    }
    x->t0 = tp;
    x->t1 = tq;
    x->p[0] = o[0] + tp * d[0]; x->p[1] = o[1] + tp * d[1];
    x->q[0] = o[0] + tq * d[0]; x->q[1] = o[1] + tq * d[1];
}

/* Groups R's discontinuities into DSets (lines within RADINTERP__DSET_ANGLE
   and tol of each other) and orders them by DSet, then along it. 0, or -1
   when memory runs out, 1 when progress asks to cancel (a receiver can hold
   millions: building_4k's took up to 8.2 s here). */
static int radinterp__group_dsets(radinterp__builder *b, uint32_t R)
{
    radinterp__disc *dd;
    uint32_t n = b->disc_count[R], i, j, k, placed = 0;
    radinterp__dkey *key;
    if (n == 0) return 0;   /* discs.data may be NULL: no pointer arithmetic on it */
    dd = (radinterp__disc *)b->discs.data + b->disc_first[R];
    key = (radinterp__dkey *)radinterp__alloc_array(&b->a, n, sizeof *key);
    if (!key) return -1;
    for (i = 0; i < n; i++) {
        double a = atan2(dd[i].q[1] - dd[i].p[1], dd[i].q[0] - dd[i].p[0]);
        while (a < RADINTERP__DSET_CUT) a += RADINTERP__PI;
        while (a >= RADINTERP__DSET_CUT + RADINTERP__PI) a -= RADINTERP__PI;
        key[i].angle = a;
        key[i].id = i;
    }
    qsort(key, n, sizeof *key, radinterp__cmp_dkey_angle);
    for (i = 0; i < n; i = j) {
        double dir[2], nrm[2];
        for (j = i + 1; j < n && key[j].angle - key[i].angle <= RADINTERP__DSET_ANGLE; j++) {}
        dir[0] = cos(key[i].angle);
        dir[1] = sin(key[i].angle);
        nrm[0] = -dir[1];
        nrm[1] = dir[0];
        for (k = i; k < j; k++) {
            const radinterp__disc *x = &dd[key[k].id];
            key[k].offset = 0.5 * (nrm[0] * (x->p[0] + x->q[0]) + nrm[1] * (x->p[1] + x->q[1]));
        }
        qsort(key + i, j - i, sizeof *key, radinterp__cmp_dkey_offset);
        for (k = i; k < j;) {
            uint32_t m, id = (uint32_t)b->dsets.count;
            double o[2];
            o[0] = nrm[0] * key[k].offset;
            o[1] = nrm[1] * key[k].offset;
            if (radinterp__new_dset(b, R, o, dir) != 0) { radinterp__free(&b->a, key); return -1; }
            for (m = k; m < j && key[m].offset - key[k].offset <= b->tol; m++) {
                radinterp__disc *x = &dd[key[m].id];
                double hp = nrm[0] * x->p[0] + nrm[1] * x->p[1] - key[k].offset;
                double hq = nrm[0] * x->q[0] + nrm[1] * x->q[1] - key[k].offset;
                if (radinterp__mesh_step(b, ++placed)) { radinterp__free(&b->a, key); return 1; }
                if (fabs(hp) > 2.0 * b->tol || fabs(hq) > 2.0 * b->tol) {
                    /* a long segment at a slightly different angle: a line of its own */
                    double d2[2], len = sqrt((x->q[0] - x->p[0]) * (x->q[0] - x->p[0]) + (x->q[1] - x->p[1]) * (x->q[1] - x->p[1]));
                    d2[0] = (x->q[0] - x->p[0]) / len;
                    d2[1] = (x->q[1] - x->p[1]) / len;
                    if (radinterp__new_dset(b, R, x->p, d2) != 0) { radinterp__free(&b->a, key); return -1; }
                    radinterp__disc_on_line(x, x->p, d2, (uint32_t)b->dsets.count - 1);
                    continue;
                }
                radinterp__disc_on_line(x, o, dir, id);
            }
            k = m;
        }
    }
    radinterp__free(&b->a, key);
    if (radinterp__mesh_tick(b)) return 1;
    qsort(dd, n, sizeof *dd, radinterp__cmp_disc_order);
    return 0;
}

/* The record the mesh returns for discontinuity d (grouped: its ends on its
   DSet's line). */
static void radinterp__export_disc(const radinterp__builder *b, radinterp__disc *d, radinterp_discontinuity *o)
{
    const radinterp_solution *s = b->s;
    radinterp__frame_to3df(&b->frames[d->receiver], d->p, o->a);
    radinterp__frame_to3df(&b->frames[d->receiver], d->q, o->b);
    o->type = d->type;
    o->receiver = s->first_caller[d->receiver];
    o->source = d->source != RADINTERP_NO_PATCH ? s->first_caller[d->source] : RADINTERP_NO_PATCH;
    o->blocker = d->blocker != RADINTERP_NO_PATCH ? s->first_caller[d->blocker] : RADINTERP_NO_PATCH;
    o->dset = d->dset;
    o->weight = radinterp__disc_weight(s, d);
    o->active = 0;
}

/* Counts R's discontinuities (grouped) by kind, moves those the mesh
   returns to its list (the candidates, or all of them with
   keep_all_discontinuities) and keeps only R's candidates in b->discs, in
   their order: the steps after the grouping use no other, and the rest are
   most of them (building_1k: 23k candidates among 2.5M discontinuities, 104
   bytes each here). The weights cannot change while the mesh is built
   (5.4), so each is computed here once. */
static int radinterp__keep_candidates(radinterp__builder *b, uint32_t R)
{
    radinterp__disc *dd;
    uint32_t n = b->disc_count[R], i, kept = 0;
    if (n == 0) return 0;   /* discs.data may be NULL: no pointer arithmetic on it */
    dd = (radinterp__disc *)b->discs.data + b->disc_first[R];
    for (i = 0; i < n; i++) {
        int candidate;
        radinterp__disc_weight(b->s, &dd[i]);   /* the weight the candidate test reads */
        candidate = radinterp__candidate(b, &dd[i]);
        if (b->found_kinds[dd[i].type] < 0xFFFFFFFFu) b->found_kinds[dd[i].type]++;   /* counts saturate */
        if (candidate || b->desc->keep_all_discontinuities) {
            radinterp_discontinuity *o = radinterp__disc_list_push(&b->a, &b->found);
            if (!o) return -1;
            radinterp__export_disc(b, &dd[i], o);
            dd[i].found = b->found.count - 1u;
        }
        if (candidate) dd[kept++] = dd[i];
    }
    b->disc_count[R] = kept;
    b->discs.count = (size_t)b->disc_first[R] + kept;
    return 0;
}

/* All discontinuities of the scene, by receiver. */
static radinterp_result radinterp__find_discontinuities(radinterp__builder *b)
{
    const radinterp_solution *s = b->s;
    radinterp__buf pairs, stack;
    uint32_t R;
    int fail = 0, cancelled = 0;
    radinterp__buf_init(&pairs, sizeof(uint64_t));
    radinterp__buf_init(&stack, sizeof(uint32_t));
    for (R = 0; R < s->patch_count && !fail && !cancelled; R++) {
        int r = 0;
        if ((cancelled = radinterp__mesh_cancelled(b)) != 0) break;
        b->disc_first[R] = (uint32_t)b->discs.count;
        if (s->patches[R].count && !b->desc->no_discontinuities) r = radinterp__receiver_discs(b, R, &pairs, &stack);
        cancelled = r > 0;
        fail = r < 0;
        b->disc_count[R] = (uint32_t)b->discs.count - b->disc_first[R];
        if (!fail && !cancelled) cancelled = radinterp__mesh_tick(b);
        if (!fail && !cancelled) {
            r = radinterp__group_dsets(b, R);
            cancelled = r > 0;
            fail = r < 0;
        }
        if (!fail && !cancelled) fail = radinterp__keep_candidates(b, R) != 0;
        radinterp__note_bytes(b, 0);
    }
    radinterp__buf_free(&b->a, &pairs);
    radinterp__buf_free(&b->a, &stack);
    /* b->discs held the largest receiver's discontinuities for a while */
    if (!fail && !cancelled) fail = radinterp__buf_trim(&b->a, &b->discs) != 0;
    if (!fail && !cancelled) fail = radinterp__disc_list_trim(&b->a, &b->found) != 0;
    if (cancelled) return RADINTERP_ERROR_CANCELLED;
    return fail ? RADINTERP_ERROR_OUT_OF_MEMORY : RADINTERP_OK;
}

/* ======================================================================
   17. the mesh's quadtrees: a copy of the solution's, restricted (balanced)
   and refined, with each node's discontinuities (5.5.6)
   A node lists the discontinuities that cross its interior, grouped by
   DSet: the root lists its patch's candidates (weight >= min_discont_weight;
   the weights cannot change while the mesh is built), a child the part of
   its parent's list that crosses it (DSet::Clip). Corners are computed with
   the solution's arithmetic (edge midpoints 0.5 (a + b), quadrilateral
   centres 0.25 (v0 + v1 + v2 + v3)), so a corner shared by two nodes is one
   float triple and a hash of (corner, patch) answers "is there a vertex
   here": the restriction (neighbour leaves differ by at most one level)
   asks it of the quarter points of each leaf edge, the triangulation of the
   midpoints (T-vertices, case A of 3.6).
   ---------------------------------------------------------------------- */
#define RADINTERP__MNODES(b) ((radinterp__mnode *)(b)->nodes.data)

static int radinterp__corner_put(radinterp__builder *b, uint32_t patch, const float *p)
{
    uint32_t key[4];
    radinterp__point_key(p, patch + 1u, key);
    return radinterp__hmap_put(&b->a, &b->corners, key, 1u) == RADINTERP__NONE ? -1 : 0;
}

static int radinterp__corner_has(const radinterp__builder *b, uint32_t patch, const float *p)
{
    uint32_t key[4];
    radinterp__point_key(p, patch + 1u, key);
    return radinterp__hmap_get(&b->corners, key) != RADINTERP__NONE;
}

/* Does discontinuity d cross the interior of node nd (shrunk by tol)? */
static int radinterp__impinges(const radinterp__builder *b, const radinterp__mnode *nd, const radinterp__disc *d)
{
    double lo[2] = {DBL_MAX, DBL_MAX}, hi[2] = {-DBL_MAX, -DBL_MAX}, t0, t1;
    uint32_t i;
    int e0, e1, k;
    for (i = 0; i < nd->count; i++)
        for (k = 0; k < 2; k++) {
            lo[k] = nd->uv[i][k] < lo[k] ? nd->uv[i][k] : lo[k];
            hi[k] = nd->uv[i][k] > hi[k] ? nd->uv[i][k] : hi[k];
        }
    for (k = 0; k < 2; k++) {
        double a = d->p[k] < d->q[k] ? d->p[k] : d->q[k], c = d->p[k] < d->q[k] ? d->q[k] : d->p[k];
        if (c < lo[k] || a > hi[k]) return 0;
    }
    return radinterp__clip_segment2((const double (*)[2])nd->uv, (int)nd->count, b->tol, d->p, d->q, &t0, &t1, &e0, &e1);
}

/* The part of a parent's discontinuity list that crosses node `child`. */
static int radinterp__inherit_discs(radinterp__builder *b, uint32_t parent, uint32_t child)
{
    const radinterp__disc *dd = (const radinterp__disc *)b->discs.data;
    uint32_t i, first = RADINTERP__MNODES(b)[parent].first_disc, count = RADINTERP__MNODES(b)[parent].disc_count;
    uint32_t start = (uint32_t)b->node_discs.count;
    for (i = 0; i < count; i++) {
        uint32_t id = RADINTERP__U32(b->node_discs)[first + i];
        if (radinterp__impinges(b, &RADINTERP__MNODES(b)[child], &dd[id]) &&
            radinterp__buf_u32(&b->a, &b->node_discs, id) != 0)
            return -1;
    }
    RADINTERP__MNODES(b)[child].first_disc = start;
    RADINTERP__MNODES(b)[child].disc_count = (uint32_t)b->node_discs.count - start;
    return 0;
}

static void radinterp__mnode_frame(const radinterp__builder *b, radinterp__mnode *nd)
{
    uint32_t i;
    for (i = 0; i < nd->count; i++) radinterp__frame_to2df(&b->frames[nd->patch], nd->v[i], nd->uv[i]);
}

/* Splits leaf `index` into four children with the corners
   radinterp__node_split gives (radinterp__child_corners). */
static int radinterp__mnode_split(radinterp__builder *b, uint32_t index)
{
    radinterp__mnode nd = RADINTERP__MNODES(b)[index];
    float corners[4][4][3];
    uint32_t first = (uint32_t)b->nodes.count, k, i;
    radinterp__child_corners((const float (*)[3])nd.v, nd.count, corners);
    if (radinterp__buf_reserve(&b->a, &b->nodes, b->nodes.count + 4) != 0) return -1;
    for (k = 0; k < 4; k++) {
        radinterp__mnode *cn = (radinterp__mnode *)radinterp__buf_push(&b->a, &b->nodes);
        memcpy(cn->v, corners[k], sizeof cn->v);
        cn->count = nd.count;
        cn->patch = nd.patch;
        cn->parent = index;
        cn->child = RADINTERP__NONE;
        cn->depth = nd.depth + 1;
        cn->leaf = RADINTERP__NONE;
        radinterp__mnode_frame(b, cn);
        for (i = 0; i < nd.count; i++)
            if (radinterp__corner_put(b, nd.patch, cn->v[i]) != 0) return -1;
    }
    RADINTERP__MNODES(b)[index].child = first;
    for (k = 0; k < 4; k++)
        if (radinterp__inherit_discs(b, index, first + k) != 0) return -1;
    return 0;
}

/* Copies patch R's quadtree from the solution, breadth first; the root
   lists R's candidate discontinuities. 0, or -1 when memory runs out, 1 when
   progress asks to cancel. */
static int radinterp__copy_tree(radinterp__builder *b, uint32_t R, radinterp__buf *queue)
{
    const radinterp_solution *s = b->s;
    radinterp__mnode *root;
    uint32_t head = 0, i;
    b->roots[R] = (uint32_t)b->nodes.count;
    root = (radinterp__mnode *)radinterp__buf_push(&b->a, &b->nodes);
    if (!root) return -1;
    memcpy(root->v, s->patches[R].v, sizeof root->v);
    root->count = s->patches[R].count;
    root->patch = R;
    root->parent = root->child = root->leaf = RADINTERP__NONE;
    radinterp__mnode_frame(b, root);
    root->first_disc = (uint32_t)b->node_discs.count;
    for (i = b->disc_first[R]; i < b->disc_first[R] + b->disc_count[R]; i++)
        if (radinterp__buf_u32(&b->a, &b->node_discs, i) != 0) return -1;
    RADINTERP__MNODES(b)[b->roots[R]].disc_count = (uint32_t)b->node_discs.count - RADINTERP__MNODES(b)[b->roots[R]].first_disc;
    for (i = 0; i < s->patches[R].count; i++)
        if (radinterp__corner_put(b, R, s->patches[R].v[i]) != 0) return -1;
    queue->count = 0;
    if (radinterp__buf_u32(&b->a, queue, s->patches[R].root) != 0 || radinterp__buf_u32(&b->a, queue, b->roots[R]) != 0)
        return -1;
    while (head < queue->count) {
        uint32_t sn = RADINTERP__U32(*queue)[head], mn = RADINTERP__U32(*queue)[head + 1], k, first;
        head += 2;
        if (radinterp__mesh_step(b, head / 2)) return 1;
        if (s->nodes[sn].child == RADINTERP__NONE || (double)s->nodes[s->nodes[sn].child].area < b->min_leaf_area) continue;
        first = (uint32_t)b->nodes.count;
        if (radinterp__buf_reserve(&b->a, &b->nodes, b->nodes.count + 4) != 0) return -1;
        for (k = 0; k < 4; k++) {
            const radinterp__node *src = &s->nodes[s->nodes[sn].child + k];
            radinterp__mnode *cn = (radinterp__mnode *)radinterp__buf_push(&b->a, &b->nodes);
            memcpy(cn->v, src->v, sizeof cn->v);
            cn->count = src->count;
            cn->patch = R;
            cn->parent = mn;
            cn->child = cn->leaf = RADINTERP__NONE;
            cn->depth = src->depth;
            radinterp__mnode_frame(b, cn);
            for (i = 0; i < src->count; i++)
                if (radinterp__corner_put(b, R, src->v[i]) != 0) return -1;
        }
        RADINTERP__MNODES(b)[mn].child = first;
        for (k = 0; k < 4; k++) {
            if (radinterp__inherit_discs(b, mn, first + k) != 0) return -1;
            if (radinterp__buf_u32(&b->a, queue, s->nodes[sn].child + k) != 0 ||
                radinterp__buf_u32(&b->a, queue, first + k) != 0)
                return -1;
        }
    }
    return 0;
}

static int radinterp__same_point(const float *a, const float *b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* A leaf must split when a neighbour is two or more levels deeper along
   one of its edges: then a corner sits at a quarter point of that edge. An
   edge a few float steps long has quarter points that round onto its own
   corners or midpoint; those say nothing about a neighbour (and would make
   the leaf split forever), so only a quarter point distinct from them
   counts. */
static int radinterp__unbalanced(const radinterp__builder *b, const radinterp__mnode *nd)
{
    uint32_t i;
    int h;
    for (i = 0; i < nd->count; i++) {
        float m[3], q[3];
        const float *a = nd->v[i], *c = nd->v[(i + 1) % nd->count];
        radinterp__mid(a, c, m);
        for (h = 0; h < 2; h++) {
            radinterp__mid(h ? m : a, h ? c : m, q);
            if (radinterp__same_point(q, a) || radinterp__same_point(q, m) || radinterp__same_point(q, c)) continue;
            if (radinterp__corner_has(b, nd->patch, q)) return 1;
        }
    }
    return 0;
}

/* Restricted quadtree (3.6): split until neighbouring leaves of a patch
   differ by at most one level. 0, or -1 when memory runs out, 1 when
   progress asks to cancel. */
static int radinterp__balance(radinterp__builder *b)
{
    int changed = 1;
    while (changed) {
        uint32_t i;
        changed = 0;
        for (i = 0; i < b->nodes.count; i++) {
            if (radinterp__mesh_step(b, i)) return 1;
            if (RADINTERP__MNODES(b)[i].child != RADINTERP__NONE || !radinterp__unbalanced(b, &RADINTERP__MNODES(b)[i]))
                continue;
            if (radinterp__mnode_split(b, i) != 0) return -1;
            b->balance_splits++;
            changed = 1;
        }
    }
    return 0;
}

/* The leaves, patch by patch, each patch's in depth-first child order. */
static int radinterp__collect_mleaves(radinterp__builder *b, radinterp__buf *stack)
{
    uint32_t R;
    b->leaves.count = 0;
    for (R = 0; R < b->s->patch_count; R++) {
        b->leaf_first[R] = (uint32_t)b->leaves.count;
        b->leaf_count[R] = 0;
        if (b->roots[R] == RADINTERP__NONE) continue;
        stack->count = 0;
        if (radinterp__buf_u32(&b->a, stack, b->roots[R]) != 0) return -1;
        while (stack->count) {
            uint32_t n = RADINTERP__U32(*stack)[--stack->count], c = RADINTERP__MNODES(b)[n].child, k;
            if (c == RADINTERP__NONE) {
                RADINTERP__MNODES(b)[n].leaf = (uint32_t)b->leaves.count;
                if (radinterp__buf_u32(&b->a, &b->leaves, n) != 0) return -1;
                continue;
            }
            RADINTERP__MNODES(b)[n].leaf = RADINTERP__NONE;
            for (k = 4; k-- > 0;)
                if (radinterp__buf_u32(&b->a, stack, c + k) != 0) return -1;
        }
        b->leaf_count[R] = (uint32_t)b->leaves.count - b->leaf_first[R];
    }
    return 0;
}

/* The leaf of patch R that contains point uv (patch frame): at each level
   the child that uv lies deepest inside. */
static uint32_t radinterp__mlocate(const radinterp__builder *b, uint32_t R, const double *uv)
{
    uint32_t node = b->roots[R];
    while (RADINTERP__MNODES(b)[node].child != RADINTERP__NONE) {
        uint32_t first = RADINTERP__MNODES(b)[node].child, best = first, k, i;
        double best_in = -DBL_MAX;
        for (k = 0; k < 4; k++) {
            const radinterp__mnode *c = &RADINTERP__MNODES(b)[first + k];
            double in = DBL_MAX;
            for (i = 0; i < c->count; i++) {
                const double *p = c->uv[i], *q = c->uv[(i + 1) % c->count];
                double dx = q[0] - p[0], dy = q[1] - p[1], len = sqrt(dx * dx + dy * dy);
                double h = len > 0.0 ? (dx * (uv[1] - p[1]) - dy * (uv[0] - p[0])) / len : 0.0;
                in = h < in ? h : in;
            }
            if (in > best_in) { best_in = in; best = first + k; }
        }
        node = best;
    }
    return node;
}

static double radinterp__mnode_area(const radinterp__mnode *nd)
{
    double a = 0.0;
    uint32_t i;
    for (i = 0; i < nd->count; i++) {
        const double *p = nd->uv[i], *q = nd->uv[(i + 1) % nd->count];
        a += p[0] * q[1] - q[0] * p[1];
    }
    return 0.5 * fabs(a);
}

/* ======================================================================
   18. active discontinuities and active DSets (5.5.7)
   Per top-level quadtree, the candidates are tried by descending weight; a
   discontinuity is activated when no leaf it crosses would then hold more
   than max_leaf_dsets active DSets (its DSet counts once per leaf, active or
   not yet), and it is then active in every leaf it crosses: the same
   decision for all of them, so no T-vertex of case B can arise. A leaf's
   active DSets are the DSets of its active discontinuities.
   ---------------------------------------------------------------------- */
typedef struct radinterp__wkey { float weight; uint32_t id; } radinterp__wkey;

static int radinterp__cmp_wkey(const void *a, const void *b)
{
    const radinterp__wkey *x = (const radinterp__wkey *)a, *y = (const radinterp__wkey *)b;
    if (x->weight != y->weight) return x->weight > y->weight ? -1 : 1;
    return x->id < y->id ? -1 : (x->id > y->id);
}

typedef struct radinterp__activation {
    radinterp__buf order;        /* radinterp__wkey */
    radinterp__buf start, list;  /* discontinuity -> leaves (CSR) */
    radinterp__buf active;       /* per leaf: max_dsets DSet ids */
    radinterp__buf active_n;     /* per leaf: how many */
} radinterp__activation;

static int radinterp__leaf_has_dset(const uint32_t *act, uint32_t n, uint32_t dset)
{
    uint32_t i;
    for (i = 0; i < n; i++)
        if (act[i] == dset) return 1;
    return 0;
}

static int radinterp__activate_patch(radinterp__builder *b, uint32_t R, radinterp__activation *w)
{
    radinterp__disc *dd = (radinterp__disc *)b->discs.data;
    uint32_t nl = b->leaf_count[R], first = b->disc_first[R], nd = b->disc_count[R], i, k, max = b->max_dsets;
    uint32_t *start, *list, *act, *act_n;
    radinterp__wkey *order;
    size_t total = 0;
    if (nl == 0 || nd == 0) return 0;
    if (radinterp__buf_reserve(&b->a, &w->start, (size_t)nd + 1) != 0 ||
        radinterp__buf_reserve(&b->a, &w->active, (size_t)nl * max) != 0 ||
        radinterp__buf_reserve(&b->a, &w->active_n, nl) != 0 || radinterp__buf_reserve(&b->a, &w->order, nd) != 0)
        return -1;
    start = (uint32_t *)w->start.data;
    memset(start, 0, ((size_t)nd + 1) * sizeof(uint32_t));
    for (i = 0; i < nl; i++) {
        const radinterp__mnode *n = &RADINTERP__MNODES(b)[RADINTERP__U32(b->leaves)[b->leaf_first[R] + i]];
        for (k = 0; k < n->disc_count; k++) start[RADINTERP__U32(b->node_discs)[n->first_disc + k] - first + 1]++;
        total += n->disc_count;
    }
    for (i = 0; i < nd; i++) start[i + 1] += start[i];
    if (radinterp__buf_reserve(&b->a, &w->list, total) != 0) return -1;
    list = (uint32_t *)w->list.data;
    for (i = 0; i < nl; i++) {
        const radinterp__mnode *n = &RADINTERP__MNODES(b)[RADINTERP__U32(b->leaves)[b->leaf_first[R] + i]];
        for (k = 0; k < n->disc_count; k++) list[start[RADINTERP__U32(b->node_discs)[n->first_disc + k] - first]++] = i;
    }
    for (i = nd; i > 0; i--) start[i] = start[i - 1];
    start[0] = 0;
    order = (radinterp__wkey *)w->order.data;
    for (i = 0; i < nd; i++) {
        order[i].weight = radinterp__disc_weight(b->s, &dd[first + i]);
        order[i].id = first + i;
    }
    qsort(order, nd, sizeof *order, radinterp__cmp_wkey);
    act = (uint32_t *)w->active.data;
    act_n = (uint32_t *)w->active_n.data;
    memset(act_n, 0, (size_t)nl * sizeof(uint32_t));
    for (i = 0; i < nd; i++) {
        uint32_t id = order[i].id, local = id - first, j, dset = dd[id].dset;
        int ok = 1;
        if (!(order[i].weight >= b->min_weight)) break;
        if (start[local] == start[local + 1]) continue;   /* not a candidate, or crosses no leaf's interior */
        for (j = start[local]; j < start[local + 1] && ok; j++) {
            uint32_t l = list[j];
            if (!radinterp__leaf_has_dset(act + (size_t)l * max, act_n[l], dset) && act_n[l] >= max) ok = 0;
        }
        if (!ok) continue;
        for (j = start[local]; j < start[local + 1]; j++) {
            uint32_t l = list[j];
            if (!radinterp__leaf_has_dset(act + (size_t)l * max, act_n[l], dset)) act[(size_t)l * max + act_n[l]++] = dset;
        }
        dd[id].active = 1;
    }
    return 0;
}

static radinterp_result radinterp__activate(radinterp__builder *b)
{
    radinterp__activation w;
    radinterp__disc *dd = (radinterp__disc *)b->discs.data;
    uint32_t R, i;
    int fail = 0;
    radinterp__buf_init(&w.order, sizeof(radinterp__wkey));
    radinterp__buf_init(&w.start, sizeof(uint32_t));
    radinterp__buf_init(&w.list, sizeof(uint32_t));
    radinterp__buf_init(&w.active, sizeof(uint32_t));
    radinterp__buf_init(&w.active_n, sizeof(uint32_t));
    for (i = 0; i < b->discs.count; i++) dd[i].active = 0;
    for (R = 0; R < b->s->patch_count && !fail; R++) fail = radinterp__mesh_tick(b) ? 1 : radinterp__activate_patch(b, R, &w);
    radinterp__buf_free(&b->a, &w.order);
    radinterp__buf_free(&b->a, &w.start);
    radinterp__buf_free(&b->a, &w.list);
    radinterp__buf_free(&b->a, &w.active);
    radinterp__buf_free(&b->a, &w.active_n);
    return radinterp__step_result(fail);
}

/* DSets of a leaf's list (they are grouped), and how many are active. */
static void radinterp__leaf_dsets(const radinterp__builder *b, const radinterp__mnode *n, uint32_t *dsets,
                                  uint32_t *active)
{
    const radinterp__disc *dd = (const radinterp__disc *)b->discs.data;
    uint32_t k, last = RADINTERP__NONE, last_active = RADINTERP__NONE;
    *dsets = *active = 0;
    for (k = 0; k < n->disc_count; k++) {
        const radinterp__disc *d = &dd[RADINTERP__U32(b->node_discs)[n->first_disc + k]];
        if (d->dset != last) { (*dsets)++; last = d->dset; }
        if (d->active && d->dset != last_active) { (*active)++; last_active = d->dset; }
    }
}

/* Moves end p of the segment (q, p), which lies on outline edge k of R
   within tol, onto that edge's line (where the segment's line meets it),
   so that the outline does not bend in to reach it. */
static void radinterp__onto_outline(const radinterp__builder *b, uint32_t R, uint32_t k, const double *q, double *p)
{
    const double (*o)[2] = radinterp__outline_of(b, R);
    const double *a = o[k], *c = o[(k + 1) % b->s->patches[R].count];
    double ex = c[0] - a[0], ey = c[1] - a[1], dx = p[0] - q[0], dy = p[1] - q[1];
    double den = dx * ey - dy * ex, t;
    if (!(fabs(den) > 1e-12 * sqrt((dx * dx + dy * dy) * (ex * ex + ey * ey)))) return;
    t = ((a[0] - q[0]) * ey - (a[1] - q[1]) * ex) / den;   /* q + t (p - q) on the edge's line */
    if (!(t > 0.5 && t < 1.5)) return;
    p[0] = q[0] + t * dx;
    p[1] = q[1] + t * dy;
}

/* A patch's discontinuity edges: for each DSet, the union of its active
   discontinuities, one segment per run of overlapping ones. */
static int radinterp__patch_segments(radinterp__builder *b, uint32_t R)
{
    const radinterp__disc *dd = (const radinterp__disc *)b->discs.data;
    const radinterp__dset *ds = (const radinterp__dset *)b->dsets.data;
    uint32_t i = b->disc_first[R], end = i + b->disc_count[R];
    b->seg_first[R] = (uint32_t)b->segs.count;
    while (i < end) {
        uint32_t dset = dd[i].dset, j = i;
        double t0 = 0.0, t1 = 0.0;
        uint32_t on0 = 0, on1 = 0, jump = 0;
        int open = 0;
        for (; j < end && dd[j].dset == dset; j++) {
            const radinterp__disc *d = &dd[j];
            if (!d->active) continue;
            if (open && d->t0 <= t1 + b->tol) {
                if (d->t1 > t1) { t1 = d->t1; on1 = d->on1; }
                jump |= d->type == RADINTERP_DISCONTINUITY_CONTACT;
                continue;
            }
            if (open) {
                radinterp__seg *sg = (radinterp__seg *)radinterp__buf_push(&b->a, &b->segs);
                if (!sg) return -1;
                sg->p[0] = ds[dset].o[0] + t0 * ds[dset].d[0]; sg->p[1] = ds[dset].o[1] + t0 * ds[dset].d[1];
                sg->q[0] = ds[dset].o[0] + t1 * ds[dset].d[0]; sg->q[1] = ds[dset].o[1] + t1 * ds[dset].d[1];
                sg->on0 = on0; sg->on1 = on1; sg->jump = jump;
            }
            open = 1;
            t0 = d->t0; t1 = d->t1; on0 = d->on0; on1 = d->on1;
            jump = d->type == RADINTERP_DISCONTINUITY_CONTACT;
        }
        if (open) {
            radinterp__seg *sg = (radinterp__seg *)radinterp__buf_push(&b->a, &b->segs);
            if (!sg) return -1;
            sg->p[0] = ds[dset].o[0] + t0 * ds[dset].d[0]; sg->p[1] = ds[dset].o[1] + t0 * ds[dset].d[1];
            sg->q[0] = ds[dset].o[0] + t1 * ds[dset].d[0]; sg->q[1] = ds[dset].o[1] + t1 * ds[dset].d[1];
            sg->on0 = on0; sg->on1 = on1; sg->jump = jump;
        }
        i = j;
    }
    b->seg_count[R] = (uint32_t)b->segs.count - b->seg_first[R];
    for (i = b->seg_first[R]; i < b->segs.count; i++) {
        radinterp__seg *sg = &((radinterp__seg *)b->segs.data)[i];
        if (sg->on0) radinterp__onto_outline(b, R, sg->on0 - 1, sg->q, sg->p);
        if (sg->on1) radinterp__onto_outline(b, R, sg->on1 - 1, sg->p, sg->q);
        radinterp__frame_to3df(&b->frames[R], sg->p, sg->a);
        radinterp__frame_to3df(&b->frames[R], sg->q, sg->b);
    }
    return 0;
}

/* ======================================================================
   19. leaf triangulation and crack-free output (5.2, 3.6)
   One constrained Delaunay triangulation per patch (section 9) whose
   constraints are every leaf edge and every active discontinuity edge: as
   leaf edges are constraints, it is the union of the leaves' own
   triangulations (the CDT of each leaf's outline with its discontinuity
   edges), and a discontinuity that crosses from one leaf into the next
   meets their common edge at one vertex that both use. T-vertices:
   - case A (leaves one level apart): a leaf edge is inserted through the
     midpoint when the neighbour has a corner there, so the larger leaf's
     triangles take that vertex too (its edge becomes two);
   - case C (patches that share an edge): every patch outline runs through
     every outline vertex of every patch within weld_distance of it (leaf
     corners, discontinuity ends), welded across patches to one float
     triple, so both sides of a seam have the same vertices;
   - case B cannot arise (18).
   Output vertices are shared by exact position, so a rasterizer with a
   consistent fill rule covers every pixel of a patch exactly once.
   ---------------------------------------------------------------------- */
#define RADINTERP__BVERTS(b) ((radinterp__bvert *)(b)->pool.data)

static int radinterp__pool_add(radinterp__builder *b, const float *x, uint32_t patch, uint32_t edge, uint32_t corner)
{
    radinterp__bvert *v = (radinterp__bvert *)radinterp__buf_push(&b->a, &b->pool);
    if (!v) return -1;
    memcpy(v->x, x, sizeof v->x);
    v->patch = patch;
    v->edge = edge;
    v->corner = corner;
    v->rep = (uint32_t)b->pool.count - 1;
    return 0;
}

/* Outline vertices of patch P: its corners, leaf corners on its outline and
   the ends of its discontinuity edges there. */
static int radinterp__outline_vertices(radinterp__builder *b, uint32_t P, radinterp__hmap *seen)
{
    const radinterp__patch *pt = &b->s->patches[P];
    const double (*o)[2] = radinterp__outline_of(b, P);
    uint32_t i, k, c, key[4];
    for (k = 0; k < pt->count; k++) {
        radinterp__point_key(pt->v[k], P + 1u, key);
        if (radinterp__hmap_put(&b->a, seen, key, 1u) == RADINTERP__NONE) return -1;
        if (radinterp__pool_add(b, pt->v[k], P, k, 1) != 0) return -1;
    }
    for (i = 0; i < b->leaf_count[P]; i++) {
        const radinterp__mnode *n = &RADINTERP__MNODES(b)[RADINTERP__U32(b->leaves)[b->leaf_first[P] + i]];
        for (c = 0; c < n->count; c++) {
            uint32_t before = seen->count;
            radinterp__point_key(n->v[c], P + 1u, key);
            if (radinterp__hmap_put(&b->a, seen, key, 1u) == RADINTERP__NONE) return -1;
            if (seen->count == before) continue;
            for (k = 0; k < pt->count; k++)
                if (radinterp__seg_dist(o[k], o[(k + 1) % pt->count], n->uv[c]) <= b->tol) {
                    if (radinterp__pool_add(b, n->v[c], P, k, 0) != 0) return -1;
                    break;
                }
        }
    }
    for (i = b->seg_first[P]; i < b->seg_first[P] + b->seg_count[P]; i++) {
        const radinterp__seg *sg = &((const radinterp__seg *)b->segs.data)[i];
        if (sg->on0 && radinterp__pool_add(b, sg->a, P, sg->on0 - 1, 0) != 0) return -1;
        if (sg->on1 && radinterp__pool_add(b, sg->b, P, sg->on1 - 1, 0) != 0) return -1;
    }
    return 0;
}

static uint32_t radinterp__find_rep(radinterp__bvert *v, uint32_t i)
{
    while (v[i].rep != i) {
        v[i].rep = v[v[i].rep].rep;
        i = v[i].rep;
    }
    return i;
}

/* Outline vertices in cells of the weld distance: a cell's vertices are
   neighbours in the sorted order. */
typedef struct radinterp__cellkey { int64_t c[3]; uint32_t id; } radinterp__cellkey;

static int radinterp__cmp_cellkey(const void *a, const void *b)
{
    const radinterp__cellkey *p = (const radinterp__cellkey *)a, *q = (const radinterp__cellkey *)b;
    int k;
    for (k = 0; k < 3; k++)
        if (p->c[k] != q->c[k]) return p->c[k] < q->c[k] ? -1 : 1;
    return p->id < q->id ? -1 : (p->id > q->id);
}

/* First sorted key at cell c or after it. */
static uint32_t radinterp__cell_lower(const radinterp__cellkey *keys, uint32_t n, const int64_t *c)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        radinterp__cellkey probe;
        memcpy(probe.c, c, sizeof probe.c);
        probe.id = 0;
        if (radinterp__cmp_cellkey(&keys[mid], &probe) < 0) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Welds outline vertices closer than weld_distance (each component to its
   first listed vertex, so the result does not depend on the order of the
   tests) and maps every point to its representative. Vertices are found
   in the 27 cells around each one's cell (cells of the weld distance), so
   vertices sharing a coordinate, as a building's walls do, cost no more
   than others. */
static int radinterp__weld(radinterp__builder *b)
{
    radinterp__bvert *v = RADINTERP__BVERTS(b);
    uint32_t n = (uint32_t)b->pool.count, i, j, key[4];
    radinterp__cellkey *keys = (radinterp__cellkey *)radinterp__alloc_array(&b->a, n ? n : 1, sizeof *keys);
    double w2 = b->weld * b->weld;
    int k, dc;
    if (!keys) return -1;
    for (i = 0; i < n; i++) {
        for (k = 0; k < 3; k++) keys[i].c[k] = (int64_t)floor((double)v[i].x[k] / b->weld);
        keys[i].id = i;
    }
    qsort(keys, n, sizeof *keys, radinterp__cmp_cellkey);
    for (i = 0; i < n; i++)
        for (dc = 0; dc < 27; dc++) {
            int64_t c[3];
            c[0] = keys[i].c[0] + dc % 3 - 1;
            c[1] = keys[i].c[1] + (dc / 3) % 3 - 1;
            c[2] = keys[i].c[2] + dc / 9 - 1;
            for (j = radinterp__cell_lower(keys, n, c); j < n && keys[j].c[0] == c[0] && keys[j].c[1] == c[1] && keys[j].c[2] == c[2]; j++) {
                const float *p = v[keys[i].id].x, *q = v[keys[j].id].x;
                double dx = (double)p[0] - q[0], dy = (double)p[1] - q[1], dz = (double)p[2] - q[2];
                if (keys[j].id <= keys[i].id || dx * dx + dy * dy + dz * dz > w2) continue;
                {
                    uint32_t ri = radinterp__find_rep(v, keys[i].id), rj = radinterp__find_rep(v, keys[j].id);
                    if (ri < rj) v[rj].rep = ri;
                    else if (rj < ri) v[ri].rep = rj;
                }
            }
        }
    radinterp__free(&b->a, keys);
    radinterp__hmap_clear(&b->canon);
    for (i = 0; i < n; i++) {
        uint32_t r = radinterp__find_rep(v, i);
        v[i].rep = r;
        radinterp__point_key(v[i].x, 0, key);
        if (radinterp__hmap_put(&b->a, &b->canon, key, r) == RADINTERP__NONE) return -1;
    }
    return 0;
}

/* The welded position of a point (itself when it is no outline vertex). */
static const float *radinterp__canonical(const radinterp__builder *b, const float *x)
{
    uint32_t key[4], r;
    radinterp__point_key(x, 0, key);
    r = radinterp__hmap_get(&b->canon, key);
    return r == RADINTERP__NONE ? x : RADINTERP__BVERTS(b)[r].x;
}

typedef struct radinterp__tkey { double t; uint32_t rep; } radinterp__tkey;

/* The outline edge of a patch nearest to x (3D): a vertex near a corner
   joins one edge's chain only. */
static uint32_t radinterp__nearest_edge(const radinterp__patch *pt, const double *x)
{
    uint32_t k, best = 0;
    double best_d = DBL_MAX;
    for (k = 0; k < pt->count; k++) {
        double a[3], c[3], d[3], w[3], t, l2, dist;
        int e;
        radinterp__d3_from_f(pt->v[k], a);
        radinterp__d3_from_f(pt->v[(k + 1) % pt->count], c);
        radinterp__d3_sub(c, a, d);
        radinterp__d3_sub(x, a, w);
        l2 = radinterp__d3_dot(d, d);
        t = l2 > 0.0 ? radinterp__d3_dot(w, d) / l2 : 0.0;
        t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
        for (e = 0; e < 3; e++) w[e] = a[e] + t * d[e] - x[e];
        dist = radinterp__d3_len(w);
        if (dist < best_d) { best_d = dist; best = k; }
    }
    return best;
}

static int radinterp__cmp_tkey(const void *a, const void *b)
{
    const radinterp__tkey *x = (const radinterp__tkey *)a, *y = (const radinterp__tkey *)b;
    if (x->t != y->t) return x->t < y->t ? -1 : 1;
    return x->rep < y->rep ? -1 : (x->rep > y->rep);
}

/* Do outline edge k of P and edge j of Q lie on one line (within reach)? */
static int radinterp__edges_collinear(const radinterp_solution *s, uint32_t P, uint32_t k, uint32_t Q, uint32_t j,
                                      double reach)
{
    const radinterp__patch *pp = &s->patches[P], *pq = &s->patches[Q];
    double a[3], c[3], a2[3], c2[3], d1[3], d2[3], x[3], w[3];
    int i, e;
    if (P == Q) return k == j;
    radinterp__d3_from_f(pp->v[k], a);
    radinterp__d3_from_f(pp->v[(k + 1) % pp->count], c);
    radinterp__d3_from_f(pq->v[j], a2);
    radinterp__d3_from_f(pq->v[(j + 1) % pq->count], c2);
    radinterp__d3_sub(c, a, d1);
    radinterp__d3_sub(c2, a2, d2);
    radinterp__d3_cross(d1, d2, x);
    if (radinterp__d3_len(x) > 1e-6 * radinterp__d3_len(d1) * radinterp__d3_len(d2)) return 0;
    for (i = 0; i < 2; i++) {
        const double *q = i ? c2 : a2;
        double t;
        radinterp__d3_sub(q, a, w);
        t = radinterp__d3_dot(w, d1) / radinterp__d3_dot(d1, d1);
        for (e = 0; e < 3; e++) x[e] = a[e] + t * d1[e] - q[e];
        if (radinterp__d3_len(x) > reach) return 0;
    }
    return 1;
}

/* The chain of outline edge k of patch P (case C of 3.6): the welded
   outline vertices of every patch whose outline edge there runs along
   this one, in order along it. A vertex belongs to P's edge when it lies
   within weld_distance + tol of it, strictly between its corners, nearer to
   it than to P's other edges, and on an edge of its own patch collinear
   with it (a vertex of a patch that meets P's edge at an angle stays out). */
static int radinterp__make_chain(radinterp__builder *b, uint32_t P, uint32_t k, const uint32_t *own, radinterp__buf *tmp,
                                 radinterp__buf *near)
{
    const radinterp__patch *pt = &b->s->patches[P];
    const radinterp__bvert *v = RADINTERP__BVERTS(b);
    uint32_t i, m, a_rep, c_rep, key[4];
    double a[3], c[3], d[3], len2, reach = b->weld + b->tol;
    float elo[3], ehi[3];
    int e;
    radinterp__d3_from_f(pt->v[k], a);
    radinterp__d3_from_f(pt->v[(k + 1) % pt->count], c);
    radinterp__d3_sub(c, a, d);
    len2 = radinterp__d3_dot(d, d);
    radinterp__box_empty(elo, ehi);
    radinterp__box_grow(elo, ehi, pt->v[k], pt->v[k]);
    radinterp__box_grow(elo, ehi, pt->v[(k + 1) % pt->count], pt->v[(k + 1) % pt->count]);
    /* a vertex within reach of the edge lies in its patch's box, which then
       comes within reach of the edge's */
    if (radinterp__patches_near(b->s, &b->a, elo, ehi, 2.0 * reach, near) != 0) return -1;
    tmp->count = 0;
    for (m = 0; m < near->count; m++)
    for (i = b->pool_first[RADINTERP__U32(*near)[m]]; i < b->pool_first[RADINTERP__U32(*near)[m] + 1]; i++) {
        const radinterp__bvert *ent = &v[i];
        const radinterp__patch *pq = &b->s->patches[ent->patch];
        uint32_t r = ent->rep, prev = (ent->edge + pq->count - 1) % pq->count;
        double x[3], w[3], t, dist;
        radinterp__tkey *tk;
        if (!radinterp__edges_collinear(b->s, P, k, ent->patch, ent->edge, reach) &&
            !(ent->corner && radinterp__edges_collinear(b->s, P, k, ent->patch, prev, reach)))
            continue;
        radinterp__d3_from_f(v[r].x, x);
        radinterp__d3_sub(x, a, w);
        t = radinterp__d3_dot(w, d) / len2;
        if (!(t > 0.0 && t < 1.0)) continue;   /* a corner, or past one */
        for (e = 0; e < 3; e++) w[e] = a[e] + t * d[e] - x[e];
        dist = radinterp__d3_len(w);
        if (dist > reach || radinterp__nearest_edge(pt, x) != k) continue;
        if (!(tk = (radinterp__tkey *)radinterp__buf_push(&b->a, tmp))) return -1;
        tk->t = t;
        tk->rep = r;
    }
    radinterp__point_key(pt->v[k], 0, key);
    a_rep = radinterp__hmap_get(&b->canon, key);
    radinterp__point_key(pt->v[(k + 1) % pt->count], 0, key);
    c_rep = radinterp__hmap_get(&b->canon, key);
    if (tmp->count > 1) qsort(tmp->data, tmp->count, sizeof(radinterp__tkey), radinterp__cmp_tkey);
    b->chain_first[4 * P + k] = (uint32_t)b->chains.count;
    if (radinterp__buf_u32(&b->a, &b->chains, a_rep) != 0) return -1;
    for (i = 0; i < tmp->count; i++) {
        uint32_t r = ((radinterp__tkey *)tmp->data)[i].rep;
        if (r == a_rep || r == c_rep || r == RADINTERP__U32(b->chains)[b->chains.count - 1]) continue;
        if (radinterp__buf_u32(&b->a, &b->chains, r) != 0) return -1;
        if (own[r] != P + 1u) b->seam++;
    }
    if (radinterp__buf_u32(&b->a, &b->chains, c_rep) != 0) return -1;
    b->chain_len[4 * P + k] = (uint32_t)b->chains.count - b->chain_first[4 * P + k];
    return 0;
}

/* Scratch of the per-patch triangulation, reused from patch to patch. */
typedef struct radinterp__lpoint { double uv[2]; float x[3]; } radinterp__lpoint;

typedef struct radinterp__tri_work {
    radinterp__buf pts;        /* radinterp__lpoint: the triangulation's input points */
    radinterp__hmap lmap;      /* point -> index in pts */
    radinterp__buf xy, ids;    /* input coordinates; the CDT vertex of each point */
    radinterp__buf v3;         /* float[3] per CDT vertex */
    radinterp__buf mark;       /* per CDT vertex: 1 on the outline chain */
    radinterp__buf inside;     /* per CDT triangle */
    radinterp__buf stack, order, tmp;
    radinterp__cdt cdt;
    int cdt_ready;
    radinterp_allocator real;  /* the caller's allocator, behind `tracked` */
    radinterp_allocator tracked;
    int out_of_memory;         /* an allocation of the triangulation failed */
} radinterp__tri_work;

/* The triangulation reports memory and geometry failures alike (c->failed):
   its allocations go through this wrapper, which remembers a NULL. */
static void *radinterp__tracked_alloc(size_t size, void *user)
{
    radinterp__tri_work *w = (radinterp__tri_work *)user;
    void *p = radinterp__alloc(&w->real, size);
    if (!p) w->out_of_memory = 1;
    return p;
}

static void radinterp__tracked_free(void *ptr, void *user)
{
    radinterp__free(&((radinterp__tri_work *)user)->real, ptr);
}

static void radinterp__tri_work_init(radinterp__tri_work *w, const radinterp_allocator *a)
{
    memset(w, 0, sizeof *w);
    w->real = *a;
    w->tracked.alloc = radinterp__tracked_alloc;
    w->tracked.free = radinterp__tracked_free;
    w->tracked.user = w;
    radinterp__buf_init(&w->pts, sizeof(radinterp__lpoint));
    radinterp__buf_init(&w->xy, 2 * sizeof(double));
    radinterp__buf_init(&w->ids, sizeof(uint32_t));
    radinterp__buf_init(&w->v3, 3 * sizeof(float));
    radinterp__buf_init(&w->mark, 1);
    radinterp__buf_init(&w->inside, 1);
    radinterp__buf_init(&w->stack, sizeof(uint32_t));
    radinterp__buf_init(&w->order, sizeof(uint64_t));
    radinterp__buf_init(&w->tmp, sizeof(radinterp__tkey));
}

static void radinterp__tri_work_free(const radinterp_allocator *a, radinterp__tri_work *w)
{
    radinterp__buf_free(a, &w->pts);
    radinterp__hmap_free(a, &w->lmap);
    radinterp__buf_free(a, &w->xy);
    radinterp__buf_free(a, &w->ids);
    radinterp__buf_free(a, &w->v3);
    radinterp__buf_free(a, &w->mark);
    radinterp__buf_free(a, &w->inside);
    radinterp__buf_free(a, &w->stack);
    radinterp__buf_free(a, &w->order);
    radinterp__buf_free(a, &w->tmp);
    if (w->cdt_ready) radinterp__cdt_free(&w->cdt);
    w->cdt_ready = 0;
}

/* Index of point x (uv: its frame coordinates, NULL = project x). */
static uint32_t radinterp__local_point(radinterp__builder *b, radinterp__tri_work *w, uint32_t P, const float *x,
                                       const double *uv)
{
    uint32_t key[4], id;
    radinterp__point_key(x, 0, key);
    id = radinterp__hmap_put(&b->a, &w->lmap, key, (uint32_t)w->pts.count);
    if (id == (uint32_t)w->pts.count) {
        radinterp__lpoint *lp = (radinterp__lpoint *)radinterp__buf_push(&b->a, &w->pts);
        if (!lp) return RADINTERP__NONE;
        memcpy(lp->x, x, sizeof lp->x);
        if (uv) { lp->uv[0] = uv[0]; lp->uv[1] = uv[1]; }
        else radinterp__frame_to2df(&b->frames[P], x, lp->uv);
    }
    return id;
}

/* CDT vertex of a point already added (by its welded position). */
static uint32_t radinterp__cdt_vertex(const radinterp__builder *b, const radinterp__tri_work *w, const float *x)
{
    uint32_t key[4], id;
    radinterp__point_key(radinterp__canonical(b, x), 0, key);
    id = radinterp__hmap_get(&w->lmap, key);
    return id == RADINTERP__NONE ? RADINTERP__NONE : RADINTERP__U32(w->ids)[id];
}

/* A leaf edge as a constraint, through the corners of finer neighbours
   on it (case A T-vertices). Returns 0, or -1 when the CDT failed. */
static int radinterp__leaf_edge(radinterp__builder *b, radinterp__tri_work *w, uint32_t P, const float *a,
                                const float *c, uint32_t depth)
{
    float m[3];
    uint32_t ia, ic;
    radinterp__mid(a, c, m);
    if (depth < 40 && radinterp__corner_has(b, P, m)) {
        b->hanging++;
        return radinterp__leaf_edge(b, w, P, a, m, depth + 1) || radinterp__leaf_edge(b, w, P, m, c, depth + 1) ? -1 : 0;
    }
    ia = radinterp__cdt_vertex(b, w, a);
    ic = radinterp__cdt_vertex(b, w, c);
    if (ia == RADINTERP__NONE || ic == RADINTERP__NONE) return -1;
    if (ia == ic) return 0;
    return radinterp__cdt_add_segment(&w->cdt, ia, ic);
}

/* Is the leaf edge (a, b) part of outline edge k of P (both ends on it)? */
static int radinterp__on_same_outline_edge(const radinterp__builder *b, uint32_t P, const double *a, const double *c)
{
    const double (*o)[2] = radinterp__outline_of(b, P);
    uint32_t k, n = b->s->patches[P].count;
    for (k = 0; k < n; k++)
        if (radinterp__seg_dist(o[k], o[(k + 1) % n], a) <= b->tol &&
            radinterp__seg_dist(o[k], o[(k + 1) % n], c) <= b->tol)
            return 1;
    return 0;
}

/* Input points and constraints of P's triangulation. Returns 0, 1 when the
   triangulation failed, -1 when out of memory. */
static int radinterp__patch_cdt(radinterp__builder *b, radinterp__tri_work *w, uint32_t P, int with_segments)
{
    const radinterp__bvert *pool = RADINTERP__BVERTS(b);
    const radinterp__seg *segs = (const radinterp__seg *)b->segs.data;
    uint32_t k, i, c, n;
    radinterp__hmap_clear(&w->lmap);
    w->pts.count = 0;
    for (k = 0; k < b->s->patches[P].count; k++)
        for (i = 0; i < b->chain_len[4 * P + k]; i++)
            if (radinterp__local_point(b, w, P, pool[RADINTERP__U32(b->chains)[b->chain_first[4 * P + k] + i]].x, NULL) ==
                RADINTERP__NONE)
                return -1;
    for (i = 0; i < b->leaf_count[P]; i++) {
        const radinterp__mnode *nd = &RADINTERP__MNODES(b)[RADINTERP__U32(b->leaves)[b->leaf_first[P] + i]];
        for (c = 0; c < nd->count; c++)
            if (radinterp__local_point(b, w, P, radinterp__canonical(b, nd->v[c]), NULL) == RADINTERP__NONE) return -1;
    }
    for (i = b->seg_first[P]; with_segments && i < b->seg_first[P] + b->seg_count[P]; i++) {
        const radinterp__seg *sg = &segs[i];
        if (radinterp__local_point(b, w, P, sg->on0 ? radinterp__canonical(b, sg->a) : sg->a, sg->on0 ? NULL : sg->p) ==
                RADINTERP__NONE ||
            radinterp__local_point(b, w, P, sg->on1 ? radinterp__canonical(b, sg->b) : sg->b, sg->on1 ? NULL : sg->q) ==
                RADINTERP__NONE)
            return -1;
    }
    n = (uint32_t)w->pts.count;
    if (radinterp__buf_reserve(&b->a, &w->xy, n) != 0 || radinterp__buf_reserve(&b->a, &w->ids, n) != 0) return -1;
    for (i = 0; i < n; i++) memcpy((double *)w->xy.data + 2 * (size_t)i, ((radinterp__lpoint *)w->pts.data)[i].uv, 2 * sizeof(double));
    w->ids.count = n;
    if (!w->cdt_ready) radinterp__cdt_init(&w->cdt, &w->tracked, NULL, 0);
    else radinterp__cdt_clear(&w->cdt);
    w->cdt_ready = 1;
    if (radinterp__cdt_add_points(&w->cdt, (const double *)w->xy.data, n, RADINTERP__U32(w->ids)) != 0 || !w->cdt.started)
        return 1;
    /* the outline chains, then the leaf edges, then the discontinuity edges */
    for (k = 0; k < b->s->patches[P].count; k++)
        for (i = 0; i + 1 < b->chain_len[4 * P + k]; i++) {
            const uint32_t *ch = RADINTERP__U32(b->chains) + b->chain_first[4 * P + k];
            uint32_t ia = radinterp__cdt_vertex(b, w, pool[ch[i]].x), ic = radinterp__cdt_vertex(b, w, pool[ch[i + 1]].x);
            if (ia == RADINTERP__NONE || ic == RADINTERP__NONE) return 1;
            if (ia != ic && radinterp__cdt_add_segment(&w->cdt, ia, ic) != 0) return 1;
        }
    for (i = 0; i < b->leaf_count[P]; i++) {
        const radinterp__mnode *nd = &RADINTERP__MNODES(b)[RADINTERP__U32(b->leaves)[b->leaf_first[P] + i]];
        for (c = 0; c < nd->count; c++) {
            uint32_t d = (c + 1) % nd->count;
            if (radinterp__on_same_outline_edge(b, P, nd->uv[c], nd->uv[d])) continue;
            if (radinterp__leaf_edge(b, w, P, nd->v[c], nd->v[d], 0) != 0) return 1;
        }
    }
    for (i = b->seg_first[P]; with_segments && i < b->seg_first[P] + b->seg_count[P]; i++) {
        const radinterp__seg *sg = &segs[i];
        uint32_t key[4], la, lb;
        radinterp__point_key(sg->on0 ? radinterp__canonical(b, sg->a) : sg->a, 0, key);
        la = radinterp__hmap_get(&w->lmap, key);
        radinterp__point_key(sg->on1 ? radinterp__canonical(b, sg->b) : sg->b, 0, key);
        lb = radinterp__hmap_get(&w->lmap, key);
        if (la == RADINTERP__NONE || lb == RADINTERP__NONE) return 1;
        la = RADINTERP__U32(w->ids)[la];
        lb = RADINTERP__U32(w->ids)[lb];
        if (la != lb && radinterp__cdt_add_segment(&w->cdt, la, lb) != 0) return 1;
    }
    return w->cdt.failed ? 1 : 0;
}

static double radinterp__perimeter(const radinterp__builder *b, uint32_t P)
{
    const double (*o)[2] = radinterp__outline_of(b, P);
    uint32_t k, n = b->s->patches[P].count;
    double sum = 0.0;
    for (k = 0; k < n; k++) sum += radinterp__seg_dist(o[k], o[k], o[(k + 1) % n]);
    return sum;
}

/* Marks the triangles inside the outline: everything reachable from the
   ghosts without crossing a constraint is outside. Checks that the inside
   covers the patch and is bounded by chain vertices only. Returns 0, 1
   when the check fails, -1 when out of memory. */
static int radinterp__classify(radinterp__builder *b, radinterp__tri_work *w, uint32_t P)
{
    radinterp__cdt *c = &w->cdt;
    unsigned char *inside, *mark;
    uint32_t t, e, i, k;
    double area = 0.0, want = b->s->patches[P].area;
    if (radinterp__buf_reserve(&b->a, &w->inside, c->tri_count) != 0 ||
        radinterp__buf_reserve(&b->a, &w->mark, c->vertex_count) != 0)
        return -1;
    inside = (unsigned char *)w->inside.data;
    mark = (unsigned char *)w->mark.data;
    w->stack.count = 0;
    for (t = 0; t < c->tri_count; t++) {
        inside[t] = (unsigned char)radinterp__cdt_is_real(c, t);
        if (!inside[t] && radinterp__buf_u32(&b->a, &w->stack, t) != 0) return -1;
    }
    while (w->stack.count) {
        t = RADINTERP__U32(w->stack)[--w->stack.count];
        for (e = 0; e < 3; e++) {
            uint32_t u = c->tri[t].n[e];
            if ((c->tri[t].flags >> e) & 1u || u >= c->tri_count || !inside[u]) continue;
            inside[u] = 0;
            if (radinterp__buf_u32(&b->a, &w->stack, u) != 0) return -1;
        }
    }
    memset(mark, 0, c->vertex_count);
    for (k = 0; k < b->s->patches[P].count; k++)
        for (i = 0; i < b->chain_len[4 * P + k]; i++) {
            uint32_t v = radinterp__cdt_vertex(b, w, RADINTERP__BVERTS(b)[RADINTERP__U32(b->chains)[b->chain_first[4 * P + k] + i]].x);
            if (v != RADINTERP__NONE) mark[v] = 1;
        }
    for (t = 0; t < c->tri_count; t++) {
        const radinterp__cdt_tri *T = &c->tri[t];
        if (!inside[t]) continue;
        {
            const double *p0 = radinterp__cdt_p(c, T->v[0]), *p1 = radinterp__cdt_p(c, T->v[1]), *p2 = radinterp__cdt_p(c, T->v[2]);
            area += 0.5 * ((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]));
        }
        for (e = 0; e < 3; e++)
            if (!inside[T->n[e]] && (!mark[T->v[(e + 1) % 3]] || !mark[T->v[(e + 2) % 3]])) return 1;
    }
    /* the outline may bend through vertices up to weld + tol off it */
    return fabs(area - want) <= 1e-9 * want + 2.0 * (b->weld + b->tol) * radinterp__perimeter(b, P) ? 0 : 1;
}

/* Does the 2D edge (p, q) lie on one of P's discontinuity edges? */
static int radinterp__on_segment(const radinterp__builder *b, uint32_t P, const double *p, const double *q)
{
    const radinterp__seg *segs = (const radinterp__seg *)b->segs.data;
    uint32_t i;
    for (i = b->seg_first[P]; i < b->seg_first[P] + b->seg_count[P]; i++)
        if (radinterp__seg_dist(segs[i].p, segs[i].q, p) <= b->tol && radinterp__seg_dist(segs[i].p, segs[i].q, q) <= b->tol)
            return segs[i].jump ? 2 : 1;
    return 0;
}

/* Twice the area of the triangle (x0, x1, x2) seen along P's normal, and
   its longest edge squared: the triangle as it is drawn, at float
   positions. */
static double radinterp__float_area2(const radinterp__builder *b, uint32_t P, const float *x0, const float *x1,
                                     const float *x2, double *longest2)
{
    double e1[3], e2[3], e3[3], n[3];
    int k;
    for (k = 0; k < 3; k++) {
        e1[k] = (double)x1[k] - x0[k];
        e2[k] = (double)x2[k] - x0[k];
        e3[k] = (double)x2[k] - x1[k];
    }
    radinterp__d3_cross(e1, e2, n);
    *longest2 = radinterp__d3_dot(e1, e1);
    if (radinterp__d3_dot(e2, e2) > *longest2) *longest2 = radinterp__d3_dot(e2, e2);
    if (radinterp__d3_dot(e3, e3) > *longest2) *longest2 = radinterp__d3_dot(e3, e3);
    return radinterp__d3_dot(n, b->s->patches[P].n);
}

/* Is the triangle flat: its height under RADINTERP__FLAT times its longest
   edge (turned over counts as flat)? */
#define RADINTERP__FLAT 1e-6
static int radinterp__float_flat(const radinterp__builder *b, uint32_t P, const float *v3, const uint32_t *v)
{
    double l2, a2 = radinterp__float_area2(b, P, v3 + 3 * (size_t)v[0], v3 + 3 * (size_t)v[1], v3 + 3 * (size_t)v[2], &l2);
    return a2 <= RADINTERP__FLAT * l2;
}

/* The triangulation is exact in the patch's plane, but its vertices are
   drawn at float positions: a vertex within rounding of the opposite edge
   (where a discontinuity crosses a leaf edge at a shallow angle, or ends
   next to one) makes a triangle that is flat or turned over once rounded,
   and it then overlaps its neighbours on screen (a pixel counted twice).
   Each such inside triangle has its longest edge flipped with the inside
   neighbour across it, when both triangles of the flip then face the front
   and are not flat; a constraint on the flipped edge carries over to the
   two edges through the vertex that lay on it. */
static void radinterp__unfold(const radinterp__builder *b, radinterp__tri_work *w, uint32_t P, const float *v3)
{
    radinterp__cdt *c = &w->cdt;
    const unsigned char *inside = (const unsigned char *)w->inside.data;
    uint32_t t, flips = 0, pass;
    for (pass = 0; pass < 4; pass++) {
        uint32_t before = flips;
        for (t = 0; t < c->tri_count; t++) {
            const radinterp__cdt_tri *T = &c->tri[t];
            uint32_t u, q[3], far;
            double best = -1.0;
            int k = 0, e, j, constrained;
            if (!inside[t] || !radinterp__float_flat(b, P, v3, T->v)) continue;
            for (e = 0; e < 3; e++) {   /* the longest edge is opposite v[k] */
                const float *p0 = v3 + 3 * (size_t)T->v[(e + 1) % 3], *p1 = v3 + 3 * (size_t)T->v[(e + 2) % 3];
                double d2 = 0.0;
                for (j = 0; j < 3; j++) d2 += ((double)p1[j] - p0[j]) * ((double)p1[j] - p0[j]);
                if (d2 > best) { best = d2; k = e; }
            }
            u = T->n[k];
            if (u >= c->tri_count || !inside[u]) continue;
            far = c->tri[u].v[radinterp__cdt_neighbour_index(c, u, t)];
            q[0] = T->v[k]; q[1] = T->v[(k + 1) % 3]; q[2] = far;         /* (a, b, d) */
            if (radinterp__float_flat(b, P, v3, q)) continue;
            q[1] = far; q[2] = T->v[(k + 2) % 3];                           /* (a, d, c) */
            if (radinterp__float_flat(b, P, v3, q)) continue;
            constrained = (int)((T->flags >> k) & 1u);
            radinterp__cdt_flip(c, t, k);                      /* t = (a, b, d), u = (a, d, c) */
            if (constrained) {
                radinterp__cdt_mark(c, t, 2, 1);
                radinterp__cdt_mark(c, u, 1, 1);
            }
            flips++;
        }
        if (flips == before) break;
    }
}

/* Appends P's inside triangles to the pass output, ordered by leaf. */
static int radinterp__emit_patch(radinterp__builder *b, radinterp__tri_work *w, uint32_t P, int with_segments)
{
    radinterp__cdt *c = &w->cdt;
    const unsigned char *inside = (const unsigned char *)w->inside.data;
    uint32_t t, i, k, first = (uint32_t)b->tris.count;
    float *v3;
    if (radinterp__buf_reserve(&b->a, &w->v3, c->vertex_count) != 0) return -1;
    v3 = (float *)w->v3.data;
    for (i = 0; i < c->vertex_count; i++) {
        float x[3];
        radinterp__frame_to3df(&b->frames[P], radinterp__cdt_p(c, i), x);
        memcpy(v3 + 3 * (size_t)i, x, sizeof x);
    }
    for (i = (uint32_t)w->pts.count; i-- > 0;)  /* input points keep their exact position (the first of duplicates) */
        memcpy(v3 + 3 * (size_t)RADINTERP__U32(w->ids)[i], ((radinterp__lpoint *)w->pts.data)[i].x, 3 * sizeof(float));
    radinterp__unfold(b, w, P, v3);
    w->order.count = 0;
    for (t = 0; t < c->tri_count; t++) {
        const radinterp__cdt_tri *T = &c->tri[t];
        radinterp__otri *o;
        uint32_t g[3], key[4];
        double uv[2], l2;
        if (!inside[t]) continue;
        /* flat or turned over once rounded where no flip could mend it (on
           the outline): it covers nothing, or overlaps whether kept or not */
        if (radinterp__float_area2(b, P, v3 + 3 * (size_t)T->v[0], v3 + 3 * (size_t)T->v[1], v3 + 3 * (size_t)T->v[2], &l2) <= 0.0) {
            b->degenerate++;
            continue;
        }
        for (k = 0; k < 3; k++) {
            radinterp__point_key(v3 + 3 * (size_t)T->v[k], 0, key);
            g[k] = radinterp__hmap_put(&b->a, &b->vmap, key, (uint32_t)(b->pos.count / 3));
            if (g[k] == RADINTERP__NONE) return -1;
            if (g[k] == (uint32_t)(b->pos.count / 3)) {
                uint32_t j;
                for (j = 0; j < 3; j++) {
                    float *f = (float *)radinterp__buf_push(&b->a, &b->pos);
                    if (!f) return -1;
                    *f = v3[3 * (size_t)T->v[k] + j];
                }
            }
        }
        if (g[0] == g[1] || g[1] == g[2] || g[2] == g[0]) { b->degenerate++; continue; }
        if (!(o = (radinterp__otri *)radinterp__buf_push(&b->a, &b->tris))) return -1;
        memcpy(o->v, g, sizeof g);
        o->patch = P;
        for (k = 0; k < 2; k++)
            uv[k] = (radinterp__cdt_p(c, T->v[0])[k] + radinterp__cdt_p(c, T->v[1])[k] + radinterp__cdt_p(c, T->v[2])[k]) / 3.0;
        o->node = radinterp__mlocate(b, P, uv);
        for (k = 0; k < 3; k++) {
            const double *p = radinterp__cdt_p(c, T->v[(k + 1) % 3]), *q = radinterp__cdt_p(c, T->v[(k + 2) % 3]);
            if (!((T->flags >> k) & 1u)) continue;
            o->flags |= 1u << k;
            if (with_segments) {
                int on = radinterp__on_segment(b, P, p, q);
                if (on) o->flags |= 8u << k;
                if (on == 2) o->flags |= RADINTERP__EDGE_JUMP << k;
            }
        }
    }
    /* leaf by leaf, in triangulation order inside a leaf */
    for (t = first; t < b->tris.count; t++) {
        uint64_t *key = (uint64_t *)radinterp__buf_push(&b->a, &w->order);
        const radinterp__otri *o = &((radinterp__otri *)b->tris.data)[t];
        if (!key) return -1;
        *key = (uint64_t)RADINTERP__MNODES(b)[o->node].leaf << 32 | (t - first);
    }
    if (w->order.count > 1) {
        radinterp__otri *copy = (radinterp__otri *)radinterp__alloc_array(&b->a, w->order.count, sizeof *copy);
        if (!copy) return -1;
        memcpy(copy, (radinterp__otri *)b->tris.data + first, w->order.count * sizeof *copy);
        qsort(w->order.data, w->order.count, sizeof(uint64_t), radinterp__cmp_u64);
        for (t = 0; t < w->order.count; t++)
            ((radinterp__otri *)b->tris.data)[first + t] = copy[((uint64_t *)w->order.data)[t] & 0xFFFFFFFFu];
        radinterp__free(&b->a, copy);
    }
    return 0;
}

/* P's triangles; without its discontinuity edges when the triangulation
   with them fails its checks (logged and counted). */
static radinterp_result radinterp__triangulate_patch(radinterp__builder *b, radinterp__tri_work *w, uint32_t P)
{
    int with = 1, r;
    for (;;) {
        uint32_t hanging = b->hanging;
        w->out_of_memory = 0;
        r = radinterp__patch_cdt(b, w, P, with);
        if (r == 0) r = radinterp__classify(b, w, P);
        if (r < 0 || w->out_of_memory) return RADINTERP_ERROR_OUT_OF_MEMORY;
        if (r == 0) break;
        b->hanging = hanging;
        if (!with) { /* thinner than the weld distance, or its outline folds: left out */
            radinterp__mesh_log(b, "radinterp_build_mesh: patch %u could not be triangulated: left out of the mesh", b->s->first_caller[P]);
            b->skipped++;
            return RADINTERP_OK;
        }
        radinterp__mesh_log(b, "radinterp_build_mesh: patch %u triangulated without its discontinuities", b->s->first_caller[P]);
        b->fallback++;
        with = 0;
    }
    return radinterp__emit_patch(b, w, P, with) != 0 ? RADINTERP_ERROR_OUT_OF_MEMORY : RADINTERP_OK;
}

/* ======================================================================
   20. interpolants (Hardt 3.3) and representation-based refinement (4.4.2)
   Each triangle gets six IrradianceAtPoint samples, at its corners and
   edge midpoints, and the quadratic through them in closed form. The
   triangles of a patch share the samples at the points where they meet
   (taken toward the centre of the first triangle in triangle order), but on
   a contact discontinuity each side takes its own, approached from the
   centre of a triangle on that side so that it takes its side's value.
   With refinement, SAMPLES x SAMPLES more points per triangle compare the
   interpolant with IrradianceAtPoint;
   a leaf whose worst difference exceeds eps is split and the pass repeats
   (triangles that did not change keep their samples).
   ---------------------------------------------------------------------- */
struct radinterp_mesh {
    radinterp_allocator allocator;
    void (*parallel_for)(void *user, radinterp_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    uint32_t vertex_count, triangle_count, patch_count, disc_count, leaf_count;
    float *positions;            /* 3 per vertex */
    uint32_t *indices;           /* 3 per triangle */
    uint32_t *tri_patch, *tri_leaf;
    unsigned char *edge_flags;
    float *irr;                  /* 18 per triangle: [6][3] irradiance coefficients */
    float *rad;                  /* 18 per triangle: radiosity coefficients */
    float *shade;                /* 24 per triangle: radiosity coefficients [6][4], for radinterp_shade */
    float *reflectance, *emission;   /* 3 per triangle */
    float *corner;               /* 9 per triangle */
    float *vertex_rad;           /* 3 per vertex */
    float *patch_rho, *patch_e;  /* 3 per patch */
    radinterp__disc_list discs;  /* disc_count records */
    radinterp_mesh_leaf *leaves;
    radinterp_mesh_info info;
};

/* Eq. 3.3 for one channel: coefficients (A, 2B, 2C, D, 2E, F) at c[0],
   c[stride], ... from values at (0,0), (1/2,0), (1,0), (1/2,1/2), (0,1),
   (0,1/2). (The thesis prints E = -3/2 r0 - 1/2 r4 + r5; its own system
   gives 2 r5 there, by symmetry with C.) */
static void radinterp__fit_channel(const double *r, float *c, size_t stride)
{
    c[0] = (float)(2.0 * r[0] - 4.0 * r[1] + 2.0 * r[2]);
    c[stride] = (float)(4.0 * (r[0] - r[1] + r[3] - r[5]));
    c[2 * stride] = (float)(-3.0 * r[0] + 4.0 * r[1] - r[2]);
    c[3 * stride] = (float)(2.0 * r[0] + 2.0 * r[4] - 4.0 * r[5]);
    c[4 * stride] = (float)(-3.0 * r[0] - r[4] + 4.0 * r[5]);
    c[5 * stride] = (float)r[0];
}

/* R(s, t) = A s^2 + 2B st + 2C s + D t^2 + 2E t + F (eq. 3.1), as
   s (A s + 2B t + 2C) + t (D t + 2E) + F: five multiplies, five adds. */
static float radinterp__quad_eval(const float *c, size_t stride, float s, float t)
{
    return s * (c[0] * s + c[stride] * t + c[2 * stride]) + t * (c[3 * stride] * t + c[4 * stride]) + c[5 * stride];
}

RADINTERP_API void radinterp_fit_quadratic(const float r[6], float coefficients[6])
{
    double d[6];
    int i;
    if (!r || !coefficients) return;
    for (i = 0; i < 6; i++) d[i] = r[i];
    radinterp__fit_channel(d, coefficients, 1);
}

#define RADINTERP__SAMPLE_JOB 1       /* points (or triangles) per job: the last jobs of a batch keep one
                                         thread waiting for the other, the fewer points the shorter */
#ifndef RADINTERP__SAMPLE_BATCH
#define RADINTERP__SAMPLE_BATCH 512   /* the most jobs between progress calls (the pacer sizes the batches
                                         below it): 512 point queries (at building scale a query in a penumbra
                                         takes up to about 20 ms of one core). Every batch ends by waiting for
                                         its last job: with 64 (v0.8.13) batches of the office's cheap points
                                         took 9 ms and two threads idled 13% of the time */
#endif

/* Where the six samples of a triangle lie, in (s, t): its corners 0, 1, 2
   at sample 0, 2, 4 and the midpoints of its edges at 1, 3, 5. */
static const double radinterp__sample_at[6][2] = {{0, 0}, {0.5, 0}, {1, 0}, {0.5, 0.5}, {0, 1}, {0, 0.5}};
static const unsigned char radinterp__sample_corner[6][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 2}, {2, 2}, {0, 2}};

/* A point the interpolants sample. Triangles of one patch meeting at a
   vertex or an edge take one sample there, so that neighbouring
   interpolants agree where they meet (C0 across leaf edges, inside a leaf
   and across discontinuities of the derivatives) and the build queries
   each point once. At points on a contact discontinuity, where the
   irradiance may jump, each side keeps its own sample, taken toward the
   centroid of a triangle on that side so that it sees that side: at an
   edge's midpoint each of the two triangles, at a vertex each sector of
   the triangles around it (radinterp__disc_sectors). */
typedef struct radinterp__spoint {
    float x[3], toward[3];
    uint32_t patch;
} radinterp__spoint;

typedef struct radinterp__sample_ctx {
    const radinterp__builder *b;
    const radinterp__spoint *pts;   /* the points to sample; their values go to value (3 per point) */
    double *value;
    const radinterp__leaf_lists *lists;   /* the leaf lists of the points' leaves (radinterp__sample_listed) */
    const radinterp__otri *tris;    /* the triangles whose representation error is measured (refine) */
    const uint32_t *unsampled;
    const float *coeff;
    float *error;
    uint32_t first, count;          /* this batch: items first .. first + count */
    radinterp__pacer pacer;         /* sizes the batches; kept from one run of batches to the next of the
                                       same job (sample_listed's runs, one per batch of leaf lists) */
    radinterp_result status[RADINTERP__SAMPLE_BATCH];   /* per job of the batch */
} radinterp__sample_ctx;

static void radinterp__point_in(const float *p0, const float *p1, const float *p2, double s, double t, float *out)
{
    int k;
    for (k = 0; k < 3; k++)
        out[k] = (float)((double)p0[k] + s * ((double)p1[k] - p0[k]) + t * ((double)p2[k] - p0[k]));
}

static void radinterp__point_job(void *ctx_, uint32_t index)
{
    radinterp__sample_ctx *ctx = (radinterp__sample_ctx *)ctx_;
    uint32_t i = ctx->first + index * RADINTERP__SAMPLE_JOB, end = i + RADINTERP__SAMPLE_JOB;
    if (end > ctx->first + ctx->count) end = ctx->first + ctx->count;
    ctx->status[index] = RADINTERP_OK;
    for (; i < end; i++) {
        const radinterp__spoint *p = &ctx->pts[i];
        radinterp_result r = radinterp__irradiance_listed(ctx->b->s, ctx->lists, p->patch, p->x, p->toward,
                                                          ctx->value + 3 * (size_t)i, NULL);
        if (r != RADINTERP_OK) ctx->status[index] = r;
    }
}

/* Largest difference between a triangle's interpolant and IrradianceAtPoint
   at SAMPLES x SAMPLES test points (4.4.2 step 2). */
static radinterp_result radinterp__fit_error(const radinterp__builder *b, const radinterp__otri *t, const float *c,
                                             float *err)
{
    const float *pos = (const float *)b->pos.data;
    const float *p0 = pos + 3 * (size_t)t->v[0], *p1 = pos + 3 * (size_t)t->v[1], *p2 = pos + 3 * (size_t)t->v[2];
    uint32_t n = b->refine_samples;
    float toward[3], x[3];
    double worst = 0.0;
    int i, j, ch;
    radinterp__point_in(p0, p1, p2, 1.0 / 3.0, 1.0 / 3.0, toward);
    for (i = 0; i < (int)n; i++)
        for (j = 0; j < (int)n; j++) {
            double s = (i + 0.5) / n, tt = (j + 0.5) / n, h[3];
            radinterp_result res;
            if (s + tt > 1.0) { s = 1.0 - s; tt = 1.0 - tt; }
            radinterp__point_in(p0, p1, p2, s, tt, x);
            res = radinterp__irradiance(b->s, t->patch, x, toward, h, NULL);
            if (res != RADINTERP_OK) return res;
            for (ch = 0; ch < 3; ch++) {
                double e = fabs(radinterp__quad_eval(c + ch, 3, (float)s, (float)tt) - h[ch]);
                worst = e > worst ? e : worst;
            }
        }
    *err = (float)worst;
    return RADINTERP_OK;
}

static void radinterp__error_job(void *ctx_, uint32_t index)
{
    radinterp__sample_ctx *ctx = (radinterp__sample_ctx *)ctx_;
    uint32_t i = ctx->first + index * RADINTERP__SAMPLE_JOB, end = i + RADINTERP__SAMPLE_JOB;
    if (end > ctx->first + ctx->count) end = ctx->first + ctx->count;
    ctx->status[index] = RADINTERP_OK;
    for (; i < end; i++) {
        uint32_t t = ctx->unsampled[i];
        radinterp_result r = radinterp__fit_error(ctx->b, &ctx->tris[t], ctx->coeff + 18 * (size_t)t, ctx->error + t);
        if (r != RADINTERP_OK) ctx->status[index] = r;
    }
}

/* Runs job over n items in batches of jobs ctx->pacer sizes, with a
   progress call after each batch (done counted from *done toward total). */
static radinterp_result radinterp__run_batches(radinterp__builder *b, radinterp_job_fn job, radinterp__sample_ctx *ctx,
                                               uint32_t n, uint64_t *done, uint64_t total)
{
    uint32_t at = 0, i;
    while (at < n) {
        uint32_t jobs = radinterp__pacer_next(&ctx->pacer, (n - at + RADINTERP__SAMPLE_JOB - 1) / RADINTERP__SAMPLE_JOB);
        uint32_t count = n - at > jobs * RADINTERP__SAMPLE_JOB ? jobs * RADINTERP__SAMPLE_JOB : n - at;
        ctx->first = at;
        ctx->count = count;
        radinterp__run_jobs(b->desc->parallel_for, b->desc->parallel_user, job, ctx, jobs);
        radinterp__pacer_adapt(&ctx->pacer);
        for (i = 0; i < jobs; i++)
            if (ctx->status[i] != RADINTERP_OK) return ctx->status[i];
        at += count;
        *done += count;
        if (b->desc->progress && b->desc->progress(b->desc->progress_user, *done, total)) return RADINTERP_ERROR_CANCELLED;
    }
    return RADINTERP_OK;
}

/* Marks the vertices of triangle edges on contact discontinuities. */
static void radinterp__mark_disc_vertices(const radinterp__builder *b, const uint32_t *list, uint32_t n,
                                          unsigned char *on_disc)
{
    const radinterp__otri *tris = (const radinterp__otri *)b->tris.data;
    uint32_t i, k;
    for (i = 0; i < n; i++) {
        const radinterp__otri *t = &tris[list[i]];
        for (k = 0; k < 3; k++)
            if (t->flags & (RADINTERP__EDGE_JUMP << k)) on_disc[t->v[(k + 1) % 3]] = on_disc[t->v[(k + 2) % 3]] = 1;
    }
}

/* The sectors of the corners of the listed triangles that lie at vertices
   on a contact discontinuity (on_disc): corner k of list[i] is slot 3 i + k,
   and parent (3 n slots) joins the slots of one vertex whose triangles
   share an edge through it that is not on a contact discontinuity. A
   sector is then the triangles around the vertex between two edges on the
   discontinuity (all of them where none passes): one side of it, where the
   irradiance is continuous. Each slot's root (radinterp__uf_find) is the
   sector's first slot in list order. Taking one sample per sector instead
   of one per triangle left 30,000 of the 1k building's 404,000 samples out
   (46,000 at such vertices in 16,000 sectors), and the triangles of a
   sector now meet at the same value there as elsewhere inside a leaf.
   Returns -1 when out of memory. */
static int radinterp__disc_sectors(const radinterp__builder *b, const uint32_t *list, uint32_t n,
                                   const unsigned char *on_disc, uint32_t *parent)
{
    const radinterp__otri *tris = (const radinterp__otri *)b->tris.data;
    radinterp__hmap edges;   /* edge (two vertices, patch) off the discontinuities -> first listed triangle */
    uint32_t i, k, e, key[3];
    for (i = 0; i < 3 * n; i++) parent[i] = i;
    memset(&edges, 0, sizeof edges);
    if (radinterp__hmap_init(&b->a, &edges, 3, 64) != 0) return -1;
    for (i = 0; i < n; i++) {
        const radinterp__otri *t = &tris[list[i]];
        for (e = 0; e < 3; e++) {
            uint32_t a = t->v[(e + 1) % 3], c = t->v[(e + 2) % 3], j;
            const radinterp__otri *u;
            if ((t->flags & (RADINTERP__EDGE_JUMP << e)) || (!on_disc[a] && !on_disc[c])) continue;
            key[0] = a < c ? a : c;
            key[1] = a < c ? c : a;
            key[2] = t->patch;
            j = radinterp__hmap_put(&b->a, &edges, key, i);
            if (j == RADINTERP__NONE) { radinterp__hmap_free(&b->a, &edges); return -1; }
            if (j == i) continue;
            u = &tris[list[j]];
            for (k = 0; k < 3; k++) {   /* the edge's ends on the discontinuity: join their corners in t and u */
                uint32_t v = t->v[k], m, x, y;
                if ((k != (e + 1) % 3 && k != (e + 2) % 3) || !on_disc[v]) continue;
                for (m = 0; m < 3 && u->v[m] != v; m++) {}
                x = radinterp__uf_find(parent, 3 * i + k);
                y = radinterp__uf_find(parent, 3 * j + m);
                if (x < y) parent[y] = x;   /* the root stays the first slot */
                else parent[x] = y;
            }
        }
    }
    radinterp__hmap_free(&b->a, &edges);
    return 0;
}

/* The sample points of the listed triangles, into pts, and for each
   triangle the indices of its six (tri_pt, 6 per listed triangle), in
   triangle order so that the points and the centroids they are taken
   toward do not depend on the thread count. Returns -1 when out of
   memory. */
static int radinterp__sample_points(radinterp__builder *b, const uint32_t *list, uint32_t n, radinterp__buf *pts,
                                    uint32_t *tri_pt)
{
    const radinterp__otri *tris = (const radinterp__otri *)b->tris.data;
    const float *pos = (const float *)b->pos.data;
    unsigned char *on_disc = (unsigned char *)radinterp__alloc(&b->a, b->pos.count / 3 + 1);
    uint32_t *sector = (uint32_t *)radinterp__alloc_array(&b->a, 3 * (size_t)n + 1, sizeof(uint32_t));
    radinterp__hmap shared;
    uint32_t i, j, key[3];
    int failed = 0;
    memset(&shared, 0, sizeof shared);
    if (!on_disc || !sector || radinterp__hmap_init(&b->a, &shared, 3, 2 * n + 16) != 0) failed = 1;
    if (!failed) {
        memset(on_disc, 0, b->pos.count / 3 + 1);
        radinterp__mark_disc_vertices(b, list, n, on_disc);
        if (radinterp__disc_sectors(b, list, n, on_disc, sector) != 0) failed = 1;
    }
    for (i = 0; i < n && !failed; i++) {
        const radinterp__otri *t = &tris[list[i]];
        float toward[3];
        radinterp__point_in(pos + 3 * (size_t)t->v[0], pos + 3 * (size_t)t->v[1], pos + 3 * (size_t)t->v[2],
                            1.0 / 3.0, 1.0 / 3.0, toward);
        for (j = 0; j < 6 && !failed; j++) {
            uint32_t a = t->v[radinterp__sample_corner[j][0]], c = t->v[radinterp__sample_corner[j][1]];
            uint32_t edge = 3u - radinterp__sample_corner[j][0] - radinterp__sample_corner[j][1];  /* opposite corner */
            uint32_t next = (uint32_t)pts->count, got = next;
            int own = a == c ? on_disc[a] : (t->flags & (RADINTERP__EDGE_JUMP << edge)) != 0;
            radinterp__spoint *sp;
            if (own && a == c) {   /* the sector's sample, made at its first corner (corner k is sample 2 k) */
                uint32_t first = radinterp__uf_find(sector, 3 * i + radinterp__sample_corner[j][0]);
                if (first != 3 * i + radinterp__sample_corner[j][0]) {
                    tri_pt[6 * (size_t)i + j] = tri_pt[6 * (size_t)(first / 3) + 2 * (first % 3)];
                    continue;
                }
            }
            if (!own) {
                key[0] = a < c ? a : c;
                key[1] = a < c ? c : a;
                key[2] = t->patch;
                got = radinterp__hmap_put(&b->a, &shared, key, next);
                if (got == RADINTERP__NONE) { failed = 1; break; }
            }
            tri_pt[6 * (size_t)i + j] = got;
            if (got != next) continue;
            if (!(sp = (radinterp__spoint *)radinterp__buf_push(&b->a, pts))) { failed = 1; break; }
            if (a == c) memcpy(sp->x, pos + 3 * (size_t)a, sizeof sp->x);
            else if (own) radinterp__point_in(pos + 3 * (size_t)t->v[0], pos + 3 * (size_t)t->v[1], pos + 3 * (size_t)t->v[2],
                                              radinterp__sample_at[j][0], radinterp__sample_at[j][1], sp->x);
            else radinterp__point_in(pos + 3 * (size_t)key[0], pos + 3 * (size_t)key[1], pos + 3 * (size_t)key[0], 0.5, 0.0, sp->x);
            memcpy(sp->toward, toward, sizeof toward);
            sp->patch = t->patch;
        }
    }
    radinterp__free(&b->a, on_disc);
    radinterp__free(&b->a, sector);
    radinterp__hmap_free(&b->a, &shared);
    return failed ? -1 : 0;
}

/* The leaves the points pts[at ..) read (radinterp__query_leaf, where the
   leaf lists hold), into leaves (ascending), from at up to the first point
   whose leaf's list would take the batch past RADINTERP__LEAF_BATCH_BYTES
   (at least one leaf); mark[leaf] = batch for those taken. Returns that
   point. */
#ifndef RADINTERP__LEAF_BATCH_BYTES
#define RADINTERP__LEAF_BATCH_BYTES ((size_t)1 << 24)
#endif
static uint32_t radinterp__batch_leaves(const radinterp_solution *s, const radinterp__spoint *pts, uint32_t at,
                                        uint32_t n, uint32_t *mark, uint32_t batch, uint32_t *leaves, uint32_t *count)
{
    size_t bytes = 0;
    *count = 0;
    for (; at < n; at++) {
        double p[3], pv[3];
        uint32_t leaf;
        size_t size;
        int lists;
        if (!radinterp__patch_ok(s, pts[at].patch) || !radinterp__finite3(pts[at].x) || !radinterp__finite3(pts[at].toward))
            continue;   /* the query says so */
        radinterp__d3_from_f(pts[at].x, p);
        radinterp__nudge(s, pts[at].patch, p, pts[at].toward, pv);
        leaf = radinterp__query_leaf(s, pts[at].patch, p, pv, &lists);
        if (!lists || mark[leaf] == batch) continue;
        size = radinterp__leaf_bytes(s, leaf);
        if (*count && bytes + size > RADINTERP__LEAF_BATCH_BYTES) break;
        mark[leaf] = batch;
        leaves[(*count)++] = leaf;
        bytes += size;
    }
    qsort(leaves, *count, sizeof *leaves, radinterp__cmp_u32);
    return at;
}

/* Fills ll's lists (radinterp__leaf_lists_job) in batches of jobs pacer
   sizes (kept from one batch of leaves to the next: started afresh, each
   batch's lists began with a job of 16 leaves, then 32, ...), with a
   progress call after each (done of total, the samples' count); CANCELLED
   when progress asks. */
static radinterp_result radinterp__fill_leaf_lists(radinterp__builder *b, radinterp__leaf_lists *ll,
                                                   radinterp__pacer *pacer, uint64_t done, uint64_t total)
{
    uint32_t jobs = radinterp__leaf_lists_jobs(ll), at = 0;
    while (at < jobs) {
        uint32_t k = radinterp__pacer_next(pacer, jobs - at);
        ll->job_first = at;
        radinterp__run_jobs(b->desc->parallel_for, b->desc->parallel_user, radinterp__leaf_lists_job, ll, k);
        radinterp__pacer_adapt(pacer);
        at += k;
        if (b->desc->progress && b->desc->progress(b->desc->progress_user, done, total)) return RADINTERP_ERROR_CANCELLED;
    }
    return RADINTERP_OK;
}

/* Samples ctx's n points (radinterp__point_job) batch by batch of the
   leaves they read (radinterp__batch_leaves): each batch's leaf lists are
   built before its points and freed after them, so the lists held at once
   stay within the batch's bound whatever the building's size. */
static radinterp_result radinterp__sample_listed(radinterp__builder *b, radinterp__sample_ctx *ctx, uint32_t n,
                                                 uint64_t *done, uint64_t total)
{
    const radinterp_solution *s = b->s;
    const radinterp__spoint *pts = ctx->pts;
    double *value = ctx->value;
    uint32_t *mark = (uint32_t *)radinterp__alloc_array(&b->a, (size_t)s->node_count + 1, sizeof(uint32_t));
    uint32_t *leaves = (uint32_t *)radinterp__alloc_array(&b->a, (size_t)s->leaf_count + 1, sizeof(uint32_t));
    uint32_t at = 0, batch = 0, count;
    radinterp__pacer pacer;   /* the lists' jobs; no buffer bounds a batch of them */
    radinterp_result res = mark && leaves ? RADINTERP_OK : RADINTERP_ERROR_OUT_OF_MEMORY;
    radinterp__pacer_init(&pacer, b->desc->progress_interval, UINT32_MAX);
    if (mark) memset(mark, 0xFF, ((size_t)s->node_count + 1) * sizeof(uint32_t));
    while (res == RADINTERP_OK && at < n) {
        radinterp__leaf_lists lists;
        uint32_t end = radinterp__batch_leaves(s, pts, at, n, mark, batch++, leaves, &count);
        res = radinterp__leaf_lists_make(s, &b->a, leaves, count, &lists);
        if (res != RADINTERP_OK) break;
        res = radinterp__fill_leaf_lists(b, &lists, &pacer, *done, total);
        if (res != RADINTERP_OK) { radinterp__leaf_lists_free(&b->a, &lists); break; }
        if (lists.bytes > b->leaf_list_bytes) b->leaf_list_bytes = lists.bytes;
        radinterp__note_bytes(b, lists.bytes);   /* the batch is held beside the builder's arrays */
        ctx->pts = pts + at;
        ctx->value = value + 3 * (size_t)at;
        ctx->lists = &lists;
        res = radinterp__run_batches(b, radinterp__point_job, ctx, end - at, done, total);
        radinterp__leaf_lists_free(&b->a, &lists);
        at = end;
    }
    ctx->pts = pts;
    ctx->value = value;
    ctx->lists = NULL;
    radinterp__free(&b->a, mark);
    radinterp__free(&b->a, leaves);
    return res;
}

/* The coefficients (eq. 3.3) of the listed triangles from their six
   samples, with refinement their representation error too. */
static radinterp_result radinterp__sample_all(radinterp__builder *b, const uint32_t *unsampled, uint32_t n,
                                              float *coeff, float *error)
{
    radinterp__sample_ctx ctx;
    radinterp__buf pts;
    uint32_t *tri_pt = (uint32_t *)radinterp__alloc_array(&b->a, (size_t)n * 6 + 1, sizeof(uint32_t));
    uint64_t done = 0, total;
    radinterp_result res = RADINTERP_OK;
    uint32_t i, j, ch;
    memset(&ctx, 0, sizeof ctx);
    radinterp__buf_init(&pts, sizeof(radinterp__spoint));
    if (!tri_pt || radinterp__sample_points(b, unsampled, n, &pts, tri_pt) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    if (res == RADINTERP_OK && !(ctx.value = (double *)radinterp__alloc_array(&b->a, pts.count * 3 + 1, sizeof(double))))
        res = RADINTERP_ERROR_OUT_OF_MEMORY;
    total = pts.count + (b->desc->refine ? n : 0u);
    ctx.b = b;
    ctx.pts = (const radinterp__spoint *)pts.data;
    radinterp__pacer_init(&ctx.pacer, b->desc->progress_interval, RADINTERP__SAMPLE_BATCH);
    if (res == RADINTERP_OK) res = radinterp__sample_listed(b, &ctx, (uint32_t)pts.count, &done, total);
    for (i = 0; i < n && res == RADINTERP_OK; i++) {
        float *c = coeff + 18 * (size_t)unsampled[i];
        for (ch = 0; ch < 3; ch++) {
            double v[6];
            for (j = 0; j < 6; j++) v[j] = ctx.value[3 * (size_t)tri_pt[6 * (size_t)i + j] + ch];
            radinterp__fit_channel(v, c + ch, 3);
        }
        error[unsampled[i]] = -1.0f;
    }
    b->samples += pts.count;
    if (res == RADINTERP_OK && b->desc->refine) {
        ctx.tris = (const radinterp__otri *)b->tris.data;
        ctx.unsampled = unsampled;
        ctx.coeff = coeff;
        ctx.error = error;
        /* refine_samples^2 queries a job: sized afresh */
        radinterp__pacer_init(&ctx.pacer, b->desc->progress_interval, RADINTERP__SAMPLE_BATCH);
        res = radinterp__run_batches(b, radinterp__error_job, &ctx, n, &done, total);
        b->samples += (uint64_t)n * b->refine_samples * b->refine_samples;
    }
    radinterp__free(&b->a, tri_pt);
    radinterp__free(&b->a, ctx.value);
    radinterp__buf_free(&b->a, &pts);
    return res;
}

/* Key of a triangle for reusing its samples in the next pass. */
static void radinterp__tri_key(const radinterp__builder *b, const radinterp__otri *t, uint32_t *key)
{
    const float *pos = (const float *)b->pos.data;
    int k;
    for (k = 0; k < 3; k++) radinterp__point_key(pos + 3 * (size_t)t->v[k], 0, key + 3 * k);
    key[9] = t->patch;
}

typedef struct radinterp__interp {
    float *coeff, *error;        /* of the current pass */
    float *prev_coeff, *prev_error;
    radinterp__hmap prev;        /* triangle key -> index in the previous pass */
} radinterp__interp;

static void radinterp__interp_free(const radinterp_allocator *a, radinterp__interp *ip)
{
    radinterp__free(a, ip->coeff);
    radinterp__free(a, ip->error);
    radinterp__free(a, ip->prev_coeff);
    radinterp__free(a, ip->prev_error);
    radinterp__hmap_free(a, &ip->prev);
    memset(ip, 0, sizeof *ip);
}

/* Bytes ip holds for a pass of n triangles: their coefficients and errors
   (this pass's, or kept as the previous pass's) and the previous pass's keys. */
static size_t radinterp__interp_bytes(const radinterp__interp *ip, size_t n)
{
    return n * 19 * sizeof(float) + radinterp__hmap_bytes(&ip->prev);
}

/* Coefficients of the pass's triangles: from the previous pass where the
   triangle is unchanged, else sampled. Remembers them for the next pass. */
static radinterp_result radinterp__interpolants(radinterp__builder *b, radinterp__interp *ip)
{
    uint32_t n = (uint32_t)b->tris.count, i, key[10], unsampled_n = 0, *unsampled;
    const radinterp__otri *tris = (const radinterp__otri *)b->tris.data;
    radinterp_result res;
    ip->coeff = (float *)radinterp__alloc_array(&b->a, (size_t)n * 18, sizeof(float));
    ip->error = (float *)radinterp__alloc_array(&b->a, n, sizeof(float));
    unsampled = (uint32_t *)radinterp__alloc_array(&b->a, n, sizeof(uint32_t));
    if (!ip->coeff || !ip->error || !unsampled) {
        radinterp__free(&b->a, unsampled);
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    for (i = 0; i < n; i++) {
        uint32_t old = RADINTERP__NONE;
        if (ip->prev.cap) {
            radinterp__tri_key(b, &tris[i], key);
            old = radinterp__hmap_get(&ip->prev, key);
        }
        if (old != RADINTERP__NONE) {
            memcpy(ip->coeff + 18 * (size_t)i, ip->prev_coeff + 18 * (size_t)old, 18 * sizeof(float));
            ip->error[i] = ip->prev_error[old];
        } else {
            unsampled[unsampled_n++] = i;
        }
    }
    res = radinterp__sample_all(b, unsampled, unsampled_n, ip->coeff, ip->error);
    radinterp__free(&b->a, unsampled);
    if (res != RADINTERP_OK) return res;
    if (b->desc->refine) {  /* remember this pass */
        radinterp__free(&b->a, ip->prev_coeff);
        radinterp__free(&b->a, ip->prev_error);
        ip->prev_coeff = ip->coeff;
        ip->prev_error = ip->error;
        ip->coeff = ip->error = NULL;
        radinterp__hmap_free(&b->a, &ip->prev);
        if (radinterp__hmap_init(&b->a, &ip->prev, 10, n) != 0) return RADINTERP_ERROR_OUT_OF_MEMORY;
        for (i = 0; i < n; i++) {
            radinterp__tri_key(b, &tris[i], key);
            if (radinterp__hmap_put(&b->a, &ip->prev, key, i) == RADINTERP__NONE) return RADINTERP_ERROR_OUT_OF_MEMORY;
        }
    }
    return RADINTERP_OK;
}

/* Splits every leaf whose triangles miss IrradianceAtPoint by more than
   eps (4.4.2 step 3). Returns the number split, or -1 when out of memory. */
static int radinterp__refine_leaves(radinterp__builder *b, const float *error, float *worst)
{
    const radinterp__otri *tris = (const radinterp__otri *)b->tris.data;
    uint32_t nl = (uint32_t)b->leaves.count, i, split = 0;
    float *leaf_err = (float *)radinterp__alloc_array(&b->a, nl, sizeof(float));
    uint32_t *list = (uint32_t *)radinterp__alloc_array(&b->a, nl, sizeof(uint32_t));
    if (!leaf_err || !list) {
        radinterp__free(&b->a, leaf_err);
        radinterp__free(&b->a, list);
        return -1;
    }
    for (i = 0; i < nl; i++) leaf_err[i] = 0.0f;
    for (i = 0; i < b->tris.count; i++) {
        uint32_t l = RADINTERP__MNODES(b)[tris[i].node].leaf;
        if (error[i] > leaf_err[l]) leaf_err[l] = error[i];
        if (error[i] > *worst) *worst = error[i];
    }
    for (i = 0; i < nl; i++) {
        uint32_t node = RADINTERP__U32(b->leaves)[i];
        if (leaf_err[i] > b->refine_eps && 0.25 * radinterp__mnode_area(&RADINTERP__MNODES(b)[node]) >= b->refine_min_area)
            list[split++] = node;
    }
    for (i = 0; i < split; i++)
        if (radinterp__mnode_split(b, list[i]) != 0) { split = RADINTERP__NONE; break; }
    radinterp__free(&b->a, leaf_err);
    radinterp__free(&b->a, list);
    return split == RADINTERP__NONE ? -1 : (int)split;
}

/* One pass over the current quadtrees: activation, discontinuity edges,
   outline vertices, and every patch's triangles. */
static radinterp_result radinterp__mesh_pass(radinterp__builder *b)
{
    const radinterp_solution *s = b->s;
    radinterp__tri_work w;
    radinterp__hmap seen;
    radinterp__buf tmp, near;
    uint32_t P, k, *own = NULL;
    size_t at;
    radinterp_result res = RADINTERP_OK;
    radinterp__tri_work_init(&w, &b->a);
    memset(&seen, 0, sizeof seen);
    radinterp__buf_init(&tmp, sizeof(radinterp__tkey));
    radinterp__buf_init(&near, sizeof(uint32_t));
    b->segs.count = b->pool.count = b->chains.count = b->pos.count = b->tris.count = 0;
    b->hanging = b->seam = b->fallback = b->degenerate = b->skipped = 0;
    radinterp__hmap_clear(&b->vmap);
    if (radinterp__collect_mleaves(b, &w.stack) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    if (res == RADINTERP_OK) res = radinterp__activate(b);
    for (P = 0; P < s->patch_count && res == RADINTERP_OK; P++)
        if (radinterp__mesh_tick(b)) res = RADINTERP_ERROR_CANCELLED;
        else if (radinterp__patch_segments(b, P) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    if (res == RADINTERP_OK && radinterp__hmap_init(&b->a, &seen, 4, 1024) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    for (P = 0; P < s->patch_count && res == RADINTERP_OK; P++) {
        if (!s->patches[P].count) continue;
        if (radinterp__mesh_tick(b)) res = RADINTERP_ERROR_CANCELLED;
        else if (radinterp__outline_vertices(b, P, &seen) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    if (res == RADINTERP_OK && radinterp__weld(b) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    if (res == RADINTERP_OK) {   /* the pool is in patch order */
        size_t i;
        if (!b->pool_first) b->pool_first = (uint32_t *)radinterp__alloc_array(&b->a, (size_t)s->patch_count + 1, sizeof(uint32_t));
        if (!b->pool_first) res = RADINTERP_ERROR_OUT_OF_MEMORY;
        else {
            memset(b->pool_first, 0, ((size_t)s->patch_count + 1) * sizeof(uint32_t));
            for (i = 0; i < b->pool.count; i++) b->pool_first[RADINTERP__BVERTS(b)[i].patch + 1]++;
            for (P = 0; P < s->patch_count; P++) b->pool_first[P + 1] += b->pool_first[P];
        }
    }
    if (res == RADINTERP_OK) {
        own = (uint32_t *)radinterp__alloc_array(&b->a, b->pool.count ? b->pool.count : 1, sizeof(uint32_t));
        if (!own) res = RADINTERP_ERROR_OUT_OF_MEMORY;
        else memset(own, 0, (b->pool.count ? b->pool.count : 1) * sizeof(uint32_t));
    }
    for (P = 0, at = 0; P < s->patch_count && res == RADINTERP_OK; P++) {
        size_t i;
        if (!s->patches[P].count) continue;
        while (at < b->pool.count && RADINTERP__BVERTS(b)[at].patch < P) at++;   /* the pool is in patch order */
        for (i = at; i < b->pool.count && RADINTERP__BVERTS(b)[i].patch == P; i++) own[RADINTERP__BVERTS(b)[i].rep] = P + 1u;
        for (k = 0; k < s->patches[P].count && res == RADINTERP_OK; k++)
            if (radinterp__make_chain(b, P, k, own, &tmp, &near) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    }
    if (res == RADINTERP_OK && radinterp__hmap_init(&b->a, &w.lmap, 4, 256) != 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
    for (P = 0; P < s->patch_count && res == RADINTERP_OK; P++)
        if (radinterp__mesh_cancelled(b)) res = RADINTERP_ERROR_CANCELLED;
        else if (s->patches[P].count) res = radinterp__triangulate_patch(b, &w, P);
    radinterp__free(&b->a, own);
    radinterp__buf_free(&b->a, &tmp);
    radinterp__buf_free(&b->a, &near);
    radinterp__hmap_free(&b->a, &seen);
    radinterp__tri_work_free(&b->a, &w);
    return res;
}

/* ======================================================================
   21. radinterp_build_mesh and the mesh object
   ---------------------------------------------------------------------- */
static int radinterp__mesh_alloc(radinterp_mesh *m)
{
    const radinterp_allocator *a = &m->allocator;
    size_t V = m->vertex_count, T = m->triangle_count, P = m->patch_count;
    m->positions = (float *)radinterp__alloc_array(a, V, 3 * sizeof(float));
    m->indices = (uint32_t *)radinterp__alloc_array(a, T, 3 * sizeof(uint32_t));
    m->tri_patch = (uint32_t *)radinterp__alloc_array(a, T, sizeof(uint32_t));
    m->tri_leaf = (uint32_t *)radinterp__alloc_array(a, T, sizeof(uint32_t));
    m->edge_flags = (unsigned char *)radinterp__alloc_array(a, T, 1);
    m->irr = (float *)radinterp__alloc_array(a, T, 18 * sizeof(float));
    m->rad = (float *)radinterp__alloc_array(a, T, 18 * sizeof(float));
    m->shade = (float *)radinterp__alloc_array(a, T, 24 * sizeof(float));
    m->reflectance = (float *)radinterp__alloc_array(a, T, 3 * sizeof(float));
    m->emission = (float *)radinterp__alloc_array(a, T, 3 * sizeof(float));
    m->corner = (float *)radinterp__alloc_array(a, T, 9 * sizeof(float));
    m->vertex_rad = (float *)radinterp__alloc_array(a, V, 3 * sizeof(float));
    m->patch_rho = (float *)radinterp__alloc_array(a, P, 3 * sizeof(float));
    m->patch_e = (float *)radinterp__alloc_array(a, P, 3 * sizeof(float));
    m->leaves = (radinterp_mesh_leaf *)radinterp__alloc_array(a, m->leaf_count, sizeof(radinterp_mesh_leaf));
    return m->positions && m->indices && m->tri_patch && m->tri_leaf && m->edge_flags && m->irr && m->rad && m->shade &&
                   m->reflectance && m->emission && m->corner && m->vertex_rad && m->patch_rho && m->patch_e && m->leaves
               ? 0
               : -1;
}

RADINTERP_API void radinterp_mesh_destroy(radinterp_mesh *m)
{
    radinterp_allocator a;
    if (!m) return;
    a = m->allocator;
    radinterp__free(&a, m->positions);
    radinterp__free(&a, m->indices);
    radinterp__free(&a, m->tri_patch);
    radinterp__free(&a, m->tri_leaf);
    radinterp__free(&a, m->edge_flags);
    radinterp__free(&a, m->irr);
    radinterp__free(&a, m->rad);
    radinterp__free(&a, m->shade);
    radinterp__free(&a, m->reflectance);
    radinterp__free(&a, m->emission);
    radinterp__free(&a, m->corner);
    radinterp__free(&a, m->vertex_rad);
    radinterp__free(&a, m->patch_rho);
    radinterp__free(&a, m->patch_e);
    radinterp__disc_list_free(&a, &m->discs);
    radinterp__free(&a, m->leaves);
    radinterp__free(&a, m);
}

/* Everything that follows from the irradiance interpolants and the
   materials: radiosity coefficients B = E + rho H, the shading table,
   corner and vertex radiosities. */
static int radinterp__mesh_derive(radinterp_mesh *m)
{
    uint32_t t, k, ch, v;
    uint32_t *uses = (uint32_t *)radinterp__alloc_array(&m->allocator, m->vertex_count, sizeof(uint32_t));
    static const float corner_st[3][2] = {{0, 0}, {1, 0}, {0, 1}};
    if (!uses) return -1;
    memset(uses, 0, (size_t)m->vertex_count * sizeof(uint32_t));
    memset(m->vertex_rad, 0, (size_t)m->vertex_count * 3 * sizeof(float));
    for (t = 0; t < m->triangle_count; t++) {
        const float *rho = m->patch_rho + 3 * (size_t)m->tri_patch[t], *e = m->patch_e + 3 * (size_t)m->tri_patch[t];
        float *rad = m->rad + 18 * (size_t)t, *sh = m->shade + 24 * (size_t)t;
        const float *irr = m->irr + 18 * (size_t)t;
        memcpy(m->reflectance + 3 * (size_t)t, rho, 3 * sizeof(float));
        memcpy(m->emission + 3 * (size_t)t, e, 3 * sizeof(float));
        for (k = 0; k < 6; k++)
            for (ch = 0; ch < 3; ch++) rad[3 * k + ch] = rho[ch] * irr[3 * k + ch] + (k == 5 ? e[ch] : 0.0f);
        for (k = 0; k < 6; k++) {
            for (ch = 0; ch < 3; ch++) sh[4 * k + ch] = rad[3 * k + ch];
            sh[4 * k + 3] = 0.0f;
        }
        for (k = 0; k < 3; k++) {
            uint32_t vi = m->indices[3 * (size_t)t + k];
            for (ch = 0; ch < 3; ch++) {
                float b = radinterp__quad_eval(rad + ch, 3, corner_st[k][0], corner_st[k][1]);
                m->corner[9 * (size_t)t + 3 * k + ch] = b;
                m->vertex_rad[3 * (size_t)vi + ch] += b;
            }
            uses[vi]++;
        }
    }
    for (v = 0; v < m->vertex_count; v++)
        for (ch = 0; ch < 3; ch++)
            if (uses[v]) m->vertex_rad[3 * (size_t)v + ch] /= (float)uses[v];
    radinterp__free(&m->allocator, uses);
    return 0;
}

static size_t radinterp__mesh_bytes(const radinterp_mesh *m)
{
    return sizeof *m + (size_t)m->vertex_count * 6 * sizeof(float) +
           (size_t)m->triangle_count * (5 * sizeof(uint32_t) + 1 + (18 + 18 + 24 + 3 + 3 + 9) * sizeof(float)) +
           (size_t)m->patch_count * 6 * sizeof(float) +
           radinterp__disc_list_bytes(&m->discs) + m->discs.blocks.count * sizeof(radinterp_discontinuity *) +
           (size_t)m->leaf_count * sizeof(radinterp_mesh_leaf);
}

/* Discontinuities found: the four kinds together, saturated like each of
   them (a loaded mesh's counts are the file's). */
static uint32_t radinterp__kinds_total(const radinterp_mesh_info *info)
{
    uint64_t n = (uint64_t)info->ev + info->ve + info->horizon + info->contact;
    return n < 0xFFFFFFFFu ? (uint32_t)n : 0xFFFFFFFFu;
}

/* The mesh from the last pass. */
static radinterp_result radinterp__assemble(radinterp__builder *b, const float *coeff, const float *error,
                                            radinterp_mesh **out)
{
    const radinterp_solution *s = b->s;
    const radinterp__otri *tris = (const radinterp__otri *)b->tris.data;
    const radinterp__disc *dd = (const radinterp__disc *)b->discs.data;
    radinterp_mesh *m = (radinterp_mesh *)radinterp__alloc(&b->a, sizeof *m);
    radinterp_mesh_info *info;
    uint32_t i;
    if (!m) return RADINTERP_ERROR_OUT_OF_MEMORY;
    memset(m, 0, sizeof *m);
    m->allocator = b->a;
    m->parallel_for = b->desc->parallel_for;
    m->parallel_user = b->desc->parallel_user;
    m->vertex_count = (uint32_t)(b->pos.count / 3);
    m->triangle_count = (uint32_t)b->tris.count;
    m->patch_count = s->caller_count;
    m->disc_count = b->found.count;
    m->leaf_count = (uint32_t)b->leaves.count;
    if (radinterp__mesh_alloc(m) != 0) { radinterp_mesh_destroy(m); return RADINTERP_ERROR_OUT_OF_MEMORY; }
    memcpy(m->positions, b->pos.data, b->pos.count * sizeof(float));
    memcpy(m->irr, coeff, (size_t)m->triangle_count * 18 * sizeof(float));
    for (i = 0; i < m->triangle_count; i++) {
        memcpy(m->indices + 3 * (size_t)i, tris[i].v, 3 * sizeof(uint32_t));
        m->tri_patch[i] = s->first_caller[tris[i].patch];
        m->tri_leaf[i] = RADINTERP__MNODES(b)[tris[i].node].leaf;
        m->edge_flags[i] = (unsigned char)(tris[i].flags & 63u);
    }
    for (i = 0; i < s->caller_count; i++) {
        memcpy(m->patch_rho + 3 * (size_t)i, s->patches[s->caller_patch[i]].rho, 3 * sizeof(float));
        memcpy(m->patch_e + 3 * (size_t)i, s->patches[s->caller_patch[i]].e, 3 * sizeof(float));
    }
    info = &m->info;
    m->discs = b->found;   /* the mesh takes the blocks over */
    radinterp__disc_list_init(&b->found);
    info->ev = b->found_kinds[RADINTERP_DISCONTINUITY_EV];
    info->ve = b->found_kinds[RADINTERP_DISCONTINUITY_VE];
    info->horizon = b->found_kinds[RADINTERP_DISCONTINUITY_HORIZON];
    info->contact = b->found_kinds[RADINTERP_DISCONTINUITY_CONTACT];
    info->candidates = (uint32_t)b->discs.count;
    for (i = 0; i < b->discs.count; i++) {
        radinterp__disc_list_at(&m->discs, dd[i].found)->active = (int)dd[i].active;
        info->active_discontinuities += dd[i].active;
    }
    for (i = 0; i < m->leaf_count; i++) {
        const radinterp__mnode *nd = &RADINTERP__MNODES(b)[RADINTERP__U32(b->leaves)[i]];
        radinterp_mesh_leaf *l = &m->leaves[i];
        memset(l, 0, sizeof *l);
        l->patch = s->first_caller[nd->patch];
        l->depth = nd->depth;
        l->vertex_count = nd->count;
        memcpy(l->vertices, nd->v, sizeof l->vertices);
        radinterp__leaf_dsets(b, nd, &l->dsets, &l->active_dsets);
        l->first_triangle = m->triangle_count;
        l->error = b->desc->refine ? 0.0f : -1.0f;
        info->active_leaf_dsets += l->active_dsets;
        if (l->active_dsets > info->max_leaf_active_dsets) info->max_leaf_active_dsets = l->active_dsets;
    }
    for (i = 0; i < m->triangle_count; i++) {
        radinterp_mesh_leaf *l = &m->leaves[m->tri_leaf[i]];
        if (l->triangle_count == 0) l->first_triangle = i;
        l->triangle_count++;
        if (b->desc->refine && error[i] > l->error) l->error = error[i];
    }
    for (i = 0; i < m->leaf_count; i++)
        if (m->leaves[i].triangle_count == 0) m->leaves[i].first_triangle = 0;
    if (radinterp__mesh_derive(m) != 0) { radinterp_mesh_destroy(m); return RADINTERP_ERROR_OUT_OF_MEMORY; }
    info->triangle_count = m->triangle_count;
    info->vertex_count = m->vertex_count;
    info->leaf_count = m->leaf_count;
    info->patch_count = m->patch_count;
    info->discontinuities = radinterp__kinds_total(info);
    info->kept_discontinuities = m->disc_count;
    info->dsets = (uint32_t)b->dsets.count;
    info->balance_splits = b->balance_splits;
    info->hanging_vertices = b->hanging;
    info->seam_vertices = b->seam;
    info->fallback_patches = b->fallback;
    info->skipped_patches = b->skipped;
    info->samples = b->samples;
    info->leaf_list_bytes = b->leaf_list_bytes;
    *out = m;
    return RADINTERP_OK;
}

static radinterp_result radinterp__check_mesh_desc(const radinterp_mesh_desc *d)
{
    const char *bad = NULL;
    if (!radinterp__allocator_valid(&d->allocator)) bad = "allocator.alloc and allocator.free must both be set or both be NULL";
    else if (radinterp__bad_param(d->min_discont_weight) || radinterp__bad_param(d->min_discont_contrast) ||
             radinterp__bad_param(d->refine_eps) ||
             radinterp__bad_param(d->refine_min_area) || radinterp__bad_param(d->weld_distance) ||
             radinterp__bad_param(d->min_leaf_area) || radinterp__bad_param(d->progress_interval))
        bad = "a parameter is negative, NaN or infinite";
    else if (d->max_leaf_dsets > 4096) bad = "max_leaf_dsets is above 4096";
    else if (d->refine_samples > 64) bad = "refine_samples is above 64";
    else if (d->refine_passes > 64) bad = "refine_passes is above 64";
    if (!bad) return RADINTERP_OK;
    if (d->log) {
        char msg[160];
        snprintf(msg, sizeof msg, "radinterp_build_mesh: %s", bad);
        d->log(d->log_user, msg);
    }
    return RADINTERP_ERROR_INVALID_ARGUMENT;
}

static void radinterp__builder_free(radinterp__builder *b)
{
    const radinterp_allocator *a = &b->a;
    radinterp__free(a, b->frames);
    radinterp__free(a, b->outline);
    radinterp__free(a, b->disc_first);
    radinterp__free(a, b->disc_count);
    radinterp__free(a, b->roots);
    radinterp__free(a, b->leaf_first);
    radinterp__free(a, b->leaf_count);
    radinterp__free(a, b->seg_first);
    radinterp__free(a, b->seg_count);
    radinterp__free(a, b->chain_first);
    radinterp__free(a, b->chain_len);
    radinterp__disc_list_free(a, &b->found);
    radinterp__buf_free(a, &b->discs);
    radinterp__buf_free(a, &b->dsets);
    radinterp__buf_free(a, &b->nodes);
    radinterp__buf_free(a, &b->node_discs);
    radinterp__buf_free(a, &b->leaves);
    radinterp__buf_free(a, &b->segs);
    radinterp__buf_free(a, &b->pool);
    radinterp__free(a, b->pool_first);
    radinterp__buf_free(a, &b->chains);
    radinterp__buf_free(a, &b->pos);
    radinterp__buf_free(a, &b->tris);
    radinterp__hmap_free(a, &b->corners);
    radinterp__hmap_free(a, &b->canon);
    radinterp__hmap_free(a, &b->vmap);
}

/* Parameters after defaults, per-patch arrays, frames and outlines. */
static radinterp_result radinterp__builder_init(radinterp__builder *b, const radinterp_solution *s,
                                                const radinterp_mesh_desc *d)
{
    uint32_t P = s->patch_count, i, k;
    float brightest = 0.0f;
    memset(b, 0, sizeof *b);
    b->s = s;
    b->desc = d;
    b->a = d->allocator;
    b->tol = s->epsilon * s->diag;
    b->weld = d->weld_distance > 0.0f ? d->weld_distance : 1e-6 * s->diag;
    if (b->weld < b->tol) b->weld = b->tol;
    for (i = 0; i < P; i++)
        if (s->patches[i].count && radinterp__brightness(s, i) > brightest) brightest = radinterp__brightness(s, i);
    b->min_weight = d->min_discont_weight > 0.0f ? d->min_discont_weight : 0.01f * brightest;
    b->min_contrast = d->min_discont_contrast > 0.0f ? d->min_discont_contrast : RADINTERP__MIN_CONTRAST;
    b->max_dsets = radinterp__def(d->max_leaf_dsets, 10u);
    b->refine_eps = d->refine_eps > 0.0f ? d->refine_eps : s->eps;
    b->refine_min_area = d->refine_min_area > 0.0f ? d->refine_min_area : s->min_area;
    b->min_leaf_area = d->min_leaf_area;
    b->refine_samples = radinterp__def(d->refine_samples, 3u);
    b->refine_passes = radinterp__def(d->refine_passes, 8u);
    radinterp__disc_list_init(&b->found);
    radinterp__buf_init(&b->discs, sizeof(radinterp__disc));
    radinterp__buf_init(&b->dsets, sizeof(radinterp__dset));
    radinterp__buf_init(&b->nodes, sizeof(radinterp__mnode));
    radinterp__buf_init(&b->node_discs, sizeof(uint32_t));
    radinterp__buf_init(&b->leaves, sizeof(uint32_t));
    radinterp__buf_init(&b->segs, sizeof(radinterp__seg));
    radinterp__buf_init(&b->pool, sizeof(radinterp__bvert));
    radinterp__buf_init(&b->chains, sizeof(uint32_t));
    radinterp__buf_init(&b->pos, sizeof(float));
    radinterp__buf_init(&b->tris, sizeof(radinterp__otri));
    b->frames = (radinterp__frame *)radinterp__alloc_array(&b->a, P, sizeof *b->frames);
    b->outline = (double *)radinterp__alloc_array(&b->a, P, 8 * sizeof(double));
    b->disc_first = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->disc_count = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->roots = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->leaf_first = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->leaf_count = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->seg_first = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->seg_count = (uint32_t *)radinterp__alloc_array(&b->a, P, sizeof(uint32_t));
    b->chain_first = (uint32_t *)radinterp__alloc_array(&b->a, P, 4 * sizeof(uint32_t));
    b->chain_len = (uint32_t *)radinterp__alloc_array(&b->a, P, 4 * sizeof(uint32_t));
    if (!b->frames || !b->outline || !b->disc_first || !b->disc_count || !b->roots || !b->leaf_first || !b->leaf_count ||
        !b->seg_first || !b->seg_count || !b->chain_first || !b->chain_len ||
        radinterp__hmap_init(&b->a, &b->corners, 4, 4 * s->node_count) != 0 ||
        radinterp__hmap_init(&b->a, &b->canon, 4, 1024) != 0 || radinterp__hmap_init(&b->a, &b->vmap, 4, 4 * s->leaf_count) != 0)
        return RADINTERP_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < P; i++) {
        const radinterp__patch *pt = &s->patches[i];
        b->roots[i] = RADINTERP__NONE;
        b->disc_first[i] = b->disc_count[i] = b->leaf_first[i] = b->leaf_count[i] = b->seg_first[i] = b->seg_count[i] = 0;
        for (k = 0; k < 4; k++) b->chain_first[4 * i + k] = b->chain_len[4 * i + k] = 0;
        memset(b->outline + 8 * (size_t)i, 0, 8 * sizeof(double));
        if (!pt->count) continue;
        radinterp__patch_frame(&b->frames[i], pt);
        for (k = 0; k < pt->count; k++) radinterp__frame_to2df(&b->frames[i], pt->v[k], b->outline + 8 * (size_t)i + 2 * k);
    }
    return RADINTERP_OK;
}

/* Quadtrees copied from the solution and restricted. */
static radinterp_result radinterp__build_trees(radinterp__builder *b)
{
    radinterp__buf queue;
    uint32_t R;
    int r = 0;
    radinterp__buf_init(&queue, sizeof(uint32_t));
    for (R = 0; R < b->s->patch_count && r == 0; R++)
        if (b->s->patches[R].count) r = radinterp__copy_tree(b, R, &queue);
    radinterp__buf_free(&b->a, &queue);
    if (r == 0) r = radinterp__balance(b);
    return radinterp__step_result(r);
}

RADINTERP_API radinterp_result radinterp_build_mesh(const radinterp_solution *s, const radinterp_mesh_desc *desc,
                                                    radinterp_mesh **out)
{
    radinterp__builder b;
    radinterp__interp ip;
    radinterp_result res;
    uint32_t pass = 0, refined = 0;
    float worst = 0.0f;
    if (!out) return RADINTERP_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!s || !desc) return RADINTERP_ERROR_INVALID_ARGUMENT;
    res = radinterp__check_mesh_desc(desc);
    if (res != RADINTERP_OK) return res;
    memset(&ip, 0, sizeof ip);
    res = radinterp__builder_init(&b, s, desc);
    if (res == RADINTERP_OK) res = radinterp__find_discontinuities(&b);
    if (res == RADINTERP_OK && b.hidden_events)
        radinterp__mesh_log(&b, "radinterp_build_mesh: %u discontinuity events hidden behind other surfaces left out",
                            b.hidden_events);
    if (res == RADINTERP_OK) res = radinterp__build_trees(&b);
    while (res == RADINTERP_OK) {
        int split;
        radinterp__note_bytes(&b, 0);
        res = radinterp__mesh_pass(&b);
        radinterp__note_bytes(&b, 0);
        if (res == RADINTERP_OK) res = radinterp__interpolants(&b, &ip);
        radinterp__note_bytes(&b, radinterp__interp_bytes(&ip, b.tris.count));
        if (res != RADINTERP_OK || !desc->refine || pass >= b.refine_passes) break;
        split = radinterp__refine_leaves(&b, ip.prev_error, &worst);
        if (split < 0) res = RADINTERP_ERROR_OUT_OF_MEMORY;
        if (split <= 0) break;
        refined += (uint32_t)split;
        pass++;
        res = radinterp__step_result(radinterp__balance(&b));
    }
    if (res == RADINTERP_OK) {
        res = radinterp__assemble(&b, desc->refine ? ip.prev_coeff : ip.coeff, desc->refine ? ip.prev_error : ip.error, out);
        if (res == RADINTERP_OK) {
            (*out)->info.refine_passes = desc->refine ? pass + 1 : 0;
            (*out)->info.refined_leaves = refined;
            (*out)->info.max_fit_error = worst;
            (*out)->info.bytes = radinterp__mesh_bytes(*out);
            radinterp__note_bytes(&b, (*out)->info.bytes + radinterp__interp_bytes(&ip, b.tris.count));
            (*out)->info.build_bytes = b.peak_bytes;
        }
    }
    if (res == RADINTERP_ERROR_OUT_OF_MEMORY) radinterp__mesh_log(&b, "radinterp_build_mesh: out of memory");
    radinterp__interp_free(&b.a, &ip);
    radinterp__builder_free(&b);
    return res;
}

RADINTERP_API void radinterp_mesh_get_info(const radinterp_mesh *m, radinterp_mesh_info *info)
{
    if (!info) return;
    memset(info, 0, sizeof *info);
    if (m) *info = m->info;
}

RADINTERP_API void radinterp_mesh_get_data(const radinterp_mesh *m, radinterp_mesh_data *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    if (!m) return;
    d->vertex_count = m->vertex_count;
    d->triangle_count = m->triangle_count;
    d->positions = m->positions;
    d->indices = m->indices;
    d->triangle_patch = m->tri_patch;
    d->triangle_leaf = m->tri_leaf;
    d->coefficients = m->rad;
    d->irradiance_coefficients = m->irr;
    d->reflectance = m->reflectance;
    d->emission = m->emission;
    d->corner_radiosity = m->corner;
    d->vertex_radiosity = m->vertex_rad;
    d->edge_flags = m->edge_flags;
}

RADINTERP_API uint32_t radinterp_mesh_discontinuity_count(const radinterp_mesh *m) { return m ? m->disc_count : 0; }

RADINTERP_API radinterp_result radinterp_mesh_get_discontinuity(const radinterp_mesh *m, uint32_t index,
                                                                radinterp_discontinuity *d)
{
    if (!d) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(d, 0, sizeof *d);
    if (!m || index >= m->disc_count) return RADINTERP_ERROR_INVALID_ARGUMENT;
    *d = *radinterp__disc_list_at(&m->discs, index);
    return RADINTERP_OK;
}

RADINTERP_API uint32_t radinterp_mesh_leaf_count(const radinterp_mesh *m) { return m ? m->leaf_count : 0; }

RADINTERP_API radinterp_result radinterp_mesh_get_leaf(const radinterp_mesh *m, uint32_t index, radinterp_mesh_leaf *leaf)
{
    if (!leaf) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(leaf, 0, sizeof *leaf);
    if (!m || index >= m->leaf_count) return RADINTERP_ERROR_INVALID_ARGUMENT;
    *leaf = m->leaves[index];
    return RADINTERP_OK;
}

RADINTERP_API void radinterp_mesh_set_parallel_for(radinterp_mesh *m,
                                                   void (*parallel_for)(void *user, radinterp_job_fn job, void *ctx,
                                                                        uint32_t count),
                                                   void *user)
{
    if (!m) return;
    m->parallel_for = parallel_for;
    m->parallel_user = user;
}

/* ======================================================================
   22. the online phase (Hardt 3.4): per-pixel interpolant evaluation
   ---------------------------------------------------------------------- */
static radinterp_result radinterp__eval_table(const radinterp_mesh *m, const float *table, uint32_t triangle, float s,
                                              float t, float rgb[3])
{
    int ch;
    if (!rgb) return RADINTERP_ERROR_INVALID_ARGUMENT;
    if (!m || triangle >= m->triangle_count || !isfinite(s) || !isfinite(t)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return RADINTERP_ERROR_INVALID_ARGUMENT;
    }
    for (ch = 0; ch < 3; ch++) rgb[ch] = radinterp__quad_eval(table + 18 * (size_t)triangle + ch, 3, s, t);
    return RADINTERP_OK;
}

RADINTERP_API radinterp_result radinterp_eval(const radinterp_mesh *m, uint32_t triangle, float s, float t, float rgb[3])
{
    return radinterp__eval_table(m, m ? m->rad : NULL, triangle, s, t, rgb);
}

RADINTERP_API radinterp_result radinterp_eval_irradiance(const radinterp_mesh *m, uint32_t triangle, float s, float t,
                                                         float rgb[3])
{
    return radinterp__eval_table(m, m ? m->irr : NULL, triangle, s, t, rgb);
}

#define RADINTERP__SHADE_CHUNK 16384   /* pixels per job */

/* A run of one triangle's pixels from its padded coefficients c (24 floats:
   (A, 2B, 2C, D, 2E, F) x 4 lanes): the interpolant's polynomial,
   channel by channel. Always compiled: the reference the SIMD kernel is
   tested against, and the kernel of builds without one. */
RADINTERP__MAYBE_UNUSED static void radinterp__shade_span_scalar(const float *c, const float *st, size_t count,
                                                                  float *rgb)
{
    size_t i;
    for (i = 0; i < count; i++) {
        float s = st[2 * i], t = st[2 * i + 1];
        int ch;
        for (ch = 0; ch < 3; ch++) {
            float v = s * (c[ch] * s + c[4 + ch] * t + c[8 + ch]) + t * (c[12 + ch] * t + c[16 + ch]) + c[20 + ch];
            rgb[3 * i + ch] = v > 0.0f ? v : 0.0f;
        }
    }
}

#if RADINTERP__SIMD
/* The same float operations with a pixel's three channels (and the zero
   pad) as the lanes of one vector: 5 multiplies, 5 adds and a max per
   pixel. Each pixel's 4-lane store spills into the next pixel's first
   channel, which that pixel then writes; the last pixel goes through a
   buffer, so nothing past rgb[3 count) is touched. */
static void radinterp__shade_span_simd(const float *c, const float *st, size_t count, float *rgb)
{
    const radinterp__f4 a = radinterp__f4_load(c), b2 = radinterp__f4_load(c + 4), c2 = radinterp__f4_load(c + 8);
    const radinterp__f4 d = radinterp__f4_load(c + 12), e2 = radinterp__f4_load(c + 16), f = radinterp__f4_load(c + 20);
    const radinterp__f4 zero = radinterp__f4_set(0.0f);
    float last[4];
    size_t i;
    for (i = 0; i < count; i++) {
        radinterp__f4 s = radinterp__f4_set(st[2 * i]), t = radinterp__f4_set(st[2 * i + 1]);
        radinterp__f4 u = radinterp__f4_add(radinterp__f4_add(radinterp__f4_mul(a, s), radinterp__f4_mul(b2, t)), c2);
        radinterp__f4 w = radinterp__f4_add(radinterp__f4_mul(d, t), e2);
        radinterp__f4 v = radinterp__f4_add(radinterp__f4_add(radinterp__f4_mul(s, u), radinterp__f4_mul(t, w)), f);
        v = radinterp__f4_max(v, zero);   /* v > 0 ? v : 0, NaN to 0, as the scalar kernel */
        if (i + 1 < count) {
            radinterp__f4_store(rgb + 3 * i, v);
        } else {
            radinterp__f4_store(last, v);
            memcpy(rgb + 3 * i, last, 3 * sizeof(float));
        }
    }
}
#endif

/* The kernel this build shades runs with (the same bits either way). */
static void radinterp__shade_span_kernel(const float *c, const float *st, size_t count, float *rgb)
{
#if RADINTERP__SIMD
    radinterp__shade_span_simd(c, st, count, rgb);
#else
    radinterp__shade_span_scalar(c, st, count, rgb);
#endif
}

typedef struct radinterp__shade_ctx {
    const radinterp_mesh *m;
    const uint32_t *ids;
    const float *st;
    float *rgb;
    size_t count;
} radinterp__shade_ctx;

/* One chunk of pixels: B(s, t) from the padded table (4 lanes per
   coefficient, so the channels evaluate as one short vector). */
static void radinterp__shade_job(void *ctx_, uint32_t index)
{
    const radinterp__shade_ctx *ctx = (const radinterp__shade_ctx *)ctx_;
    uint32_t n = ctx->m->triangle_count;
    size_t i = (size_t)index * RADINTERP__SHADE_CHUNK, end = i + RADINTERP__SHADE_CHUNK, run;
    if (end > ctx->count) end = ctx->count;
    for (; i < end; i += run) {   /* runs of one triangle: its coefficients loaded once */
        uint32_t id = ctx->ids[i];
        for (run = 1; i + run < end && ctx->ids[i + run] == id; run++) {}
        if (id >= n) continue;
        radinterp__shade_span_kernel(ctx->m->shade + 24 * (size_t)id, ctx->st + 2 * i, run, ctx->rgb + 3 * i);
    }
}

static void radinterp__gouraud_job(void *ctx_, uint32_t index)
{
    const radinterp__shade_ctx *ctx = (const radinterp__shade_ctx *)ctx_;
    const float *corner = ctx->m->corner;
    uint32_t n = ctx->m->triangle_count;
    size_t i = (size_t)index * RADINTERP__SHADE_CHUNK, end = i + RADINTERP__SHADE_CHUNK;
    if (end > ctx->count) end = ctx->count;
    for (; i < end; i++) {
        uint32_t id = ctx->ids[i];
        const float *c;
        float s, t, w;
        int ch;
        if (id >= n) continue;
        c = corner + 9 * (size_t)id;
        s = ctx->st[2 * i];
        t = ctx->st[2 * i + 1];
        w = 1.0f - s - t;
        for (ch = 0; ch < 3; ch++) {
            float v = w * c[ch] + s * c[3 + ch] + t * c[6 + ch];
            ctx->rgb[3 * i + ch] = v > 0.0f ? v : 0.0f;
        }
    }
}

static radinterp_result radinterp__shade_run(const radinterp_mesh *m, const uint32_t *ids, const float *st, size_t count,
                                             float *rgb, radinterp_job_fn job)
{
    radinterp__shade_ctx ctx;
    size_t jobs;
    if (!m || (count && (!ids || !st || !rgb))) return RADINTERP_ERROR_INVALID_ARGUMENT;
    jobs = (count + RADINTERP__SHADE_CHUNK - 1) / RADINTERP__SHADE_CHUNK;
    if (jobs > 0xFFFFFFFFu) return RADINTERP_ERROR_INVALID_ARGUMENT;
    ctx.m = m;
    ctx.ids = ids;
    ctx.st = st;
    ctx.rgb = rgb;
    ctx.count = count;
    radinterp__run_jobs(m->parallel_for, m->parallel_user, job, &ctx, (uint32_t)jobs);
    return RADINTERP_OK;
}

RADINTERP_API radinterp_result radinterp_shade(const radinterp_mesh *m, const uint32_t *triangle_ids, const float *st,
                                               size_t count, float *rgb_out)
{
    return radinterp__shade_run(m, triangle_ids, st, count, rgb_out, radinterp__shade_job);
}

RADINTERP_API radinterp_result radinterp_shade_gouraud(const radinterp_mesh *m, const uint32_t *triangle_ids,
                                                       const float *st, size_t count, float *rgb_out)
{
    return radinterp__shade_run(m, triangle_ids, st, count, rgb_out, radinterp__gouraud_job);
}


RADINTERP_API radinterp_result radinterp_shade_span(const radinterp_mesh *m, uint32_t triangle, const float *st,
                                                    size_t count, float *rgb_out)
{
    const float *c;
    if (!m || triangle >= m->triangle_count || (count && (!st || !rgb_out))) return RADINTERP_ERROR_INVALID_ARGUMENT;
    c = m->shade + 24 * (size_t)triangle;
    radinterp__shade_span_kernel(c, st, count, rgb_out);
    return RADINTERP_OK;
}

/* ======================================================================
   23. saving and loading a mesh (format of section 5)
   Payload: counts (vertices, triangles, patches, discontinuities, leaves),
   the build statistics, positions, indices, triangle patches, leaves and
   edge flags, the irradiance coefficients, each patch's reflectance and
   emission, the discontinuities and the leaves. Radiosity coefficients,
   corner and vertex radiosities are recomputed on load.
   ---------------------------------------------------------------------- */
static const unsigned char radinterp__mesh_magic[8] = {'R', 'A', 'D', 'I', 'M', 'E', 'S', 'H'};

#define RADINTERP__MESH_STATS 16   /* u32 statistics saved besides the counts */
#define RADINTERP__DISC_BYTES 52
#define RADINTERP__LEAF_BYTES 80

static void radinterp__mesh_stats(radinterp_mesh_info *info, uint32_t **f)
{
    f[0] = &info->ev; f[1] = &info->ve; f[2] = &info->horizon; f[3] = &info->contact; f[4] = &info->dsets;
    f[5] = &info->candidates; f[6] = &info->active_discontinuities; f[7] = &info->active_leaf_dsets;
    f[8] = &info->max_leaf_active_dsets; f[9] = &info->balance_splits; f[10] = &info->hanging_vertices;
    f[11] = &info->seam_vertices; f[12] = &info->fallback_patches; f[13] = &info->refine_passes;
    f[14] = &info->refined_leaves; f[15] = &info->skipped_patches;
}

static uint64_t radinterp__mesh_payload(const radinterp_mesh *m)
{
    return 5 * 4 + RADINTERP__MESH_STATS * 4 + 4 + 8 + 12 * (uint64_t)m->vertex_count +
           (12 + 4 + 4 + 1 + 72) * (uint64_t)m->triangle_count + 24 * (uint64_t)m->patch_count +
           RADINTERP__DISC_BYTES * (uint64_t)m->disc_count + RADINTERP__LEAF_BYTES * (uint64_t)m->leaf_count;
}

RADINTERP_API radinterp_result radinterp_mesh_save(const radinterp_mesh *m, radinterp_write_fn write, void *user)
{
    radinterp__writer w;
    radinterp_mesh_info info;
    uint32_t *stats[RADINTERP__MESH_STATS], i;
    int k;
    if (!m || !write) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(&w, 0, sizeof w);
    w.write = write;
    w.user = user;
    info = m->info;
    radinterp__mesh_stats(&info, stats);
    radinterp__crc_init(&w.crc);
    radinterp__put(&w, radinterp__mesh_magic, 8);
    radinterp__put_u32(&w, RADINTERP_FILE_FORMAT_VERSION);
    radinterp__put_u64(&w, radinterp__mesh_payload(m));
    radinterp__put_u32(&w, m->vertex_count);
    radinterp__put_u32(&w, m->triangle_count);
    radinterp__put_u32(&w, m->patch_count);
    radinterp__put_u32(&w, m->disc_count);
    radinterp__put_u32(&w, m->leaf_count);
    for (k = 0; k < RADINTERP__MESH_STATS; k++) radinterp__put_u32(&w, *stats[k]);
    radinterp__put_f32(&w, info.max_fit_error);
    radinterp__put_u64(&w, info.samples);
    radinterp__put_f32_array(&w, m->positions, 3 * (size_t)m->vertex_count);
    radinterp__put_u32_array(&w, m->indices, 3 * (size_t)m->triangle_count);
    radinterp__put_u32_array(&w, m->tri_patch, m->triangle_count);
    radinterp__put_u32_array(&w, m->tri_leaf, m->triangle_count);
    radinterp__put(&w, m->edge_flags, m->triangle_count);
    radinterp__put_f32_array(&w, m->irr, 18 * (size_t)m->triangle_count);
    radinterp__put_f32_array(&w, m->patch_rho, 3 * (size_t)m->patch_count);
    radinterp__put_f32_array(&w, m->patch_e, 3 * (size_t)m->patch_count);
    for (i = 0; i < m->disc_count; i++) {
        const radinterp_discontinuity *d = radinterp__disc_list_at(&m->discs, i);
        radinterp__put_f32_array(&w, d->a, 3);
        radinterp__put_f32_array(&w, d->b, 3);
        radinterp__put_u32(&w, d->type);
        radinterp__put_u32(&w, d->receiver);
        radinterp__put_u32(&w, d->source);
        radinterp__put_u32(&w, d->blocker);
        radinterp__put_u32(&w, d->dset);
        radinterp__put_f32(&w, d->weight);
        radinterp__put_u32(&w, d->active ? 1u : 0u);
    }
    for (i = 0; i < m->leaf_count; i++) {
        const radinterp_mesh_leaf *l = &m->leaves[i];
        radinterp__put_u32(&w, l->patch);
        radinterp__put_u32(&w, l->depth);
        radinterp__put_u32(&w, l->vertex_count);
        radinterp__put_f32_array(&w, &l->vertices[0][0], 12);
        radinterp__put_u32(&w, l->dsets);
        radinterp__put_u32(&w, l->active_dsets);
        radinterp__put_u32(&w, l->first_triangle);
        radinterp__put_u32(&w, l->triangle_count);
        radinterp__put_f32(&w, l->error);
    }
    radinterp__put_u32(&w, radinterp__crc_final(&w.crc));
    return w.failed ? RADINTERP_ERROR_IO : RADINTERP_OK;
}

/* n little-endian floats, each finite. */
static int radinterp__get_finite(radinterp__reader *r, float *f, size_t n)
{
    unsigned char buf[4096];
    size_t i = 0;
    while (i < n && !r->failed) {
        size_t m = n - i < sizeof buf / 4 ? n - i : sizeof buf / 4, j;
        radinterp__get(r, buf, 4 * m);
        for (j = 0; j < m; j++, i++) {
            const unsigned char *b = buf + 4 * j;
            uint32_t u = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
            memcpy(&f[i], &u, 4);
            if (!isfinite(f[i])) { r->failed = 1; return 0; }
        }
    }
    return !r->failed;
}

/* n u32 values, each below limit. */
static int radinterp__get_indices(radinterp__reader *r, uint32_t *v, size_t n, uint32_t limit)
{
    size_t i;
    for (i = 0; i < n && !r->failed; i++) {
        v[i] = radinterp__get_u32(r);
        if (v[i] >= limit) r->failed = 1;
    }
    return !r->failed;
}

static int radinterp__read_discs(radinterp__reader *r, radinterp_mesh *m)
{
    uint32_t i;
    for (i = 0; i < m->disc_count && !r->failed; i++) {
        radinterp_discontinuity *d = radinterp__disc_list_at(&m->discs, i);
        uint32_t active;
        radinterp__get_finite(r, d->a, 3);
        radinterp__get_finite(r, d->b, 3);
        d->type = radinterp__get_u32(r);
        d->receiver = radinterp__get_u32(r);
        d->source = radinterp__get_u32(r);
        d->blocker = radinterp__get_u32(r);
        d->dset = radinterp__get_u32(r);
        d->weight = radinterp__get_f32(r);
        active = radinterp__get_u32(r);
        if (d->type < RADINTERP_DISCONTINUITY_EV || d->type > RADINTERP_DISCONTINUITY_CONTACT ||
            d->receiver >= m->patch_count || (d->source >= m->patch_count && d->source != RADINTERP_NO_PATCH) ||
            (d->blocker >= m->patch_count && d->blocker != RADINTERP_NO_PATCH) || !(d->weight >= 0.0f) ||
            !isfinite(d->weight) || active > 1)
            r->failed = 1;
        d->active = (int)active;
    }
    return !r->failed;
}

static int radinterp__read_leaves(radinterp__reader *r, radinterp_mesh *m)
{
    uint32_t i;
    for (i = 0; i < m->leaf_count && !r->failed; i++) {
        radinterp_mesh_leaf *l = &m->leaves[i];
        l->patch = radinterp__get_u32(r);
        l->depth = radinterp__get_u32(r);
        l->vertex_count = radinterp__get_u32(r);
        radinterp__get_finite(r, &l->vertices[0][0], 12);
        l->dsets = radinterp__get_u32(r);
        l->active_dsets = radinterp__get_u32(r);
        l->first_triangle = radinterp__get_u32(r);
        l->triangle_count = radinterp__get_u32(r);
        l->error = radinterp__get_f32(r);
        if (l->patch >= m->patch_count || (l->vertex_count != 3 && l->vertex_count != 4) || l->depth > 64 ||
            l->active_dsets > l->dsets || l->first_triangle > m->triangle_count ||
            l->triangle_count > m->triangle_count - l->first_triangle || !isfinite(l->error))
            r->failed = 1;
    }
    return !r->failed;
}

static radinterp_result radinterp__mesh_read(radinterp_mesh *m, radinterp__reader *r)
{
    unsigned char magic[8];
    uint32_t version, *stats[RADINTERP__MESH_STATS], expected_crc, i;
    int k;
    radinterp__crc_init(&r->crc);
    r->remaining = 20;
    radinterp__get(r, magic, 8);
    version = radinterp__get_u32(r);
    r->remaining = radinterp__get_u64(r);
    if (r->failed || memcmp(magic, radinterp__mesh_magic, 8) != 0) return RADINTERP_ERROR_CORRUPT_DATA;
    if (version != RADINTERP_FILE_FORMAT_VERSION) return RADINTERP_ERROR_VERSION;
    m->vertex_count = radinterp__get_u32(r);
    m->triangle_count = radinterp__get_u32(r);
    m->patch_count = radinterp__get_u32(r);
    m->disc_count = radinterp__get_u32(r);
    m->leaf_count = radinterp__get_u32(r);
    radinterp__mesh_stats(&m->info, stats);
    for (k = 0; k < RADINTERP__MESH_STATS; k++) *stats[k] = radinterp__get_u32(r);
    m->info.max_fit_error = radinterp__get_f32(r);
    m->info.samples = radinterp__get_u64(r);
    /* every size is checked against the payload before anything is allocated */
    if (r->failed || !radinterp__can_hold(r, m->vertex_count, 12) || !radinterp__can_hold(r, m->triangle_count, 93) ||
        !radinterp__can_hold(r, m->patch_count, 24) || !radinterp__can_hold(r, m->disc_count, RADINTERP__DISC_BYTES) ||
        !radinterp__can_hold(r, m->leaf_count, RADINTERP__LEAF_BYTES) || r->remaining != radinterp__mesh_payload(m) - (5 * 4 + RADINTERP__MESH_STATS * 4 + 12))
        return RADINTERP_ERROR_CORRUPT_DATA;
    if (radinterp__mesh_alloc(m) != 0) return RADINTERP_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < m->disc_count; i++)
        if (!radinterp__disc_list_push(&m->allocator, &m->discs)) return RADINTERP_ERROR_OUT_OF_MEMORY;
    if (radinterp__disc_list_trim(&m->allocator, &m->discs) != 0) return RADINTERP_ERROR_OUT_OF_MEMORY;
    radinterp__get_finite(r, m->positions, 3 * (size_t)m->vertex_count);
    radinterp__get_indices(r, m->indices, 3 * (size_t)m->triangle_count, m->vertex_count);
    radinterp__get_indices(r, m->tri_patch, m->triangle_count, m->patch_count);
    radinterp__get_indices(r, m->tri_leaf, m->triangle_count, m->leaf_count);
    radinterp__get(r, m->edge_flags, m->triangle_count);
    for (i = 0; i < m->triangle_count && !r->failed; i++)
        if (m->edge_flags[i] > 63) r->failed = 1;
    radinterp__get_finite(r, m->irr, 18 * (size_t)m->triangle_count);
    radinterp__get_finite(r, m->patch_rho, 3 * (size_t)m->patch_count);
    radinterp__get_finite(r, m->patch_e, 3 * (size_t)m->patch_count);
    for (i = 0; i < 3 * m->patch_count && !r->failed; i++)
        if (m->patch_rho[i] < 0.0f || m->patch_rho[i] > 1.0f || m->patch_e[i] < 0.0f) r->failed = 1;
    radinterp__read_discs(r, m);
    radinterp__read_leaves(r, m);
    if (r->failed || r->remaining != 0) return RADINTERP_ERROR_CORRUPT_DATA;
    expected_crc = radinterp__crc_final(&r->crc);
    r->remaining = 4;
    if (radinterp__get_u32(r) != expected_crc || r->failed) return RADINTERP_ERROR_CORRUPT_DATA;
    m->info.triangle_count = m->triangle_count;
    m->info.vertex_count = m->vertex_count;
    m->info.leaf_count = m->leaf_count;
    m->info.patch_count = m->patch_count;
    m->info.discontinuities = radinterp__kinds_total(&m->info);
    m->info.kept_discontinuities = m->disc_count;
    if (m->info.discontinuities < m->disc_count) return RADINTERP_ERROR_CORRUPT_DATA;   /* it keeps no more than it found */
    if (radinterp__mesh_derive(m) != 0) return RADINTERP_ERROR_OUT_OF_MEMORY;
    m->info.bytes = radinterp__mesh_bytes(m);
    return RADINTERP_OK;
}

RADINTERP_API radinterp_result radinterp_mesh_load(const radinterp_allocator *allocator, radinterp_read_fn read, void *user,
                                                   radinterp_mesh **out)
{
    radinterp_allocator a;
    radinterp__reader r;
    radinterp_mesh *m;
    radinterp_result res;
    if (out) *out = NULL;
    if (!read || !out) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(&a, 0, sizeof a);
    if (allocator) a = *allocator;
    if (!radinterp__allocator_valid(&a)) return RADINTERP_ERROR_INVALID_ARGUMENT;
    m = (radinterp_mesh *)radinterp__alloc(&a, sizeof *m);
    if (!m) return RADINTERP_ERROR_OUT_OF_MEMORY;
    memset(m, 0, sizeof *m);
    m->allocator = a;
    radinterp__disc_list_init(&m->discs);
    memset(&r, 0, sizeof r);
    r.read = read;
    r.user = user;
    res = radinterp__mesh_read(m, &r);
    if (res != RADINTERP_OK) { radinterp_mesh_destroy(m); return res; }
    *out = m;
    return RADINTERP_OK;
}

RADINTERP_API radinterp_result radinterp_mesh_save_to_memory(const radinterp_mesh *m, const radinterp_allocator *allocator,
                                                             void **data, size_t *size)
{
    radinterp_allocator a;
    radinterp__membuf mb;
    radinterp_result r;
    if (data) *data = NULL;
    if (size) *size = 0;
    if (!m || !data || !size) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(&a, 0, sizeof a);
    if (allocator) a = *allocator;
    if (!radinterp__allocator_valid(&a)) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(&mb, 0, sizeof mb);
    mb.a = &a;
    r = radinterp_mesh_save(m, radinterp__membuf_write, &mb);
    if (r != RADINTERP_OK) {
        radinterp__free(&a, mb.data);
        return r == RADINTERP_ERROR_IO ? RADINTERP_ERROR_OUT_OF_MEMORY : r;
    }
    *data = mb.data;
    *size = mb.size;
    return RADINTERP_OK;
}

RADINTERP_API radinterp_result radinterp_mesh_load_from_memory(const void *data, size_t size,
                                                               const radinterp_allocator *allocator, radinterp_mesh **out)
{
    radinterp__membuf mb;
    if (out) *out = NULL;
    if (!data || !out) return RADINTERP_ERROR_INVALID_ARGUMENT;
    memset(&mb, 0, sizeof mb);
    mb.data = (unsigned char *)(uintptr_t)data;
    mb.size = size;
    return radinterp_mesh_load(allocator, radinterp__membuf_read, &mb, out);
}

RADINTERP_API void radinterp_free_memory(const radinterp_allocator *allocator, void *data)
{
    radinterp_allocator a;
    memset(&a, 0, sizeof a);
    if (allocator) a = *allocator;
    if (!radinterp__allocator_valid(&a)) return;
    radinterp__free(&a, data);
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
