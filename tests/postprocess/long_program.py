"""A long program made of the ballbar sample's targets: for tests that interrupt a rewrite."""

from __future__ import annotations

from pathlib import Path

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def long_program(n_moves: int) -> str:
    """The ballbar module with its main routine replaced by n_moves MoveJ over its 19
    targets (joint moves: no intermediate points, so the time goes into the targets)."""
    text = (SAMPLES / "ballbar.mod").read_text()
    head = text[: text.index("    PROC main()")]
    moves = [f"        MoveJ pBB{k % 19:02d}, v200, z10, tBallbar\\WObj:=wobjBallbar;"
             for k in range(n_moves)]
    return head + "    PROC main()\n" + "\n".join(moves) + "\n    ENDPROC\nENDMODULE\n"
