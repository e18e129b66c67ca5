/* What the walkthrough's two test files share (tests/test_walkthrough.c,
   tests/test_walkthrough_radiosity.c): luminance, the stored reference
   frames' paths, the moment the bunny is deepest under the desk, and
   temporary cache directories. Include after examples/common/walkthrough.h. */
#ifndef TESTS_WALKTHROUGH_TEST_H
#define TESTS_WALKTHROUGH_TEST_H

#include <stdio.h>
#include <stdlib.h>

/* Rec. 709 luminance of a linear RGB triple. */
TEST__FN float luminance(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* tests/data/walkthrough_<mode>_f<frame>.pfm */
TEST__FN void reference_path(char *path, size_t size, wt_mode mode, int frame)
{
    snprintf(path, size, "tests/data/walkthrough_%s_f%d.pfm", wt_mode_name(mode), frame);
}

/* The time at which the bunny is deepest under the office's desk (x 1.0-2.6, z 2.9-3.7). */
TEST__FN double time_under_desk(void)
{
    double best = 0.0;
    float depth = -1e9f, p[3];
    int i;
    for (i = 0; i <= 200; i++) {
        float d;
        wt_bunny_position(NULL, i / 200.0, p, NULL);
        d = fminf(fminf(p[0] - 1.0f, 2.6f - p[0]), fminf(p[2] - 2.9f, 3.7f - p[2]));
        if (d > depth) { depth = d; best = i / 200.0; }
    }
    return best;
}

/* A new empty directory under /tmp, its path into dir; 0 when none could be made. */
TEST__FN int make_temp_dir(char *dir, size_t size)
{
    snprintf(dir, size, "/tmp/walkthrough-test-XXXXXX");
    return mkdtemp(dir) != NULL;
}

TEST__FN void remove_dir(const char *dir)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "  could not remove %s\n", dir);
}

/* How many names in dir match the grep pattern; -1 when that cannot be told. */
TEST__FN int count_files(const char *dir, const char *pattern)
{
    char cmd[1200];
    FILE *p;
    int n = -1;
    snprintf(cmd, sizeof cmd, "ls -1 '%s' | grep -c -- '%s'", dir, pattern);
    p = popen(cmd, "r");
    if (p) {
        if (fscanf(p, "%d", &n) != 1) n = -1;
        pclose(p);
    }
    return n;
}

#endif
