"""The documentation site (mkdocs.yml): it builds with no warning, and every page and API reference page is in it.

`mkdocs.yml`'s `validation:` settings turn a broken link, a missing anchor and a docs page left out of the nav into
warnings, and `--strict` turns every warning (griffe's docstring complaints included) into a failed build. The
griffe extension scripts/griffe_rst.py, which makes the docstrings' reStructuredText read as Markdown, is tested here
too.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SUBPACKAGES = sorted(p.parent.name for p in (ROOT / "rgbt_toolkit").glob("*/__init__.py"))


def _nav_pages() -> list[str]:
    from mkdocs.config import load_config

    pages: list[str] = []

    def walk(entry):
        if isinstance(entry, str):
            pages.append(entry)
        elif isinstance(entry, dict):
            for value in entry.values():
                walk(value)
        elif isinstance(entry, list):
            for item in entry:
                walk(item)

    walk(load_config(str(ROOT / "mkdocs.yml"))["nav"])
    return pages


@pytest.mark.slow
def test_the_site_builds_strict_with_no_warning(tmp_path):
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")  # Material's banner about MkDocs 2 is not a build warning
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file", "mkdocs.yml",
                           "--site-dir", str(tmp_path / "site")], cwd=ROOT, env=env, capture_output=True, text=True,
                          timeout=600)
    warnings = [line for line in done.stderr.splitlines() if not line.startswith("INFO")]
    assert done.returncode == 0 and not [w for w in warnings if "WARNING" in w], "\n".join(warnings)
    reference = (tmp_path / "site" / "reference" / "eco.html").read_text(encoding="utf-8")
    # the reference is generated from the code: a class of the subpackage and a parameter from its docstring
    assert 'id="rgbt_toolkit.eco.EcoTracker"' in reference and "learning_rate" in reference
    # the docstrings' Sphinx roles are links (scripts/griffe_rst.py), never literal text
    batch = (tmp_path / "site" / "reference" / "batch.html").read_text(encoding="utf-8")
    assert 'href="#rgbt_toolkit.batch.items"><code>items</code></a>' in batch
    for page in (tmp_path / "site" / "reference").glob("*.html"):
        html = page.read_text(encoding="utf-8")
        assert not re.search(r":(func|class|mod|meth|data|attr|exc):", html), page.name
        assert "<blockquote>" not in html, f"{page.name}: a >>> line read as a Markdown quote"


def test_broken_links_and_anchors_and_pages_left_out_are_warnings():
    """What makes the strict build check links: each of these would otherwise pass silently (or as INFO)."""
    import logging

    from mkdocs.config import load_config

    validation = load_config(str(ROOT / "mkdocs.yml"))["validation"]
    assert dict(validation["nav"]) == dict.fromkeys(
        ("omitted_files", "not_found", "absolute_links"), logging.WARNING)
    assert dict(validation["links"]) == dict.fromkeys(
        ("not_found", "absolute_links", "unrecognized_links", "anchors"), logging.WARNING)


def test_every_docs_page_and_subpackage_is_in_the_nav():
    """The strict build also refuses a page left out of the nav; this names it without a build."""
    nav = _nav_pages()
    pages = sorted(p.relative_to(ROOT / "docs").as_posix() for p in (ROOT / "docs").rglob("*.md"))
    assert sorted(nav) == pages
    assert SUBPACKAGES and {f"reference/{name}.md" for name in SUBPACKAGES if name != "api"} <= set(nav)
    root = (ROOT / "docs" / "reference" / "index.md").read_text(encoding="utf-8")
    from rgbt_toolkit.api import EXPORTS

    documented = set(re.findall(r"^::: rgbt_toolkit\.api\.\w+\.(\w+)$", root, flags=re.M))
    assert documented == set(EXPORTS), "docs/reference/index.md must document each name of the public API"


def test_every_reference_page_documents_its_subpackage():
    for name in SUBPACKAGES:
        if name == "api":  # the package root's page documents it (above)
            continue
        text = (ROOT / "docs" / "reference" / f"{name}.md").read_text(encoding="utf-8")
        assert re.search(rf"^::: rgbt_toolkit\.{name}$", text, flags=re.M), name


def test_readme_links_into_the_docs_resolve():
    """README.md is not part of the site, so the build does not see its links; they must name existing files."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    targets = [t for t in re.findall(r"\]\(([^)\s]+)\)", readme) if not re.match(r"[a-z]+:", t)]
    assert targets, "README.md links nowhere"
    for target in targets:
        path, _, anchor = target.partition("#")
        assert (ROOT / path).exists(), target
        if anchor and path.endswith(".md"):
            from pymdownx.slugs import slugify  # the site's heading anchors (mkdocs.yml), GitHub's too

            heads = re.findall(r"^#+ (.+)$", (ROOT / path).read_text(encoding="utf-8"), flags=re.M)
            assert anchor in {slugify(case="lower")(h, "-") for h in heads}, target


