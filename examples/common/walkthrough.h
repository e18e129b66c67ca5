/* walkthrough.h - the frame pipeline of examples/walkthrough.c and
   examples/viewer.c: a generated building (make_building.py's OBJ, MTL and
   layout; the walk is planned from the layout: a lit room, a room without a
   lamp, up the stairs, the camera following the bunny): --scene house (the
   default, building_1k: two storeys of two rooms) or --scene building
   (building_4k: two storeys of nine rooms); the office (--scene office: the
   bunny under the desk and past the yellow divider, the camera along the
   front wall); or the house by day (--scene daylight, below), rendered in
   one of three modes that compose the project's four headers. Tests and
   the benchmark drive it too.

       wt_options o;  wt_world *w;  wt_renderer *r;  wt_frame_stats st;
       wt_options_default(&o);                         // or wt_parse_options
       wt_world_create(&o, &w, err, sizeof err);       // scene files, tracer, light-vector scene
       wt_renderer_create(w, &r, err, sizeof err);     // the mode's precompute, cached on disk
       for (f = 0; f < w->opt.frames; f++) wt_render_frame(r, f, rgb, &st);   // the frame count, resolved
       wt_renderer_destroy(r);  wt_world_destroy(w);

   Shading (modes raytrace and baseviews). A primary hit gets its emission,
   direct light from the emitting polygons (many-light sampling: a fixed
   number of shadow rays per point, --light-samples, each choosing a light
   by an importance bound of power, distance and both cosines, mixed with
   that bound times whether a coarse grid's cell around the point sees
   each light (wt__light_grid_build: lights behind walls rarely take a
   ray), and divided by the choice's probability; within 8 of a light's
   radii the ray's direction is uniform in the light's solid angle (Arvo
   1995's spherical triangles, wt__light_view_direction), farther it aims
   at a uniform point of its area; shadow rays through
   examples/common/trace.h, so the bunny casts shadows; Lambert +
   normalized Phong) and indirect light from a light
   vector (lightvec.h, Crespin & Peroche 2004): looked up in a cache, and
   gathered and inserted where the cache has too few valid vectors. Near
   the bunny, the office's indirect light is dimmed by the share of the
   hemisphere the bunny covers, ray traced against the bunny within reach
   (contact shadows, wt__contact_occlusion; --no-bunny-shadow turns them
   off). Glossy
   materials (floor, desk, lamp pole) use 5D light vectors (position and
   viewing direction), Lambertian ones view-independent 3D vectors. The
   office's vectors live in a static cache, warmed up along the path in the
   precompute and saved; the bunny's in a cache of their own, made anew at
   every pose (a gather on the bunny sees the office and the posed bunny).
   Lookups and gathers run in rounds that make the result independent of
   the thread count (wt__light_points).

     raytrace   the render cache (rendercache.h, Walter et al. 1999/2002):
                each frame reprojects the cached points, requests a fixed
                budget of pixels (default 8%, as in Crespin & Peroche) by
                error diffusion of the priority image, predicts the next
                camera's holes, shades the requests and inserts them with
                priority scale lightvec_priority(1, W) (4.3: a point lit by
                an interpolated vector of weight W is refreshed 1/W times
                sooner; the bunny's points 4 times sooner still, as its light
                changes while it walks). The first frame is traced in full.
     baseviews  range images (rendercache.h part 2, Nimeroff, Dorsey &
                Rushmeier 1996, through examples/common/baseviews.h): the
                camera's line of eyes (the office), or its route through a
                building as a chain of 2 m stretches, is subdivided until
                fish-eye id images agree on a fraction q of their pixels
                (base views), key times are refined with the same test
                (a fish-eye below each lamp and the base views), the base
                images some frame warps from are traced with the shading
                above and saved; the bunny's indirect light is solved at key
                times of its own (rendercache_keytimes_create, section 4.3)
                and interpolated in time for the base images. A frame blends
                the base images of the two views around its eye (on a route:
                around its time) to its time,
                moving the bunny by its transforms, and warps them into its
                camera with both fills, averaging the views that see a
                surface (pinterp -a); gaps wider than 8 pixels are traced.
     radiosity  the static office shaded per pixel by Hardt's quadratic
                irradiance interpolants (radinterp.h) from an ID +
                barycentric buffer (examples/common/raster.h), the bunny
                Gouraud-shaded per vertex from an irradiance volume
                (irrvol.h, Greger 1996) built from the radiosity solution,
                times its self-occlusion ratio (irrvol_visibility_ratio).
                The pixels are shaded in the raster's tile jobs, a run of
                pixels of one triangle at a time (radinterp_shade_span).

   Daylight. A layout may name a sky ("sky R G B", W/(m^2 sr), or "sky R G
   B MAP.pfm": R G B times an equirectangular little-endian RGB PFM beside
   the layout, rows from the zenith down as in scene_sky.h; wt_layout_load
   refuses a malformed line, a second sky, a negative or non-finite value
   and an unreadable map, naming the line). Materials with Tf > 0 are thin
   glass. In modes raytrace and baseviews the sky and the glass reach every
   part: camera rays go straight through the panes, dimmed by their
   transmittance, to the surface behind them or the sky
   (ex_tracer_intersect_through; a pane's own reflection is not drawn);
   shadow rays to the lamps are dimmed by the panes they cross; the
   light-vector scenes get the sky (lightvec_scene_desc.sky or
   .environment), so gathers see it through the windows: daylight is
   indirect light, in the light vectors, as lightvec.h's GLASS AND SKY
   describes. --scene daylight is make_building.py --daylight's
   building_1k_daylight (glass in every window, lamps off, a ground, an
   overcast sky). In mode radiosity the solution gets the materials'
   transmittance and the sky (radinterp.h's GLASS AND SKY: light crosses
   the panes, the sky lights every element and point through them), and
   the bunny's irradiance volume, built from the solution's mesh, gets the
   sky and the panes (irrvol's transmittance, from the patch's material).

   Precompute cache. Files <cache_dir>/walkthrough-<what>-<key>.bin, key =
   FNV-1a hash of the scene files' bytes, the paths (every frame's camera,
   the bunny's transforms), the header versions and every parameter the data
   depends on; each holds a header's own serialization (lightvec_save,
   rendercache_range_image_save, irrvol_save) in an envelope with a CRC.
   Written to a temporary file and renamed; an interrupt deletes the
   temporary file (wt_install_interrupt_handler). A damaged or stale file is
   rebuilt. A later run with the same inputs loads the data and renders the
   same frames, bit for bit.

   Header-only like the rest of examples/common; it includes the
   implementations of the four headers (unless WT_LIBRARIES_LINKED is
   defined: then link them from elsewhere), so include it in exactly one
   translation unit. Conventions: metres, +y up, time t in
   [0, 1] from the first frame to the last; object ids of the render cache
   and the range images: 0 = the office, 1 = the bunny. */
#ifndef EXAMPLES_COMMON_WALKTHROUGH_H
#define EXAMPLES_COMMON_WALKTHROUGH_H

#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L
#endif
#include <errno.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "base.h"
#include "camera.h"
#include "image.h"
#include "obj.h"
#include "pool.h"
#include "raster.h"
#include "baseviews.h"
#include "trace.h"

/* WT_LIBRARIES_LINKED: the four implementations come from another object.
   make test compiles them once per sanitizer for all its walkthrough
   programs: they were 29 of the 33 s it took to compile each. */
#ifndef WT_LIBRARIES_LINKED
#define IRRVOL_IMPLEMENTATION
#define LIGHTVEC_IMPLEMENTATION
#define RENDERCACHE_IMPLEMENTATION
#define RADINTERP_IMPLEMENTATION
#endif
#include "irrvol.h"
#include "lightvec.h"
#include "rendercache.h"
#include "radinterp.h"

#define WT_PI 3.14159265358979f
#define WT_OBJECT_OFFICE 0u
#define WT_OBJECT_BUNNY 1u
#define WT_BUNNY_SCALE 0.03f        /* bunny.obj is ~9.7 units tall: a 0.29 m bunny */
#define WT_BUNNY_KD 0.6f            /* grey, like Greger's rabbit */
#define WT_BUNNY_RADIUS 0.16f       /* metres: the scaled bunny's footprint (0.30 x 0.23 m) */
#define WT_CAMERA_VFOV 60.0f
#define WT_BUNNY_NORMAL_ANGLE 30.0f  /* degrees: light vectors valid between the bunny's normals */
#define WT_BUNNY_PRIORITY 4.0f      /* render-cache priority scale of the bunny's points */
#define WT_PHASES 4
#define WT_BASEVIEWS_MAX_FILL 8u   /* baseviews: background fill reaches this many pixels of a 640-pixel-wide frame
                                      (as far in angle at other widths); farther ones are traced */
#define WT_BASEVIEWS_SLOPE 7.0f     /* baseviews: the final warp joins neighbouring base pixels of a surface seen
                                      this steeply (tan 82 degrees from its normal) into foreground quads */
#define WT_BASEVIEWS_LAMP_SHARE 0.2f   /* baseviews: warped pixels this bright (share of the dimmest lamp's
                                         emitted luminance) are traced at the frame */
#define WT_BASEVIEWS_EDGE_REACH 1u      /* baseviews: warped pixels this near an edge are traced again (wt__edge_pixel) */
#define WT_BASEVIEWS_EDGE_CONTRAST 2.0f /* baseviews: luminances of a pixel's window further apart than this ratio are
                                           an edge (a crease between a lit and a shaded face, a shadow's border; not
                                           the base images' noise, about 5 % a pixel in a lit room). 1.5 took twice
                                           the light-vector gathers for 0.003-0.004 less LRMS (wt__edge_pixel) */
#define WT__MAX_LIGHT_SAMPLES 1024  /* bound of --light-samples: shadow rays per shaded point */
#define WT_KEY_EPSILON 0.1f        /* baseviews: a bunny vertex changed when its radiance moved by more than 10% */
#define WT_KEY_EXTRA_DEPTH 1u      /* baseviews: more halvings of the bunny's key intervals (wt__key_depth) */
/* Shadow rays at each hit point of a light-vector gather (lightvec's
   default is 1). With one, a gather ray that lands near the lamp (the wall
   and ceiling beside it, lit at 1/d^2) brings back a rare huge value: a
   firefly in the gather, which the cache then spreads over the record's
   radius as a bright blotch on the floor (issue 19). Four rays cut that
   variance by 4; measured at 160x120 against converged renders (48
   frames, every 8th): frames 0.140 -> 0.128 LRMS, full renders 0.102 ->
   0.084. Since lightvec.h v0.4.8 picks each sample's emitter by its
   importance at the hit (not by power: most samples went to lamps behind
   the hit's own plane or rooms away, and cost no shadow ray), two rays
   are as good as four were and every one is traced: the relative RMS
   noise of a gather's irradiance (one thread, the static gathers at 12 x
   9 camera pixels of t = 0.1, 0.5, 0.9, two seeds) v0.4.7 with 4 -> v0.4.8
   with 2 -> v0.4.8 with 4: office 0.069 -> 0.056 -> 0.045 at 0.80 ->
   0.93 -> 1.33 ms a gather, building_4k 0.111 -> 0.032 -> 0.031 at 1.51
   -> 2.16 -> 3.01 ms (load 8-10, outside make bench). */
#define WT_GATHER_HIT_SAMPLES 2u

typedef enum wt_mode {
    WT_MODE_RAYTRACE = 0,
    WT_MODE_BASEVIEWS,
    WT_MODE_RADIOSITY
} wt_mode;

/* Mode radiosity's full renders (--reference) gather this many reflections:
   the radiosity solution holds every interreflection, and the office's mean
   reflectance of about 0.6 leaves 0.6^9 = 1% of the light to later ones
   (with the raytrace mode's 2, the reference lacks 36% of the indirect
   light and its LRMS against the radiosity frames is 0.42 instead of 0.10). */
#define WT_REFERENCE_BOUNCES 8

/* What wt_renderer_create returns besides 0 and -1: the mode cannot
   render this scene. Every mode renders glass and a sky now; the viewer
   still passes to the next mode on it. */
#define WT_ERROR_UNSUPPORTED (-2)

/* Everything a run depends on. Fields that change pictures also change the
   keys of the precompute cache. */
struct wt_path;

typedef struct wt_options {
    wt_mode mode;
    const char *out;          /* PNG frames, contact sheet */
    const char *cache_dir;    /* precompute cache */
    const char *data_dir;     /* bunny.obj, and the scenes named by scene */
    const char *scene;        /* "house" (the default: data_dir/building_1k.*, two storeys of two rooms),
                                 "office" (data_dir/office.*), "building" (data_dir/building_4k.*, two
                                 storeys of nine rooms), "daylight" (data_dir/building_1k_daylight.*:
                                 glass and a sky), or the path of an OBJ with a .layout file beside it
                                 (make_building.py's format) */
    const struct wt_path *path;   /* set by wt_world_create in the world's copy: the walk planned through the
                                     scene's layout; NULL: the office's built-in walk */
    int frames;               /* frames along the walk; 0 = from the route (wt_route_frames), which
                                 wt_world_create sets in the world's copy */
    int width, height;
    int threads;              /* 0 = one per core */
    uint64_t seed;
    /* shading (every mode that ray traces) */
    int light_samples;        /* direct light: shadow rays per shaded point, over all the lights (wt__direct) */
    int strata;               /* light-vector gathers on the office: zenith strata (azimuth: 3x) */
    int bunny_strata;         /* gathers on the bunny */
    int bounces;              /* reflections of the gathered light (lightvec_gather_desc.bounces);
                                 mode radiosity's full renders use at least WT_REFERENCE_BOUNCES */
    int warmup_divisor;       /* light-vector warm-up: the path's views at 1/N of the frame size */
    /* raytrace */
    float budget;             /* share of the pixels sampled per frame */
    /* baseviews */
    int base_size;            /* fish-eye base images N x N */
    int id_size;              /* id images of the coherence tests */
    int keys;                 /* key times before refinement (uniform in [0, 1]) */
    float quality;            /* q of the coherence tests */
    /* radiosity */
    float radiosity_eps;      /* radinterp_desc.eps, W/m^2; 0 = radinterp's default */
    float min_leaf_area;      /* radinterp_mesh_desc.min_leaf_area, m^2; 0 = every leaf */
    int volume_resolution;    /* irradiance volume k */
    int visibility_rays;      /* self-occlusion rays per bunny vertex */
    int bunny_shadow;         /* the bunny's contact shadow on the office: radiosity, its occlusion blob;
                                 raytrace and baseviews, ray-traced occlusion of indirect light */
    int gouraud;              /* the office Gouraud-shaded from the mesh's corners (radinterp_shade_gouraud) */
    /* run */
    int use_cache;            /* load and save the precompute cache */
    int write_frames;         /* PNGs */
    int progress;             /* progress bars on stderr */
    int verbose;              /* messages on stdout */
    int reference;            /* trace every frame in full too and report LRMS */
    int converged;            /* N > 0: frames N-1, 2N-1, ... also against converged renders (wt_converged_lrms) */
    float exposure;           /* 0 = automatic per frame (wt_exposure) */
} wt_options;

/* What a frame cost. phase[] by mode (wt_phase_name). */
typedef struct wt_frame_stats {
    double phase[WT_PHASES];  /* seconds: wall time, but mode radiosity's raster, shade and volume are
                                 CPU time summed over the threads that ran them (its "other" is the
                                 wall time they leave, 0 when they ran on several threads) */
    double total;             /* seconds, the frame's wall time */
    uint32_t samples;         /* raytrace: pixels shaded; baseviews: pixels traced by the fill;
                                 radiosity: volume queries */
    uint32_t lookups, hits, gathers;   /* light vectors */
    uint32_t bunny_gathers;            /* of which on the bunny */
    int full;                 /* raytrace: the first frame, traced in full */
    double lrms;              /* against a full render (wt_options.reference), else -1 */
    double converged;         /* against converged renders, their noise taken out (wt_options.converged), else -1 */
} wt_frame_stats;

/* ======================================================================
   options
   ---------------------------------------------------------------------- */
EX_FN void wt_options_default(wt_options *o)
{
    memset(o, 0, sizeof *o);
    o->mode = WT_MODE_RADIOSITY;
    o->out = "build/out";
    o->cache_dir = "build/cache";
    o->data_dir = "examples/data";
    o->scene = "house";       /* the largest building whose radiosity precompute takes about a minute */
    o->frames = 0;            /* from the route: wt_world_create calls wt_route_frames */
    o->width = 640;
    o->height = 480;
    o->seed = 1;
    o->light_samples = 8;
    o->strata = 16;
    o->bunny_strata = 8;
    o->bounces = 2;
    o->warmup_divisor = 4;
    o->budget = 0.08f;        /* Crespin & Peroche: 21000 of 512 x 512 pixels */
    o->base_size = 512;
    o->id_size = 64;
    o->keys = 5;
    o->quality = 0.8f;
    o->volume_resolution = 17;   /* Greger's k */
    o->visibility_rays = 256;
    o->bunny_shadow = 1;
    o->use_cache = 1;
    o->write_frames = 1;
    o->progress = 1;
    o->verbose = 1;
}

EX_FN const char *wt_mode_name(wt_mode m)
{
    switch (m) {
    case WT_MODE_RAYTRACE: return "raytrace";
    case WT_MODE_BASEVIEWS: return "baseviews";
    case WT_MODE_RADIOSITY: return "radiosity";
    }
    return "?";
}

/* Names of the timing phases of a mode (NULL past the last). */
EX_FN const char *wt_phase_name(wt_mode m, int phase)
{
    static const char *raytrace[WT_PHASES] = { "cache", "trace", "lightvec", "other" };
    static const char *baseviews[WT_PHASES] = { "blend", "warp", "other", NULL };
    static const char *radiosity[WT_PHASES] = { "raster", "shade", "volume", "other" };
    if (phase < 0 || phase >= WT_PHASES) return NULL;
    return m == WT_MODE_RAYTRACE ? raytrace[phase] : m == WT_MODE_BASEVIEWS ? baseviews[phase] : radiosity[phase];
}

EX_FN void wt_usage(FILE *f)
{
    fputs("usage: walkthrough [options]\n"
          "A walkthrough of the office (or a building) with a bunny walking from room to room,\n"
          "rendered interactively with global illumination. Writes PNG frames, a contact sheet and\n"
          "a per-frame timing table; precomputed data is cached on disk and reused.\n"
          "\n"
          "  --mode M             radiosity (default): per-pixel radiosity interpolants for the office,\n"
          "                       an irradiance volume for the bunny\n"
          "                       raytrace: render cache + ray tracer + light vectors\n"
          "                       baseviews: warps of fish-eye base views (range images)\n"
          "  --frames N           frames along the path (default: from the route, the camera moving\n"
          "                       0.1 m and turning 1.5 degrees a frame, at least 48)\n"
          "  --size WxH           frame size (default 640x480)\n"
          "  --out DIR            where frames go (default build/out)\n"
          "  --cache DIR          precompute cache (default build/cache)\n"
          "  --no-cache           neither read nor write the precompute cache\n"
          "  --scene S            house (default: DIR/building_1k.obj, .mtl, .layout: two storeys of two\n"
          "                       rooms), office (DIR/office.*), building (DIR/building_4k.*: two storeys\n"
          "                       of nine rooms), daylight (DIR/building_1k_daylight.*: glass in the\n"
          "                       windows and a sky), or an OBJ with a make_building.py layout beside it\n"
          "                       (a sky line makes it daylight)\n"
          "  --data DIR           bunny.obj and the scenes (default examples/data)\n"
          "  --threads N          threads, 0 = one per core (default 0)\n"
          "  --seed N             random seed (default 1)\n"
          "  --budget F           raytrace: share of the pixels sampled per frame (default 0.08)\n"
          "  --light-samples N    direct light: shadow rays per shaded point, lights chosen by importance\n"
          "                       (default 8)\n"
          "  --strata N           light-vector gathers: N x 3N rays (default 16)\n"
          "  --base N             baseviews: fish-eye base images N x N (default 512)\n"
          "  --keys N             baseviews: key times before refinement (default 5)\n"
          "  --quality Q          baseviews: coherence quality q in [0, 1] (default 0.8)\n"
          "  --eps E              radiosity: solver error bound in W/m^2 (default: radinterp's, 1% of\n"
          "                       the scene's mean emitted radiosity under a 5% relative bound)\n"
          "  --min-leaf-area A    radiosity: coarsest mesh leaves in m^2 (default 0: every leaf)\n"
          "  --volume-k K         radiosity: irradiance volume bins 2K^2, K <= 32 (default 17)\n"
          "  --no-bunny-shadow    no contact shadow of the bunny on the office (radiosity: its occlusion\n"
          "                       blob; raytrace, baseviews: ray-traced occlusion of indirect light)\n"
          "  --gouraud            radiosity: Gouraud shading of the mesh instead of its interpolants\n"
          "  --exposure E         exposure before the filmic curve (default: automatic per frame)\n"
          "  --reference          also trace every frame in full and print the LRMS error\n"
          "  --converged N        also render frames N-1, 2N-1, ... converged (slow) and print the\n"
          "                       LRMS error against them, their own noise taken out (kept in the\n"
          "                       precompute cache: a second run renders only its frames)\n"
          "  --no-frames          do not write PNG frames or the contact sheet\n"
          "  --quiet              no progress bars or messages, only the timing table\n"
          "  --help               this text\n", f);
}

static int wt__parse_int(const char *s, int lo, int hi, int *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) return 0;
    *out = (int)v;
    return 1;
}

static int wt__parse_float(const char *s, float lo, float hi, float *out)
{
    char *end;
    float v;
    errno = 0;
    v = strtof(s, &end);
    if (errno || end == s || *end || !(v >= lo && v <= hi)) return 0;
    *out = v;
    return 1;
}

/* Parses the command line into o (start from wt_options_default). Returns
   1 to run, 0 when --help was printed, -1 on an error (message in err). */
EX_FN int wt_parse_options(int argc, char **argv, wt_options *o, char *err, size_t err_size)
{
    int i;
    err[0] = 0;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int ok = 1;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) { wt_usage(stdout); return 0; }
        if (!strcmp(a, "--no-cache")) { o->use_cache = 0; continue; }
        if (!strcmp(a, "--no-frames")) { o->write_frames = 0; continue; }
        if (!strcmp(a, "--quiet")) { o->progress = o->verbose = 0; continue; }
        if (!strcmp(a, "--reference")) { o->reference = 1; continue; }
        if (!strcmp(a, "--no-bunny-shadow")) { o->bunny_shadow = 0; continue; }
        if (!strcmp(a, "--gouraud")) { o->gouraud = 1; continue; }
        if (strncmp(a, "--", 2) != 0) {
            snprintf(err, err_size, "unexpected argument '%s' (see --help)", a);
            return -1;
        }
        if (!v) {
            if (!strcmp(a, "--mode") || !strcmp(a, "--frames") || !strcmp(a, "--size") || !strcmp(a, "--out") ||
                !strcmp(a, "--cache") || !strcmp(a, "--data") || !strcmp(a, "--scene") || !strcmp(a, "--threads") || !strcmp(a, "--seed") ||
                !strcmp(a, "--budget") || !strcmp(a, "--light-samples") || !strcmp(a, "--strata") ||
                !strcmp(a, "--base") || !strcmp(a, "--keys") || !strcmp(a, "--quality") || !strcmp(a, "--exposure") ||
                !strcmp(a, "--eps") || !strcmp(a, "--min-leaf-area") || !strcmp(a, "--volume-k") ||
                !strcmp(a, "--converged"))
                snprintf(err, err_size, "%s needs a value (see --help)", a);
            else
                snprintf(err, err_size, "unknown option '%s' (see --help)", a);
            return -1;
        }
        if (!strcmp(a, "--mode")) {
            if (!strcmp(v, "raytrace")) o->mode = WT_MODE_RAYTRACE;
            else if (!strcmp(v, "baseviews")) o->mode = WT_MODE_BASEVIEWS;
            else if (!strcmp(v, "radiosity")) o->mode = WT_MODE_RADIOSITY;
            else { snprintf(err, err_size, "--mode must be raytrace, baseviews or radiosity, not '%s'", v); return -1; }
        } else if (!strcmp(a, "--frames")) ok = wt__parse_int(v, 1, 100000, &o->frames);
        else if (!strcmp(a, "--converged")) ok = wt__parse_int(v, 1, 100000, &o->converged);
        else if (!strcmp(a, "--size")) {
            const char *x = strchr(v, 'x');
            char w[32];
            size_t n = x ? (size_t)(x - v) : 0;
            ok = x && n > 0 && n < sizeof w;
            if (ok) {
                memcpy(w, v, n);
                w[n] = 0;
                ok = wt__parse_int(w, 8, 8192, &o->width) && wt__parse_int(x + 1, 8, 8192, &o->height);
            }
        } else if (!strcmp(a, "--out")) o->out = v;
        else if (!strcmp(a, "--cache")) o->cache_dir = v;
        else if (!strcmp(a, "--data")) o->data_dir = v;
        else if (!strcmp(a, "--scene")) o->scene = v;
        else if (!strcmp(a, "--threads")) ok = wt__parse_int(v, 0, EX_POOL_MAX_THREADS, &o->threads);
        else if (!strcmp(a, "--seed")) {
            int s;
            ok = wt__parse_int(v, 0, 2147483647, &s);
            o->seed = (uint64_t)s;
        } else if (!strcmp(a, "--budget")) ok = wt__parse_float(v, 1e-4f, 1.0f, &o->budget);
        else if (!strcmp(a, "--light-samples")) ok = wt__parse_int(v, 1, WT__MAX_LIGHT_SAMPLES, &o->light_samples);
        else if (!strcmp(a, "--strata")) ok = wt__parse_int(v, 2, 128, &o->strata);
        else if (!strcmp(a, "--base")) ok = wt__parse_int(v, 16, 4096, &o->base_size);
        else if (!strcmp(a, "--keys")) ok = wt__parse_int(v, 2, 257, &o->keys);
        else if (!strcmp(a, "--quality")) ok = wt__parse_float(v, 0.0f, 1.0f, &o->quality);
        else if (!strcmp(a, "--exposure")) ok = wt__parse_float(v, 1e-6f, 1e6f, &o->exposure);
        else if (!strcmp(a, "--eps")) ok = wt__parse_float(v, 1e-6f, 1e6f, &o->radiosity_eps);
        else if (!strcmp(a, "--min-leaf-area")) ok = wt__parse_float(v, 0.0f, 100.0f, &o->min_leaf_area);
        else if (!strcmp(a, "--volume-k")) ok = wt__parse_int(v, 2, 32, &o->volume_resolution);
        else { snprintf(err, err_size, "unknown option '%s' (see --help)", a); return -1; }
        if (!ok) {
            snprintf(err, err_size, "bad value '%s' for %s (see --help for the ranges)", v, a);
            return -1;
        }
        i++;
    }
    return 1;
}

/* ======================================================================
   clocks, messages, progress bars
   ---------------------------------------------------------------------- */
EX_FN double wt_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double wt__clock(void *user)
{
    (void)user;
    return wt_seconds();
}

/* A progress bar on stderr: redrawn in place on a terminal, one final line
   otherwise. */
typedef struct wt_progress {
    const char *label;
    double start;
    int shown;       /* permille last drawn, -1 = none */
    int enabled, tty;
} wt_progress;

EX_FN void wt_progress_begin(wt_progress *p, const char *label, int enabled)
{
    p->label = label;
    p->start = wt_seconds();
    p->shown = -1;
    p->enabled = enabled;
    p->tty = isatty(2);
}

static void wt__progress_draw(wt_progress *p, int permille)
{
    int filled, i;
    char bar[41];
    p->shown = permille;
    filled = permille * 40 / 1000;
    for (i = 0; i < 40; i++) bar[i] = i < filled ? '#' : '.';
    bar[40] = 0;
    fprintf(stderr, "%s  %-34s [%s] %3d%% %6.1f s%s", p->tty ? "\r" : "", p->label, bar, permille / 10,
            wt_seconds() - p->start, permille == 1000 ? "\n" : "");
    fflush(stderr);
}

/* Matches the headers' progress callback; never cancels (Ctrl-C ends the
   process, see wt_install_interrupt_handler). 100% is drawn by
   wt_progress_end alone: a total may still grow (irrvol's refined cells
   join once the first level is gathered), and the bar then steps back. */
EX_FN int wt_progress_update(void *user, uint64_t done, uint64_t total)
{
    wt_progress *p = (wt_progress *)user;
    int permille;
    if (!p || !p->enabled || !p->tty || p->shown == 1000) return 0;
    permille = total ? (int)(1000.0 * (double)done / (double)total) : 999;
    if (permille > 999) permille = 999;
    if (abs(permille - p->shown) >= 5) wt__progress_draw(p, permille);
    return 0;
}

EX_FN void wt_progress_end(wt_progress *p)
{
    if (p && p->enabled && p->shown != 1000) wt__progress_draw(p, 1000);
}

/* ======================================================================
   the precompute cache on disk
   A file walkthrough-<what>-<key>.bin holds one header's serialized data
   behind a small envelope (magic, envelope version, key, size, CRC-32).
   The key hashes the scene files' bytes and every parameter the data
   depends on, so a change of either makes a new file. Files are written to
   a temporary name and renamed, and an interrupt removes the temporary
   file: a cache file is complete or absent.
   ---------------------------------------------------------------------- */
#define WT_CACHE_MAGIC "WTCACHE"
#define WT_CACHE_VERSION 1u

/* FNV-1a, 64 bits. */
EX_FN uint64_t wt_hash(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    if (h == 0) h = 0xcbf29ce484222325ull;
    for (i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

/* Hashes values one by one (never a struct's padding). */
EX_FN uint64_t wt_hash_u64(uint64_t h, uint64_t v)
{
    unsigned char b[8];
    int i;
    for (i = 0; i < 8; i++) b[i] = (unsigned char)(v >> (8 * i));
    return wt_hash(h, b, 8);
}

EX_FN uint64_t wt_hash_f32(uint64_t h, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    return wt_hash_u64(h, u);
}

EX_FN uint64_t wt_hash_str(uint64_t h, const char *s) { return wt_hash(wt_hash_u64(h, strlen(s)), s, strlen(s)); }

static char wt__tmp_path[1100];
static volatile sig_atomic_t wt__tmp_active;

static void wt__on_interrupt(int sig)
{
    if (wt__tmp_active) unlink(wt__tmp_path);   /* async-signal-safe */
    signal(sig, SIG_DFL);
    raise(sig);
}

/* Ctrl-C (and SIGTERM) while a cache file is being written removes the
   temporary file before the process ends. */
EX_FN void wt_install_interrupt_handler(void)
{
    signal(SIGINT, wt__on_interrupt);
    signal(SIGTERM, wt__on_interrupt);
}

/* mkdir -p */
EX_FN int wt_make_dirs(const char *path)
{
    char buf[1024];
    size_t i, n = strlen(path);
    if (n == 0 || n >= sizeof buf) return -1;
    memcpy(buf, path, n + 1);
    for (i = 1; i <= n; i++)
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
            buf[i] = c;
        }
    return 0;
}

EX_FN void wt_cache_path(const char *dir, const char *what, uint64_t key, char *path, size_t size)
{
    snprintf(path, size, "%s/walkthrough-%s-%016llx.bin", dir, what, (unsigned long long)key);
}

static void wt__put32(unsigned char *p, uint32_t v)
{
    int i;
    for (i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}
static void wt__put64(unsigned char *p, uint64_t v)
{
    int i;
    for (i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t wt__get32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint64_t wt__get64(const unsigned char *p) { return (uint64_t)wt__get32(p) | (uint64_t)wt__get32(p + 4) << 32; }

#define WT__ENVELOPE 32   /* magic 8, version 4, crc 4, key 8, size 8 */

/* Writes data under its key: a temporary file, flushed, then renamed.
   Returns 0, or -1 (with a message in err). */
EX_FN int wt_cache_store(const char *dir, const char *what, uint64_t key, const void *data, size_t size,
                         char *err, size_t err_size)
{
    char path[1024];
    unsigned char head[WT__ENVELOPE];
    FILE *f;
    int ok;
    if (wt_make_dirs(dir) != 0) {
        snprintf(err, err_size, "cannot create the cache directory %.200s: %s", dir, strerror(errno));
        return -1;
    }
    wt_cache_path(dir, what, key, path, sizeof path);
    snprintf(wt__tmp_path, sizeof wt__tmp_path, "%.1000s.tmp%ld", path, (long)getpid());
    memcpy(head, WT_CACHE_MAGIC, 8);
    wt__put32(head + 8, WT_CACHE_VERSION);
    wt__put32(head + 12, ex__crc32_update(0, (const unsigned char *)data, size));
    wt__put64(head + 16, key);
    wt__put64(head + 24, (uint64_t)size);
    wt__tmp_active = 1;
    f = fopen(wt__tmp_path, "wb");
    if (!f) {
        wt__tmp_active = 0;
        snprintf(err, err_size, "cannot write %.200s: %s", wt__tmp_path, strerror(errno));
        return -1;
    }
    ok = fwrite(head, 1, sizeof head, f) == sizeof head && fwrite(data, 1, size, f) == size && fflush(f) == 0 &&
         fsync(fileno(f)) == 0;
    ok = fclose(f) == 0 && ok;
    if (!ok || rename(wt__tmp_path, path) != 0) {
        snprintf(err, err_size, "cannot write %.200s: %s", path, strerror(errno));
        unlink(wt__tmp_path);
        wt__tmp_active = 0;
        return -1;
    }
    wt__tmp_active = 0;
    return 0;
}

/* Reads the data stored under key. Returns 1 with *data (free it) and
   *size, 0 when there is no such file, -1 when the file is damaged (it
   is then rebuilt and overwritten). */
EX_FN int wt_cache_load(const char *dir, const char *what, uint64_t key, void **data, size_t *size)
{
    char path[1024];
    unsigned char head[WT__ENVELOPE];
    FILE *f;
    uint64_t n;
    void *buf;
    *data = NULL;
    *size = 0;
    wt_cache_path(dir, what, key, path, sizeof path);
    f = fopen(path, "rb");
    if (!f) return 0;
    if (fread(head, 1, sizeof head, f) != sizeof head || memcmp(head, WT_CACHE_MAGIC, 8) != 0 ||
        wt__get32(head + 8) != WT_CACHE_VERSION || wt__get64(head + 16) != key) {
        fclose(f);
        return -1;
    }
    n = wt__get64(head + 24);
    if (n > ((uint64_t)1 << 40) || (buf = malloc((size_t)n + 1)) == NULL) {
        fclose(f);
        return -1;
    }
    if (fread(buf, 1, (size_t)n, f) != (size_t)n || fgetc(f) != EOF ||
        ex__crc32_update(0, (const unsigned char *)buf, (size_t)n) != wt__get32(head + 12)) {
        free(buf);
        fclose(f);
        return -1;
    }
    fclose(f);
    *data = buf;
    *size = (size_t)n;
    return 1;
}

/* ---- a growable byte buffer for composite cache payloads ---------------- */
typedef struct wt_bytes {
    unsigned char *data;
    size_t size, capacity, read;   /* read: cursor of wt_bytes_get */
    int failed;
} wt_bytes;

EX_FN void wt_bytes_put(wt_bytes *b, const void *p, size_t n)
{
    if (b->failed) return;
    if (b->size + n > b->capacity) {
        size_t cap = b->capacity ? b->capacity : 4096;
        unsigned char *d;
        while (cap < b->size + n) cap *= 2;
        d = (unsigned char *)realloc(b->data, cap);
        if (!d) { b->failed = 1; return; }
        b->data = d;
        b->capacity = cap;
    }
    memcpy(b->data + b->size, p, n);
    b->size += n;
}

EX_FN void wt_bytes_put_u64(wt_bytes *b, uint64_t v)
{
    unsigned char p[8];
    wt__put64(p, v);
    wt_bytes_put(b, p, 8);
}

/* Reads n bytes at the cursor; 0 when fewer are left. */
EX_FN int wt_bytes_get(wt_bytes *b, void *p, size_t n)
{
    if (n > b->size - b->read) return 0;
    memcpy(p, b->data + b->read, n);
    b->read += n;
    return 1;
}

EX_FN int wt_bytes_get_u64(wt_bytes *b, uint64_t *v)
{
    unsigned char p[8];
    if (!wt_bytes_get(b, p, 8)) return 0;
    *v = wt__get64(p);
    return 1;
}

/* Adds a file's bytes to a hash; 0 when the file cannot be read. */
static int wt__hash_file(const char *path, uint64_t *h)
{
    unsigned char buf[65536];
    size_t n;
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) *h = wt_hash(*h, buf, n);
    fclose(f);
    return 1;
}

/* ======================================================================
   the world: office, bunny, ray tracer, light-vector scenes and caches
   ---------------------------------------------------------------------- */

/* Which light-vector cache lights a shaded point. */
enum { WT_LIGHT_NONE = 0, WT_LIGHT_STATIC = 1, WT_LIGHT_BUNNY = 2 };

/* One point to shade: a primary ray in, radiance out. */
typedef struct wt_point {
    float org[3], dir[3];    /* in: the ray (dir unit) */
    uint64_t stream;         /* in: its random stream (direct light, gather) */
    float pos[3], normal[3]; /* the hit; normal faces the viewer */
    float t;                 /* distance along the ray; FLT_MAX on a miss */
    uint32_t object;         /* WT_OBJECT_* or RENDERCACHE_MISS */
    uint32_t polygon;        /* office face, or the bunny triangle + office face count (id images) */
    uint32_t material;       /* index into wt_world.materials */
    float direct[3];         /* emission + direct light; on a miss, the sky */
    float indirect[3];       /* from the light vector */
    float direct_gloss[3];   /* the specular (view-dependent) parts of direct and indirect */
    float indirect_gloss[3];
    float view_share;        /* share of rgb's luminance that depends on the view (wt__point_radiance) */
    float through[3];        /* transmittance of the glass between the eye and the hit (1: none) */
    float contact;           /* share of the indirect light the bunny leaves (wt__contact_occlusion; 1: all) */
    float rgb[3];            /* out: radiance towards the eye, through * (direct + contact * indirect) */
    float weight;            /* W of the light vector: lookup weight, 1 for a new vector */
    unsigned char light;     /* WT_LIGHT_* */
    unsigned char glossy;    /* 5D light vector (view dependent) */
    unsigned char lit;       /* indirect light known */
    unsigned char gathered;  /* its light vector was computed for it */
    unsigned char bunny_shadow;   /* the bunny blocked some of its direct or indirect light */
} wt_point;

/* An emitting polygon of the office (its fan triangles are consecutive),
   with the bounds of the many-light sampler (wt__light_importance): its
   area-weighted centroid (on its plane), the radius of the sphere about it
   that holds the polygon, and its power up to a constant (luminance of Ke
   times area). */
typedef struct wt_light {
    uint32_t first_tri, tri_count;
    float area, normal[3], point[3], ke[3];
    float centre[3], radius, power;
} wt_light;

/* The layout of a generated building (make_building.py's .layout file):
   rooms, doors and stairs as boxes, metres. */
typedef struct wt_room {
    int storey, i, j;
    int lamp;                  /* the room has a lamp of its own */
    int stair;                 /* a flight of stairs starts in it */
    float lo[3], hi[3];
} wt_room;

typedef struct wt_box {
    int storey;
    float lo[3], hi[3];
} wt_box;

/* The layout's sky (`sky R G B [MAP]`): what rays that leave the building
   see, R G B times the environment map's texel (a PFM file beside the
   layout, latitude-longitude with +y up, scene_sky.h's layout), or the
   constant R G B without a map. */
#define WT_SKY_MAX_TEXELS (1u << 22)   /* an environment map's texels: 4M, 48 MB of floats */

typedef struct wt_layout {
    wt_room *rooms;
    wt_box *doors, *stairs;    /* a stair rises along +x from lo[0] to hi[0] */
    uint32_t room_count, door_count, stair_count, lamp_count, window_count;
    int has_sky;               /* a sky line: daylight */
    ex_sky sky;                /* its map (when any) points into sky_map */
    float *sky_map;            /* owned */
    char sky_map_path[1024];   /* "" without a map */
} wt_layout;

/* The walk through a building: the bunny's route as points every
   WT_PATH_STEP metres, its feet on whatever supports them (floors, the
   stairs' treads), and the camera trailing it along the same route. */
#define WT_PATH_STEP 0.02f
#define WT_CAMERA_TRAIL 1.5f       /* metres of route between the camera and the bunny */
#define WT_EYE_HEIGHT 1.5f         /* above the floor under the camera, smoothed over the stairs */
#define WT_PATH_MAX_ROOMS 8

typedef struct wt_path {
    float *points;             /* 3 per point: the bunny's feet */
    float *eye;                /* 1 per point: the camera's eye height when it stands there */
    float *sight;              /* 1 per point: metres of route ahead the camera standing there sees
                                  (wt__path_sight), at most WT_CAMERA_TRAIL + WT__LOOK_AHEAD */
    uint32_t count;
    float length;              /* metres along the route (in plan) */
    float start;               /* the bunny's place on the route at t = 0: the camera starts at 0 */
    int rooms[WT_PATH_MAX_ROOMS];   /* layout rooms the route was planned through, in order */
    int room_count;
} wt_path;

EX_FN void wt_layout_free(wt_layout *l)
{
    free(l->rooms);
    free(l->doors);
    free(l->stairs);
    free(l->sky_map);
    memset(l, 0, sizeof *l);
}

EX_FN void wt_path_free(wt_path *p)
{
    free(p->points);
    free(p->eye);
    free(p->sight);
    memset(p, 0, sizeof *p);
}

typedef struct wt_world {
    wt_options opt;
    char office_path[1024], bunny_path[1024], layout_path[1024];
    uint64_t scene_hash;               /* the bytes of the scene's files and bunny.obj */
    obj_scene office, bunny;           /* office: the static scene, the office or a building */
    wt_layout layout;                  /* a building's rooms, doors and stairs (none for the office) */
    wt_path path;                      /* the walk through a building (opt.path points here) */
    float bunny_lo[3], bunny_hi[3];    /* bounds of bunny.obj */
    float bunny_bound_centre[3];       /* their centre (OBJ coordinates) */
    float bunny_bound_radius;          /* metres: the posed bunny lies within this of the posed centre */
    float *bunny_normals;              /* smooth vertex normals, OBJ coordinates */
    ex_tracer *tracer;
    int bunny_instance;
    wt_light *lights;                  /* emitting polygons */
    uint32_t light_count;
    /* which lights each cell of a coarse grid sees (wt__light_grid_build) */
    float *light_seen;                 /* cell-major: a neighbourhood and a cell flag (0 or 1) per light a cell */
    /* what the frames' own shadow rays found (wt__light_learn_merge): per
       key (a cell and the main axis and sign of a normal) and light */
    uint16_t *light_learned;           /* shadow rays tried, arrived: earlier frames' (read during a frame) */
    uint32_t *light_learning;          /* the same for the frame being traced (atomic adds) */
    unsigned char *learn_touched;      /* per key: the frame being traced recorded there */
    uint32_t learn_sides;              /* keys a cell: 6 (by normal), 1 (by cell), 0: no learning */
    float grid_lo[3], grid_cell;       /* the grid's corner and cells' edge, metres */
    uint32_t grid_dims[3];
    ex_pool *pool;
    lightvec_material *materials;      /* the office's, then the bunny's */
    uint32_t material_count, bunny_material;
    lightvec_scene *office_scene;      /* the static office: gathers of the static cache */
    lightvec_cache *static_cache;
    lightvec_gather_desc static_gather, bunny_gather;
    /* the bunny at the current time */
    double time;
    float pose[12];
    pthread_mutex_t pose_lock;
    int pose_ready;                    /* posed_scene and bunny_cache match pose */
    lightvec_scene *posed_scene;       /* office + bunny as posed */
    lightvec_cache *bunny_cache;       /* light vectors on the bunny at this pose */
    float *posed_positions;
    uint32_t *posed_indices, *posed_materials;
    /* scratch of the light-vector rounds */
    uint32_t *pending, *picks;
    uint64_t *cells;
    lightvec_record *records;
    uint32_t scratch_capacity, cell_capacity;
} wt_world;

static void wt__materials_from_obj(const obj_scene *s, lightvec_material *m)
{
    uint32_t i;
    for (i = 0; i < s->material_count; i++) {
        memset(&m[i], 0, sizeof m[i]);
        memcpy(m[i].diffuse, s->materials[i].kd, sizeof m[i].diffuse);
        memcpy(m[i].specular, s->materials[i].ks, sizeof m[i].specular);
        memcpy(m[i].emission, s->materials[i].ke, sizeof m[i].emission);
        memcpy(m[i].transmittance, s->materials[i].tf, sizeof m[i].transmittance);   /* glass passes light */
        m[i].exponent = s->materials[i].ns;
    }
}

static int wt__is_glossy(const lightvec_material *m)
{
    return m->specular[0] > 0.0f || m->specular[1] > 0.0f || m->specular[2] > 0.0f;
}

/* A light-vector cache with the header's defaults (radius 0.3 d_avg, 3
   valid vectors, 20 degrees between normals, gradient interpolation), or
   for the bunny, whose normals turn fast over a small body, 30 degrees. */
static lightvec_cache *wt__new_cache(const wt_world *w, int bunny)
{
    lightvec_cache_desc d;
    lightvec_cache *c = NULL;
    memset(&d, 0, sizeof d);
    if (bunny) d.max_normal_angle = WT_BUNNY_NORMAL_ANGLE;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = w->pool;
    return lightvec_cache_create(&d, &c) == LIGHTVEC_OK ? c : NULL;
}

EX_FN void wt_world_destroy(wt_world *w)
{
    if (!w) return;
    lightvec_cache_destroy(w->static_cache);
    lightvec_cache_destroy(w->bunny_cache);
    lightvec_scene_destroy(w->office_scene);
    lightvec_scene_destroy(w->posed_scene);
    ex_tracer_destroy(w->tracer);
    ex_pool_destroy(w->pool);
    pthread_mutex_destroy(&w->pose_lock);
    obj_free(&w->office);
    obj_free(&w->bunny);
    free(w->bunny_normals);
    free(w->lights);
    free(w->light_seen);
    free(w->light_learned);
    free(w->light_learning);
    free(w->learn_touched);
    free(w->materials);
    free(w->posed_positions);
    free(w->posed_indices);
    free(w->posed_materials);
    free(w->pending);
    free(w->picks);
    free(w->cells);
    free(w->records);
    wt_layout_free(&w->layout);
    wt_path_free(&w->path);
    free(w);
}

/* A light's centroid, bounding radius about it and power (see wt_light). */
static void wt__light_bounds(const wt_world *w, wt_light *L)
{
    const float *pos = w->office.positions;
    uint32_t i;
    int k, c;
    memset(L->centre, 0, sizeof L->centre);
    for (i = L->first_tri; i < L->first_tri + L->tri_count; i++)
        for (c = 0; c < 3; c++)
            for (k = 0; k < 3; k++)
                L->centre[k] += w->tracer->tri_area[i] / (3.0f * L->area) * pos[3 * (size_t)w->office.tri_indices[3 * i + c] + k];
    L->radius = 0.0f;
    for (i = L->first_tri; i < L->first_tri + L->tri_count; i++)
        for (c = 0; c < 3; c++) {
            const float *v = pos + 3 * (size_t)w->office.tri_indices[3 * i + c];
            float d = sqrtf((v[0] - L->centre[0]) * (v[0] - L->centre[0]) + (v[1] - L->centre[1]) * (v[1] - L->centre[1]) +
                            (v[2] - L->centre[2]) * (v[2] - L->centre[2]));
            if (d > L->radius) L->radius = d;
        }
    L->radius *= 1.0f + 1e-5f;   /* rounding of the centroid: the sphere still holds every corner */
    L->power = (0.2126f * L->ke[0] + 0.7152f * L->ke[1] + 0.0722f * L->ke[2]) * L->area;
}

/* The emitting polygons: runs of consecutive triangles of one emitting face. */
static int wt__find_lights(wt_world *w)
{
    const obj_scene *s = &w->office;
    uint32_t i;
    w->lights = (wt_light *)calloc(s->tri_count + 1, sizeof *w->lights);
    if (!w->lights) return -1;
    for (i = 0; i < s->tri_count; i++) {
        const obj_material *m = &s->materials[s->tri_material[i]];
        wt_light *L = w->light_count ? &w->lights[w->light_count - 1] : NULL;
        if (!(m->ke[0] > 0.0f || m->ke[1] > 0.0f || m->ke[2] > 0.0f) || !(w->tracer->tri_area[i] > 0.0f)) continue;
        if (!L || s->tri_face[L->first_tri] != s->tri_face[i] || L->first_tri + L->tri_count != i) {
            L = &w->lights[w->light_count++];
            L->first_tri = i;
            memcpy(L->normal, w->tracer->tri_normal + 3 * (size_t)i, sizeof L->normal);
            memcpy(L->point, s->positions + 3 * (size_t)s->tri_indices[3 * i], sizeof L->point);
            memcpy(L->ke, m->ke, sizeof L->ke);
        }
        L->tri_count++;
        L->area += w->tracer->tri_area[i];
    }
    for (i = 0; i < w->light_count; i++) wt__light_bounds(w, &w->lights[i]);
    return 0;
}

/* The light-vector scene of the static geometry: its triangles, the
   materials (glass passes light), and the layout's sky (GLASS AND SKY in
   lightvec.h: gather rays that leave the building see it, through the
   panes). */
static void wt__scene_desc(const wt_world *w, lightvec_scene_desc *sd)
{
    memset(sd, 0, sizeof *sd);
    sd->positions = w->office.positions;
    sd->vertex_count = w->office.vertex_count;
    sd->indices = w->office.tri_indices;
    sd->triangle_count = w->office.tri_count;
    sd->material_ids = w->office.tri_material;
    sd->materials = w->materials;
    sd->material_count = w->material_count;
    if (!w->layout.has_sky) return;
    memcpy(sd->sky, w->layout.sky.radiance, sizeof sd->sky);
    sd->environment = w->layout.sky.map;
    sd->environment_width = (uint32_t)w->layout.sky.width;
    sd->environment_height = (uint32_t)w->layout.sky.height;
}

/* The file name (without .obj) in the data directory of a built-in scene:
   "house" is building_1k (two storeys of two rooms), "building" building_4k,
   "daylight" building_1k_daylight (make_building.py --daylight); NULL when
   name is not a built-in scene but a path. */
EX_FN const char *wt_builtin_scene_file(const char *name)
{
    static const char *const names[][2] = {
        { "office", "office" }, { "house", "building_1k" }, { "building", "building_4k" }, { "daylight", "building_1k_daylight" }
    };
    size_t i;
    for (i = 0; name && i < sizeof names / sizeof *names; i++)
        if (!strcmp(name, names[i][0])) return names[i][1];
    return NULL;
}

/* The files of o->scene: the OBJ, its MTL (same name, .mtl) and for a
   building its layout (.layout; "" for the office, whose walk is built in). */
static void wt__scene_files(const wt_options *o, char *obj, char *mtl, char *layout, size_t size)
{
    const char *scene = o->scene ? o->scene : "office", *file = wt_builtin_scene_file(scene);
    size_t n;
    if (file)
        snprintf(obj, size, "%.900s/%s.obj", o->data_dir, file);
    else
        snprintf(obj, size, "%.1000s", scene);
    n = strlen(obj);
    if (n > 4 && !strcmp(obj + n - 4, ".obj")) n -= 4;
    snprintf(mtl, size, "%.*s.mtl", (int)n, obj);
    if (!strcmp(scene, "office")) layout[0] = 0;
    else snprintf(layout, size, "%.*s.layout", (int)n, obj);
}

static int wt__fail(char *err, size_t n, const char *fmt, const char *what)
{
    snprintf(err, n, fmt, what);
    return -1;
}

/* ======================================================================
   a building's layout and the walk through it
   The route visits a lit room, a room without a lamp of its own and the
   stairs: it starts in a lit room next to the dark room (by doors), walks
   into the dark room, to the foot of the stairs, up them, and into the
   room above (or on to the dark room when it is upstairs). Between those
   goals the route is planned on a walkable grid of each storey: cells of
   WT__CELL metres whose column from just above the floor to above the
   camera's eye is free of geometry and which have floor under them,
   eroded by the bunny's radius and a margin; A* finds the shortest
   8-connected route, which is then pulled straight where the grid allows
   and smoothed. The climb is the stair's centre line. The bunny's feet
   stand on the highest surface under its footprint (rays cast down), so it
   hops from tread to tread.
   ---------------------------------------------------------------------- */
#define WT__CELL 0.05f             /* metres per walkable-grid cell */
#define WT__CLEARANCE 0.26f        /* from the route to any obstacle: the bunny's radius and 10 cm */
#define WT__HEADROOM 1.8f          /* the column kept free above the floor: the camera's eye and more */
#define WT__SMOOTH 0.2f            /* metres each side: the route's moving average */

static int wt__push(void **items, uint32_t *count, size_t size, const void *item)
{
    if ((*count & (*count - 1)) == 0) {   /* grow at powers of two */
        void *p = realloc(*items, size * (*count ? 2 * (size_t)*count : 4));
        if (!p) return -1;
        *items = p;
    }
    memcpy((char *)*items + size * *count, item, size);
    ++*count;
    return 0;
}

/* The sky line's environment map: a little-endian RGB PFM (ex_write_pfm's
   format) named relative to the layout's directory. Returns 0, or -1 with
   a message. */
static int wt__sky_map_load(const char *layout_path, int number, const char *name, wt_layout *l, char *err,
                            size_t err_size)
{
    const char *slash = strrchr(layout_path, '/');
    int w, h;
    if (name[0] == '/' || !slash)
        snprintf(l->sky_map_path, sizeof l->sky_map_path, "%.1000s", name);
    else
        snprintf(l->sky_map_path, sizeof l->sky_map_path, "%.*s/%.500s", (int)(slash - layout_path), layout_path, name);
    if (ex_load_pfm(l->sky_map_path, WT_SKY_MAX_TEXELS, &w, &h, &l->sky_map) != 0) {
        snprintf(err, err_size, "%.150s:%d: the sky map %.150s is not a readable little-endian RGB PFM of at most %u texels",
                 layout_path, number, l->sky_map_path, WT_SKY_MAX_TEXELS);
        return -1;
    }
    l->sky.map = l->sky_map;
    l->sky.width = w;
    l->sky.height = h;
    return 0;
}

/* A sky line, "sky R G B [MAP]" (see wt_layout): radiance finite and >= 0,
   one sky per layout. Returns 0, or -1 with a message naming the line. */
static int wt__sky_line(const char *path, int number, const char *line, wt_layout *l, char *err, size_t err_size)
{
    char map[512], extra[2];
    float v[3];
    int n = sscanf(line, "%*s %f %f %f %511s %1s", &v[0], &v[1], &v[2], map, extra), k;
    if (n < 3 || n > 4 || l->has_sky) {
        snprintf(err, err_size, "%.200s:%d: %s", path, number,
                 l->has_sky ? "a second sky line" : "a sky line is 'sky R G B' or 'sky R G B MAP.pfm'");
        return -1;
    }
    for (k = 0; k < 3; k++)
        if (!(v[k] >= 0.0f && v[k] <= 3.4e38f)) {
            snprintf(err, err_size, "%.200s:%d: the sky's radiance must be finite and >= 0", path, number);
            return -1;
        }
    memcpy(l->sky.radiance, v, sizeof v);
    if (n == 4 && wt__sky_map_load(path, number, map, l, err, err_size) != 0) return -1;
    if (l->sky_map) {   /* the map times R G B: the headers take one array */
        size_t i, texels = (size_t)l->sky.width * (size_t)l->sky.height;
        for (i = 0; i < texels; i++)
            for (k = 0; k < 3; k++) l->sky_map[3 * i + k] *= v[k];
    }
    if (!ex_sky_valid(&l->sky)) {
        snprintf(err, err_size, "%.200s:%d: the sky map has a negative or non-finite texel", path, number);
        return -1;
    }
    l->has_sky = 1;
    return 0;
}

/* Reads a .layout file. Returns 0, or -1 with a message naming the line. */
EX_FN int wt_layout_load(const char *path, wt_layout *l, char *err, size_t err_size)
{
    FILE *f = fopen(path, "r");
    char line[512];
    int number = 0;
    memset(l, 0, sizeof *l);
    if (!f) {
        snprintf(err, err_size, "cannot read %.200s: %s", path, strerror(errno));
        return -1;
    }
    while (fgets(line, sizeof line, f)) {
        char kind[16], lamp[16];
        float v[6] = { 0, 0, 0, 0, 0, 0 };   /* lamp lines set none */
        int storey, i, j, stair, n, ok = 1, k;
        number++;
        if (sscanf(line, "%15s", kind) != 1 || kind[0] == '#') continue;
        if (!strcmp(kind, "room")) {
            wt_room r;
            n = sscanf(line, "%*s %d %d %d %f %f %f %f %f %f %15s %d", &storey, &i, &j, &v[0], &v[1], &v[2], &v[3],
                       &v[4], &v[5], lamp, &stair);
            ok = n == 11;
            memset(&r, 0, sizeof r);
            r.storey = storey;
            r.i = i;
            r.j = j;
            r.lamp = ok && strcmp(lamp, "none") != 0;
            r.stair = stair;
            for (k = 0; k < 3 && ok; k++) {
                r.lo[k] = v[2 * k];
                r.hi[k] = v[2 * k + 1];
            }
            ok = ok && wt__push((void **)&l->rooms, &l->room_count, sizeof r, &r) == 0;
        } else if (!strcmp(kind, "door") || !strcmp(kind, "stair") || !strcmp(kind, "window")) {
            wt_box b;
            n = sscanf(line, "%*s %d %f %f %f %f %f %f", &storey, &v[0], &v[1], &v[2], &v[3], &v[4], &v[5]);
            ok = n == 7;
            b.storey = storey;
            for (k = 0; k < 3 && ok; k++) {
                b.lo[k] = v[2 * k];
                b.hi[k] = v[2 * k + 1];
            }
            if (ok && kind[0] == 'd') ok = wt__push((void **)&l->doors, &l->door_count, sizeof b, &b) == 0;
            else if (ok && kind[0] == 's') ok = wt__push((void **)&l->stairs, &l->stair_count, sizeof b, &b) == 0;
            else l->window_count += ok;
        } else if (!strcmp(kind, "lamp")) {
            l->lamp_count++;
        } else if (!strcmp(kind, "sky")) {
            if (wt__sky_line(path, number, line, l, err, err_size) != 0) {
                fclose(f);
                wt_layout_free(l);
                return -1;
            }
            continue;
        } else {
            ok = 0;
        }
        for (k = 0; k < 6 && ok; k++) ok = isfinite(v[k]) && (k % 2 == 0 || v[k] >= v[k - 1]);
        if (!ok) {
            snprintf(err, err_size, "%.200s:%d: not a room, door, window, stair, lamp or sky line of make_building.py",
                     path, number);
            fclose(f);
            wt_layout_free(l);
            return -1;
        }
    }
    fclose(f);
    if (l->room_count == 0) {
        snprintf(err, err_size, "%.200s: no rooms", path);
        wt_layout_free(l);
        return -1;
    }
    return 0;
}

/* The room that holds point p (feet height within its storey), or -1. */
EX_FN int wt_layout_room_at(const wt_layout *l, const float p[3])
{
    uint32_t i;
    for (i = 0; i < l->room_count; i++) {
        const wt_room *r = &l->rooms[i];
        if (p[0] >= r->lo[0] && p[0] <= r->hi[0] && p[2] >= r->lo[2] && p[2] <= r->hi[2] && p[1] >= r->lo[1] - 0.3f &&
            p[1] < r->hi[1])
            return (int)i;
    }
    return -1;
}

/* Whether a door joins rooms a and b (it lies on the boundary of both). */
static int wt__door_joins(const wt_layout *l, int a, int b)
{
    uint32_t d;
    for (d = 0; d < l->door_count; d++) {
        const wt_box *o = &l->doors[d];
        int k, both = 1, s;
        for (s = 0; s < 2; s++) {
            const wt_room *r = &l->rooms[s ? b : a];
            if (r->storey != o->storey) both = 0;
            for (k = 0; k < 3; k += 2)
                if (o->hi[k] < r->lo[k] - 0.05f || o->lo[k] > r->hi[k] + 0.05f) both = 0;
        }
        if (both) return 1;
    }
    return 0;
}

/* Rooms one door apart from `from` through rooms of its storey: hops per
   room (-1 where unreachable). */
static void wt__room_hops(const wt_layout *l, int from, int *hops)
{
    uint32_t i, j, changed = 1;
    for (i = 0; i < l->room_count; i++) hops[i] = -1;
    hops[from] = 0;
    while (changed) {
        changed = 0;
        for (i = 0; i < l->room_count; i++)
            for (j = 0; j < l->room_count; j++)
                if (hops[i] >= 0 && (hops[j] < 0 || hops[j] > hops[i] + 1) && wt__door_joins(l, (int)i, (int)j)) {
                    hops[j] = hops[i] + 1;
                    changed = 1;
                }
    }
}

/* ---- the walkable grid of one storey ------------------------------------ */
typedef struct wt__grid {
    int nx, nz;
    float x0, z0, floor;          /* corner of cell (0, 0); the storey's floor height */
    unsigned char *open;          /* 1: the bunny may stand here (eroded by the clearance) */
} wt__grid;

static float wt__cell_x(const wt__grid *g, int i) { return g->x0 + ((float)i + 0.5f) * WT__CELL; }
static float wt__cell_z(const wt__grid *g, int j) { return g->z0 + ((float)j + 0.5f) * WT__CELL; }

/* Marks the cells under the part of triangle t inside the height band
   (floor + 3 cm, floor + headroom): its clipped outline's bounding box. */
static void wt__grid_block_triangle(const wt_world *w, wt__grid *g, uint32_t t, unsigned char *blocked)
{
    float poly[2][9][3], lo[2] = { FLT_MAX, FLT_MAX }, hi[2] = { -FLT_MAX, -FLT_MAX };
    float band[2] = { g->floor + 0.03f, g->floor + WT__HEADROOM };
    int n = 3, k, side, i0, i1, j0, j1, i, j;
    for (k = 0; k < 3; k++) memcpy(poly[0][k], w->office.positions + 3 * (size_t)w->office.tri_indices[3 * t + k], 12);
    for (side = 0; side < 2 && n > 0; side++) {   /* keep y >= band[0], then y <= band[1] */
        const float (*in)[3] = (const float (*)[3])poly[side];
        float (*out)[3] = poly[1 - side];
        int m = 0, a;
        for (a = 0; a < n; a++) {
            const float *p = in[a], *q = in[(a + 1) % n];
            float dp = side ? band[1] - p[1] : p[1] - band[0], dq = side ? band[1] - q[1] : q[1] - band[0];
            if (dp >= 0.0f) memcpy(out[m++], p, 12);
            if ((dp >= 0.0f) != (dq >= 0.0f)) {
                float s = dp / (dp - dq);
                for (k = 0; k < 3; k++) out[m][k] = p[k] + s * (q[k] - p[k]);
                m++;
            }
        }
        n = m;
    }
    if (n == 0) return;
    for (k = 0; k < n; k++) {   /* after two passes the polygon is back in poly[0] */
        lo[0] = fminf(lo[0], poly[0][k][0]);
        hi[0] = fmaxf(hi[0], poly[0][k][0]);
        lo[1] = fminf(lo[1], poly[0][k][2]);
        hi[1] = fmaxf(hi[1], poly[0][k][2]);
    }
    i0 = (int)floorf((lo[0] - g->x0) / WT__CELL);
    i1 = (int)floorf((hi[0] - g->x0) / WT__CELL);
    j0 = (int)floorf((lo[1] - g->z0) / WT__CELL);
    j1 = (int)floorf((hi[1] - g->z0) / WT__CELL);
    if (i0 < 0) i0 = 0;
    if (j0 < 0) j0 = 0;
    if (i1 >= g->nx) i1 = g->nx - 1;
    if (j1 >= g->nz) j1 = g->nz - 1;
    for (j = j0; j <= j1; j++)
        for (i = i0; i <= i1; i++) blocked[(size_t)j * (size_t)g->nx + (size_t)i] = 1;
}

static void wt__grid_free(wt__grid *g)
{
    free(g->open);
    memset(g, 0, sizeof *g);
}

/* The walkable grid of the storey whose floor is at height `floor`. */
static int wt__grid_build(const wt_world *w, float floor, wt__grid *g)
{
    float lo[3], hi[3], down[3] = { 0.0f, -1.0f, 0.0f };
    int i, j, di, dj, r = (int)ceilf(WT__CLEARANCE / WT__CELL);
    uint32_t t;
    unsigned char *blocked;
    memset(g, 0, sizeof *g);
    obj_bounds(&w->office, lo, hi);
    g->x0 = lo[0];
    g->z0 = lo[2];
    g->floor = floor;
    g->nx = (int)ceilf((hi[0] - lo[0]) / WT__CELL) + 1;
    g->nz = (int)ceilf((hi[2] - lo[2]) / WT__CELL) + 1;
    if (g->nx > 8192 || g->nz > 8192) return -1;   /* a building over 400 m: not walked */
    g->open = (unsigned char *)malloc((size_t)g->nx * (size_t)g->nz);
    blocked = (unsigned char *)calloc((size_t)g->nx * (size_t)g->nz, 1);
    if (!g->open || !blocked) {
        free(blocked);
        wt__grid_free(g);
        return -1;
    }
    for (t = 0; t < w->office.tri_count; t++) wt__grid_block_triangle(w, g, t, blocked);
    for (j = 0; j < g->nz; j++)   /* no floor just under the cell: a hole, a stairwell, outside */
        for (i = 0; i < g->nx; i++) {
            float org[3] = { wt__cell_x(g, i), floor + 0.02f, wt__cell_z(g, j) };
            tr__hit h;
            size_t c = (size_t)j * (size_t)g->nx + (size_t)i;
            if (!blocked[c] && !tr__bvh_intersect(&w->tracer->bvh, org, down, 0.0f, 0.05f, &h)) blocked[c] = 1;
        }
    memset(g->open, 1, (size_t)g->nx * (size_t)g->nz);
    for (j = 0; j < g->nz; j++)   /* erode by the clearance: a disc around every blocked cell */
        for (i = 0; i < g->nx; i++) {
            if (!blocked[(size_t)j * (size_t)g->nx + (size_t)i]) continue;
            for (dj = -r; dj <= r; dj++)
                for (di = -r; di <= r; di++)
                    if (di * di + dj * dj <= r * r && i + di >= 0 && i + di < g->nx && j + dj >= 0 && j + dj < g->nz)
                        g->open[(size_t)(j + dj) * (size_t)g->nx + (size_t)(i + di)] = 0;
        }
    free(blocked);
    return 0;
}

static int wt__grid_cell(const wt__grid *g, float x, float z, int *i, int *j)
{
    *i = (int)floorf((x - g->x0) / WT__CELL);
    *j = (int)floorf((z - g->z0) / WT__CELL);
    return *i >= 0 && *i < g->nx && *j >= 0 && *j < g->nz;
}

/* The open cell nearest to (x, z) within the box [lo, hi] of the plan (a
   room), or -1. */
static long wt__grid_nearest_open(const wt__grid *g, float x, float z, const float lo[3], const float hi[3])
{
    long best = -1;
    float best_d = FLT_MAX;
    int i, j, i0, j0, i1, j1;
    wt__grid_cell(g, lo[0], lo[2], &i0, &j0);
    wt__grid_cell(g, hi[0], hi[2], &i1, &j1);
    for (j = j0 > 0 ? j0 : 0; j <= j1 && j < g->nz; j++)
        for (i = i0 > 0 ? i0 : 0; i <= i1 && i < g->nx; i++) {
            float dx = wt__cell_x(g, i) - x, dz = wt__cell_z(g, j) - z;
            if (g->open[(size_t)j * (size_t)g->nx + (size_t)i] && dx * dx + dz * dz < best_d) {
                best_d = dx * dx + dz * dz;
                best = (long)j * g->nx + i;
            }
        }
    return best;
}

/* Whether the straight segment between two cells crosses open cells only. */
static int wt__grid_visible(const wt__grid *g, long a, long b)
{
    float ax = (float)(a % g->nx), az = (float)(a / g->nx), bx = (float)(b % g->nx), bz = (float)(b / g->nx);
    int n = (int)(2.0f * fmaxf(fabsf(bx - ax), fabsf(bz - az))) + 1, s;
    for (s = 0; s <= n; s++) {
        float u = (float)s / (float)n;
        long i = (long)floorf(ax + u * (bx - ax) + 0.5f), j = (long)floorf(az + u * (bz - az) + 0.5f);
        if (!g->open[j * g->nx + i]) return 0;
    }
    return 1;
}

/* The shortest 8-connected routes over open cells from cell a (Dijkstra;
   diagonal moves cost sqrt 2 and never cut a blocked corner), then the goal:
   the reached cell of the box [lo, hi] (a room, the stairs' foot) that
   minimizes the route's length plus twice its distance to target (x, z),
   so a goal behind furniture is not reached by a detour through other
   rooms. Appends the route's corners (the cell path pulled straight where
   open cells allow) to xyz as points at the storey's floor height, from a's
   centre to the goal's; returns the goal cell, or -1 when no cell of the
   box is reached or memory runs out. */
static long wt__grid_route(const wt__grid *g, long a, const float target[2], const float lo[3], const float hi[3],
                           float **xyz, uint32_t *count)
{
    size_t n = (size_t)g->nx * (size_t)g->nz, heap_n = 0;
    float *cost = (float *)malloc(n * sizeof(float)), *key = (float *)malloc(8 * n * sizeof(float)), best = FLT_MAX;
    long *from = (long *)malloc(n * sizeof(long)), *heap = (long *)malloc(8 * n * sizeof(long)), *cells = NULL, c;
    long ncells = 0, i, anchor, goal = -1, result = -1;
    int k, i0, j0, i1, j1, ci, cj;
    size_t x;
    static const int step[8][2] = { { 1, 0 }, { -1, 0 }, { 0, 1 }, { 0, -1 }, { 1, 1 }, { 1, -1 }, { -1, 1 }, { -1, -1 } };
    if (!cost || !from || !heap || !key) goto done;
    for (x = 0; x < n; x++) {
        cost[x] = FLT_MAX;
        from[x] = -1;
    }
    cost[a] = 0.0f;
    heap[heap_n] = a;
    key[heap_n++] = 0.0f;
    while (heap_n > 0) {
        size_t p = 0;
        long cur = heap[0];
        float f = key[0];
        heap[0] = heap[--heap_n];   /* pop the least key */
        key[0] = key[heap_n];
        for (;;) {
            size_t l = 2 * p + 1, m = p;
            if (l < heap_n && key[l] < key[m]) m = l;
            if (l + 1 < heap_n && key[l + 1] < key[m]) m = l + 1;
            if (m == p) break;
            { long tc = heap[p]; float tk = key[p]; heap[p] = heap[m]; key[p] = key[m]; heap[m] = tc; key[m] = tk; }
            p = m;
        }
        if (f > cost[cur]) continue;   /* a stale entry */
        ci = (int)(cur % g->nx);
        cj = (int)(cur / g->nx);
        for (k = 0; k < 8; k++) {
            int ni = ci + step[k][0], nj = cj + step[k][1];
            long nb;
            float nc;
            if (ni < 0 || nj < 0 || ni >= g->nx || nj >= g->nz) continue;
            nb = (long)nj * g->nx + ni;
            if (!g->open[nb]) continue;
            if (k >= 4 && (!g->open[(long)cj * g->nx + ni] || !g->open[(long)nj * g->nx + ci])) continue;
            nc = cost[cur] + (k >= 4 ? 1.41421356f : 1.0f);
            if (nc >= cost[nb] || heap_n >= 8 * n) continue;
            cost[nb] = nc;
            from[nb] = cur;
            p = heap_n++;
            heap[p] = nb;
            key[p] = nc;
            while (p > 0 && key[(p - 1) / 2] > key[p]) {
                size_t q = (p - 1) / 2;
                long tc = heap[p];
                float tk = key[p];
                heap[p] = heap[q]; key[p] = key[q]; heap[q] = tc; key[q] = tk;
                p = q;
            }
        }
    }
    wt__grid_cell(g, lo[0], lo[2], &i0, &j0);
    wt__grid_cell(g, hi[0], hi[2], &i1, &j1);
    for (cj = j0 > 0 ? j0 : 0; cj <= j1 && cj < g->nz; cj++)
        for (ci = i0 > 0 ? i0 : 0; ci <= i1 && ci < g->nx; ci++) {
            long cell = (long)cj * g->nx + ci;
            float score = cost[cell] * WT__CELL + 2.0f * hypotf(wt__cell_x(g, ci) - target[0], wt__cell_z(g, cj) - target[1]);
            if (cost[cell] < FLT_MAX && score < best) {
                best = score;
                goal = cell;
            }
        }
    if (goal < 0) goto done;
    for (c = goal; c >= 0; c = c == a ? -1 : from[c]) ncells++;
    cells = (long *)malloc((size_t)ncells * sizeof(long));
    if (!cells) goto done;
    for (c = goal, i = ncells; c >= 0; c = c == a ? -1 : from[c]) cells[--i] = c;
    for (anchor = 0; anchor < ncells;) {   /* pull straight: the farthest cell still in view */
        long next = anchor + 1;
        float p[3];
        p[0] = wt__cell_x(g, (int)(cells[anchor] % g->nx));
        p[1] = g->floor;
        p[2] = wt__cell_z(g, (int)(cells[anchor] / g->nx));
        if (wt__push((void **)xyz, count, sizeof p, p) != 0) goto done;
        if (anchor == ncells - 1) break;
        while (next + 1 < ncells && wt__grid_visible(g, cells[anchor], cells[next + 1])) next++;
        anchor = next;
    }
    result = goal;
done:
    free(cost);
    free(from);
    free(heap);
    free(key);
    free(cells);
    return result;
}

/* The storey floors of the layout, lowest first (the rooms' floor heights). */
static float wt__storey_floor(const wt_layout *l, int storey)
{
    uint32_t i;
    for (i = 0; i < l->room_count; i++)
        if (l->rooms[i].storey == storey) return l->rooms[i].lo[1];
    return 0.0f;
}

/* Chooses the rooms of the route: the dark room (no lamp; the lowest
   storey's first, one the stairs reach), a lit start room a door away from
   it (or from the stair room, when the dark room is upstairs), the stair
   room. Fills goals (room indices, -2 for "climb the stairs"). */
static int wt__route_rooms(const wt_layout *l, int *goals, int *stair_index)
{
    int *hops = (int *)malloc(sizeof(int) * l->room_count), dark = -1, stair_room = -1, start = -1, n = 0;
    uint32_t i, s;
    *stair_index = -1;
    if (!hops) return -1;
    for (s = 0; s < l->stair_count && stair_room < 0; s++)
        if (l->stairs[s].storey == 0) {
            float foot[3] = { l->stairs[s].lo[0] - 0.1f, l->stairs[s].lo[1], 0.5f * (l->stairs[s].lo[2] + l->stairs[s].hi[2]) };
            stair_room = wt_layout_room_at(l, foot);
            *stair_index = (int)s;
        }
    for (i = 0; i < l->room_count && dark < 0; i++)   /* storey 0 first, then storey 1 */
        if (!l->rooms[i].lamp && l->rooms[i].storey == 0 && (int)i != stair_room) dark = (int)i;
    for (i = 0; i < l->room_count && dark < 0; i++)
        if (!l->rooms[i].lamp && l->rooms[i].storey == 1 && stair_room >= 0) dark = (int)i;
    if (dark >= 0 && l->rooms[dark].storey == 0) {
        wt__room_hops(l, dark, hops);
        for (i = 0; i < l->room_count && start < 0; i++)   /* a lit neighbour, not the stair room if it can */
            if (hops[i] == 1 && l->rooms[i].lamp && (int)i != stair_room) start = (int)i;
        if (start < 0 && stair_room >= 0 && hops[stair_room] == 1) start = stair_room;
        if (start >= 0) goals[n++] = start;
        goals[n++] = dark;
        if (stair_room >= 0) {
            const wt_box *st = &l->stairs[*stair_index];
            float top[3] = { st->hi[0] + 0.45f, st->hi[1] + 0.1f, 0.5f * (st->lo[2] + st->hi[2]) };
            int above = wt_layout_room_at(l, top);
            goals[n++] = -2;
            if (above >= 0) goals[n++] = above;   /* into the room above */
        }
    } else if (stair_room >= 0) {
        wt__room_hops(l, stair_room, hops);
        for (i = 0; i < l->room_count && start < 0; i++)
            if (hops[i] == 1 && l->rooms[i].lamp) start = (int)i;
        goals[n++] = start >= 0 ? start : stair_room;
        goals[n++] = -2;
        if (dark >= 0) goals[n++] = dark;
    }
    free(hops);
    return n >= 2 ? n : -1;
}

/* Where the feet stand at (x, z) near height guess: the highest surface
   hit by rays cast down over the bunny's footprint, within 35 cm of the
   guess (else the guess). */
static float wt__support(const wt_world *w, float x, float z, float guess)
{
    static const float probe[5][2] = { { 0, 0 }, { 0.1f, 0 }, { -0.1f, 0 }, { 0, 0.1f }, { 0, -0.1f } };
    float down[3] = { 0.0f, -1.0f, 0.0f }, best = -FLT_MAX;
    int k;
    for (k = 0; k < 5; k++) {
        float org[3] = { x + probe[k][0], guess + 0.35f, z + probe[k][1] };
        tr__hit h;
        if (tr__bvh_intersect(&w->tracer->bvh, org, down, 0.0f, 0.7f, &h) && org[1] - h.t > best) best = org[1] - h.t;
    }
    return best > -FLT_MAX ? best : guess;
}

/* Resamples the corners every WT_PATH_STEP (in plan), smooths the plan
   positions (a moving average over WT__SMOOTH each side, which cuts a
   corner by less than the clearance's margin), stands the feet on what
   supports them and sets the camera's eye height. */
/* Where the camera looks on a planned route (wt_camera): the route's
   points from the bunny to WT__LOOK_AHEAD metres past it, at
   WT__LOOK_HEIGHT above their floor. Where the route turns through a door
   those points leave the camera's sight behind the door's jamb, and a
   camera aimed at them filled the frame with the wall beside the door
   (in the house, 7 of its 262 frames before this); it aims instead at
   the route as far as it sees it, its sight, measured here from each
   point of the route by rays through the static scene to the look points
   ahead, every WT__SIGHT_STEP metres from WT__SIGHT_NEAR on, and along the
   parallel lines WT__SIGHT_MARGIN either side: the sight ends before the
   first point hidden or grazed, averaged over WT__SIGHT_SMOOTH metres of
   route each side so that the view turns smoothly where the sight jumps. */
#define WT__LOOK_AHEAD 1.0f    /* metres past the bunny the camera looks at */
#define WT__LOOK_HEIGHT 0.25f  /* above the floor */
#define WT__SIGHT_NEAR 0.3f    /* metres: nearer look points count as seen */
#define WT__SIGHT_STEP 0.05f
#define WT__SIGHT_SMOOTH 0.5f  /* metres each side: the sight's moving average along the route */
#define WT__SIGHT_MARGIN 0.2f  /* metres each side of a line of sight that must be clear too: a
                                  line grazing a jamb still shows mostly wall; less than the
                                  route's clearance from walls (WT__CLEARANCE) */

static void wt__path_at(const wt_path *p, float s, float pos[3], float *eye);

/* out[i] = the mean of v[k * stride] over k within half of i (clipped to
   0 .. count - 1). */
static void wt__window_mean(const float *v, uint32_t stride, uint32_t count, uint32_t half, float *out)
{
    uint32_t i, k;
    for (i = 0; i < count; i++) {
        uint32_t lo = i > half ? i - half : 0, hi = i + half < count ? i + half : count - 1;
        float sum = 0.0f;
        for (k = lo; k <= hi; k++) sum += v[(size_t)k * stride];
        out[i] = sum / (float)(hi - lo + 1);
    }
}

static int wt__path_sight(const wt_world *w, wt_path *p)
{
    uint32_t i, half = (uint32_t)(WT__SIGHT_SMOOTH / WT_PATH_STEP + 0.5f);
    float *raw = (float *)malloc(sizeof(float) * p->count);
    p->sight = (float *)malloc(sizeof(float) * p->count);
    if (!p->sight || !raw) {
        free(raw);
        return -1;
    }
    for (i = 0; i < p->count; i++) {
        float s = (float)i * WT_PATH_STEP, far = WT_CAMERA_TRAIL + WT__LOOK_AHEAD, ahead, org[3];
        wt__path_at(p, s, org, &org[1]);
        p->sight[i] = far;
        for (ahead = WT__SIGHT_NEAR; ahead <= far && p->sight[i] == far; ahead += WT__SIGHT_STEP) {
            float q[3], eye, side[2], flat;
            int m;
            wt__path_at(p, s + ahead, q, &eye);
            q[1] = eye - WT_EYE_HEIGHT + WT__LOOK_HEIGHT;
            flat = hypotf(q[0] - org[0], q[2] - org[2]);
            if (!(flat > 0.0f)) continue;
            side[0] = -(q[2] - org[2]) / flat * WT__SIGHT_MARGIN;
            side[1] = (q[0] - org[0]) / flat * WT__SIGHT_MARGIN;
            for (m = -1; m <= 1; m++) {
                float from[3] = { org[0] + (float)m * side[0], org[1], org[2] + (float)m * side[1] }, dir[3], len;
                tr__hit h;
                int k;
                for (k = 0; k < 3; k++) dir[k] = q[k] - org[k];
                len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
                for (k = 0; k < 3; k++) dir[k] /= len;
                if (tr__bvh_intersect(&w->tracer->bvh, from, dir, 0.0f, len, &h)) {
                    p->sight[i] = ahead - WT__SIGHT_STEP;
                    break;
                }
            }
        }
    }
    memcpy(raw, p->sight, sizeof(float) * p->count);
    wt__window_mean(raw, 1, p->count, half, p->sight);   /* the sight jumps where a corner is passed */
    free(raw);
    return 0;
}

static int wt__path_finish(const wt_world *w, wt_path *p, const float *corners, uint32_t ncorners)
{
    uint32_t i, k, half = (uint32_t)(WT__SMOOTH / WT_PATH_STEP + 0.5f), eye_half = (uint32_t)(0.8f / WT_PATH_STEP);
    float total = 0.0f, *raw;
    for (i = 1; i < ncorners; i++)
        total += hypotf(corners[3 * i] - corners[3 * i - 3], corners[3 * i + 2] - corners[3 * i - 1]);
    p->count = (uint32_t)(total / WT_PATH_STEP) + 1;
    p->length = (float)(p->count - 1) * WT_PATH_STEP;
    /* calloc: the loops below write every point before it is read, but gcc 12
       at -O3 cannot see it and warns that the eye's mean reads them unset */
    p->points = (float *)calloc((size_t)p->count * 3, sizeof(float));
    p->eye = (float *)malloc(sizeof(float) * p->count);
    raw = (float *)malloc(3 * sizeof(float) * p->count);
    if (!p->points || !p->eye || !raw) {
        free(raw);
        return -1;
    }
    {   /* walk the corners at constant speed */
        float along = 0.0f;
        uint32_t c = 1;
        for (i = 0; i < p->count; i++) {
            float target = (float)i * WT_PATH_STEP, seg = 0.0f, u;
            while (c < ncorners) {
                seg = hypotf(corners[3 * c] - corners[3 * c - 3], corners[3 * c + 2] - corners[3 * c - 1]);
                if (target <= along + seg || c + 1 == ncorners) break;
                along += seg;
                c++;
            }
            u = seg > 0.0f ? (target - along) / seg : 0.0f;
            if (u > 1.0f) u = 1.0f;
            for (k = 0; k < 3; k++) raw[3 * i + k] = corners[3 * c - 3 + k] + u * (corners[3 * c + k] - corners[3 * c - 3 + k]);
        }
    }
    for (i = 0; i < p->count; i++) {   /* the moving average, its window shrunk at the ends */
        uint32_t h = i < half ? i : half, lo, hi;
        float sum[2] = { 0, 0 };
        if (p->count - 1 - i < h) h = p->count - 1 - i;
        lo = i - h;
        hi = i + h;
        for (k = lo; k <= hi; k++) {
            sum[0] += raw[3 * k];
            sum[1] += raw[3 * k + 2];
        }
        p->points[3 * i] = sum[0] / (float)(hi - lo + 1);
        p->points[3 * i + 2] = sum[1] / (float)(hi - lo + 1);
        p->points[3 * i + 1] = wt__support(w, p->points[3 * i], p->points[3 * i + 2], raw[3 * i + 1]);
    }
    wt__window_mean(p->points + 1, 3, p->count, eye_half, p->eye);   /* the eye: the floor smoothed over 0.8 m each side */
    for (i = 0; i < p->count; i++) p->eye[i] += WT_EYE_HEIGHT;
    free(raw);
    return wt__path_sight(w, p);
}

/* Plans the walk through w's layout (see the section's comment). Returns 0,
   or -1 with a message. */
static int wt__path_plan(wt_world *w, char *err, size_t err_size)
{
    const wt_layout *l = &w->layout;
    wt_path *p = &w->path;
    int goals[6], ngoals, stair = -1, g, storey = -1;
    float *corners = NULL, here[3] = { 0, 0, 0 };
    uint32_t ncorners = 0;
    wt__grid grid;
    long from_cell = -1;
    memset(p, 0, sizeof *p);
    memset(&grid, 0, sizeof grid);
    ngoals = wt__route_rooms(l, goals, &stair);
    if (ngoals < 0) return wt__fail(err, err_size, "%.200s: nothing to walk to (no stairs, no room without a lamp)", w->layout_path);
    for (g = 0; g < ngoals; g++) {
        long to_cell;
        float target[3] = { 0.0f, 0.0f, 0.0f };
        const float *lo, *hi;
        int to_storey;
        if (goals[g] == -2) {   /* walk to the foot of the stairs, climb, step onto the landing */
            const wt_box *s = &l->stairs[stair];
            to_storey = s->storey;
            target[0] = s->lo[0] - 0.45f;
            target[2] = 0.5f * (s->lo[2] + s->hi[2]);
            lo = s->lo;
            hi = s->hi;
        } else {
            const wt_room *r = &l->rooms[goals[g]];
            if (p->room_count < WT_PATH_MAX_ROOMS) p->rooms[p->room_count++] = goals[g];
            to_storey = r->storey;
            target[0] = 0.5f * (r->lo[0] + r->hi[0]);
            target[2] = 0.5f * (r->lo[2] + r->hi[2]);
            lo = r->lo;
            hi = r->hi;
        }
        if (to_storey != storey) {
            wt__grid_free(&grid);
            storey = to_storey;
            if (wt__grid_build(w, wt__storey_floor(l, storey), &grid) != 0) goto fail_memory;
            from_cell = -1;
            if (ncorners > 0) {   /* only the stairs lead to another storey */
                snprintf(err, err_size, "%.200s: room %d is on another storey and no stairs lead there", w->layout_path, goals[g]);
                goto fail;
            }
        }
        {
            float box_lo[3], box_hi[3], xz[2] = { target[0], target[2] };
            int k;
            for (k = 0; k < 3; k++) {   /* the goal's room, or around the stairs' foot */
                box_lo[k] = goals[g] == -2 ? target[k] - 0.6f : lo[k] + 0.05f;
                box_hi[k] = goals[g] == -2 ? target[k] + 0.2f : hi[k] - 0.05f;
            }
            if (from_cell < 0) {   /* the start: the open cell nearest the target */
                float c[3];
                to_cell = wt__grid_nearest_open(&grid, target[0], target[2], box_lo, box_hi);
                if (to_cell >= 0) {
                    c[0] = wt__cell_x(&grid, (int)(to_cell % grid.nx));
                    c[1] = grid.floor;
                    c[2] = wt__cell_z(&grid, (int)(to_cell / grid.nx));
                    if (wt__push((void **)&corners, &ncorners, sizeof c, c) != 0) goto fail_memory;
                }
            } else {
                ncorners--;   /* the segment's first corner is the last one already there */
                to_cell = wt__grid_route(&grid, from_cell, xz, box_lo, box_hi, &corners, &ncorners);
            }
        }
        if (to_cell < 0) {
            snprintf(err, err_size, "%.200s: no walkable route to %s %d (storey %d)", w->layout_path,
                     goals[g] == -2 ? "the stairs of storey" : "room", goals[g] == -2 ? storey : goals[g], storey);
            goto fail;
        }
        from_cell = to_cell;
        memcpy(here, corners + 3 * (ncorners - 1), sizeof here);
        if (goals[g] == -2) {   /* the climb: the stair's centre line, onto the floor above */
            const wt_box *s = &l->stairs[stair];
            float foot[3] = { s->lo[0] - 0.45f, s->lo[1], 0.5f * (s->lo[2] + s->hi[2]) };
            float top[3] = { s->hi[0] + 0.45f, s->hi[1], foot[2] };
            if (wt__push((void **)&corners, &ncorners, sizeof foot, foot) != 0 ||
                wt__push((void **)&corners, &ncorners, sizeof top, top) != 0)
                goto fail_memory;
            memcpy(here, top, sizeof here);
            storey++;
            wt__grid_free(&grid);
            if (wt__grid_build(w, wt__storey_floor(l, storey), &grid) != 0) goto fail_memory;
            {
                float box_lo[3] = { top[0] - 0.3f, top[1], top[2] - 0.6f }, box_hi[3] = { top[0] + 1.0f, top[1], top[2] + 0.6f };
                from_cell = wt__grid_nearest_open(&grid, top[0], top[2], box_lo, box_hi);
            }
            if (from_cell < 0) {
                snprintf(err, err_size, "%.200s: no free floor at the top of the stairs", w->layout_path);
                goto fail;
            }
        }
    }
    wt__grid_free(&grid);
    if (ncorners < 2 || wt__path_finish(w, p, corners, ncorners) != 0) {
        free(corners);
        wt_path_free(p);
        return wt__fail(err, err_size, "%s", ncorners < 2 ? "the planned walk is empty" : "out of memory");
    }
    free(corners);
    p->start = p->length > 3.0f * WT_CAMERA_TRAIL ? WT_CAMERA_TRAIL : p->length / 3.0f;
    return 0;
fail_memory:
    snprintf(err, err_size, "out of memory");
fail:
    wt__grid_free(&grid);
    free(corners);
    wt_path_free(p);
    return -1;
}

/* Loads the scene files and builds what every mode shares: the ray tracer
   (office + bunny instance), the light-vector scene of the office and an
   empty static light-vector cache. Returns 0, or -1 with a message. */
static int wt__light_grid_build(wt_world *w);
EX_FN int wt_route_frames(const wt_options *o);

EX_FN int wt_world_create(const wt_options *o, wt_world **out, char *err, size_t err_size)
{
    wt_world *w = (wt_world *)calloc(1, sizeof *w);
    char mtl_path[1024], msg[512];
    lightvec_scene_desc sd;
    float grey[3] = { WT_BUNNY_KD, WT_BUNNY_KD, WT_BUNNY_KD };
    lightvec_result lr;
    *out = NULL;
    if (!w) return wt__fail(err, err_size, "%s", "out of memory");
    w->opt = *o;
    w->opt.path = NULL;
    pthread_mutex_init(&w->pose_lock, NULL);
    wt__scene_files(o, w->office_path, mtl_path, w->layout_path, sizeof mtl_path);
    snprintf(w->bunny_path, sizeof w->bunny_path, "%s/bunny.obj", o->data_dir);
    if (!wt__hash_file(w->office_path, &w->scene_hash) || !wt__hash_file(mtl_path, &w->scene_hash) ||
        (w->layout_path[0] && !wt__hash_file(w->layout_path, &w->scene_hash)) ||
        !wt__hash_file(w->bunny_path, &w->scene_hash)) {
        const char *missing = access(w->office_path, R_OK) != 0 ? w->office_path
                              : access(mtl_path, R_OK) != 0   ? mtl_path
                              : w->layout_path[0] && access(w->layout_path, R_OK) != 0 ? w->layout_path : w->bunny_path;
        snprintf(err, err_size, "cannot read %.200s: %s (run from the repository root, or pass --data DIR)", missing,
                 strerror(errno));
        wt_world_destroy(w);
        return -1;
    }
    if (obj_load(w->office_path, &w->office, msg, sizeof msg) != 0 ||
        obj_load(w->bunny_path, &w->bunny, msg, sizeof msg) != 0) {
        snprintf(err, err_size, "%s", msg);
        wt_world_destroy(w);
        return -1;
    }
    if (!obj_bounds(&w->bunny, w->bunny_lo, w->bunny_hi) || !(w->bunny_hi[1] > w->bunny_lo[1])) {
        snprintf(err, err_size, "%.200s: an empty or flat mesh", w->bunny_path);
        wt_world_destroy(w);
        return -1;
    }
    {
        float d2 = 0.0f;
        int k;
        for (k = 0; k < 3; k++) {
            w->bunny_bound_centre[k] = 0.5f * (w->bunny_lo[k] + w->bunny_hi[k]);
            d2 += (w->bunny_hi[k] - w->bunny_lo[k]) * (w->bunny_hi[k] - w->bunny_lo[k]);
        }
        w->bunny_bound_radius = 0.5f * sqrtf(d2) * WT_BUNNY_SCALE * (1.0f + 1e-5f);   /* rounding: still bounding */
    }
    w->bunny_normals = (float *)malloc(3 * sizeof(float) * w->bunny.vertex_count);
    w->material_count = w->office.material_count + 1;
    w->bunny_material = w->office.material_count;
    w->materials = (lightvec_material *)calloc(w->material_count, sizeof *w->materials);
    w->pool = o->threads == 1 ? NULL : ex_pool_create(o->threads);   /* one thread: no pool, all work here */
    w->tracer = ex_tracer_create(&w->office);
    if (!w->bunny_normals || !w->materials || (o->threads != 1 && !w->pool) || !w->tracer) {
        wt_world_destroy(w);
        return wt__fail(err, err_size, "%s", "out of memory");
    }
    obj_vertex_normals(&w->bunny, w->bunny_normals);
    if (wt__find_lights(w) != 0 || wt__light_grid_build(w) != 0) {
        wt_world_destroy(w);
        return wt__fail(err, err_size, "%s", "out of memory");
    }
    if (w->layout_path[0] &&
        (wt_layout_load(w->layout_path, &w->layout, err, err_size) != 0 || wt__path_plan(w, err, err_size) != 0)) {
        wt_world_destroy(w);
        return -1;
    }
    if (w->layout_path[0]) w->opt.path = &w->path;
    if (w->opt.frames <= 0) w->opt.frames = wt_route_frames(&w->opt);   /* before any key hashes the frames */
    if (w->layout.sky_map_path[0] && !wt__hash_file(w->layout.sky_map_path, &w->scene_hash)) {
        wt__fail(err, err_size, "cannot read %.200s", w->layout.sky_map_path);
        wt_world_destroy(w);
        return -1;
    }
    if (w->layout.has_sky && ex_tracer_set_sky(w->tracer, &w->layout.sky) != 0) {   /* checked by the reader */
        wt__fail(err, err_size, "%.200s: an invalid sky", w->layout_path);
        wt_world_destroy(w);
        return -1;
    }
    w->bunny_instance = ex_tracer_add_instance(w->tracer, &w->bunny, grey);
    wt__materials_from_obj(&w->office, w->materials);
    memcpy(w->materials[w->bunny_material].diffuse, grey, sizeof grey);
    if (o->mode == WT_MODE_RADIOSITY) {   /* a diffuse method: its full renders (--reference) are Lambertian too */
        uint32_t i;
        for (i = 0; i < w->material_count; i++) {
            memset(w->materials[i].specular, 0, sizeof w->materials[i].specular);
            w->materials[i].exponent = 0.0f;
        }
    }
    wt__scene_desc(w, &sd);
    lr = lightvec_scene_create(&sd, &w->office_scene);
    if (w->bunny_instance < 0 || lr != LIGHTVEC_OK) {
        snprintf(err, err_size, "cannot build the scene: %s", lr != LIGHTVEC_OK ? lightvec_result_string(lr) : "out of memory");
        wt_world_destroy(w);
        return -1;
    }
    memset(&w->static_gather, 0, sizeof w->static_gather);
    w->static_gather.strata_theta = (uint32_t)o->strata;
    w->static_gather.bounces = (uint32_t)o->bounces;
    if (o->mode == WT_MODE_RADIOSITY && o->bounces < WT_REFERENCE_BOUNCES)
        w->static_gather.bounces = WT_REFERENCE_BOUNCES;
    w->static_gather.light_samples = WT_GATHER_HIT_SAMPLES;
    w->static_gather.seed = o->seed * 0x9E3779B97F4A7C15ull + 0x11ull;   /* not the direct light's streams */
    w->bunny_gather = w->static_gather;
    w->bunny_gather.strata_theta = (uint32_t)o->bunny_strata;
    w->static_cache = wt__new_cache(w, 0);
    if (!w->static_cache) {
        wt_world_destroy(w);
        return wt__fail(err, err_size, "%s", "out of memory");
    }
    w->time = -1.0;
    *out = w;
    return 0;
}

/* ======================================================================
   the paths
   In the office (the built-in walk) the bunny walks from the open floor in
   front of the desk under the desk (x 1.0-2.6, z 2.9-3.7, its top at
   0.72-0.75 m), out again and along the yellow divider (x 3.6-3.65, z
   1.3-2.6): a Catmull-Rom spline through waypoints, at constant speed,
   facing where it goes. The camera moves along the front of the room at
   eye height and looks at where the bunny is about to be. In a building
   (wt_path, planned from its layout by wt_world_create) the bunny walks the
   route at constant speed from WT_CAMERA_TRAIL metres in, and the camera
   follows it along the same route, that far behind, at eye height.
   ---------------------------------------------------------------------- */
#define WT_PATH_VERSION 4u     /* bump when the paths change: precompute keys depend on them */
#define WT_SHADING_VERSION 7u  /* bump when the shading changes: cached light vectors and base images */
#define WT__WAYPOINTS 9
static const float wt__waypoints[WT__WAYPOINTS][2] = {   /* (x, z) on the floor */
    { 1.35f, 1.55f }, { 1.65f, 2.35f }, { 1.80f, 3.15f }, { 2.15f, 3.35f }, { 2.40f, 2.80f },
    { 2.95f, 2.50f }, { 3.32f, 2.05f }, { 3.36f, 1.55f }, { 3.32f, 1.15f }
};
#define WT__PATH_STEPS 32    /* spline samples per segment for the arc length */

static void wt__spline(float s, float xz[2])
{
    int n = WT__WAYPOINTS, i, k;
    float u;
    if (s <= 0.0f) s = 0.0f;
    if (s >= (float)(n - 1)) s = (float)(n - 1) - 1e-6f;
    i = (int)s;
    u = s - (float)i;
    for (k = 0; k < 2; k++) {
        float p0 = wt__waypoints[i > 0 ? i - 1 : 0][k], p1 = wt__waypoints[i][k], p2 = wt__waypoints[i + 1][k];
        float p3 = wt__waypoints[i + 2 < n ? i + 2 : n - 1][k];
        xz[k] = 0.5f * (2.0f * p1 + (p2 - p0) * u + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * u * u +
                        (3.0f * p1 - p0 - 3.0f * p2 + p3) * u * u * u);
    }
}

/* The office's walk: the floor position (x, 0, z) and heading at time t. */
static void wt__office_position(double t, float pos[3], float *heading)
{
    float len[(WT__WAYPOINTS - 1) * WT__PATH_STEPS + 1], prev[2], xz[2], target, s, a[2], b[2];
    int n = (WT__WAYPOINTS - 1) * WT__PATH_STEPS, i;
    wt__spline(0.0f, prev);
    len[0] = 0.0f;
    for (i = 1; i <= n; i++) {
        wt__spline((float)i / WT__PATH_STEPS, xz);
        len[i] = len[i - 1] + sqrtf((xz[0] - prev[0]) * (xz[0] - prev[0]) + (xz[1] - prev[1]) * (xz[1] - prev[1]));
        prev[0] = xz[0];
        prev[1] = xz[1];
    }
    target = (float)t * len[n];
    for (i = 1; i < n && len[i] < target; i++) {}
    s = ((float)(i - 1) + (len[i] > len[i - 1] ? (target - len[i - 1]) / (len[i] - len[i - 1]) : 0.0f)) / WT__PATH_STEPS;
    wt__spline(s, xz);
    pos[0] = xz[0];
    pos[1] = 0.0f;
    pos[2] = xz[1];
    wt__spline(s - 0.02f, a);
    wt__spline(s + 0.02f, b);
    if (heading) *heading = atan2f(b[0] - a[0], b[1] - a[1]);
}

/* Where arc s (metres, clamped to the route) lies between the route's
   points: after point *i, a share *u of the way to the next. */
static void wt__path_place(const wt_path *p, float s, uint32_t *i, float *u)
{
    float x = s / WT_PATH_STEP;
    if (!(x > 0.0f)) x = 0.0f;
    if (x > (float)(p->count - 1)) x = (float)(p->count - 1);
    *i = (uint32_t)x;
    if (*i + 1 >= p->count) *i = p->count > 1 ? p->count - 2 : 0;
    *u = p->count > 1 ? x - (float)*i : 0.0f;
}

/* The point of a planned route at arc s (metres, clamped to the route),
   linear between its points; and the camera's eye height there. */
static void wt__path_at(const wt_path *p, float s, float pos[3], float *eye)
{
    float u;
    uint32_t i;
    int k;
    wt__path_place(p, s, &i, &u);
    for (k = 0; k < 3; k++) pos[k] = p->points[3 * i + k] + u * (p->points[3 * (i + (p->count > 1)) + k] - p->points[3 * i + k]);
    if (eye) *eye = p->eye[i] + u * (p->eye[i + (p->count > 1)] - p->eye[i]);
}

/* The bunny's place on a planned route at time t. */
static float wt__path_arc(const wt_path *p, double t) { return p->start + (float)t * (p->length - p->start); }

/* The camera's sight (wt__path_sight) standing at arc s, linear between
   the route's points. */
static float wt__path_sight_at(const wt_path *p, float s)
{
    float u;
    uint32_t i;
    wt__path_place(p, s, &i, &u);
    return p->sight[i] + u * (p->sight[i + (p->count > 1)] - p->sight[i]);
}

/* The bunny's feet (x, y, z) and heading (radians about +y, 0 = facing +z)
   at time t in [0, 1]: on o->path when it is set, else on the office's walk. */
EX_FN void wt_bunny_position(const wt_options *o, double t, float pos[3], float *heading)
{
    if (t < 0.0) t = 0.0;
    if (t > 1.0) t = 1.0;
    if (o && o->path) {
        float s = wt__path_arc(o->path, t), a[3], b[3];
        wt__path_at(o->path, s, pos, NULL);
        wt__path_at(o->path, s - 0.2f, a, NULL);
        wt__path_at(o->path, s + 0.2f, b, NULL);
        if (heading) *heading = atan2f(b[0] - a[0], b[2] - a[2]);
        return;
    }
    wt__office_position(t, pos, heading);
}

/* The heading of the nose of bunny.obj in its own coordinates: -x. */
#define WT_BUNNY_NOSE_HEADING (-0.5f * WT_PI)

/* Object-to-world transform of the bunny at time t (3x4 row-major): OBJ
   coordinates centred, feet on the floor, scaled by WT_BUNNY_SCALE, turned
   to its heading, moved to its position. */
EX_FN void wt_bunny_transform(const wt_world *w, double t, float m[12])
{
    float p[3], heading, yaw, c, s, k = WT_BUNNY_SCALE;
    float cx = 0.5f * (w->bunny_lo[0] + w->bunny_hi[0]), cz = 0.5f * (w->bunny_lo[2] + w->bunny_hi[2]);
    wt_bunny_position(&w->opt, t, p, &heading);
    yaw = heading - WT_BUNNY_NOSE_HEADING;
    c = cosf(yaw);
    s = sinf(yaw);
    /* world = R_y(yaw) k (q - (cx, lo_y, cz)) + p, R_y maps +z to (sin, 0, cos) */
    m[0] = k * c;  m[1] = 0.0f; m[2] = k * s;  m[3] = p[0] - k * (c * cx + s * cz);
    m[4] = 0.0f;   m[5] = k;    m[6] = 0.0f;   m[7] = p[1] - k * w->bunny_lo[1];
    m[8] = -k * s; m[9] = 0.0f; m[10] = k * c; m[11] = p[2] - k * (-s * cx + c * cz);
}

EX_FN double wt_frame_time(const wt_options *o, int frame)
{
    return o->frames > 1 ? (double)frame / (double)(o->frames - 1) : 0.0;
}

/* The camera at time t. In the office: eye height 1.35 m along the front
   wall (a line: a one-dimensional view space for the base views), looking
   at the bunny's path a little ahead and behind (smoothed). On a planned
   route: WT_CAMERA_TRAIL metres behind the bunny on its route, at eye
   height, looking at the bunny's back a little ahead (smoothed). */
EX_FN rendercache_camera wt_camera(const wt_options *o, double t, uint32_t width, uint32_t height)
{
    rendercache_camera c;
    float s = (float)(t * t * (3.0 - 2.0 * t)), look[3] = { 0, 0, 0 };
    int j;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_PERSPECTIVE;
    if (o && o->path) {
        const wt_path *p = o->path;
        float arc = wt__path_arc(p, t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t), seen[3] = { 0, 0, 0 }, to[2], d, ds;
        float sight = wt__path_sight_at(p, arc - WT_CAMERA_TRAIL) + arc - WT_CAMERA_TRAIL;
        wt__path_at(p, arc - WT_CAMERA_TRAIL, c.eye, &c.eye[1]);
        for (j = -2; j <= 2; j++) {   /* the bunny and 1 m ahead, at the floor smoothed over the stairs'
                                          treads: the feet's height rises a tread at a time and would
                                          jerk the view up by 2-4 degrees at each one */
            float q[3], eye, at = arc + 0.25f * WT__LOOK_AHEAD * (float)(j + 2);
            wt__path_at(p, at, q, &eye);
            look[0] += 0.2f * q[0];
            look[1] += 0.2f * (eye - WT_EYE_HEIGHT);
            look[2] += 0.2f * q[2];
            wt__path_at(p, at < sight ? at : sight, q, NULL);   /* the same, as far as the camera sees */
            seen[0] += 0.2f * q[0];
            seen[2] += 0.2f * q[2];
        }
        /* aimed at the route it sees, at the pitch of the bunny's look points */
        to[0] = seen[0] - c.eye[0];
        to[1] = seen[2] - c.eye[2];
        d = hypotf(look[0] - c.eye[0], look[2] - c.eye[2]);
        ds = hypotf(to[0], to[1]);
        c.look_at[0] = ds > 0.0f ? c.eye[0] + to[0] * (d / ds) : look[0];
        c.look_at[1] = look[1] + WT__LOOK_HEIGHT;
        c.look_at[2] = ds > 0.0f ? c.eye[2] + to[1] * (d / ds) : look[2];
    } else {
        c.eye[0] = 1.10f + 1.30f * s;
        c.eye[1] = 1.35f;
        c.eye[2] = 0.30f;
        for (j = -2; j <= 2; j++) {
            float p[3];
            wt_bunny_position(o, t + 0.04 * j, p, NULL);
            look[0] += 0.2f * p[0];
            look[2] += 0.2f * p[2];
        }
        c.look_at[0] = look[0];
        c.look_at[1] = 0.60f;
        c.look_at[2] = look[2];
    }
    c.up[1] = 1.0f;
    c.vfov_degrees = WT_CAMERA_VFOV;
    c.width = width;
    c.height = height;
    return c;
}

/* The default frame count follows the camera's route (wt_options.frames
   = 0): enough frames that the camera moves WT_FRAME_STEP metres and turns
   WT_FRAME_TURN degrees a frame on average over the walk, and never fewer
   than WT_MIN_FRAMES (the office's walk of 1.3 m and 51 degrees keeps its
   48 frames). A render cache that resamples 8 % of the pixels a frame can
   only reuse what the last frames saw: the building's walk in 48 frames
   moved 0.42 m a frame and left about 84 % of each frame to holes. Frames
   are evenly spaced in t, so where the camera is faster than its average
   (the office's eye eases in and out) a frame's step is larger than the
   mean, by up to 1.5 times in the office. */
#define WT_FRAME_STEP 0.1f        /* metres of eye movement per frame */
#define WT_FRAME_TURN 1.5f        /* degrees of view direction per frame */
#define WT_MIN_FRAMES 48
#define WT__ROUTE_SAMPLES 2048    /* intervals of t at which the camera is sampled */

/* What the camera does over the walk: the eye's path length and the view
   direction's total turn, summed over WT__ROUTE_SAMPLES steps of t. */
typedef struct wt_route {
    double length;   /* metres */
    double turn;     /* degrees */
} wt_route;

EX_FN wt_route wt_route_measure(const wt_options *o)
{
    wt_route r = { 0.0, 0.0 };
    float prev_eye[3] = { 0, 0, 0 }, prev_dir[3] = { 0, 0, 0 };
    int i, k;
    for (i = 0; i <= WT__ROUTE_SAMPLES; i++) {
        rendercache_camera c = wt_camera(o, (double)i / WT__ROUTE_SAMPLES, 8, 8);
        float dir[3], len;
        for (k = 0; k < 3; k++) dir[k] = c.look_at[k] - c.eye[k];
        len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        for (k = 0; k < 3; k++) dir[k] = len > 0.0f ? dir[k] / len : 0.0f;
        if (i > 0) {
            double d2 = 0.0, cosine = 0.0;
            for (k = 0; k < 3; k++) {
                d2 += (double)(c.eye[k] - prev_eye[k]) * (double)(c.eye[k] - prev_eye[k]);
                cosine += (double)dir[k] * (double)prev_dir[k];
            }
            r.length += sqrt(d2);
            r.turn += acos(cosine > 1.0 ? 1.0 : cosine < -1.0 ? -1.0 : cosine) * (180.0 / EX_PI);
        }
        memcpy(prev_eye, c.eye, sizeof prev_eye);
        memcpy(prev_dir, dir, sizeof prev_dir);
    }
    return r;
}

/* The default frame count of o's walk (o->path set as wt_world_create sets
   it in the world's options). */
EX_FN int wt_route_frames(const wt_options *o)
{
    wt_route r = wt_route_measure(o);
    double steps = ceil(fmax(r.length / WT_FRAME_STEP, r.turn / WT_FRAME_TURN));
    return steps + 1.0 > (double)WT_MIN_FRAMES ? (int)steps + 1 : WT_MIN_FRAMES;
}

/* The same camera for the software rasterizer. */
EX_FN ex_camera wt_ex_camera(const rendercache_camera *c)
{
    return ex_camera_look_at(c->eye, c->look_at, c->up, c->vfov_degrees, (int)c->width, (int)c->height);
}

/* Moves the bunny to time t: the tracer's instance now, the light-vector
   scene with the posed bunny and its empty cache when first needed. */
EX_FN void wt_set_time(wt_world *w, double t)
{
    float m[12];
    if (t == w->time) return;
    wt_bunny_transform(w, t, m);
    ex_tracer_set_transform(w->tracer, w->bunny_instance, m);
    memcpy(w->pose, m, sizeof m);
    w->time = t;
    pthread_mutex_lock(&w->pose_lock);
    w->pose_ready = 0;
    pthread_mutex_unlock(&w->pose_lock);
}

/* Builds the posed light-vector scene and a fresh bunny cache (the bunny's
   light vectors are valid at one pose only). Thread-safe. */
static int wt__ensure_pose(wt_world *w)
{
    int ok = 1;
    pthread_mutex_lock(&w->pose_lock);
    if (!w->pose_ready) {
        uint32_t nv = w->office.vertex_count + w->bunny.vertex_count, nt = w->office.tri_count + w->bunny.tri_count, i;
        lightvec_scene_desc sd;
        lightvec_scene_destroy(w->posed_scene);
        lightvec_cache_destroy(w->bunny_cache);
        w->posed_scene = NULL;
        w->bunny_cache = NULL;
        if (!w->posed_positions) {
            w->posed_positions = (float *)malloc(3 * sizeof(float) * nv);
            w->posed_indices = (uint32_t *)malloc(3 * sizeof(uint32_t) * nt);
            w->posed_materials = (uint32_t *)malloc(sizeof(uint32_t) * nt);
            if (w->posed_indices && w->posed_materials) {
                memcpy(w->posed_indices, w->office.tri_indices, 3 * sizeof(uint32_t) * w->office.tri_count);
                memcpy(w->posed_materials, w->office.tri_material, sizeof(uint32_t) * w->office.tri_count);
                for (i = 0; i < 3 * w->bunny.tri_count; i++)
                    w->posed_indices[3 * w->office.tri_count + i] = w->bunny.tri_indices[i] + w->office.vertex_count;
                for (i = 0; i < w->bunny.tri_count; i++) w->posed_materials[w->office.tri_count + i] = w->bunny_material;
            }
        }
        ok = w->posed_positions && w->posed_indices && w->posed_materials;
        if (ok) {
            memcpy(w->posed_positions, w->office.positions, 3 * sizeof(float) * w->office.vertex_count);
            for (i = 0; i < w->bunny.vertex_count; i++)
                ex__affine_point(w->pose, w->bunny.positions + 3 * (size_t)i,
                                 w->posed_positions + 3 * ((size_t)w->office.vertex_count + i));
            wt__scene_desc(w, &sd);
            sd.positions = w->posed_positions;
            sd.vertex_count = nv;
            sd.indices = w->posed_indices;
            sd.triangle_count = nt;
            sd.material_ids = w->posed_materials;
            ok = lightvec_scene_create(&sd, &w->posed_scene) == LIGHTVEC_OK;
            w->bunny_cache = ok ? wt__new_cache(w, 1) : NULL;
            ok = ok && w->bunny_cache;
        }
        w->pose_ready = ok;
    }
    pthread_mutex_unlock(&w->pose_lock);
    return ok ? 0 : -1;
}

/* ======================================================================
   shading: a primary hit gets emission + direct light (trace.h, area
   samples with shadow rays, Lambert + Phong) + indirect light from a light
   vector (lightvec.h). Light vectors are looked up in rounds so that the
   result does not depend on the thread count: every round looks up all
   points still dark (in parallel, the cache read-only), picks one point per
   cell of a grid among the misses (cells shrink round by round), gathers
   the picks' light vectors (in parallel) and inserts them in a fixed order.
   The last round gathers every point still missing. The bunny's light
   vectors come from a cache of their own, made anew at every pose.
   ---------------------------------------------------------------------- */
#define WT__ROUNDS 5
#define WT__CELL_STATIC 0.35f     /* metres: pick cells of the first round */
#define WT__CELL_BUNNY 0.08f
#define WT__CELL_SHRINK 0.7f
#define WT__BATCH 64              /* points per parallel job */
/* Picks per gather job: a gather costs about a millisecond, and a round
   often picks fewer than two batches of WT__BATCH, which left the second
   thread idle. */
#define WT__GATHER_BATCH 2

/* Smooth normal of a bunny hit, in world space. */
static void wt__bunny_normal(const wt_world *w, const ex_trace_hit *h, float n[3])
{
    const uint32_t *v = w->bunny.tri_indices + 3 * (size_t)h->tri;
    float o = 1.0f - h->u - h->v, no[3], l;
    int k;
    for (k = 0; k < 3; k++)
        no[k] = o * w->bunny_normals[3 * v[0] + k] + h->u * w->bunny_normals[3 * v[1] + k] +
                h->v * w->bunny_normals[3 * v[2] + k];
    ex__affine_vector(w->pose, no, n);   /* a similarity: normals map like vectors */
    l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (k = 0; k < 3; k++) n[k] = l > 0.0f ? n[k] / l : h->normal[k];
}

/* Shadow ray test through the tracer: 1 when something opaque blocks the
   ray (*by_bunny set when the bunny does; it blocks only when
   bunny_casts), else 0 with through = the transmittance of the glass it
   crosses (ex_tracer_transmittance_static: the bunny was tested first; 1
   without glass in the scene). */
static int wt__occluded(const wt_world *w, const float org[3], const float dir[3], float tmax, int bunny_casts,
                        float through[3], int *by_bunny)
{
    const ex_tracer *t = w->tracer;
    const ex__instance *b = &t->instances[w->bunny_instance];
    float o[3], d[3];
    through[0] = through[1] = through[2] = 1.0f;
    if (!t->has_glass && tr__bvh_occluded(&t->bvh, org, dir, 0.0f, tmax)) return 1;
    ex__affine_point(b->to_object, org, o);
    ex__affine_vector(b->to_object, dir, d);
    if (bunny_casts && tr__bvh_occluded(&b->bvh, o, d, 0.0f, tmax)) {
        *by_bunny = 1;
        return 1;
    }
    return t->has_glass && !ex_tracer_transmittance_static(t, org, dir, tmax, through);
}

/* The many-light sampler's importance of light L at a point x with normal
   n: an upper bound of what L can send there, power * cos_x * cos_y /
   d^2 with both cosines bounded over L's bounding sphere (centre c, radius
   r, seen from x under the half angle a, sin a = r / d: the cosine of the
   angle to the normal less a, 1 when that is below zero; Conty Estevez &
   Kulla 2018, eq. 3 for one light) and d^2 no less than r^2. It is 0 only
   where L sends nothing: x behind L's plane (one-sided emitters) or all of
   the sphere below x's horizon; elsewhere it is positive, so the estimator
   that divides by the selection probability is unbiased. */
static float wt__cos_bound(float cos_t, float cos_a, float sin_a)
{
    float sin_t;
    if (cos_t >= cos_a) return 1.0f;             /* the normal points into the sphere's cone */
    sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    return cos_t * cos_a + sin_t * sin_a;        /* cos(theta - a) */
}

static float wt__light_importance(const wt_light *L, const float x[3], const float n[3])
{
    float v[3] = { L->centre[0] - x[0], L->centre[1] - x[1], L->centre[2] - x[2] };
    float d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2], r2 = L->radius * L->radius, d, sin_a, cos_a, cx, cy;
    float front = (x[0] - L->point[0]) * L->normal[0] + (x[1] - L->point[1]) * L->normal[1] +
                  (x[2] - L->point[2]) * L->normal[2];
    if (front <= 0.0f) return 0.0f;              /* behind the emitter: one-sided */
    if (d2 <= r2) return L->power / r2;           /* inside the sphere: both cosines bounded by 1 */
    d = sqrtf(d2);
    sin_a = L->radius / d;
    cos_a = sqrtf(1.0f - sin_a * sin_a);
    cx = wt__cos_bound((v[0] * n[0] + v[1] * n[1] + v[2] * n[2]) / d, cos_a, sin_a);
    if (cx <= 0.0f) return 0.0f;                 /* the whole sphere below the horizon */
    cy = wt__cos_bound(-(v[0] * L->normal[0] + v[1] * L->normal[1] + v[2] * L->normal[2]) / d, cos_a, sin_a);
    return cy > 0.0f ? L->power * cx * cy / d2 : 0.0f;
}

/* ---- the lights a region sees --------------------------------------------
   In a building most lights are behind walls from any one point, and the
   importance above (power, distance, cosines) cannot know it: at 8 shadow
   rays most would end on a wall. As production renderers do for many
   lights (light lists per region of space: Ward 1994, "Adaptive Shadow
   Testing for Ray Tracing"; a visibility cache: Georgiev et al. 2012,
   "Importance Caching for Complex Illumination"), a coarse grid over the
   scene keeps, for each cell, the lights that can reach it: those that
   one of WT__GRID_RAYS rays between points of the cell and points of the
   light reaches past everything static (glass passes light; the bunny
   moves, so it is left out), in the cell or in one of its 26 neighbours
   (a point near a cell's side sees what the next cell sees): its
   neighbourhood flag; and those a ray of the cell itself reaches: its cell
   flag. The sampler picks a light from a defensive mixture (Hesterberg
   1995, "Weighted Average Importance Sampling and Defensive Mixture
   Distributions"; Veach's one-sample model, 1997, sec. 9.2.4): with
   probability WT__GRID_NEAR_SHARE by importance x neighbourhood flag,
   with WT__GRID_CELL_SHARE by importance x cell flag, and with what
   remains by importance alone, and divides by the mixture's probability:
   every light the importance allows keeps picks (a slit of a door, a
   point the rays did not come near), so the estimator stays unbiased
   everywhere, and the grid only moves shadow rays from lights behind
   walls to lights in view. Measured at 8 rays on building_4k (82 lights;
   17 x 7 x 14 cells, 13 lights a cell on average, built in 0.20 s of one
   thread, as before the cell flag): the direct light's relative RMS
   noise 0.448 -> 0.155, 0.092 -> 0.069, 0.129 -> 0.103 (test_light_grid,
   before the mixture). The neighbourhood flag alone, with 1/16 of the
   importance for the lights it lacks in place of the other two terms,
   left fireflies where the building is dark (the first rooms' floors in
   docs/walkthrough_building_raytrace_sheet.png): a cell's neighbours hold
   the lamps of the room behind the wall, and 1/16 of each of the 14 lamps
   of the storey above still took half the picks in a room without a lamp,
   whose light came through a door from lamps 8 m away with a few per cent
   of the picks. Measured with 8 shadow rays against 256
   (wt_render_converged, 160x120, the same 2 x 2 gather in both, so the
   difference is the direct light's noise; LRMS of the displayed frames),
   that sampler -> this mixture: building_4k frames 15, 23, 31, 120, 190,
   203, 215: 0.162, 0.569, 0.576, 0.060, 0.071, 0.080, 0.060 -> 0.102,
   0.228, 0.228, 0.055, 0.077, 0.082, 0.068 (pooled 0.316 -> 0.139);
   building_1k frames 15, 31, 120, 200: pooled 0.046 -> 0.047; the office
   (6 lights flagged in every cell) 0.0556 -> 0.0557. Tried and left: the
   cell's share of 32 rays that arrive in place of its flag (0.233 and
   0.229 in the dark rooms, but 0.089, 0.119, 0.082 upstairs and the
   office 0.057: a cell's volume, half inside walls and stairs, misjudges
   what its surfaces see); the neighbourhood flag with the importance-alone
   term, no cell flag (0.52 in the dark rooms).
   What the frames' shadow rays learn (importance caching, Georgiev et al.
   2012, as production many-light renderers learn visibility): the grid's
   few rays miss slits. A floor of building_4k's room without a lamp sees
   room 1's lamp only through two doors; its cell flags none of the lights,
   so the two lamps that reach it got 10 % of the picks and the rest went
   to lamps behind walls (one point in seven got a ray through: the
   walk's speckles). The raytrace frames' own shadow rays know better:
   wt__direct counts, per key and light, the rays it tried and those that
   arrived (in front of the point, nothing opaque between; a key is a
   cell and the main axis and sign of the point's normal, since a wall or
   a floor inside a cell parts surfaces that face away from each other:
   a storey's floor, the ceiling below it), and wt__light_learn_merge adds
   them to the earlier frames' counts once the frame's trace is done.
   Integer sums by atomic adds: the same in any order, so the frames stay
   bit-identical on any thread count. Both flagged terms then weigh a
   light by the square root of the share of its rays from the key that
   arrived, the flag counting as WT__LEARN_PRIOR rays
   (wt__light_flag_weight): exactly the flags while a key has no rays, so
   a first frame is unchanged, and a light the grid missed gains picks
   once rays of the importance-alone term reach it. The root because the
   share is the key's average: where part of a cell sees a lamp and part
   does not, the share itself took picks from the points that see it.
   Measured (the direct light's relative RMS noise at 8 rays over 64 x 48
   hits of a frame's view, 32 estimates each, counts recorded at 40 x 30
   hits of every earlier frame of the walk; flags -> root of the share,
   [the share itself, 1 once a ray arrived]): house frames 29, 59, 119,
   269: 0.062, 0.074, 0.058, 0.111 -> 0.062, 0.069, 0.055, 0.089 [0.065,
   0.068, 0.055, 0.104; 0.062, 0.072, 0.055, 0.089]; building_4k frames
   15, 36, 60, 72: 0.120, 0.075, 0.073, 0.069 -> 0.115, 0.068, 0.069,
   0.069 [0.115, 0.069, 0.076, 0.078; 0.115, 0.071, 0.069, 0.091]; the
   office (every light flagged everywhere) frames 7, 23: 0.073, 0.045 ->
   0.075, 0.046. At the floor point above: the two lamps that reach it
   get 70 % of the picks after 4,096 recorded rays, and its noise falls
   from 2.49 to 0.77 (test_light_learning). The walks against converged
   renders (320x240, the frames' LRMS, their noise taken out), flags ->
   learned: the house's frames 29-269 every 30 0.111, 0.078, 0.040,
   0.071, 0.060, 0.072, 0.076, 0.072, 0.154 -> 0.106, 0.077, 0.037,
   0.070, 0.060, 0.079, 0.078, 0.072, 0.125 (mean 0.0816 -> 0.0779; the
   room without a lamp 0.154 -> 0.125); the office's 48 frames, mean
   0.0593 -> 0.0596. No cost measured (office raytrace 640x480, one
   thread: 188.5 -> 189.0 ms a frame, medians of 3). Unbiased: a frame's picks read only counts merged
   before it (frozen while it is traced), never the point's own rays (a
   sampler that chose its rays from the point's own samples, as an
   adaptive penumbra test does, would be biased), and the importance-alone
   term still gives every light of non-zero importance its share, so the
   estimate divided by the mixture's probability is exact for any counts.
   Only the raytrace frames record; they and their full renders
   (wt_render_full) use the counts. Converged renders, base images (cached
   on disk) and the warp's fills keep the flags alone: they never depend
   on what was walked before. Memory: 12 bytes a key and light, 6 keys a
   cell (1 when that passes WT__LEARN_MAX_ENTRIES, then no learning):
   building_4k's 17 x 7 x 14 cells x 6 x 82 lights, 9.8 MB. The counts
   halve past WT__LEARN_MAX_TRIED rays, a window of about 40 frames: a
   light the bunny hid comes back. */
#define WT__GRID_CELL 1.0f            /* metres: a cell's edge at most, a room's corner */
#define WT__GRID_MAX_CELLS 8192u      /* larger scenes get larger cells */
#define WT__GRID_RAYS 16              /* rays per cell and light, until one arrives */
#define WT__GRID_NEAR_SHARE 0.45f     /* of the picks: importance x neighbourhood flag */
#define WT__GRID_CELL_SHARE 0.45f     /* of the picks: importance x cell flag; 0.1 left for importance alone */
#define WT__GRID_STREAM 0x6C16E7ull   /* the grid's random numbers: not the frames' */
#define WT__LEARN_PRIOR 4.0f          /* rays: the cell flag's weight in a key's arrived share */
#define WT__LEARN_MAX_TRIED 4096u     /* rays a key and light: both counts halve above (a window of ~40 frames) */
#define WT__LEARN_MAX_ENTRIES (1u << 22)   /* keys x lights: 6 keys a cell, else 1, else no learning */
#define WT__LEARN_USE 1               /* wt__direct's picks use the counts of the frames merged so far */
#define WT__LEARN_RECORD 2            /* wt__direct adds its shadow rays to the frame's counts */

/* A point y of light L chosen uniformly from u1 (by area over its fan
   triangles, then the square root of what remains: uniform on the
   triangle) and u2. */
static void wt__light_point(const wt_world *w, const wt_light *L, float u1, float u2, float y[3])
{
    const ex_tracer *t = w->tracer;
    const float *pos = w->office.positions, *a, *b, *c;
    const uint32_t *v;
    float su;
    uint32_t i = 0;
    int k;
    u1 *= L->area;
    while (i + 1 < L->tri_count && u1 >= t->tri_area[L->first_tri + i]) u1 -= t->tri_area[L->first_tri + i++];
    v = w->office.tri_indices + 3 * (size_t)(L->first_tri + i);
    a = pos + 3 * (size_t)v[0];
    b = pos + 3 * (size_t)v[1];
    c = pos + 3 * (size_t)v[2];
    su = sqrtf(fminf(u1 / t->tri_area[L->first_tri + i], 1.0f));   /* uniform on the triangle */
    for (k = 0; k < 3; k++) y[k] = (1.0f - su) * a[k] + su * (1.0f - u2) * b[k] + su * u2 * c[k];
}

/* Whether nothing static blocks the segment from x to y (glass passes). */
static int wt__static_visible(const wt_world *w, const float x[3], const float y[3])
{
    const ex_tracer *t = w->tracer;
    float wi[3] = { y[0] - x[0], y[1] - x[1], y[2] - x[2] }, d, through[3];
    int k;
    d = sqrtf(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
    if (!(d > 2.0f * t->epsilon)) return 1;
    for (k = 0; k < 3; k++) wi[k] /= d;
    if (!t->has_glass) return !tr__bvh_occluded(&t->bvh, x, wi, 0.0f, d * (1.0f - 1e-4f) - t->epsilon);
    return ex_tracer_transmittance_static(t, x, wi, d * (1.0f - 1e-4f) - t->epsilon, through);
}

/* Whether one of light L's rays from the cell with corner lo arrives:
   cell points uniform in the cell, light points stratified over L's area.
   A cell wholly behind L (one-sided) is never lit by it: no rays. */
static int wt__cell_sees(const wt_world *w, const wt_light *L, const float lo[3], ex_rng *r)
{
    float cell = w->grid_cell, x[3], y[3];
    int corner, k, i;
    for (corner = 0; corner < 8; corner++) {
        float front = 0.0f;
        for (k = 0; k < 3; k++) front += (lo[k] + (float)((corner >> k) & 1) * cell - L->point[k]) * L->normal[k];
        if (front > 0.0f) break;
    }
    if (corner == 8) return 0;
    for (i = 0; i < WT__GRID_RAYS; i++) {
        float front = 0.0f, u1 = fminf(((float)i + ex_rng_float(r)) / (float)WT__GRID_RAYS, 0.99999994f);
        float u2 = ex_rng_float(r);
        for (k = 0; k < 3; k++) x[k] = lo[k] + ex_rng_float(r) * cell;
        for (k = 0; k < 3; k++) front += (x[k] - L->point[k]) * L->normal[k];
        if (front <= 0.0f) continue;
        wt__light_point(w, L, u1, u2, y);
        if (wt__static_visible(w, x, y)) return 1;
    }
    return 0;
}

static void wt__grid_cell_coords(const wt_world *w, uint32_t c, int i[3])
{
    i[0] = (int)(c % w->grid_dims[0]);
    i[1] = (int)(c / w->grid_dims[0] % w->grid_dims[1]);
    i[2] = (int)(c / w->grid_dims[0] / w->grid_dims[1]);
}

typedef struct wt__grid_job {
    wt_world *w;
    unsigned char *sees;   /* cell-major, light_count a cell: wt__cell_sees */
} wt__grid_job;

static void wt__grid_cell_job(void *ctx, uint32_t c)
{
    const wt__grid_job *j = (const wt__grid_job *)ctx;
    const wt_world *w = j->w;
    ex_rng r = ex_rng_stream(WT__GRID_STREAM, c);   /* one stream per cell: the same for any thread count */
    float lo[3];
    uint32_t e;
    int i[3], k;
    wt__grid_cell_coords(w, c, i);
    for (k = 0; k < 3; k++) lo[k] = w->grid_lo[k] + (float)i[k] * w->grid_cell;
    for (e = 0; e < w->light_count; e++) j->sees[(size_t)c * w->light_count + e] = (unsigned char)wt__cell_sees(w, &w->lights[e], lo, &r);
}

/* A cell's two flags per light: 1 when a ray of the cell or of a
   neighbour reached it (neighbourhood), 1 when a ray of the cell did
   (cell); 0 otherwise. */
static void wt__grid_cell_weights(const wt_world *w, const unsigned char *sees, uint32_t c)
{
    float *out = w->light_seen + (size_t)c * 2u * w->light_count;
    uint32_t e;
    int i[3], a, b, d;
    wt__grid_cell_coords(w, c, i);
    for (e = 0; e < w->light_count; e++) {
        out[2 * e] = 0.0f;
        out[2 * e + 1] = (float)sees[(size_t)c * w->light_count + e];   /* 0 or 1 */
    }
    for (a = i[2] - 1; a <= i[2] + 1; a++)
        for (b = i[1] - 1; b <= i[1] + 1; b++)
            for (d = i[0] - 1; d <= i[0] + 1; d++) {
                const unsigned char *n;
                if (a < 0 || b < 0 || d < 0 || a >= (int)w->grid_dims[2] || b >= (int)w->grid_dims[1] || d >= (int)w->grid_dims[0])
                    continue;
                n = sees + ((size_t)a * w->grid_dims[1] * w->grid_dims[0] + (size_t)b * w->grid_dims[0] + (size_t)d) * w->light_count;
                for (e = 0; e < w->light_count; e++)
                    if (n[e]) out[2 * e] = 1.0f;
            }
}

/* Builds the grid over the static scene's bounds (cells of WT__GRID_CELL,
   grown until there are at most WT__GRID_MAX_CELLS). One light or none:
   no grid (the weights would cancel). 0, or -1 when out of memory. */
static int wt__light_learn_init(wt_world *w);
static int wt__light_grid_build(wt_world *w)
{
    wt__grid_job j;
    float lo[3], hi[3], ext[3];
    uint32_t cells, c;
    int k;
    if (w->light_count < 2 || !obj_bounds(&w->office, lo, hi)) return 0;
    for (k = 0; k < 3; k++) {
        ext[k] = fmaxf(hi[k] - lo[k], 1e-3f);
        if (!isfinite(ext[k])) return 0;   /* no grid covers it: importance alone */
    }
    w->grid_cell = WT__GRID_CELL;
    for (;;) {   /* counted in floats: a huge scene's first counts overflow no integer */
        float n[3];
        for (k = 0; k < 3; k++) n[k] = ceilf(ext[k] / w->grid_cell);
        if (n[0] * n[1] * n[2] <= (float)WT__GRID_MAX_CELLS) {
            for (k = 0; k < 3; k++) w->grid_dims[k] = (uint32_t)n[k];
            break;
        }
        w->grid_cell *= 1.25f;
    }
    cells = w->grid_dims[0] * w->grid_dims[1] * w->grid_dims[2];
    memcpy(w->grid_lo, lo, sizeof lo);
    j.w = w;
    j.sees = (unsigned char *)malloc((size_t)cells * w->light_count);
    w->light_seen = (float *)malloc(sizeof(float) * 2u * cells * (size_t)w->light_count);
    if (!j.sees || !w->light_seen) {
        free(j.sees);
        return -1;
    }
    ex_pool_parallel_for(w->pool, wt__grid_cell_job, &j, cells);
    for (c = 0; c < cells; c++) wt__grid_cell_weights(w, j.sees, c);
    free(j.sees);
    return wt__light_learn_init(w);
}

/* The grid's cell holding x, or the nearest. */
static size_t wt__grid_cell_of(const wt_world *w, const float x[3])
{
    size_t c = 0;
    int k;
    for (k = 2; k >= 0; k--) {
        float f = (x[k] - w->grid_lo[k]) / w->grid_cell;
        uint32_t i = f > 0.0f ? (uint32_t)fminf(f, (float)(w->grid_dims[k] - 1)) : 0u;
        c = c * w->grid_dims[k] + i;
    }
    return c;
}

/* The weights of the lights for a point at x (the grid's cell holding it,
   or the nearest), or NULL without a grid. */
static const float *wt__lights_seen(const wt_world *w, const float x[3])
{
    if (!w->light_seen) return NULL;
    return w->light_seen + wt__grid_cell_of(w, x) * 2u * w->light_count;
}

/* The key of the learned counts (the grid's comment) at x with normal n:
   x's cell, and with 6 keys a cell the main axis of n and its sign. */
static size_t wt__learn_key(const wt_world *w, const float x[3], const float n[3])
{
    size_t c = wt__grid_cell_of(w, x);
    int k, axis = 0;
    if (w->learn_sides == 1) return c;
    for (k = 1; k < 3; k++)
        if (fabsf(n[k]) > fabsf(n[axis])) axis = k;
    return c * 6u + (size_t)(2 * axis + (n[axis] < 0.0f));
}

/* The counts' arrays, zero (no history), once the grid is built: 6 keys
   a cell when they fit in WT__LEARN_MAX_ENTRIES, else 1, else none (no
   learning: the grid's flags alone). 0, or -1 when out of memory. */
static int wt__light_learn_init(wt_world *w)
{
    size_t cells = (size_t)w->grid_dims[0] * w->grid_dims[1] * w->grid_dims[2], keys;
    w->learn_sides = cells * 6u * w->light_count <= WT__LEARN_MAX_ENTRIES ? 6u
                     : cells * w->light_count <= WT__LEARN_MAX_ENTRIES ? 1u : 0u;
    if (!w->learn_sides) return 0;
    keys = cells * w->learn_sides;
    w->light_learned = (uint16_t *)calloc(keys * 2u * w->light_count, sizeof(uint16_t));
    w->light_learning = (uint32_t *)calloc(keys * 2u * w->light_count, sizeof(uint32_t));
    w->learn_touched = (unsigned char *)calloc(keys, 1);
    if (w->light_learned && w->light_learning && w->learn_touched) return 0;
    w->learn_sides = 0;
    return -1;
}

/* Adds the counts of the frame just traced to those of the earlier frames
   (both halve while the rays tried exceed WT__LEARN_MAX_TRIED: the
   counts follow the bunny's shadows and stay in 16 bits) and clears the
   frame's. Called between frames, with no shading under way: integer
   sums, so the result is the same for any order of the frame's samples
   and any thread count. */
static void wt__light_learn_merge(wt_world *w)
{
    size_t keys = (size_t)w->grid_dims[0] * w->grid_dims[1] * w->grid_dims[2] * w->learn_sides, key;
    uint32_t e;
    for (key = 0; key < keys; key++) {
        if (!w->learn_touched[key]) continue;
        w->learn_touched[key] = 0;
        for (e = 0; e < w->light_count; e++) {
            size_t i = 2u * (key * w->light_count + e);
            uint32_t tried = w->light_learning[i], arrived = w->light_learning[i + 1];
            if (!tried) continue;
            tried += w->light_learned[i];
            arrived += w->light_learned[i + 1];
            while (tried > WT__LEARN_MAX_TRIED) {
                tried >>= 1;
                arrived >>= 1;
            }
            w->light_learned[i] = (uint16_t)tried;
            w->light_learned[i + 1] = (uint16_t)arrived;
            w->light_learning[i] = w->light_learning[i + 1] = 0;
        }
    }
}

/* ---- a light's directions: by area or by solid angle ---------------------
   A shadow ray's direction towards light L from x comes with a weight, the
   sampler's measure: f(wi) x weight is, on average over the samples, the
   integral of f over the directions in which x sees L. Two samplers:
   - by area (wt__light_point): weight = area x cos_y / d^2, the Jacobian
     from L's area to directions. Near L its 1/d^2 and cos_y vary over L by
     large factors (a point on the office's wall a few centimetres beside
     the lamp sees the near corner of a face at a grazing angle, the far
     one straight on, one twice as far as the other), and that variation is
     the estimate's noise.
   - by solid angle (Arvo 1995, "Stratified Sampling of Spherical
     Triangles", fig. 2): one of L's triangles picked by its solid angle,
     then a direction uniform in its spherical triangle; weight = L's solid
     angle, the same for every sample, so only cos_x, the BRDF and the
     visibility vary. The pick uses the first coordinate's remainder and
     the mapping is continuous in both, so the Hammersley points of
     wt__direct stay stratified over L's directions.
   Both are unbiased, and which one a point uses depends on x and L alone,
   never on the random numbers, so the estimate stays unbiased. Solid angle
   within WT__SOLID_ANGLE_REACH radii of L's centre: farther, 1/d^2 and
   cos_y vary over L by less than about 25 % either way (a variance of a
   few per cent of the mean squared), which solid angle would not win back
   for its trigonometry. Area also where L's solid angle is below
   WT__SOLID_ANGLE_MIN: L seen edge-on, where Arvo's step divides by the
   sine of a corner's angle that tends to 0 with the triangle's spherical
   area, and L sends almost nothing anyway. Measured with 8 shadow rays
   against 256 (wt_render_converged at 160x120, the same 2 x 2 gather in
   both, LRMS of the displayed frames; area -> solid angle): the office's
   frames 7, 23, 39 pooled 0.056 -> 0.043, the relative RMS noise of
   wt__direct at their hits 0.10, 0.11, 0.18 -> 0.06, 0.05, 0.09;
   building_4k's frames 15-215 pooled 0.115 -> 0.113 (its dark rooms'
   lamps are farther than 8 radii: their frames are the same bit for
   bit), building_1k's 0.047 -> 0.045. Cost (wt__direct x 8 at 64 x 48
   hits, one thread): the office 41 -> 50 ms (81 ms when every sample made
   its light's spherical triangles again: wt__light_view makes them once a
   point), building_4k near its first lamps 87 -> 91 ms. */
#define WT__SOLID_ANGLE_REACH 8.0f     /* L's radii from its centre: solid angle nearer, area farther */
#define WT__SOLID_ANGLE_MIN 1e-5       /* steradians: area sampling below (edge-on) */
#define WT__SOLID_ANGLE_TRIS 4         /* a light of more triangles is sampled by area (the scenes' lamps are quads) */

/* A spherical triangle seen from a point: the unit vectors to its corners
   a, b, c, the angle at a (between the great circles ab and ac) with its
   cosine and sine, cos of the side ab, the unit vector along c's part
   perpendicular to a, and its area (the solid angle). */
typedef struct wt__spherical_triangle {
    double a[3], b[3], c_perp[3];
    double cos_alpha, sin_alpha, alpha, cos_c, area;
} wt__spherical_triangle;

static double wt__dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* The unit vector along v's part perpendicular to unit u, in out; 0 (and
   out = 0) when v is parallel to u. */
static int wt__perpendicular(const double v[3], const double u[3], double out[3])
{
    double vu = wt__dot3(v, u), len;
    int k;
    for (k = 0; k < 3; k++) out[k] = v[k] - vu * u[k];
    len = sqrt(wt__dot3(out, out));
    if (!(len > 0.0)) {
        out[0] = out[1] = out[2] = 0.0;
        return 0;
    }
    for (k = 0; k < 3; k++) out[k] /= len;
    return 1;
}

/* The spherical triangle of corners p[0..2] seen from x, which lies in
   front of their plane (height front > 0 along its normal); returns its
   solid angle. The solid angle by Van Oosterom & Strackee's formula (1983:
   tan(omega / 2) = |a . (b x c)| / (1 + a.b + b.c + c.a)), and the angle at
   a by the same triple product ((a x b) x (a x c) = (a . (b x c)) a): both
   from atan2, which keeps their precision for small triangles where the
   angle sum's excess (alpha + beta + gamma - pi) would cancel. */
static double wt__spherical_triangle_make(const float x[3], const float *const p[3], wt__spherical_triangle *s)
{
    double v[3][3], ab, bc, ca, det;
    int i, k;
    for (i = 0; i < 3; i++) {
        double len;
        for (k = 0; k < 3; k++) v[i][k] = (double)p[i][k] - x[k];
        len = sqrt(wt__dot3(v[i], v[i]));
        if (!(len > 0.0)) return s->area = 0.0;
        for (k = 0; k < 3; k++) v[i][k] /= len;
    }
    ab = wt__dot3(v[0], v[1]);
    bc = wt__dot3(v[1], v[2]);
    ca = wt__dot3(v[2], v[0]);
    det = fabs(v[0][0] * (v[1][1] * v[2][2] - v[1][2] * v[2][1]) + v[0][1] * (v[1][2] * v[2][0] - v[1][0] * v[2][2]) +
               v[0][2] * (v[1][0] * v[2][1] - v[1][1] * v[2][0]));
    memcpy(s->a, v[0], sizeof s->a);
    memcpy(s->b, v[1], sizeof s->b);
    wt__perpendicular(v[2], v[0], s->c_perp);
    s->area = 2.0 * atan2(det, 1.0 + ab + bc + ca);
    s->alpha = atan2(det, bc - ab * ca);
    s->cos_alpha = cos(s->alpha);
    s->sin_alpha = sin(s->alpha);
    s->cos_c = ab;
    return s->area;
}

/* A direction uniform in the spherical triangle s from (u1, u2) in [0, 1]^2
   (Arvo 1995, fig. 2): u1 picks the sub-triangle a b c' of area u1 x area,
   whose corner c' lies on the arc from a to c, and u2 the point on the arc
   from b to c' with cos(angle to b) uniform: area-preserving, so
   stratified (u1, u2) give stratified directions. */
static void wt__spherical_triangle_sample(const wt__spherical_triangle *s, double u1, double u2, double dir[3])
{
    double part = u1 * s->area, sp = sin(part - s->alpha), tp = cos(part - s->alpha);
    double u = tp - s->cos_alpha, v = sp + s->sin_alpha * s->cos_c;
    double q = ((v * tp - u * sp) * s->cos_alpha - v) / ((v * sp + u * tp) * s->sin_alpha);   /* cos of the arc a c' */
    double e[3], c2[3], z, r;
    int k;
    q = q < 1.0 ? (q > -1.0 ? q : -1.0) : 1.0;   /* rounding; NaN (sin alpha = 0, no area) becomes 1: c' = a */
    r = sqrt(1.0 - q * q);
    for (k = 0; k < 3; k++) c2[k] = q * s->a[k] + r * s->c_perp[k];
    z = 1.0 - u2 * (1.0 - wt__dot3(c2, s->b));
    z = z < 1.0 ? (z > -1.0 ? z : -1.0) : 1.0;
    wt__perpendicular(c2, s->b, e);
    r = sqrt(1.0 - z * z);
    for (k = 0; k < 3; k++) dir[k] = z * s->b[k] + r * e[k];
}

/* The corners of light L's triangle i (0 .. tri_count - 1). */
static void wt__light_corners(const wt_world *w, const wt_light *L, uint32_t i, const float *p[3])
{
    const uint32_t *v = w->office.tri_indices + 3 * (size_t)(L->first_tri + i);
    int k;
    for (k = 0; k < 3; k++) p[k] = w->office.positions + 3 * (size_t)v[k];
}

/* Light L as a point sees it, for its samples (wt__light_view_direction):
   its triangles in front of the point as spherical triangles, with their
   planes' heights above the point and normals (the distance along a
   direction), and their solid angles' sum; count 0: by area. */
typedef struct wt__light_view {
    const wt_light *L;
    int count;
    double solid_angle, front[WT__SOLID_ANGLE_TRIS];
    const float *normal[WT__SOLID_ANGLE_TRIS];
    wt__spherical_triangle tri[WT__SOLID_ANGLE_TRIS];
} wt__light_view;

/* L's spherical triangles seen from x (at most WT__SOLID_ANGLE_TRIS);
   returns their solid angle, -1 when L has more triangles. */
static double wt__light_view_solid_angle(const wt_world *w, const wt_light *L, const float x[3], wt__light_view *v)
{
    uint32_t i;
    v->L = L;
    v->count = 0;
    v->solid_angle = 0.0;
    if (L->tri_count > WT__SOLID_ANGLE_TRIS) return -1.0;
    for (i = 0; i < L->tri_count; i++) {
        const float *p[3], *n = w->tracer->tri_normal + 3 * (size_t)(L->first_tri + i);
        double front = 0.0;
        int k;
        wt__light_corners(w, L, i, p);
        for (k = 0; k < 3; k++) front += ((double)x[k] - p[0][k]) * n[k];
        if (!(front > 0.0) || !(wt__spherical_triangle_make(x, p, &v->tri[v->count]) > 0.0)) continue;   /* one-sided */
        v->front[v->count] = front;
        v->normal[v->count] = n;
        v->solid_angle += v->tri[v->count++].area;
    }
    return v->solid_angle;
}

/* How x samples L (the comment above): by solid angle within
   WT__SOLID_ANGLE_REACH radii of its centre unless L is edge-on or of more
   triangles, by area otherwise (count 0). */
static void wt__light_view_make(const wt_world *w, const wt_light *L, const float x[3], wt__light_view *v)
{
    float d[3] = { x[0] - L->centre[0], x[1] - L->centre[1], x[2] - L->centre[2] };
    float reach = WT__SOLID_ANGLE_REACH * L->radius;
    v->L = L;
    v->count = 0;
    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach && !(wt__light_view_solid_angle(w, L, x, v) >= WT__SOLID_ANGLE_MIN))
        v->count = 0;   /* edge-on or too many triangles: by area */
}

/* A sample of L's directions from x by area (wt__light_point): wi, the
   distance to L along it and the weight area x cos_y / d^2; 0 when the
   point of L faces away (no light). */
static int wt__light_area_direction(const wt_world *w, const wt_light *L, const float x[3], float u1, float u2,
                                    float wi[3], float *dist, float *weight)
{
    float y[3], d2, d, cos_y;
    int k;
    wt__light_point(w, L, u1, u2, y);
    for (k = 0; k < 3; k++) wi[k] = y[k] - x[k];
    d2 = wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2];
    if (!(d2 > 0.0f)) return 0;
    d = sqrtf(d2);
    for (k = 0; k < 3; k++) wi[k] /= d;
    cos_y = -(wi[0] * L->normal[0] + wi[1] * L->normal[1] + wi[2] * L->normal[2]);
    if (cos_y <= 0.0f) return 0;
    *dist = d;
    *weight = L->area * cos_y / d2;
    return 1;
}

/* A sample of L's directions from x as v says: by area, or by solid angle
   (Arvo 1995): the triangle whose share of the solid angle holds u1, a
   direction uniform in it from what is left of u1 and u2, the distance to
   its plane along it, weight = L's solid angle. 0 when nothing comes. */
static int wt__light_view_direction(const wt_world *w, const wt__light_view *v, const float x[3], float u1, float u2,
                                    float wi[3], float *dist, float *weight)
{
    double left = (double)u1 * v->solid_angle, dir[3], down = 0.0;
    int i = 0, k;
    if (!v->count) return wt__light_area_direction(w, v->L, x, u1, u2, wi, dist, weight);
    while (i + 1 < v->count && left >= v->tri[i].area) left -= v->tri[i++].area;   /* the last takes what rounding leaves */
    wt__spherical_triangle_sample(&v->tri[i], fmin(fmax(left / v->tri[i].area, 0.0), 1.0), u2, dir);
    for (k = 0; k < 3; k++) {
        down -= dir[k] * v->normal[i][k];
        wi[k] = (float)dir[k];
    }
    if (!(down > 0.0)) return 0;   /* grazing the plane by rounding */
    *dist = (float)(v->front[i] / down);
    *weight = (float)v->solid_angle;
    return 1;
}

/* One shadow-ray sample of the light v sees from org (normal n, mirror:
   the view direction reflected) for direct light: a direction towards it
   (wt__light_view_direction) from u1 and u2, added to rgb with the
   sampler's weight x scale (scale = 1 / (selection probability *
   samples)); its specular (view-dependent) term is added to gloss as well.
   The bunny blocks the shadow ray only when bunny_casts. Returns 1 when
   the ray arrived (light sent, in front of n, nothing opaque between). */
static int wt__light_view_sample(const wt_world *w, const wt__light_view *v, const float org[3], const float n[3],
                                  const float mirror[3], const lightvec_material *m, float u1, float u2, float scale,
                                  int bunny_casts, float rgb[3], float gloss[3], int *bunny_shadow)
{
    const ex_tracer *t = w->tracer;
    const wt_light *L = v->L;
    float wi[3], through[3], d, weight, cos_x, g, f, c_m = 0.0f;
    int k;
    if (!wt__light_view_direction(w, v, org, u1, u2, wi, &d, &weight)) return 0;
    cos_x = wi[0] * n[0] + wi[1] * n[1] + wi[2] * n[2];
    if (cos_x <= 0.0f) return 0;
    if (wt__occluded(w, org, wi, d * (1.0f - 1e-4f) - t->epsilon, bunny_casts, through, bunny_shadow)) return 0;
    g = cos_x * weight * scale;
    for (k = 0; k < 3; k++) c_m += mirror[k] * wi[k];
    f = c_m > 0.0f && m->exponent > 0.0f ? (m->exponent + 2.0f) / (2.0f * WT_PI) * powf(c_m, m->exponent) : 0.0f;
    for (k = 0; k < 3; k++) {
        rgb[k] += L->ke[k] * (m->diffuse[k] / WT_PI + m->specular[k] * f) * g * through[k];
        gloss[k] += L->ke[k] * m->specular[k] * f * g * through[k];
    }
    return 1;
}

/* Direct light reflected at a hit towards -dir (Lambert + normalized
   Phong), by many-light sampling as a production renderer does it: a fixed
   number n = opt.light_samples of shadow rays per point, whatever the
   number of emitting polygons. Each sample picks a light with probability
   p (wt__light_probability: importance and the grid's weights) and a
   direction towards it (wt__light_view_direction: uniform in its solid
   angle near it, through a uniform point on it farther), and is weighted
   by 1 / (p n): an unbiased estimate of the sum over every
   light. The n picks are stratified over the CDF of p (sample s at
   (s + xi) / n, so a light of probability p gets n p picks up to one), and
   what is left of a pick's stratum inside its light's interval, uniform in
   [0, 1), places the sample on the light: one light alone (the office's
   lamp face) gets n stratified samples. The sample's other coordinate is the
   van der Corput sequence of the sample's index, rotated by one random
   offset per shaded point (Cranley-Patterson): with the first coordinate
   stratified in n, the n points of one light form a randomized Hammersley
   set, stratified in both directions on the light, where two independent
   random numbers left clumps and gaps along the second. The CDF is never stored: the picks
   are sorted, so one sweep over the lights meets them in order (a second
   pass recomputes the same importances, bit for bit). Shadow rays go
   through the tracer, so the bunny casts shadows. gloss: the specular
   (view-dependent) part of rgb. */
/* The van der Corput sequence: i's bits mirrored behind the binary point. */
static float wt__radical_inverse(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
    i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
    return (float)(i >> 8) * (1.0f / 16777216.0f);
}

/* Light e's weight in a flagged term of the mixture (the grid's comment;
   flag 0: neighbourhood, 1: cell): the flag, or with learned counts
   (tried, arrived; NULL: none) the share of the earlier frames' rays that
   arrived, the flag counting as WT__LEARN_PRIOR rays: exactly the flag
   where no ray was recorded. */
static float wt__light_flag_weight(const float *seen, const uint16_t *learned, uint32_t e, int flag)
{
    if (!learned) return seen[2 * e + flag];
    return sqrtf(((float)learned[2 * e + 1] + WT__LEARN_PRIOR * seen[2 * e + flag]) / ((float)learned[2 * e] + WT__LEARN_PRIOR));
}

/* The defensive mixture's coefficients at x (the grid's comment), from
   the sums over the lights of importance alone, of importance x
   neighbourhood weight and of importance x cell weight (seen: the grid's
   flags at x, NULL without a grid; learned: the counts of x's key, or
   NULL: wt__light_flag_weight): a light's probability is its importance x
   (coef[0] + coef[1] x neighbourhood weight + coef[2] x cell weight). A term
   whose sum is 0 (no light flagged) gives its share to importance alone.
   Returns the last light of non-zero importance; coef[0] is 0 when there
   is none. */
static uint32_t wt__light_mixture(const wt_world *w, const float *seen, const uint16_t *learned, const float x[3],
                                  const float n[3], float coef[3])
{
    float total[3] = { 0.0f, 0.0f, 0.0f }, rest = 1.0f;
    uint32_t e, last = 0;
    for (e = 0; e < w->light_count; e++) {
        float imp = wt__light_importance(&w->lights[e], x, n);
        if (imp > 0.0f) last = e;
        total[0] += imp;
        if (seen) {
            total[1] += imp * wt__light_flag_weight(seen, learned, e, 0);
            total[2] += imp * wt__light_flag_weight(seen, learned, e, 1);
        }
    }
    coef[0] = coef[1] = coef[2] = 0.0f;
    if (!(total[0] > 0.0f) || !isfinite(total[0])) return last;
    if (total[1] > 0.0f) {
        coef[1] = WT__GRID_NEAR_SHARE / total[1];
        rest -= WT__GRID_NEAR_SHARE;
    }
    if (total[2] > 0.0f) {
        coef[2] = WT__GRID_CELL_SHARE / total[2];
        rest -= WT__GRID_CELL_SHARE;
    }
    coef[0] = rest / total[0];
    return last;
}

/* Light e's selection probability from the mixture's coefficients:
   positive wherever its importance is (coef[0] > 0). */
static float wt__light_probability(const wt_world *w, const float *seen, const uint16_t *learned, const float coef[3],
                                   uint32_t e, const float x[3], const float n[3])
{
    float mix = coef[0] + (seen ? coef[1] * wt__light_flag_weight(seen, learned, e, 0) +
                                      coef[2] * wt__light_flag_weight(seen, learned, e, 1) : 0.0f);
    return wt__light_importance(&w->lights[e], x, n) * mix;
}

static void wt__direct(const wt_world *w, const ex_trace_hit *h, const float dir[3], const lightvec_material *m,
                       ex_rng *r, int bunny_casts, int learn, float rgb[3], float gloss[3], int *bunny_shadow)
{
    float pick[WT__MAX_LIGHT_SAMPLES], org[3], mirror[3], coef[3], below = 0.0f, shift;
    const float *seen;
    const uint16_t *learned = NULL;
    uint32_t *record = NULL;
    float vn = -(dir[0] * h->normal[0] + dir[1] * h->normal[1] + dir[2] * h->normal[2]);
    int n = w->opt.light_samples, s = 0, k, recorded = 0;
    uint32_t e, last;
    size_t key = 0;
    rgb[0] = rgb[1] = rgb[2] = gloss[0] = gloss[1] = gloss[2] = 0.0f;
    if (n < 1 || n > WT__MAX_LIGHT_SAMPLES) return;
    for (k = 0; k < 3; k++) {
        org[k] = h->pos[k] + w->tracer->epsilon * h->normal[k];
        mirror[k] = dir[k] + 2.0f * vn * h->normal[k];   /* the view direction reflected */
    }
    seen = wt__lights_seen(w, org);
    if (seen && w->learn_sides && learn) {
        key = wt__learn_key(w, org, h->normal);
        if (learn & WT__LEARN_USE) learned = w->light_learned + key * 2u * w->light_count;
        if (learn & WT__LEARN_RECORD) record = w->light_learning + key * 2u * w->light_count;
    }
    last = wt__light_mixture(w, seen, learned, org, h->normal, coef);
    if (!(coef[0] > 0.0f) || !isfinite(coef[0]) || !isfinite(coef[1]) || !isfinite(coef[2])) return;
    for (s = 0; s < n; s++) pick[s] = ((float)s + ex_rng_float(r)) / (float)n;
    shift = ex_rng_float(r);
    s = 0;
    for (e = 0; e < w->light_count && s < n; e++) {
        float p = wt__light_probability(w, seen, learned, coef, e, org, h->normal), above = below + p;
        wt__light_view view;
        uint32_t tried = 0, arrived = 0;
        if (p > 0.0f && s < n && (pick[s] < above || e == last))   /* a pick lands: how org sees the light */
            wt__light_view_make(w, &w->lights[e], org, &view);
        if (p > 0.0f)   /* the picks in [below, above); the last light takes what rounding leaves */
            for (; s < n && (pick[s] < above || e == last); s++, tried++) {
                float u1 = fminf(fmaxf((pick[s] - below) / p, 0.0f), 0.99999994f);
                float u2 = wt__radical_inverse((uint32_t)s) + shift;
                arrived += (uint32_t)wt__light_view_sample(w, &view, org, h->normal, mirror, m, u1,
                                                           u2 < 1.0f ? u2 : u2 - 1.0f, 1.0f / (p * (float)n),
                                                           bunny_casts, rgb, gloss, bunny_shadow);
            }
        if (record && tried) {   /* integer sums: the same in any order (wt__light_learn_merge) */
            (void)__atomic_fetch_add(&record[2 * e], tried, __ATOMIC_RELAXED);
            (void)__atomic_fetch_add(&record[2 * e + 1], arrived, __ATOMIC_RELAXED);
            recorded = 1;
        }
        below = above;
    }
    if (recorded) __atomic_store_n(&w->learn_touched[key], (unsigned char)1, __ATOMIC_RELAXED);   /* once a point */
}

static float wt__luminance(const float c[3]) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* A point's radiance towards the eye: what it sends, dimmed by the glass
   in front of it; and the share of it that depends on the view. */
static void wt__point_radiance(wt_point *p)
{
    float gloss[3], all;
    int k;
    for (k = 0; k < 3; k++) {
        p->rgb[k] = p->through[k] * (p->direct[k] + p->contact * p->indirect[k]);
        gloss[k] = p->through[k] * (p->direct_gloss[k] + p->contact * p->indirect_gloss[k]);
    }
    all = wt__luminance(p->rgb);
    p->view_share = all > 0.0f ? fminf(wt__luminance(gloss) / all, 1.0f) : 0.0f;
}

/* Contact shadows of the bunny (issue 19): the office's light vectors are
   gathered without the bunny (one static cache for every pose), so the
   floor under it would keep all of its indirect light, and by day, when
   all light is indirect, the bunny would cast no shadow at all. A static
   point within reach of the posed bunny loses the share of its indirect
   light that the bunny hides: the cosine-weighted share of its hemisphere
   that the bunny covers, estimated with WT_CONTACT_RAYS rays (4 x 8
   strata of the cosine-weighted hemisphere, jittered from the point's
   stream) cast against the bunny alone and stopped at the reach
   (WT_CONTACT_REACH bounding radii), as if the light arriving there were
   the same from every direction (ambient occlusion of the indirect
   light, which is how engines shadow indirect light with a moving object:
   UE4's capsule shadows, The Last of Us' ellipsoid occluders). Beyond the
   reach the bunny covers under (1 / (1 + 2))^2 = 11% of the hemisphere
   seen from its bounding sphere's edge, and much less of it in practice
   (the bounding sphere is twice the bunny's equal-volume sphere): the
   cut-off is not seen. Points farther away cost one distance test. Direct
   light needs none of this: its shadow rays see the bunny. */
#define WT_CONTACT_RAYS 32
#define WT_CONTACT_REACH 2.0f
#define WT_CONTACT_STREAM 0xC0A7AC7ull   /* the rays' random numbers: not the direct light's */

static float wt__contact_occlusion(const wt_world *w, const float pos[3], const float n[3], uint64_t stream)
{
    const ex_tracer *t = w->tracer;
    const ex__instance *b = &t->instances[w->bunny_instance];
    float c[3], v[3], u[3], s[3], org[3], o[3], d2 = 0.0f, above = 0.0f, radius = w->bunny_bound_radius;
    float reach = WT_CONTACT_REACH * radius, l;
    ex_rng rng;
    int i, k, hits = 0;
    ex__affine_point(w->pose, w->bunny_bound_centre, c);
    for (k = 0; k < 3; k++) {
        v[k] = c[k] - pos[k];
        d2 += v[k] * v[k];
        above += v[k] * n[k];
    }
    if (d2 >= (radius + reach) * (radius + reach) || above <= -radius) return 0.0f;   /* out of reach, or below */
    /* a tangent frame (u, s, n) */
    if (fabsf(n[0]) > 0.5f) { u[0] = -n[1]; u[1] = n[0]; u[2] = 0.0f; }
    else { u[0] = 0.0f; u[1] = -n[2]; u[2] = n[1]; }
    l = sqrtf(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (k = 0; k < 3; k++) u[k] /= l;
    s[0] = n[1] * u[2] - n[2] * u[1];
    s[1] = n[2] * u[0] - n[0] * u[2];
    s[2] = n[0] * u[1] - n[1] * u[0];
    for (k = 0; k < 3; k++) org[k] = pos[k] + t->epsilon * n[k];
    ex__affine_point(b->to_object, org, o);
    rng = ex_rng_stream(w->opt.seed ^ WT_CONTACT_STREAM, stream);
    for (i = 0; i < WT_CONTACT_RAYS; i++) {
        float a = ((float)(i % 4) + ex_rng_float(&rng)) / 4.0f, phi = 2.0f * WT_PI * ((float)(i / 4) + ex_rng_float(&rng)) / 8.0f;
        float r = sqrtf(a), z = sqrtf(1.0f - a), d[3], dobj[3];   /* cosine-distributed (Malley) */
        for (k = 0; k < 3; k++) d[k] = r * cosf(phi) * u[k] + r * sinf(phi) * s[k] + z * n[k];
        ex__affine_vector(b->to_object, d, dobj);   /* unnormalised: the reach stays a world distance */
        hits += tr__bvh_occluded(&b->bvh, o, dobj, 0.0f, reach);
    }
    return (float)hits / (float)WT_CONTACT_RAYS;
}

/* How wt_shade_points (and wt__trace_point: the first and last flags) works. */
enum {
    WT_SHADE_DIRECT = 1,           /* emission + direct light (else emission only) */
    WT_SHADE_INSERT = 2,           /* new light vectors go into the caches */
    WT_SHADE_STATIC_ONLY = 4,      /* light vectors for the office only (the bunny's points get none) */
    WT_SHADE_NO_BUNNY_SHADOWS = 8, /* the bunny casts no shadow and darkens no contact (the baseviews
                                      mode's base images: its shadows belong to the frame's time) */
    WT_SHADE_LEARNED = 16,         /* direct light picks lights with the counts of the frames merged so far */
    WT_SHADE_LEARN = 32            /* direct light adds its shadow rays to the frame's counts (the
                                      raytrace frames; wt__light_learn_merge after the trace) */
};

/* Traces a point's ray and computes its emission and direct light. Camera
   rays see through glass (ex_tracer_intersect_through): the point is the
   first opaque surface behind the panes, or the sky, its radiance dimmed
   by their transmittance. A pane's own reflection is not drawn (the
   daylight building's glass has Kd 0; its faint mirror term, Ks 0.08, is
   left out). */
static void wt__trace_point(const wt_world *w, wt_point *p, int flags)
{
    int bunny_casts = !(flags & WT_SHADE_NO_BUNNY_SHADOWS);
    ex_trace_hit h;
    ex_rng rng;
    float d[3];
    int k, shadow = 0;
    p->light = WT_LIGHT_NONE;
    p->bunny_shadow = 0;
    p->lit = 1;
    p->gathered = 0;
    p->glossy = 0;
    p->weight = 0.0f;
    p->material = 0;
    for (k = 0; k < 3; k++) p->direct[k] = p->indirect[k] = p->direct_gloss[k] = p->indirect_gloss[k] = p->rgb[k] = 0.0f;
    p->contact = 1.0f;
    p->view_share = 0.0f;
    if (!ex_tracer_intersect_through(w->tracer, p->org, p->dir, FLT_MAX, &h, p->through)) {
        p->t = FLT_MAX;
        p->object = RENDERCACHE_MISS;
        p->polygon = RENDERCACHE_MISS;
        if (w->tracer->has_sky) ex_sky_radiance(&w->tracer->sky, p->dir, p->direct);
        wt__point_radiance(p);
        return;
    }
    p->t = h.t;
    memcpy(p->pos, h.pos, sizeof p->pos);
    if (h.instance == EX_TRACE_STATIC) {
        p->object = WT_OBJECT_OFFICE;
        p->polygon = w->office.tri_face[h.tri];
        p->material = w->office.tri_material[h.tri];
    } else {
        float n[3];
        p->object = WT_OBJECT_BUNNY;
        p->polygon = w->office.face_count + h.tri;
        p->material = w->bunny_material;
        wt__bunny_normal(w, &h, n);
        if (h.front && n[0] * p->dir[0] + n[1] * p->dir[1] + n[2] * p->dir[2] < 0.0f) memcpy(h.normal, n, sizeof n);
    }
    memcpy(p->normal, h.normal, sizeof p->normal);
    if (!h.front) return;                 /* one-sided surfaces: a back face is black */
    if (h.instance == EX_TRACE_STATIC && ex__passes(w->office.materials[p->material].tf))
        return;                           /* the pane after EX_TRACE_MAX_PASSES others: seen as black */
    for (k = 0; k < 3; k++) p->direct[k] = w->materials[p->material].emission[k];
    if (flags & WT_SHADE_DIRECT) {
        rng = ex_rng_stream(w->opt.seed, p->stream);
        wt__direct(w, &h, p->dir, &w->materials[p->material], &rng, bunny_casts,
                   (flags & WT_SHADE_LEARNED ? WT__LEARN_USE : 0) | (flags & WT_SHADE_LEARN ? WT__LEARN_RECORD : 0), d,
                   p->direct_gloss, &shadow);
        p->bunny_shadow = (unsigned char)shadow;
        for (k = 0; k < 3; k++) p->direct[k] += d[k];
    }
    if (p->object == WT_OBJECT_OFFICE && w->opt.bunny_shadow && bunny_casts) {
        p->contact = 1.0f - wt__contact_occlusion(w, p->pos, p->normal, p->stream);
        if (p->contact < 1.0f) p->bunny_shadow = 1;   /* refreshed sooner by the render cache: the shadow moves */
    }
    p->light = p->object == WT_OBJECT_BUNNY ? WT_LIGHT_BUNNY : WT_LIGHT_STATIC;
    p->glossy = (unsigned char)wt__is_glossy(&w->materials[p->material]);
    p->lit = 0;
}

typedef struct wt__job {
    wt_world *w;
    wt_point *points;
    uint32_t count;
    int flags;             /* WT_SHADE_* */
} wt__job;

static void wt__trace_job(void *ctx, uint32_t batch)
{
    const wt__job *j = (const wt__job *)ctx;
    uint32_t i, end = batch * WT__BATCH + WT__BATCH;
    if (end > j->count) end = j->count;
    for (i = batch * WT__BATCH; i < end; i++) wt__trace_point(j->w, &j->points[i], j->flags);
}

static const float *wt__outgoing(const wt_point *p, float wo[3])
{
    if (!p->glossy) return NULL;   /* Lambertian: a view-independent (3D) light vector */
    wo[0] = -p->dir[0];
    wo[1] = -p->dir[1];
    wo[2] = -p->dir[2];
    return wo;
}

/* The indirect light of a point from its light vector, and the glossy
   part of it (what the diffuse term alone leaves out). */
static void wt__indirect(const wt_world *w, wt_point *p, const lightvec_vector *v)
{
    float wo[3], diffuse[3];
    const float *out = wt__outgoing(p, wo);
    int k;
    lightvec_radiance(&w->materials[p->material], p->normal, out, v, p->indirect);
    if (!out) return;
    lightvec_radiance(&w->materials[p->material], p->normal, NULL, v, diffuse);
    for (k = 0; k < 3; k++) p->indirect_gloss[k] = fmaxf(p->indirect[k] - diffuse[k], 0.0f);
}

static lightvec_cache *wt__cache_of(const wt_world *w, const wt_point *p)
{
    return p->light == WT_LIGHT_BUNNY ? w->bunny_cache : w->static_cache;
}

static void wt__lookup_job(void *ctx, uint32_t batch)
{
    const wt__job *j = (const wt__job *)ctx;
    uint32_t i, end = batch * WT__BATCH + WT__BATCH;
    if (end > j->count) end = j->count;
    for (i = batch * WT__BATCH; i < end; i++) {
        wt_point *p = &j->points[j->w->pending[i]];
        lightvec_lookup_result r;
        float wo[3];
        if (lightvec_lookup(wt__cache_of(j->w, p), p->pos, p->normal, wt__outgoing(p, wo), &r) != LIGHTVEC_OK || !r.hit)
            continue;
        wt__indirect(j->w, p, &r.vector);
        p->weight = r.weight;
        p->lit = 1;
    }
}

static void wt__surface_of(const wt_world *w, const wt_point *p, lightvec_surface *s)
{
    int k;
    memset(s, 0, sizeof *s);
    memcpy(s->position, p->pos, sizeof s->position);
    memcpy(s->normal, p->normal, sizeof s->normal);
    for (k = 0; k < 3; k++) s->outgoing[k] = -p->dir[k];
    s->flags = p->glossy ? 0u : LIGHTVEC_RECORD_VIEW_INDEPENDENT;
    s->material = w->materials[p->material];
}

static void wt__gather_job(void *ctx, uint32_t batch)
{
    const wt__job *j = (const wt__job *)ctx;
    const wt_world *w = j->w;
    uint32_t i, end = batch * WT__GATHER_BATCH + WT__GATHER_BATCH;
    if (end > j->count) end = j->count;
    for (i = batch * WT__GATHER_BATCH; i < end; i++) {
        const wt_point *p = &j->points[w->picks[i]];
        lightvec_surface s;
        wt__surface_of(w, p, &s);
        if (p->light == WT_LIGHT_BUNNY)
            lightvec_gather(w->posed_scene, &w->bunny_gather, &s, p->stream, &w->records[i]);
        else
            lightvec_gather(w->office_scene, &w->static_gather, &s, p->stream, &w->records[i]);
    }
}

static int wt__reserve(wt_world *w, uint32_t n)
{
    uint32_t cells = 16;
    if (n > w->scratch_capacity) {
        free(w->pending);
        free(w->picks);
        free(w->records);
        w->pending = (uint32_t *)malloc(sizeof(uint32_t) * n);
        w->picks = (uint32_t *)malloc(sizeof(uint32_t) * n);
        w->records = (lightvec_record *)malloc(sizeof(lightvec_record) * n);
        w->scratch_capacity = w->pending && w->picks && w->records ? n : 0;
        if (!w->scratch_capacity) return -1;
    }
    while (cells < 2 * n) cells *= 2;
    if (cells > w->cell_capacity) {
        free(w->cells);
        w->cells = (uint64_t *)malloc(sizeof(uint64_t) * cells);
        w->cell_capacity = w->cells ? cells : 0;
        if (!w->cells) return -1;
    }
    return 0;
}

/* The pick cell of a point: 18 bits per axis, the cache, and for glossy
   points the octant and dominant axis of the view direction (their light
   vectors are valid within 15 degrees of it). Never 0. */
static uint64_t wt__cell_key(const wt_point *p, float cell)
{
    uint64_t key = 0;
    int k;
    for (k = 0; k < 3; k++) {
        long c = (long)floorf((p->pos[k] + 64.0f) / cell);
        if (c < 0) c = 0;
        if (c > 0x3FFFF) c = 0x3FFFF;
        key = key << 18 | (uint64_t)c;
    }
    key = key << 2 | p->light;
    if (p->glossy) {
        const float *d = p->dir;
        int axis = fabsf(d[0]) > fabsf(d[1]) ? (fabsf(d[0]) > fabsf(d[2]) ? 0 : 2) : (fabsf(d[1]) > fabsf(d[2]) ? 1 : 2);
        key = key << 5 | (uint64_t)(8 * axis + (d[0] < 0) + 2 * (d[1] < 0) + 4 * (d[2] < 0));
        key |= (uint64_t)1 << 63;
    } else {
        key <<= 5;
    }
    return key | 1u;
}

/* Picks, among the pending points, the first of each cell (in point order). */
static uint32_t wt__pick(wt_world *w, const wt_point *points, uint32_t pending, int round)
{
    uint32_t i, n = 0, mask = w->cell_capacity - 1;
    float shrink = powf(WT__CELL_SHRINK, (float)round);
    memset(w->cells, 0, sizeof(uint64_t) * w->cell_capacity);
    for (i = 0; i < pending; i++) {
        const wt_point *p = &points[w->pending[i]];
        uint64_t key = wt__cell_key(p, (p->light == WT_LIGHT_BUNNY ? WT__CELL_BUNNY : WT__CELL_STATIC) * shrink);
        uint32_t slot = (uint32_t)(key ^ key >> 29 ^ key >> 47) * 0x9E3779B1u & mask;
        while (w->cells[slot] && w->cells[slot] != key) slot = (slot + 1) & mask;
        if (w->cells[slot]) continue;
        w->cells[slot] = key;
        w->picks[n++] = w->pending[i];
    }
    return n;
}

/* Light-vector counters of one call. */
typedef struct wt_light_stats { uint32_t lookups, hits, gathers, bunny_gathers; } wt_light_stats;

/* Indirect light of every point with p->light set (see above). Without
   insert the caches stay as they are: a miss gathers a vector for itself. */
static int wt__light_points(wt_world *w, wt_point *points, uint32_t count, int insert, wt_light_stats *st)
{
    uint32_t pending = 0, i, round;
    wt__job j;
    if (wt__reserve(w, count) != 0) return -1;
    for (i = 0; i < count; i++)
        if (!points[i].lit) w->pending[pending++] = i;
    for (i = 0; i < pending; i++)
        if (points[w->pending[i]].light == WT_LIGHT_BUNNY) {
            if (wt__ensure_pose(w) != 0) return -1;
            break;
        }
    j.w = w;
    j.points = points;
    for (round = 0; pending; round++) {
        uint32_t picks, kept;
        j.count = pending;
        ex_pool_parallel_for(w->pool, wt__lookup_job, &j, (pending + WT__BATCH - 1) / WT__BATCH);
        st->lookups += pending;
        for (i = kept = 0; i < pending; i++) {
            if (points[w->pending[i]].lit) st->hits++;
            else w->pending[kept++] = w->pending[i];
        }
        pending = kept;
        if (!pending) break;
        if (round + 1 >= WT__ROUNDS || !insert) {
            memcpy(w->picks, w->pending, sizeof(uint32_t) * pending);
            picks = pending;
        } else {
            picks = wt__pick(w, points, pending, (int)round);
        }
        j.count = picks;
        ex_pool_parallel_for(w->pool, wt__gather_job, &j, (picks + WT__GATHER_BATCH - 1) / WT__GATHER_BATCH);
        st->gathers += picks;
        for (i = 0; i < picks; i++) st->bunny_gathers += points[w->picks[i]].light == WT_LIGHT_BUNNY;
        for (i = 0; i < picks; i++) {   /* one writer, in a fixed order */
            wt_point *p = &points[w->picks[i]];
            if (insert) lightvec_insert(wt__cache_of(w, p), &w->records[i], NULL);
            wt__indirect(w, p, &w->records[i].vector);
            p->weight = 1.0f;   /* exact at its own point: weight 1 */
            p->lit = p->gathered = 1;
        }
        for (i = kept = 0; i < pending; i++)
            if (!points[w->pending[i]].lit) w->pending[kept++] = w->pending[i];
        pending = kept;
    }
    return 0;
}

/* Shades points: traces them, computes emission and direct light, and adds
   the indirect light of light vectors. Adds the seconds spent tracing and
   in light vectors to *seconds_trace, *seconds_light (either may be NULL). */
EX_FN int wt_shade_points(wt_world *w, wt_point *points, uint32_t count, int flags, wt_light_stats *st,
                          double *seconds_trace, double *seconds_light)
{
    wt__job j;
    double t0 = wt_seconds();
    uint32_t i;
    j.w = w;
    j.points = points;
    j.count = count;
    j.flags = flags;
    ex_pool_parallel_for(w->pool, wt__trace_job, &j, (count + WT__BATCH - 1) / WT__BATCH);
    if (flags & WT_SHADE_STATIC_ONLY)
        for (i = 0; i < count; i++)
            if (points[i].light == WT_LIGHT_BUNNY) {
                points[i].light = WT_LIGHT_NONE;
                points[i].lit = 1;
            }
    if (seconds_trace) *seconds_trace += wt_seconds() - t0;
    t0 = wt_seconds();
    if (wt__light_points(w, points, count, (flags & WT_SHADE_INSERT) != 0, st) != 0) return -1;
    for (i = 0; i < count; i++)
        wt__point_radiance(&points[i]);
    if (seconds_light) *seconds_light += wt_seconds() - t0;
    return 0;
}

/* ======================================================================
   rays of whole images
   ---------------------------------------------------------------------- */

/* Random stream of pixel p of frame f in a given use (frames, warm-up,
   base images, full renders draw from disjoint streams). */
enum { WT_STREAM_FRAME = 0, WT_STREAM_WARMUP = 1, WT_STREAM_BASE = 2, WT_STREAM_FULL = 3, WT_STREAM_FILL = 4 };
static uint64_t wt__stream(int use, uint32_t frame, uint32_t pixel)
{
    return (uint64_t)use << 56 | (uint64_t)(frame & 0xFFFFFFu) << 32 | pixel;
}

/* One point per pixel of camera c (row-major); pixels without a ray (outside
   a fish-eye's circle) get t = -1. */
static void wt__camera_points(const rendercache_camera *c, int use, uint32_t frame, wt_point *points)
{
    uint32_t x, y;
    for (y = 0; y < c->height; y++)
        for (x = 0; x < c->width; x++) {
            wt_point *p = &points[(size_t)y * c->width + x];
            p->stream = wt__stream(use, frame, y * c->width + x);
            p->t = 0.0f;
            if (rendercache_camera_ray(c, (float)x + 0.5f, (float)y + 0.5f, p->org, p->dir) != RENDERCACHE_OK)
                p->t = -1.0f;
        }
}

/* Shades the pixels of camera c that have rays. Points without a ray are
   moved out of the way and back. */
static int wt__shade_camera(wt_world *w, const rendercache_camera *c, int use, uint32_t frame, int flags,
                            wt_point *points, uint32_t *index, wt_light_stats *st)
{
    uint32_t n = c->width * c->height, i, m = 0;
    int result;
    wt__camera_points(c, use, frame, points);
    for (i = 0; i < n; i++)   /* compact the pixels with rays to the front, stably */
        if (points[i].t >= 0.0f) {
            index[m] = i;
            if (m != i) points[m] = points[i];
            m++;
        }
    result = wt_shade_points(w, points, m, flags, st, NULL, NULL);
    for (i = m; i-- > 0;)
        if (index[i] != i) {
            points[index[i]] = points[i];
            points[i].t = -1.0f;
        }
    return result;
}

/* A copy of a light-vector cache (through its serialization), or NULL. */
static lightvec_cache *wt__cache_copy(const wt_world *w, const lightvec_cache *c)
{
    lightvec_cache_desc d;
    lightvec_cache *copy = NULL;
    void *data = NULL;
    size_t size = 0;
    memset(&d, 0, sizeof d);
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = w->pool;
    if (lightvec_save_to_memory(c, NULL, &data, &size) == LIGHTVEC_OK)
        lightvec_load_from_memory(data, size, &d, &copy);
    lightvec_free_memory(NULL, data);
    return copy;
}

/* Renders every pixel of camera c at time t with the frames' shading
   (direct light, light vectors looked up and gathered where missing): the
   full render a cached frame is compared with. New light vectors go to
   copies of the caches, so the frames see the caches unchanged. rgb: 3
   floats per pixel; object (optional): WT_OBJECT_* per pixel. */
EX_FN int wt_render_full(wt_world *w, const rendercache_camera *c, double t, uint32_t frame, float *rgb,
                         uint32_t *object)
{
    uint32_t n = c->width * c->height, i;
    wt_point *points = (wt_point *)malloc(sizeof(wt_point) * n);
    uint32_t *index = (uint32_t *)malloc(sizeof(uint32_t) * n);
    lightvec_cache *saved = w->static_cache, *copy = NULL;
    wt_light_stats st = { 0, 0, 0, 0 };
    int result = -1;
    wt_set_time(w, t);
    if (points && index && wt__ensure_pose(w) == 0 && (copy = wt__cache_copy(w, saved)) != NULL) {
        w->static_cache = copy;
        result = wt__shade_camera(w, c, WT_STREAM_FULL, frame, WT_SHADE_DIRECT | WT_SHADE_INSERT | WT_SHADE_LEARNED, points,
                                  index, &st);
        w->static_cache = saved;
        lightvec_cache_destroy(copy);
        pthread_mutex_lock(&w->pose_lock);
        w->pose_ready = 0;   /* the bunny's cache got the full render's vectors: start it anew */
        pthread_mutex_unlock(&w->pose_lock);
        for (i = 0; i < n && result == 0; i++) {
            int k;
            for (k = 0; k < 3; k++) rgb[3 * i + k] = points[i].t >= 0.0f ? points[i].rgb[k] : 0.0f;
            if (object) object[i] = points[i].t >= 0.0f ? points[i].object : RENDERCACHE_NO_SAMPLE;
        }
    }
    free(points);
    free(index);
    return result;
}

/* Converged renders: every pixel gets its own light vector (a gather at
   its point, no interpolation) and many shadow rays. */
#define WT__CONVERGED_STREAM 0xFFFFFFu   /* their random numbers: a stream no frame's number reaches */
typedef struct wt__converged_job {
    wt_world *w;
    wt_point *points;
    uint32_t count;
    lightvec_gather_desc office, bunny;
} wt__converged_job;

static void wt__converged_gather_job(void *ctx, uint32_t batch)
{
    const wt__converged_job *j = (const wt__converged_job *)ctx;
    uint32_t i, end = batch * WT__BATCH + WT__BATCH;
    if (end > j->count) end = j->count;
    for (i = batch * WT__BATCH; i < end; i++) {
        wt_point *p = &j->points[i];
        lightvec_surface s;
        lightvec_record rec;
        if (p->light == WT_LIGHT_NONE) continue;
        wt__surface_of(j->w, p, &s);
        if (lightvec_gather(p->light == WT_LIGHT_BUNNY ? j->w->posed_scene : j->w->office_scene,
                            p->light == WT_LIGHT_BUNNY ? &j->bunny : &j->office, &s, p->stream, &rec) != LIGHTVEC_OK)
            continue;
        wt__indirect(j->w, p, &rec.vector);
        wt__point_radiance(p);
    }
}

/* Renders camera c at time t converged: the frames' shading model (direct
   light plus one light vector per point) without its two approximations,
   i.e. every pixel gathers its own light vector with strata x 3 strata
   rays (no cache, no interpolation, no render-cache reuse) and takes
   light_samples shadow rays, its random numbers from `stream` (as a
   frame's pixels take theirs from the frame's number). Returns 0, or -1
   when out of memory. */
static int wt__render_converged(wt_world *w, const rendercache_camera *c, double t, int strata, int light_samples,
                                uint32_t stream, float *rgb)
{
    uint32_t n = c->width * c->height, i;
    wt_point *points = (wt_point *)malloc(sizeof(wt_point) * n);
    int saved = w->opt.light_samples, result = -1;
    wt__converged_job j;
    wt__job tj;
    wt_set_time(w, t);
    if (points && wt__ensure_pose(w) == 0) {
        wt__camera_points(c, WT_STREAM_FULL, stream, points);
        w->opt.light_samples = light_samples < 1 ? 1 : light_samples > WT__MAX_LIGHT_SAMPLES ? WT__MAX_LIGHT_SAMPLES
                                                                                                : light_samples;
        tj.w = w;
        tj.points = points;
        tj.count = n;
        tj.flags = WT_SHADE_DIRECT;
        ex_pool_parallel_for(w->pool, wt__trace_job, &tj, (n + WT__BATCH - 1) / WT__BATCH);
        w->opt.light_samples = saved;
        for (i = 0; i < n; i++) wt__point_radiance(&points[i]);
        j.w = w;
        j.points = points;
        j.count = n;
        j.office = w->static_gather;
        j.bunny = w->bunny_gather;
        j.office.strata_theta = j.bunny.strata_theta = (uint32_t)(strata < 2 ? 2 : strata);
        j.office.strata_phi = j.bunny.strata_phi = 0;
        ex_pool_parallel_for(w->pool, wt__converged_gather_job, &j, (n + WT__BATCH - 1) / WT__BATCH);
        for (i = 0; i < n; i++) memcpy(&rgb[3 * i], points[i].rgb, sizeof points[i].rgb);
        result = 0;
    }
    free(points);
    return result;
}

/* wt__render_converged with the one stream the tests compare with: the
   measure of the raytrace mode's error (issue: LRMS <= 0.07). */
EX_FN int wt_render_converged(wt_world *w, const rendercache_camera *c, double t, int strata, int light_samples,
                              float *rgb)
{
    return wt__render_converged(w, c, t, strata, light_samples, WT__CONVERGED_STREAM, rgb);
}

/* The exposure of a frame (examples/common/image.h's filmic pipeline):
   opt.exposure when set, else the frame's own key exposure (log-average
   luminance to middle grey), at most WT_EXPOSURE_RANGE times `reference`,
   the first frame's (when > 0): a camera stops down freely in a bright
   room, but opens up only so far, so a room without a lamp still looks
   darker than a lit one. Every frame's exposure depends on its own pixels and the first
   frame's only: the PNGs and the viewer agree for any frame order. */
#define WT_EXPOSURE_RANGE 2.0f

EX_FN float wt_exposure(const wt_options *o, const float *rgb, float reference)
{
    float e;
    if (o->exposure > 0.0f) return o->exposure;
    e = ex_exposure_key(rgb, o->width, o->height);
    if (reference > 0.0f && e > reference * WT_EXPOSURE_RANGE) e = reference * WT_EXPOSURE_RANGE;
    return e;
}

/* Relative luminance RMS error (Nimeroff et al.) of what is displayed:
   both images clamped at the white point 1 / exposure first, so that the
   few pixels of the lamp (radiance 40, a hundred times the room's) weigh
   as white pixels, not as a hundred. Returns 0 or -1. */
EX_FN int wt_display_lrms(const float *reference, const float *image, int width, int height, float exposure,
                          double *lrms)
{
    size_t i, n = 3 * (size_t)width * (size_t)height;
    float white = exposure > 0.0f ? 1.0f / exposure : FLT_MAX;
    float *a = (float *)malloc(sizeof(float) * n), *b = (float *)malloc(sizeof(float) * n);
    int result = -1;
    if (a && b) {
        for (i = 0; i < n; i++) {
            a[i] = reference[i] < white ? reference[i] : white;
            b[i] = image[i] < white ? image[i] : white;
        }
        result = rendercache_lrms(a, b, (uint32_t)width, (uint32_t)height, lrms) == RENDERCACHE_OK ? 0 : -1;
    }
    free(a);
    free(b);
    return result;
}

#define WT_CONVERGED_STRATA 12         /* as the tests' converged renders (tests/test_walkthrough.c) */
#define WT_CONVERGED_LIGHT_SAMPLES 32
#define WT_CONVERGED_VERSION 1u        /* of what the shading converges to (wt__converged_pair) */

/* A camera's place and view in a hash: eye, look-at and up, axis by
   axis, then the field of view (the precompute keys' paths and the
   converged renders' keys). */
static uint64_t wt__camera_hash(uint64_t h, const rendercache_camera *c)
{
    int k;
    for (k = 0; k < 3; k++) h = wt_hash_f32(wt_hash_f32(wt_hash_f32(h, c->eye[k]), c->look_at[k]), c->up[k]);
    return wt_hash_f32(h, c->vfov_degrees);
}

static uint64_t wt__converged_key(const wt_world *w, const rendercache_camera *c, double t)
{
    uint64_t h = wt_hash_str(w->scene_hash, "converged"), bits;
    float pose[12];
    int k;
    h = wt_hash_u64(h, WT_CONVERGED_VERSION);
    h = wt_hash_u64(h, LIGHTVEC_VERSION_MAJOR * 10000u + LIGHTVEC_VERSION_MINOR * 100u + LIGHTVEC_VERSION_PATCH);
    h = wt_hash_u64(h, w->opt.seed);
    h = wt_hash_u64(h, (uint64_t)w->static_gather.bounces << 32 | w->bunny_gather.bounces);
    h = wt_hash_u64(h, (uint64_t)w->opt.bunny_shadow);
    wt_bunny_transform(w, t, pose);
    for (k = 0; k < 12; k++) h = wt_hash_f32(h, pose[k]);
    h = wt_hash_u64(h, (uint64_t)c->kind);
    h = wt__camera_hash(h, c);
    h = wt_hash_u64(h, (uint64_t)c->width << 32 | c->height);
    memcpy(&bits, &t, sizeof bits);
    h = wt_hash_u64(h, bits);
    h = wt_hash_u64(h, WT_CONVERGED_STRATA);
    h = wt_hash_u64(h, WT_CONVERGED_LIGHT_SAMPLES);
    return wt_hash_u64(h, WT__CONVERGED_STREAM);
}

/* The two converged renders of camera c at time t that wt_converged_lrms
   compares with (WT_CONVERGED_STRATA, WT_CONVERGED_LIGHT_SAMPLES, two
   streams), into c1 and c2 (3 x width x height floats each). They cost
   2 x 432 rays a pixel and depend on nothing a frame's renderer chooses,
   so with the precompute cache on (opt.use_cache) they are kept in it,
   keyed by what they depend on: the scene, the bunny's pose at t and its
   contact shadow, the camera, the gathers, the shading model's version and their own
   parameters. A second measure of a walk then renders only its frames.
   WT_CONVERGED_VERSION changes when what the shading model converges to
   changes (a new term, another BRDF), not when only its sampling does: an
   unbiased sampler converges to the same picture. Returns 0, or -1 when
   out of memory. */
static int wt__converged_pair(wt_world *w, const rendercache_camera *c, double t, float *c1, float *c2)
{
    const wt_options *o = &w->opt;
    size_t n = 3 * (size_t)c->width * (size_t)c->height, size = 0;
    uint64_t key = wt__converged_key(w, c, t);
    void *data = NULL;
    char err[256];
    if (o->use_cache && wt_cache_load(o->cache_dir, "converged", key, &data, &size) == 1 &&
        size == 2 * n * sizeof(float)) {
        memcpy(c1, data, n * sizeof(float));
        memcpy(c2, (const float *)data + n, n * sizeof(float));
        free(data);
        return 0;
    }
    free(data);   /* none, damaged or of another size: rendered again */
    if (wt__render_converged(w, c, t, WT_CONVERGED_STRATA, WT_CONVERGED_LIGHT_SAMPLES, WT__CONVERGED_STREAM, c1) != 0 ||
        wt__render_converged(w, c, t, WT_CONVERGED_STRATA, WT_CONVERGED_LIGHT_SAMPLES, WT__CONVERGED_STREAM - 1u, c2) != 0)
        return -1;
    if (o->use_cache && (data = malloc(2 * n * sizeof(float))) != NULL) {   /* a failed store only costs time later */
        memcpy(data, c1, n * sizeof(float));
        memcpy((float *)data + n, c2, n * sizeof(float));
        wt_cache_store(o->cache_dir, "converged", key, data, 2 * n * sizeof(float), err, sizeof err);
        free(data);
    }
    return 0;
}

/* The LRMS of a displayed frame (rgb, shown at `exposure`) against a
   converged render with that render's own noise taken out: issue 19's
   measure (--converged). A converged render (WT_CONVERGED_STRATA,
   WT_CONVERGED_LIGHT_SAMPLES) is itself noisy, 0.034-0.040 LRMS at 320x240
   in the office; so two are made with other random numbers, C1 and C2, and
   with Cm their mean, independent noise gives
   E[LRMS(Cm, frame)^2] = e^2 + s^2 / 2 and E[LRMS(C1, C2)^2] = 2 s^2, s one
   render's noise: e^2 = LRMS(Cm, frame)^2 - LRMS(C1, C2)^2 / 4 (0 if the
   noise's estimate exceeds it). Camera c and time t are the frame's; the
   two renders come from the precompute cache when it holds them
   (wt__converged_pair). Returns 0, or -1 when out of memory. */
EX_FN int wt_converged_lrms(wt_world *w, const rendercache_camera *c, double t, const float *rgb, float exposure,
                            double *lrms)
{
    size_t i, n = 3 * (size_t)c->width * (size_t)c->height;
    float *c1 = (float *)malloc(sizeof(float) * n), *c2 = (float *)malloc(sizeof(float) * n);
    double to_mean = -1.0, apart = -1.0;
    int result = -1;
    if (c1 && c2 && wt__converged_pair(w, c, t, c1, c2) == 0 &&
        wt_display_lrms(c1, c2, (int)c->width, (int)c->height, exposure, &apart) == 0) {
        for (i = 0; i < n; i++) c1[i] = 0.5f * (c1[i] + c2[i]);
        if (wt_display_lrms(c1, rgb, (int)c->width, (int)c->height, exposure, &to_mean) == 0) {
            double e2 = to_mean * to_mean - 0.25 * apart * apart;
            *lrms = e2 > 0.0 ? sqrt(e2) : 0.0;
            result = 0;
        }
    }
    free(c1);
    free(c2);
    return result;
}

/* ======================================================================
   the renderer of a mode: precompute (cached on disk), then frames
   ---------------------------------------------------------------------- */

/* Shading data of the static office for mode radiosity: the discontinuity
   mesh of radinterp.h (Hardt 1996) with one quadratic interpolant per
   triangle, rasterized into the ID + barycentric buffers and shaded per
   pixel. */
typedef struct wt_static_shading {
    radinterp_mesh *mesh;
    radinterp_mesh_data data;   /* positions, indices (raster ids 0 .. triangle_count-1), coefficients,
                                   corner radiosities; valid while mesh lives */
    radinterp_mesh_info info;
    float *normals;             /* unit front normal per triangle (the bunny's occlusion blob) */
    uint64_t key;               /* of the mesh in the precompute cache: the solution and the mesh */
    int reused;                 /* loaded from the precompute cache */
    double seconds_solve, seconds_mesh;
} wt_static_shading;

typedef struct wt_renderer {
    wt_world *w;
    wt_mode mode;
    uint32_t width, height;
    int frames_done;
    wt_point *points;
    uint32_t *index;
    /* what the precompute did, for messages and tests */
    int reused_lightvec, reused_baseviews, reused_visibility, reused_volume;
    uint64_t lightvec_key, baseviews_key;
    double seconds_precompute;
    uint64_t static_vectors;    /* light vectors in the static cache after the precompute */
    /* raytrace */
    rendercache *rc;
    rendercache_pixel_request *req;
    rendercache_sample *samples;
    uint32_t budget;
    float trail_centre[3];      /* the centre of the bunny's bounding sphere in the last frame (wt__age_trail) */
    wt_light *trail_lamps;      /* the lamps' spheres (wt__trail_lamps), trail_lamp_count of them */
    int *trail_lamp_of;         /* each light's lamp */
    unsigned char *trail_seen;  /* 2 x trail_lamp_count: lamps seen around the two centres of a step */
    uint32_t trail_lamp_count;
    float miss_lo[3], miss_hi[3];   /* where a ray that leaves the scene is cached (wt__miss_point) */
    int miss_box;                   /* 0: the scene has no bounds, misses stay directions */
    /* baseviews */
    ex_baseviews bv;
    unsigned char *base_needed; /* per base image (view * time_count + key): some frame warps from it */
    uint32_t base_needed_count;
    double route_length;        /* metres of the camera's route (a planned route's view space) */
    ex_baseviews_reconstructor rec;
    rendercache_range_image *blend[8], *out;
    uint32_t fill_frame;
    float lamp_luminance;       /* WT_BASEVIEWS_LAMP_SHARE of the dimmest lamp's emitted luminance (wt__retraced) */
    float edge_ratio;           /* wt__edge_pixel: depths further apart than this ratio are an edge */
    rendercache_keytimes *bunny_light;   /* the bunny's indirect light at key times (Nimeroff 4.3) */
    float *bunny_indirect;      /* per bunny vertex: its indirect radiance (RGB) at bunny_time */
    double bunny_time;
    uint32_t saved_key_count;   /* key solutions read from the precompute cache, replayed by the solve */
    double *saved_key_times;
    float *saved_key_values;
    int key_replay_missed;      /* a solve found no saved key: the cache entry is stale */
    double seconds_keys;
    /* radiosity */
    wt_static_shading statics;
    irrvol *volume;
    float *visibility;          /* self-occlusion ratio per bunny vertex */
    float *bunny_world, *bunny_world_normals, *bunny_rgb;
    double *tile_cpu;           /* per raster tile: its shading's thread CPU seconds this frame */
    float bunny_centre[3];      /* the bunny's occlusion sphere: centre in OBJ coordinates */
    float bunny_radius;         /* its radius in metres (wt_bunny_sphere) */
    float sphere[4];            /* this frame's: world centre, radius */
    int blob_box[4];            /* this frame's pixels the blob may touch: x0, y0, x1, y1 (exclusive) */
    ex_raster raster;
} wt_renderer;

static void wt__say(const wt_world *w, const char *fmt, ...)
{
    va_list ap;
    if (!w->opt.verbose) return;
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    fflush(stdout);
}

/* ---- light vectors of the office: a warm-up along the path ------------- */

/* Hash of the paths: every frame's camera and the bunny at 65 times. */
static uint64_t wt__path_hash(const wt_world *w, uint64_t h)
{
    int f, k;
    for (f = 0; f < w->opt.frames; f++) {
        rendercache_camera c = wt_camera(&w->opt, wt_frame_time(&w->opt, f), 8, 8);
        h = wt__camera_hash(h, &c);
    }
    for (f = 0; f <= 64; f++) {
        float m[12];
        wt_bunny_transform(w, f / 64.0, m);
        for (k = 0; k < 12; k++) h = wt_hash_f32(h, m[k]);
    }
    return h;
}

/* Key of the static light-vector cache: the scene, the gathers, the path. */
static uint64_t wt__lightvec_key(const wt_world *w)
{
    const wt_options *o = &w->opt;
    uint64_t h = wt_hash_str(w->scene_hash, "lightvec");
    h = wt__path_hash(w, h);
    h = wt_hash_u64(h, LIGHTVEC_FILE_FORMAT_VERSION);
    h = wt_hash_u64(h, LIGHTVEC_VERSION_MAJOR * 10000u + LIGHTVEC_VERSION_MINOR * 100u + LIGHTVEC_VERSION_PATCH);
    h = wt_hash_u64(h, WT_PATH_VERSION);
    h = wt_hash_u64(h, WT_SHADING_VERSION);
    h = wt_hash_u64(h, o->seed);
    h = wt_hash_u64(h, (uint64_t)o->strata);
    h = wt_hash_u64(h, (uint64_t)w->static_gather.bounces);
    h = wt_hash_u64(h, (uint64_t)o->warmup_divisor);
    h = wt_hash_u64(h, (uint64_t)o->width);
    h = wt_hash_u64(h, (uint64_t)o->height);
    h = wt_hash_u64(h, (uint64_t)o->frames);
    return h;
}

/* Fills the static cache with the light vectors the path's views need,
   seen at 1/warmup_divisor of the frame size: the cached frames then
   mostly look vectors up (Crespin & Peroche's first picture, moved into
   the precompute). */
static int wt__warm_up(wt_renderer *r)
{
    wt_world *w = r->w;
    const wt_options *o = &w->opt;
    uint32_t ww = r->width / (uint32_t)o->warmup_divisor, hh = r->height / (uint32_t)o->warmup_divisor;
    wt_light_stats st = { 0, 0, 0, 0 };
    wt_progress bar;
    int f;
    if (ww < 8) ww = 8;
    if (hh < 8) hh = 8;
    wt_progress_begin(&bar, "light vectors along the path", o->progress);
    for (f = 0; f < o->frames; f++) {
        double t = wt_frame_time(o, f);
        rendercache_camera c = wt_camera(o, t, ww, hh);
        wt_set_time(w, t);
        if (wt__shade_camera(w, &c, WT_STREAM_WARMUP, (uint32_t)f, WT_SHADE_INSERT | WT_SHADE_STATIC_ONLY, r->points,
                             r->index, &st) != 0)
            return -1;
        wt_progress_update(&bar, (uint64_t)f + 1, (uint64_t)o->frames);
    }
    wt_progress_end(&bar);
    return lightvec_cache_optimize(w->static_cache) == LIGHTVEC_OK ? 0 : -1;
}

/* The static light-vector cache: loaded from the precompute cache, or
   warmed up and saved. */
static int wt__static_lightvec(wt_renderer *r, char *err, size_t err_size)
{
    wt_world *w = r->w;
    const wt_options *o = &w->opt;
    uint64_t key = wt__lightvec_key(w);
    char path[1024];
    void *data = NULL;
    size_t size = 0;
    lightvec_cache_stats info;
    double t0 = wt_seconds();
    int got = 0;
    r->lightvec_key = key;
    wt_cache_path(o->cache_dir, "lightvec", key, path, sizeof path);
    if (o->use_cache) got = wt_cache_load(o->cache_dir, "lightvec", key, &data, &size);
    if (got == 1) {
        lightvec_cache_desc d;
        lightvec_cache *c = NULL;
        memset(&d, 0, sizeof d);
        d.parallel_for = ex_pool_parallel_for;
        d.parallel_user = w->pool;
        if (lightvec_load_from_memory(data, size, &d, &c) == LIGHTVEC_OK) {
            lightvec_cache_destroy(w->static_cache);
            w->static_cache = c;
            r->reused_lightvec = 1;
        } else {
            got = -1;
        }
        free(data);
        data = NULL;
    }
    if (got == -1) wt__say(w, "light vectors: %s is damaged, rebuilding it\n", path);
    if (!r->reused_lightvec) {
        lightvec_cache *copy;
        if (wt__warm_up(r) != 0) {
            snprintf(err, err_size, "the light-vector warm-up failed (out of memory)");
            return -1;
        }
        /* the frames use the cache as a later run will load it (the same
           kd-trees, so the same sums in the same order) */
        if (!(copy = wt__cache_copy(w, w->static_cache))) return wt__fail(err, err_size, "%s", "out of memory");
        lightvec_cache_destroy(w->static_cache);
        w->static_cache = copy;
        if (o->use_cache) {
            lightvec_result lr = lightvec_save_to_memory(w->static_cache, NULL, &data, &size);
            if (lr != LIGHTVEC_OK || wt_cache_store(o->cache_dir, "lightvec", key, data, size, err, err_size) != 0) {
                if (lr != LIGHTVEC_OK) snprintf(err, err_size, "lightvec_save_to_memory: %s", lightvec_result_string(lr));
                wt__say(w, "light vectors: not cached (%s)\n", err);
                err[0] = 0;
            }
            lightvec_free_memory(NULL, data);
        }
    }
    lightvec_cache_info(w->static_cache, &info);
    r->static_vectors = info.record_count;
    if (w->opt.verbose) {
        if (r->reused_lightvec)
            printf("light vectors: reused the precompute cache %s (%llu vectors)\n", path,
                   (unsigned long long)info.record_count);
        else
            printf("light vectors: %llu computed along the path in %.1f s%s%s\n", (unsigned long long)info.record_count,
                   wt_seconds() - t0, o->use_cache ? ", saved to " : " (cache off)", o->use_cache ? path : "");
        fflush(stdout);
    }
    return 0;
}

/* ---- mode raytrace ------------------------------------------------------ */

/* The render cache's requests at the image's steps (rendercache_desc.
   edge_fraction; edge_step at its default, 0.5): points of earlier frames
   land anywhere in their pixel, and at a depth edge, a shadow's edge or a
   wall's corner a pixel often shows a point of the other side. Measured
   against converged renders (12 strata, 32 shadow rays; pooled LRMS at
   160x120, office frames 7-47 every 8th, building_1k frames 7-247 every
   24th), without steps 0.109 and 0.194; the walkthrough's own requests at
   steps before (half the budget) 0.079 and 0.152; edge_fraction 0.5 (up
   to half the requests for the current camera; steps taken in scan order,
   before they were spread) 0.079 and 0.165, 0.67: 0.079 and 0.149, 1 (the
   priority image gets what the steps leave): 0.078 and 0.128; spread
   over the steps when they are more than the budget: 1: 0.078 and 0.120,
   0.85: 0.079 and 0.128, 0.75: 0.079 and 0.133. Where steps are many against
   the budget (test_walkthrough's 64x48 walk of 24 frames: fast, with many
   holes) 1 starves the holes: pooled 0.155 without steps, 0.144 with the
   walkthrough's own requests before, 0.186 with 1,
   0.141 with 0.85, 0.128 with 0.75, 0.129 with 0.65, 0.135 with 0.5.
   edge_step (with 1) 0.4: 0.077 and 0.141, 0.6: 0.082 and 0.110; with
   0.75 (office, building, 64x48) 0.4: 0.077, 0.132, 0.136; 0.5: 0.079,
   0.133, 0.128; 0.6: 0.083, 0.124, 0.121: the office wants small steps,
   the others large ones, so the default stays (single frames of the
   building move by 0.05 as the requests change: within the noise); requesting steps only where a point shows (holes left to the
   priority image): 0.150 at 64x48. */
#define WT__EDGE_FRACTION 0.75f

/* A ray that leaves the scene (a window at night, the sky by day) is
   cached where it leaves the scene's bounds, a margin outside them, as a
   point of the static scene, not as a direction (RENDERCACHE_MISS). A
   direction is right only for an eye that turns: once the eye moves, a
   direction seen through a window is a wall's, and in the holes of a fast
   walk nothing near culled it (the house at 320x240 in 48 frames: black
   blobs on the stair walls, frames 29-32, LRMS 0.51-0.70, 434 of them
   shown in frame 30 while no ray of frame 30 missed). On the bounds, the
   point moves with the window it was seen through and the window's wall
   culls it. The sky's colour is kept as seen from the eye that traced it
   (its direction changes with the eye's place; its age refreshes it). */
#define WT__MISS_MARGIN 0.05f   /* m outside the scene's bounds */

static int wt__miss_box(const wt_world *w, float lo[3], float hi[3])
{
    int k;
    if (!obj_bounds(&w->office, lo, hi)) return 0;
    for (k = 0; k < 3; k++) {
        lo[k] -= WT__MISS_MARGIN;
        hi[k] += WT__MISS_MARGIN;
    }
    return 1;
}

/* Where the ray (org, dir) leaves the box of wt__miss_box: returns 1 and
   the point, or 0 when the eye is outside it (the miss stays a direction). */
static int wt__miss_point(const wt_renderer *r, const float org[3], const float dir[3], float pos[3])
{
    float t = FLT_MAX;
    int k;
    if (!r->miss_box) return 0;
    for (k = 0; k < 3; k++) {
        if (!(org[k] > r->miss_lo[k] && org[k] < r->miss_hi[k])) return 0;
        if (dir[k] != 0.0f) {
            float tk = ((dir[k] > 0.0f ? r->miss_hi[k] : r->miss_lo[k]) - org[k]) / dir[k];
            if (tk < t) t = tk;
        }
    }
    if (!(t < FLT_MAX)) return 0;
    for (k = 0; k < 3; k++) pos[k] = org[k] + t * dir[k];
    return 1;
}

static int wt__raytrace_create(wt_renderer *r, char *err, size_t err_size)
{
    rendercache_desc d;
    uint32_t n = r->width * r->height;
    rendercache_result rr;
    if (wt__static_lightvec(r, err, err_size) != 0) return -1;
    memset(&d, 0, sizeof d);
    d.width = r->width;
    d.height = r->height;
    d.object_count = 2;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = r->w->pool;
    d.clock = wt__clock;
    d.edge_fraction = WT__EDGE_FRACTION;
    d.refill_samples = 1;   /* each frame is shown after its samples are in */
    rr = rendercache_create(&d, &r->rc);
    r->budget = (uint32_t)(r->w->opt.budget * (float)n + 0.5f);
    if (r->budget < 1) r->budget = 1;
    r->miss_box = wt__miss_box(r->w, r->miss_lo, r->miss_hi);
    r->req = (rendercache_pixel_request *)malloc(sizeof *r->req * n);
    r->samples = (rendercache_sample *)malloc(sizeof *r->samples * n);
    if (rr != RENDERCACHE_OK || !r->req || !r->samples) {
        snprintf(err, err_size, "cannot create the render cache: %s",
                 rr != RENDERCACHE_OK ? rendercache_result_string(rr) : "out of memory");
        return -1;
    }
    return 0;
}

/* The narrowest view lobe of the highlights a glossy point p could show
   (wt__view_lobe), or `lobe` when none is narrower. A light's mirror image
   lies on p when the mirror direction of the view points at the light;
   the mirror direction turns by as much as the view does (a reflection
   keeps angles), so from the eye that shaded p the highlight is a turn
   theta away: the angle from the mirror direction to the light's centre,
   less the light's angular radius. How bright it would be, relative to
   p's radiance: the normalised Phong lobe over the light's solid angle
   Omega, whole once the light fills it, Ks L cos_x min(1, Omega (n + 2) /
   (2 pi)); and at most the ratio of that to the light's diffuse light,
   Ks / Kd pi min((n + 2) / (2 pi), 1 / Omega), times the direct diffuse
   light p received (a point in shadow shows no highlight): P. The
   highlight's error a turn x short of it is about P exp(-x^2 / (2 s_n^2)),
   half of p's radiance after a turn of theta - s_n sqrt(2 ln 2P) (P >
   1/2); the lobe is that turn, or 0, plus s_n / (2 P): the lobe of a
   highlight already on p (theta 0) by wt__view_lobe's rule, and so a faint one
   (P small) stays wide. The render cache's clock is the turn in any
   direction, so a point a turn theta from a highlight is resampled after
   a turn of about theta away from it too; only points that could show a
   bright highlight within that turn pay for it. Lights: those of the
   grid's neighbourhood flag (all without a grid). */
static float wt__highlight_lobe(const wt_world *w, const wt_point *p, const lightvec_material *m, float s_n, float lobe)
{
    const float *seen = wt__lights_seen(w, p->pos);
    const float *n = p->normal, *x = p->pos;
    float vn = -(p->dir[0] * n[0] + p->dir[1] * n[1] + p->dir[2] * n[2]), mirror[3];
    float ks = wt__luminance(m->specular), kd = wt__luminance(m->diffuse);
    float radiance = wt__luminance(p->direct) + p->contact * wt__luminance(p->indirect);
    float diffuse = wt__luminance(p->direct) - wt__luminance(p->direct_gloss);   /* the direct diffuse light */
    float cone = (m->exponent + 2.0f) / (2.0f * WT_PI);
    uint32_t e;
    int k;
    if (!(radiance > 0.0f) || !(diffuse > 0.0f)) return lobe;
    for (k = 0; k < 3; k++) mirror[k] = p->dir[k] + 2.0f * vn * n[k];
    for (e = 0; e < w->light_count; e++) {
        const wt_light *L = &w->lights[e];
        float v[3] = { L->centre[0] - x[0], L->centre[1] - x[1], L->centre[2] - x[2] };
        float d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2], d, cos_x, cos_y, omega, peak, P, theta, c;
        if (seen && !(seen[2 * e] > 0.0f)) continue;
        if (!(d2 > L->radius * L->radius)) continue;   /* inside its sphere: the mirror image is everywhere */
        if ((x[0] - L->point[0]) * L->normal[0] + (x[1] - L->point[1]) * L->normal[1] + (x[2] - L->point[2]) * L->normal[2] <=
            0.0f)
            continue;   /* behind the emitter: one-sided */
        d = sqrtf(d2);
        cos_x = (v[0] * n[0] + v[1] * n[1] + v[2] * n[2]) / d;
        cos_y = -(v[0] * L->normal[0] + v[1] * L->normal[1] + v[2] * L->normal[2]) / d;
        if (cos_x <= 0.0f || cos_y <= 0.0f) continue;
        omega = fminf(L->area * cos_y / d2, 2.0f * WT_PI);
        peak = ks * wt__luminance(L->ke) * cos_x * fminf(1.0f, omega * cone);
        if (kd > 0.0f) peak = fminf(peak, ks / kd * WT_PI * fminf(cone, 1.0f / omega) * diffuse);
        P = peak / radiance;
        if (!(s_n / (2.0f * P) < lobe)) continue;   /* no narrower than the lobe so far, whatever theta */
        c = (mirror[0] * v[0] + mirror[1] * v[1] + mirror[2] * v[2]) / d;
        theta = acosf(fminf(fmaxf(c, -1.0f), 1.0f)) - asinf(L->radius / d);
        if (2.0f * P > 1.0f) theta -= s_n * sqrtf(2.0f * logf(2.0f * P));
        lobe = fminf(lobe, fmaxf(theta, 0.0f) + s_n / (2.0f * P));
    }
    return lobe;
}

/* The view lobe of a point for the render cache (rendercache_sample.
   view_lobe): how far the view may turn before its colour is as stale as
   a point of age age_ramp. WDP99 ages points to find stale colours; age
   is the wrong clock for a highlight, which slides over the floor as the
   eye moves while the diffuse light stays put. The glossy part of a
   point's radiance is its light blurred by the Phong lobe, a Gaussian of
   angular radius s_n = acos(exp(-1 / (2n))) (GLOSSY SURFACES in
   lightvec.h), so seen from a direction turned by omega it is off by about
   share * omega / s_n of the point's radiance (share: wt_point.view_share).
   The render cache ranks a point turned by one lobe as one of age
   age_ramp, at RENDERCACHE__PRIORITY_POINT_MAX = 0.5 (times its scale),
   with the holes (0.5 to 0.95); the lobe s_n / (2 share) puts a highlight
   there once it is about half wrong, as a hole is. The cache measures the
   turn from the eye that shaded the point to the current eye every frame,
   so points of the first frame age too, and a point seen again from where
   it was shaded is fresh again. 0 for view-independent points. Measured
   against converged renders (12 strata, 32 shadow rays) at 160x120,
   pooled LRMS, against the one-step scale fixed at insertion it replaces:
   building (every 24th frame from 7) 0.3129 -> 0.3031, office (every 8th
   from 7) 0.1136 -> 0.1126; the lobe s_n / share 0.3015 / 0.1175, no
   view term at all 0.1233 in the office.
   A point that shows no highlight has the share of its eye, near 0, and
   so a lobe too wide to ever age, yet a lamp's highlight may lie a small
   turn away: the house's wood floor shaded from afar at a grazing angle
   stayed dark while the eye came close and looked down into the ceiling
   lamp's mirror image (frame 29: 0.111 against converged, the reuse alone
   0.097 of it). There, floor points shaded 1 to 15 frames before with
   lobes of 0.3 to 3 rad (shares 0.03 to 0.26: no highlight in their
   eye's view) held 47 % of the squared error on 4 % of the pixels, and
   75 % of the error was the frame darker than converged. So the lobe is
   also that of the highlights the point could show (wt__highlight_lobe),
   the narrowest of the two. Measured (release, 320x240, 2 threads,
   against converged renders with their noise taken out, wt_converged_lrms),
   the house's default walk, frames 29 to 269 every 30: 0.1109, 0.0784,
   0.0395, 0.0710, 0.0602, 0.0723, 0.0764, 0.0723, 0.1536 (mean 0.0816)
   -> 0.0780, 0.0678, 0.0407, 0.0731, 0.0607, 0.0744, 0.0535, 0.0684,
   0.1519 (mean 0.0743); the office (48 frames, every 8th from 7) mean
   0.0593 -> 0.0576, no frame worse. A lobe floor at the material's own
   share instead, Ks / (Kd + Ks) (0.54 rad for every wood point), gave
   frame 29 0.095 but a mean of 0.0810: it spent the budget on points no
   highlight could reach. */
static float wt__view_lobe(const wt_world *w, const wt_point *p, const lightvec_material *m)
{
    float s_n, lobe;
    if (p->object == RENDERCACHE_MISS || !(m->exponent > 0.0f) || !(wt__luminance(m->specular) > 0.0f)) return 0.0f;
    s_n = acosf(expf(-0.5f / m->exponent));
    if (!(s_n > 0.0f)) return 0.0f;
    lobe = p->view_share > 0.0f ? s_n / (2.0f * p->view_share) : FLT_MAX;
    lobe = wt__highlight_lobe(w, p, m, s_n, lobe);
    return lobe < FLT_MAX ? lobe : 0.0f;
}

/* The lamps: the lights whose bounding spheres overlap, joined (a lamp's
   faces are lights of their own: the office's lamp is 6). lamp_of[e] is
   light e's lamp; returns the number of lamps. */
static uint32_t wt__lamps(const wt_world *w, int *lamp_of)
{
    uint32_t e, f, lamps = 0;
    for (e = 0; e < w->light_count; e++) lamp_of[e] = -1;
    for (e = 0; e < w->light_count; e++) {   /* flood: e's lamp takes every light touching one of it */
        uint32_t changed = 1;
        if (lamp_of[e] >= 0) continue;
        lamp_of[e] = (int)lamps;
        while (changed)
            for (changed = 0, f = 0; f < w->light_count; f++) {
                uint32_t g;
                if (lamp_of[f] >= 0) continue;
                for (g = 0; g < w->light_count; g++) {
                    const wt_light *a = &w->lights[f], *b = &w->lights[g];
                    float d2 = 0.0f;
                    int k;
                    if (lamp_of[g] != (int)lamps) continue;
                    for (k = 0; k < 3; k++) d2 += (a->centre[k] - b->centre[k]) * (a->centre[k] - b->centre[k]);
                    if (d2 <= (a->radius + b->radius) * (a->radius + b->radius)) {
                        lamp_of[f] = (int)lamps;
                        changed = 1;
                        break;
                    }
                }
            }
        lamps++;
    }
    return lamps;
}

/* The trails behind the bunny (issues 16 and 19): the render cache only
   learns that the light changed where its samples land, so the floor the
   bunny shadowed kept its dark colour, and the floor it now shadows its
   lit one, until their age came up: a dark trail followed it. The
   walkthrough knows what moved: every frame it ages
   (rendercache_invalidate_where) the points whose light the bunny's step
   may have changed: those from which a lamp (a sphere around the
   emitting polygons of one lamp, wt__trail_lamps) is partly hidden by
   the bunny's bounding sphere at its last or
   its new place (the old shadow and the new one), and those within its
   contact shadow's reach (wt__contact_occlusion) of either, the bunny's
   own points among them. In a building only the lights the grid says are
   seen around the bunny's centres (wt__lights_seen's neighbourhood flag)
   count: a lamp behind a wall casts no shadow of the bunny, and its cones
   would age the floor of the next room for nothing. The points are aged as
   a colour change ages them (they rank with the least urgent holes):
   aged as rendercache_invalidate ages an object's points, above every
   hole, the office's region (up to a fifth of its image) took the budget
   from the holes, pooled LRMS against converged renders (160x120, frames
   7-47 every 8th) 0.079 -> 0.100; as now 0.079, and 0.081 -> 0.076 over
   the pixels whose floor lay in the bunny's cones or reach in the last 8
   frames. In a probe of the house at 320x240 (48 frames, frame 4) the
   floor behind the bunny showed points 1-2 frames old at a fifth of their
   brightness before, and only points of the current frame now (the holes
   between them: rendercache refills them since v0.9.0). Cost, one core,
   640x480: a light per face made the office's cache phase 24 -> 60 ms a
   frame; a sphere per lamp, 39 ms. LRMS against full renders
   (`--reference`, 320x240, with the refill): office 0.0736 without the
   ageing, 0.0727 with it; the house (48 frames) 0.2352 and 0.2338. */
typedef struct wt__trail {
    const wt_light *lamps;   /* a sphere around each lamp (wt__lamps): a lamp's faces count once */
    uint32_t lamp_count;
    const unsigned char *seen[2];   /* per lamp: one of its lights is seen around the two centres */
    float centre[2][3];   /* the bounding sphere's centre at the last and at the new place */
    float radius;         /* its radius, with a margin for the cone's slope */
    float near2;          /* squared reach of the contact shadow from the centre */
} wt__trail;

/* Does the sphere (c, rb) cross the cone from p to the light's sphere?
   At the closest point of the axis to c, a fraction t of the way, the cone
   is t * L->radius wide. */
static int wt__hides_light(const float p[3], const float c[3], float rb, const wt_light *L)
{
    float d[3], v[3], dd = 0.0f, t = 0.0f, e2 = 0.0f, reach;
    int k;
    for (k = 0; k < 3; k++) {
        d[k] = L->centre[k] - p[k];
        v[k] = c[k] - p[k];
        dd += d[k] * d[k];
        t += v[k] * d[k];
    }
    if (!(dd > 0.0f) || t <= 0.0f) return 0;   /* behind the point: the contact reach covers a touching one */
    t = t < dd ? t / dd : 1.0f;
    for (k = 0; k < 3; k++) e2 += (v[k] - t * d[k]) * (v[k] - t * d[k]);
    reach = rb + t * L->radius;
    return e2 <= reach * reach;
}

/* rendercache_invalidate_where's predicate: near either centre, or a
   light (that the bunny's place sees) partly hidden from p at either. */
static int wt__trail_changed(void *user, const float p[3], uint32_t object)
{
    const wt__trail *tr = (const wt__trail *)user;
    uint32_t e;
    int i, k;
    (void)object;
    for (i = 0; i < 2; i++) {
        float d2 = 0.0f;
        for (k = 0; k < 3; k++) d2 += (p[k] - tr->centre[i][k]) * (p[k] - tr->centre[i][k]);
        if (d2 <= tr->near2) return 1;
    }
    for (e = 0; e < tr->lamp_count; e++)
        for (i = 0; i < 2; i++)
            if (tr->seen[i][e] && wt__hides_light(p, tr->centre[i], tr->radius, &tr->lamps[e])) return 1;
    return 0;
}

/* The trail of the bunny's step from the bounding sphere's centre from to
   the one to. */
static void wt__trail_make(const wt_renderer *r, const float from[3], const float to[3], wt__trail *tr)
{
    const wt_world *w = r->w;
    float reach = (1.0f + WT_CONTACT_REACH) * w->bunny_bound_radius;
    uint32_t i, e;
    tr->lamps = r->trail_lamps;
    tr->lamp_count = r->trail_lamp_count;
    memcpy(tr->centre[0], from, sizeof tr->centre[0]);
    memcpy(tr->centre[1], to, sizeof tr->centre[1]);
    for (i = 0; i < 2; i++) {
        const float *seen = wt__lights_seen(w, tr->centre[i]);   /* NULL without a grid: every light counts */
        unsigned char *lamp_seen = r->trail_seen + i * (size_t)r->trail_lamp_count;
        memset(lamp_seen, 0, r->trail_lamp_count);
        for (e = 0; e < w->light_count; e++) lamp_seen[r->trail_lamp_of[e]] |= !seen || seen[2 * e] > 0.0f;
        tr->seen[i] = lamp_seen;
    }
    tr->radius = w->bunny_bound_radius * 1.05f;
    tr->near2 = reach * reach;
}

/* The lamps' spheres for the trail (made once): each bounds the spheres of
   its lights. A light of its own per face tested 6 cones in the office's
   lamp instead of 1, 16 in the house instead of 3. */
static int wt__trail_lamps(wt_renderer *r)
{
    const wt_world *w = r->w;
    uint32_t n = w->light_count ? w->light_count : 1, e, l;
    int k;
    r->trail_lamp_of = (int *)malloc(sizeof *r->trail_lamp_of * n);
    r->trail_lamps = (wt_light *)calloc(n, sizeof *r->trail_lamps);
    r->trail_seen = (unsigned char *)malloc(2 * (size_t)n);
    if (!r->trail_lamp_of || !r->trail_lamps || !r->trail_seen) return -1;
    r->trail_lamp_count = wt__lamps(w, r->trail_lamp_of);
    for (l = 0; l < r->trail_lamp_count; l++) {
        wt_light *L = &r->trail_lamps[l];
        float lo[3] = { FLT_MAX, FLT_MAX, FLT_MAX }, hi[3] = { -FLT_MAX, -FLT_MAX, -FLT_MAX };
        for (e = 0; e < w->light_count; e++)
            if (r->trail_lamp_of[e] == (int)l)
                for (k = 0; k < 3; k++) {
                    lo[k] = fminf(lo[k], w->lights[e].centre[k] - w->lights[e].radius);
                    hi[k] = fmaxf(hi[k], w->lights[e].centre[k] + w->lights[e].radius);
                }
        for (k = 0; k < 3; k++) L->centre[k] = 0.5f * (lo[k] + hi[k]);
        for (e = 0; e < w->light_count; e++)
            if (r->trail_lamp_of[e] == (int)l) {
                float d2 = 0.0f;
                for (k = 0; k < 3; k++) d2 += (w->lights[e].centre[k] - L->centre[k]) * (w->lights[e].centre[k] - L->centre[k]);
                L->radius = fmaxf(L->radius, sqrtf(d2) + w->lights[e].radius);
            }
    }
    return 0;
}

/* Ages the points where the bunny's step from the last frame's place to
   the current pose (w->pose) may have changed the light (wt__trail).
   Called between frames, before begin_frame: the _next_frame form, whose
   ageing begin_frame's ranking of every pixel takes up (the last frame's
   priority image, which invalidate_where would update, is not read
   again). */
static int wt__age_trail(wt_renderer *r, int full)
{
    wt__trail tr;
    float now[3];
    int moved;
    if (!r->trail_lamps && wt__trail_lamps(r) != 0) return -1;
    ex__affine_point(r->w->pose, r->w->bunny_bound_centre, now);
    moved = memcmp(now, r->trail_centre, sizeof now) != 0;
    wt__trail_make(r, r->trail_centre, now, &tr);
    memcpy(r->trail_centre, now, sizeof now);
    if (full || !moved) return 0;   /* nothing cached yet, or the bunny stands still */
    return rendercache_invalidate_where_next_frame(r->rc, wt__trail_changed, &tr, NULL) == RENDERCACHE_OK ? 0 : -1;
}

/* One frame of the render cache: reproject, request, shade, insert. The
   first frame requests every pixel (the render cache starts empty). */
static int wt__raytrace_view(wt_renderer *r, const rendercache_camera *camera, const rendercache_camera *next, double t,
                             int frame, float *rgb, wt_frame_stats *st)
{
    wt_world *w = r->w;
    double t0 = wt_seconds(), a;
    rendercache_camera cam = *camera;
    wt_light_stats ls = { 0, 0, 0, 0 };
    uint32_t n = 0, i;
    int full = r->frames_done == 0;
    wt_set_time(w, t);
    a = wt_seconds();
    if (wt__age_trail(r, full) != 0) return -1;
    /* After the first frame, predictive sampling (WDG02): the pass that
       reprojects the points also seeds the holes the next camera will see. */
    if (rendercache_set_object_transform(r->rc, WT_OBJECT_BUNNY, w->pose) != RENDERCACHE_OK ||
        (!full && next ? rendercache_begin_frame_predicted(r->rc, &cam, next) : rendercache_begin_frame(r->rc, &cam)) !=
            RENDERCACHE_OK)
        return -1;
    if (full) {
        for (i = 0; i < r->width * r->height; i++) {
            rendercache_pixel_request *q = &r->req[i];
            q->x = i % r->width;
            q->y = i / r->width;
            q->flags = 0;
            q->frame = 0;   /* the current frame */
            rendercache_camera_ray(&cam, (float)q->x + 0.5f, (float)q->y + 0.5f, q->org, q->dir);
        }
        n = r->width * r->height;
    } else {
        if (rendercache_request(r->rc, r->req, r->budget, &n) != RENDERCACHE_OK) return -1;
    }
    st->phase[0] += wt_seconds() - a;
    for (i = 0; i < n; i++) {
        wt_point *p = &r->points[i];
        memcpy(p->org, r->req[i].org, sizeof p->org);
        memcpy(p->dir, r->req[i].dir, sizeof p->dir);
        p->stream = wt__stream(WT_STREAM_FRAME, (uint32_t)frame, r->req[i].y * r->width + r->req[i].x +
                               (r->req[i].flags ? r->width * r->height : 0u));
    }
    if (wt_shade_points(w, r->points, n, WT_SHADE_DIRECT | WT_SHADE_INSERT | WT_SHADE_LEARNED | WT_SHADE_LEARN, &ls,
                        &st->phase[1], &st->phase[2]) != 0)
        return -1;
    wt__light_learn_merge(w);   /* the next frame's picks see this frame's shadow rays */
    for (i = 0; i < n; i++) {
        const wt_point *p = &r->points[i];
        rendercache_sample *s = &r->samples[i];
        s->frame = r->req[i].frame;
        s->x = r->req[i].x;
        s->y = r->req[i].y;
        s->flags = r->req[i].flags;
        s->object = p->object;
        memcpy(s->position, p->pos, sizeof s->position);
        if (p->object == RENDERCACHE_MISS && wt__miss_point(r, p->org, p->dir, s->position)) s->object = WT_OBJECT_OFFICE;
        memcpy(s->rgb, p->rgb, sizeof s->rgb);
        /* Crespin & Peroche 4.3: an interpolated light vector of weight W
           makes its point's priority 1/W times higher; a vector computed
           for the point itself has weight 1 */
        s->priority_scale = p->light != WT_LIGHT_NONE && !p->gathered ? lightvec_priority(1.0f, p->weight) : 1.0f;
        /* the bunny's light changes as it walks (the desk's shadow, the
           divider's colour), and so does the light of the floor it shadows:
           these points are refreshed first (the 1/W scale raises the
           priority of every static point lit by an interpolated vector) */
        if (p->object == WT_OBJECT_BUNNY || p->bunny_shadow) s->priority_scale *= WT_BUNNY_PRIORITY;
        s->view_lobe = wt__view_lobe(w, p, &w->materials[p->material]);
    }
    a = wt_seconds();
    if (rendercache_insert(r->rc, r->samples, n, NULL) != RENDERCACHE_OK) return -1;
    st->phase[0] += wt_seconds() - a;
    memcpy(rgb, rendercache_image(r->rc), sizeof(float) * 3 * r->width * r->height);
    st->samples = n;
    st->full = full;
    st->lookups = ls.lookups;
    st->hits = ls.hits;
    st->gathers = ls.gathers;
    st->bunny_gathers = ls.bunny_gathers;
    st->total = wt_seconds() - t0;
    return 0;
}

static int wt__raytrace_frame(wt_renderer *r, int frame, float *rgb, wt_frame_stats *st)
{
    const wt_options *o = &r->w->opt;
    double t = wt_frame_time(o, frame);
    rendercache_camera cam = wt_camera(o, t, r->width, r->height), next;
    if (frame + 1 < o->frames) next = wt_camera(o, wt_frame_time(o, frame + 1), r->width, r->height);
    return wt__raytrace_view(r, &cam, frame + 1 < o->frames ? &next : NULL, t, frame, rgb, st);
}

/* ---- mode baseviews ----------------------------------------------------- */

typedef struct wt__ids_job {
    wt_world *w;
    const rendercache_camera *camera;
    uint32_t *ids;
} wt__ids_job;

static void wt__ids_row(void *ctx, uint32_t y)
{
    const wt__ids_job *j = (const wt__ids_job *)ctx;
    const rendercache_camera *c = j->camera;
    uint32_t x;
    for (x = 0; x < c->width; x++) {
        float org[3], dir[3], through[3];
        ex_trace_hit h;
        uint32_t *id = &j->ids[(size_t)y * c->width + x];
        if (rendercache_camera_ray(c, (float)x + 0.5f, (float)y + 0.5f, org, dir) != RENDERCACHE_OK)
            *id = RENDERCACHE_NO_SAMPLE;
        else if (!ex_tracer_intersect_through(j->w->tracer, org, dir, FLT_MAX, &h, through))
            *id = RENDERCACHE_MISS;   /* what the frames show: the surface behind the glass */
        else   /* one id per polygon, as the paper's id images */
            *id = h.instance == EX_TRACE_STATIC ? j->w->office.tri_face[h.tri] : j->w->office.face_count + h.tri;
    }
}

/* The coherence tests' callback: an id image of camera at time. */
static int wt__render_ids(void *user, const rendercache_camera *camera, double time, uint32_t *ids)
{
    wt__ids_job j;
    j.w = (wt_world *)user;
    j.camera = camera;
    j.ids = ids;
    wt_set_time(j.w, time);
    ex_pool_parallel_for(j.w->pool, wt__ids_row, &j, camera->height);
    return 0;
}

/* Transforms of the range images' objects at time t: the office stays, the
   bunny walks. */
static void wt__object_transforms(void *user, double t, float *m)
{
    const wt_world *w = (const wt_world *)user;
    memset(m, 0, 12 * sizeof(float));
    m[0] = m[5] = m[10] = 1.0f;
    wt_bunny_transform(w, t, m + 12);
}

/* The office's base views look along the mean view direction of the path,
   from a box around the path's eyes (a line along the front wall). A planned
   route has its own view space (wt__route_view). */
static void wt__view_space(const wt_options *o, float lo[3], float hi[3], float axis[3])
{
    int f, k, frames = o->frames > 1 ? o->frames : 2;
    for (k = 0; k < 3; k++) {
        lo[k] = FLT_MAX;
        hi[k] = -FLT_MAX;
        axis[k] = 0.0f;
    }
    for (f = 0; f < frames; f++) {
        rendercache_camera c = wt_camera(o, (double)f / (frames - 1), 8, 8);
        float d[3], l;
        for (k = 0; k < 3; k++) {
            lo[k] = c.eye[k] < lo[k] ? c.eye[k] : lo[k];
            hi[k] = c.eye[k] > hi[k] ? c.eye[k] : hi[k];
            d[k] = c.look_at[k] - c.eye[k];
        }
        l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (k = 0; k < 3; k++) axis[k] += d[k] / l;
    }
}

static rendercache_camera wt__fisheye(const float eye[3], const float axis[3], uint32_t size)
{
    rendercache_camera c;
    int k;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_FISHEYE;
    for (k = 0; k < 3; k++) {
        c.eye[k] = eye[k];
        c.look_at[k] = eye[k] + axis[k];
    }
    c.up[1] = 1.0f;
    if (fabsf(axis[0]) < 1e-3f && fabsf(axis[2]) < 1e-3f) { c.up[1] = 0.0f; c.up[2] = 1.0f; }
    c.width = c.height = size;
    return c;
}

/* A planned route's view space (ex_baseviews_desc.route): the fish-eye at
   the camera's eye at time t, looking where the camera looks. Stretches of
   WT_BASEVIEWS_STRETCH metres of the route before the fitness test halves
   them (a box of eyes around the house's walk planned 729 views). */
#define WT_BASEVIEWS_STRETCH 2.0f
static void wt__route_view(void *user, double t, rendercache_camera *camera)
{
    rendercache_camera c = wt_camera((const wt_options *)user, t, 8, 8);
    float d[3], l;
    int k;
    for (k = 0; k < 3; k++) d[k] = c.look_at[k] - c.eye[k];
    l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (k = 0; k < 3; k++) d[k] = l > 0.0f ? d[k] / l : (k == 2 ? 1.0f : 0.0f);
    *camera = wt__fisheye(c.eye, d, camera->width);
}

/* The cameras of the time test's direct light coherence: a fish-eye looking
   down from WT_LAMP_EYE_DROP below each lamp (wt__lamps), at the middle of
   the lamp in plan. In the office: below the lamp's shade, (3.30, 1.55,
   3.40). *count of them into cams (w->light_count at most). */
#define WT_LAMP_EYE_DROP 0.05f
static void wt__lamp_cameras(const wt_world *w, rendercache_camera *cams, uint32_t *count, int *lamp_of)
{
    const float down[3] = { 0.0f, -1.0f, 0.0f };
    uint32_t lamps = wt__lamps(w, lamp_of), l, f;
    for (l = 0; l < lamps; l++) {
        float lo[3], hi[3], eye[3];
        int k;
        for (k = 0; k < 3; k++) {
            lo[k] = FLT_MAX;
            hi[k] = -FLT_MAX;
        }
        for (f = 0; f < w->light_count; f++)
            if (lamp_of[f] == (int)l)
                for (k = 0; k < 3; k++) {
                    lo[k] = fminf(lo[k], w->lights[f].centre[k]);
                    hi[k] = fmaxf(hi[k], w->lights[f].centre[k]);
                }
        eye[0] = 0.5f * (lo[0] + hi[0]);
        eye[1] = lo[1] - WT_LAMP_EYE_DROP;
        eye[2] = 0.5f * (lo[2] + hi[2]);
        cams[l] = wt__fisheye(eye, down, (uint32_t)w->opt.id_size);
    }
    *count = lamps;
}

static uint64_t wt__baseviews_key(const wt_renderer *r)
{
    const wt_options *o = &r->w->opt;
    uint64_t h = wt_hash_str(r->lightvec_key, "baseviews");
    h = wt_hash_u64(h, RENDERCACHE_FILE_FORMAT_VERSION);
    h = wt_hash_u64(h, RENDERCACHE_VERSION_MAJOR * 10000u + RENDERCACHE_VERSION_MINOR * 100u + RENDERCACHE_VERSION_PATCH);
    h = wt_hash_u64(h, (uint64_t)o->base_size);
    h = wt_hash_u64(h, (uint64_t)o->id_size);
    h = wt_hash_u64(h, (uint64_t)o->keys);
    h = wt_hash_f32(h, o->quality);
    h = wt_hash_u64(h, (uint64_t)o->light_samples);
    h = wt_hash_u64(h, (uint64_t)o->bunny_strata);
    h = wt_hash_f32(h, WT_KEY_EPSILON);   /* the bunny's key-time solutions are saved with the images */
    h = wt_hash_u64(h, WT_KEY_EXTRA_DEPTH);
    h = wt_hash_u64(h, (uint64_t)o->bunny_shadow);
    h = wt_hash_u64(h, 3u);   /* 3: base images without the bunny's shadows (wt__baseviews_shadows), through glass too */
    if (o->path) {   /* a route's views, and the frames that choose which base images are traced */
        h = wt_hash_f32(h, WT_BASEVIEWS_STRETCH);
        h = wt_hash_u64(h, (uint64_t)o->frames);
    }
    return h;
}

/* ---- the bunny's indirect light in time (Nimeroff 4.3) ------------------
   The object-space solution: the indirect radiance of each of the bunny's
   vertices (a light vector gathered at the posed vertex, in the office
   with the posed bunny, through the Lambertian bunny's BRDF). It is solved
   at key times that rendercache_keytimes_create chooses (an interval is
   halved while more than 1 - q of the vertices change by more than 5%),
   and base images and traced pixels interpolate it linearly in time and
   across each triangle. Its intervals are halved at most
   1 + WT_KEY_EXTRA_DEPTH times more than the base images' initial key
   intervals (--keys) need to be (--keys 5: 17 key times at most; a solve
   is a gather at each vertex, 0.2-0.6 s on 2 cores). Once more was not
   enough in the house: the bunny walks from a lit room into the room
   without a lamp within one interval, and the interpolated light drew it
   5x brighter there than the full render (the small walk of
   test_walkthrough_building: the bunny's luminance off by 8.6 % of the
   full renders' summed over the frames; 4.9 % with one more halving,
   3.8 % with two, at twice the solves). The office's indirect light
   comes from its static light vectors, as in the other modes. The
   gathers use one random stream per vertex at every time, so that the
   changes the test sees are the light's, not the noise's. */

typedef struct wt__key_job {
    wt_world *w;
    float *values;
} wt__key_job;

static void wt__bunny_vertex_job(void *ctx, uint32_t batch)
{
    const wt__key_job *j = (const wt__key_job *)ctx;
    wt_world *w = j->w;
    uint32_t v, end = batch * WT__BATCH + WT__BATCH;
    if (end > w->bunny.vertex_count) end = w->bunny.vertex_count;
    for (v = batch * WT__BATCH; v < end; v++) {
        lightvec_surface s;
        lightvec_record rec;
        float *out = j->values + 3 * (size_t)v, n[3], l;
        int k;
        memset(&s, 0, sizeof s);
        ex__affine_point(w->pose, w->bunny.positions + 3 * (size_t)v, s.position);
        ex__affine_vector(w->pose, w->bunny_normals + 3 * (size_t)v, n);
        l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (k = 0; k < 3; k++) s.normal[k] = l > 0.0f ? n[k] / l : (k == 1 ? 1.0f : 0.0f);
        s.flags = LIGHTVEC_RECORD_VIEW_INDEPENDENT;
        s.material = w->materials[w->bunny_material];
        out[0] = out[1] = out[2] = 0.0f;
        if (lightvec_gather(w->posed_scene, &w->bunny_gather, &s, wt__stream(WT_STREAM_BASE, 0xFFFFFFu, v), &rec) ==
            LIGHTVEC_OK)
            lightvec_radiance(&w->materials[w->bunny_material], s.normal, NULL, &rec.vector, out);
    }
}

/* rendercache_solve_fn: the bunny's vertex radiances at time t; a solution
   saved in the precompute cache is taken as it is. */
static int wt__bunny_solve(void *user, double t, float *values)
{
    wt_renderer *r = (wt_renderer *)user;
    wt_world *w = r->w;
    wt__key_job j;
    uint32_t k, n = 3 * w->bunny.vertex_count;
    for (k = 0; k < r->saved_key_count; k++)
        if (r->saved_key_times[k] == t) {
            memcpy(values, r->saved_key_values + (size_t)k * n, n * sizeof(float));
            return 0;
        }
    r->key_replay_missed |= r->saved_key_count > 0;
    wt_set_time(w, t);
    if (wt__ensure_pose(w) != 0) return 1;
    j.w = w;
    j.values = values;
    ex_pool_parallel_for(w->pool, wt__bunny_vertex_job, &j, (w->bunny.vertex_count + WT__BATCH - 1) / WT__BATCH);
    return 0;
}

/* Halvings of [0, 1] at most for the bunny's key times (see above). */
static uint32_t wt__key_depth(const wt_options *o)
{
    uint32_t depth = 1;
    while ((1 << (depth - 1)) < o->keys - 1) depth++;
    return depth + WT_KEY_EXTRA_DEPTH;
}

static int wt__bunny_keys(wt_renderer *r)
{
    rendercache_keytime_desc d;
    double t0 = wt_seconds();
    memset(&d, 0, sizeof d);
    d.element_count = r->w->bunny.vertex_count;
    d.components = 3;
    d.t0 = 0.0;
    d.t1 = 1.0;
    d.quality = r->w->opt.quality;
    d.epsilon = WT_KEY_EPSILON;
    d.max_depth = wt__key_depth(&r->w->opt);
    d.solve = wt__bunny_solve;
    d.user = r;
    rendercache_keytimes_destroy(r->bunny_light);
    r->bunny_light = NULL;
    if (rendercache_keytimes_create(&d, &r->bunny_light) != RENDERCACHE_OK) return -1;
    r->seconds_keys = wt_seconds() - t0;
    r->bunny_time = -1.0;
    return 0;
}

/* The bunny's indirect light of points lit by it (p->object == the bunny):
   the vertex radiances at the current time, interpolated across the hit
   triangle (barycentric coordinates of the posed hit point). */
static void wt__bunny_indirect_at(wt_renderer *r, wt_point *p)
{
    const wt_world *w = r->w;
    const uint32_t tri = p->polygon - w->office.face_count, *v = w->bunny.tri_indices + 3 * (size_t)tri;
    float a[3], b[3], c[3], e0[3], e1[3], e2[3], d00 = 0, d01 = 0, d11 = 0, d20 = 0, d21 = 0, den, bv, bw, bu;
    int k;
    ex__affine_point(w->pose, w->bunny.positions + 3 * (size_t)v[0], a);
    ex__affine_point(w->pose, w->bunny.positions + 3 * (size_t)v[1], b);
    ex__affine_point(w->pose, w->bunny.positions + 3 * (size_t)v[2], c);
    for (k = 0; k < 3; k++) {
        e0[k] = b[k] - a[k];
        e1[k] = c[k] - a[k];
        e2[k] = p->pos[k] - a[k];
        d00 += e0[k] * e0[k]; d01 += e0[k] * e1[k]; d11 += e1[k] * e1[k];
        d20 += e2[k] * e0[k]; d21 += e2[k] * e1[k];
    }
    den = d00 * d11 - d01 * d01;
    bv = den != 0.0f ? (d11 * d20 - d01 * d21) / den : 0.0f;
    bw = den != 0.0f ? (d00 * d21 - d01 * d20) / den : 0.0f;
    bu = 1.0f - bv - bw;
    for (k = 0; k < 3; k++)
        p->indirect[k] = bu * r->bunny_indirect[3 * v[0] + k] + bv * r->bunny_indirect[3 * v[1] + k] +
                         bw * r->bunny_indirect[3 * v[2] + k];
}

/* The vertex radiances at time t, interpolated between the key times. */
static int wt__bunny_light_at(wt_renderer *r, double t)
{
    if (t == r->bunny_time) return 0;
    if (rendercache_keytimes_eval(r->bunny_light, t, r->bunny_indirect, 3 * (size_t)r->w->bunny.vertex_count) !=
        RENDERCACHE_OK)
        return -1;
    r->bunny_time = t;
    return 0;
}

/* Renders base image (view, key) with the frames' shading. */
static int wt__render_base(wt_renderer *r, uint32_t view, uint32_t key, rendercache_range_image **out)
{
    wt_world *w = r->w;
    rendercache_camera c = ex_baseviews_base_camera(&r->bv, view, (uint32_t)w->opt.base_size);
    wt_light_stats st = { 0, 0, 0, 0 };
    uint32_t i, n = c.width * c.height;
    int shaded;
    rendercache_range_image *img;
    if (rendercache_range_image_create(&c, NULL, &img) != RENDERCACHE_OK) return -1;
    img->time = r->bv.times[key];
    wt_set_time(w, img->time);
    /* the office's light vectors; the bunny's indirect light from its key-time solution.
       The bunny casts no shadow here: its shadows belong to the frame's time
       (wt__baseviews_shadows), not to the key time's pose */
    shaded = wt__shade_camera(w, &c, WT_STREAM_BASE, view * r->bv.time_count + key,
                              WT_SHADE_DIRECT | WT_SHADE_INSERT | WT_SHADE_STATIC_ONLY | WT_SHADE_NO_BUNNY_SHADOWS,
                              r->points, r->index, &st);
    if (shaded != 0 || wt__bunny_light_at(r, img->time) != 0) {
        rendercache_range_image_destroy(img);
        return -1;
    }
    for (i = 0; i < n; i++) {
        wt_point *p = &r->points[i];
        if (p->t < 0.0f) continue;   /* outside the fish-eye's circle: RENDERCACHE_NO_SAMPLE */
        if (p->object == WT_OBJECT_BUNNY && p->t < FLT_MAX) {
            wt__bunny_indirect_at(r, p);
            wt__point_radiance(p);
        }
        memcpy(img->rgb + 3 * (size_t)i, p->rgb, 3 * sizeof(float));
        img->object[i] = p->object;
        img->depth[i] = p->object == RENDERCACHE_MISS ? RENDERCACHE_FAR_DEPTH : p->t;
    }
    *out = img;
    return 0;
}

static void wt__put_floats(wt_bytes *b, const float *v, size_t n);
static int wt__get_floats(wt_bytes *b, float *v, size_t n);

/* Base images from the precompute cache: the decomposition must match.
   After them, the key solutions of the bunny's indirect light (count,
   then per key its time and its vertex radiances), kept in
   r->saved_key_* for wt__bunny_solve to replay. */
static int wt__load_bases(wt_renderer *r, const void *data, size_t size)
{
    const size_t per_key = 3 * (size_t)r->w->bunny.vertex_count;
    wt_bytes b;
    uint64_t views, times, bits, n, keys;
    uint32_t i;
    memset(&b, 0, sizeof b);
    b.data = (unsigned char *)data;
    b.size = size;
    if (!wt_bytes_get_u64(&b, &views) || !wt_bytes_get_u64(&b, &times) || views != r->bv.view_count ||
        times != r->bv.time_count)
        return -1;
    for (i = 0; i < r->bv.time_count; i++) {
        double t;
        if (!wt_bytes_get_u64(&b, &bits)) return -1;
        memcpy(&t, &bits, sizeof t);
        if (t != r->bv.times[i]) return -1;
    }
    for (i = 0; i < r->bv.view_count * r->bv.time_count; i++) {
        if (!wt_bytes_get_u64(&b, &n) || n > b.size - b.read) return -1;
        if (n == 0 && !r->base_needed[i]) continue;   /* no frame warps from it: not traced */
        if (rendercache_range_image_load_from_memory(b.data + b.read, (size_t)n, NULL, &r->bv.base[i]) != RENDERCACHE_OK)
            return -1;
        b.read += (size_t)n;
    }
    if (!wt_bytes_get_u64(&b, &keys) || keys < 2 || keys > (1u << wt__key_depth(&r->w->opt)) + 1) return -1;
    r->saved_key_times = (double *)malloc(sizeof(double) * (size_t)keys);
    r->saved_key_values = (float *)malloc(sizeof(float) * per_key * (size_t)keys);
    if (!r->saved_key_times || !r->saved_key_values) return -1;
    for (i = 0; i < keys; i++) {
        if (!wt_bytes_get_u64(&b, &bits) || !wt__get_floats(&b, r->saved_key_values + per_key * i, per_key)) return -1;
        memcpy(&r->saved_key_times[i], &bits, sizeof bits);
    }
    r->saved_key_count = (uint32_t)keys;
    return b.read == b.size ? 0 : -1;
}

static int wt__save_bases(const wt_renderer *r, wt_bytes *b)
{
    uint32_t i;
    wt_bytes_put_u64(b, r->bv.view_count);
    wt_bytes_put_u64(b, r->bv.time_count);
    for (i = 0; i < r->bv.time_count; i++) {
        uint64_t bits;
        memcpy(&bits, &r->bv.times[i], sizeof bits);
        wt_bytes_put_u64(b, bits);
    }
    for (i = 0; i < r->bv.view_count * r->bv.time_count; i++) {
        void *data;
        size_t size;
        if (!r->bv.base[i]) {   /* not needed: not traced */
            wt_bytes_put_u64(b, 0);
            continue;
        }
        if (rendercache_range_image_save_to_memory(r->bv.base[i], NULL, &data, &size) != RENDERCACHE_OK) return -1;
        wt_bytes_put_u64(b, size);
        wt_bytes_put(b, data, size);
        rendercache_free_memory(NULL, data);
    }
    wt_bytes_put_u64(b, rendercache_keytimes_count(r->bunny_light));
    for (i = 0; i < rendercache_keytimes_count(r->bunny_light); i++) {
        uint64_t bits;
        memcpy(&bits, &rendercache_keytimes_times(r->bunny_light)[i], sizeof bits);
        wt_bytes_put_u64(b, bits);
        wt__put_floats(b, rendercache_keytimes_values(r->bunny_light, i), 3 * (size_t)r->w->bunny.vertex_count);
    }
    return b->failed ? -1 : 0;
}

/* What the warp's fills left empty is traced (Radiance's pinterp -fr) with
   the frames' shading; light vectors are looked up, not inserted. First
   the ray of pixel (x, y), with its direct light. */
static void wt__fill_trace(const wt_renderer *r, uint32_t x, uint32_t y, const float org[3], const float dir[3],
                           wt_point *p)
{
    memcpy(p->org, org, sizeof p->org);
    memcpy(p->dir, dir, sizeof p->dir);
    p->stream = wt__stream(WT_STREAM_FILL, r->fill_frame, y * r->width + x);
    wt__trace_point(r->w, p, WT_SHADE_DIRECT);
}

/* Then its indirect light; its colour, depth and object out. Returns 0
   when a gather failed. */
static int wt__fill_shade(wt_renderer *r, wt_point *p, float rgb[3], float *depth, uint32_t *object)
{
    wt_world *w = r->w;
    lightvec_lookup_result lr;
    lightvec_record rec;
    lightvec_surface s;
    float wo[3];
    const float *out;
    if (!p->lit && p->light == WT_LIGHT_BUNNY) {   /* the key-time solution, at the frame's time (wt__baseviews_frame) */
        wt__bunny_indirect_at(r, p);
    } else if (!p->lit) {
        out = wt__outgoing(p, wo);
        if (lightvec_lookup(wt__cache_of(w, p), p->pos, p->normal, out, &lr) == LIGHTVEC_OK && lr.hit) {
            rec.vector = lr.vector;
        } else {
            wt__surface_of(w, p, &s);
            if (lightvec_gather(w->office_scene, &w->static_gather, &s, p->stream, &rec) != LIGHTVEC_OK) return 0;
        }
        lightvec_radiance(&w->materials[p->material], p->normal, out, &rec.vector, p->indirect);
    }
    wt__point_radiance(p);
    memcpy(rgb, p->rgb, sizeof p->rgb);
    *depth = p->object == RENDERCACHE_MISS ? RENDERCACHE_FAR_DEPTH : p->t;
    *object = p->object;
    return 1;
}

/* The warp's fill callback: both. */
static int wt__fill_pixel(void *user, uint32_t x, uint32_t y, const float org[3], const float dir[3], float rgb[3],
                          float *depth, uint32_t *object)
{
    wt_renderer *r = (wt_renderer *)user;
    wt_point p;
    wt__fill_trace(r, x, y, org, dir, &p);
    return wt__fill_shade(r, &p, rgb, depth, object);
}

/* The background fill's reach in pixels of a frame width pixels wide:
   WT_BASEVIEWS_MAX_FILL at 640, as far in angle at other widths (at 160
   wide, 8 pixels smeared a lit wall across a door's opening that a trace
   shows; at least 1). */
static uint32_t wt__baseviews_max_fill(uint32_t width)
{
    uint32_t d = (WT_BASEVIEWS_MAX_FILL * width + 320u) / 640u;
    return d ? d : 1u;
}

/* The final warp's relative depth tolerance for base images size pixels
   wide: neighbouring pixels of an equidistant fish-eye are pi / size
   radians apart, so the depths of a plane seen at an angle a from its
   normal differ by about tan(a) pi / size from one to the next, and the
   warp joins them into a foreground quad within twice the tolerance.
   rendercache's default (0.02) joins up to tan(a) = 3.3 at 512 pixels but
   only 0.8 (39 degrees) at 128: walls seen obliquely were splatted as
   points, and the farther surfaces behind them showed through the dots
   between (the house at 160x120, base 128: mean LRMS 0.187 -> 0.160 with
   0.10). Never below the default. */
static float wt__baseviews_tolerance(uint32_t size)
{
    float tol = WT_BASEVIEWS_SLOPE * WT_PI / (2.0f * (float)(size ? size : 1u));
    return tol > 0.02f ? tol : 0.02f;
}

/* Whether pixel i of the warped frame (r->out) lies within
   WT_BASEVIEWS_EDGE_REACH pixels of an edge: two pixels of the window
   around it that show different objects, depths further apart than
   r->edge_ratio (the final warp's test for joining pixels into a
   foreground quad), or luminances further apart than
   WT_BASEVIEWS_EDGE_CONTRAST. A warp places an edge only as finely as
   the base images' pixels, which are about three frame pixels wide
   (180 degrees over the base size against the frame's 60 degrees over
   its height): the jambs, the table and the chair came out as
   staircases, a band of full-contrast errors along every silhouette
   (38-50 % of the house's squared error against full renders at
   320x240, base 256), and the quads across a crease (a jamb's shaded
   side beside its lit face: no depth edge) blurred the crease over
   three pixels. Those pixels are traced again at the frame's time
   (wt__retraced): their edges come out as sharp as a full render's
   (320x240, base 256, mean LRMS against full renders: house 0.109 ->
   0.078, office 0.113 -> 0.073, for about 2400 more pixels traced a
   frame, +30-37 % CPU time). */
static int wt__edge_pixel(const wt_renderer *r, size_t i)
{
    const rendercache_range_image *out = r->out;
    const uint32_t w = r->width, h = r->height, x = (uint32_t)(i % w), y = (uint32_t)(i / w), d = WT_BASEVIEWS_EDGE_REACH;
    const uint32_t x0 = x >= d ? x - d : 0, x1 = x + d < w ? x + d : w - 1, y0 = y >= d ? y - d : 0;
    const uint32_t y1 = y + d < h ? y + d : h - 1, object = out->object[i];
    float lo = FLT_MAX, hi = 0.0f, lum_lo = FLT_MAX, lum_hi = 0.0f;
    uint32_t xx, yy;
    for (yy = y0; yy <= y1; yy++)
        for (xx = x0; xx <= x1; xx++) {
            const size_t j = (size_t)yy * w + xx;
            const float l = wt__luminance(out->rgb + 3 * j);
            if (out->object[j] != object) return 1;
            lo = out->depth[j] < lo ? out->depth[j] : lo;
            hi = out->depth[j] > hi ? out->depth[j] : hi;
            lum_lo = l < lum_lo ? l : lum_lo;
            lum_hi = l > lum_hi ? l : lum_hi;
        }
    return hi > lo * r->edge_ratio || lum_hi > lum_lo * WT_BASEVIEWS_EDGE_CONTRAST;
}

/* The base images the frames warp from (r->base_needed): on a planned
   route, those of the stretch and key interval around each frame's time;
   in the office's box, all of them (as its reference frames were made:
   base images insert light vectors that later ones look up). */
static int wt__baseviews_needed(wt_renderer *r)
{
    const wt_options *o = &r->w->opt;
    const uint32_t n = r->bv.view_count * r->bv.time_count;
    uint32_t views[8], count, key, i;
    int f;
    r->base_needed = (unsigned char *)calloc(n ? n : 1, 1);
    if (!r->base_needed) return -1;
    if (!o->path) memset(r->base_needed, 1, n);
    for (f = 0; f < o->frames && o->path; f++) {
        double t = wt_frame_time(o, f);
        rendercache_camera c = wt_camera(o, t, 8, 8);
        if (ex_baseviews_needs(&r->bv, c.eye, t, views, &count, &key) != 0) return -1;
        for (i = 0; i < count; i++) {
            r->base_needed[views[i] * r->bv.time_count + key] = 1;
            r->base_needed[views[i] * r->bv.time_count + key + 1] = 1;
        }
    }
    for (r->base_needed_count = 0, i = 0; i < n; i++) r->base_needed_count += r->base_needed[i];
    return 0;
}

/* Every base image a frame warps from is there. */
static int wt__baseviews_complete(const wt_renderer *r)
{
    uint32_t i;
    for (i = 0; i < r->bv.view_count * r->bv.time_count; i++)
        if (r->base_needed[i] && !r->bv.base[i]) return 0;
    return 1;
}

static int wt__baseviews_create(wt_renderer *r, char *err, size_t err_size)
{
    wt_world *w = r->w;
    const wt_options *o = &w->opt;
    ex_baseviews_desc d;
    rendercache_warp_desc wd;
    rendercache_camera *lamps, frame_cam;
    double *keys;
    float axis[3], eye[3];
    int *lamp_of;
    char path[1024];
    void *data = NULL;
    size_t size = 0;
    uint32_t i, v, k;
    int got = 0, k0;
    double t0;
    if (wt__static_lightvec(r, err, err_size) != 0) return -1;
    /* the decomposition (id images are cheap: recomputed every run) */
    t0 = wt_seconds();
    memset(&d, 0, sizeof d);
    if (o->path) {   /* a chain of stretches along the route */
        r->route_length = wt_route_measure(o).length;
        d.route = wt__route_view;
        d.route_user = (void *)o;
        d.stretches = (uint32_t)ceil(r->route_length / WT_BASEVIEWS_STRETCH);
        d.stretches = d.stretches ? d.stretches : 1;
        d.fisheye.width = d.fisheye.height = (uint32_t)o->id_size;
        wt__route_view(d.route_user, 0.0, &d.fisheye);
    } else {
        wt__view_space(o, d.lo, d.hi, axis);
        for (k0 = 0; k0 < 3; k0++) eye[k0] = 0.5f * (d.lo[k0] + d.hi[k0]);
        d.fisheye = wt__fisheye(eye, axis, (uint32_t)o->id_size);
    }
    /* direct light coherence */
    lamps = (rendercache_camera *)malloc(sizeof *lamps * (w->light_count + 1));
    lamp_of = (int *)malloc(sizeof *lamp_of * (w->light_count + 1));
    keys = (double *)malloc(sizeof(double) * (size_t)o->keys);
    if (!lamps || !lamp_of || !keys) {
        free(lamps);
        free(lamp_of);
        free(keys);
        return wt__fail(err, err_size, "%s", "out of memory");
    }
    wt__lamp_cameras(w, lamps, &d.extra_count, lamp_of);
    free(lamp_of);
    d.extra_cameras = lamps;
    d.quality = o->quality;
    for (k0 = 0; k0 < o->keys; k0++) keys[k0] = (double)k0 / (o->keys - 1);
    d.times = keys;
    d.time_count = (uint32_t)o->keys;
    d.render_ids = wt__render_ids;
    d.user = w;
    k0 = ex_baseviews_build(&d, &r->bv);
    free(keys);
    free(lamps);
    if (k0 != 0 || wt__baseviews_needed(r) != 0)
        return wt__fail(err, err_size, "%s", "the base-view decomposition failed (out of memory)");
    if (o->verbose) {
        if (o->path)
            printf("base views: %u views along the route's %.1f m (%.1f per metre, %u stretches), %u lamps; %u key "
                   "times; %u base images of %dx%d that the frames warp from (q = %.2f, decomposition %.1f s)\n",
                   r->bv.view_count, r->route_length, r->bv.view_count / (r->route_length > 0.0 ? r->route_length : 1.0),
                   d.stretches, d.extra_count, r->bv.time_count, r->base_needed_count, o->base_size, o->base_size,
                   (double)o->quality, wt_seconds() - t0);
        else
            printf("base views: %u views x %u key times = %u base images of %dx%d (q = %.2f, decomposition %.1f s)\n",
                   r->bv.view_count, r->bv.time_count, r->bv.view_count * r->bv.time_count, o->base_size, o->base_size,
                   (double)o->quality, wt_seconds() - t0);
        fflush(stdout);
    }
    /* the base images */
    t0 = wt_seconds();
    r->baseviews_key = wt__baseviews_key(r);
    wt_cache_path(o->cache_dir, "baseviews", r->baseviews_key, path, sizeof path);
    if (o->use_cache) got = wt_cache_load(o->cache_dir, "baseviews", r->baseviews_key, &data, &size);
    if (got == 1) {
        if (wt__load_bases(r, data, size) == 0 && wt__baseviews_complete(r)) r->reused_baseviews = 1;
        else got = -1;
        free(data);
    }
    if (got == -1) {
        for (i = 0; i < r->bv.view_count * r->bv.time_count; i++) {
            rendercache_range_image_destroy(r->bv.base[i]);
            r->bv.base[i] = NULL;
        }
        r->saved_key_count = 0;
        wt__say(w, "base images: %s is damaged or stale, rebuilding it\n", path);
    }
    /* the bunny's indirect light at key times, before the base images that use it */
    r->bunny_indirect = (float *)malloc(3 * sizeof(float) * w->bunny.vertex_count);
    if (!r->bunny_indirect || wt__bunny_keys(r) != 0)
        return wt__fail(err, err_size, "%s", "the bunny's indirect light failed (out of memory)");
    if (r->key_replay_missed && r->reused_baseviews) {   /* a stale entry: trace and save anew */
        for (i = 0; i < r->bv.view_count * r->bv.time_count; i++) {
            rendercache_range_image_destroy(r->bv.base[i]);
            r->bv.base[i] = NULL;
        }
        r->reused_baseviews = 0;
    }
    if (o->verbose) {
        printf("bunny's indirect light: %u key times (q = %.2f, %s in %.1f s)\n", rendercache_keytimes_count(r->bunny_light),
               (double)o->quality, r->reused_baseviews ? "replayed" : "solved", r->seconds_keys);
        fflush(stdout);
    }
    if (!r->reused_baseviews) {
        /* base images add light vectors to a copy of the static cache, so that
           the frames see the same cache whether the base images were loaded
           or traced */
        lightvec_cache *saved = w->static_cache, *copy = wt__cache_copy(w, saved);
        wt_progress bar;
        if (!copy) return wt__fail(err, err_size, "%s", "out of memory");
        w->static_cache = copy;
        wt_progress_begin(&bar, "base images", o->progress);
        for (k = 0, i = 0; k < r->bv.time_count; k++)   /* key by key: the bunny's pose changes least often */
            for (v = 0; v < r->bv.view_count; v++) {
                if (!r->base_needed[v * r->bv.time_count + k]) continue;
                if (wt__render_base(r, v, k, &r->bv.base[v * r->bv.time_count + k]) != 0) {
                    w->static_cache = saved;
                    lightvec_cache_destroy(copy);
                    return wt__fail(err, err_size, "%s", "rendering a base image failed (out of memory)");
                }
                wt_progress_update(&bar, ++i, r->base_needed_count);
            }
        wt_progress_end(&bar);
        w->static_cache = saved;
        lightvec_cache_destroy(copy);
        if (o->use_cache) {
            wt_bytes b;
            memset(&b, 0, sizeof b);
            if (wt__save_bases(r, &b) != 0 ||
                wt_cache_store(o->cache_dir, "baseviews", r->baseviews_key, b.data, b.size, err, err_size) != 0) {
                wt__say(w, "base images: not cached (%s)\n", err[0] ? err : "out of memory");
                err[0] = 0;
            }
            free(b.data);
        }
    }
    if (o->verbose) {
        if (r->reused_baseviews) printf("base images: reused the precompute cache %s\n", path);
        else printf("base images: traced in %.1f s%s%s\n", wt_seconds() - t0, o->use_cache ? ", saved to " : "",
                    o->use_cache ? path : "");
        fflush(stdout);
    }
    /* reconstruction buffers */
    memset(&wd, 0, sizeof wd);
    wd.parallel_for = ex_pool_parallel_for;
    wd.parallel_user = w->pool;
    wd.clock = wt__clock;
    if (rendercache_warper_create(&wd, &r->rec.blender) != RENDERCACHE_OK) return wt__fail(err, err_size, "%s", "out of memory");
    wd.fill_pixel = wt__fill_pixel;
    wd.fill_user = r;
    wd.average = 1;                     /* the corner views that see a surface are averaged (pinterp -a) */
    wd.max_fill_distance = wt__baseviews_max_fill(r->width);   /* wider gaps are traced, not smeared (pinterp -fs) */
    wd.depth_tolerance = wt__baseviews_tolerance((uint32_t)o->base_size);
    if (rendercache_warper_create(&wd, &r->rec.warper) != RENDERCACHE_OK) return wt__fail(err, err_size, "%s", "out of memory");
    r->edge_ratio = 1.0f + 2.0f * wd.depth_tolerance;   /* the warp's own test for a foreground quad */
    r->lamp_luminance = FLT_MAX;
    for (i = 0; i < w->light_count; i++)
        r->lamp_luminance = fminf(r->lamp_luminance, WT_BASEVIEWS_LAMP_SHARE * wt__luminance(w->lights[i].ke));
    r->rec.object_count = 2;
    r->rec.motion = wt__object_transforms;
    r->rec.motion_user = w;
    r->rec.fill = RENDERCACHE_FILL_BOTH;
    /* no fill in the blends: a foreground quad between a bunny pixel and the
       floor next to it would stretch as the bunny moves; the warp fills */
    r->rec.blend_fill = RENDERCACHE_FILL_NONE;
    {
        rendercache_camera bc = ex_baseviews_base_camera(&r->bv, 0, (uint32_t)o->base_size);
        for (i = 0; i < 8; i++)
            if (rendercache_range_image_create(&bc, NULL, &r->blend[i]) != RENDERCACHE_OK)
                return wt__fail(err, err_size, "%s", "out of memory");
    }
    frame_cam = wt_camera(o, 0.0, r->width, r->height);
    if (rendercache_range_image_create(&frame_cam, NULL, &r->out) != RENDERCACHE_OK)
        return wt__fail(err, err_size, "%s", "out of memory");
    return 0;
}

/* The bunny's shadows at the frame's time (Nimeroff et al. keep moving
   objects' effects out of the static base images): the base images are
   traced without them, so a warped office pixel the posed bunny may
   shadow is traced again with the frame's shading (wt__fill_pixel: shadow
   rays that see the bunny, its contact occlusion), and where none of its
   shadow or contact rays met the bunny, its trace is dropped and the
   warped colour kept: an estimate of the same light, already paid for
   (in the office's frames, 72 % of the pixels the test below flags; the
   light-vector lookups of those were most of the frame). May shadow:
   within the contact shadow's reach of the bunny's bounding sphere, or
   where the cone from the point around a light's bounding sphere (which
   holds its shadow rays) meets the cone from the point around the bunny's,
   nearer than the light's far side. A conservative test: the rest of the
   office keeps its warped colour, which is what the trace would give
   there. (Its first form, the bunny's sphere within the light's radius of
   the segment from the point to the light's centre, flagged about 13 % of
   the office frame's pixels.) */
static int wt__bunny_may_shadow(const wt_world *w, const float pos[3])
{
    float c[3], v[3], d2 = 0.0f, r = w->bunny_bound_radius, reach = r + WT_CONTACT_REACH * r, lv, sin_b, cos_b;
    uint32_t e;
    int k;
    if (!w->opt.bunny_shadow) return 0;
    ex__affine_point(w->pose, w->bunny_bound_centre, c);
    for (k = 0; k < 3; k++) {
        v[k] = c[k] - pos[k];
        d2 += v[k] * v[k];
    }
    if (d2 < reach * reach) return 1;
    lv = sqrtf(d2);
    sin_b = r / lv;   /* the cone from pos around the bunny's sphere: half-angle b (d2 > r^2 here) */
    cos_b = sqrtf(1.0f - sin_b * sin_b);
    for (e = 0; e < w->light_count; e++) {
        const wt_light *L = &w->lights[e];
        float s[3], s2 = 0.0f, vs = 0.0f, ls, sin_a, cos_a;
        for (k = 0; k < 3; k++) {
            s[k] = L->centre[k] - pos[k];
            s2 += s[k] * s[k];
            vs += s[k] * v[k];
        }
        ls = sqrtf(s2);
        if (ls <= L->radius) return 1;               /* inside the light's sphere */
        if (lv - r >= ls + L->radius) continue;      /* the bunny beyond the light */
        sin_a = L->radius / ls;                      /* the cone around the light's sphere: half-angle a */
        cos_a = sqrtf(1.0f - sin_a * sin_a);
        /* the cones meet when the angle between their axes is below a + b (<= pi), i.e. its cosine
           above cos(a + b); a margin for the rounding */
        if (vs > (cos_a * cos_b - sin_a * sin_b) * ls * lv - 1e-5f * ls * lv) return 1;
    }
    return 0;
}

typedef struct wt__shadow_job {
    wt_renderer *r;
    const rendercache_camera *camera;
    uint32_t count;          /* pixels flagged (r->index[0 .. count)) */
} wt__shadow_job;

/* Warped pixels traced again at the frame's time whatever the bunny's
   shadow test says: the bunny's (its base images saw it lit as it stood
   at the key times, in another room perhaps, and the blend moves those
   colours with it: drawn bright in the room without a lamp, where the
   full render shows it dark; the pixels of the bunny's own shadow test
   are the office's), and the lamps' (a bright emitter warped
   from a coarser base image is a blob around the lamp and its quads
   smear its radiance onto the ceiling beside it; a few pixels, each
   worth hundreds of a dim wall's in the luminance error), and those
   near an edge (wt__edge_pixel). */
static int wt__retraced(const wt_renderer *r, size_t i)
{
    const rendercache_range_image *out = r->out;
    return out->object[i] == WT_OBJECT_BUNNY ||
           (out->object[i] == WT_OBJECT_OFFICE && wt__luminance(out->rgb + 3 * i) >= r->lamp_luminance) ||
           wt__edge_pixel(r, i);
}

/* Job per row: r->index[i] = 1 for each pixel i of the row that shows the
   office where the bunny may shadow it, or that wt__retraced, else 0. */
static void wt__shadow_flag_row(void *ctx, uint32_t y)
{
    const wt__shadow_job *j = (const wt__shadow_job *)ctx;
    const rendercache_range_image *out = j->r->out;
    uint32_t x;
    for (x = 0; x < j->camera->width; x++) {
        size_t i = (size_t)y * j->camera->width + x;
        float org[3], dir[3], pos[3];
        int k;
        j->r->index[i] = 0;
        if ((out->object[i] != WT_OBJECT_OFFICE && out->object[i] != WT_OBJECT_BUNNY) ||
            rendercache_camera_ray(j->camera, (float)x + 0.5f, (float)y + 0.5f, org, dir) != RENDERCACHE_OK)
            continue;
        for (k = 0; k < 3; k++) pos[k] = org[k] + out->depth[i] * dir[k];
        j->r->index[i] = (uint32_t)(wt__retraced(j->r, i) || wt__bunny_may_shadow(j->r->w, pos));
    }
}

/* Job per batch of flagged pixels: their rays, traced with direct light
   into r->points. */
static void wt__shadow_trace_job(void *ctx, uint32_t batch)
{
    const wt__shadow_job *j = (const wt__shadow_job *)ctx;
    uint32_t k, end = batch * WT__BATCH + WT__BATCH;
    if (end > j->count) end = j->count;
    for (k = batch * WT__BATCH; k < end; k++) {
        uint32_t i = j->r->index[k], x = i % j->camera->width, y = i / j->camera->width;
        float org[3], dir[3];
        rendercache_camera_ray(j->camera, (float)x + 0.5f, (float)y + 0.5f, org, dir);   /* (flagged: it has one) */
        wt__fill_trace(j->r, x, y, org, dir, &j->r->points[k]);
    }
}

/* The pass: flags (in parallel), the flagged pixels in pixel order,
   traced (in parallel); those the bunny touched or wt__retraced chose
   keep their trace: the
   bunny's own points take the key-time solution, the office's their
   light vectors, looked up and gathered in rounds with the picks of the
   raytrace mode (wt__light_points), and inserted, in that fixed order, so
   that later frames find them. Gathered one per missed pixel, as the
   warp's fill does, they were up to 180 gathers (about as many
   milliseconds) in a frame where the bunny came near the lamp. */
static int wt__baseviews_shadows(wt_renderer *r, const rendercache_camera *camera)
{
    wt__shadow_job j;
    wt_light_stats ls;
    rendercache_range_image *out = r->out;
    const uint32_t n = camera->width * camera->height;
    uint32_t i, k, kept = 0;
    j.r = r;
    j.camera = camera;
    ex_pool_parallel_for(r->w->pool, wt__shadow_flag_row, &j, camera->height);
    for (i = 0, j.count = 0; i < n; i++)
        if (r->index[i]) r->index[j.count++] = i;
    ex_pool_parallel_for(r->w->pool, wt__shadow_trace_job, &j, (j.count + WT__BATCH - 1) / WT__BATCH);
    for (k = 0; k < j.count; k++) {
        wt_point *p = &r->points[k];
        if (p->object == WT_OBJECT_OFFICE && !p->bunny_shadow && !wt__retraced(r, r->index[k]))
            continue;   /* the bunny hid none of its light */
        if (!p->lit && p->light == WT_LIGHT_BUNNY) {   /* the key-time solution, at the frame's time */
            wt__bunny_indirect_at(r, p);
            p->lit = 1;
        }
        r->index[kept] = r->index[k];
        if (kept != k) r->points[kept] = *p;
        kept++;
    }
    memset(&ls, 0, sizeof ls);
    if (wt__light_points(r->w, r->points, kept, 1, &ls) != 0) return -1;
    for (k = 0; k < kept; k++) {
        const wt_point *p;
        i = r->index[k];
        p = &r->points[k];
        wt__point_radiance(&r->points[k]);
        memcpy(out->rgb + 3 * (size_t)i, p->rgb, sizeof p->rgb);
        out->depth[i] = p->object == RENDERCACHE_MISS ? RENDERCACHE_FAR_DEPTH : p->t;
        out->object[i] = p->object;
    }
    return 0;
}

static int wt__baseviews_frame(wt_renderer *r, int frame, float *rgb, wt_frame_stats *st)
{
    wt_world *w = r->w;
    double t = wt_frame_time(&w->opt, frame), t0 = wt_seconds();
    rendercache_camera cam = wt_camera(&w->opt, t, r->width, r->height);
    rendercache_warp_stats ws;
    wt_set_time(w, t);   /* the fill traces the scene as it is at t */
    r->fill_frame = (uint32_t)frame;
    if (wt__bunny_light_at(r, t) != 0) return -1;
    if (ex_baseviews_reconstruct(&r->bv, &r->rec, &cam, t, r->blend, r->out) != 0) return -1;
    if (wt__baseviews_shadows(r, &cam) != 0) return -1;
    memcpy(rgb, r->out->rgb, sizeof(float) * 3 * r->width * r->height);
    rendercache_warp_get_stats(r->rec.warper, &ws);
    st->phase[0] = r->rec.seconds_blend;
    st->phase[1] = r->rec.seconds_warp;
    st->samples = ws.computed;
    st->total = wt_seconds() - t0;
    return 0;
}

/* ---- mode radiosity ------------------------------------------------------
   Precompute: radinterp_solve (hierarchical radiosity of the office's 55
   polygons) and radinterp_build_mesh (discontinuity mesh, one quadratic
   irradiance interpolant per triangle), saved with radinterp_mesh_save; an
   irradiance volume (irrvol.h) whose radiance is that solution; the bunny's
   self-occlusion ratios. Per frame: the bunny's vertices query the volume
   (Greger eq. 4.7: radiance = Kd H / pi, times the vertex's self-occlusion
   ratio, thesis 6.1.3), the rasterizer draws the static mesh and the bunny
   into the ID + barycentric buffers, and one pass over the pixels, tile by
   tile as the raster finishes them, shades the static ones by their
   triangle's interpolant (radinterp_shade_span on each run of pixels of
   one triangle, Hardt's online phase; radiance B / pi) with the bunny's
   occlusion blob, and the bunny's by Gouraud interpolation of its vertex
   colours.
   ------------------------------------------------------------------------ */
#define WT_RADIOSITY_VERSION 1u  /* bump when the patches, materials or the volume's source change */

/* Key of the office's mesh: the scene, radinterp's version and format, and
   the solver's and the mesh's parameters. */
static uint64_t wt__radinterp_key(const wt_world *w)
{
    const wt_options *o = &w->opt;
    uint64_t h = wt_hash_str(w->scene_hash, "radinterp");
    h = wt_hash_u64(h, RADINTERP_FILE_FORMAT_VERSION);
    h = wt_hash_u64(h, RADINTERP_VERSION_MAJOR * 10000u + RADINTERP_VERSION_MINOR * 100u + RADINTERP_VERSION_PATCH);
    h = wt_hash_u64(h, WT_RADIOSITY_VERSION);
    h = wt_hash_f32(h, o->radiosity_eps);
    h = wt_hash_f32(h, o->min_leaf_area);
    return wt_hash_u64(h, o->seed);
}

typedef struct wt__log { char text[256]; } wt__log;

static void wt__keep_log(void *user, const char *message)
{
    snprintf(((wt__log *)user)->text, sizeof ((wt__log *)user)->text, "%s", message);
}

/* Says where a piece of precomputed data came from: "reused the precompute
   cache FILE", or computed (with `detail`) and saved, after a note when a
   cache file was there but damaged or stale. */
static void wt__cache_say(const wt_world *w, const char *label, const char *what, uint64_t key, int found, int reused,
                          double seconds, const char *detail)
{
    char path[1024];
    wt_cache_path(w->opt.cache_dir, what, key, path, sizeof path);
    if (found && !reused) wt__say(w, "%s: %s is damaged or stale, rebuilt it\n", label, path);
    if (reused)
        wt__say(w, "%s: reused the precompute cache %s%s\n", label, path, detail);
    else
        wt__say(w, "%s: computed in %.1f s%s%s%s\n", label, seconds, detail,
                w->opt.use_cache ? ", saved to " : " (cache off)", w->opt.use_cache ? path : "");
}

/* The office as radinterp patches (one per OBJ polygon, 3 or 4 corners) and
   materials: reflectance Kd, emitted radiosity E = pi Ke (Ke is the MTL's
   emitted radiance). */
static int wt__radiosity_solve(wt_world *w, radinterp_solution **sol, char *err, size_t err_size)
{
    const obj_scene *s = &w->office;
    uint32_t *patches = (uint32_t *)malloc(4 * sizeof(uint32_t) * s->face_count), f, k;
    radinterp_material *mats = (radinterp_material *)calloc(s->material_count ? s->material_count : 1, sizeof *mats);
    radinterp_desc d;
    radinterp_result rr;
    wt_progress bar;
    wt__log log;
    log.text[0] = 0;
    if (!patches || !mats) {
        free(patches);
        free(mats);
        return wt__fail(err, err_size, "%s", "out of memory");
    }
    for (f = 0; f < s->face_count; f++) {
        uint32_t c = s->face_start[f + 1] - s->face_start[f];
        if (c < 3 || c > 4) {
            snprintf(err, err_size, "%.200s: polygon %u has %u corners; mode radiosity takes 3 or 4", w->office_path, f, c);
            free(patches);
            free(mats);
            return -1;
        }
        for (k = 0; k < 4; k++) patches[4 * f + k] = k < c ? s->face_vertices[s->face_start[f] + k] : RADINTERP_NO_VERTEX;
    }
    for (f = 0; f < s->material_count; f++)
        for (k = 0; k < 3; k++) {
            mats[f].reflectance[k] = s->materials[f].kd[k];
            mats[f].emission[k] = WT_PI * s->materials[f].ke[k];
            mats[f].transmittance[k] = s->materials[f].tf[k];   /* glass passes light */
        }
    memset(&d, 0, sizeof d);
    if (w->layout.has_sky) {   /* daylight: the sky lights the rooms through the windows */
        memcpy(d.sky, w->layout.sky.radiance, sizeof d.sky);
        d.environment = w->layout.sky.map;
        d.environment_width = (uint32_t)w->layout.sky.width;
        d.environment_height = (uint32_t)w->layout.sky.height;
    }
    d.positions = s->positions;
    d.vertex_count = s->vertex_count;
    d.patches = patches;
    d.patch_count = s->face_count;
    d.patch_materials = s->face_material;
    d.materials = mats;
    d.material_count = s->material_count ? s->material_count : 1;
    d.eps = w->opt.radiosity_eps;
    d.seed = w->opt.seed;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = w->pool;
    d.log = wt__keep_log;
    d.log_user = &log;
    wt_progress_begin(&bar, "radiosity solve (iterations)", w->opt.progress);   /* ends early when it converges */
    d.progress = wt_progress_update;
    d.progress_user = &bar;
    rr = radinterp_solve(&d, sol);
    if (rr == RADINTERP_OK) wt_progress_end(&bar);
    free(patches);
    free(mats);
    if (rr != RADINTERP_OK) {
        snprintf(err, err_size, "radinterp_solve: %s%s%s", radinterp_result_string(rr), log.text[0] ? ": " : "", log.text);
        return -1;
    }
    return 0;
}

/* Unit front normals of the mesh's triangles (counter-clockwise fronts). */
static int wt__mesh_normals(wt_static_shading *s)
{
    uint32_t t;
    s->normals = (float *)malloc(3 * sizeof(float) * (s->data.triangle_count ? s->data.triangle_count : 1));
    if (!s->normals) return -1;
    for (t = 0; t < s->data.triangle_count; t++) {
        const float *a = s->data.positions + 3 * (size_t)s->data.indices[3 * t];
        const float *b = s->data.positions + 3 * (size_t)s->data.indices[3 * t + 1];
        const float *c = s->data.positions + 3 * (size_t)s->data.indices[3 * t + 2];
        float e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] }, e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
        float *n = s->normals + 3 * (size_t)t, l;
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        l = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (l > 0.0f) { n[0] /= l; n[1] /= l; n[2] /= l; }
    }
    return 0;
}

/* Builds the static office's shading data: the radiosity solution and its
   interpolant mesh, or the mesh alone from the precompute cache (file
   "radinterp": radinterp_mesh_save's bytes; a loaded mesh needs no
   solution). The mesh is left without a job system: the frame's pixel
   pass shades runs of pixels from the raster's tile jobs. */
EX_FN int wt_static_shading_build(wt_world *w, wt_static_shading *s, char *err, size_t err_size)
{
    const wt_options *o = &w->opt;
    radinterp_solution *sol = NULL;
    radinterp_mesh_desc md;
    radinterp_result rr;
    wt_progress bar;
    wt__log log;
    void *data = NULL;
    size_t size = 0;
    double t0;
    char detail[256];
    int got = 0;
    memset(s, 0, sizeof *s);
    s->key = wt__radinterp_key(w);
    t0 = wt_seconds();
    if (o->use_cache) got = wt_cache_load(o->cache_dir, "radinterp", s->key, &data, &size);
    if (got == 1) {
        s->reused = radinterp_mesh_load_from_memory(data, size, NULL, &s->mesh) == RADINTERP_OK;
        free(data);
    }
    if (!s->reused) {
        t0 = wt_seconds();
        if (wt__radiosity_solve(w, &sol, err, err_size) != 0) return -1;
        s->seconds_solve = wt_seconds() - t0;
        log.text[0] = 0;
        memset(&md, 0, sizeof md);
        md.min_leaf_area = o->min_leaf_area;
        md.parallel_for = ex_pool_parallel_for;
        md.parallel_user = w->pool;
        md.log = wt__keep_log;
        md.log_user = &log;
        wt_progress_begin(&bar, "radiosity interpolants", o->progress);
        md.progress = wt_progress_update;
        md.progress_user = &bar;
        t0 = wt_seconds();
        rr = radinterp_build_mesh(sol, &md, &s->mesh);
        radinterp_solution_destroy(sol);
        if (rr != RADINTERP_OK) {
            snprintf(err, err_size, "radinterp_build_mesh: %s%s%s", radinterp_result_string(rr), log.text[0] ? ": " : "",
                     log.text);
            return -1;
        }
        wt_progress_end(&bar);
        s->seconds_mesh = wt_seconds() - t0;
        radinterp_mesh_set_parallel_for(s->mesh, NULL, NULL);
        if (o->use_cache && radinterp_mesh_save_to_memory(s->mesh, NULL, &data, &size) == RADINTERP_OK) {
            if (wt_cache_store(o->cache_dir, "radinterp", s->key, data, size, err, err_size) != 0) err[0] = 0;
            radinterp_free_memory(NULL, data);
        }
    }
    radinterp_mesh_get_data(s->mesh, &s->data);
    radinterp_mesh_get_info(s->mesh, &s->info);
    if (s->reused)
        snprintf(detail, sizeof detail, " (%u triangles)", s->info.triangle_count);
    else
        snprintf(detail, sizeof detail, " (solve %.2f s; mesh %.1f s: %u triangles, %u of %u discontinuities active, "
                 "%llu IrradianceAtPoint samples)", s->seconds_solve, s->seconds_mesh, s->info.triangle_count,
                 s->info.active_discontinuities, s->info.discontinuities, (unsigned long long)s->info.samples);
    wt__cache_say(w, "radiosity mesh", "radinterp", s->key, got != 0, s->reused, wt_seconds() - t0, detail);
    if (s->data.triangle_count == 0 || s->data.triangle_count >= EX_RASTER_EMPTY - w->bunny.tri_count)
        return wt__fail(err, err_size, "%s", "the radiosity mesh has no triangles, or too many for the ID buffer");
    return wt__mesh_normals(s) == 0 ? 0 : wt__fail(err, err_size, "%s", "out of memory");
}

/* Shades a run of count pixels of one static triangle ids[0] (every
   ids[i] the same, below s->data.triangle_count; barycentrics st[2i],
   st[2i+1]) from the triangle's interpolant: rgb[3i..] = radiosity B in
   W/m^2 (radinterp_shade_span: the coefficients loaded once for the run,
   or with gouraud the corners' radiosities blended linearly). */
EX_FN int wt_static_shading_shade(const wt_static_shading *s, const uint32_t *ids, const float *st, size_t count,
                                  int gouraud, float *rgb)
{
    radinterp_result rr;
    if (!s->mesh || !ids) return -1;
    rr = gouraud ? radinterp_shade_gouraud(s->mesh, ids, st, count, rgb)
                 : radinterp_shade_span(s->mesh, ids[0], st, count, rgb);
    return rr == RADINTERP_OK ? 0 : -1;
}

EX_FN void wt_static_shading_free(wt_static_shading *s)
{
    radinterp_mesh_destroy(s->mesh);
    free(s->normals);
    memset(s, 0, sizeof *s);
}

/* The irradiance volume's scene: the mesh's triangles with vertices of
   their own (3 per triangle), each corner's radiance its triangle's
   radiosity there over pi (data.corner_radiosity: the patch's own value,
   not blended with the patches that meet at a shared vertex; irrvol
   interpolates it linearly across the triangle). The emitters' triangles
   are IMPORTANT, so informed sampling never misses the lamp. */
typedef struct wt_volume_scene {
    float *positions, *radiance;
    uint32_t *indices, *materials;
    irrvol_material material[2];   /* 0: reflector, 1: emitter (flags only: vertex radiance replaces theirs) */
    irrvol_material *panes;        /* by day: the two above, then one per scene material (its transmittance) */
    uint32_t negative;             /* corner radiosities below 0 (or NaN) clamped */
} wt_volume_scene;

EX_FN void wt_volume_scene_free(wt_volume_scene *v)
{
    free(v->positions);
    free(v->radiance);
    free(v->indices);
    free(v->materials);
    free(v->panes);
    memset(v, 0, sizeof *v);
}

/* The volume's scene by day: the sky (irrvol's background or environment)
   and the glass. A mesh triangle of a pane (its patch's material has a
   transmittance) takes material 2 + that material, which passes light as
   the scene's does; its radiance stays the pane's own radiosity. Scenes
   without either are left as they are. Returns 0, or -1 out of memory. */
static int wt__volume_daylight(const wt_world *w, const wt_static_shading *st, wt_volume_scene *v, irrvol_desc *src)
{
    const obj_scene *s = &w->office;
    uint32_t t, m;
    if (w->layout.has_sky) {
        memcpy(src->background, w->layout.sky.radiance, sizeof src->background);
        src->environment = w->layout.sky.map;
        src->environment_width = (uint32_t)w->layout.sky.width;
        src->environment_height = (uint32_t)w->layout.sky.height;
    }
    if (!w->tracer->has_glass) return 0;
    v->panes = (irrvol_material *)calloc(2 + (size_t)s->material_count, sizeof *v->panes);
    if (!v->panes) return -1;
    memcpy(v->panes, v->material, sizeof v->material);
    for (m = 0; m < s->material_count; m++) {
        v->panes[2 + m] = v->material[0];
        memcpy(v->panes[2 + m].transmittance, s->materials[m].tf, sizeof v->panes[2 + m].transmittance);
    }
    for (t = 0; t < st->data.triangle_count; t++) {
        uint32_t f = st->data.triangle_patch[t], mat = f < s->face_count ? s->face_material[f] : s->material_count;
        if (mat < s->material_count && (s->materials[mat].tf[0] > 0.0f || s->materials[mat].tf[1] > 0.0f ||
                                        s->materials[mat].tf[2] > 0.0f))
            v->materials[t] = 2 + mat;
    }
    src->materials = v->panes;
    src->material_count = 2 + s->material_count;
    return 0;
}

EX_FN int wt_volume_scene_make(const wt_static_shading *s, wt_volume_scene *v, irrvol_desc *src)
{
    const radinterp_mesh_data *d = &s->data;
    size_t n = d->triangle_count, t, k;
    memset(v, 0, sizeof *v);
    v->positions = (float *)malloc(9 * sizeof(float) * n);
    v->radiance = (float *)malloc(9 * sizeof(float) * n);
    v->indices = (uint32_t *)malloc(3 * sizeof(uint32_t) * n);
    v->materials = (uint32_t *)malloc(sizeof(uint32_t) * n);
    if (!v->positions || !v->radiance || !v->indices || !v->materials) {
        wt_volume_scene_free(v);
        return -1;
    }
    for (t = 0; t < n; t++) {
        const float *e = d->emission + 3 * t;
        for (k = 0; k < 3; k++) {
            memcpy(v->positions + 9 * t + 3 * k, d->positions + 3 * (size_t)d->indices[3 * t + k], 3 * sizeof(float));
            v->indices[3 * t + k] = (uint32_t)(3 * t + k);
        }
        for (k = 0; k < 9; k++) {   /* the interpolant's value at a corner, clamped at 0 like radinterp_shade */
            float b = d->corner_radiosity[9 * t + k];
            v->radiance[9 * t + k] = b > 0.0f ? b / WT_PI : 0.0f;
            if (!(b >= 0.0f)) v->negative++;
        }
        v->materials[t] = e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f;
    }
    v->material[1].flags = IRRVOL_MATERIAL_IMPORTANT;
    memset(src, 0, sizeof *src);
    src->positions = v->positions;
    src->vertex_count = (uint32_t)(3 * n);
    src->indices = v->indices;
    src->triangle_count = (uint32_t)n;
    src->triangle_materials = v->materials;
    src->materials = v->material;
    src->material_count = 2;
    src->vertex_radiance = v->radiance;
    return 0;
}

static void wt__put_floats(wt_bytes *b, const float *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        unsigned char q[4];
        uint32_t u;
        memcpy(&u, &v[i], 4);
        wt__put32(q, u);
        wt_bytes_put(b, q, 4);
    }
}

static int wt__get_floats(wt_bytes *b, float *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++) {
        unsigned char q[4];
        uint32_t u;
        if (!wt_bytes_get(b, q, 4)) return 0;
        u = wt__get32(q);
        memcpy(&v[i], &u, 4);
    }
    return 1;
}

/* The bunny's self-occlusion ratio per vertex (irrvol_visibility_ratio,
   thesis 6.1.3): the cosine-weighted open part of each vertex's
   hemisphere. A rigid bunny keeps it as it moves: computed once, cached.
   ratio: one float per bunny vertex. */
EX_FN int wt_bunny_visibility(wt_world *w, float *ratio, int *reused, char *err, size_t err_size)
{
    const wt_options *o = &w->opt;
    uint64_t key = wt_hash_str(w->scene_hash, "visibility"), n;
    irrvol_visibility_desc vd;
    irrvol_result ir;
    wt_progress bar;
    void *data = NULL;
    size_t size = 0;
    int got = 0;
    key = wt_hash_u64(key, IRRVOL_VERSION_MAJOR * 10000u + IRRVOL_VERSION_MINOR * 100u + IRRVOL_VERSION_PATCH);
    key = wt_hash_u64(key, (uint64_t)o->visibility_rays);
    key = wt_hash_u64(key, o->seed);
    double t0 = wt_seconds();
    *reused = 0;
    if (o->use_cache) got = wt_cache_load(o->cache_dir, "visibility", key, &data, &size);
    if (got == 1) {
        wt_bytes b;
        memset(&b, 0, sizeof b);
        b.data = (unsigned char *)data;
        b.size = size;
        *reused = wt_bytes_get_u64(&b, &n) && n == w->bunny.vertex_count && wt__get_floats(&b, ratio, (size_t)n) &&
                  b.read == b.size;
        free(data);
        if (*reused) {
            wt__cache_say(w, "bunny self-occlusion", "visibility", key, 1, 1, 0.0, "");
            return 0;
        }
    }
    memset(&vd, 0, sizeof vd);
    vd.positions = w->bunny.positions;
    vd.vertex_count = w->bunny.vertex_count;
    vd.indices = w->bunny.tri_indices;
    vd.triangle_count = w->bunny.tri_count;
    vd.normals = w->bunny_normals;
    vd.rays = (uint32_t)o->visibility_rays;
    vd.seed = o->seed;
    vd.parallel_for = ex_pool_parallel_for;
    vd.parallel_user = w->pool;
    wt_progress_begin(&bar, "bunny self-occlusion", o->progress);
    vd.progress = wt_progress_update;
    vd.progress_user = &bar;
    ir = irrvol_visibility_ratio(&vd, ratio);
    if (ir != IRRVOL_OK) {
        snprintf(err, err_size, "irrvol_visibility_ratio: %s", irrvol_result_string(ir));
        return -1;
    }
    wt_progress_end(&bar);
    if (o->use_cache) {
        wt_bytes b;
        memset(&b, 0, sizeof b);
        wt_bytes_put_u64(&b, w->bunny.vertex_count);
        wt__put_floats(&b, ratio, w->bunny.vertex_count);
        if (b.failed || wt_cache_store(o->cache_dir, "visibility", key, b.data, b.size, err, err_size) != 0) err[0] = 0;
        free(b.data);
    }
    wt__cache_say(w, "bunny self-occlusion", "visibility", key, got != 0, 0, wt_seconds() - t0, "");
    return 0;
}

/* An irradiance volume of the office (Greger's grid: 7^3 first level, 3^3
   second level, k = opt.volume_resolution) whose radiance comes from
   `source` (its scene, materials or radiance callback; every other field is
   set here). source_key identifies the source for the precompute cache. */
EX_FN int wt_volume_build(wt_world *w, const irrvol_desc *source, uint64_t source_key, irrvol **out, int *reused,
                          char *err, size_t err_size)
{
    const wt_options *o = &w->opt;
    irrvol_desc d = *source;
    irrvol_result ir;
    wt_progress bar;
    void *data = NULL;
    size_t size = 0;
    uint64_t key = wt_hash_str(source_key, "volume");
    wt__log log;
    int got = 0;
    key = wt_hash_u64(key, IRRVOL_FILE_FORMAT_VERSION);
    key = wt_hash_u64(key, IRRVOL_VERSION_MAJOR * 10000u + IRRVOL_VERSION_MINOR * 100u + IRRVOL_VERSION_PATCH);
    key = wt_hash_u64(key, (uint64_t)o->volume_resolution);
    key = wt_hash_u64(key, o->seed);
    irrvol_volume_info info;
    char detail[128];
    double t0 = wt_seconds();
    *out = NULL;
    *reused = 0;
    if (o->use_cache) got = wt_cache_load(o->cache_dir, "volume", key, &data, &size);
    if (got == 1) {
        *reused = irrvol_load_from_memory(data, size, NULL, out) == IRRVOL_OK;
        free(data);
        if (*reused) {
            wt__cache_say(w, "irradiance volume", "volume", key, 1, 1, 0.0, "");
            return 0;
        }
    }
    d.resolution = (uint32_t)o->volume_resolution;
    d.seed = o->seed;
    d.parallel_for = ex_pool_parallel_for;
    d.parallel_user = w->pool;
    wt_progress_begin(&bar, "irradiance volume", o->progress);
    d.progress = wt_progress_update;
    d.progress_user = &bar;
    log.text[0] = 0;
    d.log = wt__keep_log;
    d.log_user = &log;
    ir = irrvol_build(&d, out);
    if (ir != IRRVOL_OK) {
        snprintf(err, err_size, "irrvol_build: %s%s%s", irrvol_result_string(ir), log.text[0] ? ": " : "", log.text);
        return -1;
    }
    wt_progress_end(&bar);
    if (o->use_cache && irrvol_save_to_memory(*out, NULL, &data, &size) == IRRVOL_OK) {
        if (wt_cache_store(o->cache_dir, "volume", key, data, size, err, err_size) != 0) err[0] = 0;
        irrvol_free_memory(NULL, data);
    }
    detail[0] = 0;
    if (irrvol_info(*out, &info) == IRRVOL_OK)
        snprintf(detail, sizeof detail, " (%u samples, %u bins each)", info.sample_count, 2 * info.resolution * info.resolution);
    wt__cache_say(w, "irradiance volume", "volume", key, got != 0, 0, wt_seconds() - t0, detail);
    return 0;
}

/* Places the bunny's vertices and normals by pose and lights them from the
   volume: rgb = Kd H / pi (eq. 4.7) times the self-occlusion ratio. */
EX_FN void wt_bunny_light(const wt_world *w, const irrvol *vol, const float *visibility, const float pose[12],
                          float *world_pos, float *world_normals, float *rgb)
{
    uint32_t v, n = w->bunny.vertex_count;
    for (v = 0; v < n; v++) {
        float *q = world_normals + 3 * (size_t)v, l;
        ex__affine_point(pose, w->bunny.positions + 3 * (size_t)v, world_pos + 3 * (size_t)v);
        ex__affine_vector(pose, w->bunny_normals + 3 * (size_t)v, q);
        l = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (l > 0.0f) { q[0] /= l; q[1] /= l; q[2] /= l; }
    }
    irrvol_query_many(vol, IRRVOL_FILTER_DEFAULT, IRRVOL_WEIGHTING_DEFAULT, n, world_pos, 0, world_normals, 0, rgb);
    for (v = 0; v < 3 * n; v++) rgb[v] *= WT_BUNNY_KD / WT_PI * (visibility ? visibility[v / 3] : 1.0f);
}

/* Rasterizes the static mesh (ids 0 .. static_count-1, its indices below
   static_vertex_count) and the posed bunny (ids static_count + triangle)
   into ra in one pass over the tiles: each tile job clears its tile, draws
   both and runs ra->tile_done (when set) on the finished tile. */
EX_FN int wt_raster_scene(const wt_world *w, ex_raster *ra, const rendercache_camera *c, const float *static_positions,
                          const uint32_t *static_indices, uint32_t static_count, uint32_t static_vertex_count,
                          const float *bunny_world)
{
    ex_camera ec = wt_ex_camera(c);
    ex_raster_mesh meshes[2];
    meshes[0].positions = static_positions;
    meshes[0].indices = static_indices;
    meshes[0].tri_count = static_count;
    meshes[0].id_base = 0;
    meshes[0].vertex_count = static_vertex_count;
    meshes[1].positions = bunny_world;
    meshes[1].indices = w->bunny.tri_indices;
    meshes[1].tri_count = w->bunny.tri_count;
    meshes[1].id_base = static_count;
    meshes[1].vertex_count = w->bunny.vertex_count;
    ex_raster_clear_deferred(ra);
    return ex_raster_draw_meshes(ra, &ec, meshes, 2);
}

/* The bunny as a sphere for its occlusion blob: the sphere of its volume
   (divergence theorem over its triangles), centred at its centroid; OBJ
   coordinates for the centre, metres for the radius. A mesh without a
   usable volume gets the sphere inside its bounding box. */
EX_FN void wt_bunny_sphere(const wt_world *w, float centre[3], float *radius)
{
    const float *p = w->bunny.positions;
    double vol = 0.0, c[3] = { 0, 0, 0 };
    uint32_t t;
    int k;
    for (t = 0; t < w->bunny.tri_count; t++) {
        const float *a = p + 3 * (size_t)w->bunny.tri_indices[3 * t], *b = p + 3 * (size_t)w->bunny.tri_indices[3 * t + 1];
        const float *q = p + 3 * (size_t)w->bunny.tri_indices[3 * t + 2];
        /* signed volume of the tetrahedron (0, a, b, q) and its centroid */
        double v = ((double)a[0] * ((double)b[1] * q[2] - (double)b[2] * q[1]) -
                    (double)a[1] * ((double)b[0] * q[2] - (double)b[2] * q[0]) +
                    (double)a[2] * ((double)b[0] * q[1] - (double)b[1] * q[0])) / 6.0;
        vol += v;
        for (k = 0; k < 3; k++) c[k] += v * ((double)a[k] + b[k] + q[k]) / 4.0;
    }
    for (k = 0; k < 3; k++) centre[k] = 0.5f * (w->bunny_lo[k] + w->bunny_hi[k]);
    *radius = 0.25f * WT_BUNNY_SCALE * (w->bunny_hi[1] - w->bunny_lo[1]);
    if (vol > 0.0) {
        double r = cbrt(3.0 * vol / (4.0 * WT_PI));
        int inside = 1;
        for (k = 0; k < 3; k++) inside &= c[k] / vol > w->bunny_lo[k] && c[k] / vol < w->bunny_hi[k];
        if (inside && r < 0.5 * (w->bunny_hi[1] - w->bunny_lo[1])) {
            for (k = 0; k < 3; k++) centre[k] = (float)(c[k] / vol);
            *radius = (float)(WT_BUNNY_SCALE * r);
        }
    }
}

static int wt__radiosity_create(wt_renderer *r, char *err, size_t err_size)
{
    wt_world *w = r->w;
    wt_volume_scene vs;
    irrvol_desc source;
    size_t nv = w->bunny.vertex_count;
    int result;
    if (wt_static_shading_build(w, &r->statics, err, err_size) != 0) return -1;
    /* the volume's radiance: the radiosity solution through the mesh */
    if (wt_volume_scene_make(&r->statics, &vs, &source) != 0 || wt__volume_daylight(w, &r->statics, &vs, &source) != 0) {
        wt_volume_scene_free(&vs);
        return wt__fail(err, err_size, "%s", "out of memory");
    }

    result = wt_volume_build(w, &source, wt_hash_str(r->statics.key, "mesh corners"), &r->volume, &r->reused_volume,
                             err, err_size);
    wt_volume_scene_free(&vs);
    if (result != 0) return -1;
    r->visibility = (float *)malloc(sizeof(float) * nv);
    r->bunny_world = (float *)malloc(3 * sizeof(float) * nv);
    r->bunny_world_normals = (float *)malloc(3 * sizeof(float) * nv);
    r->bunny_rgb = (float *)malloc(3 * sizeof(float) * nv);
    if (!r->visibility || !r->bunny_world || !r->bunny_world_normals || !r->bunny_rgb ||
        ex_raster_init(&r->raster, (int)r->width, (int)r->height) != 0)
        return wt__fail(err, err_size, "%s", "out of memory");
    r->tile_cpu = (double *)calloc((size_t)r->raster.tiles_x * (size_t)r->raster.tiles_y, sizeof(double));
    if (!r->tile_cpu) return wt__fail(err, err_size, "%s", "out of memory");
    r->raster.pool = w->pool;
    /* the shading reads the tiles' own buffers */
    r->raster.skip = EX_RASTER_SKIP_DEPTH | EX_RASTER_SKIP_ID | EX_RASTER_SKIP_BARY;
    wt_bunny_sphere(w, r->bunny_centre, &r->bunny_radius);
    return wt_bunny_visibility(w, r->visibility, &r->reused_visibility, err, err_size);
}

/* The bunny's occlusion blob (an approximation, not a shadow ray test): a
   point of the office with normal n near the bunny's sphere (centre c,
   radius R at distance d) loses the sphere's share of its hemisphere, the
   form factor F = (R / d)^2 cos(theta) of a sphere seen from a
   differential area, from its reflected light, as if the light arriving
   there were the same from every direction: B' = E + (B - E)(1 - F). F
   fades to 0 between 3R and 6R (where it is under 3%). */
#define WT__BLOB_NEAR 3.0f
#define WT__BLOB_FAR 6.0f

static float wt__blob(const float sphere[4], const float p[3], const float n[3])
{
    float v[3] = { sphere[0] - p[0], sphere[1] - p[1], sphere[2] - p[2] };
    float d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2], r2 = sphere[3] * sphere[3];
    float far2 = WT__BLOB_FAR * WT__BLOB_FAR * r2, near2 = WT__BLOB_NEAR * WT__BLOB_NEAR * r2;
    float c = v[0] * n[0] + v[1] * n[1] + v[2] * n[2], f, fade;
    if (d2 >= far2 || c <= 0.0f) return 1.0f;
    f = d2 > r2 ? r2 * c / (d2 * sqrtf(d2)) : 1.0f;
    fade = d2 <= near2 ? 1.0f : (far2 - d2) / (far2 - near2);
    f *= fade;
    return f < 1.0f ? 1.0f - f : 0.0f;
}

/* The pixels the blob may touch this frame: the screen box of the cube of
   half side 6R around the sphere, or the whole image when a corner lies
   behind the camera. */
static void wt__blob_box(wt_renderer *r, const ex_camera *cam)
{
    int i, k, box[4] = { (int)r->width, (int)r->height, 0, 0 };
    float ext = WT__BLOB_FAR * r->sphere[3];
    for (i = 0; i < 8; i++) {
        float p[3], px, py, depth;
        for (k = 0; k < 3; k++) p[k] = r->sphere[k] + ((i >> k) & 1 ? ext : -ext);
        if (!ex_camera_project(cam, p, &px, &py, &depth) || !(depth > 0.0f) || !isfinite(px) || !isfinite(py)) {
            box[0] = box[1] = 0;
            box[2] = (int)r->width;
            box[3] = (int)r->height;
            break;
        }
        if (px < (float)box[0]) box[0] = px < 0.0f ? 0 : (int)px;
        if (py < (float)box[1]) box[1] = py < 0.0f ? 0 : (int)py;
        if (px + 1.0f > (float)box[2]) box[2] = px + 1.0f > (float)r->width ? (int)r->width : (int)px + 1;
        if (py + 1.0f > (float)box[3]) box[3] = py + 1.0f > (float)r->height ? (int)r->height : (int)py + 1;
    }
    memcpy(r->blob_box, box, sizeof box);
}

typedef struct wt__pixel_job {
    const wt_renderer *r;
    float *rgb;
    int blob;
    double *tile_cpu;            /* per raster tile: the thread CPU seconds its shading took */
} wt__pixel_job;

/* Copies a finished row of the frame (n floats) to dst with streaming
   stores where SSE2 and the alignment allow them: the frame is far larger
   than the cache, and a streaming store does not first read the line it
   writes, which halves the memory traffic of the frame's colours. */
static void wt__store_row(float *dst, const float *src, size_t n)
{
#if defined(__SSE2__)
    if (((uintptr_t)dst & 15u) == 0 && n % 4 == 0) {
        size_t i;
        for (i = 0; i < n; i += 4) _mm_stream_ps(dst + i, _mm_loadu_ps(src + i));
        return;
    }
#endif
    memcpy(dst, src, n * sizeof(float));
}

/* CPU time of the calling thread, in seconds. */
static double wt__thread_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Radiance of a run of n pixels of static triangle id starting at (x, y),
   in place over its radiosities B: (E + (B - E) * blob) / pi, where blob
   is the bunny's occlusion (1 outside its box). A triangle that emits
   nothing and no blob: B / pi, the same bits, in a loop the compiler
   vectorises. */
static void wt__static_radiance(const wt__pixel_job *j, uint32_t id, const float *st, int x, int y, int n, float *rgb)
{
    const wt_renderer *r = j->r;
    const wt_static_shading *s = &r->statics;
    const float *e = s->data.emission + 3 * (size_t)id;
    const int *box = r->blob_box;
    int blob = j->blob && y >= box[1] && y < box[3] && x < box[2] && x + n > box[0], i, k;
    if (!blob && e[0] == 0.0f && e[1] == 0.0f && e[2] == 0.0f) {
        for (i = 0; i < 3 * n; i++) rgb[i] *= 1.0f / WT_PI;
        return;
    }
    for (i = 0; i < n; i++) {
        float keep = 1.0f, *out = rgb + 3 * i;
        if (blob && x + i >= box[0] && x + i < box[2]) {
            const uint32_t *tri = s->data.indices + 3 * (size_t)id;
            const float *a = s->data.positions + 3 * (size_t)tri[0], *b = s->data.positions + 3 * (size_t)tri[1];
            const float *c = s->data.positions + 3 * (size_t)tri[2];
            float u = st[2 * i], v = st[2 * i + 1], o = 1.0f - u - v, q[3];
            for (k = 0; k < 3; k++) q[k] = o * a[k] + u * b[k] + v * c[k];
            keep = wt__blob(r->sphere, q, s->normals + 3 * (size_t)id);
        }
        for (k = 0; k < 3; k++) out[k] = (e[k] + (out[k] - e[k]) * keep) * (1.0f / WT_PI);
    }
}

/* A run of n pixels of one bunny triangle: the Gouraud blend of its
   vertices' radiances. */
static void wt__bunny_radiance(const wt_renderer *r, uint32_t triangle, const float *st, int n, float *rgb)
{
    const uint32_t *tri = r->w->bunny.tri_indices + 3 * (size_t)triangle;
    const float *a = r->bunny_rgb + 3 * (size_t)tri[0], *b = r->bunny_rgb + 3 * (size_t)tri[1];
    const float *c = r->bunny_rgb + 3 * (size_t)tri[2];
    int i, k;
    for (i = 0; i < n; i++) {
        float u = st[2 * i], v = st[2 * i + 1], o = 1.0f - u - v;
        for (k = 0; k < 3; k++) rgb[3 * i + k] = o * a[k] + u * b[k] + v * c[k];
    }
}

/* The pixel pass over a finished raster tile (ex_raster.tile_done: fused
   with the raster, reading the tile's own buffers while they are in the
   cache), writing each pixel of the frame once, a row at a time into a
   buffer on the stack, a run of pixels of one triangle at a time (about
   10 at 1920x1080): static pixels get their radiosity B
   (radinterp_shade_span) and then radiance (wt__static_radiance); the
   bunny's the Gouraud blend of its vertex radiances; empty pixels black. */
static void wt__shade_tile(void *ctx, const ex_raster_tile *tile)
{
    const wt__pixel_job *j = (const wt__pixel_job *)ctx;
    const wt_renderer *r = j->r;
    const wt_static_shading *s = &r->statics;
    const uint32_t nt = s->data.triangle_count, nb = r->w->bunny.tri_count;
    const int x0 = tile->x0;
    float colours[3 * EX_RASTER_TILE];     /* one row's radiance */
    double cpu = wt__thread_cpu();
    int i, n = tile->x1 - x0, y, end;
    for (y = tile->y0; y < tile->y1; y++) {
        const uint32_t *ids = tile->id + (y - tile->y0) * EX_RASTER_TILE;   /* pixel x0 + i at i */
        const float *st = tile->bary + 2 * (y - tile->y0) * EX_RASTER_TILE;
        for (i = 0; i < n; i = end) {
            uint32_t id = ids[i];
            float *out = colours + 3 * i;
            for (end = i + 1; end < n && ids[end] == id;) end++;
            if (id < nt) {
                wt_static_shading_shade(s, ids + i, st + 2 * i, (size_t)(end - i), r->w->opt.gouraud, out);
                wt__static_radiance(j, id, st + 2 * i, x0 + i, y, end - i, out);
            } else if (id != EX_RASTER_EMPTY && id - nt < nb) {
                wt__bunny_radiance(r, id - nt, st + 2 * i, end - i, out);
            } else {
                memset(out, 0, 3 * sizeof(float) * (size_t)(end - i));
            }
        }
        wt__store_row(j->rgb + 3 * ((size_t)y * r->width + (size_t)x0), colours, 3 * (size_t)n);
    }
#if defined(__SSE2__)
    _mm_sfence();   /* the streaming stores are seen before the tile counts as done */
#endif
    j->tile_cpu[(tile->y0 / EX_RASTER_TILE) * r->raster.tiles_x + x0 / EX_RASTER_TILE] = wt__thread_cpu() - cpu;
}

/* CPU time of the whole process (all its threads), in seconds. */
static double wt__process_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int wt__radiosity_view(wt_renderer *r, const rendercache_camera *camera, double t, float *rgb, wt_frame_stats *st)
{
    wt_world *w = r->w;
    double t0 = wt_seconds(), a, shade = 0.0;
    rendercache_camera cam = *camera;
    ex_camera ec = wt_ex_camera(&cam);
    wt__pixel_job j;
    int tile, tiles = r->raster.tiles_x * r->raster.tiles_y, result;
    wt_set_time(w, t);
    a = wt__thread_cpu();
    wt_bunny_light(w, r->volume, r->visibility, w->pose, r->bunny_world, r->bunny_world_normals, r->bunny_rgb);
    st->phase[2] = wt__thread_cpu() - a;
    a = wt__process_cpu();
    ex__affine_point(w->pose, r->bunny_centre, r->sphere);
    r->sphere[3] = r->bunny_radius;
    j.r = r;
    j.rgb = rgb;
    j.blob = w->opt.bunny_shadow;
    j.tile_cpu = r->tile_cpu;
    if (j.blob) wt__blob_box(r, &ec);
    r->raster.tile_done = wt__shade_tile;   /* shading fused with the tile jobs */
    r->raster.tile_user = &j;
    result = wt_raster_scene(w, &r->raster, &cam, r->statics.data.positions, r->statics.data.indices,
                             r->statics.data.triangle_count, r->statics.data.vertex_count, r->bunny_world);
    r->raster.tile_done = NULL;
    if (result != 0) return -1;
    /* CPU seconds over all threads: the pass's, less its tiles' shading */
    for (tile = 0; tile < tiles; tile++) shade += r->tile_cpu[tile];
    st->phase[1] = shade;
    st->phase[0] = wt__process_cpu() - a - shade;
    st->samples = w->bunny.vertex_count;
    st->total = wt_seconds() - t0;
    return 0;
}

static int wt__radiosity_frame(wt_renderer *r, int frame, float *rgb, wt_frame_stats *st)
{
    double t = wt_frame_time(&r->w->opt, frame);
    rendercache_camera cam = wt_camera(&r->w->opt, t, r->width, r->height);
    return wt__radiosity_view(r, &cam, t, rgb, st);
}

/* ---- the renderer ------------------------------------------------------- */

EX_FN void wt_renderer_destroy(wt_renderer *r)
{
    int i;
    if (!r) return;
    rendercache_destroy(r->rc);
    free(r->req);
    free(r->samples);
    free(r->trail_lamps);
    free(r->trail_lamp_of);
    free(r->trail_seen);
    ex_baseviews_free(&r->bv);
    free(r->base_needed);
    rendercache_keytimes_destroy(r->bunny_light);
    free(r->bunny_indirect);
    free(r->saved_key_times);
    free(r->saved_key_values);
    rendercache_warper_destroy(r->rec.blender);
    rendercache_warper_destroy(r->rec.warper);
    for (i = 0; i < 8; i++) rendercache_range_image_destroy(r->blend[i]);
    rendercache_range_image_destroy(r->out);
    wt_static_shading_free(&r->statics);
    irrvol_destroy(r->volume);
    free(r->visibility);
    free(r->bunny_world);
    free(r->bunny_world_normals);
    free(r->bunny_rgb);
    free(r->tile_cpu);
    ex_raster_free(&r->raster);
    free(r->points);
    free(r->index);
    free(r);
}

/* The renderer of w's mode, with its precompute (loaded from the cache
   directory when it holds the data for these scene files and parameters,
   else computed and saved there). Returns 0, or -1 with a message. */
EX_FN int wt_renderer_create(wt_world *w, wt_renderer **out, char *err, size_t err_size)
{
    wt_renderer *r = (wt_renderer *)calloc(1, sizeof *r);
    const wt_options *o = &w->opt;
    uint32_t n;
    double t0 = wt_seconds();
    int result;
    *out = NULL;
    err[0] = 0;
    if (!r) return wt__fail(err, err_size, "%s", "out of memory");
    r->w = w;
    r->mode = o->mode;
    r->width = (uint32_t)o->width;
    r->height = (uint32_t)o->height;
    n = r->width * r->height;
    if (o->mode == WT_MODE_BASEVIEWS && (uint32_t)(o->base_size * o->base_size) > n)
        n = (uint32_t)(o->base_size * o->base_size);
    r->points = (wt_point *)malloc(sizeof(wt_point) * n);
    r->index = (uint32_t *)malloc(sizeof(uint32_t) * n);
    if (!r->points || !r->index) {
        wt_renderer_destroy(r);
        return wt__fail(err, err_size, "%s", "out of memory");
    }
    switch (o->mode) {
    case WT_MODE_RAYTRACE: result = wt__raytrace_create(r, err, err_size); break;
    case WT_MODE_BASEVIEWS: result = wt__baseviews_create(r, err, err_size); break;
    default: result = wt__radiosity_create(r, err, err_size); break;
    }
    if (result != 0) {
        wt_renderer_destroy(r);
        return -1;
    }
    r->seconds_precompute = wt_seconds() - t0;
    *out = r;
    return 0;
}

/* The end of a frame: "other" is the time no named phase took. */
static int wt__frame_done(wt_renderer *r, int result, wt_frame_stats *st)
{
    if (result == 0) {
        double known = 0.0;
        int k;
        for (k = 0; k < WT_PHASES; k++)
            if (wt_phase_name(r->mode, k) && strcmp(wt_phase_name(r->mode, k), "other") != 0) known += st->phase[k];
        for (k = 0; k < WT_PHASES; k++)
            if (wt_phase_name(r->mode, k) && !strcmp(wt_phase_name(r->mode, k), "other"))
                st->phase[k] = st->total > known ? st->total - known : 0.0;
        r->frames_done++;
    }
    return result;
}

/* Renders frame `frame` of the path into rgb (width x height x 3 floats,
   linear radiance). Mode raytrace must be given its frames in order. */
EX_FN int wt_render_frame(wt_renderer *r, int frame, float *rgb, wt_frame_stats *st)
{
    int result;
    memset(st, 0, sizeof *st);
    st->lrms = st->converged = -1.0;
    switch (r->mode) {
    case WT_MODE_RAYTRACE: result = wt__raytrace_frame(r, frame, rgb, st); break;
    case WT_MODE_BASEVIEWS: result = wt__baseviews_frame(r, frame, rgb, st); break;
    default: result = wt__radiosity_frame(r, frame, rgb, st); break;
    }
    return wt__frame_done(r, result, st);
}

/* Renders the view of any camera (of the renderer's size) with the bunny
   at time t: the interactive viewer's free camera. Modes radiosity and
   raytrace (the render cache reprojects its points into whatever camera
   comes next); mode baseviews reconstructs views near its base views
   only, along the path: -1. */
EX_FN int wt_render_view(wt_renderer *r, const rendercache_camera *camera, double t, float *rgb, wt_frame_stats *st)
{
    int result;
    memset(st, 0, sizeof *st);
    st->lrms = st->converged = -1.0;
    if (!camera || camera->width != r->width || camera->height != r->height || r->mode == WT_MODE_BASEVIEWS) return -1;
    result = r->mode == WT_MODE_RAYTRACE ? wt__raytrace_view(r, camera, NULL, t, r->frames_done, rgb, st)
                                         : wt__radiosity_view(r, camera, t, rgb, st);
    return wt__frame_done(r, result, st);
}

#endif /* EXAMPLES_COMMON_WALKTHROUGH_H */
