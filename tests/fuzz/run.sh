#!/bin/sh
# run.sh — runs libFuzzer harnesses (tests/fuzz/README.md).
#   tests/fuzz/run.sh [--keep] BUILD_DIR SECONDS|runs:N HARNESS...
# Each harness BUILD_DIR/fuzz_<h> runs for SECONDS (or, with runs:N, exactly N inputs from
# the fixed seed 1, so the run is deterministic: what `make test` uses, so CI fails on a
# regression but never by the luck of a new mutation) over its seed corpus
# tests/fuzz/corpus/<h> (with the dictionary tests/fuzz/<h>.dict where there is one, and
# the seeds tests/fuzz/seeds_<h>.sh writes, where there is one). New inputs go to a
# scratch folder (removed afterwards) or, with
# --keep, to BUILD_DIR/fuzz-corpus/<h>, kept between runs; the seed corpus is never
# written. Crash inputs are saved in BUILD_DIR/fuzz-artifacts/<h>/. Prints executions
# and executions/s per harness and in total; exits 1 if any harness crashed, leaked, hit
# a timeout or is missing (a missing binary is a failure, never a skip).
set -u
keep=0
if [ "${1:-}" = "--keep" ]; then keep=1; shift; fi
if [ $# -lt 3 ]; then echo "usage: $0 [--keep] BUILD_DIR SECONDS HARNESS..." >&2; exit 2; fi
build=$1 seconds=$2; shift 2
src=$(cd "$(dirname "$0")/../.." && pwd)
status=0 total=0
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}"
for h in "$@"; do
  bin=$build/fuzz_$h
  if [ ! -x "$bin" ]; then
    echo "fuzz $h: $bin is missing (make fuzz-build)" >&2
    status=1
    continue
  fi
  art=$build/fuzz-artifacts/$h
  mkdir -p "$art"
  if [ $keep = 1 ]; then
    work=$build/fuzz-corpus/$h
    mkdir -p "$work"
  else
    work=$(mktemp -d "${TMPDIR:-/tmp}/ts_fuzz_corpus_XXXXXX")
  fi
  log=$(mktemp "${TMPDIR:-/tmp}/ts_fuzz_log_XXXXXX")
  # -timeout: one input taking this long is a hang; -rss_limit_mb: libFuzzer's default.
  dict=
  [ -f "$src/tests/fuzz/$h.dict" ] && dict="-dict=$src/tests/fuzz/$h.dict"
  case $seconds in
    runs:*) budget="-runs=${seconds#runs:} -seed=1" ;;
    *) budget="-max_total_time=$seconds" ;;
  esac
  # Binary seeds are not committed: tests/fuzz/seeds_<h>.sh writes them into a scratch
  # folder, a second read-only seed corpus.
  gen=
  if [ -f "$src/tests/fuzz/seeds_$h.sh" ]; then
    gen=$(mktemp -d "${TMPDIR:-/tmp}/ts_fuzz_seeds_XXXXXX")
    if ! sh "$src/tests/fuzz/seeds_$h.sh" "$gen"; then
      echo "fuzz $h: FAILED: tests/fuzz/seeds_$h.sh could not write its seeds" >&2
      status=1
      rm -rf "$gen" "$log"
      [ $keep = 1 ] || rm -rf "$work"
      continue
    fi
  fi
  # shellcheck disable=SC2086 # $budget, $dict and $gen are lists of options / folders
  "$bin" $budget -timeout=25 -rss_limit_mb=2048 -print_final_stats=1 $dict \
         -artifact_prefix="$art/" "$work" "$src/tests/fuzz/corpus/$h" $gen >"$log" 2>&1
  rc=$?
  [ -z "$gen" ] || rm -rf "$gen"
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1)
  if [ $rc -ne 0 ] || [ -z "$runs" ]; then
    echo "fuzz $h: FAILED (exit $rc); log follows, crash input in $art/" >&2
    tail -n 80 "$log" >&2
    status=1
  else
    echo "fuzz $h: ${runs} executions, ${rate} exec/s, ${cov:-cov: ?} (budget ${seconds})"
    total=$((total + runs))
  fi
  rm -f "$log"
  [ $keep = 1 ] || rm -rf "$work"
done
echo "fuzz: ${total} executions in total"
exit $status
