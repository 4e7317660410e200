/* shape_sample.c — placeholder until its module lands. */
typedef int ts_placeholder_shape_sample;
