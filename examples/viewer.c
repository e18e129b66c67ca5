/* viewer.c - the walkthrough in a window: walk the house (or the office,
   or a larger building) with the mouse and WASD while the bunny walks its
   route, switch between the three rendering modes, and read what each
   frame cost. Needs SDL2
   (Debian: libsdl2-dev); `make view` installs it when it can, builds this
   and starts it. Every other example and header stays dependency-free.

       cc -O2 -I. examples/viewer.c -o viewer $(sdl2-config --cflags --libs) -lm -lpthread
       ./viewer                       # the house, mode radiosity (a minute's precompute, once)
       ./viewer --scene office
       ./viewer --mode raytrace --scene building --size 960x540
       ./viewer --mode raytrace --scene daylight   # by day (M skips mode radiosity)

   Keys: W A S D walk (Shift: faster), Q / E down / up, left mouse button
   held: look around, M next mode (radiosity, raytrace with the render
   cache, baseviews), P follow the bunny along its route (the offline
   frames' camera) or walk freely, Space pause the bunny, H the line of
   figures on or off, Esc quit. Mode baseviews reconstructs views near its
   base views only, so it always follows the route.

   The top line shows the mode, frames/s and the phases of the last frame
   in milliseconds (radiosity: raster, shade, volume, other; raytrace:
   cache, trace, lightvec, other; baseviews: blend, warp, other). Frames
   are tone-mapped exactly as the PNGs of examples/walkthrough.c
   (examples/common/image.h's filmic pipeline, the exposure of
   wt_exposure).

   Scripted runs (the tests): --play N renders frames 0 .. N-1 of the path,
   the offline renderer's cameras, then --screenshot FILE writes the
   window's pixels (read back from the window) as a PPM, and the viewer
   exits. Every walkthrough option is accepted (see walkthrough --help).
   Without a display the viewer says so and exits with status 1. */
#define _POSIX_C_SOURCE 200809L
#include <SDL.h>

#include "examples/common/walkthrough.h"

#define HUD_SCALE 1
#define HUD_HEIGHT (9 * HUD_SCALE + 2)   /* the band of the top line, rows */

static const char ex__font_chars[] = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ.,:/%-()=x";
static const unsigned char ex__font_rows[46][7] = {
    { 0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e }, /* 0 */
    { 0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e }, /* 1 */
    { 0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f }, /* 2 */
    { 0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e }, /* 3 */
    { 0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02 }, /* 4 */
    { 0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e }, /* 5 */
    { 0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e }, /* 6 */
    { 0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08 }, /* 7 */
    { 0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e }, /* 8 */
    { 0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c }, /* 9 */
    { 0x0e, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11 }, /* A */
    { 0x1e, 0x11, 0x11, 0x1e, 0x11, 0x11, 0x1e }, /* B */
    { 0x0e, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0e }, /* C */
    { 0x1e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1e }, /* D */
    { 0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x1f }, /* E */
    { 0x1f, 0x10, 0x10, 0x1e, 0x10, 0x10, 0x10 }, /* F */
    { 0x0e, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0f }, /* G */
    { 0x11, 0x11, 0x11, 0x1f, 0x11, 0x11, 0x11 }, /* H */
    { 0x0e, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0e }, /* I */
    { 0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0c }, /* J */
    { 0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11 }, /* K */
    { 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1f }, /* L */
    { 0x11, 0x1b, 0x15, 0x15, 0x11, 0x11, 0x11 }, /* M */
    { 0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11 }, /* N */
    { 0x0e, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e }, /* O */
    { 0x1e, 0x11, 0x11, 0x1e, 0x10, 0x10, 0x10 }, /* P */
    { 0x0e, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0d }, /* Q */
    { 0x1e, 0x11, 0x11, 0x1e, 0x14, 0x12, 0x11 }, /* R */
    { 0x0f, 0x10, 0x10, 0x0e, 0x01, 0x01, 0x1e }, /* S */
    { 0x1f, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04 }, /* T */
    { 0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0e }, /* U */
    { 0x11, 0x11, 0x11, 0x11, 0x11, 0x0a, 0x04 }, /* V */
    { 0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0a }, /* W */
    { 0x11, 0x11, 0x0a, 0x04, 0x0a, 0x11, 0x11 }, /* X */
    { 0x11, 0x11, 0x0a, 0x04, 0x04, 0x04, 0x04 }, /* Y */
    { 0x1f, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1f }, /* Z */
    { 0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c }, /* . */
    { 0x00, 0x00, 0x00, 0x00, 0x0c, 0x04, 0x08 }, /* , */
    { 0x00, 0x0c, 0x0c, 0x00, 0x0c, 0x0c, 0x00 }, /* : */
    { 0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00 }, /* / */
    { 0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03 }, /* % */
    { 0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00 }, /* - */
    { 0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02 }, /* ( */
    { 0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08 }, /* ) */
    { 0x00, 0x00, 0x1f, 0x00, 0x1f, 0x00, 0x00 }, /* = */
    { 0x00, 0x00, 0x11, 0x0a, 0x04, 0x0a, 0x11 }, /* x */
};

