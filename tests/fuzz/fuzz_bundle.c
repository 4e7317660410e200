/* fuzz_bundle.c — the bundle reader (server/bundle.h): any bytes as a posted tar bundle,
 * plain or gzip, unpacked under small limits into a folder of the process's private one.
 * Checks the unpacker's promises: a refusal leaves no folder and says why with a 4xx (or a
 * 500 for the disk); an accepted bundle holds only regular files and folders (no link,
 * device or FIFO), no more entries and bytes than the limits, everything below the folder,
 * and scene.json or scene.pbrt at its root, as a regular file. Seeds: seeds_bundle.sh. */
#include "fuzz_common.h"

#include <sys/stat.h>

#include "bundle.h"

static const srv_bundle_limits limits = {1u << 20, 64, 128, 256u << 10, 1u << 20};

static uint64_t walk_bytes;
static uint32_t walk_files;
static size_t root_len;

static int visit(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)ftw;
    FUZZ_CHECK(flag == FTW_F || flag == FTW_D || flag == FTW_DP);
    FUZZ_CHECK(S_ISREG(sb->st_mode) || S_ISDIR(sb->st_mode));
    FUZZ_CHECK(strlen(path) >= root_len);
    if (strlen(path) > root_len) FUZZ_CHECK(strlen(path) - root_len - 1 <= limits.max_path);
    if (S_ISREG(sb->st_mode)) {
        walk_files++;
        FUZZ_CHECK((uint64_t)sb->st_size <= limits.max_entry_bytes);
        walk_bytes += (uint64_t)sb->st_size;
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char dir[128], path[160];
    snprintf(dir, sizeof dir, "%s/bundle", fuzz_dir());
    srv_bundle_info info;
    int status = 0;
    ts_error err = {0};
    struct stat sb;
    ts_status st = srv_bundle_unpack(data, size, dir, &limits, &info, &status, &err);
    if (st) {
        FUZZ_CHECK(lstat(dir, &sb) != 0); /* nothing left */
        FUZZ_CHECK(err.message[0] != '\0');
        FUZZ_CHECK(status == 400 || status == 413 || status == 500);
        return 0;
    }
    FUZZ_CHECK(status == 0 && info.scene_file);
    FUZZ_CHECK(!strcmp(info.scene_file, "scene.json") || !strcmp(info.scene_file, "scene.pbrt"));
    snprintf(path, sizeof path, "%s/%s", dir, info.scene_file);
    FUZZ_CHECK(lstat(path, &sb) == 0 && S_ISREG(sb.st_mode));
    walk_bytes = 0, walk_files = 0, root_len = strlen(dir);
    FUZZ_CHECK(nftw(dir, visit, 16, FTW_PHYS) == 0);
    FUZZ_CHECK(walk_bytes == info.expanded_bytes && walk_bytes <= limits.max_expanded);
    FUZZ_CHECK(walk_files <= info.entries && info.entries <= limits.max_entries);
    FUZZ_CHECK(srv_bundle_remove_tree(dir) == 0 && lstat(dir, &sb) != 0);
    return 0;
}
