"""The layers import one way — the shared core (``workbench``: scenes, materials, analytic, results,
fields) ← the solvers (``sph``, ``fem_reference``) ← the studies (``studies``) ← the application
(``app``: CLI, verify, report) — and no module imports another in a circle. Checked on
the source (every ``import`` and ``from … import``, also inside functions), so a lazy import that
breaks the rule fails too."""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("workbench", "sph", "fem_reference", "studies", "app")
RANK = {"core": 0, "solvers": 1, "studies": 2, "app": 3}


def layer(module: str) -> str:
    """The layer of a module is its top-level package: the folders show the layers."""
    top = module.split(".")[0]
    return {"workbench": "core", "sph": "solvers", "fem_reference": "solvers",
            "studies": "studies", "app": "app"}[top]


def modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for p in (ROOT / pkg).rglob("*.py"):
            parts = p.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = p
    return out


def import_graph() -> dict[str, set[str]]:
    mods = modules()
    graph = {m: set() for m in mods}
    for m, p in mods.items():
        pkg = m if p.name == "__init__.py" else m.rpartition(".")[0]
        for node in ast.walk(ast.parse(p.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                names = [base] + [f"{base}.{a.name}" for a in node.names]
            for n in names:
                while n and n not in mods:
                    n = n.rpartition(".")[0]
                if n and n != m:
                    graph[m].add(n)
    return graph


def test_imports_go_one_way():
    bad = [f"{m} ({layer(m)}) imports {n} ({layer(n)})"
           for m, deps in import_graph().items() for n in deps
           if RANK[layer(n)] > RANK[layer(m)]]
    assert not bad, "\n".join(bad)


def test_the_two_solver_packages_are_independent():
    bad = [f"{m} imports {n}" for m, deps in import_graph().items() for n in deps
           if layer(m) == layer(n) == "solvers" and m.split(".")[0] != n.split(".")[0]]
    assert not bad, "\n".join(bad)


def test_no_import_cycles():
    graph = import_graph()
    # a package's __init__ that imports its own submodules is not a cycle of concern only when
    # the submodule does not import the package back; any back edge is reported
    seen, on, stack, cycles = set(), set(), [], []

    def visit(v):
        seen.add(v)
        on.add(v)
        stack.append(v)
        for w in sorted(graph[v]):
            if w in on:
                cycles.append(" -> ".join(stack[stack.index(w):] + [w]))
            elif w not in seen:
                visit(w)
        stack.pop()
        on.discard(v)

    for v in sorted(graph):
        if v not in seen:
            visit(v)
    assert not cycles, "\n".join(cycles[:10])
