"""ROS 1 service types (``.srv``): a request message and a response message.

How it works: a ``.srv`` text is two message texts split by a line ``---``. Each half is
registered as a message type named ``<Service>Request`` and ``<Service>Response`` (genpy's
names), so the registry's codecs serialize them; the service's md5 sum is genmsg's: the md5 of
the request's md5 text followed by the response's. The shipped services (roscpp's logger
services) live in ``definitions/<pkg>/srv/``; :func:`service_registry` holds them with every
shipped message type.
"""

from __future__ import annotations

import functools
import hashlib
from dataclasses import dataclass

from rosfpga_lab.msg.errors import MsgDefinitionError, UnknownTypeError
from rosfpga_lab.msg.limits import MAX_MSG_FILE_BYTES
from rosfpga_lab.msg.registry import DEFINITIONS_DIR, MsgRegistry

#: The line between a service's request and response definitions.
SRV_SEPARATOR = "---"


@dataclass(frozen=True)
class SrvSpec:
    """A service type: ``pkg/Name``, its two message types and genmsg's md5 sum."""

    name: str
    request: str
    response: str
    md5sum: str


def add_srv(reg: MsgRegistry, full_name: str, text: str) -> SrvSpec:
    """Register the request and response of the service ``full_name`` (``pkg/Name``) in ``reg``.

    Raises:
        MsgDefinitionError: not ``pkg/Name``, no ``---`` line, or a half that does not parse.
    """
    if full_name.count("/") != 1:
        raise MsgDefinitionError(f"service type {full_name!r}: want pkg/Name")
    lines = text.split("\n")
    cut = [i for i, line in enumerate(lines) if line.strip() == SRV_SEPARATOR]
    if len(cut) != 1:
        raise MsgDefinitionError(f"service {full_name}: want exactly one '{SRV_SEPARATOR}' line "
                                 f"between request and response, found {len(cut)}")
    request = "\n".join(lines[:cut[0]])
    response = "\n".join(lines[cut[0] + 1:])
    req, resp = f"{full_name}Request", f"{full_name}Response"
    reg.add(req, request + ("\n" if request else ""), f"<request of {full_name}>")
    reg.add(resp, response, f"<response of {full_name}>")
    digest = hashlib.md5((reg.md5_text(req) + reg.md5_text(resp)).encode()).hexdigest()
    return SrvSpec(full_name, req, resp, digest)


@functools.cache
def service_registry() -> tuple[MsgRegistry, dict[str, SrvSpec]]:
    """The shipped message types plus the shipped services' halves (read-only), and the
    services by name."""
    reg = MsgRegistry.with_defaults()
    services: dict[str, SrvSpec] = {}
    for path in sorted(DEFINITIONS_DIR.glob("*/srv/*.srv")):
        name = f"{path.parent.parent.name}/{path.stem}"
        data = path.read_bytes()[:MAX_MSG_FILE_BYTES + 1]
        if len(data) > MAX_MSG_FILE_BYTES:
            raise MsgDefinitionError(f"{path}: over {MAX_MSG_FILE_BYTES} bytes")
        services[name] = add_srv(reg, name, data.decode())
    return reg.freeze(), services


def srv_spec(name: str) -> SrvSpec:
    """A shipped service type by ``pkg/Name``.

    Raises:
        UnknownTypeError: not shipped (the list says which are).
    """
    services = service_registry()[1]
    if name not in services:
        raise UnknownTypeError(f"service type {name!r} is not shipped; shipped: "
                               f"{', '.join(sorted(services))}", name)
    return services[name]


__all__ = ["SRV_SEPARATOR", "SrvSpec", "add_srv", "service_registry", "srv_spec"]
