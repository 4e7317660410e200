#!/usr/bin/env bash
# check.sh — the layers of docs/design.md §2, checked on the source tree.
#
#   renderer/   includes only renderer/ headers, written from renderer/ ("core/error.h");
#               never a header of server/ or cli/
#   server/     includes of renderer/ only its public header "tessera.h"; no server header
#               of cli/
#   cli/        includes of renderer/ only "tessera.h"; may use server/ headers
#   and no include cycle between modules (a module is one .h/.c pair) in any layer.
# Exit 0 when all hold; else 1, with one line per violation.
set -u
root=${1:-$(cd "$(dirname "$0")/../.." && pwd)}
cd "$root" || exit 2
fail=0
bad() { echo "layering: $*"; fail=1; }

# quoted includes of a file: "path:included"
includes() { grep -Ho '^#include "[^"]*"' "$@" 2>/dev/null | sed 's/:#include "/:/; s/"$//'; }

# renderer/: every quoted include resolves from renderer/ (or is the file's own folder's, written with its folder)
while IFS=: read -r file inc; do
  [ -f "renderer/$inc" ] || bad "$file includes \"$inc\", which is not a renderer header written from renderer/"
done < <(includes $(git ls-files 'renderer/*.c' 'renderer/*.h'))

for layer in server cli; do
  while IFS=: read -r file inc; do
    if [ "$inc" = tessera.h ]; then continue; fi
    if [ -f "$layer/$inc" ]; then continue; fi
    if [ "$layer" = cli ] && [ -f "server/$inc" ]; then continue; fi
    bad "$file includes \"$inc\": $layer/ may include its own headers$([ $layer = cli ] && echo ', server/ headers') and renderer/tessera.h only"
  done < <(includes $(git ls-files "$layer/*.c" "$layer/*.h"))
done

# Module graph (a.c and a.h are module a): edges "a b" for a including b's header; tsort
# reports a cycle.
graph=$(mktemp)
trap 'rm -f "$graph"' EXIT
for layer in renderer server cli; do
  while IFS=: read -r file inc; do
    from=${file%.*}
    case "$layer" in
      renderer) to=renderer/${inc%.h} ;;
      *) if [ "$inc" = tessera.h ]; then continue; fi
         if [ -f "$layer/$inc" ]; then to=$layer/${inc%.h}; else to=server/${inc%.h}; fi ;;
    esac
    [ "$from" = "$to" ] && continue
    echo "$from $to" >> "$graph"
  done < <(includes $(git ls-files "$layer/*.c" "$layer/*.h"))
done
if ! tsort "$graph" > /dev/null 2> "$graph.err"; then
  bad "include cycle between modules: $(grep -v 'input contains a loop' "$graph.err" | sed 's/^tsort: //' | tr '\n' ' ')"
fi
rm -f "$graph.err"
[ $fail = 0 ] && echo "layering: renderer, server and cli layers hold; no include cycle"
exit $fail
