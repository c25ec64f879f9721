#!/usr/bin/env bash
# The main job, from a fresh Debian 12 / Ubuntu machine: set-up, build of every
# preset, then the control library's golden-vector and cost report (accuracy
# against the numpy double reference; instructions per control step on
# emulated Cortex-M4F, M3, M0; code size). Once the HIL harness exists this
# becomes the HIL demo of the paper's experiment.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
bash tools/setup.sh
bash tools/build-all.sh
.venv/bin/python tools/report.py "$@"
