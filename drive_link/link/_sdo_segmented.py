"""SDO expedited and segmented transfers, client side (CiA 301 §7.2.4.3.3–7.2.4.3.8), with
resends of unanswered requests.

Every request waits for the response it asked for and ignores any other frame on the response
COB-ID (a late duplicate of an earlier answer, a segment with the other toggle bit). A request
with no matching answer within ``timeout`` s is sent again, waiting twice as long each time, up
to ``resends`` times. The server answers a repeated segment request with the same segment
(upload) or the same confirmation without storing twice (download); an initiate request starts
the transfer afresh. So a resent READ is always harmless. A resent WRITE request is only sent
when no answer came: if the first one reached the drive and only its confirmation was lost,
the drive executes the same write twice — the same value to the same object, which is
harmless for every object of this drive (parameters, controlword commands that name a target
state, store/restore, trace commands).

A request that was sent k times and answered may still get k - 1 late answers (the first
answer was only slow, not lost). They can arrive during a *later* transfer on the channel,
e.g. the drive's abort of a refused write arriving while the same object is read back, or an
old statusword answering a new poll — on a starved host not only during the next transfer (the
check's SDO abort item, writing one bad value after another to one object at load 18, met the
"value too high" abort of the write before last as the answer to a "value too low" write).
The client therefore keeps the copies owed (``client.stale_answers``: frame, copies, until
when; added when a transfer ends with a request/answer pair: expedited and segmented transfers,
aborts) for :data:`OWED_FOR_S` s, and every transfer skips frames identical to one of them: if
a skipped frame was in fact the new answer, the identical late one or a resend supplies it.
Each frame a request skipped that is identical to its own final answer counts against the
copies it leaves owed: it may have been the answer to one of that request's own sends.
(Without that, at 5 % loss a poll of an unchanged statusword ratcheted up: every lost answer
made all later reads skip one more real answer, until one ran out of resends.)

A copy owed because a request was *lost* (not slow) never comes, and skipping a later
identical answer in its place cost that transfer a whole response timeout and a resend: at 5 %
loss (the hub, 300 writes and reads), 23 % of controlword writes needed a resend instead of
about 10 %, 3 % four sends or more, and ``enable`` (ten transfers) took up to 6.3 s (99th
percentile 5.7 s of 150); held back as below: 13 %, 0.3 %, and 2.5 s. So a frame
skipped as a late copy is only held back: if no other frame follows within the settle time
(:func:`settle_s`: a quarter of the response timeout, at least :data:`SETTLE_MIN_S`, and at
least three times the slowest of the channel's last answers, so that a slow drive's real late
copy, which its own answer follows after as long as answers take, is still skipped), it is taken
as the request's own answer.
"""

from __future__ import annotations

import queue
import struct
import time
from collections.abc import Callable

from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from ._sdo_client import (
    ABORT,
    CS_MASK,
    EXPEDITED,
    NO_MORE_SEGMENTS,
    REQUEST_DOWNLOAD,
    REQUEST_SEGMENT_DOWNLOAD,
    REQUEST_SEGMENT_UPLOAD,
    REQUEST_UPLOAD,
    RESPONSE_DOWNLOAD,
    RESPONSE_SEGMENT_DOWNLOAD,
    RESPONSE_SEGMENT_UPLOAD,
    RESPONSE_UPLOAD,
    SIZE_SPECIFIED,
    TOGGLE_BIT,
    ChannelClient,
)

#: s a host-clock frame timestamp may lie before the request it answers (clock steps,
#: rounding); frames stamped earlier are dropped (see drive_link.link._sdo_client.ChannelClient)
CLOCK_TOLERANCE_S = 0.002

#: s a wait may overrun before it counts as a host stall, and the time the bus thread then gets
#: to deliver what came meanwhile before a silent node counts as gone (see Exchange.next_or_gone)
STALL_GRACE_S = 0.25

#: s a late copy of an answer stays owed (see the module doc): a host that starves the drive
#: answers a resent request seconds late, and a copy that never comes (its request was lost,
#: not slow) costs a later identical answer one resend at most this long
OWED_FOR_S = 5.0

#: s a frame held back as a late copy waits at least for a frame after it (see settle_s)
SETTLE_MIN_S = 0.02

#: s a timed wait may end before the time it was given (the queue's wait): a wait that ends
#: at a request's floor this close has reached it (see Exchange.next_or_gone)
FLOOR_HAIR_S = 0.001

__all__ = [
    "CLOCK_TOLERANCE_S", "OWED_FOR_S", "SETTLE_MIN_S", "Exchange", "NoAnswer", "NodeGone",
    "check_gone", "continue_upload", "download", "settle_s", "upload", "wait_slice",
]  # fmt: skip


