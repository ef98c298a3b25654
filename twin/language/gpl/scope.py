"""Name and type resolution for the GPL compiler (User Manual ch. 4 "Scope of
Names", ch. 10 "Modules"): what a name means seen from one module and class,
and the static type (symbols.SType) of a declared type."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...errors import ProgramError
from . import ast
from .errors import AMBIGUOUS_SYMBOL, PRIVATE_SYMBOL, TYPE_MISMATCH, UNDEFINED_SYMBOL, UNSUPPORTED, message
from .library import CLASSES
from .symbols import BASIC, ClassSym, DelegateSym, ModuleSym, SType, VarSym, is_public

if TYPE_CHECKING:
    from .compiler import ProjectCompiler

UNSUPPORTED_TYPES = {"long", "int64", "decimal", "int16", "int32", "char", "variant", "date"}


def mangle(*parts: str) -> str:
    return "__".join(p.lower() for p in parts)


def _error(code: int, detail: str, file: str, node, program: str | None = None) -> ProgramError:
    return ProgramError(
        f"{message(code)}: {detail}" if detail else message(code), code, file=file,
        line=getattr(node, "line", None) or None, column=getattr(node, "column", None) or None,
        program=program,
    )


class Scope:
    """Name and type resolution from one place in the project."""

    def __init__(self, project: "ProjectCompiler", module: ModuleSym, cls: ClassSym | None):
        self.project = project
        self.module = module
        self.cls = cls

    def fail(self, code: int, detail: str, node) -> ProgramError:
        return _error(code, detail, self.module.file, node)

    # ---- types
    def resolve_type(self, ref: ast.TypeRef | None, node) -> SType:
        if ref is None:
            raise self.fail(TYPE_MISMATCH, "the data type must be specified (As type)", node)
        key = ref.key
        if key in BASIC:
            return SType(key, None, ref.rank)
        if key == "object":
            raise self.fail(UNSUPPORTED, "As Object: every object needs an explicit class (ch. 5)", node)
        if key in UNSUPPORTED_TYPES:
            raise self.fail(UNSUPPORTED, f"data type {ref.parts[-1]} (ch. 4, Table 4-2)", node)
        target = self.lookup_path([p.lower() for p in ref.parts], node, types_only=True)
        if isinstance(target, ClassSym):
            return SType("user", target, ref.rank)
        if isinstance(target, DelegateSym):
            return SType("delegate", target, ref.rank)
        if isinstance(target, type):
            return SType("lib", target, ref.rank)
        raise self.fail(UNDEFINED_SYMBOL, f"type {'.'.join(ref.parts)}", node)

    def declarator_type(self, d: ast.Declarator) -> SType:
        if d.type is None:
            raise self.fail(TYPE_MISMATCH, f"{d.name}: the data type must be specified (As type)", d)
        base = self.resolve_type(d.type, d)
        rank = len(d.bounds) if d.bounds is not None else 0
        return SType(base.base, base.ref, rank)

    def param_type(self, p: ast.Param, node) -> SType:
        if p.type is None:
            raise self.fail(TYPE_MISMATCH, f"parameter {p.name}: the data type must be specified", node)
        return self.resolve_type(p.type, node)

    # ---- names
    def lookup_path(self, parts: list[str], node, types_only: bool = False):
        first = self.lookup(parts[0], node, types_only)
        for part in parts[1:]:
            first = self.member_of_namespace(first, part, node)
        return first

    def lookup(self, key: str, node, types_only: bool = False):
        """A name seen from this scope (ch. 4 "Scope of Names"), or None."""
        cls = self.cls
        while cls is not None:
            found = cls.member(key)
            if found is not None and not (types_only and not isinstance(found, (ClassSym, DelegateSym))):
                return found
            if key == cls.key:
                return cls
            cls = cls.parent
        found = self.module.member(key)
        if found is not None:
            return found
        if key in self.project.modules:
            return self.project.modules[key]
        candidates = [m.member(key) for m in self.project.module_order if m is not self.module]
        candidates = [c for c in candidates if c is not None and is_public(c)]
        if len(candidates) > 1:
            raise self.fail(AMBIGUOUS_SYMBOL, key, node)
        if candidates:
            return candidates[0]
        for module in self.project.module_order:  # a public class's classes, by name
            for c in module.classes.values():
                if c.key == key and (c.public or module is self.module):
                    return c
        shared = [c.member(key) for c in self.project.classes]
        shared = [v for v in shared if isinstance(v, VarSym) and v.kind == "shared" and v.public]
        if len(shared) > 1:
            raise self.fail(AMBIGUOUS_SYMBOL, key, node)
        if shared:  # a class's Public Const / Shared variable, unqualified where it is unique
            return shared[0]
        if key in CLASSES:
            return CLASSES[key]
        return None

    def member_of_namespace(self, owner, key: str, node):
        if isinstance(owner, (ModuleSym, ClassSym)):
            found = owner.member(key)
            if found is None:
                raise self.fail(UNDEFINED_SYMBOL, f"{owner.name}.{getattr(node, 'name', key)}", node)
            if not is_public(found) and not self.inside(owner):
                raise self.fail(PRIVATE_SYMBOL, f"{owner.name}.{found.name}", node)
            return found
        raise self.fail(UNDEFINED_SYMBOL, key, node)

    def inside(self, owner) -> bool:
        if isinstance(owner, ModuleSym):
            return owner is self.module
        cls = self.cls
        while cls is not None:
            if cls is owner:
                return True
            cls = cls.parent
        return False
