"""`rapidfix upload` on the command line: dry run, simulated controller, user errors."""

import argparse

import pytest

from rapidfix.commands import upload
from rapidfix.exceptions import LinkError, RapidSyntaxError


def run(argv):
    parser = argparse.ArgumentParser()
    upload.register(parser.add_subparsers())
    args = parser.parse_args(["upload", *argv])
    return args.func(args)


def test_upload_is_a_registered_command():
    from rapidfix import cli

    assert "upload" in cli.COMMANDS


def test_dry_run_counts_frames_and_bytes_without_a_port(tmp_path, capsys):
    src = tmp_path / "CELL.mod"
    src.write_bytes(b"x" * 1000)
    assert run([str(src), "--dry-run", "--baud", "9600"]) == 0
    out = capsys.readouterr().out
    frames = 13  # ceil(1000 / 80)
    hello = 7 + 8 + len("CELL.mod")
    end = 7 + 6
    wire = hello + 1000 + 7 * frames + end
    assert f"{frames} data frames" in out
    assert f"{wire} bytes on the line" in out
    assert f"{wire * 10 / 9600:.1f} s at 9600 baud" in out
    assert list(tmp_path.iterdir()) == [src]


def test_simulated_controller_receives_the_file(tmp_path, capsys):
    src = tmp_path / "CELL.mod"
    data = b"MODULE CELL\n  ! compensated\nENDMODULE\n" * 20
    src.write_bytes(data)
    disk = tmp_path / "controller"
    assert run([str(src), "--simulate", str(disk), "--name", "NEW.mod"]) == 0
    assert (disk / "NEW.mod").read_bytes() == data
    assert "sent NEW.mod" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["{src}"], "no serial port"),
        (["{src}", "--port", "{tmp}/ttyNone"], "does not exist"),
        (["{tmp}/missing.mod", "--dry-run"], "cannot read"),
        (["{src}", "--dry-run", "--name", "a/b.mod"], "cannot send under the name"),
        (["{src}", "--window", "0", "--dry-run"], "must be positive"),
    ],
)
def test_user_errors_are_link_errors(tmp_path, argv, message):
    src = tmp_path / "CELL.mod"
    src.write_bytes(b"MODULE CELL\nENDMODULE\n")
    argv = [a.format(src=src, tmp=tmp_path) for a in argv]
    with pytest.raises(LinkError, match=message):
        run(argv)


def test_load_on_the_simulated_controller_uses_the_rapid_grammar(tmp_path, capsys):
    good = tmp_path / "GOOD.mod"
    good.write_text('MODULE GOOD\n  PROC main()\n    TPWrite "hi";\n  ENDPROC\nENDMODULE\n')
    bad = tmp_path / "BAD.mod"
    bad.write_text("MODULE BAD\n  PROC main(\nENDMODULE\n")
    disk = tmp_path / "controller"
    assert run([str(good), "--simulate", str(disk), "--load"]) == 0
    assert "loaded" in capsys.readouterr().out
    # a module the controller would not load is refused before a byte is sent (the
    # controller's own refusal: test_upload_pty), with the syntax error's place
    with pytest.raises(RapidSyntaxError, match=r"BAD.mod:4:1: unexpected end of file") as err:
        run([str(bad), "--simulate", str(disk), "--load"])
    assert "nothing was sent" in err.value.hint
    assert not (disk / "BAD.mod").exists()
    with pytest.raises(RapidSyntaxError):
        run([str(bad), "--dry-run", "--load"])
    # without --load any file is sent as it is (a module still being written)
    assert run([str(bad), "--simulate", str(disk)]) == 0
    assert (disk / "BAD.mod").read_bytes() == bad.read_bytes()
