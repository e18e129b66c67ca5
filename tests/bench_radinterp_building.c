/* Benchmark of radinterp.h at building scale (issue 13): the generated
   buildings of about 1k, 4k, 16k and 64k triangles (examples/data/
   make_building.py) and the office beside them, with default settings.
   Per scene and thread count: solve time, mesh time, peak memory (the
   process's peak resident set, each run in a child process of its own so
   runs do not share a peak), links, leaves, mesh triangles, the longest
   gap between two progress calls, and the growth exponent of solve + mesh
   time between sizes (log(t2 / t1) / log(n2 / n1), n = triangles).
   One thread: thread CPU time of the solving thread (the machine is
   shared); two threads: wall time, said so.

       build/bench/bench_radinterp_building [SCENE ...] [1t] [2t] [--limit S]

   SCENE is 1k, 4k, 16k, 64k or office (default: all); a run that takes
   longer than the limit (default 300 s) is stopped and reported as such.
   Targets (issue 13, this 2-core machine): 16k solve + mesh under 60 s on
   2 threads and under 2 GB; growth exponent 4k -> 16k at most 1.3; 64k in
   under 10 minutes. */
#define _POSIX_C_SOURCE 200809L
#define RADINTERP_IMPLEMENTATION
#include "radinterp.h"
#include "examples/common/obj.h"
#include "examples/common/pool.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define PI 3.14159265358979323846

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static double thread_cpu(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* What one run measured, sent from the child to the parent through a pipe. */
typedef struct run_result {
    int ok;                        /* 1 done, 2 solved (mesh under way), 0 failed, -1 out of time */
    char error[96];
    uint32_t triangles, patches, leaves, links, cluster_links, mesh_triangles, mesh_leaves;
    double solve_s, mesh_s;        /* thread CPU (1 thread) or wall (2 threads) */
    double peak_mb, solution_mb, mesh_mb;
    double mesh_build_mb;          /* radinterp_mesh_info.build_bytes: the most the mesh build held */
    double link_mb, leaf_list_mb;  /* of solution_mb: links with their blockers; leaf lists (0: the solution keeps none) */
    double batch_mb;               /* the mesh build's largest batch of leaf lists */
    uint64_t leaf_entries, leaf_blockers;
    double max_gap_s;              /* longest wall time between progress calls */
} run_result;

typedef struct progress_clock { double last, max_gap; } progress_clock;

static int on_progress(void *user, uint64_t done, uint64_t total)
{
    progress_clock *c = (progress_clock *)user;
    double t = now();
    (void)done; (void)total;
    if (t - c->last > c->max_gap) c->max_gap = t - c->last;
    c->last = t;
    return 0;
}

static const char *scene_path(const char *name, char *buf, size_t size)
{
    if (!strcmp(name, "office")) return "examples/data/office.obj";
    if (!strcmp(name, "1k") || !strcmp(name, "4k")) snprintf(buf, size, "examples/data/building_%s.obj", name);
    else snprintf(buf, size, "build/data/building_%s.obj", name);
    return buf;
}

/* Loads the scene, solves and meshes it; fills r and sends it to fd once
   solved and again at the end. Runs in the child. */
static void run_scene(const char *path, int threads, run_result *r, int fd)
{
    char err[512];
    obj_scene sc;
    uint32_t *patches, f, k;
    radinterp_material *mats;
    radinterp_desc d;
    radinterp_mesh_desc md;
    radinterp_solution *s = NULL;
    radinterp_mesh *m = NULL;
    radinterp_info info;
    radinterp_mesh_info mi;
    radinterp_result res;
    ex_pool *pool = threads > 1 ? ex_pool_create(threads) : NULL;
    progress_clock clock;
    struct rusage ru;
    double t0;
    memset(r, 0, sizeof *r);
    if (obj_load(path, &sc, err, sizeof err) != 0) { snprintf(r->error, sizeof r->error, "%.95s", err); return; }
    patches = (uint32_t *)malloc(4 * sizeof(uint32_t) * (sc.face_count ? sc.face_count : 1));
    mats = (radinterp_material *)calloc(sc.material_count ? sc.material_count : 1, sizeof *mats);
    for (f = 0; f < sc.face_count; f++) {
        uint32_t c = sc.face_start[f + 1] - sc.face_start[f];
        r->triangles += c >= 3 ? c - 2 : 0;
        for (k = 0; k < 4; k++) patches[4 * f + k] = k < c && c <= 4 ? sc.face_vertices[sc.face_start[f] + k] : RADINTERP_NO_VERTEX;
    }
    for (f = 0; f < sc.material_count; f++)
        for (k = 0; k < 3; k++) {
            mats[f].reflectance[k] = sc.materials[f].kd[k];
            mats[f].emission[k] = (float)PI * sc.materials[f].ke[k];
        }
    memset(&d, 0, sizeof d);
    d.positions = sc.positions;
    d.vertex_count = sc.vertex_count;
    d.patches = patches;
    d.patch_count = sc.face_count;
    d.patch_materials = sc.face_material;
    d.materials = mats;
    d.material_count = sc.material_count;
    d.parallel_for = pool ? ex_pool_parallel_for : NULL;
    d.parallel_user = pool;
    d.progress = on_progress;
    d.progress_user = &clock;
    clock.max_gap = 0.0;
    clock.last = now();
    t0 = threads > 1 ? now() : thread_cpu();
    res = radinterp_solve(&d, &s);
    r->solve_s = (threads > 1 ? now() : thread_cpu()) - t0;
    on_progress(&clock, 0, 0);
    if (res != RADINTERP_OK) { snprintf(r->error, sizeof r->error, "solve: %s", radinterp_result_string(res)); return; }
    radinterp_solution_info(s, &info);
    r->patches = info.patch_count;
    r->leaves = info.leaf_count;
    r->links = info.link_count;
    r->cluster_links = info.cluster_link_count;
    r->solution_mb = info.bytes / 1e6;
    r->link_mb = info.link_bytes / 1e6;
    r->leaf_list_mb = info.leaf_list_bytes / 1e6;
    r->leaf_entries = info.leaf_list_entries;
    r->leaf_blockers = info.leaf_blocker_entries;
    r->max_gap_s = clock.max_gap;
    getrusage(RUSAGE_SELF, &ru);
    r->peak_mb = ru.ru_maxrss / 1024.0;
    r->ok = 2;
    if (write(fd, r, sizeof *r) != (ssize_t)sizeof *r) return;
    r->ok = 0;
    memset(&md, 0, sizeof md);
    md.parallel_for = d.parallel_for;
    md.parallel_user = pool;
    md.progress = on_progress;
    md.progress_user = &clock;
    clock.last = now();
    t0 = threads > 1 ? now() : thread_cpu();
    res = radinterp_build_mesh(s, &md, &m);
    r->mesh_s = (threads > 1 ? now() : thread_cpu()) - t0;
    on_progress(&clock, 0, 0);
    if (res != RADINTERP_OK) { snprintf(r->error, sizeof r->error, "mesh: %s", radinterp_result_string(res)); return; }
    radinterp_mesh_get_info(m, &mi);
    r->mesh_triangles = mi.triangle_count;
    r->mesh_leaves = mi.leaf_count;
    r->mesh_mb = mi.bytes / 1e6;
    r->batch_mb = mi.leaf_list_bytes / 1e6;
    r->mesh_build_mb = mi.build_bytes / 1e6;
    r->max_gap_s = clock.max_gap;
    getrusage(RUSAGE_SELF, &ru);
    r->peak_mb = ru.ru_maxrss / 1024.0;
    r->ok = 1;
    radinterp_mesh_destroy(m);
    radinterp_solution_destroy(s);
    if (pool) ex_pool_destroy(pool);
    free(patches);
    free(mats);
    obj_free(&sc);
}

/* Runs run_scene in a child process stopped after limit seconds. */
static run_result run_child(const char *path, int threads, unsigned limit)
{
    run_result r;
    int fd[2], status = 0;
    pid_t pid;
    memset(&r, 0, sizeof r);
    if (pipe(fd) != 0) { snprintf(r.error, sizeof r.error, "pipe failed"); return r; }
    fflush(stdout);
    pid = fork();
    if (pid == 0) {
        close(fd[0]);
        alarm(limit);
        run_scene(path, threads, &r, fd[1]);
        if (r.ok != 2 && write(fd[1], &r, sizeof r) != (ssize_t)sizeof r) _exit(1);
        _exit(0);
    }
    close(fd[1]);
    r.ok = -1;
    if (pid > 0) { /* the last report sent: after the solve, then at the end */
        run_result got;
        while (read(fd[0], &got, sizeof got) == (ssize_t)sizeof got) r = got;
    }
    close(fd[0]);
    if (pid > 0) waitpid(pid, &status, 0);
    if (r.ok == 2 || r.ok == -1 || (WIFSIGNALED(status) && WTERMSIG(status) == SIGALRM)) {
        snprintf(r.error, sizeof r.error, r.ok == 2 ? "mesh stopped after %u s in all" : "stopped after %u s", limit);
        if (r.ok != 2) r.ok = -1;
    } else if (!r.ok && !r.error[0])
        snprintf(r.error, sizeof r.error, "child ended with status %d", status);
    return r;
}

/* Where the solution's memory goes (radinterp_info): the rest is nodes,
   patches, clusters and the ray-tracing structure. */
static void print_memory(const run_result *r)
{
    printf("          solution %.0f MB: links and their blockers %.0f MB, leaf lists %.0f MB (%llu entries, %llu blockers)",
           r->solution_mb, r->link_mb, r->leaf_list_mb, (unsigned long long)r->leaf_entries,
           (unsigned long long)r->leaf_blockers);
    if (r->ok == 1) printf("; the mesh's largest batch of leaf lists %.1f MB", r->batch_mb);
    printf("\n");
}

static void print_run(const char *name, int threads, const run_result *r, const run_result *prev)
{
    printf("  %-7s %dt", name, threads);
    if (r->ok == 2) {
        printf(" %6u tris %6u patches | solve %8.2f s %7u leaves %9u links (%u cluster) | %s | peak after solve %.0f MB "
               "(solution %.0f) | progress gap %.2f s\n", r->triangles, r->patches, r->solve_s, r->leaves, r->links,
               r->cluster_links, r->error, r->peak_mb, r->solution_mb, r->max_gap_s);
        print_memory(r);
        return;
    }
    if (r->ok != 1) { printf("  %s\n", r->error); return; }
    printf(" %6u tris %6u patches | solve %8.2f s %7u leaves %9u links (%u cluster) | mesh %8.2f s %8u tris | "
           "peak %7.0f MB (solution %.0f, mesh %.0f, mesh build %.0f) | progress gap %.2f s",
           r->triangles, r->patches, r->solve_s, r->leaves, r->links, r->cluster_links, r->mesh_s, r->mesh_triangles,
           r->peak_mb, r->solution_mb, r->mesh_mb, r->mesh_build_mb, r->max_gap_s);
    if (prev && prev->ok == 1 && prev->triangles > 0 && r->triangles > prev->triangles)
        printf(" | growth %.2f", log((r->solve_s + r->mesh_s) / (prev->solve_s + prev->mesh_s)) /
                                 log((double)r->triangles / prev->triangles));
    printf("\n");
    print_memory(r);
}

int main(int argc, char **argv)
{
    static const char *all[] = {"office", "1k", "4k", "16k", "64k"};
    const char *names[8];
    int n = 0, nthreads = 0, thread_list[2], i, t;
    unsigned limit = 300;
    char buf[128];
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "1t")) thread_list[nthreads++ % 2] = 1;
        else if (!strcmp(argv[i], "2t")) thread_list[nthreads++ % 2] = 2;
        else if (!strcmp(argv[i], "--limit") && i + 1 < argc) limit = (unsigned)atoi(argv[++i]);
        else if (n < 8) names[n++] = argv[i];
    }
    if (nthreads > 2) nthreads = 2;
    if (!n) for (i = 0; i < 5; i++) names[n++] = all[i];
    if (!nthreads) { thread_list[0] = 1; thread_list[1] = 2; nthreads = 2; }
    printf("radinterp.h at building scale, default settings (1t: thread CPU time; 2t: wall time; peak = the run's\n"
           "process peak resident set; mesh build = the most the mesh build held, radinterp_mesh_info.build_bytes;\n"
           "growth = exponent of solve + mesh time in the triangle count from the line above)\n"
           "targets: 16k solve + mesh < 60 s on 2 threads and < 2 GB; growth 4k -> 16k <= 1.3; 64k < 10 minutes\n");
    for (t = 0; t < nthreads; t++) {
        run_result prev;
        memset(&prev, 0, sizeof prev);
        for (i = 0; i < n; i++) {
            run_result r = run_child(scene_path(names[i], buf, sizeof buf), thread_list[t], limit);
            print_run(names[i], thread_list[t], &r, strcmp(names[i], "office") ? &prev : NULL);
            fflush(stdout);
            if (strcmp(names[i], "office")) prev = r;
        }
    }
    return 0;
}
