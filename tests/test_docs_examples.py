"""The code in README.md and docs/ is true: every Python example runs, every `rgbt` command names real options.

Python: each page's ```python (or ```py) blocks run in order, in one namespace, in an empty folder where `samples/`
is the repository's bundled sample (so `samples/demo_rgb.mp4` reads as it does from the repository root), the way a
reader pastes them. A block opts out only with an HTML comment as the last non-blank line before its fence,
`<!-- not-run: the reason -->` (a live camera, say); the comment is invisible on the rendered page.
A page whose examples read `../shared/` runs only where that folder is beside the repository.

Commands: every `rgbt ...` line of the other blocks (set-up lines after `&&` too) is checked against the click
commands: each subcommand exists, answers `--help`, and takes each option the line gives. Nothing is tracked.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,})(?P<info>[^\n`]*)\n(?P<body>.*?)^(?P=indent)(?P=fence)[ \t]*$",
                   re.S | re.M)
NOT_RUN = re.compile(r"<!--\s*not-run:\s*(?P<reason>\S.*?)\s*-->\s*$")
PYTHON = {"python", "py", "python3"}
COMMAND = re.compile(r"(?:^[ \t]*(?:\$[ \t]+)?|&&[ \t]*|;[ \t]*)(rgbt[ \t][^&;#\n]*)", re.M)


def _name(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


def fenced_blocks(text: str):
    """(language, code, not-run reason or None, line number) of each fenced block, indented fences included."""
    for match in FENCE.finditer(text):
        indent = len(match["indent"])
        code = "\n".join(line[indent:] for line in match["body"].splitlines()) + "\n"
        before = text[:match.start()].rstrip("\n").rsplit("\n", 1)[-1]
        marker = NOT_RUN.search(before)
        yield (match["info"].strip().split(" ")[0].lower(), code, marker["reason"] if marker else None,
               text.count("\n", 0, match.start()) + 1)


def python_blocks(page: Path) -> list[tuple[str, int]]:
    return [(code, line) for language, code, reason, line in fenced_blocks(page.read_text(encoding="utf-8"))
            if language in PYTHON and reason is None]


def rgbt_commands(page: Path) -> list[tuple[list[str], int]]:
    """The token lists of the `rgbt ...` commands in the page's non-Python blocks, with their block's line."""
    found = []
    for language, code, _, line in fenced_blocks(page.read_text(encoding="utf-8")):
        if language in PYTHON:
            continue
        for command in COMMAND.findall(code.replace("\\\n", " ")):
            tokens = shlex.split(command.replace("[", " ").replace("]", " ").replace("|", " | "), posix=True)
            found.append((tokens, line))
    return found


# ---- the parser itself, on a page written here ----

SAMPLE = """Text.

```python
a = 1
```

<!-- not-run: needs a camera -->
```py
camera()
```

1. A step:

   ```python
   b = a + 1
   ```

