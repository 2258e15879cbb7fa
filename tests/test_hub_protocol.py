"""The hub against the socketcand rawmode protocol, CAN arbitration, and misbehaving clients.

Truths: the socketcand protocol as documented by socketcand (doc/protocol.md) and as python-can's
``socketcand`` client speaks it (``< hi >``, ``< open >``/``< ok >``, ``< rawmode >``/``< ok >``,
``< send id len bytes >``, ``< frame id secs.usecs HEX >``, 3-digit standard / 8-digit extended
ids); CAN 2.0 arbitration (the lowest identifier wins, a standard data frame beats an extended
frame with the same base id because RTR=0 meets SRR=1).
"""

from __future__ import annotations

import re
import socket
import time

import can
import pytest

from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(30)

FRAME_RE = re.compile(rb"< frame ([0-9A-F]+) (\d+)\.(\d{6}) ([0-9A-F]*) *>")


class RawClient:
    """A hand-driven socketcand client on a plain TCP socket."""

    def __init__(self, port: int, handshake: bool = True, channel: str = "vcan0") -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.buf = b""
        if handshake:
            assert self.read_element() == b"< hi >"
            self.send(f"< open {channel} >")
            assert self.read_element() == b"< ok >"
            self.send("< rawmode >")
            assert self.read_element() == b"< ok >"
            time.sleep(Hub.handshake_hold_s + 0.02)

    def send(self, text: str | bytes) -> None:
        self.sock.sendall(text.encode() if isinstance(text, str) else text)

    def read_element(self, timeout: float = 5.0) -> bytes | None:
        """Next ``< ... >`` element (or None at timeout / EOF)."""
        deadline = time.monotonic() + timeout
        while b">" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.sock.settimeout(left)
            try:
                chunk = self.sock.recv(4096)
            except TimeoutError:
                return None
            except ConnectionError:
                return None
            if not chunk:
                return None
            self.buf += chunk
        end = self.buf.index(b">") + 1
        element, self.buf = self.buf[:end].strip(), self.buf[end:]
        return element

    def frames(self, timeout: float = 0.5) -> list[tuple[str, bytes]]:
        """All frame elements arriving within ``timeout`` as (id text, data)."""
        out = []
        while (el := self.read_element(timeout)) is not None:
            m = FRAME_RE.fullmatch(el)
            if m:
                out.append((m.group(1).decode(), bytes.fromhex(m.group(4).decode())))
        return out

    def closed_by_peer(self, timeout: float = 3.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.sock.settimeout(0.2)
            try:
                chunk = self.sock.recv(4096)
            except TimeoutError:
                continue
            except ConnectionError:
                return True
            if not chunk:
                return True
        return False

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def hub():
    with Hub(port=0) as h:
        yield h


def test_handshake_and_frame_format(hub):
    a = RawClient(hub.port)
    b = RawClient(hub.port)
    before = time.time()
    a.send("< send 123 3 1 a ff >")
    el = b.read_element()
    m = FRAME_RE.fullmatch(el)
    assert m, el
    assert m.group(1) == b"123" and m.group(4) == b"010AFF"
    stamp = int(m.group(2)) + int(m.group(3)) / 1e6
    assert before - 0.01 <= stamp <= time.time() + 0.01
    a.send("< send 1ABCDEF0 0 >")  # extended id: 8 hex digits, no data
    m = FRAME_RE.fullmatch(b.read_element())
    assert m and m.group(1) == b"1ABCDEF0" and m.group(4) == b""
    a.send("< send 7 1 5 >")  # a short standard id is sent back as 3 digits
    assert FRAME_RE.fullmatch(b.read_element()).group(1) == b"007"
    assert a.frames(0.3) == []  # no echo to the sender
    a.send("< echo >")
    assert a.read_element() == b"< echo >"
    a.close()
    b.close()


def test_channels_are_separate_buses(hub):
    a = RawClient(hub.port, channel="vcan0")
    b = RawClient(hub.port, channel="vcan0")
    c = RawClient(hub.port, channel="vcan1")
    a.send("< send 100 1 1 >")
    assert b.frames(0.3) == [("100", b"\x01")]
    assert c.frames(0.1) == []
    for x in (a, b, c):
        x.close()


def test_arbitration_lowest_id_wins_and_sender_order_is_kept():
    # 500 bit/s: an 8-byte frame occupies the bus for ~0.24 s, long enough to queue the others
    # behind it (at 5 kbit/s, 24 ms, y's frames came too late at load 17: 600 went first)
    with Hub(port=0, bitrate=500) as hub:
        x, y, z = RawClient(hub.port), RawClient(hub.port), RawClient(hub.port)
        x.send("< send 700 8 1 2 3 4 5 6 7 8 >")  # takes the idle bus at once
        time.sleep(0.004)
        x.send("< send 600 1 0 >< send 050 1 0 >")  # x's queue: 600 then 050 (FIFO per node)
        y.send("< send 100 1 0 >< send 10000000 1 0 >")  # y: 100, then extended base 0x040
        ids = [i for i, _ in z.frames(2.0)]  # (all five take ~0.65 s of bus time)
        # bus free after 700: heads x=600, y=100 -> 100; then x=600 vs y=ext(base 0x040)
        # -> ext wins (base 0x040 < 0x600); then 600, then 050.
        assert ids == ["700", "100", "10000000", "600", "050"]
        for c in (x, y, z):
            c.close()


def test_bad_clients_get_errors_or_are_dropped_and_good_clients_carry_on(hub):
    good_a = can.Bus(**hub.join_kwargs())
    good_b = can.Bus(**hub.join_kwargs())
    time.sleep(Hub.handshake_hold_s + 0.05)

    def exchange(seq: int) -> None:
        good_a.send(can.Message(arbitration_id=0x181, data=[seq], is_extended_id=False))
        m = good_b.recv(2.0)
        assert m is not None and m.arbitration_id == 0x181 and m.data == bytes([seq])

    exchange(1)
    bad = RawClient(hub.port)
    listener = RawClient(hub.port)
    bad.send(
        b"hello world\n>"  # text outside any element
        b"< send 123 9 1 2 3 4 5 6 7 8 9 >"  # DLC > 8
        b"< send 123 8 1 2 3 4 5 6 7 8 9 >"  # more data bytes than DLC
        b"< send 123 2 1 >"  # fewer
        b"< send 800 1 0 >"  # standard id above 0x7FF
        b"< send 123 1 100 >"  # byte above 0xFF
        b"< send 12345 0 >"  # 5-digit id
        b"< send 12x 0 >"  # not hex
        b"< frobnicate >"
        b"\xff\xfe >"  # not ASCII
    )
    errors = []
    while (el := bad.read_element(1.0)) is not None:
        errors.append(el)
    assert len(errors) == 10
    assert all(e.startswith(b"< error 20000008 ") for e in errors)
    assert listener.frames(0.3) == []  # nothing of it reached the bus
    exchange(2)

    # a client that never closes its element is dropped
    runaway = RawClient(hub.port)
    runaway.send(b"< send 123 " + b"1 " * 400)
    assert runaway.closed_by_peer()
    # a client that dies in the middle of an element: the partial element is discarded
    partial = RawClient(hub.port)
    partial.send(b"< send 321 2 1")
    partial.close()
    # garbage before any handshake
    early = RawClient(hub.port, handshake=False)
    assert early.read_element() == b"< hi >"
    early.send(b"\x00\x01\x02>")
    assert early.read_element().startswith(b"< error ")
    early.send(b"< rawmode >")  # rawmode before open
    assert early.read_element().startswith(b"< error ")
    early.close()
    exchange(3)
    assert listener.frames(0.3) == [("181", b"\x02"), ("181", b"\x03")]

    # a stock python-can client sending an oversized frame gets an error frame it can parse
    good_a.send(can.Message(arbitration_id=0x123, data=bytes(9), is_extended_id=False, check=False))
    m = good_a.recv(2.0)
    assert m is not None and m.is_error_frame
    exchange(4)
    assert good_b.recv(0.2) is None  # the oversized frame was not forwarded

    st = hub.stats
    assert st.protocol_errors >= 13
    assert st.clients_dropped >= 1
    assert hub.running
    for c in (bad, listener):
        c.close()
    good_a.shutdown()
    good_b.shutdown()


def test_too_many_errors_drop_the_client(hub):
    bad = RawClient(hub.port)
    bad.send(b"< nonsense >" * (Hub.max_errors_per_client + 1))
    assert bad.closed_by_peer()
    assert hub.stats.clients_dropped == 1
    ok = RawClient(hub.port)  # the hub still accepts clients
    ok.close()


def test_element_split_across_tcp_segments_is_reassembled(hub):
    a, b = RawClient(hub.port), RawClient(hub.port)
    for piece in (b"< se", b"nd 1", b"23 2 de ", b"ad >< send 0", b"01 0 >"):
        a.send(piece)
        time.sleep(0.02)
    assert b.frames(0.3) == [("123", b"\xde\xad"), ("001", b"")]
    a.close()
    b.close()


def test_python_can_reads_a_long_burst_without_cut_elements(hub, caplog):
    # python-can's socketcand client reads 1024 bytes at a time and logs a warning for each
    # element cut in two (and for any bytes it cannot parse); the hub's lines must avoid both.
    rx = can.Bus(**hub.join_kwargs())
    tx = RawClient(hub.port)
    time.sleep(Hub.handshake_hold_s + 0.05)
    caplog.set_level("WARNING", logger="can.interfaces.socketcand")
    count = 1500
    tx.send(
        b"".join(
            f"< send {i % 0x7FF:x} {i % 9} ".encode() + b"1 " * (i % 9) + b">" for i in range(count)
        )
    )
    time.sleep(0.3)  # let a backlog build up in the socket, so every read is a full 1024 bytes
    got = 0
    while rx.recv(1.0) is not None:
        got += 1
    assert got == count
    assert [r.getMessage() for r in caplog.records if r.name.startswith("can.")] == []
    rx.shutdown()
    tx.close()


def test_a_stalled_client_overruns_without_blocking_the_hub():
    count = 20_000
    with Hub(port=0, bitrate=1_000_000_000) as hub:  # pacing negligible: an instant flood
        hub.max_outbuf_bytes = 16 * 1024
        stalled = socket.socket()
        stalled.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        stalled.connect(("127.0.0.1", hub.port))
        assert stalled.recv(6) == b"< hi >"
        stalled.sendall(b"< open vcan0 >")
        assert stalled.recv(6) == b"< ok >"
        stalled.sendall(b"< rawmode >")
        assert stalled.recv(6) == b"< ok >"  # ... and then never reads again
        tx = RawClient(hub.port)
        tx.send(b"".join(b"< send 181 2 %x %x >" % (i >> 8, i & 255) for i in range(count)))
        deadline = time.monotonic() + 60  # 6 s at load 16; a busier host runs the hub slower
        while time.monotonic() < deadline:
            st = hub.stats
            if st.frames_received == count and st.frames_pending == 0:
                break
            time.sleep(0.01)
        assert st.frames_forwarded == count
        assert st.frames_overrun > 0  # the stalled client lost frames ...
        a = can.Bus(**hub.join_kwargs())  # ... while the hub keeps serving everybody else
        b = can.Bus(**hub.join_kwargs())
        time.sleep(Hub.handshake_hold_s + 0.05)
        t0 = time.monotonic()
        a.send(can.Message(arbitration_id=0x100, data=[1], is_extended_id=False))
        m = b.recv(2.0)
        assert m is not None and m.arbitration_id == 0x100
        assert time.monotonic() - t0 < 1.0  # not held behind the stalled client (~1 ms idle)
        a.shutdown()
        b.shutdown()
        tx.close()
        stalled.close()


@pytest.mark.unit
def test_fast_frame_paths_agree_with_python_cans_own_encoder_and_parser():
    """The hub's per-frame paths (parse_send_fields, frame_line) against python-can's socketcand
    client functions (the truth of what clients send and read) and the full parse_send."""
    import random

    from can.interfaces.socketcand import socketcand as pc

    from virtual_drive.hub_protocol import (
        CommandSplitter,
        ProtocolError,
        frame_line,
        parse_send,
        parse_send_fields,
        scan_sends,
    )

    rng = random.Random(13)
    splitter = CommandSplitter()
    for _ in range(3000):
        ext = rng.random() < 0.3
        can_id = rng.randrange(1 << (29 if ext else 11))
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(9)))
        msg = can.Message(arbitration_id=can_id, data=data, is_extended_id=ext)
        (words,) = splitter.feed(pc.convert_can_message_to_ascii_message(msg).encode())
        assert parse_send_fields(words) == (can_id, data, ext)
        stamp = rng.uniform(0, 2e9)
        line = frame_line(can_id, data, ext, stamp).decode()
        back = pc.convert_ascii_message_to_can_message(line)
        assert (back.arbitration_id, bytes(back.data), back.is_extended_id) == (can_id, data, ext)
        assert back.timestamp == pytest.approx(stamp, abs=1e-6)
    # scan_sends (bulk path over a received chunk) = the splitter + parse_send on every prefix
    for _ in range(1000):
        msgs = []
        for _ in range(rng.randrange(1, 5)):
            ext = rng.random() < 0.3
            can_id = rng.randrange(1 << (29 if ext else 11))
            data = bytes(rng.randrange(256) for _ in range(rng.randrange(9)))
            msgs.append(can.Message(arbitration_id=can_id, data=data, is_extended_id=ext))
        chunk = b"".join(pc.convert_can_message_to_ascii_message(m).encode() for m in msgs)
        chunk = chunk[: rng.randrange(len(chunk) + 1)]
        frames, used = scan_sends(chunk)
        ref = CommandSplitter()
        full = [parse_send(w) for w in ref.feed(chunk)]
        assert frames == [(f.arbitration_id, f.data, f.is_extended) for f in full]
        assert used == len(chunk) - ref.pending_bytes
    for odd in (b"< send 800 0  >", b"< send 181 1 1 2 >", b"< echo >< send 181 0  >"):
        assert scan_sends(odd) == ([], 0)  # left to the full path and its error messages
    for bad in (
        ["send"], ["send", "800", "0"], ["send", "1234", "0"], ["send", "12", "2", "1"],
        ["send", "12", "1", "100"], ["send", "12", "9", *["0"] * 9], ["send", "g", "0"],
        ["send", "12", "1", "+1"], ["send", "20000000", "0"],
    ):  # fmt: skip
        with pytest.raises(ProtocolError) as fast:
            parse_send_fields(bad)
        with pytest.raises(ProtocolError) as full:
            parse_send(bad)
        assert str(fast.value) == str(full.value)


