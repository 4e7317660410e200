/* scene.c — the scene's teardown; see scene.h. Building is scene_builder.c's. */
#include "scene/scene.h"

#include <stdlib.h>

#include "lights/envmap.h"
#include "materials/fourier_bsdf.h"
#include "textures/texture_cache.h"

void ts_scene_destroy(ts_scene *s)
{
    if (!s) return;
    if (s->accel) ts_accel_destroy(s->accel);
    for (uint32_t i = 0; i < s->n_fourier_tables; i++)
        ts_fourier_table_destroy(s->fourier_tables[i]);
    for (uint32_t i = 0; i < s->n_envmaps; i++)
        ts_envmap_destroy(s->envmaps[i]);
    ts_texture_cache_destroy(s->texture_cache);
    ts_light_distribution_fini(&s->light_distribution);
    ts_arena_fini(&s->arena);
    free(s);
}

double ts_scene_ray_weight(const ts_scene *s) { return 1.0 + (double)s->shading_cost / TS_LOOKUPS_PER_RAY; }
