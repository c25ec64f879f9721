"""Shared by the integration tests and their conftest: where pma-fw-host and pmactl
are, running pmactl as a program, and one pma-fw-host process."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
FW_HOST = Path(os.environ.get("PMA_FW_HOST", REPO / "build/host-ubsan/firmware/targets/host/pma-fw-host"))
CHANNEL = os.environ.get("PMA_CAN_CHANNEL", "vcan0")
SANITIZER_MARKERS = ("runtime error:", "AddressSanitizer", "LeakSanitizer", "UndefinedBehaviorSanitizer")
PMACTL = shutil.which("pmactl", path=str(Path(sys.executable).parent)) or "pmactl"


@dataclass
class Run:
    code: int
    out: str
    err: str


def pmactl_run(*args: str, node: int | None = 0, timeout_s: float = 60.0, cwd: Path | None = None) -> Run:
    """pmactl ARGS on vcan0 (socketcan, from the environment like a user's set-up);
    --node NODE and --timeout 2 unless node is None."""
    env = dict(os.environ, CAN_INTERFACE="socketcan", CAN_CHANNEL=CHANNEL)
    opts = [] if node is None else ["--node", str(node), "--timeout", "2"]
    p = subprocess.run([PMACTL, *opts, *args], capture_output=True, text=True, env=env,
                       timeout=timeout_s, cwd=cwd)
    return Run(p.returncode, p.stdout, p.stderr)


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

    def stop(self) -> int:
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
        assert self.proc.returncode == 0, f"pma-fw-host exit status {self.proc.returncode}:\n{out}"
        return self.proc.returncode
