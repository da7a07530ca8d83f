"""Notebook widgets: byte viewer, image diff, beat viewer, sequence diagram, live view, progress.

Every widget is constructible without a running kernel or front end (so plain pytest can test
its logic), and each has a static HTML form (``to_html()``) that needs no JavaScript, for
exported notebooks and GitHub's notebook view.
"""

from rosfpga_lab.widgets._common import WidgetError
from rosfpga_lab.widgets.byteview import ByteMap, ByteViewer, Span, as_span

__all__ = ["ByteMap", "ByteViewer", "Span", "WidgetError", "as_span"]
