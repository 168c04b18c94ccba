"""Griffe extension for the API reference: Sphinx cross-reference roles in docstrings become Markdown links.

bldclab's numpydoc docstrings refer to other objects with Sphinx roles (``:func:`simulate```,
``:class:`~bldclab.sim.results.SimResult```). mkdocstrings renders Markdown, where a role would show as literal text,
so before rendering every role is rewritten:

- to an autorefs link ``[`SimResult`][bldclab.sim.results.SimResult]`` when the target resolves (from the object's
  own scope, as Sphinx would) to a public object that the API reference renders (a documented module's public
  member with a docstring); re-exports (``bldclab.Drive``) link to their definition;
- to inline code otherwise (a private helper, an object of another package such as ``matplotlib.figure.Figure``),
  so that no link can point nowhere.

``~`` keeps only the last component of the displayed name, as in Sphinx.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(class|func|meth|mod|attr|data|obj|exc|const):`(~?)([^`<>]+?)`")


class SphinxRoles(griffe.Extension):
    """Rewrite Sphinx roles in the docstrings of one package to autorefs links or inline code."""

    def __init__(self, documented: list[str] | None = None) -> None:
        """Set the modules the reference renders (their public members are link targets).

        Parameters
        ----------
        documented : list of str, optional
            Dotted module names; default every public module of the package.
        """
        super().__init__()
        self.documented = set(documented) if documented else None

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        """Rewrite the roles of every docstring of the package once it is loaded."""
        collection = loader.modules_collection
        for obj in _walk(pkg):
            if obj.docstring is not None and ":" in obj.docstring.value:
                obj.docstring.value = _ROLE.sub(lambda m, o=obj: self._replace(m, o, collection),
                                                obj.docstring.value)

    def _replace(self, match: re.Match[str], obj: griffe.Object, collection: griffe.ModulesCollection) -> str:
        role, tilde, target = match.group(1), match.group(2), match.group(3).strip()
        shown = target.rsplit(".", 1)[-1] if tilde else target
        if role in ("func", "meth") and not shown.endswith(")"):
            shown += "()"
        path = self._resolve(obj, target, collection)
        return f"[`{shown}`][{path}]" if path else f"`{shown}`"

    def _resolve(self, obj: griffe.Object, target: str, collection: griffe.ModulesCollection) -> str | None:
        """Return the canonical path of a rendered object the role names, or None."""
        candidates = [target]
        scopes = [obj, *_parents(obj)]
        for scope in scopes:
            candidates.append(f"{scope.path}.{target}")
            try:
                candidates.append(scope.resolve(target.split(".", 1)[0]) + target[len(target.split(".", 1)[0]):])
            except (griffe.NameResolutionError, AttributeError, KeyError):
                pass
        for path in candidates:
            try:
                found = collection[path]
            except (KeyError, ValueError, IndexError, griffe.AliasResolutionError, griffe.CyclicAliasError):
                continue
            try:
                final = found.final_target if found.is_alias else found
            except (griffe.AliasResolutionError, griffe.CyclicAliasError):
                return None
            return final.path if self._rendered(final) else None
        return None

    def _rendered(self, obj: Any) -> bool:
        """Return whether the API reference renders this object (so a link to it resolves)."""
        if obj.is_module:
            return self._module_documented(obj.path)
        if obj.docstring is None or any(part.startswith("_") for part in obj.path.split(".")):
            return False
        if not obj.is_public:
            return False
        parent = obj.parent
        while parent is not None and not parent.is_module:
            if not parent.is_public or parent.docstring is None:
                return False
            parent = parent.parent
        return parent is not None and self._module_documented(parent.path)

    def _module_documented(self, path: str) -> bool:
        if any(part.startswith("_") for part in path.split(".")):
            return False
        return self.documented is None or path in self.documented


def _parents(obj: griffe.Object) -> list[griffe.Object]:
    out = []
    parent = obj.parent
    while parent is not None:
        out.append(parent)
        parent = parent.parent
    return out


def _walk(obj: griffe.Object) -> list[griffe.Object]:
    """Every object defined in the package (aliases skipped: their docstrings belong to their targets)."""
    out = [obj]
    for member in obj.members.values():
        if not member.is_alias:
            out.extend(_walk(member))
    return out
