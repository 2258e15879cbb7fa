"""``drive-link shell``: placeholder (being built)."""

from __future__ import annotations

import argparse

from .drive import Drive

__all__ = ["cmd_shell"]


def cmd_shell(args: argparse.Namespace, d: Drive) -> int:
    """Interactive session (not finished yet)."""
    print("drive-link shell: not finished yet")
    return 1
