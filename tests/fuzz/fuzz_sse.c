/* fuzz_sse.c — libFuzzer harness: the encoders on the way out of the server, the JSON
 * documents of a job (status, progress and tile events; job_store.h) and the SSE frame
 * around them (srv_events_format, events.h).
 *
 * The input is read as a stream of fields: a job's strings (id, name, failure message,
 * integrator, effects list; arbitrary bytes, invalid UTF-8 included) and numbers (raw
 * doubles, so NaN, ±Inf, denormals and 1e308 all occur), a progress record and a tile
 * event. Each document is printed as the server prints it and must parse back with cJSON
 * to the same values (a non-finite number as null), hold no raw line break (an SSE data
 * line cannot), and stay valid UTF-8 when its strings were. Then the printed documents
 * and the rest of the input as free text go through srv_events_format: the frame must be
 * `event: <name>`, data lines, a blank line, with no CR anywhere, and an SSE parser (the
 * HTML standard's rules) must recover the name and the text (line breaks as LF). */
#include "fuzz_common.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>

#include "events.h"
#include "integrators/effects.h"
#include "job_store.h"

typedef struct reader {
    const uint8_t *p;
    size_t n;
} reader;

static uint8_t take_u8(reader *r)
{
    if (!r->n) return 0;
    r->n--;
    return *r->p++;
}

static uint64_t take_bits(reader *r, int bytes)
{
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++)
        v = v << 8 | take_u8(r);
    return v;
}

static double take_double(reader *r)
{
    uint64_t bits = take_bits(r, 8);
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

/* A string of up to max bytes (its length from one byte of input; NUL ends it early)
 * into out[max + 1]. */
static void take_string(reader *r, char *out, size_t max)
{
    size_t len = take_u8(r) % (max + 1), i = 0;
    while (i < len && r->n) {
        char c = (char)take_u8(r);
        if (!c) break;
        out[i++] = c;
    }
    out[i] = '\0';
}

static bool utf8_valid(const char *s)
{
    const unsigned char *u = (const unsigned char *)s;
    while (*u) {
        unsigned c = *u;
        int more = c < 0x80             ? 0
                   : (c & 0xe0) == 0xc0 ? 1
                   : (c & 0xf0) == 0xe0 ? 2
                   : (c & 0xf8) == 0xf0 ? 3
                                        : -1;
        if (more < 0 || (more == 1 && c < 0xc2) || c > 0xf4) return false;
        uint32_t cp = c & (0x3fu >> more);
        for (int i = 1; i <= more; i++) {
            if ((u[i] & 0xc0) != 0x80) return false;
            cp = cp << 6 | (u[i] & 0x3f);
        }
        if ((more == 2 && cp < 0x800) || (more == 3 && (cp < 0x10000 || cp > 0x10ffff)) ||
            (cp >= 0xd800 && cp <= 0xdfff))
            return false;
        u += more + 1;
    }
    return true;
}

/* Prints o as the server does (deleting it) and parses it back (caller deletes the copy;
 * *text gets the printed document, caller frees). */
static cJSON *round_trip(cJSON *o, char **text, bool strings_utf8)
{
    FUZZ_CHECK(o != NULL);
    char *s = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    FUZZ_CHECK(s != NULL);
    FUZZ_CHECK(strpbrk(s, "\r\n") == NULL);
    if (strings_utf8) FUZZ_CHECK(utf8_valid(s));
    const char *end = NULL;
    cJSON *back = cJSON_ParseWithOpts(s, &end, 1);
    FUZZ_CHECK(back != NULL && cJSON_IsObject(back));
    *text = s;
    return back;
}

static void check_string(const cJSON *o, const char *key, const char *want)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    FUZZ_CHECK(cJSON_IsString(v) && strcmp(v->valuestring, want) == 0);
}

static void check_number(const cJSON *o, const char *key, double want)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    /* cJSON prints 15 significant digits when they read back within its own tolerance
     * (a relative DBL_EPSILON), else 17: the last bit may change, nothing more. */
    if (isfinite(want))
        FUZZ_CHECK(cJSON_IsNumber(v) &&
                   fabs(v->valuedouble - want) <= 2 * DBL_EPSILON * fmax(fabs(want), fabs(v->valuedouble)));
    else
        FUZZ_CHECK(cJSON_IsNull(v));
}

/* A number the encoder writes as null when `known` is false. */
static void check_number_or_null(const cJSON *o, const char *key, double want, bool known)
{
    if (known)
        check_number(o, key, want);
    else
        FUZZ_CHECK(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(o, key)));
}

