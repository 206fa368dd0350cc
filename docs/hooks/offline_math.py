"""mkdocs hook: serve MathJax from the built site, so that formulas render with no network.

The formulas of the documentation (``pymdownx.arithmatex`` in generic mode) are typeset in the
browser by MathJax 2.  MathJax comes from the Python package ``jupyter-server-mathjax`` (the ``docs``
extra), which ships it under ``jupyter_server_mathjax/static/``; ``on_post_build`` copies that folder
into the built site as ``assets/mathjax/`` (:data:`TARGET`), leaving out what the site does not use
(:data:`EXCLUDE`).  ``mkdocs.yml`` loads it with a relative path::

    extra_javascript:
      - javascripts/mathjax.js                                           # the configuration
      - assets/mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full      # MathJax itself

``on_config`` checks that the package is installed and that the combined configuration named by
``?config=`` is part of it, so a missing piece fails the build instead of a page's formulas.

Run ``python docs/hooks/offline_math.py DESTINATION`` to copy MathJax by hand.
"""

from __future__ import annotations

import importlib.util
import logging
import re
import shutil
import sys
from pathlib import Path

log = logging.getLogger("mkdocs.hooks.offline_math")

#: The package holding MathJax, and the folder of MathJax inside it.
PACKAGE = "jupyter_server_mathjax"
STATIC = "static"

#: Where MathJax goes in the built site (``mkdocs.yml``'s ``extra_javascript`` points here).
TARGET = "assets/mathjax"

#: Paths under the static folder that are not copied: the SVG output processor (the configuration
#: ``TeX-AMS-MML_HTMLorMML-full`` renders with HTML-CSS, and ``docs/javascripts/mathjax.js`` hides
#: the renderer menu).  TeX input, HTML-CSS output with its STIX-Web fonts, the extensions TeX
#: macros load on demand, the menus' translations and the accessibility extensions are kept.
EXCLUDE = ("jax/output/SVG",)

_SCRIPT = re.compile(r"^" + re.escape(TARGET) + r"/MathJax\.js(?:\?config=([^&#]+))?")


class OfflineMathError(Exception):
    """MathJax cannot be served from the site (mkdocs reports it and stops the build)."""


def mathjax_source() -> Path:
    """The static folder of the installed ``jupyter_server_mathjax`` (the package is not imported)."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or not spec.submodule_search_locations:
        raise OfflineMathError(
            f"the docs need the package {PACKAGE.replace('_', '-')} (MathJax for the formulas): "
            'pip install -e ".[docs]"'
        )
    static = Path(next(iter(spec.submodule_search_locations))) / STATIC
    if not (static / "MathJax.js").is_file():
        raise OfflineMathError(f"{static} holds no MathJax.js")
    return static


def copy_mathjax(source: Path, destination: Path, exclude: tuple[str, ...] = EXCLUDE) -> int:
    """Copy MathJax's folder ``source`` to ``destination`` (replaced), without the paths ``exclude``.

    ``exclude`` holds paths relative to ``source``, with ``/``.  Returns the number of files copied.
    """
    source, destination = Path(source), Path(destination)
    skipped = {Path(p) for p in exclude}

    def ignore(folder: str, names: list[str]) -> set[str]:
        here = Path(folder).relative_to(source)
        return {name for name in names if here / name in skipped}

    if destination.exists():
        shutil.rmtree(destination)
    shutil.copytree(source, destination, ignore=ignore)
    return sum(1 for p in destination.rglob("*") if p.is_file())


def configs_named(scripts) -> list[str]:
    """The combined configurations that ``extra_javascript`` entries loading the site's MathJax name."""
    names = []
    for script in scripts:
        match = _SCRIPT.match(str(getattr(script, "path", script)))
        if match and match.group(1):
            names.append(match.group(1))
    return names


def on_config(config):
    from mkdocs.exceptions import PluginError

    try:
        source = mathjax_source()
    except OfflineMathError as err:
        raise PluginError(str(err)) from err
    for name in configs_named(config["extra_javascript"]):
        if not (source / "config" / f"{name}.js").is_file():
            raise PluginError(f"extra_javascript asks MathJax for config={name}, which {source / 'config'} lacks")
    return config


def on_post_build(config):
    from mkdocs.exceptions import PluginError

    try:
        source = mathjax_source()
    except OfflineMathError as err:
        raise PluginError(str(err)) from err
    count = copy_mathjax(source, Path(config["site_dir"]) / TARGET)
    log.debug("copied MathJax (%d files) from %s to %s", count, source, TARGET)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python docs/hooks/offline_math.py DESTINATION")
    print(copy_mathjax(mathjax_source(), Path(sys.argv[1])), "files")
