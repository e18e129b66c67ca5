/* walkthrough.c - the project's main example: a walkthrough of a generated
   building (the default, --scene house: examples/data/building_1k.*, two
   storeys of two rooms, doors, windows, a staircase, lamps; --scene
   building: building_4k.*, two storeys of nine rooms) with a bunny walking
   from a lit room into a room without a lamp and up the stairs, the camera
   following it, or of the office (--scene office: the bunny under the desk
   and past the yellow divider), rendered with global illumination at
   interactive rates by composing the project's headers
   (examples/common/walkthrough.h holds the frame pipeline and plans the
   walk from the building's layout file; this file is the command line, the
   output and the timing table). Unless --frames is given, the number of
   frames follows the camera's route (wt_route_frames: 0.1 m and 1.5
   degrees a frame on average, at least 48); the header line prints it with
   the route's length and turn.
   Frames are tone-mapped by examples/common/image.h's filmic pipeline
   (exposure to middle grey per frame, ACES filmic curve, sRGB), the same
   as the interactive viewer (examples/viewer.c).

       cc -O2 -I. examples/walkthrough.c -o walkthrough -lm -lpthread
       ./walkthrough --out build/demo                 # mode radiosity, the house
       ./walkthrough --mode raytrace --out build/demo
       ./walkthrough --mode raytrace --scene daylight --out build/demo   # by day: glass and a sky

   Modes:
     radiosity  (the default) the online phase of Hardt 1996: the scene's
                radiosity solution and discontinuity mesh are precomputed
                (radinterp.h; the house's take about a minute on two
                cores, building_4k's far longer); per frame the rasterizer
                fills an ID + barycentric buffer and radinterp_shade_span
                evaluates the quadratic interpolants at every pixel, a run
                of pixels of one triangle at a time. The bunny is lit per
                vertex from an irradiance volume built from the radiosity
                solution (Greger 1996, irrvol.h), attenuated by its
                self-occlusion ratio, and casts an occlusion blob.
     raytrace   the render cache (Walter et al. 1999) fed by a ray tracer with
                direct light from the lamps and indirect light from cached 5D
                light vectors (Crespin & Peroche 2004): a pixel lit by an
                interpolated vector of weight W gets 1/W times the priority;
                a fixed sample budget per frame (8% of the pixels). The first
                frame is traced in full. Near the bunny the scene's
                indirect light is dimmed by the share of the hemisphere the
                bunny covers (ray-traced contact shadows; also in baseviews).
     baseviews  range-image reconstruction (Nimeroff, Dorsey & Rushmeier 1996):
                fish-eye base views and key times chosen by coherence tests,
                motion-compensated time blends, warps with both fills.

   Precomputed data (the radiosity mesh, the irradiance volume, the bunny's
   self-occlusion, light vectors along the path, base images) is cached
   under --cache (default build/cache) in files named by a hash of the scene
   files and the parameters; a second run reuses them. Writes
   <out>/walkthrough_<mode>_NNN.png, <out>/walkthrough_<mode>_sheet.png and
   prints a per-frame timing table in the style of Greger's figure 5.8. With
   --reference every frame is also traced in full with the same shading
   (<out>/walkthrough_<mode>_NNN_full.png) and the table shows the LRMS error
   of the displayed range. With --converged N frames N-1, 2N-1, ... are also
   rendered converged, twice with other random numbers, and the table shows
   their LRMS against a converged render with its own noise taken out
   (wt_converged_lrms; slow: 2 x 432 rays a pixel, kept in the
   precompute cache, so a second run of the same walk renders only its
   frames). --help lists the options.

   --scene daylight walks the house by day (building_1k_daylight.*:
   glass in the windows, lamps off, a sky named by its layout; every mode:
   radiosity passes light through the panes and lights the rooms with the
   sky, radinterp.h's GLASS AND SKY; its interpolant mesh takes longer to
   build than the house's).

   --scene FILE walks through a user's scene instead. An OBJ with a
   make_building.py layout beside it (FILE.layout) is read in place and
   walked along the route planned from its layout. Any other scene (or one
   given with --up, --scale, --drop-coincident; scene_load.h) in any format
   the build reads (OBJ; glTF, FBX, IFC, ... with Assimp) is turned to y-up
   metres and written as the OBJ + MTL pair the walkthrough reads, beside a
   copy of the bunny, in a directory under --cache that becomes the data
   directory; the camera and the bunny keep the office's paths. */
#define _POSIX_C_SOURCE 200809L
#include "examples/common/walkthrough.h"
#include "examples/common/scene_load.h"

#define SHEET_FRAMES 8
#define SHEET_COLUMNS 4

