#!/bin/bash
# docker/build-image.sh — `make image`: builds docker/Dockerfile into IMAGE (default
# tessera:latest) with podman, or docker where that is what a user has (docker/engine.sh),
# from the repository root, reusing the engine's layer cache; prints the image's size.
#   docker/build-image.sh [IMAGE [extra build options...]]
# Base images: every FROM image of the Dockerfile that is not in local storage is pulled;
# where no registry answers (or TESSERA_BASE=local), each debian:SUITE and debian:SUITE-slim
# is made here instead: a `debootstrap --variant=minbase SUITE` with the slim images' path
# excludes and apt settings, from the Debian mirror this machine's apt uses (DEBIAN_MIRROR
# overrides it), imported under that name. debootstrap needs root (sudo otherwise).
# Environment: CONTAINER_ENGINE (podman|docker), TESSERA_BASE (auto|local), DEBIAN_MIRROR.
# Exit status 0 when built, 1 on failure, 2 on usage errors.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
image=${1:-tessera:latest}
[ $# -gt 0 ] && shift
case $image in
'' | -*) echo "usage: $0 [IMAGE [extra build options...]]" >&2; exit 2 ;;
esac
base_mode=${TESSERA_BASE:-auto}
case $base_mode in auto | local) ;; *) echo "$0: TESSERA_BASE must be auto or local, got '$base_mode'" >&2; exit 2 ;; esac
# shellcheck source=docker/engine.sh
. "$here/engine.sh"
ts_engine_init || exit 1
sudo=""
[ "$(id -u)" = 0 ] || sudo="sudo"
t0=$(date +%s)
work=$(mktemp -d "${TMPDIR:-/tmp}/tessera-image-XXXXXX")
cleanup() { $sudo rm -rf "$work"; }
trap cleanup EXIT

# The URI of the first apt source of this machine that serves $1 (a suite: bookworm,
# bookworm-security, ...), from deb822 .sources files and one-line sources.list files.
apt_uri_for() {
    local suite=$1 f
    for f in /etc/apt/sources.list.d/*.sources; do
        [ -f "$f" ] || continue
        awk -v want="$suite" '
            function flush() { if (types ~ /(^| )deb( |$)/ && (" " suites " ") ~ (" " want " ") && uri != "") { print uri; found = 1; exit } }
            /^[ \t]*$/ { flush(); types = suites = uri = ""; next }
            tolower($1) == "types:" { types = $0; sub(/^[^:]*:[ \t]*/, "", types) }
            tolower($1) == "uris:" { uri = $2 }
            tolower($1) == "suites:" { suites = $0; sub(/^[^:]*:[ \t]*/, "", suites) }
            END { if (!found) flush() }' "$f"
    done
    for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
        [ -f "$f" ] || continue
        awk -v want="$suite" '$1 == "deb" { i = 2; if ($2 ~ /^\[/) { while (i <= NF && $i !~ /\]$/) i++; i++ }
                                          if ($(i + 1) == want) { print $i; exit } }' "$f"
    done
}

