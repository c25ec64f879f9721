"""Integration tests: pma-fw-host on vcan0, driven with python-can and the
project's protocol client (pmactl.PmaNode). Run them through hil/with-vcan,
which provides vcan0 (natively or in a User-Mode Linux guest):

    hil/with-vcan .venv/bin/python -m pytest tests/integration

They never skip for lack of vcan: without vcan0 the session stops with an error.
"""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Iterator

import can
import pytest

from pmactl import PmaNode, load_protocol
from pmactl.protocol import Protocol

ROOT = Path(__file__).resolve().parents[2]
FW_HOST = Path(os.environ.get("PMA_FW_HOST", ROOT / "build/host-ubsan/firmware/targets/host/pma-fw-host"))
CHANNEL = os.environ.get("PMA_CAN_CHANNEL", "vcan0")
SANITIZER_MARKERS = ("runtime error:", "AddressSanitizer", "LeakSanitizer", "UndefinedBehaviorSanitizer")


def pytest_configure(config: pytest.Config) -> None:
    if not Path(f"/sys/class/net/{CHANNEL}").exists():
        raise pytest.UsageError(
            f"no CAN interface {CHANNEL}: run these tests through hil/with-vcan "
            f"(hil/with-vcan .venv/bin/python -m pytest tests/integration)")
    if not FW_HOST.exists():
        raise pytest.UsageError(f"{FW_HOST} not built: cmake --preset host-ubsan && cmake --build --preset host-ubsan")


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


class Firmware:
    """One pma-fw-host process; stop() checks its exit status and sanitizer output."""

    def __init__(self, workdir: Path, args: list[str]) -> None:
        self.log_path = workdir / f"pma-fw-host-{time.monotonic_ns()}.log"
        self.args = [str(FW_HOST), "--can", CHANNEL, *args]
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> "Firmware":
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1:abort_on_error=0",
                   UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
        self.log = self.log_path.open("wb")
        self.proc = subprocess.Popen(self.args, stdout=self.log, stderr=subprocess.STDOUT, env=env)
        return self

    def output(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait(self, timeout_s: float = 10.0) -> int:
        assert self.proc is not None
        return self.proc.wait(timeout_s)

    def stop(self, expect_status: int | None = 0) -> int:
        assert self.proc is not None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()
        out = self.output()
        for marker in SANITIZER_MARKERS:
            assert marker not in out, f"sanitizer report from pma-fw-host:\n{out}"
        if expect_status is not None:
            assert self.proc.returncode == expect_status, f"exit status {self.proc.returncode}:\n{out}"
        return self.proc.returncode


@pytest.fixture
def firmware(tmp_path: Path, bus: can.BusABC, proto: Protocol) -> Iterator:
    """Factory: start(node=0, lockstep=True, storage=True, extra=[]) -> (Firmware, PmaNode).

    Waits for the node's first heartbeat. Every process started is stopped at
    the end of the test and must exit cleanly (status 0, no sanitizer report),
    unless the test stopped it itself."""
    started: list[Firmware] = []

    def start(node: int = 0, lockstep: bool = True, storage: Path | bool = True,
              extra: list[str] | None = None, wait_heartbeat: bool = True) -> tuple[Firmware, PmaNode]:
        args = ["--node", str(node)]
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