def test_a_slow_stock_client_reads_its_rawmode_ok_alone_while_frames_flow(hub):
    """python-can's socketcand client reads ``< ok >`` with one ``recv`` and compares the whole
    read. On a busy bus a client that makes that read 0.2 s late (a loaded host) must still get
    ``< ok >`` alone (the old 50 ms hold glued frames to it: "Expected '< ok >' got: '< ok ><
    frame …'"); a client that asked ``< features >`` (glue-safe) gets frames at once."""
    import threading

    talker = RawClient(hub.port)
    stop = threading.Event()

    def talk() -> None:
        while not stop.is_set():
            talker.send("< send 181 2 1 2 >")
            time.sleep(0.002)

    t = threading.Thread(target=talk, daemon=True)
    t.start()
    try:
        sock = socket.create_connection(("127.0.0.1", hub.port), timeout=5)
        assert sock.recv(256) == b"< hi >"
        sock.sendall(b"< open vcan0 >")
        assert sock.recv(256) == b"< ok >"
        sock.sendall(b"< rawmode >")
        time.sleep(0.2)  # the slow client
        assert sock.recv(256) == b"< ok >"  # exactly what python-can compares
        sock.settimeout(5)
        assert b"< frame 181" in sock.recv(4096)  # then the frames come
        sock.close()
        lean = RawClient(hub.port, handshake=False)
        assert lean.read_element() == b"< hi >"
        lean.send("< open vcan0 >")
        assert lean.read_element() == b"< ok >"
        lean.send("< features >")
        assert lean.read_element().startswith(b"< features")
        lean.send("< rawmode >")
        t0 = time.monotonic()
        assert lean.read_element() == b"< ok >"
        assert FRAME_RE.fullmatch(lean.read_element(timeout=1.0))
        assert time.monotonic() - t0 < Hub.handshake_hold_s  # no hold for it
    finally:
        stop.set()
        t.join(2)


def test_the_rawmode_hold_ends_at_the_clients_first_frame(hub):
    """A stock client that sends right after its handshake (an SDO request, an LSS query) gets
    the answer at once, not after the rawmode hold: the hold ends at its first element."""
    answerer = RawClient(hub.port)
    sock = socket.create_connection(("127.0.0.1", hub.port), timeout=5)
    assert sock.recv(256) == b"< hi >"
    sock.sendall(b"< open vcan0 >")
    assert sock.recv(256) == b"< ok >"
    sock.sendall(b"< rawmode >")
    assert sock.recv(256) == b"< ok >"
    t0 = time.monotonic()
    sock.sendall(b"< send 601 8 40 41 60 00 00 00 00 00 >")
    assert answerer.read_element().startswith(b"< frame 601 ")
    answerer.send("< send 581 8 4b 41 60 00 37 06 00 00 >")
    sock.settimeout(5)
    got = b""
    while b"< frame 581" not in got:
        got += sock.recv(4096)
    assert time.monotonic() - t0 < Hub.handshake_hold_s / 2, time.monotonic() - t0
    sock.close()