# The host's release name (the suite apt's mirror is known to serve).
host_suite() { (. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}"); }

# make_base SUITE NAME...: debootstraps SUITE and imports it as each NAME.
make_base() {
    local suite=$1
    shift
    local mirror=${DEBIAN_MIRROR:-}
    if [ -z "$mirror" ]; then
        mirror=$(apt_uri_for "$suite" | head -n 1)
        [ -n "$mirror" ] || mirror=$(apt_uri_for "$(host_suite)" | head -n 1)
    fi
    if [ -z "$mirror" ]; then
        echo "image: no Debian mirror in this machine's apt sources to debootstrap $suite from; set DEBIAN_MIRROR" >&2
        return 1
    fi
    command -v debootstrap >/dev/null || { echo "image: debootstrap is not installed (make image-deps)" >&2; return 1; }
    local rootfs="$work/$suite" started
    started=$(date +%s)
    echo "image: no registry has $*; making it here: debootstrap --variant=minbase $suite from $mirror"
    if ! $sudo debootstrap --variant=minbase "$suite" "$rootfs" "$mirror" >"$work/debootstrap-$suite.log" 2>&1; then
        tail -n 20 "$work/debootstrap-$suite.log" >&2
        echo "image: debootstrap of $suite failed" >&2
        return 1
    fi
    # As Debian's official images: dpkg without fsync (a container's layer is written
    # once), apt keeps no .debs, no translations, compressed lists;
    # the slim images' excludes (docs but copyrights, man pages, locales), applied to what
    # debootstrap installed too; the suite's updates and, where this machine has one, its
    # security source.
    local security
    security=$(apt_uri_for "$(host_suite)-security" | head -n 1)
    $sudo sh -e -c '
        r=$1 suite=$2 mirror=$3 security=$4
        cat >"$r/etc/dpkg/dpkg.cfg.d/docker" <<EOF
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/groff/*
path-exclude /usr/share/info/*
path-exclude /usr/share/linda/*
path-exclude /usr/share/lintian/overrides/*
path-exclude /usr/share/locale/*
path-exclude /usr/share/man/*
EOF
        find "$r/usr/share/doc" -mindepth 1 ! -type d ! -name copyright -delete
        find "$r/usr/share/doc" -mindepth 1 -type d -empty -delete
        rm -rf "$r"/usr/share/groff/* "$r"/usr/share/info/* "$r"/usr/share/linda/* \
               "$r"/usr/share/lintian/overrides/* "$r"/usr/share/locale/* "$r"/usr/share/man/*
        echo force-unsafe-io >"$r/etc/dpkg/dpkg.cfg.d/docker-apt-speedup"
        cat >"$r/etc/apt/apt.conf.d/docker-clean" <<EOF
DPkg::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
APT::Update::Post-Invoke { "rm -f /var/cache/apt/archives/*.deb /var/cache/apt/archives/partial/*.deb /var/cache/apt/*.bin || true"; };
Dir::Cache::pkgcache "";
Dir::Cache::srcpkgcache "";
EOF
        echo "Acquire::Languages \"none\";" >"$r/etc/apt/apt.conf.d/docker-no-languages"
        echo "Acquire::GzipIndexes \"true\";" >"$r/etc/apt/apt.conf.d/docker-gzip-indexes"
        {
            echo "deb $mirror $suite main"
            echo "deb $mirror $suite-updates main"
            [ -z "$security" ] || echo "deb $security $suite-security main"
        } >"$r/etc/apt/sources.list"
        rm -rf "$r"/var/cache/apt/archives/*.deb "$r"/var/lib/apt/lists/* "$r"/var/log/* "$r"/tmp/*
    ' sh "$rootfs" "$suite" "$mirror" "$security"
    local name first=""
    for name in "$@"; do
        if [ -z "$first" ]; then
            $sudo tar -C "$rootfs" --numeric-owner -c . | "${engine[@]}" import --change 'CMD ["bash"]' - "$name" >/dev/null
            first=$name
        else
            "${engine[@]}" tag "$first" "$name"
        fi
    done
    $sudo rm -rf "$rootfs"
    echo "image: made $* in $(($(date +%s) - started)) s"
}

# ---- base images ----
dockerfile="$here/Dockerfile"
stages=$(awk 'toupper($1) == "FROM" && toupper($3) == "AS" { print $4 }' "$dockerfile")
declare -A wanted=() # suite -> names still missing
for base in $(awk 'toupper($1) == "FROM" { print $2 }' "$dockerfile" | sort -u); do
    grep -qx -- "$base" <<<"$stages" && continue
    ts_engine_image_exists "$base" && continue
    if [ "$base_mode" = auto ]; then
        qualified=$base
        [[ $base == */* ]] || qualified="docker.io/library/$base"
        if timeout 300 "${engine[@]}" pull "$qualified" >"$work/pull.log" 2>&1; then
            echo "image: pulled $qualified"
            continue
        fi
        echo "image: cannot pull $qualified: $(tail -n 1 "$work/pull.log")"
    fi
    if [[ $base =~ ^debian:([a-z]+)(-slim)?$ ]]; then
        suite=${BASH_REMATCH[1]}
        wanted[$suite]="${wanted[$suite]:-} $base"
    else
        echo "image: $base is neither in local storage nor pullable, and only debian:SUITE[-slim] can be made here" >&2
        exit 1
    fi
done
# One debootstrap per suite, at the same time (each mostly waits for the mirror and dpkg).
pids=()
for suite in "${!wanted[@]}"; do
    # shellcheck disable=SC2086 # a list of names
    make_base "$suite" ${wanted[$suite]} &
    pids+=($!)
done
for pid in "${pids[@]}"; do wait "$pid" || exit 1; done

# ---- the image ----
build=("${engine[@]}" build -f "$dockerfile" -t "$image")
# podman: the Docker format keeps HEALTHCHECK (OCI has no such field); never pull a base
# (each is local by now); the web and build stages at the same time (BuildKit does that
# by itself).
[ "$engine_kind" = podman ] && build+=(--format docker --pull=never --jobs 2)
# The web stage's npm ci trusts the CA bundle node trusts here (NODE_EXTRA_CA_CERTS, else
# npm's cafile), as a build secret: not stored in any layer.
ca=${NODE_EXTRA_CA_CERTS:-}
[ -n "$ca" ] || ! command -v npm >/dev/null || ca=$(npm config get cafile 2>/dev/null || true)
[ -f "$ca" ] && build+=(--secret "id=npm_ca,src=$ca")
echo "image: ${build[*]} $* $root"
built=$(date +%s)
"${build[@]}" "$@" "$root"
size=$("${engine[@]}" image inspect --format '{{.Size}}' "$image")
mb=$(awk -v s="$size" 'BEGIN { printf "%.1f", s / 1e6 }')
echo "image: $image is $mb MB (target ≤ 150 MB); built in $(($(date +%s) - built)) s, $(($(date +%s) - t0)) s in all"
