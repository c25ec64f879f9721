# SPDX-License-Identifier: Apache-2.0
"""Checks of command-line options shared by `python -m hil run`, `bench` and `offline` (the bus
options are pmactl.bus_config's):
each raises OptionError with one line naming the option and what it expects, before anything
runs or is written (the commands exit with status 2)."""
from __future__ import annotations

import math
import os
from pathlib import Path


class OptionError(ValueError):
    """A bad command-line option (exit status 2)."""


def positive_number(option: str, value: float, hi: float = math.inf, unit: str = "") -> float:
    """A finite number > 0 (and <= hi)."""
    u = f" {unit}" if unit else ""
    if not (math.isfinite(value) and 0 < value <= hi):
        limit = "" if math.isinf(hi) else f", at most {hi:g}{u}"
        raise OptionError(f"{option}: expected a finite number > 0{limit}, got {value!r}")
    return value


NOISE_LIMIT_HELP = ("with --commission: commission with `pmactl commission --noise-limit K` (a quieter valve: the "
                    "sensor's noise may move the input at most K times what the reference needs, at some "
                    "accuracy; docs/commissioning.md)")


def noise_limit(value: float | None, commission: bool) -> float | None:
    """--noise-limit K of hil run / offline: a finite number > 0, and only with --commission."""
    if value is None:
        return None
    if not commission:
        raise OptionError("--noise-limit is a commissioning option: add --commission")
    return positive_number("--noise-limit", value)


def _first_existing(path: Path) -> Path:
    p = path.absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return p


def out_dir(option: str, text: str) -> Path:
    """A directory to write into: an existing directory, or one that can be made (its nearest
    existing ancestor a writable directory). Not created here."""
    path = Path(text)
    if path.exists():
        if not path.is_dir():
            raise OptionError(f"{option}: {text} exists and is not a directory")
        if not os.access(path, os.W_OK | os.X_OK):
            raise OptionError(f"{option}: {text}: not writable")
        return path
    anc = _first_existing(path)
    if not anc.is_dir():
        raise OptionError(f"{option}: {text}: cannot be made ({anc} is not a directory)")
    if not os.access(anc, os.W_OK | os.X_OK):
        raise OptionError(f"{option}: {text}: cannot be made ({anc} is not writable)")
    return path


def out_file(option: str, text: str) -> Path:
    """A file to write: not a directory, in an existing writable directory (an existing file is
    replaced)."""
    path = Path(text)
    if path.is_dir():
        raise OptionError(f"{option}: {text} is a directory (expected a file name)")
    parent = path.absolute().parent
    if not parent.is_dir():
        raise OptionError(f"{option}: {text}: no directory {parent}")
    if path.exists() and not os.access(path, os.W_OK):
        raise OptionError(f"{option}: {text}: not writable")
    if not path.exists() and not os.access(parent, os.W_OK | os.X_OK):
        raise OptionError(f"{option}: {text}: {parent} is not writable")
    return path
