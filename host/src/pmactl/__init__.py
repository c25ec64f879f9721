"""pmactl: the Python client and command-line tool for PMA controller nodes on CAN.

The protocol comes from the firmware's own single sources of truth, shipped with
the package: the DBC (``data/pma_proto.dbc``) and the parameter table
(``data/params.toml``).
"""
from pmactl.client import Ack, CommandError, NoReply, PmaNode, PmaError
from pmactl.protocol import Param, Protocol, load_protocol

__all__ = ["Ack", "CommandError", "NoReply", "Param", "PmaError", "PmaNode", "Protocol",
           "load_protocol"]
