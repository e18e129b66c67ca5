/* fuzz.h - what the project's fuzz targets share.

   One target per loader, tests/fuzz/fuzz_NAME.c: it includes this header
   (which defines the libFuzzer entry point), defines a load function (load
   the bytes, use what loaded, check it, free it) and the program's
   fuzz_this_target. The same source builds two programs:
   - `make fuzz`: with clang -fsanitize=fuzzer,address,undefined, a libFuzzer
     program that mutates the committed seeds of tests/fuzz/corpus/NAME (its
     findings and the inputs it keeps go under build/fuzz/);
   - `make test`: with tests/fuzz/replay.c under ASan+UBSan (clang's when
     clang is present, else gcc's), a program that replays every committed
     file of tests/fuzz/corpus/NAME (no libFuzzer needed).
   tests/fuzz/make_corpus.c writes the seeds from the headers' own save
   functions (`make fuzz-corpus` after a file format changes).

   Checksums. The project's files end in a CRC-32 of everything before it, so
   almost every mutation would stop at the checksum test. The fuzzing entry
   point therefore loads a copy whose last four bytes are the CRC-32 of the
   rest: the fuzzer reaches the checks behind the checksum. The replay also
   loads each file as it is, and checks that this header's CRC-32 agrees with
   the library's on every seed that must load.

   A seed's name says what loading it must give: "ok-..." must load (and,
   being a file the library wrote, save to the same bytes),
   "corrupt-..." must be refused as corrupt data, "version-..." as a version
   the library cannot read. Other names (a fuzzer's reproducers: crash-...,
   oom-..., or plain hashes) must only not crash.

   Besides the sanitizers, the targets check what a loaded object promises:
   every query on it answers without a sanitizer report, and saving it gives
   bytes that load again and save to the same bytes. A broken promise calls
   fuzz_fail, which aborts: the fuzzer keeps the input as a crash. */
#ifndef TESTS_FUZZ_FUZZ_H
#define TESTS_FUZZ_FUZZ_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(__GNUC__) || defined(__clang__)
#  define FUZZ_FN static __attribute__((unused))
#else
#  define FUZZ_FN static
#endif

typedef enum fuzz_outcome {
    FUZZ_LOADED = 0,   /* the loader accepted the bytes */
    FUZZ_CORRUPT,      /* refused as corrupt (or, for text, malformed) data */
    FUZZ_VERSION,      /* refused: a file format version this library cannot read */
    FUZZ_OTHER         /* refused otherwise (out of memory, ...) */
} fuzz_outcome;

#ifndef FUZZ_NO_TARGET   /* make_corpus.c uses only the checksum helpers */
typedef struct fuzz_target {
    const char *name;                                  /* tests/fuzz/corpus/<name> */
    fuzz_outcome (*load)(const uint8_t *data, size_t size);
    int checksum_trailer;                              /* the format ends in a CRC-32 of the rest */
    /* Whether loading the bytes and saving gives them back, as it must for a
       file the library wrote; the replay asks it of the seeds that must
       load. NULL where load itself requires it of every input, or where
       the format has no save. */
    int (*resaves_same)(const uint8_t *data, size_t size);
} fuzz_target;

/* Defined by the target's source, read by the entry point and the replay. */
extern const fuzz_target fuzz_this_target;
#endif

/* The smallest checksummed file: magic 8, version 4, payload size 8, CRC 4. */
#define FUZZ_MIN_CHECKSUMMED 24u

/* CRC-32 (IEEE 802.3, reflected), written independently of the headers;
   by table, since the fuzzer computes it for every input. */
FUZZ_FN uint32_t fuzz_crc32(const uint8_t *p, size_t n)
{
    static uint32_t table[256];
    uint32_t c = 0xFFFFFFFFu;
    size_t i;
    if (!table[1]) {   /* filled on first use (the programs are single-threaded) */
        uint32_t b, v;
        int k;
        for (b = 0; b < 256; b++) {
            for (v = b, k = 0; k < 8; k++) v = (v & 1u) ? 0xEDB88320u ^ (v >> 1) : v >> 1;
            table[b] = v;
        }
    }
    for (i = 0; i < n; i++) c = table[(c ^ p[i]) & 0xFFu] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

/* Writes the CRC-32 of data[0, size - 4) into its last four bytes
   (little-endian); size is at least FUZZ_MIN_CHECKSUMMED. */
FUZZ_FN void fuzz_fix_checksum(uint8_t *data, size_t size)
{
    uint32_t c = fuzz_crc32(data, size - 4);
    data[size - 4] = (uint8_t)c;
    data[size - 3] = (uint8_t)(c >> 8);
    data[size - 2] = (uint8_t)(c >> 16);
    data[size - 1] = (uint8_t)(c >> 24);
}

#ifndef FUZZ_NO_TARGET
/* A loaded object broke a promise: report it and abort, so that the fuzzer
   keeps the input and the replay counts a failure. */
FUZZ_FN void fuzz_fail(const char *what)
{
    fprintf(stderr, "fuzz_%s: %s\n", fuzz_this_target.name, what);
    fflush(stderr);
    abort();
}

FUZZ_FN void fuzz_require(int ok, const char *what)
{
    if (!ok) fuzz_fail(what);
}

/* Whether two byte strings are equal. */
FUZZ_FN int fuzz_same_bytes(const void *a, size_t na, const void *b, size_t nb)
{
    return na == nb && (na == 0 || memcmp(a, b, na) == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The entry point is defined once, in the target's translation unit. */
#ifndef FUZZ_REPLAY_MAIN
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t *copy;
    if (!fuzz_this_target.checksum_trailer || size < FUZZ_MIN_CHECKSUMMED) {
        fuzz_this_target.load(data, size);
        return 0;
    }
    copy = (uint8_t *)malloc(size);
    if (!copy) return 0;
    memcpy(copy, data, size);
    fuzz_fix_checksum(copy, size);
    fuzz_this_target.load(copy, size);
    free(copy);
    return 0;
}
#endif /* FUZZ_REPLAY_MAIN */
#endif /* FUZZ_NO_TARGET */

#endif /* TESTS_FUZZ_FUZZ_H */
