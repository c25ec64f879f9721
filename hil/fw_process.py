# SPDX-License-Identifier: Apache-2.0
"""One pma-fw-host process: where the binary is, starting it on a SocketCAN
interface with its output in a log file, and stopping it with a check of its
exit status and of sanitizer reports. Used by the integration tests
(tests/integration, host/tests/integration), tools/bench_rt.py and the HIL
runner.

The binary is the host-ubsan build (UBSan only: ASan cannot run inside the
User-Mode Linux guest of hil/with-vcan); PMA_FW_HOST overrides it, and
PMA_CAN_CHANNEL the interface (default vcan0).
"""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FW_HOST = Path(os.environ.get("PMA_FW_HOST", REPO / "build/host-ubsan/firmware/targets/host/pma-fw-host"))
CHANNEL = os.environ.get("PMA_CAN_CHANNEL", "vcan0")
SANITIZER_MARKERS = ("runtime error:", "AddressSanitizer", "LeakSanitizer", "UndefinedBehaviorSanitizer")
BUILD_HINT = "cmake --preset host-ubsan && cmake --build --preset host-ubsan"


class FirmwareProcess:
    """pma-fw-host --can CHANNEL ARGS..., stdout and stderr in a log file in workdir."""

    def __init__(self, workdir: Path, args: list[str], channel: str = CHANNEL) -> None:
        self.log_path = workdir / f"pma-fw-host-{time.monotonic_ns()}.log"
        self.args = [str(FW_HOST), "--can", channel, *args]
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> "FirmwareProcess":
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1:abort_on_error=0",
                   UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1")
        self.log = self.log_path.open("wb")
        # its own session: a Ctrl-C in the terminal reaches the harness, which then
        # stops the node over CAN and with SIGTERM, in that order
        self.proc = subprocess.Popen(self.args, stdout=self.log, stderr=subprocess.STDOUT, env=env,
                                     start_new_session=True)
        return self

    def output(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait(self, timeout_s: float = 10.0) -> int:
        assert self.proc is not None
        return self.proc.wait(timeout_s)

    def stop(self, expect_status: int | None = 0) -> int:
        """SIGTERM (SIGKILL after 10 s), then AssertionError on a sanitizer
        report or, unless expect_status is None, another exit status."""
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
            if marker in out:
                raise AssertionError(f"sanitizer report from pma-fw-host:\n{out}")
        if expect_status is not None and self.proc.returncode != expect_status:
            raise AssertionError(f"pma-fw-host exit status {self.proc.returncode}:\n{out}")
        return self.proc.returncode
