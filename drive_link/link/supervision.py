"""Session supervision that survives a drive restart (CiA 301 §7.2.8.3, CiA 402 0x6007).

A drive that boots again (power cycle, watchdog, NMT reset, a crashed and restarted virtual
drive) comes back with its heartbeat consumer 0x1016, its abort-connection option 0x6007 and its
PDO settings as stored or defaulted — usually *without* the supervision this host configured, so
the motor could then run with nobody watching the host. :class:`Supervisor`:

* keeps a journal of every communication object (0x1000–0x1FFF, except error history and
  store/restore commands) and 0x6007 this session wrote successfully;
* notices a restart: a boot-up message (0x700 + N, data 0x00), heartbeats that resume after a gap
  longer than 3 × the producer time, or a heartbeat falling back to PRE-OPERATIONAL without an
  NMT command of this session; the last two are confirmed by reading the journal back (a
  mismatch = the drive lost the session's settings);
* closes a gate at once (on the bus thread, when the frame arrives) so that user SDO transfers
  and NMT commands wait, re-applies 0x6007, 0x1016 and the host heartbeat producer first, then
  the rest of the journal (PDOs by the CiA 301 procedure: COB-ID invalid, mapping count 0,
  entries, count, COB-ID), then opens the gate.

A node whose heartbeat stops is gone once the host's consumer time (3 producer periods, at
least 2 s) has passed (:meth:`Supervisor.gone_at`); a call to it then fails with
:class:`~drive_link.errors.NodeGone` after one SDO response timeout (within one heartbeat
period plus one SDO timeout) instead of resending for seconds (issue 29).

Times: ``wait_timeout`` (s, default 15: a re-arm is several SDO writes, each with a ~5.7 s
resend budget; 5 s ran out with the drive starved at run-queue wait 0.63 s/s) bounds how long a
user command waits for a re-arm; after a failed
re-arm user commands raise :class:`SupervisionError` until :meth:`Supervisor.rearm` succeeds.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import math
import os
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import canopen

from firmware_protocol import load_od

from ..errors import DriveError, StateError
from ._rearm_writes import (
    ABORT_CONNECTION_OPTION,
    NOT_JOURNALLED,
    RearmReport,
    journalled,
    pdo_group,
    write_entry,
    write_pdo_group,
)
from ._sdo import Progress, SdoChannel

__all__ = [
    "ABORT_CONNECTION_OPTION",
    "CONSUMER_HEARTBEAT",
    "CONSUMER_MIN_ENV",
    "CONSUMER_MIN_S",
    "NOT_JOURNALLED",
    "PRODUCER_HEARTBEAT",
    "RESET_SILENCE_S",
    "SUPERVISION_FIRST",
    "RearmReport",
    "SupervisedSdoChannel",
    "SupervisionError",
    "Supervisor",
    "consumer_min_s",
    "journalled",
    "pdo_group",
    "write_pdo_group",
]

CONSUMER_HEARTBEAT = load_od().entry("consumer_heartbeat_time.consumer_1").index
PRODUCER_HEARTBEAT = load_od().entry("producer_heartbeat_time").index
#: First replayed, in this order: the reaction, then the watch itself, then the drive's heartbeat.
SUPERVISION_FIRST = (ABORT_CONNECTION_OPTION, CONSUMER_HEARTBEAT, PRODUCER_HEARTBEAT)

BOOT_UP = 0x00
#: s a node may stay silent after a reset this session sent (a CiA 402 drive first brakes the
#: motor; the virtual drive for at most 5 s) before a call counts it as gone
RESET_SILENCE_S = 6.0
#: shortest heartbeat consumer time (s) after which drive_link counts a node as gone. 1 s (the
#: drive's floor for the host, drive.CONSUMER_MIN_MS) called a live virtual drive gone in a
#: fresh-clone run at load 7-8 (1.2 s without a heartbeat on a 1 %-loss hub while the host was
#: busy); a DSP drive does not share the host's CPU, but the host's own reader thread does.
#: :data:`CONSUMER_MIN_ENV` replaces it (:func:`consumer_min_s`).
CONSUMER_MIN_S = 2.0
#: environment variable that sets the shortest consumer time (s, at least 1) for a host slower
#: still: the SocketCAN lane's User-Mode Linux, where a drive at host load 8-9 fell silent for
#: 2.0-2.3 s during a 64 KiB block upload (ci34, ci37, ci38), sets 5
CONSUMER_MIN_ENV = "DRIVE_LINK_CONSUMER_MIN_S"


def consumer_min_s() -> float:
    """The shortest heartbeat consumer time (s): :data:`CONSUMER_MIN_ENV` if set, else
    :data:`CONSUMER_MIN_S`. Raises ValueError (one line) for a value that is not a number of
    seconds of at least 1 (read when a session starts its supervision)."""
    text = os.environ.get(CONSUMER_MIN_ENV, "").strip()
    if not text:
        return CONSUMER_MIN_S
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 1.0):
        raise ValueError(f"{CONSUMER_MIN_ENV} must be a number of seconds >= 1, got {text!r}")
    return value
STOPPED = 0x04
OPERATIONAL = 0x05
PRE_OPERATIONAL = 0x7F


class SupervisionError(StateError):
    """The drive restarted and the session's supervision could not be re-applied."""


