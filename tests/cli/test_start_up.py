"""Start-up: `rapidfix --help` lists every command without importing any command module,
and the fast parser's grammar text (the key of Lark's cached parse table) is the same in
every process."""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys

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
