#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# All tests, from a fresh Debian 12 / Ubuntu machine: set-up, then every
# preset's CTest suite (Unity; host with ASan/UBSan; Cortex-M4F, M3, M0 under QEMU),
# the generated code's freshness, the Python tests (numpy golden reference,
# protocol and DBC consistency, the offline runs' library layer), the HIL
# acceptance tests (the paper's experiments, on the real firmware offline) and the rig
# variants, each with the controller slot in float and in Q16.16, beside a bounded
# libFuzzer run of the CAN frame handler, the hil/with-vcan tests; then
# side by side in two vcan guests: the integration tests of pma-fw-host and pmactl over
# vcan and the HIL checks only the CAN path has | the main job's quick variant and the
# offline runs against it (to the last digit), the tuning session; then the HIL benchmark alone.
# Stages that share the two CPUs well run side by side. Exits non-zero on any failure. Prints each stage's
# duration at the end (also when a stage fails).
#
#   bash tools/run-tests.sh           # everything (the README's test command, CI)
#   bash tools/run-tests.sh --quick   # host C tests and the Python tests without CAN
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"

QUICK=0
case ${1:-} in
  "") ;;
  --quick) QUICK=1 ;;
  -h | --help)
    echo "usage: bash tools/run-tests.sh [--quick]"
    echo "  (none)   every test (the README's test command, what CI runs)"
    echo "  --quick  set-up, the host build and its C tests, the Python tests that need no CAN"
    echo "           and no slow offline runs (pytest -m 'not slow'); a few minutes"
    exit 0
    ;;
  *)
    echo "run-tests: unknown option '$1' (try --help)" >&2
    exit 2
    ;;
esac

