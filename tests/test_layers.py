"""The import graph of python/adparm runs one way: every module sits on a layer (LAYERS), imports
only from its own layer or those below (imports inside functions and TYPE_CHECKING blocks
included), the graph has no circle, and no module imports another module's private name."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "python" / "adparm"

#: The layers, from the bottom: each module imports only from its own layer or those below
#: (docs/design.md, "Layers").
LAYER_NAMES = ("core access", "schema", "model", "running", "analysis", "output", "interface")
LAYERS = {
    # 0 core access: the extension and what wraps it without knowing a configuration
    "_core": 0,
    "_libraries": 0,
    "_examples": 0,
    "physical": 0,
    "urdf": 0,
    "urdf_text": 0,
    "urdf_payload": 0,
    "joint_limits": 0,
    "term_checks": 0,
    "bases": 0,
    "_files": 0,
    # 1 schema: the configuration's sections, value checks and TOML text
    "_fields": 1,
    "_arm_sections": 1,
    "_run_sections": 1,
    "_sections": 1,
    "_schema": 1,
    # 2 model: the arm, the basis, the exact optimum and the defaults derived from them
    "desired": 2,
    "dynamics": 2,
    "symbolic_arm": 2,
    "basis_family": 2,
    "optimal": 2,
    "extrapolation_region": 2,
    "rates": 2,
    "config": 2,
    "units": 2,
    # 3 running: the Config -> core translation, simulate, batch and sweep
    "translate": 3,
    "result": 3,
    "divergence": 3,
    "simulation": 3,
    "transient": 3,
    "table": 3,
    "sweep": 3,
    # 4 analysis: what a run means
    "residual": 4,
    "yardstick": 4,
    "identification": 4,
    "progress": 4,
    "against_plant": 4,
    "saturation": 4,
    "truth": 4,
    "comparison": 4,
    # 5 output: files, figures, summaries
    "summary": 5,
    "_figure_style": 5,
    "weight_figures": 5,
    "identifier_figure": 5,
    "plotting": 5,
    "storage": 5,
    "report": 5,
    # 6 interface
    "cli_parser": 6,
    "cli": 6,
    "__init__": 6,
    "__main__": 6,
}


def _imports(path: Path) -> list[tuple[str, str, int]]:
    """(module imported, name taken or "", line) for every import of the package in ``path``,
    wherever it stands (module level, functions, TYPE_CHECKING blocks)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if node.module is None or not node.module.startswith("adparm"):
                    continue
                parts = node.module.split(".")[1:]
            elif node.level == 1:
                parts = node.module.split(".") if node.module else []
            else:  # pragma: no cover - the package has no subpackages
                raise AssertionError(f"{path.name}:{node.lineno}: relative import above adparm")
            if parts:
                out.extend((parts[0], alias.name, node.lineno) for alias in node.names)
            else:  # from . import x: the module x, or a name of adparm/__init__.py
                for alias in node.names:
                    if (PACKAGE / f"{alias.name}.py").exists() or alias.name == "_core":
                        out.append((alias.name, "", node.lineno))
                    else:
                        out.append(("__init__", alias.name, node.lineno))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "adparm":
                    out.append((parts[1] if len(parts) > 1 else "__init__", "", node.lineno))
    return out


def _graph() -> dict[str, list[tuple[str, str, int]]]:
    return {path.stem: _imports(path) for path in sorted(PACKAGE.glob("*.py"))}


def test_every_module_has_a_layer():
    modules = {path.stem for path in PACKAGE.glob("*.py")} | {"_core"}
    assert modules == set(LAYERS), "add the module to LAYERS (and docs/design.md)"


def test_no_import_runs_up_a_layer():
    upward = [
        f"{module}.py:{line}: imports {target} ({LAYER_NAMES[LAYERS[target]]}) from "
        f"{LAYER_NAMES[LAYERS[module]]}"
        for module, imports in _graph().items()
        for target, _, line in imports
        if target in LAYERS and LAYERS[target] > LAYERS[module]
    ]
    assert not upward, "\n".join(upward)


def test_no_circle():
    edges = {
        module: {target for target, _, _ in imports if target != module}
        for module, imports in _graph().items()
    }
    done: set[str] = set()
    path: list[str] = []

    def visit(module: str) -> None:
        if module in path:
            circle = path[path.index(module) :] + [module]
            pytest.fail("import circle: " + " -> ".join(circle))
        if module in done:
            return
        path.append(module)
        for target in sorted(edges.get(module, ())):
            visit(target)
        path.pop()
        done.add(module)

    for module in sorted(edges):
        visit(module)


def test_no_private_name_crosses_a_module():
    private = [
        f"{module}.py:{line}: from {target} import {name}"
        for module, imports in _graph().items()
        for target, name, line in imports
        if name.startswith("_") and not (name.startswith("__") and name.endswith("__"))
    ]
    assert not private, "\n".join(private)


def test_no_module_is_over_600_lines():
    long = [
        f"{path.name}: {n} lines"
        for path in sorted(PACKAGE.glob("*.py"))
        if (n := len(path.read_text(encoding="utf-8").splitlines())) > 600
    ]
    assert not long, "split along its jobs: " + ", ".join(long)
