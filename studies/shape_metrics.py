"""The code's shape, measured: what docs/ARCHITECTURE.md promises about layers, sizes and imports.

Run from the repository root: ``python studies/shape_metrics.py [--functions N]``.  Prints the top-level modules
of ``synthesis/``, the share of imports written inside function bodies, the longest functions, the largest
module of the CLI package, the lines of ``synthesis/`` and of the toy kind, and every ContextVar or assignment
to a library attribute (a monkeypatch) left in the package.  A study, not part of any run: the tests do not
import it.
"""

from __future__ import annotations

import argparse
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = [ROOT / "synthesis"]


def python_files() -> list[Path]:
    return sorted(p for pkg in PACKAGES for p in pkg.rglob("*.py") if "__pycache__" not in p.parts)


class _Walker(ast.NodeVisitor):
    def __init__(self) -> None:
        self.depth = 0
        self.top = 0
        self.nested: list[int] = []
        self.functions: list[tuple[int, str, int]] = []

    def _function(self, node) -> None:
        self.functions.append((node.end_lineno - node.lineno + 1, node.name, node.lineno))
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_FunctionDef = visit_AsyncFunctionDef = _function

    def _import(self, node) -> None:
        if self.depth:
            self.nested.append(node.lineno)
        else:
            self.top += 1

    visit_Import = visit_ImportFrom = _import


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--functions", type=int, default=10, help="how many of the longest functions to list")
    parser.add_argument("--nested", action="store_true", help="list every import inside a function")
    args = parser.parse_args()
    top = nested = 0
    functions = []
    nested_at = []
    lines = 0
    patches = []
    for path in python_files():
        text = path.read_text()
        lines += text.count("\n")
        tree = ast.parse(text)
        walker = _Walker()
        walker.visit(tree)
        top += walker.top
        nested += len(walker.nested)
        rel = path.relative_to(ROOT)
        nested_at += [f"{rel}:{n}" for n in walker.nested]
        functions += [(n, f"{rel}:{line} {name}") for n, name, line in walker.functions]
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) == "ContextVar":
                patches.append(f"{rel}:{node.lineno} ContextVar")
            if isinstance(node, ast.Assign):
                for t in node.targets:
                    if (isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name)
                            and t.value.id in {"ca", "casadi", "np", "numpy", "scipy"}):
                        patches.append(f"{rel}:{node.lineno} assigns {t.value.id}.{t.attr}")
    modules = sorted(p.name for p in (ROOT / "synthesis").glob("*.py") if p.name != "__init__.py")
    cli = sorted(((p.read_text().count("\n"), p.name) for p in (ROOT / "synthesis" / "cli").glob("*.py")), reverse=True)
    toy = ROOT / "tests" / "toy_kind.py"
    print(f"top-level modules in synthesis/: {len(modules)} ({', '.join(modules)})")
    print(f"imports: {top + nested}, inside functions: {nested} ({100 * nested / max(1, top + nested):.1f} %)")
    print(f"lines of synthesis/: {lines}")
    print(f"largest CLI module: {cli[0][1]} ({cli[0][0]} lines)" if cli else "no CLI package")
    if toy.exists():
        print(f"toy kind: {toy.read_text().count(chr(10))} lines")
    print(f"ContextVars and library monkeypatches: {len(patches)}")
    for p in patches:
        print("   ", p)
    print(f"longest functions (of {len(functions)}):")
    for n, where in sorted(functions, reverse=True)[:args.functions]:
        print(f"   {n:4d}  {where}")
    if args.nested:
        print("imports inside functions:")
        for where in nested_at:
            print("   ", where)


if __name__ == "__main__":
    main()
