/* pbrt_lexer.c — streaming tokenizer of pbrt-v3 scene files; see pbrt_lexer.h.
 *
 * The buffer holds bytes [base, base + end) of the file; pos is the next byte to look at.
 * Refilling keeps only the token being scanned (numbers and words, which are converted
 * from the buffer) and moves it to the front; strings and comments are consumed as they
 * are scanned, so they never pin the buffer. Lines are counted while skipping white
 * space (strings and comments cannot contain a newline), and a column is the distance to
 * the offset of the current line's start, so positions cost nothing per byte. */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* O_CLOEXEC, O_NOFOLLOW */
#endif

#include "pbrt3/pbrt_lexer.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <nettle/sha2.h>

#define CHUNK (1u << 20)

struct ts_pbrt_lexer {
    int fd;          /* -1: memory */
    const char *buf; /* bytes [0, end) */
    char *own;       /* file mode: the buffer (buf == own), cap bytes */
    size_t cap, pos, end;
    int at_eof;            /* nothing more to read */
    uint64_t base;         /* file offset of buf[0] */
    uint64_t line_start;   /* file offset of the current line's first byte */
    uint32_t line;
    uint64_t max_bytes, total_read;
    const char *display;
    char *scratch; /* decoded text of the last WORD / STRING */
    size_t scratch_cap;
    struct sha256_ctx sha; /* of every byte read, in order (ts_pbrt_lexer_digest) */
};

