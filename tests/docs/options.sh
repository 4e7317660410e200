#!/bin/bash
# The documented command line against the binary's (ctest `docs_options`, issue #32.1):
# for each of render, serve, merge and convert, the options `tessera COMMAND --help` lists
# (its lines "  --option" and "  -o, --output") must be exactly those of the command's
# synopsis in README.md and in docs/design.md §5b (the code-block lines starting
# "tessera COMMAND" and their indented continuations, every synopsis of the command in the
# file together) and, for render and serve, those of design.md's option table; each
# listed option must be one the command accepts. Also: design.md §2 names every cli/*.c
# file and every Makefile target. A difference is named, and the test fails.
# usage: options.sh SOURCE_DIR TESSERA_BINARY
set -uo pipefail
src=${1:?source folder} bin=${2:?tessera binary}
fail=0
say() { echo "docs_options: $*" >&2; fail=1; }

# -o and --output are one option; written as "-o" here.
norm() { sed -E 's/^--output$/-o/' | sort -u; }

help_opts() { "$bin" "$1" --help | grep -E '^  (-[a-z], )?--[a-z]' | sed -E 's/^  (-[a-z], )?(--[a-z][a-z-]*).*/\2/' | norm; }

# Options of every synopsis of `tessera CMD` inside ``` blocks of a markdown file.
synopsis_opts() {
    awk -v cmd="$1" '
        /^```/ { code = !code; on = 0; next }
        !code { next }
        $0 ~ "^tessera +" cmd "( |$)" { on = 1; print; next }
        on && /^[ \t]/ { print; next }
        { on = 0 }' "$2" | grep -oE '(^|[[ |])(-o|--[a-z][a-z-]*)' | sed -E 's/^[[ |]//' | norm
}

# Options in the first column of design.md's table under "**`tessera CMD`**".
table_opts() {
    awk -v cmd="$1" '
        index($0, "**`tessera " cmd "`**") == 1 { on = 1; next }
        on && /^\*\*`tessera / { exit }
        on && /^## / { exit }
        on && /^\| `-/ { split($0, f, "|"); print f[2] }' "$2" | grep -oE '(-o|--[a-z][a-z-]*)' | norm
}

compare() { # what, expected (help), got (doc); empty lines are no option
    local missing extra
    missing=$(comm -23 <(echo "$2" | grep .) <(echo "$3" | grep .) | tr '\n' ' ')
    extra=$(comm -13 <(echo "$2" | grep .) <(echo "$3" | grep .) | tr '\n' ' ')
    [ -z "$missing" ] || say "$1 lacks what --help lists: $missing"
    [ -z "$extra" ] || say "$1 lists what --help does not: $extra"
}

for cmd in render serve merge convert; do
    want=$(help_opts "$cmd")
    [ -n "$want" ] || { say "tessera $cmd --help lists no options"; continue; }
    compare "README.md's synopsis of tessera $cmd" "$want" "$(synopsis_opts "$cmd" "$src/README.md")"
    compare "docs/design.md's synopsis of tessera $cmd" "$want" "$(synopsis_opts "$cmd" "$src/docs/design.md")"
    if [ "$cmd" = render ] || [ "$cmd" = serve ]; then
        compare "docs/design.md's table of tessera $cmd" "$want" "$(table_opts "$cmd" "$src/docs/design.md")"
    fi
    # Each one the command knows. Two unknown options follow it, so the command stops with a
    # usage error whatever it is (one that takes a value takes the first) and never runs.
    for o in $want; do
        timeout 10 "$bin" "$cmd" "$o" --zz-not-an-option --zz-not-an-option 2>&1 >/dev/null </dev/null |
            grep -q "unknown option '$o'" && say "tessera $cmd --help lists $o, which it refuses"
    done
done

# design.md §2: the layout names every cli/ source and every make target. (A here-string,
# not `echo | grep -q`: under pipefail grep's early exit makes echo's SIGPIPE a failure.)
layout=$(awk '/^## 2\. /{on=1; next} /^## /{on=0} on' "$src/docs/design.md")
for f in "$src"/cli/*.c; do
    b=$(basename "$f" .c)
    grep -qE "(^|[^a-z_])$b([^a-z_]|$)" <<<"$layout" || say "docs/design.md §2 does not name cli/$b.c"
done
for t in $(sed -nE 's/^\.PHONY: *//p' "$src/Makefile"); do
    grep -qE "(^|[^a-z-])$t([^a-z-]|$)" <<<"$layout" || say "docs/design.md §2 does not name the make target $t"
done
[ $fail = 0 ] && echo "docs_options: README.md and docs/design.md agree with --help of render, serve, merge and convert"
exit $fail
