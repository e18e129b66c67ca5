/* An OBJ scene (examples/common/obj.h, which ear-clips faces of more than
   four corners) as a radinterp scene: one patch a face (the 4th corner
   RADINTERP_NO_VERTEX for a triangle), Kd as reflectance and pi Ke as the
   emitted radiosity (Ke is emitted radiance). Fills the scene fields of *d
   (the rest zero) and allocates *patches and *mats, which the caller frees
   with free(). Returns 0, or -1 when out of memory. */
#ifndef TESTS_RADINTERP_OBJ_H
#define TESTS_RADINTERP_OBJ_H

#include <stdlib.h>
#include <string.h>

static int radinterp_obj_desc(const obj_scene *o, radinterp_desc *d, uint32_t **patches, radinterp_material **mats)
{
    uint32_t f, k;
    *patches = (uint32_t *)malloc(4 * sizeof(uint32_t) * (o->face_count ? o->face_count : 1));
    *mats = (radinterp_material *)calloc(o->material_count ? o->material_count : 1, sizeof(radinterp_material));
    if (!*patches || !*mats) {
        free(*patches);
        free(*mats);
        *patches = NULL;
        *mats = NULL;
        return -1;
    }
    for (f = 0; f < o->face_count; f++) {
        uint32_t n = o->face_start[f + 1] - o->face_start[f];
        for (k = 0; k < 4; k++)
            (*patches)[4 * f + k] = k < n && n <= 4 ? o->face_vertices[o->face_start[f] + k] : RADINTERP_NO_VERTEX;
    }
    for (f = 0; f < o->material_count; f++)
        for (k = 0; k < 3; k++) {
            (*mats)[f].reflectance[k] = o->materials[f].kd[k];
            (*mats)[f].emission[k] = 3.14159265358979323846f * o->materials[f].ke[k];
        }
    memset(d, 0, sizeof *d);
    d->positions = o->positions;
    d->vertex_count = o->vertex_count;
    d->patches = *patches;
    d->patch_count = o->face_count;
    d->patch_materials = o->face_material;
    d->materials = *mats;
    d->material_count = o->material_count;
    return 0;
}

#endif
