/* Fuzz target of rendercache_range_image_load (see tests/fuzz/fuzz.h): loads
   the bytes as a range image; an image that loads must have a camera that
   casts rays through its pixels and projects points along them, blend with
   itself and give its fitness (pixelwise, so every array is read whole under
   ASan), warp into other views (both fills, and averaged) giving finite
   colours, and save to bytes that load again and save to the same bytes. (Pixels
   without a surface load with the far depth whatever depth the file gave
   them, so the first save may differ from the input.) */
#define RENDERCACHE_IMPLEMENTATION
#include "rendercache.h"
#include "tests/fuzz/fuzz.h"

/* Rays are cast through at most this many pixels per input, spread evenly. */
#define MAX_RAYS 256u

static fuzz_outcome outcome_of(rendercache_result r)
{
    switch (r) {
    case RENDERCACHE_OK: return FUZZ_LOADED;
    case RENDERCACHE_ERROR_CORRUPT_DATA: return FUZZ_CORRUPT;
    case RENDERCACHE_ERROR_VERSION: return FUZZ_VERSION;
    default: return FUZZ_OTHER;
    }
}

static void cast_rays(const rendercache_range_image *img)
{
    const rendercache_camera *cam = &img->camera;
    size_t pixels = (size_t)cam->width * cam->height, step = pixels / MAX_RAYS + 1, p;
    for (p = 0; p < pixels; p += step) {
        float org[3], dir[3], point[3], px, py, depth;
        uint32_t x = (uint32_t)(p % cam->width), y = (uint32_t)(p / cam->width);
        int k;
        if (rendercache_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f, org, dir) != RENDERCACHE_OK) continue;
        if (img->object[p] >= RENDERCACHE_NO_SAMPLE) continue;
        for (k = 0; k < 3; k++) point[k] = org[k] + img->depth[p] * dir[k];
        rendercache_camera_project(cam, point, &px, &py, &depth);
    }
}

static void blend_and_fitness(const rendercache_range_image *img)
{
    rendercache_range_image *out = NULL;
    const uint32_t *ids[2];
    float fitness = -1.0f;
    if (rendercache_range_image_create(&img->camera, NULL, &out) != RENDERCACHE_OK) return;   /* out of memory */
    fuzz_require(rendercache_blend(img, img, 0.5f, out) == RENDERCACHE_OK, "a loaded image did not blend with itself");
    ids[0] = img->object;
    ids[1] = out->object;
    fuzz_require(rendercache_fitness(ids, 2, img->camera.width, img->camera.height, &fitness) == RENDERCACHE_OK &&
                     (fitness == 1.0f || fitness == 0.0f),
                 "an image blended with itself changed its ids");
    rendercache_range_image_destroy(out);
}

/* Warps the image into a small perspective view and a small sphere from its
   own eye, and into a view from a point a tenth of the way to what it looks
   at, with both fills (and once averaged): every warp succeeds and every
   output colour is finite (the inputs' are). */
static void warp_views(const rendercache_range_image *img)
{
    rendercache_camera cams[3];
    rendercache_warp_desc wd;
    const rendercache_range_image *in[1];
    int i, k;
    in[0] = img;
    for (i = 0; i < 3; i++) {
        cams[i] = img->camera;
        cams[i].kind = i == 1 ? RENDERCACHE_CAMERA_SPHERE : RENDERCACHE_CAMERA_PERSPECTIVE;
        cams[i].vfov_degrees = 60.0f;
        cams[i].width = i == 1 ? 8 : 12;
        cams[i].height = i == 1 ? 4 : 9;
    }
    for (k = 0; k < 3; k++)   /* the moved eye: 0.9 eye + 0.1 look_at (a warp may refuse it as a camera) */
        cams[2].eye[k] = 0.9f * img->camera.eye[k] + 0.1f * img->camera.look_at[k];
    memset(&wd, 0, sizeof wd);
    for (i = 0; i < 4; i++) {
        rendercache_warper *w = NULL;
        rendercache_range_image *out = NULL;
        const rendercache_camera *cam = &cams[i < 3 ? i : 0];
        size_t n, p;
        wd.average = i == 3;
        if (rendercache_warper_create(&wd, &w) != RENDERCACHE_OK) return;   /* out of memory */
        if (rendercache_range_image_create(cam, NULL, &out) == RENDERCACHE_OK) {
            rendercache_result r = rendercache_warp(w, in, 1, cam, RENDERCACHE_FILL_BOTH, out);
            fuzz_require(r == RENDERCACHE_OK || (i == 2 && r == RENDERCACHE_ERROR_INVALID_ARGUMENT),
                         "a loaded image did not warp");
            n = (size_t)cam->width * cam->height;
            for (p = 0; r == RENDERCACHE_OK && p < 3 * n; p++)
                fuzz_require(isfinite(out->rgb[p]), "a warp of finite colours gave a colour that is not finite");
            rendercache_range_image_destroy(out);
        }
        rendercache_warper_destroy(w);
    }
}

/* save, load, save: the two saves are the same bytes. */
static void check_save_is_stable(const rendercache_range_image *img)
{
    void *first = NULL, *second = NULL;
    size_t first_size = 0, second_size = 0;
    rendercache_range_image *back = NULL;
    fuzz_require(rendercache_range_image_save_to_memory(img, NULL, &first, &first_size) == RENDERCACHE_OK,
                 "a loaded image did not save");
    fuzz_require(rendercache_range_image_load_from_memory(first, first_size, NULL, &back) == RENDERCACHE_OK,
                 "a saved image did not load");
    fuzz_require(rendercache_range_image_save_to_memory(back, NULL, &second, &second_size) == RENDERCACHE_OK,
                 "a reloaded image did not save");
    fuzz_require(fuzz_same_bytes(first, first_size, second, second_size), "saving a reloaded image changed its bytes");
    rendercache_free_memory(NULL, first);
    rendercache_free_memory(NULL, second);
    rendercache_range_image_destroy(back);
}

static fuzz_outcome load_image(const uint8_t *data, size_t size)
{
    rendercache_range_image *img = NULL;
    rendercache_result r = rendercache_range_image_load_from_memory(data, size, NULL, &img);
    if (r != RENDERCACHE_OK) {
        fuzz_require(img == NULL, "a refused image was returned");
        return outcome_of(r);
    }
    cast_rays(img);
    blend_and_fitness(img);
    warp_views(img);
    check_save_is_stable(img);
    rendercache_range_image_destroy(img);
    return FUZZ_LOADED;
}

/* Whether loading the bytes and saving gives them back: true of every file
   rendercache_range_image_save wrote (it already writes the far depth where
   no surface is). */
static int resaves_same(const uint8_t *data, size_t size)
{
    rendercache_range_image *img = NULL;
    void *saved = NULL;
    size_t saved_size = 0;
    int same = rendercache_range_image_load_from_memory(data, size, NULL, &img) == RENDERCACHE_OK &&
               rendercache_range_image_save_to_memory(img, NULL, &saved, &saved_size) == RENDERCACHE_OK &&
               fuzz_same_bytes(saved, saved_size, data, size);
    rendercache_free_memory(NULL, saved);
    rendercache_range_image_destroy(img);
    return same;
}

const fuzz_target fuzz_this_target = { "rendercache", load_image, 1, resaves_same };
