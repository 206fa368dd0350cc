"""The documentation site needs no network, and its API pages show the public names first.

Checked without building the site (``PYTHONPATH=src mkdocs build --strict`` does that):

* ``mkdocs.yml`` loads no script or style sheet from another host, turns off the theme's web fonts
  (Google's font host) and registers the hook ``docs/hooks/offline_math.py``, which copies MathJax
  from the package ``jupyter-server-mathjax`` into the built site; the package holds what the
  ``extra_javascript`` entry asks for (skipped where the ``docs`` extra is not installed), and the
  hook's copy works (on a small folder, and, with the package, on MathJax itself);
* every page of ``docs/api`` written as one ``:::`` block per member shows every member that the
  module's own block would show, the public ones first: those in the module's ``__all__`` or exported
  by its package (``saltation``, ``saltation.model``...), then the section "Other members".  A name
  added to a module must be added to its page.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[2]
MKDOCS_YML = ROOT / "mkdocs.yml"
HOOK = ROOT / "docs" / "hooks" / "offline_math.py"
API = ROOT / "docs" / "api"
SRC = ROOT / "src"
OTHER = "## Other members"


def mkdocs_config() -> dict:
    yaml = pytest.importorskip("yaml")

    class Loader(yaml.SafeLoader):
        """Safe loading, with tags such as ``!!python/name:...`` or ``!ENV`` read as plain values."""

    def untagged(loader, suffix, node):
        if isinstance(node, yaml.MappingNode):
            return loader.construct_mapping(node)
        if isinstance(node, yaml.SequenceNode):
            return loader.construct_sequence(node)
        return loader.construct_scalar(node)

    Loader.add_multi_constructor("!", untagged)
    Loader.add_multi_constructor("tag:yaml.org,2002:python/", untagged)
    return yaml.load(MKDOCS_YML.read_text(), Loader=Loader)


def hook_module():
    spec = importlib.util.spec_from_file_location("offline_math_hook", HOOK)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def entry_path(entry) -> str:
    """An ``extra_javascript``/``extra_css`` entry: a path, or a mapping with ``path`` (mkdocs >= 1.5)."""
    return entry["path"] if isinstance(entry, dict) else entry


def site_mathjax_configs(config: dict) -> list[str]:
    """The ``?config=`` names of the ``extra_javascript`` entries that load the site's own MathJax."""
    names = []
    for entry in config.get("extra_javascript") or []:
        match = re.match(r"assets/mathjax/MathJax\.js\?config=([^&#]+)$", entry_path(entry))
        if match:
            names.append(match.group(1))
    return names


# ---------------------------------------------------------------------------------------------------------------
# mkdocs.yml
# ---------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("key", ["extra_javascript", "extra_css"])
def test_no_remote_scripts_or_styles(key):
    config = mkdocs_config()
    remote = [p for p in map(entry_path, config.get(key) or []) if re.match(r"(https?:)?//", p.strip(), re.IGNORECASE)]
    assert remote == [], f"{key} loads from the network: {remote}"


def test_theme_fonts_are_off():
    assert mkdocs_config()["theme"].get("font") is False, "theme: font: false (no fonts from Google's font host)"


def test_offline_math_hook_is_registered():
    config = mkdocs_config()
    assert "docs/hooks/offline_math.py" in config.get("hooks", [])
    assert "docs/hooks/gallery.py" in config.get("hooks", [])
    assert HOOK.is_file()


def test_site_mathjax_is_loaded_after_its_configuration():
    config = mkdocs_config()
    scripts = [entry_path(e) for e in config["extra_javascript"]]
    assert len(site_mathjax_configs(config)) == 1, scripts
    loader = next(i for i, s in enumerate(scripts) if s.startswith("assets/mathjax/MathJax.js"))
    assert "javascripts/mathjax.js" in scripts[:loader]
    # docs/javascripts/mathjax.js configures MathJax 2 for arithmatex's generic output
    extensions = {next(iter(e)) if isinstance(e, dict) else e: e for e in config["markdown_extensions"]}
    assert extensions["pymdownx.arithmatex"]["pymdownx.arithmatex"]["generic"] is True
    script = (ROOT / "docs" / "javascripts" / "mathjax.js").read_text()
    assert "tex2jax" in script and 'processClass: "arithmatex"' in script and "STIX-Web" in script


