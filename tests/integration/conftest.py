# SPDX-License-Identifier: Apache-2.0
"""Integration tests: pma-fw-host on vcan0, driven with python-can and the
project's protocol client (pmactl.PmaNode). Run them through hil/with-vcan,
which provides vcan0 (natively or in a User-Mode Linux guest):

    hil/with-vcan .venv/bin/python -m pytest tests/integration

They never skip for lack of vcan: without vcan0 the session stops with an error.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterator

import can
import pytest

from hil.fw_process import BUILD_HINT, CHANNEL, FW_HOST, FirmwareProcess
from pmactl import PmaNode, load_protocol
from pmactl.protocol import Protocol

Firmware = FirmwareProcess  # the name the tests use


# pma-fw-host's software watchdog counts wall time (default 1 s). On a loaded machine
# (the vcan guest has one CPU) a node can wait longer than that for the CPU, or for a
# storage write to reach the disk; the watchdog then re-executes it (same pid) and it
# comes back in FAULT WATCHDOG_RESET, with requests in flight (a SAVE) unanswered.
# 10 s (as the HIL runner's nodes) still catches a hung process; a test of the watchdog
# passes its own --watchdog-ms in extra (the last one counts).
WATCHDOG_MS = 10000


def pytest_configure(config: pytest.Config) -> None:
    if not Path(f"/sys/class/net/{CHANNEL}").exists():
        raise pytest.UsageError(
            f"no CAN interface {CHANNEL}: run these tests through hil/with-vcan "
            f"(hil/with-vcan .venv/bin/python -m pytest tests/integration)")
    if not FW_HOST.exists():
        raise pytest.UsageError(f"{FW_HOST} not built: {BUILD_HINT}")


@pytest.fixture(scope="session")
def proto() -> Protocol:
    return load_protocol()


@pytest.fixture
def bus() -> Iterator[can.BusABC]:
    b = can.Bus(interface="socketcan", channel=CHANNEL)
    try:
        yield b
    finally:
        b.shutdown()


@pytest.fixture
def firmware(tmp_path: Path, bus: can.BusABC, proto: Protocol) -> Iterator:
    """Factory: start(node=0, lockstep=True, storage=True, extra=[]) -> (Firmware, PmaNode).

    --watchdog-ms WATCHDOG_MS unless extra sets it. Waits for the node's first
    heartbeat. Every process started is stopped at
    the end of the test and must exit cleanly (status 0, no sanitizer report),
    unless the test stopped it itself."""
    started: list[Firmware] = []

    def start(node: int = 0, lockstep: bool = True, storage: Path | bool = True,
              extra: list[str] | None = None, wait_heartbeat: bool = True) -> tuple[Firmware, PmaNode]:
        args = ["--node", str(node), "--watchdog-ms", str(WATCHDOG_MS)]
        if lockstep:
            args.append("--lockstep")
        if storage:
            path = storage if isinstance(storage, Path) else tmp_path / "nvm.bin"
            args += ["--storage", str(path)]
        args += extra or []
        fw = Firmware(tmp_path, args).start()
        started.append(fw)
        client = PmaNode(bus, node, proto, timeout_s=2.0)
        if wait_heartbeat:
            client.heartbeat(timeout_s=10.0)
        return fw, client

    yield start
    for fw in started:
        if fw.proc is not None and fw.proc.returncode is None:
            fw.stop()
