"""Start-up: `rapidfix --help` lists every command without importing any command module,
and the fast parser's grammar text (the key of Lark's cached parse table) is the same in
every process."""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
from pathlib import Path

from rapidfix import cli


def test_the_listed_help_lines_are_those_the_commands_register():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    for module, (name, summary) in cli.COMMANDS.items():
        importlib.import_module(f"rapidfix.commands.{module}").register(sub)
        action = next(a for a in sub._choices_actions if a.dest == name)
        assert action.help == summary, module


def _run(code: str, seed: str = "0") -> str:
    env = {**os.environ, "PYTHONHASHSEED": seed}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True)
    return done.stdout


def test_help_imports_no_command_and_no_heavy_library():
    out = _run(
        "import contextlib, io, sys\n"
        "from rapidfix import cli\n"
        "with contextlib.redirect_stdout(io.StringIO()) as text:\n"
        "    try:\n"
        "        cli.main(['--help'])\n"
        "    except SystemExit:\n"
        "        pass\n"
        "heavy = [m for m in ('numpy', 'scipy', 'lark', 'importlib.metadata')\n"
        "         if m in sys.modules]\n"
        "commands = [m for m in sys.modules if m.startswith('rapidfix.commands.')]\n"
        "listed = all(name in text.getvalue() for name, _ in cli.COMMANDS.values())\n"
        "print(heavy, commands, listed)\n"
    )
    assert out.strip() == "[] [] True"


def test_a_command_is_registered_by_its_module_the_others_listed():
    parser = cli.build_parser(["--debug", "check", "x.mod"])
    args = parser.parse_args(["--debug", "check", "x.mod"])
    assert args.func.__module__ == "rapidfix.commands.check"
    words = {name for name, _ in cli.COMMANDS.values()}
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == words


def test_the_fast_grammar_does_not_depend_on_the_hash_seed():
    code = ("from rapidfix.rapid.fastpath import grammar_extension\n"
            "from rapidfix.rapid.grammar import grammar_text\n"
            "import hashlib\n"
            "print(hashlib.sha256(grammar_extension(grammar_text()).encode()).hexdigest())\n")
    assert _run(code, "1") == _run(code, "2") == _run(code, "3")


def test_the_console_script_exits_with_mains_status_after_freezing_what_is_left():
    # a fresh process, as the console script runs: the exit status is main's, the
    # objects left are frozen (the last collection skips them), numpy was told to keep
    # to small pages unless the environment says otherwise
    code = ("import gc, os, sys\n"
            "from rapidfix import cli\n"
            "cli.main = lambda: 3\n"
            "try:\n"
            "    cli.console_main()\n"
            "except SystemExit as done:\n"
            "    print(done.code, gc.get_freeze_count() > 0,\n"
            "          os.environ['NUMPY_MADVISE_HUGEPAGE'])\n")
    env = {k: v for k, v in os.environ.items() if k != "NUMPY_MADVISE_HUGEPAGE"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True)
    assert done.stdout.split() == ["3", "True", "0"]
    env["NUMPY_MADVISE_HUGEPAGE"] = "1"  # the user's choice stands
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, check=True)
    assert done.stdout.split() == ["3", "True", "1"]


def test_the_installed_console_script_runs_console_main():
    # pyproject's entry point names console_main, and `python -m rapidfix.cli` runs it
    text = (Path(__file__).parents[2] / "pyproject.toml").read_text(encoding="utf-8")
    assert 'rapidfix = "rapidfix.cli:console_main"' in text
    done = subprocess.run([sys.executable, "-m", "rapidfix.cli", "--version"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.startswith("rapidfix ")
