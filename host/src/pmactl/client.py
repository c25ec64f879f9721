# SPDX-License-Identifier: Apache-2.0
"""The protocol client: one class, used by pmactl, the HIL harness and the tests.

PmaNode talks to one node over any python-can bus (socketcan, pcan, kvaser,
slcan, virtual, ...). It is synchronous: each request waits for its reply and
drops unrelated frames, except heartbeats, which it keeps (the last one per
node) for status queries. Every frame it receives or sends is also passed to
its listeners (``frame_listeners``: decoded protocol frames; ``raw_listeners``:
every can.Message, e.g. a can.Logger), so a recorder sees the frames that
arrive while a request waits for its reply.

Besides PmaNode: opening a bus from python-can's configuration (open_bus),
finding nodes (scan), watching a bus (BusMonitor) and recording telemetry
(TelemetryGrouper, TelemetryRecorder).

The client is split by concern: pmactl.errors, pmactl.bus (choosing and opening a bus),
pmactl.node (PmaNode and its replies), pmactl.monitor (scan, BusMonitor) and
pmactl.recorder (telemetry rows and recording). This module re-exports them, the one
import the tools and the harness use.
"""
from __future__ import annotations

from pmactl.bus import (
    DEFAULT_CHANNEL,
    DEFAULT_INTERFACE,
    NODE_REPLIES,
    bus_config,
    describe_bus,
    frame_filters,
    open_bus,
)
from pmactl.errors import (
    BadBusConfig,
    CommandError,
    InterfaceError,
    NodeStateError,
    NoReply,
    PmaError,
    SetRejected,
)
from pmactl.monitor import (
    BusMonitor,
    MonitorEvent,
    scan,
)
from pmactl.node import (
    HOST_HEARTBEAT_PERIOD_S,
    OPS,
    TYPE_CODES,
    TYPE_NAMES,
    TYPE_SIGNALS,
    Ack,
    FrameListener,
    LoadReport,
    ParamInfo,
    ParamReply,
    PmaNode,
    RawListener,
    Status,
    param_value_text,
    wire_value,
)
from pmactl.recorder import (
    RecordProgress,
    RecordSummary,
    TelemetryGrouper,
    TelemetryRecorder,
    TelemetryRow,
    internal_labels,
)

__all__ = [
    "BadBusConfig",
    "Ack",
    "BusMonitor",
    "CommandError",
    "DEFAULT_CHANNEL",
    "DEFAULT_INTERFACE",
    "FrameListener",
    "HOST_HEARTBEAT_PERIOD_S",
    "InterfaceError",
    "LoadReport",
    "MonitorEvent",
    "NODE_REPLIES",
    "NoReply",
    "NodeStateError",
    "OPS",
    "ParamInfo",
    "ParamReply",
    "PmaError",
    "PmaNode",
    "RawListener",
    "RecordProgress",
    "RecordSummary",
    "SetRejected",
    "Status",
    "TYPE_CODES",
    "TYPE_NAMES",
    "TYPE_SIGNALS",
    "TelemetryGrouper",
    "TelemetryRecorder",
    "TelemetryRow",
    "bus_config",
    "describe_bus",
    "frame_filters",
    "internal_labels",
    "open_bus",
    "param_value_text",
    "scan",
    "wire_value",
]
