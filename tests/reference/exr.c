/* exr.c - RGB float EXR images through the OpenEXR 3 C API (see ref.h).
   Compiled as C11: OpenEXR's coding structs use anonymous unions. */
#include "tests/reference/ref.h"

#include <openexr.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Channel name -> offset in an interleaved RGB pixel, or -1. */
static int exr_channel_offset(const char *name)
{
    if (strcmp(name, "R") == 0) return 0;
    if (strcmp(name, "G") == 0) return 1;
    if (strcmp(name, "B") == 0) return 2;
    return -1;
}

static int exr_write_chunks(exr_context_t ctx, int part, int width, int height, const float *rgb)
{
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int32_t lines = 1;
    int y, first = 1, ok = 1;
    if (exr_get_scanlines_per_chunk(ctx, part, &lines) != EXR_ERR_SUCCESS || lines < 1) return -1;
    for (y = 0; ok && y < height; y += lines) {
        exr_chunk_info_t ci;
        int c;
        ok = exr_write_scanline_chunk_info(ctx, part, y, &ci) == EXR_ERR_SUCCESS;
        if (ok) ok = (first ? exr_encoding_initialize(ctx, part, &ci, &enc)
                            : exr_encoding_update(ctx, part, &ci, &enc)) == EXR_ERR_SUCCESS;
        for (c = 0; ok && c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int k = exr_channel_offset(ch->channel_name);
            if (k < 0) { ok = 0; break; }
            ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
            ch->user_line_stride = 3 * (int32_t)sizeof(float) * width;
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->encode_from_ptr = (const uint8_t *)(rgb + 3 * (size_t)ci.start_y * (size_t)width + k);
        }
        if (ok && first) ok = exr_encoding_choose_default_routines(ctx, part, &enc) == EXR_ERR_SUCCESS;
        if (ok) ok = exr_encoding_run(ctx, part, &enc) == EXR_ERR_SUCCESS;
        first = 0;
    }
    if (!first) exr_encoding_destroy(ctx, &enc);
    return ok ? 0 : -1;
}

int ref_exr_write(const char *path, int width, int height, const float *rgb)
{
    exr_context_t ctx;
    int part, ok;
    if (!path || !rgb || width <= 0 || height <= 0) return -1;
    if (exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, NULL) != EXR_ERR_SUCCESS) return -1;
    ok = exr_add_part(ctx, "rgb", EXR_STORAGE_SCANLINE, &part) == EXR_ERR_SUCCESS &&
         exr_initialize_required_attr_simple(ctx, part, width, height, EXR_COMPRESSION_ZIP) == EXR_ERR_SUCCESS &&
         exr_add_channel(ctx, part, "R", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1) == EXR_ERR_SUCCESS &&
         exr_add_channel(ctx, part, "G", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1) == EXR_ERR_SUCCESS &&
         exr_add_channel(ctx, part, "B", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1) == EXR_ERR_SUCCESS &&
         exr_set_version(ctx, part, 1) == EXR_ERR_SUCCESS &&
         exr_write_header(ctx) == EXR_ERR_SUCCESS &&
         exr_write_chunks(ctx, part, width, height, rgb) == 0;
    ok = exr_finish(&ctx) == EXR_ERR_SUCCESS && ok;
    return ok ? 0 : -1;
}

static int exr_read_chunks(exr_context_t ctx, int part, const exr_attr_box2i_t *dw, float *rgb)
{
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int width = dw->max.x - dw->min.x + 1, height = dw->max.y - dw->min.y + 1;
    int32_t lines = 1;
    int y, first = 1, ok = 1;
    if (exr_get_scanlines_per_chunk(ctx, part, &lines) != EXR_ERR_SUCCESS || lines < 1) return -1;
    for (y = dw->min.y; ok && y <= dw->max.y; y += lines) {
        exr_chunk_info_t ci;
        int c;
        ok = exr_read_scanline_chunk_info(ctx, part, y, &ci) == EXR_ERR_SUCCESS;
        if (ok) ok = (first ? exr_decoding_initialize(ctx, part, &ci, &dec)
                            : exr_decoding_update(ctx, part, &ci, &dec)) == EXR_ERR_SUCCESS;
        for (c = 0; ok && c < dec.channel_count; c++) {
            exr_coding_channel_info_t *ch = &dec.channels[c];
            int k = exr_channel_offset(ch->channel_name);
            if (k < 0 || ch->x_samples != 1 || ch->y_samples != 1) { ch->decode_to_ptr = NULL; continue; }
            ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
            ch->user_line_stride = 3 * (int32_t)sizeof(float) * width;
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->decode_to_ptr = (uint8_t *)(rgb + 3 * (size_t)(ci.start_y - dw->min.y) * (size_t)width + k);
        }
        if (ok && first) ok = exr_decoding_choose_default_routines(ctx, part, &dec) == EXR_ERR_SUCCESS;
        if (ok) ok = exr_decoding_run(ctx, part, &dec) == EXR_ERR_SUCCESS;
        first = 0;
    }
    if (!first) exr_decoding_destroy(ctx, &dec);
    (void)height;
    return ok ? 0 : -1;
}

float *ref_exr_read(const char *path, int *width, int *height)
{
    exr_context_t ctx;
    exr_attr_box2i_t dw;
    exr_storage_t storage;
    float *rgb = NULL;
    int w, h, ok;
    if (!path || !width || !height) return NULL;
    if (exr_start_read(&ctx, path, NULL) != EXR_ERR_SUCCESS) return NULL;
    ok = exr_get_storage(ctx, 0, &storage) == EXR_ERR_SUCCESS && storage == EXR_STORAGE_SCANLINE &&
         exr_get_data_window(ctx, 0, &dw) == EXR_ERR_SUCCESS;
    if (ok) {
        w = dw.max.x - dw.min.x + 1;
        h = dw.max.y - dw.min.y + 1;
        ok = w > 0 && h > 0 && w <= (1 << 15) && h <= (1 << 15);
    }
    if (ok) {
        rgb = (float *)calloc(3 * (size_t)w * (size_t)h, sizeof(float));
        ok = rgb && exr_read_chunks(ctx, 0, &dw, rgb) == 0;
    }
    exr_finish(&ctx);
    if (!ok) { free(rgb); return NULL; }
    *width = w;
    *height = h;
    return rgb;
}
