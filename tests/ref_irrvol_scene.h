/* The office with a static bunny on its floor, as the irrvol reference tests
   and benchmark use it. Radiance field: every surface emits its material's
   Ke plus a constant reflected part 0.1 * Kd W/(m^2 sr) (a plausible indirect
   level for this room: the lamp's ~28 W spread over ~90 m^2 of surfaces);
   the bunny's material is grey, Kd 0.6. The lamp's three emitting groups are
   IMPORTANT. */
#ifndef TESTS_REF_IRRVOL_SCENE_H
#define TESTS_REF_IRRVOL_SCENE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "irrvol.h"
#include "examples/common/obj.h"

typedef struct office_scene {
    float *positions;          /* office vertices, then the bunny's */
    uint32_t vertex_count;
    uint32_t *indices;
    uint32_t *tri_material;    /* office materials, then one for the bunny */
    uint32_t tri_count, office_tris;
    irrvol_material *materials;
    uint32_t material_count;
    float *tri_radiance;       /* rgb per triangle: the same field for the reference */
    obj_scene office, bunny;
} office_scene;

/* Loads both OBJ files from dir (e.g. "examples/data"), puts the bunny,
   0.3 m tall, on the floor at (x, z). Returns 0 or -1 (message printed). */
static int office_scene_load(office_scene *s, const char *dir, float x, float z)
{
    char path[512], err[256];
    float lo[3], hi[3], scale;
    uint32_t i, m;
    memset(s, 0, sizeof *s);
    snprintf(path, sizeof path, "%s/office.obj", dir);
    if (obj_load(path, &s->office, err, sizeof err) != 0) { fprintf(stderr, "%s\n", err); return -1; }
    snprintf(path, sizeof path, "%s/bunny.obj", dir);
    if (obj_load(path, &s->bunny, err, sizeof err) != 0) { fprintf(stderr, "%s\n", err); obj_free(&s->office); return -1; }
    obj_bounds(&s->bunny, lo, hi);
    scale = 0.3f / (hi[1] - lo[1]);
    s->vertex_count = s->office.vertex_count + s->bunny.vertex_count;
    s->tri_count = s->office.tri_count + s->bunny.tri_count;
    s->office_tris = s->office.tri_count;
    s->material_count = s->office.material_count + 1;
    s->positions = (float *)malloc(3 * sizeof(float) * s->vertex_count);
    s->indices = (uint32_t *)malloc(3 * sizeof(uint32_t) * s->tri_count);
    s->tri_material = (uint32_t *)malloc(sizeof(uint32_t) * s->tri_count);
    s->materials = (irrvol_material *)calloc(s->material_count, sizeof(irrvol_material));
    s->tri_radiance = (float *)malloc(3 * sizeof(float) * s->tri_count);
    if (!s->positions || !s->indices || !s->tri_material || !s->materials || !s->tri_radiance) return -1;
    memcpy(s->positions, s->office.positions, 3 * sizeof(float) * s->office.vertex_count);
    for (i = 0; i < s->bunny.vertex_count; i++) {
        const float *p = s->bunny.positions + 3 * i;
        float *q = s->positions + 3 * (s->office.vertex_count + i);
        q[0] = x + scale * (p[0] - 0.5f * (lo[0] + hi[0]));
        q[1] = scale * (p[1] - lo[1]);
        q[2] = z + scale * (p[2] - 0.5f * (lo[2] + hi[2]));
    }
    memcpy(s->indices, s->office.tri_indices, 3 * sizeof(uint32_t) * s->office.tri_count);
    memcpy(s->tri_material, s->office.tri_material, sizeof(uint32_t) * s->office.tri_count);
    for (i = 0; i < s->bunny.tri_count; i++) {
        int k;
        for (k = 0; k < 3; k++)
            s->indices[3 * (s->office.tri_count + i) + (uint32_t)k] = s->bunny.tri_indices[3 * i + (uint32_t)k] + s->office.vertex_count;
        s->tri_material[s->office.tri_count + i] = s->material_count - 1;
    }
    for (m = 0; m < s->office.material_count; m++) {
        const obj_material *om = &s->office.materials[m];
        int k;
        for (k = 0; k < 3; k++) s->materials[m].radiance[k] = om->ke[k] + 0.1f * om->kd[k];
        if (om->ke[0] > 0.0f || om->ke[1] > 0.0f || om->ke[2] > 0.0f) s->materials[m].flags = IRRVOL_MATERIAL_IMPORTANT;
    }
    s->materials[m].radiance[0] = s->materials[m].radiance[1] = s->materials[m].radiance[2] = 0.06f;
    for (i = 0; i < s->tri_count; i++) memcpy(s->tri_radiance + 3 * i, s->materials[s->tri_material[i]].radiance, 12);
    return 0;
}

static void office_scene_free(office_scene *s)
{
    free(s->positions);
    free(s->indices);
    free(s->tri_material);
    free(s->materials);
    free(s->tri_radiance);
    obj_free(&s->office);
    obj_free(&s->bunny);
}

/* Greger's settings (5.1.1): 7^3 first level, 3^3 second level, k = 17. */
static void office_scene_desc(const office_scene *s, irrvol_desc *d)
{
    memset(d, 0, sizeof *d);
    d->positions = s->positions;
    d->vertex_count = s->vertex_count;
    d->indices = s->indices;
    d->triangle_count = s->tri_count;
    d->triangle_materials = s->tri_material;
    d->materials = s->materials;
    d->material_count = s->material_count;
    d->grid_samples[0] = d->grid_samples[1] = d->grid_samples[2] = 7;
    d->subgrid_samples = 3;
    d->resolution = 17;
}

#endif /* TESTS_REF_IRRVOL_SCENE_H */
