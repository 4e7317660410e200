/* tmp_folder.h — a test program's own temporary folder for the fixtures it writes (scene
 * files, Includes, images): $TMPDIR/<program>_XXXXXX (/tmp without TMPDIR), made by the
 * cmocka group setup below and removed with everything in it by the group teardown. */
#ifndef TS_TESTS_TMP_FOLDER_H
#define TS_TESTS_TMP_FOLDER_H

#include <stddef.h>

/* The folder's path once ts_tmp_group_setup made it. */
extern char ts_tmp_dir[256];

/* For cmocka_run_group_tests: make the folder (0, or -1 when it cannot be made) … */
int ts_tmp_group_setup(void **state);
/* … and remove it and everything below it, following no link (0). */
int ts_tmp_group_teardown(void **state);

/* Writes len bytes of data to ts_tmp_dir/rel, making the folders rel names; its full path
 * goes to path (path_len bytes) unless path is NULL. Fails the test when it cannot. */
void ts_tmp_write(const char *rel, const void *data, size_t len, char *path, size_t path_len);

#endif
