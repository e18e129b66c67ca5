/* glass_room.h - the closed room with a glass window of the headers' glass
   tests (tests/ref_irrvol_glass.c, ref_lightvec_glass.c, ref_radinterp_glass.c), as plain
   arrays: the room [-1,1] x [0,2] x [-1,1], every surface facing in, a
   window [-0.5,0.5]^2 in the ceiling (the rest of the ceiling in four
   quadrilaterals around it), and optionally a second pane 0.1 below the
   first (double glazing). Materials: GLASS_ROOM_FLOOR, GLASS_ROOM_WALL (the
   four walls and the ceiling), GLASS_ROOM_PANE (the first pane),
   GLASS_ROOM_INNER_PANE (the second). */
#ifndef TESTS_GLASS_ROOM_H
#define TESTS_GLASS_ROOM_H

#include <stdint.h>
#include <string.h>

enum { GLASS_ROOM_FLOOR, GLASS_ROOM_WALL, GLASS_ROOM_PANE, GLASS_ROOM_INNER_PANE, GLASS_ROOM_MATERIALS };

#define GLASS_ROOM_MAX_QUADS 12

typedef struct glass_room {
    float positions[4 * 3 * GLASS_ROOM_MAX_QUADS];
    uint32_t indices[6 * GLASS_ROOM_MAX_QUADS];
    uint32_t materials[2 * GLASS_ROOM_MAX_QUADS];   /* per triangle */
    uint32_t vertex_count, triangle_count;
} glass_room;

/* A quadrilateral of the corners a, b, c, d in cyclic order, wound so that
   its front faces along `facing`. */
static void glass_room_quad(glass_room *r, const float a[3], const float b[3], const float c[3], const float d[3],
                            const float facing[3], uint32_t material)
{
    const float *corner[4];
    float e1[3], e2[3], n[3];
    uint32_t v = r->vertex_count, t = r->triangle_count, i;
    int flip, k;
    corner[0] = a; corner[1] = b; corner[2] = c; corner[3] = d;
    for (k = 0; k < 3; k++) { e1[k] = b[k] - a[k]; e2[k] = c[k] - a[k]; }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    flip = n[0] * facing[0] + n[1] * facing[1] + n[2] * facing[2] < 0.0f;
    for (i = 0; i < 4; i++) memcpy(r->positions + 3 * (v + i), corner[flip ? 3 - i : i], 3 * sizeof(float));
    r->indices[3 * t] = v; r->indices[3 * t + 1] = v + 1; r->indices[3 * t + 2] = v + 2;
    r->indices[3 * t + 3] = v; r->indices[3 * t + 4] = v + 2; r->indices[3 * t + 5] = v + 3;
    r->materials[t] = r->materials[t + 1] = material;
    r->vertex_count += 4;
    r->triangle_count += 2;
}

/* A horizontal rectangle [x0,x1] x [z0,z1] at height y. */
static void glass_room_rect(glass_room *r, float x0, float x1, float z0, float z1, float y, float facing_y,
                            uint32_t material)
{
    float a[3], b[3], c[3], d[3], f[3] = { 0, 0, 0 };
    a[0] = x0; a[1] = y; a[2] = z0;
    b[0] = x1; b[1] = y; b[2] = z0;
    c[0] = x1; c[1] = y; c[2] = z1;
    d[0] = x0; d[1] = y; d[2] = z1;
    f[1] = facing_y;
    glass_room_quad(r, a, b, c, d, f, material);
}

/* The room; the panes face into the room (window_faces_up 0) or out of it. */
static void glass_room_make(glass_room *r, int window_faces_up, int double_glazing)
{
    static const float corner[8][3] = { { -1, 0, -1 }, { 1, 0, -1 }, { 1, 0, 1 }, { -1, 0, 1 },
                                        { -1, 2, -1 }, { 1, 2, -1 }, { 1, 2, 1 }, { -1, 2, 1 } };
    static const float px[3] = { 1, 0, 0 }, nx[3] = { -1, 0, 0 }, pz[3] = { 0, 0, 1 }, nz[3] = { 0, 0, -1 };
    float pane_facing = window_faces_up ? 1.0f : -1.0f;
    memset(r, 0, sizeof *r);
    glass_room_rect(r, -1, 1, -1, 1, 0, 1, GLASS_ROOM_FLOOR);
    glass_room_quad(r, corner[0], corner[3], corner[7], corner[4], px, GLASS_ROOM_WALL);   /* x = -1 */
    glass_room_quad(r, corner[1], corner[2], corner[6], corner[5], nx, GLASS_ROOM_WALL);   /* x = 1 */
    glass_room_quad(r, corner[0], corner[1], corner[5], corner[4], pz, GLASS_ROOM_WALL);   /* z = -1 */
    glass_room_quad(r, corner[3], corner[2], corner[6], corner[7], nz, GLASS_ROOM_WALL);   /* z = 1 */
    glass_room_rect(r, -1, 1, -1, -0.5f, 2, -1, GLASS_ROOM_WALL);
    glass_room_rect(r, -1, 1, 0.5f, 1, 2, -1, GLASS_ROOM_WALL);
    glass_room_rect(r, -1, -0.5f, -0.5f, 0.5f, 2, -1, GLASS_ROOM_WALL);
    glass_room_rect(r, 0.5f, 1, -0.5f, 0.5f, 2, -1, GLASS_ROOM_WALL);
    glass_room_rect(r, -0.5f, 0.5f, -0.5f, 0.5f, 2, pane_facing, GLASS_ROOM_PANE);
    if (double_glazing) glass_room_rect(r, -0.5f, 0.5f, -0.5f, 0.5f, 1.9f, pane_facing, GLASS_ROOM_INNER_PANE);
}

/* The environment map of the glass tests, 8 x 4 texels (rgb), a
   latitude-longitude map as examples/common/scene_sky.h reads it: a brighter
   zenith row, green rising with the column, and a blue column. */
static void glass_room_map(float map[8 * 4 * 3])
{
    int i;
    for (i = 0; i < 8 * 4; i++) {
        map[3 * i] = i / 8 == 0 ? 4.0f : 1.0f;
        map[3 * i + 1] = 1.0f + 0.25f * (float)(i % 8);
        map[3 * i + 2] = i % 8 == 5 ? 6.0f : 0.5f;
    }
}

#endif /* TESTS_GLASS_ROOM_H */
