/* json_check.c — placeholder until its module lands. */
typedef int ts_placeholder_json_check;