def _now_iso() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="milliseconds")


class SupervisedSdoChannel(SdoChannel):
    """An :class:`SdoChannel` whose transfers wait while the supervisor re-arms the drive and
    whose successful writes of communication objects go into the supervisor's journal."""

    supervisor: Supervisor | None = None

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._held = threading.local()  # depth > 0 while this thread holds it via patience()
        # a request to a node whose heartbeat stopped fails then (NodeGone), not after resends
        self.client.watch = self

    def gone_at(self) -> float | None:
        """Monotonic time from which the node counts as gone (the supervisor's heartbeat
        watch; None: none)."""
        sup = self.supervisor
        return None if sup is None else sup.gone_at()

    def gone_reason(self) -> str:
        """Why the node counts as gone."""
        sup = self.supervisor
        return "heartbeat stopped" if sup is None else sup.gone_reason()

    def _gate(self) -> None:
        # a thread already holding the channel lock (patience) must not wait: the re-arm
        # needs that lock too
        if self.supervisor is not None and not getattr(self._held, "depth", 0):
            self.supervisor.wait_ready()

    @contextlib.contextmanager
    def patience(self, timeout: float, retries: int | None = None) -> Iterator[None]:
        self._gate()
        with super().patience(timeout, retries):
            self._held.depth = getattr(self._held, "depth", 0) + 1
            try:
                yield
            finally:
                self._held.depth -= 1

    def upload(self, index: int, subindex: int, name: str = "") -> bytes:
        self._gate()
        return super().upload(index, subindex, name)

    def download(self, index: int, subindex: int, data: bytes, name: str = "") -> None:
        self._gate()
        super().download(index, subindex, data, name)
        if self.supervisor is not None:
            self.supervisor.record(index, subindex, bytes(data))

    def upload_block(
        self, index: int, subindex: int, name: str = "", progress: Progress | None = None
    ) -> bytes:
        self._gate()
        return super().upload_block(index, subindex, name, progress)


