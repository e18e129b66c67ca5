/* Buildings made in code for the radinterp tests and benchmark: floors of
   office rooms (4 x 4 x 2.8 m inside, z up) behind 15 cm walls with both
   faces, 20 cm floor slabs, doors between neighbouring rooms (every wall
   along x has one, every other wall along y), a desk on four legs, a
   cabinet and a ceiling lamp (a thin box whose underside emits) in the
   rooms that are lit, and the building's outer faces. The doors' jambs,
   lintels and thresholds close the openings, so the walls and slabs are
   solid; where a door's edge ends on a floor or a wall there is a T-junction,
   as in an exported level. Quadrilaterals are written as two triangles when
   asked (triangle soup, as an engine exports it). About 94 triangles a room.

   rb_building(&b, nx, ny, floors, flags) builds it; rb_desc(&b) gives the
   radinterp_desc of the scene. */
#ifndef TEST_RADINTERP_SCENES_H
#define TEST_RADINTERP_SCENES_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define RB_TRIANGLES 1u   /* every quadrilateral as two triangles */
#define RB_NO_DOORS 2u    /* solid walls between the rooms */
#define RB_ALL_LIT 4u     /* a lamp in every room (else one room in five is dark) */

#define RB_ROOM_W 4.0f    /* inside, along x and y */
#define RB_ROOM_H 2.8f
#define RB_WALL 0.15f
#define RB_SLAB 0.2f
#define RB_DOOR_W 1.0f
#define RB_DOOR_H 2.1f
#define RB_LAMP_E 40.0f   /* emitted radiosity of a lamp's underside, W/m^2 */

enum { RB_WALLS, RB_FLOOR, RB_CEILING, RB_DESK, RB_CABINET, RB_LAMP_FRAME, RB_LAMP, RB_OUTSIDE, RB_MATERIALS };

typedef struct rb_scene {
    float *pos;
    uint32_t *patch, *mat;   /* 4 indices per patch (4th RADINTERP_NO_VERTEX for a triangle) */
    uint32_t nv, np, cap_v, cap_p;
    radinterp_material m[RB_MATERIALS];
    uint32_t flags;
    uint32_t nx, ny, floors;
} rb_scene;

static void rb__grow(rb_scene *b, uint32_t nv, uint32_t np)
{
    if (b->nv + nv > b->cap_v) {
        b->cap_v = 2 * (b->nv + nv);
        b->pos = (float *)realloc(b->pos, sizeof(float) * 3 * b->cap_v);
    }
    if (b->np + np > b->cap_p) {
        b->cap_p = 2 * (b->np + np);
        b->patch = (uint32_t *)realloc(b->patch, sizeof(uint32_t) * 4 * b->cap_p);
        b->mat = (uint32_t *)realloc(b->mat, sizeof(uint32_t) * b->cap_p);
    }
}

static uint32_t rb__vertex(rb_scene *b, const float *p)
{
    memcpy(b->pos + 3 * b->nv, p, 3 * sizeof(float));
    return b->nv++;
}

/* The quadrilateral p0 p1 p2 p3, counter-clockwise seen from its front:
   one patch, or the triangles (p0 p1 p2) and (p0 p2 p3). */
static void rb_quad(rb_scene *b, const float *p0, const float *p1, const float *p2, const float *p3, uint32_t mat)
{
    uint32_t v[4], i;
    rb__grow(b, 4, 2);
    v[0] = rb__vertex(b, p0); v[1] = rb__vertex(b, p1); v[2] = rb__vertex(b, p2); v[3] = rb__vertex(b, p3);
    if (b->flags & RB_TRIANGLES) {
        for (i = 0; i < 2; i++) {
            uint32_t *q = b->patch + 4 * b->np;
            q[0] = v[0]; q[1] = v[1 + i]; q[2] = v[2 + i]; q[3] = RADINTERP_NO_VERTEX;
            b->mat[b->np++] = mat;
        }
        return;
    }
    memcpy(b->patch + 4 * b->np, v, sizeof v);
    b->mat[b->np++] = mat;
}

/* The face of the box [lo, hi] on side `axis` (0 x, 1 y, 2 z) at its low
   (hi_side 0) or high end, facing outward (or inward with inward set). */
static void rb_box_face(rb_scene *b, const float *lo, const float *hi, int axis, int hi_side, int inward, uint32_t mat)
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3, k;
    float c[4][3];
    for (k = 0; k < 4; k++) {
        c[k][axis] = hi_side ? hi[axis] : lo[axis];
        c[k][u] = (k == 1 || k == 2) ? hi[u] : lo[u];
        c[k][v] = (k >= 2) ? hi[v] : lo[v];
    }
    /* (c0 c1 c2 c3) winds counter-clockwise about +axis */
    if (hi_side != inward) rb_quad(b, c[0], c[1], c[2], c[3], mat);
    else rb_quad(b, c[0], c[3], c[2], c[1], mat);
}

