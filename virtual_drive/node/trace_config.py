"""Writes of the trace configuration 0x2100 / channels 0x2101 and their copy into the recorder.

Channels and the trigger source must be 0x2040 measurements of the right bit length (else abort
0x06090030); while the recorder is armed or recording the configuration is frozen (0x08000022);
the command 0x2100:9 stops, arms (after copying the objects into the recorder) or forces.

:class:`TraceConfig` joins the two owners: the configuration objects live in the parameter
store (:class:`.DriveLocalNode`), the recorder (:class:`.TraceRecorder`) owns the copy it
records with and its state.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.od import load_od

from .local_node import DriveLocalNode
from .od_maps import MEASUREMENTS
from .recorder import (
    ARMED,
    CMD_ARM,
    CMD_FORCE,
    CMD_STOP,
    RECORDING,
    TraceConfigError,
    TraceRecorder,
)

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
MEASUREMENTS_INDEX = _OD.index_of("measurements")
TRACE_CHANNEL_COUNT = _OD.address("trace_config.channel_count")
TRACE_DIVIDER = _OD.address("trace_config.divider")
TRACE_LENGTH = _OD.address("trace_config.length")
TRACE_PRE_TRIGGER = _OD.address("trace_config.pre_trigger")
TRACE_TRIGGER_SOURCE = _OD.address("trace_config.trigger_source")
TRACE_TRIGGER_SOURCE_SUB = TRACE_TRIGGER_SOURCE[1]
TRACE_TRIGGER_LEVEL = _OD.address("trace_config.trigger_level")
TRACE_TRIGGER_EDGE = _OD.address("trace_config.trigger_edge")
TRACE_TRIGGER_MODE = _OD.address("trace_config.trigger_mode")
TRACE_COMMAND_SUB = _OD.address("trace_config.command")[1]
TRACE_CHANNELS_INDEX = _OD.index_of("trace_channels")

__all__ = ["TraceConfig"]

WriteResult = tuple[bool, Callable[[], None] | None]


class TraceConfig:
    """Writes of 0x2100/0x2101 checked against the recorder's state, and the recorder's set-up.

    :param node: the parameter store holding 0x2100/0x2101.
    :param recorder: the trace recorder.
    """

    def __init__(self, node: DriveLocalNode, recorder: TraceRecorder) -> None:
        self.node = node
        self.recorder = recorder

    def write(self, sub: int, value: Any) -> WriteResult:
        """0x2100:``sub`` := ``value`` (already checked against the EDS): store it?
        follow-up?"""
        rec = self.recorder
        if sub == TRACE_COMMAND_SUB:
            if value == CMD_STOP:
                return True, rec.stop
            self.configure_recorder()
            if value == CMD_ARM:
                try:
                    rec.arm()
                except TraceConfigError as exc:
                    raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
            elif value == CMD_FORCE:
                rec.force()
            return True, None
        if rec.state in (ARMED, RECORDING):  # configuration is frozen
            raise SdoAbortedError(abort_codes.DEVICE_STATE)
        if sub == TRACE_TRIGGER_SOURCE_SUB:
            self.check_channel(value, allow_zero=False)
        return True, None

    def check_channel(self, ref: int, allow_zero: bool = True) -> None:
        """Abort 0x06090030 unless ``ref`` (index << 16 | sub << 8 | bits) is a 0x2040
        measurement with its bit length (0 = unused channel, when ``allow_zero``)."""
        if ref == 0 and allow_zero:
            return
        index, sub, bits = (ref >> 16) & 0xFFFF, (ref >> 8) & 0xFF, ref & 0xFF
        if index != MEASUREMENTS_INDEX or sub not in MEASUREMENTS:
            raise SdoAbortedError(abort_codes.INVALID_VALUE)
        if bits != len(self.node.find_object(index, sub)):
            raise SdoAbortedError(abort_codes.INVALID_VALUE)

    def configure_recorder(self) -> None:
        """Copy 0x2100/0x2101 into the recorder (before arming)."""
        rec = self.recorder
        param = self.node.param
        count = param(TRACE_CHANNEL_COUNT)
        channels = []
        for k in range(1, count + 1):
            ref = self.node.value(TRACE_CHANNELS_INDEX, k)
            sub = (ref >> 8) & 0xFF
            if (ref >> 16) != MEASUREMENTS_INDEX or sub not in MEASUREMENTS:
                raise SdoAbortedError(abort_codes.INVALID_VALUE)
            channels.append(MEASUREMENTS[sub])
        src = param(TRACE_TRIGGER_SOURCE)
        if (src >> 16) != MEASUREMENTS_INDEX or ((src >> 8) & 0xFF) not in MEASUREMENTS:
            raise SdoAbortedError(abort_codes.INVALID_VALUE)
        length = param(TRACE_LENGTH)
        pre = param(TRACE_PRE_TRIGGER)
        divider = param(TRACE_DIVIDER)
        try:
            rec.check(channels, length, pre, divider)
        except TraceConfigError as exc:
            raise SdoAbortedError(abort_codes.INVALID_VALUE) from exc
        rec.channels = channels
        rec.length = length
        rec.pre_trigger = pre
        rec.divider = divider
        rec.trigger_source = MEASUREMENTS[(src >> 8) & 0xFF]
        rec.trigger_level = float(param(TRACE_TRIGGER_LEVEL))
        rec.trigger_edge = param(TRACE_TRIGGER_EDGE)
        rec.trigger_mode = param(TRACE_TRIGGER_MODE)
