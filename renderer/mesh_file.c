/* mesh_file.c — placeholder until its module lands. */
typedef int ts_placeholder_mesh_file;
