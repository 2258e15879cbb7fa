"""A locked SDO client channel that resends unanswered requests and restarts broken transfers.

canopen's :class:`~canopen.sdo.SdoClient` has no lock: two threads on one channel corrupt each
other's transfers. :class:`SdoChannel` serialises every transfer on its channel; a drive uses one
channel per SDO server (0x1200 for status and parameters, 0x1201 for trace uploads) so a long
upload never blocks status reads.

Two levels of recovery:

- a request that gets no answer is sent again (``retries`` times, waiting ``timeout``,
  2 × ``timeout``, … s; :mod:`drive_link.link._sdo_segmented`, :mod:`drive_link.link._sdo_block`);
  block uploads also recover lost segments through ``ackseq``;
- a transfer that still breaks in the middle (lost sync, a protocol abort such as 0x05040001,
  0x05040003 or 0x05040004, CRC or length mismatch) is started again from its beginning, up to
  ``restarts`` times and within ``deadline_s`` s in all. Reads and writes of one object are
  idempotent, so a repeat is allowed by the protocol; an abort that refuses the value or the
  access is never retried.

A node that answers no initiate request at all fails at once with :class:`DriveTimeout`
("did not answer … (N attempts)"); a transfer that cannot be completed fails with one line
naming the last reason. Wrong data is never returned: lengths and block-upload CRCs are
checked.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator
from typing import TypeVar

import can
import canopen
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from firmware_protocol import abort_codes

from ..errors import BusError, DriveTimeout, SdoAbort
from ..errors import NodeGone as NodeGoneError
from . import _sdo_segmented
from ._sdo_block import block_upload
from ._sdo_client import ChannelClient
from ._sdo_segmented import NoAnswer, NodeGone

__all__ = [
    "PROTOCOL_ABORTS",
    "Progress",
    "SdoChannel",
    "stamps_host_time",
]

#: progress(bytes_done, bytes_total_or_None)
Progress = Callable[[int, "int | None"], None]

#: what one transfer returns (bytes for an upload, None for a download)
_T = TypeVar("_T")


#: Aborts that mean the transfer itself broke (lost or late frames), not a refusal of the
#: value: SDO timeout, unknown command specifier, block size, sequence number, CRC, toggle bit.
PROTOCOL_ABORTS = (
    abort_codes.TIMEOUT,
    abort_codes.COMMAND,
    abort_codes.BLOCK_SIZE,
    abort_codes.SEQUENCE,
    abort_codes.CRC,
    abort_codes.TOGGLE_BIT,
)


_LOOPBACK = ("127.0.0.1", "localhost", "::1")


def stamps_host_time(bus: object) -> bool:
    """Whether ``bus`` stamps received frames with this host's ``time.time()`` clock: kernel
    SocketCAN (SO_TIMESTAMP), python-can's ``virtual`` bus, and socketcand on this machine (the
    project's loopback hub stamps frames with its bus time). USB adapters stamp with their own
    timer and a remote socketcand with its host's clock: not comparable, never used."""
    from can.interfaces.socketcan import SocketcanBus
    from can.interfaces.virtual import VirtualBus

    if isinstance(bus, SocketcanBus):
        return True
    if isinstance(bus, VirtualBus):
        return not getattr(bus, "preserve_timestamps", False)  # else: the senders' stamps
    info = str(getattr(bus, "channel_info", ""))
    return info.startswith("socketcand on ") and info.rsplit("@", 1)[-1].rsplit(":", 1)[0] in (
        _LOOPBACK
    )


