/* image.h - image output with no external dependency: PNG (8-bit RGB, stored
   deflate blocks), binary PPM, and PFM (float RGB, for inspection in any HDR
   viewer), plus the tone mapping the examples use.

       unsigned char *rgb8 = malloc(3 * w * h);
       ex_tonemap(hdr, w, h, exposure, rgb8);   // linear float RGB -> sRGB bytes, clipped
       ex_tonemap_filmic(hdr, w, h, ex_exposure_key(hdr, w, h), rgb8);   // or exposed and filmic
       ex_write_png("frame.png", w, h, rgb8);
       ex_write_pfm("frame.pfm", w, h, hdr);   // ex_read_pfm reads it back (ex_load_pfm: any size)

   Rows are stored top to bottom everywhere (PFM's bottom-up order is handled
   on write). Every writer returns 0 on success and -1 when the file cannot be
   written. */
#ifndef EXAMPLES_COMMON_IMAGE_H
#define EXAMPLES_COMMON_IMAGE_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base.h"

/* ---- PNG ---------------------------------------------------------------- */

static uint32_t ex__crc32_update(uint32_t crc, const unsigned char *p, size_t n)
{
    static const uint32_t nibble[16] = { /* CRC-32 of 4-bit values, reflected */
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
        0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu };
    crc = ~crc;
    while (n--) {
        crc ^= *p++;
        crc = (crc >> 4) ^ nibble[crc & 15u];
        crc = (crc >> 4) ^ nibble[crc & 15u];
    }
    return ~crc;
}

static void ex__put_be32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

static int ex__png_chunk(FILE *f, const char *type, const unsigned char *data, size_t n)
{
    unsigned char head[8], tail[4];
    uint32_t crc;
    ex__put_be32(head, (uint32_t)n);
    memcpy(head + 4, type, 4);
    crc = ex__crc32_update(0, head + 4, 4);
    crc = ex__crc32_update(crc, data, n);
    ex__put_be32(tail, crc);
    return fwrite(head, 1, 8, f) == 8 && (n == 0 || fwrite(data, 1, n, f) == n) &&
           fwrite(tail, 1, 4, f) == 4 ? 0 : -1;
}

/* Writes 8-bit RGB rows top to bottom as a PNG with uncompressed deflate blocks. */
EX_FN int ex_write_png(const char *path, int w, int h, const unsigned char *rgb)
{
    static const unsigned char signature[8] = { 137, 80, 78, 71, 13, 10, 26, 10 };
    size_t row = 3 * (size_t)w + 1, raw_size, blocks, z_size, i, pos = 0;
    unsigned char ihdr[13], *z;
    uint32_t a = 1, b = 0; /* Adler-32 of the raw stream */
    FILE *f;
    int ok;
    if (w <= 0 || h <= 0 || !rgb || (size_t)h > ((size_t)1 << 30) / row) return -1;
    raw_size = row * (size_t)h;
    blocks = (raw_size + 65534) / 65535;
    z_size = 2 + raw_size + 5 * blocks + 4;
    z = (unsigned char *)malloc(z_size);
    if (!z) return -1;
    z[pos++] = 0x78; /* zlib header: deflate, 32K window, no preset dictionary */
    z[pos++] = 0x01;
    for (i = 0; i < raw_size;) {
        size_t n = raw_size - i < 65535 ? raw_size - i : 65535, k;
        z[pos++] = (unsigned char)(i + n == raw_size); /* BFINAL on the last stored block */
        z[pos++] = (unsigned char)n;
        z[pos++] = (unsigned char)(n >> 8);
        z[pos++] = (unsigned char)~n;
        z[pos++] = (unsigned char)(~n >> 8);
        for (k = 0; k < n; k++, i++) {
            size_t y = i / row, x = i % row;
            unsigned char byte = x == 0 ? 0 /* filter: none */ : rgb[y * 3 * (size_t)w + x - 1];
            z[pos++] = byte;
            a = (a + byte) % 65521u;
            b = (b + a) % 65521u;
        }
    }
    ex__put_be32(z + pos, (b << 16) | a);
    pos += 4;
    ex__put_be32(ihdr, (uint32_t)w);
    ex__put_be32(ihdr + 4, (uint32_t)h);
    ihdr[8] = 8;  /* bit depth */
    ihdr[9] = 2;  /* colour type: RGB */
    ihdr[10] = ihdr[11] = ihdr[12] = 0;
    f = fopen(path, "wb");
    if (!f) { free(z); return -1; }
    ok = fwrite(signature, 1, 8, f) == 8 && ex__png_chunk(f, "IHDR", ihdr, 13) == 0 &&
         ex__png_chunk(f, "IDAT", z, pos) == 0 && ex__png_chunk(f, "IEND", NULL, 0) == 0;
    ok = (fclose(f) == 0) && ok;
    free(z);
    return ok ? 0 : -1;
}

/* ---- PPM and PFM -------------------------------------------------------- */

