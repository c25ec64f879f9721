# SPDX-License-Identifier: Apache-2.0
"""A python-can bus whose other end is the real firmware on the simulated rig, without CAN.

`OfflineBus` is a `can.BusABC`: pmactl's client (`pmactl.client.PmaNode`) and anything else
written against python-can talk to it as to SocketCAN. Behind it run one node of the firmware
(libpma_offline.so: the application, the control library, the fake HAL port; hil/offline.py)
and one rig (hil/rig.py), in lockstep exactly as the HIL runner steps pma-fw-host over vcan:
each control tick the rig's sensor counts go to the node as a PLANT_SENSOR frame, the node's
PLANT_ACTUATOR command goes to the rig's regulator, and the rig advances one period.

Time is control time. The node and the rig advance only while the host waits for a frame
(`recv` with a timeout steps ticks until a frame comes or the timeout's worth of control time
has passed), so a procedure that waits for telemetry runs as fast as the machine can step it,
and the same procedure gives the same figures on every run (the rig's noise is seeded).
`clock()` is that control time in seconds: `PmaNode` takes it for its host heartbeats when a
bus has one, so a RUNNING node gets its HOST_HEARTBEAT every 100 ms of control time.

    bus = OfflineBus(RigParams(), node_id=1)
    node = PmaNode(bus, node=1)
    node.get("act.p0_kpa")

The PLANT_SENSOR / PLANT_ACTUATOR exchange stays inside (the rig is the bus's); every other
frame the node sends reaches the host, every frame the host sends reaches the node.
One node per process (the fake port is static), as for hil/offline.py.
"""
from __future__ import annotations

import ctypes
import math
from collections import deque
from typing import Any

import can

from .offline import PMA_OK, Node, OfflineError, library
from .rig import Rig
from .rig_params import RigParams

PMA_ERR_EMPTY = -9


class OfflineBus(can.BusABC):
    """python-can bus to one firmware node (libpma_offline.so) on a simulated rig."""

    def __init__(self, rig: Rig | RigParams | None = None, node_id: int = 1, seed: int = 1,
                 channel: str = "offline", max_ticks_per_recv: int = 100_000, **kwargs: Any) -> None:
        self.lib = library()
        self.node = Node(self.lib)
        self.node.start(node_id)
        self.node_id = node_id
        self.lib.pma_offline_host_queue(1)
        self.rig = rig if isinstance(rig, Rig) else Rig(rig or RigParams(), seed=seed)
        self.period_s = 1.0 / float(self.node.get("sys.tick_hz"))
        self.ticks = 0
        self.max_ticks_per_recv = max_ticks_per_recv
        self.actuator_connected = True      # False: the node's commands never reach the regulator
        self._rx: deque[can.Message] = deque()
        self._id = ctypes.c_uint16()
        self._dlc = ctypes.c_uint8()
        self._data = (ctypes.c_uint8 * 8)()
        self.channel_info = f"offline node {node_id} on rig {self.rig.params.profile}"
        super().__init__(channel=channel, **kwargs)

    # ---------------------------------------------------------------- time --
    def clock(self) -> float:
        """Control time since the node started [s]."""
        return self.ticks * self.period_s

    def tick(self) -> None:
        """One control tick: the rig's sample to the node, its command to the rig, one period."""
        counts = self.rig.sensor_counts()
        out = self.node.tick(counts)
        if self.actuator_connected:
            self.rig.apply_dac(out.dac_counts)
        self.rig.step(self.period_s)
        self.ticks += 1
        self._drain()

    def run_for(self, seconds: float) -> None:
        """Advance control time by `seconds` without waiting for anything."""
        for _ in range(max(0, math.ceil(seconds / self.period_s - 1e-9))):
            self.tick()

    # -------------------------------------------------------------- frames --
    def _drain(self) -> None:
        while self.lib.pma_offline_frame_out(ctypes.byref(self._id), ctypes.byref(self._dlc), self._data) == PMA_OK:
            self._rx.append(can.Message(timestamp=self.clock(), arbitration_id=self._id.value, is_extended_id=False,
                                        dlc=self._dlc.value, data=bytes(self._data[:self._dlc.value]), is_rx=True,
                                        channel=self.channel_info))

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame:
            raise can.CanOperationError("the offline bus carries standard data frames only")
        if not 0 <= msg.arbitration_id <= 0x7FF or not 0 <= len(msg.data) <= 8:
            raise can.CanOperationError(f"bad frame: id 0x{msg.arbitration_id:X}, {len(msg.data)} bytes")
        data = (ctypes.c_uint8 * 8)(*bytes(msg.data))
        rc = self.lib.pma_offline_frame_in(msg.arbitration_id, len(msg.data), data)
        if rc != PMA_OK:
            raise can.CanOperationError(f"the node's receive queue refused the frame: {self.node.status_name(rc)}")
        rc = self.lib.pma_offline_loop()
        if rc != PMA_OK:
            raise OfflineError(f"the node's loop failed: {self.node.status_name(rc)}")
        self._drain()

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        if not self._rx:
            limit = self.max_ticks_per_recv if timeout is None else math.ceil(timeout / self.period_s)
            for _ in range(min(limit, self.max_ticks_per_recv)):
                self.tick()
                if self._rx:
                    break
        return (self._rx.popleft() if self._rx else None), False

    @property
    def dropped(self) -> int:
        """Frames the node sent that the host queue had no room for."""
        return int(self.lib.pma_offline_host_dropped())
