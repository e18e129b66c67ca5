/* Tests of the interactive viewer (examples/viewer.c) under Xvfb: a
   scripted run renders the first frames of the walk (the offline
   renderer's cameras), writes a screenshot read back from its window and
   exits with status 0 and no leak (the viewer built with ASan+UBSan,
   build/tests/viewer_asan; tests/lsan_viewer.supp names the system
   libraries' own allocations); the screenshot matches the same frame
   rendered here and tone-mapped the same way (LRMS <= 0.02, the issue's
   tolerance, below the top line of figures, which the offline frame has
   not); without a display the viewer says so and exits with status 1.

   The viewer needs SDL2, the test Xvfb (tests/deps_viewer.sh installs both
   when it can): without them the test says it skipped and passes. */
#define _POSIX_C_SOURCE 200809L
#include <sys/wait.h>

#include "examples/common/walkthrough.h"
#include "tests/test.h"
#include "tests/walkthrough_test.h"

#define VIEWER "build/tests/viewer_asan"
#define HUD_ROWS 11            /* examples/viewer.c: HUD_HEIGHT */
#define SHOT_TOLERANCE 0.02    /* LRMS, the issue's */
#define W 160
#define H 120
#define PLAY 3

static char cache_dir[256];

static int have(const char *command)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd, "command -v %s >/dev/null 2>&1", command);
    return system(cmd) == 0;
}

static int can_run(void)
{
    if (access(VIEWER, X_OK) != 0) {
        test_note("skipped: %s is not built (SDL2 missing: apt-get install libsdl2-dev)", VIEWER);
        return 0;
    }
    if (!have("xvfb-run")) {
        test_note("skipped: xvfb-run is missing (apt-get install xvfb)");
        return 0;
    }
    return 1;
}

/* Runs a shell command; its output (stdout and stderr) into out; returns
   its exit status, or -1. */
static int run(const char *cmd, char *out, size_t size)
{
    FILE *p = popen(cmd, "r");
    size_t n = 0;
    int status;
    if (!p) return -1;
    while (n + 1 < size && fgets(out + n, (int)(size - n), p)) n += strlen(out + n);
    out[n] = 0;
    status = pclose(p);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

static int read_ppm(const char *path, int w, int h, unsigned char *rgb)
{
    FILE *f = fopen(path, "rb");
    int fw, fh, max, ok;
    if (!f) return -1;
    ok = fscanf(f, "P6 %d %d %d", &fw, &fh, &max) == 3 && fw == w && fh == h && max == 255 && fgetc(f) != EOF &&
         fread(rgb, 3, (size_t)w * h, f) == (size_t)w * h;
    fclose(f);
    return ok ? 0 : -1;
}

static float srgb_to_linear(unsigned char c)
{
    float s = (float)c / 255.0f;
    return s <= 0.04045f ? s / 12.92f : powf((s + 0.055f) / 1.055f, 2.4f);
}

/* The last of PLAY path frames rendered here and tone-mapped as the viewer
   does (the first frame's exposure as reference). */
static int offline_frame(const wt_options *o, unsigned char *rgb8)
{
    wt_world *w = NULL;
    wt_renderer *r = NULL;
    wt_frame_stats st;
    float *rgb = (float *)malloc(sizeof(float) * 3 * W * H), first = 0.0f, e = 1.0f;
    char err[512];
    int f, ok = rgb && wt_world_create(o, &w, err, sizeof err) == 0 && wt_renderer_create(w, &r, err, sizeof err) == 0;
    for (f = 0; f < PLAY && ok; f++) {
        ok = wt_render_frame(r, f, rgb, &st) == 0;
        e = wt_exposure(o, rgb, first);
        if (f == 0) first = e;
    }
    if (ok) ex_tonemap_filmic(rgb, W, H, e, rgb8);
    else fprintf(stderr, "  %s\n", err);
    wt_renderer_destroy(r);
    wt_world_destroy(w);
    free(rgb);
    return ok;
}

static void check_screenshot(const char *mode, const char *scene)
{
    char cmd[2048], out[8192], shot[512];
    unsigned char *a = (unsigned char *)malloc(3 * W * H), *b = (unsigned char *)malloc(3 * W * H);
    float *fa = (float *)malloc(sizeof(float) * 3 * W * H), *fb = (float *)malloc(sizeof(float) * 3 * W * H);
    wt_options o;
    double lrms = -1.0;
    int status, i;
    const char *settings = "--frames 24 --min-leaf-area 4 --volume-k 6 --strata 6 --light-samples 1 --threads 2";
    if (!CHECK(a && b && fa && fb)) goto done;
    snprintf(shot, sizeof shot, "%s/shot-%s.ppm", cache_dir, mode);
    snprintf(cmd, sizeof cmd, "LSAN_OPTIONS=suppressions=tests/lsan_viewer.supp xvfb-run -a %s --mode %s --scene %s "
             "--size %dx%d %s --play %d --screenshot %s --cache %s --quiet 2>&1", VIEWER, mode, scene, W, H, settings,
             PLAY, shot, cache_dir);
    status = run(cmd, out, sizeof out);
    CHECK_MSG(status == 0, "%s: the viewer exited with %d:\n%s", mode, status, out);
    wt_options_default(&o);
    o.mode = !strcmp(mode, "raytrace") ? WT_MODE_RAYTRACE : WT_MODE_RADIOSITY;
    o.scene = scene;
    o.width = W;
    o.height = H;
    o.frames = 24;
    o.min_leaf_area = 4.0f;
    o.volume_resolution = 6;
    o.strata = 6;
    o.light_samples = 1;
    o.threads = 2;
    o.cache_dir = cache_dir;
    o.progress = o.verbose = 0;
    if (CHECK(read_ppm(shot, W, H, a) == 0) && CHECK(offline_frame(&o, b))) {
        for (i = 0; i < 3 * W * H; i++) {
            fa[i] = srgb_to_linear(a[i]);
            fb[i] = srgb_to_linear(b[i]);
        }
        CHECK(rendercache_lrms(fb + 3 * W * HUD_ROWS, fa + 3 * W * HUD_ROWS, W, H - HUD_ROWS, &lrms) == RENDERCACHE_OK);
    }
    test_note("viewer, mode %s, %s: the window's frame %d against the offline frame: LRMS %.4f (tolerance %.2f)", mode,
              scene, PLAY - 1, lrms, SHOT_TOLERANCE);
    CHECK(lrms >= 0.0 && lrms <= SHOT_TOLERANCE);
done:
    free(a);
    free(b);
    free(fa);
    free(fb);
}

static void test_screenshot(void)
{
    if (!can_run()) return;
    check_screenshot("radiosity", "office");
    check_screenshot("raytrace", "building");
}

static void test_no_display(void)
{
    char out[4096];
    int status;
    if (access(VIEWER, X_OK) != 0) {
        test_note("skipped: %s is not built (SDL2 missing)", VIEWER);
        return;
    }
    status = run("env -u DISPLAY -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER LSAN_OPTIONS=suppressions=tests/lsan_viewer.supp "
                 VIEWER " --quiet 2>&1", out, sizeof out);
    CHECK_MSG(status == 1 && strstr(out, "no display") != NULL, "status %d, output:\n%s", status, out);
}

int main(int argc, char **argv)
{
    int result;
    TEST_INIT(argc, argv);
    if (!make_temp_dir(cache_dir, sizeof cache_dir)) {
        fprintf(stderr, "cannot create a temporary directory\n");
        return 1;
    }
    RUN(test_no_display);
    RUN(test_screenshot);
    result = test_finish();
    remove_dir(cache_dir);
    return result;
}
