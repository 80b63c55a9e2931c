"""The layers of ARCHITECTURE.md hold: import-linter checks the contracts in pyproject.toml
(every import between rapidfix's packages, those inside functions included)."""

from __future__ import annotations

import ast
import importlib
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

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
        'layers = ["rapidfix.kinematics", "rapidfix.error_model"]\n', encoding="utf-8")
    done = subprocess.run([*_lint_imports(), "--config", str(config), "--no-cache"],
                          cwd=ROOT, capture_output=True, text=True, check=False)
    assert done.returncode != 0
    assert "rapidfix.error_model" in done.stdout and "BROKEN" in done.stdout


def _self_attributes(function: ast.FunctionDef) -> set[str]:
    found = set()
    for node in ast.walk(function):
        targets = (node.targets if isinstance(node, ast.Assign) else
                   [node.target] if isinstance(node, (ast.AnnAssign, ast.AugAssign)) else [])
        for target in targets:
            for part in ast.walk(target):
                if (isinstance(part, ast.Attribute) and isinstance(part.value, ast.Name)
                        and part.value.id == "self"):
                    found.add(part.attr)
    return found


@pytest.mark.parametrize("package", ["rapid", "kinematics", "postprocess", "demo", "link"])
def test_objects_declare_their_state_in_init(package):
    """A reader finds all of an object's state in its __init__ (or its dataclass fields):
    no method sets an attribute that __init__ does not."""
    late = []
    for path in sorted((ROOT / "rapidfix" / package).rglob("*.py")):
        for cls in (n for n in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
                    if isinstance(n, ast.ClassDef)):
            methods = [f for f in cls.body if isinstance(f, ast.FunctionDef)]
            declared = {t.target.id for t in cls.body
                        if isinstance(t, ast.AnnAssign) and isinstance(t.target, ast.Name)}
            for method in methods:
                if method.name in ("__init__", "__post_init__"):
                    declared |= _self_attributes(method)
            late += [f"{path.name}: {cls.name}.{method.name} sets {sorted(extra)}"
                     for method in methods if method.name not in ("__init__", "__post_init__")
                     for extra in [_self_attributes(method) - declared] if extra]
    assert not late, "\n".join(late)


def test_no_module_imports_a_private_name_of_another():
    """`from rapidfix.x import _name` across modules couples a reader to internals; what
    other modules use is public (no leading underscore)."""
    found = []
    for path in sorted((ROOT / "rapidfix").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("rapidfix"):
                found += [f"{path.relative_to(ROOT)}: {node.module}.{alias.name}"
                          for alias in node.names
                          if alias.name.startswith("_") and not alias.name.startswith("__")]
    assert not found, "\n".join(found)


PACKAGES = sorted(p.parent.name for p in (ROOT / "rapidfix").glob("*/__init__.py"))


def test_a_deep_import_is_reported(tmp_path):
    """The check can fail: in a copy of the code where one package reaches into a module of
    another (inside a function, past `rapidfix.rapid`'s root), the project's own contracts
    name the importing module, the module reached and the line."""
    shutil.copytree(ROOT / "rapidfix", tmp_path / "rapidfix",
                    ignore=shutil.ignore_patterns("__pycache__"))
    simulator = tmp_path / "rapidfix" / "link" / "simulator.py"
    text = simulator.read_text(encoding="utf-8")
    simulator.write_text(text + "\n\ndef _reach() -> None:\n"
                         "    from rapidfix.rapid.format import format_num  # noqa: F401\n",
                         encoding="utf-8")
    line = len(text.splitlines()) + 4
    done = subprocess.run([*_lint_imports(), "--config", str(ROOT / "pyproject.toml"),
                           "--no-cache"], cwd=tmp_path, capture_output=True, text=True,
                          check=False)
    assert done.returncode != 0
    assert "rapidfix.rapid is used through its root BROKEN" in done.stdout
    assert f"rapidfix.link.simulator -> rapidfix.rapid.format (l.{line})" in done.stdout
    assert "1 broken" in done.stdout


def _lazy_table(package: str) -> tuple[dict[str, str], dict[str, str]]:
    """A package's LAZY_EXPORTS, and what its `if TYPE_CHECKING:` block imports (name ->
    module), read from the source."""
    tree = ast.parse((ROOT / "rapidfix" / package / "__init__.py").read_text(encoding="utf-8"))
    table: dict[str, str] = {}
    typed: dict[str, str] = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and ast.unparse(node.targets[0]) == "LAZY_EXPORTS":
            table = ast.literal_eval(node.value)
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            typed |= {alias.name: imp.module.removeprefix(f"rapidfix.{package}.")
                      for imp in node.body if isinstance(imp, ast.ImportFrom)
                      for alias in imp.names}
    return table, typed


@pytest.mark.parametrize("package", PACKAGES)
def test_every_exported_name_resolves(package):
    """Every name in a package's __all__ is there (a lazy one is imported from the module its
    table names, the same object), a type checker sees each lazy name from that module, no
    lazy name is also a submodule (it would be shadowed once the module is imported), and
    dir() lists them."""
    root = importlib.import_module(f"rapidfix.{package}")
    table, typed = _lazy_table(package)
    assert typed == table
    exported = getattr(root, "__all__", [])
    assert set(table) <= set(exported)
    assert len(exported) == len(set(exported))
    submodules = {p.stem for p in (ROOT / "rapidfix" / package).glob("*.py")} | {
        p.parent.name for p in (ROOT / "rapidfix" / package).glob("*/__init__.py")}
    assert not set(table) & submodules
    for name in exported:
        value = getattr(root, name)
        if name in table:
            module = importlib.import_module(f"rapidfix.{package}.{table[name]}")
            assert value is getattr(module, name), name
    assert set(exported) <= set(dir(root))
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        root.no_such_name  # noqa: B018
