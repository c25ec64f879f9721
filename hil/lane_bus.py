# SPDX-License-Identifier: Apache-2.0
"""A python-can bus to one lane's node during the HIL run, in the lane's control time.

While the runner commissions a lane (`python -m hil run --commission`), pmactl's procedure
(pmactl.commission) talks to that lane's node through `LaneBus` as it would through SocketCAN
to a board: its frames go out on the runner's real bus (vcan), the node's come back from it.
The node is in lockstep, so its time advances only with the rig's samples: while the
procedure waits for a frame, `recv` runs the lane's ticks (the rig's sample out, the node's
command in, one rig period) until one of the node's frames comes or the timeout's worth of
control time has passed. `clock()` is that control time [s]; PmaNode takes it for its host
heartbeats. The other lanes' nodes are not ticked meanwhile.
"""
from __future__ import annotations

import math
from collections import deque
from typing import Any, Protocol

import can


class LaneTicker(Protocol):
    """What the runner gives the bus: one lane's tick, and its real bus."""
    period_s: float

    def tick_lane(self, lane: Any) -> None: ...

    def poll_lane(self, lane: Any) -> None: ...

    def send_frame(self, msg: can.Message) -> None: ...


class LaneBus(can.BusABC):
    """python-can bus to `lane`'s node through the runner `ticker` (hil/runner.py)."""

    def __init__(self, ticker: LaneTicker, lane: Any, max_ticks_per_recv: int = 100_000, **kwargs: Any) -> None:
        self._ticker = ticker
        self._lane = lane
        self.rx: deque[can.Message] = deque()   # the node's frames, filled by the runner
        self.ticks = 0
        self.max_ticks_per_recv = max_ticks_per_recv
        self.channel_info = f"lane {lane.ctrl.label} (node {lane.node}) in lockstep"
        super().__init__(channel="lane", **kwargs)

    def clock(self) -> float:
        """Control time since commissioning began [s]."""
        return self.ticks * self._ticker.period_s

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self._ticker.send_frame(msg)

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if not self.rx:
            self._ticker.poll_lane(self._lane)      # what the node sent without a tick (replies)
        if not self.rx:
            limit = self.max_ticks_per_recv if timeout is None else math.ceil(timeout / self._ticker.period_s)
            for _ in range(min(limit, self.max_ticks_per_recv)):
                self._ticker.tick_lane(self._lane)
                self.ticks += 1
                if self.rx:
                    break
        return (self.rx.popleft() if self.rx else None), False
