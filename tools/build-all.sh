#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Configure and build every preset (host, host-ubsan: pma-fw-host only, host-q16: the controller slot
# in Q16.16, host-offline: libpma_offline.so only, host-offline-q16: the same with the controller slot in
# Q16.16, cortex-m4f, cortex-m4f-q16, cortex-m3, cortex-m0,
# stm32g474: the board image, which fails above its flash/RAM budget). The fuzz preset is
# tools/fuzz.sh's.
# Usage: tools/build-all.sh [PRESET...]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
presets=("$@")
((${#presets[@]})) || presets=(host host-ubsan host-q16 host-offline host-offline-q16 cortex-m4f cortex-m4f-q16 cortex-m3 cortex-m0
                                stm32g474)
for p in "${presets[@]}"; do
  echo "== build $p"
  cmake --preset "$p" >/dev/null
  cmake --build --preset "$p"
done