class NoAnswer(SdoCommunicationError):  # noqa: N818 (named like canopen's errors)
    """A request got no matching answer after every resend.

    ``requests``: how many times it was sent; ``initial``: True for the initiate request of a
    transfer (nothing had been exchanged: the node is absent or mute).
    """

    def __init__(self, message: str, requests: int, initial: bool) -> None:
        super().__init__(message)
        self.requests = requests
        self.initial = initial


class NodeGone(SdoCommunicationError):  # noqa: N818
    """The node's heartbeat stopped while a request waited (``client.gone_at()`` said so)."""


def check_gone(client: ChannelClient) -> None:
    """Raise :class:`NodeGone` if the node's heartbeat watch says it is gone now."""
    at = client.gone_at()
    if at is not None and time.monotonic() >= at - FLOOR_HAIR_S:  # (a wait may end early)
        raise NodeGone(client.gone_reason())


def wait_slice(client: ChannelClient, left: float, floor: float = 0.0) -> float:
    """``left`` s, or less if the node counts as gone sooner (to fail then, not later), but
    not before ``floor`` (monotonic s)."""
    at = client.gone_at()
    return left if at is None else max(0.0, min(left, max(at, floor) - time.monotonic()))


def settle_s(client: ChannelClient, timeout: float) -> float:
    """s a frame held back as a late copy of an earlier answer waits for another frame before
    it is taken as the present request's answer: ``timeout``/4, at least :data:`SETTLE_MIN_S`
    and at least three times the slowest of the client's last few answers
    (s from the last send of their request; ``client.latencies``)."""
    latencies = getattr(client, "latencies", ())
    return max(SETTLE_MIN_S, timeout / 4, 3 * max(latencies, default=0.0))