/* An outward box; faces: bit 2 axis + side (bit 4 = the bottom, z low). */
static void rb_box(rb_scene *b, const float *lo, const float *hi, unsigned faces, uint32_t mat)
{
    int f;
    for (f = 0; f < 6; f++)
        if (faces & (1u << f)) rb_box_face(b, lo, hi, f / 2, f % 2, 0, mat);
}
#define RB_ALL_FACES 0x3Fu
#define RB_NO_BOTTOM (RB_ALL_FACES & ~0x10u)

/* One inner face of a room's wall: the plane axis = at (facing the room:
   +axis when facing_hi is 0), spanning [a0, a1] along the other horizontal
   axis and [z0, z0 + H] up, with a door [dc - DOOR_W / 2, dc + DOOR_W / 2] x
   [z0, z0 + DOOR_H] when door is set. */
static void rb_wall_face(rb_scene *b, int axis, float at, float a0, float a1, float z0, int facing_hi, int door,
                         float dc)
{
    int other = 1 - axis;
    float lo[3], hi[3];
    float cut[3][4];   /* pieces: along-lo, along-hi, z-lo, z-hi */
    int n = 0, i;
    if (!door) {
        cut[0][0] = a0; cut[0][1] = a1; cut[0][2] = z0; cut[0][3] = z0 + RB_ROOM_H; n = 1;
    } else {
        cut[0][0] = a0; cut[0][1] = dc - 0.5f * RB_DOOR_W; cut[0][2] = z0; cut[0][3] = z0 + RB_ROOM_H;
        cut[1][0] = dc + 0.5f * RB_DOOR_W; cut[1][1] = a1; cut[1][2] = z0; cut[1][3] = z0 + RB_ROOM_H;
        cut[2][0] = dc - 0.5f * RB_DOOR_W; cut[2][1] = dc + 0.5f * RB_DOOR_W; cut[2][2] = z0 + RB_DOOR_H;
        cut[2][3] = z0 + RB_ROOM_H;
        n = 3;
    }
    for (i = 0; i < n; i++) {
        lo[axis] = hi[axis] = at;
        lo[other] = cut[i][0]; hi[other] = cut[i][1];
        lo[2] = cut[i][2]; hi[2] = cut[i][3];
        /* a face of the zero-thickness box on its high side faces +axis */
        rb_box_face(b, lo, hi, axis, 1, facing_hi, RB_WALLS);
    }
}

/* The opening of a door through a wall slab [s0, s1] along axis, centred
   at dc on the other axis, from the floor z0: jambs, lintel, threshold. */
static void rb_door_reveal(rb_scene *b, int axis, float s0, float s1, float dc, float z0)
{
    int other = 1 - axis;
    float lo[3], hi[3];
    lo[axis] = s0; hi[axis] = s1;
    lo[other] = dc - 0.5f * RB_DOOR_W; hi[other] = dc + 0.5f * RB_DOOR_W;
    lo[2] = z0; hi[2] = z0 + RB_DOOR_H;
    rb_box_face(b, lo, hi, other, 0, 1, RB_WALLS);   /* jamb facing +other, into the opening */
    rb_box_face(b, lo, hi, other, 1, 1, RB_WALLS);
    rb_box_face(b, lo, hi, 2, 1, 1, RB_WALLS);       /* lintel facing down */
    rb_box_face(b, lo, hi, 2, 0, 1, RB_FLOOR);       /* threshold facing up */
}

static int rb_door_y(uint32_t ix, uint32_t iy) { (void)iy; return ix % 2 == 0; }
static int rb_lit(const rb_scene *b, uint32_t ix, uint32_t iy, uint32_t f)
{
    return (b->flags & RB_ALL_LIT) || (ix + 2 * iy + 3 * f) % 5 != 4;
}

