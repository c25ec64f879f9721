#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Configure and build every preset (host, host-ubsan: pma-fw-host only, host-offline: libpma_offline.so
# only, cortex-m4f, cortex-m3, cortex-m0, stm32g474: the board image, which fails above its flash/RAM
# budget).
# Usage: tools/build-all.sh [PRESET...]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
presets=("$@")
((${#presets[@]})) || presets=(host host-ubsan host-offline cortex-m4f cortex-m3 cortex-m0 stm32g474)
for p in "${presets[@]}"; do
  echo "== build $p"
  cmake --preset "$p" >/dev/null
  cmake --build --preset "$p"
done