class Exchange:
    """Requests and responses of one transfer on ``client``'s COB-IDs (object
    ``index``:``subindex``; an abort frame naming another object is ignored)."""

    def __init__(self, client: ChannelClient, index: int, subindex: int) -> None:
        self.client = client
        self.index = index
        self.subindex = subindex
        self.requests_sent = 0
        # frames stamped before now answer earlier requests (ChannelClient.on_response)
        client.not_before = time.time() - CLOCK_TOLERANCE_S
        self.drain()
        #: [frame, how many more may come, owed until (monotonic s)]: late duplicates of the
        #: answers of earlier transfers on the channel
        now = time.monotonic()
        self.stale: list[list] = [e for e in client.stale_answers if e[1] > 0 and e[2] > now]
        self.abort_frame = b""
        self._duplicates: tuple[bytes, int] | None = None  # of the last request's answer
        #: frames :meth:`next` skipped as late copies during the present :meth:`request`
        self.skipped: list[bytes] = []
        #: s a frame skipped as a late copy waits for a frame after it (None: for ever)
        self.settle: float | None = None
        #: monotonic s at which the frame :meth:`next` returned last was received
        self.received_at = 0.0

    def drain(self) -> None:
        """Forget frames of earlier transfers."""
        q = self.client.responses
        while True:
            try:
                q.get_nowait()
            except queue.Empty:
                return

    def send(self, frame: bytes) -> None:
        self.requests_sent += 1
        self.client.network.send_message(self.client.rx_cobid, bytes(frame).ljust(8, b"\0"))

    def next(self, timeout: float) -> bytes | None:
        """The next response frame within ``timeout`` s, or None.

        Raises :class:`SdoAbortedError` for an abort of this transfer's object.
        """
        deadline = time.monotonic() + timeout
        held: bytes | None = None  # a frame skipped as a late copy, until another one comes
        held_until = held_at = deadline
        while True:
            left = min(deadline, held_until) - time.monotonic()
            try:
                data = self.client.responses.get(timeout=max(0.0, left))
            except queue.Empty:
                if held is None or time.monotonic() >= deadline:
                    return None
                # nothing followed it: the copy owed never came (its request was lost, not
                # slow) and this frame is the present request's own answer
                self.skipped.remove(held)
                data, held, held_until = held, None, deadline
                taken = self._take(data)
                if taken is not None:
                    self.received_at = held_at
                    return taken
                continue
            data = bytes(data).ljust(8, b"\0")
            owed = next((e for e in self.stale if e[0] == data and e[1] > 0), None)
            if owed is not None:
                owed[1] -= 1
                self.skipped.append(data)
                if held is None and self.settle is not None:
                    held_at = time.monotonic()
                    held, held_until = data, held_at + self.settle
                continue  # a late duplicate of an earlier transfer's answer
            held, held_until = None, deadline  # (it was one: this frame came after it)
            taken = self._take(data)
            if taken is not None:
                self.received_at = time.monotonic()
                return taken

    def _take(self, data: bytes) -> bytes | None:
        """``data`` as a response of this transfer, None for another object's abort; raises
        :class:`SdoAbortedError` for an abort of this transfer's object."""
        if data[0] == ABORT:
            index, subindex, code = struct.unpack_from("<HBI", data, 1)
            if (index, subindex) == (self.index, self.subindex):
                self.abort_frame = data
                raise SdoAbortedError(code)
            return None  # the end of some other transfer
        return data

    def next_or_gone(self, timeout: float, floor: float = 0.0) -> bytes | None:
        """:meth:`next`, but raises :class:`NodeGone` as soon as the node's heartbeat watch
        says it is gone (one producer period plus one response timeout after its last
        heartbeat), not only after ``timeout``; never before ``floor`` (monotonic s: a request
        always gets one response timeout, so a node that just came back can answer)."""
        deadline = time.monotonic() + timeout
        graces = 4  # (a host that stalls every wait is judged after that many)
        while True:
            left = deadline - time.monotonic()
            step = wait_slice(self.client, left, floor)
            t0 = time.monotonic()
            frame = self.next(step)
            if frame is not None:
                return frame
            now = time.monotonic()
            if now - t0 - step > STALL_GRACE_S and graces > 0:
                graces -= 1
                # this host did not run the process meanwhile: the heartbeats that came during
                # the stall are still in the receive thread's hands, so the silence is ours,
                # not the node's; judged again once the bus thread had STALL_GRACE_S to catch up
                # (the SocketCAN lane at host load 11-16: "no heartbeat for 2178 ms")
                floor = max(floor, now + STALL_GRACE_S)
                deadline = max(deadline, floor)  # (an answer may be waiting too: no resend)
                continue
            if now >= floor - FLOOR_HAIR_S:
                check_gone(self.client)
            if step >= left or now >= deadline:
                return None

    def request(
        self,
        frame: bytes,
        accept: Callable[[bytes], bool],
        timeout: float,
        resends: int,
        initial: bool = False,
    ) -> bytes:
        """Send ``frame`` and return the first response ``accept`` takes; resend it after
        ``timeout``, 2 × ``timeout``, then every 4 × ``timeout`` s without one, at most
        ``resends`` times."""
        wait = timeout
        self.skipped = []
        self.settle = settle_s(self.client, timeout)
        for sent in range(1, resends + 2):
            self.send(frame)
            t_sent = time.monotonic()
            deadline = t_sent + wait
            # one response timeout, even for a gone node; from the same reading as the
            # deadline (wait >= timeout), so a wait that reaches the deadline has reached it
            # too and asks whether the node is gone before any resend (two readings let a host
            # stall between them put the floor past the deadline: a resend to a gone node)
            floor = t_sent + timeout
            while (left := deadline - time.monotonic()) > 0:
                try:
                    resp = self.next_or_gone(left, floor)
                except SdoAbortedError:  # ends the transfer
                    self._duplicates = self._owed(self.abort_frame, sent)
                    self.finish()
                    raise
                if resp is None:
                    break
                if accept(resp):
                    self._duplicates = self._owed(resp, sent)
                    latencies = getattr(self.client, "latencies", None)
                    if latencies is not None:
                        latencies.append(max(0.0, self.received_at - t_sent))
                    return resp
            wait = min(2 * wait, 4 * timeout)  # back off, but keep probing a slow node
        what = "initiate" if initial else "segment"
        raise NoAnswer(f"no answer to the {what} request", resends + 1, initial)

    def _owed(self, answer: bytes, sent: int) -> tuple[bytes, int] | None:
        """Late copies of ``answer`` the next transfer may still meet after ``sent`` requests:
        one per unanswered request, less the frames this request already skipped as late
        copies. Each skipped frame may have been the answer to one of this request's own
        sends (its identical, unchanged value), so without that discount a single lost answer
        in a poll of an unchanged object made every later read skip its real answer and wait
        a timeout, and each further loss added one more (seen: a statusword poll at 5 % loss
        ended in "no answer … (6 attempts)")."""
        owed = sent - 1 - self.skipped.count(answer)
        return (answer, owed) if owed > 0 else None

    def finish(self) -> None:
        """The transfer ended with the last request's answer: later transfers on the client
        skip that many identical late copies of it for :data:`OWED_FOR_S` s, and the copies
        still owed from before (see the module doc)."""
        now = time.monotonic()
        kept = [e for e in self.stale if e[1] > 0 and e[2] > now]
        if self._duplicates is not None:
            kept.append([self._duplicates[0], self._duplicates[1], now + OWED_FOR_S])
        self.client.stale_answers = kept


