# SPDX-License-Identifier: Apache-2.0
"""Shared by the integration tests and their conftest: where pma-fw-host and pmactl
are, running pmactl as a program, and one pma-fw-host process."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from hil.fw_process import CHANNEL, FW_HOST, FirmwareProcess  # noqa: F401 (re-exported)

PMACTL = shutil.which("pmactl", path=str(Path(sys.executable).parent)) or "pmactl"


@dataclass
class Run:
    code: int
    out: str
    err: str


# pmactl --timeout: how long pmactl waits for each reply. A node answers at once, but on a
# loaded machine (the vcan guest has one CPU) it may wait for the CPU for a second or more.
REPLY_TIMEOUT_S = 10.0


def pmactl_run(*args: str, node: int | None = 0, timeout_s: float = 300.0, cwd: Path | None = None,
               reply_timeout_s: float | None = REPLY_TIMEOUT_S) -> Run:
    """pmactl ARGS on vcan0 (socketcan, from the environment like a user's set-up);
    --node NODE unless node is None, --timeout REPLY_TIMEOUT_S unless None. timeout_s only
    guards against a hang: on a loaded machine a `pmactl plot` alone can take a minute."""
    env = dict(os.environ, CAN_INTERFACE="socketcan", CAN_CHANNEL=CHANNEL)
    opts = [] if node is None else ["--node", str(node)]
    if reply_timeout_s is not None:
        opts += ["--timeout", f"{reply_timeout_s:g}"]
    p = subprocess.run([PMACTL, *opts, *args], capture_output=True, text=True, env=env,
                       timeout=timeout_s, cwd=cwd)
    return Run(p.returncode, p.stdout, p.stderr)


Firmware = FirmwareProcess  # the name the tests use
