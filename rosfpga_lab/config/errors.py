"""Typed errors of the configuration layer."""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class ConfigError(LabError):
    """A node configuration file is wrong: the message names the file, line and key.

    Attributes:
        path: the configuration file (or ``"<string>"``).
        line: 1-based line of the offending key or value (0 when the file as a whole is wrong).
        key: dotted key, e.g. ``"image.width"`` (empty when not about one key).
    """

    def __init__(self, message: str, *, path: str = "", line: int = 0, key: str = "") -> None:
        self.path = path
        self.line = line
        self.key = key
        where = f"{path}:{line}" if line else path
        what = f"{key}: " if key else ""
        super().__init__(f"{where}: {what}{message}" if where else f"{what}{message}")
