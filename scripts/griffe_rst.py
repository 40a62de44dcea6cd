"""Griffe extension for the documentation site: the docstrings' reStructuredText habits read as Markdown.

The docstrings cross-reference with Sphinx roles (``:func:`~rgbt_toolkit.batch.runner.run_batch```, ``:class:`Foo```),
which MkDocs would show as literal text. Before mkdocstrings renders a docstring, each role becomes an optional
mkdocs-autorefs reference: a link when the target is on the site, plain code when it is not (a private helper, say),
never a warning. A relative name is looked up from the object outwards (its class, module, package), as Sphinx does.
Outside a numpydoc ``Examples`` section (which mkdocstrings formats itself), a run of ``>>>`` lines becomes a code
block instead of a Markdown quote, and the ``::`` that opens an indented literal block reads as ``:``. Parameters
documented together (``preset, features : str``) are written out one by one, so that each shows its own default
(griffe gives the whole group the first one's).
mkdocs.yml loads it with ``extensions: [scripts/griffe_rst.py]``.
"""

from __future__ import annotations

import html
import re
from typing import Callable

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|class|mod|meth|data|attr|exc|obj):`(?P<tilde>~?)(?P<target>[\w.]+)`")
EXAMPLES_SECTION = re.compile(r"^[ \t]*Examples[ \t]*\n[ \t]*-{3,}[ \t]*$", re.M)
PROMPTS = re.compile(r"^(?P<indent>[ \t]*)>>> .*(?:\n(?P=indent)(?:>>>|\.\.\.)(?: .*)?)*$", re.M)
LITERAL_OPENER = re.compile(r"::\n(?=\n[ \t]+\S)")
GROUPED = re.compile(r"^(?P<indent>[ \t]*)(?P<names>\w+(?:, \w+)+)(?P<rest> :(?: .*)?)$")


def candidates(target: str, scope: str) -> list[str]:
    """Full paths ``target`` may name when written inside the object at ``scope``, nearest first."""
    parts = scope.split(".")
    return [".".join(parts[:n] + [target]) for n in range(len(parts), 0, -1)] + [target]


def replace_roles(text: str, scope: str, resolve: Callable[[str], str | None]) -> str:
    """``text`` with each role turned into an optional autoref to the first candidate path that ``resolve`` finds
    (``resolve`` returns the path the object is documented under, or None)."""

    def autoref(match: re.Match) -> str:
        target = match["target"]
        path = next((found for p in candidates(target, scope) if (found := resolve(p)) is not None), target)
        title = target.rsplit(".", 1)[-1] if match["tilde"] else target
        return f'<autoref identifier="{html.escape(path)}" optional><code>{html.escape(title)}</code></autoref>'

    return ROLE.sub(autoref, text)


def markdown_blocks(text: str) -> str:
    """``>>>`` runs fenced as Python sessions and ``::`` literal-block openers as ``:``, outside ``Examples``."""
    if EXAMPLES_SECTION.search(text):
        return text
    text = PROMPTS.sub(lambda m: f"{m['indent']}```pycon\n{m[0]}\n{m['indent']}```", text)
    return LITERAL_OPENER.sub(":\n", text)


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def split_grouped_parameters(text: str, parameters: set[str]) -> str:
    """Each ``a, b : type`` entry whose names are all ``parameters`` written as one entry per name, each with the
    description (the more indented lines below it, blank lines within included)."""
    lines, out, i = text.split("\n"), [], 0
    while i < len(lines):
        match = GROUPED.match(lines[i])
        names = match["names"].split(", ") if match else []
        if not names or not set(names) <= parameters:
            out.append(lines[i])
            i += 1
            continue
        base, end = len(match["indent"]), i + 1
        while end < len(lines):
            line = lines[end]
            if line.strip() and _indent(line) <= base:
                break
            if not line.strip() and not (end + 1 < len(lines) and lines[end + 1].strip()
                                         and _indent(lines[end + 1]) > base):
                break
            end += 1
        for name in names:
            out += [match["indent"] + name + match["rest"], *lines[i + 1:end]]
        i = end
    return "\n".join(out)


class RestToMarkdown(griffe.Extension):
    """Rewrites every docstring of the package once it is loaded."""

    def on_package(self, *, pkg: griffe.Module, **kwargs) -> None:
        def resolve(path: str) -> str | None:
            """Where ``path`` is documented: itself, or for an imported name the object it imports."""
            if path == pkg.path:
                return path
            if not path.startswith(pkg.path + "."):
                return None
            try:
                found = pkg[path[len(pkg.path) + 1:]]
                return found.final_target.path if found.is_alias else found.path
            except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
                return None

        def visit(obj: griffe.Object) -> None:
            if obj.docstring is not None:
                text = markdown_blocks(replace_roles(obj.docstring.value, obj.path, resolve))
                if obj.is_function or obj.is_class:
                    try:
                        names = {parameter.name for parameter in obj.parameters}
                    except (AttributeError, griffe.AliasResolutionError):
                        names = set()
                    text = split_grouped_parameters(text, names)
                obj.docstring.value = text
            for member in obj.members.values():
                if not member.is_alias:
                    visit(member)

        visit(pkg)
