"""The house rules of docs/architecture.md, read from the source (nothing is imported).

Imports at any depth (function-level included) between fsicas modules follow the wing
order, and between continuation's modules the order of its rooms; they form no cycle; no
module imports another's private name; ``continuation`` imports nothing of fsicas, fsicas
only its public modules; every fsicas module declares ``__all__``; modules and functions
stay small.
"""
import ast
import statistics
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: who may import whom: a wing may import itself and the wings listed
ALLOWED = {
    "top": {"top"},
    "model": {"top"},
    "linear": {"top", "model"},
    "cycles": {"top", "model", "linear"},
    "timedomain": {"top", "model", "linear"},
    "studies": {"top", "model", "linear", "cycles", "timedomain"},
    "plots": {"top", "model", "linear", "cycles", "timedomain"},
    "paper": {"top", "model", "linear", "cycles", "timedomain", "plots", "package"},
    "explore": {"top", "model", "linear", "cycles", "timedomain"},
    "cli": {"top", "model", "linear", "cycles", "timedomain", "studies", "plots", "paper",
            "package", "explore"},
    "package": {"top", "model", "linear", "cycles", "timedomain", "plots"},
    "console": {"cli"},
    "__main__": {"console"},
}


#: continuation's rooms, bottom first: a room may import itself and the rooms below it
#: (``top``: the package's ``__init__`` with the public API, and ``plotting``)
ROOMS = ("_linalg", "_casadi", "_driver", "_equilibria", "_cycles", "_diagram", "top")
#: public modules that belong to a room but keep their path at the top of the package
PUBLIC_IN_ROOM = {"continuation.compilation": "_casadi"}


def _modules(package: str) -> dict[str, Path]:
    """Dotted module name -> file, for every module of ``package``."""
    out = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


FSICAS, LIBRARY = _modules("fsicas"), _modules("continuation")


def _resolve(module: str, node: ast.ImportFrom, path: Path) -> str:
    """Absolute name of the module an ImportFrom reads from."""
    if node.level == 0:
        return node.module or ""
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    base = package[:len(package) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(module: str, path: Path):
    """(imported module, names) for every import statement of the file, at any depth."""
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, []
        elif isinstance(node, ast.ImportFrom):
            yield _resolve(module, node, path), [a.name for a in node.names]


def _edges(module: str, path: Path, modules: dict = FSICAS) -> set[str]:
    """The ``modules`` that ``module`` imports (a name that is a submodule counts as it)."""
    out = set()
    for target, names in _imports(module, path):
        for name in names:
            if f"{target}.{name}" in modules:
                out.add(f"{target}.{name}")
            elif target in modules:
                out.add(target)
        if not names and target in modules:
            out.add(target)
    out.discard(module)
    return out


def _wing(module: str) -> str:
    """``package`` (fsicas itself), a wing's or ``paper``'s name, else ``top``."""
    parts = module.split(".")
    if len(parts) == 1:
        return "package"
    return parts[1] if parts[1] in ALLOWED else "top"


def test_imports_follow_the_wing_order():
    wrong = [f"{m} -> {t}" for m, p in FSICAS.items() for t in _edges(m, p)
             if _wing(t) != _wing(m) and _wing(t) not in ALLOWED[_wing(m)]]
    assert not wrong, wrong


def _room(module: str) -> str:
    """The continuation room of ``module``: its subpackage, else ``top``."""
    parts = module.split(".")
    return PUBLIC_IN_ROOM.get(module) or (parts[1] if len(parts) > 1 and parts[1] in ROOMS
                                          else "top")


def test_continuation_imports_follow_the_room_order():
    wrong = [f"{m} -> {t}" for m, p in LIBRARY.items() for t in _edges(m, p, LIBRARY)
             if ROOMS.index(_room(t)) > ROOMS.index(_room(m))]
    assert not wrong, wrong


def test_every_continuation_module_lives_in_a_room():
    """Besides the package itself, only the public modules stand at the top."""
    loose = [m for m in LIBRARY if _room(m) == "top"
             and m not in ("continuation", "continuation.plotting")]
    assert not loose, loose


@pytest.mark.parametrize("modules", [FSICAS, LIBRARY], ids=["fsicas", "continuation"])
def test_no_import_cycle_among_modules(modules):
    graph = {m: _edges(m, p, modules) for m, p in modules.items()}
    state, cycles = {}, []

    def visit(m, stack):
        state[m] = "open"
        for t in sorted(graph[m]):
            if state.get(t) == "open":
                cycles.append(stack[stack.index(t):] + [t])
            elif t not in state:
                visit(t, stack + [t])
        state[m] = "done"

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert not cycles, cycles


def test_continuation_imports_nothing_of_fsicas():
    bad = [(m, t) for m, p in LIBRARY.items() for t, _ in _imports(m, p)
           if t.split(".")[0] == "fsicas"]
    assert not bad, bad


def test_fsicas_uses_only_the_public_continuation():
    """fsicas imports ``continuation``, ``continuation.compilation`` and
    ``continuation.plotting``, and no private name of theirs."""
    public = {"continuation", "continuation.compilation", "continuation.plotting"}
    bad = [f"{m}: {t} {names}" for m, p in FSICAS.items() for t, names in _imports(m, p)
           if t.split(".")[0] == "continuation"
           and (t not in public or any(n.startswith("_") for n in names))]
    assert not bad, bad


def _private_import(module: str, target: str, name: str) -> bool:
    """A private name of another module; a package's own private submodules (its
    implementation, e.g. ``continuation._equilibria.eigen`` inside ``continuation``) are not."""
    if not name.startswith("_") or name.startswith("__") or target == module:
        return False
    same_package = target.split(".")[0] == module.split(".")[0]
    return not (same_package and f"{target}.{name}" in {**FSICAS, **LIBRARY})


@pytest.mark.parametrize("modules", [FSICAS, LIBRARY], ids=["fsicas", "continuation"])
def test_no_module_imports_a_private_name_of_another(modules):
    bad = [f"{m}: from {t} import {n}" for m, p in modules.items()
           for t, names in _imports(m, p) for n in names if _private_import(m, t, n)]
    assert not bad, bad


def test_every_fsicas_module_declares_all():
    missing = [m for m, p in FSICAS.items()
               if p.name != "__main__.py" and "__all__" not in p.read_text()]
    assert not missing, missing


def test_modules_and_functions_stay_small():
    """No module over 400 lines, no function over 40, median function <= 15 lines."""
    lengths, long_functions = [], []
    for m, p in {**FSICAS, **LIBRARY}.items():
        text = p.read_text()
        assert len(text.splitlines()) <= 400, f"{m}: {len(text.splitlines())} lines"
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                lengths.append(n)
                if n > 40:
                    long_functions.append(f"{m}.{node.name}: {n}")
    assert not long_functions, long_functions
    assert statistics.median(lengths) <= 15