typedef struct run {
    wt_options o;
    wt_world *w;
    wt_renderer *r;
    float *rgb, *full, exposure, exposure_first;
    unsigned char *rgb8, *sheet_cells[SHEET_FRAMES];
    int sheet_cell_w, sheet_cell_h, sheet_count;
    wt_frame_stats *stats;
} run;

/* Downsamples an 8-bit image by an integer factor (box filter). */
static void shrink(const unsigned char *src, int w, int h, int f, unsigned char *dst)
{
    int x, y, i, j, k, cw = w / f, ch = h / f;
    for (y = 0; y < ch; y++)
        for (x = 0; x < cw; x++)
            for (k = 0; k < 3; k++) {
                int sum = 0;
                for (j = 0; j < f; j++)
                    for (i = 0; i < f; i++) sum += src[3 * ((size_t)(y * f + j) * (size_t)w + (size_t)(x * f + i)) + (size_t)k];
                dst[3 * ((size_t)y * (size_t)cw + (size_t)x) + (size_t)k] = (unsigned char)((sum + f * f / 2) / (f * f));
            }
}

static int sheet_frame(const run *u, int f)
{
    int i;
    for (i = 0; i < SHEET_FRAMES; i++)
        if (f == (u->o.frames - 1) * i / (SHEET_FRAMES - 1)) return i;
    return -1;
}

static int write_frame(run *u, int f)
{
    char path[1024];
    int cell;
    if (u->o.reference && u->o.write_frames) {   /* the full render beside the frame */
        ex_tonemap_filmic(u->full, u->o.width, u->o.height, u->exposure, u->rgb8);
        snprintf(path, sizeof path, "%s/walkthrough_%s_%03d_full.png", u->o.out, wt_mode_name(u->o.mode), f);
        if (ex_write_png(path, u->o.width, u->o.height, u->rgb8) != 0) {
            fprintf(stderr, "walkthrough: cannot write %s: %s\n", path, strerror(errno));
            return -1;
        }
    }
    ex_tonemap_filmic(u->rgb, u->o.width, u->o.height, u->exposure, u->rgb8);
    if (u->o.write_frames) {
        snprintf(path, sizeof path, "%s/walkthrough_%s_%03d.png", u->o.out, wt_mode_name(u->o.mode), f);
        if (ex_write_png(path, u->o.width, u->o.height, u->rgb8) != 0) {
            fprintf(stderr, "walkthrough: cannot write %s: %s\n", path, strerror(errno));
            return -1;
        }
    }
    cell = u->o.frames >= SHEET_FRAMES ? sheet_frame(u, f) : f;
    if (cell >= 0 && cell < SHEET_FRAMES && u->sheet_cells[cell]) {
        int factor = u->o.width / u->sheet_cell_w;
        shrink(u->rgb8, u->o.width, u->o.height, factor, u->sheet_cells[cell]);
        if (cell + 1 > u->sheet_count) u->sheet_count = cell + 1;
    }
    return 0;
}

static void write_sheet(run *u)
{
    char path[1024];
    int rows = (u->sheet_count + SHEET_COLUMNS - 1) / SHEET_COLUMNS, cols = u->sheet_count < SHEET_COLUMNS ? u->sheet_count : SHEET_COLUMNS;
    unsigned char *sheet;
    if (u->sheet_count == 0 || !u->o.write_frames) return;   /* --no-frames: no PNG at all (the directory is not made) */
    sheet = (unsigned char *)malloc(3 * (size_t)u->sheet_cell_w * (size_t)u->sheet_cell_h * (size_t)(rows * cols));
    if (!sheet) return;
    ex_contact_sheet((const unsigned char *const *)u->sheet_cells, u->sheet_count, u->sheet_cell_w, u->sheet_cell_h,
                     cols, sheet);
    snprintf(path, sizeof path, "%s/walkthrough_%s_sheet.png", u->o.out, wt_mode_name(u->o.mode));
    if (ex_write_png(path, cols * u->sheet_cell_w, rows * u->sheet_cell_h, sheet) != 0)
        fprintf(stderr, "walkthrough: cannot write %s\n", path);
    else if (u->o.verbose)
        printf("wrote %s/walkthrough_%s_NNN.png and the contact sheet %s\n", u->o.out, wt_mode_name(u->o.mode), path);
    free(sheet);
}

/* ---- the timing table ----------------------------------------------------- */

