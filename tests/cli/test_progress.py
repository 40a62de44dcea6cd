"""Progress bars: tqdm on a terminal, a silent stand-in (and no tqdm import) when stderr is piped."""

import io
import subprocess
import sys

from rgbt_cli import progress


def test_a_piped_run_gets_a_silent_bar_that_passes_messages_on(monkeypatch, capsys):
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    with progress.progress_bar(total=3, unit="frame") as bar:
        bar.update(1)
        bar.write("failed: item 2")
    assert sys.stderr.getvalue() == "failed: item 2\n"  # the message, and no bar drawn


def test_a_terminal_gets_a_tqdm_bar(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Terminal())
    from tqdm import tqdm

    bar = progress.progress_bar(total=3, unit="frame")
    try:
        assert isinstance(bar, tqdm) and not bar.disable
        bar.update(2)
    finally:
        bar.close()
    assert "2/3" in sys.stderr.getvalue()


def test_items_get_a_bar_on_a_terminal_only(monkeypatch):
    items = [1, 2, 3]
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert progress.progress_items(items, total=3) is items

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Terminal())
    assert list(progress.progress_items(items, total=3, unit="pair")) == items
    assert "3/3" in sys.stderr.getvalue()


def test_tqdm_is_not_imported_when_stderr_is_piped():
    code = "import sys; from rgbt_cli.progress import progress_bar, progress_items; progress_bar(total=2).update(1); " \
           "list(progress_items([1, 2])); print('tqdm' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
