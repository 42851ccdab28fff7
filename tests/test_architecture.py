"""The code holds docs/architecture.md: each package imports only what its row allows, no import
circle among the modules (imports inside functions included), no module over 400 lines."""
from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "klaw_ocp"
MAX_LINES = 400

BASE = {"errors"}
#: docs/architecture.md's table: a unit (a subpackage or a top-level module) -> what it may import
ALLOWED = {
    "errors": set(), "choices": set(), "stop_signals": set(), "casadi_builds": set(),
    "kernel_calls": set(), "kernels": {"casadi_builds", "kernel_calls"},
    "console": BASE | {"stop_signals"}, "body": BASE,
    "config_yaml": BASE, "config_paths": BASE | {"config_yaml"},
    "gait": BASE | {"body"},
    "dynamics": BASE | {"body", "choices", "casadi_builds"},
    "solvers": BASE | {"kernels", "kernel_calls", "choices", "casadi_builds"},
    "kinematics": {"body"},
    "config": BASE | {"gait", "config_paths", "config_yaml", "body", "choices"},
    "control": BASE | {"kinematics", "dynamics", "solvers", "gait", "body", "choices", "casadi_builds"},
    # the middle level's state machine, one step at a time (shared by walk and stepwise)
    "step_loop": BASE | {"control", "kinematics", "dynamics", "body"},
    "walk": BASE | {"step_loop", "control", "kinematics", "dynamics", "solvers", "kernels", "gait", "config", "console",
                    "stop_signals", "body", "choices"},
    "body_motion": {"kinematics", "dynamics", "gait", "body", "kernels", "casadi_builds"},
    "results": BASE | {"body_motion", "control", "dynamics", "kinematics", "gait"},
    "compare": BASE,
    "human_gait": BASE | {"results", "body_motion", "dynamics", "gait", "body"},
    "result_files": BASE | {"results", "body_motion", "body", "package", "stop_signals"},
    "figures": BASE | {"result_files", "body_motion", "compare", "config_paths", "stop_signals"},
    "sweep_pool": BASE | {"stop_signals"},
    "sweep": BASE | {"config", "config_paths", "config_yaml", "walk", "control", "solvers", "results",
                     "result_files", "figures", "compare", "choices", "sweep_pool", "stop_signals"},
    "reproduce": BASE | {"config", "config_paths", "config_yaml", "walk", "control", "solvers", "results",
                         "result_files", "figures", "compare", "choices"},
    "stepwise": BASE | {"walk", "step_loop", "step_body", "body_motion", "config", "control", "gait", "results",
                        "solvers"},
    # a step's body frames on its window of the walk (stepwise's)
    "step_body": BASE | {"walk", "body_motion", "control"},
    # the web playground: it drives a stepwise walk; nothing below it knows of the web
    "serve": BASE | {"stepwise", "config", "gait", "body_motion", "result_files", "choices"},
}
EVERYTHING = set(ALLOWED) | {"package", "commands", "cli"}
ALLOWED.update({"commands": EVERYTHING, "cli": EVERYTHING, "package": EVERYTHING, "__main__": EVERYTHING})


def _modules() -> dict[str, Path]:
    modules = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def _imports(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Module -> the package's modules it imports, anywhere in its code."""
    def known(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets |= {known(a.name) for a in node.names if a.name.startswith("klaw_ocp")}
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(base + ([node.module] if node.module else []))
                elif (node.module or "").startswith("klaw_ocp"):
                    base = node.module
                else:
                    continue
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    targets.add(known(full) if full in modules else known(base))
        graph[name] = {t for t in targets if t and t != name}
    return graph


def _unit(module: str) -> str:
    parts = module.split(".")
    return "package" if len(parts) == 1 else parts[1]


def test_each_package_imports_only_what_docs_architecture_allows():
    graph = _imports(_modules())
    wrong = sorted(f"{a} imports {b}" for a, targets in graph.items() for b in targets
                   if _unit(b) != _unit(a) and _unit(b) not in ALLOWED[_unit(a)])
    assert not wrong, wrong
    units = {_unit(m) for m in graph}
    assert units <= set(ALLOWED), units - set(ALLOWED)


def test_no_import_circles_among_the_modules():
    """A package's __init__ may re-export its submodules; no two modules may import each other,
    directly or round a longer loop (Tarjan's strongly connected components)."""
    graph = _imports(_modules())
    index, low, stack, on_stack, circles, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    assert not circles, circles


def test_no_module_is_over_400_lines():
    long = {name: n for name, path in _modules().items()
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not long, long
