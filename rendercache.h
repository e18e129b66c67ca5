/* rendercache.h - v0.11.1 - render cache and range-image walkthroughs - public domain or MIT, see end of file

   RENDERCACHE.H: an image-space point cache that reprojects and resamples, and range-image walkthroughs of animated scenes.

   The render cache (Walter, Drettakis and Parker 1999; Walter, Drettakis and
   Greenberg 2002) keeps the shaded points of earlier frames. Every frame it
   reprojects them into the new camera, keeps the nearest one per pixel,
   drops points that show through nearer surfaces (depth cull), fills small
   holes from neighbouring points without blending across depth edges, and
   builds a priority image (old points, sparse and empty regions). Error
   diffusion of the thresholded priority image picks the pixels that deserve
   a new ray within the caller's budget; the caller shades them with any
   renderer and inserts the results, in the same frame or frames later (an
   asynchronous renderer): a late sample is stored at its own point. A
   sample whose colour differs from the point it replaces ages the points
   around it, so that changed lighting is found and resampled first (or the
   engine says so: rendercache_invalidate for an object's points, or
   rendercache_invalidate_where for the points where it knows the light
   changed, e.g. on the segments from the lights through a moved object's
   old and new bounds: its old and new shadows). A view-dependent sample (a
   glossy highlight) carries its view lobe, and its point ages by the
   angle the view has turned since it was shaded, over that lobe, as well
   as by its age. Objects may move: each point
   belongs to an object whose transform the caller updates, and the point
   moves with it. Range images can seed the cache (rendercache_seed), so
   that precomputed views warm-start an interactive session.

   Range-image walkthroughs (Nimeroff, Dorsey and Rushmeier 1996) precompute
   instead: a range image is what a camera sees (radiance, distance along
   the ray, object id per pixel), and a walkthrough of an animated scene is
   rebuilt from base images, fish-eye or full-sphere views taken at base
   view positions and key times. Coherence tests on id images choose them:
   a view space (a box of eye positions) and a time interval are subdivided
   until the id images at the ends of every cell agree on a fraction q of
   their pixels. A frame is then the base views around its eye, blended to
   its time (pixelwise, or with moving objects moved by their transforms so
   that they do not ghost) and warped into its camera as Radiance's pinterp
   does, with foreground and background fill. Object-space solutions (e.g.
   indirect irradiance per vertex) get key times of their own, and the
   relative luminance RMS error measures the result. Warps share the render
   cache's cameras and its z-buffered reprojection.

   DO THIS

       #define RENDERCACHE_IMPLEMENTATION
       #include "rendercache.h"

   in exactly one C or C++ file; include "rendercache.h" without the define
   everywhere else.

   EXAMPLE: THE RENDER CACHE

       rendercache_desc d;
       rendercache *rc;
       memset(&d, 0, sizeof d);
       d.width = 512; d.height = 512;                 // everything else: defaults
       if (rendercache_create(&d, &rc) != RENDERCACHE_OK) return 1;
       while (running) {
           uint32_t i, n;
           rendercache_begin_frame(rc, &camera);      // reproject, cull, fill, prioritise
           rendercache_predict(rc, &next_camera);     // optional: seed what the motion will uncover
           // (or both at once, reading the points once: rendercache_begin_frame_predicted(rc, &camera, &next_camera))
           rendercache_request(rc, req, budget, &n);  // the pixels that deserve a ray
           for (i = 0; i < n; i++) {
               memset(&s[i], 0, sizeof s[i]);         // priority_scale 0: 1; view_lobe 0: matte
               s[i].frame = req[i].frame;             // the request's frame, x, y and flags
               s[i].x = req[i].x; s[i].y = req[i].y; s[i].flags = req[i].flags;
               shade(req[i].org, req[i].dir, s[i].position, s[i].rgb, &s[i].object);
           }
           rendercache_insert(rc, s, n, NULL);        // now, or frames later from a render thread
           show(rendercache_image(rc));               // width * height RGB floats, top row first
       }
       rendercache_destroy(rc);

   A caller with a cheap estimate of the frame (a coarse trace, a raster
   of albedo x stored irradiance) shows it in the wide holes instead:
       rendercache_fallback fb = { est_rgb, est_conf, width / 4, height / 4, 0, 0 };
       rendercache_compose_fallback(rc, &fb, out);   // out: width * height RGB floats
   Each hole is blended towards the estimate by its distance to the
   nearest point (not at all within near_pixels, fully from far_pixels
   on); pixels showing points are copied. Not calling it leaves every
   frame as it was.

   An asynchronous renderer returns the samples of frame f's requests after
   begin_frame(f + 1) or later: insert them then, with the frame field
   copied (desc.max_latency frames at most). Each is stored where its own
   ray hit, seen with its objects' transforms of frame f.

   EXAMPLE: A WALKTHROUGH FROM BASE VIEWS

       rendercache_view_space_desc vd = {0};          // base views: fish-eyes in a box of eyes
       vd.camera = fisheye;                           // kind, look direction, id image size
       vd.lo = ..., vd.hi = ...; vd.quality = 0.9f;
       vd.render_ids = my_id_renderer; vd.user = scene;
       rendercache_view_space_create(&vd, &vs);
       // base images: for each view i (rendercache_view_space_camera) and key
       // time (rendercache_subdivide_time), fill a range image's rgb, depth, object
       // (an image warped into many frames as it is: rendercache_range_image_prepare(img))
       rendercache_warper_create(&warp_desc, &warper);
       for (each frame) {
           rendercache_view_space_locate(vs, camera.eye, corners, &n);
           for (i = 0; i < n; i++)                    // each corner view at the frame's time
               rendercache_blend_motion(blender, base[corners[i]][k], base[corners[i]][k + 1], s,
                                        &motion, RENDERCACHE_FILL_FOREGROUND, blended[i]);
           rendercache_warp(warper, blended, n, &camera, RENDERCACHE_FILL_BOTH, frame);
           show(frame->rgb);
       }

   CONFIGURATION MACROS

       RENDERCACHE_STATIC          make every function static (private to one file)
       RENDERCACHE_API             linkage of public functions (default: extern)
       RENDERCACHE_MALLOC, RENDERCACHE_FREE  replace malloc/free (define both or neither)

   FUNCTION REFERENCE

       const char *rendercache_result_string(rendercache_result r);   name of an error code
     the render cache
       rendercache_create(desc, &rc) / rendercache_destroy(rc)        the cache, sized from the image
       rendercache_set_object_transform(rc, object, m)                object-to-world 3x4 matrix
       rendercache_begin_frame(rc, camera)                            reproject into a new camera
       rendercache_predict(rc, next_camera)                           optional: sample what it will uncover
       rendercache_begin_frame_predicted(rc, camera, next_camera)     both in one pass over the points
       rendercache_request(rc, out, max, &count)                      pixels to shade this frame
       rendercache_insert(rc, samples, n, &taken)                     shaded samples become points (late too)
       rendercache_invalidate(rc, object)                             an object's (or all) lighting changed
       rendercache_invalidate_where(rc, changed, user, &aged)         the points where the engine says it changed
       rendercache_invalidate_where_next_frame(rc, changed, user, &aged)  the same, between frames: no pixel pass
       rendercache_seed(rc, images, n, &taken)                        range images become points
       rendercache_image(rc)                                          the current RGB float image
       rendercache_compose_fallback(rc, &fallback, out)               the image, a cheap estimate in its wide holes
       rendercache_priority_image(rc), rendercache_pixel_kinds(rc),
       rendercache_depth_image(rc)                                    per-pixel internals (inspection)
       rendercache_get_stats(rc, &stats)                              counts and phase times of the frame
       rendercache_clear(rc)                                          forget every point
     cameras (perspective, hemispherical fish-eye, full sphere)
       rendercache_camera_ray(camera, px, py, org, dir)               primary ray through an image point
       rendercache_camera_project(camera, p, &px, &py, &depth)        world point to image point
     range images
       rendercache_range_image_create(camera, a, &img) / _destroy     rgb, depth and object arrays
       rendercache_range_image_save(img, write, user) / _load(a, read, user, &img)
       rendercache_range_image_save_to_memory(img, a, &data, &size) / _load_from_memory(data, size, a, &img)
       rendercache_free_memory(a, data)                               what save_to_memory returned
       rendercache_range_image_prepare(img) / _unprepare(img)         keep what warps read of a base view
     view and time interpolation
       rendercache_warper_create(desc, &w) / rendercache_warper_destroy(w)
       rendercache_warp(w, images, n, camera, fill, out)              reproject range images into a view
       rendercache_blend(a, b, t, out)                                pixelwise time blend (pcomb)
       rendercache_blend_motion(w, a, b, t, motion, fill, out)        blend with moving objects moved
       rendercache_warp_get_stats(w, &stats)                          counts and times of the last call
     coherence (base views and key times)
       rendercache_fitness(id_images, count, w, h, &f)                f = N / PQ
       rendercache_view_space_create(desc, &vs) / _destroy(vs)        subdivided view space
       rendercache_view_space_count(vs), _eyes(vs), _camera(vs, i, &c) the base views
       rendercache_view_space_locate(vs, eye, views, &n)              corner views of the cell around an eye
       rendercache_view_space_cell_count(vs), _cell(vs, i, lo, hi, &f) the leaf cells
       rendercache_subdivide_time(desc, &times, &count)               key times of id images
       rendercache_keytimes_create(desc, &kt) / _destroy(kt)          key times of an object-space solution
       rendercache_keytimes_count(kt), _times(kt), _values(kt, k)     the keys
       rendercache_keytimes_eval(kt, time, values, count)             linear interpolation in time
     error
       rendercache_lrms(reference, image, w, h, &lrms)                relative luminance RMS

   CONVENTIONS

       Pixel (x, y) covers [x, x+1) x [y, y+1) of the image plane, y = 0 is the
       top row; its primary ray passes through (x + 0.5, y + 0.5). Images are
       row-major, top row first, linear RGB floats. Depth is the distance from
       the eye along the ray. A fish-eye is equidistant: the inscribed circle
       spans 180 degrees and pixels outside it have no ray (object
       RENDERCACHE_NO_SAMPLE in range images). A sphere camera puts the
       forward hemisphere in the left half of the image and the backward one
       in the right half, each by the equal-area concentric map of Shirley
       and Chiu. Range-image pixels whose ray left the scene have object
       RENDERCACHE_MISS and are warped as directions (background at
       infinity). One rendercache, warper, view space or keytimes object is
       used by one thread at a time (an asynchronous renderer hands its
       samples to the thread that calls insert); per-frame work runs in
       parallel through desc.parallel_for and gives bit-identical results
       for any thread count. Frames are numbered from 1 by begin_frame;
       requests carry their frame's number, and a sample whose frame field
       is 0 belongs to the current frame.

   HOW A FRAME WORKS (and which published step each part is)

       begin_frame: first an eighth of the cache is re-sorted into the
       camera's image order (slot ranges of 16384 points grouped by the run
       of pixels each point projects to; 2 jobs with parallel_for), so that
       the cache stays nearly in image order and the passes below read and
       write memory in runs rather than at random (after WDG02's memory
       coherence); then every
       point is projected into the camera (positions and objects kept as
       four arrays, so that the projection's loop loads whole vectors of
       each and vectorises without shuffles) and z-buffered,
       one point per pixel (WDP99 reprojection), band of 1/64 of the image by
       band: each range's points of a band (where the re-sort put them) are
       z-tested together, so that the band's part of the z-buffer stays in
       cache (after WDG02's tiles; with parallel_for, 8 jobs of bands share
       the z-buffer, each owning the pixels of its bands and handing the
       points that land elsewhere to their owner after a barrier, so no
       test needs a lock; the minimum of a key that orders by depth, then
       slot, keeps the same point for any schedule and any order; the
       depth cull reads these keys and clears them for the next frame); a
       point much farther than the average depth of its 3x3 neighbourhood, with nearer points on
       opposite sides, is dropped (WDP99 depth cull); holes are filled by a
       3x3 tent filter, or a 7x7 one where points are sparse (WDG02), from
       one depth layer only, never a blend: the first points along 8 rays
       of up to 8 pixels tell the layers around a hole; one enclosing it
       (on opposite sides, as in the cull) fills it; beside an object that
       moved in the frame the farther one does (a disocclusion: the
       background the object uncovered, from the rays' points where it
       lies beyond the 7x7 window); elsewhere the layer of more weight in
       the window (the farther on a tie); the
       priority image ranks young points (age, faster for moving objects,
       plus for a sample with a view_lobe age_ramp frames per lobe of the
       turn of the view, seen from the point, since the frame whose eye
       shaded it, times the sample's priority_scale) below holes (the fewer points
       around, the higher), points whose age times scale passes the
       holes' top above them in that order (however old: every point is
       refreshed in turn), and pixels with nothing near at 1 (WDP99). The
       cull and the filling run interleaved, tile of 8 rows by tile, so
       that a hole's neighbourhood is still in cache when it is filled (with
       parallel_for, 8 ranges of tiles each so, and the tiles at the ranges'
       ends filled after).
       request: the levels of the priority image above a threshold are all
       requested, the level at the threshold gets the rest of the budget,
       spread by Floyd-Steinberg error diffusion (WDP99) in bands of 128 rows
       diffused in parallel; with desc.edge_fraction, up to that share of
       the requests for the current camera goes first to the pixels at the
       image's steps (luminance against a 3x3 neighbour's, desc.edge_step
       times the mean: a point of an earlier frame shows the other side of
       an edge as often as not), spread evenly over them when they are
       more, and the priority image gets the rest; with predict, up to
       desc.predict_fraction of the budget goes to the regions the next
       camera uncovers: the points are counted in an occupancy image of 1/16
       the resolution (cells of 4x4 pixels) of that camera, and a cell with
       fewer than 4 is seeded with one request (WDG02 predictive sampling);
       begin_frame_predicted counts them in the same pass as the projection
       into the current camera, each batch of points while it is in cache.
       insert: a sample of the current frame replaces the point its pixel
       showed, or takes the slot of the oldest point not visible (clock;
       with parallel_for, chunks of such samples are placed in 8 jobs once
       the clock has given their slots in sample order; a chunk with a
       colour change goes one sample at a time, as its ageing depends on the
       order); a
       late or predicted sample is stored at its own point, replaces the
       point of the same surface where that lands now, and is shown there
       (the holes around it filled again) when nothing nearer is. A sample
       whose colour differs from the point it replaces by more than
       desc.change_threshold (and by more than three standard deviations of
       the last frame's resample differences: a noisy renderer does not
       trigger it) ages the points shown within RENDERCACHE_CHANGE_RADIUS
       pixels to the top of the age ramp (WDG02; a point of priority scale
       s > 1 to age_ramp / s, where it ranks with the least urgent holes
       rather than above them all), but for the points shaded in the same
       frame, which show the change already: a new shadow is found by the
       samples that land in it and filled in by the next requests.
       invalidate_where: with parallel_for, 16 jobs over ranges of slots ask
       changed and age, noting the answers a bit per slot, then 16 jobs over
       ranges of pixels set the priorities of those showing an aged point
       (invalidate_where_next_frame leaves that pass to the next
       begin_frame, which ranks every pixel anyway).

   HOW A WARP WORKS (NDR96 section 4.4, after Radiance's pinterp)

       Every pixel of every input is a point (eye + ray * depth) reprojected
       into the target camera through the render cache's z-buffer, inputs in
       order of their eye's distance to the target's. An input of rank k
       competes with its squared distances multiplied by (1 + tolerance)^2k,
       so a surface replaces the same surface seen by a nearer input only
       when it is nearer by more than the tolerance per rank between them
       (for two inputs exactly pinterp's rule). Fill NONE: one target pixel
       per source pixel. FOREGROUND: each source pixel also spans the two
       triangles of the quad to its right and lower neighbours when their
       depths agree within twice the tolerance, colour and depth interpolated
       (watertight edges); a source pixel is splatted as a point only where
       its triangles do not surround it (depth edges, borders). BACKGROUND:
       an empty pixel takes the farther of the nearest filled pixels left and
       right of its run, and of those above and below, preferring one right
       next to it. Then desc.fill_pixel computes what is still empty. Tiles of
       16x16 source pixels of a fish-eye or perspective input whose points
       all lie outside the target's frustum (by a cone bound of their rays
       and their depth range, the ring of pixels around them included, so
       that no quad reaching the image loses a corner) are skipped; for
       sphere inputs, chunks of rays that point outside it from the input's
       eye. With foreground fill, runs of 8 pixels of a later input whose
       quads and points would all fail their z-tests (against a coarse
       z-buffer of what the nearer inputs drew) are skipped too, with the
       same result, and the quad flags of a row are computed only around
       the runs that are drawn. A prepared input (range_image_prepare: the
       depth bounds of its tiles, rings included, computed once) saves each
       warp reading the depths and objects of its tiles for the culling;
       the warp is bit for bit the same. With desc.average (pinterp's -a),
       each input is warped alone and every pixel averages the inputs that see
       the surface the ranked z-buffer keeps (squared distances within the
       tolerance), weighted by 1 / sin of the angle between each input's ray
       and the target's (at most 1000): views from nearly the target's
       direction count most, and the inputs' noise and staircases average out.
       desc.max_fill_distance bounds the background fill (pinterp's -fs):
       farther gaps stay for fill_pixel. Positions more than 2^24 pixels
       from the image have no projection, squared distances are capped at
       the background's and distances below 1e-18 written as 1e-18, so any
       valid inputs give a valid image. blend_motion warps both
       images into the output's camera with each object's motion (pixels of
       static objects in their own camera stay in place, exactly), blends
       where both show the same object at the same depth, and keeps the
       nearer surface elsewhere.

   VALIDATION AND CONTRACTS

       What each call checks (a failed check returns
       RENDERCACHE_ERROR_INVALID_ARGUMENT, or CORRUPT_DATA/VERSION for data
       read, and changes nothing) and what the caller must guarantee (the
       library cannot check it: breaking it is undefined behaviour).
       Callbacks (alloc, free, parallel_for, clock, log, render_ids, solve,
       fill_pixel, write, read) must do what their comments say; parallel_for
       must run every index once and return when all are done.

       create(desc, &out): checks desc and out non-NULL; width, height > 0 and
         at most 2^28 pixels; alloc and free both or neither;
         points_per_pixel > 0 and finite, at most 2^31 points; depth_tolerance
         >= 0 and finite; predict_fraction in [0, 1]; edge_fraction in [0, 1];
         edge_step >= 0; change_threshold >= 0;
         max_latency <= 64; object_count <= 2^24; sparse_neighbours <= 8;
         wide_radius <= 7; background finite. *out is NULL on failure.
       destroy(rc), clear(rc): rc NULL does nothing. Contract: rc came from
         create and is not used after destroy.
       set_object_transform(rc, object, m): checks rc and m non-NULL, object
         < object_count, m finite and invertible. Contract: m holds 12 floats.
       begin_frame(rc, camera), predict(rc, next): check a perspective camera
         of the cache's size with finite eye, look_at and up, up not
         parallel to the view, vfov in (0, 180); predict needs a frame.
       request(rc, out, max, &count): checks rc and count non-NULL, out
         non-NULL when max > 0, a frame begun. Contract: out holds max
         requests.
       insert(rc, samples, n, &taken): checks rc, and samples non-NULL when n
         > 0; each sample: frame begun and not in the future, pixel inside
         the image, only known flags (a predicted one from a frame with a
         prediction), object < object_count or RENDERCACHE_MISS, finite
         position (hits), finite colour, priority_scale and view_lobe >= 0
         and finite;
         the others are stored and the call reports INVALID_ARGUMENT.
         Contract: samples holds n samples.
       invalidate(rc, object): checks rc, and object < object_count,
         RENDERCACHE_MISS or RENDERCACHE_ALL_OBJECTS.
       invalidate_where(rc, changed, user, &aged), and
       invalidate_where_next_frame: checks rc and changed
         non-NULL; aged may be NULL. Contract: with parallel_for, changed
         may be called from several threads at once.
       seed(rc, images, count, &taken): checks rc, a frame begun, images
         non-NULL when count > 0, each image's arrays non-NULL and camera
         valid; pixels of unknown objects, without a positive finite depth or
         with a non-finite colour are skipped. Contract: images holds count
         pointers, each image's rgb 3 w h floats, depth and object w h.
       image, priority_image, pixel_kinds, depth_image(rc): NULL for rc NULL.
         Contract: the pointer is read before the next call that changes the
         cache (begin_frame, request, insert, seed, invalidate, clear,
         destroy).
       get_stats(rc, &out): out NULL does nothing, rc NULL gives zeros.
       camera_ray(camera, px, py, org, dir): checks the camera (any kind; a
         sphere at least 2 pixels wide), px and py finite, org and dir
         non-NULL; a point outside a fish-eye's circle has no ray.
         camera_project(camera, p, ...) returns 0 for a bad camera or p NULL
         or not finite; its outputs may be NULL.
       range_image_create(camera, allocator, &out): checks out, the camera
         and the allocator (NULL: default). range_image_destroy(img): NULL
         does nothing; frees the prepared data too. Contract: img came from
         create or load (an image the caller assembled is the caller's to
         free, after unprepare); an image the caller assembled has prepared
         NULL until it is prepared.
       range_image_prepare(img): checks img, its arrays, camera and
         allocator (INVALID_ARGUMENT), OUT_OF_MEMORY when the allocator
         fails; on failure img is left unprepared. unprepare(img): NULL or
         unprepared does nothing. Contract: until unprepare, img's depth and
         object arrays keep their contents (changed in place, warps show
         what the stale bounds let through: a wrong image, never a read
         outside the arrays); a change of size or of array pointers is
         checked (below). A struct copy shares the prepared data: unprepare
         or destroy one copy only.
       range_image_save(img, write, user): checks img's arrays and camera,
         write non-NULL, time finite, every colour finite and every surface
         depth positive and finite (what a loader accepts). Contract: the
         arrays hold w h pixels (rgb 3 w h floats).
       range_image_load(allocator, read, user, &out), load_from_memory(data,
         size, ...): the input is hostile: every size is checked against the
         payload, the CRC, the camera, every colour and depth; truncated or
         altered data gives CORRUPT_DATA, another format VERSION, never a
         crash; the image is read from the start of the buffer (bytes after
         its CRC are left alone). Contract: data holds size bytes.
       save_to_memory(img, allocator, &data, &size) as save; free_memory(a,
         data): contract: data came from save_to_memory or subdivide_time
         with the same allocator.
       warper_create(desc, &out): checks desc and out, the allocator,
         depth_tolerance in [0, 1e6), background finite.
       warp(w, images, n, camera, fill, out): checks w, images non-NULL and n
         > 0, each input's arrays and camera, out's arrays and camera (camera
         NULL: out's), the sizes of camera and out, no input being out, the
         fill mode, at most 2^32 - 1 input pixels, a prepared input's size
         and arrays still those it was prepared with (else
         INVALID_ARGUMENT); out loses its prepared data (as blend's and
         blend_motion's out do); input pixels that are
         RENDERCACHE_NO_SAMPLE or have no positive finite depth are skipped,
         and any valid inputs give a valid output (see HOW A WARP WORKS).
         Contract: every array holds its image's pixels; input colours are
         finite (as save and load ensure).
       blend(a, b, t, out): checks the three images' arrays and cameras,
         equal sizes, t in [0, 1]. blend_motion(w, a, b, t, motion, fill,
         out): as blend, and out is neither a nor b, prepared inputs as
         warp, the fill mode, a
         motion's arrays non-NULL, its transforms finite and invertible,
         object_count <= 2^24. Contract: world_a, world_b and world_t hold 12
         object_count floats.
       fitness(ids, count, w, h, &f): checks ids and each image non-NULL,
         count, w, h > 0, at most 2^28 pixels. Contract: each image holds w h
         ids.
       view_space_create(desc, &out): checks desc and out, the camera, lo and
         hi finite with lo <= hi, quality in [0, 1], max_depth <= 20,
         render_ids, the allocator, time finite. Contract: render_ids writes
         camera->width * camera->height ids. The accessors check vs and
         indices; locate checks a finite eye (clamped into the box).
       subdivide_time(desc, &times, &count): checks the cameras, at least 2
         finite strictly increasing times, quality, max_depth <= 20,
         render_ids, the allocator. Contract: as view_space_create.
       keytimes_create(desc, &out): checks solve, element_count > 0, finite
         t0 < t1, quality in [0, 1], epsilon and min_value >= 0 and finite,
         max_depth <= 20, the solution's size; a solve that returns
         non-finite values fails with INVALID_ARGUMENT. Contract: solve
         writes element_count * components floats. keytimes_eval(kt, time,
         values, count): checks kt, values, a finite time and count >=
         element_count * components; keytimes_values(kt, key) is NULL for a key
         out of range.
       lrms(reference, image, w, h, &lrms): checks the pointers, w, h > 0,
         at most 2^28 pixels, a positive finite mean luminance of reference
         and a finite sum. Contract: both images hold 3 w h floats.

   LIMITS

       Render cache: image up to 2^28 pixels, cache up to 2^31 points, up to
       2^24 objects, samples up to 64 frames late. Memory: 45 bytes per cache
       point (2 per pixel by default), 43 bytes per pixel (49.5 with
       parallel_for: 6 hold the points the projection's jobs hand to each
       other), about 48 (max_latency + 8) bytes per object, 6 KB
       for the eyes of the last 256 frames, and 576 KB for the re-sort into
       image order (1.1 MB with parallel_for; at least a bit per point,
       which takes more beyond 4.7 million points; and 260 bytes per 16384
       points for where each band of the image starts): 133 bytes per pixel
       in all and the re-sort's scratch, 36 MB for 512x512 (137 bytes per
       pixel) and 277 MB for 1920x1080.
       A frame reads and
       writes at random over these tens of megabytes: an allocator (desc.
       allocator) that backs blocks of 2 MB or more with huge pages (on
       Linux, 2 MB aligned and madvise(MADV_HUGEPAGE)) saves TLB misses,
       5-10% of a frame in bench_rendercache. Point
       colours are fixed when they are inserted (the cache ages them so that
       they get refreshed, and faster where samples find a colour changed);
       view-dependent shading changes only as points are resampled, as in
       the paper (a sample's view_lobe has its point resampled sooner as
       the view turns: the turn is measured from the point where its
       pixel's ray meets it, exact to half a pixel, in world space, so for
       a point of a moving object the object's own turn is not counted,
       only its motion's ageing; a point shaded more than 255 frames ago is
       compared with the eye of 255 frames ago, and view lobes are kept to
       3 digits, between 1e-6 and 1e6 radians). A hole's layer is found along rays of 8 pixels: the middle
       of a wider disocclusion stays sparse or empty until it is sampled,
       and a sample refills the holes within 8 pixels (or wide_radius, if
       larger) of it only, and only when it is late, predicted, changed the
       colour, or desc.refill_samples is set (marked serially, refilled in
       parallel bands when the insert call ends; at 8% of the pixels per
       frame that is most holes). A late sample of a moving object is placed with the
       transform of its frame, which the cache keeps for max_latency frames.
       Colour-change detection compares a sample with the one point it
       replaces: with a renderer as noisy as the changes it should see, it
       sees nothing (its threshold rises with the noise). Error diffusion
       runs in bands of 128 rows whose error does not cross into the next
       band (seams a 2-pixel-tall image would not have); the rest of a frame
       runs in parallel too (the requests tile by tile), but for the
       predicted requests and the insertion of late and predicted samples,
       which run on the calling thread.
       Walkthroughs: a range image takes 20 bytes per pixel; a warper about
       37 bytes per target pixel (61 with parallel_for, 20 more after a
       motion blend, and 20 per input when averaging) plus, with foreground
       fill, 52 bytes per pixel of the widest input's row and half a byte per
       target pixel per job, and 10 bytes per 16x16 tile of the inputs. A
       prepared image keeps 18 bytes per 16x16 tile (72 KB for 1024x1024).
       At most 2^32 - 1 input pixels per warp. Warps reproduce no
       view-dependent shading the inputs lack, and a pixelwise blend ghosts
       moving objects; the motion-compensated blend moves objects but not
       their shadows or reflections on static surfaces (those still blend
       pixelwise). Fitness counts pixels, so objects small in the id images
       hardly drive the subdivision, and an interval whose ends look alike is
       not split even if things happen in between (the paper's tests compare
       the ends only).

   PAPER

       Bruce Walter, George Drettakis and Steven Parker, Interactive Rendering using the Render Cache, EGWR 1999; Bruce Walter, George Drettakis and Donald P. Greenberg, Enhancing and Optimizing the Render Cache, EGWR 2002; Jeffry S. Nimeroff, Julie Dorsey and Holly Rushmeier, Implementation and Analysis of an Image-Based Global Illumination Framework for Animated Environments, IEEE TVCG 2(4), 1996 (sections 3-5); Peter Shirley and Kenneth Chiu, A Low Distortion Map Between Disk and Square, JGT 1997 (sphere cameras). The render cache as used by Rodolphe Crespin and Bernard Peroche, Light Vectors for a Moving Observer, WSCG 2004 (sections 2.2 and 4.1).
*/
#ifndef RENDERCACHE_H
#define RENDERCACHE_H

#include <stddef.h>
#include <stdint.h>

#define RENDERCACHE_VERSION_MAJOR 0
#define RENDERCACHE_VERSION_MINOR 11
#define RENDERCACHE_VERSION_PATCH 1

#ifndef RENDERCACHE_API
#  ifdef RENDERCACHE_STATIC
#    define RENDERCACHE_API static
#  else
#    define RENDERCACHE_API extern
#  endif
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Every fallible function returns one of these; zero is success. */
typedef enum rendercache_result {
    RENDERCACHE_OK = 0,
    RENDERCACHE_ERROR_INVALID_ARGUMENT,  /* NULL pointer, zero count, NaN, index out of range, ... */
    RENDERCACHE_ERROR_OUT_OF_MEMORY,     /* the allocator returned NULL, or a size overflowed */
    RENDERCACHE_ERROR_CORRUPT_DATA,      /* serialized data is truncated or fails its checks */
    RENDERCACHE_ERROR_VERSION,           /* serialized data has an unsupported format version */
    RENDERCACHE_ERROR_CANCELLED,         /* the progress callback asked to stop */
    RENDERCACHE_ERROR_IO                 /* a read or write callback failed */
} rendercache_result;

/* Object id of a sample whose ray left the scene: it becomes a background
   point at infinity along the ray. */
#define RENDERCACHE_MISS 0xFFFFFFFFu

/* Object id of a range-image pixel nothing is known about: a hole a warp
   left, or a fish-eye pixel outside the image circle. Warps skip it. */
#define RENDERCACHE_NO_SAMPLE 0xFFFFFFFEu

/* Depth written for RENDERCACHE_MISS pixels of a range image: the
   background, "at infinity" (the depth read for them is ignored). */
#define RENDERCACHE_FAR_DEPTH 1e18f

/* Version of the serialized range-image format (rendercache_range_image_save). */
#define RENDERCACHE_FILE_FORMAT_VERSION 1

/* rendercache_pixel_request.flags: the ray belongs to the predicted camera
   given to rendercache_predict, not to the current one. */
#define RENDERCACHE_REQUEST_PREDICTED 1u

/* rendercache_invalidate: every object, and the background points. */
#define RENDERCACHE_ALL_OBJECTS 0xFFFFFFFDu

/* Colour-change detection (rendercache_insert): a sample that changed the
   colour of its point ages the points shown within this many pixels of it,
   but for those shaded in the same frame (a window of 7 x 7: at an 8%
   budget, requests lie about 3.5 pixels apart, so the windows of one
   frame's changed samples cover a changed region). */
#define RENDERCACHE_CHANGE_RADIUS 3

typedef struct rendercache rendercache;

typedef struct rendercache_allocator {
    void *(*alloc)(size_t size, void *user);  /* NULL: RENDERCACHE_MALLOC */
    void (*free)(void *ptr, void *user);      /* NULL: RENDERCACHE_FREE */
    void *user;
} rendercache_allocator;

typedef void (*rendercache_job_fn)(void *ctx, uint32_t index);

/* Camera models. The render cache takes perspective cameras; range images
   (base views) may use any kind. */
typedef enum rendercache_camera_kind {
    RENDERCACHE_CAMERA_PERSPECTIVE = 0,  /* pinhole; vfov_degrees spans the image height */
    RENDERCACHE_CAMERA_FISHEYE = 1,      /* hemispherical, equidistant (as Radiance's angular fish-eye):
                                            the circle inscribed in the image spans 180 degrees, the
                                            distance from its centre is proportional to the angle from
                                            the view axis; pixels outside the circle have no ray */
    RENDERCACHE_CAMERA_SPHERE = 2        /* the full sphere: two hemispheres side by side, each mapped
                                            to its half of the image by the equal-area concentric map
                                            of Shirley and Chiu (left half: looking forward, right half:
                                            looking backward); every pixel has a ray, and with
                                            width = 2 * height every pixel covers the same solid angle */
} rendercache_camera_kind;

/* A look-at camera: pixels are square, "up" need not be orthogonal to the
   view direction (it is orthogonalised), right = forward x up. */
typedef struct rendercache_camera {
    rendercache_camera_kind kind;
    float eye[3];
    float look_at[3];        /* a point on the view axis, not the eye */
    float up[3];             /* not parallel to look_at - eye */
    float vfov_degrees;      /* perspective: in (0, 180); ignored by the other kinds */
    uint32_t width, height;  /* pixels; must equal the cache's image size */
} rendercache_camera;

typedef struct rendercache_desc {
    uint32_t width, height;      /* image size in pixels (required) */
    float points_per_pixel;      /* cache capacity = points_per_pixel * width * height; default 2 */
    uint32_t object_count;       /* object ids 0 .. object_count-1, each with a transform; default 256 */
    float depth_tolerance;       /* relative depth step that counts as a discontinuity (depth cull,
                                    interpolation layers); default 0.1 */
    uint32_t age_ramp_frames;    /* a point of priority scale 1 reaches half the priority range at this
                                    age, and keeps rising after (more slowly, above the holes); default 32 */
    uint32_t moving_age_step;    /* age a point gains per frame while its object moves; default 4 */
    uint32_t sparse_neighbours;  /* a hole with fewer points in its 3x3 neighbourhood uses the wide
                                    filter; default 2 (1..8) */
    uint32_t wide_radius;        /* half width of the wide filter: default 3 (7x7), at most 7 */
    float predict_fraction;      /* share of the budget for predicted samples when
                                    rendercache_predict was called; default 0.25, at most 1 */
    float edge_fraction;         /* share of the requests for the current camera that go first to
                                    pixels at the image's steps (rendercache_request); default 0:
                                    none (a view that stops keeps its steps, which would be requested
                                    every frame: a still 64x48 camera at 8 % took 100 frames instead
                                    of 13 to show every pixel's own sample with 0.5); at most 1; a
                                    moving camera gains most with 1 */
    float edge_step;             /* a pixel is at a step when its luminance and a 3x3 neighbour's
                                    differ by more than this times the image's mean; default 0.5 */
    uint32_t max_latency;        /* frames a sample may come back late (its request's frame before
                                    the current one); later ones are dropped; default 4, at most 64 */
    float change_threshold;      /* a sample whose colour differs from the point it replaces by more
                                    than this share of the brighter of the two (largest channel
                                    difference over largest channel) ages the points shown around it
                                    (WDG02); default 0.25; FLT_MAX never */
    int refill_samples;          /* nonzero: the holes within 8 pixels of each of the current frame's
                                    samples are filled again when rendercache_insert ends, for a caller
                                    that shows the frame after inserting its samples (a fast walk shows
                                    no background between new points); 0 (default): they keep the
                                    frame's filling until the next frame, as in WDG99 (bench_rendercache
                                    at 512x512 and 8%, one thread: 11.6 ms a frame with it, 8.6
                                    without) */
    float background[3];         /* colour of pixels nothing covers; default black */
    rendercache_allocator allocator;
    void (*parallel_for)(void *user, rendercache_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    double (*clock)(void *user); /* optional: seconds, to time the phases in rendercache_stats */
    void *clock_user;
    void (*log)(void *user, const char *message); /* optional details on errors */
    void *log_user;
} rendercache_desc;

/* A pixel that deserves a new sample, with its primary ray (unit dir). */
typedef struct rendercache_pixel_request {
    uint64_t frame;          /* the frame it was made in (rendercache_stats.frame then) */
    uint32_t x, y;
    uint32_t flags;          /* RENDERCACHE_REQUEST_PREDICTED or 0 */
    float org[3], dir[3];
} rendercache_pixel_request;

/* A shaded sample: copy frame, x, y and flags from its request. It may come
   back frames later (an asynchronous renderer): it is then stored at its
   own point, as seen in its request's frame. */
typedef struct rendercache_sample {
    uint64_t frame;          /* the request's frame; 0 means the current frame */
    uint32_t x, y;           /* the requested pixel */
    uint32_t flags;          /* the request's flags */
    uint32_t object;         /* id of the object hit (< desc.object_count), or RENDERCACHE_MISS */
    float position[3];       /* world-space hit point at the request's frame (the object where it
                                was then); ignored for a miss */
    float rgb[3];            /* radiance towards the eye, linear RGB, finite */
    float priority_scale;    /* multiplies the point's priority, e.g. lightvec_priority(1, W);
                                0 means 1 */
    float view_lobe;         /* radians, >= 0: how far the view may turn before a view-dependent
                                colour (a highlight) is as stale as a point of age age_ramp_frames;
                                0 (the default): the colour does not depend on the view. The
                                point's priority grows with the angle between the eye that shaded
                                it and the current eye, seen from the point, over this */
} rendercache_sample;

/* What a pixel of the current image shows (rendercache_pixel_kinds). */
typedef enum rendercache_pixel_kind {
    RENDERCACHE_PIXEL_POINT = 0,     /* a cached point */
    RENDERCACHE_PIXEL_INTERPOLATED,  /* a hole filled by the 3x3 filter */
    RENDERCACHE_PIXEL_SPARSE,        /* a hole filled by the wide filter */
    RENDERCACHE_PIXEL_EMPTY          /* nothing near: background colour */
} rendercache_pixel_kind;

typedef struct rendercache_stats {
    uint64_t frame;              /* begin_frame calls so far */
    uint32_t capacity;           /* cache slots */
    uint32_t live_points;        /* slots holding a point */
    uint32_t projected;          /* points that landed inside the image this frame */
    uint32_t visible;            /* pixels showing a point after z-buffer and depth cull */
    uint32_t culled;             /* z-buffer winners dropped by the depth cull */
    uint32_t interpolated;       /* holes filled by the 3x3 filter */
    uint32_t sparse;             /* holes filled by the wide filter */
    uint32_t empty;              /* pixels nothing covers */
    uint32_t requested;          /* requests handed out since begin_frame (all kinds) */
    uint32_t predicted;          /* of which for the predicted camera */
    uint32_t inserted;           /* samples accepted since begin_frame */
    uint32_t replaced;           /* of which replaced the point their pixel showed */
    uint32_t evicted;            /* of which overwrote a point not visible in this frame */
    uint32_t late;               /* of which came from an earlier frame's requests */
    uint32_t changed;            /* of which changed the colour of the point they replaced */
    uint32_t rejected;           /* samples ignored since begin_frame (bad values or pixel) */
    uint32_t dropped;            /* samples ignored: later than desc.max_latency, or late or
                                    predicted ones finding no slot the frame does not show */
    /* seconds spent in each phase of the last frame (0 without desc.clock) */
    double time_project;         /* projection and z-buffer of every point */
    double time_cull;            /* depth cull, with the colour and priority of the pixels showing points,
                                    and the hole filling interleaved with it */
    double time_interpolate;     /* 0: the hole filling is timed with the cull (time_cull) */
    double time_predict;         /* rendercache_predict (begin_frame_predicted: in time_project) */
    double time_request;         /* threshold and error diffusion (all request calls) */
    double time_insert;
    double time_sort;            /* re-sorting a share of the cache into image order (end of begin_frame) */
} rendercache_stats;

RENDERCACHE_API const char *rendercache_result_string(rendercache_result r);

/* Creates a cache for images of desc->width x desc->height pixels. Every
   buffer the per-frame work needs is allocated here, none later. */
RENDERCACHE_API rendercache_result rendercache_create(const rendercache_desc *desc, rendercache **out);
RENDERCACHE_API void rendercache_destroy(rendercache *rc);

/* Sets the object-to-world transform of an object: m is 3x4 row-major
   (world = m[0..2] . p + m[3], ...). Its points move with it from the next
   begin_frame on, and age faster while the transform keeps changing. Every
   object starts at the identity. Singular or non-finite matrices are
   rejected. */
RENDERCACHE_API rendercache_result rendercache_set_object_transform(rendercache *rc, uint32_t object,
                                                                    const float m[12]);

/* Starts a frame: ages the points, projects them into the camera (a
   perspective one), z-buffers, depth-culls, fills holes and builds the
   priority image. */
RENDERCACHE_API rendercache_result rendercache_begin_frame(rendercache *rc, const rendercache_camera *camera);

/* Predictive sampling (2002): projects the cache into the camera the caller
   expects next; rendercache_request then spends up to desc.predict_fraction
   of its budget on the holes that camera would see (requests flagged
   RENDERCACHE_REQUEST_PREDICTED, rays of the predicted camera). Valid until
   the next begin_frame. */
RENDERCACHE_API rendercache_result rendercache_predict(rendercache *rc, const rendercache_camera *next);

/* begin_frame(camera) followed at once by predict(next), with the same
   result bit for bit, and cheaper: the points are read once for both (the
   prediction's count is then part of stats.time_project). For a caller
   that knows the next camera when a frame starts. (Late samples inserted
   between begin_frame and predict are counted by predict; here they come
   after the count.) */
RENDERCACHE_API rendercache_result rendercache_begin_frame_predicted(rendercache *rc, const rendercache_camera *camera,
                                                                     const rendercache_camera *next);

/* Chooses up to max pixels to sample by error diffusion of the thresholded
   priority image and writes them to out (*count of them); with
   desc.edge_fraction, pixels at the image's steps first. A second call in
   the same frame returns the next most important pixels. */
RENDERCACHE_API rendercache_result rendercache_request(rendercache *rc, rendercache_pixel_request *out,
                                                       uint32_t max, uint32_t *count);

/* Adds shaded samples as points and writes to *taken (may be NULL) how
   many were stored. A sample of the current frame replaces the point its
   pixel shows (and updates the image at once). A late sample (its
   request's frame before the current one) is stored at its own point: its
   hit point, or for a miss the direction of its request's ray; where that
   point lands in the current image it replaces the point shown there when
   that is the same surface (within the depth tolerance) and is shown when
   nothing nearer is; otherwise, and for predicted samples, it takes the
   slot of the oldest point the frame does not show. A sample that replaces
   a point of another colour (desc.change_threshold) ages the points shown
   within RENDERCACHE_CHANGE_RADIUS pixels of it, so that they are
   requested next. Returns RENDERCACHE_ERROR_INVALID_ARGUMENT when some
   sample was malformed (pixel outside the image, unknown object or flag,
   non-finite value, a frame not yet begun, a predicted sample of a frame
   without prediction): those are skipped and counted in stats.rejected,
   the others are stored. Samples later than desc.max_latency frames are
   dropped (stats.dropped; not an error). n = 0 does nothing. */
RENDERCACHE_API rendercache_result rendercache_insert(rendercache *rc, const rendercache_sample *samples,
                                                      uint32_t n, uint32_t *taken);

/* The lighting of an object changed (or of everything, object =
   RENDERCACHE_ALL_OBJECTS; the background points: RENDERCACHE_MISS): its
   points are aged to the top of the age ramp, so that they are resampled
   before every point that is merely old, from the priority image of the
   current frame on. */
RENDERCACHE_API rendercache_result rendercache_invalidate(rendercache *rc, uint32_t object);

/* The lighting changed where the engine knows it did (an object moved
   and its shadow with it, a lamp was switched on in one room): changed
   is asked about every cached point on an object (not the background
   points), with its world position in the current frame and its object
   id, and the points it answers non-zero for are aged as a colour change
   ages the points around it (rendercache_insert; WDG02): to the top of
   the age ramp, a point of priority scale s > 1 to age_ramp / s, where
   it ranks with the least urgent holes (an older point keeps its age),
   from the priority image of the current frame on. Unlike
   rendercache_invalidate, which adds the age ramp to every point of an
   object, this does not let a wide region outrank the holes: the
   walkthrough's bunny, whose step may change the light of a fifth of the
   office's image, took the budget from the holes with that (pooled LRMS
   against converged renders 0.079 -> 0.100). Each point is asked once (a
   pixel's priority takes the answer about the point it shows). With
   desc.parallel_for, changed is called from several threads at once (in
   jobs over ranges of slots, each in slot order), so it must be safe to
   call concurrently (e.g. only read user); without, from the calling
   thread in slot order. The result does not depend on threads. Cost: one
   affine transform and one call per point on an object, then a pass over
   the pixels when a point was aged (at 640x480, 2 points per pixel: up to
   614400 calls; in the walkthrough's office, whose predicate tests the
   cones of its lamps, 5.9 ms of CPU a frame, 9.0 when a shown point was
   asked twice; with parallel_for, spread over the threads).
   aged (may be NULL) gets the number of points aged. */
RENDERCACHE_API rendercache_result rendercache_invalidate_where(rendercache *rc,
                                                                int (*changed)(void *user, const float p[3],
                                                                               uint32_t object),
                                                                void *user, uint32_t *aged);

/* rendercache_invalidate_where for a caller between frames, whose frame's
   requests are made and whose next call is begin_frame (the walkthrough
   ages the points a moving object's step shadows before it begins the
   frame that shows the step): the same points are aged alike, and the
   current frame's priority image is left as it is, since begin_frame
   ranks every pixel again from the points' ages; the frames that follow
   are the same bit for bit. It saves the pass over the pixels (at 640x480
   a read of every pixel's point, spread over the threads). A request made
   before the next begin_frame would not see the ageing: call
   rendercache_invalidate_where then. */
RENDERCACHE_API rendercache_result rendercache_invalidate_where_next_frame(rendercache *rc,
                                                                           int (*changed)(void *user, const float p[3],
                                                                                          uint32_t object),
                                                                           void *user, uint32_t *aged);

/* The current image: width * height * 3 floats, valid until the next call
   that changes the cache. */
RENDERCACHE_API const float *rendercache_image(const rendercache *rc);
/* Per-pixel priority in [0, 1] (1: nothing to show), after requests zeroed the chosen pixels. */
RENDERCACHE_API const float *rendercache_priority_image(const rendercache *rc);
/* Per-pixel rendercache_pixel_kind values. */
RENDERCACHE_API const unsigned char *rendercache_pixel_kinds(const rendercache *rc);

/* A cheap estimate of the frame for its holes (e.g. a rasterized direct
   light or albedo x stored irradiance), as temporal reprojection fills
   disocclusions (WDG02 section 6 suggests a coarse render). rgb holds
   width * height * 3 floats, row-major; the size is the frame's or an
   integer fraction of it (each fallback pixel covers an equal block).
   confidence (optional, width * height in [0, 1]) scales its weight; 0
   where the estimate knows nothing. A pixel with a non-finite or huge
   value, or a confidence outside [0, 1], is skipped (the filter stays). */
typedef struct rendercache_fallback {
    const float *rgb;
    const float *confidence;    /* NULL: 1 everywhere */
    uint32_t width, height;
    float near_pixels;          /* a hole whose nearest point is this close keeps the filter; 0: default 1 */
    float far_pixels;           /* this far or farther, the fallback replaces it; 0: default wide_radius + 1 */
} rendercache_fallback;

/* The current image with its holes blended towards the fallback by how
   far the nearest point is (chamfer distance, pixels): weight
   confidence * clamp((d - near) / (far - near), 0, 1), so a hole ringed by
   close points keeps the hole filters' colour and a wide disocclusion
   takes the fallback. Pixels showing points are copied. out holds
   width * height * 3 floats of the frame. Reads the cache only; the
   image rendercache_image returns is unchanged. Errors: NULL pointers, no
   frame begun, a size that does not divide the frame's, near < 0 or
   far <= near or non-finite. */
RENDERCACHE_API rendercache_result rendercache_compose_fallback(const rendercache *rc, const rendercache_fallback *fallback,
                                                                float *out);
/* Per-pixel depth of the point shown (distance from the eye; 1e18 for a
   background point), FLT_MAX where the pixel shows no point. Computed on
   each call. */
RENDERCACHE_API const float *rendercache_depth_image(rendercache *rc);

RENDERCACHE_API void rendercache_get_stats(const rendercache *rc, rendercache_stats *out);

/* Forgets every point (e.g. after lights changed); transforms are kept. */
RENDERCACHE_API void rendercache_clear(rendercache *rc);

/* The primary ray through image point (px, py) (pixel centres at +0.5):
   org = eye, dir = unit direction. A point outside a fish-eye's circle has
   no ray: RENDERCACHE_ERROR_INVALID_ARGUMENT. */
RENDERCACHE_API rendercache_result rendercache_camera_ray(const rendercache_camera *camera, float px, float py,
                                                          float org[3], float dir[3]);
/* Projects world point p: returns 1 and the image point and the distance
   from the eye when p lands inside the image (for a fish-eye: within its
   hemisphere), else 0. */
RENDERCACHE_API int rendercache_camera_project(const rendercache_camera *camera, const float p[3],
                                               float *px, float *py, float *depth);

/* ------------------------------------------------------------------------
   Range-image walkthroughs (Nimeroff, Dorsey and Rushmeier 1996)
   ------------------------------------------------------------------------ */

/* Serialization callbacks: return 0 when all n bytes were written / read. */
typedef int (*rendercache_write_fn)(void *user, const void *bytes, size_t n);
typedef int (*rendercache_read_fn)(void *user, void *bytes, size_t n);

typedef struct rendercache_range_prepared rendercache_range_prepared;

/* A range image: what a camera sees, per pixel radiance, the distance along
   the pixel's ray and the id of the object hit. rendercache_range_image_create
   allocates the arrays (rendercache_range_image_destroy frees them); a caller
   may instead fill a struct of its own with its own arrays, and then must not
   destroy it. Pixels are row-major, top row first. A warp skips pixels of
   RENDERCACHE_NO_SAMPLE and pixels whose depth is not finite and positive;
   it reads the depth of RENDERCACHE_MISS pixels as infinite. */
typedef struct rendercache_range_image {
    rendercache_camera camera;       /* the view; its width x height is the image size */
    double time;                     /* scene time the image shows (caller's units) */
    float *rgb;                      /* 3 per pixel: radiance towards the eye, linear RGB */
    float *depth;                    /* distance from camera.eye along the pixel's ray (> 0) */
    uint32_t *object;                /* id of the object hit, RENDERCACHE_MISS (background at
                                        infinity) or RENDERCACHE_NO_SAMPLE (nothing known) */
    rendercache_allocator allocator; /* the allocator of the arrays (create and load set it) */
    rendercache_range_prepared *prepared;   /* rendercache_range_image_prepare's data, or NULL
                                               (an image of your own: zero the struct) */
} rendercache_range_image;

/* How a warp fills the pixels no reprojected pixel lands in (the four fill
   algorithms of Radiance's pinterp). 0 is the default, BOTH. */
typedef enum rendercache_fill {
    RENDERCACHE_FILL_DEFAULT = 0,      /* RENDERCACHE_FILL_BOTH */
    RENDERCACHE_FILL_NONE,             /* one target pixel per source pixel; the rest stay empty */
    RENDERCACHE_FILL_FOREGROUND,       /* each source pixel also spans the quad to its right and lower
                                          neighbours (two triangles, colour interpolated) when their
                                          depths agree within twice the tolerance */
    RENDERCACHE_FILL_BACKGROUND,       /* empty pixels take the farther of the nearest filled pixels
                                          along their row and their column */
    RENDERCACHE_FILL_BOTH              /* foreground, then background */
} rendercache_fill;

typedef struct rendercache_warper rendercache_warper;

/* Computes a pixel that the warp and the fills left empty (e.g. by tracing
   its ray): writes its colour, its distance along dir and its object id
   (RENDERCACHE_MISS for the background) and returns 1, or returns 0 to
   leave it empty. Called from desc.parallel_for jobs when one is given. */
typedef int (*rendercache_fill_fn)(void *user, uint32_t x, uint32_t y, const float org[3], const float dir[3],
                                   float rgb[3], float *depth, uint32_t *object);

typedef struct rendercache_warp_desc {
    float depth_tolerance;       /* relative depth difference below which two surfaces are the same
                                    (pinterp's -t): an input farther from the new eye replaces a
                                    pixel only when it is nearer by more than this (per rank);
                                    foreground quads span depths within twice this; default 0.02 */
    float background[3];         /* colour of the pixels left empty; default black */
    rendercache_fill_fn fill_pixel;  /* optional: computes the pixels still empty after the fill */
    void *fill_user;
    uint32_t max_fill_distance;  /* background fill: an empty pixel takes a filled pixel at most this many
                                    pixels away along its row or column, else stays empty (for
                                    fill_pixel: pinterp's -fs); default 0: any distance */
    int average;                 /* non-zero: several inputs that see the same surface (within the
                                    tolerance) are averaged, each weighted by how nearly its ray
                                    agrees with the target's (pinterp's -a); costs a warp of each
                                    input alone and 20 bytes per target pixel and input */
    rendercache_allocator allocator;
    void (*parallel_for)(void *user, rendercache_job_fn job, void *ctx, uint32_t count);
    void *parallel_user;
    double (*clock)(void *user); /* optional: seconds, to time the phases in rendercache_warp_stats */
    void *clock_user;
    void (*log)(void *user, const char *message);
    void *log_user;
} rendercache_warp_desc;

typedef struct rendercache_warp_stats {
    uint32_t images;             /* inputs of the last warp (2 for a blend) */
    uint32_t projected;          /* source pixels that landed in the image, over all inputs */
    uint32_t warped;             /* target pixels filled by reprojected pixels or foreground quads */
    uint32_t background;         /* target pixels filled by the background fill */
    uint32_t computed;           /* target pixels computed by fill_pixel */
    uint32_t empty;              /* target pixels left RENDERCACHE_NO_SAMPLE (rays only) */
    double time_project;         /* reprojection and z-buffer, all inputs (0 without desc.clock) */
    double time_fill;            /* background fill and fill_pixel */
    double time_total;
} rendercache_warp_stats;

/* Object motion for rendercache_blend_motion: object-to-world transforms
   (3x4 row-major, 12 floats per object) of objects 0 .. object_count-1 at
   the times of images a and b and at the time to show. Pixels of other ids
   are static. */
typedef struct rendercache_motion {
    uint32_t object_count;
    const float *world_a;
    const float *world_b;
    const float *world_t;
} rendercache_motion;

/* Renders an id image of camera at time: camera->width * camera->height
   object (or polygon) ids, RENDERCACHE_NO_SAMPLE where the camera has no
   ray. Returns 0, or non-zero to cancel the subdivision. */
typedef int (*rendercache_render_ids_fn)(void *user, const rendercache_camera *camera, double time, uint32_t *ids);

/* Adaptive subdivision of a view space (section 4.1): a box of eye
   positions, 1D, 2D or 3D (an axis with lo == hi is not subdivided). A
   cell whose corner cameras' id images have fitness below quality is
   halved across its longest axis, recursively; the corners of the leaf
   cells are the base views. */
typedef struct rendercache_view_space_desc {
    rendercache_camera camera;   /* every view's kind, look direction (look_at - eye), up, vfov and
                                    id image size; its eye is replaced by the view's */
    float lo[3], hi[3];          /* the view space */
    double time;                 /* passed to render_ids */
    float quality;               /* q in [0, 1]: 0 keeps the corners of the box, 1 subdivides until
                                    the id images agree (or max_depth) */
    uint32_t max_depth;          /* halvings of each axis at most: default 8, at most 20 */
    rendercache_render_ids_fn render_ids;
    void *user;
    rendercache_allocator allocator;
    void (*log)(void *user, const char *message);
    void *log_user;
} rendercache_view_space_desc;

typedef struct rendercache_view_space rendercache_view_space;

/* Adaptive subdivision of time (section 4.2): the sorted key times (at
   least two, e.g. the start and end of the animation, or an earlier list to
   refine) are refined by halving every interval in which the id images of
   some camera at its two ends have fitness below quality. Cameras: fish-eye
   or sphere cameras at the light sources (direct illumination coherence)
   and the base views (visibility coherence). */
typedef struct rendercache_time_desc {
    const rendercache_camera *cameras;
    uint32_t camera_count;
    const double *times;         /* sorted, strictly increasing, finite */
    uint32_t time_count;         /* at least 2 */
    float quality;               /* q in [0, 1] */
    uint32_t max_depth;          /* halvings of an interval at most: default 8, at most 20 */
    rendercache_render_ids_fn render_ids;
    void *user;
    rendercache_allocator allocator;
    void (*log)(void *user, const char *message);
    void *log_user;
} rendercache_time_desc;

/* Computes the object-space solution (e.g. indirect irradiance of every
   vertex) at time: element_count * components floats. Returns 0, or non-zero
   to cancel. */
typedef int (*rendercache_solve_fn)(void *user, double time, float *values);

/* Key times of an object-space solution (sections 4.3 and 5.1.2): the
   interval [t0, t1] is halved recursively while the fraction of elements
   whose value changes by more than epsilon between the interval's ends
   exceeds 1 - quality; between key times the solution is interpolated
   linearly. */
typedef struct rendercache_keytime_desc {
    uint32_t element_count;      /* vertices or elements */
    uint32_t components;         /* floats per element; default 1 (3 for RGB) */
    double t0, t1;               /* t0 < t1 */
    float quality;               /* q in [0, 1] */
    float epsilon;               /* an element changed when some component moved by more than
                                    epsilon * max(|before|, |after|, min_value); default 0.05 */
    float min_value;             /* magnitude below which changes count as absolute; default 0 */
    uint32_t max_depth;          /* halvings of an interval at most: default 8, at most 20 */
    rendercache_solve_fn solve;
    void *user;
    rendercache_allocator allocator;
    void (*log)(void *user, const char *message);
    void *log_user;
} rendercache_keytime_desc;

typedef struct rendercache_keytimes rendercache_keytimes;

/* Range images. create: arrays for camera's size, rgb 0, depth
   RENDERCACHE_FAR_DEPTH, object RENDERCACHE_NO_SAMPLE (allocator may be NULL). */
RENDERCACHE_API rendercache_result rendercache_range_image_create(const rendercache_camera *camera,
                                                                  const rendercache_allocator *allocator,
                                                                  rendercache_range_image **out);
RENDERCACHE_API void rendercache_range_image_destroy(rendercache_range_image *image);
RENDERCACHE_API rendercache_result rendercache_range_image_save(const rendercache_range_image *image,
                                                                rendercache_write_fn write, void *user);
RENDERCACHE_API rendercache_result rendercache_range_image_load(const rendercache_allocator *allocator,
                                                                rendercache_read_fn read, void *user,
                                                                rendercache_range_image **out);
RENDERCACHE_API rendercache_result rendercache_range_image_save_to_memory(const rendercache_range_image *image,
                                                                          const rendercache_allocator *allocator,
                                                                          void **data, size_t *size);
RENDERCACHE_API rendercache_result rendercache_range_image_load_from_memory(const void *data, size_t size,
                                                                            const rendercache_allocator *allocator,
                                                                            rendercache_range_image **out);
/* Frees what save_to_memory (or subdivide_time) returned. */
RENDERCACHE_API void rendercache_free_memory(const rendercache_allocator *allocator, void *data);
/* Prepares an image for warps (a base view warped again and again): stores,
   with image->allocator, what the warp needs of the image alone (the depth
   bounds of its tiles, rings included), so that warps read it instead of
   the depths and objects of half its tiles. Warps give bit for bit the images they give unprepared. The caller
   promises that the image's size and its depth and object arrays do not
   change until unprepare (or destroy): a warp of an image whose size or
   array pointers changed fails with INVALID_ARGUMENT, and one whose depths
   or objects changed in place shows what the stale bounds let through (a
   wrong image, never a crash or a read outside the arrays). Preparing again
   recomputes; on failure the image is left unprepared. A warp or blend
   that writes an image unprepares it. */
RENDERCACHE_API rendercache_result rendercache_range_image_prepare(rendercache_range_image *image);
/* Frees the prepared data (NULL or an unprepared image: nothing). */
RENDERCACHE_API void rendercache_range_image_unprepare(rendercache_range_image *image);

/* View interpolation. A warper holds the buffers of one target size (they
   are allocated by the first warp and again only when the size changes: use
   one warper per target size). */
RENDERCACHE_API rendercache_result rendercache_warper_create(const rendercache_warp_desc *desc,
                                                             rendercache_warper **out);
RENDERCACHE_API void rendercache_warper_destroy(rendercache_warper *w);

/* Reprojects every pixel of images[0..n) into camera (as Radiance's pinterp):
   inputs are ranked by the distance of their eye to camera's eye, a
   z-buffer keeps the nearest surface per pixel, and a surface of rank k
   replaces one of a nearer rank only when nearer by more than the depth
   tolerance per rank between them (its squared distances count times
   (1 + tolerance)^2k); then fill (see HOW A WARP WORKS).
   camera may be NULL (out->camera); its size must be out's. Writes out's
   camera, rgb, depth, object and time (that of the nearest input). Pixels
   left empty are RENDERCACHE_NO_SAMPLE with the background colour. */
RENDERCACHE_API rendercache_result rendercache_warp(rendercache_warper *w, const rendercache_range_image *const *images,
                                                    uint32_t n, const rendercache_camera *camera, rendercache_fill fill,
                                                    rendercache_range_image *out);

/* Seeds the cache from range images (e.g. rendercache_warp's output, or
   base views), after rendercache_begin_frame: every pixel of an image
   whose object is one of the cache's (or RENDERCACHE_MISS) and that shows
   in the current frame (lands in the image, in front of or on the surface
   shown there, or in a hole it is not hidden in) becomes a point, as old
   as the top of the age ramp (real samples replace it first), and the
   image is updated at once. Objects are taken where their current
   transforms put them. *taken (may be NULL): the points stored. */
RENDERCACHE_API rendercache_result rendercache_seed(rendercache *rc, const rendercache_range_image *const *images,
                                                    uint32_t count, uint32_t *taken);

/* Time interpolation, pixelwise (as Radiance's pcomb): rgb = (1 - t) a + t b;
   depth and object of the image nearer in time (a when t < 0.5); time
   interpolated. a, b and out have one size; out may be a or b. */
RENDERCACHE_API rendercache_result rendercache_blend(const rendercache_range_image *a, const rendercache_range_image *b,
                                                     float t, rendercache_range_image *out);

/* Motion-compensated time interpolation: every pixel of a and b is moved
   with its object from its image's time to the blend time and reprojected
   into out->camera (usually a's); where both images then show the same
   object at the same depth the colours are blended with weights 1 - t and t,
   elsewhere the nearer surface is kept, and pixels neither image saw are
   filled as by rendercache_warp. Moving objects do not ghost. */
RENDERCACHE_API rendercache_result rendercache_blend_motion(rendercache_warper *w, const rendercache_range_image *a,
                                                            const rendercache_range_image *b, float t,
                                                            const rendercache_motion *motion, rendercache_fill fill,
                                                            rendercache_range_image *out);
RENDERCACHE_API void rendercache_warp_get_stats(const rendercache_warper *w, rendercache_warp_stats *out);

/* Coherence. Fitness f = N / PQ (section 4.1): the fraction of pixels whose
   id is the same in all count images (width x height each); pixels that are
   RENDERCACHE_NO_SAMPLE in every image (no ray) are not counted. */
RENDERCACHE_API rendercache_result rendercache_fitness(const uint32_t *const *id_images, uint32_t count, uint32_t width,
                                                       uint32_t height, float *fitness);

RENDERCACHE_API rendercache_result rendercache_view_space_create(const rendercache_view_space_desc *desc,
                                                                 rendercache_view_space **out);
RENDERCACHE_API void rendercache_view_space_destroy(rendercache_view_space *vs);
/* The base views: count, and their eyes (3 floats each). */
RENDERCACHE_API uint32_t rendercache_view_space_count(const rendercache_view_space *vs);
RENDERCACHE_API const float *rendercache_view_space_eyes(const rendercache_view_space *vs);
/* The camera of view i: desc.camera moved to the view's eye. */
RENDERCACHE_API rendercache_result rendercache_view_space_camera(const rendercache_view_space *vs, uint32_t i,
                                                                 rendercache_camera *camera);
/* The views at the corners of the leaf cell holding eye (clamped into the
   box): 2^d indices for a d-dimensional space (bit k of a corner's number
   set: the upper end of the k-th subdivided axis), written to views[0..8). */
RENDERCACHE_API rendercache_result rendercache_view_space_locate(const rendercache_view_space *vs, const float eye[3],
                                                                 uint32_t views[8], uint32_t *count);
/* Leaf cells and their fitness, for reports. */
RENDERCACHE_API uint32_t rendercache_view_space_cell_count(const rendercache_view_space *vs);
RENDERCACHE_API rendercache_result rendercache_view_space_cell(const rendercache_view_space *vs, uint32_t cell,
                                                               float lo[3], float hi[3], float *fitness);

/* Refines a time list; *times (allocated with desc.allocator, free it with
   rendercache_free_memory) receives the *count sorted key times. */
RENDERCACHE_API rendercache_result rendercache_subdivide_time(const rendercache_time_desc *desc, double **times,
                                                              uint32_t *count);

RENDERCACHE_API rendercache_result rendercache_keytimes_create(const rendercache_keytime_desc *desc,
                                                               rendercache_keytimes **out);
RENDERCACHE_API void rendercache_keytimes_destroy(rendercache_keytimes *kt);
RENDERCACHE_API uint32_t rendercache_keytimes_count(const rendercache_keytimes *kt);
RENDERCACHE_API const double *rendercache_keytimes_times(const rendercache_keytimes *kt);
/* The stored solution of key k: element_count * components floats. */
RENDERCACHE_API const float *rendercache_keytimes_values(const rendercache_keytimes *kt, uint32_t key);
/* The solution at time, interpolated linearly between the key times around
   it (clamped to [t0, t1]), into values[0 .. count): count must be at
   least element_count * components. */
RENDERCACHE_API rendercache_result rendercache_keytimes_eval(const rendercache_keytimes *kt, double time, float *values,
                                                             size_t count);

/* Relative luminance RMS error (section 5): the RMS of the per-pixel
   luminance difference (Rec. 709 weights) divided by the mean luminance of
   reference. width x height RGB images; the reference mean must be > 0. */
RENDERCACHE_API rendercache_result rendercache_lrms(const float *reference, const float *image, uint32_t width,
                                                    uint32_t height, double *lrms);

#ifdef __cplusplus
}
#endif
#endif /* RENDERCACHE_H */

/* ------------------------------------------------------------------------ */
#if defined(RENDERCACHE_IMPLEMENTATION) && !defined(RENDERCACHE_IMPLEMENTATION_INCLUDED)
#define RENDERCACHE_IMPLEMENTATION_INCLUDED

#if defined(RENDERCACHE_MALLOC) != defined(RENDERCACHE_FREE)
#  error "rendercache.h: define both RENDERCACHE_MALLOC and RENDERCACHE_FREE, or neither"
#endif
#ifndef RENDERCACHE_MALLOC
#  include <stdlib.h>
#  define RENDERCACHE_MALLOC(size) malloc(size)
#  define RENDERCACHE_FREE(ptr) free(ptr)
#endif

#include <string.h>
#include <math.h>
#include <float.h>

/* ======================================================================
   1. allocation
   ---------------------------------------------------------------------- */
/* Both callbacks or neither: a lone alloc would leak through RENDERCACHE_FREE. */
static int rendercache__allocator_valid(const rendercache_allocator *a)
{
    return (a->alloc == NULL) == (a->free == NULL);
}

static void *rendercache__alloc(const rendercache_allocator *a, size_t size)
{
    if (size == 0) size = 1;
    return a->alloc ? a->alloc(size, a->user) : RENDERCACHE_MALLOC(size);
}

/* count * item bytes, or NULL when the product overflows. */
static void *rendercache__alloc_array(const rendercache_allocator *a, size_t count, size_t item)
{
    if (item && count > SIZE_MAX / item) return NULL;
    return rendercache__alloc(a, count * item);
}

static void rendercache__free(const rendercache_allocator *a, void *p)
{
    if (!p) return;
    if (a->free) a->free(p, a->user);
    else RENDERCACHE_FREE(p);
}

/* Zero means default: the documented default replaces a zero field. */
#define rendercache__def(v, d) ((v) ? (v) : (d))

/* A hint to load a cache line ahead of its use, or (_WRITE) ahead of a
   store to it (compilers without one: nothing). */
#if defined(__GNUC__) || defined(__clang__)
#  define RENDERCACHE__PREFETCH(p) __builtin_prefetch(p)
#  define RENDERCACHE__PREFETCH_WRITE(p) __builtin_prefetch((p), 1)
#else
#  define RENDERCACHE__PREFETCH(p) ((void)(p))
#  define RENDERCACHE__PREFETCH_WRITE(p) ((void)(p))
#endif

/* Small functions that loops call and must inline to vectorise. */
#if defined(__GNUC__) || defined(__clang__)
#  define RENDERCACHE__INLINE __inline__ __attribute__((always_inline))
#elif defined(__cplusplus) || (defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L)
#  define RENDERCACHE__INLINE inline
#else
#  define RENDERCACHE__INLINE
#endif

/* Rare work that a hot loop calls: kept out of the loop's code, so that
   the loop's registers and instructions stay those of its common case. */
#if defined(__GNUC__) || defined(__clang__)
#  define RENDERCACHE__NOINLINE __attribute__((noinline))
#else
#  define RENDERCACHE__NOINLINE
#endif

/* Outputs that alias nothing, so that loops writing them vectorise. */
#if defined(__cplusplus) || !defined(__STDC_VERSION__) || __STDC_VERSION__ < 199901L
#  define RENDERCACHE__RESTRICT __restrict
#else
#  define RENDERCACHE__RESTRICT restrict
#endif

/* ======================================================================
   2. small math
   ---------------------------------------------------------------------- */
static int rendercache__iabs(int v) { return v < 0 ? -v : v; }
static RENDERCACHE__INLINE float rendercache__minf(float a, float b) { return a < b ? a : b; }
static RENDERCACHE__INLINE float rendercache__maxf(float a, float b) { return a > b ? a : b; }
/* x clamped to the finite floats: a weighted mean of finite colours that
   rounds past FLT_MAX stays finite (NaN passes, and cannot arise there). */
static float rendercache__finitef(float x) { return x < -FLT_MAX ? -FLT_MAX : x > FLT_MAX ? FLT_MAX : x; }
static int rendercache__finite3(const float *p) { return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]); }

static double rendercache__dot3d(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void rendercache__cross3d(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* Normalises v in place; returns 0 when v is zero or not finite. */
static int rendercache__normalize3d(double v[3])
{
    double l = sqrt(rendercache__dot3d(v, v));
    if (!(l > 0.0) || !isfinite(l)) return 0;
    v[0] /= l; v[1] /= l; v[2] /= l;
    return 1;
}

/* y = m x for a 3x4 row-major affine matrix (w = 1). */
static void rendercache__affine(const float m[12], const float x[3], float y[3])
{
    y[0] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + m[3];
    y[1] = m[4] * x[0] + m[5] * x[1] + m[6] * x[2] + m[7];
    y[2] = m[8] * x[0] + m[9] * x[1] + m[10] * x[2] + m[11];
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
typedef struct rendercache__crc { uint32_t table[256]; uint32_t value; } rendercache__crc;

static void rendercache__crc_init(rendercache__crc *c)
{
    uint32_t i, k;
    for (i = 0; i < 256; i++) {
        uint32_t v = i;
        for (k = 0; k < 8; k++) v = (v & 1u) ? 0xEDB88320u ^ (v >> 1) : v >> 1;
        c->table[i] = v;
    }
    c->value = 0xFFFFFFFFu;
}
static void rendercache__crc_add(rendercache__crc *c, const void *bytes, size_t n)
{
    const unsigned char *p = (const unsigned char *)bytes;
    uint32_t v = c->value;
    while (n--) v = c->table[(v ^ *p++) & 0xFFu] ^ (v >> 8);
    c->value = v;
}
static uint32_t rendercache__crc_final(const rendercache__crc *c) { return c->value ^ 0xFFFFFFFFu; }

typedef struct rendercache__writer {
    rendercache_write_fn write;
    void *user;
    rendercache__crc crc;
    int failed;        /* a write callback failed: RENDERCACHE_ERROR_IO */
} rendercache__writer;

static void rendercache__put(rendercache__writer *w, const void *bytes, size_t n)
{
    if (w->failed || n == 0) return;
    rendercache__crc_add(&w->crc, bytes, n);
    if (w->write(w->user, bytes, n) != 0) w->failed = 1;
}
static void rendercache__put_u32(rendercache__writer *w, uint32_t v)
{
    unsigned char b[4];
    b[0] = (unsigned char)v; b[1] = (unsigned char)(v >> 8);
    b[2] = (unsigned char)(v >> 16); b[3] = (unsigned char)(v >> 24);
    rendercache__put(w, b, 4);
}
static void rendercache__put_u64(rendercache__writer *w, uint64_t v)
{
    rendercache__put_u32(w, (uint32_t)v);
    rendercache__put_u32(w, (uint32_t)(v >> 32));
}
static void rendercache__put_f32(rendercache__writer *w, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    rendercache__put_u32(w, v);
}
static void rendercache__put_f32_array(rendercache__writer *w, const float *f, size_t n)
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
        rendercache__put(w, buf, 4 * m);
        i += m;
    }
}
static void rendercache__put_u32_array(rendercache__writer *w, const uint32_t *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) rendercache__put_u32(w, v[i]);
}

typedef struct rendercache__reader {
    rendercache_read_fn read;
    void *user;
    rendercache__crc crc;
    uint64_t remaining;  /* payload bytes not yet read, from the header */
    int failed;          /* short read or a size past the payload: corrupt */
} rendercache__reader;

static void rendercache__get(rendercache__reader *r, void *bytes, size_t n)
{
    if (r->failed) { memset(bytes, 0, n); return; }
    if (n > r->remaining || r->read(r->user, bytes, n) != 0) {
        r->failed = 1;
        memset(bytes, 0, n);
        return;
    }
    r->remaining -= n;
    rendercache__crc_add(&r->crc, bytes, n);
}
static uint32_t rendercache__get_u32(rendercache__reader *r)
{
    unsigned char b[4];
    rendercache__get(r, b, 4);
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
}
static uint64_t rendercache__get_u64(rendercache__reader *r)
{
    uint64_t lo = rendercache__get_u32(r);
    return lo | ((uint64_t)rendercache__get_u32(r) << 32);
}
static float rendercache__get_f32(rendercache__reader *r)
{
    uint32_t v = rendercache__get_u32(r);
    float f;
    memcpy(&f, &v, 4);
    return f;
}
/* True when count items of item_bytes each can still be in the payload:
   call before allocating anything sized by a count read from the input. */
static int rendercache__can_hold(rendercache__reader *r, uint64_t count, uint64_t item_bytes)
{
    if (item_bytes && count > r->remaining / item_bytes) { r->failed = 1; return 0; }
    return !r->failed;
}

/* Memory-buffer streams behind the public save_to_memory/load_from_memory. */
typedef struct rendercache__membuf {
    unsigned char *data;
    size_t size, capacity, pos;
    const rendercache_allocator *a;
} rendercache__membuf;

static int rendercache__membuf_write(void *user, const void *bytes, size_t n)
{
    rendercache__membuf *m = (rendercache__membuf *)user;
    if (n > m->capacity - m->size) {
        size_t cap = m->capacity ? m->capacity : 4096;
        unsigned char *p;
        while (cap - m->size < n) {
            if (cap > SIZE_MAX / 2) return -1;
            cap *= 2;
        }
        p = (unsigned char *)rendercache__alloc(m->a, cap);
        if (!p) return -1;
        if (m->size) memcpy(p, m->data, m->size);
        rendercache__free(m->a, m->data);
        m->data = p;
        m->capacity = cap;
    }
    memcpy(m->data + m->size, bytes, n);
    m->size += n;
    return 0;
}

static int rendercache__membuf_read(void *user, void *bytes, size_t n)
{
    rendercache__membuf *m = (rendercache__membuf *)user;
    if (n > m->size - m->pos) return -1;
    memcpy(bytes, m->data + m->pos, n);
    m->pos += n;
    return 0;
}

/* ======================================================================
   6. Shirley-Chiu concentric map (Shirley and Chiu 1997)
   Square [0,1]^2 -> unit disk -> hemisphere around +z, preserving area: equal
   squares map to equal solid angles. The inverse maps a direction back to the
   square.
   ---------------------------------------------------------------------- */
#define RENDERCACHE__PI 3.14159265358979323846

static void rendercache__square_to_disk(float u, float v, float *dx, float *dy)
{
    float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f, r, phi;
    if (a == 0.0f && b == 0.0f) { *dx = *dy = 0.0f; return; }
    if (a * a > b * b) { r = a; phi = (float)(RENDERCACHE__PI / 4) * (b / a); }
    else { r = b; phi = (float)(RENDERCACHE__PI / 2) - (float)(RENDERCACHE__PI / 4) * (a / b); }
    *dx = r * cosf(phi);
    *dy = r * sinf(phi);
}

static void rendercache__disk_to_square(float dx, float dy, float *u, float *v)
{
    float r = sqrtf(dx * dx + dy * dy), phi = atan2f(dy, dx), a, b;
    if (phi < (float)(-RENDERCACHE__PI / 4)) phi += (float)(2 * RENDERCACHE__PI); /* phi in [-pi/4, 7pi/4) */
    if (phi < (float)(RENDERCACHE__PI / 4)) { a = r; b = phi * a / (float)(RENDERCACHE__PI / 4); }
    else if (phi < (float)(3 * RENDERCACHE__PI / 4)) { b = r; a = -(phi - (float)(RENDERCACHE__PI / 2)) * b / (float)(RENDERCACHE__PI / 4); }
    else if (phi < (float)(5 * RENDERCACHE__PI / 4)) { a = -r; b = (phi - (float)RENDERCACHE__PI) * a / (float)(RENDERCACHE__PI / 4); }
    else { b = -r; a = -(phi - (float)(3 * RENDERCACHE__PI / 2)) * b / (float)(RENDERCACHE__PI / 4); }
    *u = 0.5f * (a + 1.0f);
    *v = 0.5f * (b + 1.0f);
}

/* Square -> hemisphere (z >= 0): the disk point lifted by z = 1 - r^2.
   (This header has no vec3 type: the direction is written to d[3].) */
static void rendercache__square_to_hemisphere(float u, float v, float d[3])
{
    float dx, dy, r2, s;
    rendercache__square_to_disk(u, v, &dx, &dy);
    r2 = dx * dx + dy * dy;
    s = sqrtf(2.0f - r2 > 0.0f ? 2.0f - r2 : 0.0f);
    d[0] = dx * s;
    d[1] = dy * s;
    d[2] = 1.0f - r2;
}

/* Hemisphere -> square for a unit direction d with d[2] >= 0. */
static void rendercache__hemisphere_to_square(const float d[3], float *u, float *v)
{
    float r2 = 1.0f - d[2] > 0.0f ? 1.0f - d[2] : 0.0f, s = sqrtf(2.0f - r2 > 0.0f ? 2.0f - r2 : 0.0f);
    if (s > 0.0f) rendercache__disk_to_square(d[0] / s, d[1] / s, u, v);
    else rendercache__disk_to_square(0.0f, 0.0f, u, v);
}

/* ======================================================================
   7. jobs: the caller's parallel_for, or a serial loop
   ---------------------------------------------------------------------- */
static void rendercache__run_jobs(void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t), void *user,
                                  rendercache_job_fn job, void *ctx, uint32_t count)
{
    uint32_t i;
    if (count == 0) return;
    if (parallel_for) { parallel_for(user, job, ctx, count); return; }
    for (i = 0; i < count; i++) job(ctx, i);
}

/* ======================================================================
   8. cameras: world <-> image mapping shared by the render cache and the
   range-image warps. A view is a validated camera with its orthonormal
   basis; every mapping goes through camera space (right, up, forward
   components), so a camera kind is a case in view_to_plane and
   view_from_pixel (and a fast loop in view_row_dirs).
   ---------------------------------------------------------------------- */
#define RENDERCACHE__NONE 0xFFFFFFFFu        /* no point / no element */
#define RENDERCACHE__FAR RENDERCACHE_FAR_DEPTH   /* distance of background points, "at infinity" */
#define RENDERCACHE__FAR2 1e36f              /* its square: depths are compared squared */
#define RENDERCACHE__MAX_PIXELS (1u << 28)
#define RENDERCACHE__MAX_CAPACITY (1u << 31)
#define RENDERCACHE__MAX_OBJECTS (1u << 24)
#define RENDERCACHE__MAX_LATENCY 64u

typedef struct rendercache__view {
    rendercache_camera_kind kind;
    float eye[3];
    float axis[3][3];        /* rows: right, up, forward; orthonormal */
    float focal;             /* perspective: pixels per unit of tangent */
    float cx, cy;            /* image centre in pixels */
    float radius;            /* fish-eye: radius of the 180-degree circle in pixels */
    float half_width;        /* sphere: width of one hemisphere's half of the image */
    uint32_t width, height;
} rendercache__view;

/* Fish-eye rays without library calls: for a pixel at distance r (in units
   of the circle's radius) from the centre, the angle to the axis is
   theta = r pi/2, and sin(theta)/r and cos(theta) are even functions of r,
   so polynomials in s = r^2 (Taylor series of sin(a r)/r and cos(a r),
   a = pi/2, to s^6: error below 1e-8 for r <= 1). The loops that turn pixels
   into rays then vectorise. */
static const float rendercache__fish_sin[7] = { 1.570796327e+00f, -6.459640975e-01f, 7.969262625e-02f,
                                                -4.681754135e-03f, 1.604411848e-04f, -3.598843235e-06f,
                                                5.692172922e-08f };
static const float rendercache__fish_cos[7] = { 1.000000000e+00f, -1.233700550e+00f, 2.536695079e-01f,
                                                -2.086348076e-02f, 9.192602748e-04f, -2.520204237e-05f,
                                                4.710874779e-07f };

static float rendercache__poly6(const float c[7], float s)
{
    return c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * (c[5] + s * c[6])))));
}

/* Validates a camera and builds its view; returns 0 on bad input. */
static int rendercache__view_init(rendercache__view *v, const rendercache_camera *c)
{
    double f[3], u[3], r[3], half;
    int k;
    if (!c) return 0;
    if (c->kind != RENDERCACHE_CAMERA_PERSPECTIVE && c->kind != RENDERCACHE_CAMERA_FISHEYE &&
        c->kind != RENDERCACHE_CAMERA_SPHERE)
        return 0;
    if (!rendercache__finite3(c->eye) || !rendercache__finite3(c->look_at) || !rendercache__finite3(c->up)) return 0;
    if (c->width == 0 || c->height == 0 || (uint64_t)c->width * c->height > RENDERCACHE__MAX_PIXELS) return 0;
    if (c->kind == RENDERCACHE_CAMERA_PERSPECTIVE && !(c->vfov_degrees > 0.0f && c->vfov_degrees < 180.0f)) return 0;
    if (c->kind == RENDERCACHE_CAMERA_SPHERE && c->width < 2) return 0;
    for (k = 0; k < 3; k++) {
        f[k] = (double)c->look_at[k] - (double)c->eye[k];
        u[k] = c->up[k];
    }
    if (!rendercache__normalize3d(f)) return 0;
    rendercache__cross3d(f, u, r);
    if (!rendercache__normalize3d(r)) return 0;     /* up parallel to the view direction */
    rendercache__cross3d(r, f, u);
    v->kind = c->kind;
    for (k = 0; k < 3; k++) {
        v->eye[k] = c->eye[k];
        v->axis[0][k] = (float)r[k];
        v->axis[1][k] = (float)u[k];
        v->axis[2][k] = (float)f[k];
    }
    v->width = c->width;
    v->height = c->height;
    v->cx = 0.5f * (float)c->width;
    v->cy = 0.5f * (float)c->height;
    v->radius = 0.5f * (float)(c->width < c->height ? c->width : c->height);
    v->half_width = 0.5f * (float)c->width;
    v->focal = 1.0f;
    if (c->kind == RENDERCACHE_CAMERA_PERSPECTIVE) {
        half = 0.5 * (double)c->vfov_degrees * RENDERCACHE__PI / 180.0;
        v->focal = (float)(0.5 * (double)c->height / tan(half));
    }
    return 1;
}

/* Camera-space vector c (a point, or a direction for points at infinity) to
   continuous image-plane coordinates, which may lie outside the image.
   Returns 0 when c has no image (behind a perspective camera or a fish-eye's
   hemisphere, zero, NaN). */
static int rendercache__view_to_plane(const rendercache__view *v, const float c[3], float *px, float *py)
{
    float x, y, l, d[3], u, w;
    switch (v->kind) {
    case RENDERCACHE_CAMERA_FISHEYE:
        l = sqrtf(c[0] * c[0] + c[1] * c[1]);
        w = atan2f(l, c[2]);   /* angle to the view axis */
        if (!(w <= (float)(RENDERCACHE__PI / 2)) || (l == 0.0f && !(c[2] > 0.0f))) return 0;
        w *= v->radius / (float)(RENDERCACHE__PI / 2);   /* distance from the centre in pixels */
        x = v->cx + (l > 0.0f ? w * c[0] / l : 0.0f);
        y = v->cy - (l > 0.0f ? w * c[1] / l : 0.0f);
        break;
    case RENDERCACHE_CAMERA_SPHERE:
        l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        if (!(l > 0.0f) || !(l < FLT_MAX)) return 0;
        d[0] = c[0] / l; d[1] = c[1] / l; d[2] = c[2] / l;
        if (d[2] >= 0.0f) {
            rendercache__hemisphere_to_square(d, &u, &w);
            x = u * v->half_width;
        } else {   /* the back half: turned around the up axis */
            d[0] = -d[0]; d[2] = -d[2];
            rendercache__hemisphere_to_square(d, &u, &w);
            x = v->half_width + u * v->half_width;
        }
        y = (1.0f - w) * (float)v->height;
        break;
    case RENDERCACHE_CAMERA_PERSPECTIVE:
    default:
        if (!(c[2] > 0.0f)) return 0;
        x = v->cx + v->focal * c[0] / c[2];
        y = v->cy - v->focal * c[1] / c[2];
        break;
    }
    *px = x;
    *py = y;
    return 1;
}

/* As view_to_plane, and returns 0 also when the point does not land inside
   the image. */
static int rendercache__view_to_pixel(const rendercache__view *v, const float c[3], float *px, float *py)
{
    float x, y;
    if (!rendercache__view_to_plane(v, c, &x, &y)) return 0;
    if (!(x >= 0.0f && x < (float)v->width && y >= 0.0f && y < (float)v->height)) return 0;
    *px = x;
    *py = y;
    return 1;
}

/* Image point to a unit camera-space direction; returns 0 when the point has
   no ray (outside a fish-eye's circle). */
static int rendercache__view_from_pixel(const rendercache__view *v, float px, float py, float c[3])
{
    float l, s, p, u, w;
    switch (v->kind) {
    case RENDERCACHE_CAMERA_FISHEYE:
        u = (px - v->cx) / v->radius;
        w = (py - v->cy) / v->radius;
        s = u * u + w * w;
        if (!(s <= 1.0f)) return 0;
        p = rendercache__poly6(rendercache__fish_sin, s);   /* sin(theta) / r */
        c[0] = u * p;
        c[1] = -w * p;
        c[2] = rendercache__poly6(rendercache__fish_cos, s);
        break;
    case RENDERCACHE_CAMERA_SPHERE:
        w = 1.0f - py / (float)v->height;
        if (px < v->half_width) {
            rendercache__square_to_hemisphere(px / v->half_width, w, c);
        } else {
            rendercache__square_to_hemisphere((px - v->half_width) / v->half_width, w, c);
            c[0] = -c[0];
            c[2] = -c[2];
        }
        break;
    case RENDERCACHE_CAMERA_PERSPECTIVE:
    default:
        c[0] = (px - v->cx) / v->focal;
        c[1] = (v->cy - py) / v->focal;
        c[2] = 1.0f;
        break;
    }
    l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    c[0] /= l; c[1] /= l; c[2] /= l;
    return 1;
}

/* Whether pixel (x, y) has a ray: all but the corners outside a fish-eye's circle. */
static int rendercache__view_has_ray(const rendercache__view *v, uint32_t x, uint32_t y)
{
    float u, w;
    if (v->kind != RENDERCACHE_CAMERA_FISHEYE) return 1;
    u = ((float)x + 0.5f - v->cx) / v->radius;
    w = ((float)y + 0.5f - v->cy) / v->radius;
    return u * u + w * w <= 1.0f;
}

/* Unit camera-space directions of the pixels [x0, x0 + n) of row y (centres),
   as three arrays; ok[i] = 0 where a pixel has no ray (its direction is
   then 0). The perspective and fish-eye loops vectorise. */
static void rendercache__view_row_dirs(const rendercache__view *v, uint32_t y, uint32_t x0, uint32_t n, float *dx,
                                       float *dy, float *dz, unsigned char *ok)
{
    const float py = (float)y + 0.5f;
    uint32_t i;
    if (v->kind == RENDERCACHE_CAMERA_PERSPECTIVE) {
        const float inv_f = 1.0f / v->focal, cy = (v->cy - py) * inv_f, cy2 = 1.0f + cy * cy;
        for (i = 0; i < n; i++) {
            float cx = ((float)(x0 + i) + 0.5f - v->cx) * inv_f, inv = 1.0f / sqrtf(cx * cx + cy2);
            dx[i] = cx * inv;
            dy[i] = cy * inv;
            dz[i] = inv;
            ok[i] = 1;
        }
    } else if (v->kind == RENDERCACHE_CAMERA_FISHEYE) {
        const float inv_r = 1.0f / v->radius, w = (py - v->cy) * inv_r, w2 = w * w;
        const float *sc = rendercache__fish_sin, *cc = rendercache__fish_cos;
        for (i = 0; i < n; i++) {
            float u = ((float)(x0 + i) + 0.5f - v->cx) * inv_r, s = u * u + w2, inside = s <= 1.0f ? 1.0f : 0.0f;
            float p = sc[0] + s * (sc[1] + s * (sc[2] + s * (sc[3] + s * (sc[4] + s * (sc[5] + s * sc[6])))));
            float q = cc[0] + s * (cc[1] + s * (cc[2] + s * (cc[3] + s * (cc[4] + s * (cc[5] + s * cc[6])))));
            dx[i] = inside * u * p;
            dy[i] = -inside * w * p;
            dz[i] = inside * q;
            ok[i] = (unsigned char)(s <= 1.0f);
        }
    } else {
        for (i = 0; i < n; i++) {
            float c[3];
            ok[i] = (unsigned char)rendercache__view_from_pixel(v, (float)(x0 + i) + 0.5f, py, c);
            dx[i] = c[0];
            dy[i] = c[1];
            dz[i] = c[2];
        }
    }
}

/* World vector to camera space (rotation only). */
static void rendercache__view_rotate(const rendercache__view *v, const float w[3], float c[3])
{
    int k;
    for (k = 0; k < 3; k++) c[k] = v->axis[k][0] * w[0] + v->axis[k][1] * w[1] + v->axis[k][2] * w[2];
}

/* The primary ray direction (world, unit) through image point (px, py);
   returns 0 when the point has no ray. */
static int rendercache__view_ray(const rendercache__view *v, float px, float py, float dir[3])
{
    float c[3], l;
    int k;
    if (!rendercache__view_from_pixel(v, px, py, c)) { dir[0] = dir[1] = dir[2] = 0.0f; return 0; }
    for (k = 0; k < 3; k++) dir[k] = c[0] * v->axis[0][k] + c[1] * v->axis[1][k] + c[2] * v->axis[2][k];
    l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    dir[0] /= l; dir[1] /= l; dir[2] /= l;
    return 1;
}

/* Object-to-camera matrix: the view's [R | -R eye] times the object's
   object-to-world matrix m, composed in double. */
static void rendercache__view_compose(const rendercache__view *v, const float m[12], float out[12])
{
    int i, j;
    for (i = 0; i < 3; i++) {
        const float *r = v->axis[i];
        for (j = 0; j < 3; j++)
            out[4 * i + j] = (float)((double)r[0] * m[j] + (double)r[1] * m[4 + j] + (double)r[2] * m[8 + j]);
        out[4 * i + 3] = (float)((double)r[0] * ((double)m[3] - v->eye[0]) +
                                 (double)r[1] * ((double)m[7] - v->eye[1]) +
                                 (double)r[2] * ((double)m[11] - v->eye[2]));
    }
}

/* ======================================================================
   9. splat: many elements (cache points, range-image pixels) into one
   z-buffer (the reprojection and z-buffer step of Walter et al. 1999),
   keeping per pixel the nearest element, its depth and, for warps, a
   payload of four floats (colour and one more value) copied as it wins, so
   that nothing has to be gathered from the elements afterwards. The render
   cache keeps keys only (a test without a branch, see zbuffer_keys) and
   gathers the colours of the winners, about half of its points, in the
   depth cull.
   Parallel and deterministic: when the caller gives parallel_for, the
   elements are split into RENDERCACHE__SPLAT_JOBS ranges, each z-buffered
   into its own z-buffer, which the warps' extraction pass merges as it
   reads them (rendercache__splat_least); a splat of keys only in chunks
   (the render cache) splits the chunks into RENDERCACHE__SHARED_JOBS
   ranges that share one z-buffer, each job owning the pixels its chunks
   mostly land in (s->own): a job z-tests the elements that land in its
   own pixels with a plain minimum and defers the others to their owner,
   which z-tests them after every job has finished (a barrier: the end of
   one parallel_for), so no two jobs ever touch one key at the same time
   and no test needs a locked instruction (an atomic minimum cost 60% more
   time in the z-test on 2 threads than on 1). The deferred elements wait
   in fixed buffers; a job whose buffer for some owner could not hold
   another batch stops there and goes on in the next round, after the
   owners emptied them. The winner of a pixel is the least (depth, element
   index) in every case, so the result does not depend on the split, on
   the owners or on the thread count. The render cache's depth cull reads
   the keys themselves (no merged copy of depths and indices) and clears
   them tile by tile as it goes, so the next splat needs no clearing pass.
   (Sorting the elements into image bands first, as the tiled cache of
   Walter et al. 2002 does, let any number of threads share the z-buffer
   but cost three times as much memory traffic here.) The render cache
   keeps its points nearly in image order instead (its re-sort, section
   12) and runs them in chunks, band of the image by band (a chunk
   function), so that the z-tests of a band land in keys that stay in
   cache.
   ---------------------------------------------------------------------- */
#define RENDERCACHE__SPLAT_JOBS 2u   /* partial z-buffers when running in parallel */
#define RENDERCACHE__SHARED_JOBS 8u  /* jobs of a splat into one shared z-buffer (owned pixels) */

/* The re-sort's jobs take ranges through an atomic counter when the
   compiler has the GNU atomic builtins (else each job takes its share). */
#if defined(__GNUC__) || defined(__clang__)
#  define RENDERCACHE__ATOMICS 1
#else
#  define RENDERCACHE__ATOMICS 0
#endif
#define RENDERCACHE__BATCH 256u      /* elements per source call */
#define RENDERCACHE__TILE_ROWS 8u    /* image rows per tile job */
#define RENDERCACHE__KEY_AHEAD 64u   /* elements between a key's prefetch and its z-test (16, 32: slower;
                                        128 the same) */

/* Projects elements [begin, end): pix[i - begin] = y * width + x of the
   pixel it lands in, or RENDERCACHE__NONE; depth[...] its distance.
   Returns 0 when none landed (the batch is then skipped), else non-zero. */
typedef uint32_t (*rendercache__source_fn)(const void *src, uint32_t begin, uint32_t end, uint32_t *pix, float *depth);
/* Payload of elements [begin, end): 4 floats each, for those whose pix is
   not RENDERCACHE__NONE. */
typedef void (*rendercache__payload_fn)(const void *src, uint32_t begin, uint32_t end, const uint32_t *pix,
                                        float *payload);

/* An element may also cover many pixels (the foreground fill of a warp
   rasterises a quad per source pixel): a cover function z-buffers elements
   [begin, end) into job j's z-buffer itself (with rendercache__zbuffer_test)
   and returns how many landed in the image. */
struct rendercache__zbuffer;
typedef uint32_t (*rendercache__cover_fn)(const void *src, uint32_t job, uint32_t begin, uint32_t end,
                                          struct rendercache__zbuffer *zb, uint32_t width, uint32_t height);

/* One job's z-buffer: per pixel the key (depth bits << 32 | element; depths
   are non-negative, so their bits order as the values do, and one compare
   settles depth and then index) and the payload. One random access per test.
   Keys have one more entry, after the last pixel, where the z-test's
   prefetch of an element that misses the image points. */
typedef struct rendercache__zbuffer {
    uint64_t *key;
    float *payload;
} rendercache__zbuffer;
#define RENDERCACHE__EMPTY_KEY 0xFFFFFFFFFFFFFFFFull

typedef struct rendercache__splat {
    uint32_t width, height, pixel_count, tile_count;
    uint32_t jobs;           /* z-buffers allocated: 1, or SPLAT_JOBS with parallel_for */
    int shared;              /* keys only, in chunks, in parallel: SHARED_JOBS jobs share z-buffer 0, each
                                owning pixels [own[j], own[j + 1]) (rendercache__splat_share) */
    int clean;               /* z-buffer 0 holds only empty keys (its last user cleared it) */
    rendercache__zbuffer zb[RENDERCACHE__SPLAT_JOBS];
    uint32_t projected;      /* elements that landed in the image in the last run */
    uint32_t ran_jobs;       /* z-buffers the last run filled */
    uint32_t job_projected[RENDERCACHE__SHARED_JOBS];
    uint32_t own[RENDERCACHE__SHARED_JOBS + 1];
    /* the elements a job deferred to their owners, in blocks of DEFER_BLOCK: job j has blocks [j defer_blocks,
       (j + 1) defer_blocks) and took the first defer_used[j] of them in this round; block b holds defer_fill[b]
       elements (their keys in defer_key, their pixels in defer_pix, from b DEFER_BLOCK on) for defer_owner[b] */
    uint32_t defer_blocks;
    uint64_t *defer_key;
    uint32_t *defer_pix, *defer_owner, *defer_fill;
    uint32_t defer_used[RENDERCACHE__SHARED_JOBS];
    uint32_t next_chunk[RENDERCACHE__SHARED_JOBS];   /* where job j goes on in the next round: chunk, element */
    uint32_t next_element[RENDERCACHE__SHARED_JOBS];
    uint32_t rounds;         /* rounds of the last shared run (1 when no deferral buffer filled up) */
} rendercache__splat;

static void rendercache__splat_free(rendercache__splat *s, const rendercache_allocator *a)
{
    uint32_t j;
    for (j = 0; j < RENDERCACHE__SPLAT_JOBS; j++) {
        rendercache__free(a, s->zb[j].key);
        rendercache__free(a, s->zb[j].payload);
    }
    rendercache__free(a, s->defer_key);
    rendercache__free(a, s->defer_pix);
    rendercache__free(a, s->defer_owner);
    rendercache__free(a, s->defer_fill);
    memset(s, 0, sizeof *s);
}

/* Elements per block of a deferral buffer: a batch, so that a batch needs
   at most one new block per owner. */
#define RENDERCACHE__DEFER_BLOCK RENDERCACHE__BATCH

/* Makes a splat of one z-buffer shared by SHARED_JOBS jobs in parallel,
   job j owning pixels [own[j], own[j + 1]) (own[0] = 0, own[SHARED_JOBS]
   at least the pixel count, non-decreasing), each job deferring about
   elements to the others in a round (at least 2 SHARED_JOBS blocks).
   Returns 0, or -1 when out of memory. */
static int rendercache__splat_share(rendercache__splat *s, const uint32_t *own, uint32_t elements,
                                    const rendercache_allocator *a)
{
    size_t n;
    s->defer_blocks = elements / RENDERCACHE__DEFER_BLOCK;
    if (s->defer_blocks < 2 * RENDERCACHE__SHARED_JOBS) s->defer_blocks = 2 * RENDERCACHE__SHARED_JOBS;
    n = (size_t)RENDERCACHE__SHARED_JOBS * s->defer_blocks;
    memcpy(s->own, own, sizeof s->own);
    s->defer_key = (uint64_t *)rendercache__alloc_array(a, n * RENDERCACHE__DEFER_BLOCK, sizeof(uint64_t));
    s->defer_pix = (uint32_t *)rendercache__alloc_array(a, n * RENDERCACHE__DEFER_BLOCK, sizeof(uint32_t));
    s->defer_owner = (uint32_t *)rendercache__alloc_array(a, n, sizeof(uint32_t));
    s->defer_fill = (uint32_t *)rendercache__alloc_array(a, n, sizeof(uint32_t));
    s->shared = s->defer_key && s->defer_pix && s->defer_owner && s->defer_fill;
    return s->shared ? 0 : -1;
}

/* Allocates a splat for a width x height raster, run by jobs (1 or
   RENDERCACHE__SPLAT_JOBS) z-buffers, with payloads (warps) or without
   (the render cache). Returns 0, or -1 when out of memory. */
static int rendercache__splat_alloc(rendercache__splat *s, uint32_t width, uint32_t height, uint32_t jobs,
                                    int payload, const rendercache_allocator *a)
{
    uint32_t j;
    int failed = 0;
    memset(s, 0, sizeof *s);
    s->jobs = jobs;
    s->width = width;
    s->height = height;
    s->pixel_count = width * height;
    s->tile_count = (height + RENDERCACHE__TILE_ROWS - 1) / RENDERCACHE__TILE_ROWS;
    for (j = 0; j < jobs; j++) {
        s->zb[j].key = (uint64_t *)rendercache__alloc_array(a, (size_t)s->pixel_count + 1, sizeof(uint64_t));
        s->zb[j].payload = payload ? (float *)rendercache__alloc_array(a, s->pixel_count, 4 * sizeof(float)) : NULL;
        failed |= !s->zb[j].key || (payload && !s->zb[j].payload);
    }
    if (failed) rendercache__splat_free(s, a);
    return failed ? -1 : 0;
}

/* Elements [*begin, *end) of chunk c of a splat that runs its elements in
   chunks (rendercache__splat_run); chunks are numbered so that chunks of
   nearby numbers land in nearby pixels. */
typedef void (*rendercache__chunk_fn)(const void *src, uint32_t c, uint32_t *begin, uint32_t *end);

/* What a splat of keys also does with elements [begin, end) in job j,
   right after the source projected them, while they are in cache (the
   render cache's prediction counts them in the next camera's cells). */
typedef void (*rendercache__also_fn)(const void *also_src, uint32_t j, uint32_t begin, uint32_t end);

typedef struct rendercache__splat_job {
    rendercache__splat *s;
    rendercache__source_fn source;
    rendercache__chunk_fn chunk;       /* non-NULL: jobs split chunk_count chunks instead of the elements */
    uint32_t chunk_count;
    rendercache__payload_fn payload;   /* NULL: no payload */
    rendercache__cover_fn cover;       /* instead of source and payload */
    rendercache__also_fn also;         /* NULL: nothing more (keys only) */
    const void *src, *also_src;
    uint32_t element_count, jobs;
    int shared;                        /* the jobs share z-buffer 0 (s->shared, in parallel) */
} rendercache__splat_job;

/* Clears the keys of z-buffer 0 in the rows of tile (the last tile's also
   the key past the pixels). */
static void rendercache__splat_clear_tile(rendercache__splat *s, uint32_t tile)
{
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * s->width, p1 = p0 + RENDERCACHE__TILE_ROWS * s->width, p;
    if (p1 >= s->pixel_count) p1 = s->pixel_count + 1;
    for (p = p0; p < p1; p++) s->zb[0].key[p] = RENDERCACHE__EMPTY_KEY;
}

/* Job per tile: clears the shared z-buffer. */
static void rendercache__splat_clear(void *ctx, uint32_t tile)
{
    rendercache__splat_clear_tile(((const rendercache__splat_job *)ctx)->s, tile);
}

/* The squared distance a render cache key holds, FLT_MAX for the empty key. */
static RENDERCACHE__INLINE float rendercache__key_depth(uint64_t k)
{
    uint32_t bits = (uint32_t)(k >> 32);
    float d;
    memcpy(&d, &bits, sizeof d);
    return k == RENDERCACHE__EMPTY_KEY ? FLT_MAX : d;
}

static uint64_t rendercache__key(float depth, uint32_t element)
{
    uint32_t bits;
    memcpy(&bits, &depth, sizeof bits);
    return (uint64_t)bits << 32 | element;
}

/* The z-test of a cover function: element with depth (and payload, 4
   floats) against pixel p. */
static void rendercache__zbuffer_test(rendercache__zbuffer *zb, uint32_t p, float depth, uint32_t element,
                                      const float payload[4])
{
    uint64_t k = rendercache__key(depth, element);
    if (k < zb->key[p]) {
        zb->key[p] = k;
        memcpy(zb->payload + 4 * (size_t)p, payload, 4 * sizeof(float));
    }
}

/* The z-test of n elements (from element first on) without payload:
   without a branch on which of two elements in a pixel is nearer (a coin
   toss for a branch predictor). Elements that miss the image are skipped:
   they come in runs (a range's points outside the image at its last
   re-sort are its last chunk; a third of the points at 512x512), which a
   branch predicts. (Without the branch they went through the key past the
   last pixel, one chain of loads and stores through it: the projection
   took 3-5 % longer, bench_rendercache 512x512 on one thread.)
   The keys of the elements RENDERCACHE__KEY_AHEAD further
   on are asked for ahead of time: the points inserted since their range's
   last re-sort, a third of them, land anywhere in the image, and the keys
   of a large image do not stay in cache (perf at 512x512: -20 % of the
   z-test's time). Returns how many landed. */
static uint32_t rendercache__zbuffer_keys(uint64_t *key, uint32_t sink, const uint32_t *pix, const float *depth,
                                          uint32_t first, uint32_t n)
{
    uint32_t i, landed = 0;
    for (i = 0; i < n; i++) {
        uint32_t p = pix[i];
        uint64_t k = rendercache__key(depth[i], first + i), old;
        if (i + RENDERCACHE__KEY_AHEAD < n) {
            const uint32_t q = pix[i + RENDERCACHE__KEY_AHEAD];
            RENDERCACHE__PREFETCH_WRITE(&key[q == RENDERCACHE__NONE ? sink : q]);
        }
        if (p == RENDERCACHE__NONE) continue;
        old = key[p];
        key[p] = k < old ? k : old;
        landed++;
    }
    return landed;
}

/* Z-buffers the keys of elements [begin, end) (no payload) into key, in
   job j; returns how many landed. */
static uint32_t rendercache__splat_keys(const rendercache__splat_job *job, uint32_t j, uint64_t *key, uint32_t begin,
                                        uint32_t end)
{
    uint32_t pix[RENDERCACHE__BATCH], b, projected = 0;
    float d[RENDERCACHE__BATCH];
    for (b = begin; b < end; b += RENDERCACHE__BATCH) {
        uint32_t n = end - b < RENDERCACHE__BATCH ? end - b : RENDERCACHE__BATCH, landed = job->source(job->src, b, b + n, pix, d);
        if (job->also) job->also(job->also_src, j, b, b + n);
        if (!landed) continue;   /* nothing landed */
        projected += rendercache__zbuffer_keys(key, job->s->pixel_count, pix, d, b, n);
    }
    return projected;
}

/* The job that owns pixel p of a shared splat. */
static RENDERCACHE__INLINE uint32_t rendercache__splat_owner(const rendercache__splat *s, uint32_t p)
{
    uint32_t t, owner = 0;
    for (t = 1; t < RENDERCACHE__SHARED_JOBS; t++) owner += p >= s->own[t];
    return owner;
}

/* Z-buffers the keys of elements [begin, end) in job j of a shared splat:
   those that land in j's own pixels at once, the others into blocks for
   their owners (open[t]: the block being filled for owner t, or NONE).
   Stops before a batch that the blocks left might not hold; returns where
   it stopped (end when it did not), and adds how many landed to
   *projected. */
static uint32_t rendercache__splat_keys_owned(const rendercache__splat_job *job, uint32_t j, uint32_t begin, uint32_t end,
                                              uint32_t *open, uint32_t *projected)
{
    rendercache__splat *s = job->s;
    uint64_t *key = s->zb[0].key;
    const uint32_t lo = s->own[j], size = s->own[j + 1] - s->own[j];
    uint32_t pix[RENDERCACHE__BATCH], b, i;
    float d[RENDERCACHE__BATCH];
    for (b = begin; b < end; b += RENDERCACHE__BATCH) {
        uint32_t n = end - b < RENDERCACHE__BATCH ? end - b : RENDERCACHE__BATCH, landed;
        if (s->defer_blocks - s->defer_used[j] < RENDERCACHE__SHARED_JOBS) return b;   /* one new block per owner */
        landed = job->source(job->src, b, b + n, pix, d);
        if (job->also) job->also(job->also_src, j, b, b + n);
        if (!landed) continue;   /* nothing landed */
        for (i = 0; i < n; i++) {
            const uint32_t p = pix[i];
            const uint64_t k = rendercache__key(d[i], b + i);
            if (i + RENDERCACHE__KEY_AHEAD < n) {   /* (as zbuffer_keys does; only the job's own keys) */
                const uint32_t q = pix[i + RENDERCACHE__KEY_AHEAD];
                RENDERCACHE__PREFETCH_WRITE(&key[q - lo < size ? q : lo]);
            }
            if (p - lo < size) {   /* most elements: the chunks of a job land mostly in its own pixels */
                const uint64_t old = key[p];
                key[p] = k < old ? k : old;
            } else if (p != RENDERCACHE__NONE) {
                const uint32_t owner = rendercache__splat_owner(s, p);
                uint32_t block = open[owner];
                size_t at;
                if (block == RENDERCACHE__NONE || s->defer_fill[block] == RENDERCACHE__DEFER_BLOCK) {
                    block = open[owner] = j * s->defer_blocks + s->defer_used[j]++;
                    s->defer_owner[block] = owner;
                    s->defer_fill[block] = 0;
                }
                at = (size_t)block * RENDERCACHE__DEFER_BLOCK + s->defer_fill[block]++;
                s->defer_key[at] = k;
                s->defer_pix[at] = p;
            }
            *projected += p != RENDERCACHE__NONE;
        }
    }
    return end;
}

/* Job j of a round of a shared splat: goes on with its chunks from where
   it stopped in the last round. */
static void rendercache__splat_owned(void *ctx, uint32_t j)
{
    const rendercache__splat_job *job = (const rendercache__splat_job *)ctx;
    rendercache__splat *s = job->s;
    const uint32_t end = (uint32_t)((uint64_t)job->chunk_count * (j + 1) / job->jobs);
    uint32_t open[RENDERCACHE__SHARED_JOBS], c, projected = 0;
    for (c = 0; c < RENDERCACHE__SHARED_JOBS; c++) open[c] = RENDERCACHE__NONE;
    s->defer_used[j] = 0;   /* (the owners emptied the last round's blocks) */
    for (c = s->next_chunk[j]; c < end; c++) {
        uint32_t e0, e1, stop;
        job->chunk(job->src, c, &e0, &e1);
        if (s->next_element[j] != RENDERCACHE__NONE) e0 = s->next_element[j];
        s->next_element[j] = RENDERCACHE__NONE;
        stop = rendercache__splat_keys_owned(job, j, e0, e1, open, &projected);
        if (stop < e1) {
            s->next_element[j] = stop;
            break;
        }
    }
    s->next_chunk[j] = c;
    s->job_projected[j] += projected;
}

/* Job t after a round of a shared splat: z-tests the elements the jobs
   deferred to it in the round. */
static void rendercache__splat_drain(void *ctx, uint32_t t)
{
    const rendercache__splat *s = ((const rendercache__splat_job *)ctx)->s;
    uint64_t *key = s->zb[0].key;
    uint32_t j, b, i;
    for (j = 0; j < RENDERCACHE__SHARED_JOBS; j++)
        for (b = j * s->defer_blocks; b < j * s->defer_blocks + s->defer_used[j]; b++) {
            const size_t at = (size_t)b * RENDERCACHE__DEFER_BLOCK;
            if (s->defer_owner[b] != t) continue;
            for (i = 0; i < s->defer_fill[b]; i++) {
                const uint32_t p = s->defer_pix[at + i];
                const uint64_t k = s->defer_key[at + i], old = key[p];
                key[p] = k < old ? k : old;
            }
        }
}

/* Job j: z-buffers its range of elements (or of chunks) into its own
   z-buffer, or with the others into the shared one. */
static void rendercache__splat_range(void *ctx, uint32_t j)
{
    const rendercache__splat_job *job = (const rendercache__splat_job *)ctx;
    rendercache__splat *s = job->s;
    uint64_t *key = s->zb[j].key;
    float *payload = s->zb[j].payload;
    uint32_t pix[RENDERCACHE__BATCH], begin, end, b, i, projected = 0;
    float d[RENDERCACHE__BATCH], pay[4 * RENDERCACHE__BATCH];
    const uint32_t count = job->chunk ? job->chunk_count : job->element_count;
    begin = (uint32_t)((uint64_t)count * j / job->jobs);
    end = (uint32_t)((uint64_t)count * (j + 1) / job->jobs);
    if (j > 0 || !s->clean)
        for (i = 0; i <= s->pixel_count; i++) key[i] = RENDERCACHE__EMPTY_KEY;
    if (job->chunk) {   /* keys only */
        for (i = begin; i < end; i++) {
            uint32_t e0, e1;
            job->chunk(job->src, i, &e0, &e1);
            projected += rendercache__splat_keys(job, j, key, e0, e1);
        }
        s->job_projected[j] = projected;
        return;
    }
    if (job->cover) {
        s->job_projected[j] = job->cover(job->src, j, begin, end, &s->zb[j], s->width, s->height);
        return;
    }
    if (!job->payload) {
        s->job_projected[j] = rendercache__splat_keys(job, j, key, begin, end);
        return;
    }
    for (b = begin; b < end; b += RENDERCACHE__BATCH) {
        uint32_t n = end - b < RENDERCACHE__BATCH ? end - b : RENDERCACHE__BATCH;
        if (!job->source(job->src, b, b + n, pix, d)) continue;   /* nothing landed */
        job->payload(job->src, b, b + n, pix, pay);
        for (i = 0; i < n; i++) {
            uint32_t p = pix[i];
            uint64_t k;
            if (p == RENDERCACHE__NONE) continue;
            projected++;
            k = rendercache__key(d[i], b + i);
            if (k < key[p]) {
                key[p] = k;
                memcpy(payload + 4 * (size_t)p, pay + 4 * i, 4 * sizeof(float));
            }
        }
    }
    s->job_projected[j] = projected;
}

/* The least key of pixel p over the z-buffers of the last run, and the
   payload of the z-buffer that holds it (keys are unique but for the empty
   one, so the split of the elements does not matter). */
static RENDERCACHE__INLINE uint64_t rendercache__splat_least(const rendercache__splat *s, uint32_t p, const float **payload)
{
    uint64_t k = s->zb[0].key[p];
    uint32_t j;
    *payload = s->zb[0].payload + 4 * (size_t)p;
    for (j = 1; j < s->ran_jobs; j++)
        if (s->zb[j].key[p] < k) {
            k = s->zb[j].key[p];
            *payload = s->zb[j].payload + 4 * (size_t)p;
        }
    return k;
}

static void rendercache__splat_execute(rendercache__splat_job *job,
                                       void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t), void *user)
{
    rendercache__splat *s = job->s;
    uint32_t j, left;
    job->shared = parallel_for && s->shared && job->chunk && !job->payload;
    job->jobs = job->shared ? RENDERCACHE__SHARED_JOBS : parallel_for ? s->jobs : 1u;
    if (job->shared) {
        if (!s->clean) rendercache__run_jobs(parallel_for, user, rendercache__splat_clear, job, s->tile_count);
        for (j = 0; j < job->jobs; j++) {
            s->next_chunk[j] = (uint32_t)((uint64_t)job->chunk_count * j / job->jobs);
            s->next_element[j] = RENDERCACHE__NONE;
            s->job_projected[j] = 0;
        }
        s->rounds = 0;
        do {   /* rounds until every job went through its chunks */
            rendercache__run_jobs(parallel_for, user, rendercache__splat_owned, job, job->jobs);
            rendercache__run_jobs(parallel_for, user, rendercache__splat_drain, job, job->jobs);
            s->rounds++;
            for (j = 0, left = 0; j < job->jobs; j++)
                left += s->next_chunk[j] < (uint32_t)((uint64_t)job->chunk_count * (j + 1) / job->jobs);
        } while (left);
    } else {
        rendercache__run_jobs(parallel_for, user, rendercache__splat_range, job, job->jobs);
    }
    s->ran_jobs = job->shared ? 1u : job->jobs;
    s->clean = 0;
    s->projected = 0;
    for (j = 0; j < job->jobs; j++) s->projected += s->job_projected[j];
}

/* Runs the splat over elements [0, count) into the z-buffers of s, or
   (chunk non-NULL, keys only) over chunk_count chunks of them, chunk by
   chunk (chunk gives each chunk's elements; the jobs split the chunks in
   order); the caller takes the least key of each pixel over the z-buffers
   of the run (s->ran_jobs; rendercache__splat_least) in a pass it makes
   anyway. A splat of keys only may also hand each batch to also (NULL:
   none), in its job j < RENDERCACHE__SHARED_JOBS. */
static void rendercache__splat_run(rendercache__splat *s, void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t),
                                   void *user, rendercache__source_fn source, rendercache__payload_fn payload,
                                   rendercache__chunk_fn chunk, uint32_t chunk_count, const void *src, uint32_t count,
                                   rendercache__also_fn also, const void *also_src)
{
    rendercache__splat_job job;
    memset(&job, 0, sizeof job);
    job.s = s;
    job.source = source;
    job.payload = payload;
    job.chunk = chunk;
    job.chunk_count = chunk_count;
    job.src = src;
    job.element_count = count;
    job.also = payload ? NULL : also;
    job.also_src = also_src;
    rendercache__splat_execute(&job, parallel_for, user);
}

/* The same with a cover function (payload always kept). */
static void rendercache__splat_run_cover(rendercache__splat *s,
                                         void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t), void *user,
                                         rendercache__cover_fn cover, const void *src, uint32_t count)
{
    rendercache__splat_job job;
    memset(&job, 0, sizeof job);
    job.s = s;
    job.cover = cover;
    job.src = src;
    job.element_count = count;
    rendercache__splat_execute(&job, parallel_for, user);
}

/* ======================================================================
   10. the cache object
   ---------------------------------------------------------------------- */
#define RENDERCACHE__FREE_SLOT 0xFFFFFFFEu   /* object id of an unused cache slot */
#define RENDERCACHE__LEVELS 1024u            /* priority levels of the threshold histogram */
#define RENDERCACHE__TILE_STATS 6u           /* visible, culled, interpolated, sparse, empty, scratch */
#define RENDERCACHE__GATHER_AHEAD 64u        /* pixels between a slot's prefetch and its read */
#define RENDERCACHE__CHANGE_BINS 64u         /* histogram of relative colour differences in [0, 2] */
#define RENDERCACHE__CELL_SHIFT 2u           /* predictive sampling: cells of 4 x 4 pixels, an occupancy
                                                image of 1/16 the resolution (WDG02) */
#define RENDERCACHE__CELL (1u << RENDERCACHE__CELL_SHIFT)
#define RENDERCACHE__CELL_FEW 4u             /* points in a cell below which it is a hole: a quarter covered */
#define RENDERCACHE__CELL_JOBS 8u            /* jobs of the occupancy count with parallel_for, each with its own
                                                bytes (1/16 byte per pixel each): fine enough that a thread
                                                the system holds back holds back little */
#define RENDERCACHE__CELL_SINKS 16u          /* bytes after the cells of each count that the points missing them
                                                take in turn (rendercache__count_cells) */
/* How far (pixels) a hole looks for the layers around it: the rows the
   cull of the next tile has written when the filling of a tile runs
   (rendercache__cull_and_interpolate), and as wide as the disocclusion
   behind an object that moves 8 pixels in a frame. */
#define RENDERCACHE__HOLE_REACH RENDERCACHE__TILE_ROWS

#define RENDERCACHE__CULL_JOBS 8u            /* ranges of tiles culled and filled in parallel with parallel_for:
                                                the tiles at their ends (2 of 8 at 512x512) are filled apart */
#define RENDERCACHE__BAND_ROWS 128u          /* rows per band of the error diffusion: 9 bands at 1080p */
#define RENDERCACHE__SORT_RANGE 16384u       /* slots re-sorted together: a range (656 KB of points) and its
                                                scratch stay in a core's L2 cache */
#define RENDERCACHE__SORT_SHARE 8u           /* a frame re-sorts 1/8 of the cache, so all of it every 8 frames */
#define RENDERCACHE__SORT_JOBS 2u           /* jobs (and scratches) of the re-sort with parallel_for */
#define RENDERCACHE__SORT_KEYS 2048u         /* sort keys: blocks of pixels, and one for points outside the image */
#define RENDERCACHE__SORT_BANDS 64u          /* bands of rows whose points the projection z-buffers together: a
                                                band's keys (32 KB at 512x512, 260 KB at 1920x1080) stay in a
                                                core's L1 or L2 cache while its points from every range land */

/* Priority image values (WDP99 priority image, extended to [0, 1]): a point
   rises with age times its scale, POINT_MAX at the end of the age ramp
   for scale 1, past the holes and towards 1 beyond (point_priority);
   holes rank above young points, the sparser the higher; a pixel with
   nothing near is at 1. */
#define RENDERCACHE__PRIORITY_POINT_MAX 0.5f
#define RENDERCACHE__PRIORITY_INTERP 0.5f    /* + up to 0.25 as the 3x3 neighbourhood empties */
#define RENDERCACHE__PRIORITY_SPARSE 0.75f   /* + up to 0.2 as the wide window empties */
#define RENDERCACHE__PRIORITY_HOLE_TOP 0.95f /* the highest priority of a filled hole */

/* A cache slot as the projection reads it: 16 bytes. The cache keeps
   these in four arrays (rendercache__slots), one per field, so that the
   projection loads whole vectors of each; this struct is one slot's. */
typedef struct rendercache__geo {
    float pos[3];            /* object-space position, or the world unit direction of a background point */
    uint32_t object;         /* object id, RENDERCACHE_MISS, or RENDERCACHE__FREE_SLOT */
} rendercache__geo;

/* The geo of every slot, structure of arrays (in one block, each array
   starting on a 64-byte boundary). */
typedef struct rendercache__slots {
    float *x, *y, *z;
    uint32_t *object;
} rendercache__slots;
#define RENDERCACHE__SLOT_ALIGN 16u          /* slots per 64 bytes: each array of the block starts on a line */

static void rendercache__slot_get(const rendercache__slots *s, uint32_t slot, rendercache__geo *g)
{
    g->pos[0] = s->x[slot];
    g->pos[1] = s->y[slot];
    g->pos[2] = s->z[slot];
    g->object = s->object[slot];
}

static void rendercache__slot_set(rendercache__slots *s, uint32_t slot, const rendercache__geo *g)
{
    s->x[slot] = g->pos[0];
    s->y[slot] = g->pos[1];
    s->z[slot] = g->pos[2];
    s->object[slot] = g->object;
}

/* The rest of a slot, read by the depth cull for the points that win a
   pixel: 28 bytes. A point's age is not stored but derived, so nothing is
   written per point and frame: age = frame - birth + (motion of its object
   since birth), the last term making points of moving objects age faster;
   it is kept as one sum, age = frame + obj_motion - base (modulo 2^32).
   Nor is the eye that shaded it: the cache keeps the eyes of the last
   RENDERCACHE__EYE_FRAMES frames, and the point the frame it was shaded
   in (rendercache__view_age). */
typedef struct rendercache__point {
    float rgb[3];
    float scale;             /* priority scale */
    uint32_t base;           /* frame of insertion + the object's obj_motion then */
    uint32_t object;         /* geo's object, here too for the priority */
    uint16_t eye_frame;      /* the frame of the eye that shaded it (rendercache__eye_frame) */
    uint16_t view_lobe;      /* its view lobe (rendercache__lobe_bits), 0: view-independent */
} rendercache__point;

/* The eyes remembered for the view-dependent points' ageing: a point shaded
   longer ago is compared with the oldest (about 6 KB in the cache). */
#define RENDERCACHE__EYE_FRAMES 256u
#define RENDERCACHE__EYE_FRAME_MASK 0x7FFFu      /* eye_frame: the frame's low 15 bits ... */
#define RENDERCACHE__EYE_PREDICTED 0x8000u       /* ... and whether it was the predicted camera's eye */
#define RENDERCACHE__LOBE_MIN 1e-6f              /* view lobes are stored between these (radians) */
#define RENDERCACHE__LOBE_MAX 1e6f

/* A band of the error diffusion (rendercache__diffuse): its count and its
   marginal choices. */
typedef struct rendercache__band {
    uint32_t count, best_add, best_drop;
    float add_v, drop_v;
} rendercache__band;

/* What insert needs of a frame whose samples may still come back. */
typedef struct rendercache__frame_record {
    uint64_t frame;          /* 0: no frame here yet */
    rendercache__view view, predicted;
    int has_prediction;
} rendercache__frame_record;

struct rendercache {
    rendercache_allocator alloc;
    void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t);
    void *parallel_user;
    double (*clock)(void *);
    void *clock_user;
    void (*log)(void *, const char *);
    void *log_user;

    uint32_t width, height, pixel_count, tile_count;
    uint32_t capacity, object_count;
    float depth_tolerance, predict_fraction, change_threshold, background[3];
    float edge_fraction, edge_step;   /* desc's */
    int refill_samples;               /* desc's */
    uint32_t age_ramp, moving_age_step, sparse_neighbours, wide_radius, max_latency;
    float inv_age_ramp;
    float window_scale[8];   /* per interpolation radius: the power of two that scales its weights */
    float tol2_pow[RENDERCACHE__HOLE_REACH + 1];   /* powers 0 .. HOLE_REACH of the squared depth tolerance
                                                     factor (rendercache__find_layer), computed once */

    /* point cache: slot order is insertion order; the projection streams
       through geo. One more slot after the last stays empty (see cull_job). */
    rendercache__slots geo;  /* its arrays share one block, geo.x */
    rendercache__point *data;
    unsigned char *shown;    /* per slot: the frame's mark (rendercache__mark) when the point was
                                inserted or shown in a pixel in that frame; the eviction spares it.
                                Apart from data: the cull writes it at random, and a byte array
                                stays in cache where data would not. After the slots, one byte per
                                tile that the tile's pixels without a point write instead */
    uint32_t hand;           /* clock hand of the eviction */
    uint32_t *sort_scratch;  /* rendercache__sort_range: 2 words and a point record per slot of a range, per job;
                                between frames the parallel insertion's chunk (rendercache__insert_chunk) and
                                rendercache_invalidate_where's bit per slot */
    uint32_t *sort_bands;    /* per range, SORT_BANDS + 1 offsets into it: where the points of each band of the
                                image begin at its last re-sort, and (the last) those outside the image; all 0
                                for a range not sorted yet (all of it "outside") */
    uint32_t sort_next;      /* the range re-sorted next */
    uint32_t sort_taken;     /* ranges of this frame's share taken by the re-sort's jobs (atomic) */
    uint32_t sort_shift;     /* sort keys: pixel >> sort_shift, below RENDERCACHE__SORT_KEYS - 1 */
    uint32_t live;
    int hand_exhausted;      /* a full turn found no invisible slot in this frame */

    /* objects */
    float *obj_world;        /* 12 per object: object to world, in force since frame obj_since */
    float *obj_local;        /* 12 per object: world to object, the same */
    float *obj_next;         /* 24 per object: object to world and back set for the next frame */
    uint64_t *obj_since;     /* per object: the first frame of its transform */
    float *obj_history;      /* 12 per object and history slot: world to object in the frame of that
                                slot (rendercache__object_local) */
    float *obj_camera;       /* 12 per object: object to camera space of the current view */
    float *obj_predicted;    /* 12 per object: object to camera space of the predicted view */
    uint32_t *obj_motion;    /* per object, then the background: extra age its points gathered while
                                it moved or since its light changed */
    unsigned char *obj_moved;   /* a transform waits in obj_next */

    /* current frame, and the frames whose samples may still come back */
    uint64_t frame;
    int has_frame, has_prediction;
    rendercache__view view, predicted;
    rendercache__frame_record *history;   /* max_latency + 1 slots, frame f in slot f % that */
    float eyes[RENDERCACHE__EYE_FRAMES][2][3];   /* frame f's eye and its predicted camera's, in slot
                                                    f % RENDERCACHE__EYE_FRAMES (rendercache__shading_eye) */
    rendercache__splat splat;
    uint32_t *px_index;      /* per pixel: the slot shown, after the depth cull */
    float *px_depth;         /* per pixel: its squared distance, FLT_MAX without a point */
    float *depth_out;        /* rendercache_depth_image: distances, filled on request */
    float *image, *priority;
    unsigned char *kind, *count;
    uint32_t *tile_stats;    /* RENDERCACHE__TILE_STATS per tile */

    /* request scratch */
    uint32_t *hist;          /* RENDERCACHE__LEVELS per tile, then the merged histogram */
    float *select_v;         /* per pixel: value plus diffused error of the fractional pixels */
    unsigned char *chosen;   /* per pixel: 1 chosen, 2 fractional (error-diffused) */
    float *err_rows;         /* per band, two rows of diffused error */
    rendercache__band *bands;   /* per band: its count and marginal choices */
    uint32_t band_count;
    unsigned char *occupancy; /* predictive sampling, per job (CELL_JOBS) cell_count + CELL_SINKS bytes: the
                                points that land in the cell, up to 255 (the last bytes take the points
                                that miss); after rendercache_predict job 0's: the sum over the jobs, and
                                255 once the cell was requested */
    uint32_t cells_x, cells_y, cell_count, pred_cells;   /* the cells, and those empty not yet requested */
    uint32_t change_hist[RENDERCACHE__CHANGE_BINS];   /* relative colour differences of this frame's replacements */
    float change_level;      /* colour changes above this age the points around (this frame) */
    uint32_t refill_rows[2];  /* rows [first, end) holding holes marked RENDERCACHE__REFILL */
    uint32_t touched;        /* rendercache__touch_slots' results, kept so its reads stay */

    rendercache_stats stats;
};

static void rendercache__change_level(rendercache *rc);   /* section 15 */

/* The byte that marks slots in use in a frame: 1 .. 255, the same for no
   two frames of a run of 255; begin_frame clears the marks when a run
   starts, so that a mark left 255 frames ago never passes for a new one. */
static unsigned char rendercache__mark(uint64_t frame)
{
    return (unsigned char)(frame % 255u + 1u);
}

static double rendercache__now(const rendercache *rc)
{
    return rc->clock ? rc->clock(rc->clock_user) : 0.0;
}

static void rendercache__log(const rendercache_desc *d, const char *message)
{
    if (d && d->log) d->log(d->log_user, message);
}

static void rendercache__log_to(void (*log)(void *, const char *), void *user, const char *message)
{
    if (log) log(user, message);
}

static void rendercache__identity(float m[12])
{
    memset(m, 0, 12 * sizeof(float));
    m[0] = m[5] = m[10] = 1.0f;
}

/* Image and per-pixel state as if nothing were cached. */
static void rendercache__reset_image(rendercache *rc)
{
    uint32_t p;
    for (p = 0; p < rc->pixel_count; p++) {
        rc->image[3 * p + 0] = rc->background[0];
        rc->image[3 * p + 1] = rc->background[1];
        rc->image[3 * p + 2] = rc->background[2];
        rc->priority[p] = 1.0f;
        rc->kind[p] = RENDERCACHE_PIXEL_EMPTY;
        rc->count[p] = 0;
        rc->px_index[p] = RENDERCACHE__NONE;
        rc->px_depth[p] = FLT_MAX;
    }
}

/* Slots in a range of the re-sort (a job's scratch holds one range). */
static uint32_t rendercache__sort_range_size(const rendercache *rc)
{
    return rc->capacity < RENDERCACHE__SORT_RANGE ? rc->capacity : RENDERCACHE__SORT_RANGE;
}

/* Ranges of the cache. */
static uint32_t rendercache__sort_ranges(const rendercache *rc)
{
    const uint32_t range = rendercache__sort_range_size(rc);
    return (rc->capacity + range - 1) / range;
}

static void rendercache__reset_points(rendercache *rc)
{
    uint32_t i;
    rendercache__geo empty;
    memset(&empty, 0, sizeof empty);
    empty.object = RENDERCACHE_MISS;
    for (i = 0; i < rc->capacity; i++) rc->geo.object[i] = RENDERCACHE__FREE_SLOT;
    /* free slots are projected with the others, four at a time, and masked
       after by their object: their positions must still be numbers the
       projection may read (never used, but not left uninitialised) */
    memset(rc->geo.x, 0, (size_t)rc->capacity * sizeof(float));
    memset(rc->geo.y, 0, (size_t)rc->capacity * sizeof(float));
    memset(rc->geo.z, 0, (size_t)rc->capacity * sizeof(float));
    memset(rc->shown, 0, (size_t)rc->capacity + rc->tile_count);   /* no mark */
    rendercache__slot_set(&rc->geo, rc->capacity, &empty);   /* the empty slot (what holes read): black, priority 0 */
    memset(&rc->data[rc->capacity], 0, sizeof rc->data[0]);
    rc->hand = 0;
    rc->live = 0;
    rc->sort_next = 0;
    memset(rc->sort_bands, 0, (size_t)rendercache__sort_ranges(rc) * (RENDERCACHE__SORT_BANDS + 1) * sizeof(uint32_t));
}

/* Ranges re-sorted per frame: a SORT_SHARE of them, at least one. */
static uint32_t rendercache__sort_range_count(const rendercache *rc)
{
    return (rendercache__sort_ranges(rc) + RENDERCACHE__SORT_SHARE - 1) / RENDERCACHE__SORT_SHARE;
}

/* Jobs of the re-sort, each with its own scratch: SORT_JOBS with
   parallel_for (or fewer, when fewer ranges are sorted per frame), else 1. */
static uint32_t rendercache__sort_jobs(const rendercache *rc)
{
    uint32_t count = rendercache__sort_range_count(rc);
    return rc->parallel_for ? (count < RENDERCACHE__SORT_JOBS ? count : RENDERCACHE__SORT_JOBS) : 1u;
}

/* Words of sort_scratch: a range's scratch per job of the re-sort, and at
   least a bit per slot (rendercache_invalidate_where's answers), which
   takes more only beyond 4.7 million slots (1 job; 9.4 with 2). */
static size_t rendercache__sort_scratch_words(const rendercache *rc)
{
    const size_t sort = (size_t)rendercache__sort_range_size(rc) * rendercache__sort_jobs(rc) *
                        (2 + sizeof(rendercache__point) / sizeof(uint32_t)),
                 bits = ((size_t)rc->capacity + 31) / 32;
    return sort > bits ? sort : bits;
}

static void rendercache__release(rendercache *rc)
{
    const rendercache_allocator a = rc->alloc;
    void *blocks[29];
    size_t i;
    blocks[0] = rc->geo.x; blocks[1] = rc->data; blocks[2] = rc->obj_predicted; blocks[3] = rc->obj_motion;
    blocks[4] = rc->depth_out; blocks[5] = rc->obj_world; blocks[6] = rc->obj_local;
    blocks[7] = rc->obj_camera; blocks[8] = rc->obj_moved; blocks[9] = rc->px_index;
    blocks[10] = rc->px_depth; blocks[11] = rc->image; blocks[12] = rc->priority;
    blocks[13] = rc->occupancy; blocks[14] = rc->kind; blocks[15] = rc->count;
    blocks[16] = rc->tile_stats; blocks[17] = rc->hist; blocks[18] = rc->select_v;
    blocks[19] = rc->chosen; blocks[20] = rc->err_rows; blocks[21] = rc->shown;
    blocks[22] = rc->obj_next; blocks[23] = rc->obj_since; blocks[24] = rc->obj_history;
    blocks[25] = rc->history;
    blocks[26] = rc->bands;
    blocks[27] = rc->sort_scratch;
    blocks[28] = rc->sort_bands;
    for (i = 0; i < sizeof blocks / sizeof blocks[0]; i++) rendercache__free(&a, blocks[i]);
    rendercache__splat_free(&rc->splat, &a);
    rendercache__free(&a, rc);
}

/* With parallel_for, the projection's jobs share the z-buffer: job j takes
   the chunks of bands [SORT_BANDS j / SHARED_JOBS, SORT_BANDS (j + 1) /
   SHARED_JOBS) (rendercache__point_chunk) and owns the pixels of those
   bands as the re-sort counts them (the pixel blocks from ceil(b none_key
   / SORT_BANDS) on), where most of its points land. Points that moved
   across a band's edge since their re-sort, and those not sorted, go
   through the deferral buffers: 1/DEFER_SHARE of the pixel count in all. */
#define RENDERCACHE__DEFER_SHARE 2u   /* half the pixel count, 6 bytes per pixel: one round or two a frame in
                                         bench_rendercache at 1920x1080 (a quarter: up to 5) */
static int rendercache__share_splat(rendercache *rc)
{
    const uint32_t none_key = (rc->pixel_count >> rc->sort_shift) + 1u;
    uint32_t own[RENDERCACHE__SHARED_JOBS + 1], j;
    for (j = 0; j <= RENDERCACHE__SHARED_JOBS; j++) {
        const uint64_t band = (uint64_t)RENDERCACHE__SORT_BANDS * j / RENDERCACHE__SHARED_JOBS;
        const uint64_t p = ((band * none_key + RENDERCACHE__SORT_BANDS - 1) / RENDERCACHE__SORT_BANDS) << rc->sort_shift;
        own[j] = j == RENDERCACHE__SHARED_JOBS || p > rc->pixel_count ? rc->pixel_count : (uint32_t)p;
    }
    return rendercache__splat_share(&rc->splat, own, rc->pixel_count / RENDERCACHE__DEFER_SHARE / RENDERCACHE__SHARED_JOBS,
                                    &rc->alloc);
}

/* Bytes of one array of the occupancy count: the cells, then the sinks. */
static size_t rendercache__cell_stride(const rendercache *rc)
{
    return (size_t)rc->cell_count + RENDERCACHE__CELL_SINKS;
}

static int rendercache__alloc_buffers(rendercache *rc)
{
    const rendercache_allocator *a = &rc->alloc;
    size_t n = rc->capacity, px = rc->pixel_count, no = rc->object_count;
    size_t slots = (size_t)rc->max_latency + 1;
    const size_t stride = (n + 1 + RENDERCACHE__SLOT_ALIGN - 1) / RENDERCACHE__SLOT_ALIGN * RENDERCACHE__SLOT_ALIGN;
    rc->geo.x = (float *)rendercache__alloc_array(a, stride, 4 * sizeof(float));   /* + the empty slot */
    if (rc->geo.x) {   /* (an allocator aligns to 16 bytes at least: the arrays follow at multiples of 64) */
        rc->geo.y = rc->geo.x + stride;
        rc->geo.z = rc->geo.y + stride;
        rc->geo.object = (uint32_t *)(void *)(rc->geo.z + stride);
    }
    rc->data = (rendercache__point *)rendercache__alloc_array(a, n + 1, sizeof(rendercache__point));
    rc->shown = (unsigned char *)rendercache__alloc_array(a, n + rc->tile_count, 1);
    rc->obj_predicted = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_motion = (uint32_t *)rendercache__alloc_array(a, no + 1, sizeof(uint32_t));
    rc->obj_world = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_local = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_next = (float *)rendercache__alloc_array(a, no, 24 * sizeof(float));
    rc->obj_since = (uint64_t *)rendercache__alloc_array(a, no, sizeof(uint64_t));
    rc->obj_history = (float *)rendercache__alloc_array(a, no * slots, 12 * sizeof(float));
    rc->history = (rendercache__frame_record *)rendercache__alloc_array(a, slots, sizeof(rendercache__frame_record));
    rc->obj_camera = (float *)rendercache__alloc_array(a, no, 12 * sizeof(float));
    rc->obj_moved = (unsigned char *)rendercache__alloc_array(a, no, 1);
    rc->px_index = (uint32_t *)rendercache__alloc_array(a, px, sizeof(uint32_t));
    rc->px_depth = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->depth_out = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->image = (float *)rendercache__alloc_array(a, px, 3 * sizeof(float));
    rc->priority = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->occupancy = (unsigned char *)rendercache__alloc_array(a, rendercache__cell_stride(rc),
                                                              rc->parallel_for ? RENDERCACHE__CELL_JOBS : 1u);
    rc->kind = (unsigned char *)rendercache__alloc_array(a, px, 1);
    rc->count = (unsigned char *)rendercache__alloc_array(a, px, 1);
    rc->tile_stats = (uint32_t *)rendercache__alloc_array(a, rc->tile_count, RENDERCACHE__TILE_STATS * sizeof(uint32_t));
    rc->hist = (uint32_t *)rendercache__alloc_array(a, (size_t)rc->tile_count + 1, RENDERCACHE__LEVELS * sizeof(uint32_t));
    rc->select_v = (float *)rendercache__alloc_array(a, px, sizeof(float));
    rc->chosen = (unsigned char *)rendercache__alloc_array(a, px, 1);
    rc->err_rows = (float *)rendercache__alloc_array(a, 2 * (size_t)rc->band_count * ((size_t)rc->width + 2), sizeof(float));
    rc->bands = (rendercache__band *)rendercache__alloc_array(a, rc->band_count, sizeof *rc->bands);
    rc->sort_scratch = (uint32_t *)rendercache__alloc_array(a, rendercache__sort_scratch_words(rc), sizeof(uint32_t));
    rc->sort_bands = (uint32_t *)rendercache__alloc_array(a, rendercache__sort_ranges(rc),
                                                          (RENDERCACHE__SORT_BANDS + 1) * sizeof(uint32_t));
    if (!rc->geo.x || !rc->data || !rc->shown || !rc->obj_predicted || !rc->obj_motion || !rc->obj_world ||
        !rc->obj_local || !rc->obj_next || !rc->obj_since || !rc->obj_history || !rc->history ||
        !rc->obj_camera || !rc->obj_moved || !rc->px_index || !rc->px_depth || !rc->depth_out || !rc->image ||
        !rc->priority || !rc->occupancy || !rc->kind || !rc->count || !rc->tile_stats || !rc->hist ||
        !rc->select_v || !rc->chosen || !rc->err_rows || !rc->bands || !rc->sort_scratch || !rc->sort_bands)
        return -1;
    if (rendercache__splat_alloc(&rc->splat, rc->width, rc->height, 1u, 0, a) != 0)   /* one z-buffer: the cull reads its keys */
        return -1;
    return rc->parallel_for ? rendercache__share_splat(rc) : 0;
}

/* Applies the defaults and checks the ranges of a desc; 0 on bad input. */
static int rendercache__configure(rendercache *rc, const rendercache_desc *d)
{
    double capacity;
    uint32_t r;
    float ppp = rendercache__def(d->points_per_pixel, 2.0f);
    if (d->width == 0 || d->height == 0 || (uint64_t)d->width * d->height > RENDERCACHE__MAX_PIXELS) return 0;
    if (!rendercache__allocator_valid(&d->allocator)) return 0;
    if (!(ppp > 0.0f) || !isfinite(ppp)) return 0;
    if (!(d->depth_tolerance >= 0.0f) || !isfinite(d->depth_tolerance)) return 0;
    if (!(d->predict_fraction >= 0.0f && d->predict_fraction <= 1.0f)) return 0;
    if (!(d->change_threshold >= 0.0f) || d->max_latency > RENDERCACHE__MAX_LATENCY) return 0;
    if (!(d->edge_fraction >= 0.0f && d->edge_fraction <= 1.0f) || !(d->edge_step >= 0.0f)) return 0;
    if (!rendercache__finite3(d->background)) return 0;
    if (d->object_count > RENDERCACHE__MAX_OBJECTS || d->sparse_neighbours > 8 || d->wide_radius > 7) return 0;
    capacity = ceil((double)ppp * d->width * d->height);
    if (capacity < 1.0 || capacity > (double)RENDERCACHE__MAX_CAPACITY) return 0;
    rc->alloc = d->allocator;
    rc->parallel_for = d->parallel_for;
    rc->parallel_user = d->parallel_user;
    rc->clock = d->clock;
    rc->clock_user = d->clock_user;
    rc->log = d->log;
    rc->log_user = d->log_user;
    rc->width = d->width;
    rc->height = d->height;
    rc->pixel_count = d->width * d->height;
    rc->tile_count = (d->height + RENDERCACHE__TILE_ROWS - 1) / RENDERCACHE__TILE_ROWS;
    rc->band_count = (d->height + RENDERCACHE__BAND_ROWS - 1) / RENDERCACHE__BAND_ROWS;
    rc->cells_x = (d->width + RENDERCACHE__CELL - 1) >> RENDERCACHE__CELL_SHIFT;
    rc->cells_y = (d->height + RENDERCACHE__CELL - 1) >> RENDERCACHE__CELL_SHIFT;
    rc->cell_count = rc->cells_x * rc->cells_y;
    rc->capacity = (uint32_t)capacity;
    rc->sort_shift = 0;
    while ((rc->pixel_count >> rc->sort_shift) + 1u >= RENDERCACHE__SORT_KEYS) rc->sort_shift++;
    rc->object_count = rendercache__def(d->object_count, 256u);
    rc->depth_tolerance = rendercache__def(d->depth_tolerance, 0.1f);
    rc->predict_fraction = rendercache__def(d->predict_fraction, 0.25f);
    rc->change_threshold = rendercache__def(d->change_threshold, 0.25f);
    rc->edge_fraction = d->edge_fraction;
    rc->refill_samples = d->refill_samples != 0;
    rc->edge_step = rendercache__def(d->edge_step, 0.5f);
    rc->max_latency = rendercache__def(d->max_latency, 4u);
    rc->age_ramp = rendercache__def(d->age_ramp_frames, 32u);
    rc->inv_age_ramp = 1.0f / (float)rc->age_ramp;
    rc->moving_age_step = rendercache__def(d->moving_age_step, 4u);
    if (rc->moving_age_step > 65536u) rc->moving_age_step = 65536u;
    rc->sparse_neighbours = rendercache__def(d->sparse_neighbours, 2u);
    rc->wide_radius = rendercache__def(d->wide_radius, 3u);
    for (r = 0; r < 8; r++) {   /* tent weights of radius r sum to ((r + 1)^2)^2 at most */
        uint32_t total = (r + 1) * (r + 1) * (r + 1) * (r + 1);
        int e = 0;
        while ((1u << e) < total) e++;
        rc->window_scale[r] = ldexpf(1.0f, -e);
    }
    rc->tol2_pow[0] = 1.0f;
    for (r = 1; r <= RENDERCACHE__HOLE_REACH; r++)
        rc->tol2_pow[r] = rc->tol2_pow[r - 1] * ((1.0f + rc->depth_tolerance) * (1.0f + rc->depth_tolerance));
    memcpy(rc->background, d->background, sizeof rc->background);
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_create(const rendercache_desc *desc, rendercache **out)
{
    rendercache *rc;
    rendercache_allocator a;
    uint32_t o;
    if (!out) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    *out = NULL;
    if (!desc) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__allocator_valid(&desc->allocator)) {
        rendercache__log(desc, "rendercache_create: allocator needs both alloc and free, or neither");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    a = desc->allocator;
    rc = (rendercache *)rendercache__alloc(&a, sizeof *rc);
    if (!rc) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    memset(rc, 0, sizeof *rc);
    rc->alloc = a;
    if (!rendercache__configure(rc, desc)) {
        rendercache__log(desc, "rendercache_create: bad size, tolerance, fraction or radius in the desc");
        rendercache__release(rc);
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    if (rendercache__alloc_buffers(rc) != 0) {
        rendercache__log(desc, "rendercache_create: out of memory");
        rendercache__release(rc);
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    }
    for (o = 0; o < rc->object_count; o++) {
        rendercache__identity(rc->obj_world + 12 * (size_t)o);
        rendercache__identity(rc->obj_local + 12 * (size_t)o);
        rc->obj_moved[o] = 0;
        rc->obj_motion[o] = 0;
        rc->obj_since[o] = 0;
    }
    rc->obj_motion[rc->object_count] = 0;   /* the background */
    memset(rc->history, 0, ((size_t)rc->max_latency + 1) * sizeof *rc->history);
    rendercache__reset_points(rc);
    rendercache__reset_image(rc);
    rc->refill_rows[0] = rc->height;
    rc->stats.capacity = rc->capacity;
    *out = rc;
    return RENDERCACHE_OK;
}

RENDERCACHE_API void rendercache_destroy(rendercache *rc)
{
    if (rc) rendercache__release(rc);
}

RENDERCACHE_API void rendercache_clear(rendercache *rc)
{
    if (!rc) return;
    rendercache__reset_points(rc);
    rendercache__reset_image(rc);
    rc->has_prediction = 0;
    rc->stats.live_points = 0;
}

/* ======================================================================
   11. object transforms
   ---------------------------------------------------------------------- */
/* Inverse of an affine 3x4 matrix in double; 0 when singular. */
static int rendercache__invert_affine(const float m[12], float out[12])
{
    double a = m[0], b = m[1], c = m[2], d = m[4], e = m[5], f = m[6], g = m[8], h = m[9], k = m[10];
    double det = a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g), inv[9];
    double scale = fabs(a) + fabs(b) + fabs(c) + fabs(d) + fabs(e) + fabs(f) + fabs(g) + fabs(h) + fabs(k);
    int i;
    if (!(fabs(det) > 1e-12 * scale * scale * scale) || !isfinite(det)) return 0;
    inv[0] = (e * k - f * h) / det; inv[1] = (c * h - b * k) / det; inv[2] = (b * f - c * e) / det;
    inv[3] = (f * g - d * k) / det; inv[4] = (a * k - c * g) / det; inv[5] = (c * d - a * f) / det;
    inv[6] = (d * h - e * g) / det; inv[7] = (b * g - a * h) / det; inv[8] = (a * e - b * d) / det;
    for (i = 0; i < 3; i++) {
        out[4 * i + 0] = (float)inv[3 * i + 0];
        out[4 * i + 1] = (float)inv[3 * i + 1];
        out[4 * i + 2] = (float)inv[3 * i + 2];
        out[4 * i + 3] = (float)-(inv[3 * i + 0] * m[3] + inv[3 * i + 1] * m[7] + inv[3 * i + 2] * m[11]);
    }
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_set_object_transform(rendercache *rc, uint32_t object,
                                                                    const float m[12])
{
    float inv[12], *next;
    int k;
    if (!rc || !m || object >= rc->object_count) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (k = 0; k < 12; k++)
        if (!isfinite(m[k])) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__invert_affine(m, inv)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    next = rc->obj_next + 24 * (size_t)object;
    if (!rc->obj_moved[object] && memcmp(m, rc->obj_world + 12 * (size_t)object, 12 * sizeof(float)) == 0)
        return RENDERCACHE_OK;   /* a still transform is not motion */
    memcpy(next, m, 12 * sizeof(float));
    memcpy(next + 12, inv, 12 * sizeof(float));
    rc->obj_moved[object] = 1;
    return RENDERCACHE_OK;
}

/* The transforms set since the last frame come into force in frame
   rc->frame; the frames of the history window that saw an object's old
   transform keep it in obj_history (rendercache__object_local). Points of
   moving objects age faster. */
static void rendercache__commit_transforms(rendercache *rc)
{
    const uint64_t f = rc->frame, slots = (uint64_t)rc->max_latency + 1;
    const uint64_t first = f > rc->max_latency ? f - rc->max_latency : 1;   /* the oldest frame kept */
    uint32_t o;
    for (o = 0; o < rc->object_count; o++) {
        float *local = rc->obj_local + 12 * (size_t)o, *next = rc->obj_next + 24 * (size_t)o;
        uint64_t g;
        if (!rc->obj_moved[o]) continue;
        for (g = rc->obj_since[o] > first ? rc->obj_since[o] : first; g < f; g++)
            memcpy(rc->obj_history + 12 * ((size_t)o * slots + g % slots), local, 12 * sizeof(float));
        memcpy(rc->obj_world + 12 * (size_t)o, next, 12 * sizeof(float));
        memcpy(local, next + 12, 12 * sizeof(float));
        rc->obj_since[o] = f;
        rc->obj_motion[o] += rc->moving_age_step - 1u;
        rc->obj_moved[o] = 0;
    }
}

/* World to object space of object o in frame f of the history window. */
static const float *rendercache__object_local(const rendercache *rc, uint32_t o, uint64_t f)
{
    const size_t slots = (size_t)rc->max_latency + 1;
    if (f >= rc->obj_since[o]) return rc->obj_local + 12 * (size_t)o;
    return rc->obj_history + 12 * ((size_t)o * slots + (size_t)(f % slots));
}

/* The index of a point's object in obj_motion: the background after the objects. */
static uint32_t rendercache__motion_index(const rendercache *rc, uint32_t object)
{
    return object < rc->object_count ? object : rc->object_count;
}

/* ======================================================================
   12. per-frame pipeline (Walter et al. 1999): project every point into
   the new camera and z-buffer it (section 9) -> depth cull -> interpolate
   the holes; the priority image is written by the last two (points: age;
   holes: how few points surround them). Then requests by thresholding and
   error diffusion (section 14), and insertion (section 15).
   ---------------------------------------------------------------------- */
/* Where a projection goes: a view and its object-to-camera matrices. */
typedef struct rendercache__projector {
    const rendercache *rc;
    const rendercache__view *view;
    const float *obj_camera;
    float sky[12];           /* the view's rotation without translation: background points are directions */
    uint32_t shift, stride;  /* the index a point lands in: (y >> shift) * stride + (x >> shift); pixels:
                                0 and the width; prediction's cells: RENDERCACHE__CELL_SHIFT */
} rendercache__projector;

/* A projector into view v through the object-to-camera matrices obj_camera,
   onto cells of 2^shift x 2^shift pixels. */
static void rendercache__projector_init(rendercache__projector *pr, const rendercache *rc, const rendercache__view *v,
                                        const float *obj_camera, uint32_t shift)
{
    int k;
    pr->rc = rc;
    pr->view = v;
    pr->obj_camera = obj_camera;
    pr->shift = shift;
    pr->stride = (v->width + (1u << shift) - 1) >> shift;
    for (k = 0; k < 3; k++) {
        memcpy(pr->sky + 4 * k, v->axis[k], 3 * sizeof(float));
        pr->sky[4 * k + 3] = 0.0f;
    }
}

/* Reprojection of a point x (WDP99) through the 3x4 matrix m into camera
   space, then to the perspective view v: the index of the pixel (or cell
   of 2^shift x 2^shift pixels, stride per row) it lands in, or
   RENDERCACHE__NONE, and the squared distance (the z-buffer only compares
   them). Both the loop that vectorises and the point-by-point path go
   through this one function, so that a point lands in the same pixel
   whichever projects it (batches differ with the number of jobs). */
static RENDERCACHE__INLINE uint32_t rendercache__pixel_through(const float *m, float x, float y, float z,
                                                               const rendercache__view *v, uint32_t shift, uint32_t stride,
                                                               float *depth2)
{
    const float w = (float)v->width, h = (float)v->height;
    float c0 = m[0] * x + m[1] * y + m[2] * z + m[3];
    float c1 = m[4] * x + m[5] * y + m[6] * z + m[7];
    float c2 = m[8] * x + m[9] * y + m[10] * z + m[11];
    float inv = 1.0f / c2, px = v->cx + v->focal * c0 * inv, py = v->cy - v->focal * c1 * inv;
    int inside = (c2 > 0.0f) & (px >= 0.0f) & (px < w) & (py >= 0.0f) & (py < h);
    float xs = inside ? px : 0.0f, ys = inside ? py : 0.0f;
    *depth2 = c0 * c0 + c1 * c1 + c2 * c2;
    return inside ? ((uint32_t)ys >> shift) * stride + ((uint32_t)xs >> shift) : RENDERCACHE__NONE;
}

/* Reprojection of one cache point: object space -> camera space through
   the object's composed matrix; background points are directions, rotated
   only, at distance RENDERCACHE__FAR. */
static uint32_t rendercache__project_point(const rendercache__projector *pr, const rendercache__geo *g, float *depth2)
{
    const rendercache__view *v = pr->view;
    uint32_t p;
    if (g->object == RENDERCACHE__FREE_SLOT) return RENDERCACHE__NONE;
    if (g->object != RENDERCACHE_MISS)
        return rendercache__pixel_through(pr->obj_camera + 12 * (size_t)g->object, g->pos[0], g->pos[1], g->pos[2], v,
                                          pr->shift, pr->stride, depth2);
    p = rendercache__pixel_through(pr->sky, g->pos[0], g->pos[1], g->pos[2], v, pr->shift, pr->stride, depth2);
    *depth2 = RENDERCACHE__FAR2;
    return p;
}

/* A frame's number as a point keeps it, with whether the predicted
   camera's eye shaded it. */
static uint16_t rendercache__eye_frame(uint64_t frame, int predicted)
{
    return (uint16_t)((frame & RENDERCACHE__EYE_FRAME_MASK) | (predicted ? RENDERCACHE__EYE_PREDICTED : 0u));
}

/* A view lobe in 16 bits: the upper half of the float (8 bits of mantissa,
   rounded to nearest even), clamped to [LOBE_MIN, LOBE_MAX]; 0 for 0. The
   priority needs no more than 3 digits of it. */
static uint16_t rendercache__lobe_bits(float lobe)
{
    uint32_t bits;
    if (!(lobe > 0.0f)) return 0;
    lobe = lobe < RENDERCACHE__LOBE_MIN ? RENDERCACHE__LOBE_MIN : lobe > RENDERCACHE__LOBE_MAX ? RENDERCACHE__LOBE_MAX : lobe;
    memcpy(&bits, &lobe, sizeof bits);
    bits += 0x7FFFu + ((bits >> 16) & 1u);
    return (uint16_t)(bits >> 16);
}

static float rendercache__lobe(uint16_t code)
{
    uint32_t bits = (uint32_t)code << 16;
    float lobe;
    memcpy(&lobe, &bits, sizeof lobe);
    return lobe;
}

/* The eye that shaded a point: its frame's (or that frame's predicted
   camera's), or for a point shaded more than EYE_FRAMES - 1 frames ago
   the oldest eye remembered. */
static const float *rendercache__shading_eye(const rendercache *rc, uint16_t eye_frame)
{
    const uint32_t since = ((uint32_t)rc->frame - eye_frame) & RENDERCACHE__EYE_FRAME_MASK;
    const int known = since < RENDERCACHE__EYE_FRAMES;
    const uint64_t f = rc->frame - (known ? since : RENDERCACHE__EYE_FRAMES - 1u);
    return rc->eyes[f % RENDERCACHE__EYE_FRAMES][known && (eye_frame & RENDERCACHE__EYE_PREDICTED)];
}

/* How stale a view-dependent colour is, in units of the age ramp: the
   angle between the eye that shaded the point and the current eye, seen
   from the point, over the point's view lobe (a glossy highlight slides
   as the view turns, whatever the age). The point is where pixel p's ray
   meets it (depth2: its squared distance), exact to half a pixel. Not
   inlined: in the depth cull's loop (rendercache__write_row) it cost 1.5
   ms of a 512x512 frame (cull 5.1 -> 6.9 ms) to points without a lobe. */
static RENDERCACHE__NOINLINE float rendercache__view_age(const rendercache *rc, const rendercache__point *pt, uint32_t p,
                                                          float depth2)
{
    const float *e = rendercache__shading_eye(rc, pt->eye_frame), *eye = rc->view.eye;
    const float dist = sqrtf(depth2);
    float dir[3], a[3], c[3];
    int k;
    rendercache__view_ray(&rc->view, (float)(p % rc->width) + 0.5f, (float)(p / rc->width) + 0.5f, dir);
    for (k = 0; k < 3; k++) a[k] = eye[k] + dir[k] * dist - e[k];   /* shading eye to the point */
    c[0] = a[1] * dir[2] - a[2] * dir[1];
    c[1] = a[2] * dir[0] - a[0] * dir[2];
    c[2] = a[0] * dir[1] - a[1] * dir[0];
    return atan2f(sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), a[0] * dir[0] + a[1] * dir[1] + a[2] * dir[2]) /
           rendercache__lobe(pt->view_lobe);
}

/* Priority of a pixel showing a point (WDP99: age is the main measure of
   how likely a colour is stale; points of moving objects age faster), for
   a view-dependent point plus the view's turn since it was shaded over its
   lobe (rendercache__view_age, as age_ramp frames per lobe), times its
   priority scale (the light-vector weight of Crespin and Peroche 2004,
   section 4.2.4), in [0, 1]. motion: the object's obj_motion; p: the
   pixel, depth2: the point's squared distance. The
   product x = POINT_MAX age scale / age_ramp is the priority up to the
   filled holes' top (PRIORITY_HOLE_TOP); above it, it is squeezed into
   the levels between that and 1 (empty pixels), 0.95 + 0.05 (1 - 0.95 /
   x), so that points keep their order however old they get. Clamped at
   1, as it was, every point of scale 2 or more (most of the walkthrough's:
   1/W of an interpolated light vector) reached the top within age_ramp
   frames (half that for scale 4), and the budget then went to them at
   random while points of scale 1 (vectors gathered at the point, misses)
   never ranked above them: in the building walkthrough such points
   stayed for hundreds of frames, showing windows seen long ago through
   the walls and carrying almost all of the stale points' error (points
   older than 24 frames: 3 % of the pixels, 90 % of that error at frame
   135). */
static float rendercache__point_priority(const rendercache *rc, const rendercache__point *pt, uint32_t motion,
                                         uint32_t p, float depth2)
{
    uint32_t age = (uint32_t)rc->frame + motion - pt->base;
    float ramps = (float)age * rc->inv_age_ramp, x;
    if (pt->view_lobe) ramps += rendercache__view_age(rc, pt, p, depth2);
    x = ramps * (RENDERCACHE__PRIORITY_POINT_MAX * pt->scale);
    if (x <= RENDERCACHE__PRIORITY_HOLE_TOP) return x;
    return RENDERCACHE__PRIORITY_HOLE_TOP +
           (1.0f - RENDERCACHE__PRIORITY_HOLE_TOP) * (1.0f - RENDERCACHE__PRIORITY_HOLE_TOP / x);
}

/* Perspective projection of slots [begin, begin + n) of one object
   (matrix m): written without branches or library calls, over arrays of
   each coordinate, so that compilers vectorise it with whole loads; this
   loop is the hottest of the frame. */
static void rendercache__project_perspective(const rendercache__slots *g, uint32_t begin, uint32_t n, const float *m,
                                             const rendercache__projector *pr, uint32_t *RENDERCACHE__RESTRICT pix,
                                             float *RENDERCACHE__RESTRICT depth2)
{
    const rendercache__view *v = pr->view;
    const uint32_t shift = pr->shift, stride = pr->stride;
    const float *RENDERCACHE__RESTRICT x = g->x + begin, *RENDERCACHE__RESTRICT y = g->y + begin;
    const float *RENDERCACHE__RESTRICT z = g->z + begin;
    uint32_t i;
    for (i = 0; i < n; i++) pix[i] = rendercache__pixel_through(m, x[i], y[i], z[i], v, shift, stride, &depth2[i]);
}

/* The background points and free slots of n points that
   project_perspective projected through an object's matrix: background
   points again, as directions (through the sky matrix), at distance
   RENDERCACHE__FAR; free slots land nowhere. Every point is projected and
   the results selected, without branches, so that it vectorises too. */
static void rendercache__project_others(const rendercache__slots *g, uint32_t begin, uint32_t n,
                                        const rendercache__projector *pr, uint32_t *RENDERCACHE__RESTRICT pix,
                                        float *RENDERCACHE__RESTRICT depth2)
{
    const rendercache__view *v = pr->view;
    const uint32_t shift = pr->shift, stride = pr->stride;
    const float *RENDERCACHE__RESTRICT x = g->x + begin, *RENDERCACHE__RESTRICT y = g->y + begin;
    const float *RENDERCACHE__RESTRICT z = g->z + begin;
    const uint32_t *RENDERCACHE__RESTRICT object = g->object + begin;
    uint32_t i;
    for (i = 0; i < n; i++) {
        float d;
        uint32_t q = rendercache__pixel_through(pr->sky, x[i], y[i], z[i], v, shift, stride, &d), o = object[i];
        pix[i] = o == RENDERCACHE__FREE_SLOT ? RENDERCACHE__NONE : o == RENDERCACHE_MISS ? q : pix[i];
        depth2[i] = o == RENDERCACHE_MISS ? RENDERCACHE__FAR2 : depth2[i];
    }
}

/* Projects the points of object o among slots [begin, begin + n) through
   its matrix m into pix and depth2 (every point when all, the first pass;
   else the others' entries are kept), and returns the least object id
   above o among them (RENDERCACHE__FREE_SLOT or RENDERCACHE_MISS when
   there is none). The same arithmetic per point as project_perspective and
   project_point, without branches, so that it vectorises. */
static uint32_t rendercache__project_object(const rendercache__slots *g, uint32_t begin, uint32_t n, uint32_t o,
                                            int all, const float *m, const rendercache__projector *pr,
                                            uint32_t *RENDERCACHE__RESTRICT pix, float *RENDERCACHE__RESTRICT depth2)
{
    const rendercache__view *v = pr->view;
    const uint32_t shift = pr->shift, stride = pr->stride;
    const float *RENDERCACHE__RESTRICT x = g->x + begin, *RENDERCACHE__RESTRICT y = g->y + begin;
    const float *RENDERCACHE__RESTRICT z = g->z + begin;
    const uint32_t *RENDERCACHE__RESTRICT object = g->object + begin;
    uint32_t i, next = RENDERCACHE_MISS;
    for (i = 0; i < n; i++) {
        float d;
        const uint32_t q = rendercache__pixel_through(m, x[i], y[i], z[i], v, shift, stride, &d);
        const int take = all | (object[i] == o);
        pix[i] = take ? q : pix[i];
        depth2[i] = take ? d : depth2[i];
        next = object[i] > o && object[i] < next ? object[i] : next;   /* (the special ids lie above all others) */
    }
    return next;
}

/* The one object of the points [begin, end) other than background points
   and free slots (RENDERCACHE_MISS when there is none), RENDERCACHE__NONE
   when there are several; *others tells whether background points or free
   slots are among them, *least is the least object id (a special value
   when there is none). The least and the largest object id of the
   batch, without branches, so that the loop vectorises (object ids lie
   below both special values). */
static uint32_t rendercache__batch_object(const uint32_t *object, uint32_t begin, uint32_t end, int *others,
                                          uint32_t *least)
{
    const uint32_t *o = object + begin;
    const size_t n = end - begin;
    uint32_t lo = RENDERCACHE_MISS, hi = 0, other = 0;
    size_t i;
    for (i = 0; i < n; i++) {   /* specials (RENDERCACHE_MISS, a free slot) are the largest ids: lo passes them
                                   only when there is nothing else, and hi leaves them out */
        uint32_t g = o[i], special = (uint32_t)-(int32_t)(g >= RENDERCACHE__FREE_SLOT);   /* all ones or zero */
        other |= special;
        lo = g < lo ? g : lo;
        hi = (g & ~special) > hi ? (g & ~special) : hi;
    }
    *others = (int)(other & 1u);
    *least = lo;
    return lo >= RENDERCACHE__FREE_SLOT ? RENDERCACHE_MISS : lo == hi ? lo : RENDERCACHE__NONE;
}

#define RENDERCACHE__OBJECT_PASSES 4u   /* objects of a batch projected in passes of their own, at most (8: no
                                           faster at 512x512) */

/* The splat source of the render cache: cache slots [begin, end). Under a
   perspective view, a batch of one object (with or without background
   points and free slots) takes the vectorised path, and a batch of several
   a vectorised pass per object, the first RENDERCACHE__OBJECT_PASSES in id
   order, then the rest point by point; other views go point by point. (A
   sixth of the points of bench_rendercache's Cornell box, 8 objects, lie
   in batches of several, which went point by point: 512x512 on one
   thread, the frame took 2 % longer.) */
static uint32_t rendercache__project_points(const void *src, uint32_t begin, uint32_t end, uint32_t *pix, float *depth2)
{
    const rendercache__projector *pr = (const rendercache__projector *)src;
    const rendercache__slots *geo = &pr->rc->geo;
    int others;
    uint32_t i, o, least, ahead = end + (end - begin) < pr->rc->capacity ? end - begin : pr->rc->capacity - end;
    /* the next batch's points, a cache line of each array at a time: the stream through the points is
       the projection's bottleneck, more than its arithmetic */
    for (i = 0; i < ahead; i += 64 / sizeof(float)) {
        RENDERCACHE__PREFETCH(&geo->x[end + i]);
        RENDERCACHE__PREFETCH(&geo->y[end + i]);
        RENDERCACHE__PREFETCH(&geo->z[end + i]);
        RENDERCACHE__PREFETCH(&geo->object[end + i]);
    }
    o = rendercache__batch_object(geo->object, begin, end, &others, &least);
    if (pr->view->kind == RENDERCACHE_CAMERA_PERSPECTIVE && o != RENDERCACHE__NONE) {
        const float *m = o == RENDERCACHE_MISS ? pr->sky : pr->obj_camera + 12 * (size_t)o;
        rendercache__project_perspective(geo, begin, end - begin, m, pr, pix, depth2);
        if (others) rendercache__project_others(geo, begin, end - begin, pr, pix, depth2);
        return end - begin;
    }
    if (pr->view->kind == RENDERCACHE_CAMERA_PERSPECTIVE) {   /* several objects */
        uint32_t passes = 0;
        for (o = least; o < RENDERCACHE__FREE_SLOT && passes < RENDERCACHE__OBJECT_PASSES; passes++)
            o = rendercache__project_object(geo, begin, end - begin, o, passes == 0, pr->obj_camera + 12 * (size_t)o, pr,
                                            pix, depth2);
        if (others) rendercache__project_others(geo, begin, end - begin, pr, pix, depth2);
        for (i = begin; o < RENDERCACHE__FREE_SLOT && i < end; i++) {   /* the objects left (ids o and up) */
            rendercache__geo g;
            rendercache__slot_get(geo, i, &g);
            if (g.object >= o && g.object < RENDERCACHE__FREE_SLOT)
                pix[i - begin] = rendercache__project_point(pr, &g, &depth2[i - begin]);
        }
        return end - begin;
    }
    for (i = begin; i < end; i++) {
        rendercache__geo g;
        rendercache__slot_get(geo, i, &g);
        pix[i - begin] = rendercache__project_point(pr, &g, &depth2[i - begin]);
    }
    return end - begin;
}

/* Object-to-camera matrices of every object for view v. */
static void rendercache__compose_objects(const rendercache *rc, const rendercache__view *v, float *out)
{
    uint32_t o;
    for (o = 0; o < rc->object_count; o++)
        rendercache__view_compose(v, rc->obj_world + 12 * (size_t)o, out + 12 * (size_t)o);
}

/* The chunks of the projection, band by band of the image: chunk c of
   block b = c / (R + q) (R ranges, q = ceil(R / SORT_BANDS)) is, for i =
   c % (R + q) < R, the points of range i that fell in band b at its last
   re-sort, else the points of range (i - R) SORT_BANDS + b outside the
   image then (or not sorted yet; empty past the last range). So the
   z-tests of a block land mostly in one band's keys, which stay in cache,
   instead of sweeping the whole z-buffer once per range; the outside
   chunks are spread over the blocks so that the parallel jobs, which take
   blocks in order, get even shares. */
static uint32_t rendercache__chunk_count(const rendercache *rc)
{
    const uint32_t ranges = rendercache__sort_ranges(rc);
    return RENDERCACHE__SORT_BANDS * (ranges + (ranges + RENDERCACHE__SORT_BANDS - 1) / RENDERCACHE__SORT_BANDS);
}

static void rendercache__point_chunk(const void *src, uint32_t c, uint32_t *begin, uint32_t *end)
{
    const rendercache *rc = ((const rendercache__projector *)src)->rc;
    const uint32_t range = rendercache__sort_range_size(rc), ranges = rendercache__sort_ranges(rc);
    const uint32_t block = ranges + (ranges + RENDERCACHE__SORT_BANDS - 1) / RENDERCACHE__SORT_BANDS;
    const uint32_t b = c / block, i = c % block;
    const uint32_t r = i < ranges ? i : (i - ranges) * RENDERCACHE__SORT_BANDS + b, r0 = r * range;
    const uint32_t *bands = rc->sort_bands + (size_t)r * (RENDERCACHE__SORT_BANDS + 1);
    uint32_t n;
    if (r >= ranges) { *begin = *end = 0; return; }
    n = rc->capacity - r0 < range ? rc->capacity - r0 : range;
    *begin = r0 + (i < ranges ? bands[b] : bands[RENDERCACHE__SORT_BANDS]);
    *end = i < ranges ? r0 + bands[b + 1] : r0 + n;
}

/* Section 13: the prediction's count of points in the cells of the
   predicted view (projector cells) in job j's bytes, and its start and end. */
static void rendercache__count_cells(const void *cells, uint32_t j, uint32_t begin, uint32_t end);
static void rendercache__predict_start(rendercache *rc, const rendercache__view *next);
static void rendercache__predict_finish(rendercache *rc);

/* Projects every point into view v (matrices obj_camera) and z-buffers
   them into rc->splat. Keys only: the points that win a pixel give their
   colour and priority in the depth cull, so that the others (about half)
   cost no read of their colour and no write. With cells (the predicted
   view's projector onto its cells, or NULL) each batch of points is also
   counted in the cells it lands in, while it is in cache: the prediction
   without a second pass over the points. */
static void rendercache__splat_points(rendercache *rc, const rendercache__view *v, const float *obj_camera,
                                      const rendercache__projector *cells, double *t_project)
{
    rendercache__projector pr;
    double t0 = rendercache__now(rc);
    rendercache__projector_init(&pr, rc, v, obj_camera, 0);
    rendercache__splat_run(&rc->splat, rc->parallel_for, rc->parallel_user, rendercache__project_points, NULL,
                           rendercache__point_chunk, rendercache__chunk_count(rc), &pr, rc->capacity,
                           cells ? rendercache__count_cells : NULL, cells);
    if (t_project) *t_project += rendercache__now(rc) - t0;
}

/* Priority of a hole (WDP99, Crespin-Peroche 4.1): the fewer points around
   it, the higher; nothing near gives the maximum. */
static float rendercache__hole_priority(const rendercache *rc, unsigned char kind, uint32_t count)
{
    float window;
    switch (kind) {
    case RENDERCACHE_PIXEL_INTERPOLATED:
        return RENDERCACHE__PRIORITY_INTERP + 0.25f * (float)(8u - count) / 8.0f;
    case RENDERCACHE_PIXEL_SPARSE:
        window = (float)((2 * rc->wide_radius + 1) * (2 * rc->wide_radius + 1) - 1);
        return RENDERCACHE__PRIORITY_SPARSE + 0.2f * (1.0f - (float)count / window);
    default:
        return 1.0f;
    }
}

/* The 8 neighbours in the order W E N S NW NE SW SE, so that bits (0,1),
   (2,3), (4,7) and (5,6) are opposite pairs. */
static const int rendercache__nx[8] = { -1, 1, 0, 0, -1, 1, -1, 1 };
static const int rendercache__ny[8] = { 0, 0, -1, 1, -1, -1, 1, 1 };

/* Depth cull (WDP99): a point much farther than the average depth of the
   points in its 3x3 neighbourhood shows through a nearer surface and is
   dropped. Depths are squared distances here (FLT_MAX where empty), so the
   average is a root mean square and tol2 the squared tolerance factor.
   Refinement: the nearer points must also lie on opposite sides (left and
   right, above and below, or both diagonals), as they do when a far point
   falls into a gap of a nearer surface; a point beside a silhouette has its
   nearer neighbours on one side only and is kept, so a static view keeps
   every sampled point. d: the point's depth (FLT_MAX: no point, never
   culled); nd: the 8 neighbours' depths (order of rendercache__nx).
   Without branches: cull_row's loop over a row vectorises with it. */
static RENDERCACHE__INLINE int rendercache__occluded(float d, const float nd[8], float tol2)
{
    float sum = 0.0f, n = 0.0f;
    int k, e01, e23, ediag;
    for (k = 0; k < 8; k++) {
        sum += nd[k] < FLT_MAX ? nd[k] : 0.0f;
        n += nd[k] < FLT_MAX ? 1.0f : 0.0f;
    }
    e01 = (d > nd[0] * tol2) & (d > nd[1] * tol2);
    e23 = (d > nd[2] * tol2) & (d > nd[3] * tol2);
    ediag = (d > nd[4] * tol2) & (d > nd[5] * tol2) & (d > nd[6] * tol2) & (d > nd[7] * tol2);
    /* enclosed implies n >= 2, so the mean is defined where it matters */
    return (e01 | e23 | ediag) & (d < FLT_MAX) & (d * n > sum * tol2);
}

/* The depths of the 8 neighbours of (x, y), FLT_MAX outside the image. */
static void rendercache__neighbour_depths(const float *depth, uint32_t w, uint32_t h, uint32_t x, uint32_t y,
                                          float nd[8])
{
    int k;
    if (x > 0 && y > 0 && x + 1 < w && y + 1 < h) {
        const float *c = depth + (size_t)y * w + x;
        nd[0] = c[-1]; nd[1] = c[1]; nd[2] = c[-(ptrdiff_t)w]; nd[3] = c[w];
        nd[4] = c[-(ptrdiff_t)w - 1]; nd[5] = c[-(ptrdiff_t)w + 1]; nd[6] = c[w - 1]; nd[7] = c[w + 1];
        return;
    }
    for (k = 0; k < 8; k++) {
        int qx = (int)x + rendercache__nx[k], qy = (int)y + rendercache__ny[k];
        nd[k] = (qx < 0 || qy < 0 || qx >= (int)w || qy >= (int)h) ? FLT_MAX : depth[(size_t)qy * w + (uint32_t)qx];
    }
}

/* The depth cull of the interior pixels x in [1, w-1) of row y: occ[x] = 1
   where the pixel's point is culled. */
static void rendercache__cull_row(const float *depth, uint32_t w, uint32_t y, float tol2, unsigned char *occ)
{
    const float *c = depth + (size_t)y * w, *u = c - w, *l = c + w;
    uint32_t x;
    for (x = 1; x + 1 < w; x++) {
        float nd[8];
        nd[0] = c[x - 1]; nd[1] = c[x + 1]; nd[2] = u[x]; nd[3] = l[x];
        nd[4] = u[x - 1]; nd[5] = u[x + 1]; nd[6] = l[x - 1]; nd[7] = l[x + 1];
        occ[x] = (unsigned char)rendercache__occluded(c[x], nd, tol2);
    }
}

/* The cull decisions of row y (occ[x] = 1: the point at x is culled):
   the interior by rendercache__cull_row, the image border by the general test. */
static void rendercache__cull_decisions(const rendercache *rc, const float *depth, uint32_t y, float tol2,
                                        unsigned char *occ)
{
    const uint32_t w = rc->width, h = rc->height;
    uint32_t x;
    int interior_row = y > 0 && y + 1 < h;
    if (interior_row) rendercache__cull_row(depth, w, y, tol2, occ);
    for (x = 0; x < w; x = interior_row && x == 0 && w > 1 ? w - 1 : x + 1) {   /* border pixels */
        float nd[8];
        uint32_t p = y * w + x;
        rendercache__neighbour_depths(depth, w, h, x, y, nd);
        occ[x] = (unsigned char)rendercache__occluded(depth[p], nd, tol2);
    }
}

/* Job per tile: the depths of the z-buffer's keys as floats (FLT_MAX where
   empty), into select_v (request scratch, free until the requests), for
   the depth cull, which reads each depth nine times. */
static void rendercache__depth_job(void *ctx, uint32_t tile)
{
    rendercache *rc = (rendercache *)ctx;
    const uint64_t *RENDERCACHE__RESTRICT key = rc->splat.zb[0].key;
    float *RENDERCACHE__RESTRICT depth = rc->select_v;
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * rc->width, p1 = p0 + RENDERCACHE__TILE_ROWS * rc->width, p;
    if (p1 > rc->pixel_count) p1 = rc->pixel_count;
    for (p = p0; p < p1; p++) depth[p] = rendercache__key_depth(key[p]);
}

/* What the cull of a tile counts. */
typedef struct rendercache__cull_counts {
    uint32_t visible, culled;
} rendercache__cull_counts;

/* Writes the pixels [p0, p1) of a row after its cull decisions occ (of
   pixel p at occ[p - p0]): a surviving point gives its slot, depth, colour and
   priority to the pixel and is marked as shown; a culled point or no
   point leaves a hole (kind: the decision, for the filling, which writes
   its colour and priority). The slots are anywhere in the cache, so each
   read of a point is a cache miss: the loop asks for the slot of a pixel
   further on ahead of time, so that many misses are under way at once,
   and it does all of a pixel's writing in the same pass, while they
   complete. A hole reads the empty slot after the last (rc->capacity):
   no branch, which points and holes along silhouettes would mispredict. */
static void rendercache__write_row(rendercache *rc, const uint64_t *key, const float *depth, uint32_t p0, uint32_t p1,
                                   uint32_t tile_end, const unsigned char *occ, uint32_t sink, rendercache__cull_counts *n)
{
    const uint32_t empty = rc->capacity;
    const rendercache__point *data = rc->data;
    float *image = rc->image, *priority = rc->priority, *px_depth = rc->px_depth;
    uint32_t *px_index = rc->px_index;
    unsigned char *kind = rc->kind, *count = rc->count, *shown = rc->shown, mark = rendercache__mark(rc->frame);
    uint32_t p;
    for (p = p0; p < p1; p++) {   /* a key's low half is the slot, RENDERCACHE__NONE in the empty key */
        const uint32_t k = (uint32_t)key[p], has = k != RENDERCACHE__NONE, cull = occ[p - p0], shows = has & !cull;
        const uint32_t slot = shows ? k : empty;
        uint32_t motion = rc->obj_motion[rendercache__motion_index(rc, data[slot].object)];
        if (p + RENDERCACHE__GATHER_AHEAD < tile_end) {   /* (into the next row too; the next tile's keys may be
                                                             cleared meanwhile by its own cull) */
            uint32_t next = (uint32_t)key[p + RENDERCACHE__GATHER_AHEAD];
            const rendercache__point *q = &data[next == RENDERCACHE__NONE ? empty : next];
            RENDERCACHE__PREFETCH(q);
            RENDERCACHE__PREFETCH((const char *)q + sizeof *q - 1);   /* a record may straddle two cache lines */
            RENDERCACHE__PREFETCH_WRITE(&shown[next == RENDERCACHE__NONE ? empty : next]);
        }
        memcpy(image + 3 * (size_t)p, data[slot].rgb, 3 * sizeof(float));
        priority[p] = rendercache__point_priority(rc, &data[slot], motion, p, depth[p]);   /* (no lobe in the empty slot) */
        px_index[p] = shows ? k : RENDERCACHE__NONE;
        px_depth[p] = shows ? depth[p] : FLT_MAX;
        shown[shows ? k : sink] = mark;   /* spared by the eviction in this frame */
        kind[p] = (unsigned char)(shows ? (unsigned)RENDERCACHE_PIXEL_POINT : cull);   /* holes: set by the filling */
        count[p] = 0;
        n->visible += shows;
        n->culled += has & cull;
    }
}

/* Job per tile: depth cull; surviving points give their colour, their
   priority and their depth to the pixel, and are marked as shown. The
   kind array holds the cull decisions of a row until the row is written. */
static void rendercache__cull_job(void *ctx, uint32_t tile)
{
    rendercache *rc = (rendercache *)ctx;
    const uint64_t *key = rc->splat.zb[0].key;
    const float *depth = rc->select_v;   /* rendercache__depth_job's */
    const uint32_t w = rc->width, h = rc->height;
    const uint32_t sink = rc->capacity + tile;   /* this tile's byte for pixels without a point */
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, y;
    uint32_t *stats = rc->tile_stats + RENDERCACHE__TILE_STATS * (size_t)tile;
    rendercache__cull_counts n = { 0, 0 };
    float tol2 = (1.0f + rc->depth_tolerance) * (1.0f + rc->depth_tolerance);
    if (y1 > h) y1 = h;
    for (y = y0; y < y1; y++) {
        unsigned char *occ = rc->kind + (size_t)y * w;
        rendercache__cull_decisions(rc, depth, y, tol2, occ);
        rendercache__write_row(rc, key, depth, y * w, y * w + w, y1 * w, occ, sink, &n);
    }
    stats[0] = n.visible;
    stats[1] = n.culled;
    rendercache__splat_clear_tile(&rc->splat, tile);   /* read (the depths are in select_v): clean for the next frame */
}

/* Interpolation of a hole (WDP99 3x3 weighted filter; WDG02 wider filter
   for sparse regions) from the points within radius r, tent weights
   (r+1-|dx|)(r+1-|dy|). Never blends across a depth discontinuity, and
   takes the layer the hole belongs to (depth-aware hole filling,
   rendercache__find_layer): where the points around a hole lie at depths
   that differ by more than the tolerance, a hole that the nearest layer
   encloses (nearest points on opposite sides: the mirror of the depth
   cull) is a gap of that surface, magnified or thin, and takes it; a hole
   beside an object that moved in this frame takes the farther layer, the
   background the object uncovered (a disocclusion). Weighing the layers,
   as the filter still does elsewhere, filled the holes behind a moving
   object with its colour wherever it covered more of the window than the
   background did, and a 3x3 window that sees the object alone says
   nothing of the background a few pixels on: the layers are found along
   rays of RENDERCACHE__HOLE_REACH pixels. Behind the camera's own motion
   the farther layer is no better a guess than the heavier one: a surface
   seen from nearer spreads its points over its own silhouette as often as
   it uncovers the background (measured in the walkthrough's building).
   Depths are squared distances, compared with the squared tolerance.
   Weights are scaled by a power of two that brings their sum below 1, so
   that the sums of finite colours do not overflow and the mean is what it
   would be unscaled, bit for bit. Holes' colours are never read: the
   filling of another tile may be writing them. */
static const float rendercache__black[3] = { 0.0f, 0.0f, 0.0f };

/* The layer a hole takes: the depths (squared) its filters take, [lo, hi]
   (every depth when any: its rays met one layer or none, and the window
   decides); for a disocclusion, the weighted sum of the colours of the
   first points of the farthest layer met along the rays (rgb[3] the
   weight), its fill where no filter window reaches one (0 otherwise: a
   hole of a sparse region stays empty beyond the wide filter's radius). */
typedef struct rendercache__hole_layer {
    int any;
    float lo, hi;
    float rgb[4];
} rendercache__hole_layer;

/* The layer of hole (x, y). Along the 8 directions of rendercache__nx,
   up to RENDERCACHE__HOLE_REACH pixels, the first point met on each ray.
   A point belongs to the nearest layer when its depth is within the
   tolerance of the nearest point's, compounded once per pixel of half the
   distance between the two (a smooth surface's depth changes with the
   distance across it: a slanted plane seen over 8 pixels is one layer).
   All points of one layer, or none: the window decides. Else, when the
   first points on both sides of the row, of the column, or on all four
   diagonals belong to the nearest layer (the depth cull's test of
   opposite sides, rendercache__occluded), the nearest layer; else, when
   a nearest point belongs to an object that moved in this frame, the
   farther points (a disocclusion: what the object uncovered); else the
   window decides. The layers part at the geometric mean of the farthest
   near point and the nearest far one. A ray's point
   weighs 1/8 of the inverse of its distance (so that a sum of 8 finite
   colours stays finite). */
/* Whether object's transform changed in this frame (the background never). */
static int rendercache__moved_now(const rendercache *rc, uint32_t object)
{
    return object < rc->object_count && rc->obj_since[object] == rc->frame;
}

static rendercache__hole_layer rendercache__find_layer(const rendercache *rc, uint32_t x, uint32_t y)
{
    const int w = (int)rc->width, h = (int)rc->height;
    const float *tol_pow = rc->tol2_pow;   /* the squared tolerance factor's powers */
    float first[8], dmin = FLT_MAX, near_max = 0.0f, far_min = FLT_MAX;
    int k, s, step[8], near[8], smin = 0, far = 0, moved = 0;
    uint32_t at[8];
    rendercache__hole_layer layer = { 1, 0.0f, FLT_MAX, { 0, 0, 0, 0 } };
    for (k = 0; k < 8; k++) {
        first[k] = FLT_MAX;
        step[k] = 0;
        at[k] = 0;
        for (s = 1; s <= (int)RENDERCACHE__HOLE_REACH; s++) {
            int qx = (int)x + s * rendercache__nx[k], qy = (int)y + s * rendercache__ny[k];
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) break;
            at[k] = (uint32_t)qy * (uint32_t)w + (uint32_t)qx;
            first[k] = rc->px_depth[at[k]];
            step[k] = s;
            if (first[k] != FLT_MAX) break;
        }
        if (first[k] < dmin) {
            dmin = first[k];
            smin = step[k];
        }
    }
    if (dmin == FLT_MAX) return layer;
    for (k = 0; k < 8; k++) {
        int span = (step[k] + smin + 1) / 2;   /* 1 .. HOLE_REACH */
        near[k] = first[k] <= dmin * tol_pow[span];
        if (first[k] == FLT_MAX) continue;
        if (near[k]) near_max = first[k] > near_max ? first[k] : near_max;
        else far_min = first[k] < far_min ? first[k] : far_min;
        far |= !near[k];
    }
    if (!far) return layer;
    if ((near[0] & near[1]) | (near[2] & near[3]) | (near[4] & near[5] & near[6] & near[7])) {
        layer.any = 0;
        layer.hi = sqrtf(near_max) * sqrtf(far_min);   /* enclosed: the nearest layer */
        return layer;
    }
    /* only now the near points' objects: each is a read at random in the
       cache (a miss), which most holes (one layer, or enclosed) never need */
    for (k = 0; k < 8 && !moved; k++)
        moved = first[k] != FLT_MAX && near[k] && rendercache__moved_now(rc, rc->data[rc->px_index[at[k]]].object);
    if (!moved) return layer;
    layer.any = 0;
    layer.lo = sqrtf(near_max) * sqrtf(far_min);   /* a disocclusion: the farther points */
    for (k = 0; k < 8; k++) {
        if (first[k] == FLT_MAX || first[k] < layer.lo) continue;
        {
            const float *c = rc->image + 3 * (size_t)at[k], wgt = 0.125f / (float)step[k];
            layer.rgb[0] += wgt * c[0]; layer.rgb[1] += wgt * c[1]; layer.rgb[2] += wgt * c[2]; layer.rgb[3] += wgt;
        }
    }
    return layer;
}

/* The weighted sums of the colours of the points in the window [x0, x1] x
   [y0, y1] around (x, y) whose depths lie in [lo, hi] (colour sums, [3]
   the weight); returns their number. */
static RENDERCACHE__INLINE uint32_t rendercache__window_sums(const rendercache *rc, uint32_t x, uint32_t y, int r,
                                                             int x0, int x1, int y0, int y1, float lo, float hi,
                                                             float sum[4])
{
    const float *depth = rc->px_depth, *image = rc->image;
    const uint32_t w = rc->width;
    const float scale = rc->window_scale[r];
    uint32_t n = 0;
    int qx, qy;
    for (qy = y0; qy <= y1; qy++) {
        const float *row = depth + (size_t)qy * w;
        float wy = (float)(r + 1 - rendercache__iabs(qy - (int)y)) * scale;
        for (qx = x0; qx <= x1; qx++) {   /* without branches: points and holes alternate at random */
            float d = row[qx], wgt = wy * (float)(r + 1 - rendercache__iabs(qx - (int)x));
            int take = (d != FLT_MAX) & (d >= lo) & (d <= hi);
            const float *c = take ? image + 3 * ((size_t)qy * w + (size_t)qx) : rendercache__black;
            float wt = take ? wgt : 0.0f;
            sum[0] += wt * c[0]; sum[1] += wt * c[1]; sum[2] += wt * c[2]; sum[3] += wt;
            n += (uint32_t)take;
        }
    }
    return n;
}

/* The filter of radius r over the window [x0, x1] x [y0, y1] (the image's
   part of it), of the points of the hole's layer; with no layer known
   (any), the window's own: every point when their depths agree, else its
   nearest layer (within the tolerance of the minimum) or its farthest
   (within the tolerance of the maximum), whichever carries more weight
   (the far one on a tie: a hole beside an edge is more often uncovered
   background). Returns the number of points taken; rgb is set when it is
   not zero. */
static RENDERCACHE__INLINE uint32_t rendercache__interpolate_window(const rendercache *rc, uint32_t x, uint32_t y, int r,
                                                                    int x0, int x1, int y0, int y1,
                                                                    rendercache__hole_layer layer, float tol2, float rgb[3])
{
    float sum[4] = { 0, 0, 0, 0 }, far_sum[4] = { 0, 0, 0, 0 };
    uint32_t n;
    if (!layer.any) {
        n = rendercache__window_sums(rc, x, y, r, x0, x1, y0, y1, layer.lo, layer.hi, sum);
    } else {
        float dmin = FLT_MAX, dmax = 0.0f;
        int qx, qy;
        for (qy = y0; qy <= y1; qy++)
            for (qx = x0; qx <= x1; qx++) {
                float d = rc->px_depth[(size_t)qy * rc->width + (size_t)qx];
                dmin = d < dmin ? d : dmin;
                dmax = d != FLT_MAX && d > dmax ? d : dmax;
            }
        if (dmin == FLT_MAX) return 0;
        n = rendercache__window_sums(rc, x, y, r, x0, x1, y0, y1, 0.0f, dmin * tol2, sum);
        if (dmax > dmin * tol2) {   /* two layers: a middle one (if any) takes neither side */
            float far_lo = dmax / tol2 > dmin * tol2 ? dmax / tol2 : nextafterf(dmin * tol2, FLT_MAX);
            uint32_t n_far = rendercache__window_sums(rc, x, y, r, x0, x1, y0, y1, far_lo, FLT_MAX, far_sum);
            if (far_sum[3] >= sum[3]) {
                memcpy(sum, far_sum, sizeof sum);
                n = n_far;
            }
        }
    }
    if (n == 0) return 0;
    rgb[0] = rendercache__finitef(sum[0] / sum[3]);
    rgb[1] = rendercache__finitef(sum[1] / sum[3]);
    rgb[2] = rendercache__finitef(sum[2] / sum[3]);
    return n;
}

/* The window of radius r around (x, y), clipped to the image. */
static uint32_t rendercache__interpolate(const rendercache *rc, uint32_t x, uint32_t y, int r, rendercache__hole_layer layer,
                                         float tol2, float rgb[3])
{
    int x0 = (int)x - r, x1 = (int)x + r, y0 = (int)y - r, y1 = (int)y + r;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 >= (int)rc->width) x1 = (int)rc->width - 1;
    if (y1 >= (int)rc->height) y1 = (int)rc->height - 1;
    return rendercache__interpolate_window(rc, x, y, r, x0, x1, y0, y1, layer, tol2, rgb);
}

/* The 3x3 window of a hole inside the image (nearly all of them): a fixed
   window, whose loops the compiler unrolls; the same operations in the same
   order as rendercache__interpolate, so the same colour bit for bit. */
static uint32_t rendercache__interpolate3(const rendercache *rc, uint32_t x, uint32_t y, rendercache__hole_layer layer,
                                          float tol2, float rgb[3])
{
    return rendercache__interpolate_window(rc, x, y, 1, (int)x - 1, (int)x + 1, (int)y - 1, (int)y + 1, layer, tol2,
                                           rgb);
}

/* Fills hole (x, y) (a pixel showing no point) from the points around it
   and ranks it; returns its kind. */
static unsigned char rendercache__fill_hole(rendercache *rc, uint32_t x, uint32_t y)
{
    const uint32_t w = rc->width, h = rc->height, p = y * w + x;
    uint32_t n;
    unsigned char kind;
    float rgb[3], tol2 = (1.0f + rc->depth_tolerance) * (1.0f + rc->depth_tolerance);
    rendercache__hole_layer layer = rendercache__find_layer(rc, x, y);
    n = x > 0 && y > 0 && x + 1 < w && y + 1 < h ? rendercache__interpolate3(rc, x, y, layer, tol2, rgb)
                                                 : rendercache__interpolate(rc, x, y, 1, layer, tol2, rgb);
    if (n >= rc->sparse_neighbours) {   /* (points of its layer: a hole beside a disocclusion's edge takes the
                                           wide filter when its 3x3 window shows the nearer surface alone) */
        kind = RENDERCACHE_PIXEL_INTERPOLATED;
    } else {
        n = rendercache__interpolate(rc, x, y, (int)rc->wide_radius, layer, tol2, rgb);
        if (n == 0 && layer.rgb[3] > 0.0f) {   /* its layer lies beyond the wide window: the rays' points */
            rgb[0] = rendercache__finitef(layer.rgb[0] / layer.rgb[3]);
            rgb[1] = rendercache__finitef(layer.rgb[1] / layer.rgb[3]);
            rgb[2] = rendercache__finitef(layer.rgb[2] / layer.rgb[3]);
            n = 1;
        }
        kind = n ? RENDERCACHE_PIXEL_SPARSE : RENDERCACHE_PIXEL_EMPTY;
        if (!n) memcpy(rgb, rc->background, sizeof rgb);
    }
    rc->kind[p] = kind;
    rc->count[p] = (unsigned char)(n > 255 ? 255 : n);
    rc->priority[p] = rendercache__hole_priority(rc, kind, rc->count[p]);
    rc->image[3 * (size_t)p + 0] = rgb[0];   /* stores a race detector sees, unlike an inlined memcpy */
    rc->image[3 * (size_t)p + 1] = rgb[1];
    rc->image[3 * (size_t)p + 2] = rgb[2];
    return kind;
}

/* Job per tile: fill the holes left by projection and cull, and rank them. */
static void rendercache__interpolate_job(void *ctx, uint32_t tile)
{
    rendercache *rc = (rendercache *)ctx;
    const uint32_t w = rc->width, h = rc->height, *px_index = rc->px_index;
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, x, y;
    uint32_t counts[4] = { 0, 0, 0, 0 }, *stats = rc->tile_stats + RENDERCACHE__TILE_STATS * (size_t)tile;
    if (y1 > h) y1 = h;
    for (y = y0; y < y1; y++) {
        const uint32_t *row = px_index + (size_t)y * w;
        for (x = 0;; x++) {
            while (x < w && row[x] != RENDERCACHE__NONE) x++;   /* to the next hole (a few percent of the pixels) */
            if (x == w) break;
            counts[rendercache__fill_hole(rc, x, y)]++;
        }
    }
    stats[2] = counts[RENDERCACHE_PIXEL_INTERPOLATED];
    stats[3] = counts[RENDERCACHE_PIXEL_SPARSE];
    stats[4] = counts[RENDERCACHE_PIXEL_EMPTY];
}

/* Whether the cull of the tiles [a, b) fills tile t (a <= t < b) right
   after culling the tile below it (or after its own cull, for the last
   tile of the image): when the tile above it is culled by the same range
   too, or there is none. Else a second pass fills it, after every range
   has culled (rendercache__cull_and_interpolate). */
static int rendercache__filled_with_cull(uint32_t a, uint32_t b, uint32_t t, uint32_t tile_count)
{
    return (t > a || a == 0) && (t + 1 < b || b == tile_count);
}

/* The cull and the hole filling of the tiles [a, b), interleaved: the
   holes of tile t - 1 are filled right after the cull of tile t, while the
   rows both touch (the depths and colours around a hole) are still in
   cache; as two passes, the filling read them back from memory, about one
   miss per hole and row. A hole reads at most RENDERCACHE__HOLE_REACH
   (TILE_ROWS = 8) rows below its own and above it (its rays; its filters
   wide_radius <= 7), which the cull of the tiles before and after has
   written, so the filling reads what it read after a full cull pass: the
   same image, bit for bit. A tile whose neighbour above lies in another
   range is left to rendercache__fill_range_ends (filled_with_cull). With
   depths set, the depths of tile t + 1 are converted from the keys just
   before the cull of tile t reads them (one range over the whole image:
   the cull of a range clears its keys, which the range above would read). */
static void rendercache__cull_fill_range(rendercache *rc, uint32_t a, uint32_t b, int depths)
{
    uint32_t t;
    for (t = a; t <= b; t++) {
        if (depths && t == a) rendercache__depth_job(rc, a);
        if (depths && t + 1 < b) rendercache__depth_job(rc, t + 1);   /* the rows below tile t */
        if (t < b) rendercache__cull_job(rc, t);
        if (t > a && rendercache__filled_with_cull(a, b, t - 1, rc->tile_count)) rendercache__interpolate_job(rc, t - 1);
    }
}

/* The tiles of range r of RENDERCACHE__CULL_JOBS: [*a, *b). */
static void rendercache__cull_range(const rendercache *rc, uint32_t r, uint32_t *a, uint32_t *b)
{
    *a = (uint32_t)((uint64_t)rc->tile_count * r / RENDERCACHE__CULL_JOBS);
    *b = (uint32_t)((uint64_t)rc->tile_count * (r + 1) / RENDERCACHE__CULL_JOBS);
}

/* Job per range: its cull and filling (the depths were converted before). */
static void rendercache__cull_fill_job(void *ctx, uint32_t r)
{
    rendercache *rc = (rendercache *)ctx;
    uint32_t a, b;
    rendercache__cull_range(rc, r, &a, &b);
    rendercache__cull_fill_range(rc, a, b, 0);
}

/* Job per range: the filling of its tiles that its cull could not fill
   (their neighbour above is another range's, culled now). */
static void rendercache__fill_range_ends(void *ctx, uint32_t r)
{
    rendercache *rc = (rendercache *)ctx;
    uint32_t a, b, t;
    rendercache__cull_range(rc, r, &a, &b);
    for (t = a; t < b; t++)
        if (!rendercache__filled_with_cull(a, b, t, rc->tile_count)) rendercache__interpolate_job(rc, t);
}

/* The depth cull and the hole filling of the frame: on the calling thread
   one range of every tile; with parallel_for the depths first, then
   RENDERCACHE__CULL_JOBS ranges of tiles in parallel, each culling and
   filling as the calling thread does, then the tiles at the ranges' ends
   (a filling reads only rows culled by then, so the image is the same for
   any thread count). The two are timed together (stats.time_cull): a
   clock read per tile would cost more than the saving. */
static void rendercache__cull_and_interpolate(rendercache *rc)
{
    double t0 = rendercache__now(rc);
    if (rc->parallel_for) {
        rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__depth_job, rc, rc->tile_count);
        rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__cull_fill_job, rc, RENDERCACHE__CULL_JOBS);
        rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__fill_range_ends, rc, RENDERCACHE__CULL_JOBS);
    } else {
        rendercache__cull_fill_range(rc, 0, rc->tile_count, 1);
    }
    rc->stats.time_cull = rendercache__now(rc) - t0;
    rc->stats.time_interpolate = 0.0;
}

/* ---- image order of the point cache -----------------------------------
   Points are stored in slots in the order they came (insertion, eviction),
   so the projection's z-tests and the cull's reads of the points that win
   a pixel land at random in tens of megabytes: one cache miss each. Where
   the slots of neighbouring pixels are neighbours too, the same accesses
   share cache lines and pages. So each frame, before the projection,
   re-sorts a share of the cache (RENDERCACHE__SORT_SHARE: all of it every
   8 frames), range by range of RENDERCACHE__SORT_RANGE slots: the points
   of a range are grouped by the block of pixels (a run of at most 1/2048
   of the image, half a row at 512x512) they project to in the frame's
   camera, those outside the image and free slots last, in a stable
   counting sort whose scratch stays in cache. Points never leave their
   range, so a frame sorts a fixed amount at a fixed cost; a camera that
   moves a little keeps a sorted range nearly in image order. Nothing
   refers to a slot between frames (the pixels' slots are found again by
   the projection that follows), and which slot holds a point changes the
   image only through the z-buffer's tie-break of equal depths and the
   order in which the eviction's clock meets points not visible. */

/* Moves the n 4-byte words at a to their places to[i] (through scratch,
   n words at least). */
static void rendercache__permute(void *a, const uint32_t *to, uint32_t n, void *scratch)
{
    uint32_t *w = (uint32_t *)a, *t = (uint32_t *)scratch, i;
    for (i = 0; i < n; i++) t[to[i]] = w[i];
    memcpy(w, t, (size_t)n * sizeof *w);
}

/* Re-sorts slots [r0, r0 + n) by the pixel block their points project to
   in the current view (rendercache__project_points: where the z-buffer
   will test them). */
static void rendercache__sort_range(rendercache *rc, uint32_t r0, uint32_t n, uint32_t *scratch)
{
    const uint32_t range = rendercache__sort_range_size(rc), none_key = (rc->pixel_count >> rc->sort_shift) + 1u;
    uint32_t count[RENDERCACHE__SORT_KEYS], *pix = scratch, *to = pix + range, b, i, k, sum;
    uint32_t *bands = rc->sort_bands + (size_t)(r0 / range) * (RENDERCACHE__SORT_BANDS + 1);
    rendercache__point *data = (rendercache__point *)(to + range);   /* the records in their new order */
    float depth2[RENDERCACHE__BATCH];
    rendercache__projector pr;
    rendercache__projector_init(&pr, rc, &rc->view, rc->obj_camera, 0);
    for (b = 0; b < n; b += RENDERCACHE__BATCH) {
        uint32_t m = n - b < RENDERCACHE__BATCH ? n - b : RENDERCACHE__BATCH;
        rendercache__project_points(&pr, r0 + b, r0 + b + m, pix + b, depth2);
    }
    memset(count, 0, sizeof count);
    for (i = 0; i < n; i++) {   /* the key of each slot, and how many slots each key has */
        pix[i] = pix[i] == RENDERCACHE__NONE ? none_key : pix[i] >> rc->sort_shift;
        count[pix[i]]++;
    }
    for (k = 0, sum = 0; k <= none_key; k++) {
        uint32_t c = count[k];
        count[k] = sum;
        sum += c;
    }
    for (b = 0; b <= RENDERCACHE__SORT_BANDS; b++)   /* band b: the keys from ceil(b none_key / BANDS) on */
        bands[b] = count[(uint32_t)(((uint64_t)b * none_key + RENDERCACHE__SORT_BANDS - 1) / RENDERCACHE__SORT_BANDS)];
    for (i = 0; i < n; i++) to[i] = count[pix[i]]++;   /* the new place of each slot (stable) */
    /* the points move in their order, read as a stream (the range is not in cache yet), and land in the
       scratch, which is */
    for (i = 0; i < n; i++) data[to[i]] = rc->data[r0 + i];
    memcpy(rc->data + r0, data, (size_t)n * sizeof *data);
    rendercache__permute(rc->geo.x + r0, to, n, data);
    rendercache__permute(rc->geo.y + r0, to, n, data);
    rendercache__permute(rc->geo.z + r0, to, n, data);
    rendercache__permute(rc->geo.object + r0, to, n, data);
    /* (the shown marks stay: before the cull every mark is an earlier frame's, which no test compares equal) */
}

/* Job j of the re-sort: ranges of this frame's share (the k-th from
   rc->sort_next on), in its own scratch. With atomics each job takes the
   next range left until none is, so that a job the system holds back
   holds back one range, not half of them; else job j takes its half. */
static void rendercache__sort_job(void *ctx, uint32_t j)
{
    rendercache *rc = (rendercache *)ctx;
    const uint32_t range = rendercache__sort_range_size(rc), ranges = rendercache__sort_ranges(rc);
    const uint32_t count = rendercache__sort_range_count(rc), jobs = rendercache__sort_jobs(rc);
    const size_t scratch_words = (size_t)range * (2 + sizeof(rendercache__point) / sizeof(uint32_t));
    uint32_t k = count * j / jobs, end = count * (j + 1) / jobs;
#if RENDERCACHE__ATOMICS
    k = __atomic_fetch_add(&rc->sort_taken, 1u, __ATOMIC_RELAXED);
    end = count;
#endif
    while (k < end) {
        uint32_t r = (rc->sort_next + k) % ranges, r0 = r * range, n = rc->capacity - r0 < range ? rc->capacity - r0 : range;
        rendercache__sort_range(rc, r0, n, rc->sort_scratch + scratch_words * j);
#if RENDERCACHE__ATOMICS
        k = __atomic_fetch_add(&rc->sort_taken, 1u, __ATOMIC_RELAXED);
#else
        k++;
#endif
    }
}

/* This frame's share of the re-sort: the next sort_range_count ranges round the
   cache, in sort_jobs jobs (ranges are disjoint: any schedule gives the
   same cache). */
static void rendercache__sort_share(rendercache *rc)
{
    const uint32_t ranges = rendercache__sort_ranges(rc);
    double t0 = rendercache__now(rc);
    rc->sort_taken = 0;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__sort_job, rc, rendercache__sort_jobs(rc));
    rc->sort_next = (rc->sort_next + rendercache__sort_range_count(rc)) % ranges;
    rc->stats.time_sort = rendercache__now(rc) - t0;
}

/* Sums one column of the per-tile statistics. */
static uint32_t rendercache__tile_sum(const rendercache *rc, uint32_t column)
{
    uint32_t t, sum = 0;
    for (t = 0; t < rc->tile_count; t++) sum += rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)t + column];
    return sum;
}

static void rendercache__start_stats(rendercache *rc)
{
    rendercache_stats *s = &rc->stats;
    s->frame = rc->frame;
    s->requested = s->predicted = s->inserted = s->replaced = s->evicted = s->rejected = 0;
    s->late = s->changed = s->dropped = 0;
    s->time_project = s->time_cull = s->time_interpolate = 0.0;
    s->time_predict = s->time_request = s->time_insert = s->time_sort = 0.0;
}

/* Whether camera is one the cache can project into (perspective, of the
   cache's size), into v. */
static int rendercache__frame_view(const rendercache *rc, const rendercache_camera *camera, rendercache__view *v)
{
    return rendercache__view_init(v, camera) && camera->width == rc->width && camera->height == rc->height &&
           camera->kind == RENDERCACHE_CAMERA_PERSPECTIVE;
}

/* begin_frame into view v, and with next (or NULL) the prediction for
   that view in the same pass over the points. */
static void rendercache__begin(rendercache *rc, const rendercache__view *v, const rendercache__view *next)
{
    rendercache__frame_record *record;
    rendercache__projector cells;
    rc->frame++;
    if (rendercache__mark(rc->frame) == 1u) memset(rc->shown, 0, (size_t)rc->capacity + rc->tile_count);
    rc->view = *v;
    rc->has_prediction = 0;
    rc->hand_exhausted = 0;
    record = &rc->history[rc->frame % ((uint64_t)rc->max_latency + 1)];
    memset(record, 0, sizeof *record);
    record->frame = rc->frame;
    record->view = *v;
    memcpy(rc->eyes[rc->frame % RENDERCACHE__EYE_FRAMES][0], v->eye, sizeof v->eye);
    memcpy(rc->eyes[rc->frame % RENDERCACHE__EYE_FRAMES][1], v->eye, sizeof v->eye);   /* until a prediction */
    rendercache__start_stats(rc);
    rendercache__change_level(rc);
    rendercache__commit_transforms(rc);
    rendercache__compose_objects(rc, &rc->view, rc->obj_camera);
    rendercache__sort_share(rc);
    if (next) {
        rendercache__predict_start(rc, next);
        rendercache__projector_init(&cells, rc, &rc->predicted, rc->obj_predicted, RENDERCACHE__CELL_SHIFT);
    }
    rendercache__splat_points(rc, &rc->view, rc->obj_camera, next ? &cells : NULL, &rc->stats.time_project);
    if (next) rendercache__predict_finish(rc);
    rendercache__cull_and_interpolate(rc);
    rc->splat.clean = 1;   /* every cull job cleared its keys */
    rc->stats.projected = rc->splat.projected;
    rc->stats.visible = rendercache__tile_sum(rc, 0);
    rc->stats.culled = rendercache__tile_sum(rc, 1);
    rc->stats.interpolated = rendercache__tile_sum(rc, 2);
    rc->stats.sparse = rendercache__tile_sum(rc, 3);
    rc->stats.empty = rendercache__tile_sum(rc, 4);
    rc->stats.live_points = rc->live;
    rc->has_frame = 1;
}

RENDERCACHE_API rendercache_result rendercache_begin_frame(rendercache *rc, const rendercache_camera *camera)
{
    rendercache__view v;
    if (!rc || !rendercache__frame_view(rc, camera, &v)) {
        if (rc && rc->log) rc->log(rc->log_user, "rendercache_begin_frame: invalid camera or image size");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    rendercache__begin(rc, &v, NULL);
    return RENDERCACHE_OK;
}

/* ======================================================================
   13. predictive sampling (Walter et al. 2002): the cache projected into
   the camera expected next, into an occupancy image of 1/16 the
   resolution (cells of 4 x 4 pixels, no depth): cells that fewer than
   RENDERCACHE__CELL_FEW points land in are regions the motion will
   uncover (where the cache shows a surface, about one point lands per
   pixel). A request goes to one pixel of such a cell (its place in the
   cell varies from frame to frame), so a share of the budget seeds a large
   uncovered region sparsely, and the wide filter fills it when it comes
   into view.
   ---------------------------------------------------------------------- */
typedef struct rendercache__predict_job {
    rendercache__projector pr;
    uint32_t jobs;
} rendercache__predict_job;

/* The byte arrays of the count: one per job (RENDERCACHE__CELL_JOBS with
   parallel_for, which covers the jobs of a splat too), each a count per
   cell up to 255 and RENDERCACHE__CELL_SINKS bytes for the points that
   miss (rendercache__cell_stride). A count up to
   255 is the same whatever the order or the split of the points. */
static uint32_t rendercache__cell_arrays(const rendercache *rc)
{
    return rc->parallel_for ? RENDERCACHE__CELL_JOBS : 1u;
}
typedef char rendercache__cell_arrays_cover_splat_jobs[RENDERCACHE__SHARED_JOBS <= RENDERCACHE__CELL_JOBS ? 1 : -1];

/* Adds inc (1 or 2) to a count, up to 255: the same as adding 1 inc times. */
static RENDERCACHE__INLINE void rendercache__count_add(unsigned char *o, uint32_t inc)
{
    uint32_t v = *o + inc;
    *o = (unsigned char)(v < 255u ? v : 255u);
}

/* Counts points [begin, end) in the cells of the projector (pr; its
   cells) they land in, in job j's bytes. Without a branch, two points at
   a time. An increment waits for the store of the one before when both
   are of one byte, and neighbouring points often are (the cache is in
   image order): so the misses (a third of the points, in runs) take the
   sinks in turn, and a pair in one cell adds 2 at once (the second point
   then counts in a sink). Before, the misses' chain in one byte took a
   quarter of the count's time, and pairs in one cell a fifth. A pair of
   misses counts nowhere (a branch, predicted in the misses' runs). */
static void rendercache__count_cells(const void *pr, uint32_t j, uint32_t begin, uint32_t end)
{
    const rendercache *rc = ((const rendercache__projector *)pr)->rc;
    const uint32_t cells = rc->cell_count;
    unsigned char *occ = rc->occupancy + (size_t)j * rendercache__cell_stride(rc);
    uint32_t cell[RENDERCACHE__BATCH + 1], b, i;
    float d[RENDERCACHE__BATCH];
    for (b = begin; b < end; b += RENDERCACHE__BATCH) {
        uint32_t n = end - b < RENDERCACHE__BATCH ? end - b : RENDERCACHE__BATCH;
        rendercache__project_points(pr, b, b + n, cell, d);
        cell[n] = RENDERCACHE__NONE;   /* an odd count's pair: a miss */
        for (i = 0; i < n; i += 2) {
            const uint32_t s0 = cells + (i & (RENDERCACHE__CELL_SINKS - 1u)), s1 = s0 + 1u;   /* (SINKS even) */
            const uint32_t c0 = cell[i] == RENDERCACHE__NONE ? s0 : cell[i];
            const uint32_t c1 = cell[i + 1] == RENDERCACHE__NONE ? s1 : cell[i + 1], same = c0 == c1;
            if ((cell[i] & cell[i + 1]) == RENDERCACHE__NONE) continue;   /* two misses: nothing to count */
            rendercache__count_add(&occ[c0], 1u + same);
            rendercache__count_add(&occ[same ? s1 : c1], 1u);
        }
    }
}

/* Job j: counts the points of its range in each cell, in its own bytes. */
static void rendercache__occupancy_job(void *ctx, uint32_t j)
{
    const rendercache__predict_job *job = (const rendercache__predict_job *)ctx;
    const uint32_t capacity = job->pr.rc->capacity;
    rendercache__count_cells(&job->pr, j, (uint32_t)((uint64_t)capacity * j / job->jobs),
                             (uint32_t)((uint64_t)capacity * (j + 1) / job->jobs));
}

/* The predicted view of this frame, its matrices, and empty counts. */
static void rendercache__predict_start(rendercache *rc, const rendercache__view *next)
{
    rc->predicted = *next;
    rc->history[rc->frame % ((uint64_t)rc->max_latency + 1)].predicted = *next;
    rc->history[rc->frame % ((uint64_t)rc->max_latency + 1)].has_prediction = 1;
    memcpy(rc->eyes[rc->frame % RENDERCACHE__EYE_FRAMES][1], next->eye, sizeof next->eye);
    rendercache__compose_objects(rc, &rc->predicted, rc->obj_predicted);
    memset(rc->occupancy, 0, rendercache__cell_stride(rc) * rendercache__cell_arrays(rc));
}

/* The counts of the jobs summed into the first array (up to 255), and the
   cells with fewer than RENDERCACHE__CELL_FEW points counted. */
static void rendercache__predict_finish(rendercache *rc)
{
    const uint32_t arrays = rendercache__cell_arrays(rc);
    uint32_t j, c;
    rc->pred_cells = 0;
    for (c = 0; c < rc->cell_count; c++) {
        uint32_t sum = rc->occupancy[c];
        for (j = 1; j < arrays; j++) sum += rc->occupancy[(size_t)j * rendercache__cell_stride(rc) + c];
        rc->occupancy[c] = (unsigned char)(sum < 255u ? sum : 255u);
        rc->pred_cells += sum < RENDERCACHE__CELL_FEW;
    }
    rc->has_prediction = 1;
}

RENDERCACHE_API rendercache_result rendercache_predict(rendercache *rc, const rendercache_camera *next)
{
    rendercache__predict_job job;
    rendercache__view v;
    double t0;
    if (!rc || !rc->has_frame || !rendercache__frame_view(rc, next, &v)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    t0 = rendercache__now(rc);
    rendercache__predict_start(rc, &v);
    rendercache__projector_init(&job.pr, rc, &rc->predicted, rc->obj_predicted, RENDERCACHE__CELL_SHIFT);
    job.jobs = rendercache__cell_arrays(rc);
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__occupancy_job, &job, job.jobs);
    rendercache__predict_finish(rc);
    rc->stats.time_predict += rendercache__now(rc) - t0;
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_begin_frame_predicted(rendercache *rc, const rendercache_camera *camera,
                                                                     const rendercache_camera *next)
{
    rendercache__view v, n;
    if (!rc || !rendercache__frame_view(rc, camera, &v) || !rendercache__frame_view(rc, next, &n)) {
        if (rc && rc->log) rc->log(rc->log_user, "rendercache_begin_frame_predicted: invalid camera or image size");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    rendercache__begin(rc, &v, &n);
    return RENDERCACHE_OK;
}

/* ======================================================================
   14. sample selection: thresholding and error diffusion of the priority
   image (WDP99, after Floyd and Steinberg 1976).
   Thresholding: priorities are binned into RENDERCACHE__LEVELS levels; the
   levels above a cut level, all of whose pixels fit the budget, are taken
   whole (value 1); the cut level gets the fraction of the budget left
   (value in (0, 1)); lower levels get 0. So holes are served before old
   points, and old points before young ones.
   Error diffusion: Floyd-Steinberg on these values in serpentine order
   spreads the fractional level's requests evenly (with a modulated
   threshold for sparse levels, see below). Pixels of value 0 or 1 are
   decided outright and pass incoming error on unchanged; error that would
   leave the image (or its band) goes to the next pixel in scan order
   instead, so the count equals the budget up to each band's last residual,
   which a final pass corrects with the pixels closest to the threshold.
   Each decision depends on the previous ones, so a band is serial; the
   bands of 128 rows run in parallel, and everything around them in tiles.
   ---------------------------------------------------------------------- */
typedef struct rendercache__select_job {
    rendercache *rc;
    const float *priority;
    uint32_t cut;
    float fraction;
} rendercache__select_job;

/* The histogram level of a priority in [0, 1] (anything else: level 0). */
static uint32_t rendercache__level(float priority)
{
    float l = priority * (float)RENDERCACHE__LEVELS;
    l = l > 0.0f ? l : 0.0f;
    l = l < (float)(RENDERCACHE__LEVELS - 1) ? l : (float)(RENDERCACHE__LEVELS - 1);
    return (uint32_t)l;
}

/* Job per tile: the histogram of the positive priorities. Without a
   branch on the sign (priorities of every level mix in an image, so it
   would be mispredicted): a pixel of priority 0 adds 0 to level 0. */
static void rendercache__histogram_job(void *ctx, uint32_t tile)
{
    const rendercache__select_job *j = (const rendercache__select_job *)ctx;
    const rendercache *rc = j->rc;
    const float *priority = j->priority;
    uint32_t *h = rc->hist + (size_t)tile * RENDERCACHE__LEVELS;
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * rc->width, p1 = p0 + RENDERCACHE__TILE_ROWS * rc->width, p;
    if (p1 > rc->pixel_count) p1 = rc->pixel_count;
    memset(h, 0, RENDERCACHE__LEVELS * sizeof *h);
    for (p = p0; p < p1; p++) h[rendercache__level(priority[p])] += (uint32_t)(priority[p] > 0.0f);
}

/* Job per tile: the pixels decided outright, and those left to the error
   diffusion (all of value fraction). Written without branches, so that it
   vectorises. */
static void rendercache__threshold_job(void *ctx, uint32_t tile)
{
    const rendercache__select_job *j = (const rendercache__select_job *)ctx;
    rendercache *rc = j->rc;
    const float *RENDERCACHE__RESTRICT priority = j->priority;
    const uint32_t cut = j->cut;
    const uint32_t at_cut = j->fraction >= 1.0f ? 1u : 2u;   /* a whole level fits: chosen outright */
    unsigned char *RENDERCACHE__RESTRICT chosen = rc->chosen;
    uint32_t p0 = tile * RENDERCACHE__TILE_ROWS * rc->width, p1 = p0 + RENDERCACHE__TILE_ROWS * rc->width, p, ones = 0;
    if (p1 > rc->pixel_count) p1 = rc->pixel_count;
    for (p = p0; p < p1; p++) {
        float pr = priority[p];
        uint32_t l = rendercache__level(pr), positive = pr > 0.0f;
        /* 1: chosen outright; 2: fractional (value: the cut's fraction), for the error diffusion */
        uint32_t c = (positive & (l > cut)) | ((positive & (l == cut)) * at_cut);
        chosen[p] = (unsigned char)c;
        ones += c == 1u;
    }
    rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)tile + 5] = ones;
}

/* The first of the pixels x, x + dir, x + 2 dir, ... of a row (before x
   reaches end) whose chosen byte has one of the bits of mask, or end. Runs
   of eight bytes without are skipped at once: the selection scans every
   pixel of the image but marks a few percent of them. */
static int rendercache__next_marked(const unsigned char *row, int x, int end, int dir, unsigned char mask)
{
    const uint64_t bits = 0x0101010101010101ull * mask;
    while (x != end) {
        int lo = dir > 0 ? x : x - 7;   /* the 8 bytes ahead, in the direction of travel */
        uint64_t word;
        if ((dir > 0 ? end - x : x - end) >= 8) {
            memcpy(&word, row + lo, sizeof word);
            if (!(word & bits)) { x += 8 * dir; continue; }
        }
        if (row[x] & mask) return x;
        x += dir;
    }
    return end;
}

/* Finds the cut level and its fraction so that the values sum to budget
   (or to the number of positive pixels when fewer). */
static void rendercache__find_cut(rendercache *rc, uint32_t budget, uint32_t *cut, float *fraction)
{
    uint32_t *total = rc->hist + (size_t)rc->tile_count * RENDERCACHE__LEVELS, t, l;
    uint64_t above = 0;
    memset(total, 0, RENDERCACHE__LEVELS * sizeof *total);
    for (t = 0; t < rc->tile_count; t++) {
        const uint32_t *h = rc->hist + (size_t)t * RENDERCACHE__LEVELS;
        for (l = 0; l < RENDERCACHE__LEVELS; l++) total[l] += h[l];
    }
    *cut = 0;
    *fraction = 1.0f;
    for (l = RENDERCACHE__LEVELS; l-- > 0;) {
        if (above + total[l] >= budget) {
            *cut = l;
            *fraction = (float)((double)(budget - above) / (double)total[l]);
            return;
        }
        above += total[l];
    }
}

/* Whether pixel q takes part in the diffusion (its value is fractional). */
static int rendercache__fractional(const rendercache *rc, uint32_t q)
{
    return (rc->chosen[q] & 2u) != 0;
}

/* Hands the error e of pixel (x, y) to its unvisited neighbours with the
   Floyd-Steinberg weights 7/16 ahead, 3/16 behind-below, 5/16 below, 1/16
   ahead-below. A weight whose neighbour lies outside the image goes to the
   pixel below instead (ahead on the last row); then only fractional
   neighbours keep their weight, renormalised, so error never lands on a
   pixel whose choice is already made (it would be lost there). Returns the
   part that found no taker, for the next fractional pixel in scan order. */
static float rendercache__spread_error(const rendercache *rc, float *cur, float *next, uint32_t y, uint32_t y_end, int x,
                                       int dir, float e)
{
    const int w = (int)rc->width, ax = x + dir, bx = x - dir, ahead = ax >= 0 && ax < w, behind = bx >= 0 && bx < w;
    const uint32_t row = y * rc->width, row_below = row + rc->width;
    float w_ahead, w_behind_below, w_below, w_ahead_below, sum, s;
    if (y + 1 >= y_end) {   /* last row: everything ahead, if there is an ahead */
        if (!ahead || !rendercache__fractional(rc, row + (uint32_t)ax)) return e;
        cur[ax + 1] += e;
        return 0.0f;
    }
    /* Without branches on the neighbours, which are fractional or not at random along the level's edges
       (a miss predicted wrong costs more than the loads): weight 0 where the neighbour is outside (its
       weight went below) or decided already. The out-of-range index reads x instead (the weight is 0
       anyway), and an addition of 0 times s lands in a cell no fractional pixel reads (or the row's
       padding), so every cell a later pixel reads gets what it got with branches, bit for bit. */
    w_ahead = ahead & rendercache__fractional(rc, row + (uint32_t)(ahead ? ax : x)) ? 7.0f : 0.0f;
    w_behind_below = behind & rendercache__fractional(rc, row_below + (uint32_t)(behind ? bx : x)) ? 3.0f : 0.0f;
    w_below = rendercache__fractional(rc, row_below + (uint32_t)x) ? 5.0f + (ahead ? 0.0f : 8.0f) + (behind ? 0.0f : 3.0f)
                                                                  : 0.0f;
    w_ahead_below = ahead & rendercache__fractional(rc, row_below + (uint32_t)(ahead ? ax : x)) ? 1.0f : 0.0f;
    sum = w_ahead + w_behind_below + w_below + w_ahead_below;
    if (sum == 0.0f) return e;
    s = e / sum;
    cur[ax + 1] += w_ahead * s;
    next[bx + 1] += w_behind_below * s;
    next[x + 1] += w_below * s;
    next[ax + 1] += w_ahead_below * s;
    return 0.0f;
}

/* Threshold modulation (Knuth 1987; Eschbach and Knox 1991): a sparse
   level under plain Floyd-Steinberg chooses nothing until the error has
   piled up to 0.5, and it spreads sideways while it does, so the first rows
   of the image starve and choices come in bursts. A threshold varied per
   pixel by up to +-amp breaks that up; it fades out as the level gets
   denser (no transient there, and it would let choices touch). The
   variation is a hash of (pixel, frame): deterministic, and different from
   frame to frame. */
#define RENDERCACHE__MODULATION 0.4f          /* amplitude at density 0 */
#define RENDERCACHE__MODULATION_FADE 0.1f     /* density where it reaches 0 */

/* A 32-bit integer hash (lowbias32, Wellons): the serial loop is this one. */
static uint32_t rendercache__hash(uint32_t z)
{
    z ^= z >> 16;
    z *= 0x7FEB352Du;
    z ^= z >> 15;
    z *= 0x846CA68Bu;
    z ^= z >> 16;
    return z;
}

static float rendercache__threshold(uint32_t p, uint32_t frame, float amp)
{
    uint32_t z = rendercache__hash(p * 0x9E3779B9u ^ frame * 0x85EBCA6Bu);
    return 0.5f + amp * ((float)(z >> 8) * (1.0f / 8388608.0f) - 1.0f);
}

/* Serpentine Floyd-Steinberg over the fractional pixels (of value
   fraction, the cut level's share), in bands of RENDERCACHE__BAND_ROWS
   rows diffused each on its own (in parallel, and the same for any number
   of threads: the bands do not depend on it): error does not cross from a
   band into the next, as it does not leave the image at its bottom. Marks
   rc->chosen and counts the picks per band. Pixels of value 0 or 1 are
   decided outright; the error moves among the fractional pixels only, so a
   band's count is its total value up to its last carry. Fractional pixels
   keep value + incoming error in select_v for the count correction, and
   each band its marginal choices (the unpicked pixel nearest a pick, the
   picked one nearest a miss). */
typedef struct rendercache__diffuse_job {
    rendercache *rc;
    float fraction, amp;
} rendercache__diffuse_job;

static void rendercache__diffuse_band(void *ctx, uint32_t band)
{
    const rendercache__diffuse_job *j = (const rendercache__diffuse_job *)ctx;
    rendercache *rc = j->rc;
    rendercache__band *out = &rc->bands[band];
    const uint32_t w = rc->width, y0 = band * RENDERCACHE__BAND_ROWS;
    const uint32_t y1 = y0 + RENDERCACHE__BAND_ROWS < rc->height ? y0 + RENDERCACHE__BAND_ROWS : rc->height;
    unsigned char *chosen = rc->chosen;
    float *select_v = rc->select_v, carry = 0.0f;
    float *cur = rc->err_rows + 2 * (size_t)band * (w + 2), *next = cur + (w + 2);
    uint32_t y;
    out->count = 0;
    out->best_add = out->best_drop = RENDERCACHE__NONE;
    out->add_v = -FLT_MAX;
    out->drop_v = FLT_MAX;
    memset(cur, 0, (w + 2) * sizeof *cur);
    for (y = y0; y < y1; y++) {
        int dir = (y & 1u) ? -1 : 1, end = dir > 0 ? (int)w : -1, x = dir > 0 ? 0 : (int)w - 1;
        float *t;
        memset(next, 0, (w + 2) * sizeof *next);
        for (;; x += dir) {
            uint32_t p;
            float total, e;
            unsigned char pick;
            x = rendercache__next_marked(chosen + (size_t)y * w, x, end, dir, 2u);   /* the rest was decided by the threshold */
            if (x == end) break;
            p = y * w + (uint32_t)x;
            total = j->fraction + cur[x + 1] + carry;
            /* (without modulation the threshold is 0.5 exactly: no hash) */
            pick = total >= (j->amp > 0.0f ? rendercache__threshold(p, (uint32_t)rc->frame, j->amp) : 0.5f) ? 1u : 0u;
            e = total - (float)pick;
            select_v[p] = total;
            chosen[p] = (unsigned char)(2u | pick);
            out->count += pick;
            if (pick ? total < out->drop_v : total > out->add_v) {   /* the marginal choices, for the correction */
                if (pick) { out->drop_v = total; out->best_drop = p; }
                else { out->add_v = total; out->best_add = p; }
            }
            carry = rendercache__spread_error(rc, cur, next, y, y1, x, dir, e);
        }
        t = cur; cur = next; next = t;
    }
}

/* The diffusion of every band; returns the count of the pixels chosen and
   the image's marginal choices. */
static uint32_t rendercache__diffuse(rendercache *rc, float fraction, uint32_t *best_add, uint32_t *best_drop)
{
    rendercache__diffuse_job job;
    uint32_t b, count = rendercache__tile_sum(rc, 5);
    float add_v = -FLT_MAX, drop_v = FLT_MAX;
    job.rc = rc;
    job.fraction = fraction;
    job.amp = RENDERCACHE__MODULATION * (1.0f - fraction / RENDERCACHE__MODULATION_FADE);
    if (job.amp < 0.0f) job.amp = 0.0f;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__diffuse_band, &job, rc->band_count);
    for (b = 0; b < rc->band_count; b++) {   /* in band order: the same for any thread count */
        const rendercache__band *band = &rc->bands[b];
        count += band->count;
        if (band->best_add != RENDERCACHE__NONE && band->add_v > add_v) { add_v = band->add_v; *best_add = band->best_add; }
        if (band->best_drop != RENDERCACHE__NONE && band->drop_v < drop_v) { drop_v = band->drop_v; *best_drop = band->best_drop; }
    }
    return count;
}

/* Brings the count to the target with the fractional pixels nearest the
   threshold: adds the unchosen with the largest value + error, or drops the
   chosen with the smallest. The residual (the error left over at the end of
   the diffusion) is mostly one pixel, which the diffusion pass already
   found (best_add, best_drop); a larger one takes one scan per 64 pixels,
   keeping the best 64 candidates in a sorted list. */
#define RENDERCACHE__CORRECT_BATCH 64u
static uint32_t rendercache__correct_count(rendercache *rc, uint32_t count, uint32_t target, uint32_t best_add,
                                           uint32_t best_drop)
{
    if (count + 1 == target && best_add != RENDERCACHE__NONE) { rc->chosen[best_add] ^= 1u; return target; }
    if (count == target + 1 && best_drop != RENDERCACHE__NONE) { rc->chosen[best_drop] ^= 1u; return target; }
    while (count != target) {
        uint32_t list[RENDERCACHE__CORRECT_BATCH], n = 0, want, p, i;
        float key[RENDERCACHE__CORRECT_BATCH];
        int add = count < target;
        want = add ? target - count : count - target;
        if (want > RENDERCACHE__CORRECT_BATCH) want = RENDERCACHE__CORRECT_BATCH;
        for (p = 0; p < rc->pixel_count; p++) {
            unsigned char c = rc->chosen[p];
            float k;
            if (!(c & 2u) || (int)(c & 1u) == add) continue;
            k = add ? -rc->select_v[p] : rc->select_v[p];   /* smaller key: better candidate */
            if (n == want && !(k < key[n - 1])) continue;
            i = n < want ? n++ : n - 1;
            while (i > 0 && k < key[i - 1]) { key[i] = key[i - 1]; list[i] = list[i - 1]; i--; }
            key[i] = k;
            list[i] = p;
        }
        if (n == 0) break;
        for (i = 0; i < n; i++) rc->chosen[list[i]] ^= 1u;
        count = add ? count + n : count - n;
    }
    return count;
}

/* Selects up to budget pixels of a priority image into rc->chosen. */
static uint32_t rendercache__select(rendercache *rc, const float *priority, uint32_t budget)
{
    rendercache__select_job job;
    uint64_t positive = 0;
    uint32_t l, count, target, best_add = RENDERCACHE__NONE, best_drop = RENDERCACHE__NONE;
    if (budget == 0) return 0;
    job.rc = rc;
    job.priority = priority;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__histogram_job, &job, rc->tile_count);
    rendercache__find_cut(rc, budget, &job.cut, &job.fraction);
    for (l = 0; l < RENDERCACHE__LEVELS; l++) positive += rc->hist[(size_t)rc->tile_count * RENDERCACHE__LEVELS + l];
    target = positive < budget ? (uint32_t)positive : budget;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__threshold_job, &job, rc->tile_count);
    count = rendercache__diffuse(rc, job.fraction, &best_add, &best_drop);
    return rendercache__correct_count(rc, count, target, best_add, best_drop);
}

/* The request of pixel p of the current camera (its centre's ray); zeroes
   its priority, so that nothing requests it again in this frame. */
static void rendercache__put_request(rendercache *rc, uint32_t p, rendercache_pixel_request *r)
{
    const rendercache__view *v = &rc->view;
    r->x = p % rc->width;
    r->y = p / rc->width;
    r->flags = 0u;
    r->frame = rc->frame;
    memcpy(r->org, v->eye, sizeof r->org);
    rendercache__view_ray(v, (float)r->x + 0.5f, (float)r->y + 0.5f, r->dir);
    rc->priority[p] = 0.0f;
}

/* Writes the chosen pixels among pixels [p, end) as requests out[n],
   out[n + 1], ... (in scan order, while n < max) and zeroes their
   priority, so a further request call moves on to the next pixels;
   returns the n after the last. */
static uint32_t rendercache__emit_range(rendercache *rc, uint32_t p, uint32_t end, rendercache_pixel_request *out,
                                        uint32_t n, uint32_t max)
{
    for (; n < max; p++) {
        p = (uint32_t)rendercache__next_marked(rc->chosen, (int)p, (int)end, 1, 1u);
        if (p == end) break;
        rendercache__put_request(rc, p, &out[n++]);
    }
    return n;
}

/* The requests of the chosen pixels, tile by tile in parallel (with
   parallel_for): each tile's start in out is the count of the chosen
   pixels of the tiles before it (RENDERCACHE__TILE_STATS column 5, free
   after the selection), so out is what one pass in scan order writes. */
typedef struct rendercache__emit_job {
    rendercache *rc;
    rendercache_pixel_request *out;
    uint32_t max;
} rendercache__emit_job;

/* The pixels [*p0, *p1) of tile. */
static void rendercache__tile_pixels(const rendercache *rc, uint32_t tile, uint32_t *p0, uint32_t *p1)
{
    *p0 = tile * RENDERCACHE__TILE_ROWS * rc->width;
    *p1 = *p0 + RENDERCACHE__TILE_ROWS * rc->width < rc->pixel_count ? *p0 + RENDERCACHE__TILE_ROWS * rc->width
                                                                    : rc->pixel_count;
}

/* Job per tile: counts its chosen pixels. */
static void rendercache__count_chosen_job(void *ctx, uint32_t tile)
{
    const rendercache__emit_job *job = (const rendercache__emit_job *)ctx;
    rendercache *rc = job->rc;
    uint32_t p0, p1, p, count = 0;
    rendercache__tile_pixels(rc, tile, &p0, &p1);
    for (p = p0; p < p1; p++) count += rc->chosen[p] & 1u;
    rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)tile + 5] = count;
}

/* Job per tile: its requests, from its start. */
static void rendercache__emit_job_tile(void *ctx, uint32_t tile)
{
    const rendercache__emit_job *job = (const rendercache__emit_job *)ctx;
    rendercache *rc = job->rc;
    uint32_t p0, p1;
    rendercache__tile_pixels(rc, tile, &p0, &p1);
    rendercache__emit_range(rc, p0, p1, job->out, rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)tile + 5], job->max);
}

/* The requests of the chosen pixels in scan order, up to max; returns their count. */
static uint32_t rendercache__emit(rendercache *rc, rendercache_pixel_request *out, uint32_t max)
{
    rendercache__emit_job job;
    uint32_t t, start = 0;
    if (!rc->parallel_for) return rendercache__emit_range(rc, 0, rc->pixel_count, out, 0, max);
    job.rc = rc;
    job.out = out;
    job.max = max;
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__count_chosen_job, &job, rc->tile_count);
    for (t = 0; t < rc->tile_count; t++) {   /* counts to starts */
        uint32_t *s = &rc->tile_stats[RENDERCACHE__TILE_STATS * (size_t)t + 5], count = *s;
        *s = start;
        start = count < max - start ? start + count : max;
    }
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__emit_job_tile, &job, rc->tile_count);
    return start;
}

/* Requests for min(max, empty cells) empty cells of the prediction,
   spread evenly over them in serpentine scan order (the k-th empty cell
   is taken when floor(k max / E) steps, from an offset that changes with
   the frame), one pixel each at a place in its cell that also changes
   with the frame. Returns the count. */
static uint32_t rendercache__emit_predicted(rendercache *rc, rendercache_pixel_request *out, uint32_t max)
{
    const uint64_t e = rc->pred_cells, want = max < rc->pred_cells ? max : rc->pred_cells;
    const uint64_t offset = e ? rendercache__hash((uint32_t)rc->frame * 0x9E3779B9u) % e : 0;
    uint64_t k = offset;
    uint32_t cy, i, n = 0;
    for (cy = 0; cy < rc->cells_y && n < want; cy++)
        for (i = 0; i < rc->cells_x && n < want; i++) {
            uint32_t cx = cy & 1u ? rc->cells_x - 1 - i : i, c = cy * rc->cells_x + cx, h, x, y;
            rendercache_pixel_request *r;
            if (rc->occupancy[c] >= RENDERCACHE__CELL_FEW) continue;
            k++;
            if ((k * want) / e == ((k - 1) * want) / e) continue;
            rc->occupancy[c] = 255;   /* requested: not again in this frame */
            h = rendercache__hash(c * 0x85EBCA6Bu ^ (uint32_t)rc->frame * 0x632BE5ABu);
            x = (cx << RENDERCACHE__CELL_SHIFT) + (h & (RENDERCACHE__CELL - 1));
            y = (cy << RENDERCACHE__CELL_SHIFT) + ((h >> 8) & (RENDERCACHE__CELL - 1));
            if (x >= rc->width) x = rc->width - 1;   /* the last cells may be narrower */
            if (y >= rc->height) y = rc->height - 1;
            r = &out[n++];
            r->x = x;
            r->y = y;
            r->flags = RENDERCACHE_REQUEST_PREDICTED;
            r->frame = rc->frame;
            memcpy(r->org, rc->predicted.eye, sizeof r->org);
            rendercache__view_ray(&rc->predicted, (float)x + 0.5f, (float)y + 0.5f, r->dir);
        }
    rc->pred_cells -= n;
    return n;
}

/* Steps of the image (desc.edge_fraction, desc.edge_step). A point of an
   earlier frame lands anywhere in its pixel, so where the image steps (a
   depth edge, a shadow's edge, a wall's corner) a pixel often shows a point
   of the other side, and the priority image, which ranks points by age,
   does not see it: in the walkthrough (office, 160x120, against converged
   renders) 4 % of the pixels, those at steps, carried 65-73 % of the
   cached frames' squared error. A fresh sample at the pixel's centre shows
   the side the pixel's centre is on. (WDP99's priority measures how likely
   a pixel is wrong; at a step the point's place in its pixel matters most.)
   A pixel is at a step when its luminance differs from one of its 8
   neighbours' by more than edge_step times the image's mean, both clamped
   at RENDERCACHE__EDGE_WHITE times the mean (about a display's white point:
   a lamp's glow is no step). */
#define RENDERCACHE__EDGE_WHITE 4.0f

/* Whether the pixel of lum (a row of width w inside the image) is at a step. */
static int rendercache__at_step(const float *lum, uint32_t w, float step)
{
    const float l0 = lum[0];
    const float *row = lum - w - 1;
    int dx, dy;
    for (dy = 0; dy < 3; dy++, row += w)
        for (dx = 0; dx < 3; dx++)
            if (fabsf(row[dx] - l0) > step) return 1;
    return 0;
}

/* Whether pixel p (not on the border) may be requested at a step: its
   priority is positive (none of this frame's requests yet, no sample of
   this frame) and it is at a step of lum. */
static int rendercache__edge_pixel(const rendercache *rc, const float *lum, uint32_t p, float step)
{
    return rc->priority[p] > 0.0f && rendercache__at_step(lum + p, rc->width, step);
}

/* Requests for the pixels at steps of the image, from out[n] up to max:
   all of them in scan order when they fit, else spread evenly over them
   (the k-th is taken when floor(k m / E) steps, m of E), so that a budget
   too small for all does not leave the bottom of the image without; returns
   the n after the last. Serial: the frame stays the same for any thread
   count. */
static uint32_t rendercache__emit_edges(rendercache *rc, rendercache_pixel_request *out, uint32_t n, uint32_t max)
{
    const float *rgb = rc->image;
    float *lum = rc->select_v;   /* request scratch: free between two selections */
    const uint32_t w = rc->width, h = rc->height;
    uint32_t x, y, p;
    uint64_t e = 0, k = 0, want;
    double sum = 0.0;
    float mean, white, step;
    if (n >= max || w < 3 || h < 3) return n;
    for (p = 0; p < rc->pixel_count; p++) {
        lum[p] = 0.2126f * rgb[3 * p] + 0.7152f * rgb[3 * p + 1] + 0.0722f * rgb[3 * p + 2];
        sum += lum[p];
    }
    mean = (float)(sum / (double)rc->pixel_count);
    if (!(mean > 0.0f) || !isfinite(mean)) return n;
    white = RENDERCACHE__EDGE_WHITE * mean;
    step = rc->edge_step * mean;
    for (p = 0; p < rc->pixel_count; p++) lum[p] = lum[p] < white ? lum[p] : white;
    for (y = 1; y + 1 < h; y++)
        for (x = 1, p = y * w + 1; x + 1 < w; x++, p++) e += (uint64_t)rendercache__edge_pixel(rc, lum, p, step);
    want = max - n < e ? max - n : e;
    for (y = 1; y + 1 < h && k < e; y++)
        for (x = 1, p = y * w + 1; x + 1 < w && k < e; x++, p++)
            if (rendercache__edge_pixel(rc, lum, p, step)) {
                k++;
                if ((k * want) / e != ((k - 1) * want) / e) rendercache__put_request(rc, p, &out[n++]);
            }
    return n;
}

RENDERCACHE_API rendercache_result rendercache_request(rendercache *rc, rendercache_pixel_request *out,
                                                       uint32_t max, uint32_t *count)
{
    uint32_t n = 0, pred_budget = 0, own, edges;
    double t0;
    if (count) *count = 0;
    if (!rc || !count || (!out && max) || !rc->has_frame) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (max == 0) return RENDERCACHE_OK;
    t0 = rendercache__now(rc);
    if (rc->has_prediction) {
        pred_budget = (uint32_t)((double)max * rc->predict_fraction);
        if (pred_budget > rc->pred_cells) pred_budget = rc->pred_cells;
    }
    own = max - pred_budget;   /* for the current camera: the steps' share, the priority image the rest */
    edges = (uint32_t)((double)own * rc->edge_fraction);
    if (rendercache__select(rc, rc->priority, own - edges)) n = rendercache__emit(rc, out, own - edges);
    if (edges) {   /* the steps, then what they leave to the next most important pixels */
        n = rendercache__emit_edges(rc, out, n, n + edges);
        if (n < own && rendercache__select(rc, rc->priority, own - n)) n += rendercache__emit(rc, out + n, own - n);
    }
    if (rc->has_prediction && n < max && rc->pred_cells) {   /* the share, and what the priority image left */
        uint32_t m = rendercache__emit_predicted(rc, out + n, max - n);
        rc->stats.predicted += m;
        n += m;
    }
    rc->stats.requested += n;
    rc->stats.time_request += rendercache__now(rc) - t0;
    *count = n;
    return RENDERCACHE_OK;
}

/* ======================================================================
   15. insertion and eviction
   ---------------------------------------------------------------------- */
/* Whether slot shows in the current frame: inserted in it, or its point
   is the one a pixel shows (the depth cull marks those). */
static int rendercache__slot_in_use(const rendercache *rc, uint32_t slot)
{
    return rc->shown[slot] == rendercache__mark(rc->frame);
}

/* Eviction (clock, second chance): the hand walks the slots in the order
   they were filled, so the slot under it holds the oldest insertion; a
   point shown in this frame is skipped (still useful), a free slot or a
   point not visible (off screen, hidden, culled) is taken. When a whole
   turn finds nothing, the cache is smaller than what is visible and the
   oldest slot is taken anyway. */
static uint32_t rendercache__victim(rendercache *rc)
{
    uint32_t scanned, slot;
    for (scanned = 0; !rc->hand_exhausted && scanned < rc->capacity; scanned++) {
        slot = rc->hand;
        rc->hand = slot + 1 == rc->capacity ? 0 : slot + 1;
        if (rc->geo.object[slot] == RENDERCACHE__FREE_SLOT || !rendercache__slot_in_use(rc, slot)) return slot;
    }
    rc->hand_exhausted = 1;
    slot = rc->hand;
    rc->hand = slot + 1 == rc->capacity ? 0 : slot + 1;
    return slot;
}

/* The frame a sample was requested in (0: the current one). */
static uint64_t rendercache__sample_frame(const rendercache *rc, const rendercache_sample *s)
{
    return s->frame ? s->frame : rc->frame;
}

/* Whether a sample is well formed: a pixel of the image, known flags and
   object, finite values, a frame begun already. */
static int rendercache__sample_valid(const rendercache *rc, const rendercache_sample *s)
{
    if (!rc->has_frame || s->frame > rc->frame) return 0;
    if (s->x >= rc->width || s->y >= rc->height) return 0;
    if (s->flags & ~RENDERCACHE_REQUEST_PREDICTED) return 0;
    if (s->object != RENDERCACHE_MISS && s->object >= rc->object_count) return 0;
    if (s->object != RENDERCACHE_MISS && !rendercache__finite3(s->position)) return 0;
    if (!rendercache__finite3(s->rgb) || !(s->priority_scale >= 0.0f) || !isfinite(s->priority_scale)) return 0;
    if (!(s->view_lobe >= 0.0f) || !isfinite(s->view_lobe)) return 0;
    return 1;
}

/* The point of sample s as a slot stores it: its object and its position
   in object space (through the object's transform in frame f), or for a
   miss the unit world direction of its ray in view v. */
static void rendercache__sample_point(const rendercache *rc, const rendercache_sample *s, uint64_t f,
                                      const rendercache__view *v, rendercache__geo *g)
{
    g->object = s->object;
    if (s->object == RENDERCACHE_MISS) rendercache__view_ray(v, (float)s->x + 0.5f, (float)s->y + 0.5f, g->pos);
    else rendercache__affine(rendercache__object_local(rc, s->object, f), s->position, g->pos);
}

/* A point on its way into the cache: a sample's (age 0) or a seed's. */
typedef struct rendercache__new_point {
    rendercache__geo g;      /* object and object-space position, or the background's direction */
    float rgb[3];
    float scale;             /* priority scale, > 0 */
    uint32_t age;            /* the age it starts with (frames) */
    uint16_t eye_frame, view_lobe;   /* as rendercache__point's */
} rendercache__new_point;

/* The new point of a sample requested in frame f through view v. */
static void rendercache__sample_new_point(const rendercache *rc, const rendercache_sample *s, uint64_t f,
                                          const rendercache__view *v, rendercache__new_point *np)
{
    rendercache__sample_point(rc, s, f, v, &np->g);
    memcpy(np->rgb, s->rgb, sizeof np->rgb);
    np->scale = s->priority_scale > 0.0f ? s->priority_scale : 1.0f;
    np->age = 0;
    np->eye_frame = rendercache__eye_frame(f, (s->flags & RENDERCACHE_REQUEST_PREDICTED) != 0);
    np->view_lobe = s->object == RENDERCACHE_MISS ? 0 : rendercache__lobe_bits(s->view_lobe);   /* the sky is still */
}

/* What placing points counts (rendercache__put_point): each job of a parallel
   insertion its own, summed after. */
typedef struct rendercache__put_counts {
    uint32_t replaced, evicted, live;
} rendercache__put_counts;

/* Stores a new point in slot (a free one is one more live point). */
static void rendercache__store(rendercache *rc, uint32_t slot, const rendercache__new_point *np,
                               rendercache__put_counts *n)
{
    rendercache__point *pt = &rc->data[slot];
    n->live += rc->geo.object[slot] == RENDERCACHE__FREE_SLOT;
    rendercache__slot_set(&rc->geo, slot, &np->g);
    memcpy(pt->rgb, np->rgb, sizeof pt->rgb);
    pt->scale = np->scale;
    pt->base = (uint32_t)rc->frame + rc->obj_motion[rendercache__motion_index(rc, np->g.object)] - np->age;
    pt->object = np->g.object;
    pt->eye_frame = np->eye_frame;
    pt->view_lobe = np->view_lobe;
    rc->shown[slot] = rendercache__mark(rc->frame);   /* new points are not evicted in their own frame */
}

/* Holes around a new point are filled again when an insert call ends
   (rendercache__refill): the point is one more for their filters. The
   holes wait with this bit set in their kind. */
#define RENDERCACHE__REFILL 0x80u

/* Marks the holes whose filling reads pixel p: within wide_radius (the
   filters) or RENDERCACHE__HOLE_REACH (the layer's rays), the larger.
   Within the filters only, a hole kept a layer found without a sample of
   a later insert call, and inserting a frame's samples in pieces gave
   another image than one call. holes_only 0 marks the points of the
   window too: cheaper (a row of ORs the compiler vectorizes, no test of
   px_index per pixel) where the refill follows at once, as it fills only
   the pixels that are holes then and clears the bit on every pixel. */
static void rendercache__mark_window(rendercache *rc, uint32_t p, int holes_only)
{
    const int r = (int)(rc->wide_radius > RENDERCACHE__HOLE_REACH ? rc->wide_radius : RENDERCACHE__HOLE_REACH), x = (int)(p % rc->width), y = (int)(p / rc->width);
    int x0 = x - r < 0 ? 0 : x - r, x1 = x + r >= (int)rc->width ? (int)rc->width - 1 : x + r, qx, qy;
    int y0 = y - r < 0 ? 0 : y - r, y1 = y + r >= (int)rc->height ? (int)rc->height - 1 : y + r;
    for (qy = y0; qy <= y1; qy++) {
        unsigned char *kind = rc->kind + (size_t)qy * rc->width;
        if (holes_only) {
            const uint32_t *px_index = rc->px_index + (size_t)qy * rc->width;
            for (qx = x0; qx <= x1; qx++)
                if (px_index[qx] == RENDERCACHE__NONE) kind[qx] = (unsigned char)(kind[qx] | RENDERCACHE__REFILL);
        } else {
            for (qx = x0; qx <= x1; qx++) kind[qx] = (unsigned char)(kind[qx] | RENDERCACHE__REFILL);
        }
    }
    rc->refill_rows[0] = (uint32_t)y0 < rc->refill_rows[0] ? (uint32_t)y0 : rc->refill_rows[0];
    rc->refill_rows[1] = (uint32_t)y1 + 1 > rc->refill_rows[1] ? (uint32_t)y1 + 1 : rc->refill_rows[1];
}

/* Marks the holes around pixel p now: a point there may be evicted before
   the call ends, and that new hole was not to be filled again. */
static void rendercache__mark_refill(rendercache *rc, uint32_t p)
{
    rendercache__mark_window(rc, p, 1);
}

/* With desc.refill_samples, the holes around the current frame's samples
   are filled again too, as those of late and predicted ones are: a caller
   that inserts before it shows the frame shows them at once.
   Left for the next frame's filling, they showed what the frame began
   with: in a fast walk, where most requests go to wide holes, the
   background or a far layer between the new points (the house at 320x240
   in 48 frames: black speckles next to new points; mean LRMS against full
   renders 0.2340 -> 0.2047, the office's 48 frames 0.0727 -> 0.0720).
   Serial, in sample order after the points are placed: any thread count
   gives the same frame. Points are marked too (the cheaper marking):
   nothing places or evicts a point between this and the refill, so the
   same holes are filled (testing px_index at each of the 289 pixels of
   a window cost the walkthrough's office at 640x480 ~11 ms a frame on
   one thread: its cache phase 59.7 -> 48.9 ms). */
static void rendercache__mark_refill_current(rendercache *rc, const rendercache_sample *samples, uint32_t n)
{
    uint32_t i;
    if (!rc->has_frame) return;
    for (i = 0; i < n; i++) {
        const rendercache_sample *s = &samples[i];
        if (s->x < rc->width && s->y < rc->height && !(s->flags & RENDERCACHE_REQUEST_PREDICTED) &&
            rendercache__sample_frame(rc, s) == rc->frame)
            rendercache__mark_window(rc, s->y * rc->width + s->x, 0);
    }
}

/* Fills the marked holes of one band of RENDERCACHE__TILE_ROWS rows from
   refill_rows[0]. A hole's filling reads points only (never a kind) and
   writes its own pixel, as the frame's filling does tile by tile: bands
   run in parallel. The bit is cleared on points too (marked by
   rendercache__mark_refill_current). */
static void rendercache__refill_job(void *ctx, uint32_t band)
{
    rendercache *rc = (rendercache *)ctx;
    uint32_t x, y = rc->refill_rows[0] + band * RENDERCACHE__TILE_ROWS, end = y + RENDERCACHE__TILE_ROWS;
    if (end > rc->refill_rows[1]) end = rc->refill_rows[1];
    for (; y < end; y++)
        for (x = 0; x < rc->width; x++) {
            uint32_t q = y * rc->width + x;
            if (!(rc->kind[q] & RENDERCACHE__REFILL)) continue;
            rc->kind[q] = (unsigned char)(rc->kind[q] & ~RENDERCACHE__REFILL);
            if (rc->px_index[q] == RENDERCACHE__NONE) rendercache__fill_hole(rc, x, y);
        }
}

/* Fills the marked holes again (in parallel with parallel_for: a fast
   walk refills most holes of the image). */
static void rendercache__refill(rendercache *rc)
{
    if (rc->refill_rows[1] > rc->refill_rows[0])
        rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__refill_job, rc,
                              (rc->refill_rows[1] - rc->refill_rows[0] + RENDERCACHE__TILE_ROWS - 1) / RENDERCACHE__TILE_ROWS);
    rc->refill_rows[0] = rc->height;
    rc->refill_rows[1] = 0;
}

/* A sample also becomes the point pixel p shows, at once. */
static void rendercache__show(rendercache *rc, uint32_t p, uint32_t slot, float depth2, const float rgb[3])
{
    rc->px_index[p] = slot;
    rc->px_depth[p] = depth2;
    memcpy(rc->image + 3 * (size_t)p, rgb, 3 * sizeof(float));
    rc->kind[p] = RENDERCACHE_PIXEL_POINT;
    rc->count[p] = 0;
    rc->priority[p] = 0.0f;
}

/* Whether a new colour differs from the old one by more than the
   threshold: the largest channel difference against the largest channel
   of either. A renderer's noise makes resamples of unchanged points
   differ too, so the differences of each frame's replacements are
   counted (rendercache__change_level): a change must also lie three
   standard deviations out in the previous frame's differences. */
static float rendercache__colour_difference(const float old_rgb[3], const float rgb[3])
{
    float d = 0.0f, m = 0.0f;
    int k;
    for (k = 0; k < 3; k++) {
        float a = fabsf(old_rgb[k]), b = fabsf(rgb[k]), e = fabsf(rgb[k] - old_rgb[k]);
        m = a > m ? a : m;
        m = b > m ? b : m;
        d = e > d ? e : d;
    }
    return m > 0.0f ? d / m : 0.0f;   /* in [0, 2] for finite colours; inf when the difference overflows */
}

/* The bin of the histogram of colour differences that difference r falls in. */
static uint32_t rendercache__change_bin(float r)
{
    return r < 2.0f ? (uint32_t)(r * (0.5f * RENDERCACHE__CHANGE_BINS)) : RENDERCACHE__CHANGE_BINS - 1;
}

/* Counts a replacement's colour difference r for the next frame's level. */
static void rendercache__count_change(rendercache *rc, float r)
{
    rc->change_hist[rendercache__change_bin(r)]++;
}

static int rendercache__colour_changed(rendercache *rc, const float old_rgb[3], const float rgb[3])
{
    float r = rendercache__colour_difference(old_rgb, rgb);
    rendercache__count_change(rc, r);
    return r > rc->change_level;
}

/* At the start of a frame: the threshold of colour changes for the frame,
   the larger of desc.change_threshold and three standard deviations of
   the last frame's replacement differences (the renderer's noise),
   estimated robustly from their median (sigma = 1.4826 median absolute
   deviation), when it had 64 or more. A deterministic renderer's median
   is 0: the desc's threshold alone counts. */
#define RENDERCACHE__NOISE_SIGMAS (3.0f * 1.4826f)
static void rendercache__change_level(rendercache *rc)
{
    uint32_t b, total = 0, below = 0;
    for (b = 0; b < RENDERCACHE__CHANGE_BINS; b++) total += rc->change_hist[b];
    rc->change_level = rc->change_threshold;
    for (b = 0; total >= 64 && b < RENDERCACHE__CHANGE_BINS; b++) {
        below += rc->change_hist[b];
        if (2 * below >= total) {
            float median = (float)b * (2.0f / RENDERCACHE__CHANGE_BINS);   /* the bin's lower end: 0 when most are 0 */
            if (RENDERCACHE__NOISE_SIGMAS * median > rc->change_level) rc->change_level = RENDERCACHE__NOISE_SIGMAS * median;
            break;
        }
    }
    memset(rc->change_hist, 0, sizeof rc->change_hist);
}

/* The age a colour change gives a point of priority scale s: the top of
   the age ramp for scale 1, where its priority reaches POINT_MAX, the
   holes' floor; a larger scale gets there sooner (age_ramp / s frames,
   at least 1). At age_ramp itself a point of scale 2 or more outranked
   every hole: in the building walkthrough, whose points' scale (1/W of
   their light vectors) is mostly 2-4, the points around the changes took
   the budget while two thirds of the image were holes (cached frames
   against converged renders, pooled LRMS: building 0.2905 -> 0.2862,
   office 0.1144 -> 0.1099). */
static uint32_t rendercache__change_age(const rendercache *rc, float s)
{
    float age = (float)rc->age_ramp / s;
    return s > 1.0f ? (age > 1.0f ? (uint32_t)ceilf(age) : 1u) : rc->age_ramp;
}

/* Colour-change detection (WDG02): the points shown within
   RENDERCACHE_CHANGE_RADIUS pixels of pixel p are aged to the top of the
   age ramp (at least; rendercache__change_age), so that the next requests
   look around the change.
   Points shaded in this frame are left young: they already show the
   change. Aged, they were requested again in the next frame (at an 8%
   budget a frame's samples lie about 3.5 pixels apart, inside each
   other's windows): in the building walkthrough, where 14-25 % of the
   replacements find a change and most points' scale (1/W) is 2-4, so
   that an aged point outranks every hole, a third of each frame's
   requests went to the previous frame's samples (43 of 1536 since), and
   at frames 31 and 55 (the first rooms) none to the holes.
   An ageing sets a point's age to at least a value of its own (its
   scale's), so agings in any order, or twice, age alike: those of a
   parallel chunk run in jobs that each age only the pixels of the rows y
   with y % parts == part (rendercache__age_job; interleaved rows, since
   the changes gather where a shadow or a light moved). */
static void rendercache__age_pixel(rendercache *rc, uint32_t q)
{
    rendercache__point *pt = &rc->data[rc->px_index[q]];
    uint32_t motion = rc->obj_motion[rendercache__motion_index(rc, pt->object)], top;
    if ((uint32_t)rc->frame + motion == pt->base) return;   /* shaded in this frame (not marked: so the order
                                                               of agings and placings within a parallel chunk
                                                               is free) */
    rc->count[q] = 1;   /* aged in this frame (count is 0 for every pixel showing a point) */
    top = rendercache__change_age(rc, pt->scale);
    if ((uint32_t)rc->frame + motion - pt->base < top) pt->base = (uint32_t)rc->frame + motion - top;
    rc->priority[q] = rendercache__point_priority(rc, pt, motion, q, rc->px_depth[q]);
}

/* The window's points lie anywhere in the cache, a miss each: a first
   pass asks for all of them, so that the misses overlap (in a profile of
   the 1080p bench, the load of a point's record took over half of the
   ageing's time). */
static void rendercache__age_rows(rendercache *rc, uint32_t p, uint32_t part, uint32_t parts)
{
    const int r = RENDERCACHE_CHANGE_RADIUS, x = (int)(p % rc->width), y = (int)(p / rc->width);
    const int x0 = x - r < 0 ? 0 : x - r, x1 = x + r >= (int)rc->width ? (int)rc->width - 1 : x + r;
    int qx, qy, touch;
    for (touch = 1; touch >= 0; touch--)
        for (qy = y - r; qy <= y + r; qy++) {
            if (qy < 0 || qy >= (int)rc->height || (uint32_t)qy % parts != part) continue;
            for (qx = x0; qx <= x1; qx++) {
                uint32_t q = (uint32_t)qy * rc->width + (uint32_t)qx;
                if (q == p || rc->px_index[q] == RENDERCACHE__NONE || rc->count[q]) continue;
                if (touch) {
                    const rendercache__point *pt = &rc->data[rc->px_index[q]];
                    RENDERCACHE__PREFETCH(pt);
                    RENDERCACHE__PREFETCH((const char *)pt + sizeof *pt - 1);   /* may straddle two lines */
                } else {
                    rendercache__age_pixel(rc, q);
                }
            }
        }
}

static void rendercache__age_around(rendercache *rc, uint32_t p)
{
    rendercache__age_rows(rc, p, 0, 1);
}

/* Puts sample s in slot, replacing the point that was there (replacing:
   the slot held a point of the same surface, whose colour it compares),
   and shows it in pixel p (RENDERCACHE__NONE: not shown). A sample that
   comes after its frame's hole filling (refill: late or predicted) and
   lands in a hole has the holes around it filled again: the frame it
   shows in was filled without it. The holes around a current frame's
   samples are marked when the insert call ends
   (rendercache__mark_refill_current), and so are those around a sample
   whose colour changed (rendercache__place): they were filled from the
   stale colour it replaced (behind a moving shadow, a dark patch of holes
   between bright new samples). */
static RENDERCACHE__INLINE void rendercache__put_point(rendercache *rc, uint32_t slot, int replacing, int refill,
                             const rendercache__new_point *np, uint32_t p, float depth2, rendercache__put_counts *n)
{
    if (replacing) n->replaced++;
    else if (rc->geo.object[slot] != RENDERCACHE__FREE_SLOT) n->evicted++;
    rendercache__store(rc, slot, np, n);
    if (p != RENDERCACHE__NONE && refill && rc->px_index[p] == RENDERCACHE__NONE) rendercache__mark_refill(rc, p);
    if (p != RENDERCACHE__NONE) rendercache__show(rc, p, slot, depth2, np->rgb);
}

/* Adds what placing points counted to the frame's stats. */
static void rendercache__add_counts(rendercache *rc, const rendercache__put_counts *n)
{
    rc->stats.replaced += n->replaced;
    rc->stats.evicted += n->evicted;
    rc->live += n->live;
}

/* rendercache__put_point, and the colour-change detection of a replacement
   (which ages the points around it). */
static void rendercache__place(rendercache *rc, uint32_t slot, int replacing, int refill,
                               const rendercache__new_point *np, uint32_t p, float depth2)
{
    int changed = replacing && np->age == 0 && rendercache__colour_changed(rc, rc->data[slot].rgb, np->rgb);
    rendercache__put_counts n = { 0, 0, 0 };
    rendercache__put_point(rc, slot, replacing, refill, np, p, depth2, &n);
    rendercache__add_counts(rc, &n);
    if (changed) {
        rc->stats.changed++;
        rendercache__age_around(rc, p);
        rendercache__mark_refill(rc, p);
    }
}

/* The new point of a sample of the current frame, and its squared
   distance (the hit point projects into its own pixel). */
static float rendercache__current_point(const rendercache *rc, const rendercache_sample *s, rendercache__new_point *np)
{
    float dx, dy, dz;
    rendercache__sample_new_point(rc, s, rc->frame, &rc->view, np);
    if (s->object == RENDERCACHE_MISS) return RENDERCACHE__FAR2;
    dx = s->position[0] - rc->view.eye[0];
    dy = s->position[1] - rc->view.eye[1];
    dz = s->position[2] - rc->view.eye[2];
    return dx * dx + dy * dy + dz * dz;
}

/* A sample of the current frame: it replaces the point its pixel shows, or
   fills the hole there. */
static void rendercache__insert_current(rendercache *rc, const rendercache_sample *s)
{
    uint32_t p = s->y * rc->width + s->x, slot = rc->px_index[p];
    rendercache__new_point np;
    float d = rendercache__current_point(rc, s, &np);
    rendercache__place(rc, slot != RENDERCACHE__NONE ? slot : rendercache__victim(rc), slot != RENDERCACHE__NONE, 0, &np,
                       p, d);
}

/* A late sample (requested in frame f < the current one), a predicted
   one or a seed: its point is where its own ray hit, which the current
   camera sees in another pixel, if at all. Where it lands on the same
   surface it replaces the point shown there; where it lands in front of
   what is shown, or in a hole it is not hidden in, it is shown in a new
   slot; elsewhere it only joins the cache (unless shown_only: a seed). A
   new slot is never one the current frame shows. Returns 1 when stored,
   0 when no such slot is left (or not shown, for shown_only). */
static int rendercache__insert_other(rendercache *rc, const rendercache__new_point *np, int shown_only)
{
    const float tol2 = (1.0f + rc->depth_tolerance) * (1.0f + rc->depth_tolerance);
    rendercache__projector pr;
    uint32_t p, slot;
    float d2 = 0.0f, nd[8];
    int show;
    rendercache__projector_init(&pr, rc, &rc->view, rc->obj_camera, 0);
    p = rendercache__project_point(&pr, &np->g, &d2);
    if (p != RENDERCACHE__NONE && rc->px_index[p] != RENDERCACHE__NONE) {
        uint32_t k = rc->px_index[p];
        float dk = rc->px_depth[p];
        if (rc->data[k].object == np->g.object && d2 <= dk * tol2 && dk <= d2 * tol2) {   /* the same surface */
            rendercache__place(rc, k, 1, 1, np, p, d2);
            return 1;
        }
        show = d2 * tol2 < dk;   /* in front of what is shown there */
    } else if (p != RENDERCACHE__NONE) {   /* a hole: shown unless nearer points around enclose it */
        rendercache__neighbour_depths(rc->px_depth, rc->width, rc->height, p % rc->width, p / rc->width, nd);
        show = !rendercache__occluded(d2, nd, tol2);
    } else {
        show = 0;
    }
    if (shown_only && !show) return 0;
    slot = rendercache__victim(rc);
    if (rendercache__slot_in_use(rc, slot)) return 0;
    rendercache__place(rc, slot, 0, 1, np, show ? p : RENDERCACHE__NONE, d2);
    return 1;
}

/* Prefetches the slots that the next samples will replace in place, and
   the pixels they show in, so that their cache misses overlap instead of
   coming one by one (prefetches rather than loads: they need not complete
   before the insertion goes on). The insertion touches the sample
   RENDERCACHE__TOUCH_AHEAD on as it places each one: a steady stream of
   about ten lines a sample. Batches of 32 samples (320 lines at once)
   filled the core's line-fill buffers, so that the prefetches waited on
   each other and the insertion on them (insertion 1.4 against 2.0 ms at
   512x512, one thread). Returns a value that depends on the pixels' slots
   (for the caller to keep). */
#define RENDERCACHE__TOUCH_AHEAD 16u   /* samples between a slot's prefetch and its insertion (32, 64: slower) */

static uint32_t rendercache__touch_slots(const rendercache *rc, const rendercache_sample *samples, uint32_t n)
{
    uint32_t i, sum = 0;
    for (i = 0; i < n; i++) {
        const rendercache_sample *s = &samples[i];
        uint32_t slot, p;
        if (s->x >= rc->width || s->y >= rc->height || (s->flags & RENDERCACHE_REQUEST_PREDICTED) ||
            rendercache__sample_frame(rc, s) != rc->frame)
            continue;
        p = s->y * rc->width + s->x;
        RENDERCACHE__PREFETCH_WRITE(&rc->image[3 * (size_t)p]);   /* the pixel's lines, which show writes */
        RENDERCACHE__PREFETCH_WRITE(&rc->image[3 * (size_t)p + 2]);
        RENDERCACHE__PREFETCH_WRITE(&rc->priority[p]);
        RENDERCACHE__PREFETCH_WRITE(&rc->px_depth[p]);
        slot = rc->px_index[p];
        if (slot == RENDERCACHE__NONE) continue;
        sum += slot;
        RENDERCACHE__PREFETCH(&rc->geo.x[slot]);
        RENDERCACHE__PREFETCH(&rc->geo.y[slot]);
        RENDERCACHE__PREFETCH(&rc->geo.z[slot]);
        RENDERCACHE__PREFETCH(&rc->geo.object[slot]);
        RENDERCACHE__PREFETCH(&rc->data[slot]);
        RENDERCACHE__PREFETCH((const char *)&rc->data[slot] + sizeof rc->data[0] - 1);   /* may straddle two lines */
    }
    return sum;
}

/* The touches of an insertion at sample i of samples[first, end): the
   first TOUCH_AHEAD samples at its start, then the sample TOUCH_AHEAD on. */
static uint32_t rendercache__touch_ahead(const rendercache *rc, const rendercache_sample *samples, uint32_t i,
                                         uint32_t first, uint32_t end)
{
    uint32_t sum = 0;
    if (i == first) sum += rendercache__touch_slots(rc, samples + i, end - i < RENDERCACHE__TOUCH_AHEAD ? end - i : RENDERCACHE__TOUCH_AHEAD);
    if (end - i > RENDERCACHE__TOUCH_AHEAD) sum += rendercache__touch_slots(rc, samples + i + RENDERCACHE__TOUCH_AHEAD, 1);
    return sum;
}

/* Parallel insertion (with parallel_for). The samples of the current
   frame (not late, not predicted) are placed in chunks of consecutive
   ones: each replaces the point its pixel shows or takes the slot the
   eviction's clock gives it, and writes its own pixel. Within a chunk of
   distinct pixels (a chunk ends before a pixel it has already) these are
   distinct slots and pixels, so the samples of a chunk can be placed in
   any order once their slots are known: the calling thread first walks
   the clock for the chunk's holes in sample order (nothing the chunk
   writes changes which slots the clock takes: the slots it passes are
   behind it), then jobs find the colour differences and place the
   samples, then age the points around the colour changes, by rows
   (rendercache__age_job). That is the cache one-by-one insertion
   leaves: an ageing never marks nor ages a point shaded in this frame, so
   it finds the chunk's placed pixels as it would have found them placed
   or not yet (a hole then, a point the placing replaces, ageing and all,
   later), and agings age alike in any order. A turn of the clock
   that found nothing (it then takes slots that pixels show), and every
   other sample go one by one, in order, as without parallel_for: the same
   cache for any thread count. A chunk's slots and colour differences are
   kept in the re-sort's scratch (free outside begin_frame). The walk and
   the jobs touch their samples TOUCH_AHEAD on, as one-by-one insertion
   does: without it the chunks, at 2 threads, were slower than one thread
   inserting alone (1920x1080: 10.2-10.4 ms against 8.6-8.7; with the
   touches 8.6-8.9). */
#define RENDERCACHE__INSERT_CHUNK 65536u  /* samples placed together, at most (and as many as the re-sort's
                                             scratch holds) */
#define RENDERCACHE__INSERT_JOBS 8u       /* jobs of a chunk */
#define RENDERCACHE__MARK 4u              /* the chosen byte (request scratch) of a pixel the chunk has */

typedef struct rendercache__insert_job {
    rendercache *rc;
    const rendercache_sample *s;   /* the chunk's samples */
    uint32_t n;
    uint32_t *slot;                /* per sample: the slot it takes */
    float *change;                 /* per sample: its colour's difference from the point it replaces, -1: none */
    uint32_t changed[RENDERCACHE__INSERT_JOBS];   /* per job: its colour changes */
    uint32_t hist[RENDERCACHE__INSERT_JOBS][RENDERCACHE__CHANGE_BINS];   /* per job: its replacements' colour
                                                                           differences (rc->change_hist) */
    rendercache__put_counts counts[RENDERCACHE__INSERT_JOBS];
} rendercache__insert_job;

/* Whether a sample is one of the current frame's that a chunk may take. */
static int rendercache__chunk_sample(const rendercache *rc, const rendercache_sample *s)
{
    return rendercache__sample_valid(rc, s) && rendercache__sample_frame(rc, s) == rc->frame &&
           !(s->flags & RENDERCACHE_REQUEST_PREDICTED);
}

/* The samples [*i0, *i1) of job j of a chunk. */
static void rendercache__insert_range(const rendercache__insert_job *job, uint32_t j, uint32_t *i0, uint32_t *i1)
{
    *i0 = (uint32_t)((uint64_t)job->n * j / RENDERCACHE__INSERT_JOBS);
    *i1 = (uint32_t)((uint64_t)job->n * (j + 1) / RENDERCACHE__INSERT_JOBS);
}

/* Job j: the colour differences of its replacements, how many are changes,
   and their histogram (summed into the frame's after the chunk: counts,
   the same in any order). */
static void rendercache__change_job(void *ctx, uint32_t j)
{
    rendercache__insert_job *job = (rendercache__insert_job *)ctx;
    const rendercache *rc = job->rc;
    uint32_t i, i0, i1, changed = 0, *hist = job->hist[j];
    memset(hist, 0, sizeof job->hist[j]);
    rendercache__insert_range(job, j, &i0, &i1);
    for (i = i0; i < i1; i++) {
        if (i + RENDERCACHE__TOUCH_AHEAD < i1 && job->change[i + RENDERCACHE__TOUCH_AHEAD] >= 0.0f)
            RENDERCACHE__PREFETCH(&rc->data[job->slot[i + RENDERCACHE__TOUCH_AHEAD]]);
        if (job->change[i] < 0.0f) continue;
        job->change[i] = rendercache__colour_difference(rc->data[job->slot[i]].rgb, job->s[i].rgb);
        hist[rendercache__change_bin(job->change[i])]++;
        changed += job->change[i] > rc->change_level;
    }
    job->changed[j] = changed;
}

/* Job j: places its samples. */
static void rendercache__put_job(void *ctx, uint32_t j)
{
    rendercache__insert_job *job = (rendercache__insert_job *)ctx;
    rendercache *rc = job->rc;
    rendercache__put_counts n = { 0, 0, 0 };
    uint32_t i, i0, i1;
    rendercache__insert_range(job, j, &i0, &i1);
    for (i = i0; i < i1; i++) {
        const rendercache_sample *s = &job->s[i];
        rendercache__new_point np;
        float d;
        (void)rendercache__touch_ahead(rc, job->s, i, i0, i1);   /* (the prefetches' addresses keep their loads) */
        if (i + RENDERCACHE__TOUCH_AHEAD < i1) {   /* the slot the clock gave a hole: touch_ahead knows only the
                                                      slots pixels show */
            const uint32_t t = job->slot[i + RENDERCACHE__TOUCH_AHEAD];
            if (job->change[i + RENDERCACHE__TOUCH_AHEAD] < 0.0f) {
                RENDERCACHE__PREFETCH_WRITE(&rc->geo.x[t]);
                RENDERCACHE__PREFETCH_WRITE(&rc->geo.y[t]);
                RENDERCACHE__PREFETCH_WRITE(&rc->geo.z[t]);
                RENDERCACHE__PREFETCH_WRITE(&rc->geo.object[t]);
                RENDERCACHE__PREFETCH_WRITE(&rc->data[t]);
                RENDERCACHE__PREFETCH_WRITE((const char *)&rc->data[t] + sizeof rc->data[0] - 1);
                RENDERCACHE__PREFETCH_WRITE(&rc->shown[t]);
            }
        }
        d = rendercache__current_point(rc, s, &np);
        rendercache__put_point(rc, job->slot[i], job->change[i] >= 0.0f, 0, &np, s->y * rc->width + s->x, d, &n);
    }
    job->counts[j] = n;
}

/* The most samples of a chunk: its slots and colour differences fill
   2 words per sample of the re-sort's scratch (9 words per slot of a
   range, a range per job of the re-sort). */
static uint32_t rendercache__chunk_most(const rendercache *rc)
{
    const size_t words = (size_t)rendercache__sort_range_size(rc) * rendercache__sort_jobs(rc) *
                         (2 + sizeof(rendercache__point) / sizeof(uint32_t));
    return words / 2 < RENDERCACHE__INSERT_CHUNK ? (uint32_t)(words / 2) : RENDERCACHE__INSERT_CHUNK;
}

/* The slots of the chunk that starts at samples[0] (up to n samples), in
   job: how many samples it has; 0 when the first is not one for a chunk or
   the clock turned once (the clock is then as it was). */
static uint32_t rendercache__chunk_slots(rendercache *rc, const rendercache_sample *samples, uint32_t n,
                                         rendercache__insert_job *job)
{
    const uint32_t hand = rc->hand, most = rendercache__chunk_most(rc);
    uint32_t m, i, marked = 0;
    uint64_t walked = 0;   /* slots the clock passed: a whole turn would meet the chunk's own slots again */
    for (m = 0; m < n && m < most && rendercache__chunk_sample(rc, &samples[m]); m++) {
        uint32_t p = samples[m].y * rc->width + samples[m].x, slot, before = rc->hand;
        if (m + RENDERCACHE__TOUCH_AHEAD < n) {   /* the walk's misses overlap (a sample past the chunk: harmless) */
            const rendercache_sample *t = &samples[m + RENDERCACHE__TOUCH_AHEAD];
            if (t->x < rc->width && t->y < rc->height) {
                RENDERCACHE__PREFETCH(&rc->px_index[t->y * rc->width + t->x]);
                RENDERCACHE__PREFETCH_WRITE(&rc->chosen[t->y * rc->width + t->x]);
            }
        }
        slot = rc->px_index[p];
        if (rc->chosen[p] & RENDERCACHE__MARK) break;   /* the chunk has this pixel already */
        rc->chosen[p] |= RENDERCACHE__MARK;
        marked++;
        job->change[m] = slot != RENDERCACHE__NONE ? 0.0f : -1.0f;
        job->slot[m] = slot != RENDERCACHE__NONE ? slot : rendercache__victim(rc);
        walked += (rc->hand + (uint64_t)rc->capacity - before) % rc->capacity;
        if (rc->hand_exhausted || walked >= rc->capacity) break;
    }
    for (i = 0; i < marked; i++) rc->chosen[samples[i].y * rc->width + samples[i].x] &= (unsigned char)~RENDERCACHE__MARK;
    if (rc->hand_exhausted || walked >= rc->capacity) {
        rc->hand = hand;
        rc->hand_exhausted = 0;
        return 0;
    }
    return m;
}

/* Job j: the agings of the chunk's colour changes in the rows y with
   y % INSERT_JOBS == j (the pixels of those rows, and the points they
   show, are its own). */
static void rendercache__age_job(void *ctx, uint32_t j)
{
    rendercache__insert_job *job = (rendercache__insert_job *)ctx;
    rendercache *rc = job->rc;
    uint32_t i;
    for (i = 0; i < job->n; i++)
        if (job->change[i] > rc->change_level)
            rendercache__age_rows(rc, job->s[i].y * rc->width + job->s[i].x, j, RENDERCACHE__INSERT_JOBS);
}

/* Places the chunk that starts at samples[0] (up to n samples) in
   parallel; returns how many samples it placed. When none, *alone says
   how many go one by one before the next chunk: the first sample (not one
   for a chunk), or all of them (the clock). */
static uint32_t rendercache__insert_chunk(rendercache *rc, const rendercache_sample *samples, uint32_t n,
                                          uint32_t *alone)
{
    rendercache__insert_job job;
    rendercache__put_counts sum = { 0, 0, 0 };
    uint32_t j, b, changed = 0;
    job.rc = rc;
    job.s = samples;
    job.slot = rc->sort_scratch;
    job.change = (float *)(void *)(rc->sort_scratch + rendercache__chunk_most(rc));
    job.n = rc->hand_exhausted ? 0 : rendercache__chunk_slots(rc, samples, n, &job);
    *alone = 0;
    if (job.n == 0) {
        *alone = rendercache__chunk_sample(rc, samples) ? n : 1;   /* (a sample for a chunk: the clock) */
        return 0;
    }
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__change_job, &job, RENDERCACHE__INSERT_JOBS);
    for (j = 0; j < RENDERCACHE__INSERT_JOBS; j++) changed += job.changed[j];
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__put_job, &job, RENDERCACHE__INSERT_JOBS);
    for (j = 0; j < RENDERCACHE__INSERT_JOBS; j++) {
        sum.replaced += job.counts[j].replaced;
        sum.evicted += job.counts[j].evicted;
        sum.live += job.counts[j].live;
    }
    rendercache__add_counts(rc, &sum);
    if (changed) {
        rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__age_job, &job, RENDERCACHE__INSERT_JOBS);
        for (j = 0; j < job.n; j++)   /* (serial: few, and their windows overlap) */
            if (job.change[j] > rc->change_level) rendercache__mark_refill(rc, job.s[j].y * rc->width + job.s[j].x);
    }
    for (j = 0; j < RENDERCACHE__INSERT_JOBS; j++)
        for (b = 0; b < RENDERCACHE__CHANGE_BINS; b++) rc->change_hist[b] += job.hist[j][b];
    rc->stats.changed += changed;
    return job.n;
}

/* One sample, as rendercache_insert takes it without parallel_for. */
static RENDERCACHE__INLINE void rendercache__insert_one(rendercache *rc, const rendercache_sample *s, uint32_t *stored, uint32_t *bad)
{
    const rendercache__frame_record *record;
    int predicted = (s->flags & RENDERCACHE_REQUEST_PREDICTED) != 0;
    uint64_t f;
    if (!rendercache__sample_valid(rc, s)) { (*bad)++; return; }
    f = rendercache__sample_frame(rc, s);
    if (rc->frame - f > rc->max_latency) { rc->stats.dropped++; return; }
    record = &rc->history[f % ((uint64_t)rc->max_latency + 1)];
    if (record->frame != f || (predicted && !record->has_prediction)) { (*bad)++; return; }
    if (f == rc->frame && !predicted) {
        rendercache__insert_current(rc, s);
    } else {
        rendercache__new_point np;
        rendercache__sample_new_point(rc, s, f, predicted ? &record->predicted : &record->view, &np);
        if (!rendercache__insert_other(rc, &np, 0)) {
            rc->stats.dropped++;
            return;
        }
    }
    rc->stats.late += f != rc->frame;
    (*stored)++;
}

RENDERCACHE_API rendercache_result rendercache_insert(rendercache *rc, const rendercache_sample *samples, uint32_t n,
                                                      uint32_t *taken)
{
    uint32_t i = 0, stored = 0, bad = 0, alone = 0;
    double t0;
    if (taken) *taken = 0;
    if (!rc || (!samples && n)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    t0 = rendercache__now(rc);
    while (i < n) {
        const rendercache_sample *s = &samples[i];
        if (rc->parallel_for && alone == 0) {
            uint32_t m = rendercache__insert_chunk(rc, s, n - i, &alone);
            stored += m;
            i += m;
            if (m) continue;
        }
        rc->touched += rendercache__touch_ahead(rc, samples, i, 0, n);   /* the misses complete before the stores */
        rendercache__insert_one(rc, s, &stored, &bad);
        i++;
        alone -= alone > 0;
    }
    if (rc->refill_samples) rendercache__mark_refill_current(rc, samples, n);
    rendercache__refill(rc);
    rc->stats.inserted += stored;
    rc->stats.rejected += bad;
    rc->stats.live_points = rc->live;
    rc->stats.time_insert += rendercache__now(rc) - t0;
    if (taken) *taken = stored;
    if (bad && rc->log) rc->log(rc->log_user, "rendercache_insert: malformed samples skipped (see stats.rejected)");
    return bad ? RENDERCACHE_ERROR_INVALID_ARGUMENT : RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_invalidate(rendercache *rc, uint32_t object)
{
    uint32_t o, p;
    if (!rc || (object != RENDERCACHE_ALL_OBJECTS && object != RENDERCACHE_MISS && object >= rc->object_count))
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (o = 0; o <= rc->object_count; o++)   /* a point's age includes its object's motion counter */
        if (object == RENDERCACHE_ALL_OBJECTS || o == rendercache__motion_index(rc, object)) rc->obj_motion[o] += rc->age_ramp;
    if (!rc->has_frame) return RENDERCACHE_OK;
    for (p = 0; p < rc->pixel_count; p++) {   /* and the priorities of this frame's pixels showing them */
        const rendercache__point *pt;
        if (rc->px_index[p] == RENDERCACHE__NONE) continue;
        pt = &rc->data[rc->px_index[p]];
        if (object != RENDERCACHE_ALL_OBJECTS && pt->object != object) continue;
        rc->priority[p] = rendercache__point_priority(rc, pt, rc->obj_motion[rendercache__motion_index(rc, pt->object)], p,
                                                      rc->px_depth[p]);
    }
    return RENDERCACHE_OK;
}

/* Ages a point as a colour change around it does (rendercache__change_age),
   unless it is older already: ageing twice ages alike. */
static void rendercache__age_at_least(rendercache *rc, rendercache__point *pt)
{
    uint32_t motion = rc->obj_motion[rendercache__motion_index(rc, pt->object)], top = rendercache__change_age(rc, pt->scale);
    if ((uint32_t)rc->frame + motion - pt->base < top) pt->base = (uint32_t)rc->frame + motion - top;
}

/* The world position of slot's point (an object's point: geo.object <
   object_count) in the current frame. */
static void rendercache__world_point(const rendercache *rc, uint32_t slot, float p[3])
{
    const float x[3] = { rc->geo.x[slot], rc->geo.y[slot], rc->geo.z[slot] };
    rendercache__affine(rc->obj_world + 12 * (size_t)rc->geo.object[slot], x, p);
}

/* rendercache_invalidate_where's jobs: first ranges of slots, then ranges
   of pixels. */
#define RENDERCACHE__WHERE_JOBS 16u
typedef struct rendercache__where_job {
    rendercache *rc;
    int (*changed)(void *user, const float p[3], uint32_t object);
    void *user;
    uint32_t *yes;   /* a bit per slot: changed said yes (sort_scratch) */
    uint32_t aged[RENDERCACHE__WHERE_JOBS];
} rendercache__where_job;

/* Slot job j: asks changed about the points on an object in its whole
   words of yes (32 slots each, so that no two jobs write one word), ages
   those it says changed and notes them in yes. Ageing touches only the
   point's own record, so the result is the serial one. */
static void rendercache__where_slots_job(void *ctx, uint32_t j)
{
    rendercache__where_job *job = (rendercache__where_job *)ctx;
    rendercache *rc = job->rc;
    const uint32_t words = (rc->capacity + 31) / 32;
    uint32_t w = (uint32_t)((uint64_t)words * j / RENDERCACHE__WHERE_JOBS),
             end = (uint32_t)((uint64_t)words * (j + 1) / RENDERCACHE__WHERE_JOBS), n = 0;
    for (; w < end; w++) {
        uint32_t s = 32 * w, last = rc->capacity - s < 32 ? rc->capacity : s + 32, bits = 0;
        for (; s < last; s++) {   /* free slots and background points are not asked */
            float x[3];
            if (rc->geo.object[s] >= rc->object_count) continue;
            rendercache__world_point(rc, s, x);
            if (!job->changed(job->user, x, rc->geo.object[s])) continue;
            rendercache__age_at_least(rc, &rc->data[s]);
            bits |= 1u << (s & 31);
            n++;
        }
        job->yes[w] = bits;
    }
    job->aged[j] = n;
}

/* Pixel job j: the priorities of its pixels that show a point changed said
   yes about (asked once: the answer in yes). */
static void rendercache__where_pixels_job(void *ctx, uint32_t j)
{
    const rendercache__where_job *job = (const rendercache__where_job *)ctx;
    rendercache *rc = job->rc;
    uint32_t p = (uint32_t)((uint64_t)rc->pixel_count * j / RENDERCACHE__WHERE_JOBS),
             end = (uint32_t)((uint64_t)rc->pixel_count * (j + 1) / RENDERCACHE__WHERE_JOBS);
    for (; p < end; p++) {
        const rendercache__point *pt;
        uint32_t slot = rc->px_index[p];
        if (slot == RENDERCACHE__NONE || !(job->yes[slot / 32] >> (slot & 31) & 1u)) continue;
        pt = &rc->data[slot];
        rc->priority[p] = rendercache__point_priority(rc, pt, rc->obj_motion[rendercache__motion_index(rc, pt->object)], p,
                                                      rc->px_depth[p]);
    }
}

/* rendercache_invalidate_where, and with rank_pixels 0 its _next_frame
   form: the ageing without the pixel pass. */
static rendercache_result rendercache__invalidate_where(rendercache *rc,
                                                        int (*changed)(void *user, const float p[3], uint32_t object),
                                                        void *user, uint32_t *aged, int rank_pixels)
{
    rendercache__where_job job;
    uint32_t j, n = 0;
    if (aged) *aged = 0;
    if (!rc || !changed) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    job.rc = rc;
    job.changed = changed;
    job.user = user;
    job.yes = rc->sort_scratch;   /* (free between frames' calls; a bit per slot: sort_scratch_words) */
    rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__where_slots_job, &job, RENDERCACHE__WHERE_JOBS);
    for (j = 0; j < RENDERCACHE__WHERE_JOBS; j++) n += job.aged[j];
    if (rank_pixels && rc->has_frame && n)   /* the priorities of this frame's pixels showing them */
        rendercache__run_jobs(rc->parallel_for, rc->parallel_user, rendercache__where_pixels_job, &job,
                              RENDERCACHE__WHERE_JOBS);
    if (aged) *aged = n;
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_invalidate_where(rendercache *rc,
                                                                int (*changed)(void *user, const float p[3],
                                                                               uint32_t object),
                                                                void *user, uint32_t *aged)
{
    return rendercache__invalidate_where(rc, changed, user, aged, 1);
}

RENDERCACHE_API rendercache_result rendercache_invalidate_where_next_frame(rendercache *rc,
                                                                           int (*changed)(void *user, const float p[3],
                                                                                          uint32_t object),
                                                                           void *user, uint32_t *aged)
{
    return rendercache__invalidate_where(rc, changed, user, aged, 0);
}

/* ======================================================================
   16. accessors and camera helpers
   ---------------------------------------------------------------------- */
RENDERCACHE_API const float *rendercache_image(const rendercache *rc) { return rc ? rc->image : NULL; }
RENDERCACHE_API const float *rendercache_priority_image(const rendercache *rc) { return rc ? rc->priority : NULL; }
RENDERCACHE_API const unsigned char *rendercache_pixel_kinds(const rendercache *rc) { return rc ? rc->kind : NULL; }
/* Largest fallback value taken: beyond it a value is treated as broken. */
#define RENDERCACHE__FALLBACK_MAX 1e30f

/* Chamfer distance (1 and sqrt 2 steps, within 8 % of Euclidean) from each
   pixel to the nearest pixel showing a point, capped at cap, written to
   dist[3 * p] (the caller's output image serves as scratch). Two raster
   passes, forward then backward (Borgefors 1986). */
static void rendercache__point_distance(const rendercache *rc, float cap, float *dist)
{
    const float diag = 1.41421356f;
    uint32_t x, y, w = rc->width, h = rc->height;
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            uint32_t p = y * w + x;
            float d = rc->kind[p] == RENDERCACHE_PIXEL_POINT ? 0.0f : cap;
            if (x > 0) d = rendercache__minf(d, dist[3 * (p - 1)] + 1.0f);
            if (y > 0) {
                d = rendercache__minf(d, dist[3 * (p - w)] + 1.0f);
                if (x > 0) d = rendercache__minf(d, dist[3 * (p - w - 1)] + diag);
                if (x + 1 < w) d = rendercache__minf(d, dist[3 * (p - w + 1)] + diag);
            }
            dist[3 * p] = d;
        }
    for (y = h; y-- > 0;)
        for (x = w; x-- > 0;) {
            uint32_t p = y * w + x;
            float d = dist[3 * p];
            if (x + 1 < w) d = rendercache__minf(d, dist[3 * (p + 1)] + 1.0f);
            if (y + 1 < h) {
                d = rendercache__minf(d, dist[3 * (p + w)] + 1.0f);
                if (x + 1 < w) d = rendercache__minf(d, dist[3 * (p + w + 1)] + diag);
                if (x > 0) d = rendercache__minf(d, dist[3 * (p + w - 1)] + diag);
            }
            dist[3 * p] = d;
        }
}

/* The fallback's weight at frame pixel (x, y) at distance d from the nearest
   point; 0 where its value or confidence is unusable. */
static float rendercache__fallback_weight(const rendercache *rc, const rendercache_fallback *f, uint32_t x, uint32_t y,
                                          float d, float near_px, float far_px, const float **rgb)
{
    uint32_t q = (y / (rc->height / f->height)) * f->width + x / (rc->width / f->width);
    const float *c = f->rgb + 3 * (size_t)q;
    float conf = f->confidence ? f->confidence[q] : 1.0f, t;
    int k;
    if (!(conf >= 0.0f && conf <= 1.0f)) return 0.0f;   /* NaN fails both */
    for (k = 0; k < 3; k++)
        if (!(fabsf(c[k]) <= RENDERCACHE__FALLBACK_MAX)) return 0.0f;
    *rgb = c;
    t = (d - near_px) / (far_px - near_px);
    return conf * rendercache__minf(rendercache__maxf(t, 0.0f), 1.0f);
}

RENDERCACHE_API rendercache_result rendercache_compose_fallback(const rendercache *rc, const rendercache_fallback *fallback,
                                                                float *out)
{
    float near_px, far_px;
    uint32_t x, y;
    if (!rc || !fallback || !fallback->rgb || !out || !rc->has_frame) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (fallback->width == 0 || fallback->height == 0 || fallback->width > rc->width ||
        fallback->height > rc->height || rc->width % fallback->width || rc->height % fallback->height) {
        rendercache__log_to(rc->log, rc->log_user, "rendercache_compose_fallback: size does not divide the frame's");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    near_px = fallback->near_pixels == 0.0f ? 1.0f : fallback->near_pixels;
    far_px = fallback->far_pixels == 0.0f ? (float)rc->wide_radius + 1.0f : fallback->far_pixels;
    if (!(near_px >= 0.0f) || !(far_px > near_px) || !isfinite(far_px)) {
        rendercache__log_to(rc->log, rc->log_user, "rendercache_compose_fallback: need 0 <= near < far, finite");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    rendercache__point_distance(rc, far_px, out);
    for (y = 0; y < rc->height; y++)
        for (x = 0; x < rc->width; x++) {
            uint32_t p = y * rc->width + x;
            const float *img = rc->image + 3 * (size_t)p, *fb = NULL;
            float w = rc->kind[p] == RENDERCACHE_PIXEL_POINT
                          ? 0.0f
                          : rendercache__fallback_weight(rc, fallback, x, y, out[3 * p], near_px, far_px, &fb);
            int k;
            for (k = 0; k < 3; k++) out[3 * p + k] = w > 0.0f ? img[k] + w * (fb[k] - img[k]) : img[k];
        }
    return RENDERCACHE_OK;
}

RENDERCACHE_API const float *rendercache_depth_image(rendercache *rc)
{
    uint32_t p;
    if (!rc) return NULL;
    for (p = 0; p < rc->pixel_count; p++)
        rc->depth_out[p] = rc->px_depth[p] == FLT_MAX ? FLT_MAX : sqrtf(rc->px_depth[p]);
    return rc->depth_out;
}

RENDERCACHE_API void rendercache_get_stats(const rendercache *rc, rendercache_stats *out)
{
    if (!out) return;
    if (!rc) { memset(out, 0, sizeof *out); return; }
    *out = rc->stats;
}

RENDERCACHE_API rendercache_result rendercache_camera_ray(const rendercache_camera *camera, float px, float py,
                                                          float org[3], float dir[3])
{
    rendercache__view v;
    if (!org || !dir || !rendercache__view_init(&v, camera) || !isfinite(px) || !isfinite(py))
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    memcpy(org, v.eye, 3 * sizeof(float));
    return rendercache__view_ray(&v, px, py, dir) ? RENDERCACHE_OK : RENDERCACHE_ERROR_INVALID_ARGUMENT;
}

RENDERCACHE_API int rendercache_camera_project(const rendercache_camera *camera, const float p[3], float *px,
                                               float *py, float *depth)
{
    rendercache__view v;
    float w[3], c[3], x, y;
    if (!p || !rendercache__view_init(&v, camera) || !rendercache__finite3(p)) return 0;
    w[0] = p[0] - v.eye[0];
    w[1] = p[1] - v.eye[1];
    w[2] = p[2] - v.eye[2];
    rendercache__view_rotate(&v, w, c);
    if (!rendercache__view_to_pixel(&v, c, &x, &y)) return 0;
    if (px) *px = x;
    if (py) *py = y;
    if (depth) *depth = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    return 1;
}

/* ======================================================================
   17. range images (Nimeroff, Dorsey and Rushmeier 1996, section 3.1):
   per pixel of a camera, radiance, distance along the ray and object id.
   ---------------------------------------------------------------------- */
static void rendercache__range_clear(rendercache_range_image *img)
{
    size_t n = (size_t)img->camera.width * img->camera.height, p;
    for (p = 0; p < n; p++) {
        img->rgb[3 * p + 0] = img->rgb[3 * p + 1] = img->rgb[3 * p + 2] = 0.0f;
        img->depth[p] = RENDERCACHE__FAR;
        img->object[p] = RENDERCACHE_NO_SAMPLE;
    }
}

/* Allocates an image for a validated camera (arrays not initialised). */
static rendercache_range_image *rendercache__range_alloc(const rendercache_camera *camera, const rendercache_allocator *a)
{
    size_t n = (size_t)camera->width * camera->height;
    rendercache_range_image *img = (rendercache_range_image *)rendercache__alloc(a, sizeof *img);
    if (!img) return NULL;
    memset(img, 0, sizeof *img);
    img->camera = *camera;
    img->allocator = *a;
    img->rgb = (float *)rendercache__alloc_array(a, n, 3 * sizeof(float));
    img->depth = (float *)rendercache__alloc_array(a, n, sizeof(float));
    img->object = (uint32_t *)rendercache__alloc_array(a, n, sizeof(uint32_t));
    if (!img->rgb || !img->depth || !img->object) {
        rendercache_range_image_destroy(img);
        return NULL;
    }
    return img;
}

/* The allocator argument of a public call: NULL means the default. */
static int rendercache__allocator_arg(const rendercache_allocator *in, rendercache_allocator *out)
{
    memset(out, 0, sizeof *out);
    if (in) *out = *in;
    return rendercache__allocator_valid(out);
}

RENDERCACHE_API rendercache_result rendercache_range_image_create(const rendercache_camera *camera,
                                                                  const rendercache_allocator *allocator,
                                                                  rendercache_range_image **out)
{
    rendercache__view v;
    rendercache_allocator a;
    rendercache_range_image *img;
    if (out) *out = NULL;
    if (!out || !rendercache__view_init(&v, camera) || !rendercache__allocator_arg(allocator, &a))
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    img = rendercache__range_alloc(camera, &a);
    if (!img) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    rendercache__range_clear(img);
    *out = img;
    return RENDERCACHE_OK;
}

RENDERCACHE_API void rendercache_range_image_destroy(rendercache_range_image *img)
{
    rendercache_allocator a;
    if (!img) return;
    rendercache_range_image_unprepare(img);
    a = img->allocator;
    rendercache__free(&a, img->rgb);
    rendercache__free(&a, img->depth);
    rendercache__free(&a, img->object);
    rendercache__free(&a, img);
}

/* An image a call may read or write: arrays present, camera valid. */
static int rendercache__range_valid(const rendercache_range_image *img, rendercache__view *v)
{
    return img && img->rgb && img->depth && img->object && rendercache__view_init(v, &img->camera);
}

/* The render cache seeded from range images (the bridge between the two
   halves of this header): each pixel becomes a point as a late sample
   does (rendercache__insert_other), but only where it shows in the
   current frame, and as old as the top of the age ramp, so that the
   cache shows the precomputed view at once and real samples replace it
   first. */
static uint32_t rendercache__seed_image(rendercache *rc, const rendercache_range_image *img, const rendercache__view *v)
{
    uint32_t x, y, stored = 0;
    for (y = 0; y < v->height; y++)
        for (x = 0; x < v->width; x++) {
            const size_t p = (size_t)y * v->width + x;
            const uint32_t o = img->object[p];
            const float d = img->depth[p];
            rendercache__new_point np;
            float dir[3];
            if (o == RENDERCACHE_NO_SAMPLE || (o != RENDERCACHE_MISS && (o >= rc->object_count || !(d > 0.0f && d <= FLT_MAX))))
                continue;
            if (!rendercache__finite3(img->rgb + 3 * p) || !rendercache__view_ray(v, (float)x + 0.5f, (float)y + 0.5f, dir))
                continue;
            np.g.object = o;
            if (o == RENDERCACHE_MISS) {
                memcpy(np.g.pos, dir, sizeof dir);
            } else {
                float world[3];
                int k;
                for (k = 0; k < 3; k++) world[k] = v->eye[k] + dir[k] * d;
                rendercache__affine(rendercache__object_local(rc, o, rc->frame), world, np.g.pos);
                if (!rendercache__finite3(np.g.pos)) continue;
            }
            memcpy(np.rgb, img->rgb + 3 * p, sizeof np.rgb);
            np.scale = 1.0f;
            np.age = rc->age_ramp;
            np.eye_frame = rendercache__eye_frame(rc->frame, 0);
            np.view_lobe = 0;   /* range images carry no lobe */
            stored += (uint32_t)rendercache__insert_other(rc, &np, 1);
        }
    return stored;
}

RENDERCACHE_API rendercache_result rendercache_seed(rendercache *rc, const rendercache_range_image *const *images,
                                                    uint32_t count, uint32_t *taken)
{
    rendercache__view v;
    uint32_t i, stored = 0;
    double t0;
    if (taken) *taken = 0;
    if (!rc || !rc->has_frame || (!images && count)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (i = 0; i < count; i++)
        if (!rendercache__range_valid(images[i], &v)) {
            if (rc->log) rc->log(rc->log_user, "rendercache_seed: an image is NULL, incomplete or has an invalid camera");
            return RENDERCACHE_ERROR_INVALID_ARGUMENT;
        }
    t0 = rendercache__now(rc);
    for (i = 0; i < count; i++) {
        rendercache__view_init(&v, &images[i]->camera);
        stored += rendercache__seed_image(rc, images[i], &v);
    }
    rendercache__refill(rc);
    rc->stats.inserted += stored;
    rc->stats.live_points = rc->live;
    rc->stats.time_insert += rendercache__now(rc) - t0;
    if (taken) *taken = stored;
    return RENDERCACHE_OK;
}

/* ======================================================================
   18. view interpolation (section 4.4, as Radiance's pinterp): every pixel
   of every range image is a point in space, reprojected into the new
   camera through the splat of section 9 (the render cache's z-buffer), one
   input at a time from the nearest eye on; a later input replaces a pixel
   only when it is nearer by more than the depth tolerance. Then the fills:
   foreground quads (within the splat), background (farther of the nearest
   filled pixels along the row and the column), and the caller's callback.
   ---------------------------------------------------------------------- */
#define RENDERCACHE__DEFAULT_WARP_TOLERANCE 0.02f
#define RENDERCACHE__MAX_QUAD_FRACTION 0.25f   /* a foreground quad wider than this share of the
                                                  image is not drawn (it spans the seam of a sphere
                                                  image, or a surface grazing the eye) */
#define RENDERCACHE__COLUMN_STRIP 64u          /* columns per job of the background fill */
#define RENDERCACHE__MAX_BIAS 1e6                /* largest depth bias of a late input (keeps depths finite) */
#define RENDERCACHE__CULL_CHUNK 32u              /* rays tested together against the target's frustum */
#define RENDERCACHE__CULL_TILE 16u               /* source pixels per side of a tile culled as a whole */
#define RENDERCACHE__HIDDEN_BLOCK 4u             /* target pixels per side of a block of the coarse z-buffer */
#define RENDERCACHE__HIDDEN_RUN 8u               /* source pixels of a row tested at once against it */
#define RENDERCACHE__IN_PLACE 2                  /* a projected pixel that stays on itself (warp_project's ok) */
#define RENDERCACHE__MIN_DEPTH 1e-18f           /* least distance a warp writes (squares of smaller ones underflow) */
#define RENDERCACHE__MAX_PLANE 16777216.0f       /* 2^24: a pixel projected farther than this from the image's
                                                    origin has no projection (float positions are no longer
                                                    whole pixels there, and every position in this range
                                                    converts to an int) */

/* What filled a target pixel (warper.how). */
enum { RENDERCACHE__HOW_EMPTY = 0, RENDERCACHE__HOW_WARPED, RENDERCACHE__HOW_BACKGROUND, RENDERCACHE__HOW_COMPUTED };

/* A target image under construction: colour, squared distance (FLT_MAX when
   empty, RENDERCACHE__FAR2 for the background) and object per pixel. */
typedef struct rendercache__accum {
    float *rgb;
    float *depth2;
    uint32_t *object;
} rendercache__accum;

struct rendercache_warper {
    rendercache_allocator alloc;
    void (*parallel_for)(void *, rendercache_job_fn, void *, uint32_t);
    void *parallel_user;
    double (*clock)(void *);
    void *clock_user;
    void (*log)(void *, const char *);
    void *log_user;
    rendercache_fill_fn fill_pixel;
    void *fill_user;
    float tolerance, background[3];
    uint32_t max_fill;           /* background fill: farthest source in pixels, 0 unlimited */
    int average;                 /* average the inputs that see the same surface */

    /* buffers of the current target size (0 x 0 before the first warp) */
    uint32_t width, height, pixel_count, tile_count;
    rendercache__splat splat;
    unsigned char *how;          /* per pixel: RENDERCACHE__HOW_* */
    uint32_t *column;            /* per pixel: background fill's candidate along the column */
    uint32_t *tile_counts;       /* 4 per tile: warped, background, computed, empty */
    float *b_rgb, *b_depth2;     /* blend_motion: the second image's warp */
    uint32_t *b_object;

    /* scratch grown on demand */
    float *rows;                 /* foreground fill: per job, two rows of projected source pixels */
    size_t rows_cap;             /* floats */
    float *motion;               /* per object id: source camera to target camera, 12 floats */
    uint32_t motion_cap;         /* objects */
    unsigned char *moving;       /* per object id: 1 when its motion is not the identity */
    uint32_t moving_cap;
    uint32_t *order;             /* inputs by distance */
    uint32_t order_cap;
    struct rendercache__warp_src *src;   /* the inputs, in that order */
    uint32_t src_cap;
    unsigned char *skip;         /* tile culling: the inputs' skip flags, then the tiles' kinds */
    size_t skip_cap;
    float *skip_depths;          /* tile culling: the tiles' least, then largest depths */
    size_t skip_depths_cap;
    uint64_t *hidden;            /* foreground quads: the coarse z-buffers */
    size_t hidden_cap;
    float *layers;               /* averaging: per input, the warp of it alone (3 colour, squared
                                    distance and object bits per pixel) */
    size_t layers_cap;

    rendercache__view target;
    rendercache_warp_stats stats;
};

static double rendercache__warp_now(const rendercache_warper *w)
{
    return w->clock ? w->clock(w->clock_user) : 0.0;
}

static void rendercache__warp_log(const rendercache_warper *w, const char *message)
{
    if (w && w->log) w->log(w->log_user, message);
}

static void rendercache__warper_free_buffers(rendercache_warper *w)
{
    const rendercache_allocator *a = &w->alloc;
    rendercache__splat_free(&w->splat, a);
    rendercache__free(a, w->how);
    rendercache__free(a, w->column);
    rendercache__free(a, w->tile_counts);
    rendercache__free(a, w->b_rgb);
    rendercache__free(a, w->b_depth2);
    rendercache__free(a, w->b_object);
    w->how = NULL;
    w->column = w->tile_counts = w->b_object = NULL;
    w->b_rgb = w->b_depth2 = NULL;
    w->width = w->height = w->pixel_count = w->tile_count = 0;
}

/* Buffers for a width x height target; kept while the size stays. */
static int rendercache__warper_reserve(rendercache_warper *w, uint32_t width, uint32_t height)
{
    const rendercache_allocator *a = &w->alloc;
    size_t n = (size_t)width * height;
    if (w->width == width && w->height == height) return 1;
    rendercache__warper_free_buffers(w);
    w->tile_count = (height + RENDERCACHE__TILE_ROWS - 1) / RENDERCACHE__TILE_ROWS;
    w->how = (unsigned char *)rendercache__alloc_array(a, n, 1);
    w->column = (uint32_t *)rendercache__alloc_array(a, n, sizeof(uint32_t));
    w->tile_counts = (uint32_t *)rendercache__alloc_array(a, w->tile_count, 4 * sizeof(uint32_t));
    if (!w->how || !w->column || !w->tile_counts ||
        rendercache__splat_alloc(&w->splat, width, height, w->parallel_for ? RENDERCACHE__SPLAT_JOBS : 1u, 1, a) != 0) {
        rendercache__warper_free_buffers(w);
        return 0;
    }
    w->width = width;
    w->height = height;
    w->pixel_count = (uint32_t)n;
    return 1;
}

/* The second accumulator of blend_motion (after warper_reserve). */
static int rendercache__warper_reserve_second(rendercache_warper *w)
{
    const rendercache_allocator *a = &w->alloc;
    if (w->b_rgb) return 1;
    w->b_rgb = (float *)rendercache__alloc_array(a, w->pixel_count, 3 * sizeof(float));
    w->b_depth2 = (float *)rendercache__alloc_array(a, w->pixel_count, sizeof(float));
    w->b_object = (uint32_t *)rendercache__alloc_array(a, w->pixel_count, sizeof(uint32_t));
    return w->b_rgb && w->b_depth2 && w->b_object;
}

/* Grows *p to hold count items of item bytes (contents not kept). */
static int rendercache__reserve(const rendercache_allocator *a, void **p, size_t *cap, size_t count, size_t item)
{
    void *q;
    if (count <= *cap && *p) return 1;
    q = rendercache__alloc_array(a, count, item);
    if (!q) return 0;
    rendercache__free(a, *p);
    *p = q;
    *cap = count;
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_warper_create(const rendercache_warp_desc *desc, rendercache_warper **out)
{
    rendercache_warper *w;
    if (out) *out = NULL;
    if (!out || !desc) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__allocator_valid(&desc->allocator) || !(desc->depth_tolerance >= 0.0f) ||
        !(desc->depth_tolerance < 1e6f) || !rendercache__finite3(desc->background)) {
        if (desc->log) desc->log(desc->log_user, "rendercache_warper_create: bad allocator, tolerance or background");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    w = (rendercache_warper *)rendercache__alloc(&desc->allocator, sizeof *w);
    if (!w) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    memset(w, 0, sizeof *w);
    w->alloc = desc->allocator;
    w->parallel_for = desc->parallel_for;
    w->parallel_user = desc->parallel_user;
    w->clock = desc->clock;
    w->clock_user = desc->clock_user;
    w->log = desc->log;
    w->log_user = desc->log_user;
    w->fill_pixel = desc->fill_pixel;
    w->fill_user = desc->fill_user;
    w->tolerance = rendercache__def(desc->depth_tolerance, RENDERCACHE__DEFAULT_WARP_TOLERANCE);
    w->max_fill = desc->max_fill_distance;
    w->average = desc->average != 0;
    memcpy(w->background, desc->background, sizeof w->background);
    *out = w;
    return RENDERCACHE_OK;
}

RENDERCACHE_API void rendercache_warper_destroy(rendercache_warper *w)
{
    rendercache_allocator a;
    if (!w) return;
    a = w->alloc;
    rendercache__warper_free_buffers(w);
    rendercache__free(&a, w->rows);
    rendercache__free(&a, w->motion);
    rendercache__free(&a, w->moving);
    rendercache__free(&a, w->order);
    rendercache__free(&a, w->src);
    rendercache__free(&a, w->skip);
    rendercache__free(&a, w->skip_depths);
    rendercache__free(&a, w->hidden);
    rendercache__free(&a, w->layers);
    rendercache__free(&a, w);
}

RENDERCACHE_API void rendercache_warp_get_stats(const rendercache_warper *w, rendercache_warp_stats *out)
{
    if (!out) return;
    if (!w) { memset(out, 0, sizeof *out); return; }
    *out = w->stats;
}

/* Source camera space to target camera space, through an optional motion
   of the world (3x4, world at the image's time to world at the target's;
   NULL: static): x_target = R_t (D (R_s^T x + e_s) - e_t). Composed in
   double. */
static void rendercache__warp_matrix(const rendercache__view *s, const rendercache__view *t, const float *motion,
                                     float out[12])
{
    double sw[12], m[12];   /* source camera to world, then moved */
    int i, j;
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) sw[4 * i + j] = s->axis[j][i];   /* R_s^T */
        sw[4 * i + 3] = s->eye[i];
    }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 4; j++)
            m[4 * i + j] = motion ? (double)motion[4 * i] * sw[j] + (double)motion[4 * i + 1] * sw[4 + j] +
                                        (double)motion[4 * i + 2] * sw[8 + j] + (j == 3 ? (double)motion[4 * i + 3] : 0.0)
                                  : sw[4 * i + j];
    for (i = 0; i < 3; i++)
        for (j = 0; j < 4; j++) {
            const float *r = t->axis[i];
            double v = r[0] * m[j] + r[1] * m[4 + j] + r[2] * m[8 + j];
            if (j == 3) v -= (double)r[0] * t->eye[0] + (double)r[1] * t->eye[1] + (double)r[2] * t->eye[2];
            out[4 * i + j] = (float)v;
        }
}

/* One input of a warp. The splat's elements are the pixels of all inputs,
   input after input in rank order (nearest eye first). */
typedef struct rendercache__warp_src {
    const rendercache_range_image *image;
    rendercache__view source;
    const rendercache__view *target;
    float m[12];                 /* source camera space -> target camera space, static pixels */
    const float *motion;         /* NULL, or 12 floats per object id < motion_count */
    uint32_t motion_count;
    uint32_t first;              /* its first element */
    uint32_t count;              /* its pixels */
    float bias;                  /* its squared distances are compared times (1 + tolerance)^(2 rank) */
    float inv_bias;
    int same_view;               /* the target is its own camera: static pixels stay in place */
    const unsigned char *moving; /* with motion: per object id < motion_count, 1 when it moves */
    float cull[5][3];            /* planes of the target's frustum whose outside holds this input's eye,
                                    as normals in source camera space: a ray pointing outside one of
                                    them misses the target image at every depth */
    uint32_t cull_count;
    float planes[5][5];          /* all five planes: a point d r of the input (r its unit ray, d its
                                    depth) is on the inside of plane k when d (a . r) + o >= 0, with
                                    (a, o, |a|) = planes[k]; a background direction r when a . r >= 0 */
    const unsigned char *skip;   /* per tile of CULL_TILE^2 pixels: 1 when no pixel of it, nor of
                                    the ring of pixels around it, lands in the target; NULL: none */
    uint32_t tiles_x, tiles_y;
    const rendercache_range_prepared *prepared;   /* the image's (when it fits the image), or NULL */
} rendercache__warp_src;

/* All inputs of a splat, and the foreground fill's parameters. */
typedef struct rendercache__warp_set {
    const rendercache__warp_src *src;
    uint32_t count;
    float tol2x;                 /* foreground quads: squared (1 + 2 tolerance) */
    float max_extent;            /* foreground quads: largest in pixels */
    float *rows;                 /* foreground quads: per job, 3 rows of 4 floats and 2 rows of flags */
    size_t rows_per_job;         /* floats */
    uint64_t *hidden;            /* foreground quads: per job, the coarse z-buffer (warp_hidden_build) */
    uint32_t blocks_x, blocks_y; /* its blocks of HIDDEN_BLOCK^2 target pixels */
} rendercache__warp_set;

/* The input holding element e. */
static uint32_t rendercache__warp_input(const rendercache__warp_set *set, uint32_t e)
{
    uint32_t lo = 0, hi = set->count - 1;
    while (lo < hi) {
        uint32_t mid = (lo + hi + 1) / 2;
        if (set->src[mid].first <= e) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

/* The input holding element e, for pixels of the target that come from
   any input in turn: without branches for a few inputs. */
static uint32_t rendercache__warp_input_of(const rendercache__warp_set *set, uint32_t e)
{
    uint32_t i, k = 0;
    if (set->count > 8) return rendercache__warp_input(set, e);
    for (i = 1; i < set->count; i++) k += e >= set->src[i].first;
    return k;
}

/* Frustum culling of a batch of rays (camera-space directions, ok = has a
   ray): 1 when there is no ray (skipped tiles), or when every ray points
   outside one of the input's cull planes, so that no depth brings it into
   the target image. A known flaw, kept so that warps give the same images
   as before tile culling: a quad joining a culled batch of one row to the
   next row is dropped even where it reaches the image (a hole at the image
   border, which the background fill then covers); the tiles alone, with
   their ring of pixels, would keep it. */
static int rendercache__warp_culled(const rendercache__warp_src *ws, const float *dx, const float *dy, const float *dz,
                                    const unsigned char *ok, uint32_t n)
{
    uint32_t k, i, any = 0;
    for (i = 0; i < n; i++) any |= ok[i];
    if (!any) return 1;
    for (k = 0; k < ws->cull_count; k++) {
        const float a = ws->cull[k][0], b = ws->cull[k][1], c = ws->cull[k][2];
        uint32_t inside = 0;   /* an integer reduction: it vectorises */
        for (i = 0; i < n; i++) inside |= (uint32_t)(ok[i] & (a * dx[i] + b * dy[i] + c * dz[i] >= 0.0f));
        if (!inside) return 1;
    }
    return 0;
}

/* The cull planes of a static input into a perspective target: the image's
   four edges and the plane of the eye, as inward normals n in target camera
   space; a plane qualifies when the input's eye lies on its outside
   (n . b <= 0, b its eye in target camera space). A ray x of the input then
   lands at n . (A x d + b), outside for every depth d when (A^T n) . x < 0. */
static void rendercache__warp_cull_planes(rendercache__warp_src *ws)
{
    const rendercache__view *t = ws->target;
    const float f = t->focal, w = (float)t->width, h = (float)t->height, *m = ws->m;
    float n[5][3];
    int k, i;
    n[0][0] = f; n[0][1] = 0.0f; n[0][2] = t->cx;             /* x >= 0 */
    n[1][0] = -f; n[1][1] = 0.0f; n[1][2] = w - t->cx;        /* x < w */
    n[2][0] = 0.0f; n[2][1] = -f; n[2][2] = t->cy;            /* y >= 0 */
    n[3][0] = 0.0f; n[3][1] = f; n[3][2] = h - t->cy;         /* y < h */
    n[4][0] = 0.0f; n[4][1] = 0.0f; n[4][2] = 1.0f;           /* in front of the eye */
    ws->cull_count = 0;
    for (k = 0; k < 5; k++) {
        float *pl = ws->planes[k];
        for (i = 0; i < 3; i++) pl[i] = n[k][0] * m[i] + n[k][1] * m[4 + i] + n[k][2] * m[8 + i];
        pl[3] = n[k][0] * m[3] + n[k][1] * m[7] + n[k][2] * m[11];
        pl[4] = sqrtf(pl[0] * pl[0] + pl[1] * pl[1] + pl[2] * pl[2]);
        if (pl[3] > 0.0f) continue;
        memcpy(ws->cull[ws->cull_count++], pl, 3 * sizeof(float));
    }
}

/* ---- culling of whole tiles of an input -------------------------------
   Most pixels of a fish-eye base view land outside a perspective target.
   A tile of pixels is skipped (no ray, no projection, no quad) when all
   its points lie outside one plane of the target's frustum: their rays
   lie in a cone (centre ray c, half angle alpha, bounded from the camera
   model) and their depths in [dmin, dmax], so that d (a . r) + o is at
   most max(dmax M, dmin M) + o with M the largest a . r over the cone.
   The bounds take the ring of pixels around the tile too: every quad with
   a corner in a skipped tile then lies outside the same plane, and no quad
   that reaches the image loses a corner. */
#define RENDERCACHE__CULL_MARGIN 1e-3f   /* relative slack for rounding (angles in radians, and the plane test) */
#define RENDERCACHE__BOUNDS_BLOCK 64u    /* columns of a tile row whose depth bounds are taken together */
enum { RENDERCACHE__TILE_KEEP = 0, RENDERCACHE__TILE_SKIP = 1, RENDERCACHE__TILE_DEPTH = 2 };   /* tile classes */

/* The unit camera-space ray through image point (px, py), continued past a
   fish-eye's circle (the polynomials stay accurate to 1e-7 there); returns
   the angular radius (radians) of the rays of the square of half diagonal
   `reach` pixels around it, or -1 when the camera model has no such bound
   (sphere). */
static float rendercache__view_cone(const rendercache__view *v, float px, float py, float reach, float c[3])
{
    float l;
    if (v->kind == RENDERCACHE_CAMERA_FISHEYE) {   /* equidistant: angles grow at most pi/2 per radius */
        float u = (px - v->cx) / v->radius, w = (py - v->cy) / v->radius, q = u * u + w * w;
        float sr = rendercache__poly6(rendercache__fish_sin, q);   /* sin(theta) / r */
        c[0] = u * sr;
        c[1] = -w * sr;
        c[2] = rendercache__poly6(rendercache__fish_cos, q);
        return reach * (float)(RENDERCACHE__PI / 2) / v->radius;
    }
    if (v->kind != RENDERCACHE_CAMERA_PERSPECTIVE) return -1.0f;
    c[0] = (px - v->cx) / v->focal;   /* a segment of length L on the plane at distance >= focal spans
                                         at most L / focal radians */
    c[1] = (v->cy - py) / v->focal;
    c[2] = 1.0f;
    l = sqrtf(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    c[0] /= l; c[1] /= l; c[2] /= l;
    return reach / v->focal;
}

/* The largest a . r over unit vectors r within angle alpha (< pi/2, given
   by its cosine and sine) of c; len = |a|. */
static float rendercache__cone_max(const float a[3], float len, const float c[3], float cos_a, float sin_a)
{
    float ac = a[0] * c[0] + a[1] * c[1] + a[2] * c[2], perp2 = len * len - ac * ac;
    if (ac >= len * cos_a) return len;   /* a inside the cone */
    return ac * cos_a + sqrtf(perp2 > 0.0f ? perp2 : 0.0f) * sin_a;
}

/* Per tile of the inputs (no ring): the least and largest depth of its
   points, and bit 0 set when it has points, bit 1 when background pixels. */
typedef struct rendercache__tile_bounds {
    float *lo, *hi;
    unsigned char *kinds;
} rendercache__tile_bounds;

/* The bounds of the tiles of tile row ty of an image whose need[] is set
   (the others are left as they are; need NULL: all). Its pixels are taken in blocks of
   RENDERCACHE__BOUNDS_BLOCK columns: each column's bounds down the tile
   row first (a loop over the columns, without branches, that vectorises),
   then each tile's from its columns. */
static void rendercache__tile_row_bounds(const rendercache_range_image *img, uint32_t ty, const unsigned char *need,
                                         float *lo, float *hi, unsigned char *kinds)
{
    const uint32_t sw = img->camera.width, sh = img->camera.height, t = RENDERCACHE__CULL_TILE;
    const uint32_t y0 = ty * t, y1 = y0 + t < sh ? y0 + t : sh;
    float col_lo[RENDERCACHE__BOUNDS_BLOCK], col_hi[RENDERCACHE__BOUNDS_BLOCK];
    unsigned char col_kind[RENDERCACHE__BOUNDS_BLOCK];
    uint32_t x0, x, y;
    for (x0 = 0; x0 < sw; x0 += RENDERCACHE__BOUNDS_BLOCK) {
        const uint32_t n = sw - x0 < RENDERCACHE__BOUNDS_BLOCK ? sw - x0 : RENDERCACHE__BOUNDS_BLOCK;
        unsigned char any = need == NULL;
        for (x = 0; need && x < n; x += t) any |= need[(x0 + x) / t];
        if (!any) continue;
        for (x = 0; x < n; x++) { col_lo[x] = FLT_MAX; col_hi[x] = 0.0f; col_kind[x] = 0; }
        for (y = y0; y < y1; y++) {
            const uint32_t *RENDERCACHE__RESTRICT obj = img->object + (size_t)y * sw + x0;
            const float *RENDERCACHE__RESTRICT dep = img->depth + (size_t)y * sw + x0;
            for (x = 0; x < n; x++) {
                uint32_t point = (obj[x] < RENDERCACHE_NO_SAMPLE) & (dep[x] > 0.0f) & (dep[x] <= FLT_MAX);
                float dl = point ? dep[x] : FLT_MAX, dh = point ? dep[x] : 0.0f;
                col_lo[x] = dl < col_lo[x] ? dl : col_lo[x];
                col_hi[x] = dh > col_hi[x] ? dh : col_hi[x];
                col_kind[x] = (unsigned char)(col_kind[x] | point | (uint32_t)(obj[x] == RENDERCACHE_MISS) << 1);
            }
        }
        for (x = 0; x < n; x += t) {   /* x0 and the block size are multiples of the tile size */
            uint32_t q = (x0 + x) / t, e = x + t < n ? x + t : n, c;
            float l = FLT_MAX, h = 0.0f;
            unsigned char k = 0;
            for (c = x; c < e; c++) {
                l = col_lo[c] < l ? col_lo[c] : l;
                h = col_hi[c] > h ? col_hi[c] : h;
                k |= col_kind[c];
            }
            lo[q] = l;
            hi[q] = h;
            kinds[q] = k;
        }
    }
}

/* The class of tile (tx, ty) of input ws from the cone of its rays (half
   angle given by its cosine and sine) and m[k], the largest a . r over the
   cone for each plane: TILE_SKIP when outside a plane at every depth,
   TILE_KEEP when no plane can leave it outside at any depth, else
   TILE_DEPTH (the depths decide). */
static int rendercache__tile_class(const rendercache__warp_src *ws, uint32_t tx, uint32_t ty, float cos_a, float sin_a,
                                   float m[5])
{
    const uint32_t t = RENDERCACHE__CULL_TILE;
    float c[3];
    int k, depth = 0;
    rendercache__view_cone(&ws->source, ((float)tx + 0.5f) * (float)t, ((float)ty + 0.5f) * (float)t, 0.0f, c);
    for (k = 0; k < 5; k++) {
        m[k] = rendercache__cone_max(ws->planes[k], ws->planes[k][4], c, cos_a, sin_a);
        if (m[k] < 0.0f && ws->planes[k][3] < 0.0f) return RENDERCACHE__TILE_SKIP;
        depth |= (m[k] < 0.0f) | (ws->planes[k][3] < 0.0f);   /* near points, or far ones, may lie outside */
    }
    return depth ? RENDERCACHE__TILE_DEPTH : RENDERCACHE__TILE_KEEP;
}

/* The bounds of tile (tx, ty) of a grid of nx x ny tiles with its ring of
   pixels: those of the tiles around it, from the tiles' own bounds b. */
static void rendercache__tile_ring_bounds(const rendercache__tile_bounds *b, uint32_t nx, uint32_t ny, uint32_t tx,
                                          uint32_t ty, float *lo, float *hi, unsigned char *kinds)
{
    uint32_t qx, qy;
    float dlo = FLT_MAX, dhi = 0.0f;
    unsigned char k = 0;
    for (qy = ty > 0 ? ty - 1 : 0; qy <= ty + 1 && qy < ny; qy++)
        for (qx = tx > 0 ? tx - 1 : 0; qx <= tx + 1 && qx < nx; qx++) {
            uint32_t q = qy * nx + qx;
            dlo = b->lo[q] < dlo ? b->lo[q] : dlo;
            dhi = b->hi[q] > dhi ? b->hi[q] : dhi;
            k |= b->kinds[q];
        }
    *lo = dlo;
    *hi = dhi;
    *kinds = k;
}

/* Whether a tile of class TILE_DEPTH can be skipped, from m (see
   tile_class) and the bounds of the tile with its ring of pixels. */
static int rendercache__tile_skipped(const rendercache__warp_src *ws, float dlo, float dhi, unsigned char kinds,
                                     const float m[5])
{
    int k;
    if (!kinds) return 1;   /* nothing to warp */
    for (k = 0; k < 5; k++) {
        const float *pl = ws->planes[k], len = pl[4];
        float slack = RENDERCACHE__CULL_MARGIN * (fabsf(pl[3]) + ((kinds & 1u) ? dhi : 1.0f) * len);
        float most = (m[k] >= 0.0f ? dhi * m[k] : dlo * m[k]) + pl[3];   /* the largest d (a . r) + o */
        if ((!(kinds & 1u) || most < -slack) && (!(kinds & 2u) || m[k] < -RENDERCACHE__CULL_MARGIN * len)) return 1;
    }
    return 0;
}

/* ---- prepared images: what culling reads of an input, once -----------
   The depth bounds of an input's tiles depend on the image alone, and a
   base view is warped into frame after frame: rendercache_range_image_
   prepare computes them once, rings included, rather than every warp
   reading the depths and objects of half its tiles again (8 bytes a
   pixel). */
struct rendercache_range_prepared {
    uint32_t width, height;            /* the image's size when prepared */
    const float *depth;                /* and its arrays: a warp checks that they are still the image's */
    const uint32_t *object;
    uint32_t tiles_x, tiles_y;
    rendercache__tile_bounds ring;     /* per tile, its ring of pixels included */
    rendercache_allocator allocator;   /* the image's when prepared */
};

/* Whether an image's prepared data (if any) was made for its size and arrays. */
static int rendercache__prepared_fits(const rendercache_range_image *img)
{
    const rendercache_range_prepared *p = img->prepared;
    return !p || (p->width == img->camera.width && p->height == img->camera.height && p->depth == img->depth &&
                  p->object == img->object);
}

static void rendercache__prepared_ring(const rendercache_range_prepared *p, uint32_t tx, uint32_t ty, float *lo,
                                       float *hi, unsigned char *kinds)
{
    size_t q = (size_t)ty * p->tiles_x + tx;
    *lo = p->ring.lo[q];
    *hi = p->ring.hi[q];
    *kinds = p->ring.kinds[q];
}

RENDERCACHE_API void rendercache_range_image_unprepare(rendercache_range_image *image)
{
    rendercache_range_prepared *p;
    if (!image || !image->prepared) return;
    p = image->prepared;
    image->prepared = NULL;
    rendercache__free(&p->allocator, p);
}

RENDERCACHE_API rendercache_result rendercache_range_image_prepare(rendercache_range_image *image)
{
    const uint32_t t = RENDERCACHE__CULL_TILE;
    rendercache__view v;
    rendercache__tile_bounds own;   /* each tile's own bounds, then the rings' from them */
    rendercache_range_prepared *p;
    uint32_t nx, ny, tx, ty;
    size_t tiles;
    rendercache_range_image_unprepare(image);
    if (!rendercache__range_valid(image, &v) || !rendercache__allocator_valid(&image->allocator))
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    nx = (v.width + t - 1) / t;
    ny = (v.height + t - 1) / t;
    tiles = (size_t)nx * ny;   /* at most 2^28 pixels: no overflow below */
    p = (rendercache_range_prepared *)rendercache__alloc(&image->allocator,
                                                         sizeof *p + tiles * 2 * (2 * sizeof(float) + 1));
    if (!p) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    p->width = v.width;
    p->height = v.height;
    p->depth = image->depth;
    p->object = image->object;
    p->tiles_x = nx;
    p->tiles_y = ny;
    p->allocator = image->allocator;
    p->ring.lo = (float *)(void *)(p + 1);
    p->ring.hi = p->ring.lo + tiles;
    own.lo = p->ring.hi + tiles;
    own.hi = own.lo + tiles;
    p->ring.kinds = (unsigned char *)(own.hi + tiles);
    own.kinds = p->ring.kinds + tiles;
    for (ty = 0; ty < ny; ty++)
        rendercache__tile_row_bounds(image, ty, NULL, own.lo + (size_t)ty * nx, own.hi + (size_t)ty * nx,
                                     own.kinds + (size_t)ty * nx);
    for (ty = 0; ty < ny; ty++)
        for (tx = 0; tx < nx; tx++) {
            size_t q = (size_t)ty * nx + tx;
            rendercache__tile_ring_bounds(&own, nx, ny, tx, ty, &p->ring.lo[q], &p->ring.hi[q], &p->ring.kinds[q]);
        }
    image->prepared = p;
    return RENDERCACHE_OK;
}

/* Jobs over the tile rows of all inputs of a set, in three passes: the
   class of every tile from its cone (in the skip flags), the depth bounds
   of the tiles next to one of class TILE_DEPTH (the others are not read:
   half of the tiles of a fish-eye are decided by their cone), then the
   skip flags. */
typedef struct rendercache__cull_tiles_job {
    const rendercache__warp_set *set;
    rendercache__tile_bounds bounds;   /* all inputs', tile after tile in the order of the skip flags */
} rendercache__cull_tiles_job;

/* The input holding tile row *row of the set's culled inputs (*row becomes
   a row of it), and the offset of its tiles. */
static const rendercache__warp_src *rendercache__tiles_input(const rendercache__warp_set *set, uint32_t *row, size_t *at)
{
    uint32_t i;
    *at = 0;
    for (i = 0; i < set->count; i++) {
        const rendercache__warp_src *ws = &set->src[i];
        if (!ws->skip) continue;
        if (*row < ws->tiles_y) return ws;
        *row -= ws->tiles_y;
        *at += (size_t)ws->tiles_x * ws->tiles_y;
    }
    return NULL;
}

/* The half angle of the rays of a tile and its ring of pixels, as cosine
   and sine. */
static void rendercache__tile_cone_angle(const rendercache__warp_src *ws, float *cos_a, float *sin_a)
{
    const float reach = 0.7072f * (float)(RENDERCACHE__CULL_TILE + 2);   /* half diagonal, ring included */
    float c[3], alpha = rendercache__view_cone(&ws->source, 0.0f, 0.0f, reach, c);
    alpha = alpha * (1.0f + RENDERCACHE__CULL_MARGIN) + RENDERCACHE__CULL_MARGIN;
    if (alpha > 1.5f) alpha = 1.5f;   /* a coarse view: then only tiles behind a plane are skipped */
    *cos_a = cosf(alpha);
    *sin_a = sinf(alpha);
}

static void rendercache__tile_class_job(void *ctx, uint32_t row)
{
    const rendercache__cull_tiles_job *j = (const rendercache__cull_tiles_job *)ctx;
    size_t at;
    const rendercache__warp_src *ws = rendercache__tiles_input(j->set, &row, &at);
    unsigned char *cls = (unsigned char *)ws->skip + (size_t)row * ws->tiles_x;
    float cos_a, sin_a, m[5];
    uint32_t tx;
    rendercache__tile_cone_angle(ws, &cos_a, &sin_a);
    for (tx = 0; tx < ws->tiles_x; tx++) cls[tx] = (unsigned char)rendercache__tile_class(ws, tx, row, cos_a, sin_a, m);
}

static void rendercache__tile_bounds_job(void *ctx, uint32_t row)
{
    const rendercache__cull_tiles_job *j = (const rendercache__cull_tiles_job *)ctx;
    size_t at;
    const rendercache__warp_src *ws = rendercache__tiles_input(j->set, &row, &at);
    const uint32_t nx = ws->tiles_x;
    unsigned char need[4096];   /* per tile of the row: its bounds are wanted (wider inputs: all) */
    uint32_t tx, qy;
    if (ws->prepared) return;   /* the image's own, with the rings */
    if (nx <= sizeof need) {
        memset(need, 0, nx);
        for (qy = row > 0 ? row - 1 : 0; qy <= row + 1 && qy < ws->tiles_y; qy++)
            for (tx = 0; tx < nx; tx++) {
                if (ws->skip[(size_t)qy * nx + tx] != RENDERCACHE__TILE_DEPTH) continue;
                need[tx] = 1;
                if (tx > 0) need[tx - 1] = 1;
                if (tx + 1 < nx) need[tx + 1] = 1;
            }
    }
    at += (size_t)row * nx;
    rendercache__tile_row_bounds(ws->image, row, nx <= sizeof need ? need : NULL, j->bounds.lo + at, j->bounds.hi + at,
                                 j->bounds.kinds + at);
}

static void rendercache__tile_skip_job(void *ctx, uint32_t row)
{
    const rendercache__cull_tiles_job *j = (const rendercache__cull_tiles_job *)ctx;
    rendercache__tile_bounds b = j->bounds;
    size_t at;
    const rendercache__warp_src *ws = rendercache__tiles_input(j->set, &row, &at);
    unsigned char *skip = (unsigned char *)ws->skip + (size_t)row * ws->tiles_x;
    float cos_a, sin_a, m[5];
    uint32_t tx;
    rendercache__tile_cone_angle(ws, &cos_a, &sin_a);
    b.lo += at; b.hi += at; b.kinds += at;
    for (tx = 0; tx < ws->tiles_x; tx++) {
        float lo, hi;
        unsigned char kinds;
        if (skip[tx] != RENDERCACHE__TILE_DEPTH) continue;   /* TILE_KEEP is 0, TILE_SKIP 1: already the flag */
        rendercache__tile_class(ws, tx, row, cos_a, sin_a, m);
        if (ws->prepared) rendercache__prepared_ring(ws->prepared, tx, row, &lo, &hi, &kinds);
        else rendercache__tile_ring_bounds(&b, ws->tiles_x, ws->tiles_y, tx, row, &lo, &hi, &kinds);
        skip[tx] = (unsigned char)rendercache__tile_skipped(ws, lo, hi, kinds, m);
    }
}

/* Static pixels [i0, i1) of a batch (objects, depths, ray directions) into
   a perspective target: the projection of rendercache__project_perspective,
   fused with the pixels' rays and written to vectorise. */
static void rendercache__warp_project_static(const rendercache__warp_src *ws, const uint32_t *obj, const float *dep,
                                             const float *dx, const float *dy, const float *dz, uint32_t i0,
                                             uint32_t i1, float *RENDERCACHE__RESTRICT px,
                                             float *RENDERCACHE__RESTRICT py, float *RENDERCACHE__RESTRICT d2,
                                             unsigned char *RENDERCACHE__RESTRICT ok)
{
    const rendercache__view *t = ws->target;
    const float *m = ws->m, f = t->focal, cx = t->cx, cy = t->cy, bias = ws->bias;
    uint32_t i;
    for (i = i0; i < i1; i++) {
        uint32_t o = obj[i];
        float d = dep[i];
        int point = (o < RENDERCACHE_NO_SAMPLE) & (d > 0.0f) & (d <= FLT_MAX);
        int valid = ok[i] & (point | (o == RENDERCACHE_MISS));
        float s = point ? d : 1.0f, off = point ? 1.0f : 0.0f;   /* background: a direction */
        float x0 = dx[i] * s, x1 = dy[i] * s, x2 = dz[i] * s;
        float c0 = m[0] * x0 + m[1] * x1 + m[2] * x2 + off * m[3];
        float c1 = m[4] * x0 + m[5] * x1 + m[6] * x2 + off * m[7];
        float c2 = m[8] * x0 + m[9] * x1 + m[10] * x2 + off * m[11];
        float inv = 1.0f / c2, x = cx + f * c0 * inv, y = cy - f * c1 * inv;
        float e = (c0 * c0 + c1 * c1 + c2 * c2) * bias;   /* may overflow: capped at the background's */
        px[i] = x;
        py[i] = y;
        d2[i] = point ? rendercache__minf(e, RENDERCACHE__FAR2) : RENDERCACHE__FAR2;
        ok[i] = (unsigned char)(valid & (c2 > 0.0f) & (fabsf(x) < RENDERCACHE__MAX_PLANE) &
                                (fabsf(y) < RENDERCACHE__MAX_PLANE));   /* and not NaN */
    }
}

/* The length (at most n) of the run of pixels from (x, y) of an input whose
   tiles are all skipped or all kept (*skipped tells which). */
static uint32_t rendercache__skip_run(const rendercache__warp_src *ws, uint32_t y, uint32_t x, uint32_t n, int *skipped)
{
    const uint32_t t = RENDERCACHE__CULL_TILE;
    const unsigned char *row = ws->skip + (size_t)(y / t) * ws->tiles_x;
    uint32_t tx = x / t, end = x + n, e = (tx + 1) * t;
    *skipped = row[tx];
    while (e < end && row[e / t] == row[tx]) e += t;
    return (e < end ? e : end) - x;
}

/* Whether every pixel of [begin, end) of an input lies in a skipped tile. */
static int rendercache__range_skipped(const rendercache__warp_src *ws, uint32_t begin, uint32_t end)
{
    const uint32_t sw = ws->source.width, t = RENDERCACHE__CULL_TILE;
    uint32_t p = begin;
    while (p < end) {   /* row by row: the flags of the tiles the row segment crosses */
        uint32_t y = p / sw, x = p - y * sw, k = sw - x < end - p ? sw - x : end - p, tx;
        const unsigned char *row = ws->skip + (size_t)(y / t) * ws->tiles_x;
        unsigned char all = 1;
        for (tx = x / t; tx <= (x + k - 1) / t; tx++) all &= row[tx];
        if (!all) return 0;
        p += k;
    }
    return 1;
}

/* Pixels [begin, end) of one input (its own pixel indices) into the
   target's image plane: px, py (not clipped to the image), the squared
   distance times the input's bias (background pixels: FAR2, unbiased, so
   that the nearer input's background wins on the element index), and
   ok = 1 where the pixel has a projection (RENDERCACHE__IN_PLACE when it
   stays exactly on its own pixel: same camera, not moving). Pixels without a ray,
   RENDERCACHE_NO_SAMPLE and depths that are not finite and positive are
   not ok. Static pixels into a perspective target take a loop written to
   vectorise (the projection of rendercache__project_perspective, fused with
   the pixels' rays); moving objects and other targets go pixel by pixel
   through view_to_plane. */
static uint32_t rendercache__warp_project(const rendercache__warp_src *ws, uint32_t begin, uint32_t end,
                                          float *RENDERCACHE__RESTRICT px, float *RENDERCACHE__RESTRICT py,
                                          float *RENDERCACHE__RESTRICT d2, unsigned char *RENDERCACHE__RESTRICT ok)
{
    const rendercache_range_image *img = ws->image;
    const rendercache__view *t = ws->target;
    const uint32_t sw = ws->source.width, *obj = img->object + begin;
    const float *dep = img->depth + begin, bias = ws->bias;
    float dx[RENDERCACHE__BATCH], dy[RENDERCACHE__BATCH], dz[RENDERCACHE__BATCH];
    uint32_t p = begin, i = 0, n = end - begin, any = 0;
    if (ws->skip && rendercache__range_skipped(ws, begin, end)) {
        memset(ok, 0, n);
        return 0;
    }
    while (p < end) {   /* the rays, in row segments cut where tiles start or stop being skipped */
        uint32_t y = p / sw, x = p - y * sw, k = sw - x;
        int skipped = 0;
        if (k > end - p) k = end - p;
        if (ws->skip) k = rendercache__skip_run(ws, y, x, k, &skipped);
        if (skipped) {
            memset(ok + i, 0, k);
            memset(dx + i, 0, k * sizeof *dx);
            memset(dy + i, 0, k * sizeof *dy);
            memset(dz + i, 0, k * sizeof *dz);
        } else {
            rendercache__view_row_dirs(&ws->source, y, x, k, dx + i, dy + i, dz + i, ok + i);
            any = 1;
        }
        p += k;
        i += k;
    }
    if (!any) {
        memset(ok, 0, n);
        return 0;
    }
    if (t->kind == RENDERCACHE_CAMERA_PERSPECTIVE && !ws->motion) {
        uint32_t k0, k1, kept = 0;
        for (k0 = 0; k0 < n; k0 = k1) {   /* chunks of rays that all miss the target are skipped */
            k1 = k0 + RENDERCACHE__CULL_CHUNK < n ? k0 + RENDERCACHE__CULL_CHUNK : n;
            if (rendercache__warp_culled(ws, dx + k0, dy + k0, dz + k0, ok + k0, k1 - k0)) {
                memset(ok + k0, 0, k1 - k0);
            } else {
                rendercache__warp_project_static(ws, obj, dep, dx, dy, dz, k0, k1, px, py, d2, ok);
                kept += k1 - k0;
            }
        }
        return kept;
    }
    for (i = 0; i < n; i++) {
        uint32_t o = obj[i];
        float d = dep[i], x[3], c[3];
        int point = o < RENDERCACHE_NO_SAMPLE && d > 0.0f && d <= FLT_MAX;
        const float *m = ws->m;
        if (!ok[i] || !(point || o == RENDERCACHE_MISS)) { ok[i] = 0; continue; }
        if (ws->same_view && (!point || !ws->motion || o >= ws->motion_count || !ws->moving[o])) {
            /* into its own camera, not moving: the pixel's own centre, exactly */
            uint32_t e = begin + i, y = e / sw;
            px[i] = (float)(e - y * sw) + 0.5f;
            py[i] = (float)y + 0.5f;
            d2[i] = point ? rendercache__minf(d * d * bias, RENDERCACHE__FAR2) : RENDERCACHE__FAR2;
            ok[i] = RENDERCACHE__IN_PLACE;
            continue;
        }
        x[0] = dx[i]; x[1] = dy[i]; x[2] = dz[i];
        if (point) {
            x[0] *= d; x[1] *= d; x[2] *= d;
            if (ws->motion && o < ws->motion_count) m = ws->motion + 12 * (size_t)o;
            rendercache__affine(m, x, c);
            d2[i] = rendercache__minf((c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) * bias, RENDERCACHE__FAR2);
        } else {   /* a direction: rotated only */
            c[0] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2];
            c[1] = m[4] * x[0] + m[5] * x[1] + m[6] * x[2];
            c[2] = m[8] * x[0] + m[9] * x[1] + m[10] * x[2];
            d2[i] = RENDERCACHE__FAR2;
        }
        ok[i] = (unsigned char)(rendercache__view_to_plane(t, c, &px[i], &py[i]) && fabsf(px[i]) < RENDERCACHE__MAX_PLANE &&
                                fabsf(py[i]) < RENDERCACHE__MAX_PLANE);
    }
    return n;
}

/* The splat source of a warp without foreground quads: elements [begin,
   end), each to the pixel it lands in. */
static uint32_t rendercache__warp_source(const void *src, uint32_t begin, uint32_t end, uint32_t *pix, float *depth2)
{
    const rendercache__warp_set *set = (const rendercache__warp_set *)src;
    float px[RENDERCACHE__BATCH], py[RENDERCACHE__BATCH];
    unsigned char ok[RENDERCACHE__BATCH];
    uint32_t e = begin, any = 0;
    while (e < end) {
        const rendercache__warp_src *ws = &set->src[rendercache__warp_input(set, e)];
        const uint32_t local = e - ws->first, n = end - e < ws->count - local ? end - e : ws->count - local;
        const uint32_t width = ws->target->width, o = e - begin;
        const float w = (float)ws->target->width, h = (float)ws->target->height;
        uint32_t i;
        uint32_t *out = pix + o, inside_any = 0;
        e += n;
        if (!rendercache__warp_project(ws, local, local + n, px, py, depth2 + o, ok)) {
            memset(out, 0xFF, n * sizeof *out);   /* RENDERCACHE__NONE */
            continue;
        }
        for (i = 0; i < n; i++) {   /* through int: the conversion that vectorises everywhere */
            int inside = (ok[i] != 0) & (px[i] >= 0.0f) & (px[i] < w) & (py[i] >= 0.0f) & (py[i] < h);
            int xs = (int)(inside ? px[i] : 0.0f), ys = (int)(inside ? py[i] : 0.0f);
            out[i] = inside ? (uint32_t)ys * width + (uint32_t)xs : RENDERCACHE__NONE;
            inside_any |= (uint32_t)inside;
        }
        any |= inside_any;
    }
    return any;
}

/* Payload of a source pixel: its colour and its object id (bits). */
static void rendercache__warp_payload(const void *src, uint32_t begin, uint32_t end, const uint32_t *pix,
                                      float *payload)
{
    const rendercache__warp_set *set = (const rendercache__warp_set *)src;
    uint32_t e = begin;
    while (e < end) {
        const rendercache__warp_src *ws = &set->src[rendercache__warp_input(set, e)];
        const uint32_t local = e - ws->first, n = end - e < ws->count - local ? end - e : ws->count - local;
        const float *rgb = ws->image->rgb;
        const uint32_t *obj = ws->image->object;
        uint32_t i;
        for (i = 0; i < n; i++) {
            float *out = payload + 4 * (size_t)(e - begin + i);
            if (pix[e - begin + i] == RENDERCACHE__NONE) continue;
            memcpy(out, rgb + 3 * (size_t)(local + i), 3 * sizeof(float));
            memcpy(out + 3, &obj[local + i], sizeof(float));
        }
        e += n;
    }
}

/* A projected pixel in a row of warp_project_row (the same 4 floats). */
typedef struct rendercache__corner { float x, y, d, k; } rendercache__corner;


/* Row y of an input projected into the target's image plane, 4 floats per
   pixel: x, y, biased squared distance, 1 when it has a projection (else
   0). span receives the range [span[0], span[1]) outside which no pixel has
   one (empty: span[0] == span[1]). */
static void rendercache__warp_project_row(const rendercache__warp_src *ws, uint32_t y, float *row, uint32_t span[2])
{
    const uint32_t sw = ws->source.width;
    float px[RENDERCACHE__BATCH], py[RENDERCACHE__BATCH], d2[RENDERCACHE__BATCH];
    unsigned char ok[RENDERCACHE__BATCH];
    uint32_t x0, i, lo = sw, hi = 0;
    for (x0 = 0; x0 < sw; x0 += RENDERCACHE__BATCH) {
        uint32_t n = sw - x0 < RENDERCACHE__BATCH ? sw - x0 : RENDERCACHE__BATCH, first = 0, last = n;
        float *RENDERCACHE__RESTRICT r = row + 4 * (size_t)x0;
        if (!rendercache__warp_project(ws, y * sw + x0, y * sw + x0 + n, px, py, d2, ok)) continue;
        while (first < n && !ok[first]) first++;
        while (last > first && !ok[last - 1]) last--;
        if (first == last) continue;
        for (i = lo < hi ? hi : x0 + first; i < x0 + first; i++) row[4 * (size_t)i + 3] = 0.0f;   /* a gap in the span:
                                                                             no projection (else stale data) */
        lo = x0 + first < lo ? x0 + first : lo;
        hi = x0 + last;
        for (i = first; i < last; i++) {
            float k = (float)ok[i];   /* 0, 1, or 2 in place */
            r[4 * i + 0] = ok[i] ? px[i] : 0.0f;
            r[4 * i + 1] = ok[i] ? py[i] : 0.0f;
            r[4 * i + 2] = d2[i];
            r[4 * i + 3] = k;
        }
    }
    span[0] = lo < hi ? lo : 0;
    span[1] = lo < hi ? hi : 0;
}

/* Whether a triangle of a foreground quad is drawn (corners projected as by
   warp_project_row, all with a projection): their depths agree within
   twice the tolerance (so that no triangle bridges a depth edge), and it is
   not wider than max_extent. */
static RENDERCACHE__INLINE int rendercache__warp_triangle_ok(float tol2x, float max_extent, rendercache__corner a,
                                                              rendercache__corner b, rendercache__corner c)
{
    float dmin = rendercache__minf(rendercache__minf(a.d, b.d), c.d);
    float dmax = rendercache__maxf(rendercache__maxf(a.d, b.d), c.d);
    float xmin = rendercache__minf(rendercache__minf(a.x, b.x), c.x);
    float xmax = rendercache__maxf(rendercache__maxf(a.x, b.x), c.x);
    float ymin = rendercache__minf(rendercache__minf(a.y, b.y), c.y);
    float ymax = rendercache__maxf(rendercache__maxf(a.y, b.y), c.y);
    return (dmax <= dmin * tol2x) & (xmax - xmin <= max_extent) & (ymax - ymin <= max_extent);
}

/* The edge function of the directed edge u -> v, e(x, y) = A x + B y + C
   (positive on its left in image coordinates, y down), with coefficients
   computed from the endpoints in a fixed order (the smaller source pixel
   index first) and negated when reversed: the two triangles sharing an edge
   compute bit for bit opposite values, so that no pixel centre on a shared
   edge falls between them (watertight). */
typedef struct rendercache__edge { float a, b, c; } rendercache__edge;

static rendercache__edge rendercache__edge_of(const float *u, const float *v, uint32_t eu, uint32_t ev)
{
    const float *p = eu < ev ? u : v, *q = eu < ev ? v : u;
    rendercache__edge e;
    e.a = p[1] - q[1];
    e.b = q[0] - p[0];
    e.c = -(e.a * p[0] + e.b * p[1]);
    if (eu > ev) { e.a = -e.a; e.b = -e.b; e.c = -e.c; }
    return e;
}

static float rendercache__edge_at(const rendercache__edge *e, float x, float y) { return e->a * x + e->b * y + e->c; }

/* Whether target pixels [x0, x1] x [y0, y1] (in the image) lie in at most
   2 x 2 blocks of a coarse z-buffer (hidden, see warp_hidden_build) that
   all hold keys below least: then nothing with a key of least or more can
   pass a z-test there. The four blocks' largest key without branches (a
   quad's box spans one to four blocks, a coin toss for a branch
   predictor); a wider box is not tested (0). */
static RENDERCACHE__INLINE int rendercache__warp_box_hidden(const rendercache__warp_set *set, const uint64_t *hidden,
                                                            uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1,
                                                            uint64_t least)
{
    const uint32_t bx0 = x0 / RENDERCACHE__HIDDEN_BLOCK, bx1 = x1 / RENDERCACHE__HIDDEN_BLOCK;
    const uint32_t by0 = y0 / RENDERCACHE__HIDDEN_BLOCK, by1 = y1 / RENDERCACHE__HIDDEN_BLOCK;
    const uint64_t *r0 = hidden + (size_t)by0 * set->blocks_x, *r1 = hidden + (size_t)by1 * set->blocks_x;
    uint64_t m0, m1;
    if (bx1 - bx0 > 1 || by1 - by0 > 1) return 0;
    m0 = r0[bx0] > r0[bx1] ? r0[bx0] : r0[bx1];
    m1 = r1[bx0] > r1[bx1] ? r1[bx0] : r1[bx1];
    return (m0 > m1 ? m0 : m1) <= least;
}

/* Writes a pixel of a foreground triangle: weights wu, wv, ww (not yet
   normalised) of its corners u, v, w (projected rows, input pixels eu, ev, ew). */
static RENDERCACHE__INLINE void rendercache__warp_shade(const rendercache__warp_src *ws, rendercache__zbuffer *zb,
                                                        uint32_t pixel, float wu, float wv, float ww, const float *u,
                                                        const float *v, const float *w, uint32_t eu, uint32_t ev,
                                                        uint32_t ew, uint32_t e)
{
    const rendercache_range_image *img = ws->image;
    const float *cu = img->rgb + 3 * (size_t)eu, *cv = img->rgb + 3 * (size_t)ev, *cw = img->rgb + 3 * (size_t)ew;
    float s = 1.0f / (wu + wv + ww), payload[4], d;
    uint32_t o;
    wu *= s; wv *= s; ww *= s;
    d = wu * u[2] + wv * v[2] + ww * w[2];
    if (!(rendercache__key(d, e) < zb->key[pixel])) return;   /* hidden: no colour to interpolate */
    payload[0] = rendercache__finitef(wu * cu[0] + wv * cv[0] + ww * cw[0]);
    payload[1] = rendercache__finitef(wu * cu[1] + wv * cv[1] + ww * cw[1]);
    payload[2] = rendercache__finitef(wu * cu[2] + wv * cv[2] + ww * cw[2]);
    o = wu >= wv && wu >= ww ? img->object[eu] : (wv >= ww ? img->object[ev] : img->object[ew]);
    memcpy(payload + 3, &o, sizeof o);
    rendercache__zbuffer_test(zb, pixel, d, e, payload);
}

/* Draws the triangles of a foreground quad that passed warp_triangle_ok
   (flags bit 0: a b c, bit 1: a c d; corners projected as by
   warp_project_row, input pixels pa .. pd), for element e: colour and
   squared distance interpolated with the barycentric weights at the pixel
   centres inside (edges included), the object the heaviest corner's. Both
   triangles share the quad's box and the diagonal a c decides between
   them. Inlined, with warp_shade, into the loop over a row's quads: a
   quad covers about two pixels, and the calls with their dozen arguments
   cost as much as the pixels. Later inputs pass the coarse z-buffer of
   what the inputs before drew (hidden; NULL for the first): a quad whose
   box lies in blocks that all hold nearer keys is skipped before it reads
   its pixels' keys (in the office walkthrough, 4 % of the pixels that
   later inputs' quads in drawn runs test pass their z-test). */
static RENDERCACHE__INLINE void rendercache__warp_quad(const rendercache__warp_set *set, const uint64_t *hidden,
                                                       const rendercache__warp_src *ws, rendercache__zbuffer *zb,
                                                       const float *a, const float *b, const float *c, const float *d,
                                                       uint32_t pa, uint32_t pb, uint32_t pc, uint32_t pd,
                                                       unsigned flags, uint32_t e)
{
    const uint32_t w = ws->target->width, h = ws->target->height;
    rendercache__edge ab, bc, ac, cd, da;
    float xmin, xmax, ymin, ymax, s1 = 1.0f, s2 = 1.0f, dmin;
    uint64_t nearest;
    int x0, x1, y0, y1, x, y, edges = 0;
    xmin = a[0] < c[0] ? a[0] : c[0]; xmax = a[0] > c[0] ? a[0] : c[0];
    ymin = a[1] < c[1] ? a[1] : c[1]; ymax = a[1] > c[1] ? a[1] : c[1];
    if (flags & 1u) {
        xmin = b[0] < xmin ? b[0] : xmin; xmax = b[0] > xmax ? b[0] : xmax;
        ymin = b[1] < ymin ? b[1] : ymin; ymax = b[1] > ymax ? b[1] : ymax;
    }
    if (flags & 2u) {
        xmin = d[0] < xmin ? d[0] : xmin; xmax = d[0] > xmax ? d[0] : xmax;
        ymin = d[1] < ymin ? d[1] : ymin; ymax = d[1] > ymax ? d[1] : ymax;
    }
    x0 = (int)ceilf(xmin - 0.5f); x1 = (int)floorf(xmax - 0.5f);
    y0 = (int)ceilf(ymin - 0.5f); y1 = (int)floorf(ymax - 0.5f);
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 >= (int)w) x1 = (int)w - 1;
    if (y1 >= (int)h) y1 = (int)h - 1;
    if (x0 > x1 || y0 > y1) return;   /* no pixel centre in the box */
    /* the nearest corner: a pixel already nearer than it needs no edge test (and a quad
       hidden everywhere no edge at all) */
    dmin = a[2] < c[2] ? a[2] : c[2];
    if (flags & 1u) dmin = b[2] < dmin ? b[2] : dmin;
    if (flags & 2u) dmin = d[2] < dmin ? d[2] : dmin;
    nearest = rendercache__key(dmin, e);
    if (hidden && rendercache__warp_box_hidden(set, hidden, (uint32_t)x0, (uint32_t)x1, (uint32_t)y0, (uint32_t)y1,
                                               nearest))
        return;   /* behind what the inputs before drew */
    for (y = y0; y <= y1; y++) {
        float py = (float)y + 0.5f;
        for (x = x0; x <= x1; x++) {
            float px = (float)x + 0.5f, eac, w0, w1, w2;
            uint32_t pixel = (uint32_t)y * w + (uint32_t)x;
            if (!(nearest < zb->key[pixel])) continue;
            if (!edges) {
                ac = rendercache__edge_of(a, c, pa, pc);
                ab = rendercache__edge_of(a, b, pa, pb);
                bc = rendercache__edge_of(b, c, pb, pc);
                cd = rendercache__edge_of(c, d, pc, pd);
                da = rendercache__edge_of(d, a, pd, pa);
                /* orientations: the sign that makes each triangle's inside positive */
                s1 = rendercache__edge_at(&ab, c[0], c[1]) < 0.0f ? -1.0f : 1.0f;
                s2 = rendercache__edge_at(&cd, a[0], a[1]) < 0.0f ? -1.0f : 1.0f;
                edges = 1;
            }
            eac = rendercache__edge_at(&ac, px, py);
            {   /* both triangles tested without branches (which one holds a pixel is a coin toss for a
                   branch predictor), T1 = a b c (edges b c, c a, a b) before T2 = a c d (c d, d a, a c) */
                float u0 = s1 * rendercache__edge_at(&bc, px, py), u1 = -s1 * eac;
                float u2 = s1 * rendercache__edge_at(&ab, px, py);
                float v0 = s2 * rendercache__edge_at(&cd, px, py), v1 = s2 * rendercache__edge_at(&da, px, py);
                float v2 = s2 * eac;
                int t1 = (int)(flags & 1u) & (u1 >= 0.0f) & (u0 >= 0.0f) & (u2 >= 0.0f) & (u0 + u1 + u2 > 0.0f);
                int t2 = (int)(flags >> 1 & 1u) & (v2 >= 0.0f) & (v0 >= 0.0f) & (v1 >= 0.0f) & (v0 + v1 + v2 > 0.0f);
                if (!(t1 | t2)) continue;
                w0 = t1 ? u0 : v0;
                w1 = t1 ? u1 : v1;
                w2 = t1 ? u2 : v2;
                rendercache__warp_shade(ws, zb, pixel, w0, w1, w2, a, t1 ? b : c, t1 ? c : d, pa, t1 ? pb : pc,
                                        t1 ? pc : pd, e);
            }
        }
    }
}

/* With moving objects (motion-compensated warps), a triangle joins pixels of
   one object only: where a moving object touches a static surface at a
   similar depth (a bunny's feet on the floor), a triangle across the two
   would stretch as the object moves. Static warps keep bridging such
   contacts, as pinterp does. */
static void rendercache__warp_quad_flags_one_object(const rendercache__warp_src *ws, uint32_t y, size_t x, size_t end,
                                                    unsigned char *flags)
{
    const uint32_t *o0 = ws->image->object + (size_t)y * ws->source.width, *o1 = o0 + ws->source.width;
    for (; x < end; x++) {
        int upper = (o0[x] == o0[x + 1]) & (o0[x] == o1[x + 1]);   /* (x, y) (x+1, y) (x+1, y+1) */
        int lower = (o0[x] == o1[x + 1]) & (o0[x] == o1[x]);       /* (x, y) (x+1, y+1) (x, y+1) */
        flags[x] &= (unsigned char)(upper | lower << 1);
    }
}

/* A row of quad flags, computed where they are needed: the quads of
   source row y, between rows y and y + 1 (projected in r0 and r1, spans s0
   and s1), and per run of HIDDEN_RUN pixels a byte set once its flags are
   computed. */
typedef struct rendercache__flag_row {
    unsigned char *flags, *done;
    const float *r0, *r1;
    uint32_t s0[2], s1[2];
    uint32_t y;
} rendercache__flag_row;

/* Which triangles of the quads of pixels [xa, xb) of a flag row are drawn:
   bit 0 the upper-right triangle (x, y) (x+1, y) (x+1, y+1), bit 1 the
   lower-left (x, y) (x+1, y+1) (x, y+1). Quads with a corner that has no
   projection, or whose box misses the image, draw nothing (and cost
   little). */
static void rendercache__warp_quad_flags(const rendercache__warp_set *set, const rendercache__warp_src *ws,
                                         const rendercache__flag_row *fr, size_t xa, size_t xb)
{
    const float w = (float)ws->target->width, h = (float)ws->target->height, tol2x = set->tol2x;
    const float max_extent = set->max_extent;
    const rendercache__corner *c0 = (const rendercache__corner *)fr->r0, *c1 = (const rendercache__corner *)fr->r1;
    unsigned char *RENDERCACHE__RESTRICT flags = fr->flags;
    size_t start = fr->s0[0] > fr->s1[0] ? fr->s0[0] : fr->s1[0];   /* both rows projected */
    size_t end = fr->s0[1] < fr->s1[1] ? fr->s0[1] : fr->s1[1], x;
    end = end > 0 ? end - 1 : 0;   /* a quad needs its pixel's right neighbour */
    end = end < xb ? end : xb;
    start = start > xa ? start : xa;
    memset(flags + xa, 0, xb - xa);
    for (x = start; x < end; x++) {   /* without branches: the loop vectorises */
        rendercache__corner a = c0[x], b = c0[x + 1], c = c1[x + 1], d = c1[x];
        float xmin = rendercache__minf(rendercache__minf(a.x, b.x), rendercache__minf(c.x, d.x));
        float xmax = rendercache__maxf(rendercache__maxf(a.x, b.x), rendercache__maxf(c.x, d.x));
        float ymin = rendercache__minf(rendercache__minf(a.y, b.y), rendercache__minf(c.y, d.y));
        float ymax = rendercache__maxf(rendercache__maxf(a.y, b.y), rendercache__maxf(c.y, d.y));
        int projected = (a.k != 0.0f) & (b.k != 0.0f) & (c.k != 0.0f) & (d.k != 0.0f);
        /* four pixels that stay in place: their points land on the pixel centres, no quad needed */
        int in_place = (a.k == 2.0f) & (b.k == 2.0f) & (c.k == 2.0f) & (d.k == 2.0f);
        int draw = projected & !in_place & (xmax >= 0.0f) & (ymax >= 0.0f) & (xmin < w) & (ymin < h);
        flags[x] = (unsigned char)(draw * (rendercache__warp_triangle_ok(tol2x, max_extent, a, b, c) |
                                           rendercache__warp_triangle_ok(tol2x, max_extent, a, c, d) << 1));
    }
    if (ws->motion) rendercache__warp_quad_flags_one_object(ws, fr->y, start, end, flags);
}

/* Computes the flags of [x0, x1) of a flag row that are not computed yet
   (in whole runs). Later inputs need the flags only around the runs that
   are not hidden: most of their rows never compute them. */
static void rendercache__warp_flags_needed(const rendercache__warp_set *set, const rendercache__warp_src *ws,
                                           const rendercache__flag_row *fr, uint32_t x0, uint32_t x1)
{
    const uint32_t run = RENDERCACHE__HIDDEN_RUN, sw = ws->source.width;
    uint32_t c = x0 / run, c1 = (x1 + run - 1) / run, first;
    while (c < c1) {
        if (fr->done[c]) { c++; continue; }
        for (first = c; c < c1 && !fr->done[c]; c++) fr->done[c] = 1;
        rendercache__warp_quad_flags(set, ws, fr, (size_t)first * run, (size_t)c * run < sw ? (size_t)c * run : sw);
    }
}

/* A flag row of source row y (rows r0 and r1, spans s0 and s1) with no
   flags computed yet. */
static void rendercache__flag_row_start(rendercache__flag_row *fr, uint32_t y, const float *r0, const float *r1,
                                        const uint32_t s0[2], const uint32_t s1[2], uint32_t width)
{
    fr->y = y;
    fr->r0 = r0;
    fr->r1 = r1;
    memcpy(fr->s0, s0, sizeof fr->s0);
    memcpy(fr->s1, s1, sizeof fr->s1);
    memset(fr->done, 0, (width + RENDERCACHE__HIDDEN_RUN - 1) / RENDERCACHE__HIDDEN_RUN);
}

/* Whether all six triangles around source pixel x of a row are drawn, from
   the flags of the quad rows above (up, NULL on the first row) and below
   (down, NULL on the last): then they cover the pixel's surroundings and
   its point is not needed. */
static int rendercache__warp_surrounded(const unsigned char *up, const unsigned char *down, uint32_t x, uint32_t width)
{
    if (!up || !down || x == 0 || x + 1 == width) return 0;
    return up[x - 1] == 3u && (up[x] & 2u) && (down[x - 1] & 1u) && down[x] == 3u;
}

/* ---- hidden runs: most quads of later inputs lie behind nearer ones ---
   Inputs are warped nearest eye first, and each later one covers about
   the same pixels again, nearly all of them behind what the first drew (in
   the office walkthrough, 13k of the 307k pixels come from inputs 2-4 of
   4, which draw 520k quads). A coarse z-buffer keeps per block of target
   pixels the largest key in it; keys only decrease, so it stays an upper
   bound once built. A run of source pixels whose quads and points all fit
   in blocks whose largest key is below the least key any of them could
   write (their least depth, their first element) would fail every z-test:
   it is skipped, with the same result. */

/* The coarse z-buffer of a job's z-buffer (blocks_x * blocks_y keys). */
static void rendercache__warp_hidden_build(const rendercache__warp_set *set, const rendercache__zbuffer *zb, uint32_t width,
                                           uint32_t height, uint64_t *hidden)
{
    const uint32_t b = RENDERCACHE__HIDDEN_BLOCK, full = width / b;
    uint32_t x, y, bx;
    for (bx = 0; bx < set->blocks_x * set->blocks_y; bx++) hidden[bx] = 0;
    for (y = 0; y < height; y++) {
        const uint64_t *key = zb->key + (size_t)y * width;
        uint64_t *row = hidden + (size_t)(y / b) * set->blocks_x;
        for (bx = 0; bx < full; bx++) {   /* whole blocks: a fixed count the compiler unrolls */
            uint64_t m = row[bx];
            for (x = 0; x < b; x++) m = key[bx * b + x] > m ? key[bx * b + x] : m;
            row[bx] = m;
        }
        for (x = full * b; x < width; x++) row[full] = key[x] > row[full] ? key[x] : row[full];
    }
}

/* Whether the quads of pixels [x0, x1) of source row y (corners in rows r0,
   r1, r1 NULL on the last row) and their points would all fail their
   z-tests against the coarse z-buffer; e0 is the element of pixel x0. */
static int rendercache__warp_run_hidden(const rendercache__warp_set *set, const uint64_t *hidden, const rendercache__view *t,
                                        const float *r0, const float *r1, uint32_t x0, uint32_t x1, uint32_t e0)
{
    float xmin = FLT_MAX, xmax = -FLT_MAX, ymin = FLT_MAX, ymax = -FLT_MAX, dmin = FLT_MAX;
    uint32_t x, bx, by, bx0, bx1, by0, by1;
    int r;
    uint64_t least;
    for (r = 0; r < 2; r++) {   /* corners x0 .. x1 (the quad at x1 - 1 reaches x1) of both rows */
        const float *row = r ? r1 : r0;
        if (!row) continue;
        for (x = x0; x <= x1; x++) {   /* without branches (selects, then min and max) */
            const float *c = row + 4 * (size_t)x;
            int ok = c[3] != 0.0f;
            xmin = rendercache__minf(xmin, ok ? c[0] : FLT_MAX);
            xmax = rendercache__maxf(xmax, ok ? c[0] : -FLT_MAX);
            ymin = rendercache__minf(ymin, ok ? c[1] : FLT_MAX);
            ymax = rendercache__maxf(ymax, ok ? c[1] : -FLT_MAX);
            dmin = rendercache__minf(dmin, ok ? c[2] : FLT_MAX);
        }
    }
    if (!(xmax >= 0.0f && ymax >= 0.0f && xmin < (float)t->width && ymin < (float)t->height)) return 1;   /* off the image */
    least = rendercache__key(dmin, e0);
    bx0 = xmin > 0.0f ? (uint32_t)xmin / RENDERCACHE__HIDDEN_BLOCK : 0;
    by0 = ymin > 0.0f ? (uint32_t)ymin / RENDERCACHE__HIDDEN_BLOCK : 0;
    bx1 = xmax < (float)t->width ? (uint32_t)xmax / RENDERCACHE__HIDDEN_BLOCK : set->blocks_x - 1;
    by1 = ymax < (float)t->height ? (uint32_t)ymax / RENDERCACHE__HIDDEN_BLOCK : set->blocks_y - 1;
    for (by = by0; by <= by1; by++)
        for (bx = bx0; bx <= bx1; bx++)
            if (hidden[(size_t)by * set->blocks_x + bx] > least) return 0;
    return 1;
}

/* The points of pixels [x0, x1) of a row that land in the image (counted
   for the statistics when their run is skipped). */
static uint32_t rendercache__warp_run_landed(const rendercache__view *t, const float *row, uint32_t x0, uint32_t x1)
{
    const float w = (float)t->width, h = (float)t->height;
    uint32_t x, n = 0;
    for (x = x0; x < x1; x++) {
        const float *a = row + 4 * (size_t)x;
        n += (a[3] != 0.0f) & (a[0] >= 0.0f) & (a[0] < w) & (a[1] >= 0.0f) & (a[1] < h);
    }
    return n;
}

/* The foreground fill of pixels [begin, end) of one input: each draws the
   triangles of its quad to the right and lower neighbours that pass
   warp_triangle_ok, and is splatted as a point where its surrounding
   triangles are not all drawn (depth edges, image borders), so points fill
   what the triangles leave and never compete with them inside a surface.
   Three projected rows and two rows of quad flags slide down the rows. */
static uint32_t rendercache__warp_cover_input(const rendercache__warp_set *set, const rendercache__warp_src *ws,
                                              uint32_t job, uint32_t begin, uint32_t end, rendercache__zbuffer *zb,
                                              const uint64_t *hidden)
{
    const rendercache_range_image *img = ws->image;
    const uint32_t sw = ws->source.width, sh = ws->source.height, width = ws->target->width;
    const float w = (float)ws->target->width, h = (float)ws->target->height;
    float *rp = set->rows + set->rows_per_job * job, *rc = rp + 4 * (size_t)sw, *rn = rc + 4 * (size_t)sw, *t;
    unsigned char *fu, *fd;
    uint32_t y0 = begin / sw, y1 = (end - 1) / sw, y, projected = 0, sp[2], sc[2], sn[2], st;
    rendercache__flag_row up, down, fs;   /* the quad flags of the rows above and below the pixels */
    up.flags = (unsigned char *)(rn + 4 * (size_t)sw);
    down.flags = up.flags + sw;
    up.done = down.flags + sw;
    down.done = up.done + (sw + RENDERCACHE__HIDDEN_RUN - 1) / RENDERCACHE__HIDDEN_RUN;
    rendercache__warp_project_row(ws, y0, rc, sc);
    if (y0 > 0) {
        rendercache__warp_project_row(ws, y0 - 1, rp, sp);
        rendercache__flag_row_start(&up, y0 - 1, rp, rc, sp, sc, sw);
    }
    for (y = y0; y <= y1; y++) {
        uint32_t xa = y == y0 ? begin - y * sw : 0, xb = y == y1 ? end - y * sw : sw, x;
        int below = y + 1 < sh;
        if (below) {
            rendercache__warp_project_row(ws, y + 1, rn, sn);
            rendercache__flag_row_start(&down, y, rc, rn, sc, sn, sw);
        }
        /* only the projected part of the row has quads and points */
        xa = xa > sc[0] ? xa : sc[0];
        xb = xb < sc[1] ? xb : sc[1];
        fu = up.flags;
        fd = down.flags;
        if (!hidden && xa < xb) {   /* every run is drawn: the rows' flags at once */
            if (y > 0) rendercache__warp_flags_needed(set, ws, &up, xa > 0 ? xa - 1 : 0, xb);
            if (below) rendercache__warp_flags_needed(set, ws, &down, xa > 0 ? xa - 1 : 0, xb);
        }
        for (x = xa; x < xb; x++) {
            const float *a = rc + 4 * (size_t)x;
            uint32_t p = y * sw + x, e = ws->first + p;
            if (hidden && (x - xa) % RENDERCACHE__HIDDEN_RUN == 0) {   /* a new run: behind what is drawn? */
                uint32_t xe = x + RENDERCACHE__HIDDEN_RUN < xb ? x + RENDERCACHE__HIDDEN_RUN : xb;
                if (rendercache__warp_run_hidden(set, hidden, ws->target, rc, below ? rn : NULL, x,
                                                 xe < sw - 1 ? xe : sw - 1, e)) {
                    projected += rendercache__warp_run_landed(ws->target, rc, x, xe);
                    x = xe - 1;
                    continue;
                }
                /* drawn: its quads' flags, and those around its points */
                if (y > 0) rendercache__warp_flags_needed(set, ws, &up, x > 0 ? x - 1 : 0, xe);
                if (below) rendercache__warp_flags_needed(set, ws, &down, x > 0 ? x - 1 : 0, xe);
            }
            if (below && x + 1 < sw && fd[x])
                rendercache__warp_quad(set, hidden, ws, zb, a, a + 4, rn + 4 * (size_t)(x + 1), rn + 4 * (size_t)x, p,
                                       p + 1, p + sw + 1, p + sw, fd[x], e);
            if (a[3] != 0.0f && a[0] >= 0.0f && a[0] < w && a[1] >= 0.0f && a[1] < h) {
                float payload[4];
                projected++;
                if (rendercache__warp_surrounded(y > 0 ? fu : NULL, below ? fd : NULL, x, sw)) continue;
                memcpy(payload, img->rgb + 3 * (size_t)p, 3 * sizeof(float));
                memcpy(payload + 3, &img->object[p], sizeof(float));
                rendercache__zbuffer_test(zb, (uint32_t)a[1] * width + (uint32_t)a[0], a[2], e, payload);
            }
        }
        t = rp; rp = rc; rc = rn; rn = t;
        fs = up; up = down; down = fs;
        st = sc[0]; sc[0] = sn[0]; sn[0] = st;
        st = sc[1]; sc[1] = sn[1]; sn[1] = st;
    }
    return projected;
}

/* The splat cover function of the foreground fill (pinterp's "foreground"
   algorithm): elements [begin, end), input by input. */
static uint32_t rendercache__warp_cover(const void *src, uint32_t job, uint32_t begin, uint32_t end,
                                        rendercache__zbuffer *zb, uint32_t width, uint32_t height)
{
    const rendercache__warp_set *set = (const rendercache__warp_set *)src;
    uint64_t *hidden = set->hidden + (size_t)job * set->blocks_x * set->blocks_y;
    uint32_t e = begin, projected = 0;
    int first = 1;
    while (e < end) {
        const rendercache__warp_src *ws = &set->src[rendercache__warp_input(set, e)];
        const uint32_t local = e - ws->first, n = end - e < ws->count - local ? end - e : ws->count - local;
        if (!first) rendercache__warp_hidden_build(set, zb, width, height, hidden);   /* what the inputs before drew */
        projected += rendercache__warp_cover_input(set, ws, job, local, local + n, zb, first ? NULL : hidden);
        e += n;
        first = 0;
    }
    return projected;
}

/* Tile jobs over the target (RENDERCACHE__TILE_ROWS rows each). */
typedef struct rendercache__warp_job {
    rendercache_warper *w;
    rendercache__accum acc, second;
    const rendercache__splat *splat;     /* extract: the splat (its z-buffers) */
    const rendercache__warp_set *set;
    float tol2;                          /* squared (1 + tolerance) */
    float t;                             /* blend weight of the second image */
} rendercache__warp_job;

static void rendercache__tile_rows(const rendercache_warper *w, uint32_t tile, uint32_t *p0, uint32_t *p1)
{
    *p0 = tile * RENDERCACHE__TILE_ROWS * w->width;
    *p1 = *p0 + RENDERCACHE__TILE_ROWS * w->width;
    if (*p1 > w->pixel_count) *p1 = w->pixel_count;
}

/* The splat's result as an image: colour, object and squared distance
   (without the input's bias) per pixel, FLT_MAX where nothing landed. */
static void rendercache__extract_job(void *ctx, uint32_t tile)
{
    const rendercache__warp_job *j = (const rendercache__warp_job *)ctx;
    const rendercache__splat *s = j->splat;
    const rendercache__warp_src *ws = j->set->src;
    uint32_t p0, p1, p;
    rendercache__tile_rows(j->w, tile, &p0, &p1);
    for (p = p0; p < p1; p++) {   /* the splat's merge, fused: one pass over the pixels instead of two */
        const float *payload;
        uint64_t k = rendercache__splat_least(s, p, &payload);
        uint32_t e = (uint32_t)k, bits = (uint32_t)(k >> 32);
        float depth2;
        if (k == RENDERCACHE__EMPTY_KEY) {
            j->acc.depth2[p] = FLT_MAX;
            j->acc.object[p] = RENDERCACHE_NO_SAMPLE;
            j->w->how[p] = RENDERCACHE__HOW_EMPTY;
            continue;
        }
        memcpy(&depth2, &bits, sizeof depth2);
        memcpy(j->acc.rgb + 3 * (size_t)p, payload, 3 * sizeof(float));
        memcpy(&j->acc.object[p], payload + 3, sizeof(uint32_t));
        if (e - ws->first >= ws->count) ws = &j->set->src[rendercache__warp_input_of(j->set, e)];   /* the last one, mostly */
        j->acc.depth2[p] = j->acc.object[p] == RENDERCACHE_MISS ? RENDERCACHE__FAR2 : depth2 * ws->inv_bias;
        j->w->how[p] = RENDERCACHE__HOW_WARPED;
    }
}

/* Reprojects the inputs of set into acc, one splat for all. */
static void rendercache__warp_splat(rendercache_warper *w, const rendercache__warp_set *set, int foreground,
                                    const rendercache__accum *acc)
{
    rendercache__warp_job job;
    const rendercache__warp_src *last = &set->src[set->count - 1];
    const uint32_t count = last->first + last->count;
    if (foreground)
        rendercache__splat_run_cover(&w->splat, w->parallel_for, w->parallel_user, rendercache__warp_cover, set, count);
    else
        rendercache__splat_run(&w->splat, w->parallel_for, w->parallel_user, rendercache__warp_source,
                               rendercache__warp_payload, NULL, 0, set, count, NULL, NULL);
    w->stats.projected += w->splat.projected;
    memset(&job, 0, sizeof job);
    job.w = w;
    job.acc = *acc;
    job.splat = &w->splat;
    job.set = set;
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__extract_job, &job, w->tile_count);
}

static int rendercache__view_equal(const rendercache__view *a, const rendercache__view *b)
{
    int i, j;
    if (a->kind != b->kind || a->width != b->width || a->height != b->height || a->focal != b->focal) return 0;
    for (i = 0; i < 3; i++) {
        if (a->eye[i] != b->eye[i]) return 0;
        for (j = 0; j < 3; j++)
            if (a->axis[i][j] != b->axis[i][j]) return 0;
    }
    return 1;
}

/* Sets up input img as element range [first, first + pixels) with a bias;
   motion: per-object world motions (12 floats each) or NULL, composed into
   motion_out, with moving[o] = 1 for the objects that do move. */
static void rendercache__warp_prepare(const rendercache_warper *w, rendercache__warp_src *ws,
                                      const rendercache_range_image *img, const float *motion, uint32_t motion_count,
                                      float *motion_out, unsigned char *moving, uint32_t first, float bias)
{
    uint32_t o;
    memset(ws, 0, sizeof *ws);
    ws->image = img;
    rendercache__view_init(&ws->source, &img->camera);   /* validated by the caller */
    ws->target = &w->target;
    ws->first = first;
    ws->count = img->camera.width * img->camera.height;
    ws->bias = bias;
    ws->inv_bias = 1.0f / bias;
    if (rendercache__prepared_fits(img)) ws->prepared = img->prepared;
    rendercache__warp_matrix(&ws->source, &w->target, NULL, ws->m);
    if (w->target.kind == RENDERCACHE_CAMERA_PERSPECTIVE && !(motion && motion_count)) rendercache__warp_cull_planes(ws);
    ws->same_view = rendercache__view_equal(&ws->source, &w->target);
    if (motion && motion_count) {
        static const float identity[12] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0 };
        for (o = 0; o < motion_count; o++) {
            rendercache__warp_matrix(&ws->source, &w->target, motion + 12 * (size_t)o, motion_out + 12 * (size_t)o);
            moving[o] = (unsigned char)(memcmp(motion + 12 * (size_t)o, identity, sizeof identity) != 0);
        }
        ws->motion = motion_out;
        ws->motion_count = motion_count;
        ws->moving = moving;
    }
}

/* Tile culling for the inputs that allow it (a static input into a
   perspective target, from a fish-eye or perspective view): their skip
   flags, in w->skip. Returns 0 when out of memory. */
static int rendercache__warp_tile_culling(rendercache_warper *w, rendercache__warp_set *set, rendercache__warp_src *src)
{
    rendercache__cull_tiles_job job;
    size_t tiles = 0, at = 0;
    uint32_t i, rows = 0;
    for (i = 0; i < set->count; i++) {
        rendercache__warp_src *ws = &src[i];
        if (ws->target->kind != RENDERCACHE_CAMERA_PERSPECTIVE || ws->motion || ws->same_view ||
            ws->source.kind == RENDERCACHE_CAMERA_SPHERE)
            continue;
        ws->tiles_x = (ws->source.width + RENDERCACHE__CULL_TILE - 1) / RENDERCACHE__CULL_TILE;
        ws->tiles_y = (ws->source.height + RENDERCACHE__CULL_TILE - 1) / RENDERCACHE__CULL_TILE;
        tiles += (size_t)ws->tiles_x * ws->tiles_y;
    }
    if (tiles == 0) return 1;
    if (!rendercache__reserve(&w->alloc, (void **)&w->skip, &w->skip_cap, tiles, 2) ||   /* flags, kinds */
        !rendercache__reserve(&w->alloc, (void **)&w->skip_depths, &w->skip_depths_cap, tiles, 2 * sizeof(float)))
        return 0;
    for (i = 0; i < set->count; i++) {
        if (!src[i].tiles_x) continue;
        src[i].skip = w->skip + at;
        at += (size_t)src[i].tiles_x * src[i].tiles_y;
        rows += src[i].tiles_y;
    }
    job.set = set;
    job.bounds.lo = w->skip_depths;
    job.bounds.hi = w->skip_depths + tiles;
    job.bounds.kinds = w->skip + tiles;
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__tile_class_job, &job, rows);
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__tile_bounds_job, &job, rows);
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__tile_skip_job, &job, rows);
    return 1;
}

/* The set of n prepared inputs, with their tile culling and the
   foreground fill's buffers. Returns 0 when out of memory. */
static int rendercache__warp_set_init(rendercache_warper *w, rendercache__warp_set *set, rendercache__warp_src *src,
                                      uint32_t n, int foreground)
{
    uint32_t i, widest = 0;
    memset(set, 0, sizeof *set);
    set->src = src;
    set->count = n;
    set->tol2x = (1.0f + 2.0f * w->tolerance) * (1.0f + 2.0f * w->tolerance);
    set->max_extent = RENDERCACHE__MAX_QUAD_FRACTION * (float)(w->width > w->height ? w->width : w->height);
    if (!rendercache__warp_tile_culling(w, set, src)) return 0;
    if (!foreground) return 1;
    for (i = 0; i < n; i++) widest = src[i].source.width > widest ? src[i].source.width : widest;
    set->rows_per_job = 13 * (size_t)widest + 2;   /* three rows of 4 floats, two rows of flag bytes and
                                                      their bytes per run */
    if (!rendercache__reserve(&w->alloc, (void **)&w->rows, &w->rows_cap, set->rows_per_job * w->splat.jobs, sizeof(float)))
        return 0;
    set->rows = w->rows;
    set->blocks_x = (w->width + RENDERCACHE__HIDDEN_BLOCK - 1) / RENDERCACHE__HIDDEN_BLOCK;
    set->blocks_y = (w->height + RENDERCACHE__HIDDEN_BLOCK - 1) / RENDERCACHE__HIDDEN_BLOCK;
    if (!rendercache__reserve(&w->alloc, (void **)&w->hidden, &w->hidden_cap,
                              (size_t)set->blocks_x * set->blocks_y * w->splat.jobs, sizeof(uint64_t)))
        return 0;
    set->hidden = w->hidden;
    return 1;
}

/* ---- averaging (pinterp's -a) ---------------------------------------
   Each input is warped alone into a layer of its own; then every target
   pixel takes the surface the ranked z-buffer would have kept (the least
   biased squared distance, the nearer rank on a tie) and averages the
   colours of the layers that see it too (distances within the tolerance),
   each weighted as pinterp weighs a pixel: 1 / sin of the angle between
   its input's ray to the point and the target's ray (at most 1000), so
   that views that look from nearly the same direction count most. The
   result does not depend on the order of the jobs or their number. */
#define RENDERCACHE__MAX_AVERAGE_WEIGHT 1000.0f

typedef struct rendercache__average_job {
    rendercache_warper *w;
    rendercache__accum acc;
    const float *layers;
    uint32_t n;
} rendercache__average_job;

/* The layer of input i: colour, squared distance, object (float bits). */
static rendercache__accum rendercache__layer(const rendercache_warper *w, float *layers, uint32_t i)
{
    rendercache__accum a;
    float *base = layers + (size_t)i * 5 * w->pixel_count;
    a.rgb = base;
    a.depth2 = base + 3 * (size_t)w->pixel_count;
    a.object = (uint32_t *)(void *)(base + 4 * (size_t)w->pixel_count);
    return a;
}

static void rendercache__average_job_run(void *ctx, uint32_t tile)
{
    const rendercache__average_job *j = (const rendercache__average_job *)ctx;
    rendercache_warper *w = j->w;
    const rendercache__view *t = &w->target;
    const float tol2 = (1.0f + w->tolerance) * (1.0f + w->tolerance);
    float dx[RENDERCACHE__BATCH], dy[RENDERCACHE__BATCH], dz[RENDERCACHE__BATCH];
    unsigned char ok[RENDERCACHE__BATCH];
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, x, y, x0, i;
    if (y1 > w->height) y1 = w->height;
    for (y = y0; y < y1; y++)
        for (x0 = 0; x0 < w->width; x0 += RENDERCACHE__BATCH) {
            uint32_t m = w->width - x0 < RENDERCACHE__BATCH ? w->width - x0 : RENDERCACHE__BATCH;
            rendercache__view_row_dirs(t, y, x0, m, dx, dy, dz, ok);
            for (x = 0; x < m; x++) {
                const uint32_t p = y * w->width + x0 + x;
                uint32_t best = RENDERCACHE__NONE;
                float best_key = FLT_MAX, dbest, sum[3] = { 0, 0, 0 }, total = 0.0f, ray[3], bias = 1.0f;
                int k;
                for (i = 0; i < j->n; i++, bias = bias * tol2 < (float)RENDERCACHE__MAX_BIAS ? bias * tol2 : (float)RENDERCACHE__MAX_BIAS) {
                    rendercache__accum a = rendercache__layer(w, (float *)j->layers, i);
                    float d = a.depth2[p], key = d == FLT_MAX ? FLT_MAX : a.object[p] == RENDERCACHE_MISS ? d : d * bias;
                    if (key < best_key) { best_key = key; best = i; }
                }
                if (best == RENDERCACHE__NONE) {
                    j->acc.depth2[p] = FLT_MAX;
                    j->acc.object[p] = RENDERCACHE_NO_SAMPLE;
                    w->how[p] = RENDERCACHE__HOW_EMPTY;
                    continue;
                }
                for (k = 0; k < 3; k++) ray[k] = dx[x] * t->axis[0][k] + dy[x] * t->axis[1][k] + dz[x] * t->axis[2][k];
                dbest = rendercache__layer(w, (float *)j->layers, best).depth2[p];
                for (i = 0; i < j->n; i++) {
                    rendercache__accum a = rendercache__layer(w, (float *)j->layers, i);
                    const float d = a.depth2[p], *e = w->src[i].source.eye;
                    float wgt = RENDERCACHE__MAX_AVERAGE_WEIGHT;
                    if (d == FLT_MAX || d > dbest * tol2 || dbest > d * tol2) continue;   /* another surface */
                    if (a.object[p] != RENDERCACHE_MISS) {   /* the angle at the point between the two rays */
                        float r = sqrtf(dbest), q[3], l2 = 0.0f, c = 0.0f, s2;
                        for (k = 0; k < 3; k++) {
                            q[k] = t->eye[k] + ray[k] * r - e[k];
                            l2 += q[k] * q[k];
                            c += q[k] * ray[k];
                        }
                        s2 = l2 > 0.0f ? 1.0f - c * c / l2 : 0.0f;
                        if (s2 > 1.0f / (RENDERCACHE__MAX_AVERAGE_WEIGHT * RENDERCACHE__MAX_AVERAGE_WEIGHT)) wgt = 1.0f / sqrtf(s2);
                    }
                    for (k = 0; k < 3; k++) sum[k] += wgt * a.rgb[3 * (size_t)p + k];
                    total += wgt;
                }
                {
                    rendercache__accum b = rendercache__layer(w, (float *)j->layers, best);
                    for (k = 0; k < 3; k++) j->acc.rgb[3 * (size_t)p + k] = rendercache__finitef(sum[k] / total);
                    j->acc.depth2[p] = dbest;
                    j->acc.object[p] = b.object[p];
                    w->how[p] = RENDERCACHE__HOW_WARPED;
                }
            }
        }
}

/* The averaging warp of the n prepared inputs w->src (in rank order) into acc. */
static rendercache_result rendercache__warp_average(rendercache_warper *w, uint32_t n, int foreground,
                                                   const rendercache__accum *acc)
{
    rendercache__average_job job;
    rendercache__warp_set set;
    rendercache__warp_src one;
    uint32_t i;
    if ((size_t)n > SIZE_MAX / 5 / w->pixel_count ||
        !rendercache__reserve(&w->alloc, (void **)&w->layers, &w->layers_cap, (size_t)n * 5 * w->pixel_count, sizeof(float)))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    for (i = 0; i < n; i++) {   /* each input alone, unbiased */
        rendercache__accum layer = rendercache__layer(w, w->layers, i);
        rendercache__warp_prepare(w, &one, w->src[i].image, NULL, 0, NULL, NULL, 0, 1.0f);
        if (!rendercache__warp_set_init(w, &set, &one, 1, foreground)) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
        rendercache__warp_splat(w, &set, foreground, &layer);
    }
    job.w = w;
    job.acc = *acc;
    job.layers = w->layers;
    job.n = n;
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__average_job_run, &job, w->tile_count);
    return RENDERCACHE_OK;
}

/* ---- background fill (pinterp's "background" algorithm) -------------- */

/* Job per strip of columns: for each run of empty pixels in a column, the
   farther of the filled pixels just above and just below it (above on a
   tie), written to w->column for every pixel of the run. The strip is
   scanned row by row (one open run per column), so that reads stay in
   cache lines. */
static void rendercache__column_job(void *ctx, uint32_t strip)
{
    const rendercache__warp_job *j = (const rendercache__warp_job *)ctx;
    rendercache_warper *w = j->w;
    const float *d2 = j->acc.depth2;
    const uint32_t width = w->width, height = w->height;
    uint32_t x0 = strip * RENDERCACHE__COLUMN_STRIP, x1 = x0 + RENDERCACHE__COLUMN_STRIP, x, y;
    uint32_t run[RENDERCACHE__COLUMN_STRIP];   /* per column: first row of the open empty run, or NONE */
    if (x1 > width) x1 = width;
    for (x = x0; x < x1; x++) run[x - x0] = RENDERCACHE__NONE;
    for (y = 0; y <= height; y++)
        for (x = x0; x < x1; x++) {
            uint32_t p = y * width + x, r = run[x - x0], above, below, cand, k;
            int filled = y == height || d2[p] != FLT_MAX;
            if (!filled) {
                if (r == RENDERCACHE__NONE) run[x - x0] = y;
                continue;
            }
            if (r == RENDERCACHE__NONE) continue;
            above = r > 0 ? (r - 1) * width + x : RENDERCACHE__NONE;
            below = y < height ? p : RENDERCACHE__NONE;
            cand = above;
            if (below != RENDERCACHE__NONE && (above == RENDERCACHE__NONE || d2[above] < d2[below])) cand = below;
            for (k = r; k < y; k++) w->column[k * width + x] = cand;
            run[x - x0] = RENDERCACHE__NONE;
        }
}

/* Job per tile of rows: each empty pixel takes the row's candidate (the
   farther of the filled pixels left and right of its run) or the column's,
   the one next to the pixel if one is, else the farther. */
static void rendercache__row_job(void *ctx, uint32_t tile)
{
    const rendercache__warp_job *j = (const rendercache__warp_job *)ctx;
    rendercache_warper *w = j->w;
    float *d2 = j->acc.depth2, *rgb = j->acc.rgb;
    uint32_t *obj = j->acc.object;
    uint32_t y0 = tile * RENDERCACHE__TILE_ROWS, y1 = y0 + RENDERCACHE__TILE_ROWS, y;
    if (y1 > w->height) y1 = w->height;
    for (y = y0; y < y1; y++) {
        const uint32_t row = y * w->width;
        uint32_t x = 0;
        while (x < w->width) {
            uint32_t xa, xb, left, right, rc, k;
            if (d2[row + x] != FLT_MAX) { x++; continue; }
            xa = x;
            while (x < w->width && d2[row + x] == FLT_MAX) x++;
            xb = x;   /* the run is [xa, xb) */
            left = xa > 0 ? row + xa - 1 : RENDERCACHE__NONE;
            right = xb < w->width ? row + xb : RENDERCACHE__NONE;
            rc = left;
            if (right != RENDERCACHE__NONE && (left == RENDERCACHE__NONE || d2[left] < d2[right])) rc = right;
            for (k = xa; k < xb; k++) {
                uint32_t p = row + k, cc = w->column[p], src, reach;
                if (rc == RENDERCACHE__NONE && cc == RENDERCACHE__NONE) continue;
                if (cc == RENDERCACHE__NONE) src = rc;
                else if (rc == RENDERCACHE__NONE) src = cc;
                else if ((rc == left && k == xa) || (rc == right && k + 1 == xb)) src = rc;   /* next to the pixel */
                else if (cc == p - w->width || cc == p + w->width) src = cc;
                else src = d2[cc] < d2[rc] ? rc : cc;
                /* pinterp's -fs: a source too far away leaves the pixel to fill_pixel */
                reach = src == left ? k + 1 - xa : src == right ? xb - k : (src > p ? src - p : p - src) / w->width;
                if (w->max_fill && reach > w->max_fill) continue;
                d2[p] = d2[src];   /* candidates are pixels filled before this pass: never written here */
                memcpy(rgb + 3 * (size_t)p, rgb + 3 * (size_t)src, 3 * sizeof(float));
                obj[p] = obj[src];
                w->how[p] = RENDERCACHE__HOW_BACKGROUND;
            }
        }
    }
}

/* ---- the caller's fill, and the output ----------------------------- */

static void rendercache__callback_job(void *ctx, uint32_t tile)
{
    const rendercache__warp_job *j = (const rendercache__warp_job *)ctx;
    rendercache_warper *w = j->w;
    const rendercache__view *v = &w->target;
    uint32_t p0, p1, p;
    rendercache__tile_rows(w, tile, &p0, &p1);
    for (p = p0; p < p1; p++) {
        uint32_t x = p % w->width, y = p / w->width, o = RENDERCACHE_NO_SAMPLE;
        float dir[3], rgb[3] = { 0, 0, 0 }, depth = 0.0f;
        if (j->acc.depth2[p] != FLT_MAX || !rendercache__view_has_ray(v, x, y)) continue;
        if (!rendercache__view_ray(v, (float)x + 0.5f, (float)y + 0.5f, dir)) continue;
        if (!w->fill_pixel(w->fill_user, x, y, v->eye, dir, rgb, &depth, &o)) continue;
        if (!rendercache__finite3(rgb) || o == RENDERCACHE_NO_SAMPLE) continue;
        if (o != RENDERCACHE_MISS && !(depth > 0.0f && depth <= FLT_MAX)) continue;
        j->acc.depth2[p] = o == RENDERCACHE_MISS ? RENDERCACHE__FAR2 : depth * depth;
        memcpy(j->acc.rgb + 3 * (size_t)p, rgb, sizeof rgb);
        j->acc.object[p] = o;
        w->how[p] = RENDERCACHE__HOW_COMPUTED;
    }
}

/* Squared distances to distances, empty pixels to the background colour,
   and the counts of each kind of pixel. */
static void rendercache__finish_job(void *ctx, uint32_t tile)
{
    const rendercache__warp_job *j = (const rendercache__warp_job *)ctx;
    rendercache_warper *w = j->w;
    uint32_t p0, p1, p, *counts = w->tile_counts + 4 * (size_t)tile;
    const int fisheye = w->target.kind == RENDERCACHE_CAMERA_FISHEYE;   /* other targets have a ray everywhere */
    rendercache__tile_rows(w, tile, &p0, &p1);
    counts[0] = counts[1] = counts[2] = counts[3] = 0;
    for (p = p0; p < p1; p++) {
        int ray = !fisheye || rendercache__view_has_ray(&w->target, p % w->width, p / w->width);
        if (!ray || j->acc.depth2[p] == FLT_MAX) {
            memcpy(j->acc.rgb + 3 * (size_t)p, w->background, 3 * sizeof(float));
            j->acc.depth2[p] = RENDERCACHE__FAR;
            j->acc.object[p] = RENDERCACHE_NO_SAMPLE;
            counts[3] += (uint32_t)ray;
            continue;
        }
        counts[w->how[p] > 0 ? w->how[p] - 1 : 0]++;
        j->acc.depth2[p] = j->acc.object[p] == RENDERCACHE_MISS ? RENDERCACHE__FAR
                                                                 : rendercache__maxf(sqrtf(j->acc.depth2[p]), RENDERCACHE__MIN_DEPTH);
    }
}

/* The fills after the reprojection, and the output in acc (depth2 becomes
   the distance). */
static void rendercache__warp_finish(rendercache_warper *w, const rendercache__accum *acc, rendercache_fill fill)
{
    rendercache__warp_job job;
    uint32_t t;
    double t0 = rendercache__warp_now(w);
    memset(&job, 0, sizeof job);
    job.w = w;
    job.acc = *acc;
    if (fill == RENDERCACHE_FILL_BACKGROUND || fill == RENDERCACHE_FILL_BOTH) {
        uint32_t strips = (w->width + RENDERCACHE__COLUMN_STRIP - 1) / RENDERCACHE__COLUMN_STRIP;
        rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__column_job, &job, strips);
        rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__row_job, &job, w->tile_count);
    }
    if (w->fill_pixel) rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__callback_job, &job, w->tile_count);
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__finish_job, &job, w->tile_count);
    w->stats.time_fill = rendercache__warp_now(w) - t0;
    w->stats.warped = w->stats.background = w->stats.computed = w->stats.empty = 0;
    for (t = 0; t < w->tile_count; t++) {
        w->stats.warped += w->tile_counts[4 * t + 0];
        w->stats.background += w->tile_counts[4 * t + 1];
        w->stats.computed += w->tile_counts[4 * t + 2];
        w->stats.empty += w->tile_counts[4 * t + 3];
    }
}

static int rendercache__fill_valid(rendercache_fill fill)
{
    return fill >= RENDERCACHE_FILL_DEFAULT && fill <= RENDERCACHE_FILL_BOTH;
}

static int rendercache__has_foreground(rendercache_fill fill)
{
    return fill == RENDERCACHE_FILL_FOREGROUND || fill == RENDERCACHE_FILL_BOTH;
}

/* Orders the inputs by the distance of their eye to the target's (stable). */
static void rendercache__order_inputs(const rendercache_range_image *const *images, uint32_t n, const float eye[3],
                                      uint32_t *order)
{
    uint32_t i, k;
    for (i = 0; i < n; i++) {
        const float *e = images[i]->camera.eye;
        double di = 0.0;
        for (k = 0; k < 3; k++) di += ((double)e[k] - eye[k]) * ((double)e[k] - eye[k]);
        for (k = i; k > 0; k--) {
            const float *f = images[order[k - 1]]->camera.eye;
            double dk = ((double)f[0] - eye[0]) * ((double)f[0] - eye[0]) + ((double)f[1] - eye[1]) * ((double)f[1] - eye[1]) +
                        ((double)f[2] - eye[2]) * ((double)f[2] - eye[2]);
            if (!(di < dk)) break;
            order[k] = order[k - 1];
        }
        order[k] = i;
    }
}

/* Checks a target image and its camera, reserves the buffers and sets
   w->target. */
static rendercache_result rendercache__warp_begin(rendercache_warper *w, const rendercache_camera *camera,
                                                  rendercache_range_image *out, const char *who)
{
    rendercache__view v;
    const rendercache_camera *c = camera ? camera : (out ? &out->camera : NULL);
    if (!rendercache__range_valid(out, &v) || !rendercache__view_init(&w->target, c) ||
        c->width != out->camera.width || c->height != out->camera.height) {
        rendercache__warp_log(w, who);
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    if (!rendercache__warper_reserve(w, c->width, c->height)) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    rendercache_range_image_unprepare(out);   /* its arrays are about to change */
    out->camera = *c;
    memset(&w->stats, 0, sizeof w->stats);
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_warp(rendercache_warper *w, const rendercache_range_image *const *images,
                                                    uint32_t n, const rendercache_camera *camera, rendercache_fill fill,
                                                    rendercache_range_image *out)
{
    rendercache__accum acc;
    rendercache__warp_set set;
    rendercache_result r;
    rendercache__view v;
    size_t cap;
    uint64_t elements = 0;
    double t0, t1, bias = 1.0, tol2;
    uint32_t i;
    if (!w) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!images || n == 0 || !rendercache__fill_valid(fill)) {
        rendercache__warp_log(w, "rendercache_warp: no images, or an unknown fill mode");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    for (i = 0; i < n; i++) {
        if (!rendercache__range_valid(images[i], &v) || images[i] == out) {
            rendercache__warp_log(w, "rendercache_warp: an input image is NULL, incomplete, has an invalid camera, or is out");
            return RENDERCACHE_ERROR_INVALID_ARGUMENT;
        }
        if (!rendercache__prepared_fits(images[i])) {
            rendercache__warp_log(w, "rendercache_warp: an input's size or arrays changed since it was prepared");
            return RENDERCACHE_ERROR_INVALID_ARGUMENT;
        }
        elements += (uint64_t)images[i]->camera.width * images[i]->camera.height;
    }
    if (elements >= RENDERCACHE__NONE) {
        rendercache__warp_log(w, "rendercache_warp: more than 2^32 - 1 input pixels");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    if (fill == RENDERCACHE_FILL_DEFAULT) fill = RENDERCACHE_FILL_BOTH;
    t0 = rendercache__warp_now(w);
    r = rendercache__warp_begin(w, camera, out, "rendercache_warp: invalid output image or camera, or sizes differ");
    if (r != RENDERCACHE_OK) return r;
    cap = w->order_cap;
    if (!rendercache__reserve(&w->alloc, (void **)&w->order, &cap, n, sizeof(uint32_t))) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    w->order_cap = (uint32_t)cap;
    cap = w->src_cap;
    if (!rendercache__reserve(&w->alloc, (void **)&w->src, &cap, n, sizeof(rendercache__warp_src)))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    w->src_cap = (uint32_t)cap;
    rendercache__order_inputs(images, n, w->target.eye, w->order);
    /* input of rank k: squared distances times (1 + t)^(2k), capped so that they stay finite */
    tol2 = (1.0 + w->tolerance) * (1.0 + w->tolerance);
    for (i = 0, elements = 0; i < n; i++) {
        rendercache__warp_prepare(w, &w->src[i], images[w->order[i]], NULL, 0, NULL, NULL, (uint32_t)elements, (float)bias);
        elements += w->src[i].count;
        bias = bias * tol2 < RENDERCACHE__MAX_BIAS ? bias * tol2 : RENDERCACHE__MAX_BIAS;
    }
    acc.rgb = out->rgb;
    acc.depth2 = out->depth;
    acc.object = out->object;
    if (w->average && n > 1) {
        r = rendercache__warp_average(w, n, rendercache__has_foreground(fill), &acc);
        if (r != RENDERCACHE_OK) return r;
    } else {
        if (!rendercache__warp_set_init(w, &set, w->src, n, rendercache__has_foreground(fill))) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
        rendercache__warp_splat(w, &set, rendercache__has_foreground(fill), &acc);
    }
    t1 = rendercache__warp_now(w);
    rendercache__warp_finish(w, &acc, fill);
    out->time = images[w->order[0]]->time;
    w->stats.images = n;
    w->stats.time_project = t1 - t0;
    w->stats.time_total = rendercache__warp_now(w) - t0;
    return RENDERCACHE_OK;
}

/* ======================================================================
   19. time interpolation (section 4.4: pcomb's pixelwise linear blend, as
   the paper does it; and, beyond the paper, blending after moving each
   image's pixels with their objects)
   ---------------------------------------------------------------------- */
RENDERCACHE_API rendercache_result rendercache_blend(const rendercache_range_image *a, const rendercache_range_image *b,
                                                     float t, rendercache_range_image *out)
{
    rendercache__view va, vb, vo;
    const rendercache_range_image *nearer;
    size_t n, p;
    if (!rendercache__range_valid(a, &va) || !rendercache__range_valid(b, &vb) || !rendercache__range_valid(out, &vo) ||
        !(t >= 0.0f && t <= 1.0f))
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (a->camera.width != b->camera.width || a->camera.height != b->camera.height ||
        a->camera.width != out->camera.width || a->camera.height != out->camera.height)
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    rendercache_range_image_unprepare(out);   /* its arrays are about to change */
    n = (size_t)a->camera.width * a->camera.height;
    nearer = t < 0.5f ? a : b;
    for (p = 0; p < 3 * n; p++) out->rgb[p] = rendercache__finitef((1.0f - t) * a->rgb[p] + t * b->rgb[p]);
    if (nearer != out) {
        memcpy(out->depth, nearer->depth, n * sizeof(float));
        memcpy(out->object, nearer->object, n * sizeof(uint32_t));
    }
    out->time = (1.0 - (double)t) * a->time + (double)t * b->time;
    out->camera = a->camera;
    return RENDERCACHE_OK;
}

/* Per-pixel choice between the two warped images of a motion blend: the
   same object at the same depth is blended, else the nearer surface (or the
   only one) is kept; within the tolerance but different objects, the image
   nearer in time. */
static void rendercache__combine_job(void *ctx, uint32_t tile)
{
    const rendercache__warp_job *j = (const rendercache__warp_job *)ctx;
    const rendercache__accum *a = &j->acc, *b = &j->second;
    const float t = j->t, tol2 = j->tol2;
    uint32_t p0, p1, p;
    rendercache__tile_rows(j->w, tile, &p0, &p1);
    for (p = p0; p < p1; p++) {
        float da = a->depth2[p], db = b->depth2[p];
        int take_b;
        if (da == FLT_MAX && db == FLT_MAX) continue;
        j->w->how[p] = RENDERCACHE__HOW_WARPED;
        if (db == FLT_MAX) continue;   /* only a */
        if (da != FLT_MAX && a->object[p] == b->object[p] && da <= db * tol2 && db <= da * tol2) {
            int k;
            for (k = 0; k < 3; k++) a->rgb[3 * p + k] = rendercache__finitef((1.0f - t) * a->rgb[3 * p + k] + t * b->rgb[3 * p + k]);
            a->depth2[p] = (1.0f - t) * da + t * db;
            continue;
        }
        take_b = da == FLT_MAX || db * tol2 < da || (!(da * tol2 < db) && t >= 0.5f);
        if (!take_b) continue;
        a->depth2[p] = db;
        memcpy(a->rgb + 3 * (size_t)p, b->rgb + 3 * (size_t)p, 3 * sizeof(float));
        a->object[p] = b->object[p];
    }
}

/* World motion of each object from an image's time to the blend time:
   world_t * inverse(world_i), into out (12 floats per object). Returns 0
   when a transform is singular or not finite. */
static int rendercache__object_motions(const float *world_i, const float *world_t, uint32_t count, float *out)
{
    uint32_t o;
    int i, j, k;
    for (o = 0; o < count; o++) {
        const float *a = world_i + 12 * (size_t)o, *b = world_t + 12 * (size_t)o;
        float inv[12];
        double m[12];
        for (k = 0; k < 12; k++)
            if (!isfinite(a[k]) || !isfinite(b[k])) return 0;
        if (!rendercache__invert_affine(a, inv)) return 0;
        for (i = 0; i < 3; i++)
            for (j = 0; j < 4; j++)
                m[4 * i + j] = (double)b[4 * i] * inv[j] + (double)b[4 * i + 1] * inv[4 + j] +
                               (double)b[4 * i + 2] * inv[8 + j] + (j == 3 ? (double)b[4 * i + 3] : 0.0);
        for (k = 0; k < 12; k++) out[12 * (size_t)o + k] = (float)m[k];
    }
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_blend_motion(rendercache_warper *w, const rendercache_range_image *a,
                                                            const rendercache_range_image *b, float t,
                                                            const rendercache_motion *motion, rendercache_fill fill,
                                                            rendercache_range_image *out)
{
    rendercache__accum acc_a, acc_b;
    rendercache__warp_job job;
    rendercache__warp_src ws;
    rendercache__warp_set set;
    rendercache__view va, vb;
    rendercache_result r;
    uint32_t count = motion ? motion->object_count : 0;
    size_t cap;
    float *ma, *mb;
    double t0, t1;
    int fg;
    if (!w) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__range_valid(a, &va) || !rendercache__range_valid(b, &vb) || a == out || b == out ||
        !(t >= 0.0f && t <= 1.0f) || !rendercache__fill_valid(fill) || !rendercache__prepared_fits(a) ||
        !rendercache__prepared_fits(b) || (count && (!motion->world_a || !motion->world_b || !motion->world_t))) {
        rendercache__warp_log(w, "rendercache_blend_motion: invalid image (or changed since prepared), weight, fill mode or motion");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    if (fill == RENDERCACHE_FILL_DEFAULT) fill = RENDERCACHE_FILL_BOTH;
    fg = rendercache__has_foreground(fill);
    t0 = rendercache__warp_now(w);
    r = rendercache__warp_begin(w, NULL, out, "rendercache_blend_motion: invalid output image");
    if (r != RENDERCACHE_OK) return r;
    if (!rendercache__warper_reserve_second(w)) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    cap = w->motion_cap;
    if (count > (RENDERCACHE__MAX_OBJECTS) ||
        !rendercache__reserve(&w->alloc, (void **)&w->motion, &cap, 4 * (size_t)count + 1, 12 * sizeof(float)))
        return count > RENDERCACHE__MAX_OBJECTS ? RENDERCACHE_ERROR_INVALID_ARGUMENT : RENDERCACHE_ERROR_OUT_OF_MEMORY;
    w->motion_cap = (uint32_t)cap;
    cap = w->moving_cap;
    if (!rendercache__reserve(&w->alloc, (void **)&w->moving, &cap, 2 * (size_t)count + 1, 1))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    w->moving_cap = (uint32_t)cap;
    /* the motions of a's and b's objects, then the composed matrices */
    ma = w->motion;
    mb = w->motion + 12 * (size_t)count;
    if (count && (!rendercache__object_motions(motion->world_a, motion->world_t, count, ma) ||
                  !rendercache__object_motions(motion->world_b, motion->world_t, count, mb))) {
        rendercache__warp_log(w, "rendercache_blend_motion: a transform is singular or not finite");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    acc_a.rgb = out->rgb; acc_a.depth2 = out->depth; acc_a.object = out->object;
    acc_b.rgb = w->b_rgb; acc_b.depth2 = w->b_depth2; acc_b.object = w->b_object;
    rendercache__warp_prepare(w, &ws, a, ma, count, w->motion + 24 * (size_t)count, w->moving, 0, 1.0f);
    if (!rendercache__warp_set_init(w, &set, &ws, 1, fg)) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    rendercache__warp_splat(w, &set, fg, &acc_a);
    rendercache__warp_prepare(w, &ws, b, mb, count, w->motion + 36 * (size_t)count, w->moving + count, 0, 1.0f);
    if (!rendercache__warp_set_init(w, &set, &ws, 1, fg)) return RENDERCACHE_ERROR_OUT_OF_MEMORY;   /* b's width */
    rendercache__warp_splat(w, &set, fg, &acc_b);
    memset(&job, 0, sizeof job);
    job.w = w;
    job.acc = acc_a;
    job.second = acc_b;
    job.t = t;
    job.tol2 = (1.0f + w->tolerance) * (1.0f + w->tolerance);
    rendercache__run_jobs(w->parallel_for, w->parallel_user, rendercache__combine_job, &job, w->tile_count);
    t1 = rendercache__warp_now(w);
    rendercache__warp_finish(w, &acc_a, fill);
    out->time = (1.0 - (double)t) * a->time + (double)t * b->time;
    w->stats.images = 2;
    w->stats.time_project = t1 - t0;
    w->stats.time_total = rendercache__warp_now(w) - t0;
    return RENDERCACHE_OK;
}

/* ======================================================================
   20. coherence tests (sections 4.1 and 4.2): fitness of id images, and the
   adaptive subdivision of a view space and of time it drives.
   ---------------------------------------------------------------------- */
#define RENDERCACHE__DEFAULT_MAX_DEPTH 8u
#define RENDERCACHE__MAX_DEPTH_LIMIT 20u

/* f = N / PQ over the pixels some image has a ray for. */
static float rendercache__fitness_of(const uint32_t *const *ids, uint32_t count, size_t n)
{
    size_t p, counted = 0, same = 0;
    uint32_t k;
    for (p = 0; p < n; p++) {
        uint32_t first = ids[0][p];
        int all_same = 1, none = first == RENDERCACHE_NO_SAMPLE;
        for (k = 1; k < count; k++) {
            uint32_t v = ids[k][p];
            all_same &= v == first;
            none &= v == RENDERCACHE_NO_SAMPLE;
        }
        if (none) continue;
        counted++;
        same += (size_t)all_same;
    }
    return counted ? (float)((double)same / (double)counted) : 1.0f;
}

RENDERCACHE_API rendercache_result rendercache_fitness(const uint32_t *const *id_images, uint32_t count, uint32_t width,
                                                       uint32_t height, float *fitness)
{
    uint32_t k;
    if (fitness) *fitness = 0.0f;
    if (!fitness || !id_images || count == 0 || width == 0 || height == 0 ||
        (uint64_t)width * height > RENDERCACHE__MAX_PIXELS)
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (k = 0; k < count; k++)
        if (!id_images[k]) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    *fitness = rendercache__fitness_of(id_images, count, (size_t)width * height);
    return RENDERCACHE_OK;
}

/* Doubles a growable array to hold need items. */
static int rendercache__grow(const rendercache_allocator *a, void **p, uint32_t *cap, uint32_t need, size_t item)
{
    uint32_t c = *cap ? *cap : 16;
    void *q;
    if (need <= *cap) return 1;
    while (c < need) {
        if (c > UINT32_MAX / 2) return 0;
        c *= 2;
    }
    q = rendercache__alloc_array(a, c, item);
    if (!q) return 0;
    if (*p) memcpy(q, *p, (size_t)*cap * item);
    rendercache__free(a, *p);
    *p = q;
    *cap = c;
    return 1;
}

/* A cell of the view space, on the lattice of 2^max_depth steps per axis. */
typedef struct rendercache__vs_node {
    uint32_t lo[3], hi[3];
    int32_t axis;            /* split axis (an index into the active axes), -1 for a leaf */
    uint32_t split;          /* lattice coordinate of the split */
    uint32_t child[2];
    uint32_t corner[8];      /* views at the corners (leaves) */
    float fitness;
} rendercache__vs_node;

struct rendercache_view_space {
    rendercache_allocator alloc;
    rendercache_camera camera;
    float lo[3], hi[3];
    uint32_t axis[3], axis_count;      /* the subdivided axes */
    uint32_t steps;                    /* lattice steps per axis: 2^max_depth */
    float *eyes;                       /* 3 per view */
    uint32_t *lattice;                 /* 3 per view */
    uint32_t **ids;                    /* per view: its id image (while building) */
    uint32_t view_count, view_cap, lattice_cap, ids_cap;
    uint32_t *table;                   /* open-addressing hash of the lattice points: view or NONE */
    uint32_t table_size;               /* a power of two, at least twice the views */
    rendercache__vs_node *nodes;
    uint32_t node_count, node_cap;
    uint32_t leaf_count;
    const rendercache_view_space_desc *desc;   /* while building */
    size_t id_pixels;
};

static void rendercache__vs_eye(const rendercache_view_space *vs, const uint32_t k[3], float eye[3])
{
    int i;
    for (i = 0; i < 3; i++)
        eye[i] = (float)((double)vs->lo[i] + ((double)vs->hi[i] - vs->lo[i]) * ((double)k[i] / (double)vs->steps));
}

static void rendercache__vs_camera(const rendercache_view_space *vs, const float eye[3], rendercache_camera *c)
{
    int i;
    *c = vs->camera;
    for (i = 0; i < 3; i++) {
        c->look_at[i] = eye[i] + (vs->camera.look_at[i] - vs->camera.eye[i]);
        c->eye[i] = eye[i];
    }
}

/* The slot of lattice point k in the hash table: its view, or the empty
   slot where it goes. */
static uint32_t rendercache__vs_slot(const rendercache_view_space *vs, const uint32_t k[3])
{
    uint32_t mask = vs->table_size - 1, s;
    s = (k[0] * 0x9E3779B1u) ^ (k[1] * 0x85EBCA77u) ^ (k[2] * 0xC2B2AE3Du);
    s = (s ^ (s >> 15)) & mask;
    while (vs->table[s] != RENDERCACHE__NONE && memcmp(vs->lattice + 3 * (size_t)vs->table[s], k, 3 * sizeof(uint32_t)))
        s = (s + 1) & mask;
    return s;
}

/* Doubles the hash table when it is half full. */
static int rendercache__vs_rehash(rendercache_view_space *vs, uint32_t views)
{
    uint32_t size = vs->table_size ? vs->table_size : 64, v, *old = vs->table;
    if (vs->table && 2 * (uint64_t)views <= vs->table_size) return 1;
    while (2 * (uint64_t)views > size) {
        if (size > (1u << 30)) return 0;
        size *= 2;
    }
    vs->table = (uint32_t *)rendercache__alloc_array(&vs->alloc, size, sizeof(uint32_t));
    if (!vs->table) { vs->table = old; return 0; }
    rendercache__free(&vs->alloc, old);
    vs->table_size = size;
    for (v = 0; v < size; v++) vs->table[v] = RENDERCACHE__NONE;
    for (v = 0; v < vs->view_count; v++) vs->table[rendercache__vs_slot(vs, vs->lattice + 3 * (size_t)v)] = v;
    return 1;
}

/* The view at lattice point k, rendering its id image the first time.
   Returns RENDERCACHE_OK and *view. */
static rendercache_result rendercache__vs_view(rendercache_view_space *vs, const uint32_t k[3], uint32_t *view)
{
    const rendercache_view_space_desc *d = vs->desc;
    rendercache_camera cam;
    uint32_t v = vs->view_count, *ids, slot;
    if (!rendercache__vs_rehash(vs, v + 1)) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    slot = rendercache__vs_slot(vs, k);
    if (vs->table[slot] != RENDERCACHE__NONE) { *view = vs->table[slot]; return RENDERCACHE_OK; }
    if (!rendercache__grow(&vs->alloc, (void **)&vs->eyes, &vs->view_cap, v + 1, 3 * sizeof(float)) ||
        !rendercache__grow(&vs->alloc, (void **)&vs->lattice, &vs->lattice_cap, v + 1, 3 * sizeof(uint32_t)) ||
        !rendercache__grow(&vs->alloc, (void **)&vs->ids, &vs->ids_cap, v + 1, sizeof(uint32_t *)))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    ids = (uint32_t *)rendercache__alloc_array(&vs->alloc, vs->id_pixels, sizeof(uint32_t));
    if (!ids) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    vs->ids[v] = ids;
    memcpy(vs->lattice + 3 * (size_t)v, k, 3 * sizeof(uint32_t));
    rendercache__vs_eye(vs, k, vs->eyes + 3 * (size_t)v);
    vs->view_count = v + 1;
    vs->table[slot] = v;
    rendercache__vs_camera(vs, vs->eyes + 3 * (size_t)v, &cam);
    if (d->render_ids(d->user, &cam, d->time, ids) != 0) return RENDERCACHE_ERROR_CANCELLED;
    *view = v;
    return RENDERCACHE_OK;
}

/* Subdivides node (section 4.1): the fitness of its corners' id images;
   below quality, halved across its longest axis (in world units) that
   can still be halved, and both halves in turn. */
static rendercache_result rendercache__vs_build(rendercache_view_space *vs, uint32_t node)
{
    const uint32_t corners = 1u << vs->axis_count;
    const uint32_t *ids[8];
    rendercache__vs_node *nd = &vs->nodes[node];
    uint32_t c, i, best = 0, mid, left, right;
    double best_len = -1.0;
    rendercache_result r;
    for (c = 0; c < corners; c++) {
        uint32_t k[3];
        memcpy(k, vs->nodes[node].lo, sizeof k);
        for (i = 0; i < vs->axis_count; i++)
            if (c & (1u << i)) k[vs->axis[i]] = vs->nodes[node].hi[vs->axis[i]];
        r = rendercache__vs_view(vs, k, &vs->nodes[node].corner[c]);
        if (r != RENDERCACHE_OK) return r;
        ids[c] = vs->ids[vs->nodes[node].corner[c]];
    }
    nd = &vs->nodes[node];
    nd->fitness = rendercache__fitness_of(ids, corners, vs->id_pixels);
    nd->axis = -1;
    for (i = 0; i < vs->axis_count; i++) {
        uint32_t a = vs->axis[i];
        double len = ((double)vs->hi[a] - vs->lo[a]) * (double)(nd->hi[a] - nd->lo[a]);
        if (nd->hi[a] - nd->lo[a] >= 2 && len > best_len) { best_len = len; best = i; }
    }
    if (nd->fitness >= vs->desc->quality || best_len < 0.0) { vs->leaf_count++; return RENDERCACHE_OK; }
    if (!rendercache__grow(&vs->alloc, (void **)&vs->nodes, &vs->node_cap, vs->node_count + 2, sizeof *vs->nodes))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    nd = &vs->nodes[node];
    mid = (nd->lo[vs->axis[best]] + nd->hi[vs->axis[best]]) / 2;
    nd->axis = (int32_t)best;
    nd->split = mid;
    left = vs->node_count++;
    right = vs->node_count++;
    nd->child[0] = left;
    nd->child[1] = right;
    vs->nodes[left] = vs->nodes[right] = *nd;
    vs->nodes[left].hi[vs->axis[best]] = mid;
    vs->nodes[right].lo[vs->axis[best]] = mid;
    r = rendercache__vs_build(vs, left);
    return r != RENDERCACHE_OK ? r : rendercache__vs_build(vs, right);
}

RENDERCACHE_API void rendercache_view_space_destroy(rendercache_view_space *vs)
{
    rendercache_allocator a;
    uint32_t v;
    if (!vs) return;
    a = vs->alloc;
    if (vs->ids)
        for (v = 0; v < vs->view_count; v++) rendercache__free(&a, vs->ids[v]);
    rendercache__free(&a, vs->ids);
    rendercache__free(&a, vs->eyes);
    rendercache__free(&a, vs->lattice);
    rendercache__free(&a, vs->nodes);
    rendercache__free(&a, vs->table);
    rendercache__free(&a, vs);
}

RENDERCACHE_API rendercache_result rendercache_view_space_create(const rendercache_view_space_desc *desc,
                                                                 rendercache_view_space **out)
{
    rendercache_view_space *vs;
    rendercache__view v;
    rendercache_result r;
    uint32_t depth, i;
    if (out) *out = NULL;
    if (!out || !desc) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    depth = rendercache__def(desc->max_depth, RENDERCACHE__DEFAULT_MAX_DEPTH);
    if (!rendercache__allocator_valid(&desc->allocator) || !desc->render_ids || !rendercache__view_init(&v, &desc->camera) ||
        !rendercache__finite3(desc->lo) || !rendercache__finite3(desc->hi) || !(desc->quality >= 0.0f && desc->quality <= 1.0f) ||
        depth > RENDERCACHE__MAX_DEPTH_LIMIT || !isfinite(desc->time)) {
        rendercache__log_to(desc->log, desc->log_user, "rendercache_view_space_create: invalid camera, box, quality, depth or callback");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    for (i = 0; i < 3; i++)
        if (!(desc->lo[i] <= desc->hi[i])) {
            rendercache__log_to(desc->log, desc->log_user, "rendercache_view_space_create: lo > hi");
            return RENDERCACHE_ERROR_INVALID_ARGUMENT;
        }
    vs = (rendercache_view_space *)rendercache__alloc(&desc->allocator, sizeof *vs);
    if (!vs) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    memset(vs, 0, sizeof *vs);
    vs->alloc = desc->allocator;
    vs->camera = desc->camera;
    vs->desc = desc;
    vs->id_pixels = (size_t)desc->camera.width * desc->camera.height;
    vs->steps = 1u << depth;
    for (i = 0; i < 3; i++) {
        vs->lo[i] = desc->lo[i];
        vs->hi[i] = desc->hi[i];
        if (desc->hi[i] > desc->lo[i]) vs->axis[vs->axis_count++] = i;
    }
    r = rendercache__grow(&vs->alloc, (void **)&vs->nodes, &vs->node_cap, 1, sizeof *vs->nodes)
            ? RENDERCACHE_OK : RENDERCACHE_ERROR_OUT_OF_MEMORY;
    if (r == RENDERCACHE_OK) {
        memset(&vs->nodes[0], 0, sizeof vs->nodes[0]);
        for (i = 0; i < 3; i++) vs->nodes[0].hi[i] = vs->hi[i] > vs->lo[i] ? vs->steps : 0;
        vs->node_count = 1;
        r = rendercache__vs_build(vs, 0);
    }
    if (vs->ids)   /* id images are only needed while building */
        for (i = 0; i < vs->view_count; i++) { rendercache__free(&vs->alloc, vs->ids[i]); vs->ids[i] = NULL; }
    vs->desc = NULL;
    if (r != RENDERCACHE_OK) {
        rendercache_view_space_destroy(vs);
        return r;
    }
    *out = vs;
    return RENDERCACHE_OK;
}

RENDERCACHE_API uint32_t rendercache_view_space_count(const rendercache_view_space *vs) { return vs ? vs->view_count : 0; }
RENDERCACHE_API const float *rendercache_view_space_eyes(const rendercache_view_space *vs) { return vs ? vs->eyes : NULL; }

RENDERCACHE_API rendercache_result rendercache_view_space_camera(const rendercache_view_space *vs, uint32_t i,
                                                                 rendercache_camera *camera)
{
    if (!vs || !camera || i >= vs->view_count) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    rendercache__vs_camera(vs, vs->eyes + 3 * (size_t)i, camera);
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_view_space_locate(const rendercache_view_space *vs, const float eye[3],
                                                                 uint32_t views[8], uint32_t *count)
{
    const rendercache__vs_node *nd;
    double k[3];
    uint32_t i;
    if (count) *count = 0;
    if (!vs || !eye || !views || !count || !rendercache__finite3(eye)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (i = 0; i < 3; i++) {   /* the eye on the lattice, clamped into the box */
        double span = (double)vs->hi[i] - vs->lo[i], f = span > 0.0 ? ((double)eye[i] - vs->lo[i]) / span : 0.0;
        k[i] = (f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f) * (double)vs->steps;
    }
    nd = &vs->nodes[0];
    while (nd->axis >= 0) nd = &vs->nodes[nd->child[k[vs->axis[nd->axis]] < (double)nd->split ? 0 : 1]];
    *count = 1u << vs->axis_count;
    memcpy(views, nd->corner, *count * sizeof(uint32_t));
    return RENDERCACHE_OK;
}

RENDERCACHE_API uint32_t rendercache_view_space_cell_count(const rendercache_view_space *vs)
{
    return vs ? vs->leaf_count : 0;
}

RENDERCACHE_API rendercache_result rendercache_view_space_cell(const rendercache_view_space *vs, uint32_t cell,
                                                               float lo[3], float hi[3], float *fitness)
{
    uint32_t n, seen = 0;
    if (!vs || cell >= vs->leaf_count) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (n = 0; n < vs->node_count; n++) {
        const rendercache__vs_node *nd = &vs->nodes[n];
        if (nd->axis >= 0) continue;
        if (seen++ != cell) continue;
        if (lo) rendercache__vs_eye(vs, nd->lo, lo);
        if (hi) rendercache__vs_eye(vs, nd->hi, hi);
        if (fitness) *fitness = nd->fitness;
        return RENDERCACHE_OK;
    }
    return RENDERCACHE_ERROR_INVALID_ARGUMENT;
}

/* Time subdivision state: per camera, buffers for the id images of the
   interval ends (levels 0 and 1) and of each level's midpoint. */
typedef struct rendercache__time_state {
    const rendercache_time_desc *d;
    rendercache_allocator alloc;
    uint32_t **ids;          /* (levels) * camera_count images */
    uint32_t levels, max_depth;
    double *out;
    uint32_t count, cap;
} rendercache__time_state;

static uint32_t *rendercache__time_ids(const rendercache__time_state *s, uint32_t level, uint32_t camera)
{
    return s->ids[(size_t)level * s->d->camera_count + camera];
}

static rendercache_result rendercache__time_render(const rendercache__time_state *s, uint32_t level, double t)
{
    uint32_t c;
    for (c = 0; c < s->d->camera_count; c++)
        if (s->d->render_ids(s->d->user, &s->d->cameras[c], t, rendercache__time_ids(s, level, c)) != 0)
            return RENDERCACHE_ERROR_CANCELLED;
    return RENDERCACHE_OK;
}

static rendercache_result rendercache__time_emit(rendercache__time_state *s, double t)
{
    if (!rendercache__grow(&s->alloc, (void **)&s->out, &s->cap, s->count + 1, sizeof(double)))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    s->out[s->count++] = t;
    return RENDERCACHE_OK;
}

/* Section 4.2: the interval [ta, tb] (id images at levels la, lb) is
   coherent when every camera's pair of id images has fitness >= quality;
   else it is halved, recursively. Emits the interval's inner key times and
   tb, in order. */
static rendercache_result rendercache__time_refine(rendercache__time_state *s, double ta, uint32_t la, double tb,
                                                   uint32_t lb, uint32_t depth)
{
    uint32_t c, lm = depth + 2;
    double tm = 0.5 * (ta + tb);
    rendercache_result r;
    int coherent = 1;
    for (c = 0; c < s->d->camera_count && coherent; c++) {
        const uint32_t *pair[2];
        const rendercache_camera *cam = &s->d->cameras[c];
        pair[0] = rendercache__time_ids(s, la, c);
        pair[1] = rendercache__time_ids(s, lb, c);
        coherent = rendercache__fitness_of(pair, 2, (size_t)cam->width * cam->height) >= s->d->quality;
    }
    if (coherent || depth >= s->max_depth || !(tm > ta && tm < tb)) return rendercache__time_emit(s, tb);
    r = rendercache__time_render(s, lm, tm);
    if (r == RENDERCACHE_OK) r = rendercache__time_refine(s, ta, la, tm, lm, depth + 1);
    if (r == RENDERCACHE_OK) r = rendercache__time_refine(s, tm, lm, tb, lb, depth + 1);
    return r;
}

static int rendercache__time_desc_valid(const rendercache_time_desc *d)
{
    rendercache__view v;
    uint32_t i;
    if (!d->cameras || d->camera_count == 0 || !d->times || d->time_count < 2 || !d->render_ids ||
        !(d->quality >= 0.0f && d->quality <= 1.0f) || d->max_depth > RENDERCACHE__MAX_DEPTH_LIMIT ||
        !rendercache__allocator_valid(&d->allocator))
        return 0;
    for (i = 0; i < d->camera_count; i++)
        if (!rendercache__view_init(&v, &d->cameras[i])) return 0;
    for (i = 0; i < d->time_count; i++)
        if (!isfinite(d->times[i]) || (i > 0 && !(d->times[i] > d->times[i - 1]))) return 0;
    return 1;
}

RENDERCACHE_API rendercache_result rendercache_subdivide_time(const rendercache_time_desc *desc, double **times,
                                                              uint32_t *count)
{
    rendercache__time_state s;
    rendercache_result r = RENDERCACHE_OK;
    uint32_t i, c, ends = 0;
    if (times) *times = NULL;
    if (count) *count = 0;
    if (!desc || !times || !count) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    if (!rendercache__time_desc_valid(desc)) {
        rendercache__log_to(desc->log, desc->log_user, "rendercache_subdivide_time: invalid cameras, times, quality, depth or callback");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    memset(&s, 0, sizeof s);
    s.d = desc;
    s.alloc = desc->allocator;
    s.max_depth = rendercache__def(desc->max_depth, RENDERCACHE__DEFAULT_MAX_DEPTH);
    s.levels = s.max_depth + 2;
    s.ids = (uint32_t **)rendercache__alloc_array(&s.alloc, (size_t)s.levels * desc->camera_count, sizeof(uint32_t *));
    if (!s.ids) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    memset(s.ids, 0, (size_t)s.levels * desc->camera_count * sizeof(uint32_t *));
    for (i = 0; i < s.levels && r == RENDERCACHE_OK; i++)
        for (c = 0; c < desc->camera_count; c++) {
            const rendercache_camera *cam = &desc->cameras[c];
            uint32_t *ids = (uint32_t *)rendercache__alloc_array(&s.alloc, (size_t)cam->width * cam->height, sizeof(uint32_t));
            s.ids[(size_t)i * desc->camera_count + c] = ids;
            if (!ids) { r = RENDERCACHE_ERROR_OUT_OF_MEMORY; break; }
        }
    if (r == RENDERCACHE_OK) r = rendercache__time_render(&s, 0, desc->times[0]);
    if (r == RENDERCACHE_OK) r = rendercache__time_emit(&s, desc->times[0]);
    for (i = 1; i < desc->time_count && r == RENDERCACHE_OK; i++) {   /* the given intervals in turn; ends alternate levels 0, 1 */
        r = rendercache__time_render(&s, 1u - ends, desc->times[i]);
        if (r == RENDERCACHE_OK) r = rendercache__time_refine(&s, desc->times[i - 1], ends, desc->times[i], 1u - ends, 0);
        ends = 1u - ends;
    }
    for (i = 0; i < s.levels * desc->camera_count; i++) rendercache__free(&s.alloc, s.ids[i]);
    rendercache__free(&s.alloc, s.ids);
    if (r != RENDERCACHE_OK) {
        rendercache__free(&s.alloc, s.out);
        return r;
    }
    *times = s.out;
    *count = s.count;
    return RENDERCACHE_OK;
}

/* ======================================================================
   21. key times of an object-space solution (sections 4.3 and 5.1.2):
   recursive halving of time until, between the ends of every interval,
   the fraction of elements that changed by more than epsilon is at most
   1 - q; linear interpolation in between.
   ---------------------------------------------------------------------- */
struct rendercache_keytimes {
    rendercache_allocator alloc;
    uint32_t elements, components;
    size_t stride;           /* floats per solution */
    double *times;
    float *values;
    uint32_t count, cap, values_cap;
};

typedef struct rendercache__key_state {
    const rendercache_keytime_desc *d;
    rendercache_keytimes *kt;
    float *pool;             /* (max_depth + 2) solutions: the ends, then each level's midpoint */
    uint32_t max_depth;
    float epsilon;
} rendercache__key_state;

static float *rendercache__key_buffer(const rendercache__key_state *s, uint32_t level)
{
    return s->pool + s->kt->stride * level;
}

/* Solves at time t into buffer level; the values must be finite. */
static rendercache_result rendercache__key_solve(const rendercache__key_state *s, uint32_t level, double t)
{
    float *v = rendercache__key_buffer(s, level);
    size_t i;
    if (s->d->solve(s->d->user, t, v) != 0) return RENDERCACHE_ERROR_CANCELLED;
    for (i = 0; i < s->kt->stride; i++)
        if (!isfinite(v[i])) {
            rendercache__log_to(s->d->log, s->d->log_user, "rendercache_keytimes_create: the solution is not finite");
            return RENDERCACHE_ERROR_INVALID_ARGUMENT;
        }
    return RENDERCACHE_OK;
}

static rendercache_result rendercache__key_emit(rendercache__key_state *s, double t, const float *v)
{
    rendercache_keytimes *kt = s->kt;
    uint32_t cap = kt->values_cap;
    if (!rendercache__grow(&kt->alloc, (void **)&kt->times, &kt->cap, kt->count + 1, sizeof(double)) ||
        !rendercache__grow(&kt->alloc, (void **)&kt->values, &cap, kt->count + 1, kt->stride * sizeof(float)))
        return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    kt->values_cap = cap;
    kt->times[kt->count] = t;
    memcpy(kt->values + kt->stride * kt->count, v, kt->stride * sizeof(float));
    kt->count++;
    return RENDERCACHE_OK;
}

/* The fraction of elements unchanged between two solutions (section 4.3's f). */
static float rendercache__key_fitness(const rendercache__key_state *s, const float *a, const float *b)
{
    const uint32_t comps = s->kt->components;
    const float floor_value = s->d->min_value;
    uint32_t e, k, unchanged = 0;
    for (e = 0; e < s->kt->elements; e++) {
        const float *x = a + (size_t)e * comps, *y = b + (size_t)e * comps;
        float scale = floor_value, change = 0.0f;
        for (k = 0; k < comps; k++) {
            float ax = fabsf(x[k]), ay = fabsf(y[k]), d = fabsf(y[k] - x[k]);
            scale = ax > scale ? ax : scale;
            scale = ay > scale ? ay : scale;
            change = d > change ? d : change;
        }
        unchanged += change <= s->epsilon * scale;
    }
    return (float)((double)unchanged / (double)s->kt->elements);
}

static rendercache_result rendercache__key_refine(rendercache__key_state *s, double ta, uint32_t la, double tb,
                                                  uint32_t lb, uint32_t depth)
{
    uint32_t lm = depth + 2;
    double tm = 0.5 * (ta + tb);
    rendercache_result r;
    if (rendercache__key_fitness(s, rendercache__key_buffer(s, la), rendercache__key_buffer(s, lb)) >= s->d->quality ||
        depth >= s->max_depth || !(tm > ta && tm < tb))
        return rendercache__key_emit(s, tb, rendercache__key_buffer(s, lb));
    r = rendercache__key_solve(s, lm, tm);
    if (r == RENDERCACHE_OK) r = rendercache__key_refine(s, ta, la, tm, lm, depth + 1);
    if (r == RENDERCACHE_OK) r = rendercache__key_refine(s, tm, lm, tb, lb, depth + 1);
    return r;
}

RENDERCACHE_API void rendercache_keytimes_destroy(rendercache_keytimes *kt)
{
    rendercache_allocator a;
    if (!kt) return;
    a = kt->alloc;
    rendercache__free(&a, kt->times);
    rendercache__free(&a, kt->values);
    rendercache__free(&a, kt);
}

RENDERCACHE_API rendercache_result rendercache_keytimes_create(const rendercache_keytime_desc *desc,
                                                               rendercache_keytimes **out)
{
    rendercache__key_state s;
    rendercache_keytimes *kt;
    rendercache_result r;
    uint32_t comps;
    if (out) *out = NULL;
    if (!out || !desc) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    comps = rendercache__def(desc->components, 1u);
    if (!desc->solve || desc->element_count == 0 || !rendercache__allocator_valid(&desc->allocator) ||
        !isfinite(desc->t0) || !isfinite(desc->t1) || !(desc->t0 < desc->t1) ||
        !(desc->quality >= 0.0f && desc->quality <= 1.0f) || !(desc->epsilon >= 0.0f) || !isfinite(desc->epsilon) ||
        !(desc->min_value >= 0.0f) || !isfinite(desc->min_value) || desc->max_depth > RENDERCACHE__MAX_DEPTH_LIMIT ||
        (uint64_t)desc->element_count * comps > (uint64_t)(SIZE_MAX / sizeof(float)) / (RENDERCACHE__MAX_DEPTH_LIMIT + 2)) {
        rendercache__log_to(desc->log, desc->log_user, "rendercache_keytimes_create: invalid counts, times, quality, epsilon or callback");
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    }
    kt = (rendercache_keytimes *)rendercache__alloc(&desc->allocator, sizeof *kt);
    if (!kt) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    memset(kt, 0, sizeof *kt);
    kt->alloc = desc->allocator;
    kt->elements = desc->element_count;
    kt->components = comps;
    kt->stride = (size_t)desc->element_count * comps;
    memset(&s, 0, sizeof s);
    s.d = desc;
    s.kt = kt;
    s.max_depth = rendercache__def(desc->max_depth, RENDERCACHE__DEFAULT_MAX_DEPTH);
    s.epsilon = rendercache__def(desc->epsilon, 0.05f);
    s.pool = (float *)rendercache__alloc_array(&kt->alloc, (size_t)(s.max_depth + 2) * kt->stride, sizeof(float));
    r = s.pool ? RENDERCACHE_OK : RENDERCACHE_ERROR_OUT_OF_MEMORY;
    if (r == RENDERCACHE_OK) r = rendercache__key_solve(&s, 0, desc->t0);
    if (r == RENDERCACHE_OK) r = rendercache__key_emit(&s, desc->t0, rendercache__key_buffer(&s, 0));
    if (r == RENDERCACHE_OK) r = rendercache__key_solve(&s, 1, desc->t1);
    if (r == RENDERCACHE_OK) r = rendercache__key_refine(&s, desc->t0, 0, desc->t1, 1, 0);
    rendercache__free(&kt->alloc, s.pool);
    if (r != RENDERCACHE_OK) {
        rendercache_keytimes_destroy(kt);
        return r;
    }
    *out = kt;
    return RENDERCACHE_OK;
}

RENDERCACHE_API uint32_t rendercache_keytimes_count(const rendercache_keytimes *kt) { return kt ? kt->count : 0; }
RENDERCACHE_API const double *rendercache_keytimes_times(const rendercache_keytimes *kt) { return kt ? kt->times : NULL; }

RENDERCACHE_API const float *rendercache_keytimes_values(const rendercache_keytimes *kt, uint32_t key)
{
    return kt && key < kt->count ? kt->values + kt->stride * key : NULL;
}

RENDERCACHE_API rendercache_result rendercache_keytimes_eval(const rendercache_keytimes *kt, double time, float *values,
                                                             size_t count)
{
    uint32_t lo = 0, hi;
    const float *a, *b;
    float w;
    size_t i;
    if (!kt || !values || !isfinite(time) || count < kt->stride) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    hi = kt->count - 1;
    if (time <= kt->times[0]) { memcpy(values, kt->values, kt->stride * sizeof(float)); return RENDERCACHE_OK; }
    if (time >= kt->times[hi]) { memcpy(values, kt->values + kt->stride * hi, kt->stride * sizeof(float)); return RENDERCACHE_OK; }
    while (hi - lo > 1) {   /* times[lo] < time < times[hi] */
        uint32_t mid = (lo + hi) / 2;
        if (kt->times[mid] <= time) lo = mid;
        else hi = mid;
    }
    w = (float)((time - kt->times[lo]) / (kt->times[hi] - kt->times[lo]));
    a = kt->values + kt->stride * lo;
    b = kt->values + kt->stride * hi;
    for (i = 0; i < kt->stride; i++) values[i] = (1.0f - w) * a[i] + w * b[i];
    return RENDERCACHE_OK;
}

/* ======================================================================
   22. relative luminance RMS error (section 5)
   ---------------------------------------------------------------------- */
RENDERCACHE_API rendercache_result rendercache_lrms(const float *reference, const float *image, uint32_t width,
                                                    uint32_t height, double *lrms)
{
    size_t n = (size_t)width * height, p;
    double sum_ref = 0.0, sum_d2 = 0.0, mean;
    if (lrms) *lrms = 0.0;
    if (!reference || !image || !lrms || width == 0 || height == 0 || (uint64_t)width * height > RENDERCACHE__MAX_PIXELS)
        return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    for (p = 0; p < n; p++) {
        const float *r = reference + 3 * p, *c = image + 3 * p;
        double lr = 0.2126 * r[0] + 0.7152 * r[1] + 0.0722 * r[2];
        double lc = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        sum_ref += lr;
        sum_d2 += (lc - lr) * (lc - lr);
    }
    mean = sum_ref / (double)n;
    if (!(mean > 0.0) || !isfinite(sum_d2) || !isfinite(mean)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    *lrms = sqrt(sum_d2 / (double)n) / mean;
    return RENDERCACHE_OK;
}

/* ======================================================================
   23. save and load of range images (file format version 1)
   magic "RCRANGE\x1a", version u32, payload size u64, payload, CRC32.
   Payload: camera (kind u32, eye, look_at, up 3 f32 each, vfov f32, width
   u32, height u32), time (f64 bits as u64), rgb (3 f32 per pixel), depth
   (f32 per pixel), object (u32 per pixel). Background and no-sample pixels
   load with depth RENDERCACHE_FAR_DEPTH.
   ---------------------------------------------------------------------- */
static const unsigned char rendercache__magic[8] = { 'R', 'C', 'R', 'A', 'N', 'G', 'E', 0x1a };
#define RENDERCACHE__RANGE_HEADER 60u   /* payload bytes before the pixels */

/* Whether a pixel's depth is one a surface can have. */
static int rendercache__depth_ok(uint32_t object, float depth)
{
    return object == RENDERCACHE_MISS || object == RENDERCACHE_NO_SAMPLE || (depth > 0.0f && depth <= FLT_MAX);
}

RENDERCACHE_API rendercache_result rendercache_range_image_save(const rendercache_range_image *img,
                                                                rendercache_write_fn write, void *user)
{
    rendercache__writer w;
    rendercache__view v;
    size_t n, p;
    uint64_t bits;
    if (!rendercache__range_valid(img, &v) || !write || !isfinite(img->time)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    n = (size_t)img->camera.width * img->camera.height;
    for (p = 0; p < n; p++)   /* only what a loader accepts */
        if (!rendercache__finite3(img->rgb + 3 * p) || !rendercache__depth_ok(img->object[p], img->depth[p]))
            return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    memset(&w, 0, sizeof w);
    w.write = write;
    w.user = user;
    rendercache__crc_init(&w.crc);
    rendercache__put(&w, rendercache__magic, 8);
    rendercache__put_u32(&w, RENDERCACHE_FILE_FORMAT_VERSION);
    rendercache__put_u64(&w, RENDERCACHE__RANGE_HEADER + 20 * (uint64_t)n);
    rendercache__put_u32(&w, (uint32_t)img->camera.kind);
    rendercache__put_f32_array(&w, img->camera.eye, 3);
    rendercache__put_f32_array(&w, img->camera.look_at, 3);
    rendercache__put_f32_array(&w, img->camera.up, 3);
    rendercache__put_f32(&w, img->camera.vfov_degrees);
    rendercache__put_u32(&w, img->camera.width);
    rendercache__put_u32(&w, img->camera.height);
    memcpy(&bits, &img->time, sizeof bits);
    rendercache__put_u64(&w, bits);
    rendercache__put_f32_array(&w, img->rgb, 3 * n);
    for (p = 0; p < n; p++)
        rendercache__put_f32(&w, rendercache__depth_ok(img->object[p], img->depth[p]) &&
                                         img->object[p] < RENDERCACHE_NO_SAMPLE ? img->depth[p] : RENDERCACHE__FAR);
    rendercache__put_u32_array(&w, img->object, n);
    rendercache__put_u32(&w, rendercache__crc_final(&w.crc));
    return w.failed ? RENDERCACHE_ERROR_IO : RENDERCACHE_OK;
}

/* Reads n little-endian 32-bit words into out (floats or integers). */
static void rendercache__get_words(rendercache__reader *r, void *out, size_t n)
{
    unsigned char buf[4096];
    uint32_t *o = (uint32_t *)out;
    size_t i = 0;
    while (i < n && !r->failed) {
        size_t m = n - i < sizeof buf / 4 ? n - i : sizeof buf / 4, j;
        rendercache__get(r, buf, 4 * m);
        for (j = 0; j < m; j++, i++) {
            const unsigned char *b = buf + 4 * j;
            o[i] = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
        }
    }
}

static rendercache_result rendercache__read_range(rendercache__reader *r, const rendercache_allocator *a,
                                                  rendercache_range_image **out)
{
    unsigned char magic[8];
    rendercache_camera cam;
    rendercache__view v;
    rendercache_range_image *img;
    uint32_t version, kind, expected_crc;
    uint64_t bits;
    size_t n, p;
    rendercache__crc_init(&r->crc);
    r->remaining = 20;
    rendercache__get(r, magic, 8);
    version = rendercache__get_u32(r);
    r->remaining = rendercache__get_u64(r);
    if (r->failed || memcmp(magic, rendercache__magic, 8) != 0) return RENDERCACHE_ERROR_CORRUPT_DATA;
    if (version != RENDERCACHE_FILE_FORMAT_VERSION) return RENDERCACHE_ERROR_VERSION;
    memset(&cam, 0, sizeof cam);
    kind = rendercache__get_u32(r);
    rendercache__get_words(r, cam.eye, 3);
    rendercache__get_words(r, cam.look_at, 3);
    rendercache__get_words(r, cam.up, 3);
    cam.vfov_degrees = rendercache__get_f32(r);
    cam.width = rendercache__get_u32(r);
    cam.height = rendercache__get_u32(r);
    bits = rendercache__get_u64(r);
    if (r->failed || kind > (uint32_t)RENDERCACHE_CAMERA_SPHERE) return RENDERCACHE_ERROR_CORRUPT_DATA;
    cam.kind = (rendercache_camera_kind)kind;
    if (!rendercache__view_init(&v, &cam)) return RENDERCACHE_ERROR_CORRUPT_DATA;
    n = (size_t)cam.width * cam.height;
    if (r->remaining != 20 * (uint64_t)n || !rendercache__can_hold(r, n, 20)) return RENDERCACHE_ERROR_CORRUPT_DATA;
    img = rendercache__range_alloc(&cam, a);
    if (!img) return RENDERCACHE_ERROR_OUT_OF_MEMORY;
    *out = img;
    memcpy(&img->time, &bits, sizeof bits);
    rendercache__get_words(r, img->rgb, 3 * n);
    rendercache__get_words(r, img->depth, n);
    rendercache__get_words(r, img->object, n);
    if (r->failed || !isfinite(img->time)) return RENDERCACHE_ERROR_CORRUPT_DATA;
    for (p = 0; p < n; p++) {
        if (!rendercache__finite3(img->rgb + 3 * p) || !rendercache__depth_ok(img->object[p], img->depth[p]))
            return RENDERCACHE_ERROR_CORRUPT_DATA;
        if (img->object[p] >= RENDERCACHE_NO_SAMPLE) img->depth[p] = RENDERCACHE__FAR;
    }
    expected_crc = rendercache__crc_final(&r->crc);
    r->remaining = 4;
    if (rendercache__get_u32(r) != expected_crc || r->failed) return RENDERCACHE_ERROR_CORRUPT_DATA;
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_range_image_load(const rendercache_allocator *allocator,
                                                                rendercache_read_fn read, void *user,
                                                                rendercache_range_image **out)
{
    rendercache_allocator a;
    rendercache__reader r;
    rendercache_range_image *img = NULL;
    rendercache_result res;
    if (out) *out = NULL;
    if (!read || !out || !rendercache__allocator_arg(allocator, &a)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    memset(&r, 0, sizeof r);
    r.read = read;
    r.user = user;
    res = rendercache__read_range(&r, &a, &img);
    if (res != RENDERCACHE_OK) {
        rendercache_range_image_destroy(img);
        return res;
    }
    *out = img;
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_range_image_save_to_memory(const rendercache_range_image *image,
                                                                          const rendercache_allocator *allocator,
                                                                          void **data, size_t *size)
{
    rendercache_allocator a;
    rendercache__membuf m;
    rendercache_result r;
    if (data) *data = NULL;
    if (size) *size = 0;
    if (!image || !data || !size || !rendercache__allocator_arg(allocator, &a)) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    memset(&m, 0, sizeof m);
    m.a = &a;
    r = rendercache_range_image_save(image, rendercache__membuf_write, &m);
    if (r != RENDERCACHE_OK) {
        rendercache__free(&a, m.data);
        return r == RENDERCACHE_ERROR_IO ? RENDERCACHE_ERROR_OUT_OF_MEMORY : r;   /* only growth can fail */
    }
    *data = m.data;
    *size = m.size;
    return RENDERCACHE_OK;
}

RENDERCACHE_API rendercache_result rendercache_range_image_load_from_memory(const void *data, size_t size,
                                                                            const rendercache_allocator *allocator,
                                                                            rendercache_range_image **out)
{
    rendercache__membuf m;
    if (out) *out = NULL;
    if (!data || !out) return RENDERCACHE_ERROR_INVALID_ARGUMENT;
    memset(&m, 0, sizeof m);
    m.data = (unsigned char *)(uintptr_t)data;   /* read only */
    m.size = size;
    return rendercache_range_image_load(allocator, rendercache__membuf_read, &m, out);
}

RENDERCACHE_API void rendercache_free_memory(const rendercache_allocator *allocator, void *data)
{
    rendercache_allocator a;
    if (!rendercache__allocator_arg(allocator, &a)) return;
    rendercache__free(&a, data);
}

RENDERCACHE_API const char *rendercache_result_string(rendercache_result r)
{
    switch (r) {
    case RENDERCACHE_OK: return "ok";
    case RENDERCACHE_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RENDERCACHE_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RENDERCACHE_ERROR_CORRUPT_DATA: return "corrupt data";
    case RENDERCACHE_ERROR_VERSION: return "unsupported format version";
    case RENDERCACHE_ERROR_CANCELLED: return "cancelled";
    case RENDERCACHE_ERROR_IO: return "read or write callback failed";
    }
    return "unknown result";
}

#endif /* RENDERCACHE_IMPLEMENTATION */

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