def _same_object(frame: bytes, index: int, subindex: int) -> bool:
    return struct.unpack_from("<HB", frame, 1) == (index, subindex)


def _segment_of(scs: int, toggle: int) -> Callable[[bytes], bool]:
    """Accepts a segment response (server command ``scs``) with the toggle bit ``toggle``."""
    return lambda r: r[0] & CS_MASK == scs and r[0] & TOGGLE_BIT == toggle


def upload(
    client: ChannelClient, index: int, subindex: int, timeout: float = 0.3, resends: int = 2
) -> bytes:
    """Read ``index``:``subindex`` (expedited or segmented) and return its bytes.

    Raises :class:`SdoAbortedError` (the server aborted), :class:`NoAnswer` or
    :class:`SdoCommunicationError` (the data length disagrees with the announced size).
    """
    ex = Exchange(client, index, subindex)
    init = struct.pack("<BHB4x", REQUEST_UPLOAD, index, subindex)
    resp = ex.request(
        init,
        lambda r: r[0] & CS_MASK == RESPONSE_UPLOAD and _same_object(r, index, subindex),
        timeout,
        resends,
        initial=True,
    )
    return continue_upload(ex, resp, timeout, resends)


def continue_upload(ex: Exchange, resp: bytes, timeout: float, resends: int) -> bytes:
    """The rest of an upload whose initiate response is ``resp`` (scs 2)."""
    cmd = resp[0]
    if cmd & EXPEDITED:
        n = 4 - ((cmd >> 2) & 0x03) if cmd & SIZE_SPECIFIED else 4  # n: bytes without data
        ex.finish()
        return bytes(resp[4 : 4 + n])
    size = struct.unpack_from("<I", resp, 4)[0] if cmd & SIZE_SPECIFIED else None
    data = bytearray()
    toggle = 0
    while True:
        seg = ex.request(
            bytes([REQUEST_SEGMENT_UPLOAD | toggle]),
            _segment_of(RESPONSE_SEGMENT_UPLOAD, toggle),
            timeout,
            resends,
        )
        n = 7 - ((seg[0] >> 1) & 0x07)  # n: bytes without data
        data += seg[1 : 1 + n]
        if size is not None and len(data) > size:
            raise SdoCommunicationError(f"segmented upload sent more than {size} bytes announced")
        if seg[0] & NO_MORE_SEGMENTS:
            break
        toggle ^= TOGGLE_BIT
    if size is not None and len(data) != size:
        raise SdoCommunicationError(f"segmented upload returned {len(data)} of {size} bytes")
    ex.finish()
    return bytes(data)


def download(
    client: ChannelClient,
    index: int,
    subindex: int,
    data: bytes,
    timeout: float = 0.3,
    resends: int = 2,
) -> None:
    """Write ``data`` to ``index``:``subindex`` (expedited if ≤ 4 bytes, else segmented).

    Raises :class:`SdoAbortedError` (the server refused), :class:`NoAnswer`.
    """
    data = bytes(data)
    ex = Exchange(client, index, subindex)

    def confirmed(r: bytes) -> bool:
        return r[0] == RESPONSE_DOWNLOAD and _same_object(r, index, subindex)

    if 0 < len(data) <= 4:
        cmd = REQUEST_DOWNLOAD | EXPEDITED | SIZE_SPECIFIED | ((4 - len(data)) << 2)
        frame = struct.pack("<BHB", cmd, index, subindex) + data.ljust(4, b"\0")
        ex.request(frame, confirmed, timeout, resends, initial=True)
        ex.finish()
        return
    frame = struct.pack("<BHBI", REQUEST_DOWNLOAD | SIZE_SPECIFIED, index, subindex, len(data))
    ex.request(frame, confirmed, timeout, resends, initial=True)
    toggle = 0
    pos = 0
    while True:
        chunk = data[pos : pos + 7]
        pos += 7
        last = pos >= len(data)
        cmd = REQUEST_SEGMENT_DOWNLOAD | toggle | ((7 - len(chunk)) << 1)
        cmd |= NO_MORE_SEGMENTS if last else 0
        frame = bytes([cmd]) + chunk.ljust(7, b"\0")
        ex.request(frame, _segment_of(RESPONSE_SEGMENT_DOWNLOAD, toggle), timeout, resends)
        if last:
            ex.finish()
            return
        toggle ^= TOGGLE_BIT