class SdoChannel:
    """One SDO client channel (request COB-ID ``rx_cobid``, response COB-ID ``tx_cobid``).

    ``timeout``: s to wait for an answer before a request is sent again (doubling each time);
    ``retries``: resends of an unanswered request; ``restarts``: how often a transfer that
    broke in the middle is started again; ``deadline_s``: s one read/write/upload may take in
    all, restarts included.
    """

    def __init__(
        self,
        network: canopen.Network,
        node_id: int,
        rx_cobid: int,
        tx_cobid: int,
        timeout: float = 0.3,
        retries: int = 2,
        restarts: int = 3,
        deadline_s: float = 180.0,
    ):
        self.node_id = node_id
        self.rx_cobid = rx_cobid
        self.tx_cobid = tx_cobid
        self.retries = retries
        self.restarts = restarts
        self.deadline_s = deadline_s
        self.lock = threading.RLock()
        self._network = network
        self.client = ChannelClient(
            rx_cobid, tx_cobid, canopen.ObjectDictionary(),
            host_clock=stamps_host_time(network.bus),
        )  # fmt: skip
        self.client.network = network
        self.client.RESPONSE_TIMEOUT = timeout
        self.client.MAX_RETRIES = 1
        #: transfers started again after a break, since this channel was made (benchmarks)
        self.restarted = 0
        #: why (one line each), the last 20
        self.restart_reasons: list[str] = []
        network.subscribe(tx_cobid, self.client.on_response)

    def close(self) -> None:
        """Stop listening for responses."""
        try:
            self._network.unsubscribe(self.tx_cobid, self.client.on_response)
        except (KeyError, ValueError):
            pass

    def _run(
        self, what: str, index: int, subindex: int, name: str, fn: Callable[[float], _T]
    ) -> _T:
        where = name or f"0x{index:04X}:{subindex:02X}"
        deadline = time.monotonic() + self.deadline_s
        attempts = self.restarts + 1
        for attempt in range(1, attempts + 1):
            more = attempt < attempts and time.monotonic() < deadline
            try:
                with self.lock:
                    return fn(deadline)
            except SdoAbortedError as exc:
                if exc.code in PROTOCOL_ABORTS and more:
                    self._restart(f"abort 0x{exc.code:08X}")
                    continue  # the transfer lost sync (lost frames): start it again
                raise SdoAbort(exc.code, index, subindex, name, what) from None
            except NodeGone as exc:  # its heartbeat stopped: no resend, no restart
                raise NodeGoneError(f"{exc}; SDO {what} of {where} not answered") from None
            except NoAnswer as exc:
                if not exc.initial and more:
                    self._restart(str(exc))
                    continue
                raise DriveTimeout(
                    f"node {self.node_id} did not answer SDO {what} of {where} "
                    f"({exc.requests} attempts): {exc}"
                ) from None
            except SdoCommunicationError as exc:
                if more:
                    self._restart(str(exc))
                    continue
                raise DriveTimeout(
                    f"SDO {what} of {where} on node {self.node_id} failed after {attempt} "
                    f"attempt{'s' if attempt > 1 else ''}: {exc}"
                ) from None
            except can.CanError as exc:
                raise BusError(f"CAN send failed: {exc}") from None
            except RuntimeError as exc:  # canopen: "Not connected to CAN bus"
                raise BusError(f"CAN bus not usable: {exc}") from None
        raise AssertionError("unreachable")

    def _restart(self, reason: str) -> None:
        self.restarted += 1
        self.restart_reasons = [*self.restart_reasons[-19:], reason]

    @contextlib.contextmanager
    def patience(self, timeout: float, retries: int | None = None) -> Iterator[None]:
        """Hold the channel with a response timeout of at least ``timeout`` s (for objects
        whose write takes the drive long, e.g. store 0x1010 / restore 0x1011) and, if
        ``retries`` is given, at most that many resends and no restart (for a request that
        must get no answer, e.g. an SDO in NMT STOPPED: silence is proved in
        ``timeout`` × (2^(retries + 1) − 1) s, not the channel's full patience)."""
        with self.lock:
            old = self.client.RESPONSE_TIMEOUT, self.retries, self.restarts
            self.client.RESPONSE_TIMEOUT = max(old[0], timeout)
            if retries is not None:
                self.retries, self.restarts = min(old[1], retries), 0
            try:
                yield
            finally:
                self.client.RESPONSE_TIMEOUT, self.retries, self.restarts = old

    def upload(self, index: int, subindex: int, name: str = "") -> bytes:
        """Read an object (expedited or segmented) and return its raw bytes."""

        def go(deadline: float) -> bytes:
            return _sdo_segmented.upload(
                self.client, index, subindex, self.client.RESPONSE_TIMEOUT, self.retries
            )

        return self._run("read", index, subindex, name, go)

    def download(self, index: int, subindex: int, data: bytes, name: str = "") -> None:
        """Write raw bytes to an object (expedited if ≤ 4 bytes, else segmented). A request is
        sent again only when it got no answer (see :mod:`drive_link.link._sdo_segmented`)."""

        def go(deadline: float) -> None:
            _sdo_segmented.download(
                self.client, index, subindex, bytes(data), self.client.RESPONSE_TIMEOUT,
                self.retries,
            )  # fmt: skip

        self._run("write", index, subindex, name, go)

    def upload_block(
        self,
        index: int,
        subindex: int,
        name: str = "",
        progress: Progress | None = None,
    ) -> bytes:
        """Read a large object with SDO block upload (CiA 301 §7.2.4.3.10), reporting progress;
        lost segments are recovered, a broken upload is started again (see the module doc).
        The progress never goes back: an upload started again reports nothing new until it
        passes what the broken one had (a progress bar went backwards at load 17)."""
        report = progress
        if progress is not None:
            high = [-1]

            def report(done: int, total: int | None) -> None:
                if done > high[0]:
                    high[0] = done
                    progress(done, total)

        def go(deadline: float) -> bytes:
            return block_upload(
                self.client,
                index,
                subindex,
                report,
                timeout=self.client.RESPONSE_TIMEOUT,
                resends=self.retries,
                deadline=deadline,
            )

        return self._run("block upload", index, subindex, name, go)