def test_hook_finds_the_configurations_named():
    hook = hook_module()
    config = mkdocs_config()
    assert hook.configs_named(config["extra_javascript"]) == site_mathjax_configs(config)


# ---------------------------------------------------------------------------------------------------------------
# MathJax and the hook's copy
# ---------------------------------------------------------------------------------------------------------------


def test_package_holds_what_the_site_loads():
    package = pytest.importorskip("jupyter_server_mathjax")
    static = Path(package.__file__).parent / "static"
    assert (static / "MathJax.js").is_file()
    for name in site_mathjax_configs(mkdocs_config()):
        assert (static / "config" / f"{name}.js").is_file(), name
    # what docs/javascripts/mathjax.js relies on: TeX input, HTML-CSS output with the STIX-Web fonts
    assert (static / "jax" / "input" / "TeX" / "config.js").is_file()
    assert (static / "jax" / "output" / "HTML-CSS" / "fonts" / "STIX-Web" / "fontdata.js").is_file()
    assert any((static / "fonts" / "HTML-CSS" / "STIX-Web").rglob("*.woff"))
    assert hook_module().mathjax_source() == static


def test_copy_mathjax(tmp_path):
    hook = hook_module()
    source = tmp_path / "static"
    for path in ["MathJax.js", "config/TeX-AMS-MML_HTMLorMML-full.js", "jax/input/TeX/config.js",
                 "jax/output/HTML-CSS/jax.js", "jax/output/SVG/jax.js", "fonts/HTML-CSS/STIX-Web/woff/a.woff"]:
        (source / path).parent.mkdir(parents=True, exist_ok=True)
        (source / path).write_text(path)
    target = tmp_path / "site" / hook.TARGET
    target.mkdir(parents=True)
    (target / "stale.js").write_text("from an earlier build")

    assert hook.copy_mathjax(source, target) == 5
    assert (target / "MathJax.js").read_text() == "MathJax.js"
    assert (target / "config" / "TeX-AMS-MML_HTMLorMML-full.js").is_file()
    assert (target / "jax" / "output" / "HTML-CSS" / "jax.js").is_file()
    assert (target / "fonts" / "HTML-CSS" / "STIX-Web" / "woff" / "a.woff").is_file()
    assert not (target / "jax" / "output" / "SVG").exists()      # in hook.EXCLUDE
    assert not (target / "stale.js").exists()                     # the folder is replaced

    assert hook.copy_mathjax(source, target, exclude=()) == 6


def test_post_build_copies_mathjax_into_the_site(tmp_path):
    pytest.importorskip("jupyter_server_mathjax")
    hook = hook_module()
    hook.on_post_build({"site_dir": str(tmp_path)})
    copied = tmp_path / "assets" / "mathjax"
    assert (copied / "MathJax.js").is_file()
    for name in site_mathjax_configs(mkdocs_config()):
        assert (copied / "config" / f"{name}.js").is_file()


def test_config_check_rejects_a_missing_mathjax_configuration():
    pytest.importorskip("jupyter_server_mathjax")
    exceptions = pytest.importorskip("mkdocs.exceptions")
    hook = hook_module()
    config = {"extra_javascript": ["javascripts/mathjax.js", "assets/mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full"]}
    assert hook.on_config(config) is config
    with pytest.raises(exceptions.PluginError, match="no-such-config"):
        hook.on_config({"extra_javascript": ["assets/mathjax/MathJax.js?config=no-such-config"]})


# ---------------------------------------------------------------------------------------------------------------
# API pages: public names first
# ---------------------------------------------------------------------------------------------------------------


def module_file(module: str) -> Path:
    base = SRC.joinpath(*module.split("."))
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


def declared_all(tree: ast.Module) -> list[str] | None:
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "__all__" for t in node.targets):
            return [e.value for e in node.value.elts]
    return None


