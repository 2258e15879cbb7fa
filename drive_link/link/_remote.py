"""The drive as a :class:`canopen.RemoteNode` whose SDO traffic goes through our locked channel.

canopen's ``RemoteNode`` brings the pieces a host needs — ``node.nmt`` (NMT master),
``node.emcy`` (EMCY consumer), ``node.tpdo`` / ``node.rpdo`` (PDO configuration,
``TPDO.read()``), ``node.sdo["name"].raw`` (values encoded by the OD) — but its SDO client has no
lock (canopen #125, #143) and does not resend a lost request. :func:`remote_node` builds the node
with :class:`NodeSdo` as ``node.sdo``: the same canopen client interface (``upload``,
``download``, ``node.sdo[index][sub].raw``), every transfer made by a
:class:`~drive_link.link._sdo.SdoChannel` (per-channel lock, resends, restarts). So canopen's own
code (e.g. ``TPDO.read()``) and ours share one channel and never collide.

``node.emcy`` is :class:`~drive_link.link._emcy.EmcyListener` (canopen's consumer, hardened).
``node.nmt`` sends NMT commands; the node's NMT *state* is tracked by
:class:`~drive_link.link._nmt.HeartbeatMonitor` (see :mod:`drive_link.link._nmt` for why not
canopen's).
"""

from __future__ import annotations

from typing import Any

import canopen
from canopen.pdo import PDO, RPDO, TPDO
from canopen.sdo import SdoClient
from canopen.sdo.exceptions import SdoAbortedError

from ..errors import SdoAbort
from ._emcy import EmcyListener
from ._sdo import SdoChannel

__all__ = ["NodeSdo", "remote_node"]


class NodeSdo(SdoClient):
    """canopen's SDO client interface on top of a :class:`~drive_link.link._sdo.SdoChannel`.

    It never listens to the bus itself (the channel does), so canopen callers and ours share
    the channel's lock. Refusals are raised as canopen's :class:`SdoAbortedError` (what canopen's
    code catches, e.g. ``PdoMap.read`` for an optional sub-index); a node that does not answer
    raises :class:`~drive_link.errors.DriveTimeout` after the channel's resends.
    """

    def __init__(self, channel: SdoChannel, od: canopen.ObjectDictionary):
        super().__init__(channel.rx_cobid, channel.tx_cobid, od)
        self.channel = channel

    def upload(self, index: int, subindex: int) -> bytes:
        """Read an object's raw bytes (locked, resent, restarted by the channel)."""
        try:
            return self.channel.upload(index, subindex)
        except SdoAbort as exc:
            raise SdoAbortedError(exc.code) from exc

    def download(
        self, index: int, subindex: int, data: bytes, force_segment: bool = False
    ) -> None:
        """Write an object's raw bytes (expedited up to 4 bytes, else segmented)."""
        try:
            self.channel.download(index, subindex, bytes(data))
        except SdoAbort as exc:
            raise SdoAbortedError(exc.code) from exc

    def open(self, *args: Any, **kwargs: Any) -> Any:
        """Not offered: stream large objects with ``Drive.sdo_trace.upload_block``."""
        raise NotImplementedError("use SdoChannel.upload_block for large objects")


def remote_node(
    network: canopen.Network,
    node_id: int,
    od: canopen.ObjectDictionary,
    channel: SdoChannel,
) -> canopen.RemoteNode:
    """A ``RemoteNode`` for ``node_id`` on ``network`` with ``node.sdo`` = :class:`NodeSdo` on
    ``channel`` and ``node.emcy`` = :class:`~drive_link.link._emcy.EmcyListener`; subscribed to its
    heartbeat (``node.nmt``) and EMCY (0x80 + N) frames. Undo with ``node.remove_network()``.

    The node is not added to ``network.nodes``: several sessions may watch one node-ID.
    """
    node = canopen.RemoteNode(node_id, od)
    node.sdo = NodeSdo(channel, od)
    node.sdo_channels = []  # the channel subscribes to the responses, not canopen
    # the PDO maps bind their parameter records to node.sdo when made: make them again
    node.tpdo = TPDO(node)
    node.rpdo = RPDO(node)
    node.pdo = PDO(node, node.rpdo, node.tpdo)
    node.emcy = EmcyListener()
    node.associate_network(network)
    node.sdo.network = network
    return node
