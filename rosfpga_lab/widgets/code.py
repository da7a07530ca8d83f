"""Generated source files shown as a reader wants them: highlighted, one folding block per file.

:class:`CodeFiles` renders each file with Pygments (inline styles, so an exported page needs no
style sheet or script) inside a ``<details>`` block whose summary names the file and its line
count; long lines wrap instead of widening the notebook.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from rosfpga_lab.widgets._common import WidgetError, esc
from rosfpga_lab.widgets.limits import CODE_MAX_BYTES


def code_html(text: str, language: str = "cpp") -> str:
    """``text`` as highlighted HTML (a ``<pre>`` with inline colours, wrapping long lines)."""
    from pygments import highlight
    from pygments.formatters import HtmlFormatter
    from pygments.lexers import get_lexer_by_name

    html = highlight(text, get_lexer_by_name(language), HtmlFormatter(noclasses=True, nowrap=True))
    return ('<pre style="white-space:pre-wrap;word-break:break-word;font-size:12px;line-height:1.35;'
            f'margin:4px 0;padding:6px;background:#f8f8f8">{html}</pre>')


_LANGUAGES = {".cpp": "cpp", ".h": "cpp", ".hpp": "cpp", ".tcl": "tcl", ".md": "markdown",
              ".py": "python", ".v": "verilog", ".sv": "systemverilog", ".yaml": "yaml"}


class CodeFiles:
    """Files, each highlighted in its own folding block (open the ones named in ``open``).

    Args:
        paths: the files.
        root: shown names are relative to it (default: each file's folder).
        open: names of the blocks shown unfolded.

    Raises:
        WidgetError: a file cannot be read.
    """

    def __init__(self, paths: Iterable[str | Path], *, root: str | Path | None = None,
                 open: Iterable[str] = ()) -> None:
        self.files: list[tuple[str, str]] = []
        for p in map(Path, paths):
            try:
                raw = p.read_bytes()
            except OSError as exc:
                raise WidgetError(f"cannot read {p}: {exc.strerror}") from None
            text = raw[:CODE_MAX_BYTES].decode("utf-8", "replace")
            if len(raw) > CODE_MAX_BYTES:
                text += f"\n... ({len(raw) - CODE_MAX_BYTES} more bytes not shown)\n"
            name = str(p.relative_to(root)) if root else p.name
            self.files.append((name, text))
        self.open = set(open)

    def to_html(self) -> str:
        """The blocks as HTML."""
        blocks = []
        for name, text in self.files:
            language = _LANGUAGES.get(Path(name).suffix, "text")
            lines = text.count("\n") + (not text.endswith("\n"))
            opened = " open" if name in self.open else ""
            blocks.append(f"<details{opened}><summary><code>{esc(name)}</code> ({lines} lines)</summary>"
                          f"{code_html(text, language)}</details>")
        return "<div>" + "".join(blocks) + "</div>"

    def _repr_html_(self) -> str:
        return self.to_html()