EX_FN int ex_write_ppm(const char *path, int w, int h, const unsigned char *rgb)
{
    FILE *f;
    int ok;
    if (w <= 0 || h <= 0 || !rgb) return -1;
    f = fopen(path, "wb");
    if (!f) return -1;
    ok = fprintf(f, "P6\n%d %d\n255\n", w, h) > 0 &&
         fwrite(rgb, 3, (size_t)w * (size_t)h, f) == (size_t)w * (size_t)h;
    ok = (fclose(f) == 0) && ok;
    return ok ? 0 : -1;
}

/* Float RGB, little-endian (scale -1), rows written bottom-up as PFM requires. */
EX_FN int ex_write_pfm(const char *path, int w, int h, const float *rgb)
{
    FILE *f;
    int y, ok;
    if (w <= 0 || h <= 0 || !rgb) return -1;
    f = fopen(path, "wb");
    if (!f) return -1;
    ok = fprintf(f, "PF\n%d %d\n-1.0\n", w, h) > 0;
    for (y = h - 1; ok && y >= 0; y--) {
        int x, k;
        for (x = 0; ok && x < w; x++)
            for (k = 0; k < 3; k++) {
                float v = rgb[3 * ((size_t)y * (size_t)w + (size_t)x) + (size_t)k];
                uint32_t u;
                unsigned char b[4];
                memcpy(&u, &v, 4);
                b[0] = (unsigned char)u; b[1] = (unsigned char)(u >> 8);
                b[2] = (unsigned char)(u >> 16); b[3] = (unsigned char)(u >> 24);
                ok = ok && fwrite(b, 1, 4, f) == 4;
            }
    }
    ok = (fclose(f) == 0) && ok;
    return ok ? 0 : -1;
}

/* The pixels of an open PFM after its header: w x h RGB floats,
   little-endian, rows bottom to top in the file, top to bottom in rgb. */
static int ex__read_pfm_pixels(FILE *f, int w, int h, float *rgb)
{
    int y, ok = 1;
    for (y = h - 1; ok && y >= 0; y--) {
        int i;
        for (i = 0; ok && i < 3 * w; i++) {
            unsigned char b[4];
            uint32_t u;
            ok = fread(b, 1, 4, f) == 4;
            u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
            if (ok) memcpy(&rgb[3 * (size_t)y * (size_t)w + (size_t)i], &u, 4);
        }
    }
    return ok;
}

/* The header of a little-endian RGB PFM: its size. */
static int ex__read_pfm_header(FILE *f, int *w, int *h)
{
    char magic[3] = { 0 };
    float scale;
    return fscanf(f, "%2s %d %d %f", magic, w, h, &scale) == 4 && strcmp(magic, "PF") == 0 && *w > 0 && *h > 0 &&
           scale < 0.0f && fgetc(f) != EOF;   /* the one whitespace byte before the data */
}

/* Reads a little-endian PFM of exactly w x h pixels written by
   ex_write_pfm (the tests' stored reference frames) into rgb, rows top to
   bottom. Returns 0, or -1 when the file is missing, of another size or
   format, or short. */
EX_FN int ex_read_pfm(const char *path, int w, int h, float *rgb)
{
    FILE *f;
    int fw, fh, ok;
    if (w <= 0 || h <= 0 || !rgb) return -1;
    f = fopen(path, "rb");
    if (!f) return -1;
    ok = ex__read_pfm_header(f, &fw, &fh) && fw == w && fh == h && ex__read_pfm_pixels(f, w, h, rgb);
    fclose(f);
    return ok ? 0 : -1;
}

/* Reads a little-endian RGB PFM of any size up to max_texels pixels into
   a new array (*rgb, free() it; rows top to bottom). Returns 0, or -1 when
   the file is missing, too large, of another format, or short. */
EX_FN int ex_load_pfm(const char *path, size_t max_texels, int *w, int *h, float **rgb)
{
    FILE *f = fopen(path, "rb");
    int ok;
    *rgb = NULL;
    if (!f) return -1;
    ok = ex__read_pfm_header(f, w, h) && (size_t)*w <= max_texels / (size_t)*h;
    if (ok) *rgb = (float *)malloc(3 * sizeof(float) * (size_t)*w * (size_t)*h);
    ok = ok && *rgb && ex__read_pfm_pixels(f, *w, *h, *rgb);
    fclose(f);
    if (!ok) {
        free(*rgb);
        *rgb = NULL;
    }
    return ok ? 0 : -1;
}

/* ---- tone mapping ------------------------------------------------------- */

static unsigned char ex__srgb8(float linear)
{
    float s;
    if (!(linear > 0.0f)) return 0; /* also maps NaN to black */
    if (linear >= 1.0f) return 255;
    s = linear <= 0.0031308f ? 12.92f * linear : 1.055f * powf(linear, 1.0f / 2.4f) - 0.055f;
    return (unsigned char)(s * 255.0f + 0.5f);
}

/* Linear RGB times exposure, clamped, to sRGB bytes. */
EX_FN void ex_tonemap(const float *rgb, int w, int h, float exposure, unsigned char *out)
{
    size_t i, n = 3 * (size_t)w * (size_t)h;
    for (i = 0; i < n; i++) out[i] = ex__srgb8(rgb[i] * exposure);
}

