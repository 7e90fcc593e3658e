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


# ---------------------------------------------------------------- no solver named outside the registry
def _named_solvers(tree, names) -> list:
    """``(line, what)`` of every place ``tree`` compares a value with a solver's name or lists solver names
    (a tuple, list or set literal holding one, a dict keyed by one, a ``case`` on one)."""

    def is_name(node):
        return isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names

    def holds_name(node):
        return is_name(node) or (isinstance(node, (ast.Tuple, ast.List, ast.Set)) and any(map(is_name, node.elts)))

    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and any(holds_name(n) for n in [node.left, *node.comparators]):
            found.append((node.lineno, "compares with a solver name"))
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)) and any(map(is_name, node.elts)):
            found.append((node.lineno, "lists a solver name"))
        elif isinstance(node, ast.Dict) and any(key is not None and is_name(key) for key in node.keys):
            found.append((node.lineno, "keys a dict by solver name"))
        elif isinstance(node, ast.MatchValue) and is_name(node.value):
            found.append((node.lineno, "matches a solver name"))
    return sorted(dict(reversed(found)).items())  # one entry a line


def test_no_module_outside_the_solvers_compares_or_lists_solver_names():
    """Issue 25: studies, the CLI and plotting find solvers through the registry (solver_names,
    solvers_with and the capabilities), never by comparing or listing their names; only
    ``solvers/`` and the solvers' own packages spell them out."""
    from wavecontact.solvers import SOLVER_NAMES

    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.relative_to(PACKAGE).parts[0] in SOLVER_PACKAGES + ("solvers",):
            continue
        for line, what in _named_solvers(ast.parse(path.read_text(encoding="utf-8")), set(SOLVER_NAMES)):
            offenders.append(f"{path.relative_to(PACKAGE)}:{line} {what}")
    assert not offenders, "\n".join(offenders)


def test_the_solver_name_check_can_fail():
    probe = ast.parse('if solver == "fem": pass\nnames = ("delay", "modal")\nmarkers = {"fem": "s"}\n'
                      'ok = solver in {"modal"}\ncollide(0.6, 20, "delay")\n')
    assert [line for line, _ in _named_solvers(probe, {"delay", "fem", "modal"})] == [1, 2, 3, 4]


# ---------------------------------------------------------------- layering
#: The package's layers, lowest first: a module may import from its own layer and those below.  A unit is
#: a top-level module or subpackage; ``studies.paper_figures`` (which draws figures) sits above plotting.
LAYERS = (
    ("_version", "_jit", "errors", "progress"),
    ("io", "limits", "contact", "contact_kernels"),
    ("result", "restitution_table", "scene", "analytic", "bodies", "impact_result"),
    ("bath", "io.scene_file"),
    ("solvers",),
    SOLVER_PACKAGES,
    ("api", "solvers.auto"),  # auto chooses among the solver packages: above them
    ("gas",),
    ("studies",),
    ("plotting",),
    ("studies.paper_figures",),
    ("cli",),
    ("__init__", "__main__"),
)
LEVEL = {unit: level for level, units in enumerate(LAYERS) for unit in units}
#: at most this many imports may point upward (issue 25); the one left: scene.py's lazy import of
#: bath.scene.vibration_fields (a Scene builds its initial fields from a bath realisation it carries)
MOST_UPWARD = 1


def _unit(parts: tuple) -> str:
    """The layer unit of a module given as its dotted parts below ``wavecontact``."""
    if not parts or parts == ("__init__",):
        return "__init__"
    dotted = ".".join(parts)
    return dotted if dotted in LEVEL else parts[0]


def _upward_imports(path: Path, rel=None) -> list:
    """The imports of ``path`` (module ``wavecontact.<rel>``) from a higher layer than its own."""
    rel = path.relative_to(PACKAGE).with_suffix("").parts if rel is None else rel
    source = _unit(rel)
    package = ("wavecontact",) + rel[:-1]
    found = []
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = base + tuple(node.module.split(".") if node.module else ())
            else:
                module = tuple((node.module or "").split("."))
            targets = [module] if node.module else [module + (alias.name,) for alias in node.names]
        elif isinstance(node, ast.Import):
            targets = [tuple(alias.name.split(".")) for alias in node.names]
        else:
            continue
        for target in targets:
            if target[0] != "wavecontact":
                continue
            inner = target[1:]
            unit = _unit(inner) if not inner or inner[0] in LEVEL or ".".join(inner[:2]) in LEVEL else "__init__"
            if unit != source and LEVEL[unit] > LEVEL[source]:
                found.append(f"{'.'.join(rel)}:{node.lineno} imports {'.'.join(target)}")
    return found


