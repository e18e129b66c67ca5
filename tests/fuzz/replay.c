/* replay.c - replays a fuzz target's committed corpus without libFuzzer.

   Linked with one tests/fuzz/fuzz_NAME.c (see fuzz.h) and built with any C
   compiler under ASan+UBSan, it runs every file of tests/fuzz/corpus/NAME
   (or the files and directories given as arguments) through the target:
   once as the file is, checking the outcome its name promises ("ok-",
   "corrupt-", "version-"; an ok- file must also save to the same bytes), and once through the fuzzing entry point (with its
   checksum made to match). Each file is one case; the program ends with the
   project's closing line "N passed, N failed". */
#if !defined(_POSIX_C_SOURCE) || _POSIX_C_SOURCE < 200809L
#  undef _POSIX_C_SOURCE
#  define _POSIX_C_SOURCE 200809L   /* opendir, readdir, stat */
#endif
#include <dirent.h>
#include <sys/stat.h>
#define FUZZ_REPLAY_MAIN   /* the entry point is the target's */
#include "tests/fuzz/fuzz.h"

typedef struct replay_totals {
    int passed, failed;
    int outcomes[FUZZ_OTHER + 1];
} replay_totals;

static const char *outcome_name(fuzz_outcome o)
{
    switch (o) {
    case FUZZ_LOADED: return "loaded";
    case FUZZ_CORRUPT: return "corrupt";
    case FUZZ_VERSION: return "version";
    default: return "other error";
    }
}

/* The outcome a file's name promises, or -1 when it promises none. */
static int promised_outcome(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    if (strncmp(base, "ok-", 3) == 0) return FUZZ_LOADED;
    if (strncmp(base, "corrupt-", 8) == 0) return FUZZ_CORRUPT;
    if (strncmp(base, "version-", 8) == 0) return FUZZ_VERSION;
    return -1;
}

static uint8_t *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    uint8_t *data = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
        data = (uint8_t *)malloc((size_t)n + 1);   /* + 1: an empty file still gets a pointer */
        if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
            free(data);
            data = NULL;
        }
        *size = (size_t)n;
    }
    fclose(f);
    return data;
}

/* A seed that must load carries the checksum fuzz.h computes: otherwise the
   fuzzing entry point would write checksums the library refuses, and no
   mutation would get past them. */
static int checksum_agrees(const uint8_t *data, size_t size)
{
    uint8_t *copy;
    int same;
    if (!fuzz_this_target.checksum_trailer) return 1;
    if (size < FUZZ_MIN_CHECKSUMMED) return 0;
    copy = (uint8_t *)malloc(size);
    if (!copy) return 0;
    memcpy(copy, data, size);
    fuzz_fix_checksum(copy, size);
    same = memcmp(copy, data, size) == 0;
    free(copy);
    return same;
}

static void replay_file(const char *path, replay_totals *t)
{
    size_t size = 0;
    uint8_t *data = read_file(path, &size);
    int promised = promised_outcome(path), ok = 1;
    fuzz_outcome got;
    if (!data) {
        printf("FAIL %s: cannot read\n", path);
        t->failed++;
        return;
    }
    got = fuzz_this_target.load(data, size);
    t->outcomes[got]++;
    if (promised >= 0 && got != (fuzz_outcome)promised) {
        printf("FAIL %s: %s, its name promises %s\n", path, outcome_name(got), outcome_name((fuzz_outcome)promised));
        ok = 0;
    }
    if (promised == FUZZ_LOADED && fuzz_this_target.resaves_same && !fuzz_this_target.resaves_same(data, size)) {
        printf("FAIL %s: a file the library wrote loads and saves to other bytes\n", path);
        ok = 0;
    }
    if (promised == FUZZ_LOADED && !checksum_agrees(data, size)) {
        printf("FAIL %s: fuzz.h's CRC-32 differs from the one the library wrote\n", path);
        ok = 0;
    }
    LLVMFuzzerTestOneInput(data, size);
    free(data);
    if (ok) t->passed++;
    else t->failed++;
}

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Every regular file of dir, in name order (the output does not depend on
   the file system's order). */
static void replay_directory(const char *dir, replay_totals *t)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    char **names = NULL;
    size_t count = 0, cap = 0, i;
    if (!d) {
        printf("FAIL %s: cannot open the directory\n", dir);
        t->failed++;
        return;
    }
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(dir) + strlen(e->d_name) + 2;
        char *path;
        struct stat st;
        if (e->d_name[0] == '.') continue;
        if (count == cap) {
            char **grown = (char **)realloc(names, (cap ? 2 * cap : 64) * sizeof *names);
            if (!grown) break;
            names = grown;
            cap = cap ? 2 * cap : 64;
        }
        path = (char *)malloc(n);
        if (!path) break;
        snprintf(path, n, "%s/%s", dir, e->d_name);
        if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) { free(path); continue; }
        names[count++] = path;
    }
    closedir(d);
    if (count) qsort(names, count, sizeof *names, by_name);
    for (i = 0; i < count; i++) {
        replay_file(names[i], t);
        free(names[i]);
    }
    free(names);
    if (count == 0) {
        printf("FAIL %s: no files\n", dir);
        t->failed++;
    }
}

int main(int argc, char **argv)
{
    replay_totals t;
    char dir[256];
    int i;
    memset(&t, 0, sizeof t);
    if (argc < 2) {
        snprintf(dir, sizeof dir, "tests/fuzz/corpus/%s", fuzz_this_target.name);
        replay_directory(dir, &t);
    }
    for (i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) == 0 && S_ISDIR(st.st_mode)) replay_directory(argv[i], &t);
        else replay_file(argv[i], &t);
    }
    printf("  note: fuzz_%s corpus: %d files loaded, %d refused as corrupt, %d as a version, %d otherwise\n",
           fuzz_this_target.name, t.outcomes[FUZZ_LOADED], t.outcomes[FUZZ_CORRUPT], t.outcomes[FUZZ_VERSION],
           t.outcomes[FUZZ_OTHER]);
    printf("%d passed, %d failed\n", t.passed, t.failed);
    return t.failed ? 1 : 0;
}
