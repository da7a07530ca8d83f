"""Limits and defaults of the notebook widgets, in one place."""

from __future__ import annotations

#: Bytes shown per page of the byte viewer (32 rows of 16). The browser never gets more.
BYTE_PAGE_SIZE = 512
#: Largest page the byte viewer accepts, so a page always stays a small piece of HTML.
BYTE_PAGE_SIZE_MAX = 8192
#: Bytes per hex row.
BYTE_ROW_SIZE = 16
#: Fields listed in the live field list and in static field tables before "... N more".
FIELD_LIST_LIMIT = 2000
#: Characters of a decoded value shown before it is cut with an ellipsis.
VALUE_TEXT_LIMIT = 80
#: Mismatch positions kept in an image diff summary (the count is always exact).
DIFF_POSITIONS_LIMIT = 1000
#: Side (pixels) of the largest zoom region whose values are tabulated.
ZOOM_MAX = 16
#: Beats per page of the beat table, and beats shown in the waveform.
BEAT_PAGE_SIZE = 32
WAVE_BEATS = 16
#: Live view: default most frames per second pushed to the browser.
LIVE_MAX_FPS = 10.0
#: Live view: seconds of arrivals its fps figures count.
LIVE_RATE_WINDOW = 2.0
#: Largest width (pixels) of an image sent to the browser; bigger ones are scaled down.
DISPLAY_MAX_WIDTH = 640
#: Seconds one cell may run before the notebook export gives up.
CELL_TIMEOUT = 300

#: Largest file shown (bytes); a larger one is cut with a note.
CODE_MAX_BYTES = 200_000

#: Widest panel drawn; a table needing more columns than fit narrows the columns.
DIAGRAM_MAX_WIDTH = 900

#: Changes per signal drawn one by one in a window; more become a hatched "busy" band.
MAX_EDGES = 600
#: Largest span (clocks) of one window (a whole frame can be seen at once, in summary).
MAX_SPAN = 1 << 26
#: Signals drawn at most in one picture.
MAX_SIGNALS = 48
