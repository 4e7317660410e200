/* fuzz_ply.c — libFuzzer harness: PLY meshes, ASCII and binary (mesh_file.h), from
 * memory; the same checks as fuzz_obj.c. */
#define FUZZ_MESH_NAME "fuzz.ply"
#include "fuzz_obj.c"
