/* pbrt_lexer.h — the tokens of a pbrt-v3 scene file, read as a stream.
 *
 * Design note: a pbrt scene can be a 100 MB text of numbers, so the file is never held
 * whole: the lexer reads it in 1 MiB chunks into one buffer and only a token that
 * straddles a chunk boundary is moved (the buffer grows only for a single token longer
 * than a chunk, up to TS_PBRT_TOKEN_MAX). Tokens (pbrt-v3's file format): `#` comments to
 * the end of the line; quoted strings "…" on one line with the escapes \b \f \n \r \t \\
 * \' \"; numbers ([+-] digits [. digits] [e [+-] digits], ".5" and "5." too), converted
 * exactly (a fast path for up to 19 significant digits and |exponent| ≤ 22, strtod
 * otherwise); `[` and `]`; and bare words (directives, and the unquoted true/false that
 * bool parameters accept). Anything else — a stray character, "1.2.3", "12abc", a number
 * beyond double range, a string without its closing quote — is an error that names
 * file:line:column. Every token carries its own position (1-based line and byte column).
 *
 * Thread-safety: a lexer is used by one thread; distinct lexers share nothing. */
#ifndef TS_PBRT_LEXER_H
#define TS_PBRT_LEXER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/error.h"

/* Longest single token (a string or a number) the lexer accepts. */
#define TS_PBRT_TOKEN_MAX (16u << 20)

typedef enum ts_pbrt_token_kind {
    TS_PBRT_TOKEN_EOF = 0,
    TS_PBRT_TOKEN_WORD,   /* Shape, WorldBegin, true, All, … */
    TS_PBRT_TOKEN_STRING, /* "…": text is the content, escapes decoded */
    TS_PBRT_TOKEN_NUMBER, /* number holds the value */
    TS_PBRT_TOKEN_LBRACKET,
    TS_PBRT_TOKEN_RBRACKET,
} ts_pbrt_token_kind;

/* A position in a scene file: file is the name as the scene wrote it (or as the caller
 * named the top-level file); line and column count from 1, the column in bytes. */
typedef struct ts_pbrt_loc {
    const char *file;
    uint32_t line, column;
} ts_pbrt_loc;

typedef struct ts_pbrt_token {
    ts_pbrt_token_kind kind;
    ts_pbrt_loc loc;
    const char *text; /* WORD, STRING: NUL-terminated (len bytes), owned by the lexer and
                         valid until its next call; NULL for the other kinds */
    size_t len;
    double number; /* NUMBER */
} ts_pbrt_token;

typedef struct ts_pbrt_lexer ts_pbrt_lexer;

/* Opens the file at path for reading, with O_NONBLOCK, refused unless it is a regular
 * file. resolved: path was resolved and confined by the caller (scene_path.h), so it is
 * opened with O_NOFOLLOW too; a file the user named (false) may be a symbolic link.
 * display names the file in token positions and messages and must outlive the lexer.
 * max_bytes (0 = none) bounds the file's size (TS_ERR_LIMIT). Errors say
 * "'<display>': <problem>". */
ts_status ts_pbrt_lexer_open(const char *path, bool resolved, const char *display, uint64_t max_bytes,
                             ts_pbrt_lexer **out, ts_error *err);

/* A lexer over text[0, len) (not copied: it must outlive the lexer; NUL bytes in it are
 * errors like any other stray byte). */
ts_status ts_pbrt_lexer_from_memory(const char *text, size_t len, const char *display, ts_pbrt_lexer **out,
                                    ts_error *err);

/* The next token (TS_PBRT_TOKEN_EOF at the end, again on every later call). On error the
 * sentence is "<file>:<line>:<column>: <problem>", e.g. "a.pbrt:3:14: unterminated string". */
ts_status ts_pbrt_lexer_next(ts_pbrt_lexer *lx, ts_pbrt_token *tok, ts_error *err);

void ts_pbrt_lexer_destroy(ts_pbrt_lexer *lx);

/* Bytes of the input read so far (all of it once the lexer returned EOF). */
uint64_t ts_pbrt_lexer_bytes(const ts_pbrt_lexer *lx);

/* SHA-256 of the bytes read so far (a file lexer: as read; a memory one: its whole text);
 * call once, when done reading. */
void ts_pbrt_lexer_digest(ts_pbrt_lexer *lx, uint8_t out[32]);

/* Writes a short description of tok for messages into buf ("end of file", "'['",
 * "number 3.5", "string \"abc\"", "WorldBegin") and returns buf. */
const char *ts_pbrt_token_describe(const ts_pbrt_token *tok, char *buf, size_t buf_len);

/* Replaces, in place, every byte of s that is not part of valid UTF-8 or is a control
 * character by '?', so a message quoting scene text is always printable UTF-8. */
void ts_pbrt_sanitize_utf8(char *s);

/* Parses the whole of s[0, n) as a pbrt number (the grammar above), false if it is not
 * one or is beyond double range. Exposed for the tests and for .spd files. */
bool ts_pbrt_parse_number(const char *s, size_t n, double *out);

#endif
