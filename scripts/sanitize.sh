#!/usr/bin/env bash
# The sanitizer and fuzzing part of the README test command (scripts/test.sh runs it):
#   1. AddressSanitizer + UndefinedBehaviorSanitizer build (build-asan, gcc) of the core and the WHOLE native suite;
#   2. ThreadSanitizer build (build-tsan, gcc) running the cross-thread control tests (see below why not more);
#   3. a clang libFuzzer build (build-fuzz) of fuzz/fuzz_render.cpp, run for PHOTONSPLAT_FUZZ_SECONDS (30) from
#      the seed corpus fuzz/corpus.tar.gz (unpacked into a scratch directory, where new inputs go too) and the
#      reproducers in fuzz/regressions/ (see docs/robustness.md, Fuzzing).
# (One clang tree for the suite and the fuzzer would save a build, but one existing test,
# SplatClusterCone.LongLeafListsWithAccepts, fails its precondition when built with clang: see docs/robustness.md.)
# PHOTONSPLAT_SANITIZE_STEPS="asan tsan fuzz" selects steps. The Python module is not built in these trees.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
steps="${PHOTONSPLAT_SANITIZE_STEPS-asan tsan fuzz}"
fuzz_seconds="${PHOTONSPLAT_FUZZ_SECONDS:-30}"
jobs="$(nproc)"
status=0

configure() {  # build dir, targets (space-separated), then extra cmake arguments
  local dir="$1" target="$2"; shift 2
  # -O1 as the sanitizers' own documentation suggests: the instrumented -O3 build of the suite took most of this
  # script's time. Minimal debug info (line tables) is all a sanitizer report needs.
  cmake -S "$root" -B "$root/$dir" -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_CXX_FLAGS="-O1 -g1" \
    -DPHOTONSPLAT_BUILD_PYTHON=OFF "$@" >/dev/null
  cmake --build "$root/$dir" --parallel "$jobs" --target $target
}

# ThreadSanitizer cannot see the synchronisation inside Debian's libtbb.so (not instrumented): every parallel_for
# hand-off (data written before the spawn, read by a worker) is reported. Tried: a suppression file grew to six TBB
# entries and then had to match our own loop bodies, which would hide real races too. So TSan runs the tests in
# which threads meet through code it sees: the render on one TBB thread, its caller on a std::thread reading
# progress and cancelling (tests/native/test_control_threads.cpp); scripts/tsan.supp needs no entry for them.

for step in $steps; do
  case "$step" in
    asan)
      echo "== AddressSanitizer + UndefinedBehaviorSanitizer: the whole native suite (build-asan)"
      configure build-asan photonsplat_tests -DPHOTONSPLAT_SANITIZE="address;undefined"
      # One shard of the suite per core (gtest sharding; ctest runs these tests side by side too): most tests
      # run on one thread, and the instrumented suite is this script's longest step (147 s in one process on 2
      # cores, 123 s in two shards).
      pids=()
      for ((shard = 0; shard < jobs; shard++)); do
        ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1 \
        UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        GTEST_TOTAL_SHARDS="$jobs" GTEST_SHARD_INDEX="$shard" \
          "$root/build-asan/photonsplat_tests" --gtest_brief=1 &
        pids+=("$!")
      done
      for pid in "${pids[@]}"; do wait "$pid" || status=1; done
      ;;
    tsan)
      echo "== ThreadSanitizer: render and caller on different threads (build-tsan)"
      configure build-tsan photonsplat_thread_tests -DPHOTONSPLAT_SANITIZE=thread
      TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/tsan.supp" \
        "$root/build-tsan/photonsplat_thread_tests" --gtest_brief=1 || status=1
      ;;
    fuzz)
      echo "== libFuzzer: fuzz/fuzz_render.cpp for ${fuzz_seconds} s (build-fuzz, clang)"
      configure build-fuzz photonsplat_fuzz -DCMAKE_CXX_COMPILER=clang++-14 -DPHOTONSPLAT_BUILD_TESTS=OFF \
        -DPHOTONSPLAT_BUILD_FUZZER=ON -DPHOTONSPLAT_SANITIZE="address;undefined;fuzzer-no-link"
      scratch="$(mktemp -d)"
      tar -xzf "$root/fuzz/corpus.tar.gz" -C "$scratch"  # -> $scratch/corpus
      mkdir "$scratch/new"
      # The fuzzer's own exit status decides, not only the artifacts: a crash inside a library (an abort from
      # an assertion) may end the run before libFuzzer writes a crash-* file.
      fuzz_status=0
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        "$root/build-fuzz/photonsplat_fuzz" "$scratch/new" "$scratch/corpus" "$root/fuzz/regressions" \
        -max_total_time="$fuzz_seconds" -max_len=4096 -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 -artifact_prefix="$scratch/" \
        >"$scratch/fuzz.log" 2>&1 || fuzz_status=$?
      grep -E "^(#[0-9]+[[:space:]]+(INITED|DONE)|stat::|==[0-9]+==|SUMMARY|Done)" "$scratch/fuzz.log" || true
      if [ "$fuzz_status" -ne 0 ] || ls "$scratch"/crash-* "$scratch"/timeout-* "$scratch"/oom-* >/dev/null 2>&1; then
        tail -n 60 "$scratch/fuzz.log"
        echo "fuzzing failed (exit status $fuzz_status; inputs and log kept in $scratch)"; status=1
      else
        rm -rf "$scratch"
      fi
      ;;
  esac
done
exit $status
