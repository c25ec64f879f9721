#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job, from a fresh Debian 12 / Ubuntu machine: set-up, build of the host
# firmware (pma-fw-host) and of the simulated rig's dynamics (libpma_rig.so), then the paper's Case 3 in the HIL harness: the paper's
# controller and MFAC, each on its own pma-fw-host node in lockstep over vcan
# (through hil/with-vcan when the kernel has no SocketCAN), against identical
# simulated rigs; prints the Table 2 comparison and writes figures. Before ARM each of the
# two nodes is commissioned on its own rig over CAN (`python -m hil run --commission`, the
# procedure of `pmactl commission`): the scenario file gives only the task (w1, t_u, the
# reference, the constraints), the controllers' parameters are what commissioning derives.
#
#   bash tools/run-demo.sh            # full Case 3 (180 s of control time)
#   bash tools/run-demo.sh --quick    # the first 30 s (CI)
#   OUT=DIR bash tools/run-demo.sh    # results in DIR (default build/hil/case3)
#
#   bash tools/run-demo.sh --no-setup # skip set-up and build (the caller did both: the CI,
#                                     # whose other lane uses the same build meanwhile)
# Any other arguments go to `python -m hil run` (e.g. --controller ppc-paper; with --controller
# the lanes are the caller's choice, and so is --commission).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
setup=1
args=()
for a in "$@"; do
  if [[ $a == --no-setup ]]; then setup=0; else args+=("$a"); fi
done
if ((setup)); then
  bash tools/setup.sh
  for preset in host-ubsan host-offline; do     # pma-fw-host; libpma_rig.so (hil/rig.py)
    cmake --preset "$preset" >/dev/null
    cmake --build --preset "$preset"
  done
fi
out=${OUT:-build/hil/case3}
ctrls=(--controller ppc --controller mfac --commission)
for a in "${args[@]}"; do [[ $a == --controller ]] && ctrls=(); done
exec .venv/bin/python -m hil run case3 --out "$out" "${ctrls[@]}" "${args[@]}"
