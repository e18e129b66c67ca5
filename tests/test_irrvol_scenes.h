/* Small scenes and brute-force integrals shared by the irrvol tests. */
#ifndef TESTS_IRRVOL_SCENES_H
#define TESTS_IRRVOL_SCENES_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "irrvol.h"

#if defined(__GNUC__) || defined(__clang__)
#  define SC_FN static __attribute__((unused))
#else
#  define SC_FN static
#endif

#define SC_PI 3.14159265358979323846
#define SC_MAX_QUADS 64

SC_FN void sc_set3(float *v, float x, float y, float z) { v[0] = x; v[1] = y; v[2] = z; }

/* Uniform in [0, 1) from a linear congruential stream. */
SC_FN float sc_frand(uint32_t *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (float)(*state >> 8) * (1.0f / 16777216.0f);
}

/* A direction uniform on the sphere. */
SC_FN void sc_random_dir(uint32_t *state, float d[3])
{
    float z = 2.0f * sc_frand(state) - 1.0f, phi = 2.0f * (float)SC_PI * sc_frand(state), s = sqrtf(1.0f - z * z);
    d[0] = s * cosf(phi); d[1] = s * sinf(phi); d[2] = z;
}

/* A triangle soup of quadrilaterals, each with its own four vertices. */
typedef struct sc_scene {
    float pos[4 * 3 * SC_MAX_QUADS];
    uint32_t idx[6 * SC_MAX_QUADS];
    uint32_t mat[2 * SC_MAX_QUADS];
    uint32_t nv, nt;
} sc_scene;

SC_FN void sc_quad(sc_scene *s, const float a[3], const float b[3], const float c[3], const float d[3], uint32_t mat)
{
    uint32_t v = s->nv;
    memcpy(s->pos + 3 * v, a, 12);
    memcpy(s->pos + 3 * v + 3, b, 12);
    memcpy(s->pos + 3 * v + 6, c, 12);
    memcpy(s->pos + 3 * v + 9, d, 12);
    s->idx[3 * s->nt + 0] = v; s->idx[3 * s->nt + 1] = v + 1; s->idx[3 * s->nt + 2] = v + 2;
    s->idx[3 * s->nt + 3] = v; s->idx[3 * s->nt + 4] = v + 2; s->idx[3 * s->nt + 5] = v + 3;
    s->mat[s->nt] = s->mat[s->nt + 1] = mat;
    s->nv += 4;
    s->nt += 2;
}

/* Axis-aligned square: the plane coordinate[axis] = at, the other two axes
   (axis+1, axis+2 mod 3) in [c1 - h, c1 + h] x [c2 - h, c2 + h]. Its front
   (counter-clockwise winding) faces +axis when facing > 0, else -axis. */
SC_FN void sc_square_facing(sc_scene *s, int axis, float at, float c1, float c2, float h, uint32_t mat, int facing)
{
    float q[4][3];
    int i, a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (i = 0; i < 4; i++) {
        q[i][axis] = at;
        q[i][a1] = c1 + ((i == 1 || i == 2) ? h : -h);
        q[i][a2] = c2 + ((i >= 2) ? h : -h);
    }
    if (facing > 0) sc_quad(s, q[0], q[1], q[2], q[3], mat);
    else sc_quad(s, q[3], q[2], q[1], q[0], mat);
}

/* A square facing +axis. */
SC_FN void sc_square(sc_scene *s, int axis, float at, float c1, float c2, float h, uint32_t mat)
{
    sc_square_facing(s, axis, at, c1, c2, h, mat, 1);
}

/* An axis-aligned box [lo, hi] as six quads with material mat, facing out
   (a solid) or in (a room). */
SC_FN void sc_box(sc_scene *s, const float lo[3], const float hi[3], uint32_t mat, int inward)
{
    float q[4][3];
    int axis, side, i;
    for (axis = 0; axis < 3; axis++)
        for (side = 0; side < 2; side++) {
            int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3, out = side ? 1 : -1;
            for (i = 0; i < 4; i++) {
                q[i][axis] = side ? hi[axis] : lo[axis];
                q[i][a1] = (i == 1 || i == 2) ? hi[a1] : lo[a1];
                q[i][a2] = i >= 2 ? hi[a2] : lo[a2];
            }
            /* q winds counter-clockwise seen from +axis */
            if ((out > 0) != (inward != 0)) sc_quad(s, q[0], q[1], q[2], q[3], mat);
            else sc_quad(s, q[3], q[2], q[1], q[0], mat);
        }
}

/* The cube [-1, 1]^3 as a room (faces wind toward the inside); face f
   (0..5 = -x, +x, -y, +y, -z, +z) has material f. */
SC_FN void sc_cube(sc_scene *s)
{
    int f;
    memset(s, 0, sizeof *s);
    for (f = 0; f < 6; f++)
        sc_square_facing(s, f / 2, (f & 1) ? 1.0f : -1.0f, 0.0f, 0.0f, 1.0f, (uint32_t)f, (f & 1) ? -1 : 1);
}

/* Irradiance at p for a surface with unit normal n from a square of
   (uniform or linear) radiance, by a g x g midpoint rule over the square:
   H = integral of L max(0, n . w) cos(theta_e) / r^2 dA. The radiance at a
   point is l0 + l1 * (coordinate along axis+1). */
SC_FN double sc_square_irradiance(const double p[3], const double n[3], int axis, double at, double c1, double c2,
                                   double h, double l0, double l1, int g)
{
    int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3, i, j;
    double sum = 0.0, da = (2.0 * h / g) * (2.0 * h / g);
    for (j = 0; j < g; j++)
        for (i = 0; i < g; i++) {
            double x[3], d[3], r2, r, cr, ce;
            int k;
            x[axis] = at;
            x[a1] = c1 - h + (i + 0.5) * 2.0 * h / g;
            x[a2] = c2 - h + (j + 0.5) * 2.0 * h / g;
            for (k = 0; k < 3; k++) d[k] = x[k] - p[k];
            r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            r = sqrt(r2);
            cr = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / r;
            if (cr <= 0.0) continue;
            ce = fabs(d[axis]) / r;
            sum += (l0 + l1 * x[a1]) * cr * ce / r2 * da;
        }
    return sum;
}

/* A desc of the scene's triangles alone (for a radiance callback);
   everything else default. */
SC_FN void sc_geometry_desc(irrvol_desc *d, const sc_scene *s)
{
    memset(d, 0, sizeof *d);
    d->positions = s->pos;
    d->vertex_count = s->nv;
    d->indices = s->idx;
    d->triangle_count = s->nt;
}

/* A desc of the scene's triangles and materials; everything else default. */
SC_FN void sc_scene_desc(irrvol_desc *d, const sc_scene *s, const irrvol_material *m, uint32_t nm)
{
    sc_geometry_desc(d, s);
    d->triangle_materials = s->mat;
    d->materials = m;
    d->material_count = nm;
}

#endif /* TESTS_IRRVOL_SCENES_H */