/* Draws text (upper-cased; characters without a glyph are spaces) at (x, y)
   in white on the band's dark background. */
static void hud_text(unsigned char *rgb, int w, int h, int x, int y, const char *text)
{
    for (; *text && x + 6 * HUD_SCALE <= w; text++, x += 6 * HUD_SCALE) {
        const char *c = strchr(ex__font_chars, *text >= 'a' && *text <= 'z' && *text != 'x' ? *text - 32 : *text);
        int row, col, sy, sx;
        if (!c || *text == 0 || *text == ' ') continue;
        for (row = 0; row < 7; row++)
            for (col = 0; col < 5; col++)
                if (ex__font_rows[c - ex__font_chars][row] >> (4 - col) & 1)
                    for (sy = 0; sy < HUD_SCALE; sy++)
                        for (sx = 0; sx < HUD_SCALE; sx++) {
                            int px = x + col * HUD_SCALE + sx, py = y + row * HUD_SCALE + sy;
                            if (px < w && py < h) memset(rgb + 3 * ((size_t)py * (size_t)w + (size_t)px), 255, 3);
                        }
    }
}

static void hud(unsigned char *rgb, int w, int h, const char *line)
{
    int y, band = HUD_HEIGHT < h ? HUD_HEIGHT : h;
    for (y = 0; y < band; y++) memset(rgb + 3 * (size_t)y * (size_t)w, 16, 3 * (size_t)w);
    hud_text(rgb, w, h, 2, 1, line);
}

typedef struct viewer {
    wt_options o;
    wt_world *w;
    wt_renderer *r;
    float *rgb, exposure_first;
    unsigned char *rgb8;
    /* the free camera */
    float eye[3], yaw, pitch;   /* yaw about +y from +z, pitch up */
    int follow, paused, show_hud;
    double bunny_t, fps;
    wt_frame_stats st;
} viewer;

static void viewer_close(viewer *v)
{
    wt_renderer_destroy(v->r);
    wt_world_destroy(v->w);
    v->r = NULL;
    v->w = NULL;
}

/* The world and the renderer of v->o.mode (precomputed data from the cache).
   Returns 0, -1, or WT_ERROR_UNSUPPORTED when the mode cannot render the
   scene (no mode refuses one today). */
static int viewer_open(viewer *v, char *err, size_t err_size)
{
    int result;
    viewer_close(v);
    if (wt_world_create(&v->o, &v->w, err, err_size) != 0) return -1;
    if ((result = wt_renderer_create(v->w, &v->r, err, err_size)) != 0) {
        wt_world_destroy(v->w);
        v->w = NULL;
        return result;
    }
    return 0;
}

/* The free camera starts where the route's camera is at time t. */
static void viewer_camera_from_path(viewer *v, double t)
{
    rendercache_camera c = wt_camera(&v->w->opt, t, (uint32_t)v->o.width, (uint32_t)v->o.height);
    float d[3] = { c.look_at[0] - c.eye[0], c.look_at[1] - c.eye[1], c.look_at[2] - c.eye[2] };
    memcpy(v->eye, c.eye, sizeof v->eye);
    v->yaw = atan2f(d[0], d[2]);
    v->pitch = atan2f(d[1], sqrtf(d[0] * d[0] + d[2] * d[2]));
}