static void table_header(const run *u)
{
    int k;
    printf("\n%5s %6s %9s", "frame", "t", "total ms");
    for (k = 0; k < WT_PHASES && wt_phase_name(u->o.mode, k); k++) printf(" %9s", wt_phase_name(u->o.mode, k));
    if (u->o.mode == WT_MODE_RAYTRACE) printf(" %8s %7s %6s %6s", "samples", "gathers", "bunny", "hit %");
    if (u->o.mode == WT_MODE_BASEVIEWS) printf(" %8s", "traced");
    if (u->o.reference) printf(" %7s", "LRMS");
    if (u->o.converged) printf(" %7s", "conv");
    printf("\n");
}

static void table_row(const run *u, int f, const wt_frame_stats *s)
{
    int k;
    printf("%5d %6.3f %9.2f", f, wt_frame_time(&u->o, f), 1e3 * s->total);
    for (k = 0; k < WT_PHASES && wt_phase_name(u->o.mode, k); k++) printf(" %9.2f", 1e3 * s->phase[k]);
    if (u->o.mode == WT_MODE_RAYTRACE)
        printf(" %8u %7u %6u %6.1f", s->samples, s->gathers, s->bunny_gathers,
               s->lookups ? 100.0 * s->hits / s->lookups : 100.0);
    if (u->o.mode == WT_MODE_BASEVIEWS) printf(" %8u", s->samples);
    if (u->o.reference) printf(" %7.4f", s->lrms);
    if (u->o.converged && s->converged >= 0.0) printf(" %7.4f", s->converged);
    else if (u->o.converged) printf(" %7s", "-");
    printf("%s\n", s->full ? "   (traced in full)" : "");
}

/* Totals over the frames after the first in mode raytrace (the first one
   is traced in full), over all frames otherwise: Greger's figure 5.8 shows
   the total time, each phase's share of it and the frame rate. */
static void table_summary(const run *u)
{
    const wt_options *o = &u->o;
    int first = o->mode == WT_MODE_RAYTRACE && o->frames > 1 ? 1 : 0, f, k, n = o->frames - first;
    double total = 0.0, phase[WT_PHASES] = { 0 }, samples = 0.0, lrms = 0.0, converged = 0.0;
    int measured = 0;
    for (f = first; f < o->frames; f++) {
        if (u->stats[f].converged >= 0.0) { converged += u->stats[f].converged; measured++; }
        total += u->stats[f].total;
        samples += u->stats[f].samples;
        lrms += u->stats[f].lrms;
        for (k = 0; k < WT_PHASES; k++) phase[k] += u->stats[f].phase[k];
    }
    printf("\n%s, %dx%d, %d threads: frames %d-%d (cf. Greger fig. 5.8)\n", wt_mode_name(o->mode), o->width, o->height,
           ex_pool_threads(u->w->pool), first, o->frames - 1);
    printf("  %12s", "total (s)");
    for (k = 0; k < WT_PHASES && wt_phase_name(o->mode, k); k++) printf(" %9s %%", wt_phase_name(o->mode, k));
    printf(" %8s\n", "fps");
    printf("  %12.3f", total);
    for (k = 0; k < WT_PHASES && wt_phase_name(o->mode, k); k++) printf(" %11.1f", total > 0 ? 100.0 * phase[k] / total : 0.0);
    printf(" %8.1f\n", total > 0 ? n / total : 0.0);
    if (o->mode == WT_MODE_RADIOSITY && ex_pool_threads(u->w->pool) > 1)
        printf("  (raster, shade and volume are CPU time summed over the threads: their shares of the wall time\n"
               "  add up to more than 100%% when the threads ran them side by side)\n");
    if (o->mode == WT_MODE_RAYTRACE && total > 0)
        printf("  displayed %.1f frames/s, sampled %.0f samples/s (%.1f%% of the pixels per frame); "
               "the first frame (all %d pixels) took %.2f s\n", n / total, samples / total,
               100.0 * samples / n / ((double)o->width * o->height), o->width * o->height, u->stats[0].total);
    printf("  Greger 1996 (fig. 5.8): 5.3 fps with a 1162-polygon rabbit; Hardt 1996: 2.3 updates/s at 640x480\n");
    if (o->reference) printf("  mean LRMS against full renders: %.4f\n", lrms / n);
    if (measured) printf("  mean LRMS against converged renders (their noise taken out), %d frames: %.4f\n", measured,
                         converged / measured);
}

/* ---- a user's scene ------------------------------------------------------- */

/* Takes the scene options out of argv (they are not the walkthrough's own);
   returns -1 on a bad value, else whether --scene was given. */
