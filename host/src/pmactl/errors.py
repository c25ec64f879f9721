# SPDX-License-Identifier: Apache-2.0
"""The protocol client's errors (pmactl.client re-exports them).
"""
from __future__ import annotations

from pmactl.protocol import Param


# ------------------------------------------------------------------ errors --
class PmaError(Exception):
    """A request the node answered with an error code (negative pma_status_t)."""

    def __init__(self, what: str, code: int, name: str) -> None:
        super().__init__(f"{what}: {name} ({code})")
        self.what = what
        self.code = code
        self.name = name


class CommandError(PmaError):
    """A COMMAND answered with an error code."""


class SetRejected(PmaError):
    """A parameter SET the node refused; `current` is the value it kept."""

    def __init__(self, what: str, code: int, name: str, param: Param | None = None,
                 requested: float | int | None = None, current: float | int | None = None) -> None:
        super().__init__(what, code, name)
        self.param = param
        self.requested = requested
        self.current = current


class NoReply(TimeoutError):
    """No reply within the timeout."""


class InterfaceError(Exception):
    """The CAN interface could not be opened (or failed)."""


class BadBusConfig(InterfaceError):
    """The bus configuration holds a value python-can cannot use: an interface it does not
    have, an empty channel, a bit rate that is not a whole number of bit/s above 0. A bad
    value, not a failing adapter: pmactl and the HIL harness exit 2 for it, 3 for an
    interface that fails to open."""


class NodeStateError(Exception):
    """The node is not in a state (or configuration) that allows the request."""


