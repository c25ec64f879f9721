#!/usr/bin/env bash
# All tests, from a fresh Debian 12 / Ubuntu machine: set-up, then every
# preset's CTest suite (host with ASan/UBSan; Cortex-M4F, M3, M0 under QEMU),
# the Python tests (numpy golden reference, freshness of the committed
# vectors), and the hil/with-vcan tests. Exits non-zero on any failure.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
bash tools/setup.sh
bash tools/build-all.sh
for p in host cortex-m4f cortex-m3 cortex-m0; do
  echo "== ctest $p"
  ctest --preset "$p" -j2
done
echo "== pytest"
.venv/bin/python -m pytest -q tests/golden
echo "== hil/with-vcan"
bash hil/tests/test_with_vcan.sh
