#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# One-time (idempotent) set-up of a Debian 12 / Ubuntu machine for building and
# testing the PMA firmware: Debian packages, the pinned third-party C sources
# (Unity, ST cmsis_device_g4, Arm CMSIS_6: tools/fetch-deps.sh, into .deps/;
# PMA_DEPS_MIRROR for machines without GitHub), and a Python virtual environment
# (.venv/) with the packages of tools/requirements.txt. Run as root (or with sudo
# available).
# Called by tools/run-demo.sh and tools/run-tests.sh; safe to run again.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
say() { printf 'setup: %s\n' "$*"; }

PACKAGES=(
  cmake ninja-build gcc make pkg-config git         # host build; git for tools/fetch-deps.sh
  gcc-arm-none-eabi libnewlib-arm-none-eabi          # Cortex-M builds
  qemu-system-arm                                    # Cortex-M tests and benchmarks
  python3 python3-venv python3-pip                   # golden reference, reports
  user-mode-linux kmod iproute2 can-utils            # hil/with-vcan (vcan where the kernel has none)
  clang-14 libclang-rt-14-dev                        # libFuzzer target of the CAN frame handler
  xvfb python3-tk                                    # pmactl scope's window test (Xvfb, TkAgg)
)

SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "setup: run as root or install sudo" >&2; exit 1; }
  SUDO="sudo"
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  say "installing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  say "Debian packages present"
fi

bash "$ROOT/tools/fetch-deps.sh"

VENV=${PMA_VENV:-$ROOT/.venv}
if [[ ! -x $VENV/bin/python ]]; then
  say "creating Python virtual environment $VENV"
  python3 -m venv "$VENV"
fi
if ! "$VENV/bin/python" -c "import numpy, pytest, matplotlib, can, cantools, pmactl, hil, pma_golden, pma_tools" \
       2>/dev/null ||
   [[ $ROOT/tools/requirements.txt -nt $VENV/.pma-requirements-stamp ]] ||
   [[ $ROOT/host/pyproject.toml -nt $VENV/.pma-requirements-stamp ]] ||
   [[ $ROOT/pyproject.toml -nt $VENV/.pma-requirements-stamp ]]; then
  say "installing Python packages (tools/requirements.txt)"
  "$VENV/bin/pip" install -q --upgrade pip
  "$VENV/bin/pip" install -q -r "$ROOT/tools/requirements.txt"
  "$VENV/bin/pip" install -q -e "$ROOT/host"   # the project's protocol client (pmactl)
  # the development packages (hil, pma_golden, pma_tools: pyproject.toml), after pmactl
  "$VENV/bin/pip" install -q -e "$ROOT"
  touch "$VENV/.pma-requirements-stamp"
else
  say "Python packages present"
fi