def test_every_module_has_a_layer():
    units = {_unit(path.relative_to(PACKAGE).with_suffix("").parts) for path in PACKAGE.rglob("*.py")}
    assert units <= set(LEVEL), sorted(units - set(LEVEL))


def test_at_most_one_import_points_upward():
    upward = [item for path in sorted(PACKAGE.rglob("*.py")) for item in _upward_imports(path)]
    assert len(upward) <= MOST_UPWARD, "\n".join(upward)


def test_the_layering_check_sees_an_upward_import(tmp_path):
    # the check must be able to fail: io importing the package root and a study
    probe = tmp_path / "probe.py"
    probe.write_text("from .. import __version__\nfrom ..studies.ring import RingRun\nfrom ..errors import X\n",
                     encoding="utf-8")
    found = _upward_imports(probe, rel=("io", "probe"))
    assert len(found) == 2 and "wavecontact.__version__" in found[0] and "studies.ring" in found[1]


# ---------------------------------------------------------------- grouped arguments
#: no function takes more than this many parameters (issue 25: kernels take grouped arguments)
MOST_PARAMETERS = 12
#: the functions still above it, each with its count: an entry may only fall (lower it, or remove it once
#: the function takes at most MOST_PARAMETERS); no function may join the list
OVER_THE_LIMIT: dict[str, int] = {}


def _parameter_counts(tree) -> dict:
    """``{qualified name: parameters}`` of every function in ``tree`` (``self``, ``*args`` and ``**kwargs``
    count; a lambda is named ``<lambda>`` at its line)."""
    counts = {}

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                name = child.name if not isinstance(child, ast.Lambda) else f"<lambda>:{child.lineno}"
                a = child.args
                counts[prefix + name] = (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                                         + (a.vararg is not None) + (a.kwarg is not None))
                visit(child, prefix + name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)

    visit(tree, "")
    return counts


def _over_the_limit(paths, root=PACKAGE) -> dict:
    """``{'module.py:qualified name': parameters}`` of the functions in ``paths`` above MOST_PARAMETERS."""
    over = {}
    for path in paths:
        rel = path.relative_to(root).as_posix()
        for name, count in _parameter_counts(ast.parse(path.read_text(encoding="utf-8"))).items():
            if count > MOST_PARAMETERS:
                over[f"{rel}:{name}"] = count
    return over


def test_no_function_takes_more_parameters_than_its_allowance():
    over = _over_the_limit(sorted(PACKAGE.rglob("*.py")))
    problems = [f"{name} takes {count} parameters (at most {MOST_PARAMETERS}: group them)"
                for name, count in over.items() if name not in OVER_THE_LIMIT]
    problems += [f"{name} takes {over[name]} parameters, above its allowance of {allowed}"
                 for name, allowed in OVER_THE_LIMIT.items() if over.get(name, 0) > allowed]
    problems += [f"{name} now takes {over.get(name, 'at most ' + str(MOST_PARAMETERS))} parameters: lower or "
                 f"remove its entry in OVER_THE_LIMIT ({allowed})"
                 for name, allowed in OVER_THE_LIMIT.items() if over.get(name, 0) < allowed]
    assert not problems, "\n".join(problems)


def test_the_parameter_check_sees_a_long_signature(tmp_path):
    # the check must be able to fail: 13 parameters in a method and in a nested function, 12 let through
    probe = tmp_path / "probe.py"
    probe.write_text("class A:\n    def m(self, a, b, c, d, e, f, g, h, i, j, k, *rest):\n        pass\n"
                     "def outer(x):\n    def inner(a, b, c, d, e, f, g, h, i, j, k, l, *, m=0):\n        pass\n"
                     "def fine(a, b, c, d, e, f, g, h, i, j, k, l):\n    pass\n", encoding="utf-8")
    assert _parameter_counts(ast.parse(probe.read_text(encoding="utf-8"))) == {
        "A.m": 13, "outer": 1, "outer.inner": 13, "fine": 12}
    assert _over_the_limit([probe], root=tmp_path) == {"probe.py:A.m": 13, "probe.py:outer.inner": 13}