static void rb_room(rb_scene *b, uint32_t ix, uint32_t iy, uint32_t f)
{
    const float P = RB_ROOM_W + RB_WALL;
    float x0 = ix * P + RB_WALL, y0 = iy * P + RB_WALL, z0 = f * (RB_ROOM_H + RB_SLAB) + RB_SLAB;
    float x1 = x0 + RB_ROOM_W, y1 = y0 + RB_ROOM_W, z1 = z0 + RB_ROOM_H, lo[3], hi[3];
    int doors = !(b->flags & RB_NO_DOORS);
    float sx = 0.3f * (float)((ix * 7 + iy * 3 + f) % 3);   /* the desk moves from room to room */
    lo[0] = x0; lo[1] = y0; lo[2] = z0; hi[0] = x1; hi[1] = y1; hi[2] = z1;
    rb_box_face(b, lo, hi, 2, 0, 1, RB_FLOOR);
    rb_box_face(b, lo, hi, 2, 1, 1, RB_CEILING);
    rb_wall_face(b, 0, x0, y0, y1, z0, 0, doors && ix > 0, 0.5f * (y0 + y1));
    rb_wall_face(b, 0, x1, y0, y1, z0, 1, doors && ix + 1 < b->nx, 0.5f * (y0 + y1));
    rb_wall_face(b, 1, y0, x0, x1, z0, 0, doors && iy > 0 && rb_door_y(ix, iy - 1), 0.5f * (x0 + x1));
    rb_wall_face(b, 1, y1, x0, x1, z0, 1, doors && iy + 1 < b->ny && rb_door_y(ix, iy), 0.5f * (x0 + x1));
    if (doors && ix + 1 < b->nx) rb_door_reveal(b, 0, x1, x1 + RB_WALL, 0.5f * (y0 + y1), z0);
    if (doors && iy + 1 < b->ny && rb_door_y(ix, iy)) rb_door_reveal(b, 1, y1, y1 + RB_WALL, 0.5f * (x0 + x1), z0);
    {   /* desk: top slab on four legs */
        float dx = x0 + 0.6f + sx, dy = y0 + 0.6f;
        int l;
        lo[0] = dx; lo[1] = dy; lo[2] = z0 + 0.72f; hi[0] = dx + 1.4f; hi[1] = dy + 0.7f; hi[2] = z0 + 0.75f;
        rb_box(b, lo, hi, RB_ALL_FACES, RB_DESK);
        for (l = 0; l < 4; l++) {
            float lx = l & 1 ? dx + 1.3f : dx + 0.05f, ly = l & 2 ? dy + 0.6f : dy + 0.05f;
            lo[0] = lx; lo[1] = ly; lo[2] = z0; hi[0] = lx + 0.05f; hi[1] = ly + 0.05f; hi[2] = z0 + 0.72f;
            rb_box(b, lo, hi, RB_ALL_FACES & ~0x30u, RB_DESK);   /* four sides */
        }
    }
    lo[0] = x1 - 0.7f; lo[1] = y1 - 1.2f; lo[2] = z0; hi[0] = x1 - 0.2f; hi[1] = y1 - 0.4f; hi[2] = z0 + 1.8f;
    rb_box(b, lo, hi, RB_NO_BOTTOM, RB_CABINET);
    if (rb_lit(b, ix, iy, f)) {   /* lamp: a thin box under the ceiling, its underside emits */
        float cx = 0.5f * (x0 + x1), cy = 0.5f * (y0 + y1);
        lo[0] = cx - 0.3f; lo[1] = cy - 0.3f; lo[2] = z1 - 0.04f; hi[0] = cx + 0.3f; hi[1] = cy + 0.3f; hi[2] = z1;
        rb_box(b, lo, hi, RB_ALL_FACES & ~0x30u, RB_LAMP_FRAME);
        rb_box_face(b, lo, hi, 2, 0, 0, RB_LAMP);
    }
}

static void rb_material(rb_scene *b, int i, float r, float g, float bl, float e)
{
    b->m[i].reflectance[0] = r; b->m[i].reflectance[1] = g; b->m[i].reflectance[2] = bl;
    b->m[i].emission[0] = b->m[i].emission[1] = b->m[i].emission[2] = e;
}

/* A building of nx x ny rooms on each of `floors` floors. */
static void rb_building(rb_scene *b, uint32_t nx, uint32_t ny, uint32_t floors, uint32_t flags)
{
    const float P = RB_ROOM_W + RB_WALL;
    float lo[3], hi[3];
    uint32_t ix, iy, f;
    memset(b, 0, sizeof *b);
    b->flags = flags;
    b->nx = nx; b->ny = ny; b->floors = floors;
    rb_material(b, RB_WALLS, 0.7f, 0.7f, 0.68f, 0.0f);
    rb_material(b, RB_FLOOR, 0.45f, 0.4f, 0.35f, 0.0f);
    rb_material(b, RB_CEILING, 0.8f, 0.8f, 0.8f, 0.0f);
    rb_material(b, RB_DESK, 0.6f, 0.45f, 0.3f, 0.0f);
    rb_material(b, RB_CABINET, 0.35f, 0.4f, 0.5f, 0.0f);
    rb_material(b, RB_LAMP_FRAME, 0.8f, 0.8f, 0.8f, 0.0f);
    rb_material(b, RB_LAMP, 0.8f, 0.8f, 0.8f, RB_LAMP_E);
    rb_material(b, RB_OUTSIDE, 0.5f, 0.5f, 0.5f, 0.0f);
    for (f = 0; f < floors; f++)
        for (iy = 0; iy < ny; iy++)
            for (ix = 0; ix < nx; ix++) rb_room(b, ix, iy, f);
    lo[0] = lo[1] = lo[2] = 0.0f;
    hi[0] = nx * P + RB_WALL; hi[1] = ny * P + RB_WALL; hi[2] = floors * (RB_ROOM_H + RB_SLAB) + RB_SLAB;
    rb_box(b, lo, hi, RB_ALL_FACES, RB_OUTSIDE);
}

static radinterp_desc rb_desc(const rb_scene *b)
{
    radinterp_desc d;
    memset(&d, 0, sizeof d);
    d.positions = b->pos;
    d.vertex_count = b->nv;
    d.patches = b->patch;
    d.patch_count = b->np;
    d.patch_materials = b->mat;
    d.materials = b->m;
    d.material_count = RB_MATERIALS;
    return d;
}

static void rb_free(rb_scene *b)
{
    free(b->pos);
    free(b->patch);
    free(b->mat);
    memset(b, 0, sizeof *b);
}

#endif
