/* camera.h - look-at cameras for the examples: perspective (pinhole) and
   180-degree equidistant fish-eye. Image coordinates: x right, y down, pixel
   (x, y) covers [x, x+1) x [y, y+1), its centre is (x + 0.5, y + 0.5).

       ex_camera c = ex_camera_look_at(eye, target, up, 60.0f, 640, 480);
       ex_camera_ray(&c, x + 0.5f, y + 0.5f, dir);          // unit direction
       if (ex_camera_project(&c, p, &px, &py, &depth)) ...  // point -> pixel

   depth is the distance along the view axis (perspective) or the distance to
   the eye (fish-eye). */
#ifndef EXAMPLES_COMMON_CAMERA_H
#define EXAMPLES_COMMON_CAMERA_H

#include <math.h>

#include "base.h"

#define EX_PI 3.14159265358979323846

typedef enum ex_camera_kind {
    EX_CAMERA_PERSPECTIVE = 0,
    EX_CAMERA_FISHEYE = 1       /* equidistant: the inscribed circle spans 180 degrees */
} ex_camera_kind;

typedef struct ex_camera {
    float eye[3];
    float forward[3], right[3], up[3];  /* orthonormal; right = forward x up */
    float vfov;                         /* vertical field of view, radians (perspective) */
    float tan_half;                     /* tan(vfov / 2) */
    int width, height;
    ex_camera_kind kind;
} ex_camera;

static void ex__cross(const float a[3], const float b[3], float out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static int ex__normalize(float v[3])
{
    float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 0.0f)) return 0;
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
    return 1;
}

static float ex__dot(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* A perspective camera at eye looking at target. When up is parallel to the
   view direction another up is chosen. */
EX_FN ex_camera ex_camera_look_at(const float eye[3], const float target[3], const float up[3],
                                  float vfov_degrees, int width, int height)
{
    ex_camera c;
    float u[3];
    int k;
    for (k = 0; k < 3; k++) {
        c.eye[k] = eye[k];
        c.forward[k] = target[k] - eye[k];
        u[k] = up[k];
    }
    if (!ex__normalize(c.forward)) { c.forward[0] = c.forward[1] = 0; c.forward[2] = 1; }
    ex__cross(c.forward, u, c.right);
    if (!ex__normalize(c.right)) {
        float alt[3] = { 1, 0, 0 };
        if (fabsf(c.forward[0]) > 0.9f) { alt[0] = 0; alt[2] = 1; }
        ex__cross(c.forward, alt, c.right);
        ex__normalize(c.right);
    }
    ex__cross(c.right, c.forward, c.up);
    c.vfov = vfov_degrees * (float)(EX_PI / 180.0);
    c.tan_half = tanf(0.5f * c.vfov);
    c.width = width;
    c.height = height;
    c.kind = EX_CAMERA_PERSPECTIVE;
    return c;
}

EX_FN ex_camera ex_camera_fisheye(const float eye[3], const float target[3], const float up[3],
                                  int width, int height)
{
    ex_camera c = ex_camera_look_at(eye, target, up, 90.0f, width, height);
    c.kind = EX_CAMERA_FISHEYE;
    return c;
}

/* Unit direction through image point (px, py). Returns 0 (and a zero vector)
   for fish-eye points outside the 180-degree circle. */
EX_FN int ex_camera_ray(const ex_camera *c, float px, float py, float dir[3])
{
    int k;
    if (c->kind == EX_CAMERA_FISHEYE) {
        float radius = 0.5f * (float)(c->width < c->height ? c->width : c->height);
        float dx = (px - 0.5f * (float)c->width) / radius, dy = (py - 0.5f * (float)c->height) / radius;
        float r = sqrtf(dx * dx + dy * dy), theta = r * (float)(EX_PI / 2), s;
        if (r > 1.0f) { dir[0] = dir[1] = dir[2] = 0; return 0; }
        s = r > 0.0f ? sinf(theta) / r : 0.0f;
        for (k = 0; k < 3; k++) dir[k] = cosf(theta) * c->forward[k] + s * (dx * c->right[k] - dy * c->up[k]);
        return 1;
    } else {
        float aspect = (float)c->width / (float)c->height;
        float sx = (2.0f * px / (float)c->width - 1.0f) * c->tan_half * aspect;
        float sy = (1.0f - 2.0f * py / (float)c->height) * c->tan_half;
        for (k = 0; k < 3; k++) dir[k] = c->forward[k] + sx * c->right[k] + sy * c->up[k];
        ex__normalize(dir);
        return 1;
    }
}

/* Image point of p. Returns 0 when p is behind a perspective camera (or at
   the eye). The point may lie outside the image. */
EX_FN int ex_camera_project(const ex_camera *c, const float p[3], float *px, float *py, float *depth)
{
    float d[3], x, y, z;
    d[0] = p[0] - c->eye[0];
    d[1] = p[1] - c->eye[1];
    d[2] = p[2] - c->eye[2];
    x = ex__dot(d, c->right);
    y = ex__dot(d, c->up);
    z = ex__dot(d, c->forward);
    if (c->kind == EX_CAMERA_FISHEYE) {
        float len = sqrtf(x * x + y * y + z * z), lateral = sqrtf(x * x + y * y), theta, radius, r;
        if (!(len > 0.0f)) return 0;
        theta = atan2f(lateral, z);
        radius = 0.5f * (float)(c->width < c->height ? c->width : c->height);
        r = theta / (float)(EX_PI / 2) * radius;
        *px = 0.5f * (float)c->width + (lateral > 0.0f ? r * x / lateral : 0.0f);
        *py = 0.5f * (float)c->height - (lateral > 0.0f ? r * y / lateral : 0.0f);
        *depth = len;
        return 1;
    } else {
        float aspect = (float)c->width / (float)c->height;
        if (!(z > 0.0f)) return 0;
        *px = (x / (z * c->tan_half * aspect) + 1.0f) * 0.5f * (float)c->width;
        *py = (1.0f - y / (z * c->tan_half)) * 0.5f * (float)c->height;
        *depth = z;
        return 1;
    }
}

#endif /* EXAMPLES_COMMON_CAMERA_H */
