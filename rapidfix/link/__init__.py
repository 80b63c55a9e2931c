"""Serial upload of programs to the robot controller, for cells without a network.

- :mod:`~rapidfix.link.protocol`: frame layout, kinds, statuses, the frame decoder.
- :mod:`~rapidfix.link.checksum`: CRC-16/CCITT-FALSE, computable in RAPID.
- :mod:`~rapidfix.link.uploader`: the host side on pyserial (go-back-N window).
- :mod:`~rapidfix.link.receiver`: the controller's state machine in Python.
- :mod:`~rapidfix.link.simulator`: that receiver behind a pseudo-terminal.
- :mod:`~rapidfix.link.faults`: seeded fault injection on the simulated line.
- ``rapid/RfxRecv.mod``: the receiver in RAPID, loaded once on the controller.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from rapidfix import lazy_exports
from rapidfix.link.faults import LinkFaults
from rapidfix.link.protocol import PROTOCOL_VERSION
from rapidfix.link.simulator import SimulatedController
from rapidfix.link.uploader import (
    LinkSettings,
    Uploader,
    UploadPlan,
    UploadResult,
    open_port,
    plan_upload,
    upload_file,
)

RECEIVER_MODULE = Path(__file__).parent / "rapid" / "RfxRecv.mod"

if TYPE_CHECKING:  # what type checkers and IDEs see of the lazy exports
    from rapidfix.link.protocol import MAX_PAYLOAD, OVERHEAD

# The other exports, name -> module of this package: each is imported from its module on
# first use (PEP 562), so exporting a name costs nothing until it is used.
# To add one: ARCHITECTURE.md, "Exports".
LAZY_EXPORTS = {
    "MAX_PAYLOAD": "protocol",
    "OVERHEAD": "protocol",
}

__all__ = [
    "MAX_PAYLOAD",
    "OVERHEAD",
    "PROTOCOL_VERSION",
    "RECEIVER_MODULE",
    "LinkFaults",
    "LinkSettings",
    "SimulatedController",
    "UploadPlan",
    "UploadResult",
    "Uploader",
    "open_port",
    "plan_upload",
    "upload_file",
]

__getattr__, __dir__ = lazy_exports(__name__, LAZY_EXPORTS)