def top_level(body) -> list[ast.stmt]:
    """Module-level statements, including those under ``if``/``try`` at module level."""
    out = []
    for node in body:
        out.append(node)
        if isinstance(node, ast.If):
            out += top_level(node.body) + top_level(node.orelse)
        elif isinstance(node, ast.Try):
            out += top_level(node.body) + top_level(node.orelse) + top_level(node.finalbody)
            for handler in node.handlers:
                out += top_level(handler.body)
    return out


def documented_names(module: str) -> set[str]:
    """What ``::: module`` shows with the site's options: public-looking names defined in the module,
    and the imported ones its ``__all__`` lists."""
    tree = ast.parse(module_file(module).read_text())
    names = set(declared_all(tree) or [])
    for node in top_level(tree.body):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif type(node).__name__ == "TypeAlias":
            names.add(node.name.id)
    return {n for n in names if not n.startswith("_")}


def exported_by_packages(module: str) -> set[str]:
    """Names that a package above ``module`` (``saltation``, ``saltation.model``...) imports from it and
    lists in its ``__all__``."""
    parts, out = module.split("."), set()
    for depth in range(1, len(parts)):
        package = ".".join(parts[:depth])
        tree = ast.parse(module_file(package).read_text())
        exported = set(declared_all(tree) or [])
        for node in tree.body:
            if isinstance(node, ast.ImportFrom):
                source = node.module or ""
                if node.level:
                    source = ".".join(parts[:depth - node.level + 1] + ([source] if source else []))
                if source == module:
                    out.update(a.asname or a.name for a in node.names if (a.asname or a.name) in exported)
        # a package that imports its names on first use (PEP 562) says where each lives in ``_HOME_OF``
        home_of = getattr(importlib.import_module(package), "_HOME_OF", {})
        out.update(name for name, home in home_of.items() if home == module and name in exported)
    return out


def member_pages() -> list[Path]:
    """The API pages written as a module block without members followed by one block per member."""
    return [p for p in sorted(API.glob("*.md")) if re.search(r"^::: \S+\n    options:\n      members: false\n\n:::",
                                                             p.read_text(), re.MULTILINE)]


def test_api_pages_written_member_by_member_exist():
    pages = {p.name for p in member_pages()}
    assert {"continuation.md", "special_points_continuation.md", "single.md", "integrate.md"} <= pages


@pytest.mark.parametrize("page", member_pages(), ids=lambda p: p.name)
def test_api_page_shows_every_member_public_first(page):
    text = page.read_text()
    module = re.search(r"^::: (\S+)", text, re.MULTILINE).group(1)
    head, _, rest = text.partition(OTHER)
    first = re.findall(r"^::: " + re.escape(module) + r"\.(\w+)$", head, re.MULTILINE)
    later = re.findall(r"^::: " + re.escape(module) + r"\.(\w+)$", rest, re.MULTILINE)
    shown = first + later
    assert len(shown) == len(set(shown)), f"{page.name} shows a member twice"
    assert set(shown) == documented_names(module), (
        f"{page.name}: missing {sorted(documented_names(module) - set(shown))}, "
        f"unknown {sorted(set(shown) - documented_names(module))}")

    tree = ast.parse(module_file(module).read_text())
    public = set(declared_all(tree) or []) | exported_by_packages(module)
    if public:
        assert set(first) == public & set(shown), (
            f"{page.name}: before '{OTHER}' {sorted(set(first) - public)} are not public, "
            f"after it {sorted(public & set(later))} are")
    else:
        assert not later, f"{page.name}: the module declares no public names, so no '{OTHER}'"


def test_continuation_page_opens_with_the_entry_points():
    text = (API / "continuation.md").read_text()
    first = re.findall(r"^::: saltation\.branches\.continuation\.(\w+)$", text, re.MULTILINE)[:2]
    assert first == ["continue_branch", "ContinuationSettings"]
    text = (API / "special_points_continuation.md").read_text()
    first = re.findall(r"^::: saltation\.special_points\.continuation\.(\w+)$", text, re.MULTILINE)[:2]
    assert first == ["continue_orbit", "continue_branch"]
