/* distribution.c — placeholder until its module lands. */
typedef int ts_placeholder_distribution;
