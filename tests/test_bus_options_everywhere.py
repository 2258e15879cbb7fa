"""Every command line takes python-can's own bus options (the README's promise), from one helper
(drive_link.cli.connect), and drive-dashboard hands them to can.Bus.

Truth: python-can's own ``can.cli.add_bus_arguments`` (the option set it defines) and the
python-can bus the dashboard opened (its attributes)."""

from __future__ import annotations

import argparse
import uuid

import can
import can.cli
import pytest

from dashboard import cli as dashboard_cli
from dashboard.config import BenchConfig
from drive_link import cli as link_cli
from drive_link.cli.connect import bus_extras_from_args

pytestmark = pytest.mark.timeout(60)


def _python_can_flags() -> set[str]:
    scratch = argparse.ArgumentParser(add_help=False)
    can.cli.add_bus_arguments(scratch)
    return {s for a in scratch._actions for s in a.option_strings if s.startswith("--")}


def _flags(parser: argparse.ArgumentParser) -> set[str]:
    return {s for a in parser._actions for s in a.option_strings}


@pytest.mark.unit
def test_drive_link_and_drive_dashboard_take_every_python_can_bus_option():
    wanted = _python_can_flags()
    assert {"--bus-kwargs", "--fd", "--timing", "--interface", "--bitrate"} <= wanted
    assert wanted <= _flags(link_cli.build_parser())
    assert wanted <= _flags(dashboard_cli.build_parser())


@pytest.mark.unit
@pytest.mark.parametrize(
    "extra",
    [
        ["--fd", "--data-bitrate", "2000000"],
        ["--timing", "f_clock=8000000", "brp=1", "tseg1=5", "tseg2=2", "sjw=1", "nof_samples=1"],
    ],
)
def test_dashboard_parses_fd_timing_and_bus_kwargs_like_python_can(extra):
    argv = ["--interface", "virtual", "--channel", "x",
            "--bus-kwargs", "receive_own_messages=True", *extra]  # fmt: skip
    args = dashboard_cli.build_parser().parse_args(argv)
    ours = bus_extras_from_args(args)
    # python-can's own parser of the same words is the truth
    scratch = argparse.ArgumentParser()
    can.cli.add_bus_arguments(scratch)
    ns = vars(scratch.parse_args(argv))  # as can.cli.create_bus_from_namespace reads it
    theirs = {k: v for k, v in ns.items() if k != "bus_kwargs"} | ns["bus_kwargs"]
    theirs = {k: v for k, v in theirs.items() if v not in (None, False)}
    keys = {"receive_own_messages", *(k for k in ("fd", "data_bitrate", "timing") if k in theirs)}
    assert len(keys) >= 2
    for key in keys:
        assert ours[key] == theirs[key], key


@pytest.mark.unit
def test_bus_options_on_the_hub_are_one_clear_error():
    cfg = BenchConfig(virtual=True, bus_options={"fd": True})
    with pytest.raises(ValueError, match="--fd applies to an --interface bus"):
        cfg.validate()


def test_dashboard_bench_opens_the_bus_with_the_bus_kwargs(tmp_path):
    from dashboard._virtual import open_bench
    from virtual_drive.node import VirtualDrive

    ch = f"opts-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=3, store_path=tmp_path / "p.json").start()
    try:
        args = dashboard_cli.build_parser().parse_args(
            ["--interface", "virtual", "--channel", ch, "--node", "3",
             "--bus-kwargs", "receive_own_messages=True", "rx_queue_size=77"]
        )  # fmt: skip
        cfg = BenchConfig(
            interface=args.interface,
            channel=args.channel,
            node_id=args.node,
            bus_options=bus_extras_from_args(args),
        )
        cfg.validate()
        with open_bench(cfg) as bench:
            opened = bench.drive.bus
            assert opened.receive_own_messages is True
            assert opened.queue.maxsize == 77
    finally:
        vd.stop()
        bus.shutdown()
