"""End-to-end scenarios written once and run under each bench condition (idle, busy host,
USB-adapter latency, frame loss, real SocketCAN): see ``conditions.py`` and ``test_matrix.py``."""
