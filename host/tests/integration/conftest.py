# SPDX-License-Identifier: Apache-2.0
"""pmactl against the firmware: pma-fw-host on vcan0, pmactl run as a program (the
installed console script, in a subprocess), a simulated plant behind the plant bridge.
Run through hil/with-vcan, which provides vcan0 (natively or in a User-Mode Linux guest):

    hil/with-vcan .venv/bin/python -m pytest host/tests/integration -q

Without vcan0 or without pma-fw-host the session stops with an error: never a skip.
"""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable, Iterator

import can
import pytest
from fwhost import CHANNEL, FW_HOST, PMACTL, Firmware, Run, pmactl_run
from plant import PlantRig

from pmactl import PmaNode, load_protocol

# pma-fw-host's software watchdog counts wall time (default 1 s). On a loaded machine
# (the vcan guest has one CPU) a lockstep node can wait longer than that for the CPU;
# the watchdog then re-executes it (same pid) and it comes back in FAULT WATCHDOG_RESET,
# with requests in flight unanswered. 10 s (as the HIL runner's nodes) still catches
# a hung process.
WATCHDOG_MS = 10000


def pytest_configure(config: pytest.Config) -> None:
    if not Path(f"/sys/class/net/{CHANNEL}").exists():
        raise pytest.UsageError(
            f"no CAN interface {CHANNEL}: run these tests through hil/with-vcan "
            f"(hil/with-vcan .venv/bin/python -m pytest host/tests/integration)")
    if not FW_HOST.exists():
        raise pytest.UsageError(f"{FW_HOST} not built: cmake --preset host-ubsan && cmake --build --preset host-ubsan")
    if not Path(PMACTL).exists():
        raise pytest.UsageError(f"no pmactl next to {sys.executable}: pip install -e host")


@pytest.fixture
def pmactl() -> Callable[..., Run]:
    return pmactl_run


@pytest.fixture
def bus() -> Iterator[can.BusABC]:
    b = can.Bus(interface="socketcan", channel=CHANNEL)
    yield b
    b.shutdown()


@pytest.fixture
def firmware(tmp_path: Path, bus: can.BusABC) -> Iterator[Callable[..., PmaNode]]:
    """Factory: firmware(node=0, lockstep=True, storage=True) -> PmaNode (a client on the
    test's own bus), after the node's BOOT heartbeat; --watchdog-ms WATCHDOG_MS. Stopped
    at the end of the test; each must exit with status 0 and no sanitizer report."""
    started: list[Firmware] = []
    proto = load_protocol()

    def start(node: int = 0, lockstep: bool = True, storage: bool = True) -> PmaNode:
        while bus.recv(0) is not None:       # frames of an earlier process
            pass
        args = ["--node", str(node), "--watchdog-ms", str(WATCHDOG_MS)]
        if lockstep:
            args.append("--lockstep")
        if storage:
            args += ["--storage", str(tmp_path / f"nvm-{node}.bin")]
        fw = Firmware(tmp_path, args).start()
        started.append(fw)
        client = PmaNode(bus, node, proto, timeout_s=2.0)
        client.wait_for("HEARTBEAT", lambda s: s["State"] == 0, timeout_s=10.0)   # BOOT
        client.command(0, check=False)       # answered from the main loop: start-up is over
        return client

    yield start
    for fw in started:
        fw.stop()


@pytest.fixture
def plant() -> Iterator[Callable[..., PlantRig]]:
    """Factory: plant(node=0, **options) -> a running PlantRig on vcan0."""
    rigs: list[PlantRig] = []

    def make(node: int = 0, **kw: object) -> PlantRig:
        rig = PlantRig(CHANNEL, node, **kw).start()  # type: ignore[arg-type]
        rigs.append(rig)
        rig.wait_ticks(5)
        return rig

    yield make
    for rig in rigs:
        rig.stop()