static rendercache_camera viewer_free_camera(const viewer *v)
{
    rendercache_camera c;
    memset(&c, 0, sizeof c);
    c.kind = RENDERCACHE_CAMERA_PERSPECTIVE;
    memcpy(c.eye, v->eye, sizeof c.eye);
    c.look_at[0] = v->eye[0] + cosf(v->pitch) * sinf(v->yaw);
    c.look_at[1] = v->eye[1] + sinf(v->pitch);
    c.look_at[2] = v->eye[2] + cosf(v->pitch) * cosf(v->yaw);
    c.up[1] = 1.0f;
    c.vfov_degrees = WT_CAMERA_VFOV;
    c.width = (uint32_t)v->o.width;
    c.height = (uint32_t)v->o.height;
    return c;
}

/* Renders one frame: path frame `frame` when >= 0 (the offline camera),
   else the current view at the bunny's time. Tone-maps it into rgb8. */
static int viewer_render(viewer *v, int frame)
{
    int result;
    if (frame >= 0) {
        result = wt_render_frame(v->r, frame, v->rgb, &v->st);
    } else if (v->follow || v->o.mode == WT_MODE_BASEVIEWS) {
        int f = (int)(v->bunny_t * (v->w->opt.frames - 1) + 0.5);   /* the count the world resolved */
        if (v->o.mode == WT_MODE_BASEVIEWS) {
            result = wt_render_frame(v->r, f, v->rgb, &v->st);
        } else {
            rendercache_camera c = wt_camera(&v->w->opt, v->bunny_t, (uint32_t)v->o.width, (uint32_t)v->o.height);
            result = wt_render_view(v->r, &c, v->bunny_t, v->rgb, &v->st);
        }
    } else {
        rendercache_camera c = viewer_free_camera(v);
        result = wt_render_view(v->r, &c, v->bunny_t, v->rgb, &v->st);
    }
    if (result != 0) return -1;
    {
        float e = wt_exposure(&v->o, v->rgb, v->exposure_first);
        if (v->exposure_first <= 0.0f) v->exposure_first = e;
        ex_tonemap_filmic(v->rgb, v->o.width, v->o.height, e, v->rgb8);
    }
    if (v->show_hud) {
        char line[256];
        int k, n;
        n = snprintf(line, sizeof line, "%s %.1f fps  ms:", wt_mode_name(v->o.mode), v->fps);
        for (k = 0; k < WT_PHASES && wt_phase_name(v->o.mode, k) && n < (int)sizeof line - 32; k++)
            n += snprintf(line + n, sizeof line - (size_t)n, " %s %.1f", wt_phase_name(v->o.mode, k), 1e3 * v->st.phase[k]);
        snprintf(line + n, sizeof line - (size_t)n, "  %dx%d %d threads%s", v->o.width, v->o.height,
                 ex_pool_threads(v->w->pool), v->follow ? "  route" : "");
        hud(v->rgb8, v->o.width, v->o.height, line);
    }
    return 0;
}

/* Writes the window's pixels as a binary PPM. */
static int viewer_screenshot(SDL_Renderer *ren, int w, int h, const char *path)
{
    unsigned char *px = (unsigned char *)malloc(3 * (size_t)w * (size_t)h);
    int ok = px && SDL_RenderReadPixels(ren, NULL, SDL_PIXELFORMAT_RGB24, px, 3 * w) == 0 &&
             ex_write_ppm(path, w, h, px) == 0;
    free(px);
    return ok ? 0 : -1;
}

/* Walks the free camera: WASD in the view's plane, Q / E down and up. */
static void viewer_move(viewer *v, const Uint8 *keys, float seconds)
{
    float speed = (keys[SDL_SCANCODE_LSHIFT] || keys[SDL_SCANCODE_RSHIFT] ? 4.0f : 1.5f) * seconds;
    float f[2] = { sinf(v->yaw), cosf(v->yaw) }, r[2] = { -cosf(v->yaw), sinf(v->yaw) };
    float dx = 0.0f, dz = 0.0f;
    if (keys[SDL_SCANCODE_W]) { dx += f[0]; dz += f[1]; }
    if (keys[SDL_SCANCODE_S]) { dx -= f[0]; dz -= f[1]; }
    if (keys[SDL_SCANCODE_D]) { dx += r[0]; dz += r[1]; }
    if (keys[SDL_SCANCODE_A]) { dx -= r[0]; dz -= r[1]; }
    v->eye[0] += speed * dx;
    v->eye[2] += speed * dz;
    if (keys[SDL_SCANCODE_E]) v->eye[1] += speed;
    if (keys[SDL_SCANCODE_Q]) v->eye[1] -= speed;
}

