"""The package is layered, one way down: its import graph, read from the source with :mod:`ast`, has no cycle,
no import from a higher layer and no function-local import of a bldclab module.

The layers, lowest first (docs/design.md explains them and where new code goes):

====  ==========  ========================================================================================
  0   base        ``bldclab._version``, ``bldclab.errors``, ``bldclab._files`` (TOML, atomic writes),
                  ``bldclab.svg`` (dependency-free SVG plots)
  1   model       ``bldclab.model``: motor, back-EMF shapes, motor files, units, catalog, closed forms, design
  2   binding     ``bldclab._core``: the ctypes binding of the C core
  3   control     ``bldclab.control``: the controllers (their ``c_record`` needs the binding)
  4   sim         ``bldclab.sim``: scenario, :func:`simulate`, results, plausibility guards
  5   analysis    ``bldclab.analysis``: experiments, paper 1, paper 2, comparison, faults, identification
  6   sweep       ``bldclab.sweep``: sweep files, controller registry, executors, progress, store
  7   report      ``bldclab.report``: figures, the results directory (compare file set), the HTML report
  8   cli         ``bldclab.cli``: one module per command group
  9   api         ``bldclab`` itself: the public names (``import bldclab as bl``)
====  ==========  ========================================================================================

A module may import its own layer or any lower one. Imports under ``if TYPE_CHECKING:`` count too (they name the
same dependency). Third-party imports may be deferred into a function (matplotlib, pandas, dask: heavy or
optional), with a comment saying so; this test looks at bldclab imports only.

Imports by name (so that ``import bldclab`` and the command line load a module only when it is used) go through one
function, :func:`bldclab._lazy.load`, from two kinds of tables only: a package's module-level ``LAZY`` table of names
imported on first use (``bldclab``, ``bldclab.report``) and the command registry :data:`bldclab.cli.COMMANDS`. They
count as imports of the module that declares the table, at its top level (the layer rule and the cycle check apply
to them); ``importlib`` or ``__import__`` anywhere else fails (but in :data:`BY_NAME_ELSEWHERE`, with its reason).
"""

from __future__ import annotations

import ast
import importlib
from collections.abc import Mapping
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "src"
PACKAGE = "bldclab"

#: module prefix -> layer number; the longest matching prefix wins, every module must match one
LAYERS: dict[str, int] = {
    "bldclab._version": 0,
    "bldclab._lazy": 0,
    "bldclab.errors": 0,
    "bldclab._files": 0,
    "bldclab.svg": 0,
    "bldclab.model": 1,
    "bldclab._core": 2,
    "bldclab.control": 3,
    "bldclab.sim": 4,
    "bldclab.analysis": 5,
    "bldclab.sweep": 6,
    "bldclab.report": 7,
    "bldclab.cli": 8,
    "bldclab": 9,
}

Edge = tuple[str, str, int, bool]  # (importer, imported, line, function-local)


def _module_name(path: Path) -> tuple[str, bool]:
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[-1] == "__init__":
        return ".".join(parts[:-1]), True
    return ".".join(parts), False


def _modules() -> dict[str, tuple[Path, bool]]:
    return {name: (p, is_pkg) for p in sorted((ROOT / PACKAGE).rglob("*.py"))
            for name, is_pkg in [_module_name(p)]}


class _Imports(ast.NodeVisitor):
    """Collect the bldclab imports of one module, noting whether each sits inside a function."""

    def __init__(self, module: str, is_pkg: bool, known: Mapping[str, object]) -> None:
        self.module, self.known = module, known
        self.package = module if is_pkg else module.rpartition(".")[0]
        self.depth = 0
        self.edges: list[Edge] = []

    def _add(self, target: str, line: int) -> None:
        if target == PACKAGE or target.startswith(PACKAGE + "."):
            self.edges.append((self.module, target, line, self.depth > 0))

    def _function(self, node: ast.AST) -> None:
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_FunctionDef = visit_AsyncFunctionDef = visit_Lambda = _function

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            self._add(alias.name, node.lineno)

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        if node.level:
            base = self.package.split(".")[: len(self.package.split(".")) - (node.level - 1)]
            source = ".".join(base + ([node.module] if node.module else []))
        else:
            source = node.module or ""
        for alias in node.names:  # "from pkg import module" imports the module; "from mod import name", mod
            sub = f"{source}.{alias.name}"
            self._add(sub if sub in self.known else source, node.lineno)


