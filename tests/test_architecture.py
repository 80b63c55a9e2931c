"""The layers of ARCHITECTURE.md hold: import-linter checks the contracts in pyproject.toml
(every import between rapidfix's packages, those inside functions included)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _lint_imports() -> list[str]:
    script = Path(sys.executable).with_name("lint-imports")
    found = str(script) if script.exists() else shutil.which("lint-imports")
    assert found, "lint-imports not installed: pip install '.[test]'"
    return [found]


def test_import_contracts_are_kept():
    done = subprocess.run(
        [*_lint_imports(), "--config", str(ROOT / "pyproject.toml"), "--no-cache"],
        cwd=ROOT, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "0 broken" in done.stdout


def test_a_broken_layer_is_reported(tmp_path):
    """The check can fail: a contract the code does not keep (the error model below the
    kinematics) is reported as broken, with the import that breaks it."""
    config = tmp_path / "contracts.toml"
    config.write_text(
        '[tool.importlinter]\nroot_package = "rapidfix"\n\n'
        '[[tool.importlinter.contracts]]\nname = "inverted"\ntype = "layers"\n'
        'layers = ["rapidfix.kinematics", "rapidfix.errors"]\n', encoding="utf-8")
    done = subprocess.run([*_lint_imports(), "--config", str(config), "--no-cache"],
                          cwd=ROOT, capture_output=True, text=True, check=False)
    assert done.returncode != 0
    assert "rapidfix.errors" in done.stdout and "BROKEN" in done.stdout

