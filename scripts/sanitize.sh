#!/usr/bin/env bash
# The sanitizer and fuzzing part of the README test command (scripts/test.sh runs it):
#   1. AddressSanitizer + UndefinedBehaviorSanitizer build (build-asan) of the core and the WHOLE native suite;
#   2. ThreadSanitizer build (build-tsan) running the tests of the multi-threaded stages;
#   3. a clang libFuzzer build (build-fuzz) of fuzz/fuzz_render.cpp, run for PHOTONSPLAT_FUZZ_SECONDS (60) from
#      the checked-in corpus fuzz/corpus (new inputs go to a scratch directory; see docs/robustness.md).
# PHOTONSPLAT_SANITIZE_STEPS="asan tsan fuzz" selects steps. The Python module is not built in these trees.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
steps="${PHOTONSPLAT_SANITIZE_STEPS-asan tsan fuzz}"
fuzz_seconds="${PHOTONSPLAT_FUZZ_SECONDS:-60}"
jobs="$(nproc)"
status=0

configure() {  # build dir, then extra cmake arguments
  local dir="$1"; shift
  cmake -S "$root" -B "$root/$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHOTONSPLAT_BUILD_PYTHON=OFF "$@" >/dev/null
  cmake --build "$root/$dir" --parallel "$jobs"
}

# The tests of the stages that run on several threads (view samples, direct light, photons, hierarchy, every
# splat, the whole render), each with 1, 2 and 8 threads or a cancel from another thread.
tsan_filter='HardCases.BitIdentical*:Render.ImageIsBitIdentical*:Render.CancelStops*:ClusterHierarchy.Same*:ClusterHierarchy.ConesAreTheSame*:SplatCluster.SameOutput*:SplatCluster.SmallPairCap*:SplatCluster.StopsPromptly*:SplatClusterCone.TinyPairCap*:Directional.SameBits*:GatherSplat.SameOutput*:GatherSplat.StopsPromptly*:Tiled.SameOutput*:Tiled.TinyPairCap*:Splat.BruteStopsPromptly*'

for step in $steps; do
  case "$step" in
    asan)
      echo "== AddressSanitizer + UndefinedBehaviorSanitizer: the whole native suite (build-asan)"
      configure build-asan -DPHOTONSPLAT_SANITIZE="address;undefined"
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1 \
      UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        "$root/build-asan/photonsplat_tests" --gtest_brief=1 || status=1
      ;;
    tsan)
      echo "== ThreadSanitizer: the multi-threaded stages (build-tsan)"
      configure build-tsan -DPHOTONSPLAT_SANITIZE=thread
      TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/tsan.supp" \
        "$root/build-tsan/photonsplat_tests" --gtest_brief=1 --gtest_filter="$tsan_filter" || status=1
      ;;
    fuzz)
      echo "== libFuzzer: fuzz/fuzz_render.cpp for ${fuzz_seconds} s (build-fuzz, clang)"
      configure build-fuzz -DCMAKE_CXX_COMPILER=clang++-14 -DPHOTONSPLAT_BUILD_TESTS=OFF -DPHOTONSPLAT_BUILD_FUZZER=ON \
        -DPHOTONSPLAT_SANITIZE="address;undefined;fuzzer-no-link"
      scratch="$(mktemp -d)"
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        "$root/build-fuzz/photonsplat_fuzz" "$scratch" "$root/fuzz/corpus" -max_total_time="$fuzz_seconds" \
        -max_len=4096 -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 -artifact_prefix="$scratch/" \
        2>&1 | grep -E "^(#[0-9]+ +(INITED|DONE)|stat::|==[0-9]+==|SUMMARY|Done)" || true
      if ls "$scratch"/crash-* "$scratch"/timeout-* "$scratch"/oom-* >/dev/null 2>&1; then
        echo "fuzzing found failing inputs (kept in $scratch)"; status=1
      else
        rm -rf "$scratch"
      fi
      ;;
  esac
done
exit $status