/* The SSE frame of (name, data): parsed as a client would, it must give back both. */
static void check_frame(const char *name, const char *data)
{
    char *f = srv_events_format(name, data);
    FUZZ_CHECK(f != NULL);
    size_t n = strlen(f);
    FUZZ_CHECK(strchr(f, '\r') == NULL);
    FUZZ_CHECK(n >= 2 && f[n - 1] == '\n' && f[n - 2] == '\n');
    /* Every line but the final blank one is a field: `event: name`, then `data: …`. */
    char *got = malloc(n + 1);
    FUZZ_CHECK(got != NULL);
    size_t got_len = 0;
    int lines = 0;
    bool blank_seen = false;
    for (char *line = f; *line;) {
        char *nl = strchr(line, '\n');
        FUZZ_CHECK(nl != NULL);
        size_t len = (size_t)(nl - line);
        FUZZ_CHECK(!blank_seen); /* nothing after the blank line that ends the event */
        if (len == 0) {
            blank_seen = true;
        } else if (lines == 0) {
            FUZZ_CHECK(len == 7 + strlen(name) && !strncmp(line, "event: ", 7) &&
                       !strncmp(line + 7, name, len - 7));
        } else {
            FUZZ_CHECK(len >= 5 && !strncmp(line, "data:", 5));
            size_t skip = len > 5 && line[5] == ' ' ? 6 : 5; /* one leading space is dropped */
            if (lines > 1) got[got_len++] = '\n';
            memcpy(got + got_len, line + skip, len - skip);
            got_len += len - skip;
        }
        lines++;
        line = nl + 1;
    }
    FUZZ_CHECK(blank_seen && lines >= 3);
    got[got_len] = '\0';
    /* The data with CR LF and lone CR as LF. */
    size_t k = 0;
    for (size_t i = 0; data[i]; i++) {
        char c = data[i];
        if (c == '\r') {
            if (data[i + 1] == '\n') i++;
            c = '\n';
        }
        FUZZ_CHECK(k < got_len && got[k] == c);
        k++;
    }
    FUZZ_CHECK(k == got_len);
    free(got);
    free(f);
}

