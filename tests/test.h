/* test.h - the project's test harness: named test cases, tolerant float
   comparisons that print both values, and the closing line "N passed, N failed".

   Usage, in exactly one .c file per test program:

       #include "test.h"
       static void test_addition(void) { CHECK(1 + 1 == 2); CHECK_CLOSE(0.1 + 0.2, 0.3, 1e-12, 0.0); }
       int main(int argc, char **argv) {
           TEST_INIT(argc, argv);
           RUN(test_addition);
           return test_finish();
       }

   A test case passes when none of its checks fails. CHECK_CLOSE(actual, expected,
   rel, abs) passes when |actual - expected| <= abs + rel * |expected|; NaN never
   passes. Each failure prints file, line, both values, the difference and the
   tolerance. test_finish() prints "N passed, N failed" alone on the last line and
   returns the process exit code (non-zero when anything failed). Each case's
   line ("ok   name (1.2 s CPU)") gives the CPU time it took, all threads
   together: the figure to look at when make test grows.

   Running "prog NAME" runs only the test cases whose name contains NAME.
   test_note() prints a measured number that belongs in an issue note (an error
   table, a hit rate); it never affects the result.

   A file a test writes is named by test_scratch_path(path, size, "what"):
   TEST_SCRATCH_DIR "<program>-what", <program> the program's file name.
   tests/run.sh runs several programs at once (the gcc and clang builds of
   one test among them), and a fixed name would let one overwrite a file
   another is still reading. test_scratch_name gives the name without the
   directory, for an OBJ's mtllib line. */
#ifndef PROJECT_TEST_H
#define PROJECT_TEST_H

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(__GNUC__) || defined(__clang__)
#  define TEST__FN static __attribute__((unused))
#else
#  define TEST__FN static
#endif

typedef struct test_state {
    int passed, failed;       /* test cases */
    int case_failures;        /* failed checks in the running case */
    const char *filter;       /* run only names containing this, or NULL */
    const char *current;      /* name of the running case */
    const char *program;      /* argv[0] without its directory */
} test_state;

static test_state test__state;

#define TEST_INIT(argc, argv) test_init((argc), (argv))
#define RUN(fn) test_run(#fn, fn)

#define CHECK(cond) \
    test_check((cond) ? 1 : 0, __FILE__, __LINE__, "%s", #cond)
#define CHECK_MSG(cond, ...) \
    test_check((cond) ? 1 : 0, __FILE__, __LINE__, __VA_ARGS__)
#define CHECK_CLOSE(actual, expected, rel, abs_tol) \
    test_check_close((double)(actual), (double)(expected), (double)(rel), (double)(abs_tol), \
                     __FILE__, __LINE__, #actual, #expected)
#define CHECK_EQ_INT(actual, expected) \
    test_check_int((long long)(actual), (long long)(expected), __FILE__, __LINE__, #actual, #expected)

TEST__FN void test_init(int argc, char **argv)
{
    memset(&test__state, 0, sizeof test__state);
    test__state.filter = argc > 1 ? argv[1] : NULL;
    test__state.program = argc > 0 && argv[0] && argv[0][0] ? argv[0] : "test";
    if (strrchr(test__state.program, '/') && strrchr(test__state.program, '/')[1])
        test__state.program = strrchr(test__state.program, '/') + 1;
}

/* Where a test writes its files: a directory of the build, tests run from the
   repository's root. */
#define TEST_SCRATCH_DIR "build/tests/"

/* "<program>-what" into name (size bytes); returns name. */
TEST__FN const char *test_scratch_name(char *name, size_t size, const char *what)
{
    snprintf(name, size, "%s-%s", test__state.program ? test__state.program : "test", what);
    return name;
}

/* TEST_SCRATCH_DIR "<program>-what" into path (size bytes); returns path. */
TEST__FN const char *test_scratch_path(char *path, size_t size, const char *what)
{
    char name[256];
    snprintf(path, size, "%s%s", TEST_SCRATCH_DIR, test_scratch_name(name, sizeof name, what));
    return path;
}

/* Prints a failure and marks the running case failed. Returns ok so a caller
   can stop early: if (!CHECK(p != NULL)) return; */
TEST__FN int test_check(int ok, const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    if (ok) return 1;
    test__state.case_failures++;
    fprintf(stderr, "  FAIL %s (%s:%d): ", test__state.current ? test__state.current : "?", file, line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return 0;
}

TEST__FN int test_check_close(double actual, double expected, double rel, double abs_tol,
                            const char *file, int line, const char *actual_text,
                            const char *expected_text)
{
    double diff = fabs(actual - expected);
    double tol = abs_tol + rel * fabs(expected);
    int ok = !(diff > tol) && !isnan(actual) && !isnan(expected);
    return test_check(ok, file, line,
                      "%s = %.9g, expected %s = %.9g (difference %.3g, tolerance %.3g)",
                      actual_text, actual, expected_text, expected, diff, tol);
}

TEST__FN int test_check_int(long long actual, long long expected, const char *file, int line,
                          const char *actual_text, const char *expected_text)
{
    return test_check(actual == expected, file, line, "%s = %lld, expected %s = %lld",
                      actual_text, actual, expected_text, expected);
}

/* A measured figure worth reporting; printed, never judged. */
/* A copy of n saved bytes with one more byte after them (free it): what a
   loader given a buffer that goes on past the object sees. NULL when out of
   memory. */
TEST__FN unsigned char *test_with_byte_after(const void *bytes, size_t n)
{
    unsigned char *longer = (unsigned char *)malloc(n + 1);
    if (!longer) return NULL;
    memcpy(longer, bytes, n);
    longer[n] = 0xEE;
    return longer;
}

TEST__FN void test_note(const char *fmt, ...)
{
    va_list ap;
    printf("  note: ");
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    putchar('\n');
    fflush(stdout);
}

TEST__FN void test_run(const char *name, void (*fn)(void))
{
    if (test__state.filter && !strstr(name, test__state.filter)) return;
    clock_t start = clock();
    double cpu;
    test__state.current = name;
    test__state.case_failures = 0;
    fn();
    cpu = (double)(clock() - start) / CLOCKS_PER_SEC;
    if (test__state.case_failures) {
        test__state.failed++;
        printf("FAIL %s (%.1f s CPU)\n", name, cpu);
    } else {
        test__state.passed++;
        printf("ok   %s (%.1f s CPU)\n", name, cpu);
    }
    fflush(stdout);
    test__state.current = NULL;
}

TEST__FN int test_finish(void)
{
    printf("%d passed, %d failed\n", test__state.passed, test__state.failed);
    fflush(stdout);
    return test__state.failed ? 1 : 0;
}

#endif /* PROJECT_TEST_H */
