#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Runs the Linux port's CAN test (test_hal_linux_can) where SocketCAN exists:
#   hil/with-vcan tests/hal/run_hal_linux_can.sh build/host/tests/hal/test_hal_linux_can
#
# As root (always the case inside with-vcan's User-Mode Linux guest) it gives
# the test interfaces of its own, named after this script's PID and removed
# at exit, so that nothing else on vcan0 can disturb it, and three more
# (environment variables for the test):
#   PMA_TEST_CAN_IF            the test's interface (else vcan0)
#   PMA_TEST_CAN_DOWN_IF       a vcan left down (init must refuse it)
#   PMA_TEST_CAN_FULL_DROP_IF  a vcan whose queue holds frames ("plug" qdisc) and
#                              drops beyond 10: write() fails with ENOBUFS
#   PMA_TEST_CAN_FULL_BUF_IF   the same with room for 100000 frames, so the
#                              socket's send buffer fills first: EAGAIN
# Without root, or without the sch_plug module, the test runs on vcan0 and
# skips the tests that need them (it says so).
set -euo pipefail

if [[ $# -lt 1 ]]; then
    echo "usage: $0 TEST_BINARY [ARGS...]" >&2
    exit 2
fi

created=()
cleanup() {
    local i
    for i in "${created[@]}"; do ip link del dev "$i" >/dev/null 2>&1 || true; done
}
trap cleanup EXIT

# add_vcan NAME [up]: creates a vcan interface; fails quietly.
add_vcan() {
    ip link add dev "$1" type vcan >/dev/null 2>&1 || return 1
    created+=("$1")
    if [[ ${2-} == up ]]; then ip link set up dev "$1" >/dev/null 2>&1 || return 1; fi
}

# The plug qdisc: modprobe where /lib/modules exists, else the UML guest's modules.
load_plug() {
    modprobe sch_plug >/dev/null 2>&1 && return 0
    local ko
    ko=/usr/lib/uml/modules/$(uname -r)/kernel/net/sched/sch_plug.ko
    [[ -f $ko ]] && insmod "$ko" >/dev/null 2>&1
    tc qdisc show >/dev/null 2>&1
}

# plugged NAME LIMIT_BYTES: a vcan whose frames wait in the qdisc (never released).
plugged() {
    add_vcan "$1" up && tc qdisc add dev "$1" root plug limit "$2" >/dev/null 2>&1
}

id=$$
if [[ $(id -u) -eq 0 ]] && command -v ip >/dev/null 2>&1 && add_vcan "pmac$id" up; then
    export PMA_TEST_CAN_IF=pmac$id
    if add_vcan "pmad$id"; then export PMA_TEST_CAN_DOWN_IF=pmad$id; fi
    if command -v tc >/dev/null 2>&1 && load_plug; then
        # 16 bytes per classic frame in the qdisc: 160 bytes hold 10 frames.
        if plugged "pmaq$id" 160; then export PMA_TEST_CAN_FULL_DROP_IF=pmaq$id; fi
        if plugged "pmab$id" 1600000; then export PMA_TEST_CAN_FULL_BUF_IF=pmab$id; fi
    fi
else
    export PMA_TEST_CAN_IF=vcan0
fi
"$@"
