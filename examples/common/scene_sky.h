/* scene_sky.h - what a ray that leaves an examples' scene sees: an
   environment radiance, either constant (an overcast sky) or a small HDR
   environment map given as an array.

       static const float rgb[] = { ... };               // width x height texels
       ex_sky sky = { { 0, 0, 0 }, rgb, 32, 16 };        // or { { L, L, L }, NULL, 0, 0 }
       if (!ex_sky_valid(&sky)) ...;
       ex_sky_radiance(&sky, dir, out);                  // W/(m^2 sr) along dir

   Units: radiance in W/(m^2 sr), linear RGB. The scenes are y-up: a
   surface facing up under a constant sky of radiance L receives E = pi L.

   The map is equirectangular (latitude-longitude) with +y up: row r covers
   the polar angle theta in [pi r / height, pi (r + 1) / height) from +y (row
   0 at the zenith, the last row at the nadir), column c the azimuth
   phi = atan2(z, x) in [2 pi c / width - pi, 2 pi (c + 1) / width - pi).
   Lookups take the texel a direction falls in (no filtering), so a map is
   exactly a piecewise constant radiance: tests integrate it in closed form
   (ex_sky_irradiance_up). The caller owns the array; it must outlive every
   user of the sky. */
#ifndef EXAMPLES_COMMON_SCENE_SKY_H
#define EXAMPLES_COMMON_SCENE_SKY_H

#include <math.h>
#include <stddef.h>

#include "base.h"

#define EX_SKY_MAX_SIZE 65536   /* texels per side */

typedef struct ex_sky {
    float radiance[3];     /* the constant sky, used when map is NULL */
    const float *map;      /* rgb per texel, rows from the zenith down; NULL = constant */
    int width, height;
} ex_sky;

/* Finite, non-negative radiance, and a map of sensible size. */
EX_FN int ex_sky_valid(const ex_sky *s)
{
    size_t i, n;
    int k;
    if (!s) return 0;
    for (k = 0; k < 3; k++)
        if (!(s->radiance[k] >= 0.0f && s->radiance[k] <= 3.4e38f)) return 0;
    if (!s->map) return 1;
    if (s->width < 1 || s->height < 1 || s->width > EX_SKY_MAX_SIZE || s->height > EX_SKY_MAX_SIZE) return 0;
    n = 3 * (size_t)s->width * (size_t)s->height;
    for (i = 0; i < n; i++)
        if (!(s->map[i] >= 0.0f && s->map[i] <= 3.4e38f)) return 0;
    return 1;
}

/* The texel of direction d (any length but zero). */
EX_FN size_t ex_sky_texel(const ex_sky *s, const float d[3])
{
    const double pi = 3.14159265358979323846;
    double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
    double cos_theta = len > 0.0 ? d[1] / len : 1.0, theta, phi;
    int row, col;
    if (!(cos_theta >= -1.0)) cos_theta = -1.0;   /* NaN too */
    if (cos_theta > 1.0) cos_theta = 1.0;
    theta = acos(cos_theta);
    phi = atan2((double)d[2], (double)d[0]);
    if (!(phi >= -pi)) phi = -pi;
    row = (int)(theta / pi * s->height);
    col = (int)((phi + pi) / (2.0 * pi) * s->width);
    if (row >= s->height) row = s->height - 1;
    if (col >= s->width) col = s->width - 1;
    if (row < 0) row = 0;
    if (col < 0) col = 0;
    return (size_t)row * (size_t)s->width + (size_t)col;
}

/* Radiance arriving from direction d (pointing away from the receiver). */
EX_FN void ex_sky_radiance(const ex_sky *s, const float d[3], float rgb[3])
{
    const float *src = s->map ? s->map + 3 * ex_sky_texel(s, d) : s->radiance;
    rgb[0] = src[0];
    rgb[1] = src[1];
    rgb[2] = src[2];
}

/* Irradiance on an unoccluded surface facing +y, in closed form: a texel
   with polar angles [t0, t1] and azimuth width dphi sends
   L dphi (sin^2 t1 - sin^2 t0) / 2 (the integral of cos theta over it);
   rows below the horizon send nothing. */
EX_FN void ex_sky_irradiance_up(const ex_sky *s, double e[3])
{
    const double pi = 3.14159265358979323846;
    int r, c, k;
    e[0] = e[1] = e[2] = 0.0;
    if (!s->map) {
        for (k = 0; k < 3; k++) e[k] = pi * s->radiance[k];
        return;
    }
    for (r = 0; r < s->height; r++) {
        double t0 = pi * r / s->height, t1 = pi * (r + 1) / s->height, w;
        if (t0 >= 0.5 * pi) break;
        if (t1 > 0.5 * pi) t1 = 0.5 * pi;
        w = (2.0 * pi / s->width) * 0.5 * (sin(t1) * sin(t1) - sin(t0) * sin(t0));
        for (c = 0; c < s->width; c++)
            for (k = 0; k < 3; k++) e[k] += w * s->map[3 * ((size_t)r * (size_t)s->width + (size_t)c) + (size_t)k];
    }
}

#endif /* EXAMPLES_COMMON_SCENE_SKY_H */
