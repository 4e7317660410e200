# docker/engine.sh — sourced by docker/build-image.sh and tests/container/run.sh (bash):
# which container engine to use and how, in the array `engine`:
#   CONTAINER_ENGINE=podman|docker chooses; by default podman where it is installed, else docker.
# podman gets `--runtime runc` where runc is installed (crun, podman's first choice, fails on
# some hosts' cgroups) and, on a host not booted by systemd, `--cgroup-manager cgroupfs
# --events-backend file` (podman's defaults there need systemd and journald).
# engine_kind is "podman" or "docker".

ts_engine_init() {
    engine_kind=${CONTAINER_ENGINE:-}
    if [ -z "$engine_kind" ]; then
        if command -v podman >/dev/null; then
            engine_kind=podman
        elif command -v docker >/dev/null; then
            engine_kind=docker
        else
            echo "no container engine: install podman (make image-deps) or docker" >&2
            return 1
        fi
    fi
    case $engine_kind in
    podman)
        command -v podman >/dev/null || { echo "CONTAINER_ENGINE=podman, but podman is not installed (make image-deps)" >&2; return 1; }
        engine=(podman)
        command -v runc >/dev/null && engine+=(--runtime runc)
        [ -d /run/systemd/system ] || engine+=(--cgroup-manager cgroupfs --events-backend file)
        ;;
    docker)
        command -v docker >/dev/null || { echo "CONTAINER_ENGINE=docker, but docker is not installed" >&2; return 1; }
        engine=(docker)
        ;;
    *)
        echo "CONTAINER_ENGINE must be podman or docker, got '$engine_kind'" >&2
        return 1
        ;;
    esac
}

# ts_engine_image_exists NAME: whether NAME is in the engine's local storage.
ts_engine_image_exists() {
    if [ "$engine_kind" = podman ]; then
        "${engine[@]}" image exists "$1"
    else
        "${engine[@]}" image inspect "$1" >/dev/null 2>&1
    fi
}