/* ---- the filmic pipeline (the walkthrough and its viewer) -----------------
   Scene radiance reaches the screen in three steps, the same in the PNG
   frames and the interactive window:
     1. exposure: radiance times an exposure e, chosen so that the frame's
        log-average luminance (Reinhard et al. 2002, eq. 1: exp of the mean of
        log(delta + L) over the pixels) lands on middle grey, key 0.18;
     2. a filmic tone curve per channel, the ACES reference rendering fitted
        by Narkowicz (2015): f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14),
        clamped to [0, 1]: a toe that keeps shadows from going flat, a
        shoulder that rolls highlights off towards white instead of
        clipping them, so a lamp's hotspot on a wall keeps its gradient;
     3. the sRGB transfer function, to bytes.
   Middle grey 0.18 comes out as 0.27 (sRGB 140 of 255); an exposed radiance
   of 1 as 0.80, 4 as 0.98: the curve reaches white only towards 10. */
#define EX_FILMIC_KEY 0.18f

EX_FN float ex_filmic(float x)
{
    float y;
    if (!(x > 0.0f)) return 0.0f;   /* also NaN */
    y = x * (2.51f * x + 0.03f) / (x * (2.43f * x + 0.59f) + 0.14f);
    return y < 1.0f ? y : 1.0f;
}

/* Linear RGB times exposure, through the filmic curve, to sRGB bytes. */
EX_FN void ex_tonemap_filmic(const float *rgb, int w, int h, float exposure, unsigned char *out)
{
    size_t i, n = 3 * (size_t)w * (size_t)h;
    for (i = 0; i < n; i++) out[i] = ex__srgb8(ex_filmic(rgb[i] * exposure));
}

/* The exposure that brings the log-average luminance of the pixels to
   EX_FILMIC_KEY (black pixels count as delta = 1e-4 of the brightest);
   1 for an empty or black image. */
EX_FN float ex_exposure_key(const float *rgb, int w, int h)
{
    size_t n = (size_t)w * (size_t)h, i;
    double sum = 0.0, delta, peak = 0.0;
    if (!rgb || n == 0) return 1.0f;
    for (i = 0; i < n; i++) {
        double l = 0.2126 * rgb[3 * i] + 0.7152 * rgb[3 * i + 1] + 0.0722 * rgb[3 * i + 2];
        if (l > peak) peak = l;
    }
    if (!(peak > 0.0) || !isfinite(peak)) return 1.0f;
    delta = 1e-4 * peak;
    for (i = 0; i < n; i++) {
        double l = 0.2126 * rgb[3 * i] + 0.7152 * rgb[3 * i + 1] + 0.0722 * rgb[3 * i + 2];
        sum += log(delta + (l > 0.0 ? l : 0.0));
    }
    return (float)(EX_FILMIC_KEY / exp(sum / (double)n));
}

/* Exposure that maps the image's given luminance percentile (e.g. 0.95) to 1. */
EX_FN float ex_auto_exposure(const float *rgb, int w, int h, float percentile)
{
    size_t n = (size_t)w * (size_t)h, i, k;
    enum { BINS = 4096 };
    size_t hist[BINS];
    float lo = 1e-6f, hi = 1e6f, best;
    if (!rgb || n == 0) return 1.0f;
    memset(hist, 0, sizeof hist);
    for (i = 0; i < n; i++) {
        float l = 0.2126f * rgb[3 * i] + 0.7152f * rgb[3 * i + 1] + 0.0722f * rgb[3 * i + 2];
        int b = l > lo ? (int)(logf(l / lo) / logf(hi / lo) * (BINS - 1)) : 0;
        if (b < 0) b = 0;
        if (b >= BINS) b = BINS - 1;
        hist[b]++;
    }
    for (i = 0, k = 0; i < BINS; i++) {
        k += hist[i];
        if ((float)k >= percentile * (float)n) break;
    }
    best = lo * expf(logf(hi / lo) * (float)i / (BINS - 1));
    return best > 0.0f ? 1.0f / best : 1.0f;
}

/* Copies count 8-bit RGB images of w x h into a sheet of columns x rows
   cells (sheet: 3 * columns*w * rows*h bytes, cleared to dark grey first). */
EX_FN void ex_contact_sheet(const unsigned char *const *images, int count, int w, int h, int columns,
                            unsigned char *sheet)
{
    int rows = columns > 0 ? (count + columns - 1) / columns : 0, i, y;
    size_t sheet_w = (size_t)columns * (size_t)w;
    memset(sheet, 32, 3 * sheet_w * (size_t)rows * (size_t)h);
    for (i = 0; i < count; i++) {
        size_t x0 = (size_t)(i % columns) * (size_t)w, y0 = (size_t)(i / columns) * (size_t)h;
        for (y = 0; y < h; y++)
            memcpy(sheet + 3 * ((y0 + (size_t)y) * sheet_w + x0), images[i] + 3 * (size_t)y * (size_t)w,
                   3 * (size_t)w);
    }
}

#endif /* EXAMPLES_COMMON_IMAGE_H */