def _extension():
    import importlib.util

    spec = importlib.util.spec_from_file_location("griffe_rst", ROOT / "scripts" / "griffe_rst.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_role_links_to_the_nearest_object_of_its_name():
    extension = _extension()
    documented = {"pkg.mod.helper": "pkg.mod.helper", "pkg.Thing": "pkg.core.Thing", "pkg.mod": "pkg.mod"}
    text = extension.replace_roles(
        "Uses :func:`helper`, :class:`~pkg.Thing`, :mod:`pkg.mod` and :meth:`_private`; ``:func:`` alone stays.",
        "pkg.mod.run", documented.get)
    assert text == ('Uses <autoref identifier="pkg.mod.helper" optional><code>helper</code></autoref>, '
                    '<autoref identifier="pkg.core.Thing" optional><code>Thing</code></autoref>, '
                    '<autoref identifier="pkg.mod" optional><code>pkg.mod</code></autoref> and '
                    '<autoref identifier="_private" optional><code>_private</code></autoref>; ``:func:`` alone stays.')
    assert extension.candidates("f", "a.b.c") == ["a.b.c.f", "a.b.f", "a.f", "f"]


def test_prompt_lines_become_a_code_block_and_a_literal_opener_a_colon():
    extension = _extension()
    text = "Use it.\n\n>>> a = f()\n>>> a.run(1,\n...       2)\n\nThen::\n\n    {\"key\": 1}\n"
    assert extension.markdown_blocks(text) == ("Use it.\n\n```pycon\n>>> a = f()\n>>> a.run(1,\n...       2)\n```\n\n"
                                           "Then:\n\n    {\"key\": 1}\n")
    numpydoc = "Run.\n\nExamples\n--------\n>>> f()\n1\n"
    assert extension.markdown_blocks(numpydoc) == numpydoc  # mkdocstrings formats an Examples section itself


def test_parameters_documented_together_are_written_out_one_by_one():
    extension = _extension()
    text = ("Parameters\n----------\na, b : int\n    Sizes.\n\n    In pixels.\nc, d :\n    As before.\nx, y : float\n"
            "    Not both parameters: left alone.\n")
    assert extension.split_grouped_parameters(text, {"a", "b", "c", "d", "x"}) == (
        "Parameters\n----------\na : int\n    Sizes.\n\n    In pixels.\nb : int\n    Sizes.\n\n    In pixels.\n"
        "c :\n    As before.\nd :\n    As before.\nx, y : float\n    Not both parameters: left alone.\n")


def test_each_parameter_of_a_group_shows_its_own_default():
    """griffe alone gives `track`'s `preset, features, ... :` group the first one's default ('default')."""
    import griffe

    extension = griffe.load_extensions(str(ROOT / "scripts" / "griffe_rst.py"))
    package = griffe.load("rgbt_toolkit", search_paths=[str(ROOT)], docstring_parser="numpy", extensions=extension)
    sections = package["api.tracking.track"].docstring.parsed
    defaults = {p.name: str(p.default) for s in sections if s.kind.value == "parameters" for p in s.value}
    assert (defaults["preset"], defaults["features"], defaults["motion_model"]) == ("'default'", "'hc'", "'affine'")
