"""The ``rgbt`` command group.

Commands are discovered, not registered: every module ``cmd_<name>.py`` in this package that defines ``command``
becomes ``rgbt <name>`` (underscores become hyphens). Modules are imported only when their command runs or help is
shown, and each keeps its heavy imports inside the command body, so ``rgbt --help`` stays fast.
"""

from __future__ import annotations

import importlib
import pkgutil
import sys
import warnings

import click

import rgbt_toolkit
from rgbt_toolkit.errors import RgbtError
from rgbt_toolkit.runtime import keep_freed_memory

_PREFIX = "cmd_"


def _command_modules() -> dict[str, str]:
    """Map command name to module name for every ``cmd_*`` module in this package."""
    package_path = sys.modules[__package__].__path__
    found = {}
    for info in pkgutil.iter_modules(package_path):
        if info.name.startswith(_PREFIX):
            found[info.name[len(_PREFIX):].replace("_", "-")] = f"{__package__}.{info.name}"
    return found


def _one_line_warning(message, category, filename, lineno, line=None) -> str:
    """Library warnings (a skipped frame, a short result file) as one readable line, not a source listing."""
    return f"warning: {message}\n"


class DiscoveredGroup(click.Group):
    """A click group whose commands are the ``cmd_*`` modules, and which turns library errors into one line."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(_command_modules())

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        module_name = _command_modules().get(name)
        if module_name is None:
            return None
        return importlib.import_module(module_name).command

    def invoke(self, ctx: click.Context):
        warnings.formatwarning = _one_line_warning
        keep_freed_memory()
        try:
            return super().invoke(ctx)
        except RgbtError as exc:
            raise click.ClickException(str(exc)) from None
        except OSError as exc:  # missing, unreadable or unwritable paths, a file where a folder must be, a full disk
            raise click.ClickException(f"{exc.filename or ''}: {exc.strerror or exc}".lstrip(": ")) from None


@click.group(cls=DiscoveredGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(rgbt_toolkit.__version__, prog_name="rgbt")
def main() -> None:
    """Paired visible (RGB) and thermal (T) video and images: track, fuse, register, evaluate."""


if __name__ == "__main__":  # pragma: no cover
    main()