```bash
pip install -e . && rgbt track a.mp4 b.mp4 -o out \\
    --preset full
$ rgbt eval -b gtot [--plot FILE]
```
"""


def test_blocks_are_found_with_their_marker_and_indent(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(SAMPLE)
    assert python_blocks(page) == [("a = 1\n", 3), ("b = a + 1\n", 14)]
    assert [(t[:2], t[-2:]) for t, _ in rgbt_commands(page)] == [(["rgbt", "track"], ["--preset", "full"]),
                                                                 (["rgbt", "eval"], ["--plot", "FILE"])]


# ---- the Python examples ----

def _reads_shared(page: Path) -> bool:
    return any("../shared/" in code for code, _ in python_blocks(page))


RUNNABLE = [pytest.param(page, id=_name(page), marks=[pytest.mark.shared] if _reads_shared(page) else [])
            for page in PAGES if python_blocks(page)]


@pytest.mark.slow
@pytest.mark.parametrize("page", RUNNABLE)
def test_the_python_examples_of_the_page_run(page, tmp_path, monkeypatch):
    blocks = python_blocks(page)
    if _reads_shared(page) and not (SHARED / "README.md").is_file():
        pytest.skip(f"{_name(page)}'s examples read ../shared, which is absent (fresh clone without it)")
    work = tmp_path / "work"
    work.mkdir()
    (work / "samples").symlink_to(ROOT / "samples", target_is_directory=True)
    if SHARED.is_dir():
        (tmp_path / "shared").symlink_to(SHARED, target_is_directory=True)
    monkeypatch.chdir(work)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict = {"__name__": "__docs_example__"}
    for code, line in blocks:
        try:
            exec(compile(code, f"{_name(page)}:{line}", "exec"), namespace)
        except Exception as exc:  # name the failing block, keep the traceback
            raise AssertionError(f"{_name(page)}: the python block at line {line} failed: {exc!r}\n{code}") from exc


def test_a_marker_needs_a_reason_and_opts_out_only_its_own_block(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("<!-- not-run: -->\n```python\nx = 1\n```\n\n<!-- not-run: live -->\n\n```python\ny = 2\n```\n")
    # an empty reason is no marker; a blank line between the marker and the fence is allowed
    assert python_blocks(page) == [("x = 1\n", 2)]


def test_every_page_with_python_examples_runs_some():
    """A page is not turned off as a whole: at least one of its Python blocks runs."""
    for page in PAGES:
        blocks = [b for b in fenced_blocks(page.read_text(encoding="utf-8")) if b[0] in PYTHON]
        if blocks:
            assert python_blocks(page), f"{_name(page)}: every python block is marked not-run"


# ---- the commands ----

COMMANDS = [(page, tokens, line) for page in PAGES for tokens, line in rgbt_commands(page)]


@pytest.fixture(scope="module")
def rgbt():
    from rgbt_cli.main import main

    return main


def command_problems(group, tokens: list[str]) -> list[str]:
    """What is wrong with one `rgbt ...` command line: an unknown command or option; empty when nothing is."""
    import click
    from click.testing import CliRunner

    command, rest, path = group, tokens[1:], ["rgbt"]
    while isinstance(command, click.Group) and rest and not rest[0].startswith("-"):
        name = rest[0].rstrip(",:")
        sub = command.get_command(click.Context(command, info_name=" ".join(path)), name)
        if sub is None:
            return [f"`{' '.join(path)}` has no command {name!r}"]
        command, rest, path = sub, rest[1:], path + [name]
    if command is group:
        return ["`rgbt` without a command"]
    shown = CliRunner().invoke(group, [*path[1:], "--help"], prog_name="rgbt")
    if shown.exit_code != 0 or f"Usage: {' '.join(path)}" not in shown.output:
        return [f"`{' '.join(path)} --help` failed: {shown.output}"]
    known = {"--help", "-h"} | {name for param in command.params for name in (*param.opts, *param.secondary_opts)}
    options = [token.split("=", 1)[0] for token in rest]
    return [f"`{' '.join(path)}` has no option {option}" for option in options
            if re.fullmatch(r"--?[A-Za-z][\w-]*", option) and option not in known]


def test_the_commands_shown_are_in_the_pages():
    assert {tuple(tokens[:2]) for _, tokens, _ in COMMANDS} >= {
        ("rgbt", "track"), ("rgbt", "register"), ("rgbt", "fuse"), ("rgbt", "fusion-metrics"), ("rgbt", "eval"),
        ("rgbt", "batch")}


@pytest.mark.parametrize("page, tokens, line", COMMANDS,
                         ids=[f"{_name(p)}:{n}:{' '.join(t[1:3])}" for p, t, n in COMMANDS])
def test_each_command_and_option_shown_exists(rgbt, page, tokens, line):
    assert command_problems(rgbt, tokens) == [], f"{_name(page)}, block at line {line}: {' '.join(tokens)}"


def test_an_unknown_command_or_option_is_caught(rgbt, tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```\nrgbt track a b --no-such-option -o x\nrgbt trak a b\n"
                    "rgbt batch track D --tracker=csrt --nope\nrgbt register --no-sync --sync -o c.json\n```\n")
    assert [command_problems(rgbt, tokens) for tokens, _ in rgbt_commands(page)] == [
        ["`rgbt track` has no option --no-such-option"], ["`rgbt` has no command 'trak'"],
        ["`rgbt batch track` has no option --nope"], []]
