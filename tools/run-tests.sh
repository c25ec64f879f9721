#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# All tests, from a fresh Debian 12 / Ubuntu machine: set-up, then every
# preset's CTest suite (Unity; host with ASan/UBSan; Cortex-M4F, M3, M0 under QEMU),
# the generated code's freshness, the Python tests (numpy golden reference,
# protocol and DBC consistency, the offline runs' library layer), the
# hil/with-vcan tests, the integration tests of pma-fw-host over vcan, the HIL
# acceptance tests (the paper's experiments over vcan), an offline run against
# the same run over vcan, the main job's quick variant, the HIL benchmark, and a
# bounded libFuzzer run of the CAN frame handler. Exits non-zero on any failure.
# Prints each stage's duration at the end (also when a stage fails).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"

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

stage "set-up (tools/setup.sh)" bash tools/setup.sh
stage "generated code and docs are current (tools/gen_protocol.py --check)" \
  .venv/bin/python tools/gen_protocol.py --check
stage "build every preset (tools/build-all.sh)" bash tools/build-all.sh
for p in host cortex-m4f cortex-m3 cortex-m0; do
  stage "ctest $p" ctest --preset "$p" -j2
done
stage "pytest (no CAN)" .venv/bin/python -m pytest -q tests/golden tests/protocol \
  hil/tests/test_rig.py hil/tests/test_rig_profiles.py hil/tests/test_scenarios.py \
  hil/tests/test_offline.py hil/tests/test_metrics_names.py hil/tests/test_param_rules.py
stage "hil/with-vcan" bash hil/tests/test_with_vcan.sh
stage "pmactl unit tests (python-can virtual bus, no CAN)" \
  .venv/bin/python -m pytest -q host/tests --ignore=host/tests/integration
stage "integration tests over vcan (pma-fw-host, python-can, can-utils, pmactl)" \
  hil/with-vcan .venv/bin/python -m pytest -q tests/integration host/tests/integration
stage "HIL acceptance over vcan (the paper's Cases 1-3, MFAC, PID, load change, constraint, faults)" \
  hil/with-vcan .venv/bin/python -m pytest -q hil/tests/test_hil_acceptance.py
stage "the README's main job, quick variant (Case 3, first 30 s, PPC vs MFAC)" \
  env OUT=build/hil/ci-quick bash tools/run-demo.sh --quick --no-progress
stage "offline (libpma_offline.so) vs that lockstep run over vcan: identical figures and signals" \
  env PMA_OFFLINE_COMPARE_RUN=build/hil/ci-quick .venv/bin/python -m pytest -q \
  hil/tests/test_offline_vs_hil.py
stage "HIL lockstep benchmark (printed, never asserted)" \
  .venv/bin/python -m hil bench --seconds 5
stage "fuzz (libFuzzer on the CAN frame handler, ASan + UBSan, 60 s)" bash tools/fuzz.sh 60
if ((FAILED_STAGES > 0)); then
  echo "run-tests: $FAILED_STAGES stage(s) failed (PMA_KEEP_GOING=1)"
  exit 1
fi
