"""Griffe extension for the API reference: Sphinx roles in docstrings become links.

saltation's docstrings are numpy style and cross-reference with Sphinx roles
(``:class:`Flow```, ``:func:`~saltation.orbits.shooting.find_periodic_orbit```).
mkdocstrings does not read roles, so this extension rewrites each one, once
the package is loaded, into an *optional* autorefs link: a link where the
object is rendered in the reference, plain code where it is not (a private
helper, numpy, scipy). Optional links never warn, so ``mkdocs build --strict``
stays quiet about them; names written in the user guide are checked instead.

Used from ``mkdocs.yml`` (``plugins: mkdocstrings: handlers: python: options:
extensions``). The docstrings themselves are not changed on disk.
"""

from __future__ import annotations

import re

import griffe

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|exc|obj|const):`(~?)([^`<>]+?)(?:\(\))?`")


def _lookup(collection, path: str):
    try:
        return collection[path]
    except (KeyError, ValueError, AttributeError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None


def _canonical(obj) -> str | None:
    try:
        return obj.canonical_path if not obj.is_alias else obj.final_target.path
    except (griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None


def _resolve(collection, where, name: str) -> str | None:
    """The full path of ``name`` as written in a docstring of ``where``: absolute, a member of an
    enclosing scope, or a name imported there."""
    if name.split(".")[0] in collection.members:  # absolute: saltation.engine.flow.Flow
        found = _lookup(collection, name)
        return _canonical(found) if found is not None else None
    head, _, rest = name.partition(".")
    scope = where
    while scope is not None:
        if head in scope.members:
            found = _lookup(collection, f"{scope.path}.{name}")
            if found is not None:
                return _canonical(found)
        scope = scope.parent
    try:
        full = where.resolve(head)
    except (griffe.NameResolutionError, AttributeError):
        return None
    found = _lookup(collection, f"{full}.{rest}" if rest else full)
    return _canonical(found) if found is not None else None


class SphinxRoles(griffe.Extension):
    """Rewrite ``:role:`target``` in every docstring of the package into an optional autorefs link."""

    def on_package(self, *, pkg, loader, **kwargs) -> None:
        collection = loader.modules_collection
        self._walk(collection, pkg)

    def _walk(self, collection, obj) -> None:
        if obj.docstring is not None:

            def link(match: re.Match) -> str:
                tilde, name = match.groups()
                text = name.rsplit(".", 1)[-1] if tilde else name
                target = _resolve(collection, obj, name)
                if target is None:
                    return f"`{text}`"
                return f'<autoref identifier="{target}" optional><code>{text}</code></autoref>'

            obj.docstring.value = ROLE.sub(link, obj.docstring.value)
        for member in obj.members.values():
            if not member.is_alias:
                self._walk(collection, member)