STAGE_LINES=()
STAGE_NAME=""
STAGE_T0=$SECONDS
RUN_T0=$SECONDS
print_durations() {
  local rc=$?
  if [[ -n $STAGE_NAME ]]; then
    STAGE_LINES+=("$(printf '%6d s  %s  (FAILED, exit %d)' $((SECONDS - STAGE_T0)) "$STAGE_NAME" "$rc")")
  fi
  echo "== stage durations"
  ((${#STAGE_LINES[@]})) && printf '%s\n' "${STAGE_LINES[@]}"
  printf '%6d s  total\n' $((SECONDS - RUN_T0))
  exit "$rc"
}
trap print_durations EXIT
# stage NAME COMMAND...: runs COMMAND as one stage and records its duration. A failing stage
# ends the run, unless PMA_KEEP_GOING=1: then every stage runs and the run fails at the end.
FAILED_STAGES=0
stage() {
  STAGE_NAME=$1
  shift
  echo "== $STAGE_NAME"
  STAGE_T0=$SECONDS
  if [[ ${PMA_KEEP_GOING:-0} == 1 ]]; then
    local rc=0
    "$@" || rc=$?
    if ((rc != 0)); then
      STAGE_LINES+=("$(printf '%6d s  %s  (FAILED, exit %d)' $((SECONDS - STAGE_T0)) "$STAGE_NAME" "$rc")")
      FAILED_STAGES=$((FAILED_STAGES + 1))
      STAGE_NAME=""
      return 0
    fi
  else
    "$@"
  fi
  STAGE_LINES+=("$(printf '%6d s  %s' $((SECONDS - STAGE_T0)) "$STAGE_NAME")")
  STAGE_NAME=""
}

# side_by_side NAME_A FUNCTION_A NAME_B FUNCTION_B: two stages at once (one per CPU; a vcan stage starts
# guests of its own: a guest has one CPU, the machine two), their output in build/ci-logs/
# and printed when both have ended, a progress line every minute meanwhile. Both always run
# to their end; the run fails after them if either failed (at once unless PMA_KEEP_GOING=1).
side_by_side() {
  local names=("$1" "$3") funcs=("$2" "$4") logs="$ROOT/build/ci-logs" i
  mkdir -p "$logs"
  rm -f "$logs"/lane[01].seconds
  local pids=() t0=$SECONDS
  for i in 0 1; do
    (
      set -e # the first failing command ends the lane (not in a tested context: keeps -e)
      t=$SECONDS
      trap 'echo $((SECONDS - t)) >"$logs/lane$i.seconds"' EXIT
      "${funcs[$i]}"
    ) >"$logs/lane$i.log" 2>&1 &
    pids+=($!)
  done
  echo "== side by side: ${names[0]} | ${names[1]} (output in build/ci-logs/lane0.log, lane1.log)"
  local next=$((SECONDS + 60))
  while kill -0 "${pids[0]}" 2>/dev/null || kill -0 "${pids[1]}" 2>/dev/null; do
    sleep 2
    if ((SECONDS >= next)); then
      next=$((SECONDS + 60))
      for i in 0 1; do
        kill -0 "${pids[$i]}" 2>/dev/null &&
          printf '   %4d s  running: %s: %s\n' $((SECONDS - t0)) "${names[$i]}" \
            "$(tail -c 300 "$logs/lane$i.log" | tr '\r' '\n' | grep -v '^ *$' | tail -n 1 | cut -c1-100)"
      done
    fi
  done
  local rcs=() failed=0
  for i in 0 1; do
    local rc=0
    wait "${pids[$i]}" || rc=$?
    rcs+=("$rc")
    echo "== ${names[$i]}"
    cat "$logs/lane$i.log"
    local took
    took=$(cat "$logs/lane$i.seconds" 2>/dev/null || echo $((SECONDS - t0)))
    if ((rc != 0)); then
      STAGE_LINES+=("$(printf '%6d s  %s  (FAILED, exit %d; side by side)' "$took" "${names[$i]}" "$rc")")
      failed=$((failed + 1))
    else
      STAGE_LINES+=("$(printf '%6d s  %s  (side by side)' "$took" "${names[$i]}")")
    fi
  done
  STAGE_LINES+=("$(printf '%6d s  (both of the above, side by side)' $((SECONDS - t0)))")
  if ((failed > 0)); then
    if [[ ${PMA_KEEP_GOING:-0} == 1 ]]; then
      FAILED_STAGES=$((FAILED_STAGES + failed))
    else
      exit 1
    fi
  fi
}

# The two vcan lanes, balanced by their measured durations (build/ci-logs/lane*.seconds; here:
# integration 452 s + HIL checks 62 s | main job quick about 330 s + comparison + tuning session
# 143 s). The first guest: the firmware over vcan (its CAN interface, commands,
# parameters, storage, faults and identity, and pmactl driving it), then what only the CAN path
# of the HIL has (bus log, identity, clean stops, --board).
vcan_integration() {
  hil/with-vcan .venv/bin/python -m pytest -q tests/integration host/tests/integration/test_pmactl_fw.py
  echo "-- HIL over vcan: bus log, identity, clean stops, --board"
  hil/with-vcan .venv/bin/python -m pytest -q hil/tests/test_hil_acceptance.py
}

# The second guest, one after the other: the README main job's quick variant, the offline runs
# against that lockstep run over vcan, to the last digit (and a fault), the Q16.16 build on the
# same quick run, the tuning session of docs/tuning.md. (The lockstep benchmark runs after both
# guests, alone: beside the other guest it measured the two CPUs' sharing, 55-93 % of raw.)
vcan_hil() {
  echo "-- the README's main job, quick variant (Case 3, first 30 s, each lane commissioned, PPC vs MFAC)"
  env OUT=build/hil/ci-quick bash tools/run-demo.sh --no-setup --quick --no-progress
  echo "-- offline == over CAN (that quick run, and a fault)"
  PMA_OFFLINE_COMPARE_RUN=build/hil/ci-quick hil/with-vcan .venv/bin/python -m pytest -q \
    hil/tests/test_offline_vs_hil.py
  echo "-- the Q16.16 build (host-q16) on that quick Case 3, against the float build's run"
  PMA_FLOAT_QUICK_RUN=build/hil/ci-quick hil/with-vcan .venv/bin/python -m pytest -q -s \
    hil/tests/test_hil_fixed_point.py
  echo "-- docs/tuning.md's worked tuning session, pmactl against pma-fw-host over vcan"
  hil/with-vcan .venv/bin/python -m pytest -q host/tests/integration/test_tuning_session.py
}

# Stages of one process each that can share the two CPUs.
no_can_pytest() { .venv/bin/python -m pytest -q "${NO_CAN_TESTS[@]}"; }
pmactl_unit_tests() { .venv/bin/python -m pytest -q host/tests --ignore=host/tests/integration; }
rig_variants() { .venv/bin/python -m pytest -q hil/tests/test_rig_variants.py hil/tests/test_handover_start.py; }
# The same offline tests on the controller slot in Q16.16 (PMA_CTRL_ARITH: what the Cortex-M0 and
# M3 run): the library of the preset host-offline-q16; PMA_OFFLINE_ARITH refuses any other build.
q16_offline() {
  PMA_OFFLINE_LIB=$PWD/build/host-offline-q16/firmware/targets/offline/libpma_offline.so PMA_OFFLINE_ARITH=q16 \
    .venv/bin/python -m pytest -q "$@"
}
# Lanes balanced by their measured durations (build/ci-logs/lane*.seconds): pytest 39 s + the Q16.16
# variants 38 s | pmactl 101 s; the variants 46 s + the Q16.16 acceptance 61 s | fuzz 67 s.
no_can_pytest_and_q16_variants() {
  no_can_pytest
  echo "-- rig variants offline, the Q16.16 slot"
  q16_offline hil/tests/test_rig_variants.py
}
rig_variants_and_q16_acceptance() {
  rig_variants
  echo "-- HIL acceptance offline, the Q16.16 slot"
  q16_offline hil/tests/test_acceptance.py
}
fuzz_60s() { bash tools/fuzz.sh 60; }

NO_CAN_TESTS=(tests/golden tests/protocol tests/tools hil/tests/test_rig.py hil/tests/test_rig_profiles.py
  hil/tests/test_scenarios.py hil/tests/test_offline.py hil/tests/test_metrics_names.py
  hil/tests/test_param_rules.py hil/tests/test_summary_flags.py hil/tests/test_hysteretic_need.py hil/tests/test_commission.py
  hil/tests/test_acceptance_criteria.py)

stage "set-up (tools/setup.sh)" bash tools/setup.sh
stage "generated code and docs are current (tools/gen_protocol.py --check)" \
  .venv/bin/python tools/gen_protocol.py --check
stage "lint: ruff (every Python file, ruff.toml), mypy (pmactl and the harness, mypy.ini)" \
  bash -c '.venv/bin/ruff check . && .venv/bin/mypy'
if ((QUICK)); then
  stage "build host, host-offline (tools/build-all.sh)" bash tools/build-all.sh host host-offline
  stage "ctest host" ctest --preset host -j2
  stage "pytest (no CAN, not slow)" .venv/bin/python -m pytest -q -m "not slow" "${NO_CAN_TESTS[@]}"
  stage "pmactl unit tests (python-can virtual bus, no CAN)" \
    .venv/bin/python -m pytest -q host/tests --ignore=host/tests/integration
  exit 0
fi
stage "build every preset (tools/build-all.sh)" bash tools/build-all.sh
# the controller slot in both arithmetics: float on host and M4F, Q16.16 on host-q16,
# cortex-m4f-q16, M3 and M0 (their default)
for p in host host-q16 cortex-m4f cortex-m4f-q16 cortex-m3 cortex-m0; do
  stage "ctest $p" ctest --preset "$p" -j2
done
side_by_side "pytest (no CAN); rig variants offline on the Q16.16 slot (host-offline-q16)" no_can_pytest_and_q16_variants \
  "pmactl unit tests (python-can virtual bus, no CAN)" pmactl_unit_tests
stage "HIL acceptance offline (the paper's Cases 1-3, MFAC, PID, load change, constraint, faults; libpma_offline.so)" \
  .venv/bin/python -m pytest -q hil/tests/test_acceptance.py
# the fuzz run is bounded by time: beside the variants it costs them a little CPU, not its minute
side_by_side "rig variants offline (Case 3 on rigs the set was not tuned on: no fault, the guarantee or its flagged loss, at most MFAC's error; the hand-over during the start); HIL acceptance offline on the Q16.16 slot (host-offline-q16)" \
  rig_variants_and_q16_acceptance "fuzz (libFuzzer on the CAN frame handler, ASan + UBSan, 60 s)" fuzz_60s
# not side by side: its SIGINT test needs a shell whose background jobs may receive SIGINT (a
# background lane starts with SIGINT ignored, and then so does everything it runs)
stage "hil/with-vcan" bash hil/tests/test_with_vcan.sh
side_by_side "vcan: integration tests (pma-fw-host, python-can, can-utils, pmactl), HIL CAN-only checks" \
  vcan_integration "vcan: main job quick, offline == over CAN, tuning session" vcan_hil
stage "HIL lockstep benchmark over vcan, alone on the machine (printed, never asserted)" \
  .venv/bin/python -m hil bench --seconds 2
if ((FAILED_STAGES > 0)); then
  echo "run-tests: $FAILED_STAGES stage(s) failed (PMA_KEEP_GOING=1)"
  exit 1
fi
