#!/usr/bin/env bash
# Long fuzz run of multicue's readers (not part of CI; docs/fuzzing.md).
#
#   scripts/fuzz.sh [--seconds 600] [--rss-mb 2048] [TARGET ...]
#
# Configures and builds build-fuzz/ (clang-14, libFuzzer, ASan + UBSan) and the seed corpora
# (scripts/fuzz_seeds.py, from the CLI of build/), then runs each target (all of fuzz/targets/ by
# default) one after the other for --seconds, single process. The corpus grows in
# build-fuzz/corpus/TARGET/ from run to run; crashes, hangs (> 2 s), leaks and out-of-memory
# inputs land in build-fuzz/artifacts/TARGET/; each run's log is build-fuzz/logs/TARGET.log and
# build-fuzz/fuzz-summary.md tabulates executions per second, corpus size and coverage.
# Exit status 1 when some target left an artifact.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=600
rss_mb=2048
targets=()
while [[ $# -gt 0 ]]; do
    case "$1" in
        --seconds) seconds="$2"; shift 2 ;;
        --rss-mb) rss_mb="$2"; shift 2 ;;
        -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
        -*) echo "fuzz.sh: unknown option '$1'" >&2; exit 2 ;;
        *) targets+=("$1"); shift ;;
    esac
done
if [[ ${#targets[@]} -eq 0 ]]; then
    mapfile -t targets < <(sed -n 's/^multicue_fuzz_target(\([a-z0-9_]*\).*/\1/p' fuzz/CMakeLists.txt)
fi

build=build-fuzz
if [[ ! -f $build/build.ninja ]]; then
    cmake -S . -B $build -G Ninja -DCMAKE_CXX_COMPILER=clang++-14 \
        -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
        -DMULTICUE_BUILD_FUZZERS=ON -DMULTICUE_BUILD_TESTS=OFF -DMULTICUE_BUILD_BENCH=OFF \
        -DMULTICUE_BUILD_EVAL=OFF -DMULTICUE_BUILD_EXAMPLES=OFF -DMULTICUE_BUILD_PYTHON=OFF \
        -DMULTICUE_INSTALL=OFF -DMULTICUE_WERROR=OFF -DMULTICUE_REPORT_VIEWER=OFF \
        -DMULTICUE_PCL_TESTS=OFF -DMULTICUE_OPEN3D_TESTS=OFF
fi
cmake --build $build -j2 --target "${targets[@]/#/fuzz_}"

if [[ ! -d $build/seeds ]]; then
    if [[ ! -x build/multicue ]]; then
        cmake -S . -B build -G Ninja && cmake --build build -j2 --target multicue
    fi
    python3 scripts/fuzz_seeds.py --cli build/multicue --out $build/seeds
fi

export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=0:${ASAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$PWD/scripts/sanitizers/lsan.supp:${LSAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
summary=$build/fuzz-summary.md
{
    echo "| target | seconds | executions | exec/s | corpus (files) | corpus (bytes) | cov (edges) | ft (features) | peak RSS [MB] | artifacts |"
    echo "|---|---|---|---|---|---|---|---|---|---|"
} > "$summary"
failed=0
for t in "${targets[@]}"; do
    corpus=$build/corpus/$t
    artifacts=$build/artifacts/$t
    mkdir -p "$corpus" "$artifacts" $build/logs
    dict=()
    if [[ -f fuzz/dict/$t.dict ]]; then dict=(-dict=fuzz/dict/$t.dict); fi
    seeds=()
    if [[ -d $build/seeds/$t ]]; then seeds+=("$build/seeds/$t"); fi
    if [[ -d fuzz/regression/$t ]]; then seeds+=("fuzz/regression/$t"); fi
    echo "fuzz.sh: $t for ${seconds}s"
    set +e
    "$build/fuzz/fuzz_$t" "$corpus" "${seeds[@]}" "${dict[@]}" \
        -max_total_time="$seconds" -timeout=2 -rss_limit_mb="$rss_mb" -max_len=262144 \
        -print_final_stats=1 -artifact_prefix="$artifacts/" > $build/logs/$t.log 2>&1
    rc=$?
    set -e
    log=$build/logs/$t.log
    done_line=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
    stat() { sed -n "s/^stat::$1: *//p" "$log" | tail -1; }
    cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<< "$done_line")
    ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<< "$done_line")
    files=$(find "$corpus" -type f | wc -l)
    bytes=$(du -sb "$corpus" | cut -f1)
    found=$(find "$artifacts" -type f | wc -l)
    echo "| $t | $seconds | $(stat number_of_executed_units) | $(stat average_exec_per_sec) | $files | $bytes | $cov | $ft | $(stat peak_rss_mb) | $found |" >> "$summary"
    if [[ $rc -ne 0 || $found -ne 0 ]]; then
        failed=1
        echo "fuzz.sh: $t stopped with status $rc; see $log and $artifacts/" >&2
    fi
done
cat "$summary"
exit $failed
