/* options.c — options by table (options.h). */
#include "options.h"

#include <getopt.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define HELP_COLUMN 30

/* A number as a person writes it: whole numbers in full, others by %g. */
static void fmt_number(char *buf, size_t n, double v)
{
    if (v == floor(v) && fabs(v) < 1e15) snprintf(buf, n, "%.0f", v);
    else snprintf(buf, n, "%g", v);
}

static void *field(void *opts, const srv_option *o) { return (char *)opts + o->offset; }
static const void *cfield(const void *opts, const srv_option *o) { return (const char *)opts + o->offset; }

static unsigned long long get_uint(const void *p, size_t size)
{
    switch (size) {
    case 1: return *(const uint8_t *)p;
    case 2: return *(const uint16_t *)p;
    case 4: return *(const uint32_t *)p;
    default: return *(const uint64_t *)p;
    }
}

static void set_uint(void *p, size_t size, unsigned long long v)
{
    switch (size) {
    case 1: *(uint8_t *)p = (uint8_t)v; break;
    case 2: *(uint16_t *)p = (uint16_t)v; break;
    case 4: *(uint32_t *)p = (uint32_t)v; break;
    default: *(uint64_t *)p = (uint64_t)v; break;
    }
}

/* "a whole number from 1 to 1024 seconds" / "a positive number of seconds" / … */
static void expected(const srv_option *o, char *buf, size_t n)
{
    char lo[32], hi[32];
    fmt_number(lo, sizeof lo, o->min);
    fmt_number(hi, sizeof hi, o->max);
    const char *unit = o->unit ? o->unit : "";
    const char *sp = o->unit ? " " : "";
    if (o->type == SRV_OPT_UINT) snprintf(buf, n, "a whole number from %s to %s%s%s", lo, hi, sp, unit);
    else if (o->min_exclusive && o->min == 0 && isinf(o->max))
        snprintf(buf, n, "a positive number%s%s", o->unit ? " of " : "", unit);
    else if (o->min_exclusive) snprintf(buf, n, "a number above %s, at most %s%s%s", lo, hi, sp, unit);
    else if (isinf(o->max)) snprintf(buf, n, "a number of at least %s%s%s", lo, sp, unit);
    else snprintf(buf, n, "a number from %s to %s%s%s", lo, hi, sp, unit);
}

static bool take(const srv_option *o, void *opts, const char *arg, char *why, size_t why_len)
{
    char exp[160];
    switch (o->type) {
    case SRV_OPT_UINT: {
        char *end;
        unsigned long long v = 0;
        bool ok = arg[0] >= '0' && arg[0] <= '9';
        if (ok) {
            v = strtoull(arg, &end, 10);
            ok = !*end && (double)v >= o->min && (double)v <= o->max;
        }
        if (!ok) {
            expected(o, exp, sizeof exp);
            snprintf(why, why_len, "--%s: expected %s, got '%s'", o->name, exp, arg);
            return false;
        }
        set_uint(field(opts, o), o->size, v);
        return true;
    }
    case SRV_OPT_NUMBER: {
        char *end;
        double v = strtod(arg, &end);
        bool ok = end != arg && !*end && isfinite(v) && (o->min_exclusive ? v > o->min : v >= o->min) && v <= o->max;
        if (!ok) {
            expected(o, exp, sizeof exp);
            snprintf(why, why_len, "--%s: expected %s, got '%s'", o->name, exp, arg);
            return false;
        }
        *(double *)field(opts, o) = v;
        return true;
    }
    case SRV_OPT_STRING:
        if (o->non_empty && !arg[0]) {
            snprintf(why, why_len, "--%s: expected a non-empty %s", o->name, o->unit ? o->unit : "value");
            return false;
        }
        *(const char **)field(opts, o) = arg;
        return true;
    case SRV_OPT_FLAG: *(bool *)field(opts, o) = true; return true;
    case SRV_OPT_CUSTOM: {
        char sentence[400] = "";
        if (o->parse(opts, o->name, arg, sentence, sizeof sentence)) return true;
        snprintf(why, why_len, "--%s: %s", o->name, sentence);
        return false;
    }
    case SRV_OPT_HELP: return true;
    }
    return false;
}

