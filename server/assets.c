/* assets.c — lookup in the embedded web UI table; see assets.h. */
#include "assets.h"

#include <string.h>

const srv_asset *srv_asset_find(const char *path)
{
    if (!path || path[0] != '/') return NULL;
    size_t n = strcspn(path, "?#");
    if (n == 1) path = "/index.html", n = strlen(path);
    for (size_t i = 1; i < n; i++)
        if (path[i - 1] == '.' && path[i] == '.') return NULL;
    for (size_t i = 0; i < srv_asset_count; i++) {
        const srv_asset *a = &srv_asset_table[i];
        if (strlen(a->path) == n && !memcmp(a->path, path, n)) return a;
    }
    return NULL;
}
