"""Bytes on the socket: what the kernel's TCP sockets of a local server port sent, per
connection, from ``ss -tin`` (Linux tcp_info ``bytes_sent``). This counts what really went
over the connection (WebSocket framing and any compression included), independent of how a
browser or Playwright reports frames (Playwright's frame events arrive in bursts and give
payloads after decompression).
"""

from __future__ import annotations

import re
import subprocess

__all__ = ["bytes_sent"]

_SENT = re.compile(r"\bbytes_sent:(\d+)")


def bytes_sent(port: int) -> dict[int, int]:
    """{peer port: bytes sent so far} of every established TCP connection whose local port
    is ``port`` on 127.0.0.1 (one entry per browser tab's WebSocket and HTTP connection)."""
    out = subprocess.run(
        ["ss", "-tinH", "state", "established", f"( sport = :{port} )"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    got: dict[int, int] = {}
    peer = None
    for line in out.splitlines():
        m = re.search(r"127\.0\.0\.1:(\d+)\s+127\.0\.0\.1:(\d+)", line)
        if m and int(m.group(1)) == port:
            peer = int(m.group(2))
            continue
        s = _SENT.search(line)
        if s and peer is not None:
            got[peer] = int(s.group(1))
            peer = None
    return got
