/* log.c — the server's log; see log.h. */
#include "log.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *level_name(srv_log_level l)
{
    switch (l) {
    case SRV_LOG_ERROR: return "error";
    case SRV_LOG_WARN: return "warn";
    case SRV_LOG_INFO: return "info";
    case SRV_LOG_DEBUG: return "debug";
    }
    return "info";
}

void srv_log_init(srv_log *l, srv_log_format format, srv_log_level level, FILE *out)
{
    l->format = format;
    l->level = level;
    l->out = out;
    pthread_mutex_init(&l->mu, NULL);
}

void srv_log_fini(srv_log *l) { pthread_mutex_destroy(&l->mu); }

bool srv_log_enabled(const srv_log *l, srv_log_level level) { return l && l->out && level <= l->level; }

bool srv_log_parse_format(const char *s, srv_log_format *out)
{
    if (!strcmp(s, "text")) return *out = SRV_LOG_TEXT, true;
    if (!strcmp(s, "json")) return *out = SRV_LOG_JSON, true;
    return false;
}

bool srv_log_parse_level(const char *s, srv_log_level *out)
{
    for (int i = SRV_LOG_ERROR; i <= SRV_LOG_DEBUG; i++)
        if (!strcmp(s, level_name((srv_log_level)i))) return *out = (srv_log_level)i, true;
    return false;
}

static bool known(const srv_log_field *f) { return isfinite(f->num) && !(f->unknown_if_negative && f->num < 0); }

/* A string for a text line: as it is when it is a plain word, else JSON-quoted. */
static void put_text_value(FILE *out, const char *s)
{
    bool plain = *s != '\0';
    for (const char *c = s; *c && plain; c++)
        plain = (unsigned char)*c > ' ' && *c != '"' && *c != '=' && *c != '\\' && (unsigned char)*c != 0x7f;
    if (plain) {
        fputs(s, out);
        return;
    }
    cJSON *j = cJSON_CreateString(s);
    char *q = j ? cJSON_PrintUnformatted(j) : NULL;
    fputs(q ? q : "\"?\"", out);
    free(q);
    cJSON_Delete(j);
}

void srv_log_event(srv_log *l, srv_log_level level, const char *event, const srv_log_field *fields, int n)
{
    if (!srv_log_enabled(l, level)) return;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    struct tm tm;
    gmtime_r(&ts.tv_sec, &tm);
    char when[40];
    snprintf(when, sizeof when, "%04d-%02d-%02dT%02d:%02d:%02d.%03ldZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
             tm.tm_hour, tm.tm_min, tm.tm_sec, ts.tv_nsec / 1000000);
    if (l->format == SRV_LOG_JSON) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "time", when);
        cJSON_AddStringToObject(o, "level", level_name(level));
        cJSON_AddStringToObject(o, "event", event);
        for (int i = 0; i < n; i++) {
            if (fields[i].str) cJSON_AddStringToObject(o, fields[i].key, fields[i].str);
            else if (known(&fields[i])) cJSON_AddNumberToObject(o, fields[i].key, fields[i].num);
            else cJSON_AddNullToObject(o, fields[i].key);
        }
        char *s = cJSON_PrintUnformatted(o);
        cJSON_Delete(o);
        if (!s) return; /* out of memory: the line is lost, nothing else */
        pthread_mutex_lock(&l->mu);
        fprintf(l->out, "%s\n", s);
        fflush(l->out);
        pthread_mutex_unlock(&l->mu);
        free(s);
        return;
    }
    pthread_mutex_lock(&l->mu);
    fprintf(l->out, "%s %s %s", when, level_name(level), event);
    for (int i = 0; i < n; i++) {
        fprintf(l->out, " %s=", fields[i].key);
        if (fields[i].str) put_text_value(l->out, fields[i].str);
        else if (known(&fields[i])) fprintf(l->out, "%.6g", fields[i].num);
        else fputs("-", l->out);
    }
    fputc('\n', l->out);
    fflush(l->out);
    pthread_mutex_unlock(&l->mu);
}
