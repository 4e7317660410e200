/* tmp_folder.c — see tmp_folder.h. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* program_invocation_short_name; mkdtemp, nftw */
#endif

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "tmp_folder.h"

#include <errno.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

char ts_tmp_dir[256];

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb, (void)flag, (void)ftw;
    return remove(path);
}

int ts_tmp_group_setup(void **state)
{
    (void)state;
    const char *t = getenv("TMPDIR");
    snprintf(ts_tmp_dir, sizeof ts_tmp_dir, "%s/%.64s_XXXXXX", t && *t && strlen(t) < 160 ? t : "/tmp",
             program_invocation_short_name);
    return mkdtemp(ts_tmp_dir) ? 0 : -1;
}

int ts_tmp_group_teardown(void **state)
{
    (void)state;
    if (ts_tmp_dir[0]) nftw(ts_tmp_dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
    return 0;
}

void ts_tmp_write(const char *rel, const void *data, size_t len, char *path, size_t path_len)
{
    char full[1024];
    if (snprintf(full, sizeof full, "%s/%s", ts_tmp_dir, rel) >= (int)sizeof full) fail_msg("path too long: %s", rel);
    for (char *s = full + strlen(ts_tmp_dir) + 1; *s; s++)
        if (*s == '/') {
            *s = '\0';
            if (mkdir(full, 0755) != 0 && errno != EEXIST) fail_msg("mkdir %s: %s", full, strerror(errno));
            *s = '/';
        }
    FILE *f = fopen(full, "wb");
    if (!f) fail_msg("cannot write %s: %s", full, strerror(errno));
    if (len) assert_int_equal(fwrite(data, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
    if (path) snprintf(path, path_len, "%s", full);
}
