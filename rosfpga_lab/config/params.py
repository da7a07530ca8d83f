"""The component's private ROS parameters (``~ksize``, ``_ksize:=3``) and how they meet the YAML.

How this works: the node configuration (YAML) is the circuit's build-time truth: the image
geometry, the operation and its kernel are synthesized into the FPGA, so a parameter cannot
change them. A ROS user still expects to *see* and *give* them as private parameters (a launch
file's ``<param name="ksize" value="3"/>``, ``rosrun ... _ksize:=3``), so two kinds exist:

* :data:`CIRCUIT_PARAMS`: fixed by the circuit. A value equal to the configuration's is accepted
  (the launch file agrees with the circuit); a different one is refused with a message naming
  the file, the key, both values and what to do (edit the YAML, generate the circuit again).
* :data:`RUNTIME_PARAMS`: settings of the emulated node that no circuit fixes (the model, the
  software queues). A parameter sets them; a command-line option (``--input-queue``) wins.

Any other private parameter is refused (a typo would otherwise be ignored silently). Sans-IO:
the caller reads the parameter server and the command line and passes the values in.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from rosfpga_lab.config.errors import ConfigError
from rosfpga_lab.config.node import NodeConfig
from rosfpga_lab.config.vocabulary import MODELS

#: Parameters the circuit fixes: name -> (dotted key in the YAML, how to read it from a config).
CIRCUIT_PARAMS: dict[str, tuple[str, Callable[[NodeConfig], Any]]] = {
    "op": ("application.op", lambda c: c.application.op),
    "ksize": ("application.ksize", lambda c: c.application.ksize),
    "width": ("image.width", lambda c: c.image.width),
    "height": ("image.height", lambda c: c.image.height),
    "encoding": ("image.encoding", lambda c: c.image.encoding),
    "clock_mhz": ("clock_mhz", lambda c: c.clock_mhz),
}


def _model(value: Any) -> str | None:
    return None if value in MODELS else f"one of {', '.join(MODELS)}"


def _queue(value: Any) -> str | None:
    ok = isinstance(value, int) and not isinstance(value, bool) and value >= 1
    return None if ok else "a whole number of at least 1"


#: Parameters of the emulated node: name -> (what it sets, check returning "want ..." or None).
RUNTIME_PARAMS: dict[str, tuple[str, Callable[[Any], str | None]]] = {
    "model": ("the circuit model (--model)", _model),
    "input_queue": ("frames waiting in front of the circuit (--input-queue)", _queue),
    "output_queue": ("frames waiting per downstream subscriber (--output-queue)", _queue),
}


@dataclass(frozen=True)
class ParamSource:
    """Where a set of parameter values came from (for messages)."""

    values: Mapping[str, Any]
    where: str   # e.g. "the command line (_ksize:=)" or "the parameter server (/fpga/ksize)"
    prefix: str  # how a name is written there: "_" or "/fpga/"


def runtime_settings(config: NodeConfig, *sources: ParamSource) -> dict[str, Any]:
    """Check private parameters against the configuration; return the runtime settings.

    Args:
        config: the loaded node configuration (the circuit).
        sources: parameter values, later sources winning (the server, then the command line).

    Returns:
        ``{name: value}`` of the :data:`RUNTIME_PARAMS` given.

    Raises:
        ConfigError: an unknown parameter, a runtime value of the wrong kind, or a circuit
            parameter that differs from the configuration.
    """
    settings: dict[str, Any] = {}
    file = str(config.path) if config.path is not None else "the node configuration"
    for source in sources:
        for name, value in source.values.items():
            shown = f"{source.prefix}{name}"
            if name in CIRCUIT_PARAMS:
                key, read = CIRCUIT_PARAMS[name]
                built = read(config)
                same = value == built and isinstance(value, bool) == isinstance(built, bool)
                if not same:
                    raise ConfigError(
                        f"parameter {shown} is {value!r} in {source.where}, but the circuit was "
                        f"built with {key}: {built!r} ({file}); the YAML is the circuit's "
                        f"build-time truth, a parameter cannot change it. Set {key} in the "
                        "file and generate the circuit again (rosfpga-lab generate), or drop "
                        "the parameter")
            elif name in RUNTIME_PARAMS:
                what, check = RUNTIME_PARAMS[name]
                want = check(value)
                if want is not None:
                    raise ConfigError(f"parameter {shown} ({what}) in {source.where}: want "
                                      f"{want}, got {value!r}")
                settings[name] = value
            else:
                known = ", ".join([*CIRCUIT_PARAMS, *RUNTIME_PARAMS])
                raise ConfigError(f"unknown parameter {shown} in {source.where} (a component "
                                  f"takes: {known})")
    return settings