static int take_scene_options(int *argc, char **argv, ex_scene_options *so, char *err, size_t err_size)
{
    int i, kept = 1, r;
    ex_scene_options_default(so, NULL);
    for (i = 1; i < *argc; i++) {
        int first = i;
        if (!strcmp(argv[i], "--scene") && i + 1 < *argc && wt_builtin_scene_file(argv[i + 1])) {   /* the walkthrough's own */
            argv[kept++] = argv[i++];
            argv[kept++] = argv[i];
            continue;
        }
        if ((r = ex_scene_option(*argc, argv, &i, so, err, err_size)) < 0) return -1;
        if (r == 0) argv[kept++] = argv[first];
    }
    *argc = kept;
    argv[kept] = NULL;
    return so->path != NULL;
}

static int copy_file(const char *from, const char *to)
{
    FILE *in = fopen(from, "rb"), *out = in ? fopen(to, "wb") : NULL;
    char buf[65536];
    size_t n;
    int ok = in && out;
    while (ok && (n = fread(buf, 1, sizeof buf, in)) > 0) ok = fwrite(buf, 1, n, out) == n;
    if (in) {
        ok = ok && !ferror(in);
        fclose(in);
    }
    if (out && fclose(out) != 0) ok = 0;
    return ok ? 0 : -1;
}

/* Is the user's scene an OBJ with a make_building.py layout beside it (the
   same name, .layout), loaded as it is (no --up, --scale or
   --drop-coincident)? The walkthrough then reads it in place, layout and
   sky map included, and walks the route planned from the layout. */
static int building_in_place(const ex_scene_options *so)
{
    char layout[1024];
    size_t n = strlen(so->path);
    if (n < 5 || n > 1000 || strcmp(so->path + n - 4, ".obj") != 0) return 0;
    if ((so->up && so->up != 'y') || (so->scale != 0.0f && so->scale != 1.0f) || so->drop_coincident) return 0;
    snprintf(layout, sizeof layout, "%.*s.layout", (int)(n - 4), so->path);
    return access(layout, R_OK) == 0;
}

/* Loads the user's scene and writes it, with the bunny, as the walkthrough's
   data directory <cache>/scene_<hash of the file and the options>. */
static int prepare_scene(const ex_scene_options *so, wt_options *o, char *dir, size_t dir_size, char *err, size_t err_size)
{
    obj_scene s;
    char path[1280], bunny[1280];
    uint64_t h = 1469598103934665603ull;
    const char *c;
    for (c = so->path; *c; c++) h = (h ^ (unsigned char)*c) * 1099511628211ull;
    h = (h ^ (unsigned char)so->up) * 1099511628211ull;
    h = (h ^ (uint64_t)(so->scale * 1e6f)) * 1099511628211ull;
    h = (h ^ (uint64_t)so->drop_coincident) * 1099511628211ull;
    snprintf(dir, dir_size, "%s/scene_%016llx", o->cache_dir, (unsigned long long)h);
    if (wt_make_dirs(dir) != 0) {
        snprintf(err, err_size, "cannot create %.900s: %s", dir, strerror(errno));
        return -1;
    }
    if (ex_scene_load(so, &s, err, err_size) != 0) return -1;
    if (o->verbose)
        printf("walkthrough: %s: %u triangles, %u faces, %u materials; %u pairs of coincident faces\n", so->path, s.tri_count,
               s.face_count, s.material_count, s.coincident_pairs);
    snprintf(path, sizeof path, "%s/office.obj", dir);
    snprintf(bunny, sizeof bunny, "%s/bunny.obj", o->data_dir);
    if (obj_write(&s, path, err, err_size) != 0) { obj_free(&s); return -1; }
    obj_free(&s);
    snprintf(path, sizeof path, "%s/bunny.obj", dir);
    if (copy_file(bunny, path) != 0) {
        snprintf(err, err_size, "cannot copy %.500s to %.500s", bunny, path);
        return -1;
    }
    o->data_dir = dir;
    o->scene = "office";   /* dir/office.obj, walked along the office's paths */
    return 0;
}

