"""`rapidfix upload`: send a program to the robot controller over a serial link.

The controller must run the receiver shipped with rapidfix
(`rapidfix/link/rapid/RfxRecv.mod`). `--simulate` runs a simulated controller
behind a pseudo-terminal instead, so the whole path can be tried without a robot.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from rapidfix.exceptions import LinkError
from rapidfix.link import (
    MAX_PAYLOAD,
    OVERHEAD,
    RECEIVER_MODULE,
    LinkSettings,
    SimulatedController,
    UploadResult,
    plan_upload,
    upload_file,
)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `upload` subcommand."""
    defaults = LinkSettings()
    parser = subparsers.add_parser(
        "upload",
        help="send a program to the controller over a serial link",
        description=(
            "Send PROG to the controller over RS-232. The controller runs the "
            f"receiver RfxRecv.mod shipped with rapidfix ({RECEIVER_MODULE}); it "
            "writes the file under a temporary name, verifies it and only then "
            "renames it into place. An interrupted upload resumes when run again."
        ),
    )
    parser.add_argument("program", metavar="PROG", type=Path, help="the file to send")
    parser.add_argument("--port", help="serial port, e.g. /dev/ttyUSB0 or COM3")
    parser.add_argument("--baud", type=int, default=115200, help="line rate (default 115200)")
    parser.add_argument("--name", help="file name on the controller (default: PROG's name)")
    parser.add_argument("--load", action="store_true", help="load the module once in place")
    parser.add_argument(
        "--simulate",
        nargs="?",
        const="",
        metavar="DIR",
        help="send to a simulated controller whose disk is DIR (default: a new temporary folder)",
    )
    parser.add_argument(
        "--dry-run", action="store_true", help="report what would be sent; no port needed"
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=defaults.timeout,
        help=(
            f"seconds without progress before sending again (default {defaults.timeout:g}; "
            "HELLO and END double it after each silence, up to 4x)"
        ),
    )
    parser.add_argument(
        "--retries",
        type=int,
        default=defaults.retries,
        help=f"time-outs in a row before giving up (default {defaults.retries})",
    )
    parser.add_argument(
        "--window",
        type=int,
        default=defaults.window,
        help=f"frames sent ahead of acknowledgements (default {defaults.window})",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Send (or with --dry-run describe) the upload; 0 on success."""
    source: Path = args.program
    name = args.name or source.name
    if args.baud <= 0 or args.timeout <= 0 or args.retries < 0 or args.window < 1:
        raise LinkError("--baud, --timeout and --window must be positive, --retries not negative")
    if args.load:
        _check_loadable(source)
    if args.dry_run:
        return _dry_run(source, name, args)
    settings = LinkSettings(timeout=args.timeout, retries=args.retries, window=args.window)
    progress = sys.stderr.isatty()
    if args.simulate is not None:
        folder = Path(args.simulate) if args.simulate else Path(tempfile.mkdtemp(prefix="rfx-"))
        with SimulatedController(folder, baud=args.baud, paced=True) as sim:
            result = upload_file(source, sim.port, args.baud, name, args.load, settings, progress)
        _report(result, f"the simulated controller in {folder}", args.baud)
        return 0
    if not args.port:
        raise LinkError("no serial port given", hint="use --port PORT, or --simulate to try it")
    result = upload_file(source, args.port, args.baud, name, args.load, settings, progress)
    _report(result, args.port, args.baud)
    return 0


def _check_loadable(source: Path) -> None:
    """Refuse, before a byte is sent, a module the controller's Load would refuse for its
    syntax: at 9,600 baud a large program takes many minutes on the line."""
    from rapidfix.exceptions import RapidSyntaxError
    from rapidfix.rapid import parse_program

    try:
        parse_program(_read(source), str(source))
    except RapidSyntaxError as err:
        err.hint = ("nothing was sent: the controller would not load it; fix it, or send it "
                    "without --load")
        raise


def _read(source: Path) -> bytes:
    """The bytes of the file to send (a LinkError naming it when it cannot be read)."""
    try:
        return source.read_bytes()
    except OSError as err:
        raise LinkError(f"cannot read {source}: {err.strerror or err}", file=source) from None


def _dry_run(source: Path, name: str, args: argparse.Namespace) -> int:
    data = _read(source)
    plan = plan_upload(data, name, args.load)
    overhead = plan.wire_bytes - plan.size
    print(
        f"would send {source} as {plan.name}: {plan.size} bytes in {plan.frames} data "
        f"frames of up to {MAX_PAYLOAD} bytes (+{OVERHEAD} bytes framing each)"
    )
    print(
        f"HELLO, {plan.frames} DATA, END: {plan.wire_bytes} bytes on the line "
        f"({overhead} bytes overhead), file CRC-16 0x{plan.crc:04X}"
    )
    print(
        f"at least {plan.line_seconds(args.baud):.1f} s at {args.baud} baud (8N1)"
        + ("; then Load" if args.load else "")
    )
    return 0


def _report(result: UploadResult, where: str, baud: int) -> None:
    line_s = result.size * 10 / baud
    share = line_s / result.elapsed_s if result.elapsed_s > 0 else 0.0
    parts = [
        f"sent {result.name} ({result.size} bytes, {result.frames} frames) to {where} "
        f"in {result.elapsed_s:.1f} s ({share:.0%} of the line rate)"
    ]
    if result.resumed_from:
        parts.append(f"resumed at frame {result.resumed_from}")
    if result.resent:
        parts.append(f"{result.resent} frames sent again")
    if result.loaded:
        parts.append("loaded")
    print("; ".join(parts))
