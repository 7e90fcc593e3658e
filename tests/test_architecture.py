"""The layering of STYLE.md, checked on the source: only the solver packages and the registry
import a solver's modules; studies, the gas, the bath, I/O, plotting and the CLI go through
``wavecontact.solvers.get_solver`` (issue 9: "grep finds no study importing a solver's internals")."""

import ast
from pathlib import Path

import wavecontact

PACKAGE = Path(wavecontact.__file__).resolve().parent
SOLVER_PACKAGES = ("delay", "fem", "modal")


def _imported_modules(path: Path, package=None):
    """Absolute names of the modules ``path`` imports (``package``: its package's parts)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    if package is None:
        package = path.relative_to(PACKAGE.parent).with_suffix("").parts[:-1]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                yield ".".join(base + ((node.module,) if node.module else ()))
            else:
                yield node.module or ""
        elif isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)


def test_only_solver_packages_and_the_registry_import_solver_modules():
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        top = path.relative_to(PACKAGE).parts[0]
        if top in SOLVER_PACKAGES + ("solvers",):
            continue
        for module in _imported_modules(path):
            parts = module.split(".")
            if len(parts) >= 2 and parts[0] == "wavecontact" and parts[1] in SOLVER_PACKAGES:
                offenders.append(f"{path.relative_to(PACKAGE)} imports {module}")
    assert not offenders, "\n".join(offenders)


def test_the_check_sees_a_relative_import_of_a_solver_module(tmp_path):
    # the check must be able to fail: a study module that imports delay internals
    probe = tmp_path / "probe.py"
    probe.write_text("from ..delay.kernels import table_value\nimport wavecontact.fem.lattice\n", encoding="utf-8")
    found = set(_imported_modules(probe, package=("wavecontact", "studies")))
    assert {"wavecontact.delay.kernels", "wavecontact.fem.lattice"} <= found
