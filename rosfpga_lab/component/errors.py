"""Typed errors of the component layer (all under :class:`rosfpga_lab.errors.LabError`)."""

from __future__ import annotations

from rosfpga_lab.errors import LabError


class ComponentError(LabError):
    """Base of errors the component, camera, viewer or demo raise on purpose."""


class ComponentConfigError(ComponentError):
    """The component cannot be built from this configuration (the message says why and what to do)."""


class SourceError(ComponentError):
    """An image source (file, photo, size or encoding for the camera) is unusable."""


class ComponentShutDown(ComponentError):
    """The component's node was shut down from outside (``rosnode kill``, another node taking its
    name) while it was still starting; :attr:`reason` is the shutdown's message."""

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason
