#!/usr/bin/env bash
# check.sh — the layers of docs/design.md §2, checked on the source tree.
#
#   renderer/   includes only renderer/ headers, written from renderer/ ("core/error.h");
#               never a header of server/ or cli/
#   renderer/X/ includes headers of its own folder and of folders of a lower rank only
#               (the table FOLDER_RANK below, the same as docs/design.md §2's); a folder
#               missing from the table is a violation, so a new folder must be placed
#   renderer/X/ holds at most 20% of renderer/'s lines (.c and .h)
#   server/     includes of renderer/ only its public header "tessera.h"; no server header
#               of cli/
#   cli/        includes of renderer/ only "tessera.h"; may use server/ headers
#   and no include cycle between modules (a module is one .h/.c pair) in any layer.
# Exit 0 when all hold; else 1, with one line per violation.
#   check.sh --self-test   plants an upward include, a same-rank include, an unplaced folder
#                          and an oversized folder in scratch copies and fails unless each is
#                          reported (then checks the real tree as usual).
set -u
self_test=0
if [ "${1:-}" = --self-test ]; then self_test=1; shift; fi
root=${1:-$(cd "$(dirname "$0")/../.." && pwd)}
cd "$root" || exit 2

# The folders of renderer/ from the bottom up. A folder may include a folder of a lower rank,
# never one of its own rank or higher (docs/design.md §2).
declare -A FOLDER_RANK=(
  [core]=0
  [spectrum]=1 [sampling]=1 [image]=1 [mesh]=1
  [textures]=2
  [geometry]=3
  [camera]=4 [film]=4 [lights]=4 [materials]=4 [media]=4
  [scene]=5
  [integrators]=6
  [render]=7 [build]=7
  [json]=8
  [pbrt3]=9
  [load]=10
)
MAX_FOLDER_SHARE=20 # percent of renderer/'s lines

if [ $self_test = 1 ]; then
  script=$(cd "$(dirname "$0")" && pwd)/$(basename "$0")
  scratch=$(mktemp -d)
  trap 'rm -rf "$scratch"' EXIT
  plant() { # plant NAME SHELL-CMD EXPECTED-TEXT: copy the tree, apply, expect a report
    local dir="$scratch/$1"
    mkdir -p "$dir"
    git ls-files -z renderer server cli | tar -c --null -T - | tar -x -C "$dir"
    (cd "$dir" && git init -q && eval "$2" && git add -A >/dev/null && git -c user.name=t -c user.email=t commit -qm t)
    local out
    out=$("$script" "$dir" 2>&1) && { echo "layering self-test: planted $1 passed the check"; exit 1; }
    grep -q "$3" <<<"$out" || { echo "layering self-test: planted $1 not reported as '$3': $out"; exit 1; }
  }
  plant upward 'sed -i "1i #include \"json/scene_json.h\"" renderer/geometry/shape.c' 'upward include'
  plant same-rank 'sed -i "1i #include \"lights/light.h\"" renderer/materials/bxdf.c' 'same rank'
  plant unplaced 'mkdir renderer/newfolder && printf "int x;\n" > renderer/newfolder/a.c' 'not in the layering table'
  plant oversized 'seq 1 40000 | sed "s/.*/int v&;/" > renderer/core/big.c' 'more than'
  echo "layering self-test: 4 planted violations reported"
fi
fail=0
bad() { echo "layering: $*"; fail=1; }

# quoted includes of a file: "path:included"
includes() { grep -Ho '^#include "[^"]*"' "$@" 2>/dev/null | sed 's/:#include "/:/; s/"$//'; }

# renderer/: every quoted include resolves from renderer/ (or is the file's own folder's, written
# with its folder), and goes to the file's own folder or down the folder ranks.
while IFS=: read -r file inc; do
  [ -f "renderer/$inc" ] || { bad "$file includes \"$inc\", which is not a renderer header written from renderer/"; continue; }
  rel=${file#renderer/}
  [ "$rel" = "${rel#*/}" ] && continue # renderer/tessera.h: the top, may include any folder
  from=${rel%%/*} to=${inc%%/*}
  [ "$from" = "$to" ] && continue
  rf=${FOLDER_RANK[$from]:-} rt=${FOLDER_RANK[$to]:-}
  if [ -z "$rf" ] || [ -z "$rt" ]; then continue; fi # reported once below
  if [ "$rt" -gt "$rf" ]; then
    bad "$file includes \"$inc\": upward include (renderer/$from/ is rank $rf, renderer/$to/ rank $rt)"
  elif [ "$rt" = "$rf" ]; then
    bad "$file includes \"$inc\": renderer/$from/ and renderer/$to/ have the same rank ($rf); one must sit below the other"
  fi
done < <(includes $(git ls-files 'renderer/*.c' 'renderer/*.h'))

# renderer/'s folders: each placed in the table, none above MAX_FOLDER_SHARE of the lines.
total=$(cat $(git ls-files 'renderer/*.c' 'renderer/*.h') | wc -l)
for dir in $(git ls-files 'renderer/*/*' | cut -d/ -f2 | sort -u); do
  [ -n "${FOLDER_RANK[$dir]:-}" ] || bad "renderer/$dir/ is not in the layering table (tests/layering/check.sh FOLDER_RANK, docs/design.md §2)"
  n=$(cat $(git ls-files "renderer/$dir/*.c" "renderer/$dir/*.h") /dev/null | wc -l)
  if [ $((n * 100)) -gt $((total * MAX_FOLDER_SHARE)) ]; then
    bad "renderer/$dir/ holds $n of renderer/'s $total lines ($((n * 100 / total))%), more than $MAX_FOLDER_SHARE%: split it by role"
  fi
done

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
[ $fail = 0 ] && echo "layering: renderer folders in rank order, none over $MAX_FOLDER_SHARE% of $total lines; server and cli layers hold; no include cycle"
exit $fail
