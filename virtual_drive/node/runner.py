"""Pacing loop: runs the simulation in chunks so that simulated time follows wall-clock time.

Every ``period`` (1 ms) of wall-clock time the loop asks for the samples that bring the
simulation to ``speed × elapsed wall time`` (50 samples at speed 1, 500 at speed 10), runs them
in one call (``step(n)``), then runs the periodic services (``periodic(now)``: heartbeats,
consumer timeouts) and the ``timer`` (the TPDO engine: sends what is due, in one batch, and says
when the next frame is due). The thread sleeps until the next tick or the next due frame,
whichever comes first, so an event-driven TPDO with an inhibit time goes out on its exact time
and not on the next tick; with the default rates (multiples of 1 ms, aligned to the tick grid
by :meth:`Runner.align`) it wakes once per millisecond. The simulation never runs per sample
in Python.

After a stall (the process was not scheduled) the loop catches up the backlog without sleeping,
in chunks of at most ``max_chunk`` (5 ms of simulated time) with the periodic services run
between them, so simulated time returns to wall-clock time within milliseconds of the stall's
end; only a backlog longer than ``max_lag`` (30 s) is dropped and counted in
:attr:`RunnerStats.dropped_s`. The chunk bound matters on a busy host: the drive decides once
per chunk (e.g. a stop ramp ends when |speed| < 10 rpm), so a 0.1 s chunk let a quick stop at
the 100 A limit brake through zero to −141 rpm; 5 ms bounds that to about 13 rpm, and catch-up
still runs at about 80× real time (250-sample chunks; 140× with 0.1 s chunks, measured here).

Several drives in one process share one :class:`Pacer` (one thread, one wake-up per tick for
all of them): ``Runner(..., pacer=shared)``, or :meth:`Pacer.adopt` for a drive's own runner
before it starts. Each runner keeps its own start time, sample count and statistics; an
exception in one drive's step stops that runner (:attr:`Runner.error`), not the others.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["TS", "Pacer", "Runner", "RunnerStats"]

logger = logging.getLogger(__name__)

TS = 20e-6  #: loop sample time (s), fs = 50 kHz


@dataclass
class RunnerStats:
    """Timing figures of the pacing loop (seconds unless stated)."""

    iterations: int = 0
    samples: int = 0
    max_lag_s: float = 0.0  #: largest |sim time - speed × wall time| seen after a chunk
    last_lag_s: float = 0.0
    dropped_s: float = 0.0  #: simulated time skipped after stalls
    max_chunk: int = 0  #: most samples in one chunk


class Runner:
    """Paces ``step`` to wall-clock time (on its own :class:`Pacer` thread unless given one).

    :param step: runs ``n`` simulation samples (all chunk work: sim, recorder, faults).
    :param periodic: called with ``time.monotonic()`` after each chunk.
    :param speed: simulated seconds per wall-clock second.
    :param period: wall-clock loop period (s) of the runner's own pacer.
    :param max_lag: largest backlog of simulated time caught up after a stall (s).
    :param max_chunk: most simulated time run in one call (s).
    :param timer: ``timer(now) -> seconds until it is due again``, called after the periodic
        services and whenever that time comes (the TPDO engine's ``tick``).
    :param pacer: a shared :class:`Pacer` (several drives, one thread).
    :param timer_at: ``timer_at(t) -> monotonic time it is due next``: the timer of a drive
        whose frames carry their bus time (:meth:`PdoEngine.tick_at`). Given, the chunk of a
        tick is run in pieces that end at the timer's due points and the timer runs at each,
        with the simulation standing at that time; the thread then wakes only once per
        ``period`` (e.g. 10 ms: a tenth of the wake-ups and socket writes of 1 ms ticks) and
        the frames still show their exact event-timer spacing on the bus.
    :param flush: called at the end of each timed tick (the bus writes the frames it held).
    :param step_timed: ``step_timed(n, at, at_point) -> bool``: runs a timed tick's ``n``
        samples in one call and calls ``at_point(j)`` with the values of the instant ``at[j]``
        samples in (:meth:`VirtualDrive._step_timed`); False: it cannot now (nothing done),
        the tick goes in pieces.
    :param due_times: ``due_times(until) -> [t, ...]``: the instants (monotonic s) ``timer_at``
        will be due at up to ``until`` (:meth:`PdoEngine.due_times`), for ``step_timed``.
    """

    def __init__(
        self,
        step: Callable[[int], None],
        periodic: Callable[[float], None],
        speed: float = 1.0,
        period: float = 1e-3,
        max_lag: float = 30.0,
        max_chunk: float = 0.005,
        timer: Callable[[float], float] | None = None,
        pacer: Pacer | None = None,
        timer_at: Callable[[float], float] | None = None,
        flush: Callable[[], None] | None = None,
        step_timed: Callable[[int, list[int], Callable[[int], None]], bool] | None = None,
        due_times: Callable[[float], list[float]] | None = None,
    ) -> None:
        if not speed > 0:
            raise ValueError("speed must be > 0")
        self._step = step
        self._periodic = periodic
        self.timer = timer
        self.timer_at = timer_at
        self._flush = flush
        self._step_timed = step_timed if due_times is not None else None
        self._due_times = due_times
        self.speed = float(speed)
        self.period = float(period)
        self.max_lag = float(max_lag)
        self.max_chunk = float(max_chunk)
        self.stats = RunnerStats()
        self.error: BaseException | None = None
        self._pacer = pacer
        self._own_pacer = pacer is None
        #: ticked by its pacer (False before start, after stop or a failure)
        self.active = False
        self._t0 = 0.0
        self._done = 0
        self._max_n = 1
        self._chunk_n = 1
        self.timer_due = 0.0  #: monotonic time the timer wants to run next
        #: held while a tick runs the simulation (the pacer's, or :meth:`catch_up`'s)
        self._tick_lock = threading.Lock()

    # -- lifecycle ------------------------------------------------------------------------
    def start(self) -> None:
        if self.active:
            return
        if self._pacer is None:
            self._pacer = Pacer(self.period)
            self._own_pacer = True
        self.error = None
        self._t0 = time.monotonic()
        self._done = 0  # samples run since t0 (plus dropped ones)
        self._max_n = max(1, round(self.max_lag / TS))
        # at least 4 loop periods' worth, so a high --speed never outruns the chunk limit
        self._chunk_n = max(
            round(self.max_chunk / TS), math.ceil(4 * self._pacer.period * self.speed / TS)
        )
        self.timer_due = self._t0 if self.timer_at is not None else 0.0
        self.active = True
        self._pacer.add(self)
        self._pacer.start()

    def stop(self, timeout: float = 5.0) -> None:
        if self._pacer is None:
            return
        self.active = False
        self._pacer.remove(self, timeout)
        if self._own_pacer:
            self._pacer.stop(timeout)

    @property
    def running(self) -> bool:
        return self.active and self._pacer is not None and self._pacer.running

    def align(self, t: float) -> float:
        """The first tick of this runner's pacer at or after ``t`` (monotonic s); ``t`` itself
        when not running. TPDO event timers start on it, so they share the tick's wake-up."""
        pacer = self._pacer
        return t if pacer is None or not pacer.running else pacer.align(t)

    def catch_up(self, timeout: float = 0.005) -> bool:
        """Run the simulation up to now, on the calling thread: an SDO read of a measurement
        then answers with the value of the moment it was asked, not of the last tick (up to
        one period old: 10 ms on the hub). The tick's TPDOs due meanwhile go out with their
        own values, as the pacer would send them; the periodic services wait for the pacer.

        Does nothing on the pacer's own thread (a TPDO's payload is read inside its tick) and
        gives up after ``timeout`` s when a tick is running (a busy host): the value is then
        the one the running tick leaves. Returns True when it ran."""
        pacer = self._pacer
        if not self.active or pacer is None or threading.get_ident() == pacer.thread_ident:
            return False
        if not self._tick_lock.acquire(timeout=timeout):
            return False
        try:
            if self.active:
                self._run_sim(time.monotonic())
        except Exception as exc:  # as on the pacer: the runner stops and says why
            self.fail(exc)
        finally:
            self._tick_lock.release()
        return True

    # -- one tick (pacer thread) ----------------------------------------------------------
    def tick(self, now: float) -> None:
        with self._tick_lock:
            self._run_sim(now)
            self._periodic(time.monotonic())
            self.stats.iterations += 1

    def _run_sim(self, now: float) -> None:
        """The samples that bring the simulation to ``now`` (at most one chunk), the timer's
        TPDOs due meanwhile, and the pacing statistics."""
        stats = self.stats
        target = int((now - self._t0) * self.speed / TS)
        n = target - self._done
        if n > self._max_n:
            skipped = n - self._max_n
            stats.dropped_s += skipped * TS
            self._done += skipped
            n = self._max_n
            logger.warning(
                "pacing loop behind: %.1f ms of simulated time dropped", skipped * TS * 1e3
            )
        # (a catch_up may have run past the `now` this tick read before it took the lock)
        n = max(0, min(n, self._chunk_n))
        if self.timer_at is not None:
            self._run_timed(n, now)
        elif n > 0:
            self._step(n)
            self._done += n
            stats.samples += n
            stats.max_chunk = max(stats.max_chunk, n)
        lag = (time.monotonic() - self._t0) * self.speed - self._done * TS
        stats.last_lag_s = lag
        if abs(lag) > stats.max_lag_s and stats.iterations > 0:
            stats.max_lag_s = abs(lag)

    def _run_timed(self, n: int, now: float) -> None:
        """Run ``n`` samples in pieces that end at the due points of :attr:`timer_at` up to
        ``now``; the timer runs at each (its frames carry that time), and once more at the
        end (a reconfigured TPDO is seen within one tick)."""
        scale = self.speed / TS
        t0 = self._t0
        end = self._done + n
        # catching up after a stall (more than this chunk behind): no frame per due point; the
        # timer below sends one per TPDO and counts the missed periods, as the 1 ms ticks do
        behind = (now - t0) * scale - end > 0.5 * self._chunk_n
        # the whole tick in one simulator call, the timer run at each due point; else in pieces
        if behind or self._step_timed is None or not self._run_points(end, now):
            while not behind:
                due = self.timer_due
                if due > now:
                    break
                k = math.ceil((due - t0) * scale - 1e-9)  # the sample that reaches `due`
                if k > end:
                    break  # (catching up: the rest of the backlog comes in the next chunks)
                self._run_to(k)
                self._run_timer_at(due, now)
            self._run_to(end)
        # where the simulation stands now: sees a reconfigured TPDO within one tick
        self._run_timer_at(t0 + end / scale, now)
        if self._flush is not None:
            self._flush()  # the tick's frames in one write

    def _run_points(self, end: int, now: float) -> bool:
        """The samples up to ``end`` in one ``step_timed`` call, the timer run at each of its
        due points up to ``now`` whose sample is reached by then; False: not possible now."""
        step_timed, due_times, timer_at = self._step_timed, self._due_times, self.timer_at
        if step_timed is None or due_times is None or timer_at is None:
            return False  # (not a timed runner: _run_timed does not call this then)
        scale = self.speed / TS
        t0 = self._t0
        done = self._done
        dues = []
        at = []
        for due in due_times(now):
            k = math.ceil((due - t0) * scale - 1e-9)  # the sample that reaches `due`
            if k > end:
                break  # (its sample comes with the next tick)
            dues.append(due)
            at.append(k - done if k > done else 0)

        def at_point(j: int) -> None:  # (_run_timer_at inlined: this runs at every due point)
            try:
                self.timer_due = timer_at(dues[j])
            except Exception:  # the timer never dies: log, retry in 10 ms
                logger.exception("pacer timer")
                self.timer_due = now + 0.01

        if not step_timed(end - done, at, at_point):
            return False
        self._count_to(end)
        return True

    def _run_to(self, k: int) -> None:
        """Run the samples up to sample ``k`` (counted from the start) in one step."""
        m = k - self._done
        if m > 0:
            self._step(m)
            self._count_to(k)

    def _count_to(self, k: int) -> None:
        """The samples up to sample ``k`` have run: the count and the statistics follow."""
        m = k - self._done
        if m > 0:
            self._done = k
            stats = self.stats
            stats.samples += m
            if m > stats.max_chunk:
                stats.max_chunk = m

    def _run_timer_at(self, at: float, now: float) -> None:
        timer_at = self.timer_at
        if timer_at is None:  # (only _run_timed calls this, on a timed runner)
            return
        try:
            self.timer_due = timer_at(at)
        except Exception:  # the timer never dies: log, retry in 10 ms
            logger.exception("pacer timer")
            self.timer_due = now + 0.01

    def behind(self, now: float) -> bool:
        """More than one chunk of backlog (catch-up: no sleeping)."""
        return (now - self._t0) * self.speed / TS - self._done > self._chunk_n

    def service_timer(self, now: float) -> float:
        """Run the timer (it sends what is due); returns when it is due next (monotonic s).
        The timer never dies: an error is logged and it is retried in 10 ms."""
        if self.timer is None:
            return math.inf
        try:
            self.timer_due = time.monotonic() + self.timer(now)
        except Exception:
            logger.exception("pacer timer")
            self.timer_due = now + 0.01
        return self.timer_due

    def join_pacer(self, pacer: Pacer) -> None:
        """Run on ``pacer`` (shared with other runners) from :meth:`start` on."""
        if self.active:
            raise RuntimeError("adopt a runner before it starts")
        self._pacer = pacer
        self._own_pacer = False

    @property
    def pacer(self) -> Pacer | None:
        """The pacer this runner runs on (None before :meth:`start` without a shared one)."""
        return self._pacer

    def fail(self, exc: BaseException) -> None:
        self.error = exc
        self.active = False
        logger.exception("pacing loop stopped")


class Pacer:
    """One thread that ticks every ``period`` s and runs the chunks of all its runners.

    :param period: wall-clock loop period (s).
    """

    def __init__(self, period: float = 1e-3) -> None:
        if not period > 0:
            raise ValueError("period must be > 0")
        self.period = float(period)
        self._runners: list[Runner] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._t0 = 0.0
        self._k = 0
        #: called (on the pacer thread) after each pass of the timers and at the end of every
        #: wake-up: a shared connection writes the frames collected meanwhile in one go
        self.flush_hooks: list[Callable[[], None]] = []

    def adopt(self, runner: Runner) -> Runner:
        """Let ``runner`` (not started yet) run on this pacer when it starts."""
        runner.join_pacer(self)
        return runner

    def add(self, runner: Runner) -> None:
        with self._lock:
            if runner not in self._runners:
                self._runners = [*self._runners, runner]

    def remove(self, runner: Runner, timeout: float = 5.0) -> None:
        with self._lock:
            self._runners = [r for r in self._runners if r is not runner]
        # a chunk of this runner may be running right now: wait for the tick to end
        if self._thread is not None and self._thread is not threading.current_thread():
            end = time.monotonic() + timeout
            seen = self._k
            while self._thread.is_alive() and self._k == seen and time.monotonic() < end:
                time.sleep(self.period / 4)

    def start(self) -> None:
        if self._thread is not None and self._thread.is_alive():
            return
        self._stop.clear()
        self._t0 = time.monotonic()
        self._k = 0
        self._thread = threading.Thread(target=self._run, name="virtual-drive-pacer", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        if self._thread is not None:
            if self._thread is not threading.current_thread():  # (a step may stop its drive)
                self._thread.join(timeout)
            self._thread = None

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def thread_ident(self) -> int | None:
        """``threading.get_ident()`` of the pacer thread (None before :meth:`start`)."""
        return None if self._thread is None else self._thread.ident

    def _flush(self) -> None:
        for hook in self.flush_hooks:
            try:
                hook()
            except Exception:  # a failing write is the bus's business (it reports it lost)
                logger.exception("pacer flush hook")

    def align(self, t: float) -> float:
        """First tick time at or after ``t`` (monotonic s)."""
        k = math.ceil((t - self._t0) / self.period - 1e-9)
        return self._t0 + k * self.period

    def _run(self) -> None:
        try:
            self._loop()
        except BaseException:  # report, never die silently
            logger.exception("pacer stopped")
            for r in self._runners:
                r.error = r.error or RuntimeError("pacer stopped")

    def _loop(self) -> None:
        period = self.period
        next_tick = self._t0
        while not self._stop.is_set():
            runners = self._runners
            now = time.monotonic()
            wake = math.inf
            # frames due now go first (with the values of the last chunk): a frame due on
            # its exact time (inhibit) never waits for a simulation chunk
            for r in runners:
                if r.active and r.timer is not None and now >= r.timer_due:
                    if r.timer_at is None:  # (timed runners run theirs inside the chunk)
                        wake = min(wake, r.service_timer(now))
            if self.flush_hooks:
                self._flush()
            if now >= next_tick:
                behind = False
                for r in runners:
                    if not r.active:
                        continue
                    try:
                        r.tick(now)
                        behind = behind or r.behind(time.monotonic())
                    except BaseException as exc:
                        r.fail(exc)
                self._k += 1
                if not behind:
                    next_tick += period
                    if next_tick < time.monotonic() - period * 10:
                        # re-align after a stall
                        k = int((time.monotonic() - self._t0) / period) + 1
                        next_tick = self._t0 + k * period
                # once per tick: what fell due during the chunks, and when the next is due
                # (a reconfigured TPDO is seen within one tick)
                now = time.monotonic()
                wake = math.inf
                for r in runners:
                    if r.active and r.timer is not None and r.timer_at is None:
                        wake = min(wake, r.service_timer(now))
            else:
                for r in runners:
                    if r.active and r.timer is not None and r.timer_at is None:
                        wake = min(wake, r.timer_due)
            if self.flush_hooks:
                self._flush()
            delay = min(wake, next_tick) - time.monotonic()
            if delay > 0:
                self._stop.wait(delay) if delay > 0.02 else time.sleep(delay)
