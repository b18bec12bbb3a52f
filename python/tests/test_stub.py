"""The type stub `_coopnav.pyi` describes the compiled module: every public class and function it
declares exists, and every method and property a stub class declares (its own or a typing-only
base's) exists on the real class."""

import ast
from pathlib import Path

import coopnav._coopnav as compiled

STUB = Path(__file__).resolve().parents[1] / "coopnav" / "_coopnav.pyi"  # the repository's, not the installed copy


def _declared():
    tree = ast.parse(STUB.read_text())
    classes = {node.name: node for node in tree.body if isinstance(node, ast.ClassDef)}

    def members(cls):
        own = [f.name for f in cls.body if isinstance(f, ast.FunctionDef) and not f.name.startswith("__")]
        inherited = [m for base in cls.bases if isinstance(base, ast.Name) for m in members(classes[base.id])]
        return own + inherited

    functions = [n.name for n in tree.body if isinstance(n, ast.FunctionDef)]
    public = {name: members(cls) for name, cls in classes.items() if not name.startswith("_")}
    return functions, public


def test_every_stub_declaration_exists_in_the_compiled_module():
    functions, classes = _declared()
    assert len(functions) >= 3 and len(classes) >= 4, (functions, classes)
    missing = [f for f in functions if not hasattr(compiled, f)]
    missing += [f"{c}.{m}" for c, ms in classes.items() for m in [None, *ms]
                if not hasattr(compiled, c) or (m and not hasattr(getattr(compiled, c), m))]
    assert not missing, f"declared in {STUB.name} but absent at run time: {missing}"