int srv_options_parse(const srv_option *t, size_t n, int argc, char **argv, void *opts, int *first_arg, char *why,
                      size_t why_len)
{
    struct option *lo = calloc(n + 1, sizeof *lo);
    char shorts[2 * 16 + 2] = ":";
    if (!lo) {
        snprintf(why, why_len, "out of memory");
        return SRV_OPTIONS_BAD;
    }
    for (size_t i = 0; i < n; i++) {
        bool value = t[i].type != SRV_OPT_FLAG && t[i].type != SRV_OPT_HELP;
        lo[i] = (struct option){t[i].name, value ? required_argument : no_argument, NULL, 256 + (int)i};
        if (t[i].short_name && strlen(shorts) + 2 < sizeof shorts) {
            size_t k = strlen(shorts);
            shorts[k] = t[i].short_name;
            shorts[k + 1] = value ? ':' : '\0';
            shorts[k + 2] = '\0';
        }
    }
    optind = 1;
    opterr = 0;
    int c, rc = SRV_OPTIONS_GO;
    while ((c = getopt_long(argc, argv, shorts, lo, NULL)) != -1) {
        const srv_option *o = NULL;
        if (c >= 256 && c < 256 + (int)n) o = &t[c - 256];
        for (size_t i = 0; !o && c > 0 && c < 256 && i < n; i++)
            if (t[i].short_name == c) o = &t[i];
        if (c == ':') {
            snprintf(why, why_len, "option '%s' needs a value", argv[optind - 1]);
            rc = SRV_OPTIONS_BAD;
            break;
        }
        if (!o) {
            snprintf(why, why_len, "unknown option '%s'", argv[optind - 1]);
            rc = SRV_OPTIONS_BAD;
            break;
        }
        if (o->type == SRV_OPT_HELP) {
            rc = SRV_OPTIONS_HELP;
            break;
        }
        if (!take(o, opts, optarg ? optarg : "", why, why_len)) {
            rc = SRV_OPTIONS_BAD;
            break;
        }
    }
    free(lo);
    if (first_arg) *first_arg = optind;
    return rc;
}

void srv_options_help(FILE *f, const srv_option *t, size_t n, const void *defaults)
{
    for (size_t i = 0; i < n; i++) {
        const srv_option *o = &t[i];
        if (o->heading) fprintf(f, "%s\n", o->heading);
        if (o->type == SRV_OPT_HELP) continue; /* every command takes --help; its usage line says so */
        char lead[128];
        int len;
        if (o->short_name)
            len = snprintf(lead, sizeof lead, "  -%c, --%s%s%s", o->short_name, o->name, o->metavar ? " " : "",
                           o->metavar ? o->metavar : "");
        else
            len = snprintf(lead, sizeof lead, "  --%s%s%s", o->name, o->metavar ? " " : "", o->metavar ? o->metavar : "");
        /* the help text's lines, the range and default after the last */
        char tail[200] = "", lo[32], hi[32];
        if (o->type == SRV_OPT_UINT || o->type == SRV_OPT_NUMBER) {
            fmt_number(lo, sizeof lo, o->min);
            fmt_number(hi, sizeof hi, o->max);
            if (o->type == SRV_OPT_NUMBER && o->min_exclusive && isinf(o->max))
                snprintf(tail, sizeof tail, "above %s", lo);
            else if (isinf(o->max)) snprintf(tail, sizeof tail, "at least %s", lo);
            else snprintf(tail, sizeof tail, "%s%s to %s", o->min_exclusive ? "above " : "", lo, hi);
        }
        char dflt[96] = "";
        if (o->deflt && o->deflt[0])
            snprintf(dflt, sizeof dflt, o->deflt[0] >= '0' && o->deflt[0] <= '9' ? "default %s" : "default: %s",
                     o->deflt);
        else if (!o->deflt && defaults) {
            const void *p = cfield(defaults, o);
            char num[40];
            switch (o->type) {
            case SRV_OPT_UINT:
                fmt_number(num, sizeof num, (double)get_uint(p, o->size));
                snprintf(dflt, sizeof dflt, "default %s", num);
                break;
            case SRV_OPT_NUMBER:
                fmt_number(num, sizeof num, *(const double *)p);
                snprintf(dflt, sizeof dflt, "default %s", num);
                break;
            case SRV_OPT_STRING: {
                const char *s = *(const char *const *)p;
                snprintf(dflt, sizeof dflt, s ? "default %s" : "default: none", s ? s : "");
                break;
            }
            default: break;
            }
        }
        char extra[320] = "";
        if (tail[0] && dflt[0]) snprintf(extra, sizeof extra, " (%s; %s)", tail, dflt);
        else if (tail[0] || dflt[0]) snprintf(extra, sizeof extra, " (%s)", tail[0] ? tail : dflt);
        const char *h = o->help ? o->help : "";
        int pad = len + 2 <= HELP_COLUMN ? HELP_COLUMN - len : 2;
        fprintf(f, "%s%*s", lead, pad, "");
        for (const char *line = h;;) {
            const char *nl = strchr(line, '\n');
            if (!nl) {
                fprintf(f, "%s%s\n", line, extra);
                break;
            }
            fprintf(f, "%.*s\n%*s", (int)(nl - line), line, HELP_COLUMN, "");
            line = nl + 1;
        }
    }
}
