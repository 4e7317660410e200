/* fuzz_common.h — helpers shared by the libFuzzer harnesses in tests/fuzz/.
 *
 * Design note: every harness is one input surface of the renderer library, driven from
 * LLVMFuzzerTestOneInput with the bytes libFuzzer gives. Surfaces that need files (scene
 * references, shards) use one private temporary folder per process, made on first use
 * and removed at exit, so parallel fuzzers and the ctest smoke runs never share files.
 * A broken invariant (an API contract, not just a crash) is reported with FUZZ_CHECK,
 * which prints the condition and aborts, so libFuzzer saves the input as a crash. */
#ifndef TS_FUZZ_COMMON_H
#define TS_FUZZ_COMMON_H

#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* mkdtemp, nftw */
#endif

#include <ftw.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define FUZZ_CHECK(cond)                                                                                \
    do {                                                                                                \
        if (!(cond)) {                                                                                  \
            fprintf(stderr, "%s:%d: fuzz invariant broken: %s\n", __FILE__, __LINE__, #cond);          \
            abort();                                                                                    \
        }                                                                                               \
    } while (0)

static char fuzz_dir_path[64];

static int fuzz_remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(path);
}

static void fuzz_dir_remove(void)
{
    if (fuzz_dir_path[0]) nftw(fuzz_dir_path, fuzz_remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* The process's private folder (created on first call; aborts if it cannot be). */
static const char *fuzz_dir(void)
{
    if (!fuzz_dir_path[0]) {
        const char *tmp = getenv("TMPDIR");
        snprintf(fuzz_dir_path, sizeof fuzz_dir_path, "%s/ts_fuzz_XXXXXX",
                 tmp && *tmp && strlen(tmp) < 40 ? tmp : "/tmp");
        if (!mkdtemp(fuzz_dir_path)) {
            perror("fuzz: mkdtemp");
            abort();
        }
        atexit(fuzz_dir_remove);
    }
    return fuzz_dir_path;
}

/* Writes bytes to <fuzz_dir>/name (replacing it); the full path goes to out. */
__attribute__((unused)) static void fuzz_write_file(const char *name, const void *data, size_t len, char *out, size_t out_len)
{
    snprintf(out, out_len, "%s/%s", fuzz_dir(), name);
    FILE *f = fopen(out, "wb");
    if (!f || (len && fwrite(data, 1, len, f) != len) || fclose(f) != 0) {
        perror("fuzz: writing a temporary file");
        abort();
    }
}

/* FNV-1a of the input: a deterministic source of query points for evaluating what an
 * input loaded into (directions, texture coordinates). */
__attribute__((unused)) static uint64_t fuzz_hash(const uint8_t *data, size_t size)
{
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < size; i++) h = (h ^ data[i]) * 1099511628211ull;
    return h;
}

/* A float in [0, 1) from the state, advancing it (splitmix64). */
__attribute__((unused)) static float fuzz_unit(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (float)(z >> 40) * 0x1p-24f;
}

#endif
