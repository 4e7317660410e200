/* assets.h — the web UI's files (web/, built by Vite) embedded in the binary.
 *
 * Design note: CMake runs the web build and cmake/embed_assets.cmake turns its output
 * folder into a generated C table (web_assets.c in the build folder); this lookup is the
 * only code that reads it. The table is immutable, so lookups are thread-safe. */
#ifndef SRV_ASSETS_H
#define SRV_ASSETS_H

#include <stddef.h>

typedef struct srv_asset {
    const char *path;         /* URL path, e.g. "/index.html", "/assets/index-1a2b.js" */
    const char *content_type; /* e.g. "text/html; charset=utf-8" */
    const unsigned char *data;
    size_t size;
} srv_asset;

/* The generated table (web_assets.c): srv_asset_count entries. */
extern const srv_asset srv_asset_table[];
extern const size_t srv_asset_count;

/* The asset at URL path `path` ("/" is "/index.html"; a query string is ignored), or NULL.
 * The result is static data: never freed. */
const srv_asset *srv_asset_find(const char *path);

#endif