#: The one module that imports bldclab modules by name (importlib), from the tables below.
BY_NAME = "bldclab._lazy"
#: Other by-name imports, not of a layer: module -> why.
BY_NAME_ELSEWHERE = {
    "bldclab.sweep.executors": "rebuilds a case's controller from its recorded 'module:qualname' (any package's, "
                               "a user's too), as unpickling does",
}


def _lazy_tables(tree: ast.Module) -> bool:
    """Whether a module declares a ``LAZY`` table at its top level."""
    return any(isinstance(node, ast.Assign | ast.AnnAssign)
               and any(isinstance(t, ast.Name) and t.id == "LAZY"
                       for t in (node.targets if isinstance(node, ast.Assign) else [node.target]))
               for node in tree.body)


def by_name_edges(module: str) -> list[Edge]:
    """The imports by name of a module that declares a ``LAZY`` table or is the command registry."""
    mod = importlib.import_module(module)
    targets = [target for target, _ in getattr(mod, "LAZY", {}).values()]
    if module == "bldclab.cli":
        targets += [f"bldclab.cli.{cmd.module}" for cmd in mod.COMMANDS]
    return [(module, target, 0, False) for target in targets]


def by_name_callers() -> list[str]:
    """The modules other than :data:`BY_NAME` that call ``importlib`` or ``__import__``."""
    bad = []
    for name, (path, _) in _modules().items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            uses = ((isinstance(node, ast.Import) and any(a.name.startswith("importlib") for a in node.names))
                    or (isinstance(node, ast.ImportFrom) and (node.module or "").startswith("importlib")
                        and any(a.name in ("import_module", "__import__") for a in node.names))
                    or (isinstance(node, ast.Name) and node.id == "__import__"))
            if uses and name != BY_NAME and name not in BY_NAME_ELSEWHERE:
                bad.append(f"{name}:{node.lineno}")
    return bad


def import_edges() -> list[Edge]:
    """Every bldclab import of every module under src/bldclab, imports by name included."""
    known = _modules()
    edges: list[Edge] = []
    for name, (path, is_pkg) in known.items():
        visitor = _Imports(name, is_pkg, known)
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        visitor.visit(tree)
        edges += visitor.edges
        if _lazy_tables(tree) or name == "bldclab.cli":
            edges += by_name_edges(name)
    return edges


def layer_of(module: str, layers: Mapping[str, int] = LAYERS) -> int | None:
    """The layer of a module: its longest matching prefix in ``layers`` (None if none matches)."""
    best = None
    for prefix in layers:
        if (module == prefix or module.startswith(prefix + ".")) and (best is None or len(prefix) > len(best)):
            best = prefix
    return None if best is None else layers[best]


def upward(edges: list[Edge], layers: Mapping[str, int] = LAYERS) -> list[str]:
    """The imports from a lower layer into a higher one."""
    bad = []
    for src, dst, line, _ in edges:
        a, b = layer_of(src, layers), layer_of(dst, layers)
        if a is not None and b is not None and b > a:
            bad.append(f"{src}:{line} imports {dst} (layer {b} > {a})")
    return bad


def cycles(edges: list[Edge]) -> list[list[str]]:
    """The import cycles (each as a path of modules, first = last), by depth-first search."""
    graph: dict[str, set[str]] = {}
    for src, dst, _, _ in edges:
        if src != dst:
            graph.setdefault(src, set()).add(dst)
    found: list[list[str]] = []
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                found.append([*stack[stack.index(nxt):], nxt])
            elif nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    return found


