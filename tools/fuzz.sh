#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Fuzzes the application's CAN frame handler for a bounded time (docs/testing.md, "Fuzzing").
#
#   bash tools/fuzz.sh [SECONDS]        default 60
#
# Builds tests/fuzz/fuzz_frames.c with clang-14 and libFuzzer under ASan + UBSan
# (-fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -std=c11 -Wall -Wextra -Werror
# -g -O1) with the preset fuzz into build/fuzz/ (tests/fuzz/CMakeLists.txt), writes the seed corpus and dictionary from the DBC (tests/fuzz/make_corpus.py),
# runs the fuzzer for SECONDS, prints executions per second and coverage, and exits non-zero on
# any crash, leak, sanitizer report, invariant violation or timeout. A failing input is saved
# as build/fuzz/artifacts/crash-<sha1> (reproduce: build/fuzz/tests/fuzz/fuzz_frames <file>).
#
# Environment:
#   PMA_FUZZ_DEFINES  extra definitions for the harness, e.g. PMA_FUZZ_TRACE (prints every
#                     record's state; use it to replay a crash, not to fuzz)
#   PMA_FUZZ_ARGS     extra libFuzzer options (e.g. -seed=1 or -jobs=2 -workers=2)
#   PMA_FUZZ_FRESH=1  start from the seeds only (forget build/fuzz/corpus)
#   PMA_FUZZ_NO_REPLAY=1  do not replay tests/fuzz/crashes/* (known failures) first
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"

SECONDS_TO_RUN=${1:-60}
if ! [[ $SECONDS_TO_RUN =~ ^[0-9]+$ ]] || ((SECONDS_TO_RUN < 1)); then
  echo "usage: tools/fuzz.sh [SECONDS]   (a whole number of seconds >= 1)" >&2
  exit 2
fi
say() { printf 'fuzz: %s\n' "$*"; }

if [[ ! -x .venv/bin/python ]]; then
  say ".venv missing: running tools/setup.sh"
  bash tools/setup.sh
fi
CC_FUZZ=${PMA_FUZZ_CC:-clang-14}
if ! command -v "$CC_FUZZ" >/dev/null; then
  echo "fuzz: $CC_FUZZ not found: run 'bash tools/setup.sh' (Debian clang-14 libclang-rt-14-dev)" >&2
  exit 1
fi

OUT=build/fuzz    # the preset fuzz's binary directory
FUZZER=$OUT/tests/fuzz/fuzz_frames
say "building $FUZZER with $CC_FUZZ (preset fuzz)"
# a build/fuzz configured from tests/fuzz alone (before the preset) cannot be reused
if [[ -f $OUT/CMakeCache.txt ]] && ! grep -qx "CMAKE_HOME_DIRECTORY:INTERNAL=$ROOT" "$OUT/CMakeCache.txt"; then
  rm -rf "$OUT"
fi
mkdir -p "$OUT"
cmake --preset fuzz -DCMAKE_C_COMPILER="$CC_FUZZ" -DPMA_FUZZ_DEFINES="${PMA_FUZZ_DEFINES:-}" \
  >"$OUT/configure.log" 2>&1 || { cat "$OUT/configure.log" >&2; exit 1; }
cmake --build --preset fuzz

SEEDS=$OUT/seed
CORPUS=$OUT/corpus
ARTIFACTS=$OUT/artifacts
[[ ${PMA_FUZZ_FRESH:-0} == 1 ]] && rm -rf "$CORPUS"
rm -rf "$SEEDS"
mkdir -p "$CORPUS" "$ARTIFACTS"
.venv/bin/python tests/fuzz/make_corpus.py "$SEEDS" --dict "$OUT/frames.dict"

# Known failing inputs (tests/fuzz/crashes/README.md) first: each must pass once its bug is
# fixed, and then stays as a regression input.
if [[ ${PMA_FUZZ_NO_REPLAY:-0} != 1 ]]; then
  replay_failed=0
  for f in tests/fuzz/crashes/*; do
    [[ -f $f && $f != *.md ]] || continue
    if "$FUZZER" "$f" >"$OUT/replay.log" 2>&1; then
      say "replay $f: passes"
    else
      replay_failed=1
      echo "fuzz: replay $f FAILS:" >&2
      grep -E 'INVARIANT|at record|ERROR: |runtime error' "$OUT/replay.log" | head -n 3 >&2 || true
    fi
  done
  if ((replay_failed)); then
    echo "fuzz: FAILED: inputs of tests/fuzz/crashes/ fail (an open bug or a regression; README.md there)" >&2
    exit 1
  fi
fi

LOG=$OUT/fuzz.log
say "fuzzing for ${SECONDS_TO_RUN} s (log: $LOG)"
# -timeout: one input running longer than 10 s is a hang (a normal one takes milliseconds);
# -rss_limit_mb: the harness allocates nothing, so growth means a leak in the making;
# -max_len: 1 platform byte + 400 records of 12 bytes (the harness ignores the rest).
# Run from $OUT: with -jobs libFuzzer writes its fuzz-<n>.log files into the current directory.
# shellcheck disable=SC2086
set +e
(cd "$OUT" && "$ROOT/$FUZZER" "$ROOT/$CORPUS" "$ROOT/$SEEDS" \
  -dict="$ROOT/$OUT/frames.dict" \
  -max_total_time="$SECONDS_TO_RUN" \
  -timeout=10 -rss_limit_mb=2048 -max_len=4801 \
  -artifact_prefix="$ROOT/$ARTIFACTS/" \
  -print_final_stats=1 \
  ${PMA_FUZZ_ARGS:-}) >"$LOG" 2>&1
status=$?
set -e

# the last status line (e.g. "#123456 DONE cov: 1234 ft: 5678 corp: 90/12Kb ...") and the stats
last=$(grep -E '^#[0-9]+' "$LOG" | tail -n 1 || true)
runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$LOG" | tail -n 1)
[[ -n $runs ]] || runs=$(sed -n 's/^#\([0-9]*\).*/\1/p' <<<"$last") # (a crash prints no stats)
eps=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$LOG" | tail -n 1)
cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
corp=$(sed -n 's/.* corp: \([^ ]*\).*/\1/p' <<<"$last")
say "runs ${runs:-?}, ${eps:-?} exec/s, cov: ${cov:-?}, ft: ${ft:-?}, corpus ${corp:-?} (inputs/size)"

if ((status != 0)); then
  echo "fuzz: FAILED (libFuzzer exit status $status); the report:" >&2
  grep -E 'INVARIANT|ERROR: |runtime error|SUMMARY|Test unit written|at record|^    #[0-9]+ ' "$LOG" |
    head -n 40 >&2 || true
  echo "fuzz: replay with: $FUZZER $ARTIFACTS/<file>  (full log: $LOG)" >&2
  exit 1
fi
say "passed: no crash, leak, sanitizer report or invariant violation"
