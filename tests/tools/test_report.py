# SPDX-License-Identifier: Apache-2.0
"""tools/report.py: its options are checked before anything is built, run or written."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from pma_tools import report

TOOL = Path(report.__file__)


def test_bad_options_exit_2_before_anything_runs(tmp_path):
    for args in (["--presets="], ["--presets", ","], ["--presets", "cortex-m7"],
                 ["--markdown", str(tmp_path / "no_such_folder" / "r.md")], ["--markdown", str(tmp_path)],
                 ["--markdown", ""], ["--no-such-option"]):
        r = subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, timeout=60)
        assert r.returncode == 2, (args, r.stderr)
        assert "Traceback" not in r.stderr and "error:" in r.stderr, (args, r.stderr)
    assert list(tmp_path.iterdir()) == []          # nothing written
