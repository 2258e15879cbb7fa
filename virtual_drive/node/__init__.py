"""The virtual drive as a CANopen CiA 402 node (CiA 301 services completed around canopen's
LocalNode: NMT, block SDO on two servers, heartbeat producer/consumer, PDOs coupled to the OD,
EMCY bookkeeping, store/restore, gain sets and the trace recorder).

Python API::

    from virtual_drive.node import VirtualDrive, spawn_virtual_drive
    drive = VirtualDrive(bus, node_id=1, store_path=None, speed=1.0).start()
    drive.sim            # the virtual_drive.sim.Simulator being served
    drive.stop()
"""

from .drive_node import MEASUREMENTS, VirtualDrive
from .process import DriveProcess, spawn_virtual_drive

__all__ = ["MEASUREMENTS", "DriveProcess", "VirtualDrive", "spawn_virtual_drive"]