static ts_status lex_fail(ts_pbrt_lexer *lx, ts_error *err, ts_status st, uint64_t offset, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static ts_status lex_fail(ts_pbrt_lexer *lx, ts_error *err, ts_status st, uint64_t offset, const char *fmt, ...)
{
    char msg[TS_ERROR_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    uint64_t col = offset >= lx->line_start ? offset - lx->line_start + 1 : 1;
    ts_error_set(err, st, "%s:%u:%llu: %s", lx->display, lx->line, (unsigned long long)col, msg);
    if (err) ts_pbrt_sanitize_utf8(err->message);
    return st;
}

static ts_pbrt_lexer *lexer_alloc(const char *display)
{
    ts_pbrt_lexer *lx = calloc(1, sizeof *lx);
    if (!lx) return NULL;
    lx->fd = -1;
    lx->line = 1;
    lx->display = display;
    sha256_init(&lx->sha);
    return lx;
}

ts_status ts_pbrt_lexer_open(const char *path, bool resolved, const char *display, uint64_t max_bytes,
                             ts_pbrt_lexer **out, ts_error *err)
{
    *out = NULL;
    int fd = open(path, O_RDONLY | O_CLOEXEC | O_NONBLOCK | (resolved ? O_NOFOLLOW : 0));
    if (fd < 0) {
        int e = errno;
        return ts_error_set(err, e == ENOMEM ? TS_ERR_NOMEM : TS_ERR_IO, "'%s': cannot open (%s)", display,
                            e == ENOENT ? "no such file or directory"
                            : e == EACCES ? "permission denied"
                            : e == ELOOP ? "a symbolic link"
                                         : "system error");
    }
    ts_status st = TS_OK;
    struct stat sb;
    if (fstat(fd, &sb) != 0) {
        st = ts_error_set(err, TS_ERR_IO, "'%s': cannot read (system error)", display);
        goto fail_fd;
    }
    if (!S_ISREG(sb.st_mode)) {
        st = ts_error_set(err, TS_ERR_INVALID, "'%s': not a regular file", display);
        goto fail_fd;
    }
    if (max_bytes && (uint64_t)sb.st_size > max_bytes) {
        st = ts_error_set(err, TS_ERR_LIMIT, "'%s': file is %llu bytes, more than the limit of %llu", display,
                          (unsigned long long)sb.st_size, (unsigned long long)max_bytes);
        goto fail_fd;
    }
    ts_pbrt_lexer *lx = lexer_alloc(display);
    if (!lx) goto fail_nomem;
    /* A small file gets a buffer its size (plus room for the NUL-free refill logic). */
    size_t want = (uint64_t)sb.st_size + 1 < CHUNK ? (size_t)sb.st_size + 1 : CHUNK;
    lx->own = malloc(want);
    if (!lx->own) {
        free(lx);
        goto fail_nomem;
    }
    lx->cap = want;
    lx->buf = lx->own;
    lx->fd = fd;
    lx->max_bytes = max_bytes;
    *out = lx;
    return TS_OK;
fail_nomem:
    st = ts_error_set(err, TS_ERR_NOMEM, "'%s': out of memory", display);
fail_fd:
    close(fd);
    return st;
}

ts_status ts_pbrt_lexer_from_memory(const char *text, size_t len, const char *display, ts_pbrt_lexer **out,
                                    ts_error *err)
{
    ts_pbrt_lexer *lx = lexer_alloc(display);
    *out = NULL;
    if (!lx) return ts_error_set(err, TS_ERR_NOMEM, "'%s': out of memory", display);
    lx->buf = text;
    lx->end = len;
    lx->at_eof = 1;
    sha256_update(&lx->sha, len, (const uint8_t *)text);
    *out = lx;
    return TS_OK;
}

void ts_pbrt_lexer_destroy(ts_pbrt_lexer *lx)
{
    if (!lx) return;
    if (lx->fd >= 0) close(lx->fd);
    free(lx->own);
    free(lx->scratch);
    free(lx);
}

uint64_t ts_pbrt_lexer_bytes(const ts_pbrt_lexer *lx) { return lx->base + lx->end; }

void ts_pbrt_lexer_digest(ts_pbrt_lexer *lx, uint8_t out[32]) { sha256_digest(&lx->sha, 32, out); }

/* Reads more bytes, keeping buf[keep, end) (moved to the front). Returns 1 if bytes were
 * added, 0 at the end of the input, -1 on error (err set). keep ≤ pos ≤ end. */
static int refill(ts_pbrt_lexer *lx, size_t keep, ts_error *err)
{
    if (lx->at_eof) return 0;
    if (keep > 0) {
        memmove(lx->own, lx->own + keep, lx->end - keep);
        lx->base += keep;
        lx->end -= keep;
        lx->pos -= keep;
    }
    if (lx->end == lx->cap) {
        if (lx->cap >= TS_PBRT_TOKEN_MAX) {
            lex_fail(lx, err, TS_ERR_LIMIT, lx->base, "token longer than %u bytes", TS_PBRT_TOKEN_MAX);
            return -1;
        }
        size_t ncap = lx->cap < CHUNK ? CHUNK : lx->cap * 2;
        char *nb = realloc(lx->own, ncap);
        if (!nb) {
            lex_fail(lx, err, TS_ERR_NOMEM, lx->base, "out of memory");
            return -1;
        }
        lx->own = nb;
        lx->buf = nb;
        lx->cap = ncap;
    }
    for (;;) {
        ssize_t r = read(lx->fd, lx->own + lx->end, lx->cap - lx->end);
        if (r < 0) {
            if (errno == EINTR) continue;
            lex_fail(lx, err, TS_ERR_IO, lx->base + lx->end, "cannot read the file (system error)");
            return -1;
        }
        if (r == 0) {
            lx->at_eof = 1;
            return 0;
        }
        lx->total_read += (uint64_t)r;
        sha256_update(&lx->sha, (size_t)r, (const uint8_t *)lx->own + lx->end);
        if (lx->max_bytes && lx->total_read > lx->max_bytes) {
            lex_fail(lx, err, TS_ERR_LIMIT, lx->base + lx->end, "file grew past the limit of %llu bytes",
                     (unsigned long long)lx->max_bytes);
            return -1;
        }
        lx->end += (size_t)r;
        return 1;
    }
}

static bool scratch_reserve(ts_pbrt_lexer *lx, size_t n)
{
    if (n <= lx->scratch_cap) return true;
    size_t ncap = lx->scratch_cap ? lx->scratch_cap : 256;
    while (ncap < n) ncap *= 2;
    char *s = realloc(lx->scratch, ncap);
    if (!s) return false;
    lx->scratch = s;
    lx->scratch_cap = ncap;
    return true;
}

static inline bool is_delim(unsigned char c)
{
    return c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\f' || c == '\v' || c == '[' || c == ']' ||
           c == '"' || c == '#';
}

static const double pow10_exact[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                       1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

bool ts_pbrt_parse_number(const char *s, size_t n, double *out)
{
    size_t i = 0;
    bool neg = false;
    if (i < n && (s[i] == '+' || s[i] == '-')) neg = s[i++] == '-';
    uint64_t mant = 0;
    int sig = 0, exp10 = 0;
    bool any = false, inexact = false;
    while (i < n && s[i] >= '0' && s[i] <= '9') {
        unsigned d = (unsigned)(s[i++] - '0');
        any = true;
        if (sig < 19) {
            if (mant || d) sig++;
            mant = mant * 10 + d;
        } else {
            exp10++;
            inexact = true;
        }
    }
    if (i < n && s[i] == '.') {
        i++;
        while (i < n && s[i] >= '0' && s[i] <= '9') {
            unsigned d = (unsigned)(s[i++] - '0');
            any = true;
            if (sig < 19) {
                if (mant || d) sig++;
                mant = mant * 10 + d;
                exp10--;
            } else {
                inexact = true;
            }
        }
    }
    if (!any) return false;
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        bool eneg = false;
        if (i < n && (s[i] == '+' || s[i] == '-')) eneg = s[i++] == '-';
        if (i >= n || s[i] < '0' || s[i] > '9') return false;
        int e = 0;
        while (i < n && s[i] >= '0' && s[i] <= '9') {
            if (e < 100000) e = e * 10 + (s[i] - '0');
            i++;
        }
        exp10 += eneg ? -e : e;
    }
    if (i != n) return false;
    if (mant == 0) {
        *out = neg ? -0.0 : 0.0;
        return true;
    }
    if (!inexact && mant <= (1ull << 53) && exp10 >= -22 && exp10 <= 22) {
        /* Clinger's fast path: both operands exact, one correctly rounded operation. */
        double v = (double)mant;
        v = exp10 < 0 ? v / pow10_exact[-exp10] : v * pow10_exact[exp10];
        *out = neg ? -v : v;
        return true;
    }
    char tmp[512];
    char *heap = NULL, *p = tmp;
    if (n + 1 > sizeof tmp) {
        heap = malloc(n + 1);
        if (!heap) return false;
        p = heap;
    }
    memcpy(p, s, n);
    p[n] = '\0';
    errno = 0;
    char *endp;
    double v = strtod(p, &endp);
    bool ok = endp == p + n && isfinite(v) && !(errno == ERANGE && fabs(v) > 1.0);
    free(heap);
    if (ok) *out = v;
    return ok;
}

/* Skips white space and comments. Returns 1 at a token, 0 at the end, -1 on error. */
static int skip_space(ts_pbrt_lexer *lx, ts_error *err)
{
    for (;;) {
        if (lx->pos == lx->end) {
            int r = refill(lx, lx->end, err);
            if (r <= 0) return r;
            continue;
        }
        unsigned char c = (unsigned char)lx->buf[lx->pos];
        if (c == '\n') {
            lx->line++;
            lx->pos++;
            lx->line_start = lx->base + lx->pos;
        } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
            lx->pos++;
        } else if (c == '#') {
            for (;;) {
                const char *nl = memchr(lx->buf + lx->pos, '\n', lx->end - lx->pos);
                if (nl) {
                    lx->pos = (size_t)(nl - lx->buf);
                    break;
                }
                lx->pos = lx->end;
                int r = refill(lx, lx->end, err);
                if (r <= 0) return r;
            }
        } else {
            return 1;
        }
    }
}

static ts_status lex_string(ts_pbrt_lexer *lx, ts_pbrt_token *tok, ts_error *err)
{
    uint64_t open_offset = lx->base + lx->pos;
    lx->pos++; /* the opening quote */
    size_t n = 0;
    for (;;) {
        if (lx->pos == lx->end) {
            int r = refill(lx, lx->end, err);
            if (r < 0) return err->status;
            if (r == 0) return lex_fail(lx, err, TS_ERR_INVALID, open_offset, "unterminated string");
            continue;
        }
        /* Copy the run of ordinary bytes at once. */
        size_t run = lx->pos;
        while (run < lx->end && lx->buf[run] != '"' && lx->buf[run] != '\\' && lx->buf[run] != '\n') run++;
        size_t k = run - lx->pos;
        if (k) {
            if (n + k + 1 > TS_PBRT_TOKEN_MAX)
                return lex_fail(lx, err, TS_ERR_LIMIT, open_offset, "string longer than %u bytes",
                                TS_PBRT_TOKEN_MAX);
            if (!scratch_reserve(lx, n + k + 1)) return lex_fail(lx, err, TS_ERR_NOMEM, open_offset, "out of memory");
            memcpy(lx->scratch + n, lx->buf + lx->pos, k);
            n += k;
            lx->pos = run;
            continue;
        }
        char c = lx->buf[lx->pos];
        if (c == '"') {
            lx->pos++;
            break;
        }
        if (c == '\n')
            return lex_fail(lx, err, TS_ERR_INVALID, open_offset,
                            "unterminated string (a string must end on the line it starts)");
        /* A backslash: the escaped byte may be in the next chunk. */
        uint64_t esc_offset = lx->base + lx->pos;
        lx->pos++;
        if (lx->pos == lx->end) {
            int r = refill(lx, lx->end, err);
            if (r < 0) return err->status;
            if (r == 0) return lex_fail(lx, err, TS_ERR_INVALID, open_offset, "unterminated string");
        }
        char e = lx->buf[lx->pos], v;
        switch (e) {
        case 'b': v = '\b'; break;
        case 'f': v = '\f'; break;
        case 'n': v = '\n'; break;
        case 'r': v = '\r'; break;
        case 't': v = '\t'; break;
        case '\\': v = '\\'; break;
        case '\'': v = '\''; break;
        case '"': v = '"'; break;
        default:
            if ((unsigned char)e >= 0x21 && (unsigned char)e < 0x7f)
                return lex_fail(lx, err, TS_ERR_INVALID, esc_offset, "unknown escape '\\%c' in a string", e);
            return lex_fail(lx, err, TS_ERR_INVALID, esc_offset, "unknown escape (byte 0x%02x) in a string",
                            (unsigned char)e);
        }
        lx->pos++;
        if (!scratch_reserve(lx, n + 2)) return lex_fail(lx, err, TS_ERR_NOMEM, open_offset, "out of memory");
        lx->scratch[n++] = v;
    }
    if (!scratch_reserve(lx, n + 1)) return lex_fail(lx, err, TS_ERR_NOMEM, open_offset, "out of memory");
    lx->scratch[n] = '\0';
    tok->kind = TS_PBRT_TOKEN_STRING;
    tok->text = lx->scratch;
    tok->len = n;
    return TS_OK;
}

/* Scans a run of non-delimiter bytes starting at pos into [*start, lx->pos). */
static ts_status scan_run(ts_pbrt_lexer *lx, size_t *start, ts_error *err)
{
    *start = lx->pos;
    for (;;) {
        while (lx->pos < lx->end && !is_delim((unsigned char)lx->buf[lx->pos])) lx->pos++;
        if (lx->pos < lx->end) return TS_OK;
        size_t off = lx->pos - *start;
        int r = refill(lx, *start, err);
        if (r < 0) return err->status;
        *start = lx->pos - off;
        if (r == 0) return TS_OK;
    }
}

ts_status ts_pbrt_lexer_next(ts_pbrt_lexer *lx, ts_pbrt_token *tok, ts_error *err)
{
    tok->text = NULL;
    tok->len = 0;
    tok->number = 0;
    int r = skip_space(lx, err);
    uint64_t offset = lx->base + lx->pos;
    uint64_t col = offset - lx->line_start + 1;
    tok->loc.file = lx->display;
    tok->loc.line = lx->line;
    tok->loc.column = col > UINT32_MAX ? UINT32_MAX : (uint32_t)col;
    if (r < 0) return err->status;
    if (r == 0) {
        tok->kind = TS_PBRT_TOKEN_EOF;
        return TS_OK;
    }
    unsigned char c = (unsigned char)lx->buf[lx->pos];
    if (c == '[' || c == ']') {
        lx->pos++;
        tok->kind = c == '[' ? TS_PBRT_TOKEN_LBRACKET : TS_PBRT_TOKEN_RBRACKET;
        return TS_OK;
    }
    if (c == '"') return lex_string(lx, tok, err);
    bool number = (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
    bool word = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
    if (!number && !word) {
        if (c >= 0x21 && c < 0x7f) return lex_fail(lx, err, TS_ERR_INVALID, offset, "unexpected character '%c'", c);
        return lex_fail(lx, err, TS_ERR_INVALID, offset, "unexpected byte 0x%02x", c);
    }
    size_t start;
    ts_status st = scan_run(lx, &start, err);
    if (st) return st;
    size_t n = lx->pos - start;
    const char *s = lx->buf + start;
    if (number) {
        if (!ts_pbrt_parse_number(s, n, &tok->number)) {
            int shown = n > 40 ? 40 : (int)n;
            return lex_fail(lx, err, TS_ERR_INVALID, offset, "bad number '%.*s%s'", shown, s, n > 40 ? "..." : "");
        }
        tok->kind = TS_PBRT_TOKEN_NUMBER;
        return TS_OK;
    }
    for (size_t i = 0; i < n; i++) {
        unsigned char w = (unsigned char)s[i];
        if (!((w >= 'A' && w <= 'Z') || (w >= 'a' && w <= 'z') || (w >= '0' && w <= '9') || w == '_')) {
            if (w >= 0x21 && w < 0x7f)
                return lex_fail(lx, err, TS_ERR_INVALID, offset + i, "unexpected character '%c'", w);
            return lex_fail(lx, err, TS_ERR_INVALID, offset + i, "unexpected byte 0x%02x", w);
        }
    }
    if (!scratch_reserve(lx, n + 1)) return lex_fail(lx, err, TS_ERR_NOMEM, offset, "out of memory");
    memcpy(lx->scratch, s, n);
    lx->scratch[n] = '\0';
    tok->kind = TS_PBRT_TOKEN_WORD;
    tok->text = lx->scratch;
    tok->len = n;
    return TS_OK;
}

void ts_pbrt_sanitize_utf8(char *s)
{
    unsigned char *p = (unsigned char *)s;
    while (*p) {
        unsigned char c = *p;
        int n = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2 : (c & 0xf8) == 0xf0 ? 3 : -1;
        bool ok = n >= 0 && !(c < 0x20 || c == 0x7f) && c != 0xc0 && c != 0xc1 && c < 0xf5;
        for (int i = 1; ok && i <= n; i++)
            if ((p[i] & 0xc0) != 0x80) ok = false;
        if (ok && n == 2 && ((c == 0xe0 && p[1] < 0xa0) || (c == 0xed && p[1] >= 0xa0))) ok = false;
        if (ok && n == 3 && ((c == 0xf0 && p[1] < 0x90) || (c == 0xf4 && p[1] >= 0x90))) ok = false;
        if (!ok) {
            *p++ = '?';
            continue;
        }
        p += n + 1;
    }
}

const char *ts_pbrt_token_describe(const ts_pbrt_token *tok, char *buf, size_t buf_len)
{
    switch (tok->kind) {
    case TS_PBRT_TOKEN_EOF: snprintf(buf, buf_len, "the end of the file"); break;
    case TS_PBRT_TOKEN_LBRACKET: snprintf(buf, buf_len, "'['"); break;
    case TS_PBRT_TOKEN_RBRACKET: snprintf(buf, buf_len, "']'"); break;
    case TS_PBRT_TOKEN_NUMBER: snprintf(buf, buf_len, "the number %.9g", tok->number); break;
    case TS_PBRT_TOKEN_STRING:
        snprintf(buf, buf_len, "the string \"%.40s%s\"", tok->text, tok->len > 40 ? "..." : "");
        break;
    case TS_PBRT_TOKEN_WORD: snprintf(buf, buf_len, "%.40s%s", tok->text, tok->len > 40 ? "..." : ""); break;
    }
    return buf;
}
