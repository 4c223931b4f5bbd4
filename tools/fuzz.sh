#!/usr/bin/env bash
# libFuzzer on the harnesses of tests/fuzz (see tests/fuzz/README.md). Installs clang and
# libFuzzer if missing (tools/setup.sh with LAHAR_FUZZ=1) and builds them in build-fuzz/.
#   tools/fuzz.sh --ci                  every target, fixed seed and run count: fails on any finding
#   tools/fuzz.sh TARGET SECONDS [ARGS]  a long run of one target (case, link or msg); the corpus
#                                       grows in build-fuzz/corpus/TARGET, findings go to
#                                       build-fuzz/artifacts/TARGET/, ARGS go to libFuzzer
set -euo pipefail
cd "$(dirname "$0")/.."
src=$PWD
build=${LAHAR_FUZZ_BUILD_DIR:-build-fuzz}
LAHAR_FUZZ=1 LAHAR_SETUP_NO_BUILD=1 tools/setup.sh
CC=clang cmake -S . -B "$build" -DLAHAR_FUZZ=ON -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_C_FLAGS_DEBUG=-O1 -g" >/dev/null
cmake --build "$build" -j"$(nproc)" --target fuzz_case fuzz_link fuzz_msg >/dev/null

seeds() {
  case "$1" in
    case) echo "$src/cases $src/tests/bad_cases $src/tests/fuzz/corpus/case $src/tests/fuzz/regressions/case" ;;
    link|msg) echo "$src/tests/fuzz/corpus/$1 $src/tests/fuzz/regressions/$1" ;;
    *) echo "tools/fuzz.sh: unknown target '$1' (case, link, msg)" >&2; exit 2 ;;
  esac
}

export ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1
export LSAN_OPTIONS=suppressions=$src/tests/lsan.supp:print_suppressions=0
common=(-rss_limit_mb=2048 -timeout=10 -max_len=65536 -print_final_stats=1)

if [ "${1:-}" = "--ci" ]; then
  # runs per target: 20-60 s each on one busy core of the development VM (docs/bench/fuzz.md)
  declare -A runs=([case]=20000 [link]=40000 [msg]=60000)
  for t in case link msg; do
    work="$build/fuzz-ci/$t"
    rm -rf "$work" && mkdir -p "$work/new" "$work/artifacts"
    # shellcheck disable=SC2046
    "$build/bin/fuzz_$t" "${common[@]}" -seed=1 -runs="${runs[$t]}" -artifact_prefix="$work/artifacts/" \
      "$work/new" $(seeds "$t") >"$work/log" 2>&1 || { tail -n 60 "$work/log"; echo "fuzz_$t: finding, see $work" >&2; exit 1; }
    grep -E "^stat::number_of_executed_units|^#[0-9]+.*DONE" "$work/log" | tail -n 2 | sed "s/^/fuzz_$t: /"
  done
  exit 0
fi

[ $# -ge 2 ] || { sed -n '2,8p' "$0"; exit 2; }
t=$1 secs=$2
shift 2
seeds "$t" >/dev/null
mkdir -p "$build/corpus/$t" "$build/artifacts/$t"
# shellcheck disable=SC2046
exec "$build/bin/fuzz_$t" "${common[@]}" -max_total_time="$secs" -artifact_prefix="$build/artifacts/$t/" "$@" \
  "$build/corpus/$t" $(seeds "$t")