@pytest.fixture(scope="module")
def edges() -> list[Edge]:
    return import_edges()


def test_every_module_has_a_layer() -> None:
    missing = [m for m in _modules() if layer_of(m) is None]
    assert not missing, f"modules without a layer (add them to LAYERS and docs/design.md): {missing}"


def test_the_graph_is_found(edges: list[Edge]) -> None:
    pairs = {(s, d) for s, d, _, _ in edges}
    assert ("bldclab.sim", "bldclab._core") in pairs
    assert ("bldclab", "bldclab.sim") in pairs  # a LAZY name (and a TYPE_CHECKING import)
    assert ("bldclab.report", "bldclab.report.bundle") in pairs
    assert ("bldclab.cli", "bldclab.cli.torque_control") in pairs  # a command's module, imported by name
    assert len(_modules()) > 30


def test_imports_by_name_go_through_one_function() -> None:
    bad = by_name_callers()
    assert not bad, f"importlib outside {BY_NAME} (use a LAZY table or bldclab.cli.COMMANDS):\n" + "\n".join(bad)


def test_only_the_tables_import_by_name(edges: list[Edge]) -> None:
    tables = {name for name, (path, _) in _modules().items()
              if _lazy_tables(ast.parse(path.read_text(encoding="utf-8")))} | {"bldclab.cli"}
    users = {s for s, d, _, _ in edges if d == BY_NAME}
    assert users <= tables, f"{BY_NAME} used without a LAZY table: {sorted(users - tables)}"


def test_every_by_name_target_exists() -> None:
    known = _modules()
    targets = [d for m in ("bldclab", "bldclab.report", "bldclab.cli") for _, d, _, _ in by_name_edges(m)]
    missing = [t for t in targets if t not in known]
    assert targets and not missing, missing


def test_no_import_cycle(edges: list[Edge]) -> None:
    found = cycles(edges)
    assert not found, "import cycles:\n" + "\n".join(" -> ".join(c) for c in found)


def test_no_import_from_a_higher_layer(edges: list[Edge]) -> None:
    bad = upward(edges)
    assert not bad, "upward imports:\n" + "\n".join(bad)


def test_no_function_local_bldclab_import(edges: list[Edge]) -> None:
    local = [f"{s}:{line} imports {d}" for s, d, line, is_local in edges if is_local]
    assert not local, "function-local imports of bldclab modules (import at the top):\n" + "\n".join(local)


def test_the_checks_catch_a_bad_graph() -> None:
    layers = {"p.low": 0, "p.mid": 1, "p.top": 2}
    bad: list[Edge] = [("p.low.a", "p.low.b", 1, False), ("p.low.b", "p.low.a", 1, False),  # a cycle
                       ("p.mid.c", "p.top.d", 2, False),  # upward
                       ("p.top.d", "p.mid.c", 3, True)]  # downward, fine for the layers
    assert cycles(bad) == [["p.low.a", "p.low.b", "p.low.a"], ["p.mid.c", "p.top.d", "p.mid.c"]]
    assert upward(bad, layers) == ["p.mid.c:2 imports p.top.d (layer 2 > 1)"]
    good = [e for e in bad if e[:2] in {("p.low.a", "p.low.b"), ("p.top.d", "p.mid.c")}]
    assert cycles(good) == [] and upward(good, layers) == []
    assert layer_of("p.mid", layers) == 1 and layer_of("p.midway", layers) is None


def test_the_visitor_resolves_relative_and_local_imports(tmp_path: Path) -> None:
    code = "from . import b\nfrom ..x import y\n\ndef f():\n    from .b import g\n"
    visitor = _Imports("bldclab.pkg.a", False, {"bldclab.pkg.b": None})
    visitor.visit(ast.parse(code))
    assert visitor.edges == [("bldclab.pkg.a", "bldclab.pkg.b", 1, False), ("bldclab.pkg.a", "bldclab.x", 2, False),
                             ("bldclab.pkg.a", "bldclab.pkg.b", 5, True)]