/* Whether SDL found a display: without one it falls back to drivers that
   draw nowhere ("offscreen", "dummy"), which only SDL_VIDEODRIVER may ask for. */
static int viewer_has_display(void)
{
    const char *d = SDL_GetCurrentVideoDriver(), *asked = getenv("SDL_VIDEODRIVER");
    if (!d) return 0;
    if (asked && !strcmp(asked, d)) return 1;
    return strcmp(d, "offscreen") != 0 && strcmp(d, "dummy") != 0 && strcmp(d, "evdev") != 0;
}

/* Takes the viewer's own options out of argv; returns the new argc, or -1. */
static int viewer_options(int argc, char **argv, int *play, const char **screenshot, int *show_hud)
{
    int i, n = 1;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--play") && i + 1 < argc) {
            char *end;
            long p = strtol(argv[++i], &end, 10);
            if (*end || p < 1 || p > 100000) return -1;
            *play = (int)p;
        } else if (!strcmp(argv[i], "--screenshot") && i + 1 < argc) {
            *screenshot = argv[++i];
        } else if (!strcmp(argv[i], "--no-hud")) {
            *show_hud = 0;
        } else {
            argv[n++] = argv[i];
        }
    }
    return n;
}

int main(int argc, char **argv)
{
    viewer v;
    char err[1024];
    int play = 0, show_hud = 1, frame = 0, shown = 0, running = 1, looking = 0, status = 0, parsed;
    const char *screenshot = NULL;
    SDL_Window *win = NULL;
    SDL_Renderer *ren = NULL;
    SDL_Texture *tex = NULL;
    Uint64 last;
    memset(&v, 0, sizeof v);
    wt_options_default(&v.o);
    argc = viewer_options(argc, argv, &play, &screenshot, &show_hud);
    if (argc < 0) {
        fprintf(stderr, "viewer: --play takes a frame count from 1 to 100000\n");
        return 2;
    }
    parsed = wt_parse_options(argc, argv, &v.o, err, sizeof err);
    if (parsed <= 0) {
        if (parsed < 0) fprintf(stderr, "viewer: %s\n", err);
        else printf("\nviewer only: --play N (render path frames 0..N-1, then quit), --screenshot FILE (PPM of the "
                    "window after them), --no-hud\n");
        return parsed < 0 ? 2 : 0;
    }
    v.o.write_frames = 0;
    v.show_hud = show_hud;
    v.follow = play > 0;
    if (SDL_Init(SDL_INIT_VIDEO) != 0 || !viewer_has_display()) {
        fprintf(stderr, "viewer: no display to open a window on (%s)\n"
                "viewer: run it in a desktop session, or without one under xvfb-run (Debian: xvfb)\n",
                SDL_GetCurrentVideoDriver() ? SDL_GetCurrentVideoDriver() : SDL_GetError());
        SDL_Quit();
        return 1;
    }
    /* Frames are drawn in software: the window's surface is blitted as it is,
       without SDL opening OpenGL behind it to upload it (which loads the
       system's GL driver only to unload it again). */
    SDL_SetHint(SDL_HINT_FRAMEBUFFER_ACCELERATION, "0");
    win = SDL_CreateWindow("walkthrough", SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, v.o.width, v.o.height, 0);
    ren = win ? SDL_CreateRenderer(win, -1, SDL_RENDERER_SOFTWARE) : NULL;
    tex = ren ? SDL_CreateTexture(ren, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, v.o.width, v.o.height) : NULL;
    if (!tex) {
        fprintf(stderr, "viewer: cannot open a %dx%d window: %s\n", v.o.width, v.o.height, SDL_GetError());
        status = 1;
        goto done;
    }
    v.rgb = (float *)malloc(sizeof(float) * 3 * (size_t)v.o.width * (size_t)v.o.height);
    v.rgb8 = (unsigned char *)malloc(3 * (size_t)v.o.width * (size_t)v.o.height);
    if (!v.rgb || !v.rgb8) {
        fprintf(stderr, "viewer: out of memory\n");
        status = 1;
        goto done;
    }
    if (viewer_open(&v, err, sizeof err) != 0) {
        fprintf(stderr, "viewer: %s\n", err);
        status = 1;
        goto done;
    }
    viewer_camera_from_path(&v, 0.0);
    last = SDL_GetPerformanceCounter();
    while (running) {
        SDL_Event e;
        Uint64 now;
        float seconds;
        while (SDL_PollEvent(&e)) {
            if (e.type == SDL_QUIT) running = 0;
            else if (e.type == SDL_MOUSEBUTTONDOWN && e.button.button == SDL_BUTTON_LEFT) looking = 1;
            else if (e.type == SDL_MOUSEBUTTONUP && e.button.button == SDL_BUTTON_LEFT) looking = 0;
            else if (e.type == SDL_MOUSEMOTION && looking && !v.follow) {
                v.yaw -= 0.004f * (float)e.motion.xrel;
                v.pitch -= 0.004f * (float)e.motion.yrel;
                if (v.pitch > 1.5f) v.pitch = 1.5f;
                if (v.pitch < -1.5f) v.pitch = -1.5f;
            } else if (e.type == SDL_KEYDOWN && !e.key.repeat) {
                SDL_Keycode k = e.key.keysym.sym;
                if (k == SDLK_ESCAPE) running = 0;
                else if (k == SDLK_SPACE) v.paused = !v.paused;
                else if (k == SDLK_h) v.show_hud = !v.show_hud;
                else if (k == SDLK_p) {
                    v.follow = !v.follow;
                    if (!v.follow) viewer_camera_from_path(&v, v.bunny_t);
                } else if (k == SDLK_m) {
                    int opened;
                    do {   /* the next mode this scene has (radiosity has no glass or sky) */
                        v.o.mode = v.o.mode == WT_MODE_RADIOSITY ? WT_MODE_RAYTRACE
                                   : v.o.mode == WT_MODE_RAYTRACE ? WT_MODE_BASEVIEWS : WT_MODE_RADIOSITY;
                        printf("viewer: mode %s (precompute from %s)\n", wt_mode_name(v.o.mode), v.o.cache_dir);
                        fflush(stdout);
                        opened = viewer_open(&v, err, sizeof err);
                        if (opened == WT_ERROR_UNSUPPORTED) printf("viewer: %s; the next mode\n", err);
                    } while (opened == WT_ERROR_UNSUPPORTED);
                    if (opened != 0) {
                        fprintf(stderr, "viewer: %s\n", err);
                        status = 1;
                        goto done;
                    }
                    v.exposure_first = 0.0f;
                }
            }
        }
        now = SDL_GetPerformanceCounter();
        seconds = (float)((double)(now - last) / (double)SDL_GetPerformanceFrequency());
        last = now;
        if (seconds > 0.0f && shown > 0) v.fps = shown > 1 ? 0.9 * v.fps + 0.1 / seconds : 1.0 / seconds;
        if (!play) {
            float length = v.w->opt.path ? v.w->path.length : 5.0f;   /* the bunny walks at 0.8 m/s */
            if (!v.paused) v.bunny_t = fmod(v.bunny_t + 0.8 * seconds / length, 1.0);
            if (!v.follow) viewer_move(&v, SDL_GetKeyboardState(NULL), seconds);
        }
        if (viewer_render(&v, play ? frame : -1) != 0) {
            fprintf(stderr, "viewer: rendering failed (out of memory)\n");
            status = 1;
            break;
        }
        SDL_UpdateTexture(tex, NULL, v.rgb8, 3 * v.o.width);
        SDL_RenderClear(ren);
        SDL_RenderCopy(ren, tex, NULL, NULL);
        if (play && frame == play - 1 && screenshot && viewer_screenshot(ren, v.o.width, v.o.height, screenshot) != 0) {
            fprintf(stderr, "viewer: cannot write the screenshot %s\n", screenshot);
            status = 1;
        }
        SDL_RenderPresent(ren);
        shown++;
        if (play && ++frame >= play) running = 0;
    }
done:
    viewer_close(&v);
    free(v.rgb);
    free(v.rgb8);
    if (tex) SDL_DestroyTexture(tex);
    if (ren) SDL_DestroyRenderer(ren);
    if (win) SDL_DestroyWindow(win);
    SDL_Quit();
    return status;
}