class Supervisor:
    """Watches one node for restarts and re-applies the session's supervision.

    :param network: the canopen network of the drive's bus.
    :param node_id: the drive's node-ID.
    :param restart_producer: re-creates the host heartbeat producer (None: no producer).
    :param wait_timeout: longest wait of a user command for a re-arm in progress (s).
    :param gap_factor: heartbeats resuming after more than this × the producer time count as a
        possible restart.
    """

    def __init__(
        self,
        network: canopen.Network,
        node_id: int,
        restart_producer: Callable[[], None] | None = None,
        wait_timeout: float = 15.0,
        gap_factor: float = 3.0,
    ):
        self.node_id = node_id
        self.cob_id = 0x700 + node_id
        self._network = network
        self.restart_producer = restart_producer
        #: sends one host heartbeat now (None: no producer)
        self.send_heartbeat: Callable[[], None] | None = None
        self.wait_timeout = wait_timeout
        self.gap_factor = gap_factor
        #: how long (s) a re-arm keeps retrying a node that does not answer yet
        self.rearm_budget = 4.0
        self.sdo: SdoChannel | None = None
        self._lock = threading.Condition()
        self._journal: dict[tuple[int, int], bytes] = {}  # insertion order = last-write order
        self._ready = True
        self._pending: str | None = None  # reason of a queued check/re-arm
        self._pending_boot = False
        self._error: str | None = None
        #: reason of a suspected restart whose re-arm found the drive silent (checked again
        #: once by the next command, see :meth:`wait_ready`)
        self._unanswered: str | None = None
        self._closed = False
        self._last_state: int | None = None
        self._last_hb: float | None = None
        self._last_stamp = 0.0
        self._producer_ms = 0
        self._consumer_min_s = consumer_min_s()  # (s; a bad environment value fails here)
        self._expect_preop_until = 0.0
        self._silence_until = 0.0  # a reset this session sent: silence is expected until then
        self._alive_at: float | None = None  # the node answered (attach): alive then
        self.boots_seen = 0
        self.rearmed_at: str | None = None
        self.last_report: RearmReport | None = None
        self._callbacks: list[Callable[[dict[str, Any]], None]] = []
        self._worker = threading.Thread(
            target=self._run, name=f"supervision-{node_id}", daemon=True
        )
        network.subscribe(self.cob_id, self._on_heartbeat)
        self._worker.start()

    # ------------------------------------------------------------------ wiring
    def attach(self, sdo: SdoChannel) -> None:
        """Use ``sdo`` (its unsupervised base methods) for read-backs and re-arm writes; read the
        drive's heartbeat producer time for the gap rule."""
        self.sdo = sdo
        try:
            raw = SdoChannel.upload(sdo, PRODUCER_HEARTBEAT, 0)
            self._producer_ms = int.from_bytes(raw[:2], "little")
            with self._lock:
                self._alive_at = time.monotonic()  # it answered: a heartbeat is due from now
        except DriveError:
            self._producer_ms = 0

    def close(self) -> None:
        """Stop watching; waiting commands proceed (and meet whatever the drive answers)."""
        with self._lock:
            self._closed = True
            self._ready = True
            self._lock.notify_all()
        try:
            self._network.unsubscribe(self.cob_id, self._on_heartbeat)
        except (KeyError, ValueError):
            pass
        if self._worker.is_alive() and threading.current_thread() is not self._worker:
            self._worker.join(2.0)

    def subscribe(self, callback: Callable[[dict[str, Any]], None]) -> None:
        """Call ``callback(event)`` on "restart_suspected", "reboot_detected", "rearmed" and
        "rearm_failed" (event dict: ``event``, ``reason``, ``boots_seen``, ``at``, and for the
        last two the :class:`RearmReport` fields). Runs on the bus or supervision thread: keep
        it short."""
        self._callbacks.append(callback)

    def _emit(self, event: str, **info: Any) -> None:
        ev = {"event": event, "node_id": self.node_id, "boots_seen": self.boots_seen, **info}
        ev.setdefault("at", _now_iso())
        for cb in list(self._callbacks):
            try:
                cb(ev)
            except Exception:
                pass

    # ------------------------------------------------------------------ journal
    def record(self, index: int, subindex: int, data: bytes) -> None:
        """Note a successful write (only communication objects and 0x6007 are kept)."""
        if not journalled(index):
            return
        with self._lock:
            self._journal.pop((index, subindex), None)
            self._journal[(index, subindex)] = data
            if index == PRODUCER_HEARTBEAT and subindex == 0:
                self._producer_ms = int.from_bytes(data[:2], "little")

    @property
    def journal(self) -> dict[tuple[int, int], bytes]:
        """(index, sub-index) → raw bytes of every journalled write, in last-write order."""
        with self._lock:
            return dict(self._journal)

    def expect_nmt(self, command: str) -> None:
        """The session sends NMT ``command``: a following PRE-OPERATIONAL is expected; after a
        reset the node may be silent (INITIALISING) until its boot-up message, for at most
        :data:`RESET_SILENCE_S`."""
        if command in ("pre-operational", "reset node", "reset communication"):
            self._expect_preop_until = time.monotonic() + 2.0
        if command in ("reset node", "reset communication"):
            with self._lock:
                self._silence_until = time.monotonic() + RESET_SILENCE_S

    # ------------------------------------------------------------------ dead node
    def gone_at(self, grace: float = 0.0) -> float | None:
        """Monotonic time (s) at which the node counts as gone: its last heartbeat (before the
        first one: the answer :meth:`attach` got) plus the host's consumer time
        :meth:`consumer_s`. A call to a node that is gone gets one SDO response timeout (a node
        back on the bus answers in it), then fails with NodeGone: within one heartbeat period
        plus one SDO timeout. None while nothing is watched (producer off, supervisor
        closed). ``grace`` (s) is added (0: the consumer time alone)."""
        with self._lock:
            seen = [t for t in (self._last_hb, self._alive_at) if t is not None]
            if self._closed or self._producer_ms <= 0 or not seen:
                return None
            return max(max(seen) + self.consumer_s(), self._silence_until) + grace

    def consumer_s(self) -> float:
        """The host's heartbeat consumer time (s) for this node: 3 producer periods, at least
        :data:`CONSUMER_MIN_S` (CiA 301 leaves it to the consumer; a busy host or a starved
        virtual drive on it can hold a heartbeat back by a few hundred ms, seen at load 7)."""
        return max(self._consumer_min_s, 3 * self._producer_ms / 1000.0)

    def gone_reason(self) -> str:
        """One line: since when the node's heartbeat is missing."""
        with self._lock:
            seen = [t for t in (self._last_hb, self._alive_at) if t is not None]
            last, period = (max(seen) if seen else None), self._producer_ms
        silent = (time.monotonic() - last) * 1e3 if last is not None else float("nan")
        return (
            f"node {self.node_id} is gone: no heartbeat for {silent:.0f} ms "
            f"(producer time {period} ms)"
        )

    # ------------------------------------------------------------------ gate
    @property
    def ready(self) -> bool:
        """False while a re-arm is pending or running."""
        with self._lock:
            return self._ready

    def wait_ready(self, timeout: float | None = None) -> None:
        """Block a user command until no re-arm is pending (:class:`SupervisionError` if a
        re-arm failed or did not finish within ``timeout`` / ``wait_timeout`` s)."""
        if threading.current_thread() is self._worker:
            return
        limit = self.wait_timeout if timeout is None else timeout
        deadline = time.monotonic() + limit
        retried = False
        with self._lock:
            while True:
                while not self._ready and not self._closed:
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise SupervisionError(
                            f"node {self.node_id} restarted and re-arming its supervision did "
                            f"not finish within {limit:g} s; command not sent"
                        )
                    self._lock.wait(left)
                if self._error is None or self._closed:
                    return
                if self._unanswered is None or retried:
                    raise SupervisionError(self._error)
                # the last re-arm only found the drive silent (a starved bus or host: a late
                # heartbeat is not always a restart): check again once before refusing
                retried = True
                self._pending, self._unanswered = self._unanswered, None
                self._ready, self._error = False, None
                self._lock.notify_all()

    # ------------------------------------------------------------------ detection (bus thread)
    def _on_heartbeat(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if not data:
            return
        state = data[0] & 0x7F
        now = time.monotonic()
        stamp = float(timestamp or 0.0)
        reason = None
        boot = False
        with self._lock:
            last_hb, last_state = self._last_hb, self._last_state
            last_stamp = self._last_stamp
            self._last_hb, self._last_state, self._last_stamp = now, state, stamp
            if state == BOOT_UP:
                self._silence_until = 0.0
                boot = True
                reason = "boot-up message"
            elif last_hb is not None and self._producer_ms > 0:
                # the frames' interface timestamps when the bus gives them: a busy host's late
                # notifier thread then does not look like a silent drive
                gap = stamp - last_stamp if stamp > 0 and last_stamp > 0 else now - last_hb
                limit = max(self.gap_factor * self._producer_ms / 1000.0, 0.15)
                if gap > limit and state != STOPPED:
                    reason = f"heartbeat resumed after {gap * 1e3:.0f} ms"
            if (
                reason is None
                and state == PRE_OPERATIONAL
                and last_state in (OPERATIONAL, STOPPED)
                and now > self._expect_preop_until
            ):
                reason = "heartbeat fell back to PRE-OPERATIONAL"
            if reason is None or self._closed:
                return
            if boot:
                self.boots_seen += 1
                self._pending_boot = True
            self._pending = reason
            self._ready = False
            self._error = None
            self._lock.notify_all()
        self._emit("reboot_detected" if boot else "restart_suspected", reason=reason)

    # ------------------------------------------------------------------ re-arm (worker)
    def _run(self) -> None:
        while True:
            with self._lock:
                while self._pending is None and not self._closed:
                    self._lock.wait()
                if self._closed:
                    return
                reason, boot = self._pending, self._pending_boot
                self._pending, self._pending_boot = None, False
            report = self._rearm_with_retries(reason or "", boot)
            critical = [
                k for k in report.failed if k.startswith(("0x6007", "0x1016")) or k == "drive"
            ]
            with self._lock:
                again = self._pending is not None
                if not again:
                    self._unanswered = (
                        reason if set(report.failed) == {"drive"} and not boot else None
                    )
                    if critical:
                        self._error = (
                            f"node {self.node_id} restarted ({report.reason}) and its "
                            "supervision could not be re-armed: "
                            + "; ".join(f"{k}: {v}" for k, v in report.failed.items())
                        )
                    self._ready = True
                    self._lock.notify_all()
            if again:
                # another restart (or a late heartbeat) meanwhile: go again, the gate stays
                # closed. What this pass did is still reported (a boot-up's re-arm is never
                # left unsaid); a failure is not: the next pass decides that
                if not critical:
                    self._emit("rearmed" if report.reboot else "verified", **report.to_dict())
                continue
            self._emit(
                "rearm_failed" if self._error else ("rearmed" if report.reboot else "verified"),
                **report.to_dict(),
            )

    def _rearm_with_retries(self, reason: str, boot: bool) -> RearmReport:
        deadline = time.monotonic() + self.rearm_budget
        while True:
            report = self.rearm_now(reason, boot)
            if "drive" not in report.failed or time.monotonic() > deadline or self._closed:
                return report
            time.sleep(0.1)  # the node is not answering yet (still booting): try again

    def rearm(self) -> RearmReport:
        """Re-apply the session's supervision now (user-requested); clears a failed state."""
        with self._lock:
            self._ready = False
        try:
            report = self.rearm_now("requested", True)
        finally:
            with self._lock:
                critical = [k for k in report.failed if k.startswith(("0x6007", "0x1016"))]
                self._error = None if not critical else f"re-arm failed: {report.failed}"
                self._ready = True
                self._lock.notify_all()
        return report

    def rearm_now(self, reason: str, boot: bool) -> RearmReport:
        """Compare the journal with the drive and write what differs (supervision first).

        ``boot``: the drive is known to have restarted (counted as a reboot even if nothing had
        to be written). Unsupervised transfers (the gate does not apply to this thread)."""
        t0 = time.monotonic()
        report = RearmReport(reason=reason, reboot=boot)
        sdo = self.sdo
        if sdo is None:
            return report
        journal = self.journal
        try:
            first = [k for p in SUPERVISION_FIRST for k in journal if k[0] == p]
            plain = [k for k in journal if k not in first and pdo_group(k[0]) is None]
            groups: dict[tuple[str, int], list[tuple[int, int]]] = {}
            for k in journal:
                g = pdo_group(k[0])
                if g is not None:
                    groups.setdefault(g, []).append(k)
            stale_first = [k for k in first if self._differs(sdo, k, journal[k])]
            stale_plain = [k for k in plain if self._differs(sdo, k, journal[k])]
            stale_groups = [
                g for g, ks in groups.items() if any(self._differs(sdo, k, journal[k]) for k in ks)
            ]
        except DriveError as exc:
            report.failed["drive"] = f"no answer to read-back: {exc}"
            report.seconds = time.monotonic() - t0
            return report
        if stale_first or stale_plain or stale_groups:
            report.reboot = True
        if journal and (PRODUCER_HEARTBEAT, 0) not in journal:
            self._refresh_producer_time(sdo)  # another master may have changed it
        if report.reboot and not boot:
            with self._lock:
                self.boots_seen += 1
        # 1. the host heartbeat producer runs (the consumer must see it from its first period)
        if report.reboot and self.restart_producer is not None:
            try:
                self.restart_producer()
                report.written.append("host heartbeat producer")
            except Exception as exc:
                report.failed["host heartbeat producer"] = str(exc)
        # 2. the supervision objects, then the rest, PDOs last
        for k in stale_first + stale_plain:
            self._write(sdo, k, journal[k], report)
            if k[0] == CONSUMER_HEARTBEAT and self.send_heartbeat is not None:
                # CiA 301: the consumer starts watching at the first heartbeat it receives
                # after being configured; one now means a host that dies this instant is caught
                try:
                    self.send_heartbeat()
                except Exception as exc:
                    report.failed["host heartbeat"] = str(exc)
        for g in stale_groups:
            write_pdo_group(sdo, g, groups[g], journal, report)
        report.seconds = time.monotonic() - t0
        if report.reboot:
            report.at = _now_iso()
            if not report.failed:
                self.rearmed_at = report.at
        self.last_report = report
        return report

    def _refresh_producer_time(self, sdo: SdoChannel) -> None:
        try:
            raw = SdoChannel.upload(sdo, PRODUCER_HEARTBEAT, 0)
        except DriveError:
            return
        with self._lock:
            self._producer_ms = int.from_bytes(raw[:2], "little")

    @staticmethod
    def _differs(sdo: SdoChannel, key: tuple[int, int], data: bytes) -> bool:
        try:
            got = SdoChannel.upload(sdo, key[0], key[1])
        except DriveError as exc:
            if getattr(exc, "code", None) is not None:
                return True  # refused read (object gone?): try writing it
            raise
        return got[: len(data)] != data or len(got) < len(data)

    @staticmethod
    def _write(sdo: SdoChannel, key: tuple[int, int], data: bytes, report: RearmReport) -> None:
        write_entry(sdo, key, data, report)

    # ------------------------------------------------------------------ summary
    def status(self) -> dict[str, Any]:
        """``boots_seen``, ``supervision_rearmed_at`` and the gate state for displays."""
        with self._lock:
            return {
                "boots_seen": self.boots_seen,
                "supervision_rearmed_at": self.rearmed_at,
                "supervision_ready": self._ready and self._error is None,
                "supervision_error": self._error,
            }
