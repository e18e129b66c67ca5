/* scene_load.h - the one call the examples use to load a scene file, and
   the command-line options that go with it (--scene, --up, --scale,
   --drop-coincident), shared by every program that shows a user's scene.

       ex_scene_options so;
       obj_scene s;
       char err[512];
       ex_scene_options_default(&so, "examples/data/office.obj");
       for (i = 1; i < argc; i++) {
           int r = ex_scene_option(argc, argv, &i, &so, err, sizeof err);
           if (r < 0) { fprintf(stderr, "%s\n", err); return 2; }
           if (r == 0) ... the program's own options ...
       }
       if (ex_scene_load(&so, &s, err, sizeof err) != 0) ...

   Formats: OBJ (+MTL) always, through obj.h; every format Assimp reads
   (glTF 2.0, FBX, Collada, IFC, PLY, 3DS, STL, ...) when the program is
   built with Assimp: the Makefile defines EX_HAVE_ASSIMP and links -lassimp
   when libassimp-dev is present (scene_assimp.h). `cc examples/x.c -lm`
   builds a program that reads OBJ and says how to get the rest.

   Axes and units: the examples' scenes are y-up, in metres. --up z says the
   file is z-up (it is turned: (x, y, z) -> (x, z, -y)); --up y that it is
   y-up; --scale S that one file unit is S metres. Without them OBJ files
   are taken as y-up metres and other formats as the file declares
   (scene_assimp.h). --drop-coincident removes faces that later coincident
   faces cover (obj_drop_coincident); the loader always counts them. */
#ifndef EXAMPLES_COMMON_SCENE_LOAD_H
#define EXAMPLES_COMMON_SCENE_LOAD_H

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "obj.h"
#ifdef EX_HAVE_ASSIMP
#include "scene_assimp.h"
#endif

#include "base.h"

typedef struct ex_scene_options {
    const char *path;          /* the scene file */
    char up;                   /* 'y' or 'z'; 0 = as the file says (OBJ: y) */
    float scale;               /* metres per file unit; 0 = as the file says (OBJ: 1) */
    int drop_coincident;       /* obj_drop_coincident after loading */
} ex_scene_options;

EX_FN void ex_scene_options_default(ex_scene_options *o, const char *path)
{
    memset(o, 0, sizeof *o);
    o->path = path;
}

/* What --help says about the scene options. */
EX_FN const char *ex_scene_options_help(void)
{
#ifdef EX_HAVE_ASSIMP
#define EX__SCENE_FORMATS "OBJ, or any format Assimp reads (glTF, FBX, Collada, IFC, PLY, ...)"
#else
#define EX__SCENE_FORMATS "OBJ (built without Assimp: rebuild with libassimp-dev for glTF, FBX, IFC, ...)"
#endif
    return "  --scene FILE         the scene: " EX__SCENE_FORMATS "\n"
           "  --up y|z             the file's up axis (default: as the file says; OBJ: y)\n"
           "  --scale S            metres per file unit (default: as the file says; OBJ: 1)\n"
           "  --drop-coincident    drop faces that later coincident faces cover\n";
#undef EX__SCENE_FORMATS
}

/* Reads argv[*i] when it is a scene option, with its value (advancing *i).
   Returns 1 when it was one, 0 when it is not a scene option, -1 on a
   missing or bad value (message in err). */
EX_FN int ex_scene_option(int argc, char **argv, int *i, ex_scene_options *o, char *err, size_t err_size)
{
    const char *a = argv[*i], *v = *i + 1 < argc ? argv[*i + 1] : NULL;
    if (!strcmp(a, "--drop-coincident")) { o->drop_coincident = 1; return 1; }
    if (strcmp(a, "--scene") != 0 && strcmp(a, "--up") != 0 && strcmp(a, "--scale") != 0) return 0;
    if (!v) {
        snprintf(err, err_size, "%s needs a value", a);
        return -1;
    }
    if (!strcmp(a, "--scene")) {
        o->path = v;
    } else if (!strcmp(a, "--up")) {
        if (strcmp(v, "y") != 0 && strcmp(v, "z") != 0) {
            snprintf(err, err_size, "--up must be y or z, not '%s'", v);
            return -1;
        }
        o->up = v[0];
    } else {
        char *end;
        double s;
        errno = 0;
        s = strtod(v, &end);
        if (errno || end == v || *end || !(s > 0.0 && s <= 1e9)) {
            snprintf(err, err_size, "--scale must be a number of metres per unit in (0, 1e9], not '%s'", v);
            return -1;
        }
        o->scale = (float)s;
    }
    (*i)++;
    return 1;
}

/* Whether path ends in ".obj", in any case. */
EX_FN int ex_scene_is_obj(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && path[n - 4] == '.' && tolower((unsigned char)path[n - 3]) == 'o' &&
           tolower((unsigned char)path[n - 2]) == 'b' && tolower((unsigned char)path[n - 1]) == 'j';
}

/* An OBJ file, turned to y-up metres as asked. */
static int ex__scene_load_obj(const ex_scene_options *o, obj_scene *out, char *err, size_t err_size)
{
    float m[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 }, s = o->scale > 0.0f ? o->scale : 1.0f;
    int k;
    if (obj_load(o->path, out, err, err_size) != 0) return -1;
    if (o->up != 'z' && s == 1.0f) return 0;
    if (o->up == 'z') { m[4] = 0; m[5] = 1; m[7] = -1; m[8] = 0; }
    for (k = 0; k < 9; k++) m[k] *= s;
    if (obj_transform(out, m) != 0) {
        obj_free(out);
        snprintf(err, err_size, "%s: out of memory", o->path);
        return -1;
    }
    return 0;
}

/* Loads o->path (see the doc block). Returns 0, or -1 with a message naming
   the file; out is then empty. */
EX_FN int ex_scene_load(const ex_scene_options *o, obj_scene *out, char *err, size_t err_size)
{
    int r;
    if (out) memset(out, 0, sizeof *out);
    if (!o || !o->path || !out) {
        snprintf(err, err_size, "ex_scene_load: no scene");
        return -1;
    }
    if (o->up != 0 && o->up != 'y' && o->up != 'z') {
        snprintf(err, err_size, "%s: the up axis must be y or z", o->path);
        return -1;
    }
    if (ex_scene_is_obj(o->path)) {
        r = ex__scene_load_obj(o, out, err, err_size);
    } else {
#ifdef EX_HAVE_ASSIMP
        r = ex_assimp_load(o->path, o->up, o->scale, out, err, err_size);
#else
        snprintf(err, err_size,
                 "%s: this program reads only OBJ; install libassimp-dev and rebuild it with make for glTF, FBX, "
                 "Collada, IFC, PLY and the other formats Assimp reads", o->path);
        r = -1;
#endif
    }
    if (r == 0 && o->drop_coincident && obj_drop_coincident(out) < 0) {
        obj_free(out);
        snprintf(err, err_size, "%s: out of memory", o->path);
        r = -1;
    }
    return r;
}

#endif /* EXAMPLES_COMMON_SCENE_LOAD_H */