static const char *const event_names[] = {"tile", "progress", "done"};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader r = {data, size};
    srv_job *j = calloc(1, sizeof *j);
    FUZZ_CHECK(j != NULL);
    atomic_init(&j->refs, 1);
    char name[256];
    take_string(&r, j->id, sizeof j->id - 1);
    take_string(&r, name, sizeof name - 1);
    bool has_name = take_u8(&r) & 1;
    j->name = has_name ? name : NULL;
    take_string(&r, j->failure, 255);
    take_string(&r, j->integrator, sizeof j->integrator - 1);
    take_string(&r, j->effects, sizeof j->effects - 1);
    bool utf8 = utf8_valid(j->id) && (!has_name || utf8_valid(name)) && utf8_valid(j->failure) &&
                utf8_valid(j->integrator);
    j->settings.priority = (int)take_bits(&r, 4);
    j->settings.spp = (uint32_t)take_bits(&r, 4);
    j->settings.time_limit_s = take_double(&r);
    j->settings.target_error = take_double(&r);
    j->created_unix = take_double(&r);
    int *dims[] = {&j->full_w, &j->full_h, &j->x0, &j->y0, &j->w, &j->h, &j->nx, &j->ny};
    for (size_t i = 0; i < sizeof dims / sizeof dims[0]; i++)
        *dims[i] = (int)take_bits(&r, 4);

    /* The status document (a job without a scheduler job: what a failed restore shows). */
    char *text[3];
    cJSON *st = round_trip(srv_job_status_json(j), &text[0], utf8);
    check_string(st, "id", j->id);
    if (has_name)
        check_string(st, "name", name);
    else
        FUZZ_CHECK(cJSON_IsNull(cJSON_GetObjectItemCaseSensitive(st, "name")));
    check_string(st, "state", "failed");
    if (j->failure[0])
        check_string(st, "error", j->failure);
    else
        FUZZ_CHECK(!cJSON_GetObjectItemCaseSensitive(st, "error"));
    check_string(st, "integrator", j->integrator);
    check_number(st, "priority", j->settings.priority);
    check_number(st, "spp_target", j->settings.spp);
    check_number(st, "created_at", j->created_unix);
    check_number_or_null(st, "time_limit_s", j->settings.time_limit_s, j->settings.time_limit_s > 0);
    check_number_or_null(st, "target_error", j->settings.target_error, j->settings.target_error > 0);
    check_number_or_null(st, "error_estimate", -1, false);
    const cJSON *film = cJSON_GetObjectItemCaseSensitive(st, "film");
    FUZZ_CHECK(cJSON_IsObject(film));
    static const char *const film_keys[] = {"width",      "height",      "x0",      "y0",
                                            "crop_width", "crop_height", "tiles_x", "tiles_y"};
    for (size_t i = 0; i < sizeof film_keys / sizeof film_keys[0]; i++)
        check_number(film, film_keys[i], *dims[i]);
    /* effects: known keys only, each once, each a whole word of j->effects. */
    const cJSON *fx = cJSON_GetObjectItemCaseSensitive(st, "effects"), *e;
    FUZZ_CHECK(cJSON_IsArray(fx));
    uint32_t seen = 0;
    cJSON_ArrayForEach(e, fx)
    {
        FUZZ_CHECK(cJSON_IsString(e));
        uint32_t bit = 0;
        for (uint32_t b = 1; b < (1u << TS_EFFECT_COUNT); b <<= 1)
            if (ts_effect_key(b) && !strcmp(ts_effect_key(b), e->valuestring)) bit = b;
        FUZZ_CHECK(bit && !(seen & bit));
        seen |= bit;
        const char *at = strstr(j->effects, e->valuestring);
        FUZZ_CHECK(at != NULL);
    }
    const cJSON *urls = cJSON_GetObjectItemCaseSensitive(st, "urls");
    char want[160];
    snprintf(want, sizeof want, "/api/v1/jobs/%s", j->id);
    check_string(urls, "self", want);
    cJSON_Delete(st);

    /* A progress event. */
    ts_job_progress p = {0};
    p.state = (ts_job_state)(take_u8(&r) % (TS_JOB_FAILED + 1));
    p.halt = (ts_halt_reason)(take_u8(&r) % (TS_HALT_RESTORED + 1));
    p.spp_done = (uint32_t)take_bits(&r, 4);
    p.spp_target = (uint32_t)take_bits(&r, 4);
    p.pass_end = (uint32_t)take_bits(&r, 4);
    p.elapsed_s = take_double(&r);
    p.samples = take_bits(&r, 8);
    p.samples_per_s = take_double(&r);
    p.error_estimate = take_double(&r);
    cJSON *pr = round_trip(srv_job_progress_json(j, &p), &text[1], utf8);
    check_string(pr, "id", j->id);
    check_string(pr, "state", j->failure[0] ? "failed" : ts_job_state_name(p.state));
    check_string(pr, "halt_reason", ts_halt_reason_name(p.halt));
    check_number(pr, "spp", p.spp_done);
    check_number(pr, "spp_target", p.spp_target);
    check_number(pr, "pass_spp", p.pass_end);
    check_number(pr, "elapsed_s", p.elapsed_s);
    check_number(pr, "samples", (double)p.samples);
    check_number(pr, "samples_per_s", p.samples_per_s);
    check_number_or_null(pr, "error_estimate", p.error_estimate, p.error_estimate >= 0);
    cJSON_Delete(pr);

    /* A tile event. */
    ts_tile_event ev;
    int *tile[] = {&ev.tx, &ev.ty, &ev.x, &ev.y, &ev.w, &ev.h};
    for (size_t i = 0; i < sizeof tile / sizeof tile[0]; i++)
        *tile[i] = (int)take_bits(&r, 4);
    ev.spp = (uint32_t)take_bits(&r, 4);
    cJSON *te = round_trip(srv_job_tile_json(j, &ev), &text[2], utf8);
    static const char *const tile_keys[] = {"tx", "ty", "x", "y", "w", "h"};
    for (size_t i = 0; i < sizeof tile_keys / sizeof tile_keys[0]; i++)
        check_number(te, tile_keys[i], *tile[i]);
    check_number(te, "spp", ev.spp);
    snprintf(want, sizeof want, "/api/v1/jobs/%s/tiles/%d/%d.png", j->id, ev.tx, ev.ty);
    check_string(te, "png", want);
    snprintf(want, sizeof want, "/api/v1/jobs/%s/tiles/%d/%d.exr", j->id, ev.tx, ev.ty);
    check_string(te, "exr", want);
    cJSON_Delete(te);
    /* The directly printed frame of the same event is byte for byte the cJSON one. */
    char *direct = srv_job_tile_event(j, &ev), *framed = srv_events_format("tile", text[2]);
    FUZZ_CHECK(direct && framed && strcmp(direct, framed) == 0);
    free(direct);
    free(framed);

    /* SSE frames: the three documents, then the rest of the input as free text. */
    for (int i = 0; i < 3; i++) {
        check_frame(event_names[i], text[i]);
        free(text[i]);
    }
    char *rest = malloc(r.n + 1);
    FUZZ_CHECK(rest != NULL);
    memcpy(rest, r.p, r.n);
    rest[r.n] = '\0';
    check_frame(event_names[size % 3], rest);
    free(rest);
    free(j);
    return 0;
}
