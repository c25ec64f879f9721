# SPDX-License-Identifier: Apache-2.0
"""pmactl: the Python client and command-line tool for PMA controller nodes on CAN.

The protocol comes from the firmware's own single sources of truth, shipped with
the package: the DBC (``data/pma_proto.dbc``) and the parameter table
(``data/params.toml``). The client (pmactl.client.PmaNode) serves the command line
(pmactl.cli), the HIL harness and the tests.
"""
from pmactl.client import (
                           Ack,
                           BusMonitor,
                           CommandError,
                           InterfaceError,
                           LoadReport,
                           MonitorEvent,
                           NodeStateError,
                           NoReply,
                           ParamInfo,
                           PmaError,
                           PmaNode,
                           RecordSummary,
                           SetRejected,
                           Status,
                           TelemetryGrouper,
                           TelemetryRecorder,
                           TelemetryRow,
                           bus_config,
                           open_bus,
                           scan,
)
from pmactl.nodedbc import NodeListError, node_database, parse_nodes, write_node_dbc
from pmactl.protocol import Param, Protocol, load_protocol

__all__ = ["Ack", "BusMonitor", "CommandError", "InterfaceError", "LoadReport", "MonitorEvent",
           "NodeListError", "NodeStateError", "NoReply", "Param", "ParamInfo", "PmaError", "PmaNode", "Protocol",
           "RecordSummary", "SetRejected", "Status", "TelemetryGrouper", "TelemetryRecorder",
           "TelemetryRow", "bus_config", "load_protocol", "node_database", "open_bus", "parse_nodes",
           "scan", "write_node_dbc"]