int main(int argc, char **argv)
{
    run u;
    char err[1024], scene_dir[1024];
    int f, i, parsed, user_scene;
    ex_scene_options so;
    double t0;
    memset(&u, 0, sizeof u);
    wt_options_default(&u.o);
    user_scene = take_scene_options(&argc, argv, &so, err, sizeof err);
    if (user_scene < 0) {
        fprintf(stderr, "walkthrough: %s (see --help)\n", err);
        return 2;
    }
    parsed = wt_parse_options(argc, argv, &u.o, err, sizeof err);
    if (parsed <= 0) {
        if (parsed < 0) fprintf(stderr, "walkthrough: %s\n", err);
        else fputs(ex_scene_options_help(), stdout);
        return parsed < 0 ? 2 : 0;
    }
    if (user_scene && building_in_place(&so)) u.o.scene = so.path;
    else if (user_scene && prepare_scene(&so, &u.o, scene_dir, sizeof scene_dir, err, sizeof err) != 0) {
        fprintf(stderr, "walkthrough: %s\n", err);
        return 1;
    }
    wt_install_interrupt_handler();
    if (u.o.write_frames && wt_make_dirs(u.o.out) != 0) {
        fprintf(stderr, "walkthrough: cannot create %s: %s\n", u.o.out, strerror(errno));
        return 1;
    }
    if (wt_world_create(&u.o, &u.w, err, sizeof err) != 0) {
        fprintf(stderr, "walkthrough: %s\n", err);
        return 1;
    }
    if (u.o.verbose) {
        char route[96] = "";
        if (u.o.frames <= 0) {   /* the count the world chose from the route */
            wt_route rt = wt_route_measure(&u.w->opt);
            snprintf(route, sizeof route, " (the route: %.1f m, %.0f degrees)", rt.length, rt.turn);
        }
        printf("walkthrough: mode %s, %d frames%s of %dx%d, %d threads; %s %u triangles, bunny %u triangles\n",
               wt_mode_name(u.o.mode), u.w->opt.frames, route, u.o.width, u.o.height, ex_pool_threads(u.w->pool),
               u.w->office_path, u.w->office.tri_count, u.w->bunny.tri_count);
    }
    u.o.frames = u.w->opt.frames;
    fflush(stdout);
    t0 = wt_seconds();
    if (wt_renderer_create(u.w, &u.r, err, sizeof err) != 0) {
        fprintf(stderr, "walkthrough: %s\n", err);
        wt_world_destroy(u.w);
        return 1;
    }
    if (u.o.verbose) printf("precompute: %.1f s\n", wt_seconds() - t0);
    u.rgb = (float *)malloc(sizeof(float) * 3 * (size_t)u.o.width * (size_t)u.o.height);
    u.full = u.o.reference ? (float *)malloc(sizeof(float) * 3 * (size_t)u.o.width * (size_t)u.o.height) : NULL;
    u.rgb8 = (unsigned char *)malloc(3 * (size_t)u.o.width * (size_t)u.o.height);
    u.stats = (wt_frame_stats *)calloc((size_t)u.o.frames, sizeof *u.stats);
    for (i = 1; u.o.width / i > 320; i++) {}
    u.sheet_cell_w = u.o.width / i;
    u.sheet_cell_h = u.o.height / i;
    for (f = 0; f < SHEET_FRAMES; f++) u.sheet_cells[f] = (unsigned char *)malloc(3 * (size_t)u.sheet_cell_w * (size_t)u.sheet_cell_h);
    if (!u.rgb || !u.rgb8 || !u.stats || (u.o.reference && !u.full)) {
        fprintf(stderr, "walkthrough: out of memory\n");
        return 1;
    }
    table_header(&u);
    for (f = 0; f < u.o.frames; f++) {
        wt_frame_stats *s = &u.stats[f];
        if (wt_render_frame(u.r, f, u.rgb, s) != 0) {
            fprintf(stderr, "walkthrough: frame %d failed (out of memory)\n", f);
            return 1;
        }
        u.exposure = wt_exposure(&u.o, u.rgb, u.exposure_first);
        if (f == 0) u.exposure_first = u.exposure;
        if (u.o.reference || u.o.converged) {   /* the frame measured against other renders of its camera */
            const double t = wt_frame_time(&u.o, f);
            rendercache_camera c = wt_camera(&u.w->opt, t, (uint32_t)u.o.width, (uint32_t)u.o.height);
            if (u.o.reference && (wt_render_full(u.w, &c, t, (uint32_t)f, u.full, NULL) != 0 ||
                                  wt_display_lrms(u.full, u.rgb, u.o.width, u.o.height, u.exposure, &s->lrms) != 0))
                s->lrms = -1.0;
            if (u.o.converged && f % u.o.converged == u.o.converged - 1 &&
                wt_converged_lrms(u.w, &c, t, u.rgb, u.exposure, &s->converged) != 0)
                s->converged = -1.0;
        }
        table_row(&u, f, s);
        if (write_frame(&u, f) != 0) return 1;
    }
    table_summary(&u);
    write_sheet(&u);
    for (f = 0; f < SHEET_FRAMES; f++) free(u.sheet_cells[f]);
    free(u.rgb);
    free(u.full);
    free(u.rgb8);
    free(u.stats);
    wt_renderer_destroy(u.r);
    wt_world_destroy(u.w);
    return 0;
}
