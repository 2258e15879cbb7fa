"""A locked SDO client channel with retries and one-line errors.

canopen's :class:`~canopen.sdo.SdoClient` has no lock: two threads on one channel corrupt each
other's transfers. :class:`SdoChannel` serialises every transfer on its channel; a drive uses one
channel per SDO server (0x1200 for status and parameters, 0x1201 for trace uploads) so a long
upload never blocks status reads.

Retries: a transfer that times out or loses sync (lost frames: a protocol abort such as
0x05040001 or 0x05040003) is repeated from its start up to ``retries`` times. Reads and writes
of one object are idempotent, so a repeat is allowed by the protocol; an abort that refuses the
value or the access is never retried.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator

import can
import canopen
from canopen.sdo.client import SdoClient
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from .errors import BusError, DriveTimeout, SdoAbort
from .sdo_block import block_upload

#: progress(bytes_done, bytes_total_or_None)
Progress = Callable[[int, "int | None"], None]


#: Aborts that mean the transfer itself broke (lost or late frames), not a refusal of the
#: value: SDO timeout, unknown command specifier, block size, sequence number, CRC, toggle bit.
PROTOCOL_ABORTS = (0x05040000, 0x05040001, 0x05040002, 0x05040003, 0x05040004, 0x05030000)


class _Client(SdoClient):
    """canopen's client without the abort frame after a response timeout.

    After a lost frame canopen sends an abort (0x05040000) and, on a retry, the new request
    right behind it; nothing requires that abort (the server times the transfer out itself and
    every initiate request starts afresh, CiA 301 §7.2.4.3), and on a lossy or slow link the
    back-to-back pair only adds load. Other aborts (CRC, protocol errors) are still sent.
    """

    def abort(self, abort_code: int = 0x08000000) -> None:
        if abort_code == 0x05040000:
            return
        super().abort(abort_code)


class SdoChannel:
    """One SDO client channel (request COB-ID ``rx_cobid``, response COB-ID ``tx_cobid``).

    ``timeout`` is the per-frame response timeout in s; ``retries`` the number of repeats after
    a timeout.
    """

    def __init__(
        self,
        network: canopen.Network,
        node_id: int,
        rx_cobid: int,
        tx_cobid: int,
        timeout: float = 0.3,
        retries: int = 2,
    ):
        self.node_id = node_id
        self.rx_cobid = rx_cobid
        self.tx_cobid = tx_cobid
        self.retries = retries
        self.lock = threading.RLock()
        self._network = network
        self.client = _Client(rx_cobid, tx_cobid, canopen.ObjectDictionary())
        self.client.network = network
        self.client.RESPONSE_TIMEOUT = timeout
        self.client.MAX_RETRIES = 1
        network.subscribe(tx_cobid, self.client.on_response)

    def close(self) -> None:
        """Stop listening for responses."""
        try:
            self._network.unsubscribe(self.tx_cobid, self.client.on_response)
        except (KeyError, ValueError):
            pass

    def _run(self, what: str, index: int, subindex: int, name: str, fn):
        attempts = self.retries + 1
        for attempt in range(attempts):
            try:
                with self.lock:
                    return fn()
            except SdoAbortedError as exc:
                if exc.code in PROTOCOL_ABORTS and attempt + 1 < attempts:
                    continue  # the transfer lost sync (lost frames): start it again
                raise SdoAbort(exc.code, index, subindex, name, what) from None
            except SdoCommunicationError as exc:
                if attempt + 1 < attempts:
                    continue
                where = name or f"0x{index:04X}:{subindex:02X}"
                raise DriveTimeout(
                    f"node {self.node_id} did not answer SDO {what} of {where} "
                    f"({attempts} attempts): {exc}"
                ) from None
            except can.CanError as exc:
                raise BusError(f"CAN send failed: {exc}") from None
            except RuntimeError as exc:  # canopen: "Not connected to CAN bus"
                raise BusError(f"CAN bus not usable: {exc}") from None
        raise AssertionError("unreachable")

    @contextlib.contextmanager
    def patience(self, timeout: float) -> Iterator[None]:
        """Hold the channel with a response timeout of at least ``timeout`` s (for objects
        whose write takes the drive long, e.g. store 0x1010 / restore 0x1011)."""
        with self.lock:
            old = self.client.RESPONSE_TIMEOUT
            self.client.RESPONSE_TIMEOUT = max(old, timeout)
            try:
                yield
            finally:
                self.client.RESPONSE_TIMEOUT = old

    def upload(self, index: int, subindex: int, name: str = "") -> bytes:
        """Read an object (expedited or segmented) and return its raw bytes."""

        def go() -> bytes:
            with self.client.open(index, subindex, buffering=0) as fp:
                return fp.read()

        return self._run("read", index, subindex, name, go)

    def download(self, index: int, subindex: int, data: bytes, name: str = "") -> None:
        """Write raw bytes to an object (expedited if ≤ 4 bytes, else segmented)."""

        def go() -> None:
            self.client.download(index, subindex, bytes(data))

        self._run("write", index, subindex, name, go)

    def upload_block(
        self,
        index: int,
        subindex: int,
        name: str = "",
        progress: Progress | None = None,
    ) -> bytes:
        """Read a large object with SDO block upload (CiA 301 §7.2.4.3.10), reporting progress."""

        def go() -> bytes:
            return block_upload(
                self.client, index, subindex, progress, timeout=self.client.RESPONSE_TIMEOUT
            )

        return self._run("block upload", index, subindex, name, go)
